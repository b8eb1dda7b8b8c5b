# cmake -P script behind the `embedding` tests (tests/embedding/CMakeLists.txt): builds
# examples/minimal out of tree, in a fresh WORK folder, the way a user's project would, and runs
# it (it exits 0 only after the node answered an SDO upload of 0x1018:01 with the right bytes).
#
#   -DMODE=package       cmake --install of the stack's build STACK_BUILD into WORK/prefix, then
#                        the example with find_package(canopen) (CMAKE_PREFIX_PATH=WORK/prefix)
#   -DMODE=subdirectory  the example with add_subdirectory(SOURCE)
#   -DMODE=fetch         the example with FetchContent, its source overridden to SOURCE (a local
#                        path: FETCHCONTENT_SOURCE_DIR_CANOPEN, no network)
#   -DMODE=pkgconfig     cmake --install as for package, then no CMake at all: the installed
#                        eds2c.py generates the dictionary and the compiler gets its flags from
#                        `pkg-config --cflags --libs canopen`
#
# Other inputs: SOURCE (this checkout), WORK, GENERATOR, C_COMPILER, C_FLAGS, LINKER_FLAGS,
# BUILD_TYPE (the stack's build's own, so both halves agree on the configuration macros),
# PYTHON (an interpreter with python-canopen).
cmake_minimum_required(VERSION 3.20)

foreach(var IN ITEMS MODE SOURCE WORK GENERATOR C_COMPILER PYTHON)
  if(NOT DEFINED ${var} OR "${${var}}" STREQUAL "")
    message(FATAL_ERROR "run_example.cmake: -D${var}= is required")
  endif()
endforeach()

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " cmd "${ARGN}")
    message(FATAL_ERROR "${MODE}: failed (${rc}): ${cmd}\n${out}")
  endif()
  set(run_output "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
set(example "${SOURCE}/examples/minimal")
set(build "${WORK}/build")

if(MODE STREQUAL "package" OR MODE STREQUAL "pkgconfig")
  if(NOT STACK_BUILD)
    message(FATAL_ERROR "run_example.cmake: MODE=${MODE} needs -DSTACK_BUILD=<the stack's build>")
  endif()
  run("${CMAKE_COMMAND}" --install "${STACK_BUILD}" --prefix "${WORK}/prefix")
  foreach(f IN ITEMS lib/libcanopen.a lib/libcanopen_drive.a include/canopen/node.h
                     include/canopen/drive.h include/canopen/drive/cia402.h
                     lib/cmake/canopen/canopenConfig.cmake
                     lib/cmake/canopen/canopenConfigVersion.cmake
                     share/canopen/tools/eds2c.py lib/pkgconfig/canopen.pc)
    if(NOT EXISTS "${WORK}/prefix/${f}")
      message(FATAL_ERROR "${MODE}: the install has no ${f}")
    endif()
  endforeach()
endif()

if(MODE STREQUAL "pkgconfig")
  find_program(PKG_CONFIG pkg-config REQUIRED)
  set(ENV{PKG_CONFIG_PATH} "${WORK}/prefix/lib/pkgconfig")
  run("${PKG_CONFIG}" --cflags --libs canopen)
  string(STRIP "${run_output}" flags)
  separate_arguments(flags UNIX_COMMAND "${flags}")
  separate_arguments(c_flags UNIX_COMMAND "${C_FLAGS}")
  separate_arguments(ld_flags UNIX_COMMAND "${LINKER_FLAGS}")
  file(MAKE_DIRECTORY "${build}")
  run("${PYTHON}" "${WORK}/prefix/share/canopen/tools/eds2c.py" "${example}/minimal.eds"
      --id minimal --out-c "${build}/od_minimal.c" --out-h "${build}/od_minimal.h")
  run("${C_COMPILER}" -std=c99 -Wall -Wextra -Wpedantic -Werror ${c_flags} -I "${build}"
      "${example}/main.c" "${build}/od_minimal.c" ${flags} ${ld_flags} -o "${build}/minimal")
else()
  set(args -S "${example}" -B "${build}" -G "${GENERATOR}" "-DCANOPEN_FROM=${MODE}"
      "-DCMAKE_C_COMPILER=${C_COMPILER}" "-DCMAKE_C_FLAGS=${C_FLAGS}"
      "-DCMAKE_EXE_LINKER_FLAGS=${LINKER_FLAGS}" "-DCMAKE_BUILD_TYPE=${BUILD_TYPE}"
      "-DPython3_EXECUTABLE=${PYTHON}")
  if(MODE STREQUAL "package")
    list(APPEND args "-DCMAKE_PREFIX_PATH=${WORK}/prefix")
  elseif(MODE STREQUAL "subdirectory")
    list(APPEND args "-DCANOPEN_SOURCE_DIR=${SOURCE}")
  elseif(MODE STREQUAL "fetch")
    list(APPEND args "-DFETCHCONTENT_SOURCE_DIR_CANOPEN=${SOURCE}")
  else()
    message(FATAL_ERROR "run_example.cmake: unknown MODE ${MODE}")
  endif()
  run("${CMAKE_COMMAND}" ${args})
  # Added to another project, the stack brings the core and the drive runtime only: none of its
  # own dictionaries, drives, simulator or tests.
  if(NOT MODE STREQUAL "package" AND EXISTS "${build}/build.ninja")
    file(READ "${build}/build.ninja" ninja)
    foreach(target IN ITEMS canopen_drive od_minimal)
      if(NOT ninja MATCHES "build ${target}:")
        message(FATAL_ERROR "${MODE}: no target ${target}")
      endif()
    endforeach()
    foreach(target IN ITEMS od_vf_s15 od_test drives canopen_linux canopen-drive unity test_node)
      if(ninja MATCHES "build ${target}:")
        message(FATAL_ERROR "${MODE}: the stack added its own target ${target} to the project")
      endif()
    endforeach()
  endif()
  run("${CMAKE_COMMAND}" --build "${build}" --target minimal -j 2)
endif()

run("${build}/minimal")
message(STATUS "${MODE}: ${run_output}")
if(NOT run_output MATCHES "0x1018:01 Vendor-ID = 0x12345678")
  message(FATAL_ERROR "${MODE}: unexpected output of minimal: ${run_output}")
endif()
