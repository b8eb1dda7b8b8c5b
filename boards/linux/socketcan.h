/* SocketCAN driver for the Linux port: one raw CAN socket per simulated node, so nodes in one
 * process see each other's frames exactly as separate devices on the bus would (the kernel's local
 * loopback delivers a frame to every other socket on the interface).
 *
 * - Receive filters: only the COB-IDs a node can consume reach it (sc_node_cob_ids), recomputed
 *   whenever its communication parameters may have changed; classic 11-bit frames only.
 * - Error frames: bus-off, error passive/warning, back to error active, controller restarted and
 *   receive overruns (controller and socket queue) become sc_bus_event values.
 * - Transmit: non-blocking. When the kernel cannot take a frame, sc_send returns false and the core
 *   keeps it (and every later frame, in order) in its own queue. EAGAIN means the socket buffer is
 *   full: wait for EPOLLOUT. ENOBUFS means the interface's queue is full, which poll() does not
 *   report (the socket stays "writable"), so it is retried after a short, growing delay instead.
 *   Either way the loop calls co_node_tx_ready() once the port can send again: no frame is lost. */
#ifndef BOARDS_LINUX_SOCKETCAN_H
#define BOARDS_LINUX_SOCKETCAN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>

#include "canopen/frame.h"

struct co_node;

/* Why the port cannot send right now. */
typedef enum sc_tx_state {
    SC_TX_READY = 0,     /* frames go straight to the socket */
    SC_TX_WAIT_WRITABLE, /* EAGAIN: wait for EPOLLOUT */
    SC_TX_WAIT_RETRY     /* ENOBUFS or the interface is down: retry at tx_retry_at */
} sc_tx_state;

/* What an error frame (or the socket) said about the bus. */
typedef enum sc_bus_event {
    SC_BUS_NONE = 0,
    SC_BUS_OFF,            /* the controller went bus-off */
    SC_BUS_ERROR_PASSIVE,  /* rx or tx error counter reached 128 */
    SC_BUS_ERROR_WARNING,  /* an error counter reached 96 */
    SC_BUS_ERROR_ACTIVE,   /* back to error active */
    SC_BUS_RESTARTED,      /* the controller was restarted after bus-off */
    SC_BUS_RX_OVERRUN      /* received frames were lost (controller or socket queue) */
} sc_bus_event;

/* Frames the port has seen and what it did with them. */
typedef struct sc_stats {
    uint32_t rx_frames;
    uint32_t rx_dropped_by_kernel; /* socket receive queue overflowed (SO_RXQ_OVFL) */
    uint32_t rx_error_frames;
    uint32_t tx_frames;
    uint32_t tx_eagain;            /* sends refused with EAGAIN (frame kept by the core) */
    uint32_t tx_enobufs;           /* sends refused with ENOBUFS (frame kept by the core) */
    uint32_t tx_other_errors;      /* other refusals (interface down, ...), frame kept */
    uint32_t filter_updates;
    uint32_t tx_muted;             /* frames dropped while the port was muted */
} sc_stats;

/* Most COB-IDs one node listens to (kernel limit CAN_RAW_FILTER_MAX is 512). */
#define SC_MAX_FILTERS 256u

typedef struct sc_port {
    int fd;
    char iface[16];
    sc_tx_state tx_state;
    bool hold;                     /* sc_send refuses (the core queues) until released */
    bool muted;                    /* sc_send drops every frame (a node gone silent: its
                                      heartbeat, PDOs and answers stop); receiving goes on */
    int tx_errno;                  /* errno of the latest refused send */
    uint32_t tx_backoff_us;        /* current ENOBUFS retry delay */
    uint64_t tx_retry_at;          /* SC_TX_WAIT_RETRY: when to try again (0: not yet planned) */
    uint32_t kernel_drops;         /* latest SO_RXQ_OVFL counter */
    sc_bus_event pending[6];       /* events of the latest error frame not returned yet */
    uint8_t pending_count;
    uint16_t filter_ids[SC_MAX_FILTERS];
    uint16_t filter_count;
    sc_stats stats;
    /* The system call used to send; tests replace it to inject EAGAIN/ENOBUFS. */
    ssize_t (*sys_send)(int fd, const void *buf, size_t len, int flags);
} sc_port;

/* Opens a raw CAN socket bound to iface (non-blocking, close-on-exec, error frames on, receive
 * filters closed until sc_set_filters). Returns 0, or -1 with a one-line reason in err. */
int sc_open(sc_port *port, const char *iface, char *err, size_t err_len);

/* Uses an already open descriptor (tests: one end of a socketpair carrying struct can_frame). */
void sc_attach(sc_port *port, int fd, const char *name);

void sc_close(sc_port *port);

/* Whether the interface iface is up (IFF_UP), asked through the open socket fd: 1 up, 0 down,
 * -1 unknown (errno). A port on a down interface opens fine, but nothing is sent or received
 * until the interface comes up. */
int sc_iface_is_up(int fd, const char *iface);

/* co_driver.send: true if the kernel took the frame; false (frame kept by the core) when the
 * socket is full, a previous refusal has not been cleared yet (keeps the order), or the port is
 * on hold (see sc_port.hold: the caller then releases the frames with co_node_tx_ready). */
bool sc_send(void *port, const co_frame *frame);

/* The result of one sc_recv. */
typedef enum sc_recv_result {
    SC_RECV_NONE = 0,  /* nothing more to read (EAGAIN) */
    SC_RECV_FRAME,     /* *frame holds a CANopen frame */
    SC_RECV_EVENT,     /* *event holds a bus event (an error frame or a queue overflow) */
    SC_RECV_SKIPPED,   /* something that is not for CANopen (extended frame, ...): read again */
    SC_RECV_ERROR      /* the socket failed (errno set) */
} sc_recv_result;

/* Reads one frame without blocking. An error frame may carry several events: they are returned
 * one per call (the rest stay pending in the port). */
sc_recv_result sc_recv(sc_port *port, co_frame *frame, sc_bus_event *event);

/* Sets the receive filters to exactly these 11-bit COB-IDs (sorted and de-duplicated here).
 * Does nothing when the set has not changed. Returns 0 or -1 (errno). */
int sc_set_filters(sc_port *port, const uint16_t *ids, size_t count);

/* Every COB-ID the node may have to receive: NMT, SYNC, TIME, LSS, its SDO server(s), the
 * predefined connection set for its node-ID (RPDOs, TPDO and guarding RTRs), every RPDO/TPDO
 * COB-ID configured in 0x1400-0x15FF / 0x1800-0x19FF (valid or not, so enabling one needs no
 * refilter race), EMCY consumers (0x1028) and heartbeat producers it monitors (0x1016).
 * Generous on purpose: a missing ID silently breaks a service, an extra one costs a dropped frame.
 * Returns the number of IDs written to ids (at most cap). */
size_t sc_node_cob_ids(const struct co_node *node, uint16_t *ids, size_t cap);

/* The port after a refused send: SC_TX_WAIT_RETRY states plan their retry at now + backoff.
 * Returns the time of the retry (UINT64_MAX when not waiting for one). */
uint64_t sc_tx_retry_time(sc_port *port, uint64_t now);

/* The port may send again (EPOLLOUT, or the retry time came): back to SC_TX_READY. The caller
 * then calls co_node_tx_ready(). */
void sc_tx_resume(sc_port *port);

/* Name of an event, for logs. */
const char *sc_bus_event_name(sc_bus_event event);

#endif
