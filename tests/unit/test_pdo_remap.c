/* PDO parameter writes through SDO (test dictionary, node 5): the CiA 301 remapping procedure
 * end to end for a TPDO and an RPDO, and every refusal with its abort code and the value left
 * untouched: mapping while valid, entries while sub 0 != 0, absent / not mappable / wrong
 * direction / wrong length objects, more than 64 bits, dummies, COB-ID rules, reserved
 * transmission types, inhibit time and SYNC start value while valid; the configurable abort
 * codes; and the stored mapping coming back on reset communication. */
#include <string.h>

#include "od_test.h"
#include "test_support.h"
#include "unity.h"

#define ABORT_NOT_MAPPABLE 0x06040041u
#define ABORT_PDO_LENGTH 0x06040042u
#define ABORT_INCOMPATIBLE 0x06040043u

static test_node t;

static void start_with(const co_pdo_config *pc)
{
    memset(&t, 0, sizeof t);
    t.storage = fake_store_storage(&t.store);
    co_node_config cfg = co_node_default_config();
    cfg.od = &co_od_test;
    cfg.values = t.values;
    cfg.node_id = 5;
    cfg.driver = fake_bus_driver(&t.bus);
    cfg.storage = &t.storage;
    if (pc != NULL) {
        cfg.pdo = *pc;
    }
    TEST_ASSERT_TRUE(co_node_init(&t.node, &cfg));
    co_node_start(&t.node, t.now);
    fake_bus_clear(&t.bus);
}

void setUp(void)
{
    start_with(NULL);
}

void tearDown(void) {}

static void nmt(uint8_t command)
{
    const uint8_t d[2] = {command, 5};
    test_rx(&t, 0, 2, d);
    (void)test_advance(&t, 0);
}

static void ok(uint16_t index, uint8_t sub, uint32_t value, uint8_t size)
{
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, index, sub, value, size));
}

static uint32_t read_u32(uint16_t index, uint8_t sub)
{
    uint32_t v = 0;
    TEST_ASSERT_EQUAL_HEX32(0, sdo_read_u32(&t, index, sub, &v));
    return v;
}

/* The write is refused with code and the value reads back unchanged. */
static void refused(uint16_t index, uint8_t sub, uint32_t value, uint8_t size, uint32_t code)
{
    uint32_t before = read_u32(index, sub);
    TEST_ASSERT_EQUAL_HEX32(code, sdo_write(&t, index, sub, value, size));
    TEST_ASSERT_EQUAL_HEX32(before, read_u32(index, sub));
}

static void disable_tpdo1(void)
{
    ok(0x1800, 1, 0x80000185u, 4);
}

static void disable_rpdo1(void)
{
    ok(0x1400, 1, 0x80000205u, 4);
}

/* --- the procedure ------------------------------------------------------------------------ */

static void test_tpdo_remap_walkthrough(void)
{
    /* python-canopen's PdoMap.save(): COB-ID with bit 31, type, sub 0 = 0, entries, sub 0 = n,
     * COB-ID without bit 31. */
    ok(0x1800, 1, 0x80000185u, 4);
    ok(0x1800, 2, 0xFF, 1);
    ok(0x1A00, 0, 0, 1);
    ok(0x1A00, 1, 0x20350010u, 4);
    ok(0x1A00, 2, 0x20360020u, 4);
    ok(0x1A00, 3, 0x20340008u, 4);
    ok(0x1A00, 0, 3, 1);
    ok(0x1800, 1, 0x185u, 4);
    TEST_ASSERT_EQUAL_UINT32(3, read_u32(0x1A00, 0));
    nmt(0x01);
    TEST_ASSERT_TRUE(co_pdo_tpdo_request(&t.node, 1));
    test_advance(&t, 0);
    const uint8_t d[7] = {0x34, 0x12, 0x78, 0x56, 0x34, 0x12, 0x5A};
    expect_frame(&t, 0x185, 7, d);
    TEST_ASSERT_EQUAL_HEX32(0, co_od_set_u32(&t.node, 0x2036, 0, 0xA1B2C3D4u));
    test_advance(&t, 0);
    const uint8_t e[7] = {0x34, 0x12, 0xD4, 0xC3, 0xB2, 0xA1, 0x5A};
    expect_frame(&t, 0x185, 7, e);
}

static void test_rpdo_remap_walkthrough_with_new_cob_id(void)
{
    disable_rpdo1();
    ok(0x1600, 0, 0, 1);
    ok(0x1600, 1, 0x20300008u, 4);
    ok(0x1600, 2, 0x20320020u, 4);
    ok(0x1600, 0, 2, 1);
    ok(0x1400, 1, 0x305u, 4); /* a new CAN-ID together with enabling */
    nmt(0x01);
    const uint8_t old_id[4] = {1, 2, 3, 4};
    test_rx(&t, 0x205, 4, old_id);
    TEST_ASSERT_EQUAL_UINT8(0, co_od_get_u8(&t.node, 0x2030, 0));
    const uint8_t d[5] = {0x99, 0x44, 0x33, 0x22, 0x11};
    test_rx(&t, 0x305, 5, d);
    TEST_ASSERT_EQUAL_UINT8(0x99, co_od_get_u8(&t.node, 0x2030, 0));
    TEST_ASSERT_EQUAL_HEX32(0x11223344u, co_od_get_u32(&t.node, 0x2032, 0));
    TEST_ASSERT_EQUAL_HEX16(0, co_od_get_u16(&t.node, 0x6040, 0));
}

static void test_remap_in_operational_takes_effect_when_enabled(void)
{
    nmt(0x01);
    disable_tpdo1();
    ok(0x1A00, 0, 0, 1);
    ok(0x1A00, 1, 0x20340008u, 4);
    ok(0x1A00, 0, 1, 1);
    TEST_ASSERT_FALSE(co_pdo_tpdo_request(&t.node, 1)); /* disabled */
    ok(0x1800, 1, 0x185u, 4);
    TEST_ASSERT_TRUE(co_pdo_tpdo_request(&t.node, 1));
    test_advance(&t, 0);
    const uint8_t d[1] = {0x5A};
    expect_frame(&t, 0x185, 1, d);
}

static void test_reset_communication_restores_the_default_mapping(void)
{
    disable_tpdo1();
    ok(0x1A00, 0, 0, 1);
    ok(0x1A00, 1, 0x20340008u, 4);
    ok(0x1A00, 0, 1, 1);
    ok(0x1800, 1, 0x185u, 4);
    nmt(0x82);
    fake_bus_clear(&t.bus);
    TEST_ASSERT_EQUAL_UINT32(2, read_u32(0x1A00, 0));
    TEST_ASSERT_EQUAL_HEX32(0x60410010u, read_u32(0x1A00, 1));
    nmt(0x01);
    TEST_ASSERT_TRUE(co_pdo_tpdo_request(&t.node, 1));
    test_advance(&t, 0);
    const uint8_t d[4] = {0, 0, 0, 0};
    expect_frame(&t, 0x185, 4, d);
}

static void test_entry_of_zero_is_always_accepted_while_mapping_is_open(void)
{
    disable_tpdo1();
    ok(0x1A00, 0, 0, 1);
    ok(0x1A00, 2, 0, 4);
    TEST_ASSERT_EQUAL_HEX32(0, read_u32(0x1A00, 2));
}

/* --- mapping refusals --------------------------------------------------------------------- */

static void test_mapping_entry_refused_while_pdo_valid(void)
{
    refused(0x1A00, 1, 0x20340008u, 4, ABORT_INCOMPATIBLE);
    refused(0x1600, 2, 0x20310010u, 4, ABORT_INCOMPATIBLE);
}

static void test_mapping_sub0_refused_while_pdo_valid(void)
{
    refused(0x1A00, 0, 0, 1, ABORT_INCOMPATIBLE);
    refused(0x1600, 0, 1, 1, ABORT_INCOMPATIBLE);
}

static void test_mapping_entry_refused_while_sub0_not_zero(void)
{
    disable_tpdo1();
    refused(0x1A00, 1, 0x20340008u, 4, ABORT_INCOMPATIBLE);
    refused(0x1A00, 3, 0x20340008u, 4, ABORT_INCOMPATIBLE); /* even beyond the count */
}

static void test_mapping_absent_object_or_subindex_refused(void)
{
    disable_tpdo1();
    ok(0x1A00, 0, 0, 1);
    refused(0x1A00, 1, 0x2FFF0010u, 4, ABORT_NOT_MAPPABLE);
    refused(0x1A00, 1, 0x60410110u, 4, ABORT_NOT_MAPPABLE);
}

static void test_mapping_not_mappable_object_refused(void)
{
    disable_tpdo1();
    ok(0x1A00, 0, 0, 1);
    refused(0x1A00, 1, 0x20220010u, 4, ABORT_NOT_MAPPABLE); /* PDOMapping=0 */
    refused(0x1A00, 1, 0x20100000u | 8u, 4, ABORT_NOT_MAPPABLE); /* DOMAIN */
}

static void test_mapping_wrong_direction_refused(void)
{
    disable_tpdo1();
    ok(0x1A00, 0, 0, 1);
    refused(0x1A00, 1, 0x20270020u, 4, ABORT_NOT_MAPPABLE); /* wo, RPDO only */
    refused(0x1A00, 1, 0x60400010u, 4, ABORT_NOT_MAPPABLE); /* rww controlword */
    disable_rpdo1();
    ok(0x1600, 0, 0, 1);
    refused(0x1600, 1, 0x60410010u, 4, ABORT_NOT_MAPPABLE); /* ro statusword */
    refused(0x1600, 1, 0x20340008u, 4, ABORT_NOT_MAPPABLE);
    ok(0x1600, 1, 0x20260020u, 4); /* rw + PDOMapping: both directions */
}

static void test_mapping_wrong_length_refused(void)
{
    disable_tpdo1();
    ok(0x1A00, 0, 0, 1);
    refused(0x1A00, 1, 0x60410008u, 4, ABORT_NOT_MAPPABLE); /* 8 of 16 bits */
    refused(0x1A00, 1, 0x60410020u, 4, ABORT_NOT_MAPPABLE); /* 32 of 16 bits */
    refused(0x1A00, 1, 0x6041000Cu, 4, ABORT_NOT_MAPPABLE); /* not whole bytes */
    refused(0x1A00, 1, 0x60410011u, 4, ABORT_NOT_MAPPABLE); /* 17 bits: not whole bytes */
    refused(0x1A00, 1, 0x60410000u, 4, ABORT_NOT_MAPPABLE); /* length 0 */
}

static void test_mapping_entry_longer_than_64_bits_refused(void)
{
    disable_tpdo1();
    ok(0x1A00, 0, 0, 1);
    refused(0x1A00, 1, 0x20360048u, 4, ABORT_PDO_LENGTH);
}

static void test_sub0_over_64_bits_refused_and_pdo_keeps_old_state(void)
{
    disable_tpdo1();
    ok(0x1A00, 0, 0, 1);
    ok(0x1A00, 1, 0x20360020u, 4);
    ok(0x1A00, 2, 0x20360020u, 4);
    ok(0x1A00, 3, 0x20340008u, 4);
    refused(0x1A00, 0, 3, 1, ABORT_PDO_LENGTH); /* 72 bits */
    ok(0x1A00, 0, 2, 1);                      /* 64 bits: fine */
    TEST_ASSERT_EQUAL_UINT8(8, t.node.pdo.tpdo[0].head.size);
}

static void test_sub0_above_eight_refused(void)
{
    disable_tpdo1();
    ok(0x1A00, 0, 0, 1);
    refused(0x1A00, 0, 9, 1, ABORT_PDO_LENGTH);
    refused(0x1A00, 0, 0x40, 1, ABORT_PDO_LENGTH);
}

static void test_sub0_over_an_empty_entry_refused(void)
{
    disable_tpdo1();
    ok(0x1A00, 0, 0, 1);
    ok(0x1A00, 2, 0, 4);
    refused(0x1A00, 0, 2, 1, ABORT_NOT_MAPPABLE);
}

static void test_enabling_a_pdo_with_empty_mapping_refused(void)
{
    refused(0x1803, 1, 0x485u, 4, ABORT_INCOMPATIBLE); /* TPDO4 maps nothing */
    disable_tpdo1();
    ok(0x1A00, 0, 0, 1);
    refused(0x1800, 1, 0x185u, 4, ABORT_INCOMPATIBLE);
}

static void test_dummy_refused_unless_allowed(void)
{
    disable_rpdo1();
    ok(0x1600, 0, 0, 1);
    refused(0x1600, 1, 0x00050008u, 4, ABORT_NOT_MAPPABLE);
}

static void test_dummy_skips_bytes_of_an_rpdo_when_allowed(void)
{
    co_pdo_config pc;
    memset(&pc, 0, sizeof pc);
    pc.rpdo_dummy_mask = 1u << 5; /* Dummy0005 (UNSIGNED8) */
    start_with(&pc);
    disable_rpdo1();
    ok(0x1600, 0, 0, 1);
    ok(0x1600, 1, 0x60400010u, 4);
    ok(0x1600, 2, 0x00050008u, 4);
    ok(0x1600, 3, 0x20310010u, 4);
    refused(0x1600, 4, 0x00060008u, 4, ABORT_NOT_MAPPABLE); /* UNSIGNED16 dummy: not allowed */
    refused(0x1600, 4, 0x00050010u, 4, ABORT_NOT_MAPPABLE); /* wrong length */
    ok(0x1600, 0, 3, 1);
    ok(0x1400, 1, 0x205u, 4);
    nmt(0x01);
    const uint8_t d[5] = {0x0F, 0x00, 0xEE, 0x34, 0x12};
    test_rx(&t, 0x205, 5, d);
    TEST_ASSERT_EQUAL_HEX16(0x000F, co_od_get_u16(&t.node, 0x6040, 0));
    TEST_ASSERT_EQUAL_HEX16(0x1234, co_od_get_u16(&t.node, 0x2031, 0));
}

static void test_dummy_never_in_a_tpdo(void)
{
    co_pdo_config pc;
    memset(&pc, 0, sizeof pc);
    pc.rpdo_dummy_mask = 0xFE;
    start_with(&pc);
    disable_tpdo1();
    ok(0x1A00, 0, 0, 1);
    refused(0x1A00, 1, 0x00050008u, 4, ABORT_NOT_MAPPABLE);
}

static void test_map_while_valid_when_configured(void)
{
    co_pdo_config pc;
    memset(&pc, 0, sizeof pc);
    pc.flags = CO_PDO_MAP_WHILE_VALID;
    start_with(&pc);
    ok(0x1A00, 0, 0, 1); /* COB-ID still valid */
    refused(0x1A00, 1, 0x20340010u, 4, ABORT_NOT_MAPPABLE);
    ok(0x1A00, 1, 0x20340008u, 4);
    ok(0x1A00, 0, 1, 1);
    nmt(0x01);
    TEST_ASSERT_TRUE(co_pdo_tpdo_request(&t.node, 1));
    test_advance(&t, 0);
    const uint8_t d[1] = {0x5A};
    expect_frame(&t, 0x185, 1, d);
}

/* --- communication parameter refusals ------------------------------------------------------- */

static void test_cob_id_change_while_valid_refused(void)
{
    refused(0x1800, 1, 0x186u, 4, ABORT_INCOMPATIBLE);
    refused(0x1400, 1, 0x206u, 4, ABORT_INCOMPATIBLE);
    ok(0x1800, 1, 0x80000186u, 4); /* setting bit 31 with another CAN-ID is fine */
    ok(0x1800, 1, 0x186u, 4);
}

static void test_cob_id_29_bit_and_reserved_bits_refused(void)
{
    refused(0x1800, 1, 0xA0000185u, 4, ABORT_INCOMPATIBLE); /* bit 29, even when disabling */
    refused(0x1800, 1, 0x00000985u, 4, ABORT_INCOMPATIBLE); /* bit 11 */
    refused(0x1400, 1, 0x10000205u, 4, ABORT_INCOMPATIBLE); /* bit 28 */
}

static void test_cob_id_reserved_can_ids_refused(void)
{
    disable_tpdo1();
    refused(0x1800, 1, 0x07Fu, 4, ABORT_INCOMPATIBLE);  /* 0x001-0x07F */
    refused(0x1800, 1, 0x180u, 4, ABORT_INCOMPATIBLE);  /* 0x101-0x180 */
    refused(0x1800, 1, 0x605u, 4, ABORT_INCOMPATIBLE);  /* SDO */
    refused(0x1800, 1, 0x705u, 4, ABORT_INCOMPATIBLE);  /* NMT error control */
    refused(0x1800, 1, 0x000u, 4, ABORT_INCOMPATIBLE);  /* NMT */
    ok(0x1800, 1, 0x181u, 4);
}

static void test_rpdo_cob_id_bit_30_is_accepted(void)
{
    ok(0x1400, 1, 0x40000205u, 4); /* older masters write it back */
    nmt(0x01);
    const uint8_t d[4] = {0x0F, 0, 0, 0};
    test_rx(&t, 0x205, 4, d);
    TEST_ASSERT_EQUAL_HEX16(0x000F, co_od_get_u16(&t.node, 0x6040, 0));
}

static void test_reserved_transmission_types_refused(void)
{
    refused(0x1800, 2, 241, 1, ABORT_INCOMPATIBLE);
    refused(0x1800, 2, 251, 1, ABORT_INCOMPATIBLE);
    ok(0x1800, 2, 252, 1);
    ok(0x1800, 2, 253, 1);
    ok(0x1800, 2, 0, 1);
    ok(0x1800, 2, 240, 1);
    refused(0x1400, 2, 241, 1, ABORT_INCOMPATIBLE);
    refused(0x1400, 2, 252, 1, ABORT_INCOMPATIBLE);
    refused(0x1400, 2, 253, 1, ABORT_INCOMPATIBLE);
    ok(0x1400, 2, 254, 1);
    ok(0x1400, 2, 240, 1);
}

static void test_inhibit_time_only_while_disabled(void)
{
    refused(0x1800, 3, 100, 2, ABORT_INCOMPATIBLE);
    disable_tpdo1();
    ok(0x1800, 3, 100, 2);
    TEST_ASSERT_EQUAL_UINT32(10000, t.node.pdo.tpdo[0].inhibit_us);
}

static void test_sync_start_value_only_while_disabled_and_at_most_240(void)
{
    refused(0x1800, 6, 1, 1, ABORT_INCOMPATIBLE);
    disable_tpdo1();
    refused(0x1800, 6, 241, 1, ABORT_INCOMPATIBLE);
    ok(0x1800, 6, 240, 1);
}

static void test_event_timer_writable_while_valid(void)
{
    ok(0x1800, 5, 250, 2);
    TEST_ASSERT_EQUAL_UINT32(250000, t.node.pdo.tpdo[0].event_us);
    ok(0x1400, 5, 20, 2);
    TEST_ASSERT_EQUAL_UINT32(20000, t.node.pdo.rpdo[0].timeout_us);
}

static void test_abort_codes_follow_the_configuration(void)
{
    co_pdo_config pc;
    memset(&pc, 0, sizeof pc);
    pc.value_abort = 0x06090030u;
    pc.busy_abort = 0x06010000u;
    start_with(&pc);
    refused(0x1800, 1, 0x186u, 4, 0x06090030u);
    refused(0x1800, 2, 245, 1, 0x06090030u);
    refused(0x1A00, 1, 0x20340008u, 4, 0x06010000u);
    refused(0x1800, 3, 1, 2, 0x06010000u);
    disable_tpdo1();
    ok(0x1A00, 0, 0, 1);
    refused(0x1A00, 1, 0x20220010u, 4, ABORT_NOT_MAPPABLE); /* not configurable */
}

static void test_ro_mapping_object_sub0_and_comm_sub0_not_writable(void)
{
    refused(0x1400, 0, 2, 1, 0x06010002u); /* the dictionary refuses before the PDO layer */
    refused(0x1800, 0, 2, 1, 0x06010002u);
}

static void test_parameters_read_back_as_written(void)
{
    disable_tpdo1();
    TEST_ASSERT_EQUAL_HEX32(0x80000185u, read_u32(0x1800, 1));
    ok(0x1800, 3, 0x1234, 2);
    TEST_ASSERT_EQUAL_HEX32(0x1234, read_u32(0x1800, 3));
    ok(0x1800, 1, 0x40000190u, 4);
    TEST_ASSERT_EQUAL_HEX32(0x40000190u, read_u32(0x1800, 1));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_tpdo_remap_walkthrough);
    RUN_TEST(test_rpdo_remap_walkthrough_with_new_cob_id);
    RUN_TEST(test_remap_in_operational_takes_effect_when_enabled);
    RUN_TEST(test_reset_communication_restores_the_default_mapping);
    RUN_TEST(test_entry_of_zero_is_always_accepted_while_mapping_is_open);
    RUN_TEST(test_mapping_entry_refused_while_pdo_valid);
    RUN_TEST(test_mapping_sub0_refused_while_pdo_valid);
    RUN_TEST(test_mapping_entry_refused_while_sub0_not_zero);
    RUN_TEST(test_mapping_absent_object_or_subindex_refused);
    RUN_TEST(test_mapping_not_mappable_object_refused);
    RUN_TEST(test_mapping_wrong_direction_refused);
    RUN_TEST(test_mapping_wrong_length_refused);
    RUN_TEST(test_mapping_entry_longer_than_64_bits_refused);
    RUN_TEST(test_sub0_over_64_bits_refused_and_pdo_keeps_old_state);
    RUN_TEST(test_sub0_above_eight_refused);
    RUN_TEST(test_sub0_over_an_empty_entry_refused);
    RUN_TEST(test_enabling_a_pdo_with_empty_mapping_refused);
    RUN_TEST(test_dummy_refused_unless_allowed);
    RUN_TEST(test_dummy_skips_bytes_of_an_rpdo_when_allowed);
    RUN_TEST(test_dummy_never_in_a_tpdo);
    RUN_TEST(test_map_while_valid_when_configured);
    RUN_TEST(test_cob_id_change_while_valid_refused);
    RUN_TEST(test_cob_id_29_bit_and_reserved_bits_refused);
    RUN_TEST(test_cob_id_reserved_can_ids_refused);
    RUN_TEST(test_rpdo_cob_id_bit_30_is_accepted);
    RUN_TEST(test_reserved_transmission_types_refused);
    RUN_TEST(test_inhibit_time_only_while_disabled);
    RUN_TEST(test_sync_start_value_only_while_disabled_and_at_most_240);
    RUN_TEST(test_event_timer_writable_while_valid);
    RUN_TEST(test_abort_codes_follow_the_configuration);
    RUN_TEST(test_ro_mapping_object_sub0_and_comm_sub0_not_writable);
    RUN_TEST(test_parameters_read_back_as_written);
    return UNITY_END();
}
