/* Non-volatile storage of the blank port (port.h): the co_storage behind 0x1010 "save" and 0x1011
 * "load". Two flash sectors hold one image each; the newest valid one is the stored image.
 *
 * What the core asks (include/canopen/node.h, co_storage):
 * - load: copy a part of the stored image, or return false WITHOUT writing when no valid image
 *   of this dictionary layout (layout_hash) is stored: the node then keeps its defaults.
 * - save: replace the image atomically; on failure the old image must survive.
 * - erase: forget the image, so the next reset starts from the defaults.
 * A save goes to the sector that does not hold the newest image: erased, the image written, the
 * header (with a sequence number one above the other's and a CRC over header and image) written
 * last. A reset or power cut during the save leaves that sector without a valid header, so the
 * other sector's image - the old one - stays the newest. The core calls these from the CANopen
 * loop (co_node_start, an NMT reset, an SDO write of 0x1010/0x1011), which they block while the
 * flash works: the CAN receive queue (can.c) must hold what arrives meanwhile. */
#include <stddef.h>
#include <string.h>

#include "port.h"

/* TODO: the sectors' size (the largest od->persist_size plus the header, rounded up to the
 * flash's sector size) and their programming unit (bytes written at once, at aligned
 * addresses). */
#define SECTOR_SIZE 2048u
#define PROGRAM_UNIT 8u
#define SECTOR_MAGIC 0x434F5331u /* "COS1" */

typedef struct sector_header {
    uint32_t magic;
    uint32_t sequence;    /* the newer of two valid sectors has the larger one (mod 2^32) */
    uint32_t layout_hash; /* the dictionary's (co_od.layout_hash) */
    uint32_t length;      /* bytes of image after the header */
    uint32_t crc;         /* CRC-32 of the image, then of the header's fields above */
    uint32_t reserved;    /* 0 (a multiple of PROGRAM_UNIT) */
} sector_header;

/* --- the flash (TODO: your part's) ------------------------------------------------------------ */

/* The stand-in: two sectors of RAM (zero at start-up: no valid image), and the number of erases
 * and program units it still carries out before it fails like a power cut (the host test of this
 * file, tests/template, cuts a save at every step; UINT32_MAX: never). */
static uint8_t fake_flash[2][SECTOR_SIZE];
static uint32_t fake_flash_budget = UINT32_MAX;

static bool fake_flash_step(void)
{
    if (fake_flash_budget == 0u) {
        return false;
    }
    if (fake_flash_budget != UINT32_MAX) {
        fake_flash_budget--;
    }
    return true;
}

/* TODO: the address of sector s (0 or 1) in the memory map, where the processor reads it. */
static const uint8_t *flash_sector(uint32_t s)
{
    return fake_flash[s];
}

/* TODO: unlock the flash, erase sector s, wait, lock; false on an error. */
static bool flash_erase_sector(uint32_t s)
{
    if (!fake_flash_step()) {
        return false;
    }
    memset(fake_flash[s], 0xFF, SECTOR_SIZE);
    return true;
}

/* TODO: program PROGRAM_UNIT bytes at offset (a multiple of PROGRAM_UNIT) of sector s; false on
 * an error. */
static bool flash_program_unit(uint32_t s, uint32_t offset, const uint8_t *unit)
{
    if (!fake_flash_step()) {
        return false;
    }
    memcpy(&fake_flash[s][offset], unit, PROGRAM_UNIT);
    return true;
}

/* --- the two sectors -------------------------------------------------------------------------- */

/* CRC-32 (IEEE 802.3, reflected 0xEDB88320), bitwise: small; a save is rare. */
static uint32_t crc32_update(uint32_t crc, const uint8_t *data, uint32_t len)
{
    crc = ~crc;
    for (uint32_t i = 0; i < len; i++) {
        crc ^= data[i];
        for (unsigned b = 0; b < 8u; b++) {
            crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
        }
    }
    return ~crc;
}

static uint32_t header_crc(const sector_header *h, const uint8_t *image)
{
    uint32_t crc = crc32_update(0, image, h->length);
    return crc32_update(crc, (const uint8_t *)h, (uint32_t)offsetof(sector_header, crc));
}

/* Sector s's header if it holds a complete image, else false. */
static bool sector_valid(uint32_t s, sector_header *h)
{
    const uint8_t *sector = flash_sector(s);
    memcpy(h, sector, sizeof *h);
    return h->magic == SECTOR_MAGIC && h->length <= SECTOR_SIZE - sizeof *h &&
           h->crc == header_crc(h, sector + sizeof *h);
}

/* The sector holding the newest valid image (0 or 1), or -1 when neither is valid. */
static int newest_sector(sector_header *h)
{
    sector_header h0, h1;
    bool v0 = sector_valid(0, &h0), v1 = sector_valid(1, &h1);
    if (v0 && (!v1 || (int32_t)(h0.sequence - h1.sequence) > 0)) {
        *h = h0;
        return 0;
    }
    if (v1) {
        *h = h1;
        return 1;
    }
    return -1;
}

/* Programs len bytes at offset of sector s, the last unit padded with 0xFF. */
static bool program(uint32_t s, uint32_t offset, const uint8_t *data, uint32_t len)
{
    uint8_t unit[PROGRAM_UNIT];
    for (uint32_t done = 0; done < len; done += PROGRAM_UNIT) {
        uint32_t n = len - done < PROGRAM_UNIT ? len - done : PROGRAM_UNIT;
        memset(unit, 0xFF, sizeof unit);
        memcpy(unit, data + done, n);
        if (!flash_program_unit(s, offset + done, unit)) {
            return false;
        }
    }
    return true;
}

static bool storage_load(void *ctx, uint32_t layout_hash, uint32_t offset, uint8_t *buf,
                         uint32_t len)
{
    (void)ctx;
    sector_header h;
    int s = newest_sector(&h);
    /* an image of another dictionary layout (the EDS changed) is not this node's: defaults */
    if (s < 0 || h.layout_hash != layout_hash || offset > h.length || len > h.length - offset) {
        return false;
    }
    memcpy(buf, flash_sector((uint32_t)s) + sizeof h + offset, len);
    return true;
}

static bool storage_save(void *ctx, uint32_t layout_hash, const uint8_t *image, uint32_t len)
{
    (void)ctx;
    if (len > SECTOR_SIZE - sizeof(sector_header)) {
        return false; /* the core answers the SDO write with abort 0x08000020 */
    }
    sector_header newest;
    int s = newest_sector(&newest);
    uint32_t target = s == 0 ? 1u : 0u;
    sector_header h = {SECTOR_MAGIC, s < 0 ? 1u : newest.sequence + 1u, layout_hash, len, 0, 0};
    h.crc = header_crc(&h, image);
    /* the image first, the header last: until the header is complete the sector is invalid */
    return flash_erase_sector(target) && program(target, sizeof h, image, len) &&
           program(target, 0, (const uint8_t *)&h, sizeof h);
}

static bool storage_erase(void *ctx)
{
    (void)ctx;
    /* The older sector first: a power cut between the two erases leaves the newest image, as if
     * the erase had not begun, never the older one. */
    sector_header h;
    int s = newest_sector(&h);
    uint32_t newest = s < 0 ? 0u : (uint32_t)s;
    return flash_erase_sector(newest ^ 1u) && flash_erase_sector(newest);
}

const co_storage port_storage = {storage_load, storage_save, storage_erase, NULL};
