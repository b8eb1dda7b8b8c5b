/* See layout_alt.h: built once per switch, with LAYOUT_ALT_FN the name of the function and
 * LAYOUT_FLIP naming the switch to change (or a user header, CO_CONFIG_USER_HEADER, changing it).
 * The change is relative to what the command line gives the library (a preset may set switches
 * with -D), so each file differs from the library in exactly that switch. */
#define FLIP_TIME32 1
#define FLIP_COMPACT 2
#define FLIP_PDO_BITS 3
#define FLIP_TX_QUEUE 4
#define FLIP_HB_CONSUMERS 5

#if LAYOUT_FLIP == FLIP_TIME32
#if defined(CO_CONFIG_TIME32) && CO_CONFIG_TIME32
#undef CO_CONFIG_TIME32
#define CO_CONFIG_TIME32 0
#else
#undef CO_CONFIG_TIME32
#define CO_CONFIG_TIME32 1
#endif
#elif LAYOUT_FLIP == FLIP_COMPACT
#if defined(CO_CONFIG_OD_COMPACT) && CO_CONFIG_OD_COMPACT
#undef CO_CONFIG_OD_COMPACT
#define CO_CONFIG_OD_COMPACT 0
#else
#undef CO_CONFIG_OD_COMPACT
#define CO_CONFIG_OD_COMPACT 1
#endif
#elif LAYOUT_FLIP == FLIP_PDO_BITS
#if defined(CO_CONFIG_PDO_BITS) && CO_CONFIG_PDO_BITS == 32
#undef CO_CONFIG_PDO_BITS
#define CO_CONFIG_PDO_BITS 64
#else
#undef CO_CONFIG_PDO_BITS
#define CO_CONFIG_PDO_BITS 32
#endif
#elif LAYOUT_FLIP == FLIP_TX_QUEUE
#if defined(CO_TX_QUEUE_LEN) && CO_TX_QUEUE_LEN == 8u
#undef CO_TX_QUEUE_LEN
#define CO_TX_QUEUE_LEN 16u
#else
#undef CO_TX_QUEUE_LEN
#define CO_TX_QUEUE_LEN 8u /* the default is 16 */
#endif
#elif LAYOUT_FLIP == FLIP_HB_CONSUMERS
#if defined(CO_HB_CONSUMER_MAX) && CO_HB_CONSUMER_MAX == 9u
#undef CO_HB_CONSUMER_MAX
#define CO_HB_CONSUMER_MAX 10u
#else
#undef CO_HB_CONSUMER_MAX
#define CO_HB_CONSUMER_MAX 9u /* the default is 8 */
#endif
#endif

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
