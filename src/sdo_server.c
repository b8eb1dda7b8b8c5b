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

#define SEGMENT_DATA 7u     /* data bytes in one segment */
#define BLOCK_SIZE_MAX 127u /* segments in one sub-block (7-bit sequence number) */

/* Download sub-blocks the server offers: what the buffer holds, at most 127. */
#define BLOCK_SIZE_OFFER                                                  \
    ((CO_SDO_BUF_SIZE / SEGMENT_DATA) > BLOCK_SIZE_MAX ? BLOCK_SIZE_MAX \
                                                       : (CO_SDO_BUF_SIZE / SEGMENT_DATA))

static uint32_t min_u32(uint32_t a, uint32_t b)
{
    return a < b ? a : b;
}

/* --- frames ----------------------------------------------------------------------------------- */

/* A zeroed response: CiA 301 reserved bytes are 0. */
static void response_init(co_frame *f, uint8_t command)
{
    memset(f, 0, sizeof *f);
    f->dlc = 8;
    f->data[0] = command;
}

/* A response that repeats the multiplexer of the transfer (initiate responses, aborts). */
static void response_init_mux(co_frame *f, const co_sdo_server *s, uint8_t command)
{
    f->flags = 0u;
    f->dlc = 8;
    f->data[0] = command;
    co_put_le16(&f->data[1], s->index);
    f->data[3] = s->subindex;
    co_put_le32(&f->data[4], 0u);
}

static void send_response(co_node *node, co_frame *f)
{
    f->id = node->sdo_tx_cob;
    (void)co_node_send(node, f); /* a dropped frame is counted by the node; the client times out */
}

/* Sends an abort frame for the current multiplexer and ends the transfer. */
static void abort_transfer(co_node *node, co_abort code)
{
    co_sdo_server *s = &node->sdo;
    co_frame f;
    s->state = CO_SDO_IDLE;
    s->deadline = CO_NEVER;
    response_init_mux(&f, s, 0x80u);
    co_put_le32(&f.data[4], code);
    CO_COUNT(node->stats.sdo_aborts);
    send_response(node, &f);
}

/* Ends the transfer without a frame. */
static CO_SIZE_NOINLINE void finish(co_sdo_server *s)
{
    s->state = CO_SDO_IDLE;
    s->deadline = CO_NEVER;
}

/* Restarts the client timeout: the transfer lives timeout_us more from now. */
static void arm_timeout(co_node *node, co_time now)
{
    co_sdo_server *s = &node->sdo;
    s->deadline = co_time_after(now, s->timeout_us != 0u ? s->timeout_us : CO_SDO_TIMEOUT_US);
}

/* --- CRC -------------------------------------------------------------------------------------- */

/* CRC of each nibble shifted through the polynomial 0x1021: four bits per step, so the table
 * takes 32 bytes instead of 512 (block transfers afford the second step per byte). */
static const uint16_t crc16_nibble[16] = {
    0x0000u, 0x1021u, 0x2042u, 0x3063u, 0x4084u, 0x50A5u, 0x60C6u, 0x70E7u,
    0x8108u, 0x9129u, 0xA14Au, 0xB16Bu, 0xC18Cu, 0xD1ADu, 0xE1CEu, 0xF1EFu
};

uint16_t co_sdo_crc16(uint16_t crc, const uint8_t *data, uint32_t len)
{
    for (uint32_t i = 0; i < len; i++) {
        crc = (uint16_t)((uint16_t)(crc << 4) ^ crc16_nibble[(crc >> 12) ^ (data[i] >> 4)]);
        crc = (uint16_t)((uint16_t)(crc << 4) ^ crc16_nibble[(crc >> 12) ^ (data[i] & 0x0Fu)]);
    }
    return crc;
}

/* The start of every initiate request: a transfer in progress is dropped (see the top of this
 * file), the multiplexer is taken and the object looked up. */
static CO_SIZE_NOINLINE co_abort initiate(co_node *node, const uint8_t *d)
{
    co_sdo_server *s = &node->sdo;
    finish(s);
    s->index = co_get_le16(&d[1]);
    s->subindex = d[3];
    return co_node_locate(node, s->index, s->subindex, &s->ref);
}

/* --- download (client to server) -------------------------------------------------------------- */

/* Types a shorter value may be written to (co_od_check_value pads them). */
static bool shorter_allowed(uint8_t type)
{
    return type == CO_VISIBLE_STRING || type == CO_UNICODE_STRING;
}

/* Checks a segmented or block download initiate against the object before any data moves, and
 * sets up the collection of the data. */
static co_abort download_start(co_node *node, bool size_indicated, uint32_t size)
{
    co_sdo_server *s = &node->sdo;
    const co_od_sub *sub = s->ref.sub;
    if ((sub->flags & CO_OD_WRITE) == 0u) {
        return CO_ABORT_READ_ONLY;
    }
    s->hook = NULL;
    if (sub->type == CO_DOMAIN) {
        const co_od_hook *hook = co_node_entry_hook(node, s->ref.entry);
        if (hook == NULL || hook->domain_write == NULL) {
            return CO_ABORT_UNSUPPORTED_ACCESS;
        }
        s->hook = hook;
    } else if (size_indicated) {
        if (size > co_od_sub_size(sub)) {
            return CO_ABORT_TYPE_TOO_LONG;
        }
        if (size < co_od_sub_size(sub) && !shorter_allowed(sub->type)) {
            return CO_ABORT_TYPE_TOO_SHORT;
        }
        if (size > CO_SDO_BUF_SIZE) {
            return CO_ABORT_OUT_OF_MEMORY;
        }
    }
    s->size_indicated = size_indicated;
    s->size = size_indicated ? size : 0u;
    s->offset = 0;
    s->buf_len = 0;
    s->crc_enabled = false;
    s->crc = 0;
    return CO_ABORT_NONE;
}

/* Hands the buffered piece of a DOMAIN to its hook. */
static co_abort domain_flush(co_node *node, bool last)
{
    co_sdo_server *s = &node->sdo;
    co_abort code = s->hook->domain_write(node, s->hook->ctx, s->ref, s->offset, s->buf, s->buf_len,
                                          s->size, last);
    s->offset += s->buf_len;
    s->buf_len = 0;
    return code;
}

/* Takes len more bytes of download data: into the buffer for a value (which must then hold the
 * whole value), through the buffer in pieces for a DOMAIN. */
static co_abort download_append(co_node *node, const uint8_t *data, uint32_t len)
{
    co_sdo_server *s = &node->sdo;
    uint32_t held = s->buf_len + len; /* at most the buffer and one segment */
    /* the whole so far, offset + held, in 32-bit arithmetic: beyond when it does not fit */
    bool beyond = s->offset > UINT32_MAX - held;
    uint32_t total = s->offset + held;
    if (s->size_indicated && (beyond || total > s->size)) {
        return CO_ABORT_TYPE_LENGTH;
    }
    if (s->hook == NULL) {
        if (beyond || total > co_od_sub_size(s->ref.sub)) {
            return CO_ABORT_TYPE_TOO_LONG;
        }
        if (total > CO_SDO_BUF_SIZE) {
            return CO_ABORT_OUT_OF_MEMORY;
        }
    } else {
        if (beyond) { /* domain_write offsets are 32-bit */
            return CO_ABORT_OUT_OF_MEMORY;
        }
        if (held > CO_SDO_BUF_SIZE) {
            co_abort code = domain_flush(node, false);
            if (code != CO_ABORT_NONE) {
                return code;
            }
        }
    }
    if (s->crc_enabled) {
        s->crc = co_sdo_crc16(s->crc, data, len);
    }
    memcpy(&s->buf[s->buf_len], data, len);
    s->buf_len += len;
    return CO_ABORT_NONE;
}

/* All data is in: checks the announced size and writes the value (or the DOMAIN's last piece). */
static co_abort download_finish(co_node *node)
{
    co_sdo_server *s = &node->sdo;
    if (s->size_indicated && s->offset + s->buf_len != s->size) {
        return CO_ABORT_TYPE_LENGTH;
    }
    if (s->hook != NULL) {
        return domain_flush(node, true);
    }
    return co_od_write_ref(node, s->ref, s->buf, s->buf_len, CO_ORIGIN_SDO);
}

/* Expedited transfer without a size: the value's own size when it fits, else all four bytes. */
static uint32_t expedited_length(const co_od_sub *sub)
{
    return (co_od_sub_size(sub) != 0u && co_od_sub_size(sub) < 4u) ? co_od_sub_size(sub) : 4u;
}

static void download_initiate(co_node *node, const uint8_t *d, co_time now)
{
    co_sdo_server *s = &node->sdo;
    uint8_t command = d[0];
    co_frame f;
    co_abort code = initiate(node, d);
    if (code == CO_ABORT_NONE) {
        if ((command & 0x02u) != 0u) { /* expedited: the data is in this frame */
            uint32_t len = (command & 0x01u) != 0u ? 4u - ((command >> 2) & 0x03u)
                                                   : expedited_length(s->ref.sub);
            code = co_od_write_ref(node, s->ref, &d[4], len, CO_ORIGIN_SDO);
        } else {
            code = download_start(node, (command & 0x01u) != 0u, co_get_le32(&d[4]));
            if (code == CO_ABORT_NONE) {
                s->state = CO_SDO_DOWNLOAD_SEGMENTED;
                s->toggle = 0;
                arm_timeout(node, now);
            }
        }
    }
    if (code != CO_ABORT_NONE) {
        abort_transfer(node, code);
        return;
    }
    response_init_mux(&f, s, 0x60u);
    send_response(node, &f);
}

static void download_segment(co_node *node, const uint8_t *d, co_time now)
{
    co_sdo_server *s = &node->sdo;
    uint8_t command = d[0];
    bool last = (command & 0x01u) != 0u;
    co_frame f;
    if (((command >> 4) & 0x01u) != s->toggle) {
        abort_transfer(node, CO_ABORT_TOGGLE);
        return;
    }
    co_abort code = download_append(node, &d[1], SEGMENT_DATA - ((command >> 1) & 0x07u));
    if (code == CO_ABORT_NONE && last) {
        code = download_finish(node);
    }
    if (code != CO_ABORT_NONE) {
        abort_transfer(node, code);
        return;
    }
    response_init(&f, (uint8_t)(0x20u | ((uint32_t)s->toggle << 4)));
    if (last) {
        finish(s);
    } else {
        s->toggle ^= 1u;
        arm_timeout(node, now);
    }
    send_response(node, &f);
}

/* --- block download --------------------------------------------------------------------------- */

static void block_download_initiate(co_node *node, const uint8_t *d, co_time now)
{
    co_sdo_server *s = &node->sdo;
    uint8_t command = d[0];
    co_frame f;
    co_abort code = initiate(node, d);
    if (code == CO_ABORT_NONE) {
        code = download_start(node, (command & 0x02u) != 0u, co_get_le32(&d[4]));
    }
    if (code != CO_ABORT_NONE) {
        abort_transfer(node, code);
        return;
    }
    s->crc_enabled = (command & 0x04u) != 0u;
    s->block_size = (uint8_t)BLOCK_SIZE_OFFER;
    s->sequence = 0;
    s->segment_held = false;
    s->state = CO_SDO_DOWNLOAD_BLOCK;
    arm_timeout(node, now);
    response_init_mux(&f, s, 0xA4u); /* scs 5, sc: the server can check a CRC */
    f.data[4] = s->block_size;
    send_response(node, &f);
}

/* Acknowledges the sub-block up to the last in-order segment; the client repeats the rest. */
static void block_download_ack(co_node *node)
{
    co_sdo_server *s = &node->sdo;
    co_frame f;
    response_init(&f, 0xA2u);
    f.data[1] = s->sequence;
    f.data[2] = s->block_size;
    s->sequence = 0;
    send_response(node, &f);
}

static void block_download_segment(co_node *node, const uint8_t *d, co_time now)
{
    co_sdo_server *s = &node->sdo;
    uint8_t command = d[0];
    uint8_t seqno = command & 0x7Fu;
    bool last = (command & 0x80u) != 0u;
    if (command == 0x80u) { /* sequence number 0 is never a segment: this is the client's abort */
        finish(s);
        return;
    }
    if (seqno == 0u || seqno > s->block_size) {
        abort_transfer(node, CO_ABORT_SEQUENCE);
        return;
    }
    arm_timeout(node, now);
    if (seqno == s->sequence + 1u) {
        /* The held segment was not the last, so all 7 of its bytes are data. */
        if (s->segment_held) {
            co_abort code = download_append(node, s->segment, SEGMENT_DATA);
            if (code != CO_ABORT_NONE) {
                abort_transfer(node, code);
                return;
            }
        }
        memcpy(s->segment, &d[1], SEGMENT_DATA);
        s->segment_held = true;
        s->sequence = seqno;
        if (last) {
            s->state = CO_SDO_DOWNLOAD_BLOCK_END;
            block_download_ack(node);
            return;
        }
    }
    /* A segment out of order (one before it was lost) is ignored until the sub-block ends. */
    if (last || seqno == s->block_size) {
        block_download_ack(node);
    }
}

static void block_download_end(co_node *node, const uint8_t *d)
{
    co_sdo_server *s = &node->sdo;
    co_frame f;
    uint32_t unused = (d[0] >> 2) & 0x07u; /* bytes of the last segment that are not data */
    co_abort code = download_append(node, s->segment, SEGMENT_DATA - unused);
    if (code == CO_ABORT_NONE && s->crc_enabled && s->crc != co_get_le16(&d[1])) {
        code = CO_ABORT_CRC;
    }
    if (code == CO_ABORT_NONE) {
        code = download_finish(node);
    }
    if (code != CO_ABORT_NONE) {
        abort_transfer(node, code);
        return;
    }
    finish(s);
    response_init(&f, 0xA1u);
    send_response(node, &f);
}

/* --- upload (server to client) ---------------------------------------------------------------- */

/* DOMAIN upload: moves the unsent bytes to the front of the buffer and fills the rest from the
 * hook, up to the buffer's size or the end of the object. */
static co_abort upload_fill(co_node *node)
{
    co_sdo_server *s = &node->sdo;
    uint32_t keep = s->buf_len - s->buf_pos;
    for (uint32_t i = 0; i < keep; i++) { /* towards the front: a forward copy is safe */
        s->buf[i] = s->buf[s->buf_pos + i];
    }
    s->offset += s->buf_pos;
    s->buf_pos = 0;
    s->buf_len = keep;
    while (s->buf_len < CO_SDO_BUF_SIZE && s->offset + s->buf_len < s->size) {
        uint32_t want = min_u32(CO_SDO_BUF_SIZE - s->buf_len, s->size - s->offset - s->buf_len);
        uint32_t len = 0, total = 0;
        co_abort code = s->hook->domain_read(node, s->hook->ctx, s->ref, s->offset + s->buf_len,
                                             &s->buf[s->buf_len], want, &len, &total);
        if (code != CO_ABORT_NONE) {
            return code;
        }
        if (len == 0u) { /* the hook has less than it announced */
            return CO_ABORT_NO_DATA;
        }
        if (len > want) {
            return CO_ABORT_GENERAL;
        }
        s->buf_len += len;
    }
    return CO_ABORT_NONE;
}

/* Reads the object for an upload: a value whole into the buffer, a DOMAIN's size and first piece
 * from its hook. */
static co_abort upload_start(co_node *node)
{
    co_sdo_server *s = &node->sdo;
    const co_od_sub *sub = s->ref.sub;
    s->offset = 0;
    s->buf_pos = 0;
    s->hook = NULL;
    memset(s->buf, 0, 4u); /* an expedited answer sends 4 bytes: past the value, zeros */
    if (sub->type != CO_DOMAIN) {
        co_abort code = co_od_read_ref(node, s->ref, s->buf, CO_SDO_BUF_SIZE, &s->buf_len,
                                       CO_ORIGIN_SDO);
        s->size = s->buf_len;
        return code;
    }
    if ((sub->flags & CO_OD_READ) == 0u) {
        return CO_ABORT_WRITE_ONLY;
    }
    const co_od_hook *hook = co_node_entry_hook(node, s->ref.entry);
    if (hook == NULL || hook->domain_read == NULL) {
        return CO_ABORT_NO_DATA;
    }
    s->hook = hook;
    uint32_t len = 0, total = 0;
    co_abort code = hook->domain_read(node, hook->ctx, s->ref, 0, s->buf, CO_SDO_BUF_SIZE, &len,
                                      &total);
    if (code != CO_ABORT_NONE) {
        return code;
    }
    if (len > CO_SDO_BUF_SIZE) {
        return CO_ABORT_GENERAL;
    }
    s->size = total;
    s->buf_len = min_u32(len, total);
    return upload_fill(node);
}

/* Answers an upload initiate (or a block upload initiate below the protocol switch threshold):
 * expedited when the value fits in the frame, else segmented with the size indicated. */
static void upload_respond(co_node *node, co_time now)
{
    co_sdo_server *s = &node->sdo;
    co_frame f;
    if (s->size != 0u && s->size <= 4u) {
        response_init_mux(&f, s, (uint8_t)(0x43u | ((4u - s->size) << 2)));
        /* all four bytes at once: upload_start cleared them before the value was read in (a
         * DOMAIN's hook may have put more than its size there) */
        memcpy(&f.data[4], s->buf, 4u);
        for (uint32_t i = s->hook != NULL ? s->size : 4u; i < 4u; i++) {
            f.data[4u + i] = 0u;
        }
    } else { /* an empty value goes segmented too: an expedited frame cannot say 0 bytes */
        response_init_mux(&f, s, 0x41u);
        co_put_le32(&f.data[4], s->size);
        s->state = CO_SDO_UPLOAD_SEGMENTED;
        s->toggle = 0;
        arm_timeout(node, now);
    }
    send_response(node, &f);
}

static void upload_initiate(co_node *node, const uint8_t *d, co_time now)
{
    co_abort code = initiate(node, d);
    if (code == CO_ABORT_NONE) {
        code = upload_start(node);
    }
    if (code != CO_ABORT_NONE) {
        abort_transfer(node, code);
        return;
    }
    upload_respond(node, now);
}

static void upload_segment(co_node *node, const uint8_t *d, co_time now)
{
    co_sdo_server *s = &node->sdo;
    co_frame f;
    if (((d[0] >> 4) & 0x01u) != s->toggle) {
        abort_transfer(node, CO_ABORT_TOGGLE);
        return;
    }
    uint32_t remaining = s->size - s->offset - s->buf_pos;
    uint32_t n = min_u32(remaining, SEGMENT_DATA);
    if (s->buf_len - s->buf_pos < n) {
        co_abort code = upload_fill(node);
        if (code != CO_ABORT_NONE) {
            abort_transfer(node, code);
            return;
        }
    }
    bool last = remaining <= SEGMENT_DATA;
    response_init(&f, (uint8_t)(((uint32_t)s->toggle << 4) | ((SEGMENT_DATA - n) << 1) | (last ? 1u : 0u)));
    memcpy(&f.data[1], &s->buf[s->buf_pos], n);
    s->buf_pos += n;
    if (last) {
        finish(s);
    } else {
        s->toggle ^= 1u;
        arm_timeout(node, now);
    }
    send_response(node, &f);
}

/* --- block upload ----------------------------------------------------------------------------- */

/* A block size the client may ask for: 1..127, and for a DOMAIN, a sub-block the buffer holds
 * (it must stay there until acknowledged, to be repeated). */
static CO_SIZE_NOINLINE bool block_size_valid(const co_sdo_server *s, uint8_t block_size)
{
    if (block_size == 0u || block_size > BLOCK_SIZE_MAX) {
        return false;
    }
    return s->hook == NULL || (uint32_t)block_size * SEGMENT_DATA <= CO_SDO_BUF_SIZE;
}

static void block_upload_initiate(co_node *node, const uint8_t *d, co_time now)
{
    co_sdo_server *s = &node->sdo;
    uint8_t block_size = d[4];
    uint8_t switch_threshold = d[5];
    co_frame f;
    co_abort code = initiate(node, d);
    if (code == CO_ABORT_NONE) {
        code = upload_start(node);
    }
    if (code == CO_ABORT_NONE && !block_size_valid(s, block_size)) {
        code = CO_ABORT_BLOCK_SIZE;
    }
    if (code != CO_ABORT_NONE) {
        abort_transfer(node, code);
        return;
    }
    if (switch_threshold != 0u && s->size <= switch_threshold) { /* 0: the client forbids it */
        upload_respond(node, now);
        return;
    }
    s->crc_enabled = (d[0] & 0x04u) != 0u;
    s->crc = 0;
    s->block_size = block_size;
    s->state = CO_SDO_UPLOAD_BLOCK_INITIATED;
    arm_timeout(node, now);
    response_init_mux(&f, s, 0xC6u); /* scs 6, sc: CRC supported, s: size indicated */
    co_put_le32(&f.data[4], s->size);
    send_response(node, &f);
}

/* Sends the segments of the current sub-block the transmit queue has room for; the rest go out
 * from co_sdo_server_process. The timeout runs from the last segment sent. */
static void block_upload_send(co_node *node, co_time now)
{
    co_sdo_server *s = &node->sdo;
    uint32_t end = s->size - s->offset; /* end of the object, relative to buf */
    co_frame f;
    while (s->sequence < s->block_segments) {
        if (node->txq.count >= CO_TX_QUEUE_LEN) {
            return;
        }
        uint32_t at = s->buf_pos + (uint32_t)s->sequence * SEGMENT_DATA;
        uint32_t n = min_u32(end - at, SEGMENT_DATA);
        s->sequence++;
        response_init(&f, (uint8_t)((end - at <= SEGMENT_DATA ? 0x80u : 0u) | s->sequence));
        memcpy(&f.data[1], &s->buf[at], n);
        send_response(node, &f);
    }
    arm_timeout(node, now);
}

/* Starts a sub-block at the first unacknowledged byte. */
static void block_upload_sub_block(co_node *node, co_time now)
{
    co_sdo_server *s = &node->sdo;
    uint32_t remaining = s->size - s->offset - s->buf_pos;
    uint32_t span = min_u32(remaining, (uint32_t)s->block_size * SEGMENT_DATA);
    if (s->buf_len - s->buf_pos < span) {
        co_abort code = upload_fill(node);
        if (code != CO_ABORT_NONE) {
            abort_transfer(node, code);
            return;
        }
    }
    /* An empty object still takes one segment (with no data). */
    s->block_segments = span == 0u ? 1u : (uint8_t)((span + SEGMENT_DATA - 1u) / SEGMENT_DATA);
    s->sequence = 0;
    s->state = CO_SDO_UPLOAD_BLOCK;
    block_upload_send(node, now);
}

static void block_upload_ack(co_node *node, const uint8_t *d, co_time now)
{
    co_sdo_server *s = &node->sdo;
    uint8_t acked_segments = d[1];
    uint8_t block_size = d[2];
    co_frame f;
    if (acked_segments > s->sequence) {
        abort_transfer(node, CO_ABORT_SEQUENCE);
        return;
    }
    if (!block_size_valid(s, block_size)) {
        abort_transfer(node, CO_ABORT_BLOCK_SIZE);
        return;
    }
    uint32_t end = s->size - s->offset;
    uint32_t acked = min_u32((uint32_t)acked_segments * SEGMENT_DATA, end - s->buf_pos);
    if (s->crc_enabled) {
        s->crc = co_sdo_crc16(s->crc, &s->buf[s->buf_pos], acked);
    }
    s->buf_pos += acked;
    s->block_size = block_size;
    if (acked_segments != s->block_segments || s->buf_pos != end) {
        block_upload_sub_block(node, now);
        return;
    }
    /* Everything acknowledged: n is the number of bytes of the last segment that were not data. */
    uint32_t last_bytes = acked - (uint32_t)(s->block_segments - 1u) * SEGMENT_DATA;
    response_init(&f, (uint8_t)(0xC1u | ((SEGMENT_DATA - last_bytes) << 2)));
    co_put_le16(&f.data[1], s->crc_enabled ? s->crc : 0u);
    s->state = CO_SDO_UPLOAD_BLOCK_END;
    arm_timeout(node, now);
    send_response(node, &f);
}

/* --- dispatch --------------------------------------------------------------------------------- */

void co_sdo_server_init(co_node *node)
{
    co_sdo_server *s = &node->sdo;
    s->state = CO_SDO_IDLE;
    s->deadline = CO_NEVER;
    s->hook = NULL;
    s->index = 0;
    s->subindex = 0;
    s->buf_len = 0;
    s->buf_pos = 0;
    if (s->timeout_us == 0u) {
        s->timeout_us = CO_SDO_TIMEOUT_US;
    }
    co_node_recheck(node);
}

static void server_rx(co_node *node, const co_frame *frame, co_time now)
{
    co_sdo_server *s = &node->sdo;
    const uint8_t *d = frame->data;
    if (frame->dlc != 8u || (frame->flags & CO_FRAME_RTR) != 0u) {
        CO_COUNT(node->stats.rx_malformed);
        return;
    }
    if (s->state == CO_SDO_DOWNLOAD_BLOCK) { /* byte 0 is a sequence number, not a command */
        block_download_segment(node, d, now);
        return;
    }
    switch (d[0] >> 5) {
    case CCS_DOWNLOAD_INITIATE:
        download_initiate(node, d, now);
        return;
    case CCS_UPLOAD_INITIATE:
        upload_initiate(node, d, now);
        return;
    case CCS_DOWNLOAD_SEGMENT:
        if (s->state == CO_SDO_DOWNLOAD_SEGMENTED) {
            download_segment(node, d, now);
            return;
        }
        break;
    case CCS_UPLOAD_SEGMENT:
        if (s->state == CO_SDO_UPLOAD_SEGMENTED) {
            upload_segment(node, d, now);
            return;
        }
        break;
    case CCS_ABORT: /* the client ends the transfer; nothing is answered, even when idle */
        finish(s);
        return;
    case CCS_BLOCK_UPLOAD:
        switch (d[0] & 0x03u) {
        case BLOCK_UP_INITIATE:
            block_upload_initiate(node, d, now);
            return;
        case BLOCK_UP_START:
            if (s->state == CO_SDO_UPLOAD_BLOCK_INITIATED) {
                block_upload_sub_block(node, now);
                return;
            }
            break;
        case BLOCK_UP_ACK:
            if (s->state == CO_SDO_UPLOAD_BLOCK) {
                block_upload_ack(node, d, now);
                return;
            }
            break;
        default: /* BLOCK_UP_END */
            if (s->state == CO_SDO_UPLOAD_BLOCK_END) {
                finish(s);
                return;
            }
            break;
        }
        break;
    case CCS_BLOCK_DOWNLOAD:
        if ((d[0] & 0x01u) == 0u) {
            block_download_initiate(node, d, now);
            return;
        }
        if (s->state == CO_SDO_DOWNLOAD_BLOCK_END) {
            block_download_end(node, d);
            return;
        }
        break;
    default: /* ccs 7 does not exist */
        break;
    }
    abort_transfer(node, CO_ABORT_COMMAND);
}

void co_sdo_server_rx(co_node *node, const co_frame *frame, co_time now)
{
    /* The deadline is CO_NEVER whenever the server is idle (finish, abort, init). */
    co_time old = node->sdo.deadline;
    server_rx(node, frame, now);
    co_node_reschedule(node, old, node->sdo.deadline);
    if (node->pdo.pending) {
        (void)co_pdo_process(node, now); /* TPDOs mapping a value the SDO wrote go out now */
    }
}

co_time co_sdo_server_process(co_node *node, co_time now)
{
    co_sdo_server *s = &node->sdo;
    if (s->state == CO_SDO_IDLE) {
        return CO_NEVER;
    }
    if (now >= s->deadline) {
        abort_transfer(node, CO_ABORT_TIMEOUT);
        return CO_NEVER;
    }
    if (s->state == CO_SDO_UPLOAD_BLOCK && s->sequence < s->block_segments) {
        block_upload_send(node, now);
        if (s->sequence < s->block_segments) {
            co_time retry = co_time_after(now, CO_SDO_TX_RETRY_US);
            return retry < s->deadline ? retry : s->deadline;
        }
    }
    return s->deadline;
}

void co_sdo_server_abort(co_node *node, uint32_t code)
{
    if (node->sdo.state != CO_SDO_IDLE) {
        abort_transfer(node, code);
        co_node_recheck(node);
    }
}
