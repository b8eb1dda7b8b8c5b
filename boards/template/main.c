/* The blank port's firmware (port.h): one CANopen slave and the loop that makes every call into
 * the core. The interrupts (can.c, clock.c) only fill the port's queues, so nothing here needs a
 * lock: the core is called from this loop alone (docs/porting.md, "Threads and interrupts"). */
#include <stdbool.h>
#include <stdint.h>

#include "canopen/emcy.h"
#include "canopen/node.h"
#include "od_template.h" /* generated from the EDS by canopen_add_od (CMakeLists.txt) */
#include "port.h"

/* TODO: the node-ID (1..127), e.g. from DIP switches or a stored setting (CiA 305 LSS), and the
 * bit rate. */
#define NODE_ID 5u
#define BITRATE 500000u

int main(void);

/* The node and its object values (the dictionary's value block, 8-byte aligned): all the RAM the
 * core uses. */
static co_node node;
static uint64_t od_values[(CO_OD_TEMPLATE_VALUE_SIZE + 7u) / 8u];

/* What the node tells the application (any of them may be left NULL). They run inside the core's
 * calls, in this loop. */
static void on_nmt(co_node *n, void *ctx, co_nmt_state from, co_nmt_state to)
{
    (void)n;
    (void)ctx;
    (void)from;
    /* TODO: e.g. enable the outputs only in OPERATIONAL. */
    (void)to;
}

static void on_reset(co_node *n, void *ctx, bool whole_node)
{
    (void)n;
    (void)ctx;
    /* TODO: a reset node (whole_node) puts the application into its power-on state; the core
     * restores the dictionary's values itself. */
    (void)whole_node;
}

static void on_comm(co_node *n, void *ctx, co_comm_event event, uint32_t detail)
{
    (void)n;
    (void)ctx;
    /* TODO: the device's reaction to a communication loss (a heartbeat or life guarding lost,
     * an RPDO timeout, bus-off): e.g. stop the outputs. The core has already sent its EMCY and
     * applied 0x1029. */
    (void)event;
    (void)detail;
}

int main(void)
{
    port_clock_init();
    if (!port_can_init(BITRATE)) {
        for (;;) {
        }
    }
    co_node_config cfg = co_node_default_config();
    cfg.od = &co_od_template;
    cfg.values = (uint8_t *)od_values;
    cfg.node_id = NODE_ID;
    cfg.driver.send = port_can_send;
    cfg.storage = &port_storage;
    cfg.events.nmt_changed = on_nmt;
    cfg.events.reset = on_reset;
    cfg.events.comm = on_comm;
    if (!co_node_init(&node, &cfg)) {
        /* A layout mismatch (the port compiled with other switches than the library) is named by
         * co_layout_mismatch(CO_LAYOUT_SIGNATURE); otherwise the config is wrong. TODO: report
         * it (a debugger sees it here). */
        const char *volatile why = co_layout_mismatch(CO_LAYOUT_SIGNATURE);
        (void)why;
        for (;;) {
        }
    }
    co_node_start(&node, port_clock_us()); /* stored values, boot-up, PRE-OPERATIONAL */

    for (;;) {
        uint64_t now = port_clock_us();
        co_frame frame;
        while (port_can_receive(&frame)) {
            co_node_rx(&node, &frame, now);
        }
        port_can_events ev;
        port_can_take_events(&ev);
        if (ev.rx_lost != 0u) {
            co_node_rx_overrun(&node, ev.rx_lost, now);
        }
        if (ev.state_changed) {
            co_node_bus_state(&node, ev.state, now);
        }
        if (ev.tx_ready) {
            co_node_tx_ready(&node);
        }

        /* TODO: the application: read inputs into the dictionary's values, act on the values the
         * master wrote (RPDOs, SDO), raise and clear errors (co_emcy_raise / co_emcy_clear), all
         * here, in this loop. */

        uint64_t next = co_node_process(&node, now);
        port_sleep_until(next);
    }
}
