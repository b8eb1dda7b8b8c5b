/* Store parameters 0x1010 and restore default parameters 0x1011 (CiA 301 §7.5.2.13-14). */
#include "canopen/store.h"

#include <string.h>

#include "canopen/node.h"
#include "dispatch.h"
#include "services.h"

/* Copies the persistent values of the objects of group (sub - 1: a CO_GROUP_*) into image: the
 * current ones, or the defaults with the node-ID applied as a reset would. */
static void copy_group(const co_node *node, uint8_t *image, bool defaults, uint32_t group)
{
    (void)co_node_copy_values(node, image, defaults ? NULL : node->values, group | CO_OD_PERSIST);
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
    copy_group(node, image, true, CO_GROUP_ALL);
    return false;
}

static bool scratch_ok(const co_node *node)
{
    return node->store_scratch != NULL && node->store_scratch_size >= node->od->persist_size;
}

/* A "save" (restore 0) or "load" (restore nonzero) command for group sub. */
static co_abort store_command(co_node *node, uint8_t sub, uint32_t restore)
{
    const co_storage *st = node->storage;
    uint32_t group = sub - 1u;
    bool ok = false;
    if (st == NULL || group >= 4u) {
        /* no storage, or no such group: refused */
    } else if (restore != 0u && group == 0u) { /* all: forget the image */
        ok = st->erase != NULL && st->erase(st->ctx);
    } else if (st->save != NULL) {
        const uint8_t *image = node->values; /* save sub 1: the persistent prefix as it is */
        if (group != 0u) {
            uint8_t *scratch = node->store_scratch;
            if (!scratch_ok(node)) {
                return CO_ABORT_STORE;
            }
            if (!load_image(node, scratch) && restore != 0u) {
                return CO_ABORT_NONE; /* nothing stored: the defaults take effect at the next reset */
            }
            copy_group(node, scratch, restore != 0u, group);
            image = scratch;
        }
        /* The port keeps the old image when saving fails, so a refusal changes nothing. */
        ok = st->save(st->ctx, node->od->layout_hash, image, node->od->persist_size);
    }
    return ok ? CO_ABORT_NONE : CO_ABORT_STORE;
}

co_abort co_store_save(co_node *node, uint8_t sub)
{
    return store_command(node, sub, 0u);
}

co_abort co_store_restore(co_node *node, uint8_t sub)
{
    return store_command(node, sub, 1u);
}

/* Reads of sub 1..: what the device offers (EDS default), nothing without a storage. The value
 * block holds the last signature written, so it is put back before every SDO read. */
co_abort co_store_refresh(co_node *node, void *ctx, co_od_ref ref)
{
    (void)ctx;
    const co_od_sub *sub = ref.sub;
    if (sub->subindex == 0u || co_od_sub_size(sub) != 4u) { /* a DOMAIN's size is 0 */
        return CO_ABORT_NONE;
    }
    uint32_t at = co_od_value_offset(ref.entry, sub);
    uint8_t *value = node->values + at;
    if (node->storage != NULL) {
        co_od_default_copy(node->od, value, at, 4u);
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
    uint32_t restore = ref.entry->index - 0x1010u; /* 0 (0x1010) or 1 (0x1011) */
    uint32_t signature = restore != 0u ? CO_STORE_SIGNATURE_LOAD : CO_STORE_SIGNATURE_SAVE;
    return co_get_le32(data) == signature ? store_command(node, sub, restore) : CO_ABORT_STORE;
}

