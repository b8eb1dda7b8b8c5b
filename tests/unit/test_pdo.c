/* PDO reception and transmission on the virtual clock (test dictionary, node 5): RPDOs only in
 * OPERATIONAL, synchronous RPDOs applied at the SYNC, short / long / out-of-range frames, hooks,
 * RPDO timeout; TPDOs on change (application and SDO), inhibit time and event timer to the tick,
 * the drive-style inhibit unit and floor, SYNC types 0 and 1-240 with the start value, RTR types,
 * and nothing outside OPERATIONAL. */
#include <string.h>

#include "od_test.h"
#include "od_test_sparse.h"
#include "test_support.h"
#include "unity.h"

static test_node t;
static uint32_t comm_events;
static co_comm_event last_event;
static uint32_t last_detail;

static void on_comm(co_node *node, void *ctx, co_comm_event event, uint32_t detail)
{
    (void)node;
    (void)ctx;
    comm_events++;
    last_event = event;
    last_detail = detail;
}

/* Starts node 5 on the test dictionary with these PDO options. */
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
    cfg.events.comm = on_comm;
    if (pc != NULL) {
        cfg.pdo = *pc;
    }
    TEST_ASSERT_TRUE(co_node_init(&t.node, &cfg));
    co_node_start(&t.node, t.now);
    fake_bus_clear(&t.bus);
}

void setUp(void)
{
    comm_events = 0;
    start_with(NULL);
}

void tearDown(void) {}

static void nmt(uint8_t command)
{
    const uint8_t d[2] = {command, 5};
    test_rx(&t, 0, 2, d);
    (void)test_advance(&t, 0);
}

static void go_operational(void)
{
    nmt(0x01);
    TEST_ASSERT_EQUAL(CO_NMT_OPERATIONAL, t.node.nmt_state);
}

static void sync_frame(void)
{
    test_rx(&t, 0x80, 0, NULL);
}

static void sync_counter(uint8_t counter)
{
    test_rx(&t, 0x80, 1, &counter);
}

static void rtr(uint16_t id)
{
    co_frame f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.flags = CO_FRAME_RTR;
    co_node_rx(&t.node, &f, t.now);
}

static void sdo_ok(uint16_t index, uint8_t sub, uint32_t value, uint8_t size)
{
    TEST_ASSERT_EQUAL_HEX32(0, sdo_write(&t, index, sub, value, size));
}

/* TPDO1 parameters can change only while it is disabled (sub 3, sub 6). */
static void tpdo1_param(uint8_t sub, uint32_t value, uint8_t size)
{
    sdo_ok(0x1800, 1, 0x80000185u, 4);
    sdo_ok(0x1800, sub, value, size);
    sdo_ok(0x1800, 1, 0x185u, 4);
}

static void statusword(uint16_t v)
{
    TEST_ASSERT_EQUAL_HEX32(0, co_od_set_u16(&t.node, 0x6041, 0, v));
}

/* TPDO1 = 6041 (statusword) + 6044 (velocity actual, 0). */
static void expect_tpdo1(uint16_t sw)
{
    const uint8_t d[4] = {(uint8_t)sw, (uint8_t)(sw >> 8), 0, 0};
    expect_frame(&t, 0x185, 4, d);
}

/* --- RPDO --------------------------------------------------------------------------------- */

static void test_rpdo_writes_mapped_objects_in_operational(void)
{
    go_operational();
    const uint8_t d[4] = {0x0F, 0x00, 0xE8, 0x03};
    test_rx(&t, 0x205, 4, d);
    TEST_ASSERT_EQUAL_HEX16(0x000F, co_od_get_u16(&t.node, 0x6040, 0));
    TEST_ASSERT_EQUAL_INT16(1000, co_od_get_i16(&t.node, 0x6042, 0));
    TEST_ASSERT_EQUAL_UINT32(1, t.node.pdo.stats.rpdo_received);
    expect_no_frame(&t);
}

static void test_rpdo_ignored_in_pre_operational_and_stopped(void)
{
    const uint8_t d[4] = {0x0F, 0x00, 0xE8, 0x03};
    uint32_t ignored = t.node.stats.rx_ignored;
    test_rx(&t, 0x205, 4, d);
    nmt(0x02);
    test_rx(&t, 0x205, 4, d);
    TEST_ASSERT_EQUAL_HEX16(0, co_od_get_u16(&t.node, 0x6040, 0));
    TEST_ASSERT_EQUAL_INT16(0, co_od_get_i16(&t.node, 0x6042, 0));
    TEST_ASSERT_EQUAL_UINT32(ignored + 2u, t.node.stats.rx_ignored);
    TEST_ASSERT_EQUAL_UINT32(0, t.node.pdo.stats.rpdo_received);
}

static void test_rpdo_longer_frame_uses_mapped_bytes(void)
{
    go_operational();
    test_rx8(&t, 0x205, 0x06, 0x00, 0x10, 0x00, 0xAA, 0xBB, 0xCC, 0xDD);
    TEST_ASSERT_EQUAL_HEX16(0x0006, co_od_get_u16(&t.node, 0x6040, 0));
    TEST_ASSERT_EQUAL_INT16(16, co_od_get_i16(&t.node, 0x6042, 0));
    expect_no_frame(&t);
}

static void test_rpdo_short_frame_dropped_counted_with_emcy_until_right_length(void)
{
    go_operational();
    const uint8_t d[4] = {0x0F, 0x00, 0xE8, 0x03};
    uint32_t malformed = t.node.stats.rx_malformed;
    test_rx(&t, 0x205, 3, d);
    TEST_ASSERT_EQUAL_HEX16(0, co_od_get_u16(&t.node, 0x6040, 0));
    TEST_ASSERT_EQUAL_INT16(0, co_od_get_i16(&t.node, 0x6042, 0));
    TEST_ASSERT_EQUAL_UINT32(1, t.node.pdo.stats.rpdo_short);
    TEST_ASSERT_EQUAL_UINT32(malformed + 1u, t.node.stats.rx_malformed);
    const co_frame *f = fake_bus_next(&t.bus);
    TEST_ASSERT_NOT_NULL(f);
    TEST_ASSERT_EQUAL_HEX16(0x85, f->id);
    TEST_ASSERT_EQUAL_HEX8(0x10, f->data[0]);
    TEST_ASSERT_EQUAL_HEX8(0x82, f->data[1]);
    TEST_ASSERT_TRUE(co_emcy_is_active(&t.node, 0x8210));
    test_rx(&t, 0x205, 2, d); /* still short: no second EMCY */
    expect_no_frame(&t);
    test_rx(&t, 0x205, 4, d);
    TEST_ASSERT_FALSE(co_emcy_is_active(&t.node, 0x8210));
    f = fake_bus_next(&t.bus); /* error reset */
    TEST_ASSERT_NOT_NULL(f);
    TEST_ASSERT_EQUAL_HEX16(0x85, f->id);
    TEST_ASSERT_EQUAL_HEX8(0x00, f->data[0]);
    TEST_ASSERT_EQUAL_HEX8(0x00, f->data[1]);
    TEST_ASSERT_EQUAL_HEX16(0x000F, co_od_get_u16(&t.node, 0x6040, 0));
}

static void test_rpdo_short_frame_without_emcy_when_configured(void)
{
    co_pdo_config pc;
    memset(&pc, 0, sizeof pc);
    pc.flags = CO_PDO_RPDO_NO_LENGTH_EMCY;
    start_with(&pc);
    go_operational();
    const uint8_t d[4] = {0x0F, 0x00, 0xE8, 0x03};
    test_rx(&t, 0x205, 1, d);
    TEST_ASSERT_EQUAL_UINT32(1, t.node.pdo.stats.rpdo_short);
    expect_no_frame(&t);
}

static void test_rpdo_longer_frame_raises_0x8220_when_configured(void)
{
    co_pdo_config pc;
    memset(&pc, 0, sizeof pc);
    pc.flags = CO_PDO_RPDO_LONG_EMCY;
    start_with(&pc);
    go_operational();
    test_rx8(&t, 0x205, 0x06, 0x00, 0x10, 0x00, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_HEX16(0x0006, co_od_get_u16(&t.node, 0x6040, 0)); /* still applied */
    const co_frame *f = fake_bus_next(&t.bus);
    TEST_ASSERT_NOT_NULL(f);
    TEST_ASSERT_EQUAL_HEX16(0x85, f->id);
    TEST_ASSERT_EQUAL_HEX8(0x20, f->data[0]);
    TEST_ASSERT_EQUAL_HEX8(0x82, f->data[1]);
}

/* RPDO3 (0x1402, invalid by default): 2030 u8, 2031 u16, 2033 i32 in -100000..100000. */
static void enable_rpdo3(void)
{
    sdo_ok(0x1402, 1, 0x405, 4);
}

static void test_rpdo_out_of_range_value_refuses_the_whole_frame(void)
{
    enable_rpdo3();
    go_operational();
    uint32_t malformed = t.node.stats.rx_malformed;
    /* 2033 = 200000 (0x00030D40): above its limit */
    test_rx8(&t, 0x405, 0x11, 0x22, 0x33, 0x40, 0x0D, 0x03, 0x00, 0);
    TEST_ASSERT_EQUAL_UINT8(0, co_od_get_u8(&t.node, 0x2030, 0));
    TEST_ASSERT_EQUAL_HEX16(0, co_od_get_u16(&t.node, 0x2031, 0));
    TEST_ASSERT_EQUAL_INT32(0, co_od_get_i32(&t.node, 0x2033, 0));
    TEST_ASSERT_EQUAL_UINT32(1, t.node.pdo.stats.rpdo_refused);
    TEST_ASSERT_EQUAL_UINT32(malformed + 1u, t.node.stats.rx_malformed);
    /* -100000 (0xFFFE7960) is the low limit itself: accepted */
    test_rx8(&t, 0x405, 0x11, 0x22, 0x33, 0x60, 0x79, 0xFE, 0xFF, 0);
    TEST_ASSERT_EQUAL_UINT8(0x11, co_od_get_u8(&t.node, 0x2030, 0));
    TEST_ASSERT_EQUAL_HEX16(0x3322, co_od_get_u16(&t.node, 0x2031, 0));
    TEST_ASSERT_EQUAL_INT32(-100000, co_od_get_i32(&t.node, 0x2033, 0));
    /* -100001: below */
    test_rx8(&t, 0x405, 0x55, 0x66, 0x77, 0x5F, 0x79, 0xFE, 0xFF, 0);
    TEST_ASSERT_EQUAL_UINT8(0x11, co_od_get_u8(&t.node, 0x2030, 0));
    TEST_ASSERT_EQUAL_INT32(-100000, co_od_get_i32(&t.node, 0x2033, 0));
    TEST_ASSERT_EQUAL_UINT32(2, t.node.pdo.stats.rpdo_refused);
}

static uint32_t hook_calls;
static co_od_origin hook_origin;

static co_abort controlword_hook(co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                                 uint32_t len, co_od_origin origin)
{
    (void)node;
    (void)ctx;
    (void)ref;
    (void)len;
    hook_calls++;
    hook_origin = origin;
    return co_get_le16(data) == 0xDEADu ? CO_ABORT_VALUE_RANGE : CO_ABORT_NONE;
}

static void test_rpdo_goes_through_object_hooks_which_may_refuse(void)
{
    hook_calls = 0;
    const co_od_hook h = {0x6040, 0x6040, NULL, controlword_hook, NULL, NULL, NULL};
    TEST_ASSERT_TRUE(co_node_add_hook(&t.node, &h));
    go_operational();
    const uint8_t ok[4] = {0x06, 0x00, 0x64, 0x00};
    test_rx(&t, 0x205, 4, ok);
    TEST_ASSERT_EQUAL_UINT32(1, hook_calls);
    TEST_ASSERT_EQUAL(CO_ORIGIN_RPDO, hook_origin);
    TEST_ASSERT_EQUAL_HEX16(0x0006, co_od_get_u16(&t.node, 0x6040, 0));
    const uint8_t bad[4] = {0xAD, 0xDE, 0xC8, 0x00};
    test_rx(&t, 0x205, 4, bad);
    TEST_ASSERT_EQUAL_UINT32(2, hook_calls);
    TEST_ASSERT_EQUAL_HEX16(0x0006, co_od_get_u16(&t.node, 0x6040, 0));
    TEST_ASSERT_EQUAL_INT16(100, co_od_get_i16(&t.node, 0x6042, 0)); /* stopped at the refusal */
    TEST_ASSERT_EQUAL_UINT32(1, t.node.pdo.stats.rpdo_refused);
}

static void test_rtr_on_rpdo_cob_id_is_ignored(void)
{
    go_operational();
    uint32_t ignored = t.node.stats.rx_ignored;
    rtr(0x205);
    TEST_ASSERT_EQUAL_UINT32(ignored + 1u, t.node.stats.rx_ignored);
    TEST_ASSERT_EQUAL_UINT32(0, t.node.pdo.stats.rpdo_received);
    expect_no_frame(&t);
}

static void test_rpdo_timeout_event_to_the_tick_once_then_rearmed(void)
{
    sdo_ok(0x1400, 5, 100, 2); /* 100 ms */
    go_operational();
    test_advance(&t, 1000000); /* not armed before the first RPDO */
    TEST_ASSERT_EQUAL_UINT32(0, comm_events);
    const uint8_t d[4] = {0, 0, 0, 0};
    test_rx(&t, 0x205, 4, d);
    TEST_ASSERT_EQUAL_UINT64(t.now + 100000u, co_node_process(&t.node, t.now));
    test_advance(&t, 99999);
    TEST_ASSERT_EQUAL_UINT32(0, comm_events);
    test_advance(&t, 1);
    TEST_ASSERT_EQUAL_UINT32(1, comm_events);
    TEST_ASSERT_EQUAL(CO_COMM_RPDO_TIMEOUT, last_event);
    TEST_ASSERT_EQUAL_UINT32(1, last_detail);
    test_advance(&t, 1000000);
    TEST_ASSERT_EQUAL_UINT32(1, comm_events);
    test_rx(&t, 0x205, 4, d);
    test_advance(&t, 50000);
    test_rx(&t, 0x205, 4, d); /* each RPDO restarts the timer */
    test_advance(&t, 99999);
    TEST_ASSERT_EQUAL_UINT32(1, comm_events);
    test_advance(&t, 1);
    TEST_ASSERT_EQUAL_UINT32(2, comm_events);
}

static void test_rpdo_timeout_not_armed_by_short_frames_nor_outside_operational(void)
{
    sdo_ok(0x1400, 5, 10, 2);
    go_operational();
    const uint8_t d[4] = {0, 0, 0, 0};
    test_rx(&t, 0x205, 2, d);
    test_advance(&t, 20000);
    TEST_ASSERT_EQUAL_UINT32(0, comm_events);
    test_rx(&t, 0x205, 4, d);
    nmt(0x80); /* pre-operational: monitoring stops */
    test_advance(&t, 20000);
    TEST_ASSERT_EQUAL_UINT32(0, comm_events);
}

static void test_synchronous_rpdo_applied_only_at_sync(void)
{
    sdo_ok(0x1400, 2, 1, 1);
    go_operational();
    const uint8_t a[4] = {0x06, 0x00, 0x10, 0x00};
    const uint8_t b[4] = {0x07, 0x00, 0x20, 0x00};
    test_rx(&t, 0x205, 4, a);
    test_rx(&t, 0x205, 4, b); /* the latest before the SYNC wins */
    TEST_ASSERT_EQUAL_HEX16(0, co_od_get_u16(&t.node, 0x6040, 0));
    test_advance(&t, 500);
    TEST_ASSERT_EQUAL_HEX16(0, co_od_get_u16(&t.node, 0x6040, 0));
    sync_frame();
    TEST_ASSERT_EQUAL_HEX16(0x0007, co_od_get_u16(&t.node, 0x6040, 0));
    TEST_ASSERT_EQUAL_INT16(0x20, co_od_get_i16(&t.node, 0x6042, 0));
    statusword(0); /* nothing else pending: the next SYNC writes nothing */
    TEST_ASSERT_EQUAL_HEX32(0, co_od_set_u16(&t.node, 0x6040, 0, 0x1234));
    sync_frame();
    TEST_ASSERT_EQUAL_HEX16(0x1234, co_od_get_u16(&t.node, 0x6040, 0));
}

static void test_synchronous_rpdo_type_0_waits_for_sync_too(void)
{
    sdo_ok(0x1400, 2, 0, 1);
    go_operational();
    const uint8_t a[4] = {0x0F, 0x00, 0x00, 0x00};
    test_rx(&t, 0x205, 4, a);
    TEST_ASSERT_EQUAL_HEX16(0, co_od_get_u16(&t.node, 0x6040, 0));
    sync_frame();
    TEST_ASSERT_EQUAL_HEX16(0x000F, co_od_get_u16(&t.node, 0x6040, 0));
}

static void test_buffered_rpdo_dropped_when_leaving_operational(void)
{
    sdo_ok(0x1400, 2, 1, 1);
    go_operational();
    const uint8_t a[4] = {0x0F, 0x00, 0x00, 0x00};
    test_rx(&t, 0x205, 4, a);
    nmt(0x80);
    sync_frame();
    go_operational();
    sync_frame();
    TEST_ASSERT_EQUAL_HEX16(0, co_od_get_u16(&t.node, 0x6040, 0));
}

/* --- what a parameter write keeps ------------------------------------------------------------ */

/* The same COB-ID again and a new timeout keep a synchronous RPDO's data for the SYNC; a write of
 * the type (even the same one) drops it. */
static void test_rpdo_parameter_writes_keep_or_drop_the_buffered_data(void)
{
    sdo_ok(0x1400, 2, 1, 1);
    go_operational();
    const uint8_t a[4] = {0x06, 0x00, 0x00, 0x00};
    test_rx(&t, 0x205, 4, a);
    sdo_ok(0x1400, 1, 0x205u, 4);
    sdo_ok(0x1400, 5, 10, 2);
    sync_frame();
    TEST_ASSERT_EQUAL_HEX16(0x0006, co_od_get_u16(&t.node, 0x6040, 0));
    const uint8_t b[4] = {0x07, 0x00, 0x00, 0x00};
    test_rx(&t, 0x205, 4, b);
    sdo_ok(0x1400, 2, 1, 1);
    sync_frame();
    TEST_ASSERT_EQUAL_HEX16(0x0006, co_od_get_u16(&t.node, 0x6040, 0));
}

/* A new event timer runs from the write; the TPDO's other triggers go on. */
static void test_event_timer_write_restarts_only_the_timer(void)
{
    sdo_ok(0x1800, 5, 100, 2);
    go_operational();
    test_advance(&t, 60000);
    sdo_ok(0x1800, 5, 100, 2);
    test_advance(&t, 99999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    expect_tpdo1(0);
    sdo_ok(0x1800, 5, 0, 2); /* stops it */
    test_advance(&t, 300000);
    expect_no_frame(&t);
}

/* Bit 30 of a valid TPDO's COB-ID changes nothing of its SYNC count; a write of its type restarts
 * the count, a new mapping too. */
static void test_cyclic_tpdo_count_kept_or_restarted_by_parameter_writes(void)
{
    sdo_ok(0x1800, 2, 3, 1);
    go_operational();
    sync_frame();
    sync_frame();
    sdo_ok(0x1800, 1, 0x40000185u, 4);
    sync_frame();
    expect_tpdo1(0);
    sync_frame();
    sdo_ok(0x1800, 2, 3, 1);
    sync_frame();
    sync_frame();
    expect_no_frame(&t);
    sync_frame();
    expect_tpdo1(0);
    sync_frame();
    sdo_ok(0x1800, 1, 0xC0000185u, 4);
    sdo_ok(0x1A00, 0, 1, 1);
    sdo_ok(0x1800, 1, 0x185u, 4);
    sync_frame();
    sync_frame();
    expect_no_frame(&t);
    sync_frame();
    const uint8_t d[2] = {0, 0};
    expect_frame(&t, 0x185, 2, d);
}

/* --- TPDO events -------------------------------------------------------------------------- */

static void test_tpdo_sent_when_application_changes_a_mapped_value(void)
{
    go_operational();
    expect_no_frame(&t); /* nothing on entering OPERATIONAL by default */
    statusword(0x0237);
    expect_no_frame(&t); /* application writes go out at the next process */
    test_advance(&t, 0);
    expect_tpdo1(0x0237);
    expect_no_frame(&t);
    statusword(0x0237); /* same value: nothing new */
    test_advance(&t, 0);
    expect_no_frame(&t);
    statusword(0x0233);
    test_advance(&t, 10);
    expect_tpdo1(0x0233);
}

static void test_tpdo_sent_when_sdo_writes_a_mapped_value(void)
{
    /* TPDO1 remapped to 0x2035 (rwr u16, SDO-writable). */
    sdo_ok(0x1800, 1, 0x80000185u, 4);
    sdo_ok(0x1A00, 0, 0, 1);
    sdo_ok(0x1A00, 1, 0x20350010u, 4);
    sdo_ok(0x1A00, 0, 1, 1);
    sdo_ok(0x1800, 1, 0x185u, 4);
    go_operational();
    sdo_ok(0x2035, 0, 0xBEEF, 2); /* response first, then the TPDO, within the same frame */
    const uint8_t d[2] = {0xEF, 0xBE};
    expect_frame(&t, 0x185, 2, d);
    expect_no_frame(&t);
}

static void test_tpdo_not_sent_outside_operational(void)
{
    statusword(0x0250);
    test_advance(&t, 1000);
    nmt(0x02);
    statusword(0x0251);
    test_advance(&t, 1000);
    sync_frame();
    rtr(0x185);
    expect_no_frame(&t);
    go_operational();
    statusword(0x0252);
    test_advance(&t, 0);
    expect_tpdo1(0x0252);
    nmt(0x80);
    statusword(0x0253);
    test_advance(&t, 0);
    expect_no_frame(&t);
}

static void test_tpdo_send_on_start_when_configured(void)
{
    co_pdo_config pc;
    memset(&pc, 0, sizeof pc);
    pc.flags = CO_PDO_TPDO_SEND_ON_START;
    start_with(&pc);
    statusword(0x0240);
    go_operational();
    expect_tpdo1(0x0240);
    expect_no_frame(&t);
}

static void test_inhibit_time_to_the_tick(void)
{
    tpdo1_param(3, 10, 2); /* 10 x 100 us = 1 ms */
    go_operational();
    statusword(1);
    test_advance(&t, 0);
    expect_tpdo1(1);
    uint64_t sent_at = t.now;
    test_advance(&t, 100);
    statusword(2);
    TEST_ASSERT_EQUAL_UINT64(sent_at + 1000u, test_advance(&t, 0));
    expect_no_frame(&t);
    statusword(3); /* the latest value goes out when the inhibit time ends */
    test_advance(&t, 899);
    expect_no_frame(&t);
    test_advance(&t, 1);
    expect_tpdo1(3);
    expect_no_frame(&t);
    test_advance(&t, 5000); /* and nothing more without a change */
    expect_no_frame(&t);
}

static void test_inhibit_time_change_and_back_sends_nothing(void)
{
    tpdo1_param(3, 10, 2);
    go_operational();
    statusword(1);
    test_advance(&t, 0);
    expect_tpdo1(1);
    statusword(2);
    statusword(1);
    test_advance(&t, 2000);
    expect_no_frame(&t);
}

static void test_inhibit_unit_and_floor_from_config(void)
{
    co_pdo_config pc;
    memset(&pc, 0, sizeof pc);
    pc.tpdo_inhibit_unit_us = 1000; /* a drive counting ms ... */
    pc.tpdo_inhibit_min_us = 50000; /* ... with a 50 ms floor */
    start_with(&pc);
    tpdo1_param(3, 10, 2); /* 10 ms -> 50 ms */
    go_operational();
    statusword(1);
    test_advance(&t, 0);
    expect_tpdo1(1);
    statusword(2);
    test_advance(&t, 49999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    expect_tpdo1(2);
    nmt(0x80);
    tpdo1_param(3, 100, 2); /* 100 ms, above the floor */
    go_operational();
    statusword(3);
    test_advance(&t, 0);
    expect_tpdo1(3);
    statusword(4);
    test_advance(&t, 99999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    expect_tpdo1(4);
}

static void test_inhibit_floor_of_zero_applies_unless_only_if_set(void)
{
    co_pdo_config pc;
    memset(&pc, 0, sizeof pc);
    pc.tpdo_inhibit_min_us = 2000;
    start_with(&pc); /* sub 3 = 0 still gets 2 ms */
    go_operational();
    statusword(1);
    test_advance(&t, 0);
    expect_tpdo1(1);
    statusword(2);
    test_advance(&t, 1999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    expect_tpdo1(2);

    pc.flags = CO_PDO_INHIBIT_MIN_IF_SET; /* 0 means none, a non-zero value at least 2 ms */
    start_with(&pc);
    go_operational();
    statusword(1);
    test_advance(&t, 0);
    statusword(2);
    test_advance(&t, 0);
    expect_tpdo1(1);
    expect_tpdo1(2);
}

static void test_event_timer_to_the_tick_and_restarted_by_each_transmission(void)
{
    sdo_ok(0x1800, 5, 100, 2); /* 100 ms, writable while valid */
    go_operational();
    uint64_t start = t.now;
    TEST_ASSERT_EQUAL_UINT64(start + 100000u, co_node_process(&t.node, t.now));
    test_advance(&t, 99999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    expect_tpdo1(0); /* sent although nothing changed */
    test_advance(&t, 100000);
    expect_tpdo1(0);
    test_advance(&t, 30000);
    statusword(9); /* a change sends and restarts the timer */
    test_advance(&t, 0);
    expect_tpdo1(9);
    test_advance(&t, 99999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    expect_tpdo1(9);
}

/* An application's local START (co_nmt_command_local) long after the node last ran: the event
 * timer counts from the command's time, not from the node's last rx or process call. */
static void test_event_timer_from_a_local_start_counts_from_its_time(void)
{
    sdo_ok(0x1800, 5, 100, 2);
    t.now += 10000000u; /* 10 s in PRE-OPERATIONAL with nothing due: no call */
    co_nmt_command_local(&t.node, CO_NMT_CMD_START, t.now);
    TEST_ASSERT_EQUAL(CO_NMT_OPERATIONAL, t.node.nmt_state);
    TEST_ASSERT_EQUAL_UINT64(t.now + 100000u, co_node_process(&t.node, t.now));
    test_advance(&t, 99999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    expect_tpdo1(0);
}

static void test_event_timer_floor_from_config(void)
{
    co_pdo_config pc;
    memset(&pc, 0, sizeof pc);
    pc.tpdo_event_min_us = 10000;
    start_with(&pc);
    sdo_ok(0x1800, 5, 5, 2); /* 5 ms acts as 10 ms */
    go_operational();
    test_advance(&t, 9999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    expect_tpdo1(0);
}

static void test_event_timer_waits_for_inhibit_time(void)
{
    tpdo1_param(3, 30, 2); /* 3 ms */
    sdo_ok(0x1800, 5, 2, 2); /* 2 ms */
    go_operational();
    test_advance(&t, 2000);
    expect_tpdo1(0);
    test_advance(&t, 2000); /* timer expired 1 ms before the inhibit time ends */
    expect_no_frame(&t);
    test_advance(&t, 1000);
    expect_tpdo1(0);
}

static void test_application_request_sends_even_without_change(void)
{
    go_operational();
    TEST_ASSERT_TRUE(co_pdo_tpdo_request(&t.node, 1));
    test_advance(&t, 0);
    expect_tpdo1(0);
    TEST_ASSERT_TRUE(co_pdo_tpdo_request(&t.node, 1));
    test_advance(&t, 0);
    expect_tpdo1(0);
    TEST_ASSERT_FALSE(co_pdo_tpdo_request(&t.node, 2));  /* invalid */
    TEST_ASSERT_FALSE(co_pdo_tpdo_request(&t.node, 99)); /* absent */
}

/* --- TPDO and SYNC ------------------------------------------------------------------------- */

static void test_tpdo_every_nth_sync(void)
{
    sdo_ok(0x1800, 2, 3, 1);
    go_operational();
    statusword(0x11); /* changes do not send a cyclic TPDO */
    test_advance(&t, 0);
    sync_frame();
    sync_frame();
    expect_no_frame(&t);
    sync_frame();
    expect_tpdo1(0x11);
    sync_frame();
    sync_frame();
    expect_no_frame(&t);
    sync_frame();
    expect_tpdo1(0x11);
}

static void test_tpdo_type_1_every_sync_with_current_data(void)
{
    sdo_ok(0x1800, 2, 1, 1);
    go_operational();
    sync_frame();
    expect_tpdo1(0);
    statusword(0x22);
    sync_frame();
    expect_tpdo1(0x22);
    sync_frame();
    expect_tpdo1(0x22);
}

static void test_tpdo_type_0_only_at_sync_after_change(void)
{
    sdo_ok(0x1800, 2, 0, 1);
    go_operational();
    sync_frame();
    expect_no_frame(&t);
    statusword(0x31);
    test_advance(&t, 100);
    expect_no_frame(&t); /* waits for the SYNC */
    sync_frame();
    expect_tpdo1(0x31);
    sync_frame();
    expect_no_frame(&t);
    statusword(0x31); /* written, but the same */
    sync_frame();
    expect_no_frame(&t);
    statusword(0x32);
    statusword(0x33);
    sync_frame();
    expect_tpdo1(0x33);
}

static void test_sync_start_value_with_sync_counter(void)
{
    sdo_ok(0x1019, 0, 5, 1);
    sdo_ok(0x1800, 2, 2, 1);
    tpdo1_param(6, 3, 1);
    go_operational();
    sync_counter(1);
    sync_counter(2);
    expect_no_frame(&t);
    sync_counter(3); /* the first SYNC for this TPDO */
    expect_tpdo1(0);
    sync_counter(4);
    expect_no_frame(&t);
    sync_counter(5);
    expect_tpdo1(0);
    sync_counter(1);
    expect_no_frame(&t);
    sync_counter(2);
    expect_tpdo1(0);
}

static void test_sync_start_value_unused_without_counter(void)
{
    sdo_ok(0x1800, 2, 2, 1);
    tpdo1_param(6, 3, 1);
    go_operational();
    sync_frame();
    expect_no_frame(&t);
    sync_frame();
    expect_tpdo1(0);
}

static void test_sync_counter_restarts_when_entering_operational(void)
{
    sdo_ok(0x1800, 2, 2, 1);
    go_operational();
    sync_frame();
    nmt(0x80);
    go_operational();
    sync_frame();
    expect_no_frame(&t);
    sync_frame();
    expect_tpdo1(0);
}

/* --- RTR ----------------------------------------------------------------------------------- */

static void test_rtr_type_253_samples_and_sends(void)
{
    sdo_ok(0x1800, 2, 253, 1);
    go_operational();
    statusword(0x41); /* not sent on change */
    test_advance(&t, 0);
    sync_frame();
    expect_no_frame(&t);
    rtr(0x185);
    expect_tpdo1(0x41);
    expect_no_frame(&t);
}

static void test_rtr_type_252_sends_the_sync_sample(void)
{
    sdo_ok(0x1800, 2, 252, 1);
    go_operational();
    rtr(0x185); /* no SYNC yet: the current data */
    expect_tpdo1(0);
    statusword(0x51);
    sync_frame();
    expect_no_frame(&t);
    statusword(0x52);
    rtr(0x185);
    expect_tpdo1(0x51);
    sync_frame();
    rtr(0x185);
    expect_tpdo1(0x52);
}

static void test_rtr_answered_for_event_driven_types(void)
{
    go_operational();
    statusword(0x61);
    rtr(0x185);
    expect_tpdo1(0x61);
    test_advance(&t, 0); /* the RTR answer carried the change: nothing more */
    expect_no_frame(&t);
}

static void test_rtr_refused_when_cob_id_bit_30_set(void)
{
    sdo_ok(0x1800, 1, 0x40000185u, 4); /* only bit 30 changes: allowed while valid */
    go_operational();
    uint32_t malformed = t.node.stats.rx_malformed;
    rtr(0x185);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT32(malformed + 1u, t.node.stats.rx_malformed);
    statusword(0x71); /* the TPDO itself still works */
    test_advance(&t, 0);
    expect_tpdo1(0x71);
}

static void test_rtr_on_cyclic_type_only_with_any_type_flag(void)
{
    sdo_ok(0x1800, 2, 5, 1);
    go_operational();
    rtr(0x185);
    expect_no_frame(&t);

    co_pdo_config pc;
    memset(&pc, 0, sizeof pc);
    pc.flags = CO_PDO_TPDO_RTR_ANY_TYPE;
    start_with(&pc);
    sdo_ok(0x1800, 2, 5, 1);
    go_operational();
    rtr(0x185);
    expect_tpdo1(0);
}

/* Starts the node with the PDO flags given and TPDO1 sent on RTR only (type 253), OPERATIONAL. */
static void start_rtr_only_tpdo1(uint16_t flags)
{
    co_pdo_config pc;
    memset(&pc, 0, sizeof pc);
    pc.flags = flags;
    start_with(&pc);
    sdo_ok(0x1800, 2, 253, 1);
    go_operational();
}

static void test_rtr_never_answered_with_no_rtr_flag(void)
{
    start_rtr_only_tpdo1(CO_PDO_TPDO_NO_RTR);
    rtr(0x185);
    expect_no_frame(&t);
}

static void test_tpdo_padded_to_eight_bytes_with_dlc_8_flag(void)
{
    start_rtr_only_tpdo1(CO_PDO_TPDO_DLC_8);
    rtr(0x185);
    const uint8_t d[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    expect_frame(&t, 0x185, 8, d); /* 4 mapped bytes, then 4 zero bytes */
}

static void test_padded_tpdo_tail_stays_zero_after_a_shorter_mapping(void)
{
    start_rtr_only_tpdo1(CO_PDO_TPDO_DLC_8);
    statusword(0x1234);
    TEST_ASSERT_EQUAL_HEX32(0, co_od_set_i16(&t.node, 0x6044, 0, -2));
    rtr(0x185);
    const uint8_t full[8] = {0x34, 0x12, 0xFE, 0xFF, 0, 0, 0, 0};
    expect_frame(&t, 0x185, 8, full);
    /* the velocity no longer mapped: its bytes of the last frame are not sent again */
    sdo_ok(0x1800, 1, 0x80000185u, 4);
    sdo_ok(0x1A00, 0, 1, 1);
    sdo_ok(0x1800, 1, 0x185u, 4);
    rtr(0x185);
    const uint8_t shorter[8] = {0x34, 0x12, 0, 0, 0, 0, 0, 0};
    expect_frame(&t, 0x185, 8, shorter);
    expect_no_frame(&t);
}

static void test_rpdo_limits_of_unsigned_and_real_objects(void)
{
    /* Second dictionary, node 7: RPDO1 remapped to 2000 (u16, no limits) + 2003 (u16 10..500) +
     * 2004 (REAL32 +-1.5). A refused value leaves 2000, written before it, untouched too. */
    memset(&t, 0, sizeof t);
    co_node_config cfg = co_node_default_config();
    cfg.od = &co_od_test_sparse;
    cfg.values = t.values;
    cfg.node_id = 7;
    cfg.driver = fake_bus_driver(&t.bus);
    TEST_ASSERT_TRUE(co_node_init(&t.node, &cfg));
    co_node_start(&t.node, t.now);
    fake_bus_clear(&t.bus);
    sdo_ok(0x1400, 1, 0x80000207u, 4);
    sdo_ok(0x1600, 0, 0, 1);
    sdo_ok(0x1600, 1, 0x20000010u, 4);
    sdo_ok(0x1600, 2, 0x20030010u, 4);
    sdo_ok(0x1600, 3, 0x20040020u, 4);
    sdo_ok(0x1600, 0, 3, 1);
    sdo_ok(0x1400, 1, 0x207u, 4);
    const uint8_t start[2] = {0x01, 7};
    test_rx(&t, 0x0, 2, start);
    TEST_ASSERT_EQUAL(CO_NMT_OPERATIONAL, t.node.nmt_state);
    test_rx8(&t, 0x207, 1, 0, 9, 0, 0x00, 0x00, 0x00, 0x00);       /* 9 < 10 */
    test_rx8(&t, 0x207, 2, 0, 0xF5, 0x01, 0x00, 0x00, 0x00, 0x00); /* 501 > 500 */
    test_rx8(&t, 0x207, 3, 0, 0x0A, 0x00, 0x01, 0x00, 0xC0, 0x3F); /* 1.5000001 */
    test_rx8(&t, 0x207, 4, 0, 0x0A, 0x00, 0x00, 0x00, 0xC0, 0x7F); /* NaN */
    test_rx8(&t, 0x207, 5, 0, 0x0A, 0x00, 0x00, 0x00, 0xC0, 0xFF); /* -NaN */
    TEST_ASSERT_EQUAL_UINT16(0, co_od_get_u16(&t.node, 0x2000, 0));
    TEST_ASSERT_EQUAL_UINT16(10, co_od_get_u16(&t.node, 0x2003, 0));
    TEST_ASSERT_EQUAL_HEX32(0, co_od_get_u32(&t.node, 0x2004, 0));
    TEST_ASSERT_EQUAL_UINT32(5, t.node.pdo.stats.rpdo_refused);
    test_rx8(&t, 0x207, 6, 0, 0xF4, 0x01, 0x00, 0x00, 0xC0, 0x3F); /* 500, 1.5 */
    TEST_ASSERT_EQUAL_UINT16(6, co_od_get_u16(&t.node, 0x2000, 0));
    TEST_ASSERT_EQUAL_UINT16(500, co_od_get_u16(&t.node, 0x2003, 0));
    TEST_ASSERT_EQUAL_HEX32(0x3FC00000u, co_od_get_u32(&t.node, 0x2004, 0));
    test_rx8(&t, 0x207, 7, 0, 0x0A, 0x00, 0x00, 0x00, 0xC0, 0xBF); /* 10, -1.5 */
    TEST_ASSERT_EQUAL_UINT16(10, co_od_get_u16(&t.node, 0x2003, 0));
    TEST_ASSERT_EQUAL_HEX32(0xBFC00000u, co_od_get_u32(&t.node, 0x2004, 0));
    TEST_ASSERT_EQUAL_UINT32(5, t.node.pdo.stats.rpdo_refused);
}

/* xorshift32: deterministic junk. */
static uint32_t junk(uint32_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 17;
    *s ^= *s << 5;
    return *s;
}

static void test_junk_on_every_other_cob_id_in_operational_changes_no_value(void)
{
    /* Every PDO active and synchronous data pending, then junk everywhere but NMT, SDO and
     * RPDO1: no value may change (TPDO answers to RTRs are fine). */
    sdo_ok(0x1402, 1, 0x405, 4);
    sdo_ok(0x1800, 2, 1, 1);
    go_operational();
    static uint8_t before[8192];
    memcpy(before, t.values, co_od_test.value_size);
    uint32_t seed = 0xC0FFEE01u;
    for (uint16_t id = 1; id <= 0x7FFu; id++) {
        if (id == 0x605u || id == 0x205u || id == 0x405u) {
            continue;
        }
        for (uint8_t dlc = 0; dlc <= 8u; dlc++) {
            co_frame f;
            f.id = id;
            f.dlc = dlc;
            f.flags = (junk(&seed) & 1u) != 0u ? CO_FRAME_RTR : 0u;
            for (int i = 0; i < 8; i++) {
                f.data[i] = (uint8_t)junk(&seed);
            }
            co_node_rx(&t.node, &f, t.now);
            t.now += 7;
            (void)co_node_process(&t.node, t.now);
        }
    }
    TEST_ASSERT_EQUAL_HEX8_ARRAY(before, t.values, co_od_test.value_size);
    TEST_ASSERT_EQUAL(CO_NMT_OPERATIONAL, t.node.nmt_state);
    TEST_ASSERT_EQUAL_UINT32(0, t.node.pdo.stats.rpdo_received);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_rpdo_writes_mapped_objects_in_operational);
    RUN_TEST(test_rpdo_ignored_in_pre_operational_and_stopped);
    RUN_TEST(test_rpdo_longer_frame_uses_mapped_bytes);
    RUN_TEST(test_rpdo_short_frame_dropped_counted_with_emcy_until_right_length);
    RUN_TEST(test_rpdo_short_frame_without_emcy_when_configured);
    RUN_TEST(test_rpdo_longer_frame_raises_0x8220_when_configured);
    RUN_TEST(test_rpdo_out_of_range_value_refuses_the_whole_frame);
    RUN_TEST(test_rpdo_goes_through_object_hooks_which_may_refuse);
    RUN_TEST(test_rtr_on_rpdo_cob_id_is_ignored);
    RUN_TEST(test_rpdo_timeout_event_to_the_tick_once_then_rearmed);
    RUN_TEST(test_rpdo_timeout_not_armed_by_short_frames_nor_outside_operational);
    RUN_TEST(test_synchronous_rpdo_applied_only_at_sync);
    RUN_TEST(test_synchronous_rpdo_type_0_waits_for_sync_too);
    RUN_TEST(test_buffered_rpdo_dropped_when_leaving_operational);
    RUN_TEST(test_rpdo_parameter_writes_keep_or_drop_the_buffered_data);
    RUN_TEST(test_event_timer_write_restarts_only_the_timer);
    RUN_TEST(test_cyclic_tpdo_count_kept_or_restarted_by_parameter_writes);
    RUN_TEST(test_tpdo_sent_when_application_changes_a_mapped_value);
    RUN_TEST(test_tpdo_sent_when_sdo_writes_a_mapped_value);
    RUN_TEST(test_tpdo_not_sent_outside_operational);
    RUN_TEST(test_tpdo_send_on_start_when_configured);
    RUN_TEST(test_inhibit_time_to_the_tick);
    RUN_TEST(test_inhibit_time_change_and_back_sends_nothing);
    RUN_TEST(test_inhibit_unit_and_floor_from_config);
    RUN_TEST(test_inhibit_floor_of_zero_applies_unless_only_if_set);
    RUN_TEST(test_event_timer_to_the_tick_and_restarted_by_each_transmission);
    RUN_TEST(test_event_timer_from_a_local_start_counts_from_its_time);
    RUN_TEST(test_event_timer_floor_from_config);
    RUN_TEST(test_event_timer_waits_for_inhibit_time);
    RUN_TEST(test_application_request_sends_even_without_change);
    RUN_TEST(test_tpdo_every_nth_sync);
    RUN_TEST(test_tpdo_type_1_every_sync_with_current_data);
    RUN_TEST(test_tpdo_type_0_only_at_sync_after_change);
    RUN_TEST(test_sync_start_value_with_sync_counter);
    RUN_TEST(test_sync_start_value_unused_without_counter);
    RUN_TEST(test_sync_counter_restarts_when_entering_operational);
    RUN_TEST(test_rtr_type_253_samples_and_sends);
    RUN_TEST(test_rtr_type_252_sends_the_sync_sample);
    RUN_TEST(test_rtr_answered_for_event_driven_types);
    RUN_TEST(test_rtr_refused_when_cob_id_bit_30_set);
    RUN_TEST(test_rtr_on_cyclic_type_only_with_any_type_flag);
    RUN_TEST(test_rtr_never_answered_with_no_rtr_flag);
    RUN_TEST(test_tpdo_padded_to_eight_bytes_with_dlc_8_flag);
    RUN_TEST(test_padded_tpdo_tail_stays_zero_after_a_shorter_mapping);
    RUN_TEST(test_rpdo_limits_of_unsigned_and_real_objects);
    RUN_TEST(test_junk_on_every_other_cob_id_in_operational_changes_no_value);
    return UNITY_END();
}
