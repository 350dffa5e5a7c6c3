# Install rules for the shared host library (PTERYLA_SHARED=ON): libpteryla.so, the host API headers,
# the bundled data, a relocatable CMake package (find_package(pteryla) -> pteryla::pteryla) and a
# relocatable pkg-config file (pteryla.pc). Only pteryla.hpp and what it includes are installed: the
# module headers use GLM, nlohmann/json and each other, and are not a stable interface.
include(CMakePackageConfigHelpers)

set(PTERYLA_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/pteryla)

install(TARGETS pteryla_host EXPORT pterylaTargets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(FILES
  ${PROJECT_SOURCE_DIR}/include/pteryla/pteryla.hpp
  ${PROJECT_SOURCE_DIR}/include/pteryla/export.hpp
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/pteryla)
install(FILES
  ${PROJECT_SOURCE_DIR}/include/pteryla/core/error.hpp
  ${PROJECT_SOURCE_DIR}/include/pteryla/core/data_dir.hpp
  ${PROJECT_SOURCE_DIR}/include/pteryla/core/atomic_file.hpp
  ${PROJECT_SOURCE_DIR}/include/pteryla/core/limits.hpp
  ${PROJECT_SOURCE_DIR}/include/pteryla/core/memory.hpp
  ${PROJECT_SOURCE_DIR}/include/pteryla/core/paths.hpp
  ${PROJECT_SOURCE_DIR}/include/pteryla/core/quiet.hpp
  ${PROJECT_SOURCE_DIR}/include/pteryla/core/sha256.hpp
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/pteryla/core)
install(FILES
  ${PROJECT_SOURCE_DIR}/include/pteryla/render/image.hpp
  ${PROJECT_SOURCE_DIR}/include/pteryla/render/image_diff.hpp
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/pteryla/render)
# The data the defaults need (feathers; textures for renderers), and the bundled scenes with their
# meshes so that Session::fromSceneFile can open them from the installed copy.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/data/ DESTINATION ${PTERYLA_INSTALL_DATADIR})

install(EXPORT pterylaTargets NAMESPACE pteryla:: DESTINATION ${PTERYLA_INSTALL_CMAKEDIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/pterylaConfig.cmake.in
  ${PROJECT_BINARY_DIR}/pterylaConfig.cmake INSTALL_DESTINATION ${PTERYLA_INSTALL_CMAKEDIR}
  PATH_VARS PTERYLA_INSTALL_DATADIR)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/pterylaConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/pterylaConfig.cmake ${PROJECT_BINARY_DIR}/pterylaConfigVersion.cmake
  DESTINATION ${PTERYLA_INSTALL_CMAKEDIR})

# pteryla.pc finds its prefix from its own place (${pcfiledir}), so the installed tree can move.
file(RELATIVE_PATH PTERYLA_PC_TO_PREFIX /prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig /prefix)
string(REGEX REPLACE "/$" "" PTERYLA_PC_TO_PREFIX "${PTERYLA_PC_TO_PREFIX}")
configure_file(${PROJECT_SOURCE_DIR}/cmake/pteryla.pc.in ${PROJECT_BINARY_DIR}/pteryla.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/pteryla.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
