/* Object dictionary access: lookup, typed and checked reads and writes. */
#include "canopen/od.h"

#include <string.h>

#include "canopen/node.h"
#include "dispatch.h"
#include "services.h"


/* Binary search of entries[lo, hi) for index. */
static const co_od_entry *search(const co_od_entry *entries, uint32_t lo, uint32_t hi,
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

const co_od_sub *co_od_find_sub(const co_od_entry *entry, uint8_t subindex)
{
    /* Sub-indices are sorted and distinct, so sub-index s is at position s or below: the scan
     * starts there and goes down. Most objects number their sub-entries densely from 0: the
     * first look finds it. */
    const co_od_sub *subs = co_od_entry_subs(entry);
    uint32_t end = co_od_entry_sub_count(entry);
    if (end > (uint32_t)subindex + 1u) {
        end = (uint32_t)subindex + 1u;
    }
    for (const co_od_sub *at = subs + end; at != subs;) {
        at--;
        if (at->subindex == subindex) {
            return at;
        }
    }
    return NULL;
}

/* co_node_find_entry (src/od_internal.h): only the entries of the index's page are searched. */
static inline const co_od_entry *find_entry(const co_node *node, uint16_t index)
{
    const co_od *od = node->od;
    if (od->pages == NULL) {
        return search(od->entries, 0u, od->entry_count, index);
    }
    uint32_t page = co_od_page_of(index);
    return search(od->entries, od->pages[page], od->pages[page + 1u], index);
}

const co_od_entry *co_node_find_entry(const co_node *node, uint16_t index)
{
    return find_entry(node, index);
}

/* The end of both lookups: the sub-entry of entry (NULL: no object), the reference and its abort. */
static co_abort locate_sub(const co_od_entry *entry, uint8_t subindex, co_od_ref *ref)
{
    ref->entry = entry;
    if (entry == NULL) {
        ref->sub = NULL;
        return CO_ABORT_NO_OBJECT;
    }
    ref->sub = co_od_find_sub(entry, subindex);
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
    /* by type number; 0 for strings, DOMAIN and numbers that are no type */
    static const uint8_t sizes[CO_UNSIGNED64 + 1] = {
        [CO_BOOLEAN] = 1, [CO_INTEGER8] = 1, [CO_UNSIGNED8] = 1,
        [CO_INTEGER16] = 2, [CO_UNSIGNED16] = 2,
        [CO_INTEGER24] = 3, [CO_UNSIGNED24] = 3,
        [CO_INTEGER32] = 4, [CO_UNSIGNED32] = 4, [CO_REAL32] = 4,
        [CO_INTEGER40] = 5, [CO_UNSIGNED40] = 5,
        [CO_INTEGER48] = 6, [CO_UNSIGNED48] = 6, [CO_TIME_OF_DAY] = 6, [CO_TIME_DIFFERENCE] = 6,
        [CO_INTEGER56] = 7, [CO_UNSIGNED56] = 7,
        [CO_INTEGER64] = 8, [CO_UNSIGNED64] = 8, [CO_REAL64] = 8,
    };
    return type < sizeof sizes ? sizes[type] : 0u;
}

#if CO_CONFIG_OD_COMPACT
uint32_t co_od_sub_size(const co_od_sub *sub)
{
    uint32_t size = co_type_size(sub->type);
    return size != 0u ? size : sub->aux; /* a string's capacity; 0 for DOMAIN */
}
#endif

uint8_t *co_od_value_ptr(const co_node *node, co_od_ref ref)
{
    if (ref.sub->type == CO_DOMAIN) {
        return NULL;
    }
    return node->values + co_od_value_offset(ref.entry, ref.sub);
}

/* Bytes a read of a sub-entry with its value at value returns: a VISIBLE_STRING's length up to its
 * first NUL, else the sub-entry's size (0 for a DOMAIN). */
static uint32_t value_length(const co_od_sub *sub, const uint8_t *value)
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
        bool is_signed = co_type_is_signed(sub->type);
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
 * Its length check has passed, so len is its size. */
static co_abort check_limits(const co_od *od, const co_od_sub *sub, const uint8_t *data,
                             uint32_t len)
{
    uint32_t size = len;
    uint32_t v = co_le_value(data, size);
    const co_od_limit *lim = &od->limits[co_od_sub_limit(sub)];
    uint32_t low = (uint32_t)lim->low, high = (uint32_t)lim->high;
    if (co_type_is_signed(sub->type)) { /* sign-extend, then two's complement -> unsigned order */
        uint32_t shift = 32u - size * 8u;
        v = (uint32_t)((int32_t)(v << shift) >> shift) ^ 0x80000000u;
        low ^= 0x80000000u;
        high ^= 0x80000000u;
    }
    if (v > high) {
        return CO_ABORT_VALUE_TOO_HIGH;
    }
    if (v < low) {
        return CO_ABORT_VALUE_TOO_LOW;
    }
    return CO_ABORT_NONE;
}

#endif

co_abort co_od_check_length(const co_od_sub *sub, uint32_t len)
{
    uint32_t size = co_od_sub_size(sub);
    if (len == size) {
        return CO_ABORT_NONE;
    }
    if (len > size) {
        return CO_ABORT_TYPE_TOO_LONG;
    }
    /* shorter than the type: only a string may be */
    return sub->type == CO_VISIBLE_STRING || sub->type == CO_UNICODE_STRING
               ? CO_ABORT_NONE
               : CO_ABORT_TYPE_TOO_SHORT;
}

/* co_od_check_sub (src/od_internal.h). */
static inline co_abort check_value(const co_od *od, const co_od_sub *sub, const uint8_t *data,
                                   uint32_t len)
{
    /* the length against the type (a DOMAIN has any length), the BOOLEAN range, the limits */
    if (sub->type != CO_DOMAIN) {
        co_abort rc = co_od_check_length(sub, len);
        if (rc != CO_ABORT_NONE) {
            return rc;
        }
        if (sub->type == CO_BOOLEAN && data[0] > 1u) { /* (len is 1 here) */
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
    return co_od_check_sub(od, ref.sub, data, len);
}

/* --- who handles an object: the application's hooks, the core's services -------------------- */

uint8_t co_node_hook_search(const co_node *node, uint16_t index)
{
    /* the latest application hook covering index wins */
    for (uint32_t i = node->hook_count; i != 0u; i--) {
        const co_od_hook *h = &node->hooks[i - 1u];
        if (index >= h->index_first && index <= h->index_last) {
            return (uint8_t)i;
        }
    }
    for (uint32_t i = 0; i < CO_NODE_SERVICES; i++) {
        const co_od_service *s = &co_node_services[i];
        if (index >= s->index_first && index <= s->index_last) {
            return (uint8_t)(CO_SLOT_CORE + i);
        }
    }
    return CO_SLOT_NONE;
}

/* The write handler of slot (not CO_SLOT_NONE): an application hook's, or a core service's. */
static co_abort hook_write(co_node *node, uint32_t slot, co_od_ref ref, const uint8_t *data,
                           uint32_t len, co_od_origin origin)
{
    const co_od_hook *hook = co_node_slot_hook(node, slot);
    if (hook == NULL) {
        return co_node_services[slot - CO_SLOT_CORE].written(node, NULL, ref, data, len, origin);
    }
    return hook->write != NULL ? hook->write(node, hook->ctx, ref, data, len, origin)
                               : CO_ABORT_NONE;
}

/* The SDO refresh of slot (not CO_SLOT_NONE): an application hook's, if it has one, or the core's
 * (co_node_service_refresh). */
static co_abort hook_refresh(co_node *node, uint32_t slot, co_od_ref ref)
{
    const co_od_hook *hook = co_node_slot_hook(node, slot);
    if (hook == NULL) {
        return co_node_service_refresh(node, ref);
    }
    return hook->refresh != NULL ? hook->refresh(node, hook->ctx, ref) : CO_ABORT_NONE;
}

/* memcpy of a value: the common sizes as single moves instead of a call. */
static inline void copy_value(uint8_t *dst, const uint8_t *src, uint32_t n)
{
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
}

co_abort co_od_read_sized(co_node *node, const co_od_ref *ref, uint8_t *buf, uint32_t cap,
                          uint32_t *len, uint32_t *total, co_od_origin origin)
{
    const co_od_sub *sub = ref->sub;
    *len = 0;
    if (origin == CO_ORIGIN_SDO && (sub->flags & CO_OD_READ) == 0u) {
        return CO_ABORT_WRITE_ONLY;
    }
    uint8_t slot = co_node_hook_slot(node, ref->entry);
    if (sub->type == CO_DOMAIN) { /* only an application hook has a DOMAIN's data */
        const co_od_hook *hook = co_node_slot_hook(node, slot);
        if (hook == NULL || hook->domain_read == NULL) {
            return CO_ABORT_NO_DATA;
        }
        *total = 0;
        return hook->domain_read(node, hook->ctx, *ref, 0, buf, cap, len, total);
    }
    /* refresh hooks serve the bus, not the device itself */
    if (origin == CO_ORIGIN_SDO && slot != CO_SLOT_NONE) {
        co_abort rc = hook_refresh(node, slot, *ref);
        if (rc != CO_ABORT_NONE) {
            return rc;
        }
    }
    const uint8_t *value = node->values + co_od_value_offset(ref->entry, sub);
    uint32_t n = value_length(sub, value);
    if (n > cap) {
        return CO_ABORT_OUT_OF_MEMORY;
    }
    copy_value(buf, value, n);
    *len = n;
    *total = n;
    return CO_ABORT_NONE;
}

co_abort co_od_read_ref(co_node *node, co_od_ref ref, uint8_t *buf, uint32_t cap, uint32_t *len,
                        co_od_origin origin)
{
    uint32_t total;
    return co_od_read_sized(node, &ref, buf, cap, len, &total, origin);
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

/* Stores a checked value and tells the services that hear value changes. */
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
    co_node_value_stored(node, at);
}

/* co_od_write_checked (src/od_internal.h), for the RPDOs' values they have checked themselves. */
static inline co_abort write_checked(co_node *node, const co_od_ref *ref, uint8_t slot,
                                     const uint8_t *data, uint32_t len, co_od_origin origin)
{
    if (slot != CO_SLOT_NONE) { /* CO_SLOT_NONE for CO_ORIGIN_APP (the contract) */
        co_abort rc = hook_write(node, slot, *ref, data, len, origin);
        if (rc != CO_ABORT_NONE) {
            return rc;
        }
    }
    store(node, *ref, data, len);
    return CO_ABORT_NONE;
}

co_abort co_od_write_checked(co_node *node, const co_od_ref *ref, uint8_t slot,
                             const uint8_t *data, uint32_t len, co_od_origin origin)
{
    return write_checked(node, ref, slot, data, len, origin);
}

co_abort co_od_write_ref(co_node *node, co_od_ref ref, const uint8_t *data, uint32_t len,
                         co_od_origin origin)
{
    const co_od_sub *sub = ref.sub;
    if (origin == CO_ORIGIN_SDO) {
        if ((sub->flags & CO_OD_WRITE) == 0u) {
            return CO_ABORT_READ_ONLY;
        }
        if (CO_NODE_OPTION(node, CO_NODE_COMM_READ_ONLY_IN_OPERATIONAL) &&
            ref.entry->index >= 0x1000u && ref.entry->index <= 0x1FFFu &&
            node->nmt_state == CO_NMT_OPERATIONAL) {
            return CO_ABORT_DEVICE_STATE;
        }
    } else if (origin == CO_ORIGIN_RPDO && (sub->flags & CO_OD_RPDO) == 0u) {
        return CO_ABORT_NOT_MAPPABLE;
    }
    co_abort rc = check_value(node->od, sub, data, len);
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
    uint8_t slot = origin != CO_ORIGIN_APP ? co_node_hook_slot(node, ref.entry) : CO_SLOT_NONE;
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
