/* SDO server: expedited transfers of every size, the abort codes of CiA 301 from the requests
 * that cause them (each with the value checked untouched), malformed and unexpected frames, the
 * client's abort, a new initiate during a transfer, timeouts and the CRC. Segmented transfers are
 * in test_sdo_segmented.c, block transfers in test_sdo_block.c. */
#include <string.h>

#include "canopen/sdo_server.h"
#include "../../src/dispatch.h" /* co_sdo_server_init, _rx, _process: driven directly */
#include "od_test.h"
#include "test_support.h"
#include "unity.h"

#define RX 0x605u /* node 5: client -> server */
#define TX 0x585u /* server -> client */

static test_node t;

void setUp(void)
{
    test_node_start(&t, 5);
    fake_bus_clear(&t.bus);
}

void tearDown(void) {}

/* --- expedited upload, each size -------------------------------------------------------------- */

static void test_expedited_upload_1_byte(void)
{
    sdo_req(&t, 0x40, 0x06, 0x20, 0x00, 0, 0, 0, 0); /* 0x2006 UNSIGNED8 = 200 */
    sdo_expect(&t, 0x4F, 0x06, 0x20, 0x00, 200, 0, 0, 0);
    expect_no_frame(&t);
}

static void test_expedited_upload_2_bytes(void)
{
    sdo_req(&t, 0x40, 0x20, 0x20, 0x00, 0, 0, 0, 0); /* 0x2020 ro UNSIGNED16 = 0x1234 */
    sdo_expect(&t, 0x4B, 0x20, 0x20, 0x00, 0x34, 0x12, 0, 0);
}

static void test_expedited_upload_3_bytes(void)
{
    sdo_req(&t, 0x40, 0x08, 0x20, 0x00, 0, 0, 0, 0); /* 0x2008 UNSIGNED24 = 0x123456 */
    sdo_expect(&t, 0x47, 0x08, 0x20, 0x00, 0x56, 0x34, 0x12, 0);
}

static void test_expedited_upload_4_bytes(void)
{
    sdo_req(&t, 0x40, 0x09, 0x20, 0x00, 0, 0, 0, 0); /* 0x2009 UNSIGNED32 = 0xDEADBEEF */
    sdo_expect(&t, 0x43, 0x09, 0x20, 0x00, 0xEF, 0xBE, 0xAD, 0xDE);
}

static void test_expedited_upload_echoes_sub_index(void)
{
    sdo_req(&t, 0x40, 0x18, 0x10, 0x02, 0, 0, 0, 0); /* 0x1018 sub 2 product code 0x1234 */
    sdo_expect(&t, 0x43, 0x18, 0x10, 0x02, 0x34, 0x12, 0, 0);
}

static void test_expedited_upload_of_a_short_string(void)
{
    sdo_req(&t, 0x40, 0x09, 0x10, 0x00, 0, 0, 0, 0); /* 0x1009 "1.0" */
    sdo_expect(&t, 0x47, 0x09, 0x10, 0x00, '1', '.', '0', 0);
}

/* The bytes past a short value are 0 even when a longer value was read into the server's buffer
 * before. */
static void test_expedited_upload_after_a_longer_one_pads_with_zeros(void)
{
    sdo_req(&t, 0x40, 0x09, 0x20, 0x00, 0, 0, 0, 0); /* 0x2009 = 0xDEADBEEF */
    sdo_expect(&t, 0x43, 0x09, 0x20, 0x00, 0xEF, 0xBE, 0xAD, 0xDE);
    fake_bus_clear(&t.bus);
    sdo_req(&t, 0x40, 0x06, 0x20, 0x00, 0, 0, 0, 0); /* 0x2006 = 200, one byte */
    sdo_expect(&t, 0x4F, 0x06, 0x20, 0x00, 200, 0, 0, 0);
    fake_bus_clear(&t.bus);
    sdo_req(&t, 0x40, 0x20, 0x20, 0x00, 0, 0, 0, 0); /* 0x2020 = 0x1234, two bytes */
    sdo_expect(&t, 0x4B, 0x20, 0x20, 0x00, 0x34, 0x12, 0, 0);
}

/* CO_NODE_SDO_UPLOAD_COMM_AS_32: numeric entries of 0x1000-0x1FFF shorter than 4 bytes answer
 * 0x43 with the value zero-extended; strings and the other areas keep their exact size. */
static void test_upload_comm_as_32_answers_four_bytes_in_0x1000_0x1fff_only(void)
{
    t.node.options |= CO_NODE_SDO_UPLOAD_COMM_AS_32;
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1017, 0, 0x03E8, 2)); /* UNSIGNED16 */
    fake_bus_clear(&t.bus);
    sdo_req(&t, 0x40, 0x17, 0x10, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x43, 0x17, 0x10, 0x00, 0xE8, 0x03, 0, 0);
    fake_bus_clear(&t.bus);
    sdo_req(&t, 0x40, 0x01, 0x10, 0x00, 0, 0, 0, 0); /* 0x1001 UNSIGNED8 error register = 0 */
    sdo_expect(&t, 0x43, 0x01, 0x10, 0x00, 0, 0, 0, 0);
    fake_bus_clear(&t.bus);
    sdo_req(&t, 0x40, 0x09, 0x10, 0x00, 0, 0, 0, 0); /* 0x1009 "1.0": a string keeps its size */
    sdo_expect(&t, 0x47, 0x09, 0x10, 0x00, '1', '.', '0', 0);
    fake_bus_clear(&t.bus);
    sdo_req(&t, 0x40, 0x20, 0x20, 0x00, 0, 0, 0, 0); /* 0x2020 UNSIGNED16 outside the area */
    sdo_expect(&t, 0x4B, 0x20, 0x20, 0x00, 0x34, 0x12, 0, 0);
    fake_bus_clear(&t.bus);
    t.node.options &= ~CO_NODE_SDO_UPLOAD_COMM_AS_32; /* without: CiA 301's exact size */
    sdo_req(&t, 0x40, 0x17, 0x10, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x4B, 0x17, 0x10, 0x00, 0xE8, 0x03, 0, 0);
}

static void test_upload_ignores_the_data_bytes_of_the_request(void)
{
    sdo_req(&t, 0x40, 0x06, 0x20, 0x00, 0xFF, 0xFF, 0xFF, 0xFF);
    sdo_expect(&t, 0x4F, 0x06, 0x20, 0x00, 200, 0, 0, 0);
}

/* --- expedited download, each size ------------------------------------------------------------ */

static void test_expedited_download_1_byte(void)
{
    sdo_req(&t, 0x2F, 0x06, 0x20, 0x00, 0x12, 0xAA, 0xBB, 0xCC);
    sdo_expect(&t, 0x60, 0x06, 0x20, 0x00, 0, 0, 0, 0);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT8(0x12, co_od_get_u8(&t.node, 0x2006, 0));
}

static void test_expedited_download_2_bytes(void)
{
    sdo_req(&t, 0x2B, 0x22, 0x20, 0x00, 0xBC, 0x02, 0xAA, 0xBB); /* 0x2022 = 700 (range 0..1000) */
    sdo_expect(&t, 0x60, 0x22, 0x20, 0x00, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT16(700, co_od_get_u16(&t.node, 0x2022, 0));
}

static void test_expedited_download_3_bytes(void)
{
    sdo_req(&t, 0x27, 0x08, 0x20, 0x00, 0xEF, 0xCD, 0xAB, 0x99);
    sdo_expect(&t, 0x60, 0x08, 0x20, 0x00, 0, 0, 0, 0);
    const uint8_t *v = test_value_of(&t, 0x2008, 0);
    TEST_ASSERT_EQUAL_HEX8(0xEF, v[0]);
    TEST_ASSERT_EQUAL_HEX8(0xCD, v[1]);
    TEST_ASSERT_EQUAL_HEX8(0xAB, v[2]);
}

static void test_expedited_download_4_bytes(void)
{
    sdo_req(&t, 0x23, 0x09, 0x20, 0x00, 0x04, 0x03, 0x02, 0x01);
    sdo_expect(&t, 0x60, 0x09, 0x20, 0x00, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_HEX32(0x01020304, co_od_get_u32(&t.node, 0x2009, 0));
}

static void test_expedited_download_to_a_sub_index(void)
{
    sdo_req(&t, 0x23, 0x16, 0x10, 0x03, 0x88, 0x13, 0x7F, 0x00);
    sdo_expect(&t, 0x60, 0x16, 0x10, 0x03, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_HEX32(0x007F1388, co_od_get_u32(&t.node, 0x1016, 3));
}

static void test_expedited_download_without_size_takes_the_type_size(void)
{
    sdo_req(&t, 0x22, 0x22, 0x20, 0x00, 0x2C, 0x01, 0xFF, 0xFF); /* e=1 s=0 to a u16: 300 */
    sdo_expect(&t, 0x60, 0x22, 0x20, 0x00, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT16(300, co_od_get_u16(&t.node, 0x2022, 0));
}

static void test_expedited_download_without_size_to_u32(void)
{
    sdo_req(&t, 0x22, 0x09, 0x20, 0x00, 0x11, 0x22, 0x33, 0x44);
    sdo_expect(&t, 0x60, 0x09, 0x20, 0x00, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_HEX32(0x44332211, co_od_get_u32(&t.node, 0x2009, 0));
}

static void test_expedited_download_of_a_short_string(void)
{
    sdo_req(&t, 0x2B, 0x0D, 0x20, 0x00, 'a', 'b', 'x', 'x'); /* "ab" into 0x200D "hello" */
    sdo_expect(&t, 0x60, 0x0D, 0x20, 0x00, 0, 0, 0, 0);
    co_od_ref ref;
    TEST_ASSERT_EQUAL_HEX32(0, co_od_locate(t.node.od, 0x200D, 0, &ref));
    TEST_ASSERT_EQUAL_UINT32(2, co_od_value_length(&t.node, ref));
    TEST_ASSERT_EQUAL_MEMORY("ab\0\0\0", test_value_of(&t, 0x200D, 0), 5);
}

static void test_expedited_round_trip(void)
{
    uint32_t v = 0;
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x2004, 0, 0xFFFE7961u, 4));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_read_u32(&t, 0x2004, 0, &v));
    TEST_ASSERT_EQUAL_HEX32(0xFFFE7961u, v);
}

/* --- abort codes: object, access, length, value ----------------------------------------------- */

static void test_upload_of_a_missing_object_aborts_0x06020000(void)
{
    sdo_req(&t, 0x40, 0x00, 0x30, 0x00, 0, 0, 0, 0);
    sdo_expect_abort(&t, 0x3000, 0, CO_ABORT_NO_OBJECT);
}

static void test_download_to_a_missing_object_aborts_0x06020000(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x23, 0x00, 0x30, 0x00, 1, 2, 3, 4);
    sdo_expect_abort(&t, 0x3000, 0, CO_ABORT_NO_OBJECT);
    test_expect_values_unchanged(&t);
}

static void test_upload_of_a_missing_sub_index_aborts_0x06090011(void)
{
    sdo_req(&t, 0x40, 0x18, 0x10, 0x09, 0, 0, 0, 0);
    sdo_expect_abort(&t, 0x1018, 9, CO_ABORT_NO_SUBINDEX);
}

static void test_download_to_a_missing_sub_index_aborts_0x06090011(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x2F, 0x00, 0x14, 0x03, 1, 0, 0, 0); /* 0x1400 has subs 0, 1, 2, 5 */
    sdo_expect_abort(&t, 0x1400, 3, CO_ABORT_NO_SUBINDEX);
    test_expect_values_unchanged(&t);
}

static void test_download_to_read_only_aborts_0x06010002(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x2B, 0x20, 0x20, 0x00, 0x11, 0x11, 0, 0);
    sdo_expect_abort(&t, 0x2020, 0, CO_ABORT_READ_ONLY);
    test_expect_values_unchanged(&t);
    TEST_ASSERT_EQUAL_HEX16(0x1234, co_od_get_u16(&t.node, 0x2020, 0));
}

static void test_download_to_const_aborts_0x06010002(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x2B, 0x25, 0x20, 0x00, 0x11, 0x11, 0, 0);
    sdo_expect_abort(&t, 0x2025, 0, CO_ABORT_READ_ONLY);
    test_expect_values_unchanged(&t);
}

static void test_segmented_download_to_read_only_aborts_at_the_initiate(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x21, 0x08, 0x10, 0x00, 5, 0, 0, 0); /* 0x1008 const string, 5 bytes announced */
    sdo_expect_abort(&t, 0x1008, 0, CO_ABORT_READ_ONLY);
    /* no transfer: the segment is unexpected */
    sdo_req(&t, 0x00, 'a', 'b', 'c', 'd', 'e', 'f', 'g');
    sdo_expect_abort(&t, 0x1008, 0, CO_ABORT_COMMAND);
    test_expect_values_unchanged(&t);
}

static void test_upload_of_write_only_aborts_0x06010001(void)
{
    sdo_req(&t, 0x40, 0x21, 0x20, 0x00, 0, 0, 0, 0);
    sdo_expect_abort(&t, 0x2021, 0, CO_ABORT_WRITE_ONLY);
}

static void test_write_only_accepts_a_download(void)
{
    sdo_req(&t, 0x2B, 0x21, 0x20, 0x00, 0x34, 0x12, 0, 0);
    sdo_expect(&t, 0x60, 0x21, 0x20, 0x00, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_HEX16(0x1234, co_od_get_u16(&t.node, 0x2021, 0));
}

static void test_expedited_too_long_aborts_0x06070012(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x23, 0x22, 0x20, 0x00, 1, 0, 0, 0); /* 4 bytes into a u16 */
    sdo_expect_abort(&t, 0x2022, 0, CO_ABORT_TYPE_TOO_LONG);
    test_expect_values_unchanged(&t);
}

static void test_expedited_too_short_aborts_0x06070013(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x2F, 0x09, 0x20, 0x00, 1, 0, 0, 0); /* 1 byte into a u32 */
    sdo_expect_abort(&t, 0x2009, 0, CO_ABORT_TYPE_TOO_SHORT);
    test_expect_values_unchanged(&t);
}

static void test_announced_size_too_long_aborts_0x06070012(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x21, 0x09, 0x20, 0x00, 8, 0, 0, 0); /* u32, 8 announced */
    sdo_expect_abort(&t, 0x2009, 0, CO_ABORT_TYPE_TOO_LONG);
    test_expect_values_unchanged(&t);
}

static void test_announced_size_too_short_aborts_0x06070013(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x21, 0x0A, 0x20, 0x00, 4, 0, 0, 0); /* u64, 4 announced */
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_TYPE_TOO_SHORT);
    test_expect_values_unchanged(&t);
}

static void test_announced_size_beyond_string_capacity_aborts_0x06070012(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x21, 0x0E, 0x20, 0x00, 17, 0, 0, 0); /* capacity 16 */
    sdo_expect_abort(&t, 0x200E, 0, CO_ABORT_TYPE_TOO_LONG);
    test_expect_values_unchanged(&t);
}

static void test_announced_huge_size_aborts_without_overflow(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x21, 0x0D, 0x20, 0x00, 0xFF, 0xFF, 0xFF, 0xFF);
    sdo_expect_abort(&t, 0x200D, 0, CO_ABORT_TYPE_TOO_LONG);
    sdo_req(&t, 0xC6, 0x0D, 0x20, 0x00, 0xFF, 0xFF, 0xFF, 0xFF); /* block download, the same */
    sdo_expect_abort(&t, 0x200D, 0, CO_ABORT_TYPE_TOO_LONG);
    test_expect_values_unchanged(&t);
}

static void test_boolean_out_of_range_aborts_0x06090030(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x2F, 0x00, 0x20, 0x00, 2, 0, 0, 0);
    sdo_expect_abort(&t, 0x2000, 0, CO_ABORT_VALUE_RANGE);
    test_expect_values_unchanged(&t);
}

static void test_real_nan_aborts_0x06090030(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x23, 0x0B, 0x20, 0x00, 0x00, 0x00, 0xC0, 0x7F); /* REAL32 NaN into -10..10 */
    sdo_expect_abort(&t, 0x200B, 0, CO_ABORT_VALUE_RANGE);
    test_expect_values_unchanged(&t);
}

static void test_value_too_high_aborts_0x06090031(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x2F, 0x01, 0x20, 0x00, 101, 0, 0, 0); /* INTEGER8 -100..100 */
    sdo_expect_abort(&t, 0x2001, 0, CO_ABORT_VALUE_TOO_HIGH);
    test_expect_values_unchanged(&t);
}

static void test_value_too_low_aborts_0x06090032(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x2F, 0x01, 0x20, 0x00, (uint8_t)-101, 0, 0, 0);
    sdo_expect_abort(&t, 0x2001, 0, CO_ABORT_VALUE_TOO_LOW);
    test_expect_values_unchanged(&t);
}

static void test_value_at_the_limit_is_written(void)
{
    sdo_req(&t, 0x2F, 0x01, 0x20, 0x00, (uint8_t)-100, 0, 0, 0);
    sdo_expect(&t, 0x60, 0x01, 0x20, 0x00, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_INT8(-100, (int8_t)co_od_get_u8(&t.node, 0x2001, 0));
}

/* --- abort codes a write hook gives are passed through ---------------------------------------- */

static co_abort refusal; /* what refusing_write answers */
static uint32_t refusing_calls;

static co_abort refusing_write(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                               uint32_t len, co_od_origin origin)
{
    (void)node;
    (void)ctx;
    (void)ref;
    (void)data;
    (void)len;
    TEST_ASSERT_EQUAL(CO_ORIGIN_SDO, origin);
    refusing_calls++;
    return refusal;
}

static void expect_hook_refusal_passed_through(co_abort code)
{
    const co_od_hook hook = {0x2009, 0x2009, NULL, refusing_write, NULL, NULL, NULL};
    TEST_ASSERT_TRUE(co_node_add_hook(&t.node, &hook));
    refusal = code;
    refusing_calls = 0;
    test_values_snapshot(&t);
    sdo_req(&t, 0x23, 0x09, 0x20, 0x00, 1, 2, 3, 4);
    sdo_expect_abort(&t, 0x2009, 0, code);
    TEST_ASSERT_EQUAL_UINT32(1, refusing_calls);
    test_expect_values_unchanged(&t);
    TEST_ASSERT_EQUAL_HEX32(0xDEADBEEF, co_od_get_u32(&t.node, 0x2009, 0));
}

static void test_hook_abort_0x06040041_passes_through(void)
{
    expect_hook_refusal_passed_through(CO_ABORT_NOT_MAPPABLE);
}

static void test_hook_abort_0x06040042_passes_through(void)
{
    expect_hook_refusal_passed_through(CO_ABORT_PDO_LENGTH);
}

static void test_hook_abort_0x06040043_passes_through(void)
{
    expect_hook_refusal_passed_through(CO_ABORT_PARAM_INCOMPATIBLE);
}

static void test_hook_abort_0x08000020_passes_through(void)
{
    expect_hook_refusal_passed_through(CO_ABORT_STORE);
}

static void test_hook_abort_0x08000021_passes_through(void)
{
    expect_hook_refusal_passed_through(CO_ABORT_LOCAL_CONTROL);
}

static void test_hook_abort_0x08000022_passes_through(void)
{
    expect_hook_refusal_passed_through(CO_ABORT_DEVICE_STATE);
}

static void test_hook_refusal_of_a_segmented_download_leaves_the_value(void)
{
    const co_od_hook hook = {0x200A, 0x200A, NULL, refusing_write, NULL, NULL, NULL};
    TEST_ASSERT_TRUE(co_node_add_hook(&t.node, &hook));
    refusal = CO_ABORT_PARAM_INCOMPATIBLE;
    test_values_snapshot(&t);
    sdo_req(&t, 0x21, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    sdo_expect(&t, 0x60, 0x0A, 0x20, 0x00, 0, 0, 0, 0);
    sdo_req(&t, 0x00, 1, 2, 3, 4, 5, 6, 7);
    sdo_expect(&t, 0x20, 0, 0, 0, 0, 0, 0, 0);
    sdo_req(&t, 0x1D, 8, 0, 0, 0, 0, 0, 0);
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_PARAM_INCOMPATIBLE);
    test_expect_values_unchanged(&t);
}

static co_abort refusing_refresh(co_node *node, void *ctx, co_od_ref ref)
{
    (void)node;
    (void)ctx;
    (void)ref;
    return CO_ABORT_DEVICE_STATE;
}

static void test_refresh_hook_refusal_aborts_the_upload(void)
{
    const co_od_hook hook = {0x2009, 0x2009, refusing_refresh, NULL, NULL, NULL, NULL};
    TEST_ASSERT_TRUE(co_node_add_hook(&t.node, &hook));
    sdo_req(&t, 0x40, 0x09, 0x20, 0x00, 0, 0, 0, 0);
    sdo_expect_abort(&t, 0x2009, 0, CO_ABORT_DEVICE_STATE);
}

static void test_comm_objects_read_only_in_operational_abort_0x08000022(void)
{
    t.node.options |= CO_NODE_COMM_READ_ONLY_IN_OPERATIONAL;
    co_nmt_command_local(&t.node, CO_NMT_CMD_START, t.now);
    fake_bus_clear(&t.bus);
    test_values_snapshot(&t);
    sdo_req(&t, 0x2B, 0x17, 0x10, 0x00, 100, 0, 0, 0);
    sdo_expect_abort(&t, 0x1017, 0, CO_ABORT_DEVICE_STATE);
    test_expect_values_unchanged(&t);
}

static void test_domain_without_hook_download_aborts_0x06010000(void)
{
    sdo_req(&t, 0x23, 0x10, 0x20, 0x00, 1, 2, 3, 4);
    sdo_expect_abort(&t, 0x2010, 0, CO_ABORT_UNSUPPORTED_ACCESS);
    sdo_req(&t, 0x21, 0x10, 0x20, 0x00, 100, 0, 0, 0); /* segmented: refused at the initiate */
    sdo_expect_abort(&t, 0x2010, 0, CO_ABORT_UNSUPPORTED_ACCESS);
    sdo_req(&t, 0xC6, 0x10, 0x20, 0x00, 100, 0, 0, 0); /* block */
    sdo_expect_abort(&t, 0x2010, 0, CO_ABORT_UNSUPPORTED_ACCESS);
}

static void test_domain_without_hook_upload_aborts_0x08000024(void)
{
    sdo_req(&t, 0x40, 0x10, 0x20, 0x00, 0, 0, 0, 0);
    sdo_expect_abort(&t, 0x2010, 0, CO_ABORT_NO_DATA);
}

/* --- malformed and unexpected frames ---------------------------------------------------------- */

static void test_frames_shorter_than_8_bytes_are_dropped_and_counted(void)
{
    const uint8_t write[8] = {0x2F, 0x06, 0x20, 0x00, 0x12, 0, 0, 0};
    const uint8_t read[8] = {0x40, 0x06, 0x20, 0x00, 0, 0, 0, 0};
    test_values_snapshot(&t);
    uint32_t malformed = t.node.stats.rx_malformed;
    for (uint8_t dlc = 0; dlc < 8u; dlc++) {
        test_rx(&t, RX, dlc, write);
        test_rx(&t, RX, dlc, read);
    }
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT32(malformed + 16u, t.node.stats.rx_malformed);
    test_expect_values_unchanged(&t);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
}

static void test_short_frame_calls_leave_the_server_usable(void)
{
    const uint8_t bytes[8] = {0xE0, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
    for (uint8_t dlc = 0; dlc < 8u; dlc++) {
        test_rx(&t, RX, dlc, bytes);
    }
    expect_no_frame(&t);
    sdo_req(&t, 0x40, 0x06, 0x20, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x4F, 0x06, 0x20, 0x00, 200, 0, 0, 0);
}

static void test_short_frame_during_a_transfer_leaves_it_going(void)
{
    sdo_req(&t, 0x21, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    sdo_expect(&t, 0x60, 0x0A, 0x20, 0x00, 0, 0, 0, 0);
    const uint8_t seg[8] = {0x00, 1, 2, 3, 4, 5, 6, 7};
    test_rx(&t, RX, 7, seg); /* dropped: not even the toggle moves */
    expect_no_frame(&t);
    sdo_req(&t, 0x00, 1, 2, 3, 4, 5, 6, 7);
    sdo_expect(&t, 0x20, 0, 0, 0, 0, 0, 0, 0);
    sdo_req(&t, 0x1D, 8, 0, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0x30, 0, 0, 0, 0, 0, 0, 0);
    const uint8_t want[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    TEST_ASSERT_EQUAL_MEMORY(want, test_value_of(&t, 0x200A, 0), 8);
}

static void test_rtr_frame_is_dropped(void)
{
    co_frame f;
    memset(&f, 0, sizeof f);
    f.id = RX;
    f.dlc = 8;
    f.flags = CO_FRAME_RTR;
    f.data[0] = 0x40;
    f.data[1] = 0x06;
    f.data[2] = 0x20;
    uint32_t malformed = t.node.stats.rx_malformed;
    co_node_rx(&t.node, &f, t.now);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT32(malformed + 1u, t.node.stats.rx_malformed);
    /* the server itself refuses one too, whoever hands it over */
    co_sdo_server_rx(&t.node, &f, t.now);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT32(malformed + 2u, t.node.stats.rx_malformed);
}

static void test_unknown_command_specifier_aborts_0x05040001(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0xE0, 0x06, 0x20, 0x00, 1, 2, 3, 4); /* ccs 7 */
    sdo_expect_abort(&t, 0, 0, CO_ABORT_COMMAND);
    sdo_req(&t, 0xFF, 0x06, 0x20, 0x00, 1, 2, 3, 4);
    sdo_expect_abort(&t, 0, 0, CO_ABORT_COMMAND);
    test_expect_values_unchanged(&t);
}

static void test_unknown_command_during_a_transfer_ends_it(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x21, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    sdo_expect(&t, 0x60, 0x0A, 0x20, 0x00, 0, 0, 0, 0);
    sdo_req(&t, 0xE0, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_COMMAND);
    sdo_req(&t, 0x00, 1, 2, 3, 4, 5, 6, 7);
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_COMMAND);
    test_expect_values_unchanged(&t);
}

static void test_download_segment_while_idle_aborts_0x05040001(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x00, 1, 2, 3, 4, 5, 6, 7);
    sdo_expect_abort(&t, 0, 0, CO_ABORT_COMMAND);
    test_expect_values_unchanged(&t);
}

static void test_upload_segment_while_idle_aborts_0x05040001(void)
{
    sdo_req(&t, 0x60, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect_abort(&t, 0, 0, CO_ABORT_COMMAND);
}

static void test_block_sub_commands_while_idle_abort_0x05040001(void)
{
    sdo_req(&t, 0xA1, 0, 0, 0, 0, 0, 0, 0); /* block upload end */
    sdo_expect_abort(&t, 0, 0, CO_ABORT_COMMAND);
    sdo_req(&t, 0xA2, 1, 127, 0, 0, 0, 0, 0); /* block upload ack */
    sdo_expect_abort(&t, 0, 0, CO_ABORT_COMMAND);
    sdo_req(&t, 0xA3, 0, 0, 0, 0, 0, 0, 0); /* block upload start */
    sdo_expect_abort(&t, 0, 0, CO_ABORT_COMMAND);
    sdo_req(&t, 0xC1, 0, 0, 0, 0, 0, 0, 0); /* block download end */
    sdo_expect_abort(&t, 0, 0, CO_ABORT_COMMAND);
}

static void test_wrong_segment_kind_aborts_0x05040001(void)
{
    sdo_req(&t, 0x40, 0x0A, 0x20, 0x00, 0, 0, 0, 0); /* segmented upload of u64 */
    sdo_expect(&t, 0x41, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    sdo_req(&t, 0x00, 1, 2, 3, 4, 5, 6, 7); /* a download segment */
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_COMMAND);
}

static void test_abort_while_idle_is_ignored(void)
{
    sdo_req(&t, 0x80, 0x06, 0x20, 0x00, 0, 0, 0x04, 0x05);
    expect_no_frame(&t);
    sdo_req(&t, 0x40, 0x06, 0x20, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x4F, 0x06, 0x20, 0x00, 200, 0, 0, 0);
}

static void test_client_abort_ends_a_download_silently(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x21, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    sdo_expect(&t, 0x60, 0x0A, 0x20, 0x00, 0, 0, 0, 0);
    sdo_req(&t, 0x00, 1, 2, 3, 4, 5, 6, 7);
    sdo_expect(&t, 0x20, 0, 0, 0, 0, 0, 0, 0);
    sdo_req(&t, 0x80, 0x0A, 0x20, 0x00, 0x00, 0x00, 0x04, 0x05);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
    TEST_ASSERT_EQUAL_UINT64(CO_TIME_NEVER, co_node_process(&t.node, t.now + 10000000u));
    expect_no_frame(&t);
    test_expect_values_unchanged(&t);
}

static void test_new_initiate_replaces_a_transfer_without_an_abort(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x21, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    sdo_expect(&t, 0x60, 0x0A, 0x20, 0x00, 0, 0, 0, 0);
    sdo_req(&t, 0x00, 1, 2, 3, 4, 5, 6, 7);
    sdo_expect(&t, 0x20, 0, 0, 0, 0, 0, 0, 0);
    sdo_req(&t, 0x40, 0x06, 0x20, 0x00, 0, 0, 0, 0); /* the client starts over with an upload */
    sdo_expect(&t, 0x4F, 0x06, 0x20, 0x00, 200, 0, 0, 0);
    expect_no_frame(&t);
    test_expect_values_unchanged(&t);
    sdo_req(&t, 0x1D, 8, 0, 0, 0, 0, 0, 0); /* the old transfer is gone */
    sdo_expect_abort(&t, 0x2006, 0, CO_ABORT_COMMAND);
    test_expect_values_unchanged(&t);
}

static void test_new_download_initiate_during_an_upload(void)
{
    sdo_req(&t, 0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x41, 0x08, 0x10, 0x00, 12, 0, 0, 0);
    sdo_req(&t, 0x2F, 0x06, 0x20, 0x00, 7, 0, 0, 0);
    sdo_expect(&t, 0x60, 0x06, 0x20, 0x00, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT8(7, co_od_get_u8(&t.node, 0x2006, 0));
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
}

static void test_failed_new_initiate_aborts_with_its_own_multiplexer(void)
{
    sdo_req(&t, 0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x41, 0x08, 0x10, 0x00, 12, 0, 0, 0);
    sdo_req(&t, 0x40, 0x34, 0x12, 0x07, 0, 0, 0, 0);
    sdo_expect_abort(&t, 0x1234, 7, CO_ABORT_NO_OBJECT);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
}

/* --- the node around the server --------------------------------------------------------------- */

static void test_server_abort_sends_the_code_with_the_multiplexer(void)
{
    co_sdo_server_abort(&t.node, CO_ABORT_GENERAL); /* idle: nothing */
    expect_no_frame(&t);
    sdo_req(&t, 0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x41, 0x08, 0x10, 0x00, 12, 0, 0, 0);
    uint32_t aborts = t.node.stats.sdo_aborts;
    co_sdo_server_abort(&t.node, CO_ABORT_LOCAL_CONTROL);
    sdo_expect_abort(&t, 0x1008, 0, CO_ABORT_LOCAL_CONTROL);
    TEST_ASSERT_EQUAL_UINT32(aborts + 1u, t.node.stats.sdo_aborts);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
}

static void test_aborts_are_counted(void)
{
    uint32_t aborts = t.node.stats.sdo_aborts;
    sdo_req(&t, 0x40, 0x00, 0x30, 0x00, 0, 0, 0, 0);
    sdo_req(&t, 0xE0, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(aborts + 2u, t.node.stats.sdo_aborts);
}

static void test_stopped_node_drops_the_transfer_and_answers_nothing(void)
{
    sdo_req(&t, 0x21, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    sdo_expect(&t, 0x60, 0x0A, 0x20, 0x00, 0, 0, 0, 0);
    co_nmt_command_local(&t.node, CO_NMT_CMD_STOP, t.now);
    fake_bus_clear(&t.bus);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
    sdo_req(&t, 0x40, 0x06, 0x20, 0x00, 0, 0, 0, 0);
    expect_no_frame(&t);
    co_nmt_command_local(&t.node, CO_NMT_CMD_ENTER_PRE_OPERATIONAL, t.now);
    fake_bus_clear(&t.bus);
    /* the old transfer did not survive (nor its multiplexer) */
    sdo_req(&t, 0x00, 1, 2, 3, 4, 5, 6, 7);
    sdo_expect_abort(&t, 0, 0, CO_ABORT_COMMAND);
}

static void test_init_keeps_the_timeout_and_defaults_zero(void)
{
    t.node.sdo.timeout_us = 1234;
    co_sdo_server_init(&t.node);
    TEST_ASSERT_EQUAL_UINT32(1234, t.node.sdo.timeout_us);
    t.node.sdo.timeout_us = 0;
    co_sdo_server_init(&t.node);
    TEST_ASSERT_EQUAL_UINT32(CO_SDO_TIMEOUT_US, t.node.sdo.timeout_us);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
}

static void test_configured_timeout_comes_from_the_node_config(void)
{
    co_node n;
    static uint8_t values[8192];
    fake_bus bus;
    memset(&bus, 0, sizeof bus);
    co_node_config cfg = co_node_default_config();
    cfg.od = &co_od_test;
    cfg.values = values;
    cfg.node_id = 9;
    cfg.driver = fake_bus_driver(&bus);
    cfg.sdo_timeout_us = 2500;
    TEST_ASSERT_TRUE(co_node_init(&n, &cfg));
    co_node_start(&n, 0);
    fake_bus_clear(&bus);
    co_frame f = {0x609, 8, 0, {0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0}};
    co_node_rx(&n, &f, 100);
    TEST_ASSERT_NOT_NULL(fake_bus_next(&bus));
    TEST_ASSERT_EQUAL_UINT64(2600, co_node_process(&n, 100));
    co_node_process(&n, 2599);
    TEST_ASSERT_EQUAL_UINT32(0, fake_bus_pending(&bus));
    co_node_process(&n, 2600);
    const co_frame *a = fake_bus_next(&bus);
    TEST_ASSERT_NOT_NULL(a);
    TEST_ASSERT_EQUAL_HEX16(0x589, a->id);
    TEST_ASSERT_EQUAL_HEX8(0x80, a->data[0]);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_TIMEOUT, co_get_le32(&a->data[4]));
}

static void test_idle_server_has_no_deadline(void)
{
    TEST_ASSERT_EQUAL_UINT64(CO_NEVER, co_sdo_server_process(&t.node, t.node.now));
    sdo_req(&t, 0x40, 0x06, 0x20, 0x00, 0, 0, 0, 0); /* expedited: nothing stays pending */
    TEST_ASSERT_EQUAL_UINT64(CO_NEVER, co_sdo_server_process(&t.node, t.node.now));
}

#if !CO_CONFIG_TIME32 /* a co_time never comes near its end (include/canopen/time_base.h) */
static void test_timeout_near_the_end_of_time_saturates(void)
{
    t.now = UINT64_MAX - 10u;
    sdo_req(&t, 0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x41, 0x08, 0x10, 0x00, 12, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT64(UINT64_MAX, t.node.sdo.deadline);
    co_sdo_server_process(&t.node, UINT64_MAX - 1u);
    expect_no_frame(&t);
}
#endif

static void test_responses_use_the_configured_cob_id(void)
{
    t.node.sdo_tx_cob = 0x5F0;
    sdo_req(&t, 0x40, 0x06, 0x20, 0x00, 0, 0, 0, 0);
    const uint8_t d[8] = {0x4F, 0x06, 0x20, 0x00, 200, 0, 0, 0};
    expect_frame(&t, 0x5F0, 8, d);
}

/* --- CRC -------------------------------------------------------------------------------------- */

static void test_crc16_check_value(void)
{
    const uint8_t digits[9] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
    TEST_ASSERT_EQUAL_HEX16(0x31C3, co_sdo_crc16(0, digits, 9)); /* CRC-16/XMODEM check */
    TEST_ASSERT_EQUAL_HEX16(0x0000, co_sdo_crc16(0, digits, 0));
}

static void test_crc16_continues_across_pieces(void)
{
    uint8_t data[300];
    for (uint32_t i = 0; i < sizeof data; i++) {
        data[i] = (uint8_t)(i * 37u + 11u);
    }
    uint16_t whole = co_sdo_crc16(0, data, sizeof data);
    uint16_t pieces = co_sdo_crc16(0, data, 7);
    pieces = co_sdo_crc16(pieces, &data[7], 200);
    pieces = co_sdo_crc16(pieces, &data[207], 93);
    TEST_ASSERT_EQUAL_HEX16(whole, pieces);
    /* a bitwise reference */
    uint16_t ref = 0;
    for (uint32_t i = 0; i < sizeof data; i++) {
        ref = (uint16_t)(ref ^ (data[i] << 8));
        for (int b = 0; b < 8; b++) {
            ref = (ref & 0x8000u) != 0u ? (uint16_t)((ref << 1) ^ 0x1021u) : (uint16_t)(ref << 1);
        }
    }
    TEST_ASSERT_EQUAL_HEX16(ref, whole);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_expedited_upload_1_byte);
    RUN_TEST(test_expedited_upload_2_bytes);
    RUN_TEST(test_expedited_upload_3_bytes);
    RUN_TEST(test_expedited_upload_4_bytes);
    RUN_TEST(test_expedited_upload_echoes_sub_index);
    RUN_TEST(test_expedited_upload_of_a_short_string);
    RUN_TEST(test_expedited_upload_after_a_longer_one_pads_with_zeros);
    RUN_TEST(test_upload_comm_as_32_answers_four_bytes_in_0x1000_0x1fff_only);
    RUN_TEST(test_upload_ignores_the_data_bytes_of_the_request);
    RUN_TEST(test_expedited_download_1_byte);
    RUN_TEST(test_expedited_download_2_bytes);
    RUN_TEST(test_expedited_download_3_bytes);
    RUN_TEST(test_expedited_download_4_bytes);
    RUN_TEST(test_expedited_download_to_a_sub_index);
    RUN_TEST(test_expedited_download_without_size_takes_the_type_size);
    RUN_TEST(test_expedited_download_without_size_to_u32);
    RUN_TEST(test_expedited_download_of_a_short_string);
    RUN_TEST(test_expedited_round_trip);
    RUN_TEST(test_upload_of_a_missing_object_aborts_0x06020000);
    RUN_TEST(test_download_to_a_missing_object_aborts_0x06020000);
    RUN_TEST(test_upload_of_a_missing_sub_index_aborts_0x06090011);
    RUN_TEST(test_download_to_a_missing_sub_index_aborts_0x06090011);
    RUN_TEST(test_download_to_read_only_aborts_0x06010002);
    RUN_TEST(test_download_to_const_aborts_0x06010002);
    RUN_TEST(test_segmented_download_to_read_only_aborts_at_the_initiate);
    RUN_TEST(test_upload_of_write_only_aborts_0x06010001);
    RUN_TEST(test_write_only_accepts_a_download);
    RUN_TEST(test_expedited_too_long_aborts_0x06070012);
    RUN_TEST(test_expedited_too_short_aborts_0x06070013);
    RUN_TEST(test_announced_size_too_long_aborts_0x06070012);
    RUN_TEST(test_announced_size_too_short_aborts_0x06070013);
    RUN_TEST(test_announced_size_beyond_string_capacity_aborts_0x06070012);
    RUN_TEST(test_announced_huge_size_aborts_without_overflow);
    RUN_TEST(test_boolean_out_of_range_aborts_0x06090030);
    RUN_TEST(test_real_nan_aborts_0x06090030);
    RUN_TEST(test_value_too_high_aborts_0x06090031);
    RUN_TEST(test_value_too_low_aborts_0x06090032);
    RUN_TEST(test_value_at_the_limit_is_written);
    RUN_TEST(test_hook_abort_0x06040041_passes_through);
    RUN_TEST(test_hook_abort_0x06040042_passes_through);
    RUN_TEST(test_hook_abort_0x06040043_passes_through);
    RUN_TEST(test_hook_abort_0x08000020_passes_through);
    RUN_TEST(test_hook_abort_0x08000021_passes_through);
    RUN_TEST(test_hook_abort_0x08000022_passes_through);
    RUN_TEST(test_hook_refusal_of_a_segmented_download_leaves_the_value);
    RUN_TEST(test_refresh_hook_refusal_aborts_the_upload);
    RUN_TEST(test_comm_objects_read_only_in_operational_abort_0x08000022);
    RUN_TEST(test_domain_without_hook_download_aborts_0x06010000);
    RUN_TEST(test_domain_without_hook_upload_aborts_0x08000024);
    RUN_TEST(test_frames_shorter_than_8_bytes_are_dropped_and_counted);
    RUN_TEST(test_short_frame_calls_leave_the_server_usable);
    RUN_TEST(test_short_frame_during_a_transfer_leaves_it_going);
    RUN_TEST(test_rtr_frame_is_dropped);
    RUN_TEST(test_unknown_command_specifier_aborts_0x05040001);
    RUN_TEST(test_unknown_command_during_a_transfer_ends_it);
    RUN_TEST(test_download_segment_while_idle_aborts_0x05040001);
    RUN_TEST(test_upload_segment_while_idle_aborts_0x05040001);
    RUN_TEST(test_block_sub_commands_while_idle_abort_0x05040001);
    RUN_TEST(test_wrong_segment_kind_aborts_0x05040001);
    RUN_TEST(test_abort_while_idle_is_ignored);
    RUN_TEST(test_client_abort_ends_a_download_silently);
    RUN_TEST(test_new_initiate_replaces_a_transfer_without_an_abort);
    RUN_TEST(test_new_download_initiate_during_an_upload);
    RUN_TEST(test_failed_new_initiate_aborts_with_its_own_multiplexer);
    RUN_TEST(test_server_abort_sends_the_code_with_the_multiplexer);
    RUN_TEST(test_aborts_are_counted);
    RUN_TEST(test_stopped_node_drops_the_transfer_and_answers_nothing);
    RUN_TEST(test_init_keeps_the_timeout_and_defaults_zero);
    RUN_TEST(test_configured_timeout_comes_from_the_node_config);
    RUN_TEST(test_idle_server_has_no_deadline);
#if !CO_CONFIG_TIME32
    RUN_TEST(test_timeout_near_the_end_of_time_saturates);
#endif
    RUN_TEST(test_responses_use_the_configured_cob_id);
    RUN_TEST(test_crc16_check_value);
    RUN_TEST(test_crc16_continues_across_pieces);
    return UNITY_END();
}
