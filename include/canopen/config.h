/* Compile-time sizes and behaviour switches of the core. Every buffer the core uses lives in the
 * caller's co_node, so the sizes decide the RAM a node takes. Set any of them in a header of your
 * own, named by CO_CONFIG_USER_HEADER (below), or with -D on the compiler command line; the library
 * and every file that includes these headers must see the same values (co_node_init() refuses a
 * caller whose view of co_node differs: CO_LAYOUT_SIGNATURE, node.h). The defaults suit a host (the simulator); a small microcontroller slave
 * sets smaller ones, as boards/cortex-m4 does: 4 + 4 PDOs, a 127-byte SDO buffer, 8 queued frames,
 * 8 hooks, no hook map - a node of about 1.9 kB on a Cortex-M4 - and, as a generic CiA 301 slave,
 * every behaviour switch at the end of this file off. */
#ifndef CANOPEN_CONFIG_H
#define CANOPEN_CONFIG_H

/* The user's own switches: compile the library and the application with
 * -DCO_CONFIG_USER_HEADER='"my_canopen_config.h"' (a quoted or <...> header name) and that header,
 * included here before any default, #defines the values to change (the rest keep the defaults
 * below). With CMake: set CANOPEN_CONFIG_HEADER to the header's path (docs/porting.md). */
#ifdef CO_CONFIG_USER_HEADER
#include CO_CONFIG_USER_HEADER
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* Frames the core holds while the port's own queue is full. Must be a power of two. */
#ifndef CO_TX_QUEUE_LEN
#define CO_TX_QUEUE_LEN 16u
#endif

/* SDO server buffer: the largest non-DOMAIN object a segmented or block download can write (a
 * download is committed only once complete, so an aborted transfer changes nothing), and the
 * block size offered in block transfers (buffer / 7 segments, at most 127). */
#ifndef CO_SDO_BUF_SIZE
#define CO_SDO_BUF_SIZE 889u
#endif

/* Default SDO server timeout between two frames of one transfer, in microseconds. */
#ifndef CO_SDO_TIMEOUT_US
#define CO_SDO_TIMEOUT_US 1000000u
#endif

/* RPDOs and TPDOs one node handles (the dictionary's PDOs in number order; more are ignored), up
 * to CiA 301's 512 each. Each costs about 130 bytes (RPDO) / 90 bytes (TPDO) of RAM on a 32-bit
 * target. */
#ifndef CO_MAX_RPDO
#define CO_MAX_RPDO 8u
#endif
#ifndef CO_MAX_TPDO
#define CO_MAX_TPDO 8u
#endif

/* Object hooks (computed or side-effecting objects) the application can register on one node, at
 * most 246 (the core handles its own communication objects without hooks). */
#ifndef CO_MAX_HOOKS
#define CO_MAX_HOOKS 24u
#endif

/* Dictionary entries (the first ones, in index order: the communication profile comes first) for
 * which the node keeps the slot of their hook in a byte each, so a read or write finds its hook
 * without a search; the entries after them search the hooks (CO_MAX_HOOKS compares). 0: none. */
#ifndef CO_HOOK_MAP_ENTRIES
#define CO_HOOK_MAP_ENTRIES 256u
#endif

/* --- Behaviour switches, in the style of CANopenNode's CO_CONFIG_* ----------------------------
 * The core carries the deviations from CiA 301 that some drives' manuals describe, each chosen at
 * run time by co_node_config.options (CO_NODE_*, include/canopen/node.h) and co_node_config.pdo
 * (CO_PDO_* flags and the numeric options of co_pdo_config, include/canopen/pdo.h). The
 * simulated drives need them, so the defaults keep them all. A generic CiA 301 slave needs none
 * of them: setting a switch to 0 leaves its code out, and co_node_init() then refuses (returns
 * false) a configuration that asks for what was left out, so nothing is silently ignored.
 * boards/cortex-m4 builds its generic slaves (bench, vf_s15) with all of them 0. */

/* The CO_NODE_* options the core honours (a mask; 0: none, every node behaves as CiA 301 says). */
#ifndef CO_CONFIG_NODE_OPTIONS
#define CO_CONFIG_NODE_OPTIONS 0xFFFFFFFFu
#endif

/* The CO_PDO_* flags the core honours (a mask; 0: none). */
#ifndef CO_CONFIG_PDO_FLAGS
#define CO_CONFIG_PDO_FLAGS 0xFFFFu
#endif

/* 1: co_pdo_config's numeric options - the unit of the TPDO inhibit time (sub 3), the floors of
 * the inhibit time and of the event timer, and the drive's own abort codes for invalid PDO and
 * SYNC parameters. 0: CiA 301's values (100 µs, no floors, 0x06040043); those fields must be 0. */
#ifndef CO_CONFIG_PDO_TUNING
#define CO_CONFIG_PDO_TUNING 1
#endif

/* 1: value limits (EDS LowLimit/HighLimit) of REAL32/REAL64 objects and of integers wider than 32
 * bits are checked. 0: limits are compared in 32-bit arithmetic, for integers of up to 32 bits only
 * (what CiA 301 slaves and the drives' manuals use), and co_node_init() refuses a dictionary that
 * has limits on a REAL or a wider integer. Objects of those types without limits work either way. */
#ifndef CO_CONFIG_OD_WIDE_LIMITS
#define CO_CONFIG_OD_WIDE_LIMITS 1
#endif

/* 1: the statistics counters (co_node.stats, pdo.stats, emcy/errctl/sync counters: frames
 * received, dropped, malformed, ignored, sent, deferred, aborted, ...) count. 0: they are left out
 * and stay 0 (CANopenNode keeps none); the protocol is the same. */
#ifndef CO_CONFIG_STATS
#define CO_CONFIG_STATS 1
#endif

/* 1: an EMCY raised in STOPPED is held in the EMCY queue and sent on leaving STOPPED if it is
 * still true (include/canopen/emcy.h), as CANopenNode keeps its EMCY FIFO, so a master that only
 * listens for EMCYs learns of a fault raised while it had the node stopped. 0: as in INITIALISING,
 * an EMCY raised in STOPPED updates 0x1001 and 0x1003 but its frame is not sent, nor sent later
 * (CiA 301 makes EMCY no service of STOPPED and asks for nothing more), and frames waiting for the
 * inhibit time are dropped on entering STOPPED. */
#ifndef CO_CONFIG_EMCY_HOLD
#define CO_CONFIG_EMCY_HOLD 1
#endif

/* 1: an EMCY listener (co_emcy_set_listener, include/canopen/emcy.h) hears every EMCY the node
 * produces, for another transport of the same node to carry (the EtherCAT slave's CoE emergency,
 * ecat/). 0: no listener, for a slave whose EMCYs go on CAN only; co_emcy_set_listener is then not
 * declared. */
#ifndef CO_CONFIG_EMCY_LISTENER
#define CO_CONFIG_EMCY_LISTENER 1
#endif

/* 1: the dictionary's sub-entry descriptors are 6 bytes instead of 8 (co_od_sub, include/canopen/
 * od.h): a numeric value's size comes from its type, and one byte holds either the index of its
 * limits or a string's capacity (at most 255 bytes). The tables must be generated for it
 * (tools/eds2c.py --compact); the core and the drive layer read the size with co_od_sub_size(). */
#ifndef CO_CONFIG_OD_COMPACT
#define CO_CONFIG_OD_COMPACT 0
#endif

/* Width of the PDO service's hashed bit sets (co_pdo.watch, co_pdo.rpdo_filter): 64, or 32 for a
 * 32-bit processor, which tests and sets one word in a register (more values and CAN-IDs share a
 * bit, so a few more changes and frames take the slow path), or 0: no sets, every stored value
 * and every frame is looked up in the PDOs (a small slave with a few PDOs, where that search is
 * short; the smallest code). The behaviour is the same. */
#ifndef CO_CONFIG_PDO_BITS
#define CO_CONFIG_PDO_BITS 64
#endif

/* 1: the services keep their deadlines as 32-bit µs counts from a per-node epoch (co_time,
 * include/canopen/time_base.h), which the node moves forward as time passes, instead of 64-bit
 * µs times: a 32-bit processor compares and adds them in one register. The API (co_node_rx,
 * co_node_process, ...) still takes and returns 64-bit µs times, and the CiA 301 timing is the
 * same; the periods that can exceed 2^31 µs (SYNC period and window, life guarding) keep absolute
 * 64-bit API times. co_node_init() refuses an sdo_timeout_us or a co_pdo_config time of 2^31 µs or
 * more. 0: 64-bit times. */
#ifndef CO_CONFIG_TIME32
#define CO_CONFIG_TIME32 0
#endif

#ifdef __cplusplus
}
#endif

#endif
