/* The emulated ESC: frame processing (ETG.1000.4 §5 datagrams, working counter), memory access
 * through registers, SyncManagers and FMMUs, the SII EEPROM interface and the SM watchdog.
 * Facts cite the Beckhoff ESC datasheet, section I (technology) and section II (registers). */
#include "canopen/ecat/esc.h"

#include <string.h>

/* Who accesses the memory. */
enum { SIDE_ECAT, SIDE_PDI };

/* Access operations; mem_access returns the ACC_* bits of what happened. */
#define OP_READ 1u  /* memory -> frame */
#define OP_WRITE 2u /* frame -> memory */
#define OP_OR 4u    /* a read ORs the memory into the frame (broadcast reads) */
#define ACC_READ 1u
#define ACC_WRITE 2u
#define ACC_DENIED 4u

/* EtherCAT commands (ETG.1000.4 Table 12 / datasheet section I Table 6). */
enum {
    CMD_NOP, CMD_APRD, CMD_APWR, CMD_APRW, CMD_FPRD, CMD_FPWR, CMD_FPRW, CMD_BRD, CMD_BWR,
    CMD_BRW, CMD_LRD, CMD_LWR, CMD_LRW, CMD_ARMW, CMD_FRMW
};

#define ETH_HDR 14u
#define ECAT_HDR 2u
#define DG_HDR 10u
#define DG_WKC 2u

/* EEPROM control/status 0x0502 (section II). */
#define EEP_WRITE_EN 0x0001u
#define EEP_READ8 0x0040u
#define EEP_CMD_MASK 0x0700u
#define EEP_CMD_READ 0x0100u
#define EEP_CMD_WRITE 0x0200u
#define EEP_CMD_RELOAD 0x0400u
#define EEP_CSUM_ERR 0x0800u
#define EEP_LOAD_ERR 0x1000u
#define EEP_ACK_ERR 0x2000u
#define EEP_WE_ERR 0x4000u

static uint16_t rd16(const uint8_t *p)
{
    return (uint16_t)(p[0] | (p[1] << 8));
}

static uint32_t rd32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) |
           ((uint32_t)p[3] << 24);
}

static void wr16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}

static void wr64(uint8_t *p, uint64_t v)
{
    for (unsigned i = 0; i < 8u; i++) {
        p[i] = (uint8_t)(v >> (8u * i));
    }
}

static uint64_t rd64(const uint8_t *p)
{
    uint64_t v = 0;
    for (unsigned i = 8; i-- > 0;) {
        v = (v << 8) | p[i];
    }
    return v;
}

/* Does [a, a + n) meet [b, b + m)? */
static bool overlaps(uint32_t a, uint32_t n, uint32_t b, uint32_t m)
{
    return a < b + m && b < a + n;
}

/* Only the low 16 bits of the AL event request are used here (SM events for SM0..7). */
static void al_event_set(co_esc *esc, uint32_t bits)
{
    uint8_t *r = &esc->mem[CO_ESC_REG_AL_EVENT];
    wr16(r, (uint16_t)(rd16(r) | bits));
}

static void al_event_clear(co_esc *esc, uint32_t bits)
{
    uint8_t *r = &esc->mem[CO_ESC_REG_AL_EVENT];
    wr16(r, (uint16_t)(rd16(r) & ~bits));
}

static void ecat_event_set(co_esc *esc, uint16_t bits)
{
    uint8_t *r = &esc->mem[CO_ESC_REG_ECAT_EVENT];
    wr16(r, (uint16_t)(rd16(r) | bits));
}

static void ecat_event_clear(co_esc *esc, uint16_t bits)
{
    uint8_t *r = &esc->mem[CO_ESC_REG_ECAT_EVENT];
    wr16(r, (uint16_t)(rd16(r) & ~(uint32_t)bits));
}

/* ---- SM watchdog (section I §5 Watchdogs; section II 0x0400-0x0443) ---- */

/* Process-data watchdog time in ns: 0x0420 increments of (0x0400 + 2) x 40 ns; 0 = disabled. */
static uint64_t wd_timeout(const co_esc *esc)
{
    uint64_t ticks = rd16(&esc->mem[CO_ESC_REG_WD_SM]);
    return ticks * ((uint64_t)rd16(&esc->mem[CO_ESC_REG_WD_DIV]) + 2u) * 40u;
}

/* A completed master write to an SM with the watchdog trigger bit restarts the watchdog. */
static void wd_trigger(co_esc *esc)
{
    uint64_t t = wd_timeout(esc);
    esc->mem[CO_ESC_REG_WD_STATUS] |= 1u; /* active */
    esc->wd_deadline = t != 0 ? esc->now + t : CO_ESC_TIME_NEVER;
}

static void wd_run(co_esc *esc)
{
    if (esc->wd_deadline != CO_ESC_TIME_NEVER && esc->now >= esc->wd_deadline) {
        esc->wd_deadline = CO_ESC_TIME_NEVER;
        esc->mem[CO_ESC_REG_WD_STATUS] &= (uint8_t)~1u; /* expired */
        if (esc->mem[CO_ESC_REG_WD_COUNT] != 0xFFu) {   /* the counter stops at 0xFF */
            esc->mem[CO_ESC_REG_WD_COUNT]++;
        }
        al_event_set(esc, CO_ESC_AL_EVENT_WD_PD);
    }
}

/* ---- SyncManagers (section I §8) ---- */

static bool sm_mailbox(const co_esc_sm *sm)
{
    return (sm->ctrl & 0x03u) == CO_ESC_SM_CTRL_MAILBOX;
}

/* The side that writes the buffer: control bits 3:2 = 01 the master, 00 the PDI. */
static int sm_writer(const co_esc_sm *sm)
{
    return (sm->ctrl & 0x0Cu) == CO_ESC_SM_CTRL_MASTER_WRITES ? SIDE_ECAT : SIDE_PDI;
}

/* The enabled SMs in order of start address, for mem_access's lookup. */
static void sm_sort(co_esc *esc)
{
    unsigned k = 0;
    for (unsigned s = 0; s < esc->sm_count; s++) {
        if (esc->sm[s].on) {
            unsigned j = k++;
            while (j > 0 && esc->sm[esc->sm_order[j - 1]].start > esc->sm[s].start) {
                esc->sm_order[j] = esc->sm_order[j - 1];
                j--;
            }
            esc->sm_order[j] = (uint8_t)s;
        }
    }
    esc->sm_enabled = (uint8_t)k;
    for (unsigned j = 0; j < k; j++) { /* an enabled SM's buffer ends inside the image */
        const co_esc_sm *sm = &esc->sm[esc->sm_order[j]];
        esc->sm_lo[j] = sm->start;
        esc->sm_hi[j] = (uint16_t)(sm->start + sm->len);
    }
}

/* The SM whose buffer mem_access finds for addr (the first enabled one, in order of start
 * address, that ends above addr), CO_ESC_MAX_SM if addr is in plain RAM or a register. */
static unsigned sm_at(const co_esc *esc, uint32_t addr)
{
    for (unsigned k = 0; k < esc->sm_enabled; k++) {
        if (addr < esc->sm_lo[k]) {
            break;
        }
        if (addr < esc->sm_hi[k]) {
            return esc->sm_order[k];
        }
    }
    return CO_ESC_MAX_SM;
}

/* Which SM buffer each active FMMU's physical window lies in, worked out when an FMMU or SM is
 * configured rather than for every datagram: a cyclic frame then goes straight to the buffer. A
 * window that reaches plain RAM, registers or another SM keeps the general path (mem_access). */
static void fmmu_map_sms(co_esc *esc)
{
    for (unsigned k = 0; k < esc->fmmu_active; k++) {
        co_esc_fmmu *f = &esc->fmmu[k];
        unsigned s = sm_at(esc, f->phys);
        bool inside = s != CO_ESC_MAX_SM &&
                      (uint32_t)f->phys + f->len <= (uint32_t)esc->sm[s].start + esc->sm[s].len;
        f->sm = (uint8_t)(inside ? s : CO_ESC_MAX_SM);
    }
}

/* Re-reads SM n's registers after a write to them; a change of the enable state resets the
 * buffer state (a disabled SM forgets a full mailbox and its buffers). */
static void sm_update(co_esc *esc, unsigned n)
{
    co_esc_sm *sm = &esc->sm[n];
    const uint8_t *r = &esc->mem[CO_ESC_REG_SM(n)];
    uint16_t start = rd16(r), len = rd16(r + 2);
    uint8_t act = r[6];
    uint32_t need = ((r[4] & 0x03u) == CO_ESC_SM_CTRL_MAILBOX) ? len : 3u * (uint32_t)len;
    /* Process RAM only; mode 01 and direction 1x are reserved; the buffers must fit. */
    bool on = (act & 1u) && !(r[7] & 1u) && len != 0 && start >= CO_ESC_REG_SIZE &&
              (r[4] & 0x03u) != 0x01u && (r[4] & 0x08u) == 0 &&
              (uint32_t)start + need <= CO_ESC_MEM_SIZE;

    if (act != sm->act) {
        sm->act = act;
        al_event_set(esc, CO_ESC_AL_EVENT_SM_CHANGE);
    }
    sm->start = start;
    sm->len = len;
    sm->ctrl = r[4];
    if ((uint8_t)on != sm->on) {
        sm->on = (uint8_t)on;
        sm->latest = 3;
        sm->w_open = 0;
        sm->r_open = 0;
        esc->mem[CO_ESC_REG_SM_STATUS(n)] = (on && !sm_mailbox(sm)) ? 0x30u : 0x00u;
        al_event_clear(esc, CO_ESC_AL_EVENT_SM(n));
        ecat_event_clear(esc, (uint16_t)CO_ESC_ECAT_EVENT_SM(n));
    }
    sm_sort(esc);
    fmmu_map_sms(esc);
}

/* Tells the other side that this side completed an access to SM n's buffer. */
static inline void sm_notify(co_esc *esc, unsigned n, int side)
{
    const co_esc_sm *sm = &esc->sm[n];
    if (side == SIDE_ECAT) {
        if (sm->ctrl & CO_ESC_SM_CTRL_AL_EVENT) {
            al_event_set(esc, CO_ESC_AL_EVENT_SM(n));
        }
    } else if (sm->ctrl & CO_ESC_SM_CTRL_ECAT_EVENT) {
        ecat_event_set(esc, (uint16_t)CO_ESC_ECAT_EVENT_SM(n));
    }
}

/* This side begins an access to SM n's buffer: its pending event is consumed. */
static void sm_consume(co_esc *esc, unsigned n, int side)
{
    if (side == SIDE_ECAT) {
        ecat_event_clear(esc, (uint16_t)CO_ESC_ECAT_EVENT_SM(n));
    } else {
        al_event_clear(esc, CO_ESC_AL_EVENT_SM(n));
    }
}

/* An access of one side to [addr, addr + len) inside SM n's buffer. A buffer is accessed from its
 * start address, in one or several strokes, and the access that covers its end address completes
 * it (section I §8). Returns ACC_* bits. */
static unsigned sm_access(co_esc *esc, unsigned n, int side, unsigned op, uint32_t addr,
                          uint8_t *out, const uint8_t *in, uint32_t len)
{
    co_esc_sm *sm = &esc->sm[n];
    uint8_t *status = &esc->mem[CO_ESC_REG_SM_STATUS(n)];
    bool at_start = addr == sm->start;
    bool at_end = addr + len == (uint32_t)sm->start + sm->len;
    bool mailbox = sm_mailbox(sm);
    uint32_t shift;

    if (sm_writer(sm) == side) {
        if (!(op & OP_WRITE)) {
            return ACC_DENIED; /* the writer side may not read the buffer */
        }
        if (mailbox && (*status & CO_ESC_SM_STATUS_MBX_FULL)) {
            return ACC_DENIED;
        }
        if (at_start) {
            sm->w_open = 1;
            *status &= (uint8_t)~CO_ESC_SM_STATUS_IRQ_READ;
            sm_consume(esc, n, side);
            if (!mailbox) { /* the free buffer: neither the latest nor the one being read */
                uint8_t b = 0;
                while (b == sm->latest || (sm->r_open && b == sm->rbuf)) {
                    b++;
                }
                sm->wbuf = b;
            }
        }
        if (!sm->w_open) {
            return ACC_DENIED;
        }
        shift = mailbox ? 0u : (uint32_t)sm->wbuf * sm->len;
        memcpy(&esc->mem[addr + shift], in, len);
        if (at_end) {
            sm->w_open = 0;
            if (mailbox) {
                *status |= CO_ESC_SM_STATUS_MBX_FULL;
            } else {
                sm->latest = sm->wbuf;
                *status = (uint8_t)((*status & ~0x30u) | (uint8_t)(sm->latest << 4));
            }
            *status |= CO_ESC_SM_STATUS_IRQ_WRITE;
            sm_notify(esc, n, side);
            if (side == SIDE_ECAT && (sm->ctrl & CO_ESC_SM_CTRL_WATCHDOG)) {
                wd_trigger(esc);
            }
        }
        return ACC_WRITE;
    }

    if (!(op & OP_READ)) {
        return ACC_DENIED; /* the reader side may not write the buffer */
    }
    if (mailbox && !(*status & CO_ESC_SM_STATUS_MBX_FULL)) {
        return ACC_DENIED;
    }
    if (at_start) {
        sm->r_open = 1;
        *status &= (uint8_t)~CO_ESC_SM_STATUS_IRQ_WRITE;
        sm_consume(esc, n, side);
        sm->rbuf = sm->latest == 3u ? 0u : sm->latest;
    }
    if (!sm->r_open) {
        return ACC_DENIED;
    }
    shift = mailbox ? 0u : (uint32_t)sm->rbuf * sm->len;
    if (op & OP_OR) {
        for (uint32_t i = 0; i < len; i++) {
            out[i] |= esc->mem[addr + shift + i];
        }
    } else {
        memcpy(out, &esc->mem[addr + shift], len);
    }
    if (at_end) {
        sm->r_open = 0;
        if (mailbox) {
            *status &= (uint8_t)~CO_ESC_SM_STATUS_MBX_FULL;
        }
        *status |= CO_ESC_SM_STATUS_IRQ_READ;
        sm_notify(esc, n, side);
    }
    return ACC_READ;
}

/* ---- FMMUs (section I §7) ---- */

/* The active FMMUs, those that write to memory first: a logical command is executed in this
 * order, so write FMMUs take the data as received before read FMMUs overwrite it. */
static void fmmu_update(co_esc *esc)
{
    esc->fmmu_active = 0;
    for (unsigned want = 2; want > 0; want--) { /* type bit 1 (write) set, then not set */
        for (unsigned i = 0; i < esc->fmmu_count; i++) {
            const uint8_t *r = &esc->mem[CO_ESC_REG_FMMU(i)];
            co_esc_fmmu *f = &esc->fmmu[esc->fmmu_active];
            unsigned type = r[11] & 3u;
            if ((r[12] & 1u) && rd16(r + 4) != 0 && type != 0 && ((type >> 1) == want - 1u)) {
                f->log = rd32(r);
                f->len = rd16(r + 4);
                f->phys = rd16(r + 8);
                f->type = (uint8_t)type;
                esc->fmmu_active++;
            }
        }
    }
    fmmu_map_sms(esc);
}

/* ---- SII EEPROM interface (section I §11, section II 0x0500-0x050F) ---- */

/* CRC-8 of the SII configuration area, words 0-6 (polynomial x^8 + x^2 + x + 1, initial 0xFF),
 * stored in the low byte of word 7 (ETG.2010). */
static bool sii_header_ok(const co_esc *esc)
{
    uint8_t crc = 0xFF;
    if (esc->sii == NULL || esc->sii_size < 16u) {
        return false;
    }
    for (unsigned i = 0; i < 14u; i++) {
        crc ^= esc->sii[i];
        for (unsigned b = 0; b < 8u; b++) {
            crc = (uint8_t)((crc & 0x80u) ? ((unsigned)crc << 1) ^ 0x07u : (unsigned)crc << 1);
        }
    }
    return crc == esc->sii[14];
}

/* The ESC's EEPROM load at power-on or on a reload command: configuration words into their
 * registers, or the checksum/loading error bits. */
static void sii_load(co_esc *esc)
{
    uint8_t *m = esc->mem;
    uint16_t ctl = rd16(&m[CO_ESC_REG_EEP_CTL]) & (uint16_t) ~(EEP_CSUM_ERR | EEP_LOAD_ERR);
    if (sii_header_ok(esc)) {
        m[CO_ESC_REG_PDICTL] = esc->sii[0];
        m[CO_ESC_REG_PDICTL + 1u] = esc->sii[1];
        memcpy(&m[0x0150], &esc->sii[2], 2);  /* PDI configuration */
        memcpy(&m[0x0152], &esc->sii[6], 2);  /* extended PDI configuration */
        memcpy(&m[CO_ESC_REG_ALIAS], &esc->sii[8], 2);
        if (esc->dc) {
            memcpy(&m[0x0982], &esc->sii[4], 2); /* SYNC pulse length */
        }
        m[CO_ESC_REG_DLSTAT] |= 1u; /* PDI operational: EEPROM loaded */
    } else {
        ctl |= EEP_CSUM_ERR | EEP_LOAD_ERR;
        m[CO_ESC_REG_DLSTAT] &= (uint8_t)~1u;
    }
    wr16(&m[CO_ESC_REG_EEP_CTL], ctl);
}

/* A command written to 0x0502 (with the address already in 0x0504): executed at once, so the
 * busy bit is never seen set. Reads copy 4 (or 8) bytes from the word address; words beyond the
 * image read 0xFFFF as an unprogrammed EEPROM. The image is read-only: a write command answers
 * with the write-enable error (no write enable) or the acknowledge error. */
static void eeprom_command(co_esc *esc)
{
    uint8_t *m = esc->mem;
    uint16_t ctl = rd16(&m[CO_ESC_REG_EEP_CTL]) & (uint16_t) ~(EEP_ACK_ERR | EEP_WE_ERR);
    uint16_t cmd = ctl & EEP_CMD_MASK;

    if (cmd == EEP_CMD_READ) {
        uint64_t at = (uint64_t)rd32(&m[CO_ESC_REG_EEP_ADDR]) * 2u;
        unsigned n = (ctl & EEP_READ8) ? 8u : 4u;
        for (unsigned i = 0; i < n; i++) {
            m[CO_ESC_REG_EEP_DATA + i] = at + i < esc->sii_size ? esc->sii[at + i] : 0xFFu;
        }
    } else if (cmd == EEP_CMD_WRITE) {
        ctl |= (ctl & EEP_WRITE_EN) ? EEP_ACK_ERR : EEP_WE_ERR;
    } else if (cmd == EEP_CMD_RELOAD) {
        wr16(&m[CO_ESC_REG_EEP_CTL], ctl);
        sii_load(esc);
        ctl = rd16(&m[CO_ESC_REG_EEP_CTL]);
    } else if (cmd != 0) {
        ctl |= EEP_ACK_ERR; /* invalid command */
    }
    /* The command is done and the write enable is used up. */
    wr16(&m[CO_ESC_REG_EEP_CTL], (uint16_t)(ctl & ~(EEP_CMD_MASK | EEP_WRITE_EN)));
}

/* ---- Distributed clocks (section I §9), when emulated ---- */

/* The local copy of the system time: the caller's clock plus the system time offset 0x0920. */
static void dc_systime(co_esc *esc)
{
    wr64(&esc->mem[CO_ESC_REG_DC_SYSTIME], esc->now + rd64(&esc->mem[CO_ESC_REG_DC_OFFSET]));
}

/* A write to 0x0900 latches the receive time of the frame at each open port (32-bit local
 * time) and at the processing unit (64-bit, 0x0918). The frame comes back to port p > 0 after
 * the slaves behind it: 100 ns per port here, so port 0 always has the lowest time. */
static void dc_latch(co_esc *esc, uint8_t open_ports)
{
    for (unsigned p = 0; p < 4u; p++) {
        uint32_t t = (open_ports & (1u << p)) ? (uint32_t)esc->now + 100u * p : 0u;
        for (unsigned i = 0; i < 4u; i++) {
            esc->mem[CO_ESC_REG_DC_RECV_TIME + 4u * p + i] = (uint8_t)(t >> (8u * i));
        }
    }
    wr64(&esc->mem[CO_ESC_REG_DC_RECV_TIME_PU], esc->now);
}

/* ---- Registers ---- */

/* The bits of register byte a that `side` may write (the table in esc.h). */
static uint8_t reg_write_mask(const co_esc *esc, int side, uint32_t a)
{
    if (a >= 0x0F80u) {
        return 0xFFu; /* user RAM */
    }
    if (a >= CO_ESC_REG_SM(0) && a < CO_ESC_REG_SM(esc->sm_count)) {
        unsigned byte = (a - CO_ESC_REG_SM(0)) % 8u;
        bool enabled = esc->mem[a - byte + 6u] & 1u;
        if (side == SIDE_PDI) {
            return byte == 7u ? 0x03u : 0x00u;
        }
        if (byte == 6u) {
            return 0xC3u;
        }
        return byte <= 4u && !enabled ? 0xFFu : 0x00u;
    }
    if (side == SIDE_PDI) {
        if ((a >= 0x0012u && a <= 0x0013u) || (a >= 0x0130u && a <= 0x0135u) ||
            (a >= 0x0204u && a <= 0x0207u)) {
            return 0xFFu;
        }
        return 0x00u;
    }
    if (a >= CO_ESC_REG_FMMU(0) && a < CO_ESC_REG_FMMU(esc->fmmu_count)) {
        return 0xFFu;
    }
    if (a >= 0x0900u && a <= 0x09FFu) {
        if (!esc->dc) {
            return 0x00u;
        }
        /* Receive and system times are written only for their effect (latch, drift input). */
        return (a >= 0x0920u && a <= 0x092Bu) || (a >= 0x0930u && a <= 0x0935u) ||
                       (a >= 0x0980u && a <= 0x0981u) || (a >= 0x0990u && a <= 0x0997u) ||
                       (a >= 0x09A0u && a <= 0x09A9u)
                   ? 0xFFu
                   : 0x00u;
    }
    switch (a) {
    case 0x0010: case 0x0011:                         /* station address */
    case 0x0100: case 0x0101: case 0x0102: case 0x0103: /* DL control */
    case 0x0108: case 0x0109:                         /* physical read/write offset */
    case 0x0120: case 0x0121:                         /* AL control */
    case 0x0200: case 0x0201:                         /* ECAT event mask */
    case 0x0400: case 0x0401: case 0x0410: case 0x0411: case 0x0420: case 0x0421: /* watchdogs */
    case 0x0504: case 0x0505: case 0x0506: case 0x0507:                         /* EEPROM address */
    case 0x0508: case 0x0509: case 0x050A: case 0x050B:
    case 0x050C: case 0x050D: case 0x050E: case 0x050F:                         /* EEPROM data */
        return 0xFFu;
    case 0x0500:
        return 0x03u; /* EEPROM offered to the PDI, force ECAT access */
    case 0x0502:
        return 0x01u; /* write enable */
    case 0x0503:
        return 0x07u; /* command */
    default:
        return 0x00u;
    }
}

/* Counters that a master write clears whatever the value (section II 0x0300, 0x0442). */
static bool reg_clear_on_write(int side, uint32_t a)
{
    return side == SIDE_ECAT && ((a >= 0x0300u && a <= 0x0313u) || a == 0x0442u || a == 0x0443u);
}

/* Access to [a, a + n) of the register space (a + n <= 0x1000): every access is acknowledged,
 * read-only bytes are left as they are. Side effects after the bytes are moved. */
static unsigned reg_access(co_esc *esc, int side, unsigned op, uint32_t a, uint8_t *out,
                           const uint8_t *in, uint32_t n)
{
    uint8_t *m = esc->mem;
    unsigned done = 0;

    if ((op & OP_READ) && esc->dc && overlaps(a, n, CO_ESC_REG_DC_SYSTIME, 8)) {
        dc_systime(esc);
    }
    for (uint32_t i = 0; i < n; i++) {
        uint8_t old = m[a + i];
        if (op & OP_WRITE) {
            uint8_t v = in[i];
            uint8_t mask = reg_write_mask(esc, side, a + i);
            if (reg_clear_on_write(side, a + i)) {
                m[a + i] = 0;
            } else {
                m[a + i] = (uint8_t)((old & ~mask) | (v & mask));
            }
            if (op & OP_READ) {
                out[i] = (op & OP_OR) ? (uint8_t)(v | old) : old;
            }
        } else if (op & OP_OR) {
            out[i] |= old;
        } else {
            out[i] = old;
        }
    }

    if (op & OP_WRITE) {
        done |= ACC_WRITE;
        if (side == SIDE_ECAT && overlaps(a, n, CO_ESC_REG_ALCTL, 2)) {
            al_event_set(esc, CO_ESC_AL_EVENT_ALCTL);
        }
        if (side == SIDE_PDI && overlaps(a, n, CO_ESC_REG_ALSTAT, 6)) {
            ecat_event_set(esc, CO_ESC_ECAT_EVENT_ALSTAT);
        }
        if (overlaps(a, n, CO_ESC_REG_SM(0), 8u * esc->sm_count)) {
            for (unsigned s = 0; s < esc->sm_count; s++) {
                if (overlaps(a, n, CO_ESC_REG_SM(s), 8)) {
                    sm_update(esc, s);
                }
            }
        }
        if (side == SIDE_ECAT) {
            if (overlaps(a, n, CO_ESC_REG_FMMU(0), 16u * esc->fmmu_count)) {
                fmmu_update(esc);
            }
            if (overlaps(a, n, CO_ESC_REG_EEP_CTL, 2)) {
                eeprom_command(esc);
            }
            if (overlaps(a, n, CO_ESC_REG_WD_DIV, 2) || overlaps(a, n, CO_ESC_REG_WD_SM, 2)) {
                /* A new time applies from now; 0 disables the watchdog (status "active"). */
                if (wd_timeout(esc) == 0) {
                    esc->wd_deadline = CO_ESC_TIME_NEVER;
                    m[CO_ESC_REG_WD_STATUS] |= 1u;
                } else if (esc->wd_deadline != CO_ESC_TIME_NEVER) {
                    wd_trigger(esc);
                }
            }
            if (esc->dc && overlaps(a, n, CO_ESC_REG_DC_RECV_TIME, 1)) {
                dc_latch(esc, (uint8_t)(m[CO_ESC_REG_DLSTAT] >> 4));
            }
        }
    }
    if (op & OP_READ) {
        done |= ACC_READ;
        if (side == SIDE_ECAT && overlaps(a, n, CO_ESC_REG_ALSTAT, 2)) {
            ecat_event_clear(esc, CO_ESC_ECAT_EVENT_ALSTAT);
        }
        if (side == SIDE_PDI) {
            if (overlaps(a, n, CO_ESC_REG_ALCTL, 2)) {
                al_event_clear(esc, CO_ESC_AL_EVENT_ALCTL);
            }
            if (overlaps(a, n, CO_ESC_REG_WD_STATUS, 1)) {
                al_event_clear(esc, CO_ESC_AL_EVENT_WD_PD);
            }
            for (unsigned s = 0; s < esc->sm_count; s++) {
                if (overlaps(a, n, CO_ESC_REG_SM_ACTIVATE(s), 1)) {
                    al_event_clear(esc, CO_ESC_AL_EVENT_SM_CHANGE);
                }
            }
        }
    }
    return done;
}

/* Process RAM outside SyncManagers: plain memory for both sides. */
static unsigned ram_access(co_esc *esc, unsigned op, uint32_t a, uint8_t *out, const uint8_t *in,
                           uint32_t n)
{
    uint8_t *m = &esc->mem[a];
    for (uint32_t i = 0; i < n; i++) {
        uint8_t old = m[i];
        if (op & OP_WRITE) {
            m[i] = in[i];
        }
        if (op & OP_READ) {
            out[i] = (op & OP_OR) ? (uint8_t)(old | ((op & OP_WRITE) ? in[i] : out[i])) : old;
        }
    }
    return op & (OP_READ | OP_WRITE); /* ACC_READ / ACC_WRITE have the same values */
}

/* One side's access to [addr, addr + len) of the image, split into register, SyncManager and
 * plain RAM parts. Bytes beyond the image are not accessed (and counted as denied). out receives
 * read bytes, in gives written bytes (the same buffer for a frame; one of them is NULL for the
 * PDI). */
static unsigned mem_access(co_esc *esc, int side, unsigned op, uint32_t addr, uint8_t *out,
                           const uint8_t *in, uint32_t len)
{
    unsigned done = 0;
    uint32_t pos = 0;

    while (pos < len) {
        uint32_t a = addr + pos, seg = len - pos;
        uint8_t *o = out != NULL ? out + pos : NULL;
        const uint8_t *i = in != NULL ? in + pos : NULL;

        if (a >= CO_ESC_MEM_SIZE) {
            return done | ACC_DENIED;
        }
        if (a < CO_ESC_REG_SIZE) {
            if (seg > CO_ESC_REG_SIZE - a) {
                seg = CO_ESC_REG_SIZE - a;
            }
            done |= reg_access(esc, side, op, a, o, i, seg);
        } else {
            uint32_t bound = CO_ESC_MEM_SIZE;
            unsigned hit = CO_ESC_MAX_SM;
            for (unsigned k = 0; k < esc->sm_enabled; k++) {
                if (a < esc->sm_lo[k]) {
                    bound = esc->sm_lo[k]; /* plain RAM up to the next SM */
                    break;
                }
                if (a < esc->sm_hi[k]) {
                    hit = esc->sm_order[k];
                    bound = esc->sm_hi[k];
                    break;
                }
            }
            if (seg > bound - a) {
                seg = bound - a;
            }
            if (hit != CO_ESC_MAX_SM) {
                done |= sm_access(esc, hit, side, op, a, o, i, seg);
            } else {
                done |= ram_access(esc, op, a, o, i, seg);
            }
        }
        pos += seg;
    }
    return done;
}

/* A PDI access: the common case, an SM buffer that holds all of it, goes straight to the buffer
 * (the application's SM2 read and SM3 write each cycle); anything else through mem_access. */
static unsigned pdi_access(co_esc *esc, unsigned op, uint32_t addr, uint8_t *out,
                           const uint8_t *in, uint32_t len)
{
    if (addr >= CO_ESC_REG_SIZE) {
        unsigned s = sm_at(esc, addr);
        if (s != CO_ESC_MAX_SM && addr + len <= (uint32_t)esc->sm[s].start + esc->sm[s].len) {
            return sm_access(esc, s, SIDE_PDI, op, addr, out, in, len);
        }
    }
    return mem_access(esc, SIDE_PDI, op, addr, out, in, len);
}

/* ---- Datagrams ---- */

/* A logical command through the active FMMUs (in fmmu_update's order: the write FMMUs take the
 * data as received, then the read FMMUs put memory into the frame, so a slave whose inputs and
 * outputs share logical addresses sees the master's outputs). Byte-granular: start bit 0 and
 * stop bit 7 are assumed, as SOEM programs them for byte-aligned slaves. Returns ACC_READ /
 * ACC_WRITE if any FMMU of that direction moved data. */
static unsigned logical(co_esc *esc, unsigned op, uint32_t laddr, uint8_t *data, uint32_t dlen)
{
    unsigned done = 0;
    uint64_t lend = (uint64_t)laddr + dlen;

    for (unsigned k = 0; k < esc->fmmu_active; k++) {
        const co_esc_fmmu *f = &esc->fmmu[k];
        uint64_t fend = (uint64_t)f->log + f->len;
        uint64_t from = laddr > f->log ? laddr : f->log;
        uint64_t to = lend < fend ? lend : fend;
        unsigned fop = f->type & op;
        if (fop != 0 && from < to) {
            uint8_t *d = data + (from - laddr);
            uint32_t phys = (uint32_t)(f->phys + (from - f->log)), n = (uint32_t)(to - from);
            done |= (f->sm != CO_ESC_MAX_SM ? sm_access(esc, f->sm, SIDE_ECAT, fop, phys, d, d, n)
                                            : mem_access(esc, SIDE_ECAT, fop, phys, d, d, n)) &
                    fop;
        }
    }
    return done;
}

/* Configured addressing: the station address, or the alias when DL control bit 24 enables it. */
static bool fixed_hit(const co_esc *esc, uint16_t adp)
{
    return adp == rd16(&esc->mem[CO_ESC_REG_STADR]) ||
           ((esc->mem[CO_ESC_REG_DLCTL + 3u] & 1u) && adp == rd16(&esc->mem[CO_ESC_REG_ALIAS]));
}

/* Executes one well-formed datagram at dg (header, data, WKC). */
static void datagram(co_esc *esc, uint8_t *dg)
{
    static const uint8_t phys_op[] = {
        0, OP_READ, OP_WRITE, OP_READ | OP_WRITE,   /* NOP, APRD, APWR, APRW */
        OP_READ, OP_WRITE, OP_READ | OP_WRITE,      /* FPRD, FPWR, FPRW */
        OP_READ | OP_OR, OP_WRITE, OP_READ | OP_WRITE | OP_OR, /* BRD, BWR, BRW */
        OP_READ, OP_WRITE, OP_READ | OP_WRITE,      /* LRD, LWR, LRW */
    };
    uint8_t cmd = dg[0];
    uint16_t adp = rd16(dg + 2), ado = rd16(dg + 4);
    uint32_t dlen = rd16(dg + 6) & 0x7FFu;
    uint8_t *data = dg + DG_HDR;
    unsigned op = 0, got, wkc = 0;

    esc->stats.datagrams++;
    switch (cmd) {
    case CMD_NOP:
        break;
    case CMD_APRD: case CMD_APWR: case CMD_APRW:
        if (adp == 0) {
            op = phys_op[cmd];
        }
        wr16(dg + 2, (uint16_t)(adp + 1u));
        break;
    case CMD_FPRD: case CMD_FPWR: case CMD_FPRW:
        if (fixed_hit(esc, adp)) {
            op = phys_op[cmd];
        }
        break;
    case CMD_BRD: case CMD_BWR: case CMD_BRW:
        op = phys_op[cmd];
        wr16(dg + 2, (uint16_t)(adp + 1u));
        break;
    case CMD_ARMW:
        op = adp == 0 ? OP_READ : OP_WRITE;
        wr16(dg + 2, (uint16_t)(adp + 1u));
        break;
    case CMD_FRMW:
        op = fixed_hit(esc, adp) ? OP_READ : OP_WRITE;
        break;
    case CMD_LRD: case CMD_LWR: case CMD_LRW:
        got = logical(esc, phys_op[cmd], rd32(dg + 2), data, dlen);
        /* Read +1, write +2 for LRW; a single direction counts 1 (ETG.1000.4 WKC rules). */
        wkc = cmd == CMD_LRW ? (got & ACC_READ) + (got & ACC_WRITE) : (got != 0);
        break;
    default:
        esc->stats.unknown_cmds++;
        return; /* not a command this ESC knows: passed on as it is */
    }
    if (op != 0 && dlen != 0) {
        got = mem_access(esc, SIDE_ECAT, op, ado, data, data, dlen);
        if ((op & (OP_READ | OP_WRITE)) == (OP_READ | OP_WRITE)) {
            wkc = (got & ACC_READ) + (got & ACC_WRITE); /* RW: read +1, write +2 */
        } else {
            wkc = (got & (ACC_READ | ACC_WRITE)) != 0;
        }
    }
    wr16(dg + DG_HDR + dlen, (uint16_t)(rd16(dg + DG_HDR + dlen) + wkc));
    /* The IRQ field collects the ECAT event requests that the ECAT event mask lets through. */
    wr16(dg + 8, (uint16_t)(rd16(dg + 8) | (rd16(&esc->mem[CO_ESC_REG_ECAT_EVENT]) &
                                            rd16(&esc->mem[CO_ESC_REG_ECAT_EVENT_MASK]))));
}

/* Checks the frame's structure: EtherType 0x88A4, type 1, the length field inside the frame and
 * the datagrams (each with its data and WKC) filling exactly that length. */
static int frame_check(const uint8_t *f, size_t len)
{
    size_t off = ETH_HDR + ECAT_HDR, end;
    uint16_t hdr;
    bool more;

    if (len < ETH_HDR) {
        return CO_ESC_FRAME_SHORT;
    }
    if (f[12] != 0x88u || f[13] != 0xA4u) {
        return CO_ESC_FRAME_NOT_ECAT;
    }
    if (len < ETH_HDR + ECAT_HDR) {
        return CO_ESC_FRAME_SHORT;
    }
    hdr = rd16(f + ETH_HDR);
    if ((hdr >> 12) != 1u) {
        return CO_ESC_FRAME_NOT_ECAT;
    }
    end = off + (hdr & 0x7FFu);
    if (end > len) {
        return CO_ESC_FRAME_BAD_LENGTH;
    }
    do {
        size_t dlen;
        if (off + DG_HDR + DG_WKC > end) {
            return CO_ESC_FRAME_BAD_LENGTH;
        }
        dlen = rd16(f + off + 6) & 0x7FFu;
        more = (f[off + 7] & 0x80u) != 0;
        off += DG_HDR + dlen + DG_WKC;
        if (off > end) {
            return CO_ESC_FRAME_BAD_LENGTH;
        }
    } while (more);
    return off == end ? CO_ESC_FRAME_OK : CO_ESC_FRAME_BAD_LENGTH;
}

/* ---- Public API ---- */

co_esc_config co_esc_default_config(void)
{
    co_esc_config c;
    memset(&c, 0, sizeof c);
    c.type = 0x11;      /* ET1100 */
    c.revision = 0x00;
    c.build = 0x0000;
    c.fmmu_count = 8;
    c.sm_count = 8;
    c.port_desc = 0x0F; /* ports 0 and 1 MII, 2 and 3 not implemented */
    c.open_ports = 0x01;
    return c;
}

int co_esc_init(co_esc *esc, const co_esc_config *cfg)
{
    uint8_t *m;
    uint16_t dl = 0x0002; /* PDI watchdog not expired (it is not emulated) */
    uint16_t features = CO_ESC_FEATURE_FMMU_BYTES;

    if (esc == NULL || cfg == NULL || cfg->fmmu_count == 0 || cfg->fmmu_count > CO_ESC_MAX_FMMU ||
        cfg->sm_count == 0 || cfg->sm_count > CO_ESC_MAX_SM) {
        return -1;
    }
    memset(esc, 0, sizeof *esc);
    m = esc->mem;
    esc->sii = cfg->sii;
    esc->sii_size = cfg->sii != NULL ? cfg->sii_size : 0;
    esc->fmmu_count = cfg->fmmu_count;
    esc->sm_count = cfg->sm_count;
    esc->dc = cfg->dc;
    esc->wd_deadline = CO_ESC_TIME_NEVER;
    for (unsigned s = 0; s < CO_ESC_MAX_SM; s++) {
        esc->sm[s].latest = 3;
    }

    m[0x0000] = cfg->type;
    m[0x0001] = cfg->revision;
    wr16(&m[0x0002], cfg->build);
    m[0x0004] = cfg->fmmu_count;
    m[0x0005] = cfg->sm_count;
    m[0x0006] = (uint8_t)(CO_ESC_RAM_SIZE / 1024u);
    m[0x0007] = cfg->port_desc;
    if (cfg->dc) {
        features |= CO_ESC_FEATURE_DC | CO_ESC_FEATURE_DC64;
    }
    wr16(&m[CO_ESC_REG_FEATURES], features);

    /* DL status: per port p, physical link (bit 4+p) and communication (bit 9+2p) when open,
     * loop closed (bit 8+2p) otherwise. */
    for (unsigned p = 0; p < 4u; p++) {
        if ((cfg->open_ports | 1u) & (1u << p)) {
            dl |= (uint16_t)((1u << (4u + p)) | (1u << (9u + 2u * p)));
        } else {
            dl |= (uint16_t)(1u << (8u + 2u * p));
        }
    }
    wr16(&m[CO_ESC_REG_DLSTAT], dl);

    wr16(&m[CO_ESC_REG_ALSTAT], 0x0001); /* INIT until the application says otherwise */
    wr16(&m[CO_ESC_REG_WD_DIV], 2498);   /* 100 µs */
    wr16(&m[CO_ESC_REG_WD_PDI], 1000);   /* 100 ms */
    wr16(&m[CO_ESC_REG_WD_SM], 1000);
    m[CO_ESC_REG_WD_STATUS] = 1;
    wr16(&m[CO_ESC_REG_EEP_CTL], cfg->eeprom_read8 ? EEP_READ8 : 0u);
    sii_load(esc);
    return 0;
}

int co_esc_process_frame(co_esc *esc, uint8_t *frame, size_t len, uint64_t now_ns)
{
    int rc = frame_check(frame, len);
    size_t off = ETH_HDR + ECAT_HDR;
    bool more;

    esc->now = now_ns;
    wd_run(esc);
    if (rc == CO_ESC_FRAME_NOT_ECAT) {
        esc->stats.ignored++;
        return rc;
    }
    if (rc != CO_ESC_FRAME_OK) {
        esc->stats.bad_frames++;
        if (esc->mem[CO_ESC_REG_RXERR] != 0xFFu) { /* invalid frame counter, port 0 */
            esc->mem[CO_ESC_REG_RXERR]++;
        }
        return rc;
    }
    esc->stats.frames++;
    do {
        uint8_t *dg = frame + off;
        size_t dlen = rd16(dg + 6) & 0x7FFu;
        more = (dg[7] & 0x80u) != 0;
        datagram(esc, dg);
        off += DG_HDR + dlen + DG_WKC;
    } while (more);
    frame[6] |= 0x02u; /* source MAC: locally administered, the frame has passed an ESC */
    return CO_ESC_FRAME_OK;
}

int co_esc_chain_process(co_esc *const esc[], size_t n, uint8_t *frame, size_t len,
                         uint64_t now_ns)
{
    int rc = CO_ESC_FRAME_NOT_ECAT;
    for (size_t i = 0; i < n; i++) {
        rc = co_esc_process_frame(esc[i], frame, len, now_ns);
    }
    return rc;
}

int co_esc_pdi_read(co_esc *esc, uint16_t addr, void *buf, size_t len)
{
    unsigned got;
    if ((size_t)addr + len > CO_ESC_MEM_SIZE) {
        return CO_ESC_PDI_RANGE;
    }
    if (len == 0) {
        return CO_ESC_PDI_OK;
    }
    got = pdi_access(esc, OP_READ, addr, buf, NULL, (uint32_t)len);
    return (got & ACC_DENIED) ? CO_ESC_PDI_BLOCKED : CO_ESC_PDI_OK;
}

int co_esc_pdi_write(co_esc *esc, uint16_t addr, const void *buf, size_t len)
{
    unsigned got;
    if ((size_t)addr + len > CO_ESC_MEM_SIZE) {
        return CO_ESC_PDI_RANGE;
    }
    if (len == 0) {
        return CO_ESC_PDI_OK;
    }
    got = pdi_access(esc, OP_WRITE, addr, NULL, buf, (uint32_t)len);
    return (got & ACC_DENIED) ? CO_ESC_PDI_BLOCKED : CO_ESC_PDI_OK;
}

uint32_t co_esc_al_event(const co_esc *esc)
{
    return rd32(&esc->mem[CO_ESC_REG_AL_EVENT]);
}

uint64_t co_esc_tick(co_esc *esc, uint64_t now_ns)
{
    esc->now = now_ns;
    wd_run(esc);
    return esc->wd_deadline;
}
