/* Boot demo on the emulated board: one CANopen node on the bench dictionary (od/bench/bench.eds)
 * whose CAN driver prints every frame it is given, started once. What it prints is the node's
 * boot-up message (CiA 301 §7.2.8.3, error control: COB-ID 0x700 + node-ID, one data byte 0x00,
 * the state INITIALISING); the program's exit status says whether it came (the ctest test `boot`). */
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "canopen/node.h"
#include "od_bench.h"

#define BOOT_NODE_ID 5u

static co_node node;
static uint8_t od_values[CO_OD_BENCH_VALUE_SIZE];

/* co_driver.send: prints the frame and notes whether it was the boot-up message. */
static bool print_frame(void *ctx, const co_frame *frame)
{
    bool *booted = ctx;
    if (frame->id == 0x700u + BOOT_NODE_ID && frame->dlc == 1u && frame->data[0] == 0u) {
        *booted = true;
    }
    printf("tx 0x%03x [%u]", (unsigned)frame->id, (unsigned)frame->dlc);
    for (unsigned i = 0; i < frame->dlc; i++) {
        printf(" %02x", (unsigned)frame->data[i]);
    }
    printf("\n");
    return true;
}

int main(void)
{
    static bool booted;
    co_node_config cfg = co_node_default_config();
    cfg.od = &co_od_bench;
    cfg.values = od_values;
    cfg.node_id = BOOT_NODE_ID;
    cfg.driver.send = print_frame;
    cfg.driver.ctx = &booted;
    if (!co_node_init(&node, &cfg)) {
        printf("co_node_init failed\n");
        return 1;
    }
    printf("node %u on the bench dictionary, starting\n", (unsigned)BOOT_NODE_ID);
    co_node_start(&node, 0);
    printf("boot-up %s, NMT state 0x%02x\n", booted ? "sent" : "missing", (unsigned)node.nmt_state);
    return booted && node.nmt_state == CO_NMT_PRE_OPERATIONAL ? 0 : 1;
}
