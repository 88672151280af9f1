/* Prints the state after 0.1 s of free fall from the stand pose with each
 * integrator and the stand statics, one number per line, for comparing the
 * float build with the double build (compare_precision.py). */
#include <stdio.h>

#include "legsim/legsim.h"
#include "legsim/models.h"

static _Alignas(16) unsigned char storage[64 * 1024];

int main(void) {
  for (int integ = 0; integ < 2; ++integ) {
    legsim_options o = legsim_default_options();
    o.integrator = (legsim_integrator)integ;
    legsim_sim *sim;
    legsim_status s = legsim_init(storage, sizeof storage, &legsim_model_leg_revolute, &o, &sim);
    if (s == LEGSIM_OK) s = legsim_assemble_pose(sim, 0);
    if (s == LEGSIM_OK) s = legsim_step(sim, 100);
    if (s != LEGSIM_OK) {
      fprintf(stderr, "probe: %s\n", legsim_status_str(s));
      return 1;
    }
    legsim_real q[18], foot[2], f[2];
    legsim_reaction r[8];
    legsim_get_q(sim, q);
    legsim_foot_position(sim, foot);
    for (int k = 0; k < 18; ++k) printf("q%d %.9g\n", k, (double)q[k]);
    printf("foot_x %.9g\nfoot_y %.9g\n", (double)foot[0], (double)foot[1]);
    legsim_reactions(sim, r);
    for (int j = 0; j < 8; ++j) printf("reaction%d_fy %.9g\n", j, (double)r[j].force_n[1]);
    legsim_assemble_pose(sim, 0);
    if (legsim_statics(sim, f) != LEGSIM_OK) return 1;
    printf("statics_upper %.9g\nstatics_lower %.9g\n", (double)f[0], (double)f[1]);
  }
  return 0;
}
