/* The leg at its stand pose, 50 N on the upper actuator, 0.1 s of RK4; prints the
 * joint reactions and checks them against Newton's law for the whole leg. */
#include <math.h>
#include <stdio.h>

#include "legsim/legsim.h"
#include "legsim/models.h" /* the compiled-in leg, generated from models/leg.toml */

static _Alignas(LEGSIM_STORAGE_ALIGN) unsigned char storage[64 * 1024]; /* >= legsim_sim_size() */

int main(void) {
  legsim_options opt = legsim_default_options(); /* RK4, h = 1 ms */
  legsim_sim *sim = NULL;
  legsim_status s = legsim_init(storage, sizeof storage, &legsim_model_leg_revolute, &opt, &sim);
  if (s == LEGSIM_OK) s = legsim_assemble_pose(sim, 0);       /* the stand pose */
  if (s == LEGSIM_OK) s = legsim_command_force(sim, 0, 50.0); /* 50 N on the upper actuator */
  if (s == LEGSIM_OK) s = legsim_step(sim, 100);              /* 100 steps: 0.1 s */
  legsim_reaction r[LEGSIM_MAX_JOINTS];
  legsim_real qdd[3 * LEGSIM_MAX_BODIES], phi[2 * LEGSIM_MAX_JOINTS], residual = 0;
  if (s == LEGSIM_OK) s = legsim_reactions(sim, r); /* force and moment of each joint on its first body */
  if (s == LEGSIM_OK) s = legsim_get_qdd(sim, qdd);
  if (s == LEGSIM_OK) s = legsim_constraints(sim, phi, &residual); /* max |Phi(q)| */
  if (s != LEGSIM_OK) {
    fprintf(stderr, "legsim: %s\n", legsim_status_str(s));
    return 1;
  }

  /* Newton for the whole leg: the frame joints carry gravity and the inertia,
   * sum of m a = sum of m g + frame reactions (joint and actuator forces are internal). */
  const legsim_model_desc *m = legsim_model(sim);
  double unbalanced[2] = {0, 0}, scale = 0;
  for (int32_t b = 0; b < m->n_bodies; ++b)
    for (int k = 0; k < 2; ++k) {
      unbalanced[k] += m->body[b].mass_kg * (qdd[3 * b + k] - m->gravity_mps2[k]);
      scale += fabs(m->body[b].mass_kg * m->gravity_mps2[k]);
    }
  for (int32_t j = 0; j < m->n_joints; ++j) {
    printf("%-16s Fx %9.3f N  Fy %9.3f N  M %8.4f N m\n", m->joint[j].name,
           (double)r[j].force_n[0], (double)r[j].force_n[1], (double)r[j].moment_nm);
    if (m->joint[j].kind == LEGSIM_JOINT_REVOLUTE_TO_FRAME)
      for (int k = 0; k < 2; ++k) unbalanced[k] -= r[j].force_n[k];
  }
  const double tol = LEGSIM_USE_FLOAT ? 1e-4 : 1e-9; /* relative to the weight; m or rad */
  printf("t = %.3f s, constraint residual %.2e, unbalanced force %.2e N\n", legsim_time(sim),
         (double)residual, hypot(unbalanced[0], unbalanced[1]));
  if (legsim_step_count(sim) != 100 || fabs(legsim_time(sim) - 0.1) > 1e-9 || !(residual < tol) ||
      !(hypot(unbalanced[0], unbalanced[1]) < tol * scale)) {
    fprintf(stderr, "legsim: results break an invariant\n");
    return 1;
  }
  return 0;
}
