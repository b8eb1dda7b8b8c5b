/* Non-volatile storage (0x1010 store / 0x1011 restore) for the Linux port: one file holds the
 * stored images of every node of the process, each keyed by node-ID and drive id.
 *
 * File layout (little-endian):
 *   header   "CODSTOR1" (8 bytes), u32 format version (1), u32 record count
 *   record   u8 node-ID, 3 bytes 0, char drive[32] (NUL-padded), u32 layout_hash, u32 length,
 *            u32 CRC-32 of the data, then length bytes of data padded with zeros to 4 bytes
 *   trailer  u32 CRC-32 of everything before it
 *
 * Writing is atomic: the whole new file goes to "<file>.tmp", is fsync()ed, renamed over the old
 * one and the directory is fsync()ed, so a crash (or power cut) at any moment leaves either the
 * old or the new file, never a mix. A file that fails any check (magic, version, sizes, CRCs)
 * is reported once on stderr with the reason and every node starts from its EDS defaults; the
 * next store rewrites it. A record whose layout_hash differs from the node's dictionary (the EDS
 * changed) or whose drive differs is ignored with a message, and replaced by the next store.
 *
 * One process per file: each process rewrites the whole file from its own memory, so a second
 * process on the same file would silently replace the first one's acknowledged saves. The store
 * therefore holds an exclusive lock (flock) on the file "<file>.lock" beside it (created if absent,
 * left in place, holding the owner's process ID as text) for as long as it is open, and a second
 * open of the same file fails while the first holds it. The store file itself cannot carry the
 * lock: every save replaces it by a new file. */
#ifndef BOARDS_LINUX_FILE_STORE_H
#define BOARDS_LINUX_FILE_STORE_H

#include <stdbool.h>
#include <stdint.h>

#include "canopen/node.h"

#define FILE_STORE_MAX_RECORDS 127u
#define FILE_STORE_DRIVE_LEN 32u
#define FILE_STORE_MAX_IMAGE (1u << 20) /* larger records mean a corrupt file */
/* The largest file the layout allows: header, FILE_STORE_MAX_RECORDS records of the largest image,
 * trailer. A bigger file is refused rather than read. */
#define FILE_STORE_MAX_FILE \
    (16ul + 4ul + FILE_STORE_MAX_RECORDS * (4ul + FILE_STORE_DRIVE_LEN + 12ul + FILE_STORE_MAX_IMAGE))

typedef struct file_store_record {
    uint8_t node_id;
    char drive[FILE_STORE_DRIVE_LEN];
    uint32_t layout_hash;
    uint32_t length;
    uint8_t *data;                  /* malloc'ed */
} file_store_record;

typedef struct file_store {
    char *path;
    int lock_fd;                    /* holds the flock on "<path>.lock"; -1 when not open */
    file_store_record records[FILE_STORE_MAX_RECORDS];
    uint32_t record_count;
    bool loaded_ok;                 /* the file existed and was valid */
    uint32_t saves;                 /* successful writes of the file */
} file_store;

/* One node's view of the store: the ctx of its co_storage. */
typedef struct file_store_slot {
    file_store *store;
    uint8_t node_id;
    char drive[FILE_STORE_DRIVE_LEN];
    bool warned;                    /* a mismatch message was printed already */
} file_store_slot;

/* Takes the store at path for this process (the lock above) and reads it. A missing file is an
 * empty store; a damaged one is reported and ignored (every node starts from its defaults).
 * Returns false, with the reason on stderr and nothing left open, when the process must not use
 * the store: another process holds it, the lock file cannot be created, path is not a regular
 * file (a directory, a FIFO, a device, ...; never opened, so a FIFO cannot block), the file is
 * larger than FILE_STORE_MAX_FILE, or memory runs out. Messages are prefixed with
 * "canopen-drive: store <path>: ". */
bool file_store_open(file_store *store, const char *path);

/* Frees the records and releases the lock (writes nothing). */
void file_store_close(file_store *store);

/* Fills slot and returns the co_storage the node's config points to (slot must outlive it). */
co_storage file_store_storage(file_store *store, file_store_slot *slot, uint8_t node_id,
                              const char *drive);

/* co_storage callbacks (ctx = file_store_slot). */
bool file_store_load(void *ctx, uint32_t layout_hash, uint32_t offset, uint8_t *buf, uint32_t len);
bool file_store_save(void *ctx, uint32_t layout_hash, const uint8_t *image, uint32_t len);
bool file_store_erase(void *ctx);

/* CRC-32 (IEEE 802.3, reflected 0xEDB88320, init and final XOR 0xFFFFFFFF). */
uint32_t file_store_crc32(uint32_t crc, const uint8_t *data, uint32_t len);

#endif
