/* CiA 402 PDS state machine: controlword decoding, transitions, statusword. */
#include "canopen/drive/cia402.h"

co_cia402_command co_cia402_decode(uint16_t controlword, uint16_t previous, uint32_t flags)
{
    if ((controlword & CO_CW_FAULT_RESET) != 0u) {
        if ((previous & CO_CW_FAULT_RESET) == 0u) {
            return CO_CIA402_CMD_FAULT_RESET;
        }
        if ((flags & CO_CIA402_BIT7_DONT_CARE) == 0u) {
            return CO_CIA402_CMD_NONE; /* every command of table 27 has bit 7 = 0 */
        }
    }
    if ((controlword & CO_CW_ENABLE_VOLTAGE) == 0u) {
        return CO_CIA402_CMD_DISABLE_VOLTAGE; /* x x 0 x */
    }
    if ((controlword & CO_CW_QUICK_STOP) == 0u) {
        return CO_CIA402_CMD_QUICK_STOP; /* x 0 1 x */
    }
    if ((controlword & CO_CW_SWITCH_ON) == 0u) {
        return CO_CIA402_CMD_SHUTDOWN; /* x 1 1 0 */
    }
    return (controlword & CO_CW_ENABLE_OPERATION) != 0u ? CO_CIA402_CMD_ENABLE_OPERATION
                                                        : CO_CIA402_CMD_SWITCH_ON;
}

static int go(co_cia402_state *to, co_cia402_state state, int transition)
{
    *to = state;
    return transition;
}

int co_cia402_next(co_cia402_state from, co_cia402_command command, uint32_t flags,
                   bool quick_stop_stays, co_cia402_state *to)
{
    *to = from;
    switch (from) {
    case CO_CIA402_SWITCH_ON_DISABLED:
        if (command == CO_CIA402_CMD_SHUTDOWN) {
            return go(to, CO_CIA402_READY_TO_SWITCH_ON, 2);
        }
        return -1; /* Switch on / Enable operation here are not Shutdown: nothing */
    case CO_CIA402_READY_TO_SWITCH_ON:
        switch (command) {
        case CO_CIA402_CMD_SWITCH_ON:
        case CO_CIA402_CMD_ENABLE_OPERATION: /* 3 (+ 4 by the caller) */
            return go(to, CO_CIA402_SWITCHED_ON, 3);
        case CO_CIA402_CMD_DISABLE_VOLTAGE:
        case CO_CIA402_CMD_QUICK_STOP:
            return go(to, CO_CIA402_SWITCH_ON_DISABLED, 7);
        default:
            return -1;
        }
    case CO_CIA402_SWITCHED_ON:
        switch (command) {
        case CO_CIA402_CMD_ENABLE_OPERATION:
            return go(to, CO_CIA402_OPERATION_ENABLED, 4);
        case CO_CIA402_CMD_SHUTDOWN:
            return go(to, CO_CIA402_READY_TO_SWITCH_ON, 6);
        case CO_CIA402_CMD_DISABLE_VOLTAGE:
        case CO_CIA402_CMD_QUICK_STOP:
            return go(to, CO_CIA402_SWITCH_ON_DISABLED, 10);
        default:
            return -1;
        }
    case CO_CIA402_OPERATION_ENABLED:
        switch (command) {
        case CO_CIA402_CMD_SWITCH_ON: /* = Disable operation */
            return go(to, CO_CIA402_SWITCHED_ON, 5);
        case CO_CIA402_CMD_SHUTDOWN:
            return go(to, CO_CIA402_READY_TO_SWITCH_ON, 8);
        case CO_CIA402_CMD_DISABLE_VOLTAGE:
            return go(to, CO_CIA402_SWITCH_ON_DISABLED, 9);
        case CO_CIA402_CMD_QUICK_STOP:
            return go(to, CO_CIA402_QUICK_STOP_ACTIVE, 11);
        default:
            return -1;
        }
    case CO_CIA402_QUICK_STOP_ACTIVE:
        if ((flags & CO_CIA402_QUICK_STOP_LOCKED) != 0u) {
            return -1;
        }
        if (command == CO_CIA402_CMD_DISABLE_VOLTAGE) {
            return go(to, CO_CIA402_SWITCH_ON_DISABLED, 12);
        }
        if (command == CO_CIA402_CMD_ENABLE_OPERATION &&
            (quick_stop_stays || (flags & CO_CIA402_ALWAYS_16) != 0u)) {
            return go(to, CO_CIA402_OPERATION_ENABLED, 16);
        }
        return -1;
    case CO_CIA402_FAULT:
        if (command == CO_CIA402_CMD_FAULT_RESET) {
            return go(to, CO_CIA402_SWITCH_ON_DISABLED, 15);
        }
        return -1;
    case CO_CIA402_NOT_READY_TO_SWITCH_ON:   /* left automatically (1) */
    case CO_CIA402_FAULT_REACTION_ACTIVE:    /* left automatically (14) */
    default:
        return -1;
    }
}

uint16_t co_cia402_statusword(const co_cia402_status *status, uint32_t flags)
{
    uint16_t sw;
    switch (status->state) {
    case CO_CIA402_SWITCH_ON_DISABLED: sw = 0x0040u; break;
    case CO_CIA402_READY_TO_SWITCH_ON: sw = 0x0021u; break;
    case CO_CIA402_SWITCHED_ON: sw = 0x0023u; break;
    case CO_CIA402_OPERATION_ENABLED: sw = 0x0027u; break;
    case CO_CIA402_QUICK_STOP_ACTIVE: sw = 0x0007u; break;
    case CO_CIA402_FAULT_REACTION_ACTIVE: sw = 0x000Fu; break;
    case CO_CIA402_FAULT: sw = 0x0008u; break;
    case CO_CIA402_NOT_READY_TO_SWITCH_ON:
    default: sw = 0x0000u; break;
    }
    if ((status->state == CO_CIA402_FAULT || status->state == CO_CIA402_FAULT_REACTION_ACTIVE) &&
        (flags & CO_CIA402_FAULT_KEEPS_QS_BIT) != 0u && status->quick_stop_before) {
        sw |= CO_SW_QUICK_STOP;
    }
    if (status->voltage_enabled) {
        sw |= CO_SW_VOLTAGE_ENABLED;
    }
    if (status->warning) {
        sw |= CO_SW_WARNING;
    }
    if (status->remote) {
        sw |= CO_SW_REMOTE;
    }
    if (status->target_reached) {
        sw |= CO_SW_TARGET_REACHED;
    }
    if (status->internal_limit) {
        sw |= CO_SW_INTERNAL_LIMIT;
    }
    sw |= (uint16_t)(status->manufacturer & 0xF100u);
    return sw;
}

co_cia402_state co_cia402_state_of(uint16_t statusword)
{
    switch (statusword & 0x4Fu) {
    case 0x00u: return CO_CIA402_NOT_READY_TO_SWITCH_ON;
    case 0x40u: return CO_CIA402_SWITCH_ON_DISABLED;
    case 0x0Fu: return CO_CIA402_FAULT_REACTION_ACTIVE;
    case 0x08u: return CO_CIA402_FAULT;
    default: break;
    }
    switch (statusword & 0x6Fu) {
    case 0x21u: return CO_CIA402_READY_TO_SWITCH_ON;
    case 0x23u: return CO_CIA402_SWITCHED_ON;
    case 0x27u: return CO_CIA402_OPERATION_ENABLED;
    case 0x07u: return CO_CIA402_QUICK_STOP_ACTIVE;
    default: return CO_CIA402_NOT_READY_TO_SWITCH_ON; /* not a valid pattern */
    }
}

const char *co_cia402_state_name(co_cia402_state state)
{
    switch (state) {
    case CO_CIA402_NOT_READY_TO_SWITCH_ON: return "NOT READY TO SWITCH ON";
    case CO_CIA402_SWITCH_ON_DISABLED: return "SWITCH ON DISABLED";
    case CO_CIA402_READY_TO_SWITCH_ON: return "READY TO SWITCH ON";
    case CO_CIA402_SWITCHED_ON: return "SWITCHED ON";
    case CO_CIA402_OPERATION_ENABLED: return "OPERATION ENABLED";
    case CO_CIA402_QUICK_STOP_ACTIVE: return "QUICK STOP ACTIVE";
    case CO_CIA402_FAULT_REACTION_ACTIVE: return "FAULT REACTION ACTIVE";
    case CO_CIA402_FAULT: return "FAULT";
    default: return "UNKNOWN";
    }
}
