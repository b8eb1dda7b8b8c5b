/* Store 0x1010 / restore 0x1011 with the fake storage: signatures (and their wire bytes), wrong
 * signatures and failing storage change nothing, round trips through reset node and reset
 * communication, restore taking effect only at the next reset, the partial groups (sub 2-4)
 * merged into the stored image, and a node without storage. */
#include <string.h>

#include "canopen/store.h"
#include "od_test.h"
#include "test_support.h"
#include "unity.h"

static test_node t;
static uint8_t scratch[4096];

#define SAVE 0x65766173u
#define LOAD 0x64616F6Cu

void setUp(void)
{
    test_node_start(&t, 5);
    t.node.store_scratch = scratch;
    t.node.store_scratch_size = sizeof scratch;
    fake_bus_clear(&t.bus);
}

void tearDown(void) {}

static void nmt(uint8_t command)
{
    const uint8_t d[2] = {command, 5};
    test_rx(&t, 0, 2, d);
    fake_bus_clear(&t.bus); /* boot-up */
}

static uint32_t read_u32(uint16_t index, uint8_t sub)
{
    uint32_t v = 0xDEADBEEFu;
    TEST_ASSERT_EQUAL_HEX32(0, sdo_read_u32(&t, index, sub, &v));
    return v;
}

/* Three persistent values, one per group: communication, manufacturer, device profile. */
static void set_values(uint16_t hb, uint16_t manufacturer, int16_t profile)
{
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1017, 0, hb, 2));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x2070, 0, manufacturer, 2));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x605A, 0, (uint16_t)profile, 2));
}

static void expect_values(uint16_t hb, uint16_t manufacturer, int16_t profile)
{
    TEST_ASSERT_EQUAL_UINT16(hb, co_od_get_u16(&t.node, 0x1017, 0));
    TEST_ASSERT_EQUAL_UINT16(manufacturer, co_od_get_u16(&t.node, 0x2070, 0));
    TEST_ASSERT_EQUAL_INT16(profile, co_od_get_i16(&t.node, 0x605A, 0));
}

static int16_t default_605a;
static uint16_t default_2070_value;
static uint32_t default_2060; /* $NODEID-relative */

static void remember_defaults(void)
{
    default_2070_value = co_od_get_u16(&t.node, 0x2070, 0);
    default_605a = co_od_get_i16(&t.node, 0x605A, 0);
    default_2060 = co_od_get_u32(&t.node, 0x2060, 0);
}

static void test_sub_entries_read_saves_on_command(void)
{
    for (uint8_t sub = 1; sub <= 4u; sub++) {
        TEST_ASSERT_EQUAL_HEX32(1, read_u32(0x1010, sub));
        TEST_ASSERT_EQUAL_HEX32(1, read_u32(0x1011, sub));
    }
    TEST_ASSERT_EQUAL_HEX32(4, read_u32(0x1010, 0));
}

static void test_save_all_then_reset_node_brings_values_back(void)
{
    remember_defaults();
    set_values(250, 7, 3);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1010, 1, SAVE, 4));
    TEST_ASSERT_EQUAL_UINT32(1, t.store.saves);
    TEST_ASSERT_EQUAL_UINT32(co_od_test.persist_size, t.store.len);
    set_values(0, 9, -1);
    nmt(0x81);
    expect_values(250, 7, 3);
    TEST_ASSERT_TRUE(default_2070_value != 7u || default_605a != 3);
}

static void test_signature_bytes_on_the_wire(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1017, 0, 123, 2));
    test_rx8(&t, 0x605, 0x23, 0x10, 0x10, 0x01, 0x73, 0x61, 0x76, 0x65); /* "save" */
    const uint8_t ok[8] = {0x60, 0x10, 0x10, 0x01, 0, 0, 0, 0};
    expect_frame(&t, 0x585, 8, ok);
    TEST_ASSERT_EQUAL_UINT32(1, t.store.saves);
    test_rx8(&t, 0x605, 0x23, 0x11, 0x10, 0x01, 0x6C, 0x6F, 0x61, 0x64); /* "load" */
    const uint8_t ok2[8] = {0x60, 0x11, 0x10, 0x01, 0, 0, 0, 0};
    expect_frame(&t, 0x585, 8, ok2);
    TEST_ASSERT_FALSE(t.store.valid);
}

static void test_reads_after_a_save_still_say_one(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1010, 1, SAVE, 4));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1011, 1, LOAD, 4));
    TEST_ASSERT_EQUAL_HEX32(1, read_u32(0x1010, 1));
    TEST_ASSERT_EQUAL_HEX32(1, read_u32(0x1011, 1));
}

static void test_wrong_signatures_change_nothing(void)
{
    set_values(250, 7, 3);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1010, 1, SAVE, 4));
    set_values(300, 8, 4);
    const uint32_t wrong[] = {0, 1, LOAD, 0x73617665u, 0x65766174u, 0xFFFFFFFFu};
    for (uint32_t i = 0; i < sizeof wrong / sizeof wrong[0]; i++) {
        TEST_ASSERT_EQUAL_HEX32(0x08000020, sdo_write(&t, 0x1010, 1, wrong[i], 4));
        TEST_ASSERT_EQUAL_HEX32(0x08000020, sdo_write(&t, 0x1010, 2, wrong[i], 4));
    }
    const uint32_t wrong_load[] = {0, 1, SAVE, 0x6C6F6164u};
    for (uint32_t i = 0; i < sizeof wrong_load / sizeof wrong_load[0]; i++) {
        TEST_ASSERT_EQUAL_HEX32(0x08000020, sdo_write(&t, 0x1011, 1, wrong_load[i], 4));
    }
    TEST_ASSERT_EQUAL_UINT32(1, t.store.saves);
    TEST_ASSERT_TRUE(t.store.valid);
    expect_values(300, 8, 4);
    nmt(0x81);
    expect_values(250, 7, 3);
}

static void test_wrong_length_is_refused(void)
{
    TEST_ASSERT_EQUAL_HEX32(0x06070013, sdo_write(&t, 0x1010, 1, 0x6173, 2));
    TEST_ASSERT_EQUAL_UINT32(0, t.store.saves);
}

static void test_failed_save_aborts_and_keeps_old_image(void)
{
    set_values(250, 7, 3);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1010, 1, SAVE, 4));
    set_values(300, 8, 4);
    t.store.fail_save = true;
    TEST_ASSERT_EQUAL_HEX32(0x08000020, sdo_write(&t, 0x1010, 1, SAVE, 4));
    TEST_ASSERT_EQUAL_HEX32(0x08000020, sdo_write(&t, 0x1010, 2, SAVE, 4));
    TEST_ASSERT_EQUAL_UINT32(1, t.store.saves);
    expect_values(300, 8, 4);
    t.store.fail_save = false;
    nmt(0x81);
    expect_values(250, 7, 3);
}

static void test_failed_partial_restore_keeps_image(void)
{
    set_values(250, 7, 3);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1010, 1, SAVE, 4));
    t.store.fail_save = true;
    TEST_ASSERT_EQUAL_HEX32(0x08000020, sdo_write(&t, 0x1011, 2, LOAD, 4));
    t.store.fail_save = false;
    nmt(0x81);
    expect_values(250, 7, 3);
}

static void test_restore_takes_effect_only_at_reset(void)
{
    remember_defaults();
    set_values(250, 7, 3);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1010, 1, SAVE, 4));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1011, 1, LOAD, 4));
    expect_values(250, 7, 3); /* current values untouched */
    test_advance(&t, 1000000);
    expect_values(250, 7, 3);
    /* reset communication: the communication defaults come back, application values stay */
    nmt(0x82);
    expect_values(0, 7, 3);
    /* reset node: everything is default */
    nmt(0x81);
    expect_values(0, default_2070_value, default_605a);
}

static void test_reset_communication_loads_only_communication_values(void)
{
    set_values(250, 7, 3);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1010, 1, SAVE, 4));
    set_values(300, 8, 4);
    nmt(0x82);
    expect_values(250, 8, 4);
}

static void test_save_communication_only(void)
{
    remember_defaults();
    set_values(250, 7, 3);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1010, 2, SAVE, 4));
    nmt(0x81);
    expect_values(250, default_2070_value, default_605a);
}

static void test_save_communication_keeps_stored_application_values(void)
{
    set_values(250, 7, 3);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1010, 1, SAVE, 4));
    set_values(300, 8, 4);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1010, 2, SAVE, 4));
    expect_values(300, 8, 4); /* the merge does not touch current values */
    nmt(0x81);
    expect_values(300, 7, 3);
}

static void test_save_application_group_is_0x6000_to_0x9fff(void)
{
    set_values(250, 7, 3);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1010, 1, SAVE, 4));
    set_values(300, 8, 4);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1010, 3, SAVE, 4));
    nmt(0x81);
    expect_values(250, 7, 4);
}

static void test_save_manufacturer_group_is_0x2000_to_0x5fff(void)
{
    set_values(250, 7, 3);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1010, 1, SAVE, 4));
    set_values(300, 8, 4);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1010, 4, SAVE, 4));
    nmt(0x81);
    expect_values(250, 8, 3);
}

static void test_restore_communication_keeps_stored_application_values(void)
{
    set_values(250, 7, 3);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1010, 1, SAVE, 4));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1011, 2, LOAD, 4));
    expect_values(250, 7, 3);
    nmt(0x81);
    expect_values(0, 7, 3);
}

static void test_restore_applies_node_id_to_relative_defaults(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1014, 0, 0x80000085u, 4));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1010, 1, SAVE, 4));
    nmt(0x81);
    TEST_ASSERT_EQUAL_HEX32(0x80000085u, co_od_get_u32(&t.node, 0x1014, 0));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1011, 2, LOAD, 4));
    nmt(0x81);
    TEST_ASSERT_EQUAL_HEX32(0x85u, co_od_get_u32(&t.node, 0x1014, 0));
}

static void test_partial_restore_with_nothing_stored_succeeds(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1011, 3, LOAD, 4));
    TEST_ASSERT_EQUAL_UINT32(0, t.store.saves);
    TEST_ASSERT_FALSE(t.store.valid);
}

static void test_partial_save_with_nothing_stored_uses_defaults(void)
{
    remember_defaults();
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x2060, 0, 0x1234, 4));
    set_values(250, 7, 3);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1010, 3, SAVE, 4));
    nmt(0x81);
    expect_values(0, default_2070_value, 3);
    TEST_ASSERT_EQUAL_HEX32(default_2060, co_od_get_u32(&t.node, 0x2060, 0)); /* node-ID applied */
}

static void test_partial_operations_need_scratch(void)
{
    t.node.store_scratch = NULL;
    TEST_ASSERT_EQUAL_HEX32(0x08000020, sdo_write(&t, 0x1010, 2, SAVE, 4));
    TEST_ASSERT_EQUAL_HEX32(0x08000020, sdo_write(&t, 0x1011, 2, LOAD, 4));
    t.node.store_scratch = scratch;
    t.node.store_scratch_size = co_od_test.persist_size - 1u;
    TEST_ASSERT_EQUAL_HEX32(0x08000020, sdo_write(&t, 0x1010, 3, SAVE, 4));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1010, 1, SAVE, 4)); /* sub 1 needs none */
    TEST_ASSERT_EQUAL_UINT32(1, t.store.saves);
}

static void test_sub_zero_is_read_only(void)
{
    TEST_ASSERT_EQUAL_HEX32(0x06010002, sdo_write(&t, 0x1010, 0, 1, 1));
    TEST_ASSERT_EQUAL_HEX32(0x06010002, sdo_write(&t, 0x1011, 0, 1, 1));
}

static void test_api_save_and_restore(void)
{
    set_values(250, 7, 3);
    TEST_ASSERT_EQUAL_HEX32(0, co_store_save(&t.node, 1));
    TEST_ASSERT_EQUAL_HEX32(0x08000020, co_store_save(&t.node, 5));
    TEST_ASSERT_EQUAL_HEX32(0x08000020, co_store_restore(&t.node, 0));
    TEST_ASSERT_EQUAL_HEX32(0, co_store_restore(&t.node, 1));
    TEST_ASSERT_FALSE(t.store.valid);
}

static void test_node_without_storage(void)
{
    static test_node n;
    test_node_init(&n, 5);
    co_node_config cfg = co_node_default_config();
    cfg.od = &co_od_test;
    cfg.values = n.values;
    cfg.node_id = 5;
    cfg.driver = fake_bus_driver(&n.bus);
    TEST_ASSERT_TRUE(co_node_init(&n.node, &cfg)); /* storage NULL */
    co_node_start(&n.node, 0);
    fake_bus_clear(&n.bus);
    uint32_t v = 0xFFu;
    TEST_ASSERT_EQUAL_HEX32(0, sdo_read_u32(&n, 0x1010, 1, &v));
    TEST_ASSERT_EQUAL_HEX32(0, v);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_read_u32(&n, 0x1011, 1, &v));
    TEST_ASSERT_EQUAL_HEX32(0, v);
    TEST_ASSERT_EQUAL_HEX32(0x08000020, sdo_write(&n, 0x1010, 1, SAVE, 4));
    TEST_ASSERT_EQUAL_HEX32(0x08000020, sdo_write(&n, 0x1011, 1, LOAD, 4));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_sub_entries_read_saves_on_command);
    RUN_TEST(test_save_all_then_reset_node_brings_values_back);
    RUN_TEST(test_signature_bytes_on_the_wire);
    RUN_TEST(test_reads_after_a_save_still_say_one);
    RUN_TEST(test_wrong_signatures_change_nothing);
    RUN_TEST(test_wrong_length_is_refused);
    RUN_TEST(test_failed_save_aborts_and_keeps_old_image);
    RUN_TEST(test_failed_partial_restore_keeps_image);
    RUN_TEST(test_restore_takes_effect_only_at_reset);
    RUN_TEST(test_reset_communication_loads_only_communication_values);
    RUN_TEST(test_save_communication_only);
    RUN_TEST(test_save_communication_keeps_stored_application_values);
    RUN_TEST(test_save_application_group_is_0x6000_to_0x9fff);
    RUN_TEST(test_save_manufacturer_group_is_0x2000_to_0x5fff);
    RUN_TEST(test_restore_communication_keeps_stored_application_values);
    RUN_TEST(test_restore_applies_node_id_to_relative_defaults);
    RUN_TEST(test_partial_restore_with_nothing_stored_succeeds);
    RUN_TEST(test_partial_save_with_nothing_stored_uses_defaults);
    RUN_TEST(test_partial_operations_need_scratch);
    RUN_TEST(test_sub_zero_is_read_only);
    RUN_TEST(test_api_save_and_restore);
    RUN_TEST(test_node_without_storage);
    return UNITY_END();
}
