/* The drive registry (library `drives`, canopen-drive --list-drives): every od/<id>/drive.c is
 * listed, found by its id, tied to its own dictionary and trip table, and starts. */
#include <string.h>

#include "drive_fixture.h"

static drive_fx fx;

void setUp(void) {}
void tearDown(void) {}

static void test_lists_the_five_drives_in_order(void)
{
    const char *ids[] = {"benshaw-rsi", "sourcetronic-st600", "vacon-optc6", "vf-mb1-ecat",
                         "vf-s15"};
    TEST_ASSERT_EQUAL_size_t(5, co_drive_registry_count());
    for (size_t i = 0; i < 5; i++) {
        TEST_ASSERT_EQUAL_STRING(ids[i], co_drive_registry_at(i)->id);
    }
    TEST_ASSERT_NULL(co_drive_registry_at(5));
}

static void test_find_by_id(void)
{
    TEST_ASSERT_EQUAL_STRING("vf-s15", co_drive_registry_find("vf-s15")->id);
    TEST_ASSERT_NULL(co_drive_registry_find("vf-s16"));
    TEST_ASSERT_NULL(co_drive_registry_find(""));
    TEST_ASSERT_NULL(co_drive_registry_find(NULL));
}

static void test_each_description_is_whole_and_starts(void)
{
    for (size_t i = 0; i < co_drive_registry_count(); i++) {
        const co_drive_desc *desc = co_drive_registry_at(i);
        TEST_ASSERT_EQUAL_STRING(desc->id, desc->od->name);
        TEST_ASSERT_TRUE(strlen(desc->title) > 10u);
        TEST_ASSERT_TRUE(desc->trip_count > 0u);
        TEST_ASSERT_TRUE(desc->setting_count <= CO_DRIVE_MAX_SETTINGS);
        fx_start(&fx, desc, 10);
        const co_frame *boot = fx_last(&fx, 0x70A);
        TEST_ASSERT_NOT_NULL(boot);
        TEST_ASSERT_EQUAL_HEX8(0x00, boot->data[0]);
        TEST_ASSERT_EQUAL_UINT64(CO_TIME_NEVER, fx.next); /* an idle drive asks for nothing */
    }
}

static void test_every_trip_code_of_every_table_is_found(void)
{
    for (size_t i = 0; i < co_drive_registry_count(); i++) {
        const co_drive_desc *desc = co_drive_registry_at(i);
        for (uint32_t t = 0; t < desc->trip_count; t++) {
            const co_drive_trip *row = &desc->trips[t];
            if ((row->flags & CO_DRIVE_TRIP_NO_CODE) == 0u) {
                TEST_ASSERT_EQUAL_PTR(row, co_drive_find_trip(desc, row->trip_code));
            }
            TEST_ASSERT_NOT_NULL(co_drive_find_emcy(desc, row->emcy_code));
            TEST_ASSERT_NOT_EQUAL(0, row->error_register);
        }
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_lists_the_five_drives_in_order);
    RUN_TEST(test_find_by_id);
    RUN_TEST(test_each_description_is_whole_and_starts);
    RUN_TEST(test_every_trip_code_of_every_table_is_found);
    return UNITY_END();
}
