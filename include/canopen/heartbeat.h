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

/* The core's handler of writes to 0x1017 (the bus's; co_od_hook write signature): the heartbeat
 * restarts with the period written, from the time of the write. */
co_abort co_heartbeat_time_written(struct co_node *node, void *ctx, co_od_ref ref,
                                   const uint8_t *data, uint32_t len, co_od_origin origin);

#ifdef __cplusplus
}
#endif

#endif
