/* Toshiba TOSVERT VF-MB1/S15 with the EtherCAT option IPE003Z (CoE, CiA 402), served over CAN:
 * the drive's description and its own C. Authority: Toshiba "TOSVERT VF-MB1/S15 series EtherCAT option unit Function Manual, IPE003Z"
 * ("§" below); Bn/Cn are the items of od/vf-mb1-ecat/NOTES.md written from it. Where NOTES and
 * the manual disagree the manual is followed and the comment says so.
 *
 * Departures from plain CiA 402:
 * - controlword bit 7 is 'x' in every command (§6.1.4 table); fault reset is its rising edge in
 *   Fault; 0x000F in Ready to switch on reaches Operation enabled (3 + 4, B10);
 * - controlword bit 11 asks for reverse (§6.1.3): reference = 6042 x (bit 11 ? -1 : +1) (C28);
 * - transition 4 only once 6042 has been received since the last reset while the CiA 402
 *   profile is in effect (§6.1.5 state 5 NOTE, B4.4); the enable waits for it;
 * - 6042 cleared on entering Operation enabled (§6.1.6), the enabling RPDO's 6042 kept (C29);
 * - transitions 5, 8, 9 and faults switch the output off at once (§6.1.5 power table, B4.5);
 * - Quick stop active ignores the controlword: no 12 on Disable voltage, no 16 (§6.1.4 lists
 *   7, 9, 10 only); 0x605A 5-8 act like 1 (§6.1.13 '*Not supported ... slow down ramp and
 *   transit into Switch On Disabled' - NOTES B4.6 puts 7 with 3 as 'like 2': the manual is
 *   followed, 7 acts like 1); 3, negatives and reserved act like 2 (C32);
 * - statusword: Ready 0x0021 (bit 4 only in Switched on / Operation enabled / Quick stop
 *   active, §6.1.4 table), Fault 0x0008 or 0x0028 (bit 5 as before the fault, C25), bit 9 remote
 *   in the CiA 402 profile (CMOd = 4, FMOd = 7), bit 11 never (C27: §8.13 shows 0x0237 above
 *   6046:02);
 * - CMOd, FMOd and F856 take effect at the next reset node (§3.1 'It is necessary to reset');
 * - 6044 = 6043 (a sensorless image, §6.1.8); FD00/FD16 in 0.01 Hz truncated (B5.4);
 * - communication loss (§3.2 C100-C103, §3.3.1, B8): RPDO1 deadline, heartbeat consumer,
 *   bus-off, or leaving OPERATIONAL while enabled; C101 = 4 trips Err8 (0x1B, 0x7520); the other
 *   reactions keep the CiA 402 state and set the FC91 bit 11 alarm; no 0x81xx EMCY (C34);
 * - FA06 bit 12 emergency stop trips E (0x11, 0x9000) in both profiles, bit 13 resets a fault
 *   (§5.2.1.1); FA00 resets the drive, F899 the communication (§3.1, §4.1 note). */
#include "canopen/drive.h"
#include "canopen/nmt.h"
#include "drive_trips_vf_mb1_ecat.h"
#include "od_vf_mb1_ecat.h"

#define CMOD 0x2003u /* 4: command from the option */
#define FMOD 0x2004u /* 7: frequency from the option */
#define F856 0x2856u /* pole pairs */
#define F899 0x2899u
#define FA00 0x2A00u
#define FA06 0x2A06u
#define FC91 0x2C91u /* alarm code: bit 11 option communication alarm */
#define FD00 0x2D00u /* output frequency, 0.01 Hz */
#define FD01 0x2D01u /* inverter operating status 1 */
#define FD03 0x2D03u /* output current, 0.01 % of the rated current */
#define FD16 0x2D16u /* estimated speed, 0.01 Hz */
#define FD18 0x2D18u /* torque, 0.01 % */
#define FD20 0x2D20u /* torque current, 0.01 % */
#define FD26 0x2D26u /* motor load factor, % */
#define C100 0x4100u
#define C101 0x4101u
#define C102 0x4102u
#define C103 0x4103u
#define C400 0x4400u /* EtherCAT state: 1 INIT, 2 PREOP, 8 OP */
#define C402 0x4402u /* station address: the node-ID here */

/* co_drive.var */
#define V_CMOD 0u      /* CMOd in effect (read at reset node) */
#define V_FMOD 1u      /* FMOd in effect */
#define V_PAIRS 2u     /* F856 in effect */
#define V_REFERENCE 3u /* 6042 received since the last reset */
#define V_LOST 4u      /* loss sources, LOST_* */
#define V_REACTED 5u
#define V_DEFERRED 6u  /* 1: reset communication, 2: reset node, at the next process */
#define V_FA06 7u      /* the last FA06 */
#define V_ALARM 8u     /* FC91 bit 11 */
#define T_LOSS 0u
#define LOST_RPDO 0x01
#define LOST_HEARTBEAT 0x02
#define LOST_BUS_OFF 0x04
#define LOST_NMT 0x08

/* Drive parameters 0x2000-0x4F99 keep their values across a reset node (EEPROM, B1.5). */
static const co_drive_range mb1_keep[] = {{0x2000u, 0x4FFFu}};

static uint16_t param(const co_drive *d, uint16_t index)
{
    return co_od_get_u16(&d->node, index, 0);
}

static bool cia402_profile(const co_drive *d)
{
    return d->var[V_CMOD] == 4 && d->var[V_FMOD] == 7;
}

static bool command_from_bus(const co_drive *d)
{
    return d->var[V_CMOD] == 4 || (d->var[V_FA06] & 0x8000) != 0; /* FA06 bit 15: priority */
}

static bool reference_from_bus(const co_drive *d)
{
    return d->var[V_FMOD] == 7;
}

static uint16_t poles_of(const co_drive *d)
{
    return (uint16_t)(2 * d->var[V_PAIRS]);
}

static bool may_enable(const co_drive *d)
{
    return !cia402_profile(d) || d->var[V_REFERENCE] != 0;
}

/* §6.1.13 (see the header comment for 5-8). */
static co_drive_quick_stop quick_stop(int16_t code)
{
    co_drive_quick_stop q = {CO_DRIVE_STOP_QUICK, false};
    if (code == 0) {
        q.stop = CO_DRIVE_STOP_COAST;
    } else if (code == 1 || (code >= 5 && code <= 8)) {
        q.stop = CO_DRIVE_STOP_RAMP;
    }
    return q;
}

/* --- communication loss (B8) ---------------------------------------------------------------- */

static bool enabled(const co_drive *d)
{
    uint16_t cmod = param(d, CMOD);
    uint16_t fmod = param(d, FMOD);
    return (cmod == 3u || cmod == 4u) && (fmod == 6u || fmod == 7u);
}

static bool loss_applies(const co_drive *d)
{
    switch (param(d, C103)) {
    case 0: return true;
    case 1: return enabled(d);
    default: return enabled(d) && d->output;
    }
}

static void react(co_drive *d, uint64_t now)
{
    d->var[V_REACTED] = 1;
    if (!loss_applies(d)) {
        return;
    }
    uint16_t c101 = param(d, C101);
    if (c101 == 4u) { /* network error stop: Err8 */
        co_drive_loss_react(d, CO_DRIVE_LOSS_TRIP, 0x7520, now);
        return;
    }
    d->var[V_ALARM] = 1; /* the 't' alarm while the error lasts (C37) */
    switch (c101) {
    case 0: /* stop, controlled by CMOd/FMOd: as 2 (B8.4) */
    case 2:
    case 5: /* preset speeds are not in the dictionary: as 2 (B8.4) */
        co_drive_loss_react(d, CO_DRIVE_LOSS_PRESET, 0, now);
        break;
    case 3:
        co_drive_loss_react(d, CO_DRIVE_LOSS_FREEWHEEL, 0, now);
        break;
    default: /* 1: continue, with the warning bit 7 of the alarm (NOTES B4 statusword) */
        co_drive_loss_react(d, CO_DRIVE_LOSS_WARNING, 0, now);
        break;
    }
}

static void loss_begins(co_drive *d, int32_t source)
{
    uint64_t now = d->node.now;
    if (d->var[V_LOST] == 0) {
        d->var[V_REACTED] = 0;
        d->timer[T_LOSS] = now + (uint64_t)param(d, C100) * 100000u;
    }
    d->var[V_LOST] |= source;
    if (d->var[V_REACTED] == 0 && now >= d->timer[T_LOSS]) {
        d->timer[T_LOSS] = CO_TIME_NEVER;
        react(d, now);
    }
}

static void loss_ends(co_drive *d, int32_t source)
{
    if ((d->var[V_LOST] & source) == 0) {
        return;
    }
    d->var[V_LOST] &= ~source;
    if (d->var[V_LOST] == 0) {
        d->timer[T_LOSS] = CO_TIME_NEVER;
        if (d->var[V_REACTED] != 0) {
            d->var[V_ALARM] = 0;
            co_drive_loss_clear(d, d->node.now);
        }
        d->var[V_REACTED] = 0;
    }
}

static void comm(co_drive *d, co_comm_event event, uint32_t detail)
{
    switch (event) {
    case CO_COMM_RPDO_TIMEOUT:
        if (detail == 1u) {
            loss_begins(d, LOST_RPDO);
        }
        break;
    case CO_COMM_HEARTBEAT_LOST: loss_begins(d, LOST_HEARTBEAT); break;
    case CO_COMM_HEARTBEAT_RESUMED: loss_ends(d, LOST_HEARTBEAT); break;
    case CO_COMM_BUS_OFF: loss_begins(d, LOST_BUS_OFF); break;
    case CO_COMM_BUS_RECOVERED: loss_ends(d, LOST_BUS_OFF); break;
    default: break;
    }
}

static void nmt_changed(co_drive *d, co_nmt_state from, co_nmt_state to)
{
    (void)co_od_set_u16(&d->node, C400, 0,
                        to == CO_NMT_OPERATIONAL ? 8u : (to == CO_NMT_STOPPED ? 1u : 2u));
    if (from == CO_NMT_OPERATIONAL && to != CO_NMT_OPERATIONAL &&
        (d->state == CO_CIA402_OPERATION_ENABLED || d->state == CO_CIA402_QUICK_STOP_ACTIVE) &&
        enabled(d)) {
        loss_begins(d, LOST_NMT); /* OP -> SAFE-OP/PRE-OP/INIT while enabled (§7) */
    } else if (to == CO_NMT_OPERATIONAL) {
        loss_ends(d, LOST_NMT);
    }
}

static void reset_parameters(co_drive *d);

static uint64_t process(co_drive *d, uint64_t now)
{
    if (d->var[V_DEFERRED] != 0) {
        int32_t what = d->var[V_DEFERRED];
        d->var[V_DEFERRED] = 0;
        if (what == 2) {
            co_nmt_reset_node(&d->node, now);
        } else {
            co_nmt_reset_communication(&d->node, now);
            /* §3.1: C003/F004 (and F856) need "a reset of the drive", and F899 = 1 is the reset
             * a master can give: they take effect (B9.4) */
            reset_parameters(d);
        }
        (void)co_od_set_u16(&d->node, F899, 0, 0);
        (void)co_od_set_u16(&d->node, FA00, 0, 0);
    }
    if (d->timer[T_LOSS] != CO_TIME_NEVER) {
        if (now >= d->timer[T_LOSS]) {
            d->timer[T_LOSS] = CO_TIME_NEVER;
            react(d, now);
        } else {
            return d->timer[T_LOSS];
        }
    }
    return CO_TIME_NEVER;
}

/* --- objects -------------------------------------------------------------------------------- */

static co_abort profile_written(co_drive *d, co_od_ref ref, const uint8_t *data, uint32_t len,
                                co_od_origin origin)
{
    (void)data;
    (void)len;
    if (origin == CO_ORIGIN_RPDO) {
        loss_ends(d, LOST_RPDO); /* RPDO1 is back */
    }
    if (ref.entry->index == 0x6042u) {
        d->var[V_REFERENCE] = 1; /* any value, 0 included (B4.4) */
    }
    return CO_ABORT_NONE;
}

static co_abort param_written(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                              uint32_t len, co_od_origin origin)
{
    co_drive *d = ctx;
    co_drive_wake(d); /* its process may read what this sets */
    uint64_t now = node->now;
    uint16_t value = len >= 2u ? (uint16_t)(data[0] | (data[1] << 8)) : 0u;
    if (origin == CO_ORIGIN_RPDO) {
        loss_ends(d, LOST_RPDO);
    }
    switch (ref.entry->index) {
    case FA06: {
        uint16_t before = (uint16_t)d->var[V_FA06];
        d->var[V_FA06] = value;
        if ((value & 0x1000u) != 0u && (before & 0x1000u) == 0u) {
            (void)co_drive_inject_fault(d, 0x11, now); /* emergency stop E, always enabled */
        } else if ((value & 0x1000u) == 0u && (before & 0x1000u) != 0u &&
                   d->fault_trip == 0x11u) {
            co_drive_clear_fault_cause(d); /* the reset is refused while bit 12 = 1 (B7.3) */
        }
        if ((value & 0x2000u) != 0u && (before & 0x2000u) == 0u) {
            (void)co_drive_fault_reset(d, now);
        }
        co_drive_touch(d);
        break;
    }
    case FA00:
        if (value != 0u) {
            d->var[V_DEFERRED] = 2; /* a drive (power) reset, after the SDO answer */
        }
        break;
    case F899:
        if (value == 1u) {
            d->var[V_DEFERRED] = 1;
        }
        break;
    default:
        break;
    }
    return CO_ABORT_NONE;
}

static void publish(co_drive *d)
{
    int32_t hz = d->motor.frequency < 0 ? -d->motor.frequency : d->motor.frequency;
    bool tripped = d->state == CO_CIA402_FAULT || d->state == CO_CIA402_FAULT_REACTION_ACTIVE;
    uint16_t fd01 = 0;
    if (tripped) {
        fd01 |= 0x0003u; /* FL, tripped */
    }
    if (d->var[V_ALARM] != 0) {
        fd01 |= 0x0004u;
    }
    fd01 |= (uint16_t)(d->var[V_FA06] & 0x01F0); /* bits 4-8 from FA06 */
    if (d->ramp.demand < 0) {
        fd01 |= 0x0200u;
    }
    if (d->output) {
        fd01 |= 0x0400u;
    }
    fd01 |= (uint16_t)(d->var[V_FA06] & 0x0800); /* coast stop command */
    if (tripped && d->fault_trip == 0x11u) {
        fd01 |= 0x1000u;
    }
    if (!tripped && d->var[V_ALARM] == 0) {
        fd01 |= 0x4000u; /* standby */
        if (d->state == CO_CIA402_OPERATION_ENABLED) {
            fd01 |= 0x2000u;
        }
    }
    (void)co_od_set_u16(&d->node, FD00, 0, (uint16_t)hz);
    (void)co_od_set_u16(&d->node, FD16, 0, (uint16_t)hz);
    /* the load (B11): current and torque current in 0.01 % of the rated current, torque in
       0.01 % of the rated torque, motor load factor in % */
    (void)co_od_set_u16(&d->node, FD03, 0, d->motor.current);
    (void)co_od_set_u16(&d->node, FD18, 0, d->motor.torque);
    (void)co_od_set_u16(&d->node, FD20, 0, d->motor.torque_current);
    (void)co_od_set_u16(&d->node, FD26, 0, (uint16_t)((d->motor.torque + 50u) / 100u));
    (void)co_od_set_u16(&d->node, FD01, 0, fd01);
    (void)co_od_set_u16(&d->node, FC91, 0, d->var[V_ALARM] != 0 ? 0x0800u : 0u);
}

static bool remote(const co_drive *d)
{
    return cia402_profile(d);
}

/* Parameters that need a reset take effect now (B9.4). */
static void reset_parameters(co_drive *d)
{
    d->var[V_CMOD] = param(d, CMOD);
    d->var[V_FMOD] = param(d, FMOD);
    d->var[V_PAIRS] = param(d, F856);
    co_drive_touch(d);
}

static void reset(co_drive *d, bool whole_node)
{
    if (whole_node) {
        reset_parameters(d);
        d->var[V_FA06] = 0;
        d->var[V_LOST] = 0;
        d->var[V_REACTED] = 0;
        d->var[V_ALARM] = 0;
        d->timer[T_LOSS] = CO_TIME_NEVER;
    }
    d->var[V_REFERENCE] = 0;
    (void)co_od_set_u16(&d->node, C402, 0, d->node.node_id);
}

static void init(co_drive *d)
{
    const co_od_hook commands = {FA00, FA06, NULL, param_written, NULL, NULL, d};
    const co_od_hook comm_reset = {F899, F899, NULL, param_written, NULL, NULL, d};
    (void)co_node_add_hook(&d->node, &commands);
    (void)co_node_add_hook(&d->node, &comm_reset);
}

static void configure(const co_drive_desc *desc, co_node_config *cfg)
{
    (void)desc;
    /* C34: no 0x81xx EMCY; a communication loss is reported as Err8 or the FC91 alarm */
    cfg->options |= CO_NODE_COMM_EMCY_BY_APP;
    /* B8.6: a heartbeat loss keeps the NMT state, so the heartbeat's return ends it (B8.2) */
    cfg->comm_error_behaviour = 1;
}

const co_drive_desc co_drive_desc_vf_mb1_ecat = {
    .id = "vf-mb1-ecat",
    .title = "Toshiba TOSVERT VF-MB1/S15 with EtherCAT option IPE003Z (CoE over CAN, CiA 402 vl)",
    .od = &co_od_vf_mb1_ecat,
    .trips = co_drive_trips_vf_mb1_ecat,
    .trip_count = DRIVE_TRIP_COUNT_VF_MB1_ECAT,
    .profile = CO_DRIVE_PROFILE_CIA402,
    .emcy_info = CO_DRIVE_EMCY_TRIP_U8,
    .cia402_flags = CO_CIA402_BIT7_DONT_CARE | CO_CIA402_QUICK_STOP_LOCKED |
                    CO_CIA402_FAULT_KEEPS_QS_BIT,
    .flags = CO_DRIVE_CLEAR_TARGET | CO_DRIVE_RFG_IGNORED | CO_DRIVE_CW_BIT11_REVERSE |
             CO_DRIVE_NO_INTERNAL_LIMIT | CO_DRIVE_TRUNCATE_HZ,
    .voltage_states = CO_CIA402_STATE_BIT(CO_CIA402_SWITCHED_ON) |
                      CO_CIA402_STATE_BIT(CO_CIA402_OPERATION_ENABLED) |
                      CO_CIA402_STATE_BIT(CO_CIA402_QUICK_STOP_ACTIVE),
    .velocity_unit = CO_MOTOR_UNIT_RPM,
    .poles = 4,
    .max_speed = 1500,
    .ramp_time_unit_us = 1000000u, /* C7: delta time in 1 s */
    .coast_us = 0,                 /* 6043 = 6044 = FD00 = 0 once the output is off (B4.5) */
    .quick_stop_option = 2,
    .shutdown_option = 0,
    .disable_operation_option = 0,
    .halt_option = 1,
    .fault_reaction_option = 0,    /* C36: every trip coasts */
    .keep = mb1_keep,
    .keep_count = 1,
    .configure = configure,
    .init = init,
    .reset = reset,
    .nmt_changed = nmt_changed,
    .comm = comm,
    .write = profile_written,
    .process = process,
    .publish = publish,
    .remote = remote,
    .command_from_bus = command_from_bus,
    .reference_from_bus = reference_from_bus,
    .may_enable = may_enable,
    .quick_stop = quick_stop,
    .poles_of = poles_of,
};
