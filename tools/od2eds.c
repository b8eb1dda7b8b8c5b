/* od2eds.c - prints the generated const tables of one object dictionary back as a CiA 306 EDS.
 *
 * Built against one generated table (tools/eds2c.py output), e.g.
 *     cc -std=c99 -Iinclude -Ibuild/od -DCO_OD_SYMBOL=co_od_vf_s15 \
 *        tools/od2eds.c build/od/od_vf_s15.c -o od2eds_vf_s15
 *     ./od2eds_vf_s15 > exported.eds
 * It reads only what the firmware has (co_od: entries, subs, limits, default image) plus the
 * optional name tables; so loading the original EDS and this output with python-canopen and
 * comparing them object by object checks the generator end to end (tests/generator). Each
 * sub-entry section also carries a `; layout:` comment with its offset, size and flags, and the
 * file starts with `; od:` comments giving the co_od sizes, for the tests of the layout.
 * Define CO_OD_NO_NAMES when the table was built without names: the EDS then gets made-up names.
 * No dependency on the core (src/): only the types of include/canopen/od.h. */
#include <inttypes.h>
#include <stdio.h>
#include <string.h>

#include "canopen/od.h"

#ifndef CO_OD_SYMBOL
#error "define CO_OD_SYMBOL, e.g. -DCO_OD_SYMBOL=co_od_vf_s15"
#endif

#define OD2EDS_CAT2(a, b) a##b
#define OD2EDS_CAT(a, b) OD2EDS_CAT2(a, b)

extern const co_od CO_OD_SYMBOL;
#if !defined(CO_OD_NO_NAMES)
extern const char *const OD2EDS_CAT(CO_OD_SYMBOL, _entry_names)[];
extern const char *const OD2EDS_CAT(CO_OD_SYMBOL, _sub_names)[];
#endif

static const co_od *const od = &CO_OD_SYMBOL;

static int is_signed(uint8_t t)
{
    return t == CO_INTEGER8 || t == CO_INTEGER16 || t == CO_INTEGER24 || t == CO_INTEGER32 ||
           t == CO_INTEGER40 || t == CO_INTEGER48 || t == CO_INTEGER56 || t == CO_INTEGER64;
}

static int is_real(uint8_t t) { return t == CO_REAL32 || t == CO_REAL64; }

static int is_string(uint8_t t)
{
    return t == CO_VISIBLE_STRING || t == CO_OCTET_STRING || t == CO_UNICODE_STRING ||
           t == CO_DOMAIN;
}

static uint64_t get_le(const uint8_t *p, uint16_t size)
{
    uint64_t v = 0;
    for (uint16_t i = size; i > 0u; i--) {
        v = (v << 8) | p[i - 1u];
    }
    return v;
}

static int64_t sign_extend(uint64_t v, unsigned bits)
{
    if (bits < 64u && (v & ((uint64_t)1 << (bits - 1u))) != 0u) {
        v |= ~(((uint64_t)1 << bits) - 1u);
    }
    return (int64_t)v;
}

static double bits_to_double(uint64_t v)
{
    double d;
    memcpy(&d, &v, sizeof d);
    return d;
}

static float bits_to_float(uint32_t v)
{
    float f;
    memcpy(&f, &v, sizeof f);
    return f;
}

static const char *access_of(uint8_t flags)
{
    if ((flags & CO_OD_CONST) != 0u) {
        return "const";
    }
    if ((flags & CO_OD_READ) != 0u && (flags & CO_OD_WRITE) != 0u) {
        uint8_t pdo = flags & (CO_OD_TPDO | CO_OD_RPDO);
        return pdo == CO_OD_RPDO ? "rww" : pdo == CO_OD_TPDO ? "rwr" : "rw";
    }
    return (flags & CO_OD_WRITE) != 0u ? "wo" : "ro";
}

static void print_flags(uint8_t f)
{
    static const struct {
        uint8_t bit;
        const char *name;
    } names[] = {{CO_OD_READ, "READ"},    {CO_OD_WRITE, "WRITE"},     {CO_OD_TPDO, "TPDO"},
                 {CO_OD_RPDO, "RPDO"},    {CO_OD_CONST, "CONST"},     {CO_OD_PERSIST, "PERSIST"},
                 {CO_OD_NODEID, "NODEID"}, {CO_OD_LIMITS, "LIMITS"}};
    const char *sep = "";
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        if ((f & names[i].bit) != 0u) {
            printf("%s%s", sep, names[i].name);
            sep = "|";
        }
    }
}

/* A real number that reads back exactly and always looks like one (1.0, not 1). */
static void print_real(double d, int digits)
{
    char buf[64];
    snprintf(buf, sizeof buf, "%.*g", digits, d);
    printf("%s%s", buf, strpbrk(buf, ".eEni") == NULL ? ".0" : "");
}

/* A numeric bound or default as python-canopen reads it back. */
static void print_number(uint8_t type, uint16_t size, uint64_t raw, int as_limit)
{
    if (type == CO_REAL32 && !as_limit) {
        print_real((double)bits_to_float((uint32_t)raw), 9);
    } else if (is_real(type)) {
        print_real(bits_to_double(raw), 17); /* REAL64 value, or any REAL limit */
    } else if (is_signed(type)) {
        printf("%" PRId64, as_limit ? (int64_t)raw : sign_extend(raw, (unsigned)size * 8u));
    } else {
        printf("0x%" PRIX64, raw);
    }
}

/* The default value block, unpacked when the dictionary was generated with --packed-defaults
 * (this tool is built without the core, so it reads co_od.packed_defaults itself). */
static const uint8_t *default_block(void)
{
    static uint8_t block[65536]; /* a value block is below 64 KiB */
    static bool unpacked;
    if (od->defaults != NULL) {
        return od->defaults;
    }
    if (!unpacked && od->packed_defaults != NULL) {
        const uint8_t *p = od->packed_defaults;
        uint32_t at = 0;
        while (p[0] != 0u) { /* (zeros << 3 | count), then count bytes (od.h) */
            at += p[0] >> 3;
            memcpy(block + at, p + 1, p[0] & 7u);
            at += p[0] & 7u;
            p += 1u + (p[0] & 7u);
        }
    }
    unpacked = true;
    return block;
}

static void print_default(const co_od_entry *e, const co_od_sub *s)
{
    if (s->type == CO_DOMAIN) {
        return;
    }
    const uint8_t *p = default_block() + co_od_value_offset(e, s);
    printf("DefaultValue=");
    if (s->type == CO_VISIBLE_STRING) {
        for (uint16_t i = 0; i < s->size && p[i] != 0u; i++) {
            putchar(p[i]);
        }
    } else if (s->type == CO_UNICODE_STRING) {
        for (uint16_t i = 0; i + 1u < s->size; i = (uint16_t)(i + 2u)) {
            unsigned c = (unsigned)p[i] | ((unsigned)p[i + 1u] << 8);
            if (c == 0u) {
                break;
            }
            putchar(c < 0x80u ? (int)c : '?');
        }
    } else if (s->type == CO_OCTET_STRING) {
        for (uint16_t i = 0; i < s->size; i++) {
            printf("%02X", p[i]);
        }
    } else if ((s->flags & CO_OD_NODEID) != 0u) {
        printf("$NODEID+0x%" PRIX64, get_le(p, s->size));
    } else {
        print_number(s->type, s->size, get_le(p, s->size), 0);
    }
    putchar('\n');
}

static void print_sub(const co_od_entry *e, const co_od_sub *s, size_t flat, int nested)
{
    if (nested) {
        printf("[%04Xsub%X]\n", e->index, s->subindex);
    } else {
        printf("[%04X]\n", e->index);
    }
    uint32_t at = s->size != 0u ? co_od_value_offset(e, s) : 0u; /* a DOMAIN has no value */
    printf("; layout: offset=%" PRIu32 " size=%u flags=", at, (unsigned)s->size);
    print_flags(s->flags);
    printf(" limit=%u\n", (unsigned)s->limit);
#if !defined(CO_OD_NO_NAMES)
    printf("ParameterName=%s\n", OD2EDS_CAT(CO_OD_SYMBOL, _sub_names)[flat]);
#else
    (void)flat;
    printf("ParameterName=Object %04Xh sub %u\n", e->index, (unsigned)s->subindex);
#endif
    printf("ObjectType=0x7\n");
    printf("DataType=0x%04X\n", s->type);
    printf("AccessType=%s\n", access_of(s->flags));
    print_default(e, s);
    printf("PDOMapping=%d\n", (s->flags & (CO_OD_TPDO | CO_OD_RPDO)) != 0u ? 1 : 0);
    if ((s->flags & CO_OD_LIMITS) != 0u && !is_string(s->type)) {
        const co_od_limit *l = &od->limits[s->limit];
        printf("LowLimit=");
        print_number(s->type, s->size, l->low, 1);
        printf("\nHighLimit=");
        print_number(s->type, s->size, l->high, 1);
        putchar('\n');
    }
    putchar('\n');
}

static void print_list(const char *name, int which)
{
    unsigned n = 0;
    for (uint16_t i = 0; i < od->entry_count; i++) {
        uint16_t x = od->entries[i].index;
        int kind = (x == 0x1000u || x == 0x1001u || x == 0x1018u) ? 0
                   : (x >= 0x2000u && x <= 0x5FFFu)              ? 2
                                                                  : 1;
        n += kind == which ? 1u : 0u;
    }
    printf("[%s]\nSupportedObjects=%u\n", name, n);
    n = 0;
    for (uint16_t i = 0; i < od->entry_count; i++) {
        uint16_t x = od->entries[i].index;
        int kind = (x == 0x1000u || x == 0x1001u || x == 0x1018u) ? 0
                   : (x >= 0x2000u && x <= 0x5FFFu)              ? 2
                                                                  : 1;
        if (kind == which) {
            printf("%u=0x%04X\n", ++n, x);
        }
    }
    putchar('\n');
}

static unsigned count_range(uint16_t lo, uint16_t hi)
{
    unsigned n = 0;
    for (uint16_t i = 0; i < od->entry_count; i++) {
        n += (od->entries[i].index >= lo && od->entries[i].index <= hi) ? 1u : 0u;
    }
    return n;
}

int main(void)
{
    printf("; Exported by tools/od2eds.c from the generated tables of \"%s\".\n", od->name);
    printf("; od: entry_count=%u limit_count=%u value_size=%" PRIu32 " comm_persist_size=%" PRIu32
           " persist_size=%" PRIu32 " layout_hash=0x%08" PRIX32 "\n",
           (unsigned)od->entry_count, (unsigned)od->limit_count, od->value_size,
           od->comm_persist_size, od->persist_size, od->layout_hash);
    printf("\n[FileInfo]\nFileName=%s.eds\nFileVersion=1\nFileRevision=0\nEDSVersion=4.0\n"
           "Description=exported from generated tables\n\n", od->name);
    printf("[DeviceInfo]\nVendorName=%s\nProductName=%s\n", od->name, od->name);
    printf("BaudRate_10=1\nBaudRate_20=1\nBaudRate_50=1\nBaudRate_125=1\nBaudRate_250=1\n"
           "BaudRate_500=1\nBaudRate_800=1\nBaudRate_1000=1\n");
    printf("SimpleBootUpMaster=0\nSimpleBootUpSlave=1\nGranularity=8\n");
    printf("NrOfRXPDO=%u\nNrOfTXPDO=%u\nLSS_Supported=0\n\n", count_range(0x1400u, 0x15FFu),
           count_range(0x1800u, 0x19FFu));
    printf("[DummyUsage]\n");
    for (unsigned i = 1; i <= 7u; i++) {
        printf("Dummy%04u=0\n", i);
    }
    putchar('\n');
    print_list("MandatoryObjects", 0);
    print_list("OptionalObjects", 1);
    print_list("ManufacturerObjects", 2);

    size_t flat = 0;
    for (uint16_t i = 0; i < od->entry_count; i++) {
        const co_od_entry *e = &od->entries[i];
        /* the name table counts every entry's sub-entries in table order (entries of one shape
         * share their descriptors, so their positions in the descriptor table do not) */
        if (i != 0u) {
            flat += od->entries[i - 1u].sub_count;
        }
        if (e->object_code == CO_OBJ_VAR) {
            print_sub(e, &e->subs[0], flat, 0);
            continue;
        }
        printf("[%04X]\n", e->index);
#if !defined(CO_OD_NO_NAMES)
        printf("ParameterName=%s\n", OD2EDS_CAT(CO_OD_SYMBOL, _entry_names)[i]);
#else
        printf("ParameterName=Object %04Xh\n", e->index);
#endif
        printf("ObjectType=0x%X\nSubNumber=%u\n\n", e->object_code, (unsigned)e->sub_count);
        for (uint8_t k = 0; k < e->sub_count; k++) {
            print_sub(e, &e->subs[k], flat + k, 1);
        }
    }
    return 0;
}
