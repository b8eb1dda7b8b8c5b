#include "test_support.h"

#include <string.h>

#include "od_test.h"
#include "unity.h"

static bool fake_send(void *ctx, const co_frame *frame)
{
    fake_bus *bus = ctx;
    if (bus->refuse) {
        return false;
    }
    if (bus->count < FAKE_CAPTURE_MAX) {
        bus->frames[bus->count] = *frame;
    }
    bus->count++;
    return true;
}

co_driver fake_bus_driver(fake_bus *bus)
{
    co_driver d = {fake_send, bus};
    return d;
}

const co_frame *fake_bus_next(fake_bus *bus)
{
    if (bus->read >= bus->count || bus->read >= FAKE_CAPTURE_MAX) {
        return NULL;
    }
    return &bus->frames[bus->read++];
}

uint32_t fake_bus_pending(const fake_bus *bus)
{
    return bus->count - bus->read;
}

void fake_bus_clear(fake_bus *bus)
{
    bus->read = bus->count;
}

static bool store_load(void *ctx, uint32_t hash, uint32_t offset, uint8_t *buf, uint32_t len)
{
    fake_store *s = ctx;
    if (!s->valid || s->layout_hash != hash || (uint64_t)offset + len > s->len) {
        return false;
    }
    memcpy(buf, s->image + offset, len);
    return true;
}

static bool store_save(void *ctx, uint32_t hash, const uint8_t *image, uint32_t len)
{
    fake_store *s = ctx;
    if (s->fail_save || len > sizeof s->image) {
        return false;
    }
    memcpy(s->image, image, len);
    s->len = len;
    s->layout_hash = hash;
    s->valid = true;
    s->saves++;
    return true;
}

static bool store_erase(void *ctx)
{
    fake_store *s = ctx;
    s->valid = false;
    return true;
}

co_storage fake_store_storage(fake_store *store)
{
    co_storage st = {store_load, store_save, store_erase, store};
    return st;
}

void test_node_init(test_node *t, uint8_t node_id)
{
    memset(t, 0, sizeof *t);
    TEST_ASSERT_TRUE(co_od_test.value_size <= sizeof t->values);
    t->storage = fake_store_storage(&t->store);
    co_node_config cfg = co_node_default_config();
    cfg.od = &co_od_test;
    cfg.values = t->values;
    cfg.node_id = node_id;
    cfg.driver = fake_bus_driver(&t->bus);
    cfg.storage = &t->storage;
    TEST_ASSERT_TRUE(co_node_init(&t->node, &cfg));
}

void test_node_start(test_node *t, uint8_t node_id)
{
    test_node_init(t, node_id);
    co_node_start(&t->node, t->now);
}

void test_rx(test_node *t, uint16_t id, uint8_t dlc, const uint8_t *data)
{
    co_frame f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.dlc = dlc;
    if (data != NULL && dlc <= 8u) {
        memcpy(f.data, data, dlc);
    }
    co_node_rx(&t->node, &f, t->now);
}

void test_rx8(test_node *t, uint16_t id, uint8_t b0, uint8_t b1, uint8_t b2, uint8_t b3,
              uint8_t b4, uint8_t b5, uint8_t b6, uint8_t b7)
{
    const uint8_t d[8] = {b0, b1, b2, b3, b4, b5, b6, b7};
    test_rx(t, id, 8, d);
}

uint64_t test_advance(test_node *t, uint64_t us)
{
    t->now += us;
    return co_node_process(&t->node, t->now);
}

void expect_frame(test_node *t, uint16_t id, uint8_t dlc, const uint8_t *data)
{
    const co_frame *f = fake_bus_next(&t->bus);
    TEST_ASSERT_NOT_NULL_MESSAGE(f, "expected a frame, none was sent");
    TEST_ASSERT_EQUAL_HEX16(id, f->id);
    TEST_ASSERT_EQUAL_UINT8(dlc, f->dlc);
    if (dlc > 0u && data != NULL) {
        TEST_ASSERT_EQUAL_HEX8_ARRAY(data, f->data, dlc);
    }
}

void expect_no_frame(test_node *t)
{
    TEST_ASSERT_EQUAL_UINT32_MESSAGE(0u, fake_bus_pending(&t->bus), "unexpected frame sent");
}

uint32_t sdo_read_u32(test_node *t, uint16_t index, uint8_t sub, uint32_t *value)
{
    test_rx8(t, (uint16_t)(0x600u + t->node.node_id), 0x40, (uint8_t)index, (uint8_t)(index >> 8),
             sub, 0, 0, 0, 0);
    const co_frame *f = fake_bus_next(&t->bus);
    TEST_ASSERT_NOT_NULL_MESSAGE(f, "no SDO response");
    TEST_ASSERT_EQUAL_HEX16(0x580u + t->node.node_id, f->id);
    if (f->data[0] == 0x80u) {
        return co_get_le32(&f->data[4]);
    }
    *value = co_get_le32(&f->data[4]);
    return 0;
}

void sdo_req(test_node *t, uint8_t b0, uint8_t b1, uint8_t b2, uint8_t b3, uint8_t b4, uint8_t b5,
             uint8_t b6, uint8_t b7)
{
    test_rx8(t, (uint16_t)(0x600u + t->node.node_id), b0, b1, b2, b3, b4, b5, b6, b7);
}

void sdo_expect(test_node *t, uint8_t b0, uint8_t b1, uint8_t b2, uint8_t b3, uint8_t b4,
                uint8_t b5, uint8_t b6, uint8_t b7)
{
    const uint8_t d[8] = {b0, b1, b2, b3, b4, b5, b6, b7};
    expect_frame(t, (uint16_t)(0x580u + t->node.node_id), 8, d);
}

void sdo_expect_abort(test_node *t, uint16_t index, uint8_t sub, uint32_t code)
{
    sdo_expect(t, 0x80, (uint8_t)index, (uint8_t)(index >> 8), sub, (uint8_t)code,
               (uint8_t)(code >> 8), (uint8_t)(code >> 16), (uint8_t)(code >> 24));
    expect_no_frame(t);
}

const uint8_t *test_value_of(test_node *t, uint16_t index, uint8_t sub)
{
    co_od_ref ref;
    TEST_ASSERT_EQUAL_HEX32(0, co_od_locate(t->node.od, index, sub, &ref));
    return co_od_value_ptr(&t->node, ref);
}

void test_values_snapshot(test_node *t)
{
    memcpy(t->values_before, t->values, sizeof t->values_before);
}

void test_expect_values_unchanged(test_node *t)
{
    TEST_ASSERT_EQUAL_MEMORY(t->values_before, t->values, sizeof t->values);
}

uint32_t sdo_write(test_node *t, uint16_t index, uint8_t sub, uint32_t value, uint8_t size)
{
    uint8_t d[8] = {(uint8_t)(0x23u | ((4u - size) << 2)), (uint8_t)index, (uint8_t)(index >> 8),
                    sub, 0, 0, 0, 0};
    co_put_le32(&d[4], value);
    if (size < 4u) { /* bytes beyond the size are not part of the value */
        memset(&d[4 + size], 0, 4u - size);
    }
    test_rx(t, (uint16_t)(0x600u + t->node.node_id), 8, d);
    const co_frame *f = fake_bus_next(&t->bus);
    TEST_ASSERT_NOT_NULL_MESSAGE(f, "no SDO response");
    if (f->data[0] == 0x80u) {
        return co_get_le32(&f->data[4]);
    }
    TEST_ASSERT_EQUAL_HEX8(0x60, f->data[0]);
    return 0;
}
