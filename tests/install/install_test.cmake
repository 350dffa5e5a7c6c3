# Driven by ctest (tests/install/CMakeLists.txt): cmake -DSOURCE_DIR= -DBUILD_DIR= -DWORK_DIR= -DSHARED=
# -DGENERATOR= -DBUILD_TYPE= -DWERROR= -DCC= -DCXX= [-DSANITIZE=address,undefined] -P install_test.cmake
# 1. libpteryla.so: this build's, or a PTERYLA_SHARED sub-build's; 2. cmake --install into a fresh
# prefix; 3. what was installed (headers, library, exports, data, package files); 4. the consumer
# through find_package(pteryla), and again through pkg-config; both run without PTERYLA_DATA_DIR, so the
# data is found beside the installed library.
cmake_minimum_required(VERSION 3.20)

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " cmd "${ARGN}")
    message(FATAL_ERROR "failed (${rc}): ${cmd}")
  endif()
endfunction()

if(SHARED)
  set(lib_build ${BUILD_DIR})
  # A sanitized libpteryla.so (tools/sanitize.sh) needs its runtime in the consumer as well.
  if(SANITIZE)
    set(consumer_flags -fsanitize=${SANITIZE})
  endif()
else()
  set(lib_build ${WORK_DIR}/lib)
  run(${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${lib_build} -G ${GENERATOR} -DCMAKE_BUILD_TYPE=${BUILD_TYPE}
      -DCMAKE_C_COMPILER=${CC} -DCMAKE_CXX_COMPILER=${CXX}
      -DPTERYLA_SHARED=ON -DPTERYLA_WERROR=${WERROR} -DPTERYLA_BUILD_TESTS=OFF -DPTERYLA_BUILD_VIEWER=OFF
      -DPTERYLA_BUILD_BENCHMARKS=OFF)
endif()
run(${CMAKE_COMMAND} --build ${lib_build} --target pteryla_host -j 2)

set(prefix ${WORK_DIR}/prefix)
file(REMOVE_RECURSE ${prefix} ${WORK_DIR}/consumer ${WORK_DIR}/consumer-pc)
run(${CMAKE_COMMAND} --install ${lib_build} --prefix ${prefix})

# What a consumer gets: the host API headers only, one library, the package files and the data.
file(GLOB_RECURSE headers RELATIVE ${prefix}/include ${prefix}/include/*)
list(SORT headers)
set(expected pteryla/core/atomic_file.hpp pteryla/core/data_dir.hpp pteryla/core/error.hpp pteryla/core/limits.hpp
    pteryla/core/memory.hpp pteryla/core/paths.hpp pteryla/core/quiet.hpp pteryla/core/sha256.hpp pteryla/export.hpp
    pteryla/pteryla.hpp pteryla/render/image.hpp pteryla/render/image_diff.hpp)
if(NOT headers STREQUAL expected)
  message(FATAL_ERROR "installed headers: ${headers}; expected ${expected}")
endif()
file(GLOB_RECURSE libs ${prefix}/libpteryla.so)
list(LENGTH libs nlibs)
if(NOT nlibs EQUAL 1)
  message(FATAL_ERROR "expected one libpteryla.so under ${prefix}, found: ${libs}")
endif()
get_filename_component(libdir ${libs} DIRECTORY)
foreach(f ${libdir}/cmake/pteryla/pterylaConfig.cmake ${libdir}/cmake/pteryla/pterylaTargets.cmake
          ${libdir}/pkgconfig/pteryla.pc ${prefix}/share/pteryla/feathers/contour.json
          ${prefix}/share/pteryla/scenes/sphere_250.json ${prefix}/share/pteryla/textures/barb_alpha.png)
  if(NOT EXISTS ${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()

# Exported symbols: the host API and its error types, nothing of the modules or third-party code.
find_program(NM nm)
if(NM)
  execute_process(COMMAND ${NM} -D -C --defined-only ${libs} OUTPUT_VARIABLE symbols RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "nm failed on ${libs}")
  endif()
  # One line per symbol, "<address> <type> <name>": everything exported must be in namespace pteryla
  # (its functions, and the typeinfo and vtables of its exception types), and outside its modules, but
  # for the image utilities the host API includes (render/image.hpp, render/image_diff.hpp).
  string(REPLACE "\n" ";" lines "${symbols}")
  set(image_api "pteryla::render::(Image::Image|saveImage|loadImage|fitImage|meanAbsoluteError|coveredFraction|diffImages|differenceImage)\\(")
  foreach(line ${lines})
    if(NOT line MATCHES "^[0-9a-f]+ [A-Za-z] ((typeinfo|typeinfo name|vtable) for )?pteryla::" OR
       (line MATCHES "^[0-9a-f]+ [A-Za-z] [^(]*pteryla::(coat|pipeline|feather|moult|render)::" AND
        NOT line MATCHES "^[0-9a-f]+ [A-Za-z] ${image_api}"))
      message(FATAL_ERROR "libpteryla.so exports more than the host API: ${line}")
    endif()
  endforeach()
  foreach(needed "pteryla::Session::evaluate" "typeinfo for pteryla::Error" "pteryla::dataDirectory")
    string(FIND "${symbols}" "${needed}" at)
    if(at EQUAL -1)
      message(FATAL_ERROR "libpteryla.so does not export ${needed}:\n${symbols}")
    endif()
  endforeach()
endif()

# The consumer, through the CMake package.
run(${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/install/consumer -B ${WORK_DIR}/consumer -G ${GENERATOR}
    -DCMAKE_BUILD_TYPE=${BUILD_TYPE} -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_PREFIX_PATH=${prefix}
    "-DCMAKE_CXX_FLAGS=${consumer_flags}")
run(${CMAKE_COMMAND} --build ${WORK_DIR}/consumer)
run(${CMAKE_COMMAND} -E env --unset=PTERYLA_DATA_DIR --unset=PTERYLA_DATA ${WORK_DIR}/consumer/consumer ${prefix})

# The consumer, through pkg-config.
find_program(PKG_CONFIG pkg-config)
if(PKG_CONFIG)
  set(ENV{PKG_CONFIG_PATH} ${libdir}/pkgconfig)
  execute_process(COMMAND ${PKG_CONFIG} --cflags --libs pteryla OUTPUT_VARIABLE flags RESULT_VARIABLE rc
                  OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "pkg-config --cflags --libs pteryla failed")
  endif()
  separate_arguments(flags UNIX_COMMAND "${flags}")
  file(MAKE_DIRECTORY ${WORK_DIR}/consumer-pc)
  run(${CXX} -std=c++17 -O1 -Wall -Wextra -Werror ${consumer_flags} ${SOURCE_DIR}/tests/install/consumer/main.cpp ${flags}
      -Wl,-rpath,${libdir} -o ${WORK_DIR}/consumer-pc/consumer)
  run(${CMAKE_COMMAND} -E env --unset=PTERYLA_DATA_DIR --unset=PTERYLA_DATA ${WORK_DIR}/consumer-pc/consumer ${prefix})
else()
  message(WARNING "pkg-config not found: pteryla.pc not tried")
endif()
message(STATUS "installed into ${prefix}; the consumer built and passed")
