/* A simulated drive: CiA 402 state machine, vl ramp and motor model on one node, driven by the
 * controlword and target writes, the clock, faults and communication events. Drive-specific
 * behaviour comes from the description (drive.h); nothing here names a drive. */
#include "canopen/drive.h"

#include <string.h>

#include "canopen/emcy.h"

/* Keeps the work behind a skip test (co_drive_process's pass) out of its caller, so that a call
 * with nothing to do neither carries that code nor saves the registers it needs: the same rule as
 * the core's CO_NOINLINE (gcc's noinline; other compilers inline as they like). */
#if defined(__GNUC__)
#define DRIVE_NOINLINE __attribute__((noinline))
#else
#define DRIVE_NOINLINE
#endif

#define IDX_ERROR_CODE 0x603Fu
#define IDX_CONTROLWORD 0x6040u
#define IDX_TARGET 0x6042u
#define IDX_MIN_MAX 0x6046u
#define IDX_MODES 0x6060u

static uint64_t earliest(uint64_t a, uint64_t b)
{
    return a < b ? a : b;
}

/* An input changed (a state, a dictionary value, a description's source): the next pass of
 * co_drive_process recomputes the setpoint, slopes and flags (rearm). */
static void input_changed(co_drive *d)
{
    d->dirty = true;
    co_drive_wake(d);
}

/* --- object access ------------------------------------------------------------------------ */

static void resolve(const co_od *od, uint16_t index, uint8_t subindex, co_od_ref *ref)
{
    if (co_od_locate(od, index, subindex, ref) != CO_ABORT_NONE || co_od_sub_size(ref->sub) == 0u ||
        co_od_sub_size(ref->sub) > 4u || ref->sub->type == CO_DOMAIN) {
        ref->entry = NULL;
        ref->sub = NULL;
    }
}

static bool has(co_od_ref ref)
{
    return ref.sub != NULL;
}

/* A little-endian integer of 1-4 bytes, sign-extended for signed types. */
static int64_t decode(const uint8_t *p, uint32_t size, uint8_t type)
{
    uint32_t v;
    switch (size) {
    case 1: v = p[0]; break;
    case 2: v = co_get_le16(p); break;
    case 4: v = co_get_le32(p); break;
    default: v = (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16); break;
    }
    bool is_signed = type == CO_INTEGER8 || type == CO_INTEGER16 || type == CO_INTEGER32 ||
                     type == CO_INTEGER24;
    uint32_t sign = UINT32_C(1) << (size * 8u - 1u);
    if (is_signed && (v & sign) != 0u) {
        return (int64_t)v - ((int64_t)sign << 1); /* two's complement of size bytes */
    }
    return (int64_t)v;
}

static int64_t get(const co_drive *d, co_od_ref ref)
{
    /* resolve() kept only values of 1-4 bytes, never a DOMAIN: straight into the block */
    return decode(d->node.values + co_od_value_offset(ref.entry, ref.sub), co_od_sub_size(ref.sub),
                  ref.sub->type);
}

/* Writes v (clamped to the type's range) as the application, only if it changes. */
static void put(co_drive *d, co_od_ref ref, int64_t v)
{
    if (!has(ref)) {
        return;
    }
    uint32_t size = co_od_sub_size(ref.sub);
    uint8_t type = ref.sub->type;
    int64_t lo = 0;
    int64_t hi = (int64_t)((UINT64_C(1) << (size * 8u)) - 1u);
    if (type == CO_INTEGER8 || type == CO_INTEGER16 || type == CO_INTEGER24 ||
        type == CO_INTEGER32) { /* the signed types resolve() keeps */
        hi = (int64_t)((UINT64_C(1) << (size * 8u - 1u)) - 1u);
        lo = -hi - 1;
    }
    v = v < lo ? lo : (v > hi ? hi : v);
    if (get(d, ref) == v) {
        return;
    }
    uint8_t b[4];
    uint32_t u = (uint32_t)(uint64_t)v;
    for (uint32_t i = 0; i < size; i++) {
        b[i] = (uint8_t)(u >> (8u * i));
    }
    (void)co_od_write_ref(&d->node, ref, b, size, CO_ORIGIN_APP);
}

static int64_t get_or(const co_drive *d, co_od_ref ref, int64_t fallback)
{
    return has(ref) ? get(d, ref) : fallback;
}

static void resolve_objects(co_drive *d)
{
    const co_od *od = d->desc->od;
    co_drive_objects *o = &d->obj;
    resolve(od, IDX_ERROR_CODE, 0, &o->error_code);
    resolve(od, IDX_CONTROLWORD, 0, &o->controlword);
    resolve(od, 0x6041u, 0, &o->statusword);
    resolve(od, IDX_TARGET, 0, &o->target);
    resolve(od, 0x6043u, 0, &o->demand);
    resolve(od, 0x6044u, 0, &o->actual);
    resolve(od, IDX_MIN_MAX, 1, &o->min_amount);
    resolve(od, IDX_MIN_MAX, 2, &o->max_amount);
    resolve(od, 0x6048u, 1, &o->acc_speed);
    resolve(od, 0x6048u, 2, &o->acc_time);
    resolve(od, 0x6049u, 1, &o->dec_speed);
    resolve(od, 0x6049u, 2, &o->dec_time);
    resolve(od, 0x604Au, 1, &o->qs_speed);
    resolve(od, 0x604Au, 2, &o->qs_time);
    resolve(od, 0x605Au, 0, &o->quick_stop_option);
    resolve(od, 0x605Bu, 0, &o->shutdown_option);
    resolve(od, 0x605Cu, 0, &o->disable_operation_option);
    resolve(od, 0x605Du, 0, &o->halt_option);
    resolve(od, 0x605Eu, 0, &o->fault_reaction_option);
    resolve(od, 0x6007u, 0, &o->abort_connection);
    resolve(od, IDX_MODES, 0, &o->modes);
    resolve(od, 0x6061u, 0, &o->modes_display);
}

/* --- slopes, limits and options ----------------------------------------------------------- */

static co_vl_slope slope_of(const co_drive *d, co_od_ref speed, co_od_ref time)
{
    const co_drive_desc *desc = d->desc;
    co_vl_slope s = {desc->max_speed, desc->drive_ramp_us};
    if (!has(speed) && !has(time)) {
        return s; /* no such object: the drive's own ramp (or a step when it has none) */
    }
    int64_t ds = get_or(d, speed, (int64_t)desc->max_speed); /* no sub 1: delta speed fixed */
    int64_t dt = get_or(d, time, 0);
    if ((ds <= 0 || dt <= 0) && (desc->flags & CO_DRIVE_ZERO_SLOPE_IS_DRIVE_RAMP) != 0u) {
        return s;
    }
    s.delta_speed = ds > 0 ? (uint32_t)ds : 0u;
    s.delta_time_us = dt > 0 ? (uint64_t)dt * desc->ramp_time_unit_us : 0u;
    return s;
}

static co_vl_slope acceleration(const co_drive *d)
{
    return slope_of(d, d->obj.acc_speed, d->obj.acc_time);
}

static co_vl_slope deceleration(const co_drive *d)
{
    return slope_of(d, d->obj.dec_speed, d->obj.dec_time);
}

static co_vl_slope quick_slope(const co_drive *d)
{
    if (!has(d->obj.qs_speed) && !has(d->obj.qs_time)) {
        return deceleration(d); /* no 0x604A: the deceleration ramp */
    }
    return slope_of(d, d->obj.qs_speed, d->obj.qs_time);
}

/* The slope of a stop, with the deceleration slope already read (dec). */
static co_vl_slope stop_slope_dec(const co_drive *d, uint8_t stop, co_vl_slope dec)
{
    switch (stop) {
    case CO_DRIVE_STOP_QUICK:
        if (!has(d->obj.qs_speed) && !has(d->obj.qs_time)) {
            return dec; /* no 0x604A: the deceleration ramp */
        }
        return slope_of(d, d->obj.qs_speed, d->obj.qs_time);
    case CO_DRIVE_STOP_CUSTOM: return d->custom_slope;
    default: return dec;
    }
}

static co_vl_slope stop_slope(const co_drive *d, uint8_t stop)
{
    switch (stop) {
    case CO_DRIVE_STOP_QUICK: return quick_slope(d);
    case CO_DRIVE_STOP_CUSTOM: return d->custom_slope;
    default: return deceleration(d);
    }
}

static uint32_t max_amount(const co_drive *d)
{
    const co_drive_desc *desc = d->desc;
    if (!has(d->obj.max_amount)) {
        return desc->max_speed != 0u ? desc->max_speed : UINT32_MAX;
    }
    int64_t v = get(d, d->obj.max_amount);
    if (v == 0 && (desc->flags & CO_DRIVE_ZERO_MAX_IS_MAX_SPEED) != 0u) {
        return desc->max_speed;
    }
    return v > 0 ? (uint32_t)v : 0u;
}

static uint32_t min_amount(const co_drive *d)
{
    int64_t v = get_or(d, d->obj.min_amount, 0);
    return v > 0 ? (uint32_t)v : 0u;
}

static int16_t option(const co_drive *d, co_od_ref ref, int16_t fallback)
{
    return has(ref) ? (int16_t)get(d, ref) : fallback;
}

/* CiA 402-2 0x605A: 0 disable drive function, 1/2 slow down on the slow down / quick stop ramp,
 * 3/4 on the current / voltage limit (simulated as the quick stop ramp), then Switch on disabled;
 * 5-8 the same but stay in Quick stop active. Manufacturer (<0) and reserved (>8) values: the
 * quick stop ramp (a quick stop must stop). */
static co_drive_quick_stop standard_quick_stop(int16_t code)
{
    co_drive_quick_stop q = {CO_DRIVE_STOP_QUICK, false};
    if (code == 0) {
        q.stop = CO_DRIVE_STOP_COAST;
    } else if (code == 1 || code == 5) {
        q.stop = CO_DRIVE_STOP_RAMP;
    }
    q.stay = code >= 5 && code <= 8;
    return q;
}

static co_drive_quick_stop quick_stop_action(const co_drive *d)
{
    int16_t code = option(d, d->obj.quick_stop_option, d->desc->quick_stop_option);
    return d->desc->quick_stop != NULL ? d->desc->quick_stop(code) : standard_quick_stop(code);
}

/* 0x605B shutdown / 0x605C disable operation: 0 disable drive function (coast), 1 slow down on
 * the slow down ramp; CO_DRIVE_OPTION_HOLD keeps the output. */
static uint8_t disable_stop(int16_t code)
{
    if (code == CO_DRIVE_OPTION_HOLD) {
        return CO_DRIVE_STOP_HOLD;
    }
    return code == 1 ? CO_DRIVE_STOP_RAMP : CO_DRIVE_STOP_COAST;
}

/* 0x605E fault reaction: 0 coast, 1 slow down ramp, 2 quick stop ramp, 3/4 limits (as 2). */
static uint8_t fault_stop(int16_t code)
{
    switch (code) {
    case 1: return CO_DRIVE_STOP_RAMP;
    case 2: case 3: case 4: return CO_DRIVE_STOP_QUICK;
    default: return CO_DRIVE_STOP_COAST;
    }
}

/* 0x605D halt: 1 slow down ramp (default), 2 quick stop ramp, 3/4 limits (as 2). */
static uint8_t halt_stop(int16_t code)
{
    return (code >= 2 && code <= 4) ? CO_DRIVE_STOP_QUICK : CO_DRIVE_STOP_RAMP;
}

static uint16_t poles(const co_drive *d)
{
    return d->desc->poles_of != NULL ? d->desc->poles_of(d) : d->desc->poles;
}

/* --- motion ------------------------------------------------------------------------------- */

/* The reference as last set: 0x6042 as the dictionary holds it when a write of it (SDO, RPDO)
 * came last, else the value co_drive_set_target or a cleared target left. */
static int32_t target_of(const co_drive *d)
{
    return d->target_stored ? (int32_t)get(d, d->obj.target) : d->target;
}

static void set_target(co_drive *d, int32_t target)
{
    d->target = target;
    d->target_stored = false;
}

/* The reference before limits, reversed by controlword bit 11 where the drive does that, 0 when
 * the reference comes from a local source. */
static int32_t reference(const co_drive *d)
{
    int32_t target = target_of(d);
    if ((d->desc->flags & CO_DRIVE_CW_BIT11_REVERSE) != 0u && (d->controlword & 0x0800u) != 0u) {
        target = target == INT32_MIN ? INT32_MAX : -target;
    }
    if (d->desc->reference_from_bus != NULL && !d->desc->reference_from_bus(d)) {
        target = 0; /* a local source, simulated as 0 */
    }
    return target;
}

int32_t co_drive_limited_target(const co_drive *d)
{
    bool limited;
    return co_vl_limit(reference(d), min_amount(d), max_amount(d), &limited);
}

/* The ramp input while running, from the target, the limits, the controlword's vl bits, halt
 * and any communication-loss override. */
static void compute_setpoint(co_drive *d)
{
    const co_drive_desc *desc = d->desc;
    bool limited;
    int32_t target = co_vl_limit(reference(d), min_amount(d), max_amount(d), &limited);
    int32_t wanted = target;
    d->internal_limit = limited && d->state == CO_CIA402_OPERATION_ENABLED &&
                        (desc->flags & CO_DRIVE_NO_INTERNAL_LIMIT) == 0u;
    d->hold = false;
    d->halting = false;
    if (desc->command_from_bus != NULL && !desc->command_from_bus(d)) {
        target = 0; /* no run command from the bus: the motor stays at 0 */
    }
    if (d->override == CO_DRIVE_LOSS_PRESET) {
        target = d->override_setpoint;
        wanted = target;
    } else if (d->override == CO_DRIVE_LOSS_HOLD_OUTPUT) {
        d->hold = true;
    }
    bool cia402 = desc->profile == CO_DRIVE_PROFILE_CIA402;
    uint16_t cw = d->controlword;
    if ((desc->flags & CO_DRIVE_RFG_LATCHED) != 0u) {
        /* Benshaw §8.1.2.2: bit 5 = 0 holds the output, bit 6 = 0 takes 0 as the target; both
         * as latched while bit 4 was 1 (the latch is (0, 0) on entering Operation enabled). */
        if ((cw & CO_CW_VL_RFG_ENABLE) != 0u) {
            d->rfg_latch = (uint8_t)(cw & (CO_CW_VL_RFG_UNLOCK | CO_CW_VL_RFG_USE_REF));
        }
        if ((d->rfg_latch & CO_CW_VL_RFG_UNLOCK) == 0u) {
            d->hold = true;
        }
        if ((d->rfg_latch & CO_CW_VL_RFG_USE_REF) == 0u) {
            target = 0;
        }
    } else if ((desc->flags & CO_DRIVE_RFG_IGNORED) == 0u && cia402) {
        /* CiA 402 vl: bit 4 = 0 forces the ramp output to 0, bit 5 = 0 holds it, bit 6 = 0 sets
         * its input to 0. So 0x007F runs, 0x000F enables at standstill. */
        if ((cw & CO_CW_VL_RFG_ENABLE) == 0u) {
            target = 0;
            co_vl_ramp_reset(&d->ramp, 0);
        } else if ((cw & CO_CW_VL_RFG_UNLOCK) == 0u) {
            d->hold = true;
        } else if ((cw & CO_CW_VL_RFG_USE_REF) == 0u) {
            target = 0;
        }
    }
    d->goal = wanted; /* what 'target reached' compares with */
    if ((desc->flags & CO_DRIVE_HALT_IGNORED) == 0u && (cw & CO_CW_HALT) != 0u && cia402) {
        target = 0; /* halt: to 0 on the halt option's slope, staying in Operation enabled */
        d->halting = true;
        d->goal = 0;
    }
    d->setpoint = target;
}

static co_vl_slope halt_slope(const co_drive *d, co_vl_slope dec)
{
    return stop_slope_dec(d, halt_stop(option(d, d->obj.halt_option, d->desc->halt_option)),
                          dec);
}

/* The value 0x6043 shows. */
static int32_t shown_demand(const co_drive *d)
{
    if (d->output) {
        return d->ramp.demand;
    }
    return (d->desc->flags & CO_DRIVE_DEMAND_SHOWS_MOTOR) != 0u ? d->motor.actual : 0;
}

static bool ramp_settled(const co_drive *d)
{
    switch (d->motion) {
    case CO_DRIVE_MOTION_RUN:
        return d->hold || d->ramp.demand == d->setpoint;
    case CO_DRIVE_MOTION_STOP:
        return d->ramp.demand == 0 && d->then == CO_DRIVE_THEN_STAY;
    default:
        return true;
    }
}

static void transition(co_drive *d, int t, co_cia402_state to, uint64_t now);
static void trip_row(co_drive *d, const co_drive_trip *row, uint16_t trip_code, bool cause,
                     uint64_t now);

/* A stop has reached standstill: what comes next. */
static void stop_done(co_drive *d, uint64_t now)
{
    switch (d->then) {
    case CO_DRIVE_THEN_OFF:
        d->output = false;
        d->motion = CO_DRIVE_MOTION_OFF;
        break;
    case CO_DRIVE_THEN_DISABLE:
        d->output = false;
        d->motion = CO_DRIVE_MOTION_OFF;
        switch (d->state) {
        case CO_CIA402_QUICK_STOP_ACTIVE: transition(d, 12, CO_CIA402_SWITCH_ON_DISABLED, now); break;
        case CO_CIA402_OPERATION_ENABLED: transition(d, 9, CO_CIA402_SWITCH_ON_DISABLED, now); break;
        case CO_CIA402_SWITCHED_ON: transition(d, 10, CO_CIA402_SWITCH_ON_DISABLED, now); break;
        case CO_CIA402_READY_TO_SWITCH_ON: transition(d, 7, CO_CIA402_SWITCH_ON_DISABLED, now); break;
        default: break;
        }
        break;
    case CO_DRIVE_THEN_FAULT:
        d->output = false;
        d->motion = CO_DRIVE_MOTION_OFF;
        if (d->state == CO_CIA402_FAULT_REACTION_ACTIVE) {
            transition(d, 14, CO_CIA402_FAULT, now);
        }
        break;
    default:
        break; /* stay at 0 with the output on */
    }
}

/* Runs the ramp and the motor for elapsed_us. */
static void step(co_drive *d, uint64_t elapsed, uint64_t now)
{
    bool reached_stop = false;
    switch (d->motion) {
    case CO_DRIVE_MOTION_RUN:
        if (!d->hold) {
            (void)co_vl_ramp_run(&d->ramp, d->setpoint, &d->acc, d->halting ? &d->halt : &d->dec,
                                 elapsed);
        }
        break;
    case CO_DRIVE_MOTION_STOP:
        reached_stop = co_vl_ramp_toward(&d->ramp, 0, &d->stop_s, elapsed) &&
                       d->then != CO_DRIVE_THEN_STAY;
        break;
    case CO_DRIVE_MOTION_OFF:
        co_vl_ramp_reset(&d->ramp, 0);
        break;
    default:
        break;
    }
    bool coasting = co_motor_update(&d->motor, &d->motor_cfg, d->ramp.demand, d->output,
                                    d->pole_count, elapsed);
    if (reached_stop) {
        stop_done(d, now);
        coasting = co_motor_update(&d->motor, &d->motor_cfg, d->ramp.demand, d->output,
                                   d->pole_count, 0) ||
                   coasting;
    }
    bool was = d->moving;
    d->moving = coasting || !ramp_settled(d);
    if (d->moving && !was) {
        d->tick_origin = now;
    }
    d->stale = true; /* the next pass shows it */
    co_drive_wake(d);
}

/* Brings the motion up to now. */
static void advance(co_drive *d, uint64_t now)
{
    if (now <= d->last) {
        return;
    }
    uint64_t elapsed = now - d->last;
    d->last = now;
    if (d->moving) {
        step(d, elapsed, now);
    }
}

/* Inputs changed at now (motion already advanced to now): recompute and re-arm. Dictionary
 * values and the description's sources are read here, not at every tick. */
static void rearm(co_drive *d, uint64_t now)
{
    co_drive_wake(d); /* what changed may move a deadline */
    d->dirty = false;
    d->acc = acceleration(d);
    d->dec = deceleration(d);
    d->halt = halt_slope(d, d->dec); /* slopes read once each */
    if (d->motion == CO_DRIVE_MOTION_STOP) {
        d->stop_s = stop_slope_dec(d, d->stop, d->dec);
    }
    d->pole_count = poles(d);
    d->remote = d->desc->remote == NULL || d->desc->remote(d);
    if (d->motion == CO_DRIVE_MOTION_RUN) {
        compute_setpoint(d);
    } else {
        d->internal_limit = false;
        d->hold = false;
        d->halting = false;
    }
    step(d, 0, now);
}

static void start_motion(co_drive *d, uint8_t motion)
{
    if (!d->output) {
        /* switching on: the ramp picks the motor up where it is (0 unless it still coasts) */
        co_vl_ramp_reset(&d->ramp, d->motor.actual);
        d->output = true;
    }
    d->motion = motion;
}

/* Starts a stop; a coast (or a stop with the output already off) ends it at once. */
static void start_stop(co_drive *d, uint8_t stop, uint8_t then, uint64_t now)
{
    if (stop == CO_DRIVE_STOP_HOLD && d->output) {
        d->motion = CO_DRIVE_MOTION_HOLD;
        return;
    }
    if (stop == CO_DRIVE_STOP_COAST || stop == CO_DRIVE_STOP_HOLD || !d->output) {
        d->output = false;
        d->motion = CO_DRIVE_MOTION_OFF;
        if (then == CO_DRIVE_THEN_FAULT) {
            /* the output is off: Fault reaction active ends at the next tick (transition 14) */
            d->pending_fault = true;
            d->pending_at = now + CO_DRIVE_TICK_US;
        } else if (then == CO_DRIVE_THEN_DISABLE) {
            d->then = then;
            stop_done(d, now);
        }
        return;
    }
    d->motion = CO_DRIVE_MOTION_STOP;
    d->stop = stop;
    d->then = then;
    d->stop_s = stop_slope(d, stop);
}

/* --- the state machine -------------------------------------------------------------------- */

static void clear_target(co_drive *d)
{
    /* An RPDO that carries the target together with the controlword sets the target after the
     * transition, whatever the mapping order (VF-S15 §7, VF-MB1 C29). */
    if (d->target_rx_frame != 0u && d->target_rx_frame == d->node.stats.rx_frames) {
        return;
    }
    set_target(d, 0);
    put(d, d->obj.target, 0);
}

static void transition(co_drive *d, int t, co_cia402_state to, uint64_t now)
{
    const co_drive_desc *desc = d->desc;
    co_cia402_state from = d->state;
    d->state = to;
    d->last_transition = t;
    input_changed(d);
    switch (t) {
    case 4:
    case 16:
        if ((desc->flags & CO_DRIVE_CLEAR_TARGET) != 0u) {
            clear_target(d); /* 'all internal set-points cleared' (CiA 402 transition 4) */
        }
        d->rfg_latch = 0;
        start_motion(d, CO_DRIVE_MOTION_RUN);
        break;
    case 5:
        start_stop(d,
                   disable_stop(option(d, d->obj.disable_operation_option,
                                       desc->disable_operation_option)),
                   CO_DRIVE_THEN_OFF, now);
        break;
    case 8:
        start_stop(d, disable_stop(option(d, d->obj.shutdown_option, desc->shutdown_option)),
                   CO_DRIVE_THEN_OFF, now);
        break;
    case 11: {
        co_drive_quick_stop q = quick_stop_action(d);
        start_stop(d, q.stop, q.stay ? CO_DRIVE_THEN_STAY : CO_DRIVE_THEN_DISABLE, now);
        break;
    }
    case 14:
        d->pending_fault = false;
        d->output = false;
        d->motion = CO_DRIVE_MOTION_OFF;
        break;
    case 15:
        put(d, d->obj.error_code, 0);
        if (d->fault_emcy != 0u) {
            co_emcy_clear(&d->node, d->fault_emcy);
        }
        d->fault_emcy = 0;
        d->fault_trip = 0;
        d->loss_tripped = false;
        if (desc->fault_reset != NULL) {
            desc->fault_reset(d);
        }
        break;
    case 2:
    case 3:
        break;
    default: /* 6, 7, 9, 10, 12: the output goes off, a running motor coasts */
        d->output = false;
        d->motion = CO_DRIVE_MOTION_OFF;
        break;
    }
    if (desc->transition != NULL) {
        desc->transition(d, t, from, to);
    }
    if (d->observer.state_changed != NULL) {
        d->observer.state_changed(d, d->observer.ctx, t, from, to);
    }
}

static void apply(co_drive *d, co_cia402_command command, uint64_t now)
{
    const co_drive_desc *desc = d->desc;
    for (int i = 0; i < 2; i++) {
        co_cia402_state to;
        int t = co_cia402_next(d->state, command, desc->cia402_flags, quick_stop_action(d).stay,
                               &to);
        if (t < 0) {
            return;
        }
        if ((t == 4 || t == 16) && desc->may_enable != NULL && !desc->may_enable(d)) {
            return;
        }
        if (t == 15 && d->fault_cause) {
            return; /* the cause is still there: stay in Fault */
        }
        transition(d, t, to, now);
        if ((desc->flags & CO_DRIVE_LEVEL_TRIGGERED) != 0u) {
            /* one transition per evaluation; the held controlword again at the next tick */
            d->reevaluate = true;
            d->reevaluate_at = now + CO_DRIVE_TICK_US;
            return;
        }
        if (!(t == 3 && command == CO_CIA402_CMD_ENABLE_OPERATION &&
              (desc->cia402_flags & CO_CIA402_NO_SWITCH_ON_ENABLE) == 0u)) {
            return;
        }
    }
}

/* --- showing ------------------------------------------------------------------------------ */

static uint16_t statusword(const co_drive *d)
{
    const co_drive_desc *desc = d->desc;
    co_cia402_status st;
    st.state = d->state;
    st.voltage_enabled = d->mains_on && (desc->voltage_states & CO_CIA402_STATE_BIT(d->state)) != 0u;
    st.quick_stop_before = d->quick_stop_before;
    st.warning = d->warning;
    st.remote = d->remote;
    st.target_reached = d->target_reached;
    st.internal_limit = d->internal_limit;
    st.manufacturer = 0;
    return co_cia402_statusword(&st, desc->cia402_flags);
}

static void publish(co_drive *d)
{
    co_drive_wake(d); /* the description's publish hook may change what its process reads */
    if (d->state == CO_CIA402_OPERATION_ENABLED) {
        d->target_reached = d->motion == CO_DRIVE_MOTION_RUN && !d->hold && d->output &&
                            d->ramp.demand == d->setpoint && d->setpoint == d->goal;
    } else if (d->state == CO_CIA402_QUICK_STOP_ACTIVE) {
        d->target_reached = d->ramp.demand == 0 && d->motor.actual == 0;
    } else {
        d->target_reached = false;
    }
    put(d, d->obj.statusword, statusword(d));
    put(d, d->obj.demand, shown_demand(d));
    put(d, d->obj.actual, d->motor.actual);
    d->stale = false;
    if (d->desc->publish != NULL) {
        d->desc->publish(d);
    }
}

/* --- hooks and events --------------------------------------------------------------------- */

static void evaluate(co_drive *d, bool edge, uint64_t now)
{
    uint32_t flags = d->desc->cia402_flags;
    co_cia402_command cmd =
        co_cia402_decode(d->controlword, edge ? d->previous_cw : d->controlword, flags);
    if (cmd == CO_CIA402_CMD_FAULT_RESET && d->state != CO_CIA402_FAULT &&
        (flags & CO_CIA402_BIT7_DONT_CARE) != 0u) {
        /* bit 7 is 'x' in every other command: outside Fault its edge is just that command */
        cmd = co_cia402_decode((uint16_t)(d->controlword & ~CO_CW_FAULT_RESET), 0, flags);
    }
    apply(d, cmd, now);
}

/* 0x6046:01/02: a minimum above the maximum is refused (0x06090036). */
static co_abort check_min_max(const co_drive *d, uint8_t subindex, int64_t value)
{
    if (subindex != 1u && subindex != 2u) {
        return CO_ABORT_NONE;
    }
    int64_t lo = subindex == 1u ? value : get_or(d, d->obj.min_amount, 0);
    int64_t hi = subindex == 2u ? value : get_or(d, d->obj.max_amount, INT64_MAX);
    if (has(d->obj.min_amount) && has(d->obj.max_amount) && lo > hi) {
        return CO_ABORT_MAX_BELOW_MIN;
    }
    return CO_ABORT_NONE;
}

/* The value a write brings, for an object of 1-4 bytes (the core has checked its length). */
static int64_t written_value(co_od_ref ref, const uint8_t *data, uint32_t len)
{
    return len <= 4u && len == co_od_sub_size(ref.sub) ? decode(data, len, ref.sub->type) : 0;
}

/* A write of any runtime object but 0x6042: the controlword is evaluated at once; limits,
 * slopes and options are read from the dictionary by the next pass, once the value is stored
 * (after this hook returns). */
static co_abort object_other_written(co_drive *d, co_od_ref ref, int64_t value, uint64_t now)
{
    uint16_t index = ref.entry->index;
    if (index == IDX_MIN_MAX) {
        co_abort rc = check_min_max(d, ref.sub->subindex, value);
        if (rc != CO_ABORT_NONE) {
            return rc;
        }
    }
    advance(d, now);
    if (index == IDX_CONTROLWORD && ref.sub->subindex == 0u) {
        d->previous_cw = d->controlword;
        d->controlword = (uint16_t)value;
        evaluate(d, true, now);
    }
    input_changed(d);
    return CO_ABORT_NONE;
}

/* 0x6042 written (before the dictionary stores the value). The reference is read from the
 * dictionary where it is used (target_of), so most writes are only noted: the value matters to a
 * running ramp (compute_setpoint, at the next pass) and to an enable that waited for it, which is
 * evaluated now and so takes the value from the write. */
static void target_written(co_drive *d, co_od_ref ref, const uint8_t *data, uint32_t len,
                           co_od_origin origin, uint64_t now)
{
    advance(d, now);
    if (ref.sub->subindex == 0u) {
        d->target_rx_frame = origin == CO_ORIGIN_RPDO ? d->node.stats.rx_frames : 0u;
        if (d->state == CO_CIA402_SWITCHED_ON && d->desc->may_enable != NULL) {
            set_target(d, (int32_t)written_value(ref, data, len));
            evaluate(d, false, now); /* an enable that waited for the first reference */
        } else if (has(d->obj.target)) {
            d->target_stored = true;
        } else {
            set_target(d, 0); /* not a value of 1-4 bytes */
        }
    }
    if (d->motion == CO_DRIVE_MOTION_RUN) {
        input_changed(d);
    }
}

/* The runtime's hook for writes of 0x6000-0x67FF (after the description's, if it has one). */
static co_abort object_written(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                               uint32_t len, co_od_origin origin)
{
    co_drive *d = ctx;
    uint16_t index = ref.entry->index;
    if (d->profile_off && (index == IDX_CONTROLWORD || index == IDX_TARGET)) {
        if (index == IDX_TARGET) {
            set_target(d, target_of(d)); /* the value stored now is not the reference */
        }
        return CO_ABORT_NONE; /* stored only */
    }
    if (index != IDX_TARGET) {
        return object_other_written(d, ref, written_value(ref, data, len), node->now);
    }
    target_written(d, ref, data, len, origin, node->now);
    return CO_ABORT_NONE;
}

/* The hook of a drive whose description hears the writes first (desc->write): an abort it
 * returns refuses the write. */
static co_abort object_written_by_description(co_node *node, void *ctx, co_od_ref ref,
                                              const uint8_t *data, uint32_t len,
                                              co_od_origin origin)
{
    co_drive *d = ctx;
    co_drive_wake(d); /* the description hears the write */
    co_abort rc = d->desc->write(d, ref, data, len, origin);
    if (rc != CO_ABORT_NONE) {
        return rc;
    }
    return object_written(node, ctx, ref, data, len, origin);
}

static co_abort object_read(co_node *node, void *ctx, co_od_ref ref)
{
    co_drive *d = ctx;
    if (d->desc->refresh != NULL) {
        co_drive_wake(d); /* the description hears the read */
        co_abort rc = d->desc->refresh(d, ref);
        if (rc != CO_ABORT_NONE) {
            return rc;
        }
    }
    advance(d, node->now); /* an SDO read between two ticks sees the value of its moment */
    if (d->dirty) {
        rearm(d, node->now); /* a write since the last co_drive_process */
    }
    publish(d);
    return CO_ABORT_NONE;
}

/* The application's state after power-on or a reset node: transitions 0 and 1. */
static void reset_application(co_drive *d)
{
    co_drive_wake(d);
    d->state = CO_CIA402_SWITCH_ON_DISABLED; /* 0, 1: self-test, then communication enabled */
    d->last_transition = 1;
    d->controlword = 0;
    d->previous_cw = 0;
    d->rfg_latch = 0;
    set_target(d, 0);
    d->target_rx_frame = 0;
    d->output = false;
    d->motion = CO_DRIVE_MOTION_OFF;
    d->override = 0;
    d->warning = false;
    d->internal_limit = false;
    d->reevaluate = false;
    d->pending_fault = false;
    d->fault_emcy = 0;
    d->fault_trip = 0;
    d->loss_active = false;
    d->loss_tripped = false;
    co_vl_ramp_reset(&d->ramp, 0);
    d->moving = d->motor.actual != 0; /* a running motor coasts down */
}

/* Copies the values of the description's keep ranges into d->kept (save) or back. The order is
 * the dictionary's, so both walks meet the same bytes. Runs only at a reset node. */
static void keep_walk(co_drive *d, bool save)
{
    const co_drive_desc *desc = d->desc;
    const co_od *od = desc->od;
    uint32_t pos = 0;
    /* the entries are sorted by index: none after the last range's end is kept */
    uint32_t last = 0;
    for (uint32_t r = 0; r < desc->keep_count; r++) {
        last = desc->keep[r].last > last ? desc->keep[r].last : last;
    }
    for (uint32_t e = 0; e < od->entry_count && od->entries[e].index <= last; e++) {
        const co_od_entry *entry = &od->entries[e];
        bool kept = false;
        for (uint32_t r = 0; r < desc->keep_count; r++) {
            kept = kept || (entry->index >= desc->keep[r].first &&
                            entry->index <= desc->keep[r].last);
        }
        for (uint32_t s = 0; kept && s < co_od_entry_sub_count(entry); s++) {
            const co_od_sub *sub = &co_od_entry_subs(entry)[s];
            if (sub->type == CO_DOMAIN || co_od_sub_size(sub) == 0u) {
                continue;
            }
            if (pos + co_od_sub_size(sub) > CO_DRIVE_KEEP_BYTES) {
                return; /* beyond the keep area: back to the default */
            }
            uint8_t *value = d->node.values + co_od_value_offset(entry, sub);
            if (save) {
                memcpy(d->kept + pos, value, co_od_sub_size(sub));
            } else {
                memcpy(value, d->kept + pos, co_od_sub_size(sub));
            }
            pos += co_od_sub_size(sub);
        }
    }
}

static void on_reset(co_node *node, void *ctx, bool whole_node)
{
    co_drive *d = ctx;
    co_drive_wake(d);
    advance(d, node->now);
    if (whole_node) {
        d->retrip_emcy = d->fault_cause ? d->fault_emcy : 0u;
        d->retrip_code = d->fault_trip;
        reset_application(d);
        keep_walk(d, true);
    }
    d->reset_kind = whole_node ? 2u : 1u; /* the description hears of it once it is done */
    if (d->app_events.reset != NULL) {
        d->app_events.reset(node, d->app_events.ctx, whole_node);
    }
}

static void on_nmt_changed(co_node *node, void *ctx, co_nmt_state from, co_nmt_state to)
{
    co_drive *d = ctx;
    d->core_event = true;
    co_drive_wake(d); /* the description hears of it */
    if (from == CO_NMT_INITIALISING) {
        /* The reset has restored the defaults: tell the description, show the drive again. */
        bool whole = d->reset_kind == 2u;
        d->reset_kind = 0;
        if (whole && d->started) {
            keep_walk(d, false); /* the inverter's parameters were not reset */
        }
        d->started = true;
        if (d->desc->reset != NULL) {
            d->desc->reset(d, whole);
        }
        if (whole && d->retrip_emcy != 0u) {
            /* the cause of the trip outlived the reset: the drive trips again */
            uint16_t emcy = d->retrip_emcy;
            d->retrip_emcy = 0;
            const co_drive_trip *row =
                d->retrip_code != 0u ? co_drive_find_trip(d->desc, d->retrip_code) : NULL;
            if (row == NULL || row->emcy_code != emcy) {
                row = co_drive_find_emcy(d->desc, emcy);
            }
            if (row != NULL) {
                trip_row(d, row, d->retrip_code, true, node->now);
            } else {
                co_drive_trip_codes(d, emcy, emcy, d->desc->other_trips_register, d->retrip_code, true,
                                    CO_DRIVE_STOP_COAST, node->now);
            }
        }
        rearm(d, node->now);
        publish(d);
    }
    if (d->desc->nmt_changed != NULL) {
        d->desc->nmt_changed(d, from, to);
    }
    if (d->app_events.nmt_changed != NULL) {
        d->app_events.nmt_changed(node, d->app_events.ctx, from, to);
    }
}

/* CiA 402 0x6007 abort connection option code: 1 fault, 2 disable voltage, 3 quick stop. */
static void abort_connection(co_drive *d, co_comm_event event, uint64_t now)
{
    if (event != CO_COMM_HEARTBEAT_LOST && event != CO_COMM_LIFE_GUARD_LOST &&
        event != CO_COMM_RPDO_TIMEOUT && event != CO_COMM_BUS_OFF) {
        return;
    }
    switch (get(d, d->obj.abort_connection)) {
    case 1:
        if (!co_drive_trip_emcy(d, 0x8130u, false, now)) {
            co_drive_trip_codes(d, 0x8130u, 0x8130u, 0x10u, 0, false,
                                fault_stop(option(d, d->obj.fault_reaction_option,
                                         d->desc->fault_reaction_option)),
                                now);
        }
        break;
    case 2: co_drive_command(d, CO_CIA402_CMD_DISABLE_VOLTAGE, now); break;
    case 3: co_drive_command(d, CO_CIA402_CMD_QUICK_STOP, now); break;
    default: break;
    }
}

static void on_comm(co_node *node, void *ctx, co_comm_event event, uint32_t detail)
{
    co_drive *d = ctx;
    d->core_event = true;
    co_drive_wake(d); /* a loss may arm the description's timer */
    advance(d, node->now);
    if (d->desc->comm != NULL) {
        d->desc->comm(d, event, detail);
    } else if (has(d->obj.abort_connection)) {
        abort_connection(d, event, node->now);
    }
    if (d->dirty) {
        rearm(d, node->now);
        publish(d);
    }
    if (d->app_events.comm != NULL) {
        d->app_events.comm(node, d->app_events.ctx, event, detail);
    }
}

/* --- public API --------------------------------------------------------------------------- */

bool co_drive_init(co_drive *d, const co_drive_desc *desc, const co_node_config *cfg)
{
    if (d == NULL || desc == NULL || cfg == NULL || desc->od == NULL ||
        (cfg->od != NULL && cfg->od != desc->od)) {
        return false;
    }
    memset(d, 0, sizeof *d);
    d->desc = desc;
    d->app_events = cfg->events;
    co_node_config c = *cfg;
    c.od = desc->od;
    if (desc->configure != NULL) {
        desc->configure(desc, &c);
    }
    c.events.nmt_changed = on_nmt_changed;
    c.events.reset = on_reset;
    c.events.comm = on_comm;
    c.events.ctx = d;
    if (!co_node_init(&d->node, &c)) {
        return false;
    }
    resolve_objects(d);
    d->motor_cfg.unit = desc->velocity_unit;
    d->motor_cfg.truncate = (desc->flags & CO_DRIVE_TRUNCATE_HZ) != 0u;
    d->motor_cfg.quantise = (desc->flags & CO_DRIVE_QUANTISE_HZ) != 0u;
    d->motor_cfg.coast.delta_speed = desc->max_speed;
    d->motor_cfg.coast.delta_time_us = desc->coast_us;
    co_motor_reset(&d->motor);
    d->mains_on = true;
    d->last_transition = -1;
    for (uint32_t i = 0; i < CO_DRIVE_TIMERS; i++) {
        d->timer[i] = CO_TIME_NEVER;
    }
    for (uint32_t i = 0; i < desc->setting_count && i < CO_DRIVE_MAX_SETTINGS; i++) {
        d->setting[i] = desc->settings[i].def;
    }
    reset_application(d);
    /* Built on the stack: the core keeps no data outside the node (see node.c). */
    const co_od_hook hook = {0x6000u, 0x67FFu, object_read,
                             desc->write != NULL ? object_written_by_description : object_written,
                             NULL, NULL, d};
    if (!co_node_add_hook(&d->node, &hook)) {
        return false;
    }
    if (desc->init != NULL) {
        desc->init(d);
    }
    return true;
}

void co_drive_observe(co_drive *d, const co_drive_observer *observer)
{
    d->observer = *observer;
}

void co_drive_start(co_drive *d, uint64_t now)
{
    d->last = now;
    co_node_start(&d->node, now);
}

void co_drive_rx(co_drive *d, const co_frame *frame, uint64_t now)
{
    co_node_rx(&d->node, frame, now);
}

/* The next tick on the grid that started with the movement, or the exact end of a ramp. */
static uint64_t motion_deadline(const co_drive *d, uint64_t now)
{
    if (!d->moving) {
        return CO_TIME_NEVER;
    }
    if (now < d->tick_origin) {
        return now + CO_DRIVE_TICK_US; /* a clock that went back: no grid to keep */
    }
    uint64_t since = now - d->tick_origin;
    uint64_t next = d->tick_origin + (since / CO_DRIVE_TICK_US + 1u) * CO_DRIVE_TICK_US;
    uint64_t left = UINT64_MAX;
    if (d->motion == CO_DRIVE_MOTION_RUN && !d->hold) {
        left = co_vl_ramp_time_to(&d->ramp, d->setpoint, &d->acc, d->halting ? &d->halt : &d->dec);
    } else if (d->motion == CO_DRIVE_MOTION_STOP) {
        left = co_vl_ramp_time_to(&d->ramp, 0, &d->stop_s, &d->stop_s);
    }
    if (left != 0u && left != UINT64_MAX && left < UINT64_MAX - now) {
        next = earliest(next, now + left);
    }
    return next;
}

/* The drive's own work at now, the motor already advanced to now: timers, the description's
 * process, inputs taken in (rearm), the state shown (publish). Returns the drive's next deadline
 * (without the node's) and sets pass_at. */
static DRIVE_NOINLINE uint64_t drive_pass(co_drive *d, uint64_t now)
{
    const co_drive_desc *desc = d->desc;
    d->pass_at = CO_TIME_NEVER; /* what wakes the drive during the pass sets it to 0 */
    uint64_t next = CO_TIME_NEVER;
    if (d->pending_fault) {
        if (now >= d->pending_at) {
            transition(d, 14, CO_CIA402_FAULT, now);
        } else {
            next = d->pending_at;
        }
    }
    if (!d->mains_on && d->state == CO_CIA402_SWITCHED_ON && desc->mains_timeout_us != 0u) {
        if (now - d->mains_lost_at >= desc->mains_timeout_us) {
            transition(d, 10, CO_CIA402_SWITCH_ON_DISABLED, now);
        } else {
            next = earliest(next, d->mains_lost_at + desc->mains_timeout_us);
        }
    }
    if (d->reevaluate && now >= d->reevaluate_at) {
        d->reevaluate = false;
        evaluate(d, false, now);
        input_changed(d);
    }
    if (desc->process != NULL) {
        next = earliest(next, desc->process(d, now));
    }
    if (d->dirty) {
        rearm(d, now);
    }
    if (d->stale) {
        publish(d);
    }
    if (d->reevaluate) {
        next = earliest(next, d->reevaluate_at);
    }
    next = earliest(next, motion_deadline(d, now));
    /* A pass that changed and showed nothing, with the motor settled, is the pass every call
     * before `next` would make: those calls skip it. Anything else is looked at again at the next
     * call (a moving motor is shown at every call). */
    bool woken = d->pass_at == 0u;
    d->pass_at = woken || d->moving ? 0u : next;
    return next;
}

uint64_t co_drive_process(co_drive *d, uint64_t now)
{
    uint64_t next;
    if (now < d->pass_at && now >= d->last) {
        /* Nothing due and nothing new (pass_at): the motor is settled, so advancing it to now is
         * only taking the time. A clock that went back makes a pass, as it always has. */
        d->last = now;
        next = d->pass_at;
    } else {
        advance(d, now);
        next = drive_pass(d, now);
    }
    d->core_event = false;
    next = earliest(next, co_node_process(&d->node, now));
    if (d->core_event) {
        /* A timeout found by the core (heartbeat, guarding, ...) reached the drive after its
         * deadlines were taken: a reaction may have armed a timer or started a stop. Be called
         * again now, so that they are counted. */
        d->core_event = false;
        return now;
    }
    return next;
}

void co_drive_wake(co_drive *d)
{
    d->pass_at = 0u;
}

const co_drive_trip *co_drive_find_trip(const co_drive_desc *desc, uint16_t trip_code)
{
    for (uint32_t i = 0; i < desc->trip_count; i++) {
        const co_drive_trip *t = &desc->trips[i];
        if ((t->flags & CO_DRIVE_TRIP_NO_CODE) == 0u && t->trip_code == trip_code) {
            return t;
        }
    }
    return NULL;
}

const co_drive_trip *co_drive_find_emcy(const co_drive_desc *desc, uint16_t emcy_code)
{
    for (uint32_t i = 0; i < desc->trip_count; i++) {
        if (desc->trips[i].emcy_code == emcy_code) {
            return &desc->trips[i];
        }
    }
    return NULL;
}

static bool report_only(const co_drive_desc *desc, uint16_t emcy_code)
{
    for (uint32_t i = 0; i < desc->report_only_count; i++) {
        if (desc->report_only[i] == emcy_code) {
            return true;
        }
    }
    return false;
}

static void emcy_info(const co_drive *d, uint16_t trip_code, uint8_t info[5])
{
    memset(info, 0, 5);
    switch (d->desc->emcy_info) {
    case CO_DRIVE_EMCY_TRIP_U8:
        info[0] = (uint8_t)trip_code;
        break;
    case CO_DRIVE_EMCY_TRIP_LE:
        info[0] = (uint8_t)trip_code;
        info[1] = (uint8_t)(trip_code >> 8);
        break;
    default:
        break;
    }
}

void co_drive_trip_codes(co_drive *d, uint16_t emcy_code, uint16_t error_code,
                         uint8_t register_bits, uint16_t trip_code, bool cause_stays, uint8_t stop,
                         uint64_t now)
{
    advance(d, now);
    if (d->state == CO_CIA402_FAULT || d->state == CO_CIA402_FAULT_REACTION_ACTIVE) {
        /* one trip is shown at a time: the first is kept */
        d->fault_cause = d->fault_cause || cause_stays;
        return;
    }
    d->quick_stop_before = (statusword(d) & CO_SW_QUICK_STOP) != 0u;
    d->fault_emcy = emcy_code;
    d->fault_trip = trip_code;
    d->fault_cause = cause_stays;
    d->override = 0;
    put(d, d->obj.error_code, error_code);
    uint8_t info[5];
    emcy_info(d, trip_code, info);
    (void)co_emcy_raise_info(&d->node, emcy_code, register_bits, info,
                             (d->desc->flags & CO_DRIVE_HISTORY_TRIP_CODE) != 0u ? trip_code : 0u);
    co_cia402_state from = d->state;
    d->state = CO_CIA402_FAULT_REACTION_ACTIVE; /* transition 13 */
    d->last_transition = 13;
    input_changed(d);
    if (d->desc->tripped != NULL) {
        d->desc->tripped(d, trip_code);
    }
    if (d->desc->transition != NULL) {
        d->desc->transition(d, 13, from, d->state);
    }
    if (d->observer.state_changed != NULL) {
        d->observer.state_changed(d, d->observer.ctx, 13, from, d->state);
    }
    start_stop(d, stop, CO_DRIVE_THEN_FAULT, now);
    rearm(d, now);
    publish(d);
}

static void trip_row(co_drive *d, const co_drive_trip *row, uint16_t trip_code, bool cause,
                     uint64_t now)
{
    const co_drive_desc *desc = d->desc;
    uint16_t error_code = (desc->flags & CO_DRIVE_603F_TRIP_CODE) != 0u &&
                                  (row->flags & CO_DRIVE_TRIP_NO_CODE) == 0u
                              ? row->trip_code
                              : row->emcy_code;
    co_drive_trip_codes(d, row->emcy_code, error_code, row->error_register, trip_code, cause,
                        fault_stop(option(d, d->obj.fault_reaction_option, desc->fault_reaction_option)),
                        now);
}

bool co_drive_inject_fault(co_drive *d, uint16_t trip_code, uint64_t now)
{
    const co_drive_desc *desc = d->desc;
    const co_drive_trip *row = co_drive_find_trip(desc, trip_code);
    if (row == NULL) {
        if (desc->other_trips_emcy == 0u) {
            return false;
        }
        co_drive_trip_codes(d, desc->other_trips_emcy, desc->other_trips_emcy, desc->other_trips_register,
                            trip_code, true,
                            fault_stop(option(d, d->obj.fault_reaction_option, desc->fault_reaction_option)),
                            now);
        return true;
    }
    if (report_only(desc, row->emcy_code)) {
        return co_drive_report_error(d, row->emcy_code, now);
    }
    trip_row(d, row, trip_code, true, now);
    return true;
}

bool co_drive_trip_emcy(co_drive *d, uint16_t emcy_code, bool cause_stays, uint64_t now)
{
    const co_drive_trip *row = co_drive_find_emcy(d->desc, emcy_code);
    if (row == NULL) {
        return false;
    }
    trip_row(d, row, (row->flags & CO_DRIVE_TRIP_NO_CODE) != 0u ? 0u : row->trip_code,
             cause_stays, now);
    return true;
}

void co_drive_clear_fault_cause(co_drive *d)
{
    d->fault_cause = false;
    co_drive_wake(d);
}

bool co_drive_report_error(co_drive *d, uint16_t emcy_code, uint64_t now)
{
    (void)now;
    const co_drive_trip *row = co_drive_find_emcy(d->desc, emcy_code);
    if (row == NULL) {
        return false;
    }
    uint8_t info[5];
    emcy_info(d, (row->flags & CO_DRIVE_TRIP_NO_CODE) != 0u ? 0u : row->trip_code, info);
    (void)co_emcy_raise(&d->node, row->emcy_code, row->error_register, info);
    return true;
}

void co_drive_clear_error(co_drive *d, uint16_t emcy_code)
{
    co_emcy_clear(&d->node, emcy_code);
}

bool co_drive_fault_reset(co_drive *d, uint64_t now)
{
    advance(d, now);
    if (d->state != CO_CIA402_FAULT || d->fault_cause) {
        return false;
    }
    transition(d, 15, CO_CIA402_SWITCH_ON_DISABLED, now);
    rearm(d, now);
    publish(d);
    return true;
}

void co_drive_command(co_drive *d, co_cia402_command command, uint64_t now)
{
    advance(d, now);
    apply(d, command, now);
    rearm(d, now);
    publish(d);
}

void co_drive_set_target(co_drive *d, int32_t target, uint64_t now)
{
    advance(d, now);
    set_target(d, target);
    rearm(d, now);
    publish(d);
}

bool co_drive_set_load(co_drive *d, int32_t percent, uint64_t now)
{
    advance(d, now);
    if (!co_motor_set_load(&d->motor, percent)) {
        return false;
    }
    publish(d);
    co_drive_wake(d); /* the description's monitors follow at the next process */
    return true;
}

void co_drive_loss_react(co_drive *d, co_drive_loss reaction, int32_t param, uint64_t now)
{
    advance(d, now);
    bool running = d->state == CO_CIA402_OPERATION_ENABLED && d->output;
    d->loss_active = true;
    switch (reaction) {
    case CO_DRIVE_LOSS_WARNING:
        d->warning = true;
        break;
    case CO_DRIVE_LOSS_RAMP_STOP:
        if (d->state == CO_CIA402_OPERATION_ENABLED) {
            start_stop(d, CO_DRIVE_STOP_RAMP, CO_DRIVE_THEN_DISABLE, now);
        } else if (d->state != CO_CIA402_SWITCH_ON_DISABLED && d->state != CO_CIA402_FAULT &&
                   d->state != CO_CIA402_FAULT_REACTION_ACTIVE) {
            start_stop(d, CO_DRIVE_STOP_COAST, CO_DRIVE_THEN_DISABLE, now);
        }
        break;
    case CO_DRIVE_LOSS_COAST_STOP:
        if (d->state != CO_CIA402_SWITCH_ON_DISABLED && d->state != CO_CIA402_FAULT &&
            d->state != CO_CIA402_FAULT_REACTION_ACTIVE) {
            start_stop(d, CO_DRIVE_STOP_COAST, CO_DRIVE_THEN_DISABLE, now);
        }
        break;
    case CO_DRIVE_LOSS_QUICK_STOP:
        apply(d, CO_CIA402_CMD_QUICK_STOP, now);
        break;
    case CO_DRIVE_LOSS_DISABLE_VOLTAGE:
        apply(d, CO_CIA402_CMD_DISABLE_VOLTAGE, now);
        break;
    case CO_DRIVE_LOSS_HOLD_OUTPUT:
        if (running) {
            d->override = CO_DRIVE_LOSS_HOLD_OUTPUT;
            d->warning = true;
        }
        break;
    case CO_DRIVE_LOSS_FREEWHEEL:
        if (running) {
            d->override = CO_DRIVE_LOSS_FREEWHEEL;
            d->warning = true;
            d->output = false;
            d->motion = CO_DRIVE_MOTION_OFF;
        }
        break;
    case CO_DRIVE_LOSS_PRESET:
        if (running) {
            int32_t speed = param == INT32_MIN ? INT32_MAX : (param < 0 ? -param : param);
            d->override = CO_DRIVE_LOSS_PRESET;
            d->override_setpoint = d->ramp.demand < 0 ? -speed : speed;
            d->warning = true;
        }
        break;
    case CO_DRIVE_LOSS_TRIP:
        if (co_drive_trip_emcy(d, (uint16_t)param, true, now)) {
            d->loss_tripped = true;
        }
        break;
    default:
        break;
    }
    input_changed(d);
    rearm(d, now);
    publish(d);
}

void co_drive_loss_clear(co_drive *d, uint64_t now)
{
    advance(d, now);
    d->loss_active = false;
    d->warning = false;
    if (d->override == CO_DRIVE_LOSS_FREEWHEEL && d->state == CO_CIA402_OPERATION_ENABLED) {
        start_motion(d, CO_DRIVE_MOTION_RUN); /* the drive follows the command again */
    }
    d->override = 0;
    if (d->loss_tripped) {
        d->fault_cause = false;
    }
    rearm(d, now);
    publish(d);
}

void co_drive_set_mains(co_drive *d, bool on, uint64_t now)
{
    advance(d, now);
    if (d->mains_on && !on) {
        d->mains_lost_at = now;
    }
    d->mains_on = on;
    rearm(d, now);
    publish(d);
}

bool co_drive_set_setting(co_drive *d, const char *name, int32_t value)
{
    const co_drive_desc *desc = d->desc;
    for (uint32_t i = 0; i < desc->setting_count && i < CO_DRIVE_MAX_SETTINGS; i++) {
        if (strcmp(desc->settings[i].name, name) == 0) {
            if (value < desc->settings[i].min || value > desc->settings[i].max) {
                return false;
            }
            d->setting[i] = value;
            input_changed(d);
            return true;
        }
    }
    return false;
}

void co_drive_touch(co_drive *d)
{
    input_changed(d);
}
