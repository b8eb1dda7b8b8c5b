/* Toshiba TOSVERT VF-S15 with its CANopen option (CAN001Z/002Z/003Z): the drive's description
 * and its own C. Authority: Toshiba "TOSVERT VF-S15 series CANopen Communication Function Manual" ("§" below); the
 * behaviour items Bn are those of od/vf-s15/NOTES.md, which were written from it. Where a NOTES
 * choice is used it says so.
 *
 * Departures from plain CiA 402 (B5, B7, B8):
 * - velocity mode only; 0x000F in Ready to switch on is 'Switch on + Enable operation' (3 + 4,
 *   §5.1.2 table), 0x000F in Switch on disabled does nothing; bit 7 = 1 carries no command;
 * - controlword bits 4-6 and halt (bit 8) are not supported (§5.1.2 'bold bits'): 0x000F runs,
 *   as the §7 example does;
 * - 0x6042 is cleared on entering Operation enabled (§5.1.4); the target of the RPDO that enables
 *   is taken after the transition, so §7's 0F 00 DC 05 runs at 1500 min-1;
 * - 0x6042 is clamped by 0x6046 (not refused) with statusword bit 11 while clamped (§5.1);
 * - rpm <-> Hz through F856 (pole pairs, §5.1, B7); 6044 is the 0.01 Hz output frequency in rpm;
 * - statusword bit 4 = main circuit charged (all states while mains are on), bit 9 remote when
 *   CMOd = 3 and FMOd = 6 (§7 prints 0x0637), bit 10 target reached;
 * - 0x605A (§5.1.11): negatives and 9.. act as 0, 3 as 2, 7 as 6 (NOTES B8 choices);
 * - transition 5 decelerates on 0x6049 (NOTES B5 choice), 7-10/12 coast, faults coast;
 * - switched on without mains for 3 s -> Switch on disabled (§5.1.2 NOTE);
 * - 603F/EMCY/0x1003 from faults.csv (§5.1.1), EMCY byte 3 = trip code (NOTES Choices 21);
 * - communication loss: C100 delay, C101 reaction, C103 condition (§3.2, B9);
 * - FA04/FA06 fault reset, FA00 drive reset, F899 communication reset (§3.2, B6). */
#include "canopen/drive.h"
#include "canopen/nmt.h"
#include "drive_trips_vf_s15.h"
#include "od_vf_s15.h"

#define CMOD 0x2003u  /* command mode: 3 = CANopen */
#define FMOD 0x2004u  /* frequency setting mode 1: 6 = CANopen */
#define F856 0x2856u  /* pole pairs for communication (1-8, 2 = 4 poles) */
#define F899 0x2899u  /* communication function reset */
#define FA00 0x2A00u  /* communication command: reset */
#define FA04 0x2A04u  /* CANopen command: CiA 402 reset */
#define FA06 0x2A06u  /* COM option command: CiA 402 reset */
#define C100 0x4100u  /* communication time-out delay, 0.1 s */
#define C101 0x4101u  /* operation at communication loss */
#define C102 0x4102u  /* preset speed */
#define C103 0x4103u  /* time-out condition */
#define C701 0x4701u  /* node-ID */

/* co_drive.var / timer use */
#define V_LOST 0u        /* sources of a communication loss: bits of LOST_* */
#define V_REACTED 1u     /* the C101 reaction has been applied */
#define V_COMM_RESET 2u  /* F899 = 1 written: reset communication at the next process */
#define V_CMOD_AT 3u     /* value-block offsets of CMOd, FMOd and F856, which the drive reads */
#define V_FMOD_AT 4u     /* at every change of its inputs: resolved once by init (-1: the */
#define V_F856_AT 5u     /* dictionary has no such UNSIGNED16) */
#define T_LOSS 0u        /* when the C101 reaction is due */
#define LOST_HEARTBEAT 0x01
#define LOST_GUARD 0x02
#define LOST_BUS_OFF 0x04

/* Settings without an object: the preset frequencies of C101 = 5 are drive parameters this
 * manual does not give (B9). */
static const co_drive_setting vf_s15_settings[] = {
    {"preset_speed", 0, 0, 30000,
     "min-1 run at by C101 = 5 (preset speed); 0 keeps the last speed (NOTES B9)"},
};

/* Inverter parameters (F, A, C: 0x2000-0x5FFF, §4.2) live in the inverter's EEPROM: an NMT
 * reset node resets the CANopen option, not them (B2: 'stored immediately'). */
static const co_drive_range vf_s15_keep[] = {{0x2000u, 0x5FFFu}};

static uint16_t param(const co_drive *d, uint16_t index)
{
    return co_od_get_u16(&d->node, index, 0);
}

/* Where param(d, index) would read, for the parameters read on every input change. */
static int32_t param_offset(const co_drive *d, uint16_t index)
{
    co_od_ref ref;
    if (co_od_locate(d->node.od, index, 0, &ref) != CO_ABORT_NONE ||
        co_od_sub_size(ref.sub) != 2u || ref.sub->type == CO_DOMAIN) {
        return -1;
    }
    return (int32_t)co_od_value_offset(ref.entry, ref.sub);
}

/* param() of a parameter whose offset init resolved into var[v]. */
static uint16_t param_at(const co_drive *d, uint32_t v)
{
    return d->var[v] < 0 ? 0u : co_get_le16(d->node.values + d->var[v]);
}

static bool remote(const co_drive *d)
{
    return param_at(d, V_CMOD_AT) == 3u && param_at(d, V_FMOD_AT) == 6u;
}

static bool command_from_bus(const co_drive *d)
{
    return param_at(d, V_CMOD_AT) == 3u;
}

static bool reference_from_bus(const co_drive *d)
{
    return param_at(d, V_FMOD_AT) == 6u;
}

static uint16_t poles_of(const co_drive *d)
{
    return (uint16_t)(2u * param_at(d, V_F856_AT)); /* F856 = k means 2k poles */
}

/* §5.1.11 with the NOTES B8 readings of the values the manual does not define. */
static co_drive_quick_stop quick_stop(int16_t code)
{
    co_drive_quick_stop q = {CO_DRIVE_STOP_COAST, false};
    switch (code) {
    case 1: q.stop = CO_DRIVE_STOP_RAMP; break;
    case 2: case 3: case 4: q.stop = CO_DRIVE_STOP_QUICK; break;
    case 5: q.stop = CO_DRIVE_STOP_RAMP; q.stay = true; break;
    case 6: case 7: case 8: q.stop = CO_DRIVE_STOP_QUICK; q.stay = true; break;
    default: break; /* 0, 'no function' (<0) and reserved (>8): output off */
    }
    return q;
}

/* C103: does the drive react to the loss? */
static bool loss_applies(const co_drive *d)
{
    uint16_t c103 = param(d, C103);
    if (c103 == 0u) {
        return true;
    }
    uint16_t cmod = param(d, CMOD);
    uint16_t fmod = param(d, FMOD);
    bool enabled = (cmod == 3u || cmod == 4u) && (fmod == 6u || fmod == 7u);
    if (c103 == 1u) {
        return enabled;
    }
    bool running = d->motor.actual != 0 || (d->state == CO_CIA402_OPERATION_ENABLED && d->output);
    return enabled && running;
}

/* C101 (default 4): what the drive does once the loss has lasted C100. */
static void react(co_drive *d, uint64_t now)
{
    d->var[V_REACTED] = 1;
    if (!loss_applies(d)) {
        return;
    }
    switch (param(d, C101)) {
    case 0: /* 'stop and communication release' (not for software 1.00): as 2 (NOTES B9) */
    case 2:
        co_drive_loss_react(d, CO_DRIVE_LOSS_RAMP_STOP, 0, now);
        break;
    case 3:
        co_drive_loss_react(d, CO_DRIVE_LOSS_COAST_STOP, 0, now);
        break;
    case 4: /* emergency stop: a trip with the communication error code */
        co_drive_loss_react(d, CO_DRIVE_LOSS_TRIP,
                            (d->var[V_LOST] & LOST_BUS_OFF) != 0 ? 0x8140 : 0x8130, now);
        break;
    case 5:
        if (param(d, C102) != 0u && d->setting[0] != 0) {
            co_drive_loss_react(d, CO_DRIVE_LOSS_PRESET, d->setting[0], now);
        }
        break;
    default: /* 1: none */
        break;
    }
}

static void comm(co_drive *d, co_comm_event event, uint32_t detail)
{
    (void)detail;
    uint64_t now = d->node.now;
    int32_t bit = 0;
    bool lost = false;
    switch (event) {
    case CO_COMM_HEARTBEAT_LOST: bit = LOST_HEARTBEAT; lost = true; break;
    case CO_COMM_HEARTBEAT_RESUMED: bit = LOST_HEARTBEAT; break;
    case CO_COMM_LIFE_GUARD_LOST: bit = LOST_GUARD; lost = true; break;
    case CO_COMM_LIFE_GUARD_RESUMED: bit = LOST_GUARD; break;
    case CO_COMM_BUS_OFF: bit = LOST_BUS_OFF; lost = true; break; /* a loss too (NOTES B9) */
    case CO_COMM_BUS_RECOVERED: bit = LOST_BUS_OFF; break;
    default: return;
    }
    if (lost) {
        if (d->var[V_LOST] == 0) {
            d->var[V_REACTED] = 0;
            d->timer[T_LOSS] = now + (uint64_t)param(d, C100) * 100000u;
        }
        d->var[V_LOST] |= bit;
        if (now >= d->timer[T_LOSS] && d->var[V_REACTED] == 0) {
            d->timer[T_LOSS] = CO_TIME_NEVER;
            react(d, now); /* C100 = 0: at once */
        }
        return;
    }
    d->var[V_LOST] &= ~bit;
    if (d->var[V_LOST] == 0) {
        d->timer[T_LOSS] = CO_TIME_NEVER; /* back within C100: nothing happened */
        if (d->var[V_REACTED] != 0) {
            co_drive_loss_clear(d, now); /* a trip can now be reset; warnings end */
        }
        d->var[V_REACTED] = 0;
    }
}

static uint64_t process(co_drive *d, uint64_t now)
{
    if (d->var[V_COMM_RESET] != 0) {
        d->var[V_COMM_RESET] = 0;
        co_nmt_reset_communication(&d->node, now); /* F899 = 1 (B6); then it reads 0 */
        (void)co_od_set_u16(&d->node, F899, 0, 0);
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

/* Toshiba parameters that act when written. */
static co_abort param_written(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                              uint32_t len, co_od_origin origin)
{
    (void)node;
    (void)origin;
    co_drive *d = ctx;
    co_drive_wake(d); /* its process may read what this sets */
    uint16_t value = len >= 2u ? (uint16_t)(data[0] | (data[1] << 8)) : 0u;
    switch (ref.entry->index) {
    case FA04:
    case FA06:
        /* CiA 402 reset commands (F898 = 0: clear the fault condition); the bit layout is not
           in this manual: a non-zero value resets (NOTES Choices 12). */
        if (value != 0u) {
            (void)co_drive_fault_reset(d, d->node.now);
        }
        break;
    case FA00:
        if (value != 0u) {
            (void)co_drive_fault_reset(d, d->node.now);
            co_drive_command(d, CO_CIA402_CMD_DISABLE_VOLTAGE, d->node.now);
            co_drive_set_target(d, 0, d->node.now);
            (void)co_od_set_i16(&d->node, 0x6042u, 0, 0);
        }
        break;
    case F899:
        if (value == 1u) {
            d->var[V_COMM_RESET] = 1; /* after the SDO response has gone */
        }
        break;
    default:
        co_drive_touch(d); /* CMOd, FMOd, F856 change what the drive shows */
        break;
    }
    return CO_ABORT_NONE;
}

static void init(co_drive *d)
{
    const co_od_hook modes = {CMOD, FMOD, NULL, param_written, NULL, NULL, d};
    const co_od_hook poles = {F856, F899, NULL, param_written, NULL, NULL, d};
    const co_od_hook commands = {FA00, FA06, NULL, param_written, NULL, NULL, d};
    (void)co_node_add_hook(&d->node, &modes);
    (void)co_node_add_hook(&d->node, &poles);
    (void)co_node_add_hook(&d->node, &commands);
    d->var[V_CMOD_AT] = param_offset(d, CMOD);
    d->var[V_FMOD_AT] = param_offset(d, FMOD);
    d->var[V_F856_AT] = param_offset(d, F856);
}

static void reset(co_drive *d, bool whole_node)
{
    if (whole_node) {
        /* C701 reads the node-ID the drive was commissioned with (NOTES Choices 7) */
        (void)co_od_set_u16(&d->node, C701, 0, d->node.node_id);
    }
    d->var[V_LOST] = 0;
    d->var[V_REACTED] = 0;
    d->timer[T_LOSS] = CO_TIME_NEVER;
}

static void configure(const co_drive_desc *desc, co_node_config *cfg)
{
    (void)desc;
    cfg->options |= CO_NODE_COMM_READ_ONLY_IN_OPERATIONAL; /* §6.2: 0x1000-0x1FFF read-only */
    cfg->comm_error_behaviour = 1; /* a guard/heartbeat loss keeps the NMT state (B9) */
}

const co_drive_desc co_drive_desc_vf_s15 = {
    .id = "vf-s15",
    .title = "Toshiba TOSVERT VF-S15 with CANopen option CAN001Z/002Z/003Z (CiA 402 vl)",
    .od = &co_od_vf_s15,
    .trips = co_drive_trips_vf_s15,
    .trip_count = DRIVE_TRIP_COUNT_VF_S15,
    .profile = CO_DRIVE_PROFILE_CIA402,
    .emcy_info = CO_DRIVE_EMCY_TRIP_U8,
    .cia402_flags = 0,
    .flags = CO_DRIVE_CLEAR_TARGET | CO_DRIVE_RFG_IGNORED | CO_DRIVE_HALT_IGNORED |
             CO_DRIVE_QUANTISE_HZ,
    .voltage_states = 0xFFu, /* bit 4 = main circuit charged, in every state */
    .velocity_unit = CO_MOTOR_UNIT_RPM,
    .poles = 4,
    .max_speed = 1500,       /* 50 Hz at 4 poles; the limits are 0x6046's */
    .ramp_time_unit_us = 1000000u,
    .drive_ramp_us = 0,
    .coast_us = 0,           /* 6044 is the output frequency: 0 once the output is off */
    .mains_timeout_us = 3000000u,
    .quick_stop_option = 2,
    .shutdown_option = 0,
    .disable_operation_option = 1,
    .halt_option = 1,
    .fault_reaction_option = 0,
    .keep = vf_s15_keep,
    .keep_count = 1,
    .settings = vf_s15_settings,
    .setting_count = 1,
    .configure = configure,
    .init = init,
    .reset = reset,
    .comm = comm,
    .process = process,
    .remote = remote,
    .command_from_bus = command_from_bus,
    .reference_from_bus = reference_from_bus,
    .quick_stop = quick_stop,
    .poles_of = poles_of,
};
