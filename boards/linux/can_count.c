/* can-count: records every frame on a SocketCAN interface, for the bus-level benchmark
 * (tools/bench --vcan, tools/vcan_bench.py).
 *
 *   can-count --iface vcan0 --out FILE
 *
 * Prints "can-count: ready" once the socket is bound, then records until SIGINT or SIGTERM. Each
 * frame becomes one 16-byte record in FILE, written at exit: the kernel's receive timestamp
 * (CLOCK_REALTIME, nanoseconds, uint64) and the CAN-ID with its flags (struct can_frame can_id,
 * uint32), then 4 bytes of zero, all in host byte order. The last line on stdout is
 * "can-count: frames N dropped D", D being the socket's own overflow counter (SO_RXQ_OVFL): the
 * frames the kernel had to throw away because this reader was too slow. D != 0 makes every
 * count of the run useless.
 *
 * It drains the socket with recvmmsg in batches, then sleeps DRAIN_PERIOD_NS: woken for every
 * frame, it would cost the measured system a context switch per frame (in a one-CPU guest that
 * is the simulator's CPU). The socket buffer, as large as the kernel allows (SO_RCVBUFFORCE as
 * root), holds tens of thousands of frames, a few seconds of a saturated bus. Exit status: 0,
 * 1 on a run-time failure, 2 on a usage error. */
#define _GNU_SOURCE
#include <errno.h>
#include <linux/can.h>
#include <net/if.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#define PROG "can-count"
#define BATCH 64u
#define RCVBUF_BYTES (64 * 1024 * 1024)
#define DRAIN_PERIOD_NS 10000000L

typedef struct record {
    uint64_t ts_ns;
    uint32_t can_id;
    uint32_t zero;
} record;

static volatile sig_atomic_t stop_requested;

static void on_stop(int sig)
{
    (void)sig;
    stop_requested = 1;
}

static int usage(void)
{
    fprintf(stderr, "usage: " PROG " --iface IFACE --out FILE\n");
    return 2;
}

int main(int argc, char **argv)
{
    const char *iface = NULL, *out_path = NULL;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--iface") == 0 && i + 1 < argc) {
            iface = argv[++i];
        } else if (strcmp(argv[i], "--out") == 0 && i + 1 < argc) {
            out_path = argv[++i];
        } else {
            return usage();
        }
    }
    if (iface == NULL || out_path == NULL || strlen(iface) >= IFNAMSIZ) {
        return usage();
    }
    FILE *out = fopen(out_path, "wb");
    if (out == NULL) {
        fprintf(stderr, PROG ": %s: %s\n", out_path, strerror(errno));
        return 1;
    }
    int fd = socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
    if (fd < 0) {
        fprintf(stderr, PROG ": socket(AF_CAN): %s\n", strerror(errno));
        return 1;
    }
    int one = 1;
    int rcvbuf = RCVBUF_BYTES;
    /* As root the limit net.core.rmem_max does not apply; otherwise take what it allows. */
    if (setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &rcvbuf, sizeof rcvbuf) != 0) {
        (void)setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
    }
    if (setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one) != 0 ||
        setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof one) != 0) {
        fprintf(stderr, PROG ": setsockopt: %s\n", strerror(errno));
        return 1;
    }
    struct sockaddr_can addr;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = (int)if_nametoindex(iface);
    if (addr.can_ifindex == 0 || bind(fd, (struct sockaddr *)&addr, sizeof addr) != 0) {
        fprintf(stderr, PROG ": %s: %s\n", iface, strerror(errno));
        return 1;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop; /* no SA_RESTART: a blocked read returns EINTR */
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);

    size_t cap = 1u << 20, count = 0;
    record *recs = malloc(cap * sizeof *recs);
    struct can_frame frames[BATCH];
    struct iovec iov[BATCH];
    union {
        char buf[CMSG_SPACE(sizeof(struct timespec)) + CMSG_SPACE(sizeof(uint32_t))];
        size_t align; /* as struct cmsghdr (which cannot be an array element: flexible member) */
    } control[BATCH];
    struct mmsghdr msgs[BATCH];
    uint32_t dropped = 0;
    if (recs == NULL) {
        fprintf(stderr, PROG ": out of memory\n");
        return 1;
    }
    printf(PROG ": ready\n");
    fflush(stdout);
    while (!stop_requested) {
        for (unsigned i = 0; i < BATCH; i++) {
            iov[i].iov_base = &frames[i];
            iov[i].iov_len = sizeof frames[i];
            memset(&msgs[i], 0, sizeof msgs[i]);
            msgs[i].msg_hdr.msg_iov = &iov[i];
            msgs[i].msg_hdr.msg_iovlen = 1;
            msgs[i].msg_hdr.msg_control = control[i].buf;
            msgs[i].msg_hdr.msg_controllen = sizeof control[i].buf;
        }
        int n = recvmmsg(fd, msgs, BATCH, MSG_DONTWAIT, NULL);
        if (n < 0) {
            if (errno == EAGAIN || errno == EWOULDBLOCK) {
                struct timespec pause = {0, DRAIN_PERIOD_NS};
                nanosleep(&pause, NULL); /* a stop signal cuts it short */
                continue;
            }
            if (errno == EINTR) {
                continue;
            }
            fprintf(stderr, PROG ": recvmmsg: %s\n", strerror(errno));
            return 1;
        }
        for (int i = 0; i < n; i++) {
            record r = {0, frames[i].can_id, 0};
            struct msghdr *h = &msgs[i].msg_hdr;
            for (struct cmsghdr *c = CMSG_FIRSTHDR(h); c != NULL; c = CMSG_NXTHDR(h, c)) {
                if (c->cmsg_level != SOL_SOCKET) {
                    continue;
                }
                if (c->cmsg_type == SO_TIMESTAMPNS) {
                    struct timespec ts;
                    memcpy(&ts, CMSG_DATA(c), sizeof ts);
                    r.ts_ns = (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
                } else if (c->cmsg_type == SO_RXQ_OVFL) {
                    memcpy(&dropped, CMSG_DATA(c), sizeof dropped);
                }
            }
            if (count == cap) {
                record *bigger = realloc(recs, 2u * cap * sizeof *recs);
                if (bigger == NULL) {
                    fprintf(stderr, PROG ": out of memory after %zu frames\n", count);
                    return 1;
                }
                recs = bigger;
                cap *= 2u;
            }
            recs[count++] = r;
        }
    }
    if (fwrite(recs, sizeof *recs, count, out) != count || fclose(out) != 0) {
        fprintf(stderr, PROG ": %s: write failed\n", out_path);
        return 1;
    }
    free(recs);
    close(fd);
    printf(PROG ": frames %zu dropped %u\n", count, (unsigned)dropped);
    return 0;
}
