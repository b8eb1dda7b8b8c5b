/* NMT slave: the state machine of CiA 301 §7.3.2 and the two reset sequences. */
#include "canopen/nmt.h"

#include "canopen/node.h"
#include "dispatch.h"
#include "services.h"

const char *co_nmt_state_name(co_nmt_state state)
{
    switch (state) {
    case CO_NMT_INITIALISING: return "INITIALISING";
    case CO_NMT_STOPPED: return "STOPPED";
    case CO_NMT_OPERATIONAL: return "OPERATIONAL";
    case CO_NMT_PRE_OPERATIONAL: return "PRE-OPERATIONAL";
    default: return "UNKNOWN";
    }
}

void co_nmt_enter(co_node *node, co_nmt_state state)
{
    co_nmt_state from = node->nmt_state;
    if (from == state) {
        return;
    }
    node->nmt_state = state;
    co_node_recheck(node); /* every service looks at the new state in the next pass */
    if (state == CO_NMT_STOPPED) {
        /* SDO is not available in STOPPED: a transfer in progress ends without a word, as the
         * master can no longer expect an answer either. */
        co_sdo_server_init(node);
    }
    /* PDOs run only in OPERATIONAL (the TPDOs due on entering it go out at the next
     * co_node_process, after the application has heard of the change); the SYNC producer stops
     * in STOPPED. */
    co_sync_nmt_changed(node, from, state);
    co_pdo_nmt_changed(node);
    if (node->events.nmt_changed != NULL) {
        node->events.nmt_changed(node, node->events.ctx, from, state);
    }
}

/* A COB-ID of the SDO server, 0x1200 sub (1: client to server, 2: server to client): without
 * 0x1200 (or with an invalid entry) the default SDO server of CiA 301 answers, on dflt. */
static uint16_t sdo_cob_id(const co_node *node, uint32_t sub, uint32_t dflt)
{
    uint32_t v = co_node_od_value(node, 0x1200u, sub, 0u);
    return (uint16_t)((v == 0u || (v & 0x80000000u) != 0u) ? dflt : (v & 0x7FFu));
}

/* Reads the communication parameters the node itself uses after a communication reset. */
static void apply_communication_parameters(co_node *node, co_time now)
{
    node->sdo_rx_cob = sdo_cob_id(node, 1u, 0x600u + node->node_id);
    node->sdo_tx_cob = sdo_cob_id(node, 2u, 0x580u + node->node_id);
    co_sdo_server_init(node);
    co_heartbeat_producer_configure(node, now);
    co_emcy_configure(node);
    co_errctl_configure(node);
    co_sync_configure(node, now);
    co_pdo_configure(node, now);
}

/* Reset node (whole) or reset communication: the application is told, the values restored (all
 * of them for a reset node, those of 0x1000-0x1FFF for a reset communication), the communication
 * parameters applied, boot-up sent. */
static void reset(co_node *node, co_time now, bool whole)
{
    if (node->events.reset != NULL) {
        node->events.reset(node, node->events.ctx, whole);
    }
    node->nmt_state = CO_NMT_INITIALISING;
    /* The defaults, then the stored image over the block's first bytes: all values for a reset
     * node, those of 0x1000-0x1FFF for a reset communication. load() must return false without
     * writing when there is no valid image, so a failed load leaves the defaults in place. */
    const co_od *od = node->od;
    co_node_copy_values(node, node->values, NULL, whole ? CO_GROUP_ALL : CO_GROUP_COMM);
    const co_storage *st = node->storage;
    uint32_t len = whole ? od->persist_size : od->comm_persist_size;
    if (st != NULL && st->load != NULL && len != 0u) {
        (void)st->load(st->ctx, od->layout_hash, 0, node->values, len);
    }
    apply_communication_parameters(node, now);

    /* boot-up: the heartbeat frame with the state byte INITIALISING (0) */
    co_svc_send_state(node, (uint8_t)CO_NMT_INITIALISING);
    co_nmt_enter(node, CO_NMT_PRE_OPERATIONAL);
}

/* The time of an application's call, which is also the node's time from now on: what starts
 * on the call (TPDO event timers, the SYNC producer, EMCY inhibit times) counts from node->now,
 * not from the node's last rx or process call. */
static co_time api_call_time(co_node *node, uint64_t now)
{
    node->now = co_node_time(node, now);
    return node->now;
}

void co_nmt_reset_communication(co_node *node, uint64_t now)
{
    reset(node, api_call_time(node, now), false);
}

void co_nmt_reset_node(co_node *node, uint64_t now)
{
    reset(node, api_call_time(node, now), true);
}

void co_node_start(co_node *node, uint64_t now)
{
    reset(node, api_call_time(node, now), true);
}

/* Runs an NMT command; false if command is none. */
static bool command_local(co_node *node, uint8_t command, co_time now)
{
    switch (command) {
    case CO_NMT_CMD_START:
        co_nmt_enter(node, CO_NMT_OPERATIONAL);
        return true;
    case CO_NMT_CMD_STOP:
        co_nmt_enter(node, CO_NMT_STOPPED);
        return true;
    case CO_NMT_CMD_ENTER_PRE_OPERATIONAL:
        co_nmt_enter(node, CO_NMT_PRE_OPERATIONAL);
        return true;
    case CO_NMT_CMD_RESET_NODE:
    case CO_NMT_CMD_RESET_COMMUNICATION:
        reset(node, now, command == CO_NMT_CMD_RESET_NODE);
        return true;
    default:
        return false;
    }
}

void co_nmt_command_local(co_node *node, co_nmt_command command, uint64_t now)
{
    (void)command_local(node, (uint8_t)command, api_call_time(node, now));
}

/* An NMT command CiA 301 defines (only counted: command_local ignores any other; a macro, as a
 * build without the counters does not evaluate it). */
#define IS_COMMAND(c) ((uint8_t)((c) - CO_NMT_CMD_START) <= 1u || \
                       (uint8_t)((c) - CO_NMT_CMD_ENTER_PRE_OPERATIONAL) <= 2u)

void co_nmt_rx(co_node *node, const co_frame *frame, co_time now)
{
    if (frame->dlc != 2u || (frame->flags & CO_FRAME_RTR) != 0u) {
        CO_COUNT(node->stats.rx_malformed);
        return;
    }
    uint8_t command = frame->data[0];
    uint8_t target = frame->data[1];
    if ((target != 0u && target != node->node_id) || node->nmt_state == CO_NMT_INITIALISING) {
        /* a command that is none counts as malformed wherever it is sent */
        CO_COUNT(*(IS_COMMAND(command) ? &node->stats.rx_ignored : &node->stats.rx_malformed));
        return;
    }
    if (!command_local(node, command, now)) {
        CO_COUNT(node->stats.rx_malformed);
    }
}
