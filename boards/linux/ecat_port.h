/* The EtherCAT face of canopen-drive: a line of emulated EtherCAT slaves on one Ethernet
 * interface, reached through a raw AF_PACKET socket (EtherType 0x88A4) in the same epoll loop as
 * everything else.
 *
 * Each position of the line is one drive: an emulated ESC (ecat/include/canopen/ecat/esc.h) with
 * the drive's SII image, the slave application layer (slave.h: ESM, mailbox, CoE, process data)
 * and the drive itself (its co_drive, created by sim.c as for CAN). A frame from the master passes
 * the ESCs in line order (co_esc_chain_process), as it passes the processing units of a real line,
 * and goes back out on the interface, as the last slave of a line returns it. Positions count from
 * 1 in the order of the --drive options, as a master numbers the slaves it finds (SOEM slave 1 is
 * the first after the master).
 *
 * The drive keeps its co_node (one dictionary, one drive) but has no CAN face: its CAN frames go
 * nowhere (the node is reached over CoE only).
 *
 *   ecat_port ep; ecat_port_open(&ep, "veth0", err, sizeof err);
 *   ecat_port_add(&ep, "vf-mb1-ecat", &drive, err, sizeof err);   // once per position
 *   co_drive_start(&drive, now_us);
 *   ecat_port_start(&ep, now_us);                                 // ESCs and slaves up, INIT
 *   on input: ecat_port_input(&ep, now_us); at deadlines: ecat_port_process(&ep, now_us)
 */
#ifndef BOARDS_LINUX_ECAT_PORT_H
#define BOARDS_LINUX_ECAT_PORT_H

#include <net/if.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>

#include "canopen/drive.h"
#include "canopen/ecat/esc.h"
#include "canopen/ecat/slave.h"

#define ECAT_PORT_MAX_SLAVES 32u
#define ECAT_ETHERTYPE 0x88A4u
/* The largest Ethernet frame without FCS (1500 bytes of payload). */
#define ECAT_FRAME_MAX 1514u
/* Frames read in one ecat_port_input call before the loop looks at its other members. */
#define ECAT_RX_BATCH 64u

/* One position of the line. */
typedef struct ecat_slot {
    const char *id;         /* drive id (for logs) */
    unsigned position;      /* 1-based */
    co_drive *drive;
    co_esc esc;
    co_ecat_slave slave;
    uint8_t logged_state;   /* AL status last logged (state and error bit) */
    uint16_t logged_code;   /* AL status code last logged */
} ecat_slot;

typedef struct ecat_stats {
    uint32_t rx_frames;     /* EtherCAT frames received and processed */
    uint32_t rx_bad;        /* frames the ESCs refused (short, bad length): not sent back */
    uint32_t rx_skipped;    /* our own frames seen again (PACKET_OUTGOING), other EtherTypes */
    uint32_t rx_errors;     /* recv errors other than "nothing more" */
    uint32_t tx_frames;     /* frames sent back */
    uint32_t tx_errors;     /* send failures (the master sees a lost frame) */
} ecat_stats;

typedef struct ecat_port {
    int fd;
    int ifindex;                       /* 0 for an attached test descriptor */
    char iface[IF_NAMESIZE];
    ecat_slot *slots[ECAT_PORT_MAX_SLAVES];
    co_esc *chain[ECAT_PORT_MAX_SLAVES];
    size_t count;
    bool started;
    ecat_stats stats;
    uint8_t buf[ECAT_FRAME_MAX + 64u]; /* one frame; room to see an oversized one as such */
    /* The system calls, replaceable by tests (injected errors). */
    ssize_t (*sys_send)(int fd, const void *buf, size_t len, int flags);
} ecat_port;

/* Whether drive id has an EtherCAT face (an SII image and a slave layout): vf-mb1-ecat. */
bool ecat_drive_supported(const char *id);
/* The ids that have one, for messages ("vf-mb1-ecat"). */
const char *ecat_drive_ids(void);

/* Opens a raw packet socket for EtherType 0x88A4 bound to iface, in promiscuous mode (an ESC
 * processes every EtherCAT frame, whatever its destination address). 0, or -1 with the reason in
 * err (no such interface, no permission: CAP_NET_RAW, ...). */
int ecat_port_open(ecat_port *ep, const char *iface, char *err, size_t err_len);

/* Uses fd (a datagram socketpair end in tests) as the port's socket: frames in, frames out. */
void ecat_port_attach(ecat_port *ep, int fd, const char *name);

/* Whether the interface is up (IFF_UP): 1, 0, or -1 if it cannot be asked. */
int ecat_port_iface_up(const ecat_port *ep);

/* Appends drive (of drive id) at the next position and unplugs its CAN face (its CAN frames are
 * dropped). Before ecat_port_start and before the drive starts. 0, or -1 with a reason. */
int ecat_port_add(ecat_port *ep, const char *id, co_drive *drive, char *err, size_t err_len);

/* Powers the line on once every drive has started: each ESC gets its SII image (ports 0 and 1
 * open, the last slave's port 1 closed: the end of the line), each slave its layout; all in INIT.
 * 0, or -1 with a reason. */
int ecat_port_start(ecat_port *ep, uint64_t now_us, char *err, size_t err_len);

/* Reads the waiting frames (up to ECAT_RX_BATCH), passes each through the line and sends it back,
 * running every slave after each frame. */
void ecat_port_input(ecat_port *ep, uint64_t now_us);

/* Runs every slave (and logs EtherCAT state changes); returns when to call again (us,
 * UINT64_MAX: never). The drives themselves run through their sim_node. */
uint64_t ecat_port_process(ecat_port *ep, uint64_t now_us);

/* The slot at position (1-based), NULL if none. */
ecat_slot *ecat_port_slot(ecat_port *ep, unsigned position);

/* The status line of the slot (into buf, cap bytes): EtherCAT state, AL status code, the RUN and ERR LEDs as the
 * manual describes them, mailbox and process-data counters. */
void ecat_port_status_line(const ecat_port *ep, const ecat_slot *slot, char *buf, size_t cap);

/* Closes the socket and frees the slots. */
void ecat_port_close(ecat_port *ep);

#endif
