/* libFuzzer target: the emulated EtherCAT Slave Controller (ecat/) fed whole frames of any bytes,
 * interleaved with PDI reads and writes and clock steps, on one ESC or a chain of two.
 *
 * Input: byte 0 = setup (bit 0: chain of two, bit 1: DC emulated, bit 2: 8-byte EEPROM reads,
 * bit 3: a few SMs/FMMUs preconfigured as SOEM leaves them, bit 4: SII checksum right). Then operations, each
 *   op (1 byte), len (2 bytes LE), payload (len bytes, cut at the input's end):
 *   op % 4 == 0: the payload is a frame (passed through the ESC or the chain);
 *   op % 4 == 1: PDI write of the payload at the address in its first 2 bytes;
 *   op % 4 == 2: PDI read of len bytes at the address in the payload's first 2 bytes;
 *   (both on the ESC op >> 7 of a chain; not on an ESC the application layer runs on);
 *   op % 4 == 3: the clock moves by the payload's first 4 bytes (ns) and co_esc_tick runs.
 * A frame op with len 0 sends a ready-made LRW / mailbox frame (so the state space is reached
 * faster than from random bytes).
 *
 * Invariants (docs/robustness.md, "Emulated EtherCAT slave controller"), checked after every op:
 *   1. No crash, no sanitizer report (ASan, UBSan without recovery).
 *   2. The master side changes no byte outside the areas it may write or the ESC derives from
 *      its accesses (listed in master_may_change below, written from the register description,
 *      not from esc.c's table).
 *   3. The PDI side changes no byte of the registers only the master writes.
 *   4. A frame that is not processed is left as it came; a processed one keeps its length and
 *      every datagram header but ADP (+1 per slave for auto-increment and broadcast commands)
 *      and IRQ (bits only added); each WKC grows by 0..3 per slave, never decreases.
 * With the slave application layer (FUZZ_ECAT_SLAVE, setup bit 5: ecat/src/slave.c and the VF-MB1
 * drive behind the first ESC, co_ecat_slave_process after every operation):
 *   5. Its PDI accesses change no byte only the master writes (invariant 3 again).
 *   6. AL status is INIT, PRE-OP, SAFE-OP or OP, with the error bit exactly when the AL status
 *      code is not 0; the slave's own state agrees with the register.
 *   7. The node's NMT state is the one the ESM state maps to (slave.h).
 * Canned frames (an op with len 0): by op >> 2 (mod 4): a mailbox write of 16 bytes, an LRW of
 * 8 bytes, an AL control request (state op >> 4), a read of the SM1 mailbox.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "canopen/ecat/esc.h"
#if FUZZ_ECAT_SLAVE
#include "canopen/drive.h"
#include "canopen/ecat/slave.h"
#include "od_vf_mb1_ecat.h"
#endif

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define FAIL(...)                                                                                  \
    do {                                                                                           \
        fprintf(stderr, "fuzz_esc_frame: " __VA_ARGS__);                                        \
        fputc('\n', stderr);                                                                       \
        abort();                                                                                   \
    } while (0)

typedef struct fz_esc {
    co_esc esc[2];
    co_esc *chain[2];
    unsigned n;
    uint64_t now;
    uint8_t sii[256];
    uint8_t before[2][CO_ESC_MEM_SIZE];
    uint8_t frame[1600];
    uint8_t frame_in[1600];
#if FUZZ_ECAT_SLAVE
    bool app;
    co_drive drive;
    co_ecat_slave slave;
    uint8_t values[8192];
#endif
} fz_esc;

static uint16_t rd16(const uint8_t *p)
{
    return (uint16_t)(p[0] | (p[1] << 8));
}

static bool in(uint32_t a, uint32_t lo, uint32_t hi)
{
    return a >= lo && a <= hi;
}

/* Bytes a master frame may change: those it may write, and those the ESC changes because of
 * its accesses (events, SM status, EEPROM status and data, watchdog status and counters, error
 * counters, DC times). Everything else (device information, alias, DL status, AL status and code,
 * PDI control and configuration, AL event mask, SM PDI control, reserved areas) must stay. */
static bool master_may_change(const co_esc *e, uint32_t a)
{
    if (a >= CO_ESC_REG_SIZE || a >= 0x0F80u) {
        return true; /* process RAM, user RAM */
    }
    if (in(a, 0x0600, 0x06FF)) {
        return a < CO_ESC_REG_FMMU(e->fmmu_count);
    }
    if (in(a, 0x0800, 0x087F)) {
        return a < CO_ESC_REG_SM(e->sm_count) && (a - 0x0800u) % 8u != 7u;
    }
    if (in(a, 0x0900, 0x09FF)) {
        return e->dc;
    }
    /* The EEPROM reload command loads alias, PDI control and configuration from the SII again. */
    return in(a, 0x0010, 0x0013) || in(a, 0x0100, 0x0103) || in(a, 0x0108, 0x0109) ||
           in(a, 0x0140, 0x0141) || in(a, 0x0150, 0x0153) || in(a, 0x0120, 0x0121) || in(a, 0x0200, 0x0201) || in(a, 0x0210, 0x0211) ||
           in(a, 0x0220, 0x0223) || in(a, 0x0300, 0x0313) || in(a, 0x0400, 0x0401) ||
           in(a, 0x0410, 0x0411) || in(a, 0x0420, 0x0421) || in(a, 0x0440, 0x0443) ||
           in(a, 0x0500, 0x050F);
}

/* Registers only the master writes: the PDI must not change them. */
static bool master_only(const co_esc *e, uint32_t a)
{
    if (in(a, 0x0600, 0x06FF)) {
        return true;
    }
    if (in(a, 0x0800, 0x087F)) {
        uint32_t b = (a - 0x0800u) % 8u;
        return b <= 4u || b == 6u;
    }
    if (in(a, 0x0900, 0x09FF)) {
        return e->dc;
    }
    return in(a, 0x0010, 0x0011) || in(a, 0x0100, 0x0103) || in(a, 0x0120, 0x0121) ||
           in(a, 0x0200, 0x0201) || in(a, 0x0400, 0x0421) || in(a, 0x0500, 0x050F) ||
           in(a, 0x0000, 0x000F);
}

/* The local copy of the system time (0x0910-0x0917, with DC), which the ESC refreshes whenever
 * it is read, from either side, to its clock plus the system time offset (0x0920): a PDI read may
 * change it, to that value only. */
static bool systime_refreshed(const co_esc *e, uint32_t a)
{
    if (!e->dc || !in(a, 0x0910, 0x0917)) {
        return false;
    }
    uint64_t t = 0, offset = 0;
    for (unsigned i = 0; i < 8u; i++) {
        t |= (uint64_t)e->mem[0x0910u + i] << (8u * i);
        offset |= (uint64_t)e->mem[0x0920u + i] << (8u * i);
    }
    return t == e->now + offset;
}

#define CHECK_BLOCK 256u /* bytes of ESC memory compared at once by check_mem */

static void check_mem(const fz_esc *z, bool master)
{
    for (unsigned k = 0; k < z->n; k++) {
        const co_esc *e = &z->esc[k];
        if (memcmp(e->mem, z->before[k], CO_ESC_MEM_SIZE) == 0) {
            continue; /* the common case, without a traced compare per byte */
        }
        /* A frame or PDI access changes a few bytes of the whole memory: only the blocks that
         * differ are compared byte by byte (this file has libFuzzer's comparison tracing, and a
         * traced compare per byte of every ESC's memory took 60 % of the target's time). */
        for (uint32_t block = 0; block < CO_ESC_MEM_SIZE; block += CHECK_BLOCK) {
            uint32_t end = CO_ESC_MEM_SIZE - block < CHECK_BLOCK ? CO_ESC_MEM_SIZE
                                                                 : block + CHECK_BLOCK;
            if (memcmp(e->mem + block, z->before[k] + block, end - block) == 0) {
                continue;
            }
            for (uint32_t a = block; a < end; a++) {
                if (e->mem[a] == z->before[k][a]) {
                    continue;
                }
                if (master ? !master_may_change(e, a)
                           : master_only(e, a) && !systime_refreshed(e, a)) {
                    FAIL("%s changed 0x%04X of slave %u: 0x%02X -> 0x%02X",
                         master ? "a frame" : "the PDI", (unsigned)a, k, z->before[k][a],
                         e->mem[a]);
                }
            }
        }
    }
}

/* Invariant 4 on a processed frame: only ADP, IRQ, data, WKC and the source MAC bit move. */
static void check_frame(const fz_esc *z, size_t len, int rc)
{
    const uint8_t *a = z->frame_in, *b = z->frame;
    size_t off = 16;
    bool more;
    if (rc != CO_ESC_FRAME_OK) {
        if (memcmp(a, b, len) != 0) {
            FAIL("a rejected frame (%d) was changed", rc);
        }
        return;
    }
    if (memcmp(a, b, 6) != 0 || memcmp(a + 7, b + 7, 9) != 0 || (a[6] | 0x02u) != b[6]) {
        FAIL("Ethernet/EtherCAT header changed");
    }
    do {
        uint16_t dlen = rd16(a + off + 6) & 0x7FFu;
        uint8_t cmd = a[off];
        uint16_t wa = rd16(a + off + 10 + dlen), wb = rd16(b + off + 10 + dlen);
        uint16_t adp_a = rd16(a + off + 2), adp_b = rd16(b + off + 2);
        bool increments = cmd == 1 || cmd == 2 || cmd == 3 || cmd == 7 || cmd == 8 || cmd == 9 ||
                          cmd == 13;
        more = (a[off + 7] & 0x80u) != 0;
        if (a[off] != b[off] || a[off + 1] != b[off + 1] || memcmp(a + off + 4, b + off + 4, 4) != 0 ||
            (cmd <= 14 && !(cmd >= 10 && cmd <= 12) &&
             adp_b != (uint16_t)(adp_a + (increments ? z->n : 0u))) ||
            ((cmd > 14 || (cmd >= 10 && cmd <= 12)) && adp_a != adp_b)) {
            FAIL("datagram header at %zu changed", off);
        }
        if ((rd16(a + off + 8) & ~rd16(b + off + 8)) != 0) {
            FAIL("IRQ bits cleared");
        }
        if ((uint16_t)(wb - wa) > 3u * z->n) {
            FAIL("WKC 0x%04X -> 0x%04X", wa, wb);
        }
        if ((cmd == 0 || cmd > 14) && (memcmp(a + off, b + off, 12u + dlen) != 0)) {
            FAIL("NOP or unknown command changed");
        }
        off += 12u + dlen;
    } while (more);
}

static size_t canned_frame(fz_esc *z, uint8_t which)
{
    uint8_t *f = z->frame;
    memset(f, 0, 16 + 12 + 128);
    memset(f, 0xFF, 6);
    f[12] = 0x88;
    f[13] = 0xA4;
    f[15] = 0x10;
    if ((which & 3u) == 2u) { /* APWR AL control */
        f[14] = 14;
        f[16] = 2;
        f[20] = 0x20;
        f[21] = 0x01;
        f[22] = 2;
        f[26] = (uint8_t)(which >> 2);
        return 60;
    }
    if ((which & 3u) == 3u) { /* APRD of the 128-byte SM1 mailbox */
        f[14] = 12 + 128;
        f[16] = 1;
        f[20] = 0x80;
        f[21] = 0x10;
        f[22] = 128;
        return 16 + 12 + 128;
    }
    if (which & 1u) { /* LRW of 8 bytes at logical 0 */
        f[14] = 20;
        f[16] = 12;
        f[22] = 8;
        return 36;
    }
    f[14] = 12 + 16; /* FPWR of 16 bytes to the first mailbox */
    f[16] = 5;
    f[18] = 0x01;
    f[19] = 0x10;
    f[20] = 0x00;
    f[21] = 0x10;
    f[22] = 16;
    return 44;
}

#if FUZZ_ECAT_SLAVE
static bool drop_frame(void *ctx, const co_frame *frame)
{
    (void)ctx;
    (void)frame;
    return true;
}

static void app_start(fz_esc *z)
{
    co_node_config nc = co_node_default_config();
    co_ecat_slave_config sc = co_ecat_slave_default_config();
    const co_drive_desc *desc = co_drive_registry_find("vf-mb1-ecat");
    if (desc == NULL || desc->od->value_size > sizeof z->values) {
        FAIL("no vf-mb1-ecat drive");
    }
    nc.node_id = 1;
    nc.values = z->values;
    nc.driver.send = drop_frame;
    if (!co_drive_init(&z->drive, desc, &nc)) {
        FAIL("drive init");
    }
    co_drive_start(&z->drive, 0);
    sc.esc = &z->esc[0];
    sc.node = &z->drive.node;
    sc.drive = &z->drive;
    sc.al_state_index = 0x4400;
#if !defined(CO_OD_NO_NAMES)
    /* SDO information with the EDS names: any index and sub-index a frame asks about */
    sc.entry_names = co_od_vf_mb1_ecat_entry_names;
    sc.sub_names = co_od_vf_mb1_ecat_sub_names;
#endif
    if (!co_ecat_slave_init(&z->slave, &sc, 0)) {
        FAIL("slave init");
    }
}

/* Invariants 5-7 around one co_ecat_slave_process. */
static void app_run(fz_esc *z)
{
    const co_ecat_slave *s = &z->slave;
    const uint8_t *m = z->esc[0].mem;
    for (unsigned k = 0; k < z->n; k++) {
        memcpy(z->before[k], z->esc[k].mem, CO_ESC_MEM_SIZE);
    }
    (void)co_ecat_slave_process(&z->slave, z->now);
    check_mem(z, false);
    uint8_t st = m[CO_ESC_REG_ALSTAT];
    uint16_t code = rd16(m + CO_ESC_REG_ALSTATCODE);
    uint8_t state = st & CO_ECAT_STATE_MASK;
    if ((state != 1u && state != 2u && state != 4u && state != 8u) || (st & 0xE0u) != 0u ||
        ((st & CO_ECAT_AL_ERROR) != 0u) != (code != 0u)) {
        FAIL("AL status 0x%02X code 0x%04X", st, code);
    }
    if (co_ecat_slave_state(s) != state || co_ecat_slave_error(s) != ((st & 0x10u) != 0u)) {
        FAIL("slave state 0x%02X, register 0x%02X", s->state, st);
    }
    co_nmt_state want = state == 8u ? CO_NMT_OPERATIONAL
                        : state == 1u ? CO_NMT_STOPPED : CO_NMT_PRE_OPERATIONAL;
    if (z->drive.node.nmt_state != want) {
        FAIL("NMT state 0x%02X in ESM state %u", z->drive.node.nmt_state, state);
    }
}
#endif

/* The fuzzer's own PDI operations reach an ESC whose PDI the application layer does not own
 * (two PDI users on one ESC would only test the fuzzer against itself). */
static bool pdi_free(const fz_esc *z, uint8_t op)
{
#if FUZZ_ECAT_SLAVE
    return !z->app || (op >> 7 & (z->n - 1u)) != 0u;
#else
    (void)z;
    (void)op;
    return true;
#endif
}

static void preconfigure(co_esc *e, uint16_t station)
{
    /* As SOEM leaves one slave before OP: station address, SM0-3, FMMU0/1. */
    static const uint8_t sm[32] = {0x00, 0x10, 0x80, 0, 0x26, 0, 1, 0, 0x80, 0x10, 0x80, 0, 0x22, 0, 1, 0,
                                   0x00, 0x11, 4, 0, 0x64, 0, 1, 0, 0x80, 0x11, 4, 0, 0x20, 0, 1, 0};
    static const uint8_t fmmu[32] = {0, 0, 0, 0, 4, 0, 0, 7, 0x00, 0x11, 0, 2, 1, 0, 0, 0,
                                     4, 0, 0, 0, 4, 0, 0, 7, 0x80, 0x11, 0, 1, 1, 0, 0, 0};
    uint8_t f[16 + 12 + 32];
    memset(f, 0, sizeof f);
    f[12] = 0x88;
    f[13] = 0xA4;
    f[15] = 0x10;
    f[22] = 2;
    f[14] = 14;
    f[16] = 8; /* BWR station address (a fresh ESC; the chain's second is set below) */
    f[20] = 0x10;
    f[26] = (uint8_t)station;
    f[27] = (uint8_t)(station >> 8);
    co_esc_process_frame(e, f, 30, 0);
    for (unsigned k = 0; k < 2; k++) {
        memset(f + 16, 0, sizeof f - 16);
        f[14] = 12 + 32;
        f[16] = 5; /* FPWR */
        f[18] = (uint8_t)station;
        f[19] = (uint8_t)(station >> 8);
        f[21] = k == 0 ? 0x08 : 0x06;
        f[22] = 32;
        memcpy(f + 26, k == 0 ? sm : fmmu, 32);
        co_esc_process_frame(e, f, sizeof f, 0);
    }
}

/* The set-up (byte 0's six bits) builds the ESCs and, with bit 5, starts a drive: most of an
 * input's time when done for every input. The state it leaves is kept per set-up and the next
 * input with that set-up starts from a copy (fz_esc lives at one address, so its pointers into
 * itself stay valid). FZ_CHECK_SNAPSHOT=1 builds anyway and compares the copy with the fresh
 * build; FZ_NO_SNAPSHOT=1 always builds. */
#define SETUP_BITS 0x3Fu

typedef struct fz_esc_state {
    co_esc esc[2];
    co_esc *chain[2];
    unsigned n;
    uint8_t sii[256];
#if FUZZ_ECAT_SLAVE
    bool app;
    co_drive drive;
    co_ecat_slave slave;
    uint8_t values[8192];
#endif
} fz_esc_state;

static void state_copy(fz_esc_state *to, const fz_esc *z)
{
    memcpy(to->esc, z->esc, sizeof to->esc);
    memcpy(to->chain, z->chain, sizeof to->chain);
    to->n = z->n;
    memcpy(to->sii, z->sii, sizeof to->sii);
#if FUZZ_ECAT_SLAVE
    to->app = z->app;
    memcpy(&to->drive, &z->drive, sizeof to->drive);
    memcpy(&to->slave, &z->slave, sizeof to->slave);
    memcpy(to->values, z->values, sizeof to->values);
#endif
}

static void state_restore(fz_esc *z, const fz_esc_state *from)
{
    memcpy(z->esc, from->esc, sizeof z->esc);
    memcpy(z->chain, from->chain, sizeof z->chain);
    z->n = from->n;
    memcpy(z->sii, from->sii, sizeof z->sii);
#if FUZZ_ECAT_SLAVE
    z->app = from->app;
    memcpy(&z->drive, &from->drive, sizeof z->drive);
    memcpy(&z->slave, &from->slave, sizeof z->slave);
    memcpy(z->values, from->values, sizeof z->values);
#endif
    z->now = 0;
}

/* FZ_CHECK_SNAPSHOT: the kept state against a fresh build: the chain, the SII, every ESC's
 * memory, and with the application layer the drive's values, its NMT state and the slave's
 * state. */
static void state_compare(const fz_esc_state *kept, const fz_esc *z)
{
    if (kept->n != z->n || memcmp(kept->sii, z->sii, sizeof z->sii) != 0) {
        FAIL("a snapshot of the set-up differs from a fresh build: chain or SII");
    }
    for (unsigned k = 0; k < z->n; k++) {
        if (memcmp(kept->esc[k].mem, z->esc[k].mem, CO_ESC_MEM_SIZE) != 0) {
            FAIL("a snapshot of the set-up differs from a fresh build: ESC %u memory", k);
        }
    }
#if FUZZ_ECAT_SLAVE
    if (kept->app != z->app ||
        (z->app && (memcmp(kept->values, z->values, sizeof z->values) != 0 ||
                    kept->drive.node.nmt_state != z->drive.node.nmt_state ||
                    kept->slave.state != z->slave.state))) {
        FAIL("a snapshot of the set-up differs from a fresh build: drive or slave");
    }
#endif
}

static void set_up(fz_esc *z, uint8_t setup)
{
    co_esc_config cfg = co_esc_default_config();
    memset(&z->sii, 0xFF, sizeof z->sii);
    memset(z->sii, 0, 64);
    z->sii[8] = 0x34; /* alias */
    if (setup & 16u) { /* a right checksum (CRC-8 0x07, initial 0xFF, words 0-6) */
        uint8_t crc = 0xFF;
        for (unsigned i = 0; i < 14; i++) {
            crc ^= z->sii[i];
            for (unsigned b = 0; b < 8; b++) {
                crc = (uint8_t)((crc & 0x80u) ? ((unsigned)crc << 1) ^ 0x07u : (unsigned)crc << 1);
            }
        }
        z->sii[14] = crc;
    }
    cfg.sii = z->sii;
    cfg.sii_size = sizeof z->sii;
    cfg.dc = (setup & 2u) != 0;
    cfg.eeprom_read8 = (setup & 4u) != 0;
    z->n = (setup & 1u) ? 2u : 1u;
    cfg.open_ports = z->n == 2 ? 0x03 : 0x01;
    for (unsigned k = 0; k < z->n; k++) {
        if (co_esc_init(&z->esc[k], &cfg) != 0) {
            FAIL("init");
        }
        if (setup & 8u) {
            preconfigure(&z->esc[k], (uint16_t)(0x1001u + k));
        }
        z->chain[k] = &z->esc[k];
        cfg.open_ports = 0x01; /* the last slave of the line */
    }
    z->now = 0;
#if FUZZ_ECAT_SLAVE
    z->app = (setup & 32u) != 0;
    if (z->app) {
        app_start(z);
    }
#endif
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static fz_esc z; /* 2 x 8 KiB images and copies: kept off the stack */
    static fz_esc_state snaps[SETUP_BITS + 1u];
    static bool taken[SETUP_BITS + 1u];
    static int mode = -1; /* 0 no snapshots, 1 snapshots, 2 checked */
    size_t pos = 1;

    if (size < 1) {
        return 0;
    }
    if (mode < 0) {
        mode = getenv("FZ_CHECK_SNAPSHOT") != NULL ? 2 : getenv("FZ_NO_SNAPSHOT") != NULL ? 0 : 1;
    }
    uint8_t setup = data[0] & SETUP_BITS;
    if (mode == 0 || !taken[setup]) {
        set_up(&z, setup);
        if (mode != 0) {
            state_copy(&snaps[setup], &z);
            taken[setup] = true;
        }
    } else {
        if (mode == 2) {
            set_up(&z, setup);
            state_compare(&snaps[setup], &z);
        }
        state_restore(&z, &snaps[setup]);
    }
    while (pos + 3 <= size) {
        uint8_t op = data[pos];
        size_t len = rd16(data + pos + 1);
        const uint8_t *p = data + pos + 3;
        size_t avail = size - pos - 3;
        if (len > avail) {
            len = avail;
        }
        pos += 3 + len;
        for (unsigned k = 0; k < z.n; k++) {
            memcpy(z.before[k], z.esc[k].mem, CO_ESC_MEM_SIZE);
        }
        switch (op % 4u) {
        case 0: {
            size_t flen = len;
            int rc;
            if (len == 0) {
                flen = canned_frame(&z, op >> 2);
            } else {
                if (flen > sizeof z.frame) {
                    flen = sizeof z.frame;
                }
                memcpy(z.frame, p, flen);
            }
            memcpy(z.frame_in, z.frame, flen);
            rc = co_esc_chain_process(z.chain, z.n, z.frame, flen, z.now);
            check_frame(&z, flen, rc);
            check_mem(&z, true);
            break;
        }
        case 1:
            if (len >= 2 && pdi_free(&z, op)) {
                uint16_t addr = rd16(p);
                int rc = co_esc_pdi_write(&z.esc[op >> 7 & (z.n - 1u)], addr, p + 2, len - 2);
                if (rc == CO_ESC_PDI_RANGE && (size_t)addr + len - 2 <= CO_ESC_MEM_SIZE) {
                    FAIL("PDI write in range refused");
                }
                check_mem(&z, false);
            }
            break;
        case 2:
            if (len >= 2 && pdi_free(&z, op)) {
                uint8_t buf[CO_ESC_MEM_SIZE];
                co_esc_pdi_read(&z.esc[op >> 7 & (z.n - 1u)], rd16(p), buf, len - 2);
                check_mem(&z, false);
            }
            break;
        default: {
            uint32_t step = 0;
            for (size_t i = 0; i < len && i < 4; i++) {
                step |= (uint32_t)p[i] << (8u * i);
            }
            z.now += step;
            for (unsigned k = 0; k < z.n; k++) {
                co_esc_tick(&z.esc[k], z.now);
            }
            break;
        }
        }
#if FUZZ_ECAT_SLAVE
        if (z.app) {
            app_run(&z);
        }
#endif
    }
    return 0;
}
