/* Heartbeat producer on the virtual clock: period to the microsecond, state byte, restart on
 * write, off at 0, the deadline returned by process, and no heartbeat together with boot-up. */
#include <string.h>

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

static void set_period_ms(uint16_t ms)
{
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1017, 0, ms, 2));
}

static void test_off_by_default_sends_nothing(void)
{
    TEST_ASSERT_EQUAL_UINT64(CO_TIME_NEVER, test_advance(&t, 10000000));
    expect_no_frame(&t);
}

static void test_first_heartbeat_one_period_after_write(void)
{
    set_period_ms(100);
    TEST_ASSERT_EQUAL_UINT64(t.now + 100000u, co_node_process(&t.node, t.now));
    test_advance(&t, 99999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    const uint8_t pre_op = 0x7F;
    expect_frame(&t, 0x705, 1, &pre_op);
    expect_no_frame(&t);
}

static void test_period_is_kept_to_the_microsecond(void)
{
    set_period_ms(10);
    for (int i = 1; i <= 50; i++) {
        uint64_t next = test_advance(&t, 10000);
        TEST_ASSERT_EQUAL_UINT32(1, fake_bus_pending(&t.bus));
        fake_bus_clear(&t.bus);
        TEST_ASSERT_EQUAL_UINT64(t.now + 10000u, next);
    }
}

static void test_state_byte_follows_nmt_state(void)
{
    set_period_ms(1);
    const uint8_t start[2] = {0x01, 5};
    test_rx(&t, 0, 2, start);
    test_advance(&t, 1000);
    const uint8_t op = 0x05;
    expect_frame(&t, 0x705, 1, &op);
    const uint8_t stop[2] = {0x02, 5};
    test_rx(&t, 0, 2, stop);
    test_advance(&t, 1000);
    const uint8_t stopped = 0x04;
    expect_frame(&t, 0x705, 1, &stopped);
}

static void test_heartbeat_continues_in_stopped(void)
{
    set_period_ms(5);
    const uint8_t stop[2] = {0x02, 5};
    test_rx(&t, 0, 2, stop);
    test_advance(&t, 5000);
    TEST_ASSERT_EQUAL_UINT32(1, fake_bus_pending(&t.bus));
}

static void test_writing_zero_stops_heartbeat(void)
{
    set_period_ms(10);
    test_advance(&t, 10000);
    fake_bus_clear(&t.bus);
    set_period_ms(0);
    TEST_ASSERT_EQUAL_UINT64(CO_TIME_NEVER, test_advance(&t, 100000));
    expect_no_frame(&t);
}

static void test_new_period_restarts_from_the_write(void)
{
    set_period_ms(100);
    test_advance(&t, 60000);
    set_period_ms(50);
    test_advance(&t, 49999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    TEST_ASSERT_EQUAL_UINT32(1, fake_bus_pending(&t.bus));
}

static void test_late_process_sends_one_heartbeat_not_a_burst(void)
{
    set_period_ms(10);
    uint64_t next = test_advance(&t, 1000000);
    TEST_ASSERT_EQUAL_UINT32(1, fake_bus_pending(&t.bus));
    TEST_ASSERT_EQUAL_UINT64(t.now + 10000u, next);
}

/* As if 0x1010 had saved the current values: the stored image is the value block's prefix. */
static void store_current_values(void)
{
    memcpy(t.store.image, t.values, co_od_test.persist_size);
    t.store.len = co_od_test.persist_size;
    t.store.layout_hash = co_od_test.layout_hash;
    t.store.valid = true;
}

static void test_no_heartbeat_at_boot_up_instant(void)
{
    /* A stored 0x1017 is applied at reset: boot-up first, heartbeat one period later. */
    set_period_ms(20);
    store_current_values();
    const uint8_t reset_comm[2] = {0x82, 5};
    test_rx(&t, 0, 2, reset_comm);
    TEST_ASSERT_EQUAL_UINT16(20, co_od_get_u16(&t.node, 0x1017, 0));
    const uint8_t zero = 0;
    expect_frame(&t, 0x705, 1, &zero);
    test_advance(&t, 0);
    expect_no_frame(&t);
    test_advance(&t, 19999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    const uint8_t pre_op = 0x7F;
    expect_frame(&t, 0x705, 1, &pre_op);
}

static void test_reset_without_stored_value_turns_heartbeat_off(void)
{
    set_period_ms(20);
    const uint8_t reset_comm[2] = {0x82, 5};
    test_rx(&t, 0, 2, reset_comm);
    fake_bus_clear(&t.bus);
    TEST_ASSERT_EQUAL_UINT64(CO_TIME_NEVER, test_advance(&t, 1000000));
    expect_no_frame(&t);
}

static void test_process_before_deadline_returns_same_deadline(void)
{
    set_period_ms(100);
    uint64_t due = t.now + 100000u;
    TEST_ASSERT_EQUAL_UINT64(due, test_advance(&t, 1));
    TEST_ASSERT_EQUAL_UINT64(due, test_advance(&t, 50000));
    expect_no_frame(&t);
}

static void test_maximum_period(void)
{
    set_period_ms(65535);
    test_advance(&t, 65534999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    TEST_ASSERT_EQUAL_UINT32(1, fake_bus_pending(&t.bus));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_off_by_default_sends_nothing);
    RUN_TEST(test_first_heartbeat_one_period_after_write);
    RUN_TEST(test_period_is_kept_to_the_microsecond);
    RUN_TEST(test_state_byte_follows_nmt_state);
    RUN_TEST(test_heartbeat_continues_in_stopped);
    RUN_TEST(test_writing_zero_stops_heartbeat);
    RUN_TEST(test_new_period_restarts_from_the_write);
    RUN_TEST(test_late_process_sends_one_heartbeat_not_a_burst);
    RUN_TEST(test_no_heartbeat_at_boot_up_instant);
    RUN_TEST(test_reset_without_stored_value_turns_heartbeat_off);
    RUN_TEST(test_process_before_deadline_returns_same_deadline);
    RUN_TEST(test_maximum_period);
    return UNITY_END();
}
