/* Reproducers of what the fuzzers (tests/fuzz, docs/robustness.md) found, smallest first: each
 * test names the target and the invariant that caught it. A test here fails until its bug is
 * fixed; the harness tolerates a known bug only while its FZ_TOLERATE_* switch in
 * tests/fuzz/fuzz_harness.c is set. */
#include <string.h>

#include "od_test_sparse.h"
#include "test_support.h"
#include "unity.h"

static test_node t;

/* A node on od/test/test_sparse.eds (it has 0x1006: it can produce SYNC). */
static void start_sparse(uint8_t node_id)
{
    memset(&t, 0, sizeof t);
    t.storage = fake_store_storage(&t.store);
    co_node_config cfg = co_node_default_config();
    cfg.od = &co_od_test_sparse;
    cfg.values = t.values;
    cfg.node_id = node_id;
    cfg.driver = fake_bus_driver(&t.bus);
    cfg.storage = &t.storage;
    TEST_ASSERT_TRUE(co_node_init(&t.node, &cfg));
    co_node_start(&t.node, t.now);
    fake_bus_clear(&t.bus);
}

void setUp(void)
{
    TEST_ASSERT_TRUE(co_od_test_sparse.value_size <= sizeof t.values);
    start_sparse(5);
}

void tearDown(void) {}

static uint32_t read_u32(uint16_t index, uint8_t sub)
{
    uint32_t v = 0;
    TEST_ASSERT_EQUAL_HEX32(0, sdo_read_u32(&t, index, sub, &v));
    return v;
}

/* fuzz_pdo_sync, invariant "no frame on a restricted CAN-ID": 0x1005 = 0x4000001B was taken and
 * the node produced SYNC on CAN-ID 0x01B, which CiA 301 §7.3.5 reserves (0x001-0x07F are NMT
 * error control / LSS territory; 0x701-0x77F are other nodes' heartbeats). Restricted CAN-IDs
 * "shall not be used for any configurable communication object", SYNC included; the PDO and EMCY
 * COB-ID writes already refuse them. The write must be refused and nothing sent there.
 * Fixed in src/sync.c (co_sync_param_written refuses them with value_abort); the fuzz input is
 * tests/fuzz/regressions/fuzz_pdo_sync/sync_cob_id_restricted_0x01B. */
static void test_sync_cob_id_refuses_restricted_can_ids(void)
{
    static const uint32_t restricted[] = {0x4000001Bu, 0x40000000u, 0x40000705u, 0x40000585u,
                                          0x40000601u, 0x400006E0u, 0x40000780u, 0x0000001Bu};
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1006, 0, 10000, 4)); /* 10 ms cycle */
    for (size_t i = 0; i < sizeof restricted / sizeof restricted[0]; i++) {
        uint32_t before = read_u32(0x1005, 0);
        uint32_t rc = sdo_write(&t, 0x1005, 0, restricted[i], 4);
        TEST_ASSERT_EQUAL_HEX32_MESSAGE(0x06040043u, rc, "0x1005 and a restricted CAN-ID: not "
                                                         "the default value abort");
        TEST_ASSERT_EQUAL_HEX32(before, read_u32(0x1005, 0));
        fake_bus_clear(&t.bus);
        (void)test_advance(&t, 20000);
        for (const co_frame *f = fake_bus_next(&t.bus); f != NULL; f = fake_bus_next(&t.bus)) {
            TEST_ASSERT_NOT_EQUAL_MESSAGE(restricted[i] & 0x7FFu, f->id,
                                          "SYNC sent on a restricted CAN-ID");
        }
    }
}

/* fuzz_drive_sourcetronic_st600, invariant "rx counters": with two TPDOs on one CAN-ID (0x38B),
 * each remote request on it was counted twice in stats.rx_malformed, once per TPDO that does not
 * answer RTRs, so the node counted more malformed frames than it had received. Two RPDOs on one
 * CAN-ID did the same with a short frame. A frame counts once, and is malformed only if none of
 * the PDOs on its CAN-ID took it. Fixed in src/pdo.c (co_pdo_rx); the fuzz input is
 * tests/fuzz/regressions/fuzz_drive_sourcetronic_st600/rtr_on_two_tpdos_counted_twice. */
static void test_a_frame_for_two_pdos_is_counted_once(void)
{
    const uint8_t start[2] = {0x01, 0};
    /* TPDO3 (type 2: answers no RTR) moved onto TPDO1's CAN-ID 0x185 */
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1802, 1, 0x80000185u, 4));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1802, 1, 0x00000185u, 4));
    test_rx(&t, 0x000, 2, start);
    TEST_ASSERT_EQUAL(CO_NMT_OPERATIONAL, t.node.nmt_state);
    fake_bus_clear(&t.bus);

    /* TPDO1 (type 0xFF) answers: the frame was taken, not malformed */
    uint32_t malformed = t.node.stats.rx_malformed;
    co_frame rtr = {0};
    rtr.id = 0x185;
    rtr.flags = CO_FRAME_RTR;
    co_node_rx(&t.node, &rtr, t.now);
    TEST_ASSERT_EQUAL_UINT32(malformed, t.node.stats.rx_malformed);
    const co_frame *f = fake_bus_next(&t.bus);
    TEST_ASSERT_NOT_NULL(f);
    TEST_ASSERT_EQUAL_HEX16(0x185, f->id);

    /* TPDO1 without RTR (bit 30) too: neither answers, the frame is malformed once */
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1800, 1, 0xC0000185u, 4));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1800, 1, 0x40000185u, 4));
    fake_bus_clear(&t.bus);
    uint32_t frames = t.node.stats.rx_frames;
    co_node_rx(&t.node, &rtr, t.now);
    TEST_ASSERT_EQUAL_UINT32(frames + 1u, t.node.stats.rx_frames);
    TEST_ASSERT_EQUAL_UINT32(malformed + 1u, t.node.stats.rx_malformed);
    TEST_ASSERT_NULL(fake_bus_next(&t.bus));

    /* RPDO2 mapping 0x2000 (2 bytes), moved onto RPDO1's CAN-ID 0x205 (4 bytes): a 1-byte frame
     * is short for both, one malformed frame, two short RPDOs */
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1601, 0, 0, 1));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1601, 1, 0x20000010u, 4));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1601, 0, 1, 1));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1401, 1, 0x00000205u, 4));
    uint32_t shorts = t.node.pdo.stats.rpdo_short;
    const uint8_t one[1] = {0x11};
    test_rx(&t, 0x205, 1, one);
    TEST_ASSERT_EQUAL_UINT32(malformed + 2u, t.node.stats.rx_malformed);
    TEST_ASSERT_EQUAL_UINT32(shorts + 2u, t.node.pdo.stats.rpdo_short);
    TEST_ASSERT_TRUE(t.node.stats.rx_malformed + t.node.stats.rx_ignored <=
                     t.node.stats.rx_frames);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_sync_cob_id_refuses_restricted_can_ids);
    RUN_TEST(test_a_frame_for_two_pdos_is_counted_once);
    return UNITY_END();
}
