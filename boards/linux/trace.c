/* The frame trace: a filterless CAN socket per interface, written as candump -L lines. */
#define _GNU_SOURCE
#include "trace.h"

#include <errno.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#define READS_PER_WAKEUP 256u
#define TRACE_RCVBUF (1024 * 1024) /* a burst of frames waits here while a line is written */

bool trace_open(trace *t, loop *lp, const char *path)
{
    memset(t, 0, sizeof *t);
    t->lp = lp;
    snprintf(t->path, sizeof t->path, "%s", path);
    t->file = fopen(path, "w");
    if (t->file == NULL) {
        fprintf(stderr, "canopen-drive: --trace %s: %s; running without a trace\n", path,
                strerror(errno));
        return false;
    }
    return true;
}

void trace_format(char *buf, size_t cap, uint64_t sec, uint32_t usec, const char *iface,
                  uint32_t id, bool rtr, const uint8_t *data, uint8_t len)
{
    static const char hex[] = "0123456789ABCDEF";
    int n = snprintf(buf, cap, "(%llu.%06u) %s %03X#", (unsigned long long)sec, (unsigned)usec,
                     iface, (unsigned)id);
    if (n < 0 || (size_t)n >= cap) {
        return;
    }
    size_t pos = (size_t)n;
    if (rtr) {
        if (pos + 3u <= cap) {
            buf[pos++] = 'R';
            if (len != 0u) {
                buf[pos++] = hex[len & 0x0Fu];
            }
        }
    } else {
        for (uint8_t i = 0; i < len && i < 8u && pos + 3u <= cap; i++) {
            buf[pos++] = hex[data[i] >> 4];
            buf[pos++] = hex[data[i] & 0x0Fu];
        }
    }
    buf[pos < cap ? pos : cap - 1u] = '\0';
}

static void stop_tracing(trace *t, int err)
{
    fprintf(stderr, "canopen-drive: --trace %s: cannot write: %s; tracing stopped, the "
                    "simulation goes on\n", t->path, strerror(err));
    (void)fclose(t->file);
    t->file = NULL;
    for (size_t i = 0; i < t->bus_count; i++) {
        loop_unwatch_fd(t->lp, t->buses[i].fd);
        close(t->buses[i].fd);
        t->buses[i].fd = -1;
    }
}

static void bus_ready(void *ctx, uint32_t events, uint64_t now)
{
    trace_bus *b = ctx;
    trace *t = b->owner;
    (void)events;
    (void)now;
    for (unsigned k = 0; k < READS_PER_WAKEUP && t->file != NULL; k++) {
        struct can_frame cf;
        ssize_t n = read(b->fd, &cf, sizeof cf);
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n != (ssize_t)sizeof cf) {
            break; /* EAGAIN, or not a classic frame */
        }
        if ((cf.can_id & (CAN_ERR_FLAG | CAN_EFF_FLAG)) != 0u) {
            continue; /* CANopen is 11-bit; error frames are not enabled anyway */
        }
        struct timeval tv;
        gettimeofday(&tv, NULL);
        char line[96];
        trace_format(line, sizeof line, (uint64_t)tv.tv_sec, (uint32_t)tv.tv_usec, b->iface,
                     cf.can_id & CAN_SFF_MASK, (cf.can_id & CAN_RTR_FLAG) != 0u, cf.data,
                     cf.can_dlc <= 8u ? cf.can_dlc : 8u);
        if (fprintf(t->file, "%s\n", line) < 0) {
            stop_tracing(t, errno);
            return;
        }
        t->frames++;
    }
    if (t->file != NULL && fflush(t->file) != 0) {
        stop_tracing(t, errno);
    }
}

bool trace_add_iface(trace *t, const char *iface)
{
    if (t->file == NULL) {
        return false;
    }
    for (size_t i = 0; i < t->bus_count; i++) {
        if (strcmp(t->buses[i].iface, iface) == 0) {
            return true;
        }
    }
    if (t->bus_count == TRACE_MAX_IFACES) {
        fprintf(stderr, "canopen-drive: --trace: more than %u interfaces\n",
                (unsigned)TRACE_MAX_IFACES);
        return false;
    }
    int fd = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
    struct ifreq ifr;
    memset(&ifr, 0, sizeof ifr);
    snprintf(ifr.ifr_name, sizeof ifr.ifr_name, "%s", iface);
    int size = TRACE_RCVBUF;
    struct sockaddr_can addr;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    if (fd < 0 || ioctl(fd, SIOCGIFINDEX, &ifr) != 0) {
        fprintf(stderr, "canopen-drive: --trace: %s: %s\n", iface, strerror(errno));
        if (fd >= 0) {
            close(fd);
        }
        return false;
    }
    addr.can_ifindex = ifr.ifr_ifindex;
    (void)setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &size, sizeof size);
    if (bind(fd, (struct sockaddr *)&addr, sizeof addr) != 0) {
        fprintf(stderr, "canopen-drive: --trace: %s: %s\n", iface, strerror(errno));
        close(fd);
        return false;
    }
    trace_bus *b = &t->buses[t->bus_count];
    b->owner = t;
    b->fd = fd;
    snprintf(b->iface, sizeof b->iface, "%s", iface);
    if (loop_watch_fd(t->lp, fd, EPOLLIN, bus_ready, b) != 0) {
        fprintf(stderr, "canopen-drive: --trace: %s: epoll: %s\n", iface, strerror(errno));
        close(fd);
        return false;
    }
    t->bus_count++;
    return true;
}

void trace_close(trace *t)
{
    for (size_t i = 0; i < t->bus_count; i++) {
        if (t->buses[i].fd >= 0) {
            bus_ready(&t->buses[i], EPOLLIN, 0); /* what is still queued */
            if (t->buses[i].fd >= 0) {
                loop_unwatch_fd(t->lp, t->buses[i].fd);
                close(t->buses[i].fd);
                t->buses[i].fd = -1;
            }
        }
    }
    if (t->file != NULL) {
        if (fclose(t->file) != 0) {
            fprintf(stderr, "canopen-drive: --trace %s: %s\n", t->path, strerror(errno));
        }
        t->file = NULL;
    }
}
