# cmake -P script behind ctest embedding_template (tests/embedding/CMakeLists.txt): configures and
# builds boards/template, the blank port, out of tree in a fresh WORK folder, as a user who copied
# it would (add_subdirectory of SOURCE, its canopen_config.h as CANOPEN_CONFIG_HEADER), so the
# template keeps compiling with -Werror. It talks to no hardware: built, not run. Then checks that
# the port's switch header reached the core's compile lines, not the port's alone.
#
# Inputs: SOURCE (this checkout), WORK, GENERATOR, C_COMPILER, C_FLAGS, LINKER_FLAGS, BUILD_TYPE,
# PYTHON (an interpreter with python-canopen, for canopen_add_od).
cmake_minimum_required(VERSION 3.20)

foreach(var IN ITEMS SOURCE WORK GENERATOR C_COMPILER PYTHON)
  if(NOT DEFINED ${var} OR "${${var}}" STREQUAL "")
    message(FATAL_ERROR "build_template.cmake: -D${var}= is required")
  endif()
endforeach()

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " cmd "${ARGN}")
    message(FATAL_ERROR "template: failed (${rc}): ${cmd}\n${out}")
  endif()
endfunction()

file(REMOVE_RECURSE "${WORK}")
set(build "${WORK}/build")
run("${CMAKE_COMMAND}" -S "${SOURCE}/boards/template" -B "${build}" -G "${GENERATOR}"
    "-DCANOPEN_SOURCE_DIR=${SOURCE}" "-DCMAKE_C_COMPILER=${C_COMPILER}" "-DCMAKE_C_FLAGS=${C_FLAGS}"
    "-DCMAKE_EXE_LINKER_FLAGS=${LINKER_FLAGS}" "-DCMAKE_BUILD_TYPE=${BUILD_TYPE}"
    "-DPython3_EXECUTABLE=${PYTHON}")
run("${CMAKE_COMMAND}" --build "${build}" --target template -j 2)
if(NOT EXISTS "${build}/build.ninja")
  return() # another generator: built, the compile lines not checked
endif()
file(STRINGS "${build}/build.ninja" lines REGEX "CO_CONFIG_USER_HEADER=.*canopen_config\\.h")
list(LENGTH lines n)
# the core's sources (src/*.c) and the port's four files each compile with it
file(GLOB core_sources "${SOURCE}/src/*.c")
list(LENGTH core_sources core_n)
math(EXPR want "${core_n} + 4")
if(n LESS want)
  message(FATAL_ERROR "template: ${n} compile lines carry the port's switch header, expected at "
                      "least ${want} (the core's ${core_n} and the port's 4)")
endif()
message(STATUS "template: built; ${n} compile lines with the port's canopen_config.h")
