/* Statics and inverse dynamics: whole-leg balance, the slot variant's missing
 * equilibrium, the worst-case sweep, and inverse dynamics driving the forward
 * dynamics onto the same accelerations. */
#include <math.h>
#include <stdio.h>

#include "leg_fixture.h"
#include "unity.h"

static fixture_storage st;

void setUp(void) {}
void tearDown(void) {}

/* The leg as one free body: the frame joints (A, B_thigh, B_lower) plus gravity
 * plus the foot load must balance, in force and in moment about the origin. */
static void check_balance(legsim_sim *sim, const double *foot_load) {
  const legsim_model_desc *m = legsim_model(sim);
  legsim_real q[NQ], foot[2];
  legsim_reaction r[NJ];
  legsim_get_q(sim, q);
  legsim_reactions(sim, r);
  legsim_foot_position(sim, foot);
  double fx = foot_load[0], fy = foot_load[1];
  double mz = foot[0] * foot_load[1] - foot[1] * foot_load[0];
  for (int b = 0; b < m->n_bodies; ++b) {
    const double w = m->body[b].mass_kg * m->gravity_mps2[1];
    fy += w;
    mz += q[3 * b] * w;
  }
  for (int j = 0; j < m->n_joints; ++j) {
    if (m->joint[j].kind != LEGSIM_JOINT_REVOLUTE_TO_FRAME) continue;
    const int b = m->joint[j].body[0];
    fx += r[j].force_n[0];
    fy += r[j].force_n[1];
    mz += q[3 * b] * r[j].force_n[1] - q[3 * b + 1] * r[j].force_n[0] + r[j].moment_nm;
  }
  TEST_ASSERT_DOUBLE_WITHIN(1e-9, 0.0, fx);
  TEST_ASSERT_DOUBLE_WITHIN(1e-9, 0.0, fy);
  TEST_ASSERT_DOUBLE_WITHIN(1e-9, 0.0, mz);
}

static void test_static_balance_under_gravity_and_a_foot_load(void) {
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, legsim_default_options());
  legsim_real f[NA];
  const double none[2] = {0, 0}, load[2] = {0, 300.0};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_statics(sim, f));
  check_balance(sim, none);
  const legsim_real g_only = f[0];
  const legsim_real foot_load[2] = {0, 300.0};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_set_force(sim, 0, foot_load));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_statics(sim, f));
  check_balance(sim, load);
  printf("stand statics: upper %.6f N (gravity only %.6f N), lower %.6f N\n", f[0], g_only, f[1]);
  /* virtual work: a 300 N lift of the foot needs delta F_upper = 300 * dy_foot / dl_upper */
  legsim_real len[NA], foot_lo[2], foot_hi[2];
  legsim_actuator_lengths(sim, len, NULL);
  const double h = 1e-5;
  legsim_real lo[NA] = {len[0] - h, len[1]}, hi[NA] = {len[0] + h, len[1]};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble(sim, lo));
  legsim_foot_position(sim, foot_lo);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble(sim, hi));
  legsim_foot_position(sim, foot_hi);
  /* the Newton tolerance (1e-10) over 2h bounds the finite difference's accuracy */
  TEST_ASSERT_DOUBLE_WITHIN(5e-3, -300.0 * (foot_hi[1] - foot_lo[1]) / (2 * h), f[0] - g_only);
}

static void test_slot_variant_has_no_equilibrium_with_two_locked_actuators(void) {
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_slot, legsim_default_options());
  legsim_real f[NA], qd0[NQ], qd1[NQ], qdd0[NQ], qdd1[NQ];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 20)); /* moving: qd != 0 */
  legsim_get_qd(sim, qd0);
  legsim_get_qdd(sim, qdd0);
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_NO_EQUILIBRIUM, legsim_statics(sim, f));
  legsim_get_qd(sim, qd1);
  legsim_get_qdd(sim, qdd1);
  /* a refused analysis leaves the state as it was */
  TEST_ASSERT_EQUAL_DOUBLE(0.0, max_abs_diff(qd0, qd1, NQ));
  TEST_ASSERT_EQUAL_DOUBLE(0.0, max_abs_diff(qdd0, qdd1, NQ));
}

static void test_worst_case_sweep(void) {
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, legsim_default_options());
  const legsim_real foot_load[2] = {0, 300.0};
  legsim_set_force(sim, 0, foot_load);
  legsim_real f_stand[NA];
  legsim_reaction r_stand[NJ];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_statics(sim, f_stand));
  legsim_reactions(sim, r_stand);
  legsim_worst_case wc;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_statics_sweep(sim, 11, &wc));
  TEST_ASSERT_EQUAL_INT(121, wc.n_poses + wc.n_failed);
  TEST_ASSERT_TRUE(wc.n_poses > 60);
  TEST_ASSERT_TRUE(wc.n_failed > 0); /* upper lengths past 0.75 m cannot be reached */
  /* the stand pose is not on the grid: compare with a grid pose instead, at the end */
  legsim_real f_last[NA];
  legsim_reaction r_last[NJ];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_statics(sim, f_last));
  legsim_reactions(sim, r_last);
  for (int j = 0; j < NJ; ++j)
    TEST_ASSERT_TRUE(wc.max_reaction_n[j] >= hypot(r_last[j].force_n[0], r_last[j].force_n[1]) - 1e-9);
  (void)r_stand;
  TEST_ASSERT_TRUE(wc.max_actuator_force_n[0] > fabs(f_stand[0]));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_statics_sweep(sim, 1, &wc));
}

/* Inverse dynamics gives the forces that, commanded, reproduce its accelerations. */
static void test_inverse_dynamics_reproduces_the_motion(void) {
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, legsim_default_options());
  const legsim_real len[NA] = {0.63, 0.60}, rate[NA] = {0.1, -0.2}, acc[NA] = {2.0, 1.0};
  legsim_real f[NA], qdd_id[NQ], qdd_fd[NQ], len_acc_check[NA];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_inverse_dynamics(sim, len, rate, acc, f));
  legsim_get_qdd(sim, qdd_id);
  legsim_reaction r_id[NJ], r_fd[NJ];
  legsim_reactions(sim, r_id);
  for (int a = 0; a < NA; ++a) TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_force(sim, a, f[a]));
  legsim_real q[NQ], qd[NQ];
  legsim_get_q(sim, q);
  legsim_get_qd(sim, qd);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_set_state(sim, q, qd, 0)); /* free dynamics there */
  legsim_get_qdd(sim, qdd_fd);
  legsim_reactions(sim, r_fd);
  TEST_ASSERT_TRUE(max_abs_diff(qdd_id, qdd_fd, NQ) < 1e-8);
  for (int j = 0; j < NJ; ++j) {
    TEST_ASSERT_DOUBLE_WITHIN(1e-8, r_id[j].force_n[0], r_fd[j].force_n[0]);
    TEST_ASSERT_DOUBLE_WITHIN(1e-8, r_id[j].force_n[1], r_fd[j].force_n[1]);
    TEST_ASSERT_DOUBLE_WITHIN(1e-8, r_id[j].moment_nm, r_fd[j].moment_nm);
  }
  (void)len_acc_check;
  const legsim_real beyond[NA] = {0.9, 0.6};
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_OUT_OF_STROKE, legsim_inverse_dynamics(sim, beyond, rate, acc, f));
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_static_balance_under_gravity_and_a_foot_load);
  RUN_TEST(test_slot_variant_has_no_equilibrium_with_two_locked_actuators);
  RUN_TEST(test_worst_case_sweep);
  RUN_TEST(test_inverse_dynamics_reproduces_the_motion);
  return UNITY_END();
}
