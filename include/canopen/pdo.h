/* Process data objects (CiA 301 §7.2.2): RPDOs 0x1400-0x15FF / 0x1600-0x17FF and TPDOs
 * 0x1800-0x19FF / 0x1A00-0x1BFF, as many as the dictionary defines (numbers may be sparse, e.g.
 * PDO 1, 2, 3 and 21), up to CO_MAX_RPDO / CO_MAX_TPDO of each, 8 mapped objects and 8 bytes each.
 *
 * What the bus sees:
 * - PDOs are received and sent only in OPERATIONAL. A PDO is in use when its COB-ID has bit 31
 *   clear, bits 11-29 clear, a CAN-ID outside the ranges CiA 301 §7.3.5 reserves, and a valid
 *   mapping with at least one object.
 * - RPDO, transmission type 254/255: written at once. Types 0-240: the data is kept and written at
 *   the next SYNC; one that arrives outside the synchronous window (0x1007) is discarded (counted
 *   in pdo.stats.rpdo_late). Types 241-253 are refused.
 *   Every mapped value goes through co_od_write_ref(..., CO_ORIGIN_RPDO), so limits and hooks
 *   (the CiA 402 controlword) apply, in mapping order. All values of a frame are checked first:
 *   if one is outside its limits nothing is written (pdo.stats.rpdo_refused, and
 *   stats.rx_malformed for an event-driven RPDO; a synchronous one's frame was well formed when
 *   it came). A hook that refuses a value stops the frame there (counted the same). A frame
 *   shorter than the mapping is dropped (pdo.stats.rpdo_short, stats.rx_malformed) and
 *   raises EMCY 0x8210 (cleared by the next frame of the right length); a longer one uses the
 *   mapped bytes. An RTR on an RPDO CAN-ID is ignored.
 * - RPDO event timer (sub 5, ms): after the first RPDO, if no other arrives within it the
 *   application hears events.comm(CO_COMM_RPDO_TIMEOUT, pdo_number) once; the next RPDO re-arms.
 * - TPDO types: 0 = at the SYNC after an event (a mapped value changed); 1-240 = every n-th SYNC
 *   (the first at the n-th SYNC after entering OPERATIONAL, or, with a SYNC counter (0x1019 != 0)
 *   and a SYNC start value (sub 6) != 0, at the SYNC whose counter equals the start value);
 *   252 = sampled at each SYNC, sent on RTR; 253 = sampled and sent on RTR; 254/255 = on an event:
 *   a mapped value changed, the event timer (sub 5, ms) expired, or co_pdo_tpdo_request(). 241-251
 *   are refused. Events of 254/255 respect the inhibit time (sub 3, 100 µs by default; 254 only
 *   with CO_PDO_INHIBIT_254_ONLY): an event inside it is sent, with the latest data, when it
 *   ends. A change only counts if the frame
 *   differs from the last one sent; the event timer and requests always send. Every transmission
 *   of a 254/255 TPDO restarts its event timer and inhibit time.
 * - "A mapped value changed": every successful co_od_write_ref (SDO, RPDO or the application)
 *   tells the PDO layer. After an SDO or RPDO frame the TPDO goes out before co_node_rx returns;
 *   after an application write, at the next co_node_process(). A value written straight through
 *   co_od_value_ptr() is not seen (the TPDO still goes out on its timer, or on request).
 * - With CO_PDO_TPDO_SEND_ON_START (as CANopenNode does; CiA 301 does not ask for it), entering
 *   OPERATIONAL sends every TPDO of type 254/255 once, and every TPDO of type 0 at the first SYNC.
 *   Without it the first transmission waits for the first event.
 * - RTR on a TPDO CAN-ID (COB-ID bit 30 clear): 252 sends the data sampled at the last SYNC (the
 *   current data before the first SYNC), 253/254/255 send the current data; other types ignore
 *   it (unless CO_PDO_TPDO_RTR_ANY_TYPE). With bit 30 set, or CO_PDO_TPDO_NO_RTR, the RTR is
 *   dropped and counted (stats.rx_malformed).
 *
 * Writes to the PDO objects (SDO) go through the core's handler (co_pdo_param_written), which
 * validates them, then reloads the PDO from its objects as co_pdo_configure does: the mapping
 * resolved into the mapped values (and, for RPDOs, the handler of each mapped object and whether
 * it has limits), so frames need no dictionary lookups. A new type or mapping, or the PDO made
 * valid or invalid, restarts it; other writes keep its state (a new event timer runs from the
 * write, a new RPDO timeout from the next RPDO). The checks:
 * - COB-ID (sub 1): bit 29 or bits 11-28 set, a reserved CAN-ID, enabling a PDO whose mapping is
 *   empty, or a new CAN-ID while the PDO is valid (except a write that sets bit 31) -> value_abort.
 *   Enabling a PDO beyond CO_MAX_RPDO / CO_MAX_TPDO -> 0x06040047. Bit 30 of an RPDO is kept but
 *   means nothing (older masters set it).
 * - Transmission type (sub 2): RPDO 241-253, TPDO 241-251 -> value_abort.
 * - TPDO inhibit time (sub 3; not with CO_PDO_INHIBIT_WHILE_VALID) and SYNC start value (sub 6)
 *   while the PDO is valid -> busy_abort;
 *   a start value above 240 -> value_abort.
 * - Mapping (CiA 301 procedure: set COB-ID bit 31, sub 0 = 0, write the entries, sub 0 = n, clear
 *   bit 31): an entry or sub 0 written while the PDO is valid (unless CO_PDO_MAP_WHILE_VALID), or
 *   an entry written while sub 0 != 0 -> busy_abort; an entry naming an absent object, a DOMAIN,
 *   an object not mappable in this direction, a length that is not whole bytes or does not match
 *   the object, or a dummy (0x0001-0x0007) the configuration does not allow -> 0x06040041; sub 0
 *   above 8 or above the entries the object has, or a total above 64 bits -> 0x06040042.
 *   An entry of 0 is always accepted (an unused slot).
 * value_abort and busy_abort are 0x06040043 unless co_pdo_config says otherwise.
 * Writes by the application (CO_ORIGIN_APP) skip the handler: call co_pdo_configure() afterwards. */
#ifndef CANOPEN_PDO_H
#define CANOPEN_PDO_H

#include <stdbool.h>
#include <stdint.h>

#include "canopen/abort.h"
#include "canopen/config.h"
#include "canopen/frame.h"
#include "canopen/nmt.h"
#include "canopen/od.h"
#include "canopen/time_base.h"

#ifdef __cplusplus
extern "C" {
#endif

struct co_node;

#define CO_PDO_MAX_MAPPED 8u /* mapped objects per PDO */

#if CO_MAX_RPDO > 512 || CO_MAX_TPDO > 512
#error "CiA 301 has at most 512 RPDOs and 512 TPDOs"
#endif
#define CO_PDO_MAX_BYTES 8u  /* a classic CAN frame */

/* co_pdo_config.flags: behaviours where drives differ. */
#define CO_PDO_TPDO_SEND_ON_START    0x0001u /* TPDOs 0/254/255 sent once on entering OPERATIONAL */
#define CO_PDO_TPDO_RTR_ANY_TYPE     0x0002u /* RTR answered for types 0-240 too (current data) */
#define CO_PDO_TPDO_NO_RTR           0x0004u /* RTRs on TPDO CAN-IDs are never answered */
#define CO_PDO_MAP_WHILE_VALID       0x0008u /* mapping writable while the COB-ID is valid */
#define CO_PDO_RPDO_NO_LENGTH_EMCY   0x0010u /* short RPDOs are dropped without EMCY 0x8210 */
#define CO_PDO_RPDO_LONG_EMCY        0x0020u /* longer RPDOs raise EMCY 0x8220 (still applied) */
#define CO_PDO_INHIBIT_MIN_IF_SET    0x0040u /* tpdo_inhibit_min_us only floors a non-zero sub 3 */
#define CO_PDO_SYNC_CONSUMER_ONLY    0x0080u /* never a SYNC producer, even with 0x1006 present */
#define CO_PDO_TPDO_DLC_8            0x0100u /* TPDOs always go out with DLC 8, unmapped bytes 0 */
#define CO_PDO_INHIBIT_WHILE_VALID   0x0200u /* TPDO sub 3 (inhibit time) writable while the PDO is
                                              * valid; it applies from the next transmission */
#define CO_PDO_EVENT_TIMER_ALONE     0x0400u /* a TPDO 254/255 with a non-zero event timer is sent
                                              * by it alone: no change-driven sends and no
                                              * inhibit time (the inhibit time paces changes) */
#define CO_PDO_INHIBIT_254_ONLY      0x0800u /* the inhibit time paces type 254 only: a 255
                                              * TPDO is sent on each event without it */

/* Per-node PDO options (co_node_config.pdo). All zero gives CiA 301 behaviour. */
typedef struct co_pdo_config {
    uint32_t tpdo_inhibit_unit_us; /* unit of TPDO sub 3; 0: 100 µs (CiA 301) */
    uint32_t tpdo_inhibit_min_us;  /* floor of the effective inhibit time (see the flag above) */
    uint32_t tpdo_event_min_us;    /* floor of a non-zero TPDO event timer */
    co_abort value_abort;          /* invalid COB-ID / type / value; 0: 0x06040043 */
    co_abort busy_abort;           /* write the PDO's state forbids; 0: 0x06040043 */
    uint16_t flags;                /* CO_PDO_* */
    uint8_t rpdo_dummy_mask;       /* bit n set: dummy object n (1..7) may be mapped into RPDOs,
                                    * as the EDS [DummyUsage] Dummy000n=1 says */
} co_pdo_config;

/* What RPDOs and TPDOs have in common, the first member of both: code that handles either
 * direction (mapping, communication parameters, lookup by number or CAN-ID) takes a co_pdo_head. */
typedef struct co_pdo_head {
    bool cob_valid;                     /* sub 1 bit 31 clear, a usable CAN-ID */
    bool active;                        /* in use (see above) */
    uint8_t count;                      /* mapped objects in use */
    uint8_t size;                       /* mapped bytes */
    uint8_t type;                       /* transmission type */
    uint16_t number;                    /* 1-based PDO number (0x1400/0x1800 + number - 1) */
    uint16_t cob_id;                    /* CAN-ID (bits 0-10 of sub 1) */
    uint8_t map_len[CO_PDO_MAX_MAPPED]; /* bytes of each mapped object */
} co_pdo_head;

typedef struct co_rpdo {
    co_pdo_head head;
    bool buffered;                    /* buffer holds data for the next SYNC (active, type 0-240) */
    bool armed;                       /* timeout monitoring running */
    uint8_t check;                    /* bit j: object j has limits (or is BOOLEAN): checked */
    uint16_t length_error;            /* EMCY code raised for this RPDO (0x8210 / 0x8220), or 0 */
    uint8_t map_hook[CO_PDO_MAX_MAPPED]; /* who handles each mapped object's writes (see
                                          * co_node_hook_slot), resolved with the mapping */
    uint8_t buffer[CO_PDO_MAX_BYTES]; /* synchronous RPDO waiting for the SYNC */
    co_time deadline;                 /* event timer (timeout) deadline while armed */
    uint32_t timeout_us;              /* sub 5 */
    co_od_ref map[CO_PDO_MAX_MAPPED]; /* mapped sub-entries; sub NULL: dummy bytes, skipped */
} co_rpdo;

typedef struct co_tpdo {
    co_pdo_head head;
    bool event;                       /* a transmission is wanted */
    bool forced;                      /* ... even if the data did not change */
    bool sent;                        /* data holds a frame sent (or sampled) */
    bool started;                     /* cyclic: the SYNC start value was reached */
    bool rtr_allowed;                 /* sub 1 bit 30 clear */
    uint8_t sync_count;               /* SYNCs since the last cyclic transmission */
    uint8_t sync_start;               /* sub 6 */
    uint16_t map[CO_PDO_MAX_MAPPED];  /* offsets of the mapped values in the node's value block */
    co_frame frame;                   /* last frame sent (type 252: the SYNC sample) */
    co_time inhibit_end;              /* earliest time of the next event-driven transmission */
    co_time event_deadline;           /* event timer expiry while the timer runs */
    uint32_t inhibit_us;              /* effective inhibit time */
    uint32_t event_us;                /* effective event timer */
} co_tpdo;

typedef struct co_pdo_stats {
    uint32_t rpdo_received; /* RPDOs written, or kept for the SYNC */
    uint32_t rpdo_short;    /* dropped: shorter than the mapping */
    uint32_t rpdo_refused;  /* dropped: a value outside its limits or refused by its hook */
    uint32_t rpdo_late;     /* synchronous RPDOs discarded outside the window */
    uint32_t tpdo_sent;     /* TPDOs handed to co_node_send */
} co_pdo_stats;

/* A set of hashed bits (CO_CONFIG_PDO_BITS): the fast paths that tell at once that no PDO maps a
 * value (watch) or takes a CAN-ID (rpdo_filter). With CO_CONFIG_PDO_BITS 0 there are none: every
 * stored value and every frame is looked up in the PDOs. */
#if CO_CONFIG_PDO_BITS == 0
#elif CO_CONFIG_PDO_BITS == 32
typedef uint32_t co_pdo_bits;
#elif CO_CONFIG_PDO_BITS == 64
typedef uint64_t co_pdo_bits;
#else
#error "CO_CONFIG_PDO_BITS is 0, 32 or 64"
#endif
#if CO_CONFIG_PDO_BITS != 0
#define CO_PDO_BIT(hash) ((co_pdo_bits)1u << ((hash) & (CO_CONFIG_PDO_BITS - 1u)))
#endif

typedef struct co_pdo {
    co_rpdo rpdo[CO_MAX_RPDO];
    co_tpdo tpdo[CO_MAX_TPDO];
    co_pdo_config cfg;
    co_pdo_stats stats;
#if CO_CONFIG_PDO_BITS != 0
    co_pdo_bits watch;  /* co_pdo_watch_bit of every value an event-driven TPDO maps */
    co_pdo_bits rpdo_filter; /* a bit per CAN-ID of an active RPDO (a hash of it): a frame whose
                           * bit is clear is no RPDO of ours, without a look at the slots */
#endif
    co_time next;       /* earliest PDO timer deadline (may be early, never late) */
    uint16_t rpdo_count; /* slots in use, in PDO number order (CiA 301: up to 512 of each) */
    uint16_t tpdo_count;
    bool pending;        /* an event-driven TPDO may be due now */
} co_pdo;

/* Re-reads every PDO's communication and mapping parameters and resolves the mappings (reset
 * communication; or after the application wrote PDO objects with CO_ORIGIN_APP). A stored
 * configuration that is not valid leaves that PDO unused. */
void co_pdo_configure(struct co_node *node, co_time now);

/* Handles a frame in OPERATIONAL. Returns true if its CAN-ID is one of this node's PDOs (the frame
 * was used or dropped and counted), false to let the caller count it as ignored. */
bool co_pdo_rx(struct co_node *node, const co_frame *frame, co_time now);

/* The core's handler of SDO/RPDO writes to 0x1400-0x1BFF (checks, then applies the new value to
 * the PDO's state), with the co_od_hook write signature: the node calls it unless an application
 * hook covers the object. Hooks do not chain: a drive that adds its own hook on some of these
 * objects (e.g. a manual's stricter rules) calls this one from it once its own checks pass, and
 * returns what it returns. A write it accepts is in the dictionary when it returns (the PDO's
 * state is loaded from its objects); the node then stores the same value. */
co_abort co_pdo_param_written(struct co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                              uint32_t len, co_od_origin origin);

/* The application asks TPDO pdo_number (1-based) to be sent: at once for 254/255 (after the
 * inhibit time), at the next SYNC for type 0. False if there is no such TPDO in use. */
bool co_pdo_tpdo_request(struct co_node *node, uint16_t pdo_number);

#ifdef __cplusplus
}
#endif

#endif
