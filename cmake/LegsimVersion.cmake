# legsim's version, from project() in the top-level CMakeLists.txt (the one place it is
# written; python/pyproject.toml, python/legsim/__init__.py and CHANGELOG.md repeat it and
# tests/package/version_test.py checks that they agree):
#   legsim/version.h  LEGSIM_VERSION_MAJOR/MINOR/PATCH, LEGSIM_VERSION_STRING, LEGSIM_VERSION
#                     (generated into LEGSIM_VERSION_INCLUDE_DIR; part of legsim::core's
#                     interface and installed beside legsim.h, cmake/LegsimInstall.cmake)
set(LEGSIM_VERSION_INCLUDE_DIR ${PROJECT_BINARY_DIR}/generated_version)
configure_file(${CMAKE_CURRENT_LIST_DIR}/version.h.in
               ${LEGSIM_VERSION_INCLUDE_DIR}/legsim/version.h @ONLY)
