/* The robot report: what the Cortex-M7 two-leg image (main.c, preset
 * cortex-m7-robot) and its host twin (tests/mcu/report_host.c) run, the shared report
 * (report.h) with the robot's hooks, through the C API only: the compiled-in
 * models/robot.toml in caller storage, its stand put on the ground (legsim_assemble_pose
 * "stand", then legsim_assemble_on_ground), printed,
 * then ROBOT_REPORT_STEPS steps of each integrator from it with both feet stuck: the
 * Fig. 7 Scene A commands (right upper actuator at its hold force + 50 N = 185.55 N,
 * the other three held by their servos at the stand lengths), printing q, the feet's
 * contacts and the instructions per step.
 *
 * Output lines (parsed by tests/mcu/mcu_test.py), numbers in plain decimal:
 *   legsim-mcu board <b> cpu <c> real <float|double>
 *   sim_size <bytes> storage <bytes>
 *   model <name> bodies <n> coords <n> constraints <n> actuators <n> contacts <n>
 *   stand status <s> iterations <n> residual <r> insns <n>
 *   stand q <body> <x> <y> <phi>                   (one line per body, 0-based)
 *   stand contact <name> <state> <N> <T> <x> <y>   (state 0 free, 1 stuck, 2 sliding)
 *   step <integrator> status <s> steps <n> t <t>
 *   step <integrator> q <body> <x> <y> <phi>
 *   step <integrator> contact <name> <state> <N> <T> <x> <y>
 *   step <integrator> insns_per_step mean <n> min <n> max <n>
 *   done status <s>
 * "insns" as in report.h (QEMU -icount shift=0; 0 without a timer). */
#ifndef LEGSIM_MCU_ROBOT_REPORT_H
#define LEGSIM_MCU_ROBOT_REPORT_H

#include "report.h"

#ifdef __cplusplus
extern "C" {
#endif

#define ROBOT_REPORT_STEPS 50

/* report_run(storage, bytes, platform, &robot_report) */
extern const report_model robot_report;

#ifdef __cplusplus
}
#endif
#endif
