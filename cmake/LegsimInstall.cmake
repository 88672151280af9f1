# The core as a package users build against (included at the end of
# firmware_core/CMakeLists.txt, whose targets and variables it uses).
#
#   cmake --install build/host --prefix /opt/legsim            host
#   cmake --install build/cortex-m4f --prefix <sysroot>/usr    cross: the same layout
#
# installs
#   include/legsim/legsim.h    the C API
#   include/legsim/config.h    this build's precision, capacities and feature switches
#   include/legsim/models.h    the compiled-in models (models/leg.toml: legsim_model_leg_*)
#   include/legsim/robot_models.h  the robot (models/robot.toml: legsim_model_robot_*), when
#                              the build's capacities hold it (LEGSIM_HAS_ROBOT)
#   include/legsim/version.h   LEGSIM_VERSION_MAJOR/MINOR/PATCH, LEGSIM_VERSION_STRING
#   <libdir>/liblegsim_core.a, liblegsim_models.a
#   <libdir>/liblegsim.so.X.Y.Z, liblegsim_f32.so.X.Y.Z   host only: for the Python API
#                              (SONAME liblegsim.so.X.Y: 0.x minors may break the ABI)
#   bin/legsim_cli             host only: runs a scene (and bin/hil_sim with LEGSIM_BUILD_HIL_SIM)
#   share/legsim/models/, scenes/, can/legsim.dbc   the shipped models, scenes and the DBC
#                              (scenes name their models relative to themselves: same tree)
#   <libdir>/cmake/legsim/     find_package(legsim): legsim::core, legsim::<model> (legsim::leg)
#   <libdir>/pkgconfig/legsim.pc (core and models), legsim-core.pc (the core alone)
#
# The installed headers are plain C (stddef.h, stdint.h and each other): Eigen is a
# private, header-only dependency of the core and consumers never see it. The core is
# C++ built without exceptions, RTTI, heap or static guards: its archive needs nothing
# from the C++ runtime (memcpy, memset and libm only, `nm -u liblegsim_core.a`), so a
# C program links it with the C compiler and -lm. tests/package proves both (a C
# consumer built with CMake and with pkg-config, linked by the C compiler).
#
# Two install components: "runtime" (the shared libraries, the programs, models, scenes,
# DBC) and "development" (headers, static libraries, the CMake and pkg-config files).
# The Python wheel (python/pyproject.toml, scikit-build-core) installs "runtime" alone,
# into its package directory, in the same layout (lib/, bin/, share/legsim/).
include(CMakePackageConfigHelpers)

set(legsim_cmake_install_dir ${CMAKE_INSTALL_LIBDIR}/cmake/legsim)

# ---- targets -----------------------------------------------------------------
# legsim::core and one target per compiled-in model, named after its symbol.
set_target_properties(legsim_core PROPERTIES EXPORT_NAME core)
set_target_properties(legsim_models PROPERTIES EXPORT_NAME ${legsim_model_symbol})
# The core calls libm (sqrt, sincos): a static library hands that on to its users
# (exported as $<LINK_ONLY:m>).
target_link_libraries(legsim_core PRIVATE m)

install(TARGETS legsim_core legsim_models EXPORT legsimTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT development)
# legsim/version.h (cmake/LegsimVersion.cmake) is part of the core's interface.
target_include_directories(legsim_core PUBLIC $<BUILD_INTERFACE:${LEGSIM_VERSION_INCLUDE_DIR}>)
# Host only: the core, the leg and the run-time loader in one shared library per
# precision, for dynamic bindings (the Python API loads them; no C headers for them).
# Versioned: liblegsim.so.X.Y.Z with the SONAME liblegsim.so.X.Y (a 0.x minor may break
# the ABI, as the CMake package's SameMinorVersion says).
foreach(legsim_shared legsim legsim_f32)
  if(TARGET ${legsim_shared})
    set_target_properties(${legsim_shared} PROPERTIES VERSION ${PROJECT_VERSION}
      SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR})
    if(SKBUILD)
      # A wheel holds no symbolic links: the one file, under the name the Python API loads
      # (by path, with ctypes; nothing links against it).
      install(FILES $<TARGET_FILE:${legsim_shared}> DESTINATION ${CMAKE_INSTALL_LIBDIR}
              RENAME ${CMAKE_SHARED_LIBRARY_PREFIX}${legsim_shared}${CMAKE_SHARED_LIBRARY_SUFFIX}
              COMPONENT runtime)
    else()
      install(TARGETS ${legsim_shared}
              LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT runtime
                NAMELINK_COMPONENT development)
    endif()
  endif()
endforeach()
if(TARGET legsim_cli)
  install(TARGETS legsim_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
endif()
# hil_sim is defined later (hil_sim/): the top-level CMakeLists.txt installs it.

# ---- models, scenes, DBC -------------------------------------------------------
if(LEGSIM_BUILD_HOST)
  set(legsim_data_dir ${CMAKE_INSTALL_DATADIR}/legsim)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/models ${PROJECT_SOURCE_DIR}/scenes
          DESTINATION ${legsim_data_dir} COMPONENT runtime FILES_MATCHING PATTERN "*.toml"
          PATTERN "*.md")
  install(FILES ${PROJECT_SOURCE_DIR}/can/legsim.dbc DESTINATION ${legsim_data_dir}/can
          COMPONENT runtime)
endif()

# ---- headers -----------------------------------------------------------------
install(DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/include/legsim
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT development
        FILES_MATCHING PATTERN "*.h")
set(legsim_generated_headers ${CMAKE_CURRENT_BINARY_DIR}/generated/legsim/config.h
    ${legsim_models_dir}/legsim/models.h ${LEGSIM_VERSION_INCLUDE_DIR}/legsim/version.h)
if(LEGSIM_HAS_ROBOT)
  list(APPEND legsim_generated_headers ${legsim_models_dir}/legsim/robot_models.h)
endif()
install(FILES ${legsim_generated_headers}
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/legsim COMPONENT development)

# ---- CMake package: find_package(legsim) ---------------------------------------
install(EXPORT legsimTargets NAMESPACE legsim:: FILE legsimTargets.cmake
        DESTINATION ${legsim_cmake_install_dir} COMPONENT development)
# What legsimConfig.cmake reports about the build (legsim_USE_FLOAT etc.).
if(LEGSIM_USE_FLOAT)
  set(legsim_config_use_float ON)
else()
  set(legsim_config_use_float OFF)
endif()
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/legsimConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/legsimConfig.cmake INSTALL_DESTINATION ${legsim_cmake_install_dir}
  NO_SET_AND_CHECK_MACRO)
# 0.x: a minor version may change the API. The file also refuses a build for another
# pointer size (a Cortex-M package found by a 64-bit host project).
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/legsimConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/legsimConfig.cmake
              ${CMAKE_CURRENT_BINARY_DIR}/legsimConfigVersion.cmake
        DESTINATION ${legsim_cmake_install_dir} COMPONENT development)

# ---- pkg-config: legsim.pc, legsim-core.pc -----------------------------------------
# Relocatable: the prefix is found from the .pc file's own place (${pcfiledir}), so
# `cmake --install --prefix <anywhere>` and DESTDIR installs give working files.
if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}" OR IS_ABSOLUTE "${CMAKE_INSTALL_INCLUDEDIR}")
  set(legsim_pc_libdir "${CMAKE_INSTALL_FULL_LIBDIR}")
  set(legsim_pc_includedir "${CMAKE_INSTALL_FULL_INCLUDEDIR}")
  set(legsim_pc_prefix "${CMAKE_INSTALL_PREFIX}")
else()
  set(legsim_pc_prefix "\${pcfiledir}")
  string(REPLACE "/" ";" legsim_pc_parts "${CMAKE_INSTALL_LIBDIR}/pkgconfig")
  foreach(legsim_pc_part IN LISTS legsim_pc_parts)
    string(APPEND legsim_pc_prefix "/..")
  endforeach()
  set(legsim_pc_libdir "\${prefix}/${CMAKE_INSTALL_LIBDIR}")
  set(legsim_pc_includedir "\${prefix}/${CMAKE_INSTALL_INCLUDEDIR}")
endif()
if(LEGSIM_USE_FLOAT)
  set(legsim_pc_build "float")
else()
  set(legsim_pc_build "double")
endif()
string(APPEND legsim_pc_build ", for ${CMAKE_SYSTEM_PROCESSOR} (${CMAKE_SYSTEM_NAME})")
foreach(legsim_pc legsim legsim-core)
  configure_file(${PROJECT_SOURCE_DIR}/cmake/${legsim_pc}.pc.in
                 ${CMAKE_CURRENT_BINARY_DIR}/pkgconfig/${legsim_pc}.pc @ONLY)
  install(FILES ${CMAKE_CURRENT_BINARY_DIR}/pkgconfig/${legsim_pc}.pc
          DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig COMPONENT development)
endforeach()
