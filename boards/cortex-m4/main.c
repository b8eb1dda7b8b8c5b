/* The footprint firmware: one CANopen slave on the stub port, linking what a CANopenNode-
 * equivalent device uses - NMT, heartbeat producer and consumer, node guarding, SDO server
 * (expedited, segmented, block), the dictionary's PDOs, SYNC, EMCY and storage hooks - with the
 * dictionary BOARD_OD (bench: od/bench/bench.eds, vf_s15: the VF-S15), and with BOARD_DRIVE_DESC
 * the CiA 402 drive layer of that drive around the node. Everything the core needs lives in two
 * static blocks, the node (or drive) and the value block, so `size` shows the whole RAM.
 *
 * Built by boards/cortex-m4/CMakeLists.txt; measured by tools/bench (docs/performance.md). */
#include <stdbool.h>
#include <stdint.h>

#include "canopen/node.h"
#include "stub_can.h"
#include BOARD_OD_HEADER
#ifdef BOARD_HAVE_EMCY
#include "canopen/emcy.h"
#endif
#ifdef BOARD_DRIVE_DESC
#include "canopen/drive.h"
extern const co_drive_desc BOARD_DRIVE_DESC;
#endif

#define BOARD_NODE_ID 5u

int main(void);

/* The node (or the drive, which holds its node) and the value block: the core's whole RAM
 * (nothing else is static in the core). */
#ifdef BOARD_DRIVE_DESC
static co_drive drive;
#define NODE (&drive.node)
#else
static co_node node;
#define NODE (&node)
#endif
static uint64_t od_values[(BOARD_OD_VALUE_SIZE + 7u) / 8u];

/* What the application (the drive) does with the node's events: it only notes them here, as
 * CANopenNode's main_blank.c does. */
static uint32_t comm_events;

static void on_comm(co_node *n, void *ctx, co_comm_event event, uint32_t detail)
{
    (void)n;
    (void)ctx;
    (void)detail;
    comm_events |= 1u << (unsigned)event;
}

static void on_nmt(co_node *n, void *ctx, co_nmt_state from, co_nmt_state to)
{
    (void)n;
    (void)ctx;
    (void)from;
    (void)to;
}

static void on_reset(co_node *n, void *ctx, bool whole_node)
{
    (void)n;
    (void)ctx;
    (void)whole_node;
}

int main(void)
{
    co_node_config cfg = co_node_default_config();
    cfg.od = &BOARD_OD;
    cfg.values = (uint8_t *)od_values;
    cfg.node_id = BOARD_NODE_ID;
    cfg.driver.send = stub_can_send;
    cfg.driver.ctx = 0;
    cfg.storage = &stub_flash_storage;
    cfg.events.comm = on_comm;
    cfg.events.nmt_changed = on_nmt;
    cfg.events.reset = on_reset;
#ifdef BOARD_DRIVE_DESC
    if (!co_drive_init(&drive, &BOARD_DRIVE_DESC, &cfg)) {
        for (;;) {
        }
    }
    co_drive_start(&drive, stub_clock_us());
#else
    if (!co_node_init(&node, &cfg)) {
        for (;;) {
        }
    }
    co_node_start(&node, stub_clock_us());
#endif

#if defined(BOARD_HAVE_EMCY) && !defined(BOARD_DRIVE_DESC)
    bool fault = false;
#endif
    for (;;) {
        uint64_t now = stub_clock_us();
        co_frame frame;
        while (stub_can_receive(&frame)) {
#ifdef BOARD_DRIVE_DESC
            co_drive_rx(&drive, &frame, now);
#else
            co_node_rx(&node, &frame, now);
#endif
        }
#if defined(BOARD_DRIVE_DESC)
        /* A trip input, as the simulated drive's fault injection. */
        if ((stub_input() & 1u) != 0u) {
            (void)co_drive_inject_fault(&drive, (uint16_t)(stub_input() >> 16), now);
        }
#elif defined(BOARD_HAVE_EMCY)
        /* An application error, raised and cleared as a drive does with its trips. */
        bool input = (stub_input() & 1u) != 0u;
        if (input != fault) {
            fault = input;
            if (fault) {
                (void)co_emcy_raise(NODE, 0x5000u, CO_ERR_REG_MANUFACTURER, 0);
            } else {
                co_emcy_clear(NODE, 0x5000u);
            }
        }
#endif
#ifdef BOARD_DRIVE_DESC
        (void)co_drive_process(&drive, now);
#else
        (void)co_node_process(&node, now);
#endif
        /* A real port sleeps here until the returned deadline or the next frame. */
    }
}
