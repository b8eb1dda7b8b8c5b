/* The two size macros of the core (both gcc's noinline), each with its reason. No other compiler
 * attribute and no optimisation-level test is used anywhere in the core: every build compiles the
 * same code. */
#ifndef CANOPEN_COMPILER_H
#define CANOPEN_COMPILER_H

/* Keeps a cold or slow path (a loss, a queue full, the work behind a skip test) out of its hot
 * caller, so that the caller's common path neither carries its code nor saves the registers it
 * needs. */
#if defined(__GNUC__)
#define CO_NOINLINE __attribute__((noinline))
#else
#define CO_NOINLINE
#endif

/* Keeps one copy of a function in every build: one that several callers share, which gcc's
 * inliner would otherwise copy into each caller (counting the branches a constant argument folds
 * away), or a large one whose only caller would take it in together with the helpers it shares
 * with other functions. Either way the copies cost more than the call. */
#if defined(__GNUC__)
#define CO_ONE_COPY __attribute__((noinline))
#else
#define CO_ONE_COPY
#endif

#endif
