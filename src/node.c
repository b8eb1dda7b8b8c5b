/* Node: set-up, frame dispatch by COB-ID, the ordered transmit queue and the process loop. */
#include "canopen/node.h"

#include <stddef.h>
#include <string.h>

#include "canopen/store.h"
#include "dispatch.h"
#include "services.h"

co_node_config co_node_default_config(void)
{
    return (co_node_config){.sdo_timeout_us = CO_SDO_TIMEOUT_US};
}

/* --- set-up ----------------------------------------------------------------------------------- */

/* The bytes of driver to options (storage, events, comm_error_behaviour, the store's scratch),
 * laid out alike in co_node_config and co_node. */
#define CONFIG_BLOCK (offsetof(co_node_config, options) + sizeof(uint32_t) - \
                      offsetof(co_node_config, driver))
#define CONFIG_SAME(field) (offsetof(co_node_config, field) - offsetof(co_node_config, driver) == \
                            offsetof(co_node, field) - offsetof(co_node, driver))
typedef char config_block_check[CONFIG_SAME(storage) && CONFIG_SAME(events) &&
                                CONFIG_SAME(comm_error_behaviour) && CONFIG_SAME(store_scratch) &&
                                CONFIG_SAME(store_scratch_size) && CONFIG_SAME(options) ? 1 : -1];

/* co_node_init past the tests of the pointers and the node-ID. */
static bool set_up(co_node *node, const co_node_config *cfg)
{
    /* A behaviour this build left out (include/canopen/config.h) is refused, not ignored (the
     * settings ORed together: one test). */
    uint32_t left_out = (cfg->options & ~(uint32_t)CO_CONFIG_NODE_OPTIONS) |
                        (cfg->pdo.flags & ~(uint32_t)CO_CONFIG_PDO_FLAGS);
#if !CO_CONFIG_PDO_TUNING
    left_out |= cfg->pdo.tpdo_inhibit_unit_us | cfg->pdo.tpdo_inhibit_min_us |
                cfg->pdo.tpdo_event_min_us | cfg->pdo.value_abort | cfg->pdo.busy_abort;
#endif
    if (left_out != 0u) {
        return false;
    }
#if CO_CONFIG_TIME32
    /* times a deadline is set ahead by must fit (include/canopen/time_base.h) */
    if (cfg->sdo_timeout_us > CO_TIME_SPAN_MAX || cfg->pdo.tpdo_inhibit_min_us > CO_TIME_SPAN_MAX ||
        cfg->pdo.tpdo_event_min_us > CO_TIME_SPAN_MAX) {
        return false;
    }
#endif
    memset(node, 0, sizeof *node);
    node->od = cfg->od;
    node->values = cfg->values;
    memcpy(&node->driver, &cfg->driver, CONFIG_BLOCK);
    node->node_id = cfg->node_id;
    node->nmt_state = CO_NMT_INITIALISING;
    /* 0: CO_SDO_TIMEOUT_US. The SDO server and the heartbeat producer are set up by the reset of
     * co_node_start (co_sdo_server_init applies that default and makes the server idle,
     * co_heartbeat_producer_configure schedules the heartbeat); until then the node is
     * INITIALISING and neither runs. */
    node->sdo.timeout_us = cfg->sdo_timeout_us;
    if (CO_NODE_OPTION(node, CO_NODE_SDO_HIDDEN_RANGE)) {
        node->sdo.hidden_first = cfg->sdo_hidden_first;
        node->sdo.hidden_last = cfg->sdo_hidden_last;
    }
    /* the defaults; a dictionary with limits this build cannot check is refused (the walk
     * looks at every sub-entry: see CO_CONFIG_OD_WIDE_LIMITS) */
    if (!co_node_copy_values(node, node->values, NULL, CO_GROUP_ALL)) {
        return false;
    }
#if CO_HOOK_MAP_ENTRIES > 0
    for (uint32_t e = 0; e < cfg->od->entry_count && e < CO_HOOK_MAP_ENTRIES; e++) {
        node->hook_map[e] = co_node_hook_search(node, cfg->od->entries[e].index); /* no hooks yet */
    }
#endif
    co_emcy_init(node);
    co_errctl_init(node);
    co_sync_init(node);
    co_pdo_init(node, &cfg->pdo);
    return true;
}

bool co_node_init_layout(co_node *node, const co_node_config *cfg, uint32_t layout)
{
    /* the layout first: a caller that sees another co_node may have passed a smaller one than
     * set_up would clear */
    return layout == CO_LAYOUT_SIGNATURE && node != NULL && cfg != NULL && cfg->od != NULL &&
           cfg->values != NULL && cfg->driver.send != NULL && cfg->node_id >= 1u &&
           cfg->node_id <= 127u && set_up(node, cfg);
}

#if CO_CONFIG_TIME32
/* The co_time values the services keep in the node: count of them, words * 4 bytes apart (their
 * structs hold a co_time: a multiple of 4 bytes), from offset. */
typedef struct time_run {
    uint16_t offset;
    uint8_t count;
    uint8_t words;
} time_run;
#define TIME_ONE(field) {(uint16_t)offsetof(co_node, field), 1u, 0u}
#define TIME_EACH(array, field, n) \
    {(uint16_t)offsetof(co_node, array[0].field), n, \
     (uint8_t)(sizeof(((co_node *)0)->array[0]) / 4u)}
typedef char emcy_times_adjacent[offsetof(co_emcy, last_sent) ==
                                 offsetof(co_emcy, next_allowed) + sizeof(co_time) ? 1 : -1];
typedef char time_run_fits[sizeof(co_node) <= UINT16_MAX && sizeof(co_hb_consumer) / 4u <= 255u &&
                           sizeof(co_rpdo) / 4u <= 255u && sizeof(co_tpdo) / 4u <= 255u
                           ? 1 : -1];

/* Moves the epoch forward to epoch: every time the services keep moves back by as much. */
static void move_epoch(co_node *node, uint64_t epoch)
{
    static const time_run times[] = {
        TIME_ONE(now), TIME_ONE(heartbeat.next),
        {(uint16_t)offsetof(co_node, emcy.next_allowed), 2u, 1u}, /* and emcy.last_sent */
        TIME_ONE(sdo.deadline),
        TIME_EACH(errctl.hb, deadline, CO_HB_CONSUMER_MAX),
        TIME_EACH(pdo.rpdo, deadline, CO_MAX_RPDO),
        TIME_EACH(pdo.tpdo, inhibit_end, CO_MAX_TPDO),
        TIME_EACH(pdo.tpdo, event_deadline, CO_MAX_TPDO),
    };
    /* a co_time below CO_NEVER is below d or d's 32 bits alike when d is larger */
    uint64_t d = epoch - node->epoch;
    co_time d32 = d >= CO_NEVER ? CO_NEVER : (co_time)d;
    node->epoch = epoch;
    for (const time_run *r = times; r < times + sizeof times / sizeof times[0]; r++) {
        co_time *t = (co_time *)(void *)((uint8_t *)node + r->offset);
        for (uint32_t n = r->count; n != 0u; n--, t += r->words) {
            /* CO_NEVER stays, a time older than the new epoch becomes 0 */
            if (*t != CO_NEVER) {
                *t = *t > d32 ? *t - d32 : 0u;
            }
        }
    }
    /* The services' earliest deadlines are looked at afresh: a wide deadline beyond co_time's
     * range (scheduled as CO_NEVER - 1) may now be within it. */
    node->errctl.next = 0u;
    node->pdo.next = 0u;
    co_node_recheck(node);
}

co_time co_time_from_wide(const co_node *node, co_time_wide t)
{
    uint64_t d = t - node->epoch;
    if (t < node->epoch) {
        return 0u;
    }
    if ((d >> 32) == 0u && (co_time)d != CO_NEVER) {
        return (co_time)d;
    }
    return CO_NEVER - (t != CO_WIDE_NEVER);
}

co_time co_node_time(co_node *node, uint64_t now)
{
    /* a time before the epoch (a clock gone back that far) is the epoch: 0 */
    co_time t = co_time_from_wide(node, now);
    if (t >= CO_TIME32_REBASE_AT) {
        move_epoch(node, now - CO_TIME32_HISTORY);
        t = CO_TIME32_HISTORY;
    }
    return t;
}
#endif

/* The API time of a co_time deadline. */
static inline uint64_t api_time(const co_node *node, co_time t)
{
#if CO_CONFIG_TIME32
    return t == CO_NEVER ? CO_TIME_NEVER : node->epoch + t;
#else
    (void)node;
    return t;
#endif
}

/* The entries of each CO_GROUP_*, as a bit per block of 0x1000 indices (index >> 12): 0x0000-0xFFFF,
 * 0x1000-0x1FFF, 0x6000-0x9FFF and 0x2000-0x5FFF. */
static const uint16_t group_blocks[4] = {0xFFFFu, 0x0002u, 0x03C0u, 0x003Cu};

bool co_node_copy_values(const co_node *node, uint8_t *dst, const uint8_t *src, uint32_t what)
{
    const co_od *od = node->od;
    uint32_t blocks = group_blocks[what & 3u];
    uint32_t flags = what & CO_OD_PERSIST;
    uint32_t end = flags != 0u ? od->persist_size : od->value_size;
    bool narrow = true;
    const co_od_entry *entry = od->entries;
    for (uint32_t left = od->entry_count; left != 0u; left--, entry++) { /* (a count: no end pointer) */
        if (((blocks >> (entry->index >> 12)) & 1u) == 0u) {
            continue;
        }
        const co_od_sub *sub = co_od_entry_subs(entry);
        for (uint32_t n = co_od_entry_sub_count(entry); n != 0u; n--, sub++) {
            uint32_t size = co_od_sub_size(sub);
            uint32_t at = co_od_value_offset(entry, sub);
#if !CO_CONFIG_OD_WIDE_LIMITS
            /* limits on a REAL32, a DOMAIN (size 0) or a wider value: not checkable here */
            if ((sub->flags & CO_OD_LIMITS) != 0u &&
                (size == 0u || size > 4u || sub->type == CO_REAL32)) {
                narrow = false;
            }
#endif
            /* a DOMAIN's size is 0 */
            if ((sub->flags & flags) != flags || size == 0u || at + size > end) {
                continue;
            }
            uint8_t *value = dst + at;
            if (src != NULL) {
                memcpy(value, src + at, size);
                continue;
            }
            co_od_default_copy(node->od, value, at, size);
            if ((sub->flags & CO_OD_NODEID) != 0u) {
                /* Add the node-ID to the little-endian base value (COB-IDs: no carry beyond
                 * bit 10 in practice, but add with carry anyway; a carry of 0 rewrites the
                 * bytes as they are). */
                uint32_t carry = node->node_id;
                for (uint32_t i = 0; i < size; i++) {
                    carry += value[i];
                    value[i] = (uint8_t)carry;
                    carry >>= 8;
                }
            }
        }
    }
    return narrow;
}

/* --- transmit queue ------------------------------------------------------------------------ */

static void flush_queue(co_node *node)
{
    co_tx_queue *q = &node->txq;
    while (q->count != 0u) {
        if (!node->driver.send(node->driver.ctx, &q->frames[q->head])) {
            return;
        }
        CO_COUNT(node->stats.tx_frames);
        q->head = (uint16_t)((q->head + 1u) & (CO_TX_QUEUE_LEN - 1u));
        q->count--;
    }
}

/* The driver refused, or frames are waiting: queue it behind them. */
static CO_NOINLINE bool enqueue(co_node *node, const co_frame *frame)
{
    co_tx_queue *q = &node->txq;
    if (q->count == CO_TX_QUEUE_LEN) {
        CO_COUNT(node->stats.tx_dropped);
        return false;
    }
    q->frames[(q->head + q->count) & (CO_TX_QUEUE_LEN - 1u)] = *frame;
    q->count++;
    CO_COUNT(node->stats.tx_deferred);
    return true;
}

bool co_node_send(co_node *node, const co_frame *frame)
{
    if (node->txq.count == 0u && node->driver.send(node->driver.ctx, frame)) {
        CO_COUNT(node->stats.tx_frames);
        return true;
    }
    return enqueue(node, frame);
}

void co_node_tx_ready(co_node *node)
{
    flush_queue(node);
    co_node_recheck(node); /* a service waiting for room (block upload) goes on at once */
}

/* --- hooks --------------------------------------------------------------------------------- */

/* The core's services that hear writes to their objects (src/od_internal.h), in index order. */
const co_od_service co_node_services[CO_NODE_SERVICES] = {
    {0x1003u, 0x1003u, co_emcy_param_written},
    {0x1005u, 0x1007u, co_sync_param_written},
    {0x100Cu, 0x100Du, co_errctl_guarding_written},
    {0x1010u, 0x1011u, co_store_written},
    {0x1014u, 0x1015u, co_emcy_param_written},
    {0x1016u, 0x1016u, co_errctl_consumer_written},
    {0x1017u, 0x1017u, co_heartbeat_time_written},
    {0x1019u, 0x1019u, co_sync_param_written},
    {0x1029u, 0x1029u, co_errctl_consumer_written},
    {0x1400u, 0x1BFFu, co_pdo_param_written}
};

co_abort co_node_service_refresh(co_node *node, co_od_ref ref)
{
    uint16_t index = ref.entry->index;
    if (index == 0x1010u || index == 0x1011u) {
        return co_store_refresh(node, NULL, ref);
    }
    return CO_ABORT_NONE;
}
/* Every slot (src/od_internal.h) fits the byte of node->hook_map: CO_MAX_HOOKS is 1..245. */
typedef char hook_slots_fit_a_byte[CO_MAX_HOOKS >= 1u &&
                                   CO_SLOT_CORE + CO_NODE_SERVICES <= 0x100u ? 1 : -1];

bool co_node_add_hook(co_node *node, const co_od_hook *hook)
{
    if (node->hook_count >= CO_MAX_HOOKS || hook->index_first > hook->index_last) {
        return false;
    }
    node->hooks[node->hook_count++] = *hook;
#if CO_HOOK_MAP_ENTRIES > 0
    /* The new hook serves every mapped entry in its range (later registrations win). */
    const co_od *od = node->od;
    uint32_t lo = 0, hi = od->entry_count; /* first entry at or above index_first */
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2u;
        if (od->entries[mid].index < hook->index_first) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    for (uint32_t e = lo; e < od->entry_count && e < CO_HOOK_MAP_ENTRIES &&
                          od->entries[e].index <= hook->index_last;
         e++) {
        node->hook_map[e] = node->hook_count; /* slot + 1 */
    }
#endif
    co_pdo_hooks_changed(node);
    return true;
}

const co_od_hook *co_node_find_hook(const co_node *node, uint16_t index)
{
    return co_node_slot_hook(node, co_node_hook_search(node, index));
}

const co_od_hook *co_node_entry_hook(const co_node *node, const co_od_entry *entry)
{
    return co_node_slot_hook(node, co_node_hook_slot(node, entry));
}

/* --- reception and the process loop --------------------------------------------------------- */

/* The dispatch of co_node_rx at the node's time now. */
static CO_ONE_COPY void dispatch(co_node *node, const co_frame *frame, co_time now)
{
    if (frame->dlc > 8u || frame->id > 0x7FFu) {
        CO_COUNT(node->stats.rx_malformed);
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
    /* INITIALISING and STOPPED take nothing but NMT and error control. */
    if (!co_nmt_communicating(node->nmt_state)) {
        CO_COUNT(node->stats.rx_ignored);
        return;
    }
    if (frame->id == node->sdo_rx_cob) {
        /* it drops and counts an RTR frame, and sends the TPDOs mapping a value a request wrote */
        co_sdo_server_rx(node, frame, now);
        return;
    }
    if (frame->id == node->sync.cob_id) {
        co_sync_rx(node, frame, now);
        return;
    }
    if (node->nmt_state == CO_NMT_OPERATIONAL && co_pdo_rx(node, frame, now)) {
        return;
    }
    CO_COUNT(node->stats.rx_ignored);
}

void co_node_rx(co_node *node, const co_frame *frame, uint64_t api_now)
{
    CO_COUNT(node->stats.rx_frames);
    co_time now = co_node_time(node, api_now);
    node->now = now;
    dispatch(node, frame, now);
}

static co_time earliest(co_time a, co_time b)
{
    return a < b ? a : b;
}

static co_time process_pass(co_node *node, co_time now);

uint64_t co_node_process(co_node *node, uint64_t api_now)
{
    co_time now = co_node_time(node, api_now);
    node->now = now;
    /* Nothing due, nothing queued, no TPDO event waiting: node->next is what the pass would
     * return (the services keep it so, see src/schedule.h), so a tick costs a few compares. */
    co_time next = now < node->next && node->txq.count == 0u && !node->pdo.pending
                       ? node->next
                       : process_pass(node, now);
    return api_time(node, next);
}

/* The pass of co_node_process over every service, behind its skip test. */
static CO_NOINLINE co_time process_pass(co_node *node, co_time now)
{
    flush_queue(node);
    /* From here the services set their deadlines afresh; what they set while running (a callback
     * resetting communication, say) lowers node->next from NEVER. */
    node->next = CO_NEVER;
    if (node->nmt_state == CO_NMT_INITIALISING) {
        return CO_NEVER;
    }
    co_time next = co_heartbeat_producer_process(node, now);
    /* a service with nothing under way would only answer CO_NEVER: not called */
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
    /* What a callback of the pass changed (node->next lowered from NEVER) waits for the next
     * call, as it always has; only the skip test sees it. */
    if (next < node->next) {
        node->next = next;
    }
    return next;
}
