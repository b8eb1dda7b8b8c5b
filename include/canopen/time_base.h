/* The time base of the services' deadlines (CO_CONFIG_TIME32, include/canopen/config.h).
 *
 * The API takes and returns absolute 64-bit µs times. Inside, every service keeps its deadlines as
 * co_time:
 * - 64-bit build (the default): co_time is that same 64-bit µs time.
 * - CO_CONFIG_TIME32: co_time is a 32-bit µs count from the node's epoch (co_node.epoch). The
 *   node keeps it below CO_TIME32_REBASE_AT: when a call's time reaches it, the epoch moves
 *   forward so that the time becomes CO_TIME32_HISTORY and every stored time moves back by the
 *   same amount (co_node_time, src/node.c). A future deadline (now + at most CO_TIME_SPAN_MAX)
 *   therefore always fits below CO_NEVER, and plain unsigned compares stay right. A past time
 *   more than CO_TIME32_HISTORY old becomes 0: still past, and every service that reads a past
 *   time (a heartbeat's cadence, the EMCY inhibit) only asks whether it is older than its period,
 *   at most 65.5 s. The SYNC period and window (32-bit µs) and life guarding (up to 65535 ms x
 *   255) can exceed 2^31 µs; their times are co_time_wide, absolute 64-bit API times, which the
 *   epoch's moves leave alone (co_time_wide_of / co_time_from_wide, src/schedule.h). The
 *   other periods are 16-bit ms or 100 µs counts; a PDO time a dictionary declares wider
 *   saturates at CO_TIME_SPAN_MAX (2^31 - 1 µs instead of 2^32 - 1), and co_node_init() refuses
 *   an SDO timeout or a PDO floor (co_pdo_config) above it. A call
 *   with a time before the epoch (a clock gone back by more than CO_TIME32_HISTORY) counts as
 *   the epoch.
 * The services' functions that take a co_time (co_pdo_configure, co_sync_window_open,
 * co_sdo_server_process, ...) take the node's time, co_node.now, not an API time. */
#ifndef CANOPEN_TIME_BASE_H
#define CANOPEN_TIME_BASE_H

#include <stdint.h>

#include "canopen/config.h"

#ifdef __cplusplus
extern "C" {
#endif

#if CO_CONFIG_TIME32
typedef uint32_t co_time;
typedef uint64_t co_time_wide; /* an API time */
#define CO_NEVER UINT32_MAX
#define CO_WIDE_NEVER UINT64_MAX
/* A call at this time or later (µs since the epoch) moves the epoch; the time is then
 * CO_TIME32_HISTORY. */
#define CO_TIME32_REBASE_AT 0x80000000u
#define CO_TIME32_HISTORY 0x40000000u
/* The longest time a co_time deadline may lie ahead of now. */
#define CO_TIME_SPAN_MAX 0x7FFFFFFFu

/* The deadline span µs after now (span at most CO_TIME_SPAN_MAX: it always fits). */
static inline co_time co_time_after(co_time now, uint32_t span)
{
    return now + span;
}
#else
typedef uint64_t co_time;
typedef uint64_t co_time_wide;
#define CO_NEVER UINT64_MAX
#define CO_WIDE_NEVER UINT64_MAX
#define CO_TIME_SPAN_MAX UINT32_MAX

/* The deadline span µs after now, CO_NEVER if that is beyond the end of time. */
static inline co_time co_time_after(co_time now, uint32_t span)
{
    return now > CO_NEVER - span ? CO_NEVER : now + span;
}
#endif

#ifdef __cplusplus
}
#endif

#endif
