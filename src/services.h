/* What the core's services share and an application does not call: the build's behaviour
 * switches, statistics, NMT state helpers, and the helpers every service uses to store its
 * parameters, report events and send its frames (src/service.c). */
#ifndef CANOPEN_SERVICES_H
#define CANOPEN_SERVICES_H

#include "canopen/node.h"
#include "compiler.h"
#include "od_internal.h"
#include "schedule.h"

/* A CO_NODE_* option / CO_PDO_* flag in effect: constant false when the build leaves it out
 * (CO_CONFIG_NODE_OPTIONS / CO_CONFIG_PDO_FLAGS, include/canopen/config.h). */
#define CO_NODE_OPTION(node, opt) \
    ((CO_CONFIG_NODE_OPTIONS & (opt)) != 0u && ((node)->options & (opt)) != 0u)
#define CO_PDO_FLAG(node, flag) \
    ((CO_CONFIG_PDO_FLAGS & (flag)) != 0u && ((node)->pdo.cfg.flags & (flag)) != 0u)

/* The abort for an invalid PDO or SYNC parameter value / a write the PDO's state forbids
 * (co_pdo_config.value_abort / busy_abort, 0x06040043 by default). */
static inline co_abort co_pdo_value_abort(const co_node *node)
{
#if CO_CONFIG_PDO_TUNING
    if (node->pdo.cfg.value_abort != 0u) {
        return node->pdo.cfg.value_abort;
    }
#else
    (void)node;
#endif
    return CO_ABORT_PARAM_INCOMPATIBLE;
}
static inline co_abort co_pdo_busy_abort(const co_node *node)
{
#if CO_CONFIG_PDO_TUNING
    if (node->pdo.cfg.busy_abort != 0u) {
        return node->pdo.cfg.busy_abort;
    }
#else
    (void)node;
#endif
    return CO_ABORT_PARAM_INCOMPATIBLE;
}

/* Counts an event in one of the statistics counters (co_node_stats, co_pdo_stats, the services'
 * own); nothing when the build leaves the counters out (CO_CONFIG_STATS 0: they stay 0). */
#if CO_CONFIG_STATS
#define CO_COUNT(counter) ((void)(counter)++)
#else
#define CO_COUNT(counter) ((void)sizeof(counter)) /* not evaluated */
#endif

/* CAN-IDs CiA 301 §7.3.5 keeps out of every configurable communication object (NMT, SYNC/EMCY
 * of other nodes, TIME, SDO, NMT error control, LSS); the default 0x080 is not one of them. */
bool co_can_id_restricted(uint16_t id);

/* PRE-OPERATIONAL or OPERATIONAL, where SDO, SYNC, EMCY and the PDOs' frames flow: of the four
 * states only these two have bit 0 set. */
typedef char co_nmt_bit0_check[(CO_NMT_OPERATIONAL & CO_NMT_PRE_OPERATIONAL & 1) != 0 &&
                               ((CO_NMT_INITIALISING | CO_NMT_STOPPED) & 1) == 0 ? 1 : -1];
static inline bool co_nmt_communicating(co_nmt_state state)
{
    return ((uint32_t)state & 1u) != 0u;
}

/* Changes the NMT state and tells the application. */
void co_nmt_enter(co_node *node, co_nmt_state state);

/* A core write handler stores the value it accepted itself (the same bytes co_od_write_checked
 * stores after it), so that its service loads its state from the dictionary in one place, at
 * reset communication and after a write alike. The services' parameters are
 * numeric: check_value has made the written length the sub-entry's size. */
void co_svc_store(co_node *node, const uint8_t *data, co_od_ref ref);

/* co_node_od_value(node, index, 0, 0): a service's parameter at sub 0, 0 without it
 *. */
uint32_t co_svc_od_value(const co_node *node, uint16_t index);

/* Tells the application a communication event (events.comm), if it listens. */
void co_svc_report(co_node *node, co_comm_event event, uint32_t detail);

/* Sends a data frame of dlc (0 or 1) bytes, byte the first, the others 0: a heartbeat, a
 * guarding answer, a SYNC. */
void co_svc_send(co_node *node, uint16_t id, uint8_t dlc, uint8_t byte);

/* Sends one byte on the node's error control CAN-ID 0x700 + node-ID: a heartbeat, a guarding
 * answer, the boot-up message. */
void co_svc_send_state(co_node *node, uint8_t byte);

#endif
