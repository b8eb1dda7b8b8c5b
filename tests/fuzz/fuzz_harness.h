/* Fuzz harness shared by every libFuzzer target in tests/fuzz: one node (a plain co_node on a
 * test dictionary, or a whole drive with its dictionary and drive layer) driven only through the
 * public API by a byte string read as a header and a sequence of operations (frames, time steps,
 * bus events, drive events). Invariants (docs/robustness.md) are checked after every operation and
 * on every frame the node sends; a violation prints what was seen and aborts, which libFuzzer
 * records as a crash.
 *
 * Input format (bytes missing at the end read as 0):
 *   header, 8 bytes
 *     h0  node-ID = 1 + h0 % 127
 *     h1  dictionary, protocol targets only: h1 % (2 + drives): 0 od/test/test.eds,
 *         1 od/test/test_sparse.eds, 2 + k the k-th drive of the registry with its drive layer
 *     h2  bit 0 no storage, bit 1 no store scratch, bit 2 saves fail, bit 3 NMT start after
 *         boot-up, bit 4 SDO timeout 50 ms, bit 5 clock starts at 10^12 us,
 *         bits 6-7 0x1029 fallback (3 -> 0x80) - plain nodes
 *     h3  co_node_config.options (CO_NODE_*), plain nodes only
 *     h4  co_pdo_config.flags (CO_PDO_*), plain nodes only
 *     h5  co_pdo_config.rpdo_dummy_mask, plain nodes only
 *     h6  co_pdo_config units and abort codes, bits 6-7 two more CO_PDO_* flags, plain nodes
 *         only (see fuzz_harness.c)
 *     h7  drives: h7 % 4 settings follow, each a selector byte and an int32 (LE), applied with
 *         co_drive_set_setting() before co_drive_start(); plain nodes: the size of the DOMAIN objects
 *         (h7 x 61 bytes), which a hook of the application streams
 *   operations: an opcode byte (op % FZ_OP_COUNT) and its operands (below). An operation a target
 *   does not enable is skipped (only its opcode byte is consumed). The input ends after 4096
 *   operations or after the node's 8th reset (FZ_MAX_RESETS: boot-ups after the set-up's).
 *
 * Dictionary selectors ("entry sel", 2 bytes LE, then "sub sel") pick the (sel % n)-th object of
 * the node's dictionary and the (sel % m)-th of its sub-entries, so seeds stay meaningful while
 * mutations stay inside the dictionary.
 *
 * The set-up (what the build reads of the header, and a drive's settings) is built and started
 * once; the state it leaves is kept and the next input with the same set-up starts from a copy of
 * it, byte for byte what a fresh build gives (FZ_CHECK_SNAPSHOT=1 builds anyway and compares;
 * FZ_NO_SNAPSHOT=1 and FZ_TRACE=1 always build). */
#ifndef FUZZ_HARNESS_H
#define FUZZ_HARNESS_H

#include <stddef.h>
#include <stdint.h>

enum fz_op {
    FZ_OP_RAW = 0,       /* id lo, id hi (& 0x7FF), flags (bit 0 RTR), dlc (& 0x0F), data */
    FZ_OP_REL,           /* fn, flags|dlc: COB-ID base fn & 0x0F (fz_bases) + node-ID (bit 7:
                            a neighbour's, bit 6: none), flags|dlc bits 0-3 dlc, bit 4 RTR */
    FZ_OP_SDO,           /* 8 bytes: a request on 0x600 + node-ID */
    FZ_OP_NMT,           /* cmd sel, target sel, [raw bytes]: NMT frame or local command */
    FZ_OP_TIME,          /* mode, lo, hi: time step (to / before / after the next deadline, or
                            a delta), running every deadline on the way */
    FZ_OP_PROCESS,       /* co_node_process / co_drive_process at the present time */
    FZ_OP_BUS,           /* b: bit 0 the port refuses frames, bit 1 tx_ready, bit 4 bus state
                            (bits 2-3), bit 5 rx overrun (bits 6-7 + 1 frames) */
    FZ_OP_SDO_WRITE,     /* entry sel, sub sel, mode, 4 value bytes: expedited download */
    FZ_OP_SDO_READ,      /* entry sel, sub sel: expedited (or first segmented) upload */
    FZ_OP_LIMIT,         /* sel lo, sel hi, which: a limited sub-entry just above its high
                            limit, just below its low limit, at the high or at the low limit */
    FZ_OP_SEG_WRITE,     /* entry sel, sub sel, opts, len, data: segmented download */
    FZ_OP_BLOCK_WRITE,   /* entry sel, sub sel, opts, len, data: block download */
    FZ_OP_UPLOAD,        /* entry sel, sub sel, opts, blksize: segmented or block upload, as a
                            client following the server's answers */
    FZ_OP_REMAP,         /* pdo sel, opts, count, count x (entry sel, sub sel), type, cob lo/hi:
                            the CiA 301 remapping procedure through SDO */
    FZ_OP_SYNC,          /* opts, counter: a SYNC on the configured COB-ID */
    FZ_OP_RPDO,          /* pdo sel, opts, 8 data bytes: a frame on an RPDO's COB-ID */
    FZ_OP_TPDO_RTR,      /* pdo sel, dlc: a remote request on a TPDO's COB-ID */
    FZ_OP_HEARTBEAT,     /* sel, state sel, dlc: a heartbeat of a producer 0x1016 monitors */
    FZ_OP_GUARD,         /* dlc: node guarding request (RTR on 0x700 + node-ID) */
    FZ_OP_APP,           /* kind, a, b, c: application API (TPDO request; plain nodes: EMCY raise
                            / clear, co_od_write with CO_ORIGIN_APP) */
    FZ_OP_DRIVE,         /* kind, a, b: drive API (inject fault, clear cause, mains, fault
                            reset) - drives only */
    FZ_OP_COUNT
};

#define FZ_BIT(op) (1u << (op))
#define FZ_ALL_OPS ((1u << FZ_OP_COUNT) - 1u)
/* What every target feeds besides its own concern: raw frames, SDO requests (to configure),
 * NMT, time and the port's events. */
#define FZ_BASE_OPS                                                                      \
    (FZ_BIT(FZ_OP_RAW) | FZ_BIT(FZ_OP_REL) | FZ_BIT(FZ_OP_SDO) | FZ_BIT(FZ_OP_NMT) |     \
     FZ_BIT(FZ_OP_TIME) | FZ_BIT(FZ_OP_PROCESS) | FZ_BIT(FZ_OP_BUS))

/* What one target feeds. */
typedef struct fz_target {
    const char *name;
    uint32_t ops;         /* FZ_BIT(FZ_OP_*) of the operations enabled */
    const char *drive_id; /* a drive target: this drive of the registry; NULL: header h1 picks */
} fz_target;

/* Runs one input; returns 0 (libFuzzer's convention) or aborts on a violated invariant. */
int fz_run(const fz_target *target, const uint8_t *data, size_t size);

#endif
