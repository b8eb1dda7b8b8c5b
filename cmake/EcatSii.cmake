# SII EEPROM images and ESI files of EtherCAT (CoE) slaves, generated at build time from the
# slave's EDS and its EtherCAT choices file (tools/eds2sii.py).
#
#   include(cmake/EcatSii.cmake)
#   canopen_add_sii(<id> <eds-path> <choices-path>)
#
# generates ${CMAKE_BINARY_DIR}/sii/sii_<id_>.c, sii_<id_>.h and <id>.xml (id_ = id with '-'
# replaced by '_') whenever the EDS, the choices or the generator change, and creates
#   sii_<id_>  static library defining `const uint8_t co_sii_<id_>[]` (include dir
#              ${CMAKE_BINARY_DIR}/sii; the header also carries the layout macros CO_SII_<ID_>_*)
#   esi_<id_>  target that builds only the ESI file ${CMAKE_BINARY_DIR}/sii/<id>.xml
# The generator reads the EDS with tools/eds2c.py's reader, which needs python-canopen.
include_guard(GLOBAL)

find_package(Python3 COMPONENTS Interpreter REQUIRED)

get_filename_component(CANOPEN_SII_ROOT "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
set(CANOPEN_SII_GENERATOR "${CANOPEN_SII_ROOT}/tools/eds2sii.py")
set(CANOPEN_SII_OUTPUT_DIR "${CMAKE_BINARY_DIR}/sii")

execute_process(
  COMMAND "${Python3_EXECUTABLE}" -c "import canopen"
  RESULT_VARIABLE _canopen_sii_python_rc
  OUTPUT_QUIET ERROR_QUIET)
if(NOT _canopen_sii_python_rc EQUAL 0)
  message(FATAL_ERROR
    "EcatSii: ${Python3_EXECUTABLE} cannot import python-canopen, which tools/eds2sii.py needs "
    "(pip install canopen, or pass -DPython3_EXECUTABLE=<a python that has it>).")
endif()
file(MAKE_DIRECTORY "${CANOPEN_SII_OUTPUT_DIR}")

function(canopen_add_sii id eds choices)
  if(ARGN)
    message(FATAL_ERROR "canopen_add_sii(${id}): unexpected arguments ${ARGN}")
  endif()
  if(NOT id MATCHES "^[A-Za-z][A-Za-z0-9_-]*$")
    message(FATAL_ERROR "canopen_add_sii: bad id '${id}' (letters, digits, '-', '_')")
  endif()
  string(REPLACE "-" "_" uid "${id}")
  foreach(input IN ITEMS eds choices)
    get_filename_component(${input}_abs "${${input}}" ABSOLUTE BASE_DIR
                           "${CMAKE_CURRENT_SOURCE_DIR}")
    if(NOT EXISTS "${${input}_abs}")
      message(FATAL_ERROR "canopen_add_sii(${id}): ${${input}_abs} does not exist")
    endif()
  endforeach()
  set(out_c "${CANOPEN_SII_OUTPUT_DIR}/sii_${uid}.c")
  set(out_h "${CANOPEN_SII_OUTPUT_DIR}/sii_${uid}.h")
  set(out_xml "${CANOPEN_SII_OUTPUT_DIR}/${id}.xml")

  # One run writes all three: the image and the ESI cannot disagree.
  add_custom_command(
    OUTPUT "${out_c}" "${out_h}" "${out_xml}"
    COMMAND "${Python3_EXECUTABLE}" "${CANOPEN_SII_GENERATOR}" "${eds_abs}"
            --choices "${choices_abs}" --id "${id}"
            --out-c "${out_c}" --out-h "${out_h}" --out-xml "${out_xml}"
    DEPENDS "${eds_abs}" "${choices_abs}" "${CANOPEN_SII_GENERATOR}"
            "${CANOPEN_SII_ROOT}/tools/eds2c.py"
    COMMENT "Generating SII image and ESI ${id} from ${eds} and ${choices}"
    VERBATIM)

  add_library(sii_${uid} STATIC "${out_c}" "${out_h}")
  target_include_directories(sii_${uid} PUBLIC "${CANOPEN_SII_OUTPUT_DIR}")
  if(DEFINED CANOPEN_WARNINGS)
    target_compile_options(sii_${uid} PRIVATE ${CANOPEN_WARNINGS})
  endif()
  add_custom_target(esi_${uid} DEPENDS "${out_xml}")
endfunction()
