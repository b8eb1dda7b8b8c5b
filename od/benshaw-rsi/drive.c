/* Benshaw RSi 'S' & 'SW' with the CANopen module PC-100094-00: the drive's description and its
 * own C. Authority: Benshaw "CANopen for RSi 'S' & 'SW' Series Variable Frequency Drive, Instruction Manual" (890049-12-00) ("§" below); Bn/Cn are the items
 * of od/benshaw-rsi/NOTES.md written from it.
 *
 * Departures from plain CiA 402:
 * - the controlword is level-triggered: evaluated on every write and again at each processing
 *   cycle while it keeps causing transitions, one transition per evaluation (B9), so a held
 *   0x000F in Ready to switch on gives 3, then 4 one tick later; bit 7 = 1 blocks the others;
 * - transition 5 does not stop the motor: 'stop command is not accepted' (§8.1.1 transition 5,
 *   C18) - the output frequency is kept until 4, 6, 10 or a trip;
 * - shutdown (6, 8) and disable voltage (9, 10, 12) coast ('free run stop', §8.1.1);
 * - no 0x605A: quick stop decelerates on 0x604A and stays in Quick stop active; Enable operation
 *   there is transition 16 (§8.1.1 lists it; C30);
 * - delta speed of 0x6048/0x6049/0x604A is fixed at the max speed, 1800 rpm (§8.1.2.7 'it fixes
 *   Delta Speed at Max Speed'); delta time in 0.1 s (C5);
 * - controlword bits 4-6: bit 4 = 1 takes bits 5 (0 holds the output) and 6 (0: target 0), bit 4
 *   = 0 keeps the previous ones (§8.1.2.2 second table, B10); halt (bit 8) 'Not used';
 * - target clipped to +-1800 rpm with statusword bit 11 (B9), 6043/6044 show the coasting motor;
 * - 0x603F shows the trip code of the 0x603F table, EMCY/0x1003 the §7.3 code (0xFF01/0xFF02 for
 *   Ethermal, C16); 0x1001 holds only the class bit (C29); 0x82xx are reported, never trips (C17);
 * - bit 9 remote while dr.06 = 4 (Cmd Source FieldBus); the motor runs from the bus only then,
 *   and 0x6042 is the reference only while dr.07 = 8 (B10.5);
 * - Lost Command (§9.4): NMT state other than Operational for Pr.13 while dr.06 = 4 or dr.07 = 8
 *   -> Pr.12 reaction (C20, C22, B13); no EMCY for a life-guard error (B2.2);
 * - CM.11 'Profile' chooses the PDO set (PDO1 or PDO3, modes.csv), applied by CM.94 Comm Update
 *   together with CM.07 node-ID (B14); with CM.11 = 1 0x6040-0x6049 do not exist (§9.2.7, C6);
 *   0x3010-0x3013 carry the inverter parameters whose addresses are CM.51-54 (in) / CM.31-34
 *   (out) (C15);
 * - inverter parameters survive a reset node (B1.5). */
#include "canopen/drive.h"
#include "canopen/nmt.h"
#include "drive_trips_benshaw_rsi.h"
#include "od_benshaw_rsi.h"

#define DRV 0x4010u      /* DRV group: sub = code + 1 */
#define DRV_ACC 3u       /* ACC.Time-1 = 0x6048:02 (C23) */
#define DRV_CMD_SRC 7u   /* dr.06: 4 = FieldBus */
#define DRV_FREQ_SRC 8u  /* dr.07: 8 = Fieldbus */
#define DRV_CURRENT 9u   /* output current, 0.1 A */
#define COM 0x4016u
#define PRT 0x401Au
#define PR_TRIP_DEC 7u   /* Pr.07, 0.1 s */
#define PR_LOST_MODE 12u /* Pr.12 */
#define PR_LOST_TIME 13u /* Pr.13, 0.1 s */
#define PR_LOST_FREQ 14u /* Pr.14, 0.01 Hz */
#define PDO3_WORDS 0x3010u

/* co_drive.var */
#define V_PROFILE 0u     /* CM.11 in effect (applied by Comm Update) */
#define V_LOST 1u        /* Lost Command reaction applied */
#define V_UPDATE 2u      /* Comm Update written: apply at the next process */
#define V_POWERED 3u     /* the power-on reset has been seen */
#define V_REARM 12u      /* dr.06/dr.07/Pr.12 written: re-check Lost Command arming */
#define V_PARAM0 4u      /* var[4..11]: inverter common-area words addressed by CM.3x/CM.5x */
#define T_LOST 0u        /* when Lost Command is reached */

#define MAX_SPEED 1800   /* 60.00 Hz at 4 poles (NOTES 'Model values') */
#define RATED_CURRENT 50 /* the motor's rated current, 0.1 A (NOTES 'Model values') */

static const co_drive_range benshaw_keep[] = {
    {0x3010u, 0x3013u}, {0x4010u, 0x401Du}, {0x6048u, 0x604Au}};
static const uint16_t benshaw_report_only[] = {0x8200u, 0x8210u, 0x8220u};

static uint16_t sub16(const co_drive *d, uint16_t index, uint8_t sub)
{
    return co_od_get_u16(&d->node, index, sub);
}

static bool remote(const co_drive *d)
{
    return sub16(d, DRV, DRV_CMD_SRC) == 4u;
}

static bool reference_from_bus(const co_drive *d)
{
    return sub16(d, DRV, DRV_FREQ_SRC) == 8u;
}

static bool lost_command_armed(const co_drive *d)
{
    return (remote(d) || reference_from_bus(d)) && sub16(d, PRT, PR_LOST_MODE) != 0u;
}

/* --- Lost Command (§9.4) ------------------------------------------------------------------ */

static void lost_command(co_drive *d, uint64_t now)
{
    d->var[V_LOST] = 1;
    bool running = d->state == CO_CIA402_OPERATION_ENABLED && d->motor.actual != 0;
    switch (sub16(d, PRT, PR_LOST_MODE)) {
    case 1: /* Free-Run: trip, coast */
        co_drive_loss_react(d, CO_DRIVE_LOSS_TRIP, 0xFF0A, now);
        break;
    case 2: { /* Dec: trip; Fault reaction active while decelerating on Pr.07 */
        uint64_t t = (uint64_t)sub16(d, PRT, PR_TRIP_DEC) * 100000u;
        d->custom_slope.delta_speed = MAX_SPEED;
        d->custom_slope.delta_time_us = t;
        const co_drive_trip *row = co_drive_find_trip(d->desc, 0xFF0A);
        co_drive_trip_codes(d, 0xFF0A, 0xFF0A, row != NULL ? row->error_register : 0x80u, 0xFF0A, true,
                            CO_DRIVE_STOP_CUSTOM, now);
        d->loss_tripped = true;
        d->loss_active = true;
        break;
    }
    case 3: /* Hold Input: keep the last command, warning */
        if (running) {
            co_drive_loss_react(d, CO_DRIVE_LOSS_WARNING, 0, now);
        }
        break;
    case 4: /* Hold Output */
        if (running) {
            co_drive_loss_react(d, CO_DRIVE_LOSS_HOLD_OUTPUT, 0, now);
        }
        break;
    case 5: /* Lost Preset: Pr.14 (0.01 Hz) in the present direction */
        if (running) {
            int32_t rpm = co_motor_centihz_to_rpm(sub16(d, PRT, PR_LOST_FREQ), 4, false);
            co_drive_loss_react(d, CO_DRIVE_LOSS_PRESET, rpm, now);
        }
        break;
    default:
        break;
    }
}

static void arm_lost_command(co_drive *d)
{
    if (d->node.nmt_state != CO_NMT_OPERATIONAL && lost_command_armed(d)) {
        if (d->timer[T_LOST] == CO_TIME_NEVER && d->var[V_LOST] == 0) {
            d->timer[T_LOST] = d->node.now + (uint64_t)sub16(d, PRT, PR_LOST_TIME) * 100000u;
        }
    } else {
        d->timer[T_LOST] = CO_TIME_NEVER;
        if (d->var[V_LOST] != 0) {
            d->var[V_LOST] = 0;
            co_drive_loss_clear(d, d->node.now); /* warning ends; a Lost Command trip may be reset */
        }
    }
}

static void nmt_changed(co_drive *d, co_nmt_state from, co_nmt_state to)
{
    (void)from;
    (void)to;
    arm_lost_command(d);
}

/* --- the PDO set of CM.11 (modes.csv) ----------------------------------------------------- */

static void apply_profile(co_drive *d)
{
    uint32_t id = d->node.node_id;
    bool pdo3 = d->var[V_PROFILE] == 1;
    (void)co_od_set_u32(&d->node, 0x1400u, 1, (pdo3 ? 0x80000200u : 0x200u) + id);
    (void)co_od_set_u32(&d->node, 0x1800u, 1, (pdo3 ? 0x80000180u : 0x180u) + id);
    (void)co_od_set_u32(&d->node, 0x1402u, 1, (pdo3 ? 0x400u : 0x80000400u) + id);
    (void)co_od_set_u32(&d->node, 0x1802u, 1, (pdo3 ? 0x380u : 0x80000380u) + id);
    co_pdo_configure(&d->node, d->node.now);
}

/* The value of an inverter common-area address (C15, B8.4: 0x000A output frequency in 0.01 Hz,
 * 0x000E operation status, 0x000F trip information; other addresses are plain storage). */
static uint16_t inverter_word(const co_drive *d, uint16_t address)
{
    switch (address) {
    case 0x0000u: return 0;
    case 0x000Au: {
        int32_t hz = d->motor.frequency < 0 ? -d->motor.frequency : d->motor.frequency;
        return (uint16_t)hz;
    }
    case 0x000Fu: return d->fault_trip;
    default: break;
    }
    for (uint32_t n = 0; n < 4u; n++) {
        if (sub16(d, COM, (uint8_t)(51u + n)) == address) {
            return (uint16_t)d->var[V_PARAM0 + n];
        }
    }
    return 0;
}

static void publish(co_drive *d)
{
    for (uint32_t n = 0; n < 4u; n++) {
        uint16_t address = sub16(d, COM, (uint8_t)(31u + n));
        (void)co_od_set_u16(&d->node, (uint16_t)(PDO3_WORDS + n), 0, inverter_word(d, address));
    }
    /* Output Current (DRV code 8), 0.1 A: the motor's current under its load (B15) */
    (void)co_od_set_u16(&d->node, DRV, DRV_CURRENT,
                        (uint16_t)((RATED_CURRENT * (uint32_t)d->motor.current + 5000u) / 10000u));
}

/* --- objects -------------------------------------------------------------------------------- */

static bool profile_object_hidden(const co_drive *d, uint16_t index)
{
    return d->var[V_PROFILE] == 1 && index >= 0x6040u && index <= 0x6049u;
}

static co_abort profile_read(co_drive *d, co_od_ref ref)
{
    return profile_object_hidden(d, ref.entry->index) ? CO_ABORT_NO_OBJECT : CO_ABORT_NONE;
}

static co_abort profile_written(co_drive *d, co_od_ref ref, const uint8_t *data, uint32_t len,
                                co_od_origin origin)
{
    (void)origin;
    if (profile_object_hidden(d, ref.entry->index)) {
        return CO_ABORT_NO_OBJECT;
    }
    if (ref.entry->index == 0x6048u && ref.sub->subindex == 2u && len == 2u) {
        /* ACC.Time-1 and 0x6048:02 are one value (C23) */
        co_od_ref acc;
        if (co_od_locate(d->node.od, DRV, DRV_ACC, &acc) == CO_ABORT_NONE) {
            uint8_t *p = co_od_value_ptr(&d->node, acc);
            p[0] = data[0];
            p[1] = data[1];
        }
    }
    return CO_ABORT_NONE;
}

/* CM aliases (C10): CM.61/62/63/67 are CM.07/10/11/94. */
static uint8_t alias_of(uint8_t sub)
{
    switch (sub) {
    case 0x07u: return 0x3Du;
    case 0x3Du: return 0x07u;
    case 0x0Au: return 0x3Eu;
    case 0x3Eu: return 0x0Au;
    case 0x0Bu: return 0x3Fu;
    case 0x3Fu: return 0x0Bu;
    case 0x5Eu: return 0x43u;
    case 0x43u: return 0x5Eu;
    default: return 0;
    }
}

static co_abort keypad_written(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                               uint32_t len, co_od_origin origin)
{
    (void)node;
    (void)origin;
    co_drive *d = ctx;
    co_drive_wake(d); /* its process may read what this sets */
    uint16_t index = ref.entry->index;
    uint8_t sub = ref.sub->subindex;
    uint16_t value = len >= 2u ? (uint16_t)(data[0] | (data[1] << 8)) : 0u;
    if (index == DRV && sub == DRV_FREQ_SRC && (value == 3u || value == 7u || value >= 9u) &&
        value <= 11u) {
        return CO_ABORT_VALUE_RANGE; /* reserved Freq Ref Src values (B10.7) */
    }
    if (index == DRV && sub == DRV_ACC) {
        (void)co_od_set_u16(&d->node, 0x6048u, 2, value);
    }
    if (index == COM) {
        uint8_t other = alias_of(sub);
        if (other != 0u) {
            (void)co_od_set_u16(&d->node, COM, other, value);
        }
        if ((sub == 0x5Eu || sub == 0x43u) && value == 1u) {
            d->var[V_UPDATE] = 1; /* after the SDO answer, with the old COB-IDs (B14.3) */
        }
    }
    co_drive_touch(d); /* dr.06/dr.07 change bit 9 and the motor's sources */
    d->var[V_REARM] = 1; /* Lost Command arming, once the value is stored */
    return CO_ABORT_NONE;
}

static co_abort words_written(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                              uint32_t len, co_od_origin origin)
{
    (void)node;
    (void)origin;
    co_drive *d = ctx;
    co_drive_wake(d); /* its process may read what this sets */
    uint32_t n = ref.entry->index - PDO3_WORDS;
    if (len == 2u && n < 4u) {
        d->var[V_PARAM0 + n] = (int32_t)(uint16_t)(data[0] | (data[1] << 8));
    }
    return CO_ABORT_NONE;
}

static uint64_t process(co_drive *d, uint64_t now)
{
    if (d->var[V_REARM] != 0) {
        d->var[V_REARM] = 0;
        arm_lost_command(d);
    }
    if (d->var[V_UPDATE] != 0) {
        d->var[V_UPDATE] = 0;
        uint16_t id = sub16(d, COM, 0x07u);
        d->var[V_PROFILE] = sub16(d, COM, 0x0Bu);
        (void)co_od_set_u16(&d->node, COM, 0x5Eu, 0);
        (void)co_od_set_u16(&d->node, COM, 0x43u, 0);
        if (id >= 1u && id <= 127u) {
            d->node.node_id = (uint8_t)id; /* the module takes the new ID (B14.3) */
        }
        co_nmt_reset_communication(&d->node, now);
    }
    if (d->timer[T_LOST] != CO_TIME_NEVER) {
        if (now >= d->timer[T_LOST]) {
            d->timer[T_LOST] = CO_TIME_NEVER;
            lost_command(d, now);
        } else {
            return d->timer[T_LOST];
        }
    }
    return CO_TIME_NEVER;
}

static void reset(co_drive *d, bool whole_node)
{
    if (d->var[V_POWERED] == 0) {
        /* power-on: the start-up node-ID is both CM.07 and the module's (B14.5) */
        d->var[V_POWERED] = 1;
        (void)co_od_set_u16(&d->node, COM, 0x07u, d->node.node_id);
        (void)co_od_set_u16(&d->node, COM, 0x3Du, d->node.node_id);
        d->var[V_PROFILE] = sub16(d, COM, 0x0Bu);
    }
    (void)whole_node;
    apply_profile(d); /* the active CM.11's PDO set at every reset communication (B1.4) */
    d->var[V_LOST] = 0;
    d->timer[T_LOST] = CO_TIME_NEVER;
    arm_lost_command(d);
}

static void init(co_drive *d)
{
    const co_od_hook keypad = {DRV, PRT, NULL, keypad_written, NULL, NULL, d};
    const co_od_hook words = {PDO3_WORDS, PDO3_WORDS + 3u, NULL, words_written, NULL, NULL, d};
    (void)co_node_add_hook(&d->node, &keypad);
    (void)co_node_add_hook(&d->node, &words);
}

static void configure(const co_drive_desc *desc, co_node_config *cfg)
{
    (void)desc;
    cfg->options |= CO_NODE_ERR_REG_NO_GENERIC | /* 0x1001 = the class bit only (C29) */
                    CO_NODE_COMM_EMCY_BY_APP;    /* no EMCY for a guard error (B2.2) */
    cfg->pdo.flags |= CO_PDO_RPDO_LONG_EMCY;     /* 0x8210 short / 0x8220 long (B6.6) */
}

const co_drive_desc co_drive_desc_benshaw_rsi = {
    .id = "benshaw-rsi",
    .title = "Benshaw RSi S/SW with CANopen module PC-100094-00 (CiA 402 vl)",
    .od = &co_od_benshaw_rsi,
    .trips = co_drive_trips_benshaw_rsi,
    .trip_count = DRIVE_TRIP_COUNT_BENSHAW_RSI,
    .profile = CO_DRIVE_PROFILE_CIA402,
    .emcy_info = CO_DRIVE_EMCY_ZERO,
    .cia402_flags = CO_CIA402_ALWAYS_16,
    .flags = CO_DRIVE_603F_TRIP_CODE | CO_DRIVE_RFG_LATCHED | CO_DRIVE_HALT_IGNORED |
             CO_DRIVE_LEVEL_TRIGGERED | CO_DRIVE_DEMAND_SHOWS_MOTOR,
    .voltage_states = CO_CIA402_STATE_BIT(CO_CIA402_READY_TO_SWITCH_ON) |
                      CO_CIA402_STATE_BIT(CO_CIA402_SWITCHED_ON) |
                      CO_CIA402_STATE_BIT(CO_CIA402_OPERATION_ENABLED) |
                      CO_CIA402_STATE_BIT(CO_CIA402_QUICK_STOP_ACTIVE),
    .velocity_unit = CO_MOTOR_UNIT_RPM,
    .poles = 4,
    .max_speed = MAX_SPEED,
    .ramp_time_unit_us = 100000u,
    .coast_us = 5000000u, /* free run from max speed (a simulation constant) */
    .quick_stop_option = 6,
    .shutdown_option = 0,
    .disable_operation_option = CO_DRIVE_OPTION_HOLD,
    .halt_option = 1,
    .fault_reaction_option = 0,
    .report_only = benshaw_report_only,
    .report_only_count = 3,
    .keep = benshaw_keep,
    .keep_count = 3,
    .configure = configure,
    .init = init,
    .reset = reset,
    .nmt_changed = nmt_changed,
    .write = profile_written,
    .refresh = profile_read,
    .process = process,
    .publish = publish,
    .remote = remote,
    .command_from_bus = remote,
    .reference_from_bus = reference_from_bus,
};
