/* Node: set-up, frame dispatch by COB-ID, the ordered transmit queue and the process loop. */
#include "canopen/node.h"

#include <string.h>

#include "canopen/store.h"
#include "node_internal.h"

co_node_config co_node_default_config(void)
{
    co_node_config cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.sdo_timeout_us = CO_SDO_TIMEOUT_US;
    return cfg;
}

/* 0x1017 written: the heartbeat restarts with the new period from the time of the write. */
static co_abort heartbeat_time_written(co_node *node, void *ctx, co_od_ref ref,
                                       const uint8_t *data, uint32_t len, co_od_origin origin)
{
    (void)ctx;
    (void)origin;
    (void)len;
    if (ref.sub->subindex == 0u) {
        node->heartbeat.period_us = (uint32_t)co_get_le16(data) * 1000u;
        node->heartbeat.next = node->heartbeat.period_us != 0u
                                   ? node->now + node->heartbeat.period_us
                                   : CO_TIME_NEVER;
    }
    return CO_ABORT_NONE;
}

bool co_node_init(co_node *node, const co_node_config *cfg)
{
    if (node == NULL || cfg == NULL || cfg->od == NULL || cfg->values == NULL ||
        cfg->driver.send == NULL || cfg->node_id < 1u || cfg->node_id > 127u) {
        return false;
    }
    memset(node, 0, sizeof *node);
    node->od = cfg->od;
    node->values = cfg->values;
    node->driver = cfg->driver;
    node->storage = cfg->storage;
    node->events = cfg->events;
    node->options = cfg->options;
    node->node_id = cfg->node_id;
    node->nmt_state = CO_NMT_INITIALISING;
    node->sdo.timeout_us = cfg->sdo_timeout_us != 0u ? cfg->sdo_timeout_us : CO_SDO_TIMEOUT_US;
    node->heartbeat.next = CO_TIME_NEVER;
    node->comm_error_behaviour = cfg->comm_error_behaviour;
    node->store_scratch = cfg->store_scratch;
    node->store_scratch_size = cfg->store_scratch_size;
    co_node_restore_defaults(node, 0x0000u, 0xFFFFu);

    /* Built on the stack: a static const with a function pointer lands in .data.rel.ro in a
     * position-independent build, and the core keeps no data outside the node. */
    const co_od_hook heartbeat_hook = {0x1017u, 0x1017u, NULL, heartbeat_time_written,
                                       NULL, NULL, NULL};
    (void)co_node_add_hook(node, &heartbeat_hook);
    co_emcy_init(node);
    co_errctl_init(node);
    co_store_init(node);
    co_sync_init(node);
    co_pdo_init(node, &cfg->pdo);
    return true;
}

void co_node_start(co_node *node, uint64_t now)
{
    node->now = now;
    co_nmt_reset_node(node, now);
}

void co_node_restore_defaults(co_node *node, uint16_t first, uint16_t last)
{
    const co_od *od = node->od;
    for (uint32_t e = 0; e < od->entry_count; e++) {
        const co_od_entry *entry = &od->entries[e];
        if (entry->index < first || entry->index > last) {
            continue;
        }
        for (uint32_t s = 0; s < entry->sub_count; s++) {
            const co_od_sub *sub = &entry->subs[s];
            if (sub->type == CO_DOMAIN || sub->size == 0u) {
                continue;
            }
            uint8_t *value = node->values + sub->offset;
            memcpy(value, od->defaults + sub->offset, sub->size);
            if ((sub->flags & CO_OD_NODEID) != 0u) {
                /* Add the node-ID to the little-endian base value (COB-IDs: no carry beyond
                 * bit 10 in practice, but add with carry anyway). */
                uint32_t carry = node->node_id;
                for (uint32_t i = 0; i < sub->size && carry != 0u; i++) {
                    carry += value[i];
                    value[i] = (uint8_t)carry;
                    carry >>= 8;
                }
            }
        }
    }
}

void co_node_load_stored(co_node *node, uint32_t len)
{
    if (node->storage == NULL || node->storage->load == NULL || len == 0u) {
        return;
    }
    /* load() writes straight into the block; it must return false without writing when there is
     * no valid image, so a failed load leaves the defaults in place. */
    (void)node->storage->load(node->storage->ctx, node->od->layout_hash, 0, node->values, len);
}

/* --- transmit queue ------------------------------------------------------------------------ */

static void flush_queue(co_node *node)
{
    co_tx_queue *q = &node->txq;
    while (q->count != 0u) {
        if (!node->driver.send(node->driver.ctx, &q->frames[q->head])) {
            return;
        }
        node->stats.tx_frames++;
        q->head = (uint16_t)((q->head + 1u) & (CO_TX_QUEUE_LEN - 1u));
        q->count--;
    }
}

bool co_node_send(co_node *node, const co_frame *frame)
{
    co_tx_queue *q = &node->txq;
    if (q->count == 0u) {
        if (node->driver.send(node->driver.ctx, frame)) {
            node->stats.tx_frames++;
            return true;
        }
    }
    if (q->count == CO_TX_QUEUE_LEN) {
        node->stats.tx_dropped++;
        return false;
    }
    q->frames[(q->head + q->count) & (CO_TX_QUEUE_LEN - 1u)] = *frame;
    q->count++;
    node->stats.tx_deferred++;
    return true;
}

void co_node_tx_ready(co_node *node)
{
    flush_queue(node);
}

/* --- hooks --------------------------------------------------------------------------------- */

bool co_node_add_hook(co_node *node, const co_od_hook *hook)
{
    if (node->hook_count >= CO_MAX_HOOKS || hook->index_first > hook->index_last) {
        return false;
    }
    node->hooks[node->hook_count++] = *hook;
    return true;
}

const co_od_hook *co_node_find_hook(const co_node *node, uint16_t index)
{
    for (uint32_t i = node->hook_count; i > 0u; i--) {
        const co_od_hook *h = &node->hooks[i - 1u];
        if (index >= h->index_first && index <= h->index_last) {
            return h;
        }
    }
    return NULL;
}

/* --- reception and the process loop --------------------------------------------------------- */

void co_node_rx(co_node *node, const co_frame *frame, uint64_t now)
{
    node->stats.rx_frames++;
    node->now = now;
    if (frame->dlc > 8u || frame->id > 0x7FFu) {
        node->stats.rx_malformed++;
        return;
    }
    if (frame->id == 0u) {
        co_nmt_rx(node, frame, now);
        return;
    }
    if ((frame->id & 0x780u) == 0x700u) { /* 0x700-0x77F: error control, also in STOPPED */
        co_errctl_rx(node, frame, now);
        return;
    }
    switch (node->nmt_state) {
    case CO_NMT_PRE_OPERATIONAL:
    case CO_NMT_OPERATIONAL:
        break;
    default: /* INITIALISING and STOPPED take nothing but NMT and error control */
        node->stats.rx_ignored++;
        return;
    }
    if (frame->id == node->sdo_rx_cob) {
        if ((frame->flags & CO_FRAME_RTR) != 0u) {
            node->stats.rx_malformed++;
            return;
        }
        co_sdo_server_rx(node, frame, now);
        if (node->pdo.pending) {
            (void)co_pdo_process(node, now); /* TPDOs mapping a value the SDO wrote */
        }
        return;
    }
    if (frame->id == node->sync.cob_id) {
        co_sync_rx(node, frame, now);
        return;
    }
    if (node->nmt_state == CO_NMT_OPERATIONAL && co_pdo_rx(node, frame, now)) {
        return;
    }
    node->stats.rx_ignored++;
}

static uint64_t earliest(uint64_t a, uint64_t b)
{
    return a < b ? a : b;
}

uint64_t co_node_process(co_node *node, uint64_t now)
{
    node->now = now;
    if (node->txq.count != 0u) {
        flush_queue(node);
    }
    if (node->nmt_state == CO_NMT_INITIALISING) {
        return CO_TIME_NEVER;
    }
    uint64_t next = co_heartbeat_producer_process(node, now);
    if (node->emcy.queued_count != 0u) {
        next = earliest(next, co_emcy_process(node, now));
    }
    next = earliest(next, now >= node->errctl.next ? co_errctl_process(node, now)
                                                   : node->errctl.next);
    if (node->sdo.state != CO_SDO_IDLE) {
        next = earliest(next, co_sdo_server_process(node, now));
    }
    next = earliest(next, co_sync_process(node, now));
    next = earliest(next, co_pdo_process(node, now));
    return next;
}
