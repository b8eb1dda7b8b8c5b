/* The core built as a generic CiA 301 slave (every behaviour switch of include/canopen/config.h
 * off, as boards/cortex-m4 builds its bench and vf_s15 firmwares): what it refuses, and that its
 * 32-bit limit checks decide as the 64-bit ones do for every limited object of the dictionaries. */
#include <string.h>

#include "canopen/emcy.h"
#include "canopen/node.h"
#include "od_bench.h"
#include "od_benshaw_rsi.h"
#include "od_sourcetronic_st600.h"
#include "od_test.h"
#include "od_test_packed.h"
#include "od_vf_s15_packed.h"
#include "od_vacon_optc6.h"
#include "od_vf_mb1_ecat.h"
#include "od_vf_s15.h"
#include "unity.h"

#if CO_CONFIG_NODE_OPTIONS != 0u || CO_CONFIG_PDO_FLAGS != 0u || CO_CONFIG_PDO_TUNING != 0 || \
    CO_CONFIG_OD_WIDE_LIMITS != 0 || CO_CONFIG_STATS != 0 || CO_CONFIG_EMCY_HOLD != 0 || \
    CO_CONFIG_EMCY_LISTENER != 0
#error "this test is built with every behaviour switch off"
#endif

void setUp(void);
void tearDown(void);
void setUp(void) {}
void tearDown(void) {}

static uint64_t values[8192 / 8];
static co_node node;
static uint32_t sent;
static uint32_t sent_emcy; /* frames on the node's default EMCY CAN-ID, 0x80 + 5 */

static bool send(void *ctx, const co_frame *f)
{
    (void)ctx;
    sent++;
    if (f->id == 0x85u) {
        sent_emcy++;
    }
    return true;
}

static co_node_config config(const co_od *od)
{
    co_node_config cfg = co_node_default_config();
    cfg.od = od;
    cfg.values = (uint8_t *)values;
    cfg.node_id = 5;
    cfg.driver.send = send;
    return cfg;
}

static const co_od *const drive_ods[] = {&co_od_bench, &co_od_vf_s15, &co_od_benshaw_rsi,
                                         &co_od_sourcetronic_st600, &co_od_vacon_optc6,
                                         &co_od_vf_mb1_ecat};
#define DRIVE_ODS (sizeof drive_ods / sizeof drive_ods[0])

/* A limit on a REAL or an integer wider than 32 bits. */
static bool has_wide_limits(const co_od *od)
{
    for (uint32_t e = 0; e < od->entry_count; e++) {
        for (uint32_t i = 0; i < od->entries[e].sub_count; i++) {
            const co_od_sub *s = &od->entries[e].subs[i];
            if ((s->flags & CO_OD_LIMITS) != 0u &&
                (s->size > 4u || s->type == CO_REAL32 || s->type == CO_REAL64)) {
                return true;
            }
        }
    }
    return false;
}

static void test_every_drive_dictionary_is_accepted(void)
{
    for (uint32_t i = 0; i < DRIVE_ODS; i++) {
        TEST_ASSERT_FALSE(has_wide_limits(drive_ods[i]));
        co_node_config cfg = config(drive_ods[i]);
        TEST_ASSERT_TRUE(co_node_init(&node, &cfg));
    }
}

static void test_a_dictionary_with_wide_limits_is_refused(void)
{
    TEST_ASSERT_TRUE(has_wide_limits(&co_od_test)); /* REAL32/REAL64/64-bit limits */
    co_node_config cfg = config(&co_od_test);
    TEST_ASSERT_FALSE(co_node_init(&node, &cfg));
}

static void test_behaviours_left_out_are_refused(void)
{
    co_node_config cfg = config(&co_od_vf_s15);
    cfg.options = CO_NODE_GUARD_TOGGLE_FIRST_SET;
    TEST_ASSERT_FALSE(co_node_init(&node, &cfg));
    cfg = config(&co_od_vf_s15);
    cfg.pdo.flags = CO_PDO_TPDO_SEND_ON_START;
    TEST_ASSERT_FALSE(co_node_init(&node, &cfg));
    cfg = config(&co_od_vf_s15);
    cfg.pdo.tpdo_inhibit_unit_us = 1000u;
    TEST_ASSERT_FALSE(co_node_init(&node, &cfg));
    cfg = config(&co_od_vf_s15);
    cfg.pdo.tpdo_event_min_us = 1000u;
    TEST_ASSERT_FALSE(co_node_init(&node, &cfg));
    cfg = config(&co_od_vf_s15);
    cfg.pdo.value_abort = CO_ABORT_VALUE_RANGE;
    TEST_ASSERT_FALSE(co_node_init(&node, &cfg));
    cfg = config(&co_od_vf_s15);
    cfg.pdo.rpdo_dummy_mask = 0xFEu; /* dummies are CiA 301, not a drive quirk: kept */
    TEST_ASSERT_TRUE(co_node_init(&node, &cfg));
}

/* What the 64-bit check says about value v (sign-extended for signed types) of sub s. */
static co_abort expected(const co_od *od, const co_od_sub *s, uint64_t v)
{
    const co_od_limit *lim = &od->limits[s->limit];
    uint64_t flip = co_type_is_signed(s->type) ? 0x8000000000000000u : 0u;
    if ((v ^ flip) > (lim->high ^ flip)) {
        return CO_ABORT_VALUE_TOO_HIGH;
    }
    if ((v ^ flip) < (lim->low ^ flip)) {
        return CO_ABORT_VALUE_TOO_LOW;
    }
    return CO_ABORT_NONE;
}

/* v truncated to the sub's size and sign-extended back: the value its bytes hold. */
static uint64_t in_type(const co_od_sub *s, uint64_t v)
{
    uint32_t bits = s->size * 8u;
    uint64_t mask = bits >= 64u ? ~(uint64_t)0 : (((uint64_t)1 << bits) - 1u);
    v &= mask;
    if (co_type_is_signed(s->type) && bits < 64u && ((v >> (bits - 1u)) & 1u) != 0u) {
        v |= ~mask;
    }
    return v;
}

static void test_narrow_limit_checks_match_the_wide_ones(void)
{
    uint32_t checked = 0;
    for (uint32_t d = 0; d < DRIVE_ODS; d++) {
        const co_od *od = drive_ods[d];
        for (uint32_t e = 0; e < od->entry_count; e++) {
            for (uint32_t i = 0; i < od->entries[e].sub_count; i++) {
                const co_od_sub *s = &od->entries[e].subs[i];
                if ((s->flags & CO_OD_LIMITS) == 0u) {
                    continue;
                }
                const co_od_limit *lim = &od->limits[s->limit];
                const uint64_t probes[] = {lim->low - 1u, lim->low, lim->low + 1u, lim->high - 1u,
                                           lim->high, lim->high + 1u, 0u, 1u, ~(uint64_t)0,
                                           0x7Fu, 0x80u, 0x7FFFu, 0x8000u, 0xFFFFu,
                                           0x7FFFFFFFu, 0x80000000u, 0xFFFFFFFFu};
                co_od_ref ref = {&od->entries[e], s};
                for (uint32_t p = 0; p < sizeof probes / sizeof probes[0]; p++) {
                    uint64_t v = in_type(s, probes[p]);
                    uint8_t data[8];
                    for (uint32_t b = 0; b < 8u; b++) {
                        data[b] = (uint8_t)(v >> (8u * b));
                    }
                    if (s->type == CO_BOOLEAN && data[0] > 1u) {
                        continue; /* refused by the type check before any limit */
                    }
                    TEST_ASSERT_EQUAL_HEX32(expected(od, s, v),
                                            co_od_check_value(od, ref, data, s->size));
                    checked++;
                }
            }
        }
    }
    TEST_ASSERT_GREATER_THAN_UINT32(100u, checked);
}

/* The generic node still does its job: boot-up, an expedited SDO upload, a TPDO inhibit time in
 * CiA 301's 100 µs. */
static void test_generic_node_answers_sdo(void)
{
    co_node_config cfg = config(&co_od_bench);
    TEST_ASSERT_TRUE(co_node_init(&node, &cfg));
    sent = 0;
    co_node_start(&node, 0);
    TEST_ASSERT_EQUAL_UINT32(1u, sent);
    co_frame f = {0x605u, 8u, 0u, {0x40u, 0x18u, 0x10u, 0x01u, 0u, 0u, 0u, 0u}};
    co_node_rx(&node, &f, 10);
    TEST_ASSERT_EQUAL_UINT32(2u, sent);
    co_frame w = {0x605u, 8u, 0u, {0x2Bu, 0x00u, 0x18u, 0x03u, 30u, 0u, 0u, 0u}};
    co_node_rx(&node, &w, 20); /* TPDO1 inhibit time 30 x 100 µs (the PDO is not valid) */
    TEST_ASSERT_EQUAL_UINT32(3u, sent);
    TEST_ASSERT_EQUAL_UINT32(3000u, node.pdo.tpdo[0].inhibit_us);
    co_frame bad = {0x605u, 7u, 0u, {0x40u, 0x18u, 0x10u, 0x01u, 0u, 0u, 0u, 0u}};
    co_node_rx(&node, &bad, 30); /* dropped (DLC 7), not counted: no counters in this build */
    TEST_ASSERT_EQUAL_UINT32(3u, sent);
    TEST_ASSERT_EQUAL_UINT32(0u, node.stats.rx_malformed);
    TEST_ASSERT_EQUAL_UINT32(0u, node.stats.rx_frames);
    TEST_ASSERT_EQUAL_UINT32(0u, node.stats.tx_frames);
}

/* Without CO_CONFIG_EMCY_HOLD, an EMCY raised in STOPPED updates 0x1001 but its frame is never
 * sent, not even once the node is back in PRE-OPERATIONAL; one raised there goes out at once. */
static void test_emcy_raised_in_stopped_is_not_sent_later(void)
{
    co_node_config cfg = config(&co_od_bench);
    TEST_ASSERT_TRUE(co_node_init(&node, &cfg));
    co_node_start(&node, 0);
    co_frame stop = {0x000u, 2u, 0u, {0x02u, 5u}};
    co_node_rx(&node, &stop, 10);
    TEST_ASSERT_EQUAL(CO_NMT_STOPPED, node.nmt_state);
    sent_emcy = 0;
    (void)co_emcy_raise(&node, 0x5000u, CO_ERR_REG_MANUFACTURER, NULL);
    TEST_ASSERT_EQUAL_HEX8(CO_ERR_REG_GENERIC | CO_ERR_REG_MANUFACTURER,
                           co_emcy_error_register(&node));
    co_frame preop = {0x000u, 2u, 0u, {0x80u, 5u}};
    co_node_rx(&node, &preop, 20);
    TEST_ASSERT_EQUAL(CO_NMT_PRE_OPERATIONAL, node.nmt_state);
    (void)co_node_process(&node, 30);
    (void)co_node_process(&node, 10000000);
    TEST_ASSERT_EQUAL_UINT32(0u, sent_emcy);
    (void)co_emcy_raise(&node, 0x5001u, CO_ERR_REG_MANUFACTURER, NULL);
    (void)co_node_process(&node, 10000010);
    TEST_ASSERT_EQUAL_UINT32(1u, sent_emcy);
}

/* A dictionary whose defaults are packed (eds2c --packed-defaults) gives the same default bytes
 * as the whole block, for every range, and a node the same values at start. */
static void check_packed(const co_od *dense, const co_od *packed)
{
    TEST_ASSERT_NOT_NULL(dense->defaults);
    TEST_ASSERT_NULL(packed->defaults);
    TEST_ASSERT_NOT_NULL(packed->packed_defaults);
    TEST_ASSERT_EQUAL_UINT32(dense->value_size, packed->value_size);
    static uint8_t a[8192], b[8192];
    uint32_t size = dense->value_size;
    for (uint32_t off = 0; off < size; off += 1u + off / 16u) {
        for (uint32_t len = 1; off + len <= size && len < 70u; len += 1u + len / 8u) {
            memset(a, 0xA5, sizeof a);
            memset(b, 0x5A, sizeof b);
            co_od_default_copy(dense, a, off, len);
            co_od_default_copy(packed, b, off, len);
            TEST_ASSERT_EQUAL_MEMORY(a, b, len);
            TEST_ASSERT_EQUAL_HEX8(0x5Au, b[len]); /* nothing written beyond the range */
        }
    }
    co_od_default_copy(dense, a, 0u, size);
    co_od_default_copy(packed, b, 0u, size);
    TEST_ASSERT_EQUAL_MEMORY(a, b, size);
}

static void test_packed_defaults_read_as_the_whole_block(void)
{
    check_packed(&co_od_vf_s15, &co_od_vf_s15_packed);
    check_packed(&co_od_test, &co_od_test_packed);
    static uint64_t other[8192 / 8];
    co_node_config cfg = config(&co_od_vf_s15);
    TEST_ASSERT_TRUE(co_node_init(&node, &cfg));
    memcpy(other, values, sizeof other);
    cfg = config(&co_od_vf_s15_packed);
    TEST_ASSERT_TRUE(co_node_init(&node, &cfg));
    TEST_ASSERT_EQUAL_MEMORY(other, values, co_od_vf_s15.value_size);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_every_drive_dictionary_is_accepted);
    RUN_TEST(test_a_dictionary_with_wide_limits_is_refused);
    RUN_TEST(test_behaviours_left_out_are_refused);
    RUN_TEST(test_narrow_limit_checks_match_the_wide_ones);
    RUN_TEST(test_generic_node_answers_sdo);
    RUN_TEST(test_packed_defaults_read_as_the_whole_block);
    RUN_TEST(test_emcy_raised_in_stopped_is_not_sent_later);
    return UNITY_END();
}
