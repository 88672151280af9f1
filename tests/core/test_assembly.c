/* Assembly: the stand pose printed in the leg's TOML, lengths round trips,
 * and the failures (out of stroke, unreachable, dead centre, bad input). */
#include <math.h>
#include <stdio.h>

#include "leg_fixture.h"
#include "unity.h"

static fixture_storage st;

void setUp(void) {}
void tearDown(void) {}

/* Facts printed in models/leg.toml (7 digits). */
static const double kC[2] = {0.4330127, -0.25}, kD[2] = {0.4330127, -0.45}, kFoot[2] = {0.4330127, -0.85};

static void test_stand_pose_matches_the_printed_facts(void) {
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, legsim_default_options());
  legsim_real q[NQ], len[NA], foot[2];
  double c[2], c6[2], d[2];
  legsim_get_q(sim, q);
  body_point(q, 2, 0.25, 0, c);    /* distal end of the thigh */
  body_point(q, 5, -0.30, 0, c6);  /* proximal end of the shank */
  body_point(q, 5, -0.10, 0, d);
  TEST_ASSERT_DOUBLE_WITHIN(1e-7, kC[0], c[0]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-7, kC[1], c[1]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-7, kC[0], c6[0]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-7, kD[0], d[0]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-7, kD[1], d[1]);
  legsim_foot_position(sim, foot);
  TEST_ASSERT_DOUBLE_WITHIN(1e-7, kFoot[0], foot[0]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-7, kFoot[1], foot[1]);
  legsim_actuator_lengths(sim, len, NULL);
  TEST_ASSERT_DOUBLE_WITHIN(1e-7, 0.6614378, len[0]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-7, 0.6244998, len[1]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-7, 0.7137244, q[2]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-7, 0.7137244, q[5]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-12, 1.0471975511965976, q[8]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-7, 0.7661626, q[11]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-7, 0.7661626, q[14]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-12, 0.0, q[17]);
  legsim_real res;
  legsim_constraints(sim, NULL, &res);
  TEST_ASSERT_TRUE(res < 1e-10);
  legsim_report rep;
  legsim_get_report(sim, &rep);
  TEST_ASSERT_TRUE(rep.condition > 1 && rep.condition < 1e3);
}

static void test_slot_variant_stand_pose(void) {
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_slot, legsim_default_options());
  TEST_ASSERT_EQUAL_INT(15, legsim_n_constraints(sim));
  legsim_real q[NQ], foot[2], res;
  double c[2], d5[2];
  legsim_get_q(sim, q);
  body_point(q, 2, 0.25, 0, c);
  TEST_ASSERT_DOUBLE_WITHIN(1e-7, kC[0], c[0]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-7, kC[1], c[1]);
  legsim_foot_position(sim, foot);
  TEST_ASSERT_DOUBLE_WITHIN(1e-7, kFoot[0], foot[0]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-7, kFoot[1], foot[1]);
  /* the distal end of the lower rod lies on the (vertical) shank axis */
  body_point(q, 4, 0.175, 0, d5);
  TEST_ASSERT_DOUBLE_WITHIN(1e-9, 0.5 * sin(M_PI / 3), d5[0]);
  legsim_constraints(sim, NULL, &res);
  TEST_ASSERT_TRUE(res < 1e-10);
  /* the same pose as the pinned knee: the lower length of the stand */
  legsim_real len[NA];
  legsim_actuator_lengths(sim, len, NULL);
  TEST_ASSERT_DOUBLE_WITHIN(1e-7, 0.6244998, len[1]);
}

static void test_assembly_from_a_rough_guess(void) {
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, legsim_default_options());
  legsim_real q[NQ], len[NA];
  legsim_get_q(sim, q);
  for (int k = 0; k < NQ; ++k) q[k] += (k % 3 == 2 ? 0.03 : -0.01); /* centimetres, degrees off */
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_set_state(sim, q, NULL, 0));
  const legsim_real stand[NA] = {0.66143782776614768, 0.62449979983983983};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble(sim, stand));
  legsim_report rep;
  legsim_get_report(sim, &rep);
  TEST_ASSERT_TRUE(rep.iterations >= 2);
  legsim_get_q(sim, q);
  TEST_ASSERT_DOUBLE_WITHIN(1e-9, 1.0471975511965976, q[8]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-9, 0.0, q[17]);
  legsim_actuator_lengths(sim, len, NULL);
  TEST_ASSERT_DOUBLE_WITHIN(1e-10, stand[0], len[0]);
}

static void test_assembly_to_lengths_round_trip(void) {
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, legsim_default_options());
  const legsim_real target[NA] = {0.60, 0.55};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble(sim, target));
  legsim_real len[NA], res, rate[NA];
  legsim_actuator_lengths(sim, len, rate);
  TEST_ASSERT_DOUBLE_WITHIN(1e-10, target[0], len[0]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-10, target[1], len[1]);
  TEST_ASSERT_EQUAL_DOUBLE(0.0, rate[0]);
  legsim_constraints(sim, NULL, &res);
  TEST_ASSERT_TRUE(res < 1e-10);
  /* back to the stand lengths gives the stand pose again */
  const legsim_real stand[NA] = {0.66143782776614768, 0.62449979983983983};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble(sim, stand));
  legsim_real q[NQ];
  legsim_get_q(sim, q);
  TEST_ASSERT_DOUBLE_WITHIN(1e-9, 1.0471975511965976, q[8]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-9, 0.0, q[17]);
}

static void test_out_of_stroke_and_bad_lengths_change_nothing(void) {
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, legsim_default_options());
  legsim_real q0[NQ], q1[NQ];
  legsim_get_q(sim, q0);
  const legsim_real too_long[NA] = {0.81, 0.6}, nan_len[NA] = {NAN, 0.6}, inf_len[NA] = {0.6, INFINITY};
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_OUT_OF_STROKE, legsim_assemble(sim, too_long));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_assemble(sim, nan_len));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_assemble(sim, inf_len));
  legsim_get_q(sim, q1);
  TEST_ASSERT_EQUAL_DOUBLE(0.0, max_abs_diff(q0, q1, NQ));
}

static void test_unreachable_lengths_are_reported_not_nan(void) {
  /* |A - B| = 0.25 and the thigh is 0.5 long: the upper length cannot exceed 0.75,
   * yet 0.78 is inside its stroke. */
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, legsim_default_options());
  legsim_real q0[NQ], q1[NQ];
  legsim_get_q(sim, q0);
  const legsim_real beyond[NA] = {0.78, 0.6244998};
  const legsim_status s = legsim_assemble(sim, beyond);
  TEST_ASSERT_TRUE(s == LEGSIM_ERR_UNREACHABLE || s == LEGSIM_ERR_SINGULAR);
  legsim_get_q(sim, q1);
  TEST_ASSERT_EQUAL_DOUBLE(0.0, max_abs_diff(q0, q1, NQ)); /* untouched, finite */
  legsim_report rep;
  legsim_get_report(sim, &rep);
  TEST_ASSERT_FALSE(isnan(rep.residual));
}

static void test_dead_centre_is_reported_with_its_condition(void) {
  /* upper length 0.75: A, B and C aligned, the thigh and the upper actuator
   * in line (a dead centre): the driven Jacobian loses rank. */
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, legsim_default_options());
  const legsim_real dead[NA] = {0.75, 0.6244998};
  legsim_report before, rep;
  legsim_get_report(sim, &before);
  const legsim_status s = legsim_assemble(sim, dead);
  /* the sim's report is its state's, untouched; the refusal's figures are the failure report's */
  legsim_get_report(sim, &rep);
  TEST_ASSERT_EQUAL_MEMORY(&before, &rep, sizeof rep);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_failure_report(sim, &rep));
  printf("dead centre: %s, condition %g, residual %g, iterations %d\n", legsim_status_str(s),
         rep.condition, rep.residual, (int)rep.iterations);
  TEST_ASSERT_TRUE(s == LEGSIM_ERR_SINGULAR || s == LEGSIM_ERR_NOT_CONVERGED);
  TEST_ASSERT_TRUE(rep.condition > LEGSIM_COND_SINGULAR);
  /* approaching it, the estimate grows and the near-singular event is raised */
  legsim_assemble_pose(sim, 0);
  legsim_clear_events(sim);
  const legsim_real close[NA] = {0.745, 0.6244998}, closer[NA] = {0.749999, 0.6244998};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble(sim, close));
  legsim_get_report(sim, &rep);
  const double c1 = rep.condition;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble(sim, closer));
  legsim_get_report(sim, &rep);
  printf("condition at upper length 0.745: %g, at 0.749999: %g\n", c1, rep.condition);
  TEST_ASSERT_TRUE(rep.condition > 3 * c1);
  TEST_ASSERT_TRUE(rep.events & LEGSIM_EVENT_NEAR_SINGULAR);
}

static void test_assemble_pose_index_checked(void) {
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, legsim_default_options());
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_assemble_pose(sim, 1));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_assemble_pose(sim, -1));
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_stand_pose_matches_the_printed_facts);
  RUN_TEST(test_slot_variant_stand_pose);
  RUN_TEST(test_assembly_from_a_rough_guess);
  RUN_TEST(test_assembly_to_lengths_round_trip);
  RUN_TEST(test_out_of_stroke_and_bad_lengths_change_nothing);
  RUN_TEST(test_unreachable_lengths_are_reported_not_nan);
  RUN_TEST(test_dead_centre_is_reported_with_its_condition);
  RUN_TEST(test_assemble_pose_index_checked);
  return UNITY_END();
}
