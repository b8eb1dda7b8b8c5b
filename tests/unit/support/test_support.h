/* Unit-test support: a fake CAN driver that captures every frame, a virtual clock, and a node
 * on the generated test dictionary (od/test/test.eds). Time only moves when a test moves it. */
#ifndef TEST_SUPPORT_H
#define TEST_SUPPORT_H

#include <stdbool.h>
#include <stdint.h>

#include "canopen/node.h"

#define FAKE_CAPTURE_MAX 4096u

typedef struct fake_bus {
    co_frame frames[FAKE_CAPTURE_MAX]; /* frames the node sent, oldest first */
    uint32_t count;                    /* frames captured (capped at FAKE_CAPTURE_MAX) */
    uint32_t read;                     /* next frame fake_bus_next() returns */
    bool refuse;                       /* when true, send() refuses like a full port queue */
} fake_bus;

typedef struct fake_store {
    uint8_t image[4096];
    uint32_t len;
    uint32_t layout_hash;
    bool valid;
    bool fail_save;
    uint32_t saves;
} fake_store;

/* One node under test with its bus, clock and storage. */
typedef struct test_node {
    co_node node;
    fake_bus bus;
    fake_store store;
    co_storage storage;
    uint64_t now;
    uint8_t values[8192];
    uint8_t values_before[8192]; /* test_values_snapshot()'s copy of values */
} test_node;

/* Sets up t with the test dictionary, node-ID node_id, and starts it (boot-up captured). */
void test_node_start(test_node *t, uint8_t node_id);

/* Sets up without starting (the node stays INITIALISING). */
void test_node_init(test_node *t, uint8_t node_id);

/* The driver t's node sends through. */
co_driver fake_bus_driver(fake_bus *bus);

/* Next unread captured frame, or NULL. */
const co_frame *fake_bus_next(fake_bus *bus);

/* Number of captured frames not read yet. */
uint32_t fake_bus_pending(const fake_bus *bus);

/* Drops every captured frame. */
void fake_bus_clear(fake_bus *bus);

/* Feeds a frame to t's node at t->now. */
void test_rx(test_node *t, uint16_t id, uint8_t dlc, const uint8_t *data);

/* Feeds an 8-byte frame given as bytes. */
void test_rx8(test_node *t, uint16_t id, uint8_t b0, uint8_t b1, uint8_t b2, uint8_t b3,
              uint8_t b4, uint8_t b5, uint8_t b6, uint8_t b7);

/* Moves the virtual clock to t->now + us and runs co_node_process; returns its next deadline. */
uint64_t test_advance(test_node *t, uint64_t us);

/* Asserts (Unity) that the next captured frame has this id, dlc and data. */
void expect_frame(test_node *t, uint16_t id, uint8_t dlc, const uint8_t *data);

/* Asserts that nothing more was sent. */
void expect_no_frame(test_node *t);

/* An SDO expedited read of index/sub through the node's SDO server; returns the abort code (0 on
 * success) and the value in *value. Consumes the response frame. */
uint32_t sdo_read_u32(test_node *t, uint16_t index, uint8_t sub, uint32_t *value);

/* An SDO expedited write of size bytes (1-4); returns the abort code (0 on success). */
uint32_t sdo_write(test_node *t, uint16_t index, uint8_t sub, uint32_t value, uint8_t size);

/* --- SDO frames byte for byte (client 0x600 + node-ID, server 0x580 + node-ID) --- */

/* Feeds the 8-byte SDO request b0..b7 to t's node. */
void sdo_req(test_node *t, uint8_t b0, uint8_t b1, uint8_t b2, uint8_t b3, uint8_t b4, uint8_t b5,
             uint8_t b6, uint8_t b7);

/* Asserts that the next captured frame is the SDO response b0..b7. */
void sdo_expect(test_node *t, uint8_t b0, uint8_t b1, uint8_t b2, uint8_t b3, uint8_t b4,
                uint8_t b5, uint8_t b6, uint8_t b7);

/* Asserts that the next captured frame is the abort of index/sub with code, and nothing follows. */
void sdo_expect_abort(test_node *t, uint16_t index, uint8_t sub, uint32_t code);

/* The value bytes of a sub-entry in t's value block. */
const uint8_t *test_value_of(test_node *t, uint16_t index, uint8_t sub);

/* Keeps a copy of the whole value block, for test_expect_values_unchanged(). */
void test_values_snapshot(test_node *t);

/* Asserts that the value block is as test_values_snapshot() saw it (a refused request changed
 * nothing). */
void test_expect_values_unchanged(test_node *t);

/* The fake storage as a co_storage. */
co_storage fake_store_storage(fake_store *store);

#endif
