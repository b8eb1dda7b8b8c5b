/* examples/minimal: one CANopen slave (node-ID 5, dictionary minimal.eds) on an in-memory "bus".
 * A master's SDO upload of 0x1018:01 (Vendor-ID) goes in as a frame; the expedited answer the
 * node sends is checked byte for byte. Exit status 0 when it is right.
 *
 * A real port differs only in its driver: send() hands the frame to the CAN controller (false
 * when its queue is full), received frames go to co_node_rx(), and co_node_process() runs again
 * by the time it returned. */
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "canopen/node.h"
#include "od_minimal.h" /* generated from minimal.eds by canopen_add_od(minimal minimal.eds) */

#define NODE_ID 5u

/* The driver: every frame the node sends lands in this array. */
typedef struct memory_bus {
    co_frame frames[16];
    unsigned count;
} memory_bus;

static bool memory_bus_send(void *ctx, const co_frame *frame)
{
    memory_bus *bus = (memory_bus *)ctx;
    if (bus->count == sizeof bus->frames / sizeof bus->frames[0]) {
        return false; /* "controller queue full": the core keeps the frame and retries */
    }
    bus->frames[bus->count++] = *frame;
    return true;
}

int main(void)
{
    static co_node node;
    /* The node's object values, 8-byte aligned as od_minimal.h asks. */
    static uint64_t values[(CO_OD_MINIMAL_VALUE_SIZE + 7u) / 8u];
    memory_bus bus = {0};
    uint64_t now = 0; /* µs, from any monotonic clock */

    co_node_config cfg = co_node_default_config();
    cfg.od = &co_od_minimal;
    cfg.values = (uint8_t *)values;
    cfg.node_id = NODE_ID;
    cfg.driver.send = memory_bus_send;
    cfg.driver.ctx = &bus;
    if (!co_node_init(&node, &cfg)) {
        fprintf(stderr, "co_node_init refused the configuration\n");
        return 1;
    }
    co_node_start(&node, now); /* boot-up message, PRE-OPERATIONAL */

    /* SDO upload request (CiA 301 §7.2.4.3, initiate SDO upload): client -> server COB-ID
     * 0x600 + node-ID, command 0x40, index 0x1018 little-endian, sub-index 1. */
    const co_frame request = {.id = 0x600u + NODE_ID, .dlc = 8u,
                              .data = {0x40u, 0x18u, 0x10u, 0x01u, 0u, 0u, 0u, 0u}};
    now += 1000u;
    co_node_rx(&node, &request, now);
    (void)co_node_process(&node, now);

    /* The expedited answer on 0x580 + node-ID: command 0x43 (4 bytes of data), the index and
     * sub-index again, then the Vendor-ID 0x12345678 of minimal.eds, least significant byte
     * first. */
    static const uint8_t expected[8] = {0x43u, 0x18u, 0x10u, 0x01u, 0x78u, 0x56u, 0x34u, 0x12u};
    for (unsigned i = 0; i < bus.count; i++) {
        const co_frame *f = &bus.frames[i];
        if (f->id == 0x580u + NODE_ID) {
            if (f->dlc == 8u && memcmp(f->data, expected, sizeof expected) == 0) {
                printf("node %u: 0x1018:01 Vendor-ID = 0x%02X%02X%02X%02X\n", NODE_ID,
                       f->data[7], f->data[6], f->data[5], f->data[4]);
                return 0;
            }
            fprintf(stderr, "unexpected SDO response %02X %02X %02X %02X %02X %02X %02X %02X\n",
                    f->data[0], f->data[1], f->data[2], f->data[3], f->data[4], f->data[5],
                    f->data[6], f->data[7]);
            return 1;
        }
    }
    fprintf(stderr, "no SDO response among the %u frames sent\n", bus.count);
    return 1;
}
