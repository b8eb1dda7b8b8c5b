/* canopen-drive: simulated CANopen drives on a SocketCAN interface.
 *
 *   canopen-drive --iface vcan0 --drive vf-s15 --node-id 5 [--drive ID --node-id N ...]
 *                 [--store FILE]
 *   canopen-drive --ecat-iface veth0 --drive vf-mb1-ecat [--drive vf-mb1-ecat ...]
 *
 * With --ecat-iface the drives are a line of EtherCAT slaves on an Ethernet interface
 * (ecat_port.h), addressed by position; commands name them by position (1, 2, ...).
 *
 * `--drive bench` is no drive but a benchmark device (sim.h, SIM_BENCH_ID) for SDO throughput.
 *
 * Each drive is one co_node with its own raw CAN socket; one epoll loop runs them all, on one
 * or several interfaces. Commands (commands.c) are read from standard input, one per line, and
 * from the control socket (control.c, --control); NMT and drive state changes and faults are
 * logged on standard output, one line each, and sent to the control socket's subscribers.
 * --trace records the buses (trace.c), --scenario runs timed commands (scenario.c).
 * SIGINT/SIGTERM stop it with exit status 0. */
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

#include "canopen/drive/cia402.h"
#include "canopen/nmt.h"
#include "canopen/node.h"
#include "commands.h"
#include "ecat_port.h"
#include "control.h"
#include "scenario.h"
#include "trace.h"
#include "file_store.h"
#include "loop.h"
#include "sim.h"
#include "socketcan.h"

#define PROG "canopen-drive"
#define MAX_NODES 127u
#define EXIT_USAGE 2
#define MAX_SETTINGS 8u
#define MAX_IFACES TRACE_MAX_IFACES

typedef struct app {
    const char *ifaces[MAX_IFACES]; /* each --iface, in order */
    size_t iface_count;
    const char *trace_path;         /* --trace */
    const char *scenario_path;      /* --scenario */
    scenario *scn;                  /* NULL without one */
    trace tr;
    bool tracing;
    const char *store_path;
    sim_node *nodes[MAX_NODES];
    size_t node_count;
    file_store store;
    bool have_store;
    loop lp;
    bool loop_ready;
    const char *control_path;      /* --control */
    long control_tcp;              /* --control-tcp port, -1: none */
    control *ctl;                  /* NULL without a control socket */
    const char *ecat_iface;        /* --ecat-iface: the drives are an EtherCAT line */
    ecat_port ecat;
    bool ecat_open;
    loop_member ecat_member;
} app;

static void usage(FILE *out)
{
    fprintf(out,
            "usage: " PROG " --iface IFACE --drive ID --node-id N [--set NAME=VALUE ...]\n"
            "                     [--drive ID --node-id N ...] [--store FILE] [--control PATH]\n"
            "                     [--trace FILE] [--scenario FILE] [--control-tcp PORT]\n"
            "                     [--iface IFACE2 --drive ID --node-id N ...] [--sdo-timeout MS]\n"
            "       " PROG " --ecat-iface IFACE --drive vf-mb1-ecat [--drive vf-mb1-ecat ...]\n"
            "                     [--store FILE] [--control PATH] [--control-tcp PORT]\n"
            "                     [--scenario FILE]\n"
            "       " PROG " --list-drives\n"
            "       " PROG " --help\n"
            "\n"
            "Simulates CANopen drives on a SocketCAN interface (e.g. vcan0): each --drive/--node-id\n"
            "pair is one slave with the drive's object dictionary, PDOs, CiA 402 state machine and\n"
            "fault codes. Without kernel CAN, run it through tools/vcan-run.\n"
            "\n"
            "  -i, --iface IFACE    CAN interface to attach to (required); repeat it for several\n"
            "                       buses, each --iface followed by its drives (node-IDs stay\n"
            "                       unique in the process: commands name a node by its ID)\n"
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
            "      --scenario FILE  run the timed and conditional commands of FILE (README,\n"
            "                       \"Scenarios\"; examples in examples/scenarios)\n"
            "      --trace FILE     write every frame on the buses to FILE, candump -L format\n"
            "      --control PATH   also take commands on the Unix socket PATH (protocol: README,\n"
            "                       \"Control socket\"); several clients at once\n"
            "      --control-tcp PORT  the same on 127.0.0.1:PORT (0: any free port, printed)\n"
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
            "  state NODE           the same of one node as a JSON object\n"
            "  nodes                the nodes: node-ID, drive, interface\n"
            "  pdo NODE             its PDO layout in force (COB-IDs and mapping entries)\n"
            "  mute NODE            the node sends nothing (heartbeat, PDOs, answers); unmute NODE\n"
            "  mains NODE on|off    the drive's mains supply\n"
            "  load NODE PERCENT    load torque on the motor, 0..200 %% of rated (current, torque)\n"
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

/* An option naming a file (--store, --scenario, --trace): given once, a name that can be a path.
 * Stores arg in *slot and returns true, or prints why not and returns false. */
static bool take_file_name(const char **slot, const char *option, const char *arg)
{
    char shown[SIM_SHOW_BUF];
    if (*slot != NULL) {
        usage_error("%s given twice", option);
        return false;
    }
    if (*arg == '\0') {
        usage_error("%s needs a file name", option);
        return false;
    }
    if (strlen(arg) >= PATH_MAX) {
        usage_error("%s '%s': a file name of %zu bytes is longer than any path (%d)", option,
                    sim_show(arg, shown, sizeof shown), strlen(arg), PATH_MAX - 1);
        return false;
    }
    *slot = arg;
    return true;
}

/* --- loop callbacks ---------------------------------------------------------------------------- */

static void node_rx(void *ctx, const co_frame *frame, uint64_t now)
{
    sim_node *sn = ctx;
    bool may_move = frame->id == 0u || frame->id == sim_co_node(sn)->sdo_rx_cob;
    if (may_move) {
        sim_begin_filter_change(sn);
    }
    sim_rx(sn, frame, now);
    if (may_move) {
        sim_end_filter_change(sn);
    }
}

static uint64_t node_process(void *ctx, uint64_t now)
{
    sim_node *sn = ctx;
    uint64_t next = sim_process(sn, now);
    if (sn->refilter) {
        sim_refresh_filters(sn);
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

/* What commands act on: the nodes, the loop, and the EtherCAT line if there is one. */
static cmd_env app_env(app *a)
{
    cmd_env env = {a->nodes, a->node_count, &a->lp, a->ecat_open ? &a->ecat : NULL};
    return env;
}

/* Results on stdout, refusals on stderr. */
static void stdin_emit(void *ctx, cmd_emit_kind kind, const char *text)
{
    (void)ctx;
    if (kind == CMD_ERROR) {
        fprintf(stderr, PROG ": %s\n", text);
    } else {
        puts(text);
        fflush(stdout);
    }
}

static void on_line(void *ctx, char *line, uint64_t now)
{
    app *a = ctx;
    cmd_env env = app_env(a);
    (void)cmd_run(&env, line, now, stdin_emit, NULL, NULL);
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

/* The control socket(s) of --control and --control-tcp; every node's log lines become its
 * events. Returns 0, or -1 after saying why on stderr. */
static int open_control(app *a)
{
    char err[256];
    a->ctl = calloc(1, sizeof *a->ctl);
    if (a->ctl == NULL) {
        fprintf(stderr, PROG ": out of memory\n");
        return -1;
    }
    cmd_env env = app_env(a);
    control_init(a->ctl, &a->lp, &env, loop_now());
    if ((a->control_path != NULL && control_listen_unix(a->ctl, a->control_path, err,
                                                        sizeof err) != 0) ||
        (a->control_tcp >= 0 && control_listen_tcp(a->ctl, (unsigned)a->control_tcp, err,
                                                   sizeof err) != 0)) {
        fprintf(stderr, PROG ": %s\n", err);
        return -1;
    }
    for (size_t i = 0; i < a->node_count; i++) {
        a->nodes[i]->log_hook = control_event;
        a->nodes[i]->log_ctx = a->ctl;
    }
    return 0;
}

/* --- the scenario (scenario.h) ---------------------------------------------------------------- */

static sim_node *node_by_id(app *a, unsigned node)
{
    for (size_t i = 0; i < a->node_count; i++) {
        if (a->nodes[i]->node_id == node) {
            return a->nodes[i];
        }
    }
    return NULL;
}

static bool scenario_observe(void *ctx, unsigned node, scenario_view *view)
{
    sim_node *sn = node_by_id(ctx, node);
    if (sn == NULL || view == NULL) {
        return sn != NULL;
    }
    view->nmt = co_nmt_state_name(sim_co_node(sn)->nmt_state);
    if (sn->desc != NULL) {
        view->state = co_cia402_state_name(sn->drive.state);
        view->actual = (long)sn->drive.motor.actual;
        view->fault = sn->drive.fault_emcy != 0u;
    }
    return true;
}

static void scenario_run(void *ctx, const scenario_step *step, char *command, uint64_t now)
{
    app *a = ctx;
    char line[SIM_LOG_MAX];
    uint64_t t = now - a->scn->t0;
    snprintf(line, sizeof line, PROG ": scenario %s:%u at %lu.%06lu s: %s", a->scenario_path,
             step->line, (unsigned long)(t / 1000000u), (unsigned long)(t % 1000000u), command);
    puts(line);
    fflush(stdout);
    if (a->ctl != NULL) {
        control_event(a->ctl, line);
    }
    cmd_env env = app_env(a);
    (void)cmd_run(&env, command, now, stdin_emit, NULL, NULL);
}

static uint64_t scenario_ticker(void *ctx, uint64_t now)
{
    app *a = ctx;
    return scenario_tick(a->scn, now, scenario_observe, scenario_run, a);
}

/* Reads and checks --scenario FILE: 2 (usage error, said why) or 0. */
static int load_scenario(app *a)
{
    enum { MAX_FILE = 64 * 1024 };
    FILE *f = fopen(a->scenario_path, "r");
    char *text = malloc(MAX_FILE + 1);
    a->scn = malloc(sizeof *a->scn);
    if (f == NULL || text == NULL || a->scn == NULL) {
        int e = errno;
        if (f != NULL) {
            fclose(f);
        }
        free(text);
        return usage_error("--scenario %s: %s", a->scenario_path, strerror(e));
    }
    size_t len = fread(text, 1, MAX_FILE + 1, f);
    bool bad_read = ferror(f) != 0;
    fclose(f);
    if (bad_read || len > MAX_FILE || memchr(text, '\0', len) != NULL) {
        free(text);
        return usage_error("--scenario %s: %s", a->scenario_path,
                           bad_read ? "cannot be read" : len > MAX_FILE
                                                           ? "larger than 64 KiB"
                                                           : "holds a NUL byte: not a text file");
    }
    text[len] = '\0';
    char err[300];
    bool ok = scenario_parse(a->scn, text, a->scenario_path, scenario_observe, a, err, sizeof err);
    free(text);
    if (!ok) {
        fprintf(stderr, PROG ": scenario %s\n", err);
        return EXIT_USAGE;
    }
    return 0;
}

/* How many of the first n drives are on bus k. */
static size_t drives_on_iface(const size_t *drive_iface, size_t n, size_t k)
{
    size_t count = 0;
    for (size_t i = 0; i < n; i++) {
        count += drive_iface[i] == k ? 1u : 0u;
    }
    return count;
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

/* Runs the event loop until a signal or `quit`; returns the process's exit status. */
static int serve(app *a)
{
    int rc = loop_run(&a->lp) == 0 ? 0 : 1;
    if (a->lp.signal != 0) {
        printf("canopen-drive: %s, stopping\n", strsignal(a->lp.signal));
    } else {
        printf("canopen-drive: stopping\n");
    }
    fflush(stdout);
    return rc;
}

/* What a test engineer drives a running simulator with, on either kind of bus: the --scenario
 * ticker, the --control socket(s) and the commands on standard input. 0, or the exit status. */
static int add_instruments(app *a)
{
    if (a->scenario_path != NULL) {
        int rc = load_scenario(a);
        if (rc != 0) {
            return rc;
        }
        if (loop_add_ticker(&a->lp, scenario_ticker, a) != 0) {
            fprintf(stderr, PROG ": scenario: %s\n", strerror(errno));
            return 1;
        }
    }
    if (a->control_path != NULL || a->control_tcp >= 0) {
        if (open_control(a) != 0) {
            return 1;
        }
    }
    if (loop_watch_stdin(&a->lp, STDIN_FILENO, on_line, a) != 0) {
        fprintf(stderr, PROG ": cannot watch standard input: %s (commands disabled)\n",
                strerror(errno));
    }
    return 0;
}

/* The control sockets in the "ready" line, where clients find them. */
static void print_control(const app *a)
{
    if (a->ctl != NULL && a->ctl->unix_fd >= 0) {
        printf(", control %s", a->ctl->path);
    }
    if (a->ctl != NULL && a->ctl->tcp_fd >= 0) {
        printf(", control tcp 127.0.0.1:%u", a->ctl->tcp_port);
    }
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
        /* the interface it is reached on, as `nodes` and `state` report it (a name of at most
         * IFNAMSIZ - 1 characters, checked with --ecat-iface) */
        snprintf(sn->port.iface, sizeof sn->port.iface, "%s", a->ecat_iface);
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
    int rc = add_instruments(a);
    if (rc != 0) {
        return rc;
    }
    uint64_t now = loop_now();
    if (a->scn != NULL) {
        scenario_start(a->scn, now);
    }
    for (size_t i = 0; i < a->node_count; i++) {
        sim_start(a->nodes[i], now);
    }
    if (ecat_port_start(&a->ecat, now, err, sizeof err) != 0) {
        fprintf(stderr, PROG ": %s\n", err);
        return 1;
    }
    printf("canopen-drive: %zu EtherCAT slave(s) on %s%s%s", a->node_count, a->ecat_iface,
           a->have_store ? ", store " : "", a->have_store ? a->store_path : "");
    print_control(a);
    printf(", ready\n");
    fflush(stdout);
    return serve(a);
}

/* Parses the command line and runs the simulator; main() frees what it set up. */
static int run(app *a, int argc, char **argv)
{
    static const struct option options[] = {
        {"iface", required_argument, NULL, 'i'},
        {"trace", required_argument, NULL, 'R'},
        {"scenario", required_argument, NULL, 'P'},
        {"drive", required_argument, NULL, 'd'},
        {"node-id", required_argument, NULL, 'n'},
        {"store", required_argument, NULL, 's'},
        {"set", required_argument, NULL, 'S'},
        {"list-drives", no_argument, NULL, 'L'},
        {"control", required_argument, NULL, 'C'},
        {"control-tcp", required_argument, NULL, 'T'},
        {"ecat-iface", required_argument, NULL, 'E'},
        {"sdo-timeout", required_argument, NULL, 'O'},
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0},
    };
    const char *drives[MAX_NODES];
    unsigned long ids[MAX_NODES];
    static const char *setting_args[MAX_NODES * MAX_SETTINGS];
    const char **settings[MAX_NODES];
    size_t setting_count[MAX_NODES];
    size_t drive_iface[MAX_NODES]; /* index into a->ifaces; SIZE_MAX: given before any --iface */
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
            if (*optarg == '\0' || strlen(optarg) >= IFNAMSIZ) {
                return usage_error("'%s' is not an interface name (1 to %d characters)",
                                   sim_show(optarg, shown, sizeof shown), IFNAMSIZ - 1);
            }
            for (size_t k = 0; k < a->iface_count; k++) {
                if (strcmp(a->ifaces[k], optarg) == 0) {
                    return usage_error("--iface %s given twice (give each bus once, followed by "
                                       "its drives)", sim_show(optarg, shown, sizeof shown));
                }
            }
            if (a->iface_count == 1u && drive_count != 0u && drive_iface[0] == SIZE_MAX) {
                return usage_error("--drive %s comes before any --iface: with several buses, "
                                   "each --iface is followed by its drives",
                                   sim_show(drives[0], shown, sizeof shown));
            }
            if (a->iface_count == MAX_IFACES) {
                return usage_error("more than %u --iface", (unsigned)MAX_IFACES);
            }
            if (a->iface_count != 0u && drives_on_iface(drive_iface, drive_count,
                                                        a->iface_count - 1u) == 0u) {
                return usage_error("--iface %s has no --drive (each --iface is followed by its "
                                   "drives)", a->ifaces[a->iface_count - 1u]);
            }
            a->ifaces[a->iface_count++] = optarg;
            break;
        case 'P':
            if (!take_file_name(&a->scenario_path, "--scenario", optarg)) {
                return EXIT_USAGE;
            }
            break;
        case 'R':
            if (!take_file_name(&a->trace_path, "--trace", optarg)) {
                return EXIT_USAGE;
            }
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
            /* the bus of the latest --iface; before any, the first one given (one bus) */
            drive_iface[drive_count] = a->iface_count != 0u ? a->iface_count - 1u : SIZE_MAX;
            drives[drive_count++] = optarg;
            break;
        case 'n':
            if (id_count == MAX_NODES) {
                return usage_error("more than %u node-IDs", MAX_NODES);
            }
            if (!cmd_parse_uint(optarg, 1, 127, &ids[id_count])) {
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
            if (!take_file_name(&a->store_path, "--store", optarg)) {
                return EXIT_USAGE;
            }
            break;
        case 'C':
            if (a->control_path != NULL) {
                return usage_error("--control given twice");
            }
            if (*optarg == '\0' || strlen(optarg) >= CONTROL_PATH_MAX) {
                return usage_error("--control '%s': a socket path has 1 to %u bytes",
                                   sim_show(optarg, shown, sizeof shown),
                                   (unsigned)CONTROL_PATH_MAX - 1u);
            }
            a->control_path = optarg;
            break;
        case 'T': {
            unsigned long port;
            if (a->control_tcp >= 0) {
                return usage_error("--control-tcp given twice");
            }
            if (!cmd_parse_uint(optarg, 0, 65535, &port)) {
                return usage_error("--control-tcp '%s' is not a port number in 0..65535",
                                   sim_show(optarg, shown, sizeof shown));
            }
            a->control_tcp = (long)port;
            break;
        }
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
        case 'O':
            /* co_node's times are below 2^31 us (the 32-bit time base of the firmware builds) */
            if (!cmd_parse_uint(optarg, 1, 2147483ul, &sdo_timeout_ms)) {
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
    if (a->iface_count != 0u && a->ecat_iface != NULL) {
        return usage_error("--iface and --ecat-iface together: one process serves CAN "
                           "interfaces or one EtherCAT line");
    }
    if (a->ecat_iface != NULL) {
        if (sdo_timeout_ms != 0u) {
            return usage_error("--sdo-timeout applies to the CAN SDO server, not to CoE over "
                               "--ecat-iface");
        }
        if (a->trace_path != NULL) {
            return usage_error("--trace writes CAN frames (candump -L); not with --ecat-iface "
                               "(capture the EtherCAT frames on the interface instead)");
        }
        return run_ecat(a, drives, drive_count, id_count, settings, setting_count);
    }
    if (a->iface_count == 0u) {
        return usage_error("--iface is required (e.g. --iface vcan0; or --ecat-iface for "
                           "EtherCAT)");
    }
    for (size_t i = 0; i < drive_count; i++) {
        if (drive_iface[i] == SIZE_MAX) {
            if (a->iface_count > 1u) {
                return usage_error("--drive %s comes before any --iface: with several buses, "
                                   "each --iface is followed by its drives",
                                   sim_show(drives[i], shown, sizeof shown));
            }
            drive_iface[i] = 0;
        }
    }
    if (a->iface_count > 1u && drives_on_iface(drive_iface, drive_count,
                                               a->iface_count - 1u) == 0u) {
        return usage_error("--iface %s has no --drive (each --iface is followed by its drives)",
                           a->ifaces[a->iface_count - 1u]);
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
        const char *iface = a->ifaces[drive_iface[i]];
        if (sc_open(&sn->port, iface, err, sizeof err) != 0) {
            fprintf(stderr, PROG ": %s\n", err);
            return 1;
        }
        bool first_on_bus = drives_on_iface(drive_iface, i, drive_iface[i]) == 0u;
        if (first_on_bus && sc_iface_is_up(sn->port.fd, iface) == 0) {
            /* not an error: the frames wait (the port retries) until someone brings it up */
            fprintf(stderr,
                    PROG ": warning: interface %s is down: nothing is sent or received until it "
                         "is up (ip link set %s up)\n",
                    iface, iface);
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
    int rc = add_instruments(a);
    if (rc != 0) {
        return rc;
    }
    if (a->trace_path != NULL && trace_open(&a->tr, &a->lp, a->trace_path)) {
        a->tracing = true;
        for (size_t k = 0; k < a->iface_count; k++) {
            (void)trace_add_iface(&a->tr, a->ifaces[k]); /* a failure is said and skipped */
        }
    }
    /* Each boot-up goes out once the filters hold the node's COB-IDs (stored ones may differ
     * from the defaults). */
    uint64_t now = loop_now();
    if (a->scn != NULL) {
        scenario_start(a->scn, now);
    }
    for (size_t i = 0; i < a->node_count; i++) {
        sim_begin_filter_change(a->nodes[i]);
        sim_start(a->nodes[i], now);
        sim_end_filter_change(a->nodes[i]);
    }
    printf("canopen-drive: %zu node(s) on ", a->node_count);
    for (size_t k = 0; k < a->iface_count; k++) {
        printf("%s%s", k != 0u ? " and " : "", a->ifaces[k]);
    }
    printf("%s%s", a->have_store ? ", store " : "", a->have_store ? a->store_path : "");
    if (a->tracing) {
        printf(", trace %s", a->trace_path);
    }
    print_control(a);
    printf(", ready\n");
    fflush(stdout);
    return serve(a);
}

int main(int argc, char **argv)
{
    setvbuf(stdout, NULL, _IOLBF, 0); /* one log line reaches a pipe as soon as it is written */
    app *a = calloc(1, sizeof *a);
    if (a == NULL) {
        fprintf(stderr, PROG ": out of memory\n");
        return 1;
    }
    a->control_tcp = -1;
    int rc = run(a, argc, argv);
    if (a->ctl != NULL) {
        control_close(a->ctl);
        free(a->ctl);
    }
    if (a->tracing) {
        trace_close(&a->tr);
    }
    free(a->scn);
    if (a->loop_ready) {
        loop_close(&a->lp);
    }
    free_app(a);
    free(a);
    return rc;
}
