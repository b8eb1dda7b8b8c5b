/* An emulated EtherCAT Slave Controller (ESC): the register and process RAM image of one slave,
 * processed by EtherCAT frames on the master side and by register accesses on the PDI side, the
 * way a hardware ESC (ET1100, LAN9252) sits between the wire and the slave's microcontroller.
 * All state is in the caller's co_esc; no OS call, no allocation.
 *
 *   co_esc esc;
 *   co_esc_config cfg = co_esc_default_config();
 *   cfg.sii = image; cfg.sii_size = sizeof image;
 *   co_esc_init(&esc, &cfg);
 *   for (;;) {
 *       receive a frame (EtherType 0x88A4);
 *       co_esc_process_frame(&esc, frame, len, now_ns);   // in place, like the ESC on the wire
 *       send the frame back (same length);
 *       the application layer: co_esc_al_event(&esc), co_esc_pdi_read/write(...);
 *       next = co_esc_tick(&esc, now_ns);                  // SM watchdog on the caller's clock
 *   }
 *
 * Memory: registers 0x0000-0x0FFF, process RAM 0x1000 .. 0x1000 + CO_ESC_RAM_SIZE - 1. Multi-byte
 * registers are little-endian (ETG.1000.4). Times are nanoseconds of the caller's monotonic clock.
 *
 * What the PDI side (the application layer) must do, as on a real ESC (Beckhoff ESC datasheet
 * section I §8 SyncManager, section II register description):
 *   - Poll the AL event request word (co_esc_al_event): bit 0 = AL control 0x0120 was written
 *     (cleared by a PDI read of 0x0120), bit 4 = an SM activate register 0x0806+8n changed
 *     (cleared by a PDI read of that byte), bit 6 = process-data watchdog expired (cleared by a PDI
 *     read of 0x0440), bit 8+n = SyncManager n needs attention: the master completed a write into
 *     a buffer the PDI reads, or completed a read of a buffer the PDI writes (cleared when the PDI
 *     accesses the first byte of that SM's buffer). SM n events need SM control bit 5.
 *   - Decide the EtherCAT state: read AL control 0x0120, write AL status 0x0130 and AL status code
 *     0x0134 (the ESC never changes AL status itself: no device emulation, 0x0141 bit 0 = 0).
 *   - Mailbox SM the master writes (SM0): when 0x0805+8n bit 3 (mailbox full) is set, read the
 *     buffer from its start address; the read that covers its last byte empties it (bit 3 := 0) so
 *     the master may write the next message. A read that does not begin at the start address
 *     (and does not continue a read that did) is refused (CO_ESC_PDI_BLOCKED).
 *   - Mailbox SM the master reads (SM1): when bit 3 is clear, write the message from the start
 *     address; the write that covers the last byte (write the whole length, or the message and
 *     then the last byte) marks it full; the master's read of its last byte empties it and raises
 *     event bit 8+n. A write to a full mailbox is refused.
 *   - Buffered SMs (3-buffer mode, SM2/SM3): read or write at the start address as often as
 *     wanted; a read sees the last complete buffer, a write is published when its last byte is
 *     written. Buffers 1 and 2 occupy start+len .. start+3*len-1 of the RAM.
 *   - Repeat request: the master toggles 0x0806+8n bit 1; the PDI answers by toggling 0x0807+8n
 *     bit 1 (repeat acknowledge). Setting 0x0807+8n bit 0 deactivates the SM (its buffer state is
 *     reset, a full mailbox is emptied); clearing it activates the SM again.
 *
 * Who may write what (everything else is read-only for both sides; a write to a read-only byte
 * is acknowledged, as by the ESC, but changes nothing):
 *   master only:  0x0010 station address, 0x0100-0x0103 DL control, 0x0108 physical RW offset,
 *                 0x0120 AL control, 0x0200 ECAT event mask, 0x0300-0x0313 error counters and
 *                 0x0442/0x0443 watchdog counters (a write clears them), 0x0400 watchdog divider,
 *                 0x0410 PDI / 0x0420 SM watchdog time, 0x0500 EEPROM configuration, 0x0502
 *                 bit 0 and bits 8-10 (EEPROM command), 0x0504-0x050F EEPROM address and data,
 *                 FMMUs 0x0600+16n, SM start/length/control 0x0800-0x0804+8n (only while the SM is
 *                 disabled), SM activate 0x0806+8n (bits 0, 1, 6, 7), the DC registers (if DC)
 *   PDI only:     0x0012 station alias, 0x0130 AL status, 0x0134 AL status code, 0x0204 AL event
 *                 mask, SM PDI control 0x0807+8n (bits 0, 1)
 *   both:         user RAM 0x0F80-0x0FFF, the process RAM outside enabled SyncManagers
 */
#ifndef CANOPEN_ECAT_ESC_H
#define CANOPEN_ECAT_ESC_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Process RAM behind the registers, in bytes (a multiple of 1024, reported in 0x0006 in KiB). */
#ifndef CO_ESC_RAM_SIZE
#define CO_ESC_RAM_SIZE 4096u
#endif
#define CO_ESC_REG_SIZE 0x1000u
#define CO_ESC_MEM_SIZE (CO_ESC_REG_SIZE + CO_ESC_RAM_SIZE)
#define CO_ESC_MAX_FMMU 8u
#define CO_ESC_MAX_SM 8u
#define CO_ESC_TIME_NEVER UINT64_MAX

/* Registers (Beckhoff ESC datasheet section II; SOEM ethercattype.h ECT_REG_*). */
#define CO_ESC_REG_TYPE 0x0000u
#define CO_ESC_REG_FEATURES 0x0008u
#define CO_ESC_REG_STADR 0x0010u
#define CO_ESC_REG_ALIAS 0x0012u
#define CO_ESC_REG_DLCTL 0x0100u
#define CO_ESC_REG_DLSTAT 0x0110u
#define CO_ESC_REG_ALCTL 0x0120u
#define CO_ESC_REG_ALSTAT 0x0130u
#define CO_ESC_REG_ALSTATCODE 0x0134u
#define CO_ESC_REG_PDICTL 0x0140u
#define CO_ESC_REG_ECAT_EVENT_MASK 0x0200u
#define CO_ESC_REG_AL_EVENT_MASK 0x0204u
#define CO_ESC_REG_ECAT_EVENT 0x0210u
#define CO_ESC_REG_AL_EVENT 0x0220u
#define CO_ESC_REG_RXERR 0x0300u
#define CO_ESC_REG_WD_DIV 0x0400u
#define CO_ESC_REG_WD_PDI 0x0410u
#define CO_ESC_REG_WD_SM 0x0420u
#define CO_ESC_REG_WD_STATUS 0x0440u
#define CO_ESC_REG_WD_COUNT 0x0442u
#define CO_ESC_REG_EEP_CFG 0x0500u
#define CO_ESC_REG_EEP_CTL 0x0502u
#define CO_ESC_REG_EEP_ADDR 0x0504u
#define CO_ESC_REG_EEP_DATA 0x0508u
#define CO_ESC_REG_FMMU(n) (0x0600u + 16u * (n))
#define CO_ESC_REG_SM(n) (0x0800u + 8u * (n))
#define CO_ESC_REG_SM_STATUS(n) (0x0805u + 8u * (n))
#define CO_ESC_REG_SM_ACTIVATE(n) (0x0806u + 8u * (n))
#define CO_ESC_REG_SM_PDICTL(n) (0x0807u + 8u * (n))
#define CO_ESC_REG_DC_RECV_TIME 0x0900u
#define CO_ESC_REG_DC_SYSTIME 0x0910u
#define CO_ESC_REG_DC_RECV_TIME_PU 0x0918u
#define CO_ESC_REG_DC_OFFSET 0x0920u
#define CO_ESC_REG_DC_DELAY 0x0928u
#define CO_ESC_REG_DC_SYNC_ACT 0x0981u
#define CO_ESC_REG_DC_SYNC0_CYCLE 0x09A0u

/* AL event request bits (0x0220). */
#define CO_ESC_AL_EVENT_ALCTL 0x00000001u
#define CO_ESC_AL_EVENT_SM_CHANGE 0x00000010u
#define CO_ESC_AL_EVENT_WD_PD 0x00000040u
#define CO_ESC_AL_EVENT_SM(n) (0x00000100u << (n))

/* ECAT event request bits (0x0210), ORed (masked by 0x0200) into every datagram's IRQ field. */
#define CO_ESC_ECAT_EVENT_ALSTAT 0x0008u
#define CO_ESC_ECAT_EVENT_SM(n) (0x0010u << (n))

/* SM status (0x0805+8n) and control (0x0804+8n) bits. */
#define CO_ESC_SM_STATUS_IRQ_WRITE 0x01u
#define CO_ESC_SM_STATUS_IRQ_READ 0x02u
#define CO_ESC_SM_STATUS_MBX_FULL 0x08u
#define CO_ESC_SM_CTRL_MAILBOX 0x02u
#define CO_ESC_SM_CTRL_MASTER_WRITES 0x04u
#define CO_ESC_SM_CTRL_ECAT_EVENT 0x10u
#define CO_ESC_SM_CTRL_AL_EVENT 0x20u
#define CO_ESC_SM_CTRL_WATCHDOG 0x40u

/* ESC features (0x0008): FMMUs byte-oriented (bit 0), DC (bit 2) with 64-bit time (bit 3). */
#define CO_ESC_FEATURE_FMMU_BYTES 0x0001u
#define CO_ESC_FEATURE_DC 0x0004u
#define CO_ESC_FEATURE_DC64 0x0008u

/* co_esc_process_frame results. */
#define CO_ESC_FRAME_OK 0          /* processed; the frame now carries the replies */
#define CO_ESC_FRAME_NOT_ECAT 1    /* not EtherType 0x88A4 or not type 1 (commands): untouched */
#define CO_ESC_FRAME_SHORT (-1)    /* shorter than Ethernet + EtherCAT header: untouched, counted */
#define CO_ESC_FRAME_BAD_LENGTH (-2) /* length field or a datagram beyond the frame or not ending
                                        where the length field says: untouched, counted */

/* co_esc_pdi_read / co_esc_pdi_write results. */
#define CO_ESC_PDI_OK 0
#define CO_ESC_PDI_BLOCKED 1 /* part of the range is a SyncManager buffer the PDI may not access
                                now (mailbox empty/full, not started at the start address) */
#define CO_ESC_PDI_RANGE (-1) /* the range leaves the image: nothing accessed */

typedef struct co_esc_config {
    uint8_t type;          /* 0x0000 ESC type */
    uint8_t revision;      /* 0x0001 */
    uint16_t build;        /* 0x0002 */
    uint8_t fmmu_count;    /* 0x0004, 1..CO_ESC_MAX_FMMU */
    uint8_t sm_count;      /* 0x0005, 1..CO_ESC_MAX_SM */
    uint8_t port_desc;     /* 0x0007: 2 bits per port, 00 none, 01 not configured, 10 EBUS, 11 MII */
    uint8_t open_ports;    /* bit p: port p has a link and communication (bit 0: towards the
                              master, always set); the others are closed loops. Makes 0x0110. */
    bool dc;               /* emulate the distributed-clock registers and advertise them in 0x0008 */
    bool eeprom_read8;     /* EEPROM reads return 8 bytes (0x0502 bit 6) instead of 4 */
    const uint8_t *sii;    /* SII EEPROM image (words little-endian), read-only */
    size_t sii_size;       /* bytes */
} co_esc_config;

/* Buffer state of one SyncManager (private to esc.c; in the header for the struct's size). */
typedef struct co_esc_sm {
    uint16_t start;
    uint16_t len;
    uint8_t ctrl;
    uint8_t act;     /* activate byte as last seen (change detection) */
    uint8_t on;      /* enabled: activated by the master, not deactivated by the PDI, valid */
    uint8_t latest;  /* buffered mode: last complete buffer 0..2, 3 = none yet */
    uint8_t wbuf;    /* buffer being written */
    uint8_t rbuf;    /* buffer being read */
    uint8_t w_open;  /* a write began at the start address and has not reached the end */
    uint8_t r_open;  /* the same for a read */
} co_esc_sm;

/* An active FMMU as decoded from 0x0600+16n (private). */
typedef struct co_esc_fmmu {
    uint32_t log;
    uint16_t len;
    uint16_t phys;
    uint8_t type; /* bit 0 read (memory to frame), bit 1 write (frame to memory) */
    uint8_t sm;   /* the SM whose buffer holds all of [phys, phys + len), CO_ESC_MAX_SM if none */
} co_esc_fmmu;

typedef struct co_esc_stats {
    uint32_t frames;       /* EtherCAT frames processed */
    uint32_t bad_frames;   /* short or bad length: left untouched */
    uint32_t ignored;      /* not EtherCAT commands: left untouched */
    uint32_t datagrams;    /* datagrams processed (NOP and unknown commands included) */
    uint32_t unknown_cmds; /* datagrams with a command code above 14: passed on untouched */
} co_esc_stats;

typedef struct co_esc {
    uint8_t mem[CO_ESC_MEM_SIZE]; /* registers and process RAM */
    const uint8_t *sii;
    size_t sii_size;
    uint8_t fmmu_count;
    uint8_t sm_count;
    bool dc;
    uint8_t fmmu_active;
    co_esc_fmmu fmmu[CO_ESC_MAX_FMMU];
    co_esc_sm sm[CO_ESC_MAX_SM];
    uint8_t sm_order[CO_ESC_MAX_SM]; /* the enabled SMs by start address (memory lookup) */
    uint8_t sm_enabled;              /* entries in sm_order */
    uint16_t sm_lo[CO_ESC_MAX_SM];   /* start and end (exclusive) of sm_order[k]'s buffer */
    uint16_t sm_hi[CO_ESC_MAX_SM];
    uint64_t now;         /* time of the frame or tick being processed */
    uint64_t wd_deadline; /* process-data watchdog expiry, CO_ESC_TIME_NEVER when not running */
    co_esc_stats stats;
} co_esc;

/* An ET1100-like configuration (ecat/NOTES.md): type 0x11, 8 FMMUs, 8 SMs, ports 0 and 1 MII,
 * port 0 open, no DC, 4-byte EEPROM reads, no SII image. */
co_esc_config co_esc_default_config(void);

/* Power-on: zeroes the image, sets the read-only information registers from cfg, loads the SII
 * header as the ESC does (0x0140/0x0141 from word 0, 0x0150 from word 1, 0x0152 from word 3, alias
 * 0x0012 from word 4) when its CRC (word 7) is right, and otherwise sets 0x0502 bits 11/12 and
 * clears 0x0110 bit 0. Watchdog defaults: divider 2498 (100 µs), PDI and SM times 1000 (100 ms).
 * Returns 0, or -1 (nothing done) for a NULL argument or counts outside 1..CO_ESC_MAX_*. */
int co_esc_init(co_esc *esc, const co_esc_config *cfg);

/* Processes one Ethernet frame in place as the ESC does when it passes: every datagram is
 * executed (ETG.1000.4 commands and working counter rules), ADP incremented for auto-increment
 * and broadcast commands, the event request ORed into the IRQ field, and the locally-administered
 * bit set in the source MAC. The frame is checked first; a bad one is left untouched and counted
 * (0x0300 invalid frame counter of port 0, stats). now_ns also runs the SM watchdog. */
int co_esc_process_frame(co_esc *esc, uint8_t *frame, size_t len, uint64_t now_ns);

/* Passes the frame through esc[0] .. esc[n-1] in turn (a line: the order the frame meets their
 * processing units). Returns the last result. */
int co_esc_chain_process(co_esc *const esc[], size_t n, uint8_t *frame, size_t len,
                         uint64_t now_ns);

/* PDI read of len bytes at addr into buf, with the side effects a PDI read has on the ESC
 * (events cleared, mailbox emptied, buffered SM locked). A refused SM buffer part leaves its
 * bytes of buf untouched. */
int co_esc_pdi_read(co_esc *esc, uint16_t addr, void *buf, size_t len);

/* PDI write of len bytes at addr; read-only bytes for the PDI are skipped (see above). */
int co_esc_pdi_write(co_esc *esc, uint16_t addr, const void *buf, size_t len);

/* The AL event request register 0x0220-0x0223 (reading it clears nothing). */
uint32_t co_esc_al_event(const co_esc *esc);

/* Runs the SM watchdog up to now_ns (0x0440 bit 0 cleared, 0x0442 counted, AL event bit 6 on
 * expiry) and returns when to call again (CO_ESC_TIME_NEVER if the watchdog is not running). */
uint64_t co_esc_tick(co_esc *esc, uint64_t now_ns);

#endif
