/* SDO server (CiA 301 §7.2.4): expedited, segmented and block transfers, both directions.
 *
 * What a client sees:
 * - With CO_NODE_SDO_HIDDEN_RANGE (include/canopen/node.h), every initiate on an index of
 *   co_node_config.sdo_hidden_first..sdo_hidden_last aborts 0x06020000 before any other check.
 * - Every request frame must be 8 bytes (CiA 301 SDO frames always are). A shorter frame, or an
 *   RTR frame, is dropped without an answer and counted in node->stats.rx_malformed; a transfer
 *   in progress is left as it was (its timeout still runs).
 * - Downloads into values of the block (everything but DOMAIN) are collected whole and written
 *   once complete, through co_od_write_ref(..., CO_ORIGIN_SDO): an aborted or failing transfer
 *   leaves the value untouched. Access (0x06010002), the object (0x06020000, 0x06090011) and an
 *   announced size (0x06070012 / 0x06070013, 0x05040005 beyond CO_SDO_BUF_SIZE) are checked at
 *   the initiate, before any data moves. Data that does not match the size announced in the
 *   initiate aborts with 0x06070010. Without an announced size, data beyond CO_SDO_BUF_SIZE
 *   aborts with 0x05040005 as it comes, a value longer than its object with 0x06070012 at the
 *   write (the last segment or the block end).
 * - DOMAIN objects stream through their hook's domain_read / domain_write a piece of at most
 *   CO_SDO_BUF_SIZE bytes at a time, so their size is not limited by the buffer. domain_write
 *   gets last = true only when the whole transfer is good (size and CRC checked), never on an
 *   aborted one. A DOMAIN without domain_write aborts a download with 0x06010000, one without
 *   domain_read an upload with 0x08000024 (as co_od_write_ref / co_od_read_ref do).
 * - Block transfers: CRC as the client asks (the server always supports it); the server offers
 *   min(127, CO_SDO_BUF_SIZE / 7) segments per sub-block on download; a sub-block with a lost or
 *   repeated segment is acknowledged with the last in-order sequence number so the client repeats
 *   the rest; a block upload whose object is at most the client's protocol switch threshold is
 *   answered as a normal (expedited or segmented) upload.
 * - A new initiate request during a transfer abandons the old one without an abort frame and
 *   starts the new one (see sdo_server.c for why); an abort frame from the client ends the
 *   transfer silently; a request that does not fit the state aborts with 0x05040001.
 * - No frame of the client for node->sdo.timeout_us during a transfer aborts it with 0x05040000.
 *   A block upload's timeout runs from the last segment sent: while segments of a sub-block wait
 *   for room in the transmit queue the client owes no answer, so the transfer does not time out
 *   (co_sdo_server_process retries them every CO_SDO_TX_RETRY_US).
 * - Abort frames carry the multiplexer (index, sub-index) of the transfer they end; an unexpected
 *   segment while idle carries that of the last transfer. Every abort sent is counted in
 *   node->stats.sdo_aborts. */
#ifndef CANOPEN_SDO_SERVER_H
#define CANOPEN_SDO_SERVER_H

#include <stdbool.h>
#include <stdint.h>

#include "canopen/config.h"
#include "canopen/frame.h"
#include "canopen/od.h"
#include "canopen/time_base.h"

#ifdef __cplusplus
extern "C" {
#endif

struct co_node;

/* While a block upload's sub-block is held back because the transmit queue is full,
 * co_sdo_server_process asks to be called again after this many microseconds. */
#ifndef CO_SDO_TX_RETRY_US
#define CO_SDO_TX_RETRY_US 1000u
#endif

typedef enum co_sdo_state {
    CO_SDO_IDLE = 0,
    CO_SDO_DOWNLOAD_SEGMENTED,     /* waiting for the next download segment */
    CO_SDO_UPLOAD_SEGMENTED,       /* waiting for the next upload segment request */
    CO_SDO_DOWNLOAD_BLOCK,         /* receiving the segments of sub-blocks */
    CO_SDO_DOWNLOAD_BLOCK_END,     /* last segment received: waiting for the end request */
    CO_SDO_UPLOAD_BLOCK_INITIATED, /* initiate answered: waiting for the start request */
    CO_SDO_UPLOAD_BLOCK,           /* sending a sub-block / waiting for its acknowledgement */
    CO_SDO_UPLOAD_BLOCK_END        /* end sent: waiting for the client's end response */
} co_sdo_state;

/* One SDO server channel: all the state of the transfer in progress. */
typedef struct co_sdo_server {
    co_sdo_state state;
    uint8_t toggle;             /* segmented: toggle bit t expected next, in its place (bit 4 of
                                 * the command byte) */
    uint8_t sequence;           /* block download: last in-order sequence number of this
                                 * sub-block; block upload: segments of it sent so far */
    uint8_t segment_held;       /* block download: data bytes of segment[] that the next in-order
                                 * segment adds (0 before the first, then 7) */
    uint8_t block_size;         /* block: segments per sub-block */
    uint8_t block_segments;     /* block upload: segments in the current sub-block */
    bool crc_enabled;           /* block: client and server both use the CRC */
    bool size_indicated;        /* download: the client announced the size */
    co_od_ref ref;              /* object being transferred */
    const co_od_hook *hook;     /* DOMAIN transfers: the hook streaming it; NULL for values */
    uint32_t offset;            /* DOMAIN: download: bytes handed to domain_write; upload: object
                                 * offset of buf[0] */
    uint32_t buf_len;           /* bytes held in buf */
    uint32_t buf_pos;           /* upload: next byte of buf to send / first unacknowledged */
    uint16_t crc;               /* block: CRC of the data so far */
    uint32_t mux;               /* multiplexer of the transfer in bytes 1-3 of its frames' first
                                 * word: index << 8 | subindex << 24 (for responses and aborts) */
    uint32_t size;              /* download: announced size (0 if none); upload: bytes from buf[0]
                                 * to the end of the object (its size until a DOMAIN's buffer
                                 * moves on) */
    uint16_t hidden_first;      /* from co_node_config.sdo_hidden_first/last: indexes SDO does */
    uint16_t hidden_last;       /* not show (CO_NODE_SDO_HIDDEN_RANGE) */
    uint32_t timeout_us;        /* from co_node_config.sdo_timeout_us; co_sdo_server_init
                                 * (every reset) replaces 0 by CO_SDO_TIMEOUT_US */
    co_time deadline;           /* abort with CO_ABORT_TIMEOUT at this time (CO_NEVER: none,
                                 * always so while idle) */
    uint8_t segment[8];         /* block download: the latest good segment frame (its data in
                                 * bytes 1-7), kept back until the next one or the end request
                                 * says how much of it is data */
    uint8_t buf[CO_SDO_BUF_SIZE];
} co_sdo_server;

/* Aborts a transfer in progress with code (an abort frame is sent) and returns to idle. Does
 * nothing when idle. */
void co_sdo_server_abort(struct co_node *node, uint32_t code);

/* CRC-16-CCITT (polynomial 0x1021, no reflection, no final XOR) of len bytes, continuing from
 * crc; CiA 301 block transfers start from 0. */
uint16_t co_sdo_crc16(uint16_t crc, const uint8_t *data, uint32_t len);

#ifdef __cplusplus
}
#endif

#endif
