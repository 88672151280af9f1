/* The firmware image for QEMU's MPS2 boards: one report (report.h) printed through
 * semihosting; QEMU exits with its status. LEGSIM_MCU_REPORT names the report:
 * leg_report (leg_m4f.elf, leg_m7.elf) or robot_report (robot_m7.elf).
 *
 *   qemu-system-arm -M mps2-an386 -nographic -monitor none -serial none \
 *     -semihosting-config enable=on,target=native -icount shift=0 -kernel leg_m4f.elf
 *
 * LEGSIM_MCU_BOARD / LEGSIM_MCU_CPU / LEGSIM_MCU_STORAGE_BYTES and LEGSIM_MCU_REPORT come
 * from CMake (legsim_mcu_image in CMakeLists.txt). */
#include "legsim/legsim.h"
#include "leg_report.h"
#include "robot_report.h"
#include "mcu_runtime.h"
#include "out.h"

/* The solver's whole state: static, sized at build time, checked at run time
 * against legsim_sim_size(). */
static unsigned char storage[LEGSIM_MCU_STORAGE_BYTES]
    __attribute__((aligned(LEGSIM_STORAGE_ALIGN)));

int main(void) {
  static const report_platform platform = {
      LEGSIM_MCU_BOARD, LEGSIM_MCU_CPU, mcu_timer_start, mcu_timer_ticks, MCU_INSNS_PER_TICK};
  const int status = report_run(storage, sizeof storage, &platform, &LEGSIM_MCU_REPORT);
  out_str("stack used ");
  out_uint(mcu_stack_used());
  out_str(" of ");
  out_uint(mcu_stack_size());
  out_char('\n');
  return status;
}
