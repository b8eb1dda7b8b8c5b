/* The services' entry points: what the node (src/node.c) calls in each service of the core - set
 * up at a reset, a frame for it (rx), its timers (process), an NMT state change, the news of
 * hooks and values. An application calls none of these (it calls co_node_rx, co_node_process
 * and the public functions of include/canopen/). The services' write handlers (co_*_written)
 * stay public: an application hook over their objects calls them to chain. */
#ifndef CANOPEN_DISPATCH_H
#define CANOPEN_DISPATCH_H

#include "canopen/node.h"

/* --- emcy (include/canopen/emcy.h has its types) ---------------------------- */

/* Resolves 0x1001/0x1003 (co_node_init, once the value block holds the defaults). */
void co_emcy_init(struct co_node *node);

/* Re-reads 0x1014/0x1015, drops queued EMCYs, restarts the history from 0x1003's values and
 * recomputes 0x1001 (reset communication). */
void co_emcy_configure(struct co_node *node);

/* Sends queued EMCYs whose inhibit time has passed. Returns when the next one is due
 * (CO_NEVER when none is queued). */
co_time co_emcy_process(struct co_node *node, co_time now);

/* --- errctl (include/canopen/errctl.h has its types) ------------------------ */

/* Called by co_node_init, which has cleared the state: nothing to do until co_errctl_configure. */
static inline void co_errctl_init(struct co_node *node)
{
    (void)node; /* inline: co_node_init needs no call for it */
}

/* Handles a frame on 0x700-0x77F: guarding request, heartbeat or boot-up of a producer. */
void co_errctl_rx(struct co_node *node, const co_frame *frame, co_time now);

/* Runs the heartbeat consumer and life guarding timers. Returns the next deadline (CO_NEVER
 * if none); the node calls it only once errctl.next has passed. */
co_time co_errctl_process(struct co_node *node, co_time now);

/* --- heartbeat (include/canopen/heartbeat.h has its types) ------------------ */

/* Re-reads 0x1017 and restarts the period from now. Called on reset communication and when 0x1017
 * is written. */
void co_heartbeat_producer_configure(struct co_node *node, co_time now);

/* Sends a heartbeat when due. Returns the time of the next one (CO_NEVER when off). */
co_time co_heartbeat_producer_process(struct co_node *node, co_time now);

/* --- nmt (include/canopen/nmt.h has its types) ------------------------------ */

/* Handles a frame on COB-ID 0. Frames that are not 2 bytes, RTR frames and unknown commands are
 * dropped and counted; commands for other nodes are ignored. */
void co_nmt_rx(struct co_node *node, const co_frame *frame, co_time now);

/* --- pdo (include/canopen/pdo.h has its types) ------------------------------ */

/* Sets the PDO layer up from cfg: finds the dictionary's PDOs. Called once by co_node_init, on
 * the node it has cleared, with a cfg (not NULL) it has checked (values are read later, by
 * co_pdo_configure). */
void co_pdo_init(struct co_node *node, const co_pdo_config *cfg);

/* A SYNC in OPERATIONAL (counter 0 without one): writes the synchronous RPDOs, sends the
 * synchronous TPDOs. */
void co_pdo_sync(struct co_node *node, uint8_t counter, co_time now);

/* Sends the event-driven TPDOs that are due, runs the event timers and RPDO timeouts. Returns the
 * next deadline (CO_NEVER if none). Cheap when nothing is due. */
co_time co_pdo_process(struct co_node *node, co_time now);

/* Called by co_node_add_hook: the RPDOs look up again who handles each mapped object. */
void co_pdo_hooks_changed(struct co_node *node);

/* Called by co_od_write_ref after the value at offset (co_od_value_offset) changed, if
 * co_pdo_may_watch says a TPDO may map it: marks the TPDOs that map it. */
void co_pdo_value_changed(struct co_node *node, uint32_t offset);

/* The NMT state changed (node->nmt_state is the new one; co_nmt_enter calls this only on a
 * change): entering OPERATIONAL starts the PDOs, leaving it stops them (buffered RPDOs and
 * pending TPDOs are dropped). */
void co_pdo_nmt_changed(struct co_node *node);

/* Whether an event-driven TPDO may map the value at offset of the value block (false: none
 * does; true: co_pdo_value_changed looks). */
static inline bool co_pdo_may_watch(const struct co_node *node, uint32_t offset)
{
#if CO_CONFIG_PDO_BITS != 0
    return (node->pdo.watch & CO_PDO_BIT(offset)) != 0u;
#else
    (void)node;
    (void)offset;
    return true;
#endif
}

/* --- sync (include/canopen/sync.h has its types) ---------------------------- */

/* Called once by co_node_init, which has cleared the state: nothing to do until
 * co_sync_configure. */
static inline void co_sync_init(struct co_node *node)
{
    (void)node; /* inline: co_node_init needs no call for it */
}

/* Handles a frame on the SYNC CAN-ID (the caller checked the id and the NMT state). */
void co_sync_rx(struct co_node *node, const co_frame *frame, co_time now);

/* Producer: sends the SYNC when due. Returns the time of the next one (CO_NEVER when the node
 * does not produce SYNC or is not in PRE-OPERATIONAL / OPERATIONAL). */
co_time co_sync_process(struct co_node *node, co_time now);

/* The NMT state changed: the producer stops in STOPPED, and restarts its period on leaving it. */
void co_sync_nmt_changed(struct co_node *node, co_nmt_state from, co_nmt_state to);

/* --- sdo_server (include/canopen/sdo_server.h has its types) ---------------- */

/* Clears the server to idle without sending anything (on reset communication, and when NMT
 * enters STOPPED). Keeps timeout_us (0 becomes CO_SDO_TIMEOUT_US). */
void co_sdo_server_init(struct co_node *node);

/* Handles a frame received on the server's request COB-ID at time now, and sends the responses
 * with co_node_send on node->sdo_tx_cob. A frame that is not 8 bytes long, or an RTR frame, is
 * dropped without an answer and counted in node->stats.rx_malformed. Event-driven TPDOs mapping
 * a value the request wrote are sent before it returns. */
void co_sdo_server_rx(struct co_node *node, const co_frame *frame, co_time now);

/* Runs the transfer timeout (abort 0x05040000 once now reaches the deadline) and sends block
 * upload segments the transmit queue had no room for. Returns the time it must be called again
 * (CO_NEVER: nothing pending). */
co_time co_sdo_server_process(struct co_node *node, co_time now);

#endif
