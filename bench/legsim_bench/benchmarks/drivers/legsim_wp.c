/* The leg in legsim for the work-precision benchmark (workprecision.py builds and runs it).
 *
 *   legsim_wp traj  INTEG H T FU FL DISABLE TOL SAMPLE_DT   q at t = 0, SAMPLE_DT, ..., T
 *   legsim_wp time  INTEG H T FU FL DISABLE TOL REPS        wall time of the T-second run
 *   legsim_wp count INTEG H T FU FL DISABLE TOL NSTEPS      NSTEPS steps, for callgrind
 *
 * INTEG rk4 | galpha; H step (s); T end time (s); FU, FL constant axial forces on the
 * upper and lower actuators (N); DISABLE legsim_disable flags; TOL newton_tol.
 * The compiled-in model legsim_model_leg_revolute from the stand pose at rest.
 * Set-up (legsim_init, assembly, commands) happens outside run_steps(), the only
 * function timed and the only one callgrind counts (--toggle-collect=run_steps),
 * as in mujoco_wp.c. Output: lines of numbers on stdout; errors on stderr, exit 3. */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "wp_common.h"

#include "legsim/legsim.h"

extern const legsim_model_desc legsim_model_leg_revolute;

static _Alignas(16) unsigned char storage[64 * 1024];

typedef struct {
  legsim_options opt;
  double fu, fl;
} setup;

static legsim_sim *start(const setup *s) {
  legsim_sim *sim;
  legsim_status st = legsim_init(storage, sizeof storage, &legsim_model_leg_revolute, &s->opt, &sim);
  if (st == LEGSIM_OK) st = legsim_assemble_pose(sim, 0);
  if (st == LEGSIM_OK) st = legsim_command_force(sim, 0, (legsim_real)s->fu);
  if (st == LEGSIM_OK) st = legsim_command_force(sim, 1, (legsim_real)s->fl);
  if (st != LEGSIM_OK) {
    fprintf(stderr, "legsim_wp: set-up: %s\n", legsim_status_str(st));
    exit(3);
  }
  return sim;
}

/* The timed and counted work: n steps. Not static, not inlined: callgrind finds it by name. */
__attribute__((noinline)) legsim_status run_steps(legsim_sim *sim, int n) { return legsim_step(sim, n); }

static void check(legsim_status st, double t) {
  if (st != LEGSIM_OK) {
    fprintf(stderr, "legsim_wp: step failed near t = %g s: %s\n", t, legsim_status_str(st));
    exit(3);
  }
}

int main(int argc, char **argv) {
  if (argc != 10) {
    fprintf(stderr, "usage: legsim_wp traj|time|count rk4|galpha H T FU FL DISABLE TOL X\n");
    return 2;
  }
  setup s;
  s.opt = legsim_default_options();
  if (strcmp(argv[2], "rk4") == 0) s.opt.integrator = LEGSIM_INTEGRATOR_RK4;
  else if (strcmp(argv[2], "galpha") == 0) s.opt.integrator = LEGSIM_INTEGRATOR_GENERALIZED_ALPHA;
  else { fprintf(stderr, "legsim_wp: unknown integrator %s\n", argv[2]); return 2; }
  s.opt.step_s = atof(argv[3]);
  const double t_end = atof(argv[4]);
  s.fu = atof(argv[5]);
  s.fl = atof(argv[6]);
  s.opt.disable = (uint32_t)strtoul(argv[7], NULL, 0);
  s.opt.newton_tol = atof(argv[8]);
  const double h = s.opt.step_s;
  const int n = steps_of("legsim_wp", t_end, h);

  if (strcmp(argv[1], "traj") == 0) {
    const int every = steps_of("legsim_wp", atof(argv[9]), h);
    legsim_sim *sim = start(&s);
    legsim_real q[18];
    for (int k = 0; k <= n; k += every) {
      if (k > 0) check(run_steps(sim, every), k * h);
      legsim_get_q(sim, q);
      printf("%.17g", k * h);
      for (int i = 0; i < 18; ++i) printf(" %.17g", (double)q[i]);
      printf("\n");
    }
  } else if (strcmp(argv[1], "time") == 0) {
    const int reps = atoi(argv[9]);
    double best = 1e300, sum = 0;
    for (int r = 0; r < reps; ++r) {
      legsim_sim *sim = start(&s);
      const double t0 = now_s();
      const legsim_status st = run_steps(sim, n);
      const double w = now_s() - t0;
      check(st, t_end);
      best = w < best ? w : best;
      sum += w;
    }
    printf("%.9g %.9g %d\n", best, sum / reps, n);
  } else if (strcmp(argv[1], "count") == 0) {
    const int m = atoi(argv[9]);
    legsim_sim *sim = start(&s);
    check(run_steps(sim, m < n ? m : n), t_end);
    printf("%d\n", m < n ? m : n);
  } else {
    fprintf(stderr, "legsim_wp: unknown mode %s\n", argv[1]);
    return 2;
  }
  return 0;
}
