/* EtherCAT frames for the tests and benches: an Ethernet header with EtherType 0x88A4 and the
 * EtherCAT header (length, type 1), then datagrams (ETG.1000.4: command, index, 32-bit address,
 * length with the "more follows" bit 15, interrupt, data, working counter). Header only: the
 * benches include it without the Unity-based test support. */
#ifndef ECAT_FRAME_H
#define ECAT_FRAME_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

/* Datagram commands (ETG.1000.4 table 13). */
enum { NOP, APRD, APWR, APRW, FPRD, FPWR, FPRW, BRD, BWR, BRW, LRD, LWR, LRW, ARMW, FRMW };

#define ECAT_FRAME_MIN 60u /* shortest Ethernet frame without its FCS: padding after the datagrams */

typedef struct ecat_frame {
    uint8_t b[1600];
    size_t len;  /* bytes up to the end of the last datagram */
    size_t last; /* offset of the last datagram, 0 = none */
} ecat_frame;

/* Starts f with the headers and no datagram; the bytes after them are left as they are. */
static inline void ecat_frame_start(ecat_frame *f)
{
    memset(f->b, 0xFF, 6);     /* broadcast destination, as masters send */
    memset(f->b + 6, 0x01, 6); /* a source the ESC will mark (bit 1 of its first byte) */
    f->b[12] = 0x88;
    f->b[13] = 0xA4;
    f->b[14] = 0;
    f->b[15] = 0x10; /* type 1: EtherCAT commands */
    f->len = 16;
    f->last = 0;
}

/* Appends a datagram with the 32-bit address field addr (ADP | ADO << 16, or a logical
 * address); data NULL gives zeros. Returns the datagram's offset. */
static inline size_t ecat_frame_add32(ecat_frame *f, uint8_t cmd, uint32_t addr, const void *data,
                                      uint16_t len)
{
    size_t at = f->len;
    uint8_t *d = &f->b[at];
    if (f->last != 0) {
        f->b[f->last + 7] |= 0x80u; /* more datagrams follow */
    }
    d[0] = cmd;
    d[1] = 0x42; /* index */
    d[2] = (uint8_t)addr;
    d[3] = (uint8_t)(addr >> 8);
    d[4] = (uint8_t)(addr >> 16);
    d[5] = (uint8_t)(addr >> 24);
    d[6] = (uint8_t)len;
    d[7] = (uint8_t)(len >> 8);
    d[8] = 0;
    d[9] = 0;
    if (data != NULL) {
        memcpy(d + 10, data, len);
    } else {
        memset(d + 10, 0, len);
    }
    d[10 + len] = 0;
    d[11 + len] = 0;
    f->len += 12u + len;
    f->last = at;
    uint16_t l = (uint16_t)(f->len - 16u);
    f->b[14] = (uint8_t)l;
    f->b[15] = (uint8_t)(0x10u | (l >> 8));
    return at;
}

/* Appends a datagram addressed by ADP (position, station address) and ADO (register). */
static inline size_t ecat_frame_add(ecat_frame *f, uint8_t cmd, uint16_t adp, uint16_t ado,
                                    const void *data, uint16_t len)
{
    return ecat_frame_add32(f, cmd, (uint32_t)adp | ((uint32_t)ado << 16), data, len);
}

/* The length on the wire: the datagrams, padded to the Ethernet minimum. */
static inline size_t ecat_frame_wire_len(const ecat_frame *f)
{
    return f->len < ECAT_FRAME_MIN ? ECAT_FRAME_MIN : f->len;
}

/* The data length of the datagram at offset dg. */
static inline uint16_t ecat_frame_dlen(const ecat_frame *f, size_t dg)
{
    return (uint16_t)((f->b[dg + 6] | (f->b[dg + 7] << 8)) & 0x7FF);
}

/* The working counter of the datagram at offset dg. */
static inline uint16_t ecat_frame_wkc(const ecat_frame *f, size_t dg)
{
    size_t at = dg + 10 + ecat_frame_dlen(f, dg);
    return (uint16_t)(f->b[at] | (f->b[at + 1] << 8));
}

/* The data of the datagram at offset dg. */
static inline uint8_t *ecat_frame_data(ecat_frame *f, size_t dg)
{
    return &f->b[dg + 10];
}

#endif
