# Install rules, the CMake package (mjtetherConfig.cmake, its version file and the exported
# targets), mjtether.pc, and the Debian package through CPack (docs/install.md).
include(CMakePackageConfigHelpers)

set(MJTETHER_CMAKE_INSTALL_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/mjtether)
set(MJTETHER_MODELS_INSTALL_DIR ${CMAKE_INSTALL_DATADIR}/mjtether/models)

install(TARGETS ${MJTETHER_LIBRARIES} EXPORT mjtetherTargets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(FILES ${MJTETHER_CORE_HEADERS} ${MJTETHER_GLUE_HEADERS}
        ${PROJECT_BINARY_DIR}/include/mjtether/version.h
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/mjtether)
if(MJTETHER_RENDER)
  install(FILES ${MJTETHER_RENDER_HEADERS} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/mjtether)
endif()
if(MJTETHER_CLI)
  install(TARGETS mjtether RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()
install(DIRECTORY ${PROJECT_SOURCE_DIR}/models/ DESTINATION ${MJTETHER_MODELS_INSTALL_DIR})

install(EXPORT mjtetherTargets NAMESPACE mjtether:: DESTINATION ${MJTETHER_CMAKE_INSTALL_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/mjtetherConfig.cmake.in
  ${PROJECT_BINARY_DIR}/mjtetherConfig.cmake
  INSTALL_DESTINATION ${MJTETHER_CMAKE_INSTALL_DIR}
  PATH_VARS CMAKE_INSTALL_INCLUDEDIR MJTETHER_MODELS_INSTALL_DIR)
# 0.x: a minor version may break the API, so only the same major.minor is compatible.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/mjtetherConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/mjtetherConfig.cmake
        ${PROJECT_BINARY_DIR}/mjtetherConfigVersion.cmake
        ${PROJECT_SOURCE_DIR}/cmake/MjtetherMujoco.cmake
        DESTINATION ${MJTETHER_CMAKE_INSTALL_DIR})

# Relocatable: the prefix is found from the .pc file's own place (pkg-config's ${pcfiledir}).
file(RELATIVE_PATH MJTETHER_PC_TO_PREFIX "/p/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/p")
string(REGEX REPLACE "/$" "" MJTETHER_PC_TO_PREFIX "${MJTETHER_PC_TO_PREFIX}")
configure_file(${PROJECT_SOURCE_DIR}/cmake/mjtether.pc.in ${PROJECT_BINARY_DIR}/mjtether.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/mjtether.pc
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

# Debian package: cpack -G DEB in the build directory gives mjtether_<version>_amd64.deb.
# Configure with -DCMAKE_INSTALL_PREFIX=/usr for it (tools/consumer_check.sh does).
set(CPACK_PACKAGE_NAME mjtether)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_CONTACT "mjtether developers <mjtether@localhost>")
set(CPACK_GENERATOR DEB)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_PACKAGE_DESCRIPTION "A lumped-mass tether (umbilical, mooring line) simulated inside
MuJoCo 2.2 through its passive-force callback, with ROV hydrodynamics, thrust schedules and
prescribed motion: the mjtether command-line tool, C++ libraries with CMake and pkg-config
files, the Python module and example models.")
# Debian 12 package names. libmujoco-dev and libeigen3-dev: the installed headers and CMake
# package need them. libosmesa6 is opened with dlopen by the renderer; ffmpeg and gnuplot-nox
# are run by `mjtether render` and `mjtether plot`.
set(CPACK_DEBIAN_PACKAGE_DEPENDS
    "libc6, libstdc++6, libmujoco2.2.2, libmujoco-dev (>= 2.2.2), libeigen3-dev, libosmesa6, libpng16-16, python3 (>= 3.11), python3 (<< 3.12), python3-numpy")
# `mjtether view` links GLFW when it was built.
if(MJTETHER_CLI AND glfw3_FOUND)
  string(APPEND CPACK_DEBIAN_PACKAGE_DEPENDS ", libglfw3")
endif()
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "ffmpeg, gnuplot-nox")
include(CPack)
