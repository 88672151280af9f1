// The hexapod file (models/hexapod.toml, legsim/hexapod.h) through the one model file parser
// (legsim_hexapod_load_toml) and the spatial module (robot_lift_hexapod):
// - its six legs are models/leg.toml as the compiled-in leg, bit for bit (the same loader);
// - lifted: 43 bodies, 234 rows, 12 linear actuators; the box level at the origin, every leg at
//   its stand and rowing angle 0: every row met, the six feet at one height, the right and left
//   feet mirror images across the box's x-z plane;
// - refused, each with a message naming the file, the item and the problem: a hexapod file given
//   to the model loader and a leg file given here, five legs, a horizontal gravity, a leg file
//   whose gravity differs, a leg without a [foot], a rowing stroke past pi, a ground normal
//   that is not a unit vector.
// Runs from the source tree's root (legsim_add_unity_test's WORKING_DIRECTORY).
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include <unistd.h>

#include "legsim/legsim.h"
#include "legsim/models.h"
#include "model_toml.hpp"
#include "spatial/robot.hpp"
#include "unity.h"

void setUp(void) {}
void tearDown(void) {}

namespace {
using namespace legsim::spatial;
const char *kHexapod = "models/hexapod.toml";
alignas(16) unsigned char storage[1 << 20];

std::string read(const char *path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// A folder holding leg.toml and hexapod.toml with one text replaced (must occur once).
std::string variant_dir(const std::string &leg_text, const std::string &from, const std::string &to) {
  char tmpl[] = "/tmp/legsim_hexapod_XXXXXX";
  const std::string dir = mkdtemp(tmpl);
  std::string hex = read(kHexapod);
  if (!from.empty()) {
    const size_t k = hex.find(from);
    TEST_ASSERT_TRUE_MESSAGE(k != std::string::npos && hex.find(from, k + 1) == std::string::npos, from.c_str());
    hex.replace(k, from.size(), to);
  }
  std::ofstream(dir + "/hexapod.toml") << hex;
  std::ofstream(dir + "/leg.toml") << leg_text;
  return dir;
}

void expect_refused(const std::string &dir, const char *file, legsim_status want, const char *needle) {
  auto h = std::make_unique<legsim_hexapod_desc>();
  char msg[512] = {0};
  const std::string path = dir + "/" + file;
  const legsim_status st = legsim_hexapod_load_toml(path.c_str(), h.get(), msg, sizeof msg);
  printf("%s\n", msg);
  for (const char *f : {"/hexapod.toml", "/leg.toml"}) std::remove((dir + f).c_str());
  rmdir(dir.c_str());
  TEST_ASSERT_EQUAL_INT(want, st);
  TEST_ASSERT_TRUE_MESSAGE(std::strstr(msg, path.c_str()) == msg, msg);
  TEST_ASSERT_TRUE_MESSAGE(std::strstr(msg, needle) != nullptr, msg);
}
}  // namespace

void test_loads_six_legs_of_the_leg_file(void) {
  auto h = std::make_unique<legsim_hexapod_desc>();
  char msg[256];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_hexapod_load_toml(kHexapod, h.get(), msg, sizeof msg));
  TEST_ASSERT_EQUAL_INT(6, h->n_legs);
  TEST_ASSERT_EQUAL_STRING("inta-csic-hexapod", h->name);
  TEST_ASSERT_EQUAL_DOUBLE(-9.81, h->gravity_mps2[2]);
  for (int l = 0; l < 6; ++l)
    TEST_ASSERT_EQUAL_INT(0, std::memcmp(&h->leg[l].leg, &legsim_model_leg_revolute, sizeof(legsim_model_desc)));
  TEST_ASSERT_EQUAL_STRING("left_rear", h->leg[5].name);
}

void test_lifted_stand(void) {
  auto h = std::make_unique<legsim_hexapod_desc>();
  char msg[256];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_hexapod_load_toml(kHexapod, h.get(), msg, sizeof msg));
  static SpatialRobot robot;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_lift_hexapod(*h, robot));
  TEST_ASSERT_EQUAL_INT(43, robot.nb);
  TEST_ASSERT_EQUAL_INT(234, robot.m);
  TEST_ASSERT_EQUAL_INT(12, robot.na);
  // the leg's stand (the planar core's assembly)
  legsim_options opt = legsim_default_options();
  legsim_sim *sim = nullptr;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage, sizeof storage, &h->leg[0].leg, &opt, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  double qp[3 * LEGSIM_MAX_BODIES], zero[3 * LEGSIM_MAX_BODIES] = {0};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_get_q(sim, qp));
  const double *qs[6], *vs[6];
  double psi[6] = {0}, psid[6] = {0};
  for (int l = 0; l < 6; ++l) qs[l] = qp, vs[l] = zero;
  const double box_q[7] = {0, 0, 0, 1, 0, 0, 0}, box_v[6] = {0, 0, 0, 0, 0, 0};
  static double q[kBodyConfig * kMaxRobotBodies], v[kBodyDof * kMaxRobotBodies];
  static Row rows[kMaxRobotRows];
  robot_state(robot, box_q, box_v, qs, vs, psi, psid, q, v);
  robot_rows(robot, q, v, rows);
  double phi = 0;
  for (int r = 0; r < robot.m; ++r) phi = std::fmax(phi, std::fabs(rows[r].phi));
  TEST_ASSERT_TRUE(phi < 1e-12);
  const V3 f0 = robot_foot_position(robot, 0, q);
  printf("the right front foot at (%.6f, %.6f, %.6f) m from the box's centre\n", f0.x, f0.y, f0.z);
  for (int l = 0; l < 6; ++l) {
    const V3 f = robot_foot_position(robot, l, q), m = robot_foot_position(robot, (l + 3) % 6, q);
    TEST_ASSERT_TRUE(std::fabs(f.z - f0.z) < 1e-14);
    TEST_ASSERT_TRUE(std::fabs(f.x - m.x) < 1e-14 && std::fabs(f.y + m.y) < 1e-14);
    TEST_ASSERT_TRUE(std::fabs(f.x - h->leg[l].hip_m[0]) < 1e-14);  // in its hip's vertical plane
  }
}

void test_refusals(void) {
  const std::string leg = read("models/leg.toml");
  {  // the model loader refuses a hexapod file; this one a leg file
    legsim_model_desc d;
    char msg[256] = {0};
    TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_model_load_toml(kHexapod, nullptr, &d, msg, sizeof msg));
    printf("%s\n", msg);
    TEST_ASSERT_NOT_NULL(std::strstr(msg, "legsim_hexapod_load_toml"));
    expect_refused(variant_dir(leg, "", ""), "leg.toml", LEGSIM_ERR_BAD_INPUT, "not a hexapod file");
  }
  const std::string last_leg = "[[leg]]\nname = \"left_rear\"\nfile = \"leg.toml\"\nhip = [-0.35, 0.25, -0.15]\n"
                               "heading = 1.5707963267948966\n";
  expect_refused(variant_dir(leg, last_leg, ""), "hexapod.toml", LEGSIM_ERR_MODEL, "needs 6 [[leg]] (got 5)");
  expect_refused(variant_dir(leg, "gravity = [0.0, 0.0, -9.81]", "gravity = [0.5, 0.0, -9.81]"), "hexapod.toml",
                 LEGSIM_ERR_MODEL, "'gravity' must be vertical");
  {
    const size_t k = leg.find("gravity = [0.0, -9.81]");
    TEST_ASSERT_TRUE(k != std::string::npos);
    std::string moon = leg;
    moon.replace(k, std::strlen("gravity = [0.0, -9.81]"), "gravity = [0.0, -1.62]");
    expect_refused(variant_dir(moon, "", ""), "hexapod.toml", LEGSIM_ERR_MODEL, "is not the hexapod's");
  }
  {
    const size_t k = leg.find("[foot]");
    TEST_ASSERT_TRUE(k != std::string::npos);
    const size_t e = leg.find("\n[", k + 1);
    std::string footless = leg;
    footless.erase(k, (e == std::string::npos ? leg.size() : e + 1) - k);
    expect_refused(variant_dir(footless, "", ""), "hexapod.toml", LEGSIM_ERR_MODEL, "has no [foot]");
  }
  expect_refused(variant_dir(leg, "stroke = [-0.6, 0.6]", "stroke = [-0.6, 3.2]"), "hexapod.toml",
                 LEGSIM_ERR_MODEL, "'stroke' must be [min, max]");
  expect_refused(variant_dir(leg, "normal = [0.0, 0.0, 1.0]", "normal = [0.0, 0.0, 2.0]"), "hexapod.toml",
                 LEGSIM_ERR_MODEL, "'normal' must be a unit vector");
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_loads_six_legs_of_the_leg_file);
  RUN_TEST(test_lifted_stand);
  RUN_TEST(test_refusals);
  return UNITY_END();
}
