/* libFuzzer target: PDOs and SYNC. RPDO frames of any length, TPDO remote requests, SYNC with and
 * without counter, remapping through SDO (valid and invalid entries, COB-IDs, transmission types),
 * application requests, NMT and time, on the test dictionaries and every drive. */
#include "fuzz_harness.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const fz_target target = {
        "fuzz_pdo_sync",
        FZ_BASE_OPS | FZ_BIT(FZ_OP_SDO_WRITE) | FZ_BIT(FZ_OP_REMAP) | FZ_BIT(FZ_OP_SYNC) |
            FZ_BIT(FZ_OP_RPDO) | FZ_BIT(FZ_OP_TPDO_RTR) | FZ_BIT(FZ_OP_APP),
        NULL};
    return fz_run(&target, data, size);
}
