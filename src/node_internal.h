/* Functions the core's services share but an application does not call. */
#ifndef CANOPEN_NODE_INTERNAL_H
#define CANOPEN_NODE_INTERNAL_H

#include "canopen/node.h"
#include "compiler.h"
#include "od_internal.h"

/* A CO_NODE_* option / CO_PDO_* flag in effect: constant false when the build leaves it out
 * (CO_CONFIG_NODE_OPTIONS / CO_CONFIG_PDO_FLAGS, include/canopen/config.h). */
#define CO_NODE_OPTION(node, opt) \
    ((CO_CONFIG_NODE_OPTIONS & (opt)) != 0u && ((node)->options & (opt)) != 0u)
#define CO_PDO_FLAG(node, flag) \
    ((CO_CONFIG_PDO_FLAGS & (flag)) != 0u && ((node)->pdo.cfg.flags & (flag)) != 0u)

/* The abort for an invalid PDO or SYNC parameter value / a write the PDO's state forbids
 * (co_pdo_config.value_abort / busy_abort, 0x06040043 by default). */
static inline co_abort co_pdo_value_abort(const co_node *node)
{
#if CO_CONFIG_PDO_TUNING
    if (node->pdo.cfg.value_abort != 0u) {
        return node->pdo.cfg.value_abort;
    }
#else
    (void)node;
#endif
    return CO_ABORT_PARAM_INCOMPATIBLE;
}
static inline co_abort co_pdo_busy_abort(const co_node *node)
{
#if CO_CONFIG_PDO_TUNING
    if (node->pdo.cfg.busy_abort != 0u) {
        return node->pdo.cfg.busy_abort;
    }
#else
    (void)node;
#endif
    return CO_ABORT_PARAM_INCOMPATIBLE;
}

/* A little-endian unsigned value of len bytes (1..4; of a longer one, the first 4). */
uint32_t co_le_value(const uint8_t *data, uint32_t len);

/* The value of numeric object index:subindex of up to 4 bytes (sub-entries of other sizes and
 * DOMAINs do not count), or dflt when the dictionary has none. */
uint32_t co_node_od_value(const co_node *node, uint32_t index, uint32_t subindex, uint32_t dflt);

/* CAN-IDs CiA 301 §7.3.5 keeps out of every configurable communication object (NMT, SYNC/EMCY
 * of other nodes, TIME, SDO, NMT error control, LSS); the default 0x080 is not one of them. */
bool co_can_id_restricted(uint16_t id);

/* Counts an event in one of the statistics counters (co_node_stats, co_pdo_stats, the services'
 * own); nothing when the build leaves the counters out (CO_CONFIG_STATS 0: they stay 0). */
#if CO_CONFIG_STATS
#define CO_COUNT(counter) ((void)(counter)++)
#else
#define CO_COUNT(counter) ((void)sizeof(counter)) /* not evaluated */
#endif

/* Groups of objects, as the sub-entries 1-4 of 0x1010/0x1011 (sub - 1) name them. */
#define CO_GROUP_ALL 0u  /* 0x0000-0xFFFF */
#define CO_GROUP_COMM 1u /* 0x1000-0x1FFF, the communication profile */
#define CO_GROUP_APP 2u  /* 0x6000-0x9FFF, the device profile */
#define CO_GROUP_MANU 3u /* 0x2000-0x5FFF, manufacturer-specific */

/* Copies the values of the objects of group (what & 3: a CO_GROUP_*) into dst, at their offsets
 * in the value block: with CO_OD_PERSIST in what those of the persistent sub-entries (which end
 * at or below od->persist_size), else those of every sub-entry; from src, or with src NULL their
 * defaults with the node-ID applied. DOMAINs have no value. False when a sub-entry of those
 * objects has limits this build cannot check (CO_CONFIG_OD_WIDE_LIMITS 0: on a REAL, a DOMAIN
 * or a value wider than 32 bits), which co_node_init refuses. */
bool co_node_copy_values(const co_node *node, uint8_t *dst, const uint8_t *src, uint32_t what);

/* Copies the default values (node-ID applied) of the objects of group (a CO_GROUP_*) into the
 * value block, then overwrites its first len bytes with the stored image, if there is one (len 0:
 * none). */
void co_node_load_values(co_node *node, uint32_t group, uint32_t len);

/* The end of co_od_write_ref, for a value the caller has already checked (co_od_check_value,
 * access, mappability) and whose handler it has resolved (co_node_hook_slot; 0 for
 * CO_ORIGIN_APP, whose writes skip the handlers): the handler of slot, then the value is stored
 * and the TPDOs mapping it are told. */
co_abort co_od_write_checked(co_node *node, const co_od_ref *ref, uint8_t slot,
                             const uint8_t *data, uint32_t len, co_od_origin origin);

/* co_od_check_value of the sub-entry sub (the checks need no more than the sub-entry). */
co_abort co_od_check_sub(const co_od *od, const co_od_sub *sub, const uint8_t *data,
                         uint32_t len);

/* A value's length against its sub-entry's type (not a DOMAIN): CO_ABORT_TYPE_TOO_LONG beyond its
 * size, CO_ABORT_TYPE_TOO_SHORT below it except for a string (co_od_check_value's first checks). */
co_abort co_od_check_length(const co_od_sub *sub, uint32_t len);

/* co_od_read_ref, which also gives the object's size in *total: the value's length, or the total
 * a DOMAIN's hook announced in its first read (at offset 0; 0 unless the hook sets it); not set
 * when the core refuses the read. */
co_abort co_od_read_sized(co_node *node, const co_od_ref *ref, uint8_t *buf, uint32_t cap,
                          uint32_t *len, uint32_t *total, co_od_origin origin);

/* Who handles reads and writes of an entry, its slot: CO_SLOT_NONE nobody; 1..CO_MAX_HOOKS the
 * application hook node->hooks[slot - 1], the latest registered covering the entry; CO_SLOT_CORE + i
 * the core's service co_node_services[i] (src/od_internal.h). O(1) for the first
 * CO_HOOK_MAP_ENTRIES entries of the dictionary. */
#define CO_SLOT_NONE 0u
#define CO_SLOT_CORE (CO_MAX_HOOKS + 1u)
uint8_t co_node_hook_search(const co_node *node, uint16_t index);
static inline uint8_t co_node_hook_slot(const co_node *node, const co_od_entry *entry)
{
#if CO_HOOK_MAP_ENTRIES > 0
    /* The entry's position, if it is one of the node's dictionary (byte arithmetic: a ref into
     * another table is simply not found in the map). */
    uintptr_t at = ((uintptr_t)entry - (uintptr_t)node->od->entries) / sizeof *entry;
    if (at < CO_HOOK_MAP_ENTRIES && at < node->od->entry_count) {
        return node->hook_map[at];
    }
#endif
    return co_node_hook_search(node, entry->index);
}

/* The application hook of a slot, or NULL: nobody's slot, or a service of the core. */
static inline const co_od_hook *co_node_slot_hook(const co_node *node, uint32_t slot)
{
    return slot - 1u < CO_MAX_HOOKS ? &node->hooks[slot - 1u] : NULL;
}

/* The application hook of an entry (DOMAINs: the core has none), or NULL. */
const co_od_hook *co_node_entry_hook(const co_node *node, const co_od_entry *entry);

/* The page of an index (CO_OD_PAGES, include/canopen/node.h): pages follow the index order. */
static inline uint32_t co_od_page_of(uint32_t index)
{
    uint32_t high = index >> 12;
    if (high == 1u) {
        return 1u + ((index >> 8) & 0xFu); /* 1-16: 0x1000-0x1FFF by 0x100 */
    }
    return high == 0u ? 0u : high + 15u; /* 17-30: 0x2000-0xFFFF by 0x1000 */
}

/* co_od_locate in the node's dictionary, faster: a binary search of the entries of the index's
 * page only (node->od_page, filled at co_node_init), so a lookup costs O(log n) in the number of
 * objects of that page. */
co_abort co_node_locate(const co_node *node, uint32_t index, uint32_t subindex, co_od_ref *ref);
const co_od_entry *co_node_find_entry(const co_node *node, uint16_t index);

/* The co_time of the API time now (include/canopen/time_base.h): now itself in a 64-bit build;
 * with CO_CONFIG_TIME32 the µs since the node's epoch, after moving the epoch (and every time the
 * services keep) forward once now is CO_TIME32_REBASE_AT past it. Every API function that takes
 * a time converts it here. */
#if CO_CONFIG_TIME32
co_time co_node_time(co_node *node, uint64_t now);
#else
static inline co_time co_node_time(co_node *node, uint64_t now)
{
    (void)node;
    return now;
}
#endif

/* The times that can lie more than CO_TIME_SPAN_MAX ahead or back (the SYNC period and window,
 * life guarding) are co_time_wide: with CO_CONFIG_TIME32 absolute API times, which the epoch's
 * moves leave alone. co_time_wide_of is the wide time of the co_time t; co_time_from_wide the
 * co_time the node schedules a wide time by: CO_NEVER for CO_WIDE_NEVER, 0 for a time before the
 * epoch (past), CO_NEVER - 1 for one beyond co_time's range (not never: the node is called then,
 * moves its epoch and looks again). */
#if CO_CONFIG_TIME32
co_time co_time_from_wide(const co_node *node, co_time_wide t);
static inline co_time_wide co_time_wide_of(const co_node *node, co_time t)
{
    return node->epoch + t;
}
#else
static inline co_time co_time_from_wide(const co_node *node, co_time_wide t)
{
    (void)node;
    return t;
}
static inline co_time_wide co_time_wide_of(const co_node *node, co_time t)
{
    (void)node;
    return t;
}
#endif

/* PRE-OPERATIONAL or OPERATIONAL, where SDO, SYNC, EMCY and the PDOs' frames flow: of the four
 * states only these two have bit 0 set. */
typedef char co_nmt_bit0_check[(CO_NMT_OPERATIONAL & CO_NMT_PRE_OPERATIONAL & 1) != 0 &&
                               ((CO_NMT_INITIALISING | CO_NMT_STOPPED) & 1) == 0 ? 1 : -1];
static inline bool co_nmt_communicating(co_nmt_state state)
{
    return ((uint32_t)state & 1u) != 0u;
}

/* Changes the NMT state and tells the application. */
void co_nmt_enter(co_node *node, co_nmt_state state);

/* node->next is the earliest of the deadlines the services keep (heartbeat.next, errctl.next,
 * sdo.deadline while a transfer runs, sync.next, pdo.next, the EMCY inhibit while frames wait),
 * exactly what a full co_node_process pass would return, or earlier. Whoever changes one of them
 * outside the pass says so with one of these, so the pass can be skipped while nothing is due. */

/* A deadline was set at `at` or earlier than before. */
static inline void co_node_wake(co_node *node, co_time at)
{
    if (at < node->next) {
        node->next = at;
    }
}

/* A deadline moved from old to at: if old may have been the earliest, the next pass recomputes. */
static inline void co_node_reschedule(co_node *node, co_time old, co_time at)
{
    if (at < node->next) {
        node->next = at;
    } else if (at != old && old <= node->next) {
        node->next = 0u;
    }
}

/* Something the next pass must look at changed (a state, a cancelled timer, ...). */
static inline void co_node_recheck(co_node *node)
{
    node->next = 0u;
}

/* --- shared by the services --------------------------------------------------------------- */

/* A core write handler stores the value it accepted itself (the same bytes co_od_write_checked
 * stores after it), so that its service loads its state from the dictionary in one place, at
 * reset communication and after a write alike (src/errctl.c). The services' parameters are
 * numeric: check_value has made the written length the sub-entry's size. */
void co_svc_store(co_node *node, const uint8_t *data, co_od_ref ref);

/* co_node_od_value(node, index, 0, 0): a service's parameter at sub 0, 0 without it
 * (src/errctl.c). */
uint32_t co_svc_od_value(const co_node *node, uint16_t index);

/* Tells the application a communication event (events.comm), if it listens (src/errctl.c). */
void co_svc_report(co_node *node, co_comm_event event, uint32_t detail);

/* Sends a data frame of dlc (0 or 1) bytes, byte the first, the others 0: a heartbeat, a
 * guarding answer, a SYNC (src/heartbeat.c). */
void co_svc_send(co_node *node, uint16_t id, uint8_t dlc, uint8_t byte);

/* Sends one byte on the node's error control CAN-ID 0x700 + node-ID: a heartbeat, a guarding
 * answer, the boot-up message (src/heartbeat.c). */
void co_svc_send_state(co_node *node, uint8_t byte);

#endif
