// The spatial legs' constrained-dynamics factor (firmware_core/src/spatial/dynamics.cpp:
// robot_factor, robot_solve) against a dense solve of [M J^T; J 0] [x; mu] = [f; g] (Eigen's
// full-pivot LU) for right-hand sides of their own, on the paths the hexapod's tests do not
// take: one leg of models/leg.toml on the fixed box (no hip rows on a box) with its foot free,
// sliding and stuck, the same leg with its joints in another order, and six legs on a free box
// with stuck, sliding and free feet, and on a tripod (the legs factored in pairs, a free foot's
// leg in its stuck layout). Each leg's layout (robot_lift's) holds each of its rows
// once, its foot's held ones and, on a free box, its hip's last.

#include <cmath>
#include <cstdio>
#include <cstring>

#include "legsim/legsim.h"
#include "legsim/models.h"
#include "spatial/dynamics.hpp"
#include "spatial_kkt.hpp"
#include "unity.h"

void setUp(void) {}
void tearDown(void) {}

namespace {
using namespace legsim::spatial;
using Eigen::VectorXd;

alignas(16) unsigned char storage[1 << 20];

// The planar leg's assembled stand pose (x, y, phi per bar).
const double *stand_pose() {
  static double q[3 * LEGSIM_MAX_BODIES];
  legsim_options opt = legsim_default_options();
  legsim_sim *sim = nullptr;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage, sizeof storage, &legsim_model_leg_revolute, &opt, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_get_q(sim, q));
  return q;
}

// The foot's hold: mode per leg 0 free, 1 sliding, 3 stuck; anchors at the feet; a tilted ground.
FeetHold hold_of(const SpatialRobot &R, const double *q, const int *mode) {
  FeetHold h;
  h.stuck = h.sliding = 0;
  for (int l = 0; l < R.nlegs; ++l) {
    if (mode[l] == 3) h.stuck |= 1u << l;
    if (mode[l] == 1) h.sliding |= 1u << l;
    h.anchor[l] = robot_foot_position(R, l, q);
  }
  const double c = std::cos(0.2), s = std::sin(0.2);
  h.normal = {s, 0, c}, h.t1 = {c, 0, -s}, h.t2 = {0, 1, 0};
  return h;
}

// robot_factor and robot_solve at q for f, g of their own against the dense KKT; the largest
// difference over the largest value, of x and of mu.
void check_against_dense(const SpatialRobot &R, const double *q, const int *mode, const char *what) {
  static double v[kMaxRobotDof], f[kMaxRobotDof], g[kMaxSystemRows], x[kMaxRobotDof], mu[kMaxSystemRows];
  static Row rows[kMaxSystemRows];
  static RobotFactor F;
  const FeetHold hold = hold_of(R, q, mode);
  system_rows(R, hold, q, v, rows);
  int idx[kMaxSystemRows], m = 0;
  for (int r = 0; r < R.m; ++r) idx[m++] = r;
  for (int l = 0; l < R.nlegs; ++l)
    for (int k = 0; k < foot_rows(hold, l); ++k) idx[m++] = foot_row(R, l) + k;
  // the rows' phi alone (a projection's residual): the same values
  static double phi[kMaxSystemRows];
  system_phi(R, hold, q, phi);
  for (int i = 0; i < m; ++i) TEST_ASSERT_TRUE(phi[idx[i]] == rows[idx[i]].phi);
  const int nv = kBodyDof * R.nb;
  for (int k = 0; k < nv; ++k) f[k] = 10 * std::sin(0.7 * k + 0.3);
  for (int i = 0; i < m; ++i) g[idx[i]] = std::cos(1.3 * i);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_factor(R, hold, rows, F));
  robot_solve(R, F, f, g, x, mu);
  VectorXd rhs(nv + m);
  for (int k = 0; k < nv; ++k) rhs[k] = f[k];
  for (int i = 0; i < m; ++i) rhs[nv + i] = g[idx[i]];
  const VectorXd y = spatial_kkt::matrix(R, rows, idx, m).fullPivLu().solve(rhs);
  double dx = 0, sx = 0, dl = 0, sl = 0;
  for (int k = 0; k < nv; ++k) dx = std::fmax(dx, std::fabs(x[k] - y[k])), sx = std::fmax(sx, std::fabs(y[k]));
  for (int i = 0; i < m; ++i)
    dl = std::fmax(dl, std::fabs(mu[idx[i]] - y[nv + i])), sl = std::fmax(sl, std::fabs(y[nv + i]));
  printf("%s: %d rows on %d; x off the dense solve by %.2e of %.2e, mu by %.2e of %.2e\n", what, m, nv, dx, sx, dl,
         sl);
  TEST_ASSERT_TRUE(sx > 0.1 && sl > 0.1);
  TEST_ASSERT_TRUE(dx < 1e-10 * sx);
  TEST_ASSERT_TRUE(dl < 1e-10 * sl);
}

// Every layout of every leg: its rows and its held foot's once each, the hip's last on a free box.
void check_layouts(const SpatialRobot &R) {
  for (int l = 0; l < R.nlegs; ++l) {
    const RobotLeg &L = R.leg[l];
    for (int k = 0; k < 3; ++k) {
      const LegLayout &Y = L.layout[k];
      const int nf = k == 2 ? 3 : k;
      TEST_ASSERT_EQUAL_INT(L.nrows + nf, Y.n);
      TEST_ASSERT_EQUAL_INT(R.free_box ? 5 : 0, Y.nh);
      int seen[kMaxSystemRows] = {};
      for (int i = 0; i < Y.n; ++i) {
        const int r = Y.row[i];
        const bool own = r >= L.row0 && r < L.row0 + L.nrows, foot = r >= foot_row(R, l) && r < foot_row(R, l) + nf;
        TEST_ASSERT_TRUE(own || foot);
        TEST_ASSERT_EQUAL_INT(0, seen[r]++);
        if (i >= Y.n - Y.nh) TEST_ASSERT_TRUE(r < L.row0 + 5);  // the hip's: the leg's first joint
      }
    }
  }
}

SpatialRobot &one_leg(const legsim_model_desc *d) {
  static SpatialRobot leg;
  const HipDesc hip = {{0, 0, 0}, 0};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_lift(&d, &hip, 1, YokeDesc{}, nullptr, leg));
  return leg;
}
void one_leg_state(const SpatialRobot &leg, double *q) {
  static double v[kMaxRobotDof], zero[3 * LEGSIM_MAX_BODIES];
  const double *qp = stand_pose(), *qdp = zero, psi = 0.3, psid = 0;
  robot_state(leg, nullptr, nullptr, &qp, &qdp, &psi, &psid, q, v);
}
}  // namespace

void test_one_leg_on_the_fixed_box(void) {
  const SpatialRobot &leg = one_leg(&legsim_model_leg_revolute);
  check_layouts(leg);
  static double q[kBodyConfig * kMaxRobotBodies];
  one_leg_state(leg, q);
  const char *name[4] = {"fixed box, foot free", "fixed box, foot sliding", "", "fixed box, foot stuck"};
  for (int mode : {0, 1, 3}) check_against_dense(leg, q, &mode, name[mode]);
}

void test_joint_order_of_the_file_does_not_matter(void) {
  // the leg's frame joints last (they then close loops against the yoke by their in-plane rows)
  static legsim_model_desc d;
  d = legsim_model_leg_revolute;
  int k = 0;
  for (int pass = 0; pass < 2; ++pass)
    for (int j = 0; j < legsim_model_leg_revolute.n_joints; ++j) {
      const bool frame = legsim_model_leg_revolute.joint[j].kind == LEGSIM_JOINT_REVOLUTE_TO_FRAME;
      if (frame == (pass == 1)) d.joint[k++] = legsim_model_leg_revolute.joint[j];
    }
  for (int a = 0; a < d.n_actuators; ++a)
    for (int j = 0; j < d.n_joints; ++j)
      if (std::strcmp(d.joint[j].name,
                      legsim_model_leg_revolute.joint[legsim_model_leg_revolute.actuator[a].joint].name) == 0)
        d.actuator[a].joint = j;
  const SpatialRobot &leg = one_leg(&d);
  check_layouts(leg);
  static double q[kBodyConfig * kMaxRobotBodies];
  one_leg_state(leg, q);
  const int stuck = 3;
  check_against_dense(leg, q, &stuck, "frame joints last, foot stuck");
}

void test_six_legs_on_a_free_box(void) {
  static SpatialRobot robot;
  const legsim_model_desc *legs[6];
  HipDesc hips[6];
  for (int k = 0; k < 6; ++k) {
    legs[k] = &legsim_model_leg_revolute;
    const double side = k < 3 ? -1 : 1;
    hips[k] = {{-0.3 + 0.3 * (k % 3), 0.25 * side, -0.1}, side * 1.5707963267948966};
  }
  const BoxDesc box = {30.0, {0.5, 1.2, 1.5}};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_lift(legs, hips, 6, YokeDesc{}, &box, robot));
  check_layouts(robot);
  static double q[kBodyConfig * kMaxRobotBodies], v[kMaxRobotDof], zero[3 * LEGSIM_MAX_BODIES];
  const double *qp[6], *qdp[6], box_q[7] = {0.1, -0.05, 0.6, std::cos(0.1), 0.0, std::sin(0.1), 0.0},
                          box_v[6] = {};
  double psi[6], psid[6] = {};
  for (int k = 0; k < 6; ++k) qp[k] = stand_pose(), qdp[k] = zero, psi[k] = 0.4 * k - 1.0;
  robot_state(robot, box_q, box_v, qp, qdp, psi, psid, q, v);
  const int mixed[6] = {3, 0, 1, 3, 0, 3};
  check_against_dense(robot, q, mixed, "free box, feet stuck, free and sliding");
  // legs 4 and 5 left over: the free foot's leg factored in its stuck layout beside the stuck one
  const int tripod[6] = {3, 0, 3, 0, 3, 0};
  check_against_dense(robot, q, tripod, "free box, a tripod");
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_one_leg_on_the_fixed_box);
  RUN_TEST(test_joint_order_of_the_file_does_not_matter);
  RUN_TEST(test_six_legs_on_a_free_box);
  return UNITY_END();
}
