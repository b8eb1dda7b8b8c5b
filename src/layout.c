/* Why a caller's layout signature is not the library's (co_layout_mismatch, node.h). In a file of
 * its own so that a firmware that never asks links none of its text. */
#include "canopen/node.h"

#include <stddef.h>

const char *co_layout_mismatch(uint32_t layout)
{
    uint32_t differ = layout ^ CO_LAYOUT_SIGNATURE;
    if (differ == 0u) {
        return NULL;
    }
    if ((differ & CO_LAYOUT_TIME32) != 0u) {
        return "CO_CONFIG_TIME32 differs between the caller and the canopen library";
    }
    if ((differ & CO_LAYOUT_OD_COMPACT) != 0u) {
        return "CO_CONFIG_OD_COMPACT differs between the caller and the canopen library";
    }
    if ((differ & CO_LAYOUT_PDO_BITS32) != 0u) {
        return "CO_CONFIG_PDO_BITS differs between the caller and the canopen library";
    }
    return "the CO_* sizes differ between the caller and the canopen library (sizeof(co_node) is "
           "not the same: CO_TX_QUEUE_LEN, CO_SDO_BUF_SIZE, CO_MAX_RPDO/TPDO, CO_MAX_HOOKS, "
           "CO_HOOK_MAP_ENTRIES, CO_HB_CONSUMER_MAX, CO_EMCY_MAX_ACTIVE, CO_EMCY_QUEUE_LEN)";
}
