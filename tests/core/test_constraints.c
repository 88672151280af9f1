/* The constraint Jacobian and the acceleration right-hand side against central
 * finite differences of the residual, at poses off the constraint manifold too
 * (the formulas hold for any q). */
#include <math.h>
#include <stdlib.h>

#include "leg_fixture.h"
#include "unity.h"

static fixture_storage st;

void setUp(void) {}
void tearDown(void) {}

static void perturbed_state(legsim_sim *sim, unsigned seed, legsim_real *q, legsim_real *qd) {
  srand(seed);
  legsim_get_q(sim, q);
  for (int k = 0; k < NQ; ++k) {
    q[k] += 0.05 * ((double)rand() / RAND_MAX - 0.5);
    qd[k] = 2.0 * ((double)rand() / RAND_MAX - 0.5);
  }
}

static void check_jacobian(const legsim_model_desc *model) {
  legsim_sim *sim = leg_at_stand(&st, model, legsim_default_options());
  const int m = legsim_n_constraints(sim);
  legsim_real q[NQ], qd[NQ], jac[16 * NQ], phip[16], phim[16];
  for (unsigned seed = 1; seed <= 5; ++seed) {
    perturbed_state(sim, seed, q, qd);
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_set_state(sim, q, qd, 0));
    legsim_jacobian(sim, jac);
    const double h = 1e-6;
    for (int k = 0; k < NQ; ++k) {
      legsim_real qp[NQ], qm[NQ];
      for (int i = 0; i < NQ; ++i) qp[i] = qm[i] = q[i];
      qp[k] += h;
      qm[k] -= h;
      legsim_set_state(sim, qp, NULL, 0);
      legsim_constraints(sim, phip, NULL);
      legsim_set_state(sim, qm, NULL, 0);
      legsim_constraints(sim, phim, NULL);
      for (int i = 0; i < m; ++i)
        TEST_ASSERT_DOUBLE_WITHIN(1e-8, (phip[i] - phim[i]) / (2 * h), jac[i * NQ + k]);
    }
  }
}

static void test_jacobian_matches_finite_differences_revolute(void) {
  check_jacobian(&legsim_model_leg_revolute);
}
static void test_jacobian_matches_finite_differences_slot(void) { check_jacobian(&legsim_model_leg_slot); }

/* gamma = -(Phi_q qd)_q qd: along q(t) = q + t qd + t^2/2 qdd, Phi'' = J qdd - gamma... so
 * for qdd = 0: d^2 Phi / dt^2 = -gamma. Checked through the accelerations of the
 * free dynamics: J qdd must equal gamma, i.e. Phi(q(t)) = O(t^3). */
static void test_accelerations_keep_the_constraints_to_second_order(void) {
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_slot, legsim_default_options());
  legsim_real q[NQ], qd[NQ], qdd[NQ];
  /* a consistent velocity: from a velocity analysis */
  const legsim_real rate[NA] = {0.3, -0.2};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_velocity_analysis(sim, rate));
  legsim_get_q(sim, q);
  legsim_get_qd(sim, qd);
  legsim_get_qdd(sim, qdd);
  double prev = 0;
  for (int e = 0; e < 3; ++e) {
    const double t = 1e-2 / pow(2.0, e);
    legsim_real qt[NQ], res;
    for (int k = 0; k < NQ; ++k) qt[k] = q[k] + t * qd[k] + 0.5 * t * t * qdd[k];
    legsim_set_state(sim, qt, NULL, 0);
    legsim_constraints(sim, NULL, &res);
    if (e > 0) TEST_ASSERT_TRUE(res < prev / 6); /* third order: halving t divides by 8 */
    prev = res;
  }
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_jacobian_matches_finite_differences_revolute);
  RUN_TEST(test_jacobian_matches_finite_differences_slot);
  RUN_TEST(test_accelerations_keep_the_constraints_to_second_order);
  return UNITY_END();
}
