/* libFuzzer target: scenario files (boards/linux/scenario.c, --scenario). Any bytes are parsed;
 * a refusal must name the file and a line, and a file that parses is run for 20 virtual seconds
 * against two fake nodes whose state the commands change. Invariants: no crash or UB, every
 * message NUL-terminated, steps within SCENARIO_MAX_STEPS, deadlines never in the past, each
 * step run at most once and never before it is due. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scenario.h"

typedef struct world {
    scenario_view view[2];
    size_t runs;
    uint64_t now;
} world;

static bool observe(void *ctx, unsigned node, scenario_view *view)
{
    world *w = ctx;
    if (node != 5u && node != 6u) {
        return false;
    }
    if (view != NULL) {
        *view = w->view[node - 5u];
    }
    return true;
}

static void run(void *ctx, const scenario_step *step, char *command, uint64_t now)
{
    world *w = ctx;
    if (step->kind == SCENARIO_AT && now < step->due) {
        abort(); /* run before it was due */
    }
    if (strlen(command) >= SCENARIO_COMMAND_MAX) {
        abort();
    }
    w->runs++;
    scenario_view *v = &w->view[(w->runs & 1u)];
    if (strncmp(command, "fault", 5) == 0) {
        v->fault = true;
        v->state = "FAULT";
    } else if (strncmp(command, "clear", 5) == 0) {
        v->fault = false;
    } else if (strncmp(command, "nmt", 3) == 0) {
        v->nmt = "OPERATIONAL";
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static scenario sc; /* 100 kB: not on the stack */
    char *text = malloc(size + 1u);
    if (text == NULL) {
        return 0;
    }
    memcpy(text, data, size);
    text[size] = '\0';
    world w = {{{"SWITCH ON DISABLED", "PRE-OPERATIONAL", 0, false},
                {"OPERATION ENABLED", "OPERATIONAL", 1500, false}}, 0, 0};
    char err[300];
    memset(err, 'x', sizeof err);
    bool ok = scenario_parse(&sc, text, "f", observe, &w, err, sizeof err);
    free(text);
    if (!ok) {
        if (memchr(err, '\0', sizeof err) == NULL || strncmp(err, "f:", 2) != 0) {
            abort();
        }
        return 0;
    }
    if (sc.count > SCENARIO_MAX_STEPS) {
        abort();
    }
    scenario_start(&sc, 1000u);
    for (uint64_t t = 1000u; t < 1000u + 20000000u; t += 250000u) {
        w.view[1].actual = (long)(t / 10000u);
        uint64_t next = scenario_tick(&sc, t, observe, run, &w);
        if (next < t) {
            abort(); /* a deadline in the past: the loop would spin */
        }
    }
    if (w.runs > sc.count || sc.fired != w.runs) {
        abort(); /* a step ran twice */
    }
    return 0;
}
