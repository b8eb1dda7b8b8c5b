/* --trace FILE: every frame on the simulator's buses, in candump's log format (candump -L;
 * replayable with canplayer):
 *
 *   (1764370000.123456) vcan0 605#4000100000000000
 *   (1764370000.123789) vcan0 585#4300100092010100
 *
 * One raw CAN socket per interface, without filters, sees every frame there: those the masters
 * send the simulated nodes (received) and those the nodes send (the kernel's loopback delivers a
 * node's frame to every other socket on the interface), in bus order. Remote frames are
 * "ID#R" (with the DLC digit when it is not 0). The file is flushed after every batch of frames,
 * so it is complete up to the latest batch while the simulator runs.
 *
 * A file that cannot be written (at start or later, e.g. a full disk) is reported on stderr once
 * and tracing stops; the simulator keeps running. */
#ifndef BOARDS_LINUX_TRACE_H
#define BOARDS_LINUX_TRACE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "loop.h"

#define TRACE_MAX_IFACES 8u

typedef struct trace_bus {
    struct trace *owner;
    int fd;
    char iface[16];
} trace_bus;

typedef struct trace {
    FILE *file;                    /* NULL: not tracing (never opened, or failed) */
    char path[256];
    loop *lp;
    trace_bus buses[TRACE_MAX_IFACES];
    size_t bus_count;
    uint32_t frames;               /* lines written */
} trace;

/* Opens path for writing (truncated). On failure says why on stderr and returns false: the
 * caller runs on without a trace. */
bool trace_open(trace *t, loop *lp, const char *path);

/* Records the interface iface too. Returns false after saying why on stderr (tracing goes on
 * for the other interfaces). */
bool trace_add_iface(trace *t, const char *iface);

/* Formats one frame as a candump -L line (no newline) into buf (64 bytes are enough). */
void trace_format(char *buf, size_t cap, uint64_t sec, uint32_t usec, const char *iface,
                  uint32_t id, bool rtr, const uint8_t *data, uint8_t len);

void trace_close(trace *t);

#endif
