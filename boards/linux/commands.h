/* The operator's commands of canopen-drive, shared by standard input and the control socket
 * (control.h): fault, clear, status, state, nodes, pdo, mute, unmute, mains, load, nmt, help,
 * quit. One line in, its result out
 * through an emit callback, so each channel words it its own way (stdin: stdout and stderr; the
 * control socket: "data"/"ok"/"error" lines). */
#ifndef BOARDS_LINUX_COMMANDS_H
#define BOARDS_LINUX_COMMANDS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ecat_port.h"
#include "loop.h"
#include "sim.h"

/* What a command may act on. */
typedef struct cmd_env {
    sim_node *const *nodes;
    size_t node_count;
    loop *lp;                      /* quit stops it */
    ecat_port *ecat;               /* the EtherCAT line (--ecat-iface): nodes are its slaves,
                                    * named by position; NULL on CAN */
} cmd_env;

typedef enum cmd_emit_kind {
    CMD_DATA = 0,                  /* a line of the result (status, state, nodes, help) */
    CMD_ERROR                      /* why the command was refused (one line; nothing was done) */
} cmd_emit_kind;

typedef void (*cmd_emit_fn)(void *ctx, cmd_emit_kind kind, const char *text);

/* Longest result line. */
#define CMD_LINE_MAX SIM_LOG_MAX

/* Runs one command line (modified in place: split into words). An empty line or a '#' comment
 * does nothing. Returns false when it was refused (after one CMD_ERROR), true otherwise;
 * *is_empty tells a blank or comment line (may be NULL). */
bool cmd_run(const cmd_env *env, char *line, uint64_t now, cmd_emit_fn emit, void *ctx,
             bool *is_empty);

/* The node with this node-ID argument, or NULL with a reason in err. */
sim_node *cmd_find_node(const cmd_env *env, const char *arg, char *err, size_t err_len);

/* Strict integer parsing: decimal or 0x hex (never octal: "010" is ten), the whole string,
 * within [lo, hi]. */
bool cmd_parse_uint(const char *s, unsigned long lo, unsigned long hi, unsigned long *out);

#endif
