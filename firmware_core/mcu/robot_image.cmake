# The two-leg robot's firmware image (issue 9, section 4), included by CMakeLists.txt
# when the build's capacities hold models/robot.toml (LEGSIM_HAS_ROBOT: the preset
# cortex-m7-robot, 13 bodies, 16 joints, 4 actuators, 2 forces, 2 contacts). Built
# beside the leg's image, with the same runtime, linker script, heap traps and size
# report; robot_report.c runs the compiled-in robot (feet stuck) and prints it.
#
#   robot_m7.elf  (mps2-an500; robot_m4f.elf on mps2-an386 if a float build held it)
#   cmake --build --preset cortex-m7-robot --target robot_m7_qemu
string(REPLACE "leg_" "robot_" legsim_mcu_robot_image "${legsim_mcu_image}")

add_executable(${legsim_mcu_robot_image} robot_main.c robot_report.c)
set_target_properties(${legsim_mcu_robot_image} PROPERTIES SUFFIX .elf LINKER_LANGUAGE CXX)
target_compile_definitions(${legsim_mcu_robot_image} PRIVATE
  LEGSIM_MCU_BOARD="${legsim_mcu_board}" LEGSIM_MCU_CPU="${legsim_mcu_cpu}"
  LEGSIM_MCU_STORAGE_BYTES=${LEGSIM_MCU_STORAGE_BYTES})
target_compile_options(${legsim_mcu_robot_image} PRIVATE -Wall -Wextra)
target_link_libraries(${legsim_mcu_robot_image} PRIVATE legsim_mcu_rt legsim_models legsim_core m)
target_link_options(${legsim_mcu_robot_image} PRIVATE
  -nostartfiles
  -T${CMAKE_CURRENT_SOURCE_DIR}/${legsim_mcu_ld}
  -L${CMAKE_CURRENT_SOURCE_DIR}
  LINKER:--defsym=__stack_size=${LEGSIM_MCU_STACK_BYTES}
  LINKER:-Map=$<TARGET_FILE_DIR:${legsim_mcu_robot_image}>/${legsim_mcu_robot_image}.map
  LINKER:--print-memory-usage
  ${legsim_mcu_wraps})
set_property(TARGET ${legsim_mcu_robot_image} APPEND PROPERTY LINK_DEPENDS
  ${CMAKE_CURRENT_SOURCE_DIR}/${legsim_mcu_ld} ${CMAKE_CURRENT_SOURCE_DIR}/cortex_m_sections.ld)

if(LEGSIM_ARM_SIZE)
  add_custom_command(TARGET ${legsim_mcu_robot_image} POST_BUILD
    COMMAND ${LEGSIM_ARM_SIZE} $<TARGET_FILE:${legsim_mcu_robot_image}>
    COMMENT "Size of ${legsim_mcu_robot_image}.elf (${legsim_mcu_board}, ${legsim_mcu_cpu})"
    VERBATIM)
endif()
if(LEGSIM_QEMU_SYSTEM_ARM)
  add_custom_target(${legsim_mcu_robot_image}_qemu
    COMMAND ${LEGSIM_QEMU_SYSTEM_ARM} -M ${legsim_mcu_board} -nographic -monitor none
            -serial none -semihosting-config enable=on,target=native -icount shift=0
            -kernel $<TARGET_FILE:${legsim_mcu_robot_image}>
    DEPENDS ${legsim_mcu_robot_image}
    USES_TERMINAL
    COMMENT "Running ${legsim_mcu_robot_image}.elf on QEMU ${legsim_mcu_board}"
    VERBATIM)
endif()

# What tests/mcu looks at (mcu_test.py --manifest legsim_mcu_robot_manifest.txt)
file(GENERATE OUTPUT ${CMAKE_BINARY_DIR}/legsim_mcu_robot_manifest.txt CONTENT
"board=${legsim_mcu_board}
cpu=${legsim_mcu_cpu}
image=$<TARGET_FILE:${legsim_mcu_robot_image}>
lib_core=$<TARGET_FILE:legsim_core>
lib_models=$<TARGET_FILE:legsim_models>
nm=${CMAKE_NM}
size=${LEGSIM_ARM_SIZE}
use_float=${LEGSIM_USE_FLOAT}
")
