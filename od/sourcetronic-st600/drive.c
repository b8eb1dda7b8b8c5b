/* Sourcetronic ST600 with the CANopen communication card EC-TX105: the drive's description and
 * its own C. Authority: Sourcetronic "Installation and Setup Guide - PROFIBUS/CANopen communication extension cards" ("§" below); Bn/choice n
 * are the items of od/sourcetronic-st600/NOTES.md written from it.
 *
 * The card has no CiA 402 (0x1000 = 0, no 0x6000 objects). The drive is run with command codes
 * in its control word CW 0x2101 (1 forward, 2 reverse, 3/4 jog, 5 stop on the ramp, 6 coast,
 * 7 fault reset, 8 stop jogging; B10) and reports a state code in SW 0x2001 (1 forward, 2
 * reverse, 3 stopped, 4 faulty, 5 POFF). References and monitors are 16-bit words whose meaning
 * drive parameters choose (P15.02-P15.23); speeds are frequencies in 0.01 Hz. The commands only
 * act with P00.01 = 2 and P00.02 = 1 (§3.5.3); the set frequency comes from the bus with
 * P00.06 = 9. The CiA 402 state machine of the runtime is used inside, unseen: stopped = Ready
 * to switch on, running = Operation enabled, stopping = Switched on on the ramp.
 *
 * Also here: the PDO1 parameter channel (request/address/data in RPDO1, response in TPDO1,
 * §3.5.2), the P15.26 communication timeout (trip 31 E-CAN), the fault log P07.27-P07.32, the
 * drive parameter image 0x4000-0x5FFF that the SDO server does not show (B15), and the card's
 * own CANopen options: TPDO 'disabled time' in ms with a 50 ms floor, the first guarding answer
 * with toggle 1, 0x1001 with one class bit (choices 1, 13, 14). */
#include "canopen/drive.h"
#include "drive_trips_sourcetronic_st600.h"
#include "od_sourcetronic_st600.h"

#define RESPONSE 0x2000u /* subs 0-2: PDO1 response; 3-13 returned values 1-11 */
#define SW 0x2001u
#define REQUEST 0x2100u  /* subs 0-2: PDO1 request; 3-13 settings 1-11 */
#define CW 0x2101u
#define PARAMS 0x4000u   /* Pgg.nn -> 0x4000 + (gg << 8 | nn) */
#define P00_01 0x4001u   /* channel of running commands: 2 communication */
#define P00_02 0x4002u   /* communication channel: 1 PROFIBUS/CANopen/DeviceNet */
#define P00_06 0x4006u   /* frequency A: 9 from the bus */
#define P07_27 0x471Bu   /* type of current fault; P07.28-P07.32 the five before */
#define P08_31 0x481Fu   /* motor 1/2 switching channel */
#define P15_02 0x4F02u   /* function of setting 1 (P15.02-P15.12) */
#define P15_13 0x4F0Du   /* function of returned value 1 (P15.13-P15.23) */
#define P15_26 0x4F1Au   /* CANopen communication timeout, 0.1 s, 0 off */
#define P19_00 0x5300u   /* state of card slot 1 */

#define FMAX 5000        /* 50.00 Hz (choice 34) */
#define JOG 500          /* 5.00 Hz */
#define RATED_CURRENT 50 /* the motor's rated current, 0.1 A (model value, B17) */
#define E_CAN 0x1Fu      /* fault 31: CANopen communication fault */

/* co_drive.var */
#define V_SETFREQ 0u     /* set frequency from setting function 1, 0.01 Hz */
#define V_DIR 1u         /* +1 forward / -1 reverse */
#define V_JOG 2u         /* jogging */
#define V_CW 3u          /* last control word */
#define V_GROUP 4u       /* active motor group */
#define V_ARMED 5u       /* communication timeout armed by an RPDO */
#define V_ANSWER 6u      /* bit n: TPDO n answers the RPDO n just applied */
#define V_RESPONSE_AT 7u /* RESPONSE's position among the dictionary's entries, -1 without it */
#define V_FUNCTION_AT 8u /* P15.13's, -1 without it (init: publish looks nothing up) */
#define T_TIMEOUT 0u

static bool commands_from_bus(const co_drive *d)
{
    return co_od_get_u16(&d->node, P00_01, 0) == 2u && co_od_get_u16(&d->node, P00_02, 0) == 1u;
}

static int32_t set_frequency(const co_drive *d)
{
    return co_od_get_u16(&d->node, P00_06, 0) == 9u ? d->var[V_SETFREQ] : 0;
}

static void update_target(co_drive *d, uint64_t now)
{
    int32_t f = d->var[V_JOG] != 0 ? JOG : set_frequency(d);
    co_drive_set_target(d, d->var[V_DIR] < 0 ? -f : f, now);
}

static bool stopped(const co_drive *d)
{
    return d->state != CO_CIA402_OPERATION_ENABLED && d->state != CO_CIA402_FAULT &&
           d->state != CO_CIA402_FAULT_REACTION_ACTIVE && !d->output;
}

static void run(co_drive *d, int32_t dir, bool jog, uint64_t now)
{
    d->var[V_DIR] = dir;
    d->var[V_JOG] = jog ? 1 : 0;
    update_target(d, now);
    if (d->state == CO_CIA402_SWITCH_ON_DISABLED) {
        co_drive_command(d, CO_CIA402_CMD_SHUTDOWN, now);
    }
    co_drive_command(d, CO_CIA402_CMD_ENABLE_OPERATION, now); /* 3 + 4, or 4 while stopping */
}

/* B10: the command code (bits 0-7) is executed every time a CW is received. */
static void command(co_drive *d, uint16_t cw, uint64_t now)
{
    d->var[V_CW] = cw;
    if (!commands_from_bus(d)) {
        co_drive_touch(d); /* stored; SW bit 15 still echoes it */
        return;
    }
    uint32_t p0831 = co_od_get_u16(&d->node, P08_31, 0);
    if (p0831 % 10u == 2u && (p0831 / 10u != 0u || stopped(d))) {
        d->var[V_GROUP] = (cw >> 9) & 0x3; /* motor group, bits 9-10 */
    }
    bool faulty = d->state == CO_CIA402_FAULT || d->state == CO_CIA402_FAULT_REACTION_ACTIVE;
    uint8_t code = (uint8_t)cw;
    if (faulty) {
        if (code == 7u) {
            (void)co_drive_fault_reset(d, now);
            co_drive_command(d, CO_CIA402_CMD_SHUTDOWN, now);
        }
        return;
    }
    bool jogging = d->var[V_JOG] != 0 && !stopped(d);
    bool running = !stopped(d) && d->state == CO_CIA402_OPERATION_ENABLED;
    switch (code) {
    case 1:
    case 2:
        run(d, code == 1u ? 1 : -1, false, now);
        break;
    case 3:
    case 4:
        if (!running) {
            run(d, code == 3u ? 1 : -1, true, now);
        }
        break;
    case 5: /* stop: slow down, then stopped */
    case 8: /* stop jogging */
        if (running && (code == 5u || jogging)) {
            co_drive_command(d, CO_CIA402_CMD_SWITCH_ON, now);
        }
        break;
    case 6:
        co_drive_command(d, CO_CIA402_CMD_DISABLE_VOLTAGE, now); /* output off at once */
        co_drive_command(d, CO_CIA402_CMD_SHUTDOWN, now);
        break;
    default:
        break; /* 0, 7 outside a fault, 9-255: no command */
    }
}

/* Settings 1-11 (0x2100:03-0D), function P15.(n+1): applied in order; a value outside its range
 * is ignored (§3.5.3). Only function 1, the set frequency, moves the motor; the others stay in
 * their 0x2100 sub-entries. */
static void setting(co_drive *d, uint32_t n, uint16_t value, uint64_t now)
{
    uint16_t function = co_od_get_u16(&d->node, (uint16_t)(P15_02 + n - 1u), 0);
    if (function == 1u && value <= FMAX) {
        d->var[V_SETFREQ] = value;
        update_target(d, now);
    }
}

/* --- the PDO1 parameter channel (§3.5.2, B11) --------------------------------------------------- */

static void parameter_request(co_drive *d, uint16_t code, uint16_t address, uint16_t data)
{
    uint16_t response = 3, error = 0x01, value = 0;
    co_od_ref ref;
    bool known = co_od_locate(d->node.od, (uint16_t)(PARAMS + address), 0, &ref) == CO_ABORT_NONE &&
                 address <= 0x1FFFu;
    bool faulty = d->state == CO_CIA402_FAULT || d->state == CO_CIA402_FAULT_REACTION_ACTIVE;
    switch (code) {
    case 0:
        response = 0;
        error = 0;
        break;
    case 1:
        if (!known) {
            error = 0x02;
        } else {
            response = 1;
            error = 0;
            value = co_od_get_u16(&d->node, (uint16_t)(PARAMS + address), 0);
        }
        break;
    case 2:
        if (!known) {
            error = 0x02;
        } else if ((ref.sub->flags & CO_OD_WRITE) == 0u) {
            error = 0x07; /* read-only */
        } else if (faulty) {
            error = 0x01; /* the slave station is in the faulty state */
        } else {
            uint8_t b[2] = {(uint8_t)data, (uint8_t)(data >> 8)};
            if (co_od_write_ref(&d->node, ref, b, 2, CO_ORIGIN_APP) != CO_ABORT_NONE) {
                error = 0x04; /* an invalid value */
            } else {
                response = 1;
                error = 0;
                value = data;
                co_drive_touch(d);
            }
        }
        break;
    default:
        break; /* 3 and up (4 'RAM and EEPROM' is reserved, choice 29): invalid command */
    }
    (void)co_od_set_u16(&d->node, RESPONSE, 0, response);
    (void)co_od_set_u16(&d->node, RESPONSE, 1, error);
    (void)co_od_set_u16(&d->node, RESPONSE, 2, value);
    (void)co_pdo_tpdo_request(&d->node, 1);
}

/* The RPDO (1-based number) whose mapping ends with this sub-entry, or 0. */
static uint16_t rpdo_ending_with(const co_drive *d, const co_od_sub *sub)
{
    for (uint32_t i = 0; i < d->node.pdo.rpdo_count; i++) {
        const co_rpdo *r = &d->node.pdo.rpdo[i];
        if (r->head.active && r->head.count != 0u && r->map[r->head.count - 1u].sub == sub) {
            return r->head.number;
        }
    }
    return 0;
}

static co_abort process_data_written(co_node *node, void *ctx, co_od_ref ref,
                                     const uint8_t *data, uint32_t len, co_od_origin origin)
{
    co_drive *d = ctx;
    co_drive_wake(d); /* its process may read what this sets */
    uint64_t now = node->now;
    uint16_t index = ref.entry->index;
    uint8_t sub = ref.sub->subindex;
    uint16_t value = len >= 2u ? (uint16_t)(data[0] | (data[1] << 8)) : 0u;
    if (origin == CO_ORIGIN_RPDO) {
        /* P15.26: every RPDO restarts the timeout; the first one arms it (B6) */
        uint16_t tenths = co_od_get_u16(&d->node, P15_26, 0);
        d->var[V_ARMED] = 1;
        d->timer[T_TIMEOUT] = tenths != 0u ? now + (uint64_t)tenths * 100000u : CO_TIME_NEVER;
    }
    if (index == CW) {
        command(d, value, now);
    } else if (index == REQUEST && sub >= 3u && sub <= 13u) {
        setting(d, sub - 2u, value, now);
    } else if (index == REQUEST && sub <= 2u && origin == CO_ORIGIN_RPDO &&
               rpdo_ending_with(d, ref.sub) == 1u) {
        /* the whole request has arrived (subs 0 and 1 are stored already): process it. An SDO
           write only stores (choice 39). */
        parameter_request(d, co_od_get_u16(&d->node, REQUEST, 0),
                          co_od_get_u16(&d->node, REQUEST, 1), value);
        return CO_ABORT_NONE;
    }
    if (origin == CO_ORIGIN_RPDO) {
        /* type 255 without event timer: TPDOn answers each RPDOn (§3.5.1) */
        uint16_t n = rpdo_ending_with(d, ref.sub);
        if (n >= 2u && co_od_get_u8(&d->node, (uint16_t)(0x1800u + n - 1u), 2) == 255u &&
            co_od_get_u16(&d->node, (uint16_t)(0x1800u + n - 1u), 5) == 0u) {
            d->var[V_ANSWER] |= 1 << n; /* after the frame is applied: in process() */
        }
    }
    return CO_ABORT_NONE;
}

/* --- what the drive shows --------------------------------------------------------------------- */

static uint16_t state_code(const co_drive *d)
{
    if (d->state == CO_CIA402_FAULT || d->state == CO_CIA402_FAULT_REACTION_ACTIVE) {
        return 4;
    }
    if (!d->mains_on) {
        return 5;
    }
    if (d->output && (d->state == CO_CIA402_OPERATION_ENABLED || d->ramp.demand != 0)) {
        if (d->ramp.demand != 0) {
            return d->ramp.demand < 0 ? 2u : 1u;
        }
        return d->var[V_DIR] < 0 ? 2u : 1u;
    }
    return 3;
}

static uint16_t status_word(const co_drive *d)
{
    uint16_t sw = state_code(d);
    if (d->mains_on) {
        sw |= 0x0100u; /* bus voltage established */
    }
    sw |= (uint16_t)((d->var[V_GROUP] & 0x3) << 9);
    sw |= (uint16_t)((co_od_get_u16(&d->node, P00_01, 0) & 0x3u) << 13);
    sw |= (uint16_t)(d->var[V_CW] & 0x8000); /* heartbeat reference echoed (choice) */
    return sw;
}

static uint16_t returned_value(const co_drive *d, uint16_t function)
{
    int32_t f = d->motor.frequency < 0 ? -d->motor.frequency : d->motor.frequency;
    int32_t rpm = d->motor.rpm < 0 ? -d->motor.rpm : d->motor.rpm;
    int32_t ramp = d->ramp.demand < 0 ? -d->ramp.demand : d->ramp.demand;
    switch (function) {
    case 1: return (uint16_t)f;                   /* running frequency, 0.01 Hz */
    case 2: return (uint16_t)set_frequency(d);    /* set frequency */
    case 3: return 5400;                          /* bus voltage 540.0 V */
    case 4: return (uint16_t)(f * 380 / FMAX);    /* output voltage, linear V/F */
    case 5: return (uint16_t)((RATED_CURRENT * (uint32_t)d->motor.current + 5000u) / 10000u);
                                                  /* output current, 0.1 A (B17) */
    case 6: return (uint16_t)((d->motor.torque + 5u) / 10u); /* output torque, 0.1 % */
    case 7: return (uint16_t)((d->motor.torque + 5u) / 10u * (uint32_t)f / FMAX);
                                                  /* output power, 0.1 %: torque x speed */
    case 8: return (uint16_t)rpm;                 /* speed */
    case 10: return (uint16_t)ramp;               /* ramp frequency reference */
    case 11: return d->state == CO_CIA402_FAULT || d->state == CO_CIA402_FAULT_REACTION_ACTIVE
                        ? co_od_get_u16(&d->node, P07_27, 0)
                        : 0u;                     /* active fault code */
    case 25: return status_word(d);
    default: return 0;                            /* not simulated: analog inputs, PID, ... */
    }
}

/* P15.13 + n, the function of returned value n + 1. The dictionary's entries are sorted and
 * P15.13-P15.23 follow each other: it is the n-th entry after P15.13's, else it is looked up. */
static uint16_t function_of(const co_drive *d, uint32_t n)
{
    const co_od *od = d->node.od;
    int32_t at = d->var[V_FUNCTION_AT];
    if (at >= 0 && (uint32_t)at + n < od->entry_count) {
        const co_od_entry *e = &od->entries[(uint32_t)at + n];
        const co_od_sub *sub = co_od_entry_subs(e);
        if (e->index == P15_13 + n && sub->subindex == 0u && sub->type == CO_UNSIGNED16) {
            return co_get_le16(d->node.values + co_od_value_offset(e, sub));
        }
    }
    return co_od_get_u16(&d->node, (uint16_t)(P15_13 + n), 0);
}

/* Runs after every event: the response object and P15.13 were found by init, so the 11
 * returned values need no lookup of their own. */
static void publish(co_drive *d)
{
    co_node *node = &d->node;
    (void)co_od_set_u16(node, SW, 0, status_word(d));
    int32_t at = d->var[V_RESPONSE_AT];
    for (uint32_t n = 0; n < 11u; n++) {
        uint8_t b[2];
        co_put_le16(b, returned_value(d, function_of(d, n)));
        if (at >= 0) {
            co_od_ref response = {&node->od->entries[at], NULL};
            response.sub = co_od_find_sub(response.entry, (uint8_t)(n + 3u));
            if (response.sub != NULL) {
                (void)co_od_write_ref(node, response, b, 2, CO_ORIGIN_APP);
            }
        }
    }
}

/* --- faults, timers --------------------------------------------------------------------------- */

static void tripped(co_drive *d, uint16_t trip_code)
{
    /* fault log: P07.32 <- P07.31 ... P07.28 <- P07.27, P07.27 = the new fault (B5) */
    for (uint16_t i = 5; i > 0u; i--) {
        uint16_t older = co_od_get_u16(&d->node, (uint16_t)(P07_27 + i - 1u), 0);
        (void)co_od_set_u16(&d->node, (uint16_t)(P07_27 + i), 0, older);
    }
    (void)co_od_set_u16(&d->node, P07_27, 0, trip_code);
    d->var[V_JOG] = 0;
}

static uint64_t process(co_drive *d, uint64_t now)
{
    int32_t answer = d->var[V_ANSWER];
    if (answer != 0) {
        d->var[V_ANSWER] = 0;
        for (uint16_t n = 2; n <= 4u; n++) {
            if ((answer & (1 << n)) != 0) {
                (void)co_pdo_tpdo_request(&d->node, n);
            }
        }
    }
    if (d->timer[T_TIMEOUT] != CO_TIME_NEVER) {
        if (now < d->timer[T_TIMEOUT]) {
            return d->timer[T_TIMEOUT];
        }
        d->timer[T_TIMEOUT] = CO_TIME_NEVER;
        d->var[V_ARMED] = 0; /* re-armed by the next RPDO */
        const co_drive_trip *row = co_drive_find_trip(d->desc, E_CAN);
        if (row != NULL) { /* 31 E-CAN: EMCY 00 81 10 1F 00 00 00 00 (B6); code 7 resets it */
            co_drive_trip_codes(d, row->emcy_code, row->emcy_code, row->error_register, E_CAN, false,
                                CO_DRIVE_STOP_COAST, now);
        }
    }
    return CO_TIME_NEVER;
}

static void reset(co_drive *d, bool whole_node)
{
    (void)co_od_set_u16(&d->node, P19_00, 0, 9); /* CANopen card in slot 1 (choice 26) */
    d->timer[T_TIMEOUT] = CO_TIME_NEVER;
    d->var[V_ARMED] = 0;
    if (whole_node) {
        d->var[V_CW] = 0;
        d->var[V_JOG] = 0;
        d->var[V_DIR] = 1;
        if (d->state == CO_CIA402_SWITCH_ON_DISABLED) {
            co_drive_command(d, CO_CIA402_CMD_SHUTDOWN, d->node.now); /* 'stopped and ready' */
        }
    }
}

/* The position of index among the dictionary's entries, -1 without it. */
static int32_t entry_at(const co_od *od, uint16_t index)
{
    const co_od_entry *e = co_od_find_entry(od, index);
    return e != NULL ? (int32_t)(e - od->entries) : -1;
}

static void init(co_drive *d)
{
    d->var[V_RESPONSE_AT] = entry_at(d->node.od, RESPONSE);
    d->var[V_FUNCTION_AT] = entry_at(d->node.od, P15_13);
    const co_od_hook process_data = {RESPONSE, CW, NULL, process_data_written, NULL, NULL, d};
    (void)co_node_add_hook(&d->node, &process_data);
}

static void configure(const co_drive_desc *desc, co_node_config *cfg)
{
    (void)desc;
    cfg->options |= CO_NODE_GUARD_TOGGLE_FIRST_SET | /* §3.4.4: first answer 0x85 (choice 13) */
                    CO_NODE_ERR_REG_NO_GENERIC |     /* §3.4.8: register 0x04, no bit 0 */
                    CO_NODE_SDO_HIDDEN_RANGE |       /* the parameter image (B15) */
                    CO_NODE_SDO_UPLOAD_COMM_AS_32;   /* §3.4.9: 0x1801:03 read as 0x43 (choice 2) */
    cfg->sdo_hidden_first = PARAMS;                  /* the card's dictionary ends at 0x2101 */
    cfg->sdo_hidden_last = 0x5FFFu;
    cfg->pdo.tpdo_inhibit_unit_us = 1000u;           /* 'disabled time' in ms (choice 1) */
    cfg->pdo.tpdo_inhibit_min_us = 50000u;           /* < 50 ms acts as 50 ms (§3.5.1) */
    /* RTRs on TPDO CAN-IDs are ignored (B8). Not CO_PDO_TPDO_SEND_ON_START: TPDO1 answers
       requests and its inhibit time would delay the first answer. TPDOs go out with DLC 8
       (§3.5.2.2: the parameter channel's answer `01 00 00 00 01 00 00 00`, NOTES choice 4). */
    cfg->pdo.flags |= CO_PDO_TPDO_NO_RTR | CO_PDO_SYNC_CONSUMER_ONLY | CO_PDO_TPDO_DLC_8 |
                      CO_PDO_INHIBIT_WHILE_VALID | /* §3.4.9 writes it on the active TPDO2 */
                      CO_PDO_EVENT_TIMER_ALONE |  /* §3.5.1: timer 200 -> every 200 ms */
                      CO_PDO_INHIBIT_254_ONLY;    /* §3.5.1: disabled time named for 254 only */
}

const co_drive_desc co_drive_desc_sourcetronic_st600 = {
    .id = "sourcetronic-st600",
    .title = "Sourcetronic ST600 with CANopen card EC-TX105 (own command codes, no CiA 402)",
    .od = &co_od_sourcetronic_st600,
    .trips = co_drive_trips_sourcetronic_st600,
    .trip_count = DRIVE_TRIP_COUNT_SOURCETRONIC_ST600,
    .profile = CO_DRIVE_PROFILE_OWN,
    .emcy_info = CO_DRIVE_EMCY_TRIP_LE, /* bytes 3-7: the P07.27 fault number, LSB first */
    .cia402_flags = 0,
    .flags = 0,
    .voltage_states = 0,
    .velocity_unit = CO_MOTOR_UNIT_CENTI_HZ,
    .poles = 4,
    .max_speed = FMAX,
    .ramp_time_unit_us = 1000000u,
    .drive_ramp_us = 10000000u, /* 0 <-> Fmax in 10.0 s (choice 34) */
    .coast_us = 0,              /* the running frequency is 0 once the output is off */
    .quick_stop_option = 1,
    .shutdown_option = 0,
    .disable_operation_option = 1, /* code 5: decelerating to stop */
    .halt_option = 1,
    .fault_reaction_option = 0,
    .configure = configure,
    .init = init,
    .reset = reset,
    .process = process,
    .publish = publish,
    .tripped = tripped,
};
