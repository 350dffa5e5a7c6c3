# The Python module `pteryla` (python/, pybind11) is built when PTERYLA_BUILD_PYTHON is on (default)
# and a Python 3 with its headers and pybind11 are found; otherwise it is skipped with a message.
# Debian's pybind11, numpy and pytest, and Blender's embedded Python, are the system interpreter's:
# it is preferred over one found first on PATH (pyenv, venv). Pass -DPython3_EXECUTABLE=... to override.
option(PTERYLA_BUILD_PYTHON "Build the Python module pteryla (needs Python 3 headers and pybind11)" ON)
set(PTERYLA_PYTHON OFF)
if(PTERYLA_BUILD_PYTHON AND NOT PTERYLA_FUZZ)  # a fuzzing build (libFuzzer targets only) has no use for it
  if(NOT DEFINED Python3_EXECUTABLE AND EXISTS /usr/bin/python3)
    set(Python3_EXECUTABLE /usr/bin/python3 CACHE FILEPATH "Python interpreter of the pteryla module")
  endif()
  find_package(Python3 COMPONENTS Interpreter Development.Module)
  if(Python3_FOUND)
    find_package(pybind11 CONFIG QUIET)
  endif()
  if(Python3_FOUND AND pybind11_FOUND)
    set(PTERYLA_PYTHON ON)
    # The module is a shared object linking the static module archives: they must be position-independent.
    set(CMAKE_POSITION_INDEPENDENT_CODE ON)
    message(STATUS "pteryla: Python module for ${Python3_EXECUTABLE} (${Python3_VERSION}), pybind11 ${pybind11_VERSION}")
  else()
    message(STATUS "pteryla: Python module skipped (needs Python 3 headers and pybind11: tools/bootstrap.sh)")
  endif()
endif()
