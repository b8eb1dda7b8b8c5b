/* The operator's commands, for standard input and the control socket alike. */
#define _GNU_SOURCE
#include "commands.h"

#include "canopen/od.h"

#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_WORDS 4u

bool cmd_parse_uint(const char *s, unsigned long lo, unsigned long hi, unsigned long *out)
{
    if (s == NULL) {
        return false;
    }
    bool hex = s[0] == '0' && (s[1] == 'x' || s[1] == 'X');
    const char *digits = hex ? s + 2 : s;
    if (hex ? !isxdigit((unsigned char)digits[0]) : !isdigit((unsigned char)digits[0])) {
        return false; /* no sign, no blank, not empty */
    }
    char *end = NULL;
    errno = 0;
    unsigned long v = strtoul(digits, &end, hex ? 16 : 10);
    if (errno != 0 || *end != '\0' || v < lo || v > hi) {
        return false;
    }
    *out = v;
    return true;
}

sim_node *cmd_find_node(const cmd_env *env, const char *arg, char *err, size_t err_len)
{
    unsigned long id;
    if (!cmd_parse_uint(arg, 1, 127, &id)) {
        char shown[SIM_SHOW_BUF];
        if (env->ecat != NULL) {
            snprintf(err, err_len, "'%s' is not a slave position (1..%zu)",
                     sim_show(arg != NULL ? arg : "", shown, sizeof shown), env->node_count);
        } else {
            snprintf(err, err_len, "'%s' is not a node-ID (1..127)",
                     sim_show(arg != NULL ? arg : "", shown, sizeof shown));
        }
        return NULL;
    }
    for (size_t i = 0; i < env->node_count; i++) {
        if (env->nodes[i]->node_id == id) {
            return env->nodes[i];
        }
    }
    const char *what = env->ecat != NULL ? "slave" : "node";
    int pos = snprintf(err, err_len, "no %s %lu here (%ss:", what, id, what);
    for (size_t i = 0; i < env->node_count && pos > 0 && (size_t)pos < err_len; i++) {
        pos += snprintf(err + pos, err_len - (size_t)pos, " %u", (unsigned)env->nodes[i]->node_id);
    }
    if (pos > 0 && (size_t)pos < err_len) {
        snprintf(err + pos, err_len - (size_t)pos, ")");
    }
    return NULL;
}

/* The PDO layout in force: one line per PDO the dictionary has, "rpdo|tpdo NUMBER COB-ID
 * MAPPING..." (COB-ID as 0x1400/0x1800 sub 1 holds it, bit 31 set when the PDO is not valid; the
 * mapping entries of 0x1600/0x1A00, as many as sub 0 says), all in hex. */
static void pdo_lines(sim_node *sn, cmd_emit_fn emit, void *ctx)
{
    co_node *node = sim_co_node(sn);
    static const struct {
        const char *kind;
        uint16_t comm, map;
    } kinds[] = {{"rpdo", 0x1400u, 0x1600u}, {"tpdo", 0x1800u, 0x1A00u}};
    for (size_t k = 0; k < 2u; k++) {
        for (uint16_t i = 0; i < 512u; i++) {
            uint16_t comm = (uint16_t)(kinds[k].comm + i), map = (uint16_t)(kinds[k].map + i);
            if (co_od_find_entry(node->od, comm) == NULL ||
                co_od_find_entry(node->od, map) == NULL) {
                continue;
            }
            char text[CMD_LINE_MAX];
            int pos = snprintf(text, sizeof text, "%s %u 0x%08lX", kinds[k].kind, i + 1u,
                               (unsigned long)co_od_get_u32(node, comm, 1));
            uint8_t count = co_od_get_u8(node, map, 0);
            for (uint8_t m = 1; m <= count && m <= 64u && pos > 0 && (size_t)pos < sizeof text;
                 m++) {
                pos += snprintf(text + pos, sizeof text - (size_t)pos, " 0x%08lX",
                                (unsigned long)co_od_get_u32(node, map, m));
            }
            emit(ctx, CMD_DATA, text);
        }
    }
}

static bool refuse(cmd_emit_fn emit, void *ctx, const char *text)
{
    emit(ctx, CMD_ERROR, text);
    return false;
}

/* Commands that take exactly `want` words (the command included). */
static bool arity(size_t n, size_t want, const char *usage, cmd_emit_fn emit, void *ctx)
{
    if (n == want) {
        return true;
    }
    char text[128];
    snprintf(text, sizeof text, "usage: %s", usage);
    emit(ctx, CMD_ERROR, text);
    return false;
}

/* The status line of a node, and on an EtherCAT line the slave's EtherCAT line after it. */
static void status_lines(const cmd_env *env, sim_node *sn, cmd_emit_fn emit, void *ctx)
{
    char text[CMD_LINE_MAX];
    sim_status_line(sn, text, sizeof text);
    emit(ctx, CMD_DATA, text);
    if (env->ecat != NULL) {
        ecat_port_status_line(env->ecat, ecat_port_slot(env->ecat, sn->node_id), text,
                              sizeof text);
        emit(ctx, CMD_DATA, text);
    }
}

bool cmd_run(const cmd_env *env, char *line, uint64_t now, cmd_emit_fn emit, void *ctx,
             bool *is_empty)
{
    char *words[MAX_WORDS + 1u];
    size_t n = 0;
    char *save = NULL;
    char err[CMD_LINE_MAX];
    char shown[SIM_SHOW_BUF];
    for (char *w = strtok_r(line, " \t\r", &save); w != NULL; w = strtok_r(NULL, " \t\r", &save)) {
        if (n == MAX_WORDS + 1u) {
            break; /* more than any command takes: n says so */
        }
        words[n++] = w;
    }
    if (is_empty != NULL) {
        *is_empty = n == 0u || words[0][0] == '#';
    }
    if (n == 0u || words[0][0] == '#') {
        return true;
    }
    const char *cmd = words[0];
    if (strcmp(cmd, "quit") == 0 || strcmp(cmd, "exit") == 0) {
        if (!arity(n, 1, "quit (no arguments)", emit, ctx)) {
            return false;
        }
        loop_stop(env->lp);
        return true;
    }
    if (strcmp(cmd, "help") == 0) {
        if (!arity(n, 1, "help (no arguments)", emit, ctx)) {
            return false;
        }
        emit(ctx, CMD_DATA, "commands: fault NODE TRIP | clear NODE | status [NODE] | state NODE | "
                            "nodes | pdo NODE | mute NODE | unmute NODE | mains NODE on|off | load NODE PERCENT | nmt NODE start|stop|preop|reset-node|reset-comm | help | quit");
        return true;
    }
    if (strcmp(cmd, "nodes") == 0) {
        if (!arity(n, 1, "nodes (no arguments)", emit, ctx)) {
            return false;
        }
        for (size_t i = 0; i < env->node_count; i++) {
            char text[CMD_LINE_MAX];
            snprintf(text, sizeof text, "%u %s %s", (unsigned)env->nodes[i]->node_id,
                     env->nodes[i]->id, env->nodes[i]->port.iface);
            emit(ctx, CMD_DATA, text);
        }
        return true;
    }
    if (strcmp(cmd, "status") == 0) {
        if (n > 2u) {
            return refuse(emit, ctx, "usage: status [NODE]");
        }
        if (n == 2u) {
            sim_node *sn = cmd_find_node(env, words[1], err, sizeof err);
            if (sn == NULL) {
                return refuse(emit, ctx, err);
            }
            status_lines(env, sn, emit, ctx);
        } else {
            for (size_t i = 0; i < env->node_count; i++) {
                status_lines(env, env->nodes[i], emit, ctx);
            }
        }
        return true;
    }
    if (strcmp(cmd, "state") == 0) {
        if (!arity(n, 2, "state NODE", emit, ctx)) {
            return false;
        }
        sim_node *sn = cmd_find_node(env, words[1], err, sizeof err);
        if (sn == NULL) {
            return refuse(emit, ctx, err);
        }
        char text[CMD_LINE_MAX];
        sim_state_json(sn, text, sizeof text);
        emit(ctx, CMD_DATA, text);
        return true;
    }
    if (strcmp(cmd, "pdo") == 0) {
        if (!arity(n, 2, "pdo NODE", emit, ctx)) {
            return false;
        }
        sim_node *sn = cmd_find_node(env, words[1], err, sizeof err);
        if (sn == NULL) {
            return refuse(emit, ctx, err);
        }
        pdo_lines(sn, emit, ctx);
        return true;
    }
    if (strcmp(cmd, "fault") == 0) {
        if (!arity(n, 3, "fault NODE TRIP (e.g. fault 5 0x01)", emit, ctx)) {
            return false;
        }
        sim_node *sn = cmd_find_node(env, words[1], err, sizeof err);
        if (sn == NULL) {
            return refuse(emit, ctx, err);
        }
        unsigned long trip;
        if (!cmd_parse_uint(words[2], 0, 0xFFFFFFFFul, &trip)) {
            snprintf(err, sizeof err, "'%s' is not a trip code (decimal or 0x..)",
                     sim_show(words[2], shown, sizeof shown));
            return refuse(emit, ctx, err);
        }
        if (!sim_fault(sn, (uint32_t)trip, now, err, sizeof err)) {
            return refuse(emit, ctx, err);
        }
        return true;
    }
    if (strcmp(cmd, "clear") == 0) {
        if (!arity(n, 2, "clear NODE", emit, ctx)) {
            return false;
        }
        sim_node *sn = cmd_find_node(env, words[1], err, sizeof err);
        if (sn == NULL || !sim_clear(sn, now, err, sizeof err)) {
            return refuse(emit, ctx, err);
        }
        return true;
    }
    if (strcmp(cmd, "mute") == 0 || strcmp(cmd, "unmute") == 0) {
        if (!arity(n, 2, cmd[0] == 'm' ? "mute NODE" : "unmute NODE", emit, ctx)) {
            return false;
        }
        sim_node *sn = cmd_find_node(env, words[1], err, sizeof err);
        if (sn != NULL && env->ecat != NULL) {
            snprintf(err, sizeof err, "slave %u is on EtherCAT: %s is for CAN nodes (a master "
                                      "that stops its cycle gives the SM watchdog's reaction)",
                     (unsigned)sn->node_id, cmd);
            return refuse(emit, ctx, err);
        }
        if (sn == NULL) {
            return refuse(emit, ctx, err);
        }
        bool mute = cmd[0] == 'm';
        if (sn->port.muted != mute) {
            sn->port.muted = mute;
            sim_log(sn, mute ? "muted: sends nothing (heartbeat, PDOs, answers) until unmute"
                             : "unmuted: sends again");
        }
        return true;
    }
    if (strcmp(cmd, "mains") == 0) {
        if (!arity(n, 3, "mains NODE on|off", emit, ctx)) {
            return false;
        }
        sim_node *sn = cmd_find_node(env, words[1], err, sizeof err);
        if (sn == NULL) {
            return refuse(emit, ctx, err);
        }
        bool on = strcmp(words[2], "on") == 0;
        if (!on && strcmp(words[2], "off") != 0) {
            snprintf(err, sizeof err, "mains %s: 'on' or 'off', not '%s'", words[1],
                     sim_show(words[2], shown, sizeof shown));
            return refuse(emit, ctx, err);
        }
        if (sn->desc == NULL) {
            snprintf(err, sizeof err, "node %u %s: a benchmark device has no mains",
                     (unsigned)sn->node_id, sn->id);
            return refuse(emit, ctx, err);
        }
        co_drive_set_mains(&sn->drive, on, now);
        sim_log(sn, "mains %s", on ? "on" : "off");
        return true;
    }
    if (strcmp(cmd, "load") == 0) {
        if (!arity(n, 3, "load NODE PERCENT (0..200 % of rated torque)", emit, ctx)) {
            return false;
        }
        sim_node *sn = cmd_find_node(env, words[1], err, sizeof err);
        if (sn == NULL) {
            return refuse(emit, ctx, err);
        }
        unsigned long percent;
        if (!cmd_parse_uint(words[2], 0, CO_MOTOR_LOAD_MAX, &percent)) {
            snprintf(err, sizeof err, "load %s: '%s' is not a load (0..%u %% of rated torque)",
                     words[1], sim_show(words[2], shown, sizeof shown),
                     (unsigned)CO_MOTOR_LOAD_MAX);
            return refuse(emit, ctx, err);
        }
        if (sn->desc == NULL) {
            snprintf(err, sizeof err, "node %u %s: a benchmark device has no motor",
                     (unsigned)sn->node_id, sn->id);
            return refuse(emit, ctx, err);
        }
        (void)co_drive_set_load(&sn->drive, (int32_t)percent, now);
        sim_log(sn, "load %lu %% of rated torque", percent);
        return true;
    }
    if (strcmp(cmd, "nmt") == 0) {
        if (!arity(n, 3, "nmt NODE start|stop|preop|reset-node|reset-comm", emit, ctx)) {
            return false;
        }
        sim_node *sn = cmd_find_node(env, words[1], err, sizeof err);
        if (sn != NULL && env->ecat != NULL) {
            snprintf(err, sizeof err, "slave %u is on EtherCAT: its state follows the master's "
                                      "AL control requests, not NMT commands",
                     (unsigned)sn->node_id);
            return refuse(emit, ctx, err);
        }
        if (sn == NULL || !sim_nmt(sn, words[2], now, err, sizeof err)) {
            return refuse(emit, ctx, err);
        }
        return true;
    }
    snprintf(err, sizeof err, "unknown command '%s' (try 'help')", sim_show(cmd, shown, sizeof shown));
    return refuse(emit, ctx, err);
}
