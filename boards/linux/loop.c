/* Event loop: epoll over CAN sockets, a timerfd for the earliest deadline, stdin and a signalfd. */
#define _GNU_SOURCE
#include "loop.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/signalfd.h>
#include <sys/socket.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#define TAG_TIMER 0u
#define TAG_SIGNAL 1u
#define TAG_STDIN 2u
#define TAG_MEMBER 3u        /* + member index */
#define RX_BATCH 64u         /* frames read from one socket before looking at the others */
#define NEVER UINT64_MAX
/* Watched descriptors: bit 40 set, the slot's generation in bits 8..39, the slot in bits 0..7. */
#define TAG_WATCH (1ull << 40)

uint64_t loop_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

static sigset_t stop_signals(void)
{
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    return set;
}

int loop_init(loop *lp)
{
    memset(lp, 0, sizeof *lp);
    lp->epoll_fd = lp->timer_fd = lp->signal_fd = lp->stdin_fd = -1;
    lp->armed = NEVER;
    for (size_t i = 0; i < LOOP_MAX_WATCHES; i++) {
        lp->watches[i].fd = -1;
    }
    signal(SIGPIPE, SIG_IGN); /* a closed stdout must not kill the simulator */
    sigset_t set = stop_signals();
    if (sigprocmask(SIG_BLOCK, &set, NULL) != 0) {
        return -1;
    }
    lp->epoll_fd = epoll_create1(EPOLL_CLOEXEC);
    lp->timer_fd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    lp->signal_fd = signalfd(-1, &set, SFD_NONBLOCK | SFD_CLOEXEC);
    if (lp->epoll_fd < 0 || lp->timer_fd < 0 || lp->signal_fd < 0) {
        int e = errno;
        loop_close(lp);
        errno = e;
        return -1;
    }
    struct epoll_event ev = {.events = EPOLLIN, .data.u64 = TAG_TIMER};
    if (epoll_ctl(lp->epoll_fd, EPOLL_CTL_ADD, lp->timer_fd, &ev) != 0) {
        return -1;
    }
    ev.data.u64 = TAG_SIGNAL;
    if (epoll_ctl(lp->epoll_fd, EPOLL_CTL_ADD, lp->signal_fd, &ev) != 0) {
        return -1;
    }
    return 0;
}

void loop_close(loop *lp)
{
    if (lp->epoll_fd >= 0) {
        close(lp->epoll_fd);
    }
    if (lp->timer_fd >= 0) {
        close(lp->timer_fd);
    }
    if (lp->signal_fd >= 0) {
        close(lp->signal_fd);
    }
    lp->epoll_fd = lp->timer_fd = lp->signal_fd = -1;
    sigset_t set = stop_signals();
    (void)sigprocmask(SIG_UNBLOCK, &set, NULL);
}

int loop_add(loop *lp, loop_member *member)
{
    if (lp->member_count >= LOOP_MAX_MEMBERS) {
        errno = ENOSPC;
        return -1;
    }
    struct epoll_event ev = {.events = EPOLLIN, .data.u64 = TAG_MEMBER + lp->member_count};
    int fd = member->port != NULL ? member->port->fd : member->fd;
    if (fd >= 0 && epoll_ctl(lp->epoll_fd, EPOLL_CTL_ADD, fd, &ev) != 0) {
        return -1;
    }
    lp->epollout[lp->member_count] = 0;
    lp->members[lp->member_count++] = member;
    return 0;
}

int loop_watch_stdin(loop *lp, int fd, loop_line_fn on_line, void *ctx)
{
    lp->on_line = on_line;
    lp->line_ctx = ctx;
    lp->stdin_fd = fd;
    int flags = fcntl(fd, F_GETFL);
    if (flags >= 0) {
        (void)fcntl(fd, F_SETFL, flags | O_NONBLOCK);
    }
    struct epoll_event ev = {.events = EPOLLIN, .data.u64 = TAG_STDIN};
    if (epoll_ctl(lp->epoll_fd, EPOLL_CTL_ADD, fd, &ev) != 0) {
        if (errno != EPERM) {
            lp->stdin_fd = -1;
            return -1;
        }
        /* A regular file or /dev/null: read to its end in loop_run (stdin_fd stays set). */
        return 0;
    }
    lp->stdin_polled = true;
    return 0;
}

static uint64_t watch_tag(const loop *lp, size_t slot)
{
    return TAG_WATCH | ((uint64_t)lp->watches[slot].generation << 8) | slot;
}

static loop_watch *find_watch(loop *lp, int fd)
{
    for (size_t i = 0; i < LOOP_MAX_WATCHES; i++) {
        if (lp->watches[i].fd == fd) {
            return &lp->watches[i];
        }
    }
    return NULL;
}

int loop_watch_fd(loop *lp, int fd, uint32_t events, loop_fd_fn fn, void *ctx)
{
    loop_watch *w = fd >= 0 ? find_watch(lp, -1) : NULL;
    if (w == NULL) {
        errno = fd >= 0 ? ENOSPC : EBADF;
        return -1;
    }
    size_t slot = (size_t)(w - lp->watches);
    w->generation = (w->generation + 1u) & 0xFFFFFFFFu;
    struct epoll_event ev = {.events = events, .data.u64 = watch_tag(lp, slot)};
    if (epoll_ctl(lp->epoll_fd, EPOLL_CTL_ADD, fd, &ev) != 0) {
        return -1;
    }
    w->fd = fd;
    w->events = events;
    w->fn = fn;
    w->ctx = ctx;
    return 0;
}

int loop_modify_fd(loop *lp, int fd, uint32_t events)
{
    loop_watch *w = fd >= 0 ? find_watch(lp, fd) : NULL;
    if (w == NULL) {
        errno = EBADF;
        return -1;
    }
    if (w->events == events) {
        return 0;
    }
    struct epoll_event ev = {.events = events, .data.u64 = watch_tag(lp, (size_t)(w - lp->watches))};
    if (epoll_ctl(lp->epoll_fd, EPOLL_CTL_MOD, fd, &ev) != 0) {
        return -1;
    }
    w->events = events;
    return 0;
}

void loop_unwatch_fd(loop *lp, int fd)
{
    loop_watch *w = fd >= 0 ? find_watch(lp, fd) : NULL;
    if (w != NULL) {
        (void)epoll_ctl(lp->epoll_fd, EPOLL_CTL_DEL, fd, NULL);
        w->fd = -1;
        w->fn = NULL;
    }
}

int loop_add_ticker(loop *lp, loop_tick_fn fn, void *ctx)
{
    if (lp->ticker_count >= LOOP_MAX_TICKERS) {
        errno = ENOSPC;
        return -1;
    }
    lp->tickers[lp->ticker_count] = fn;
    lp->ticker_ctx[lp->ticker_count++] = ctx;
    return 0;
}

static void watch_ready(loop *lp, uint64_t tag, uint32_t events, uint64_t now)
{
    size_t slot = (size_t)(tag & 0xFFu);
    uint32_t generation = (uint32_t)((tag >> 8) & 0xFFFFFFFFu);
    if (slot >= LOOP_MAX_WATCHES) {
        return;
    }
    loop_watch *w = &lp->watches[slot];
    if (w->fd < 0 || w->fn == NULL || w->generation != generation) {
        return; /* unwatched (or the slot reused) earlier in this batch */
    }
    w->fn(w->ctx, events, now);
}

void loop_stop(loop *lp)
{
    lp->stop = true;
}

/* --- standard input ---------------------------------------------------------------------------- */

static void take_line(loop *lp, uint64_t now)
{
    lp->line[lp->line_len] = '\0';
    if (lp->line_too_long) {
        fprintf(stderr, "canopen-drive: command line longer than %u characters ignored\n",
                (unsigned)(LOOP_LINE_MAX - 1u));
    } else if (lp->on_line != NULL) {
        lp->on_line(lp->line_ctx, lp->line, now);
    }
    lp->line_len = 0;
    lp->line_too_long = false;
}

/* Reads what is available; returns false at end of file. */
static bool read_stdin(loop *lp, int fd, uint64_t now)
{
    char buf[4096];
    for (;;) {
        ssize_t n = read(fd, buf, sizeof buf);
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
            return true;
        }
        if (n <= 0) {
            if (lp->line_len != 0u || lp->line_too_long) {
                take_line(lp, now); /* a last line without its newline */
            }
            return false;
        }
        for (ssize_t i = 0; i < n && !lp->stop; i++) {
            if (buf[i] == '\n') {
                take_line(lp, now);
            } else if (lp->line_len + 1u < LOOP_LINE_MAX) {
                lp->line[lp->line_len++] = buf[i];
            } else {
                lp->line_too_long = true;
            }
        }
        if (lp->stop) {
            return true;
        }
    }
}

static void stdin_ready(loop *lp, uint64_t now)
{
    int fd = lp->stdin_fd;
    if (!read_stdin(lp, fd, now)) {
        /* End of input: keep simulating (a simulator started with </dev/null or from a script
         * that closed its end runs until it is signalled). */
        (void)epoll_ctl(lp->epoll_fd, EPOLL_CTL_DEL, fd, NULL);
        lp->stdin_fd = -1;
    }
}

/* --- members ----------------------------------------------------------------------------------- */

static void member_input(loop *lp, size_t i, uint32_t events, uint64_t now)
{
    loop_member *m = lp->members[i];
    if (m->port == NULL) {
        if ((events & (EPOLLIN | EPOLLERR)) != 0u) {
            m->input(m->ctx, now);
        }
        return;
    }
    if ((events & EPOLLERR) != 0u) {
        int err = 0;
        socklen_t len = sizeof err;
        (void)getsockopt(m->port->fd, SOL_SOCKET, SO_ERROR, &err, &len); /* clears it */
        if (err != 0 && err != ENOBUFS) {
            fprintf(stderr, "canopen-drive: %s: socket error: %s\n", m->port->iface,
                    strerror(err));
        }
    }
    if ((events & EPOLLOUT) != 0u && m->port->tx_state == SC_TX_WAIT_WRITABLE) {
        sc_tx_resume(m->port);
        m->tx_ready(m->ctx, now);
    }
    if ((events & EPOLLIN) == 0u) {
        return;
    }
    for (unsigned k = 0; k < RX_BATCH; k++) {
        co_frame frame;
        sc_bus_event event = SC_BUS_NONE;
        sc_recv_result r = sc_recv(m->port, &frame, &event);
        if (r == SC_RECV_FRAME) {
            m->rx(m->ctx, &frame, now);
        } else if (r == SC_RECV_EVENT) {
            if (m->bus_event != NULL) {
                m->bus_event(m->ctx, event, now);
            }
        } else if (r == SC_RECV_SKIPPED) {
            continue;
        } else {
            if (r == SC_RECV_ERROR && errno != ENETDOWN) {
                fprintf(stderr, "canopen-drive: %s: receive: %s\n", m->port->iface,
                        strerror(errno));
            }
            break;
        }
    }
}

/* Runs every member's due work; returns the earliest deadline. */
static uint64_t run_members(loop *lp, uint64_t now)
{
    uint64_t next = NEVER;
    for (size_t i = 0; i < lp->member_count; i++) {
        loop_member *m = lp->members[i];
        sc_port *port = m->port;
        if (port == NULL) {
            uint64_t due = m->process(m->ctx, now);
            next = due < next ? due : next;
            continue;
        }
        if (port->tx_state == SC_TX_WAIT_RETRY && sc_tx_retry_time(port, now) <= now) {
            sc_tx_resume(port);
            m->tx_ready(m->ctx, now);
        }
        uint64_t due = m->process(m->ctx, now);
        if (port->tx_state == SC_TX_WAIT_RETRY) {
            uint64_t retry = sc_tx_retry_time(port, now);
            due = retry < due ? retry : due;
        }
        uint32_t want = port->tx_state == SC_TX_WAIT_WRITABLE ? (uint32_t)EPOLLOUT : 0u;
        if (want != lp->epollout[i]) {
            struct epoll_event ev = {.events = EPOLLIN | want, .data.u64 = TAG_MEMBER + i};
            if (epoll_ctl(lp->epoll_fd, EPOLL_CTL_MOD, port->fd, &ev) == 0) {
                lp->epollout[i] = want;
            }
        }
        next = due < next ? due : next;
    }
    for (size_t i = 0; i < lp->ticker_count; i++) {
        uint64_t due = lp->tickers[i](lp->ticker_ctx[i], now);
        next = due < next ? due : next;
    }
    return next;
}

static int arm_timer(loop *lp, uint64_t deadline)
{
    if (deadline == lp->armed) {
        return 0;
    }
    struct itimerspec its;
    memset(&its, 0, sizeof its);
    if (deadline != NEVER) {
        its.it_value.tv_sec = (time_t)(deadline / 1000000u);
        its.it_value.tv_nsec = (long)(deadline % 1000000u) * 1000L;
        if (its.it_value.tv_sec == 0 && its.it_value.tv_nsec == 0) {
            its.it_value.tv_nsec = 1; /* zero would disarm */
        }
    }
    if (timerfd_settime(lp->timer_fd, TFD_TIMER_ABSTIME, &its, NULL) != 0) {
        return -1;
    }
    lp->armed = deadline;
    return 0;
}

int loop_run(loop *lp)
{
    struct epoll_event events[32];
    bool stdin_file = lp->stdin_fd >= 0 && !lp->stdin_polled; /* read once the members ran */
    while (!lp->stop) {
        uint64_t now = loop_now();
        uint64_t next = run_members(lp, now);
        if (stdin_file) {
            stdin_file = false;
            (void)read_stdin(lp, lp->stdin_fd, now);
            lp->stdin_fd = -1;
            continue;
        }
        if (lp->stop) {
            break;
        }
        int timeout = -1;
        if (next <= now) {
            timeout = 0; /* already due: look at the sockets, then run it */
        } else if (arm_timer(lp, next) != 0) {
            fprintf(stderr, "canopen-drive: timerfd_settime: %s\n", strerror(errno));
            return -1;
        }
        int n = epoll_wait(lp->epoll_fd, events, (int)(sizeof events / sizeof events[0]), timeout);
        if (n < 0) {
            if (errno == EINTR) {
                continue;
            }
            fprintf(stderr, "canopen-drive: epoll_wait: %s\n", strerror(errno));
            return -1;
        }
        lp->wakeups++;
        now = loop_now();
        for (int k = 0; k < n && !lp->stop; k++) {
            uint64_t tag = events[k].data.u64;
            if (tag == TAG_TIMER) {
                uint64_t expirations;
                while (read(lp->timer_fd, &expirations, sizeof expirations) > 0) {
                }
                lp->armed = NEVER; /* expired: must be set again even to the same time */
            } else if (tag == TAG_SIGNAL) {
                struct signalfd_siginfo si;
                while (read(lp->signal_fd, &si, sizeof si) == (ssize_t)sizeof si) {
                    lp->signal = (int)si.ssi_signo;
                    lp->stop = true;
                }
            } else if (tag == TAG_STDIN) {
                stdin_ready(lp, now);
            } else if ((tag & TAG_WATCH) != 0u) {
                watch_ready(lp, tag, events[k].events, now);
            } else {
                member_input(lp, (size_t)(tag - TAG_MEMBER), events[k].events, now);
            }
        }
    }
    return 0;
}
