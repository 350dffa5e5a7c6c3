# Every third-party dependency is found here, once, and exposed as a target.
# Debian 12 packages; tools/bootstrap.sh installs them.
find_package(PkgConfig REQUIRED)
find_package(Threads REQUIRED)
find_package(glm CONFIG REQUIRED PATHS /usr/share/cmake/glm)
find_package(nlohmann_json CONFIG REQUIRED)
find_package(CLI11 CONFIG REQUIRED)
find_package(OpenMesh CONFIG REQUIRED)
find_package(Eigen3 CONFIG REQUIRED)
find_package(TBB CONFIG REQUIRED)

# OpenImageIO's CMake config points at a missing /usr/include/opencv4 on Debian 12: use pkg-config.
pkg_check_modules(OIIO REQUIRED IMPORTED_TARGET OpenImageIO)
pkg_check_modules(OSMESA REQUIRED IMPORTED_TARGET osmesa)

# CGAL is header-heavy: only link pteryla_cgal into the few .cpp files that need it.
find_package(CGAL CONFIG REQUIRED)

if(PTERYLA_BUILD_VIEWER)
  find_package(glfw3 CONFIG REQUIRED)
  find_package(OpenGL REQUIRED)
  pkg_check_modules(IMGUI REQUIRED IMPORTED_TARGET imgui)
endif()
if(PTERYLA_BUILD_TESTS)
  find_package(GTest CONFIG REQUIRED)
endif()
if(PTERYLA_BUILD_BENCHMARKS)
  find_package(benchmark CONFIG REQUIRED)
endif()
