/* PDOs: parameter checks and mapping resolution (the write hook), RPDO reception, TPDO triggering
 * (SYNC, events, inhibit time, event timer, RTR) and RPDO timeout monitoring. */
#include "canopen/pdo.h"

#include <stddef.h>
#include <string.h>

#include "canopen/emcy.h"
#include "canopen/node.h"
#include "canopen/sync.h"
#include "dispatch.h"
#include "services.h"

#define COB_INVALID 0x80000000u  /* bit 31: PDO does not exist */
#define COB_NO_RTR 0x40000000u   /* bit 30 (TPDO): no RTR allowed */
#define COB_FRAME_29 0x20000000u /* bit 29: 29-bit CAN-ID (not supported) */
#define COB_ID_BITS_11_28 0x1FFFF800u

#define RPDO_COMM 0x1400u
#define RPDO_MAP 0x1600u
#define TPDO_COMM 0x1800u
#define TPDO_MAP 0x1A00u
#define PDO_LAST 0x1BFFu

/* The transmission types from 241 on that are none: RPDO 241-253, TPDO 241-251 (a type t is
 * one of them when t - 241 is below this; 0-240 wrap far above). */
#define PDO_NO_TYPES(rpdo) (11u + 2u * (uint32_t)(rpdo))

#define EMCY_RPDO_SHORT 0x8210u /* PDO not processed due to length error */
#define EMCY_RPDO_LONG 0x8220u  /* PDO length exceeded */

/* --- small helpers ------------------------------------------------------------------------- */

/* The RPDO or TPDO whose head h is (the first member of both: C99 6.7.2.1 lets a pointer to it
 * stand for the struct). */
static co_rpdo *rpdo_of(co_pdo_head *h)
{
    return (co_rpdo *)(void *)h;
}
static co_tpdo *tpdo_of(co_pdo_head *h)
{
    return (co_tpdo *)(void *)h;
}

static co_time earliest(co_time a, co_time b)
{
    return a < b ? a : b;
}

/* A PDO timer deadline: kept in pdo.next and in the node's. */
static CO_ONE_COPY void schedule(co_node *node, co_time at)
{
    node->pdo.next = earliest(node->pdo.next, at);
    co_node_wake(node, at);
}

/* An event-driven TPDO may be due now: the next co_pdo_process pass looks (co_node_process checks
 * the flag before anything else). */
static void mark_pending(co_node *node)
{
    node->pdo.pending = true;
}

static bool tpdo_event_driven(uint8_t type)
{
    return type >= 254u;
}

/* TPDOs that go out when a mapped value changes. */
static bool tpdo_watches(const co_tpdo *t)
{
    return t->head.active && (t->head.type == 0u || tpdo_event_driven(t->head.type));
}

/* The slot of PDO number (an RPDO if rpdo, else a TPDO), NULL if none. */
static co_pdo_head *find_pdo(co_node *node, bool rpdo, uint16_t number)
{
    co_pdo *p = &node->pdo;
    if (rpdo) {
        for (co_rpdo *r = p->rpdo; r < p->rpdo + p->rpdo_count; r++) {
            if (r->head.number == number) {
                return &r->head;
            }
        }
    } else {
        for (co_tpdo *t = p->tpdo; t < p->tpdo + p->tpdo_count; t++) {
            if (t->head.number == number) {
                return &t->head;
            }
        }
    }
    return NULL;
}

/* raw x unit in µs, saturated at the longest span a deadline may have (a drive may declare the
 * 16-bit objects wider). */
static CO_ONE_COPY uint32_t scaled_us(uint32_t raw, uint32_t unit)
{
    uint64_t us = (uint64_t)raw * unit;
    return us > CO_TIME_SPAN_MAX ? CO_TIME_SPAN_MAX : (uint32_t)us;
}

static uint32_t effective_inhibit_us(const co_node *node, uint32_t raw)
{
#if CO_CONFIG_PDO_TUNING
    const co_pdo_config *c = &node->pdo.cfg;
    uint32_t us = scaled_us(raw, c->tpdo_inhibit_unit_us != 0u ? c->tpdo_inhibit_unit_us : 100u);
    bool floor = raw != 0u || !CO_PDO_FLAG(node, CO_PDO_INHIBIT_MIN_IF_SET);
    return (floor && us < c->tpdo_inhibit_min_us) ? c->tpdo_inhibit_min_us : us;
#else
    (void)node;
    return scaled_us(raw, 100u);
#endif
}

static uint32_t effective_event_us(const co_node *node, uint32_t raw_ms)
{
    uint32_t us = scaled_us(raw_ms, 1000u);
#if CO_CONFIG_PDO_TUNING
    uint32_t min = node->pdo.cfg.tpdo_event_min_us;
    return (us != 0u && us < min) ? min : us;
#else
    (void)node;
    return us;
#endif
}

/* --- mapping ------------------------------------------------------------------------------- */

/* Checks one mapping entry (index << 16 | sub << 8 | bits) for this direction: *ref the object
 * (sub NULL: a dummy), set only for a good entry (its bytes are then (value & 0xFF) / 8). */
static co_abort resolve_entry(const co_node *node, uint32_t value, bool rpdo, co_od_ref *ref)
{
    uint16_t index = (uint16_t)(value >> 16);
    uint8_t subindex = (uint8_t)(value >> 8);
    uint32_t bits = value & 0xFFu;
    if (bits > CO_PDO_MAX_BYTES * 8u) {
        return CO_ABORT_PDO_LENGTH;
    }
    if (bits == 0u || (bits % 8u) != 0u) { /* byte granularity only */
        return CO_ABORT_NOT_MAPPABLE;
    }
    if (index >= 0x0001u && index <= 0x0007u) {
        /* A dummy: bytes of an RPDO this device skips, if its [DummyUsage] allows the type. */
        bool allowed = rpdo && (node->pdo.cfg.rpdo_dummy_mask & (1u << index)) != 0u &&
                       subindex == 0u && co_type_size((uint8_t)index) * 8u == bits;
        if (!allowed) {
            return CO_ABORT_NOT_MAPPABLE;
        }
        ref->entry = NULL;
        ref->sub = NULL;
        return CO_ABORT_NONE;
    }
    if (co_node_locate(node, value >> 16, value >> 8, ref) != CO_ABORT_NONE) {
        return CO_ABORT_NOT_MAPPABLE;
    }
    const co_od_sub *sub = ref->sub;
    /* the EDS PDOMapping of this direction */
    uint32_t mappable = rpdo ? CO_OD_RPDO : CO_OD_TPDO;
    if ((sub->flags & mappable) == 0u || sub->type == CO_DOMAIN) {
        return CO_ABORT_NOT_MAPPABLE;
    }
    uint32_t bytes = bits / 8u;
    bool partial_ok = sub->type == CO_VISIBLE_STRING || sub->type == CO_UNICODE_STRING ||
                      (!rpdo && sub->type == CO_OCTET_STRING);
    uint32_t size = co_od_sub_size(sub);
    if (bytes > size || (bytes < size && !partial_ok)) {
        return CO_ABORT_NOT_MAPPABLE;
    }
    return CO_ABORT_NONE;
}

/* The handler of a mapped object (co_node_hook_slot; CO_SLOT_NONE for a dummy): resolved with the
 * mapping, so that a frame needs no lookup. */
static uint8_t rpdo_slot(const co_node *node, const co_od_ref *ref)
{
    return ref->sub != NULL ? co_node_hook_slot(node, ref->entry) : (uint8_t)CO_SLOT_NONE;
}

/* Resolves entries 1..count of mapping object map_index, with sub 0 = count. pdo (a co_rpdo if
 * rpdo, else a co_tpdo; NULL: only checked) gets the map, its count and size, and an RPDO the
 * handlers (rpdo_slot) and the values that need a check; a mapping that is not valid leaves it
 * none (count 0). */
static co_abort resolve_mapping(const co_node *node, uint16_t map_index, uint32_t count, bool rpdo,
                                co_pdo_head *pdo)
{
    co_abort rc = count > CO_PDO_MAX_MAPPED ? CO_ABORT_PDO_LENGTH : CO_ABORT_NONE;
    uint32_t total = 0;
    uint32_t check = 0;
    for (uint32_t j = 0; rc == CO_ABORT_NONE && j < count; j++) {
        /* the entries are UNSIGNED32 (tools/eds2c.py); one the object lacks reads as 255 bits,
         * too long: more objects than the mapping has entries */
        uint32_t value = co_node_od_value(node, map_index, j + 1u, 0xFFu);
        co_od_ref ref;
        rc = resolve_entry(node, value, rpdo, &ref);
        uint8_t len = (uint8_t)((value & 0xFFu) / 8u);
        total += len;
        if (rc != CO_ABORT_NONE) {
            break;
        }
        if (pdo == NULL) {
            continue;
        }
        pdo->map_len[j] = len;
        if (rpdo) {
            /* its handler, and whether its value needs a check (limits, BOOLEAN: bit j) */
            co_rpdo *r = rpdo_of(pdo);
            r->map[j] = ref;
            r->map_hook[j] = rpdo_slot(node, &ref);
            if (ref.sub != NULL &&
                ((ref.sub->flags & CO_OD_LIMITS) != 0u || ref.sub->type == CO_BOOLEAN)) {
                check |= 1u << j;
            }
        } else {
            /* no dummy */
            tpdo_of(pdo)->map[j] = (uint16_t)co_od_value_offset(ref.entry, ref.sub);
        }
    }
    if (total > CO_PDO_MAX_BYTES) {
        rc = CO_ABORT_PDO_LENGTH;
    }
    if (rc != CO_ABORT_NONE) {
        count = 0u;
        total = 0u;
        check = 0u;
    }
    if (pdo != NULL) {
        pdo->count = (uint8_t)count;
        pdo->size = (uint8_t)total;
        if (rpdo) {
            rpdo_of(pdo)->check = (uint8_t)check;
        }
    }
    return rc;
}

/* --- state ---------------------------------------------------------------------------------- */

static bool cob_usable(uint32_t cob)
{
    return (cob & (COB_INVALID | COB_FRAME_29 | COB_ID_BITS_11_28)) == 0u &&
           !co_can_id_restricted((uint16_t)(cob & 0x7FFu));
}

#if CO_CONFIG_PDO_BITS != 0
/* Bit of a CAN-ID in pdo.rpdo_filter: both halves of the 11 bits mixed, so the RPDOs of a node
 * (0x200 + n, 0x300 + n, ...) fall on different bits. */
static co_pdo_bits rpdo_filter_bit(uint16_t id)
{
    return CO_PDO_BIT((uint32_t)id ^ ((uint32_t)id >> 6));
}
#endif

/* Whether an RPDO may take a data frame on CAN-ID id (false: none does). */
static bool rpdo_may_take(const co_pdo *p, uint16_t id)
{
#if CO_CONFIG_PDO_BITS != 0
    return (p->rpdo_filter & rpdo_filter_bit(id)) != 0u;
#else
    (void)p;
    (void)id;
    return true;
#endif
}

/* The hashed sets from the PDOs in use (none with CO_CONFIG_PDO_BITS 0). */
static void rebuild_sets(co_node *node)
{
#if CO_CONFIG_PDO_BITS == 0
    (void)node;
#else
    co_pdo *p = &node->pdo;
    co_pdo_bits filter = 0u;
    for (uint32_t i = 0; i < p->rpdo_count; i++) {
        if (p->rpdo[i].head.active) {
            filter |= rpdo_filter_bit(p->rpdo[i].head.cob_id);
        }
    }
    p->rpdo_filter = filter;
    co_pdo_bits w = 0;
    for (uint32_t i = 0; i < p->tpdo_count; i++) {
        const co_tpdo *t = &p->tpdo[i];
        if (!tpdo_watches(t)) {
            continue;
        }
        for (uint32_t j = 0; j < t->head.count; j++) {
            w |= CO_PDO_BIT(t->map[j]);
        }
    }
    p->watch = w;
#endif
}

/* Forgets any pending transmission and restarts the TPDO's counts and inhibit time (the event
 * timer: tpdo_start_timer). */
static void tpdo_reset_triggers(co_node *node, co_tpdo *t)
{
    t->event = false;
    t->forced = false;
    t->sent = false;
    t->started = false;
    t->sync_count = 0u;
    t->inhibit_end = node->now;
}

/* The event timer of an event-driven TPDO in use in OPERATIONAL runs from now (else it stops). */
static void tpdo_start_timer(co_node *node, co_tpdo *t)
{
    t->event_deadline = CO_NEVER;
    if (node->nmt_state == CO_NMT_OPERATIONAL && t->head.active && tpdo_event_driven(t->head.type) &&
        t->event_us != 0u) {
        t->event_deadline = node->now + t->event_us;
        schedule(node, t->event_deadline);
    }
}

/* Restarts the TPDO's triggers; in OPERATIONAL, the first transmission and the event timer. */
static void tpdo_start(co_node *node, co_tpdo *t)
{
    tpdo_reset_triggers(node, t);
    if (t->head.active && node->nmt_state == CO_NMT_OPERATIONAL &&
        (t->head.type == 0u || tpdo_event_driven(t->head.type)) &&
        CO_PDO_FLAG(node, CO_PDO_TPDO_SEND_ON_START)) {
        t->event = true;
        t->forced = true;
        if (tpdo_event_driven(t->head.type)) {
            mark_pending(node);
        }
    }
    tpdo_start_timer(node, t); /* stops the event timer unless in use and OPERATIONAL */
}

/* Starts a PDO again (pdo: a co_rpdo if rpdo, else a co_tpdo): nothing received kept, no RPDO
 * timeout running; a TPDO's triggers restarted (tpdo_start). */
static void pdo_restart(co_node *node, bool rpdo, co_pdo_head *pdo)
{
    if (rpdo) {
        co_rpdo *r = rpdo_of(pdo);
        r->buffered = false;
        r->armed = false;
    } else {
        tpdo_start(node, tpdo_of(pdo));
    }
}

/* --- transmission --------------------------------------------------------------------------- */

/* What tpdo_send does with a TPDO. */
#define TPDO_EVENT 0u  /* samples; sends if the data changed since the last frame, or t->forced */
#define TPDO_NOW 1u    /* samples and sends */
#define TPDO_SAMPLE 2u /* samples only (type 252 at a SYNC) */
#define TPDO_KEPT 3u   /* sends the data sampled before (an RTR of type 252 after a SYNC) */

/* The one way out of a TPDO: t->frame.data holds the mapped values (its unmapped tail 0) and the
 * last frame sent or sampled. */
static void tpdo_send(co_node *node, co_tpdo *t, co_time now, uint32_t how)
{
    uint8_t *data = t->frame.data;
    if (how != TPDO_KEPT) {
        uint64_t old;
        uint64_t cur;
        memcpy(&old, data, sizeof old);
        memset(data, 0, sizeof old);
        uint8_t *out = data;
        const uint8_t *len = t->head.map_len;
        for (const uint16_t *at = t->map, *end = at + t->head.count; at != end; at++, len++) {
            memcpy(out, node->values + *at, *len);
            out += *len;
        }
        memcpy(&cur, data, sizeof cur);
        /* set here for every path on, one store (a TPDO_KEPT send comes only once it is set) */
        bool was_sent = t->sent;
        t->sent = true;
        if (how == TPDO_SAMPLE) {
            return;
        }
        if (how == TPDO_EVENT && !t->forced && was_sent &&
            old == cur) {
            t->event = false; /* changed and changed back: nothing new to tell */
            return;
        }
    }
    /* flags stay 0 (co_node_init clears the node) */
    t->frame.id = t->head.cob_id;
    /* some cards pad every TPDO to a full frame (CO_PDO_TPDO_DLC_8); the tail is zero */
    t->frame.dlc = CO_PDO_FLAG(node, CO_PDO_TPDO_DLC_8) ? CO_PDO_MAX_BYTES : t->head.size;
    t->event = false;
    t->forced = false;
    (void)co_node_send(node, &t->frame);
    CO_COUNT(node->pdo.stats.tpdo_sent);
    if (tpdo_event_driven(t->head.type)) {
        t->inhibit_end = now + t->inhibit_us;
        if (t->event_us != 0u) {
            t->event_deadline = now + t->event_us;
            schedule(node, t->event_deadline);
        }
    }
}

/* --- loading a PDO from its objects ----------------------------------------------------------- */

/* Loads a PDO's parameters from its objects (pdo: a co_rpdo if rpdo, else a co_tpdo) and whether
 * it is in use (a write that changes that restarts it: pdo_restart). A stored mapping that is not
 * valid leaves the PDO without one: unused. */
static void pdo_load(co_node *node, bool rpdo, co_pdo_head *pdo)
{
    uint16_t number = pdo->number;
    /* number is 1-512 (co_pdo_init): both indexes fit 16 bits */
    uint32_t comm = (rpdo ? RPDO_COMM : TPDO_COMM) + number - 1u;
    uint32_t map = comm + 0x200u;
    /* one loop, one call site: v[0] the mapping's count, v[1..6] the communication parameters
     * (absent: type 255, else 0; a COB-ID of 0 is CAN-ID 0, reserved: not usable, as an absent
     * one is) */
    uint32_t v[7];
    uint32_t index = map;
    for (uint32_t sub = 0; sub <= 6u; sub++) {
        v[sub] = co_node_od_value(node, index, sub,
                                  sub == 2u ? 255u : 0u);
        index = comm;
    }
    uint32_t cob = v[1];
    uint32_t timer = v[5];
    (void)resolve_mapping(node, (uint16_t)map, v[0], rpdo, pdo);
    bool valid = cob_usable(cob);
    uint32_t type = (uint8_t)v[2];
    pdo->cob_valid = valid;
    pdo->cob_id = (uint16_t)(cob & 0x7FFu);
    pdo->type = (uint8_t)type;
    if (rpdo) {
        /* length_error stays: its EMCY is still active and clears with the next good frame */
        rpdo_of(pdo)->timeout_us = scaled_us(timer, 1000u);
    } else {
        co_tpdo *t = tpdo_of(pdo);
        t->rtr_allowed = (cob & COB_NO_RTR) == 0u;
        t->event_us = effective_event_us(node, timer);
        /* with CO_PDO_EVENT_TIMER_ALONE the event timer alone paces a 254/255 TPDO that has one
           (co_pdo_value_changed ignores its changes) */
        bool timer_alone = t->event_us != 0u && CO_PDO_FLAG(node, CO_PDO_EVENT_TIMER_ALONE);
        /* with CO_PDO_INHIBIT_254_ONLY a type 255 TPDO has no inhibit time */
        bool no_inhibit = type == 255u && CO_PDO_FLAG(node, CO_PDO_INHIBIT_254_ONLY);
        t->inhibit_us = (timer_alone || no_inhibit) ? 0u : effective_inhibit_us(node, v[3]);
        t->sync_start = v[6] <= 240u ? (uint8_t)v[6] : 0u;
    }
    /* the CAN-ID is no reserved one (cob_usable); RPDO 241-253 and TPDO 241-251 are no types.
     * Only a write that restarts the PDO changes this (a COB-ID that keeps its validity, sub 3,
     * 5 and 6 leave it as it was). */
    pdo->active = valid && pdo->count != 0u && type - 241u >= PDO_NO_TYPES(rpdo);
}

/* --- the write hook ------------------------------------------------------------------------- */

/* A COB-ID write to pdo (a co_rpdo if rpdo, else a co_tpdo; NULL: the dictionary has the PDO but
 * this node no slot for it). */
static co_abort check_cob_write(const co_node *node, uint32_t v, const co_pdo_head *pdo)
{
    if ((v & (COB_FRAME_29 | COB_ID_BITS_11_28)) != 0u) {
        return co_pdo_value_abort(node);
    }
    if ((v & COB_INVALID) != 0u) {
        return CO_ABORT_NONE; /* disabling (or staying disabled) is always allowed */
    }
    if (pdo == NULL) {
        return CO_ABORT_DEVICE_INCOMPATIBLE;
    }
    uint16_t id = (uint16_t)(v & 0x7FFu);
    if ((pdo->cob_valid && id != pdo->cob_id) || co_can_id_restricted(id) || pdo->count == 0u) {
        return co_pdo_value_abort(node);
    }
    return CO_ABORT_NONE;
}

/* The checks of a communication parameter write, against the PDO's state before it (pdo as for
 * check_cob_write). */
static co_abort check_comm_write(const co_node *node, bool rpdo, uint8_t subindex, uint32_t v,
                                 const co_pdo_head *pdo)
{
    if (subindex == 1u) {
        return check_cob_write(node, v, pdo);
    }
    if (subindex == 2u) { /* RPDO 241-253, TPDO 241-251 are no types */
        return v - 241u < PDO_NO_TYPES(rpdo) ? co_pdo_value_abort(node) : CO_ABORT_NONE;
    }
    /* TPDO inhibit time and SYNC start value: CiA 301, not while the PDO exists (some drives'
       manuals change the inhibit time of a valid TPDO: CO_PDO_INHIBIT_WHILE_VALID) */
    if ((subindex == 3u || subindex == 6u) && !rpdo) {
        if (pdo != NULL && pdo->cob_valid &&
            !(subindex == 3u && CO_PDO_FLAG(node, CO_PDO_INHIBIT_WHILE_VALID))) {
            return co_pdo_busy_abort(node);
        }
        return subindex == 6u && v > 240u ? co_pdo_value_abort(node) : CO_ABORT_NONE;
    }
    return CO_ABORT_NONE;
}

/* The checks of a mapping parameter write. */
static co_abort check_mapping_write(const co_node *node, bool rpdo, uint16_t map_index,
                                    uint8_t subindex, uint32_t v)
{
    /* Validity as the master sees it: the COB-ID object of the PDO. */
    uint16_t comm_index = (uint16_t)(map_index - 0x200u);
    bool valid = (co_node_od_value(node, comm_index, 1, COB_INVALID) & COB_INVALID) == 0u;
    if (valid && !CO_PDO_FLAG(node, CO_PDO_MAP_WHILE_VALID)) {
        return co_pdo_busy_abort(node);
    }
    if (subindex != 0u) {
        if (co_node_od_value(node, map_index, 0, 0u) != 0u) {
            return co_pdo_busy_abort(node);
        }
        co_od_ref ref;
        return v == 0u ? CO_ABORT_NONE : resolve_entry(node, v, rpdo, &ref);
    }
    return resolve_mapping(node, map_index, v, rpdo, NULL);
}

co_abort co_pdo_param_written(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                              uint32_t len, co_od_origin origin)
{
    (void)ctx;
    (void)origin;
    uint16_t index = ref.entry->index;
    uint8_t subindex = ref.sub->subindex;
    uint32_t v = co_le_value(data, len);
    uint16_t number = (uint16_t)((index & 0x1FFu) + 1u);
    bool rpdo = (index & 0x800u) == 0u; /* 0x1400-0x17FF (the handler's objects only) */
    bool mapping = (index & 0x200u) != 0u;
    /* the co_rpdo or co_tpdo written; NULL: no slot for it */
    co_pdo_head *pdo = find_pdo(node, rpdo, number);
    co_abort rc = mapping ? check_mapping_write(node, rpdo, index, subindex, v)
                          : check_comm_write(node, rpdo, subindex, v, pdo);
    if (rc != CO_ABORT_NONE || pdo == NULL) {
        return rc;
    }
    bool was_valid = pdo->cob_valid;
    /* Accepted: the value goes into the dictionary now (the node then stores the same bytes) and
     * the PDO loads its parameters from its objects. */
    co_svc_store(node, data, ref);
    pdo_load(node, rpdo, pdo);
    /* A new mapping or type, or the PDO made valid or invalid, restarts it; any other write keeps
     * what it is doing (a mapping entry or the COB-ID of an unused PDO: it has nothing to keep). */
    if (mapping || subindex == 2u || (subindex == 1u && pdo->cob_valid != was_valid)) {
        pdo_restart(node, rpdo, pdo);
        rebuild_sets(node);
    } else if (subindex == 5u) {
        if (rpdo) {
            ((co_rpdo *)pdo)->armed = false; /* timeout monitoring restarts with the next RPDO */
        } else {
            tpdo_start_timer(node, tpdo_of(pdo)); /* the new period from now */
        }
    }
    return CO_ABORT_NONE;
}

/* Nothing pending, no PDO timer: what comes next schedules itself again (node->next is at worst
 * early: src/schedule.h). */
static void pdo_clear_schedule(co_node *node)
{
    node->pdo.pending = false;
    node->pdo.next = CO_NEVER;
}

/* --- set-up ----------------------------------------------------------------------------------- */

void co_pdo_hooks_changed(co_node *node)
{
    /* only the handlers change (which values need a check does not) */
    for (uint32_t i = 0; i < node->pdo.rpdo_count; i++) {
        co_rpdo *r = &node->pdo.rpdo[i];
        for (uint32_t j = 0; j < r->head.count; j++) {
            r->map_hook[j] = rpdo_slot(node, &r->map[j]);
        }
    }
}

void co_pdo_init(co_node *node, const co_pdo_config *cfg)
{
    co_pdo *p = &node->pdo; /* all zero: co_node_init has cleared the node */
    /* cfg is never NULL: co_node_init passes its own config's */
#if CO_CONFIG_PDO_TUNING || CO_CONFIG_PDO_FLAGS != 0
    p->cfg = *cfg;
#else
    /* the rest is 0: co_node_init refuses a setting the build leaves out */
    p->cfg.rpdo_dummy_mask = cfg->rpdo_dummy_mask;
#endif
    p->next = CO_NEVER;
    const co_od *od = node->od;
    const co_od_entry *end = od->entries + od->entry_count;
    for (const co_od_entry *en = od->entries; en != end; en++) {
        /* a PDO is there when its communication parameter is (0x1400-0x15FF, 0x1800-0x19FF);
         * one beyond CO_MAX_RPDO / CO_MAX_TPDO is left out */
        uint16_t index = en->index;
        uint16_t number = (uint16_t)((index & 0x1FFu) + 1u);
        if (index >= RPDO_COMM && index <= RPDO_COMM + 0x1FFu) {
            if (p->rpdo_count < CO_MAX_RPDO) {
                p->rpdo[p->rpdo_count++].head.number = number;
            }
        } else if (index >= TPDO_COMM && index <= TPDO_COMM + 0x1FFu) {
            if (p->tpdo_count < CO_MAX_TPDO) {
                p->tpdo[p->tpdo_count++].head.number = number;
            }
        }
    }
}

/* A PDO (pdo: a co_rpdo if rpdo, else a co_tpdo) loaded from its objects and its use decided
 * again (load), or restarted. */
static void pdo_step(co_node *node, bool load, bool rpdo, co_pdo_head *pdo)
{
    if (load) {
        pdo_load(node, rpdo, pdo);
    }
    pdo_restart(node, rpdo, pdo); /* on an NMT change node->nmt_state is the new one already */
}

/* pdo_step for every PDO, the RPDOs first. */
static CO_ONE_COPY void pdo_walk(co_node *node, bool load)
{
    co_pdo *p = &node->pdo;
    pdo_clear_schedule(node);
    co_rpdo *r = p->rpdo;
    for (uint32_t n = p->rpdo_count; n != 0u; n--, r++) {
        pdo_step(node, load, true, &r->head);
    }
    co_tpdo *t = p->tpdo;
    for (uint32_t n = p->tpdo_count; n != 0u; n--, t++) {
        pdo_step(node, load, false, &t->head);
    }
    if (load) {
        rebuild_sets(node);
    }
}

void co_pdo_configure(co_node *node, co_time now)
{
    node->now = now;
    pdo_walk(node, true);
}

/* --- NMT ------------------------------------------------------------------------------------- */

void co_pdo_nmt_changed(co_node *node)
{
    pdo_walk(node, false);
}

/* --- reception -------------------------------------------------------------------------------- */

static bool any_length_error(const co_node *node, uint16_t code)
{
    const co_rpdo *r = node->pdo.rpdo;
    for (uint32_t n = node->pdo.rpdo_count; n != 0u; n--, r++) {
        if (r->length_error == code) {
            return true;
        }
    }
    return false;
}

/* Records this RPDO's length state (code 0: right length) and raises / clears the EMCY. */
static void rpdo_length_state(co_node *node, co_rpdo *r, uint16_t code)
{
    uint16_t old = r->length_error;
    if (old == code) {
        return;
    }
    r->length_error = code;
    if (old != 0u && !any_length_error(node, old)) {
        co_emcy_clear(node, old);
    }
    if (code != 0u) {
        (void)co_emcy_raise(node, code, CO_ERR_REG_COMMUNICATION, NULL);
    }
}

/* The check pass of rpdo_apply: the mapped objects with limits or of type BOOLEAN (r->check; the
 * mapping has checked access and length). Returns false when one is refused. */
static bool rpdo_check(co_node *node, const co_rpdo *r, const uint8_t *data)
{
    for (uint32_t j = 0; (r->check >> j) != 0u; j++) {
        if (((r->check >> j) & 1u) != 0u &&
            co_od_check_sub(node->od, r->map[j].sub, data, r->head.map_len[j]) != CO_ABORT_NONE) {
            CO_COUNT(node->pdo.stats.rpdo_refused);
            return false;
        }
        data += r->head.map_len[j];
    }
    return true;
}

/* The write pass of rpdo_apply: every mapped object in order (a dummy's bytes are skipped).
 * Returns false when a hook refuses one: the objects after it keep their values. */
static bool rpdo_write(co_node *node, co_rpdo *r, const uint8_t *data)
{
    for (uint32_t j = 0; j < r->head.count; j++) {
        if (r->map[j].sub != NULL &&
            co_od_write_checked(node, &r->map[j], r->map_hook[j], data, r->head.map_len[j],
                                CO_ORIGIN_RPDO) != CO_ABORT_NONE) {
            CO_COUNT(node->pdo.stats.rpdo_refused);
            return false;
        }
        data += r->head.map_len[j];
    }
    return true;
}

/* Writes a frame's data into the mapped objects: every object is checked before any is written
 * (a frame applies whole or not at all), then written in order. Returns false when the frame was
 * refused (counted in pdo.stats.rpdo_refused). */
static bool rpdo_apply(co_node *node, co_rpdo *r, const uint8_t *data)
{
    return rpdo_check(node, r, data) && rpdo_write(node, r, data);
}

/* Returns false when the RPDO refused the frame (too short, or its values refused). */
static bool rpdo_receive(co_node *node, co_rpdo *r, const co_frame *frame, co_time now)
{
    co_pdo *p = &node->pdo;
    bool length_emcy = !CO_PDO_FLAG(node, CO_PDO_RPDO_NO_LENGTH_EMCY);
    bool short_frame = frame->dlc < r->head.size;
    uint16_t length_code = short_frame ? EMCY_RPDO_SHORT
                           : frame->dlc > r->head.size && CO_PDO_FLAG(node, CO_PDO_RPDO_LONG_EMCY)
                               ? EMCY_RPDO_LONG
                               : 0u;
    /* without length EMCYs, a good frame still clears one raised before */
    if (length_emcy || (!short_frame && r->length_error != 0u)) {
        rpdo_length_state(node, r, length_code);
    }
    if (short_frame) {
        CO_COUNT(p->stats.rpdo_short);
        return false;
    }
    if (r->timeout_us != 0u) {
        r->armed = true;
        r->deadline = now + r->timeout_us;
        schedule(node, r->deadline);
    }
    if (r->head.type <= 240u) {
        if (!co_sync_window_open(node, now)) {
            CO_COUNT(p->stats.rpdo_late);
            return true; /* well formed, late: counted apart */
        }
        memcpy(r->buffer, frame->data, r->head.size);
        r->buffered = true;
        CO_COUNT(p->stats.rpdo_received);
        return true;
    }
    CO_COUNT(p->stats.rpdo_received);
    return rpdo_apply(node, r, frame->data);
}

/* Returns false when the TPDO does not answer remote requests. */
static bool tpdo_rtr(co_node *node, co_tpdo *t, co_time now)
{
    bool answers = t->head.type >= 252u || CO_PDO_FLAG(node, CO_PDO_TPDO_RTR_ANY_TYPE);
    if (!t->rtr_allowed || CO_PDO_FLAG(node, CO_PDO_TPDO_NO_RTR) || !answers) {
        return false;
    }
    /* 252: the data sampled at the last SYNC (the current data before the first) */
    tpdo_send(node, t, now, t->head.type == 252u && t->sent ? TPDO_KEPT : TPDO_NOW);
    return true;
}

bool co_pdo_rx(co_node *node, const co_frame *frame, co_time now)
{
    co_pdo *p = &node->pdo;
    /* An RTR is for the TPDOs (on an RPDO CAN-ID it is for its producer, not for us), a data
     * frame for the RPDOs. */
    bool rtr = (frame->flags & CO_FRAME_RTR) != 0u;
    if (!rtr && !rpdo_may_take(p, frame->id)) {
        return false; /* no RPDO of ours on this CAN-ID: most frames of the other nodes */
    }
    /* Several PDOs may share a CAN-ID (a configuration CiA 301 leaves to the integrator): the
     * frame is counted once, malformed only if none of them took it. */
    bool matched = false;
    bool taken = false;
    if (rtr) {
        for (co_tpdo *t = p->tpdo; t < p->tpdo + p->tpdo_count; t++) {
            if (t->head.active && t->head.cob_id == frame->id) {
                taken = tpdo_rtr(node, t, now) || taken;
                matched = true;
            }
        }
    } else {
        for (co_rpdo *r = p->rpdo; r < p->rpdo + p->rpdo_count; r++) {
            if (r->head.active && r->head.cob_id == frame->id) {
                taken = rpdo_receive(node, r, frame, now) || taken;
                matched = true;
            }
        }
    }
    if (matched && !taken) {
        CO_COUNT(node->stats.rx_malformed);
    }
    if (!rtr && matched && p->pending) {
        (void)co_pdo_process(node, now); /* TPDOs the written values trigger */
    }
    return matched;
}

/* --- SYNC ---------------------------------------------------------------------------------- */

static void tpdo_on_sync(co_node *node, co_tpdo *t, uint8_t counter, co_time now)
{
    if (t->head.type == 0u) {
        if (t->event) {
            tpdo_send(node, t, now, TPDO_EVENT);
        }
        return;
    }
    if (t->head.type == 252u) {
        tpdo_send(node, t, now, TPDO_SAMPLE);
        return;
    }
    /* 1-240 (the caller passes no other active type) */
    if (!t->started) {
        if (node->sync.overflow != 0u && t->sync_start != 0u) {
            if (counter != t->sync_start) {
                return;
            }
            t->sync_count = (uint8_t)(t->head.type - 1u); /* sent at this SYNC, counted from it */
        }
        t->started = true;
    }
    if (++t->sync_count >= t->head.type) {
        t->sync_count = 0u;
        tpdo_send(node, t, now, TPDO_NOW);
    }
}

void co_pdo_sync(co_node *node, uint8_t counter, co_time now)
{
    co_pdo *p = &node->pdo;
    co_rpdo *r = p->rpdo;
    for (uint32_t n = p->rpdo_count; n != 0u; n--, r++) {
        if (r->buffered) { /* only ever of an active synchronous RPDO: pdo_load */
            r->buffered = false;
            /* refused values are counted in pdo.stats.rpdo_refused; the frame itself was well
             * formed when it came */
            (void)rpdo_apply(node, r, r->buffer);
        }
    }
    co_tpdo *t = p->tpdo;
    for (uint32_t n = p->tpdo_count; n != 0u; n--, t++) {
        if (t->head.active && t->head.type <= 252u) {
            tpdo_on_sync(node, t, counter, now);
        }
    }
    if (p->pending) {
        (void)co_pdo_process(node, now); /* event-driven TPDOs the synchronous RPDOs changed */
    }
}

/* --- events and timers -------------------------------------------------------------------- */

void co_pdo_value_changed(co_node *node, uint32_t offset)
{
    co_pdo *p = &node->pdo;
    /* the caller (store, src/od.c) has looked at the watch bit: no TPDO maps most values */
    if (node->nmt_state != CO_NMT_OPERATIONAL) {
        return;
    }
    co_tpdo *t = p->tpdo;
    for (uint32_t n = p->tpdo_count; n != 0u; n--, t++) {
        if (!tpdo_watches(t) || (t->event_us != 0u && tpdo_event_driven(t->head.type) &&
                                 CO_PDO_FLAG(node, CO_PDO_EVENT_TIMER_ALONE))) {
            continue;
        }
        const uint16_t *at = t->map;
        for (uint32_t m = t->head.count; m != 0u; m--, at++) {
            if (*at == offset) {
                t->event = true;
                if (tpdo_event_driven(t->head.type)) {
                    mark_pending(node);
                }
                break;
            }
        }
    }
}

bool co_pdo_tpdo_request(co_node *node, uint16_t pdo_number)
{
    co_pdo_head *h = find_pdo(node, false, pdo_number);
    co_tpdo *t = h != NULL ? tpdo_of(h) : NULL;
    if (t == NULL || !tpdo_watches(t)) {
        return false;
    }
    if (node->nmt_state == CO_NMT_OPERATIONAL) {
        t->event = true;
        t->forced = true;
        if (tpdo_event_driven(t->head.type)) {
            mark_pending(node);
        }
    }
    return true;
}

/* The work of co_pdo_process behind its skip test. Returns the p->next it leaves. */
static co_time pdo_run(co_node *node, co_time now)
{
    co_pdo *p = &node->pdo;
    p->pending = false;
    p->next = CO_NEVER; /* lowered by whatever the work below schedules */
    co_time next = CO_NEVER;
    if (node->nmt_state != CO_NMT_OPERATIONAL) {
        return CO_NEVER;
    }
    for (uint32_t i = 0; i < p->tpdo_count; i++) {
        co_tpdo *t = &p->tpdo[i];
        if (!t->head.active || !tpdo_event_driven(t->head.type)) {
            continue;
        }
        if (t->event_deadline <= now) {
            t->event = true;
            t->forced = true;
            t->event_deadline = CO_NEVER; /* restarted by the transmission */
        }
        if (t->event) {
            if (now >= t->inhibit_end) {
                tpdo_send(node, t, now, TPDO_EVENT);
            } else {
                next = earliest(next, t->inhibit_end);
            }
        }
        next = earliest(next, t->event_deadline);
    }
    co_rpdo *r = p->rpdo;
    for (const co_rpdo *end = r + p->rpdo_count; r != end; r++) {
        if (!r->armed) {
            continue;
        }
        if (r->deadline <= now) {
            r->armed = false; /* told once; the next RPDO re-arms */
            co_svc_report(node, CO_COMM_RPDO_TIMEOUT, r->head.number);
        } else {
            next = earliest(next, r->deadline);
        }
    }
    /* A callback above may have set new deadlines or events: keep the earliest. */
    p->next = earliest(next, p->next);
    if (p->pending) {
        p->next = now;
    }
    return p->next;
}

co_time co_pdo_process(co_node *node, co_time now)
{
    co_pdo *p = &node->pdo;
    if (!p->pending && now < p->next) {
        return p->next;
    }
    co_time old = p->next;
    /* p->next as pdo_run leaves it, kept in a register (co_node_reschedule leaves it) */
    co_time next = pdo_run(node, now);
    co_node_reschedule(node, old, next);
    return next;
}
