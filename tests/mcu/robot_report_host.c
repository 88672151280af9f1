/* The host twin of the two-leg robot's firmware image: the same robot report
 * (firmware_core/mcu/robot_report.c) against the host build of the core, printed to
 * stdout. The MCU test mcu_qemu_cortex-m7-robot compares the image's numbers with these. */
#include <stdio.h>

#include "legsim/legsim.h"
#include "out.h"
#include "robot_report.h"

void out_sink(const char *s) { fputs(s, stdout); }

/* the host capacities are at least the robot's; legsim_sim_size() is checked */
static unsigned char storage[1 << 17] __attribute__((aligned(LEGSIM_STORAGE_ALIGN)));

int main(void) {
  static const leg_report_platform platform = {"host", "host", NULL, NULL, 0};
  const int status = robot_report_run(storage, sizeof storage, &platform);
  out_flush();
  fflush(stdout);
  return status;
}
