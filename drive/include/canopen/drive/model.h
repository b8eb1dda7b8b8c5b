/* The simulated motor behind a drive: what vl_velocity_actual_value (0x6044) and the drive's
 * frequency monitors show. With the output on, the shaft follows the ramp output as a V/F or
 * sensorless drive reports it (CiA 402 §6044: 'the appropriate image of the actual velocity'):
 * the demand goes to the inverter as an output frequency of 0.01 Hz resolution and comes back as
 * a speed, so 6044 = rpm(Hz(6043)). With the output off the motor coasts down on its own slope
 * and the output frequency is 0. Speed and frequency are tied by the pole count:
 *   f [Hz] = n [rpm] x poles / 120      (VF-S15 §5.1: F856 = pole pairs, 1500 rpm at 4 poles = 50 Hz)
 * Integer arithmetic, deterministic to the microsecond like the ramp (vl.h).
 *
 * The load: a mechanical load torque on the shaft, in percent of the motor's rated torque
 * (co_motor_set_load, 0..CO_MOTOR_LOAD_MAX), a constant-torque load such as a conveyor. While the
 * output is on the motor delivers that torque; the drive's monitors show it as torque and as
 * current. The current of an induction motor is the vector sum of its magnetising current (which
 * flows at no load) and its torque-producing current:
 *   I = sqrt(Im^2 + It^2),  It = T x sqrt(100 %^2 - Im^2)      (percent of rated current/torque)
 * so that rated torque draws rated current. Im is CO_MOTOR_MAGNETISING (30 %, a typical 4-pole
 * motor's no-load current; a model value, not from a drive manual). With the output off torque
 * and current are 0. The load does not slow the shaft: a V/F or sensorless drive reports the
 * output-frequency image (above), so 0x6044 is unchanged by the load. */
#ifndef CANOPEN_DRIVE_MODEL_H
#define CANOPEN_DRIVE_MODEL_H

#include <stdbool.h>
#include <stdint.h>

#include "canopen/drive/vl.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The unit a drive's speed values are in. */
typedef enum co_motor_unit {
    CO_MOTOR_UNIT_RPM = 0,      /* min^-1 (CiA 402 vl) */
    CO_MOTOR_UNIT_CENTI_HZ = 1  /* 0.01 Hz (drives that are set in frequency) */
} co_motor_unit;

typedef struct co_motor_config {
    uint8_t unit;          /* co_motor_unit of the demand and of co_motor.actual */
    bool truncate;         /* conversions truncate (VF-MB1 §8.14) rather than round to nearest */
    bool quantise;         /* rpm demands pass through the 0.01 Hz output frequency */
    co_vl_slope coast;     /* how a coasting motor slows down; a step (0) stops it at once */
} co_motor_config;

/* The largest load (percent of rated torque): twice the rated torque, an overload no motor
 * carries for long, within the range the drives' own torque settings take (the ST600's torque
 * reference and limits reach 300.0 %). Above the drive's current limit a real motor would
 * stall, which the model does not simulate. */
#define CO_MOTOR_LOAD_MAX 200u
/* Magnetising (no-load) current, 0.01 % of rated current. */
#define CO_MOTOR_MAGNETISING 3000

typedef struct co_motor {
    int32_t actual;        /* shaft speed in the configured unit, signed (negative = reverse) */
    int32_t rpm;           /* shaft speed in rpm, signed */
    int32_t frequency;     /* output frequency in 0.01 Hz, signed; 0 while the output is off */
    bool output_on;
    co_vl_ramp coast;      /* the coasting shaft */
    uint16_t load;         /* load torque on the shaft, percent of rated torque (set) */
    /* Shown while the output is on, 0 while it is off (magnitudes, 0.01 % of rated): */
    uint16_t torque;       /* motor torque, of rated torque */
    uint16_t current;      /* output current, of rated motor current */
    uint16_t torque_current; /* its torque-producing component, of rated motor current */
} co_motor;

/* A motor at standstill with the output off and no load. */
void co_motor_reset(co_motor *motor);

/* Sets the load torque (percent of rated torque, 0..CO_MOTOR_LOAD_MAX) and the torque and
 * current shown at once. False (load untouched) out of range. */
bool co_motor_set_load(co_motor *motor, int32_t percent);

/* Runs the model: demand (the ramp output) is applied for elapsed_us with the output on or off.
 * poles is the motor's pole count (0 is read as 2). Returns true while the shaft still coasts
 * (the caller keeps ticking). */
bool co_motor_update(co_motor *motor, const co_motor_config *cfg, int32_t demand, bool output_on,
                     uint16_t poles, uint64_t elapsed_us);

/* Speed (rpm) to output frequency (0.01 Hz) and back for a pole count, rounded to the nearest
 * unit (half away from zero) or truncated. */
int32_t co_motor_rpm_to_centihz(int32_t rpm, uint16_t poles, bool truncate);
int32_t co_motor_centihz_to_rpm(int32_t centihz, uint16_t poles, bool truncate);

/* -1 reverse, 0 standstill, +1 forward. */
int co_motor_direction(const co_motor *motor);

#ifdef __cplusplus
}
#endif

#endif
