/* EMCY producer (CiA 301 §7.2.7), error register 0x1001 and pre-defined error field 0x1003.
 *
 * What the bus sees:
 * - An EMCY is 8 bytes on the CAN-ID of 0x1014 (0x80 + node-ID when the dictionary has no 0x1014):
 *   error code (little-endian), the error register 0x1001, 5 manufacturer-specific bytes.
 * - EMCY is sent in PRE-OPERATIONAL and OPERATIONAL only (CiA 301 §7.3.2.2). An EMCY raised in
 *   STOPPED (0x1001 and 0x1003 are updated at once) is held, with the frames the inhibit time
 *   was holding back, in the same queue of CO_EMCY_QUEUE_LEN frames (one that finds it full is
 *   lost and counted in emcy.lost), and sent, in order and after the inhibit time, once the node
 *   leaves STOPPED for PRE-OPERATIONAL or OPERATIONAL - as CANopenNode keeps its EMCY FIFO - so a
 *   master that only listens for EMCYs still learns of the fault. Only what is still true goes
 *   out: a held error EMCY only if its error is still active, a held error-reset EMCY only if
 *   the last EMCY sent told of an active error; the others are counted in emcy.suppressed.
 *   Reset communication or reset node drops held frames (the errors still active stay active
 *   and are in 0x1001). A build with CO_CONFIG_EMCY_HOLD 0 (include/canopen/config.h) holds
 *   nothing: an EMCY raised in STOPPED is treated as one raised in INITIALISING (below), and the
 *   frames the inhibit time was holding back are dropped on entering STOPPED. An EMCY raised in INITIALISING or while 0x1014 bit 31 is set updates
 *   0x1001 and 0x1003 but is not sent, nor sent later (emcy.suppressed).
 * - Inhibit time 0x1015 (100 µs units): an EMCY that would follow the previous one sooner waits in
 *   a queue of CO_EMCY_QUEUE_LEN frames and goes out, in order, when the time ends (co_node_process
 *   returns that moment). A frame that finds the queue full is lost and counted (emcy.lost).
 * - An error already active is not a new error: raising it again sends its EMCY again but adds no
 *   0x1003 entry. When the last active error is cleared the error-reset EMCY (code 0x0000,
 *   register 0x00, manufacturer bytes 0) is sent; with CO_NODE_EMCY_RESET_EACH every clear sends
 *   it, with the register of the errors still active (CiA 301 allows both; CANopenNode does the
 *   latter).
 * - 0x1001 is the OR of the active errors' register bits, plus the generic bit (bit 0) while any
 *   error is active (unless CO_NODE_ERR_REG_NO_GENERIC: drives whose manuals set one class bit).
 * - 0x1003: the newest entry at sub 1, older ones shift down, the oldest falls off when the depth
 *   the dictionary gives (its number of sub-entries above 0) is full; sub 0 = number of entries.
 *   An entry is the error code in bits 0-15 and the additional information (manufacturer-specific,
 *   CiA 301 §7.5.2.4) in bits 16-31: 0 for co_emcy_raise(), chosen with co_emcy_raise_info().
 *   Writing 0 to sub 0 empties the history (active errors and 0x1001 stay); any other value aborts
 *   0x06090030; the other sub-entries are read-only (0x06010002). A dictionary whose sub 0 default
 *   is not 0 prints sub 0 as a constant "number of entries" (the VF-S15's "only one possible error
 *   (1)"): sub 0 then keeps its value and only the entries change.
 * - Reset communication restores 0x1001 and 0x1003 to their defaults (history emptied), drops
 *   queued EMCYs and re-reads 0x1014/0x1015; errors still active stay active and 0x1001 is
 *   recomputed from them.
 * - SDO writes of 0x1014: bits 11-30 set (29-bit CAN-ID, reserved bits), a CAN-ID CiA 301 §7.3.5
 *   reserves while valid, or a new CAN-ID while the EMCY is valid (set bit 31 first) abort
 *   0x06090030. 0x1015 takes effect at once (the running inhibit time is measured again from the
 *   last EMCY sent). */
#ifndef CANOPEN_EMCY_H
#define CANOPEN_EMCY_H

#include <stdbool.h>
#include <stdint.h>

#include "canopen/od.h"
#include "canopen/time_base.h"

#ifdef __cplusplus
extern "C" {
#endif

struct co_node;

#ifndef CO_EMCY_MAX_ACTIVE
#define CO_EMCY_MAX_ACTIVE 8u /* errors that can be active at once */
#endif
#ifndef CO_EMCY_QUEUE_LEN
#define CO_EMCY_QUEUE_LEN 4u  /* EMCY frames held back by the inhibit time (0x1015) */
#endif

/* Error register bits (0x1001). */
#define CO_ERR_REG_GENERIC       0x01u
#define CO_ERR_REG_CURRENT       0x02u
#define CO_ERR_REG_VOLTAGE       0x04u
#define CO_ERR_REG_TEMPERATURE   0x08u
#define CO_ERR_REG_COMMUNICATION 0x10u
#define CO_ERR_REG_PROFILE       0x20u
#define CO_ERR_REG_MANUFACTURER  0x80u

/* CiA 301 error codes the core itself raises. */
#define CO_EMCY_NO_ERROR            0x0000u /* error reset */
#define CO_EMCY_CAN_OVERRUN         0x8110u /* CAN overrun (received frames lost) */
#define CO_EMCY_CAN_PASSIVE         0x8120u /* CAN in error passive mode */
#define CO_EMCY_LIFE_GUARD          0x8130u /* life guard error or heartbeat error */
#define CO_EMCY_BUS_OFF_RECOVERED   0x8140u /* recovered from bus off */

typedef struct co_emcy_active {
    uint16_t code;
    uint8_t register_bits;
} co_emcy_active;

typedef struct co_emcy {
    /* the scalars first (short loads on a microcontroller), the arrays last */
    uint8_t active_count;
    uint8_t queued_count;
    uint8_t queued_head;       /* oldest queued frame */
    bool has_sent;
    bool valid;                /* 0x1014 bit 31 clear */
    bool held;                 /* the queue holds frames raised or waiting in STOPPED */
    bool reported;             /* the last EMCY sent told of an active error (non-zero code or
                                * register) */
    uint8_t history_depth;           /* entries 0x1003 holds (sub 1..depth) */
    uint8_t history_count;           /* entries in use */
    bool history_fixed_count;        /* sub 0 is a constant (non-zero default) */
    uint16_t cob_id;           /* CAN-ID of 0x1014 */
    uint32_t inhibit_us;       /* 0x1015, 100 µs units converted */
    co_time next_allowed;      /* earliest time the next EMCY may be sent */
    co_time last_sent;         /* time of the last EMCY sent (valid when has_sent) */
    /* Resolved once at node init (the dictionary is const). */
    const co_od_entry *history;      /* 0x1003, NULL if absent */
    uint8_t *error_register; /* the value of 0x1001 in the value block, NULL if absent */
    uint32_t lost;             /* EMCY frames dropped because the queue was full */
    uint32_t suppressed;       /* EMCY frames not sent: INITIALISING, 0x1014 invalid, or held
                                * through STOPPED and no longer true */
    uint32_t sent;             /* EMCY frames handed to co_node_send */
    co_emcy_active active[CO_EMCY_MAX_ACTIVE]; /* in no particular order */
    uint8_t queued[CO_EMCY_QUEUE_LEN][8];
} co_emcy;

/* Hears every EMCY the node produces (an error raised or raised again, an error reset), with its
 * 8 data bytes (code, 0x1001, the 5 manufacturer bytes), when it is produced and whether or not
 * the CAN frame goes out (NMT state, 0x1014 bit 31, inhibit queue): another transport of the same
 * node (CoE emergency over EtherCAT) carries it from here. Set with co_emcy_set_listener. */
typedef void (*co_emcy_listener)(struct co_node *node, void *ctx, const uint8_t data[8]);

/* Raises an error: records code in 0x1003 (newest at sub 1, older ones shift down, depth as the
 * OD defines), sets register_bits (and the generic bit) in 0x1001, and sends an EMCY with code,
 * 0x1001 and the 5 manufacturer bytes (NULL: zeros), after the inhibit time if one is running.
 * Raising a code that is already active only sends again (its register bits are merged). Code
 * 0x0000 is not an error: nothing happens and false is returned. Returns false if the active list
 * is full (the EMCY is still sent and 0x1003/0x1001 updated, but the error cannot be cleared
 * individually: co_emcy_clear_all does). */
bool co_emcy_raise(struct co_node *node, uint16_t code, uint8_t register_bits,
                   const uint8_t manufacturer[5]);

/* The same with the additional information of the 0x1003 entry (bits 16-31), e.g. a drive's own
 * fault number. co_emcy_raise() uses 0. */
bool co_emcy_raise_info(struct co_node *node, uint16_t code, uint8_t register_bits,
                        const uint8_t manufacturer[5], uint16_t info);

#if CO_CONFIG_EMCY_LISTENER
/* Sets (fn NULL: removes) the node's EMCY listener; one per node, kept across resets. Only in a
 * build with CO_CONFIG_EMCY_LISTENER 1 (include/canopen/config.h). */
void co_emcy_set_listener(struct co_node *node, co_emcy_listener fn, void *ctx);
#endif

/* Clears an active error: recomputes 0x1001 from the errors still active; when none is left
 * sends the error-reset EMCY (code 0x0000). Unknown codes are ignored. */
void co_emcy_clear(struct co_node *node, uint16_t code);

/* Clears every active error (as a fault reset does), sending one error-reset EMCY (none if no
 * error was active). */
void co_emcy_clear_all(struct co_node *node);

/* True while code is active. */
bool co_emcy_is_active(const struct co_node *node, uint16_t code);

/* The error register as computed from the active errors (the value of 0x1001). */
uint8_t co_emcy_error_register(const struct co_node *node);

/* --- called by the node ------------------------------------------------------------------- */

/* The core's handlers of SDO/RPDO writes to 0x1003 (pre-defined error field) and 0x1014/0x1015
 * (COB-ID EMCY, inhibit time), with the co_od_hook write signature (see co_errctl_* in
 * errctl.h for how they are called). */
co_abort co_emcy_history_written(struct co_node *node, void *ctx, co_od_ref ref,
                                 const uint8_t *data, uint32_t len, co_od_origin origin);
co_abort co_emcy_param_written(struct co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                               uint32_t len, co_od_origin origin);

#ifdef __cplusplus
}
#endif

#endif
