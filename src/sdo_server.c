/* SDO server (CiA 301 §7.2.4.3): one channel, expedited, segmented and block transfers.
 *
 * Byte 0 of a request holds the client command specifier (ccs) in bits 7-5, except during the
 * sub-blocks of a block download, where it is c (last segment) and the sequence number.
 *
 * A new initiate request during a transfer starts the new transfer and drops the old one without
 * an abort frame. A client only sends an initiate when it considers the old transfer finished
 * (it timed out, or it was restarted and lost its state); an abort frame sent then would reach it
 * as the answer to its new request and fail that one too. CiA 301 leaves this case open. */
#include "canopen/sdo_server.h"

#include <stddef.h>
#include <string.h>

#include "canopen/node.h"
#include "node_internal.h"

#if CO_SDO_BUF_SIZE < 7
#error "CO_SDO_BUF_SIZE must hold at least one segment (7 bytes)"
#endif
#if CO_SDO_TIMEOUT_US > CO_TIME_SPAN_MAX || CO_SDO_TX_RETRY_US > CO_TIME_SPAN_MAX
#error "the SDO timeout and retry must fit a deadline (CO_TIME_SPAN_MAX)"
#endif

/* Client command specifiers (byte 0, bits 7-5). */
enum {
    CCS_DOWNLOAD_SEGMENT = 0,
    CCS_DOWNLOAD_INITIATE = 1,
    CCS_UPLOAD_INITIATE = 2,
    CCS_UPLOAD_SEGMENT = 3,
    CCS_ABORT = 4,
    CCS_BLOCK_UPLOAD = 5,
    CCS_BLOCK_DOWNLOAD = 6
};

/* Block upload client sub-commands (byte 0, bits 1-0). */
enum { BLOCK_UP_INITIATE = 0, BLOCK_UP_END = 1, BLOCK_UP_ACK = 2, BLOCK_UP_START = 3 };

/* What the dispatch expects of an initiate request instead of a state: one past them all. */
#define INITIATE_REQUEST ((uint32_t)CO_SDO_UPLOAD_BLOCK_END + 1u)

#define SEGMENT_DATA 7u     /* data bytes in one segment */
#define BLOCK_SIZE_MAX 127u /* segments in one sub-block (7-bit sequence number) */

/* Download sub-blocks the server offers: what the buffer holds, at most 127. */
#define BLOCK_SIZE_OFFER                                                  \
    ((CO_SDO_BUF_SIZE / SEGMENT_DATA) > BLOCK_SIZE_MAX ? BLOCK_SIZE_MAX \
                                                       : (CO_SDO_BUF_SIZE / SEGMENT_DATA))

/* -O2 keeps a function so marked out of the dispatcher, which then has the registers for the
 * expedited transfers inlined into it; -Os inlines it into its one caller. */
#if defined(__OPTIMIZE_SIZE__)
#define OFF_FAST_PATH
#else
#define OFF_FAST_PATH CO_NOINLINE
#endif

static uint32_t min_u32(uint32_t a, uint32_t b)
{
    return a < b ? a : b;
}

/* The node a server belongs to (it is the node's member sdo). The services pass the server
 * itself: its fields are then at small offsets, which short instructions reach. */
static co_node *node_of(co_sdo_server *s)
{
    return (co_node *)(void *)((char *)s - offsetof(co_node, sdo));
}

/* --- frames ----------------------------------------------------------------------------------- */

/* Sends a frame: bytes 0-3 from lo, 4-7 from hi, little-endian (the command byte, then the
 * multiplexer or data; CiA 301 reserved bytes are 0), and over bytes 1-7 the data of a segment:
 * piece is its place in the buffer << 3 | its length (0: none). */
static CO_SIZE_NOINLINE void send_frame(co_sdo_server *s, uint32_t lo, uint32_t hi, uint32_t piece)
{
    co_node *node = node_of(s);
    co_frame f;
    f.id = node->sdo_tx_cob;
    f.dlc = 8;
    f.flags = 0u;
    co_put_le32(&f.data[0], lo);
    co_put_le32(&f.data[4], hi);
    memcpy(&f.data[1], &s->buf[piece >> 3], piece & 0x07u);
    (void)co_node_send(node, &f); /* a dropped frame is counted by the node; the client times out */
}

/* Sends a response without segment data. */
static void send_reply(co_sdo_server *s, uint32_t lo, uint32_t hi)
{
    send_frame(s, lo, hi, 0u);
}

/* Sends a segment: the command byte, then n bytes of the buffer from at (the rest 0). */
static void send_segment(co_sdo_server *s, uint32_t command, uint32_t at, uint32_t n)
{
    send_frame(s, command, 0u, at << 3 | n);
}

/* Ends the transfer without a frame. */
static CO_SIZE_NOINLINE void finish(co_sdo_server *s)
{
    s->state = CO_SDO_IDLE;
    s->deadline = CO_NEVER;
}

/* Sends an abort frame for the current multiplexer and ends the transfer. */
static CO_SIZE_NOINLINE void abort_transfer(co_sdo_server *s, co_abort code)
{
    co_node *node = node_of(s);
    finish(s);
    CO_COUNT(node->stats.sdo_aborts);
    send_reply(s, 0x80u | s->mux, code);
}

/* Restarts the client timeout: the transfer lives timeout_us more from now (never 0 here:
 * co_sdo_server_init, which every reset runs, replaces 0 by CO_SDO_TIMEOUT_US). */
static void arm_timeout(co_sdo_server *s, co_time now)
{
    s->deadline = co_time_after(now, s->timeout_us);
}

/* --- CRC -------------------------------------------------------------------------------------- */

/* CRC of each nibble shifted through the polynomial 0x1021: four bits per step (block transfers
 * afford the second step per byte). A nibble n times 0x1021 without carries is
 * n ^ n << 5 ^ n << 12 (no reduction: the product has at most 16 bits). -O2 looks it up in a
 * 32-byte table of those products; -Os computes it (two operations instead of a load, no table). */
#define CRC16_NIBBLE(n) ((n) ^ ((n) << 5) ^ ((n) << 12))
#if defined(__OPTIMIZE_SIZE__)
#define crc16_nibble(n) CRC16_NIBBLE(n)
#else
static const uint16_t crc16_table[16] = {
    CRC16_NIBBLE(0u),  CRC16_NIBBLE(1u),  CRC16_NIBBLE(2u),  CRC16_NIBBLE(3u),
    CRC16_NIBBLE(4u),  CRC16_NIBBLE(5u),  CRC16_NIBBLE(6u),  CRC16_NIBBLE(7u),
    CRC16_NIBBLE(8u),  CRC16_NIBBLE(9u),  CRC16_NIBBLE(10u), CRC16_NIBBLE(11u),
    CRC16_NIBBLE(12u), CRC16_NIBBLE(13u), CRC16_NIBBLE(14u), CRC16_NIBBLE(15u)
};
#define crc16_nibble(n) crc16_table[n]
#endif

/* One step: the CRC after the nibble n (out of line under -Os: one copy for both steps). */
static CO_SIZE_NOINLINE uint16_t crc16_step(uint16_t crc, uint32_t n)
{
    return (uint16_t)((uint16_t)(crc << 4) ^ crc16_nibble((uint32_t)(crc >> 12) ^ n));
}

uint16_t co_sdo_crc16(uint16_t crc, const uint8_t *data, uint32_t len)
{
    for (uint32_t i = 0; i < len; i++) {
        crc = crc16_step(crc, data[i] >> 4u);
        crc = crc16_step(crc, data[i] & 0x0Fu);
    }
    return crc;
}

/* --- download (client to server) -------------------------------------------------------------- */

/* Checks a segmented or block download initiate against the object before any data moves, and
 * sets up the collection of the data. */
static co_abort download_start(co_sdo_server *s, bool size_indicated, uint32_t size)
{
    co_node *node = node_of(s);
    const co_od_sub *sub = s->ref.sub;
    if ((sub->flags & CO_OD_WRITE) == 0u) {
        return CO_ABORT_READ_ONLY;
    }
    if (sub->type == CO_DOMAIN) {
        const co_od_hook *hook = co_node_entry_hook(node, s->ref.entry);
        if (hook == NULL || hook->domain_write == NULL) {
            return CO_ABORT_UNSUPPORTED_ACCESS;
        }
        s->hook = hook;
    } else if (size_indicated) {
        co_abort code = co_od_check_length(sub, size);
        if (code != CO_ABORT_NONE) {
            return code;
        }
        if (size > CO_SDO_BUF_SIZE) {
            return CO_ABORT_OUT_OF_MEMORY;
        }
    }
    s->size_indicated = size_indicated;
    s->size = size & (0u - (uint32_t)size_indicated); /* 0 when not indicated */
    return CO_ABORT_NONE;
}

/* Hands the buffered piece of a DOMAIN to its hook. */
static co_abort domain_flush(co_sdo_server *s, bool last)
{
    co_node *node = node_of(s);
    co_abort code = s->hook->domain_write(node, s->hook->ctx, s->ref, s->offset, s->buf, s->buf_len,
                                          s->size, last);
    s->offset += s->buf_len;
    s->buf_len = 0;
    return code;
}

/* Takes len more bytes of download data: into the buffer for a value (which must then hold the
 * whole value), through the buffer in pieces for a DOMAIN. */
static co_abort download_append(co_sdo_server *s, const uint8_t *data, uint32_t len)
{
    uint32_t held = s->buf_len + len; /* at most the buffer and one segment */
    /* the whole so far, offset + held, in 32-bit arithmetic: beyond when it wraps (only a
     * DOMAIN's offset grows) */
    uint32_t total = s->offset + held;
    bool beyond = total < held;
    if (s->size_indicated && (beyond || total > s->size)) {
        return CO_ABORT_TYPE_LENGTH;
    }
    if (beyond) { /* domain_write offsets are 32-bit */
        return CO_ABORT_OUT_OF_MEMORY;
    }
    if (s->hook == NULL) {
        if (total > co_od_sub_size(s->ref.sub)) {
            return CO_ABORT_TYPE_TOO_LONG;
        }
        if (total > CO_SDO_BUF_SIZE) {
            return CO_ABORT_OUT_OF_MEMORY;
        }
    } else if (held > CO_SDO_BUF_SIZE) {
        co_abort code = domain_flush(s, false);
        if (code != CO_ABORT_NONE) {
            return code;
        }
    }
    if (s->crc_enabled) {
        s->crc = co_sdo_crc16(s->crc, data, len);
    }
    memcpy(&s->buf[s->buf_len], data, len);
    s->buf_len += len;
    return CO_ABORT_NONE;
}

/* All data is in: checks the CRC (a block download's, when used: its end request d carries it in
 * bytes 1-2), the announced size, and writes the value (or the DOMAIN's last piece). */
static co_abort download_finish(co_sdo_server *s, const uint8_t *d)
{
    co_node *node = node_of(s);
    if (s->crc_enabled && s->crc != co_get_le16(&d[1])) {
        return CO_ABORT_CRC;
    }
    if (s->size_indicated && s->offset + s->buf_len != s->size) {
        return CO_ABORT_TYPE_LENGTH;
    }
    if (s->hook != NULL) {
        return domain_flush(s, true);
    }
    return co_od_write_ref(node, s->ref, s->buf, s->buf_len, CO_ORIGIN_SDO);
}

/* Expedited transfer without a size: the value's own size when it fits, else all four bytes. */
static uint32_t expedited_length(const co_od_sub *sub)
{
    uint32_t size = co_od_sub_size(sub);
    return size - 1u < 3u ? size : 4u; /* 1..3 (0 wraps) */
}

/* Acknowledges the sub-block up to the last in-order segment; the client repeats the rest. */
static void block_download_ack(co_sdo_server *s)
{
    uint32_t sequence = s->sequence;
    s->sequence = 0;
    send_reply(s, 0xA2u | (sequence << 8) | ((uint32_t)s->block_size << 16), 0u);
}

static co_abort block_download_segment(co_sdo_server *s, uint32_t command, const uint8_t *d)
{
    uint32_t seqno = command & 0x7Fu;
    bool last = (command & 0x80u) != 0u;
    if (command == 0x80u) { /* sequence number 0 is never a segment: this is the client's abort */
        finish(s);
        return CO_ABORT_NONE;
    }
    if (seqno - 1u >= s->block_size) { /* 0 (wraps) or beyond the sub-block */
        return CO_ABORT_SEQUENCE;
    }
    if (seqno == s->sequence + 1u) {
        /* The held segment was not the last, so all 7 of its bytes are data (none before the
         * first segment). */
        co_abort code = download_append(s, &s->segment[1], s->segment_held);
        if (code != CO_ABORT_NONE) {
            return code;
        }
        memcpy(s->segment, d, 8u); /* the whole frame: two words */
        s->segment_held = SEGMENT_DATA;
        s->sequence = (uint8_t)seqno;
        s->state = (co_sdo_state)(CO_SDO_DOWNLOAD_BLOCK + (command >> 7)); /* END after the last */
    }
    /* A segment out of order (one before it was lost) is ignored until the sub-block ends. */
    if (last || seqno == s->block_size) {
        block_download_ack(s);
    }
    return CO_ABORT_NONE;
}

/* Download data of a segment (segmented) or of the held last segment (block download end), and
 * the end of the transfer when it was the last: the size, the CRC (block, when used) and the
 * write. Answers with the segment's toggle bit, or the end of the block download. */
static OFF_FAST_PATH co_abort download_data(co_sdo_server *s, uint32_t command, const uint8_t *d)
{
    bool block = s->state == CO_SDO_DOWNLOAD_BLOCK_END;
    /* bytes of the segment that are not data: bits 3-1 of a segment, 4-2 of the block end */
    uint32_t unused = (command >> (block ? 2u : 1u)) & 0x07u;
    bool last = block || (command & 0x01u) != 0u;
    co_abort code = download_append(s, block ? &s->segment[1] : &d[1], SEGMENT_DATA - unused);
    if (code == CO_ABORT_NONE && last) {
        code = download_finish(s, d); /* (only a block download uses the CRC) */
    }
    if (code == CO_ABORT_NONE) {
        if (last) { /* (an abort ends the transfer itself) */
            finish(s);
        }
        send_reply(s, block ? 0xA1u : 0x20u | (command & 0x10u), 0u);
    }
    return code;
}

/* --- upload (server to client) ---------------------------------------------------------------- */

/* DOMAIN upload: moves the unsent bytes to the front of the buffer and fills the rest from the
 * hook, up to the buffer's size or the end of the object. */
static co_abort upload_fill(co_sdo_server *s)
{
    co_node *node = node_of(s);
    uint32_t held = s->buf_len - s->buf_pos;
    for (uint32_t i = 0; i < held; i++) { /* towards the front: a forward copy is safe */
        s->buf[i] = s->buf[s->buf_pos + i];
    }
    s->offset += s->buf_pos;
    s->size -= s->buf_pos; /* the end stays where it is in the object */
    s->buf_pos = 0;
    for (;;) {
        uint32_t room = min_u32(CO_SDO_BUF_SIZE, s->size); /* a full buffer or the end */
        if (held >= room) {
            break;
        }
        uint32_t want = room - held;
        uint32_t len = 0, total = 0;
        co_abort code = s->hook->domain_read(node, s->hook->ctx, s->ref, s->offset + held,
                                             &s->buf[held], want, &len, &total);
        if (code != CO_ABORT_NONE) { /* (the transfer ends: what the buffer holds is lost) */
            return code;
        }
        if (len > want) {
            return CO_ABORT_GENERAL;
        }
        if (len == 0u) { /* the hook has less than it announced */
            return CO_ABORT_NO_DATA;
        }
        held += len;
    }
    s->buf_len = held;
    return CO_ABORT_NONE;
}

/* Reads the object for an upload (co_od_read_sized): a value whole into the buffer, a DOMAIN's
 * size and first piece from its hook (a whole buffer asked for at offset 0), then the rest of a
 * buffer. */
static co_abort upload_start(co_sdo_server *s)
{
    co_node *node = node_of(s);
    co_abort code = co_od_read_sized(node, &s->ref, s->buf, CO_SDO_BUF_SIZE, &s->buf_len, &s->size,
                                     CO_ORIGIN_SDO);
    if (code != CO_ABORT_NONE || s->ref.sub->type != CO_DOMAIN) {
        return code;
    }
    if (s->buf_len > CO_SDO_BUF_SIZE) {
        return CO_ABORT_GENERAL;
    }
    /* (bytes beyond the total the hook may have put there are never sent) */
    s->hook = co_node_entry_hook(node, s->ref.entry);
    return upload_fill(s);
}

/* The next bytes to send from buf_pos, at most max (up to the end of the object), made present
 * in the buffer; *span says how many. */
static CO_SIZE_NOINLINE co_abort upload_next(co_sdo_server *s, uint32_t max, uint32_t *span)
{
    uint32_t n = min_u32(s->size - s->buf_pos, max);
    *span = n;
    if (s->buf_len - s->buf_pos < n) { /* only a DOMAIN's buffer holds less than the object */
        return upload_fill(s);
    }
    return CO_ABORT_NONE;
}

/* The next segment of a segmented upload; toggle is the request's toggle bit (bit 4). */
static co_abort upload_segment(co_sdo_server *s, uint32_t toggle)
{
    uint32_t n;
    co_abort code = upload_next(s, SEGMENT_DATA, &n);
    if (code != CO_ABORT_NONE) {
        return code;
    }
    uint32_t at = s->buf_pos;
    bool last = s->size - at == n; /* nothing after this segment */
    s->buf_pos = at + n;
    if (last) {
        finish(s);
    }
    send_segment(s, toggle | ((SEGMENT_DATA - n) << 1) | (last ? 1u : 0u), at, n);
    return CO_ABORT_NONE;
}

/* --- block upload ----------------------------------------------------------------------------- */

/* A block size the client may ask for: 1..127, and for a DOMAIN, a sub-block the buffer holds
 * (it must stay there until acknowledged, to be repeated). */
static CO_SIZE_NOINLINE bool block_size_valid(const co_sdo_server *s, uint32_t block_size)
{
    /* block_size * 7 <= CO_SDO_BUF_SIZE is block_size <= CO_SDO_BUF_SIZE / 7; 0 wraps */
    return block_size - 1u < (s->hook == NULL ? BLOCK_SIZE_MAX : BLOCK_SIZE_OFFER);
}

/* Sends the segments of the current sub-block the transmit queue has room for; the rest go out
 * from co_sdo_server_process. The timeout runs from the last segment sent. Returns true when
 * segments are held back. */
static bool block_upload_send(co_sdo_server *s, co_time now)
{
    co_node *node = node_of(s);
    uint32_t end = s->size; /* end of the object, relative to buf */
    while (s->sequence < s->block_segments) {
        if (node->txq.count >= CO_TX_QUEUE_LEN) {
            return true;
        }
        uint32_t at = s->buf_pos + (uint32_t)s->sequence * SEGMENT_DATA;
        s->sequence++;
        send_segment(s, (end - at <= SEGMENT_DATA ? 0x80u : 0u) | s->sequence, at,
                     min_u32(end - at, SEGMENT_DATA));
    }
    arm_timeout(s, now);
    return false;
}

/* Starts a sub-block at the first unacknowledged byte. */
static co_abort block_upload_sub_block(co_sdo_server *s, co_time now)
{
    uint32_t span;
    co_abort code = upload_next(s, (uint32_t)s->block_size * SEGMENT_DATA, &span);
    if (code != CO_ABORT_NONE) {
        return code;
    }
    /* An empty object still takes one segment (with no data). */
    s->block_segments =
        (uint8_t)((span + SEGMENT_DATA - 1u) / SEGMENT_DATA | (span == 0u ? 1u : 0u));
    s->sequence = 0;
    s->state = CO_SDO_UPLOAD_BLOCK;
    (void)block_upload_send(s, now);
    return CO_ABORT_NONE;
}

static co_abort block_upload_ack(co_sdo_server *s, const uint8_t *d, co_time now)
{
    uint32_t acked_segments = d[1];
    uint32_t block_size = d[2];
    if (acked_segments > s->sequence) {
        return CO_ABORT_SEQUENCE;
    }
    if (!block_size_valid(s, block_size)) {
        return CO_ABORT_BLOCK_SIZE;
    }
    uint32_t end = s->size;
    uint32_t acked = min_u32(acked_segments * SEGMENT_DATA, end - s->buf_pos);
    if (s->crc_enabled) {
        s->crc = co_sdo_crc16(s->crc, &s->buf[s->buf_pos], acked);
    }
    s->buf_pos += acked;
    s->block_size = (uint8_t)block_size;
    if (acked_segments != s->block_segments || s->buf_pos != end) {
        return block_upload_sub_block(s, now);
    }
    /* Everything acknowledged: n is the number of bytes of the last segment that were not data;
     * the CRC stays 0 when it is not used. */
    uint32_t last_bytes = acked - (acked_segments - 1u) * SEGMENT_DATA;
    s->state = CO_SDO_UPLOAD_BLOCK_END;
    send_reply(s, 0xC1u | ((SEGMENT_DATA - last_bytes) << 2) | ((uint32_t)s->crc << 8), 0u);
    return CO_ABORT_NONE;
}

/* --- dispatch --------------------------------------------------------------------------------- */

/* Every initiate request: a transfer in progress is dropped (see the top of this file), the
 * multiplexer taken, the object looked up and checked, and the transfer set up and answered. */
static co_abort initiate(co_sdo_server *s, const uint8_t *d, uint32_t ccs)
{
    co_node *node = node_of(s);
    uint32_t command = d[0];
    uint32_t value = co_get_le32(&d[4]); /* the size, or an expedited download's data */
    uint32_t reply;
    co_abort code;
    finish(s);
    uint32_t mux = co_get_le32(d) & 0xFFFFFF00u; /* index << 8 | subindex << 24 */
    s->mux = mux;
    code = co_node_locate(node, mux >> 8, mux >> 24, &s->ref);
    if (code != CO_ABORT_NONE) {
        return code;
    }
    if (ccs == CCS_DOWNLOAD_INITIATE && (command & 0x02u) != 0u) { /* expedited: data in here */
        uint32_t len = (command & 0x01u) != 0u ? 4u - ((command >> 2) & 0x03u)
                                               : expedited_length(s->ref.sub);
        code = co_od_write_ref(node, s->ref, &d[4], len, CO_ORIGIN_SDO);
        reply = 0x60u;
        value = 0u;
    } else {
        /* a transfer that may go on: from the start, no DOMAIN hook, CRC as the client asks */
        s->hook = NULL;
        s->offset = 0;
        s->buf_len = 0;
        s->buf_pos = 0;
        s->toggle = 0;
        s->sequence = 0;
        s->segment_held = 0;
        s->crc = 0;
        s->crc_enabled = ccs >= CCS_BLOCK_UPLOAD && (command & 0x04u) != 0u;
        if (ccs == CCS_DOWNLOAD_INITIATE) {
            code = download_start(s, (command & 0x01u) != 0u, value);
            s->state = CO_SDO_DOWNLOAD_SEGMENTED;
            reply = 0x60u;
            value = 0u;
        } else if (ccs == CCS_BLOCK_DOWNLOAD) {
            code = download_start(s, (command & 0x02u) != 0u, value);
            s->block_size = (uint8_t)BLOCK_SIZE_OFFER;
            s->state = CO_SDO_DOWNLOAD_BLOCK;
            reply = 0xA4u; /* scs 5, sc: the server can check a CRC */
            value = BLOCK_SIZE_OFFER;
        } else {
            code = upload_start(s);
            if (code != CO_ABORT_NONE) {
                return code;
            }
            value = s->size;
            /* A block upload of an object at most the client's protocol switch threshold (0: the
             * client forbids the switch) is answered as a normal upload. */
            if (ccs == CCS_BLOCK_UPLOAD && !block_size_valid(s, d[4])) {
                return CO_ABORT_BLOCK_SIZE;
            }
            /* (ccs tested twice, not a marker tested later: gcc merges the two tests) */
            if (ccs == CCS_BLOCK_UPLOAD && (d[5] == 0u || value > d[5])) {
                s->block_size = d[4];
                s->state = CO_SDO_UPLOAD_BLOCK_INITIATED;
                reply = 0xC6u; /* scs 6, sc: CRC supported, s: size indicated */
            } else if (value != 0u && value <= 4u) {
                /* expedited, the bytes past the value 0 (a DOMAIN's hook may have put more there) */
                uint32_t unused = 4u - value;
                reply = 0x43u | (unused << 2);
                value = co_get_le32(s->buf) << (unused * 8u) >> (unused * 8u);
            } else { /* an empty value goes segmented too: an expedited frame cannot say 0 bytes */
                reply = 0x41u;
                s->state = CO_SDO_UPLOAD_SEGMENTED;
            }
        }
    }
    if (code != CO_ABORT_NONE) {
        return code;
    }
    send_reply(s, reply | s->mux, value);
    return CO_ABORT_NONE;
}

void co_sdo_server_init(co_node *node)
{
    co_sdo_server *s = &node->sdo;
    finish(s);
    s->mux = 0; /* what an abort carries until the next initiate (which sets up the rest) */
    if (s->timeout_us == 0u) {
        s->timeout_us = CO_SDO_TIMEOUT_US;
    }
    co_node_recheck(node);
}

/* Handles a request; returns the abort to answer it with, or CO_ABORT_NONE. */
static co_abort dispatch(co_sdo_server *s, const uint8_t *d, co_time now)
{
    uint32_t command = d[0];
    uint32_t ccs = command >> 5;
    uint32_t expected; /* the state a request that continues a transfer belongs to */
    if (s->state == CO_SDO_DOWNLOAD_BLOCK) { /* byte 0 is a sequence number, not a command */
        return block_download_segment(s, command, d);
    }
    /* -O2 tests for the initiates (the expedited transfers) before the jump table; -Os takes
     * them in it, which spares the test */
#if !defined(__OPTIMIZE_SIZE__)
    if (ccs == CCS_DOWNLOAD_INITIATE || ccs == CCS_UPLOAD_INITIATE) {
        expected = INITIATE_REQUEST;
    } else
#endif
    switch (ccs) {
    case CCS_DOWNLOAD_INITIATE:
    case CCS_UPLOAD_INITIATE:
        expected = INITIATE_REQUEST;
        break;
    case CCS_ABORT: /* the client ends the transfer; nothing is answered, even when idle */
        finish(s);
        return CO_ABORT_NONE;
    case CCS_DOWNLOAD_SEGMENT:
    case CCS_UPLOAD_SEGMENT: /* ccs 0 and 3: the two segmented states */
        expected = CO_SDO_DOWNLOAD_SEGMENTED + (ccs >> 1);
        break;
    case CCS_BLOCK_UPLOAD:
        /* end 1, acknowledgement 2, start 3: the three block upload states backwards; the
         * initiate (0) one past them */
        expected = CO_SDO_UPLOAD_BLOCK_END + BLOCK_UP_END - (command & 0x03u);
        break;
    case CCS_BLOCK_DOWNLOAD:
        expected = (command & 0x01u) != 0u ? CO_SDO_DOWNLOAD_BLOCK_END : INITIATE_REQUEST;
        break;
    default: /* ccs 7 does not exist */
        return CO_ABORT_COMMAND;
    }
    if (expected == INITIATE_REQUEST) {
        return initiate(s, d, ccs);
    }
    if (s->state != expected) {
        return CO_ABORT_COMMAND;
    }
    switch (expected) {
    case CO_SDO_DOWNLOAD_SEGMENTED:
    case CO_SDO_UPLOAD_SEGMENTED: { /* segmented: the toggle bit alternates from 0 */
        uint32_t toggle = command & 0x10u;
        if (toggle != s->toggle) {
            return CO_ABORT_TOGGLE;
        }
        s->toggle = (uint8_t)(toggle ^ 0x10u); /* an initiate clears it again */
        if (expected == CO_SDO_UPLOAD_SEGMENTED) {
            return upload_segment(s, toggle);
        }
    }
        /* fall through */
    case CO_SDO_DOWNLOAD_BLOCK_END:
        return download_data(s, command, d);
    case CO_SDO_UPLOAD_BLOCK_INITIATED:
        return block_upload_sub_block(s, now);
    case CO_SDO_UPLOAD_BLOCK:
        return block_upload_ack(s, d, now);
    default: /* CO_SDO_UPLOAD_BLOCK_END */
        finish(s);
        return CO_ABORT_NONE;
    }
}

/* Handles a request, answers it and restarts the timeout of the transfer it keeps going. */
static CO_SIZE_NOINLINE void request(co_sdo_server *s, const uint8_t *d, co_time now)
{
    co_abort code = dispatch(s, d, now);
    if (code != CO_ABORT_NONE) {
        abort_transfer(s, code);
    } else if (s->state != CO_SDO_IDLE && s->state != CO_SDO_UPLOAD_BLOCK) {
        /* every request that keeps a transfer going restarts its timeout (a block upload's
         * runs from its last segment sent, block_upload_send) */
        arm_timeout(s, now);
    }
}

void co_sdo_server_rx(co_node *node, const co_frame *frame, co_time now)
{
    co_sdo_server *s = &node->sdo;
    /* The deadline is CO_NEVER whenever the server is idle (finish, abort, init). */
    co_time old = s->deadline;
    if (frame->dlc != 8u || (frame->flags & CO_FRAME_RTR) != 0u) {
        CO_COUNT(node->stats.rx_malformed);
    } else {
        request(s, frame->data, now);
    }
    co_node_reschedule(node, old, s->deadline);
    if (node->pdo.pending) {
        (void)co_pdo_process(node, now); /* TPDOs mapping a value the SDO wrote go out now */
    }
}

static CO_SIZE_NOINLINE co_time process(co_sdo_server *s, co_time now)
{
    if (s->state == CO_SDO_IDLE) {
        return CO_NEVER;
    }
    if (now >= s->deadline) {
        abort_transfer(s, CO_ABORT_TIMEOUT);
        return CO_NEVER;
    }
    if (s->state == CO_SDO_UPLOAD_BLOCK && s->sequence < s->block_segments &&
        block_upload_send(s, now)) {
        co_time retry = co_time_after(now, CO_SDO_TX_RETRY_US);
        return retry < s->deadline ? retry : s->deadline;
    }
    return s->deadline;
}

co_time co_sdo_server_process(co_node *node, co_time now)
{
    return process(&node->sdo, now);
}

void co_sdo_server_abort(co_node *node, uint32_t code)
{
    if (node->sdo.state != CO_SDO_IDLE) {
        abort_transfer(&node->sdo, code);
        co_node_recheck(node);
    }
}
