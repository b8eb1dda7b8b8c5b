/* The EtherCAT line of canopen-drive: raw Ethernet socket, ESC chain, slave application layers. */
#define _GNU_SOURCE
#include "ecat_port.h"

#include <arpa/inet.h>
#include <errno.h>
#include <linux/if_packet.h>
#include <net/ethernet.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include "od_vf_mb1_ecat.h"
#include "sii_vf_mb1_ecat.h"

/* The drives with an EtherCAT face: their SII image and their slave layout (the SII's numbers). */
typedef struct ecat_face {
    const char *id;
    const uint8_t *sii;
    size_t sii_size;
    co_ecat_slave_config (*layout)(void);
} ecat_face;

static co_ecat_slave_config vf_mb1_layout(void)
{
    co_ecat_slave_config c = co_ecat_slave_default_config(); /* ecat.ini's layout */
    c.mbx_out_start = CO_SII_VF_MB1_ECAT_SM0_START;
    c.mbx_out_size = CO_SII_VF_MB1_ECAT_SM0_LENGTH;
    c.mbx_out_ctrl = CO_SII_VF_MB1_ECAT_SM0_CONTROL;
    c.mbx_in_start = CO_SII_VF_MB1_ECAT_SM1_START;
    c.mbx_in_size = CO_SII_VF_MB1_ECAT_SM1_LENGTH;
    c.mbx_in_ctrl = CO_SII_VF_MB1_ECAT_SM1_CONTROL;
    c.out_start = CO_SII_VF_MB1_ECAT_SM2_START;
    c.out_ctrl = CO_SII_VF_MB1_ECAT_SM2_CONTROL;
    c.in_start = CO_SII_VF_MB1_ECAT_SM3_START;
    c.in_ctrl = CO_SII_VF_MB1_ECAT_SM3_CONTROL;
    c.rx_pdo = CO_SII_VF_MB1_ECAT_RXPDO1;
    c.tx_pdo = CO_SII_VF_MB1_ECAT_TXPDO1;
#if !defined(CO_OD_NO_NAMES)
    /* the EDS names for SDO information (the drive's dictionary is co_od_vf_mb1_ecat) */
    c.entry_names = co_od_vf_mb1_ecat_entry_names;
    c.sub_names = co_od_vf_mb1_ecat_sub_names;
#endif
    return c;
}

static const ecat_face faces[] = {
    {"vf-mb1-ecat", co_sii_vf_mb1_ecat, CO_SII_VF_MB1_ECAT_SIZE, vf_mb1_layout},
};

static const ecat_face *find_face(const char *id)
{
    for (size_t i = 0; i < sizeof faces / sizeof faces[0]; i++) {
        if (strcmp(faces[i].id, id) == 0) {
            return &faces[i];
        }
    }
    return NULL;
}

bool ecat_drive_supported(const char *id)
{
    return find_face(id) != NULL;
}

const char *ecat_drive_ids(void)
{
    return "vf-mb1-ecat";
}

/* The drive's CAN frames: there is no CAN face on the EtherCAT line. Accepted and dropped, so the
 * core never queues them. */
static bool no_can(void *ctx, const co_frame *frame)
{
    (void)ctx;
    (void)frame;
    return true;
}

static void port_reset(ecat_port *ep)
{
    memset(ep, 0, sizeof *ep);
    ep->fd = -1;
    ep->sys_send = send;
}

int ecat_port_open(ecat_port *ep, const char *iface, char *err, size_t err_len)
{
    port_reset(ep);
    if (strlen(iface) >= sizeof ep->iface) {
        snprintf(err, err_len, "interface name '%s' is too long", iface);
        return -1;
    }
    strcpy(ep->iface, iface);
    unsigned idx = if_nametoindex(iface);
    if (idx == 0u) {
        snprintf(err, err_len, "no interface %s: %s", iface, strerror(errno));
        return -1;
    }
    int fd = socket(AF_PACKET, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, htons(ECAT_ETHERTYPE));
    if (fd < 0) {
        snprintf(err, err_len, "cannot open a raw packet socket on %s: %s%s", iface,
                 strerror(errno),
                 errno == EPERM ? " (needs root or CAP_NET_RAW; or run it through tools/veth-run)"
                                : "");
        return -1;
    }
    struct sockaddr_ll sll;
    memset(&sll, 0, sizeof sll);
    sll.sll_family = AF_PACKET;
    sll.sll_protocol = htons(ECAT_ETHERTYPE);
    sll.sll_ifindex = (int)idx;
    if (bind(fd, (struct sockaddr *)&sll, sizeof sll) != 0) {
        snprintf(err, err_len, "cannot bind to %s: %s", iface, strerror(errno));
        close(fd);
        return -1;
    }
    struct packet_mreq mr;
    memset(&mr, 0, sizeof mr);
    mr.mr_ifindex = (int)idx;
    mr.mr_type = PACKET_MR_PROMISC;
    if (setsockopt(fd, SOL_PACKET, PACKET_ADD_MEMBERSHIP, &mr, sizeof mr) != 0) {
        snprintf(err, err_len, "cannot put %s in promiscuous mode: %s", iface, strerror(errno));
        close(fd);
        return -1;
    }
    ep->fd = fd;
    ep->ifindex = (int)idx;
    return 0;
}

void ecat_port_attach(ecat_port *ep, int fd, const char *name)
{
    port_reset(ep);
    snprintf(ep->iface, sizeof ep->iface, "%s", name);
    ep->fd = fd;
}

int ecat_port_iface_up(const ecat_port *ep)
{
    struct ifreq ifr;
    memset(&ifr, 0, sizeof ifr);
    snprintf(ifr.ifr_name, sizeof ifr.ifr_name, "%s", ep->iface);
    if (ep->ifindex == 0 || ioctl(ep->fd, SIOCGIFFLAGS, &ifr) != 0) {
        return -1;
    }
    return (ifr.ifr_flags & IFF_UP) != 0 ? 1 : 0;
}

int ecat_port_add(ecat_port *ep, const char *id, co_drive *drive, char *err, size_t err_len)
{
    if (find_face(id) == NULL) {
        snprintf(err, err_len, "drive %s has no EtherCAT face (EtherCAT drives: %s)", id,
                 ecat_drive_ids());
        return -1;
    }
    if (ep->count == ECAT_PORT_MAX_SLAVES || ep->started) {
        snprintf(err, err_len, "more than %u slaves on one line", ECAT_PORT_MAX_SLAVES);
        return -1;
    }
    ecat_slot *slot = calloc(1, sizeof *slot);
    if (slot == NULL) {
        snprintf(err, err_len, "out of memory");
        return -1;
    }
    slot->id = id;
    slot->position = (unsigned)ep->count + 1u;
    slot->drive = drive;
    drive->node.driver.send = no_can;
    drive->node.driver.ctx = NULL;
    ep->slots[ep->count] = slot;
    ep->chain[ep->count] = &slot->esc;
    ep->count++;
    return 0;
}

int ecat_port_start(ecat_port *ep, uint64_t now_us, char *err, size_t err_len)
{
    for (size_t i = 0; i < ep->count; i++) {
        ecat_slot *slot = ep->slots[i];
        const ecat_face *face = find_face(slot->id);
        co_esc_config ec = co_esc_default_config();
        ec.sii = face->sii;
        ec.sii_size = face->sii_size;
        /* Port 0 towards the master; port 1 leads on to the next slave, and is closed (looped
         * back) at the last one: the DL status a master reads to find the line's topology. */
        ec.open_ports = i + 1u < ep->count ? 0x03u : 0x01u;
        if (co_esc_init(&slot->esc, &ec) != 0) {
            snprintf(err, err_len, "slave %u %s: the ESC refused its configuration",
                     slot->position, slot->id);
            return -1;
        }
        co_ecat_slave_config sc = face->layout();
        sc.esc = &slot->esc;
        sc.node = &slot->drive->node;
        sc.drive = slot->drive;
        if (!co_ecat_slave_init(&slot->slave, &sc, now_us * 1000u)) {
            snprintf(err, err_len, "slave %u %s: the application layer refused its layout",
                     slot->position, slot->id);
            return -1;
        }
        slot->logged_state = co_ecat_slave_state(&slot->slave);
        slot->logged_code = 0u;
    }
    ep->started = true;
    return 0;
}

ecat_slot *ecat_port_slot(ecat_port *ep, unsigned position)
{
    return position >= 1u && position <= ep->count ? ep->slots[position - 1u] : NULL;
}

/* --- state changes and status ----------------------------------------------------------------- */

static const char *al_code_text(uint16_t code)
{
    switch (code) {
    case CO_ECAT_AL_NO_ERROR: return "no error";
    case CO_ECAT_AL_UNSPECIFIED: return "unspecified error";
    case CO_ECAT_AL_INVALID_STATE_CHANGE: return "invalid requested state change";
    case CO_ECAT_AL_UNKNOWN_STATE: return "unknown requested state";
    case CO_ECAT_AL_BOOT_NOT_SUPPORTED: return "bootstrap not supported";
    case CO_ECAT_AL_INVALID_MBX_CONFIG: return "invalid mailbox configuration";
    case CO_ECAT_AL_INVALID_SM_CONFIG: return "invalid sync manager configuration";
    case CO_ECAT_AL_SM_WATCHDOG: return "sync manager watchdog";
    case CO_ECAT_AL_INVALID_OUTPUT_CONFIG: return "invalid output configuration";
    case CO_ECAT_AL_INVALID_INPUT_CONFIG: return "invalid input configuration";
    case CO_ECAT_AL_INVALID_INPUT_MAPPING: return "invalid input mapping";
    case CO_ECAT_AL_INVALID_OUTPUT_MAPPING: return "invalid output mapping";
    default: return "see ETG.1000.6";
    }
}

static void log_state(ecat_slot *slot)
{
    uint8_t st = slot->slave.state;
    uint16_t code = slot->slave.status_code;
    if (st == slot->logged_state && code == slot->logged_code) {
        return;
    }
    const char *from = co_ecat_state_name(slot->logged_state & CO_ECAT_STATE_MASK);
    const char *to = co_ecat_state_name(st & CO_ECAT_STATE_MASK);
    printf("slave %u %s: EtherCAT %s -> %s", slot->position, slot->id, from, to);
    if ((st & CO_ECAT_AL_ERROR) != 0u) {
        printf(", error: AL status code 0x%04X (%s)", (unsigned)code, al_code_text(code));
    }
    putchar('\n');
    fflush(stdout);
    slot->logged_state = st;
    slot->logged_code = code;
}

void ecat_port_status_line(const ecat_port *ep, const ecat_slot *slot, char *buf, size_t cap)
{
    const co_ecat_slave *s = &slot->slave;
    const co_ecat_slave_stats *st = &s->stats;
    uint8_t state = co_ecat_slave_state(s);
    snprintf(buf, cap,
             "slave %u %s: EtherCAT %s%s, AL status code 0x%04X (%s), RUN LED %s, ERR LED %s; "
             "mailbox rx %u, errors %u, SDO aborts %u, emergencies %u; outputs %u, watchdog "
             "expiries %u; line: frames %u, bad %u, sent %u, send errors %u",
             slot->position, slot->id, co_ecat_state_name(state),
             co_ecat_slave_error(s) ? " (error)" : "", (unsigned)s->status_code,
             al_code_text(s->status_code), co_ecat_slave_run_led(s), co_ecat_slave_err_led(s),
             (unsigned)st->mbx_rx, (unsigned)st->mbx_errors, (unsigned)st->sdo_aborts,
             (unsigned)st->emcy_sent, (unsigned)st->outputs, (unsigned)st->wd_expired,
             (unsigned)ep->stats.rx_frames, (unsigned)ep->stats.rx_bad,
             (unsigned)ep->stats.tx_frames, (unsigned)ep->stats.tx_errors);
}

/* --- frames ------------------------------------------------------------------------------------ */

uint64_t ecat_port_process(ecat_port *ep, uint64_t now_us)
{
    uint64_t next = UINT64_MAX;
    if (!ep->started) {
        return next;
    }
    for (size_t i = 0; i < ep->count; i++) {
        ecat_slot *slot = ep->slots[i];
        uint64_t due = co_ecat_slave_process(&slot->slave, now_us * 1000u);
        log_state(slot);
        if (due != CO_ESC_TIME_NEVER) {
            uint64_t due_us = due / 1000u + (due % 1000u != 0u ? 1u : 0u); /* not before it */
            next = due_us < next ? due_us : next;
        }
    }
    return next;
}

/* One received frame: through the line and back out. */
static void handle_frame(ecat_port *ep, size_t len, uint64_t now_us)
{
    int r = co_esc_chain_process(ep->chain, ep->count, ep->buf, len, now_us * 1000u);
    if (r == CO_ESC_FRAME_NOT_ECAT) {
        ep->stats.rx_skipped++;
        return;
    }
    if (r != CO_ESC_FRAME_OK) {
        ep->stats.rx_bad++; /* a broken frame is lost on a real line too (bad FCS) */
        return;
    }
    ep->stats.rx_frames++;
    for (;;) {
        ssize_t n = ep->sys_send(ep->fd, ep->buf, len, MSG_DONTWAIT);
        if (n == (ssize_t)len) {
            ep->stats.tx_frames++;
            break;
        }
        if (n < 0 && errno == EINTR) {
            continue;
        }
        /* A full queue or a downed link: the frame is lost, as on a wire; the master repeats. */
        ep->stats.tx_errors++;
        break;
    }
    (void)ecat_port_process(ep, now_us); /* the slaves see what the frame did at once */
}

void ecat_port_input(ecat_port *ep, uint64_t now_us)
{
    for (unsigned k = 0; k < ECAT_RX_BATCH; k++) {
        struct sockaddr_ll from;
        socklen_t from_len = sizeof from;
        memset(&from, 0, sizeof from);
        ssize_t n = recvfrom(ep->fd, ep->buf, sizeof ep->buf, MSG_DONTWAIT | MSG_TRUNC,
                             (struct sockaddr *)&from, &from_len);
        if (n < 0) {
            if (errno == EINTR) {
                continue;
            }
            if (errno != EAGAIN && errno != EWOULDBLOCK && errno != ENETDOWN) {
                ep->stats.rx_errors++;
            }
            return;
        }
        /* Our own replies, should the kernel show them to us: never processed twice. */
        if (from_len >= sizeof from && from.sll_pkttype == PACKET_OUTGOING) {
            ep->stats.rx_skipped++;
            continue;
        }
        if ((size_t)n > ECAT_FRAME_MAX) {
            ep->stats.rx_bad++; /* longer than Ethernet allows: not an EtherCAT frame */
            continue;
        }
        if (!ep->started) {
            continue;
        }
        handle_frame(ep, (size_t)n, now_us);
    }
}

void ecat_port_close(ecat_port *ep)
{
    if (ep->fd >= 0) {
        close(ep->fd);
    }
    ep->fd = -1;
    for (size_t i = 0; i < ep->count; i++) {
        free(ep->slots[i]);
        ep->slots[i] = NULL;
    }
    ep->count = 0;
}
