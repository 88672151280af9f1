# legsim_pypi_archive(): files out of one pinned PyPI distribution, fetched at configure time.
#
# Some of what the build needs has no Debian package but rides in a PyPI distribution (Unity's
# C sources in an sdist, the FMI 3.0 headers in FMPy's wheel). pip downloads that one file,
# pinned by its sha256 (--require-hashes; pip's index settings apply), the hash is checked
# again (also for a file given by hand), and only the named members are extracted into
# ${CMAKE_BINARY_DIR}/_deps/<ID>. A stamp holding the hash makes later configures offline.
#
#   legsim_pypi_archive(<ID>
#     WHAT     "<what it is, for messages>"
#     REQUIREMENT <name>==<version>      # what pip downloads
#     FILE     <the distribution's file name>
#     SHA256   <its sha256>
#     KIND     sdist|wheel
#     MEMBERS  <paths or folders inside it to extract>...
#     EXPECT   <paths, relative to the extraction root, that must exist>...
#     LOCAL    <cache variable naming a local copy to use instead of downloading>
#     HINT     "<how to do without it, for the error message>")
# Sets <ID>_ROOT in the caller's scope: the folder the members were extracted into.
include_guard(GLOBAL)

function(legsim_pypi_archive id)
  cmake_parse_arguments(PARSE_ARGV 1 A "" "WHAT;REQUIREMENT;FILE;SHA256;KIND;LOCAL;HINT"
                        "MEMBERS;EXPECT")
  set(root ${CMAKE_BINARY_DIR}/_deps/${id})
  set(stamp ${root}/extracted.stamp)
  set(${id}_ROOT ${root} PARENT_SCOPE)

  set(have FALSE)
  if(EXISTS ${stamp})
    file(READ ${stamp} stamped)
    string(STRIP "${stamped}" stamped)
    set(have TRUE)
    if(NOT stamped STREQUAL A_SHA256)
      set(have FALSE)
    endif()
    foreach(f IN LISTS A_EXPECT)
      if(NOT EXISTS ${root}/${f})
        set(have FALSE)
      endif()
    endforeach()
  endif()
  if(have)
    return()
  endif()

  file(REMOVE_RECURSE ${root})
  file(MAKE_DIRECTORY ${root}/download)
  set(local "${${A_LOCAL}}")
  if(local)
    if(NOT EXISTS ${local})
      message(FATAL_ERROR "${A_WHAT}: ${A_LOCAL}=${local} does not exist.")
    endif()
    set(archive ${local})
    message(STATUS "${A_WHAT}: using ${archive}")
  else()
    if(NOT Python3_EXECUTABLE)
      find_package(Python3 REQUIRED COMPONENTS Interpreter)
    endif()
    # A Debian system Python has no pip (python3-pip is a separate package); the project's
    # .venv (tools/setup.sh) has it.
    execute_process(COMMAND ${Python3_EXECUTABLE} -m pip --version
                    RESULT_VARIABLE pip_rc OUTPUT_QUIET ERROR_QUIET)
    if(NOT pip_rc EQUAL 0)
      message(FATAL_ERROR
        "${A_WHAT}: fetched with pip (${A_REQUIREMENT}, pinned by sha256), and "
        "${Python3_EXECUTABLE} has no pip (No module named pip). Either\n"
        "  run tools/setup.sh (it makes .venv, which has pip; the build then uses .venv/bin/python),\n"
        "  or configure with -DPython3_EXECUTABLE=<a python with pip> (on Debian: apt-get install python3-pip),\n"
        "  or give the file: -D${A_LOCAL}=/path/to/${A_FILE},\n"
        "  or ${A_HINT}.")
    endif()
    if(A_KIND STREQUAL "sdist")
      set(only --no-binary=:all:)
    else()
      set(only --only-binary=:all:)
    endif()
    set(req ${root}/requirements.txt)
    file(WRITE ${req} "${A_REQUIREMENT} --hash=sha256:${A_SHA256}\n")
    message(STATUS "${A_WHAT}: downloading the ${A_REQUIREMENT} ${A_KIND} with pip (pinned by sha256)")
    execute_process(
      COMMAND ${CMAKE_COMMAND} -E env PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1
              ${Python3_EXECUTABLE} -m pip download --no-deps ${only}
              --require-hashes -r ${req} -d ${root}/download
      RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err TIMEOUT 900)
    set(archive ${root}/download/${A_FILE})
    if(NOT rc EQUAL 0 OR NOT EXISTS ${archive})
      message(FATAL_ERROR
        "${A_WHAT}: could not download ${A_REQUIREMENT} from PyPI with\n"
        "  ${Python3_EXECUTABLE} -m pip download --no-deps ${only} --require-hashes -r ${req}\n"
        "pip exit status: ${rc}\npip said:\n${err}\n"
        "Check that PyPI is reachable (pip's index settings apply), or download the file "
        "elsewhere and configure with -D${A_LOCAL}=/path/to/${A_FILE}, or ${A_HINT}.")
    endif()
  endif()

  # pip checked the hash already; check again (and check a file given by hand).
  file(SHA256 ${archive} sha)
  if(NOT sha STREQUAL A_SHA256)
    message(FATAL_ERROR "${A_WHAT}: ${archive} has sha256 ${sha}, expected ${A_SHA256}.")
  endif()
  file(ARCHIVE_EXTRACT INPUT ${archive} DESTINATION ${root} PATTERNS ${A_MEMBERS})
  foreach(f IN LISTS A_EXPECT)
    if(NOT EXISTS ${root}/${f})
      message(FATAL_ERROR "${A_WHAT}: ${archive} holds no ${f}.")
    endif()
  endforeach()
  file(WRITE ${stamp} "${A_SHA256}\n")
  message(STATUS "${A_WHAT}: extracted into ${root}")
endfunction()
