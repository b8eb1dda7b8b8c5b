/* libFuzzer target: error control. Heartbeats of monitored and unknown producers (any state byte,
 * any length, boot-ups), node guarding requests, heartbeat producer / consumer / guarding / 0x1029
 * configuration through SDO, bus-off, error passive, receive overruns, EMCY from the application,
 * NMT and time, on the test dictionaries and every drive. */
#include "fuzz_harness.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const fz_target target = {
        "fuzz_errctl",
        FZ_BASE_OPS | FZ_BIT(FZ_OP_SDO_WRITE) | FZ_BIT(FZ_OP_SDO_READ) | FZ_BIT(FZ_OP_HEARTBEAT) |
            FZ_BIT(FZ_OP_GUARD) | FZ_BIT(FZ_OP_APP),
        NULL};
    return fz_run(&target, data, size);
}
