/* VACON NX with the OPTC6 CANopen option board: the drive's description and its own C.
 * Authority: "VACON NX AC Drives, OPTC6 CANopen Option Board User Manual" (DPD00896B) ("§" below); Bn and 'choice n' are the
 * items of od/vacon-optc6/NOTES.md written from it.
 *
 * The board has an 'Operate mode' keypad parameter (P7.5.1.3, no object): setting
 * "operate_mode", read at board initialisation (power-on, reset node; choice 20). It selects the
 * PDO set (modes.csv, applied at every reset) and how the drive is controlled:
 * - 1 Drive Profile: CiA 402 velocity mode on 0x6040/0x6042 (§7.5). RUN = 0x000F: bits 4-6 are
 *   not needed (§7.5 command table); 0x000F in Ready to switch on runs through Switched on;
 *   STOP = 0x0007 stops on the ramp (disable operation); shutdown / disable voltage coast; quick
 *   stop decelerates on the normal ramp and ends in Switch on disabled (0x604A 'Not Used', §8);
 *   halt decelerates and stays enabled; 0x6046/0x6048/0x6049 values of 0 mean 'not set': the
 *   drive's own limit (max frequency) and ramp (1.0 s) apply (choice 21, 32).
 * - 2-5 Bypass: nx_control_word 0x27D1 (RUN, DIR, RST edge) and nx_speed_reference 0x27D3 in
 *   0.01 % of min..max frequency drive the motor; nx_status_word 0x2836, nx_actual_speed 0x2838
 *   and process data out 0x2839.. report it (§7.6, §7.7, Tab. 7-4, App. C; the Bypass 2/4 layout
 *   in every Bypass mode, choice 22); 0x6040 is stored only, 0x6041 shows a CiA 402 view (B8.8).
 * Faults: NX fault numbers; 0x2063 shows the active one; EMCY bytes 3-4 and 0x1003 bits 16-31
 * carry it (B6.1, B6.4); faults outside faults.csv are EMCY 0x1000. Node-guarding life time
 * expiry = Fieldbus Fault 53 / EMCY 0x8130 with the reaction of setting
 * "fieldbus_fault_response" (B2.5; default 3: fault, coast). AnyParameter service 0x2000-0x2002
 * completes after 10 ms (B9). */
#include "canopen/drive.h"
#include "drive_trips_vacon_optc6.h"
#include "od_vacon_optc6.h"

#define ANY_READ_ID 0x2000u
#define ANY_READ_VALUE 0x2001u
#define ANY_WRITE 0x2002u
#define NX_CURRENT 0x2003u
#define NX_TORQUE 0x2004u
#define NX_FAULT 0x2063u
#define NX_CONTROL 0x27D1u
#define NX_REFERENCE 0x27D3u
#define NX_STATUS 0x2836u
#define NX_SPEED 0x2838u
#define NX_OUT1 0x2839u

#define FIELDBUS_FAULT 53u
#define MAX_SPEED 1500 /* 50 Hz, 4 poles (choice 32) */
#define MAX_FREQ 5000  /* 0.01 Hz */
#define RATED_CURRENT 1000 /* the motor's rated current, 0.01 A (model value, B10) */

enum { S_MODE, S_RESPONSE, S_FIELDBUS };
static const co_drive_setting vacon_settings[] = {
    {"operate_mode", 1, 1, 5,
     "P7.5.1.3 Operate mode: 1 Drive Profile, 2 ByPass, 3 ByPass 2, 4 Bypass 3, 5 Bypass 4"},
    {"fieldbus_fault_response", 3, 0, 3,
     "response to Fieldbus Fault: 0 none, 1 warning, 2 fault + ramp stop, 3 fault + coast"},
    {"control_place_fieldbus", 1, 0, 1, "1: Fieldbus is the active control place (§6)"},
};

/* co_drive.var */
#define V_MODE 0u        /* operate mode in effect */
#define V_NX_CW 1u       /* last nx_control_word */
#define V_NEED_EDGE 2u   /* RUN must rise again before the motor starts (after a fault) */
#define V_ANY_READ 3u    /* AnyParameter read pending: ID + 1 */
#define V_ANY_WRITE 4u   /* AnyParameter write pending: 1 */
#define V_ANY_WRITE_WORD 5u
#define V_PARAM_MIN 6u   /* NX ID 101 min frequency, 0.01 Hz */
#define V_PARAM_MAX 7u   /* 102 max frequency */
#define V_PARAM_ACC 8u   /* 103 acceleration time 1, 0.1 s */
#define V_PARAM_DEC 9u   /* 104 deceleration time 1 */
#define V_POWERED 10u
#define V_REF_WRITTEN 11u /* 0x27D3 written: the Bypass target follows in process() */
#define T_ANY_READ 0u
#define T_ANY_WRITE 1u
#define ANY_DELAY_US 10000u

static bool bypass(const co_drive *d)
{
    return d->var[V_MODE] >= 2;
}

static bool fieldbus(const co_drive *d)
{
    return d->setting[S_FIELDBUS] != 0;
}

/* --- the PDO set of the operate mode (modes.csv) --------------------------------------------- */

typedef struct vacon_pdo {
    uint16_t comm;      /* communication object */
    uint16_t base;      /* CAN-ID without the node-ID */
    uint8_t modes;      /* bit m: part of operate mode m's set */
} vacon_pdo;

static void apply_mode(co_drive *d)
{
    /* Tab. 6-1 / Tab. 7-1 / Tab. 7-2: PDO1 in every mode, PDO6 in Drive Profile, PDO21/22 in
       the Bypass modes, PDO23 in Bypass 3/4. */
    const vacon_pdo set[10] = {
        {0x1400u, 0x200u, 0x3Eu}, {0x1405u, 0x300u, 0x02u}, {0x1414u, 0x400u, 0x3Cu},
        {0x1415u, 0x500u, 0x3Cu}, {0x1416u, 0x300u, 0x30u}, {0x1800u, 0x180u, 0x3Eu},
        {0x1805u, 0x280u, 0x02u}, {0x1814u, 0x380u, 0x3Cu}, {0x1815u, 0x480u, 0x3Cu},
        {0x1816u, 0x280u, 0x30u}};
    uint32_t mode_bit = 1u << (uint32_t)d->var[V_MODE];
    for (uint32_t i = 0; i < 10u; i++) {
        uint32_t cob = set[i].base + d->node.node_id;
        if ((set[i].modes & mode_bit) == 0u) {
            cob |= 0x80000000u;
        }
        (void)co_od_set_u32(&d->node, set[i].comm, 1, cob);
    }
    co_pdo_configure(&d->node, d->node.now);
}

/* --- Bypass control (§7.6) ------------------------------------------------------------------- */

/* nx_speed_reference -> rpm: f = f_min + min(|ref|, 10000) / 10000 x (f_max - f_min); direction
 * DIR xor (ref < 0) (B8.2). */
static int32_t bypass_target(const co_drive *d)
{
    int32_t ref = co_od_get_i16(&d->node, NX_REFERENCE, 0);
    int32_t mag = ref < 0 ? -ref : ref;
    if (mag > 10000) {
        mag = 10000;
    }
    int32_t fmin = d->var[V_PARAM_MIN];
    int32_t fmax = d->var[V_PARAM_MAX];
    int32_t f = fmin + (int32_t)((int64_t)mag * (fmax - fmin) / 10000);
    int32_t rpm = co_motor_centihz_to_rpm(f, 4, false);
    bool reverse = ((d->var[V_NX_CW] & 0x2) != 0) != (ref < 0);
    return reverse ? -rpm : rpm;
}

static void bypass_stopped_ready(co_drive *d, uint64_t now)
{
    if (d->state == CO_CIA402_SWITCH_ON_DISABLED ||
        (d->state == CO_CIA402_SWITCHED_ON && !d->output)) {
        co_drive_command(d, CO_CIA402_CMD_SHUTDOWN, now); /* 'ready and stopped' view */
    }
}

static void bypass_control(co_drive *d, uint16_t cw, uint64_t now)
{
    uint16_t before = (uint16_t)d->var[V_NX_CW];
    d->var[V_NX_CW] = cw;
    if ((cw & 0x4u) != 0u && (before & 0x4u) == 0u && co_drive_fault_reset(d, now)) {
        d->var[V_NEED_EDGE] = 1; /* restart only on a new RUN edge (B8.1) */
        bypass_stopped_ready(d, now);
    }
    bool run = (cw & 0x1u) != 0u;
    if (run && (before & 0x1u) == 0u) {
        d->var[V_NEED_EDGE] = 0;
    }
    co_drive_set_target(d, bypass_target(d), now);
    if (run && d->var[V_NEED_EDGE] == 0 && fieldbus(d)) {
        if (d->state == CO_CIA402_READY_TO_SWITCH_ON || d->state == CO_CIA402_SWITCHED_ON) {
            co_drive_command(d, CO_CIA402_CMD_ENABLE_OPERATION, now);
        }
    } else if (!run && d->state == CO_CIA402_OPERATION_ENABLED) {
        co_drive_command(d, CO_CIA402_CMD_SWITCH_ON, now); /* stop by the stop function: ramp */
    }
}

/* --- AnyParameter service (§7.8, B9) ---------------------------------------------------------- */

static bool any_read(const co_drive *d, uint16_t id, uint16_t *value)
{
    int32_t hz = d->motor.frequency < 0 ? -d->motor.frequency : d->motor.frequency;
    int32_t rpm = d->motor.rpm < 0 ? -d->motor.rpm : d->motor.rpm;
    switch (id) {
    case 1: *value = (uint16_t)hz; return true;
    case 2: *value = (uint16_t)rpm; return true;
    case 3: *value = co_od_get_u16(&d->node, NX_CURRENT, 0); return true;
    case 4: *value = co_od_get_u16(&d->node, NX_TORQUE, 0); return true;
    case 101: *value = (uint16_t)d->var[V_PARAM_MIN]; return true;
    case 102: *value = (uint16_t)d->var[V_PARAM_MAX]; return true;
    case 103: *value = (uint16_t)d->var[V_PARAM_ACC]; return true;
    case 104: *value = (uint16_t)d->var[V_PARAM_DEC]; return true;
    default: return false;
    }
}

static bool any_write(co_drive *d, uint16_t id, uint16_t value)
{
    switch (id) {
    case 101:
        if (value > d->var[V_PARAM_MAX]) {
            return false;
        }
        d->var[V_PARAM_MIN] = value;
        return true;
    case 102:
        if (value < d->var[V_PARAM_MIN] || value > 32000u) {
            return false;
        }
        d->var[V_PARAM_MAX] = value;
        return true;
    case 103:
    case 104:
        if (value < 1u || value > 32000u) {
            return false;
        }
        d->var[id == 103 ? V_PARAM_ACC : V_PARAM_DEC] = value;
        return true;
    default:
        return false; /* unknown or read-only (monitor values) */
    }
}

static co_abort board_written(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                              uint32_t len, co_od_origin origin)
{
    (void)origin;
    co_drive *d = ctx;
    co_drive_wake(d); /* its process may read what this sets */
    uint64_t now = node->now;
    switch (ref.entry->index) {
    case ANY_READ_ID:
        /* a new read: 0x2001 reads 0 until it completes */
        d->var[V_ANY_READ] = (int32_t)(uint16_t)(data[0] | (data[1] << 8)) + 1;
        (void)co_od_set_u32(&d->node, ANY_READ_VALUE, 0, 0);
        d->timer[T_ANY_READ] = now + ANY_DELAY_US;
        break;
    case ANY_WRITE:
        if (d->var[V_ANY_WRITE] != 0) {
            return CO_ABORT_DEVICE_STATE; /* a write is still in progress (choice) */
        }
        d->var[V_ANY_WRITE] = 1;
        d->var[V_ANY_WRITE_WORD] =
            (int32_t)((uint32_t)data[0] | ((uint32_t)data[1] << 8) | ((uint32_t)data[2] << 16) |
                      ((uint32_t)data[3] << 24));
        d->timer[T_ANY_WRITE] = now + ANY_DELAY_US;
        break;
    case NX_CONTROL:
        if (bypass(d) && len == 2u) {
            bypass_control(d, (uint16_t)(data[0] | (data[1] << 8)), now);
        }
        break;
    case NX_REFERENCE:
        if (bypass(d)) {
            d->var[V_REF_WRITTEN] = 1; /* the target follows once the value is stored */
        }
        break;
    default:
        break;
    }
    return CO_ABORT_NONE;
}

/* --- monitors -------------------------------------------------------------------------------- */

static uint16_t magnitude(int32_t v)
{
    return (uint16_t)(v < 0 ? -v : v);
}

static void publish(co_drive *d)
{
    bool faulted = d->state == CO_CIA402_FAULT || d->state == CO_CIA402_FAULT_REACTION_ACTIVE;
    int32_t hz = d->motor.frequency;
    int32_t span = d->var[V_PARAM_MAX] - d->var[V_PARAM_MIN];
    int32_t above = (int32_t)magnitude(hz) - d->var[V_PARAM_MIN];
    int32_t percent = span > 0 && above > 0 ? (int32_t)((int64_t)above * 10000 / span) : 0;
    /* nx_status_word, Tab. 7-4 (bits 7, 8, 10 as printed: 1 = not ready / not active) */
    uint16_t sw = 0x0500u;
    if (!faulted && d->mains_on) {
        sw |= 0x0001u;
    }
    if (d->output) {
        sw |= 0x0002u;
    }
    if (d->motor.actual < 0 || (d->motor.actual == 0 && d->setpoint < 0)) {
        sw |= 0x0004u;
    }
    if (faulted) {
        sw |= 0x0008u;
    }
    if (d->warning) {
        sw |= 0x0010u;
    }
    if (d->output && d->ramp.demand == d->setpoint) {
        sw |= 0x0020u;
    }
    if (d->output && d->motor.actual == 0) {
        sw |= 0x0040u;
    }
    if (!d->output) {
        sw |= 0x0080u; /* flux not ready while stopped (choice) */
    }
    (void)co_od_set_i16(&d->node, NX_STATUS, 0, (int16_t)sw);
    (void)co_od_set_i16(&d->node, NX_SPEED, 0, (int16_t)percent);
    /* process data out, Standard application (App. C), magnitudes */
    (void)co_od_set_i16(&d->node, NX_OUT1, 0, (int16_t)magnitude(hz));
    (void)co_od_set_i16(&d->node, NX_OUT1 + 1u, 0, (int16_t)magnitude(d->motor.rpm));
    (void)co_od_set_i16(&d->node, NX_OUT1 + 5u, 0,
                        (int16_t)(magnitude(hz) * 4000 / MAX_FREQ)); /* 400.0 V at 50 Hz */
    /* the load (B10): current in 0.01 A (0x2003) and 0.1 A (out 3), torque and power in 0.1 %
       (0x2004, out 4, out 5); power = torque x speed, rated at 50 Hz */
    uint32_t centiamps = (RATED_CURRENT * (uint32_t)d->motor.current + 5000u) / 10000u;
    uint32_t torque = ((uint32_t)d->motor.torque + 5u) / 10u;
    uint32_t power = torque * magnitude(hz) / MAX_FREQ;
    (void)co_od_set_u16(&d->node, NX_CURRENT, 0, (uint16_t)centiamps);
    (void)co_od_set_u16(&d->node, NX_TORQUE, 0, (uint16_t)torque);
    (void)co_od_set_i16(&d->node, NX_OUT1 + 2u, 0, (int16_t)((centiamps + 5u) / 10u));
    (void)co_od_set_i16(&d->node, NX_OUT1 + 3u, 0, (int16_t)torque);
    (void)co_od_set_i16(&d->node, NX_OUT1 + 4u, 0, (int16_t)power);
}

/* --- faults and the bus ---------------------------------------------------------------------- */

static void tripped(co_drive *d, uint16_t trip_code)
{
    (void)co_od_set_i16(&d->node, NX_FAULT, 0, (int16_t)trip_code);
    d->var[V_NEED_EDGE] = 1;
}

static void fault_reset(co_drive *d)
{
    (void)co_od_set_i16(&d->node, NX_FAULT, 0, 0);
}

static void comm(co_drive *d, co_comm_event event, uint32_t detail)
{
    (void)detail;
    uint64_t now = d->node.now;
    switch (event) {
    case CO_COMM_LIFE_GUARD_LOST:
        switch (d->setting[S_RESPONSE]) {
        case 1:
            co_drive_loss_react(d, CO_DRIVE_LOSS_WARNING, 0, now);
            break;
        case 2:
        case 3: {
            const co_drive_trip *row = co_drive_find_trip(d->desc, FIELDBUS_FAULT);
            /* Fieldbus Fault: a fault reset clears it at any time (B2.6) */
            co_drive_trip_codes(d, row->emcy_code, row->emcy_code, row->error_register, FIELDBUS_FAULT,
                                false, d->setting[S_RESPONSE] == 2 ? CO_DRIVE_STOP_RAMP
                                                          : CO_DRIVE_STOP_COAST,
                                now);
            break;
        }
        default:
            break;
        }
        break;
    case CO_COMM_LIFE_GUARD_RESUMED:
        if (d->setting[S_RESPONSE] == 1) {
            co_drive_loss_clear(d, now);
        }
        break;
    case CO_COMM_RX_OVERRUN: /* board-level: reported, no trip (faults.csv) */
        (void)co_drive_report_error(d, 0x8110u, now);
        co_drive_clear_error(d, 0x8110u);
        break;
    case CO_COMM_ERROR_PASSIVE:
        (void)co_drive_report_error(d, 0x8120u, now);
        break;
    case CO_COMM_BUS_RECOVERED:
        co_drive_clear_error(d, 0x8120u);
        break;
    default:
        break;
    }
}

static uint64_t process(co_drive *d, uint64_t now)
{
    uint64_t next = CO_TIME_NEVER;
    if (d->var[V_REF_WRITTEN] != 0) {
        d->var[V_REF_WRITTEN] = 0;
        co_drive_set_target(d, bypass_target(d), now);
    }
    if (d->var[V_ANY_READ] != 0) {
        if (now >= d->timer[T_ANY_READ]) {
            uint16_t id = (uint16_t)(d->var[V_ANY_READ] - 1);
            uint16_t value = 0;
            uint32_t result = any_read(d, id, &value) ? ((uint32_t)id << 16) | value : 0xFFFF0000u;
            (void)co_od_set_u32(&d->node, ANY_READ_VALUE, 0, result);
            d->var[V_ANY_READ] = 0;
        } else {
            next = d->timer[T_ANY_READ];
        }
    }
    if (d->var[V_ANY_WRITE] != 0) {
        if (now >= d->timer[T_ANY_WRITE]) {
            uint32_t word = (uint32_t)d->var[V_ANY_WRITE_WORD];
            bool ok = any_write(d, (uint16_t)(word >> 16), (uint16_t)word);
            (void)co_od_set_u32(&d->node, ANY_WRITE, 0, ok ? 0u : 0xFFFF0000u);
            d->var[V_ANY_WRITE] = 0;
        } else if (d->timer[T_ANY_WRITE] < next) {
            next = d->timer[T_ANY_WRITE];
        }
    }
    if (bypass(d) && d->state == CO_CIA402_SWITCHED_ON && !d->output) {
        bypass_stopped_ready(d, now);
    }
    return next;
}

static bool remote(const co_drive *d)
{
    return fieldbus(d);
}

static void reset(co_drive *d, bool whole_node)
{
    if (whole_node) {
        /* board initialisation: the keypad parameters are read now (choice 20) */
        d->var[V_MODE] = d->setting[S_MODE];
        d->var[V_NX_CW] = 0;
        d->var[V_NEED_EDGE] = 0;
        d->var[V_ANY_READ] = 0;
        d->var[V_ANY_WRITE] = 0;
        if (d->var[V_POWERED] == 0) {
            d->var[V_POWERED] = 1; /* the NX application's parameters, B9.5 defaults */
            d->var[V_PARAM_MIN] = 0;
            d->var[V_PARAM_MAX] = MAX_FREQ;
            d->var[V_PARAM_ACC] = 10;
            d->var[V_PARAM_DEC] = 10;
        }
    }
    d->profile_off = bypass(d);
    apply_mode(d);
    if (bypass(d)) {
        bypass_stopped_ready(d, d->node.now);
    }
}

static void init(co_drive *d)
{
    const co_od_hook any = {ANY_READ_ID, ANY_WRITE, NULL, board_written, NULL, NULL, d};
    const co_od_hook nx = {NX_CONTROL, NX_REFERENCE, NULL, board_written, NULL, NULL, d};
    (void)co_node_add_hook(&d->node, &any);
    (void)co_node_add_hook(&d->node, &nx);
}

static void configure(const co_drive_desc *desc, co_node_config *cfg)
{
    (void)desc;
    /* Fieldbus Fault carries the NX number in its EMCY and 0x1003 entry: the drive raises it */
    cfg->options |= CO_NODE_COMM_EMCY_BY_APP;
}

const co_drive_desc co_drive_desc_vacon_optc6 = {
    .id = "vacon-optc6",
    .title = "VACON NX with OPTC6 CANopen option board (Drive Profile vl, Bypass modes)",
    .od = &co_od_vacon_optc6,
    .trips = co_drive_trips_vacon_optc6,
    .trip_count = DRIVE_TRIP_COUNT_VACON_OPTC6,
    .profile = CO_DRIVE_PROFILE_CIA402,
    .emcy_info = CO_DRIVE_EMCY_TRIP_LE,
    .cia402_flags = 0,
    .flags = CO_DRIVE_RFG_IGNORED | CO_DRIVE_ZERO_MAX_IS_MAX_SPEED |
             CO_DRIVE_ZERO_SLOPE_IS_DRIVE_RAMP | CO_DRIVE_HISTORY_TRIP_CODE,
    .voltage_states = CO_CIA402_STATE_BIT(CO_CIA402_READY_TO_SWITCH_ON) |
                      CO_CIA402_STATE_BIT(CO_CIA402_SWITCHED_ON) |
                      CO_CIA402_STATE_BIT(CO_CIA402_OPERATION_ENABLED) |
                      CO_CIA402_STATE_BIT(CO_CIA402_QUICK_STOP_ACTIVE) |
                      CO_CIA402_STATE_BIT(CO_CIA402_FAULT_REACTION_ACTIVE),
    .velocity_unit = CO_MOTOR_UNIT_RPM,
    .poles = 4,
    .max_speed = MAX_SPEED,
    .ramp_time_unit_us = 1000000u,
    .drive_ramp_us = 1000000u,  /* the drive's own ramp: 1.0 s from 0 to max (choice 32) */
    .coast_us = 5000000u,       /* coasting: 5 s from max speed (B7.9 choice) */
    .quick_stop_option = 1,     /* normal deceleration ramp, then Switch on disabled (B7.7) */
    .shutdown_option = 0,
    .disable_operation_option = 1,
    .halt_option = 1,
    .fault_reaction_option = 0,
    .other_trips_emcy = 0x1000u,
    .other_trips_register = 0x01u,
    .settings = vacon_settings,
    .setting_count = 3,
    .configure = configure,
    .init = init,
    .reset = reset,
    .comm = comm,
    .process = process,
    .publish = publish,
    .remote = remote,
    .command_from_bus = remote,
    .tripped = tripped,
    .fault_reset = fault_reset,
};
