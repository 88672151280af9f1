/* The leg report: what the MCU images (and the host twin in tests/mcu) run.
 * Through the C API only: init in caller storage, assemble the stand pose,
 * print it, then 100 steps of each integrator from it (free fall: actuators in
 * force mode at 0 N), printing q, the foot and the instructions per step.
 *
 * Output lines (parsed by tests/mcu/mcu_test.py), numbers in plain decimal:
 *   legsim-mcu board <b> cpu <c> real <float|double>
 *   sim_size <bytes> storage <bytes>
 *   model <name> bodies <n> coords <n> constraints <n> actuators <n>
 *   stand status <s> iterations <n> residual <r> insns <n>
 *   stand q <body> <x> <y> <phi>            (one line per body, 0-based)
 *   stand foot <x> <y>
 *   stand joint <name> <x> <y>              (point[0] of each non-prismatic joint)
 *   step <integrator> status <s> steps <n> t <t>
 *   step <integrator> q <body> <x> <y> <phi>
 *   step <integrator> foot <x> <y>
 *   step <integrator> insns_per_step mean <n> min <n> max <n>
 *   done status <s>
 * "insns" come from a timer read around each call; they count instructions only
 * when the platform's timer runs 1 tick per insns_per_tick instructions (QEMU's
 * -icount shift=0); a platform without a timer prints 0. */
#ifndef LEGSIM_MCU_LEG_REPORT_H
#define LEGSIM_MCU_LEG_REPORT_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct leg_report_platform {
  const char *board;                 /* e.g. "mps2-an386" */
  const char *cpu;                   /* e.g. "cortex-m4f" */
  void (*timer_start)(void);         /* NULL: no timer */
  uint32_t (*timer_ticks)(void);
  uint32_t insns_per_tick;
} leg_report_platform;

/* Returns 0 (all calls LEGSIM_OK), 1 (a legsim call failed) or 2 (storage too
 * small for legsim_sim_size()). */
int leg_report_run(void *storage, size_t storage_bytes, const leg_report_platform *pf);

#ifdef __cplusplus
}
#endif
#endif
