# Object dictionaries generated from EDS files at build time (tools/eds2c.py).
#
#   include(cmake/CanopenOd.cmake)   # or find_package(canopen), or add_subdirectory of the stack
#   canopen_add_od(<id> <eds-path> [EXPORTER])
#
# generates ${CMAKE_BINARY_DIR}/od/od_<id_>.c and od_<id_>.h (id_ = id with '-' replaced by '_')
# whenever the EDS or the generator changes, and creates the static library target od_<id_>
# (linked against the core, canopen::canopen or `canopen`, include dir ${CMAKE_BINARY_DIR}/od),
# which defines `const co_od co_od_<id_>`; its header declares it and CO_OD_<ID_>_VALUE_SIZE.
# EXPORTER also builds od2eds_<id_> (tools/od2eds.c), which prints the generated tables back as an
# EDS on stdout.
# CANOPEN_OD_NAMES (ON by default): OFF builds the tables without the name strings
# (CO_OD_NO_NAMES), which only tools and diagnostics use.
#
# canopen_add_od() needs nothing from the scope this file was included in: it finds the generator
# next to this file (../tools/, in the source tree and in an installed package alike) and Python
# when it is called. A project that adds the stack with add_subdirectory or FetchContent and then
# includes this file itself (a no-op: the function is already defined) gets a working function.
include_guard(GLOBAL)

option(CANOPEN_OD_NAMES "Keep the object/sub-index name tables in generated dictionaries" ON)

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

  # Paths from this file's own folder and the build being configured, never from variables of the
  # scope that included it.
  get_filename_component(tools "${CMAKE_CURRENT_FUNCTION_LIST_DIR}/../tools" ABSOLUTE)
  set(generator "${tools}/eds2c.py")
  set(out_dir "${CMAKE_BINARY_DIR}/od")
  set(out_c "${out_dir}/od_${uid}.c")
  set(out_h "${out_dir}/od_${uid}.h")
  if(NOT EXISTS "${generator}")
    message(FATAL_ERROR "canopen_add_od(${id}): the generator ${generator} is missing")
  endif()

  if(NOT Python3_EXECUTABLE)
    find_package(Python3 COMPONENTS Interpreter REQUIRED)
  endif()
  # The generator reads the EDS with python-canopen (what masters use): fail at configure time,
  # with a clear message, rather than on the first build. Checked once per interpreter.
  get_property(checked GLOBAL PROPERTY CANOPEN_OD_PYTHON_CHECKED)
  if(NOT checked STREQUAL Python3_EXECUTABLE)
    execute_process(
      COMMAND "${Python3_EXECUTABLE}" -c "import canopen"
      RESULT_VARIABLE rc
      OUTPUT_QUIET ERROR_QUIET)
    if(NOT rc EQUAL 0)
      message(FATAL_ERROR
        "canopen_add_od: ${Python3_EXECUTABLE} cannot import python-canopen, which "
        "${generator} needs to read EDS files (pip install canopen, or pass "
        "-DPython3_EXECUTABLE=<a python that has it>).")
    endif()
    set_property(GLOBAL PROPERTY CANOPEN_OD_PYTHON_CHECKED "${Python3_EXECUTABLE}")
  endif()
  file(MAKE_DIRECTORY "${out_dir}")

  add_custom_command(
    OUTPUT "${out_c}" "${out_h}"
    COMMAND "${Python3_EXECUTABLE}" "${generator}" "${eds_abs}" --id "${id}"
            --out-c "${out_c}" --out-h "${out_h}"
    DEPENDS "${eds_abs}" "${generator}"
    COMMENT "Generating object dictionary ${id} from ${eds}"
    VERBATIM)

  # The core as the stack's own build names it, as an installed package names it, or (a project
  # that stands in for the core with its own target) plain `canopen`.
  if(TARGET canopen::canopen)
    set(core canopen::canopen)
  else()
    set(core canopen)
  endif()
  add_library(od_${uid} STATIC "${out_c}" "${out_h}")
  target_include_directories(od_${uid} PUBLIC "${out_dir}")
  target_link_libraries(od_${uid} PUBLIC ${core})
  if(NOT CANOPEN_OD_NAMES)
    target_compile_definitions(od_${uid} PUBLIC CO_OD_NO_NAMES)
  endif()
  if(DEFINED CANOPEN_WARNINGS)
    target_compile_options(od_${uid} PRIVATE ${CANOPEN_WARNINGS})
  endif()

  if(ARG_EXPORTER)
    add_executable(od2eds_${uid} "${tools}/od2eds.c")
    target_link_libraries(od2eds_${uid} PRIVATE od_${uid})
    target_compile_definitions(od2eds_${uid} PRIVATE CO_OD_SYMBOL=co_od_${uid})
  endif()
endfunction()
