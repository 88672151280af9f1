# The FMI 3.0 headers (fmi3Functions.h, fmi3FunctionTypes.h, fmi3PlatformTypes.h; the
# Modelica Association's, 2-clause BSD) for the FMUs (fmu/), fetched at configure time.
#
# No Debian package ships them; FMPy's wheel on PyPI carries them (fmpy/c-code/), and FMPy
# is the FMUs' client in the tests anyway. We download that wheel with pip, pinned by its
# sha256, and extract the three headers into the build tree: LEGSIM_FMI3_INCLUDE_DIR.
# Cached (a stamp holding the hash); offline: -DLEGSIM_FMPY_WHEEL=<a copy of the wheel>
# (hash-checked all the same).
include_guard(GLOBAL)

set(LEGSIM_FMPY_VERSION 0.3.32)
set(LEGSIM_FMPY_SHA256 b379deb9417b842028003a288d00c1c5f138d1580e1ff12cc6c42a98719cecf0)
set(LEGSIM_FMPY_WHEEL "" CACHE FILEPATH
    "Local fmpy-${LEGSIM_FMPY_VERSION}-py3-none-any.whl to use instead of downloading it")

set(_fmi_root ${CMAKE_BINARY_DIR}/_deps/fmi3)
set(LEGSIM_FMI3_INCLUDE_DIR ${_fmi_root}/fmpy/c-code)
set(_fmi_stamp ${_fmi_root}/extracted.stamp)
set(_fmi_headers fmi3Functions.h fmi3FunctionTypes.h fmi3PlatformTypes.h)

set(_fmi_have FALSE)
if(EXISTS ${_fmi_stamp})
  file(READ ${_fmi_stamp} _fmi_stamped)
  string(STRIP "${_fmi_stamped}" _fmi_stamped)
  if(_fmi_stamped STREQUAL LEGSIM_FMPY_SHA256)
    set(_fmi_have TRUE)
  endif()
endif()

if(NOT _fmi_have)
  file(REMOVE_RECURSE ${_fmi_root})
  file(MAKE_DIRECTORY ${_fmi_root}/download)
  set(_fmi_wheel ${_fmi_root}/download/fmpy-${LEGSIM_FMPY_VERSION}-py3-none-any.whl)
  if(LEGSIM_FMPY_WHEEL)
    set(_fmi_wheel ${LEGSIM_FMPY_WHEEL})
  else()
    set(_fmi_req ${_fmi_root}/requirements.txt)
    file(WRITE ${_fmi_req} "fmpy==${LEGSIM_FMPY_VERSION} --hash=sha256:${LEGSIM_FMPY_SHA256}\n")
    message(STATUS "FMI 3.0 headers: downloading the fmpy==${LEGSIM_FMPY_VERSION} wheel with pip "
                   "(pinned by sha256)")
    execute_process(
      COMMAND ${CMAKE_COMMAND} -E env PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1
              ${Python3_EXECUTABLE} -m pip download --no-deps --only-binary=:all:
              --require-hashes -r ${_fmi_req} -d ${_fmi_root}/download
      RESULT_VARIABLE _fmi_rc ERROR_VARIABLE _fmi_err OUTPUT_QUIET TIMEOUT 900)
    if(NOT _fmi_rc EQUAL 0 OR NOT EXISTS ${_fmi_wheel})
      message(FATAL_ERROR
        "FMI 3.0 headers: could not download fmpy==${LEGSIM_FMPY_VERSION} (its wheel carries "
        "them) with ${Python3_EXECUTABLE} -m pip download (exit ${_fmi_rc}):\n${_fmi_err}\n"
        "Check that PyPI is reachable, or give the wheel: -DLEGSIM_FMPY_WHEEL=/path/to/it, or "
        "leave the FMUs out: -DLEGSIM_BUILD_FMU=OFF.")
    endif()
  endif()
  file(SHA256 ${_fmi_wheel} _fmi_sha)
  if(NOT _fmi_sha STREQUAL LEGSIM_FMPY_SHA256)
    message(FATAL_ERROR "FMI 3.0 headers: ${_fmi_wheel} has sha256 ${_fmi_sha}, expected "
                        "${LEGSIM_FMPY_SHA256}.")
  endif()
  list(TRANSFORM _fmi_headers PREPEND fmpy/c-code/ OUTPUT_VARIABLE _fmi_members)
  file(ARCHIVE_EXTRACT INPUT ${_fmi_wheel} DESTINATION ${_fmi_root} PATTERNS ${_fmi_members})
  foreach(h IN LISTS _fmi_headers)
    if(NOT EXISTS ${LEGSIM_FMI3_INCLUDE_DIR}/${h})
      message(FATAL_ERROR "FMI 3.0 headers: ${_fmi_wheel} holds no fmpy/c-code/${h}.")
    endif()
  endforeach()
  file(WRITE ${_fmi_stamp} "${LEGSIM_FMPY_SHA256}\n")
  message(STATUS "FMI 3.0 headers: extracted into ${LEGSIM_FMI3_INCLUDE_DIR}")
endif()
