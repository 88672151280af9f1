/* Velocity and acceleration analysis against finite differences of assembly. */
#include <math.h>

#include "leg_fixture.h"
#include "unity.h"

static fixture_storage st;

void setUp(void) {}
void tearDown(void) {}

static const legsim_real kLen[NA] = {0.62, 0.58}, kRate[NA] = {0.2, -0.15}, kAcc[NA] = {1.5, 0.7};

static void assemble_at(legsim_sim *sim, double t, legsim_real *q) {
  legsim_real len[NA];
  for (int a = 0; a < NA; ++a) len[a] = kLen[a] + kRate[a] * t + 0.5 * kAcc[a] * t * t;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble(sim, len));
  legsim_get_q(sim, q);
}

static void test_velocity_and_acceleration_match_finite_differences(void) {
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, legsim_default_options());
  const double h = 1e-4;
  legsim_real qm[NQ], q0[NQ], qp[NQ], qd[NQ], qdd[NQ], rate[NA];
  assemble_at(sim, -h, qm);
  assemble_at(sim, h, qp);
  assemble_at(sim, 0, q0);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_velocity_analysis(sim, kRate));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_acceleration_analysis(sim, kAcc));
  legsim_get_qd(sim, qd);
  legsim_get_qdd(sim, qdd);
  for (int k = 0; k < NQ; ++k) {
    TEST_ASSERT_DOUBLE_WITHIN(1e-7, (qp[k] - qm[k]) / (2 * h), qd[k]);
    TEST_ASSERT_DOUBLE_WITHIN(1e-4, (qp[k] - 2 * q0[k] + qm[k]) / (h * h), qdd[k]);
  }
  legsim_actuator_lengths(sim, NULL, rate);
  TEST_ASSERT_DOUBLE_WITHIN(1e-12, kRate[0], rate[0]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-12, kRate[1], rate[1]);
}

static void test_bad_rates_are_refused(void) {
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, legsim_default_options());
  const legsim_real nan_rate[NA] = {NAN, 0};
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_velocity_analysis(sim, nan_rate));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_acceleration_analysis(sim, nan_rate));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_NULL, legsim_velocity_analysis(sim, NULL));
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_velocity_and_acceleration_match_finite_differences);
  RUN_TEST(test_bad_rates_are_refused);
  return UNITY_END();
}
