# Cortex-M4F: Thumb-2, single-precision FPU (FPv4-SP-D16), hard-float ABI.
# A double on this core runs in software: build the core with LEGSIM_USE_FLOAT=ON
# (the cortex-m4f preset does; the toolchain only describes the CPU).
set(LEGSIM_ARM_CPU_FLAGS "-mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard")
set(LEGSIM_ARM_CPU cortex-m4f)
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi-common.cmake)
