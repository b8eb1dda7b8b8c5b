/* Benshaw RSi CANopen module (od/benshaw-rsi): level-triggered controlword, transition 5 without
 * stop, coast on shutdown/disable voltage, latched vl bits, max-speed slopes in 0.1 s, the trip
 * table with its 0x603F/EMCY split, Lost Command (Pr.12/Pr.13), CM.11 PDO sets with CM.94.
 * Manual: Benshaw "CANopen for RSi 'S' & 'SW' Series Variable Frequency Drive, Instruction Manual" (890049-12-00). */
#include "drive_fixture.h"
#include "drive_trips_benshaw_rsi.h"

extern const co_drive_desc co_drive_desc_benshaw_rsi;

static drive_fx fx;

void setUp(void)
{
    fx_start(&fx, &co_drive_desc_benshaw_rsi, 3);
}

void tearDown(void) {}

/* dr.06 = 4 (Cmd Source FieldBus), dr.07 = 8 (Freq Ref Src Fieldbus). */
static void fieldbus_control(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4010, 7, 4, 2));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4010, 8, 8, 2));
}

static void enable(void)
{
    fx_cw(&fx, 0x0006);
    fx_cw(&fx, 0x000F);
    fx_advance(&fx, 1000);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
}

static void running_at(int16_t rpm)
{
    fieldbus_control();
    enable();
    fx_cw(&fx, 0x007F);
    fx_target(&fx, rpm);
    fx_advance(&fx, 40000000);
    TEST_ASSERT_EQUAL_INT16(rpm, fx_i16(&fx, 0x6044, 0));
}

static void test_boot_and_remote_with_dr06_fieldbus(void)
{
    TEST_ASSERT_EQUAL_HEX16(0x0040, fx_sw(&fx));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4010, 7, 4, 2));
    fx_advance(&fx, 1);
    TEST_ASSERT_EQUAL_HEX16(0x0240, fx_sw(&fx));
    TEST_ASSERT_EQUAL_UINT16(3, fx_u16(&fx, 0x4016, 7)); /* CM.07 = the start-up node-ID */
}

static void test_statusword_patterns_of_b9(void)
{
    fieldbus_control();
    fx_cw(&fx, 0x0006);
    TEST_ASSERT_EQUAL_HEX16(0x0231, fx_sw(&fx));
    fx_cw(&fx, 0x0007);
    TEST_ASSERT_EQUAL_HEX16(0x0233, fx_sw(&fx));
    fx_cw(&fx, 0x000F);
    fx_advance(&fx, 1000);
    TEST_ASSERT_EQUAL_HEX16(0x0637, fx_sw(&fx) | 0x0400); /* 0x0237 or with target reached */
    fx_cw(&fx, 0x000B);
    TEST_ASSERT_EQUAL_HEX16(0x0217, fx_sw(&fx) & ~0x0400u);
}

static void test_held_0x000F_gives_3_then_4_at_the_next_cycle(void)
{
    fx_cw(&fx, 0x0006);
    fx_cw(&fx, 0x000F);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCHED_ON, fx.d.state);
    fx_advance(&fx, 999);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCHED_ON, fx.d.state);
    fx_advance(&fx, 1);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
}

static void test_bit_7_high_blocks_every_command(void)
{
    fx_cw(&fx, 0x0086);
    fx_advance(&fx, 5000);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_0x000F_enables_at_0_hz_0x007F_runs(void)
{
    fieldbus_control();
    enable();
    fx_target(&fx, 900);
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0)); /* latch (0, 0): output held at 0 */
    fx_cw(&fx, 0x007F);
    fx_advance(&fx, 10000000); /* 1800 rpm per 20.0 s: 900 in 10 s */
    TEST_ASSERT_EQUAL_INT16(900, fx_i16(&fx, 0x6044, 0));
}

static void test_bit_4_zero_keeps_the_latched_bits(void)
{
    running_at(900);
    fx_cw(&fx, 0x000F); /* bit 4 = 0: keep running as before */
    fx_target(&fx, 1800);
    fx_advance(&fx, 10000000);
    TEST_ASSERT_EQUAL_INT16(1800, fx_i16(&fx, 0x6044, 0));
    fx_cw(&fx, 0x005F); /* bit 5 = 0: hold */
    fx_target(&fx, 0);
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT16(1800, fx_i16(&fx, 0x6044, 0));
    fx_cw(&fx, 0x003F); /* bit 6 = 0: target 0, on 6049 (30.0 s from max speed) */
    fx_target(&fx, 1800);
    fx_advance(&fx, 15000000);
    TEST_ASSERT_EQUAL_INT16(900, fx_i16(&fx, 0x6044, 0));
}

/* The load (NOTES B15): Output Current 0x4010:09 in 0.1 A of the model's 5.0 A motor. */
static void test_output_current_follows_the_load(void)
{
    running_at(900);
    TEST_ASSERT_EQUAL_UINT16(15, fx_u16(&fx, 0x4010, 9)); /* no load: 30 % magnetising */
    TEST_ASSERT_TRUE(co_drive_set_load(&fx.d, 80, fx.now));
    TEST_ASSERT_EQUAL_UINT16(41, fx_u16(&fx, 0x4010, 9)); /* 82 % of 5.0 A */
    TEST_ASSERT_TRUE(co_drive_set_load(&fx.d, 200, fx.now));
    TEST_ASSERT_EQUAL_UINT16(97, fx_u16(&fx, 0x4010, 9)); /* 193.13 % */
    TEST_ASSERT_EQUAL_INT16(900, fx_i16(&fx, 0x6044, 0));
    fx_cw(&fx, 0x0006); /* shutdown: free run stop */
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x4010, 9));
}

static void test_slopes_fix_delta_speed_at_max_speed(void)
{
    fieldbus_control();
    TEST_ASSERT_EQUAL_HEX32(0x06090011, fx_sdo_write(&fx, 0x6048, 1, 1500, 4)); /* no sub 1 */
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x6048, 2, 50, 2)); /* 5.0 s */
    TEST_ASSERT_EQUAL_UINT16(50, fx_u16(&fx, 0x4010, 3));             /* ACC.Time-1 (C23) */
    enable();
    fx_cw(&fx, 0x007F);
    fx_target(&fx, 1800);
    fx_advance(&fx, 2500000);
    TEST_ASSERT_EQUAL_INT16(900, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4010, 3, 200, 2));
    TEST_ASSERT_EQUAL_UINT16(200, fx_u16(&fx, 0x6048, 2));
}

static void test_target_clipped_at_max_speed_with_internal_limit(void)
{
    fieldbus_control();
    enable();
    fx_cw(&fx, 0x007F);
    fx_target(&fx, 3000);
    TEST_ASSERT_EQUAL_HEX16(0x0800, fx_sw(&fx) & 0x0800);
    fx_advance(&fx, 30000000);
    TEST_ASSERT_EQUAL_INT16(1800, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX32(0x06090031, fx_sdo_write(&fx, 0x6042, 0, 30001, 2));
}

static void test_transition_5_keeps_the_output_frequency(void)
{
    running_at(900);
    fx_cw(&fx, 0x0007);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCHED_ON, fx.d.state);
    fx_target(&fx, 0);
    fx_advance(&fx, 20000000);
    TEST_ASSERT_EQUAL_INT16(900, fx_i16(&fx, 0x6044, 0)); /* 'stop command is not accepted' */
    fx_cw(&fx, 0x0006);                                   /* 6: free run from 900 */
    TEST_ASSERT_EQUAL(CO_CIA402_READY_TO_SWITCH_ON, fx.d.state);
    fx_advance(&fx, 1250000);
    TEST_ASSERT_EQUAL_INT16(450, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_INT16(450, fx_i16(&fx, 0x6043, 0)); /* the coasting motor */
}

static void test_shutdown_and_disable_voltage_coast(void)
{
    running_at(1800);
    fx_cw(&fx, 0x0006); /* 8 */
    fx_advance(&fx, 2500000);
    TEST_ASSERT_EQUAL_INT16(900, fx_i16(&fx, 0x6044, 0));
    running_at(1800);
    fx_cw(&fx, 0x0000); /* 9 */
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
}

static void test_quick_stop_on_604A_stays_and_16_reenables(void)
{
    running_at(1800);
    fx_cw(&fx, 0x000B); /* 604A:02 = 3.0 s from max speed */
    fx_advance(&fx, 1500000);
    TEST_ASSERT_EQUAL_INT16(900, fx_i16(&fx, 0x6044, 0));
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL(CO_CIA402_QUICK_STOP_ACTIVE, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0x0617, fx_sw(&fx));
    fx_cw(&fx, 0x007F);
    fx_advance(&fx, 1000);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    TEST_ASSERT_EQUAL(16, fx.d.last_transition);
    fx_cw(&fx, 0x000B);
    fx_cw(&fx, 0x0000);
    TEST_ASSERT_EQUAL(12, fx.d.last_transition);
}

static void test_every_trip_of_the_table(void)
{
    for (uint32_t i = 0; i < DRIVE_TRIP_COUNT_BENSHAW_RSI; i++) {
        const co_drive_trip *t = &co_drive_trips_benshaw_rsi[i];
        fx_start(&fx, &co_drive_desc_benshaw_rsi, 3);
        fx_clear(&fx);
        TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, t->trip_code, fx.now));
        fx_expect_emcy(&fx, t->emcy_code, t->error_register, 0);
        TEST_ASSERT_EQUAL_HEX8(t->error_register, fx_u8(&fx, 0x1001, 0)); /* no bit 0 added */
        fx_advance(&fx, 1000);
        if (t->emcy_code >= 0x8200u && t->emcy_code <= 0x8220u) {
            TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state); /* reported only */
            TEST_ASSERT_EQUAL_HEX16(0, fx_u16(&fx, 0x603F, 0));
            continue;
        }
        TEST_ASSERT_EQUAL(CO_CIA402_FAULT, fx.d.state);
        TEST_ASSERT_EQUAL_HEX16(t->trip_code, fx_u16(&fx, 0x603F, 0));
        co_drive_clear_fault_cause(&fx.d);
        fx_cw(&fx, 0x0080);
        TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
        fx_expect_emcy(&fx, 0x0000, 0x00, 0);
    }
}

static void test_ethermal_603f_ff01_emcy_ff02(void)
{
    fx_clear(&fx);
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0xFF01, fx.now));
    TEST_ASSERT_EQUAL_HEX16(0xFF01, fx_u16(&fx, 0x603F, 0));
    fx_expect_emcy(&fx, 0xFF02, 0x80, 0);
    TEST_ASSERT_EQUAL_HEX32(0xFF02, fx_u32(&fx, 0x1003, 1));
}

/* --- Lost Command ---------------------------------------------------------------------------- */

static void lost_mode(uint16_t mode)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x401A, 12, mode, 2));
}

static void test_lost_command_free_run_trips_after_pr13(void)
{
    running_at(900);
    fx_nmt(&fx, 0x01);
    lost_mode(1);
    fx_nmt(&fx, 0x80); /* Pre-operational: the Lost Command time runs */
    fx_advance(&fx, 999999);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    fx_clear(&fx);
    fx_advance(&fx, 1);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT_REACTION_ACTIVE, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0xFF0A, fx_u16(&fx, 0x603F, 0));
    fx_expect_emcy(&fx, 0xFF0A, 0x80, 0);
    fx_advance(&fx, 1000);
    fx_cw(&fx, 0x0080);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT, fx.d.state); /* still not Operational */
    fx_nmt(&fx, 0x01);
    fx_cw(&fx, 0x0000);
    fx_cw(&fx, 0x0080);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_lost_command_back_in_time_is_no_error(void)
{
    running_at(900);
    fx_nmt(&fx, 0x01);
    lost_mode(1);
    fx_nmt(&fx, 0x80);
    fx_advance(&fx, 900000);
    fx_nmt(&fx, 0x01);
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
}

static void test_lost_command_not_armed_without_fieldbus_source_or_mode(void)
{
    lost_mode(1); /* dr.06/dr.07 not fieldbus */
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    fieldbus_control();
    lost_mode(0);
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_lost_command_dec_decelerates_on_pr07_in_fault_reaction(void)
{
    running_at(1800);
    fx_nmt(&fx, 0x01);
    lost_mode(2);
    fx_nmt(&fx, 0x80);
    fx_advance(&fx, 1000000 + 1500000); /* Pr.07 = 3.0 s from max speed */
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT_REACTION_ACTIVE, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(900, fx_i16(&fx, 0x6044, 0));
    fx_advance(&fx, 1500000);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT, fx.d.state);
}

static void test_lost_command_hold_output_warns(void)
{
    running_at(900);
    fx_nmt(&fx, 0x01);
    lost_mode(4);
    fx_nmt(&fx, 0x02); /* Stopped counts too */
    fx_advance(&fx, 1000000);
    TEST_ASSERT_EQUAL_HEX16(0x0080, fx_sw(&fx) & 0x0080);
    fx_nmt(&fx, 0x80); /* SDO again (Stopped has none); still not Operational */
    fx_target(&fx, 0);
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT16(900, fx_i16(&fx, 0x6044, 0));
    fx_nmt(&fx, 0x01);
    TEST_ASSERT_EQUAL_HEX16(0, fx_sw(&fx) & 0x0080);
    fx_advance(&fx, 20000000);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
}

static void test_lost_command_preset_speed(void)
{
    running_at(900);
    fx_nmt(&fx, 0x01);
    lost_mode(5);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x401A, 14, 1000, 2)); /* 10.00 Hz */
    fx_nmt(&fx, 0x80);
    fx_advance(&fx, 30000000);
    TEST_ASSERT_EQUAL_INT16(300, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX16(0x0080, fx_sw(&fx) & 0x0080);
}

/* Over vcan the guard error is found inside co_node_process (no frame arrives): the Lost Command
 * timer it arms must be in the deadline co_drive_process returns, or a port that sleeps until that
 * deadline never trips (found by tests/integration/test_comm_loss.py). */
static void test_lost_command_after_a_guard_error_on_a_silent_bus(void)
{
    running_at(900);
    fx_nmt(&fx, 0x01);
    lost_mode(1);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x100C, 0, 100, 2));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x100D, 0, 2, 1));
    fx_rtr(&fx, 0x703); /* arms life guarding: 200 ms */
    uint64_t last_rtr = fx.now;
    fx_wake_at_deadlines(&fx, last_rtr + 200000 + 1000000 - 1);
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, fx.d.node.nmt_state);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    fx_wake_at_deadlines(&fx, last_rtr + 200000 + 1000000);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT_REACTION_ACTIVE, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0xFF0A, fx_u16(&fx, 0x603F, 0));
}

/* --- CM.11 / CM.94 ---------------------------------------------------------------------------- */

static void test_comm_update_switches_to_the_pdo3_set(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4016, 11, 1, 2));
    TEST_ASSERT_EQUAL_UINT16(1, fx_u16(&fx, 0x4016, 0x3F)); /* alias CM.63 */
    TEST_ASSERT_EQUAL_HEX32(0x203, fx_u32(&fx, 0x1400, 1)); /* not before Comm Update */
    fx_clear(&fx);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4016, 94, 1, 2));
    TEST_ASSERT_EQUAL_UINT32(1, fx_count(&fx, 0x703)); /* boot-up after the SDO answer */
    TEST_ASSERT_EQUAL_HEX32(0x80000203, fx_u32(&fx, 0x1400, 1));
    TEST_ASSERT_EQUAL_HEX32(0x80000183, fx_u32(&fx, 0x1800, 1));
    TEST_ASSERT_EQUAL_HEX32(0x00000403, fx_u32(&fx, 0x1402, 1));
    TEST_ASSERT_EQUAL_HEX32(0x00000383, fx_u32(&fx, 0x1802, 1));
    uint32_t v;
    TEST_ASSERT_EQUAL_HEX32(0x06020000, fx_sdo_read(&fx, 0x6040, 0, &v));
    TEST_ASSERT_EQUAL_HEX32(0x06020000, fx_sdo_write(&fx, 0x6042, 0, 100, 2));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x604A, 2, &v)); /* stays */
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x4016, 94));
}

static void test_pdo3_words_follow_cm31_to_cm54(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4016, 11, 1, 2));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4016, 94, 1, 2));
    fx_nmt(&fx, 0x01);
    const uint8_t words[8] = {0x34, 0x12, 0x78, 0x56, 0, 0, 0, 0};
    fx_rx(&fx, 0x403, 8, words); /* CM.51 = 0x0005, CM.52 = 0x0006 */
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4016, 34, 0x0005, 2)); /* CM.34 -> 0x0005 */
    fx_advance(&fx, 1);
    TEST_ASSERT_EQUAL_HEX16(0x1234, fx_u16(&fx, 0x3013, 0));
    TEST_ASSERT_EQUAL_HEX16(0, fx_u16(&fx, 0x3010, 0)); /* CM.31 = 0x000A: output frequency */
}

static void test_comm_update_takes_the_new_node_id(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4016, 0x3D, 9, 2)); /* CM.61 = CM.07 */
    TEST_ASSERT_EQUAL_UINT16(9, fx_u16(&fx, 0x4016, 7));
    fx_clear(&fx);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4016, 0x43, 1, 2)); /* CM.67 = CM.94 */
    TEST_ASSERT_EQUAL_UINT32(1, fx_count(&fx, 0x709));
    TEST_ASSERT_EQUAL_UINT8(9, fx.d.node.node_id);
    TEST_ASSERT_EQUAL_HEX32(0x209, fx_u32(&fx, 0x1400, 1));
}

static void test_reset_node_keeps_inverter_parameters(void)
{
    running_at(900);
    fx_nmt(&fx, 0x81);
    TEST_ASSERT_EQUAL_UINT16(4, fx_u16(&fx, 0x4010, 7));
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6042, 0));
    fx_advance(&fx, 1250000); /* a running motor coasts */
    TEST_ASSERT_EQUAL_INT16(450, fx_i16(&fx, 0x6044, 0));
}

static void test_reserved_freq_ref_sources_refused(void)
{
    TEST_ASSERT_EQUAL_HEX32(0x06090030, fx_sdo_write(&fx, 0x4010, 8, 3, 2));
    TEST_ASSERT_EQUAL_HEX32(0x06090030, fx_sdo_write(&fx, 0x4010, 8, 10, 2));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4010, 8, 12, 2));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_boot_and_remote_with_dr06_fieldbus);
    RUN_TEST(test_statusword_patterns_of_b9);
    RUN_TEST(test_held_0x000F_gives_3_then_4_at_the_next_cycle);
    RUN_TEST(test_bit_7_high_blocks_every_command);
    RUN_TEST(test_0x000F_enables_at_0_hz_0x007F_runs);
    RUN_TEST(test_bit_4_zero_keeps_the_latched_bits);
    RUN_TEST(test_slopes_fix_delta_speed_at_max_speed);
    RUN_TEST(test_target_clipped_at_max_speed_with_internal_limit);
    RUN_TEST(test_transition_5_keeps_the_output_frequency);
    RUN_TEST(test_shutdown_and_disable_voltage_coast);
    RUN_TEST(test_quick_stop_on_604A_stays_and_16_reenables);
    RUN_TEST(test_every_trip_of_the_table);
    RUN_TEST(test_ethermal_603f_ff01_emcy_ff02);
    RUN_TEST(test_lost_command_free_run_trips_after_pr13);
    RUN_TEST(test_lost_command_back_in_time_is_no_error);
    RUN_TEST(test_lost_command_not_armed_without_fieldbus_source_or_mode);
    RUN_TEST(test_lost_command_dec_decelerates_on_pr07_in_fault_reaction);
    RUN_TEST(test_lost_command_hold_output_warns);
    RUN_TEST(test_lost_command_preset_speed);
    RUN_TEST(test_lost_command_after_a_guard_error_on_a_silent_bus);
    RUN_TEST(test_comm_update_switches_to_the_pdo3_set);
    RUN_TEST(test_pdo3_words_follow_cm31_to_cm54);
    RUN_TEST(test_comm_update_takes_the_new_node_id);
    RUN_TEST(test_reset_node_keeps_inverter_parameters);
    RUN_TEST(test_reserved_freq_ref_sources_refused);
    RUN_TEST(test_output_current_follows_the_load);
    return UNITY_END();
}
