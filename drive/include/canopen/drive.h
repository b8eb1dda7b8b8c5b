/* A simulated drive: one co_node with its object dictionary, the CiA 402 state machine
 * (drive/cia402.h), the vl ramp (drive/vl.h) and the motor model (drive/model.h), driven by what arrives on
 * the bus and by the caller's clock. Everything that makes one drive differ from another - its
 * dictionary, trip table, option codes, quirks of the state machine, communication-loss reaction,
 * manufacturer objects - is in its description (co_drive_desc, one per od/<id>/drive.c): the core
 * never names a drive.
 *
 *   co_drive d;
 *   co_node_config cfg = co_node_default_config();
 *   cfg.node_id = 1; cfg.values = block; cfg.driver = my_driver;  // block: desc->od->value_size
 *   co_drive_init(&d, co_drive_registry_find("vf-s15"), &cfg);
 *   co_drive_start(&d, now);                                  // boot-up, Switch on disabled
 *   for (;;) { co_drive_rx(&d, &frame, now); next = co_drive_process(&d, now); }
 *
 * Time: the drive works on the node's clock (microseconds from the caller). While the motor
 * moves, co_drive_process asks to be called every CO_DRIVE_TICK_US on a grid that starts when the
 * movement starts, and at the exact microsecond a ramp ends; an idle drive asks for nothing.
 * Ramps are exact whatever the calls in between (vl.h).
 *
 * Deadline contract (as the core's co_node_process, docs/design.md "Scheduling"): the value
 * co_drive_process returns is the earliest of the node's deadlines and the drive's own (motion
 * tick, end of a ramp, fault reaction by coasting, mains timeout, held-controlword re-evaluation,
 * the description's process). A call before the drive's own deadline, while the motor is settled
 * and nothing has reached the drive since the last call, runs only the node (which has the same
 * rule): the drive's pass would change nothing. Everything that reaches the drive wakes it - a
 * state machine transition, a write or read of its objects that acts, an NMT, reset or
 * communication event, a co_drive_* call that changes it - and the next call makes a full pass.
 * A description's own object hook (co_node_add_hook) that changes what its process reads calls
 * co_drive_wake(). A 0x6042 write while the motor is not running only notes that the reference
 * is the value stored (target_stored): it wakes nothing.
 *
 * Objects the runtime serves when the dictionary has them (all optional): 0x603F error code,
 * 0x6040 controlword, 0x6041 statusword, 0x6042 target, 0x6043 demand, 0x6044 actual,
 * 0x6046 min/max amount (min > max refused 0x06090036), 0x6048/0x6049/0x604A slopes,
 * 0x605A/0x605B/0x605C/0x605D/0x605E option codes (the description's defaults without them),
 * 0x6007 abort connection option code. 0x6060 writes are stored (velocity mode is the only
 * mode; the dictionary's limits and access decide what is accepted), 0x6061 is the dictionary's.
 * It writes what it shows with CO_ORIGIN_APP (so event-driven TPDOs follow) and hears
 * 0x6000-0x67FF writes through one hook. */
#ifndef CANOPEN_DRIVE_H
#define CANOPEN_DRIVE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "canopen/drive/cia402.h"
#include "canopen/drive/model.h"
#include "canopen/node.h"
#include "canopen/drive/vl.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The ramp tick: while the motor moves, 0x6043/0x6044 and the statusword are brought up to date
 * at least this often (1 ms; CANopen drives typically update process data every 1-2 ms). */
#ifndef CO_DRIVE_TICK_US
#define CO_DRIVE_TICK_US 1000u
#endif
#define CO_DRIVE_VARS 16u      /* words a drive description keeps in co_drive.var */
#define CO_DRIVE_TIMERS 4u     /* deadlines a drive description keeps in co_drive.timer */
#define CO_DRIVE_MAX_SETTINGS 8u
/* Bytes of drive parameters a reset node keeps (co_drive_desc.keep). */
#ifndef CO_DRIVE_KEEP_BYTES
#define CO_DRIVE_KEEP_BYTES 512u
#endif

struct co_drive;

/* One row of a drive's trip table (generated from od/<id>/faults.csv). */
typedef struct co_drive_trip {
    uint16_t trip_code;     /* the drive's own code ('trip_code'); 0 with CO_DRIVE_TRIP_NO_CODE */
    uint16_t emcy_code;     /* EMCY error code, 0x1003 entry and (by default) 0x603F */
    uint8_t error_register; /* 0x1001 bits: 1 << error_register_bit */
    uint8_t flags;          /* CO_DRIVE_TRIP_* */
    const char *name;       /* e.g. "OC1" */
    const char *description;
} co_drive_trip;

#define CO_DRIVE_TRIP_NO_CODE 0x01u /* a row without trip code: a communication-layer event */

/* A drive setting that has no object in the dictionary (a keypad-only board parameter, a
 * simulation constant): set by the simulator's command line before drive_start. */
typedef struct co_drive_setting {
    const char *name;
    int32_t def, min, max;
    const char *help;
} co_drive_setting;

/* A range of object indices. */
typedef struct co_drive_range {
    uint16_t first, last;
} co_drive_range;

/* How the drive stops for an option code (0x605A-0x605E) or a reaction. */
typedef enum co_drive_stop {
    CO_DRIVE_STOP_COAST = 0, /* output off at once, the motor coasts ('disable drive function') */
    CO_DRIVE_STOP_RAMP,      /* slow down on the deceleration ramp (0x6049) */
    CO_DRIVE_STOP_QUICK,     /* slow down on the quick stop ramp (0x604A) */
    CO_DRIVE_STOP_HOLD,      /* keep the present output frequency (the ramp is frozen) */
    CO_DRIVE_STOP_CUSTOM     /* slow down on co_drive.custom_slope */
} co_drive_stop;

/* What a quick stop option code does: how it stops and whether the drive then stays in Quick
 * stop active (5-8) or goes on to Switch on disabled (transition 12). */
typedef struct co_drive_quick_stop {
    uint8_t stop; /* co_drive_stop */
    bool stay;
} co_drive_quick_stop;

/* Communication-loss reactions a description applies with co_drive_loss_react(). */
typedef enum co_drive_loss {
    CO_DRIVE_LOSS_NONE = 0,      /* keep running on the last command and reference */
    CO_DRIVE_LOSS_WARNING,       /* keep running; statusword bit 7 until co_drive_loss_clear() */
    CO_DRIVE_LOSS_RAMP_STOP,     /* decelerate on 0x6049, then Switch on disabled */
    CO_DRIVE_LOSS_COAST_STOP,    /* output off, Switch on disabled */
    CO_DRIVE_LOSS_QUICK_STOP,    /* the quick stop command (transition 11, 0x605A) */
    CO_DRIVE_LOSS_DISABLE_VOLTAGE, /* the disable voltage command */
    CO_DRIVE_LOSS_HOLD_OUTPUT,   /* keep the present output frequency; warning */
    CO_DRIVE_LOSS_FREEWHEEL,     /* output off while the loss lasts, state kept; warning */
    CO_DRIVE_LOSS_PRESET,        /* ramp to the given speed (same direction); warning */
    CO_DRIVE_LOSS_TRIP           /* trip with the given EMCY code's row */
} co_drive_loss;

/* co_drive_desc.flags */
#define CO_DRIVE_603F_TRIP_CODE     0x0001u /* 0x603F shows trip_code, not emcy_code */
#define CO_DRIVE_CLEAR_TARGET       0x0002u /* 0x6042 := 0 on entering Operation enabled */
#define CO_DRIVE_RFG_IGNORED        0x0004u /* controlword bits 4-6 ignored: 0x000F runs */
#define CO_DRIVE_RFG_LATCHED        0x0008u /* bits 5/6 taken only while bit 4 = 1 (Benshaw) */
#define CO_DRIVE_HALT_IGNORED       0x0010u /* controlword bit 8 ignored */
#define CO_DRIVE_CW_BIT11_REVERSE   0x0020u /* controlword bit 11 reverses 0x6042 */
#define CO_DRIVE_NO_INTERNAL_LIMIT  0x0040u /* statusword bit 11 never set */
#define CO_DRIVE_LEVEL_TRIGGERED    0x0080u /* the held controlword is evaluated again each tick
                                               while it keeps causing transitions */
#define CO_DRIVE_ZERO_MAX_IS_MAX_SPEED 0x0100u /* 0x6046:02 = 0 means max_speed (not set) */
#define CO_DRIVE_ZERO_SLOPE_IS_DRIVE_RAMP 0x0200u /* 0x6048.. delta 0 means the drive's ramp */
#define CO_DRIVE_DEMAND_SHOWS_MOTOR 0x0400u /* with the output off 0x6043 shows the coasting
                                               motor, not 0 */
#define CO_DRIVE_QUANTISE_HZ        0x0800u /* 6044 = rpm(Hz(6043)) at 0.01 Hz resolution */
#define CO_DRIVE_TRUNCATE_HZ        0x1000u /* rpm <-> Hz conversions truncate */
#define CO_DRIVE_HISTORY_TRIP_CODE  0x2000u /* 0x1003 entries carry the trip code in bits 16-31 */

/* Manufacturer bytes of the drive's EMCY frames (bytes 3-7). */
typedef enum co_drive_emcy_info {
    CO_DRIVE_EMCY_ZERO = 0,  /* five zero bytes (CiA 301) */
    CO_DRIVE_EMCY_TRIP_U8,   /* byte 3 = trip code, 4-7 = 0 */
    CO_DRIVE_EMCY_TRIP_LE    /* bytes 3.. = trip code, little-endian */
} co_drive_emcy_info;

/* Profiles. */
#define CO_DRIVE_PROFILE_CIA402 0u /* controlled through 0x6040/0x6042 */
#define CO_DRIVE_PROFILE_OWN    1u /* no CiA 402: the description's hooks drive the state
                                      machine through co_drive_command() and friends */

/* Option code a description declares for a dictionary without the object. */
#define CO_DRIVE_OPTION_HOLD (-1) /* 0x605C-like: keep the output (Benshaw transition 5) */

/* The description of one simulated drive. Const; any hook may be NULL. */
typedef struct co_drive_desc {
    const char *id;            /* "vf-s15": the od/<id> directory and the OD name */
    const char *title;         /* one line for canopen-drive --list-drives */
    const co_od *od;
    const co_drive_trip *trips;
    uint16_t trip_count;
    uint8_t profile;           /* CO_DRIVE_PROFILE_* */
    uint8_t emcy_info;         /* co_drive_emcy_info */
    uint32_t cia402_flags;     /* CO_CIA402_* departures of the state machine */
    uint32_t flags;            /* CO_DRIVE_* */
    uint8_t voltage_states;    /* states (CO_CIA402_STATE_BIT) with statusword bit 4 while the
                                  mains are on */
    uint8_t velocity_unit;     /* co_motor_unit of 0x6042-0x6044 (or the own profile's values) */
    uint16_t poles;            /* motor poles when poles_of is NULL */
    uint32_t max_speed;        /* the drive's maximum speed (velocity unit): the limit without
                                  0x6046, the delta speed of a slope without sub 1 */
    uint32_t ramp_time_unit_us;/* unit of the slopes' delta time (1 s in CiA 402) */
    uint64_t drive_ramp_us;    /* the drive's own ramp, 0 -> max_speed, where the slope says
                                  'not set' (CO_DRIVE_ZERO_SLOPE_IS_DRIVE_RAMP) */
    uint64_t coast_us;         /* a coasting motor's time from max_speed to 0 (0: at once) */
    uint64_t mains_timeout_us; /* mains lost in Switched on this long -> Switch on disabled */
    /* Option codes used when the dictionary lacks 0x605A/0x605B/0x605C/0x605D/0x605E. */
    int16_t quick_stop_option;
    int16_t shutdown_option;
    int16_t disable_operation_option;
    int16_t halt_option;
    int16_t fault_reaction_option;
    /* EMCY codes of the table that never trip the drive (they are only reported). */
    const uint16_t *report_only;
    uint8_t report_only_count;
    /* Trip codes outside the table: refused when 0, else tripped with this EMCY code and
       0x1001 bits (a catch-all the manual describes, e.g. Vacon 0x1000). */
    uint16_t other_trips_emcy;
    uint8_t other_trips_register;
    /* Objects that live in the inverter, not in the communication board: a reset node (which
       restores the board's defaults) keeps their values, up to CO_DRIVE_KEEP_BYTES. */
    const co_drive_range *keep;
    uint8_t keep_count;
    /* Board settings without an object (co_drive.setting[i]). */
    const co_drive_setting *settings;
    uint8_t setting_count;

    /* The node configuration this drive needs (options, PDO quirks), applied by drive_init. */
    void (*configure)(const struct co_drive_desc *desc, co_node_config *cfg);
    /* After the node is set up: register the drive's own object hooks. */
    void (*init)(struct co_drive *d);
    /* A reset node (whole_node) or reset communication has just restored the defaults. */
    void (*reset)(struct co_drive *d, bool whole_node);
    /* The NMT state changed. */
    void (*nmt_changed)(struct co_drive *d, co_nmt_state from, co_nmt_state to);
    /* A communication event; NULL: 0x6007 if the dictionary has it, else nothing. */
    void (*comm)(struct co_drive *d, co_comm_event event, uint32_t detail);
    /* A write to 0x6000-0x67FF before the runtime handles it: an abort refuses it. */
    co_abort (*write)(struct co_drive *d, co_od_ref ref, const uint8_t *data, uint32_t len,
                      co_od_origin origin);
    /* An SDO read of 0x6000-0x67FF: an abort refuses it (e.g. objects a mode hides). */
    co_abort (*refresh)(struct co_drive *d, co_od_ref ref);
    /* Runs the drive's own timers; returns its next deadline (CO_TIME_NEVER). Called by
       co_drive_process at that deadline and after anything woke the drive (see "Deadline
       contract" above), not at every call. */
    uint64_t (*process)(struct co_drive *d, uint64_t now);
    /* The runtime has just shown the drive's state (0x6041/0x6043/0x6044): the description
       updates its own monitors (only when something may have changed). */
    void (*publish)(struct co_drive *d);
    /* Statusword bit 9: the drive takes its commands from the bus (NULL: always). */
    bool (*remote)(const struct co_drive *d);
    /* The motor may run on bus commands (run command source) / 0x6042 is the reference
       (frequency source). NULL: yes. Without them the state machine still follows the
       controlword but the motor stays at 0. */
    bool (*command_from_bus)(const struct co_drive *d);
    bool (*reference_from_bus)(const struct co_drive *d);
    /* Transition 4 may take place now (NULL: yes). */
    bool (*may_enable)(const struct co_drive *d);
    /* The quick stop option code's action (NULL: CiA 402-2 table). */
    co_drive_quick_stop (*quick_stop)(int16_t option);
    /* The motor's pole count now (NULL: poles). */
    uint16_t (*poles_of)(const struct co_drive *d);
    /* A state machine transition has been made (after its actions). */
    void (*transition)(struct co_drive *d, int transition, co_cia402_state from,
                       co_cia402_state to);
    /* The drive tripped (trip_code: the code injected, 0 for a table row without one) / its
       fault was reset. */
    void (*tripped)(struct co_drive *d, uint16_t trip_code);
    void (*fault_reset)(struct co_drive *d);
} co_drive_desc;

/* Where the motor's speed is going. */
typedef enum co_drive_motion {
    CO_DRIVE_MOTION_OFF = 0, /* output off (the motor may still coast) */
    CO_DRIVE_MOTION_RUN,     /* following the setpoint with 0x6048/0x6049 */
    CO_DRIVE_MOTION_STOP,    /* slowing down to 0, then `then` */
    CO_DRIVE_MOTION_HOLD     /* output frozen */
} co_drive_motion;

/* What happens when a stop reaches standstill. */
typedef enum co_drive_then {
    CO_DRIVE_THEN_STAY = 0,  /* keep the output on at 0 */
    CO_DRIVE_THEN_OFF,       /* output off */
    CO_DRIVE_THEN_DISABLE,   /* Switch on disabled (transition 12 from Quick stop active) */
    CO_DRIVE_THEN_FAULT      /* Fault (transition 14) */
} co_drive_then;

/* What the application (a simulator's log) hears of the drive. Any callback may be NULL. */
typedef struct co_drive_observer {
    /* A state machine transition (0-16; 13 when the drive trips) has been made. */
    void (*state_changed)(struct co_drive *d, void *ctx, int transition, co_cia402_state from,
                          co_cia402_state to);
    void *ctx;
} co_drive_observer;

/* Resolved objects (sub == NULL when the dictionary lacks them). */
typedef struct co_drive_objects {
    co_od_ref error_code, controlword, statusword, target, demand, actual;
    co_od_ref min_amount, max_amount, acc_speed, acc_time, dec_speed, dec_time, qs_speed, qs_time;
    co_od_ref quick_stop_option, shutdown_option, disable_operation_option, halt_option,
        fault_reaction_option, abort_connection, modes, modes_display;
} co_drive_objects;

typedef struct co_drive {
    co_node node;
    const co_drive_desc *desc;
    co_node_events app_events;  /* the application's callbacks, called after the drive's */
    co_drive_observer observer; /* set with co_drive_observe() */
    co_drive_objects obj;
    co_motor_config motor_cfg;

    co_cia402_state state;
    int last_transition;        /* -1 before the first */
    uint16_t controlword;       /* the last controlword received */
    uint16_t previous_cw;       /* the one before it (fault reset edge) */
    uint8_t rfg_latch;          /* CO_DRIVE_RFG_LATCHED: bits 5/6 as latched */
    bool quick_stop_before;     /* statusword bit 5 before the fault */
    bool mains_on;
    bool warning;               /* statusword bit 7 (set by descriptions) */
    bool internal_limit;
    bool target_reached;
    bool reevaluate;            /* CO_DRIVE_LEVEL_TRIGGERED: evaluate the held controlword */
    uint64_t reevaluate_at;     /* ... at this time (the next tick) */
    uint8_t reset_kind;         /* reset announced: 0 none, 1 communication, 2 node */
    bool started;               /* the first reset (power-on) is done */
    bool dirty;                 /* an input changed: recompute the setpoint, slopes, flags */
    bool stale;                 /* what the drive shows changed: publish it */
    bool core_event;            /* an NMT or error control event reached the drive during
                                   co_node_process: its deadlines are not yet counted */
    bool profile_off;           /* set by a description: 0x6040/0x6042 writes are stored, not
                                   acted on (another control path drives the state machine) */
    uint64_t pass_at;           /* co_drive_process makes its pass from this time on: the drive's
                                   own next deadline after a pass that changed and showed nothing
                                   with the motor settled; 0 while an input waits (dirty), a value
                                   waits to be shown (stale), the motor moves, or once anything
                                   woke the drive (co_drive_wake) */

    /* Motion. */
    uint8_t motion;             /* co_drive_motion */
    uint8_t stop;               /* co_drive_stop of a MOTION_STOP */
    uint8_t then;               /* co_drive_then */
    bool output;                /* power stage on */
    int32_t setpoint;           /* ramp input while running */
    int32_t goal;               /* the limited target 'target reached' compares with */
    int32_t override_setpoint;  /* CO_DRIVE_LOSS_PRESET */
    uint8_t override;           /* 0, CO_DRIVE_LOSS_HOLD_OUTPUT, _FREEWHEEL or _PRESET */
    co_vl_slope custom_slope;   /* CO_DRIVE_STOP_CUSTOM */
    co_vl_ramp ramp;
    co_motor motor;
    co_vl_slope acc, dec, halt; /* the slopes in use, read when an input changes */
    co_vl_slope stop_s;         /* slope of a MOTION_STOP */
    uint16_t pole_count;        /* the motor's poles, read when an input changes */
    bool remote;                /* statusword bit 9, read when an input changes */
    uint64_t last;              /* time motion was computed up to */
    uint64_t tick_origin;       /* start of the tick grid */
    bool moving;                /* ramp or motor not settled */
    uint64_t mains_lost_at;

    int32_t target;             /* the reference set by co_drive_set_target() or a cleared
                                   target (0); see target_stored */
    bool target_stored;         /* 0x6042 was written (SDO, RPDO) since: the reference is the
                                   value the dictionary holds */
    bool hold;                  /* running with the ramp frozen (rfg bit 5 = 0, hold reaction) */
    bool halting;               /* running to 0 on the halt slope */
    bool pending_fault;         /* Fault reaction active by coasting: 14 at pending_at */
    uint64_t pending_at;

    /* Fault. */
    bool fault_cause;           /* the cause of the trip is still present */
    uint16_t fault_emcy;        /* EMCY code of the active trip (0: none) */
    uint16_t fault_trip;        /* its trip code */
    uint16_t retrip_emcy;       /* a trip whose cause outlived a reset node: raised again */
    uint16_t retrip_code;
    uint32_t target_rx_frame;   /* node.stats.rx_frames when an RPDO last wrote 0x6042 (0: an
                                   SDO or the application did) */

    /* Communication loss. */
    bool loss_active;
    bool loss_tripped;          /* the active trip came from co_drive_loss_react */

    uint8_t kept[CO_DRIVE_KEEP_BYTES]; /* the keep ranges' values across a reset node */

    /* Owned by the description (meaning per drive). */
    int32_t setting[CO_DRIVE_MAX_SETTINGS];
    int32_t var[CO_DRIVE_VARS];
    uint64_t timer[CO_DRIVE_TIMERS];
} co_drive;

/* Sets d up as a drive of kind desc. cfg gives the node-ID, driver, value block (at least
 * desc->od->value_size bytes), storage and the application's events (called after the drive's);
 * cfg->od may be NULL or desc->od. The description's configure() adjusts the node options.
 * False on a bad configuration. Settings are at their defaults. */
bool co_drive_init(co_drive *d, const co_drive_desc *desc, const co_node_config *cfg);

/* Sets the application's observer (copied). */
void co_drive_observe(co_drive *d, const co_drive_observer *observer);

/* Starts the node (boot-up, PRE-OPERATIONAL) with the state machine in Switch on disabled. */
void co_drive_start(co_drive *d, uint64_t now);

/* Hands a received frame to the drive's node (co_node_rx). */
void co_drive_rx(co_drive *d, const co_frame *frame, uint64_t now);

/* Moves the motor up to now, runs the drive's timers and the node (co_node_process). Returns the
 * absolute time to be called again (CO_TIME_NEVER: nothing pending). Before the drive's own
 * deadline, with nothing new, only the node runs (see "Deadline contract" at the top). */
uint64_t co_drive_process(co_drive *d, uint64_t now);

/* Something the drive's next pass must look at changed outside the runtime (a description's
 * own object hook set a flag or a timer its process reads): the next co_drive_process makes a
 * full pass, whatever the deadlines. */
void co_drive_wake(co_drive *d);

/* Raises one of the drive's own trip codes (its faults.csv), as the inverter would: 0x603F,
 * 0x1001, 0x1003 and the EMCY carry the table's codes, the fault reaction runs, then Fault. The
 * cause stays present until co_drive_clear_fault_cause(). False if the code is not in the table
 * (and the description has no catch-all row). */
bool co_drive_inject_fault(co_drive *d, uint16_t trip_code, uint64_t now);

/* The cause of the injected fault has gone: a fault reset now succeeds. */
void co_drive_clear_fault_cause(co_drive *d);

/* Trips with the row whose EMCY code is emcy_code (also rows without a trip code, e.g. a
 * communication-loss trip). False if there is none. */
bool co_drive_trip_emcy(co_drive *d, uint16_t emcy_code, bool cause_stays, uint64_t now);

/* Trips with explicit codes (a catch-all row): 0x603F error_code, EMCY emcy_code with 0x1001
 * register bits, trip_code in the EMCY manufacturer bytes. stop: the fault reaction
 * (co_drive_stop; CO_DRIVE_STOP_CUSTOM uses d->custom_slope). */
void co_drive_trip_codes(co_drive *d, uint16_t emcy_code, uint16_t error_code,
                         uint8_t register_bits, uint16_t trip_code, bool cause_stays,
                         uint8_t stop, uint64_t now);

/* Sends a table row's EMCY without tripping (a communication-layer event) / clears it. */
bool co_drive_report_error(co_drive *d, uint16_t emcy_code, uint64_t now);
void co_drive_clear_error(co_drive *d, uint16_t emcy_code);

/* A fault reset from outside the controlword (keypad, terminal, a drive's own command): as
 * transition 15. False if not in Fault or the cause is still present. */
bool co_drive_fault_reset(co_drive *d, uint64_t now);

/* A device control command as if it came in the controlword (drives whose own control words
 * drive the state machine, communication-loss reactions). */
void co_drive_command(co_drive *d, co_cia402_command command, uint64_t now);

/* Communication-loss reaction (called by a description when its criterion is met). param:
 * the preset speed (CO_DRIVE_LOSS_PRESET) or the EMCY code of the trip row (CO_DRIVE_LOSS_TRIP).
 * Reactions that keep running only act while the motor runs. */
void co_drive_loss_react(co_drive *d, co_drive_loss reaction, int32_t param, uint64_t now);

/* Communication is back: ends a warning, hold or preset reaction (trips and stops stay). */
void co_drive_loss_clear(co_drive *d, uint64_t now);

/* Mains present or lost: statusword bit 4 and the description's mains_timeout_us rule. */
void co_drive_set_mains(co_drive *d, bool on, uint64_t now);

/* Sets a named setting (co_drive_desc.settings). False if unknown or out of range. */
bool co_drive_set_setting(co_drive *d, const char *name, int32_t value);

/* The trip table row of a trip code / an EMCY code, or NULL. */
const co_drive_trip *co_drive_find_trip(const co_drive_desc *desc, uint16_t trip_code);
const co_drive_trip *co_drive_find_emcy(const co_drive_desc *desc, uint16_t emcy_code);

/* Marks the shown values for recomputation (a description whose own parameters change what the
 * statusword shows calls this from its hooks). */
void co_drive_touch(co_drive *d);

/* The reference of a drive whose own profile has no 0x6042 (velocity unit, signed). */
void co_drive_set_target(co_drive *d, int32_t target, uint64_t now);

/* The mechanical load on the motor's shaft (a test instrument's load step): percent of the
 * motor's rated torque, 0..CO_MOTOR_LOAD_MAX (drive/model.h). The motor's torque and current
 * (co_drive.motor) follow it while the output is on, from now; the description's monitors show
 * them at once. The load stays across state changes, trips and resets (it is the machine's, not
 * the drive's). False (nothing changed) out of range. */
bool co_drive_set_load(co_drive *d, int32_t percent, uint64_t now);

/* The current setpoint after limits (velocity unit), for descriptions' monitors. */
int32_t co_drive_limited_target(const co_drive *d);

/* --- registry (library `drives`, not the core) ------------------------------------------- */

/* Every drive description built into the program, in a fixed order. */
size_t co_drive_registry_count(void);
const co_drive_desc *co_drive_registry_at(size_t i);
/* The description with this id, or NULL. */
const co_drive_desc *co_drive_registry_find(const char *id);

#ifdef __cplusplus
}
#endif

#endif
