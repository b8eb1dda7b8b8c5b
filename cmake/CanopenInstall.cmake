# Install rules and the package files (included from the top-level CMakeLists.txt):
#
#   <prefix>/lib/libcanopen.a                 core, canopen::canopen     component core
#   <prefix>/include/canopen/*.h
#   <prefix>/lib/libcanopen_drive.a           drive runtime, canopen::drive   component drive
#   <prefix>/include/canopen/drive.h, include/canopen/drive/*.h
#   <prefix>/lib/cmake/canopen/               canopenConfig.cmake (+ version file, targets)
#   <prefix>/share/canopen/cmake/CanopenOd.cmake, share/canopen/tools/eds2c.py, od2eds.c
#                                             canopen_add_od() and its generator (component core)
#   <prefix>/lib/pkgconfig/canopen.pc, canopen-drive.pc
#
# find_package(canopen [COMPONENTS drive]) then gives canopen::canopen, canopen::drive and
# canopen_add_od(); `cmake --install <build> --component core` installs the core alone.
include(CMakePackageConfigHelpers)

set(CANOPEN_CMAKE_DIR "${CMAKE_INSTALL_LIBDIR}/cmake/canopen")
set(CANOPEN_DATA_DIR "${CMAKE_INSTALL_DATADIR}/canopen")

# --- core ----------------------------------------------------------------------------------------
install(TARGETS canopen EXPORT canopenTargets
        ARCHIVE DESTINATION "${CMAKE_INSTALL_LIBDIR}" COMPONENT core)
install(DIRECTORY "${PROJECT_SOURCE_DIR}/include/canopen"
        DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}" COMPONENT core FILES_MATCHING PATTERN "*.h")
install(EXPORT canopenTargets NAMESPACE canopen:: FILE canopenTargets.cmake
        DESTINATION "${CANOPEN_CMAKE_DIR}" COMPONENT core)
# canopen_add_od() finds the generator in ../tools/ from its own folder, as in the source tree.
install(FILES "${PROJECT_SOURCE_DIR}/cmake/CanopenOd.cmake"
        DESTINATION "${CANOPEN_DATA_DIR}/cmake" COMPONENT core)
install(PROGRAMS "${PROJECT_SOURCE_DIR}/tools/eds2c.py"
        DESTINATION "${CANOPEN_DATA_DIR}/tools" COMPONENT core)
install(FILES "${PROJECT_SOURCE_DIR}/tools/od2eds.c"
        DESTINATION "${CANOPEN_DATA_DIR}/tools" COMPONENT core)

# --- drive runtime -------------------------------------------------------------------------------
install(TARGETS canopen_drive EXPORT canopenDriveTargets
        ARCHIVE DESTINATION "${CMAKE_INSTALL_LIBDIR}" COMPONENT drive)
install(DIRECTORY "${PROJECT_SOURCE_DIR}/drive/include/canopen"
        DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}" COMPONENT drive FILES_MATCHING PATTERN "*.h")
install(EXPORT canopenDriveTargets NAMESPACE canopen:: FILE canopenDriveTargets.cmake
        DESTINATION "${CANOPEN_CMAKE_DIR}" COMPONENT drive)

# --- package files -------------------------------------------------------------------------------
configure_package_config_file("${CMAKE_CURRENT_LIST_DIR}/canopenConfig.cmake.in"
  "${PROJECT_BINARY_DIR}/canopenConfig.cmake"
  INSTALL_DESTINATION "${CANOPEN_CMAKE_DIR}"
  PATH_VARS CANOPEN_DATA_DIR)
# 0.x: a minor version may change the API.
write_basic_package_version_file("${PROJECT_BINARY_DIR}/canopenConfigVersion.cmake"
  VERSION "${PROJECT_VERSION}" COMPATIBILITY SameMinorVersion)
install(FILES "${PROJECT_BINARY_DIR}/canopenConfig.cmake"
              "${PROJECT_BINARY_DIR}/canopenConfigVersion.cmake"
        DESTINATION "${CANOPEN_CMAKE_DIR}" COMPONENT core)

# pkg-config files that find their prefix from their own place (${pcfiledir}), so an install
# with `cmake --install --prefix` elsewhere, or a copied tree, still points at itself.
file(RELATIVE_PATH CANOPEN_PC_PREFIX "/p/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/p")
string(REGEX REPLACE "/$" "" CANOPEN_PC_PREFIX "${CANOPEN_PC_PREFIX}")
foreach(pc IN ITEMS canopen canopen-drive)
  if(pc STREQUAL "canopen")
    set(component core)
  else()
    set(component drive)
  endif()
  configure_file("${CMAKE_CURRENT_LIST_DIR}/${pc}.pc.in" "${PROJECT_BINARY_DIR}/${pc}.pc" @ONLY)
  install(FILES "${PROJECT_BINARY_DIR}/${pc}.pc"
          DESTINATION "${CMAKE_INSTALL_LIBDIR}/pkgconfig" COMPONENT ${component})
endforeach()
