/* The emulated EtherCAT Slave Controller (ecat/): every command's data and working counter,
 * auto-increment and configured addressing, a chain of two, FMMU mapping onto buffered SMs,
 * mailbox handshakes both ways, the SII EEPROM interface, AL control events, the SM watchdog on
 * the virtual clock, distributed clocks, and malformed frames that must change nothing. */
#include <string.h>

#include "canopen/ecat/esc.h"
#include "ecat_frame.h"
#include "unity.h"

/* ---- frames: tests/unit/support/ecat_frame.h, kept cleared for exact checks ---- */

static void tf_init(ecat_frame *f)
{
    memset(f, 0, sizeof *f);
    ecat_frame_start(f);
}

static uint16_t tf_adp(const ecat_frame *f, size_t dg)
{
    return (uint16_t)(f->b[dg + 2] | (f->b[dg + 3] << 8));
}

/* ---- the slave under test ---- */

#define STATION 0x1001u

static co_esc esc;
static co_esc esc2;
static uint64_t now;
static uint8_t sii[128];

static uint8_t crc8(const uint8_t *p, size_t n)
{
    uint8_t crc = 0xFF;
    for (size_t i = 0; i < n; i++) {
        crc ^= p[i];
        for (int b = 0; b < 8; b++) {
            crc = (uint8_t)((crc & 0x80u) ? ((unsigned)crc << 1) ^ 0x07u : (unsigned)crc << 1);
        }
    }
    return crc;
}

/* A small SII image: PDI control 0x05 / ESC configuration 0x00, alias 0x0077, vendor 0x284,
 * product 0xE1, and word 0x40.. = 0x0A0B, 0x0C0D, then 0xFFFF. */
static void make_sii(void)
{
    memset(sii, 0, sizeof sii);
    sii[0] = 0x05;
    sii[8] = 0x77;
    sii[14] = crc8(sii, 14);
    sii[16] = 0x84;
    sii[17] = 0x02;
    sii[20] = 0xE1;
    sii[0x80 - 4] = 0x0B; /* word 0x3E */
    sii[0x80 - 3] = 0x0A;
    sii[0x80 - 2] = 0x0D;
    sii[0x80 - 1] = 0x0C;
}

static int run(co_esc *e, ecat_frame *f)
{
    return co_esc_process_frame(e, f->b, f->len, now);
}

/* One datagram in a frame of its own; returns its WKC, data copied to out if given. */
static uint16_t one(co_esc *e, uint8_t cmd, uint16_t adp, uint16_t ado, const void *data,
                    uint16_t len, void *out)
{
    ecat_frame f;
    tf_init(&f);
    size_t dg = ecat_frame_add(&f, cmd, adp, ado, data, len);
    TEST_ASSERT_EQUAL_INT(CO_ESC_FRAME_OK, run(e, &f));
    if (out != NULL) {
        memcpy(out, ecat_frame_data(&f, dg), len);
    }
    return ecat_frame_wkc(&f, dg);
}

static uint16_t reg16(co_esc *e, uint16_t addr)
{
    uint8_t b[2];
    TEST_ASSERT_EQUAL_INT(CO_ESC_PDI_OK, co_esc_pdi_read(e, addr, b, 2));
    return (uint16_t)(b[0] | (b[1] << 8));
}

static void set_station(co_esc *e, uint16_t adp, uint16_t station)
{
    uint8_t v[2] = {(uint8_t)station, (uint8_t)(station >> 8)};
    TEST_ASSERT_EQUAL_UINT16(1, one(e, APWR, adp, 0x0010, v, 2, NULL));
}

static void fpwr_ok(uint16_t ado, const void *data, uint16_t len)
{
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPWR, STATION, ado, data, len, NULL));
}

/* SM n: start, length, control, enabled. */
static void config_sm(unsigned n, uint16_t start, uint16_t len, uint8_t ctrl)
{
    uint8_t r[8] = {(uint8_t)start, (uint8_t)(start >> 8), (uint8_t)len, (uint8_t)(len >> 8),
                    ctrl, 0, 1, 0};
    fpwr_ok((uint16_t)(0x0800u + 8u * n), r, 8);
}

static void config_fmmu(unsigned n, uint32_t log, uint16_t len, uint16_t phys, uint8_t type)
{
    uint8_t r[16] = {(uint8_t)log, (uint8_t)(log >> 8), (uint8_t)(log >> 16), (uint8_t)(log >> 24),
                     (uint8_t)len, (uint8_t)(len >> 8), 0, 7, (uint8_t)phys,
                     (uint8_t)(phys >> 8), 0, type, 1, 0, 0, 0};
    fpwr_ok((uint16_t)(0x0600u + 16u * n), r, 16);
}

/* SOEM's layout for one slave with 4 output and 4 input bytes. */
static void config_process_data(void)
{
    config_sm(2, 0x1100, 4, 0x64); /* buffered, master writes, AL event, watchdog trigger */
    config_sm(3, 0x1180, 4, 0x20); /* buffered, master reads, AL event */
    config_fmmu(0, 0, 4, 0x1100, 2);
    config_fmmu(1, 4, 4, 0x1180, 1);
}

static void config_mailboxes(void)
{
    config_sm(0, 0x1000, 128, 0x26);
    config_sm(1, 0x1080, 128, 0x22);
}

void setUp(void)
{
    co_esc_config cfg = co_esc_default_config();
    make_sii();
    cfg.sii = sii;
    cfg.sii_size = sizeof sii;
    now = 1000;
    TEST_ASSERT_EQUAL_INT(0, co_esc_init(&esc, &cfg));
    TEST_ASSERT_EQUAL_INT(0, co_esc_init(&esc2, &cfg));
    set_station(&esc, 0, STATION);
}

void tearDown(void) {}

/* ---- tests ---- */

static void test_init_registers(void)
{
    co_esc_config bad = co_esc_default_config();
    TEST_ASSERT_EQUAL_HEX16(0x0011, reg16(&esc, 0x0000)); /* ET1100, revision 0 */
    TEST_ASSERT_EQUAL_HEX16(0x0808, reg16(&esc, 0x0004)); /* 8 FMMUs, 8 SMs */
    TEST_ASSERT_EQUAL_HEX16(0x0F04, reg16(&esc, 0x0006)); /* 4 KiB, ports 0/1 MII */
    TEST_ASSERT_EQUAL_HEX16(0x0001, reg16(&esc, 0x0008)); /* byte FMMUs, no DC */
    /* EEPROM loaded, PDI watchdog ok, port 0 link + communication, ports 1-3 loops closed. */
    TEST_ASSERT_EQUAL_HEX16(0x5613, reg16(&esc, 0x0110));
    TEST_ASSERT_EQUAL_HEX16(0x0077, reg16(&esc, 0x0012));
    TEST_ASSERT_EQUAL_HEX16(0x0005, reg16(&esc, 0x0140));
    TEST_ASSERT_EQUAL_HEX16(0x0001, reg16(&esc, 0x0130));
    TEST_ASSERT_EQUAL_UINT16(2498, reg16(&esc, 0x0400));
    TEST_ASSERT_EQUAL_UINT16(1000, reg16(&esc, 0x0420));
    TEST_ASSERT_EQUAL_HEX16(0x0001, reg16(&esc, 0x0440));
    TEST_ASSERT_EQUAL_HEX16(0x0000, reg16(&esc, 0x0502));
    bad.fmmu_count = 0;
    TEST_ASSERT_EQUAL_INT(-1, co_esc_init(&esc2, &bad));
    bad.fmmu_count = 9;
    TEST_ASSERT_EQUAL_INT(-1, co_esc_init(&esc2, &bad));
}

static void test_auto_increment_commands(void)
{
    ecat_frame f;
    uint8_t v[2] = {0xAA, 0xBB};
    tf_init(&f);
    size_t rd = ecat_frame_add(&f, APRD, 0, 0x0000, NULL, 2);
    size_t other = ecat_frame_add(&f, APRD, 0xFFFF, 0x0000, NULL, 2); /* the second slave */
    size_t wr = ecat_frame_add(&f, APWR, 0, 0x0F80, v, 2);
    size_t rw = ecat_frame_add(&f, APRW, 0, 0x0F80, (const uint8_t[]){0x11, 0x22}, 2);
    TEST_ASSERT_EQUAL_INT(CO_ESC_FRAME_OK, run(&esc, &f));
    TEST_ASSERT_EQUAL_HEX8(0x11, ecat_frame_data(&f, rd)[0]);
    TEST_ASSERT_EQUAL_UINT16(1, ecat_frame_wkc(&f, rd));
    TEST_ASSERT_EQUAL_HEX16(0x0001, tf_adp(&f, rd)); /* every slave increments ADP */
    TEST_ASSERT_EQUAL_UINT16(0, ecat_frame_wkc(&f, other));
    TEST_ASSERT_EQUAL_HEX16(0x0000, tf_adp(&f, other));
    TEST_ASSERT_EQUAL_HEX8(0x00, ecat_frame_data(&f, other)[0]);
    TEST_ASSERT_EQUAL_UINT16(1, ecat_frame_wkc(&f, wr));
    /* APRW: the old memory into the frame, the received data into memory, WKC 1 + 2. */
    TEST_ASSERT_EQUAL_UINT16(3, ecat_frame_wkc(&f, rw));
    TEST_ASSERT_EQUAL_HEX8(0xAA, ecat_frame_data(&f, rw)[0]);
    TEST_ASSERT_EQUAL_HEX8(0xBB, ecat_frame_data(&f, rw)[1]);
    TEST_ASSERT_EQUAL_HEX16(0x2211, reg16(&esc, 0x0F80));
    TEST_ASSERT_EQUAL_HEX8(0x03, f.b[6]); /* source MAC marked by the ESC */
}

static void test_configured_address_and_alias(void)
{
    uint8_t b[2];
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPRD, STATION, 0x0010, NULL, 2, b));
    TEST_ASSERT_EQUAL_HEX8(0x01, b[0]);
    TEST_ASSERT_EQUAL_HEX8(0x10, b[1]);
    TEST_ASSERT_EQUAL_UINT16(0, one(&esc, FPRD, 0x1002, 0x0010, NULL, 2, NULL));
    /* The alias (0x0077 from the SII) answers only with DL control bit 24 set. */
    TEST_ASSERT_EQUAL_UINT16(0, one(&esc, FPRD, 0x0077, 0x0010, NULL, 2, NULL));
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPWR, STATION, 0x0103, (const uint8_t[]){1}, 1, NULL));
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPRD, 0x0077, 0x0010, NULL, 2, NULL));
    /* FPRW: read +1, write +2; ADP is not changed by configured addressing. */
    ecat_frame f;
    tf_init(&f);
    size_t dg = ecat_frame_add(&f, FPRW, STATION, 0x0F90, (const uint8_t[]){7}, 1);
    run(&esc, &f);
    TEST_ASSERT_EQUAL_UINT16(3, ecat_frame_wkc(&f, dg));
    TEST_ASSERT_EQUAL_HEX16(STATION, tf_adp(&f, dg));
}

static void test_broadcast_commands(void)
{
    ecat_frame f;
    uint8_t or_in[2] = {0x40, 0x00};
    tf_init(&f);
    size_t brd = ecat_frame_add(&f, BRD, 0, 0x0000, or_in, 2);
    size_t bwr = ecat_frame_add(&f, BWR, 0, 0x0F82, (const uint8_t[]){0x5A}, 1);
    size_t brw = ecat_frame_add(&f, BRW, 0, 0x0F82, (const uint8_t[]){0x01}, 1);
    TEST_ASSERT_EQUAL_INT(CO_ESC_FRAME_OK, run(&esc, &f));
    TEST_ASSERT_EQUAL_HEX8(0x51, ecat_frame_data(&f, brd)[0]); /* 0x40 | type 0x11 */
    TEST_ASSERT_EQUAL_UINT16(1, ecat_frame_wkc(&f, brd));
    TEST_ASSERT_EQUAL_HEX16(1, tf_adp(&f, brd));
    TEST_ASSERT_EQUAL_UINT16(1, ecat_frame_wkc(&f, bwr));
    TEST_ASSERT_EQUAL_UINT16(3, ecat_frame_wkc(&f, brw));
    TEST_ASSERT_EQUAL_HEX8(0x5B, ecat_frame_data(&f, brw)[0]); /* 0x01 | old 0x5A */
    TEST_ASSERT_EQUAL_HEX8(0x01, esc.mem[0x0F82]);
}

static void test_read_multiple_write(void)
{
    uint8_t b[1] = {0x33};
    esc.mem[0x0F84] = 0x99;
    /* ARMW: the slave with ADP 0 reads, the others write. */
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, ARMW, 0, 0x0F84, b, 1, b));
    TEST_ASSERT_EQUAL_HEX8(0x99, b[0]);
    b[0] = 0x44;
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, ARMW, 0xFFFF, 0x0F84, b, 1, NULL));
    TEST_ASSERT_EQUAL_HEX8(0x44, esc.mem[0x0F84]);
    /* FRMW: the addressed slave reads, the others write. */
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FRMW, STATION, 0x0F84, b, 1, b));
    TEST_ASSERT_EQUAL_HEX8(0x44, b[0]);
    b[0] = 0x55;
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FRMW, 0x2000, 0x0F84, b, 1, NULL));
    TEST_ASSERT_EQUAL_HEX8(0x55, esc.mem[0x0F84]);
}

static void test_nop_and_unknown_command_pass_untouched(void)
{
    ecat_frame f, before;
    tf_init(&f);
    size_t nop = ecat_frame_add(&f, NOP, 0, 0x0000, (const uint8_t[]){9, 9}, 2);
    size_t unk = ecat_frame_add(&f, 15, 0, 0x0000, (const uint8_t[]){8, 8}, 2);
    size_t rd = ecat_frame_add(&f, APRD, 0, 0x0000, NULL, 1);
    before = f;
    co_esc copy = esc;
    TEST_ASSERT_EQUAL_INT(CO_ESC_FRAME_OK, run(&esc, &f));
    TEST_ASSERT_EQUAL_MEMORY(&before.b[nop], &f.b[nop], unk + 14 - nop);
    TEST_ASSERT_EQUAL_UINT16(1, ecat_frame_wkc(&f, rd));
    TEST_ASSERT_EQUAL_MEMORY(copy.mem, esc.mem, sizeof esc.mem);
    TEST_ASSERT_EQUAL_UINT32(1, esc.stats.unknown_cmds);
}

static void test_write_protection(void)
{
    uint8_t v[2] = {0x08, 0x00};
    /* AL status is the application's: a master write is acknowledged and changes nothing. */
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPWR, STATION, 0x0130, v, 2, NULL));
    TEST_ASSERT_EQUAL_HEX16(0x0001, reg16(&esc, 0x0130));
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPWR, STATION, 0x0000, v, 2, NULL));
    TEST_ASSERT_EQUAL_HEX16(0x0011, reg16(&esc, 0x0000));
    /* AL control is the master's: the PDI cannot change it. */
    TEST_ASSERT_EQUAL_INT(CO_ESC_PDI_OK, co_esc_pdi_write(&esc, 0x0120, v, 2));
    TEST_ASSERT_EQUAL_HEX16(0x0000, reg16(&esc, 0x0120));
    TEST_ASSERT_EQUAL_INT(CO_ESC_PDI_OK, co_esc_pdi_write(&esc, 0x0010, v, 2));
    TEST_ASSERT_EQUAL_HEX16(STATION, reg16(&esc, 0x0010));
    /* SM start/length/control cannot change while the SM is enabled. */
    config_sm(2, 0x1100, 4, 0x64);
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPWR, STATION, 0x0810, (const uint8_t[]){0x00, 0x12}, 2,
                                    NULL));
    TEST_ASSERT_EQUAL_HEX16(0x1100, reg16(&esc, 0x0810));
    /* Error counters are cleared by any write. */
    esc.mem[0x0300] = 5;
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, BWR, 0, 0x0300, (const uint8_t[]){7}, 1, NULL));
    TEST_ASSERT_EQUAL_HEX8(0, esc.mem[0x0300]);
    /* Outside the image: nothing accessed. */
    TEST_ASSERT_EQUAL_UINT16(0, one(&esc, FPRD, STATION, 0x2000, NULL, 4, NULL));
    TEST_ASSERT_EQUAL_INT(CO_ESC_PDI_RANGE, co_esc_pdi_read(&esc, 0x1FFF, v, 2));
}

static void test_chain_of_two(void)
{
    co_esc *chain[2] = {&esc, &esc2};
    ecat_frame f;
    uint8_t b[2];
    /* esc already has 0x1001; a fresh chain: station addresses by auto-increment. */
    tf_init(&f);
    size_t first = ecat_frame_add(&f, APWR, 0, 0x0010, (const uint8_t[]){0x01, 0x10}, 2);
    size_t second = ecat_frame_add(&f, APWR, 0xFFFF, 0x0010, (const uint8_t[]){0x02, 0x10}, 2);
    size_t count = ecat_frame_add(&f, BRD, 0, 0x0000, NULL, 2);
    TEST_ASSERT_EQUAL_INT(CO_ESC_FRAME_OK, co_esc_chain_process(chain, 2, f.b, f.len, now));
    TEST_ASSERT_EQUAL_UINT16(1, ecat_frame_wkc(&f, first));
    TEST_ASSERT_EQUAL_UINT16(1, ecat_frame_wkc(&f, second));
    TEST_ASSERT_EQUAL_HEX16(2, tf_adp(&f, first));  /* incremented by both */
    TEST_ASSERT_EQUAL_HEX16(1, tf_adp(&f, second)); /* 0xFFFF + 2 */
    TEST_ASSERT_EQUAL_UINT16(2, ecat_frame_wkc(&f, count)); /* SOEM counts the slaves this way */
    TEST_ASSERT_EQUAL_HEX16(0x1002, reg16(&esc2, 0x0010));
    tf_init(&f);
    size_t rd = ecat_frame_add(&f, FPRD, 0x1002, 0x0010, NULL, 2);
    co_esc_chain_process(chain, 2, f.b, f.len, now);
    memcpy(b, ecat_frame_data(&f, rd), 2);
    TEST_ASSERT_EQUAL_UINT16(1, ecat_frame_wkc(&f, rd));
    TEST_ASSERT_EQUAL_HEX8(0x02, b[0]);
}

static void test_lrw_through_fmmus_to_buffered_sms(void)
{
    uint8_t in[4] = {0x37, 0x06, 0xDC, 0x05}, out[4];
    uint8_t pd[8] = {0x0F, 0x00, 0xDC, 0x05, 0xEE, 0xEE, 0xEE, 0xEE};
    ecat_frame f;
    config_process_data();
    TEST_ASSERT_EQUAL_INT(CO_ESC_PDI_OK, co_esc_pdi_write(&esc, 0x1180, in, 4));
    tf_init(&f);
    size_t dg = ecat_frame_add32(&f, LRW, 0, pd, 8);
    TEST_ASSERT_EQUAL_INT(CO_ESC_FRAME_OK, run(&esc, &f));
    TEST_ASSERT_EQUAL_UINT16(3, ecat_frame_wkc(&f, dg)); /* outputs +2, inputs +1 */
    TEST_ASSERT_EQUAL_MEMORY(pd, ecat_frame_data(&f, dg), 4);
    TEST_ASSERT_EQUAL_MEMORY(in, ecat_frame_data(&f, dg) + 4, 4);
    TEST_ASSERT_TRUE(co_esc_al_event(&esc) & CO_ESC_AL_EVENT_SM(2));
    TEST_ASSERT_EQUAL_INT(CO_ESC_PDI_OK, co_esc_pdi_read(&esc, 0x1100, out, 4));
    TEST_ASSERT_EQUAL_MEMORY(pd, out, 4);
    TEST_ASSERT_FALSE(co_esc_al_event(&esc) & CO_ESC_AL_EVENT_SM(2));

    /* Two cycles without a PDI read: the PDI gets the latest complete buffer. */
    pd[0] = 0x06;
    tf_init(&f);
    ecat_frame_add32(&f, LWR, 0, pd, 4);
    run(&esc, &f);
    pd[0] = 0x07;
    tf_init(&f);
    dg = ecat_frame_add32(&f, LWR, 0, pd, 4);
    run(&esc, &f);
    TEST_ASSERT_EQUAL_UINT16(1, ecat_frame_wkc(&f, dg));
    co_esc_pdi_read(&esc, 0x1100, out, 4);
    TEST_ASSERT_EQUAL_HEX8(0x07, out[0]);
    /* A write that stops before the end address publishes nothing. */
    tf_init(&f);
    ecat_frame_add32(&f, LWR, 0, (const uint8_t[]){0x99, 0x99}, 2);
    run(&esc, &f);
    co_esc_pdi_read(&esc, 0x1100, out, 4);
    TEST_ASSERT_EQUAL_HEX8(0x07, out[0]);
    /* LRD: inputs only, WKC 1; a logical range no FMMU maps: WKC 0. */
    tf_init(&f);
    dg = ecat_frame_add32(&f, LRD, 0, NULL, 8);
    size_t none = ecat_frame_add32(&f, LRW, 0x100, NULL, 8);
    run(&esc, &f);
    TEST_ASSERT_EQUAL_UINT16(1, ecat_frame_wkc(&f, dg));
    TEST_ASSERT_EQUAL_MEMORY(in, ecat_frame_data(&f, dg) + 4, 4);
    TEST_ASSERT_EQUAL_UINT16(0, ecat_frame_wkc(&f, none));
    /* The write begun above may go on from where it stopped (several strokes, across frames);
     * once complete, an access must begin at the start address again. */
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPWR, STATION, 0x1102, pd, 2, NULL));
    TEST_ASSERT_EQUAL_UINT16(0, one(&esc, FPWR, STATION, 0x1101, pd, 3, NULL));
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPWR, STATION, 0x1100, pd, 4, NULL));
}

/* The SM an FMMU writes through follows the SM and FMMU registers: the SM disabled and moved
 * under a configured FMMU, a window that starts in plain RAM and ends in the buffer, the FMMU
 * moved onto the buffer. */
static void test_fmmu_follows_sm_reconfiguration(void)
{
    uint8_t pd[8] = {0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88}, out[8];
    ecat_frame f;
    /* the SM, then an FMMU onto its buffer: the buffer handshake runs */
    config_sm(2, 0x1100, 4, 0x64);
    config_fmmu(0, 0, 4, 0x1100, 2);
    tf_init(&f);
    ecat_frame_add32(&f, LWR, 0, pd, 4);
    run(&esc, &f);
    TEST_ASSERT_TRUE(co_esc_al_event(&esc) & CO_ESC_AL_EVENT_SM(2));
    /* SM status: buffer written */
    TEST_ASSERT_TRUE(esc.mem[CO_ESC_REG_SM_STATUS(2)] & CO_ESC_SM_STATUS_IRQ_WRITE);
    TEST_ASSERT_EQUAL_INT(CO_ESC_PDI_OK, co_esc_pdi_read(&esc, 0x1100, out, 4));
    TEST_ASSERT_EQUAL_MEMORY(pd, out, 4);
    /* SM2 disabled: the FMMU writes plain RAM, the SM's status and events stay untouched */
    uint8_t off = 0;
    fpwr_ok((uint16_t)CO_ESC_REG_SM_ACTIVATE(2), &off, 1);
    tf_init(&f);
    size_t dg = ecat_frame_add32(&f, LWR, 0, pd + 4, 4);
    run(&esc, &f);
    TEST_ASSERT_EQUAL_UINT16(1, ecat_frame_wkc(&f, dg));
    TEST_ASSERT_EQUAL_HEX8(0x00, esc.mem[CO_ESC_REG_SM_STATUS(2)]);
    TEST_ASSERT_FALSE(co_esc_al_event(&esc) & CO_ESC_AL_EVENT_SM(2));
    TEST_ASSERT_EQUAL_MEMORY(pd + 4, &esc.mem[0x1100], 4);
    /* SM2 enabled at 0x1102: the FMMU's window 0x1100-0x1103 now starts in plain RAM and ends in
     * the buffer, which the 2 bytes from its start address do not complete */
    config_sm(2, 0x1102, 4, 0x64);
    tf_init(&f);
    dg = ecat_frame_add32(&f, LWR, 0, pd, 4);
    run(&esc, &f);
    TEST_ASSERT_EQUAL_UINT16(1, ecat_frame_wkc(&f, dg));
    TEST_ASSERT_EQUAL_MEMORY(pd, &esc.mem[0x1100], 2);
    TEST_ASSERT_FALSE(co_esc_al_event(&esc) & CO_ESC_AL_EVENT_SM(2));
    /* the FMMU moved onto the whole buffer: complete again */
    config_fmmu(0, 0, 4, 0x1102, 2);
    tf_init(&f);
    ecat_frame_add32(&f, LWR, 0, pd + 4, 4);
    run(&esc, &f);
    TEST_ASSERT_TRUE(co_esc_al_event(&esc) & CO_ESC_AL_EVENT_SM(2));
    TEST_ASSERT_EQUAL_INT(CO_ESC_PDI_OK, co_esc_pdi_read(&esc, 0x1102, out, 4));
    TEST_ASSERT_EQUAL_MEMORY(pd + 4, out, 4);
}

static void test_mailbox_master_to_pdi(void)
{
    uint8_t msg[128], got[128], st;
    config_mailboxes();
    for (unsigned i = 0; i < sizeof msg; i++) {
        msg[i] = (uint8_t)i;
    }
    /* A write that does not begin at the start address is refused. */
    TEST_ASSERT_EQUAL_UINT16(0, one(&esc, FPWR, STATION, 0x1010, msg, 16, NULL));
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPWR, STATION, 0x1000, msg, 128, NULL));
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPRD, STATION, 0x0805, NULL, 1, &st));
    TEST_ASSERT_TRUE(st & CO_ESC_SM_STATUS_MBX_FULL);
    TEST_ASSERT_TRUE(co_esc_al_event(&esc) & CO_ESC_AL_EVENT_SM(0));
    /* Full: a second write (a master retry) is refused. */
    TEST_ASSERT_EQUAL_UINT16(0, one(&esc, FPWR, STATION, 0x1000, msg, 128, NULL));
    /* The PDI reads the header, then the rest: the read of the last byte empties it. */
    TEST_ASSERT_EQUAL_INT(CO_ESC_PDI_OK, co_esc_pdi_read(&esc, 0x1000, got, 6));
    TEST_ASSERT_FALSE(co_esc_al_event(&esc) & CO_ESC_AL_EVENT_SM(0));
    TEST_ASSERT_TRUE(esc.mem[0x0805] & CO_ESC_SM_STATUS_MBX_FULL);
    TEST_ASSERT_EQUAL_INT(CO_ESC_PDI_OK, co_esc_pdi_read(&esc, 0x1006, got + 6, 122));
    TEST_ASSERT_EQUAL_MEMORY(msg, got, 128);
    TEST_ASSERT_FALSE(esc.mem[0x0805] & CO_ESC_SM_STATUS_MBX_FULL);
    TEST_ASSERT_EQUAL_INT(CO_ESC_PDI_BLOCKED, co_esc_pdi_read(&esc, 0x1000, got, 6));
    /* The next message goes in. */
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPWR, STATION, 0x1000, msg, 128, NULL));
}

static void test_mailbox_pdi_to_master(void)
{
    uint8_t msg[128], got[128];
    uint8_t last = 0xFF;
    config_mailboxes();
    memset(msg, 0xA5, sizeof msg);
    /* Empty: the master's read is refused (SOEM polls the status first). */
    TEST_ASSERT_EQUAL_UINT16(0, one(&esc, FPRD, STATION, 0x1080, NULL, 128, NULL));
    /* The PDI writes the message, then the last byte (as SOES does): now full. */
    TEST_ASSERT_EQUAL_INT(CO_ESC_PDI_OK, co_esc_pdi_write(&esc, 0x1080, msg, 16));
    TEST_ASSERT_FALSE(esc.mem[0x080D] & CO_ESC_SM_STATUS_MBX_FULL);
    TEST_ASSERT_EQUAL_INT(CO_ESC_PDI_OK, co_esc_pdi_write(&esc, 0x1080 + 127, &last, 1));
    TEST_ASSERT_TRUE(esc.mem[0x080D] & CO_ESC_SM_STATUS_MBX_FULL);
    TEST_ASSERT_EQUAL_INT(CO_ESC_PDI_BLOCKED, co_esc_pdi_write(&esc, 0x1080, msg, 16));
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPRD, STATION, 0x1080, NULL, 128, got));
    TEST_ASSERT_EQUAL_MEMORY(msg, got, 16);
    TEST_ASSERT_EQUAL_HEX8(0xFF, got[127]);
    TEST_ASSERT_FALSE(esc.mem[0x080D] & CO_ESC_SM_STATUS_MBX_FULL);
    TEST_ASSERT_TRUE(co_esc_al_event(&esc) & CO_ESC_AL_EVENT_SM(1)); /* read: send the next */
    TEST_ASSERT_EQUAL_UINT16(0, one(&esc, FPRD, STATION, 0x1080, NULL, 128, NULL));
    TEST_ASSERT_EQUAL_INT(CO_ESC_PDI_OK, co_esc_pdi_write(&esc, 0x1080, msg, 128));
    TEST_ASSERT_FALSE(co_esc_al_event(&esc) & CO_ESC_AL_EVENT_SM(1));
    TEST_ASSERT_TRUE(esc.mem[0x080D] & CO_ESC_SM_STATUS_MBX_FULL);
    /* The PDI deactivates SM1 (repeat handling): the mailbox is emptied. */
    TEST_ASSERT_EQUAL_INT(CO_ESC_PDI_OK, co_esc_pdi_write(&esc, 0x080F, (const uint8_t[]){1}, 1));
    TEST_ASSERT_FALSE(esc.mem[0x080D] & CO_ESC_SM_STATUS_MBX_FULL);
    TEST_ASSERT_EQUAL_INT(CO_ESC_PDI_OK, co_esc_pdi_write(&esc, 0x080F, (const uint8_t[]){0}, 1));
    TEST_ASSERT_EQUAL_INT(CO_ESC_PDI_OK, co_esc_pdi_write(&esc, 0x1080, msg, 128));
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPRD, STATION, 0x1080, NULL, 128, NULL));
}

static void test_repeat_request_toggle(void)
{
    uint8_t act;
    config_mailboxes();
    co_esc_pdi_read(&esc, 0x080E, &act, 1); /* consumes the SM change event */
    TEST_ASSERT_FALSE(co_esc_al_event(&esc) & CO_ESC_AL_EVENT_SM_CHANGE);
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPWR, STATION, 0x080E, (const uint8_t[]){0x03}, 1, NULL));
    TEST_ASSERT_TRUE(co_esc_al_event(&esc) & CO_ESC_AL_EVENT_SM_CHANGE);
    co_esc_pdi_read(&esc, 0x080E, &act, 1);
    TEST_ASSERT_EQUAL_HEX8(0x03, act);
    TEST_ASSERT_FALSE(co_esc_al_event(&esc) & CO_ESC_AL_EVENT_SM_CHANGE);
    co_esc_pdi_write(&esc, 0x080F, (const uint8_t[]){0x02}, 1); /* repeat acknowledge */
    TEST_ASSERT_EQUAL_HEX8(0x02, esc.mem[0x080F]);
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPRD, STATION, 0x080F, NULL, 1, &act));
    TEST_ASSERT_EQUAL_HEX8(0x02, act);
}

/* SOEM's read: command and address in one FPWR of 6 bytes at 0x0502, status, then data. */
static void sii_read(uint32_t word, uint8_t *data, unsigned n)
{
    uint8_t cmd[6] = {0x00, 0x01, (uint8_t)word, (uint8_t)(word >> 8), (uint8_t)(word >> 16),
                      (uint8_t)(word >> 24)};
    uint8_t st[2];
    fpwr_ok(0x0502, cmd, 6);
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPRD, STATION, 0x0502, NULL, 2, st));
    TEST_ASSERT_FALSE(st[1] & 0x80u); /* never busy */
    TEST_ASSERT_EQUAL_HEX8(0, st[1] & 0x78u);
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPRD, STATION, 0x0508, NULL, (uint16_t)n, data));
}

static void test_sii_read(void)
{
    uint8_t d[8];
    sii_read(0x08, d, 4);
    TEST_ASSERT_EQUAL_HEX8(0x84, d[0]);
    TEST_ASSERT_EQUAL_HEX8(0x02, d[1]);
    sii_read(0x0A, d, 4);
    TEST_ASSERT_EQUAL_HEX8(0xE1, d[0]);
    sii_read(0x3E, d, 4);
    TEST_ASSERT_EQUAL_HEX8(0x0B, d[0]);
    TEST_ASSERT_EQUAL_HEX8(0x0C, d[3]);
    sii_read(0x3F, d, 4); /* the last word, then past the image: 0xFFFF */
    TEST_ASSERT_EQUAL_HEX8(0x0D, d[0]);
    TEST_ASSERT_EQUAL_HEX8(0xFF, d[2]);
    sii_read(0xFFFFFFFFu, d, 4);
    TEST_ASSERT_EQUAL_HEX8(0xFF, d[0]);

    /* A write command: no write enable -> bit 14; with it -> bit 13 (read-only image). */
    fpwr_ok(0x0502, (const uint8_t[]){0x00, 0x02}, 2);
    TEST_ASSERT_EQUAL_HEX16(0x4000, reg16(&esc, 0x0502));
    fpwr_ok(0x0502, (const uint8_t[]){0x01, 0x02}, 2);
    TEST_ASSERT_EQUAL_HEX16(0x2000, reg16(&esc, 0x0502));
    fpwr_ok(0x0502, (const uint8_t[]){0x00, 0x00}, 2); /* SOEM clears errors with 0 */
    TEST_ASSERT_EQUAL_HEX16(0x0000, reg16(&esc, 0x0502));
}

static void test_sii_read8_and_checksum_error(void)
{
    co_esc_config cfg = co_esc_default_config();
    uint8_t d[8];
    cfg.sii = sii;
    cfg.sii_size = sizeof sii;
    cfg.eeprom_read8 = true;
    co_esc_init(&esc, &cfg);
    set_station(&esc, 0, STATION);
    TEST_ASSERT_EQUAL_HEX16(0x0040, reg16(&esc, 0x0502));
    sii_read(0x08, d, 8);
    TEST_ASSERT_EQUAL_HEX8(0x84, d[0]);
    TEST_ASSERT_EQUAL_HEX8(0xE1, d[4]);

    sii[14] ^= 1; /* bad CRC: nothing loaded, checksum error shown, PDI not operational */
    co_esc_init(&esc, &cfg);
    TEST_ASSERT_EQUAL_HEX16(0x1840, reg16(&esc, 0x0502));
    TEST_ASSERT_EQUAL_HEX16(0x0000, reg16(&esc, 0x0012));
    TEST_ASSERT_EQUAL_HEX16(0x5612, reg16(&esc, 0x0110));
}

static void test_al_control_event_and_status(void)
{
    uint8_t b[6];
    TEST_ASSERT_EQUAL_UINT32(0, co_esc_al_event(&esc) & CO_ESC_AL_EVENT_ALCTL);
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, BWR, 0, 0x0120, (const uint8_t[]){0x12, 0x00}, 2, NULL));
    TEST_ASSERT_TRUE(co_esc_al_event(&esc) & CO_ESC_AL_EVENT_ALCTL);
    TEST_ASSERT_EQUAL_HEX16(0x0001, reg16(&esc, 0x0130)); /* the ESC does not change state */
    TEST_ASSERT_EQUAL_HEX16(0x0012, reg16(&esc, 0x0120)); /* the PDI read clears the event */
    TEST_ASSERT_FALSE(co_esc_al_event(&esc) & CO_ESC_AL_EVENT_ALCTL);
    /* The application answers: PRE-OP + error, code 0x0016. */
    TEST_ASSERT_EQUAL_INT(CO_ESC_PDI_OK,
                          co_esc_pdi_write(&esc, 0x0130, (const uint8_t[]){0x12, 0, 0, 0, 0x16, 0}, 6));
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPRD, STATION, 0x0130, NULL, 6, b));
    TEST_ASSERT_EQUAL_HEX8(0x12, b[0]);
    TEST_ASSERT_EQUAL_HEX8(0x16, b[4]);
}

static void test_sm_watchdog_on_the_virtual_clock(void)
{
    uint8_t pd[4] = {1, 2, 3, 4};
    config_process_data();
    /* Not running before the first trigger. */
    TEST_ASSERT_EQUAL_UINT64(CO_ESC_TIME_NEVER, co_esc_tick(&esc, now + 1000000000u));
    now = 5000000;
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, LWR, 0, 0, pd, 4, NULL)); /* logical 0 */
    /* 1000 x (2498 + 2) x 40 ns = 100 ms */
    TEST_ASSERT_EQUAL_UINT64(now + 100000000u, co_esc_tick(&esc, now + 99999999u));
    TEST_ASSERT_EQUAL_HEX8(1, esc.mem[0x0440]);
    TEST_ASSERT_EQUAL_UINT64(CO_ESC_TIME_NEVER, co_esc_tick(&esc, now + 100000000u));
    TEST_ASSERT_EQUAL_HEX8(0, esc.mem[0x0440] & 1u);
    TEST_ASSERT_EQUAL_HEX8(1, esc.mem[0x0442]);
    TEST_ASSERT_TRUE(co_esc_al_event(&esc) & CO_ESC_AL_EVENT_WD_PD);
    TEST_ASSERT_EQUAL_HEX16(0x0000, reg16(&esc, 0x0440)); /* PDI read clears the event */
    TEST_ASSERT_FALSE(co_esc_al_event(&esc) & CO_ESC_AL_EVENT_WD_PD);
    /* The next output write restarts it; a shorter time applies from its write. */
    now += 200000000u;
    one(&esc, LWR, 0, 0, pd, 4, NULL);
    TEST_ASSERT_EQUAL_HEX8(1, esc.mem[0x0440] & 1u);
    fpwr_ok(0x0420, (const uint8_t[]){10, 0}, 2); /* 1 ms */
    TEST_ASSERT_EQUAL_UINT64(now + 1000000u, co_esc_tick(&esc, now));
    /* An SM without the trigger bit (SM3, read by the master) never restarts it. */
    co_esc_tick(&esc, now + 1000000u);
    TEST_ASSERT_EQUAL_HEX8(0, esc.mem[0x0440] & 1u);
    one(&esc, LRD, 4, 0, NULL, 4, NULL); /* logical 4: the inputs */
    TEST_ASSERT_EQUAL_HEX8(0, esc.mem[0x0440] & 1u);
    fpwr_ok(0x0420, (const uint8_t[]){0, 0}, 2); /* 0 disables: status "active or disabled" */
    TEST_ASSERT_EQUAL_HEX8(1, esc.mem[0x0440] & 1u);
    TEST_ASSERT_EQUAL_HEX8(2, esc.mem[0x0442]);
    fpwr_ok(0x0442, (const uint8_t[]){0x55}, 1); /* a write clears the counter */
    TEST_ASSERT_EQUAL_HEX8(0, esc.mem[0x0442]);
}

static void test_distributed_clocks(void)
{
    co_esc_config cfg = co_esc_default_config();
    uint8_t b[8];
    uint64_t offset = 123456789000u, t;
    cfg.sii = sii;
    cfg.sii_size = sizeof sii;
    cfg.dc = true;
    co_esc_init(&esc, &cfg);
    set_station(&esc, 0, STATION);
    TEST_ASSERT_EQUAL_HEX16(0x000D, reg16(&esc, 0x0008));
    now = 777000;
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, BWR, 0, 0x0900, NULL, 4, NULL)); /* latch */
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPRD, STATION, 0x0918, NULL, 8, b));
    t = 0;
    for (int i = 7; i >= 0; i--) {
        t = (t << 8) | b[i];
    }
    TEST_ASSERT_EQUAL_UINT64(777000, t);
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPRD, STATION, 0x0900, NULL, 8, b));
    TEST_ASSERT_EQUAL_HEX8(0x28, b[0]); /* 777000 = 0x0BDB28 */
    TEST_ASSERT_EQUAL_HEX8(0x00, b[4]); /* port 1 closed */
    for (int i = 0; i < 8; i++) {
        b[i] = (uint8_t)(offset >> (8 * i));
    }
    fpwr_ok(0x0920, b, 8);
    now = 900000;
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FRMW, STATION, 0x0910, NULL, 8, b));
    t = 0;
    for (int i = 7; i >= 0; i--) {
        t = (t << 8) | b[i];
    }
    TEST_ASSERT_EQUAL_UINT64(900000u + offset, t);
    /* Without DC the block is reserved: reads 0, writes change nothing. */
    cfg.dc = false;
    co_esc_init(&esc, &cfg);
    set_station(&esc, 0, STATION);
    fpwr_ok(0x0920, b, 8);
    TEST_ASSERT_EQUAL_UINT16(1, one(&esc, FPRD, STATION, 0x0910, NULL, 8, b));
    TEST_ASSERT_EQUAL_HEX8(0, b[0] | b[7]);
    TEST_ASSERT_EQUAL_HEX16(0, reg16(&esc, 0x0920));
}

/* A malformed frame: returned code, frame bytes unchanged, memory unchanged but the invalid
 * frame counter 0x0300. */
static void expect_rejected(ecat_frame *f, size_t len, int code)
{
    uint8_t before[1600];
    static co_esc copy;
    copy = esc;
    memcpy(before, f->b, sizeof before);
    TEST_ASSERT_EQUAL_INT(code, co_esc_process_frame(&esc, f->b, len, now));
    TEST_ASSERT_EQUAL_MEMORY(before, f->b, sizeof before);
    if (code < 0) {
        TEST_ASSERT_EQUAL_UINT8((uint8_t)(copy.mem[0x0300] + 1u), esc.mem[0x0300]);
        copy.mem[0x0300] = esc.mem[0x0300];
    }
    TEST_ASSERT_EQUAL_MEMORY(copy.mem, esc.mem, sizeof esc.mem);
}

static void test_malformed_frames_change_nothing(void)
{
    ecat_frame f;
    config_mailboxes();
    tf_init(&f);
    ecat_frame_add(&f, FPWR, STATION, 0x1000, NULL, 128);
    ecat_frame_add(&f, BWR, 0, 0x0120, (const uint8_t[]){0x02, 0}, 2);
    expect_rejected(&f, 10, CO_ESC_FRAME_SHORT);             /* no EtherType */
    expect_rejected(&f, 15, CO_ESC_FRAME_SHORT);             /* no EtherCAT header */
    expect_rejected(&f, f.len - 1, CO_ESC_FRAME_BAD_LENGTH); /* length field past the end */
    f.b[14]++;                                               /* length field says 1 more */
    expect_rejected(&f, f.len + 1, CO_ESC_FRAME_BAD_LENGTH);
    f.b[14] = (uint8_t)(f.b[14] - 2);                        /* 1 less: last WKC cut */
    expect_rejected(&f, f.len, CO_ESC_FRAME_BAD_LENGTH);
    f.b[14]++;
    f.b[16 + 7] = 0x00; /* first datagram without "more": the second is left over */
    expect_rejected(&f, f.len, CO_ESC_FRAME_BAD_LENGTH);
    f.b[16 + 7] = 0x80;
    f.b[16 + 6] = 0xFF; /* first datagram's data runs past the end */
    f.b[16 + 7] = 0x87;
    expect_rejected(&f, f.len, CO_ESC_FRAME_BAD_LENGTH);
    f.b[16 + 6] = 128;
    f.b[16 + 7] = 0x80;
    f.b[f.last + 7] = 0x80; /* the last one says "more" */
    expect_rejected(&f, f.len, CO_ESC_FRAME_BAD_LENGTH);
    f.b[f.last + 7] = 0x00;
    f.b[15] = 0x20; /* EtherCAT type 2: not commands */
    expect_rejected(&f, f.len, CO_ESC_FRAME_NOT_ECAT);
    f.b[15] = 0x10;
    f.b[13] = 0x00; /* another EtherType */
    expect_rejected(&f, f.len, CO_ESC_FRAME_NOT_ECAT);
    f.b[13] = 0xA4;
    TEST_ASSERT_EQUAL_UINT32(8, esc.stats.bad_frames);
    /* Repaired, the same frame is processed; padding after the datagrams is allowed. */
    TEST_ASSERT_EQUAL_INT(CO_ESC_FRAME_OK, co_esc_process_frame(&esc, f.b, f.len + 20, now));
    TEST_ASSERT_EQUAL_UINT16(1, ecat_frame_wkc(&f, 16));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_init_registers);
    RUN_TEST(test_auto_increment_commands);
    RUN_TEST(test_configured_address_and_alias);
    RUN_TEST(test_broadcast_commands);
    RUN_TEST(test_read_multiple_write);
    RUN_TEST(test_nop_and_unknown_command_pass_untouched);
    RUN_TEST(test_write_protection);
    RUN_TEST(test_chain_of_two);
    RUN_TEST(test_lrw_through_fmmus_to_buffered_sms);
    RUN_TEST(test_fmmu_follows_sm_reconfiguration);
    RUN_TEST(test_mailbox_master_to_pdi);
    RUN_TEST(test_mailbox_pdi_to_master);
    RUN_TEST(test_repeat_request_toggle);
    RUN_TEST(test_sii_read);
    RUN_TEST(test_sii_read8_and_checksum_error);
    RUN_TEST(test_al_control_event_and_status);
    RUN_TEST(test_sm_watchdog_on_the_virtual_clock);
    RUN_TEST(test_distributed_clocks);
    RUN_TEST(test_malformed_frames_change_nothing);
    return UNITY_END();
}
