/* The EtherCAT slave application layer (ecat/src/slave.c) with the VF-MB1 drive behind it, driven
 * by frames through co_esc_process_frame exactly as a master sends them (auto-increment
 * addressing, position 0), on the virtual clock: ESM transitions and refusals with their AL status
 * codes, mailbox errors and repeat, CoE SDO expedited / normal / segmented / complete access, SDO
 * information, CoE emergency, process data through LRW, the SM watchdog and the manual's
 * communication-interruption table (VF-MB1 EtherCAT option manual §7). */
#include <string.h>

#include "canopen/drive.h"
#include "canopen/ecat/esc.h"
#include "canopen/ecat/slave.h"
#include "drive_fixture.h"
#include "ecat_frame.h"
#include "od_vf_mb1_ecat.h"
#include "unity.h"

/* ---- a master: frames of one datagram ---- */

static drive_fx fx;
static co_esc esc;
static co_ecat_slave sl;
static uint16_t mbx_size; /* SM0/SM1 length in this test */
static uint8_t master_counter;

static uint64_t now_ns(void)
{
    return fx.now * 1000u;
}

/* One datagram in a frame of its own through the ESC, then the application layer runs (as the
 * port does after every frame). Returns the WKC; the datagram's data is copied to out. */
static uint16_t datagram(uint8_t cmd, uint32_t addr, const void *data, uint16_t len, void *out)
{
    ecat_frame f;
    memset(&f, 0, sizeof f);
    ecat_frame_start(&f);
    size_t dg = ecat_frame_add32(&f, cmd, addr, data, len);
    TEST_ASSERT_EQUAL_INT(CO_ESC_FRAME_OK,
                          co_esc_process_frame(&esc, f.b, ecat_frame_wire_len(&f), now_ns()));
    (void)co_ecat_slave_process(&sl, now_ns());
    if (out != NULL) {
        memcpy(out, ecat_frame_data(&f, dg), len);
    }
    return ecat_frame_wkc(&f, dg);
}

static uint16_t apwr(uint16_t ado, const void *data, uint16_t len)
{
    return datagram(APWR, (uint32_t)ado << 16, data, len, NULL);
}

static uint16_t aprd(uint16_t ado, void *out, uint16_t len)
{
    return datagram(APRD, (uint32_t)ado << 16, NULL, len, out);
}

static uint16_t reg16(uint16_t ado)
{
    uint8_t v[2] = {0, 0};
    TEST_ASSERT_EQUAL_UINT16(1, aprd(ado, v, 2));
    return (uint16_t)(v[0] | (v[1] << 8));
}

static void wr8(uint16_t ado, uint8_t v)
{
    TEST_ASSERT_EQUAL_UINT16(1, apwr(ado, &v, 1));
}

static void wr16(uint16_t ado, uint16_t v)
{
    uint8_t b[2] = {(uint8_t)v, (uint8_t)(v >> 8)};
    TEST_ASSERT_EQUAL_UINT16(1, apwr(ado, b, 2));
}

/* Moves the clock (the drive at its deadlines) and runs the slave. */
static void advance_us(uint64_t us)
{
    fx_advance(&fx, us);
    (void)co_ecat_slave_process(&sl, now_ns());
}

static void config_sm(unsigned n, uint16_t start, uint16_t len, uint8_t ctrl)
{
    uint8_t sm[8] = {(uint8_t)start, (uint8_t)(start >> 8), (uint8_t)len, (uint8_t)(len >> 8),
                     ctrl, 0, 1, 0};
    TEST_ASSERT_EQUAL_UINT16(1, apwr((uint16_t)CO_ESC_REG_SM(n), sm, 8));
}

static void config_mailboxes(void)
{
    config_sm(0, 0x1000, mbx_size, 0x26);
    config_sm(1, 0x1080, mbx_size, 0x22);
}

/* SM2/SM3 as SOEM programs them from 0x1C12/0x1C13 and the mapping (4 bytes each), and FMMU0
 * (logical 0, outputs) / FMMU1 (logical 4, inputs). */
static void config_process_data(uint16_t out_len, uint16_t in_len)
{
    config_sm(2, 0x1100, out_len, 0x64);
    config_sm(3, 0x1180, in_len, 0x20);
    uint8_t fmmu[32] = {0};
    fmmu[4] = (uint8_t)out_len;
    fmmu[7] = 7;
    fmmu[8] = 0x00;
    fmmu[9] = 0x11;
    fmmu[11] = 2; /* write */
    fmmu[12] = 1;
    fmmu[16] = 4;
    fmmu[20] = (uint8_t)in_len;
    fmmu[23] = 7;
    fmmu[24] = 0x80;
    fmmu[25] = 0x11;
    fmmu[27] = 1; /* read */
    fmmu[28] = 1;
    TEST_ASSERT_EQUAL_UINT16(1, apwr(CO_ESC_REG_FMMU(0), fmmu, 32));
}

static void request(uint8_t state)
{
    wr16(CO_ESC_REG_ALCTL, state);
}

static uint8_t al_status(void)
{
    return (uint8_t)reg16(CO_ESC_REG_ALSTAT);
}

static uint16_t al_code(void)
{
    return reg16(CO_ESC_REG_ALSTATCODE);
}

/* One LRW cycle: 4 output bytes (controlword, target) out, 4 input bytes (statusword, 6044)
 * back. Returns the WKC (3 when both directions moved). */
static uint16_t cycle(uint16_t cw, int16_t target, uint16_t *sw, int16_t *actual)
{
    uint8_t b[8] = {(uint8_t)cw, (uint8_t)(cw >> 8), (uint8_t)target,
                    (uint8_t)((uint16_t)target >> 8), 0, 0, 0, 0};
    uint16_t wkc = datagram(LRW, 0, b, 8, b);
    if (sw != NULL) {
        *sw = (uint16_t)(b[4] | (b[5] << 8));
    }
    if (actual != NULL) {
        *actual = (int16_t)(b[6] | (b[7] << 8));
    }
    return wkc;
}

/* ---- mailbox as SOEM does it ---- */

/* Writes a whole SM0 buffer: header (length, address 0, channel 0, type, counter) and data. */
static uint16_t mbx_send_raw(uint16_t len_field, uint8_t type, uint8_t counter, const void *data,
                             uint16_t n)
{
    uint8_t b[CO_ECAT_MBX_MAX];
    memset(b, 0, sizeof b);
    b[0] = (uint8_t)len_field;
    b[1] = (uint8_t)(len_field >> 8);
    b[5] = (uint8_t)(type | (counter << 4));
    memcpy(b + 6, data, n);
    return apwr(0x1000, b, mbx_size);
}

static void mbx_send(uint8_t type, const void *data, uint16_t n)
{
    master_counter = (uint8_t)(master_counter % 7u + 1u);
    TEST_ASSERT_EQUAL_UINT16(1, mbx_send_raw(n, type, master_counter, data, n));
}

/* Reads SM1 if full: returns the mailbox length field (0: empty), data into out. */
static uint16_t mbx_receive(uint8_t *type, uint8_t *out)
{
    uint8_t st = 0, b[CO_ECAT_MBX_MAX];
    TEST_ASSERT_EQUAL_UINT16(1, aprd(CO_ESC_REG_SM_STATUS(1), &st, 1));
    if ((st & CO_ESC_SM_STATUS_MBX_FULL) == 0u) {
        return 0;
    }
    TEST_ASSERT_EQUAL_UINT16(1, aprd(0x1080, b, mbx_size));
    if (type != NULL) {
        *type = b[5] & 0x0Fu;
    }
    uint16_t len = (uint16_t)(b[0] | (b[1] << 8));
    if (out != NULL) {
        memcpy(out, b + 6, len <= mbx_size - 6u ? len : mbx_size - 6u);
    }
    return len;
}

/* A CoE message: CoE header service, then the bytes. */
static void coe_send(uint8_t service, const uint8_t *d, uint16_t n)
{
    uint8_t b[CO_ECAT_MBX_MAX];
    b[0] = 0;
    b[1] = (uint8_t)(service << 4);
    memcpy(b + 2, d, n);
    mbx_send(3, b, (uint16_t)(n + 2u));
}

/* The next CoE answer (skipping nothing): its length after the mailbox header. */
static uint16_t coe_receive(uint8_t *out)
{
    uint8_t type = 0xFF;
    uint16_t len = mbx_receive(&type, out);
    TEST_ASSERT_TRUE_MESSAGE(len > 0u, "no mailbox answer");
    TEST_ASSERT_EQUAL_UINT8(3, type);
    return len;
}

/* The next answer that is not an emergency (SOEM keeps emergencies aside the same way). */
static uint32_t emergencies_skipped;
static uint16_t coe_answer(uint8_t *out)
{
    for (;;) {
        uint16_t n = coe_receive(out);
        if ((out[1] >> 4) != 1) {
            return n;
        }
        emergencies_skipped++;
    }
}

static uint32_t le32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

/* Expedited (or normal, if the answer is) upload; returns the abort code (0: value in out). */
static uint32_t ec_sdo_read(uint16_t index, uint8_t sub, bool ca, uint8_t *out, uint32_t *len)
{
    uint8_t q[8] = {(uint8_t)(ca ? 0x50 : 0x40), (uint8_t)index, (uint8_t)(index >> 8), sub,
                    0, 0, 0, 0};
    uint8_t r[CO_ECAT_MBX_MAX];
    coe_send(2, q, 8);
    uint16_t n = coe_answer(r);
    if ((r[1] >> 4) == 2 && r[2] == 0x80) {
        TEST_ASSERT_EQUAL_UINT16(10, n);
        return le32(r + 6);
    }
    TEST_ASSERT_EQUAL_UINT8(3, r[1] >> 4);
    TEST_ASSERT_EQUAL_UINT8((uint8_t)index, r[3]);
    TEST_ASSERT_EQUAL_UINT8((uint8_t)(index >> 8), r[4]);
    if (r[2] & 0x02) {
        *len = 4u - ((r[2] >> 2) & 3u);
        memcpy(out, r + 6, *len);
        return 0;
    }
    uint32_t size = le32(r + 6), got = n - 10u;
    memcpy(out, r + 10, got);
    uint8_t toggle = 0;
    while (got < size) { /* upload segments */
        uint8_t seg[8] = {(uint8_t)(0x60 | toggle), 0, 0, 0, 0, 0, 0, 0};
        coe_send(2, seg, 8);
        n = coe_answer(r);
        if (r[2] == 0x80) {
            return le32(r + 6);
        }
        TEST_ASSERT_EQUAL_UINT8(toggle, r[2] & 0x10);
        uint32_t k = n - 3u;
        if (n == 10u) {
            k = 7u - ((r[2] >> 1) & 7u);
        }
        memcpy(out + got, r + 3, k);
        got += k;
        TEST_ASSERT_EQUAL(got == size, (r[2] & 1) != 0);
        toggle ^= 0x10;
    }
    *len = got;
    return 0;
}

static uint32_t ec_sdo_write_exp(uint16_t index, uint8_t sub, uint32_t value, uint8_t size)
{
    uint8_t q[8] = {(uint8_t)(0x23 | ((4 - size) << 2)), (uint8_t)index, (uint8_t)(index >> 8),
                    sub, (uint8_t)value, (uint8_t)(value >> 8), (uint8_t)(value >> 16),
                    (uint8_t)(value >> 24)};
    uint8_t r[CO_ECAT_MBX_MAX];
    coe_send(2, q, 8);
    coe_answer(r);
    if (r[2] == 0x80) {
        return le32(r + 6);
    }
    TEST_ASSERT_EQUAL_HEX8(0x60, r[2]);
    TEST_ASSERT_EQUAL_UINT8(sub, r[5]);
    return 0;
}

/* Normal download (complete access when ca), segmented when data does not fit the first
 * message: SOEM's way for values above 4 bytes. */
static uint32_t ec_sdo_write(uint16_t index, uint8_t sub, bool ca, const uint8_t *data, uint32_t n,
                          uint32_t first)
{
    uint8_t q[CO_ECAT_MBX_MAX];
    uint8_t r[CO_ECAT_MBX_MAX];
    q[0] = (uint8_t)(ca ? 0x31 : 0x21);
    q[1] = (uint8_t)index;
    q[2] = (uint8_t)(index >> 8);
    q[3] = sub;
    q[4] = (uint8_t)n;
    q[5] = (uint8_t)(n >> 8);
    q[6] = 0;
    q[7] = 0;
    if (first > n) {
        first = n;
    }
    memcpy(q + 8, data, first);
    coe_send(2, q, (uint16_t)(8u + first));
    coe_answer(r);
    if (r[2] == 0x80) {
        return le32(r + 6);
    }
    TEST_ASSERT_EQUAL_HEX8(0x60, r[2]);
    uint32_t done = first;
    uint8_t toggle = 0;
    while (done < n) {
        uint32_t k = n - done > 7u ? 7u : n - done;
        q[0] = (uint8_t)(toggle | (done + k == n ? 1u : 0u) | ((7u - k) << 1));
        memset(q + 1, 0, 7);
        memcpy(q + 1, data + done, k);
        coe_send(2, q, 8);
        coe_answer(r);
        if (r[2] == 0x80) {
            return le32(r + 6);
        }
        TEST_ASSERT_EQUAL_HEX8(0x20 | toggle, r[2]);
        done += k;
        toggle ^= 0x10;
    }
    return 0;
}

/* ---- fixture ---- */

static void start_with_mailbox(uint16_t size)
{
    fx_start(&fx, co_drive_registry_find("vf-mb1-ecat"), 1);
    co_esc_config ec = co_esc_default_config();
    TEST_ASSERT_EQUAL_INT(0, co_esc_init(&esc, &ec));
    co_ecat_slave_config c = co_ecat_slave_default_config();
    c.esc = &esc;
    c.node = &fx.d.node;
    c.drive = &fx.d;
    c.mbx_out_size = size;
    c.mbx_in_size = size;
    c.in_start = 0x1180; /* 3 x 4 bytes of SM2 from 0x1100 end below it */
    c.al_state_index = 0x4400; /* C400 */
    mbx_size = size;
    master_counter = 0;
    TEST_ASSERT_TRUE(co_ecat_slave_init(&sl, &c, now_ns()));
}

void setUp(void)
{
    start_with_mailbox(128);
}

void tearDown(void)
{
}

static void to_preop(void)
{
    config_mailboxes();
    request(CO_ECAT_STATE_PREOP);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_PREOP, al_status());
}

static void to_safeop(void)
{
    to_preop();
    config_process_data(4, 4);
    request(CO_ECAT_STATE_SAFEOP);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_SAFEOP, al_status());
}

static void to_op(void)
{
    to_safeop();
    TEST_ASSERT_EQUAL_UINT16(3, cycle(0, 0, NULL, NULL));
    request(CO_ECAT_STATE_OP);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_OP, al_status());
}

/* §3.1: C003 = 4, F004 = 7 over CoE, then F899 = 1 (the communication function reset). */
static void cia402_profile(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_write_exp(0x2003, 0, 4, 2));
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_write_exp(0x2004, 0, 7, 2));
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_write_exp(0x2899, 0, 1, 2));
    advance_us(1000);
}

/* PRE-OP, the CiA 402 profile, process data of 4 + 4 bytes, SAFE-OP with a first cycle
 * (shutdown), then OP. */
static void in_op_with_the_profile(void)
{
    to_preop();
    cia402_profile();
    config_process_data(4, 4);
    request(CO_ECAT_STATE_SAFEOP);
    cycle(0x0006, 0, NULL, NULL);
    request(CO_ECAT_STATE_OP);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_OP, al_status());
}

static void running_at(int16_t rpm)
{
    in_op_with_the_profile();
    cycle(0x0006, 0, NULL, NULL);
    cycle(0x0007, 0, NULL, NULL);
    cycle(0x000F, 0, NULL, NULL);
    for (int i = 0; i < 600; i++) { /* 6 s of 10 ms cycles: 0x6048 is 1500 rpm in 10 s */
        cycle(0x000F, rpm, NULL, NULL);
        advance_us(10000);
    }
    int16_t actual = 0;
    cycle(0x000F, rpm, NULL, &actual);
    TEST_ASSERT_EQUAL_INT16(rpm, actual);
}

/* ---- ESM ---- */

static void test_power_on_is_init_and_node_stopped(void)
{
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_INIT, al_status());
    TEST_ASSERT_EQUAL_HEX16(0, al_code());
    TEST_ASSERT_EQUAL(CO_NMT_STOPPED, fx.d.node.nmt_state);
    TEST_ASSERT_EQUAL_UINT16(1, fx_u16(&fx, 0x4400, 0)); /* C400: INIT */
    TEST_ASSERT_EQUAL_STRING("off", co_ecat_slave_run_led(&sl));
}

static void test_preop_needs_the_mailbox_sync_managers(void)
{
    request(CO_ECAT_STATE_PREOP); /* no SM0/SM1 */
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_INIT | CO_ECAT_AL_ERROR, al_status());
    TEST_ASSERT_EQUAL_HEX16(CO_ECAT_AL_INVALID_MBX_CONFIG, al_code());
    TEST_ASSERT_EQUAL_STRING("blinking", co_ecat_slave_err_led(&sl));
    /* a wrong length is as bad */
    config_sm(0, 0x1000, 64, 0x26);
    config_sm(1, 0x1080, 128, 0x22);
    request(CO_ECAT_STATE_PREOP | CO_ECAT_AL_ERROR);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_INIT | CO_ECAT_AL_ERROR, al_status());
    TEST_ASSERT_EQUAL_HEX16(CO_ECAT_AL_INVALID_MBX_CONFIG, al_code());
    /* as the SII says: PRE-OP with the error acknowledged */
    wr8(CO_ESC_REG_SM_ACTIVATE(0), 0);
    config_mailboxes();
    request(CO_ECAT_STATE_PREOP | CO_ECAT_AL_ERROR);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_PREOP, al_status());
    TEST_ASSERT_EQUAL_HEX16(0, al_code());
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, fx.d.node.nmt_state);
    TEST_ASSERT_EQUAL_UINT16(2, fx_u16(&fx, 0x4400, 0));
}

static void test_refused_requests_and_their_codes(void)
{
    request(CO_ECAT_STATE_SAFEOP); /* I -> S */
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_INIT | CO_ECAT_AL_ERROR, al_status());
    TEST_ASSERT_EQUAL_HEX16(CO_ECAT_AL_INVALID_STATE_CHANGE, al_code());
    /* without the acknowledgement the error stays, whatever is asked */
    config_mailboxes();
    request(CO_ECAT_STATE_PREOP);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_INIT | CO_ECAT_AL_ERROR, al_status());
    request(CO_ECAT_STATE_BOOT | CO_ECAT_AL_ERROR); /* I -> B: no bootstrap */
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_INIT | CO_ECAT_AL_ERROR, al_status());
    TEST_ASSERT_EQUAL_HEX16(CO_ECAT_AL_BOOT_NOT_SUPPORTED, al_code());
    request(CO_ECAT_STATE_OP | CO_ECAT_AL_ERROR); /* I -> O */
    TEST_ASSERT_EQUAL_HEX16(CO_ECAT_AL_INVALID_STATE_CHANGE, al_code());
    request(0x05 | CO_ECAT_AL_ERROR);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_INIT | CO_ECAT_AL_ERROR, al_status());
    TEST_ASSERT_EQUAL_HEX16(CO_ECAT_AL_UNKNOWN_STATE, al_code());
    request(CO_ECAT_STATE_INIT); /* INIT clears the error */
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_INIT, al_status());
    TEST_ASSERT_EQUAL_HEX16(0, al_code());
    to_preop();
    request(CO_ECAT_STATE_OP); /* P -> O */
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_PREOP | CO_ECAT_AL_ERROR, al_status());
    TEST_ASSERT_EQUAL_HEX16(CO_ECAT_AL_INVALID_STATE_CHANGE, al_code());
    request(CO_ECAT_STATE_BOOT | CO_ECAT_AL_ERROR); /* P -> B */
    TEST_ASSERT_EQUAL_HEX16(CO_ECAT_AL_INVALID_STATE_CHANGE, al_code());
}

static void test_safeop_needs_process_data_sync_managers_as_mapped(void)
{
    to_preop();
    config_sm(2, 0x1100, 6, 0x64); /* the mapping gives 4 bytes */
    config_sm(3, 0x1180, 4, 0x20);
    request(CO_ECAT_STATE_SAFEOP);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_PREOP | CO_ECAT_AL_ERROR, al_status());
    TEST_ASSERT_EQUAL_HEX16(CO_ECAT_AL_INVALID_OUTPUT_CONFIG, al_code());
    wr8(CO_ESC_REG_SM_ACTIVATE(2), 0);
    wr8(CO_ESC_REG_SM_ACTIVATE(3), 0);
    config_sm(2, 0x1100, 4, 0x64);
    config_sm(3, 0x1190, 4, 0x20); /* wrong start */
    request(CO_ECAT_STATE_SAFEOP | CO_ECAT_AL_ERROR);
    TEST_ASSERT_EQUAL_HEX16(CO_ECAT_AL_INVALID_INPUT_CONFIG, al_code());
    wr8(CO_ESC_REG_SM_ACTIVATE(3), 0);
    config_sm(3, 0x1180, 4, 0x20);
    request(CO_ECAT_STATE_SAFEOP | CO_ECAT_AL_ERROR);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_SAFEOP, al_status());
    TEST_ASSERT_EQUAL_UINT16(4, fx_u16(&fx, 0x4400, 0)); /* C400 4: SAFE-OP */
    TEST_ASSERT_EQUAL_STRING("single flash", co_ecat_slave_run_led(&sl));
}

static void test_a_mapping_change_in_preop_changes_the_sm_lengths(void)
{
    to_preop();
    uint32_t cob = fx_u32(&fx, 0x1400, 1);
    TEST_ASSERT_EQUAL_HEX32(0, cob & 0x80000000u); /* the CAN face's RPDO1 is valid */
    /* 0x1600 with the controlword only (complete access: count, pad, entries) */
    const uint8_t map[6] = {1, 0, 0x10, 0x00, 0x40, 0x60};
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_write(0x1600, 0, true, map, sizeof map, 100));
    TEST_ASSERT_EQUAL_HEX32(cob | 0x80000000u, fx_u32(&fx, 0x1400, 1)); /* made invalid */
    config_sm(2, 0x1100, 4, 0x64);
    config_sm(3, 0x1180, 4, 0x20);
    request(CO_ECAT_STATE_SAFEOP);
    TEST_ASSERT_EQUAL_HEX16(CO_ECAT_AL_INVALID_OUTPUT_CONFIG, al_code());
    wr8(CO_ESC_REG_SM_ACTIVATE(2), 0);
    config_sm(2, 0x1100, 2, 0x64);
    request(CO_ECAT_STATE_SAFEOP | CO_ECAT_AL_ERROR);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_SAFEOP, al_status());
    TEST_ASSERT_EQUAL_HEX32(cob, fx_u32(&fx, 0x1400, 1)); /* valid again with the new mapping */
    TEST_ASSERT_EQUAL_UINT8(1, fx_u8(&fx, 0x1600, 0));
    /* the mapping is fixed outside PRE-OP */
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_DEVICE_STATE, ec_sdo_write(0x1600, 0, true, map, sizeof map, 100));
}

static void test_op_waits_for_valid_outputs_then_gives_up_with_0x001B(void)
{
    to_safeop();
    request(CO_ECAT_STATE_OP);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_SAFEOP, al_status()); /* pending */
    advance_us(50000);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_SAFEOP, al_status());
    TEST_ASSERT_EQUAL_UINT16(3, cycle(0, 0, NULL, NULL)); /* the first outputs */
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_OP, al_status());
    TEST_ASSERT_EQUAL(CO_NMT_OPERATIONAL, fx.d.node.nmt_state);
    TEST_ASSERT_EQUAL_UINT16(8, fx_u16(&fx, 0x4400, 0));
    /* again without outputs: SM watchdog time (100 ms), then SAFE-OP + error, 0x001B */
    request(CO_ECAT_STATE_SAFEOP);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_SAFEOP, al_status());
    request(CO_ECAT_STATE_OP);
    advance_us(99000);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_SAFEOP, al_status());
    advance_us(2000);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_SAFEOP | CO_ECAT_AL_ERROR, al_status());
    TEST_ASSERT_EQUAL_HEX16(CO_ECAT_AL_SM_WATCHDOG, al_code());
}

/* ---- process data ---- */

static void test_outputs_reach_the_drive_in_op_only_inputs_from_safeop(void)
{
    uint16_t sw = 0xFFFF;
    to_preop();
    cia402_profile();
    config_process_data(4, 4);
    request(CO_ECAT_STATE_SAFEOP);
    TEST_ASSERT_EQUAL_UINT16(3, cycle(0x0006, 0, &sw, NULL));
    advance_us(1000);
    TEST_ASSERT_EQUAL_UINT16(3, cycle(0x0006, 0, &sw, NULL));
    TEST_ASSERT_EQUAL_HEX16(0x0240, sw); /* inputs run; the shutdown command was ignored */
    TEST_ASSERT_EQUAL_HEX16(0, fx_u16(&fx, 0x6040, 0));
    request(CO_ECAT_STATE_OP);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_OP, al_status());
    TEST_ASSERT_EQUAL_HEX16(0x0006, fx_u16(&fx, 0x6040, 0)); /* the latest outputs applied */
    cycle(0x0006, 0, &sw, NULL);
    TEST_ASSERT_EQUAL_HEX16(0x0221, sw);
    cycle(0x0007, 0, NULL, NULL);
    cycle(0x000F, 1500, &sw, NULL);
    cycle(0x000F, 1500, &sw, NULL);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    int16_t actual = 0;
    for (int i = 0; i < 1100; i++) { /* 11 s of 10 ms cycles */
        advance_us(10000);
        cycle(0x000F, 1500, &sw, &actual);
    }
    TEST_ASSERT_EQUAL_INT16(1500, actual);
    TEST_ASSERT_EQUAL_HEX16(0x0637, sw); /* manual §7.1 example: 0x0637 at 1500 */
    /* an SDO write of the target is overridden by the next cycle's output, as by an RPDO */
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_write_exp(0x6042, 0, 300, 2));
    TEST_ASSERT_EQUAL_INT16(300, fx_i16(&fx, 0x6042, 0));
    cycle(0x000F, 1500, NULL, NULL);
    TEST_ASSERT_EQUAL_INT16(1500, fx_i16(&fx, 0x6042, 0));
}

/* A cyclic master repeats its outputs: a frame that brings only an SM2 buffer equal to the objects
 * leaves the drive alone until its deadline (nothing reached it); a changed output, a call without
 * a frame (the application changed something) and the drive's own deadlines run it. */
static void test_repeated_outputs_run_the_drive_only_when_something_reached_it(void)
{
    uint16_t sw = 0;
    int16_t actual = 0;
    in_op_with_the_profile();
    fx.now += 1000u;
    (void)co_ecat_slave_process(&sl, now_ns()); /* no frame: runs the drive */
    uint64_t ran = fx.now;
    TEST_ASSERT_EQUAL_UINT64(ran, fx.d.node.now);
    /* Ready to switch on, no timer: the drive's deadline is far */
    TEST_ASSERT_TRUE(sl.node_next > now_ns() + 1000000u);
    fx.now += 1000u;
    cycle(0x0006, 0, &sw, NULL);
    TEST_ASSERT_EQUAL_UINT64(ran, fx.d.node.now); /* not run: the same outputs */
    TEST_ASSERT_EQUAL_HEX16(0x0221, sw);
    fx.now += 1000u;
    (void)co_ecat_slave_process(&sl, now_ns()); /* no frame: runs the drive */
    TEST_ASSERT_EQUAL_UINT64(fx.now, fx.d.node.now);
    fx.now += 1000u;
    cycle(0x0007, 0, NULL, NULL); /* a new output: runs it */
    TEST_ASSERT_EQUAL_UINT64(fx.now, fx.d.node.now);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCHED_ON, fx.d.state);
    /* frames only, 1 ms apart: the ramp (1500 rpm in 10 s) runs at the deadlines it returns */
    for (int i = 0; i < 5000; i++) {
        fx.now += 1000u;
        cycle(0x000F, 600, &sw, &actual);
    }
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    TEST_ASSERT_EQUAL_INT16(600, actual);
    TEST_ASSERT_EQUAL_HEX16(0x0637, sw);
}

static void test_sm_watchdog_leaves_op_and_trips_err8(void)
{
    running_at(600);
    advance_us(99000); /* 100 ms watchdog: nothing yet */
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_OP, al_status());
    advance_us(2000);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_SAFEOP | CO_ECAT_AL_ERROR, al_status());
    TEST_ASSERT_EQUAL_HEX16(CO_ECAT_AL_SM_WATCHDOG, al_code());
    TEST_ASSERT_EQUAL_STRING("double flash", co_ecat_slave_err_led(&sl));
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, fx.d.node.nmt_state);
    /* the drive's communication loss: C100 = 0.1 s, then C101 = 4 network error stop (Err8) */
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    advance_us(100000);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT_REACTION_ACTIVE, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0x7520, fx_u16(&fx, 0x603F, 0));
    advance_us(1000000);
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT, fx.d.state);
    /* the master acknowledges and comes back: the fault stays until reset */
    request(CO_ECAT_STATE_SAFEOP | CO_ECAT_AL_ERROR);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_SAFEOP, al_status());
}

/* A port that wakes only at the deadlines co_ecat_slave_process returns (and runs no other timer
 * for the drive) still sees the watchdog expire and the drive's C100 delay end. */
static void test_returned_deadlines_carry_the_watchdog_and_the_drive(void)
{
    running_at(600);
    uint64_t last_cycle = fx.now;
    uint64_t next = co_ecat_slave_process(&sl, now_ns());
    for (int guard = 0; guard < 100000 && fx.d.state == CO_CIA402_OPERATION_ENABLED; guard++) {
        TEST_ASSERT_TRUE(next != CO_ESC_TIME_NEVER);
        uint64_t us = (next + 999u) / 1000u;
        fx.now = us > fx.now ? us : fx.now + 1u;
        next = co_ecat_slave_process(&sl, now_ns());
    }
    TEST_ASSERT_EQUAL(CO_CIA402_FAULT_REACTION_ACTIVE, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(CO_ECAT_AL_SM_WATCHDOG, al_code());
    /* watchdog 100 ms (0x0420 = 1000 ticks of 100 µs) + C100 0.1 s */
    TEST_ASSERT_UINT64_WITHIN(1000, last_cycle + 200000u, fx.now);
}

static void test_os_while_enabled_is_a_network_error(void)
{
    running_at(600);
    request(CO_ECAT_STATE_SAFEOP);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_SAFEOP, al_status());
    advance_us(99000);
    TEST_ASSERT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    advance_us(2000);
    TEST_ASSERT_NOT_EQUAL(CO_CIA402_OPERATION_ENABLED, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0x7520, fx_u16(&fx, 0x603F, 0));
}

static void test_sp_while_disabled_is_no_error(void)
{
    to_op();
    request(CO_ECAT_STATE_PREOP);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_PREOP, al_status());
    advance_us(500000);
    TEST_ASSERT_EQUAL(CO_CIA402_SWITCH_ON_DISABLED, fx.d.state);
    TEST_ASSERT_EQUAL_HEX16(0, fx_u16(&fx, 0x603F, 0));
}

/* ---- mailbox ---- */

static void test_mailbox_errors(void)
{
    uint8_t r[CO_ECAT_MBX_MAX], type = 0xFF;
    to_preop();
    const uint8_t foe[8] = {0};
    mbx_send(4, foe, 8); /* FoE: not supported */
    TEST_ASSERT_EQUAL_UINT16(4, mbx_receive(&type, r));
    TEST_ASSERT_EQUAL_UINT8(0, type);
    TEST_ASSERT_EQUAL_HEX16(0x0001, r[0] | (r[1] << 8));
    TEST_ASSERT_EQUAL_HEX16(0x0002, r[2] | (r[3] << 8));
    TEST_ASSERT_EQUAL_UINT16(1, mbx_send_raw(0, 3, 2, foe, 8)); /* length 0 */
    TEST_ASSERT_EQUAL_UINT16(4, mbx_receive(&type, r));
    TEST_ASSERT_EQUAL_HEX16(0x0005, r[2] | (r[3] << 8));
    TEST_ASSERT_EQUAL_UINT16(1, mbx_send_raw(123, 3, 3, foe, 8)); /* past the mailbox */
    TEST_ASSERT_EQUAL_UINT16(4, mbx_receive(&type, r));
    TEST_ASSERT_EQUAL_HEX16(0x0005, r[2] | (r[3] << 8));
    TEST_ASSERT_EQUAL_UINT16(1, mbx_send_raw(1, 3, 4, foe, 1)); /* CoE without its header */
    TEST_ASSERT_EQUAL_UINT16(4, mbx_receive(&type, r));
    TEST_ASSERT_EQUAL_HEX16(0x0006, r[2] | (r[3] << 8));
    const uint8_t short_sdo[4] = {0x00, 0x20, 0x40, 0x00};
    TEST_ASSERT_EQUAL_UINT16(1, mbx_send_raw(4, 3, 5, short_sdo, 4)); /* SDO of 2 bytes */
    TEST_ASSERT_EQUAL_UINT16(4, mbx_receive(&type, r));
    TEST_ASSERT_EQUAL_HEX16(0x0006, r[2] | (r[3] << 8));
    /* a repeated counter is the master's retry: dropped, not answered twice */
    const uint8_t rd[10] = {0x00, 0x20, 0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0};
    TEST_ASSERT_EQUAL_UINT16(1, mbx_send_raw(10, 3, 6, rd, 10));
    TEST_ASSERT_EQUAL_UINT16(10, mbx_receive(&type, r));
    TEST_ASSERT_EQUAL_UINT16(1, mbx_send_raw(10, 3, 6, rd, 10));
    TEST_ASSERT_EQUAL_UINT16(0, mbx_receive(&type, r));
    TEST_ASSERT_EQUAL_UINT32(1, sl.stats.mbx_dropped);
    /* no mailbox in INIT: SM0 is not even read */
    request(CO_ECAT_STATE_INIT);
    TEST_ASSERT_EQUAL_UINT16(1, mbx_send_raw(10, 3, 7, rd, 10));
    TEST_ASSERT_EQUAL_UINT16(0, mbx_receive(&type, r));
}

static void test_repeat_request_posts_the_last_answer_again(void)
{
    uint8_t r[CO_ECAT_MBX_MAX], r2[CO_ECAT_MBX_MAX];
    uint8_t act = 0;
    to_preop();
    const uint8_t q[8] = {0x40, 0x18, 0x10, 0x02, 0, 0, 0, 0};
    coe_send(2, q, 8);
    uint16_t n = coe_receive(r); /* the master "lost" this read */
    TEST_ASSERT_EQUAL_UINT16(0, mbx_receive(NULL, NULL));
    TEST_ASSERT_EQUAL_UINT16(1, aprd(CO_ESC_REG_SM_ACTIVATE(1), &act, 1));
    wr8(CO_ESC_REG_SM_ACTIVATE(1), (uint8_t)(act ^ 0x02)); /* toggle the repeat request */
    uint8_t pdi = 0;
    TEST_ASSERT_EQUAL_UINT16(1, aprd(CO_ESC_REG_SM_PDICTL(1), &pdi, 1));
    TEST_ASSERT_EQUAL_HEX8((act ^ 0x02) & 0x02, pdi & 0x02); /* acknowledged */
    TEST_ASSERT_EQUAL_UINT16(n, coe_receive(r2));
    TEST_ASSERT_EQUAL_MEMORY(r, r2, n);
    TEST_ASSERT_EQUAL_UINT32(1, sl.stats.mbx_repeats);
}

/* The master's read of an emergency was lost after the ESC had emptied SM1, and the slave has
 * already posted the SDO answer behind it: the repeat request brings the emergency back first,
 * then the answer. */
static void test_repeat_request_after_the_next_message_was_posted(void)
{
    uint8_t r[CO_ECAT_MBX_MAX];
    uint8_t act = 0;
    to_preop();
    (void)co_emcy_raise(&fx.d.node, 0xFF01u, CO_ERR_REG_MANUFACTURER, NULL);
    const uint8_t q[8] = {0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0};
    coe_send(2, q, 8); /* the emergency goes into SM1, the answer waits */
    TEST_ASSERT_EQUAL_UINT16(10, coe_receive(r)); /* read, but "lost" on the way back */
    TEST_ASSERT_EQUAL_UINT8(1, r[1] >> 4);
    TEST_ASSERT_EQUAL_UINT16(1, aprd(CO_ESC_REG_SM_ACTIVATE(1), &act, 1));
    wr8(CO_ESC_REG_SM_ACTIVATE(1), (uint8_t)(act ^ 0x02)); /* repeat request */
    TEST_ASSERT_EQUAL_UINT16(10, coe_receive(r));
    TEST_ASSERT_EQUAL_UINT8(1, r[1] >> 4); /* the emergency again */
    TEST_ASSERT_EQUAL_HEX16(0xFF01, r[2] | (r[3] << 8));
    TEST_ASSERT_EQUAL_UINT16(10, coe_receive(r));
    TEST_ASSERT_EQUAL_UINT8(3, r[1] >> 4); /* then the answer */
    TEST_ASSERT_EQUAL_HEX32(0x284, le32(r + 6));
    TEST_ASSERT_EQUAL_UINT16(0, mbx_receive(NULL, NULL));
}

/* ---- CoE SDO ---- */

static void test_sdo_expedited_and_aborts_as_over_can(void)
{
    uint8_t v[CO_ECAT_SDO_BUF];
    uint32_t len = 0;
    to_preop();
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_read(0x1018, 1, false, v, &len));
    TEST_ASSERT_EQUAL_UINT32(4, len);
    TEST_ASSERT_EQUAL_HEX32(0x284, le32(v));
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_read(0x1018, 2, false, v, &len));
    TEST_ASSERT_EQUAL_HEX32(0xE1, le32(v));
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_write_exp(0x6042, 0, 1200, 2));
    TEST_ASSERT_EQUAL_INT16(1200, fx_i16(&fx, 0x6042, 0));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_OBJECT, ec_sdo_read(0x1234, 0, false, v, &len));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_SUBINDEX, ec_sdo_read(0x1018, 9, false, v, &len));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_READ_ONLY, ec_sdo_write_exp(0x1018, 1, 1, 4));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_TYPE_TOO_LONG, ec_sdo_write_exp(0x6042, 0, 1, 4));
    TEST_ASSERT_EQUAL_INT16(1200, fx_i16(&fx, 0x6042, 0)); /* untouched */
    const uint8_t bad[8] = {0xE0, 0x42, 0x60, 0, 0, 0, 0, 0};
    uint8_t r[CO_ECAT_MBX_MAX];
    coe_send(2, bad, 8); /* command specifier 7 */
    coe_receive(r);
    TEST_ASSERT_EQUAL_HEX8(0x80, r[2]);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_COMMAND, le32(r + 6));
    /* 0x1C00/0x1C12/0x1C13 as SOEM's config_map reads them */
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_read(0x1C00, 0, false, v, &len));
    TEST_ASSERT_EQUAL_UINT32(1, len);
    TEST_ASSERT_EQUAL_UINT8(4, v[0]);
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_read(0x1C00, 3, false, v, &len));
    TEST_ASSERT_EQUAL_UINT8(3, v[0]);
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_read(0x1C13, 1, false, v, &len));
    TEST_ASSERT_EQUAL_UINT32(2, len);
    TEST_ASSERT_EQUAL_HEX16(0x1A00, v[0] | (v[1] << 8));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_READ_ONLY, ec_sdo_write_exp(0x1C12, 1, 0x1601, 2));
}

static void test_sdo_normal_and_segmented(void)
{
    uint8_t v[CO_ECAT_SDO_BUF];
    uint32_t len = 0;
    to_preop();
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_read(0x1008, 0, false, v, &len)); /* normal upload */
    TEST_ASSERT_EQUAL_UINT32(6, len);
    TEST_ASSERT_EQUAL_MEMORY("VF-MB1", v, 6);
    /* segmented download: initiate with the size only, then 7-byte segments */
    const uint8_t speed[2] = {0x34, 0x02};
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_write(0x6042, 0, false, speed, 2, 0));
    TEST_ASSERT_EQUAL_INT16(0x234, fx_i16(&fx, 0x6042, 0));
    /* a value that is too long, segmented: aborted, nothing written */
    const uint8_t three[3] = {1, 2, 3};
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_TYPE_TOO_LONG, ec_sdo_write(0x6042, 0, false, three, 3, 0));
    TEST_ASSERT_EQUAL_INT16(0x234, fx_i16(&fx, 0x6042, 0));
    /* a size beyond any object: too long, or no such object */
    uint8_t big[8] = {0x21, 0x42, 0x60, 0, 0x00, 0x10, 0, 0}, ans[CO_ECAT_MBX_MAX];
    coe_send(2, big, 8);
    coe_answer(ans);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_TYPE_TOO_LONG, le32(ans + 6));
    big[1] = 0x34;
    big[2] = 0x12;
    coe_send(2, big, 8);
    coe_answer(ans);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_OBJECT, le32(ans + 6));
    /* a wrong toggle */
    uint8_t q[8] = {0x21, 0x42, 0x60, 0, 2, 0, 0, 0}, r[CO_ECAT_MBX_MAX];
    coe_send(2, q, 8);
    coe_receive(r);
    uint8_t seg[8] = {0x10 | 0x01 | (5 << 1), 9, 9, 0, 0, 0, 0, 0};
    coe_send(2, seg, 8);
    coe_receive(r);
    TEST_ASSERT_EQUAL_HEX8(0x80, r[2]);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_TOGGLE, le32(r + 6));
    TEST_ASSERT_EQUAL_INT16(0x234, fx_i16(&fx, 0x6042, 0));
}

static void test_segmented_upload_through_a_small_mailbox(void)
{
    uint8_t v[CO_ECAT_SDO_BUF];
    uint32_t len = 0;
    start_with_mailbox(32); /* 16 data bytes in a normal upload, 23 per segment */
    to_preop();
    /* 0x1003 by complete access: count, pad, 16 entries of 4 bytes = 66 bytes */
        TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x1B, fx.now)); /* an entry to find */
    advance_us(1000);
    (void)mbx_receive(NULL, NULL); /* the emergency */
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_read(0x1003, 0, true, v, &len));
    TEST_ASSERT_EQUAL_UINT32(2u + 4u * v[0], len);
    TEST_ASSERT_EQUAL_HEX16(0x7520, v[2] | (v[3] << 8));
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_read(0x1008, 0, false, v, &len));
    TEST_ASSERT_EQUAL_MEMORY("VF-MB1", v, 6);
}

static void test_complete_access(void)
{
    uint8_t v[CO_ECAT_SDO_BUF];
    uint32_t len = 0;
    to_preop();
    /* an entry that cannot be mapped, before anything else: refused, and RPDO1 stays valid */
    const uint8_t unmappable[6] = {1, 0, 0x10, 0x00, 0x18, 0x10};
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_READ_ONLY, ec_sdo_write(0x1018, 0, true, unmappable, 6, 100));
    TEST_ASSERT_NOT_EQUAL(0, ec_sdo_write(0x1600, 0, true, unmappable, 6, 100));
    TEST_ASSERT_EQUAL_HEX32(0, fx_u32(&fx, 0x1400, 1) & 0x80000000u);
    TEST_ASSERT_EQUAL_HEX32(0x60400010, fx_u32(&fx, 0x1600, 1));
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_read(0x1C12, 0, true, v, &len));
    const uint8_t assign[4] = {1, 0, 0x00, 0x16};
    TEST_ASSERT_EQUAL_UINT32(4, len);
    TEST_ASSERT_EQUAL_MEMORY(assign, v, 4);
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_read(0x1600, 0, true, v, &len));
    const uint8_t map[10] = {2, 0, 0x10, 0x00, 0x40, 0x60, 0x10, 0x00, 0x42, 0x60};
    TEST_ASSERT_EQUAL_UINT32(10, len);
    TEST_ASSERT_EQUAL_MEMORY(map, v, 10);
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_read(0x1018, 1, true, v, &len)); /* from sub 1 */
    TEST_ASSERT_EQUAL_UINT32(16, len);
    TEST_ASSERT_EQUAL_HEX32(0x284, le32(v));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_UNSUPPORTED_ACCESS, ec_sdo_read(0x1018, 2, true, v, &len));
    /* download: the mapping swapped (target first) */
    const uint8_t swapped[10] = {2, 0, 0x10, 0x00, 0x42, 0x60, 0x10, 0x00, 0x40, 0x60};
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_write(0x1600, 0, true, swapped, 10, 100));
    TEST_ASSERT_EQUAL_HEX32(0x60420010, fx_u32(&fx, 0x1600, 1));
    TEST_ASSERT_EQUAL_HEX32(0x60400010, fx_u32(&fx, 0x1600, 2));
    TEST_ASSERT_EQUAL_UINT8(2, fx_u8(&fx, 0x1600, 0));
    /* an entry that cannot be mapped: refused before anything is written */
    const uint8_t bad[6] = {1, 0, 0x10, 0x00, 0x18, 0x10};
    TEST_ASSERT_NOT_EQUAL(0, ec_sdo_write(0x1600, 0, true, bad, 6, 100));
    TEST_ASSERT_EQUAL_HEX32(0x60420010, fx_u32(&fx, 0x1600, 1));
    /* lengths that do not add up */
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_TYPE_TOO_SHORT, ec_sdo_write(0x1600, 0, true, swapped, 8, 100));
    TEST_ASSERT_EQUAL_HEX32(0x60420010, fx_u32(&fx, 0x1600, 1));
}

/* ---- SDO information ---- */

static void test_sdo_information(void)
{
    uint8_t r[CO_ECAT_MBX_MAX];
    to_preop();
    /* OD list, all objects, in fragments read back to back */
    const uint8_t list[6] = {0x01, 0, 0, 0, 0x01, 0x00};
    coe_send(8, list, 6);
    uint32_t count = 0;
    uint16_t prev = 0;
    bool saw_1c12 = false, first = true;
    for (int guard = 0; guard < 100; guard++) {
        uint16_t n = coe_receive(r);
        TEST_ASSERT_EQUAL_UINT8(8, r[1] >> 4);
        TEST_ASSERT_EQUAL_HEX8(0x02, r[2] & 0x7F);
        uint32_t at = first ? 8u : 6u;
        if (first) {
            TEST_ASSERT_EQUAL_HEX16(1, r[6] | (r[7] << 8));
        }
        for (; at + 1u < n; at += 2u) {
            uint16_t index = (uint16_t)(r[at] | (r[at + 1] << 8));
            TEST_ASSERT_TRUE(first && count == 0 ? true : index > prev);
            saw_1c12 |= index == 0x1C12u;
            prev = index;
            count++;
        }
        first = false;
        uint16_t left = (uint16_t)(r[4] | (r[5] << 8));
        TEST_ASSERT_EQUAL(left != 0, (r[2] & 0x80) != 0);
        if (left == 0) {
            break;
        }
    }
    TEST_ASSERT_EQUAL_UINT32(fx.d.node.od->entry_count + 3u, count);
    TEST_ASSERT_TRUE(saw_1c12);
    /* object description of 0x1018 */
    const uint8_t obj[6] = {0x03, 0, 0, 0, 0x18, 0x10};
    coe_send(8, obj, 6);
    uint16_t n = coe_receive(r);
    TEST_ASSERT_EQUAL_HEX8(0x04, r[2]);
    TEST_ASSERT_EQUAL_HEX16(0x1018, r[6] | (r[7] << 8));
    TEST_ASSERT_EQUAL_UINT8(4, r[10]); /* max sub */
    TEST_ASSERT_EQUAL_UINT8(CO_OBJ_RECORD, r[11]);
    /* no name tables in the config: the index in hex */
    TEST_ASSERT_EQUAL_UINT16(2u + 4u + 6u + 6u, n);
    TEST_ASSERT_EQUAL_MEMORY("0x1018", r + 12, 6);
    /* entry description of 0x6040:00, value info 0x07 as SOEM asks */
    const uint8_t ent[8] = {0x05, 0, 0, 0, 0x40, 0x60, 0x00, 0x07};
    coe_send(8, ent, 8);
    coe_receive(r);
    TEST_ASSERT_EQUAL_HEX8(0x06, r[2]);
    TEST_ASSERT_EQUAL_HEX16(CO_UNSIGNED16, r[10] | (r[11] << 8));
    TEST_ASSERT_EQUAL_UINT16(16, r[12] | (r[13] << 8));
    TEST_ASSERT_EQUAL_HEX16(0x0040, (r[14] | (r[15] << 8)) & 0x0040); /* RxPDO-mappable */
    TEST_ASSERT_EQUAL_HEX16(0x003F, (r[14] | (r[15] << 8)) & 0x003F); /* rw in every state */
    /* an unknown object: SDO information error */
    const uint8_t none[6] = {0x03, 0, 0, 0, 0x34, 0x12};
    coe_send(8, none, 6);
    coe_receive(r);
    TEST_ASSERT_EQUAL_HEX8(0x07, r[2]);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_OBJECT, le32(r + 6));
}

#if !defined(CO_OD_NO_NAMES)
/* The description of index:sub (sub < 0: the object's) with the EDS name tables in the config;
 * the name's length in *len, the name at the returned offset of r. */
static uint32_t described_name(uint8_t *r, uint16_t index, int sub, uint16_t *len)
{
    uint8_t req[8] = {sub < 0 ? 0x03 : 0x05, 0, 0, 0, (uint8_t)index, (uint8_t)(index >> 8),
                      (uint8_t)(sub < 0 ? 0 : sub), 0x07};
    coe_send(8, req, sub < 0 ? 6u : 8u);
    uint16_t n = coe_receive(r);
    TEST_ASSERT_EQUAL_HEX8(sub < 0 ? 0x04 : 0x06, r[2]);
    uint32_t at = sub < 0 ? 12u : 16u;
    *len = (uint16_t)(n - at);
    return at;
}

static void test_sdo_information_names_from_the_eds(void)
{
    uint8_t r[CO_ECAT_MBX_MAX];
    uint16_t len;
    uint32_t at;
    start_with_mailbox(128);
    sl.cfg.entry_names = co_od_vf_mb1_ecat_entry_names;
    sl.cfg.sub_names = co_od_vf_mb1_ecat_sub_names;
    to_preop();
    /* vf-mb1-ecat.eds: [1018] ParameterName=Identity object, [1018sub2] Product code, [1008]
     * Manufacturer device name */
    at = described_name(r, 0x1018, -1, &len);
    TEST_ASSERT_EQUAL_UINT16(strlen("Identity object"), len);
    TEST_ASSERT_EQUAL_MEMORY("Identity object", r + at, len);
    at = described_name(r, 0x1018, 2, &len);
    TEST_ASSERT_EQUAL_UINT16(strlen("Product code"), len);
    TEST_ASSERT_EQUAL_MEMORY("Product code", r + at, len);
    at = described_name(r, 0x1008, 0, &len);
    TEST_ASSERT_EQUAL_UINT16(strlen("Manufacturer device name"), len);
    TEST_ASSERT_EQUAL_MEMORY("Manufacturer device name", r + at, len);
    /* the objects the slave layer adds have no EDS name: the index in hex */
    at = described_name(r, 0x1C12, -1, &len);
    TEST_ASSERT_EQUAL_UINT16(6, len);
    TEST_ASSERT_EQUAL_MEMORY("0x1C12", r + at, len);
    /* a 32-byte SM1 has room for 14 bytes of name after the object description's fixed part
     * (6 mailbox + 2 CoE + 4 SDO information + 6): the name is cut, the reply still sent */
    start_with_mailbox(32);
    sl.cfg.entry_names = co_od_vf_mb1_ecat_entry_names;
    to_preop();
    at = described_name(r, 0x1018, -1, &len);
    TEST_ASSERT_EQUAL_UINT16(14, len);
    TEST_ASSERT_EQUAL_MEMORY("Identity objec", r + at, len);
}
#endif

/* ---- emergency, F899 ---- */

static void test_every_emcy_becomes_a_coe_emergency(void)
{
    uint8_t r[CO_ECAT_MBX_MAX];
    to_preop();
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x1B, fx.now)); /* Err8 */
    advance_us(1000);
    TEST_ASSERT_EQUAL_UINT16(10, coe_receive(r));
    TEST_ASSERT_EQUAL_UINT8(1, r[1] >> 4); /* emergency */
    TEST_ASSERT_EQUAL_HEX16(0x7520, r[2] | (r[3] << 8));
    TEST_ASSERT_EQUAL_HEX8(fx_u8(&fx, 0x1001, 0), r[4]);
    TEST_ASSERT_NOT_EQUAL(0, r[4]);
    TEST_ASSERT_EQUAL_HEX8(0x1B, r[5]); /* trip code byte (C33) */
    TEST_ASSERT_EQUAL_HEX16(0x7520, fx_u16(&fx, 0x603F, 0));
    /* the fault reset: the error-reset emergency */
    co_drive_clear_fault_cause(&fx.d);
    TEST_ASSERT_TRUE(co_drive_fault_reset(&fx.d, fx.now));
    advance_us(1000);
    TEST_ASSERT_EQUAL_UINT16(10, coe_receive(r));
    TEST_ASSERT_EQUAL_HEX16(0x0000, r[2] | (r[3] << 8));
}

/* Emergencies the master does not read fill the queue up to its last slot only: the answer to
 * the next request still gets through, behind them. */
static void test_unread_emergencies_leave_room_for_the_answer(void)
{
    uint8_t v[CO_ECAT_SDO_BUF];
    uint32_t len = 0;
    to_preop();
    for (uint16_t i = 0; i < 6; i++) {
        (void)co_emcy_raise(&fx.d.node, (uint16_t)(0xFF00u + i), CO_ERR_REG_MANUFACTURER, NULL);
    }
    TEST_ASSERT_EQUAL_UINT32(CO_ECAT_TX_QUEUE - 1u, sl.queue_count);
    TEST_ASSERT_EQUAL_UINT32(6u - (CO_ECAT_TX_QUEUE - 1u), sl.stats.mbx_lost);
    emergencies_skipped = 0;
    TEST_ASSERT_EQUAL_HEX32(0, ec_sdo_read(0x1018, 1, false, v, &len));
    TEST_ASSERT_EQUAL_HEX32(0x284, le32(v));
    TEST_ASSERT_EQUAL_UINT32(CO_ECAT_TX_QUEUE - 1u, emergencies_skipped);
}

static void test_f899_resets_communication_and_applies_the_profile(void)
{
    uint16_t sw = 0;
    to_preop();
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x1B, fx.now));
    advance_us(1000);
    co_drive_clear_fault_cause(&fx.d);
    TEST_ASSERT_TRUE(co_drive_fault_reset(&fx.d, fx.now));
    TEST_ASSERT_TRUE(fx_u8(&fx, 0x1003, 0) > 0u);
    TEST_ASSERT_EQUAL_HEX16(0x0040, fx_sw(&fx)); /* not remote */
    cia402_profile(); /* C003 = 4, F004 = 7, F899 = 1 */
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x2899, 0)); /* after execution: 0 */
    TEST_ASSERT_EQUAL_UINT8(0, fx_u8(&fx, 0x1003, 0)); /* §4.1 note */
    TEST_ASSERT_EQUAL_HEX16(0x0240, fx_sw(&fx)); /* the CiA 402 profile is in effect */
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_PREOP, al_status()); /* the link keeps its state */
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, fx.d.node.nmt_state);
    config_process_data(4, 4);
    request(CO_ECAT_STATE_SAFEOP);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_SAFEOP, al_status());
    cycle(0x0006, 0, &sw, NULL);
    request(CO_ECAT_STATE_OP);
    TEST_ASSERT_EQUAL_HEX8(CO_ECAT_STATE_OP, al_status());
    TEST_ASSERT_EQUAL_HEX16(0x0006, fx_u16(&fx, 0x6040, 0));
    cycle(0x0006, 0, &sw, NULL);
    TEST_ASSERT_EQUAL_HEX16(0x0221, sw);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_power_on_is_init_and_node_stopped);
    RUN_TEST(test_preop_needs_the_mailbox_sync_managers);
    RUN_TEST(test_refused_requests_and_their_codes);
    RUN_TEST(test_safeop_needs_process_data_sync_managers_as_mapped);
    RUN_TEST(test_a_mapping_change_in_preop_changes_the_sm_lengths);
    RUN_TEST(test_op_waits_for_valid_outputs_then_gives_up_with_0x001B);
    RUN_TEST(test_outputs_reach_the_drive_in_op_only_inputs_from_safeop);
    RUN_TEST(test_repeated_outputs_run_the_drive_only_when_something_reached_it);
    RUN_TEST(test_sm_watchdog_leaves_op_and_trips_err8);
    RUN_TEST(test_returned_deadlines_carry_the_watchdog_and_the_drive);
    RUN_TEST(test_os_while_enabled_is_a_network_error);
    RUN_TEST(test_sp_while_disabled_is_no_error);
    RUN_TEST(test_mailbox_errors);
    RUN_TEST(test_repeat_request_posts_the_last_answer_again);
    RUN_TEST(test_repeat_request_after_the_next_message_was_posted);
    RUN_TEST(test_sdo_expedited_and_aborts_as_over_can);
    RUN_TEST(test_sdo_normal_and_segmented);
    RUN_TEST(test_segmented_upload_through_a_small_mailbox);
    RUN_TEST(test_complete_access);
    RUN_TEST(test_sdo_information);
#if !defined(CO_OD_NO_NAMES)
    RUN_TEST(test_sdo_information_names_from_the_eds);
#endif
    RUN_TEST(test_every_emcy_becomes_a_coe_emergency);
    RUN_TEST(test_unread_emergencies_leave_room_for_the_answer);
    RUN_TEST(test_f899_resets_communication_and_applies_the_profile);
    return UNITY_END();
}
