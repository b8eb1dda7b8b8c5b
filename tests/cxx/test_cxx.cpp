// A C++17 user of the stack (ctest test_cxx, label unit): every public header of the core and of
// the drive runtime, and a generated dictionary header, compile as C++ under -Wall -Wextra
// -Werror, and their functions link with C linkage (their extern "C" blocks). It runs
// examples/minimal's exchange - an SDO upload of 0x1018:01 answered with the Vendor-ID of
// minimal.eds - and reads the same value through the application API.
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <vector>

#include "canopen/abort.h"
#include "canopen/config.h"
#include "canopen/drive.h"
#include "canopen/drive/cia402.h"
#include "canopen/drive/model.h"
#include "canopen/drive/vl.h"
#include "canopen/emcy.h"
#include "canopen/errctl.h"
#include "canopen/frame.h"
#include "canopen/heartbeat.h"
#include "canopen/nmt.h"
#include "canopen/node.h"
#include "canopen/od.h"
#include "canopen/pdo.h"
#include "canopen/sdo_server.h"
#include "canopen/store.h"
#include "canopen/sync.h"
#include "canopen/time_base.h"
#include "od_minimal.h"

namespace {

constexpr std::uint8_t node_id = 5;

int failures = 0;

void check(bool ok, const char *what)
{
    if (!ok) {
        std::fprintf(stderr, "test_cxx: FAILED: %s\n", what);
        failures++;
    }
}

// The driver, as a C++ object behind the C callback's context pointer.
struct Bus {
    std::vector<co_frame> sent;

    static bool send(void *ctx, const co_frame *frame)
    {
        static_cast<Bus *>(ctx)->sent.push_back(*frame);
        return true;
    }

    const co_frame *find(std::uint16_t id) const
    {
        for (const co_frame &f : sent) {
            if (f.id == id) {
                return &f;
            }
        }
        return nullptr;
    }
};

} // namespace

int main()
{
    Bus bus;
    static co_node node;
    static std::array<std::uint64_t, (CO_OD_MINIMAL_VALUE_SIZE + 7u) / 8u> values{};

    co_node_config cfg = co_node_default_config();
    cfg.od = &co_od_minimal;
    cfg.values = reinterpret_cast<std::uint8_t *>(values.data());
    cfg.node_id = node_id;
    cfg.driver.send = &Bus::send;
    cfg.driver.ctx = &bus;
    check(co_node_init(&node, &cfg), "co_node_init");
    std::uint64_t now = 0;
    co_node_start(&node, now);
    const co_frame *boot = bus.find(0x700u + node_id);
    check(boot != nullptr && boot->dlc == 1u && boot->data[0] == 0u, "boot-up message");

    co_frame request{};
    request.id = 0x600u + node_id;
    request.dlc = 8;
    const std::uint8_t upload[8] = {0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0};
    std::memcpy(request.data, upload, sizeof upload);
    now += 1000;
    co_node_rx(&node, &request, now);
    (void)co_node_process(&node, now);
    const co_frame *response = bus.find(0x580u + node_id);
    const std::uint8_t expected[8] = {0x43, 0x18, 0x10, 0x01, 0x78, 0x56, 0x34, 0x12};
    check(response != nullptr && response->dlc == 8u &&
              std::memcmp(response->data, expected, sizeof expected) == 0,
          "SDO upload of 0x1018:01");

    // The application side of the same dictionary: a read through the core's API.
    std::uint8_t vendor[4] = {};
    std::uint32_t len = 0;
    co_abort abort = co_od_read(&node, 0x1018, 1, vendor, sizeof vendor, &len, CO_ORIGIN_APP);
    check(abort == CO_ABORT_NONE && len == 4u && vendor[0] == 0x78u && vendor[3] == 0x12u,
          "co_od_read of 0x1018:01");

    // The drive runtime's pure helpers link too.
    check(co_cia402_state_of(0x0040u) == CO_CIA402_SWITCH_ON_DISABLED, "co_cia402_state_of");
    check(std::strlen(co_cia402_state_name(CO_CIA402_FAULT)) > 0u, "co_cia402_state_name");

    if (failures == 0) {
        std::printf("test_cxx: OK\n");
    }
    return failures == 0 ? 0 : 1;
}
