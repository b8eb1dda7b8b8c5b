/* Dictionary internals: what the core's services and the node (src/node.c) use of the dictionary
 * beyond the public co_od_* API - locating in the node's pages, the value block, the write path
 * past its checks, hook slots - and how the services hear the dictionary: the list of bindings
 * the node is built from (src/node.c). The dictionary (src/od.c) walks that list; it names no
 * service. */
#ifndef CANOPEN_OD_INTERNAL_H
#define CANOPEN_OD_INTERNAL_H

#include "canopen/node.h"
#include "dispatch.h"

/* What a service of the core needs to hear about its objects index_first..index_last (CiA 301
 * communication objects it implements): every write by SDO or RPDO (not the application's own,
 * CO_ORIGIN_APP), after the dictionary has checked access, length and limits and before it stores
 * the value. The service checks what the dictionary cannot (CiA 301 rules between values, its
 * state) and applies the value; an abort code other than CO_ABORT_NONE refuses the write and
 * nothing is stored. The handler has the signature of co_od_hook's write (its ctx is NULL), so an
 * application hook registered over the same objects can call it to chain (co_node_add_hook): an
 * application hook wins over the service for the objects it covers. The ranges in
 * co_node_services do not overlap. */
typedef struct co_od_service {
    uint16_t index_first;
    uint16_t index_last;
    co_abort (*written)(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data, uint32_t len,
                        co_od_origin origin);
} co_od_service;

/* Called before every SDO read of an object of co_node_services (an application hook over it has
 * its own refresh): brings the stored value up to date, or refuses the read with an abort code.
 * Of the core's objects only 0x1010/0x1011 need it (co_store_refresh: a read shows what the
 * storage offers, whatever was last written), so it is one function, not a column of the table. */
co_abort co_node_service_refresh(co_node *node, co_od_ref ref);

/* The other binding: a value the dictionary stored changed, at offset of the value block. The
 * services that send values by themselves hear it - the event-driven TPDOs (src/pdo.c), whose
 * watch set tells at once that no TPDO maps most values. */
static inline void co_node_value_stored(co_node *node, uint32_t offset)
{
    if (co_pdo_may_watch(node, offset)) {
        co_pdo_value_changed(node, offset);
    }
}

/* The services a node is built from, in index order (src/node.c): the node composes them, each
 * service exports its handlers (include/canopen/<service>.h). */
#define CO_NODE_SERVICES 10u
extern const co_od_service co_node_services[CO_NODE_SERVICES];


/* A little-endian unsigned value of len bytes (1..4; of a longer one, the first 4). */
uint32_t co_le_value(const uint8_t *data, uint32_t len);

/* The value of numeric object index:subindex of up to 4 bytes (sub-entries of other sizes and
 * DOMAINs do not count), or dflt when the dictionary has none. */
uint32_t co_node_od_value(const co_node *node, uint32_t index, uint32_t subindex, uint32_t dflt);

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

/* The page of an index (CO_OD_PAGES, include/canopen/od.h): pages follow the index order. */
static inline uint32_t co_od_page_of(uint32_t index)
{
    uint32_t high = index >> 12;
    if (high == 1u) {
        return 1u + ((index >> 8) & 0xFu); /* 1-16: 0x1000-0x1FFF by 0x100 */
    }
    return high == 0u ? 0u : high + 15u; /* 17-30: 0x2000-0xFFFF by 0x1000 */
}

/* co_od_locate in the node's dictionary, faster: a binary search of the entries of the index's
 * page only (co_od.pages), so a lookup costs O(log n) in the number of
 * objects of that page. */
co_abort co_node_locate(const co_node *node, uint32_t index, uint32_t subindex, co_od_ref *ref);
const co_od_entry *co_node_find_entry(const co_node *node, uint16_t index);

#endif
