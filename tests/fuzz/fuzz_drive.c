/* libFuzzer target: a whole drive (FUZZ_DRIVE_ID, one target per od/<id>/drive.c): its dictionary,
 * CiA 402 state machine, ramps, motor model, trip table and communication-loss reactions, fed
 * every kind of operation - frames of every service, time steps, bus events, injected faults,
 * mains, fault resets - through the public API (drive.h). */
#include "fuzz_harness.h"

#ifndef FUZZ_DRIVE_ID
#error "FUZZ_DRIVE_ID must name a drive of the registry, e.g. -DFUZZ_DRIVE_ID=\"vf-s15\""
#endif
#ifndef FUZZ_TARGET_NAME
#define FUZZ_TARGET_NAME "fuzz_drive"
#endif

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const fz_target target = {FUZZ_TARGET_NAME, FZ_ALL_OPS, FUZZ_DRIVE_ID};
    return fz_run(&target, data, size);
}
