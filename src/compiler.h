/* The one compiler attribute the core uses, with its reason. */
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

/* Keeps one copy of a function that several callers share, in every build: gcc's inliner would
 * otherwise copy it into each caller (counting the branches a constant argument folds away), even
 * when optimising for size, where the copies cost more than the calls. */
#if defined(__GNUC__)
#define CO_ONE_COPY __attribute__((noinline))
#else
#define CO_ONE_COPY
#endif

/* TODO: compatibility definitions for src/od.c and src/sdo_server.c only, which still use them;
 * remove both once those files no longer do. CO_SIZE_NOINLINE kept a function out of line when
 * optimising for size; CO_SIZE_BASE hid a pointer from the optimiser under -Os. */
#if defined(__GNUC__) && defined(__OPTIMIZE_SIZE__)
#define CO_SIZE_NOINLINE __attribute__((noinline))
#define CO_SIZE_BASE(p) \
    __extension__({ __typeof__(p) co_base_ = (p); __asm__("" : "+r"(co_base_)); co_base_; })
#else
#define CO_SIZE_NOINLINE
#define CO_SIZE_BASE(p) (p)
#endif

#endif
