/* One simulated node of canopen-drive: a co_drive (its co_node, CiA 402 state machine and motor),
 * its CAN socket and its slot in the store file, glued together and logged. main.c owns the
 * process; this file owns one node.
 *
 * Besides the drives there is one benchmark device, `bench` (SIM_BENCH_ID): not a drive, a plain
 * co_node on the DS301-minimal dictionary od/bench whose DOMAIN 0x2000 is a RAM buffer of up to
 * SIM_BENCH_DOMAIN_CAP bytes: a download stores the bytes, an upload returns the last complete
 * download. It exists to measure SDO block/segmented throughput (tools/bench --vcan). */
#ifndef BOARDS_LINUX_SIM_H
#define BOARDS_LINUX_SIM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "canopen/drive.h"
#include "canopen/node.h"
#include "file_store.h"
#include "loop.h"
#include "socketcan.h"

/* The benchmark device's id on the command line (--drive bench). */
#define SIM_BENCH_ID "bench"
/* Largest DOMAIN 0x2000 download the benchmark device stores (bytes). */
#define SIM_BENCH_DOMAIN_CAP (1024u * 1024u)

typedef struct sim_node {
    uint8_t node_id;              /* on an EtherCAT line: the position (1-based) */
    const char *label;            /* "node", or "slave" on an EtherCAT line; for logs */
    const char *id;               /* drive id, or SIM_BENCH_ID; for logs */
    const co_drive_desc *desc;    /* NULL for the benchmark device */
    co_node *node;                /* &drive.node, or &bench_node */
    co_drive drive;               /* drives: holds the co_node (drive.node) */
    co_node bench_node;           /* benchmark device: its node (no drive layer) */
    uint8_t *domain;              /* benchmark device: DOMAIN 0x2000 (malloc'ed) */
    uint32_t domain_len;          /* bytes of the last complete download */
    uint8_t *values;              /* the node's value block (malloc'ed, 8-byte aligned) */
    uint8_t *scratch;             /* partial store/restore work area (0x1010/0x1011 sub 2-4) */
    sc_port port;
    file_store_slot slot;
    co_storage storage;
    loop_member member;
    bool refilter;                /* communication parameters may have changed */
    bool started;                 /* power-on done: later resets are logged */
    uint32_t trips_logged;        /* faults written to the log */
    uint32_t rx_lost_reported;    /* port drops already handed to the core */
    uint32_t overruns;            /* receive overrun events seen (status) */
    uint32_t overruns_unlogged;   /* of them, not yet in a log line */
    uint64_t overrun_logged_at;   /* when the latest "receive overrun" line was written */
    bool overrun_logged;          /* such a line was written */
    /* Called with every log line (without its newline) after it is printed: the control socket
     * forwards them to its subscribers. May be NULL. */
    void (*log_hook)(void *ctx, const char *line);
    void *log_ctx;
} sim_node;

/* Longest log line (longer ones are cut). */
#define SIM_LOG_MAX 768u

/* A bus that overruns logs at most one "receive overrun" line per node in this time (us); the
 * line counts the events since the previous one. */
#define SIM_OVERRUN_LOG_US 1000000u

/* Longest part of a user's word that messages repeat, and the buffer sim_show needs. */
#define SIM_SHOW_MAX 64u
#define SIM_SHOW_BUF (SIM_SHOW_MAX * 4u + 4u)

/* Text from the user (a command word, an argument) as a message may repeat it: a byte outside
 * printable ASCII becomes \xNN, a backslash \\, and beyond SIM_SHOW_MAX bytes of s it is cut
 * and ends in "...". Writes into buf (cap bytes, SIM_SHOW_BUF is enough) and returns it. */
const char *sim_show(const char *s, char *buf, size_t cap);

/* The node inside. */
static inline co_node *sim_co_node(sim_node *sn)
{
    return sn->node;
}

/* Creates a node of drive desc (not started, no socket yet). NULL with a reason in err on
 * failure. store may be NULL (no non-volatile storage). */
sim_node *sim_node_create(const co_drive_desc *desc, uint8_t node_id, file_store *store,
                          char *err, size_t err_len);
/* Creates the benchmark device (see SIM_BENCH_ID) with node-ID node_id, as sim_node_create. */
sim_node *sim_bench_create(uint8_t node_id, file_store *store, char *err, size_t err_len);
void sim_node_destroy(sim_node *sn);

/* Sets a drive setting (co_drive_desc.settings) from "NAME=VALUE". False with a reason (also for
 * the benchmark device, which has none). */
bool sim_set(sim_node *sn, const char *assignment, char *err, size_t err_len);

/* Power on: boot-up, PRE-OPERATIONAL, Switch on disabled. */
void sim_start(sim_node *sn, uint64_t now);
void sim_rx(sim_node *sn, const co_frame *frame, uint64_t now);
/* Runs the drive and its node; returns the next deadline. */
uint64_t sim_process(sim_node *sn, uint64_t now);
/* A bus event: logged (receive overruns at most once per SIM_OVERRUN_LOG_US, with their count)
 * and handed to the core. */
void sim_bus_event(sim_node *sn, sc_bus_event event, uint64_t now);
/* The operator's commands. False with a reason in err when refused: fault and clear refuse the
 * benchmark device (it has no trips), fault a trip code the drive's table lacks. */
bool sim_fault(sim_node *sn, uint32_t trip, uint64_t now, char *err, size_t err_len);
bool sim_clear(sim_node *sn, uint64_t now, char *err, size_t err_len);
/* A local NMT command by name: start, stop, preop, reset-node, reset-comm. The receive filters
 * follow before any answer leaves (sim_begin_filter_change). */
bool sim_nmt(sim_node *sn, const char *command, uint64_t now, char *err, size_t err_len);
/* The status line ("node N ID: NMT ..., counters") into buf, and printed on stdout. */
void sim_status_line(sim_node *sn, char *buf, size_t cap);
void sim_status(sim_node *sn);
/* The node's state as one JSON object (no newline): node, drive, iface, nmt, state (CiA 402 or
 * the drive's own state name; null for the benchmark device), controlword, statusword (0x6041,
 * null without one), target, actual,
 * fault (null or {trip, emcy, name, cause}), rx, tx, rx_malformed, tx_dropped, sdo_aborts,
 * trips (faults raised so far). SIM_LOG_MAX bytes are enough. */
void sim_state_json(sim_node *sn, char *buf, size_t cap);

/* Recomputes the receive filters from the node's communication parameters. */
void sim_refresh_filters(sim_node *sn);
/* An SDO download or an NMT command may move a COB-ID (an RPDO, the SYNC, a monitored
 * heartbeat). The node's answer is held back (begin) until the receive filters follow (end), so
 * a master that uses the new COB-ID as soon as it has the answer never finds it filtered out. */
void sim_begin_filter_change(sim_node *sn);
void sim_end_filter_change(sim_node *sn);

/* One line on stdout: "node N ID: <text>", flushed. */
void sim_log(const sim_node *sn, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

#endif
