/* Instruction count of one process-data cycle through the emulated ESC: the frame SOEM sends for
 * one slave with 4 output and 4 input bytes (one LRW datagram, logical address 0, 8 bytes; FMMU0
 * outputs to SM2, FMMU1 inputs from SM3), processed N times.
 *
 *   valgrind --tool=callgrind --callgrind-out-file=/dev/null bench_esc 10000   (and with 0)
 *   instructions per cycle = (Ir(10000) - Ir(0)) / 10000
 *
 * Each cycle also lets the PDI side do what an application does per cycle: read the outputs from
 * SM2 and write the inputs to SM3 (run with a second argument "esc" to leave that out). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "canopen/ecat/esc.h"

/* One FPWR datagram of len bytes at ado to station 0x1001, in a frame of its own. */
static void fpwr(co_esc *esc, uint16_t ado, const uint8_t *data, uint16_t len)
{
    uint8_t f[64] = {0};
    memset(f, 0xFF, 6);
    f[12] = 0x88;
    f[13] = 0xA4;
    f[14] = (uint8_t)(12 + len);
    f[15] = 0x10;
    f[16] = 5; /* FPWR */
    f[18] = 0x01;
    f[19] = 0x10;
    f[20] = (uint8_t)ado;
    f[21] = (uint8_t)(ado >> 8);
    f[22] = (uint8_t)len;
    memcpy(&f[26], data, len);
    co_esc_process_frame(esc, f, 28u + len, 0);
}

int main(int argc, char **argv)
{
    static co_esc esc;
    co_esc_config cfg = co_esc_default_config();
    static const uint8_t station[2] = {0x01, 0x10};
    static const uint8_t sm23[16] = {0x00, 0x11, 4, 0, 0x64, 0, 1, 0, /* SM2: outputs */
                                     0x80, 0x11, 4, 0, 0x20, 0, 1, 0}; /* SM3: inputs */
    static const uint8_t fmmu01[32] = {0, 0, 0, 0, 4, 0, 0, 7, 0x00, 0x11, 0, 2, 1, 0, 0, 0,
                                       4, 0, 0, 0, 4, 0, 0, 7, 0x80, 0x11, 0, 1, 1, 0, 0, 0};
    uint8_t frame[14 + 2 + 12 + 8] = {0};
    uint8_t io[4] = {0x37, 0x06, 0xDC, 0x05};
    long n = argc > 1 ? strtol(argv[1], NULL, 10) : 0;
    int app = !(argc > 2 && strcmp(argv[2], "esc") == 0);
    unsigned wkc_sum = 0;

    co_esc_init(&esc, &cfg);
    {   /* APWR station address 0x1001 to the first slave */
        uint8_t f[30] = {0};
        f[12] = 0x88; f[13] = 0xA4; f[14] = 14; f[15] = 0x10;
        f[16] = 2; f[20] = 0x10; f[22] = 2;
        memcpy(&f[26], station, 2);
        co_esc_process_frame(&esc, f, sizeof f, 0);
    }
    fpwr(&esc, 0x0810, sm23, sizeof sm23);
    fpwr(&esc, 0x0600, fmmu01, sizeof fmmu01);
    co_esc_pdi_write(&esc, 0x1180, io, sizeof io);

    memset(frame, 0xFF, 6);
    memset(frame + 6, 0x01, 6);
    frame[12] = 0x88;
    frame[13] = 0xA4;
    frame[14] = 12 + 8;
    frame[15] = 0x10;
    frame[16] = 12; /* LRW, logical address 0 */
    frame[22] = 8;
    for (long i = 0; i < n; i++) {
        frame[34] = 0; /* the master's WKC starts at 0 */
        frame[35] = 0;
        co_esc_process_frame(&esc, frame, sizeof frame, (uint64_t)i * 1000000u);
        wkc_sum += frame[34];
        if (app) {
            uint8_t out[4];
            co_esc_pdi_read(&esc, 0x1100, out, sizeof out);
            io[0] = out[0];
            co_esc_pdi_write(&esc, 0x1180, io, sizeof io);
        }
    }
    printf("%ld cycles, WKC %u each\n", n, n > 0 ? wkc_sum / (unsigned)n : 0u);
    return 0;
}
