/* A CANopen node: all of one slave's state in one caller-owned struct, so a process can run many
 * nodes and nothing in the core is global. Frames come in through co_node_rx(), leave through the
 * driver's send(), and co_node_process(now) runs every timer and says when to call it next.
 *
 *   co_node node;
 *   co_node_config cfg = co_node_default_config();
 *   cfg.node_id = 5; cfg.od = &co_od_vf_s15; cfg.values = block; cfg.driver = my_driver;
 *   co_node_init(&node, &cfg);
 *   co_node_start(&node, now);               // boot-up, PRE-OPERATIONAL
 *   for (;;) { wait for a frame or next; co_node_rx(&node, &f, now); next = co_node_process(&node, now); }
 */
#ifndef CANOPEN_NODE_H
#define CANOPEN_NODE_H

#include <stdbool.h>
#include <stdint.h>

#include "canopen/abort.h"
#include "canopen/config.h"
#include "canopen/emcy.h"
#include "canopen/errctl.h"
#include "canopen/frame.h"
#include "canopen/heartbeat.h"
#include "canopen/nmt.h"
#include "canopen/od.h"
#include "canopen/pdo.h"
#include "canopen/sdo_server.h"
#include "canopen/sync.h"
#include "canopen/time_base.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What co_node_process returns when nothing is pending (the API's times are 64-bit µs). */
#define CO_TIME_NEVER UINT64_MAX

struct co_node;

/* Non-volatile storage for 0x1010/0x1011, provided by the port (a file, flash, ...). The image is
 * the first persist_size bytes of the value block, tagged by the port with the OD's layout_hash. */
typedef struct co_storage {
    /* Copies len bytes at offset of the stored image into buf. False if no valid image is stored
     * for this layout (the caller then keeps the defaults). */
    bool (*load)(void *ctx, uint32_t layout_hash, uint32_t offset, uint8_t *buf, uint32_t len);
    /* Replaces the stored image atomically. False on failure (the old image must survive). */
    bool (*save)(void *ctx, uint32_t layout_hash, const uint8_t *image, uint32_t len);
    /* Forgets the stored image, so the next reset restores defaults. */
    bool (*erase)(void *ctx);
    void *ctx;
} co_storage;

/* Communication events an application (a drive) reacts to, e.g. by its communication-loss
 * reaction. detail: the producer's node-ID for heartbeat events, the RPDO number (1-based) for
 * RPDO timeouts, 0 otherwise. */
typedef enum co_comm_event {
    CO_COMM_HEARTBEAT_LOST,     /* a monitored producer's heartbeat (0x1016) timed out */
    CO_COMM_HEARTBEAT_RESUMED,  /* it came back */
    CO_COMM_LIFE_GUARD_LOST,    /* node guarding: no guard request within guard time x factor */
    CO_COMM_LIFE_GUARD_RESUMED,
    CO_COMM_RPDO_TIMEOUT,       /* an RPDO's event timer expired without the PDO */
    CO_COMM_BUS_OFF,
    CO_COMM_ERROR_PASSIVE,
    CO_COMM_BUS_RECOVERED,      /* back to error active */
    CO_COMM_RX_OVERRUN          /* the port lost received frames */
} co_comm_event;

/* What a node tells its application. Any callback may be NULL. */
typedef struct co_node_events {
    /* The NMT state changed (including INITIALISING -> PRE-OPERATIONAL after boot-up). */
    void (*nmt_changed)(struct co_node *node, void *ctx, co_nmt_state from, co_nmt_state to);
    /* A reset node or reset communication is about to run: the application resets its own state
     * (a drive: back to 'switch on disabled', speed 0) on a node reset. */
    void (*reset)(struct co_node *node, void *ctx, bool whole_node);
    /* A communication event (see co_comm_event). */
    void (*comm)(struct co_node *node, void *ctx, co_comm_event event, uint32_t detail);
    void *ctx;
} co_node_events;

/* Node-wide options a drive may set. */
#define CO_NODE_COMM_READ_ONLY_IN_OPERATIONAL 0x01u /* 0x1000-0x1FFF refuse SDO writes in OPERATIONAL */
#define CO_NODE_GUARD_TOGGLE_FIRST_SET 0x02u /* first node-guarding answer has toggle 1 (not CiA 301) */
#define CO_NODE_EMCY_RESET_EACH        0x04u /* error-reset EMCY on every clear, not only the last */
#define CO_NODE_ERR_REG_NO_GENERIC     0x08u /* 0x1001 gets no automatic generic bit (bit 0) */
#define CO_NODE_COMM_EMCY_BY_APP       0x10u /* error control/bus EMCYs left to the comm callback */
/* Objects sdo_hidden_first..sdo_hidden_last are internal to the device: every SDO request on
 * them (upload, download, segmented or block) aborts 0x06020000 "object does not exist" before
 * any other check (sub-index, access, size, value), as on a card whose dictionary ends before
 * them. The application still reads and writes them (CO_ORIGIN_APP), and a PDO cannot map them
 * unless their EDS PDOMapping says so. */
#define CO_NODE_SDO_HIDDEN_RANGE       0x20u
/* An expedited SDO upload of a numeric entry of 1 to 3 bytes in 0x1000-0x1FFF (the
 * communication profile area) answers 0x43, four bytes indicated, with the value zero-extended,
 * instead of CiA 301's exact size (0x4F/0x4B/0x47), as a card whose communication objects are
 * all read as 32-bit words. Strings and DOMAINs, and every other index, keep their exact size. */
#define CO_NODE_SDO_UPLOAD_COMM_AS_32  0x40u

typedef struct co_node_config {
    const co_od *od;
    uint8_t *values;          /* od->value_size bytes, owned by the caller */
    uint8_t node_id;          /* 1..127 */
    co_driver driver;
    const co_storage *storage; /* NULL: no non-volatile storage (0x1010 aborts 0x08000020) */
    co_node_events events;
    /* 0x1029 sub 1 to apply when the dictionary has none: 0 PRE-OPERATIONAL (CiA 301 default),
     * 1 no change, 2 STOPPED. */
    uint8_t comm_error_behaviour;
    /* Work area of the partial store/restore (0x1010/0x1011 sub 2-4), at least od->persist_size
     * bytes; only used during the write, so nodes run from one thread may share one. NULL: those
     * sub-entries abort 0x08000020. */
    uint8_t *store_scratch;
    uint32_t store_scratch_size;
    uint32_t options;         /* CO_NODE_* */
    uint32_t sdo_timeout_us;  /* 0: CO_SDO_TIMEOUT_US */
    uint16_t sdo_hidden_first; /* with CO_NODE_SDO_HIDDEN_RANGE: the first and last index SDO */
    uint16_t sdo_hidden_last;  /* does not show (inclusive) */
    co_pdo_config pdo;        /* PDO behaviour where drives differ; all zero: CiA 301 */
} co_node_config;

/* Counters: nothing is dropped without being counted. A received frame counts once in
 * rx_frames and at most once in rx_malformed or rx_ignored. */
typedef struct co_node_stats {
    uint32_t rx_frames;       /* frames handed to co_node_rx */
    uint32_t rx_malformed;    /* dropped: wrong length, RTR where none is allowed, bad command */
    uint32_t rx_ignored;      /* not for this node, or not allowed in the NMT state */
    uint32_t tx_frames;       /* frames the driver accepted */
    uint32_t tx_deferred;     /* times the driver refused and the core queued */
    uint32_t tx_dropped;      /* frames lost because the core's own queue was full */
    uint32_t sdo_aborts;      /* aborts sent */
} co_node_stats;

typedef struct co_tx_queue {
    co_frame frames[CO_TX_QUEUE_LEN];
    uint16_t head; /* next to send */
    uint16_t count;
} co_tx_queue;

typedef struct co_node {
    /* The fields read most often come first, then the EMCY producer (its scalars lead its
     * struct): on a Thumb-2 microcontroller a load or store with a short offset from the node
     * (bytes below 32, halfwords below 64, words below 128) is 2 bytes shorter. */
    const co_od *od;
    uint8_t *values;
    uint8_t node_id;
    co_nmt_state nmt_state;
    uint16_t sdo_rx_cob;      /* SDO server request COB-ID (client -> server) */
    uint16_t sdo_tx_cob;      /* SDO server response COB-ID */
    co_time now;              /* time of the latest co_node_rx / co_node_process call */
    co_time next;             /* earliest deadline of all services, kept by them as they change
                               * (src/od_internal.h): co_node_process has nothing to do before
                               * it and returns it at once */
    co_emcy emcy;
    co_heartbeat_producer heartbeat;
    co_sdo_server sdo;
    /* driver to options as in co_node_config: co_node_init copies them in one block */
    co_driver driver;
    const co_storage *storage;
    co_node_events events;
    uint8_t comm_error_behaviour;
    uint8_t *store_scratch;
    uint32_t store_scratch_size;
    uint32_t options;
    co_tx_queue txq;
#if CO_CONFIG_TIME32
    uint64_t epoch;           /* API time of co_time 0 (include/canopen/time_base.h) */
#endif
    co_errctl errctl;
    co_sync sync;
    co_pdo pdo;
    co_node_stats stats;
#if CO_CONFIG_EMCY_LISTENER
    co_emcy_listener emcy_listener; /* co_emcy_set_listener, NULL: none */
    void *emcy_listener_ctx;
#endif
    co_od_hook hooks[CO_MAX_HOOKS]; /* in registration order */
    uint8_t hook_count;
#if CO_HOOK_MAP_ENTRIES > 0
    /* Who handles od->entries[e] (see co_node_hook_slot in src/od_internal.h), for the first
     * CO_HOOK_MAP_ENTRIES entries, so a read or write finds its hook without a search. */
    uint8_t hook_map[CO_HOOK_MAP_ENTRIES];
#endif
} co_node;

/* The layout of co_node and of the dictionary tables as the file that expands this macro sees
 * them: the switches that change a struct (CO_CONFIG_TIME32, CO_CONFIG_OD_COMPACT,
 * CO_CONFIG_PDO_BITS) as CO_LAYOUT_* bits, and the size of co_node, which every CO_* size of
 * include/canopen/config.h, emcy.h and errctl.h changes, in bits 8-31. The inline co_node_init()
 * below passes it from the caller's file, and the library refuses a node whose caller was built
 * with other switches than itself (two files with different -D or user headers would otherwise
 * disagree silently on where every field of co_node is). */
#define CO_LAYOUT_TIME32 0x01u     /* CO_CONFIG_TIME32 1 */
#define CO_LAYOUT_OD_COMPACT 0x02u /* CO_CONFIG_OD_COMPACT 1 */
#define CO_LAYOUT_PDO_BITS32 0x04u /* CO_CONFIG_PDO_BITS 32 */
#define CO_LAYOUT_SIGNATURE                                                              \
    (((uint32_t)sizeof(co_node) << 8) | (CO_CONFIG_TIME32 ? CO_LAYOUT_TIME32 : 0u) |     \
     (CO_CONFIG_OD_COMPACT ? CO_LAYOUT_OD_COMPACT : 0u) |                                \
     (CO_CONFIG_PDO_BITS == 32 ? CO_LAYOUT_PDO_BITS32 : 0u))

/* A config with every optional field at its default. */
co_node_config co_node_default_config(void);

/* co_node_init() with the caller's layout signature (CO_LAYOUT_SIGNATURE): false, with nothing
 * written, when it is not the library's. Call co_node_init(), which passes it. */
bool co_node_init_layout(co_node *node, const co_node_config *cfg, uint32_t layout);

/* Sets the node up from cfg (values from defaults; nothing is sent). Returns false on a bad
 * config: NULL od/values/send, node-ID outside 1..127, a caller built with other layout switches
 * or sizes than the library (co_layout_mismatch() says which; nothing is written), a behaviour or
 * a time this build cannot honour (include/canopen/config.h), or a dictionary with limits this
 * build cannot check (CO_CONFIG_OD_WIDE_LIMITS 0) - found by the walk that writes the defaults, so
 * after that refusal the node and the value block hold what the walk had written, and neither is
 * usable. */
static inline bool co_node_init(co_node *node, const co_node_config *cfg)
{
    return co_node_init_layout(node, cfg, CO_LAYOUT_SIGNATURE);
}

/* Why co_node_init() refuses a caller built with layout signature layout: NULL when it is the
 * library's, otherwise a sentence naming the switch that differs (the first of CO_CONFIG_TIME32,
 * CO_CONFIG_OD_COMPACT, CO_CONFIG_PDO_BITS, then the sizes), e.g. for a log line:
 *   const char *why = co_layout_mismatch(CO_LAYOUT_SIGNATURE); */
const char *co_layout_mismatch(uint32_t layout);

/* Leaves INITIALISING: loads stored values, sends the boot-up message, enters PRE-OPERATIONAL. */
void co_node_start(co_node *node, uint64_t now);

/* Hands one received frame to the node. Frames for other nodes are ignored, malformed ones dropped
 * and counted; nothing here can crash or change a value it should not. */
void co_node_rx(co_node *node, const co_frame *frame, uint64_t now);

/* Runs every timer due at now and sends what is due. Returns the absolute time at which it must be
 * called again (CO_TIME_NEVER if nothing is pending); calling it earlier is harmless and cheap
 * (a few compares while nothing is due). */
uint64_t co_node_process(co_node *node, uint64_t now);

/* Tells the node the driver has room again: sends what the core had queued. */
void co_node_tx_ready(co_node *node);

/* Sends a frame through the ordered queue. Returns false if it had to be dropped (counted). */
bool co_node_send(co_node *node, const co_frame *frame);

/* Registers a hook for objects index_first..index_last (see co_od_hook). Later registrations win
 * over earlier ones for the same index, and over the core's own handling of the communication
 * objects it implements (0x1003, 0x1005-0x1007, 0x100C/0x100D, 0x1010/0x1011, 0x1014-0x1017,
 * 0x1019, 0x1029, 0x1400-0x1BFF: see co_pdo_param_written and its siblings, which such a hook
 * calls to chain). False when CO_MAX_HOOKS are in use. */
bool co_node_add_hook(co_node *node, const co_od_hook *hook);

/* The registered hook covering index, or NULL (the core's own handlers are not hooks). */
const co_od_hook *co_node_find_hook(const co_node *node, uint16_t index);

#ifdef __cplusplus
}
#endif

#endif
