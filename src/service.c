/* The helpers every service of the core uses (src/services.h): storing an accepted parameter,
 * reading one, reporting a communication event, sending a one-byte frame. */
#include <string.h>

#include "dispatch.h"
#include "services.h"

bool co_can_id_restricted(uint16_t id)
{
    /* all but the IDs left free: 0x080-0x100, 0x181-0x580, 0x600, 0x680-0x6DF and 0x700 */
    return !((uint32_t)id - 0x080u <= 0x080u || (uint32_t)id - 0x181u <= 0x3FFu || id == 0x600u ||
             (uint32_t)id - 0x680u < 0x060u || id == 0x700u);
}

void co_svc_store(co_node *node, const uint8_t *data, co_od_ref ref)
{
    /* the write path checked the length against the sub-entry's size (check_value) */
    memcpy(node->values + co_od_value_offset(ref.entry, ref.sub), data, co_od_sub_size(ref.sub));
}

uint32_t co_svc_od_value(const co_node *node, uint16_t index)
{
    return co_node_od_value(node, index, 0u, 0u);
}

void co_svc_report(co_node *node, co_comm_event event, uint32_t detail)
{
    if (node->events.comm != NULL) {
        node->events.comm(node, node->events.ctx, event, detail);
    }
}

void co_svc_send(co_node *node, uint16_t id, uint8_t dlc, uint8_t byte)
{
    co_frame frame = {id, dlc, 0u, {byte}};
    (void)co_node_send(node, &frame);
}

void co_svc_send_state(co_node *node, uint8_t byte)
{
    co_svc_send(node, (uint16_t)(0x700u + node->node_id), 1u, byte);
}
