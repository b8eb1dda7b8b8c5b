/* Toshiba VF-S15 CANopen (od/vf-s15): the manual's §7 example frame for frame, its state machine
 * departures, velocity limits and ramps, quick stop options, trip table, communication loss. All
 * on the virtual clock. Manual: Toshiba "TOSVERT VF-S15 series CANopen Communication Function Manual". */
#include "drive_fixture.h"
#include "drive_trips_vf_s15.h"

extern const co_drive_desc co_drive_desc_vf_s15;

static drive_fx fx;

void setUp(void)
{
    fx_start(&fx, &co_drive_desc_vf_s15, 1);
}

void tearDown(void) {}

/* The §7 set-up: command and frequency from CANopen. */
static void canopen_control(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2003, 0, 3, 2)); /* CMOd = 3 */
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2004, 0, 6, 2)); /* FMOd = 6 */
}

static void rpdo1(uint16_t cw, int16_t target)
{
    const uint8_t b[8] = {(uint8_t)cw, (uint8_t)(cw >> 8), (uint8_t)target,
                          (uint8_t)((uint16_t)target >> 8), 0, 0, 0, 0};
    fx_rx(&fx, 0x201, 8, b);
}

/* Operation enabled at speed rpm (reached). */
static void running_at(int16_t rpm)
{
    canopen_control();
    fx_enable(&fx);
    fx_target(&fx, rpm);
    fx_advance(&fx, 20000000);
    TEST_ASSERT_EQUAL_INT16(rpm, fx_i16(&fx, 0x6044, 0));
}

/* --- boot and the §7 example -------------------------------------------------------------- */

static void test_boots_in_switch_on_disabled_with_mains_bit(void)
{
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0x0050, fx_sw(&fx)); /* 0x0040 + bit 4: main circuit charged */
    uint32_t v = 0;
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x6061, 0, &v));
    TEST_ASSERT_EQUAL_UINT32(2, v);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x6502, 0, &v));
    TEST_ASSERT_EQUAL_HEX32(0x00000002, v);
    TEST_ASSERT_EQUAL_UINT16(1, fx_u16(&fx, 0x4701, 0)); /* C701: the commissioned node-ID */
}

static void test_manual_section_7_asynchronous_example_frame_for_frame(void)
{
    canopen_control();
    fx_clear(&fx);
    const uint8_t start[2] = {0x01, 0x01};
    fx_rx(&fx, 0x000, 2, start);
    rpdo1(0x0006, 0);
    TEST_ASSERT_EQUAL_HEX16(0x0231, fx_sw(&fx)); /* ready to switch on, remote */
    rpdo1(0x0007, 0);
    TEST_ASSERT_EQUAL_HEX16(0x0233, fx_sw(&fx));
    rpdo1(0x000F, 0x05DC);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6042, 0)); /* taken after the transition */
    TEST_ASSERT_EQUAL_HEX16(0x0237, fx_sw(&fx));           /* running up: not reached yet */
    fx_advance(&fx, 10000000);
    fx_clear(&fx);
    fx_rtr(&fx, 0x181);
    const co_frame *f = fx_last(&fx, 0x181);
    TEST_ASSERT_NOT_NULL(f);
    const uint8_t expected[4] = {0x37, 0x06, 0xDC, 0x05};
    TEST_ASSERT_EQUAL_UINT8(4, f->dlc);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expected, f->data, 4);
}

static void test_tpdo1_follows_the_ramp_by_itself(void)
{
    canopen_control();
    fx_nmt(&fx, 0x01);
    rpdo1(0x0006, 0);
    rpdo1(0x0007, 0);
    rpdo1(0x000F, 1500);
    fx_clear(&fx);
    fx_advance(&fx, 1000000);
    TEST_ASSERT_TRUE(fx_count(&fx, 0x181) >= 10); /* event-driven, inhibit 3 ms */
    const co_frame *f = fx_last(&fx, 0x181);
    TEST_ASSERT_EQUAL_INT16(150, (int16_t)(f->data[2] | (f->data[3] << 8)));
}

static void test_section_7_2_synchronous_example(void)
{
    canopen_control();
    /* C713/C716 = 1 act at the next reset; 0x1400:02 is read-only (NOTES Choices 3): the live
       transmission types are set by the application here, as the reset would. */
    TEST_ASSERT_EQUAL_HEX32(0, co_od_set_u8(&fx.d.node, 0x1400, 2, 1));
    TEST_ASSERT_EQUAL_HEX32(0, co_od_set_u8(&fx.d.node, 0x1800, 2, 1));
    co_pdo_configure(&fx.d.node, fx.now);
    fx_nmt(&fx, 0x01);
    rpdo1(0x0006, 0);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state); /* waits for the SYNC */
    fx_rx(&fx, 0x080, 0, NULL);
    TEST_ASSERT_EQUAL(CO_CIA402_READY_TO_SWITCH_ON, fx.d.state);
    rpdo1(0x0007, 0);
    fx_rx(&fx, 0x080, 0, NULL);
    rpdo1(0x000F, 0x05DC);
    fx_rx(&fx, 0x080, 0, NULL);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    fx_advance(&fx, 10000000);
    fx_clear(&fx);
    fx_rx(&fx, 0x080, 0, NULL);
    const co_frame *f = fx_last(&fx, 0x181);
    TEST_ASSERT_NOT_NULL(f);
    const uint8_t expected[4] = {0x37, 0x06, 0xDC, 0x05};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expected, f->data, 4);
}

/* --- state machine departures ------------------------------------------------------------- */

static void test_0x000F_in_ready_switches_on_and_enables_in_one_step(void)
{
    fx_cw(&fx, 0x0006);
    fx_cw(&fx, 0x000F);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0x0437, fx_sw(&fx)); /* at 0 with target 0: reached */
}

static void test_0x000F_in_switch_on_disabled_does_nothing(void)
{
    fx_cw(&fx, 0x000F);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_bit_7_high_carries_no_command(void)
{
    fx_cw(&fx, 0x0006);
    fx_cw(&fx, 0x0087); /* a fault reset edge outside Fault, then nothing */
    TEST_ASSERT_EQUAL(CO_CIA402_READY_TO_SWITCH_ON, fx.d.state);
    fx_cw(&fx, 0x008F);
    TEST_ASSERT_EQUAL(CO_CIA402_READY_TO_SWITCH_ON, fx.d.state);
}

static void test_remote_bit_needs_cmod_3_and_fmod_6(void)
{
    TEST_ASSERT_EQUAL_HEX16(0, fx_sw(&fx) & 0x0200);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2003, 0, 3, 2));
    TEST_ASSERT_EQUAL_HEX16(0, fx_sw(&fx) & 0x0200);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2004, 0, 6, 2));
    TEST_ASSERT_EQUAL_HEX16(0x0200, fx_sw(&fx) & 0x0200);
}

static void test_factory_cmod_keeps_the_motor_still(void)
{
    fx_enable(&fx); /* CMOd = 1, FMOd = 0: the state machine follows, the motor does not */
    fx_target(&fx, 1500);
    fx_advance(&fx, 12000000);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
}

static void test_target_cleared_on_entering_operation_enabled(void)
{
    canopen_control();
    fx_cw(&fx, 0x0006);
    fx_cw(&fx, 0x0007);
    fx_target(&fx, 1000); /* §5.1.4: written before the transition, lost */
    fx_cw(&fx, 0x000F);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6042, 0));
    fx_advance(&fx, 1000000);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
}

static void test_halt_and_rfg_bits_are_ignored(void)
{
    running_at(1500);
    fx_cw(&fx, 0x010F); /* halt */
    fx_advance(&fx, 1000000);
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6044, 0));
}

static void test_mains_lost_in_switched_on_for_3_s(void)
{
    fx_cw(&fx, 0x0006);
    fx_cw(&fx, 0x0007);
    co_drive_set_mains(&fx.d, false, fx.now);
    TEST_ASSERT_EQUAL_HEX16(0, fx_sw(&fx) & 0x0010);
    fx_advance(&fx, 2999999);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCHED_ON, fx.d.state);
    fx_advance(&fx, 1);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_modes_of_operation_accepts_any_value_and_shows_2(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x6060, 0, 0xFD, 1));
    uint32_t v = 0;
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x6061, 0, &v));
    TEST_ASSERT_EQUAL_UINT32(2, v);
}

/* --- velocity ------------------------------------------------------------------------------ */

static void test_ramp_0_to_1500_reaches_at_10_s_to_the_tick_monotone(void)
{
    canopen_control();
    fx_enable(&fx);
    fx_target(&fx, 1500);
    uint64_t t0 = fx.now;
    int16_t previous = 0;
    for (uint32_t ms = 1; ms <= 10000; ms++) {
        fx_at(&fx, t0 + ms * 1000u);
        int16_t v = fx_i16(&fx, 0x6043, 0);
        TEST_ASSERT_TRUE(v >= previous);
        previous = v;
        if (ms == 9999) {
            TEST_ASSERT_EQUAL_INT16(1499, v);
            TEST_ASSERT_EQUAL_HEX16(0, fx_sw(&fx) & 0x0400);
        }
    }
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6043, 0));
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX16(0x0637, fx_sw(&fx));
}

static void test_ramp_is_a_straight_line_of_6048(void)
{
    canopen_control();
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x6048, 2, 5, 2)); /* 1500 per 5 s */
    fx_enable(&fx);
    fx_target(&fx, 1200);
    fx_advance(&fx, 1000000);
    TEST_ASSERT_EQUAL_INT16(300, fx_i16(&fx, 0x6043, 0));
    fx_advance(&fx, 3000000);
    TEST_ASSERT_EQUAL_INT16(1200, fx_i16(&fx, 0x6043, 0));
}

static void test_deceleration_uses_6049(void)
{
    running_at(1500);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x6049, 2, 3, 2)); /* 1500 per 3 s */
    fx_target(&fx, 0);
    fx_advance(&fx, 1000000);
    TEST_ASSERT_EQUAL_INT16(1000, fx_i16(&fx, 0x6043, 0));
    fx_advance(&fx, 2000000);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6043, 0));
}

static void test_delta_time_0_is_a_step(void)
{
    canopen_control();
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x6048, 2, 0, 2));
    fx_enable(&fx);
    fx_target(&fx, 900);
    TEST_ASSERT_EQUAL_INT16(900, fx_i16(&fx, 0x6044, 0));
}

static void test_reversal_decelerates_through_zero(void)
{
    running_at(600);
    fx_target(&fx, -600);
    fx_advance(&fx, 4000000); /* 600 -> 0 in 4 s */
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6043, 0));
    fx_advance(&fx, 2000000);
    TEST_ASSERT_EQUAL_INT16(-300, fx_i16(&fx, 0x6043, 0));
    fx_advance(&fx, 2000000);
    TEST_ASSERT_EQUAL_INT16(-600, fx_i16(&fx, 0x6044, 0));
}

static void test_max_amount_clamps_and_sets_internal_limit(void)
{
    canopen_control();
    fx_enable(&fx);
    fx_target(&fx, 3000); /* 6046:02 = 1500: clamped, not refused (§5.1) */
    TEST_ASSERT_EQUAL_INT16(3000, fx_i16(&fx, 0x6042, 0));
    TEST_ASSERT_EQUAL_HEX16(0x0800, fx_sw(&fx) & 0x0800);
    fx_advance(&fx, 20000000);
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX16(0x0E37, fx_sw(&fx));
    fx_target(&fx, -3000);
    fx_advance(&fx, 30000000);
    TEST_ASSERT_EQUAL_INT16(-1500, fx_i16(&fx, 0x6044, 0));
    fx_target(&fx, 1000);
    TEST_ASSERT_EQUAL_HEX16(0, fx_sw(&fx) & 0x0800);
}

static void test_min_amount_raises_small_targets_but_not_zero(void)
{
    canopen_control();
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x6046, 1, 300, 4));
    fx_enable(&fx);
    fx_target(&fx, 100);
    TEST_ASSERT_EQUAL_HEX16(0x0800, fx_sw(&fx) & 0x0800);
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT16(300, fx_i16(&fx, 0x6044, 0));
    fx_target(&fx, -100);
    fx_advance(&fx, 10000000);
    TEST_ASSERT_EQUAL_INT16(-300, fx_i16(&fx, 0x6044, 0));
    fx_target(&fx, 0);
    TEST_ASSERT_EQUAL_HEX16(0, fx_sw(&fx) & 0x0800);
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
}

static void test_min_above_max_is_refused(void)
{
    TEST_ASSERT_EQUAL_HEX32(0x06090036, fx_sdo_write(&fx, 0x6046, 1, 2000, 4));
    TEST_ASSERT_EQUAL_UINT32(0, fx_u32(&fx, 0x6046, 1));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x6046, 1, 500, 4));
    TEST_ASSERT_EQUAL_HEX32(0x06090036, fx_sdo_write(&fx, 0x6046, 2, 400, 4));
    TEST_ASSERT_EQUAL_UINT32(1500, fx_u32(&fx, 0x6046, 2));
}

static void test_acceleration_out_of_range_refused(void)
{
    TEST_ASSERT_EQUAL_HEX32(0x06090032, fx_sdo_write(&fx, 0x6048, 1, 100, 4));
    TEST_ASSERT_EQUAL_HEX32(0x06090031, fx_sdo_write(&fx, 0x6048, 2, 3601, 2));
    TEST_ASSERT_EQUAL_UINT32(1500, fx_u32(&fx, 0x6048, 1));
}

static void test_pole_count_f856_sets_the_output_frequency(void)
{
    running_at(1500);
    TEST_ASSERT_EQUAL_INT32(5000, fx.d.motor.frequency); /* 4 poles: 50.00 Hz */
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2856, 0, 1, 2)); /* 2 poles */
    fx_advance(&fx, 1000);
    TEST_ASSERT_EQUAL_INT32(2500, fx.d.motor.frequency);
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6044, 0));
}

/* --- stops ---------------------------------------------------------------------------------- */

static void test_disable_operation_decelerates_on_6049_in_switched_on(void)
{
    running_at(1500);
    fx_cw(&fx, 0x0007);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCHED_ON, fx.d.state);
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT16(750, fx_i16(&fx, 0x6044, 0));
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
}

static void test_shutdown_and_disable_voltage_coast(void)
{
    running_at(1500);
    fx_cw(&fx, 0x0006); /* 8 */
    TEST_ASSERT_EQUAL(CO_CIA402_READY_TO_SWITCH_ON, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
    running_at(1500);
    fx_cw(&fx, 0x0000); /* 9 */
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
}

static void quick_stop_with(int16_t code)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x605A, 0, (uint16_t)code, 2));
    running_at(1500);
    fx_cw(&fx, 0x000B);
}

static void test_quick_stop_option_0_coasts_to_switch_on_disabled(void)
{
    quick_stop_with(0);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
}

static void test_quick_stop_option_1_slow_down_ramp_then_disabled(void)
{
    quick_stop_with(1);
    TEST_ASSERT_EQUAL_HEX16(0x0217, fx_sw(&fx)); /* quick stop active, remote */
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT16(750, fx_i16(&fx, 0x6044, 0));
    fx_advance(&fx, 4999999);
    TEST_ASSERT_EQUAL(CO_CIA402_QUICK_STOP_ACTIVE, fx.d.state);
    fx_advance(&fx, 1);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_quick_stop_option_2_quick_stop_ramp_then_disabled(void)
{
    quick_stop_with(2); /* 604A 3420 min-1 per 6 s: 1500 in 2.6316 s */
    fx_advance(&fx, 1000000);
    TEST_ASSERT_EQUAL_INT16(1500 - 570, fx_i16(&fx, 0x6044, 0));
    fx_advance(&fx, 1631578);
    TEST_ASSERT_EQUAL(CO_CIA402_QUICK_STOP_ACTIVE, fx.d.state);
    fx_advance(&fx, 1);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
}

static void test_quick_stop_option_2_refuses_transition_16(void)
{
    quick_stop_with(2);
    fx_cw(&fx, 0x000F);
    TEST_ASSERT_EQUAL(CO_CIA402_QUICK_STOP_ACTIVE, fx.d.state);
}

static void test_quick_stop_option_5_stays_and_16_reenables(void)
{
    quick_stop_with(5);
    fx_advance(&fx, 11000000);
    TEST_ASSERT_EQUAL(CO_CIA402_QUICK_STOP_ACTIVE, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0x0617, fx_sw(&fx)); /* target reached: at standstill */
    fx_cw(&fx, 0x000F);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    TEST_ASSERT_EQUAL(16, fx.d.last_transition);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6042, 0)); /* cleared on every entry */
}

static void test_quick_stop_option_6_quick_ramp_stays(void)
{
    quick_stop_with(6);
    fx_advance(&fx, 3000000);
    TEST_ASSERT_EQUAL(CO_CIA402_QUICK_STOP_ACTIVE, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
    fx_cw(&fx, 0x0000); /* 12 */
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_quick_stop_options_3_4_7_8_negative_and_reserved(void)
{
    quick_stop_with(3); /* 'do not set': as 2 */
    fx_advance(&fx, 2700000);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    quick_stop_with(4); /* voltage limit: simulated on 604A */
    fx_advance(&fx, 2700000);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    quick_stop_with(7); /* as 6 */
    fx_advance(&fx, 2700000);
    TEST_ASSERT_EQUAL(CO_CIA402_QUICK_STOP_ACTIVE, fx.d.state);
    fx_cw(&fx, 0x0000);
    quick_stop_with(8);
    fx_advance(&fx, 2700000);
    TEST_ASSERT_EQUAL(CO_CIA402_QUICK_STOP_ACTIVE, fx.d.state);
    fx_cw(&fx, 0x0000);
    quick_stop_with(-1); /* no function: output off */
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    quick_stop_with(9); /* reserved: output off */
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_disable_voltage_during_quick_stop_coasts(void)
{
    quick_stop_with(1);
    fx_advance(&fx, 1000000);
    fx_cw(&fx, 0x0000);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    TEST_ASSERT_EQUAL(12, fx.d.last_transition);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
}

/* --- faults --------------------------------------------------------------------------------- */

static void test_oc1_trip_gives_2310_everywhere(void)
{
    running_at(1500);
    fx_clear(&fx);
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x01, fx.now));
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT_REACTION_ACTIVE, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0x021F, fx_sw(&fx));
    TEST_ASSERT_EQUAL_HEX16(0x2310, fx_u16(&fx, 0x603F, 0));
    TEST_ASSERT_EQUAL_HEX8(0x03, fx_u8(&fx, 0x1001, 0)); /* current + generic */
    TEST_ASSERT_EQUAL_HEX32(0x00002310, fx_u32(&fx, 0x1003, 1));
    fx_expect_emcy(&fx, 0x2310, 0x03, 0x01);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0)); /* output off */
    fx_advance(&fx, 1000);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0x0218, fx_sw(&fx));
}

static void test_fault_reset_only_once_the_cause_is_cleared(void)
{
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x11, fx.now)); /* emergency stop E */
    fx_advance(&fx, 1000);
    TEST_ASSERT_EQUAL_HEX16(0x9000, fx_u16(&fx, 0x603F, 0));
    fx_cw(&fx, 0x0080);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT, fx.d.state);
    co_drive_clear_fault_cause(&fx.d);
    fx_cw(&fx, 0x0080); /* level, no edge: nothing */
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT, fx.d.state);
    fx_clear(&fx);
    fx_cw(&fx, 0x0000);
    fx_cw(&fx, 0x0080);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    TEST_ASSERT_EQUAL(15, fx.d.last_transition);
    TEST_ASSERT_EQUAL_HEX16(0, fx_u16(&fx, 0x603F, 0));
    TEST_ASSERT_EQUAL_HEX8(0, fx_u8(&fx, 0x1001, 0));
    fx_expect_emcy(&fx, 0x0000, 0x00, 0x00);
}

static void test_every_trip_of_the_table_raises_its_emcy(void)
{
    for (uint32_t i = 0; i < DRIVE_TRIP_COUNT_VF_S15; i++) {
        const co_drive_trip *t = &co_drive_trips_vf_s15[i];
        fx_start(&fx, &co_drive_desc_vf_s15, 1);
        fx_clear(&fx);
        if ((t->flags & CO_DRIVE_TRIP_NO_CODE) != 0u) {
            TEST_ASSERT_TRUE(co_drive_trip_emcy(&fx.d, t->emcy_code, true, fx.now));
        } else {
            TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, t->trip_code, fx.now));
        }
        uint8_t reg = (uint8_t)(t->error_register | 0x01u);
        fx_expect_emcy(&fx, t->emcy_code, reg, (uint8_t)t->trip_code);
        TEST_ASSERT_EQUAL_HEX16(t->emcy_code, fx_u16(&fx, 0x603F, 0));
        TEST_ASSERT_EQUAL_HEX8(reg, fx_u8(&fx, 0x1001, 0));
        fx_advance(&fx, 1000);
        TEST_ASSERT_EQUAL(CO_CIA402_FAULT, fx.d.state);
        co_drive_clear_fault_cause(&fx.d);
        fx_cw(&fx, 0x0080);
        TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    }
}

static void test_unknown_trip_code_refused(void)
{
    TEST_ASSERT_FALSE(co_drive_inject_fault(&fx.d, 0x99, fx.now));
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_fa04_resets_a_fault(void)
{
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x10, fx.now)); /* OH */
    fx_advance(&fx, 1000);
    co_drive_clear_fault_cause(&fx.d);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2A04, 0, 1, 2));
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_second_trip_keeps_the_first(void)
{
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x01, fx.now));
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x10, fx.now));
    fx_advance(&fx, 1000);
    TEST_ASSERT_EQUAL_HEX16(0x2310, fx_u16(&fx, 0x603F, 0));
}

/* --- communication loss (C100-C103) --------------------------------------------------------- */

static void heartbeat_from_master(void)
{
    const uint8_t op = 0x05;
    fx_rx(&fx, 0x77F, 1, &op);
}

/* Running at 1500 with the master's heartbeat monitored at 100 ms. */
static void monitored_and_running(void)
{
    running_at(1500);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x1016, 1, (0x7Fu << 16) | 100u, 4));
    heartbeat_from_master();
}

static void test_heartbeat_loss_c101_4_trips_8130(void)
{
    monitored_and_running();
    fx_advance(&fx, 99999);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    fx_advance(&fx, 1);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT_REACTION_ACTIVE, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0x8130, fx_u16(&fx, 0x603F, 0));
    fx_advance(&fx, 1000);
    fx_cw(&fx, 0x0080); /* still lost: refused */
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT, fx.d.state);
    heartbeat_from_master();
    fx_cw(&fx, 0x0000);
    fx_cw(&fx, 0x0080);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_heartbeat_loss_c101_2_decelerates_then_disabled(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4101, 0, 2, 2));
    monitored_and_running();
    fx_advance(&fx, 100000 + 5000000);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(750, fx_i16(&fx, 0x6044, 0));
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_heartbeat_loss_c101_3_coasts(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4101, 0, 3, 2));
    monitored_and_running();
    fx_advance(&fx, 100000);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
}

static void test_heartbeat_loss_c101_1_keeps_running(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4101, 0, 1, 2));
    monitored_and_running();
    fx_nmt(&fx, 0x01); /* (0x1016 is read-only in OPERATIONAL, §6.2) */
    heartbeat_from_master();
    fx_clear(&fx);
    fx_advance(&fx, 1000000);
    fx_expect_emcy(&fx, 0x8130, 0x11, 0x00); /* the loss is reported (§6.3.4) */
    TEST_ASSERT_EQUAL(CO_NMT_OPERATIONAL, fx.d.node.nmt_state); /* no 0x1029: kept (B9) */
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6044, 0));
}

static void test_heartbeat_loss_c101_5_runs_at_the_preset_speed(void)
{
    TEST_ASSERT_TRUE(co_drive_set_setting(&fx.d, "preset_speed", 300));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4101, 0, 5, 2));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4102, 0, 1, 2)); /* C102: preset speed 1 */
    monitored_and_running();
    fx_advance(&fx, 100000 + 10000000); /* 1500 -> 300 on the 10 s 0x6049 ramp: 8 s */
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(300, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX16(0, fx_u16(&fx, 0x603F, 0));
}

static void test_heartbeat_loss_c101_5_without_c102_keeps_running(void)
{
    TEST_ASSERT_TRUE(co_drive_set_setting(&fx.d, "preset_speed", 300));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4101, 0, 5, 2)); /* C102 = 0: none (B9) */
    monitored_and_running();
    fx_advance(&fx, 100000 + 10000000);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6044, 0));
}

static void test_c100_delays_the_reaction_and_recovery_cancels_it(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4100, 0, 20, 2)); /* 2.0 s */
    monitored_and_running();
    fx_advance(&fx, 100000 + 1999999);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    heartbeat_from_master(); /* back in time */
    fx_advance(&fx, 50000);
    heartbeat_from_master();
    fx_advance(&fx, 50000);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    /* lost again: 100 ms after the last heartbeat (50 ms ago), then C100 */
    fx_advance(&fx, 50000 + 2000000 - 1);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    fx_advance(&fx, 1);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT_REACTION_ACTIVE, fx.d.state);
}

/* The heartbeat loss is found inside co_node_process: the C100 timer it arms and the 0x6049 ramp
 * of C101 = 2 must be in the deadlines co_drive_process returns, for a port that sleeps until then
 * (found by tests/integration/test_comm_loss.py). */
static void test_loss_reactions_run_on_a_silent_bus(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x1017, 0, 0, 2)); /* no wake-ups of its own */
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4100, 0, 10, 2)); /* 1.0 s */
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4101, 0, 2, 2));
    monitored_and_running();
    uint64_t last_hb = fx.now;
    fx_wake_at_deadlines(&fx, last_hb + 100000 + 1000000 + 5000000);
    TEST_ASSERT_EQUAL_INT16(750, fx_i16(&fx, 0x6044, 0)); /* half way down the 10 s ramp */
    fx_wake_at_deadlines(&fx, last_hb + 100000 + 1000000 + 10000000);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
}

static void test_c103_1_needs_canopen_command_mode(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x1016, 1, (0x7Fu << 16) | 100u, 4));
    heartbeat_from_master();
    fx_advance(&fx, 200000); /* CMOd = 1: not enabled, C103 = 1: no reaction */
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0, fx_u16(&fx, 0x603F, 0));
}

static void test_c103_2_only_while_running(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x4103, 0, 2, 2));
    canopen_control();
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x1016, 1, (0x7Fu << 16) | 100u, 4));
    heartbeat_from_master();
    fx_advance(&fx, 200000);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
}

static void test_node_reset_returns_to_switch_on_disabled(void)
{
    running_at(1500);
    fx_nmt(&fx, 0x81);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(0, fx_i16(&fx, 0x6044, 0));
    TEST_ASSERT_EQUAL_HEX16(0x0250, fx_sw(&fx)); /* CMOd/FMOd kept: inverter EEPROM */
    TEST_ASSERT_EQUAL_UINT16(3, fx_u16(&fx, 0x2003, 0));
}

static void test_idle_drive_asks_for_no_tick(void)
{
    canopen_control();
    fx_enable(&fx);
    TEST_ASSERT_EQUAL_UINT64(CO_TIME_NEVER, co_drive_process(&fx.d, fx.now));
    fx_target(&fx, 100);
    TEST_ASSERT_EQUAL_UINT64(fx.now + 1000u, co_drive_process(&fx.d, fx.now));
    fx_advance(&fx, 1000000);
    TEST_ASSERT_EQUAL_UINT64(CO_TIME_NEVER, co_drive_process(&fx.d, fx.now));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_boots_in_switch_on_disabled_with_mains_bit);
    RUN_TEST(test_manual_section_7_asynchronous_example_frame_for_frame);
    RUN_TEST(test_tpdo1_follows_the_ramp_by_itself);
    RUN_TEST(test_section_7_2_synchronous_example);
    RUN_TEST(test_0x000F_in_ready_switches_on_and_enables_in_one_step);
    RUN_TEST(test_0x000F_in_switch_on_disabled_does_nothing);
    RUN_TEST(test_bit_7_high_carries_no_command);
    RUN_TEST(test_remote_bit_needs_cmod_3_and_fmod_6);
    RUN_TEST(test_factory_cmod_keeps_the_motor_still);
    RUN_TEST(test_target_cleared_on_entering_operation_enabled);
    RUN_TEST(test_halt_and_rfg_bits_are_ignored);
    RUN_TEST(test_mains_lost_in_switched_on_for_3_s);
    RUN_TEST(test_modes_of_operation_accepts_any_value_and_shows_2);
    RUN_TEST(test_ramp_0_to_1500_reaches_at_10_s_to_the_tick_monotone);
    RUN_TEST(test_ramp_is_a_straight_line_of_6048);
    RUN_TEST(test_deceleration_uses_6049);
    RUN_TEST(test_delta_time_0_is_a_step);
    RUN_TEST(test_reversal_decelerates_through_zero);
    RUN_TEST(test_max_amount_clamps_and_sets_internal_limit);
    RUN_TEST(test_min_amount_raises_small_targets_but_not_zero);
    RUN_TEST(test_min_above_max_is_refused);
    RUN_TEST(test_acceleration_out_of_range_refused);
    RUN_TEST(test_pole_count_f856_sets_the_output_frequency);
    RUN_TEST(test_disable_operation_decelerates_on_6049_in_switched_on);
    RUN_TEST(test_shutdown_and_disable_voltage_coast);
    RUN_TEST(test_quick_stop_option_0_coasts_to_switch_on_disabled);
    RUN_TEST(test_quick_stop_option_1_slow_down_ramp_then_disabled);
    RUN_TEST(test_quick_stop_option_2_quick_stop_ramp_then_disabled);
    RUN_TEST(test_quick_stop_option_2_refuses_transition_16);
    RUN_TEST(test_quick_stop_option_5_stays_and_16_reenables);
    RUN_TEST(test_quick_stop_option_6_quick_ramp_stays);
    RUN_TEST(test_quick_stop_options_3_4_7_8_negative_and_reserved);
    RUN_TEST(test_disable_voltage_during_quick_stop_coasts);
    RUN_TEST(test_oc1_trip_gives_2310_everywhere);
    RUN_TEST(test_fault_reset_only_once_the_cause_is_cleared);
    RUN_TEST(test_every_trip_of_the_table_raises_its_emcy);
    RUN_TEST(test_unknown_trip_code_refused);
    RUN_TEST(test_fa04_resets_a_fault);
    RUN_TEST(test_second_trip_keeps_the_first);
    RUN_TEST(test_heartbeat_loss_c101_4_trips_8130);
    RUN_TEST(test_heartbeat_loss_c101_2_decelerates_then_disabled);
    RUN_TEST(test_heartbeat_loss_c101_3_coasts);
    RUN_TEST(test_heartbeat_loss_c101_1_keeps_running);
    RUN_TEST(test_heartbeat_loss_c101_5_runs_at_the_preset_speed);
    RUN_TEST(test_heartbeat_loss_c101_5_without_c102_keeps_running);
    RUN_TEST(test_c100_delays_the_reaction_and_recovery_cancels_it);
    RUN_TEST(test_loss_reactions_run_on_a_silent_bus);
    RUN_TEST(test_c103_1_needs_canopen_command_mode);
    RUN_TEST(test_c103_2_only_while_running);
    RUN_TEST(test_node_reset_returns_to_switch_on_disabled);
    RUN_TEST(test_idle_drive_asks_for_no_tick);
    return UNITY_END();
}
