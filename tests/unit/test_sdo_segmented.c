/* SDO server, segmented transfers: upload and download with and without a size, frames byte for
 * byte, strings, toggle errors, data that does not match the announced size, the timeout on the
 * virtual clock, DOMAIN objects streamed through their hook, and objects beyond the buffer. */
#include <string.h>

#include "canopen/sdo_server.h"
#include "od_test.h"
#include "test_domain.h"
#include "test_support.h"
#include "unity.h"

#define RX 0x605u
#define TX 0x585u

static test_node t;

static test_domain dom; /* the DOMAIN hook on 0x2010 */

void setUp(void)
{
    test_node_start(&t, 5);
    fake_bus_clear(&t.bus);
    test_domain_reset(&dom);
}

void tearDown(void) {}

/* --- frames ----------------------------------------------------------------------------------- */

static void set_string(uint16_t index, const char *s)
{
    TEST_ASSERT_EQUAL_HEX32(0, co_od_write(&t.node, index, 0, (const uint8_t *)s,
                                           (uint32_t)strlen(s), CO_ORIGIN_APP));
}

/* --- a segmented client ----------------------------------------------------------------------- */

/* Abort code of an abort frame, or fails the test if f is something else. */
static uint32_t abort_code(const co_frame *f)
{
    TEST_ASSERT_EQUAL_HEX8(0x80, f->data[0]);
    return co_get_le32(&f->data[4]);
}

static const co_frame *response(void)
{
    const co_frame *f = fake_bus_next(&t.bus);
    TEST_ASSERT_NOT_NULL_MESSAGE(f, "no SDO response");
    TEST_ASSERT_EQUAL_HEX16(TX, f->id);
    TEST_ASSERT_EQUAL_UINT8(8, f->dlc);
    return f;
}

/* Writes len bytes with a segmented download and checks every response byte for byte. Returns the
 * abort code (0 when the transfer completed). */
static uint32_t download(uint16_t index, uint8_t sub, const uint8_t *data, uint32_t len,
                         bool size_indicated)
{
    sdo_req(&t, size_indicated ? 0x21 : 0x20, (uint8_t)index, (uint8_t)(index >> 8), sub,
        size_indicated ? (uint8_t)len : 0, size_indicated ? (uint8_t)(len >> 8) : 0,
        size_indicated ? (uint8_t)(len >> 16) : 0, size_indicated ? (uint8_t)(len >> 24) : 0);
    const co_frame *f = response();
    if (f->data[0] == 0x80u) {
        return abort_code(f);
    }
    const uint8_t init[8] = {0x60, (uint8_t)index, (uint8_t)(index >> 8), sub, 0, 0, 0, 0};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(init, f->data, 8);
    uint32_t pos = 0;
    uint8_t toggle = 0;
    bool last;
    do {
        uint32_t n = len - pos < 7u ? len - pos : 7u;
        last = pos + n >= len;
        uint8_t seg[8] = {(uint8_t)((toggle << 4) | ((7u - n) << 1) | (last ? 1u : 0u))};
        memcpy(&seg[1], &data[pos], n);
        test_rx(&t, RX, 8, seg);
        f = response();
        if (f->data[0] == 0x80u) {
            return abort_code(f);
        }
        const uint8_t ack[8] = {(uint8_t)(0x20u | (toggle << 4)), 0, 0, 0, 0, 0, 0, 0};
        TEST_ASSERT_EQUAL_HEX8_ARRAY(ack, f->data, 8);
        pos += n;
        toggle ^= 1u;
    } while (!last);
    expect_no_frame(&t);
    return 0;
}

/* Reads with a segmented upload into buf; checks the frames' form. Returns the abort code. */
static uint32_t upload(uint16_t index, uint8_t sub, uint8_t *buf, uint32_t cap, uint32_t *len)
{
    sdo_req(&t, 0x40, (uint8_t)index, (uint8_t)(index >> 8), sub, 0, 0, 0, 0);
    const co_frame *f = response();
    if (f->data[0] == 0x80u) {
        return abort_code(f);
    }
    TEST_ASSERT_EQUAL_HEX16(index, co_get_le16(&f->data[1]));
    TEST_ASSERT_EQUAL_HEX8(sub, f->data[3]);
    if ((f->data[0] & 0x02u) != 0u) { /* expedited */
        TEST_ASSERT_EQUAL_HEX8(0x43, f->data[0] & 0xF3u);
        *len = 4u - ((f->data[0] >> 2) & 3u);
        memcpy(buf, &f->data[4], *len);
        return 0;
    }
    TEST_ASSERT_EQUAL_HEX8(0x41, f->data[0]);
    uint32_t size = co_get_le32(&f->data[4]);
    uint32_t pos = 0;
    uint8_t toggle = 0;
    for (;;) {
        sdo_req(&t, (uint8_t)(0x60u | (toggle << 4)), 0, 0, 0, 0, 0, 0, 0);
        f = response();
        if (f->data[0] == 0x80u) {
            return abort_code(f);
        }
        TEST_ASSERT_EQUAL_HEX8(toggle << 4, f->data[0] & 0xF0u);
        uint32_t n = 7u - ((f->data[0] >> 1) & 7u);
        TEST_ASSERT_TRUE(pos + n <= cap);
        memcpy(&buf[pos], &f->data[1], n);
        for (uint32_t i = 1u + n; i < 8u; i++) {
            TEST_ASSERT_EQUAL_HEX8(0, f->data[i]); /* unused bytes are 0 */
        }
        pos += n;
        toggle ^= 1u;
        if ((f->data[0] & 0x01u) != 0u) {
            break;
        }
    }
    TEST_ASSERT_EQUAL_UINT32(size, pos);
    expect_no_frame(&t);
    *len = pos;
    return 0;
}

static uint8_t big[4000];

static const uint8_t *pattern_data(uint32_t len)
{
    TEST_ASSERT_TRUE(len <= sizeof big);
    for (uint32_t i = 0; i < len; i++) {
        big[i] = test_domain_pattern(i);
    }
    return big;
}

/* --- upload ----------------------------------------------------------------------------------- */

static void test_upload_u64_frames_byte_for_byte(void)
{
    sdo_req(&t, 0x40, 0x0A, 0x20, 0x00, 0, 0, 0, 0); /* 0x0123456789ABCDEF */
    sdo_expect(&t, 0x41, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    sdo_req(&t, 0x60, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0x00, 0xEF, 0xCD, 0xAB, 0x89, 0x67, 0x45, 0x23);
    sdo_req(&t, 0x70, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0x1D, 0x01, 0, 0, 0, 0, 0, 0); /* toggle 1, 6 bytes unused, last */
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
}

static void test_upload_string_frames_byte_for_byte(void)
{
    sdo_req(&t, 0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0); /* "canopen-test" */
    sdo_expect(&t, 0x41, 0x08, 0x10, 0x00, 12, 0, 0, 0);
    sdo_req(&t, 0x60, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0x00, 'c', 'a', 'n', 'o', 'p', 'e', 'n');
    sdo_req(&t, 0x70, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0x15, '-', 't', 'e', 's', 't', 0, 0); /* toggle 1, 2 unused, last */
    expect_no_frame(&t);
}

static void test_upload_of_exactly_one_full_segment(void)
{
    set_string(0x200D, "abcdefg");
    sdo_req(&t, 0x40, 0x0D, 0x20, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x41, 0x0D, 0x20, 0x00, 7, 0, 0, 0);
    sdo_req(&t, 0x60, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0x01, 'a', 'b', 'c', 'd', 'e', 'f', 'g');
    expect_no_frame(&t);
}

static void test_upload_of_two_full_segments(void)
{
    set_string(0x200D, "abcdefghijklmn");
    sdo_req(&t, 0x40, 0x0D, 0x20, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x41, 0x0D, 0x20, 0x00, 14, 0, 0, 0);
    sdo_req(&t, 0x60, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0x00, 'a', 'b', 'c', 'd', 'e', 'f', 'g');
    sdo_req(&t, 0x70, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0x11, 'h', 'i', 'j', 'k', 'l', 'm', 'n');
    expect_no_frame(&t);
}

static void test_upload_of_an_empty_string(void)
{
    set_string(0x200D, "");
    sdo_req(&t, 0x40, 0x0D, 0x20, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x41, 0x0D, 0x20, 0x00, 0, 0, 0, 0);
    sdo_req(&t, 0x60, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0x0F, 0, 0, 0, 0, 0, 0, 0); /* 7 bytes unused, last */
    expect_no_frame(&t);
}

static void test_upload_of_a_full_capacity_string(void)
{
    char s[33];
    for (int i = 0; i < 32; i++) {
        s[i] = (char)('A' + i % 26);
    }
    s[32] = '\0';
    set_string(0x200D, s);
    uint8_t buf[64];
    uint32_t len = 0;
    TEST_ASSERT_EQUAL_HEX32(0, upload(0x200D, 0, buf, sizeof buf, &len));
    TEST_ASSERT_EQUAL_UINT32(32, len);
    TEST_ASSERT_EQUAL_MEMORY(s, buf, 32);
}

static void test_upload_toggle_error_aborts_0x05030000(void)
{
    sdo_req(&t, 0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x41, 0x08, 0x10, 0x00, 12, 0, 0, 0);
    sdo_req(&t, 0x70, 0, 0, 0, 0, 0, 0, 0); /* first request must have toggle 0 */
    sdo_expect_abort(&t, 0x1008, 0, CO_ABORT_TOGGLE);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
}

static void test_upload_repeated_toggle_aborts_0x05030000(void)
{
    sdo_req(&t, 0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x41, 0x08, 0x10, 0x00, 12, 0, 0, 0);
    sdo_req(&t, 0x60, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0x00, 'c', 'a', 'n', 'o', 'p', 'e', 'n');
    sdo_req(&t, 0x60, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect_abort(&t, 0x1008, 0, CO_ABORT_TOGGLE);
}

static void test_upload_request_after_the_last_segment_aborts_0x05040001(void)
{
    sdo_req(&t, 0x40, 0x0A, 0x20, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x41, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    sdo_req(&t, 0x60, 0, 0, 0, 0, 0, 0, 0);
    (void)response();
    sdo_req(&t, 0x70, 0, 0, 0, 0, 0, 0, 0);
    (void)response();
    sdo_req(&t, 0x60, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_COMMAND);
}

/* --- download --------------------------------------------------------------------------------- */

static void test_download_u64_with_size_frames_byte_for_byte(void)
{
    sdo_req(&t, 0x21, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    sdo_expect(&t, 0x60, 0x0A, 0x20, 0x00, 0, 0, 0, 0);
    sdo_req(&t, 0x00, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77);
    sdo_expect(&t, 0x20, 0, 0, 0, 0, 0, 0, 0);
    /* nothing written before the end */
    TEST_ASSERT_EQUAL_HEX8(0xEF, test_value_of(&t, 0x200A, 0)[0]);
    sdo_req(&t, 0x1D, 0x88, 0xAA, 0xAA, 0xAA, 0xAA, 0xAA, 0xAA);
    sdo_expect(&t, 0x30, 0, 0, 0, 0, 0, 0, 0);
    expect_no_frame(&t);
    const uint8_t want[8] = {0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88};
    TEST_ASSERT_EQUAL_MEMORY(want, test_value_of(&t, 0x200A, 0), 8);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
}

static void test_download_u64_without_size(void)
{
    const uint8_t data[8] = {8, 7, 6, 5, 4, 3, 2, 1};
    TEST_ASSERT_EQUAL_HEX32(0, download(0x200A, 0, data, 8, false));
    TEST_ASSERT_EQUAL_MEMORY(data, test_value_of(&t, 0x200A, 0), 8);
}

static void test_download_of_a_small_value_segmented(void)
{
    const uint8_t data[2] = {0xE8, 0x03}; /* a client may segment anything: 1000 into 0x2022 */
    TEST_ASSERT_EQUAL_HEX32(0, download(0x2022, 0, data, 2, true));
    TEST_ASSERT_EQUAL_UINT16(1000, co_od_get_u16(&t.node, 0x2022, 0));
}

static void test_download_string_with_size(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, download(0x200D, 0, (const uint8_t *)"hello world!", 12, true));
    TEST_ASSERT_EQUAL_MEMORY("hello world!\0", test_value_of(&t, 0x200D, 0), 13);
}

static void test_download_string_without_size(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, download(0x200D, 0, (const uint8_t *)"a longer string of 28 bytes.",
                                        28, false));
    TEST_ASSERT_EQUAL_MEMORY("a longer string of 28 bytes.\0", test_value_of(&t, 0x200D, 0), 29);
}

static void test_download_string_of_full_capacity(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, download(0x200E, 0, (const uint8_t *)"0123456789abcdef", 16, false));
    TEST_ASSERT_EQUAL_MEMORY("0123456789abcdef", test_value_of(&t, 0x200E, 0), 16);
    uint8_t buf[32];
    uint32_t len = 0;
    TEST_ASSERT_EQUAL_HEX32(0, upload(0x200E, 0, buf, sizeof buf, &len));
    TEST_ASSERT_EQUAL_UINT32(16, len);
}

static void test_download_string_into_a_record(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, download(0x2040, 4, (const uint8_t *)"record string", 13, true));
    TEST_ASSERT_EQUAL_MEMORY("record string", test_value_of(&t, 0x2040, 4), 13);
}

static void test_download_toggle_error_aborts_0x05030000(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x21, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    sdo_expect(&t, 0x60, 0x0A, 0x20, 0x00, 0, 0, 0, 0);
    sdo_req(&t, 0x10, 1, 2, 3, 4, 5, 6, 7); /* first segment with toggle 1 */
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_TOGGLE);
    test_expect_values_unchanged(&t);
}

static void test_download_repeated_toggle_aborts_0x05030000(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x21, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    sdo_expect(&t, 0x60, 0x0A, 0x20, 0x00, 0, 0, 0, 0);
    sdo_req(&t, 0x00, 1, 2, 3, 4, 5, 6, 7);
    sdo_expect(&t, 0x20, 0, 0, 0, 0, 0, 0, 0);
    sdo_req(&t, 0x0D, 8, 0, 0, 0, 0, 0, 0); /* toggle 0 again on the last segment */
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_TOGGLE);
    test_expect_values_unchanged(&t);
    sdo_req(&t, 0x1D, 8, 0, 0, 0, 0, 0, 0); /* the transfer is over */
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_COMMAND);
    test_expect_values_unchanged(&t);
}

static void test_download_more_than_announced_aborts_0x06070010(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x21, 0x0D, 0x20, 0x00, 5, 0, 0, 0);
    sdo_expect(&t, 0x60, 0x0D, 0x20, 0x00, 0, 0, 0, 0);
    sdo_req(&t, 0x03, 'a', 'b', 'c', 'd', 'e', 'f', 0); /* 6 bytes, last */
    sdo_expect_abort(&t, 0x200D, 0, CO_ABORT_TYPE_LENGTH);
    test_expect_values_unchanged(&t);
}

static void test_download_less_than_announced_aborts_0x06070010(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x21, 0x0D, 0x20, 0x00, 10, 0, 0, 0);
    sdo_expect(&t, 0x60, 0x0D, 0x20, 0x00, 0, 0, 0, 0);
    sdo_req(&t, 0x00, 'a', 'b', 'c', 'd', 'e', 'f', 'g');
    sdo_expect(&t, 0x20, 0, 0, 0, 0, 0, 0, 0);
    sdo_req(&t, 0x1B, 'h', 'i', 0, 0, 0, 0, 0); /* 2 bytes, last: 9 of 10 */
    sdo_expect_abort(&t, 0x200D, 0, CO_ABORT_TYPE_LENGTH);
    test_expect_values_unchanged(&t);
}

static void test_download_beyond_string_capacity_aborts_0x06070012(void)
{
    test_values_snapshot(&t);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_TYPE_TOO_LONG,
                            download(0x200E, 0, (const uint8_t *)"0123456789abcdefg", 17, false));
    test_expect_values_unchanged(&t);
}

static void test_download_octet_string_too_long_aborts_0x06070012(void)
{
    test_values_snapshot(&t);
    const uint8_t data[5] = {1, 2, 3, 4, 5};
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_TYPE_TOO_LONG, download(0x200F, 0, data, 5, false));
    test_expect_values_unchanged(&t);
}

static void test_download_too_short_for_the_type_aborts_0x06070013(void)
{
    test_values_snapshot(&t);
    const uint8_t data[5] = {1, 2, 3, 4, 5};
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_TYPE_TOO_SHORT, download(0x200A, 0, data, 5, false));
    test_expect_values_unchanged(&t);
}

static void test_download_out_of_range_aborts_at_the_end_0x06090031(void)
{
    test_values_snapshot(&t);
    const uint8_t data[3] = {0x40, 0x0D, 0x03}; /* 200000 into INTEGER24 -100000..100000 */
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_HIGH, download(0x2003, 0, data, 3, true));
    test_expect_values_unchanged(&t);
}

static void test_download_segment_without_data_is_accepted(void)
{
    sdo_req(&t, 0x20, 0x0D, 0x20, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x60, 0x0D, 0x20, 0x00, 0, 0, 0, 0);
    sdo_req(&t, 0x00, 'a', 'b', 'c', 'd', 'e', 'f', 'g');
    sdo_expect(&t, 0x20, 0, 0, 0, 0, 0, 0, 0);
    sdo_req(&t, 0x1F, 'x', 'x', 'x', 'x', 'x', 'x', 'x'); /* n = 7: no data, last */
    sdo_expect(&t, 0x30, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_MEMORY("abcdefg\0", test_value_of(&t, 0x200D, 0), 8);
}

static void test_download_then_upload_round_trip(void)
{
    const uint8_t *data = (const uint8_t *)"round trip through both directions"; /* 34 > 32 */
    TEST_ASSERT_EQUAL_HEX32(0, download(0x200D, 0, data, 32, true));
    uint8_t buf[40];
    uint32_t len = 0;
    TEST_ASSERT_EQUAL_HEX32(0, upload(0x200D, 0, buf, sizeof buf, &len));
    TEST_ASSERT_EQUAL_UINT32(32, len);
    TEST_ASSERT_EQUAL_MEMORY(data, buf, 32);
}

/* --- timeout ---------------------------------------------------------------------------------- */

static void test_download_timeout_just_before_and_at_the_deadline(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0x21, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    sdo_expect(&t, 0x60, 0x0A, 0x20, 0x00, 0, 0, 0, 0);
    sdo_req(&t, 0x00, 1, 2, 3, 4, 5, 6, 7);
    sdo_expect(&t, 0x20, 0, 0, 0, 0, 0, 0, 0);
    uint64_t deadline = t.now + CO_SDO_TIMEOUT_US;
    TEST_ASSERT_EQUAL_UINT64(deadline, test_advance(&t, CO_SDO_TIMEOUT_US - 1u));
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT64(CO_TIME_NEVER, test_advance(&t, 1));
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_TIMEOUT);
    test_expect_values_unchanged(&t);
    sdo_req(&t, 0x1D, 8, 0, 0, 0, 0, 0, 0); /* too late */
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_COMMAND);
    test_expect_values_unchanged(&t);
}

static void test_upload_timeout_just_before_and_at_the_deadline(void)
{
    sdo_req(&t, 0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x41, 0x08, 0x10, 0x00, 12, 0, 0, 0);
    test_advance(&t, CO_SDO_TIMEOUT_US - 1u);
    expect_no_frame(&t);
    test_advance(&t, 1);
    sdo_expect_abort(&t, 0x1008, 0, CO_ABORT_TIMEOUT);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
}

static void test_each_segment_restarts_the_timeout(void)
{
    sdo_req(&t, 0x20, 0x0D, 0x20, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x60, 0x0D, 0x20, 0x00, 0, 0, 0, 0);
    test_advance(&t, CO_SDO_TIMEOUT_US - 1u);
    sdo_req(&t, 0x00, 'a', 'b', 'c', 'd', 'e', 'f', 'g');
    sdo_expect(&t, 0x20, 0, 0, 0, 0, 0, 0, 0);
    test_advance(&t, CO_SDO_TIMEOUT_US - 1u);
    expect_no_frame(&t);
    sdo_req(&t, 0x17, 'h', 0, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0x30, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_MEMORY("abcdefgh\0", test_value_of(&t, 0x200D, 0), 9);
    TEST_ASSERT_EQUAL_UINT64(CO_TIME_NEVER, test_advance(&t, 10u * CO_SDO_TIMEOUT_US));
    expect_no_frame(&t);
}

static void test_configured_timeout_is_used(void)
{
    t.node.sdo.timeout_us = 5000;
    sdo_req(&t, 0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x41, 0x08, 0x10, 0x00, 12, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT64(t.now + 5000u, co_node_process(&t.node, t.now));
    test_advance(&t, 4999);
    expect_no_frame(&t);
    test_advance(&t, 1);
    sdo_expect_abort(&t, 0x1008, 0, CO_ABORT_TIMEOUT);
}

static void test_late_process_call_still_times_out(void)
{
    sdo_req(&t, 0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x41, 0x08, 0x10, 0x00, 12, 0, 0, 0);
    test_advance(&t, 50u * CO_SDO_TIMEOUT_US);
    sdo_expect_abort(&t, 0x1008, 0, CO_ABORT_TIMEOUT);
}

/* --- DOMAIN ----------------------------------------------------------------------------------- */

static void test_domain_download_without_size_streams_in_pieces(void)
{
    test_domain_add_hook(&t, &dom);
    TEST_ASSERT_EQUAL_HEX32(0, download(0x2010, 0, pattern_data(2000), 2000, false));
    TEST_ASSERT_EQUAL_UINT32(2000, dom.received);
    TEST_ASSERT_TRUE(dom.in_order);
    TEST_ASSERT_TRUE(dom.pattern_ok);
    TEST_ASSERT_EQUAL_UINT32(1, dom.last_calls);
    TEST_ASSERT_EQUAL_UINT32(0, dom.total);
    TEST_ASSERT_TRUE(dom.pieces >= 3u);
    TEST_ASSERT_TRUE(dom.largest_piece <= CO_SDO_BUF_SIZE);
}

static void test_domain_download_with_size_passes_the_total(void)
{
    test_domain_add_hook(&t, &dom);
    TEST_ASSERT_EQUAL_HEX32(0, download(0x2010, 0, pattern_data(2000), 2000, true));
    TEST_ASSERT_EQUAL_UINT32(2000, dom.received);
    TEST_ASSERT_EQUAL_UINT32(2000, dom.total);
    TEST_ASSERT_TRUE(dom.pattern_ok);
    TEST_ASSERT_EQUAL_UINT32(1, dom.last_calls);
}

static void test_domain_download_hook_refusal_passes_through(void)
{
    test_domain_add_hook(&t, &dom);
    dom.write_refusal = CO_ABORT_STORE;
    dom.refuse_from = 1000;
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_STORE, download(0x2010, 0, pattern_data(3000), 3000, true));
    TEST_ASSERT_EQUAL_UINT32(0, dom.last_calls);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
}

static void test_domain_download_aborted_by_the_client_never_ends(void)
{
    test_domain_add_hook(&t, &dom);
    sdo_req(&t, 0x20, 0x10, 0x20, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x60, 0x10, 0x20, 0x00, 0, 0, 0, 0);
    uint8_t toggle = 0;
    for (uint32_t pos = 0; pos < 1400u; pos += 7u) {
        uint8_t seg[8] = {(uint8_t)(toggle << 4)};
        for (uint32_t i = 0; i < 7u; i++) {
            seg[1 + i] = test_domain_pattern(pos + i);
        }
        test_rx(&t, RX, 8, seg);
        sdo_expect(&t, 0x20 | (uint8_t)(toggle << 4), 0, 0, 0, 0, 0, 0, 0);
        toggle ^= 1u;
    }
    sdo_req(&t, 0x80, 0x10, 0x20, 0x00, 0, 0, 0, 0x08);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_UINT32(0, dom.last_calls);
    TEST_ASSERT_TRUE(dom.received < 1400u);
}

static void test_domain_download_more_than_announced_aborts_0x06070010(void)
{
    test_domain_add_hook(&t, &dom);
    sdo_req(&t, 0x21, 0x10, 0x20, 0x00, 10, 0, 0, 0);
    sdo_expect(&t, 0x60, 0x10, 0x20, 0x00, 0, 0, 0, 0);
    sdo_req(&t, 0x00, 1, 2, 3, 4, 5, 6, 7);
    sdo_expect(&t, 0x20, 0, 0, 0, 0, 0, 0, 0);
    sdo_req(&t, 0x10, 8, 9, 10, 11, 12, 13, 14);
    sdo_expect_abort(&t, 0x2010, 0, CO_ABORT_TYPE_LENGTH);
    TEST_ASSERT_EQUAL_UINT32(0, dom.last_calls);
}

static void test_domain_expedited_download(void)
{
    test_domain_add_hook(&t, &dom);
    sdo_req(&t, 0x23, 0x10, 0x20, 0x00, test_domain_pattern(0), test_domain_pattern(1), test_domain_pattern(2), test_domain_pattern(3));
    sdo_expect(&t, 0x60, 0x10, 0x20, 0x00, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(4, dom.received);
    TEST_ASSERT_EQUAL_UINT32(1, dom.last_calls);
    TEST_ASSERT_TRUE(dom.pattern_ok);
}

static void test_domain_segmented_upload_in_small_pieces(void)
{
    test_domain_add_hook(&t, &dom);
    dom.source_size = 2000;
    dom.read_piece = 100;
    static uint8_t buf[2100];
    uint32_t len = 0;
    TEST_ASSERT_EQUAL_HEX32(0, upload(0x2010, 0, buf, sizeof buf, &len));
    TEST_ASSERT_EQUAL_UINT32(2000, len);
    TEST_ASSERT_EQUAL_MEMORY(pattern_data(2000), buf, 2000);
}

static void test_domain_segmented_upload_larger_than_the_buffer(void)
{
    test_domain_add_hook(&t, &dom);
    dom.source_size = 3 * CO_SDO_BUF_SIZE + 5u;
    static uint8_t buf[4000];
    uint32_t len = 0;
    TEST_ASSERT_EQUAL_HEX32(0, upload(0x2010, 0, buf, sizeof buf, &len));
    TEST_ASSERT_EQUAL_UINT32(dom.source_size, len);
    TEST_ASSERT_EQUAL_MEMORY(pattern_data(len), buf, len);
}

static void test_domain_small_upload_is_expedited(void)
{
    test_domain_add_hook(&t, &dom);
    dom.source_size = 3;
    sdo_req(&t, 0x40, 0x10, 0x20, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x47, 0x10, 0x20, 0x00, test_domain_pattern(0), test_domain_pattern(1), test_domain_pattern(2), 0);
    expect_no_frame(&t);
}

/* A hook whose first read gives more bytes than the total it announces: only the total goes out. */
static void test_domain_upload_sends_only_the_announced_total(void)
{
    test_domain_add_hook(&t, &dom);
    dom.source_size = 3;
    dom.extra = 20;
    sdo_req(&t, 0x40, 0x10, 0x20, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x47, 0x10, 0x20, 0x00, test_domain_pattern(0), test_domain_pattern(1), test_domain_pattern(2), 0);
    expect_no_frame(&t);
    dom.source_size = 10;
    static uint8_t buf[64];
    uint32_t len = 0;
    TEST_ASSERT_EQUAL_HEX32(0, upload(0x2010, 0, buf, sizeof buf, &len));
    TEST_ASSERT_EQUAL_UINT32(10, len);
    TEST_ASSERT_EQUAL_MEMORY(pattern_data(10), buf, 10);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
}

static void test_domain_empty_upload(void)
{
    test_domain_add_hook(&t, &dom);
    dom.source_size = 0;
    sdo_req(&t, 0x40, 0x10, 0x20, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x41, 0x10, 0x20, 0x00, 0, 0, 0, 0);
    sdo_req(&t, 0x60, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0x0F, 0, 0, 0, 0, 0, 0, 0);
}

static void test_domain_upload_with_less_data_than_announced_aborts_0x08000024(void)
{
    test_domain_add_hook(&t, &dom);
    dom.source_size = 2000;
    dom.dry_from = 1500;
    static uint8_t buf[2100];
    uint32_t len = 0;
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_DATA, upload(0x2010, 0, buf, sizeof buf, &len));
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
}

static void test_domain_upload_hook_refusal_passes_through(void)
{
    test_domain_add_hook(&t, &dom);
    dom.source_size = 100;
    dom.read_refusal = CO_ABORT_LOCAL_CONTROL;
    dom.refuse_read_from = 0;
    sdo_req(&t, 0x40, 0x10, 0x20, 0x00, 0, 0, 0, 0);
    sdo_expect_abort(&t, 0x2010, 0, CO_ABORT_LOCAL_CONTROL);
}

static void test_domain_upload_hook_refusal_midway_passes_through(void)
{
    test_domain_add_hook(&t, &dom);
    dom.source_size = 2000;
    dom.read_refusal = CO_ABORT_STORE;
    dom.refuse_read_from = 1000;
    static uint8_t buf[2100];
    uint32_t len = 0;
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_STORE, upload(0x2010, 0, buf, sizeof buf, &len));
}

/* --- objects beyond the buffer (a dictionary of its own: a 1000-byte string) ------------------ */

static const co_od_sub big_subs[1] = {
    {0u, 1000u, 0u, 0x00u, CO_VISIBLE_STRING, CO_OD_READ | CO_OD_WRITE}};
static const co_od_entry big_entries[1] = {{0x3000u, CO_OBJ_VAR, 1u, 0u, big_subs}};
static const uint8_t big_defaults[1000] = {0};
static const co_od big_od = {"big", big_entries, NULL, big_defaults, 1, 0, 1000, 0, 0, 0, NULL, NULL};

typedef struct big_node {
    co_node node;
    fake_bus bus;
    uint8_t values[1000];
} big_node;

static big_node bn;

static void big_start(void)
{
    memset(&bn, 0, sizeof bn);
    co_node_config cfg = co_node_default_config();
    cfg.od = &big_od;
    cfg.values = bn.values;
    cfg.node_id = 7;
    cfg.driver = fake_bus_driver(&bn.bus);
    TEST_ASSERT_TRUE(co_node_init(&bn.node, &cfg));
    co_node_start(&bn.node, 0);
    fake_bus_clear(&bn.bus);
}

static void big_req(uint8_t b0, uint8_t b1, uint8_t b2, uint8_t b3, uint8_t b4, uint8_t b5,
                    uint8_t b6, uint8_t b7)
{
    co_frame f = {0x607, 8, 0, {b0, b1, b2, b3, b4, b5, b6, b7}};
    co_node_rx(&bn.node, &f, 0);
}

static const co_frame *big_response(void)
{
    const co_frame *f = fake_bus_next(&bn.bus);
    TEST_ASSERT_NOT_NULL(f);
    TEST_ASSERT_EQUAL_HEX16(0x587, f->id);
    return f;
}

static void test_announced_size_beyond_the_buffer_aborts_0x05040005(void)
{
    big_start();
    big_req(0x21, 0x00, 0x30, 0x00, 0x84, 0x03, 0, 0); /* 900 > CO_SDO_BUF_SIZE (889) */
    const co_frame *f = big_response();
    TEST_ASSERT_EQUAL_HEX8(0x80, f->data[0]);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_OUT_OF_MEMORY, co_get_le32(&f->data[4]));
}

/* Sends len bytes of 'x' without a size; returns the code of the first abort (0: none). */
static uint32_t big_download(uint32_t len)
{
    big_req(0x20, 0x00, 0x30, 0x00, 0, 0, 0, 0);
    const co_frame *f = big_response();
    TEST_ASSERT_EQUAL_HEX8(0x60, f->data[0]);
    uint8_t toggle = 0;
    for (uint32_t pos = 0; pos < len; pos += 7u) {
        uint32_t n = len - pos < 7u ? len - pos : 7u;
        bool last = pos + n >= len;
        big_req((uint8_t)((toggle << 4) | ((7u - n) << 1) | (last ? 1u : 0u)), 'x', 'x', 'x', 'x',
                'x', 'x', 'x');
        f = big_response();
        if (f->data[0] == 0x80u) {
            return co_get_le32(&f->data[4]);
        }
        toggle ^= 1u;
    }
    return 0;
}

static void test_download_beyond_the_buffer_aborts_0x05040005(void)
{
    big_start();
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_OUT_OF_MEMORY, big_download(CO_SDO_BUF_SIZE + 1u));
    TEST_ASSERT_EQUAL_HEX8(0, bn.values[0]); /* untouched */
}

static void test_download_filling_the_buffer_exactly_works(void)
{
    big_start();
    TEST_ASSERT_EQUAL_HEX32(0, big_download(CO_SDO_BUF_SIZE));
    TEST_ASSERT_EQUAL_HEX8('x', bn.values[CO_SDO_BUF_SIZE - 1u]);
    TEST_ASSERT_EQUAL_HEX8(0, bn.values[CO_SDO_BUF_SIZE]);
}

static void test_upload_beyond_the_buffer_aborts_0x05040005(void)
{
    big_start();
    memset(bn.values, 'y', 1000); /* a 1000-character string */
    big_req(0x40, 0x00, 0x30, 0x00, 0, 0, 0, 0);
    const co_frame *f = big_response();
    TEST_ASSERT_EQUAL_HEX8(0x80, f->data[0]);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_OUT_OF_MEMORY, co_get_le32(&f->data[4]));
    bn.values[CO_SDO_BUF_SIZE] = 0; /* now it fits */
    big_req(0x40, 0x00, 0x30, 0x00, 0, 0, 0, 0);
    f = big_response();
    TEST_ASSERT_EQUAL_HEX8(0x41, f->data[0]);
    TEST_ASSERT_EQUAL_UINT32(CO_SDO_BUF_SIZE, co_get_le32(&f->data[4]));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_upload_u64_frames_byte_for_byte);
    RUN_TEST(test_upload_string_frames_byte_for_byte);
    RUN_TEST(test_upload_of_exactly_one_full_segment);
    RUN_TEST(test_upload_of_two_full_segments);
    RUN_TEST(test_upload_of_an_empty_string);
    RUN_TEST(test_upload_of_a_full_capacity_string);
    RUN_TEST(test_upload_toggle_error_aborts_0x05030000);
    RUN_TEST(test_upload_repeated_toggle_aborts_0x05030000);
    RUN_TEST(test_upload_request_after_the_last_segment_aborts_0x05040001);
    RUN_TEST(test_download_u64_with_size_frames_byte_for_byte);
    RUN_TEST(test_download_u64_without_size);
    RUN_TEST(test_download_of_a_small_value_segmented);
    RUN_TEST(test_download_string_with_size);
    RUN_TEST(test_download_string_without_size);
    RUN_TEST(test_download_string_of_full_capacity);
    RUN_TEST(test_download_string_into_a_record);
    RUN_TEST(test_download_toggle_error_aborts_0x05030000);
    RUN_TEST(test_download_repeated_toggle_aborts_0x05030000);
    RUN_TEST(test_download_more_than_announced_aborts_0x06070010);
    RUN_TEST(test_download_less_than_announced_aborts_0x06070010);
    RUN_TEST(test_download_beyond_string_capacity_aborts_0x06070012);
    RUN_TEST(test_download_octet_string_too_long_aborts_0x06070012);
    RUN_TEST(test_download_too_short_for_the_type_aborts_0x06070013);
    RUN_TEST(test_download_out_of_range_aborts_at_the_end_0x06090031);
    RUN_TEST(test_download_segment_without_data_is_accepted);
    RUN_TEST(test_download_then_upload_round_trip);
    RUN_TEST(test_download_timeout_just_before_and_at_the_deadline);
    RUN_TEST(test_upload_timeout_just_before_and_at_the_deadline);
    RUN_TEST(test_each_segment_restarts_the_timeout);
    RUN_TEST(test_configured_timeout_is_used);
    RUN_TEST(test_late_process_call_still_times_out);
    RUN_TEST(test_domain_download_without_size_streams_in_pieces);
    RUN_TEST(test_domain_download_with_size_passes_the_total);
    RUN_TEST(test_domain_download_hook_refusal_passes_through);
    RUN_TEST(test_domain_download_aborted_by_the_client_never_ends);
    RUN_TEST(test_domain_download_more_than_announced_aborts_0x06070010);
    RUN_TEST(test_domain_expedited_download);
    RUN_TEST(test_domain_segmented_upload_in_small_pieces);
    RUN_TEST(test_domain_segmented_upload_larger_than_the_buffer);
    RUN_TEST(test_domain_small_upload_is_expedited);
    RUN_TEST(test_domain_empty_upload);
    RUN_TEST(test_domain_upload_sends_only_the_announced_total);
    RUN_TEST(test_domain_upload_with_less_data_than_announced_aborts_0x08000024);
    RUN_TEST(test_domain_upload_hook_refusal_passes_through);
    RUN_TEST(test_domain_upload_hook_refusal_midway_passes_through);
    RUN_TEST(test_announced_size_beyond_the_buffer_aborts_0x05040005);
    RUN_TEST(test_download_beyond_the_buffer_aborts_0x05040005);
    RUN_TEST(test_download_filling_the_buffer_exactly_works);
    RUN_TEST(test_upload_beyond_the_buffer_aborts_0x05040005);
    return UNITY_END();
}
