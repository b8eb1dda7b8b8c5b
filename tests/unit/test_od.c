/* Object dictionary access on the generated test dictionary (od/test/test.eds): lookup, every
 * basic type, lengths, limits, access rights per origin, NMT-state rule, hooks, strings, domains,
 * node-ID defaults and the storage layout. Every refused write leaves the value untouched. */
#include <string.h>

#include "../../src/dispatch.h"
#include "../../src/services.h" /* co_can_id_restricted, co_node_hook_search */
#include "od_test.h"
#include "test_support.h"
#include "unity.h"

static test_node t;

void setUp(void)
{
    test_node_start(&t, 5);
    fake_bus_clear(&t.bus);
}

void tearDown(void) {}

static co_od_ref ref_of(uint16_t index, uint8_t sub)
{
    co_od_ref ref;
    TEST_ASSERT_EQUAL_HEX32(0, co_od_locate(&co_od_test, index, sub, &ref));
    return ref;
}

/* Snapshot of one value, to prove a refused write changed nothing. */
static uint8_t saved[64];
static void save_value(uint16_t index, uint8_t sub)
{
    co_od_ref r = ref_of(index, sub);
    memcpy(saved, t.values + co_od_value_offset(r.entry, r.sub), r.sub->size);
}
static void assert_value_unchanged(uint16_t index, uint8_t sub)
{
    co_od_ref r = ref_of(index, sub);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(saved, t.values + co_od_value_offset(r.entry, r.sub), r.sub->size);
}

static co_abort write_bytes(uint16_t index, uint8_t sub, const void *data, uint32_t len,
                            co_od_origin origin)
{
    return co_od_write(&t.node, index, sub, data, len, origin);
}

static co_abort write_le(uint16_t index, uint8_t sub, uint64_t value, uint32_t len)
{
    uint8_t b[8];
    for (uint32_t i = 0; i < 8u; i++) {
        b[i] = (uint8_t)(value >> (8u * i));
    }
    save_value(index, sub);
    co_abort rc = write_bytes(index, sub, b, len, CO_ORIGIN_SDO);
    if (rc != CO_ABORT_NONE) {
        assert_value_unchanged(index, sub);
    }
    return rc;
}

static uint64_t read_le(uint16_t index, uint8_t sub, uint32_t expect_len)
{
    uint8_t b[8] = {0};
    uint32_t len = 0;
    TEST_ASSERT_EQUAL_HEX32(0, co_od_read(&t.node, index, sub, b, sizeof b, &len, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT32(expect_len, len);
    uint64_t v = 0;
    for (uint32_t i = len; i > 0u; i--) {
        v = (v << 8) | b[i - 1u];
    }
    return v;
}

/* --- lookup -------------------------------------------------------------------------------- */

static void test_lookup_finds_every_entry_and_misses_others(void)
{
    for (uint32_t i = 0; i < co_od_test.entry_count; i++) {
        const co_od_entry *e = &co_od_test.entries[i];
        TEST_ASSERT_EQUAL_PTR(e, co_od_find_entry(&co_od_test, e->index));
        if (i > 0u) {
            TEST_ASSERT_TRUE(co_od_test.entries[i - 1u].index < e->index);
        }
        for (uint32_t s = 0; s < e->sub_count; s++) {
            TEST_ASSERT_EQUAL_PTR(&e->subs[s], co_od_find_sub(e, e->subs[s].subindex));
        }
    }
    TEST_ASSERT_NULL(co_od_find_entry(&co_od_test, 0x0000));
    TEST_ASSERT_NULL(co_od_find_entry(&co_od_test, 0x1002));
    TEST_ASSERT_NULL(co_od_find_entry(&co_od_test, 0xFFFF));
}

static void test_missing_object_and_subindex_aborts(void)
{
    uint8_t b[4] = {0};
    uint32_t len;
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_OBJECT,
                            co_od_read(&t.node, 0x2F00, 0, b, 4, &len, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_SUBINDEX,
                            co_od_read(&t.node, 0x2050, 5, b, 4, &len, CO_ORIGIN_SDO));
    /* a gap inside a record: 0x1400 has subs 0, 1, 2, 5 */
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_SUBINDEX,
                            co_od_read(&t.node, 0x1400, 3, b, 4, &len, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_OBJECT, write_bytes(0x2F00, 0, b, 1, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_SUBINDEX, write_bytes(0x2050, 9, b, 4, CO_ORIGIN_SDO));
}

/* --- every basic type ----------------------------------------------------------------------- */

static void test_defaults_of_every_basic_type(void)
{
    TEST_ASSERT_EQUAL_HEX64(1, read_le(0x2000, 0, 1));
    TEST_ASSERT_EQUAL_HEX64(0xFB, read_le(0x2001, 0, 1));            /* -5 */
    TEST_ASSERT_EQUAL_HEX64(0xFC18, read_le(0x2002, 0, 2));          /* -1000 */
    TEST_ASSERT_EQUAL_HEX64(0xFEEE90, read_le(0x2003, 0, 3));        /* -70000 in 24 bits */
    TEST_ASSERT_EQUAL_HEX64(0xFFFE7960, read_le(0x2004, 0, 4));      /* -100000 */
    TEST_ASSERT_EQUAL_HEX64((uint64_t)-5000000000LL, read_le(0x2005, 0, 8));
    TEST_ASSERT_EQUAL_HEX64(200, read_le(0x2006, 0, 1));
    TEST_ASSERT_EQUAL_HEX64(50000, read_le(0x2007, 0, 2));
    TEST_ASSERT_EQUAL_HEX64(0x123456, read_le(0x2008, 0, 3));
    TEST_ASSERT_EQUAL_HEX64(0xDEADBEEF, read_le(0x2009, 0, 4));
    TEST_ASSERT_EQUAL_HEX64(0x0123456789ABCDEFULL, read_le(0x200A, 0, 8));
    TEST_ASSERT_EQUAL_HEX64(0x3FC00000, read_le(0x200B, 0, 4));      /* 1.5f */
    TEST_ASSERT_EQUAL_HEX64(0xC002000000000000ULL, read_le(0x200C, 0, 8)); /* -2.25 */
}

static void test_type_sizes_and_signedness(void)
{
    TEST_ASSERT_EQUAL_UINT32(1, co_type_size(CO_BOOLEAN));
    TEST_ASSERT_EQUAL_UINT32(3, co_type_size(CO_INTEGER24));
    TEST_ASSERT_EQUAL_UINT32(3, co_type_size(CO_UNSIGNED24));
    TEST_ASSERT_EQUAL_UINT32(5, co_type_size(CO_UNSIGNED40));
    TEST_ASSERT_EQUAL_UINT32(6, co_type_size(CO_TIME_OF_DAY));
    TEST_ASSERT_EQUAL_UINT32(7, co_type_size(CO_INTEGER56));
    TEST_ASSERT_EQUAL_UINT32(8, co_type_size(CO_REAL64));
    TEST_ASSERT_EQUAL_UINT32(0, co_type_size(CO_VISIBLE_STRING));
    TEST_ASSERT_EQUAL_UINT32(0, co_type_size(CO_DOMAIN));
    TEST_ASSERT_TRUE(co_type_is_signed(CO_INTEGER24));
    TEST_ASSERT_TRUE(co_type_is_signed(CO_INTEGER64));
    TEST_ASSERT_FALSE(co_type_is_signed(CO_UNSIGNED32));
    TEST_ASSERT_FALSE(co_type_is_signed(CO_REAL32));
}

static void test_write_and_read_back_every_basic_type(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x2000, 0, 0, 1));
    TEST_ASSERT_EQUAL_HEX64(0, read_le(0x2000, 0, 1));
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x2002, 0, 0x8000, 2));
    TEST_ASSERT_EQUAL_HEX64(0x8000, read_le(0x2002, 0, 2));
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x2004, 0, 0x80000000u, 4));
    TEST_ASSERT_EQUAL_HEX64(0x80000000u, read_le(0x2004, 0, 4));
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x2005, 0, 0x8000000000000000ULL, 8));
    TEST_ASSERT_EQUAL_HEX64(0x8000000000000000ULL, read_le(0x2005, 0, 8));
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x2006, 0, 0xFF, 1));
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x2008, 0, 0xFFFFFF, 3));
    TEST_ASSERT_EQUAL_HEX64(0xFFFFFF, read_le(0x2008, 0, 3));
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x2009, 0, 0, 4));
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x200A, 0, 0xFFFFFFFFFFFFFFFFULL, 8));
    TEST_ASSERT_EQUAL_HEX64(0xFFFFFFFFFFFFFFFFULL, read_le(0x200A, 0, 8));
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x200C, 0, 0x4000000000000000ULL, 8)); /* 2.0 */
}

static void test_wrong_length_is_refused_for_each_size(void)
{
    static const struct { uint16_t index; uint32_t size; } objs[] = {
        {0x2000, 1}, {0x2002, 2}, {0x2003, 3}, {0x2004, 4}, {0x2005, 8}, {0x2006, 1},
        {0x2008, 3}, {0x2009, 4}, {0x200A, 8}, {0x200B, 4}, {0x200C, 8}, {0x200F, 4}};
    for (size_t i = 0; i < sizeof objs / sizeof objs[0]; i++) {
        TEST_ASSERT_EQUAL_HEX32(CO_ABORT_TYPE_TOO_LONG, write_le(objs[i].index, 0, 0, objs[i].size + 1u));
        TEST_ASSERT_EQUAL_HEX32(CO_ABORT_TYPE_TOO_SHORT, write_le(objs[i].index, 0, 0, objs[i].size - 1u));
    }
}

static void test_boolean_accepts_only_0_and_1(void)
{
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_RANGE, write_le(0x2000, 0, 2, 1));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_RANGE, write_le(0x2000, 0, 0xFF, 1));
    TEST_ASSERT_EQUAL_HEX64(1, read_le(0x2000, 0, 1));
}

/* --- limits ------------------------------------------------------------------------------- */

static void test_signed8_limits(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x2001, 0, 100, 1));
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x2001, 0, (uint8_t)-100, 1));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_HIGH, write_le(0x2001, 0, 101, 1));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_HIGH, write_le(0x2001, 0, 127, 1));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_LOW, write_le(0x2001, 0, (uint8_t)-101, 1));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_LOW, write_le(0x2001, 0, 0x80, 1));
    TEST_ASSERT_EQUAL_HEX64(0x9C, read_le(0x2001, 0, 1));
}

static void test_signed24_limits_sign_extend(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x2003, 0, 100000, 3));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_HIGH, write_le(0x2003, 0, 100001, 3));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_LOW, write_le(0x2003, 0, 0xFE795F, 3)); /* -100001 */
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x2003, 0, 0xFE7960, 3));                     /* -100000 */
}

static void test_unsigned16_limits(void)
{
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_LOW, write_le(0x2007, 0, 99, 2));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_LOW, write_le(0x2007, 0, 0, 2));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_HIGH, write_le(0x2007, 0, 60001, 2));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_HIGH, write_le(0x2007, 0, 0xFFFF, 2));
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x2007, 0, 100, 2));
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x2007, 0, 60000, 2));
}

static uint32_t float_bits(float f)
{
    uint32_t b;
    memcpy(&b, &f, sizeof b);
    return b;
}

static void test_real32_limits_and_nan(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x200B, 0, float_bits(10.0f), 4));
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x200B, 0, float_bits(-10.0f), 4));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_HIGH, write_le(0x200B, 0, float_bits(10.5f), 4));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_LOW, write_le(0x200B, 0, float_bits(-11.0f), 4));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_RANGE, write_le(0x200B, 0, 0x7FC00000u, 4));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_HIGH, write_le(0x200B, 0, 0x7F800000u, 4)); /* +inf */
}

static void test_high_limit_only(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x2080, 0, 0, 1));
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x2080, 0, 100, 1));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_HIGH, write_le(0x2080, 0, 101, 1));
}

static void test_record_and_array_members_keep_their_limits(void)
{
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_HIGH, write_le(0x2040, 2, 501, 2));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_LOW, write_le(0x2040, 2, (uint16_t)-501, 2));
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x2040, 2, (uint16_t)-500, 2));
    for (uint8_t s = 1; s <= 4u; s++) {
        TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_HIGH, write_le(0x2050, s, 1001, 4));
        TEST_ASSERT_EQUAL_HEX32(0, write_le(0x2050, s, (uint32_t)-1000, 4));
    }
    TEST_ASSERT_EQUAL_HEX64(4, read_le(0x2050, 0, 1));
}

static void test_identical_limits_share_one_entry(void)
{
    co_od_ref a = ref_of(0x2022, 0), b = ref_of(0x2070, 0);
    TEST_ASSERT_TRUE((a.sub->flags & CO_OD_LIMITS) != 0u);
    TEST_ASSERT_EQUAL_UINT16(a.sub->limit, b.sub->limit);
    TEST_ASSERT_TRUE(a.sub->limit < co_od_test.limit_count);
}

static void test_check_value_without_writing(void)
{
    uint8_t b[2] = {0x61, 0xEA}; /* 60001 */
    co_od_ref r = ref_of(0x2007, 0);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_HIGH, co_od_check_value(&co_od_test, r, b, 2));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_TYPE_TOO_LONG, co_od_check_value(&co_od_test, r, b, 3));
    b[1] = 0x00; /* 97 */
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_LOW, co_od_check_value(&co_od_test, r, b, 2));
    TEST_ASSERT_EQUAL_UINT16(50000, co_od_get_u16(&t.node, 0x2007, 0)); /* nothing written */
}

/* --- access rights ------------------------------------------------------------------------- */

static void test_read_only_refuses_sdo_but_not_application(void)
{
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_READ_ONLY, write_le(0x2020, 0, 1, 2));
    TEST_ASSERT_EQUAL_HEX64(0x1234, read_le(0x2020, 0, 2));
    TEST_ASSERT_EQUAL_HEX32(0, co_od_set_u16(&t.node, 0x2020, 0, 0x4321));
    TEST_ASSERT_EQUAL_HEX64(0x4321, read_le(0x2020, 0, 2));
}

static void test_const_refuses_sdo_write(void)
{
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_READ_ONLY, write_le(0x2025, 0, 1, 2));
    TEST_ASSERT_EQUAL_HEX64(0xCAFE, read_le(0x2025, 0, 2));
    TEST_ASSERT_TRUE((ref_of(0x2025, 0).sub->flags & CO_OD_CONST) != 0u);
}

static void test_write_only_refuses_sdo_read(void)
{
    uint8_t b[4];
    uint32_t len = 99;
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_WRITE_ONLY,
                            co_od_read(&t.node, 0x2021, 0, b, 4, &len, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT32(0, len);
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x2021, 0, 7, 2));
    TEST_ASSERT_EQUAL_UINT16(7, co_od_get_u16(&t.node, 0x2021, 0));
}

static void test_pdo_mapping_flags_follow_access_type(void)
{
    TEST_ASSERT_EQUAL_HEX8(CO_OD_READ | CO_OD_WRITE | CO_OD_RPDO,
                           ref_of(0x2023, 0).sub->flags & 0x0Fu);
    TEST_ASSERT_EQUAL_HEX8(CO_OD_READ | CO_OD_WRITE | CO_OD_TPDO,
                           ref_of(0x2024, 0).sub->flags & 0x0Fu);
    TEST_ASSERT_EQUAL_HEX8(CO_OD_READ | CO_OD_WRITE | CO_OD_TPDO | CO_OD_RPDO,
                           ref_of(0x2026, 0).sub->flags & 0x0Fu);
    TEST_ASSERT_EQUAL_HEX8(CO_OD_WRITE | CO_OD_RPDO, ref_of(0x2027, 0).sub->flags & 0x0Fu);
    TEST_ASSERT_EQUAL_HEX8(CO_OD_READ | CO_OD_TPDO, ref_of(0x2034, 0).sub->flags & 0x0Fu);
    TEST_ASSERT_EQUAL_HEX8(CO_OD_READ | CO_OD_WRITE, ref_of(0x2022, 0).sub->flags & 0x0Fu);
}

static void test_rpdo_origin_needs_rpdo_mappable(void)
{
    uint8_t b[2] = {1, 0};
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NOT_MAPPABLE, write_bytes(0x2022, 0, b, 2, CO_ORIGIN_RPDO));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NOT_MAPPABLE, write_bytes(0x2024, 0, b, 2, CO_ORIGIN_RPDO));
    TEST_ASSERT_EQUAL_HEX32(0, write_bytes(0x2023, 0, b, 2, CO_ORIGIN_RPDO));
    TEST_ASSERT_EQUAL_UINT16(1, co_od_get_u16(&t.node, 0x2023, 0));
}

static void test_rpdo_write_out_of_range_is_refused(void)
{
    uint8_t b[4];
    co_put_le32(b, 100001u);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_HIGH, write_bytes(0x2033, 0, b, 4, CO_ORIGIN_RPDO));
    TEST_ASSERT_EQUAL_INT32(0, co_od_get_i32(&t.node, 0x2033, 0));
}

static void test_application_cannot_write_out_of_range_either(void)
{
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_HIGH, co_od_set_u16(&t.node, 0x2022, 0, 1001));
    TEST_ASSERT_EQUAL_UINT16(500, co_od_get_u16(&t.node, 0x2022, 0));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_HIGH, co_od_set_i16(&t.node, 0x605A, 0, 8));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_LOW, co_od_set_i16(&t.node, 0x605A, 0, -3));
    TEST_ASSERT_EQUAL_INT16(2, co_od_get_i16(&t.node, 0x605A, 0));
}

/* --- strings and domains ------------------------------------------------------------------- */

static void test_visible_string_length_and_shorter_write(void)
{
    uint8_t b[40];
    uint32_t len;
    TEST_ASSERT_EQUAL_HEX32(0, co_od_read(&t.node, 0x200D, 0, b, sizeof b, &len, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT32(5, len);
    TEST_ASSERT_EQUAL_MEMORY("hello", b, 5);
    TEST_ASSERT_EQUAL_HEX32(0, write_bytes(0x200D, 0, "abc", 3, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_HEX32(0, co_od_read(&t.node, 0x200D, 0, b, sizeof b, &len, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT32(3, len);
    TEST_ASSERT_EQUAL_MEMORY("abc", b, 3);
}

static void test_visible_string_capacity(void)
{
    static const char long_text[] = "0123456789abcdef0123456789abcdefX"; /* 33 */
    co_od_ref r = ref_of(0x200D, 0);
    TEST_ASSERT_EQUAL_UINT16(32, r.sub->size);
    TEST_ASSERT_EQUAL_HEX32(0, write_bytes(0x200D, 0, long_text, 32, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_TYPE_TOO_LONG, write_bytes(0x200D, 0, long_text, 33, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT16(16, ref_of(0x200E, 0).sub->size);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_TYPE_TOO_LONG, write_bytes(0x200E, 0, long_text, 17, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_HEX32(0, write_bytes(0x200E, 0, long_text, 16, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT32(16, co_od_value_length(&t.node, ref_of(0x200E, 0)));
}

static void test_read_into_too_small_buffer(void)
{
    uint8_t b[4];
    uint32_t len = 9;
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_OUT_OF_MEMORY,
                            co_od_read(&t.node, 0x200D, 0, b, 4, &len, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT32(0, len);
}

static void test_octet_string(void)
{
    const uint8_t def[4] = {1, 2, 3, 4};
    uint8_t b[8];
    uint32_t len;
    TEST_ASSERT_EQUAL_HEX32(0, co_od_read(&t.node, 0x200F, 0, b, sizeof b, &len, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT32(4, len);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(def, b, 4);
}

static void test_domain_without_hook(void)
{
    uint8_t b[4];
    uint32_t len;
    TEST_ASSERT_NULL(co_od_value_ptr(&t.node, ref_of(0x2010, 0)));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_DATA,
                            co_od_read(&t.node, 0x2010, 0, b, 4, &len, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_UNSUPPORTED_ACCESS, write_bytes(0x2010, 0, b, 4, CO_ORIGIN_SDO));
}

static uint8_t domain_store[16];
static uint32_t domain_len;

static co_abort domain_read(co_node *node, void *ctx, co_od_ref ref, uint32_t offset,
                            uint8_t *buf, uint32_t cap, uint32_t *len, uint32_t *total)
{
    (void)node;
    (void)ctx;
    (void)ref;
    uint32_t n = domain_len - offset;
    if (n > cap) {
        n = cap;
    }
    memcpy(buf, domain_store + offset, n);
    *len = n;
    *total = domain_len;
    return CO_ABORT_NONE;
}

static co_abort domain_write(co_node *node, void *ctx, co_od_ref ref, uint32_t offset,
                             const uint8_t *data, uint32_t len, uint32_t total, bool last)
{
    (void)node;
    (void)ctx;
    (void)ref;
    (void)total;
    (void)last;
    if (offset + len > sizeof domain_store) {
        return CO_ABORT_OUT_OF_MEMORY;
    }
    memcpy(domain_store + offset, data, len);
    domain_len = offset + len;
    return CO_ABORT_NONE;
}

static void test_domain_through_hook(void)
{
    co_od_hook h = {0x2010, 0x2010, NULL, NULL, domain_read, domain_write, NULL};
    TEST_ASSERT_TRUE(co_node_add_hook(&t.node, &h));
    TEST_ASSERT_EQUAL_HEX32(0, write_bytes(0x2010, 0, "domain", 6, CO_ORIGIN_SDO));
    uint8_t b[16];
    uint32_t len;
    TEST_ASSERT_EQUAL_HEX32(0, co_od_read(&t.node, 0x2010, 0, b, sizeof b, &len, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT32(6, len);
    TEST_ASSERT_EQUAL_MEMORY("domain", b, 6);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_OUT_OF_MEMORY,
                            write_bytes(0x2010, 0, "0123456789abcdefg", 17, CO_ORIGIN_SDO));
}

/* --- hooks --------------------------------------------------------------------------------- */

static int refreshes;
static co_abort refresh_2020(co_node *node, void *ctx, co_od_ref ref)
{
    (void)ctx;
    refreshes++;
    co_put_le16(node->values + co_od_value_offset(ref.entry, ref.sub), 0x7777);
    return CO_ABORT_NONE;
}

static void test_refresh_hook_runs_before_sdo_read(void)
{
    co_od_hook h = {0x2020, 0x2020, refresh_2020, NULL, NULL, NULL, NULL};
    co_node_add_hook(&t.node, &h);
    TEST_ASSERT_EQUAL_HEX64(0x7777, read_le(0x2020, 0, 2));
    TEST_ASSERT_EQUAL(1, refreshes);
}

static uint16_t hook_saw;
static co_abort veto_odd(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                         uint32_t len, co_od_origin origin)
{
    (void)ctx;
    (void)len;
    (void)origin;
    /* the hook sees the new value while the old one is still in place */
    hook_saw = co_get_le16(node->values + co_od_value_offset(ref.entry, ref.sub));
    return (data[0] & 1u) != 0u ? CO_ABORT_PARAM_INCOMPATIBLE : CO_ABORT_NONE;
}

static void test_write_hook_sees_old_value_and_can_veto(void)
{
    co_od_hook h = {0x2022, 0x2022, NULL, veto_odd, NULL, NULL, NULL};
    co_node_add_hook(&t.node, &h);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_PARAM_INCOMPATIBLE, write_le(0x2022, 0, 7, 2));
    TEST_ASSERT_EQUAL_UINT16(500, hook_saw);
    TEST_ASSERT_EQUAL_HEX32(0, write_le(0x2022, 0, 8, 2));
    TEST_ASSERT_EQUAL_UINT16(8, co_od_get_u16(&t.node, 0x2022, 0));
    /* limits are checked before the hook: an out-of-range value never reaches it */
    hook_saw = 0;
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_HIGH, write_le(0x2022, 0, 2000, 2));
    TEST_ASSERT_EQUAL_UINT16(0, hook_saw);
}

/* --- defaults and layout ------------------------------------------------------------------- */

static void test_node_id_relative_default_in_application_area(void)
{
    TEST_ASSERT_EQUAL_HEX32(0x1005, co_od_get_u32(&t.node, 0x2060, 0));
    TEST_ASSERT_TRUE((ref_of(0x2060, 0).sub->flags & CO_OD_NODEID) != 0u);
}

static void test_storage_layout_groups_values(void)
{
    co_od_ref hb = ref_of(0x1017, 0);
    co_od_ref param = ref_of(0x2022, 0);
    co_od_ref ctrl = ref_of(0x6040, 0);
    co_od_ref ro = ref_of(0x2020, 0);
    co_od_ref qs = ref_of(0x605A, 0);
    uint32_t hb_at = co_od_value_offset(hb.entry, hb.sub);
    uint32_t param_at = co_od_value_offset(param.entry, param.sub);
    uint32_t qs_at = co_od_value_offset(qs.entry, qs.sub);
    TEST_ASSERT_TRUE(hb_at + hb.sub->size <= co_od_test.comm_persist_size);
    TEST_ASSERT_TRUE((hb.sub->flags & CO_OD_PERSIST) != 0u);
    TEST_ASSERT_TRUE(param_at >= co_od_test.comm_persist_size);
    TEST_ASSERT_TRUE(param_at + param.sub->size <= co_od_test.persist_size);
    TEST_ASSERT_TRUE(qs_at >= co_od_test.comm_persist_size && qs_at < co_od_test.persist_size);
    TEST_ASSERT_TRUE(co_od_value_offset(ctrl.entry, ctrl.sub) >= co_od_test.persist_size);
    TEST_ASSERT_TRUE(co_od_value_offset(ro.entry, ro.sub) >= co_od_test.persist_size);
    TEST_ASSERT_TRUE(co_od_test.persist_size <= co_od_test.value_size);
    TEST_ASSERT_NOT_EQUAL(0, co_od_test.layout_hash);
}

static void test_values_are_aligned_to_their_size(void)
{
    for (uint32_t i = 0; i < co_od_test.entry_count; i++) {
        const co_od_entry *e = &co_od_test.entries[i];
        for (uint32_t s = 0; s < e->sub_count; s++) {
            const co_od_sub *sub = &e->subs[s];
            uint32_t size = co_type_size(sub->type);
            if (size == 2u || size == 4u || size == 8u) {
                TEST_ASSERT_EQUAL_UINT32(0, co_od_value_offset(e, sub) % size);
            }
            TEST_ASSERT_TRUE(sub->type == CO_DOMAIN ||
                             co_od_value_offset(e, sub) + sub->size <= co_od_test.value_size);
        }
    }
}

static void test_typed_getters_on_absent_or_mismatched_objects(void)
{
    TEST_ASSERT_EQUAL_UINT32(0, co_od_get_u32(&t.node, 0x2F00, 0));
    TEST_ASSERT_EQUAL_UINT32(0, co_od_get_u32(&t.node, 0x2022, 0)); /* u16, asked as u32 */
    TEST_ASSERT_EQUAL_UINT8(0, co_od_get_u8(&t.node, 0x2010, 0));  /* domain */
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_TYPE_TOO_LONG, co_od_set_u32(&t.node, 0x2022, 0, 1));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_OBJECT, co_od_set_u8(&t.node, 0x2F00, 0, 1));
}

static void test_typed_setters_round_trip(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, co_od_set_i32(&t.node, 0x2004, 0, -123456));
    TEST_ASSERT_EQUAL_INT32(-123456, co_od_get_i32(&t.node, 0x2004, 0));
    TEST_ASSERT_EQUAL_HEX32(0, co_od_set_u8(&t.node, 0x2006, 0, 17));
    TEST_ASSERT_EQUAL_UINT8(17, co_od_get_u8(&t.node, 0x2006, 0));
    TEST_ASSERT_EQUAL_HEX32(0, co_od_set_i16(&t.node, 0x6042, 0, -1500));
    TEST_ASSERT_EQUAL_INT16(-1500, co_od_get_i16(&t.node, 0x6042, 0));
}

/* The CAN-IDs CiA 301 keeps out of configurable communication objects, against the list. */
static void test_restricted_can_ids_are_the_listed_ranges(void)
{
    for (uint32_t id = 0; id <= 0xFFFFu; id++) {
        bool listed = id <= 0x07Fu || (id >= 0x101u && id <= 0x180u) ||
                      (id >= 0x581u && id <= 0x5FFu) || (id >= 0x601u && id <= 0x67Fu) ||
                      (id >= 0x6E0u && id <= 0x6FFu) || id >= 0x701u;
        TEST_ASSERT_EQUAL_MESSAGE(listed, co_can_id_restricted((uint16_t)id), "CAN-ID");
    }
}

/* The core's objects get a slot of the core, one per service binding; the others of
 * 0x1000-0x1FFF none of the core. */
static void test_core_objects_have_their_service_slot(void)
{
    static const uint16_t same[][4] = {
        {0x1003u}, {0x1005u, 0x1006u, 0x1007u}, {0x1019u}, {0x100Cu, 0x100Du}, {0x1010u, 0x1011u},
        {0x1014u, 0x1015u}, {0x1016u}, {0x1017u}, {0x1029u}, {0x1400u, 0x15FFu, 0x1A00u, 0x1BFFu}};
    uint8_t seen[sizeof same / sizeof same[0]];
    bool core[0x1000] = {false};
    for (uint32_t g = 0; g < sizeof same / sizeof same[0]; g++) {
        seen[g] = co_node_hook_search(&t.node, same[g][0]);
        TEST_ASSERT_TRUE(seen[g] >= CO_SLOT_CORE);
        for (uint32_t k = 0; k < 4u && same[g][k] != 0u; k++) {
            TEST_ASSERT_EQUAL_UINT8(seen[g], co_node_hook_search(&t.node, same[g][k]));
        }
        for (uint32_t h = 0; h < g; h++) {
            TEST_ASSERT_NOT_EQUAL(seen[h], seen[g]);
        }
    }
    for (uint32_t i = 0x1400u; i <= 0x1BFFu; i++) {
        core[i - 0x1000u] = true;
    }
    for (uint32_t g = 0; g + 1u < sizeof same / sizeof same[0]; g++) {
        for (uint32_t k = 0; k < 4u && same[g][k] != 0u; k++) {
            core[same[g][k] - 0x1000u] = true;
        }
    }
    for (uint32_t i = 0x1000u; i <= 0x1FFFu; i++) {
        TEST_ASSERT_EQUAL_MESSAGE(core[i - 0x1000u],
                                  co_node_hook_search(&t.node, (uint16_t)i) >= CO_SLOT_CORE,
                                  "core object");
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_lookup_finds_every_entry_and_misses_others);
    RUN_TEST(test_missing_object_and_subindex_aborts);
    RUN_TEST(test_defaults_of_every_basic_type);
    RUN_TEST(test_type_sizes_and_signedness);
    RUN_TEST(test_write_and_read_back_every_basic_type);
    RUN_TEST(test_wrong_length_is_refused_for_each_size);
    RUN_TEST(test_boolean_accepts_only_0_and_1);
    RUN_TEST(test_signed8_limits);
    RUN_TEST(test_signed24_limits_sign_extend);
    RUN_TEST(test_unsigned16_limits);
    RUN_TEST(test_real32_limits_and_nan);
    RUN_TEST(test_high_limit_only);
    RUN_TEST(test_record_and_array_members_keep_their_limits);
    RUN_TEST(test_identical_limits_share_one_entry);
    RUN_TEST(test_check_value_without_writing);
    RUN_TEST(test_read_only_refuses_sdo_but_not_application);
    RUN_TEST(test_const_refuses_sdo_write);
    RUN_TEST(test_write_only_refuses_sdo_read);
    RUN_TEST(test_pdo_mapping_flags_follow_access_type);
    RUN_TEST(test_rpdo_origin_needs_rpdo_mappable);
    RUN_TEST(test_rpdo_write_out_of_range_is_refused);
    RUN_TEST(test_application_cannot_write_out_of_range_either);
    RUN_TEST(test_visible_string_length_and_shorter_write);
    RUN_TEST(test_visible_string_capacity);
    RUN_TEST(test_read_into_too_small_buffer);
    RUN_TEST(test_octet_string);
    RUN_TEST(test_domain_without_hook);
    RUN_TEST(test_domain_through_hook);
    RUN_TEST(test_refresh_hook_runs_before_sdo_read);
    RUN_TEST(test_write_hook_sees_old_value_and_can_veto);
    RUN_TEST(test_node_id_relative_default_in_application_area);
    RUN_TEST(test_storage_layout_groups_values);
    RUN_TEST(test_values_are_aligned_to_their_size);
    RUN_TEST(test_typed_getters_on_absent_or_mismatched_objects);
    RUN_TEST(test_typed_setters_round_trip);
    RUN_TEST(test_restricted_can_ids_are_the_listed_ranges);
    RUN_TEST(test_core_objects_have_their_service_slot);
    return UNITY_END();
}
