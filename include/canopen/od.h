/* Object dictionary: const descriptor tables (generated from an EDS by tools/eds2c.py) and the
 * typed, checked access every service and the application go through.
 *
 * A node's values live in one caller-owned byte block (co_od.value_size bytes), little-endian as on
 * the wire, laid out by the generator in this order:
 *   [0, comm_persist_size)               persistent values of 0x1000-0x1FFF
 *   [comm_persist_size, persist_size)    persistent values of 0x2000-0xFFFF
 *   [persist_size, value_size)           values that are never stored
 * so one store (0x1010) saves a prefix, reset communication reloads the first part and reset node
 * the whole prefix. Several nodes of one drive share the const tables and own one block each. */
#ifndef CANOPEN_OD_H
#define CANOPEN_OD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "canopen/abort.h"
#include "canopen/config.h"

#ifdef __cplusplus
extern "C" {
#endif

struct co_node;

/* CiA 301 data types (the DataType numbers of an EDS). */
enum co_type {
    CO_BOOLEAN = 0x01, CO_INTEGER8 = 0x02, CO_INTEGER16 = 0x03, CO_INTEGER32 = 0x04,
    CO_UNSIGNED8 = 0x05, CO_UNSIGNED16 = 0x06, CO_UNSIGNED32 = 0x07, CO_REAL32 = 0x08,
    CO_VISIBLE_STRING = 0x09, CO_OCTET_STRING = 0x0A, CO_UNICODE_STRING = 0x0B,
    CO_TIME_OF_DAY = 0x0C, CO_TIME_DIFFERENCE = 0x0D, CO_DOMAIN = 0x0F,
    CO_INTEGER24 = 0x10, CO_REAL64 = 0x11, CO_INTEGER40 = 0x12, CO_INTEGER48 = 0x13,
    CO_INTEGER56 = 0x14, CO_INTEGER64 = 0x15, CO_UNSIGNED24 = 0x16, CO_UNSIGNED40 = 0x18,
    CO_UNSIGNED48 = 0x19, CO_UNSIGNED56 = 0x1A, CO_UNSIGNED64 = 0x1B
};

/* CiA 301 object codes. */
enum co_object_code { CO_OBJ_VAR = 0x07, CO_OBJ_ARRAY = 0x08, CO_OBJ_RECORD = 0x09 };

/* Sub-entry flags (co_od_sub.flags). EDS AccessType ro/wo/rw/rww/rwr/const and PDOMapping map onto
 * the first five; rww is rw + RPDO, rwr is rw + TPDO, a mappable ro is TPDO, a mappable wo is RPDO. */
#define CO_OD_READ     0x01u /* SDO may read */
#define CO_OD_WRITE    0x02u /* SDO may write */
#define CO_OD_TPDO     0x04u /* may be mapped into a TPDO */
#define CO_OD_RPDO     0x08u /* may be mapped into an RPDO */
#define CO_OD_CONST    0x10u /* EDS 'const': never changes */
#define CO_OD_PERSIST  0x20u /* lives in the stored prefix of the value block */
#define CO_OD_NODEID   0x40u /* default is $NODEID + the stored default */
#define CO_OD_LIMITS   0x80u /* co_od_sub.limit indexes co_od.limits */

/* One sub-index; const, so it stays in flash on a microcontroller (the sub-entries are most of a
 * dictionary's tables). Read its size with co_od_sub_size() and its limits' index with
 * co_od_sub_limit(), which work with either layout. Its offset is relative to its entry's
 * value_base, so objects of one shape (the PDO parameters, 0x1010/0x1011, ...) share one run of
 * descriptors: find a value with co_od_value_offset(entry, sub), never with offset alone. */
#if CO_CONFIG_OD_COMPACT
/* 6 bytes (tools/eds2c.py --compact): a numeric value's size is its type's. */
typedef struct co_od_sub {
    uint16_t offset;   /* of the value, from co_od_entry.value_base (0 for DOMAIN) */
    uint8_t aux;       /* CO_OD_LIMITS: index into co_od.limits; strings: capacity; else 0 */
    uint8_t subindex;
    uint8_t type;      /* enum co_type */
    uint8_t flags;     /* CO_OD_* */
} co_od_sub;
#else
/* 8 bytes. */
typedef struct co_od_sub {
    uint16_t offset;   /* of the value, from co_od_entry.value_base (0 for DOMAIN) */
    uint16_t size;     /* bytes: the type's size, a string's capacity, 0 for DOMAIN */
    uint8_t limit;     /* index into co_od.limits when CO_OD_LIMITS is set (at most 256) */
    uint8_t subindex;
    uint8_t type;      /* enum co_type */
    uint8_t flags;     /* CO_OD_* */
} co_od_sub;
#endif

/* One object (index). Its descriptors (co_od_entry_subs()) are sorted by sub-index. Several
 * entries may share their descriptors: the generator lays out the values of objects of one shape
 * alike, one stride apart, and gives each its own value_base. */
#if CO_CONFIG_OD_COMPACT
/* 6 bytes: the generator puts the descriptors and the entries in one object, and an entry finds
 * its descriptors subs_back bytes before itself; each run of descriptors follows a co_od_run that
 * the entries sharing the run share (co_od_entry_sub_count()). No object code is kept (none of
 * the core reads it). */
typedef struct co_od_run {
    uint16_t sub_count; /* number of co_od_sub descriptors (not the value of sub 0) */
} co_od_run;
typedef struct co_od_entry {
    uint16_t index;
    uint16_t value_base; /* where co_od_sub.offset counts from in the value block */
    uint16_t subs_back;  /* bytes from the first descriptor to this entry */
} co_od_entry;
static inline const co_od_sub *co_od_entry_subs(const co_od_entry *entry)
{
    return (const co_od_sub *)(const void *)((const uint8_t *)entry - entry->subs_back);
}
static inline uint32_t co_od_entry_sub_count(const co_od_entry *entry)
{
    return ((const co_od_run *)(const void *)co_od_entry_subs(entry) - 1)->sub_count;
}
#else
/* 12 bytes on a 32-bit target, 16 on a 64-bit one. */
typedef struct co_od_entry {
    uint16_t index;
    uint8_t object_code; /* enum co_object_code (not kept by CO_CONFIG_OD_COMPACT) */
    uint8_t sub_count;   /* number of co_od_sub descriptors (not the value of sub 0): read it
                          * with co_od_entry_sub_count(), which works with either layout */
    uint16_t value_base; /* where co_od_sub.offset counts from in the value block */
    const co_od_sub *subs; /* read it with co_od_entry_subs(), which works with either layout */
} co_od_entry;
static inline const co_od_sub *co_od_entry_subs(const co_od_entry *entry)
{
    return entry->subs;
}
static inline uint32_t co_od_entry_sub_count(const co_od_entry *entry)
{
    return entry->sub_count;
}
#endif

/* Where the value of sub (one of entry's subs) is in the node's value block (below 64 KiB);
 * meaningless for a DOMAIN, which has no value. */
static inline uint32_t co_od_value_offset(const co_od_entry *entry, const co_od_sub *sub)
{
    return (uint32_t)entry->value_base + sub->offset;
}

/* Inclusive limits as raw 64-bit patterns: sign-extended for signed types, zero-extended for
 * unsigned, IEEE 754 double bits for REAL32/REAL64. */
typedef struct co_od_limit {
    uint64_t low;
    uint64_t high;
} co_od_limit;

/* A whole dictionary, as generated from one EDS. */
/* The index pages a node's lookup searches within (co_od.pages): 0x0000-0x0FFF, the
 * communication profile's 0x1000-0x1FFF by 0x100 (what SDO tools read most; 0x1400-0x1BFF are the
 * PDOs'), and 0x2000-0xFFFF by 0x1000. */
#define CO_OD_PAGES 31u

typedef struct co_od {
    const char *name;               /* drive id, e.g. "vf-s15" */
    const co_od_entry *entries;     /* sorted by index */
    const co_od_limit *limits;
    const uint8_t *defaults;        /* default value block (value_size bytes), or NULL: */
    uint16_t entry_count;
    uint16_t limit_count;
    uint32_t value_size;
    uint32_t comm_persist_size;
    uint32_t persist_size;
    uint32_t layout_hash;           /* changes whenever the value layout does: guards stored images */
    /* With defaults NULL, the default value block with its zero bytes counted (tools/eds2c.py
     * --packed-defaults, for microcontrollers): per piece a control byte, the zero bytes before
     * the piece in its high 5 bits and the piece's length (0..7) in its low 3, then the piece's
     * bytes; a control byte of 0 ends the list (the rest of the block is zero). NULL: all zero.
     * Read through co_od_default_copy(). */
    const uint8_t *packed_defaults;
    /* CO_OD_PAGES + 1 entry positions (tools/eds2c.py computes them): pages[p] is the first entry
     * of page p or above, pages[CO_OD_PAGES] is entry_count, so a node's lookup searches only the
     * index's page. NULL: the lookup searches every entry. */
    const uint16_t *pages;
} co_od;

/* A located sub-entry. On a 32-bit target gcc keeps a by-value struct of two pointers in its
 * registers only when it is aligned like a 64-bit integer; otherwise every function taking one
 * (the hooks, the write path) first stores it to its stack. */
#if defined(__GNUC__) && UINTPTR_MAX == 0xFFFFFFFFu
#define CO_OD_REF_ALIGN __attribute__((aligned(8)))
#else
#define CO_OD_REF_ALIGN
#endif
typedef struct co_od_ref {
    const co_od_entry *entry;
    const co_od_sub *sub;
} CO_OD_REF_ALIGN co_od_ref;

/* Who is writing: SDO writes check access rights, NMT-state rules and hooks; RPDO writes check
 * mappability and hooks; the application (the device itself) may write read-only objects and skips
 * hooks, but never a value outside its limits. */
typedef enum co_od_origin { CO_ORIGIN_SDO, CO_ORIGIN_RPDO, CO_ORIGIN_APP } co_od_origin;

/* Object hooks, registered per node for an index range (co_node_add_hook).
 * - refresh: called before a read, to recompute the value in the value block (e.g. a statusword).
 * - write: called after type, length and limit checks with the new value and before it is stored;
 *   return CO_ABORT_NONE to store it, an abort code to refuse (the value stays untouched).
 * - domain_read / domain_write: stream a DOMAIN sub-entry, which has no value in the block.
 *   domain_read copies up to cap bytes from offset into buf, sets *len, and *total to the whole
 *   size. domain_write receives consecutive pieces; total is the announced size or 0 if unknown;
 *   last is true on the final piece.
 * Any of the four may be NULL. */
typedef struct co_od_hook {
    uint16_t index_first;
    uint16_t index_last;
    co_abort (*refresh)(struct co_node *node, void *ctx, co_od_ref ref);
    co_abort (*write)(struct co_node *node, void *ctx, co_od_ref ref, const uint8_t *data,
                      uint32_t len, co_od_origin origin);
    co_abort (*domain_read)(struct co_node *node, void *ctx, co_od_ref ref, uint32_t offset,
                            uint8_t *buf, uint32_t cap, uint32_t *len, uint32_t *total);
    co_abort (*domain_write)(struct co_node *node, void *ctx, co_od_ref ref, uint32_t offset,
                             const uint8_t *data, uint32_t len, uint32_t total, bool last);
    void *ctx;
} co_od_hook;

/* Finds an object by index (binary search). NULL if absent. */
const co_od_entry *co_od_find_entry(const co_od *od, uint16_t index);

/* Finds a sub-entry of an object. NULL if absent. */
const co_od_sub *co_od_find_sub(const co_od_entry *entry, uint8_t subindex);

/* Locates index/subindex. Returns CO_ABORT_NO_OBJECT or CO_ABORT_NO_SUBINDEX if absent. */
co_abort co_od_locate(const co_od *od, uint16_t index, uint8_t subindex, co_od_ref *ref);

/* Bytes a read of this sub-entry returns now: the type's size, a VISIBLE_STRING's length up to its
 * first NUL, 0 for a DOMAIN (ask its hook). */
uint32_t co_od_value_length(const struct co_node *node, co_od_ref ref);

/* Reads a value as origin would: checks read access for SDO, calls the refresh hook, copies up to
 * cap bytes into buf and sets *len. CO_ABORT_OUT_OF_MEMORY if cap is too small. */
co_abort co_od_read(struct co_node *node, uint16_t index, uint8_t subindex, uint8_t *buf,
                    uint32_t cap, uint32_t *len, co_od_origin origin);

/* The same on a located sub-entry. */
co_abort co_od_read_ref(struct co_node *node, co_od_ref ref, uint8_t *buf, uint32_t cap,
                        uint32_t *len, co_od_origin origin);

/* Writes a value: access rights and NMT-state rule (SDO), length against the type, limits, then
 * the write hook; only if all pass is the value stored. Returns the abort code of the first check
 * that fails; on failure the value is untouched. */
co_abort co_od_write(struct co_node *node, uint16_t index, uint8_t subindex, const uint8_t *data,
                     uint32_t len, co_od_origin origin);

/* The same on a located sub-entry. */
co_abort co_od_write_ref(struct co_node *node, co_od_ref ref, const uint8_t *data, uint32_t len,
                         co_od_origin origin);

/* Copies len default bytes at offset of the value block into dst, from defaults or
 * packed_defaults. */
void co_od_default_copy(const co_od *od, uint8_t *dst, uint32_t offset, uint32_t len);

/* Checks data against the sub-entry's type length and its limits in od, without writing: the
 * checks co_od_write_ref makes before any hook runs. */
co_abort co_od_check_value(const co_od *od, co_od_ref ref, const uint8_t *data, uint32_t len);

/* Pointer to the value of a located sub-entry in the node's block (NULL for DOMAIN). For the
 * services' fast paths; writes through it bypass every check, so the application uses
 * co_od_write. */
uint8_t *co_od_value_ptr(const struct co_node *node, co_od_ref ref);

/* Typed application helpers (CO_ORIGIN_APP). get returns 0 if the object is absent; set returns
 * the abort code of the write. */
uint32_t co_od_get_u32(const struct co_node *node, uint16_t index, uint8_t subindex);
uint16_t co_od_get_u16(const struct co_node *node, uint16_t index, uint8_t subindex);
uint8_t co_od_get_u8(const struct co_node *node, uint16_t index, uint8_t subindex);
int32_t co_od_get_i32(const struct co_node *node, uint16_t index, uint8_t subindex);
int16_t co_od_get_i16(const struct co_node *node, uint16_t index, uint8_t subindex);
co_abort co_od_set_u32(struct co_node *node, uint16_t index, uint8_t subindex, uint32_t value);
co_abort co_od_set_u16(struct co_node *node, uint16_t index, uint8_t subindex, uint16_t value);
co_abort co_od_set_u8(struct co_node *node, uint16_t index, uint8_t subindex, uint8_t value);
co_abort co_od_set_i32(struct co_node *node, uint16_t index, uint8_t subindex, int32_t value);
co_abort co_od_set_i16(struct co_node *node, uint16_t index, uint8_t subindex, int16_t value);

/* Size in bytes of a fixed-size basic type, 0 for strings and DOMAIN. */
uint32_t co_type_size(uint8_t type);

/* Bytes of a sub-entry's value (the type's size, a string's capacity, 0 for DOMAIN), and the index
 * of its limits in co_od.limits (when CO_OD_LIMITS is set). */
#if CO_CONFIG_OD_COMPACT
#if defined(__GNUC__)
__attribute__((pure))
#endif
uint32_t co_od_sub_size(const co_od_sub *sub);
static inline uint8_t co_od_sub_limit(const co_od_sub *sub)
{
    return sub->aux;
}
#else
static inline uint32_t co_od_sub_size(const co_od_sub *sub)
{
    return sub->size;
}
static inline uint8_t co_od_sub_limit(const co_od_sub *sub)
{
    return sub->limit;
}
#endif

/* True for the signed integer types (a mask indexed by the type; inline: the limit checks of
 * every write ask it). */
static inline bool co_type_is_signed(uint8_t type)
{
    const uint32_t signed_types = 1u << CO_INTEGER8 | 1u << CO_INTEGER16 | 1u << CO_INTEGER24 |
                                  1u << CO_INTEGER32 | 1u << CO_INTEGER40 | 1u << CO_INTEGER48 |
                                  1u << CO_INTEGER56 | 1u << CO_INTEGER64;
    return type < 32u && ((signed_types >> type) & 1u) != 0u;
}

/* Little-endian codecs used throughout the core (frames and the value block are little-endian):
 * one load or store where the CPU is little-endian, byte by byte elsewhere. */
#if defined(__BYTE_ORDER__) && defined(__ORDER_LITTLE_ENDIAN__) && \
    __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
static inline uint16_t co_get_le16(const uint8_t *p)
{
    uint16_t v;
    memcpy(&v, p, 2u);
    return v;
}
static inline uint32_t co_get_le32(const uint8_t *p)
{
    uint32_t v;
    memcpy(&v, p, 4u);
    return v;
}
static inline void co_put_le16(uint8_t *p, uint16_t v)
{
    memcpy(p, &v, 2u);
}
static inline void co_put_le32(uint8_t *p, uint32_t v)
{
    memcpy(p, &v, 4u);
}
#else
static inline uint16_t co_get_le16(const uint8_t *p) { return (uint16_t)(p[0] | (p[1] << 8)); }
static inline uint32_t co_get_le32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static inline void co_put_le16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}
static inline void co_put_le32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

#endif

#ifdef __cplusplus
}
#endif

#endif
