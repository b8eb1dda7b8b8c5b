# CMake toolchain file for a bare-metal Cortex-M4 build with Debian's arm-none-eabi-gcc
# (packages gcc-arm-none-eabi, libnewlib-arm-none-eabi):
#   cmake -G Ninja -S boards/cortex-m4 -B build/cm4 \
#         -DCMAKE_TOOLCHAIN_FILE=$PWD/boards/cortex-m4/toolchain.cmake
# The flags are those CANopenNode was measured with (the side-by-side measurement, docs/performance.md): -mcpu=cortex-m4 -mthumb -Os,
# one section per function and object, newlib-nano and nosys stubs, --gc-sections. No FPU flags
# (soft-float ABI, as in that measurement).
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)
set(CMAKE_C_FLAGS_INIT "-mcpu=cortex-m4 -mthumb -ffunction-sections -fdata-sections")
set(CMAKE_C_FLAGS_MINSIZEREL_INIT "-Os")
set(CMAKE_EXE_LINKER_FLAGS_INIT "--specs=nano.specs --specs=nosys.specs -Wl,--gc-sections")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
