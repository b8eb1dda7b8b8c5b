/* Sourcetronic ST600 CANopen card EC-TX105 (od/sourcetronic-st600): no CiA 402 - command codes
 * in CW 0x2101, state codes in SW 0x2001, 0.01 Hz references, the PDO1 parameter channel, the
 * manual's frames (§3.4.4, §3.4.8, §3.5.2.1, §3.5.3, §3.5.4), P15.26 timeout, fault log, the
 * hidden parameter image and the card's CANopen options.
 * Manual: Sourcetronic "Installation and Setup Guide - PROFIBUS/CANopen communication extension cards". Node 3 as in the manual's examples. */
#include "drive_fixture.h"
#include "drive_trips_sourcetronic_st600.h"

extern const co_drive_desc co_drive_desc_sourcetronic_st600;

static drive_fx fx;

void setUp(void)
{
    fx_start(&fx, &co_drive_desc_sourcetronic_st600, 3);
}

void tearDown(void) {}

/* A PDO1 request, then 500 ms for the drive to act on it (TPDO1, type 255, answers at once:
 * test_section_3_5_1_type_255_answers_every_request_without_disabled_time). */
static void rpdo1(uint16_t code, uint16_t address, uint16_t data)
{
    const uint8_t b[6] = {(uint8_t)code, (uint8_t)(code >> 8), (uint8_t)address,
                          (uint8_t)(address >> 8), (uint8_t)data, (uint8_t)(data >> 8)};
    fx_rx(&fx, 0x203, 6, b);
    fx_advance(&fx, 500000);
}

static void rpdo2(uint16_t cw, uint16_t s1, uint16_t s2, uint16_t s3)
{
    const uint8_t b[8] = {(uint8_t)cw, (uint8_t)(cw >> 8), (uint8_t)s1, (uint8_t)(s1 >> 8),
                          (uint8_t)s2, (uint8_t)(s2 >> 8), (uint8_t)s3, (uint8_t)(s3 >> 8)};
    fx_rx(&fx, 0x303, 8, b);
}

static uint16_t sw(void)
{
    return fx_u16(&fx, 0x2001, 0);
}

/* Asserts the last TPDO1 (the parameter channel's answer). */
static void expect_response(uint16_t response, uint16_t error, uint16_t data)
{
    const co_frame *f = fx_last(&fx, 0x183);
    TEST_ASSERT_NOT_NULL_MESSAGE(f, "no TPDO1");
    TEST_ASSERT_EQUAL_HEX16(response, (uint16_t)(f->data[0] | (f->data[1] << 8)));
    TEST_ASSERT_EQUAL_HEX16(error, (uint16_t)(f->data[2] | (f->data[3] << 8)));
    TEST_ASSERT_EQUAL_HEX16(data, (uint16_t)(f->data[4] | (f->data[5] << 8)));
}

/* §3.5.3 step 1: run command and frequency from CANopen, setting 2 = set frequency. */
static void communication_control(void)
{
    fx_nmt(&fx, 0x01);
    rpdo1(2, 0x0001, 2); /* P00.01 = 2 */
    rpdo1(2, 0x0002, 1); /* P00.02 = 1 */
    rpdo1(2, 0x0006, 9); /* P00.06 = 9 */
    rpdo1(2, 0x0F03, 1); /* P15.03 = 1 */
}

static void running_at(uint16_t centihz)
{
    communication_control();
    rpdo2(0x0001, 0, centihz, 0);
    fx_advance(&fx, 12000000);
    TEST_ASSERT_EQUAL_INT32(centihz, fx.d.motor.frequency);
}

static void test_power_up_status_word_and_no_cia402(void)
{
    TEST_ASSERT_EQUAL_HEX16(0x0103, sw());
    uint32_t v;
    TEST_ASSERT_EQUAL_HEX32(0x06020000, fx_sdo_read(&fx, 0x6000, 0, &v)); /* §3.4.9 */
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x1000, 0, &v));
    TEST_ASSERT_EQUAL_HEX32(0, v);
}

static void test_parameter_image_is_not_visible_by_sdo(void)
{
    uint32_t v;
    TEST_ASSERT_EQUAL_HEX32(0x06020000, fx_sdo_read(&fx, 0x4001, 0, &v));
    TEST_ASSERT_EQUAL_HEX32(0x06020000, fx_sdo_write(&fx, 0x4001, 0, 2, 2));
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x4001, 0));
    TEST_ASSERT_EQUAL_UINT16(9, fx_u16(&fx, 0x5300, 0)); /* P19.00: card in slot 1 */
}

/* B15: every SDO request on 0x4000-0x5FFF is answered as for an object the card does not have,
 * whatever its sub-index, size or value would have been refused for. */
static void test_parameter_image_aborts_0x06020000_before_any_other_check(void)
{
    static const uint8_t requests[][8] = {
        {0x2B, 0x01, 0x40, 0x03, 0x00, 0x00, 0x00, 0x00}, /* unknown sub-index 3 */
        {0x23, 0x01, 0x40, 0x00, 0x01, 0x00, 0x00, 0x00}, /* 4 bytes into a U16 */
        {0x2B, 0x02, 0x53, 0x00, 0xFF, 0xFF, 0x00, 0x00}, /* P19.02: read-only, out of range */
        {0x2B, 0x01, 0x40, 0x00, 0xFF, 0xFF, 0x00, 0x00}, /* P00.01 above its high limit */
        {0x2B, 0x01, 0x40, 0x00, 0x02, 0x00, 0x00, 0x00}, /* a good value */
        {0x21, 0x01, 0x40, 0x00, 0x09, 0x00, 0x00, 0x00}, /* segmented download, 9 bytes */
        {0x40, 0x01, 0x40, 0x00, 0x00, 0x00, 0x00, 0x00}, /* upload */
        {0x40, 0x01, 0x40, 0x07, 0x00, 0x00, 0x00, 0x00}, /* upload of an unknown sub-index */
        {0xC6, 0x01, 0x40, 0x00, 0x02, 0x00, 0x00, 0x00}, /* block download, size 2 */
        {0xA4, 0x01, 0x40, 0x00, 0x7F, 0x00, 0x00, 0x00}, /* block upload */
        {0x40, 0x00, 0x40, 0x00, 0x00, 0x00, 0x00, 0x00}, /* 0x4000: first of the range */
        {0x40, 0xFF, 0x5F, 0x00, 0x00, 0x00, 0x00, 0x00}, /* 0x5FFF: last of the range */
    };
    fx_nmt(&fx, 0x01);
    for (uint32_t i = 0; i < sizeof requests / sizeof requests[0]; i++) {
        fx_clear(&fx);
        fx_rx(&fx, 0x603, 8, requests[i]);
        const co_frame *f = fx_last(&fx, 0x583);
        TEST_ASSERT_NOT_NULL(f);
        const uint8_t abort[8] = {0x80, requests[i][1], requests[i][2], requests[i][3],
                                  0x00, 0x00, 0x02, 0x06};
        TEST_ASSERT_EQUAL_HEX8_ARRAY_MESSAGE(abort, f->data, 8, "abort 0x06020000");
    }
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x4001, 0));    /* untouched */
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x5302, 0));
    /* next to the range the dictionary answers as usual */
    uint32_t v;
    TEST_ASSERT_EQUAL_HEX32(0x06090011, fx_sdo_read(&fx, 0x2101, 1, &v));
    TEST_ASSERT_EQUAL_HEX32(0x06020000, fx_sdo_read(&fx, 0x6000, 0, &v));
}

static void test_commands_need_the_communication_channel(void)
{
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2101, 0, 1, 2)); /* stored, not executed */
    fx_advance(&fx, 1000000);
    TEST_ASSERT_EQUAL_HEX16(0x0103, sw());
    TEST_ASSERT_EQUAL_UINT16(1, fx_u16(&fx, 0x2101, 0));
}

static void test_manual_parameter_write_example(void)
{
    fx_nmt(&fx, 0x01);
    fx_clear(&fx);
    const uint8_t req[6] = {0x02, 0x00, 0x0D, 0x0F, 0x01, 0x00}; /* P15.13 := 1 */
    fx_rx(&fx, 0x203, 6, req);
    expect_response(1, 0, 1);
    TEST_ASSERT_EQUAL_UINT16(1, fx_u16(&fx, 0x4F0D, 0));
    TEST_ASSERT_EQUAL_UINT16(1, fx_u16(&fx, 0x2000, 0));
    TEST_ASSERT_EQUAL_UINT16(1, fx_u16(&fx, 0x2000, 2));
}

static void test_parameter_channel_answers(void)
{
    fx_nmt(&fx, 0x01);
    rpdo1(1, 0x0F1A, 0); /* read P15.26 */
    expect_response(1, 0, 0);
    rpdo1(1, 0x0A63, 0); /* unknown address */
    expect_response(3, 0x02, 0);
    rpdo1(2, 0x071B, 5); /* P07.27 is read-only */
    expect_response(3, 0x07, 0);
    rpdo1(2, 0x0001, 3); /* P00.01 0..2 */
    expect_response(3, 0x04, 0);
    TEST_ASSERT_EQUAL_UINT16(0, fx_u16(&fx, 0x4001, 0));
    rpdo1(4, 0x0001, 1); /* 'RAM and EEPROM' is reserved */
    expect_response(3, 0x01, 0);
    fx_clear(&fx);
    rpdo1(0, 0, 0);
    expect_response(0, 0, 0);
    /* §3.5.2.2: bytes 6 and 7 are reserved and 0; the manual's answer has 8 bytes */
    const co_frame *f = fx_last(&fx, 0x183);
    TEST_ASSERT_EQUAL_UINT8(8, f->dlc);
    TEST_ASSERT_EQUAL_HEX8(0, f->data[6]);
    TEST_ASSERT_EQUAL_HEX8(0, f->data[7]);
}

static void test_parameter_writes_refused_while_faulty_reads_work(void)
{
    fx_nmt(&fx, 0x01);
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x01, fx.now));
    fx_advance(&fx, 1000);
    rpdo1(2, 0x0001, 2);
    expect_response(3, 0x01, 0);
    rpdo1(1, 0x071B, 0);
    expect_response(1, 0, 1); /* P07.27 = 1 */
}

static void test_section_3_5_3_recipe_runs_forward_at_50_hz(void)
{
    communication_control();
    fx_clear(&fx);
    const uint8_t frame[8] = {0x01, 0x00, 0x00, 0x00, 0x88, 0x13, 0x00, 0x00};
    fx_rx(&fx, 0x303, 8, frame);
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT32(2500, fx.d.motor.frequency); /* 0 <-> 50 Hz in 10 s */
    TEST_ASSERT_EQUAL_HEX16(0x4101, sw());
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT32(5000, fx.d.motor.frequency);
    const co_frame *f = fx_last(&fx, 0x283);
    TEST_ASSERT_NOT_NULL(f);
    TEST_ASSERT_EQUAL_HEX8(0x01, f->data[0]);
    TEST_ASSERT_EQUAL_HEX8(0x41, f->data[1]);
}

static void test_section_3_5_4_returned_values(void)
{
    running_at(5000);
    rpdo1(2, 0x0F0D, 1); /* P15.13 = 1: running frequency */
    rpdo1(2, 0x0F0E, 4); /* P15.14 = 4: output voltage */
    fx_advance(&fx, 600000);
    uint32_t v;
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x2000, 3, &v));
    TEST_ASSERT_EQUAL_UINT32(0x1388, v);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x2000, 4, &v));
    TEST_ASSERT_EQUAL_UINT32(0x017C, v); /* 380 V */
    const co_frame *f = fx_last(&fx, 0x283);
    TEST_ASSERT_NOT_NULL(f);
    const uint8_t expected[8] = {0x01, 0x41, 0x88, 0x13, 0x7C, 0x01, 0x00, 0x00};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expected, f->data, 8); /* the manual's with P00.01 = 2 */
}

/* The load (NOTES B17): returned values 5 output current (0.1 A of the model's 5.0 A motor),
 * 6 output torque and 7 output power (0.1 %); 0 once the output is off. */
static void test_load_shows_in_returned_values_5_6_7(void)
{
    running_at(2500); /* 25.00 Hz */
    rpdo1(2, 0x0F0D, 5);
    rpdo1(2, 0x0F0E, 6);
    rpdo1(2, 0x0F0F, 7);
    TEST_ASSERT_TRUE(co_drive_set_load(&fx.d, 80, fx.now));
    uint32_t v;
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x2000, 3, &v));
    TEST_ASSERT_EQUAL_UINT32(41, v);  /* 82 % of 5.0 A = 4.1 A */
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x2000, 4, &v));
    TEST_ASSERT_EQUAL_UINT32(800, v); /* 80.0 % */
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x2000, 5, &v));
    TEST_ASSERT_EQUAL_UINT32(400, v); /* 80 % torque at half speed */
    rpdo2(0x0006, 0, 2500, 0);        /* coast stop: output off */
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x2000, 3, &v));
    TEST_ASSERT_EQUAL_UINT32(0, v);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x2000, 4, &v));
    TEST_ASSERT_EQUAL_UINT32(0, v);
}

static void test_reverse_stop_and_coast(void)
{
    running_at(2000);
    rpdo2(0x0002, 0, 2000, 0); /* reverse: through 0 Hz */
    fx_advance(&fx, 4000000);
    TEST_ASSERT_EQUAL_INT32(0, fx.d.motor.frequency);
    fx_advance(&fx, 4000000);
    TEST_ASSERT_EQUAL_INT32(-2000, fx.d.motor.frequency);
    TEST_ASSERT_EQUAL_HEX8(0x02, (uint8_t)sw());
    rpdo2(0x0005, 0, 2000, 0); /* stop: ramp down, still 'reverse running' */
    fx_advance(&fx, 2000000);
    TEST_ASSERT_EQUAL_INT32(-1000, fx.d.motor.frequency);
    TEST_ASSERT_EQUAL_HEX8(0x02, (uint8_t)sw());
    fx_advance(&fx, 2000000);
    TEST_ASSERT_EQUAL_HEX8(0x03, (uint8_t)sw());
    rpdo2(0x0001, 0, 2000, 0);
    fx_advance(&fx, 1000000);
    rpdo2(0x0006, 0, 2000, 0); /* coast: stopped at once */
    TEST_ASSERT_EQUAL_INT32(0, fx.d.motor.frequency);
    TEST_ASSERT_EQUAL_HEX8(0x03, (uint8_t)sw());
}

static void test_jogging(void)
{
    communication_control();
    rpdo2(0x0003, 0, 3000, 0); /* forward jog: 5.00 Hz */
    fx_advance(&fx, 2000000);
    TEST_ASSERT_EQUAL_INT32(500, fx.d.motor.frequency);
    TEST_ASSERT_EQUAL_HEX8(0x01, (uint8_t)sw());
    rpdo2(0x0008, 0, 3000, 0); /* stop jogging */
    fx_advance(&fx, 2000000);
    TEST_ASSERT_EQUAL_HEX8(0x03, (uint8_t)sw());
    rpdo2(0x0004, 0, 3000, 0); /* reverse jog, then normal running */
    fx_advance(&fx, 2000000);
    TEST_ASSERT_EQUAL_INT32(-500, fx.d.motor.frequency);
    rpdo2(0x0001, 0, 3000, 0);
    fx_advance(&fx, 8000000);
    TEST_ASSERT_EQUAL_INT32(3000, fx.d.motor.frequency);
    rpdo2(0x0003, 0, 3000, 0); /* jog while running: ignored */
    fx_advance(&fx, 1000000);
    TEST_ASSERT_EQUAL_INT32(3000, fx.d.motor.frequency);
}

static void test_setting_out_of_range_is_ignored(void)
{
    running_at(2000);
    rpdo2(0x0001, 0, 6000, 0); /* above Fmax: previous value kept */
    fx_advance(&fx, 5000000);
    TEST_ASSERT_EQUAL_INT32(2000, fx.d.motor.frequency);
}

static void test_fault_emcy_of_section_3_4_8_and_reset_by_code_7(void)
{
    running_at(2000);
    fx_clear(&fx);
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x01, fx.now)); /* OUT1 */
    const co_frame *f = fx_last(&fx, 0x83);
    TEST_ASSERT_NOT_NULL(f);
    const uint8_t expected[8] = {0x00, 0x30, 0x04, 0x01, 0x00, 0x00, 0x00, 0x00};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expected, f->data, 8);
    fx_advance(&fx, 1000);
    TEST_ASSERT_EQUAL_HEX8(0x04, (uint8_t)sw());
    TEST_ASSERT_EQUAL_INT32(0, fx.d.motor.frequency);
    TEST_ASSERT_EQUAL_UINT16(1, fx_u16(&fx, 0x471B, 0));
    co_drive_clear_fault_cause(&fx.d);
    rpdo2(0x0001, 0, 2000, 0); /* other codes are ignored while faulty */
    TEST_ASSERT_EQUAL_HEX8(0x04, (uint8_t)sw());
    fx_clear(&fx);
    rpdo2(0x0007, 0, 2000, 0);
    TEST_ASSERT_EQUAL_HEX8(0x03, (uint8_t)sw());
    f = fx_last(&fx, 0x83);
    TEST_ASSERT_NOT_NULL(f);
    const uint8_t reset[8] = {0};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(reset, f->data, 8);
    TEST_ASSERT_EQUAL_UINT16(1, fx_u16(&fx, 0x471B, 0)); /* kept after the reset */
    TEST_ASSERT_EQUAL_HEX32(0x3000, fx_u32(&fx, 0x1003, 1));
}

static void test_fault_log_shifts(void)
{
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x01, fx.now));
    fx_advance(&fx, 1000);
    co_drive_clear_fault_cause(&fx.d);
    TEST_ASSERT_TRUE(co_drive_fault_reset(&fx.d, fx.now));
    TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, 0x3C, fx.now));
    TEST_ASSERT_EQUAL_UINT16(0x3C, fx_u16(&fx, 0x471B, 0));
    TEST_ASSERT_EQUAL_UINT16(0x01, fx_u16(&fx, 0x471C, 0));
}

static void test_every_trip_of_the_table(void)
{
    for (uint32_t i = 0; i < DRIVE_TRIP_COUNT_SOURCETRONIC_ST600; i++) {
        const co_drive_trip *t = &co_drive_trips_sourcetronic_st600[i];
        fx_start(&fx, &co_drive_desc_sourcetronic_st600, 3);
        fx_clear(&fx);
        TEST_ASSERT_TRUE(co_drive_inject_fault(&fx.d, t->trip_code, fx.now));
        fx_expect_emcy(&fx, t->emcy_code, t->error_register, (uint8_t)t->trip_code);
        TEST_ASSERT_EQUAL_HEX8(t->error_register, fx_u8(&fx, 0x1001, 0));
        TEST_ASSERT_EQUAL_UINT16(t->trip_code, fx_u16(&fx, 0x471B, 0));
    }
}

static void test_p15_26_timeout_trips_e_can(void)
{
    communication_control();
    rpdo1(2, 0x0F1A, 5); /* P15.26 = 0.5 s */
    rpdo2(0x0001, 0, 1000, 0);
    fx_clear(&fx);
    fx_advance(&fx, 499999);
    TEST_ASSERT_EQUAL_HEX8(0x01, (uint8_t)sw());
    fx_advance(&fx, 1);
    const co_frame *f = fx_last(&fx, 0x83);
    TEST_ASSERT_NOT_NULL(f);
    const uint8_t expected[8] = {0x00, 0x81, 0x10, 0x1F, 0x00, 0x00, 0x00, 0x00};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expected, f->data, 8);
    fx_advance(&fx, 1000);
    TEST_ASSERT_EQUAL_HEX8(0x04, (uint8_t)sw());
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x2101, 0, 7, 2)); /* CW 7 by SDO */
    TEST_ASSERT_EQUAL_HEX8(0x03, (uint8_t)sw());
    fx_advance(&fx, 2000000); /* not armed again until the next RPDO */
    TEST_ASSERT_EQUAL_HEX8(0x03, (uint8_t)sw());
}

static void test_guarding_first_answer_has_toggle_1(void)
{
    fx_nmt(&fx, 0x01);
    fx_clear(&fx);
    fx_rtr(&fx, 0x703);
    TEST_ASSERT_EQUAL_HEX8(0x85, fx_last(&fx, 0x703)->data[0]); /* §3.4.4 */
    fx_clear(&fx);
    fx_rtr(&fx, 0x703);
    TEST_ASSERT_EQUAL_HEX8(0x05, fx_last(&fx, 0x703)->data[0]);
}

static void test_heartbeat_loss_is_an_emcy_not_a_trip(void)
{
    running_at(1000);
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x1016, 1, (0x7Fu << 16) | 100u, 4));
    const uint8_t op = 0x05;
    fx_rx(&fx, 0x77F, 1, &op);
    fx_clear(&fx);
    fx_advance(&fx, 100000);
    fx_expect_emcy(&fx, 0x8130, 0x10, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x01, (uint8_t)sw());
}

/* §3.4.9: the master writes TPDO2's disabled time while TPDO2 is in use, and the card answers
 * with success (NOTES B8, "Disabled time written while the PDO is valid"). */
static void test_section_3_4_9_disabled_time_written_while_tpdo2_is_valid(void)
{
    communication_control(); /* OPERATIONAL, TPDO2 (0x283) valid and sending */
    const uint8_t write[8] = {0x2B, 0x01, 0x18, 0x03, 0xE8, 0x03, 0x00, 0x00};
    fx_clear(&fx);
    fx_rx(&fx, 0x603, 8, write);
    const uint8_t ok[8] = {0x60, 0x01, 0x18, 0x03, 0x00, 0x00, 0x00, 0x00};
    const co_frame *f = fx_last(&fx, 0x583);
    TEST_ASSERT_NOT_NULL(f);
    TEST_ASSERT_EQUAL_UINT8(8, f->dlc);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(ok, f->data, 8);
    /* The manual's read of the same UNSIGNED16 answers 4 bytes (0x43, NOTES choice 2). */
    const uint8_t read[8] = {0x40, 0x01, 0x18, 0x03, 0x00, 0x00, 0x00, 0x00};
    fx_clear(&fx);
    fx_rx(&fx, 0x603, 8, read);
    const uint8_t answer[8] = {0x43, 0x01, 0x18, 0x03, 0xE8, 0x03, 0x00, 0x00};
    f = fx_last(&fx, 0x583);
    TEST_ASSERT_NOT_NULL(f);
    TEST_ASSERT_EQUAL_UINT8(8, f->dlc);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(answer, f->data, 8);
    /* §3.6 Examples 3/4: a 2-byte manufacturer object answers 0x4B. */
    const uint8_t read_sw[8] = {0x40, 0x01, 0x20, 0x00, 0x00, 0x00, 0x00, 0x00};
    fx_clear(&fx);
    fx_rx(&fx, 0x603, 8, read_sw);
    f = fx_last(&fx, 0x583);
    TEST_ASSERT_NOT_NULL(f);
    TEST_ASSERT_EQUAL_HEX8(0x4B, f->data[0]);
    TEST_ASSERT_EQUAL_HEX32(0x283u, fx_u32(&fx, 0x1801, 1)); /* still valid */
}

/* §3.5.1 (255): "after receiving a PDO2 Rx command, the slave station transmits a PDO2 Tx
 * command"; the disabled time is named for 254 only (NOTES B8). TPDO1 (255, disabled time 500 ms
 * by default) answers two requests 10 ms apart at once each. */
static void test_section_3_5_1_type_255_answers_every_request_without_disabled_time(void)
{
    fx_nmt(&fx, 0x01);
    fx_clear(&fx);
    const uint8_t read_p15_26[6] = {0x01, 0x00, 0x1A, 0x0F, 0x00, 0x00};
    const uint8_t read_unknown[6] = {0x01, 0x00, 0x63, 0x0A, 0x00, 0x00};
    fx_rx(&fx, 0x203, 6, read_p15_26);
    TEST_ASSERT_EQUAL_UINT32(1, fx_count(&fx, 0x183));
    expect_response(1, 0, 0);
    fx_advance(&fx, 10000);
    fx_rx(&fx, 0x203, 6, read_unknown);
    TEST_ASSERT_EQUAL_UINT32(2, fx_count(&fx, 0x183));
    expect_response(3, 0x02, 0);
}

static void test_tpdo_disabled_time_is_in_ms(void)
{
    communication_control();
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x1801, 3, 1000, 2)); /* 1000 ms */
    uint32_t v;
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_read(&fx, 0x1801, 3, &v));
    TEST_ASSERT_EQUAL_UINT32(1000, v);
    rpdo1(2, 0x0F0D, 1); /* returned value 1: running frequency (changes while ramping) */
    rpdo2(0x0001, 0, 5000, 0);
    fx_clear(&fx);
    fx_advance(&fx, 5000000);
    uint32_t n = fx_count(&fx, 0x283);
    TEST_ASSERT_TRUE(n >= 4u && n <= 6u); /* one per 1000 ms, not per tick */
}

/* §3.5.1: "if the event timer of PDO2 Tx is set to 200, the slave station transmits a PDO2 Tx
 * command at the interval of 200 ms"; the disabled time (default 500) paces the sends on change
 * ("when the value of the event timer is zero"), not the timer's. */
static void test_section_3_5_1_event_timer_200_ms_beats_the_disabled_time(void)
{
    communication_control();
    rpdo1(2, 0x0F0D, 1); /* returned value 1: running frequency, changing while it ramps */
    rpdo2(0x0001, 0, 5000, 0);
    TEST_ASSERT_EQUAL_UINT16(500, fx_u16(&fx, 0x1801, 3));
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x1801, 5, 200, 2));
    fx_advance(&fx, 1000000);
    fx_clear(&fx);
    fx_advance(&fx, 2000000); /* still ramping: the data changes on every tick */
    TEST_ASSERT_EQUAL_UINT32(10, fx_count(&fx, 0x283));
    TEST_ASSERT_NOT_EQUAL(0, fx.d.motor.frequency);
    TEST_ASSERT_TRUE(fx.d.motor.frequency < 5000);
    /* event timer 0 again: the disabled time paces the changes */
    TEST_ASSERT_EQUAL_HEX32(0, fx_sdo_write(&fx, 0x1801, 5, 0, 2));
    fx_advance(&fx, 1000000);
    fx_clear(&fx);
    fx_advance(&fx, 2000000);
    uint32_t n = fx_count(&fx, 0x283);
    TEST_ASSERT_TRUE(n >= 3u && n <= 5u); /* one per 500 ms */
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_power_up_status_word_and_no_cia402);
    RUN_TEST(test_parameter_image_is_not_visible_by_sdo);
    RUN_TEST(test_parameter_image_aborts_0x06020000_before_any_other_check);
    RUN_TEST(test_commands_need_the_communication_channel);
    RUN_TEST(test_manual_parameter_write_example);
    RUN_TEST(test_parameter_channel_answers);
    RUN_TEST(test_parameter_writes_refused_while_faulty_reads_work);
    RUN_TEST(test_section_3_5_3_recipe_runs_forward_at_50_hz);
    RUN_TEST(test_section_3_5_4_returned_values);
    RUN_TEST(test_load_shows_in_returned_values_5_6_7);
    RUN_TEST(test_reverse_stop_and_coast);
    RUN_TEST(test_jogging);
    RUN_TEST(test_setting_out_of_range_is_ignored);
    RUN_TEST(test_fault_emcy_of_section_3_4_8_and_reset_by_code_7);
    RUN_TEST(test_fault_log_shifts);
    RUN_TEST(test_every_trip_of_the_table);
    RUN_TEST(test_p15_26_timeout_trips_e_can);
    RUN_TEST(test_guarding_first_answer_has_toggle_1);
    RUN_TEST(test_heartbeat_loss_is_an_emcy_not_a_trip);
    RUN_TEST(test_section_3_4_9_disabled_time_written_while_tpdo2_is_valid);
    RUN_TEST(test_section_3_5_1_type_255_answers_every_request_without_disabled_time);
    RUN_TEST(test_tpdo_disabled_time_is_in_ms);
    RUN_TEST(test_section_3_5_1_event_timer_200_ms_beats_the_disabled_time);
    return UNITY_END();
}
