/* The CAN driver of the blank port (port.h). The interrupts put received frames into a queue and
 * note the controller's events; the CANopen loop (main.c) takes them out and calls the core.
 * TODO marks what a real controller needs. */
#include <string.h>

#include "port.h"

/* Received frames between the receive interrupt and the loop. The loop empties it each pass;
 * size it for the longest the loop may be away (a flash save in storage.c takes milliseconds:
 * at 1 Mbit/s a fully loaded bus brings one frame every ~50-130 µs). A power of two. */
#define RX_QUEUE_LEN 32u

typedef struct can_port {
    co_frame rx[RX_QUEUE_LEN];
    uint32_t rx_head;      /* next to take (loop) */
    uint32_t rx_count;     /* written by the interrupt, read and lowered by the loop under lock */
    uint32_t rx_lost;      /* frames lost since the last port_can_take_events() */
    bool tx_ready;
    bool state_changed;
    co_bus_state state;    /* the controller's state as last reported by its error interrupt */
} can_port;

static can_port can;

/* --- the controller (TODO: your part's registers) --------------------------------------------- */

/* TODO: true when a transmit mailbox is free. */
static bool hw_tx_mailbox_free(void)
{
    return true;
}

/* TODO: write id (11 bits), RTR, dlc and data into a free mailbox and request transmission. */
static void hw_tx_write(const co_frame *frame)
{
    (void)frame;
}

/* TODO: read the oldest frame of the receive FIFO into frame and release it; false when empty. */
static bool hw_rx_read(co_frame *frame)
{
    (void)frame;
    return false;
}

/* TODO: the controller's fault confinement state (error counters, bus-off flag), from its error
 * status register. */
static co_bus_state hw_bus_state(void)
{
    return CO_BUS_ERROR_ACTIVE;
}

/* TODO: true (and clear the flag) when the controller's receive FIFO overflowed. */
static bool hw_rx_overrun(void)
{
    return false;
}

bool port_can_init(uint32_t bitrate)
{
    memset(&can, 0, sizeof can);
    can.state = CO_BUS_ERROR_ACTIVE;
    /* TODO: clock the controller, set the bit timing for bitrate (CiA 301 / CiA 303-1 sample
     * point 87.5 %), accept every standard identifier (the core drops what is not its own),
     * automatic bus-off recovery on (ISO 11898-1: after 128 x 11 recessive bits), enable the
     * receive, transmit-complete and error interrupts, leave initialisation mode. */
    (void)bitrate;
    return true;
}

/* --- the core's side (CANopen loop) ----------------------------------------------------------- */

bool port_can_send(void *ctx, const co_frame *frame)
{
    (void)ctx;
    /* Bus-off: nothing can be sent; the core queues (CO_TX_QUEUE_LEN frames, then counts what it
     * drops) and gets co_node_tx_ready() after the recovery. The state is read with the same
     * lock as the transmit mailbox, which the transmit interrupt also looks at. */
    uint32_t key = port_lock();
    bool taken = can.state != CO_BUS_OFF && hw_tx_mailbox_free();
    if (taken) {
        hw_tx_write(frame);
    }
    port_unlock(key);
    return taken;
}

bool port_can_receive(co_frame *frame)
{
    uint32_t key = port_lock();
    bool got = can.rx_count != 0u;
    if (got) {
        *frame = can.rx[can.rx_head];
        can.rx_head = (can.rx_head + 1u) & (RX_QUEUE_LEN - 1u);
        can.rx_count--;
    }
    port_unlock(key);
    return got;
}

void port_can_take_events(port_can_events *events)
{
    uint32_t key = port_lock();
    events->tx_ready = can.tx_ready;
    events->state_changed = can.state_changed;
    events->state = can.state;
    events->rx_lost = can.rx_lost;
    can.tx_ready = false;
    can.state_changed = false;
    can.rx_lost = 0;
    port_unlock(key);
}

bool port_can_pending(void)
{
    return can.rx_count != 0u || can.tx_ready || can.state_changed || can.rx_lost != 0u;
}

/* --- interrupts ------------------------------------------------------------------------------- */

void port_can_rx_isr(void)
{
    co_frame frame;
    while (hw_rx_read(&frame)) {
        if (can.rx_count == RX_QUEUE_LEN) {
            can.rx_lost++; /* reported to the core as CO_EMCY_CAN_OVERRUN (0x8110) */
            continue;
        }
        can.rx[(can.rx_head + can.rx_count) & (RX_QUEUE_LEN - 1u)] = frame;
        can.rx_count++;
    }
    if (hw_rx_overrun()) {
        can.rx_lost++; /* the controller does not say how many: at least one */
    }
}

void port_can_tx_isr(void)
{
    /* TODO: acknowledge the transmit-complete flags. */
    can.tx_ready = true;
}

void port_can_error_isr(void)
{
    /* TODO: acknowledge the error interrupt. The core wants the state changes only: error active
     * <-> error passive <-> bus-off (co_node_bus_state ignores a repeated state). */
    co_bus_state state = hw_bus_state();
    if (state != can.state) {
        can.state = state;
        can.state_changed = true;
        if (state != CO_BUS_OFF) {
            can.tx_ready = true; /* after a recovery the queued frames may go */
        }
    }
}
