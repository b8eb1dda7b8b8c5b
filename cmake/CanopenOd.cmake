# Object dictionaries generated from EDS files at build time (tools/eds2c.py).
#
#   include(cmake/CanopenOd.cmake)
#   canopen_add_od(<id> <eds-path> [EXPORTER])
#
# generates ${CMAKE_BINARY_DIR}/od/od_<id_>.c and od_<id_>.h (id_ = id with '-' replaced by '_')
# whenever the EDS or the generator changes, and creates the static library target od_<id_>
# (linked against the core target `canopen`, include dir ${CMAKE_BINARY_DIR}/od), which defines
# `const co_od co_od_<id_>`; its header declares it and CO_OD_<ID_>_VALUE_SIZE.
# EXPORTER also builds od2eds_<id_> (tools/od2eds.c), which prints the generated tables back as an
# EDS on stdout.
# CANOPEN_OD_NAMES (ON by default): OFF builds the tables without the name strings
# (CO_OD_NO_NAMES), which only tools and diagnostics use.
include_guard(GLOBAL)

find_package(Python3 COMPONENTS Interpreter REQUIRED)

get_filename_component(CANOPEN_OD_ROOT "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
set(CANOPEN_OD_GENERATOR "${CANOPEN_OD_ROOT}/tools/eds2c.py")
set(CANOPEN_OD_EXPORTER_SOURCE "${CANOPEN_OD_ROOT}/tools/od2eds.c")
set(CANOPEN_OD_OUTPUT_DIR "${CMAKE_BINARY_DIR}/od")
option(CANOPEN_OD_NAMES "Keep the object/sub-index name tables in generated dictionaries" ON)

# The generator reads the EDS with python-canopen (what masters use): fail at configure time, with
# a clear message, rather than on the first build.
execute_process(
  COMMAND "${Python3_EXECUTABLE}" -c "import canopen"
  RESULT_VARIABLE _canopen_od_python_rc
  OUTPUT_QUIET ERROR_QUIET)
if(NOT _canopen_od_python_rc EQUAL 0)
  message(FATAL_ERROR
    "CanopenOd: ${Python3_EXECUTABLE} cannot import python-canopen, which tools/eds2c.py needs "
    "(pip install canopen, or pass -DPython3_EXECUTABLE=<a python that has it>).")
endif()
file(MAKE_DIRECTORY "${CANOPEN_OD_OUTPUT_DIR}")

function(canopen_add_od id eds)
  cmake_parse_arguments(ARG "EXPORTER" "" "" ${ARGN})
  if(ARG_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "canopen_add_od(${id}): unexpected arguments ${ARG_UNPARSED_ARGUMENTS}")
  endif()
  if(NOT id MATCHES "^[A-Za-z][A-Za-z0-9_-]*$")
    message(FATAL_ERROR "canopen_add_od: bad id '${id}' (letters, digits, '-', '_')")
  endif()
  string(REPLACE "-" "_" uid "${id}")
  get_filename_component(eds_abs "${eds}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
  if(NOT EXISTS "${eds_abs}")
    message(FATAL_ERROR "canopen_add_od(${id}): ${eds_abs} does not exist")
  endif()
  set(out_c "${CANOPEN_OD_OUTPUT_DIR}/od_${uid}.c")
  set(out_h "${CANOPEN_OD_OUTPUT_DIR}/od_${uid}.h")

  add_custom_command(
    OUTPUT "${out_c}" "${out_h}"
    COMMAND "${Python3_EXECUTABLE}" "${CANOPEN_OD_GENERATOR}" "${eds_abs}" --id "${id}"
            --out-c "${out_c}" --out-h "${out_h}"
    DEPENDS "${eds_abs}" "${CANOPEN_OD_GENERATOR}"
    COMMENT "Generating object dictionary ${id} from ${eds}"
    VERBATIM)

  add_library(od_${uid} STATIC "${out_c}" "${out_h}")
  target_include_directories(od_${uid} PUBLIC "${CANOPEN_OD_OUTPUT_DIR}")
  target_link_libraries(od_${uid} PUBLIC canopen)
  if(NOT CANOPEN_OD_NAMES)
    target_compile_definitions(od_${uid} PUBLIC CO_OD_NO_NAMES)
  endif()
  if(DEFINED CANOPEN_WARNINGS)
    target_compile_options(od_${uid} PRIVATE ${CANOPEN_WARNINGS})
  endif()

  if(ARG_EXPORTER)
    add_executable(od2eds_${uid} "${CANOPEN_OD_EXPORTER_SOURCE}")
    target_link_libraries(od2eds_${uid} PRIVATE od_${uid})
    target_compile_definitions(od2eds_${uid} PRIVATE CO_OD_SYMBOL=co_od_${uid})
  endif()
endfunction()
