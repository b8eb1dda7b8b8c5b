# CMake toolchain file for the MPS2-AN386 board under QEMU: the compiler and code-generation flags
# of the Cortex-M4 size build (boards/cortex-m4/toolchain.cmake, included as it is), linked with
# newlib's semihosting library (librdimon, --specs=rdimon.specs) instead of the nosys stubs, so that
# printf reaches the host's stdout and exit(n) ends QEMU with a status.
#   cmake -G Ninja -S boards/mps2-an386 -B build/qemu \
#         -DCMAKE_TOOLCHAIN_FILE=$PWD/boards/mps2-an386/toolchain.cmake
include("${CMAKE_CURRENT_LIST_DIR}/../cortex-m4/toolchain.cmake")
set(CMAKE_EXE_LINKER_FLAGS_INIT "--specs=nano.specs --specs=rdimon.specs -Wl,--gc-sections")
