/* Desktop cost of one step and the accuracy it buys: for each integrator at
 * h = 1 ms, the median time per step over repeated 1000-step runs (free fall
 * from the stand pose, reactions on), and the position error at t = 0.1 s
 * against the project's own high-accuracy run (RK4 at h = 1e-5 s).
 * Run: build/host/firmware_core/benchmarks/step_timing [repetitions] */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "legsim/legsim.h"
#include "legsim/models.h"

static _Alignas(16) unsigned char storage[64 * 1024];

static legsim_sim *stand(legsim_integrator integ, double h, uint32_t disable) {
  legsim_options o = legsim_default_options();
  o.integrator = integ;
  o.step_s = h;
  o.disable = disable;
  legsim_sim *sim;
  if (legsim_init(storage, sizeof storage, &legsim_model_leg_revolute, &o, &sim) != LEGSIM_OK ||
      legsim_assemble_pose(sim, 0) != LEGSIM_OK) {
    fprintf(stderr, "step_timing: cannot set up the stand pose\n");
    exit(1);
  }
  return sim;
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static int cmp(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static void free_fall(legsim_integrator integ, double h, legsim_real *q) {
  legsim_sim *sim = stand(integ, h, 0);
  const int n = (int)(0.1 / h + 0.5);
  if (legsim_step(sim, n) != LEGSIM_OK) {
    fprintf(stderr, "step_timing: free fall failed\n");
    exit(1);
  }
  legsim_get_q(sim, q);
}

int main(int argc, char **argv) {
  const int reps = argc > 1 ? atoi(argv[1]) : 200;
  const char *names[2] = {"rk4 (index-1, projected)", "generalized-alpha (index-3)"};
  legsim_real ref[18], q[18];
  free_fall(LEGSIM_INTEGRATOR_RK4, 1e-5, ref);
  printf("| integrator | h (s) | median us/step | p10-p90 us/step | max position error at 0.1 s (m, rad) |\n");
  printf("|---|---|---|---|---|\n");
  double *t = malloc(sizeof(double) * (size_t)reps); /* the benchmark's own buffer, not the solver's */
  for (int integ = 0; integ < 2; ++integ) {
    legsim_sim *sim = stand((legsim_integrator)integ, 1e-3, 0);
    for (int r = 0; r < reps; ++r) {
      legsim_assemble_pose(sim, 0);
      const double t0 = now_s();
      const legsim_status s = legsim_step(sim, 100);
      t[r] = (now_s() - t0) / 100 * 1e6;
      if (s != LEGSIM_OK) {
        fprintf(stderr, "step_timing: %s\n", legsim_status_str(s));
        return 1;
      }
    }
    qsort(t, (size_t)reps, sizeof *t, cmp);
    free_fall((legsim_integrator)integ, 1e-3, q);
    double err = 0;
    for (int k = 0; k < 18; ++k) err = fmax(err, fabs((double)q[k] - (double)ref[k]));
    printf("| %s | 1e-3 | %.2f | %.2f-%.2f | %.2e |\n", names[integ], t[reps / 2], t[reps / 10],
           t[reps * 9 / 10], err);
  }
  free(t);
  return 0;
}
