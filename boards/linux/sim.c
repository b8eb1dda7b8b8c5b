/* One simulated node: co_drive + socket + store slot, and its log lines. */
#define _GNU_SOURCE
#include "sim.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "canopen/drive/cia402.h"
#include "canopen/errctl.h"
#include "canopen/nmt.h"
#include "canopen/od.h"
#include "od_bench.h"

void sim_log(const sim_node *sn, const char *fmt, ...)
{
    char line[SIM_LOG_MAX];
    int head = snprintf(line, sizeof line, "%s %u %s: ", sn->label, (unsigned)sn->node_id, sn->id);
    va_list ap;
    va_start(ap, fmt);
    if (head > 0 && (size_t)head < sizeof line) {
        (void)vsnprintf(line + head, sizeof line - (size_t)head, fmt, ap);
    }
    va_end(ap);
    puts(line);
    fflush(stdout);
    if (sn->log_hook != NULL) {
        sn->log_hook(sn->log_ctx, line);
    }
}

/* --- what the drive and its node tell us ------------------------------------------------------ */

static void on_nmt_changed(co_node *node, void *ctx, co_nmt_state from, co_nmt_state to)
{
    sim_node *sn = ctx;
    (void)node;
    sim_log(sn, "NMT %s -> %s", co_nmt_state_name(from), co_nmt_state_name(to));
    sn->refilter = true;
}

static void on_reset(co_node *node, void *ctx, bool whole_node)
{
    sim_node *sn = ctx;
    (void)node;
    if (sn->started) { /* power-on is not a reset command */
        sim_log(sn, "NMT %s", whole_node ? "reset node" : "reset communication");
    }
    sn->refilter = true;
}

static void on_comm(co_node *node, void *ctx, co_comm_event event, uint32_t detail)
{
    sim_node *sn = ctx;
    (void)node;
    switch (event) {
    case CO_COMM_HEARTBEAT_LOST:
        sim_log(sn, "heartbeat of node %u lost", (unsigned)detail);
        break;
    case CO_COMM_HEARTBEAT_RESUMED:
        sim_log(sn, "heartbeat of node %u back", (unsigned)detail);
        break;
    case CO_COMM_LIFE_GUARD_LOST:
        sim_log(sn, "life guarding lost (no guarding request in time)");
        break;
    case CO_COMM_LIFE_GUARD_RESUMED:
        sim_log(sn, "life guarding back");
        break;
    case CO_COMM_RPDO_TIMEOUT:
        sim_log(sn, "RPDO%u timed out", (unsigned)detail);
        break;
    default:
        break; /* bus states are logged where the port sees them */
    }
}

static void log_trip(sim_node *sn)
{
    const co_drive *d = &sn->drive;
    const co_drive_trip *row = d->fault_trip != 0u ? co_drive_find_trip(sn->desc, d->fault_trip)
                                                   : NULL;
    if (row == NULL) {
        row = co_drive_find_emcy(sn->desc, d->fault_emcy);
    }
    sim_log(sn, "fault: trip 0x%02X %s, EMCY 0x%04X%s%s", (unsigned)d->fault_trip,
            row != NULL && row->name != NULL ? row->name : "-", (unsigned)d->fault_emcy,
            row != NULL && row->description != NULL ? " - " : "",
            row != NULL && row->description != NULL ? row->description : "");
    sn->trips_logged++;
}

static void on_state_changed(co_drive *d, void *ctx, int transition, co_cia402_state from,
                             co_cia402_state to)
{
    sim_node *sn = ctx;
    (void)d;
    if (transition == 13) {
        log_trip(sn);
    }
    sim_log(sn, "%s %s -> %s", sn->desc->profile == CO_DRIVE_PROFILE_CIA402 ? "CiA 402" : "state",
            co_cia402_state_name(from), co_cia402_state_name(to));
    if (transition == 15) {
        sim_log(sn, "fault reset");
    }
}

/* --- life cycle -------------------------------------------------------------------------------- */

/* What every node shares: the value block, the store slot, the driver and the event callbacks.
 * NULL with a reason on failure; cfg is ready for co_drive_init or co_node_init. */
static sim_node *node_alloc(const char *id, const co_od *od, uint8_t node_id, file_store *store,
                            co_node_config *cfg, char *err, size_t err_len)
{
    sim_node *sn = calloc(1, sizeof *sn);
    if (sn == NULL) {
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    sn->node_id = node_id;
    sn->label = "node";
    sn->id = id;
    sn->port.fd = -1;
    size_t block = ((size_t)od->value_size + 7u) & ~(size_t)7u;
    sn->values = aligned_alloc(8, block != 0u ? block : 8u);
    sn->scratch = malloc(od->persist_size != 0u ? od->persist_size : 1u);
    if (sn->values == NULL || sn->scratch == NULL) {
        sim_node_destroy(sn);
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    memset(sn->values, 0, block);
    *cfg = co_node_default_config();
    cfg->od = od;
    cfg->values = sn->values;
    cfg->node_id = node_id;
    cfg->driver.send = sc_send;
    cfg->driver.ctx = &sn->port;
    if (store != NULL) {
        sn->storage = file_store_storage(store, &sn->slot, node_id, id);
        cfg->storage = &sn->storage;
        cfg->store_scratch = sn->scratch;
        cfg->store_scratch_size = od->persist_size;
    }
    cfg->events.nmt_changed = on_nmt_changed;
    cfg->events.reset = on_reset;
    cfg->events.comm = on_comm;
    cfg->events.ctx = sn;
    return sn;
}

sim_node *sim_node_create(const co_drive_desc *desc, uint8_t node_id, file_store *store,
                          char *err, size_t err_len)
{
    co_node_config cfg;
    sim_node *sn = node_alloc(desc->id, desc->od, node_id, store, &cfg, err, err_len);
    if (sn == NULL) {
        return NULL;
    }
    sn->desc = desc;
    sn->node = &sn->drive.node;
    if (!co_drive_init(&sn->drive, desc, &cfg)) {
        snprintf(err, err_len, "the drive refused the node configuration");
        sim_node_destroy(sn);
        return NULL;
    }
    co_drive_observer observer = {on_state_changed, sn};
    co_drive_observe(&sn->drive, &observer);
    return sn;
}

/* --- the benchmark device ---------------------------------------------------------------------- */

/* DOMAIN 0x2000 upload: the bytes of the last complete download. */
static co_abort bench_domain_read(co_node *node, void *ctx, co_od_ref ref, uint32_t offset,
                                  uint8_t *buf, uint32_t cap, uint32_t *len, uint32_t *total)
{
    sim_node *sn = ctx;
    (void)node;
    (void)ref;
    uint32_t left = offset < sn->domain_len ? sn->domain_len - offset : 0u;
    uint32_t n = left < cap ? left : cap;
    memcpy(buf, sn->domain + offset, n);
    *len = n;
    *total = sn->domain_len;
    return CO_ABORT_NONE;
}

/* DOMAIN 0x2000 download: stored in place. The length is set only by the last piece, so an
 * aborted download leaves the object empty rather than half old, half new. */
static co_abort bench_domain_write(co_node *node, void *ctx, co_od_ref ref, uint32_t offset,
                                   const uint8_t *data, uint32_t len, uint32_t total, bool last)
{
    sim_node *sn = ctx;
    (void)node;
    (void)ref;
    if (offset == 0u) {
        sn->domain_len = 0u;
        if (total > SIM_BENCH_DOMAIN_CAP) {
            return CO_ABORT_OUT_OF_MEMORY;
        }
    }
    if (offset > SIM_BENCH_DOMAIN_CAP || len > SIM_BENCH_DOMAIN_CAP - offset) {
        return CO_ABORT_OUT_OF_MEMORY;
    }
    memcpy(sn->domain + offset, data, len);
    if (last) {
        sn->domain_len = offset + len;
    }
    return CO_ABORT_NONE;
}

sim_node *sim_bench_create(uint8_t node_id, file_store *store, char *err, size_t err_len)
{
    co_node_config cfg;
    sim_node *sn = node_alloc(SIM_BENCH_ID, &co_od_bench, node_id, store, &cfg, err, err_len);
    if (sn == NULL) {
        return NULL;
    }
    sn->node = &sn->bench_node;
    sn->domain = malloc(SIM_BENCH_DOMAIN_CAP);
    if (sn->domain == NULL) {
        snprintf(err, err_len, "out of memory");
        sim_node_destroy(sn);
        return NULL;
    }
    const co_od_hook domain = {0x2000u, 0x2000u, NULL, NULL, bench_domain_read,
                               bench_domain_write, sn};
    if (!co_node_init(sn->node, &cfg) || !co_node_add_hook(sn->node, &domain)) {
        snprintf(err, err_len, "the core refused the node configuration");
        sim_node_destroy(sn);
        return NULL;
    }
    return sn;
}

void sim_node_destroy(sim_node *sn)
{
    if (sn == NULL) {
        return;
    }
    sc_close(&sn->port);
    free(sn->domain);
    free(sn->values);
    free(sn->scratch);
    free(sn);
}

bool sim_set(sim_node *sn, const char *assignment, char *err, size_t err_len)
{
    const char *eq = strchr(assignment, '=');
    char name[64];
    size_t n = eq != NULL ? (size_t)(eq - assignment) : 0u;
    if (eq == NULL || n == 0u || n >= sizeof name || eq[1] == '\0') {
        char shown[SIM_SHOW_BUF];
        snprintf(err, err_len, "--set wants NAME=VALUE, not '%s'",
                 sim_show(assignment, shown, sizeof shown));
        return false;
    }
    memcpy(name, assignment, n);
    name[n] = '\0';
    if (sn->desc == NULL) {
        snprintf(err, err_len, "%s is a benchmark device: it has no settings", sn->id);
        return false;
    }
    const co_drive_setting *setting = NULL;
    for (uint8_t i = 0; i < sn->desc->setting_count; i++) {
        if (strcmp(sn->desc->settings[i].name, name) == 0) {
            setting = &sn->desc->settings[i];
        }
    }
    if (setting == NULL) {
        char shown[SIM_SHOW_BUF];
        int pos = snprintf(err, err_len, "%s has no setting '%s'", sn->desc->id,
                           sim_show(name, shown, sizeof shown));
        for (uint8_t i = 0; i < sn->desc->setting_count && pos > 0 && (size_t)pos < err_len; i++) {
            pos += snprintf(err + pos, err_len - (size_t)pos, "%s%s", i == 0u ? " (known: " : ", ",
                            sn->desc->settings[i].name);
        }
        if (pos > 0 && (size_t)pos < err_len) {
            snprintf(err + pos, err_len - (size_t)pos, "%s",
                     sn->desc->setting_count != 0u ? ")" : " (it has none)");
        }
        return false;
    }
    char *end = NULL;
    errno = 0;
    long value = strtol(eq + 1, &end, 0);
    if (errno != 0 || *end != '\0' || value < setting->min || value > setting->max ||
        !co_drive_set_setting(&sn->drive, name, (int32_t)value)) {
        char shown[SIM_SHOW_BUF];
        snprintf(err, err_len, "%s setting %s=%s: not a number in %ld..%ld (%s)", sn->desc->id,
                 name, sim_show(eq + 1, shown, sizeof shown), (long)setting->min,
                 (long)setting->max, setting->help);
        return false;
    }
    return true;
}

void sim_start(sim_node *sn, uint64_t now)
{
    if (sn->desc == NULL) {
        co_node_start(sn->node, now);
    } else {
        co_drive_start(&sn->drive, now);
    }
    sn->started = true;
}

void sim_rx(sim_node *sn, const co_frame *frame, uint64_t now)
{
    if (sn->desc == NULL) {
        co_node_rx(sn->node, frame, now);
    } else {
        co_drive_rx(&sn->drive, frame, now);
    }
}

/* One line for the receive overruns not logged yet. */
static void log_overruns(sim_node *sn, uint64_t now)
{
    if (!sn->overrun_logged) {
        sim_log(sn, "CAN receive overrun");
    } else {
        sim_log(sn, "CAN receive overrun: %u more since the previous such line (%u in all)",
                (unsigned)sn->overruns_unlogged, (unsigned)sn->overruns);
    }
    sn->overruns_unlogged = 0;
    sn->overrun_logged_at = now;
    sn->overrun_logged = true;
}

uint64_t sim_process(sim_node *sn, uint64_t now)
{
    uint64_t next = sn->desc == NULL ? co_node_process(sn->node, now)
                                     : co_drive_process(&sn->drive, now);
    if (sn->overruns_unlogged != 0u) {
        /* overruns held back by the one-line-a-second rule: logged when their second is over */
        uint64_t due = sn->overrun_logged_at + SIM_OVERRUN_LOG_US;
        if (now >= due) {
            log_overruns(sn, now);
        } else if (due < next) {
            next = due;
        }
    }
    return next;
}

const char *sim_show(const char *s, char *buf, size_t cap)
{
    static const char hex[] = "0123456789ABCDEF";
    size_t pos = 0;
    size_t i = 0;
    for (; s[i] != '\0' && i < SIM_SHOW_MAX && pos + 5u < cap; i++) {
        unsigned char c = (unsigned char)s[i];
        if (c == '\\') {
            buf[pos++] = '\\';
            buf[pos++] = '\\';
        } else if (c >= 0x20u && c < 0x7Fu) {
            buf[pos++] = (char)c;
        } else {
            buf[pos++] = '\\';
            buf[pos++] = 'x';
            buf[pos++] = hex[c >> 4];
            buf[pos++] = hex[c & 0x0Fu];
        }
    }
    if (s[i] != '\0' && pos + 4u <= cap) {
        memcpy(buf + pos, "...", 3u);
        pos += 3u;
    }
    buf[pos] = '\0';
    return buf;
}

void sim_bus_event(sim_node *sn, sc_bus_event event, uint64_t now)
{
    co_node *node = sim_co_node(sn);
    if (event == SC_BUS_RX_OVERRUN) {
        /* A flooded bus overruns at every read: one line a second, not one per event. */
        sn->overruns++;
        sn->overruns_unlogged++;
        if (!sn->overrun_logged || now - sn->overrun_logged_at >= SIM_OVERRUN_LOG_US) {
            log_overruns(sn, now);
        }
    } else {
        sim_log(sn, "CAN %s", sc_bus_event_name(event));
    }
    switch (event) {
    case SC_BUS_OFF:
        co_node_bus_state(node, CO_BUS_OFF, now);
        break;
    case SC_BUS_ERROR_PASSIVE:
        co_node_bus_state(node, CO_BUS_ERROR_PASSIVE, now);
        break;
    case SC_BUS_ERROR_ACTIVE:
    case SC_BUS_RESTARTED:
        co_node_bus_state(node, CO_BUS_ERROR_ACTIVE, now);
        break;
    case SC_BUS_RX_OVERRUN: {
        /* The socket queue counts what it dropped; a controller overflow says "some". */
        uint32_t dropped = sn->port.stats.rx_dropped_by_kernel - sn->rx_lost_reported;
        sn->rx_lost_reported = sn->port.stats.rx_dropped_by_kernel;
        co_node_rx_overrun(node, dropped != 0u ? dropped : 1u, now);
        break;
    }
    default:
        break; /* error warning: still error active, only logged */
    }
}

bool sim_fault(sim_node *sn, uint32_t trip, uint64_t now, char *err, size_t err_len)
{
    uint32_t before = sn->trips_logged;
    if (sn->desc == NULL) {
        snprintf(err, err_len, "node %u %s: a benchmark device has no trips",
                 (unsigned)sn->node_id, sn->id);
        return false;
    }
    if (trip > 0xFFFFu || !co_drive_inject_fault(&sn->drive, (uint16_t)trip, now)) {
        snprintf(err, err_len, "%s %u %s: no trip code 0x%02X in its table (od/%s/faults.csv)",
                 sn->label, (unsigned)sn->node_id, sn->desc->id, (unsigned)trip, sn->desc->id);
        return false;
    }
    if (sn->trips_logged == before) {
        log_trip(sn); /* already in FAULT: no transition 13 to log it */
    }
    return true;
}

bool sim_clear(sim_node *sn, uint64_t now, char *err, size_t err_len)
{
    (void)now;
    if (sn->desc == NULL) {
        snprintf(err, err_len, "node %u %s: a benchmark device has no faults",
                 (unsigned)sn->node_id, sn->id);
        return false;
    }
    co_drive_clear_fault_cause(&sn->drive);
    sim_log(sn, "fault cause cleared (a fault reset from the master now succeeds)");
    return true;
}

void sim_refresh_filters(sim_node *sn)
{
    uint16_t ids[SC_MAX_FILTERS];
    if (sn->port.fd < 0) {
        sn->refilter = false; /* no CAN face (EtherCAT line) */
        return;
    }
    size_t n = sc_node_cob_ids(sim_co_node(sn), ids, SC_MAX_FILTERS);
    if (sc_set_filters(&sn->port, ids, n) != 0) {
        fprintf(stderr, "canopen-drive: node %u: cannot set receive filters: %s\n",
                (unsigned)sn->node_id, strerror(errno));
    }
    sn->refilter = false;
}

void sim_begin_filter_change(sim_node *sn)
{
    sn->port.hold = true;
}

void sim_end_filter_change(sim_node *sn)
{
    sim_refresh_filters(sn);
    sn->port.hold = false;
    co_node_tx_ready(sim_co_node(sn));
}

bool sim_nmt(sim_node *sn, const char *command, uint64_t now, char *err, size_t err_len)
{
    static const struct {
        const char *name;
        co_nmt_command command;
    } nmt_cmds[] = {
        {"start", CO_NMT_CMD_START},
        {"stop", CO_NMT_CMD_STOP},
        {"preop", CO_NMT_CMD_ENTER_PRE_OPERATIONAL},
        {"reset-node", CO_NMT_CMD_RESET_NODE},
        {"reset-comm", CO_NMT_CMD_RESET_COMMUNICATION},
    };
    for (size_t i = 0; i < sizeof nmt_cmds / sizeof nmt_cmds[0]; i++) {
        if (strcmp(command, nmt_cmds[i].name) == 0) {
            sim_begin_filter_change(sn);
            co_nmt_command_local(sim_co_node(sn), nmt_cmds[i].command, now);
            sim_end_filter_change(sn);
            return true;
        }
    }
    char shown[SIM_SHOW_BUF];
    snprintf(err, err_len, "unknown NMT command '%s' (start, stop, preop, reset-node, reset-comm)",
             sim_show(command, shown, sizeof shown));
    return false;
}

/* The frame counters of the node and of its port, shared by both kinds of status line. */
static void counters(const sim_node *sn, char *buf, size_t cap)
{
    const co_node_stats *st = &sn->node->stats;
    const sc_stats *ps = &sn->port.stats;
    snprintf(buf, cap,
             "rx %u (malformed %u, ignored %u), tx %u (deferred %u, dropped %u), SDO aborts %u; "
             "socket: tx %u, EAGAIN %u, ENOBUFS %u, other errors %u, rx dropped by kernel %u, "
             "receive overruns %u",
             (unsigned)st->rx_frames, (unsigned)st->rx_malformed, (unsigned)st->rx_ignored,
             (unsigned)st->tx_frames, (unsigned)st->tx_deferred, (unsigned)st->tx_dropped,
             (unsigned)st->sdo_aborts, (unsigned)ps->tx_frames, (unsigned)ps->tx_eagain,
             (unsigned)ps->tx_enobufs, (unsigned)ps->tx_other_errors,
             (unsigned)ps->rx_dropped_by_kernel, (unsigned)sn->overruns);
}

void sim_status_line(sim_node *sn, char *buf, size_t cap)
{
    char count[400];
    counters(sn, count, sizeof count);
    int head = snprintf(buf, cap, "%s %u %s: ", sn->label, (unsigned)sn->node_id, sn->id);
    if (head < 0 || (size_t)head >= cap) {
        return;
    }
    buf += head;
    cap -= (size_t)head;
    if (sn->desc == NULL) {
        snprintf(buf, cap, "NMT %s, benchmark device, DOMAIN 0x2000 holds %u bytes; %s",
                 co_nmt_state_name(sn->node->nmt_state), (unsigned)sn->domain_len, count);
        return;
    }
    co_drive *d = &sn->drive;
    co_node *node = sim_co_node(sn);
    char fault[64] = "none";
    if (d->fault_emcy != 0u) {
        snprintf(fault, sizeof fault, "EMCY 0x%04X%s", (unsigned)d->fault_emcy,
                 d->fault_cause ? " (cause present)" : " (cause gone)");
    }
    if (sn->port.fd < 0) { /* no CAN face (an EtherCAT line): no CAN frame counters */
        count[0] = '\0';
    }
    snprintf(buf, cap, "NMT %s, %s %s, target %ld, actual %ld, fault %s%s%s",
             co_nmt_state_name(node->nmt_state),
             sn->desc->profile == CO_DRIVE_PROFILE_CIA402 ? "CiA 402" : "state",
             co_cia402_state_name(d->state), (long)d->target, (long)d->motor.actual, fault,
             count[0] != '\0' ? "; " : "", count);
}

void sim_status(sim_node *sn)
{
    char line[SIM_LOG_MAX];
    sim_status_line(sn, line, sizeof line);
    puts(line);
    fflush(stdout);
}

/* One JSON string value: the names printed here are plain ASCII, but a drive id or name could
 * hold a quote or a backslash one day. */
static size_t json_str(char *buf, size_t cap, const char *s)
{
    size_t pos = 0;
    if (cap < 3u) {
        return 0;
    }
    buf[pos++] = '"';
    for (; *s != '\0' && pos + 8u < cap; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\') {
            buf[pos++] = '\\';
            buf[pos++] = (char)c;
        } else if (c < 0x20u || c >= 0x7Fu) {
            pos += (size_t)snprintf(buf + pos, cap - pos, "\\u%04x", (unsigned)c);
        } else {
            buf[pos++] = (char)c;
        }
    }
    buf[pos++] = '"';
    buf[pos] = '\0';
    return pos;
}

void sim_state_json(sim_node *sn, char *buf, size_t cap)
{
    const co_node_stats *st = &sn->node->stats;
    char drive[80], nmt[40], iface[40], state[60] = "null", fault[120] = "null";
    json_str(drive, sizeof drive, sn->id);
    json_str(nmt, sizeof nmt, co_nmt_state_name(sn->node->nmt_state));
    json_str(iface, sizeof iface, sn->port.iface);
    long target = 0, actual = 0;
    unsigned load = 0;
    unsigned controlword = 0;
    char statusword[8] = "null"; /* 0x6041 as the master reads it, where the drive has one */
    if (co_od_find_entry(sn->node->od, 0x6041u) != NULL) {
        snprintf(statusword, sizeof statusword, "%u",
                 (unsigned)co_od_get_u16(sn->node, 0x6041u, 0u));
    }
    if (sn->desc != NULL) {
        const co_drive *d = &sn->drive;
        json_str(state, sizeof state, co_cia402_state_name(d->state));
        if (d->fault_emcy != 0u) {
            const co_drive_trip *row = d->fault_trip != 0u
                                           ? co_drive_find_trip(sn->desc, d->fault_trip)
                                           : co_drive_find_emcy(sn->desc, d->fault_emcy);
            char name[40] = "null";
            if (row != NULL && row->name != NULL) {
                json_str(name, sizeof name, row->name);
            }
            snprintf(fault, sizeof fault, "{\"trip\":%u,\"emcy\":%u,\"name\":%s,\"cause\":%s}",
                     (unsigned)d->fault_trip, (unsigned)d->fault_emcy, name,
                     d->fault_cause ? "true" : "false");
        }
        target = (long)d->target;
        actual = (long)d->motor.actual;
        load = d->motor.load;
        controlword = d->controlword;
    }
    snprintf(buf, cap,
             "{\"node\":%u,\"drive\":%s,\"iface\":%s,\"nmt\":%s,\"state\":%s,"
             "\"controlword\":%u,\"statusword\":%s,\"target\":%ld,\"actual\":%ld,\"load\":%u,"
             "\"fault\":%s,\"rx\":%u,\"tx\":%u,\"rx_malformed\":%u,\"tx_dropped\":%u,"
             "\"sdo_aborts\":%u,\"trips\":%u}",
             (unsigned)sn->node_id, drive, iface, nmt, state, controlword, statusword, target,
             actual, load, fault, (unsigned)st->rx_frames, (unsigned)st->tx_frames,
             (unsigned)st->rx_malformed, (unsigned)st->tx_dropped, (unsigned)st->sdo_aborts, (unsigned)sn->trips_logged);
}
