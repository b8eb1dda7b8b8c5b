/* Control socket: listening sockets and clients on the simulator's epoll loop. */
#define _GNU_SOURCE
#include "control.h"

#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <stdio.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#define READS_PER_WAKEUP 16u       /* one busy client cannot starve the bus: epoll comes back */

static void drop_client(control *c, control_client *cl);

void control_init(control *c, loop *lp, const cmd_env *env, uint64_t t0)
{
    memset(c, 0, sizeof *c);
    c->unix_fd = c->tcp_fd = -1;
    c->lp = lp;
    c->env = *env;
    c->t0 = t0;
    for (size_t i = 0; i < CONTROL_MAX_CLIENTS; i++) {
        c->clients[i].fd = -1;
    }
}

/* --- output ------------------------------------------------------------------------------------ */

/* Sends what the client's buffer holds, as far as the socket takes it. False: the client is gone
 * (and was dropped). */
static bool flush_client(control *c, control_client *cl)
{
    size_t sent = 0;
    while (sent < cl->out_len) {
        ssize_t n = send(cl->fd, cl->out + sent, cl->out_len - sent, MSG_NOSIGNAL | MSG_DONTWAIT);
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
            break;
        }
        if (n <= 0) {
            drop_client(c, cl); /* EPIPE, ECONNRESET: it went away */
            return false;
        }
        sent += (size_t)n;
    }
    memmove(cl->out, cl->out + sent, cl->out_len - sent);
    cl->out_len -= sent;
    uint32_t want = EPOLLIN | (cl->out_len != 0u ? (uint32_t)EPOLLOUT : 0u);
    (void)loop_modify_fd(c->lp, cl->fd, want);
    return true;
}

/* Queues one line (a '\n' is added) and sends what it can. */
static void put_line(control *c, control_client *cl, const char *prefix, const char *text)
{
    if (cl->fd < 0) {
        return;
    }
    size_t lp = strlen(prefix), lt = strlen(text);
    if (cl->out_len + lp + lt + 1u > CONTROL_OUT_MAX) {
        fprintf(stderr, "canopen-drive: control client dropped: %u bytes of answers and events "
                        "unread\n", (unsigned)cl->out_len);
        c->dropped++;
        drop_client(c, cl);
        return;
    }
    memcpy(cl->out + cl->out_len, prefix, lp);
    memcpy(cl->out + cl->out_len + lp, text, lt);
    cl->out_len += lp + lt;
    cl->out[cl->out_len++] = '\n';
    (void)flush_client(c, cl);
}

void control_event(void *ctx, const char *line)
{
    control *c = ctx;
    char head[32];
    uint64_t t = loop_now() - c->t0;
    snprintf(head, sizeof head, "event %lu.%06lu ", (unsigned long)(t / 1000000u),
             (unsigned long)(t % 1000000u));
    for (size_t i = 0; i < CONTROL_MAX_CLIENTS; i++) {
        if (c->clients[i].fd >= 0 && c->clients[i].subscribed) {
            put_line(c, &c->clients[i], head, line);
        }
    }
}

/* --- input ------------------------------------------------------------------------------------- */

typedef struct reply {
    control *c;
    control_client *cl;
} reply;

static void client_emit(void *ctx, cmd_emit_kind kind, const char *text)
{
    reply *r = ctx;
    put_line(r->c, r->cl, kind == CMD_ERROR ? "error " : "data ", text);
}

static void run_line(control *c, control_client *cl, uint64_t now)
{
    char *line = cl->in;
    line[cl->in_len] = '\0';
    if (cl->too_long) {
        char text[96];
        snprintf(text, sizeof text, "line longer than %u bytes ignored",
                 (unsigned)(CONTROL_LINE_MAX - 1u));
        put_line(c, cl, "error ", text);
        return;
    }
    if (cl->binary) {
        put_line(c, cl, "error ", "line with bytes other than printable ASCII ignored");
        return;
    }
    char copy[CONTROL_LINE_MAX];
    memcpy(copy, line, cl->in_len + 1u);
    char *save = NULL;
    const char *w0 = strtok_r(copy, " \t\r", &save);
    const char *w1 = w0 != NULL ? strtok_r(NULL, " \t\r", &save) : NULL;
    if (w0 != NULL && (strcmp(w0, "subscribe") == 0 || strcmp(w0, "unsubscribe") == 0 ||
                       strcmp(w0, "version") == 0)) {
        if (w1 != NULL) {
            char text[64];
            snprintf(text, sizeof text, "usage: %s (no arguments)", w0);
            put_line(c, cl, "error ", text);
        } else if (w0[0] == 'v') {
            char text[32];
            snprintf(text, sizeof text, "%d", CONTROL_PROTOCOL);
            put_line(c, cl, "data ", text);
            put_line(c, cl, "ok", "");
        } else {
            cl->subscribed = w0[0] == 's';
            put_line(c, cl, "ok", "");
        }
        return;
    }
    reply r = {c, cl};
    int fd = cl->fd;
    /* every line gets one answer, a blank one or a comment too ("ok") */
    if (cmd_run(&c->env, line, now, client_emit, &r, NULL) && cl->fd == fd) {
        put_line(c, cl, "ok", "");
    }
}

/* Takes the bytes of one read into lines; returns false when the client was dropped. */
static bool take_bytes(control *c, control_client *cl, const char *buf, size_t n, uint64_t now)
{
    int fd = cl->fd;
    for (size_t i = 0; i < n; i++) {
        unsigned char ch = (unsigned char)buf[i];
        if (ch == '\n') {
            run_line(c, cl, now);
            if (cl->fd != fd) {
                return false;
            }
            cl->in_len = 0;
            cl->too_long = cl->binary = false;
            continue;
        }
        if ((ch < 0x20u && ch != '\t' && ch != '\r') || ch >= 0x7Fu) {
            cl->binary = true;
        }
        if (cl->in_len + 1u < CONTROL_LINE_MAX) {
            cl->in[cl->in_len++] = (char)ch;
        } else {
            cl->too_long = true;
        }
    }
    return true;
}

static void client_ready(void *ctx, uint32_t events, uint64_t now)
{
    control_client *cl = ctx;
    control *c = cl->owner;
    int fd = cl->fd;
    if ((events & EPOLLOUT) != 0u && !flush_client(c, cl)) {
        return;
    }
    if ((events & (EPOLLIN | EPOLLHUP | EPOLLERR)) == 0u) {
        return;
    }
    for (unsigned k = 0; k < READS_PER_WAKEUP && cl->fd == fd; k++) {
        char buf[4096];
        ssize_t n = recv(fd, buf, sizeof buf, MSG_DONTWAIT);
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
            return;
        }
        if (n <= 0) {
            drop_client(c, cl); /* end of file or reset: a half line is dropped, not run */
            return;
        }
        if (!take_bytes(c, cl, buf, (size_t)n, now)) {
            return;
        }
    }
}

static void drop_client(control *c, control_client *cl)
{
    if (cl->fd < 0) {
        return;
    }
    loop_unwatch_fd(c->lp, cl->fd);
    close(cl->fd);
    cl->fd = -1;
    cl->subscribed = cl->too_long = cl->binary = false;
    cl->in_len = cl->out_len = 0;
}

/* --- listening --------------------------------------------------------------------------------- */

static void accept_ready(void *ctx, uint32_t events, uint64_t now, int lfd)
{
    control *c = ctx;
    (void)events;
    (void)now;
    for (;;) {
        int fd = accept4(lfd, NULL, NULL, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (fd < 0) {
            if (errno == EINTR || errno == ECONNABORTED) {
                continue;
            }
            if (errno != EAGAIN && errno != EWOULDBLOCK) {
                fprintf(stderr, "canopen-drive: control socket: accept: %s\n", strerror(errno));
            }
            return;
        }
        control_client *cl = NULL;
        for (size_t i = 0; i < CONTROL_MAX_CLIENTS && cl == NULL; i++) {
            if (c->clients[i].fd < 0) {
                cl = &c->clients[i];
            }
        }
        if (cl == NULL) {
            static const char busy[] = "error too many control clients (16)\n";
            (void)send(fd, busy, sizeof busy - 1u, MSG_NOSIGNAL | MSG_DONTWAIT);
            close(fd);
            continue;
        }
        cl->owner = c;
        cl->fd = fd;
        cl->subscribed = cl->too_long = cl->binary = false;
        cl->in_len = cl->out_len = 0;
        if (loop_watch_fd(c->lp, fd, EPOLLIN, client_ready, cl) != 0) {
            fprintf(stderr, "canopen-drive: control socket: %s\n", strerror(errno));
            close(fd);
            cl->fd = -1;
            continue;
        }
        c->accepted++;
        char hello[64];
        snprintf(hello, sizeof hello, "hello canopen-drive control %d", CONTROL_PROTOCOL);
        put_line(c, cl, "", hello);
    }
}

static void unix_ready(void *ctx, uint32_t events, uint64_t now)
{
    control *c = ctx;
    accept_ready(c, events, now, c->unix_fd);
}

static void tcp_ready(void *ctx, uint32_t events, uint64_t now)
{
    control *c = ctx;
    accept_ready(c, events, now, c->tcp_fd);
}

/* Whether someone accepts connections on the socket file at path. */
static bool socket_alive(const struct sockaddr_un *addr)
{
    int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) {
        return true; /* cannot tell: do not remove it */
    }
    bool alive = connect(fd, (const struct sockaddr *)addr, sizeof *addr) == 0 ||
                 (errno != ECONNREFUSED && errno != ENOENT);
    close(fd);
    return alive;
}

int control_listen_unix(control *c, const char *path, char *err, size_t err_len)
{
    struct sockaddr_un addr;
    memset(&addr, 0, sizeof addr);
    addr.sun_family = AF_UNIX;
    size_t len = strlen(path);
    if (len == 0u || len >= sizeof addr.sun_path) {
        snprintf(err, err_len, "--control: a socket path has 1 to %u bytes",
                 (unsigned)sizeof addr.sun_path - 1u);
        return -1;
    }
    memcpy(addr.sun_path, path, len);
    struct stat st;
    if (lstat(path, &st) == 0) {
        if (!S_ISSOCK(st.st_mode)) {
            snprintf(err, err_len, "--control %s: exists and is not a socket", path);
            return -1;
        }
        if (socket_alive(&addr)) {
            snprintf(err, err_len, "--control %s: another process is listening on it", path);
            return -1;
        }
        (void)unlink(path); /* left behind by a simulator that was killed */
    }
    int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd < 0 || bind(fd, (const struct sockaddr *)&addr, sizeof addr) != 0 ||
        listen(fd, 8) != 0) {
        snprintf(err, err_len, "--control %s: %s", path, strerror(errno));
        if (fd >= 0) {
            close(fd);
        }
        return -1;
    }
    if (loop_watch_fd(c->lp, fd, EPOLLIN, unix_ready, c) != 0) {
        snprintf(err, err_len, "--control %s: epoll: %s", path, strerror(errno));
        close(fd);
        (void)unlink(path);
        return -1;
    }
    c->unix_fd = fd;
    memcpy(c->path, path, len + 1u);
    return 0;
}

int control_listen_tcp(control *c, unsigned port, char *err, size_t err_len)
{
    struct sockaddr_in addr;
    memset(&addr, 0, sizeof addr);
    addr.sin_family = AF_INET;
    addr.sin_port = htons((uint16_t)port);
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK); /* never reachable from another machine */
    int one = 1;
    int fd = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    socklen_t alen = sizeof addr;
    if (fd < 0 || setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) != 0 ||
        bind(fd, (const struct sockaddr *)&addr, sizeof addr) != 0 || listen(fd, 8) != 0 ||
        getsockname(fd, (struct sockaddr *)&addr, &alen) != 0) {
        snprintf(err, err_len, "--control-tcp %u: %s", port, strerror(errno));
        if (fd >= 0) {
            close(fd);
        }
        return -1;
    }
    if (loop_watch_fd(c->lp, fd, EPOLLIN, tcp_ready, c) != 0) {
        snprintf(err, err_len, "--control-tcp %u: epoll: %s", port, strerror(errno));
        close(fd);
        return -1;
    }
    c->tcp_fd = fd;
    c->tcp_port = ntohs(addr.sin_port);
    return 0;
}

void control_close(control *c)
{
    for (size_t i = 0; i < CONTROL_MAX_CLIENTS; i++) {
        if (c->clients[i].fd >= 0) {
            (void)flush_client(c, &c->clients[i]); /* the last events, if the socket takes them */
        }
        drop_client(c, &c->clients[i]);
    }
    if (c->unix_fd >= 0) {
        loop_unwatch_fd(c->lp, c->unix_fd);
        close(c->unix_fd);
        (void)unlink(c->path);
        c->unix_fd = -1;
    }
    if (c->tcp_fd >= 0) {
        loop_unwatch_fd(c->lp, c->tcp_fd);
        close(c->tcp_fd);
        c->tcp_fd = -1;
    }
}
