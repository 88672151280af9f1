// One source of truth for the model: the descriptions compiled in (written as C by the
// build tool legsim_model, tools/legsim_model) equal, field by field, those the host
// loads at run time (host/model_toml.cpp); every bad model gives the expected status and
// message.
//
// Runs from the source tree's root (legsim_add_unity_test's WORKING_DIRECTORY).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "legsim/legsim.h"
#include "legsim/mini_models.h"  // tests/model/fixtures/good_mini.toml, generated as C
#include "legsim/models.h"       // models/leg.toml, generated as C (legsim_models)
#include "legsim/leg_cxx_models.h"  // models/leg.toml, generated and compiled as C++
#if __has_include("legsim/robot_models.h")
#include "legsim/robot_models.h"  // models/robot.toml, generated when the capacities hold it
#define HAVE_ROBOT 1
#else
#define HAVE_ROBOT 0
#endif
#include "model_toml.hpp"
#include "toml_limits.hpp"
#include "unity.h"

#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

void setUp(void) {}
void tearDown(void) {}

namespace {

const char *kLeg = "models/leg.toml";
const char *kMini = "tests/model/fixtures/good_mini.toml";
const char *kFixtures = "tests/model/fixtures/";

// ---- field-by-field comparison ---------------------------------------------------
std::string g_diff;  // first difference found

void note(const std::string &where) {
  if (g_diff.empty()) g_diff = where;
}

void eq_real(double a, double b, const std::string &where) {
  // Exact: the same TOML text must give the same double on both paths (and the same
  // sign of zero).
  if (!(a == b) || std::signbit(a) != std::signbit(b)) {
    char buf[96];
    std::snprintf(buf, sizeof buf, " (%.17g vs %.17g)", a, b);
    note(where + buf);
  }
}
void eq_int(long a, long b, const std::string &where) {
  if (a != b) note(where + " (" + std::to_string(a) + " vs " + std::to_string(b) + ")");
}
void eq_name(const char (&a)[LEGSIM_NAME_LEN], const char (&b)[LEGSIM_NAME_LEN], const std::string &where) {
  if (std::memcmp(a, b, LEGSIM_NAME_LEN) != 0)
    note(where + " ('" + std::string(a, strnlen(a, LEGSIM_NAME_LEN)) + "' vs '" +
         std::string(b, strnlen(b, LEGSIM_NAME_LEN)) + "')");
}

std::string compare(const legsim_model_desc &a, const legsim_model_desc &b) {
  g_diff.clear();
  eq_name(a.name, b.name, "name");
  for (int i = 0; i < 2; ++i) eq_real(a.gravity_mps2[i], b.gravity_mps2[i], "gravity");
  eq_int(a.n_bodies, b.n_bodies, "n_bodies");
  eq_int(a.n_joints, b.n_joints, "n_joints");
  eq_int(a.n_actuators, b.n_actuators, "n_actuators");
  eq_int(a.n_forces, b.n_forces, "n_forces");
  eq_int(a.n_poses, b.n_poses, "n_poses");
  if (!g_diff.empty()) return g_diff;
  // Whole arrays (capacity), so that the unused tail is zero on both sides too.
  for (int i = 0; i < LEGSIM_MAX_BODIES; ++i) {
    const std::string w = "body[" + std::to_string(i) + "].";
    eq_name(a.body[i].name, b.body[i].name, w + "name");
    eq_real(a.body[i].length_m, b.body[i].length_m, w + "length_m");
    eq_real(a.body[i].mass_kg, b.body[i].mass_kg, w + "mass_kg");
    eq_real(a.body[i].inertia_kgm2, b.body[i].inertia_kgm2, w + "inertia_kgm2");
  }
  for (int i = 0; i < LEGSIM_MAX_JOINTS; ++i) {
    const std::string w = "joint[" + std::to_string(i) + "].";
    eq_name(a.joint[i].name, b.joint[i].name, w + "name");
    eq_int(a.joint[i].kind, b.joint[i].kind, w + "kind");
    for (int s = 0; s < 2; ++s) {
      eq_int(a.joint[i].body[s], b.joint[i].body[s], w + "body[" + std::to_string(s) + "]");
      for (int c = 0; c < 2; ++c)
        eq_real(a.joint[i].point[s][c], b.joint[i].point[s][c],
                w + "point[" + std::to_string(s) + "][" + std::to_string(c) + "]");
    }
  }
  for (int i = 0; i < LEGSIM_MAX_ACTUATORS; ++i) {
    const std::string w = "actuator[" + std::to_string(i) + "].";
    const legsim_actuator_desc &x = a.actuator[i], &y = b.actuator[i];
    eq_name(x.name, y.name, w + "name");
    eq_int(x.joint, y.joint, w + "joint");
    eq_real(x.stroke_min_m, y.stroke_min_m, w + "stroke_min_m");
    eq_real(x.stroke_max_m, y.stroke_max_m, w + "stroke_max_m");
    eq_real(x.max_force_n, y.max_force_n, w + "max_force_n");
    eq_real(x.servo_kp_n_per_m, y.servo_kp_n_per_m, w + "servo_kp_n_per_m");
    eq_real(x.servo_kd_ns_per_m, y.servo_kd_ns_per_m, w + "servo_kd_ns_per_m");
  }
  for (int i = 0; i < LEGSIM_MAX_FORCES; ++i) {
    const std::string w = "force[" + std::to_string(i) + "].";
    const legsim_force_desc &x = a.force[i], &y = b.force[i];
    eq_name(x.name, y.name, w + "name");
    eq_int(x.kind, y.kind, w + "kind");
    for (int s = 0; s < 2; ++s) {
      eq_int(x.body[s], y.body[s], w + "body[" + std::to_string(s) + "]");
      for (int c = 0; c < 2; ++c)
        eq_real(x.point[s][c], y.point[s][c],
                w + "point[" + std::to_string(s) + "][" + std::to_string(c) + "]");
      eq_real(x.value[s], y.value[s], w + "value[" + std::to_string(s) + "]");
    }
    eq_real(x.stiffness_n_per_m, y.stiffness_n_per_m, w + "stiffness_n_per_m");
    eq_real(x.damping_ns_per_m, y.damping_ns_per_m, w + "damping_ns_per_m");
    eq_real(x.rest_length_m, y.rest_length_m, w + "rest_length_m");
  }
  for (int i = 0; i < LEGSIM_MAX_POSES; ++i) {
    const std::string w = "pose[" + std::to_string(i) + "].";
    const legsim_pose_desc &x = a.pose[i], &y = b.pose[i];
    eq_name(x.name, y.name, w + "name");
    eq_int(x.n_drivers, y.n_drivers, w + "n_drivers");
    for (int d = 0; d < LEGSIM_MAX_POSE_DRIVERS; ++d) {
      const std::string wd = w + "driver[" + std::to_string(d) + "].";
      eq_int(x.driver[d].body, y.driver[d].body, wd + "body");
      eq_int(x.driver[d].coord, y.driver[d].coord, wd + "coord");
      eq_real(x.driver[d].value, y.driver[d].value, wd + "value");
    }
    for (int bb = 0; bb < LEGSIM_MAX_BODIES; ++bb)
      for (int c = 0; c < 3; ++c)
        eq_real(x.guess[bb][c], y.guess[bb][c],
                w + "guess[" + std::to_string(bb) + "][" + std::to_string(c) + "]");
  }
  eq_int(a.foot_body, b.foot_body, "foot_body");
  for (int c = 0; c < 2; ++c) eq_real(a.foot_point[c], b.foot_point[c], "foot_point");
  eq_int(a.n_contacts, b.n_contacts, "n_contacts");
  for (int i = 0; i < LEGSIM_CONTACT_SLOTS; ++i) {
    const std::string w = "contact[" + std::to_string(i) + "].";
    eq_name(a.contact[i].name, b.contact[i].name, w + "name");
    eq_int(a.contact[i].body, b.contact[i].body, w + "body");
    for (int c = 0; c < 2; ++c) eq_real(a.contact[i].point[c], b.contact[i].point[c], w + "point");
  }
  for (int c = 0; c < 2; ++c) eq_real(a.ground.point[c], b.ground.point[c], "ground.point");
  eq_real(a.ground.slope_rad, b.ground.slope_rad, "ground.slope_rad");
  eq_real(a.ground.mu_static, b.ground.mu_static, "ground.mu_static");
  eq_real(a.ground.mu_kinetic, b.ground.mu_kinetic, "ground.mu_kinetic");
  return g_diff;
}

legsim_model_desc load_ok(const char *path, const char *variant) {
  legsim_model_desc d;
  std::memset(&d, 0, sizeof d);
  char msg[512] = {0};
  const legsim_status st = legsim_model_load_toml(path, variant, &d, msg, sizeof msg);
  if (st != LEGSIM_OK) {
    const std::string m = std::string(path) + " [" + variant + "]: " + legsim_status_str(st) + ": " + msg;
    TEST_FAIL_MESSAGE(m.c_str());
  }
  return d;
}

void check_same(const char *path, const legsim_model_variant *variants, int32_t count) {
  for (int32_t v = 0; v < count; ++v) {
    const legsim_model_desc loaded = load_ok(path, variants[v].name);
    const std::string diff = compare(loaded, *variants[v].model);
    const std::string m = std::string(path) + " [" + variants[v].name + "]: loaded vs generated: " + diff;
    TEST_ASSERT_TRUE_MESSAGE(diff.empty(), m.c_str());
  }
}

int find_joint(const legsim_model_desc &m, const char *name) {
  for (int i = 0; i < m.n_joints; ++i)
    if (std::strcmp(m.joint[i].name, name) == 0) return i;
  return -1;
}

}  // namespace

// ---- generated == loaded --------------------------------------------------------------
static void test_leg_generated_equals_loaded(void) {
  TEST_ASSERT_EQUAL_INT32(2, legsim_model_leg_variant_count);
  TEST_ASSERT_EQUAL_STRING("revolute", legsim_model_leg_variants[0].name);
  TEST_ASSERT_EQUAL_STRING("slot", legsim_model_leg_variants[1].name);
  TEST_ASSERT_EQUAL_PTR(&legsim_model_leg_revolute, legsim_model_leg_variants[0].model);
  TEST_ASSERT_EQUAL_PTR(&legsim_model_leg_slot, legsim_model_leg_variants[1].model);
  check_same(kLeg, legsim_model_leg_variants, legsim_model_leg_variant_count);
}

static void test_leg_compiled_as_cxx_equals_c(void) {
  TEST_ASSERT_EQUAL_INT32(legsim_model_leg_variant_count, legsim_model_leg_cxx_variant_count);
  for (int32_t v = 0; v < legsim_model_leg_variant_count; ++v) {
    const std::string diff = compare(*legsim_model_leg_cxx_variants[v].model, *legsim_model_leg_variants[v].model);
    TEST_ASSERT_TRUE_MESSAGE(diff.empty(), diff.c_str());
  }
}

static void test_mini_generated_equals_loaded(void) {
  // Every feature of the format: "at" points, ids out of order, all force kinds, x/y drivers...
  TEST_ASSERT_EQUAL_INT32(3, legsim_model_mini_variant_count);
  TEST_ASSERT_EQUAL_STRING("stiff", legsim_model_mini_variants[1].name);  // file order
  TEST_ASSERT_EQUAL_STRING("slider", legsim_model_mini_variants[2].name);
  check_same(kMini, legsim_model_mini_variants, legsim_model_mini_variant_count);
}

static void test_variant_names_in_compiled_in_order(void) {
  char names[4][LEGSIM_NAME_LEN];
  int32_t n = 0;
  char msg[256];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_model_toml_variants(kMini, names, 4, &n, msg, sizeof msg));
  TEST_ASSERT_EQUAL_INT32(legsim_model_mini_variant_count, n);
  for (int32_t i = 0; i < n; ++i) TEST_ASSERT_EQUAL_STRING(legsim_model_mini_variants[i].name, names[i]);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_model_toml_variants(kLeg, names, 1, &n, msg, sizeof msg));
  TEST_ASSERT_EQUAL_INT32(2, n);  // the total, though only one name fits
  TEST_ASSERT_EQUAL_STRING("revolute", names[0]);
}

// ---- the mapping, spot checks against leg.toml ------------------------------------------
static void test_leg_mapping(void) {
  const legsim_model_desc &m = legsim_model_leg_revolute;
  TEST_ASSERT_EQUAL_STRING("inta-csic-leg", m.name);
  TEST_ASSERT_EQUAL_INT32(6, m.n_bodies);
  TEST_ASSERT_EQUAL_INT32(8, m.n_joints);
  TEST_ASSERT_EQUAL_INT32(2, m.n_actuators);
  TEST_ASSERT_EQUAL_DOUBLE(-9.81, m.gravity_mps2[1]);
  // Inertia defaults to m L^2 / 12.
  TEST_ASSERT_EQUAL_STRING("thigh", m.body[2].name);
  TEST_ASSERT_EQUAL_DOUBLE(1.5 * 0.5 * 0.5 / 12.0, m.body[2].inertia_kgm2);
  // revolute_to_frame: proximal end (-L/2, 0) of body 1 on frame point A (0, 0.25).
  const int a = find_joint(m, "A");
  TEST_ASSERT_EQUAL_INT(0, a);
  TEST_ASSERT_EQUAL_INT(LEGSIM_JOINT_REVOLUTE_TO_FRAME, m.joint[a].kind);
  TEST_ASSERT_EQUAL_INT32(0, m.joint[a].body[0]);
  TEST_ASSERT_EQUAL_INT32(LEGSIM_FRAME, m.joint[a].body[1]);
  TEST_ASSERT_EQUAL_DOUBLE(-0.2, m.joint[a].point[0][0]);
  TEST_ASSERT_EQUAL_DOUBLE(0.0, m.joint[a].point[1][0]);
  TEST_ASSERT_EQUAL_DOUBLE(0.25, m.joint[a].point[1][1]);
  // revolute with ends distal/proximal: C_rod_shank = bodies 2 and 6.
  const int c = find_joint(m, "C_rod_shank");
  TEST_ASSERT_EQUAL_INT32(1, m.joint[c].body[0]);
  TEST_ASSERT_EQUAL_INT32(5, m.joint[c].body[1]);
  TEST_ASSERT_EQUAL_DOUBLE(0.2, m.joint[c].point[0][0]);
  TEST_ASSERT_EQUAL_DOUBLE(-0.3, m.joint[c].point[1][0]);
  // D: revolute at (-0.10, 0) on the shank; the slot variant puts the distal end of 5
  // on the axis of 6 (point[1] unused).
  const int d = find_joint(m, "D");
  TEST_ASSERT_EQUAL_INT(LEGSIM_JOINT_REVOLUTE, m.joint[d].kind);
  TEST_ASSERT_EQUAL_DOUBLE(0.175, m.joint[d].point[0][0]);
  TEST_ASSERT_EQUAL_DOUBLE(-0.10, m.joint[d].point[1][0]);
  const legsim_model_desc &s = legsim_model_leg_slot;
  TEST_ASSERT_EQUAL_INT(LEGSIM_JOINT_SLOT, s.joint[d].kind);
  TEST_ASSERT_EQUAL_INT32(4, s.joint[d].body[0]);
  TEST_ASSERT_EQUAL_INT32(5, s.joint[d].body[1]);
  TEST_ASSERT_EQUAL_DOUBLE(0.175, s.joint[d].point[0][0]);
  TEST_ASSERT_EQUAL_DOUBLE(0.0, s.joint[d].point[1][0]);
  // Actuators on the prismatic joints, in order.
  TEST_ASSERT_EQUAL_STRING("upper", m.actuator[0].name);
  TEST_ASSERT_EQUAL_INT32(find_joint(m, "upper_actuator"), m.actuator[0].joint);
  TEST_ASSERT_EQUAL_INT32(find_joint(m, "lower_actuator"), m.actuator[1].joint);
  TEST_ASSERT_EQUAL_DOUBLE(0.35, m.actuator[1].stroke_min_m);
  TEST_ASSERT_EQUAL_DOUBLE(0.70, m.actuator[1].stroke_max_m);
  TEST_ASSERT_EQUAL_DOUBLE(1500.0, m.actuator[1].max_force_n);
  TEST_ASSERT_EQUAL_DOUBLE(20000.0, m.actuator[1].servo_kp_n_per_m);
  TEST_ASSERT_EQUAL_DOUBLE(400.0, m.actuator[1].servo_kd_ns_per_m);
  // Foot load and foot at the shank's distal end.
  TEST_ASSERT_EQUAL_INT(LEGSIM_FORCE_POINT, m.force[0].kind);
  TEST_ASSERT_EQUAL_INT32(5, m.force[0].body[0]);
  TEST_ASSERT_EQUAL_DOUBLE(0.3, m.force[0].point[0][0]);
  TEST_ASSERT_EQUAL_INT32(5, m.foot_body);
  TEST_ASSERT_EQUAL_DOUBLE(0.3, m.foot_point[0]);
  TEST_ASSERT_EQUAL_DOUBLE(0.0, m.foot_point[1]);
}

static void test_stand_pose_drivers(void) {
  for (int32_t v = 0; v < legsim_model_leg_variant_count; ++v) {
    const legsim_model_desc &m = *legsim_model_leg_variants[v].model;
    TEST_ASSERT_EQUAL_INT32(1, m.n_poses);
    const legsim_pose_desc &p = m.pose[0];
    TEST_ASSERT_EQUAL_STRING("stand", p.name);
    TEST_ASSERT_EQUAL_INT32(2, p.n_drivers);
    // phi3 = 60 deg -> body 2, coord 2; phi6 = 0 -> body 5, coord 2.
    TEST_ASSERT_EQUAL_INT32(2, p.driver[0].body);
    TEST_ASSERT_EQUAL_INT32(2, p.driver[0].coord);
    TEST_ASSERT_EQUAL_DOUBLE(1.0471975511965976, p.driver[0].value);
    TEST_ASSERT_DOUBLE_WITHIN(1e-15, std::acos(-1.0) / 3.0, p.driver[0].value);
    TEST_ASSERT_EQUAL_INT32(5, p.driver[1].body);
    TEST_ASSERT_EQUAL_INT32(2, p.driver[1].coord);
    TEST_ASSERT_EQUAL_DOUBLE(0.0, p.driver[1].value);
    // guess rows per body [x, y, phi].
    TEST_ASSERT_EQUAL_DOUBLE(0.1309307341, p.guess[0][0]);
    TEST_ASSERT_EQUAL_DOUBLE(0.7137243789, p.guess[0][2]);
    TEST_ASSERT_EQUAL_DOUBLE(-0.55, p.guess[5][1]);
    TEST_ASSERT_EQUAL_DOUBLE(0.0, p.guess[5][2]);
  }
  // x/y/phi drivers, sorted by (body, coord) whatever the file order.
  const legsim_pose_desc &p = legsim_model_mini_revolute.pose[0];
  TEST_ASSERT_EQUAL_STRING("start", p.name);
  TEST_ASSERT_EQUAL_INT32(3, p.n_drivers);
  const int want[3][2] = {{0, 0}, {0, 2}, {1, 1}};
  const double val[3] = {0.0, -0.5, -0.3};
  for (int i = 0; i < 3; ++i) {
    TEST_ASSERT_EQUAL_INT32(want[i][0], p.driver[i].body);
    TEST_ASSERT_EQUAL_INT32(want[i][1], p.driver[i].coord);
    TEST_ASSERT_EQUAL_DOUBLE(val[i], p.driver[i].value);
  }
  TEST_ASSERT_EQUAL_STRING("alt", legsim_model_mini_revolute.pose[1].name);  // file order
}

static void test_generated_models_pass_the_core_check(void) {
  const legsim_model_variant *sets[] = {legsim_model_leg_variants, legsim_model_mini_variants};
  const int32_t counts[] = {legsim_model_leg_variant_count, legsim_model_mini_variant_count};
  for (int k = 0; k < 2; ++k)
    for (int32_t v = 0; v < counts[k]; ++v) {
      char msg[256] = {0};
      const legsim_status st = legsim_model_check(sets[k][v].model, msg, sizeof msg);
      const std::string m = std::string(sets[k][v].name) + ": " + msg;
      TEST_ASSERT_EQUAL_INT_MESSAGE(LEGSIM_OK, st, m.c_str());
    }
}

// ---- bad inputs -----------------------------------------------------------------------------
static legsim_status status_named(const std::string &s) {
  static const struct {
    const char *name;
    legsim_status st;
  } table[] = {{"LEGSIM_ERR_MODEL", LEGSIM_ERR_MODEL},
               {"LEGSIM_ERR_CAPACITY", LEGSIM_ERR_CAPACITY},
               {"LEGSIM_ERR_BAD_INPUT", LEGSIM_ERR_BAD_INPUT}};
  for (const auto &e : table)
    if (s == e.name) return e.st;
  TEST_FAIL_MESSAGE(("expected.tsv: unknown status " + s).c_str());
  return LEGSIM_OK;
}

static std::string substitute_capacities(std::string s) {
  const struct {
    const char *macro;
    int value;
  } caps[] = {{"${LEGSIM_MAX_BODIES}", LEGSIM_MAX_BODIES},
              {"${LEGSIM_MAX_JOINTS}", LEGSIM_MAX_JOINTS},
              {"${LEGSIM_MAX_ACTUATORS}", LEGSIM_MAX_ACTUATORS},
              {"${LEGSIM_MAX_FORCES}", LEGSIM_MAX_FORCES},
              {"${LEGSIM_MAX_POSES}", LEGSIM_MAX_POSES},
              {"${LEGSIM_MAX_POSE_DRIVERS}", LEGSIM_MAX_POSE_DRIVERS}};
  for (const auto &c : caps)
    for (size_t p; (p = s.find(c.macro)) != std::string::npos;)
      s.replace(p, std::strlen(c.macro), std::to_string(c.value));
  return s;
}

static void test_bad_fixtures_give_expected_errors(void) {
  std::ifstream f(std::string(kFixtures) + "expected.tsv");
  TEST_ASSERT_TRUE_MESSAGE(f.good(), "cannot read tests/model/fixtures/expected.tsv");
  std::string line, failures;
  int n = 0;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> col;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, '\t');) col.push_back(c);
    TEST_ASSERT_EQUAL_INT_MESSAGE(5, (int)col.size(), line.c_str());
    const std::string path = kFixtures + col[0];
    const std::string want = path + ": " + substitute_capacities(col[4]);
    const legsim_status want_st = status_named(col[2]);

    legsim_model_desc d;
    std::memset(&d, 0x5a, sizeof d);
    const legsim_model_desc before = d;
    char msg[512] = {0};
    const legsim_status st = legsim_model_load_toml(path.c_str(), col[1].c_str(), &d, msg, sizeof msg);
    const std::string got = msg;
    const bool msg_ok = col[3] == "exact" ? got == want : got.compare(0, want.size(), want) == 0;
    if (st != want_st || !msg_ok)
      failures += " | " + col[0] + ": got " + legsim_status_str(st) + " \"" + got + "\" want " +
                  col[2] + " \"" + want + "\"";
    if (std::memcmp(&d, &before, sizeof d) != 0) failures += " | " + col[0] + ": *out written on error";
    ++n;
  }
  TEST_ASSERT_GREATER_OR_EQUAL_INT(40, n);
  TEST_ASSERT_TRUE_MESSAGE(failures.empty(), failures.c_str());
}

static void test_every_fixture_is_listed(void) {
  // A bad fixture that expected.tsv does not name would go untested.
  std::ifstream f(std::string(kFixtures) + "expected.tsv");
  std::stringstream all;
  all << f.rdbuf();
  int n = 0;
  for (const auto &e : std::filesystem::directory_iterator(kFixtures)) {
    const std::string name = e.path().filename().string();
    if (e.path().extension() != ".toml" || name.rfind("good_", 0) == 0) continue;
    TEST_ASSERT_TRUE_MESSAGE(all.str().find("\n" + name + "\t") != std::string::npos,
                             (name + " is not in expected.tsv").c_str());
    ++n;
  }
  TEST_ASSERT_GREATER_OR_EQUAL_INT(40, n);
}

static void test_loader_api_errors(void) {
  legsim_model_desc d;
  char msg[256];
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_NULL, legsim_model_load_toml(nullptr, nullptr, &d, msg, sizeof msg));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_NULL, legsim_model_load_toml(kLeg, nullptr, nullptr, msg, sizeof msg));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT,
                        legsim_model_load_toml("tests/model/fixtures/no_such_file.toml", nullptr, &d, msg, sizeof msg));
  TEST_ASSERT_NOT_NULL(std::strstr(msg, "no_such_file.toml: cannot read"));
  // NULL or empty variant = "revolute"; msg may be NULL.
  legsim_model_desc d2;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_model_load_toml(kLeg, nullptr, &d, nullptr, 0));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_model_load_toml(kLeg, "", &d2, msg, sizeof msg));
  TEST_ASSERT_TRUE(compare(d, legsim_model_leg_revolute).empty());
  TEST_ASSERT_TRUE(compare(d2, legsim_model_leg_revolute).empty());
  // The message is truncated to the buffer, NUL-terminated.
  char small[12];
  std::memset(small, 'x', sizeof small);
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_model_load_toml(kLeg, "knee", &d, small, sizeof small));
  TEST_ASSERT_EQUAL_size_t(sizeof small - 1, std::strlen(small));
  TEST_ASSERT_EQUAL_INT(0, std::strncmp(small, kLeg, sizeof small - 1));
}

static void test_parse_from_memory(void) {
  std::ifstream f(kLeg);
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string text = ss.str();
  legsim_model_desc d;
  char msg[256];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK,
                        legsim_model_parse_toml(text.data(), text.size(), "mem", "slot", &d, msg, sizeof msg));
  TEST_ASSERT_TRUE(compare(d, legsim_model_leg_slot).empty());
  const std::string bad = text + "\n[[body]]\nid = 7\nname = \"extra\"\nlength = -1.0\nmass = 1.0\n";
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_MODEL,
                        legsim_model_parse_toml(bad.data(), bad.size(), "mem", nullptr, &d, msg, sizeof msg));
  TEST_ASSERT_EQUAL_STRING("mem: body 'extra': 'length' must be positive (got -1)", msg);
}

// ---- hostile text: bounded before toml++ sees it -------------------------------------------
// toml++ 3.3.0 overflows the stack on a key or header of 50,000 dotted parts (about 100 KB)
// and reaches code it marks unreachable on `zz = 1` followed by a non-ASCII letter; the
// small cases are fixtures (expected.tsv), the large ones are made here.
static std::string leg_text() {
  std::ifstream f(kLeg, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

static void expect_refused(const std::string &text, const std::string &why) {
  legsim_model_desc d;
  std::memset(&d, 0, sizeof d);
  char msg[512] = {0};
  const legsim_status st = legsim_model_parse_toml(text.data(), text.size(), "mem", nullptr, &d, msg, sizeof msg);
  TEST_ASSERT_EQUAL_INT_MESSAGE(LEGSIM_ERR_MODEL, st, msg);
  TEST_ASSERT_EQUAL_STRING(("mem: TOML input refused: " + why).c_str(), msg);
}

static std::string repeat(const std::string &part, int n, const std::string &sep) {
  std::string s;
  for (int i = 0; i < n; ++i) s += (i ? sep : "") + part;
  return s;
}

static void test_hostile_text_is_refused_before_parsing(void) {
  const std::string parts = "a key or table header of more than 16 dotted parts (line 1)";
  expect_refused(repeat("a", 50000, ".") + " = 1\n", parts);
  expect_refused("[" + repeat("a", 50000, ".") + "]\n", parts);
  expect_refused("[[" + repeat("b", 50000, ".") + "]]\n", parts);
  expect_refused(repeat("\"q\"", 50000, ".") + " = 1\n", parts);
  const std::string nested = "arrays, inline tables or headers nested deeper than 16 (line 1)";
  expect_refused("a = " + std::string(10000, '[') + std::string(10000, ']') + "\n", nested);
  expect_refused("a = " + repeat("{b = ", 10000, "") + "1" + std::string(10000, '}') + "\n", nested);
  expect_refused("zz = 1\n\xce\xb1\n", "a non-ASCII character outside a string or comment (line 2)");
  const std::string leg = leg_text();
  const long last = std::count(leg.begin(), leg.end(), '\n') + 1;
  expect_refused(leg + "\xc3\xa9 = 1\n",
                 "a non-ASCII character outside a string or comment (line " + std::to_string(last) + ")");
  expect_refused("a = \"\xed\xa0\x80\"\n", "invalid UTF-8 (line 1)");  // a surrogate
  // a backslash before a non-ASCII character (U+01A5), in a string and a multi-line string
  const std::string escape = "a backslash before a non-ASCII character in a string (line 1)";
  expect_refused("a = \"x\\\xc6\xa5\"\n", escape);
  expect_refused("bsp = \"\"\"0.00( t\\\xc6\xa5" "cprn\\x", escape);  // found by fuzz_model
  // larger than 1 MiB: refused from memory, and from a file without reading it whole
  std::string big = leg_text();
  big += "#" + std::string(kTomlMaxBytes - big.size(), 'x');
  expect_refused(big, "larger than 1048576 bytes");
  const std::string path = (std::filesystem::temp_directory_path() / "legsim_test_big_model.toml").string();
  {
    std::ofstream f(path, std::ios::binary);
    f << big;
  }
  legsim_model_desc d;
  char msg[512] = {0};
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_MODEL, legsim_model_load_toml(path.c_str(), nullptr, &d, msg, sizeof msg));
  TEST_ASSERT_EQUAL_STRING((path + ": TOML input refused: larger than 1048576 bytes").c_str(), msg);
  std::filesystem::remove(path);
}

static void test_text_within_the_limits_still_loads(void) {
  // exactly 1 MiB, 16 dotted parts, nesting 16, non-ASCII in comments and strings
  std::string text = leg_text() + "# \xc3\xa9t\xc3\xa9, \xce\xb1, \xf0\x9f\xa6\xbf\n";
  text += "#" + std::string(kTomlMaxBytes - text.size() - 2, 'x') + "\n";
  TEST_ASSERT_EQUAL_size_t(kTomlMaxBytes, text.size());
  legsim_model_desc d;
  char msg[512] = {0};
  TEST_ASSERT_EQUAL_INT_MESSAGE(LEGSIM_OK, legsim_model_parse_toml(text.data(), text.size(), "mem", nullptr, &d, msg, sizeof msg), msg);
  TEST_ASSERT_TRUE(compare(d, legsim_model_leg_revolute).empty());
  std::string why;
  TEST_ASSERT_TRUE(toml_input_within_limits(repeat("a", 16, ".") + " = 1.5\n", why));
  TEST_ASSERT_TRUE(toml_input_within_limits("a = " + std::string(16, '[') + std::string(16, ']'), why));
  TEST_ASSERT_TRUE(toml_input_within_limits("s = \"\\\"\xc3\xa9.[{\" # \xc3\xa9\nt = '''\xc3\xa9\n'''''\nu = 1979-05-27T07:32:00.999", why));
  TEST_ASSERT_FALSE(toml_input_within_limits(repeat("a", 17, ".") + " = 1", why));
  TEST_ASSERT_EQUAL_STRING("a key or table header of more than 16 dotted parts (line 1)", why.c_str());
  // a name with non-ASCII letters in a string: the loader's own message, no crash
  const std::string named = "name = \"b\xc3\xa9in\"\n";
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_MODEL, legsim_model_parse_toml(named.data(), named.size(), "mem", nullptr, &d, msg, sizeof msg));
  TEST_ASSERT_EQUAL_STRING("mem: model: name 'b\xc3\xa9in' may hold only letters, digits, '_', '-' and '.'", msg);
}


// ---- the robot file: a box with the leg file placed twice -------------------------------
static void test_robot_generated_equals_loaded(void) {
#if HAVE_ROBOT
  TEST_ASSERT_EQUAL_INT32(1, legsim_model_robot_variant_count);
  check_same("models/robot.toml", legsim_model_robot_variants, legsim_model_robot_variant_count);
#else
  TEST_IGNORE_MESSAGE("this build's capacities do not hold the robot");
#endif
}

static void test_robot_mapping(void) {
  legsim_model_desc r, leg = load_ok(kLeg, "revolute");
  std::memset(&r, 0, sizeof r);
  char msg[512] = {0};
  const legsim_status st = legsim_model_load_toml("models/robot.toml", nullptr, &r, msg, sizeof msg);
  if (LEGSIM_MAX_BODIES < 13 || LEGSIM_MAX_CONTACTS < 2) {
    TEST_ASSERT_EQUAL_INT_MESSAGE(LEGSIM_ERR_CAPACITY, st, msg);
    return;
  }
  TEST_ASSERT_EQUAL_INT_MESSAGE(LEGSIM_OK, st, msg);
  TEST_ASSERT_EQUAL_INT32(13, r.n_bodies);
  TEST_ASSERT_EQUAL_INT32(16, r.n_joints);
  TEST_ASSERT_EQUAL_INT32(4, r.n_actuators);
  TEST_ASSERT_EQUAL_INT32(2, r.n_contacts);
  TEST_ASSERT_EQUAL_INT32(-1, r.foot_body);
  TEST_ASSERT_EQUAL_STRING("box", r.body[0].name);
  TEST_ASSERT_EQUAL_DOUBLE(20.0, r.body[0].mass_kg);
  TEST_ASSERT_EQUAL_STRING("left.thigh", r.body[9].name);
  // the right leg: translated; the left: reflected (body-fixed eta negated)
  const int d = find_joint(leg, "D"), a = find_joint(leg, "A");
  TEST_ASSERT_EQUAL_INT32(leg.joint[d].body[0] + 1, r.joint[d].body[0]);
  TEST_ASSERT_EQUAL_INT32(leg.joint[d].body[0] + 7, r.joint[8 + d].body[0]);
  TEST_ASSERT_EQUAL_DOUBLE(leg.joint[d].point[1][0], r.joint[8 + d].point[1][0]);
  TEST_ASSERT_EQUAL_DOUBLE(-leg.joint[d].point[1][1], r.joint[8 + d].point[1][1]);
  // frame joint A -> a revolute to the box at its attach point (x, y) = (+-0.20, 0.10),
  // in box body coordinates (xi, eta) = (-y, x)
  TEST_ASSERT_EQUAL_INT(LEGSIM_JOINT_REVOLUTE, r.joint[a].kind);
  TEST_ASSERT_EQUAL_INT32(0, r.joint[a].body[1]);
  TEST_ASSERT_EQUAL_DOUBLE(-0.10, r.joint[a].point[1][0]);
  TEST_ASSERT_EQUAL_DOUBLE(0.20, r.joint[a].point[1][1]);
  TEST_ASSERT_EQUAL_DOUBLE(-0.20, r.joint[8 + a].point[1][1]);
  TEST_ASSERT_EQUAL_STRING("right.upper", r.actuator[0].name);
  TEST_ASSERT_EQUAL_STRING("left.lower", r.actuator[3].name);
  TEST_ASSERT_EQUAL_INT32(8 + leg.actuator[1].joint, r.actuator[3].joint);
  TEST_ASSERT_EQUAL_STRING("right.foot", r.contact[0].name);
  TEST_ASSERT_EQUAL_INT32(1 + leg.foot_body, r.contact[0].body);
  TEST_ASSERT_EQUAL_INT32(7 + leg.foot_body, r.contact[1].body);
  TEST_ASSERT_EQUAL_DOUBLE(0.6, r.ground.mu_static);
  TEST_ASSERT_EQUAL_DOUBLE(0.5, r.ground.mu_kinetic);
  // the stand's guess: the feet on the ground line (y = 0) at +-0.633 m, the box 1 m up
  TEST_ASSERT_EQUAL_STRING("stand", r.pose[0].name);
  TEST_ASSERT_DOUBLE_WITHIN(1e-9, 1.0, r.pose[0].guess[0][1]);
  for (int k = 0; k < 2; ++k) {
    const double *gq = r.pose[0].guess[r.contact[k].body];
    const double xi = r.contact[k].point[0], eta = r.contact[k].point[1];
    const double fx = gq[0] + xi * std::sin(gq[2]) + eta * std::cos(gq[2]);
    const double fy = gq[1] - xi * std::cos(gq[2]) + eta * std::sin(gq[2]);
    TEST_ASSERT_DOUBLE_WITHIN(1e-9, k == 0 ? 0.6330127019 : -0.6330127019, fx);
    TEST_ASSERT_DOUBLE_WITHIN(1e-12, 0.0, fy);
  }
  TEST_ASSERT_EQUAL_INT_MESSAGE(LEGSIM_OK, legsim_model_check(&r, msg, sizeof msg), msg);
}

// ---- files that are not regular files ------------------------------------------------------
// The load in a child process, so that a load that blocks fails the test (after 10 s)
// instead of hanging it: "STATUS MESSAGE", or "blocked".
static std::string load_in_child(const std::string &path) {
  int fd[2];
  TEST_ASSERT_EQUAL_INT(0, ::pipe(fd));
  const pid_t pid = ::fork();
  TEST_ASSERT_TRUE(pid >= 0);
  if (pid == 0) {
    ::close(fd[0]);
    legsim_model_desc d;
    char msg[512] = {0};
    const legsim_status st = legsim_model_load_toml(path.c_str(), nullptr, &d, msg, sizeof msg);
    const std::string out = std::to_string(static_cast<int>(st)) + " " + msg;
    if (::write(fd[1], out.data(), out.size()) < 0) ::_exit(2);
    ::_exit(0);
  }
  ::close(fd[1]);
  int wstatus = 0;
  bool done = false;
  for (int i = 0; i < 1000 && !done; ++i) {  // 10 s
    done = ::waitpid(pid, &wstatus, WNOHANG) == pid;
    if (!done) ::usleep(10000);
  }
  if (!done) {
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &wstatus, 0);
    ::close(fd[0]);
    return "blocked";
  }
  std::string out;
  char buf[512];
  for (ssize_t k; (k = ::read(fd[0], buf, sizeof buf)) > 0;) out.append(buf, static_cast<size_t>(k));
  ::close(fd[0]);
  return out;
}

static void test_non_regular_files_are_refused_without_blocking(void) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("legsim_test_fifo_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string fifo = (dir / "leg.toml").string(), robot = (dir / "robot.toml").string();
  TEST_ASSERT_EQUAL_INT(0, ::mkfifo(fifo.c_str(), 0600));
  {
    std::ofstream f(robot);
    f << "name = \"fifo-biped\"\n[box]\nmass = 20.0\nsize = [0.6, 0.3]\ninertia = 0.75\n"
         "[[leg]]\nname = \"right\"\nfile = \"leg.toml\"\nattach = { A = [0.2, 0.1], B = [0.2, -0.15] }\n"
         "[ground]\nmu_static = 0.6\nmu_kinetic = 0.5\n";
  }
  const std::string bad = std::to_string(static_cast<int>(LEGSIM_ERR_BAD_INPUT)) + " ";
  // a robot whose leg file is a FIFO, the FIFO as the model file, a folder
  TEST_ASSERT_EQUAL_STRING((bad + robot + ": leg 'right': file 'leg.toml': cannot read: not a regular file").c_str(),
                           load_in_child(robot).c_str());
  TEST_ASSERT_EQUAL_STRING((bad + fifo + ": cannot read: not a regular file").c_str(), load_in_child(fifo).c_str());
  TEST_ASSERT_EQUAL_STRING((bad + dir.string() + ": cannot read: not a regular file").c_str(),
                           load_in_child(dir.string()).c_str());
  char names[2][LEGSIM_NAME_LEN];
  int32_t n = 0;
  char msg[256];
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_model_toml_variants(fifo.c_str(), names, 2, &n, msg, sizeof msg));
  fs::remove_all(dir);
}

// ---- the ground's slope: one rule, one constant of legsim.h ------------------------------
// LEGSIM_MAX_SLOPE_RAD is the bound; legsim_ground_desc's documentation states it by name
// ("|slope_rad| <= LEGSIM_MAX_SLOPE_RAD = B rad" with B its value, below pi/2); the loader and
// the core's check both take a slope of B and refuse the next double past it.
static void test_slope_rule_is_the_headers(void) {
  std::ifstream f("firmware_core/include/legsim/legsim.h");
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string h = ss.str();
  const size_t end = h.find("typedef struct legsim_ground_desc");
  TEST_ASSERT_TRUE(end != std::string::npos);
  const std::string doc = h.substr(h.rfind("/*", end), end - h.rfind("/*", end));
  const std::string rule = "|slope_rad| <= LEGSIM_MAX_SLOPE_RAD = ";
  const size_t at = doc.find(rule);
  TEST_ASSERT_TRUE_MESSAGE(at != std::string::npos, ("legsim.h states no \"" + rule + "B\": " + doc).c_str());
  const double bound = LEGSIM_MAX_SLOPE_RAD;
  TEST_ASSERT_EQUAL_DOUBLE(bound, std::strtod(doc.c_str() + at + rule.size(), nullptr));
  TEST_ASSERT_TRUE(bound > 1.0 && bound < std::acos(-1.0) / 2);
  const double past = std::nextafter(bound, 2.0);
#if LEGSIM_MAX_CONTACTS >= 2 && LEGSIM_MAX_BODIES >= 13
  char buf[32];
  for (const double slope : {bound, -bound, past, -past}) {
    std::ifstream rf("models/robot.toml");
    std::stringstream rs;
    rs << rf.rdbuf();
    std::string text = rs.str();
    const size_t k = text.find("slope = 0.0");
    TEST_ASSERT_TRUE(k != std::string::npos);
    std::snprintf(buf, sizeof buf, "%.17g", slope);
    text.replace(k, std::strlen("slope = 0.0"), std::string("slope = ") + buf);
    legsim_model_desc d;
    char msg[512] = {0};
    const legsim_status st =
        legsim_model_parse_toml(text.data(), text.size(), "models/robot.toml", nullptr, &d, msg, sizeof msg);
    if (std::abs(slope) <= bound) {
      TEST_ASSERT_EQUAL_INT_MESSAGE(LEGSIM_OK, st, msg);
      TEST_ASSERT_EQUAL_DOUBLE(slope, d.ground.slope_rad);
    } else {
      TEST_ASSERT_EQUAL_INT_MESSAGE(LEGSIM_ERR_MODEL, st, msg);
      std::snprintf(buf, sizeof buf, "%g", bound);
      const std::string want = std::string("models/robot.toml: ground: 'slope' must be in [-") + buf + ", " + buf + "] rad";
      TEST_ASSERT_EQUAL_INT_MESSAGE(0, std::string(msg).compare(0, want.size(), want), msg);
    }
  }
#endif
  // the core's check, on the compiled-in leg given a ground
  legsim_model_desc m = legsim_model_leg_revolute;
  char msg[256];
  for (const double slope : {bound, -bound}) {
    m.ground.slope_rad = slope;
    TEST_ASSERT_EQUAL_INT_MESSAGE(LEGSIM_OK, legsim_model_check(&m, msg, sizeof msg), msg);
  }
  for (const double slope : {past, -past}) {
    m.ground.slope_rad = slope;
    TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_MODEL, legsim_model_check(&m, msg, sizeof msg));
  }
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_leg_generated_equals_loaded);
  RUN_TEST(test_leg_compiled_as_cxx_equals_c);
  RUN_TEST(test_mini_generated_equals_loaded);
  RUN_TEST(test_variant_names_in_compiled_in_order);
  RUN_TEST(test_leg_mapping);
  RUN_TEST(test_robot_generated_equals_loaded);
  RUN_TEST(test_robot_mapping);
  RUN_TEST(test_stand_pose_drivers);
  RUN_TEST(test_generated_models_pass_the_core_check);
  RUN_TEST(test_bad_fixtures_give_expected_errors);
  RUN_TEST(test_every_fixture_is_listed);
  RUN_TEST(test_loader_api_errors);
  RUN_TEST(test_parse_from_memory);
  RUN_TEST(test_hostile_text_is_refused_before_parsing);
  RUN_TEST(test_text_within_the_limits_still_loads);
  RUN_TEST(test_non_regular_files_are_refused_without_blocking);
  RUN_TEST(test_slope_rule_is_the_headers);
  return UNITY_END();
}
