/* SDO server, block transfers: download and upload of values and of a 100 kB DOMAIN with and
 * without CRC, frames byte for byte, lost and repeated segments, wrong CRC, bad block sizes and
 * sequence numbers, the protocol switch threshold, timeouts and a port that refuses frames. */
#include <string.h>

#include "canopen/sdo_server.h"
#include "od_test.h"
#include "test_domain.h"
#include "test_support.h"
#include "unity.h"

#define RX 0x605u
#define TX 0x585u
#define BIG 100000u /* the 100 kB DOMAIN */

static test_node t;

static test_domain dom; /* the DOMAIN hook on 0x2010 */
static uint8_t payload[BIG];   /* what a client sends: the DOMAIN's pattern */

void setUp(void)
{
    test_node_start(&t, 5);
    fake_bus_clear(&t.bus);
    test_domain_reset(&dom);
    for (uint32_t i = 0; i < BIG; i++) {
        payload[i] = test_domain_pattern(i);
    }
}

void tearDown(void) {}

/* --- frames ----------------------------------------------------------------------------------- */

static const co_frame *response(void)
{
    const co_frame *f = fake_bus_next(&t.bus);
    TEST_ASSERT_NOT_NULL_MESSAGE(f, "no SDO response");
    TEST_ASSERT_EQUAL_HEX16(TX, f->id);
    TEST_ASSERT_EQUAL_UINT8(8, f->dlc);
    return f;
}

/* Forgets every captured frame, so a long transfer never fills the capture. */
static void bus_reset(void)
{
    expect_no_frame(&t);
    t.bus.count = 0;
    t.bus.read = 0;
}

/* The client's CRC, bit by bit (independent of the server's table). */
static uint16_t crc_ref(const uint8_t *data, uint32_t len)
{
    uint16_t crc = 0;
    for (uint32_t i = 0; i < len; i++) {
        crc = (uint16_t)(crc ^ (data[i] << 8));
        for (int b = 0; b < 8; b++) {
            crc = (crc & 0x8000u) != 0u ? (uint16_t)((crc << 1) ^ 0x1021u) : (uint16_t)(crc << 1);
        }
    }
    return crc;
}

/* --- a block download client ------------------------------------------------------------------ */

typedef struct dl_options {
    bool crc;           /* client asks for the CRC */
    bool size;          /* size indicated */
    uint32_t lose_at;   /* drop the segment starting at this byte once (UINT32_MAX: none) */
    bool bad_crc;       /* send a wrong CRC in the end request */
} dl_options;

static dl_options dl_default(void)
{
    dl_options o = {true, true, UINT32_MAX, false};
    return o;
}

/* Writes data with a block download; returns the abort code (0: done). *acks counts the
 * sub-block acknowledgements. */
static uint32_t block_download(uint16_t index, uint8_t sub, const uint8_t *data, uint32_t len,
                               dl_options o, uint32_t *acks)
{
    uint32_t size = o.size ? len : 0u;
    sdo_req(&t, (uint8_t)(0xC0u | (o.crc ? 0x04u : 0u) | (o.size ? 0x02u : 0u)), (uint8_t)index,
        (uint8_t)(index >> 8), sub, (uint8_t)size, (uint8_t)(size >> 8), (uint8_t)(size >> 16),
        (uint8_t)(size >> 24));
    const co_frame *f = response();
    if (f->data[0] == 0x80u) {
        return co_get_le32(&f->data[4]);
    }
    TEST_ASSERT_EQUAL_HEX8(0xA4, f->data[0]); /* the server supports the CRC */
    TEST_ASSERT_EQUAL_HEX16(index, co_get_le16(&f->data[1]));
    uint8_t block_size = f->data[4];
    TEST_ASSERT_TRUE(block_size >= 1u && block_size <= 127u);
    uint32_t pos = 0;
    bool lost = false;
    *acks = 0;
    for (;;) {
        uint32_t p = pos;
        uint8_t seq = 0;
        bool sent_last = false;
        while (seq < block_size) {
            seq++;
            uint32_t n = len - p < 7u ? len - p : 7u;
            bool last = p + n >= len;
            uint8_t seg[8] = {(uint8_t)((last ? 0x80u : 0u) | seq)};
            memcpy(&seg[1], &data[p], n);
            if (p == o.lose_at && !lost) {
                lost = true;
            } else {
                test_rx(&t, RX, 8, seg);
            }
            p += n;
            if (last) {
                sent_last = true;
                break;
            }
            /* in the middle of a sub-block the server says nothing, unless it aborts */
            if (seq < block_size && fake_bus_pending(&t.bus) != 0u) {
                f = response();
                TEST_ASSERT_EQUAL_HEX8(0x80, f->data[0]);
                return co_get_le32(&f->data[4]);
            }
        }
        f = response();
        if (f->data[0] == 0x80u) {
            return co_get_le32(&f->data[4]);
        }
        TEST_ASSERT_EQUAL_HEX8(0xA2, f->data[0]);
        uint8_t acked = f->data[1];
        TEST_ASSERT_TRUE(acked <= seq);
        block_size = f->data[2];
        TEST_ASSERT_TRUE(block_size >= 1u && block_size <= 127u);
        (*acks)++;
        pos += (uint32_t)acked * 7u;
        pos = pos > len ? len : pos;
        bus_reset();
        if (sent_last && acked == seq) {
            break;
        }
    }
    uint32_t last_bytes = len == 0u ? 0u : len - 7u * ((len - 1u) / 7u);
    uint16_t crc = (uint16_t)(crc_ref(data, len) ^ (o.bad_crc ? 0x0100u : 0u));
    sdo_req(&t, (uint8_t)(0xC1u | ((7u - last_bytes) << 2)), (uint8_t)crc, (uint8_t)(crc >> 8), 0, 0,
            0, 0, 0);
    f = response();
    if (f->data[0] == 0x80u) {
        return co_get_le32(&f->data[4]);
    }
    const uint8_t end[8] = {0xA1, 0, 0, 0, 0, 0, 0, 0};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(end, f->data, 8);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
    return 0;
}

/* --- a block upload client -------------------------------------------------------------------- */

typedef struct ul_options {
    bool crc;
    uint8_t block_size;
    uint8_t pst;
    uint32_t lose_at;      /* pretend the segment starting at this byte was lost, once */
    uint8_t next_size[4];  /* block sizes for the first acknowledgements (0: keep) */
} ul_options;

static ul_options ul_default(void)
{
    ul_options o = {true, 127, 0, UINT32_MAX, {0, 0, 0, 0}};
    return o;
}

static uint8_t received[BIG + 8u];

/* Reads with a block upload into received[]; returns the abort code (0: done). *len is the size
 * the data came to; *sub_blocks counts the sub-blocks. */
static uint32_t block_upload(uint16_t index, uint8_t sub, ul_options o, uint32_t *len,
                             uint32_t *sub_blocks)
{
    sdo_req(&t, (uint8_t)(0xA0u | (o.crc ? 0x04u : 0u)), (uint8_t)index, (uint8_t)(index >> 8), sub,
        o.block_size, o.pst, 0, 0);
    const co_frame *f = response();
    if (f->data[0] == 0x80u) {
        return co_get_le32(&f->data[4]);
    }
    TEST_ASSERT_EQUAL_HEX8(0xC6, f->data[0]); /* CRC supported, size indicated */
    TEST_ASSERT_EQUAL_HEX16(index, co_get_le16(&f->data[1]));
    TEST_ASSERT_EQUAL_HEX8(sub, f->data[3]);
    uint32_t size = co_get_le32(&f->data[4]);
    TEST_ASSERT_TRUE(size <= BIG);
    sdo_req(&t, 0xA3, 0, 0, 0, 0, 0, 0, 0);
    uint8_t block_size = o.block_size;
    uint32_t pos = 0;
    bool lost = false;
    *sub_blocks = 0;
    for (;;) {
        uint8_t good = 0;
        bool gap = false, got_last = false;
        for (uint8_t k = 1;; k++) {
            f = response();
            if (f->data[0] == 0x80u) {
                return co_get_le32(&f->data[4]);
            }
            TEST_ASSERT_EQUAL_UINT8(k, f->data[0] & 0x7Fu);
            bool last = (f->data[0] & 0x80u) != 0u;
            uint32_t at = pos + 7u * (k - 1u);
            if (at == o.lose_at && !lost) {
                lost = true;
                gap = true;
            } else if (!gap) {
                TEST_ASSERT_TRUE(at + 7u <= sizeof received);
                memcpy(&received[at], &f->data[1], 7);
                good = k;
                got_last = last;
            }
            if (last || k == block_size) {
                break;
            }
        }
        expect_no_frame(&t); /* exactly the sub-block, nothing more */
        bus_reset();
        pos += 7u * good;
        if (*sub_blocks < 4u && o.next_size[*sub_blocks] != 0u) {
            block_size = o.next_size[*sub_blocks];
        }
        (*sub_blocks)++;
        sdo_req(&t, 0xA2, good, block_size, 0, 0, 0, 0, 0);
        if (got_last) {
            break;
        }
    }
    f = response();
    if (f->data[0] == 0x80u) {
        return co_get_le32(&f->data[4]);
    }
    TEST_ASSERT_EQUAL_HEX8(0xC1, f->data[0] & 0xE3u);
    uint32_t unused = (f->data[0] >> 2) & 7u;
    for (int i = 3; i < 8; i++) {
        TEST_ASSERT_EQUAL_HEX8(0, f->data[i]);
    }
    *len = pos - unused;
    TEST_ASSERT_EQUAL_UINT32(size, *len);
    TEST_ASSERT_EQUAL_HEX16(o.crc ? crc_ref(received, *len) : 0u, co_get_le16(&f->data[1]));
    sdo_req(&t, 0xA1, 0, 0, 0, 0, 0, 0, 0);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
    return 0;
}

/* --- block download --------------------------------------------------------------------------- */

static void test_block_download_value_frames_byte_for_byte(void)
{
    const uint8_t data[8] = {0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88};
    uint16_t crc = crc_ref(data, 8);
    sdo_req(&t, 0xC6, 0x0A, 0x20, 0x00, 8, 0, 0, 0); /* CRC, size 8 */
    sdo_expect(&t, 0xA4, 0x0A, 0x20, 0x00, 127, 0, 0, 0);
    sdo_req(&t, 0x01, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77);
    expect_no_frame(&t);
    sdo_req(&t, 0x82, 0x88, 0, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0xA2, 2, 127, 0, 0, 0, 0, 0);
    /* nothing written before the end */
    TEST_ASSERT_EQUAL_HEX8(0xEF, test_value_of(&t, 0x200A, 0)[0]);
    sdo_req(&t, 0xD9, (uint8_t)crc, (uint8_t)(crc >> 8), 0, 0, 0, 0, 0); /* 6 bytes unused */
    sdo_expect(&t, 0xA1, 0, 0, 0, 0, 0, 0, 0);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL_MEMORY(data, test_value_of(&t, 0x200A, 0), 8);
}

static void test_block_size_offered_is_what_the_buffer_holds(void)
{
    uint32_t offer = CO_SDO_BUF_SIZE / 7u > 127u ? 127u : CO_SDO_BUF_SIZE / 7u;
    sdo_req(&t, 0xC2, 0x0D, 0x20, 0x00, 3, 0, 0, 0);
    sdo_expect(&t, 0xA4, 0x0D, 0x20, 0x00, (uint8_t)offer, 0, 0, 0);
}

static void test_block_download_without_crc_ignores_the_crc_field(void)
{
    dl_options o = dl_default();
    o.crc = false;
    o.bad_crc = true;
    uint32_t acks;
    TEST_ASSERT_EQUAL_HEX32(0, block_download(0x200D, 0, (const uint8_t *)"no crc here", 11, o,
                                              &acks));
    TEST_ASSERT_EQUAL_MEMORY("no crc here\0", test_value_of(&t, 0x200D, 0), 12);
}

static void test_block_download_string_without_size(void)
{
    dl_options o = dl_default();
    o.size = false;
    uint32_t acks;
    const uint8_t *text = (const uint8_t *)"a string of 25 characters";
    TEST_ASSERT_EQUAL_HEX32(0, block_download(0x200D, 0, text, 25, o, &acks));
    TEST_ASSERT_EQUAL_MEMORY("a string of 25 characters\0", test_value_of(&t, 0x200D, 0), 26);
}

static void test_block_download_of_a_small_value(void)
{
    const uint8_t data[4] = {0x78, 0x56, 0x34, 0x12};
    uint32_t acks;
    TEST_ASSERT_EQUAL_HEX32(0, block_download(0x2009, 0, data, 4, dl_default(), &acks));
    TEST_ASSERT_EQUAL_HEX32(0x12345678, co_od_get_u32(&t.node, 0x2009, 0));
}

static void test_block_download_100k_domain_with_crc(void)
{
    test_domain_add_hook(&t, &dom);
    uint32_t acks;
    TEST_ASSERT_EQUAL_HEX32(0, block_download(0x2010, 0, payload, BIG, dl_default(), &acks));
    TEST_ASSERT_EQUAL_UINT32(BIG, dom.received);
    TEST_ASSERT_EQUAL_UINT32(BIG, dom.total);
    TEST_ASSERT_TRUE(dom.in_order);
    TEST_ASSERT_TRUE(dom.pattern_ok);
    TEST_ASSERT_EQUAL_UINT32(1, dom.last_calls);
    TEST_ASSERT_TRUE(dom.largest_piece <= CO_SDO_BUF_SIZE);
    TEST_ASSERT_EQUAL_UINT32((BIG + 7u * 127u - 1u) / (7u * 127u), acks);
}

static void test_block_download_100k_domain_without_crc(void)
{
    test_domain_add_hook(&t, &dom);
    dl_options o = dl_default();
    o.crc = false;
    uint32_t acks;
    TEST_ASSERT_EQUAL_HEX32(0, block_download(0x2010, 0, payload, BIG, o, &acks));
    TEST_ASSERT_EQUAL_UINT32(BIG, dom.received);
    TEST_ASSERT_TRUE(dom.pattern_ok);
    TEST_ASSERT_EQUAL_UINT32(1, dom.last_calls);
}

static void test_block_download_100k_domain_without_size(void)
{
    test_domain_add_hook(&t, &dom);
    dl_options o = dl_default();
    o.size = false;
    uint32_t acks;
    TEST_ASSERT_EQUAL_HEX32(0, block_download(0x2010, 0, payload, BIG, o, &acks));
    TEST_ASSERT_EQUAL_UINT32(BIG, dom.received);
    TEST_ASSERT_EQUAL_UINT32(0, dom.total);
    TEST_ASSERT_TRUE(dom.pattern_ok);
}

static void test_block_download_of_whole_sub_blocks(void)
{
    test_domain_add_hook(&t, &dom);
    uint32_t acks;
    TEST_ASSERT_EQUAL_HEX32(0, block_download(0x2010, 0, payload, 3u * 889u, dl_default(), &acks));
    TEST_ASSERT_EQUAL_UINT32(3, acks);
    TEST_ASSERT_EQUAL_UINT32(3u * 889u, dom.received);
    TEST_ASSERT_TRUE(dom.pattern_ok);
}

static void test_block_download_lost_segment_is_repeated(void)
{
    test_domain_add_hook(&t, &dom);
    dl_options o = dl_default();
    o.lose_at = 14; /* segment 3 of the first sub-block */
    uint32_t acks;
    TEST_ASSERT_EQUAL_HEX32(0, block_download(0x2010, 0, payload, 2000, o, &acks));
    TEST_ASSERT_EQUAL_UINT32(2000, dom.received);
    TEST_ASSERT_TRUE(dom.in_order);
    TEST_ASSERT_TRUE(dom.pattern_ok);
    TEST_ASSERT_EQUAL_UINT32(4, acks); /* 3 sub-blocks, one repeated in part */
}

static void test_block_download_lost_segment_acknowledges_the_last_good_one(void)
{
    const uint8_t *s = (const uint8_t *)"abcdefghijklmnopqrst"; /* 3 segments */
    sdo_req(&t, 0xC6, 0x0D, 0x20, 0x00, 20, 0, 0, 0);
    sdo_expect(&t, 0xA4, 0x0D, 0x20, 0x00, 127, 0, 0, 0);
    sdo_req(&t, 0x01, s[0], s[1], s[2], s[3], s[4], s[5], s[6]);
    /* segment 2 lost */
    sdo_req(&t, 0x83, s[14], s[15], s[16], s[17], s[18], s[19], 0);
    sdo_expect(&t, 0xA2, 1, 127, 0, 0, 0, 0, 0); /* the client repeats from segment 2, numbered 1 */
    sdo_req(&t, 0x01, s[7], s[8], s[9], s[10], s[11], s[12], s[13]);
    sdo_req(&t, 0x82, s[14], s[15], s[16], s[17], s[18], s[19], 0);
    sdo_expect(&t, 0xA2, 2, 127, 0, 0, 0, 0, 0);
    uint16_t crc = crc_ref(s, 20);
    sdo_req(&t, 0xC5, (uint8_t)crc, (uint8_t)(crc >> 8), 0, 0, 0, 0, 0); /* 1 unused */
    sdo_expect(&t, 0xA1, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_MEMORY("abcdefghijklmnopqrst\0", test_value_of(&t, 0x200D, 0), 21);
}

static void test_block_download_lost_first_segment_acknowledges_0(void)
{
    sdo_req(&t, 0xC6, 0x0D, 0x20, 0x00, 10, 0, 0, 0);
    sdo_expect(&t, 0xA4, 0x0D, 0x20, 0x00, 127, 0, 0, 0);
    sdo_req(&t, 0x82, 'h', 'i', 'j', 0, 0, 0, 0);
    sdo_expect(&t, 0xA2, 0, 127, 0, 0, 0, 0, 0);
    sdo_req(&t, 0x01, 'a', 'b', 'c', 'd', 'e', 'f', 'g');
    sdo_req(&t, 0x82, 'h', 'i', 'j', 0, 0, 0, 0);
    sdo_expect(&t, 0xA2, 2, 127, 0, 0, 0, 0, 0);
    uint16_t crc = crc_ref((const uint8_t *)"abcdefghij", 10);
    sdo_req(&t, 0xD1, (uint8_t)crc, (uint8_t)(crc >> 8), 0, 0, 0, 0, 0); /* 4 unused */
    sdo_expect(&t, 0xA1, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_MEMORY("abcdefghij\0", test_value_of(&t, 0x200D, 0), 11);
}

static void test_block_download_duplicate_segment_is_ignored(void)
{
    sdo_req(&t, 0xC6, 0x0D, 0x20, 0x00, 10, 0, 0, 0);
    sdo_expect(&t, 0xA4, 0x0D, 0x20, 0x00, 127, 0, 0, 0);
    sdo_req(&t, 0x01, 'a', 'b', 'c', 'd', 'e', 'f', 'g');
    sdo_req(&t, 0x01, 'X', 'X', 'X', 'X', 'X', 'X', 'X');
    expect_no_frame(&t);
    sdo_req(&t, 0x82, 'h', 'i', 'j', 0, 0, 0, 0);
    sdo_expect(&t, 0xA2, 2, 127, 0, 0, 0, 0, 0);
    uint16_t crc = crc_ref((const uint8_t *)"abcdefghij", 10);
    sdo_req(&t, 0xD1, (uint8_t)crc, (uint8_t)(crc >> 8), 0, 0, 0, 0, 0);
    sdo_expect(&t, 0xA1, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_MEMORY("abcdefghij\0", test_value_of(&t, 0x200D, 0), 11);
}

static void test_block_download_wrong_crc_aborts_0x05040004(void)
{
    test_values_snapshot(&t);
    dl_options o = dl_default();
    o.bad_crc = true;
    uint32_t acks;
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_CRC, block_download(0x200D, 0, (const uint8_t *)"crc!", 4, o,
                                                         &acks));
    test_expect_values_unchanged(&t);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
}

static void test_block_download_wrong_crc_never_ends_the_domain(void)
{
    test_domain_add_hook(&t, &dom);
    dl_options o = dl_default();
    o.bad_crc = true;
    uint32_t acks;
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_CRC, block_download(0x2010, 0, payload, 5000, o, &acks));
    TEST_ASSERT_EQUAL_UINT32(0, dom.last_calls);
}

static void test_block_download_sequence_number_0_aborts_0x05040003(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0xC6, 0x0D, 0x20, 0x00, 10, 0, 0, 0);
    sdo_expect(&t, 0xA4, 0x0D, 0x20, 0x00, 127, 0, 0, 0);
    sdo_req(&t, 0x00, 'a', 'b', 'c', 'd', 'e', 'f', 'g');
    sdo_expect_abort(&t, 0x200D, 0, CO_ABORT_SEQUENCE);
    test_expect_values_unchanged(&t);
}

static void test_block_download_more_than_announced_aborts_0x06070010(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0xC6, 0x0D, 0x20, 0x00, 5, 0, 0, 0);
    sdo_expect(&t, 0xA4, 0x0D, 0x20, 0x00, 127, 0, 0, 0);
    sdo_req(&t, 0x01, 'a', 'b', 'c', 'd', 'e', 'f', 'g');
    sdo_req(&t, 0x82, 'h', 0, 0, 0, 0, 0, 0);
    sdo_expect_abort(&t, 0x200D, 0, CO_ABORT_TYPE_LENGTH);
    test_expect_values_unchanged(&t);
}

static void test_block_download_less_than_announced_aborts_0x06070010(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0xC6, 0x0D, 0x20, 0x00, 10, 0, 0, 0);
    sdo_expect(&t, 0xA4, 0x0D, 0x20, 0x00, 127, 0, 0, 0);
    sdo_req(&t, 0x81, 'a', 'b', 'c', 'd', 'e', 'f', 'g');
    sdo_expect(&t, 0xA2, 1, 127, 0, 0, 0, 0, 0);
    uint16_t crc = crc_ref((const uint8_t *)"abcdefg", 7);
    sdo_req(&t, 0xC1, (uint8_t)crc, (uint8_t)(crc >> 8), 0, 0, 0, 0, 0);
    sdo_expect_abort(&t, 0x200D, 0, CO_ABORT_TYPE_LENGTH);
    test_expect_values_unchanged(&t);
}

static void test_block_download_too_short_for_the_type_aborts_0x06070013(void)
{
    test_values_snapshot(&t);
    dl_options o = dl_default();
    o.size = false;
    uint32_t acks;
    const uint8_t data[7] = {1, 2, 3, 4, 5, 6, 7};
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_TYPE_TOO_SHORT, block_download(0x200A, 0, data, 7, o, &acks));
    test_expect_values_unchanged(&t);
}

static void test_block_download_too_long_without_size_aborts_0x06070012(void)
{
    test_values_snapshot(&t);
    dl_options o = dl_default();
    o.size = false;
    uint32_t acks;
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_TYPE_TOO_LONG, block_download(0x200E, 0, payload, 40, o,
                                                                   &acks));
    test_expect_values_unchanged(&t);
}

static void test_block_download_to_read_only_aborts_0x06010002(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0xC6, 0x20, 0x20, 0x00, 2, 0, 0, 0);
    sdo_expect_abort(&t, 0x2020, 0, CO_ABORT_READ_ONLY);
    test_expect_values_unchanged(&t);
}

static void test_block_download_to_a_missing_object_aborts_0x06020000(void)
{
    sdo_req(&t, 0xC4, 0x00, 0x30, 0x00, 0, 0, 0, 0);
    sdo_expect_abort(&t, 0x3000, 0, CO_ABORT_NO_OBJECT);
}

static void test_block_download_announced_too_short_aborts_0x06070013(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0xC6, 0x0A, 0x20, 0x00, 7, 0, 0, 0);
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_TYPE_TOO_SHORT);
    test_expect_values_unchanged(&t);
}

static void test_block_download_out_of_range_aborts_0x06090032(void)
{
    test_values_snapshot(&t);
    const uint8_t data[2] = {0x0C, 0xFE}; /* -500 ... into 0x605A -2..7 */
    uint32_t acks;
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_TOO_LOW, block_download(0x605A, 0, data, 2,
                                                                   dl_default(), &acks));
    test_expect_values_unchanged(&t);
}

static void test_block_download_client_abort_is_silent(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0xC6, 0x0D, 0x20, 0x00, 20, 0, 0, 0);
    sdo_expect(&t, 0xA4, 0x0D, 0x20, 0x00, 127, 0, 0, 0);
    sdo_req(&t, 0x01, 'a', 'b', 'c', 'd', 'e', 'f', 'g');
    sdo_req(&t, 0x80, 0x0D, 0x20, 0x00, 0x00, 0x00, 0x04, 0x05);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
    test_expect_values_unchanged(&t);
}

static void test_block_download_timeout_just_before_and_at_the_deadline(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0xC6, 0x0D, 0x20, 0x00, 20, 0, 0, 0);
    sdo_expect(&t, 0xA4, 0x0D, 0x20, 0x00, 127, 0, 0, 0);
    test_advance(&t, 500000);
    sdo_req(&t, 0x01, 'a', 'b', 'c', 'd', 'e', 'f', 'g'); /* restarts the timeout */
    test_advance(&t, CO_SDO_TIMEOUT_US - 1u);
    expect_no_frame(&t);
    test_advance(&t, 1);
    sdo_expect_abort(&t, 0x200D, 0, CO_ABORT_TIMEOUT);
    test_expect_values_unchanged(&t);
}

static void test_block_download_timeout_waiting_for_the_end(void)
{
    sdo_req(&t, 0xC6, 0x0D, 0x20, 0x00, 3, 0, 0, 0);
    sdo_expect(&t, 0xA4, 0x0D, 0x20, 0x00, 127, 0, 0, 0);
    sdo_req(&t, 0x81, 'a', 'b', 'c', 0, 0, 0, 0);
    sdo_expect(&t, 0xA2, 1, 127, 0, 0, 0, 0, 0);
    test_advance(&t, CO_SDO_TIMEOUT_US);
    sdo_expect_abort(&t, 0x200D, 0, CO_ABORT_TIMEOUT);
}

static void test_block_download_wrong_request_at_the_end_aborts_0x05040001(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0xC6, 0x0D, 0x20, 0x00, 3, 0, 0, 0);
    sdo_expect(&t, 0xA4, 0x0D, 0x20, 0x00, 127, 0, 0, 0);
    sdo_req(&t, 0x81, 'a', 'b', 'c', 0, 0, 0, 0);
    sdo_expect(&t, 0xA2, 1, 127, 0, 0, 0, 0, 0);
    sdo_req(&t, 0x60, 0, 0, 0, 0, 0, 0, 0); /* an upload segment request */
    sdo_expect_abort(&t, 0x200D, 0, CO_ABORT_COMMAND);
    test_expect_values_unchanged(&t);
}

static void test_block_download_new_initiate_at_the_end_starts_over(void)
{
    test_values_snapshot(&t);
    sdo_req(&t, 0xC6, 0x0D, 0x20, 0x00, 3, 0, 0, 0);
    sdo_expect(&t, 0xA4, 0x0D, 0x20, 0x00, 127, 0, 0, 0);
    sdo_req(&t, 0x81, 'a', 'b', 'c', 0, 0, 0, 0);
    sdo_expect(&t, 0xA2, 1, 127, 0, 0, 0, 0, 0);
    sdo_req(&t, 0x40, 0x06, 0x20, 0x00, 0, 0, 0, 0);
    sdo_expect(&t, 0x4F, 0x06, 0x20, 0x00, 200, 0, 0, 0);
    test_expect_values_unchanged(&t);
}

/* --- block upload ----------------------------------------------------------------------------- */

static void test_block_upload_value_frames_byte_for_byte(void)
{
    const uint8_t data[8] = {0xEF, 0xCD, 0xAB, 0x89, 0x67, 0x45, 0x23, 0x01};
    uint16_t crc = crc_ref(data, 8);
    sdo_req(&t, 0xA4, 0x0A, 0x20, 0x00, 127, 0, 0, 0);
    sdo_expect(&t, 0xC6, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    expect_no_frame(&t);
    sdo_req(&t, 0xA3, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0x01, 0xEF, 0xCD, 0xAB, 0x89, 0x67, 0x45, 0x23);
    sdo_expect(&t, 0x82, 0x01, 0, 0, 0, 0, 0, 0);
    expect_no_frame(&t);
    sdo_req(&t, 0xA2, 2, 127, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0xD9, (uint8_t)crc, (uint8_t)(crc >> 8), 0, 0, 0, 0, 0);
    expect_no_frame(&t);
    sdo_req(&t, 0xA1, 0, 0, 0, 0, 0, 0, 0);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
}

static void test_block_upload_without_crc_sends_crc_0(void)
{
    ul_options o = ul_default();
    o.crc = false;
    uint32_t len, blocks;
    TEST_ASSERT_EQUAL_HEX32(0, block_upload(0x1008, 0, o, &len, &blocks));
    TEST_ASSERT_EQUAL_UINT32(12, len);
    TEST_ASSERT_EQUAL_MEMORY("canopen-test", received, 12);
}

static void test_block_upload_100k_domain_with_crc(void)
{
    test_domain_add_hook(&t, &dom);
    dom.source_size = BIG;
    uint32_t len, blocks;
    TEST_ASSERT_EQUAL_HEX32(0, block_upload(0x2010, 0, ul_default(), &len, &blocks));
    TEST_ASSERT_EQUAL_UINT32(BIG, len);
    TEST_ASSERT_EQUAL_MEMORY(payload, received, BIG);
    TEST_ASSERT_EQUAL_UINT32((BIG + 7u * 127u - 1u) / (7u * 127u), blocks);
}

static void test_block_upload_100k_domain_without_crc(void)
{
    test_domain_add_hook(&t, &dom);
    dom.source_size = BIG;
    dom.read_piece = 500; /* the hook gives less than asked: the server asks again */
    ul_options o = ul_default();
    o.crc = false;
    uint32_t len, blocks;
    TEST_ASSERT_EQUAL_HEX32(0, block_upload(0x2010, 0, o, &len, &blocks));
    TEST_ASSERT_EQUAL_UINT32(BIG, len);
    TEST_ASSERT_EQUAL_MEMORY(payload, received, BIG);
}

static void test_block_upload_lost_segment_is_repeated(void)
{
    test_domain_add_hook(&t, &dom);
    dom.source_size = 3000;
    ul_options o = ul_default();
    o.lose_at = 7u * 40u; /* segment 41 of the first sub-block */
    uint32_t len, blocks;
    TEST_ASSERT_EQUAL_HEX32(0, block_upload(0x2010, 0, o, &len, &blocks));
    TEST_ASSERT_EQUAL_UINT32(3000, len);
    TEST_ASSERT_EQUAL_MEMORY(payload, received, 3000);
    TEST_ASSERT_EQUAL_UINT32(5, blocks); /* 4 sub-blocks, one repeated in part */
}

static void test_block_upload_lost_last_segment_is_repeated(void)
{
    ul_options o = ul_default();
    o.lose_at = 7; /* the second and last segment of the string */
    uint32_t len, blocks;
    TEST_ASSERT_EQUAL_HEX32(0, block_upload(0x1008, 0, o, &len, &blocks));
    TEST_ASSERT_EQUAL_UINT32(12, len);
    TEST_ASSERT_EQUAL_MEMORY("canopen-test", received, 12);
    TEST_ASSERT_EQUAL_UINT32(2, blocks);
}

static void test_block_upload_ack_0_repeats_the_whole_sub_block(void)
{
    sdo_req(&t, 0xA4, 0x0A, 0x20, 0x00, 127, 0, 0, 0);
    sdo_expect(&t, 0xC6, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    sdo_req(&t, 0xA3, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0x01, 0xEF, 0xCD, 0xAB, 0x89, 0x67, 0x45, 0x23);
    sdo_expect(&t, 0x82, 0x01, 0, 0, 0, 0, 0, 0);
    sdo_req(&t, 0xA2, 0, 127, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0x01, 0xEF, 0xCD, 0xAB, 0x89, 0x67, 0x45, 0x23);
    sdo_expect(&t, 0x82, 0x01, 0, 0, 0, 0, 0, 0);
    sdo_req(&t, 0xA2, 1, 127, 0, 0, 0, 0, 0); /* only the first arrived this time */
    sdo_expect(&t, 0x81, 0x01, 0, 0, 0, 0, 0, 0);
    sdo_req(&t, 0xA2, 1, 127, 0, 0, 0, 0, 0);
    const uint8_t data[8] = {0xEF, 0xCD, 0xAB, 0x89, 0x67, 0x45, 0x23, 0x01};
    uint16_t crc = crc_ref(data, 8);
    sdo_expect(&t, 0xD9, (uint8_t)crc, (uint8_t)(crc >> 8), 0, 0, 0, 0, 0);
}

static void test_block_upload_with_changing_block_sizes(void)
{
    test_domain_add_hook(&t, &dom);
    dom.source_size = 200;
    ul_options o = ul_default();
    o.block_size = 3;
    o.next_size[0] = 5;
    o.next_size[1] = 1;
    o.next_size[2] = 20;
    uint32_t len, blocks;
    TEST_ASSERT_EQUAL_HEX32(0, block_upload(0x2010, 0, o, &len, &blocks));
    TEST_ASSERT_EQUAL_UINT32(200, len);
    TEST_ASSERT_EQUAL_MEMORY(payload, received, 200);
    TEST_ASSERT_EQUAL_UINT32(4, blocks); /* 21 + 35 + 7 + 137 = 200 bytes */
}

static void test_block_upload_of_one_full_sub_block(void)
{
    test_domain_add_hook(&t, &dom);
    dom.source_size = 889;
    uint32_t len, blocks;
    TEST_ASSERT_EQUAL_HEX32(0, block_upload(0x2010, 0, ul_default(), &len, &blocks));
    TEST_ASSERT_EQUAL_UINT32(889, len);
    TEST_ASSERT_EQUAL_UINT32(1, blocks);
    TEST_ASSERT_EQUAL_MEMORY(payload, received, 889);
}

static void test_block_upload_of_an_empty_string(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, co_od_write(&t.node, 0x200D, 0, (const uint8_t *)"", 0,
                                           CO_ORIGIN_APP));
    sdo_req(&t, 0xA4, 0x0D, 0x20, 0x00, 127, 0, 0, 0);
    sdo_expect(&t, 0xC6, 0x0D, 0x20, 0x00, 0, 0, 0, 0);
    sdo_req(&t, 0xA3, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0x81, 0, 0, 0, 0, 0, 0, 0);
    sdo_req(&t, 0xA2, 1, 127, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0xDD, 0, 0, 0, 0, 0, 0, 0); /* 7 unused, CRC of nothing */
    sdo_req(&t, 0xA1, 0, 0, 0, 0, 0, 0, 0);
    expect_no_frame(&t);
}

static void test_block_upload_block_size_0_aborts_0x05040002(void)
{
    sdo_req(&t, 0xA4, 0x0A, 0x20, 0x00, 0, 0, 0, 0);
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_BLOCK_SIZE);
}

static void test_block_upload_block_size_128_aborts_0x05040002(void)
{
    sdo_req(&t, 0xA4, 0x0A, 0x20, 0x00, 128, 0, 0, 0);
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_BLOCK_SIZE);
    sdo_req(&t, 0xA4, 0x0A, 0x20, 0x00, 255, 0, 0, 0);
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_BLOCK_SIZE);
}

static void test_block_upload_ack_with_bad_block_size_aborts_0x05040002(void)
{
    test_domain_add_hook(&t, &dom);
    dom.source_size = 100;
    sdo_req(&t, 0xA4, 0x10, 0x20, 0x00, 2, 0, 0, 0);
    sdo_expect(&t, 0xC6, 0x10, 0x20, 0x00, 100, 0, 0, 0);
    sdo_req(&t, 0xA3, 0, 0, 0, 0, 0, 0, 0);
    (void)response();
    (void)response();
    sdo_req(&t, 0xA2, 2, 0, 0, 0, 0, 0, 0);
    sdo_expect_abort(&t, 0x2010, 0, CO_ABORT_BLOCK_SIZE);
    sdo_req(&t, 0xA4, 0x10, 0x20, 0x00, 2, 0, 0, 0);
    sdo_expect(&t, 0xC6, 0x10, 0x20, 0x00, 100, 0, 0, 0);
    sdo_req(&t, 0xA3, 0, 0, 0, 0, 0, 0, 0);
    (void)response();
    (void)response();
    sdo_req(&t, 0xA2, 2, 200, 0, 0, 0, 0, 0);
    sdo_expect_abort(&t, 0x2010, 0, CO_ABORT_BLOCK_SIZE);
}

static void test_block_upload_ack_beyond_the_sub_block_aborts_0x05040003(void)
{
    sdo_req(&t, 0xA4, 0x0A, 0x20, 0x00, 127, 0, 0, 0);
    sdo_expect(&t, 0xC6, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    sdo_req(&t, 0xA3, 0, 0, 0, 0, 0, 0, 0);
    (void)response();
    (void)response();
    sdo_req(&t, 0xA2, 3, 127, 0, 0, 0, 0, 0); /* only 2 were sent */
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_SEQUENCE);
}

static void test_block_upload_of_write_only_aborts_0x06010001(void)
{
    sdo_req(&t, 0xA4, 0x21, 0x20, 0x00, 127, 0, 0, 0);
    sdo_expect_abort(&t, 0x2021, 0, CO_ABORT_WRITE_ONLY);
}

static void test_block_upload_of_a_missing_sub_index_aborts_0x06090011(void)
{
    sdo_req(&t, 0xA4, 0x18, 0x10, 0x05, 127, 0, 0, 0);
    sdo_expect_abort(&t, 0x1018, 5, CO_ABORT_NO_SUBINDEX);
}

static void test_pst_switches_to_expedited(void)
{
    sdo_req(&t, 0xA4, 0x09, 0x20, 0x00, 127, 4, 0, 0); /* u32, threshold 4 */
    sdo_expect(&t, 0x43, 0x09, 0x20, 0x00, 0xEF, 0xBE, 0xAD, 0xDE);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
}

static void test_pst_switches_to_segmented(void)
{
    sdo_req(&t, 0xA4, 0x08, 0x10, 0x00, 127, 12, 0, 0); /* 12 bytes, threshold 12: equal switches */
    sdo_expect(&t, 0x41, 0x08, 0x10, 0x00, 12, 0, 0, 0);
    sdo_req(&t, 0x60, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0x00, 'c', 'a', 'n', 'o', 'p', 'e', 'n');
    sdo_req(&t, 0x70, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0x15, '-', 't', 'e', 's', 't', 0, 0);
    expect_no_frame(&t);
}

static void test_pst_below_the_size_keeps_the_block_transfer(void)
{
    sdo_req(&t, 0xA4, 0x08, 0x10, 0x00, 127, 11, 0, 0);
    sdo_expect(&t, 0xC6, 0x08, 0x10, 0x00, 12, 0, 0, 0);
}

static void test_pst_0_never_switches(void)
{
    sdo_req(&t, 0xA0, 0x06, 0x20, 0x00, 127, 0, 0, 0); /* 1 byte, no CRC */
    sdo_expect(&t, 0xC6, 0x06, 0x20, 0x00, 1, 0, 0, 0);
    sdo_req(&t, 0xA3, 0, 0, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0x81, 200, 0, 0, 0, 0, 0, 0);
    sdo_req(&t, 0xA2, 1, 127, 0, 0, 0, 0, 0);
    sdo_expect(&t, 0xD9, 0, 0, 0, 0, 0, 0, 0); /* 6 unused, no CRC */
    sdo_req(&t, 0xA1, 0, 0, 0, 0, 0, 0, 0);
    expect_no_frame(&t);
}

static void test_block_upload_timeout_waiting_for_the_ack(void)
{
    sdo_req(&t, 0xA4, 0x0A, 0x20, 0x00, 127, 0, 0, 0);
    sdo_expect(&t, 0xC6, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    test_advance(&t, 100);
    sdo_req(&t, 0xA3, 0, 0, 0, 0, 0, 0, 0);
    (void)response();
    (void)response();
    uint64_t deadline = t.now + CO_SDO_TIMEOUT_US;
    TEST_ASSERT_EQUAL_UINT64(deadline, test_advance(&t, CO_SDO_TIMEOUT_US - 1u));
    expect_no_frame(&t);
    test_advance(&t, 1);
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_TIMEOUT);
}

static void test_block_upload_timeout_waiting_for_the_end(void)
{
    sdo_req(&t, 0xA4, 0x0A, 0x20, 0x00, 127, 0, 0, 0);
    sdo_expect(&t, 0xC6, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    sdo_req(&t, 0xA3, 0, 0, 0, 0, 0, 0, 0);
    (void)response();
    (void)response();
    sdo_req(&t, 0xA2, 2, 127, 0, 0, 0, 0, 0);
    (void)response();
    test_advance(&t, CO_SDO_TIMEOUT_US - 1u);
    expect_no_frame(&t);
    test_advance(&t, 1);
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_TIMEOUT);
}

static void test_block_upload_timeout_waiting_for_the_start(void)
{
    sdo_req(&t, 0xA4, 0x0A, 0x20, 0x00, 127, 0, 0, 0);
    sdo_expect(&t, 0xC6, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    test_advance(&t, CO_SDO_TIMEOUT_US);
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_TIMEOUT);
}

static void test_block_upload_requests_out_of_turn_abort_0x05040001(void)
{
    sdo_req(&t, 0xA4, 0x0A, 0x20, 0x00, 127, 0, 0, 0);
    sdo_expect(&t, 0xC6, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    sdo_req(&t, 0xA2, 0, 127, 0, 0, 0, 0, 0); /* an ack before the start */
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_COMMAND);
    sdo_req(&t, 0xA4, 0x0A, 0x20, 0x00, 127, 0, 0, 0);
    sdo_expect(&t, 0xC6, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    sdo_req(&t, 0xA3, 0, 0, 0, 0, 0, 0, 0);
    (void)response();
    (void)response();
    sdo_req(&t, 0xA3, 0, 0, 0, 0, 0, 0, 0); /* a second start */
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_COMMAND);
    sdo_req(&t, 0xA4, 0x0A, 0x20, 0x00, 127, 0, 0, 0);
    sdo_expect(&t, 0xC6, 0x0A, 0x20, 0x00, 8, 0, 0, 0);
    sdo_req(&t, 0xA3, 0, 0, 0, 0, 0, 0, 0);
    (void)response();
    (void)response();
    sdo_req(&t, 0xA1, 0, 0, 0, 0, 0, 0, 0); /* the end before the server's end */
    sdo_expect_abort(&t, 0x200A, 0, CO_ABORT_COMMAND);
}

static void test_block_upload_client_abort_is_silent(void)
{
    test_domain_add_hook(&t, &dom);
    dom.source_size = 5000;
    sdo_req(&t, 0xA4, 0x10, 0x20, 0x00, 10, 0, 0, 0);
    sdo_expect(&t, 0xC6, 0x10, 0x20, 0x00, 0x88, 0x13, 0, 0);
    sdo_req(&t, 0xA3, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(10, fake_bus_pending(&t.bus));
    fake_bus_clear(&t.bus);
    sdo_req(&t, 0x80, 0x10, 0x20, 0x00, 0, 0, 0, 0x08);
    expect_no_frame(&t);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
}

static void test_block_upload_with_less_data_than_announced_aborts_0x08000024(void)
{
    test_domain_add_hook(&t, &dom);
    dom.source_size = 5000;
    dom.dry_from = 2000;
    uint32_t len, blocks;
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_DATA, block_upload(0x2010, 0, ul_default(), &len, &blocks));
}

/* The client's acknowledgement restarts the timeout even when the next sub-block has to wait for
 * room in the transmit queue: the client owes nothing while the server still has segments to send,
 * so a sub-block held back past the previous sub-block's deadline must not abort. */
static void test_block_upload_held_back_after_an_ack_does_not_time_out(void)
{
    test_domain_add_hook(&t, &dom);
    dom.source_size = 2000;
    sdo_req(&t, 0xA4, 0x10, 0x20, 0x00, 10, 0, 0, 0);
    sdo_expect(&t, 0xC6, 0x10, 0x20, 0x00, 0xD0, 0x07, 0, 0);
    sdo_req(&t, 0xA3, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(10, fake_bus_pending(&t.bus));
    fake_bus_clear(&t.bus);
    test_advance(&t, CO_SDO_TIMEOUT_US - 100000u); /* a slow client acknowledges late */
    t.bus.refuse = true;
    sdo_req(&t, 0xA2, 10, 127, 0, 0, 0, 0, 0); /* the next sub-block is larger than the queue */
    TEST_ASSERT_EQUAL_UINT16(CO_TX_QUEUE_LEN, t.node.txq.count);
    test_advance(&t, 300000u); /* the bus stays busy past the first sub-block's deadline */
    TEST_ASSERT_EQUAL(CO_SDO_UPLOAD_BLOCK, t.node.sdo.state);
    t.bus.refuse = false;
    co_node_tx_ready(&t.node);
    test_advance(&t, CO_SDO_TX_RETRY_US);
    TEST_ASSERT_EQUAL_UINT32(127, fake_bus_pending(&t.bus));
    for (uint32_t k = 1; k <= 127u; k++) {
        const co_frame *f = response();
        TEST_ASSERT_EQUAL_HEX8(k, f->data[0]);
        TEST_ASSERT_EQUAL_MEMORY(&payload[70u + 7u * (k - 1u)], &f->data[1], 7);
    }
    test_advance(&t, CO_SDO_TIMEOUT_US - 100000u); /* timed from the last segment sent */
    TEST_ASSERT_EQUAL(CO_SDO_UPLOAD_BLOCK, t.node.sdo.state);
    test_advance(&t, 100000u);
    TEST_ASSERT_EQUAL(CO_SDO_IDLE, t.node.sdo.state);
}

static void test_block_upload_waits_for_room_in_the_transmit_queue(void)
{
    sdo_req(&t, 0xA4, 0x08, 0x10, 0x00, 127, 0, 0, 0);
    sdo_expect(&t, 0xC6, 0x08, 0x10, 0x00, 12, 0, 0, 0);
    test_domain_add_hook(&t, &dom);
    dom.source_size = 2000;
    sdo_req(&t, 0xA4, 0x10, 0x20, 0x00, 127, 0, 0, 0);
    sdo_expect(&t, 0xC6, 0x10, 0x20, 0x00, 0xD0, 0x07, 0, 0);
    t.bus.refuse = true;
    sdo_req(&t, 0xA3, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(0, fake_bus_pending(&t.bus));
    TEST_ASSERT_EQUAL_UINT16(CO_TX_QUEUE_LEN, t.node.txq.count); /* the queue full, nothing lost */
    TEST_ASSERT_EQUAL_UINT32(0, t.node.stats.tx_dropped);
    TEST_ASSERT_EQUAL_UINT64(t.now + CO_SDO_TX_RETRY_US, test_advance(&t, 0));
    t.bus.refuse = false;
    co_node_tx_ready(&t.node);
    TEST_ASSERT_EQUAL_UINT32(CO_TX_QUEUE_LEN, fake_bus_pending(&t.bus));
    test_advance(&t, CO_SDO_TX_RETRY_US);
    TEST_ASSERT_EQUAL_UINT32(127, fake_bus_pending(&t.bus));
    TEST_ASSERT_EQUAL_UINT32(0, t.node.stats.tx_dropped);
    for (uint32_t k = 1; k <= 127u; k++) {
        const co_frame *f = response();
        TEST_ASSERT_EQUAL_HEX8(k, f->data[0]);
        TEST_ASSERT_EQUAL_MEMORY(&payload[7u * (k - 1u)], &f->data[1], 7);
    }
    sdo_req(&t, 0xA2, 127, 127, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(127, fake_bus_pending(&t.bus));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_block_download_value_frames_byte_for_byte);
    RUN_TEST(test_block_size_offered_is_what_the_buffer_holds);
    RUN_TEST(test_block_download_without_crc_ignores_the_crc_field);
    RUN_TEST(test_block_download_string_without_size);
    RUN_TEST(test_block_download_of_a_small_value);
    RUN_TEST(test_block_download_100k_domain_with_crc);
    RUN_TEST(test_block_download_100k_domain_without_crc);
    RUN_TEST(test_block_download_100k_domain_without_size);
    RUN_TEST(test_block_download_of_whole_sub_blocks);
    RUN_TEST(test_block_download_lost_segment_is_repeated);
    RUN_TEST(test_block_download_lost_segment_acknowledges_the_last_good_one);
    RUN_TEST(test_block_download_lost_first_segment_acknowledges_0);
    RUN_TEST(test_block_download_duplicate_segment_is_ignored);
    RUN_TEST(test_block_download_wrong_crc_aborts_0x05040004);
    RUN_TEST(test_block_download_wrong_crc_never_ends_the_domain);
    RUN_TEST(test_block_download_sequence_number_0_aborts_0x05040003);
    RUN_TEST(test_block_download_more_than_announced_aborts_0x06070010);
    RUN_TEST(test_block_download_less_than_announced_aborts_0x06070010);
    RUN_TEST(test_block_download_too_short_for_the_type_aborts_0x06070013);
    RUN_TEST(test_block_download_too_long_without_size_aborts_0x06070012);
    RUN_TEST(test_block_download_to_read_only_aborts_0x06010002);
    RUN_TEST(test_block_download_to_a_missing_object_aborts_0x06020000);
    RUN_TEST(test_block_download_announced_too_short_aborts_0x06070013);
    RUN_TEST(test_block_download_out_of_range_aborts_0x06090032);
    RUN_TEST(test_block_download_client_abort_is_silent);
    RUN_TEST(test_block_download_timeout_just_before_and_at_the_deadline);
    RUN_TEST(test_block_download_timeout_waiting_for_the_end);
    RUN_TEST(test_block_download_wrong_request_at_the_end_aborts_0x05040001);
    RUN_TEST(test_block_download_new_initiate_at_the_end_starts_over);
    RUN_TEST(test_block_upload_value_frames_byte_for_byte);
    RUN_TEST(test_block_upload_without_crc_sends_crc_0);
    RUN_TEST(test_block_upload_100k_domain_with_crc);
    RUN_TEST(test_block_upload_100k_domain_without_crc);
    RUN_TEST(test_block_upload_lost_segment_is_repeated);
    RUN_TEST(test_block_upload_lost_last_segment_is_repeated);
    RUN_TEST(test_block_upload_ack_0_repeats_the_whole_sub_block);
    RUN_TEST(test_block_upload_with_changing_block_sizes);
    RUN_TEST(test_block_upload_of_one_full_sub_block);
    RUN_TEST(test_block_upload_of_an_empty_string);
    RUN_TEST(test_block_upload_block_size_0_aborts_0x05040002);
    RUN_TEST(test_block_upload_block_size_128_aborts_0x05040002);
    RUN_TEST(test_block_upload_ack_with_bad_block_size_aborts_0x05040002);
    RUN_TEST(test_block_upload_ack_beyond_the_sub_block_aborts_0x05040003);
    RUN_TEST(test_block_upload_of_write_only_aborts_0x06010001);
    RUN_TEST(test_block_upload_of_a_missing_sub_index_aborts_0x06090011);
    RUN_TEST(test_pst_switches_to_expedited);
    RUN_TEST(test_pst_switches_to_segmented);
    RUN_TEST(test_pst_below_the_size_keeps_the_block_transfer);
    RUN_TEST(test_pst_0_never_switches);
    RUN_TEST(test_block_upload_timeout_waiting_for_the_ack);
    RUN_TEST(test_block_upload_timeout_waiting_for_the_end);
    RUN_TEST(test_block_upload_timeout_waiting_for_the_start);
    RUN_TEST(test_block_upload_requests_out_of_turn_abort_0x05040001);
    RUN_TEST(test_block_upload_client_abort_is_silent);
    RUN_TEST(test_block_upload_with_less_data_than_announced_aborts_0x08000024);
    RUN_TEST(test_block_upload_waits_for_room_in_the_transmit_queue);
    RUN_TEST(test_block_upload_held_back_after_an_ack_does_not_time_out);
    return UNITY_END();
}
