/* The host twin of the firmware images: the same report (firmware_core/mcu/report.c
 * with LEGSIM_MCU_REPORT's hooks: leg_report.c or robot_report.c) against the host
 * build of the core, printed to stdout. The MCU tests compare the images' numbers
 * with these. */
#include <stdio.h>

#include "legsim/legsim.h"
#include "leg_report.h"
#include "robot_report.h"
#include "out.h"

void out_sink(const char *s) { fputs(s, stdout); }

/* the host capacities are at least the leg's and the robot's; legsim_sim_size() is checked */
static unsigned char storage[1 << 17] __attribute__((aligned(LEGSIM_STORAGE_ALIGN)));

int main(void) {
  static const report_platform platform = {"host", "host", NULL, NULL, 0};
  const int status = report_run(storage, sizeof storage, &platform, &LEGSIM_MCU_REPORT);
  out_flush();
  fflush(stdout);
  return status;
}
