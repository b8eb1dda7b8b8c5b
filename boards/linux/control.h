/* The control socket of canopen-drive (--control PATH, --control-tcp PORT): the operator's
 * commands (commands.h) for programs, on the same epoll loop, no threads.
 *
 * Protocol version 1, lines of text ending in '\n' both ways (README "Control socket"):
 *   on connect     the server sends "hello canopen-drive control 1"
 *   a command      any stdin command, or subscribe / unsubscribe / version; its answer is zero or
 *                  more "data TEXT" lines, then "ok" or "error REASON" (exactly one of them)
 *   events         after "subscribe": "event SECONDS LINE" for every line the simulator logs on
 *                  stdout for a node (SECONDS since the simulator started, 6 decimals), in order,
 *                  possibly between the data lines and the ok of a command
 * A line longer than CONTROL_LINE_MAX - 1 bytes, or holding bytes other than printable ASCII,
 * tab and CR, is answered "error ..." and not run; a line not ended by '\n' when the client goes
 * away is dropped, never run. A client that lets CONTROL_OUT_MAX bytes of answers and events pile
 * up unread is disconnected (reported on stderr); the others and the simulation go on. */
#ifndef BOARDS_LINUX_CONTROL_H
#define BOARDS_LINUX_CONTROL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "commands.h"
#include "loop.h"

#define CONTROL_PROTOCOL 1
#define CONTROL_MAX_CLIENTS 16u
#define CONTROL_LINE_MAX LOOP_LINE_MAX
#define CONTROL_OUT_MAX (64u * 1024u)
#define CONTROL_PATH_MAX 108u      /* sun_path */

struct control;

typedef struct control_client {
    struct control *owner;
    int fd;                        /* -1: free */
    bool subscribed;
    bool too_long;                 /* the current line overflowed: answered at its '\n' */
    bool binary;                   /* the current line holds a byte we do not take */
    size_t in_len;
    char in[CONTROL_LINE_MAX];
    size_t out_len;
    char out[CONTROL_OUT_MAX];
} control_client;

typedef struct control {
    int unix_fd;                   /* listening sockets, -1 when not open */
    int tcp_fd;
    unsigned tcp_port;             /* the port bound (useful with port 0) */
    char path[CONTROL_PATH_MAX];
    loop *lp;
    cmd_env env;
    uint64_t t0;                   /* event times count from here */
    uint32_t accepted, dropped;    /* clients accepted; disconnected for not reading */
    control_client clients[CONTROL_MAX_CLIENTS];
} control;

/* Prepares c (no socket yet); env says what commands act on; t0 is the simulator's start. */
void control_init(control *c, loop *lp, const cmd_env *env, uint64_t t0);

/* Listens on the Unix socket path. A stale socket file (nobody accepting) is replaced; anything
 * else at path (a live simulator's socket, a regular file) is refused. Returns 0, or -1 with a
 * one-line reason in err. */
int control_listen_unix(control *c, const char *path, char *err, size_t err_len);

/* Listens on 127.0.0.1:port (0: a free port, then in c->tcp_port). Returns 0 or -1 with err. */
int control_listen_tcp(control *c, unsigned port, char *err, size_t err_len);

/* A log line of a node (sim_node.log_hook): sent as an event to every subscriber. */
void control_event(void *c, const char *line);

/* Disconnects every client, closes the listening sockets and removes the socket file. */
void control_close(control *c);

#endif
