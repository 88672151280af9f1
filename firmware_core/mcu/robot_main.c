/* The two-leg robot's firmware image (preset cortex-m7-robot, QEMU mps2-an500): the
 * robot report (robot_report.h) printed through semihosting; QEMU exits with its status.
 *
 *   qemu-system-arm -M mps2-an500 -nographic -monitor none -serial none \
 *     -semihosting-config enable=on,target=native -icount shift=0 -kernel robot_m7.elf
 *
 * LEGSIM_MCU_BOARD / LEGSIM_MCU_CPU / LEGSIM_MCU_STORAGE_BYTES come from CMake. */
#include "legsim/legsim.h"
#include "robot_report.h"
#include "mcu_runtime.h"
#include "out.h"

/* The solver's whole state: static, sized at build time, checked at run time
 * against legsim_sim_size(). */
static unsigned char storage[LEGSIM_MCU_STORAGE_BYTES]
    __attribute__((aligned(LEGSIM_STORAGE_ALIGN)));

int main(void) {
  static const leg_report_platform platform = {
      LEGSIM_MCU_BOARD, LEGSIM_MCU_CPU, mcu_timer_start, mcu_timer_ticks, MCU_INSNS_PER_TICK};
  const int status = robot_report_run(storage, sizeof storage, &platform);
  out_str("stack used ");
  out_uint(mcu_stack_used());
  out_str(" of ");
  out_uint(mcu_stack_size());
  out_char('\n');
  return status;
}
