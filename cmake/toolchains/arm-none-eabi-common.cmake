# Shared part of the arm-none-eabi (GNU Arm Embedded, newlib) toolchain files.
# Included by arm-none-eabi-<cpu>.cmake after they set LEGSIM_ARM_CPU_FLAGS.
#
# Bare metal: CMAKE_SYSTEM_NAME Generic, and try_compile builds static libraries
# (no startup code or linker script is needed to probe the compiler).
# Compilers come from PATH, or from ARM_TOOLCHAIN_DIR (…/bin) if set (cache or env).
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

if(NOT ARM_TOOLCHAIN_DIR AND DEFINED ENV{ARM_TOOLCHAIN_DIR})
  set(ARM_TOOLCHAIN_DIR "$ENV{ARM_TOOLCHAIN_DIR}")
endif()
# try_compile re-reads this file in a fresh project: hand the variables on.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES ARM_TOOLCHAIN_DIR)

set(_arm_prefix arm-none-eabi-)
if(ARM_TOOLCHAIN_DIR)
  set(_arm_prefix ${ARM_TOOLCHAIN_DIR}/arm-none-eabi-)
endif()
set(CMAKE_C_COMPILER ${_arm_prefix}gcc)
set(CMAKE_CXX_COMPILER ${_arm_prefix}g++)
set(CMAKE_ASM_COMPILER ${_arm_prefix}gcc)
# ar, ranlib, nm, objcopy, objdump come with the compiler's prefix (CMake finds them);
# arm-none-eabi-size is looked up where it is needed (firmware_core/mcu).

# Code and data in their own sections so the linker can drop what is unused.
# -fno-math-errno: sqrt is the FPU's vsqrt inline, not a call to newlib's sqrtf wrapper that
# checks for a negative argument to set errno (nothing here reads errno; the result, NaN for
# x < 0, is the same). -fconserve-stack: inline less where it would grow a frame (with the
# link-time optimization of the cortex-m4f preset the image's stack went from 2.1 to 3.6 KB
# without it, 2.0 KB with it).
set(_arm_common
    "${LEGSIM_ARM_CPU_FLAGS} -ffunction-sections -fdata-sections -fno-math-errno -fconserve-stack")
set(CMAKE_C_FLAGS_INIT "${_arm_common}")
set(CMAKE_ASM_FLAGS_INIT "${LEGSIM_ARM_CPU_FLAGS}")
# No exceptions, no RTTI, no thread-safe static guards (no __cxa_guard_*), and no
# __cxa_atexit/__dso_handle: a static object with a destructor would register it
# with plain atexit (newlib's exit-handler list, which can reach for malloc); the
# firmware has none, and the MCU tests check the images for atexit.
set(CMAKE_CXX_FLAGS_INIT
    "${_arm_common} -fno-exceptions -fno-rtti -fno-threadsafe-statics -fno-use-cxa-atexit")
# newlib-nano (smaller libc/libstdc++); unused sections collected.
# (the CPU flags reach the link through CMAKE_<LANG>_FLAGS)
set(CMAKE_EXE_LINKER_FLAGS_INIT "--specs=nano.specs -Wl,--gc-sections")

# Release is for size on the target: -Os instead of CMake's -O3. GNU.cmake appends
# -O3 to the *_INIT value, so set the cache entries (read before it) instead.
foreach(_lang C CXX ASM)
  set(CMAKE_${_lang}_FLAGS_RELEASE "-Os -DNDEBUG" CACHE STRING
      "Flags used by the ${_lang} compiler during Release builds (size-optimised).")
endforeach()

# Search the host for programs, the target sysroot for libraries and headers.
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
