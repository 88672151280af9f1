/* The hexapod's cost per step (issue 24, section 5), for robot_step_cost.py --hexapod: the robot
 * of models/hexapod.toml at its legs' stand, the box 1 m up, its feet on the ground, standing on a
 * tripod (legs 0, 2, 4 stuck, the other three free, their upper actuators 3 cm shorter: their
 * feet 8.6 cm up) or on six feet, under its statics' commands with 20 N more on
 * every upper actuator (so that it moves), stepped at h = 1 ms through legsim_hexapod_step.
 *
 *     hexapod_step_cost CASE INTEGRATOR STEPS [REPS]     CASE: tripod | six; INTEGRATOR: rk4 | galpha
 *
 * Prints robot_step_cost's lines: the count of steps of each kind (all "stuck": the feet held)
 * and, with REPS, the min over REPS repetitions of the median step's wall time. Runs from the
 * source tree's root (the model file's path). With HEXAPOD_STATE set in the environment it also
 * prints every body's pose, the box's velocity and the feet's forces at the end to 17 digits
 * (to compare two builds' trajectories). */
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>

#include "legsim/hexapod.h"
#include "legsim/legsim.h"
#include "model_toml.hpp"

#define MAX_STEPS 100000
alignas(LEGSIM_STORAGE_ALIGN) static unsigned char storage[4 * 1024 * 1024];
alignas(LEGSIM_STORAGE_ALIGN) static unsigned char work[4 * 1024 * 1024];
static legsim_hexapod_desc desc;
static double step_us[MAX_STEPS];

static double now_s(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}
static int cmp(const void *a, const void *b) {
  const double x = *static_cast<const double *>(a), y = *static_cast<const double *>(b);
  return (x > y) - (x < y);
}

/* callgrind's inclusive cost of this function over the count of steps is a step's */
__attribute__((noinline)) legsim_status step_stuck(legsim_hexapod_sim *sim) { return legsim_hexapod_step(sim, 1e-3, 1); }

static legsim_status set_up(uint32_t stance, legsim_integrator integrator, legsim_hexapod_sim **out) {
  legsim_sim *leg = NULL;
  legsim_options opt = legsim_default_options();
  legsim_status st = legsim_init(work, sizeof work, &desc.leg[0].leg, &opt, &leg);
  legsim_real len[LEGSIM_MAX_ACTUATORS];
  if (st == LEGSIM_OK) st = legsim_assemble_pose(leg, 0);
  if (st == LEGSIM_OK) st = legsim_actuator_lengths(leg, len, NULL);
  if (st != LEGSIM_OK) return st;
  legsim_hexapod_pose pose = {{0, 0, 1.0}, {1, 0, 0, 0}, {0.1, 0, -0.1, 0.1, 0, -0.1}, {}};
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l) {
    const bool lift = !((stance >> l) & 1u);
    pose.length_m[l][0] = len[0] - (lift ? 0.03 : 0.0), pose.length_m[l][1] = len[1];
  }
  legsim_hexapod_standing s;
  st = legsim_hexapod_statics(&desc, &pose, stance, NULL, work, sizeof work, &s);
  if (st == LEGSIM_OK) st = legsim_hexapod_sim_init(storage, sizeof storage, &desc, &pose, stance, out);
  if (st == LEGSIM_OK) st = legsim_hexapod_set_integrator(*out, integrator);
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l) s.actuator_force_n[l][0] += 20.0;
  if (st == LEGSIM_OK) st = legsim_hexapod_command(*out, s.actuator_force_n, s.rowing_torque_nm);
  return st;
}

int main(int argc, char **argv) {
  if (argc < 4 || (strcmp(argv[1], "tripod") && strcmp(argv[1], "six")) ||
      (strcmp(argv[2], "rk4") && strcmp(argv[2], "galpha"))) {
    fprintf(stderr, "usage: hexapod_step_cost tripod|six rk4|galpha STEPS [REPS]\n");
    return 2;
  }
  const long n = atol(argv[3]), reps = argc > 4 ? atol(argv[4]) : 0;
  if (n < 1 || n > MAX_STEPS) return 2;
  char msg[512];
  legsim_status st = legsim_hexapod_load_toml("models/hexapod.toml", &desc, msg, sizeof msg);
  if (st != LEGSIM_OK) {
    fprintf(stderr, "%s\n", msg);
    return 1;
  }
  const uint32_t stance = strcmp(argv[1], "six") ? 0x15u : 0x3Fu;
  double best = 0;
  legsim_hexapod_sim *sim = NULL;
  for (long r = 0; r < (reps > 0 ? reps : 1) && st == LEGSIM_OK; ++r) {
    st = set_up(stance, strcmp(argv[2], "rk4") ? LEGSIM_INTEGRATOR_GENERALIZED_ALPHA : LEGSIM_INTEGRATOR_RK4, &sim);
    for (long i = 0; i < n && st == LEGSIM_OK; ++i) {
      const double t0 = now_s();
      st = step_stuck(sim);
      step_us[i] = 1e6 * (now_s() - t0);
    }
    qsort(step_us, size_t(n), sizeof step_us[0], cmp);
    if (r == 0 || step_us[n / 2] < best) best = step_us[n / 2];
  }
  legsim_hexapod_state s;
  if (sim) legsim_hexapod_get_state(sim, &s);
  printf("%s %s: %ld steps, status %s, t = %g s, box at z %+.6f m; steps by kind: stuck %ld\n", argv[1], argv[2], n,
         legsim_status_str(st), sim ? s.t_s : 0.0, sim ? s.box_m[2] : 0.0, n);
  if (sim && getenv("HEXAPOD_STATE")) {
    double pose[7 * 64];
    int32_t nb = 0;
    legsim_hexapod_body_poses(sim, pose, 64, &nb);
    for (int i = 0; i < 7 * nb; ++i) printf("pose %d %.17g\n", i, pose[i]);
    for (int i = 0; i < 3; ++i) printf("box v %.17g omega %.17g\n", s.box_velocity_mps[i], s.box_omega_radps[i]);
    for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l)
      for (int i = 0; i < 3; ++i) printf("foot %d force %.17g\n", l, s.foot_force_n[l][i]);
  }
  if (reps > 0) printf("%s %s: wall us/step, min over %ld repetitions of each kind's median: stuck %.3f\n", argv[1],
                       argv[2], reps, best);
  return st == LEGSIM_OK ? 0 : 1;
}
