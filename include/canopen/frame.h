/* A classic CAN frame and the driver contract between the core and a port. */
#ifndef CANOPEN_FRAME_H
#define CANOPEN_FRAME_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define CO_FRAME_RTR 0x01u /* remote transmission request: no data, dlc is the requested length */

typedef struct co_frame {
    uint16_t id;     /* 11-bit CAN identifier (CANopen uses base frames only) */
    uint8_t dlc;     /* 0..8 */
    uint8_t flags;   /* CO_FRAME_RTR */
    uint8_t data[8];
} co_frame;

/* What a port provides. The core never calls the OS: it hands frames to send() and nothing else. */
typedef struct co_driver {
    /* Put one frame on the bus. Return true if taken, false if the port's queue is full: the core
     * then keeps the frame, and all later ones, in order, and offers it again on the next
     * co_node_process() or co_node_tx_ready(). */
    bool (*send)(void *ctx, const co_frame *frame);
    void *ctx;
} co_driver;

#ifdef __cplusplus
}
#endif

#endif
