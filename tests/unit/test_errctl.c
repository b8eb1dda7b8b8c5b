/* Error control on the virtual clock: heartbeat consumer (first heartbeat, timeout exactly at the
 * deadline, several producers, resume, boot-up, malformed heartbeats, 0x1016 write rules), node
 * guarding (toggle sequence, heartbeat exclusion), life guarding to the microsecond, the error
 * behaviour 0x1029, and the CAN bus state reports (bus-off, error passive, overrun). */
#include <string.h>

#include "canopen/emcy.h"
#include "canopen/errctl.h"
#include "od_test.h"
#include "test_support.h"
#include "unity.h"

static test_node t;

typedef struct event_log {
    co_comm_event event[32];
    uint32_t detail[32];
    co_nmt_state state_at[32]; /* the node's NMT state when the event was reported */
    uint32_t count;
} event_log;

static event_log events;

static void on_comm(co_node *node, void *ctx, co_comm_event event, uint32_t detail)
{
    event_log *log = ctx;
    if (log->count < 32u) {
        log->event[log->count] = event;
        log->detail[log->count] = detail;
        log->state_at[log->count] = node->nmt_state;
    }
    log->count++;
}

void setUp(void)
{
    memset(&events, 0, sizeof events);
    test_node_start(&t, 5);
    t.node.events.comm = on_comm;
    t.node.events.ctx = &events;
    fake_bus_clear(&t.bus);
}

void tearDown(void) {}

static void expect_event(uint32_t i, co_comm_event event, uint32_t detail)
{
    TEST_ASSERT_TRUE_MESSAGE(i < events.count, "event missing");
    TEST_ASSERT_EQUAL_INT(event, events.event[i]);
    TEST_ASSERT_EQUAL_UINT32(detail, events.detail[i]);
}

static void expect_emcy(uint16_t code, uint8_t reg)
{
    const uint8_t d[8] = {(uint8_t)code, (uint8_t)(code >> 8), reg, 0, 0, 0, 0, 0};
    expect_frame(&t, 0x85, 8, d);
}

static void nmt(uint8_t command)
{
    const uint8_t d[2] = {command, 5};
    test_rx(&t, 0, 2, d);
}

static void heartbeat(uint8_t producer, uint8_t state)
{
    test_rx(&t, (uint16_t)(0x700u + producer), 1, &state);
}

static void guard_rtr(void)
{
    co_frame f = {0x705, 0, CO_FRAME_RTR, {0}};
    co_node_rx(&t.node, &f, t.now);
}

static void consume(uint8_t sub, uint8_t producer, uint16_t ms)
{
    uint32_t v = ((uint32_t)producer << 16) | ms;
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1016, sub, v, 4));
}

/* --- heartbeat consumer -------------------------------------------------------------------- */

static void test_producer_is_not_missed_before_its_first_heartbeat(void)
{
    consume(1, 10, 100);
    TEST_ASSERT_EQUAL_UINT64(CO_TIME_NEVER, test_advance(&t, 5000000));
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT32(0, events.count);
    TEST_ASSERT_EQUAL_INT(CO_HBC_WAITING, co_errctl_producer_state(&t.node, 10));
}

static void test_heartbeat_timeout_exactly_at_the_deadline(void)
{
    consume(1, 10, 100);
    test_advance(&t, 1234);
    heartbeat(10, 0x05);
    uint64_t due = t.now + 100000u;
    TEST_ASSERT_EQUAL_UINT64(due, co_node_process(&t.node, t.now));
    test_advance(&t, 99999);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT32(0, events.count);
    test_advance(&t, 1);
    expect_emcy(0x8130, 0x11);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT32(1, events.count);
    expect_event(0, CO_COMM_HEARTBEAT_LOST, 10);
    TEST_ASSERT_EQUAL_HEX8(0x11, co_od_get_u8(&t.node, 0x1001, 0));
    TEST_ASSERT_EQUAL_HEX32(0x8130, co_od_get_u32(&t.node, 0x1003, 1));
    TEST_ASSERT_EQUAL_INT(CO_HBC_LOST, co_errctl_producer_state(&t.node, 10));
    test_advance(&t, 1000000); /* reported once */
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT32(1, events.count);
}

static void test_heartbeats_in_time_keep_the_producer(void)
{
    consume(1, 10, 100);
    for (int i = 0; i < 50; i++) {
        heartbeat(10, 0x7F);
        test_advance(&t, 99999);
    }
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT32(0, events.count);
    TEST_ASSERT_EQUAL_INT(CO_HBC_ACTIVE, co_errctl_producer_state(&t.node, 10));
}

static void test_heartbeat_resumes_and_clears_emcy(void)
{
    consume(1, 10, 100);
    heartbeat(10, 0x05);
    test_advance(&t, 100000);
    fake_bus_clear(&t.bus);
    test_advance(&t, 5000);
    heartbeat(10, 0x05);
    expect_emcy(0x0000, 0x00);
    expect_event(1, CO_COMM_HEARTBEAT_RESUMED, 10);
    TEST_ASSERT_EQUAL_HEX8(0, co_od_get_u8(&t.node, 0x1001, 0));
    /* and it is monitored again */
    test_advance(&t, 100000);
    expect_emcy(0x8130, 0x11);
    expect_event(2, CO_COMM_HEARTBEAT_LOST, 10);
}

static void test_several_producers_share_one_emcy(void)
{
    consume(1, 10, 100);
    consume(2, 11, 50);
    heartbeat(10, 0x05);
    heartbeat(11, 0x05);
    test_advance(&t, 50000);
    expect_emcy(0x8130, 0x11);
    expect_event(0, CO_COMM_HEARTBEAT_LOST, 11);
    test_advance(&t, 50000);
    expect_no_frame(&t); /* the error is already active */
    expect_event(1, CO_COMM_HEARTBEAT_LOST, 10);
    heartbeat(11, 0x05);
    expect_no_frame(&t); /* producer 10 still lost */
    expect_event(2, CO_COMM_HEARTBEAT_RESUMED, 11);
    TEST_ASSERT_TRUE(co_emcy_is_active(&t.node, 0x8130));
    heartbeat(10, 0x05);
    expect_emcy(0x0000, 0x00);
    expect_event(3, CO_COMM_HEARTBEAT_RESUMED, 10);
    TEST_ASSERT_EQUAL_UINT32(4, events.count);
}

static void test_process_returns_earliest_producer_deadline(void)
{
    consume(1, 10, 100);
    consume(2, 11, 30);
    heartbeat(10, 0x05);
    test_advance(&t, 10000);
    heartbeat(11, 0x05);
    TEST_ASSERT_EQUAL_UINT64(40000u, co_node_process(&t.node, t.now));
    test_advance(&t, 30000);
    fake_bus_clear(&t.bus);
    TEST_ASSERT_EQUAL_UINT64(100000u, co_node_process(&t.node, t.now));
}

static void test_bootup_of_monitored_producer_counts_as_loss(void)
{
    consume(1, 10, 100);
    heartbeat(10, 0x05);
    test_advance(&t, 10000);
    heartbeat(10, 0x00);
    expect_emcy(0x8130, 0x11);
    expect_event(0, CO_COMM_HEARTBEAT_LOST, 10);
    test_advance(&t, 500000); /* not reported again while it boots */
    expect_no_frame(&t);
    heartbeat(10, 0x7F);
    expect_emcy(0x0000, 0x00);
    expect_event(1, CO_COMM_HEARTBEAT_RESUMED, 10);
}

static void test_bootup_before_first_heartbeat_changes_nothing(void)
{
    consume(1, 10, 100);
    heartbeat(10, 0x00);
    test_advance(&t, 1000000);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT32(0, events.count);
}

static void test_malformed_heartbeats_are_counted_and_do_not_refresh(void)
{
    consume(1, 10, 100);
    heartbeat(10, 0x05);
    test_advance(&t, 50000);
    const uint8_t two[2] = {0x05, 0x00};
    test_rx(&t, 0x70A, 2, two);
    test_rx(&t, 0x70A, 0, NULL);
    heartbeat(10, 0x85);
    heartbeat(10, 0x12);
    TEST_ASSERT_EQUAL_UINT32(4, t.node.stats.rx_malformed);
    test_advance(&t, 50000);
    expect_emcy(0x8130, 0x11);
}

static void test_unmonitored_heartbeats_and_foreign_guarding_are_ignored(void)
{
    consume(1, 10, 100);
    uint32_t ignored = t.node.stats.rx_ignored;
    heartbeat(12, 0x05);
    co_frame rtr = {0x70A, 1, CO_FRAME_RTR, {0}};
    co_node_rx(&t.node, &rtr, t.now);
    TEST_ASSERT_EQUAL_UINT32(ignored + 2u, t.node.stats.rx_ignored);
    TEST_ASSERT_EQUAL_INT(CO_HBC_WAITING, co_errctl_producer_state(&t.node, 10));
    expect_no_frame(&t);
}

static void test_duplicate_producer_is_refused(void)
{
    consume(1, 10, 100);
    TEST_ASSERT_EQUAL_HEX32(0x06040043, sdo_write(&t, 0x1016, 2, 0x000A00C8u, 4));
    uint32_t v = 1;
    TEST_ASSERT_EQUAL_HEX32(0, sdo_read_u32(&t, 0x1016, 2, &v));
    TEST_ASSERT_EQUAL_HEX32(0, v);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1016, 2, 0x000A0000u, 4)); /* time 0: unused */
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1016, 1, 0x000A00C8u, 4)); /* same sub: fine */
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1016, 3, 0x000B00C8u, 4));
}

static void test_consumer_reserved_bits_and_node_ids_are_refused(void)
{
    TEST_ASSERT_EQUAL_HEX32(0x06090030, sdo_write(&t, 0x1016, 1, 0x010A0064u, 4));
    TEST_ASSERT_EQUAL_HEX32(0x06090030, sdo_write(&t, 0x1016, 1, 0x00800064u, 4));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1016, 1, 0x00800000u, 4));
    uint32_t v = 0;
    TEST_ASSERT_EQUAL_HEX32(0, sdo_read_u32(&t, 0x1016, 1, &v));
    TEST_ASSERT_EQUAL_HEX32(0x00800000u, v);
}

static void test_disabling_a_lost_producer_withdraws_the_emcy(void)
{
    consume(1, 10, 100);
    heartbeat(10, 0x05);
    test_advance(&t, 100000);
    expect_emcy(0x8130, 0x11);
    test_rx8(&t, 0x605, 0x23, 0x16, 0x10, 0x01, 0x00, 0x00, 0x0A, 0x00); /* 0x1016:1 = 0x000A0000 */
    expect_emcy(0x0000, 0x00);
    const uint8_t done[8] = {0x60, 0x16, 0x10, 0x01, 0, 0, 0, 0};
    expect_frame(&t, 0x585, 8, done);
    TEST_ASSERT_EQUAL_UINT32(1, events.count);
    TEST_ASSERT_EQUAL_INT(CO_HBC_OFF, co_errctl_producer_state(&t.node, 10));
}

static void test_rewriting_an_entry_waits_for_a_new_first_heartbeat(void)
{
    consume(1, 10, 100);
    heartbeat(10, 0x05);
    test_advance(&t, 50000);
    consume(1, 10, 200);
    test_advance(&t, 1000000);
    expect_no_frame(&t);
    heartbeat(10, 0x05);
    test_advance(&t, 199999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    expect_emcy(0x8130, 0x11);
}

static void test_heartbeat_consumed_in_stopped(void)
{
    consume(1, 10, 100);
    nmt(0x02);
    heartbeat(10, 0x05);
    test_advance(&t, 100000);
    expect_no_frame(&t); /* no EMCY in STOPPED */
    expect_event(0, CO_COMM_HEARTBEAT_LOST, 10);
    TEST_ASSERT_EQUAL_HEX8(0x11, co_od_get_u8(&t.node, 0x1001, 0));
    TEST_ASSERT_EQUAL(CO_NMT_STOPPED, t.node.nmt_state);
}

static void test_reset_communication_restarts_monitoring(void)
{
    consume(1, 10, 100);
    heartbeat(10, 0x05);
    test_advance(&t, 100000);
    TEST_ASSERT_TRUE(co_emcy_is_active(&t.node, 0x8130));
    nmt(0x82);
    TEST_ASSERT_FALSE(co_emcy_is_active(&t.node, 0x8130));
    TEST_ASSERT_EQUAL_HEX8(0, co_od_get_u8(&t.node, 0x1001, 0));
    /* 0x1016 is back to its default (0): nothing monitored */
    TEST_ASSERT_EQUAL_INT(CO_HBC_OFF, co_errctl_producer_state(&t.node, 10));
}

/* --- 0x1029 -------------------------------------------------------------------------------- */

static void lose_producer_in(uint8_t nmt_command)
{
    consume(1, 10, 100);
    nmt(nmt_command);
    heartbeat(10, 0x05);
    test_advance(&t, 100000);
}

static void test_behaviour_0_goes_pre_operational(void)
{
    lose_producer_in(0x01);
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, t.node.nmt_state);
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, events.state_at[0]); /* reported after the change */
}

static void test_behaviour_0_leaves_stopped_alone(void)
{
    lose_producer_in(0x02);
    TEST_ASSERT_EQUAL(CO_NMT_STOPPED, t.node.nmt_state);
}

static void test_behaviour_1_changes_nothing(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1029, 1, 1, 1));
    lose_producer_in(0x01);
    TEST_ASSERT_EQUAL(CO_NMT_OPERATIONAL, t.node.nmt_state);
}

static void test_behaviour_2_stops(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1029, 1, 2, 1));
    lose_producer_in(0x01);
    TEST_ASSERT_EQUAL(CO_NMT_STOPPED, t.node.nmt_state);
    expect_emcy(0x8130, 0x11); /* sent before the node stopped */
}

static void test_behaviour_reserved_values_refused(void)
{
    for (uint32_t v = 3; v <= 0x7Fu; v++) {
        TEST_ASSERT_EQUAL_HEX32(0x06090030, sdo_write(&t, 0x1029, 1, v, 1));
    }
    TEST_ASSERT_EQUAL_UINT8(0, co_od_get_u8(&t.node, 0x1029, 1));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1029, 1, 0x80, 1)); /* manufacturer: no change */
    lose_producer_in(0x01);
    TEST_ASSERT_EQUAL(CO_NMT_OPERATIONAL, t.node.nmt_state);
}

/* --- node guarding and life guarding -------------------------------------------------------- */

static void set_guarding(uint16_t guard_ms, uint8_t factor)
{
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x100C, 0, guard_ms, 2));
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x100D, 0, factor, 1));
}

static void test_guarding_toggle_sequence(void)
{
    const uint8_t expected[] = {0x7F, 0xFF, 0x7F, 0xFF};
    for (uint32_t i = 0; i < 4u; i++) {
        guard_rtr();
        expect_frame(&t, 0x705, 1, &expected[i]);
    }
    nmt(0x01);
    guard_rtr();
    const uint8_t op = 0x05;
    expect_frame(&t, 0x705, 1, &op);
    guard_rtr();
    const uint8_t op_t = 0x85;
    expect_frame(&t, 0x705, 1, &op_t);
    nmt(0x02);
    guard_rtr();
    const uint8_t stopped = 0x04; /* guarding is answered in STOPPED */
    expect_frame(&t, 0x705, 1, &stopped);
    nmt(0x82); /* reset communication: the toggle starts again at 0 */
    fake_bus_clear(&t.bus);
    guard_rtr();
    expect_frame(&t, 0x705, 1, &expected[0]);
}

static void test_first_toggle_set_option(void)
{
    test_node_init(&t, 5);
    t.node.options |= CO_NODE_GUARD_TOGGLE_FIRST_SET;
    co_node_start(&t.node, t.now);
    fake_bus_clear(&t.bus);
    nmt(0x01);
    const uint8_t seq[] = {0x85, 0x05, 0x85};
    for (uint32_t i = 0; i < 3u; i++) {
        guard_rtr();
        expect_frame(&t, 0x705, 1, &seq[i]);
    }
}

static void test_guarding_not_answered_while_heartbeat_produced(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1017, 0, 1000, 2));
    uint32_t ignored = t.node.stats.rx_ignored;
    guard_rtr();
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT32(ignored + 1u, t.node.stats.rx_ignored);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1017, 0, 0, 2));
    guard_rtr();
    const uint8_t first = 0x7F;
    expect_frame(&t, 0x705, 1, &first);
}

static void test_guarding_ignored_before_start(void)
{
    test_node_init(&t, 5);
    guard_rtr();
    TEST_ASSERT_EQUAL_UINT32(0, t.bus.count);
}

static void test_life_guarding_expires_to_the_tick(void)
{
    set_guarding(100, 3);
    test_advance(&t, 777);
    guard_rtr();
    fake_bus_clear(&t.bus);
    TEST_ASSERT_EQUAL_UINT64(t.now + 300000u, co_node_process(&t.node, t.now));
    test_advance(&t, 299999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    expect_emcy(0x8130, 0x11);
    expect_event(0, CO_COMM_LIFE_GUARD_LOST, 0);
    test_advance(&t, 10000000); /* disarmed: once */
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT32(1, events.count);
    guard_rtr();
    const uint8_t answer = 0xFF;
    expect_frame(&t, 0x705, 1, &answer);
    expect_emcy(0x0000, 0x00);
    expect_event(1, CO_COMM_LIFE_GUARD_RESUMED, 0);
}

static void test_each_request_restarts_the_life_time(void)
{
    set_guarding(100, 2);
    for (int i = 0; i < 20; i++) {
        guard_rtr();
        test_advance(&t, 199999);
    }
    TEST_ASSERT_EQUAL_UINT32(0, events.count);
    TEST_ASSERT_FALSE(co_emcy_is_active(&t.node, 0x8130));
}

static void test_life_guarding_waits_for_first_request(void)
{
    set_guarding(100, 2);
    TEST_ASSERT_EQUAL_UINT64(CO_TIME_NEVER, test_advance(&t, 10000000));
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT32(0, events.count);
}

static void test_life_guarding_off_with_factor_zero(void)
{
    set_guarding(100, 0);
    guard_rtr();
    fake_bus_clear(&t.bus);
    test_advance(&t, 10000000);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT32(0, events.count);
}

static void test_guard_time_write_restarts_running_timer(void)
{
    set_guarding(100, 2);
    guard_rtr();
    fake_bus_clear(&t.bus);
    test_advance(&t, 150000);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x100C, 0, 50, 2)); /* 100 ms from now */
    test_advance(&t, 99999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    expect_emcy(0x8130, 0x11);
    TEST_ASSERT_EQUAL_UINT64(250000u, t.now);
}

/* The application's writes skip the handler (CO_ORIGIN_APP): the life time loaded last stays in
 * effect, whatever the build optimises for, until co_errctl_configure loads the objects again. */
static void test_app_guard_time_write_waits_for_configure(void)
{
    set_guarding(100, 2);
    TEST_ASSERT_EQUAL_HEX32(0, co_od_set_u16(&t.node, 0x100C, 0, 50));
    guard_rtr();
    fake_bus_clear(&t.bus);
    test_advance(&t, 199999); /* still 100 ms x 2, not 50 ms x 2 */
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT32(0, events.count);
    test_advance(&t, 1);
    expect_emcy(0x8130, 0x11);
    expect_event(0, CO_COMM_LIFE_GUARD_LOST, 0);
    co_errctl_configure(&t.node); /* the application makes its write take effect */
    fake_bus_clear(&t.bus);
    guard_rtr();
    fake_bus_clear(&t.bus);
    uint64_t armed = t.now;
    test_advance(&t, 99999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    expect_emcy(0x8130, 0x11);
    TEST_ASSERT_EQUAL_UINT64(armed + 100000u, t.now);
}

static void test_life_guarding_loss_applies_behaviour(void)
{
    set_guarding(10, 1);
    nmt(0x01);
    guard_rtr();
    test_advance(&t, 10000);
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, t.node.nmt_state);
    expect_event(0, CO_COMM_LIFE_GUARD_LOST, 0);
}

static void test_heartbeat_and_life_guarding_losses_share_the_emcy(void)
{
    consume(1, 10, 100);
    set_guarding(50, 1);
    heartbeat(10, 0x05);
    guard_rtr();
    fake_bus_clear(&t.bus);
    test_advance(&t, 50000);
    expect_emcy(0x8130, 0x11);
    test_advance(&t, 50000);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT32(2, events.count);
    heartbeat(10, 0x05);
    expect_no_frame(&t); /* life guarding still lost */
    guard_rtr();
    const uint8_t answer = 0xFF;
    expect_frame(&t, 0x705, 1, &answer);
    expect_emcy(0x0000, 0x00);
}

static void test_emcy_by_app_option_reports_events_only(void)
{
    t.node.options |= CO_NODE_COMM_EMCY_BY_APP;
    consume(1, 10, 100);
    heartbeat(10, 0x05);
    test_advance(&t, 100000);
    expect_no_frame(&t);
    expect_event(0, CO_COMM_HEARTBEAT_LOST, 10);
    TEST_ASSERT_EQUAL_HEX8(0, co_od_get_u8(&t.node, 0x1001, 0));
    co_node_bus_state(&t.node, CO_BUS_ERROR_PASSIVE, t.now);
    expect_no_frame(&t);
    expect_event(1, CO_COMM_ERROR_PASSIVE, 0);
}

/* --- CAN bus state ------------------------------------------------------------------------- */

static void test_bus_off_and_recovery(void)
{
    nmt(0x01);
    co_node_bus_state(&t.node, CO_BUS_OFF, t.now);
    expect_no_frame(&t);
    expect_event(0, CO_COMM_BUS_OFF, 0);
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, t.node.nmt_state); /* 0x1029 = 0 */
    co_node_bus_state(&t.node, CO_BUS_OFF, t.now); /* repeated: nothing */
    TEST_ASSERT_EQUAL_UINT32(1, events.count);
    test_advance(&t, 1000);
    co_node_bus_state(&t.node, CO_BUS_ERROR_ACTIVE, t.now);
    expect_emcy(0x8140, 0x11);
    expect_emcy(0x0000, 0x00);
    expect_no_frame(&t);
    expect_event(1, CO_COMM_BUS_RECOVERED, 0);
    TEST_ASSERT_EQUAL_HEX32(0x8140, co_od_get_u32(&t.node, 0x1003, 1));
    TEST_ASSERT_EQUAL_HEX8(0, co_od_get_u8(&t.node, 0x1001, 0));
}

static void test_bus_off_with_behaviour_stop(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1029, 1, 2, 1));
    co_node_bus_state(&t.node, CO_BUS_OFF, t.now);
    TEST_ASSERT_EQUAL(CO_NMT_STOPPED, t.node.nmt_state);
}

static void test_error_passive_and_back(void)
{
    co_node_bus_state(&t.node, CO_BUS_ERROR_PASSIVE, t.now);
    expect_emcy(0x8120, 0x11);
    expect_event(0, CO_COMM_ERROR_PASSIVE, 0);
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, t.node.nmt_state);
    co_node_bus_state(&t.node, CO_BUS_ERROR_ACTIVE, t.now);
    expect_emcy(0x0000, 0x00);
    expect_event(1, CO_COMM_BUS_RECOVERED, 0);
    co_node_bus_state(&t.node, (co_bus_state)7, t.now); /* not a state: ignored */
    TEST_ASSERT_EQUAL_UINT32(2, events.count);
    expect_no_frame(&t);
}

static void test_bus_off_recovering_to_passive(void)
{
    co_node_bus_state(&t.node, CO_BUS_OFF, t.now);
    co_node_bus_state(&t.node, CO_BUS_ERROR_PASSIVE, t.now);
    expect_emcy(0x8140, 0x11);
    expect_emcy(0x8120, 0x11);
    expect_no_frame(&t); /* still passive: no reset */
    TEST_ASSERT_FALSE(co_emcy_is_active(&t.node, 0x8140));
    co_node_bus_state(&t.node, CO_BUS_ERROR_ACTIVE, t.now);
    expect_emcy(0x0000, 0x00);
}

static void test_rx_overrun(void)
{
    co_node_rx_overrun(&t.node, 3, t.now);
    expect_emcy(0x8110, 0x11);
    expect_emcy(0x0000, 0x00);
    expect_event(0, CO_COMM_RX_OVERRUN, 3);
    co_node_rx_overrun(&t.node, 2, t.now);
    TEST_ASSERT_EQUAL_UINT32(5, t.node.errctl.rx_lost);
    TEST_ASSERT_EQUAL_HEX32(0x8110, co_od_get_u32(&t.node, 0x1003, 1));
    TEST_ASSERT_EQUAL_HEX32(0x8110, co_od_get_u32(&t.node, 0x1003, 2));
}

static void test_overrun_with_inhibit_time(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1015, 0, 100, 2)); /* 10 ms */
    co_node_rx_overrun(&t.node, 1, t.now);
    expect_emcy(0x8110, 0x11);
    expect_no_frame(&t);
    test_advance(&t, 10000);
    expect_emcy(0x0000, 0x00);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_producer_is_not_missed_before_its_first_heartbeat);
    RUN_TEST(test_heartbeat_timeout_exactly_at_the_deadline);
    RUN_TEST(test_heartbeats_in_time_keep_the_producer);
    RUN_TEST(test_heartbeat_resumes_and_clears_emcy);
    RUN_TEST(test_several_producers_share_one_emcy);
    RUN_TEST(test_process_returns_earliest_producer_deadline);
    RUN_TEST(test_bootup_of_monitored_producer_counts_as_loss);
    RUN_TEST(test_bootup_before_first_heartbeat_changes_nothing);
    RUN_TEST(test_malformed_heartbeats_are_counted_and_do_not_refresh);
    RUN_TEST(test_unmonitored_heartbeats_and_foreign_guarding_are_ignored);
    RUN_TEST(test_duplicate_producer_is_refused);
    RUN_TEST(test_consumer_reserved_bits_and_node_ids_are_refused);
    RUN_TEST(test_disabling_a_lost_producer_withdraws_the_emcy);
    RUN_TEST(test_rewriting_an_entry_waits_for_a_new_first_heartbeat);
    RUN_TEST(test_heartbeat_consumed_in_stopped);
    RUN_TEST(test_reset_communication_restarts_monitoring);
    RUN_TEST(test_behaviour_0_goes_pre_operational);
    RUN_TEST(test_behaviour_0_leaves_stopped_alone);
    RUN_TEST(test_behaviour_1_changes_nothing);
    RUN_TEST(test_behaviour_2_stops);
    RUN_TEST(test_behaviour_reserved_values_refused);
    RUN_TEST(test_guarding_toggle_sequence);
    RUN_TEST(test_first_toggle_set_option);
    RUN_TEST(test_guarding_not_answered_while_heartbeat_produced);
    RUN_TEST(test_guarding_ignored_before_start);
    RUN_TEST(test_life_guarding_expires_to_the_tick);
    RUN_TEST(test_each_request_restarts_the_life_time);
    RUN_TEST(test_life_guarding_waits_for_first_request);
    RUN_TEST(test_life_guarding_off_with_factor_zero);
    RUN_TEST(test_guard_time_write_restarts_running_timer);
    RUN_TEST(test_app_guard_time_write_waits_for_configure);
    RUN_TEST(test_life_guarding_loss_applies_behaviour);
    RUN_TEST(test_heartbeat_and_life_guarding_losses_share_the_emcy);
    RUN_TEST(test_emcy_by_app_option_reports_events_only);
    RUN_TEST(test_bus_off_and_recovery);
    RUN_TEST(test_bus_off_with_behaviour_stop);
    RUN_TEST(test_error_passive_and_back);
    RUN_TEST(test_bus_off_recovering_to_passive);
    RUN_TEST(test_rx_overrun);
    RUN_TEST(test_overrun_with_inhibit_time);
    return UNITY_END();
}
