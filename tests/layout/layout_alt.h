/* One co_node_init() call from a file built with other switches than the library (layout_alt.c,
 * compiled once per function, each changing one switch; layout_same changes none). */
#ifndef LAYOUT_ALT_H
#define LAYOUT_ALT_H

#include <stdbool.h>

#include "canopen/node.h"

/* The result of the call. */
typedef struct layout_alt_result {
    bool accepted;      /* co_node_init()'s answer */
    bool untouched;     /* the node, as that file sees it, holds the bytes it held before */
    const char *reason; /* co_layout_mismatch() of that file's signature */
} layout_alt_result;

/* Calls co_node_init on a node of that file's own layout, with cfg (the same for every file: no
 * switch changes co_node_config). */
layout_alt_result layout_time32(const co_node_config *cfg);
layout_alt_result layout_compact(const co_node_config *cfg);
layout_alt_result layout_pdo_bits(const co_node_config *cfg);
layout_alt_result layout_tx_queue(const co_node_config *cfg);
layout_alt_result layout_hb_consumers(const co_node_config *cfg);
layout_alt_result layout_user_header(const co_node_config *cfg);
layout_alt_result layout_same(const co_node_config *cfg);

#endif
