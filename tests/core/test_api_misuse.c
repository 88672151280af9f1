/* The C API refuses misuse with status codes: NULLs, storage, options, models. */
#include <math.h>
#include <string.h>

#include "leg_fixture.h"
#include "unity.h"

static fixture_storage st;
static legsim_model_desc bad;

void setUp(void) { bad = legsim_model_leg_revolute; }
void tearDown(void) {}

static void test_storage_and_null_checks(void) {
  legsim_options o = legsim_default_options();
  legsim_sim *sim = NULL;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_NULL, legsim_init(NULL, 10, &legsim_model_leg_revolute, &o, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_STORAGE, legsim_init(st.bytes, legsim_sim_size() - 1, &legsim_model_leg_revolute, &o, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_STORAGE, legsim_init(st.bytes + 1, sizeof st.bytes - 1, &legsim_model_leg_revolute, &o, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(st.bytes, sizeof st.bytes, &legsim_model_leg_revolute, &o, &sim));
  /* nothing assembled yet: the analyses say so */
  legsim_real f[NA];
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_STATE, legsim_step(sim, 1));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_STATE, legsim_contacts_check(sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_STATE, legsim_statics(sim, f));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_NULL, legsim_get_q(sim, NULL));
  TEST_ASSERT_EQUAL_STRING("ok", legsim_status_str(LEGSIM_OK));
}

static void test_options_are_checked(void) {
  legsim_sim *sim = NULL;
  legsim_options o = legsim_default_options();
  o.step_s = 0;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_init(st.bytes, sizeof st.bytes, &legsim_model_leg_revolute, &o, &sim));
  o = legsim_default_options();
  o.step_s = NAN;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_init(st.bytes, sizeof st.bytes, &legsim_model_leg_revolute, &o, &sim));
  o = legsim_default_options();
  o.rho_inf = 1.5;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_init(st.bytes, sizeof st.bytes, &legsim_model_leg_revolute, &o, &sim));
  o = legsim_default_options();
  o.integrator = (legsim_integrator)7;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_init(st.bytes, sizeof st.bytes, &legsim_model_leg_revolute, &o, &sim));
}

static void test_model_errors_name_the_item(void) {
  char msg[160];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_model_check(&bad, msg, sizeof msg));
  bad.joint[7].body[1] = 9;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_MODEL, legsim_model_check(&bad, msg, sizeof msg));
  TEST_ASSERT_NOT_NULL(strstr(msg, "joint 'D'"));
  bad = legsim_model_leg_revolute;
  bad.body[2].mass_kg = -1;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_MODEL, legsim_model_check(&bad, msg, sizeof msg));
  TEST_ASSERT_NOT_NULL(strstr(msg, "body 'thigh'"));
  bad = legsim_model_leg_revolute;
  bad.body[2].length_m = NAN;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_MODEL, legsim_model_check(&bad, msg, sizeof msg));
  bad = legsim_model_leg_revolute;
  bad.joint[0].kind = (legsim_joint_kind)9;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_MODEL, legsim_model_check(&bad, msg, sizeof msg));
  TEST_ASSERT_NOT_NULL(strstr(msg, "unknown kind"));
  bad = legsim_model_leg_revolute;
  bad.actuator[0].joint = 0; /* a revolute joint */
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_MODEL, legsim_model_check(&bad, msg, sizeof msg));
  bad = legsim_model_leg_revolute;
  bad.actuator[1].stroke_min_m = 0.9;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_MODEL, legsim_model_check(&bad, msg, sizeof msg));
  bad = legsim_model_leg_revolute;
  bad.n_bodies = LEGSIM_MAX_BODIES + 1;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_CAPACITY, legsim_model_check(&bad, msg, sizeof msg));
  legsim_options o = legsim_default_options();
  legsim_sim *sim = NULL;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_CAPACITY, legsim_init(st.bytes, sizeof st.bytes, &bad, &o, &sim));
}

static void test_refused_state_and_out_of_stroke_assembly_change_nothing(void) {
  legsim_options o = legsim_default_options();
  legsim_sim *sim = NULL;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(st.bytes, sizeof st.bytes, &legsim_model_leg_revolute, &o, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  legsim_real q[NQ], qd[NQ], qdd0[NQ], qdd1[NQ], lambda0[16], lambda1[16];
  legsim_get_q(sim, q);
  legsim_get_qdd(sim, qdd0);
  legsim_multipliers(sim, lambda0);
  for (int k = 0; k < NQ; ++k) qd[k] = 1e155; /* finite, absurd */
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_set_state(sim, q, qd, 0));
  legsim_get_qdd(sim, qdd1);
  legsim_multipliers(sim, lambda1);
  TEST_ASSERT_EQUAL_DOUBLE(0.0, max_abs_diff(qdd0, qdd1, NQ));
  TEST_ASSERT_EQUAL_DOUBLE(0.0, max_abs_diff(lambda0, lambda1, 16));
  /* slide the lower rod 0.3 m into its cylinder: its length 0.3245 m is below the stroke */
  const double phi4 = q[11];
  q[12] -= 0.3 * sin(phi4);
  q[13] += 0.3 * cos(phi4);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_set_state(sim, q, NULL, 0));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_OUT_OF_STROKE, legsim_assemble(sim, NULL));
  /* a spring-damper has no value to set; this leg has none, the point force takes two */
  const legsim_real load[2] = {0, 10};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_set_force(sim, 0, load));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_set_force(sim, 1, load));
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_storage_and_null_checks);
  RUN_TEST(test_options_are_checked);
  RUN_TEST(test_model_errors_name_the_item);
  RUN_TEST(test_refused_state_and_out_of_stroke_assembly_change_nothing);
  return UNITY_END();
}
