/* The EtherCAT slave application layer: the EtherCAT state machine (ESM), the mailbox on SM0/SM1
 * with CoE (SDO, SDO information, emergency) and the process data on SM2/SM3, for one CANopen node
 * (one object dictionary, one drive) behind one emulated ESC. It talks to the ESC only through
 * the PDI functions of esc.h (co_esc_pdi_read/write, co_esc_al_event, co_esc_tick), as firmware
 * talks to an ET1100 or a LAN9252; it talks to the node only through the core's public API (the
 * OD access functions, NMT local commands, the EMCY listener). All state is in the caller's
 * co_ecat_slave; no OS call, no allocation.
 *
 *   co_esc esc;            co_esc_init(&esc, &esc_cfg);            // SII image in esc_cfg
 *   co_drive drive;        co_drive_init(&drive, desc, &node_cfg); co_drive_start(&drive, us);
 *   co_ecat_slave slave;
 *   co_ecat_slave_config cfg = co_ecat_slave_default_config();      // the SII's SM layout
 *   cfg.esc = &esc; cfg.node = &drive.node; cfg.drive = &drive;
 *   co_ecat_slave_init(&slave, &cfg, now_ns);                        // ESM in INIT
 *   for (;;) {
 *       co_esc_process_frame(&esc, frame, len, now_ns); send the frame on;
 *       next = co_ecat_slave_process(&slave, now_ns);   // after every frame, and at `next`
 *   }
 * co_ecat_slave_process runs the drive (co_drive_process) itself and its result includes the
 * drive's deadline; calling co_drive_process as well (a CAN face of the same drive) is harmless.
 *
 * Time: the slave and the ESC count nanoseconds, the node microseconds (now_ns / 1000).
 *
 * EtherCAT state and NMT state: the node's NMT state follows the ESM (INIT -> STOPPED, PRE-OP and
 * SAFE-OP -> PRE-OPERATIONAL, OP -> OPERATIONAL), so a drive that reacts to leaving OPERATIONAL
 * (the VF-MB1's communication-interruption table) reacts to leaving OP. The SM watchdog's expiry
 * in OP also reaches the node's comm event callback as CO_COMM_RPDO_TIMEOUT (detail 1): the outputs
 * stopped arriving. If something else changes the NMT state (a reset communication by F899 = 1,
 * an NMT command on a CAN face), co_ecat_slave_process puts the node back in the state the ESM
 * asks for. A mapping write over CoE (PRE-OP only) sets bit 31 of the CAN PDO's COB-ID, as the
 * core needs for a new mapping, and SAFE-OP clears it again.
 *
 * What the layer answers (ETG.1000.6; SOES/SOEM behaviour as digested in ecat/NOTES.md):
 *   - ESM: INIT, PRE-OP, SAFE-OP, OP; BOOT refused (0x0013 from INIT, 0x0011 elsewhere); error
 *     indication (AL status bit 4) with the AL status code, acknowledged by a request with bit 4
 *     or a request for INIT; checks: SM0/SM1 as configured before PRE-OP (0x0016), SM2/SM3 as
 *     0x1C12/0x1C13 and the mapping give before SAFE-OP (0x001D outputs, 0x001E inputs, 0x0024 /
 *     0x0025 a mapping the slave cannot serve), SM watchdog in OP (0x001B).
 *   - Mailbox: 6-byte header, counter (a repeated non-zero counter is dropped), repeat request
 *     (SM1 activate bit 1 toggle), mailbox error replies (unsupported protocol, bad length).
 *   - CoE: SDO upload/download expedited, normal and segmented, complete access, abort codes of
 *     the core's OD access (the same as over CAN); SDO information (OD list, object description,
 *     entry description), segmented when the answer exceeds SM1; an emergency for every EMCY the
 *     node produces while the mailbox runs; 0x1C00, 0x1C12 and 0x1C13 from the configuration.
 *   - Process data: SM2 outputs written to the objects 0x1600 maps (CO_ORIGIN_RPDO) in OP only,
 *     each whose value differs from the output (all of them with the first buffer in OP);
 *     SM3 inputs read from the objects 0x1A00 maps, in SAFE-OP and OP.
 */
#ifndef CANOPEN_ECAT_SLAVE_H
#define CANOPEN_ECAT_SLAVE_H

#include <stdbool.h>
#include <stdint.h>

#include "canopen/ecat/esc.h"
#include "canopen/node.h"

#ifdef __cplusplus
extern "C" {
#endif

struct co_drive;

/* EtherCAT states (AL control 0x0120 / AL status 0x0130, bits 0-3) and the flags of bit 4. */
#define CO_ECAT_STATE_INIT 0x01u
#define CO_ECAT_STATE_PREOP 0x02u
#define CO_ECAT_STATE_BOOT 0x03u
#define CO_ECAT_STATE_SAFEOP 0x04u
#define CO_ECAT_STATE_OP 0x08u
#define CO_ECAT_STATE_MASK 0x0Fu
#define CO_ECAT_AL_ERROR 0x10u /* AL status: error indication; AL control: error acknowledge */

/* AL status codes (0x0134, ETG.1000.6). */
#define CO_ECAT_AL_NO_ERROR 0x0000u
#define CO_ECAT_AL_UNSPECIFIED 0x0001u
#define CO_ECAT_AL_INVALID_STATE_CHANGE 0x0011u
#define CO_ECAT_AL_UNKNOWN_STATE 0x0012u
#define CO_ECAT_AL_BOOT_NOT_SUPPORTED 0x0013u
#define CO_ECAT_AL_INVALID_MBX_CONFIG 0x0016u
#define CO_ECAT_AL_INVALID_SM_CONFIG 0x0017u
#define CO_ECAT_AL_SM_WATCHDOG 0x001Bu
#define CO_ECAT_AL_INVALID_OUTPUT_CONFIG 0x001Du
#define CO_ECAT_AL_INVALID_INPUT_CONFIG 0x001Eu
#define CO_ECAT_AL_INVALID_INPUT_MAPPING 0x0024u
#define CO_ECAT_AL_INVALID_OUTPUT_MAPPING 0x0025u

/* Largest mailbox (SM0/SM1 length) the slave buffers, and the largest process image per
 * direction (SM2/SM3 length) and mapped objects per PDO it serves. */
#ifndef CO_ECAT_MBX_MAX
#define CO_ECAT_MBX_MAX 256u
#endif
#ifndef CO_ECAT_PD_MAX
#define CO_ECAT_PD_MAX 64u
#endif
#define CO_ECAT_PD_ENTRIES 16u
/* Slave-to-master messages waiting for SM1; emergencies take at most all but one, so the answer
 * to a request always has room (an emergency that finds them taken is lost, counted). */
#ifndef CO_ECAT_TX_QUEUE
#define CO_ECAT_TX_QUEUE 4u
#endif
/* Largest value an SDO download or upload moves through the slave's own buffer. */
#ifndef CO_ECAT_SDO_BUF
#define CO_ECAT_SDO_BUF 256u
#endif

/* The slave's layout: what its SII says (cmake/EcatSii.cmake's CO_SII_<ID>_* macros carry the
 * same numbers) and which object shows the EtherCAT state. */
typedef struct co_ecat_slave_config {
    co_esc *esc;
    co_node *node;            /* the drive's node when drive is set */
    struct co_drive *drive;   /* optional: NULL for a plain CANopen node */
    uint16_t mbx_out_start;   /* SM0: master -> slave mailbox */
    uint16_t mbx_out_size;
    uint16_t mbx_in_start;    /* SM1: slave -> master mailbox */
    uint16_t mbx_in_size;
    uint8_t mbx_out_ctrl;     /* SM control bytes the master must program (0x0804 + 8n) */
    uint8_t mbx_in_ctrl;
    uint8_t out_ctrl;         /* SM2 */
    uint8_t in_ctrl;          /* SM3 */
    uint16_t out_start;       /* SM2: outputs (RxPDO) */
    uint16_t in_start;        /* SM3: inputs (TxPDO) */
    uint16_t rx_pdo;          /* the PDO 0x1C12:01 assigns to SM2 (0x1600), 0: none */
    uint16_t tx_pdo;          /* the PDO 0x1C13:01 assigns to SM3 (0x1A00), 0: none */
    uint16_t al_state_index;  /* object (sub 0, UNSIGNED16) showing the AL state 1/2/4/8 (the
                                 VF-MB1's C400 = 0x4400), 0: none */
    /* The dictionary's names, for the SDO information service (what masters show when they
     * browse the dictionary): tools/eds2c.py's co_od_<id>_entry_names and co_od_<id>_sub_names
     * (the EDS ParameterName; absent when built with CO_OD_NO_NAMES). entry_names[i] names
     * node->od->entries[i]; sub_names counts every entry's sub-entries in table order. NULL: the
     * index in hex ("0x6040", "0x6048:02"). */
    const char *const *entry_names;
    const char *const *sub_names;
} co_ecat_slave_config;

/* A mailbox message (header + data) waiting for SM1. */
typedef struct co_ecat_mbx_msg {
    uint16_t len; /* bytes including the 6-byte header */
    uint8_t b[CO_ECAT_MBX_MAX];
} co_ecat_mbx_msg;

/* One mapped object of a PDO, resolved when SAFE-OP is entered. */
typedef struct co_ecat_pd_entry {
    co_od_ref ref;
    const uint8_t *value; /* the object's value in the node's block (co_od_value_ptr) */
    uint16_t offset; /* byte offset in the process image */
    uint8_t size;    /* bytes */
} co_ecat_pd_entry;

/* A segmented SDO transfer or a fragmented SDO information answer in progress. */
typedef struct co_ecat_sdo_xfer {
    uint8_t kind;      /* 0 none, 1 upload, 2 download, 3 SDO information list */
    uint8_t toggle;    /* the toggle bit expected next */
    bool complete_access;
    uint16_t index;
    uint8_t subindex;
    uint32_t size;     /* bytes of the whole value */
    uint32_t done;     /* bytes moved */
    uint16_t list_type;
    uint8_t buf[CO_ECAT_SDO_BUF];
} co_ecat_sdo_xfer;

typedef struct co_ecat_slave_stats {
    uint32_t al_requests;    /* AL control writes handled */
    uint32_t al_refused;     /* state requests answered with the error indication */
    uint32_t mbx_rx;         /* mailbox messages read from SM0 */
    uint32_t mbx_dropped;    /* repeated counter: dropped as a retry */
    uint32_t mbx_errors;     /* mailbox error replies sent */
    uint32_t mbx_repeats;    /* repeat requests answered */
    uint32_t mbx_lost;       /* replies or emergencies lost to a full queue */
    uint32_t sdo_aborts;     /* CoE SDO aborts sent */
    uint32_t emcy_sent;      /* CoE emergencies queued */
    uint32_t wd_expired;     /* SM watchdog expiries that left OP */
    uint32_t outputs;        /* SM2 buffers applied */
} co_ecat_slave_stats;

typedef struct co_ecat_slave {
    co_esc *esc;
    co_node *node;
    struct co_drive *drive;
    co_ecat_slave_config cfg;
    uint8_t state;           /* AL status 0x0130 (state and error bit) */
    uint16_t status_code;    /* AL status code 0x0134 */
    uint64_t now;            /* ns, time of the latest process call */
    bool node_current;       /* the node has been run at now in this process call */
    bool settled;            /* the last call ran the node and left SM3 as the objects are */
    uint64_t node_next;      /* the node's (drive's) deadline from its last run (ns) */
    bool op_pending;         /* OP requested, waiting for the first outputs */
    uint64_t op_deadline;    /* ... until then (ns) */
    /* mailbox */
    uint8_t rx_counter;      /* counter of the last accepted master message (0: none yet) */
    uint8_t tx_counter;      /* counter of the last slave message (1..7) */
    uint8_t repeat_toggle;   /* SM1 activate bit 1 as last answered */
    bool last_valid;         /* last_sent holds a message for a repeat request */
    bool newer_posted;       /* SM1 got last_sent after the master's read of prev_sent */
    co_ecat_mbx_msg last_sent;
    co_ecat_mbx_msg prev_sent;
    co_ecat_mbx_msg queue[CO_ECAT_TX_QUEUE];
    uint8_t queue_head;
    uint8_t queue_count;
    uint8_t rx_buf[CO_ECAT_MBX_MAX];
    co_ecat_sdo_xfer xfer;
    /* process data */
    uint16_t out_size;       /* SM2 / SM3 lengths from the mapping (bytes) */
    uint16_t in_size;
    uint8_t out_count;       /* resolved entries */
    uint8_t in_count;
    bool outputs_valid;      /* an SM2 buffer arrived since SAFE-OP was entered */
    uint8_t rx_invalidated;  /* bit n: the slave set 0x1400+n bit 31 for a mapping write */
    uint8_t tx_invalidated;  /* the same for 0x1800+n */
    co_ecat_pd_entry out[CO_ECAT_PD_ENTRIES];
    co_ecat_pd_entry in[CO_ECAT_PD_ENTRIES];
    bool applied_valid;      /* the objects have been given an SM2 buffer since OP began */
    bool inputs_written;     /* in_image is in SM3 */
    uint8_t out_image[CO_ECAT_PD_MAX];
    uint8_t in_image[CO_ECAT_PD_MAX];
    co_ecat_slave_stats stats;
} co_ecat_slave;

/* The VF-MB1 layout of od/vf-mb1-ecat/ecat.ini: SM0 0x1000/128/0x26, SM1 0x1080/128/0x22,
 * SM2 0x1100/0x64, SM3 0x1180/0x20, 0x1C12:01 = 0x1600, 0x1C13:01 = 0x1A00, no AL state object;
 * esc, node and drive NULL. */
co_ecat_slave_config co_ecat_slave_default_config(void);

/* Binds the slave to cfg->esc and cfg->node (and cfg->drive), sets AL status INIT with code 0,
 * puts the node in STOPPED (the ESM's INIT) and registers the node's EMCY listener. The ESC must
 * be initialised, the node started. Returns false (nothing changed) on a NULL esc or node, a
 * mailbox larger than CO_ECAT_MBX_MAX or smaller than 16 bytes. */
bool co_ecat_slave_init(co_ecat_slave *s, const co_ecat_slave_config *cfg, uint64_t now_ns);

/* Brings the node (co_drive_process with a drive, else co_node_process, at now_ns / 1000) up to
 * now, then handles everything the ESC has for the application since the last call: AL control
 * requests, the SM watchdog, SM0 messages, SM1 reads (the next queued message, repeat requests), SM2
 * outputs (in OP) and SM3 inputs (in SAFE-OP and OP). Runs co_esc_tick. Call it after every
 * frame the ESC processed and when the returned time (ns) has come; it includes the node's (or
 * drive's) deadline, so the caller needs no other timer for them. CO_ESC_TIME_NEVER: nothing
 * pending.
 * A call for which the ESC has only a new SM2 buffer, equal to the objects (a cyclic master
 * repeating its outputs), before the node's deadline and after a call that left nothing pending,
 * does not run the node and leaves SM3 as it is: nothing reached the node since then. Whatever
 * changes the drive or the dictionary other than through the slave (the application, an SDO on a
 * CAN face) is followed by a co_ecat_slave_process call before the next frame, as the Linux port
 * does after every wake-up; that call (no new SM2 buffer) runs the node and refreshes SM3. */
uint64_t co_ecat_slave_process(co_ecat_slave *s, uint64_t now_ns);

/* The EtherCAT state (CO_ECAT_STATE_*) and whether the error indication is set. */
uint8_t co_ecat_slave_state(const co_ecat_slave *s);
bool co_ecat_slave_error(const co_ecat_slave *s);

/* The AL state's name ("INIT", "PREOP", "SAFEOP", "OP", "BOOT", "?"), and the RUN and ERR LEDs
 * as the VF-MB1 manual §2.3 describes them ("off", "blinking", "single flash", "on",
 * "double flash", ...) for a status display. */
const char *co_ecat_state_name(uint8_t state);
const char *co_ecat_slave_run_led(const co_ecat_slave *s);
const char *co_ecat_slave_err_led(const co_ecat_slave *s);

#ifdef __cplusplus
}
#endif

#endif
