/* Toshiba VF-MB1/S15 EtherCAT option IPE003Z served over CAN (od/vf-mb1-ecat): the §8.13/§8.14
 * start sequence, its state machine departures (bit 7 'x', bit 11 reverse, first reference,
 * locked quick stop, Fault 0x0028), the trip table, FA06, and the C100-C103 network error
 * reactions. Manual: Toshiba "TOSVERT VF-MB1/S15 series EtherCAT option unit Function Manual, IPE003Z". */
#include "drive_fixture.h"
#include "drive_trips_vf_mb1_ecat.h"

extern const co_drive_desc co_drive_desc_vf_mb1_ecat;

static drive_fx fx;

void setUp(void)
{
    fx_start(&fx, &co_drive_desc_vf_mb1_ecat, 2);
}

void tearDown(void) {}

/* CMOd = 4, FMOd = 7 (§3.1 'Setting'), effective after a reset node (B9.4). */
static void cia402_profile(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2003, 0, 4, 2));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2004, 0, 7, 2));
    fx_nmt(&fx, 0x81);
}

static void rpdo1(uint16_t cw, int16_t target)
{
    const uint8_t b[4] = {(uint8_t)cw, (uint8_t)(cw >> 8), (uint8_t)target,
                          (uint8_t)((uint16_t)target >> 8)};
    fx_rx(&fx, 0x202, 4, b);
}

static void running_at(int16_t rpm)
{
    cia402_profile();
    fx_nmt(&fx, 0x01);
    rpdo1(0x0006, 0);
    rpdo1(0x0007, 0);
    rpdo1(0x000F, 0);
    rpdo1(0x000F, rpm);
    fx_advance(&fx, 20000000);
    TEST_ASSERT_EQUAL_INT16(rpm, fx_i16(&fx, 0x6044, 0));
}

static void test_boot_and_profile_selection_needs_a_reset(void)
{
    TEST_ASSERT_EQUAL_HEX16(0x0040, fx_sw(&fx));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2003, 0, 4, 2));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2004, 0, 7, 2));
    TEST_ASSERT_EQUAL_HEX16(0x0040, fx_sw(&fx)); /* not yet */
    fx_nmt(&fx, 0x81);
    TEST_ASSERT_EQUAL_HEX16(0x0240, fx_sw(&fx)); /* remote: CiA 402 profile in effect */
    TEST_ASSERT_EQUAL_UINT16(4, fx_u16(&fx, 0x2003, 0)); /* EEPROM: kept by the reset */
}

static void test_section_8_14_start_and_stop(void)
{
    cia402_profile();
    fx_nmt(&fx, 0x01);
    TEST_ASSERT_EQUAL_UINT16(8, fx_u16(&fx, 0x4400, 0)); /* C400: OP */
    rpdo1(0x0006, 0);
    TEST_ASSERT_EQUAL_HEX16(0x0221, fx_sw(&fx)); /* Ready 0x0021: bit 4 'x' printed 0 */
    rpdo1(0x0007, 0);
    TEST_ASSERT_EQUAL_HEX16(0x0233, fx_sw(&fx));
    rpdo1(0x000F, 0);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    rpdo1(0x000F, 0x05DC);
    fx_advance(&fx, 10000000);
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_UINT16(5000, fx_u16(&fx, 0x2D00, 0)); /* '50.0' Hz */
    TEST_ASSERT_EQUAL_HEX16(0x0400, fx_u16(&fx, 0x2D01, 0) & 0x0400);
    rpdo1(0x0000, 0x05DC);
    TEST_ASSERT_EQUAL_HEX16(0x0240, fx_sw(&fx));
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x2D00, 0));
}

static void test_section_8_13_snapshot_0x0237_without_internal_limit(void)
{
    cia402_profile();
    fx_nmt(&fx, 0x01);
    rpdo1(0x0006, 0);
    rpdo1(0x0007, 0);
    rpdo1(0x000F, 0x0708); /* 1800 min-1, above 6046:02 = 1500 */
    fx_advance(&fx, 7527000); /* 0x0469 = 1129 min-1 on the 150 min-1/s ramp */
    TEST_ASSERT_EQUAL_INT16(0x0469, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX16(0x0237, fx_sw(&fx));
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX16(0x0637, fx_sw(&fx)); /* never bit 11 (C27) */
}

static void test_enable_waits_for_the_first_reference(void)
{
    cia402_profile();
    fx_enable(&fx);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCHED_ON, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0x0233, fx_sw(&fx));
    fx_target(&fx, 0);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    fx_nmt(&fx, 0x82); /* a reset forgets the reference */
    fx_cw(&fx, 0x0000);
    fx_enable(&fx);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCHED_ON, fx.d.state);
}

static void test_enabling_rpdo_keeps_its_target(void)
{
    cia402_profile();
    fx_nmt(&fx, 0x01);
    rpdo1(0x0006, 0);
    rpdo1(0x0007, 0);
    rpdo1(0x000F, 1200); /* the first reference comes with the enable: kept */
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(1200, fx_i16(&fx, 0x6042, 0));
}

static void test_controlword_bit_11_reverses(void)
{
    running_at(600);
    rpdo1(0x080F, 600);
    fx_advance(&fx, 10000000);
    TEST_ASSERT_EQUAL_INT16(-600, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX16(0x0200, fx_u16(&fx, 0x2D01, 0) & 0x0200);
    rpdo1(0x080F, -300); /* reverse of reverse: forward (C28) */
    fx_advance(&fx, 10000000);
    TEST_ASSERT_EQUAL_INT16(300, fx_i16(&fx, 0x6044, 0));
}

static void test_bit_7_dont_care(void)
{
    cia402_profile();
    fx_cw(&fx, 0x0086);
    TEST_ASSERT_EQUAL(CO_CIA402_READY_TO_SWITCH_ON, fx.d.state);
    fx_cw(&fx, 0x0087);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCHED_ON, fx.d.state);
}

static void test_disable_operation_and_shutdown_coast(void)
{
    running_at(1500);
    rpdo1(0x0007, 1500);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCHED_ON, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6043, 0));
}

static void test_quick_stop_runs_to_its_end_and_ignores_disable_voltage(void)
{
    running_at(1500); /* 604A 1500 per 6 s */
    rpdo1(0x000B, 1500);
    TEST_ASSERT_EQUAL_HEX16(0x0217, fx_sw(&fx));
    rpdo1(0x0000, 1500);
    TEST_ASSERT_EQUAL(CO_CIA402_QUICK_STOP_ACTIVE, fx.d.state);
    fx_advance(&fx, 3000000);
    TEST_ASSERT_EQUAL_INT16(750, fx_i16(&fx, 0x6044, 0));
    rpdo1(0x000F, 1500); /* no 16 */
    TEST_ASSERT_EQUAL(CO_CIA402_QUICK_STOP_ACTIVE, fx.d.state);
    fx_advance(&fx, 3000000);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_quick_stop_options_5_to_8_act_like_1(void)
{
    running_at(1500); /* 605A is back to its default after the reset node (B1.5) */
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x605A, 0, 7, 2));
    rpdo1(0x0002, 1500);
    fx_advance(&fx, 6000000);
    TEST_ASSERT_EQUAL_INT16(600, fx_i16(&fx, 0x6044, 0)); /* on 6049: 150 per s */
    fx_advance(&fx, 4000000);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_quick_stop_option_0_freewheels(void)
{
    running_at(1500);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x605A, 0, 0, 2));
    rpdo1(0x0002, 1500);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_fault_from_operation_enabled_shows_0x0028(void)
{
    running_at(900);
    fx_clear(&fx);
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x01, fx.now)); /* OC1 */
    TEST_ASSERT_EQUAL_HEX16(0x022F, fx_sw(&fx));
    fx_advance(&fx, 1000);
    TEST_ASSERT_EQUAL_HEX16(0x0228, fx_sw(&fx));
    fx_expect_emcy(&fx, 0x2310, 0x01, 0x01);
    TEST_ASSERT_EQUAL_HEX16(0x0003, fx_u16(&fx, 0x2D01, 0) & 0x0003);
}

static void test_fault_from_quick_stop_shows_0x0008(void)
{
    running_at(900);
    rpdo1(0x0002, 900);
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x10, fx.now));
    fx_advance(&fx, 1000);
    TEST_ASSERT_EQUAL_HEX16(0x0208, fx_sw(&fx));
}

static void test_every_trip_of_the_table_and_history_kept_by_reset(void)
{
    for (uint32_t i = 0; i < DRIVE_TRIP_COUNT_VF_MB1_ECAT; i++) {
        const co_drive_trip *t = &co_drive_trips_vf_mb1_ecat[i];
        fx_start(&fx, &co_drive_desc_vf_mb1_ecat, 2);
        fx_clear(&fx);
        TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, t->trip_code, fx.now));
        fx_expect_emcy(&fx, t->emcy_code, 0x01, (uint8_t)t->trip_code);
        TEST_ASSERT_EQUAL_HEX16(t->emcy_code, fx_u16(&fx, 0x603F, 0));
        fx_advance(&fx, 1000);
        co_drive_clear_fault_cause(&fx.d);
        fx_cw(&fx, 0x0080);
        TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
        TEST_ASSERT_EQUAL_HEX16(0, fx_u16(&fx, 0x603F, 0));
        TEST_ASSERT_EQUAL_HEX32(t->emcy_code, fx_u32(&fx, 0x1003, 1) & 0xFFFFu); /* §4.1 note */
    }
}

static void test_fa06_emergency_stop_and_reset(void)
{
    running_at(900);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2A06, 0, 0x1000, 2));
    fx_advance(&fx, 1000);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0x9000, fx_u16(&fx, 0x603F, 0));
    TEST_ASSERT_EQUAL_HEX16(0x1000, fx_u16(&fx, 0x2D01, 0) & 0x1000);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2A06, 0, 0x3000, 2)); /* bit 12 still 1 */
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT, fx.d.state);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2A06, 0, 0x0000, 2));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2A06, 0, 0x2000, 2));
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

/* --- network error (B8) --------------------------------------------------------------------- */

/* RPDO1 deadline 100 ms armed by the frames of running_at. */
static void watched_and_running(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2003, 0, 4, 2));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2004, 0, 7, 2));
    fx_nmt(&fx, 0x81);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x1400, 5, 100, 2));
    fx_nmt(&fx, 0x01);
    rpdo1(0x0006, 0);
    rpdo1(0x0007, 0);
    rpdo1(0x000F, 1500);
    for (int i = 0; i < 110; i++) {
        fx_advance(&fx, 99000);
        rpdo1(0x000F, 1500);
    }
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6044, 0));
}

static void test_rpdo_deadline_trips_err8_after_c100(void)
{
    watched_and_running();
    fx_clear(&fx);
    fx_advance(&fx, 100000 + 99999); /* deadline + C100 = 0.1 s */
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    fx_advance(&fx, 1);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT_REACTION_ACTIVE, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0x7520, fx_u16(&fx, 0x603F, 0));
    fx_expect_emcy(&fx, 0x7520, 0x01, 0x1B);
    TEST_ASSERT_EQUAL_UINT32(1, fx_count(&fx, 0x82)); /* no 0x81xx EMCY (C34) */
    fx_advance(&fx, 1000);
    fx_cw(&fx, 0x0080);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT, fx.d.state); /* still no RPDO */
    rpdo1(0x0000, 0);
    rpdo1(0x0080, 0);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_rpdo_back_within_c100_nothing_happens(void)
{
    watched_and_running();
    fx_advance(&fx, 150000);
    rpdo1(0x000F, 1500);
    fx_advance(&fx, 90000);
    rpdo1(0x000F, 1500);
    fx_advance(&fx, 90000);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
}

/* C101 = 1 keeps going; the alarm FC91 bit 11 and with it the statusword's warning bit 7 (NOTES
 * B4: bit 7 = 1 while FC91 is not 0) while the error lasts (found by the vcan test
 * test_vf_mb1_rpdo_deadline_c101_1_keeps_running_and_flags_fc91). */
static void test_c101_1_continues_with_the_alarm_and_warning_bit(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4101, 0, 1, 2));
    watched_and_running();
    fx_advance(&fx, 200000 + 1000000);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX16(0x0800, fx_u16(&fx, 0x2C91, 0));
    TEST_ASSERT_EQUAL_HEX16(0x0080, fx_sw(&fx) & 0x0080);
    rpdo1(0x000F, 1500);
    TEST_ASSERT_EQUAL_HEX16(0, fx_u16(&fx, 0x2C91, 0));
    TEST_ASSERT_EQUAL_HEX16(0, fx_sw(&fx) & 0x0080);
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6044, 0));
}

static void test_c101_2_decelerates_keeps_the_state_and_resumes(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4101, 0, 2, 2));
    watched_and_running();
    fx_advance(&fx, 200000 + 5000000);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(750, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX16(0x0800, fx_u16(&fx, 0x2C91, 0));
    rpdo1(0x000F, 1500);
    TEST_ASSERT_EQUAL_HEX16(0, fx_u16(&fx, 0x2C91, 0));
    fx_advance(&fx, 90000);
    rpdo1(0x000F, 1500);
    TEST_ASSERT_TRUE(fx_i16(&fx, 0x6044, 0) > 750);
}

static void test_c101_3_coasts_while_the_error_lasts(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4101, 0, 3, 2));
    watched_and_running();
    fx_advance(&fx, 200000);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX16(0x0080, fx_sw(&fx) & 0x0080);
    for (int i = 0; i < 10; i++) {
        rpdo1(0x000F, 1500);
        fx_advance(&fx, 100000);
    }
    TEST_ASSERT_EQUAL_INT16(150, fx_i16(&fx, 0x6044, 0));
}

static void test_leaving_operational_while_enabled_is_a_network_error(void)
{
    running_at(600);
    fx_nmt(&fx, 0x80);
    TEST_ASSERT_EQUAL_UINT16(2, fx_u16(&fx, 0x4400, 0));
    fx_advance(&fx, 99999);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    fx_advance(&fx, 1);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT_REACTION_ACTIVE, fx.d.state);
}

static void test_heartbeat_back_ends_the_c101_3_coast_and_the_alarm(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4101, 0, 3, 2));
    running_at(600);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x1016, 1, (0x7Fu << 16) | 50u, 4));
    const uint8_t op = 0x05;
    fx_rx(&fx, 0x77F, 1, &op);
    fx_advance(&fx, 50000 + 100000); /* consumer time + C100 (0.1 s) */
    TEST_ASSERT_EQUAL_HEX16(0x0800, fx_u16(&fx, 0x2C91, 0));
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
    fx_rx(&fx, 0x77F, 1, &op); /* the master is back */
    TEST_ASSERT_EQUAL_HEX16(0, fx_u16(&fx, 0x2C91, 0));
    TEST_ASSERT_EQUAL_HEX16(0, fx_sw(&fx) & 0x0080);
    for (int i = 0; i < 20; i++) {
        fx_advance(&fx, 40000);
        fx_rx(&fx, 0x77F, 1, &op);
    }
    TEST_ASSERT_TRUE(fx_i16(&fx, 0x6044, 0) > 0); /* follows the command again (B8.4) */
}

static void test_heartbeat_loss_sends_no_8130(void)
{
    running_at(600);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x1016, 1, (0x7Fu << 16) | 50u, 4));
    const uint8_t op = 0x05;
    fx_rx(&fx, 0x77F, 1, &op);
    fx_clear(&fx);
    fx_advance(&fx, 200000);
    const co_frame *f = fx_last(&fx, 0x82);
    TEST_ASSERT_NOT_NULL(f);
    TEST_ASSERT_EQUAL_HEX8(0x20, f->data[0]);
    TEST_ASSERT_EQUAL_HEX8(0x75, f->data[1]); /* Err8, not 0x8130 */
    TEST_ASSERT_EQUAL_UINT32(1, fx_count(&fx, 0x82));
}

/* The load (NOTES B11): FD03 output current and FD20 torque current in 0.01 % of the rated
 * current, FD18 torque in 0.01 %, FD26 motor load factor in %; 0 with the output off; 6044 keeps
 * the output-frequency image. */
static void test_load_shows_in_fd03_fd18_fd20_fd26_while_the_output_is_on(void)
{
    TEST_ASSERT_TRUE(co_drive_set_load(&fx.d, 80, fx.now)); /* before the run: nothing shown */
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x2D03, 0));
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x2D18, 0));
    running_at(1500);
    TEST_ASSERT_EQUAL_UINT16(8200, fx_u16(&fx, 0x2D03, 0)); /* 82.00 % of rated current */
    TEST_ASSERT_EQUAL_UINT16(8000, fx_u16(&fx, 0x2D18, 0)); /* 80.00 % torque */
    TEST_ASSERT_EQUAL_UINT16(7631, fx_u16(&fx, 0x2D20, 0));
    TEST_ASSERT_EQUAL_UINT16(80, fx_u16(&fx, 0x2D26, 0));
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6044, 0));
    /* a step at a chosen microsecond shows at that microsecond, in SDO answers too */
    fx_advance(&fx, 1234);
    TEST_ASSERT_TRUE(co_drive_set_load(&fx.d, 0, fx.now));
    TEST_ASSERT_EQUAL_UINT16(3000, fx_u16(&fx, 0x2D03, 0)); /* magnetising current alone */
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x2D18, 0));
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x2D26, 0));
    uint32_t fd03 = 0;
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x2D03, 0, &fd03));
    TEST_ASSERT_EQUAL_UINT32(3000, fd03);
    TEST_ASSERT_FALSE(co_drive_set_load(&fx.d, 201, fx.now)); /* refused, nothing changes */
    TEST_ASSERT_EQUAL_UINT16(0, fx.d.motor.load);
    TEST_ASSERT_TRUE(co_drive_set_load(&fx.d, 150, fx.now));
    TEST_ASSERT_EQUAL_UINT16(150, fx_u16(&fx, 0x2D26, 0));
    TEST_ASSERT_EQUAL_UINT16(15000, fx_u16(&fx, 0x2D18, 0));
    rpdo1(0x0007, 1500); /* disable operation: the output goes off, the motor coasts */
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x2D03, 0));
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x2D18, 0));
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x2D20, 0));
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x2D26, 0));
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x2D23, 0)); /* overload factor: not modelled */
}

static void test_c402_reads_the_node_id(void)
{
    TEST_ASSERT_EQUAL_UINT16(2, fx_u16(&fx, 0x4402, 0));
    TEST_ASSERT_EQUAL_UINT16(2, fx_u16(&fx, 0x4400, 0));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_boot_and_profile_selection_needs_a_reset);
    RUN_TEST(test_section_8_14_start_and_stop);
    RUN_TEST(test_section_8_13_snapshot_0x0237_without_internal_limit);
    RUN_TEST(test_enable_waits_for_the_first_reference);
    RUN_TEST(test_enabling_rpdo_keeps_its_target);
    RUN_TEST(test_controlword_bit_11_reverses);
    RUN_TEST(test_bit_7_dont_care);
    RUN_TEST(test_disable_operation_and_shutdown_coast);
    RUN_TEST(test_quick_stop_runs_to_its_end_and_ignores_disable_voltage);
    RUN_TEST(test_quick_stop_options_5_to_8_act_like_1);
    RUN_TEST(test_quick_stop_option_0_freewheels);
    RUN_TEST(test_fault_from_operation_enabled_shows_0x0028);
    RUN_TEST(test_fault_from_quick_stop_shows_0x0008);
    RUN_TEST(test_every_trip_of_the_table_and_history_kept_by_reset);
    RUN_TEST(test_fa06_emergency_stop_and_reset);
    RUN_TEST(test_rpdo_deadline_trips_err8_after_c100);
    RUN_TEST(test_rpdo_back_within_c100_nothing_happens);
    RUN_TEST(test_c101_1_continues_with_the_alarm_and_warning_bit);
    RUN_TEST(test_c101_2_decelerates_keeps_the_state_and_resumes);
    RUN_TEST(test_c101_3_coasts_while_the_error_lasts);
    RUN_TEST(test_leaving_operational_while_enabled_is_a_network_error);
    RUN_TEST(test_heartbeat_loss_sends_no_8130);
    RUN_TEST(test_heartbeat_back_ends_the_c101_3_coast_and_the_alarm);
    RUN_TEST(test_c402_reads_the_node_id);
    RUN_TEST(test_load_shows_in_fd03_fd18_fd20_fd26_while_the_output_is_on);
    return UNITY_END();
}
