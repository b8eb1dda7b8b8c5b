/* boards/template: a blank port of the CANopen core, to copy and fill in (docs/porting.md).
 * Every place a real port must change says TODO. It compiles as it is (the build of this
 * repository builds it, ctest embedding_template) but talks to no hardware: the "controller"
 * never receives, the clock is a counter and the "flash" is RAM.
 *
 * The structure is the one docs/porting.md recommends: the interrupts only move frames and
 * flags into this port's own queues (under port_lock()), and one loop (main.c) makes every call
 * into the core, so the core itself needs no lock. */
#ifndef TEMPLATE_PORT_H
#define TEMPLATE_PORT_H

#include <stdbool.h>
#include <stdint.h>

#include "canopen/errctl.h"
#include "canopen/frame.h"
#include "canopen/node.h"

/* --- critical section (CANopenNode's CO_LOCK_*: here the port's own, the core needs none) ----- */

/* Masks the interrupts that touch this port's queues (the CAN and timer interrupts) and returns
 * what to restore. port_unlock(key) restores it. Nests. */
uint32_t port_lock(void);
void port_unlock(uint32_t key);

/* --- CAN controller (can.c) ------------------------------------------------------------------- */

/* Sets the controller up at bitrate bit/s, its acceptance filters open (the core filters), and
 * enables its receive, transmit-complete and error interrupts. */
bool port_can_init(uint32_t bitrate);

/* co_driver.send: puts the frame into a free transmit mailbox; false when none is free or the
 * controller is bus-off (the core keeps the frame, in order, until co_node_tx_ready()). */
bool port_can_send(void *ctx, const co_frame *frame);

/* Takes the oldest received frame out of the receive queue; false when it is empty. */
bool port_can_receive(co_frame *frame);

/* What the interrupts noted since the last call. */
typedef struct port_can_events {
    bool tx_ready;        /* a mailbox became free: co_node_tx_ready() */
    bool state_changed;   /* the controller's state is now state: co_node_bus_state() */
    co_bus_state state;
    uint32_t rx_lost;     /* frames lost (queue or controller overrun): co_node_rx_overrun() */
} port_can_events;
void port_can_take_events(port_can_events *events);

/* True when a frame or an event waits (port_sleep_until() does not sleep then). Call it with the
 * interrupts masked (port_lock). */
bool port_can_pending(void);

/* The interrupt handlers: put them into the vector table. */
void port_can_rx_isr(void);
void port_can_tx_isr(void);
void port_can_error_isr(void);

/* --- time (clock.c) --------------------------------------------------------------------------- */

/* Starts the microsecond clock. */
void port_clock_init(void);

/* Microseconds since port_clock_init(), 64 bits: never wraps, never goes back. Any context. */
uint64_t port_clock_us(void);

/* Sleeps until deadline (a time of port_clock_us(); CO_TIME_NEVER: no deadline) or until an
 * interrupt, whichever is first; returns at once when a frame or an event already waits. */
void port_sleep_until(uint64_t deadline);

/* The timer's overflow interrupt (vector table). */
void port_timer_overflow_isr(void);

/* --- non-volatile storage (storage.c) --------------------------------------------------------- */

/* 0x1010/0x1011 on two flash sectors used in turn: a save writes the sector that does not hold
 * the newest image, so a reset or power cut at any moment leaves the old image or the new one. */
extern const co_storage port_storage;

#endif
