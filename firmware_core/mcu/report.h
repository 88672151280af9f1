/* The MCU report shared by the leg and the two-leg robot (leg_report.h, robot_report.h
 * give each one's output lines): through the C API only, init a compiled-in model in
 * caller storage, put it in its stand and print it, then run each integrator from
 * there, printing q, the model's own lines (the leg's foot, the robot's contacts) and
 * the instructions per step. A model's differences are the few hooks of report_model.
 *
 * "insns" come from a timer read around each call; they count instructions only
 * when the platform's timer runs 1 tick per insns_per_tick instructions (QEMU's
 * -icount shift=0); a platform without a timer prints 0. */
#ifndef LEGSIM_MCU_REPORT_H
#define LEGSIM_MCU_REPORT_H

#include <stddef.h>
#include <stdint.h>

#include "legsim/legsim.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct report_platform {
  const char *board;                 /* e.g. "mps2-an386" */
  const char *cpu;                   /* e.g. "cortex-m4f" */
  void (*timer_start)(void);         /* NULL: no timer */
  uint32_t (*timer_ticks)(void);
  uint32_t insns_per_tick;
} report_platform;

typedef struct report_model {
  const legsim_model_desc *model;
  int32_t steps;                     /* steps of each integrator */
  int model_line_contacts;           /* nonzero: the model line ends " contacts <n>" */
  /* the stand, timed and printed ("stand status ..."); its name in a failure line */
  legsim_status (*stand)(legsim_sim *sim);
  const char *stand_name;
  /* before each integrator's steps: from the stand at rest, t = 0, plus any
   * commands; prints its own failure line and returns 1 on one, else 0 */
  int (*start)(legsim_sim *sim);
  /* after the q lines of "<prefix> q ..." (stand and each integrator) */
  void (*print_state)(const char *prefix, const legsim_sim *sim);
  /* after the stand's state lines; NULL: none */
  void (*print_stand)(const legsim_sim *sim);
} report_model;

/* Returns 0 (all calls LEGSIM_OK), 1 (a legsim call failed) or 2 (storage too
 * small for legsim_sim_size()). */
int report_run(void *storage, size_t storage_bytes, const report_platform *pf,
               const report_model *model);

/* For the hooks: "<what> failed: <status> (<n>)" unless s is LEGSIM_OK; 1 if printed */
int report_failed(const char *what, legsim_status s);
/* a legsim_real in the build's precision's decimals */
void report_real(double v);

#ifdef __cplusplus
}
#endif
#endif
