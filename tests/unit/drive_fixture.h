/* Drive unit tests: one drive (co_drive) on the fake bus of test_support, a virtual clock that
 * only moves when the test moves it, and expedited SDO / PDO / NMT helpers on the wire.
 * Header-only (static inline) so each test_drive_*.c and test_cia402.c includes what it uses. */
#ifndef DRIVE_FIXTURE_H
#define DRIVE_FIXTURE_H

#include <string.h>

#include "canopen/drive.h"
#include "test_support.h"
#include "unity.h"

typedef struct drive_fx {
    co_drive d;
    fake_bus bus;
    uint64_t now;
    uint64_t next;          /* the drive's last deadline */
    uint8_t id;
    uint8_t values[8192];
} drive_fx;

/* Sets up fx as a drive of kind desc with node-ID id and starts it at t = 0 (boot-up on the bus). */
static inline void fx_start(drive_fx *fx, const co_drive_desc *desc, uint8_t id)
{
    memset(fx, 0, sizeof *fx);
    TEST_ASSERT_NOT_NULL(desc);
    TEST_ASSERT_TRUE(desc->od->value_size <= sizeof fx->values);
    co_node_config cfg = co_node_default_config();
    cfg.node_id = id;
    cfg.values = fx->values;
    cfg.driver = fake_bus_driver(&fx->bus);
    TEST_ASSERT_TRUE(co_drive_init(&fx->d, desc, &cfg));
    fx->id = id;
    co_drive_start(&fx->d, 0);
    fx->next = co_drive_process(&fx->d, 0);
}

/* Runs the drive at every deadline it asks for up to now + us, then at now + us. */
static inline void fx_advance(drive_fx *fx, uint64_t us)
{
    uint64_t end = fx->now + us;
    for (int guard = 0; guard < 100000000; guard++) {
        uint64_t next = co_drive_process(&fx->d, fx->now);
        fx->next = next;
        if (next > end) {
            break;
        }
        fx->now = next > fx->now ? next : fx->now + 1u;
    }
    fx->now = end;
    fx->next = co_drive_process(&fx->d, end);
}

/* Moves the clock to the absolute time t (>= now). */
static inline void fx_at(drive_fx *fx, uint64_t t)
{
    TEST_ASSERT_TRUE(t >= fx->now);
    fx_advance(fx, t - fx->now);
}

/* A port on a silent bus: co_drive_process is called only at the deadlines it returns (as the
 * Linux loop does), never in between, until `end`. A reaction whose deadline is not returned is
 * never run. */
static inline void fx_wake_at_deadlines(drive_fx *fx, uint64_t end)
{
    for (int guard = 0; guard < 100000000 && fx->next <= end; guard++) {
        fx->now = fx->next > fx->now ? fx->next : fx->now + 1u;
        fx->next = co_drive_process(&fx->d, fx->now);
    }
}

static inline void fx_rx(drive_fx *fx, uint16_t cob, uint8_t dlc, const uint8_t *data)
{
    co_frame f;
    memset(&f, 0, sizeof f);
    f.id = cob;
    f.dlc = dlc;
    if (data != NULL) {
        memcpy(f.data, data, dlc);
    }
    co_drive_rx(&fx->d, &f, fx->now);
    fx->next = co_drive_process(&fx->d, fx->now);
}

static inline void fx_rtr(drive_fx *fx, uint16_t cob)
{
    co_frame f;
    memset(&f, 0, sizeof f);
    f.id = cob;
    f.flags = CO_FRAME_RTR;
    co_drive_rx(&fx->d, &f, fx->now);
    fx->next = co_drive_process(&fx->d, fx->now);
}

static inline void fx_nmt(drive_fx *fx, uint8_t command)
{
    const uint8_t b[2] = {command, fx->id};
    fx_rx(fx, 0x000, 2, b);
}

/* The newest captured frame with this CAN-ID sent since the last fx_clear (NULL if none). */
static inline const co_frame *fx_last(drive_fx *fx, uint16_t cob)
{
    for (uint32_t i = fx->bus.count; i > fx->bus.read; i--) {
        if (i - 1u < FAKE_CAPTURE_MAX && fx->bus.frames[i - 1u].id == cob) {
            return &fx->bus.frames[i - 1u];
        }
    }
    return NULL;
}

/* Frames with this CAN-ID sent since the last fx_clear. */
static inline uint32_t fx_count(drive_fx *fx, uint16_t cob)
{
    uint32_t n = 0;
    for (uint32_t i = fx->bus.read; i < fx->bus.count && i < FAKE_CAPTURE_MAX; i++) {
        n += fx->bus.frames[i].id == cob ? 1u : 0u;
    }
    return n;
}

static inline void fx_clear(drive_fx *fx)
{
    fake_bus_clear(&fx->bus);
}

/* An SDO expedited download of size (1, 2, 4) bytes; returns the abort code (0: success). */
static inline uint32_t fx_sdo_write(drive_fx *fx, uint16_t index, uint8_t sub, uint32_t value,
                                    uint8_t size)
{
    uint8_t cmd = (uint8_t)(0x23u | ((4u - size) << 2));
    const uint8_t req[8] = {cmd, (uint8_t)index, (uint8_t)(index >> 8), sub, (uint8_t)value,
                            (uint8_t)(value >> 8), (uint8_t)(value >> 16), (uint8_t)(value >> 24)};
    uint32_t mark = fx->bus.count;
    fx_rx(fx, (uint16_t)(0x600u + fx->id), 8, req);
    for (uint32_t i = mark; i < fx->bus.count && i < FAKE_CAPTURE_MAX; i++) {
        const co_frame *f = &fx->bus.frames[i];
        if (f->id == 0x580u + fx->id) {
            if (f->data[0] == 0x80u) {
                return (uint32_t)f->data[4] | ((uint32_t)f->data[5] << 8) |
                       ((uint32_t)f->data[6] << 16) | ((uint32_t)f->data[7] << 24);
            }
            TEST_ASSERT_EQUAL_HEX8(0x60, f->data[0]);
            return 0;
        }
    }
    TEST_FAIL_MESSAGE("no SDO response");
    return 0xFFFFFFFFu;
}

/* An SDO expedited upload; returns the abort code and the value (zero-extended) in *value. */
static inline uint32_t fx_sdo_read(drive_fx *fx, uint16_t index, uint8_t sub, uint32_t *value)
{
    const uint8_t req[8] = {0x40, (uint8_t)index, (uint8_t)(index >> 8), sub, 0, 0, 0, 0};
    uint32_t mark = fx->bus.count;
    fx_rx(fx, (uint16_t)(0x600u + fx->id), 8, req);
    for (uint32_t i = mark; i < fx->bus.count && i < FAKE_CAPTURE_MAX; i++) {
        const co_frame *f = &fx->bus.frames[i];
        if (f->id == 0x580u + fx->id) {
            uint32_t v = (uint32_t)f->data[4] | ((uint32_t)f->data[5] << 8) |
                         ((uint32_t)f->data[6] << 16) | ((uint32_t)f->data[7] << 24);
            if (f->data[0] == 0x80u) {
                return v;
            }
            uint32_t n = (f->data[0] & 0x02u) != 0u ? 4u - ((f->data[0] >> 2) & 3u) : 4u;
            *value = n >= 4u ? v : (v & ((1u << (8u * n)) - 1u));
            return 0;
        }
    }
    TEST_FAIL_MESSAGE("no SDO response");
    return 0xFFFFFFFFu;
}

/* Controlword by SDO; asserts success. */
static inline void fx_cw(drive_fx *fx, uint16_t cw)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(fx, 0x6040, 0, cw, 2));
}

static inline void fx_target(drive_fx *fx, int16_t rpm)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(fx, 0x6042, 0, (uint16_t)rpm, 2));
}

/* Values as the dictionary holds them. */
static inline uint16_t fx_u16(drive_fx *fx, uint16_t index, uint8_t sub)
{
    return co_od_get_u16(&fx->d.node, index, sub);
}

static inline int16_t fx_i16(drive_fx *fx, uint16_t index, uint8_t sub)
{
    return co_od_get_i16(&fx->d.node, index, sub);
}

static inline uint32_t fx_u32(drive_fx *fx, uint16_t index, uint8_t sub)
{
    return co_od_get_u32(&fx->d.node, index, sub);
}

static inline uint8_t fx_u8(drive_fx *fx, uint16_t index, uint8_t sub)
{
    return co_od_get_u8(&fx->d.node, index, sub);
}

static inline uint16_t fx_sw(drive_fx *fx)
{
    return fx_u16(fx, 0x6041, 0);
}

/* Asserts the last EMCY since fx_clear: code, error register, manufacturer byte 3. */
static inline void fx_expect_emcy(drive_fx *fx, uint16_t code, uint8_t reg, uint8_t b3)
{
    const co_frame *f = fx_last(fx, (uint16_t)(0x80u + fx->id));
    TEST_ASSERT_NOT_NULL_MESSAGE(f, "no EMCY sent");
    TEST_ASSERT_EQUAL_UINT8(8, f->dlc);
    TEST_ASSERT_EQUAL_HEX16(code, (uint16_t)(f->data[0] | (f->data[1] << 8)));
    TEST_ASSERT_EQUAL_HEX8(reg, f->data[2]);
    TEST_ASSERT_EQUAL_HEX8(b3, f->data[3]);
}

/* 0x6042 in -> Operation enabled with the usual sequence (0x0006, 0x0007, 0x000F). */
static inline void fx_enable(drive_fx *fx)
{
    fx_cw(fx, 0x0006);
    fx_cw(fx, 0x0007);
    fx_cw(fx, 0x000F);
}

#endif
