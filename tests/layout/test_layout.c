/* co_node_init() refuses a caller built with other layout switches or sizes than the library
 * (CO_LAYOUT_SIGNATURE, include/canopen/node.h), writes nothing into its node, and
 * co_layout_mismatch() names the switch. Each layout_* function is a file of its own, compiled
 * with one switch changed (tests/layout/CMakeLists.txt); this file and the library use the
 * preset's switches. */
#include <string.h>

#include "canopen/node.h"
#include "layout_alt.h"
#include "od_test.h"
#include "unity.h"

static uint64_t values[(CO_OD_TEST_VALUE_SIZE + 7u) / 8u];
static co_node_config cfg;

static bool send_any(void *ctx, const co_frame *frame)
{
    (void)ctx;
    (void)frame;
    return true;
}

void setUp(void)
{
    cfg = co_node_default_config();
    cfg.od = &co_od_test;
    cfg.values = (uint8_t *)values;
    cfg.node_id = 5;
    cfg.driver.send = send_any;
}

void tearDown(void)
{
}

/* The same config is accepted from a file with the library's layout: the refusals below are the
 * layout's, not the config's. */
static void test_same_layout_accepted(void)
{
    static co_node node;
    TEST_ASSERT_TRUE(co_node_init(&node, &cfg));
    TEST_ASSERT_NULL(co_layout_mismatch(CO_LAYOUT_SIGNATURE));
    layout_alt_result r = layout_same(&cfg);
    TEST_ASSERT_TRUE(r.accepted);
    TEST_ASSERT_NULL(r.reason);
}

static void check_refused(layout_alt_result r, const char *switch_name)
{
    TEST_ASSERT_FALSE(r.accepted);
    TEST_ASSERT_TRUE(r.untouched);
    TEST_ASSERT_NOT_NULL(r.reason);
    TEST_ASSERT_NOT_NULL_MESSAGE(strstr(r.reason, switch_name), r.reason);
}

static void test_time32_refused(void)
{
    check_refused(layout_time32(&cfg), "CO_CONFIG_TIME32");
}

static void test_od_compact_refused(void)
{
    check_refused(layout_compact(&cfg), "CO_CONFIG_OD_COMPACT");
}

static void test_pdo_bits_refused(void)
{
    check_refused(layout_pdo_bits(&cfg), "CO_CONFIG_PDO_BITS");
}

static void test_sizes_refused(void)
{
    check_refused(layout_tx_queue(&cfg), "sizes");
    check_refused(layout_hb_consumers(&cfg), "sizes");
}

/* The switch set in a user header (CO_CONFIG_USER_HEADER) counts as one given with -D. */
static void test_user_header_refused(void)
{
    check_refused(layout_user_header(&cfg), "CO_CONFIG_TIME32");
}

/* A signature that differs in any bit is refused by co_node_init_layout itself. */
static void test_any_bit_refused(void)
{
    static co_node node;
    for (uint32_t bit = 0; bit < 32u; bit++) {
        TEST_ASSERT_FALSE(co_node_init_layout(&node, &cfg, CO_LAYOUT_SIGNATURE ^ (1u << bit)));
        TEST_ASSERT_NOT_NULL(co_layout_mismatch(CO_LAYOUT_SIGNATURE ^ (1u << bit)));
    }
    TEST_ASSERT_TRUE(co_node_init_layout(&node, &cfg, CO_LAYOUT_SIGNATURE));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_same_layout_accepted);
    RUN_TEST(test_time32_refused);
    RUN_TEST(test_od_compact_refused);
    RUN_TEST(test_pdo_bits_refused);
    RUN_TEST(test_sizes_refused);
    RUN_TEST(test_user_header_refused);
    RUN_TEST(test_any_bit_refused);
    return UNITY_END();
}
