/* vl ramp function generator, velocity limit function and motor model: integer arithmetic exact
 * to the microsecond whatever the calls in between, monotone curves, reversals through zero,
 * steps, limits, rpm <-> Hz through the pole count, coasting. No dictionary, no clock but the
 * elapsed times handed in. */
#include "canopen/drive/model.h"
#include "canopen/drive/vl.h"
#include "unity.h"

void setUp(void) {}
void tearDown(void) {}

static const co_vl_slope s1500_10 = {1500, 10000000}; /* 1500 rpm per 10 s */

/* --- the 6048 example: 0 -> 1500 at 1500 per 10 s ------------------------------------------ */

static void test_0_to_1500_reaches_at_exactly_10_s_in_1_ms_ticks(void)
{
    co_vl_ramp r;
    co_vl_ramp_reset(&r, 0);
    int32_t previous = 0;
    for (int ms = 1; ms <= 10000; ms++) {
        bool done = co_vl_ramp_run(&r, 1500, &s1500_10, &s1500_10, 1000);
        TEST_ASSERT_TRUE(r.demand >= previous);          /* monotone */
        TEST_ASSERT_TRUE(r.demand - previous <= 1);      /* 0.15 rpm per ms: never jumps */
        TEST_ASSERT_EQUAL_INT32(ms * 15 / 100, r.demand); /* floor(t x 1500 / 10 s) */
        TEST_ASSERT_EQUAL(ms == 10000, done);
        previous = r.demand;
    }
    TEST_ASSERT_EQUAL_INT32(1500, r.demand);
}

static void test_result_does_not_depend_on_how_time_is_cut(void)
{
    const uint64_t cuts[] = {1, 7, 999, 1000, 1001, 33333, 250000, 1000000};
    for (size_t c = 0; c < sizeof cuts / sizeof cuts[0]; c++) {
        co_vl_ramp r;
        co_vl_ramp_reset(&r, 0);
        uint64_t t = 0;
        while (t + cuts[c] <= 6543210u) {
            co_vl_ramp_run(&r, 1500, &s1500_10, &s1500_10, cuts[c]);
            t += cuts[c];
        }
        co_vl_ramp_run(&r, 1500, &s1500_10, &s1500_10, 6543210u - t);
        TEST_ASSERT_EQUAL_INT32(981, r.demand); /* floor(6.54321 s x 150 rpm/s) */
    }
}

static void test_one_call_of_ten_seconds(void)
{
    co_vl_ramp r;
    co_vl_ramp_reset(&r, 0);
    TEST_ASSERT_FALSE(co_vl_ramp_run(&r, 1500, &s1500_10, &s1500_10, 9999999));
    TEST_ASSERT_EQUAL_INT32(1499, r.demand);
    TEST_ASSERT_TRUE(co_vl_ramp_run(&r, 1500, &s1500_10, &s1500_10, 1));
    TEST_ASSERT_EQUAL_INT32(1500, r.demand);
}

static void test_time_to_reach(void)
{
    co_vl_ramp r;
    co_vl_ramp_reset(&r, 0);
    TEST_ASSERT_EQUAL_UINT64(10000000, co_vl_ramp_time_to(&r, 1500, &s1500_10, &s1500_10));
    co_vl_ramp_run(&r, 1500, &s1500_10, &s1500_10, 2500);
    TEST_ASSERT_EQUAL_UINT64(9997500, co_vl_ramp_time_to(&r, 1500, &s1500_10, &s1500_10));
    co_vl_ramp_reset(&r, 1500);
    TEST_ASSERT_EQUAL_UINT64(0, co_vl_ramp_time_to(&r, 1500, &s1500_10, &s1500_10));
    /* a reversal: down to 0 on dec, up on acc */
    const co_vl_slope fast = {1500, 1000000};
    TEST_ASSERT_EQUAL_UINT64(1000000 + 10000000, co_vl_ramp_time_to(&r, -1500, &s1500_10, &fast));
}

/* --- deceleration, reversal, steps ---------------------------------------------------------- */

static void test_deceleration_slope_used_while_slowing(void)
{
    const co_vl_slope dec = {1500, 3000000};
    co_vl_ramp r;
    co_vl_ramp_reset(&r, 1500);
    co_vl_ramp_run(&r, 0, &s1500_10, &dec, 1000000);
    TEST_ASSERT_EQUAL_INT32(1000, r.demand);
    co_vl_ramp_run(&r, 500, &s1500_10, &dec, 1000000); /* still slowing: dec */
    TEST_ASSERT_EQUAL_INT32(500, r.demand);
}

static void test_reversal_goes_through_zero_with_both_slopes_in_one_call(void)
{
    const co_vl_slope acc = {1000, 1000000};
    const co_vl_slope dec = {500, 1000000};
    co_vl_ramp r;
    co_vl_ramp_reset(&r, 500);
    /* 1 s to reach 0 on dec, then 0.25 s on acc: -250 */
    TEST_ASSERT_FALSE(co_vl_ramp_run(&r, -1000, &acc, &dec, 1250000));
    TEST_ASSERT_EQUAL_INT32(-250, r.demand);
    TEST_ASSERT_TRUE(co_vl_ramp_run(&r, -1000, &acc, &dec, 750000));
    TEST_ASSERT_EQUAL_INT32(-1000, r.demand);
}

static void test_negative_direction_is_the_mirror(void)
{
    co_vl_ramp r;
    co_vl_ramp_reset(&r, 0);
    co_vl_ramp_run(&r, -1500, &s1500_10, &s1500_10, 4000000);
    TEST_ASSERT_EQUAL_INT32(-600, r.demand);
    co_vl_ramp_run(&r, 0, &s1500_10, &s1500_10, 4000000);
    TEST_ASSERT_EQUAL_INT32(0, r.demand);
}

static void test_zero_delta_time_or_speed_is_a_step(void)
{
    const co_vl_slope no_time = {1500, 0};
    const co_vl_slope no_speed = {0, 10000000};
    co_vl_ramp r;
    co_vl_ramp_reset(&r, 0);
    TEST_ASSERT_TRUE(co_vl_ramp_run(&r, 1200, &no_time, &s1500_10, 0));
    TEST_ASSERT_EQUAL_INT32(1200, r.demand);
    /* slowing down is a step to 0; the way on to -300 accelerates on its slope */
    TEST_ASSERT_FALSE(co_vl_ramp_run(&r, -300, &s1500_10, &no_speed, 0));
    TEST_ASSERT_EQUAL_INT32(0, r.demand);
    TEST_ASSERT_FALSE(co_vl_ramp_run(&r, -300, &s1500_10, &no_speed, 1000000));
    TEST_ASSERT_EQUAL_INT32(-150, r.demand);
}

static void test_changing_the_setpoint_mid_ramp(void)
{
    co_vl_ramp r;
    co_vl_ramp_reset(&r, 0);
    co_vl_ramp_run(&r, 1500, &s1500_10, &s1500_10, 2000000);
    TEST_ASSERT_EQUAL_INT32(300, r.demand);
    TEST_ASSERT_TRUE(co_vl_ramp_run(&r, 200, &s1500_10, &s1500_10, 1000000));
    TEST_ASSERT_EQUAL_INT32(200, r.demand);
}

static void test_ramp_toward_uses_one_slope(void)
{
    const co_vl_slope qs = {3420, 6000000};
    co_vl_ramp r;
    co_vl_ramp_reset(&r, 1500);
    co_vl_ramp_toward(&r, 0, &qs, 1000000);
    TEST_ASSERT_EQUAL_INT32(930, r.demand);
    TEST_ASSERT_TRUE(co_vl_ramp_toward(&r, 0, &qs, 1631579));
    TEST_ASSERT_EQUAL_INT32(0, r.demand);
}

static void test_huge_slopes_and_times_do_not_overflow(void)
{
    const co_vl_slope huge = {UINT32_MAX, UINT64_MAX};
    const co_vl_slope steep = {UINT32_MAX, 1};
    co_vl_ramp r;
    co_vl_ramp_reset(&r, INT32_MIN + 1);
    co_vl_ramp_run(&r, INT32_MAX, &huge, &huge, UINT64_MAX / 2);
    TEST_ASSERT_TRUE(r.demand <= INT32_MAX);
    co_vl_ramp_reset(&r, -30000);
    TEST_ASSERT_TRUE(co_vl_ramp_run(&r, 30000, &steep, &steep, 1000));
    TEST_ASSERT_EQUAL_INT32(30000, r.demand);
    TEST_ASSERT_NOT_EQUAL(0, co_vl_ramp_time_to(&r, -30000, &huge, &huge));
}

/* --- limits ---------------------------------------------------------------------------------- */

static void test_limit_function(void)
{
    bool limited;
    TEST_ASSERT_EQUAL_INT32(1500, co_vl_limit(3000, 0, 1500, &limited));
    TEST_ASSERT_TRUE(limited);
    TEST_ASSERT_EQUAL_INT32(-1500, co_vl_limit(-3000, 0, 1500, &limited));
    TEST_ASSERT_TRUE(limited);
    TEST_ASSERT_EQUAL_INT32(100, co_vl_limit(10, 100, 1500, &limited));
    TEST_ASSERT_TRUE(limited);
    TEST_ASSERT_EQUAL_INT32(-100, co_vl_limit(-10, 100, 1500, &limited));
    TEST_ASSERT_EQUAL_INT32(0, co_vl_limit(0, 100, 1500, &limited));
    TEST_ASSERT_FALSE(limited);
    TEST_ASSERT_EQUAL_INT32(700, co_vl_limit(700, 100, 1500, &limited));
    TEST_ASSERT_FALSE(limited);
    TEST_ASSERT_EQUAL_INT32(1500, co_vl_limit(1500, 100, 1500, &limited));
    TEST_ASSERT_FALSE(limited);
    TEST_ASSERT_EQUAL_INT32(-INT32_MAX, co_vl_limit(INT32_MIN, 0, UINT32_MAX, &limited));
}

/* --- motor model ----------------------------------------------------------------------------- */

static void test_rpm_hz_through_pole_count(void)
{
    TEST_ASSERT_EQUAL_INT32(5000, co_motor_rpm_to_centihz(1500, 4, false)); /* 50.00 Hz */
    TEST_ASSERT_EQUAL_INT32(2500, co_motor_rpm_to_centihz(1500, 2, false));
    TEST_ASSERT_EQUAL_INT32(-5000, co_motor_rpm_to_centihz(-1500, 4, false));
    TEST_ASSERT_EQUAL_INT32(1500, co_motor_centihz_to_rpm(5000, 4, false));
    TEST_ASSERT_EQUAL_INT32(1800, co_motor_centihz_to_rpm(6000, 4, false)); /* x 30 */
    TEST_ASSERT_EQUAL_INT32(3, co_motor_rpm_to_centihz(1, 4, false));  /* 0.0333 -> 0.03 */
    TEST_ASSERT_EQUAL_INT32(7, co_motor_rpm_to_centihz(1, 8, false));  /* 0.0667 -> 0.07 */
    TEST_ASSERT_EQUAL_INT32(6, co_motor_rpm_to_centihz(1, 8, true));   /* truncated */
    TEST_ASSERT_EQUAL_INT32(-7, co_motor_rpm_to_centihz(-1, 8, false));
    TEST_ASSERT_EQUAL_INT32(2, co_motor_rpm_to_centihz(1, 0, false)); /* 0 read as 2 poles */
}

static void test_motor_follows_demand_through_the_output_frequency(void)
{
    const co_motor_config cfg = {CO_MOTOR_UNIT_RPM, false, true, {1500, 5000000}};
    co_motor m;
    co_motor_reset(&m);
    co_motor_update(&m, &cfg, 1500, true, 4, 1000);
    TEST_ASSERT_EQUAL_INT32(1500, m.actual);
    TEST_ASSERT_EQUAL_INT32(5000, m.frequency);
    TEST_ASSERT_EQUAL(1, co_motor_direction(&m));
    co_motor_update(&m, &cfg, -1499, true, 16, 1000); /* 16 poles: 0.01 Hz is 0.075 rpm */
    TEST_ASSERT_EQUAL_INT32(-19987, m.frequency);
    TEST_ASSERT_EQUAL_INT32(-1499, m.actual);
    TEST_ASSERT_EQUAL(-1, co_motor_direction(&m));
}

static void test_motor_coasts_when_the_output_goes_off(void)
{
    const co_motor_config cfg = {CO_MOTOR_UNIT_RPM, false, false, {1500, 5000000}};
    co_motor m;
    co_motor_reset(&m);
    co_motor_update(&m, &cfg, 1500, true, 4, 0);
    TEST_ASSERT_TRUE(co_motor_update(&m, &cfg, 0, false, 4, 1000000));
    TEST_ASSERT_EQUAL_INT32(1200, m.actual);
    TEST_ASSERT_EQUAL_INT32(0, m.frequency);
    TEST_ASSERT_FALSE(co_motor_update(&m, &cfg, 0, false, 4, 4000000));
    TEST_ASSERT_EQUAL_INT32(0, m.actual);
    TEST_ASSERT_EQUAL(0, co_motor_direction(&m));
}

static void test_motor_without_coast_slope_stops_at_once(void)
{
    const co_motor_config cfg = {CO_MOTOR_UNIT_RPM, false, true, {1500, 0}};
    co_motor m;
    co_motor_reset(&m);
    co_motor_update(&m, &cfg, 900, true, 4, 0);
    TEST_ASSERT_FALSE(co_motor_update(&m, &cfg, 0, false, 4, 0));
    TEST_ASSERT_EQUAL_INT32(0, m.actual);
}

/* The load (model.h): torque = load, current = sqrt(Im^2 + It^2) with Im = 30 % and rated torque
 * drawing rated current; nothing while the output is off; the speed shown does not change. */
static void test_motor_load_shows_torque_and_current_while_the_output_is_on(void)
{
    const co_motor_config cfg = {CO_MOTOR_UNIT_RPM, false, true, {1500, 5000000}};
    co_motor m;
    co_motor_reset(&m);
    TEST_ASSERT_TRUE(co_motor_set_load(&m, 80));
    TEST_ASSERT_EQUAL_UINT16(80, m.load);
    TEST_ASSERT_EQUAL_UINT16(0, m.torque); /* output off: nothing shown */
    TEST_ASSERT_EQUAL_UINT16(0, m.current);
    co_motor_update(&m, &cfg, 1500, true, 4, 1000);
    TEST_ASSERT_EQUAL_INT32(1500, m.actual); /* the output-frequency image, load or not */
    TEST_ASSERT_EQUAL_UINT16(8000, m.torque);          /* 80.00 % */
    TEST_ASSERT_EQUAL_UINT16(8200, m.current);         /* sqrt(30^2 + 0.91 x 80^2) = 82.00 % */
    TEST_ASSERT_EQUAL_UINT16(7631, m.torque_current);  /* floor(sqrt(0.91) x 80.00 %) */
    TEST_ASSERT_TRUE(co_motor_set_load(&m, 100));      /* shown at once, no update needed */
    TEST_ASSERT_EQUAL_UINT16(10000, m.current);        /* rated torque: rated current */
    TEST_ASSERT_EQUAL_UINT16(9539, m.torque_current);
    TEST_ASSERT_TRUE(co_motor_set_load(&m, 0));
    TEST_ASSERT_EQUAL_UINT16(0, m.torque);
    TEST_ASSERT_EQUAL_UINT16(3000, m.current);         /* magnetising current alone */
    TEST_ASSERT_TRUE(co_motor_set_load(&m, (int32_t)CO_MOTOR_LOAD_MAX));
    TEST_ASSERT_EQUAL_UINT16(20000, m.torque);
    TEST_ASSERT_EQUAL_UINT16(19313, m.current);
    TEST_ASSERT_EQUAL_UINT16(19078, m.torque_current);
    /* out of range: refused, nothing changes */
    TEST_ASSERT_FALSE(co_motor_set_load(&m, (int32_t)CO_MOTOR_LOAD_MAX + 1));
    TEST_ASSERT_FALSE(co_motor_set_load(&m, -1));
    TEST_ASSERT_FALSE(co_motor_set_load(&m, INT32_MIN));
    TEST_ASSERT_EQUAL_UINT16(200, m.load);
    TEST_ASSERT_EQUAL_UINT16(19313, m.current);
    /* output off: the coasting motor carries no current; the load stays set */
    TEST_ASSERT_TRUE(co_motor_update(&m, &cfg, 0, false, 4, 1000000));
    TEST_ASSERT_EQUAL_INT32(1200, m.actual);
    TEST_ASSERT_EQUAL_UINT16(0, m.torque);
    TEST_ASSERT_EQUAL_UINT16(0, m.current);
    TEST_ASSERT_EQUAL_UINT16(0, m.torque_current);
    TEST_ASSERT_EQUAL_UINT16(200, m.load);
    co_motor_update(&m, &cfg, 300, true, 4, 0); /* on again */
    TEST_ASSERT_EQUAL_UINT16(19313, m.current);
}

static void test_motor_in_hertz(void)
{
    const co_motor_config cfg = {CO_MOTOR_UNIT_CENTI_HZ, false, false, {5000, 0}};
    co_motor m;
    co_motor_reset(&m);
    co_motor_update(&m, &cfg, 5000, true, 4, 0);
    TEST_ASSERT_EQUAL_INT32(5000, m.frequency);
    TEST_ASSERT_EQUAL_INT32(5000, m.actual);
    TEST_ASSERT_EQUAL_INT32(1500, m.rpm);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_0_to_1500_reaches_at_exactly_10_s_in_1_ms_ticks);
    RUN_TEST(test_result_does_not_depend_on_how_time_is_cut);
    RUN_TEST(test_one_call_of_ten_seconds);
    RUN_TEST(test_time_to_reach);
    RUN_TEST(test_deceleration_slope_used_while_slowing);
    RUN_TEST(test_reversal_goes_through_zero_with_both_slopes_in_one_call);
    RUN_TEST(test_negative_direction_is_the_mirror);
    RUN_TEST(test_zero_delta_time_or_speed_is_a_step);
    RUN_TEST(test_changing_the_setpoint_mid_ramp);
    RUN_TEST(test_ramp_toward_uses_one_slope);
    RUN_TEST(test_huge_slopes_and_times_do_not_overflow);
    RUN_TEST(test_limit_function);
    RUN_TEST(test_rpm_hz_through_pole_count);
    RUN_TEST(test_motor_follows_demand_through_the_output_frequency);
    RUN_TEST(test_motor_coasts_when_the_output_goes_off);
    RUN_TEST(test_motor_without_coast_slope_stops_at_once);
    RUN_TEST(test_motor_in_hertz);
    RUN_TEST(test_motor_load_shows_torque_and_current_while_the_output_is_on);
    return UNITY_END();
}
