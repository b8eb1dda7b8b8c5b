# Unity is a test dependency, never committed: take it from -DUNITY_DIR, an installed Debian
# 'cmock' package, a copy fetched earlier into the build tree, or fetch it now (tools/fetch-unity.sh).
set(UNITY_DIR "" CACHE PATH "Folder holding Unity's src/unity.c (empty: find or fetch it)")
set(_unity_fetched "${CMAKE_BINARY_DIR}/_deps/unity")
if(NOT UNITY_DIR OR NOT EXISTS "${UNITY_DIR}/src/unity.c")
  if(EXISTS "/usr/share/cmock/vendor/unity/src/unity.c")
    set(UNITY_DIR "/usr/share/cmock/vendor/unity")
  elseif(EXISTS "${_unity_fetched}/src/unity.c")
    set(UNITY_DIR "${_unity_fetched}")
  else()
    message(STATUS "Fetching Unity from Debian's cmock package")
    execute_process(COMMAND sh "${CMAKE_CURRENT_LIST_DIR}/../tools/fetch-unity.sh"
                            "${_unity_fetched}"
                    RESULT_VARIABLE _unity_rc)
    if(NOT _unity_rc EQUAL 0)
      message(FATAL_ERROR "Unity not found and tools/fetch-unity.sh failed (${_unity_rc})")
    endif()
    set(UNITY_DIR "${_unity_fetched}")
  endif()
endif()
message(STATUS "Unity: ${UNITY_DIR}")
add_library(unity STATIC "${UNITY_DIR}/src/unity.c")
target_include_directories(unity SYSTEM PUBLIC "${UNITY_DIR}/src")
target_compile_definitions(unity PUBLIC UNITY_INCLUDE_DOUBLE UNITY_SUPPORT_64)
# Unity is not ours: build it without our -Werror set.
set_target_properties(unity PROPERTIES C_STANDARD 99 COMPILE_OPTIONS "")
