/* Heartbeat producer: one frame with the NMT state every 0x1017 ms. */
#include "canopen/heartbeat.h"

#include <string.h>

#include "canopen/node.h"
#include "dispatch.h"
#include "services.h"

/* Restarts the producer with a period of period_ms (0: off; at most 65535) from now: 0x1017's
 * value at reset communication, or the value written to it. */
static CO_ONE_COPY void producer_start(co_node *node, uint32_t period_ms, co_time now)
{
    co_heartbeat_producer *hb = &node->heartbeat;
    co_time old = hb->next;
    hb->period_us = period_ms * 1000u;
    /* The first heartbeat follows one period after the boot-up message, never with it: a master
     * waiting for the boot-up would otherwise see the heartbeat first. */
    hb->next = hb->period_us != 0u ? now + hb->period_us : CO_NEVER;
    co_node_reschedule(node, old, hb->next);
}

void co_heartbeat_producer_configure(co_node *node, co_time now)
{
    producer_start(node, (uint16_t)co_svc_od_value(node, 0x1017u), now);
}

co_abort co_heartbeat_time_written(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                                   uint32_t len, co_od_origin origin)
{
    (void)ctx;
    (void)len;
    (void)origin;
    if (ref.sub->subindex == 0u) {
        producer_start(node, co_get_le16(data), node->now);
    }
    return CO_ABORT_NONE;
}

co_time co_heartbeat_producer_process(co_node *node, co_time now)
{
    co_heartbeat_producer *hb = &node->heartbeat;
    if (now < hb->next) {
        return hb->next;
    }
#if !CO_CONFIG_TIME32
    /* off (next is CO_NEVER): only an API time of UINT64_MAX gets here; a 32-bit now is always
     * below CO_NEVER (include/canopen/time_base.h) */
    if (hb->period_us == 0u) {
        hb->next = CO_NEVER;
        return CO_NEVER;
    }
#endif
    co_svc_send_state(node, (uint8_t)node->nmt_state);
    /* Keep the cadence; after a long gap (process called late) start again from now rather
     * than sending a burst of missed heartbeats. */
    hb->next += hb->period_us;
    if (hb->next <= now) {
        hb->next = now + hb->period_us;
    }
    return hb->next;
}
