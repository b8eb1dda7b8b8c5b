/* Bad input on every drive (docs/robustness.md, the bad-input table): the rows no other unit test
 * covers for all five drives. Each drive of the registry runs with its own dictionary and drive
 * layer on the fake bus, and gets
 *   - every writable sub-entry with limits, by a real SDO download, one step above its high limit
 *     and one step below its low limit: refused 0x06090031 / 0x06090032, value untouched;
 *   - the same through every RPDO mapping such an object: the whole frame refused, every value
 *     untouched;
 *   - remaps to a non-mappable object, a wrong length, more than 64 bits or more than 8 entries:
 *     0x06040041 / 0x06040042;
 *   - store / restore with a wrong signature or length: refused, nothing stored;
 *   - wrong DLCs, RTR where none is allowed, NMT for other nodes, frames of other nodes: dropped
 *     (and counted), no value changed, nothing sent. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "canopen/drive.h"
#include "canopen/store.h"
#include "drive_fixture.h"

static drive_fx fx;
static fake_store store;
static co_storage storage;

void setUp(void) {}

void tearDown(void) {}

/* fx_start with storage behind 0x1010/0x1011. */
static void start(const co_drive_desc *desc, uint8_t id)
{
    memset(&fx, 0, sizeof fx);
    memset(&store, 0, sizeof store);
    storage = fake_store_storage(&store);
    co_node_config cfg = co_node_default_config();
    cfg.node_id = id;
    cfg.values = fx.values;
    cfg.driver = fake_bus_driver(&fx.bus);
    cfg.storage = &storage;
    TEST_ASSERT_TRUE(desc->od->value_size <= sizeof fx.values);
    TEST_ASSERT_TRUE(co_drive_init(&fx.d, desc, &cfg));
    fx.id = id;
    co_drive_start(&fx.d, 0);
    fx.next = co_drive_process(&fx.d, 0);
    fx_clear(&fx);
}

static const uint8_t *value_of(const co_od_entry *entry, const co_od_sub *sub)
{
    return fx.values + co_od_value_offset(entry, sub);
}

/* The response to the last request (NULL if none came). */
static const co_frame *sdo_response(uint32_t mark)
{
    for (uint32_t i = mark; i < fx.bus.count && i < FAKE_CAPTURE_MAX; i++) {
        if (fx.bus.frames[i].id == 0x580u + fx.id) {
            return &fx.bus.frames[i];
        }
    }
    return NULL;
}

static uint32_t abort_of(const co_frame *f)
{
    TEST_ASSERT_NOT_NULL_MESSAGE(f, "no SDO response");
    return f->data[0] == 0x80u ? co_get_le32(&f->data[4]) : 0u;
}

/* A download of size bytes: expedited up to 4, else segmented. Returns the abort code (0: ok). */
static uint32_t sdo_download(uint16_t index, uint8_t sub, const uint8_t *data, uint32_t size)
{
    uint32_t mark = fx.bus.count;
    if (size <= 4u) {
        uint8_t req[8] = {(uint8_t)(0x23u | ((4u - size) << 2)), (uint8_t)index,
                          (uint8_t)(index >> 8), sub, 0, 0, 0, 0};
        memcpy(&req[4], data, size);
        fx_rx(&fx, (uint16_t)(0x600u + fx.id), 8, req);
        return abort_of(sdo_response(mark));
    }
    uint8_t init[8] = {0x21, (uint8_t)index, (uint8_t)(index >> 8), sub, 0, 0, 0, 0};
    co_put_le32(&init[4], size);
    fx_rx(&fx, (uint16_t)(0x600u + fx.id), 8, init);
    uint32_t rc = abort_of(sdo_response(mark));
    uint8_t toggle = 0;
    for (uint32_t pos = 0; rc == 0u && pos < size; pos += 7u) {
        uint32_t k = size - pos < 7u ? size - pos : 7u;
        bool last = pos + k >= size;
        uint8_t seg[8] = {(uint8_t)((toggle << 4) | ((7u - k) << 1) | (last ? 1u : 0u))};
        memcpy(&seg[1], data + pos, k);
        mark = fx.bus.count;
        fx_rx(&fx, (uint16_t)(0x600u + fx.id), 8, seg);
        rc = abort_of(sdo_response(mark));
        toggle ^= 1u;
    }
    return rc;
}

/* The next representable float / double above (up) or below a finite x (nextafter without
 * libm). */
static float float_step(float x, bool up)
{
    if (x == 0.0f) {
        uint32_t tiny = 1u;
        float t;
        memcpy(&t, &tiny, sizeof t);
        return up ? t : -t;
    }
    uint32_t b;
    memcpy(&b, &x, sizeof b);
    b = ((x > 0.0f) == up) ? b + 1u : b - 1u;
    memcpy(&x, &b, sizeof x);
    return x;
}

static double double_step(double x, bool up)
{
    if (x == 0.0) {
        uint64_t tiny = 1u;
        double t;
        memcpy(&t, &tiny, sizeof t);
        return up ? t : -t;
    }
    uint64_t b;
    memcpy(&b, &x, sizeof b);
    b = ((x > 0.0) == up) ? b + 1u : b - 1u;
    memcpy(&x, &b, sizeof x);
    return x;
}

/* The value one step outside a limit (above the high one when above, else below the low one),
 * little-endian in out. False when the type has no room beyond the limit. */
static bool just_outside(const co_od_sub *sub, const co_od_limit *lim, bool above, uint8_t out[8])
{
    memset(out, 0, 8);
    if (sub->type == CO_REAL32 || sub->type == CO_REAL64) {
        double lo, hi;
        memcpy(&lo, &lim->low, sizeof lo);
        memcpy(&hi, &lim->high, sizeof hi);
        if (sub->type == CO_REAL32) {
            float f = (float)(above ? hi : lo);
            while (!isinf(f) && (above ? (double)f <= hi : (double)f >= lo)) {
                f = float_step(f, above);
            }
            memcpy(out, &f, 4);
            return !isinf(f);
        }
        double d = isinf(above ? hi : lo) ? (above ? hi : lo) : double_step(above ? hi : lo, above);
        memcpy(out, &d, 8);
        return !isinf(d);
    }
    uint32_t bits = 8u * sub->size;
    uint64_t umax = bits >= 64u ? UINT64_MAX : (UINT64_C(1) << bits) - 1u;
    uint64_t v;
    if (co_type_is_signed(sub->type)) {
        int64_t smax = (int64_t)(umax >> 1);
        int64_t smin = -smax - 1;
        if (above ? (int64_t)lim->high >= smax : (int64_t)lim->low <= smin) {
            return false;
        }
        v = above ? lim->high + 1u : lim->low - 1u;
    } else {
        if (above ? lim->high >= umax : lim->low == 0u) {
            return false;
        }
        v = above ? lim->high + 1u : lim->low - 1u;
    }
    for (uint32_t i = 0; i < sub->size && i < 8u; i++) {
        out[i] = (uint8_t)(v >> (8u * i));
    }
    return true;
}

/* An object the drive keeps out of SDO's sight (CO_NODE_SDO_HIDDEN_RANGE): every request on it
 * aborts 0x06020000 first. */
static bool sdo_hidden(uint16_t index)
{
    return (fx.d.node.options & CO_NODE_SDO_HIDDEN_RANGE) != 0u &&
           index >= fx.d.node.sdo.hidden_first && index <= fx.d.node.sdo.hidden_last;
}

static bool numeric(const co_od_sub *sub)
{
    return sub->size >= 1u && sub->size <= 8u && sub->type != CO_DOMAIN &&
           sub->type != CO_VISIBLE_STRING && sub->type != CO_OCTET_STRING &&
           sub->type != CO_UNICODE_STRING;
}

/* --- values outside their limits ------------------------------------------------------------ */

static void test_every_drive_refuses_every_value_just_outside_its_limits_by_sdo(void)
{
    char msg[160];
    for (size_t i = 0; i < co_drive_registry_count(); i++) {
        const co_drive_desc *desc = co_drive_registry_at(i);
        const co_od *od = desc->od;
        start(desc, 5);
        uint32_t probed = 0;
        for (uint32_t e = 0; e < od->entry_count; e++) {
            const co_od_entry *entry = &od->entries[e];
            for (uint32_t s = 0; s < entry->sub_count; s++) {
                const co_od_sub *sub = &entry->subs[s];
                if ((sub->flags & CO_OD_LIMITS) == 0u || (sub->flags & CO_OD_WRITE) == 0u ||
                    !numeric(sub)) {
                    continue;
                }
                for (int above = 0; above < 2; above++) {
                    uint8_t v[8];
                    if (!just_outside(sub, &od->limits[sub->limit], above != 0, v)) {
                        continue;
                    }
                    uint8_t before[8];
                    memcpy(before, value_of(entry, sub), sub->size);
                    uint32_t rc = sdo_download(entry->index, sub->subindex, v, sub->size);
                    snprintf(msg, sizeof msg, "%s 0x%04X sub %u %s its limit", desc->id,
                             entry->index, sub->subindex, above ? "above" : "below");
                    TEST_ASSERT_EQUAL_HEX32_MESSAGE(sdo_hidden(entry->index)
                                                        ? CO_ABORT_NO_OBJECT
                                                        : above ? CO_ABORT_VALUE_TOO_HIGH
                                                                : CO_ABORT_VALUE_TOO_LOW,
                                                    rc, msg);
                    TEST_ASSERT_EQUAL_HEX8_ARRAY_MESSAGE(before, value_of(entry, sub), sub->size,
                                                         msg);
                    probed++;
                }
            }
        }
        snprintf(msg, sizeof msg, "%s: no writable object with limits", desc->id);
        TEST_ASSERT_TRUE_MESSAGE(probed > 0u, msg);
    }
}

static void test_every_drive_refuses_a_limit_violation_in_any_rpdo_whole(void)
{
    char msg[160];
    uint32_t probed = 0;
    for (size_t i = 0; i < co_drive_registry_count(); i++) {
        const co_drive_desc *desc = co_drive_registry_at(i);
        start(desc, 5);
        fx_nmt(&fx, 0x01);
        TEST_ASSERT_EQUAL(CO_NMT_OPERATIONAL, fx.d.node.nmt_state);
        const co_pdo *pdo = &fx.d.node.pdo;
        for (uint32_t r = 0; r < pdo->rpdo_count; r++) {
            const co_rpdo *rp = &pdo->rpdo[r];
            if (!rp->head.active) {
                continue;
            }
            for (uint32_t k = 0; k < rp->head.count; k++) {
                const co_od_sub *sub = rp->map[k].sub;
                if (sub == NULL || (sub->flags & CO_OD_LIMITS) == 0u || !numeric(sub)) {
                    continue;
                }
                for (int above = 0; above < 2; above++) {
                    uint8_t v[8];
                    if (!just_outside(sub, &desc->od->limits[sub->limit], above != 0, v)) {
                        continue;
                    }
                    /* the frame carries every other mapped object's present value */
                    uint8_t frame[8] = {0};
                    uint8_t before[CO_PDO_MAX_MAPPED][8];
                    uint32_t pos = 0;
                    for (uint32_t m = 0; m < rp->head.count; m++) {
                        const co_od_sub *ms = rp->map[m].sub;
                        if (ms != NULL) {
                            memcpy(before[m], value_of(rp->map[m].entry, ms), rp->head.map_len[m]);
                            memcpy(&frame[pos], m == k ? v : value_of(rp->map[m].entry, ms),
                                   rp->head.map_len[m]);
                        }
                        pos += rp->head.map_len[m];
                    }
                    uint32_t refused = pdo->stats.rpdo_refused;
                    fx_rx(&fx, rp->head.cob_id, rp->head.size, frame);
                    if (rp->head.type <= 240u) {
                        fx_rx(&fx, 0x080, 0, NULL); /* a synchronous RPDO is written at SYNC */
                    }
                    snprintf(msg, sizeof msg, "%s RPDO %u: 0x%04X sub %u %s its limit", desc->id,
                             rp->head.number, rp->map[k].entry->index, sub->subindex,
                             above ? "above" : "below");
                    TEST_ASSERT_EQUAL_UINT32_MESSAGE(refused + 1u, pdo->stats.rpdo_refused, msg);
                    for (uint32_t m = 0; m < rp->head.count; m++) {
                        if (rp->map[m].sub != NULL) {
                            const co_od_ref *mr = &rp->map[m];
                            TEST_ASSERT_EQUAL_HEX8_ARRAY_MESSAGE(before[m],
                                                                 value_of(mr->entry, mr->sub),
                                                                 rp->head.map_len[m], msg);
                        }
                    }
                    probed++;
                }
            }
        }
    }
    TEST_ASSERT_TRUE_MESSAGE(probed > 0u, "no RPDO of any drive maps an object with limits");
}

/* --- remaps --------------------------------------------------------------------------------- */

static uint32_t sdo_u32(uint16_t index, uint8_t sub, uint32_t v, uint8_t size)
{
    return fx_sdo_write(&fx, index, sub, v, size);
}

/* A sub-entry of the dictionary that can / cannot go into a PDO of this direction, of a given
 * size (0: any), or NULL. */
static const co_od_sub *find_sub(const co_od *od, uint8_t flag, bool mappable, uint16_t size,
                                 uint16_t *index)
{
    for (uint32_t e = 0; e < od->entry_count; e++) {
        const co_od_entry *entry = &od->entries[e];
        for (uint32_t s = 0; s < entry->sub_count; s++) {
            const co_od_sub *sub = &entry->subs[s];
            if (((sub->flags & flag) != 0u) == mappable && numeric(sub) &&
                (size == 0u || sub->size == size) && entry->index >= 0x1000u) {
                *index = entry->index;
                return sub;
            }
        }
    }
    return NULL;
}

static uint32_t map_entry(uint16_t index, const co_od_sub *sub, uint32_t bits)
{
    return ((uint32_t)index << 16) | ((uint32_t)sub->subindex << 8) | bits;
}

/* What a mapping's sub 0 = n that does not fit gets: 0x06040042, or 0x06090031 when n is above
 * the sub-entry's own HighLimit. */
static uint32_t count_abort(const co_od *od, const co_od_sub *sub0, uint32_t n)
{
    if ((sub0->flags & CO_OD_LIMITS) != 0u && n > od->limits[sub0->limit].high) {
        return CO_ABORT_VALUE_TOO_HIGH;
    }
    return CO_ABORT_PDO_LENGTH;
}

static void test_every_drive_refuses_remaps_to_non_mappable_or_oversized_entries(void)
{
    char msg[160];
    uint32_t remappable = 0;
    for (size_t i = 0; i < co_drive_registry_count(); i++) {
        const co_drive_desc *desc = co_drive_registry_at(i);
        const co_od *od = desc->od;
        start(desc, 5);
        for (uint32_t e = 0; e < od->entry_count; e++) {
            uint16_t comm = od->entries[e].index;
            bool tpdo = comm >= 0x1800u && comm <= 0x19FFu;
            if (!tpdo && !(comm >= 0x1400u && comm <= 0x15FFu)) {
                continue;
            }
            uint16_t map = (uint16_t)(comm + 0x200u);
            co_od_ref m0, c1;
            if (co_od_locate(od, map, 0, &m0) != CO_ABORT_NONE ||
                co_od_locate(od, comm, 1, &c1) != CO_ABORT_NONE) {
                continue;
            }
            snprintf(msg, sizeof msg, "%s 0x%04X", desc->id, map);
            if ((m0.sub->flags & CO_OD_WRITE) == 0u) {
                /* a fixed mapping: the remap itself is refused */
                TEST_ASSERT_EQUAL_HEX32_MESSAGE(CO_ABORT_READ_ONLY, sdo_u32(map, 0, 0, 1), msg);
                continue;
            }
            uint32_t cob = co_od_get_u32(&fx.d.node, comm, 1);
            if ((c1.sub->flags & CO_OD_WRITE) != 0u) {
                TEST_ASSERT_EQUAL_HEX32_MESSAGE(0, sdo_u32(comm, 1, cob | 0x80000000u, 4), msg);
            }
            if (sdo_u32(map, 0, 0, 1) != 0u) {
                continue; /* the drive allows no remap now (its manual's rule) */
            }
            remappable++;
            uint8_t flag = tpdo ? CO_OD_TPDO : CO_OD_RPDO;
            uint16_t index;
            const co_od_sub *bad = find_sub(od, flag, false, 0, &index);
            if (bad != NULL) {
                TEST_ASSERT_EQUAL_HEX32_MESSAGE(CO_ABORT_NOT_MAPPABLE,
                                                sdo_u32(map, 1, map_entry(index, bad,
                                                                          8u * bad->size), 4),
                                                msg);
            }
            const co_od_sub *good = find_sub(od, flag, true, 0, &index);
            if (good == NULL) {
                continue;
            }
            /* the right object with a length that is not its own */
            TEST_ASSERT_EQUAL_HEX32_MESSAGE(
                CO_ABORT_NOT_MAPPABLE,
                sdo_u32(map, 1, map_entry(index, good, 8u * good->size + 8u), 4), msg);
            /* more entries than 8, or than the object has (the EDS's HighLimit of sub 0, where it
             * gives one, answers first) */
            TEST_ASSERT_EQUAL_HEX32_MESSAGE(count_abort(od, m0.sub, 9), sdo_u32(map, 0, 9, 1),
                                            msg);
            /* more than 64 bits: the largest mappable object as often as it takes */
            const co_od_sub *big = find_sub(od, flag, true, 4, &index);
            uint32_t bits = 32u;
            if (big == NULL) {
                big = find_sub(od, flag, true, 2, &index);
                bits = 16u;
            }
            if (big == NULL) {
                continue;
            }
            uint32_t need = 64u / bits + 1u;
            if (need + 1u > m0.entry->sub_count) {
                continue; /* the object has too few entries to go over 64 bits */
            }
            for (uint32_t n = 1; n <= need; n++) {
                TEST_ASSERT_EQUAL_HEX32_MESSAGE(0, sdo_u32(map, (uint8_t)n,
                                                           map_entry(index, big, bits), 4),
                                                msg);
            }
            TEST_ASSERT_EQUAL_HEX32_MESSAGE(count_abort(od, m0.sub, need),
                                            sdo_u32(map, 0, (uint8_t)need, 1), msg);
            TEST_ASSERT_EQUAL_UINT8_MESSAGE(0, fx_u8(&fx, map, 0), msg);
        }
    }
    TEST_ASSERT_TRUE_MESSAGE(remappable > 0u, "no drive lets a PDO be remapped");
}

/* --- store and restore ---------------------------------------------------------------------- */

static void test_every_drive_refuses_wrong_store_and_restore_signatures(void)
{
    static const uint32_t wrong[] = {0x65766174u /* "tave" */, 0x73617665u /* bytes reversed */,
                                     0x00000000u, 0xFFFFFFFFu, CO_STORE_SIGNATURE_LOAD};
    static const uint32_t wrong_load[] = {0x64616F6Du, 0x6C6F6164u, 0u, CO_STORE_SIGNATURE_SAVE};
    char msg[160];
    uint32_t checked = 0;
    for (size_t i = 0; i < co_drive_registry_count(); i++) {
        const co_drive_desc *desc = co_drive_registry_at(i);
        start(desc, 5);
        co_od_ref ref;
        for (uint8_t sub = 1; sub <= 4u; sub++) {
            if (co_od_locate(desc->od, 0x1010, sub, &ref) == CO_ABORT_NONE &&
                (ref.sub->flags & CO_OD_WRITE) != 0u) {
                for (size_t w = 0; w < sizeof wrong / sizeof wrong[0]; w++) {
                    snprintf(msg, sizeof msg, "%s 0x1010 sub %u signature 0x%08lX", desc->id, sub,
                             (unsigned long)wrong[w]);
                    TEST_ASSERT_EQUAL_HEX32_MESSAGE(CO_ABORT_STORE,
                                                    sdo_u32(0x1010, sub, wrong[w], 4), msg);
                }
                snprintf(msg, sizeof msg, "%s 0x1010 sub %u 'sa' in 2 bytes", desc->id, sub);
                TEST_ASSERT_EQUAL_HEX32_MESSAGE(CO_ABORT_TYPE_TOO_SHORT,
                                                sdo_u32(0x1010, sub, 0x6173u, 2), msg);
                checked++;
            }
            if (co_od_locate(desc->od, 0x1011, sub, &ref) == CO_ABORT_NONE &&
                (ref.sub->flags & CO_OD_WRITE) != 0u) {
                for (size_t w = 0; w < sizeof wrong_load / sizeof wrong_load[0]; w++) {
                    snprintf(msg, sizeof msg, "%s 0x1011 sub %u signature 0x%08lX", desc->id, sub,
                             (unsigned long)wrong_load[w]);
                    TEST_ASSERT_EQUAL_HEX32_MESSAGE(CO_ABORT_STORE,
                                                    sdo_u32(0x1011, sub, wrong_load[w], 4), msg);
                }
                checked++;
            }
        }
        snprintf(msg, sizeof msg, "%s: a wrong signature stored something", desc->id);
        TEST_ASSERT_EQUAL_UINT32_MESSAGE(0, store.saves, msg);
        TEST_ASSERT_FALSE_MESSAGE(store.valid, msg);
    }
    TEST_ASSERT_TRUE_MESSAGE(checked > 0u, "no drive has a writable 0x1010 / 0x1011");
}

/* --- frames that are dropped ---------------------------------------------------------------- */

/* Feeds f and expects it dropped: counted as malformed (or ignored), nothing sent, no value
 * changed. */
static void expect_dropped(const co_drive_desc *desc, co_frame f, bool malformed, const char *what)
{
    static uint8_t before[sizeof fx.values];
    char msg[200];
    snprintf(msg, sizeof msg, "%s: %s (0x%03X dlc %u%s)", desc->id, what, f.id, f.dlc,
             (f.flags & CO_FRAME_RTR) != 0u ? " RTR" : "");
    memcpy(before, fx.values, desc->od->value_size);
    co_node_stats st = fx.d.node.stats;
    co_nmt_state state = fx.d.node.nmt_state;
    uint32_t sent = fx.bus.count;
    co_drive_rx(&fx.d, &f, fx.now);
    fx.next = co_drive_process(&fx.d, fx.now);
    TEST_ASSERT_EQUAL_UINT32_MESSAGE(st.rx_malformed + (malformed ? 1u : 0u),
                                     fx.d.node.stats.rx_malformed, msg);
    TEST_ASSERT_EQUAL_UINT32_MESSAGE(st.rx_ignored + (malformed ? 0u : 1u),
                                     fx.d.node.stats.rx_ignored, msg);
    TEST_ASSERT_EQUAL_UINT32_MESSAGE(sent, fx.bus.count, msg);
    TEST_ASSERT_EQUAL_MESSAGE(state, fx.d.node.nmt_state, msg);
    TEST_ASSERT_EQUAL_HEX8_ARRAY_MESSAGE(before, fx.values, desc->od->value_size, msg);
}

static co_frame frame(uint16_t id, uint8_t dlc, bool rtr)
{
    co_frame f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.dlc = dlc;
    f.flags = rtr ? CO_FRAME_RTR : 0u;
    for (uint32_t i = 0; i < 8u && !rtr; i++) {
        f.data[i] = (uint8_t)(0x40u + i); /* an SDO upload request if it were taken */
    }
    return f;
}

static void test_every_drive_drops_wrong_dlcs_and_rtrs_and_changes_nothing(void)
{
    for (size_t i = 0; i < co_drive_registry_count(); i++) {
        const co_drive_desc *desc = co_drive_registry_at(i);
        start(desc, 5);
        fx_nmt(&fx, 0x01);
        fx_clear(&fx);
        uint16_t sdo = (uint16_t)(0x600u + fx.id);
        for (uint8_t dlc = 0; dlc < 8u; dlc++) {
            co_frame f = frame(sdo, dlc, false);
            expect_dropped(desc, f, true, "SDO request shorter than 8 bytes");
        }
        expect_dropped(desc, frame(sdo, 8, true), true, "RTR on the SDO request COB-ID");
        expect_dropped(desc, frame(sdo, 9, false), true, "DLC 9");
        expect_dropped(desc, frame(sdo, 15, false), true, "DLC 15");
        for (uint8_t dlc = 0; dlc <= 8u; dlc++) {
            if (dlc == 2u) {
                continue;
            }
            co_frame f = frame(0x000, dlc, false);
            f.data[0] = CO_NMT_CMD_STOP;
            f.data[1] = fx.id;
            expect_dropped(desc, f, true, "NMT stop of wrong length");
        }
        co_frame nmt = frame(0x000, 2, true);
        expect_dropped(desc, nmt, true, "RTR on the NMT COB-ID");
        co_od_ref sync_ref;
        if (co_od_locate(desc->od, 0x1005, 0, &sync_ref) == CO_ABORT_NONE) {
            uint16_t sync = (uint16_t)(co_od_get_u32(&fx.d.node, 0x1005, 0) & 0x7FFu);
            uint8_t sync_dlc = co_od_get_u8(&fx.d.node, 0x1019, 0) != 0u ? 1u : 0u;
            for (uint8_t dlc = 2; dlc <= 8u; dlc++) {
                expect_dropped(desc, frame(sync, dlc, false), true, "SYNC of wrong length");
            }
            expect_dropped(desc, frame(sync, sync_dlc, true), true, "RTR on the SYNC COB-ID");
        }
        co_frame own_ec = frame((uint16_t)(0x700u + fx.id), 1, false);
        own_ec.data[0] = 0x05;
        expect_dropped(desc, own_ec, true, "a heartbeat on our own error control COB-ID");
        for (uint32_t r = 0; r < fx.d.node.pdo.rpdo_count; r++) {
            const co_rpdo *rp = &fx.d.node.pdo.rpdo[r];
            if (rp->head.active) {
                expect_dropped(desc, frame(rp->head.cob_id, rp->head.size, true), false,
                               "RTR on an RPDO COB-ID");
            }
        }
    }
}

static void test_every_drive_ignores_nmt_and_frames_for_other_nodes(void)
{
    static const uint8_t commands[] = {CO_NMT_CMD_START, CO_NMT_CMD_STOP,
                                       CO_NMT_CMD_ENTER_PRE_OPERATIONAL, CO_NMT_CMD_RESET_NODE,
                                       CO_NMT_CMD_RESET_COMMUNICATION};
    for (size_t i = 0; i < co_drive_registry_count(); i++) {
        const co_drive_desc *desc = co_drive_registry_at(i);
        start(desc, 5);
        for (size_t c = 0; c < sizeof commands; c++) {
            for (uint32_t target = 1; target <= 0xFFu; target++) {
                if (target == fx.id) {
                    continue;
                }
                co_frame f = frame(0x000, 2, false);
                f.data[0] = commands[c];
                f.data[1] = (uint8_t)target;
                expect_dropped(desc, f, false, "NMT command for another node");
            }
        }
        /* every service's COB-ID of node 6 (SDO, PDOs, EMCY, guarding) */
        static const uint16_t bases[] = {0x080, 0x180, 0x200, 0x280, 0x300, 0x380, 0x400,
                                         0x480, 0x500, 0x580, 0x600};
        fx_nmt(&fx, 0x01);
        for (size_t b = 0; b < sizeof bases / sizeof bases[0]; b++) {
            uint16_t id = (uint16_t)(bases[b] + 6u);
            bool own = false;
            for (uint32_t r = 0; r < fx.d.node.pdo.rpdo_count; r++) {
                own = own || (fx.d.node.pdo.rpdo[r].head.active && fx.d.node.pdo.rpdo[r].head.cob_id == id);
            }
            if (!own) {
                expect_dropped(desc, frame(id, 8, false), false, "a frame of node 6");
            }
        }
        expect_dropped(desc, frame(0x706, 0, true), false, "a guarding request for node 6");
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_every_drive_refuses_every_value_just_outside_its_limits_by_sdo);
    RUN_TEST(test_every_drive_refuses_a_limit_violation_in_any_rpdo_whole);
    RUN_TEST(test_every_drive_refuses_remaps_to_non_mappable_or_oversized_entries);
    RUN_TEST(test_every_drive_refuses_wrong_store_and_restore_signatures);
    RUN_TEST(test_every_drive_drops_wrong_dlcs_and_rtrs_and_changes_nothing);
    RUN_TEST(test_every_drive_ignores_nmt_and_frames_for_other_nodes);
    return UNITY_END();
}
