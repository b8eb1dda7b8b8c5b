/* boards/template/storage.c, the blank port's two-sector flash storage, on its RAM stand-in: the
 * co_storage contract (include/canopen/node.h) and its atomicity - a save or an erase cut like a
 * power cut after every single flash step leaves the old image or the new one, never a mix or
 * none. The file is included whole, so the test reaches the stand-in's flash and step budget. */
#include "storage.c"

#include "unity.h"

#define HASH 0x1234ABCDu
#define IMAGE_LEN 300u /* not a multiple of PROGRAM_UNIT: the last unit is padded */

static uint8_t image_a[IMAGE_LEN], image_b[IMAGE_LEN];

void setUp(void)
{
    memset(fake_flash, 0, sizeof fake_flash);
    fake_flash_budget = UINT32_MAX;
    for (uint32_t i = 0; i < IMAGE_LEN; i++) {
        image_a[i] = (uint8_t)(i * 7u + 1u);
        image_b[i] = (uint8_t)(i * 13u + 5u);
    }
}

void tearDown(void)
{
}

/* 0: nothing loaded (buf untouched), 'a' or 'b': that image, 'x': anything else. */
static char loaded(void)
{
    uint8_t buf[IMAGE_LEN];
    memset(buf, 0x5A, sizeof buf);
    if (!port_storage.load(port_storage.ctx, HASH, 0, buf, IMAGE_LEN)) {
        for (uint32_t i = 0; i < IMAGE_LEN; i++) {
            TEST_ASSERT_EQUAL_HEX8_MESSAGE(0x5A, buf[i], "a failed load wrote into the buffer");
        }
        return 0;
    }
    if (memcmp(buf, image_a, IMAGE_LEN) == 0) {
        return 'a';
    }
    return memcmp(buf, image_b, IMAGE_LEN) == 0 ? 'b' : 'x';
}

static bool save(const uint8_t *image)
{
    return port_storage.save(port_storage.ctx, HASH, image, IMAGE_LEN);
}

static void test_nothing_stored_loads_nothing(void)
{
    TEST_ASSERT_EQUAL(0, loaded());
}

static void test_saves_alternate_and_the_newest_loads(void)
{
    for (int round = 0; round < 5; round++) {
        TEST_ASSERT_TRUE(save(image_a));
        TEST_ASSERT_EQUAL('a', loaded());
        TEST_ASSERT_TRUE(save(image_b));
        TEST_ASSERT_EQUAL('b', loaded());
    }
}

static void test_a_part_loads_from_its_offset(void)
{
    TEST_ASSERT_TRUE(save(image_a));
    uint8_t buf[10];
    TEST_ASSERT_TRUE(port_storage.load(port_storage.ctx, HASH, 100, buf, sizeof buf));
    TEST_ASSERT_EQUAL_UINT8_ARRAY(image_a + 100, buf, sizeof buf);
    /* beyond the stored image: nothing */
    TEST_ASSERT_FALSE(port_storage.load(port_storage.ctx, HASH, IMAGE_LEN - 5u, buf, sizeof buf));
}

static void test_another_layout_loads_nothing(void)
{
    TEST_ASSERT_TRUE(save(image_a));
    uint8_t buf[IMAGE_LEN];
    TEST_ASSERT_FALSE(port_storage.load(port_storage.ctx, HASH ^ 1u, 0, buf, IMAGE_LEN));
}

static void test_an_image_larger_than_a_sector_is_refused(void)
{
    static uint8_t big[SECTOR_SIZE];
    TEST_ASSERT_TRUE(save(image_a));
    TEST_ASSERT_FALSE(port_storage.save(port_storage.ctx, HASH, big, sizeof big));
    TEST_ASSERT_EQUAL('a', loaded());
}

/* A save cut after every possible number of flash steps, from either sector being the newest:
 * false and the old image, or true and the new one. */
static void test_a_save_cut_at_any_step_keeps_the_old_or_the_new_image(void)
{
    for (int both_used = 0; both_used < 2; both_used++) {
        uint32_t steps = 0;
        bool completed = false;
        for (uint32_t cut = 0; !completed; cut++) {
            setUp();
            TEST_ASSERT_TRUE(save(image_b));
            if (both_used != 0) {
                TEST_ASSERT_TRUE(save(image_a)); /* now sector 1 is the newest */
            } else {
                memset(fake_flash, 0, sizeof fake_flash);
                TEST_ASSERT_TRUE(save(image_a)); /* sector 0 is the newest, sector 1 empty */
            }
            fake_flash_budget = cut;
            bool ok = save(image_b);
            fake_flash_budget = UINT32_MAX;
            TEST_ASSERT_EQUAL(ok ? 'b' : 'a', loaded());
            completed = ok;
            steps = cut;
        }
        /* erase + 300 bytes + a 24-byte header in 8-byte units: 1 + 38 + 3 */
        TEST_ASSERT_EQUAL_UINT32(42u, steps);
    }
}

/* An erase cut after its first step leaves the newest image; a whole one leaves none. */
static void test_an_erase_cut_keeps_the_newest_image_or_none(void)
{
    TEST_ASSERT_TRUE(save(image_a));
    TEST_ASSERT_TRUE(save(image_b));
    fake_flash_budget = 1u;
    TEST_ASSERT_FALSE(port_storage.erase(port_storage.ctx));
    fake_flash_budget = UINT32_MAX;
    TEST_ASSERT_EQUAL('b', loaded());
    TEST_ASSERT_TRUE(port_storage.erase(port_storage.ctx));
    TEST_ASSERT_EQUAL(0, loaded());
    TEST_ASSERT_TRUE(save(image_a));
    TEST_ASSERT_EQUAL('a', loaded());
}

/* A flipped bit anywhere in the newest image makes the older one the stored image. */
static void test_a_damaged_newest_sector_falls_back_to_the_other(void)
{
    TEST_ASSERT_TRUE(save(image_a));
    TEST_ASSERT_TRUE(save(image_b)); /* in sector 1 */
    fake_flash[1][sizeof(sector_header) + 123u] ^= 0x10u;
    TEST_ASSERT_EQUAL('a', loaded());
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_nothing_stored_loads_nothing);
    RUN_TEST(test_saves_alternate_and_the_newest_loads);
    RUN_TEST(test_a_part_loads_from_its_offset);
    RUN_TEST(test_another_layout_loads_nothing);
    RUN_TEST(test_an_image_larger_than_a_sector_is_refused);
    RUN_TEST(test_a_save_cut_at_any_step_keeps_the_old_or_the_new_image);
    RUN_TEST(test_an_erase_cut_keeps_the_newest_image_or_none);
    RUN_TEST(test_a_damaged_newest_sector_falls_back_to_the_other);
    return UNITY_END();
}
