/* CiA 402 velocity mode (vl): the velocity limit function (0x6046) and the ramp function
 * generator that turns vl_target_velocity (0x6042) into vl_velocity_demand (0x6043) with the
 * slopes of 0x6048 (acceleration), 0x6049 (deceleration) and 0x604A (quick stop), each a delta
 * speed over a delta time.
 *
 * Integer arithmetic only, exact to the microsecond: a ramp of delta_speed per delta_time that
 * started at t0 has moved floor((t - t0) * delta_speed / delta_time) units at t, whatever the
 * times in between at which co_vl_ramp_run was called (the remainder is carried). So 0 -> 1500
 * rpm at 1500 rpm per 10 s reads 1499 at 9.999 s and 1500 at exactly 10.000 s, and the curve is
 * monotone. The unit is the caller's (rpm for 0x6042, 0.01 Hz for a drive that works in Hz).
 *
 *   co_vl_ramp r; co_vl_ramp_reset(&r, 0);
 *   co_vl_slope acc = {1500, 10000000}, dec = {1500, 10000000};
 *   co_vl_ramp_run(&r, 1500, &acc, &dec, elapsed_us);   // r.demand follows
 */
#ifndef CANOPEN_DRIVE_VL_H
#define CANOPEN_DRIVE_VL_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* A slope: delta_speed units per delta_time_us microseconds. Either one 0 means no ramp: the
 * demand steps to its goal (CiA 402 leaves a zero slope to the device; the VF-S15 manual allows a
 * delta time of 0 s, §5.1.8). */
typedef struct co_vl_slope {
    uint32_t delta_speed;
    uint64_t delta_time_us;
} co_vl_slope;

typedef struct co_vl_ramp {
    int32_t demand;          /* the ramp output */
    uint64_t remainder;      /* carried numerator (< delta_time_us of the slope in use) */
    co_vl_slope in_use;      /* slope the remainder belongs to */
    int8_t direction;        /* +1 / -1: direction the remainder belongs to, 0: none */
} co_vl_ramp;

/* Sets the ramp output to demand, with no carried remainder. */
void co_vl_ramp_reset(co_vl_ramp *ramp, int32_t demand);

/* Moves the demand towards setpoint for elapsed_us: with acc while |demand| grows, with dec while
 * it shrinks; a reversal first decelerates to 0, then accelerates. Returns true once the demand
 * equals the setpoint. */
bool co_vl_ramp_run(co_vl_ramp *ramp, int32_t setpoint, const co_vl_slope *acc,
                    const co_vl_slope *dec, uint64_t elapsed_us);

/* Moves the demand towards goal with one slope, whatever the direction. Returns true at goal. */
bool co_vl_ramp_toward(co_vl_ramp *ramp, int32_t goal, const co_vl_slope *slope,
                       uint64_t elapsed_us);

/* Microseconds the ramp still needs to reach setpoint (0 if there), or UINT64_MAX if it would
 * not fit; for deadlines. */
uint64_t co_vl_ramp_time_to(const co_vl_ramp *ramp, int32_t setpoint, const co_vl_slope *acc,
                            const co_vl_slope *dec);

/* The velocity limit function (CiA 402 vl, 0x6046): |target| above max_amount gives +-max_amount,
 * a non-zero |target| below min_amount gives +-min_amount (sign kept), 0 stays 0. *limited is set
 * when the result differs from target. */
int32_t co_vl_limit(int32_t target, uint32_t min_amount, uint32_t max_amount, bool *limited);

#ifdef __cplusplus
}
#endif

#endif
