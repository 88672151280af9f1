/* Cost of a step of the two-leg robot beside the one leg (issue 9, section 8).
 *
 *   robot_step_cost MODEL INTEGRATOR N
 *     MODEL       leg | robot      (the compiled-in models)
 *     INTEGRATOR  rk4 | galpha     (h = 1 ms)
 *     N           steps to run
 *
 * The leg: 50 N on the upper actuator, the lower passive. The robot: both feet stuck on
 * the ground (its stand pose), three actuators held by their servos at the stand lengths,
 * the right upper at 185.55 N (its hold force + 50 N, the Fig. 7 Scene A push).
 * Instructions per step: run under valgrind twice with different N and take the
 * difference (firmware_core/benchmarks/results.md shows the commands); only run_steps()
 * is counted (--toggle-collect=run_steps). */
#include <stdio.h>
#include <string.h>
#include <stdlib.h>

#include "legsim/legsim.h"
#include "legsim/models.h"
#if __has_include("legsim/robot_models.h")
#include "legsim/robot_models.h"
#define HAVE_ROBOT 1
#endif

static _Alignas(LEGSIM_STORAGE_ALIGN) unsigned char storage[128 * 1024];

__attribute__((noinline)) legsim_status run_steps(legsim_sim *sim, int32_t n) { return legsim_step(sim, n); }

int main(int argc, char **argv) {
  if (argc != 4 || (strcmp(argv[2], "rk4") && strcmp(argv[2], "galpha"))) {
    fprintf(stderr, "usage: robot_step_cost leg|robot rk4|galpha N\n");
    return 2;
  }
  const int robot = strcmp(argv[1], "robot") == 0;
  const long n = strtol(argv[3], NULL, 10);
  if (n < 1 || n > 10000000) {
    fprintf(stderr, "robot_step_cost: N must be in 1..1e7\n");
    return 2;
  }
  const legsim_model_desc *model = &legsim_model_leg_revolute;
  if (robot) {
#ifdef HAVE_ROBOT
    model = &legsim_model_robot_revolute;
#else
    fprintf(stderr, "robot_step_cost: this build's capacities do not hold the robot\n");
    return 2;
#endif
  }
  legsim_options opt = legsim_default_options();
  opt.integrator = strcmp(argv[2], "rk4") == 0 ? LEGSIM_INTEGRATOR_RK4 : LEGSIM_INTEGRATOR_GENERALIZED_ALPHA;
  legsim_sim *sim;
  legsim_status st = legsim_init(storage, sizeof storage, model, &opt, &sim);
  if (st == LEGSIM_OK) st = legsim_assemble_pose(sim, 0);
  if (st == LEGSIM_OK && robot) {
    legsim_real len[4], rate[4];
    st = legsim_actuator_lengths(sim, len, rate);
    for (int a = 1; a < 4 && st == LEGSIM_OK; ++a) st = legsim_command_length(sim, a, len[a]);
    if (st == LEGSIM_OK) st = legsim_command_force(sim, 0, 185.55);
  } else if (st == LEGSIM_OK) {
    st = legsim_command_force(sim, 0, 50.0);
  }
  if (st == LEGSIM_OK) st = run_steps(sim, (int32_t)n);
  printf("%s %s: %ld steps, status %s, t = %g s\n", argv[1], argv[2], n, legsim_status_str(st),
         legsim_time(sim));
  return st == LEGSIM_OK ? 0 : 1;
}
