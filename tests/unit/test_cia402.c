/* CiA 402 power drive state machine: every command decoded, every transition 0-16 with its
 * action, the statusword of every state, the vl controlword bits, halt, quick stop option codes,
 * the fault path and its reset, and the departures a description can declare - on a plain CiA 402
 * drive described here on the test dictionary (od/test/test.eds), so nothing of a real drive is
 * involved. Virtual clock, no sleeps. */
#include "canopen/drive/cia402.h"
#include "canopen/emcy.h"
#include "drive_fixture.h"
#include "od_test.h"

/* --- a plain CiA 402 drive on the test dictionary ----------------------------------------- */

static const co_drive_trip plain_trips[] = {
    {0x0001u, 0x2310u, 0x02u, 0u, "OC", "over-current"},
    {0x0002u, 0x4210u, 0x08u, 0u, "OH", "over-temperature"},
    {0x0000u, 0x8130u, 0x10u, CO_DRIVE_TRIP_NO_CODE, "", "life guard"},
    {0x0003u, 0x8210u, 0x10u, 0u, "PDO", "length: reported, no trip"},
};
static const uint16_t plain_report_only[] = {0x8210u};
static const co_drive_setting plain_settings[] = {{"speed_limit", 10, 0, 100, "test"}};

static co_drive_desc plain;   /* copied from plain_base and varied per test */

static const co_drive_desc plain_base = {
    .id = "test",
    .title = "plain CiA 402 drive on the test dictionary",
    .od = &co_od_test,
    .trips = plain_trips,
    .trip_count = 4,
    .profile = CO_DRIVE_PROFILE_CIA402,
    .emcy_info = CO_DRIVE_EMCY_TRIP_LE,
    .voltage_states = CO_CIA402_STATE_BIT(CO_CIA402_READY_TO_SWITCH_ON) |
                      CO_CIA402_STATE_BIT(CO_CIA402_SWITCHED_ON) |
                      CO_CIA402_STATE_BIT(CO_CIA402_OPERATION_ENABLED) |
                      CO_CIA402_STATE_BIT(CO_CIA402_QUICK_STOP_ACTIVE),
    .velocity_unit = CO_MOTOR_UNIT_RPM,
    .poles = 4,
    .max_speed = 3000,
    .ramp_time_unit_us = 1000000u,
    .quick_stop_option = 2,
    .shutdown_option = 0,
    .disable_operation_option = 1,
    .halt_option = 1,
    .fault_reaction_option = 0,
    .report_only = plain_report_only,
    .report_only_count = 1,
    .settings = plain_settings,
    .setting_count = 1,
};

static drive_fx fx;

void setUp(void)
{
    plain = plain_base;
    fx_start(&fx, &plain, 4);
}

void tearDown(void) {}

static void restart(void)
{
    fx_start(&fx, &plain, 4);
}

static void run(int16_t rpm)
{
    fx_enable(&fx);
    fx_cw(&fx, 0x007F);
    fx_target(&fx, rpm);
    fx_advance(&fx, 30000000);
    TEST_ASSERT_EQUAL_INT16(rpm, fx_i16(&fx, 0x6044, 0));
}

/* --- decoding ------------------------------------------------------------------------------- */

static void test_decode_every_command_of_table_27(void)
{
    for (uint32_t low = 0; low < 16u; low++) {
        co_cia402_command expected;
        if ((low & 0x2u) == 0u) {
            expected = CO_CIA402_CMD_DISABLE_VOLTAGE;
        } else if ((low & 0x4u) == 0u) {
            expected = CO_CIA402_CMD_QUICK_STOP;
        } else if ((low & 0x1u) == 0u) {
            expected = CO_CIA402_CMD_SHUTDOWN;
        } else if ((low & 0x8u) == 0u) {
            expected = CO_CIA402_CMD_SWITCH_ON;
        } else {
            expected = CO_CIA402_CMD_ENABLE_OPERATION;
        }
        /* bits 4-6 and 8-15 do not change the command */
        TEST_ASSERT_EQUAL(expected, co_cia402_decode((uint16_t)low, 0, 0));
        TEST_ASSERT_EQUAL(expected, co_cia402_decode((uint16_t)(low | 0xFF70u), 0, 0));
    }
}

static void test_decode_fault_reset_is_the_rising_edge_of_bit_7(void)
{
    TEST_ASSERT_EQUAL(CO_CIA402_CMD_FAULT_RESET, co_cia402_decode(0x0080, 0x0000, 0));
    TEST_ASSERT_EQUAL(CO_CIA402_CMD_FAULT_RESET, co_cia402_decode(0x008F, 0x000F, 0));
    TEST_ASSERT_EQUAL(CO_CIA402_CMD_NONE, co_cia402_decode(0x0080, 0x0080, 0));
    TEST_ASSERT_EQUAL(CO_CIA402_CMD_NONE, co_cia402_decode(0x008F, 0x0080, 0));
    /* VF-MB1 style: bit 7 'x' for the other commands */
    TEST_ASSERT_EQUAL(CO_CIA402_CMD_ENABLE_OPERATION,
                      co_cia402_decode(0x008F, 0x0080, CO_CIA402_BIT7_DONT_CARE));
    TEST_ASSERT_EQUAL(CO_CIA402_CMD_FAULT_RESET,
                      co_cia402_decode(0x0086, 0x0006, CO_CIA402_BIT7_DONT_CARE));
}

/* --- the transition table ------------------------------------------------------------------- */

typedef struct {
    co_cia402_state from;
    co_cia402_command cmd;
    int transition;
    co_cia402_state to;
} row;

static void test_every_state_and_command(void)
{
    const row table[] = {
        {CO_CIA402_SWITCH_ON_DISABLED, CO_CIA402_CMD_SHUTDOWN, 2, CO_CIA402_READY_TO_SWITCH_ON},
        {CO_CIA402_SWITCH_ON_DISABLED, CO_CIA402_CMD_SWITCH_ON, -1, CO_CIA402_SWITCH_ON_DISABLED},
        {CO_CIA402_SWITCH_ON_DISABLED, CO_CIA402_CMD_ENABLE_OPERATION, -1,
         CO_CIA402_SWITCH_ON_DISABLED},
        {CO_CIA402_SWITCH_ON_DISABLED, CO_CIA402_CMD_DISABLE_VOLTAGE, -1,
         CO_CIA402_SWITCH_ON_DISABLED},
        {CO_CIA402_SWITCH_ON_DISABLED, CO_CIA402_CMD_QUICK_STOP, -1, CO_CIA402_SWITCH_ON_DISABLED},
        {CO_CIA402_SWITCH_ON_DISABLED, CO_CIA402_CMD_FAULT_RESET, -1, CO_CIA402_SWITCH_ON_DISABLED},
        {CO_CIA402_READY_TO_SWITCH_ON, CO_CIA402_CMD_SWITCH_ON, 3, CO_CIA402_SWITCHED_ON},
        {CO_CIA402_READY_TO_SWITCH_ON, CO_CIA402_CMD_ENABLE_OPERATION, 3, CO_CIA402_SWITCHED_ON},
        {CO_CIA402_READY_TO_SWITCH_ON, CO_CIA402_CMD_DISABLE_VOLTAGE, 7,
         CO_CIA402_SWITCH_ON_DISABLED},
        {CO_CIA402_READY_TO_SWITCH_ON, CO_CIA402_CMD_QUICK_STOP, 7, CO_CIA402_SWITCH_ON_DISABLED},
        {CO_CIA402_READY_TO_SWITCH_ON, CO_CIA402_CMD_SHUTDOWN, -1, CO_CIA402_READY_TO_SWITCH_ON},
        {CO_CIA402_SWITCHED_ON, CO_CIA402_CMD_ENABLE_OPERATION, 4, CO_CIA402_OPERATION_ENABLED},
        {CO_CIA402_SWITCHED_ON, CO_CIA402_CMD_SHUTDOWN, 6, CO_CIA402_READY_TO_SWITCH_ON},
        {CO_CIA402_SWITCHED_ON, CO_CIA402_CMD_DISABLE_VOLTAGE, 10, CO_CIA402_SWITCH_ON_DISABLED},
        {CO_CIA402_SWITCHED_ON, CO_CIA402_CMD_QUICK_STOP, 10, CO_CIA402_SWITCH_ON_DISABLED},
        {CO_CIA402_SWITCHED_ON, CO_CIA402_CMD_SWITCH_ON, -1, CO_CIA402_SWITCHED_ON},
        {CO_CIA402_OPERATION_ENABLED, CO_CIA402_CMD_SWITCH_ON, 5, CO_CIA402_SWITCHED_ON},
        {CO_CIA402_OPERATION_ENABLED, CO_CIA402_CMD_SHUTDOWN, 8, CO_CIA402_READY_TO_SWITCH_ON},
        {CO_CIA402_OPERATION_ENABLED, CO_CIA402_CMD_DISABLE_VOLTAGE, 9,
         CO_CIA402_SWITCH_ON_DISABLED},
        {CO_CIA402_OPERATION_ENABLED, CO_CIA402_CMD_QUICK_STOP, 11, CO_CIA402_QUICK_STOP_ACTIVE},
        {CO_CIA402_OPERATION_ENABLED, CO_CIA402_CMD_ENABLE_OPERATION, -1,
         CO_CIA402_OPERATION_ENABLED},
        {CO_CIA402_QUICK_STOP_ACTIVE, CO_CIA402_CMD_DISABLE_VOLTAGE, 12,
         CO_CIA402_SWITCH_ON_DISABLED},
        {CO_CIA402_QUICK_STOP_ACTIVE, CO_CIA402_CMD_ENABLE_OPERATION, -1,
         CO_CIA402_QUICK_STOP_ACTIVE},
        {CO_CIA402_QUICK_STOP_ACTIVE, CO_CIA402_CMD_SHUTDOWN, -1, CO_CIA402_QUICK_STOP_ACTIVE},
        {CO_CIA402_QUICK_STOP_ACTIVE, CO_CIA402_CMD_SWITCH_ON, -1, CO_CIA402_QUICK_STOP_ACTIVE},
        {CO_CIA402_FAULT, CO_CIA402_CMD_FAULT_RESET, 15, CO_CIA402_SWITCH_ON_DISABLED},
        {CO_CIA402_FAULT, CO_CIA402_CMD_ENABLE_OPERATION, -1, CO_CIA402_FAULT},
        {CO_CIA402_FAULT, CO_CIA402_CMD_SHUTDOWN, -1, CO_CIA402_FAULT},
        {CO_CIA402_FAULT_REACTION_ACTIVE, CO_CIA402_CMD_FAULT_RESET, -1,
         CO_CIA402_FAULT_REACTION_ACTIVE},
        {CO_CIA402_FAULT_REACTION_ACTIVE, CO_CIA402_CMD_DISABLE_VOLTAGE, -1,
         CO_CIA402_FAULT_REACTION_ACTIVE},
        {CO_CIA402_NOT_READY_TO_SWITCH_ON, CO_CIA402_CMD_SHUTDOWN, -1,
         CO_CIA402_NOT_READY_TO_SWITCH_ON},
    };
    for (size_t i = 0; i < sizeof table / sizeof table[0]; i++) {
        co_cia402_state to;
        int t = co_cia402_next(table[i].from, table[i].cmd, 0, false, &to);
        TEST_ASSERT_EQUAL_INT_MESSAGE(table[i].transition, t, co_cia402_state_name(table[i].from));
        TEST_ASSERT_EQUAL(table[i].to, to);
    }
}

static void test_transition_16_needs_a_staying_option_code(void)
{
    co_cia402_state to;
    TEST_ASSERT_EQUAL_INT(16, co_cia402_next(CO_CIA402_QUICK_STOP_ACTIVE,
                                             CO_CIA402_CMD_ENABLE_OPERATION, 0, true, &to));
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, to);
    TEST_ASSERT_EQUAL_INT(16, co_cia402_next(CO_CIA402_QUICK_STOP_ACTIVE,
                                             CO_CIA402_CMD_ENABLE_OPERATION,
                                             CO_CIA402_ALWAYS_16, false, &to));
    TEST_ASSERT_EQUAL_INT(-1, co_cia402_next(CO_CIA402_QUICK_STOP_ACTIVE,
                                             CO_CIA402_CMD_DISABLE_VOLTAGE,
                                             CO_CIA402_QUICK_STOP_LOCKED, true, &to));
}

/* --- statusword ------------------------------------------------------------------------------ */

static void test_statusword_pattern_of_every_state(void)
{
    const uint16_t expected[8] = {0x0000, 0x0040, 0x0021, 0x0023, 0x0027, 0x0007, 0x000F, 0x0008};
    for (int s = 0; s < 8; s++) {
        co_cia402_status st = {(co_cia402_state)s, false, false, false, false, false, false, 0};
        uint16_t sw = co_cia402_statusword(&st, 0);
        TEST_ASSERT_EQUAL_HEX16(expected[s], sw);
        TEST_ASSERT_EQUAL((co_cia402_state)s, co_cia402_state_of(sw));
        st.voltage_enabled = st.warning = st.remote = st.target_reached = st.internal_limit = true;
        sw = co_cia402_statusword(&st, 0);
        TEST_ASSERT_EQUAL_HEX16(expected[s] | 0x0E90u, sw);
        TEST_ASSERT_EQUAL((co_cia402_state)s, co_cia402_state_of(sw));
    }
}

static void test_statusword_fault_keeps_quick_stop_bit_when_asked(void)
{
    co_cia402_status st = {CO_CIA402_FAULT, false, true, false, false, false, false, 0};
    TEST_ASSERT_EQUAL_HEX16(0x0008, co_cia402_statusword(&st, 0));
    TEST_ASSERT_EQUAL_HEX16(0x0028, co_cia402_statusword(&st, CO_CIA402_FAULT_KEEPS_QS_BIT));
    st.manufacturer = 0xFFFF; /* only bits 8 and 12-15 are the drive's */
    TEST_ASSERT_EQUAL_HEX16(0xF128, co_cia402_statusword(&st, CO_CIA402_FAULT_KEEPS_QS_BIT));
}

static void test_state_names_are_python_canopens(void)
{
    TEST_ASSERT_EQUAL_STRING("OPERATION ENABLED", co_cia402_state_name(CO_CIA402_OPERATION_ENABLED));
    TEST_ASSERT_EQUAL_STRING("SWITCH ON DISABLED",
                             co_cia402_state_name(CO_CIA402_SWITCH_ON_DISABLED));
    TEST_ASSERT_EQUAL_STRING("FAULT REACTION ACTIVE",
                             co_cia402_state_name(CO_CIA402_FAULT_REACTION_ACTIVE));
}

/* --- the drive: transitions with their actions ---------------------------------------------- */

static void test_start_passes_0_and_1_to_switch_on_disabled(void)
{
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    TEST_ASSERT_EQUAL(1, fx.d.last_transition);
    TEST_ASSERT_EQUAL_HEX16(0x0240, fx_sw(&fx));
}

static void test_transitions_2_3_4_by_controlword(void)
{
    fx_cw(&fx, 0x0006);
    TEST_ASSERT_EQUAL(2, fx.d.last_transition);
    TEST_ASSERT_EQUAL_HEX16(0x0231, fx_sw(&fx));
    fx_cw(&fx, 0x0007);
    TEST_ASSERT_EQUAL(3, fx.d.last_transition);
    TEST_ASSERT_EQUAL_HEX16(0x0233, fx_sw(&fx));
    fx_cw(&fx, 0x000F);
    TEST_ASSERT_EQUAL(4, fx.d.last_transition);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    TEST_ASSERT_TRUE(fx.d.output);
}

static void test_switch_on_and_enable_in_one_step_3_plus_4(void)
{
    fx_cw(&fx, 0x0006);
    fx_cw(&fx, 0x000F);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    TEST_ASSERT_EQUAL(4, fx.d.last_transition);
}

static void test_no_switch_on_enable_flag_stops_at_switched_on(void)
{
    plain.cia402_flags = CO_CIA402_NO_SWITCH_ON_ENABLE;
    restart();
    fx_cw(&fx, 0x0006);
    fx_cw(&fx, 0x000F);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCHED_ON, fx.d.state);
}

static void test_transition_5_ramps_down_with_option_1(void)
{
    run(1500);
    fx_cw(&fx, 0x0007);
    TEST_ASSERT_EQUAL(5, fx.d.last_transition);
    TEST_ASSERT_EQUAL_HEX16(0x0233, fx_sw(&fx));
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT16(750, fx_i16(&fx, 0x6044, 0));
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_FALSE(fx.d.output);
}

static void test_transition_5_option_0_coasts_and_hold_keeps_output(void)
{
    plain.disable_operation_option = 0;
    restart();
    run(1500);
    fx_cw(&fx, 0x0007);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
    plain.disable_operation_option = CO_DRIVE_OPTION_HOLD;
    restart();
    run(1500);
    fx_cw(&fx, 0x0007);
    fx_target(&fx, 0);
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6044, 0)); /* output frozen */
    fx_cw(&fx, 0x007F);
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT16(750, fx_i16(&fx, 0x6044, 0)); /* follows again */
}

static void test_transition_6_7_8_9_10_switch_the_output_off(void)
{
    run(1500);
    fx_cw(&fx, 0x0006); /* 8 */
    TEST_ASSERT_EQUAL(8, fx.d.last_transition);
    TEST_ASSERT_FALSE(fx.d.output);
    fx_cw(&fx, 0x0002); /* 7 by quick stop */
    TEST_ASSERT_EQUAL(7, fx.d.last_transition);
    fx_cw(&fx, 0x0006);
    fx_cw(&fx, 0x0007);
    fx_cw(&fx, 0x0006); /* 6 */
    TEST_ASSERT_EQUAL(6, fx.d.last_transition);
    fx_cw(&fx, 0x0007);
    fx_cw(&fx, 0x0000); /* 10 */
    TEST_ASSERT_EQUAL(10, fx.d.last_transition);
    fx_cw(&fx, 0x0006);
    fx_cw(&fx, 0x0007);
    fx_cw(&fx, 0x0002); /* 10 by quick stop */
    TEST_ASSERT_EQUAL(10, fx.d.last_transition);
    run(1500);
    fx_cw(&fx, 0x0000); /* 9 */
    TEST_ASSERT_EQUAL(9, fx.d.last_transition);
    TEST_ASSERT_FALSE(fx.d.output);
    TEST_ASSERT_EQUAL_HEX16(0x0240, fx_sw(&fx));
}

static void test_transition_11_and_automatic_12_with_option_2(void)
{
    run(1500);
    fx_cw(&fx, 0x000B);
    TEST_ASSERT_EQUAL(11, fx.d.last_transition);
    TEST_ASSERT_EQUAL_HEX16(0x0217, fx_sw(&fx));
    fx_advance(&fx, 9999999); /* no 0x604A here: the deceleration ramp */
    TEST_ASSERT_EQUAL(CO_CIA402_QUICK_STOP_ACTIVE, fx.d.state);
    fx_advance(&fx, 1);
    TEST_ASSERT_EQUAL(12, fx.d.last_transition);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_transition_12_by_disable_voltage_and_16_by_enable(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x605A, 0, 6, 2));
    run(1500);
    fx_cw(&fx, 0x0002);
    fx_advance(&fx, 20000000);
    TEST_ASSERT_EQUAL(CO_CIA402_QUICK_STOP_ACTIVE, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0x0617, fx_sw(&fx));
    fx_cw(&fx, 0x007F);
    TEST_ASSERT_EQUAL(16, fx.d.last_transition);
    fx_cw(&fx, 0x0002);
    fx_cw(&fx, 0x0000);
    TEST_ASSERT_EQUAL(12, fx.d.last_transition);
}

static void test_quick_stop_locked_runs_to_its_end(void)
{
    plain.cia402_flags = CO_CIA402_QUICK_STOP_LOCKED;
    restart();
    run(1500);
    fx_cw(&fx, 0x0002);
    fx_cw(&fx, 0x0000);
    TEST_ASSERT_EQUAL(CO_CIA402_QUICK_STOP_ACTIVE, fx.d.state);
    fx_advance(&fx, 10000000);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_quick_stop_option_0_disables_at_once(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x605A, 0, 0, 2));
    run(1500);
    fx_cw(&fx, 0x0002);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    TEST_ASSERT_EQUAL(12, fx.d.last_transition);
}

static void test_quick_stop_option_1_and_5_use_the_slow_down_ramp(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x605A, 0, 1, 2));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x6049, 2, 5, 2));
    run(1500);
    fx_cw(&fx, 0x0002);
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x605A, 0, 5, 2));
    run(1500);
    fx_cw(&fx, 0x0002);
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL(CO_CIA402_QUICK_STOP_ACTIVE, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
}

static void test_quick_stop_option_outside_the_dictionary_limits_refused(void)
{
    TEST_ASSERT_EQUAL_HEX32(0x06090031, fx_sdo_write(&fx, 0x605A, 0, 8, 2));
    TEST_ASSERT_EQUAL_HEX32(0x06090032, fx_sdo_write(&fx, 0x605A, 0, 0xFFFD, 2));
    TEST_ASSERT_EQUAL_INT16(2, fx_i16(&fx, 0x605A, 0));
}

static void test_quick_stop_manufacturer_option_uses_the_quick_ramp(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x605A, 0, 0xFFFF, 2)); /* -1 */
    run(1500);
    fx_cw(&fx, 0x0002);
    TEST_ASSERT_EQUAL(CO_CIA402_QUICK_STOP_ACTIVE, fx.d.state);
    fx_advance(&fx, 10000000);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

/* --- vl controlword bits and halt ----------------------------------------------------------- */

static void test_vl_0x000F_enables_at_standstill_0x007F_runs(void)
{
    fx_enable(&fx);
    fx_target(&fx, 600);
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX16(0, fx_sw(&fx) & 0x0400);
    fx_cw(&fx, 0x007F);
    fx_advance(&fx, 4000000);
    TEST_ASSERT_EQUAL_INT16(600, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX16(0x0400, fx_sw(&fx) & 0x0400);
}

static void test_vl_bit_5_holds_and_bit_6_ramps_to_zero(void)
{
    run(1500);
    fx_target(&fx, 0);
    fx_cw(&fx, 0x005F); /* rfg unlock = 0: hold */
    fx_advance(&fx, 3000000);
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6043, 0));
    fx_target(&fx, 1500);
    fx_cw(&fx, 0x003F); /* use ref = 0: ramp to 0 */
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT16(750, fx_i16(&fx, 0x6043, 0));
    fx_cw(&fx, 0x006F); /* rfg enable = 0: output 0 at once */
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6043, 0));
}

static void test_halt_ramps_to_zero_and_stays_enabled(void)
{
    run(1500);
    fx_cw(&fx, 0x017F);
    fx_advance(&fx, 9999999);
    TEST_ASSERT_EQUAL_INT16(1, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX16(0, fx_sw(&fx) & 0x0400);
    fx_advance(&fx, 1);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0x0637, fx_sw(&fx)); /* halted: target reached */
    fx_cw(&fx, 0x007F);
    fx_advance(&fx, 10000000);
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6044, 0));
}

static void test_limits_of_6046_on_a_plain_drive(void)
{
    fx_enable(&fx);
    fx_cw(&fx, 0x007F);
    fx_target(&fx, 5000);
    TEST_ASSERT_EQUAL_HEX16(0x0800, fx_sw(&fx) & 0x0800);
    fx_advance(&fx, 30000000);
    TEST_ASSERT_EQUAL_INT16(3000, fx_i16(&fx, 0x6044, 0));
}

static void test_target_kept_on_enable_without_the_clear_flag(void)
{
    fx_cw(&fx, 0x0006);
    fx_cw(&fx, 0x0007);
    fx_target(&fx, 300);
    fx_cw(&fx, 0x007F);
    TEST_ASSERT_EQUAL_INT16(300, fx_i16(&fx, 0x6042, 0));
}

/* --- faults --------------------------------------------------------------------------------- */

static void test_fault_path_13_14_and_reset_15(void)
{
    run(1500);
    fx_clear(&fx);
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x0002, fx.now));
    TEST_ASSERT_EQUAL(13, fx.d.last_transition);
    TEST_ASSERT_EQUAL_HEX16(0x020F, fx_sw(&fx));
    TEST_ASSERT_EQUAL_HEX16(0x4210, fx_u16(&fx, 0x603F, 0));
    fx_expect_emcy(&fx, 0x4210, 0x09, 0x02);
    TEST_ASSERT_EQUAL_UINT8(0, fx.bus.frames[fx.bus.count - 1u].data[4]);
    fx_advance(&fx, 999);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT_REACTION_ACTIVE, fx.d.state);
    fx_advance(&fx, 1);
    TEST_ASSERT_EQUAL(14, fx.d.last_transition);
    TEST_ASSERT_EQUAL_HEX16(0x0208, fx_sw(&fx));
    fx_cw(&fx, 0x0080);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT, fx.d.state); /* cause present */
    co_drive_clear_fault_cause(&fx.d);
    fx_cw(&fx, 0x0000);
    fx_cw(&fx, 0x0080);
    TEST_ASSERT_EQUAL(15, fx.d.last_transition);
    TEST_ASSERT_EQUAL_HEX16(0, fx_u16(&fx, 0x603F, 0));
    TEST_ASSERT_FALSE(co_emcy_is_active(&fx.d.node, 0x4210));
    fx_enable(&fx); /* back through the states after a reset */
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
}

static void test_fault_reaction_ramp_then_fault(void)
{
    plain.fault_reaction_option = 1;
    restart();
    run(1500);
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x0001, fx.now));
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT_REACTION_ACTIVE, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(750, fx_i16(&fx, 0x6044, 0));
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT, fx.d.state);
}

static void test_trip_from_any_state(void)
{
    const uint16_t cws[] = {0x0000, 0x0006, 0x0007, 0x000F};
    for (size_t i = 0; i < 4; i++) {
        restart();
        if (i >= 1) {
            fx_cw(&fx, 0x0006);
        }
        if (i >= 2) {
            fx_cw(&fx, cws[i]);
        }
        TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x0001, fx.now));
        fx_advance(&fx, 1000);
        TEST_ASSERT_EQUAL(CO_CIA402_FAULT, fx.d.state);
    }
}

static void test_report_only_row_sends_emcy_without_trip(void)
{
    fx_clear(&fx);
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x0003, fx.now));
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    fx_expect_emcy(&fx, 0x8210, 0x11, 0x03);
    co_drive_clear_error(&fx.d, 0x8210);
    fx_expect_emcy(&fx, 0x0000, 0x00, 0x00);
}

static void test_catch_all_trip_codes(void)
{
    TEST_ASSERT_FALSE(co_drive_inject_fault(&fx.d, 0x0777, fx.now));
    plain.other_trips_emcy = 0x1000;
    plain.other_trips_register = 0x01;
    restart();
    fx_clear(&fx);
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x0777, fx.now));
    fx_expect_emcy(&fx, 0x1000, 0x01, 0x77);
    TEST_ASSERT_EQUAL_HEX8(0x07, fx_last(&fx, 0x84)->data[4]);
}

static void test_fault_survives_a_node_reset_while_its_cause_stays(void)
{
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x0001, fx.now));
    fx_advance(&fx, 1000);
    fx_nmt(&fx, 0x81);
    fx_advance(&fx, 1000);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0x2310, fx_u16(&fx, 0x603F, 0));
    co_drive_clear_fault_cause(&fx.d);
    fx_nmt(&fx, 0x81);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0, fx_u16(&fx, 0x603F, 0));
}

static void test_fault_reset_from_outside_the_controlword(void)
{
    TEST_ASSERT_FALSE(co_drive_fault_reset(&fx.d, fx.now)); /* not in Fault */
    TEST_ASSERT_TRUE(co_drive_trip_emcy(&fx.d, 0x8130, false, fx.now));
    fx_advance(&fx, 1000);
    TEST_ASSERT_TRUE(co_drive_fault_reset(&fx.d, fx.now));
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_fault_keeps_quick_stop_bit_flag(void)
{
    plain.cia402_flags = CO_CIA402_FAULT_KEEPS_QS_BIT;
    restart();
    run(600);
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x0001, fx.now));
    fx_advance(&fx, 1000);
    TEST_ASSERT_EQUAL_HEX16(0x0228, fx_sw(&fx));
}

/* --- departures and reactions --------------------------------------------------------------- */

static bool never_yet(const co_drive *d)
{
    return d->var[0] != 0;
}

static void test_may_enable_waits_for_the_reference(void)
{
    plain.may_enable = never_yet;
    restart();
    fx_enable(&fx);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCHED_ON, fx.d.state);
    fx.d.var[0] = 1;
    fx_target(&fx, 100); /* the held enable is taken when the reference comes */
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
}

static void test_level_triggered_one_transition_per_tick(void)
{
    plain.flags = CO_DRIVE_LEVEL_TRIGGERED;
    restart();
    fx_cw(&fx, 0x0006);
    fx_advance(&fx, 1000);
    fx_cw(&fx, 0x000F);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCHED_ON, fx.d.state);
    fx_advance(&fx, 999);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCHED_ON, fx.d.state);
    fx_advance(&fx, 1);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
}

static void test_bit7_dont_care_flag(void)
{
    plain.cia402_flags = CO_CIA402_BIT7_DONT_CARE;
    restart();
    fx_cw(&fx, 0x0086);
    TEST_ASSERT_EQUAL(CO_CIA402_READY_TO_SWITCH_ON, fx.d.state);
    fx_cw(&fx, 0x0087);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCHED_ON, fx.d.state);
}

static void test_loss_reactions_warning_hold_preset_clear(void)
{
    run(1500);
    co_drive_loss_react(&fx.d, CO_DRIVE_LOSS_WARNING, 0, fx.now);
    TEST_ASSERT_EQUAL_HEX16(0x0080, fx_sw(&fx) & 0x0080);
    co_drive_loss_clear(&fx.d, fx.now);
    TEST_ASSERT_EQUAL_HEX16(0, fx_sw(&fx) & 0x0080);
    co_drive_loss_react(&fx.d, CO_DRIVE_LOSS_HOLD_OUTPUT, 0, fx.now);
    fx_target(&fx, 0);
    fx_advance(&fx, 3000000);
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6044, 0));
    co_drive_loss_clear(&fx.d, fx.now);
    fx_target(&fx, 1500);
    co_drive_loss_react(&fx.d, CO_DRIVE_LOSS_PRESET, 300, fx.now);
    fx_advance(&fx, 10000000);
    TEST_ASSERT_EQUAL_INT16(300, fx_i16(&fx, 0x6044, 0));
    co_drive_loss_clear(&fx.d, fx.now);
    fx_advance(&fx, 10000000);
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6044, 0));
}

static void test_loss_reactions_stop_and_trip(void)
{
    run(1500);
    co_drive_loss_react(&fx.d, CO_DRIVE_LOSS_QUICK_STOP, 0, fx.now);
    TEST_ASSERT_EQUAL(CO_CIA402_QUICK_STOP_ACTIVE, fx.d.state);
    fx_advance(&fx, 11000000);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    run(1500);
    co_drive_loss_react(&fx.d, CO_DRIVE_LOSS_DISABLE_VOLTAGE, 0, fx.now);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    run(1500);
    co_drive_loss_react(&fx.d, CO_DRIVE_LOSS_COAST_STOP, 0, fx.now);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    run(1500);
    co_drive_loss_react(&fx.d, CO_DRIVE_LOSS_TRIP, 0x8130, fx.now);
    fx_advance(&fx, 1000);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT, fx.d.state);
    TEST_ASSERT_FALSE(co_drive_fault_reset(&fx.d, fx.now)); /* the loss lasts */
    co_drive_loss_clear(&fx.d, fx.now);
    TEST_ASSERT_TRUE(co_drive_fault_reset(&fx.d, fx.now));
}

static int observed[20];
static int observed_count;

static void observe(co_drive *d, void *ctx, int transition, co_cia402_state from,
                    co_cia402_state to)
{
    (void)d;
    (void)from;
    (void)to;
    TEST_ASSERT_EQUAL_PTR(&observed_count, ctx);
    if (observed_count < 20) {
        observed[observed_count++] = transition;
    }
}

static void test_observer_hears_every_transition(void)
{
    const co_drive_observer obs = {observe, &observed_count};
    observed_count = 0;
    co_drive_observe(&fx.d, &obs);
    fx_enable(&fx);
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x0001, fx.now));
    fx_advance(&fx, 1000);
    const int expected[] = {2, 3, 4, 13, 14};
    TEST_ASSERT_EQUAL_INT(5, observed_count);
    TEST_ASSERT_EQUAL_INT_ARRAY(expected, observed, 5);
}

static void test_settings_by_name(void)
{
    TEST_ASSERT_EQUAL_INT32(10, fx.d.setting[0]);
    TEST_ASSERT_TRUE(co_drive_set_setting(&fx.d, "speed_limit", 55));
    TEST_ASSERT_EQUAL_INT32(55, fx.d.setting[0]);
    TEST_ASSERT_FALSE(co_drive_set_setting(&fx.d, "speed_limit", 101));
    TEST_ASSERT_FALSE(co_drive_set_setting(&fx.d, "nonsense", 1));
}

static void test_init_refuses_a_foreign_dictionary(void)
{
    co_drive d;
    uint8_t values[16];
    co_node_config cfg = co_node_default_config();
    cfg.node_id = 1;
    cfg.values = values;
    cfg.driver = fake_bus_driver(&fx.bus);
    co_od other = co_od_test;
    cfg.od = &other;
    TEST_ASSERT_FALSE(co_drive_init(&d, &plain, &cfg));
    TEST_ASSERT_FALSE(co_drive_init(&d, NULL, &cfg));
}

static void test_rpdo_carrying_controlword_and_target(void)
{
    plain.flags = CO_DRIVE_CLEAR_TARGET | CO_DRIVE_RFG_IGNORED;
    restart();
    fx_nmt(&fx, 0x01);
    fx_cw(&fx, 0x0006);
    fx_cw(&fx, 0x0007);
    /* an SDO target before the enable is cleared by it */
    fx_target(&fx, 700);
    fx_cw(&fx, 0x000F);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6042, 0));
}

static void test_sdo_read_between_ticks_sees_its_moment(void)
{
    fx_enable(&fx);
    fx_cw(&fx, 0x007F);
    fx_target(&fx, 1500);
    fx.now += 2500; /* no process call in between */
    uint32_t v = 0;
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x6043, 0, &v));
    TEST_ASSERT_EQUAL_UINT32(0, v); /* 2.5 ms at 150 rpm/s: 0.375 */
    fx.now += 997500;
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x6043, 0, &v));
    TEST_ASSERT_EQUAL_UINT32(150, v);
}

/* --- the deadline contract (drive.h): the pass is skipped while nothing is due or new -------- */

static uint32_t process_calls;   /* calls of counting_process */
static uint64_t process_due;     /* the deadline counting_process returns */

static uint64_t counting_process(co_drive *d, uint64_t now)
{
    (void)d;
    process_calls++;
    return now < process_due ? process_due : CO_TIME_NEVER;
}

static void test_idle_calls_skip_the_description_until_its_deadline_or_a_wake(void)
{
    plain.process = counting_process;
    process_due = 50000;
    restart();
    fx_advance(&fx, 10000);
    TEST_ASSERT_EQUAL_UINT64(50000, fx.next); /* no heartbeat: the description's deadline */
    uint32_t calls = process_calls;
    for (int i = 0; i < 100; i++) {
        fx.now += 7;
        TEST_ASSERT_EQUAL_UINT64(50000, co_drive_process(&fx.d, fx.now));
    }
    TEST_ASSERT_EQUAL_UINT32(calls, process_calls); /* nothing due, nothing new */
    co_drive_wake(&fx.d);
    (void)co_drive_process(&fx.d, fx.now);
    TEST_ASSERT_EQUAL_UINT32(calls + 1u, process_calls);
    fx.now += 1u;
    (void)co_drive_process(&fx.d, fx.now);
    TEST_ASSERT_EQUAL_UINT32(calls + 1u, process_calls);
    fx_at(&fx, 50000);
    TEST_ASSERT_EQUAL_UINT32(calls + 2u, process_calls); /* at its deadline */
    TEST_ASSERT_EQUAL_UINT64(CO_TIME_NEVER, fx.next);
}

static void test_a_transition_wakes_the_description(void)
{
    plain.process = counting_process;
    process_due = 0;
    restart();
    fx_advance(&fx, 1000);
    uint32_t calls = process_calls;
    fx_cw(&fx, 0x0006); /* transition 2 */
    TEST_ASSERT_EQUAL(CO_CIA402_READY_TO_SWITCH_ON, fx.d.state);
    (void)co_drive_process(&fx.d, fx.now);
    TEST_ASSERT_TRUE(process_calls > calls);
}

static void test_target_stored_while_idle_is_taken_when_running(void)
{
    fx_target(&fx, 600); /* Switch on disabled: only stored, nothing woken */
    TEST_ASSERT_TRUE(fx.d.pass_at != 0u);
    fx_advance(&fx, 5000);
    fx_enable(&fx);
    fx_cw(&fx, 0x007F);
    fx_advance(&fx, 30000000);
    TEST_ASSERT_EQUAL_INT16(600, fx_i16(&fx, 0x6044, 0));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_decode_every_command_of_table_27);
    RUN_TEST(test_decode_fault_reset_is_the_rising_edge_of_bit_7);
    RUN_TEST(test_every_state_and_command);
    RUN_TEST(test_transition_16_needs_a_staying_option_code);
    RUN_TEST(test_statusword_pattern_of_every_state);
    RUN_TEST(test_statusword_fault_keeps_quick_stop_bit_when_asked);
    RUN_TEST(test_state_names_are_python_canopens);
    RUN_TEST(test_start_passes_0_and_1_to_switch_on_disabled);
    RUN_TEST(test_transitions_2_3_4_by_controlword);
    RUN_TEST(test_switch_on_and_enable_in_one_step_3_plus_4);
    RUN_TEST(test_no_switch_on_enable_flag_stops_at_switched_on);
    RUN_TEST(test_transition_5_ramps_down_with_option_1);
    RUN_TEST(test_transition_5_option_0_coasts_and_hold_keeps_output);
    RUN_TEST(test_transition_6_7_8_9_10_switch_the_output_off);
    RUN_TEST(test_transition_11_and_automatic_12_with_option_2);
    RUN_TEST(test_transition_12_by_disable_voltage_and_16_by_enable);
    RUN_TEST(test_quick_stop_locked_runs_to_its_end);
    RUN_TEST(test_quick_stop_option_0_disables_at_once);
    RUN_TEST(test_quick_stop_option_1_and_5_use_the_slow_down_ramp);
    RUN_TEST(test_quick_stop_option_outside_the_dictionary_limits_refused);
    RUN_TEST(test_quick_stop_manufacturer_option_uses_the_quick_ramp);
    RUN_TEST(test_vl_0x000F_enables_at_standstill_0x007F_runs);
    RUN_TEST(test_vl_bit_5_holds_and_bit_6_ramps_to_zero);
    RUN_TEST(test_halt_ramps_to_zero_and_stays_enabled);
    RUN_TEST(test_limits_of_6046_on_a_plain_drive);
    RUN_TEST(test_target_kept_on_enable_without_the_clear_flag);
    RUN_TEST(test_fault_path_13_14_and_reset_15);
    RUN_TEST(test_fault_reaction_ramp_then_fault);
    RUN_TEST(test_trip_from_any_state);
    RUN_TEST(test_report_only_row_sends_emcy_without_trip);
    RUN_TEST(test_catch_all_trip_codes);
    RUN_TEST(test_fault_survives_a_node_reset_while_its_cause_stays);
    RUN_TEST(test_fault_reset_from_outside_the_controlword);
    RUN_TEST(test_fault_keeps_quick_stop_bit_flag);
    RUN_TEST(test_may_enable_waits_for_the_reference);
    RUN_TEST(test_level_triggered_one_transition_per_tick);
    RUN_TEST(test_bit7_dont_care_flag);
    RUN_TEST(test_loss_reactions_warning_hold_preset_clear);
    RUN_TEST(test_loss_reactions_stop_and_trip);
    RUN_TEST(test_observer_hears_every_transition);
    RUN_TEST(test_settings_by_name);
    RUN_TEST(test_init_refuses_a_foreign_dictionary);
    RUN_TEST(test_rpdo_carrying_controlword_and_target);
    RUN_TEST(test_sdo_read_between_ticks_sees_its_moment);
    RUN_TEST(test_idle_calls_skip_the_description_until_its_deadline_or_a_wake);
    RUN_TEST(test_a_transition_wakes_the_description);
    RUN_TEST(test_target_stored_while_idle_is_taken_when_running);
    return UNITY_END();
}
