/* Object dictionary access: lookup, typed and checked reads and writes. */
#include "canopen/od.h"

#include <string.h>

#include "canopen/node.h"
#include "canopen/store.h"
#include "node_internal.h"

/* Binary search of entries[lo, hi) for index. */
static CO_SIZE_NOINLINE const co_od_entry *search(const co_od_entry *entries, uint32_t lo, uint32_t hi,
                                 uint16_t index)
{
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2u;
        uint16_t at = entries[mid].index;
        if (at == index) {
            return &entries[mid];
        }
        if (at < index) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return NULL;
}

const co_od_entry *co_od_find_entry(const co_od *od, uint16_t index)
{
    return search(od->entries, 0, od->entry_count, index);
}

#if defined(__GNUC__)
__attribute__((always_inline)) /* into co_od_find_sub; into co_node_locate except under -Os */
#endif
static inline const co_od_sub *find_sub(const co_od_entry *entry, uint8_t subindex)
{
    const co_od_sub *subs = co_od_entry_subs(entry);
#if defined(__OPTIMIZE_SIZE__)
    /* the shorter code of a scan, from where a dense object has it down (sub-indices are sorted
     * and distinct, so the one at position i is i or more) */
    uint32_t end = (uint32_t)subindex + 1u; /* min(subindex + 1, sub_count) */
    if (end > co_od_entry_sub_count(entry)) {
        end = co_od_entry_sub_count(entry);
    }
    const co_od_sub *at = subs + end;
    while (at != subs) {
        at--;
        if (at->subindex == subindex) {
            return at;
        }
    }
#else
    /* Most objects have dense sub-indices: try the direct slot before searching. */
    if (subindex < co_od_entry_sub_count(entry) && subs[subindex].subindex == subindex) {
        return &subs[subindex];
    }
    uint32_t lo = 0, hi = co_od_entry_sub_count(entry);
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2u;
        uint8_t at = subs[mid].subindex;
        if (at == subindex) {
            return &subs[mid];
        }
        if (at < subindex) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
#endif
    return NULL;
}

const co_od_sub *co_od_find_sub(const co_od_entry *entry, uint8_t subindex)
{
    return find_sub(entry, subindex);
}
#if defined(__OPTIMIZE_SIZE__)
#define find_sub co_od_find_sub /* one copy, not a wrapper beside it */
#endif

/* The node's entry of index, or NULL. */
static inline const co_od_entry *find_entry(const co_node *node, uint16_t index)
{
#if defined(__OPTIMIZE_SIZE__)
    /* the shortest code: a scan of the sorted table up to index (a microcontroller's dictionary
     * has a few dozen objects) */
    const co_od_entry *e = node->od->entries, *end = e + node->od->entry_count;
    for (; e < end && e->index <= index; e++) {
        if (e->index == index) {
            return e;
        }
    }
    return NULL;
#else
    /* Only the entries of the index's page are searched. */
    uint32_t page = co_od_page_of(index);
    return search(node->od->entries, node->od_page[page], node->od_page[page + 1u], index);
#endif
}

const co_od_entry *co_node_find_entry(const co_node *node, uint16_t index)
{
    return find_entry(node, index);
}

/* The end of both lookups: the sub-entry of entry (NULL: no object), the reference and its abort. */
#if defined(__GNUC__)
__attribute__((always_inline)) /* into co_node_locate and co_od_locate */
#endif
static inline co_abort locate_sub(const co_od_entry *entry, uint8_t subindex, co_od_ref *ref)
{
    ref->entry = entry;
    if (entry == NULL) {
        ref->sub = NULL;
        return CO_ABORT_NO_OBJECT;
    }
    ref->sub = find_sub(entry, subindex);
    return ref->sub == NULL ? CO_ABORT_NO_SUBINDEX : CO_ABORT_NONE;
}

co_abort co_node_locate(const co_node *node, uint32_t index, uint32_t subindex, co_od_ref *ref)
{
    return locate_sub(find_entry(node, (uint16_t)index), (uint8_t)subindex, ref);
}

co_abort co_od_locate(const co_od *od, uint16_t index, uint8_t subindex, co_od_ref *ref)
{
    return locate_sub(co_od_find_entry(od, index), subindex, ref);
}

uint32_t co_le_value(const uint8_t *data, uint32_t len)
{
    uint32_t v = 0;
    for (uint32_t i = len < 4u ? len : 4u; i > 0u; i--) {
        v = (v << 8) | data[i - 1u];
    }
    return v;
}

uint32_t co_node_od_value(const co_node *node, uint32_t index, uint32_t subindex, uint32_t dflt)
{
    co_od_ref ref;
    if (co_node_locate(node, index, subindex, &ref) != CO_ABORT_NONE ||
        co_od_sub_size(ref.sub) - 1u >= 4u) { /* 1..4 bytes (a DOMAIN's size is 0) */
        return dflt;
    }
    return co_le_value(node->values + co_od_value_offset(ref.entry, ref.sub),
                       co_od_sub_size(ref.sub));
}

bool co_can_id_restricted(uint16_t id)
{
    /* all but the IDs left free: 0x080-0x100, 0x181-0x580, 0x600, 0x680-0x6DF and 0x700 */
    return !((uint32_t)id - 0x080u <= 0x080u || (uint32_t)id - 0x181u <= 0x3FFu || id == 0x600u ||
             (uint32_t)id - 0x680u < 0x060u || id == 0x700u);
}

void co_od_default_copy(const co_od *od, uint8_t *dst, uint32_t offset, uint32_t len)
{
    if (od->defaults != NULL) {
        memcpy(dst, od->defaults + offset, len);
        return;
    }
    memset(dst, 0, len);
    const uint8_t *p = od->packed_defaults;
    /* per piece: (zeros before it << 3 | its length), then its bytes; 0 ends (od.h); at counts
     * from offset (negative before it: a value block is below 64 KiB) */
    for (int32_t at = -(int32_t)offset, c; p != NULL && (c = *p++) != 0 && at < (int32_t)len;) {
        at += c >> 3;
        for (c &= 7; c > 0; c--, at++, p++) {
            if ((uint32_t)at < len) {
                dst[at] = *p;
            }
        }
    }
}

uint32_t co_type_size(uint8_t type)
{
    switch (type) {
    case CO_BOOLEAN: case CO_INTEGER8: case CO_UNSIGNED8: return 1;
    case CO_INTEGER16: case CO_UNSIGNED16: return 2;
    case CO_INTEGER24: case CO_UNSIGNED24: return 3;
    case CO_INTEGER32: case CO_UNSIGNED32: case CO_REAL32: return 4;
    case CO_INTEGER40: case CO_UNSIGNED40: return 5;
    case CO_INTEGER48: case CO_UNSIGNED48: case CO_TIME_OF_DAY: case CO_TIME_DIFFERENCE: return 6;
    case CO_INTEGER56: case CO_UNSIGNED56: return 7;
    case CO_INTEGER64: case CO_UNSIGNED64: case CO_REAL64: return 8;
    default: return 0;
    }
}

#if CO_CONFIG_OD_COMPACT
uint32_t co_od_sub_size(const co_od_sub *sub)
{
    uint32_t size = co_type_size(sub->type);
    return size != 0u ? size : sub->aux; /* a string's capacity; 0 for DOMAIN */
}
#endif

/* The signed integer types, as bits of a mask indexed by the type. */
#define SIGNED_TYPES                                                                              \
    (1u << CO_INTEGER8 | 1u << CO_INTEGER16 | 1u << CO_INTEGER24 | 1u << CO_INTEGER32 |          \
     1u << CO_INTEGER40 | 1u << CO_INTEGER48 | 1u << CO_INTEGER56 | 1u << CO_INTEGER64)

#if defined(__GNUC__)
__attribute__((always_inline)) /* into the limit check, its one caller in the core */
#endif
static inline bool type_is_signed(uint32_t type)
{
    return type < 32u && ((SIGNED_TYPES >> type) & 1u) != 0u;
}

bool co_type_is_signed(uint8_t type)
{
    return type_is_signed(type);
}

uint8_t *co_od_value_ptr(const co_node *node, co_od_ref ref)
{
    if (ref.sub->type == CO_DOMAIN) {
        return NULL;
    }
    return node->values + co_od_value_offset(ref.entry, ref.sub);
}

/* Bytes a read of a sub-entry with its value at value returns: a VISIBLE_STRING's length up to its
 * first NUL, else the sub-entry's size (0 for a DOMAIN). */
#if defined(__GNUC__)
__attribute__((always_inline)) /* into co_od_read_ref: co_od_value_length is for the application */
#endif
static inline uint32_t value_length(const co_od_sub *sub, const uint8_t *value)
{
    uint32_t size = co_od_sub_size(sub);
    if (sub->type == CO_VISIBLE_STRING) {
        uint32_t n = 0;
        while (n < size && value[n] != 0u) {
            n++;
        }
        return n;
    }
    return size;
}

uint32_t co_od_value_length(const co_node *node, co_od_ref ref)
{
    if (ref.sub->type == CO_DOMAIN) {
        return 0;
    }
    return value_length(ref.sub, node->values + co_od_value_offset(ref.entry, ref.sub));
}

#if CO_CONFIG_OD_WIDE_LIMITS
/* Reads size little-endian bytes as a 64-bit pattern, sign-extended for signed types. */
static uint64_t load_pattern(const uint8_t *data, uint32_t size, bool is_signed)
{
    uint64_t v = 0;
    for (uint32_t i = size; i > 0u; i--) {
        v = (v << 8) | data[i - 1u];
    }
    if (is_signed && size < 8u && (data[size - 1u] & 0x80u) != 0u) {
        v |= ~(uint64_t)0 << (size * 8u);
    }
    return v;
}

/* The IEEE 754 double pattern of a REAL32 pattern (exact: every float is a double), by integer
 * arithmetic only, so no soft-float library is linked on a microcontroller. */
static uint64_t real32_as_real64(uint32_t f)
{
    uint64_t sign = (uint64_t)(f >> 31) << 63;
    uint32_t exp = (f >> 23) & 0xFFu;
    uint64_t man = f & 0x7FFFFFu;
    if (exp == 0xFFu) { /* infinity, NaN */
        return sign | 0x7FF0000000000000u | (man << 29);
    }
    if (exp == 0u) {
        if (man == 0u) {
            return sign;
        }
        uint32_t e = 1023u - 126u; /* subnormal: normalise */
        while ((man & 0x800000u) == 0u) {
            man <<= 1;
            e--;
        }
        return sign | ((uint64_t)e << 52) | ((man & 0x7FFFFFu) << 29);
    }
    return sign | ((uint64_t)(exp + 1023u - 127u) << 52) | (man << 29);
}

#define SIGN64 0x8000000000000000u

/* A double pattern as an unsigned integer that orders as the value does (the negative values
 * reversed below the positive ones; +0 and -0 equal). False for NaN, which has no order. */
static bool real_key(uint64_t bits, uint64_t *key)
{
    uint64_t magnitude = bits & ~SIGN64;
    if (magnitude > 0x7FF0000000000000u) {
        return false;
    }
    *key = (bits & SIGN64) != 0u ? SIGN64 - magnitude : SIGN64 + magnitude;
    return true;
}

/* Compares a new value against the sub-entry's limits, all three turned into unsigned integers
 * that order as the values do: one comparison for every type. */
static co_abort check_limits(const co_od *od, const co_od_sub *sub, const uint8_t *data,
                             uint32_t len)
{
    (void)len; /* the size is the sub-entry's here: a hand-made table may limit a DOMAIN */
    uint32_t size = co_od_sub_size(sub);
    const co_od_limit *lim = &od->limits[co_od_sub_limit(sub)];
    uint64_t v, low = lim->low, high = lim->high;
    if (sub->type == CO_REAL32 || sub->type == CO_REAL64) {
        uint64_t bits = sub->type == CO_REAL32 ? real32_as_real64(co_get_le32(data))
                                                : load_pattern(data, 8, false);
        if (!real_key(bits, &v)) { /* NaN is outside every range */
            return CO_ABORT_VALUE_RANGE;
        }
        /* a NaN limit bounds nothing (as a comparison with it is false) */
        if (!real_key(lim->high, &high)) {
            high = UINT64_MAX;
        }
        if (!real_key(lim->low, &low)) {
            low = 0u;
        }
    } else {
        bool is_signed = type_is_signed(sub->type);
        v = load_pattern(data, size, is_signed);
        if (is_signed) { /* two's complement order -> unsigned order */
            v ^= SIGN64;
            low ^= SIGN64;
            high ^= SIGN64;
        }
    }
    if (v > high) {
        return CO_ABORT_VALUE_TOO_HIGH;
    }
    if (v < low) {
        return CO_ABORT_VALUE_TOO_LOW;
    }
    return CO_ABORT_NONE;
}
#else
/* Limits in 32-bit arithmetic: every limited object is an integer of up to 4 bytes (co_node_init
 * refused the dictionary otherwise), whose limits are the low 32 bits of the table's patterns.
 * Its length check has passed, so len is its size (no second co_od_sub_size call). */
static co_abort check_limits(const co_od *od, const co_od_sub *sub, const uint8_t *data,
                             uint32_t len)
{
    uint32_t size = len;
    uint32_t v = co_le_value(data, size);
    /* (its limits read through one pointer: gcc would address the low one by a second index) */
    const co_od_limit *lim = &od->limits[co_od_sub_limit(sub)];
    lim = CO_SIZE_BASE(lim);
    uint32_t low = (uint32_t)lim->low, high = (uint32_t)lim->high;
    if (type_is_signed(sub->type)) { /* sign-extend, then two's complement -> unsigned order */
        uint32_t shift = 32u - size * 8u;
        v = (uint32_t)((int32_t)(v << shift) >> shift) ^ 0x80000000u;
        low ^= 0x80000000u;
        high ^= 0x80000000u;
    }
    /* CO_ABORT_VALUE_TOO_HIGH and _TOO_LOW follow CO_ABORT_VALUE_RANGE: one constant for both */
    uint32_t outside = v > high ? 1u : v < low ? 2u : 0u;
    return outside != 0u ? CO_ABORT_VALUE_RANGE + outside : CO_ABORT_NONE;
}
typedef char abort_codes_follow[CO_ABORT_VALUE_RANGE + 1u == CO_ABORT_VALUE_TOO_HIGH &&
                                CO_ABORT_VALUE_RANGE + 2u == CO_ABORT_VALUE_TOO_LOW ? 1 : -1];

#endif

/* A length against a value's type (not a DOMAIN's): more than its size is too long, less too short
 * except for a string. Always inlined: into co_od_check_length, and into check_value except under
 * -Os, where check_value calls co_od_check_length (one copy, which the SDO initiate also calls). */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline co_abort check_length(const co_od_sub *sub, uint32_t len)
{
    uint32_t type = sub->type;
    uint32_t size = co_od_sub_size(sub);
    uint32_t shorter = len < size ? 1u : 0u;
    if (len == size || (shorter != 0u && (type == CO_VISIBLE_STRING || type == CO_UNICODE_STRING))) {
        return CO_ABORT_NONE;
    }
    /* CO_ABORT_TYPE_TOO_SHORT follows CO_ABORT_TYPE_TOO_LONG: one constant for both */
    return CO_ABORT_TYPE_TOO_LONG + shorter;
}
typedef char length_aborts_follow[CO_ABORT_TYPE_TOO_LONG + 1u == CO_ABORT_TYPE_TOO_SHORT ? 1 : -1];

co_abort co_od_check_length(const co_od_sub *sub, uint32_t len)
{
    return check_length(sub, len);
}
#if defined(__OPTIMIZE_SIZE__)
#define check_length co_od_check_length
#endif

/* Length against the type (a string may be shorter, a DOMAIN any length), the BOOLEAN range,
 * then the limits. */
#if defined(__GNUC__)
__attribute__((always_inline)) /* into co_od_check_sub; into co_od_check_value and co_od_write_ref
                                 * except under -Os */
#endif
static inline co_abort check_value(const co_od *od, const co_od_sub *sub, const uint8_t *data,
                                   uint32_t len)
{
    uint32_t type = sub->type;
    if (type != CO_DOMAIN) {
        co_abort rc = check_length(sub, len);
        if (rc != CO_ABORT_NONE) {
            return rc;
        }
        if (type == CO_BOOLEAN && data[0] > 1u) { /* (len is 1 here) */
            return CO_ABORT_VALUE_RANGE;
        }
    }
    if ((sub->flags & CO_OD_LIMITS) != 0u) {
        return check_limits(od, sub, data, len);
    }
    return CO_ABORT_NONE;
}

co_abort co_od_check_sub(const co_od *od, const co_od_sub *sub, const uint8_t *data,
                         uint32_t len)
{
    return check_value(od, sub, data, len);
}

co_abort co_od_check_value(const co_od *od, co_od_ref ref, const uint8_t *data, uint32_t len)
{
#if defined(__OPTIMIZE_SIZE__)
    return co_od_check_sub(od, ref.sub, data, len); /* one copy */
#else
    return check_value(od, ref.sub, data, len);
#endif
}

/* --- the core's own objects and the hooks ------------------------------------------------------------------ */

typedef co_abort (*write_handler)(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                                  uint32_t len, co_od_origin origin);

/* The services of the core that check and apply writes to their objects, by their slot
 * (CO_HOOK_CORE + the number here): a fixed set, no table in RAM. */
enum {
    CORE_PDO, CORE_EMCY_HISTORY, CORE_SYNC, CORE_GUARDING, CORE_STORE, CORE_EMCY, CORE_CONSUMER,
    CORE_HEARTBEAT, CORE_BEHAVIOUR, CORE_SERVICES
};
typedef char core_slots_fit[CO_HOOK_CORE + CORE_SERVICES - 1u <= 0xFFu ? 1 : -1];
/* No service: the one number past them, whose slot wraps to 0 (core_slot needs no test for it). */
#define CORE_NONE CORE_SERVICES
typedef char core_none_wraps[(uint8_t)(CO_HOOK_CORE + CORE_NONE) == 0u ? 1 : -1];
static const write_handler core_written[CORE_SERVICES] = {
    co_pdo_param_written, co_emcy_param_written, co_sync_param_written,
    co_errctl_guarding_written, co_store_written, co_emcy_param_written,
    co_errctl_consumer_written, co_heartbeat_time_written, co_errctl_consumer_written
};

/* The service of the core that handles 0x1000..0x1029 (CORE_NONE: none; the PDOs' objects
 * apart), as a constant expression: the table below holds it for two indices a byte. */
#define CORE_SERVICE_OF(i)                                                                        \
    ((i) == 0x1003u ? CORE_EMCY_HISTORY                                                           \
     : ((i) >= 0x1005u && (i) <= 0x1007u) || (i) == 0x1019u ? CORE_SYNC                          \
     : (i) == 0x100Cu || (i) == 0x100Du ? CORE_GUARDING                                           \
     : (i) == 0x1010u || (i) == 0x1011u ? CORE_STORE                                              \
     : (i) == 0x1014u || (i) == 0x1015u ? CORE_EMCY                                               \
     : (i) == 0x1016u ? CORE_CONSUMER                                                             \
     : (i) == 0x1017u ? CORE_HEARTBEAT                                                            \
     : (i) == 0x1029u ? CORE_BEHAVIOUR                                                            \
     : CORE_NONE)
#define CORE_PAIR(i) ((uint8_t)(CORE_SERVICE_OF(i) | CORE_SERVICE_OF((i) + 1u) << 4))
static const uint8_t core_services[21] = { /* from 0x1000: one subtraction fewer than 0x1003 */
    CORE_PAIR(0x1000u), CORE_PAIR(0x1002u), CORE_PAIR(0x1004u), CORE_PAIR(0x1006u),
    CORE_PAIR(0x1008u), CORE_PAIR(0x100Au), CORE_PAIR(0x100Cu), CORE_PAIR(0x100Eu),
    CORE_PAIR(0x1010u), CORE_PAIR(0x1012u), CORE_PAIR(0x1014u), CORE_PAIR(0x1016u),
    CORE_PAIR(0x1018u), CORE_PAIR(0x101Au), CORE_PAIR(0x101Cu), CORE_PAIR(0x101Eu),
    CORE_PAIR(0x1020u), CORE_PAIR(0x1022u), CORE_PAIR(0x1024u), CORE_PAIR(0x1026u),
    CORE_PAIR(0x1028u)
};

/* The slot of the service of the core that handles index, or 0. */
static uint8_t core_slot(uint16_t index)
{
    if (index >= 0x1400u && index <= 0x1BFFu) { /* PDO communication and mapping */
        return CO_HOOK_CORE + CORE_PDO;
    }
    uint32_t at = (uint32_t)index - 0x1000u;
    if (at > 0x1029u - 0x1000u) {
        return 0u;
    }
    uint32_t service = (core_services[at >> 1] >> ((at & 1u) * 4u)) & 0xFu;
    return (uint8_t)(CO_HOOK_CORE + service); /* 0 for CORE_NONE */
}

uint8_t co_node_hook_search(const co_node *node, uint16_t index)
{
    uint32_t i = node->hook_count;
    for (const co_od_hook *h = &node->hooks[i]; i != 0u; i--) {
        h--;
        if (index >= h->index_first && index <= h->index_last) {
            return (uint8_t)i;
        }
    }
    return core_slot(index);
}

/* The write handler of slot (co_node_hook_slot, not 0): one call for both kinds, the core's
 * handlers sharing the co_od_hook write signature. Inlined into its one caller under -Os; out of
 * line otherwise, so an RPDO's write of a value without a handler saves fewer registers. */
#if defined(__GNUC__) && !defined(__OPTIMIZE_SIZE__)
#define CO_HOOK_WRITE_INLINE __attribute__((noinline))
#else
#define CO_HOOK_WRITE_INLINE inline
#endif
static CO_HOOK_WRITE_INLINE co_abort hook_write(co_node *node, uint8_t slot, co_od_ref ref,
                                                const uint8_t *data, uint32_t len,
                                                co_od_origin origin)
{
    write_handler written;
    void *ctx = NULL;
    if (slot >= CO_HOOK_CORE) {
        written = core_written[slot - CO_HOOK_CORE];
    } else {
        const co_od_hook *hook = &node->hooks[slot - 1u];
        written = hook->write;
        ctx = hook->ctx;
        if (written == NULL) {
            return CO_ABORT_NONE;
        }
    }
    return written(node, ctx, ref, data, len, origin);
}

/* The SDO refresh of a slot that is not 0 (co_node_hook_slot). */
static inline co_abort hook_refresh(co_node *node, uint8_t slot, co_od_ref ref)
{
    co_abort (*refresh)(co_node *node, void *ctx, co_od_ref ref) = NULL;
    void *ctx = NULL;
    if (slot >= CO_HOOK_CORE) {
        if (slot == CO_HOOK_CORE + CORE_STORE) { /* 0x1010, 0x1011 */
            refresh = co_store_refresh;
        }
    } else {
        const co_od_hook *hook = &node->hooks[slot - 1u];
        refresh = hook->refresh;
        ctx = hook->ctx;
    }
    return refresh != NULL ? refresh(node, ctx, ref) : CO_ABORT_NONE;
}

/* memcpy of a value: the common sizes as single moves instead of a call (when optimising for
 * size, the call: one copy of that code). */
static inline void copy_value(uint8_t *dst, const uint8_t *src, uint32_t n)
{
#if defined(__OPTIMIZE_SIZE__)
    memcpy(dst, src, n);
#else
    switch (n) {
    case 1:
        dst[0] = src[0];
        return;
    case 2:
        memcpy(dst, src, 2);
        return;
    case 4:
        memcpy(dst, src, 4);
        return;
    default:
        memcpy(dst, src, n);
        return;
    }
#endif
}

/* The read of co_od_read_ref, and the object's size in *total: the value's length, a DOMAIN's
 * total from its hook's first read (0 unless the hook sets it); not set when the core refuses the
 * read. Always inlined: into co_od_read_sized, and into co_od_read_ref except under -Os, where
 * co_od_read_ref calls co_od_read_sized (one copy). */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline co_abort read_sized(co_node *node, const co_od_ref *at, uint8_t *buf, uint32_t cap,
                                  uint32_t *len, uint32_t *total, co_od_origin origin)
{
    const co_od_sub *sub = at->sub;
    *len = 0;
    if (origin == CO_ORIGIN_SDO && (sub->flags & CO_OD_READ) == 0u) {
        return CO_ABORT_WRITE_ONLY;
    }
    /* one lookup for both a DOMAIN's hook and the refresh (gcc tested DOMAIN twice otherwise) */
    uint8_t slot = co_node_hook_slot(node, at->entry);
    if (sub->type == CO_DOMAIN) {
        const co_od_hook *hook = co_node_slot_hook(node, slot);
        if (hook == NULL || hook->domain_read == NULL) {
            return CO_ABORT_NO_DATA;
        }
        *total = 0;
        return hook->domain_read(node, hook->ctx, *at, 0, buf, cap, len, total);
    }
    /* refresh hooks serve the bus, not the device itself */
    if (origin == CO_ORIGIN_SDO && slot != 0u) {
        co_abort rc = hook_refresh(node, slot, *at);
        if (rc != CO_ABORT_NONE) {
            return rc;
        }
    }
    const uint8_t *value = node->values + co_od_value_offset(at->entry, sub);
    uint32_t n = value_length(sub, value);
    if (n > cap) {
        return CO_ABORT_OUT_OF_MEMORY;
    }
    copy_value(buf, value, n);
    *len = n;
    *total = n;
    return CO_ABORT_NONE;
}

co_abort co_od_read_sized(co_node *node, const co_od_ref *ref, uint8_t *buf, uint32_t cap,
                          uint32_t *len, uint32_t *total, co_od_origin origin)
{
    return read_sized(node, ref, buf, cap, len, total, origin);
}

co_abort co_od_read_ref(co_node *node, co_od_ref ref, uint8_t *buf, uint32_t cap, uint32_t *len,
                        co_od_origin origin)
{
    uint32_t total;
#if defined(__OPTIMIZE_SIZE__)
    return co_od_read_sized(node, &ref, buf, cap, len, &total, origin); /* one copy */
#else
    return read_sized(node, &ref, buf, cap, len, &total, origin);
#endif
}

co_abort co_od_read(co_node *node, uint16_t index, uint8_t subindex, uint8_t *buf, uint32_t cap,
                    uint32_t *len, co_od_origin origin)
{
    co_od_ref ref;
    co_abort rc = co_node_locate(node, index, subindex, &ref);
    if (rc != CO_ABORT_NONE) {
        *len = 0;
        return rc;
    }
    return co_od_read_ref(node, ref, buf, cap, len, origin);
}

/* Stores a checked value and tells the PDOs. */
static inline void store(co_node *node, co_od_ref ref, const uint8_t *data, uint32_t len)
{
    const co_od_sub *sub = ref.sub;
    uint32_t at = co_od_value_offset(ref.entry, sub);
    uint8_t *value = node->values + at;
    copy_value(value, data, len);
    uint32_t size = co_od_sub_size(sub);
    if (len < size) { /* a shorter string: clear the rest so its length reads back right */
        memset(value + len, 0, size - len);
    }
    /* a TPDO mapping it goes out by itself (the watch bits tell at once most values are not) */
    if ((node->pdo.watch & co_pdo_watch_bit(at)) != 0u) {
        co_pdo_value_changed(node, at);
    }
}

/* The end of a write, co_od_write_checked. Always inlined: into co_od_write_checked, and into
 * co_od_write_ref except under -Os, where co_od_write_ref calls co_od_write_checked (one copy;
 * gcc would otherwise keep a copy of its own behind a wrapper). */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline co_abort write_checked(co_node *node, const co_od_ref *at, uint8_t slot,
                                     const uint8_t *data, uint32_t len, co_od_origin origin)
{
    co_od_ref ref = *at;
    if (slot != 0u) { /* 0 for CO_ORIGIN_APP (the contract) */
        co_abort rc = hook_write(node, slot, ref, data, len, origin);
        if (rc != CO_ABORT_NONE) {
            return rc;
        }
    }
    store(node, ref, data, len);
    return CO_ABORT_NONE;
}

co_abort co_od_write_checked(co_node *node, const co_od_ref *ref, uint8_t slot,
                             const uint8_t *data, uint32_t len, co_od_origin origin)
{
    return write_checked(node, ref, slot, data, len, origin);
}
#if defined(__OPTIMIZE_SIZE__)
#define write_checked co_od_write_checked
#endif

co_abort co_od_write_ref(co_node *node, co_od_ref ref, const uint8_t *data, uint32_t len,
                         co_od_origin origin)
{
    const co_od_sub *sub = ref.sub;
    if (origin == CO_ORIGIN_SDO) {
        if ((sub->flags & CO_OD_WRITE) == 0u) {
            return CO_ABORT_READ_ONLY;
        }
        if (CO_NODE_OPTION(node, CO_NODE_COMM_READ_ONLY_IN_OPERATIONAL) &&
            node->nmt_state == CO_NMT_OPERATIONAL && ref.entry->index >= 0x1000u &&
            ref.entry->index <= 0x1FFFu) {
            return CO_ABORT_DEVICE_STATE;
        }
    } else if (origin == CO_ORIGIN_RPDO && (sub->flags & CO_OD_RPDO) == 0u) {
        return CO_ABORT_NOT_MAPPABLE;
    }
#if defined(__OPTIMIZE_SIZE__)
    co_abort rc = co_od_check_sub(node->od, sub, data, len); /* one copy, not a wrapper */
#else
    co_abort rc = check_value(node->od, sub, data, len);
#endif
    if (rc != CO_ABORT_NONE) {
        return rc;
    }
    if (sub->type == CO_DOMAIN) {
        const co_od_hook *hook = co_node_entry_hook(node, ref.entry);
        if (hook == NULL || hook->domain_write == NULL) {
            return CO_ABORT_UNSUPPORTED_ACCESS;
        }
        return hook->domain_write(node, hook->ctx, ref, 0, data, len, len, true);
    }
    /* The device's own writes skip the hooks: no lookup for them. */
    uint8_t slot = origin != CO_ORIGIN_APP ? co_node_hook_slot(node, ref.entry) : 0u;
    return write_checked(node, &ref, slot, data, len, origin);
}

co_abort co_od_write(co_node *node, uint16_t index, uint8_t subindex, const uint8_t *data,
                     uint32_t len, co_od_origin origin)
{
    co_od_ref ref;
    co_abort rc = co_node_locate(node, index, subindex, &ref);
    if (rc != CO_ABORT_NONE) {
        return rc;
    }
    return co_od_write_ref(node, ref, data, len, origin);
}

/* The application's typed view: the value's bytes when it exists with the expected size. */
static const uint8_t *typed_value(const co_node *node, uint16_t index, uint8_t subindex,
                                  uint32_t size)
{
    co_od_ref ref;
    if (co_node_locate(node, index, subindex, &ref) != CO_ABORT_NONE ||
        co_od_sub_size(ref.sub) != size || ref.sub->type == CO_DOMAIN) {
        return NULL;
    }
    return node->values + co_od_value_offset(ref.entry, ref.sub);
}

uint32_t co_od_get_u32(const co_node *node, uint16_t index, uint8_t subindex)
{
    const uint8_t *p = typed_value(node, index, subindex, 4);
    return p != NULL ? co_get_le32(p) : 0u;
}

uint16_t co_od_get_u16(const co_node *node, uint16_t index, uint8_t subindex)
{
    const uint8_t *p = typed_value(node, index, subindex, 2);
    return p != NULL ? co_get_le16(p) : 0u;
}

uint8_t co_od_get_u8(const co_node *node, uint16_t index, uint8_t subindex)
{
    const uint8_t *p = typed_value(node, index, subindex, 1);
    return p != NULL ? p[0] : 0u;
}

int32_t co_od_get_i32(const co_node *node, uint16_t index, uint8_t subindex)
{
    return (int32_t)co_od_get_u32(node, index, subindex);
}

int16_t co_od_get_i16(const co_node *node, uint16_t index, uint8_t subindex)
{
    return (int16_t)co_od_get_u16(node, index, subindex);
}

co_abort co_od_set_u32(co_node *node, uint16_t index, uint8_t subindex, uint32_t value)
{
    uint8_t b[4];
    co_put_le32(b, value);
    return co_od_write(node, index, subindex, b, 4, CO_ORIGIN_APP);
}

co_abort co_od_set_u16(co_node *node, uint16_t index, uint8_t subindex, uint16_t value)
{
    uint8_t b[2];
    co_put_le16(b, value);
    return co_od_write(node, index, subindex, b, 2, CO_ORIGIN_APP);
}

co_abort co_od_set_u8(co_node *node, uint16_t index, uint8_t subindex, uint8_t value)
{
    return co_od_write(node, index, subindex, &value, 1, CO_ORIGIN_APP);
}

co_abort co_od_set_i32(co_node *node, uint16_t index, uint8_t subindex, int32_t value)
{
    return co_od_set_u32(node, index, subindex, (uint32_t)value);
}

co_abort co_od_set_i16(co_node *node, uint16_t index, uint8_t subindex, int16_t value)
{
    return co_od_set_u16(node, index, subindex, (uint16_t)value);
}
