/* The leg report: what the MCU images (and the host twin in tests/mcu) run, the
 * shared report (report.h) with the leg's hooks. Through the C API only: init in
 * caller storage, assemble the stand pose, print it, then LEG_REPORT_STEPS steps
 * of each integrator from it (free fall: actuators in force mode at 0 N),
 * printing q, the foot and the instructions per step.
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
 * "insns" as in report.h (QEMU -icount shift=0; 0 without a timer). */
#ifndef LEGSIM_MCU_LEG_REPORT_H
#define LEGSIM_MCU_LEG_REPORT_H

#include "report.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LEG_REPORT_STEPS 100

/* report_run(storage, bytes, platform, &leg_report) */
extern const report_model leg_report;

#ifdef __cplusplus
}
#endif
#endif
