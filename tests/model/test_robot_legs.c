/* Robot files of 2, 4 and 6 legs (models/robot.toml, robot4.toml, robot6.toml) in the
 * six-leg capacities (legsim_core_legs6): the loader composes one box and L copies of the
 * leg; the stance puts every foot on the ground; standing under its servos the robot's
 * feet carry its weight, mirror-image feet alike. Runs from the source tree's root. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "legsim/legsim.h"
#include "model_toml.hpp"
#include "unity.h"

static _Alignas(LEGSIM_STORAGE_ALIGN) unsigned char storage[1024 * 1024];
static legsim_model_desc model; /* outlives the sim */

void setUp(void) {}
void tearDown(void) {}

static void load(const char *path) {
  char msg[256] = "";
  const legsim_status st = legsim_model_load_toml(path, NULL, &model, msg, sizeof msg);
  TEST_ASSERT_EQUAL_INT_MESSAGE(LEGSIM_OK, st, msg);
}

/* the leg file alone: what each [[leg]] adds */
static void leg_counts(int *bodies, int *joints, int *actuators, int *forces) {
  load("models/leg.toml");
  *bodies = model.n_bodies, *joints = model.n_joints, *actuators = model.n_actuators, *forces = model.n_forces;
}

static void check_composed(const char *path, int legs) {
  int lb, lj, la, lf;
  leg_counts(&lb, &lj, &la, &lf);
  load(path);
  TEST_ASSERT_EQUAL_INT(1 + legs * lb, model.n_bodies); /* the box and the legs' bodies */
  TEST_ASSERT_EQUAL_INT(legs * lj, model.n_joints);     /* frame joints become joints to the box */
  TEST_ASSERT_EQUAL_INT(legs * la, model.n_actuators);
  TEST_ASSERT_EQUAL_INT(legs * lf, model.n_forces);
  TEST_ASSERT_EQUAL_INT(legs, model.n_contacts); /* one foot a leg */
  TEST_ASSERT_EQUAL_INT(1, model.n_poses);
}

void test_loader_composes_two_legs(void) { check_composed("models/robot.toml", 2); }
void test_loader_composes_four_legs(void) { check_composed("models/robot4.toml", 4); }
void test_loader_composes_six_legs(void) { check_composed("models/robot6.toml", 6); }

/* Stand on every foot, servos holding the stand lengths, for 3 s: the robot comes to
 * rest, so the feet's normal forces sum to the whole weight (sum of m g over bodies,
 * g = 9.81 m/s^2); the fixtures' boxes weigh the same per leg and their legs are alike, so
 * every foot carries the same normal force; the model is mirror-symmetric, so foot k and
 * foot L-1-k (its mirror image) carry opposite tangential forces at mirrored points. */
static void check_standing(const char *path, int legs) {
  load(path);
  legsim_options opt = legsim_default_options();
  opt.integrator = LEGSIM_INTEGRATOR_GENERALIZED_ALPHA;
  legsim_sim *sim = NULL;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage, sizeof storage, &model, &opt, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_on_ground(sim, NULL, 0.0));
  legsim_real len[LEGSIM_MAX_ACTUATORS], rate[LEGSIM_MAX_ACTUATORS];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_actuator_lengths(sim, len, rate));
  for (int a = 0; a < model.n_actuators; ++a) TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_length(sim, a, len[a]));
  legsim_contact k[LEGSIM_CONTACT_SLOTS];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_contacts(sim, k));
  for (int i = 0; i < legs; ++i) {
    TEST_ASSERT_EQUAL_INT(LEGSIM_CONTACT_STUCK, k[i].state);
    TEST_ASSERT_DOUBLE_WITHIN(1e-9, 0.0, k[i].position[1]); /* on the line y = 0 */
  }
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 3000)); /* 3 s at 1 ms */
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_contacts(sim, k));
  double weight = 0, sum = 0;
  for (int b = 0; b < model.n_bodies; ++b) weight += model.body[b].mass_kg * 9.81;
  for (int i = 0; i < legs; ++i) {
    TEST_ASSERT_EQUAL_INT(LEGSIM_CONTACT_STUCK, k[i].state);
    TEST_ASSERT_TRUE(k[i].normal_n > 0);
    sum += k[i].normal_n;
    TEST_ASSERT_DOUBLE_WITHIN(1e-6 * weight, k[0].normal_n, k[i].normal_n);
    const legsim_contact *m = &k[legs - 1 - i];
    TEST_ASSERT_DOUBLE_WITHIN(1e-6 * weight, m->normal_n, k[i].normal_n);
    TEST_ASSERT_DOUBLE_WITHIN(1e-6 * weight, -m->tangential_n, k[i].tangential_n);
    TEST_ASSERT_DOUBLE_WITHIN(1e-9, -m->position[0], k[i].position[0]);
  }
  TEST_ASSERT_DOUBLE_WITHIN(1e-6 * weight, weight, sum);
}

void test_two_legs_stand_on_their_weight(void) { check_standing("models/robot.toml", 2); }
void test_four_legs_stand_on_their_weight(void) { check_standing("models/robot4.toml", 4); }
void test_six_legs_stand_on_their_weight(void) { check_standing("models/robot6.toml", 6); }

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_loader_composes_two_legs);
  RUN_TEST(test_loader_composes_four_legs);
  RUN_TEST(test_loader_composes_six_legs);
  RUN_TEST(test_two_legs_stand_on_their_weight);
  RUN_TEST(test_four_legs_stand_on_their_weight);
  RUN_TEST(test_six_legs_stand_on_their_weight);
  return UNITY_END();
}
