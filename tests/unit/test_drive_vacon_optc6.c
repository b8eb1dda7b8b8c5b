/* VACON NX OPTC6 (od/vacon-optc6): Drive Profile with RUN = 0x000F and the drive's own ramps and
 * limits, stops, the Fieldbus Fault on node-guarding loss, NX fault numbers in EMCY and 0x1003,
 * the Bypass modes' nx_control_word / nx_speed_reference, AnyParameter.
 * Manual: "VACON NX AC Drives, OPTC6 CANopen Option Board User Manual" (DPD00896B). */
#include "drive_fixture.h"
#include "drive_trips_vacon_optc6.h"

extern const co_drive_desc co_drive_desc_vacon_optc6;

static drive_fx fx;

void setUp(void)
{
    fx_start(&fx, &co_drive_desc_vacon_optc6, 1);
}

void tearDown(void) {}

static void rpdo6(uint16_t cw, int16_t target)
{
    const uint8_t b[4] = {(uint8_t)cw, (uint8_t)(cw >> 8), (uint8_t)target,
                          (uint8_t)((uint16_t)target >> 8)};
    fx_rx(&fx, 0x301, 4, b);
}

static void running_at(int16_t rpm)
{
    fx_nmt(&fx, 0x01);
    rpdo6(0x0006, 0);
    rpdo6(0x0007, 0);
    rpdo6(0x000F, rpm);
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT16(rpm, fx_i16(&fx, 0x6044, 0));
}

/* --- Drive Profile --------------------------------------------------------------------------- */

static void test_section_7_5_prepare_ready_prepare_run_run(void)
{
    TEST_ASSERT_EQUAL_HEX16(0x0240, fx_sw(&fx));
    fx_nmt(&fx, 0x01);
    rpdo6(0x0006, 0);
    TEST_ASSERT_EQUAL_HEX16(0x0231, fx_sw(&fx));
    rpdo6(0x0007, 0);
    TEST_ASSERT_EQUAL_HEX16(0x0233, fx_sw(&fx));
    fx_clear(&fx);
    rpdo6(0x000F, 1500); /* RUN: no 0x007F needed */
    fx_advance(&fx, 500000); /* the drive's own ramp: 1.0 s from 0 to 1500 */
    TEST_ASSERT_EQUAL_INT16(750, fx_i16(&fx, 0x6044, 0));
    fx_advance(&fx, 500000);
    TEST_ASSERT_EQUAL_HEX16(0x0637, fx_sw(&fx));
    const co_frame *f = fx_last(&fx, 0x281); /* TPDO6: statusword, vl_control_effort */
    TEST_ASSERT_NOT_NULL(f);
    TEST_ASSERT_EQUAL_UINT8(4, f->dlc);
    const uint8_t expected[4] = {0x37, 0x06, 0xDC, 0x05};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expected, f->data, 4);
}

static void test_rpdo1_carries_the_controlword_alone(void)
{
    fx_nmt(&fx, 0x01);
    const uint8_t cw[2] = {0x06, 0x00};
    fx_rx(&fx, 0x201, 2, cw);
    TEST_ASSERT_EQUAL(CO_CIA402_READY_TO_SWITCH_ON, fx.d.state);
}

static void test_stop_0x0007_ramps_down_in_switched_on(void)
{
    running_at(1500);
    rpdo6(0x0007, 1500);
    TEST_ASSERT_EQUAL_HEX16(0x0233, fx_sw(&fx));
    fx_advance(&fx, 500000);
    TEST_ASSERT_EQUAL_INT16(750, fx_i16(&fx, 0x6044, 0));
    fx_advance(&fx, 500000);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
}

static void test_shutdown_coasts_over_5_s(void)
{
    running_at(1500);
    rpdo6(0x0006, 1500);
    fx_advance(&fx, 1000000);
    TEST_ASSERT_EQUAL_INT16(1200, fx_i16(&fx, 0x6044, 0));
    fx_advance(&fx, 4000000);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
}

static void test_quick_stop_decelerates_on_the_normal_ramp_then_disabled(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x604A, 1, 100, 4)); /* 'Not Used': stored */
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x604A, 2, 60, 2));
    running_at(1500);
    rpdo6(0x000B, 1500);
    TEST_ASSERT_EQUAL_HEX16(0x0217, fx_sw(&fx));
    fx_advance(&fx, 999999);
    TEST_ASSERT_EQUAL(CO_CIA402_QUICK_STOP_ACTIVE, fx.d.state);
    fx_advance(&fx, 1);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_6048_set_replaces_the_drive_ramp(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x6048, 1, 1500, 4));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x6048, 2, 3, 2));
    fx_nmt(&fx, 0x01);
    rpdo6(0x0006, 0);
    rpdo6(0x000F, 1500);
    fx_advance(&fx, 1000000);
    TEST_ASSERT_EQUAL_INT16(500, fx_i16(&fx, 0x6044, 0));
}

static void test_limits_max_zero_means_max_frequency(void)
{
    running_at(1000);
    rpdo6(0x000F, 3000);
    TEST_ASSERT_EQUAL_HEX16(0x0800, fx_sw(&fx) & 0x0800);
    fx_advance(&fx, 2000000);
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x6046, 2, 1200, 4));
    fx_advance(&fx, 2000000);
    TEST_ASSERT_EQUAL_INT16(1200, fx_i16(&fx, 0x6044, 0));
}

static void test_halt_stops_and_stays_enabled(void)
{
    running_at(1500);
    rpdo6(0x010F, 1500);
    fx_advance(&fx, 1000000);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX16(0x0637, fx_sw(&fx));
    rpdo6(0x000F, 1500);
    fx_advance(&fx, 1000000);
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6044, 0));
}

static void test_6060_is_read_only(void)
{
    TEST_ASSERT_EQUAL_HEX32(0x06010002, fx_sdo_write(&fx, 0x6060, 0, 3, 1));
}

/* --- faults ---------------------------------------------------------------------------------- */

static void test_nx_fault_outside_the_table_is_emcy_1000_with_the_number(void)
{
    running_at(600);
    fx_clear(&fx);
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 14, fx.now)); /* e.g. NX fault 14 */
    fx_expect_emcy(&fx, 0x1000, 0x01, 14);
    TEST_ASSERT_EQUAL_INT16(14, fx_i16(&fx, 0x2063, 0));
    TEST_ASSERT_EQUAL_HEX32(0x000E1000, fx_u32(&fx, 0x1003, 1));
    TEST_ASSERT_EQUAL_HEX16(0x021F, fx_sw(&fx)); /* Fault reaction active 0x001F */
    fx_advance(&fx, 1000);
    TEST_ASSERT_EQUAL_HEX16(0x0208, fx_sw(&fx));
    co_drive_clear_fault_cause(&fx.d);
    rpdo6(0x0000, 0);
    rpdo6(0x0080, 0);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x2063, 0));
}

static void test_every_row_of_the_table(void)
{
    for (uint32_t i = 0; i < DRIVE_TRIP_COUNT_VACON_OPTC6; i++) {
        const co_drive_trip *t = &co_drive_trips_vacon_optc6[i];
        fx_start(&fx, &co_drive_desc_vacon_optc6, 1);
        fx_clear(&fx);
        if ((t->flags & CO_DRIVE_TRIP_NO_CODE) != 0u) {
            TEST_ASSERT_TRUE(co_drive_report_error(&fx.d, t->emcy_code, fx.now)); /* board level */
            fx_expect_emcy(&fx, t->emcy_code, (uint8_t)(t->error_register | 1u), 0);
            TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x2063, 0));
            continue;
        }
        TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, t->trip_code, fx.now));
        fx_expect_emcy(&fx, t->emcy_code, (uint8_t)(t->error_register | 1u), (uint8_t)t->trip_code);
        TEST_ASSERT_EQUAL_INT16((int16_t)t->trip_code, fx_i16(&fx, 0x2063, 0));
    }
}

static void guarded(void)
{
    fx_rtr(&fx, 0x701); /* the first guard request arms life guarding: 1000 ms x 2 */
}

static void test_life_guarding_loss_is_fieldbus_fault_53(void)
{
    running_at(1500);
    guarded();
    fx_clear(&fx);
    fx_advance(&fx, 1999999);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    fx_advance(&fx, 1);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT_REACTION_ACTIVE, fx.d.state);
    fx_expect_emcy(&fx, 0x8130, 0x11, 53);
    TEST_ASSERT_EQUAL_HEX32(0x00358130, fx_u32(&fx, 0x1003, 1));
    TEST_ASSERT_EQUAL_INT16(53, fx_i16(&fx, 0x2063, 0));
    TEST_ASSERT_EQUAL_UINT32(1, fx_count(&fx, 0x81)); /* one EMCY: the drive's */
    fx_advance(&fx, 1000000);
    TEST_ASSERT_EQUAL_INT16(1200, fx_i16(&fx, 0x6044, 0)); /* coasting (response 3) */
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, fx.d.node.nmt_state); /* CiA 301 default */
    fx_cw(&fx, 0x0000);
    fx_cw(&fx, 0x0080); /* cleared at any time (B2.6), no guard request needed */
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x2063, 0));
}

static void test_fieldbus_fault_response_1_is_a_warning(void)
{
    TEST_ASSERT_TRUE(co_drive_set_setting(&fx.d, "fieldbus_fault_response", 1));
    running_at(1500);
    guarded();
    fx_advance(&fx, 2000000);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0x0080, fx_sw(&fx) & 0x0080);
    guarded();
    TEST_ASSERT_EQUAL_HEX16(0, fx_sw(&fx) & 0x0080);
}

static void test_fieldbus_fault_response_2_ramps(void)
{
    TEST_ASSERT_TRUE(co_drive_set_setting(&fx.d, "fieldbus_fault_response", 2));
    running_at(1500);
    guarded();
    fx_advance(&fx, 2500000);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT_REACTION_ACTIVE, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(750, fx_i16(&fx, 0x6044, 0));
    fx_advance(&fx, 500000);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT, fx.d.state);
}

/* --- Bypass ------------------------------------------------------------------------------------ */

static void bypass_mode(int32_t mode)
{
    TEST_ASSERT_TRUE(co_drive_set_setting(&fx.d, "operate_mode", mode));
    fx_nmt(&fx, 0x81); /* board initialisation */
    fx_nmt(&fx, 0x01);
}

static void rpdo21(uint16_t nx_cw, int16_t reference)
{
    const uint8_t b[8] = {(uint8_t)nx_cw, (uint8_t)(nx_cw >> 8), (uint8_t)reference,
                          (uint8_t)((uint16_t)reference >> 8), 0, 0, 0, 0};
    fx_rx(&fx, 0x401, 8, b);
}

static void test_operate_mode_applies_its_pdo_set(void)
{
    TEST_ASSERT_EQUAL_HEX32(0x80000401, fx_u32(&fx, 0x1414, 1));
    bypass_mode(3);
    TEST_ASSERT_EQUAL_HEX32(0x00000401, fx_u32(&fx, 0x1414, 1));
    TEST_ASSERT_EQUAL_HEX32(0x80000301, fx_u32(&fx, 0x1405, 1));
    TEST_ASSERT_EQUAL_HEX32(0x80000301, fx_u32(&fx, 0x1416, 1));
    TEST_ASSERT_EQUAL_HEX32(0x00000381, fx_u32(&fx, 0x1814, 1));
    bypass_mode(5);
    TEST_ASSERT_EQUAL_HEX32(0x00000301, fx_u32(&fx, 0x1416, 1));
    TEST_ASSERT_EQUAL_HEX32(0x00000281, fx_u32(&fx, 0x1816, 1));
    fx_nmt(&fx, 0x82); /* reset communication keeps the mode's set */
    TEST_ASSERT_EQUAL_HEX32(0x00000301, fx_u32(&fx, 0x1416, 1));
}

static void test_bypass_run_with_percent_reference(void)
{
    bypass_mode(3);
    TEST_ASSERT_EQUAL_HEX16(0x0231, fx_sw(&fx)); /* ready and stopped */
    fx_clear(&fx);
    rpdo21(0x0001, 5000); /* RUN, 50.00 % of 0..50 Hz */
    fx_advance(&fx, 1000000);
    TEST_ASSERT_EQUAL_INT16(750, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_INT16(2500, fx_i16(&fx, 0x2839, 0)); /* OUT1: 25.00 Hz */
    TEST_ASSERT_EQUAL_INT16(750, fx_i16(&fx, 0x283A, 0));  /* OUT2: rpm */
    TEST_ASSERT_EQUAL_INT16(5000, fx_i16(&fx, 0x2838, 0)); /* nx_actual_speed */
    TEST_ASSERT_EQUAL_HEX16(0x0523, (uint16_t)fx_i16(&fx, 0x2836, 0)); /* RDY RUN AREF */
    TEST_ASSERT_EQUAL_HEX16(0x0637, fx_sw(&fx));
    const co_frame *f = fx_last(&fx, 0x381);
    TEST_ASSERT_NOT_NULL(f);
    TEST_ASSERT_EQUAL_HEX8(0x23, f->data[0]);
    TEST_ASSERT_EQUAL_HEX8(0x88, f->data[2]); /* 5000 = 0x1388 */
}

static void test_bypass_direction_and_stop(void)
{
    bypass_mode(2);
    rpdo21(0x0003, 10000); /* RUN + DIR counter-clockwise, 100 % */
    fx_advance(&fx, 1000000);
    TEST_ASSERT_EQUAL_INT16(-1500, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX16(0x0004, (uint16_t)fx_i16(&fx, 0x2836, 0) & 0x0004);
    rpdo21(0x0003, -10000); /* DIR xor negative: clockwise */
    fx_advance(&fx, 2000000);
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6044, 0));
    rpdo21(0x0000, 10000); /* RUN = 0: stop on the ramp */
    fx_advance(&fx, 500000);
    TEST_ASSERT_EQUAL_INT16(750, fx_i16(&fx, 0x6044, 0));
    fx_advance(&fx, 600000);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX16(0x0231, fx_sw(&fx));
}

static void test_bypass_ignores_the_controlword_and_resets_by_rst(void)
{
    bypass_mode(4);
    fx_cw(&fx, 0x000F); /* stored, no effect */
    TEST_ASSERT_EQUAL_UINT16(0x000F, fx_u16(&fx, 0x6040, 0));
    TEST_ASSERT_EQUAL(CO_CIA402_READY_TO_SWITCH_ON, fx.d.state);
    rpdo21(0x0001, 2000);
    fx_advance(&fx, 1000000);
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 14, fx.now));
    fx_advance(&fx, 1000);
    TEST_ASSERT_EQUAL_HEX16(0x0008, (uint16_t)fx_i16(&fx, 0x2836, 0) & 0x0008);
    co_drive_clear_fault_cause(&fx.d);
    rpdo21(0x0005, 2000); /* RST edge, RUN still 1 */
    TEST_ASSERT_EQUAL_HEX16(0x0231, fx_sw(&fx));
    fx_advance(&fx, 1000000);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0)); /* needs a new RUN edge */
    rpdo21(0x0000, 2000);
    rpdo21(0x0001, 2000);
    fx_advance(&fx, 1000000);
    TEST_ASSERT_EQUAL_INT16(300, fx_i16(&fx, 0x6044, 0));
}

/* --- AnyParameter ------------------------------------------------------------------------------ */

/* The load (NOTES B10): 0x2003 motor current in 0.01 A and 0x2004 torque in 0.1 %, process data
 * out 3/4/5 current 0.1 A, torque and power 0.1 %; rated current 10.00 A (model value). */
static void test_load_shows_in_current_torque_and_power(void)
{
    running_at(750); /* 25.00 Hz */
    TEST_ASSERT_EQUAL_UINT16(300, fx_u16(&fx, 0x2003, 0)); /* no load: 30 % magnetising */
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x2004, 0));
    TEST_ASSERT_TRUE(co_drive_set_load(&fx.d, 80, fx.now));
    TEST_ASSERT_EQUAL_UINT16(820, fx_u16(&fx, 0x2003, 0));  /* 8.20 A */
    TEST_ASSERT_EQUAL_UINT16(800, fx_u16(&fx, 0x2004, 0));  /* 80.0 % */
    TEST_ASSERT_EQUAL_INT16(82, fx_i16(&fx, 0x283B, 0));    /* OUT3: 8.2 A */
    TEST_ASSERT_EQUAL_INT16(800, fx_i16(&fx, 0x283C, 0));   /* OUT4: 80.0 % */
    TEST_ASSERT_EQUAL_INT16(400, fx_i16(&fx, 0x283D, 0));   /* OUT5: 80 % torque at half speed */
    TEST_ASSERT_EQUAL_INT16(750, fx_i16(&fx, 0x6044, 0));   /* speed unchanged */
    rpdo6(0x0006, 750); /* shutdown: coasts, output off */
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x2003, 0));
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x2004, 0));
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x283B, 0));
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x283D, 0));
    fx_nmt(&fx, 0x81); /* the load is the machine's: a reset node keeps it */
    TEST_ASSERT_EQUAL_UINT16(80, fx.d.motor.load);
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x2003, 0));
}

static void test_anyparameter_read(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2000, 0, 102, 2));
    uint32_t v = 1;
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x2001, 0, &v));
    TEST_ASSERT_EQUAL_HEX32(0, v); /* in progress */
    fx_advance(&fx, 10000);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x2001, 0, &v));
    TEST_ASSERT_EQUAL_HEX32(0x00661388, v); /* ID 102, 50.00 Hz */
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2000, 0, 999, 2));
    fx_advance(&fx, 10000);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x2001, 0, &v));
    TEST_ASSERT_EQUAL_HEX32(0xFFFF0000, v);
}

static void test_anyparameter_write(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2002, 0, (103u << 16) | 30u, 4));
    uint32_t v = 0;
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x2002, 0, &v));
    TEST_ASSERT_EQUAL_HEX32((103u << 16) | 30u, v); /* still being written */
    TEST_ASSERT_EQUAL_HEX32(0x08000022, fx_sdo_write(&fx, 0x2002, 0, (104u << 16) | 5u, 4));
    fx_advance(&fx, 10000);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x2002, 0, &v));
    TEST_ASSERT_EQUAL_HEX32(0, v);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2002, 0, (1u << 16) | 5u, 4)); /* monitor */
    fx_advance(&fx, 10000);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x2002, 0, &v));
    TEST_ASSERT_EQUAL_HEX32(0xFFFF0000, v);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2000, 0, 103, 2));
    fx_advance(&fx, 10000);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x2001, 0, &v));
    TEST_ASSERT_EQUAL_HEX32(0x0067001E, v);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_section_7_5_prepare_ready_prepare_run_run);
    RUN_TEST(test_rpdo1_carries_the_controlword_alone);
    RUN_TEST(test_stop_0x0007_ramps_down_in_switched_on);
    RUN_TEST(test_shutdown_coasts_over_5_s);
    RUN_TEST(test_quick_stop_decelerates_on_the_normal_ramp_then_disabled);
    RUN_TEST(test_6048_set_replaces_the_drive_ramp);
    RUN_TEST(test_limits_max_zero_means_max_frequency);
    RUN_TEST(test_halt_stops_and_stays_enabled);
    RUN_TEST(test_6060_is_read_only);
    RUN_TEST(test_nx_fault_outside_the_table_is_emcy_1000_with_the_number);
    RUN_TEST(test_every_row_of_the_table);
    RUN_TEST(test_life_guarding_loss_is_fieldbus_fault_53);
    RUN_TEST(test_fieldbus_fault_response_1_is_a_warning);
    RUN_TEST(test_fieldbus_fault_response_2_ramps);
    RUN_TEST(test_operate_mode_applies_its_pdo_set);
    RUN_TEST(test_bypass_run_with_percent_reference);
    RUN_TEST(test_bypass_direction_and_stop);
    RUN_TEST(test_bypass_ignores_the_controlword_and_resets_by_rst);
    RUN_TEST(test_anyparameter_read);
    RUN_TEST(test_anyparameter_write);
    RUN_TEST(test_load_shows_in_current_torque_and_power);
    return UNITY_END();
}
