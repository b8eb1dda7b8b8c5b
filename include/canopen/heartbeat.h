/* Heartbeat producer (0x1017, CiA 301 §7.2.8.3.2.2). */
#ifndef CANOPEN_HEARTBEAT_H
#define CANOPEN_HEARTBEAT_H

#include <stdint.h>

#include "canopen/od.h"
#include "canopen/time_base.h"

#ifdef __cplusplus
extern "C" {
#endif

struct co_node;

typedef struct co_heartbeat_producer {
    uint32_t period_us; /* 0: off */
    co_time next;       /* time of the next heartbeat */
} co_heartbeat_producer;

/* Re-reads 0x1017 and restarts the period from now. Called on reset communication and when 0x1017
 * is written. */
void co_heartbeat_producer_configure(struct co_node *node, co_time now);

/* The core's handler of writes to 0x1017 (the bus's; co_od_hook write signature): the heartbeat
 * restarts with the period written, from the time of the write. */
co_abort co_heartbeat_time_written(struct co_node *node, void *ctx, co_od_ref ref,
                                   const uint8_t *data, uint32_t len, co_od_origin origin);

/* Sends a heartbeat when due. Returns the time of the next one (CO_NEVER when off). */
co_time co_heartbeat_producer_process(struct co_node *node, co_time now);

#ifdef __cplusplus
}
#endif

#endif
