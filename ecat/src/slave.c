/* The EtherCAT slave application layer (include/canopen/ecat/slave.h): ESM, mailbox, CoE and
 * process data on the ESC's PDI functions and the core's public API. Protocol sources: ETG.1000.6
 * as SOEM 1.4 and SOES use it (ecat/NOTES.md, "Application layer"); the VF-MB1 EtherCAT option's
 * manual §7 for the services per state and the communication-interruption table. */
#include "canopen/ecat/slave.h"

#include <string.h>

#include "canopen/drive.h"
#include "canopen/emcy.h"
#include "canopen/nmt.h"
#include "canopen/od.h"

/* ---- register and protocol encodings ------------------------------------------------------ */

#define SM_MBX_OUT 0u /* master -> slave mailbox */
#define SM_MBX_IN 1u  /* slave -> master mailbox */
#define SM_OUTPUTS 2u
#define SM_INPUTS 3u

#define SM_ACT_ENABLE 0x01u      /* SM activate byte 0x0806+8n: enabled by the master */
#define SM_ACT_REPEAT 0x02u      /* repeat request toggle */
#define SM_PDI_REPEAT_ACK 0x02u  /* SM PDI control 0x0807+8n: repeat acknowledge */
/* Control byte bits the slave insists on: mode (bits 0-1), direction (bits 2-3), AL event
 * (bit 5, the slave learns of new data through it). ECAT event and watchdog trigger are the
 * master's choice. */
#define SM_CTRL_CHECKED 0x2Fu

/* Mailbox header (6 bytes) and types. */
#define MBX_HDR 6u
#define MBX_TYPE_ERROR 0x00u
#define MBX_TYPE_COE 0x03u
/* Mailbox error reply details (ETG.1000.4 / SOEM ec_mbxerrort). */
#define MBX_ERR_SYNTAX 0x0001u
#define MBX_ERR_UNSUPPORTED_PROTOCOL 0x0002u
#define MBX_ERR_INVALID_CHANNEL 0x0003u
#define MBX_ERR_SERVICE_NOT_SUPPORTED 0x0004u
#define MBX_ERR_INVALID_HEADER 0x0005u
#define MBX_ERR_SIZE_TOO_SHORT 0x0006u

/* CoE header: bits 12-15 service. */
#define COE_HDR 2u
#define COE_EMERGENCY 0x1u
#define COE_SDO_REQUEST 0x2u
#define COE_SDO_RESPONSE 0x3u
#define COE_SDO_INFO 0x8u

/* SDO command byte (CiA 301 client/server command specifiers, ETG.1000.6 complete access). */
#define SDO_CCS(cmd) ((uint8_t)((cmd) >> 5))
#define SDO_CCS_DOWNLOAD_SEGMENT 0u
#define SDO_CCS_DOWNLOAD 1u
#define SDO_CCS_UPLOAD 2u
#define SDO_CCS_UPLOAD_SEGMENT 3u
#define SDO_CCS_ABORT 4u
#define SDO_SIZE_INDICATED 0x01u
#define SDO_EXPEDITED 0x02u
#define SDO_COMPLETE_ACCESS 0x10u
#define SDO_TOGGLE 0x10u
#define SDO_LAST_SEGMENT 0x01u
#define SDO_ABORT_CMD 0x80u
#define SDO_FRAME 10u /* CoE header + command + index + sub + 4 data bytes */

/* SDO information opcodes (ETG.1000.6). */
#define INFO_OD_LIST_REQ 0x01u
#define INFO_OD_LIST_RESP 0x02u
#define INFO_OBJ_DESC_REQ 0x03u
#define INFO_OBJ_DESC_RESP 0x04u
#define INFO_ENTRY_DESC_REQ 0x05u
#define INFO_ENTRY_DESC_RESP 0x06u
#define INFO_ERROR 0x07u
#define INFO_INCOMPLETE 0x80u
#define INFO_HDR 4u /* opcode, reserved, fragments left */
/* bytes of a name in an object or entry description at most; SM1's size limits it further */
#define INFO_NAME_MAX 120u
/* Object access word of an entry description. */
#define ACCESS_READ_ALL 0x0007u  /* readable in PRE-OP, SAFE-OP, OP */
#define ACCESS_WRITE_ALL 0x0038u /* writable in PRE-OP, SAFE-OP, OP */
#define ACCESS_RXPDO 0x0040u
#define ACCESS_TXPDO 0x0080u
#define ACCESS_BACKUP 0x0100u

#define XFER_NONE 0u
#define XFER_UPLOAD 1u
#define XFER_DOWNLOAD 2u
#define XFER_OD_LIST 3u

#define ABORT_NO_CA 0x06010004u        /* complete access not supported for this object */

/* ---- small helpers ------------------------------------------------------------------------ */

static uint16_t le16(const uint8_t *p)
{
    return (uint16_t)(p[0] | (p[1] << 8));
}

static void put16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}

static void put32(uint8_t *p, uint32_t v)
{
    put16(p, (uint16_t)v);
    put16(p + 2, (uint16_t)(v >> 16));
}

static uint8_t rd8(co_ecat_slave *s, uint16_t reg)
{
    uint8_t v = 0;
    (void)co_esc_pdi_read(s->esc, reg, &v, 1);
    return v;
}

static uint16_t rd16(co_ecat_slave *s, uint16_t reg)
{
    uint8_t v[2] = {0, 0};
    (void)co_esc_pdi_read(s->esc, reg, v, 2);
    return le16(v);
}

static void wr16(co_ecat_slave *s, uint16_t reg, uint16_t value)
{
    uint8_t v[2];
    put16(v, value);
    (void)co_esc_pdi_write(s->esc, reg, v, 2);
}

static uint64_t node_us(const co_ecat_slave *s)
{
    return s->now / 1000u;
}

static bool mailbox_running(const co_ecat_slave *s)
{
    uint8_t st = s->state & CO_ECAT_STATE_MASK;
    return st == CO_ECAT_STATE_PREOP || st == CO_ECAT_STATE_SAFEOP || st == CO_ECAT_STATE_OP;
}

/* ---- NMT state and AL status -------------------------------------------------------------- */

/* The node's NMT state follows the ESM (slave.h): INIT -> STOPPED, PRE-OP and SAFE-OP ->
 * PRE-OPERATIONAL, OP -> OPERATIONAL. */
static bool sync_nmt(co_ecat_slave *s)
{
    bool changed = false;
    co_node *n = s->node;
    co_nmt_state want;
    co_nmt_command cmd;
    switch (s->state & CO_ECAT_STATE_MASK) {
    case CO_ECAT_STATE_OP:
        want = CO_NMT_OPERATIONAL;
        cmd = CO_NMT_CMD_START;
        break;
    case CO_ECAT_STATE_PREOP:
    case CO_ECAT_STATE_SAFEOP:
        want = CO_NMT_PRE_OPERATIONAL;
        cmd = CO_NMT_CMD_ENTER_PRE_OPERATIONAL;
        break;
    default:
        want = CO_NMT_STOPPED;
        cmd = CO_NMT_CMD_STOP;
        break;
    }
    if (n->nmt_state != want && n->nmt_state != CO_NMT_INITIALISING) {
        co_nmt_command_local(n, cmd, node_us(s));
        changed = true;
    }
    if (s->cfg.al_state_index != 0u &&
        co_od_get_u16(n, s->cfg.al_state_index, 0) != (s->state & CO_ECAT_STATE_MASK)) {
        (void)co_od_set_u16(n, s->cfg.al_state_index, 0, s->state & CO_ECAT_STATE_MASK);
    }
    return changed;
}

static void publish_al_status(co_ecat_slave *s)
{
    wr16(s, CO_ESC_REG_ALSTAT, s->state);
    wr16(s, CO_ESC_REG_ALSTATCODE, s->status_code);
    (void)sync_nmt(s);
}

static void enter(co_ecat_slave *s, uint8_t state)
{
    s->state = state;
    s->status_code = CO_ECAT_AL_NO_ERROR;
    publish_al_status(s);
}

/* A refused request or a local error: the state (OP falls back to SAFE-OP: outputs are no longer
 * trusted) with the error indication and its code. */
static void refuse(co_ecat_slave *s, uint8_t state, uint16_t code)
{
    if (state == CO_ECAT_STATE_OP) {
        state = CO_ECAT_STATE_SAFEOP;
    }
    s->state = (uint8_t)(state | CO_ECAT_AL_ERROR);
    s->status_code = code;
    s->op_pending = false;
    s->stats.al_refused++;
    publish_al_status(s);
}

/* ---- mailbox: sending ----------------------------------------------------------------------- */

static void stop_mailbox(co_ecat_slave *s)
{
    s->newer_posted = false;
    s->queue_count = 0;
    s->queue_head = 0;
    s->last_valid = false;
    s->xfer.kind = XFER_NONE;
    s->rx_counter = 0;
}

/* A free slot at the end of the send queue with its header filled for type and len bytes of
 * data, or NULL (counted) when the queue is full. */
static uint8_t *reply_begin(co_ecat_slave *s, uint8_t type, uint16_t len)
{
    co_ecat_mbx_msg *m;
    if (s->queue_count >= CO_ECAT_TX_QUEUE || len + MBX_HDR > s->cfg.mbx_in_size) {
        s->stats.mbx_lost++;
        return NULL;
    }
    m = &s->queue[(s->queue_head + s->queue_count) % CO_ECAT_TX_QUEUE];
    s->queue_count++;
    memset(m->b, 0, sizeof m->b);
    m->len = (uint16_t)(len + MBX_HDR);
    s->tx_counter = (uint8_t)(s->tx_counter % 7u + 1u); /* 1..7, never 0 */
    put16(m->b, len);
    /* address 0 (the master), channel 0, priority 0 */
    m->b[5] = (uint8_t)(type | (s->tx_counter << 4));
    return m->b + MBX_HDR;
}

static void mailbox_error(co_ecat_slave *s, uint16_t detail)
{
    uint8_t *d = reply_begin(s, MBX_TYPE_ERROR, 4);
    s->stats.mbx_errors++;
    if (d != NULL) {
        put16(d, 0x0001u); /* type: mailbox command */
        put16(d + 2, detail);
    }
}

/* Writes m into SM1 (the whole buffer, so the write covers its last byte and fills it); the
 * message before it is kept too, for a repeat request that comes after m was posted. */
static void post(co_ecat_slave *s, const co_ecat_mbx_msg *m)
{
    uint8_t buf[CO_ECAT_MBX_MAX];
    memset(buf, 0, s->cfg.mbx_in_size);
    memcpy(buf, m->b, m->len);
    if (co_esc_pdi_write(s->esc, s->cfg.mbx_in_start, buf, s->cfg.mbx_in_size) == CO_ESC_PDI_OK) {
        if (m != &s->last_sent) {
            s->prev_sent = s->last_sent;
            s->last_sent = *m;
        }
        s->newer_posted = s->last_valid && m != &s->last_sent ? true : s->newer_posted;
        s->last_valid = true;
    }
}

static bool sm1_full(co_ecat_slave *s)
{
    return (rd8(s, CO_ESC_REG_SM_STATUS(SM_MBX_IN)) & CO_ESC_SM_STATUS_MBX_FULL) != 0u;
}

static void od_list_fragment(co_ecat_slave *s);

/* Repeat request (SM1 activate bit 1 toggled by the master after a lost read): post the last
 * message again if SM1 has been emptied, then acknowledge with the same toggle value. */
static void mailbox_repeat(co_ecat_slave *s)
{
    uint8_t toggle = rd8(s, CO_ESC_REG_SM_ACTIVATE(SM_MBX_IN)) & SM_ACT_REPEAT;
    if (toggle == s->repeat_toggle) {
        return;
    }
    s->repeat_toggle = toggle;
    s->stats.mbx_repeats++;
    uint8_t pdi = toggle != 0u ? SM_PDI_REPEAT_ACK : 0u;
    if (s->last_valid && !sm1_full(s)) {
        post(s, &s->last_sent); /* the master's read emptied SM1 but never reached it */
    } else if (s->last_valid && s->newer_posted && s->queue_count < CO_ECAT_TX_QUEUE) {
        /* SM1 already holds the next message, posted after the read the master lost: take it
         * back (switching SM1 off and on empties it, SOES does the same), queue it first again
         * and post the lost one (SOES ESC_mbxprocess) */
        uint8_t off = pdi | 0x01u;
        s->queue_head = (uint8_t)((s->queue_head + CO_ECAT_TX_QUEUE - 1u) % CO_ECAT_TX_QUEUE);
        s->queue[s->queue_head] = s->last_sent;
        s->queue_count++;
        (void)co_esc_pdi_write(s->esc, CO_ESC_REG_SM_PDICTL(SM_MBX_IN), &off, 1);
        (void)co_esc_pdi_write(s->esc, CO_ESC_REG_SM_PDICTL(SM_MBX_IN), &pdi, 1);
        s->last_sent = s->prev_sent;
        post(s, &s->last_sent);
    }
    s->newer_posted = false;
    (void)co_esc_pdi_write(s->esc, CO_ESC_REG_SM_PDICTL(SM_MBX_IN), &pdi, 1);
}

/* Nothing for mailbox_send to post: no message queued, no OD list in fragments. */
static bool mailbox_idle(const co_ecat_slave *s)
{
    return s->queue_count == 0u && s->xfer.kind != XFER_OD_LIST;
}

/* The next queued message into an empty SM1. */
static void mailbox_send(co_ecat_slave *s)
{
    if (s->queue_count == 0u && s->xfer.kind == XFER_OD_LIST) {
        od_list_fragment(s);
    }
    if (s->queue_count == 0u || sm1_full(s)) {
        return;
    }
    post(s, &s->queue[s->queue_head]);
    s->queue_head = (uint8_t)((s->queue_head + 1u) % CO_ECAT_TX_QUEUE);
    s->queue_count--;
}

/* ---- CoE: objects the slave adds (SM types and PDO assignment) ---------------------------- */

/* 0x1C00 SM communication types, 0x1C12/0x1C13 PDO assignment of SM2/SM3 (ETG.1000.6): the
 * dictionary has none (the CANopen face does not need them), the SII layout fixes them. */
static bool virtual_object(uint16_t index)
{
    return index == 0x1C00u || index == 0x1C12u || index == 0x1C13u;
}

static uint8_t virtual_max_sub(const co_ecat_slave *s, uint16_t index)
{
    if (index == 0x1C00u) {
        return 4u;
    }
    return (index == 0x1C12u ? s->cfg.rx_pdo : s->cfg.tx_pdo) != 0u ? 1u : 0u;
}

static co_abort virtual_read(const co_ecat_slave *s, uint16_t index, uint8_t sub, uint8_t *buf,
                             uint32_t *len)
{
    uint8_t max = virtual_max_sub(s, index);
    if (sub > (index == 0x1C00u ? 4u : 1u)) {
        return CO_ABORT_NO_SUBINDEX;
    }
    if (sub == 0u) {
        buf[0] = max;
        *len = 1;
    } else if (index == 0x1C00u) {
        static const uint8_t types[4] = {1u, 2u, 3u, 4u}; /* mbx out, mbx in, outputs, inputs */
        buf[0] = types[sub - 1u];
        *len = 1;
    } else {
        put16(buf, index == 0x1C12u ? s->cfg.rx_pdo : s->cfg.tx_pdo);
        *len = 2;
    }
    return CO_ABORT_NONE;
}

/* ---- CoE: SDO ------------------------------------------------------------------------------ */

static void sdo_abort(co_ecat_slave *s, uint16_t index, uint8_t sub, uint32_t code)
{
    uint8_t *d = reply_begin(s, MBX_TYPE_COE, SDO_FRAME);
    s->stats.sdo_aborts++;
    s->xfer.kind = XFER_NONE;
    if (d != NULL) {
        put16(d, COE_SDO_REQUEST << 12); /* an abort goes as an SDO request (ETG.1000.6) */
        d[2] = SDO_ABORT_CMD;
        put16(d + 3, index);
        d[5] = sub;
        put32(d + 6, code);
    }
}

/* Objects whose writes change the process data layout: only in PRE-OP (ETG.1000.6), where the
 * NMT rule of the node (PRE-OPERATIONAL for PRE-OP and SAFE-OP) would allow SAFE-OP too. */
static bool layout_object(uint16_t index)
{
    return (index >= 0x1600u && index <= 0x17FFu) || (index >= 0x1A00u && index <= 0x1BFFu) ||
           index == 0x1C12u || index == 0x1C13u;
}

static co_abort read_sub(co_ecat_slave *s, uint16_t index, uint8_t sub, uint8_t *buf,
                         uint32_t cap, uint32_t *len)
{
    if (virtual_object(index)) {
        if (cap < 2u) {
            return CO_ABORT_OUT_OF_MEMORY;
        }
        return virtual_read(s, index, sub, buf, len);
    }
    return co_od_read(s->node, index, sub, buf, cap, len, CO_ORIGIN_SDO);
}

/* True for a VAR: one sub-entry, sub-index 0. */
static bool is_var(const co_od_entry *e)
{
    return co_od_entry_sub_count(e) == 1u && co_od_entry_subs(e)[0].subindex == 0u;
}

/* Complete access upload (ETG.1000.6): every sub-entry from sub (0 or 1) to the number sub 0
 * holds, concatenated; sub 0 of an ARRAY/RECORD takes 16 bits (its value and a pad byte). */
static co_abort read_complete(co_ecat_slave *s, uint16_t index, uint8_t sub, uint8_t *buf,
                              uint32_t cap, uint32_t *len)
{
    uint8_t max;
    uint32_t at = 0, n;
    co_abort rc;
    if (sub > 1u) {
        return CO_ABORT_UNSUPPORTED_ACCESS; /* complete access starts at sub 0 or 1 */
    }
    if (!virtual_object(index)) {
        const co_od_entry *e = co_od_find_entry(s->node->od, index);
        if (e == NULL) {
            return CO_ABORT_NO_OBJECT;
        }
        if (is_var(e)) {
            return sub == 0u ? co_od_read(s->node, index, 0, buf, cap, len, CO_ORIGIN_SDO)
                             : CO_ABORT_NO_SUBINDEX;
        }
    }
    rc = read_sub(s, index, 0, buf, cap, &n);
    if (rc != CO_ABORT_NONE) {
        return rc;
    }
    if (n != 1u) {
        return ABORT_NO_CA;
    }
    max = buf[0];
    if (sub == 0u) {
        buf[1] = 0; /* the pad byte */
        at = 2;
    }
    for (uint32_t k = 1; k <= max; k++) {
        if (!virtual_object(index)) {
            const co_od_entry *e = co_od_find_entry(s->node->od, index);
            const co_od_sub *d = co_od_find_sub(e, (uint8_t)k);
            if (d == NULL) {
                continue; /* a gap in the sub-indices */
            }
            if (co_type_size(d->type) == 0u) {
                return ABORT_NO_CA; /* strings and domains have no fixed place */
            }
        }
        rc = read_sub(s, index, (uint8_t)k, buf + at, cap - at, &n);
        if (rc != CO_ABORT_NONE) {
            return rc;
        }
        at += n;
    }
    *len = at;
    return CO_ABORT_NONE;
}

/* EtherCAT has no COB-IDs, but the core (CiA 301 §7.5.2.36) accepts a new mapping only while its
 * CAN PDO is invalid (COB-ID bit 31). Before the first mapping write in PRE-OP the slave sets that
 * bit itself (PDO n: 0x1400+n for 0x1600+n, 0x1800+n for 0x1A00+n) and clears it again when
 * SAFE-OP is entered with the new mapping. */
static bool pdo_invalidate(co_ecat_slave *s, uint16_t map_index)
{
    uint16_t comm = (uint16_t)(map_index - 0x200u);
    uint32_t n = map_index & 0x1FFu;
    uint8_t *mask = map_index < 0x1A00u ? &s->rx_invalidated : &s->tx_invalidated;
    co_od_ref ref;
    if (n >= 8u || co_od_locate(s->node->od, comm, 1, &ref) != CO_ABORT_NONE) {
        return false;
    }
    uint32_t cob = co_od_get_u32(s->node, comm, 1);
    if ((cob & 0x80000000u) == 0u) {
        uint8_t v[4];
        put32(v, cob | 0x80000000u);
        if (co_od_write(s->node, comm, 1, v, 4, CO_ORIGIN_SDO) == CO_ABORT_NONE) {
            *mask = (uint8_t)(*mask | (1u << n));
            return true;
        }
    }
    return false;
}

/* Clears bit 31 again of the PDO (rx: 0x1400+n, else 0x1800+n) if the slave had set it. */
static void pdo_restore_one(co_ecat_slave *s, bool rx, uint32_t n)
{
    uint8_t *mask = rx ? &s->rx_invalidated : &s->tx_invalidated;
    uint16_t comm = (uint16_t)((rx ? 0x1400u : 0x1800u) + n);
    if ((*mask & (1u << n)) != 0u) {
        uint8_t v[4];
        put32(v, co_od_get_u32(s->node, comm, 1) & ~0x80000000u);
        /* an empty mapping keeps the CAN PDO invalid (the core refuses it) */
        (void)co_od_write(s->node, comm, 1, v, 4, CO_ORIGIN_SDO);
        *mask = (uint8_t)(*mask & ~(1u << n));
    }
}

static void pdo_restore(co_ecat_slave *s)
{
    for (uint32_t n = 0; n < 8u; n++) {
        pdo_restore_one(s, true, n);
        pdo_restore_one(s, false, n);
    }
}

static co_abort write_value_to(co_ecat_slave *s, uint16_t index, uint8_t sub, bool ca,
                               const uint8_t *buf, uint32_t len);

/* Writes a whole value (len bytes of buf) as the download of index/sub asked; a refused mapping
 * write leaves the CAN PDO as it found it. */
static co_abort write_value(co_ecat_slave *s, uint16_t index, uint8_t sub, bool ca,
                            const uint8_t *buf, uint32_t len)
{
    bool fresh = false;
    co_abort rc;
    if (layout_object(index) && !virtual_object(index) &&
        (s->state & CO_ECAT_STATE_MASK) == CO_ECAT_STATE_PREOP) {
        fresh = pdo_invalidate(s, index);
    }
    rc = write_value_to(s, index, sub, ca, buf, len);
    if (rc != CO_ABORT_NONE && fresh) {
        pdo_restore_one(s, index < 0x1A00u, index & 0x1FFu);
    }
    return rc;
}

static co_abort write_value_to(co_ecat_slave *s, uint16_t index, uint8_t sub, bool ca,
                               const uint8_t *buf, uint32_t len)
{
    co_node *n = s->node;
    if (layout_object(index) && (s->state & CO_ECAT_STATE_MASK) != CO_ECAT_STATE_PREOP) {
        return CO_ABORT_DEVICE_STATE;
    }
    if (virtual_object(index)) {
        if (!ca && sub > (index == 0x1C00u ? 4u : 1u)) {
            return CO_ABORT_NO_SUBINDEX;
        }
        return CO_ABORT_READ_ONLY;
    }
    if (!ca) {
        return co_od_write(n, index, sub, buf, len, CO_ORIGIN_SDO);
    }
    const co_od_entry *e = co_od_find_entry(n->od, index);
    if (e == NULL) {
        return CO_ABORT_NO_OBJECT;
    }
    if (sub > 1u) {
        return CO_ABORT_UNSUPPORTED_ACCESS; /* complete access starts at sub 0 or 1 */
    }
    if (is_var(e)) {
        return sub == 0u ? co_od_write(n, index, 0, buf, len, CO_ORIGIN_SDO) : CO_ABORT_NO_SUBINDEX;
    }
    /* Check every piece first (type, length, limits, access), so that a bad download changes
     * nothing the checks can foresee; then sub 0 := 0, the entries, sub 0 := count, the order a
     * PDO mapping needs (CiA 301 §7.5.2.36). A hook may still refuse an entry on the way. */
    uint32_t at = 0;
    uint8_t count;
    const co_od_sub *s0 = co_od_find_sub(e, 0);
    if (s0 == NULL) {
        return ABORT_NO_CA;
    }
    if (sub == 0u) {
        if (len < 2u) {
            return CO_ABORT_TYPE_TOO_SHORT;
        }
        count = buf[0];
        at = 2;
    } else {
        count = co_od_get_u8(n, index, 0);
    }
    for (uint32_t k = 1; k <= count; k++) {
        const co_od_sub *d = co_od_find_sub(e, (uint8_t)k);
        uint32_t size;
        co_od_ref ref;
        if (d == NULL) {
            return CO_ABORT_NO_SUBINDEX;
        }
        size = co_type_size(d->type);
        if (size == 0u) {
            return ABORT_NO_CA;
        }
        if (at + size > len) {
            return CO_ABORT_TYPE_TOO_SHORT;
        }
        if ((d->flags & CO_OD_WRITE) == 0u) {
            return CO_ABORT_READ_ONLY;
        }
        ref.entry = e;
        ref.sub = d;
        co_abort rc = co_od_check_value(n->od, ref, buf + at, size);
        if (rc != CO_ABORT_NONE) {
            return rc;
        }
        at += size;
    }
    if (at != len) {
        return CO_ABORT_TYPE_TOO_LONG;
    }
    bool count_writable = sub == 0u && (s0->flags & CO_OD_WRITE) != 0u;
    uint8_t old_count = co_od_get_u8(n, index, 0);
    /* the entries' values before, to undo a refused download (their sizes add up to at most
     * len, checked above, and len fits the SDO buffer) */
    uint8_t old[CO_ECAT_SDO_BUF];
    uint32_t old_len = 0;
    co_abort rc = CO_ABORT_NONE;
    if (!count_writable && sub == 0u && count != old_count) {
        return CO_ABORT_READ_ONLY;
    }
    for (uint32_t k = 1; k <= count; k++) {
        uint32_t got = 0;
        (void)co_od_read(n, index, (uint8_t)k, old + old_len, (uint32_t)sizeof old - old_len,
                         &got, CO_ORIGIN_APP);
        old_len += co_type_size(co_od_find_sub(e, (uint8_t)k)->type);
    }
    if (count_writable) {
        uint8_t zero = 0;
        rc = co_od_write(n, index, 0, &zero, 1, CO_ORIGIN_SDO);
        if (rc != CO_ABORT_NONE) {
            return rc;
        }
    }
    at = sub == 0u ? 2u : 0u;
    uint32_t k = 1;
    for (; k <= count && rc == CO_ABORT_NONE; k++) {
        uint32_t size = co_type_size(co_od_find_sub(e, (uint8_t)k)->type);
        rc = co_od_write(n, index, (uint8_t)k, buf + at, size, CO_ORIGIN_SDO);
        at += size;
    }
    if (rc == CO_ABORT_NONE) {
        rc = count_writable ? co_od_write(n, index, 0, &count, 1, CO_ORIGIN_SDO) : CO_ABORT_NONE;
        if (rc == CO_ABORT_NONE) {
            return CO_ABORT_NONE;
        }
    }
    /* refused on the way: the entries written so far and sub 0 get their old values back */
    at = 0;
    for (uint32_t j = 1; j < k; j++) {
        uint32_t size = co_type_size(co_od_find_sub(e, (uint8_t)j)->type);
        (void)co_od_write(n, index, (uint8_t)j, old + at, size, CO_ORIGIN_SDO);
        at += size;
    }
    if (count_writable) {
        (void)co_od_write(n, index, 0, &old_count, 1, CO_ORIGIN_SDO);
    }
    return rc;
}

/* Largest data of a normal upload answer (CoE header, command, index, sub, size, data). */
static uint32_t upload_room(const co_ecat_slave *s)
{
    return s->cfg.mbx_in_size - MBX_HDR - SDO_FRAME;
}

static void sdo_upload(co_ecat_slave *s, uint16_t index, uint8_t sub, bool ca)
{
    co_ecat_sdo_xfer *x = &s->xfer;
    uint32_t len = 0, part;
    co_abort rc = ca ? read_complete(s, index, sub, x->buf, sizeof x->buf, &len)
                     : read_sub(s, index, sub, x->buf, sizeof x->buf, &len);
    uint8_t *d;
    if (rc != CO_ABORT_NONE) {
        sdo_abort(s, index, sub, rc);
        return;
    }
    if (len <= 4u && !ca) {
        d = reply_begin(s, MBX_TYPE_COE, SDO_FRAME);
        if (d != NULL) {
            put16(d, COE_SDO_RESPONSE << 12);
            d[2] = (uint8_t)(0x40u | SDO_EXPEDITED | SDO_SIZE_INDICATED | ((4u - len) << 2));
            put16(d + 3, index);
            d[5] = sub;
            memcpy(d + 6, x->buf, len);
        }
        return;
    }
    part = len <= upload_room(s) ? len : upload_room(s);
    d = reply_begin(s, MBX_TYPE_COE, (uint16_t)(SDO_FRAME + part));
    if (d == NULL) {
        return;
    }
    put16(d, COE_SDO_RESPONSE << 12);
    d[2] = 0x40u | SDO_SIZE_INDICATED;
    put16(d + 3, index);
    d[5] = sub;
    put32(d + 6, len);
    memcpy(d + 10, x->buf, part);
    if (part < len) { /* the rest in upload segments */
        x->kind = XFER_UPLOAD;
        x->index = index;
        x->subindex = sub;
        x->size = len;
        x->done = part;
        x->toggle = 0;
    }
}

static void sdo_upload_segment(co_ecat_slave *s, uint8_t cmd)
{
    co_ecat_sdo_xfer *x = &s->xfer;
    uint32_t room = s->cfg.mbx_in_size - MBX_HDR - COE_HDR - 1u;
    uint32_t k = x->size - x->done;
    uint8_t *d;
    if (x->kind != XFER_UPLOAD) {
        sdo_abort(s, 0, 0, CO_ABORT_COMMAND);
        return;
    }
    if ((cmd & SDO_TOGGLE) != x->toggle) {
        sdo_abort(s, x->index, x->subindex, CO_ABORT_TOGGLE);
        return;
    }
    if (k > room) {
        k = room;
    }
    d = reply_begin(s, MBX_TYPE_COE, (uint16_t)(COE_HDR + 1u + (k < 7u ? 7u : k)));
    if (d == NULL) {
        return;
    }
    put16(d, COE_SDO_RESPONSE << 12);
    d[2] = (uint8_t)(x->toggle | (k < 7u ? (7u - k) << 1 : 0u));
    memcpy(d + 3, x->buf + x->done, k);
    x->done += k;
    x->toggle ^= SDO_TOGGLE;
    if (x->done == x->size) {
        d[2] |= SDO_LAST_SEGMENT;
        x->kind = XFER_NONE;
    }
}

static void download_response(co_ecat_slave *s, uint8_t cmd, uint16_t index, uint8_t sub)
{
    uint8_t *d = reply_begin(s, MBX_TYPE_COE, SDO_FRAME);
    if (d != NULL) {
        put16(d, COE_SDO_RESPONSE << 12);
        d[2] = cmd;
        put16(d + 3, index);
        d[5] = sub;
    }
}

static void sdo_download(co_ecat_slave *s, const uint8_t *d, uint32_t len)
{
    co_ecat_sdo_xfer *x = &s->xfer;
    uint8_t cmd = d[0];
    uint16_t index = le16(d + 1);
    uint8_t sub = d[3];
    bool ca = (cmd & SDO_COMPLETE_ACCESS) != 0u;
    co_abort rc;
    if ((cmd & SDO_EXPEDITED) != 0u) {
        uint32_t size = (cmd & SDO_SIZE_INDICATED) != 0u ? 4u - ((cmd >> 2) & 3u) : 4u;
        rc = write_value(s, index, sub, ca, d + 4, size);
    } else {
        uint32_t size = le16(d + 4) | ((uint32_t)le16(d + 6) << 16);
        uint32_t part = len - 8u;
        if (size > sizeof x->buf) {
            /* longer than any value the slave holds: an absent object says so first, as the
             * write would */
            co_od_ref ref;
            co_abort where = virtual_object(index) || ca
                                 ? CO_ABORT_NONE
                                 : co_od_locate(s->node->od, index, sub, &ref);
            sdo_abort(s, index, sub, where != CO_ABORT_NONE ? where : CO_ABORT_TYPE_TOO_LONG);
            return;
        }
        if (part >= size) {
            rc = write_value(s, index, sub, ca, d + 8, size);
        } else {
            memcpy(x->buf, d + 8, part);
            x->kind = XFER_DOWNLOAD;
            x->index = index;
            x->subindex = sub;
            x->complete_access = ca;
            x->size = size;
            x->done = part;
            x->toggle = 0;
            download_response(s, 0x60u, index, sub);
            return;
        }
    }
    if (rc != CO_ABORT_NONE) {
        sdo_abort(s, index, sub, rc);
        return;
    }
    download_response(s, 0x60u, index, sub);
}

static void sdo_download_segment(co_ecat_slave *s, const uint8_t *d, uint32_t len)
{
    co_ecat_sdo_xfer *x = &s->xfer;
    uint8_t cmd = d[0];
    /* 7 data bytes with n unused in a minimal segment, all that follow the command otherwise */
    uint32_t k = len == 8u ? 7u - ((cmd >> 1) & 7u) : len - 1u;
    if (x->kind != XFER_DOWNLOAD) {
        sdo_abort(s, 0, 0, CO_ABORT_COMMAND);
        return;
    }
    if ((cmd & SDO_TOGGLE) != x->toggle) {
        sdo_abort(s, x->index, x->subindex, CO_ABORT_TOGGLE);
        return;
    }
    if (k > x->size - x->done) {
        sdo_abort(s, x->index, x->subindex, CO_ABORT_TYPE_TOO_LONG);
        return;
    }
    memcpy(x->buf + x->done, d + 1, k);
    x->done += k;
    if ((cmd & SDO_LAST_SEGMENT) != 0u) {
        co_abort rc = x->done != x->size
                          ? CO_ABORT_TYPE_TOO_SHORT
                          : write_value(s, x->index, x->subindex, x->complete_access, x->buf,
                                        x->size);
        x->kind = XFER_NONE;
        if (rc != CO_ABORT_NONE) {
            sdo_abort(s, x->index, x->subindex, rc);
            return;
        }
    }
    uint8_t *r = reply_begin(s, MBX_TYPE_COE, SDO_FRAME);
    if (r != NULL) {
        put16(r, COE_SDO_RESPONSE << 12);
        r[2] = (uint8_t)(0x20u | x->toggle);
    }
    x->toggle ^= SDO_TOGGLE;
}

/* d: the SDO part after the CoE header, len bytes (at least 8). */
static void sdo_request(co_ecat_slave *s, const uint8_t *d, uint32_t len)
{
    uint8_t cmd = d[0];
    switch (SDO_CCS(cmd)) {
    case SDO_CCS_UPLOAD:
        s->xfer.kind = XFER_NONE;
        sdo_upload(s, le16(d + 1), d[3], (cmd & SDO_COMPLETE_ACCESS) != 0u);
        break;
    case SDO_CCS_DOWNLOAD:
        s->xfer.kind = XFER_NONE;
        sdo_download(s, d, len);
        break;
    case SDO_CCS_UPLOAD_SEGMENT:
        sdo_upload_segment(s, cmd);
        break;
    case SDO_CCS_DOWNLOAD_SEGMENT:
        sdo_download_segment(s, d, len);
        break;
    case SDO_CCS_ABORT:
        s->xfer.kind = XFER_NONE; /* the master ends the transfer: no answer */
        break;
    default:
        sdo_abort(s, le16(d + 1), d[3], CO_ABORT_COMMAND);
        break;
    }
}

/* ---- CoE: SDO information ------------------------------------------------------------------- */

static uint8_t *info_begin(co_ecat_slave *s, uint8_t opcode, uint16_t fragments_left,
                           uint16_t len)
{
    uint8_t *d = reply_begin(s, MBX_TYPE_COE, (uint16_t)(COE_HDR + INFO_HDR + len));
    if (d != NULL) {
        put16(d, COE_SDO_INFO << 12);
        d[2] = (uint8_t)(opcode | (fragments_left != 0u ? INFO_INCOMPLETE : 0u));
        d[3] = 0;
        put16(d + 4, fragments_left);
        return d + COE_HDR + INFO_HDR;
    }
    return NULL;
}

static void info_error(co_ecat_slave *s, uint32_t code)
{
    uint8_t *d = info_begin(s, INFO_ERROR, 0, 4);
    s->xfer.kind = XFER_NONE;
    if (d != NULL) {
        put32(d, code);
    }
}

/* Does the object at position i of the list (the dictionary, 0x1C00/0x1C12/0x1C13 merged in
 * index order) belong to the list type? 1 all, 2 RxPDO-mappable, 3 TxPDO-mappable, 4 backup
 * (stored by 0x1010), 5 settings (none here). */
static bool in_list(const co_od_entry *e, uint16_t type)
{
    uint8_t want;
    switch (type) {
    case 1: return true;
    case 2: want = CO_OD_RPDO; break;
    case 3: want = CO_OD_TPDO; break;
    case 4: want = CO_OD_PERSIST; break;
    default: return false;
    }
    const co_od_sub *d = co_od_entry_subs(e);
    for (uint32_t k = 0; k < co_od_entry_sub_count(e); k++) {
        if ((d[k].flags & want) != 0u) {
            return true;
        }
    }
    return false;
}

/* The position-th index of list type (position counts from 0), or -1 past the end. The three
 * objects the slave adds go into list 1 at their place. */
static int32_t list_index(const co_ecat_slave *s, uint16_t type, uint32_t position)
{
    static const uint16_t added[3] = {0x1C00u, 0x1C12u, 0x1C13u};
    const co_od *od = s->node->od;
    uint32_t e = 0, a = 0, seen = 0;
    while (e < od->entry_count || (type == 1u && a < 3u)) {
        uint16_t index;
        bool take;
        if (type == 1u && a < 3u &&
            (e >= od->entry_count || added[a] < od->entries[e].index)) {
            index = added[a++];
            take = true;
        } else {
            index = od->entries[e].index;
            take = in_list(&od->entries[e], type);
            e++;
            if (type == 1u && a < 3u && index == added[a]) {
                a++; /* the dictionary has it after all */
            }
        }
        if (take) {
            if (seen == position) {
                return index;
            }
            seen++;
        }
    }
    return -1;
}

static uint32_t list_length(const co_ecat_slave *s, uint16_t type)
{
    const co_od *od = s->node->od;
    uint32_t n = 0;
    for (uint32_t e = 0; e < od->entry_count; e++) {
        n += in_list(&od->entries[e], type) ? 1u : 0u;
    }
    if (type == 1u) { /* the three the slave adds, unless the dictionary has them */
        n += co_od_find_entry(od, 0x1C00u) == NULL ? 1u : 0u;
        n += co_od_find_entry(od, 0x1C12u) == NULL ? 1u : 0u;
        n += co_od_find_entry(od, 0x1C13u) == NULL ? 1u : 0u;
    }
    return n;
}

/* Indexes per fragment: the first carries the list type word too. */
static uint32_t list_room(const co_ecat_slave *s)
{
    return (s->cfg.mbx_in_size - MBX_HDR - COE_HDR - INFO_HDR) / 2u;
}

static void od_list_fragment(co_ecat_slave *s)
{
    co_ecat_sdo_xfer *x = &s->xfer;
    uint32_t room = list_room(s) - (x->done == 0u ? 1u : 0u);
    uint32_t k = x->size - x->done;
    uint32_t after, frags = 0;
    uint8_t *d;
    if (k > room) {
        k = room;
    }
    after = x->size - x->done - k;
    frags = (after + list_room(s) - 1u) / list_room(s);
    d = info_begin(s, INFO_OD_LIST_RESP, (uint16_t)frags,
                   (uint16_t)(2u * k + (x->done == 0u ? 2u : 0u)));
    if (d == NULL) {
        x->kind = XFER_NONE;
        return;
    }
    if (x->done == 0u) {
        put16(d, x->list_type);
        d += 2;
    }
    /* positions in order: one walk per fragment */
    for (uint32_t i = 0; i < k; i++) {
        put16(d + 2u * i, (uint16_t)list_index(s, x->list_type, x->done + i));
    }
    x->done += k;
    if (x->done >= x->size) {
        x->kind = XFER_NONE;
    }
}

static void info_od_list(co_ecat_slave *s, uint16_t type)
{
    if (type == 0u) { /* the length of each list */
        uint8_t *d = info_begin(s, INFO_OD_LIST_RESP, 0, 12);
        if (d != NULL) {
            put16(d, 0);
            for (uint16_t t = 1; t <= 5u; t++) {
                put16(d + 2u * t, (uint16_t)list_length(s, t));
            }
        }
        return;
    }
    if (type > 5u) {
        info_error(s, CO_ABORT_VALUE_RANGE);
        return;
    }
    s->xfer.kind = XFER_OD_LIST;
    s->xfer.list_type = type;
    s->xfer.size = list_length(s, type);
    s->xfer.done = 0;
    od_list_fragment(s); /* the rest when SM1 has room (mailbox_send) */
}

/* The index in hex, the name of an object the name tables do not cover: "0xIIII", with ":SS"
 * for a sub-entry (sub >= 0). */
static uint32_t hex_name(char *out, uint16_t index, int sub)
{
    static const char hex[] = "0123456789ABCDEF";
    uint32_t n = 0;
    out[n++] = '0';
    out[n++] = 'x';
    for (int shift = 12; shift >= 0; shift -= 4) {
        out[n++] = hex[(index >> shift) & 0xFu];
    }
    if (sub >= 0) {
        out[n++] = ':';
        out[n++] = hex[(sub >> 4) & 0xF];
        out[n++] = hex[sub & 0xF];
    }
    return n;
}

/* The name SDO information gives an object (sub < 0) or a sub-entry, from the config's name
 * tables (the EDS ParameterName) where it has them, else the index in hex; at most cap bytes
 * (what the reply has room for in SM1). The tables count sub-entries per entry in table order:
 * entries of one shape share their descriptors, so a descriptor's position does not say it. */
static uint32_t object_name(const co_ecat_slave *s, char *out, uint32_t cap, uint16_t index,
                            int sub)
{
    const co_od *od = s->node->od;
    const co_od_entry *e = virtual_object(index) ? NULL : co_od_find_entry(od, index);
    const char *name = NULL;
    if (e != NULL && sub < 0 && s->cfg.entry_names != NULL) {
        name = s->cfg.entry_names[e - od->entries];
    } else if (e != NULL && sub >= 0 && s->cfg.sub_names != NULL) {
        const co_od_sub *d = co_od_find_sub(e, (uint8_t)sub);
        if (d != NULL) {
            uint32_t flat = (uint32_t)(d - co_od_entry_subs(e));
            for (const co_od_entry *p = od->entries; p < e; p++) {
                flat += co_od_entry_sub_count(p);
            }
            name = s->cfg.sub_names[flat];
        }
    }
    if (name == NULL) {
        return hex_name(out, index, sub); /* 10 bytes at most */
    }
    uint32_t n = (uint32_t)strlen(name);
    n = n < cap ? n : cap;
    memcpy(out, name, n);
    return n;
}

/* Room for a name in an SDO information reply whose fixed part is fixed bytes. */
static uint32_t name_room(const co_ecat_slave *s, uint32_t fixed)
{
    uint32_t used = MBX_HDR + COE_HDR + INFO_HDR + fixed;
    uint32_t room = s->cfg.mbx_in_size > used ? s->cfg.mbx_in_size - used : 0u;
    return room < INFO_NAME_MAX ? room : INFO_NAME_MAX;
}

static void info_object(co_ecat_slave *s, uint16_t index)
{
    uint16_t type;
    uint8_t max_sub, code;
    char name[INFO_NAME_MAX];
    uint32_t nlen = object_name(s, name, name_room(s, 6u), index, -1);
    if (virtual_object(index)) {
        type = index == 0x1C00u ? CO_UNSIGNED8 : CO_UNSIGNED16;
        max_sub = index == 0x1C00u ? 4u : 1u;
        code = CO_OBJ_ARRAY;
    } else {
        const co_od_entry *e = co_od_find_entry(s->node->od, index);
        const co_od_sub *d;
        uint32_t count;
        if (e == NULL) {
            info_error(s, CO_ABORT_NO_OBJECT);
            return;
        }
        d = co_od_entry_subs(e);
        count = co_od_entry_sub_count(e);
        max_sub = d[count - 1u].subindex;
        if (is_var(e)) {
            code = CO_OBJ_VAR;
            type = d[0].type;
        } else {
#if CO_CONFIG_OD_COMPACT
            code = CO_OBJ_RECORD;
#else
            code = e->object_code;
#endif
            /* an ARRAY's type is its elements' */
            type = code == CO_OBJ_ARRAY && count > 1u ? d[1].type : 0u;
        }
    }
    uint8_t *r = info_begin(s, INFO_OBJ_DESC_RESP, 0, (uint16_t)(6u + nlen));
    if (r != NULL) {
        put16(r, index);
        put16(r + 2, type);
        r[4] = max_sub;
        r[5] = code;
        memcpy(r + 6, name, nlen);
    }
}

static void info_entry(co_ecat_slave *s, uint16_t index, uint8_t sub, uint8_t value_info)
{
    uint16_t type, bits, access;
    char name[INFO_NAME_MAX];
    uint32_t nlen = object_name(s, name, name_room(s, 10u), index, sub);
    if (virtual_object(index)) {
        if (sub > (index == 0x1C00u ? 4u : 1u)) {
            info_error(s, CO_ABORT_NO_SUBINDEX);
            return;
        }
        type = sub == 0u || index == 0x1C00u ? CO_UNSIGNED8 : CO_UNSIGNED16;
        bits = type == CO_UNSIGNED8 ? 8u : 16u;
        access = ACCESS_READ_ALL;
    } else {
        const co_od_entry *e = co_od_find_entry(s->node->od, index);
        const co_od_sub *d = e != NULL ? co_od_find_sub(e, sub) : NULL;
        if (d == NULL) {
            info_error(s, e == NULL ? CO_ABORT_NO_OBJECT : CO_ABORT_NO_SUBINDEX);
            return;
        }
        type = d->type;
        bits = (uint16_t)(8u * (co_type_size(d->type) != 0u ? co_type_size(d->type)
                                                            : co_od_sub_size(d)));
        if (type == CO_BOOLEAN) {
            bits = 1;
        }
        access = (uint16_t)(((d->flags & CO_OD_READ) != 0u ? ACCESS_READ_ALL : 0u) |
                            ((d->flags & CO_OD_WRITE) != 0u ? ACCESS_WRITE_ALL : 0u) |
                            ((d->flags & CO_OD_RPDO) != 0u ? ACCESS_RXPDO : 0u) |
                            ((d->flags & CO_OD_TPDO) != 0u ? ACCESS_TXPDO : 0u) |
                            ((d->flags & CO_OD_PERSIST) != 0u ? ACCESS_BACKUP : 0u));
    }
    /* value info: only access rights, category and mappability, which add no fields (SOEM
     * reads the name from a fixed place) */
    uint8_t *r = info_begin(s, INFO_ENTRY_DESC_RESP, 0, (uint16_t)(10u + nlen));
    if (r != NULL) {
        put16(r, index);
        r[2] = sub;
        r[3] = (uint8_t)(value_info & 0x07u);
        put16(r + 4, type);
        put16(r + 6, bits);
        put16(r + 8, access);
        memcpy(r + 10, name, nlen);
    }
}

/* d: after the CoE header, len bytes. */
static void sdo_info(co_ecat_slave *s, const uint8_t *d, uint32_t len)
{
    uint8_t opcode = d[0] & 0x7Fu;
    s->xfer.kind = XFER_NONE;
    if (opcode == INFO_OD_LIST_REQ && len >= INFO_HDR + 2u) {
        info_od_list(s, le16(d + INFO_HDR));
    } else if (opcode == INFO_OBJ_DESC_REQ && len >= INFO_HDR + 2u) {
        info_object(s, le16(d + INFO_HDR));
    } else if (opcode == INFO_ENTRY_DESC_REQ && len >= INFO_HDR + 4u) {
        info_entry(s, le16(d + INFO_HDR), d[INFO_HDR + 2u], d[INFO_HDR + 3u]);
    } else if (opcode == INFO_OD_LIST_REQ || opcode == INFO_OBJ_DESC_REQ ||
               opcode == INFO_ENTRY_DESC_REQ) {
        mailbox_error(s, MBX_ERR_SIZE_TOO_SHORT);
    } else {
        info_error(s, CO_ABORT_COMMAND);
    }
}

/* ---- mailbox: receiving --------------------------------------------------------------------- */

static void coe_request(co_ecat_slave *s, const uint8_t *d, uint32_t len)
{
    if (len < COE_HDR) {
        mailbox_error(s, MBX_ERR_SIZE_TOO_SHORT);
        return;
    }
    switch (le16(d) >> 12) {
    case COE_SDO_REQUEST:
        if (len < SDO_FRAME) {
            mailbox_error(s, MBX_ERR_SIZE_TOO_SHORT);
        } else {
            sdo_request(s, d + COE_HDR, len - COE_HDR);
        }
        break;
    case COE_SDO_INFO:
        if (len < COE_HDR + INFO_HDR) {
            mailbox_error(s, MBX_ERR_SIZE_TOO_SHORT);
        } else {
            sdo_info(s, d + COE_HDR, len - COE_HDR);
        }
        break;
    default: /* PDOs over the mailbox, emergencies from the master: not served */
        mailbox_error(s, MBX_ERR_SERVICE_NOT_SUPPORTED);
        break;
    }
}

/* A full SM0: read it whole (which empties it for the master's next message) and answer. */
static void mailbox_receive(co_ecat_slave *s)
{
    uint8_t *b = s->rx_buf;
    uint16_t len;
    uint8_t type, counter;
    if ((rd8(s, CO_ESC_REG_SM_STATUS(SM_MBX_OUT)) & CO_ESC_SM_STATUS_MBX_FULL) == 0u) {
        return;
    }
    if (co_esc_pdi_read(s->esc, s->cfg.mbx_out_start, b, s->cfg.mbx_out_size) != CO_ESC_PDI_OK) {
        return;
    }
    s->stats.mbx_rx++;
    len = le16(b);
    type = b[5] & 0x0Fu;
    counter = (uint8_t)((b[5] >> 4) & 7u);
    if (len == 0u || len > s->cfg.mbx_out_size - MBX_HDR || type == MBX_TYPE_ERROR) {
        mailbox_error(s, MBX_ERR_INVALID_HEADER);
        return;
    }
    if ((b[4] & 0x3Fu) != 0u) {
        mailbox_error(s, MBX_ERR_INVALID_CHANNEL);
        return;
    }
    if (counter != 0u && counter == s->rx_counter) {
        s->stats.mbx_dropped++; /* the master sent it again: already answered */
        return;
    }
    s->rx_counter = counter;
    if (type != MBX_TYPE_COE) {
        mailbox_error(s, MBX_ERR_UNSUPPORTED_PROTOCOL);
        return;
    }
    coe_request(s, b + MBX_HDR, len);
}

/* ---- CoE emergency -------------------------------------------------------------------------- */

static void on_emcy(co_node *node, void *ctx, const uint8_t data[8])
{
    co_ecat_slave *s = ctx;
    (void)node;
    if (!mailbox_running(s)) {
        return; /* no mailbox in INIT (ETG.1000.6): the EMCY is in 0x1003 and 0x603F */
    }
    if (s->queue_count + 1u >= CO_ECAT_TX_QUEUE) {
        s->stats.mbx_lost++; /* the last slot stays for the answer to the master's request */
        return;
    }
    uint8_t *d = reply_begin(s, MBX_TYPE_COE, SDO_FRAME);
    if (d != NULL) {
        put16(d, COE_EMERGENCY << 12);
        memcpy(d + 2, data, 8);
        s->stats.emcy_sent++;
    }
}

/* ---- process data --------------------------------------------------------------------------- */


/* Resolves the mapping object pdo (0x1600/0x1A00) into entries; total bytes in *size. */
static bool map_pdo(co_ecat_slave *s, uint16_t pdo, bool outputs, co_ecat_pd_entry *out,
                    uint8_t *count, uint16_t *size)
{
    co_node *n = s->node;
    uint32_t total = 0;
    uint8_t entries;
    *count = 0;
    *size = 0;
    if (pdo == 0u) {
        return true;
    }
    if (co_od_find_entry(n->od, pdo) == NULL) {
        return false;
    }
    entries = co_od_get_u8(n, pdo, 0);
    if (entries > CO_ECAT_PD_ENTRIES) {
        return false;
    }
    for (uint8_t k = 1; k <= entries; k++) {
        uint32_t m = co_od_get_u32(n, pdo, k);
        uint32_t bits = m & 0xFFu;
        co_od_ref ref;
        if (bits == 0u || bits % 8u != 0u ||
            co_od_locate(n->od, (uint16_t)(m >> 16), (uint8_t)(m >> 8), &ref) != CO_ABORT_NONE ||
            co_type_size(ref.sub->type) != bits / 8u ||
            (ref.sub->flags & (outputs ? CO_OD_RPDO : CO_OD_TPDO)) == 0u ||
            total + bits / 8u > CO_ECAT_PD_MAX) {
            return false;
        }
        out[*count].ref = ref;
        out[*count].value = co_od_value_ptr(n, ref); /* a fixed-size type: never NULL */
        out[*count].offset = (uint16_t)total;
        out[*count].size = (uint8_t)(bits / 8u);
        (*count)++;
        total += bits / 8u;
    }
    *size = (uint16_t)total;
    return true;
}

/* SM n programmed as the slave expects: start, length, control byte, enabled iff length > 0. */
static bool sm_matches(co_ecat_slave *s, uint8_t n, uint16_t start, uint16_t len, uint8_t ctrl)
{
    uint8_t r[8];
    bool on;
    if (co_esc_pdi_read(s->esc, (uint16_t)CO_ESC_REG_SM(n), r, 8) != CO_ESC_PDI_OK) {
        return false;
    }
    on = (r[6] & SM_ACT_ENABLE) != 0u;
    if (len == 0u) {
        return !on || le16(r + 2) == 0u;
    }
    return on && le16(r) == start && le16(r + 2) == len &&
           (r[4] & SM_CTRL_CHECKED) == (ctrl & SM_CTRL_CHECKED);
}

/* Process-data entries are 1 to 8 bytes, mostly 1, 2 or 4: copies and compares of those sizes
 * done inline (one load and store each) rather than through a library call for 2 bytes. */
static void pd_copy(uint8_t *dst, const uint8_t *src, uint8_t size)
{
    switch (size) {
    case 1: dst[0] = src[0]; break;
    case 2: memcpy(dst, src, 2); break;
    case 4: memcpy(dst, src, 4); break;
    default: memcpy(dst, src, size); break;
    }
}

static bool pd_equal(const uint8_t *a, const uint8_t *b, uint8_t size)
{
    uint16_t a16, b16;
    uint32_t a32, b32;
    switch (size) {
    case 1: return a[0] == b[0];
    case 2:
        memcpy(&a16, a, 2);
        memcpy(&b16, b, 2);
        return a16 == b16;
    case 4:
        memcpy(&a32, a, 4);
        memcpy(&b32, b, 4);
        return a32 == b32;
    default: return memcmp(a, b, size) == 0;
    }
}

/* Inputs: the mapped objects' values into SM3 (SAFE-OP and OP), when they changed (the master
 * reads the last buffer written as often as it wants). */
static void update_inputs(co_ecat_slave *s)
{
    bool changed = !s->inputs_written;
    if (s->in_size == 0u) {
        return;
    }
    /* the values as the application reads them (no refresh hook: those serve SDO reads), straight
     * from the value block */
    for (uint8_t i = 0; i < s->in_count; i++) {
        const co_ecat_pd_entry *e = &s->in[i];
        if (!pd_equal(s->in_image + e->offset, e->value, e->size)) {
            pd_copy(s->in_image + e->offset, e->value, e->size);
            changed = true;
        }
    }
    if (changed) {
        s->inputs_written =
            co_esc_pdi_write(s->esc, s->cfg.in_start, s->in_image, s->in_size) == CO_ESC_PDI_OK;
    }
}

static void node_to_now(co_ecat_slave *s);

/* Outputs: the latest SM2 buffer; applied to the mapped objects in OP only. */
static void read_outputs(co_ecat_slave *s, bool apply)
{
    if (s->out_size == 0u ||
        co_esc_pdi_read(s->esc, s->cfg.out_start, s->out_image, s->out_size) != CO_ESC_PDI_OK) {
        return;
    }
    s->outputs_valid = true;
    if (!apply) {
        return; /* SAFE-OP: the outputs stay in their safe state (manual §7) */
    }
    s->stats.outputs++;
    /* Each object whose value differs from the output (every object with the first buffer in
     * OP): a cyclic master repeats the same outputs every cycle, and rewriting an equal value
     * would make the drive recompute what it shows for nothing. Comparing with the object, not
     * with the last buffer, lets the output win again when something else changed the object
     * (an SDO write, the drive itself), as every RPDO does over CAN. */
    for (uint8_t i = 0; i < s->out_count; i++) {
        const co_ecat_pd_entry *e = &s->out[i];
        const uint8_t *now = s->out_image + e->offset;
        if (!s->applied_valid || !pd_equal(now, e->value, e->size)) {
            node_to_now(s);
            (void)co_od_write_ref(s->node, e->ref, now, e->size, CO_ORIGIN_RPDO);
        }
    }
    s->applied_valid = true;
}

/* ---- ESM transitions (one function each; manual §7 names them IP, PS, SO, ...) -------------- */

/* IP: start mailbox communication, if SM0/SM1 are as the SII says. */
static void init_to_preop(co_ecat_slave *s)
{
    if (!sm_matches(s, SM_MBX_OUT, s->cfg.mbx_out_start, s->cfg.mbx_out_size,
                    s->cfg.mbx_out_ctrl) ||
        !sm_matches(s, SM_MBX_IN, s->cfg.mbx_in_start, s->cfg.mbx_in_size, s->cfg.mbx_in_ctrl)) {
        refuse(s, CO_ECAT_STATE_INIT, CO_ECAT_AL_INVALID_MBX_CONFIG);
        return;
    }
    stop_mailbox(s);
    /* the repeat toggle starts where the master left it, acknowledged */
    s->repeat_toggle = rd8(s, CO_ESC_REG_SM_ACTIVATE(SM_MBX_IN)) & SM_ACT_REPEAT;
    uint8_t pdi = s->repeat_toggle != 0u ? SM_PDI_REPEAT_ACK : 0u;
    (void)co_esc_pdi_write(s->esc, CO_ESC_REG_SM_PDICTL(SM_MBX_IN), &pdi, 1);
    enter(s, CO_ECAT_STATE_PREOP);
}

/* PS: start input update, if the mapping can be served and SM2/SM3 match it. */
static void preop_to_safeop(co_ecat_slave *s)
{
    if (!map_pdo(s, s->cfg.rx_pdo, true, s->out, &s->out_count, &s->out_size)) {
        refuse(s, CO_ECAT_STATE_PREOP, CO_ECAT_AL_INVALID_OUTPUT_MAPPING);
        return;
    }
    if (!map_pdo(s, s->cfg.tx_pdo, false, s->in, &s->in_count, &s->in_size)) {
        refuse(s, CO_ECAT_STATE_PREOP, CO_ECAT_AL_INVALID_INPUT_MAPPING);
        return;
    }
    if (!sm_matches(s, SM_OUTPUTS, s->cfg.out_start, s->out_size, s->cfg.out_ctrl)) {
        refuse(s, CO_ECAT_STATE_PREOP, CO_ECAT_AL_INVALID_OUTPUT_CONFIG);
        return;
    }
    if (!sm_matches(s, SM_INPUTS, s->cfg.in_start, s->in_size, s->cfg.in_ctrl)) {
        refuse(s, CO_ECAT_STATE_PREOP, CO_ECAT_AL_INVALID_INPUT_CONFIG);
        return;
    }
    pdo_restore(s);
    s->outputs_valid = false;
    s->inputs_written = false;
    enter(s, CO_ECAT_STATE_SAFEOP);
    update_inputs(s);
}

/* The SM watchdog time (0x0400 divider, 0x0420 time), ns; 0: disabled. */
static uint64_t watchdog_ns(co_ecat_slave *s)
{
    return ((uint64_t)rd16(s, CO_ESC_REG_WD_DIV) + 2u) * 40u * rd16(s, CO_ESC_REG_WD_SM);
}

/* SO: start output update, once valid outputs have arrived (ETG.1000.6): the request waits for
 * the first SM2 buffer up to the SM watchdog time (1 s without one), then fails with 0x001B. */
static void safeop_to_op(co_ecat_slave *s)
{
    if (s->out_size != 0u && !s->outputs_valid) {
        uint64_t wait = watchdog_ns(s);
        s->op_pending = true;
        s->op_deadline = s->now + (wait != 0u ? wait : 1000000000u);
        return;
    }
    s->op_pending = false;
    s->applied_valid = false;
    enter(s, CO_ECAT_STATE_OP);
    read_outputs(s, true);
}

/* OS, OP, OI, SP, SI, PI: stop what the lower state does not run. Leaving OP reaches the node as
 * leaving OPERATIONAL (the drive's communication-interruption reaction, manual §7). */
static void go_down(co_ecat_slave *s, uint8_t to)
{
    s->op_pending = false;
    s->outputs_valid = false; /* OP again needs new outputs */
    if (to == CO_ECAT_STATE_INIT) {
        stop_mailbox(s);
    }
    enter(s, to);
}

static void al_control(co_ecat_slave *s)
{
    uint16_t ctl = rd16(s, CO_ESC_REG_ALCTL); /* clears the AL control event */
    uint8_t req = (uint8_t)(ctl & CO_ECAT_STATE_MASK);
    uint8_t from = s->state & CO_ECAT_STATE_MASK;
    s->stats.al_requests++;
    if ((s->state & CO_ECAT_AL_ERROR) != 0u) {
        /* the error indication stays until acknowledged (or INIT is requested) */
        if ((ctl & CO_ECAT_AL_ERROR) == 0u && req != CO_ECAT_STATE_INIT) {
            return;
        }
        s->state = from;
        s->status_code = CO_ECAT_AL_NO_ERROR;
        publish_al_status(s);
    }
    s->op_pending = false;
    switch (req) {
    case CO_ECAT_STATE_INIT:
        if (from != CO_ECAT_STATE_INIT) {
            go_down(s, CO_ECAT_STATE_INIT);
        }
        break;
    case CO_ECAT_STATE_PREOP:
        if (from == CO_ECAT_STATE_INIT) {
            init_to_preop(s);
        } else if (from != CO_ECAT_STATE_PREOP) {
            go_down(s, CO_ECAT_STATE_PREOP);
        }
        break;
    case CO_ECAT_STATE_SAFEOP:
        if (from == CO_ECAT_STATE_PREOP) {
            preop_to_safeop(s);
        } else if (from == CO_ECAT_STATE_OP) {
            go_down(s, CO_ECAT_STATE_SAFEOP);
        } else if (from != CO_ECAT_STATE_SAFEOP) {
            refuse(s, from, CO_ECAT_AL_INVALID_STATE_CHANGE);
        }
        break;
    case CO_ECAT_STATE_OP:
        if (from == CO_ECAT_STATE_SAFEOP) {
            safeop_to_op(s);
        } else if (from != CO_ECAT_STATE_OP) {
            refuse(s, from, CO_ECAT_AL_INVALID_STATE_CHANGE);
        }
        break;
    case CO_ECAT_STATE_BOOT:
        /* IB is listed by the manual (§7) but there is no firmware download (no FoE) */
        refuse(s, from, from == CO_ECAT_STATE_INIT ? CO_ECAT_AL_BOOT_NOT_SUPPORTED
                                                   : CO_ECAT_AL_INVALID_STATE_CHANGE);
        break;
    default:
        refuse(s, from, CO_ECAT_AL_UNKNOWN_STATE);
        break;
    }
}

/* SM watchdog expiry (outputs stopped arriving): leave OP with the error indication and 0x001B;
 * the node hears it as an RPDO timeout and as leaving OPERATIONAL. */
static void watchdog_expired(co_ecat_slave *s)
{
    (void)rd16(s, CO_ESC_REG_WD_STATUS); /* clears the AL event */
    if ((s->state & CO_ECAT_STATE_MASK) != CO_ECAT_STATE_OP) {
        return;
    }
    s->stats.wd_expired++;
    refuse(s, CO_ECAT_STATE_OP, CO_ECAT_AL_SM_WATCHDOG);
    s->stats.al_refused--; /* not a refused request */
    if (s->node->events.comm != NULL) {
        s->node->events.comm(s->node, s->node->events.ctx, CO_COMM_RPDO_TIMEOUT, 1u);
    }
}

/* ---- the API -------------------------------------------------------------------------------- */

co_ecat_slave_config co_ecat_slave_default_config(void)
{
    co_ecat_slave_config c;
    memset(&c, 0, sizeof c);
    c.mbx_out_start = 0x1000u;
    c.mbx_out_size = 128u;
    c.mbx_out_ctrl = 0x26u;
    c.mbx_in_start = 0x1080u;
    c.mbx_in_size = 128u;
    c.mbx_in_ctrl = 0x22u;
    c.out_start = 0x1100u;
    c.out_ctrl = 0x64u;
    c.in_start = 0x1180u;
    c.in_ctrl = 0x20u;
    c.rx_pdo = 0x1600u;
    c.tx_pdo = 0x1A00u;
    return c;
}

bool co_ecat_slave_init(co_ecat_slave *s, const co_ecat_slave_config *cfg, uint64_t now_ns)
{
    if (s == NULL || cfg == NULL || cfg->esc == NULL || cfg->node == NULL ||
        cfg->mbx_out_size > CO_ECAT_MBX_MAX || cfg->mbx_in_size > CO_ECAT_MBX_MAX ||
        cfg->mbx_out_size < 16u || cfg->mbx_in_size < 16u) {
        return false;
    }
    memset(s, 0, sizeof *s);
    s->cfg = *cfg;
    s->esc = cfg->esc;
    s->node = cfg->node;
    s->drive = cfg->drive;
    s->now = now_ns;
    co_emcy_set_listener(s->node, on_emcy, s);
    enter(s, CO_ECAT_STATE_INIT);
    return true;
}

/* The node's clock brought to now (the drive moved up to it), so that hooks of the writes below
 * run at the right time; its deadline in ns. */
static uint64_t run_node(co_ecat_slave *s)
{
    uint64_t next = s->drive != NULL ? co_drive_process(s->drive, node_us(s))
                                     : co_node_process(s->node, node_us(s));
    return next >= CO_TIME_NEVER / 1000u ? CO_ESC_TIME_NEVER : next * 1000u;
}

/* Before the first write to the dictionary in a process call: the node's clock (and the drive)
 * brought to now, so that the writes' hooks run at the right time. A cycle that writes nothing
 * (outputs equal to the objects, no state change, no mailbox message) runs the drive once, at
 * the end of the call. */
static void node_to_now(co_ecat_slave *s)
{
    if (!s->node_current) {
        (void)run_node(s);
        s->node_current = true;
    }
}

uint64_t co_ecat_slave_process(co_ecat_slave *s, uint64_t now_ns)
{
    /* the process-data events of a cycle; read_outputs brings the node to now itself */
    const uint32_t pd_events = CO_ESC_AL_EVENT_SM(SM_OUTPUTS) | CO_ESC_AL_EVENT_SM(SM_INPUTS);
    uint64_t next, node_next;
    uint32_t events, news;
    uint8_t st;
    s->now = now_ns;
    s->node_current = false;
    next = co_esc_tick(s->esc, now_ns);
    events = co_esc_al_event(s->esc);
    news = events & ~pd_events;
    if (!s->newer_posted && mailbox_idle(s)) {
        /* SM1's event stays from the master's read of SM1 until the next message is posted:
         * with nothing posted since and nothing waiting, it brings nothing new */
        news &= ~CO_ESC_AL_EVENT_SM(SM_MBX_IN);
    }
    if (news != 0u || s->op_pending) {
        node_to_now(s);
    }
    if ((events & CO_ESC_AL_EVENT_ALCTL) != 0u) {
        al_control(s);
    }
    if ((events & CO_ESC_AL_EVENT_WD_PD) != 0u) {
        watchdog_expired(s);
    }
    if (mailbox_running(s)) {
        /* the ESC's events say when to look: an activate byte changed (the repeat toggle), the
         * master completed a message in SM0 */
        if ((events & CO_ESC_AL_EVENT_SM_CHANGE) != 0u) {
            mailbox_repeat(s);
        }
        if ((events & CO_ESC_AL_EVENT_SM(SM_MBX_OUT)) != 0u) {
            mailbox_receive(s);
        }
        if ((events & CO_ESC_AL_EVENT_SM(SM_MBX_IN)) != 0u) {
            s->newer_posted = false; /* the master has read what SM1 held */
        }
    }
    st = s->state & CO_ECAT_STATE_MASK;
    if ((st == CO_ECAT_STATE_SAFEOP || st == CO_ECAT_STATE_OP) &&
        (events & CO_ESC_AL_EVENT_SM(SM_OUTPUTS)) != 0u) {
        read_outputs(s, st == CO_ECAT_STATE_OP);
    }
    /* Only process data came, and it changed no object (node_current: nothing was written):
     * the node is as the last call left it until its deadline, and so are the inputs in SM3. */
    if (s->settled && !s->node_current && news == 0u &&
        (events & CO_ESC_AL_EVENT_SM(SM_OUTPUTS)) != 0u && now_ns < s->node_next) {
        return s->node_next < next ? s->node_next : next;
    }
    if (s->op_pending) {
        if (s->outputs_valid) {
            safeop_to_op(s);
        } else if (now_ns >= s->op_deadline) {
            refuse(s, CO_ECAT_STATE_SAFEOP, CO_ECAT_AL_SM_WATCHDOG);
        } else if (s->op_deadline < next) {
            next = s->op_deadline;
        }
    }
    /* the drive acts on what arrived (outputs, state changes, SDO writes) and says when it
     * needs to run next (a communication-loss delay, a ramp); the inputs show the result */
    node_next = run_node(s);
    if (sync_nmt(s)) { /* a reset communication (F899 = 1) put the node in PRE-OPERATIONAL */
        node_next = run_node(s);
    }
    /* replies, and the emergencies the drive raised in this call, go out now */
    if (mailbox_running(s)) {
        mailbox_send(s);
    }
    st = s->state & CO_ECAT_STATE_MASK;
    if (st == CO_ECAT_STATE_SAFEOP || st == CO_ECAT_STATE_OP) {
        update_inputs(s);
    }
    /* the next call may skip the node if this one left SM3 as the objects are, in SAFE-OP or
     * OP, with no message waiting for SM1 */
    s->settled = (st == CO_ECAT_STATE_SAFEOP || st == CO_ECAT_STATE_OP) && s->inputs_written &&
                 !s->op_pending && mailbox_idle(s);
    s->node_next = node_next;
    return node_next < next ? node_next : next;
}

uint8_t co_ecat_slave_state(const co_ecat_slave *s)
{
    return s->state & CO_ECAT_STATE_MASK;
}

bool co_ecat_slave_error(const co_ecat_slave *s)
{
    return (s->state & CO_ECAT_AL_ERROR) != 0u;
}

const char *co_ecat_state_name(uint8_t state)
{
    switch (state & CO_ECAT_STATE_MASK) {
    case CO_ECAT_STATE_INIT: return "INIT";
    case CO_ECAT_STATE_PREOP: return "PREOP";
    case CO_ECAT_STATE_BOOT: return "BOOT";
    case CO_ECAT_STATE_SAFEOP: return "SAFEOP";
    case CO_ECAT_STATE_OP: return "OP";
    default: return "?";
    }
}

/* VF-MB1 EtherCAT option manual §2.3, RUN LED: off INIT, green blinking PRE-OP, single flash
 * SAFE-OP, on OP. */
const char *co_ecat_slave_run_led(const co_ecat_slave *s)
{
    switch (s->state & CO_ECAT_STATE_MASK) {
    case CO_ECAT_STATE_PREOP: return "blinking";
    case CO_ECAT_STATE_SAFEOP: return "single flash";
    case CO_ECAT_STATE_OP: return "on";
    default: return "off";
    }
}

/* §2.3, ERR LED: off no error, blinking invalid configuration, single flash local error,
 * double flash watchdog time-out. */
const char *co_ecat_slave_err_led(const co_ecat_slave *s)
{
    if ((s->state & CO_ECAT_AL_ERROR) == 0u) {
        return "off";
    }
    switch (s->status_code) {
    case CO_ECAT_AL_SM_WATCHDOG: return "double flash";
    case CO_ECAT_AL_INVALID_STATE_CHANGE:
    case CO_ECAT_AL_UNKNOWN_STATE:
    case CO_ECAT_AL_BOOT_NOT_SUPPORTED:
    case CO_ECAT_AL_INVALID_MBX_CONFIG:
    case CO_ECAT_AL_INVALID_SM_CONFIG:
    case CO_ECAT_AL_INVALID_OUTPUT_CONFIG:
    case CO_ECAT_AL_INVALID_INPUT_CONFIG:
    case CO_ECAT_AL_INVALID_INPUT_MAPPING:
    case CO_ECAT_AL_INVALID_OUTPUT_MAPPING: return "blinking";
    default: return "single flash";
    }
}
