/* The host twin of the firmware images: the same leg report (firmware_core/mcu/
 * leg_report.c) against the host build of the core, printed to stdout. The MCU
 * tests compare the images' numbers with these. */
#include <stdio.h>

#include "leg_report.h"
#include "legsim/legsim.h"
#include "out.h"

void out_sink(const char *s) { fputs(s, stdout); }

/* the host capacities are larger than the leg's; legsim_sim_size() is checked */
static unsigned char storage[1 << 17] __attribute__((aligned(LEGSIM_STORAGE_ALIGN)));

int main(void) {
  static const leg_report_platform platform = {"host", "host", NULL, NULL, 0};
  const int status = leg_report_run(storage, sizeof storage, &platform);
  out_flush();
  fflush(stdout);
  return status;
}
