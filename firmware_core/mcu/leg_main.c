/* The firmware image for QEMU's MPS2 boards: the leg report (leg_report.h)
 * printed through semihosting; QEMU exits with its status.
 *
 *   qemu-system-arm -M mps2-an386 -nographic -monitor none -serial none \
 *     -semihosting-config enable=on,target=native -icount shift=0 -kernel leg_m4f.elf
 *
 * LEGSIM_MCU_BOARD / LEGSIM_MCU_CPU / LEGSIM_MCU_STORAGE_BYTES come from CMake. */
#include "legsim/legsim.h"
#include "leg_report.h"
#include "mcu_runtime.h"
#include "out.h"

/* The solver's whole state: static, sized at build time, checked at run time
 * against legsim_sim_size(). */
static unsigned char storage[LEGSIM_MCU_STORAGE_BYTES]
    __attribute__((aligned(LEGSIM_STORAGE_ALIGN)));

int main(void) {
  static const leg_report_platform platform = {
      LEGSIM_MCU_BOARD, LEGSIM_MCU_CPU, mcu_timer_start, mcu_timer_ticks, MCU_INSNS_PER_TICK};
  const int status = leg_report_run(storage, sizeof storage, &platform);
  out_str("stack used ");
  out_uint(mcu_stack_used());
  out_str(" of ");
  out_uint(mcu_stack_size());
  out_char('\n');
  return status;
}
