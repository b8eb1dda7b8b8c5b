/* SYNC and sparse PDO numbers (second test dictionary od/test/test_sparse.eds, node 7: RPDO 1,
 * 2, 21 and TPDO 1, 3, 21; 0x1006/0x1007 present): consumer in PRE-OPERATIONAL and OPERATIONAL,
 * frame length with and without the counter, the window for synchronous RPDOs, the producer with
 * its period and counter, the 0x1005/0x1019 write checks, and the PDOs numbered 21. */
#include <string.h>

#include "od_test.h"
#include "od_test_sparse.h"
#include "test_support.h"
#include "unity.h"

#define ABORT_INCOMPATIBLE 0x06040043u

static test_node t;

static void start_on(const co_od *od, uint8_t node_id, const co_pdo_config *pc)
{
    memset(&t, 0, sizeof t);
    t.storage = fake_store_storage(&t.store);
    co_node_config cfg = co_node_default_config();
    cfg.od = od;
    cfg.values = t.values;
    cfg.node_id = node_id;
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
    TEST_ASSERT_TRUE(co_od_test_sparse.value_size <= sizeof t.values);
    start_on(&co_od_test_sparse, 7, NULL);
}

void tearDown(void) {}

static void nmt(uint8_t command)
{
    const uint8_t d[2] = {command, t.node.node_id};
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

static void refused(uint16_t index, uint8_t sub, uint32_t value, uint8_t size, uint32_t code)
{
    uint32_t before = read_u32(index, sub);
    TEST_ASSERT_EQUAL_HEX32(code, sdo_write(&t, index, sub, value, size));
    TEST_ASSERT_EQUAL_HEX32(before, read_u32(index, sub));
}

static void sync_frame(void)
{
    test_rx(&t, 0x80, 0, NULL);
}

/* RPDO21 on 0x507 (type 1) maps 0x2002 u32. */
static void rpdo21(uint32_t v)
{
    uint8_t d[4];
    co_put_le32(d, v);
    test_rx(&t, 0x507, 4, d);
}

/* --- sparse PDO numbers ------------------------------------------------------------------- */

static void test_sparse_pdo_numbers_found(void)
{
    TEST_ASSERT_EQUAL_UINT8(3, t.node.pdo.rpdo_count);
    TEST_ASSERT_EQUAL_UINT16(1, t.node.pdo.rpdo[0].head.number);
    TEST_ASSERT_EQUAL_UINT16(2, t.node.pdo.rpdo[1].head.number);
    TEST_ASSERT_EQUAL_UINT16(21, t.node.pdo.rpdo[2].head.number);
    TEST_ASSERT_EQUAL_UINT8(3, t.node.pdo.tpdo_count);
    TEST_ASSERT_EQUAL_UINT16(1, t.node.pdo.tpdo[0].head.number);
    TEST_ASSERT_EQUAL_UINT16(3, t.node.pdo.tpdo[1].head.number);
    TEST_ASSERT_EQUAL_UINT16(21, t.node.pdo.tpdo[2].head.number);
    TEST_ASSERT_TRUE(t.node.pdo.rpdo[2].head.active);
    TEST_ASSERT_FALSE(t.node.pdo.rpdo[1].head.active); /* RPDO2: bit 31, and a dummy not allowed */
}

static void test_sparse_rpdo21_synchronous_and_tpdos_3_and_21(void)
{
    nmt(0x01);
    rpdo21(0xCAFEF00Du);
    TEST_ASSERT_EQUAL_HEX32(0, co_od_get_u32(&t.node, 0x2002, 0));
    TEST_ASSERT_EQUAL_HEX32(0, co_od_set_u16(&t.node, 0x2100, 0, 0xABCD));
    test_advance(&t, 0);
    const uint8_t t1[4] = {0xCD, 0xAB, 0x22, 0x22};
    expect_frame(&t, 0x187, 4, t1); /* TPDO1, type 255 */
    const uint8_t t21[2] = {0xCD, 0xAB};
    expect_frame(&t, 0x487, 2, t21); /* TPDO21, type 254, maps 2100 too */
    sync_frame();
    TEST_ASSERT_EQUAL_HEX32(0xCAFEF00Du, co_od_get_u32(&t.node, 0x2002, 0));
    expect_no_frame(&t);
    sync_frame(); /* TPDO3: every 2nd SYNC */
    const uint8_t t3[4] = {0x33, 0x33, 0x33, 0x33};
    expect_frame(&t, 0x387, 4, t3);
    expect_no_frame(&t);
}

static void test_sparse_remap_of_pdo_21_through_sdo(void)
{
    ok(0x1814, 1, 0x80000487u, 4);
    ok(0x1A14, 0, 0, 1);
    ok(0x1A14, 1, 0x21020020u, 4);
    ok(0x1A14, 2, 0x21010010u, 4);
    ok(0x1A14, 0, 2, 1);
    ok(0x1814, 1, 0x488u, 4);
    refused(0x1A14, 0, 0, 1, ABORT_INCOMPATIBLE); /* valid again: mapping closed */
    nmt(0x01);
    TEST_ASSERT_TRUE(co_pdo_tpdo_request(&t.node, 21));
    test_advance(&t, 0);
    const uint8_t d[6] = {0x33, 0x33, 0x33, 0x33, 0x22, 0x22};
    expect_frame(&t, 0x488, 6, d);
}

static void test_dummy_in_stored_mapping_used_when_allowed(void)
{
    co_pdo_config pc;
    memset(&pc, 0, sizeof pc);
    pc.rpdo_dummy_mask = 1u << 5;
    start_on(&co_od_test_sparse, 7, &pc);
    ok(0x1401, 1, 0x307u, 4); /* RPDO2: 2000 u16, dummy u8, 2001 i16 */
    nmt(0x01);
    const uint8_t d[5] = {0x11, 0x22, 0xFF, 0x2C, 0x01};
    test_rx(&t, 0x307, 5, d);
    TEST_ASSERT_EQUAL_HEX16(0x2211, co_od_get_u16(&t.node, 0x2000, 0));
    TEST_ASSERT_EQUAL_INT16(300, co_od_get_i16(&t.node, 0x2001, 0));
}

/* --- consumer ----------------------------------------------------------------------------- */

static void test_sync_consumed_in_pre_operational_without_pdos(void)
{
    rpdo21(1);
    sync_frame();
    TEST_ASSERT_TRUE(t.node.sync.seen);
    TEST_ASSERT_EQUAL_HEX32(0, co_od_get_u32(&t.node, 0x2002, 0));
    expect_no_frame(&t);
}

static void test_sync_ignored_in_stopped(void)
{
    nmt(0x02);
    uint32_t ignored = t.node.stats.rx_ignored;
    sync_frame();
    TEST_ASSERT_FALSE(t.node.sync.seen);
    TEST_ASSERT_EQUAL_UINT32(ignored + 1u, t.node.stats.rx_ignored);
}

static void test_sync_length_without_counter(void)
{
    nmt(0x01);
    uint32_t malformed = t.node.stats.rx_malformed;
    const uint8_t d[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    test_rx(&t, 0x80, 2, d);
    test_rx(&t, 0x80, 8, d);
    TEST_ASSERT_EQUAL_UINT32(2, t.node.sync.bad_length);
    TEST_ASSERT_EQUAL_UINT32(malformed + 2u, t.node.stats.rx_malformed);
    TEST_ASSERT_FALSE(t.node.sync.seen);
    test_rx(&t, 0x80, 1, d); /* a counter byte is tolerated */
    TEST_ASSERT_TRUE(t.node.sync.seen);
    co_frame f = {0x80, 0, CO_FRAME_RTR, {0}};
    co_node_rx(&t.node, &f, t.now);
    TEST_ASSERT_EQUAL_UINT32(3, t.node.sync.bad_length);
}

static void test_sync_length_with_counter(void)
{
    ok(0x1019, 0, 10, 1);
    nmt(0x01);
    sync_frame(); /* no counter byte: dropped */
    TEST_ASSERT_EQUAL_UINT32(1, t.node.sync.bad_length);
    TEST_ASSERT_FALSE(t.node.sync.seen);
    const uint8_t d[2] = {4, 0};
    test_rx(&t, 0x80, 2, d);
    TEST_ASSERT_EQUAL_UINT32(2, t.node.sync.bad_length);
    test_rx(&t, 0x80, 1, d);
    TEST_ASSERT_TRUE(t.node.sync.seen);
    TEST_ASSERT_EQUAL_UINT8(4, t.node.sync.counter);
}

static void test_sync_cob_id_can_move(void)
{
    ok(0x1005, 0, 0x81, 4);
    nmt(0x01);
    rpdo21(5);
    sync_frame(); /* the old CAN-ID: nothing */
    TEST_ASSERT_EQUAL_HEX32(0, co_od_get_u32(&t.node, 0x2002, 0));
    test_rx(&t, 0x81, 0, NULL);
    TEST_ASSERT_EQUAL_HEX32(5, co_od_get_u32(&t.node, 0x2002, 0));
}

/* --- window --------------------------------------------------------------------------------- */

static void test_window_discards_late_synchronous_rpdo(void)
{
    ok(0x1007, 0, 1000, 4);
    nmt(0x01);
    sync_frame();
    test_advance(&t, 999);
    rpdo21(0x11);
    sync_frame();
    TEST_ASSERT_EQUAL_HEX32(0x11, co_od_get_u32(&t.node, 0x2002, 0));
    test_advance(&t, 1000);
    rpdo21(0x22); /* 1000 us after the SYNC: outside */
    TEST_ASSERT_EQUAL_UINT32(1, t.node.pdo.stats.rpdo_late);
    sync_frame();
    TEST_ASSERT_EQUAL_HEX32(0x11, co_od_get_u32(&t.node, 0x2002, 0));
}

static void test_window_does_not_apply_before_the_first_sync_nor_to_async_rpdos(void)
{
    ok(0x1007, 0, 10, 4);
    nmt(0x01);
    rpdo21(0x33);
    sync_frame();
    TEST_ASSERT_EQUAL_HEX32(0x33, co_od_get_u32(&t.node, 0x2002, 0));
    test_advance(&t, 5000);
    const uint8_t d[4] = {0x01, 0x00, 0x02, 0x00};
    test_rx(&t, 0x207, 4, d); /* RPDO1 is type 255 */
    TEST_ASSERT_EQUAL_HEX16(1, co_od_get_u16(&t.node, 0x2000, 0));
}

/* --- producer ---------------------------------------------------------------------------- */

static void test_producer_sends_every_period(void)
{
    ok(0x1006, 0, 10000, 4);
    ok(0x1005, 0, 0x40000080u, 4);
    uint64_t start = t.now;
    TEST_ASSERT_EQUAL_UINT64(start + 10000u, test_advance(&t, 0));
    test_advance(&t, 9999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    expect_frame(&t, 0x80, 0, NULL); /* PRE-OPERATIONAL produces too */
    test_advance(&t, 10000);
    expect_frame(&t, 0x80, 0, NULL);
    expect_no_frame(&t);
}

static void test_producer_with_counter_wraps(void)
{
    ok(0x1019, 0, 3, 1); /* only while 0x1006 is 0 */
    ok(0x1006, 0, 1000, 4);
    ok(0x1005, 0, 0x40000080u, 4);
    const uint8_t c1 = 1, c2 = 2, c3 = 3;
    test_advance(&t, 1000);
    expect_frame(&t, 0x80, 1, &c1);
    test_advance(&t, 1000);
    expect_frame(&t, 0x80, 1, &c2);
    test_advance(&t, 1000);
    expect_frame(&t, 0x80, 1, &c3);
    test_advance(&t, 1000);
    expect_frame(&t, 0x80, 1, &c1);
}

static void test_producer_drives_its_own_synchronous_pdos(void)
{
    ok(0x1006, 0, 1000, 4);
    ok(0x1005, 0, 0x40000080u, 4);
    nmt(0x01);
    rpdo21(0x44);
    test_advance(&t, 1000);
    expect_frame(&t, 0x80, 0, NULL);
    TEST_ASSERT_EQUAL_HEX32(0x44, co_od_get_u32(&t.node, 0x2002, 0));
    test_advance(&t, 1000);
    expect_frame(&t, 0x80, 0, NULL);
    const uint8_t t3[4] = {0x33, 0x33, 0x33, 0x33};
    expect_frame(&t, 0x387, 4, t3);
    uint32_t ignored = t.node.stats.rx_ignored;
    sync_frame(); /* another producer's SYNC: ignored */
    TEST_ASSERT_EQUAL_UINT32(ignored + 1u, t.node.stats.rx_ignored);
}

static void test_producer_silent_in_stopped_and_restarts_after(void)
{
    ok(0x1006, 0, 1000, 4);
    ok(0x1005, 0, 0x40000080u, 4);
    nmt(0x02);
    test_advance(&t, 5000);
    expect_no_frame(&t);
    nmt(0x80);
    test_advance(&t, 999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    expect_frame(&t, 0x80, 0, NULL);
}

/* The application re-reading the parameters (co_sync_configure) in STOPPED does not start the
 * producer there: it starts on leaving STOPPED. */
static void test_producer_configured_in_stopped_stays_silent(void)
{
    ok(0x1006, 0, 1000, 4);
    ok(0x1005, 0, 0x40000080u, 4);
    nmt(0x02);
    co_sync_configure(&t.node, t.node.now);
    test_advance(&t, 5000);
    expect_no_frame(&t);
    nmt(0x80);
    test_advance(&t, 1000);
    expect_frame(&t, 0x80, 0, NULL);
}

static void test_producer_stops_when_bit_30_cleared_or_period_zero(void)
{
    ok(0x1006, 0, 1000, 4);
    ok(0x1005, 0, 0x40000080u, 4);
    ok(0x1006, 0, 0, 4);
    TEST_ASSERT_EQUAL_UINT64(CO_TIME_NEVER, test_advance(&t, 5000));
    expect_no_frame(&t);
    ok(0x1006, 0, 1000, 4);
    ok(0x1005, 0, 0x80u, 4);
    test_advance(&t, 5000);
    expect_no_frame(&t);
}

/* --- writes --------------------------------------------------------------------------------- */

static void test_sync_cob_id_checks(void)
{
    refused(0x1005, 0, 0x20000080u, 4, ABORT_INCOMPATIBLE); /* 29-bit */
    refused(0x1005, 0, 0x00000880u, 4, ABORT_INCOMPATIBLE); /* bit 11 */
    ok(0x1006, 0, 1000, 4);
    ok(0x1005, 0, 0x40000080u, 4);
    refused(0x1005, 0, 0x40000081u, 4, ABORT_INCOMPATIBLE); /* CAN-ID while producing */
    ok(0x1005, 0, 0x81u, 4);                                /* stop producing and move */
}

static void test_sync_producer_refused_without_0x1006(void)
{
    start_on(&co_od_test, 5, NULL);
    refused(0x1005, 0, 0x40000080u, 4, ABORT_INCOMPATIBLE);
    co_pdo_config pc;
    memset(&pc, 0, sizeof pc);
    pc.value_abort = 0x06090030u;
    start_on(&co_od_test, 5, &pc);
    refused(0x1005, 0, 0x40000080u, 4, 0x06090030u);
}

static void test_sync_producer_refused_for_a_consumer_only_device(void)
{
    co_pdo_config pc;
    memset(&pc, 0, sizeof pc);
    pc.flags = CO_PDO_SYNC_CONSUMER_ONLY;
    start_on(&co_od_test_sparse, 7, &pc);
    ok(0x1006, 0, 1000, 4); /* stored, no effect */
    refused(0x1005, 0, 0x40000080u, 4, ABORT_INCOMPATIBLE);
    TEST_ASSERT_EQUAL_UINT64(CO_TIME_NEVER, test_advance(&t, 5000));
    expect_no_frame(&t);
}

static void test_counter_overflow_checks(void)
{
    refused(0x1019, 0, 1, 1, ABORT_INCOMPATIBLE);
    refused(0x1019, 0, 241, 1, ABORT_INCOMPATIBLE);
    ok(0x1019, 0, 240, 1);
    ok(0x1019, 0, 0, 1);
    ok(0x1006, 0, 1000, 4);
    refused(0x1019, 0, 5, 1, 0x08000022u); /* not while a cycle period is set */
    ok(0x1019, 0, 0, 1);                   /* the same value is fine */
}

static void test_configure_rereads_after_application_writes(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, co_od_set_u32(&t.node, 0x1005, 0, 0x82u));
    TEST_ASSERT_EQUAL_UINT16(0x80, t.node.sync.cob_id); /* application writes skip the hook */
    co_sync_configure(&t.node, t.now);
    TEST_ASSERT_EQUAL_UINT16(0x82, t.node.sync.cob_id);
    TEST_ASSERT_EQUAL_HEX32(0, co_od_set_u32(&t.node, 0x1814, 1, 0x80000487u));
    co_pdo_configure(&t.node, t.now);
    TEST_ASSERT_FALSE(t.node.pdo.tpdo[2].head.active);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_sparse_pdo_numbers_found);
    RUN_TEST(test_sparse_rpdo21_synchronous_and_tpdos_3_and_21);
    RUN_TEST(test_sparse_remap_of_pdo_21_through_sdo);
    RUN_TEST(test_dummy_in_stored_mapping_used_when_allowed);
    RUN_TEST(test_sync_consumed_in_pre_operational_without_pdos);
    RUN_TEST(test_sync_ignored_in_stopped);
    RUN_TEST(test_sync_length_without_counter);
    RUN_TEST(test_sync_length_with_counter);
    RUN_TEST(test_sync_cob_id_can_move);
    RUN_TEST(test_window_discards_late_synchronous_rpdo);
    RUN_TEST(test_window_does_not_apply_before_the_first_sync_nor_to_async_rpdos);
    RUN_TEST(test_producer_sends_every_period);
    RUN_TEST(test_producer_with_counter_wraps);
    RUN_TEST(test_producer_drives_its_own_synchronous_pdos);
    RUN_TEST(test_producer_silent_in_stopped_and_restarts_after);
    RUN_TEST(test_producer_configured_in_stopped_stays_silent);
    RUN_TEST(test_producer_stops_when_bit_30_cleared_or_period_zero);
    RUN_TEST(test_sync_cob_id_checks);
    RUN_TEST(test_sync_producer_refused_without_0x1006);
    RUN_TEST(test_sync_producer_refused_for_a_consumer_only_device);
    RUN_TEST(test_counter_overflow_checks);
    RUN_TEST(test_configure_rereads_after_application_writes);
    return UNITY_END();
}
