/* Functions the core's services share but an application does not call. */
#ifndef CANOPEN_NODE_INTERNAL_H
#define CANOPEN_NODE_INTERNAL_H

#include "canopen/node.h"

/* Copies the default values (node-ID applied) of objects first..last into the value block. */
void co_node_restore_defaults(co_node *node, uint16_t first, uint16_t last);

/* Overwrites the first len bytes of the value block with the stored image, if there is one. */
void co_node_load_stored(co_node *node, uint32_t len);

/* Changes the NMT state and tells the application. */
void co_nmt_enter(co_node *node, co_nmt_state state);

#endif
