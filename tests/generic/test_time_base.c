/* The services' timing across long runs, built twice: on the generic core with 64-bit co_time and
 * with CO_CONFIG_TIME32 (32-bit counts from an epoch the node moves, include/canopen/time_base.h,
 * as boards/cortex-m4 builds it). The expectations are the same absolute times in both builds:
 * frames at exact API times across many moves of the epoch, periods longer than 2^31 and 2^32 µs
 * (life guarding 65535 ms x 255, a SYNC period and window of 2^32 - 1 µs), a call hours late,
 * and co_node_process's answer, which an application may sleep on. */
#include <string.h>

#include "canopen/node.h"
#include "od_bench.h"
#include "unity.h"

void setUp(void);
void tearDown(void);

#define NODE_ID 5u
#define SECOND 1000000ull
#define MINUTE (60u * SECOND)
#define HOUR (60u * MINUTE)
/* Far from 0 and not a multiple of 2^32: the first call moves the epoch at once. */
#define T0 ((1ull << 40) + 12345u)

typedef struct sent_frame {
    uint64_t at;
    co_frame frame;
} sent_frame;

static uint64_t values[CO_OD_BENCH_VALUE_SIZE / 8u + 1u];
static co_node node;
static uint64_t now;          /* API time of the call in progress */
static sent_frame sent[512];
static uint32_t sent_count;
static uint32_t life_lost_events;

static bool capture(void *ctx, const co_frame *f)
{
    (void)ctx;
    if (sent_count < sizeof sent / sizeof sent[0]) {
        sent[sent_count].at = now;
        sent[sent_count].frame = *f;
    }
    sent_count++;
    return true;
}

static void on_comm(co_node *n, void *ctx, co_comm_event event, uint32_t detail)
{
    (void)n;
    (void)ctx;
    (void)detail;
    if (event == CO_COMM_LIFE_GUARD_LOST) {
        life_lost_events++;
    }
}

static co_node_config config(void)
{
    co_node_config cfg = co_node_default_config();
    cfg.od = &co_od_bench;
    cfg.values = (uint8_t *)values;
    cfg.node_id = NODE_ID;
    cfg.driver.send = capture;
    cfg.events.comm = on_comm;
    return cfg;
}

void setUp(void)
{
    co_node_config cfg = config();
    TEST_ASSERT_TRUE(co_node_init(&node, &cfg));
    sent_count = 0u;
    life_lost_events = 0u;
    now = T0;
    co_node_start(&node, now);
    (void)co_node_process(&node, now);
    sent_count = 0u; /* the boot-up */
}

void tearDown(void) {}

/* Writes an object as an SDO download would, at time t. */
static void write_at(uint64_t t, uint16_t index, uint8_t subindex, uint32_t value, uint32_t len)
{
    now = t;
    (void)co_node_process(&node, now);
    uint8_t data[4];
    co_put_le32(data, value);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NONE, co_od_write(&node, index, subindex, data, len,
                                                       CO_ORIGIN_SDO));
}

static void rx_at(uint64_t t, uint16_t id, uint8_t dlc, uint8_t flags, const uint8_t *data)
{
    co_frame f = {id, dlc, flags, {0}};
    if (data != NULL) {
        memcpy(f.data, data, dlc);
    }
    now = t;
    co_node_rx(&node, &f, now);
    (void)co_node_process(&node, now);
}

/* Calls co_node_process at every time it asks for, and at least every step µs, up to end. */
static void run_until(uint64_t end, uint64_t step)
{
    while (now < end) {
        uint64_t next = co_node_process(&node, now);
        TEST_ASSERT_TRUE(next > now); /* nothing due is left behind */
        uint64_t limit = end - now < step ? end : now + step;
        now = next < limit ? next : limit;
    }
    (void)co_node_process(&node, now);
}

/* The times of the frames sent with CAN-ID id, in order. */
static uint32_t frames_with_id(uint16_t id, uint64_t *at, uint32_t cap)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < sent_count && i < sizeof sent / sizeof sent[0]; i++) {
        if (sent[i].frame.id == id) {
            if (n < cap) {
                at[n] = sent[i].at;
            }
            n++;
        }
    }
    return n;
}

static void test_heartbeats_keep_their_cadence_for_hours(void)
{
    write_at(T0, 0x1017u, 0u, 60000u, 2u); /* 60 s */
    run_until(T0 + 3u * HOUR, 7u * MINUTE);
    uint64_t at[200];
    uint32_t n = frames_with_id(0x700u + NODE_ID, at, 200u);
    TEST_ASSERT_EQUAL_UINT32(180u, n);
    for (uint32_t k = 0; k < n; k++) {
        TEST_ASSERT_EQUAL_UINT64(T0 + (k + 1u) * MINUTE, at[k]);
    }
    /* the application may sleep until the time co_node_process names */
    TEST_ASSERT_EQUAL_UINT64(T0 + 181u * MINUTE, co_node_process(&node, now));
}

static void test_a_call_hours_late_restarts_the_cadence_from_then(void)
{
    write_at(T0, 0x1017u, 0u, 1000u, 2u);
    now = T0 + 10u * HOUR + 123u;
    TEST_ASSERT_EQUAL_UINT64(now + SECOND, co_node_process(&node, now));
    uint64_t at[4];
    TEST_ASSERT_EQUAL_UINT32(1u, frames_with_id(0x700u + NODE_ID, at, 4u));
    TEST_ASSERT_EQUAL_UINT64(now, at[0]);
}

static void test_a_clock_gone_back_hours_sends_nothing_early(void)
{
    write_at(T0, 0x1017u, 0u, 1000u, 2u);
    run_until(T0 + 2u * HOUR, 10u * MINUTE);
    TEST_ASSERT_EQUAL_UINT32(7200u, sent_count);
    uint64_t next = co_node_process(&node, now);
    TEST_ASSERT_EQUAL_UINT64(T0 + 2u * HOUR + SECOND, next);
    now = T0 + 1u; /* two hours back */
    (void)co_node_process(&node, now);
    TEST_ASSERT_EQUAL_UINT32(7200u, sent_count);
    now = next;
    (void)co_node_process(&node, now);
    TEST_ASSERT_EQUAL_UINT32(7201u, sent_count);
}

static void test_nothing_pending_is_never_across_epochs(void)
{
    for (uint32_t i = 0; i < 20u; i++) {
        now += 3u * HOUR + 17u;
        TEST_ASSERT_EQUAL_UINT64(CO_TIME_NEVER, co_node_process(&node, now));
    }
    TEST_ASSERT_EQUAL_UINT32(0u, sent_count);
}

/* 65535 ms x 255 = 16 711.425 s: far beyond 2^32 µs. */
static void test_life_guarding_of_four_and_a_half_hours(void)
{
    const uint64_t life = 65535ull * 1000u * 255u;
    write_at(T0, 0x100Cu, 0u, 65535u, 2u);
    write_at(T0, 0x100Du, 0u, 255u, 1u);
    uint64_t t1 = T0 + 5u * SECOND;
    rx_at(t1, 0x700u + NODE_ID, 1u, CO_FRAME_RTR, NULL); /* the first guard request */
    TEST_ASSERT_EQUAL_UINT32(1u, sent_count);           /* its answer */
    run_until(t1 + life - 1u, 10u * MINUTE);
    TEST_ASSERT_EQUAL_UINT32(0u, life_lost_events);
    run_until(t1 + life, 10u * MINUTE);
    TEST_ASSERT_EQUAL_UINT32(1u, life_lost_events);
}

static void test_life_guarding_deadline_is_met_by_sleeping_on_the_answer(void)
{
    const uint64_t life = 65535ull * 1000u * 200u;
    write_at(T0, 0x100Cu, 0u, 65535u, 2u);
    write_at(T0, 0x100Du, 0u, 200u, 1u);
    uint64_t t1 = T0 + 7u;
    rx_at(t1, 0x700u + NODE_ID, 1u, CO_FRAME_RTR, NULL);
    /* only at the times co_node_process names: the first one at or after the deadline is it */
    while (life_lost_events == 0u) {
        uint64_t next = co_node_process(&node, now);
        TEST_ASSERT_TRUE(next <= t1 + life);
        now = next;
        (void)co_node_process(&node, now);
    }
    TEST_ASSERT_EQUAL_UINT64(t1 + life, now);
}

/* A SYNC period of 2^32 - 1 µs (71.6 min). */
static void test_sync_producer_with_the_longest_period(void)
{
    const uint64_t period = 0xFFFFFFFFu;
    write_at(T0, 0x1006u, 0u, (uint32_t)period, 4u);
    write_at(T0, 0x1005u, 0u, 0x40000080u, 4u); /* producer: the period starts now */
    run_until(T0 + 3u * period, UINT64_MAX);     /* at the times it asks for only */
    run_until(T0 + 4u * period + 5u, 13u * MINUTE);
    uint64_t at[8];
    uint32_t n = frames_with_id(0x080u, at, 8u);
    TEST_ASSERT_EQUAL_UINT32(4u, n);
    for (uint32_t k = 0; k < n; k++) {
        TEST_ASSERT_EQUAL_UINT64(T0 + (k + 1u) * period, at[k]);
    }
}

/* A synchronous window of 2^32 - 1 µs after a SYNC received. */
static void test_sync_window_longer_than_2_pow_31(void)
{
    write_at(T0, 0x1007u, 0u, 0xFFFFFFFFu, 4u);
    uint64_t t1 = T0 + 3u * SECOND;
    rx_at(t1, 0x080u, 0u, 0u, NULL);
    for (uint64_t t = t1; t < t1 + 0xFFFFFFFFu; t += 9u * MINUTE) {
        now = t;
        (void)co_node_process(&node, now);
        TEST_ASSERT_TRUE(co_sync_window_open(&node, node.now));
    }
    now = t1 + 0xFFFFFFFEu;
    (void)co_node_process(&node, now);
    TEST_ASSERT_TRUE(co_sync_window_open(&node, node.now));
    now = t1 + 0xFFFFFFFFu;
    (void)co_node_process(&node, now);
    TEST_ASSERT_FALSE(co_sync_window_open(&node, node.now));
}

/* A clock that jumps 2^63 µs ahead: the SYNC seen before is far past, the node goes on. */
static void test_a_jump_of_2_pow_63(void)
{
    write_at(T0, 0x1007u, 0u, 0xFFFFFFFFu, 4u);
    rx_at(T0 + 1u, 0x080u, 0u, 0u, NULL);
    write_at(T0 + 2u, 0x1017u, 0u, 1000u, 2u);
    sent_count = 0u;
    now = T0 + (1ull << 63);
    TEST_ASSERT_EQUAL_UINT64(now + SECOND, co_node_process(&node, now));
    TEST_ASSERT_EQUAL_UINT32(1u, sent_count); /* the heartbeat that was due */
    TEST_ASSERT_FALSE(co_sync_window_open(&node, node.now));
    rx_at(now + 5u, 0x080u, 0u, 0u, NULL);
    TEST_ASSERT_TRUE(co_sync_window_open(&node, node.now));
}

/* An SDO transfer times out one second after its last frame, wherever the epoch moves. */
static void test_sdo_timeout_across_epoch_moves(void)
{
    for (uint64_t start = T0 + MINUTE; start < T0 + 2u * HOUR; start += 7u * MINUTE + 333u) {
        const uint8_t upload[8] = {0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0}; /* 0x1008: segmented */
        sent_count = 0u;
        rx_at(start, 0x600u + NODE_ID, 8u, 0u, upload);
        TEST_ASSERT_EQUAL_UINT32(1u, sent_count);
        TEST_ASSERT_EQUAL_HEX8(0x41, sent[0].frame.data[0]);
        now = start + SECOND - 1u;
        TEST_ASSERT_EQUAL_UINT64(start + SECOND, co_node_process(&node, now));
        TEST_ASSERT_EQUAL_UINT32(1u, sent_count);
        now = start + SECOND;
        (void)co_node_process(&node, now);
        TEST_ASSERT_EQUAL_UINT32(2u, sent_count);
        TEST_ASSERT_EQUAL_HEX8(0x80, sent[1].frame.data[0]);
        TEST_ASSERT_EQUAL_HEX32(CO_ABORT_TIMEOUT, co_get_le32(&sent[1].frame.data[4]));
    }
}

/* Timeouts of the SDO server up to 2^31 - 1 µs are accepted by both builds; the 32-bit one
 * refuses longer ones (their deadline would not fit), the 64-bit one takes them. */
static void test_sdo_timeout_limit(void)
{
    co_node_config cfg = config();
    cfg.sdo_timeout_us = 0x7FFFFFFFu;
    TEST_ASSERT_TRUE(co_node_init(&node, &cfg));
    cfg.sdo_timeout_us = 0x80000000u;
    TEST_ASSERT_EQUAL(!CO_CONFIG_TIME32, co_node_init(&node, &cfg));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_heartbeats_keep_their_cadence_for_hours);
    RUN_TEST(test_a_call_hours_late_restarts_the_cadence_from_then);
    RUN_TEST(test_a_clock_gone_back_hours_sends_nothing_early);
    RUN_TEST(test_nothing_pending_is_never_across_epochs);
    RUN_TEST(test_life_guarding_of_four_and_a_half_hours);
    RUN_TEST(test_life_guarding_deadline_is_met_by_sleeping_on_the_answer);
    RUN_TEST(test_sync_producer_with_the_longest_period);
    RUN_TEST(test_sync_window_longer_than_2_pow_31);
    RUN_TEST(test_a_jump_of_2_pow_63);
    RUN_TEST(test_sdo_timeout_across_epoch_moves);
    RUN_TEST(test_sdo_timeout_limit);
    return UNITY_END();
}
