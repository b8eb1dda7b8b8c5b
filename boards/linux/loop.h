/* The Linux port's event loop: one epoll set holding every node's CAN socket, a timerfd, standard
 * input, a signalfd and any other descriptor watched with loop_watch_fd (the control socket and
 * its clients, the trace sockets); tickers (loop_add_ticker: the scenario) give deadlines too. It sleeps until a frame, a command line, a signal or the earliest deadline
 * any member returned (the core's co_node_process deadline, a drive's ramp tick, a transmit retry):
 * no busy loop and no fixed poll period. Time is CLOCK_MONOTONIC in microseconds.
 *
 *   loop lp; loop_init(&lp);
 *   loop_add(&lp, &member);             // once per node; member.port is open
 *   loop_watch_stdin(&lp, on_line, ctx);
 *   int rc = loop_run(&lp);             // until SIGINT/SIGTERM or loop_stop()
 */
#ifndef BOARDS_LINUX_LOOP_H
#define BOARDS_LINUX_LOOP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "canopen/frame.h"
#include "socketcan.h"

#define LOOP_MAX_MEMBERS 127u
#define LOOP_LINE_MAX 512u
#define LOOP_MAX_WATCHES 40u  /* other descriptors: control socket and its clients, trace sockets */
#define LOOP_MAX_TICKERS 8u   /* deadline providers that are not nodes (scenario, live state) */

/* One node (or anything with a CAN socket and deadlines). Every callback gets ctx.
 * A member without a CAN socket (port NULL: the EtherCAT line's raw Ethernet socket) gives fd and
 * input instead; rx, bus_event and tx_ready are then unused. */
typedef struct loop_member {
    sc_port *port;
    void *ctx;
    /* A frame arrived (already filtered to the node's COB-IDs). */
    void (*rx)(void *ctx, const co_frame *frame, uint64_t now);
    /* The bus reported an error state change or lost frames. May be NULL. */
    void (*bus_event)(void *ctx, sc_bus_event event, uint64_t now);
    /* Runs what is due at now; returns the absolute time to be called again (UINT64_MAX: never).
     * Called after every batch of events, so calling it early must be harmless. */
    uint64_t (*process)(void *ctx, uint64_t now);
    /* The port can send again: hand the core's queued frames over (co_node_tx_ready). */
    void (*tx_ready)(void *ctx, uint64_t now);
    int fd;                                   /* port NULL: the descriptor to watch for input;
                                                 -1: none (deadlines only) */
    void (*input)(void *ctx, uint64_t now);   /* port NULL: fd is readable */
} loop_member;

/* A watched descriptor is ready: events are the EPOLL* bits epoll reported. */
typedef void (*loop_fd_fn)(void *ctx, uint32_t events, uint64_t now);

/* Runs what is due at now and returns the next time it wants to run (UINT64_MAX: never); called
 * after every batch of events, as loop_member.process is. */
typedef uint64_t (*loop_tick_fn)(void *ctx, uint64_t now);

typedef struct loop_watch {
    int fd;                        /* -1: free slot */
    uint32_t events;
    uint32_t generation;           /* tells a stale epoll event from one for the slot's new fd */
    loop_fd_fn fn;
    void *ctx;
} loop_watch;

/* A complete line from standard input, without its newline (NUL-terminated, writable). */
typedef void (*loop_line_fn)(void *ctx, char *line, uint64_t now);

typedef struct loop {
    int epoll_fd;
    int timer_fd;
    int signal_fd;
    int stdin_fd;                  /* -1 when not read (or after end of file) */
    bool stdin_polled;             /* watched by epoll; false: a file read once in loop_run */
    loop_member *members[LOOP_MAX_MEMBERS];
    uint32_t epollout[LOOP_MAX_MEMBERS]; /* EPOLLOUT currently requested for member i */
    size_t member_count;
    loop_line_fn on_line;
    void *line_ctx;
    char line[LOOP_LINE_MAX];
    size_t line_len;
    bool line_too_long;
    loop_watch watches[LOOP_MAX_WATCHES];
    loop_tick_fn tickers[LOOP_MAX_TICKERS];
    void *ticker_ctx[LOOP_MAX_TICKERS];
    size_t ticker_count;
    uint64_t armed;                /* deadline the timerfd is set to (UINT64_MAX: disarmed) */
    bool stop;
    int signal;                    /* the signal that stopped the loop, 0 if none */
    uint64_t wakeups;              /* epoll_wait returns, for the no-busy-loop check */
} loop;

/* Current CLOCK_MONOTONIC time in microseconds. */
uint64_t loop_now(void);

/* Creates the epoll set, the timerfd and the signalfd (SIGINT and SIGTERM are blocked and read
 * from it; SIGPIPE is ignored). Returns 0, or -1 with errno. */
int loop_init(loop *lp);

/* Adds a member whose port is open. Returns 0, or -1 (errno). */
int loop_add(loop *lp, loop_member *member);

/* Reads commands from fd (standard input) line by line. A file or /dev/null, which epoll cannot
 * watch, is read to its end at the first loop_run iteration instead. End of file just stops
 * watching: the loop keeps running. */
int loop_watch_stdin(loop *lp, int fd, loop_line_fn on_line, void *ctx);

/* Watches fd (non-blocking, owned by the caller) for events (EPOLLIN, EPOLLOUT); fn gets what
 * epoll reports, including EPOLLHUP/EPOLLERR. Returns 0, or -1 (errno; ENOSPC: no free slot). */
int loop_watch_fd(loop *lp, int fd, uint32_t events, loop_fd_fn fn, void *ctx);

/* Changes the events watched on fd. Returns 0 or -1 (errno). */
int loop_modify_fd(loop *lp, int fd, uint32_t events);

/* Stops watching fd (before the caller closes it); an event of this batch still pending for it is
 * dropped. */
void loop_unwatch_fd(loop *lp, int fd);

/* Adds a deadline provider run with the members. Returns 0, or -1 (ENOSPC). */
int loop_add_ticker(loop *lp, loop_tick_fn fn, void *ctx);

/* Runs until a signal or loop_stop(). Returns 0 after SIGINT/SIGTERM or loop_stop(), -1 when a
 * system call of the loop itself fails (errno set; the reason is printed on stderr). */
int loop_run(loop *lp);

/* Makes loop_run return after the current iteration. */
void loop_stop(loop *lp);

/* Closes what loop_init opened (not the members' ports) and unblocks the signals. */
void loop_close(loop *lp);

#endif
