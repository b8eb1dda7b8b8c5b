/* EMCY producer on the virtual clock: frame bytes, error register 0x1001, the 0x1003 history
 * (order, depth, clearing, read-only entries), error-reset EMCY, inhibit time queueing to the
 * microsecond, NMT-state rules, COB-ID 0x1014 rules and reset communication. */
#include <string.h>

#include "canopen/emcy.h"
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

static void expect_emcy_on(uint16_t cob, uint16_t code, uint8_t reg, const uint8_t *mfr)
{
    uint8_t d[8] = {(uint8_t)code, (uint8_t)(code >> 8), reg, 0, 0, 0, 0, 0};
    if (mfr != NULL) {
        memcpy(&d[3], mfr, 5);
    }
    expect_frame(&t, cob, 8, d);
}

static void expect_emcy(uint16_t code, uint8_t reg)
{
    expect_emcy_on(0x85, code, reg, NULL);
}

static uint32_t read_u32(uint16_t index, uint8_t sub)
{
    uint32_t v = 0xDEADBEEFu;
    TEST_ASSERT_EQUAL_HEX32(0, sdo_read_u32(&t, index, sub, &v));
    return v;
}

static void nmt(uint8_t command)
{
    const uint8_t d[2] = {command, 5};
    test_rx(&t, 0, 2, d);
}

/* --- frames and 0x1001 --------------------------------------------------------------------- */

static void test_frame_has_code_register_and_manufacturer_bytes(void)
{
    const uint8_t mfr[5] = {0x11, 0x22, 0x33, 0x44, 0x55};
    TEST_ASSERT_TRUE(co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, mfr));
    const uint8_t wire[8] = {0x10, 0x23, 0x03, 0x11, 0x22, 0x33, 0x44, 0x55};
    expect_frame(&t, 0x85, 8, wire);
    expect_no_frame(&t);
}

static void test_null_manufacturer_bytes_are_zero(void)
{
    co_emcy_raise(&t.node, 0x3210, CO_ERR_REG_VOLTAGE, NULL);
    expect_emcy(0x3210, 0x05);
}

static void test_error_register_has_generic_bit_while_active(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, read_u32(0x1001, 0));
    co_emcy_raise(&t.node, 0x4210, CO_ERR_REG_TEMPERATURE, NULL);
    expect_emcy(0x4210, 0x09);
    TEST_ASSERT_EQUAL_HEX32(0x09, read_u32(0x1001, 0));
    TEST_ASSERT_EQUAL_HEX8(0x09, co_emcy_error_register(&t.node));
    co_emcy_clear(&t.node, 0x4210);
    expect_emcy(0x0000, 0x00);
    TEST_ASSERT_EQUAL_HEX32(0x00, read_u32(0x1001, 0));
}

static void test_error_register_is_or_of_active_errors(void)
{
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    co_emcy_raise(&t.node, 0x3210, CO_ERR_REG_VOLTAGE, NULL);
    TEST_ASSERT_EQUAL_HEX8(0x07, co_od_get_u8(&t.node, 0x1001, 0));
    co_emcy_clear(&t.node, 0x2310);
    TEST_ASSERT_EQUAL_HEX8(0x05, co_od_get_u8(&t.node, 0x1001, 0));
    co_emcy_raise(&t.node, 0xFF02, CO_ERR_REG_MANUFACTURER, NULL);
    TEST_ASSERT_EQUAL_HEX8(0x85, co_od_get_u8(&t.node, 0x1001, 0));
}

static void test_no_generic_option_keeps_exact_class_bit(void)
{
    t.node.options |= CO_NODE_ERR_REG_NO_GENERIC;
    co_emcy_raise(&t.node, 0x3210, CO_ERR_REG_VOLTAGE, NULL);
    expect_emcy(0x3210, 0x04);
    TEST_ASSERT_EQUAL_HEX8(0x04, co_od_get_u8(&t.node, 0x1001, 0));
}

static void test_error_reset_emcy_only_when_last_error_goes(void)
{
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    co_emcy_raise(&t.node, 0x3210, CO_ERR_REG_VOLTAGE, NULL);
    fake_bus_clear(&t.bus);
    co_emcy_clear(&t.node, 0x2310);
    expect_no_frame(&t);
    co_emcy_clear(&t.node, 0x3210);
    expect_emcy(0x0000, 0x00);
    expect_no_frame(&t);
}

static void test_reset_each_option_sends_reset_with_remaining_register(void)
{
    t.node.options |= CO_NODE_EMCY_RESET_EACH;
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    co_emcy_raise(&t.node, 0x3210, CO_ERR_REG_VOLTAGE, NULL);
    fake_bus_clear(&t.bus);
    co_emcy_clear(&t.node, 0x2310);
    expect_emcy(0x0000, 0x05);
    co_emcy_clear(&t.node, 0x3210);
    expect_emcy(0x0000, 0x00);
}

static void test_raising_an_active_code_sends_again_without_new_history(void)
{
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    TEST_ASSERT_TRUE(co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL));
    expect_emcy(0x2310, 0x03);
    expect_emcy(0x2310, 0x03);
    TEST_ASSERT_EQUAL_UINT32(1, read_u32(0x1003, 0));
    TEST_ASSERT_EQUAL_UINT8(1, t.node.emcy.active_count);
}

static void test_clearing_unknown_code_does_nothing(void)
{
    co_emcy_clear(&t.node, 0x1234);
    expect_no_frame(&t);
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    fake_bus_clear(&t.bus);
    co_emcy_clear(&t.node, 0x1234);
    expect_no_frame(&t);
    TEST_ASSERT_TRUE(co_emcy_is_active(&t.node, 0x2310));
}

static void test_clear_all_sends_one_reset(void)
{
    co_emcy_clear_all(&t.node); /* nothing active: nothing to say */
    expect_no_frame(&t);
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    co_emcy_raise(&t.node, 0x3210, CO_ERR_REG_VOLTAGE, NULL);
    co_emcy_raise(&t.node, 0x4210, CO_ERR_REG_TEMPERATURE, NULL);
    fake_bus_clear(&t.bus);
    co_emcy_clear_all(&t.node);
    expect_emcy(0x0000, 0x00);
    expect_no_frame(&t);
    TEST_ASSERT_FALSE(co_emcy_is_active(&t.node, 0x3210));
    TEST_ASSERT_EQUAL_HEX8(0, co_od_get_u8(&t.node, 0x1001, 0));
}

static void test_code_zero_is_not_an_error(void)
{
    TEST_ASSERT_FALSE(co_emcy_raise(&t.node, 0x0000, CO_ERR_REG_CURRENT, NULL));
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_HEX8(0, co_od_get_u8(&t.node, 0x1001, 0));
    TEST_ASSERT_EQUAL_UINT32(0, read_u32(0x1003, 0));
}

static void test_full_active_list_still_reports(void)
{
    for (uint16_t i = 0; i < CO_EMCY_MAX_ACTIVE; i++) {
        TEST_ASSERT_TRUE(co_emcy_raise(&t.node, (uint16_t)(0x1000 + i), 0, NULL));
    }
    fake_bus_clear(&t.bus);
    TEST_ASSERT_FALSE(co_emcy_raise(&t.node, 0x3210, CO_ERR_REG_VOLTAGE, NULL));
    expect_emcy(0x3210, 0x05);
    TEST_ASSERT_EQUAL_HEX32(0x3210, read_u32(0x1003, 1));
    co_emcy_clear_all(&t.node);
    expect_emcy(0x0000, 0x00);
}

/* --- 0x1003 -------------------------------------------------------------------------------- */

static void test_history_newest_first(void)
{
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    co_emcy_raise(&t.node, 0x3210, CO_ERR_REG_VOLTAGE, NULL);
    co_emcy_raise(&t.node, 0x4210, CO_ERR_REG_TEMPERATURE, NULL);
    fake_bus_clear(&t.bus);
    TEST_ASSERT_EQUAL_UINT32(3, read_u32(0x1003, 0));
    TEST_ASSERT_EQUAL_HEX32(0x4210, read_u32(0x1003, 1));
    TEST_ASSERT_EQUAL_HEX32(0x3210, read_u32(0x1003, 2));
    TEST_ASSERT_EQUAL_HEX32(0x2310, read_u32(0x1003, 3));
    TEST_ASSERT_EQUAL_HEX32(0, read_u32(0x1003, 4));
}

static void test_history_keeps_errors_after_they_are_cleared(void)
{
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    co_emcy_clear(&t.node, 0x2310);
    fake_bus_clear(&t.bus);
    TEST_ASSERT_EQUAL_UINT32(1, read_u32(0x1003, 0));
    TEST_ASSERT_EQUAL_HEX32(0x2310, read_u32(0x1003, 1));
}

static void test_history_depth_drops_oldest(void)
{
    for (uint16_t i = 1; i <= 11u; i++) {
        co_emcy_raise(&t.node, (uint16_t)(0x5000 + i), 0, NULL);
        co_emcy_clear(&t.node, (uint16_t)(0x5000 + i));
    }
    fake_bus_clear(&t.bus);
    TEST_ASSERT_EQUAL_UINT32(8, read_u32(0x1003, 0)); /* depth of the test dictionary */
    for (uint8_t sub = 1; sub <= 8u; sub++) {
        TEST_ASSERT_EQUAL_HEX32(0x5000u + 12u - sub, read_u32(0x1003, sub));
    }
}

static void test_history_additional_information_in_high_word(void)
{
    const uint8_t mfr[5] = {0x35, 0x00, 0, 0, 0};
    co_emcy_raise_info(&t.node, 0x8130, CO_ERR_REG_COMMUNICATION, mfr, 0x0035);
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, mfr);
    fake_bus_clear(&t.bus);
    TEST_ASSERT_EQUAL_HEX32(0x00002310, read_u32(0x1003, 1)); /* default: no information */
    TEST_ASSERT_EQUAL_HEX32(0x00358130, read_u32(0x1003, 2));
}

static void test_writing_zero_clears_history_but_not_active_errors(void)
{
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    co_emcy_raise(&t.node, 0x3210, CO_ERR_REG_VOLTAGE, NULL);
    fake_bus_clear(&t.bus);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1003, 0, 0, 1));
    TEST_ASSERT_EQUAL_UINT32(0, read_u32(0x1003, 0));
    TEST_ASSERT_EQUAL_HEX32(0, read_u32(0x1003, 1));
    TEST_ASSERT_EQUAL_HEX32(0, read_u32(0x1003, 2));
    TEST_ASSERT_EQUAL_HEX32(0x07, read_u32(0x1001, 0));
    expect_no_frame(&t);
    /* the next error starts a fresh history */
    co_emcy_raise(&t.node, 0x4210, CO_ERR_REG_TEMPERATURE, NULL);
    fake_bus_clear(&t.bus);
    TEST_ASSERT_EQUAL_UINT32(1, read_u32(0x1003, 0));
    TEST_ASSERT_EQUAL_HEX32(0x4210, read_u32(0x1003, 1));
}

static void test_writing_other_count_is_refused(void)
{
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    fake_bus_clear(&t.bus);
    for (uint32_t v = 1; v <= 255u; v += 17u) {
        TEST_ASSERT_EQUAL_HEX32(0x06090030, sdo_write(&t, 0x1003, 0, v, 1));
    }
    TEST_ASSERT_EQUAL_UINT32(1, read_u32(0x1003, 0));
    TEST_ASSERT_EQUAL_HEX32(0x2310, read_u32(0x1003, 1));
}

static void test_history_entries_are_read_only(void)
{
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    fake_bus_clear(&t.bus);
    TEST_ASSERT_EQUAL_HEX32(0x06010002, sdo_write(&t, 0x1003, 1, 0, 4));
    TEST_ASSERT_EQUAL_HEX32(0x06010002, sdo_write(&t, 0x1001, 0, 0, 1));
    TEST_ASSERT_EQUAL_HEX32(0x2310, read_u32(0x1003, 1));
    TEST_ASSERT_EQUAL_HEX32(0x03, read_u32(0x1001, 0));
}

/* A dictionary printing 0x1003 as the VF-S15 does: depth 1, sub 0 read-only with default 1. */
static const co_od_sub mini_1001[] = {{0u, 1u, 0u, 0u, CO_UNSIGNED8, CO_OD_READ}};
static const co_od_sub mini_1003[] = {{1u, 1u, 0u, 0u, CO_UNSIGNED8, CO_OD_READ},
                                      {4u, 4u, 0u, 1u, CO_UNSIGNED32, CO_OD_READ}};
static const co_od_entry mini_entries[] = {{0x1001u, CO_OBJ_VAR, 1u, 0u, mini_1001},
                                           {0x1003u, CO_OBJ_ARRAY, 2u, 0u, mini_1003}};
static const uint8_t mini_defaults[8] = {0, 1, 0, 0, 0, 0, 0, 0};
static const co_od mini_od = {"mini", mini_entries, NULL, mini_defaults, 2u, 0u, 8u, 0u, 0u, 0u, NULL, NULL};

static void test_constant_count_and_depth_one(void)
{
    static co_node n;
    static fake_bus bus;
    uint8_t values[8];
    memset(&bus, 0, sizeof bus);
    co_node_config cfg = co_node_default_config();
    cfg.od = &mini_od;
    cfg.values = values;
    cfg.node_id = 3;
    cfg.driver = fake_bus_driver(&bus);
    TEST_ASSERT_TRUE(co_node_init(&n, &cfg));
    co_node_start(&n, 0);
    fake_bus_clear(&bus);
    TEST_ASSERT_EQUAL_UINT8(1, n.emcy.history_depth);
    co_emcy_raise(&n, 0x2310, CO_ERR_REG_CURRENT, NULL);
    co_emcy_raise(&n, 0x3210, CO_ERR_REG_VOLTAGE, NULL);
    TEST_ASSERT_EQUAL_UINT8(1, co_od_get_u8(&n, 0x1003, 0)); /* always "one possible error" */
    TEST_ASSERT_EQUAL_HEX32(0x3210, co_od_get_u32(&n, 0x1003, 1));
    TEST_ASSERT_EQUAL_HEX8(0x07, co_od_get_u8(&n, 0x1001, 0));
    const co_frame *f = fake_bus_next(&bus); /* no 0x1014: 0x80 + node-ID */
    TEST_ASSERT_NOT_NULL(f);
    TEST_ASSERT_EQUAL_HEX16(0x83, f->id);
}

/* --- inhibit time -------------------------------------------------------------------------- */

static void set_inhibit_100us(uint16_t n)
{
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1015, 0, n, 2));
}

static void test_inhibit_holds_next_emcy_to_the_tick(void)
{
    set_inhibit_100us(10); /* 1 ms */
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    uint64_t sent_at = t.now;
    co_emcy_raise(&t.node, 0x3210, CO_ERR_REG_VOLTAGE, NULL);
    expect_emcy(0x2310, 0x03);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT64(sent_at + 1000u, co_node_process(&t.node, t.now));
    test_advance(&t, 999);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT64(CO_TIME_NEVER, test_advance(&t, 1));
    expect_emcy(0x3210, 0x07);
    expect_no_frame(&t);
}

static void test_inhibit_spaces_queued_frames_in_order(void)
{
    set_inhibit_100us(5); /* 500 µs */
    co_emcy_raise(&t.node, 0x1001, 0, NULL);
    co_emcy_raise(&t.node, 0x1002, 0, NULL);
    co_emcy_raise(&t.node, 0x1003, 0, NULL);
    co_emcy_clear_all(&t.node);
    expect_emcy(0x1001, 0x01);
    expect_no_frame(&t);
    for (uint32_t i = 0; i < 3u; i++) {
        test_advance(&t, 499);
        TEST_ASSERT_EQUAL_UINT32(i, fake_bus_pending(&t.bus));
        test_advance(&t, 1);
        TEST_ASSERT_EQUAL_UINT32(i + 1u, fake_bus_pending(&t.bus));
    }
    const co_frame *f;
    f = &t.bus.frames[t.bus.read];
    TEST_ASSERT_EQUAL_HEX8(0x02, f[0].data[0]);
    TEST_ASSERT_EQUAL_HEX8(0x03, f[1].data[0]);
    TEST_ASSERT_EQUAL_HEX8(0x00, f[2].data[0]);
    TEST_ASSERT_EQUAL_HEX8(0x00, f[2].data[2]);
}

static void test_emcy_after_inhibit_goes_at_once(void)
{
    set_inhibit_100us(10);
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    fake_bus_clear(&t.bus);
    test_advance(&t, 1000);
    co_emcy_clear(&t.node, 0x2310);
    expect_emcy(0x0000, 0x00);
}

static void test_inhibit_queue_overflow_is_counted(void)
{
    set_inhibit_100us(10);
    co_emcy_raise(&t.node, 0x1000, 0, NULL); /* sent */
    for (uint16_t i = 1; i <= CO_EMCY_QUEUE_LEN + 2u; i++) {
        co_emcy_raise(&t.node, (uint16_t)(0x1000 + i), 0, NULL);
    }
    TEST_ASSERT_EQUAL_UINT32(2, t.node.emcy.lost);
    fake_bus_clear(&t.bus);
    for (uint16_t i = 1; i <= CO_EMCY_QUEUE_LEN; i++) {
        test_advance(&t, 1000);
        const co_frame *f = fake_bus_next(&t.bus);
        TEST_ASSERT_NOT_NULL(f);
        TEST_ASSERT_EQUAL_HEX16(0x1000 + i, co_get_le16(f->data));
    }
    test_advance(&t, 10000);
    expect_no_frame(&t);
    /* the lost ones are still in the history */
    TEST_ASSERT_EQUAL_HEX32(0x1000u + CO_EMCY_QUEUE_LEN + 2u, read_u32(0x1003, 1));
}

static void test_inhibit_change_applies_from_last_emcy(void)
{
    set_inhibit_100us(100); /* 10 ms */
    co_emcy_raise(&t.node, 0x1001, 0, NULL);
    co_emcy_raise(&t.node, 0x1002, 0, NULL);
    fake_bus_clear(&t.bus);
    test_advance(&t, 2000);
    set_inhibit_100us(30); /* 3 ms from the first EMCY: due at 3000 */
    TEST_ASSERT_EQUAL_UINT64(3000u, co_node_process(&t.node, t.now));
    test_advance(&t, 999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    expect_emcy(0x1002, 0x01);
}

/* --- NMT states and 0x1014 ----------------------------------------------------------------- */

static void test_emcy_raised_in_stopped_is_held_until_the_node_leaves_it(void)
{
    const uint8_t mfr[5] = {0x1F, 0, 0, 0, 0x42};
    nmt(0x02);
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, mfr);
    TEST_ASSERT_EQUAL_HEX8(0x03, co_od_get_u8(&t.node, 0x1001, 0));
    TEST_ASSERT_EQUAL_HEX32(0x2310, co_od_get_u32(&t.node, 0x1003, 1));
    test_advance(&t, 10000000); /* 10 s in STOPPED: nothing */
    expect_no_frame(&t);
    nmt(0x80);
    expect_no_frame(&t); /* the next co_node_process sends it */
    test_advance(&t, 0);
    expect_emcy_on(0x85, 0x2310, 0x03, mfr);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT32(0, t.node.emcy.suppressed);
    test_advance(&t, 1000000);
    expect_no_frame(&t); /* once */
    co_emcy_clear(&t.node, 0x2310);
    expect_emcy(0x0000, 0x00);
}

static void test_emcy_held_in_stopped_goes_out_in_operational_too(void)
{
    nmt(0x02);
    co_emcy_raise(&t.node, 0x3210, CO_ERR_REG_VOLTAGE, NULL);
    nmt(0x01);
    test_advance(&t, 0);
    expect_emcy(0x3210, 0x05);
    expect_no_frame(&t);
}

static void test_error_raised_and_cleared_in_stopped_is_not_sent(void)
{
    nmt(0x02);
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    co_emcy_clear(&t.node, 0x2310);
    nmt(0x80);
    test_advance(&t, 0);
    expect_no_frame(&t); /* neither the error nor a reset the master has no use for */
    TEST_ASSERT_EQUAL_UINT32(2, t.node.emcy.suppressed);
    TEST_ASSERT_EQUAL_HEX32(0x2310, co_od_get_u32(&t.node, 0x1003, 1)); /* history kept */
}

static void test_error_cleared_in_stopped_sends_its_reset_on_leaving(void)
{
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    expect_emcy(0x2310, 0x03);
    nmt(0x02);
    co_emcy_clear(&t.node, 0x2310);
    test_advance(&t, 1000);
    expect_no_frame(&t);
    nmt(0x80);
    test_advance(&t, 0);
    expect_emcy(0x0000, 0x00); /* the master heard of the error: it hears it is gone */
    expect_no_frame(&t);
}

static void test_held_emcys_keep_order_and_inhibit_time(void)
{
    set_inhibit_100us(10); /* 1 ms */
    co_emcy_raise(&t.node, 0x1001, 0, NULL);
    expect_emcy(0x1001, 0x01); /* at 0: the inhibit time runs to 1000 */
    co_emcy_raise(&t.node, 0x1002, 0, NULL); /* held back by the inhibit time */
    nmt(0x02);
    co_emcy_raise(&t.node, 0x1003, 0, NULL);
    test_advance(&t, 5000);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT8(2, t.node.emcy.queued_count);
    nmt(0x80);
    test_advance(&t, 0);
    expect_emcy(0x1002, 0x01); /* the inhibit time is long over */
    expect_no_frame(&t);
    test_advance(&t, 999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    expect_emcy(0x1003, 0x01);
    expect_no_frame(&t);
}

static void test_emcys_held_in_stopped_are_bounded(void)
{
    nmt(0x02);
    for (uint16_t i = 0; i < CO_EMCY_QUEUE_LEN + 2u; i++) {
        co_emcy_raise(&t.node, (uint16_t)(0x1000u + i), 0, NULL);
    }
    TEST_ASSERT_EQUAL_UINT8(CO_EMCY_QUEUE_LEN, t.node.emcy.queued_count);
    TEST_ASSERT_EQUAL_UINT32(2, t.node.emcy.lost);
    nmt(0x80);
    test_advance(&t, 0);
    for (uint16_t i = 0; i < CO_EMCY_QUEUE_LEN; i++) {
        expect_emcy((uint16_t)(0x1000u + i), 0x01);
    }
    expect_no_frame(&t);
}

static void test_reset_communication_drops_held_emcys(void)
{
    nmt(0x02);
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    nmt(0x82);
    fake_bus_clear(&t.bus); /* the boot-up */
    test_advance(&t, 0);
    expect_no_frame(&t);
    TEST_ASSERT_TRUE(co_emcy_is_active(&t.node, 0x2310));
    TEST_ASSERT_EQUAL_HEX8(0x03, co_od_get_u8(&t.node, 0x1001, 0));
}

static void test_emcy_sent_in_operational(void)
{
    nmt(0x01);
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    expect_emcy(0x2310, 0x03);
}

static void test_no_emcy_before_start(void)
{
    test_node_init(&t, 5);
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    TEST_ASSERT_EQUAL_UINT32(0, t.bus.count);
    TEST_ASSERT_TRUE(co_emcy_is_active(&t.node, 0x2310));
}

static void test_invalid_cob_id_suppresses_emcy(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1014, 0, 0x80000085u, 4));
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT32(1, t.node.emcy.suppressed);
}

static void test_cob_id_changes_only_through_invalid(void)
{
    TEST_ASSERT_EQUAL_HEX32(0x06090030, sdo_write(&t, 0x1014, 0, 0x95, 4));
    TEST_ASSERT_EQUAL_HEX32(0x85, read_u32(0x1014, 0));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1014, 0, 0x85, 4)); /* same id: fine */
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1014, 0, 0x80000095u, 4));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1014, 0, 0x95, 4));
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    expect_emcy_on(0x95, 0x2310, 0x03, NULL);
}

static void test_cob_id_reserved_bits_and_ids_are_refused(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1014, 0, 0x80000085u, 4));
    TEST_ASSERT_EQUAL_HEX32(0x06090030, sdo_write(&t, 0x1014, 0, 0x20000085u, 4)); /* 29-bit */
    TEST_ASSERT_EQUAL_HEX32(0x06090030, sdo_write(&t, 0x1014, 0, 0x40000085u, 4));
    TEST_ASSERT_EQUAL_HEX32(0x06090030, sdo_write(&t, 0x1014, 0, 0x00000885u, 4));
    const uint32_t reserved[] = {0x000, 0x07F, 0x101, 0x180, 0x581, 0x5FF, 0x601, 0x67F,
                                 0x6E0, 0x6FF, 0x701, 0x77F, 0x780, 0x7FF};
    for (uint32_t i = 0; i < sizeof reserved / sizeof reserved[0]; i++) {
        TEST_ASSERT_EQUAL_HEX32(0x06090030, sdo_write(&t, 0x1014, 0, reserved[i], 4));
    }
    TEST_ASSERT_EQUAL_HEX32(0x80000085u, read_u32(0x1014, 0));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1014, 0, 0x80000701u, 4)); /* not valid: stored */
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1014, 0, 0x080, 4));
}

static void test_reset_communication_keeps_active_errors_only(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1014, 0, 0x80000085u, 4));
    co_emcy_raise(&t.node, 0x2310, CO_ERR_REG_CURRENT, NULL);
    co_emcy_raise(&t.node, 0x3210, CO_ERR_REG_VOLTAGE, NULL);
    co_emcy_clear(&t.node, 0x3210);
    nmt(0x82);
    fake_bus_clear(&t.bus);
    TEST_ASSERT_EQUAL_UINT32(0, read_u32(0x1003, 0));
    TEST_ASSERT_EQUAL_HEX32(0, read_u32(0x1003, 1));
    TEST_ASSERT_EQUAL_HEX32(0x03, read_u32(0x1001, 0));
    TEST_ASSERT_EQUAL_HEX32(0x85, read_u32(0x1014, 0)); /* default again: EMCY valid */
    co_emcy_clear(&t.node, 0x2310);
    expect_emcy(0x0000, 0x00);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_frame_has_code_register_and_manufacturer_bytes);
    RUN_TEST(test_null_manufacturer_bytes_are_zero);
    RUN_TEST(test_error_register_has_generic_bit_while_active);
    RUN_TEST(test_error_register_is_or_of_active_errors);
    RUN_TEST(test_no_generic_option_keeps_exact_class_bit);
    RUN_TEST(test_error_reset_emcy_only_when_last_error_goes);
    RUN_TEST(test_reset_each_option_sends_reset_with_remaining_register);
    RUN_TEST(test_raising_an_active_code_sends_again_without_new_history);
    RUN_TEST(test_clearing_unknown_code_does_nothing);
    RUN_TEST(test_clear_all_sends_one_reset);
    RUN_TEST(test_code_zero_is_not_an_error);
    RUN_TEST(test_full_active_list_still_reports);
    RUN_TEST(test_history_newest_first);
    RUN_TEST(test_history_keeps_errors_after_they_are_cleared);
    RUN_TEST(test_history_depth_drops_oldest);
    RUN_TEST(test_history_additional_information_in_high_word);
    RUN_TEST(test_writing_zero_clears_history_but_not_active_errors);
    RUN_TEST(test_writing_other_count_is_refused);
    RUN_TEST(test_history_entries_are_read_only);
    RUN_TEST(test_constant_count_and_depth_one);
    RUN_TEST(test_inhibit_holds_next_emcy_to_the_tick);
    RUN_TEST(test_inhibit_spaces_queued_frames_in_order);
    RUN_TEST(test_emcy_after_inhibit_goes_at_once);
    RUN_TEST(test_inhibit_queue_overflow_is_counted);
    RUN_TEST(test_inhibit_change_applies_from_last_emcy);
    RUN_TEST(test_emcy_raised_in_stopped_is_held_until_the_node_leaves_it);
    RUN_TEST(test_emcy_held_in_stopped_goes_out_in_operational_too);
    RUN_TEST(test_error_raised_and_cleared_in_stopped_is_not_sent);
    RUN_TEST(test_error_cleared_in_stopped_sends_its_reset_on_leaving);
    RUN_TEST(test_held_emcys_keep_order_and_inhibit_time);
    RUN_TEST(test_emcys_held_in_stopped_are_bounded);
    RUN_TEST(test_reset_communication_drops_held_emcys);
    RUN_TEST(test_emcy_sent_in_operational);
    RUN_TEST(test_no_emcy_before_start);
    RUN_TEST(test_invalid_cob_id_suppresses_emcy);
    RUN_TEST(test_cob_id_changes_only_through_invalid);
    RUN_TEST(test_cob_id_reserved_bits_and_ids_are_refused);
    RUN_TEST(test_reset_communication_keeps_active_errors_only);
    return UNITY_END();
}
