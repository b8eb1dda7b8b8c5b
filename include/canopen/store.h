/* Store parameters 0x1010 and restore default parameters 0x1011 (CiA 301 §7.5.2.13/§7.5.2.14),
 * on the port's co_storage (node.h).
 *
 * What the bus sees:
 * - Sub 1 = all parameters, sub 2 = communication (0x1000-0x1FFF), sub 3 = application
 *   (0x6000-0x9FFF), sub 4 = manufacturer-defined (0x2000-0x5FFF), as far as the dictionary has
 *   these sub-entries. Only persistent values count (CO_OD_PERSIST, the prefix of the value block).
 * - Reading a sub-entry above 0 returns its EDS default (CiA 301 bit 0 = saves / restores on
 *   command, bit 1 = autonomously), or 0 when the node has no storage.
 * - Writing "save" (0x65766173, bytes 73 61 76 65) to 0x1010 stores the current values of that
 *   group; "load" (0x64616F6C, bytes 6C 6F 61 64) to 0x1011 makes that group's defaults take
 *   effect at the next reset (reset communication for 0x1000-0x1FFF, reset node for all), without
 *   changing a current value. Any other value, no storage, a sub-entry above 4, or a storage that
 *   fails abort 0x08000020 and change nothing (CiA 301 §7.5.2.13; CANopenNode answers the same to
 *   a wrong signature, and 0x06010002 when it has no storage).
 * - The store holds one image, the whole persistent prefix. Sub 1 saves the value block as it is
 *   and sub 1 of 0x1011 erases the image. Subs 2-4 merge: the stored image (or, if none, the
 *   defaults) with that group replaced by the current values (save) or by the defaults (restore),
 *   saved whole; they need co_node_config.store_scratch (at least od->persist_size bytes) and abort
 *   0x08000020 without it. A restore with nothing stored succeeds and writes nothing. */
#ifndef CANOPEN_STORE_H
#define CANOPEN_STORE_H

#include <stdint.h>

#include "canopen/abort.h"
#include "canopen/od.h"

#ifdef __cplusplus
extern "C" {
#endif

struct co_node;

#define CO_STORE_SIGNATURE_SAVE 0x65766173u /* "save" */
#define CO_STORE_SIGNATURE_LOAD 0x64616F6Cu /* "load" */

/* Stores the values of group sub (1..4 as above), as a "save" written to 0x1010 sub would; for
 * an application that stores by itself (e.g. a parameter the manual says is saved when written).
 * Returns the abort code the SDO write would get. */
co_abort co_store_save(struct co_node *node, uint8_t sub);

/* Restores the defaults of group sub at the next reset, as "load" written to 0x1011 sub would. */
co_abort co_store_restore(struct co_node *node, uint8_t sub);

/* The core's handlers of 0x1010/0x1011, with the co_od_hook signatures: refresh before an SDO
 * read, write for SDO writes (see co_errctl_* in errctl.h for how they are called). */
co_abort co_store_refresh(struct co_node *node, void *ctx, co_od_ref ref);
co_abort co_store_written(struct co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                          uint32_t len, co_od_origin origin);

#ifdef __cplusplus
}
#endif

#endif
