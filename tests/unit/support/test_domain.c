#include "test_domain.h"

#include <string.h>

#include "unity.h"

uint8_t test_domain_pattern(uint32_t i)
{
    return (uint8_t)(i * 13u + (i >> 8) + 1u);
}

void test_domain_reset(test_domain *d)
{
    memset(d, 0, sizeof *d);
    d->in_order = true;
    d->pattern_ok = true;
    d->dry_from = UINT32_MAX;
}

static co_abort domain_write(co_node *node, void *ctx, co_od_ref ref, uint32_t offset,
                             const uint8_t *data, uint32_t len, uint32_t total, bool last)
{
    test_domain *d = ctx;
    (void)node;
    TEST_ASSERT_EQUAL_HEX16(0x2010, ref.entry->index);
    if (d->write_refusal != CO_ABORT_NONE && offset + len > d->refuse_from) {
        return d->write_refusal;
    }
    if (offset != d->received) {
        d->in_order = false;
    }
    for (uint32_t i = 0; i < len; i++) {
        if (data[i] != test_domain_pattern(offset + i)) {
            d->pattern_ok = false;
        }
        if (offset + i < sizeof d->kept) {
            d->kept[offset + i] = data[i];
        }
    }
    d->received += len;
    d->pieces++;
    d->largest_piece = len > d->largest_piece ? len : d->largest_piece;
    d->total = total;
    d->last_calls += last ? 1u : 0u;
    return CO_ABORT_NONE;
}

static co_abort domain_read(co_node *node, void *ctx, co_od_ref ref, uint32_t offset, uint8_t *buf,
                            uint32_t cap, uint32_t *len, uint32_t *total)
{
    test_domain *d = ctx;
    (void)node;
    (void)ref;
    d->reads++;
    if (d->read_refusal != CO_ABORT_NONE && offset >= d->refuse_read_from) {
        return d->read_refusal;
    }
    uint32_t n = (offset < d->source_size ? d->source_size - offset : 0u) + d->extra;
    n = n < cap ? n : cap;
    if (d->read_piece != 0u && n > d->read_piece) {
        n = d->read_piece;
    }
    if (offset >= d->dry_from) {
        n = 0;
    }
    for (uint32_t i = 0; i < n; i++) {
        buf[i] = test_domain_pattern(offset + i);
    }
    *len = n;
    *total = d->source_size;
    return CO_ABORT_NONE;
}

void test_domain_add_hook(test_node *t, test_domain *d)
{
    const co_od_hook hook = {0x2010, 0x2010, NULL, NULL, domain_read, domain_write, d};
    TEST_ASSERT_TRUE(co_node_add_hook(&t->node, &hook));
}
