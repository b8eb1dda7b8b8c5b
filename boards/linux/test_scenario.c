/* Scenario files (scenario.h) on a virtual clock: the parser's answers to bad files (file, line,
 * reason), time steps at their deadlines, conditions, "after" delays, file order for steps due
 * together, and a command that makes another step's condition hold. */
#include <stdio.h>
#include <string.h>

#include "scenario.h"
#include "unity.h"

#define S 1000000u /* one second in microseconds */

/* A fake simulator: nodes 5 and 6, their state, and the commands run. */
typedef struct world {
    scenario_view view[2];
    char ran[16][SCENARIO_COMMAND_MAX];
    uint64_t ran_at[16];
    unsigned ran_line[16];
    size_t ran_count;
} world;

static world w;
static scenario sc;

static int slot(unsigned node)
{
    return node == 5u ? 0 : node == 6u ? 1 : -1;
}

static bool observe(void *ctx, unsigned node, scenario_view *view)
{
    world *wd = ctx;
    int i = slot(node);
    if (i < 0) {
        return false;
    }
    if (view != NULL) {
        *view = wd->view[i];
    }
    return true;
}

static void run(void *ctx, const scenario_step *step, char *command, uint64_t now)
{
    world *wd = ctx;
    TEST_ASSERT_LESS_THAN(16, wd->ran_count);
    snprintf(wd->ran[wd->ran_count], SCENARIO_COMMAND_MAX, "%s", command);
    wd->ran_at[wd->ran_count] = now;
    wd->ran_line[wd->ran_count++] = step->line;
    if (strncmp(command, "fault 5", 7) == 0) {
        wd->view[0].fault = true; /* as the drive would: the fault is active at once */
        wd->view[0].state = "FAULT";
    }
    if (strcmp(command, "nmt 5 start") == 0) {
        wd->view[0].nmt = "OPERATIONAL";
    }
}

void setUp(void)
{
    memset(&w, 0, sizeof w);
    w.view[0] = (scenario_view){"SWITCH ON DISABLED", "PRE-OPERATIONAL", 0, false};
    w.view[1] = (scenario_view){"SWITCH ON DISABLED", "PRE-OPERATIONAL", 0, false};
}

void tearDown(void)
{
}

static void expect_error(const char *text, const char *message)
{
    char err[300] = "";
    TEST_ASSERT_FALSE_MESSAGE(scenario_parse(&sc, text, "s.txt", observe, &w, err, sizeof err),
                              text);
    TEST_ASSERT_EQUAL_STRING(message, err);
}

static void test_parse_errors_name_file_line_and_reason(void)
{
    expect_error("at 1: nmt 5 start\nat x: nmt 5 start\n",
                 "s.txt:2: 'at' wants SECONDS (e.g. at 2.5: ...)");
    expect_error("at 1 nmt 5 start", "s.txt:1: no ':' before the command (at SECONDS: COMMAND, "
                                     "or when NODE CONDITION [after SECONDS]: COMMAND)");
    expect_error("# c\n\nsoon: nmt 5 start", "s.txt:3: a step starts with 'at' or 'when', not "
                                             "'soon'");
    expect_error("at 1: jump 5", "s.txt:1: unknown command 'jump'");
    expect_error("at 1: fault 9 1", "s.txt:1: no node 9 in this simulator");
    expect_error("at 1: fault", "s.txt:1: usage: fault NODE TRIP");
    expect_error("at 1: fault 5", "s.txt:1: usage: fault NODE TRIP");
    expect_error("at 1: fault x 1", "s.txt:1: 'x' is not a node-ID (1..127)");
    expect_error("at 1: nmt 5 go", "s.txt:1: usage: nmt NODE start|stop|preop|reset-node|reset-comm");
    expect_error("at 1: mains 5 maybe", "s.txt:1: usage: mains NODE on|off");
    expect_error("at 1: load 5", "s.txt:1: usage: load NODE PERCENT (0..200)");
    expect_error("at 1: load 5 201", "s.txt:1: '201' is not a load (0..200 % of rated torque)");
    expect_error("at 1: load 5 -1", "s.txt:1: '-1' is not a load (0..200 % of rated torque)");
    expect_error("at 1: load 5 8O", "s.txt:1: '8O' is not a load (0..200 % of rated torque)");
    expect_error("at 1: load 5 99999999999999999999999",
                 "s.txt:1: '99999999999999999999' is not a load (0..200 % of rated torque)");
    expect_error("at 1: load 7 50", "s.txt:1: no node 7 in this simulator");
    expect_error("at 1: quit now", "s.txt:1: usage: quit");
    expect_error("at 1:", "s.txt:1: no command after ':'");
    expect_error("at 1.0000001: quit", "s.txt:1: 'at' wants SECONDS (e.g. at 2.5: ...)");
    expect_error("when 7 fault: quit", "s.txt:1: no node 7 in this simulator");
    expect_error("when 5 state RUNNING: quit",
                 "s.txt:1: 'state' wants a CiA 402 state, spaces as '_' (e.g. OPERATION_ENABLED)");
    expect_error("when 5 nmt RUN: quit", "s.txt:1: 'nmt' wants INITIALISING, PRE-OPERATIONAL, "
                                         "OPERATIONAL or STOPPED");
    expect_error("when 5 actual => 3: quit", "s.txt:1: 'actual' wants >=, <=, >, <, == or != and "
                                             "a number (e.g. actual >= 1500)");
    expect_error("when 5 actual >= 1.5: quit", "s.txt:1: '1.5' is not a number");
    expect_error("when 5 speed: quit", "s.txt:1: unknown condition 'speed' (state, nmt, actual, "
                                       "fault, no-fault)");
    expect_error("when 5 fault later 2: quit", "s.txt:1: unexpected 'later' before ':'");
    expect_error("when 5 fault after x: quit", "s.txt:1: 'after' wants SECONDS");
    expect_error("at 1: quit\nat 2: qu\x01it", "s.txt:2: byte 0x01 is not text");
    char longline[400];
    memset(longline, 'a', sizeof longline - 1u);
    longline[sizeof longline - 1u] = '\0';
    expect_error(longline, "s.txt:1: line longer than 255 characters");
}

static void test_parse_accepts_every_form(void)
{
    char err[300] = "";
    const char *text = "# a trip 2 s after the drive reaches speed\n"
                       "at 0.5: nmt 5 start   # comment\n"
                       "at 1500ms: mute 6\n"
                       "at 2s: unmute 6\r\n"
                       "when 5 state operation_enabled: status 5\n"
                       "when 5 actual >= 1500 after 2: fault 5 0x01\n"
                       "when 0x6 nmt OPERATIONAL after 0.25: mains 6 off\n"
                       "when 5 fault: clear 5\n"
                       "when 5 no-fault: nodes\n"
                       "at 30: quit";
    TEST_ASSERT_TRUE_MESSAGE(scenario_parse(&sc, text, "s.txt", observe, &w, err, sizeof err), err);
    TEST_ASSERT_EQUAL_UINT(9, sc.count);
    TEST_ASSERT_EQUAL_UINT64(500000u, sc.steps[0].delay_us);
    TEST_ASSERT_EQUAL_UINT64(1500000u, sc.steps[1].delay_us);
    TEST_ASSERT_EQUAL_STRING("unmute 6", sc.steps[2].command);
    TEST_ASSERT_EQUAL_STRING("OPERATION ENABLED", sc.steps[3].name);
    TEST_ASSERT_EQUAL_INT(SCENARIO_COND_ACTUAL, sc.steps[4].cond);
    TEST_ASSERT_EQUAL_INT(1500, sc.steps[4].value);
    TEST_ASSERT_EQUAL_UINT64(2u * S, sc.steps[4].delay_us);
    TEST_ASSERT_EQUAL_UINT8(6, sc.steps[5].node);
    TEST_ASSERT_EQUAL_UINT(10, sc.steps[8].line);
}

static void test_time_steps_run_at_their_deadline_in_file_order(void)
{
    char err[300] = "";
    const char *text = "at 2: nmt 5 start\nat 1: mute 6\nat 2: unmute 6\n";
    TEST_ASSERT_TRUE(scenario_parse(&sc, text, "s.txt", observe, &w, err, sizeof err));
    uint64_t t0 = 1000u * S; /* any start */
    scenario_start(&sc, t0);
    TEST_ASSERT_EQUAL_UINT64(t0 + 1u * S, scenario_tick(&sc, t0, observe, run, &w));
    TEST_ASSERT_EQUAL_UINT(0, w.ran_count);
    /* a tick just before the deadline runs nothing */
    TEST_ASSERT_EQUAL_UINT64(t0 + 1u * S, scenario_tick(&sc, t0 + S - 1u, observe, run, &w));
    TEST_ASSERT_EQUAL_UINT(0, w.ran_count);
    TEST_ASSERT_EQUAL_UINT64(t0 + 2u * S, scenario_tick(&sc, t0 + S, observe, run, &w));
    TEST_ASSERT_EQUAL_UINT(1, w.ran_count);
    TEST_ASSERT_EQUAL_STRING("mute 6", w.ran[0]);
    /* late (the loop woke after both were due): both, in file order */
    TEST_ASSERT_EQUAL_UINT64(UINT64_MAX, scenario_tick(&sc, t0 + 3u * S, observe, run, &w));
    TEST_ASSERT_EQUAL_UINT(3, w.ran_count);
    TEST_ASSERT_EQUAL_STRING("nmt 5 start", w.ran[1]);
    TEST_ASSERT_EQUAL_STRING("unmute 6", w.ran[2]);
    /* nothing runs twice */
    TEST_ASSERT_EQUAL_UINT64(UINT64_MAX, scenario_tick(&sc, t0 + 9u * S, observe, run, &w));
    TEST_ASSERT_EQUAL_UINT(3, w.ran_count);
}

static void test_condition_then_after_delay_once(void)
{
    char err[300] = "";
    const char *text = "when 5 actual >= 1500 after 2: fault 5 0x01\n"
                       "when 5 state FAULT: clear 5\n"
                       "when 6 nmt OPERATIONAL: mute 6\n";
    TEST_ASSERT_TRUE(scenario_parse(&sc, text, "s.txt", observe, &w, err, sizeof err));
    scenario_start(&sc, 0);
    TEST_ASSERT_EQUAL_UINT64(UINT64_MAX, scenario_tick(&sc, 10u * S, observe, run, &w));
    w.view[0].actual = 1499;
    TEST_ASSERT_EQUAL_UINT64(UINT64_MAX, scenario_tick(&sc, 11u * S, observe, run, &w));
    w.view[0].actual = 1500; /* reaches speed at 12 s: the trip is due at 14 s */
    TEST_ASSERT_EQUAL_UINT64(14u * S, scenario_tick(&sc, 12u * S, observe, run, &w));
    w.view[0].actual = 1400; /* the condition held once: that is enough */
    TEST_ASSERT_EQUAL_UINT64(14u * S, scenario_tick(&sc, 13u * S, observe, run, &w));
    TEST_ASSERT_EQUAL_UINT(0, w.ran_count);
    /* at 14 s the trip runs, and the FAULT it causes is seen in the same tick */
    TEST_ASSERT_EQUAL_UINT64(UINT64_MAX, scenario_tick(&sc, 14u * S, observe, run, &w));
    TEST_ASSERT_EQUAL_UINT(2, w.ran_count);
    TEST_ASSERT_EQUAL_STRING("fault 5 0x01", w.ran[0]);
    TEST_ASSERT_EQUAL_STRING("clear 5", w.ran[1]);
    TEST_ASSERT_EQUAL_UINT64(14u * S, w.ran_at[1]);
    TEST_ASSERT_EQUAL_UINT(2, w.ran_line[1]);
    w.view[1].nmt = "OPERATIONAL";
    scenario_tick(&sc, 20u * S, observe, run, &w);
    scenario_tick(&sc, 21u * S, observe, run, &w);
    TEST_ASSERT_EQUAL_UINT(3, w.ran_count);
    TEST_ASSERT_EQUAL_STRING("mute 6", w.ran[2]);
}

/* examples/scenarios/load-step.txt: a load step 2 s after the drive reaches speed, another 5 s
 * later, each once. */
static void test_load_step_example(void)
{
    char err[300] = "";
    static char text[4096];
    FILE *f = fopen(EXAMPLES_DIR "/load-step.txt", "rb");
    TEST_ASSERT_NOT_NULL_MESSAGE(f, EXAMPLES_DIR "/load-step.txt");
    size_t len = fread(text, 1, sizeof text - 1u, f);
    fclose(f);
    text[len] = '\0';
    TEST_ASSERT_TRUE_MESSAGE(scenario_parse(&sc, text, "load-step.txt", observe, &w, err,
                                            sizeof err), err);
    TEST_ASSERT_EQUAL_UINT(2, sc.count);
    scenario_start(&sc, 0);
    w.view[0].actual = 1200;
    TEST_ASSERT_EQUAL_UINT64(UINT64_MAX, scenario_tick(&sc, 3u * S, observe, run, &w));
    w.view[0].actual = 1500; /* at speed at 4 s */
    TEST_ASSERT_EQUAL_UINT64(6u * S, scenario_tick(&sc, 4u * S, observe, run, &w));
    TEST_ASSERT_EQUAL_UINT64(6u * S, scenario_tick(&sc, 6u * S - 1u, observe, run, &w));
    TEST_ASSERT_EQUAL_UINT(0, w.ran_count);
    TEST_ASSERT_EQUAL_UINT64(11u * S, scenario_tick(&sc, 6u * S, observe, run, &w));
    TEST_ASSERT_EQUAL_UINT(1, w.ran_count);
    TEST_ASSERT_EQUAL_STRING("load 5 80", w.ran[0]);
    TEST_ASSERT_EQUAL_UINT64(6u * S, w.ran_at[0]);
    TEST_ASSERT_EQUAL_UINT64(UINT64_MAX, scenario_tick(&sc, 11u * S, observe, run, &w));
    TEST_ASSERT_EQUAL_UINT(2, w.ran_count);
    TEST_ASSERT_EQUAL_STRING("load 5 20", w.ran[1]);
    TEST_ASSERT_EQUAL_UINT64(11u * S, w.ran_at[1]);
    scenario_tick(&sc, 30u * S, observe, run, &w); /* each once */
    TEST_ASSERT_EQUAL_UINT(2, w.ran_count);
}

static void test_same_file_same_run(void)
{
    /* Determinism: the same inputs give the same commands at the same times. */
    const char *text = "at 1: nmt 5 start\nwhen 5 nmt OPERATIONAL after 0.5: fault 5 1\n"
                       "when 5 fault: clear 5\nat 1: mute 6\n";
    char first[8][SCENARIO_COMMAND_MAX];
    uint64_t first_at[8];
    size_t first_count = 0;
    for (int round = 0; round < 2; round++) {
        setUp();
        char err[300] = "";
        TEST_ASSERT_TRUE(scenario_parse(&sc, text, "s.txt", observe, &w, err, sizeof err));
        scenario_start(&sc, 0);
        for (uint64_t t = 0; t <= 3u * S; t += 100000u) {
            scenario_tick(&sc, t, observe, run, &w);
        }
        if (round == 0) {
            first_count = w.ran_count;
            memcpy(first, w.ran, sizeof first);
            memcpy(first_at, w.ran_at, sizeof first_at);
        }
    }
    TEST_ASSERT_EQUAL_UINT(4, first_count);
    TEST_ASSERT_EQUAL_UINT(first_count, w.ran_count);
    for (size_t k = 0; k < first_count; k++) {
        TEST_ASSERT_EQUAL_STRING(first[k], w.ran[k]);
        TEST_ASSERT_EQUAL_UINT64(first_at[k], w.ran_at[k]);
    }
    TEST_ASSERT_EQUAL_STRING("nmt 5 start", w.ran[0]);
    TEST_ASSERT_EQUAL_STRING("mute 6", w.ran[1]);
    TEST_ASSERT_EQUAL_STRING("fault 5 1", w.ran[2]);
    TEST_ASSERT_EQUAL_UINT64(1500000u, w.ran_at[2]);
    TEST_ASSERT_EQUAL_STRING("clear 5", w.ran[3]);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_parse_errors_name_file_line_and_reason);
    RUN_TEST(test_parse_accepts_every_form);
    RUN_TEST(test_time_steps_run_at_their_deadline_in_file_order);
    RUN_TEST(test_condition_then_after_delay_once);
    RUN_TEST(test_same_file_same_run);
    RUN_TEST(test_load_step_example);
    return UNITY_END();
}
