// The hexapod file (models/hexapod.toml, legsim/hexapod.h) through the one model file parser
// (legsim_hexapod_load_toml) and the spatial module (robot_lift_hexapod):
// - its six legs are models/leg.toml as the compiled-in leg, bit for bit (the same loader);
// - lifted: 43 bodies, 234 rows, 12 linear actuators; the box level at the origin, every leg at
//   its stand and rowing angle 0: every row met, the six feet at one height, the right and left
//   feet mirror images across the box's x-z plane;
// - standing (robot_statics): on a tripod the feet's vertical forces are the closed form of the
//   centre of mass's place in the support triangle and their horizontal forces zero; on six
//   feet they balance the weight; each leg's actuator forces are the planar core's statics of
//   the leg under its foot's force (another formulation); the box's own equilibrium, from the
//   legs' hip multipliers, holds; a horizontal push on the box makes each stance leg's rowing
//   torque -((p_foot - p_hip) x f)_z; collinear feet, two feet and a tripod around which the
//   centre of mass falls (a foot would pull) are refused;
// - refused, each with a message naming the file, the item and the problem: a hexapod file given
//   to the model loader and a leg file given here, five legs, a horizontal gravity, a leg file
//   whose gravity differs, a leg without a [foot], a leg of the slot variant (no spatial rows
//   for a slot), a rowing stroke past pi, a ground normal
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
#include "hexapod_standing.hpp"
#include "spatial/statics.hpp"
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

namespace {
// The planar core's statics of the leg under a foot force (fx along its plane's x, fz up), N.
void planar_statics(const legsim_model_desc &leg, double fx, double fz, double *force) {
  legsim_options opt = legsim_default_options();
  legsim_sim *sim = nullptr;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage, sizeof storage, &leg, &opt, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  const double load[2] = {fx, fz};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_set_force(sim, 0, load));  // leg.toml's foot_load
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_statics(sim, force));
}

// The box's own equation from the legs' hip multipliers: J_box^T lambda - Q_box (its weight,
// the load, the rowing torques' reactions): zero when the whole robot and every leg balance.
double box_residual(const Standing &s, const RobotStatics &st, const double *box_force) {
  static Row rows[kMaxRobotRows];
  static double rest[kBodyDof * kMaxRobotBodies];
  robot_rows(s.robot, s.q, rest, rows);
  double r[6] = {0, 0, s.robot.mass[0] * 9.81, 0, 0, 0};  // -(its weight)
  for (int i = 0; i < 3; ++i) r[i] -= box_force ? box_force[i] : 0.0;
  for (int l = 0; l < 6; ++l) r[5] += st.rowing_torque[l];
  for (int k = 0; k < s.robot.nj; ++k) {
    const LegJoint &j = s.robot.joint[k];
    if (j.b != 0) continue;
    for (int row = j.row; row < j.row + j.nrows; ++row)
      for (int i = 0; i < 6; ++i) r[i] += rows[row].jb[i] * st.multiplier[row];
  }
  double worst = 0;
  for (double x : r) worst = std::fmax(worst, std::fabs(x));
  return worst;
}
}  // namespace

void test_standing_on_a_tripod(void) {
  Standing &s = standing();
  static RobotStatics st;
  const uint32_t tripod = 1u << 0 | 1u << 2 | 1u << 4;  // right front, right rear, left middle
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_statics(s.robot, s.q, tripod, nullptr, st));
  const double W = s.M * 9.81;
  // the closed form: the weight shared by the centre of mass's barycentric coordinates
  const V3 a = robot_foot_position(s.robot, 0, s.q), b = robot_foot_position(s.robot, 2, s.q),
           c = robot_foot_position(s.robot, 4, s.q);
  const double det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
  const double wb = ((s.com.x - a.x) * (c.y - a.y) - (c.x - a.x) * (s.com.y - a.y)) / det;
  const double wc = ((b.x - a.x) * (s.com.y - a.y) - (s.com.x - a.x) * (b.y - a.y)) / det;
  const double expect[3] = {(1 - wb - wc) * W, wb * W, wc * W};
  const int legs[3] = {0, 2, 4};
  for (int k = 0; k < 3; ++k) {
    const V3 &f = st.foot_force[legs[k]];
    printf("tripod: leg %d's foot force (%.3e, %.3e, %.9f) N, closed form %.9f N\n", legs[k], f.x, f.y, f.z,
           expect[k]);
    TEST_ASSERT_TRUE(std::fabs(f.z - expect[k]) <= 1e-9 * W);
    TEST_ASSERT_TRUE(std::fabs(f.x) <= 1e-9 * W && std::fabs(f.y) <= 1e-9 * W);
  }
  // each leg's actuators: the planar statics under its foot's vertical force; no rowing torque
  for (int l = 0; l < 6; ++l) {
    double planar[2];
    planar_statics(s.desc.leg[l].leg, 0.0, st.foot_force[l].z, planar);
    for (int i = 0; i < 2; ++i) {
      const double f = st.actuator_force[2 * l + i];
      TEST_ASSERT_TRUE_MESSAGE(std::fabs(f - planar[i]) <= 1e-9 * (1 + std::fabs(planar[i])), "actuator");
    }
    TEST_ASSERT_TRUE(std::fabs(st.rowing_torque[l]) <= 1e-9 * W);
  }
  printf("tripod: leg 0's actuators %.6f, %.6f N; the box's residual %.2e N\n", st.actuator_force[0],
         st.actuator_force[1], box_residual(s, st, nullptr));
  TEST_ASSERT_TRUE(box_residual(s, st, nullptr) <= 1e-9 * W);
}

void test_standing_on_six_feet_and_pushed(void) {
  Standing &s = standing();
  static RobotStatics st;
  const double W = s.M * 9.81;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_statics(s.robot, s.q, 0x3F, nullptr, st));
  double fz = 0;
  for (int l = 0; l < 6; ++l) {
    fz += st.foot_force[l].z;
    double planar[2];
    planar_statics(s.desc.leg[l].leg, 0.0, st.foot_force[l].z, planar);
    for (int i = 0; i < 2; ++i) TEST_ASSERT_TRUE(std::fabs(st.actuator_force[2 * l + i] - planar[i]) <= 1e-9 * W);
  }
  TEST_ASSERT_TRUE(std::fabs(fz - W) <= 1e-9 * W);
  TEST_ASSERT_TRUE(box_residual(s, st, nullptr) <= 1e-9 * W);
  // a push on the box, on the tripod: horizontal foot forces, and rowing torques that balance
  // their moments about the hip axes
  const double push[3] = {30.0, -20.0, 0.0};
  const uint32_t tripod = 1u << 0 | 1u << 2 | 1u << 4;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_statics(s.robot, s.q, tripod, push, st));
  double fx = 0, fy = 0;
  for (int l : {0, 2, 4}) {
    const V3 f = st.foot_force[l], p = robot_foot_position(s.robot, l, s.q);
    const double *hip = s.desc.leg[l].hip_m;
    const double expect = -((p.x - hip[0]) * f.y - (p.y - hip[1]) * f.x);
    printf("pushed: leg %d's rowing torque %.9f N m, -((p - hip) x f)_z %.9f N m\n", l, st.rowing_torque[l], expect);
    TEST_ASSERT_TRUE(std::fabs(st.rowing_torque[l] - expect) <= 1e-9 * (1 + std::fabs(expect)));
    TEST_ASSERT_TRUE(std::fabs(expect) > 0.1);
    fx += f.x, fy += f.y;
  }
  TEST_ASSERT_TRUE(std::fabs(fx + push[0]) <= 1e-9 * W && std::fabs(fy + push[1]) <= 1e-9 * W);
  TEST_ASSERT_TRUE(box_residual(s, st, push) <= 1e-9 * W);
}

void test_leg_targets_round_trip(void) {
  // each foot of the lifted stand (legs at unequal rowing angles) given back as a target: its
  // rowing angle and its planar foot point; the planar leg's inverse kinematics at that point
  // gives back the stand's lengths
  Standing &s = standing();
  const double psi_set[6] = {0.3, 0.1, -0.2, 0.0, 0.25, -0.15};
  legsim_options opt = legsim_default_options();
  legsim_sim *sim = nullptr;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage, sizeof storage, &s.desc.leg[0].leg, &opt, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  double stand_foot[2], stand_len[2];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_foot_position(sim, stand_foot));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_actuator_lengths(sim, stand_len, nullptr));
  for (int l = 0; l < 6; ++l) {
    const V3 f = robot_foot_position(s.robot, l, s.q);  // the box at the origin, level: its frame
    double psi, xy[2];
    leg_plane_target(s.robot, l, f, psi, xy);
    TEST_ASSERT_TRUE(std::fabs(psi - psi_set[l]) < 1e-14);
    TEST_ASSERT_TRUE(std::fabs(xy[0] - stand_foot[0]) < 1e-14 && std::fabs(xy[1] - stand_foot[1]) < 1e-14);
    // from a pose off the stand, the inverse kinematics finds the stand's lengths again
    const double other[2] = {0.62, 0.60};
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble(sim, other));
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_foot(sim, xy));
    double len[2];
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_actuator_lengths(sim, len, nullptr));
    TEST_ASSERT_TRUE(std::fabs(len[0] - stand_len[0]) < 1e-9 && std::fabs(len[1] - stand_len[1]) < 1e-9);
  }
  // a foot behind the hip axis: the plane turned back by pi, the planar x beyond the axis
  double psi, xy[2];
  const V3 hip = {s.desc.leg[0].hip_m[0], s.desc.leg[0].hip_m[1], s.desc.leg[0].hip_m[2]};
  leg_plane_target(s.robot, 0, V3{hip.x, hip.y + 0.02, hip.z - 0.8}, psi, xy);  // right leg: heading -y
  TEST_ASSERT_TRUE(std::fabs(psi) < 1e-14);
  TEST_ASSERT_TRUE(std::fabs(xy[0] - (-0.02 - s.desc.hip_offset_m)) < 1e-14 && std::fabs(xy[1] + 0.8) < 1e-14);
}

void test_stance_that_cannot_stand(void) {
  Standing &s = standing();
  static RobotStatics st;
  // at rowing angles 0 the right side's three feet lie on one line; two feet are too few
  legsim_options opt = legsim_default_options();
  legsim_sim *sim = nullptr;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage, sizeof storage, &s.desc.leg[0].leg, &opt, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  static double qp[3 * LEGSIM_MAX_BODIES], zero[3 * LEGSIM_MAX_BODIES], q0[kBodyConfig * kMaxRobotBodies],
      v0[kBodyDof * kMaxRobotBodies];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_get_q(sim, qp));
  const double *qs[6] = {qp, qp, qp, qp, qp, qp}, *vs[6] = {zero, zero, zero, zero, zero, zero};
  const double psi[6] = {0}, box_q[7] = {0, 0, 0, 1, 0, 0, 0}, box_v[6] = {0};
  robot_state(s.robot, box_q, box_v, qs, vs, psi, psi, q0, v0);
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_NO_EQUILIBRIUM, robot_statics(s.robot, q0, 0x07, nullptr, st));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_NO_EQUILIBRIUM, robot_statics(s.robot, s.q, 0x09, nullptr, st));
  // right front, right middle and left front: the centre of mass outside their triangle (a
  // foot would have to pull)
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_NO_EQUILIBRIUM, robot_statics(s.robot, s.q, 0x0B, nullptr, st));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, robot_statics(s.robot, s.q, 1u << 6, nullptr, st));
}

void test_api_refuses_and_leaves_out(void) {
  // legsim_hexapod_statics and _gait_setpoints: NULLs, short or misaligned storage, bad values;
  // a refused call leaves its output as it was
  Standing &s = standing();
  alignas(16) static unsigned char big[1 << 20];
  TEST_ASSERT_TRUE(legsim_hexapod_storage_size() + 16 <= sizeof big);
  legsim_hexapod_pose pose = {};
  pose.box_m[2] = 1.0;
  pose.box_quat[0] = 1.0;
  for (int l = 0; l < 6; ++l) pose.length_m[l][0] = 0.6614378277661477, pose.length_m[l][1] = 0.6244997998398398;
  legsim_hexapod_standing out;
  std::memset(&out, 0x5a, sizeof out);
  const legsim_hexapod_standing before = out;
  const size_t n = legsim_hexapod_storage_size();
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_NULL, legsim_hexapod_statics(nullptr, &pose, 0x15, nullptr, big, n, &out));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_NULL, legsim_hexapod_statics(&s.desc, &pose, 0x15, nullptr, big, n, nullptr));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_STORAGE, legsim_hexapod_statics(&s.desc, &pose, 0x15, nullptr, big, n - 1, &out));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_STORAGE, legsim_hexapod_statics(&s.desc, &pose, 0x15, nullptr, big + 8, n, &out));
  pose.box_quat[1] = 0.5;  // not a unit quaternion
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_statics(&s.desc, &pose, 0x15, nullptr, big, n, &out));
  pose.box_quat[1] = 0;
  pose.length_m[2][0] = NAN;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_statics(&s.desc, &pose, 0x15, nullptr, big, n, &out));
  pose.length_m[2][0] = 0.6614378277661477;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_statics(&s.desc, &pose, 1u << 6, nullptr, big, n, &out));
  TEST_ASSERT_EQUAL_INT(0, std::memcmp(&before, &out, sizeof out));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_hexapod_statics(&s.desc, &pose, 0x15, nullptr, big, n, &out));
  legsim_hexapod_gait g = {1.2, 0.6, 0.12, 0.05, 0.0, 1.0};
  legsim_hexapod_setpoint sp;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_NULL, legsim_hexapod_gait_setpoints(&s.desc, nullptr, 0, big, n, &sp));
  g.box_height_m = -1;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_gait_setpoints(&s.desc, &g, 0, big, n, &sp));
  g.box_height_m = 1.0;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_gait_setpoints(&s.desc, &g, NAN, big, n, &sp));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_hexapod_gait_setpoints(&s.desc, &g, 0.3, big, n, &sp));
  // the box's planned pose: 0.3 s at step_length / (duty period) along x, level, 1 m up
  TEST_ASSERT_TRUE(std::fabs(sp.box_m[0] - 0.3 * 0.12 / 0.72) < 1e-15 && sp.box_m[1] == 0 && sp.box_m[2] == 1.0);
  TEST_ASSERT_TRUE(sp.box_quat[0] == 1 && sp.box_quat[1] == 0 && sp.box_quat[2] == 0 && sp.box_quat[3] == 0);
  // the margin's refusals; an equilateral triangle's inradius about its centre
  const double tri[3][3] = {{1, 0, 0.5}, {-0.5, 0.8660254037844386, 0}, {-0.5, -0.8660254037844386, 0}};
  const double centre[3] = {0, 0, 1}, far[3] = {1e9, 0, 0};
  double margin = 0;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_NULL, legsim_hexapod_support_margin(tri, 3, centre, nullptr));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_support_margin(tri, 7, centre, &margin));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_support_margin(tri, 3, far, &margin));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_hexapod_support_margin(tri, 3, centre, &margin));
  TEST_ASSERT_TRUE(std::fabs(margin - 0.5) < 1e-15);
  // one leg's reach and the Section V sweep: refused calls write nothing
  double psi = 7, len[2] = {7, 7};
  const double foot[3] = {0.8, -0.6, -1.0}, beyond[3] = {5.0, 0, -1.0}, nan_foot[3] = {0.8, NAN, -1.0};
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_NULL, legsim_hexapod_leg_reach(&s.desc, 0, nullptr, big, n, &psi, len));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_STORAGE, legsim_hexapod_leg_reach(&s.desc, 0, foot, big, n - 1, &psi, len));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_leg_reach(&s.desc, -1, foot, big, n, &psi, len));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_leg_reach(&s.desc, 0, nan_foot, big, n, &psi, len));
  TEST_ASSERT_TRUE(legsim_hexapod_leg_reach(&s.desc, 0, beyond, big, n, &psi, len) != LEGSIM_OK);
  TEST_ASSERT_TRUE(psi == 7 && len[0] == 7 && len[1] == 7);
  legsim_hexapod_sweep sw = {0, 0x15, 1.0, {0.4, 0.6}, 3, {0, 0}, 1};
  legsim_hexapod_sweep_point pts[3];
  std::memset(pts, 0x5a, sizeof pts);
  unsigned char untouched[sizeof pts];
  std::memcpy(untouched, pts, sizeof pts);
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_NULL, legsim_hexapod_reaction_sweep(&s.desc, nullptr, 0, 3, big, n, pts));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_STORAGE, legsim_hexapod_reaction_sweep(&s.desc, &sw, 0, 3, big + 8, n, pts));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_reaction_sweep(&s.desc, &sw, 1, 3, big, n, pts));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_reaction_sweep(&s.desc, &sw, 0, 0, big, n, pts));
  sw.stance_mask = 0x2A;  // a stance without the moving leg
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_reaction_sweep(&s.desc, &sw, 0, 3, big, n, pts));
  sw.stance_mask = 0x15, sw.heading_rad[1] = NAN;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_reaction_sweep(&s.desc, &sw, 0, 3, big, n, pts));
  sw.heading_rad[1] = 0;
  TEST_ASSERT_EQUAL_INT(0, std::memcmp(untouched, pts, sizeof pts));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_hexapod_reaction_sweep(&s.desc, &sw, 0, 3, big, n, pts));
  for (int k = 0; k < 3; ++k) TEST_ASSERT_TRUE(pts[k].index == k && pts[k].status == LEGSIM_OK);
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
  expect_refused(variant_dir(leg, "file = \"leg.toml\"\nhip = [0.35, -0.25, -0.15]",
                             "file = \"leg.toml\"\nvariant = \"slot\"\nhip = [0.35, -0.25, -0.15]"),
                 "hexapod.toml", LEGSIM_ERR_MODEL, "is a slot");
  expect_refused(variant_dir(leg, "stroke = [-0.6, 0.6]", "stroke = [-0.6, 3.2]"), "hexapod.toml",
                 LEGSIM_ERR_MODEL, "'stroke' must be [min, max]");
  expect_refused(variant_dir(leg, "normal = [0.0, 0.0, 1.0]", "normal = [0.0, 0.0, 2.0]"), "hexapod.toml",
                 LEGSIM_ERR_MODEL, "'normal' must be a unit vector");
}

// The box's own contact points ([[box_contact]]): read, lifted (after the feet: contact 6 + k,
// on the box), reported by the C API's state as the feet are; refused past the capacity, off the
// box, not finite.
void test_box_contacts(void) {
  const std::string leg = read("models/leg.toml");
  const std::string belly = "[[box_contact]]\npoint = [0.3, -0.2, -0.15]\n[[box_contact]]\npoint = [0.3, 0.2, -0.15]\n"
                            "[[box_contact]]\npoint = [-0.3, 0.0, -0.15]\n\n[ground]";
  {
    const std::string dir = variant_dir(leg, "[ground]", belly), path = dir + "/hexapod.toml";
    auto h = std::make_unique<legsim_hexapod_desc>();
    char msg[256] = {0};
    const legsim_status st = legsim_hexapod_load_toml(path.c_str(), h.get(), msg, sizeof msg);
    for (const char *f : {"/hexapod.toml", "/leg.toml"}) std::remove((dir + f).c_str());
    rmdir(dir.c_str());
    TEST_ASSERT_EQUAL_INT_MESSAGE(LEGSIM_OK, st, msg);
    TEST_ASSERT_EQUAL_INT(3, h->n_box_contacts);
    TEST_ASSERT_EQUAL_DOUBLE(-0.3, h->box_contact_m[2][0]);
    TEST_ASSERT_EQUAL_DOUBLE(0.2, h->box_contact_m[1][1]);
    static SpatialRobot robot;
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_lift_hexapod(*h, robot));
    TEST_ASSERT_EQUAL_INT(3, robot.nbox_contacts);
    TEST_ASSERT_EQUAL_INT(9, robot_contacts(robot));
    // the C API: the standing robot, its box turned, the skids where the box puts them, free
    Standing &s = standing();
    alignas(16) static unsigned char store[1 << 21];
    TEST_ASSERT_TRUE(legsim_hexapod_sim_size() <= sizeof store);
    legsim_hexapod_pose pose = {};
    const double c = std::cos(0.15), sn = std::sin(0.15);
    pose.box_m[2] = 1.0, pose.box_quat[0] = c, pose.box_quat[3] = sn;  // 0.3 rad about z
    for (int l = 0; l < 6; ++l) pose.length_m[l][0] = 0.6614378277661477, pose.length_m[l][1] = 0.6244997998398398;
    (void)s;
    legsim_hexapod_sim *sim = nullptr;
    TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_sim_init(store, sizeof store, h.get(), &pose, 1u << 9, &sim));
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_hexapod_sim_init(store, sizeof store, h.get(), &pose, 0, &sim));
    legsim_hexapod_state st2;
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_hexapod_get_state(sim, &st2));
    TEST_ASSERT_EQUAL_INT(3, st2.n_box_contacts);
    const double ca = std::cos(0.3), sa = std::sin(0.3);
    for (int k = 0; k < 3; ++k) {
      const double *p = h->box_contact_m[k];
      TEST_ASSERT_DOUBLE_WITHIN(1e-14, ca * p[0] - sa * p[1], st2.box_contact_m[k][0]);
      TEST_ASSERT_DOUBLE_WITHIN(1e-14, sa * p[0] + ca * p[1], st2.box_contact_m[k][1]);
      TEST_ASSERT_DOUBLE_WITHIN(1e-14, 1.0 + p[2], st2.box_contact_m[k][2]);
      TEST_ASSERT_EQUAL_INT(LEGSIM_CONTACT_FREE, st2.box_contact_state[k]);
      TEST_ASSERT_EQUAL_DOUBLE(0.0, st2.box_contact_force_n[k][2]);
    }
    TEST_ASSERT_EQUAL_INT(LEGSIM_CONTACT_FREE, st2.box_contact_state[3]);
  }
  std::string five;
  for (int k = 0; k < 5; ++k) five += "[[box_contact]]\npoint = [0.0, 0.0, -0.15]\n";
  expect_refused(variant_dir(leg, "[ground]", five + "\n[ground]"), "hexapod.toml", LEGSIM_ERR_CAPACITY,
                 "5 [[box_contact]] (at most 4");
  expect_refused(variant_dir(leg, "[ground]", "[[box_contact]]\npoint = [0.0, 0.3, -0.15]\n\n[ground]"),
                 "hexapod.toml", LEGSIM_ERR_MODEL, "'point' must be on or inside the box");
  expect_refused(variant_dir(leg, "[ground]", "[[box_contact]]\npoint = [nan, 0.0, -0.15]\n\n[ground]"),
                 "hexapod.toml", LEGSIM_ERR_MODEL, "'point' is not finite");
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_loads_six_legs_of_the_leg_file);
  RUN_TEST(test_lifted_stand);
  RUN_TEST(test_standing_on_a_tripod);
  RUN_TEST(test_standing_on_six_feet_and_pushed);
  RUN_TEST(test_leg_targets_round_trip);
  RUN_TEST(test_stance_that_cannot_stand);
  RUN_TEST(test_api_refuses_and_leaves_out);
  RUN_TEST(test_refusals);
  RUN_TEST(test_box_contacts);
  return UNITY_END();
}
