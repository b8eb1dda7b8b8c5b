/* --scenario FILE: timed and conditional commands, run by the simulator itself, the same way
 * every run. One step per line ('#' starts a comment):
 *
 *   at SECONDS: COMMAND                      at SECONDS after the simulator started
 *   when NODE CONDITION [after SECONDS]: COMMAND
 *                                            once, the first time CONDITION holds for NODE (then
 *                                            SECONDS later, if given)
 *
 * CONDITION is one of
 *   state NAME        the CiA 402 state (or the drive's own state) is NAME; spaces in the name
 *                     written as '_' (OPERATION_ENABLED), any case
 *   nmt NAME          the NMT state: INITIALISING, PRE-OPERATIONAL, OPERATIONAL, STOPPED
 *   actual >= N       the actual speed (0x6044's unit), also <=, >, <, ==, !=
 *   fault / no-fault  a fault is active / none is
 * COMMAND is any operator command (fault, clear, nmt, mute, unmute, mains, status, quit, ...);
 * SECONDS a decimal number with up to 6 decimals, optionally ending in "s" or "ms" (ms: an
 * integer).
 *
 * Determinism: time steps run at their deadline (the loop sleeps until then), conditions are
 * evaluated after every batch of events, and steps that are due together run in file order; a
 * step's command may make another step's condition hold, which is seen in the same pass.
 *
 * This file is pure (no OS calls): the caller gives the time, observes the nodes and runs the
 * commands, so tests drive it on a virtual clock. */
#ifndef BOARDS_LINUX_SCENARIO_H
#define BOARDS_LINUX_SCENARIO_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define SCENARIO_MAX_STEPS 256u
#define SCENARIO_COMMAND_MAX 128u
#define SCENARIO_NAME_MAX 32u

typedef enum scenario_kind { SCENARIO_AT = 0, SCENARIO_WHEN } scenario_kind;

typedef enum scenario_cond {
    SCENARIO_COND_STATE = 0,
    SCENARIO_COND_NMT,
    SCENARIO_COND_ACTUAL,
    SCENARIO_COND_FAULT,
    SCENARIO_COND_NO_FAULT
} scenario_cond;

typedef enum scenario_cmp { CMP_GE = 0, CMP_LE, CMP_GT, CMP_LT, CMP_EQ, CMP_NE } scenario_cmp;

typedef struct scenario_step {
    unsigned line;                 /* in the file, for messages */
    scenario_kind kind;
    uint64_t delay_us;             /* at: from the start; when: from the condition holding */
    uint8_t node;                  /* when: the node observed */
    scenario_cond cond;
    scenario_cmp cmp;
    long value;                    /* actual's comparison value */
    char name[SCENARIO_NAME_MAX];  /* state / nmt name, as the simulator spells it */
    char command[SCENARIO_COMMAND_MAX];
    bool armed;                    /* when: the condition held; due at `due` */
    bool fired;
    uint64_t due;
} scenario_step;

typedef struct scenario {
    scenario_step steps[SCENARIO_MAX_STEPS];
    size_t count;
    uint64_t t0;                   /* scenario_start */
    size_t fired;
} scenario;

/* What the scenario sees of one node. */
typedef struct scenario_view {
    const char *state;             /* CiA 402 (or the drive's) state name; NULL: none */
    const char *nmt;
    long actual;
    bool fault;
} scenario_view;

/* Whether the node exists (for the parser) and, when view is not NULL, what it looks like now. */
typedef bool (*scenario_observe_fn)(void *ctx, unsigned node, scenario_view *view);
/* Runs a step's command (a writable copy of it). */
typedef void (*scenario_run_fn)(void *ctx, const scenario_step *step, char *command,
                                uint64_t now);

/* Parses text (NUL-terminated; the file's name for messages). Every node a step names, in its
 * condition or in its command's NODE argument, must exist (observe with view NULL). False with
 * "FILE:LINE: reason" in err. */
bool scenario_parse(scenario *sc, const char *text, const char *file, scenario_observe_fn observe,
                    void *ctx, char *err, size_t err_len);

/* Time 0 of the at steps. */
void scenario_start(scenario *sc, uint64_t now);

/* Runs every step that is due at now (see Determinism above); returns the next deadline
 * (UINT64_MAX: none; conditions waiting to hold are looked at on every call anyway). */
uint64_t scenario_tick(scenario *sc, uint64_t now, scenario_observe_fn observe,
                       scenario_run_fn run, void *ctx);

#endif
