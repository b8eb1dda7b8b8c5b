/* SocketCAN driver: raw socket, receive filters, error frames, non-blocking transmit. */
#define _GNU_SOURCE
#include "socketcan.h"

#include <errno.h>
#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include "canopen/node.h"

/* ENOBUFS retry: first after 1 ms, doubling up to 20 ms (a full interface queue drains in a few
 * frame times at any real bit rate; vcan never fills). */
#define SC_BACKOFF_MIN_US 1000u
#define SC_BACKOFF_MAX_US 20000u

static void copy_name(char *dst, size_t cap, const char *src)
{
    size_t n = strlen(src);
    if (n >= cap) {
        n = cap - 1u;
    }
    memcpy(dst, src, n);
    dst[n] = '\0';
}

static void port_reset(sc_port *port)
{
    memset(port, 0, sizeof *port);
    port->fd = -1;
    port->sys_send = send;
    port->tx_backoff_us = SC_BACKOFF_MIN_US;
}

void sc_attach(sc_port *port, int fd, const char *name)
{
    port_reset(port);
    port->fd = fd;
    copy_name(port->iface, sizeof port->iface, name);
}

int sc_open(sc_port *port, const char *iface, char *err, size_t err_len)
{
    port_reset(port);
    copy_name(port->iface, sizeof port->iface, iface);
    if (strlen(iface) == 0u || strlen(iface) >= IFNAMSIZ) {
        snprintf(err, err_len, "'%s' is not a valid interface name", iface);
        return -1;
    }
    int fd = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
    if (fd < 0) {
        if (errno == EAFNOSUPPORT) {
            snprintf(err, err_len,
                     "this kernel has no SocketCAN (socket(AF_CAN) failed: %s); run it through "
                     "tools/vcan-run, which provides vcan0/vcan1 in a User-Mode Linux guest",
                     strerror(errno));
        } else {
            snprintf(err, err_len, "socket(AF_CAN): %s", strerror(errno));
        }
        return -1;
    }
    unsigned int ifindex = if_nametoindex(iface);
    if (ifindex == 0u) {
        snprintf(err, err_len,
                 "no network interface '%s' (create it: ip link add dev %s type vcan && ip link "
                 "set %s up; or run through tools/vcan-run)",
                 iface, iface, iface);
        close(fd);
        return -1;
    }
    /* Nothing arrives until sc_set_filters opens the node's COB-IDs. */
    if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, NULL, 0) != 0) {
        snprintf(err, err_len, "%s: CAN_RAW_FILTER: %s", iface, strerror(errno));
        close(fd);
        return -1;
    }
    can_err_mask_t err_mask = CAN_ERR_BUSOFF | CAN_ERR_CRTL | CAN_ERR_RESTARTED;
    if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask) != 0) {
        snprintf(err, err_len, "%s: CAN_RAW_ERR_FILTER: %s", iface, strerror(errno));
        close(fd);
        return -1;
    }
    int one = 1;
    /* Frames the socket queue had to drop are counted by the kernel: report them as overruns. */
    (void)setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one);
    int rcvbuf = 1 << 20;
    (void)setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);

    struct sockaddr_can addr;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = (int)ifindex;
    if (bind(fd, (struct sockaddr *)&addr, sizeof addr) != 0) {
        snprintf(err, err_len, "%s: bind: %s (is it a CAN interface?)", iface, strerror(errno));
        close(fd);
        return -1;
    }
    port->fd = fd;
    return 0;
}

int sc_iface_is_up(int fd, const char *iface)
{
    struct ifreq ifr;
    memset(&ifr, 0, sizeof ifr);
    copy_name(ifr.ifr_name, sizeof ifr.ifr_name, iface);
    if (ioctl(fd, SIOCGIFFLAGS, &ifr) != 0) {
        return -1;
    }
    return (ifr.ifr_flags & IFF_UP) != 0 ? 1 : 0;
}

void sc_close(sc_port *port)
{
    if (port->fd >= 0) {
        close(port->fd);
    }
    port->fd = -1;
}

/* --- transmit ---------------------------------------------------------------------------------- */

bool sc_send(void *ctx, const co_frame *frame)
{
    sc_port *port = ctx;
    if (port->tx_state != SC_TX_READY || port->hold) {
        return false; /* an earlier frame is waiting, or on hold: the core keeps the order */
    }
    if (port->muted) {
        port->stats.tx_muted++; /* a simulated loss of the node's transmitter: gone */
        return true;
    }
    struct can_frame cf;
    memset(&cf, 0, sizeof cf);
    cf.can_id = frame->id & CAN_SFF_MASK;
    if ((frame->flags & CO_FRAME_RTR) != 0u) {
        cf.can_id |= CAN_RTR_FLAG;
    }
    cf.can_dlc = frame->dlc <= 8u ? frame->dlc : 8u;
    if ((frame->flags & CO_FRAME_RTR) == 0u) {
        memcpy(cf.data, frame->data, cf.can_dlc);
    }
    for (;;) {
        ssize_t n = port->sys_send(port->fd, &cf, sizeof cf, MSG_DONTWAIT);
        if (n == (ssize_t)sizeof cf) {
            port->stats.tx_frames++;
            port->tx_backoff_us = SC_BACKOFF_MIN_US;
            return true;
        }
        if (n < 0 && errno == EINTR) {
            continue;
        }
        port->tx_errno = n < 0 ? errno : EIO;
        if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
            port->stats.tx_eagain++;
            port->tx_state = SC_TX_WAIT_WRITABLE;
        } else {
            if (n < 0 && errno == ENOBUFS) {
                port->stats.tx_enobufs++;
            } else {
                port->stats.tx_other_errors++; /* ENETDOWN, ...: try again later, keep frames */
            }
            port->tx_state = SC_TX_WAIT_RETRY;
            port->tx_retry_at = 0u;
        }
        return false;
    }
}

uint64_t sc_tx_retry_time(sc_port *port, uint64_t now)
{
    if (port->tx_state != SC_TX_WAIT_RETRY) {
        return UINT64_MAX;
    }
    if (port->tx_retry_at == 0u) {
        port->tx_retry_at = now + port->tx_backoff_us;
        port->tx_backoff_us = port->tx_backoff_us * 2u > SC_BACKOFF_MAX_US
                                  ? SC_BACKOFF_MAX_US
                                  : port->tx_backoff_us * 2u;
    }
    return port->tx_retry_at;
}

void sc_tx_resume(sc_port *port)
{
    port->tx_state = SC_TX_READY;
    port->tx_retry_at = 0u;
}

/* --- receive ----------------------------------------------------------------------------------- */

static void push_event(sc_port *port, sc_bus_event event)
{
    if (port->pending_count < sizeof port->pending / sizeof port->pending[0]) {
        port->pending[port->pending_count++] = event;
    }
}

static bool pop_event(sc_port *port, sc_bus_event *event)
{
    if (port->pending_count == 0u) {
        return false;
    }
    *event = port->pending[0];
    port->pending_count--;
    memmove(&port->pending[0], &port->pending[1], port->pending_count * sizeof port->pending[0]);
    return true;
}

/* Error frame -> events, most severe first (see linux/can/error.h). */
static void decode_error_frame(sc_port *port, const struct can_frame *cf)
{
    canid_t id = cf->can_id;
    uint8_t ctrl = cf->can_dlc >= 2u ? cf->data[1] : 0u;
    if ((id & CAN_ERR_BUSOFF) != 0u) {
        push_event(port, SC_BUS_OFF);
    }
    if ((id & CAN_ERR_CRTL) != 0u) {
        if ((ctrl & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) != 0u) {
            push_event(port, SC_BUS_ERROR_PASSIVE);
        } else if ((ctrl & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) != 0u) {
            push_event(port, SC_BUS_ERROR_WARNING);
        }
        if ((ctrl & CAN_ERR_CRTL_ACTIVE) != 0u) {
            push_event(port, SC_BUS_ERROR_ACTIVE);
        }
        if ((ctrl & CAN_ERR_CRTL_RX_OVERFLOW) != 0u) {
            push_event(port, SC_BUS_RX_OVERRUN);
        }
    }
    if ((id & CAN_ERR_RESTARTED) != 0u) {
        push_event(port, SC_BUS_RESTARTED);
    }
}

sc_recv_result sc_recv(sc_port *port, co_frame *frame, sc_bus_event *event)
{
    if (pop_event(port, event)) {
        return SC_RECV_EVENT;
    }
    struct can_frame cf;
    struct iovec iov = {&cf, sizeof cf};
    union {
        char buf[CMSG_SPACE(sizeof(uint32_t))];
        struct cmsghdr align;
    } control;
    struct msghdr msg;
    memset(&msg, 0, sizeof msg);
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control.buf;
    msg.msg_controllen = sizeof control.buf;
    ssize_t n;
    do {
        n = recvmsg(port->fd, &msg, MSG_DONTWAIT);
    } while (n < 0 && errno == EINTR);
    if (n < 0) {
        return (errno == EAGAIN || errno == EWOULDBLOCK) ? SC_RECV_NONE : SC_RECV_ERROR;
    }
    if (n == 0) {
        return SC_RECV_NONE;
    }
    for (struct cmsghdr *c = CMSG_FIRSTHDR(&msg); c != NULL; c = CMSG_NXTHDR(&msg, c)) {
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL &&
            c->cmsg_len >= CMSG_LEN(sizeof(uint32_t))) {
            uint32_t drops;
            memcpy(&drops, CMSG_DATA(c), sizeof drops);
            if (drops != port->kernel_drops) {
                port->stats.rx_dropped_by_kernel += drops - port->kernel_drops;
                port->kernel_drops = drops;
                push_event(port, SC_BUS_RX_OVERRUN);
            }
        }
    }
    if ((size_t)n != sizeof cf) {
        return SC_RECV_SKIPPED; /* CAN FD or something else: not CANopen CC */
    }
    if ((cf.can_id & CAN_ERR_FLAG) != 0u) {
        port->stats.rx_error_frames++;
        decode_error_frame(port, &cf);
        return pop_event(port, event) ? SC_RECV_EVENT : SC_RECV_SKIPPED;
    }
    if ((cf.can_id & CAN_EFF_FLAG) != 0u) {
        return pop_event(port, event) ? SC_RECV_EVENT : SC_RECV_SKIPPED;
    }
    port->stats.rx_frames++;
    frame->id = (uint16_t)(cf.can_id & CAN_SFF_MASK);
    /* A DLC above 8 on a classic frame means 8 bytes (ISO 11898-1); the core sees 8. */
    frame->dlc = cf.can_dlc <= 8u ? cf.can_dlc : 8u;
    frame->flags = (cf.can_id & CAN_RTR_FLAG) != 0u ? CO_FRAME_RTR : 0u;
    memset(frame->data, 0, sizeof frame->data);
    if ((frame->flags & CO_FRAME_RTR) == 0u) {
        memcpy(frame->data, cf.data, frame->dlc);
    }
    /* An overrun noticed with this frame is reported with the next read. */
    return SC_RECV_FRAME;
}

/* --- filters ----------------------------------------------------------------------------------- */

static int cmp_u16(const void *a, const void *b)
{
    uint16_t x = *(const uint16_t *)a;
    uint16_t y = *(const uint16_t *)b;
    return (x > y) - (x < y);
}

int sc_set_filters(sc_port *port, const uint16_t *ids, size_t count)
{
    uint16_t sorted[SC_MAX_FILTERS];
    size_t n = 0;
    for (size_t i = 0; i < count && n < SC_MAX_FILTERS; i++) {
        sorted[n++] = ids[i] & CAN_SFF_MASK;
    }
    qsort(sorted, n, sizeof sorted[0], cmp_u16);
    size_t unique = 0;
    for (size_t i = 0; i < n; i++) {
        if (unique == 0u || sorted[unique - 1u] != sorted[i]) {
            sorted[unique++] = sorted[i];
        }
    }
    if (unique == port->filter_count &&
        memcmp(sorted, port->filter_ids, unique * sizeof sorted[0]) == 0) {
        return 0;
    }
    struct can_filter filters[SC_MAX_FILTERS];
    for (size_t i = 0; i < unique; i++) {
        filters[i].can_id = sorted[i];
        /* Exact 11-bit ID, data or remote frame, never an extended frame. */
        filters[i].can_mask = CAN_SFF_MASK | CAN_EFF_FLAG;
    }
    if (setsockopt(port->fd, SOL_CAN_RAW, CAN_RAW_FILTER, filters,
                   (socklen_t)(unique * sizeof filters[0])) != 0) {
        return -1;
    }
    memcpy(port->filter_ids, sorted, unique * sizeof sorted[0]);
    port->filter_count = (uint16_t)unique;
    port->stats.filter_updates++;
    return 0;
}

static size_t add_id(uint16_t *ids, size_t n, size_t cap, uint32_t id)
{
    if (n < cap) {
        ids[n++] = (uint16_t)(id & 0x7FFu);
    }
    return n;
}

size_t sc_node_cob_ids(const co_node *node, uint16_t *ids, size_t cap)
{
    const co_od *od = node->od;
    uint32_t id = node->node_id;
    size_t n = 0;
    n = add_id(ids, n, cap, 0x000u);            /* NMT */
    n = add_id(ids, n, cap, 0x080u);            /* SYNC (default) */
    n = add_id(ids, n, cap, 0x100u);            /* TIME (default) */
    n = add_id(ids, n, cap, 0x7E5u);            /* LSS master -> slave */
    n = add_id(ids, n, cap, node->sdo_rx_cob);
    n = add_id(ids, n, cap, 0x600u + id);       /* default SDO server */
    n = add_id(ids, n, cap, 0x700u + id);       /* node guarding RTR */
    for (uint32_t k = 0; k < 4u; k++) {         /* predefined connection set */
        n = add_id(ids, n, cap, 0x200u + 0x100u * k + id); /* RPDO1..4 */
        n = add_id(ids, n, cap, 0x180u + 0x100u * k + id); /* TPDO1..4 (RTR) */
    }
    for (uint32_t e = 0; e < od->entry_count; e++) {
        const co_od_entry *entry = &od->entries[e];
        uint16_t index = entry->index;
        if (index == 0x1005u || index == 0x1012u) { /* SYNC, TIME COB-IDs */
            n = add_id(ids, n, cap, co_od_get_u32(node, index, 0));
        } else if (index >= 0x1200u && index <= 0x127Fu) { /* SDO servers: client -> server */
            uint32_t cob = co_od_get_u32(node, index, 1);
            if (cob != 0u) {
                n = add_id(ids, n, cap, cob);
            }
        } else if ((index >= 0x1400u && index <= 0x15FFu) ||
                   (index >= 0x1800u && index <= 0x19FFu)) { /* PDO COB-IDs, valid or not */
            uint32_t cob = co_od_get_u32(node, index, 1);
            if (cob != 0u) {
                n = add_id(ids, n, cap, cob);
            }
        } else if (index == 0x1016u || index == 0x1028u) { /* heartbeat / EMCY consumers */
            for (uint32_t s = 0; s < entry->sub_count; s++) {
                const co_od_sub *sub = &entry->subs[s];
                if (sub->subindex == 0u || sub->size != 4u) {
                    continue;
                }
                uint32_t v = co_od_get_u32(node, index, sub->subindex);
                if (index == 0x1016u) {
                    uint32_t producer = (v >> 16) & 0xFFu;
                    if (producer >= 1u && producer <= 127u) {
                        n = add_id(ids, n, cap, 0x700u + producer);
                    }
                } else if ((v & 0x80000000u) == 0u && v != 0u) {
                    n = add_id(ids, n, cap, v);
                }
            }
        }
    }
    return n;
}

const char *sc_bus_event_name(sc_bus_event event)
{
    switch (event) {
    case SC_BUS_OFF: return "bus-off";
    case SC_BUS_ERROR_PASSIVE: return "error passive";
    case SC_BUS_ERROR_WARNING: return "error warning";
    case SC_BUS_ERROR_ACTIVE: return "error active";
    case SC_BUS_RESTARTED: return "controller restarted";
    case SC_BUS_RX_OVERRUN: return "receive overrun";
    default: return "none";
    }
}
