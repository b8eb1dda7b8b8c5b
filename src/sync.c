/* SYNC: consumer, producer, window and counter (CiA 301 §7.2.5), and the hook that checks writes
 * to 0x1005-0x1007 and 0x1019. */
#include "canopen/sync.h"

#include "canopen/node.h"
#include "canopen/pdo.h"
#include "dispatch.h"
#include "services.h"

#define SYNC_PRODUCER 0x40000000u /* 0x1005 bit 30: this node generates SYNC */
#define SYNC_FRAME_29 0x20000000u /* 0x1005 bit 29: 29-bit CAN-ID (not supported) */
#define SYNC_ID_BITS_11_28 0x1FFFF800u
/* (v & (SYNC_FRAME_29 | SYNC_ID_BITS_11_28)) == 0, shifted: no mask constant */
#define BITS_11_29_CLEAR(v) (((v) << 2) < 1u << 13)

static bool can_produce(const co_node *node)
{
    return !CO_PDO_FLAG(node, CO_PDO_SYNC_CONSUMER_ONLY) &&
           co_node_find_entry(node, 0x1006u) != NULL;
}

/* (Re)starts the producer's period from now, with the counter back at 1. Only a producer with a
 * period in PRE-OPERATIONAL or OPERATIONAL has a next SYNC (co_sync_process relies on it): in
 * INITIALISING, co_sync_nmt_changed starts it on entering PRE-OPERATIONAL. The next pass looks
 * at every deadline again (cheaper here than working out whether the old one was the earliest;
 * no frame-path operation restarts the producer). */
static void restart_producer(co_node *node, co_time now)
{
    co_sync *s = &node->sync;
    bool runs = co_nmt_communicating(node->nmt_state);
    s->counter = 1u;
    s->next = (runs && s->producer && s->period_us != 0u)
                  ? co_time_wide_of(node, now) + s->period_us
                  : CO_WIDE_NEVER;
    co_node_recheck(node);
}

/* Loads 0x1005, 0x1006, 0x1007 and 0x1019: values a write has checked, or what reset
 * communication restored (a stored value a write would refuse leaves SYNC off or the counter
 * unused). */
static void load(co_node *node)
{
    co_sync *s = &node->sync;
    /* without 0x1005 (all ones: bits 11-28 set), no SYNC */
    uint32_t cob = co_node_od_value(node, 0x1005u, 0u, UINT32_MAX);
    bool usable = BITS_11_29_CLEAR(cob);
    s->cob_id = usable ? (uint16_t)(cob & 0x7FFu) : CO_SYNC_NO_COB;
    s->producer = usable && (cob & SYNC_PRODUCER) != 0u && can_produce(node);
    s->period_us = co_svc_od_value(node, 0x1006u);
    s->window_us = co_svc_od_value(node, 0x1007u);
    uint32_t overflow = co_svc_od_value(node, 0x1019u);
    s->overflow = overflow - 2u <= 240u - 2u ? (uint8_t)overflow : 0u; /* 0, 1, > 240: none */
}

/* An index as its distance from 0x1005 (small constants compare in one 2-byte instruction). */
#define AT(index) ((index) - 0x1005u)

/* The abort for writing v to 0x1005 or 0x1019 (at: AT(index); 0: accepted). */
static co_abort check_write(const co_node *node, uint32_t at, uint32_t v)
{
    const co_sync *s = &node->sync;
    if (at == AT(0x1005u)) {
        bool produce = (v & SYNC_PRODUCER) != 0u;
        if (!BITS_11_29_CLEAR(v) ||
            co_can_id_restricted((uint16_t)(v & 0x7FFu)) || (produce && !can_produce(node))) {
            return co_pdo_value_abort(node);
        }
        if (produce && s->producer && (uint16_t)(v & 0x7FFu) != s->cob_id) {
            return co_pdo_busy_abort(node);
        }
    } else if (at == AT(0x1019u)) {
        if (v == 1u || v > 240u) {
            return co_pdo_value_abort(node);
        }
        if (s->period_us != 0u && v != s->overflow) {
            return CO_ABORT_DEVICE_STATE; /* CiA 301: only while 0x1006 is 0 */
        }
    }
    return CO_ABORT_NONE;
}

co_abort co_sync_param_written(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                               uint32_t len, co_od_origin origin)
{
    (void)ctx;
    (void)origin;
    co_sync *s = &node->sync;
    uint32_t at = AT((uint32_t)ref.entry->index);
    if (ref.sub->subindex != 0u) {
        return CO_ABORT_NONE;
    }
    co_abort rc = check_write(node, at, co_le_value(data, len));
    if (rc != CO_ABORT_NONE) {
        return rc;
    }
    bool was = s->producer;
    co_svc_store(node, data, ref);
    load(node);
    if (at == AT(0x1019u)) {
        s->counter = s->producer ? 1u : 0u; /* (0x1019 leaves the producer as it was) */
    } else if (at == AT(0x1006u) || s->producer != was) {
        /* a new period, or the producer switched on or off, restarts it */
        restart_producer(node, node->now);
    }
    return CO_ABORT_NONE;
}

void co_sync_configure(co_node *node, co_time now)
{
    co_sync *s = &node->sync;
    load(node);
    s->seen = false;
    restart_producer(node, now);
    s->counter = s->producer ? 1u : 0u; /* a producer sends 1 next; a consumer has seen none */
}

/* One SYNC happened (received or produced). */
static CO_ONE_COPY void sync_event(co_node *node, uint8_t counter, co_time now)
{
    co_sync *s = &node->sync;
    s->last = co_time_wide_of(node, now);
    s->seen = true;
    if (node->nmt_state == CO_NMT_OPERATIONAL) {
        co_pdo_sync(node, counter, now);
    }
}

void co_sync_rx(co_node *node, const co_frame *frame, co_time now)
{
    co_sync *s = &node->sync;
    bool counted = s->overflow != 0u;
    /* 0 or 1 byte without the counter, exactly 1 with it; never an RTR */
    if ((frame->flags & CO_FRAME_RTR) != 0u || frame->dlc > 1u || (counted && frame->dlc == 0u)) {
        CO_COUNT(s->bad_length);
        CO_COUNT(node->stats.rx_malformed);
        return;
    }
    /* (taken before the producer test: one path, not one per counter case) */
    uint8_t counter = counted ? frame->data[0] : 0u;
    if (s->producer) {
        /* a second producer on our CAN-ID: ours is the one we follow */
        CO_COUNT(node->stats.rx_ignored);
        return;
    }
    s->counter = counter;
    sync_event(node, counter, now);
}

co_time co_sync_process(co_node *node, co_time now)
{
    co_sync *s = &node->sync;
    /* next is CO_WIDE_NEVER unless the node produces SYNC with a period in PRE-OPERATIONAL or
     * OPERATIONAL (restart_producer, co_sync_nmt_changed) */
    co_time at = co_time_from_wide(node, s->next);
    /* not due, or off (CO_NEVER: with CO_CONFIG_TIME32 a now is always below it, time_base.h) */
    if (now < at || (!CO_CONFIG_TIME32 && at == CO_NEVER)) {
        return at;
    }
    uint8_t counter = 0u;
    if (s->overflow != 0u) {
        counter = s->counter;
        s->counter = counter >= s->overflow ? 1u : (uint8_t)(counter + 1u);
    }
    /* with the counter in use one byte, the counter; else none */
    co_svc_send(node, s->cob_id, s->overflow != 0u ? 1u : 0u, counter);
    /* Keep the cadence; after a long gap start again from now rather than sending a burst. */
    co_time_wide wide_now = co_time_wide_of(node, now);
    s->next += s->period_us;
    if (s->next <= wide_now) {
        s->next = wide_now + s->period_us;
    }
    sync_event(node, counter, now);
    return co_time_from_wide(node, s->next);
}

bool co_sync_window_open(const co_node *node, co_time now)
{
    const co_sync *s = &node->sync;
    return s->window_us == 0u || !s->seen || co_time_wide_of(node, now) - s->last < s->window_us;
}

void co_sync_nmt_changed(co_node *node, co_nmt_state from, co_nmt_state to)
{
    /* Between PRE-OPERATIONAL and OPERATIONAL the period goes on; any other change starts it
     * (on entering one of them) or stops it (restart_producer looks at the new state). */
    bool was_running = co_nmt_communicating(from);
    bool runs = co_nmt_communicating(to);
    if (!was_running || !runs) {
        restart_producer(node, node->now);
    }
}
