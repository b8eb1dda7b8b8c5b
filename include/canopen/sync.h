/* SYNC consumer and producer (CiA 301 §7.2.5): COB-ID 0x1005, communication cycle period 0x1006,
 * synchronous window length 0x1007, synchronous counter overflow value 0x1019.
 *
 * What the bus sees:
 * - SYNC is consumed in PRE-OPERATIONAL and OPERATIONAL on the CAN-ID in 0x1005 bits 0-10 (bit 31
 *   is "don't care" for SYNC). Only in OPERATIONAL does a SYNC move the synchronous PDOs.
 * - Frame length: with 0x1019 = 0 a SYNC has 0 bytes (a 1-byte SYNC is tolerated, its counter
 *   ignored); with 0x1019 = 2..240 it has exactly 1 byte, the SYNC counter. Any other length, and
 *   an RTR frame, is dropped and counted (node->sync.bad_length and node->stats.rx_malformed).
 * - Producer: when 0x1005 bit 30 is set and 0x1006 is non-zero, the node sends a SYNC every 0x1006
 *   µs in PRE-OPERATIONAL and OPERATIONAL (the first one period after the producer was set up),
 *   with the counter 1..0x1019 when the counter is in use. It consumes its own SYNC; SYNC frames
 *   of another producer on the same CAN-ID are then ignored (counted in stats.rx_ignored).
 *   Bit 30 is refused (0x06040043 by default, co_pdo_config.value_abort) when the dictionary has
 *   no 0x1006, or co_pdo_config.flags has CO_PDO_SYNC_CONSUMER_ONLY: the device cannot produce.
 * - Window (0x1007, µs, 0 = none): synchronous RPDOs that arrive when at least 0x1007 µs have
 *   passed since the last SYNC are discarded (see pdo.h); synchronous TPDOs are only ever sent at
 *   the SYNC itself, so always inside the window.
 *
 * Writes (SDO) are checked by the core's handler (co_sync_param_written):
 * - 0x1005: bit 29 (29-bit CAN-ID) or any of bits 11-28 set, or a CAN-ID CiA 301 §7.3.5
 *   restricts (0x000-0x07F, 0x101-0x180, 0x581-0x5FF, 0x601-0x67F, 0x6E0-0x6FF, 0x701-0x7FF) ->
 *   value_abort; bit 30 without 0x1006
 *   -> value_abort; a new CAN-ID while the node produces SYNC and keeps producing -> busy_abort
 *   (CiA 301: bits 0-29 are not changed while bit 30 = 1).
 * - 0x1019: 1 or more than 240 -> value_abort; any change while 0x1006 is not 0 -> 0x08000022
 *   (CiA 301 §7.5.2.22).
 * - 0x1006, 0x1007: any value; they take effect at once (the producer restarts its period). */
#ifndef CANOPEN_SYNC_H
#define CANOPEN_SYNC_H

#include <stdbool.h>
#include <stdint.h>

#include "canopen/abort.h"
#include "canopen/frame.h"
#include "canopen/nmt.h"
#include "canopen/od.h"
#include "canopen/time_base.h"

#ifdef __cplusplus
extern "C" {
#endif

struct co_node;

#define CO_SYNC_NO_COB 0xFFFFu /* sync.cob_id when the node has no 0x1005: matches no frame */

typedef struct co_sync {
    /* the bytes first (short offsets on a microcontroller), the 64-bit times last */
    uint16_t cob_id;       /* 11-bit CAN-ID, or CO_SYNC_NO_COB */
    uint8_t overflow;      /* 0x1019: 0 = no counter, 2..240 */
    uint8_t counter;       /* counter of the latest SYNC (0 without one); producer: next to send */
    bool producer;         /* 0x1005 bit 30 set and the dictionary has 0x1006 */
    bool seen;             /* a SYNC was received or produced since the last reset */
    uint32_t period_us;    /* 0x1006 */
    uint32_t window_us;    /* 0x1007; 0: no window */
    uint32_t bad_length;   /* SYNC frames dropped for their length or an RTR */
    co_time_wide last;     /* time of the latest SYNC received or produced (valid when seen) */
    co_time_wide next;     /* producer: time of the next SYNC; CO_WIDE_NEVER when not producing */
} co_sync;

/* Re-reads 0x1005, 0x1006, 0x1007 and 0x1019 (reset communication, or after the application
 * changed them with CO_ORIGIN_APP writes, which skip the handler). The producer's first SYNC follows
 * one period after now, or after entering PRE-OPERATIONAL / OPERATIONAL when the node is not in
 * one of them. */
void co_sync_configure(struct co_node *node, co_time now);

/* The core's handler of SDO/RPDO writes to 0x1005-0x1007 and 0x1019 (checks above), with the
 * co_od_hook write signature: the node calls it unless an application hook covers the object;
 * such a hook (hooks do not chain) calls it once its own checks pass. */
co_abort co_sync_param_written(struct co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                               uint32_t len, co_od_origin origin);

/* True while a synchronous RPDO received at now is inside the synchronous window: no window set,
 * no SYNC seen yet, or less than 0x1007 µs since the last SYNC. */
bool co_sync_window_open(const struct co_node *node, co_time now);

#ifdef __cplusplus
}
#endif

#endif
