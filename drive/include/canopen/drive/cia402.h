/* CiA 402 power drive system (PDS) finite state automaton (CiA 402-2 §6.3 / DSP 402 V3.0 tables
 * 26 and 27): the eight states, the controlword commands, transitions 0-16 and the statusword, as
 * pure functions with no object dictionary behind them. The drive (drive.h) keeps the state, runs
 * the actions a transition asks for and writes 0x6041; a drive's departures from the plain profile
 * are the CO_CIA402_* flags below, set in its description, never special cases here.
 *
 *   co_cia402_command cmd = co_cia402_decode(cw, previous_cw, flags);
 *   co_cia402_state to;
 *   int t = co_cia402_next(state, cmd, flags, quick_stop_stays, &to);  // -1: no transition
 */
#ifndef CANOPEN_DRIVE_CIA402_H
#define CANOPEN_DRIVE_CIA402_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The PDS states. Not ready to switch on is passed through at start-up (transitions 0 and 1). */
typedef enum co_cia402_state {
    CO_CIA402_NOT_READY_TO_SWITCH_ON = 0,
    CO_CIA402_SWITCH_ON_DISABLED = 1,
    CO_CIA402_READY_TO_SWITCH_ON = 2,
    CO_CIA402_SWITCHED_ON = 3,
    CO_CIA402_OPERATION_ENABLED = 4,
    CO_CIA402_QUICK_STOP_ACTIVE = 5,
    CO_CIA402_FAULT_REACTION_ACTIVE = 6,
    CO_CIA402_FAULT = 7
} co_cia402_state;

/* Bit of a state in a set of states (e.g. co_drive_desc.voltage_states). */
#define CO_CIA402_STATE_BIT(s) (1u << (unsigned)(s))

/* Device control commands (controlword bits 7, 3, 2, 1, 0). */
typedef enum co_cia402_command {
    CO_CIA402_CMD_NONE = 0,         /* bit 7 held high, so no command is decoded */
    CO_CIA402_CMD_SHUTDOWN,         /* 0 x 1 1 0: transitions 2, 6, 8 */
    CO_CIA402_CMD_SWITCH_ON,        /* 0 0 1 1 1: transition 3; in Operation enabled it is
                                       Disable operation (5) */
    CO_CIA402_CMD_ENABLE_OPERATION, /* 0 1 1 1 1: transitions 4, 16; in Ready to switch on it is
                                       Switch on + Enable operation (3 + 4) */
    CO_CIA402_CMD_DISABLE_VOLTAGE,  /* 0 x x 0 x: transitions 7, 9, 10, 12 */
    CO_CIA402_CMD_QUICK_STOP,       /* 0 x 0 1 x: transitions 7, 10, 11 */
    CO_CIA402_CMD_FAULT_RESET       /* rising edge of bit 7: transition 15 */
} co_cia402_command;

/* Controlword (0x6040) bits. */
#define CO_CW_SWITCH_ON        0x0001u
#define CO_CW_ENABLE_VOLTAGE   0x0002u
#define CO_CW_QUICK_STOP       0x0004u /* active low: 0 requests a quick stop */
#define CO_CW_ENABLE_OPERATION 0x0008u
#define CO_CW_VL_RFG_ENABLE    0x0010u /* vl: ramp function generator enable */
#define CO_CW_VL_RFG_UNLOCK    0x0020u /* vl: 0 holds the ramp output */
#define CO_CW_VL_RFG_USE_REF   0x0040u /* vl: 0 sets the ramp input to 0 */
#define CO_CW_FAULT_RESET      0x0080u
#define CO_CW_HALT             0x0100u

/* Statusword (0x6041) bits. */
#define CO_SW_READY_TO_SWITCH_ON 0x0001u
#define CO_SW_SWITCHED_ON        0x0002u
#define CO_SW_OPERATION_ENABLED  0x0004u
#define CO_SW_FAULT              0x0008u
#define CO_SW_VOLTAGE_ENABLED    0x0010u
#define CO_SW_QUICK_STOP         0x0020u /* active low: 0 while a quick stop is active */
#define CO_SW_SWITCH_ON_DISABLED 0x0040u
#define CO_SW_WARNING            0x0080u
#define CO_SW_REMOTE             0x0200u
#define CO_SW_TARGET_REACHED     0x0400u
#define CO_SW_INTERNAL_LIMIT     0x0800u

/* Departures from plain CiA 402 (a drive description's cia402_flags). */
/* Commands are decoded whatever bit 7 holds (VF-MB1 EtherCAT §6.1.4 prints bit 7 'x'); by default
 * bit 7 = 1 carries no command but the fault reset edge, as in the CiA 402 command table. */
#define CO_CIA402_BIT7_DONT_CARE    0x0001u
/* Enable operation in Ready to switch on performs transition 3 only (DSP 402 V1.1 reading);
 * by default it is 'Switch on + Enable operation', transitions 3 + 4 (CiA 402-2 table 27). */
#define CO_CIA402_NO_SWITCH_ON_ENABLE 0x0002u
/* Quick stop active ignores the controlword: no transition 12 on Disable voltage and no 16; the
 * quick stop runs to its end (VF-MB1 EtherCAT §6.1.4 lists 7, 9, 10 only). */
#define CO_CIA402_QUICK_STOP_LOCKED 0x0004u
/* Transition 16 (Enable operation in Quick stop active) whatever the quick stop option code
 * (Benshaw RSi §8.1.1 lists 16 but has no 0x605A). */
#define CO_CIA402_ALWAYS_16         0x0008u
/* In Fault reaction active and Fault the quick stop bit 5 keeps the value it had before the
 * fault (VF-MB1 EtherCAT §6.1.4: 'Fault 0x0008 or 0x0028'); by default it reads 0. */
#define CO_CIA402_FAULT_KEEPS_QS_BIT 0x0010u

/* Decodes the controlword. previous is the controlword received before it (0 after a reset): a
 * 0 -> 1 change of bit 7 is the fault reset command, whatever the other bits. */
co_cia402_command co_cia402_decode(uint16_t controlword, uint16_t previous, uint32_t flags);

/* The transition a command asks for from state: returns its number (2-12, 15, 16) and the new
 * state in *to, or -1 (and *to = from) when the command does nothing in that state.
 * quick_stop_stays: the quick stop option code keeps the drive in Quick stop active (5-8), which
 * is what allows transition 16. Conditions outside the state machine (a fault still present, a
 * drive that needs a reference first) are for the caller to check. Enable operation in Ready to
 * switch on returns 3 (Switched on); the caller runs it again for 4 unless
 * CO_CIA402_NO_SWITCH_ON_ENABLE is set. Transitions 0, 1, 13 and 14 are not caused by commands:
 * the caller makes them. */
int co_cia402_next(co_cia402_state from, co_cia402_command command, uint32_t flags,
                   bool quick_stop_stays, co_cia402_state *to);

/* What the statusword shows besides the state. */
typedef struct co_cia402_status {
    co_cia402_state state;
    bool voltage_enabled;   /* bit 4 */
    bool quick_stop_before; /* bit 5 before the fault (CO_CIA402_FAULT_KEEPS_QS_BIT) */
    bool warning;           /* bit 7 */
    bool remote;            /* bit 9 */
    bool target_reached;    /* bit 10 */
    bool internal_limit;    /* bit 11 */
    uint16_t manufacturer;  /* bits 8, 12-15 as the drive sets them (others are masked off) */
} co_cia402_status;

/* The statusword for a state and its flags: the state pattern of CiA 402-2 table 30 (bits 0-3,
 * 5, 6) with bits 4, 7, 9, 10, 11 and the manufacturer bits added. */
uint16_t co_cia402_statusword(const co_cia402_status *status, uint32_t flags);

/* The state a statusword shows (its bits 0-3, 5, 6), as a master decodes it. */
co_cia402_state co_cia402_state_of(uint16_t statusword);

/* A short name, e.g. "OPERATION ENABLED" (python-canopen's spelling). */
const char *co_cia402_state_name(co_cia402_state state);

#ifdef __cplusplus
}
#endif

#endif
