/* Error control: heartbeat consumer, node and life guarding, error behaviour 0x1029 and the CAN
 * bus state (CiA 301 §7.2.8.3, §7.5.2.32). */
#include "canopen/errctl.h"

#include <string.h>

#include "canopen/emcy.h"
#include "canopen/node.h"
#include "dispatch.h"
#include "services.h"

#define NO_STATE 0xFFu /* co_hb_consumer.nmt_state before the first heartbeat */

/* A new error control deadline: kept in errctl.next and in the node's. */
static void schedule(co_node *node, co_time at)
{
    if (at < node->errctl.next) {
        node->errctl.next = at;
    }
    co_node_wake(node, at);
}

static bool core_emcy(const co_node *node)
{
    return !CO_NODE_OPTION(node, CO_NODE_COMM_EMCY_BY_APP);
}

/* 0x1029 sub 1 on a communication error. */
static void apply_error_behaviour(co_node *node)
{
    co_nmt_state state = node->nmt_state;
    uint32_t behaviour = co_node_od_value(node, 0x1029u, 1u, node->comm_error_behaviour);
    if (behaviour == 0u && state == CO_NMT_OPERATIONAL) {
        co_nmt_enter(node, CO_NMT_PRE_OPERATIONAL);
    } else if (behaviour == 2u && state != CO_NMT_INITIALISING) {
        co_nmt_enter(node, CO_NMT_STOPPED);
    }
}

/* A heartbeat or life guarding loss: one EMCY 0x8130 while any loss lasts. */
static void communication_lost(co_node *node, co_comm_event event, uint32_t detail)
{
    if (core_emcy(node) && !co_emcy_is_active(node, CO_EMCY_LIFE_GUARD)) {
        (void)co_emcy_raise(node, CO_EMCY_LIFE_GUARD, CO_ERR_REG_COMMUNICATION, NULL);
    }
    apply_error_behaviour(node);
    co_svc_report(node, event, detail);
}

/* A loss ended or was withdrawn (hb: 1 for a heartbeat consumer's, which leaves the count of
 * lost entries; 0 for life guarding's): EMCY 0x8130 goes with the last one. */
static void loss_ended(co_node *node, uint8_t hb)
{
    co_errctl *c = &node->errctl;
    c->hb_lost = (uint8_t)(c->hb_lost - hb);
    if (core_emcy(node) && c->hb_lost == 0u && !c->life_lost) {
        co_emcy_clear(node, CO_EMCY_LIFE_GUARD);
    }
}

/* --- heartbeat consumer -------------------------------------------------------------------- */

static void configure_consumer(co_hb_consumer *h, uint32_t value)
{
    uint32_t id = value >> 16; /* with bits 24-31, which must be 0 */
    uint16_t ms = (uint16_t)value;
    memset(h, 0, sizeof *h); /* (deadline: set when the first heartbeat makes it ACTIVE) */
    h->nmt_state = NO_STATE;
    if (id - 1u >= 127u || ms == 0u) {
        return; /* CO_HBC_OFF: a node-ID outside 1..127, or time 0 */
    }
    h->node_id = (uint8_t)id;
    h->time_us = (uint32_t)ms * 1000u;
    h->state = CO_HBC_WAITING;
}

/* The first entry monitoring producer (NULL: none). */
static co_hb_consumer *find_consumer(const co_node *node, uint8_t producer)
{
    const co_hb_consumer *end = node->errctl.hb + CO_HB_CONSUMER_MAX;
    for (const co_hb_consumer *h = node->errctl.hb; h != end; h++) {
        if (h->state != CO_HBC_OFF && h->node_id == producer) {
            return (co_hb_consumer *)(uintptr_t)h;
        }
    }
    return NULL;
}

co_hb_consumer_state co_errctl_producer_state(const co_node *node, uint8_t producer)
{
    const co_hb_consumer *h = find_consumer(node, producer);
    return h != NULL ? (co_hb_consumer_state)h->state : CO_HBC_OFF;
}

/* A monitored producer timed out or booted (rare: kept out of the frame and timer paths). */
static CO_NOINLINE void consumer_lost(co_node *node, co_hb_consumer *h)
{
    h->state = CO_HBC_LOST;
    node->errctl.hb_lost++;
    communication_lost(node, CO_COMM_HEARTBEAT_LOST, h->node_id);
}

static void heartbeat_received(co_node *node, co_hb_consumer *h, const co_frame *frame,
                               co_time now)
{
    if (frame->dlc != 1u) {
        CO_COUNT(node->stats.rx_malformed);
        return;
    }
    uint8_t state = frame->data[0];
    if (state != CO_NMT_INITIALISING && state != CO_NMT_STOPPED &&
        state != CO_NMT_OPERATIONAL && state != CO_NMT_PRE_OPERATIONAL) {
        CO_COUNT(node->stats.rx_malformed);
        return;
    }
    h->nmt_state = state;
    uint8_t was = h->state;
    if (state == CO_NMT_INITIALISING) {
        /* Boot-up: the producer was reset. Monitoring starts again with its next heartbeat. */
        if (was == CO_HBC_ACTIVE) {
            consumer_lost(node, h);
        }
        return;
    }
    h->deadline = now + h->time_us;
    schedule(node, h->deadline);
    h->state = CO_HBC_ACTIVE;
    if (was == CO_HBC_LOST) {
        loss_ended(node, 1u);
        co_svc_report(node, CO_COMM_HEARTBEAT_RESUMED, h->node_id);
    }
}

/* 0x1029: reserved values are refused. */
static co_abort behaviour_written(co_od_ref ref, const uint8_t *data, uint32_t len)
{
    if (ref.sub->subindex != 0u && len == 1u && data[0] >= 3u && data[0] <= 0x7Fu) {
        return CO_ABORT_VALUE_RANGE;
    }
    return CO_ABORT_NONE;
}

co_abort co_errctl_behaviour_written(co_node *node, void *ctx, co_od_ref ref,
                                     const uint8_t *data, uint32_t len, co_od_origin origin)
{
    (void)node;
    (void)ctx;
    (void)origin;
    return behaviour_written(ref, data, len);
}

/* 0x1016 written by SDO; 0x1029 too (the node's table has this handler in its slot). */
co_abort co_errctl_consumer_written(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                                    uint32_t len, co_od_origin origin)
{
    (void)ctx;
    (void)origin;
    co_errctl *c = &node->errctl;
    uint8_t sub = ref.sub->subindex;
    if (ref.entry->index == 0x1029u) {
        return behaviour_written(ref, data, len);
    }
    if (sub == 0u || len != 4u) {
        return CO_ABORT_NONE;
    }
    uint32_t value = co_get_le32(data);
    uint8_t id = (uint8_t)(value >> 16);
    uint16_t ms = (uint16_t)value;
    if ((value >> 24) != 0u || (ms != 0u && id > 127u)) {
        return CO_ABORT_VALUE_RANGE;
    }
    bool on = ms != 0u && id != 0u;
    if (sub > CO_HB_CONSUMER_MAX) {
        return on ? CO_ABORT_DEVICE_INCOMPATIBLE : CO_ABORT_NONE;
    }
    co_hb_consumer *h = &c->hb[sub - 1u];
    /* A producer another entry monitors, as the consumers say (co_errctl_configure leaves a
     * stored duplicate off): not every sub-entry read again. */
    co_hb_consumer *other = find_consumer(node, id);
    if (on && other != NULL && other != h) {
        return CO_ABORT_PARAM_INCOMPATIBLE;
    }
    bool was_lost = h->state == CO_HBC_LOST;
    configure_consumer(h, value);
    if (was_lost) {
        /* The loss is withdrawn with the entry; no RESUMED: the producer did not come back. */
        loss_ended(node, 1u);
    }
    return CO_ABORT_NONE;
}

/* --- node guarding and life guarding ------------------------------------------------------- */

/* The life time, 0x100C x 0x100D in µs (0: no life guarding). */
static co_time_wide life_time(const co_node *node)
{
    return (co_time_wide)((uint64_t)co_svc_od_value(node, 0x100Cu) * 1000u *
                          co_svc_od_value(node, 0x100Du));
}

/* Life guarding (re)starts from node->now (every caller's now: co_node_rx sets it before the
 * dispatch): armed while the life time is not 0. The life time is life_us, which life_load
 * computes from 0x100C and 0x100D when they are loaded (reset communication, SDO/RPDO writes):
 * a guarding request looks nothing up in the dictionary. */
static void life_arm(co_node *node)
{
    co_errctl *c = &node->errctl;
    c->guard_armed = c->life_us != 0u;
    if (c->guard_armed) {
        c->life_deadline = co_time_wide_of(node, node->now) + c->life_us;
        schedule(node, co_time_from_wide(node, c->life_deadline));
    }
}

/* 0x100C or 0x100D changed (or reset communication): a running timer restarts with the new
 * life time. */
static void life_load(co_node *node)
{
    co_errctl *c = &node->errctl;
    c->life_us = life_time(node);
    if (c->guard_armed) {
        life_arm(node);
    }
}

static void guard_request(co_node *node)
{
    co_errctl *c = &node->errctl;
    if (node->heartbeat.period_us != 0u) {
        CO_COUNT(node->stats.rx_ignored); /* the heartbeat producer is the error control protocol */
        return;
    }
    uint8_t reply = (uint8_t)((uint8_t)node->nmt_state | c->toggle);
    c->toggle ^= 0x80u;
    CO_COUNT(c->guard_requests);
    co_svc_send_state(node, reply);
    life_arm(node);
    if (c->life_lost) {
        c->life_lost = false;
        loss_ended(node, 0u);
        co_svc_report(node, CO_COMM_LIFE_GUARD_RESUMED, 0u);
    }
}

/* 0x100C / 0x100D written by SDO: the life time changes at once, a running timer restarts. */
co_abort co_errctl_guarding_written(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                                    uint32_t len, co_od_origin origin)
{
    (void)ctx;
    (void)len;
    (void)origin;
    if (ref.sub->subindex == 0u) {
        co_svc_store(node, data, ref);
        life_load(node);
    }
    return CO_ABORT_NONE;
}

/* --- the service --------------------------------------------------------------------------- */

void co_errctl_rx(co_node *node, const co_frame *frame, co_time now)
{
    if (node->nmt_state == CO_NMT_INITIALISING) {
        CO_COUNT(node->stats.rx_ignored);
        return;
    }
    uint8_t id = (uint8_t)(frame->id - 0x700u);
    bool own = id == node->node_id;
    if ((frame->flags & CO_FRAME_RTR) != 0u) {
        if (own) {
            guard_request(node);
        } else {
            CO_COUNT(node->stats.rx_ignored); /* another node's guarding */
        }
        return;
    }
    if (own) {
        CO_COUNT(node->stats.rx_malformed); /* a data frame on our own heartbeat CAN-ID */
        return;
    }
    co_hb_consumer *h = find_consumer(node, id);
    if (h == NULL) {
        CO_COUNT(node->stats.rx_ignored); /* another node's guarding or an unmonitored heartbeat */
        return;
    }
    heartbeat_received(node, h, frame, now);
}

co_time co_errctl_process(co_node *node, co_time now)
{
    co_errctl *c = &node->errctl;
    co_time next = CO_NEVER;
    for (uint32_t i = 0; i < CO_HB_CONSUMER_MAX; i++) {
        co_hb_consumer *h = &c->hb[i];
        if (h->state != CO_HBC_ACTIVE) {
            continue;
        }
        if (now >= h->deadline) {
            consumer_lost(node, h);
        } else if (h->deadline < next) {
            next = h->deadline;
        }
    }
    if (c->guard_armed) {
        if (node->heartbeat.period_us != 0u) {
            c->guard_armed = false; /* the master switched to heartbeat: guarding ended */
        } else {
            co_time at = co_time_from_wide(node, c->life_deadline);
            if (now >= at) {
                c->guard_armed = false;
                c->life_lost = true;
                communication_lost(node, CO_COMM_LIFE_GUARD_LOST, 0u);
            } else {
                next = at < next ? at : next;
            }
        }
    }
    /* A callback above may have reset communication; its state is fresh then and an early value
     * here only costs one more look. */
    c->next = next;
    return next;
}

void co_errctl_configure(co_node *node)
{
    co_errctl *c = &node->errctl;
    bool had_loss = c->hb_lost != 0u || c->life_lost;
    for (uint32_t i = 0; i < CO_HB_CONSUMER_MAX; i++) {
        co_hb_consumer *h = &c->hb[i];
        configure_consumer(h, co_node_od_value(node, 0x1016u, i + 1u, 0u));
        /* A stored duplicate (SDO writes refuse one): the first sub-entry wins. */
        if (find_consumer(node, h->node_id) != h) {
            h->state = CO_HBC_OFF;
        }
    }
    c->hb_lost = 0u;
    c->toggle = CO_NODE_OPTION(node, CO_NODE_GUARD_TOGGLE_FIRST_SET) ? 0x80u : 0x00u;
    c->guard_armed = false;
    c->life_lost = false;
    c->next = 0u; /* the next pass looks at the service again */
    life_load(node); /* disarmed: life_deadline is set when it is armed */
    co_node_recheck(node);
    if (had_loss && core_emcy(node)) {
        co_emcy_clear(node, CO_EMCY_LIFE_GUARD);
    }
}

/* --- CAN bus state ------------------------------------------------------------------------- */

void co_node_bus_state(co_node *node, co_bus_state state, uint64_t now)
{
    co_errctl *c = &node->errctl;
    co_bus_state from = (co_bus_state)c->bus;
    if (state == from || (state != CO_BUS_ERROR_ACTIVE && state != CO_BUS_ERROR_PASSIVE &&
                          state != CO_BUS_OFF)) {
        return;
    }
    node->now = co_node_time(node, now);
    c->bus = (uint8_t)state;
    bool emcy = core_emcy(node);
    if (state == CO_BUS_OFF) {
        apply_error_behaviour(node);
        co_svc_report(node, CO_COMM_BUS_OFF, 0u);
        return;
    }
    if (from == CO_BUS_OFF && emcy) {
        /* "Recovered from bus off" is an event, not a lasting condition: recorded in 0x1003 with
         * the communication bit in its frame, then cleared. */
        (void)co_emcy_raise(node, CO_EMCY_BUS_OFF_RECOVERED, CO_ERR_REG_COMMUNICATION, NULL);
    }
    if (state == CO_BUS_ERROR_PASSIVE) {
        if (emcy && !co_emcy_is_active(node, CO_EMCY_CAN_PASSIVE)) {
            (void)co_emcy_raise(node, CO_EMCY_CAN_PASSIVE, CO_ERR_REG_COMMUNICATION, NULL);
        }
        if (from == CO_BUS_OFF && emcy) {
            co_emcy_clear(node, CO_EMCY_BUS_OFF_RECOVERED);
        }
        co_svc_report(node, CO_COMM_ERROR_PASSIVE, 0u);
        return;
    }
    if (emcy) {
        co_emcy_clear(node, CO_EMCY_CAN_PASSIVE);
        if (from == CO_BUS_OFF) {
            co_emcy_clear(node, CO_EMCY_BUS_OFF_RECOVERED);
        }
    }
    co_svc_report(node, CO_COMM_BUS_RECOVERED, 0u);
}

void co_node_rx_overrun(co_node *node, uint32_t lost, uint64_t now)
{
    co_errctl *c = &node->errctl;
    node->now = co_node_time(node, now);
    c->rx_lost = lost > UINT32_MAX - c->rx_lost ? UINT32_MAX : c->rx_lost + lost;
    if (core_emcy(node) && !co_emcy_is_active(node, CO_EMCY_CAN_OVERRUN)) {
        (void)co_emcy_raise(node, CO_EMCY_CAN_OVERRUN, CO_ERR_REG_COMMUNICATION, NULL);
        co_emcy_clear(node, CO_EMCY_CAN_OVERRUN);
    }
    co_svc_report(node, CO_COMM_RX_OVERRUN, lost);
}
