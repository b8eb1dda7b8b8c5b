/* libFuzzer target: the NMT slave. NMT commands (for this node, broadcast, other nodes, malformed,
 * local) interleaved with SDO traffic, error control, SYNC and time, on the test dictionaries and
 * every drive. */
#include "fuzz_harness.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const fz_target target = {
        "fuzz_nmt",
        FZ_BASE_OPS | FZ_BIT(FZ_OP_SDO_WRITE) | FZ_BIT(FZ_OP_SDO_READ) | FZ_BIT(FZ_OP_HEARTBEAT) |
            FZ_BIT(FZ_OP_GUARD) | FZ_BIT(FZ_OP_SYNC) | FZ_BIT(FZ_OP_SEG_WRITE),
        NULL};
    return fz_run(&target, data, size);
}
