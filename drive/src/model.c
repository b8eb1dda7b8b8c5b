/* Motor model: actual speed follows the demand through the 0.01 Hz output; coasting when off. */
#include "canopen/drive/model.h"

void co_motor_reset(co_motor *motor)
{
    motor->actual = 0;
    motor->rpm = 0;
    motor->frequency = 0;
    motor->output_on = false;
    co_vl_ramp_reset(&motor->coast, 0);
    motor->load = 0;
    motor->torque = 0;
    motor->current = 0;
    motor->torque_current = 0;
}

/* floor(sqrt(v)), bit by bit. */
static uint32_t isqrt(uint64_t v)
{
    uint64_t root = 0;
    uint64_t bit = (uint64_t)1 << 62;
    while (bit > v) {
        bit >>= 2;
    }
    while (bit != 0u) {
        if (v >= root + bit) {
            v -= root + bit;
            root = (root >> 1) + bit;
        } else {
            root >>= 1;
        }
        bit >>= 2;
    }
    return (uint32_t)root;
}

/* Torque and current for the load with the output on or off (model.h). */
static void show_load(co_motor *motor)
{
    if (!motor->output_on) {
        motor->torque = 0;
        motor->current = 0;
        motor->torque_current = 0;
        return;
    }
    const uint64_t full = 10000u * 10000u; /* (100.00 %)^2 */
    const uint64_t im2 = (uint64_t)CO_MOTOR_MAGNETISING * CO_MOTOR_MAGNETISING;
    uint64_t t = (uint64_t)motor->load * 100u; /* 0.01 % */
    uint64_t it2 = (full - im2) * t * t / full;
    motor->torque = (uint16_t)t;
    motor->torque_current = (uint16_t)isqrt(it2);
    motor->current = (uint16_t)isqrt(im2 + it2);
}

bool co_motor_set_load(co_motor *motor, int32_t percent)
{
    if (percent < 0 || percent > (int32_t)CO_MOTOR_LOAD_MAX) {
        return false;
    }
    motor->load = (uint16_t)percent;
    show_load(motor);
    return true;
}

/* num / den rounded to nearest (half away from zero) or truncated towards zero; den > 0. */
static int32_t divide(int64_t num, int64_t den, bool truncate)
{
    int64_t q;
    if (truncate) {
        q = num / den;
    } else if (num >= 0) {
        q = (num + den / 2) / den;
    } else {
        q = -((-num + den / 2) / den);
    }
    if (q > INT32_MAX) {
        return INT32_MAX;
    }
    if (q < -INT32_MAX) {
        return -INT32_MAX;
    }
    return (int32_t)q;
}

int32_t co_motor_rpm_to_centihz(int32_t rpm, uint16_t poles, bool truncate)
{
    int64_t p = poles != 0u ? poles : 2;
    return divide((int64_t)rpm * p * 100, 120, truncate); /* f = n x p / 120 */
}

int32_t co_motor_centihz_to_rpm(int32_t centihz, uint16_t poles, bool truncate)
{
    int64_t p = poles != 0u ? poles : 2;
    return divide((int64_t)centihz * 120, p * 100, truncate);
}

bool co_motor_update(co_motor *motor, const co_motor_config *cfg, int32_t demand, bool output_on,
                     uint16_t poles, uint64_t elapsed_us)
{
    bool hz = cfg->unit == CO_MOTOR_UNIT_CENTI_HZ;
    if (output_on) {
        motor->output_on = true;
        if (hz) {
            motor->frequency = demand;
            motor->actual = demand;
            motor->rpm = co_motor_centihz_to_rpm(demand, poles, cfg->truncate);
        } else {
            motor->frequency = co_motor_rpm_to_centihz(demand, poles, cfg->truncate);
            motor->actual = cfg->quantise
                                ? co_motor_centihz_to_rpm(motor->frequency, poles, cfg->truncate)
                                : demand;
            motor->rpm = motor->actual;
        }
        co_vl_ramp_reset(&motor->coast, motor->actual);
        show_load(motor);
        return false;
    }
    if (motor->output_on) { /* output just switched off: the shaft coasts from where it was */
        motor->output_on = false;
        co_vl_ramp_reset(&motor->coast, motor->actual);
    }
    show_load(motor);
    motor->frequency = 0;
    bool stopped = co_vl_ramp_toward(&motor->coast, 0, &cfg->coast, elapsed_us);
    motor->actual = motor->coast.demand;
    motor->rpm = hz ? co_motor_centihz_to_rpm(motor->actual, poles, cfg->truncate) : motor->actual;
    return !stopped;
}

int co_motor_direction(const co_motor *motor)
{
    return motor->actual > 0 ? 1 : (motor->actual < 0 ? -1 : 0);
}
