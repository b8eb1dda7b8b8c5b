/* One simulated node: co_drive + socket + store slot, and its log lines. */
#define _GNU_SOURCE
#include "sim.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "canopen/cia402.h"
#include "canopen/errctl.h"
#include "canopen/nmt.h"

void sim_log(const sim_node *sn, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    printf("node %u %s: ", (unsigned)sn->node_id, sn->desc->id);
    vprintf(fmt, ap);
    va_end(ap);
    putchar('\n');
    fflush(stdout);
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
    const co_drive_trip *row = d->fault_trip != 0u ? drive_find_trip(sn->desc, d->fault_trip)
                                                   : NULL;
    if (row == NULL) {
        row = drive_find_emcy(sn->desc, d->fault_emcy);
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

sim_node *sim_node_create(const co_drive_desc *desc, uint8_t node_id, file_store *store,
                          char *err, size_t err_len)
{
    sim_node *sn = calloc(1, sizeof *sn);
    if (sn == NULL) {
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    sn->node_id = node_id;
    sn->desc = desc;
    sn->port.fd = -1;
    const co_od *od = desc->od;
    size_t block = ((size_t)od->value_size + 7u) & ~(size_t)7u;
    sn->values = aligned_alloc(8, block != 0u ? block : 8u);
    sn->scratch = malloc(od->persist_size != 0u ? od->persist_size : 1u);
    if (sn->values == NULL || sn->scratch == NULL) {
        sim_node_destroy(sn);
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    memset(sn->values, 0, block);
    co_node_config cfg = co_node_default_config();
    cfg.od = od;
    cfg.values = sn->values;
    cfg.node_id = node_id;
    cfg.driver.send = sc_send;
    cfg.driver.ctx = &sn->port;
    if (store != NULL) {
        sn->storage = file_store_storage(store, &sn->slot, node_id, desc->id);
        cfg.storage = &sn->storage;
        cfg.store_scratch = sn->scratch;
        cfg.store_scratch_size = od->persist_size;
    }
    cfg.events.nmt_changed = on_nmt_changed;
    cfg.events.reset = on_reset;
    cfg.events.comm = on_comm;
    cfg.events.ctx = sn;
    if (!drive_init(&sn->drive, desc, &cfg)) {
        snprintf(err, err_len, "the drive refused the node configuration");
        sim_node_destroy(sn);
        return NULL;
    }
    co_drive_observer observer = {on_state_changed, sn};
    drive_observe(&sn->drive, &observer);
    return sn;
}

void sim_node_destroy(sim_node *sn)
{
    if (sn == NULL) {
        return;
    }
    sc_close(&sn->port);
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
        snprintf(err, err_len, "--set wants NAME=VALUE, not '%s'", assignment);
        return false;
    }
    memcpy(name, assignment, n);
    name[n] = '\0';
    const co_drive_setting *setting = NULL;
    for (uint8_t i = 0; i < sn->desc->setting_count; i++) {
        if (strcmp(sn->desc->settings[i].name, name) == 0) {
            setting = &sn->desc->settings[i];
        }
    }
    if (setting == NULL) {
        int pos = snprintf(err, err_len, "%s has no setting '%s'", sn->desc->id, name);
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
        !drive_set_setting(&sn->drive, name, (int32_t)value)) {
        snprintf(err, err_len, "%s setting %s=%s: not a number in %ld..%ld (%s)", sn->desc->id,
                 name, eq + 1, (long)setting->min, (long)setting->max, setting->help);
        return false;
    }
    return true;
}

void sim_start(sim_node *sn, uint64_t now)
{
    drive_start(&sn->drive, now);
    sn->started = true;
}

void sim_rx(sim_node *sn, const co_frame *frame, uint64_t now)
{
    drive_rx(&sn->drive, frame, now);
}

uint64_t sim_process(sim_node *sn, uint64_t now)
{
    return drive_process(&sn->drive, now);
}

void sim_bus_event(sim_node *sn, sc_bus_event event, uint64_t now)
{
    co_node *node = sim_co_node(sn);
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

void sim_fault(sim_node *sn, uint32_t trip, uint64_t now)
{
    uint32_t before = sn->trips_logged;
    if (trip > 0xFFFFu || !drive_inject_fault(&sn->drive, (uint16_t)trip, now)) {
        fprintf(stderr, "canopen-drive: node %u %s: no trip code 0x%02X in its table "
                        "(od/%s/faults.csv)\n",
                (unsigned)sn->node_id, sn->desc->id, (unsigned)trip, sn->desc->id);
        return;
    }
    if (sn->trips_logged == before) {
        log_trip(sn); /* already in FAULT: no transition 13 to log it */
    }
}

void sim_clear(sim_node *sn, uint64_t now)
{
    (void)now;
    drive_clear_fault_cause(&sn->drive);
    sim_log(sn, "fault cause cleared (a fault reset from the master now succeeds)");
}

void sim_status(sim_node *sn)
{
    co_drive *d = &sn->drive;
    co_node *node = sim_co_node(sn);
    const co_node_stats *st = &node->stats;
    char fault[64] = "none";
    if (d->fault_emcy != 0u) {
        snprintf(fault, sizeof fault, "EMCY 0x%04X%s", (unsigned)d->fault_emcy,
                 d->fault_cause ? " (cause present)" : " (cause gone)");
    }
    sim_log(sn,
            "NMT %s, %s %s, target %ld, actual %ld, fault %s; rx %u (malformed %u, ignored %u), "
            "tx %u (deferred %u, dropped %u), SDO aborts %u",
            co_nmt_state_name(node->nmt_state),
            sn->desc->profile == CO_DRIVE_PROFILE_CIA402 ? "CiA 402" : "state",
            co_cia402_state_name(d->state), (long)d->target, (long)d->motor.actual, fault,
            (unsigned)st->rx_frames, (unsigned)st->rx_malformed, (unsigned)st->rx_ignored,
            (unsigned)st->tx_frames, (unsigned)st->tx_deferred, (unsigned)st->tx_dropped,
            (unsigned)st->sdo_aborts);
}
