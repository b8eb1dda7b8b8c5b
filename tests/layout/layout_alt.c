/* See layout_alt.h: built once per switch, with the switch on the command line or in a user
 * header (CO_CONFIG_USER_HEADER), and LAYOUT_ALT_FN the name of the function. */
#include "layout_alt.h"

#include <string.h>

layout_alt_result LAYOUT_ALT_FN(const co_node_config *cfg)
{
    static co_node node; /* this file's co_node: its size is this file's view */
    memset(&node, 0xA5, sizeof node);
    layout_alt_result r;
    r.accepted = co_node_init(&node, cfg);
    const uint8_t *bytes = (const uint8_t *)&node;
    r.untouched = true;
    for (size_t i = 0; i < sizeof node; i++) {
        r.untouched = r.untouched && bytes[i] == 0xA5u;
    }
    r.reason = co_layout_mismatch(CO_LAYOUT_SIGNATURE);
    return r;
}
