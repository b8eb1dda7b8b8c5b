/* Instruction count of the whole emulated EtherCAT slave (ESC + application layer + the VF-MB1
 * drive) per process-data cycle and per CoE expedited SDO upload, as tools/bench measures the CAN
 * side:
 *
 *   valgrind --tool=callgrind --callgrind-out-file=/dev/null bench_ecat_slave 10000      (and 0)
 *   instructions per LRW cycle = (Ir(10000) - Ir(0)) / 10000
 *   bench_ecat_slave N sdo: N expedited uploads of 0x6041 instead (mailbox write frame, the
 *   slave's answer, the master's read frame, the slave again)
 *
 * A cycle is what the port does per frame: the LRW frame of SOEM for one slave (4 output bytes:
 * controlword, target; 4 input bytes: statusword, actual speed) through the ESC, then
 * co_ecat_slave_process 1 ms later than the last (which leaves the drive until its deadline when
the outputs are the same as in the last cycle). The drive is in OP and
 * Operation enabled at constant speed. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "canopen/drive.h"
#include "canopen/ecat/esc.h"
#include "canopen/ecat/slave.h"

static co_esc esc;
static co_drive drive;
static co_ecat_slave slave;
static uint8_t values[8192];
static uint64_t now_ns;

static bool drop(void *ctx, const co_frame *frame)
{
    (void)ctx;
    (void)frame;
    return true;
}

/* One datagram (APxx to position 0, or LRW at logical 0) in a frame of its own. */
static void datagram(uint8_t cmd, uint16_t ado, const uint8_t *data, uint16_t len, uint8_t *out)
{
    uint8_t f[16 + 12 + 128];
    memset(f, 0, sizeof f);
    memset(f, 0xFF, 6);
    f[12] = 0x88;
    f[13] = 0xA4;
    f[14] = (uint8_t)(12u + len);
    f[15] = (uint8_t)(0x10u | ((12u + len) >> 8));
    f[16] = cmd;
    f[20] = (uint8_t)ado;
    f[21] = (uint8_t)(ado >> 8);
    f[22] = (uint8_t)len;
    if (data != NULL) {
        memcpy(&f[26], data, len);
    }
    co_esc_process_frame(&esc, f, 28u + len, now_ns);
    (void)co_ecat_slave_process(&slave, now_ns);
    if (out != NULL) {
        memcpy(out, &f[26], len);
    }
}

#define APRD 1u
#define APWR 2u
#define LRW 12u

static void lrw(uint16_t cw, int16_t target)
{
    uint8_t b[8] = {(uint8_t)cw, (uint8_t)(cw >> 8), (uint8_t)target,
                    (uint8_t)((uint16_t)target >> 8), 0, 0, 0, 0};
    datagram(LRW, 0, b, 8, NULL);
}

static void request(uint8_t state)
{
    const uint8_t v[2] = {state, 0};
    datagram(APWR, 0x0120, v, 2, NULL);
}

static uint8_t last_answer[128];

static void sdo_upload(void)
{
    static const uint8_t req[16] = {10, 0, 0, 0, 0, 0x13, 0x00, 0x20, 0x40, 0x41, 0x60, 0x00};
    uint8_t mbx[128];
    memset(mbx, 0, sizeof mbx);
    memcpy(mbx, req, sizeof req);
    mbx[5] = (uint8_t)(0x03u | ((now_ns / 1000000u) % 7u + 1u) << 4); /* CoE, counter 1..7 */
    datagram(APWR, 0x1000, mbx, 128, NULL);
    datagram(APRD, 0x1080, NULL, 128, last_answer);
}

int main(int argc, char **argv)
{
    long n = argc > 1 ? strtol(argv[1], NULL, 10) : 1000;
    bool sdo = argc > 2 && strcmp(argv[2], "sdo") == 0;
    co_node_config nc = co_node_default_config();
    co_esc_config ec = co_esc_default_config();
    co_ecat_slave_config sc = co_ecat_slave_default_config();
    static const uint8_t sm[32] = {0x00, 0x10, 128, 0, 0x26, 0, 1, 0, 0x80, 0x10, 128, 0, 0x22, 0, 1, 0,
                                   0x00, 0x11, 4, 0, 0x64, 0, 1, 0, 0x80, 0x11, 4, 0, 0x20, 0, 1, 0};
    static const uint8_t fmmu[32] = {0, 0, 0, 0, 4, 0, 0, 7, 0x00, 0x11, 0, 2, 1, 0, 0, 0,
                                     4, 0, 0, 0, 4, 0, 0, 7, 0x80, 0x11, 0, 1, 1, 0, 0, 0};
    nc.node_id = 1;
    nc.values = values;
    nc.driver.send = drop;
    if (!co_drive_init(&drive, co_drive_registry_find("vf-mb1-ecat"), &nc) ||
        co_esc_init(&esc, &ec) != 0) {
        return 1;
    }
    co_drive_start(&drive, 0);
    sc.esc = &esc;
    sc.node = &drive.node;
    sc.drive = &drive;
    if (!co_ecat_slave_init(&slave, &sc, 0)) {
        return 1;
    }
    datagram(APWR, 0x0800, sm, 32, NULL);
    datagram(APWR, 0x0600, fmmu, 32, NULL);
    request(CO_ECAT_STATE_PREOP);
    request(CO_ECAT_STATE_SAFEOP);
    lrw(0x0006, 0);
    request(CO_ECAT_STATE_OP);
    for (int i = 0; i < 3000; i++) { /* enabled, at 600 rpm */
        now_ns += 1000000u;
        lrw(i < 10 ? 0x0006 : i < 20 ? 0x0007 : 0x000F, 600);
    }
    if (co_ecat_slave_state(&slave) != CO_ECAT_STATE_OP) {
        fprintf(stderr, "bench_ecat_slave: not in OP\n");
        return 1;
    }
    if (sdo) { /* the SM watchdog off: no process data during the SDOs */
        static const uint8_t off[2] = {0, 0};
        datagram(APWR, 0x0420, off, 2, NULL);
    }
    for (long i = 0; i < n; i++) {
        now_ns += 1000000u;
        if (sdo) {
            sdo_upload();
        } else {
            lrw(0x000F, 600);
        }
    }
    if (sdo && n > 0 && (last_answer[8] != 0x4B || last_answer[9] != 0x41)) {
        fprintf(stderr, "bench_ecat_slave: no upload answer\n");
        return 1;
    }
    printf("%ld %s, state %s, stats: outputs %u, mailbox %u\n", n, sdo ? "SDO uploads" : "cycles",
           co_ecat_state_name(co_ecat_slave_state(&slave)), (unsigned)slave.stats.outputs,
           (unsigned)slave.stats.mbx_rx);
    return 0;
}
