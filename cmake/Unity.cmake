# Unity (ThrowTheSwitch, MIT) for the C tests, fetched at configure time.
#
# No system package ships Unity; the PyPI source distribution pytest-unity==0.1.0
# carries the whole Unity 2.7.0 tree under vendor/unity/ (its wheel does not).
# We download that sdist with pip, pinned by its sha256, extract vendor/unity/
# into the build tree and add it as a subdirectory: that defines unity::framework.
#
# Cached: once extracted (stamp file holding the hash) nothing is downloaded again
# for this build tree. Offline: point LEGSIM_UNITY_SDIST at a copy of the sdist
# (it is hash-checked all the same).
#
# Options honoured: UNITY_EXTENSION_FIXTURE / UNITY_EXTENSION_MEMORY (Unity's own).
include_guard(GLOBAL)

set(LEGSIM_UNITY_PYPI_NAME pytest-unity)
set(LEGSIM_UNITY_PYPI_VERSION 0.1.0)
set(LEGSIM_UNITY_SHA256 cd3ceb4aeb4f7866f935957f91874999d8ae13ff014684464ade0b7071e28298)
set(LEGSIM_UNITY_SDIST "" CACHE FILEPATH
    "Local pytest_unity-${LEGSIM_UNITY_PYPI_VERSION}.tar.gz to use instead of downloading it")

set(_unity_root ${CMAKE_BINARY_DIR}/_deps/unity)
set(_unity_top pytest_unity-${LEGSIM_UNITY_PYPI_VERSION})
set(_unity_src ${_unity_root}/${_unity_top}/vendor/unity)
set(_unity_stamp ${_unity_root}/extracted.stamp)

set(_unity_have_tree FALSE)
if(EXISTS ${_unity_stamp} AND EXISTS ${_unity_src}/CMakeLists.txt
   AND EXISTS ${_unity_src}/src/unity.c)
  file(READ ${_unity_stamp} _unity_stamped)
  string(STRIP "${_unity_stamped}" _unity_stamped)
  if(_unity_stamped STREQUAL LEGSIM_UNITY_SHA256)
    set(_unity_have_tree TRUE)
  endif()
endif()

if(NOT _unity_have_tree)
  file(REMOVE_RECURSE ${_unity_root})
  file(MAKE_DIRECTORY ${_unity_root}/download)

  if(LEGSIM_UNITY_SDIST)
    set(_unity_sdist ${LEGSIM_UNITY_SDIST})
    if(NOT EXISTS ${_unity_sdist})
      message(FATAL_ERROR "Unity: LEGSIM_UNITY_SDIST=${_unity_sdist} does not exist.")
    endif()
    message(STATUS "Unity: using ${_unity_sdist}")
  else()
    if(NOT Python3_EXECUTABLE)
      find_package(Python3 REQUIRED COMPONENTS Interpreter)
    endif()
    # A Debian system Python has no pip (python3-pip is a separate package); the
    # project's .venv (tools/setup.sh) has it.
    execute_process(COMMAND ${Python3_EXECUTABLE} -m pip --version
                    RESULT_VARIABLE _unity_pip_rc OUTPUT_QUIET ERROR_QUIET)
    if(NOT _unity_pip_rc EQUAL 0)
      message(FATAL_ERROR
        "Unity: the C tests fetch Unity with pip (the sdist ${LEGSIM_UNITY_PYPI_NAME}=="
        "${LEGSIM_UNITY_PYPI_VERSION}, pinned by sha256), and ${Python3_EXECUTABLE} has no pip "
        "(No module named pip). Either\n"
        "  run tools/setup.sh (it makes .venv, which has pip; the build then uses .venv/bin/python),\n"
        "  or configure with -DPython3_EXECUTABLE=<a python with pip> (on Debian: apt-get install python3-pip),\n"
        "  or give the sdist: -DLEGSIM_UNITY_SDIST=/path/to/${_unity_top}.tar.gz,\n"
        "  or leave the tests out: -DLEGSIM_BUILD_TESTS=OFF (the preset \"cli\").")
    endif()
    set(_unity_req ${_unity_root}/requirements.txt)
    file(WRITE ${_unity_req}
         "${LEGSIM_UNITY_PYPI_NAME}==${LEGSIM_UNITY_PYPI_VERSION} --hash=sha256:${LEGSIM_UNITY_SHA256}\n")
    message(STATUS "Unity: downloading the ${LEGSIM_UNITY_PYPI_NAME}==${LEGSIM_UNITY_PYPI_VERSION} "
                   "sdist with pip (pinned by sha256)")
    execute_process(
      COMMAND ${CMAKE_COMMAND} -E env PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1
              ${Python3_EXECUTABLE} -m pip download --no-deps --no-binary=:all:
              --require-hashes -r ${_unity_req} -d ${_unity_root}/download
      RESULT_VARIABLE _unity_rc
      OUTPUT_VARIABLE _unity_out
      ERROR_VARIABLE _unity_err
      TIMEOUT 900)
    set(_unity_sdist ${_unity_root}/download/${_unity_top}.tar.gz)
    if(NOT _unity_rc EQUAL 0 OR NOT EXISTS ${_unity_sdist})
      message(FATAL_ERROR
        "Unity: could not download ${LEGSIM_UNITY_PYPI_NAME}==${LEGSIM_UNITY_PYPI_VERSION} "
        "(the sdist that carries Unity) from PyPI with\n"
        "  ${Python3_EXECUTABLE} -m pip download --no-deps --no-binary=:all: --require-hashes "
        "-r ${_unity_req}\n"
        "pip exit status: ${_unity_rc}\n"
        "pip said:\n${_unity_err}\n"
        "Check that PyPI is reachable (pip's index settings apply), or download the sdist "
        "elsewhere and configure with -DLEGSIM_UNITY_SDIST=/path/to/${_unity_top}.tar.gz.")
    endif()
  endif()

  # pip checked the hash already; check again (and check a hand-given file).
  file(SHA256 ${_unity_sdist} _unity_sha)
  if(NOT _unity_sha STREQUAL LEGSIM_UNITY_SHA256)
    message(FATAL_ERROR "Unity: ${_unity_sdist} has sha256 ${_unity_sha}, expected "
                        "${LEGSIM_UNITY_SHA256}.")
  endif()

  file(ARCHIVE_EXTRACT INPUT ${_unity_sdist} DESTINATION ${_unity_root}
       PATTERNS ${_unity_top}/vendor/unity)
  if(NOT EXISTS ${_unity_src}/CMakeLists.txt OR NOT EXISTS ${_unity_src}/src/unity.c)
    message(FATAL_ERROR "Unity: ${_unity_sdist} holds no ${_unity_top}/vendor/unity tree.")
  endif()
  file(WRITE ${_unity_stamp} "${LEGSIM_UNITY_SHA256}\n")
  message(STATUS "Unity: extracted into ${_unity_src}")
endif()

# EXCLUDE_FROM_ALL: built only for the tests that link it, and its install rules stay out.
add_subdirectory(${_unity_src} ${CMAKE_BINARY_DIR}/_deps/unity-build EXCLUDE_FROM_ALL)
if(NOT TARGET unity::framework)
  message(FATAL_ERROR "Unity: ${_unity_src} did not define unity::framework.")
endif()
