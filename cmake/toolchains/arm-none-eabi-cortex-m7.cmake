# Cortex-M7 with the double-precision FPU (FPv5-D16), hard-float ABI: the core
# runs in double (LEGSIM_USE_FLOAT=OFF, the default).
set(LEGSIM_ARM_CPU_FLAGS "-mcpu=cortex-m7 -mthumb -mfpu=fpv5-d16 -mfloat-abi=hard")
set(LEGSIM_ARM_CPU cortex-m7)
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi-common.cmake)
