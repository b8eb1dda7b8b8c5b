/* How the core's services hear the dictionary: the list of bindings the node is built from
 * (src/node.c). The dictionary (src/od.c) walks that list; it names no service. */
#ifndef CANOPEN_OD_INTERNAL_H
#define CANOPEN_OD_INTERNAL_H

#include "canopen/node.h"

/* What a service of the core needs to hear about its objects index_first..index_last (CiA 301
 * communication objects it implements):
 *   refresh   NULL, or called before every SDO read, to bring the stored value up to date; an
 *             abort code refuses the read.
 *   written   every write by SDO or RPDO (not the application's own, CO_ORIGIN_APP), after the
 *             dictionary has checked access, length and limits and before it stores the value:
 *             the service checks what the dictionary cannot (CiA 301 rules between values, its
 *             state) and applies the value; an abort code other than CO_ABORT_NONE refuses the
 *             write and nothing is stored.
 * Both have the signatures of co_od_hook's refresh and write (their ctx is NULL), so an
 * application hook registered over the same objects can call the service's handler to chain
 * (co_node_add_hook): an application hook wins over the service for the objects it covers. The
 * ranges in co_node_services do not overlap. */
typedef struct co_od_service {
    uint16_t index_first;
    uint16_t index_last;
    co_abort (*refresh)(co_node *node, void *ctx, co_od_ref ref);
    co_abort (*written)(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data, uint32_t len,
                        co_od_origin origin);
} co_od_service;

/* The services a node is built from, in index order (src/node.c): the node composes them, each
 * service exports its handlers (include/canopen/<service>.h). */
#define CO_NODE_SERVICES 10u
extern const co_od_service co_node_services[CO_NODE_SERVICES];

#endif
