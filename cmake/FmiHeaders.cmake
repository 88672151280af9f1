# The FMI 3.0 headers (fmi3Functions.h, fmi3FunctionTypes.h, fmi3PlatformTypes.h; the
# Modelica Association's, 2-clause BSD) for the FMUs (fmu/), fetched at configure time.
#
# No Debian package ships them; FMPy's wheel on PyPI carries them (fmpy/c-code/), and FMPy
# is the FMUs' client in the tests anyway. That wheel, pinned by its sha256, gives the three
# headers (cmake/PypiArchive.cmake): LEGSIM_FMI3_INCLUDE_DIR. Offline:
# -DLEGSIM_FMPY_WHEEL=<a copy of the wheel> (hash-checked all the same).
include_guard(GLOBAL)
include(${CMAKE_CURRENT_LIST_DIR}/PypiArchive.cmake)

set(LEGSIM_FMPY_WHEEL "" CACHE FILEPATH
    "Local fmpy-0.3.32-py3-none-any.whl to use instead of downloading it")
legsim_pypi_archive(fmi3
  WHAT "FMI 3.0 headers"
  REQUIREMENT fmpy==0.3.32
  FILE fmpy-0.3.32-py3-none-any.whl
  SHA256 b379deb9417b842028003a288d00c1c5f138d1580e1ff12cc6c42a98719cecf0
  KIND wheel
  MEMBERS fmpy/c-code/fmi3Functions.h fmpy/c-code/fmi3FunctionTypes.h fmpy/c-code/fmi3PlatformTypes.h
  EXPECT fmpy/c-code/fmi3Functions.h fmpy/c-code/fmi3FunctionTypes.h fmpy/c-code/fmi3PlatformTypes.h
  LOCAL LEGSIM_FMPY_WHEEL
  HINT "leave the FMUs out: -DLEGSIM_BUILD_FMU=OFF")
set(LEGSIM_FMI3_INCLUDE_DIR ${fmi3_ROOT}/fmpy/c-code)
