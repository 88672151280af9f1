/* The leg in MuJoCo for the work-precision benchmark (workprecision.py writes the MJCF with
 * peers/mujoco_leg.build_xml, builds this against the mujoco wheel's own libmujoco and
 * headers, and runs it).
 *
 *   mujoco_wp traj  MODEL.xml T FU FL SAMPLE_DT   qpos at t = 0, SAMPLE_DT, ..., T
 *   mujoco_wp time  MODEL.xml T FU FL REPS        wall time of the T-second run
 *   mujoco_wp count MODEL.xml T FU FL NSTEPS      NSTEPS steps, for callgrind
 *
 * The step h, the integrator and the solver settings are in the MJCF. ctrl = (FU, FL), the
 * axial forces (N) of the two motors. Set-up (mj_loadXML, mj_makeData, mj_resetData, ctrl)
 * happens outside run_steps(), the only function timed and the only one callgrind counts,
 * as in legsim_wp.c. A step that sets MuJoCo's bad-acceleration warning is a failure
 * (stderr, exit 3). */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "wp_common.h"

#include <mujoco/mujoco.h>

/* The timed and counted work: n steps. Not static, not inlined: callgrind finds it by name. */
__attribute__((noinline)) void run_steps(const mjModel *m, mjData *d, int n) {
  for (int k = 0; k < n; ++k) mj_step(m, d);
}

static void reset(const mjModel *m, mjData *d, double fu, double fl) {
  mj_resetData(m, d);
  d->ctrl[0] = fu;
  d->ctrl[1] = fl;
}

static void check(const mjData *d) {
  if (d->warning[mjWARN_BADQACC].number > 0) {
    fprintf(stderr, "mujoco_wp: bad acceleration near t = %g s\n", d->time);
    exit(3);
  }
}

int main(int argc, char **argv) {
  if (argc != 7) {
    fprintf(stderr, "usage: mujoco_wp traj|time|count MODEL.xml T FU FL X\n");
    return 2;
  }
  char err[1000] = "";
  mjModel *m = mj_loadXML(argv[2], NULL, err, sizeof err);
  if (!m) {
    fprintf(stderr, "mujoco_wp: %s: %s\n", argv[2], err);
    return 2;
  }
  mjData *d = mj_makeData(m);
  const double h = m->opt.timestep, t_end = atof(argv[3]), fu = atof(argv[4]), fl = atof(argv[5]);
  const int n = steps_of("mujoco_wp", t_end, h);

  if (strcmp(argv[1], "traj") == 0) {
    const int every = steps_of("mujoco_wp", atof(argv[6]), h);
    reset(m, d, fu, fl);
    for (int k = 0; k <= n; k += every) {
      if (k > 0) run_steps(m, d, every);
      check(d);
      printf("%.17g", k * h);
      for (int i = 0; i < m->nq; ++i) printf(" %.17g", d->qpos[i]);
      printf("\n");
    }
  } else if (strcmp(argv[1], "time") == 0) {
    const int reps = atoi(argv[6]);
    double best = 1e300, sum = 0;
    for (int r = 0; r < reps; ++r) {
      reset(m, d, fu, fl);
      const double t0 = now_s();
      run_steps(m, d, n);
      const double w = now_s() - t0;
      check(d);
      best = w < best ? w : best;
      sum += w;
    }
    printf("%.9g %.9g %d\n", best, sum / reps, n);
  } else if (strcmp(argv[1], "count") == 0) {
    const int k = atoi(argv[6]) < n ? atoi(argv[6]) : n;
    reset(m, d, fu, fl);
    run_steps(m, d, k);
    check(d);
    printf("%d\n", k);
  } else {
    fprintf(stderr, "mujoco_wp: unknown mode %s\n", argv[1]);
    return 2;
  }
  mj_deleteData(d);
  mj_deleteModel(m);
  return 0;
}
