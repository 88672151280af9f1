#include "leg_fixture.h"

#include <math.h>
#include <string.h>

#include "unity.h"

legsim_sim *leg_at_stand(fixture_storage *st, const legsim_model_desc *model, legsim_options opt) {
  legsim_sim *sim = NULL;
  TEST_ASSERT_TRUE(legsim_sim_size() <= sizeof st->bytes);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(st->bytes, sizeof st->bytes, model, &opt, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  return sim;
}

void body_point(const legsim_real *q, int b, double xi, double eta, double *xy) {
  const double phi = q[3 * b + 2];
  xy[0] = q[3 * b] + xi * sin(phi) + eta * cos(phi);
  xy[1] = q[3 * b + 1] - xi * cos(phi) + eta * sin(phi);
}

double leg_energy(const legsim_sim *sim, const double *actuator_force) {
  const legsim_model_desc *m = legsim_model(sim);
  legsim_real q[NQ], qd[NQ], len[NA];
  legsim_get_q(sim, q);
  legsim_get_qd(sim, qd);
  legsim_actuator_lengths(sim, len, NULL);
  double e = 0;
  for (int b = 0; b < m->n_bodies; ++b) {
    const double mass = m->body[b].mass_kg, inertia = m->body[b].inertia_kgm2;
    e += 0.5 * mass * (qd[3 * b] * qd[3 * b] + qd[3 * b + 1] * qd[3 * b + 1]);
    e += 0.5 * inertia * qd[3 * b + 2] * qd[3 * b + 2];
    e -= mass * (m->gravity_mps2[0] * q[3 * b] + m->gravity_mps2[1] * q[3 * b + 1]);
  }
  for (int a = 0; a < m->n_actuators; ++a) e -= actuator_force[a] * len[a];
  return e;
}

double max_abs_diff(const legsim_real *a, const legsim_real *b, int n) {
  double d = 0;
  for (int i = 0; i < n; ++i) d = fmax(d, fabs((double)a[i] - (double)b[i]));
  return d;
}
