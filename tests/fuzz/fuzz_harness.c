/* Fuzz harness: see fuzz_harness.h for the input format and docs/robustness.md for the invariants.
 * Everything here is test code: it keeps its state in statics (reset for every input) and reads the
 * node's structs to check them, but drives the node only through the public API. */
#include "fuzz_harness.h"

#include <math.h>
#include <stddef.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "canopen/drive.h"
#include "canopen/node.h"
#include "canopen/store.h"
#include "od_test.h"
#include "od_test_sparse.h"

#define FZ_MAX_FRAMES_PER_CALL 600u /* a block upload sub-block is 127 frames: more is a storm */
#define FZ_LOG_MAX 1024u
#define FZ_REF_MAX 2048u
#define FZ_PDO_MAX 512u
#define FZ_STORE_MAX 16384u
/* An input ends after this many resets of the node (boot-ups after the set-up's; the seeds have
 * at most 7). A reset costs as much as dozens of other operations, and the fuzzer kept inputs
 * of 30 and more resets in a row for their hit counts, which tell nothing new: those inputs took
 * half of fuzz_sdo's time. */
#define FZ_MAX_RESETS 8u

/* Known bugs, each with its failing reproducer in tests/unit/test_regressions.c: while set, the
 * harness lets them pass so the fuzzers look further. Set to 0 once the bug is fixed. */
#ifndef FZ_TOLERATE_SYNC_RESTRICTED_ID
#define FZ_TOLERATE_SYNC_RESTRICTED_ID 0 /* src/sync.c took CiA 301 7.3.5 IDs: fixed */
#endif

/* --- state of the run ------------------------------------------------------------------------ */

/* What one input's run holds. Small on purpose: a snapshot of the set-up (below) copies it. */
typedef struct fz_world {
    const fz_target *target;
    const uint8_t *in;
    size_t in_size, in_pos;

    const co_od *od;
    const co_drive_desc *desc; /* NULL: a plain node */
    co_drive *drive;
    co_node *node;
    uint8_t *values;
    uint8_t *scratch;
    bool started;

    uint64_t now, next;
    bool refuse;             /* the port's queue is full */
    uint8_t ids[32];         /* every node-ID the node had (a drive may change it at a reset) */
    uint32_t accepted;       /* frames the port took */
    uint32_t resets;         /* boot-ups the node sent (the input's count starts at 0) */
    uint32_t rx_given;       /* frames handed to the node */

    /* The call in progress: frames it produced (accepted at once or left in the core's queue). */
    uint16_t q_head0, q_count0;
    uint32_t flushed;
    uint32_t call_frames;

    /* The application's DOMAIN objects (plain nodes): streamed through a hook. */
    uint32_t domain_size;    /* bytes an upload gives */
    uint32_t domain_written; /* bytes of the download in progress */
    bool domain_open;
} fz_world;

static fz_world W;

/* Frames the call in progress produced, in order (call_begin empties it). */
static struct {
    co_frame frames[FZ_LOG_MAX];
    uint32_t count;
} Log;

/* Storage the port would give. */
static struct {
    uint8_t image[FZ_STORE_MAX];
    uint32_t len, hash;
    bool valid, save_fails;
} Store;

/* What the harness knows of one dictionary, found once per process: its sub-entries by kind, and
 * the node's memory, allocated once with the exact sizes (ASan sees overruns) and reused by every
 * input on that dictionary, so a snapshot of the set-up (below) holds valid pointers. */
typedef struct fz_dict {
    const co_od *od;
    const co_drive_desc *desc;
    co_od_ref limited[FZ_REF_MAX]; /* in dictionary order */
    uint32_t limited_count;
    co_od_ref booleans[FZ_REF_MAX];
    uint32_t boolean_count;
    uint16_t *limited_at;          /* [value offset]: 1 + the limited[] starting there, or 0 */
    uint16_t *boolean_at;          /* [value offset]: 1 + the booleans[] there, or 0 */
    co_od_ref rmap[FZ_REF_MAX], tmap[FZ_REF_MAX];
    uint32_t rmap_count, tmap_count;
    uint16_t rpdo_comm[FZ_PDO_MAX], tpdo_comm[FZ_PDO_MAX];
    uint32_t rpdo_count, tpdo_count;
    void *object;                  /* the co_node or co_drive */
    uint8_t *values;               /* the node's value block */
    uint8_t *scratch;              /* the store scratch */
    uint8_t *checked;              /* the values as check_values last saw them */
    bool checked_valid;            /* false: check_values looks at every value */
} fz_dict;

#define FZ_DICT_MAX 16u
static fz_dict Dicts[FZ_DICT_MAX];
static fz_dict *D; /* the dictionary of the run */
static bool trace; /* FZ_TRACE=1 in the environment: print every operation and frame */

static void trace_frame(const char *what, const co_frame *f)
{
    if (!trace) {
        return;
    }
    fprintf(stderr, "  %s %03X%s [%u]", what, f->id, (f->flags & CO_FRAME_RTR) != 0u ? " RTR" : "",
            f->dlc);
    for (uint32_t i = 0; i < f->dlc && i < 8u && (f->flags & CO_FRAME_RTR) == 0u; i++) {
        fprintf(stderr, " %02X", f->data[i]);
    }
    fprintf(stderr, "  (t=%llu, NMT 0x%02X)\n", (unsigned long long)W.now, W.node->nmt_state);
}

static void fail(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "\n*** fuzz invariant violated (%s, %s, node-ID %u, t=%llu us): ",
            W.target != NULL ? W.target->name : "?", W.od != NULL ? W.od->name : "?",
            W.node != NULL ? W.node->node_id : 0u, (unsigned long long)W.now);
    vfprintf(stderr, fmt, ap);
    fprintf(stderr, "\n");
    va_end(ap);
    abort();
}

/* --- input ----------------------------------------------------------------------------------- */

static bool in_more(void)
{
    return W.in_pos < W.in_size;
}

static uint8_t in_u8(void)
{
    return W.in_pos < W.in_size ? W.in[W.in_pos++] : 0u;
}

static uint16_t in_u16(void)
{
    uint16_t lo = in_u8();
    return (uint16_t)(lo | (in_u8() << 8));
}

static uint32_t in_u32(void)
{
    uint32_t lo = in_u16();
    return lo | ((uint32_t)in_u16() << 16);
}

/* --- reading the dictionary as it stands ----------------------------------------------------- */

static bool od_u32(uint16_t index, uint8_t sub, uint32_t *v)
{
    co_od_ref ref;
    if (co_od_locate(W.od, index, sub, &ref) != CO_ABORT_NONE || ref.sub->type == CO_DOMAIN ||
        ref.sub->size == 0u || ref.sub->size > 4u) {
        return false;
    }
    const uint8_t *p = W.values + co_od_value_offset(ref.entry, ref.sub);
    uint32_t x = 0;
    for (uint32_t i = ref.sub->size; i > 0u; i--) {
        x = (x << 8) | p[i - 1u];
    }
    *v = x;
    return true;
}

static uint32_t od_u32_or(uint16_t index, uint8_t sub, uint32_t fallback)
{
    uint32_t v;
    return od_u32(index, sub, &v) ? v : fallback;
}

/* Bytes a PDO's mapping object maps (sum of the lengths of entries 1..sub 0), 0xFF if not whole. */
static uint32_t mapped_bytes(uint16_t map_index)
{
    uint32_t n = od_u32_or(map_index, 0, 0);
    uint32_t bits = 0;
    for (uint32_t i = 1; i <= n && i <= 0xFFu; i++) {
        bits += od_u32_or(map_index, (uint8_t)i, 0) & 0xFFu;
    }
    return (bits % 8u) != 0u ? 0xFFu : bits / 8u;
}

/* CiA 301 §7.3.5: CAN-IDs no PDO, EMCY or SYNC may use. */
static bool restricted_can_id(uint16_t id)
{
    return id <= 0x07Fu || (id >= 0x101u && id <= 0x180u) || (id >= 0x581u && id <= 0x5FFu) ||
           (id >= 0x601u && id <= 0x67Fu) || (id >= 0x6E0u && id <= 0x6FFu) || id >= 0x701u;
}

static bool known_abort(uint32_t code)
{
    static const uint32_t codes[] = {
        CO_ABORT_TOGGLE, CO_ABORT_TIMEOUT, CO_ABORT_COMMAND, CO_ABORT_BLOCK_SIZE,
        CO_ABORT_SEQUENCE, CO_ABORT_CRC, CO_ABORT_OUT_OF_MEMORY, CO_ABORT_UNSUPPORTED_ACCESS,
        CO_ABORT_WRITE_ONLY, CO_ABORT_READ_ONLY, CO_ABORT_NO_OBJECT, CO_ABORT_NOT_MAPPABLE,
        CO_ABORT_PDO_LENGTH, CO_ABORT_PARAM_INCOMPATIBLE, CO_ABORT_DEVICE_INCOMPATIBLE,
        CO_ABORT_HARDWARE, CO_ABORT_TYPE_LENGTH, CO_ABORT_TYPE_TOO_LONG, CO_ABORT_TYPE_TOO_SHORT,
        CO_ABORT_NO_SUBINDEX, CO_ABORT_VALUE_RANGE, CO_ABORT_VALUE_TOO_HIGH,
        CO_ABORT_VALUE_TOO_LOW, CO_ABORT_MAX_BELOW_MIN, CO_ABORT_GENERAL, CO_ABORT_STORE,
        CO_ABORT_LOCAL_CONTROL, CO_ABORT_DEVICE_STATE, CO_ABORT_NO_DICTIONARY, CO_ABORT_NO_DATA,
        0x06040001u /* general parameter incompatibility: not in abort.h, but CiA 301 */};
    for (size_t i = 0; i < sizeof codes / sizeof codes[0]; i++) {
        if (codes[i] == code) {
            return true;
        }
    }
    return false;
}

/* --- frames the node sends ------------------------------------------------------------------- */

static bool is_tpdo_frame(const co_node *n, const co_frame *f)
{
    bool padded = (n->pdo.cfg.flags & CO_PDO_TPDO_DLC_8) != 0u;
    for (uint32_t i = 0; i < D->tpdo_count; i++) {
        uint16_t comm = D->tpdo_comm[i];
        uint32_t cob;
        if (!od_u32(comm, 1, &cob) || (cob & 0x80000000u) != 0u || (cob & 0x7FFu) != f->id) {
            continue;
        }
        uint32_t type = od_u32_or(comm, 2, 254);
        if (type >= 241u && type <= 251u) {
            continue;
        }
        uint32_t size = mapped_bytes((uint16_t)(comm + 0x200u));
        if (size == f->dlc) {
            return true;
        }
        if (padded && f->dlc == 8u && size < 8u) {
            /* CO_PDO_TPDO_DLC_8: the bytes after the mapped ones are zero. Several TPDOs may
               share a COB-ID, so a frame that is not this one's may still be another's. */
            bool zero_tail = true;
            for (uint32_t b = size; b < 8u; b++) {
                zero_tail = zero_tail && f->data[b] == 0u;
            }
            if (zero_tail) {
                return true;
            }
        }
    }
    return false;
}

static bool is_emcy_frame(const co_frame *f)
{
    uint32_t cob;
    if (od_u32(0x1014, 0, &cob)) {
        if ((cob & 0x80000000u) != 0u || (cob & 0x7FFu) != f->id) {
            return false;
        }
    } else if (f->id != 0x80u + W.node->node_id) {
        return false;
    }
    return f->dlc == 8u;
}

static bool is_sync_frame(const co_frame *f)
{
    uint32_t cob, period;
    if (!od_u32(0x1005, 0, &cob) || (cob & 0x40000000u) == 0u || (cob & 0x7FFu) != f->id ||
        !od_u32(0x1006, 0, &period) || period == 0u) {
        return false;
    }
    uint32_t overflow = od_u32_or(0x1019, 0, 0);
    if (overflow == 0u) {
        return f->dlc == 0u;
    }
    return f->dlc == 1u && f->data[0] >= 1u && f->data[0] <= overflow;
}

/* Checks a frame the node hands to the port (direct: produced now, with the node's state as it
 * is; otherwise it waited in the core's queue and only its identity is checked). */
static void check_frame(const co_frame *f, bool direct)
{
    co_node *n = W.node;
    if (f->dlc > 8u) {
        fail("frame 0x%03X with DLC %u", f->id, f->dlc);
    }
    if (f->flags != 0u) {
        fail("frame 0x%03X sent with flags 0x%02X (a slave never sends RTR)", f->id, f->flags);
    }
    if (f->id > 0x7FFu) {
        fail("frame with a CAN-ID above 11 bits: 0x%X", f->id);
    }
    bool alive = n->nmt_state == CO_NMT_PRE_OPERATIONAL || n->nmt_state == CO_NMT_OPERATIONAL;
#if FZ_TOLERATE_SYNC_RESTRICTED_ID
    if (restricted_can_id(f->id) && is_sync_frame(f)) {
        return; /* known bug, test_regressions.c: 0x1005 takes a restricted CAN-ID */
    }
#endif
    uint8_t id = (uint8_t)(f->id & 0x7Fu);
    if (!direct && id != n->node_id && (W.ids[id / 8u] & (1u << (id % 8u))) != 0u &&
        ((f->id & 0x780u) == 0x580u || (f->id & 0x780u) == 0x700u)) {
        return; /* queued under a node-ID the node had before */
    }
    if (f->id == 0x700u + n->node_id) {
        uint8_t s = (uint8_t)(f->data[0] & 0x7Fu);
        if (f->dlc != 1u || (s != 0u && s != 4u && s != 5u && s != 0x7Fu)) {
            fail("error control frame 0x%03X dlc %u byte 0x%02X", f->id, f->dlc, f->data[0]);
        }
        if (direct && s != 0u && s != (uint8_t)n->nmt_state) {
            fail("error control frame shows state 0x%02X in state 0x%02X", s, n->nmt_state);
        }
        return;
    }
    if (f->id == 0x580u + n->node_id) {
        if (f->dlc != 8u) {
            fail("SDO response with DLC %u", f->dlc);
        }
        if (direct && !alive) {
            fail("SDO response sent in NMT state 0x%02X", n->nmt_state);
        }
        if (f->data[0] == 0x80u && n->sdo.state == CO_SDO_IDLE) {
            uint32_t code = co_get_le32(&f->data[4]);
            if (!known_abort(code)) {
                fail("SDO abort with unknown code 0x%08X", code);
            }
        }
        return;
    }
    if (restricted_can_id(f->id)) {
        fail("frame on restricted CAN-ID 0x%03X (CiA 301 7.3.5)", f->id);
    }
    if (!direct) {
        return;
    }
    if (alive && is_emcy_frame(f)) {
        return;
    }
    if (alive && is_sync_frame(f)) {
        return;
    }
    if (n->nmt_state == CO_NMT_OPERATIONAL && is_tpdo_frame(n, f)) {
        return;
    }
    fail("frame 0x%03X dlc %u in NMT state 0x%02X is none of this node's (EMCY, SYNC, TPDO as "
         "configured now)", f->id, f->dlc, n->nmt_state);
}

static void log_frame(const co_frame *f)
{
    /* a boot-up: the heartbeat frame with state 0 (INITIALISING), sent only by a reset */
    if (f->id >= 0x701u && f->id <= 0x77Fu && f->dlc == 1u && f->data[0] == 0u) {
        W.resets++;
    }
    if (Log.count < FZ_LOG_MAX) {
        Log.frames[Log.count++] = *f;
    }
}

static bool port_send(void *ctx, const co_frame *f)
{
    (void)ctx;
    bool direct = W.node->txq.count == 0u;
    trace_frame(W.refuse ? "tx(refused)" : (direct ? "tx" : "tx(queued)"), f);
    check_frame(f, direct);
    if (++W.call_frames > FZ_MAX_FRAMES_PER_CALL) {
        fail("more than %u frames from one call", FZ_MAX_FRAMES_PER_CALL);
    }
    if (W.refuse) {
        return false;
    }
    W.accepted++;
    if (direct) {
        log_frame(f);
    } else {
        W.flushed++;
    }
    return true;
}

static void call_begin(void)
{
    W.ids[W.node->node_id / 8u] = (uint8_t)(W.ids[W.node->node_id / 8u] | (1u << (W.node->node_id % 8u)));
    W.q_head0 = W.node->txq.head;
    W.q_count0 = W.node->txq.count;
    W.flushed = 0;
    W.call_frames = 0;
    Log.count = 0;
}

/* Frames the call left in the core's queue are frames it produced too. */
static void call_end(void)
{
    W.ids[W.node->node_id / 8u] = (uint8_t)(W.ids[W.node->node_id / 8u] | (1u << (W.node->node_id % 8u)));
    const co_tx_queue *q = &W.node->txq;
    if (q->count > CO_TX_QUEUE_LEN || q->head >= CO_TX_QUEUE_LEN) {
        fail("transmit queue out of bounds: head %u count %u", q->head, q->count);
    }
    uint32_t kept = W.q_count0 >= W.flushed ? W.q_count0 - W.flushed : 0u;
    if (q->count < kept) {
        fail("transmit queue lost frames: %u kept, %u left", kept, q->count);
    }
    uint32_t fresh = q->count - kept;
    for (uint32_t k = 0; k < fresh; k++) {
        const co_frame *f = &q->frames[(q->head + kept + k) & (CO_TX_QUEUE_LEN - 1u)];
        check_frame(f, false);
        log_frame(f);
    }
    if (W.node->stats.tx_frames != W.accepted) {
        fail("stats.tx_frames %u but the port took %u", W.node->stats.tx_frames, W.accepted);
    }
}

/* --- storage --------------------------------------------------------------------------------- */

static bool store_load(void *ctx, uint32_t hash, uint32_t offset, uint8_t *buf, uint32_t len)
{
    (void)ctx;
    if (!Store.valid || hash != Store.hash || offset > Store.len ||
        len > Store.len - offset) {
        return false;
    }
    memcpy(buf, Store.image + offset, len);
    return true;
}

static bool store_save(void *ctx, uint32_t hash, const uint8_t *image, uint32_t len)
{
    (void)ctx;
    if (Store.save_fails || len > FZ_STORE_MAX) {
        return false;
    }
    memcpy(Store.image, image, len);
    Store.len = len;
    Store.hash = hash;
    Store.valid = true;
    return true;
}

static bool store_erase(void *ctx)
{
    (void)ctx;
    Store.valid = false;
    return true;
}

/* --- the application's DOMAIN objects ------------------------------------------------------- */

/* Checks the streaming contract of sdo_server.h: pieces come in order from offset 0, at most
 * CO_SDO_BUF_SIZE each, never beyond an announced total; a piece starting with 0xEE is refused
 * (the application's abort must reach the client). */
static co_abort domain_write(co_node *node, void *ctx, co_od_ref ref, uint32_t offset,
                             const uint8_t *data, uint32_t len, uint32_t total, bool last)
{
    (void)node;
    (void)ctx;
    (void)ref;
    if (offset == 0u) {
        W.domain_written = 0;
        W.domain_open = true;
    }
    if (!W.domain_open || offset != W.domain_written || len > CO_SDO_BUF_SIZE ||
        (total != 0u && offset + len > total) || (last && total != 0u && offset + len != total)) {
        fail("domain_write out of order: offset %u (expected %u), len %u, total %u, last %d",
             offset, W.domain_written, len, total, last);
    }
    W.domain_written += len;
    if (last) {
        W.domain_open = false;
    }
    return (len != 0u && data[0] == 0xEEu) ? CO_ABORT_HARDWARE : CO_ABORT_NONE;
}

static co_abort domain_read(co_node *node, void *ctx, co_od_ref ref, uint32_t offset,
                            uint8_t *buf, uint32_t cap, uint32_t *len, uint32_t *total)
{
    (void)node;
    (void)ctx;
    (void)ref;
    if (offset > W.domain_size) {
        fail("domain_read beyond the end: offset %u of %u", offset, W.domain_size);
    }
    uint32_t n = W.domain_size - offset < cap ? W.domain_size - offset : cap;
    for (uint32_t i = 0; i < n; i++) {
        buf[i] = (uint8_t)((offset + i) * 7u);
    }
    *len = n;
    *total = W.domain_size;
    return CO_ABORT_NONE;
}

static void add_domain_hooks(void)
{
    for (uint32_t e = 0; e < W.od->entry_count; e++) {
        const co_od_entry *entry = &W.od->entries[e];
        for (uint32_t s = 0; s < entry->sub_count; s++) {
            if (entry->subs[s].type == CO_DOMAIN && entry->index >= 0x2000u &&
                co_node_find_hook(W.node, entry->index) == NULL) {
                co_od_hook hook;
                memset(&hook, 0, sizeof hook); /* the padding too: snapshots compare bytes */
                hook.index_first = hook.index_last = entry->index;
                hook.domain_read = domain_read;
                hook.domain_write = domain_write;
                (void)co_node_add_hook(W.node, &hook);
                break;
            }
        }
    }
}

/* --- invariants ------------------------------------------------------------------------------ */

static bool in_limits(const co_od_sub *sub, const uint8_t *v)
{
    if (sub->limit >= W.od->limit_count) {
        fail("sub-entry limit index %u beyond %u", sub->limit, W.od->limit_count);
    }
    const co_od_limit *lim = &W.od->limits[sub->limit];
    double lo_d, hi_d;
    memcpy(&lo_d, &lim->low, sizeof lo_d);
    memcpy(&hi_d, &lim->high, sizeof hi_d);
    switch (sub->type) {
    case CO_REAL32: {
        float f;
        memcpy(&f, v, sizeof f); /* little-endian host */
        return !isnan(f) && (double)f >= lo_d && (double)f <= hi_d;
    }
    case CO_REAL64: {
        double d;
        memcpy(&d, v, sizeof d);
        return !isnan(d) && d >= lo_d && d <= hi_d;
    }
    default:
        break;
    }
    uint32_t size = sub->size;
    if (size == 0u || size > 8u) {
        return true; /* strings: no numeric limit */
    }
    uint64_t u = 0;
    for (uint32_t i = size; i > 0u; i--) {
        u = (u << 8) | v[i - 1u];
    }
    if (co_type_is_signed(sub->type)) {
        if (size < 8u && (v[size - 1u] & 0x80u) != 0u) {
            u |= ~UINT64_C(0) << (8u * size);
        }
        int64_t s = (int64_t)u;
        return s >= (int64_t)lim->low && s <= (int64_t)lim->high;
    }
    return u >= lim->low && u <= lim->high;
}

static void check_limited(const co_od_ref *r)
{
    const uint8_t *v = W.values + co_od_value_offset(r->entry, r->sub);
    if (!in_limits(r->sub, v)) {
        uint64_t raw = 0;
        for (uint32_t b = r->sub->size < 8u ? r->sub->size : 8u; b > 0u; b--) {
            raw = (raw << 8) | v[b - 1u];
        }
        fail("0x%04X sub %u holds 0x%llX, outside [0x%llX, 0x%llX]", r->entry->index,
             r->sub->subindex, (unsigned long long)raw,
             (unsigned long long)W.od->limits[r->sub->limit].low,
             (unsigned long long)W.od->limits[r->sub->limit].high);
    }
}

static void check_boolean(const co_od_ref *r)
{
    if (W.values[co_od_value_offset(r->entry, r->sub)] > 1u) {
        fail("BOOLEAN 0x%04X sub %u holds %u", r->entry->index, r->sub->subindex,
             W.values[co_od_value_offset(r->entry, r->sub)]);
    }
}

/* Every limited value within its limits, every BOOLEAN 0 or 1. A value the last check saw and
 * that has not changed since is not looked at again: the values are compared with that check's
 * copy 8 bytes at a time, and only the values overlapping a changed group are checked. */
static void check_values(void)
{
    uint32_t size = W.od->value_size;
    if (!D->checked_valid) {
        for (uint32_t i = 0; i < D->limited_count; i++) {
            check_limited(&D->limited[i]);
        }
        for (uint32_t i = 0; i < D->boolean_count; i++) {
            check_boolean(&D->booleans[i]);
        }
        memcpy(D->checked, W.values, size);
        D->checked_valid = true;
        return;
    }
    if (memcmp(W.values, D->checked, size) == 0) {
        return; /* most operations change no value */
    }
    for (uint32_t block = 0; block < size; block += 64u) {
        uint32_t block_end = size - block < 64u ? size : block + 64u;
        if (memcmp(W.values + block, D->checked + block, block_end - block) == 0) {
            continue;
        }
        for (uint32_t at = block; at < block_end; at += 8u) {
            uint32_t n = block_end - at < 8u ? block_end - at : 8u;
            uint64_t now = 0, then = 0; /* fixed-size copies: no call, unlike a memcmp */
            if (n == 8u) {
                memcpy(&now, W.values + at, 8);
                memcpy(&then, D->checked + at, 8);
            } else {
                memcpy(&now, W.values + at, n);
                memcpy(&then, D->checked + at, n);
            }
            if (now == then) {
                continue;
            }
            /* A limited number is at most 8 bytes long: those overlapping [at, at + n) start
             * at most 7 bytes before it. */
            for (uint32_t b = at >= 7u ? at - 7u : 0u; b < at + n; b++) {
                uint16_t k = D->limited_at[b];
                const co_od_ref *lr = k != 0u ? &D->limited[k - 1u] : NULL;
                if (lr != NULL && co_od_value_offset(lr->entry, lr->sub) + lr->sub->size > at) {
                    check_limited(&D->limited[k - 1u]);
                }
            }
            for (uint32_t b = at; b < at + n; b++) {
                if (D->boolean_at[b] != 0u) {
                    check_boolean(&D->booleans[D->boolean_at[b] - 1u]);
                }
            }
            memcpy(D->checked + at, W.values + at, n);
        }
    }
}

static void check_node(void)
{
    co_node *n = W.node;
    if (n->node_id < 1u || n->node_id > 127u) {
        fail("node-ID %u", n->node_id);
    }
    if (W.started && n->nmt_state != CO_NMT_PRE_OPERATIONAL &&
        n->nmt_state != CO_NMT_OPERATIONAL && n->nmt_state != CO_NMT_STOPPED) {
        fail("NMT state 0x%02X is none of PRE-OPERATIONAL, OPERATIONAL, STOPPED", n->nmt_state);
    }
    if (n->txq.count > CO_TX_QUEUE_LEN || n->txq.head >= CO_TX_QUEUE_LEN) {
        fail("transmit queue head %u count %u", n->txq.head, n->txq.count);
    }
    const co_emcy *e = &n->emcy;
    if (e->queued_count > CO_EMCY_QUEUE_LEN || e->queued_head >= CO_EMCY_QUEUE_LEN ||
        e->active_count > CO_EMCY_MAX_ACTIVE || e->history_count > e->history_depth) {
        fail("EMCY queue %u/%u, active %u, history %u of %u", e->queued_count, e->queued_head,
             e->active_count, e->history_count, e->history_depth);
    }
    const co_sdo_server *s = &n->sdo;
    bool uploading = s->state == CO_SDO_UPLOAD_SEGMENTED || s->state == CO_SDO_UPLOAD_BLOCK ||
                     s->state == CO_SDO_UPLOAD_BLOCK_INITIATED;
    if ((unsigned)s->state > (unsigned)CO_SDO_UPLOAD_BLOCK_END || s->buf_len > CO_SDO_BUF_SIZE ||
        (uploading && s->buf_pos > s->buf_len)) {
        fail("SDO server state %u buf_len %u buf_pos %u", (unsigned)s->state, s->buf_len,
             s->buf_pos);
    }
    if (n->nmt_state == CO_NMT_STOPPED && s->state != CO_SDO_IDLE) {
        fail("SDO transfer still open in STOPPED");
    }
    const co_pdo *p = &n->pdo;
    if (p->rpdo_count > CO_MAX_RPDO || p->tpdo_count > CO_MAX_TPDO) {
        fail("PDO slots %u/%u", p->rpdo_count, p->tpdo_count);
    }
    for (uint32_t i = 0; i < p->rpdo_count; i++) {
        if (p->rpdo[i].head.count > CO_PDO_MAX_MAPPED || p->rpdo[i].head.size > CO_PDO_MAX_BYTES) {
            fail("RPDO %u maps %u objects, %u bytes", p->rpdo[i].head.number, p->rpdo[i].head.count,
                 p->rpdo[i].head.size);
        }
    }
    for (uint32_t i = 0; i < p->tpdo_count; i++) {
        if (p->tpdo[i].head.count > CO_PDO_MAX_MAPPED || p->tpdo[i].head.size > CO_PDO_MAX_BYTES) {
            fail("TPDO %u maps %u objects, %u bytes", p->tpdo[i].head.number, p->tpdo[i].head.count,
                 p->tpdo[i].head.size);
        }
    }
    const co_errctl *ec = &n->errctl;
    uint32_t lost = 0;
    for (uint32_t i = 0; i < CO_HB_CONSUMER_MAX; i++) {
        if (ec->hb[i].state > CO_HBC_LOST) {
            fail("heartbeat consumer %u in state %u", i + 1u, ec->hb[i].state);
        }
        lost += ec->hb[i].state == CO_HBC_LOST ? 1u : 0u;
    }
    if (lost != ec->hb_lost || (ec->toggle != 0u && ec->toggle != 0x80u) ||
        ec->bus > CO_BUS_OFF) {
        fail("error control: %u lost (counted %u), toggle 0x%02X, bus %u", lost, ec->hb_lost,
             ec->toggle, ec->bus);
    }
    if (n->stats.rx_frames != W.rx_given ||
        n->stats.rx_malformed + n->stats.rx_ignored > n->stats.rx_frames) {
        fail("rx counters: %u frames (%u given), %u malformed, %u ignored", n->stats.rx_frames,
             W.rx_given, n->stats.rx_malformed, n->stats.rx_ignored);
    }
    if (W.drive != NULL) {
        const co_drive *d = W.drive;
        if ((unsigned)d->state > (unsigned)CO_CIA402_FAULT) {
            fail("CiA 402 state %u", (unsigned)d->state);
        }
        if ((d->state == CO_CIA402_SWITCH_ON_DISABLED || d->state == CO_CIA402_FAULT) &&
            d->output) {
            fail("power stage on in %s", co_cia402_state_name(d->state));
        }
    }
    check_values();
}

/* What the drive shows after co_drive_process: the statusword's state is the state machine's. */
static void check_drive_shown(void)
{
    const co_drive *d = W.drive;
    if (d == NULL || d->desc->profile != CO_DRIVE_PROFILE_CIA402 || d->obj.statusword.sub == NULL) {
        return;
    }
    uint16_t sw = co_od_get_u16(&d->node, 0x6041, 0);
    co_cia402_state shown = co_cia402_state_of(sw);
    if (shown != d->state) {
        fail("statusword 0x%04X shows %s, state machine is in %s", sw,
             co_cia402_state_name(shown), co_cia402_state_name(d->state));
    }
}

/* --- driving the node ------------------------------------------------------------------------ */

static void do_process(void)
{
    call_begin();
    uint64_t next = W.drive != NULL ? co_drive_process(W.drive, W.now) : co_node_process(W.node, W.now);
    call_end();
    W.next = next;
    check_drive_shown();
}

static void do_rx_only(const co_frame *f)
{
    trace_frame("rx", f);
    call_begin();
    W.rx_given++;
    if (W.drive != NULL) {
        co_drive_rx(W.drive, f, W.now);
    } else {
        co_node_rx(W.node, f, W.now);
    }
    call_end();
}

static void do_rx(const co_frame *f)
{
    do_rx_only(f);
    do_process();
}

static co_frame make_frame(uint16_t id, uint8_t dlc, const uint8_t *data, bool rtr)
{
    co_frame f;
    memset(&f, 0, sizeof f);
    f.id = (uint16_t)(id & 0x7FFu);
    f.dlc = (uint8_t)(dlc & 0x0Fu);
    f.flags = rtr ? CO_FRAME_RTR : 0u;
    if (data != NULL && !rtr) {
        memcpy(f.data, data, f.dlc < 8u ? f.dlc : 8u);
    }
    return f;
}

/* The first SDO response the last request produced (or NULL). */
static const co_frame *W_resp;

static uint32_t resp_abort(void)
{
    return (W_resp != NULL && W_resp->data[0] == 0x80u) ? co_get_le32(&W_resp->data[4]) : 0u;
}

/* One SDO request frame. On an abort of a download, the object named in the abort keeps its
 * value. */
static void sdo_request(const uint8_t req[8], uint8_t dlc)
{
    static uint8_t before[FZ_STORE_MAX];
    memcpy(before, W.values, W.od->value_size);
    co_frame f = make_frame((uint16_t)(0x600u + W.node->node_id), dlc, req, false);
    uint8_t ccs = (uint8_t)(req[0] >> 5);
    bool download = ccs == 0u || ccs == 1u || ccs == 6u;
    do_rx_only(&f);
    W_resp = NULL;
    for (uint32_t i = 0; i < Log.count; i++) {
        if (Log.frames[i].id == 0x580u + W.node->node_id) {
            W_resp = &Log.frames[i];
            break;
        }
    }
    static co_frame resp;
    if (W_resp != NULL) {
        resp = *W_resp;
        W_resp = &resp;
    }
    if (W_resp != NULL && W_resp->data[0] == 0x80u && download) {
        co_od_ref ref;
        uint16_t index = co_get_le16(&W_resp->data[1]);
        if (co_od_locate(W.od, index, W_resp->data[3], &ref) == CO_ABORT_NONE &&
            ref.sub->type != CO_DOMAIN &&
            memcmp(before + co_od_value_offset(ref.entry, ref.sub),
                   W.values + co_od_value_offset(ref.entry, ref.sub), ref.sub->size) != 0) {
            fail("download of 0x%04X sub %u aborted 0x%08X but the value changed", index,
                 W_resp->data[3], co_get_le32(&W_resp->data[4]));
        }
    }
    do_process();
}

static void sdo8(const uint8_t req[8])
{
    sdo_request(req, 8);
}

static void sdo_put(uint8_t cmd, uint16_t index, uint8_t sub, uint32_t v)
{
    const uint8_t req[8] = {cmd, (uint8_t)index, (uint8_t)(index >> 8), sub,
                            (uint8_t)v, (uint8_t)(v >> 8), (uint8_t)(v >> 16), (uint8_t)(v >> 24)};
    sdo8(req);
}

/* Expedited download of n (1-4) bytes with the size indicated. */
static void sdo_write_n(uint16_t index, uint8_t sub, uint32_t v, uint32_t n)
{
    sdo_put((uint8_t)(0x23u | ((4u - n) << 2)), index, sub, v);
}

static co_od_ref pick_ref(void)
{
    uint16_t e = in_u16();
    uint8_t s = in_u8();
    co_od_ref ref;
    ref.entry = &W.od->entries[e % W.od->entry_count];
    ref.sub = ref.entry->sub_count != 0u ? &ref.entry->subs[s % ref.entry->sub_count] : NULL;
    return ref;
}

/* --- operations ------------------------------------------------------------------------------ */

static void op_raw(void)
{
    uint16_t id = in_u16();
    uint8_t flags = in_u8();
    uint8_t dlc = in_u8();
    uint8_t data[8] = {0};
    bool rtr = (flags & 1u) != 0u;
    for (uint32_t i = 0; i < (dlc & 0x0Fu) && i < 8u && !rtr; i++) {
        data[i] = in_u8();
    }
    co_frame f = make_frame(id, dlc, data, rtr);
    do_rx(&f);
}

static uint8_t neighbour(void)
{
    return (uint8_t)(W.node->node_id % 127u + 1u);
}

static void op_rel(void)
{
    static const uint16_t bases[16] = {0x000, 0x080, 0x080, 0x100, 0x180, 0x200, 0x280, 0x300,
                                       0x380, 0x400, 0x480, 0x500, 0x580, 0x600, 0x700, 0x7E5};
    uint8_t fn = in_u8();
    uint8_t fd = in_u8();
    uint16_t id = bases[fn & 0x0Fu];
    if ((fn & 0x40u) == 0u) {
        id = (uint16_t)(id + ((fn & 0x80u) != 0u ? neighbour() : W.node->node_id));
    }
    bool rtr = (fd & 0x10u) != 0u;
    uint8_t data[8] = {0};
    for (uint32_t i = 0; i < (fd & 0x0Fu) && i < 8u && !rtr; i++) {
        data[i] = in_u8();
    }
    co_frame f = make_frame(id, fd, data, rtr);
    if (id == 0x600u + W.node->node_id && !rtr) {
        sdo_request(data, (uint8_t)(fd & 0x0Fu));
    } else {
        do_rx(&f);
    }
}

static void op_sdo(void)
{
    uint8_t req[8];
    for (uint32_t i = 0; i < 8u; i++) {
        req[i] = in_u8();
    }
    sdo8(req);
}

static void op_nmt(void)
{
    static const uint8_t cmds[5] = {CO_NMT_CMD_START, CO_NMT_CMD_STOP,
                                    CO_NMT_CMD_ENTER_PRE_OPERATIONAL, CO_NMT_CMD_RESET_NODE,
                                    CO_NMT_CMD_RESET_COMMUNICATION};
    uint8_t c = in_u8();
    uint8_t t = in_u8();
    uint8_t cmd = (c & 7u) < 5u ? cmds[c & 7u] : in_u8();
    if ((c & 0x80u) != 0u) {
        if ((c & 7u) < 5u) { /* the application's local control: a valid command only */
            call_begin();
            co_nmt_command_local(W.node, (co_nmt_command)cmd, W.now);
            call_end();
            do_process();
        }
        return;
    }
    uint8_t target;
    switch (t & 3u) {
    case 0: target = W.node->node_id; break;
    case 1: target = 0; break;
    case 2: target = neighbour(); break;
    default: target = in_u8(); break;
    }
    static const uint8_t lengths[4] = {2, 1, 3, 0};
    const uint8_t data[3] = {cmd, target, in_u8()};
    co_frame f = make_frame(0x000, lengths[(t >> 2) & 3u], data, (t & 0x10u) != 0u);
    do_rx(&f);
}

/* Runs the node at each deadline up to target (at most 64 of them: the drive's ramps are exact
 * whatever the calls in between), then at target. */
static void advance_to(uint64_t target)
{
    uint32_t same = 0;
    for (uint32_t i = 0; i < 64u && W.next <= target; i++) {
        if (W.next > W.now) {
            W.now = W.next;
            same = 0;
        } else if (++same >= 4u && !W.refuse && W.node->txq.count == 0u) {
            fail("process keeps returning %llu at %llu", (unsigned long long)W.next,
                 (unsigned long long)W.now);
        }
        do_process();
    }
    if (target > W.now) {
        W.now = target;
    }
    do_process();
}

static void op_time(void)
{
    uint8_t mode = in_u8();
    uint64_t v = in_u16();
    uint64_t target;
    bool never = W.next == CO_TIME_NEVER;
    switch (mode & 3u) {
    case 0: target = never ? W.now + v : W.next; break;
    case 1: target = never ? W.now + v : W.next - 1u; break;
    case 2: target = W.now + (v << (2u * ((mode >> 2) & 7u))); break;
    default: target = never ? W.now + v : W.next + v; break;
    }
    if (target < W.now) {
        target = W.now;
    }
    advance_to(target);
}

static void op_bus(void)
{
    uint8_t b = in_u8();
    W.refuse = (b & 1u) != 0u;
    call_begin();
    if ((b & 0x10u) != 0u) {
        co_node_bus_state(W.node, (co_bus_state)((b >> 2) & 3u), W.now);
    }
    if ((b & 0x20u) != 0u) {
        co_node_rx_overrun(W.node, (uint32_t)(b >> 6) + 1u, W.now);
    }
    if ((b & 2u) != 0u) {
        co_node_tx_ready(W.node);
    }
    call_end();
    do_process();
}

static void op_sdo_write(void)
{
    co_od_ref ref = pick_ref();
    uint8_t mode = in_u8();
    uint32_t v = in_u32();
    if (ref.sub == NULL) {
        return;
    }
    uint32_t n = ref.sub->size >= 1u && ref.sub->size <= 4u ? ref.sub->size : 1u + (mode & 3u);
    if ((mode & 8u) != 0u) {
        n = 1u + ((mode >> 4) & 3u);
    }
    uint8_t cmd = (mode & 4u) != 0u ? 0x22u : (uint8_t)(0x23u | ((4u - n) << 2));
    sdo_put(cmd, ref.entry->index, ref.sub->subindex, v);
}

static void op_sdo_read(void)
{
    co_od_ref ref = pick_ref();
    if (ref.sub != NULL) {
        sdo_put(0x40, ref.entry->index, ref.sub->subindex, 0);
    }
}

/* Segmented download of len bytes; returns false once the server aborted. */
static void segmented_download(uint16_t index, uint8_t sub, const uint8_t *data, uint32_t len,
                               uint8_t opts)
{
    uint32_t announced = len;
    if ((opts & 2u) != 0u) {
        announced = (opts & 0x80u) != 0u ? len + 1u : (len > 0u ? len - 1u : 0u);
    }
    sdo_put((opts & 1u) != 0u ? 0x20u : 0x21u, index, sub, (opts & 1u) != 0u ? 0u : announced);
    if (W_resp == NULL || W_resp->data[0] != 0x60u) {
        return;
    }
    uint32_t pos = 0;
    uint8_t toggle = 0;
    uint32_t seg = 0;
    do {
        uint32_t k = len - pos < 7u ? len - pos : 7u;
        bool last = pos + k >= len;
        if ((opts & 8u) != 0u && last) {
            return; /* the client goes quiet: the server's timeout ends it */
        }
        uint8_t req[8] = {0};
        req[0] = (uint8_t)((toggle << 4) | ((7u - k) << 1) | (last ? 1u : 0u));
        if ((opts & 4u) != 0u && seg == (uint32_t)(opts >> 4)) {
            req[0] ^= 0x10u; /* toggle error */
        }
        memcpy(&req[1], data + pos, k);
        sdo8(req);
        if (W_resp == NULL || W_resp->data[0] == 0x80u) {
            return;
        }
        pos += k;
        toggle ^= 1u;
        seg++;
    } while (pos < len);
}

/* The limit probe: a value just outside a limit is refused with the limit's abort code, and the
 * value stays. */
/* An index the node keeps out of SDO's sight (CO_NODE_SDO_HIDDEN_RANGE): every request on it
 * answers 0x06020000 before any other check. */
static bool sdo_hidden(uint16_t index)
{
    const co_node *n = W.node;
    return (n->options & CO_NODE_SDO_HIDDEN_RANGE) != 0u && index >= n->sdo.hidden_first &&
           index <= n->sdo.hidden_last;
}

static void op_limit(void)
{
    uint16_t sel = in_u16();
    uint8_t which = (uint8_t)(in_u8() & 3u);
    if (D->limited_count == 0u) {
        return;
    }
    const co_od_ref ref = D->limited[sel % D->limited_count];
    const co_od_sub *sub = ref.sub;
    const co_od_limit *lim = &W.od->limits[sub->limit];
    uint8_t data[8] = {0};
    bool outside = false;
    co_abort expected = 0;
    uint32_t size = sub->size;
    if (sub->type == CO_REAL32 || sub->type == CO_REAL64) {
        double lo, hi;
        memcpy(&lo, &lim->low, sizeof lo);
        memcpy(&hi, &lim->high, sizeof hi);
        double v = (which & 1u) != 0u ? lo : hi;
        if (which < 2u) {
            v = which == 0u ? nextafter(hi, INFINITY) : nextafter(lo, -INFINITY);
        }
        if (sub->type == CO_REAL32) {
            float f = (float)v;
            if (which == 0u && (double)f <= hi) {
                f = nextafterf(f, INFINITY);
            }
            if (which == 1u && (double)f >= lo) {
                f = nextafterf(f, -INFINITY);
            }
            memcpy(data, &f, 4);
            outside = which < 2u && !isinf(f);
        } else {
            memcpy(data, &v, 8);
            outside = which < 2u && !isinf(v);
        }
    } else if (size >= 1u && size <= 8u) {
        bool is_signed = co_type_is_signed(sub->type);
        uint64_t bits = 8u * size;
        uint64_t umax = bits == 64u ? UINT64_MAX : (UINT64_C(1) << bits) - 1u;
        int64_t smax = (int64_t)(umax >> 1);
        int64_t smin = -smax - 1;
        uint64_t v = (which & 1u) != 0u ? lim->low : lim->high;
        if (which == 0u) {
            outside = is_signed ? (int64_t)lim->high < smax : lim->high < umax;
            v = outside ? lim->high + 1u : lim->high;
        } else if (which == 1u) {
            outside = is_signed ? (int64_t)lim->low > smin : lim->low > 0u;
            v = outside ? lim->low - 1u : lim->low;
        }
        for (uint32_t i = 0; i < size; i++) {
            data[i] = (uint8_t)(v >> (8u * i));
        }
    } else {
        return;
    }
    if (outside) {
        expected = which == 0u ? CO_ABORT_VALUE_TOO_HIGH : CO_ABORT_VALUE_TOO_LOW;
    }
    uint8_t before[8];
    memcpy(before, W.values + co_od_value_offset(ref.entry, sub), size);
    uint32_t abort_code = 0;
    bool answered = false;
    if (size <= 4u) {
        uint32_t v = 0;
        for (uint32_t i = 0; i < size; i++) {
            v |= (uint32_t)data[i] << (8u * i);
        }
        sdo_write_n(ref.entry->index, sub->subindex, v, size);
        answered = W_resp != NULL;
        abort_code = resp_abort();
    } else {
        segmented_download(ref.entry->index, sub->subindex, data, size, 0);
        answered = W_resp != NULL;
        abort_code = resp_abort();
    }
    if (!outside) {
        return;
    }
    if (memcmp(before, W.values + co_od_value_offset(ref.entry, sub), size) != 0) {
        fail("0x%04X sub %u changed by a value outside its limits", ref.entry->index,
             sub->subindex);
    }
    if (answered && abort_code != expected && abort_code != CO_ABORT_READ_ONLY &&
        abort_code != CO_ABORT_DEVICE_STATE &&
        !(abort_code == CO_ABORT_NO_OBJECT && sdo_hidden(ref.entry->index))) {
        fail("0x%04X sub %u: a value %s its limit answered 0x%08X, not 0x%08X", ref.entry->index,
             sub->subindex, which == 0u ? "above" : "below", abort_code, expected);
    }
}

static void op_seg_write(void)
{
    co_od_ref ref = pick_ref();
    uint8_t opts = in_u8();
    uint32_t len = in_u8();
    uint8_t data[256];
    for (uint32_t i = 0; i < len; i++) {
        data[i] = in_u8();
    }
    if (ref.sub != NULL) {
        segmented_download(ref.entry->index, ref.sub->subindex, data, len, opts);
    }
}

static uint16_t crc16(uint16_t crc, const uint8_t *p, uint32_t n)
{
    for (uint32_t i = 0; i < n; i++) {
        crc ^= (uint16_t)(p[i] << 8);
        for (int b = 0; b < 8; b++) {
            crc = (crc & 0x8000u) != 0u ? (uint16_t)((crc << 1) ^ 0x1021u) : (uint16_t)(crc << 1);
        }
    }
    return crc;
}

/* Block download as a client: follows the block size and acknowledgements the server sends.
 * opts: bit 0 no CRC, bit 1 no size, bit 2 wrong CRC, bit 3 a lost segment, bit 4 a wrong
 * sequence number, bit 5 silent end, bits 6-7 where the error goes. */
static void op_block_write(void)
{
    co_od_ref ref = pick_ref();
    uint8_t opts = in_u8();
    uint32_t len = in_u8();
    uint8_t data[256];
    for (uint32_t i = 0; i < len; i++) {
        data[i] = in_u8();
    }
    if (ref.sub == NULL) {
        return;
    }
    bool crc = (opts & 1u) == 0u;
    uint8_t cmd = (uint8_t)(0xC0u | (crc ? 0x04u : 0u) | ((opts & 2u) == 0u ? 0x02u : 0u));
    sdo_put(cmd, ref.entry->index, ref.sub->subindex, (opts & 2u) == 0u ? len : 0u);
    if (W_resp == NULL || (W_resp->data[0] & 0xFBu) != 0xA0u) {
        return;
    }
    uint32_t blksize = W_resp->data[4];
    uint32_t pos = 0;
    uint32_t error_at = (uint32_t)(opts >> 6);
    for (uint32_t round = 0; round < 64u && pos < len + 1u; round++) {
        if (blksize == 0u || blksize > 127u) {
            fail("block download offered block size %u", blksize);
        }
        uint32_t seq = 0;
        uint32_t p = pos;
        bool last = false;
        while (seq < blksize && !last) {
            uint32_t k = len - p < 7u ? len - p : 7u;
            last = p + k >= len;
            seq++;
            uint8_t req[8] = {0};
            req[0] = (uint8_t)(seq | (last ? 0x80u : 0u));
            memcpy(&req[1], data + p, k);
            p += k;
            if (round == 0u && seq == error_at + 1u) {
                if ((opts & 8u) != 0u) {
                    continue; /* lost on the bus */
                }
                if ((opts & 0x10u) != 0u) {
                    req[0] = (uint8_t)(req[0] & 0x80u); /* sequence number 0 */
                }
            }
            sdo8(req);
            if (W_resp != NULL && W_resp->data[0] == 0x80u) {
                return;
            }
        }
        if (W_resp == NULL || W_resp->data[0] != 0xA2u) {
            return; /* the server is waiting for more, or aborted */
        }
        uint32_t acked = W_resp->data[1];
        blksize = W_resp->data[2];
        /* segments up to acked arrived: go on after them (7 bytes each) */
        uint32_t done = pos + 7u * acked;
        pos = done > len ? len : done;
        if (acked == seq && last) {
            break;
        }
        if (acked == 0u && pos >= len && len == 0u) {
            break;
        }
    }
    if ((opts & 0x20u) != 0u) {
        return;
    }
    uint32_t rem = len % 7u;
    uint32_t unused = (len == 0u) ? 7u : (rem == 0u ? 0u : 7u - rem);
    uint16_t c = crc ? crc16(0, data, len) : 0u;
    if ((opts & 4u) != 0u) {
        c ^= 0x5A5Au;
    }
    const uint8_t end[8] = {(uint8_t)(0xC1u | (unused << 2)), (uint8_t)c, (uint8_t)(c >> 8),
                            0, 0, 0, 0, 0};
    sdo8(end);
}

/* A segmented upload after its initiate was answered: segment requests with alternating toggles
 * until the last segment (an error at segment error_at when asked). */
static void segmented_upload(uint8_t opts, uint32_t error_at)
{
    if (W_resp == NULL || (W_resp->data[0] & 0xE2u) != 0x40u) {
        return; /* expedited answer, abort or nothing */
    }
    uint8_t toggle = 0;
    for (uint32_t seg = 0; seg < 200u; seg++) {
        if ((opts & 8u) != 0u && seg == error_at) {
            return;
        }
        uint8_t cmd = (uint8_t)(0x60u | (toggle << 4));
        if ((opts & 4u) != 0u && seg == error_at) {
            cmd ^= 0x10u;
        }
        const uint8_t req[8] = {cmd, 0, 0, 0, 0, 0, 0, 0};
        sdo8(req);
        if (W_resp == NULL || (W_resp->data[0] & 0xE0u) != 0x00u || (W_resp->data[0] & 1u) != 0u) {
            return;
        }
        toggle ^= 1u;
    }
}

/* Uploads as a client. opts: bit 0 block, bit 1 CRC, bit 2 a toggle / acknowledgement error,
 * bit 3 stop midway, bits 4-7 where the error goes. */
static void op_upload(void)
{
    co_od_ref ref = pick_ref();
    uint8_t opts = in_u8();
    uint8_t blk = in_u8();
    uint8_t pst = in_u8();
    if (ref.sub == NULL) {
        return;
    }
    uint32_t error_at = (uint32_t)(opts >> 4);
    if ((opts & 1u) == 0u) {
        sdo_put(0x40, ref.entry->index, ref.sub->subindex, 0);
        segmented_upload(opts, error_at);
        return;
    }
    bool crc = (opts & 2u) != 0u;
    const uint8_t init[8] = {(uint8_t)(0xA0u | (crc ? 0x04u : 0u)), (uint8_t)ref.entry->index,
                             (uint8_t)(ref.entry->index >> 8), ref.sub->subindex, blk, pst, 0, 0};
    sdo8(init);
    if (W_resp == NULL) {
        return;
    }
    if ((W_resp->data[0] & 0xE0u) == 0x40u) {
        segmented_upload(opts, error_at); /* the protocol switch threshold chose a normal upload */
        return;
    }
    if ((W_resp->data[0] & 0xF9u) != 0xC0u) {
        return;
    }
    uint8_t req[8] = {0xA3, 0, 0, 0, 0, 0, 0, 0};
    for (uint32_t round = 0; round < 64u; round++) {
        sdo8(req);
        /* the sub-block the server sent in answer to the request just made */
        uint32_t last_seq = 0;
        bool end_seen = false;
        uint32_t frames = 0;
        for (uint32_t i = 0; i < Log.count; i++) {
            const co_frame *f = &Log.frames[i];
            if (f->id != 0x580u + W.node->node_id) {
                continue;
            }
            frames++;
            if (f->data[0] == 0x80u) {
                return;
            }
            if ((f->data[0] & 0x7Fu) == last_seq + 1u) {
                last_seq++;
            }
            if ((f->data[0] & 0xE3u) == 0xC1u) {
                end_seen = true;
            }
        }
        if (end_seen) {
            if ((opts & 8u) == 0u) {
                const uint8_t end[8] = {0xA1, 0, 0, 0, 0, 0, 0, 0};
                sdo8(end);
            }
            return;
        }
        if (frames == 0u || ((opts & 8u) != 0u && round == error_at)) {
            return; /* nothing came (the port refuses: the server retries later), or we stop */
        }
        uint8_t ack = (uint8_t)last_seq;
        if ((opts & 4u) != 0u && round == error_at) {
            ack = (uint8_t)(ack + 1u);
        }
        const uint8_t a[8] = {0xA2, ack, (uint8_t)(blk == 0u ? 1u : blk), 0, 0, 0, 0, 0};
        memcpy(req, a, 8);
    }
}

static uint16_t pick_pdo(bool tpdo, uint16_t sel)
{
    if (tpdo) {
        return D->tpdo_count != 0u ? D->tpdo_comm[sel % D->tpdo_count] : 0u;
    }
    return D->rpdo_count != 0u ? D->rpdo_comm[sel % D->rpdo_count] : 0u;
}

/* The CiA 301 remapping procedure through SDO. opts: bit 0 TPDO, bit 1 entries from the
 * dictionary's mappable objects (else raw), bit 2 write the transmission type, bit 3 a new
 * CAN-ID, bit 4 leave the PDO disabled, bit 5 skip disabling first. */
static void op_remap(void)
{
    uint8_t sel = in_u8();
    uint8_t opts = in_u8();
    uint32_t count = in_u8() % 9u;
    bool tpdo = (opts & 1u) != 0u;
    uint16_t comm = pick_pdo(tpdo, sel);
    uint32_t entries[8];
    for (uint32_t i = 0; i < count; i++) {
        if ((opts & 2u) != 0u) {
            uint16_t s = in_u16();
            uint32_t n = tpdo ? D->tmap_count : D->rmap_count;
            if (n == 0u) {
                entries[i] = 0;
                continue;
            }
            const co_od_ref *r = tpdo ? &D->tmap[s % n] : &D->rmap[s % n];
            entries[i] = ((uint32_t)r->entry->index << 16) | ((uint32_t)r->sub->subindex << 8) |
                         (uint32_t)(r->sub->size * 8u);
        } else {
            entries[i] = in_u32();
        }
    }
    uint8_t type = in_u8();
    uint16_t new_id = in_u16();
    if (comm == 0u) {
        return;
    }
    uint16_t map = (uint16_t)(comm + 0x200u);
    uint32_t cob = od_u32_or(comm, 1, 0x80000000u);
    if ((opts & 0x20u) == 0u) {
        sdo_write_n(comm, 1, cob | 0x80000000u, 4);
    }
    sdo_write_n(map, 0, 0, 1);
    for (uint32_t i = 0; i < count; i++) {
        sdo_write_n(map, (uint8_t)(i + 1u), entries[i], 4);
    }
    sdo_write_n(map, 0, count, 1);
    if ((opts & 4u) != 0u) {
        sdo_write_n(comm, 2, type, 1);
    }
    uint32_t id = (opts & 8u) != 0u ? (uint32_t)(new_id & 0x7FFu) : (cob & 0x7FFu);
    if ((opts & 0x10u) == 0u) {
        sdo_write_n(comm, 1, (cob & 0x40000000u) | id, 4);
    }
}

static void op_sync(void)
{
    uint8_t opts = in_u8();
    uint8_t counter = in_u8();
    uint16_t id = (uint16_t)(od_u32_or(0x1005, 0, 0x80u) & 0x7FFu);
    uint8_t dlc;
    switch (opts & 3u) {
    case 0: dlc = od_u32_or(0x1019, 0, 0) != 0u ? 1u : 0u; break;
    case 1: dlc = 0; break;
    case 2: dlc = 1; break;
    default: dlc = (uint8_t)((opts >> 2) & 0x0Fu); break;
    }
    const uint8_t data[8] = {counter, 0, 0, 0, 0, 0, 0, 0};
    co_frame f = make_frame(id, dlc, data, (opts & 0x40u) != 0u);
    do_rx(&f);
}

static void op_rpdo(void)
{
    uint8_t sel = in_u8();
    uint8_t opts = in_u8();
    uint8_t data[8];
    for (uint32_t i = 0; i < 8u; i++) {
        data[i] = in_u8();
    }
    uint16_t comm = pick_pdo(false, sel);
    if (comm == 0u) {
        return;
    }
    uint16_t id = (uint16_t)(od_u32_or(comm, 1, 0) & 0x7FFu);
    uint8_t dlc = (uint8_t)(opts & 0x0Fu);
    if (dlc > 8u) {
        uint32_t n = mapped_bytes((uint16_t)(comm + 0x200u));
        dlc = (uint8_t)(n <= 8u ? n : 8u);
    }
    co_frame f = make_frame(id, dlc, data, (opts & 0x10u) != 0u);
    do_rx(&f);
}

static void op_tpdo_rtr(void)
{
    uint8_t sel = in_u8();
    uint8_t dlc = in_u8();
    uint16_t comm = pick_pdo(true, sel);
    if (comm == 0u) {
        return;
    }
    co_frame f = make_frame((uint16_t)(od_u32_or(comm, 1, 0) & 0x7FFu), dlc, NULL, true);
    do_rx(&f);
}

static void op_heartbeat(void)
{
    uint8_t sel = in_u8();
    uint8_t state = in_u8();
    uint8_t dlc = in_u8();
    uint8_t producer = (uint8_t)(sel % 127u + 1u);
    co_od_ref ref;
    if (co_od_locate(W.od, 0x1016, 0, &ref) == CO_ABORT_NONE && ref.entry->sub_count > 1u) {
        uint8_t sub = ref.entry->subs[1u + sel % (ref.entry->sub_count - 1u)].subindex;
        uint32_t v = od_u32_or(0x1016, sub, 0);
        uint8_t id = (uint8_t)(v >> 16);
        if ((sel & 0x80u) == 0u && id >= 1u && id <= 127u) {
            producer = id;
        }
    }
    static const uint8_t states[4] = {0x00, 0x04, 0x05, 0x7F};
    uint8_t b = (state & 4u) != 0u ? (uint8_t)(state >> 3) : states[state & 3u];
    const uint8_t data[8] = {b, 0, 0, 0, 0, 0, 0, 0};
    co_frame f = make_frame((uint16_t)(0x700u + producer),
                            (dlc & 0x80u) != 0u ? (uint8_t)(dlc & 0x0Fu) : 1u, data, false);
    do_rx(&f);
}

static void op_guard(void)
{
    uint8_t dlc = in_u8();
    co_frame f = make_frame((uint16_t)(0x700u + W.node->node_id), dlc, NULL, true);
    do_rx(&f);
}

static void op_app(void)
{
    uint8_t kind = (uint8_t)(in_u8() % 6u);
    co_od_ref ref = {NULL, NULL};
    if (kind == 4u) {
        ref = pick_ref();
    }
    uint8_t a = in_u8();
    uint8_t b = in_u8();
    uint8_t c = in_u8();
    call_begin();
    if (kind == 0u) {
        (void)co_pdo_tpdo_request(W.node, (uint16_t)(1u + a % 8u));
    } else if (W.drive == NULL) {
        /* The application of a plain node. A drive's layer is its application: it owns these. */
        uint8_t manufacturer[5] = {a, b, c, 0, 0};
        switch (kind) {
        case 1: (void)co_emcy_raise(W.node, (uint16_t)(a | (b << 8)), c, manufacturer); break;
        case 2: co_emcy_clear(W.node, (uint16_t)(a | (b << 8))); break;
        case 3: co_emcy_clear_all(W.node); break;
        case 4: {
            uint8_t len = (uint8_t)(a & 0x0Fu); /* a: length, b, c and more: the data */
            uint8_t data[16] = {b, c};
            for (uint32_t i = 2; i < len; i++) {
                data[i] = in_u8();
            }
            /* 0x1000-0x1FFF: the services cache their parameters and an application write skips
             * their hooks (pdo.h, sync.h): the application reconfigures them itself. */
            if (ref.sub == NULL || ref.sub->type == CO_DOMAIN || ref.entry->index < 0x2000u) {
                break;
            }
            uint8_t before[64];
            uint32_t size = ref.sub->size < sizeof before ? ref.sub->size : sizeof before;
            memcpy(before, W.values + co_od_value_offset(ref.entry, ref.sub), size);
            co_abort rc = co_od_write_ref(W.node, ref, data, len, CO_ORIGIN_APP);
            const uint8_t *now = W.values + co_od_value_offset(ref.entry, ref.sub);
            if (rc != CO_ABORT_NONE && memcmp(before, now, size) != 0) {
                fail("application write of 0x%04X sub %u refused 0x%08X but changed it",
                     ref.entry->index, ref.sub->subindex, rc);
            }
            if (rc == CO_ABORT_NONE && memcmp(data, now, len < size ? len : size) != 0) {
                fail("application write of 0x%04X sub %u accepted but not stored",
                     ref.entry->index, ref.sub->subindex);
            }
            break;
        }
        default:
            (void)((a & 1u) != 0u ? co_store_restore(W.node, (uint8_t)(b % 6u))
                                  : co_store_save(W.node, (uint8_t)(b % 6u)));
            break;
        }
    }
    call_end();
    do_process();
}

static void op_drive(void)
{
    uint8_t kind = (uint8_t)(in_u8() % 8u);
    uint8_t a = in_u8();
    uint8_t b = in_u8();
    if (W.drive == NULL) {
        return;
    }
    co_drive *d = W.drive;
    const co_drive_desc *desc = W.desc;
    const co_drive_trip *row = desc->trip_count != 0u ? &desc->trips[a % desc->trip_count] : NULL;
    call_begin();
    switch (kind) {
    case 0:
    case 1: {
        uint16_t code = kind == 0u && row != NULL ? row->trip_code : (uint16_t)(a | (b << 8));
        bool known = co_drive_find_trip(desc, code) != NULL;
        bool ok = co_drive_inject_fault(d, code, W.now);
        if (ok != (known || desc->other_trips_emcy != 0u)) {
            fail("co_drive_inject_fault(%u) returned %d", code, ok);
        }
        break;
    }
    case 2: co_drive_clear_fault_cause(d); break;
    case 3: co_drive_set_mains(d, (a & 1u) != 0u, W.now); break;
    case 4: {
        co_cia402_state from = d->state;
        bool ok = co_drive_fault_reset(d, W.now);
        if (ok && (from != CO_CIA402_FAULT || d->state != CO_CIA402_SWITCH_ON_DISABLED)) {
            fail("co_drive_fault_reset from %s went to %s", co_cia402_state_name(from),
                 co_cia402_state_name(d->state));
        }
        break;
    }
    case 5:
        if (row != NULL) {
            (void)co_drive_trip_emcy(d, row->emcy_code, (b & 1u) != 0u, W.now);
        }
        break;
    case 6:
        if (row != NULL) {
            if ((b & 1u) != 0u) {
                co_drive_clear_error(d, row->emcy_code);
            } else {
                (void)co_drive_report_error(d, row->emcy_code, W.now);
            }
        }
        break;
    default:
        if ((b & 0x80u) != 0u) {
            co_drive_loss_clear(d, W.now);
        } else {
            co_drive_loss reaction = (co_drive_loss)(a % 10u);
            int32_t param = reaction == CO_DRIVE_LOSS_TRIP && row != NULL ? (int32_t)row->emcy_code
                                                                        : (int32_t)(b * 16);
            co_drive_loss_react(d, reaction, param, W.now);
        }
        break;
    }
    call_end();
    do_process();
}

/* --- set-up ---------------------------------------------------------------------------------- */

/* The harness's facts about one dictionary (with or without a drive layer), found on first use. */
static fz_dict *dict_for(const co_od *od, const co_drive_desc *desc)
{
    for (uint32_t i = 0; i < FZ_DICT_MAX; i++) {
        fz_dict *d = &Dicts[i];
        if (d->od == od && d->desc == desc) {
            return d;
        }
        if (d->od != NULL) {
            continue;
        }
        if (od->value_size > FZ_STORE_MAX) {
            fail("value block of %u bytes: raise FZ_STORE_MAX", od->value_size);
        }
        d->od = od;
        d->desc = desc;
        uint32_t size = od->value_size != 0u ? od->value_size : 1u;
        d->limited_at = calloc(size, sizeof *d->limited_at);
        d->boolean_at = calloc(size, sizeof *d->boolean_at);
        d->checked = malloc(size);
        d->values = malloc(size); /* exact sizes: ASan sees overruns */
        d->scratch = malloc(od->persist_size != 0u ? od->persist_size : 1u);
        d->object = malloc(desc != NULL ? sizeof(co_drive) : sizeof(co_node));
        if (d->limited_at == NULL || d->boolean_at == NULL || d->checked == NULL ||
            d->values == NULL || d->scratch == NULL || d->object == NULL) {
            fail("out of memory for dictionary %s", od->name);
        }
        for (uint32_t e = 0; e < od->entry_count; e++) {
            const co_od_entry *entry = &od->entries[e];
            uint16_t index = entry->index;
            if (index >= 0x1400u && index <= 0x15FFu && d->rpdo_count < FZ_PDO_MAX) {
                d->rpdo_comm[d->rpdo_count++] = index;
            }
            if (index >= 0x1800u && index <= 0x19FFu && d->tpdo_count < FZ_PDO_MAX) {
                d->tpdo_comm[d->tpdo_count++] = index;
            }
            for (uint32_t k = 0; k < entry->sub_count; k++) {
                const co_od_sub *sub = &entry->subs[k];
                co_od_ref ref = {entry, sub};
                bool stored = sub->type != CO_DOMAIN && sub->size != 0u;
                if ((sub->flags & CO_OD_LIMITS) != 0u && d->limited_count < FZ_REF_MAX) {
                    d->limited[d->limited_count++] = ref;
                    if (stored && sub->size <= 8u) {
                        if (d->limited_at[co_od_value_offset(entry, sub)] != 0u) {
                            fail("two limited values at offset %u",
                                 (unsigned)co_od_value_offset(entry, sub));
                        }
                        d->limited_at[co_od_value_offset(entry, sub)] = (uint16_t)d->limited_count;
                    }
                }
                if (sub->type == CO_BOOLEAN && d->boolean_count < FZ_REF_MAX) {
                    d->booleans[d->boolean_count++] = ref;
                    if (stored) {
                        d->boolean_at[co_od_value_offset(entry, sub)] = (uint16_t)d->boolean_count;
                    }
                }
                if ((sub->flags & CO_OD_RPDO) != 0u && d->rmap_count < FZ_REF_MAX) {
                    d->rmap[d->rmap_count++] = ref;
                }
                if ((sub->flags & CO_OD_TPDO) != 0u && d->tmap_count < FZ_REF_MAX) {
                    d->tmap[d->tmap_count++] = ref;
                }
            }
        }
        return d;
    }
    fail("more than %u dictionaries: raise FZ_DICT_MAX", FZ_DICT_MAX);
    return NULL;
}

/* What the set-up reads of the input: the header and a drive's settings (zero where the input
 * ends). Equal set-ups give equal nodes, so the node is built once per set-up and copied. */
typedef struct fz_setup {
    const fz_target *target;
    const co_od *od;
    const co_drive_desc *desc;
    uint8_t h[8];
    uint8_t setting_count;
    uint8_t settings[3][5]; /* selector, int32 LE */
} fz_setup;

static void read_setup(const fz_target *target, fz_setup *su)
{
    memset(su, 0, sizeof *su); /* the padding too: set-ups are compared with memcmp */
    su->target = target;
    for (uint32_t i = 0; i < 8u; i++) {
        su->h[i] = in_u8();
    }
    const co_drive_desc *desc = NULL;
    const co_od *od = NULL;
    if (target->drive_id != NULL) {
        desc = co_drive_registry_find(target->drive_id);
        if (desc == NULL) {
            fail("drive '%s' is not in the registry", target->drive_id);
        }
    } else {
        size_t pick = su->h[1] % (2u + co_drive_registry_count());
        if (pick == 0u) {
            od = &co_od_test;
        } else if (pick == 1u) {
            od = &co_od_test_sparse;
        } else {
            desc = co_drive_registry_at(pick - 2u);
        }
    }
    su->od = desc != NULL ? desc->od : od;
    su->desc = desc;
    /* Only what build() reads is kept, so that inputs whose headers differ only in bytes the
     * set-up ignores share its snapshot (below): the node-ID's and the dictionary's selectors
     * reduced, and for a drive the bytes of plain nodes cleared. */
    su->h[0] = (uint8_t)(su->h[0] % 127u);
    su->h[1] = 0;
    if (desc != NULL) {
        su->h[2] &= 0x3Fu;
        su->h[3] = su->h[4] = su->h[5] = su->h[6] = 0;
        su->h[7] %= 4u;
        su->setting_count = su->h[7];
        for (uint32_t i = 0; i < su->setting_count; i++) {
            for (uint32_t k = 0; k < 5u; k++) {
                su->settings[i][k] = in_u8();
            }
        }
    }
}

/* Builds and starts the node of a set-up in its dictionary's memory. */
static void build(const fz_setup *su)
{
    const uint8_t *h = su->h;
    const co_od *od = su->od;
    const co_drive_desc *desc = su->desc;
    W.od = od;
    W.desc = desc;
    if (trace) {
        fprintf(stderr, "setup: %s, node-ID %u, header %02X %02X %02X %02X %02X %02X %02X %02X\n",
                od->name, 1u + h[0] % 127u, h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7]);
    }
    W.values = D->values;
    W.scratch = (h[2] & 2u) == 0u ? D->scratch : NULL;
    memset(W.values, 0xA5, od->value_size);
    memset(D->scratch, 0x5A, od->persist_size != 0u ? od->persist_size : 1u);
    D->checked_valid = false;
    Store.save_fails = (h[2] & 4u) != 0u;
    W.now = (h[2] & 0x20u) != 0u ? UINT64_C(1000000000000) : 0u;
    W.next = CO_TIME_NEVER;

    static co_storage storage;
    storage.load = store_load;
    storage.save = store_save;
    storage.erase = store_erase;
    storage.ctx = NULL;

    co_node_config cfg = co_node_default_config();
    cfg.node_id = (uint8_t)(1u + h[0] % 127u);
    cfg.values = W.values;
    cfg.driver.send = port_send;
    cfg.driver.ctx = NULL;
    cfg.storage = (h[2] & 1u) == 0u ? &storage : NULL;
    cfg.store_scratch = W.scratch;
    cfg.store_scratch_size = W.scratch != NULL ? od->persist_size : 0u;
    if ((h[2] & 0x10u) != 0u) {
        cfg.sdo_timeout_us = 50000u;
    }
    if (desc == NULL) {
        static const uint8_t behaviours[4] = {0, 1, 2, 0x80};
        static const uint32_t units[4] = {0, 1000, 1, 10000};
        cfg.od = od;
        cfg.comm_error_behaviour = behaviours[h[2] >> 6];
        cfg.options = h[3] & 0x5Fu; /* all but CO_NODE_SDO_HIDDEN_RANGE (a drive's) */
        /* h6 bits 6-7: CO_PDO_EVENT_TIMER_ALONE, CO_PDO_INHIBIT_254_ONLY */
        cfg.pdo.flags = (uint16_t)(h[4] | (uint32_t)(h[6] & 0xC0u) << 4);
        cfg.pdo.rpdo_dummy_mask = h[5];
        cfg.pdo.tpdo_inhibit_unit_us = units[h[6] & 3u];
        cfg.pdo.tpdo_inhibit_min_us = (h[6] & 4u) != 0u ? 1000u : 0u;
        cfg.pdo.tpdo_event_min_us = (h[6] & 8u) != 0u ? 1000u : 0u;
        cfg.pdo.value_abort = (h[6] & 0x10u) != 0u ? CO_ABORT_VALUE_RANGE : 0u;
        cfg.pdo.busy_abort = (h[6] & 0x20u) != 0u ? CO_ABORT_DEVICE_STATE : 0u;
        co_node *n = D->object;
        W.node = n;
        memset(n, 0, sizeof *n); /* port_send reads txq even during init */
        if (!co_node_init(n, &cfg)) {
            fail("co_node_init refused a valid configuration");
        }
        W.domain_size = (uint32_t)h[7] * 61u; /* up to 15555 bytes: several buffers */
        add_domain_hooks();
    } else {
        co_drive *d = D->object;
        memset(d, 0, sizeof *d);
        W.drive = d;
        W.node = &d->node;
        if (!co_drive_init(d, desc, &cfg)) {
            fail("co_drive_init refused a valid configuration");
        }
        for (uint32_t i = 0; i < su->setting_count; i++) {
            uint8_t sel = su->settings[i][0];
            int32_t value = (int32_t)co_get_le32(&su->settings[i][1]);
            if (desc->setting_count == 0u) {
                continue;
            }
            const co_drive_setting *s = &desc->settings[sel % desc->setting_count];
            bool ok = co_drive_set_setting(d, s->name, value);
            if (ok != (value >= s->min && value <= s->max)) {
                fail("co_drive_set_setting(%s, %d) returned %d for [%d, %d]", s->name, value, ok,
                     s->min, s->max);
            }
        }
    }
    check_values(); /* defaults and the application's initial values */

    call_begin();
    if (W.drive != NULL) {
        co_drive_start(W.drive, W.now);
    } else {
        co_node_start(W.node, W.now);
    }
    call_end();
    W.started = true;
    do_process();
    check_node();
    if ((h[2] & 8u) != 0u) {
        const uint8_t start[2] = {CO_NMT_CMD_START, 0};
        co_frame f = make_frame(0x000, 2, start, false);
        do_rx(&f);
        check_node();
    }
}

/* --- snapshots of the set-up ------------------------------------------------------------------
 * Building and starting a node (every default restored, the PDOs configured, the boot-up sent)
 * costs more than most inputs' operations, and libFuzzer runs many inputs with the same header.
 * So the state a set-up leaves - the run's W, the node's memory and the store - is kept, keyed by
 * the set-up, and the next input with that set-up starts from a copy of it. The copy is the very
 * state a fresh build gives (the node's memory is the dictionary's own, at the same address), so
 * an input behaves the same whether its set-up was built or copied, and a finding replays from
 * its file alone. FZ_CHECK_SNAPSHOT=1 builds anyway and compares, byte for byte; FZ_TRACE=1 and
 * FZ_NO_SNAPSHOT=1 always build. */
#define FZ_SNAP_SLOTS 4096u

typedef struct fz_snap {
    fz_setup key;
    bool used;
    fz_world w;
    uint32_t store_len, store_hash;
    bool store_valid;
    uint8_t *bytes; /* the node object, the values, the scratch, the store image */
    size_t cap;
} fz_snap;

static fz_snap Snaps[FZ_SNAP_SLOTS];
static int snapshot_mode = -1; /* 0 off, 1 on, 2 on and checked */

static uint32_t setup_hash(const fz_setup *su)
{
    const uint8_t *p = (const uint8_t *)su;
    uint32_t x = 2166136261u; /* FNV-1a */
    for (size_t i = 0; i < sizeof *su; i++) {
        x = (x ^ p[i]) * 16777619u;
    }
    return x;
}

static size_t object_size(void)
{
    return W.drive != NULL ? sizeof(co_drive) : sizeof(co_node);
}

/* The parts of the snapshot's byte block, in order. */
static size_t snap_size(void)
{
    return object_size() + W.od->value_size + W.od->persist_size + (Store.valid ? Store.len : 0u);
}

static void snap_take(fz_snap *sn, const fz_setup *su)
{
    size_t need = snap_size();
    if (sn->cap < need) {
        free(sn->bytes);
        sn->bytes = malloc(need);
        sn->cap = need;
        if (sn->bytes == NULL) {
            fail("out of memory for a snapshot of %zu bytes", need);
        }
    }
    uint8_t *p = sn->bytes;
    memcpy(p, D->object, object_size());
    p += object_size();
    memcpy(p, D->values, W.od->value_size);
    p += W.od->value_size;
    memcpy(p, D->scratch, W.od->persist_size);
    p += W.od->persist_size;
    if (Store.valid) {
        memcpy(p, Store.image, Store.len);
    }
    memcpy(&sn->key, su, sizeof *su);
    memcpy(&sn->w, &W, sizeof W);
    sn->store_len = Store.len;
    sn->store_hash = Store.hash;
    sn->store_valid = Store.valid;
    sn->used = true;
}

static void snap_restore(const fz_snap *sn)
{
    const uint8_t *in = W.in;
    size_t in_size = W.in_size, in_pos = W.in_pos;
    memcpy(&W, &sn->w, sizeof W);
    W.in = in;
    W.in_size = in_size;
    W.in_pos = in_pos;
    const uint8_t *p = sn->bytes;
    memcpy(D->object, p, object_size());
    p += object_size();
    memcpy(D->values, p, W.od->value_size);
    p += W.od->value_size;
    memcpy(D->scratch, p, W.od->persist_size);
    p += W.od->persist_size;
    Store.len = sn->store_len;
    Store.hash = sn->store_hash;
    Store.valid = sn->store_valid;
    Store.save_fails = (sn->key.h[2] & 4u) != 0u;
    if (Store.valid) {
        memcpy(Store.image, p, Store.len);
    }
    /* the snapshot's values were checked when it was taken */
    memcpy(D->checked, D->values, W.od->value_size);
    D->checked_valid = true;
}

static void snap_same(const char *part, const void *fresh, const void *kept, size_t n)
{
    const uint8_t *a = fresh, *b = kept;
    for (size_t i = 0; i < n; i++) {
        if (a[i] != b[i]) {
            fail("a snapshot of the set-up differs from a fresh build of it: %s byte %zu of %zu "
                 "(fresh 0x%02X, snapshot 0x%02X)", part, i, n, a[i], b[i]);
        }
    }
}

/* FZ_CHECK_SNAPSHOT: the snapshot against a fresh build of the same set-up. */
static void snap_compare(const fz_snap *sn, const fz_setup *su)
{
    build(su);
    Log.count = 0;
    const uint8_t *p = sn->bytes;
    /* co_node_add_hook copies a hook whole, padding too, and a hook built on the stack brings
     * whatever its padding held: that is not state, so it is cleared on both sides. */
    static uint8_t fresh[sizeof(co_drive) > sizeof(co_node) ? sizeof(co_drive) : sizeof(co_node)];
    static uint8_t kept[sizeof fresh];
    memcpy(fresh, D->object, object_size());
    memcpy(kept, p, object_size());
    size_t at = (size_t)((const uint8_t *)W.node - (const uint8_t *)D->object) +
                offsetof(co_node, hooks);
    size_t pad_from = offsetof(co_od_hook, index_last) + sizeof(uint16_t);
    size_t pad_to = offsetof(co_od_hook, refresh);
    for (uint32_t i = 0; i < CO_MAX_HOOKS; i++) {
        memset(fresh + at + i * sizeof(co_od_hook) + pad_from, 0, pad_to - pad_from);
        memset(kept + at + i * sizeof(co_od_hook) + pad_from, 0, pad_to - pad_from);
    }
    snap_same("node object", fresh, kept, object_size());
    p += object_size();
    snap_same("values", D->values, p, W.od->value_size);
    p += W.od->value_size;
    snap_same("store scratch", D->scratch, p, W.od->persist_size);
    fz_world w;
    memcpy(&w, &W, sizeof w);
    w.in = sn->w.in; /* the input that took the snapshot */
    w.in_size = sn->w.in_size;
    w.in_pos = sn->w.in_pos;
    snap_same("harness state", &w, &sn->w, sizeof w);
    if (Store.valid != sn->store_valid || Store.len != sn->store_len ||
        Store.hash != sn->store_hash) {
        fail("a snapshot of the set-up differs from a fresh build of it: the store");
    }
}

static void setup(const fz_target *target)
{
    if (snapshot_mode < 0) {
        snapshot_mode = getenv("FZ_CHECK_SNAPSHOT") != NULL ? 2
                        : getenv("FZ_NO_SNAPSHOT") != NULL  ? 0
                                                            : 1;
    }
    fz_setup su;
    read_setup(target, &su);
    D = dict_for(su.od, su.desc);
    W_resp = NULL;
    Log.count = 0;
    Store.valid = false;
    Store.len = Store.hash = 0;
    if (snapshot_mode == 0 || trace) {
        build(&su);
        Log.count = 0;
        return;
    }
    fz_snap *sn = &Snaps[setup_hash(&su) % FZ_SNAP_SLOTS];
    if (sn->used && memcmp(&sn->key, &su, sizeof su) == 0) {
        if (snapshot_mode == 2) {
            snap_compare(sn, &su);
        }
        snap_restore(sn);
        return;
    }
    build(&su);
    Log.count = 0;
    snap_take(sn, &su);
}

/* The node's memory stays with its dictionary for the next input. */
static void teardown(void)
{
    memset(&W, 0, sizeof W);
    W_resp = NULL;
}

int fz_run(const fz_target *target, const uint8_t *data, size_t size)
{
    memset(&W, 0, sizeof W);
    trace = getenv("FZ_TRACE") != NULL;
    W.target = target;
    W.in = data;
    W.in_size = size;
    setup(target);
    W.resets = 0;
    for (uint32_t ops = 0; in_more() && ops < 4096u && W.resets < FZ_MAX_RESETS; ops++) {
        enum fz_op op = (enum fz_op)(in_u8() % FZ_OP_COUNT);
        if ((target->ops & FZ_BIT(op)) == 0u) {
            continue;
        }
        if (trace) {
            fprintf(stderr, "op %u at byte %zu\n", (unsigned)op, W.in_pos - 1u);
        }
        switch (op) {
        case FZ_OP_RAW: op_raw(); break;
        case FZ_OP_REL: op_rel(); break;
        case FZ_OP_SDO: op_sdo(); break;
        case FZ_OP_NMT: op_nmt(); break;
        case FZ_OP_TIME: op_time(); break;
        case FZ_OP_PROCESS: do_process(); break;
        case FZ_OP_BUS: op_bus(); break;
        case FZ_OP_SDO_WRITE: op_sdo_write(); break;
        case FZ_OP_SDO_READ: op_sdo_read(); break;
        case FZ_OP_LIMIT: op_limit(); break;
        case FZ_OP_SEG_WRITE: op_seg_write(); break;
        case FZ_OP_BLOCK_WRITE: op_block_write(); break;
        case FZ_OP_UPLOAD: op_upload(); break;
        case FZ_OP_REMAP: op_remap(); break;
        case FZ_OP_SYNC: op_sync(); break;
        case FZ_OP_RPDO: op_rpdo(); break;
        case FZ_OP_TPDO_RTR: op_tpdo_rtr(); break;
        case FZ_OP_HEARTBEAT: op_heartbeat(); break;
        case FZ_OP_GUARD: op_guard(); break;
        case FZ_OP_APP: op_app(); break;
        case FZ_OP_DRIVE: op_drive(); break;
        default: break;
        }
        if (trace) {
            fprintf(stderr, "  rx counters: %u frames, %u malformed, %u ignored\n",
                    W.node->stats.rx_frames, W.node->stats.rx_malformed, W.node->stats.rx_ignored);
        }
        check_node();
    }
    if (trace && in_more()) {
        fprintf(stderr, "input ends at byte %zu: %u resets\n", W.in_pos, W.resets);
    }
    teardown();
    return 0;
}
