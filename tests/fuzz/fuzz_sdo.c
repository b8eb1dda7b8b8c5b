/* libFuzzer target: the SDO server. Raw request frames and whole expedited, segmented and block
 * transfers in both directions (a client that follows the server's answers, with toggle, sequence,
 * CRC, size and timeout errors), the limit probe, NMT and time, on the test dictionaries and
 * every drive. */
#include "fuzz_harness.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const fz_target target = {
        "fuzz_sdo",
        FZ_BASE_OPS | FZ_BIT(FZ_OP_SDO_WRITE) | FZ_BIT(FZ_OP_SDO_READ) | FZ_BIT(FZ_OP_LIMIT) |
            FZ_BIT(FZ_OP_SEG_WRITE) | FZ_BIT(FZ_OP_BLOCK_WRITE) | FZ_BIT(FZ_OP_UPLOAD),
        NULL};
    return fz_run(&target, data, size);
}
