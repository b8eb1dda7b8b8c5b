/* Time and the next-deadline contract of the services (docs/design.md, "Scheduling"): the
 * node's time base and how a service that moves a deadline outside co_node_process says so. */
#ifndef CANOPEN_SCHEDULE_H
#define CANOPEN_SCHEDULE_H

#include "canopen/node.h"

/* The co_time of the API time now (include/canopen/time_base.h): now itself in a 64-bit build;
 * with CO_CONFIG_TIME32 the µs since the node's epoch, after moving the epoch (and every time the
 * services keep) forward once now is CO_TIME32_REBASE_AT past it. Every API function that takes
 * a time converts it here. */
#if CO_CONFIG_TIME32
co_time co_node_time(co_node *node, uint64_t now);
#else
static inline co_time co_node_time(co_node *node, uint64_t now)
{
    (void)node;
    return now;
}
#endif

/* The times that can lie more than CO_TIME_SPAN_MAX ahead or back (the SYNC period and window,
 * life guarding) are co_time_wide: with CO_CONFIG_TIME32 absolute API times, which the epoch's
 * moves leave alone. co_time_wide_of is the wide time of the co_time t; co_time_from_wide the
 * co_time the node schedules a wide time by: CO_NEVER for CO_WIDE_NEVER, 0 for a time before the
 * epoch (past), CO_NEVER - 1 for one beyond co_time's range (not never: the node is called then,
 * moves its epoch and looks again). */
#if CO_CONFIG_TIME32
co_time co_time_from_wide(const co_node *node, co_time_wide t);
static inline co_time_wide co_time_wide_of(const co_node *node, co_time t)
{
    return node->epoch + t;
}
#else
static inline co_time co_time_from_wide(const co_node *node, co_time_wide t)
{
    (void)node;
    return t;
}
static inline co_time_wide co_time_wide_of(const co_node *node, co_time t)
{
    (void)node;
    return t;
}
#endif

/* node->next is the earliest of the deadlines the services keep (heartbeat.next, errctl.next,
 * sdo.deadline while a transfer runs, sync.next, pdo.next, the EMCY inhibit while frames wait),
 * exactly what a full co_node_process pass would return, or earlier. Whoever changes one of them
 * outside the pass says so with one of these, so the pass can be skipped while nothing is due. */

/* A deadline was set at `at` or earlier than before. */
static inline void co_node_wake(co_node *node, co_time at)
{
    if (at < node->next) {
        node->next = at;
    }
}

/* A deadline moved from old to at: if old may have been the earliest, the next pass recomputes. */
static inline void co_node_reschedule(co_node *node, co_time old, co_time at)
{
    if (at < node->next) {
        node->next = at;
    } else if (at != old && old <= node->next) {
        node->next = 0u;
    }
}

/* Something the next pass must look at changed (a state, a cancelled timer, ...). */
static inline void co_node_recheck(co_node *node)
{
    node->next = 0u;
}

#endif
