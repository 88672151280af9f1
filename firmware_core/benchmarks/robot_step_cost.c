/* Cost of a step of the two-leg robot beside the one leg, feet stuck and with a slipping
 * foot (issue 9, section 8).
 *
 *   robot_step_cost CASE INTEGRATOR N [REPS]
 *     CASE        leg | leg-loop | robot | robot-slip
 *     INTEGRATOR  rk4 | galpha     (h = 1 ms)
 *     N           steps to run
 *     REPS        also time the N steps REPS times (set-up outside the clock) and print,
 *                 per kind of step, the min over the repetitions of the median us/step
 *
 * leg:        50 N on the upper actuator, the lower passive.
 * leg-loop:   the leg under a controller in the loop: before every step a new force
 *             command for the upper actuator, 50 N + 10 N sin(2 pi 2 t) (a command that
 *             changes restarts the integrators from the accelerations under it: this is
 *             the cost a controller that updates its setpoint every step meets). The
 *             command is part of each step's count.
 * robot:      both feet stuck on level ground (the stand pose put on the ground with
 *             legsim_assemble_on_ground), three actuators held by their servos at the
 *             stand lengths, the right upper at 185.55 N (its hold force + 50 N, the
 *             Fig. 7 Scene A push). Both feet stay stuck (mu_static 0.6).
 * robot-slip: the same on a slippery ground: the compiled-in robot with mu_static =
 *             mu_kinetic = 0.1 (models/robot.toml has 0.6 / 0.5). The push makes the left
 *             foot slip at step 14 (one foot sliding, the right stuck), the right one at
 *             step 56 (both sliding) and a foot lifts off at step 781 (RK4).
 * stand:PATH the robot file PATH (any number of legs), loaded at run time
 *             (legsim_model_load_toml), every foot stuck on the ground
 *             (legsim_assemble_on_ground), every actuator held by its servo at its stand
 *             length, on the general path (legsim_kernel_use(sim, 0): the same path for
 *             any number of legs, whatever kernels the build has): the scaling case.
 *
 * Each step is a kind: "stuck" (no foot sliding; the leg's steps too), "slip1" (one foot
 * sliding, the other stuck), "slip2" (both sliding), each only when the contact states
 * are the same before and after the step, else "change" (an event in the step: its
 * location and the new solve). A first pass records the kinds; a second, identical
 * (deterministic) pass runs each step through the function of its kind,
 * step_stuck / step_slip1 / step_slip2 / step_change, so that valgrind's callgrind
 * gives each kind's instructions as that function's inclusive cost, divided by the
 * count printed here (firmware_core/benchmarks/robot_step_cost.py does it all;
 * results.md). The wall time is measured around each step (two clock_gettime calls,
 * ~50 ns, included); per kind the median of its steps, then the min over repetitions. */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <time.h>

#include "legsim/legsim.h"
#include "legsim/models.h"
#include "model_toml.hpp"
#if __has_include("legsim/robot_models.h")
#include "legsim/robot_models.h"
#define HAVE_ROBOT 1
#endif

enum bench_case { CASE_LEG, CASE_LEG_LOOP, CASE_ROBOT, CASE_ROBOT_SLIP, CASE_STAND };
enum step_kind { KIND_STUCK, KIND_SLIP1, KIND_SLIP2, KIND_CHANGE, N_KINDS };
static const char *const kind_name[N_KINDS] = {"stuck", "slip1", "slip2", "change"};

#define MU_SLIPPERY 0.1
#define MAX_STEPS 100000

static _Alignas(LEGSIM_STORAGE_ALIGN) unsigned char storage[1024 * 1024];
static legsim_model_desc file_model; /* stand:PATH; must outlive the sim */
/* the general path instead of a generated kernel (firmware_core/src/planar/kernel.hpp) */
int legsim_kernel_use(legsim_sim *sim, int on);
#ifdef HAVE_ROBOT
static legsim_model_desc robot_slippery; /* must outlive the sim */
#endif
static unsigned char kinds[MAX_STEPS];
static double step_us[MAX_STEPS], scratch[MAX_STEPS];
static double loop_force_n[MAX_STEPS]; /* leg-loop: step i's command (computed before) */
static int command_every_step;

/* step i, after its command in leg-loop */
static inline legsim_status step_once(legsim_sim *sim, long i) {
  if (command_every_step) {
    const legsim_status st = legsim_command_force(sim, 0, loop_force_n[i]);
    if (st != LEGSIM_OK) return st;
  }
  return legsim_step(sim, 1);
}
/* one function per kind of step: callgrind's inclusive cost of each is that kind's */
__attribute__((noinline)) legsim_status step_stuck(legsim_sim *sim, long i) { return step_once(sim, i); }
__attribute__((noinline)) legsim_status step_slip1(legsim_sim *sim, long i) { return step_once(sim, i); }
__attribute__((noinline)) legsim_status step_slip2(legsim_sim *sim, long i) { return step_once(sim, i); }
__attribute__((noinline)) legsim_status step_change(legsim_sim *sim, long i) { return step_once(sim, i); }
static legsim_status (*const step_of_kind[N_KINDS])(legsim_sim *, long) = {step_stuck, step_slip1, step_slip2,
                                                                           step_change};

/* The case's starting state and commands, at t = 0. */
static legsim_status set_up(enum bench_case c, legsim_integrator integrator, legsim_sim **out) {
  const legsim_model_desc *model = &legsim_model_leg_revolute;
#ifdef HAVE_ROBOT
  if (c == CASE_ROBOT) model = &legsim_model_robot_revolute;
  if (c == CASE_ROBOT_SLIP) {
    robot_slippery = legsim_model_robot_revolute;
    robot_slippery.ground.mu_static = MU_SLIPPERY;
    robot_slippery.ground.mu_kinetic = MU_SLIPPERY;
    model = &robot_slippery;
  }
#endif
  if (c == CASE_STAND) model = &file_model;
  legsim_options opt = legsim_default_options();
  opt.integrator = integrator;
  legsim_sim *sim = NULL;
  legsim_status st = legsim_init(storage, sizeof storage, model, &opt, &sim);
  if (st == LEGSIM_OK) st = legsim_assemble_pose(sim, 0);
  if (st == LEGSIM_OK && c == CASE_STAND) {
    legsim_real len[LEGSIM_MAX_ACTUATORS], rate[LEGSIM_MAX_ACTUATORS];
    if (legsim_kernel_use(sim, 0) < 0) st = LEGSIM_ERR_STATE; /* every robot on the general path */
    if (st == LEGSIM_OK) st = legsim_assemble_on_ground(sim, NULL, 0.0);
    if (st == LEGSIM_OK) st = legsim_actuator_lengths(sim, len, rate);
    for (int32_t a = 0; a < legsim_n_actuators(sim) && st == LEGSIM_OK; ++a) st = legsim_command_length(sim, a, len[a]);
  } else if (st == LEGSIM_OK && c != CASE_LEG && c != CASE_LEG_LOOP) {
    legsim_real len[4], rate[4];
    st = legsim_assemble_on_ground(sim, NULL, 0.0);
    if (st == LEGSIM_OK) st = legsim_actuator_lengths(sim, len, rate);
    for (int a = 1; a < 4 && st == LEGSIM_OK; ++a) st = legsim_command_length(sim, a, len[a]);
    if (st == LEGSIM_OK) st = legsim_command_force(sim, 0, 185.55);
  } else if (st == LEGSIM_OK) {
    st = legsim_command_force(sim, 0, 50.0);
  }
  *out = sim;
  return st;
}

/* contact states as one number (base 3), -1 on error; 0 without contacts */
static int states_code(const legsim_sim *sim, int *n_sliding, int *n_free) {
  legsim_contact k[LEGSIM_CONTACT_SLOTS];
  const int32_t nc = legsim_n_contacts(sim);
  int code = 0;
  *n_sliding = *n_free = 0;
  if (nc > 0 && legsim_contacts(sim, k) != LEGSIM_OK) return -1;
  for (int32_t i = 0; i < nc; ++i) {
    code = 3 * code + (int)k[i].state;
    *n_sliding += k[i].state == LEGSIM_CONTACT_SLIDING;
    *n_free += k[i].state == LEGSIM_CONTACT_FREE;
  }
  return code;
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* The median of the kind's step times: robust to the steps the OS preempted (on a
 * shared machine a mean over many steps takes in other processes' time slices). */
static double median_of_kind(const double *us, long n, int kind) {
  long m = 0;
  for (long i = 0; i < n; ++i)
    if (kinds[i] == kind) scratch[m++] = us[i];
  qsort(scratch, (size_t)m, sizeof scratch[0], cmp_double);
  return m % 2 ? scratch[m / 2] : 0.5 * (scratch[m / 2 - 1] + scratch[m / 2]);
}

int main(int argc, char **argv) {
  if ((argc != 4 && argc != 5) || (strcmp(argv[2], "rk4") && strcmp(argv[2], "galpha"))) {
    fprintf(stderr, "usage: robot_step_cost leg|leg-loop|robot|robot-slip|stand:PATH rk4|galpha N [REPS]\n");
    return 2;
  }
  enum bench_case c;
  if (!strcmp(argv[1], "leg")) c = CASE_LEG;
  else if (!strcmp(argv[1], "leg-loop")) c = CASE_LEG_LOOP;
  else if (!strcmp(argv[1], "robot")) c = CASE_ROBOT;
  else if (!strcmp(argv[1], "robot-slip")) c = CASE_ROBOT_SLIP;
  else if (!strncmp(argv[1], "stand:", 6)) {
    char msg[256];
    c = CASE_STAND;
    if (legsim_model_load_toml(argv[1] + 6, NULL, &file_model, msg, sizeof msg) != LEGSIM_OK) {
      fprintf(stderr, "robot_step_cost: %s\n", msg);
      return 2;
    }
  } else {
    fprintf(stderr, "robot_step_cost: CASE is leg, leg-loop, robot, robot-slip or stand:PATH, not '%s'\n", argv[1]);
    return 2;
  }
#ifndef HAVE_ROBOT
  if (c == CASE_ROBOT || c == CASE_ROBOT_SLIP) {
    fprintf(stderr, "robot_step_cost: this build's capacities do not hold the robot\n");
    return 2;
  }
#endif
  const legsim_integrator integrator =
      strcmp(argv[2], "rk4") == 0 ? LEGSIM_INTEGRATOR_RK4 : LEGSIM_INTEGRATOR_GENERALIZED_ALPHA;
  const long n = strtol(argv[3], NULL, 10);
  const long reps = argc == 5 ? strtol(argv[4], NULL, 10) : 0;
  if (n < 1 || n > MAX_STEPS || (argc == 5 && (reps < 1 || reps > 1000))) {
    fprintf(stderr, "robot_step_cost: N must be in 1..%d, REPS in 1..1000\n", MAX_STEPS);
    return 2;
  }
  command_every_step = c == CASE_LEG_LOOP;
  for (long i = 0; i < n; ++i) loop_force_n[i] = 50.0 + 10.0 * sin(2 * 3.14159265358979 * 2.0 * (double)i * 1e-3);

  /* pass 1: the kind of each step */
  legsim_sim *sim;
  legsim_status st = set_up(c, integrator, &sim);
  long count[N_KINDS] = {0};
  int ns, nf, before = st == LEGSIM_OK ? states_code(sim, &ns, &nf) : -1;
  for (long i = 0; i < n && st == LEGSIM_OK; ++i) {
    int ns1, nf1;
    st = step_once(sim, i);
    const int after = states_code(sim, &ns1, &nf1);
    enum step_kind kd = KIND_CHANGE;
    if (after == before && after >= 0 && nf == 0) kd = ns == 0 ? KIND_STUCK : ns == 1 ? KIND_SLIP1 : KIND_SLIP2;
    kinds[i] = (unsigned char)kd;
    ++count[kd];
    before = after, ns = ns1, nf = nf1;
  }
  if (st != LEGSIM_OK) {
    printf("%s %s: status %s at t = %g s\n", argv[1], argv[2], legsim_status_str(st),
           sim ? legsim_time(sim) : 0.0);
    return 1;
  }

  /* pass 2 (and the timed repetitions): each step through its kind's function */
  double best_us[N_KINDS] = {0};
  for (long r = 0; r < (reps > 0 ? reps : 1); ++r) {
    if ((st = set_up(c, integrator, &sim)) != LEGSIM_OK) break;
    for (long i = 0; i < n && st == LEGSIM_OK; ++i) {
      const double t0 = now_s();
      st = step_of_kind[kinds[i]](sim, i);
      step_us[i] = 1e6 * (now_s() - t0);
    }
    for (int k = 0; k < N_KINDS; ++k) {
      if (!count[k]) continue;
      const double us = median_of_kind(step_us, n, k);
      if (r == 0 || us < best_us[k]) best_us[k] = us;
    }
  }
  printf("%s %s: %ld steps, status %s, t = %g s; steps by kind:", argv[1], argv[2], n,
         legsim_status_str(st), legsim_time(sim));
  for (int k = 0; k < N_KINDS; ++k) printf(" %s %ld", kind_name[k], count[k]);
  printf("\n");
  if (reps > 0) {
    printf("%s %s: wall us/step, min over %ld repetitions of each kind's median:", argv[1], argv[2], reps);
    for (int k = 0; k < N_KINDS; ++k)
      if (count[k]) printf(" %s %.3f", kind_name[k], best_us[k]);
    printf("\n");
  }
  return st == LEGSIM_OK ? 0 : 1;
}
