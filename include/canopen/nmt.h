/* NMT slave (CiA 301 §7.2.8.2): states, commands, boot-up. */
#ifndef CANOPEN_NMT_H
#define CANOPEN_NMT_H

#include <stdint.h>

#include "canopen/frame.h"
#include "canopen/time_base.h"

#ifdef __cplusplus
extern "C" {
#endif

struct co_node;

/* States as they appear in the heartbeat / boot-up byte. */
typedef enum co_nmt_state {
    CO_NMT_INITIALISING = 0x00,
    CO_NMT_STOPPED = 0x04,
    CO_NMT_OPERATIONAL = 0x05,
    CO_NMT_PRE_OPERATIONAL = 0x7F
} co_nmt_state;

/* NMT command specifiers (first byte of a COB-ID 0 frame). */
typedef enum co_nmt_command {
    CO_NMT_CMD_START = 0x01,
    CO_NMT_CMD_STOP = 0x02,
    CO_NMT_CMD_ENTER_PRE_OPERATIONAL = 0x80,
    CO_NMT_CMD_RESET_NODE = 0x81,
    CO_NMT_CMD_RESET_COMMUNICATION = 0x82
} co_nmt_command;

/* Applies a command as if it had come from the master (also the application's local control). */
void co_nmt_command_local(struct co_node *node, co_nmt_command command, uint64_t now);

/* Runs the reset node sequence: restore all values (stored image, else defaults), then reset
 * communication. */
void co_nmt_reset_node(struct co_node *node, uint64_t now);

/* Runs the reset communication sequence: restore 0x1000-0x1FFF, re-read the communication
 * parameters, send the boot-up message and enter PRE-OPERATIONAL. */
void co_nmt_reset_communication(struct co_node *node, uint64_t now);

/* Name of a state, for logs. */
const char *co_nmt_state_name(co_nmt_state state);

#ifdef __cplusplus
}
#endif

#endif
