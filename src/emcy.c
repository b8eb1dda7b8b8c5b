/* EMCY producer, error register 0x1001 and pre-defined error field 0x1003 (CiA 301 §7.2.7). */
#include "canopen/emcy.h"

#include <string.h>

#include "canopen/node.h"
#include "dispatch.h"
#include "services.h"

/* --- frames and the inhibit queue ---------------------------------------------------------- */

static bool emcy_allowed(const co_node *node)
{
    return node->emcy.valid && co_nmt_communicating(node->nmt_state);
}

/* Sends f, its data filled, on the EMCY CAN-ID; the inhibit time starts. */
static void emcy_transmit(co_node *node, co_frame *f)
{
    co_emcy *e = &node->emcy;
    f->id = e->cob_id;
    f->dlc = 8u;
    f->flags = 0u;
    /* A frame the node's own tx queue cannot take is counted there (stats.tx_dropped). */
    (void)co_node_send(node, f);
    CO_COUNT(e->sent);
    e->last_sent = node->now;
    e->has_sent = true;
    e->next_allowed = node->now + e->inhibit_us;
    if (CO_CONFIG_EMCY_HOLD) {
        e->reported = co_get_le16(f->data) != CO_EMCY_NO_ERROR || f->data[2] != 0u;
    }
}

/* An EMCY's 8 data bytes: code, 0x1001, the manufacturer bytes (NULL: zeros). */
static inline void emcy_fill(uint8_t data[8], uint16_t code, uint8_t reg,
                             const uint8_t manufacturer[5])
{
    co_put_le16(data, code);
    data[2] = reg;
    if (manufacturer != NULL) {
        memcpy(&data[3], manufacturer, 5u);
    } else {
        memset(&data[3], 0, 5u);
    }
}

/* Every EMCY goes through the queue, behind the frames already waiting (order first); what is
 * due goes out at once, the rest when the inhibit time allows (co_emcy_process). A node that may
 * not send (INITIALISING, 0x1014 invalid, STOPPED unless held) has co_emcy_process drop it, with
 * whatever still waited, and count it in emcy.suppressed. */
static void emcy_send(co_node *node, uint16_t code, uint8_t reg, const uint8_t manufacturer[5])
{
    co_emcy *e = &node->emcy;
#if CO_CONFIG_EMCY_LISTENER
    if (node->emcy_listener != NULL) {
        uint8_t data[8];
        emcy_fill(data, code, reg, manufacturer);
        node->emcy_listener(node, node->emcy_listener_ctx, data);
    }
#endif
    bool held = CO_CONFIG_EMCY_HOLD && node->nmt_state == CO_NMT_STOPPED;
    uint32_t count = e->queued_count;
    if (count >= CO_EMCY_QUEUE_LEN) {
        CO_COUNT(e->lost);
        return;
    }
    emcy_fill(e->queued[(e->queued_head + count) % CO_EMCY_QUEUE_LEN], code, reg, manufacturer);
    e->queued_count = (uint8_t)(count + 1u);
    if (held) {
        e->held = true; /* sent on leaving STOPPED (co_nmt_enter rechecks every service) */
        return;
    }
    co_node_wake(node, co_emcy_process(node, node->now));
}

/* Whether a frame held through STOPPED still tells the master something: an error EMCY if its
 * error is still active, an error-reset EMCY if the last EMCY sent told of an active error. */
static bool held_frame_due(const co_node *node, const uint8_t data[8])
{
    uint16_t code = co_get_le16(data);
    return code != CO_EMCY_NO_ERROR ? co_emcy_is_active(node, code) : node->emcy.reported;
}

co_time co_emcy_process(co_node *node, co_time now)
{
    co_emcy *e = &node->emcy;
    if (!emcy_allowed(node)) {
        if (CO_CONFIG_EMCY_HOLD && e->valid && node->nmt_state == CO_NMT_STOPPED) {
            e->held = true; /* waiting frames wait for the node to leave STOPPED */
            return CO_NEVER;
        }
        /* INITIALISING, 0x1014 invalid (or STOPPED without CO_CONFIG_EMCY_HOLD): the waiting
         * frames are not sent later. */
#if CO_CONFIG_STATS
        e->suppressed += e->queued_count;
#endif
        e->queued_count = 0u;
        e->held = false;
    }
    for (; e->queued_count != 0u; e->queued_count--) {
        const uint8_t *data = e->queued[e->queued_head];
        if (CO_CONFIG_EMCY_HOLD && e->held && !held_frame_due(node, data)) {
            CO_COUNT(e->suppressed);
        } else if (now < e->next_allowed) {
            return e->next_allowed;
        } else {
            co_frame f;
            memcpy(f.data, data, 8u);
            emcy_transmit(node, &f);
        }
        e->queued_head = (uint8_t)((e->queued_head + 1u) % CO_EMCY_QUEUE_LEN);
    }
    e->held = false;
    return CO_NEVER;
}

/* --- 0x1001 and 0x1003 --------------------------------------------------------------------- */

/* 0x1001 from the active errors (one body: the core itself calls only update_register). */
static inline uint8_t error_register(const co_node *node)
{
    const co_emcy *e = &node->emcy;
    /* the generic bit with any active error (in the loop: no second test of the count) */
    uint8_t generic = CO_NODE_OPTION(node, CO_NODE_ERR_REG_NO_GENERIC) ? 0u : CO_ERR_REG_GENERIC;
    uint8_t reg = 0u;
    for (uint32_t i = 0; i < e->active_count; i++) {
        reg |= e->active[i].register_bits | generic;
    }
    return reg;
}

uint8_t co_emcy_error_register(const co_node *node)
{
    return error_register(node);
}

/* Writes 0x1001 from the active errors, plus extra bits of an error the list could not hold. */
static uint8_t update_register(co_node *node, uint8_t extra)
{
    uint8_t reg = (uint8_t)(error_register(node) | extra);
    if (node->emcy.error_register != NULL) {
        *node->emcy.error_register = reg;
    }
    return reg;
}

static void history_push(co_node *node, uint32_t entry)
{
    co_emcy *e = &node->emcy;
    uint32_t depth = e->history_depth;
    if (depth == 0u) { /* also without 0x1003 */
        return;
    }
    const co_od_sub *subs = co_od_entry_subs(e->history);
    uint8_t *values = node->values + e->history->value_base;
    for (uint32_t i = depth; i > 1u; i--) {
        memcpy(values + subs[i].offset, values + subs[i - 1u].offset, 4u);
    }
    co_put_le32(values + subs[1].offset, entry);
    uint32_t count = e->history_count;
    count += count < depth ? 1u : 0u;
    e->history_count = (uint8_t)count;
    if (!e->history_fixed_count) {
        values[subs[0].offset] = (uint8_t)count;
    }
}

static co_emcy_active *find_active(const co_node *node, uint16_t code)
{
    const co_emcy *e = &node->emcy;
    const co_emcy_active *a = e->active;
    for (; a < e->active + e->active_count; a++) {
        if (a->code == code) {
            return (co_emcy_active *)(uintptr_t)a;
        }
    }
    return NULL;
}

/* --- the API ------------------------------------------------------------------------------- */

bool co_emcy_raise_info(co_node *node, uint16_t code, uint8_t register_bits,
                        const uint8_t manufacturer[5], uint16_t info)
{
    co_emcy *e = &node->emcy;
    if (code == CO_EMCY_NO_ERROR) {
        return false;
    }
    co_emcy_active *at = find_active(node, code);
    uint8_t extra = 0u;
    bool tracked = true; /* (a flag, not at != NULL: at would be kept and tested) */
    if (at != NULL) {
        at->register_bits |= register_bits;
    } else {
        history_push(node, ((uint32_t)info << 16) | code);
        uint32_t count = e->active_count;
        if (count < CO_EMCY_MAX_ACTIVE) {
            at = &e->active[count];
            e->active_count = (uint8_t)(count + 1u);
            at->code = code;
            at->register_bits = register_bits;
        } else {
            /* Untracked: its bits are in this 0x1001 only (the list is full, so the generic
             * bit is set anyway). */
            extra = register_bits;
            tracked = false;
        }
    }
    emcy_send(node, code, update_register(node, extra), manufacturer);
    return tracked;
}

#if CO_CONFIG_EMCY_LISTENER
void co_emcy_set_listener(co_node *node, co_emcy_listener fn, void *ctx)
{
    node->emcy_listener = fn;
    node->emcy_listener_ctx = ctx;
}
#endif

bool co_emcy_raise(co_node *node, uint16_t code, uint8_t register_bits,
                   const uint8_t manufacturer[5])
{
    return co_emcy_raise_info(node, code, register_bits, manufacturer, 0u);
}

void co_emcy_clear(co_node *node, uint16_t code)
{
    co_emcy *e = &node->emcy;
    co_emcy_active *at = find_active(node, code);
    if (at == NULL) {
        return;
    }
    /* The list has no order: the last one takes the freed place. */
    uint32_t count = e->active_count - 1u;
    e->active_count = (uint8_t)count;
    *at = e->active[count];
    uint8_t reg = update_register(node, 0u);
    if (count == 0u || CO_NODE_OPTION(node, CO_NODE_EMCY_RESET_EACH)) {
        emcy_send(node, CO_EMCY_NO_ERROR, reg, NULL);
    }
}

void co_emcy_clear_all(co_node *node)
{
    co_emcy *e = &node->emcy;
    if (e->active_count == 0u) {
        return;
    }
    e->active_count = 0u;
    emcy_send(node, CO_EMCY_NO_ERROR, update_register(node, 0u), NULL);
}

bool co_emcy_is_active(const co_node *node, uint16_t code)
{
    return find_active(node, code) != NULL;
}

/* --- objects ------------------------------------------------------------------------------- */

/* CiA 301 §7.3.5: CAN-IDs no EMCY (or PDO) may use. */

/* 0x1003: writing 0 to sub 0 empties the history; nothing else is writable. */
static co_abort history_written(co_node *node, co_od_ref ref, const uint8_t *data, uint32_t len)
{
    co_emcy *e = &node->emcy;
    if (ref.sub->subindex != 0u || e->history == NULL || len != 1u) {
        return CO_ABORT_READ_ONLY;
    }
    if (data[0] != 0u) {
        return CO_ABORT_VALUE_RANGE;
    }
    /* depth entries of 0 push every old one out (the write path stores the 0 in sub 0 after) */
    for (uint32_t i = e->history_depth; i > 0u; i--) {
        history_push(node, 0u);
    }
    e->history_count = 0u;
    return CO_ABORT_NONE;
}

co_abort co_emcy_history_written(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                                 uint32_t len, co_od_origin origin)
{
    (void)ctx;
    (void)origin;
    return history_written(node, ref, data, len);
}

/* Loads 0x1014 and 0x1015: values a write has checked, or what reset communication restored. The
 * running inhibit time is measured again from the last EMCY sent. */
static void load_params(co_node *node)
{
    co_emcy *e = &node->emcy;
    uint32_t v = co_node_od_value(node, 0x1014u, 0u, 0x80u + node->node_id);
    e->cob_id = (uint16_t)(v & 0x7FFu);
    e->valid = (v & 0x80000000u) == 0u;
    /* 0x1015 is UNSIGNED16: 100 µs units up to 6.5 s */
    e->inhibit_us = (uint32_t)(uint16_t)co_svc_od_value(node, 0x1015u) * 100u;
    e->next_allowed = e->has_sent ? e->last_sent + e->inhibit_us : 0u;
    co_node_recheck(node); /* waiting frames: sent sooner, later, or not at all */
}

/* 0x1014 / 0x1015 written by SDO: validated, then in effect at once. */
co_abort co_emcy_param_written(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                               uint32_t len, co_od_origin origin)
{
    (void)ctx;
    (void)origin;
    const co_emcy *e = &node->emcy;
    if (ref.entry->index == 0x1003u) {
        return history_written(node, ref, data, len);
    }
    if (ref.sub->subindex != 0u) {
        return CO_ABORT_NONE;
    }
    if (ref.entry->index == 0x1014u) {
        uint32_t v = co_le_value(data, len);
        uint16_t id = (uint16_t)(v & 0x7FFu);
        bool valid = (v & 0x80000000u) == 0u;
        if ((v << 1) >= 1u << 12 || /* bits 11-30 (shifted: no mask constant) */
            (valid && (co_can_id_restricted(id) || (e->valid && id != e->cob_id)))) {
            return CO_ABORT_VALUE_RANGE;
        }
    }
    co_svc_store(node, data, ref);
    load_params(node);
    return CO_ABORT_NONE;
}

void co_emcy_init(co_node *node)
{
    /* co_node_init cleared the node: no error active, nothing queued or sent; 0x1014 is loaded
     * at reset communication (until then the node is INITIALISING and sends no EMCY). A DOMAIN's
     * size is 0 (include/canopen/od.h): a sub-entry of 1 or 4 bytes has a value. */
    co_emcy *e = &node->emcy;

    co_od_ref ref;
    if (co_node_locate(node, 0x1001u, 0u, &ref) == CO_ABORT_NONE && co_od_sub_size(ref.sub) == 1u) {
        e->error_register = node->values + co_od_value_offset(ref.entry, ref.sub);
    }
    /* 0x1003 sub 0 is its first sub-entry (sub-entries are sorted) */
    if (co_node_locate(node, 0x1003u, 0u, &ref) == CO_ABORT_NONE && co_od_sub_size(ref.sub) == 1u) {
        const co_od_entry *h = ref.entry;
        /* The depth is the run of 32-bit entries at sub 1, 2, ... (the generator keeps subs
         * sorted; an entry of another size ends the usable history). */
        const co_od_sub *sub = ref.sub + 1;
        uint32_t depth = 0u;
        while (depth + 1u < co_od_entry_sub_count(h) && sub->subindex == depth + 1u &&
               co_od_sub_size(sub) == 4u) {
            depth++;
            sub++;
        }
        e->history = h;
        e->history_depth = (uint8_t)depth;
        /* co_node_init has just put every default into the value block */
        e->history_fixed_count = node->values[co_od_value_offset(h, ref.sub)] != 0u;
    }
}

void co_emcy_configure(co_node *node)
{
    co_emcy *e = &node->emcy;
    e->queued_count = 0u;
    e->queued_head = 0u;
    e->has_sent = false;
    e->held = false;
    e->reported = false;
    load_params(node);

    e->history_count = 0u;
    if (e->history != NULL && !e->history_fixed_count) {
        uint8_t n = node->values[co_od_value_offset(e->history, &co_od_entry_subs(e->history)[0])];
        e->history_count = n < e->history_depth ? n : e->history_depth;
    }
    (void)update_register(node, 0u);
}
