/* Scenario files: parser and scheduler (pure; see scenario.h). */
#define _GNU_SOURCE
#include "scenario.h"

#include <ctype.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NEVER UINT64_MAX
#define LINE_MAX_LEN 256u

static const char *const state_names[] = {
    "NOT READY TO SWITCH ON", "SWITCH ON DISABLED", "READY TO SWITCH ON", "SWITCHED ON",
    "OPERATION ENABLED", "QUICK STOP ACTIVE", "FAULT REACTION ACTIVE", "FAULT",
};
static const char *const nmt_names[] = {"INITIALISING", "PRE-OPERATIONAL", "OPERATIONAL",
                                        "STOPPED"};
/* Commands a step may run (commands.c runs them) and their usage: words with the command, the
 * fewest and the most (status takes its NODE or not). */
static const struct {
    const char *name;
    uint8_t min_words, max_words;
    const char *usage;
} commands[] = {
    {"fault", 3, 3, "fault NODE TRIP"},
    {"clear", 2, 2, "clear NODE"},
    {"nmt", 3, 3, "nmt NODE start|stop|preop|reset-node|reset-comm"},
    {"mute", 2, 2, "mute NODE"},
    {"unmute", 2, 2, "unmute NODE"},
    {"mains", 3, 3, "mains NODE on|off"},
    {"load", 3, 3, "load NODE PERCENT (0..200)"},
    {"status", 1, 2, "status [NODE]"},
    {"state", 2, 2, "state NODE"},
    {"pdo", 2, 2, "pdo NODE"},
    {"nodes", 1, 1, "nodes"},
    {"quit", 1, 1, "quit"},
    {"help", 1, 1, "help"},
};

static bool fail(char *err, size_t err_len, const char *file, unsigned line, const char *fmt, ...)
{
    int n = snprintf(err, err_len, "%s:%u: ", file, line);
    if (n > 0 && (size_t)n < err_len) {
        va_list ap;
        va_start(ap, fmt);
        (void)vsnprintf(err + n, err_len - (size_t)n, fmt, ap);
        va_end(ap);
    }
    return false;
}

/* "2", "2.5", "0.000001", "2.5s", "500ms" -> microseconds. */
static bool parse_seconds(const char *s, uint64_t *us)
{
    uint64_t whole = 0, frac = 0, scale = 100000u;
    const char *p = s;
    if (!isdigit((unsigned char)*p)) {
        return false;
    }
    for (; isdigit((unsigned char)*p); p++) {
        if (whole > 1000000u) {
            return false; /* more than about eleven days: a typo */
        }
        whole = whole * 10u + (uint64_t)(*p - '0');
    }
    if (strcmp(p, "ms") == 0) {
        *us = whole * 1000u;
        return true;
    }
    if (*p == '.') {
        p++;
        if (!isdigit((unsigned char)*p)) {
            return false;
        }
        for (; isdigit((unsigned char)*p); p++) {
            if (scale == 0u) {
                return false; /* finer than a microsecond */
            }
            frac += (uint64_t)(*p - '0') * scale;
            scale /= 10u;
        }
    }
    if (*p == 's') {
        p++;
    }
    if (*p != '\0') {
        return false;
    }
    *us = whole * 1000000u + frac;
    return true;
}

static bool parse_node(const char *s, unsigned *node)
{
    char *end = NULL;
    if (!isdigit((unsigned char)s[0])) {
        return false;
    }
    unsigned long v = strtoul(s, &end, 0);
    if (*end != '\0' || v < 1u || v > 127u) {
        return false;
    }
    *node = (unsigned)v;
    return true;
}

/* NAME with '_' for spaces, any case, to the simulator's spelling; NULL if not in names. */
static const char *match_name(const char *word, const char *const *names, size_t count)
{
    char up[SCENARIO_NAME_MAX];
    size_t n = strlen(word);
    if (n >= sizeof up) {
        return NULL;
    }
    for (size_t i = 0; i <= n; i++) {
        char c = word[i];
        up[i] = c == '_' ? ' ' : (char)toupper((unsigned char)c);
    }
    for (size_t i = 0; i < count; i++) {
        if (strcmp(up, names[i]) == 0) {
            return names[i];
        }
    }
    return NULL;
}

static bool parse_cmp(const char *s, scenario_cmp *cmp)
{
    static const struct {
        const char *text;
        scenario_cmp cmp;
    } ops[] = {{">=", CMP_GE}, {"<=", CMP_LE}, {">", CMP_GT},
               {"<", CMP_LT},  {"==", CMP_EQ}, {"!=", CMP_NE}};
    for (size_t i = 0; i < sizeof ops / sizeof ops[0]; i++) {
        if (strcmp(s, ops[i].text) == 0) {
            *cmp = ops[i].cmp;
            return true;
        }
    }
    return false;
}

/* The command part: a known command, and its NODE (if it names one) exists. */
static bool check_command(const char *command, const char *file, unsigned line,
                          scenario_observe_fn observe, void *ctx, char *err, size_t err_len)
{
    char copy[SCENARIO_COMMAND_MAX];
    snprintf(copy, sizeof copy, "%s", command);
    char *save = NULL;
    const char *words[4];
    size_t n = 0;
    for (const char *w = strtok_r(copy, " \t", &save); w != NULL; w = strtok_r(NULL, " \t", &save)) {
        if (n == 4u) {
            n++;
            break;
        }
        words[n++] = w;
    }
    if (n == 0u) {
        return fail(err, err_len, file, line, "no command after ':'");
    }
    size_t k = 0;
    while (k < sizeof commands / sizeof commands[0] && strcmp(words[0], commands[k].name) != 0) {
        k++;
    }
    if (k == sizeof commands / sizeof commands[0]) {
        return fail(err, err_len, file, line, "unknown command '%.40s'", words[0]);
    }
    if (n < commands[k].min_words || n > commands[k].max_words) {
        return fail(err, err_len, file, line, "usage: %s", commands[k].usage);
    }
    unsigned node;
    if (n >= 2u) {
        if (!parse_node(words[1], &node)) {
            return fail(err, err_len, file, line, "'%.20s' is not a node-ID (1..127)", words[1]);
        }
        if (!observe(ctx, node, NULL)) {
            return fail(err, err_len, file, line, "no node %u in this simulator", node);
        }
    }
    if (n == 3u && strcmp(words[0], "nmt") == 0) {
        static const char *const nmt_cmds[] = {"start", "stop", "preop", "reset-node",
                                               "reset-comm"};
        bool known = false;
        for (size_t i = 0; i < 5u; i++) {
            known = known || strcmp(words[2], nmt_cmds[i]) == 0;
        }
        if (!known) {
            return fail(err, err_len, file, line, "usage: %s", commands[k].usage);
        }
    }
    if (n == 3u && strcmp(words[0], "mains") == 0 && strcmp(words[2], "on") != 0 &&
        strcmp(words[2], "off") != 0) {
        return fail(err, err_len, file, line, "usage: %s", commands[k].usage);
    }
    if (n == 3u && strcmp(words[0], "load") == 0) {
        char *end = NULL;
        unsigned long percent = isdigit((unsigned char)words[2][0]) ? strtoul(words[2], &end, 10)
                                                                     : 0;
        if (end == NULL || *end != '\0' || percent > 200u) {
            return fail(err, err_len, file, line, "'%.20s' is not a load (0..200 %% of rated "
                                                  "torque)", words[2]);
        }
    }
    return true;
}

static bool parse_line(scenario *sc, char *text, const char *file, unsigned line,
                       scenario_observe_fn observe, void *ctx, char *err, size_t err_len)
{
    char *hash = strchr(text, '#');
    if (hash != NULL) {
        *hash = '\0';
    }
    char *colon = strchr(text, ':');
    char *save = NULL;
    char *w = strtok_r(text, " \t\r", &save);
    if (w == NULL && colon == NULL) {
        return true; /* blank or comment */
    }
    if (colon == NULL) {
        return fail(err, err_len, file, line, "no ':' before the command (at SECONDS: COMMAND, "
                                              "or when NODE CONDITION [after SECONDS]: COMMAND)");
    }
    *colon = '\0';
    if (sc->count == SCENARIO_MAX_STEPS) {
        return fail(err, err_len, file, line, "more than %u steps", (unsigned)SCENARIO_MAX_STEPS);
    }
    scenario_step *st = &sc->steps[sc->count];
    memset(st, 0, sizeof *st);
    st->line = line;
    /* the command: trimmed */
    char *cmd = colon + 1;
    while (*cmd == ' ' || *cmd == '\t') {
        cmd++;
    }
    size_t len = strlen(cmd);
    while (len > 0u && (cmd[len - 1u] == ' ' || cmd[len - 1u] == '\t' || cmd[len - 1u] == '\r')) {
        cmd[--len] = '\0';
    }
    if (len >= SCENARIO_COMMAND_MAX) {
        return fail(err, err_len, file, line, "command longer than %u characters",
                    (unsigned)SCENARIO_COMMAND_MAX - 1u);
    }
    memcpy(st->command, cmd, len + 1u);
    if (w == NULL) {
        return fail(err, err_len, file, line, "'at' or 'when' expected before ':'");
    }
    char *words[8];
    size_t n = 0;
    words[n++] = w;
    while (n < 8u && (words[n] = strtok_r(NULL, " \t\r", &save)) != NULL) {
        n++;
    }
    if (n == 8u) {
        return fail(err, err_len, file, line, "too many words before ':'");
    }
    if (strcmp(words[0], "at") == 0) {
        st->kind = SCENARIO_AT;
        if (n != 2u || !parse_seconds(words[1], &st->delay_us)) {
            return fail(err, err_len, file, line, "'at' wants SECONDS (e.g. at 2.5: ...)");
        }
    } else if (strcmp(words[0], "when") == 0) {
        st->kind = SCENARIO_WHEN;
        unsigned node;
        if (n < 3u || !parse_node(words[1], &node)) {
            return fail(err, err_len, file, line, "'when' wants NODE CONDITION (e.g. when 5 "
                                                  "state OPERATION_ENABLED: ...)");
        }
        if (!observe(ctx, node, NULL)) {
            return fail(err, err_len, file, line, "no node %u in this simulator", node);
        }
        st->node = (uint8_t)node;
        size_t used;
        const char *c = words[2];
        if (strcmp(c, "state") == 0 || strcmp(c, "nmt") == 0) {
            bool is_state = c[0] == 's';
            const char *name = n > 3u ? match_name(words[3], is_state ? state_names : nmt_names,
                                                   is_state ? 8u : 4u)
                                      : NULL;
            if (name == NULL) {
                return fail(err, err_len, file, line, is_state
                    ? "'state' wants a CiA 402 state, spaces as '_' (e.g. OPERATION_ENABLED)"
                    : "'nmt' wants INITIALISING, PRE-OPERATIONAL, OPERATIONAL or STOPPED");
            }
            st->cond = is_state ? SCENARIO_COND_STATE : SCENARIO_COND_NMT;
            snprintf(st->name, sizeof st->name, "%s", name);
            used = 4;
        } else if (strcmp(c, "actual") == 0) {
            char *end = NULL;
            if (n < 5u || !parse_cmp(words[3], &st->cmp)) {
                return fail(err, err_len, file, line, "'actual' wants >=, <=, >, <, == or != "
                                                      "and a number (e.g. actual >= 1500)");
            }
            st->value = strtol(words[4], &end, 10);
            if (*end != '\0' || end == words[4]) {
                return fail(err, err_len, file, line, "'%.20s' is not a number", words[4]);
            }
            st->cond = SCENARIO_COND_ACTUAL;
            used = 5;
        } else if (strcmp(c, "fault") == 0 || strcmp(c, "no-fault") == 0) {
            st->cond = c[0] == 'f' ? SCENARIO_COND_FAULT : SCENARIO_COND_NO_FAULT;
            used = 3;
        } else {
            return fail(err, err_len, file, line, "unknown condition '%.20s' (state, nmt, actual, "
                                                  "fault, no-fault)", c);
        }
        if (n == used + 2u && strcmp(words[used], "after") == 0) {
            if (!parse_seconds(words[used + 1u], &st->delay_us)) {
                return fail(err, err_len, file, line, "'after' wants SECONDS");
            }
        } else if (n != used) {
            return fail(err, err_len, file, line, "unexpected '%.20s' before ':'", words[used]);
        }
    } else {
        return fail(err, err_len, file, line, "a step starts with 'at' or 'when', not '%.20s'",
                    words[0]);
    }
    if (!check_command(st->command, file, line, observe, ctx, err, err_len)) {
        return false;
    }
    sc->count++;
    return true;
}

bool scenario_parse(scenario *sc, const char *text, const char *file, scenario_observe_fn observe,
                    void *ctx, char *err, size_t err_len)
{
    memset(sc, 0, sizeof *sc);
    unsigned line = 1;
    const char *p = text;
    while (*p != '\0') {
        const char *nl = strchr(p, '\n');
        size_t len = nl != NULL ? (size_t)(nl - p) : strlen(p);
        if (len >= LINE_MAX_LEN) {
            return fail(err, err_len, file, line, "line longer than %u characters",
                        (unsigned)LINE_MAX_LEN - 1u);
        }
        char buf[LINE_MAX_LEN];
        memcpy(buf, p, len);
        buf[len] = '\0';
        for (size_t i = 0; i < len; i++) {
            unsigned char c = (unsigned char)buf[i];
            if ((c < 0x20u && c != '\t' && c != '\r') || c >= 0x7Fu) {
                return fail(err, err_len, file, line, "byte 0x%02X is not text", (unsigned)c);
            }
        }
        if (!parse_line(sc, buf, file, line, observe, ctx, err, err_len)) {
            return false;
        }
        if (nl == NULL) {
            break;
        }
        p = nl + 1;
        line++;
    }
    return true;
}

void scenario_start(scenario *sc, uint64_t now)
{
    sc->t0 = now;
    for (size_t i = 0; i < sc->count; i++) {
        scenario_step *st = &sc->steps[i];
        st->fired = false;
        st->armed = st->kind == SCENARIO_AT;
        st->due = st->kind == SCENARIO_AT ? now + st->delay_us : NEVER;
    }
    sc->fired = 0;
}

static bool holds(const scenario_step *st, const scenario_view *v)
{
    switch (st->cond) {
    case SCENARIO_COND_STATE:
        return v->state != NULL && strcmp(v->state, st->name) == 0;
    case SCENARIO_COND_NMT:
        return v->nmt != NULL && strcmp(v->nmt, st->name) == 0;
    case SCENARIO_COND_FAULT:
        return v->fault;
    case SCENARIO_COND_NO_FAULT:
        return !v->fault;
    case SCENARIO_COND_ACTUAL:
        switch (st->cmp) {
        case CMP_GE: return v->actual >= st->value;
        case CMP_LE: return v->actual <= st->value;
        case CMP_GT: return v->actual > st->value;
        case CMP_LT: return v->actual < st->value;
        case CMP_EQ: return v->actual == st->value;
        default: return v->actual != st->value;
        }
    default:
        return false;
    }
}

uint64_t scenario_tick(scenario *sc, uint64_t now, scenario_observe_fn observe,
                       scenario_run_fn run, void *ctx)
{
    /* Passes until nothing more fires: a command may make a later (or earlier) step's condition
     * hold. Each pass fires at least one step, so count + 1 passes end it. */
    for (size_t pass = 0; pass <= sc->count; pass++) {
        bool any = false;
        for (size_t i = 0; i < sc->count; i++) {
            scenario_step *st = &sc->steps[i];
            if (st->fired) {
                continue;
            }
            if (!st->armed) {
                scenario_view v = {NULL, NULL, 0, false};
                if (observe(ctx, st->node, &v) && holds(st, &v)) {
                    st->armed = true;
                    st->due = now + st->delay_us;
                }
            }
            if (st->armed && now >= st->due) {
                char command[SCENARIO_COMMAND_MAX];
                memcpy(command, st->command, sizeof command);
                st->fired = true;
                sc->fired++;
                run(ctx, st, command, now);
                any = true;
            }
        }
        if (!any) {
            break;
        }
    }
    uint64_t next = NEVER;
    for (size_t i = 0; i < sc->count; i++) {
        const scenario_step *st = &sc->steps[i];
        if (!st->fired && st->armed && st->due < next) {
            next = st->due;
        }
    }
    return next;
}
