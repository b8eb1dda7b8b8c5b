/* Object dictionary access: lookup, typed and checked reads and writes. */
#include "canopen/od.h"

#include <string.h>

#include "canopen/node.h"

const co_od_entry *co_od_find_entry(const co_od *od, uint16_t index)
{
    uint32_t lo = 0, hi = od->entry_count;
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2u;
        uint16_t at = od->entries[mid].index;
        if (at == index) {
            return &od->entries[mid];
        }
        if (at < index) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return NULL;
}

const co_od_sub *co_od_find_sub(const co_od_entry *entry, uint8_t subindex)
{
    /* Most objects have dense sub-indices: try the direct slot before searching. */
    if (subindex < entry->sub_count && entry->subs[subindex].subindex == subindex) {
        return &entry->subs[subindex];
    }
    uint32_t lo = 0, hi = entry->sub_count;
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2u;
        uint8_t at = entry->subs[mid].subindex;
        if (at == subindex) {
            return &entry->subs[mid];
        }
        if (at < subindex) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return NULL;
}

co_abort co_od_locate(const co_od *od, uint16_t index, uint8_t subindex, co_od_ref *ref)
{
    ref->entry = co_od_find_entry(od, index);
    if (ref->entry == NULL) {
        ref->sub = NULL;
        return CO_ABORT_NO_OBJECT;
    }
    ref->sub = co_od_find_sub(ref->entry, subindex);
    return ref->sub == NULL ? CO_ABORT_NO_SUBINDEX : CO_ABORT_NONE;
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

bool co_type_is_signed(uint8_t type)
{
    switch (type) {
    case CO_INTEGER8: case CO_INTEGER16: case CO_INTEGER24: case CO_INTEGER32:
    case CO_INTEGER40: case CO_INTEGER48: case CO_INTEGER56: case CO_INTEGER64:
        return true;
    default:
        return false;
    }
}

uint8_t *co_od_value_ptr(const co_node *node, const co_od_sub *sub)
{
    if (sub->type == CO_DOMAIN) {
        return NULL;
    }
    return node->values + sub->offset;
}

uint32_t co_od_value_length(const co_node *node, co_od_ref ref)
{
    const co_od_sub *sub = ref.sub;
    if (sub->type == CO_VISIBLE_STRING) {
        const uint8_t *value = node->values + sub->offset;
        uint32_t n = 0;
        while (n < sub->size && value[n] != 0u) {
            n++;
        }
        return n;
    }
    if (sub->type == CO_DOMAIN) {
        return 0;
    }
    return sub->size;
}

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

static double pattern_to_double(uint64_t bits)
{
    double d;
    memcpy(&d, &bits, sizeof d);
    return d;
}

static double real_value(const uint8_t *data, uint8_t type)
{
    if (type == CO_REAL32) {
        uint32_t bits = co_get_le32(data);
        float f;
        memcpy(&f, &bits, sizeof f);
        return (double)f;
    }
    return pattern_to_double(load_pattern(data, 8, false));
}

/* Compares a new value against the sub-entry's limits. */
static co_abort check_limits(const co_od *od, const co_od_sub *sub, const uint8_t *data)
{
    const co_od_limit *lim = &od->limits[sub->limit];
    if (sub->type == CO_REAL32 || sub->type == CO_REAL64) {
        double v = real_value(data, sub->type);
        if (v != v) { /* NaN is outside every range */
            return CO_ABORT_VALUE_RANGE;
        }
        if (v > pattern_to_double(lim->high)) {
            return CO_ABORT_VALUE_TOO_HIGH;
        }
        if (v < pattern_to_double(lim->low)) {
            return CO_ABORT_VALUE_TOO_LOW;
        }
        return CO_ABORT_NONE;
    }
    if (co_type_is_signed(sub->type)) {
        int64_t v = (int64_t)load_pattern(data, sub->size, true);
        if (v > (int64_t)lim->high) {
            return CO_ABORT_VALUE_TOO_HIGH;
        }
        if (v < (int64_t)lim->low) {
            return CO_ABORT_VALUE_TOO_LOW;
        }
        return CO_ABORT_NONE;
    }
    uint64_t v = load_pattern(data, sub->size, false);
    if (v > lim->high) {
        return CO_ABORT_VALUE_TOO_HIGH;
    }
    if (v < lim->low) {
        return CO_ABORT_VALUE_TOO_LOW;
    }
    return CO_ABORT_NONE;
}

/* Length (and BOOLEAN range) against the type. */
static co_abort check_length(co_od_ref ref, const uint8_t *data, uint32_t len)
{
    const co_od_sub *sub = ref.sub;
    switch (sub->type) {
    case CO_DOMAIN:
        return CO_ABORT_NONE;
    case CO_VISIBLE_STRING:
    case CO_UNICODE_STRING:
        return len > sub->size ? CO_ABORT_TYPE_TOO_LONG : CO_ABORT_NONE;
    default:
        break;
    }
    if (len != sub->size) {
        return len > sub->size ? CO_ABORT_TYPE_TOO_LONG : CO_ABORT_TYPE_TOO_SHORT;
    }
    if (sub->type == CO_BOOLEAN && data[0] > 1u) {
        return CO_ABORT_VALUE_RANGE;
    }
    return CO_ABORT_NONE;
}

co_abort co_od_check_value(const co_od *od, co_od_ref ref, const uint8_t *data, uint32_t len)
{
    co_abort rc = check_length(ref, data, len);
    if (rc == CO_ABORT_NONE && (ref.sub->flags & CO_OD_LIMITS) != 0u) {
        rc = check_limits(od, ref.sub, data);
    }
    return rc;
}

co_abort co_od_read_ref(co_node *node, co_od_ref ref, uint8_t *buf, uint32_t cap, uint32_t *len,
                        co_od_origin origin)
{
    const co_od_sub *sub = ref.sub;
    *len = 0;
    if (origin == CO_ORIGIN_SDO && (sub->flags & CO_OD_READ) == 0u) {
        return CO_ABORT_WRITE_ONLY;
    }
    const co_od_hook *hook = co_node_find_hook(node, ref.entry->index);
    if (sub->type == CO_DOMAIN) {
        if (hook == NULL || hook->domain_read == NULL) {
            return CO_ABORT_NO_DATA;
        }
        uint32_t total = 0;
        return hook->domain_read(node, hook->ctx, ref, 0, buf, cap, len, &total);
    }
    if (origin == CO_ORIGIN_SDO && hook != NULL && hook->refresh != NULL) {
        co_abort rc = hook->refresh(node, hook->ctx, ref);
        if (rc != CO_ABORT_NONE) {
            return rc;
        }
    }
    uint32_t n = co_od_value_length(node, ref);
    if (n > cap) {
        return CO_ABORT_OUT_OF_MEMORY;
    }
    memcpy(buf, node->values + sub->offset, n);
    *len = n;
    return CO_ABORT_NONE;
}

co_abort co_od_read(co_node *node, uint16_t index, uint8_t subindex, uint8_t *buf, uint32_t cap,
                    uint32_t *len, co_od_origin origin)
{
    co_od_ref ref;
    co_abort rc = co_od_locate(node->od, index, subindex, &ref);
    if (rc != CO_ABORT_NONE) {
        *len = 0;
        return rc;
    }
    return co_od_read_ref(node, ref, buf, cap, len, origin);
}

co_abort co_od_write_ref(co_node *node, co_od_ref ref, const uint8_t *data, uint32_t len,
                         co_od_origin origin)
{
    const co_od_sub *sub = ref.sub;
    if (origin == CO_ORIGIN_SDO) {
        if ((sub->flags & CO_OD_WRITE) == 0u) {
            return CO_ABORT_READ_ONLY;
        }
        if ((node->options & CO_NODE_COMM_READ_ONLY_IN_OPERATIONAL) != 0u &&
            node->nmt_state == CO_NMT_OPERATIONAL && ref.entry->index >= 0x1000u &&
            ref.entry->index <= 0x1FFFu) {
            return CO_ABORT_DEVICE_STATE;
        }
    } else if (origin == CO_ORIGIN_RPDO && (sub->flags & CO_OD_RPDO) == 0u) {
        return CO_ABORT_NOT_MAPPABLE;
    }
    co_abort rc = co_od_check_value(node->od, ref, data, len);
    if (rc != CO_ABORT_NONE) {
        return rc;
    }
    const co_od_hook *hook = co_node_find_hook(node, ref.entry->index);
    if (sub->type == CO_DOMAIN) {
        if (hook == NULL || hook->domain_write == NULL) {
            return CO_ABORT_UNSUPPORTED_ACCESS;
        }
        return hook->domain_write(node, hook->ctx, ref, 0, data, len, len, true);
    }
    if (origin != CO_ORIGIN_APP && hook != NULL && hook->write != NULL) {
        rc = hook->write(node, hook->ctx, ref, data, len, origin);
        if (rc != CO_ABORT_NONE) {
            return rc;
        }
    }
    uint8_t *value = node->values + sub->offset;
    memcpy(value, data, len);
    if (len < sub->size) { /* a shorter string: clear the rest so its length reads back right */
        memset(value + len, 0, sub->size - len);
    }
    co_pdo_value_changed(node, sub); /* a TPDO mapping it goes out by itself */
    return CO_ABORT_NONE;
}

co_abort co_od_write(co_node *node, uint16_t index, uint8_t subindex, const uint8_t *data,
                     uint32_t len, co_od_origin origin)
{
    co_od_ref ref;
    co_abort rc = co_od_locate(node->od, index, subindex, &ref);
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
    if (co_od_locate(node->od, index, subindex, &ref) != CO_ABORT_NONE || ref.sub->size != size ||
        ref.sub->type == CO_DOMAIN) {
        return NULL;
    }
    return node->values + ref.sub->offset;
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
