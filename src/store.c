/* Store parameters 0x1010 and restore default parameters 0x1011 (CiA 301 §7.5.2.13-14). */
#include "canopen/store.h"

#include <string.h>

#include "canopen/node.h"

/* The objects a sub-entry of 0x1010/0x1011 stands for. */
static bool group_range(uint8_t sub, uint16_t *first, uint16_t *last)
{
    switch (sub) {
    case 1: *first = 0x0000u; *last = 0xFFFFu; return true;  /* all */
    case 2: *first = 0x1000u; *last = 0x1FFFu; return true;  /* communication */
    case 3: *first = 0x6000u; *last = 0x9FFFu; return true;  /* application (device profile) */
    case 4: *first = 0x2000u; *last = 0x5FFFu; return true;  /* manufacturer-specific */
    default: return false;
    }
}

/* Copies the persistent values of objects first..last into image: the current ones, or the
 * defaults with the node-ID applied as a reset would. */
static void copy_group(const co_node *node, uint8_t *image, bool defaults, uint16_t first,
                       uint16_t last)
{
    const co_od *od = node->od;
    for (uint32_t e = 0; e < od->entry_count; e++) {
        const co_od_entry *entry = &od->entries[e];
        if (entry->index < first || entry->index > last) {
            continue;
        }
        for (uint32_t s = 0; s < entry->sub_count; s++) {
            const co_od_sub *sub = &entry->subs[s];
            uint32_t size = co_od_sub_size(sub);
            if ((sub->flags & CO_OD_PERSIST) == 0u || sub->type == CO_DOMAIN || size == 0u ||
                sub->offset + size > od->persist_size) {
                continue;
            }
            uint8_t *dst = image + sub->offset;
            if (!defaults) {
                memcpy(dst, node->values + sub->offset, size);
                continue;
            }
            co_od_default_copy(od, dst, sub->offset, size);
            if ((sub->flags & CO_OD_NODEID) != 0u) {
                uint32_t carry = node->node_id;
                for (uint32_t i = 0; i < size && carry != 0u; i++) {
                    carry += dst[i];
                    dst[i] = (uint8_t)carry;
                    carry >>= 8;
                }
            }
        }
    }
}

/* The image a partial store or restore starts from: the stored one, else the defaults.
 * Returns false when no image is stored. */
static bool load_image(const co_node *node, uint8_t *image)
{
    const co_storage *st = node->storage;
    uint32_t len = node->od->persist_size;
    if (st->load != NULL && st->load(st->ctx, node->od->layout_hash, 0u, image, len)) {
        return true;
    }
    co_od_default_copy(node->od, image, 0u, len);
    copy_group(node, image, true, 0x0000u, 0xFFFFu);
    return false;
}

static bool scratch_ok(const co_node *node)
{
    return node->store_scratch != NULL && node->store_scratch_size >= node->od->persist_size;
}

co_abort co_store_save(co_node *node, uint8_t sub)
{
    const co_storage *st = node->storage;
    uint16_t first, last;
    if (st == NULL || st->save == NULL || !group_range(sub, &first, &last)) {
        return CO_ABORT_STORE;
    }
    const uint8_t *image = node->values; /* sub 1: the persistent prefix as it is */
    if (sub != 1u) {
        if (!scratch_ok(node)) {
            return CO_ABORT_STORE;
        }
        (void)load_image(node, node->store_scratch);
        copy_group(node, node->store_scratch, false, first, last);
        image = node->store_scratch;
    }
    /* The port keeps the old image when saving fails, so a refusal changes nothing. */
    return st->save(st->ctx, node->od->layout_hash, image, node->od->persist_size)
               ? CO_ABORT_NONE
               : CO_ABORT_STORE;
}

co_abort co_store_restore(co_node *node, uint8_t sub)
{
    const co_storage *st = node->storage;
    uint16_t first, last;
    if (st == NULL || !group_range(sub, &first, &last)) {
        return CO_ABORT_STORE;
    }
    if (sub == 1u) {
        return st->erase != NULL && st->erase(st->ctx) ? CO_ABORT_NONE : CO_ABORT_STORE;
    }
    if (!scratch_ok(node) || st->save == NULL) {
        return CO_ABORT_STORE;
    }
    if (!load_image(node, node->store_scratch)) {
        return CO_ABORT_NONE; /* nothing stored: the defaults take effect at the next reset */
    }
    copy_group(node, node->store_scratch, true, first, last);
    return st->save(st->ctx, node->od->layout_hash, node->store_scratch, node->od->persist_size)
               ? CO_ABORT_NONE
               : CO_ABORT_STORE;
}

/* Reads of sub 1..: what the device offers (EDS default), nothing without a storage. The value
 * block holds the last signature written, so it is put back before every SDO read. */
co_abort co_store_refresh(co_node *node, void *ctx, co_od_ref ref)
{
    (void)ctx;
    const co_od_sub *sub = ref.sub;
    if (sub->subindex == 0u || co_od_sub_size(sub) != 4u || sub->type == CO_DOMAIN) {
        return CO_ABORT_NONE;
    }
    uint8_t *value = node->values + sub->offset;
    if (node->storage != NULL) {
        co_od_default_copy(node->od, value, sub->offset, 4u);
    } else {
        memset(value, 0, 4u);
    }
    return CO_ABORT_NONE;
}

co_abort co_store_written(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                          uint32_t len, co_od_origin origin)
{
    (void)ctx;
    (void)origin;
    uint8_t sub = ref.sub->subindex;
    if (sub == 0u) {
        return CO_ABORT_READ_ONLY;
    }
    if (len != 4u) {
        return CO_ABORT_TYPE_LENGTH;
    }
    uint32_t signature = co_get_le32(data);
    if (ref.entry->index == 0x1010u) {
        return signature == CO_STORE_SIGNATURE_SAVE ? co_store_save(node, sub) : CO_ABORT_STORE;
    }
    return signature == CO_STORE_SIGNATURE_LOAD ? co_store_restore(node, sub) : CO_ABORT_STORE;
}

