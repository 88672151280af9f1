# Unity (ThrowTheSwitch, MIT) for the C tests, fetched at configure time.
#
# No system package ships Unity; the PyPI source distribution pytest-unity==0.1.0
# carries the whole Unity 2.7.0 tree under vendor/unity/ (its wheel does not). That sdist,
# pinned by its sha256, gives vendor/unity/ (cmake/PypiArchive.cmake), added here as a
# subdirectory: that defines unity::framework. Offline: point LEGSIM_UNITY_SDIST at a
# copy of the sdist (it is hash-checked all the same).
#
# Options honoured: UNITY_EXTENSION_FIXTURE / UNITY_EXTENSION_MEMORY (Unity's own).
include_guard(GLOBAL)
include(${CMAKE_CURRENT_LIST_DIR}/PypiArchive.cmake)

set(LEGSIM_UNITY_SDIST "" CACHE FILEPATH
    "Local pytest_unity-0.1.0.tar.gz to use instead of downloading it")
set(_unity_top pytest_unity-0.1.0)
legsim_pypi_archive(unity
  WHAT "Unity (the C tests' framework)"
  REQUIREMENT pytest-unity==0.1.0
  FILE ${_unity_top}.tar.gz
  SHA256 cd3ceb4aeb4f7866f935957f91874999d8ae13ff014684464ade0b7071e28298
  KIND sdist
  MEMBERS ${_unity_top}/vendor/unity
  EXPECT ${_unity_top}/vendor/unity/CMakeLists.txt ${_unity_top}/vendor/unity/src/unity.c
  LOCAL LEGSIM_UNITY_SDIST
  HINT "leave the tests out: -DLEGSIM_BUILD_TESTS=OFF (the preset \"cli\")")

# EXCLUDE_FROM_ALL: built only for the tests that link it, and its install rules stay out.
add_subdirectory(${unity_ROOT}/${_unity_top}/vendor/unity ${CMAKE_BINARY_DIR}/_deps/unity-build
                 EXCLUDE_FROM_ALL)
if(NOT TARGET unity::framework)
  message(FATAL_ERROR "Unity: ${unity_ROOT} did not define unity::framework.")
endif()
