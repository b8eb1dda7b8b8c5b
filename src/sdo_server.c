/* SDO server (CiA 301 §7.2.4): one channel, expedited, segmented and block transfers.
 *
 * A request is handled by the function of its phase (CiA 301 §7.2.4.3): the initiates start a
 * transfer in any state, every other request continues the transfer of one state; dispatch()
 * says which. The answers and aborts go out on node->sdo_tx_cob.
 *
 * A new initiate request during a transfer starts the new transfer and drops the old one without
 * an abort frame. A client only sends an initiate when it considers the old transfer finished
 * (it timed out, or it was restarted and lost its state); an abort frame sent then would reach it
 * as the answer to its new request and fail that one too. CiA 301 leaves this case open. */
#include "canopen/sdo_server.h"

#include <stddef.h>
#include <string.h>

#include "canopen/node.h"
#include "dispatch.h"
#include "services.h"

#if CO_SDO_BUF_SIZE < 7
#error "CO_SDO_BUF_SIZE must hold at least one segment (7 bytes)"
#endif
#if CO_SDO_TIMEOUT_US > CO_TIME_SPAN_MAX || CO_SDO_TX_RETRY_US > CO_TIME_SPAN_MAX
#error "the SDO timeout and retry must fit a deadline (CO_TIME_SPAN_MAX)"
#endif

/* --- the command byte (CiA 301 §7.2.4.3) ----------------------------------------------------------
 *
 * Byte 0 of every SDO frame, bits 7..0 (x: reserved, 0):
 *   download / upload initiate      ccs|scs:3  x  n:2  e  s    n: bytes of 4-7 without data
 *   download / upload segment       ccs|scs:3  t  n:3  c       n: bytes of 1-7 without data
 *   abort (either side)             cs = 4:3   x:5
 *   block download initiate         ccs = 6:3  x:2  cc  s  cs = 0
 *   block download end              ccs = 6:3  n:3  x  cs = 1  n: of the last segment
 *   block download responses        scs = 5:3  x:2  sc  ss:2   ss: 0 initiate, 2 ack, 1 end
 *   block upload requests           ccs = 5:3  x:2  cc  cs:2   cs: 0 initiate, 3 start, 2 ack,
 *                                                                  1 end
 *   block upload initiate response  scs = 6:3  x:2  sc  s  ss = 0
 *   block upload end                scs = 6:3  n:3  x  ss = 1  n: of the last segment
 *   block segment                   c  seqno:7 */

/* Client command specifier ccs (bits 7-5 of a request). */
enum {
    SDO_CCS_DOWNLOAD_SEGMENT = 0,
    SDO_CCS_DOWNLOAD_INITIATE = 1,
    SDO_CCS_UPLOAD_INITIATE = 2,
    SDO_CCS_UPLOAD_SEGMENT = 3,
    SDO_CCS_ABORT = 4,
    SDO_CCS_BLOCK_UPLOAD = 5,
    SDO_CCS_BLOCK_DOWNLOAD = 6
};

/* Server command specifier scs, in its place in byte 0 of a response. */
#define SDO_SCS_UPLOAD_SEGMENT 0x00u    /* scs 0 */
#define SDO_SCS_DOWNLOAD_SEGMENT 0x20u  /* scs 1 */
#define SDO_SCS_UPLOAD_INITIATE 0x40u   /* scs 2 */
#define SDO_SCS_DOWNLOAD_INITIATE 0x60u /* scs 3 */
#define SDO_CS_ABORT 0x80u              /* cs 4, either side */
#define SDO_SCS_BLOCK_DOWNLOAD 0xA0u    /* scs 5 */
#define SDO_SCS_BLOCK_UPLOAD 0xC0u      /* scs 6 */

/* Block download: the client's subcommand cs, the server's ss (in place). */
enum { SDO_CS_BLOCK_DOWNLOAD_INITIATE = 0, SDO_CS_BLOCK_DOWNLOAD_END = 1 };
#define SDO_SS_BLOCK_DOWNLOAD_INITIATE 0x00u
#define SDO_SS_BLOCK_DOWNLOAD_END 0x01u
#define SDO_SS_BLOCK_DOWNLOAD_ACK 0x02u

/* Block upload: the client's subcommand cs, the server's ss (in place). */
enum {
    SDO_CS_BLOCK_UPLOAD_INITIATE = 0,
    SDO_CS_BLOCK_UPLOAD_END = 1,
    SDO_CS_BLOCK_UPLOAD_ACK = 2,
    SDO_CS_BLOCK_UPLOAD_START = 3
};
#define SDO_SS_BLOCK_UPLOAD_INITIATE 0x00u
#define SDO_SS_BLOCK_UPLOAD_END 0x01u

/* The one-bit fields, in place. */
#define SDO_SIZE_INDICATED 0x01u       /* s (initiate): the size, or n, is given */
#define SDO_EXPEDITED 0x02u            /* e (initiate): the data is in bytes 4-7 */
#define SDO_NO_MORE_SEGMENTS 0x01u     /* c (segment): this is the last one */
#define SDO_TOGGLE 0x10u               /* t (segment): alternates from 0 */
#define SDO_BLOCK_SIZE_INDICATED 0x02u /* s (block initiate): the size is in bytes 4-7 */
#define SDO_BLOCK_CRC 0x04u            /* cc / sc (block initiate): that side uses the CRC */
#define SDO_BLOCK_LAST_SEGMENT 0x80u   /* c (block segment): the last of the transfer */

/* n (bytes without data), in place. */
#define SDO_INITIATE_N(n) ((uint32_t)(n) << 2)
#define SDO_SEGMENT_N(n) ((uint32_t)(n) << 1)
#define SDO_BLOCK_END_N(n) ((uint32_t)(n) << 2)

/* The fields of a request's command byte. */
static uint32_t sdo_ccs(uint32_t cmd)
{
    return cmd >> 5;
}

static bool sdo_expedited(uint32_t cmd)
{
    return (cmd & SDO_EXPEDITED) != 0u;
}

static bool sdo_size_indicated(uint32_t cmd)
{
    return (cmd & SDO_SIZE_INDICATED) != 0u;
}

static uint32_t sdo_initiate_n(uint32_t cmd)
{
    return (cmd >> 2) & 0x03u;
}

static uint32_t sdo_toggle(uint32_t cmd) /* in place */
{
    return cmd & SDO_TOGGLE;
}

static uint32_t sdo_segment_n(uint32_t cmd)
{
    return (cmd >> 1) & 0x07u;
}

static bool sdo_no_more_segments(uint32_t cmd)
{
    return (cmd & SDO_NO_MORE_SEGMENTS) != 0u;
}

static bool sdo_block_crc(uint32_t cmd)
{
    return (cmd & SDO_BLOCK_CRC) != 0u;
}

static bool sdo_block_size_indicated(uint32_t cmd)
{
    return (cmd & SDO_BLOCK_SIZE_INDICATED) != 0u;
}

static uint32_t sdo_block_download_cs(uint32_t cmd)
{
    return cmd & 0x01u;
}

static uint32_t sdo_block_upload_cs(uint32_t cmd)
{
    return cmd & 0x03u;
}

static uint32_t sdo_block_end_n(uint32_t cmd)
{
    return (cmd >> 2) & 0x07u;
}

static uint32_t sdo_seqno(uint32_t cmd)
{
    return cmd & 0x7Fu;
}

static bool sdo_block_last_segment(uint32_t cmd)
{
    return (cmd & SDO_BLOCK_LAST_SEGMENT) != 0u;
}

/* The multiplexer of an initiate as it stands in bytes 1-3 of its frame's first word:
 * index << 8 | subindex << 24. The responses and aborts of the transfer repeat it. */
static uint32_t sdo_mux(const uint8_t *d)
{
    return co_get_le32(d) & 0xFFFFFF00u;
}

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

/* The node a server belongs to (it is the node's member sdo). */
static co_node *node_of(co_sdo_server *s)
{
    return (co_node *)(void *)((char *)s - offsetof(co_node, sdo));
}

/* --- frames ----------------------------------------------------------------------------------- */

/* Sends a frame: bytes 0-3 from lo, 4-7 from hi, little-endian (the command byte, then the
 * multiplexer or data; CiA 301 reserved bytes are 0), then over bytes 1-7 the len bytes of the
 * buffer from at (a segment's data; len 0: none). */
static void send_frame(co_sdo_server *s, uint32_t lo, uint32_t hi, uint32_t at,
                                        uint32_t len)
{
    co_node *node = node_of(s);
    co_frame f;
    f.id = node->sdo_tx_cob;
    f.dlc = 8;
    f.flags = 0u;
    co_put_le32(&f.data[0], lo);
    co_put_le32(&f.data[4], hi);
    memcpy(&f.data[1], &s->buf[at], len);
    (void)co_node_send(node, &f); /* a dropped frame is counted by the node; the client times out */
}

/* Sends a response without segment data. */
static void send_reply(co_sdo_server *s, uint32_t lo, uint32_t hi)
{
    send_frame(s, lo, hi, 0u, 0u);
}

/* Sends a segment: the command byte, then len bytes of the buffer from at (the rest 0). */
static void send_segment(co_sdo_server *s, uint32_t cmd, uint32_t at, uint32_t len)
{
    send_frame(s, cmd, 0u, at, len);
}

/* Ends the transfer without a frame. Its timeout goes with it where the request ends (request):
 * the functions of the phases only set the state. */
static void finish(co_sdo_server *s)
{
    s->state = CO_SDO_IDLE;
}

/* Sends an abort frame for the current multiplexer and ends the transfer and its timeout. */
static void abort_transfer(co_sdo_server *s, co_abort code)
{
    co_node *node = node_of(s);
    finish(s);
    s->deadline = CO_NEVER;
    CO_COUNT(node->stats.sdo_aborts);
    send_reply(s, SDO_CS_ABORT | s->mux, code);
}

/* The client's abort: the transfer ends, nothing is answered (even when idle). */
static void abort_received(co_sdo_server *s)
{
    finish(s);
}

/* Restarts the client timeout: the transfer lives timeout_us more from now (never 0 here:
 * co_sdo_server_init, which every reset runs, replaces 0 by CO_SDO_TIMEOUT_US). The node hears of
 * the deadline; one that moves later or goes (finish) is found by the pass it was due for, which
 * recomputes (src/schedule.h: node->next may be earlier than the deadlines). */
static CO_ONE_COPY void arm_timeout(co_sdo_server *s, co_time now)
{
    s->deadline = co_time_after(now, s->timeout_us);
    co_node_wake(node_of(s), s->deadline);
}

/* --- CRC -------------------------------------------------------------------------------------- */

/* One step of the CRC, four bits at a time: the CRC after the nibble n. The product of a nibble m
 * and the polynomial 0x1021 without carries is m ^ m << 5 ^ m << 12 (it has at most 16 bits: no
 * reduction). */
static uint16_t crc16_step(uint16_t crc, uint32_t n)
{
    uint32_t m = (uint32_t)(crc >> 12) ^ n;
    return (uint16_t)((uint32_t)crc << 4 ^ m ^ m << 5 ^ m << 12);
}

uint16_t co_sdo_crc16(uint16_t crc, const uint8_t *data, uint32_t len)
{
    for (uint32_t i = 0; i < len; i++) {
        crc = crc16_step(crc, data[i] >> 4u);
        crc = crc16_step(crc, data[i] & 0x0Fu);
    }
    return crc;
}

/* --- the transfer's data ---------------------------------------------------------------------- */

/* Sets up a transfer that may go on over several requests: from the start, no DOMAIN hook, no
 * CRC. */
static CO_ONE_COPY void transfer_reset(co_sdo_server *s)
{
    s->hook = NULL;
    s->offset = 0;
    s->buf_len = 0;
    s->buf_pos = 0;
    s->toggle = 0;
    s->sequence = 0;
    s->segment_held = 0;
    s->crc = 0;
    s->crc_enabled = false;
}

/* Sets up a segmented or block download (transfer_reset) and checks it against the object before
 * any data moves: access, a DOMAIN's hook, an announced size. */
static co_abort download_start(co_sdo_server *s, bool size_indicated, uint32_t size)
{
    co_node *node = node_of(s);
    const co_od_sub *sub = s->ref.sub;
    transfer_reset(s);
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
    s->size = size_indicated ? size : 0u;
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
        /* a value longer than its object is refused by the write (download_finish) */
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

/* All data is in: checks the announced size, writes the value (or hands the DOMAIN's last piece
 * to its hook) and, when that is accepted, ends the transfer. */
static co_abort download_finish(co_sdo_server *s)
{
    co_node *node = node_of(s);
    co_abort code;
    if (s->size_indicated && s->offset + s->buf_len != s->size) {
        return CO_ABORT_TYPE_LENGTH;
    }
    if (s->hook != NULL) {
        code = domain_flush(s, true);
    } else {
        code = co_od_write_ref(node, s->ref, s->buf, s->buf_len, CO_ORIGIN_SDO);
    }
    if (code == CO_ABORT_NONE) {
        finish(s);
    }
    return code;
}

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

/* Sets up an upload (transfer_reset) and reads the object (co_od_read_sized): a value whole into
 * the buffer, a DOMAIN's size and first piece from its hook (a whole buffer asked for at offset
 * 0), then the rest of a buffer. */
static co_abort upload_start(co_sdo_server *s)
{
    co_node *node = node_of(s);
    transfer_reset(s);
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
static co_abort upload_next(co_sdo_server *s, uint32_t max, uint32_t *span)
{
    uint32_t n = min_u32(s->size - s->buf_pos, max);
    *span = n;
    if (s->buf_len - s->buf_pos < n) { /* only a DOMAIN's buffer holds less than the object */
        return upload_fill(s);
    }
    return CO_ABORT_NONE;
}

/* A block size the client may ask for: 1..127, and for a DOMAIN, a sub-block the buffer holds
 * (it must stay there until acknowledged, to be repeated). */
static bool block_size_valid(const co_sdo_server *s, uint32_t block_size)
{
    uint32_t max = s->hook == NULL ? BLOCK_SIZE_MAX : BLOCK_SIZE_OFFER;
    return block_size >= 1u && block_size <= max;
}

/* --- initiates -------------------------------------------------------------------------------- */

/* What every initiate does first: the transfer in progress is dropped (see the top of this file),
 * the multiplexer taken and the object looked up. */
static co_abort initiate(co_sdo_server *s, const uint8_t *d)
{
    finish(s);
    s->mux = sdo_mux(d);
    co_node *node = node_of(s);
    uint32_t index = (s->mux >> 8) & 0xFFFFu;
    if (CO_NODE_OPTION(node, CO_NODE_SDO_HIDDEN_RANGE) && index >= s->hidden_first &&
        index <= s->hidden_last) {
        return CO_ABORT_NO_OBJECT; /* an internal object: not there for SDO, whatever is asked */
    }
    return co_node_locate(node, s->mux >> 8, s->mux >> 24, &s->ref);
}

/* Download initiate: an expedited one writes its data (bytes 4-7) at once; a segmented one
 * announces its size there, if any, and waits for the segments. */
static co_abort download_initiate(co_sdo_server *s, const uint8_t *d)
{
    uint32_t cmd = d[0];
    co_abort code = initiate(s, d);
    if (code != CO_ABORT_NONE) {
        return code;
    }
    if (sdo_expedited(cmd)) {
        uint32_t len = 4u;
        if (sdo_size_indicated(cmd)) {
            len -= sdo_initiate_n(cmd);
        } else { /* the value's own size when it fits, else all four bytes */
            uint32_t size = co_od_sub_size(s->ref.sub);
            if (size >= 1u && size <= 3u) {
                len = size;
            }
        }
        code = co_od_write_ref(node_of(s), s->ref, &d[4], len, CO_ORIGIN_SDO);
    } else {
        code = download_start(s, sdo_size_indicated(cmd), co_get_le32(&d[4]));
        s->state = CO_SDO_DOWNLOAD_SEGMENTED; /* (an abort ends the transfer again) */
    }
    if (code != CO_ABORT_NONE) {
        return code;
    }
    send_reply(s, SDO_SCS_DOWNLOAD_INITIATE | s->mux, 0u);
    return CO_ABORT_NONE;
}

/* CO_NODE_SDO_UPLOAD_COMM_AS_32: a numeric entry of 0x1000-0x1FFF is answered as 4 bytes. */
static bool upload_as_32(co_sdo_server *s)
{
    uint32_t index = (s->mux >> 8) & 0xFFFFu;
    uint8_t type = s->ref.sub->type;
    return CO_NODE_OPTION(node_of(s), CO_NODE_SDO_UPLOAD_COMM_AS_32) && index >= 0x1000u &&
           index <= 0x1FFFu && type != CO_VISIBLE_STRING && type != CO_OCTET_STRING &&
           type != CO_UNICODE_STRING && type != CO_DOMAIN;
}

/* The answer to an upload initiate (also to a block upload initiate that switches to a normal
 * upload): expedited for 1 to 4 bytes, the bytes past the value 0 (a DOMAIN's hook may have put
 * more there); else segmented with the size indicated, also for an empty value (an expedited
 * frame cannot say 0 bytes). */
static co_abort upload_initiate_reply(co_sdo_server *s)
{
    uint32_t cmd = SDO_SCS_UPLOAD_INITIATE | SDO_SIZE_INDICATED;
    uint32_t value = s->size;
    if (value >= 1u && value <= 4u) {
        uint32_t unused = 4u - value;
        value = co_get_le32(s->buf) << (unused * 8u) >> (unused * 8u);
        if (upload_as_32(s)) {
            unused = 0u; /* four bytes indicated, the value zero-extended */
        }
        cmd |= SDO_EXPEDITED | SDO_INITIATE_N(unused);
    } else {
        s->state = CO_SDO_UPLOAD_SEGMENTED;
    }
    send_reply(s, cmd | s->mux, value);
    return CO_ABORT_NONE;
}

/* Upload initiate: the object is read (a DOMAIN's first piece) and its size answered. */
static co_abort upload_initiate(co_sdo_server *s, const uint8_t *d)
{
    co_abort code = initiate(s, d);
    if (code != CO_ABORT_NONE) {
        return code;
    }
    code = upload_start(s);
    if (code != CO_ABORT_NONE) {
        return code;
    }
    return upload_initiate_reply(s);
}

/* Block download initiate: checked as a segmented one; the server offers its block size and
 * says it can check a CRC. */
static co_abort block_download_initiate(co_sdo_server *s, const uint8_t *d)
{
    uint32_t cmd = d[0];
    co_abort code = initiate(s, d);
    if (code != CO_ABORT_NONE) {
        return code;
    }
    code = download_start(s, sdo_block_size_indicated(cmd), co_get_le32(&d[4]));
    if (code != CO_ABORT_NONE) {
        return code;
    }
    s->crc_enabled = sdo_block_crc(cmd);
    s->block_size = (uint8_t)BLOCK_SIZE_OFFER;
    s->state = CO_SDO_DOWNLOAD_BLOCK;
    send_reply(s, SDO_SCS_BLOCK_DOWNLOAD | SDO_BLOCK_CRC | SDO_SS_BLOCK_DOWNLOAD_INITIATE | s->mux,
               BLOCK_SIZE_OFFER);
    return CO_ABORT_NONE;
}

/* Block upload initiate: byte 4 is the client's block size, byte 5 its protocol switch
 * threshold. An object of at most that many bytes (0: the client forbids the switch) is answered
 * as a normal upload. */
static co_abort block_upload_initiate(co_sdo_server *s, const uint8_t *d)
{
    uint32_t block_size = d[4];
    uint32_t switch_threshold = d[5];
    co_abort code = initiate(s, d);
    if (code != CO_ABORT_NONE) {
        return code;
    }
    code = upload_start(s);
    if (code != CO_ABORT_NONE) {
        return code;
    }
    s->crc_enabled = sdo_block_crc(d[0]);
    if (!block_size_valid(s, block_size)) {
        return CO_ABORT_BLOCK_SIZE;
    }
    if (switch_threshold != 0u && s->size <= switch_threshold) {
        return upload_initiate_reply(s);
    }
    s->block_size = (uint8_t)block_size;
    s->state = CO_SDO_UPLOAD_BLOCK_INITIATED;
    send_reply(s,
               SDO_SCS_BLOCK_UPLOAD | SDO_BLOCK_CRC | SDO_BLOCK_SIZE_INDICATED |
                   SDO_SS_BLOCK_UPLOAD_INITIATE | s->mux,
               s->size);
    return CO_ABORT_NONE;
}

/* --- segmented transfers ---------------------------------------------------------------------- */

/* A segmented transfer's toggle bit alternates from 0 (an initiate clears it): checks a
 * request's and expects the other one next. */
static bool toggle_ok(co_sdo_server *s, uint32_t cmd)
{
    if (sdo_toggle(cmd) != s->toggle) {
        return false;
    }
    s->toggle = (uint8_t)(sdo_toggle(cmd) ^ SDO_TOGGLE);
    return true;
}

/* Download segment: 7 - n bytes of data; the last one (c) writes the value. */
static co_abort download_segment(co_sdo_server *s, const uint8_t *d)
{
    uint32_t cmd = d[0];
    if (!toggle_ok(s, cmd)) {
        return CO_ABORT_TOGGLE;
    }
    co_abort code = download_append(s, &d[1], SEGMENT_DATA - sdo_segment_n(cmd));
    if (code == CO_ABORT_NONE && sdo_no_more_segments(cmd)) {
        code = download_finish(s);
    }
    if (code != CO_ABORT_NONE) {
        return code;
    }
    send_reply(s, SDO_SCS_DOWNLOAD_SEGMENT | sdo_toggle(cmd), 0u);
    return CO_ABORT_NONE;
}

/* Upload segment request: answered with the next (up to) 7 bytes, the last with c. */
static co_abort upload_segment(co_sdo_server *s, const uint8_t *d)
{
    uint32_t cmd = d[0];
    if (!toggle_ok(s, cmd)) {
        return CO_ABORT_TOGGLE;
    }
    uint32_t n;
    co_abort code = upload_next(s, SEGMENT_DATA, &n);
    if (code != CO_ABORT_NONE) {
        return code;
    }
    uint32_t at = s->buf_pos;
    bool last = s->size - at == n; /* nothing after this segment */
    s->buf_pos = at + n;
    uint32_t reply = SDO_SCS_UPLOAD_SEGMENT | sdo_toggle(cmd) | SDO_SEGMENT_N(SEGMENT_DATA - n);
    if (last) {
        finish(s);
        reply |= SDO_NO_MORE_SEGMENTS;
    }
    send_segment(s, reply, at, n);
    return CO_ABORT_NONE;
}

/* --- block download --------------------------------------------------------------------------- */

/* Acknowledges the sub-block up to the last in-order segment; the client repeats the rest. */
static void block_download_ack(co_sdo_server *s)
{
    uint32_t sequence = s->sequence;
    s->sequence = 0;
    send_reply(s,
               SDO_SCS_BLOCK_DOWNLOAD | SDO_SS_BLOCK_DOWNLOAD_ACK | sequence << 8 |
                   (uint32_t)s->block_size << 16,
               0u);
}

/* A segment of a sub-block: byte 0 is c and the sequence number. Each in-order segment releases
 * the one held before it (which was then not the last: 7 bytes of data) and is held in turn,
 * until the next one or the end request says how much of it is data. */
static co_abort block_download_sub_block(co_sdo_server *s, const uint8_t *d)
{
    uint32_t cmd = d[0];
    uint32_t seqno = sdo_seqno(cmd);
    if (cmd == SDO_CS_ABORT) { /* sequence number 0 is never a segment: this is the client's abort */
        abort_received(s);
        return CO_ABORT_NONE;
    }
    if (seqno < 1u || seqno > s->block_size) {
        return CO_ABORT_SEQUENCE;
    }
    if (seqno == s->sequence + 1u) {
        co_abort code = download_append(s, &s->segment[1], s->segment_held);
        if (code != CO_ABORT_NONE) {
            return code;
        }
        memcpy(s->segment, d, 8u);
        s->segment_held = SEGMENT_DATA;
        s->sequence = (uint8_t)seqno;
        if (sdo_block_last_segment(cmd)) {
            s->state = CO_SDO_DOWNLOAD_BLOCK_END;
        }
    }
    /* A segment out of order (one before it was lost) is ignored until the sub-block ends. */
    if (sdo_block_last_segment(cmd) || seqno == s->block_size) {
        block_download_ack(s);
    }
    return CO_ABORT_NONE;
}

/* Block download end: n says how much of the held last segment is data; then the CRC (bytes
 * 1-2, when used), the size and the write. */
static co_abort block_download_end(co_sdo_server *s, const uint8_t *d)
{
    co_abort code = download_append(s, &s->segment[1], SEGMENT_DATA - sdo_block_end_n(d[0]));
    if (code != CO_ABORT_NONE) {
        return code;
    }
    if (s->crc_enabled && s->crc != co_get_le16(&d[1])) {
        return CO_ABORT_CRC;
    }
    code = download_finish(s);
    if (code != CO_ABORT_NONE) {
        return code;
    }
    send_reply(s, SDO_SCS_BLOCK_DOWNLOAD | SDO_SS_BLOCK_DOWNLOAD_END, 0u);
    return CO_ABORT_NONE;
}

/* --- block upload ----------------------------------------------------------------------------- */

/* Sends the segments of the current sub-block the transmit queue has room for; the rest go out
 * from co_sdo_server_process. The client owes no answer while segments of the sub-block are still
 * to be sent, so the timeout restarts at every call and runs from the last segment sent. Returns
 * true when segments are held back. */
static bool block_upload_send(co_sdo_server *s, co_time now)
{
    co_node *node = node_of(s);
    uint32_t end = s->size; /* end of the object, relative to buf */
    arm_timeout(s, now);
    while (s->sequence < s->block_segments) {
        if (node->txq.count >= CO_TX_QUEUE_LEN) {
            return true;
        }
        uint32_t at = s->buf_pos + (uint32_t)s->sequence * SEGMENT_DATA;
        uint32_t cmd = (uint32_t)s->sequence + 1u;
        if (end - at <= SEGMENT_DATA) {
            cmd |= SDO_BLOCK_LAST_SEGMENT;
        }
        s->sequence++;
        send_segment(s, cmd, at, min_u32(end - at, SEGMENT_DATA));
    }
    return false;
}

/* Starts a sub-block at the first unacknowledged byte (after the start request, and after an
 * acknowledgement that leaves data to send). */
static co_abort block_upload_sub_block(co_sdo_server *s, co_time now)
{
    uint32_t span;
    co_abort code = upload_next(s, (uint32_t)s->block_size * SEGMENT_DATA, &span);
    if (code != CO_ABORT_NONE) {
        return code;
    }
    /* An empty object still takes one segment (with no data). */
    s->block_segments = (uint8_t)(span == 0u ? 1u : (span + SEGMENT_DATA - 1u) / SEGMENT_DATA);
    s->sequence = 0;
    s->state = CO_SDO_UPLOAD_BLOCK;
    (void)block_upload_send(s, now);
    return CO_ABORT_NONE;
}

/* Block upload start: the client is ready for the first sub-block. */
static co_abort block_upload_start(co_sdo_server *s, co_time now)
{
    return block_upload_sub_block(s, now);
}

/* Block upload acknowledgement: byte 1 the segments received in order (the rest are sent again),
 * byte 2 the block size of the next sub-block. Once all is acknowledged, the end request with
 * the CRC. */
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
    /* n: the bytes of the last segment that were not data; the CRC stays 0 when it is not used. */
    uint32_t last_bytes = acked - (acked_segments - 1u) * SEGMENT_DATA;
    s->state = CO_SDO_UPLOAD_BLOCK_END;
    send_reply(s,
               SDO_SCS_BLOCK_UPLOAD | SDO_BLOCK_END_N(SEGMENT_DATA - last_bytes) |
                   SDO_SS_BLOCK_UPLOAD_END | (uint32_t)s->crc << 8,
               0u);
    return CO_ABORT_NONE;
}

/* Block upload end: the client's response to the end request closes the transfer. */
static void block_upload_end(co_sdo_server *s)
{
    finish(s);
}

/* --- dispatch --------------------------------------------------------------------------------- */

/* Hands a request to the function of its phase; returns the abort to answer it with, or
 * CO_ABORT_NONE. The initiates and the client's abort are taken in any state; every other request
 * continues the transfer of one state, and the server must be in it (else CO_ABORT_COMMAND). */
static co_abort dispatch(co_sdo_server *s, const uint8_t *d, co_time now)
{
    uint32_t cmd = d[0];
    co_sdo_state expected; /* the state the request continues */
    if (s->state == CO_SDO_DOWNLOAD_BLOCK) { /* byte 0 is c and a sequence number, not a ccs */
        return block_download_sub_block(s, d);
    }
    /* The expedited transfers are most of the traffic: their initiates are tested first. */
    if (sdo_ccs(cmd) == SDO_CCS_DOWNLOAD_INITIATE) {
        return download_initiate(s, d);
    }
    if (sdo_ccs(cmd) == SDO_CCS_UPLOAD_INITIATE) {
        return upload_initiate(s, d);
    }
    switch (sdo_ccs(cmd)) {
    case SDO_CCS_ABORT:
        abort_received(s);
        return CO_ABORT_NONE;
    case SDO_CCS_DOWNLOAD_SEGMENT:
        expected = CO_SDO_DOWNLOAD_SEGMENTED;
        break;
    case SDO_CCS_UPLOAD_SEGMENT:
        expected = CO_SDO_UPLOAD_SEGMENTED;
        break;
    case SDO_CCS_BLOCK_DOWNLOAD:
        if (sdo_block_download_cs(cmd) == SDO_CS_BLOCK_DOWNLOAD_INITIATE) {
            return block_download_initiate(s, d);
        }
        expected = CO_SDO_DOWNLOAD_BLOCK_END; /* the end request */
        break;
    case SDO_CCS_BLOCK_UPLOAD:
        switch (sdo_block_upload_cs(cmd)) {
        case SDO_CS_BLOCK_UPLOAD_INITIATE:
            return block_upload_initiate(s, d);
        case SDO_CS_BLOCK_UPLOAD_START:
            expected = CO_SDO_UPLOAD_BLOCK_INITIATED;
            break;
        case SDO_CS_BLOCK_UPLOAD_ACK:
            expected = CO_SDO_UPLOAD_BLOCK;
            break;
        default: /* SDO_CS_BLOCK_UPLOAD_END */
            expected = CO_SDO_UPLOAD_BLOCK_END;
            break;
        }
        break;
    default: /* ccs 7 does not exist */
        return CO_ABORT_COMMAND;
    }
    if (s->state != expected) {
        return CO_ABORT_COMMAND;
    }
    switch (expected) {
    case CO_SDO_DOWNLOAD_SEGMENTED:
        return download_segment(s, d);
    case CO_SDO_UPLOAD_SEGMENTED:
        return upload_segment(s, d);
    case CO_SDO_DOWNLOAD_BLOCK_END:
        return block_download_end(s, d);
    case CO_SDO_UPLOAD_BLOCK_INITIATED:
        return block_upload_start(s, now);
    case CO_SDO_UPLOAD_BLOCK:
        return block_upload_ack(s, d, now);
    default: /* CO_SDO_UPLOAD_BLOCK_END */
        block_upload_end(s);
        return CO_ABORT_NONE;
    }
}

/* Handles a request, answers it and restarts the timeout of the transfer it keeps going; the
 * TPDOs mapping a value the request wrote go out now. */
static CO_ONE_COPY void request(co_sdo_server *s, const uint8_t *d, co_time now)
{
    co_abort code = dispatch(s, d, now);
    if (code != CO_ABORT_NONE) {
        abort_transfer(s, code);
    }
    if (s->state == CO_SDO_IDLE) {
        s->deadline = CO_NEVER; /* the transfer ended (or none was under way) */
    } else if (s->state != CO_SDO_UPLOAD_BLOCK) {
        /* every request that keeps a transfer going restarts its timeout (a block upload's
         * runs from its last segment sent, block_upload_send) */
        arm_timeout(s, now);
    }
    co_node *node = node_of(s);
    if (node->pdo.pending) {
        (void)co_pdo_process(node, now);
    }
}

void co_sdo_server_init(co_node *node)
{
    co_sdo_server *s = &node->sdo;
    finish(s);
    s->deadline = CO_NEVER;
    s->mux = 0; /* what an abort carries until the next initiate (which sets up the rest) */
    if (s->timeout_us == 0u) {
        s->timeout_us = CO_SDO_TIMEOUT_US;
    }
    /* a deadline dropped, none set: node->next is at worst early (src/schedule.h) */
}

void co_sdo_server_rx(co_node *node, const co_frame *frame, co_time now)
{
    if (frame->dlc != 8u || (frame->flags & CO_FRAME_RTR) != 0u) {
        CO_COUNT(node->stats.rx_malformed); /* dropped: no answer, the transfer goes on */
        return;
    }
    request(&node->sdo, frame->data, now);
}

static CO_ONE_COPY co_time process(co_sdo_server *s, co_time now)
{
    if (s->state == CO_SDO_IDLE) {
        return CO_NEVER;
    }
    if (s->state == CO_SDO_UPLOAD_BLOCK && s->sequence < s->block_segments) {
        /* segments held back: the server, not the client, is late (block_upload_send) */
        if (block_upload_send(s, now)) {
            return co_time_after(now, CO_SDO_TX_RETRY_US);
        }
        return s->deadline;
    }
    if (now >= s->deadline) {
        abort_transfer(s, CO_ABORT_TIMEOUT);
        return CO_NEVER;
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
