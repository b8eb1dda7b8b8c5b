/* Error control (CiA 301 §7.2.8.3): heartbeat consumer 0x1016, node guarding and life guarding
 * (0x100C, 0x100D), the communication error behaviour 0x1029, and the CAN bus state the port
 * reports.
 *
 * What the bus sees:
 * - Heartbeat consumer: each 0x1016 sub-entry with a node-ID (bits 16-23, 1..127) and a time
 *   (bits 0-15, ms) both non-zero monitors that producer, from its first heartbeat on (a producer
 *   that never sent one is not missed). A heartbeat is one byte on 0x700 + producer: 0x04, 0x05 or
 *   0x7F; 0x00 is a boot-up. Any other length or byte is dropped and counted (rx_malformed).
 *   No heartbeat for the consumer time after the last one -> the producer is lost, exactly when
 *   the time has passed (process returns that moment): EMCY 0x8130 with the communication bit in
 *   0x1001 (once, while any loss lasts), 0x1029 applied, events.comm(CO_COMM_HEARTBEAT_LOST,
 *   producer). Its next heartbeat -> CO_COMM_HEARTBEAT_RESUMED, and the EMCY is cleared when no
 *   other loss remains (error-reset EMCY when it was the last error).
 *   A boot-up from a producer being monitored means it was reset (CiA 301 lists "remote reset" with
 *   the heartbeat errors; CANopenNode reports it as EMCY 0x8130): it is reported like a loss, and
 *   monitoring resumes with its next heartbeat. A boot-up before the first heartbeat changes
 *   nothing. Heartbeats are consumed in PRE-OPERATIONAL, OPERATIONAL and STOPPED (error control is
 *   the one service besides NMT that STOPPED keeps).
 *   SDO writes of 0x1016 take effect at once (the entry waits for a first heartbeat again). A
 *   node-ID already monitored by another sub-entry with a non-zero time aborts 0x06040043; bits
 *   24-31 set, or a node-ID above 127 with a non-zero time, abort 0x06090030; enabling a sub-entry
 *   above CO_HB_CONSUMER_MAX aborts 0x06040047.
 * - Node guarding: a remote frame (any DLC: python-canopen sends 0, CANopenNode 1) on 0x700 +
 *   node-ID is answered with one byte, the NMT state with the toggle bit (bit 7). The toggle is 0
 *   in the first answer after reset communication (1 with CO_NODE_GUARD_TOGGLE_FIRST_SET, as the
 *   Sourcetronic manual shows) and alternates. While the heartbeat producer 0x1017 is on, guarding
 *   requests are not answered (CiA 301: one error control protocol at a time; counted rx_ignored).
 *   A data frame on 0x700 + node-ID (someone else using our CAN-ID) is dropped and counted.
 * - Life guarding: with 0x100C (ms) and 0x100D both non-zero, armed by the first guarding request.
 *   No request within 0x100C x 0x100D -> EMCY 0x8130, 0x1029 applied,
 *   events.comm(CO_COMM_LIFE_GUARD_LOST, 0); disarmed until the next request, which answers,
 *   re-arms and reports CO_COMM_LIFE_GUARD_RESUMED (EMCY cleared when no other loss remains).
 *   SDO (and RPDO) writes of 0x100C/0x100D take effect at once and restart a running life timer.
 *   The application's own writes (CO_ORIGIN_APP) skip the handler, as for every service's
 *   parameters: the life time stays the one loaded last until co_errctl_configure() (which reset
 *   communication calls, after restoring the objects' values).
 * - 0x1029 sub 1 (communication error): 0 = OPERATIONAL -> PRE-OPERATIONAL, 1 = no change, 2 =
 *   STOPPED; 0x80-0xFF (manufacturer-specific) = no change. Applied on a heartbeat loss (or remote
 *   reset), a life guarding loss and bus-off. Values 3-0x7F (reserved) written by SDO abort
 *   0x06090030. Without 0x1029 in the dictionary, co_node_config.comm_error_behaviour is used.
 * - CAN bus state (co_node_bus_state): error passive -> EMCY 0x8120 (active until error active
 *   again), CO_COMM_ERROR_PASSIVE; bus-off -> 0x1029 applied, CO_COMM_BUS_OFF (no EMCY can be
 *   sent while bus-off); leaving bus-off -> EMCY 0x8140 "recovered from bus off" (recorded in
 *   0x1003, then cleared at once: the error-reset EMCY follows when nothing else is active);
 *   back to error active -> CO_COMM_BUS_RECOVERED. Received frames lost by the port
 *   (co_node_rx_overrun) -> EMCY 0x8110 (recorded, then cleared at once), CO_COMM_RX_OVERRUN with
 *   the number lost.
 * - With CO_NODE_COMM_EMCY_BY_APP the core raises and clears none of these EMCYs: the application
 *   does it from its comm callback (e.g. a drive whose communication loss is a drive fault with its
 *   own manufacturer bytes, cleared by a fault reset).
 * - Reset communication re-reads 0x1016/0x100C/0x100D, forgets the producers seen and the life
 *   guarding state (toggle back to its first value) and withdraws EMCY 0x8130. The bus state is
 *   kept: it is the controller's.
 * Events are reported after the EMCY and the 0x1029 reaction, so a callback sees the new state. */
#ifndef CANOPEN_ERRCTL_H
#define CANOPEN_ERRCTL_H

#include <stdbool.h>
#include <stdint.h>

#include "canopen/abort.h"
#include "canopen/frame.h"
#include "canopen/od.h"
#include "canopen/time_base.h"

#ifdef __cplusplus
extern "C" {
#endif

struct co_node;

#ifndef CO_HB_CONSUMER_MAX
#define CO_HB_CONSUMER_MAX 8u /* 0x1016 sub-entries (producers) one node can monitor */
#endif

/* CAN controller states a port reports (CiA 301 / ISO 11898 fault confinement). */
typedef enum co_bus_state {
    CO_BUS_ERROR_ACTIVE = 0,
    CO_BUS_ERROR_PASSIVE = 1,
    CO_BUS_OFF = 2
} co_bus_state;

/* Monitoring state of one 0x1016 entry. */
typedef enum co_hb_consumer_state {
    CO_HBC_OFF = 0,     /* sub-entry unused (node-ID or time 0) */
    CO_HBC_WAITING = 1, /* configured, no heartbeat seen yet */
    CO_HBC_ACTIVE = 2,  /* heartbeats arriving */
    CO_HBC_LOST = 3     /* timed out (or the producer booted): waiting for its next heartbeat */
} co_hb_consumer_state;

typedef struct co_hb_consumer {
    co_time deadline;   /* while ACTIVE: when the producer is lost */
    uint32_t time_us;
    uint8_t node_id;
    uint8_t state;      /* co_hb_consumer_state */
    uint8_t nmt_state;  /* last state the producer reported (0xFF: none yet) */
} co_hb_consumer;

typedef struct co_errctl {
    /* the scalars first (short offsets on a microcontroller), the consumers last */
    uint8_t hb_lost;        /* entries in CO_HBC_LOST */
    uint8_t toggle;         /* toggle bit of the next guarding answer (0 or 0x80) */
    bool guard_armed;       /* life guarding running */
    bool life_lost;         /* life guarding timed out, no request since */
    uint8_t bus;            /* co_bus_state */
    co_time next;           /* no deadline of this service is earlier */
    uint32_t guard_requests;/* guarding requests answered */
    uint32_t rx_lost;       /* frames the port reported lost (co_node_rx_overrun) */
    co_time_wide life_us;   /* 0x100C x 0x100D in µs; 0: no life guarding */
    co_time_wide life_deadline; /* while armed */
    co_hb_consumer hb[CO_HB_CONSUMER_MAX]; /* hb[i] is 0x1016 sub i + 1 */
} co_errctl;

/* The port reports a change of the CAN controller state (see above). Repeating the current state
 * does nothing; a value outside co_bus_state is ignored. now: the time of the report. */
void co_node_bus_state(struct co_node *node, co_bus_state state, uint64_t now);

/* The port lost lost received frames (its receive queue overflowed). */
void co_node_rx_overrun(struct co_node *node, uint32_t lost, uint64_t now);

/* Monitoring state of the producer with this node-ID (CO_HBC_OFF when it is not in 0x1016). */
co_hb_consumer_state co_errctl_producer_state(const struct co_node *node, uint8_t producer);

/* --- called by the node ------------------------------------------------------------------- */

/* The core's handlers of SDO/RPDO writes to 0x100C/0x100D (guard time, life time factor), 0x1016
 * (consumer heartbeat time) and 0x1029 (error behaviour), with the co_od_hook write signature:
 * the node calls them for these objects unless an application hook covers them (hooks do not
 * chain: such a hook calls the core's handler once its own checks pass). */
co_abort co_errctl_guarding_written(struct co_node *node, void *ctx, co_od_ref ref,
                                    const uint8_t *data, uint32_t len, co_od_origin origin);
co_abort co_errctl_consumer_written(struct co_node *node, void *ctx, co_od_ref ref,
                                    const uint8_t *data, uint32_t len, co_od_origin origin);
co_abort co_errctl_behaviour_written(struct co_node *node, void *ctx, co_od_ref ref,
                                     const uint8_t *data, uint32_t len, co_od_origin origin);

/* Re-reads 0x1016/0x100C/0x100D and restarts monitoring (reset communication). */
void co_errctl_configure(struct co_node *node);

#ifdef __cplusplus
}
#endif

#endif
