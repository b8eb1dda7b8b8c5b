/* A stand-in for a Cortex-M4 port: CAN mailboxes, a microsecond timer and a flash page at fixed
 * peripheral addresses. It never runs; it exists so the linker keeps exactly what a real port
 * keeps (the footprint build of docs/performance.md), the way CANopenNode's CO_driver_blank.c
 * does for its own size figures. */
#ifndef STUB_CAN_H
#define STUB_CAN_H

#include <stdbool.h>
#include <stdint.h>

#include "canopen/frame.h"
#include "canopen/node.h"

/* co_driver.send: writes the frame into the transmit mailbox, false while it is busy. */
bool stub_can_send(void *ctx, const co_frame *frame);

/* Takes one received frame from the receive FIFO; false when it is empty. */
bool stub_can_receive(co_frame *frame);

/* Microseconds since start-up: the 32-bit hardware timer widened in software. */
uint64_t stub_clock_us(void);

/* Non-volatile storage for 0x1010/0x1011 in one flash page. */
extern const co_storage stub_flash_storage;

/* An application input the firmware polls (a fault line, say). */
uint32_t stub_input(void);

#endif
