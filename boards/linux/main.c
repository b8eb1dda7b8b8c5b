/* canopen-drive: simulated CANopen drives on a SocketCAN interface.
 *
 *   canopen-drive --iface vcan0 --drive vf-s15 --node-id 5 [--drive ID --node-id N ...]
 *                 [--store FILE]
 *   canopen-drive --ecat-iface veth0 --drive vf-mb1-ecat [--drive vf-mb1-ecat ...]
 *
 * With --ecat-iface the drives are a line of EtherCAT slaves on an Ethernet interface
 * (ecat_port.h), addressed by position; stdin commands name them by position (1, 2, ...).
 *
 * `--drive bench` is no drive but a benchmark device (sim.h, SIM_BENCH_ID) for SDO throughput.
 *
 * Each drive is one co_node with its own raw CAN socket; one epoll loop runs them all. Commands
 * are read from standard input, one per line; NMT and drive state changes and faults are logged on
 * standard output, one line each. SIGINT/SIGTERM stop it with exit status 0. */
#define _GNU_SOURCE
#include <ctype.h>
#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <net/if.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "canopen/nmt.h"
#include "canopen/node.h"
#include "ecat_port.h"
#include "file_store.h"
#include "loop.h"
#include "sim.h"
#include "socketcan.h"

#define PROG "canopen-drive"
#define MAX_NODES 127u
#define EXIT_USAGE 2
#define MAX_SETTINGS 8u

typedef struct app {
    const char *iface;
    const char *store_path;
    sim_node *nodes[MAX_NODES];
    size_t node_count;
    file_store store;
    bool have_store;
    loop lp;
    bool loop_ready;
    const char *ecat_iface;  /* --ecat-iface: the drives are an EtherCAT line */
    ecat_port ecat;
    bool ecat_open;
    loop_member ecat_member;
} app;

static void usage(FILE *out)
{
    fprintf(out,
            "usage: " PROG " --iface IFACE --drive ID --node-id N [--set NAME=VALUE ...]\n"
            "                     [--drive ID --node-id N ...] [--store FILE]\n"
            "                     [--sdo-timeout MS]\n"
            "       " PROG " --ecat-iface IFACE --drive vf-mb1-ecat [--drive vf-mb1-ecat ...]\n"
            "                     [--store FILE]\n"
            "       " PROG " --list-drives\n"
            "       " PROG " --help\n"
            "\n"
            "Simulates CANopen drives on a SocketCAN interface (e.g. vcan0): each --drive/--node-id\n"
            "pair is one slave with the drive's object dictionary, PDOs, CiA 402 state machine and\n"
            "fault codes. Without kernel CAN, run it through tools/vcan-run.\n"
            "\n"
            "  -i, --iface IFACE    CAN interface to attach to\n"
            "      --ecat-iface IFACE  Ethernet interface: the drives are a line of EtherCAT\n"
            "                       slaves there (raw EtherType 0x88A4, needs CAP_NET_RAW; e.g.\n"
            "                       one end of a veth pair, see tools/veth-run), in --drive order,\n"
            "                       addressed by position 1, 2, ... (no --node-id)\n"
            "  -d, --drive ID       drive to simulate (see --list-drives); repeatable; 'bench'\n"
            "                       is a benchmark device, not a drive (a 1 MiB DOMAIN 0x2000)\n"
            "  -n, --node-id N      its node-ID, 1..127 (decimal or 0x..); the k-th --node-id\n"
            "                       belongs to the k-th --drive\n"
            "      --set NAME=VALUE a setting of the preceding --drive that has no object (see\n"
            "                       --list-drives)\n"
            "  -s, --store FILE     keep the values stored with 0x1010 in FILE (one file for all\n"
            "                       nodes, keyed by node-ID and drive; written atomically; one\n"
            "                       process per FILE, locked with FILE.lock); without it, 0x1010\n"
            "                       store commands are refused (0x08000020)\n"
            "      --sdo-timeout MS an SDO transfer with no frame of the client for MS\n"
            "                       milliseconds is aborted (0x05040000); 1..2147483, default\n"
            "                       1000 (every node; a slow master or a busy machine needs more)\n"
            "      --list-drives    print the drive ids and exit\n"
            "  -h, --help           print this help and exit\n"
            "\n"
            "Commands on standard input, one per line:\n"
            "(on an EtherCAT line NODE is the slave's position, 1 = next to the master)\n"
            "  fault NODE TRIP      raise the drive's trip code TRIP (e.g. fault 5 0x01)\n"
            "  clear NODE           the fault's cause is gone (the master must still reset it)\n"
            "  status [NODE]        print the NMT and drive state of one or every node\n"
            "  nmt NODE CMD         local NMT command: start, stop, preop, reset-node, reset-comm\n"
            "  help                 list the commands\n"
            "  quit                 stop (as SIGINT/SIGTERM do)\n"
            "\n"
            "Exit status: 0 after quit, SIGINT or SIGTERM; 1 on a run-time failure; 2 on a usage\n"
            "error.\n");
}

static int usage_error(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, PROG ": ");
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, "\nTry '" PROG " --help'.\n");
    return EXIT_USAGE;
}

/* Strict integer parsing: decimal or 0x hex (never octal: "010" is ten), the whole string,
 * within [lo, hi]. */
static bool parse_uint(const char *s, unsigned long lo, unsigned long hi, unsigned long *out)
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

/* --- loop callbacks ---------------------------------------------------------------------------- */

static void refresh_filters(sim_node *sn)
{
    uint16_t ids[SC_MAX_FILTERS];
    if (sn->port.fd < 0) {
        sn->refilter = false; /* no CAN face (EtherCAT line) */
        return;
    }
    size_t n = sc_node_cob_ids(sim_co_node(sn), ids, SC_MAX_FILTERS);
    if (sc_set_filters(&sn->port, ids, n) != 0) {
        fprintf(stderr, PROG ": node %u: cannot set receive filters: %s\n",
                (unsigned)sn->node_id, strerror(errno));
    }
    sn->refilter = false;
}

/* An SDO download or an NMT command may move a COB-ID (an RPDO, the SYNC, a monitored
 * heartbeat). The node's answer is held back until the receive filters follow, so a master that
 * uses the new COB-ID as soon as it has the answer never finds it filtered out. */
static void begin_filter_change(sim_node *sn)
{
    sn->port.hold = true;
}

static void end_filter_change(sim_node *sn)
{
    refresh_filters(sn);
    sn->port.hold = false;
    co_node_tx_ready(sim_co_node(sn));
}

static void node_rx(void *ctx, const co_frame *frame, uint64_t now)
{
    sim_node *sn = ctx;
    bool may_move = frame->id == 0u || frame->id == sim_co_node(sn)->sdo_rx_cob;
    if (may_move) {
        begin_filter_change(sn);
    }
    sim_rx(sn, frame, now);
    if (may_move) {
        end_filter_change(sn);
    }
}

static uint64_t node_process(void *ctx, uint64_t now)
{
    sim_node *sn = ctx;
    uint64_t next = sim_process(sn, now);
    if (sn->refilter) {
        refresh_filters(sn);
    }
    return next;
}

static void node_tx_ready(void *ctx, uint64_t now)
{
    sim_node *sn = ctx;
    (void)now;
    co_node_tx_ready(sim_co_node(sn));
}

static void node_bus_event(void *ctx, sc_bus_event event, uint64_t now)
{
    sim_bus_event(ctx, event, now); /* logs it too */
}

/* --- commands on standard input ---------------------------------------------------------------- */

static sim_node *find_node(app *a, const char *arg)
{
    unsigned long id;
    if (!parse_uint(arg, 1, 127, &id)) {
        char shown[SIM_SHOW_BUF];
        fprintf(stderr, PROG ": '%s' is not a %s (1..%u)\n",
                sim_show(arg != NULL ? arg : "", shown, sizeof shown),
                a->ecat_iface != NULL ? "slave position" : "node-ID",
                a->ecat_iface != NULL ? (unsigned)a->node_count : 127u);
        return NULL;
    }
    for (size_t i = 0; i < a->node_count; i++) {
        if (a->nodes[i]->node_id == id) {
            return a->nodes[i];
        }
    }
    fprintf(stderr, PROG ": no %s %lu here (%ss:", a->ecat_iface != NULL ? "slave" : "node", id,
            a->ecat_iface != NULL ? "slave" : "node");
    for (size_t i = 0; i < a->node_count; i++) {
        fprintf(stderr, " %u", (unsigned)a->nodes[i]->node_id);
    }
    fprintf(stderr, ")\n");
    return NULL;
}

static void command_help(void)
{
    printf("commands: fault NODE TRIP | clear NODE | status [NODE] | nmt NODE "
           "start|stop|preop|reset-node|reset-comm | help | quit\n");
    fflush(stdout);
}

static void on_line(void *ctx, char *line, uint64_t now)
{
    app *a = ctx;
    char *words[5];
    size_t n = 0;
    char *save = NULL;
    for (char *w = strtok_r(line, " \t\r", &save); w != NULL; w = strtok_r(NULL, " \t\r", &save)) {
        if (n == sizeof words / sizeof words[0]) {
            n++;
            break;
        }
        words[n++] = w;
    }
    if (n == 0u || words[0][0] == '#') {
        return;
    }
    const char *cmd = words[0];
    char shown[SIM_SHOW_BUF];
    if (strcmp(cmd, "quit") == 0 || strcmp(cmd, "exit") == 0) {
        if (n != 1u) {
            fprintf(stderr, PROG ": usage: %s (no arguments)\n", cmd);
            return;
        }
        loop_stop(&a->lp);
    } else if (strcmp(cmd, "help") == 0) {
        if (n != 1u) {
            fprintf(stderr, PROG ": usage: help (no arguments)\n");
            return;
        }
        command_help();
    } else if (strcmp(cmd, "fault") == 0) {
        unsigned long trip;
        if (n != 3u) {
            fprintf(stderr, PROG ": usage: fault NODE TRIP (e.g. fault 5 0x01)\n");
            return;
        }
        sim_node *sn = find_node(a, words[1]);
        if (sn == NULL) {
            return;
        }
        if (!parse_uint(words[2], 0, 0xFFFFFFFFul, &trip)) {
            fprintf(stderr, PROG ": '%s' is not a trip code (decimal or 0x..)\n",
                    sim_show(words[2], shown, sizeof shown));
            return;
        }
        sim_fault(sn, (uint32_t)trip, now);
    } else if (strcmp(cmd, "clear") == 0) {
        if (n != 2u) {
            fprintf(stderr, PROG ": usage: clear NODE\n");
            return;
        }
        sim_node *sn = find_node(a, words[1]);
        if (sn != NULL) {
            sim_clear(sn, now);
        }
    } else if (strcmp(cmd, "status") == 0) {
        if (n > 2u) {
            fprintf(stderr, PROG ": usage: status [NODE]\n");
            return;
        }
        for (size_t i = 0; i < a->node_count; i++) {
            sim_node *sn = n == 2u ? find_node(a, words[1]) : a->nodes[i];
            if (sn == NULL) {
                return;
            }
            sim_status(sn);
            if (a->ecat_open) {
                ecat_port_status(&a->ecat, ecat_port_slot(&a->ecat, sn->node_id));
            }
            if (n == 2u) {
                break;
            }
        }
    } else if (strcmp(cmd, "nmt") == 0) {
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
        if (n != 3u) {
            fprintf(stderr, PROG ": usage: nmt NODE start|stop|preop|reset-node|reset-comm\n");
            return;
        }
        sim_node *sn = find_node(a, words[1]);
        if (sn == NULL) {
            return;
        }
        if (a->ecat_iface != NULL) {
            fprintf(stderr, PROG ": slave %u is on EtherCAT: its state follows the master's AL "
                            "control requests, not NMT commands\n", (unsigned)sn->node_id);
            return;
        }
        for (size_t i = 0; i < sizeof nmt_cmds / sizeof nmt_cmds[0]; i++) {
            if (strcmp(words[2], nmt_cmds[i].name) == 0) {
                begin_filter_change(sn);
                co_nmt_command_local(sim_co_node(sn), nmt_cmds[i].command, now);
                end_filter_change(sn);
                return;
            }
        }
        fprintf(stderr, PROG ": unknown NMT command '%s' (start, stop, preop, reset-node, "
                        "reset-comm)\n", sim_show(words[2], shown, sizeof shown));
    } else {
        fprintf(stderr, PROG ": unknown command '%s' (try 'help')\n",
                sim_show(cmd, shown, sizeof shown));
    }
}

/* --- start-up ---------------------------------------------------------------------------------- */

static void list_drives(void)
{
    printf("%-20s %s\n", SIM_BENCH_ID,
           "benchmark device, not a drive: DS301 dictionary od/bench, DOMAIN 0x2000 stores up to "
           "1 MiB (SDO throughput)");
    for (size_t i = 0; i < co_drive_registry_count(); i++) {
        const co_drive_desc *desc = co_drive_registry_at(i);
        printf("%-20s %s\n", desc->id, desc->title);
        for (uint8_t k = 0; k < desc->setting_count; k++) {
            const co_drive_setting *st = &desc->settings[k];
            printf("%-20s   --set %s=%ld (%ld..%ld): %s\n", "", st->name, (long)st->def,
                   (long)st->min, (long)st->max, st->help);
        }
    }
}

/* "id1, id2, ..." for messages. */
static const char *drive_ids(char *buf, size_t cap)
{
    size_t pos = 0;
    buf[0] = '\0';
    for (size_t i = 0; i < co_drive_registry_count() && pos < cap; i++) {
        int n = snprintf(buf + pos, cap - pos, "%s%s", i != 0u ? ", " : "",
                         co_drive_registry_at(i)->id);
        if (n < 0) {
            break;
        }
        pos += (size_t)n;
    }
    return buf;
}

static void free_app(app *a)
{
    for (size_t i = 0; i < a->node_count; i++) {
        sim_node_destroy(a->nodes[i]);
    }
    a->node_count = 0;
    if (a->have_store) {
        file_store_close(&a->store);
    }
    if (a->ecat_open) {
        ecat_port_close(&a->ecat);
        a->ecat_open = false;
    }
}

/* --- the EtherCAT line ------------------------------------------------------------------------- */

static void ecat_input(void *ctx, uint64_t now)
{
    app *a = ctx;
    ecat_port_input(&a->ecat, now);
}

static uint64_t ecat_process(void *ctx, uint64_t now)
{
    app *a = ctx;
    return ecat_port_process(&a->ecat, now);
}

/* --ecat-iface: the drives as a line of EtherCAT slaves, positions 1.. in --drive order. */
static int run_ecat(app *a, const char *const drives[], size_t drive_count, size_t id_count,
                    const char **const settings[], const size_t setting_count[])
{
    if (id_count != 0u) {
        return usage_error("--node-id with --ecat-iface: EtherCAT slaves are addressed by their "
                           "position on the line (1, 2, ... in --drive order)");
    }
    if (drive_count == 0u) {
        return usage_error("no drive given (e.g. --ecat-iface veth0 --drive %s)",
                           ecat_drive_ids());
    }
    if (drive_count > ECAT_PORT_MAX_SLAVES) {
        return usage_error("more than %u drives on one EtherCAT line", ECAT_PORT_MAX_SLAVES);
    }
    for (size_t i = 0; i < drive_count; i++) {
        if (!ecat_drive_supported(drives[i])) {
            return usage_error("drive '%s' has no EtherCAT face (EtherCAT drives: %s)", drives[i],
                               ecat_drive_ids());
        }
    }
    char err[256];
    if (a->store_path != NULL) {
        if (!file_store_open(&a->store, a->store_path)) {
            return 1;
        }
        a->have_store = true;
    }
    if (ecat_port_open(&a->ecat, a->ecat_iface, err, sizeof err) != 0) {
        fprintf(stderr, PROG ": %s\n", err);
        return 1;
    }
    a->ecat_open = true;
    if (ecat_port_iface_up(&a->ecat) == 0) {
        fprintf(stderr, PROG ": warning: interface %s is down: no frame arrives until it is up "
                        "(ip link set %s up)\n", a->ecat_iface, a->ecat_iface);
    }
    if (loop_init(&a->lp) != 0) {
        fprintf(stderr, PROG ": cannot set up the event loop: %s\n", strerror(errno));
        return 1;
    }
    a->loop_ready = true;
    for (size_t i = 0; i < drive_count; i++) {
        file_store *store = a->have_store ? &a->store : NULL;
        sim_node *sn = sim_node_create(co_drive_registry_find(drives[i]), (uint8_t)(i + 1u),
                                       store, err, sizeof err);
        if (sn == NULL) {
            fprintf(stderr, PROG ": slave %zu %s: %s\n", i + 1u, drives[i], err);
            return 1;
        }
        sn->label = "slave";
        a->nodes[a->node_count++] = sn;
        for (size_t k = 0; k < setting_count[i]; k++) {
            if (!sim_set(sn, settings[i][k], err, sizeof err)) {
                return usage_error("%s", err);
            }
        }
        if (ecat_port_add(&a->ecat, drives[i], &sn->drive, err, sizeof err) != 0) {
            fprintf(stderr, PROG ": slave %zu: %s\n", i + 1u, err);
            return 1;
        }
        sn->member.port = NULL; /* no CAN face: the drive runs on its deadlines only */
        sn->member.fd = -1;
        sn->member.ctx = sn;
        sn->member.process = node_process;
        if (loop_add(&a->lp, &sn->member) != 0) {
            fprintf(stderr, PROG ": epoll: %s\n", strerror(errno));
            return 1;
        }
    }
    a->ecat_member.port = NULL;
    a->ecat_member.fd = a->ecat.fd;
    a->ecat_member.ctx = a;
    a->ecat_member.input = ecat_input;
    a->ecat_member.process = ecat_process;
    if (loop_add(&a->lp, &a->ecat_member) != 0) {
        fprintf(stderr, PROG ": epoll: %s\n", strerror(errno));
        return 1;
    }
    if (loop_watch_stdin(&a->lp, STDIN_FILENO, on_line, a) != 0) {
        fprintf(stderr, PROG ": cannot watch standard input: %s (commands disabled)\n",
                strerror(errno));
    }
    uint64_t now = loop_now();
    for (size_t i = 0; i < a->node_count; i++) {
        sim_start(a->nodes[i], now);
    }
    if (ecat_port_start(&a->ecat, now, err, sizeof err) != 0) {
        fprintf(stderr, PROG ": %s\n", err);
        return 1;
    }
    printf("canopen-drive: %zu EtherCAT slave(s) on %s%s%s, ready\n", a->node_count,
           a->ecat_iface, a->have_store ? ", store " : "", a->have_store ? a->store_path : "");
    fflush(stdout);
    int rc = loop_run(&a->lp) == 0 ? 0 : 1;
    if (a->lp.signal != 0) {
        printf("canopen-drive: %s, stopping\n", strsignal(a->lp.signal));
    } else {
        printf("canopen-drive: stopping\n");
    }
    fflush(stdout);
    return rc;
}

/* Parses the command line and runs the simulator; main() frees what it set up. */
static int run(app *a, int argc, char **argv)
{
    static const struct option options[] = {
        {"iface", required_argument, NULL, 'i'},
        {"ecat-iface", required_argument, NULL, 'E'},
        {"drive", required_argument, NULL, 'd'},
        {"node-id", required_argument, NULL, 'n'},
        {"store", required_argument, NULL, 's'},
        {"set", required_argument, NULL, 'S'},
        {"sdo-timeout", required_argument, NULL, 'T'},
        {"list-drives", no_argument, NULL, 'L'},
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0},
    };
    const char *drives[MAX_NODES];
    unsigned long ids[MAX_NODES];
    static const char *setting_args[MAX_NODES * MAX_SETTINGS];
    const char **settings[MAX_NODES];
    size_t setting_count[MAX_NODES];
    size_t drive_count = 0, id_count = 0;
    unsigned long sdo_timeout_ms = 0; /* 0: the core's default */
    opterr = 0;
    int c;
    char shown[SIM_SHOW_BUF]; /* a word of the command line, as messages repeat it */
    while ((c = getopt_long(argc, argv, ":i:d:n:s:h", options, NULL)) != -1) {
        /* "--drive --node-id 5": the value is missing, not a drive named "--node-id". */
        if (optarg != NULL && strncmp(optarg, "--", 2) == 0) {
            return usage_error("option '%s' needs a value",
                               sim_show(argv[optind - 2], shown, sizeof shown));
        }
        switch (c) {
        case 'i':
            if (a->iface != NULL) {
                return usage_error("--iface given twice (one process serves one interface)");
            }
            if (*optarg == '\0' || strlen(optarg) >= IFNAMSIZ) {
                return usage_error("'%s' is not an interface name (1 to %d characters)",
                                   sim_show(optarg, shown, sizeof shown), IFNAMSIZ - 1);
            }
            a->iface = optarg;
            break;
        case 'E':
            if (a->ecat_iface != NULL) {
                return usage_error("--ecat-iface given twice (one process serves one line)");
            }
            if (*optarg == '\0' || strlen(optarg) >= IFNAMSIZ) {
                return usage_error("'%s' is not an interface name (1 to %d characters)",
                                   sim_show(optarg, shown, sizeof shown), IFNAMSIZ - 1);
            }
            a->ecat_iface = optarg;
            break;
        case 'd':
            if (drive_count == MAX_NODES) {
                return usage_error("more than %u drives", MAX_NODES);
            }
            if (co_drive_registry_find(optarg) == NULL && strcmp(optarg, SIM_BENCH_ID) != 0) {
                char known[512];
                return usage_error("unknown drive '%s' (known: %s; and the benchmark device "
                                   SIM_BENCH_ID ")", sim_show(optarg, shown, sizeof shown),
                                   drive_ids(known, sizeof known));
            }
            settings[drive_count] = NULL;
            setting_count[drive_count] = 0;
            drives[drive_count++] = optarg;
            break;
        case 'n':
            if (id_count == MAX_NODES) {
                return usage_error("more than %u node-IDs", MAX_NODES);
            }
            if (!parse_uint(optarg, 1, 127, &ids[id_count])) {
                return usage_error("node-ID '%s' is not a number in 1..127",
                                   sim_show(optarg, shown, sizeof shown));
            }
            for (size_t k = 0; k < id_count; k++) {
                if (ids[k] == ids[id_count]) {
                    return usage_error("node-ID %lu given twice", ids[id_count]);
                }
            }
            id_count++;
            break;
        case 'S':
            if (drive_count == 0u) {
                return usage_error("--set %s: give it after the --drive it is for",
                                   sim_show(optarg, shown, sizeof shown));
            }
            if (setting_count[drive_count - 1u] == MAX_SETTINGS) {
                return usage_error("too many --set for one drive");
            }
            if (settings[drive_count - 1u] == NULL) {
                settings[drive_count - 1u] = &setting_args[(drive_count - 1u) * MAX_SETTINGS];
            }
            settings[drive_count - 1u][setting_count[drive_count - 1u]++] = optarg;
            break;
        case 's':
            if (a->store_path != NULL) {
                return usage_error("--store given twice");
            }
            if (*optarg == '\0') {
                return usage_error("--store needs a file name");
            }
            if (strlen(optarg) >= PATH_MAX) {
                return usage_error("--store '%s': a file name of %zu bytes is longer than any "
                                   "path (%d)", sim_show(optarg, shown, sizeof shown),
                                   strlen(optarg), PATH_MAX - 1);
            }
            a->store_path = optarg;
            break;
        case 'T':
            /* co_node's times are below 2^31 us (the 32-bit time base of the firmware builds) */
            if (!parse_uint(optarg, 1, 2147483ul, &sdo_timeout_ms)) {
                return usage_error("--sdo-timeout '%s' is not a number of milliseconds in "
                                   "1..2147483", sim_show(optarg, shown, sizeof shown));
            }
            break;
        case 'L':
            list_drives();
            return 0;
        case 'h':
            usage(stdout);
            return 0;
        case ':':
            return usage_error("option '%s' needs a value",
                               sim_show(argv[optind - 1], shown, sizeof shown));
        default:
            return usage_error("unknown option '%s'",
                               sim_show(argv[optind - 1], shown, sizeof shown));
        }
    }
    if (optind < argc) {
        return usage_error("unexpected argument '%s'", sim_show(argv[optind], shown, sizeof shown));
    }
    if (a->iface != NULL && a->ecat_iface != NULL) {
        return usage_error("--iface and --ecat-iface together: one process serves one CAN "
                           "interface or one EtherCAT line");
    }
    if (a->ecat_iface != NULL && sdo_timeout_ms != 0u) {
        return usage_error("--sdo-timeout applies to the CAN SDO server, not to CoE over "
                           "--ecat-iface");
    }
    if (a->ecat_iface != NULL) {
        return run_ecat(a, drives, drive_count, id_count, settings, setting_count);
    }
    if (a->iface == NULL) {
        return usage_error("--iface is required (e.g. --iface vcan0; or --ecat-iface for "
                           "EtherCAT)");
    }
    if (drive_count == 0u) {
        return usage_error("no drive given (e.g. --drive vf-s15 --node-id 5)");
    }
    if (drive_count != id_count) {
        return usage_error("%zu --drive but %zu --node-id: give one node-ID per drive",
                           drive_count, id_count);
    }

    if (a->store_path != NULL) {
        if (!file_store_open(&a->store, a->store_path)) {
            return 1; /* in use by another process, not a file, ...: said on stderr */
        }
        a->have_store = true;
    }
    if (loop_init(&a->lp) != 0) {
        fprintf(stderr, PROG ": cannot set up the event loop: %s\n", strerror(errno));
        return 1;
    }
    a->loop_ready = true;
    for (size_t i = 0; i < drive_count; i++) {
        char err[256];
        file_store *store = a->have_store ? &a->store : NULL;
        const co_drive_desc *desc = co_drive_registry_find(drives[i]);
        sim_node *sn = desc != NULL
                           ? sim_node_create(desc, (uint8_t)ids[i], store, err, sizeof err)
                           : sim_bench_create((uint8_t)ids[i], store, err, sizeof err);
        if (sn == NULL) {
            fprintf(stderr, PROG ": node %lu %s: %s\n", ids[i], drives[i], err);
            return 1;
        }
        a->nodes[a->node_count++] = sn;
        if (sdo_timeout_ms != 0u) {
            sim_co_node(sn)->sdo.timeout_us = (uint32_t)(sdo_timeout_ms * 1000u);
        }
        for (size_t k = 0; k < setting_count[i]; k++) {
            if (!sim_set(sn, settings[i][k], err, sizeof err)) {
                return usage_error("%s", err);
            }
        }
        if (sc_open(&sn->port, a->iface, err, sizeof err) != 0) {
            fprintf(stderr, PROG ": %s\n", err);
            return 1;
        }
        if (i == 0u && sc_iface_is_up(sn->port.fd, a->iface) == 0) {
            /* not an error: the frames wait (the port retries) until someone brings it up */
            fprintf(stderr,
                    PROG ": warning: interface %s is down: nothing is sent or received until it "
                         "is up (ip link set %s up)\n",
                    a->iface, a->iface);
        }
        sn->member.port = &sn->port;
        sn->member.ctx = sn;
        sn->member.rx = node_rx;
        sn->member.bus_event = node_bus_event;
        sn->member.process = node_process;
        sn->member.tx_ready = node_tx_ready;
        if (loop_add(&a->lp, &sn->member) != 0) {
            fprintf(stderr, PROG ": epoll: %s\n", strerror(errno));
            return 1;
        }
    }
    if (loop_watch_stdin(&a->lp, STDIN_FILENO, on_line, a) != 0) {
        fprintf(stderr, PROG ": cannot watch standard input: %s (commands disabled)\n",
                strerror(errno));
    }
    /* Each boot-up goes out once the filters hold the node's COB-IDs (stored ones may differ
     * from the defaults). */
    uint64_t now = loop_now();
    for (size_t i = 0; i < a->node_count; i++) {
        begin_filter_change(a->nodes[i]);
        sim_start(a->nodes[i], now);
        end_filter_change(a->nodes[i]);
    }
    printf("canopen-drive: %zu node(s) on %s%s%s, ready\n", a->node_count, a->iface,
           a->have_store ? ", store " : "", a->have_store ? a->store_path : "");
    fflush(stdout);

    int rc = loop_run(&a->lp) == 0 ? 0 : 1;
    if (a->lp.signal != 0) {
        printf("canopen-drive: %s, stopping\n", strsignal(a->lp.signal));
    } else {
        printf("canopen-drive: stopping\n");
    }
    fflush(stdout);
    return rc;
}

int main(int argc, char **argv)
{
    setvbuf(stdout, NULL, _IOLBF, 0); /* one log line reaches a pipe as soon as it is written */
    app *a = calloc(1, sizeof *a);
    if (a == NULL) {
        fprintf(stderr, PROG ": out of memory\n");
        return 1;
    }
    int rc = run(a, argc, argv);
    if (a->loop_ready) {
        loop_close(&a->lp);
    }
    free_app(a);
    free(a);
    return rc;
}
