/* NMT slave: boot-up, every command and transition, broadcast, other nodes' commands, malformed
 * frames, the restores each reset performs, and what each state lets through. */
#include <string.h>

#include "test_support.h"
#include "unity.h"

static test_node t;
static co_nmt_state seen_from, seen_to;
static int nmt_events, resets_node, resets_comm;

static void on_nmt(co_node *node, void *ctx, co_nmt_state from, co_nmt_state to)
{
    (void)node;
    (void)ctx;
    seen_from = from;
    seen_to = to;
    nmt_events++;
}

static void on_reset(co_node *node, void *ctx, bool whole)
{
    (void)node;
    (void)ctx;
    if (whole) {
        resets_node++;
    } else {
        resets_comm++;
    }
}

void setUp(void)
{
    nmt_events = resets_node = resets_comm = 0;
    test_node_init(&t, 5);
    t.node.events.nmt_changed = on_nmt;
    t.node.events.reset = on_reset;
    co_node_start(&t.node, 0);
}

void tearDown(void) {}

static void nmt(uint8_t cmd, uint8_t target)
{
    const uint8_t d[2] = {cmd, target};
    test_rx(&t, 0, 2, d);
}

static void test_boot_up_message_then_pre_operational(void)
{
    const uint8_t zero = 0;
    expect_frame(&t, 0x705, 1, &zero);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, t.node.nmt_state);
    TEST_ASSERT_EQUAL(CO_NMT_INITIALISING, seen_from);
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, seen_to);
    TEST_ASSERT_EQUAL(1, resets_node);
}

static void test_node_stays_initialising_until_started(void)
{
    test_node_init(&t, 9);
    TEST_ASSERT_EQUAL(CO_NMT_INITIALISING, t.node.nmt_state);
    nmt(0x01, 9);
    TEST_ASSERT_EQUAL(CO_NMT_INITIALISING, t.node.nmt_state);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL(CO_TIME_NEVER, co_node_process(&t.node, 1000));
}

static void test_start_enters_operational(void)
{
    nmt(0x01, 5);
    TEST_ASSERT_EQUAL(CO_NMT_OPERATIONAL, t.node.nmt_state);
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, seen_from);
}

static void test_stop_enters_stopped_from_pre_operational(void)
{
    nmt(0x02, 5);
    TEST_ASSERT_EQUAL(CO_NMT_STOPPED, t.node.nmt_state);
}

static void test_stop_enters_stopped_from_operational(void)
{
    nmt(0x01, 5);
    nmt(0x02, 5);
    TEST_ASSERT_EQUAL(CO_NMT_STOPPED, t.node.nmt_state);
    TEST_ASSERT_EQUAL(CO_NMT_OPERATIONAL, seen_from);
}

static void test_start_from_stopped(void)
{
    nmt(0x02, 5);
    nmt(0x01, 5);
    TEST_ASSERT_EQUAL(CO_NMT_OPERATIONAL, t.node.nmt_state);
}

static void test_enter_pre_operational_from_operational(void)
{
    nmt(0x01, 5);
    nmt(0x80, 5);
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, t.node.nmt_state);
}

static void test_enter_pre_operational_from_stopped(void)
{
    nmt(0x02, 5);
    nmt(0x80, 5);
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, t.node.nmt_state);
}

static void test_same_state_command_raises_no_event(void)
{
    int before = nmt_events;
    nmt(0x80, 5);
    TEST_ASSERT_EQUAL(before, nmt_events);
}

static void test_broadcast_reaches_every_node(void)
{
    nmt(0x01, 0);
    TEST_ASSERT_EQUAL(CO_NMT_OPERATIONAL, t.node.nmt_state);
}

static void test_command_for_other_node_is_ignored(void)
{
    uint32_t ignored = t.node.stats.rx_ignored;
    nmt(0x01, 6);
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, t.node.nmt_state);
    TEST_ASSERT_EQUAL_UINT32(ignored + 1u, t.node.stats.rx_ignored);
}

static void test_unknown_command_is_dropped_and_counted(void)
{
    uint32_t bad = t.node.stats.rx_malformed;
    nmt(0x03, 5);
    nmt(0x83, 0);
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, t.node.nmt_state);
    TEST_ASSERT_EQUAL_UINT32(bad + 2u, t.node.stats.rx_malformed);
}

static void test_wrong_length_nmt_frames_are_dropped(void)
{
    const uint8_t d[8] = {0x01, 5, 0, 0, 0, 0, 0, 0};
    uint32_t bad = t.node.stats.rx_malformed;
    for (uint8_t dlc = 0; dlc <= 8u; dlc++) {
        if (dlc == 2u) {
            continue;
        }
        test_rx(&t, 0, dlc, d);
    }
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, t.node.nmt_state);
    TEST_ASSERT_EQUAL_UINT32(bad + 8u, t.node.stats.rx_malformed);
}

static void test_rtr_on_nmt_is_dropped(void)
{
    co_frame f = {0, 2, CO_FRAME_RTR, {0x01, 5}};
    co_node_rx(&t.node, &f, 0);
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, t.node.nmt_state);
}

static void test_reset_communication_sends_boot_up_and_restores_comm_values(void)
{
    fake_bus_clear(&t.bus);
    TEST_ASSERT_EQUAL_UINT32(0, sdo_write(&t, 0x1017, 0, 250, 2));
    nmt(0x01, 5);
    nmt(0x82, 5);
    const uint8_t zero = 0;
    expect_frame(&t, 0x705, 1, &zero);
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, t.node.nmt_state);
    TEST_ASSERT_EQUAL_UINT16(0, co_od_get_u16(&t.node, 0x1017, 0));
    TEST_ASSERT_EQUAL(1, resets_comm);
    TEST_ASSERT_EQUAL(1, resets_node);
}

static void test_reset_node_restores_application_values(void)
{
    uint16_t before = co_od_get_u16(&t.node, 0x6040, 0);
    TEST_ASSERT_EQUAL(CO_ABORT_NONE, co_od_set_u16(&t.node, 0x6040, 0, (uint16_t)(before + 7u)));
    nmt(0x82, 5); /* communication reset keeps application values */
    TEST_ASSERT_EQUAL_UINT16(before + 7u, co_od_get_u16(&t.node, 0x6040, 0));
    nmt(0x81, 5);
    TEST_ASSERT_EQUAL_UINT16(before, co_od_get_u16(&t.node, 0x6040, 0));
    TEST_ASSERT_EQUAL(2, resets_node);
}

static void test_reset_node_from_stopped_boots_again(void)
{
    nmt(0x02, 5);
    fake_bus_clear(&t.bus);
    nmt(0x81, 0);
    const uint8_t zero = 0;
    expect_frame(&t, 0x705, 1, &zero);
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, t.node.nmt_state);
}

static void test_sdo_refused_in_stopped(void)
{
    nmt(0x02, 5);
    fake_bus_clear(&t.bus);
    test_rx8(&t, 0x605, 0x40, 0x00, 0x10, 0, 0, 0, 0, 0);
    expect_no_frame(&t);
}

static void test_sdo_answered_in_pre_operational_and_operational(void)
{
    uint32_t v = 0;
    fake_bus_clear(&t.bus);
    TEST_ASSERT_EQUAL_UINT32(0, sdo_read_u32(&t, 0x1000, 0, &v));
    nmt(0x01, 5);
    TEST_ASSERT_EQUAL_UINT32(0, sdo_read_u32(&t, 0x1000, 0, &v));
}

static void test_comm_objects_read_only_in_operational_when_drive_says_so(void)
{
    t.node.options |= CO_NODE_COMM_READ_ONLY_IN_OPERATIONAL;
    fake_bus_clear(&t.bus);
    nmt(0x01, 5);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_DEVICE_STATE, sdo_write(&t, 0x1017, 0, 100, 2));
    TEST_ASSERT_EQUAL_UINT16(0, co_od_get_u16(&t.node, 0x1017, 0));
    nmt(0x80, 5);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1017, 0, 100, 2));
    TEST_ASSERT_EQUAL_UINT16(100, co_od_get_u16(&t.node, 0x1017, 0));
}

static void test_comm_objects_writable_in_operational_by_default(void)
{
    fake_bus_clear(&t.bus);
    nmt(0x01, 5);
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, 0x1017, 0, 100, 2));
}

static void test_node_id_relative_defaults_follow_the_node_id(void)
{
    TEST_ASSERT_EQUAL_HEX32(0x85, co_od_get_u32(&t.node, 0x1014, 0));
    TEST_ASSERT_EQUAL_HEX32(0x605, co_od_get_u32(&t.node, 0x1200, 1));
    TEST_ASSERT_EQUAL_HEX32(0x585, co_od_get_u32(&t.node, 0x1200, 2));
    test_node_start(&t, 127);
    TEST_ASSERT_EQUAL_HEX32(0xFF, co_od_get_u32(&t.node, 0x1014, 0));
    TEST_ASSERT_EQUAL_HEX32(0x67F, co_od_get_u32(&t.node, 0x1200, 1));
}

static void test_state_names(void)
{
    TEST_ASSERT_EQUAL_STRING("OPERATIONAL", co_nmt_state_name(CO_NMT_OPERATIONAL));
    TEST_ASSERT_EQUAL_STRING("PRE-OPERATIONAL", co_nmt_state_name(CO_NMT_PRE_OPERATIONAL));
    TEST_ASSERT_EQUAL_STRING("STOPPED", co_nmt_state_name(CO_NMT_STOPPED));
    TEST_ASSERT_EQUAL_STRING("INITIALISING", co_nmt_state_name(CO_NMT_INITIALISING));
}

static void test_local_command_matches_remote(void)
{
    co_nmt_command_local(&t.node, CO_NMT_CMD_START, 0);
    TEST_ASSERT_EQUAL(CO_NMT_OPERATIONAL, t.node.nmt_state);
    co_nmt_command_local(&t.node, CO_NMT_CMD_STOP, 0);
    TEST_ASSERT_EQUAL(CO_NMT_STOPPED, t.node.nmt_state);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_boot_up_message_then_pre_operational);
    RUN_TEST(test_node_stays_initialising_until_started);
    RUN_TEST(test_start_enters_operational);
    RUN_TEST(test_stop_enters_stopped_from_pre_operational);
    RUN_TEST(test_stop_enters_stopped_from_operational);
    RUN_TEST(test_start_from_stopped);
    RUN_TEST(test_enter_pre_operational_from_operational);
    RUN_TEST(test_enter_pre_operational_from_stopped);
    RUN_TEST(test_same_state_command_raises_no_event);
    RUN_TEST(test_broadcast_reaches_every_node);
    RUN_TEST(test_command_for_other_node_is_ignored);
    RUN_TEST(test_unknown_command_is_dropped_and_counted);
    RUN_TEST(test_wrong_length_nmt_frames_are_dropped);
    RUN_TEST(test_rtr_on_nmt_is_dropped);
    RUN_TEST(test_reset_communication_sends_boot_up_and_restores_comm_values);
    RUN_TEST(test_reset_node_restores_application_values);
    RUN_TEST(test_reset_node_from_stopped_boots_again);
    RUN_TEST(test_sdo_refused_in_stopped);
    RUN_TEST(test_sdo_answered_in_pre_operational_and_operational);
    RUN_TEST(test_comm_objects_read_only_in_operational_when_drive_says_so);
    RUN_TEST(test_comm_objects_writable_in_operational_by_default);
    RUN_TEST(test_node_id_relative_defaults_follow_the_node_id);
    RUN_TEST(test_state_names);
    RUN_TEST(test_local_command_matches_remote);
    return UNITY_END();
}
