/* A DOMAIN hook on 0x2010 of the test dictionary for the SDO transfer tests: it checks what it is
 * given against a known byte pattern and makes up what it is asked for, with knobs for a hook that
 * refuses, gives less or more than it announces, or gives its data in small pieces. */
#ifndef TEST_DOMAIN_H
#define TEST_DOMAIN_H

#include <stdbool.h>
#include <stdint.h>

#include "test_support.h"

typedef struct test_domain {
    /* written through the hook (SDO download) */
    uint32_t received;      /* bytes handed over so far */
    uint32_t pieces;        /* calls */
    uint32_t largest_piece; /* most bytes in one call */
    uint32_t total;         /* total argument of the latest call */
    uint32_t last_calls;    /* calls with last = true */
    bool in_order;          /* every piece started where the one before ended */
    bool pattern_ok;        /* every byte matched test_domain_pattern() */
    co_abort write_refusal; /* refuse a piece reaching beyond refuse_from with this */
    uint32_t refuse_from;
    uint8_t kept[64];       /* the first bytes, for exact checks */
    /* read through the hook (SDO upload) */
    uint32_t source_size;   /* what *total says */
    uint32_t extra;         /* bytes a read gives beyond what is left of source_size (a hook
                             * that gives more than it announces) */
    uint32_t read_piece;    /* most bytes one call gives (0: as many as asked) */
    uint32_t dry_from;      /* gives nothing from this offset on (less than announced) */
    co_abort read_refusal;  /* refuse a read from refuse_read_from on with this */
    uint32_t refuse_read_from;
    uint32_t reads;         /* calls */
} test_domain;

/* Byte i of the DOMAIN's content. */
uint8_t test_domain_pattern(uint32_t i);

/* Clears d: nothing received, in order, pattern intact, never dry, no refusals. */
void test_domain_reset(test_domain *d);

/* Adds d as the read and write hook of 0x2010 on t's node (asserts that the node took it). */
void test_domain_add_hook(test_node *t, test_domain *d);

#endif
