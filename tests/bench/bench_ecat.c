/* EtherCAT benchmark (tools/bench, section "EtherCAT"): what one simulated VF-MB1 slave (emulated
 * ESC + slave application layer + the drive behind it) costs per frame, as canopen-drive
 * --ecat-iface runs it, on the virtual clock.
 *
 *   bench_ecat --list                  scenarios: name, operations per iteration, what
 *   bench_ecat --check SCENARIO [--slaves K]   runs a few iterations, checks the effect (0 ok)
 *   bench_ecat SCENARIO N [--slaves K] N iterations (callgrind: (Ir(N) - Ir(0)) / N)
 *
 * A line of K slaves (default 1) is configured by frames as SOEM configures it (station
 * addresses, SM0/SM1, PRE-OP, SM2/SM3 and FMMUs from the 4-byte mapping, SAFE-OP, a first cycle,
 * OP): outputs of slave i at logical 4i, inputs at 4K + 4i, one LRW datagram per cycle.
 *   lrw_cycle               one cycle: the LRW frame through the K ESCs (co_esc_chain_process)
 *                           and every slave's co_ecat_slave_process after it, 1 ms apart (the
 *                           same outputs every cycle: the drives, idle, are not run)
 *   lrw_frame_esc           the same frame through the ESCs only (the application layers and the
 *                           drives not run): the ESC emulation's share
 *   coe_sdo_upload          an expedited CoE SDO upload (0x6048:02) of slave 1 as SOEM does it:
 *                           FPRD SM0 status, FPWR the request into SM0, FPRD SM1 status, FPRD
 *                           the reply from SM1 (4 frames, the slaves run after each)
 *   coe_sdo_download        the same for an expedited download of 0x6048:02
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "canopen/drive.h"
#include "canopen/ecat/esc.h"
#include "canopen/ecat/slave.h"
#include "ecat_frame.h"
#include "sii_vf_mb1_ecat.h"

#define MAX_SLAVES 32u
#define MBX 128u

typedef struct slave {
    co_esc esc;
    co_ecat_slave sl;
    co_drive drive;
    uint64_t values[512]; /* the dictionary's value block, 8-byte aligned */
} slave;

typedef struct line {
    slave s[MAX_SLAVES];
    co_esc *chain[MAX_SLAVES];
    unsigned k;
    uint64_t now_us;
    ecat_frame frame; /* the latest frame of datagram() */
    uint8_t cycle[16u + 12u + 8u * MAX_SLAVES + 2u]; /* the LRW cycle frame, kept */
    size_t cycle_len;
    uint8_t counter; /* mailbox counter 1..7 */
    bool esc_only;   /* frames through the ESCs only, the application layers not run */
} line;

static bool no_can(void *ctx, const co_frame *f)
{
    (void)ctx;
    (void)f;
    return true;
}

static void run_slaves(line *l)
{
    for (unsigned i = 0; i < l->k; i++) {
        (void)co_ecat_slave_process(&l->s[i].sl, l->now_us * 1000u);
    }
}

/* One datagram in a frame through the line; returns the WKC, data copied to out. */
static uint16_t datagram(line *l, uint8_t cmd, uint32_t addr, const void *data, uint16_t len,
                         void *out)
{
    ecat_frame *f = &l->frame;
    ecat_frame_start(f);
    size_t dg = ecat_frame_add32(f, cmd, addr, data, len);
    (void)co_esc_chain_process(l->chain, l->k, f->b, ecat_frame_wire_len(f), l->now_us * 1000u);
    if (!l->esc_only) {
        run_slaves(l);
    }
    if (out != NULL) {
        memcpy(out, ecat_frame_data(f, dg), len);
    }
    return ecat_frame_wkc(f, dg);
}

static uint32_t fp(unsigned i, uint16_t ado)
{
    return (uint32_t)(0x1001u + i) | (uint32_t)ado << 16;
}

static void sm(line *l, unsigned i, unsigned n, uint16_t start, uint16_t len, uint8_t ctrl)
{
    uint8_t b[8] = {(uint8_t)start, (uint8_t)(start >> 8), (uint8_t)len, (uint8_t)(len >> 8),
                    ctrl, 0, 1, 0};
    (void)datagram(l, FPWR, fp(i, (uint16_t)(0x0800u + 8u * n)), b, 8, NULL);
}

static void fmmu(line *l, unsigned i, unsigned n, uint32_t log, uint16_t phys, uint8_t type)
{
    uint8_t b[16] = {(uint8_t)log, (uint8_t)(log >> 8), (uint8_t)(log >> 16), (uint8_t)(log >> 24),
                     4, 0, 0, 7, (uint8_t)phys, (uint8_t)(phys >> 8), 0, type, 1, 0, 0, 0};
    (void)datagram(l, FPWR, fp(i, (uint16_t)(0x0600u + 16u * n)), b, 16, NULL);
}

static bool al_all(line *l, uint8_t state)
{
    for (unsigned i = 0; i < l->k; i++) {
        (void)datagram(l, FPWR, fp(i, 0x0120), &state, 1, NULL);
    }
    for (unsigned i = 0; i < l->k; i++) {
        uint8_t st[2] = {0, 0};
        (void)datagram(l, FPRD, fp(i, 0x0130), NULL, 2, st);
        if (st[0] != state) {
            fprintf(stderr, "slave %u: AL status 0x%02X, not 0x%02X\n", i + 1u, st[0], state);
            return false;
        }
    }
    return true;
}

/* One cycle: the LRW frame, built once as a master keeps its process-data frame, gets the
 * outputs and a cleared working counter, goes through the line, and the slaves run. What the
 * bench spends here is the master's side: copying 4 bytes per slave and reading the WKC. */
static uint16_t lrw(line *l)
{
    uint16_t len = (uint16_t)(8u * l->k);
    uint8_t *d = l->cycle + 16;
    if (l->cycle_len == 0u) { /* built by datagram() once, then kept */
        uint8_t zero[8u * MAX_SLAVES] = {0};
        (void)datagram(l, LRW, 0, zero, len, NULL);
        memcpy(l->cycle, l->frame.b, sizeof l->cycle);
        l->cycle_len = ecat_frame_wire_len(&l->frame);
    }
    for (unsigned i = 0; i < l->k; i++) {
        d[10u + 4u * i] = 0x06; /* controlword: shutdown */
        d[11u + 4u * i] = 0;
        d[12u + 4u * i] = 0xDC; /* target 1500 */
        d[13u + 4u * i] = 0x05;
    }
    d[10 + len] = 0;
    d[11 + len] = 0;
    (void)co_esc_chain_process(l->chain, l->k, l->cycle, l->cycle_len, l->now_us * 1000u);
    if (!l->esc_only) {
        run_slaves(l);
    }
    return (uint16_t)(d[10 + len] | (d[11 + len] << 8));
}

static bool line_up(line *l, unsigned k)
{
    const co_drive_desc *desc = co_drive_registry_find("vf-mb1-ecat");
    memset(l, 0, sizeof *l);
    l->k = k;
    l->now_us = 1000u;
    for (unsigned i = 0; i < k; i++) {
        slave *s = &l->s[i];
        co_node_config nc = co_node_default_config();
        nc.node_id = (uint8_t)(i + 1u);
        nc.values = (uint8_t *)s->values;
        nc.driver.send = no_can;
        if (desc == NULL || desc->od->value_size > sizeof s->values ||
            !co_drive_init(&s->drive, desc, &nc)) {
            return false;
        }
        co_drive_start(&s->drive, l->now_us);
        co_esc_config ec = co_esc_default_config();
        ec.sii = co_sii_vf_mb1_ecat;
        ec.sii_size = CO_SII_VF_MB1_ECAT_SIZE;
        ec.open_ports = i + 1u < k ? 0x03u : 0x01u;
        if (co_esc_init(&s->esc, &ec) != 0) {
            return false;
        }
        co_ecat_slave_config c = co_ecat_slave_default_config();
        c.esc = &s->esc;
        c.node = &s->drive.node;
        c.drive = &s->drive;
        if (!co_ecat_slave_init(&s->sl, &c, l->now_us * 1000u)) {
            return false;
        }
        l->chain[i] = &s->esc;
    }
    for (unsigned i = 0; i < k; i++) {
        uint8_t st[2] = {(uint8_t)(0x01u + i), 0x10};
        (void)datagram(l, APWR, (uint32_t)(uint16_t)(0u - i) | 0x0010u << 16, st, 2, NULL);
    }
    for (unsigned i = 0; i < k; i++) {
        sm(l, i, 0, 0x1000, MBX, 0x26);
        sm(l, i, 1, 0x1080, MBX, 0x22);
    }
    if (!al_all(l, 2)) {
        return false;
    }
    for (unsigned i = 0; i < k; i++) {
        sm(l, i, 2, 0x1100, 4, 0x64);
        sm(l, i, 3, 0x1180, 4, 0x20);
        fmmu(l, i, 0, 4u * i, 0x1100, 2);
        fmmu(l, i, 1, 4u * k + 4u * i, 0x1180, 1);
    }
    if (!al_all(l, 4)) {
        return false;
    }
    (void)lrw(l); /* valid outputs before OP */
    return al_all(l, 8);
}

/* One CoE SDO request to slave 1 and its reply, SOEM's four frames. Returns the reply. */
static void coe(line *l, const uint8_t sdo[8], uint8_t reply[MBX])
{
    uint8_t req[MBX] = {0};
    uint8_t st = 0;
    l->counter = (uint8_t)(l->counter % 7u + 1u);
    req[0] = 10;          /* length: CoE header + SDO */
    req[5] = (uint8_t)(l->counter << 4 | 0x03); /* CoE */
    req[7] = 0x20;        /* SDO request */
    memcpy(req + 8, sdo, 8);
    (void)datagram(l, FPRD, fp(0, 0x0805), NULL, 1, &st); /* SM0 empty? */
    (void)datagram(l, FPWR, fp(0, 0x1000), req, MBX, NULL);
    (void)datagram(l, FPRD, fp(0, 0x080D), NULL, 1, &st); /* SM1 full? */
    (void)datagram(l, FPRD, fp(0, 0x1080), NULL, MBX, reply);
}

typedef struct scenario {
    const char *name;
    const char *what;
} scenario;

static const scenario SCENARIOS[] = {
    {"lrw_cycle", "one LRW cycle frame through the line and every slave's application layer"},
    {"lrw_frame_esc", "the LRW cycle frame through the ESCs only (no application layer)"},
    {"coe_sdo_upload", "expedited CoE SDO upload of 0x6048:02, SOEM's 4 frames"},
    {"coe_sdo_download", "expedited CoE SDO download of 0x6048:02, SOEM's 4 frames"},
};

static int run(const char *name, long n, unsigned k, bool check)
{
    static line l;
    if (!line_up(&l, k)) {
        fprintf(stderr, "bench_ecat: the line did not reach OP\n");
        return 1;
    }
    uint8_t reply[MBX];
    if (strcmp(name, "lrw_cycle") == 0 || strcmp(name, "lrw_frame_esc") == 0) {
        unsigned good = 0;
        l.esc_only = name[4] == 'f';
        for (long i = 0; i < n; i++) {
            l.now_us += 1000u;
            good += lrw(&l) == 3u * k;
        }
        if (check && good != (unsigned)n) {
            printf("WKC wrong in %ld of %ld cycles\n", n - (long)good, n);
            return 1;
        }
        if (check && !l.esc_only && co_ecat_slave_state(&l.s[k - 1u].sl) != CO_ECAT_STATE_OP) {
            printf("the last slave left OP\n");
            return 1;
        }
        return 0;
    }
    if (strcmp(name, "coe_sdo_upload") == 0 || strcmp(name, "coe_sdo_download") == 0) {
        bool up = name[8] == 'u';
        for (long i = 0; i < n; i++) {
            uint16_t v = (uint16_t)(1u + (unsigned)i % 100u);
            uint8_t sdo[8] = {up ? 0x40 : 0x2B, 0x48, 0x60, 0x02, (uint8_t)v, (uint8_t)(v >> 8)};
            coe(&l, sdo, reply);
            if (check && reply[5] >> 4 == 0u) {
                printf("no reply\n");
                return 1;
            }
            if (check && reply[8] != (up ? 0x4B : 0x60)) {
                printf("reply command 0x%02X\n", reply[8]);
                return 1;
            }
        }
        return 0;
    }
    fprintf(stderr, "bench_ecat: unknown scenario %s\n", name);
    return 1;
}

int main(int argc, char **argv)
{
    if (argc == 2 && strcmp(argv[1], "--list") == 0) {
        for (size_t i = 0; i < sizeof SCENARIOS / sizeof SCENARIOS[0]; i++) {
            printf("%s\t1\t%s\n", SCENARIOS[i].name, SCENARIOS[i].what);
        }
        return 0;
    }
    bool check = argc >= 3 && strcmp(argv[1], "--check") == 0;
    const char *name = check ? argv[2] : argc >= 3 ? argv[1] : NULL;
    long n = check ? 20 : argc >= 3 ? strtol(argv[2], NULL, 10) : -1;
    unsigned k = 1;
    if (argc >= 5 && strcmp(argv[argc - 2], "--slaves") == 0) {
        long v = strtol(argv[argc - 1], NULL, 10);
        k = v >= 1 && v <= (long)MAX_SLAVES ? (unsigned)v : 0u;
    }
    if (name == NULL || n < 0 || k == 0u) {
        fprintf(stderr, "usage: bench_ecat --list | --check SCENARIO [--slaves K] | "
                        "SCENARIO N [--slaves K]   (K 1..%u)\n", MAX_SLAVES);
        return 2;
    }
    return run(name, n, k, check);
}
