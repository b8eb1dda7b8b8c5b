/* CiA 402 velocity mode: limit function and ramp function generator, integer arithmetic. */
#include "canopen/drive/vl.h"

/* Slopes are scaled down (keeping their ratio) until delta_speed <= 2^23 and delta_time <= 2^40
 * us (12.7 days), so that every product below fits in 64 bits. Real slopes (a 16-bit speed over
 * at most 65535 s) are never touched. */
#define VL_MAX_SPEED (UINT64_C(1) << 23)
#define VL_MAX_TIME (UINT64_C(1) << 40)

static uint64_t magnitude(int64_t v)
{
    return v < 0 ? (uint64_t)(-v) : (uint64_t)v;
}

void co_vl_ramp_reset(co_vl_ramp *ramp, int32_t demand)
{
    ramp->demand = demand;
    ramp->remainder = 0;
    ramp->in_use.delta_speed = 0;
    ramp->in_use.delta_time_us = 0;
    ramp->direction = 0;
}

static void normalise(const co_vl_slope *slope, uint64_t *ds, uint64_t *dt)
{
    *ds = slope->delta_speed;
    *dt = slope->delta_time_us;
    while (*ds > VL_MAX_SPEED || *dt > VL_MAX_TIME) {
        *ds >>= 1;
        *dt >>= 1;
    }
}

/* Time (us) to cover distance units from a carried remainder; UINT64_MAX if it cannot be told. */
static uint64_t time_for(uint64_t distance, uint64_t remainder, uint64_t ds, uint64_t dt)
{
    if (distance == 0u) {
        return 0;
    }
    if (ds == 0u || dt == 0u) {
        return 0;
    }
    if (distance > VL_MAX_SPEED) { /* distance * dt would not fit: never for 16-bit speeds */
        return UINT64_MAX;
    }
    uint64_t x = distance * dt - remainder; /* remainder < dt <= distance * dt */
    return x / ds + (x % ds != 0u ? 1u : 0u);
}

/* One monotone segment towards goal with one slope. Consumes the time it uses from *elapsed;
 * returns true when goal is reached. */
static bool segment(co_vl_ramp *ramp, int32_t goal, const co_vl_slope *slope, uint64_t *elapsed)
{
    int64_t diff = (int64_t)goal - ramp->demand;
    if (diff == 0) {
        return true;
    }
    uint64_t ds, dt;
    normalise(slope, &ds, &dt);
    if (ds == 0u || dt == 0u) {
        ramp->demand = goal;
        ramp->remainder = 0;
        ramp->direction = 0;
        return true;
    }
    int8_t dir = diff > 0 ? 1 : -1;
    if (ramp->direction != dir || ramp->in_use.delta_speed != slope->delta_speed ||
        ramp->in_use.delta_time_us != slope->delta_time_us) {
        /* a new segment: the carried fraction belonged to another slope or direction */
        ramp->remainder = 0;
        ramp->in_use = *slope;
        ramp->direction = dir;
    }
    uint64_t distance = magnitude(diff);
    uint64_t whole = *elapsed / dt; /* full delta times: at least ds units each */
    uint64_t part = *elapsed % dt;
    if (whole < distance) {
        uint64_t num = part * ds + ramp->remainder; /* < 2^63 + 2^40 */
        uint64_t moved = whole * ds + num / dt;     /* whole < distance <= 2^33 */
        if (moved < distance) {
            ramp->demand = (int32_t)(ramp->demand + dir * (int64_t)moved);
            ramp->remainder = num % dt;
            *elapsed = 0;
            return false;
        }
    }
    uint64_t used = time_for(distance, ramp->remainder, ds, dt);
    *elapsed = used < *elapsed ? *elapsed - used : 0u;
    ramp->demand = goal;
    ramp->remainder = 0;
    ramp->direction = 0;
    return true;
}

bool co_vl_ramp_toward(co_vl_ramp *ramp, int32_t goal, const co_vl_slope *slope,
                       uint64_t elapsed_us)
{
    return segment(ramp, goal, slope, &elapsed_us);
}

/* The goal and slope of the segment the ramp is in. */
static int32_t next_goal(int32_t demand, int32_t setpoint, const co_vl_slope *acc,
                         const co_vl_slope *dec, const co_vl_slope **slope)
{
    if (demand != 0 && (setpoint == 0 || (demand > 0) != (setpoint > 0))) {
        *slope = dec; /* slowing down, or a reversal: to 0 first */
        return 0;
    }
    *slope = magnitude(setpoint) > magnitude(demand) ? acc : dec;
    return setpoint;
}

bool co_vl_ramp_run(co_vl_ramp *ramp, int32_t setpoint, const co_vl_slope *acc,
                    const co_vl_slope *dec, uint64_t elapsed_us)
{
    for (int i = 0; i < 3 && ramp->demand != setpoint; i++) {
        const co_vl_slope *slope;
        int32_t goal = next_goal(ramp->demand, setpoint, acc, dec, &slope);
        if (!segment(ramp, goal, slope, &elapsed_us)) {
            break; /* time used up on the way */
        }
    }
    return ramp->demand == setpoint;
}

uint64_t co_vl_ramp_time_to(const co_vl_ramp *ramp, int32_t setpoint, const co_vl_slope *acc,
                            const co_vl_slope *dec)
{
    int32_t demand = ramp->demand;
    uint64_t remainder = ramp->remainder;
    int8_t direction = ramp->direction;
    co_vl_slope in_use = ramp->in_use;
    uint64_t total = 0;
    for (int i = 0; i < 2 && demand != setpoint; i++) {
        const co_vl_slope *slope;
        int32_t goal = next_goal(demand, setpoint, acc, dec, &slope);
        uint64_t ds, dt;
        normalise(slope, &ds, &dt);
        int64_t diff = (int64_t)goal - demand;
        int8_t dir = diff > 0 ? 1 : -1;
        if (direction != dir || in_use.delta_speed != slope->delta_speed ||
            in_use.delta_time_us != slope->delta_time_us) {
            remainder = 0;
        }
        uint64_t t = time_for(magnitude(diff), remainder, ds, dt);
        if (t == UINT64_MAX || total > UINT64_MAX - t) {
            return UINT64_MAX;
        }
        total += t;
        demand = goal;
        remainder = 0;
        direction = 0;
    }
    return total;
}

int32_t co_vl_limit(int32_t target, uint32_t min_amount, uint32_t max_amount, bool *limited)
{
    uint64_t amount = magnitude(target);
    uint64_t out = amount;
    if (amount > max_amount) {
        out = max_amount;
    } else if (amount != 0u && amount < min_amount) {
        out = min_amount;
        if (out > max_amount) { /* min above max cannot be configured (0x06090036) */
            out = max_amount;
        }
    }
    if (out > INT32_MAX) {
        out = INT32_MAX;
    }
    *limited = out != amount;
    return target < 0 ? -(int32_t)out : (int32_t)out;
}
