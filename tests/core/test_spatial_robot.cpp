// Legs in space (firmware_core/src/spatial/robot.hpp): models/leg.toml (the compiled-in
// description) lifted onto its hip yoke, on a fixed box and six times on a free box, against
// the planar core (another formulation: planar absolute coordinates and its own row units),
// the spatial prototype (firmware_core/tools/prototypes/spatial_leg.py, docs/design/spatial.md)
// and invariants. One leg on the fixed box:
// - 39 rows on 42 velocity coordinates; the two loop-closing joints by their in-plane rows;
// - the planar core's stand pose and a planar velocity, lifted at any rowing angle and rate:
//   every row vanishes, J v = 0;
// - J has full row rank, its smallest singular value at the stand 0.254 (the prototype's);
// - the spatial equations of motion (M a + J^T lambda = Q, J a = gamma, gravity alone, the
//   yoke free) give the planar core's accelerations lifted, and no rowing acceleration (the
//   leg's forces lie in a plane through the hip axis).
// Six on a free box (three hips a side, the left ones turned by pi): 234 rows on 258 velocity
// coordinates (the prototype's counts); the stand lifted at any box pose and rowing angles
// meets every row; a rigid motion of the whole robot, and the legs' own motions on a moving
// box, are in J's null space; J has full row rank; in free fall (gravity alone, at rest) every
// body falls at g and every multiplier is zero.
#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "legsim/legsim.h"
#include "legsim/models.h"
#include "spatial/robot.hpp"
#include "spatial_kkt.hpp"
#include "unity.h"

void setUp(void) {}
void tearDown(void) {}

namespace {
using namespace legsim::spatial;
using Eigen::MatrixXd;
using Eigen::VectorXd;

alignas(16) unsigned char storage[1 << 20];

struct PlanarState {
  int nq;
  double q[3 * LEGSIM_MAX_BODIES], qd[3 * LEGSIM_MAX_BODIES], qdd[3 * LEGSIM_MAX_BODIES];
  double length[LEGSIM_MAX_ACTUATORS];
};

// The planar core's leg at its stand pose moving at actuator rates (0.1, -0.2) m/s under
// gravity and the actuator forces f (N), one RK4 step of 1 ms on: q, qd and the derivative at
// them, and the actuators' lengths.
PlanarState planar_leg(double f0 = 0, double f1 = 0) {
  legsim_options opt = legsim_default_options();
  opt.integrator = LEGSIM_INTEGRATOR_RK4;
  legsim_sim *sim = nullptr;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage, sizeof storage, &legsim_model_leg_revolute, &opt, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  const legsim_real rates[2] = {0.1, -0.2};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_velocity_analysis(sim, rates));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_force(sim, 0, f0));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_force(sim, 1, f1));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 1));
  PlanarState p;
  p.nq = 3 * legsim_model_leg_revolute.n_bodies;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_get_q(sim, p.q));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_get_qd(sim, p.qd));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_get_qdd(sim, p.qdd));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_actuator_lengths(sim, p.length, nullptr));
  return p;
}

const legsim_model_desc *const kLeg = &legsim_model_leg_revolute;
const HipDesc kStandHip = {{0, 0, 0}, 0};

// One leg on the fixed box, its hip at the origin.
SpatialRobot lifted() {
  SpatialRobot leg;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_lift(&kLeg, &kStandHip, 1, YokeDesc{}, nullptr, leg));
  return leg;
}
// The one leg's state.
void leg_state(const SpatialRobot &leg, const double *qp, const double *qdp, double psi, double psid, double *q,
               double *v) {
  robot_state(leg, nullptr, nullptr, &qp, &qdp, &psi, &psid, q, v);
}
void leg_rows(const SpatialRobot &leg, const double *q, const double *v, Row *rows) { robot_rows(leg, q, v, rows); }

using spatial_kkt::jacobian;
// [M J^T; J 0] [a; lambda] = [Q; gamma] at (q, v) with Q from robot_forces.
VectorXd accelerations(const SpatialRobot &robot, const double *q, const double *v, const double *force_n,
                       const double *rowing_nm) {
  static Row rows[kMaxRobotRows];
  static double Q[kBodyDof * kMaxRobotBodies];
  robot_rows(robot, q, v, rows);
  robot_forces(robot, q, v, force_n, rowing_nm, Q);
  const int nv = kBodyDof * robot.nb, m = robot.m;
  VectorXd rhs = VectorXd::Zero(nv + m);
  for (int i = 0; i < nv; ++i) rhs[i] = Q[i];
  for (int r = 0; r < m; ++r) rhs[nv + r] = rows[r].gamma;
  return spatial_kkt::matrix(robot, rows).fullPivLu().solve(rhs);
}

// The largest difference between the spatial accelerations x of the one leg on its yoke at
// angle psi and the planar accelerations qdd lifted (linear along the plane's axes, angular
// about its normal, in the body frame), and the largest lifted one.
void lifted_difference(const SpatialRobot &leg, const double *q, const double *qdd, double psi, const VectorXd &x,
                       double &worst, double &scale) {
  const double c = std::cos(psi), s = std::sin(psi);
  worst = 0, scale = 0;
  for (int b = 1; b < leg.nb; ++b) {
    const double *a = qdd + 3 * (b - 1);
    const double *qb = q + kBodyConfig * b;
    const Rot R = rotation({qb[3], qb[4], qb[5], qb[6]});
    const V3 ang = rotate_back(R, V3{a[2] * s, -a[2] * c, 0});
    const double expect[6] = {c * a[0], s * a[0], a[1], ang.x, ang.y, ang.z};
    for (int i = 0; i < 6; ++i) {
      worst = std::fmax(worst, std::fabs(x[kBodyDof * b + i] - expect[i]));
      scale = std::fmax(scale, std::fabs(expect[i]));
    }
  }
}
}  // namespace

void test_rows_and_tree(void) {
  const SpatialRobot leg = lifted();
  TEST_ASSERT_EQUAL_INT(7, leg.nb);
  TEST_ASSERT_EQUAL_INT(39, leg.m);
  // the yoke's hip, then leg.toml's joints: C_rod_thigh (5th) and D (8th) close the loops
  int cuts = 0;
  for (int k = 0; k < leg.nj; ++k) cuts += leg.joint[k].kind == LegJointKind::Cut;
  TEST_ASSERT_EQUAL_INT(2, cuts);
  TEST_ASSERT_TRUE(leg.joint[5].kind == LegJointKind::Cut && leg.joint[8].kind == LegJointKind::Cut);
}

void test_lifted_state_meets_every_row(void) {
  const SpatialRobot leg = lifted();
  const PlanarState p = planar_leg();
  legsim_real q[kBodyConfig * kMaxRobotBodies], v[kBodyDof * kMaxRobotBodies];
  Row rows[kMaxRobotRows];
  const double psis[4] = {0.0, 0.7, -2.4, 3.1};
  for (double psi : psis) {
    leg_state(leg, p.q, p.qd, psi, 1.3 * psi - 0.5, q, v);
    leg_rows(leg, q, v, rows);
    const MatrixXd J = jacobian(leg, rows);
    VectorXd vv(kBodyDof * leg.nb);
    for (int i = 0; i < kBodyDof * leg.nb; ++i) vv[i] = v[i];
    double phi = 0;
    for (int r = 0; r < leg.m; ++r) phi = std::fmax(phi, std::fabs(rows[r].phi));
    const double jv = (J * vv).cwiseAbs().maxCoeff();
    printf("psi %+.1f: max |Phi| %.2e, max |J v| %.2e\n", psi, phi, jv);
    TEST_ASSERT_TRUE(phi < 1e-12);
    TEST_ASSERT_TRUE(jv < 1e-12);
  }
}

void test_jacobian_full_rank_as_the_prototype(void) {
  const SpatialRobot leg = lifted();
  legsim_options opt = legsim_default_options();
  legsim_sim *sim = nullptr;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage, sizeof storage, &legsim_model_leg_revolute, &opt, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  double qp[3 * LEGSIM_MAX_BODIES], zero[3 * LEGSIM_MAX_BODIES] = {0};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_get_q(sim, qp));
  legsim_real q[kBodyConfig * kMaxRobotBodies], v[kBodyDof * kMaxRobotBodies];
  Row rows[kMaxRobotRows];
  leg_state(leg, qp, zero, 0.0, 0.0, q, v);
  leg_rows(leg, q, v, rows);
  const Eigen::JacobiSVD<MatrixXd> svd(jacobian(leg, rows));
  const double smin = svd.singularValues()[leg.m - 1];
  printf("the stand pose: smallest singular value of J %.4f\n", smin);
  TEST_ASSERT_TRUE(std::fabs(smin - 0.254) < 5e-4);
}

void test_dynamics_is_the_planar_leg_lifted(void) {
  const SpatialRobot leg = lifted();
  const PlanarState p = planar_leg();
  const int nv = kBodyDof * leg.nb, m = leg.m;
  legsim_real q[kBodyConfig * kMaxRobotBodies], v[kBodyDof * kMaxRobotBodies];
  Row rows[kMaxRobotRows];
  const double psi = 0.9;
  leg_state(leg, p.q, p.qd, psi, 0.0, q, v);
  leg_rows(leg, q, v, rows);
  // [M J^T; J 0] [a; lambda] = [Q; gamma]: Q the weights and the gyroscopic forces
  const MatrixXd K = spatial_kkt::matrix(leg, rows);
  VectorXd rhs = VectorXd::Zero(nv + m);
  for (int b = 0; b < leg.nb; ++b) {
    const double I[3] = {leg.inertia[b].x, leg.inertia[b].y, leg.inertia[b].z};
    const double *w = v + kBodyDof * b + 3;
    rhs[kBodyDof * b + 2] = leg.mass[b] * leg.gravity.z;
    // -omega x (I omega)
    const double Iw[3] = {I[0] * w[0], I[1] * w[1], I[2] * w[2]};
    rhs[kBodyDof * b + 3] = -(w[1] * Iw[2] - w[2] * Iw[1]);
    rhs[kBodyDof * b + 4] = -(w[2] * Iw[0] - w[0] * Iw[2]);
    rhs[kBodyDof * b + 5] = -(w[0] * Iw[1] - w[1] * Iw[0]);
  }
  for (int r = 0; r < m; ++r) rhs[nv + r] = rows[r].gamma;
  const VectorXd x = K.fullPivLu().solve(rhs);
  // the planar accelerations lifted: linear along the plane's axes, angular about its normal
  const double c = std::cos(psi), s = std::sin(psi);
  double worst = 0, scale = 0;
  for (int b = 1; b < leg.nb; ++b) {
    const double *a = p.qdd + 3 * (b - 1);
    const double lin[3] = {c * a[0], s * a[0], a[1]};
    // angular: phi'' about the plane's normal (world (s, -c, 0)), in the body frame
    const double *qb = q + kBodyConfig * b;
    const Rot R = rotation({qb[3], qb[4], qb[5], qb[6]});
    const V3 ang = rotate_back(R, V3{a[2] * s, -a[2] * c, 0});
    const double expect[6] = {lin[0], lin[1], lin[2], ang.x, ang.y, ang.z};
    for (int i = 0; i < 6; ++i) {
      worst = std::fmax(worst, std::fabs(x[kBodyDof * b + i] - expect[i]));
      scale = std::fmax(scale, std::fabs(expect[i]));
    }
  }
  const double rowing = x[5];  // the yoke's angular acceleration about its (vertical) z
  printf("spatial - planar accelerations: %.2e of %.2e; rowing acceleration %.2e\n", worst, scale, rowing);
  TEST_ASSERT_TRUE(scale > 1);
  TEST_ASSERT_TRUE(worst < 1e-9 * scale);
  TEST_ASSERT_TRUE(std::fabs(rowing) < 1e-9 * scale);
}

void test_angular_momentum_about_the_hip_axis(void) {
  // the yoke turning and the leg moving in its plane, on the fixed box: no moment about the hip
  // axis acts but the rowing torque (gravity is parallel to it, the hip's force acts on it, its
  // moments across it), so the angular momentum about it, summed body by body in Newton-Euler's
  // form, dH_z/dt = sum m (r x a)_z + (R (J w' + w x J w))_z, equals the rowing torque; this
  // holds only with the gyroscopic moments -w x J w in Q right
  const SpatialRobot leg = lifted();
  const PlanarState p = planar_leg(40.0, -10.0);
  static double q[kBodyConfig * kMaxRobotBodies], v[kBodyDof * kMaxRobotBodies];
  leg_state(leg, p.q, p.qd, 0.5, 1.7, q, v);
  for (const double tau : {0.0, 3.0}) {
    const double force[2] = {40.0, -10.0}, rowing[1] = {tau};
    const VectorXd x = accelerations(leg, q, v, force, rowing);
    double dH = 0, scale = 0;
    for (int b = 0; b < leg.nb; ++b) {
      const double *qb = q + kBodyConfig * b, *vb = v + kBodyDof * b;
      const Rot R = rotation({qb[3], qb[4], qb[5], qb[6]});
      const V3 r = {qb[0], qb[1], qb[2]}, a = {x[kBodyDof * b], x[kBodyDof * b + 1], x[kBodyDof * b + 2]};
      const V3 w = {vb[3], vb[4], vb[5]}, wd = {x[kBodyDof * b + 3], x[kBodyDof * b + 4], x[kBodyDof * b + 5]};
      const V3 &I = leg.inertia[b];
      const V3 Jw = {I.x * w.x, I.y * w.y, I.z * w.z}, Jwd = {I.x * wd.x, I.y * wd.y, I.z * wd.z};
      const double lin = leg.mass[b] * cross(r, a).z, ang = rotate(R, Jwd + cross(w, Jw)).z;
      dH += lin + ang;
      scale += std::fabs(lin) + std::fabs(ang);
    }
    printf("rowing torque %.1f N m: dH_z/dt %.12f N m (terms up to %.3f)\n", tau, dH, scale);
    TEST_ASSERT_TRUE(scale > 1);
    TEST_ASSERT_TRUE(std::fabs(dH - tau) < 1e-10 * scale);
  }
}

void test_joint_order_does_not_matter(void) {
  // the leg's frame joints last: A and B_thigh/B_lower then close loops against the yoke, by
  // their in-plane rows; still 39 rows of full rank, every row met at the lifted stand
  static legsim_model_desc d;
  d = legsim_model_leg_revolute;
  int k = 0;
  for (int pass = 0; pass < 2; ++pass)
    for (int j = 0; j < legsim_model_leg_revolute.n_joints; ++j) {
      const bool frame = legsim_model_leg_revolute.joint[j].kind == LEGSIM_JOINT_REVOLUTE_TO_FRAME;
      if (frame == (pass == 1)) d.joint[k++] = legsim_model_leg_revolute.joint[j];
    }
  for (int a = 0; a < d.n_actuators; ++a)  // the actuators' joints, renumbered
    for (int j = 0; j < d.n_joints; ++j)
      if (std::strcmp(d.joint[j].name,
                      legsim_model_leg_revolute.joint[legsim_model_leg_revolute.actuator[a].joint].name) == 0)
        d.actuator[a].joint = j;
  const legsim_model_desc *dp = &d;
  static SpatialRobot leg;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_lift(&dp, &kStandHip, 1, YokeDesc{}, nullptr, leg));
  TEST_ASSERT_EQUAL_INT(39, leg.m);
  const PlanarState p = planar_leg();
  static double q[kBodyConfig * kMaxRobotBodies], v[kBodyDof * kMaxRobotBodies];
  static Row rows[kMaxRobotRows];
  leg_state(leg, p.q, p.qd, 0.4, 0.2, q, v);
  robot_rows(leg, q, v, rows);
  const Eigen::JacobiSVD<MatrixXd> svd(jacobian(leg, rows));
  double phi = 0;
  for (int r = 0; r < leg.m; ++r) phi = std::fmax(phi, std::fabs(rows[r].phi));
  printf("frame joints last: %d rows, max |Phi| %.2e, smallest singular value %.4f\n", leg.m, phi,
         svd.singularValues()[leg.m - 1]);
  TEST_ASSERT_TRUE(phi < 1e-12);
  TEST_ASSERT_TRUE(svd.singularValues()[leg.m - 1] > 0.1);
}

void test_refuses_what_it_cannot_lift(void) {
  static SpatialRobot leg;
  static legsim_model_desc d;
  const legsim_model_desc *dp = &d;
  d = legsim_model_leg_revolute;
  d.gravity_mps2[0] = 1.0;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_MODEL, robot_lift(&dp, &kStandHip, 1, YokeDesc{}, nullptr, leg));
  d = legsim_model_leg_revolute;
  d.joint[0].kind = LEGSIM_JOINT_SLOT;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_MODEL, robot_lift(&dp, &kStandHip, 1, YokeDesc{}, nullptr, leg));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_CAPACITY, robot_lift(&dp, &kStandHip, kMaxLegs + 1, YokeDesc{}, nullptr, leg));
}

namespace {
// Six legs on a free box: hips at x = -0.3, 0, 0.3 m, y = -0.25 (right, the leg out along -y)
// and +0.25 m (left, turned by pi), on the box's underside (z = -0.1 m). The box numbers are the
// test's own (models/hexapod.toml's are tested in tests/model/test_hexapod_file.cpp).
SpatialRobot &hexapod() {
  static SpatialRobot robot;
  static bool built = false;
  if (!built) {
    const legsim_model_desc *legs[6];
    HipDesc hips[6];
    for (int k = 0; k < 6; ++k) {
      legs[k] = kLeg;
      const double side = k < 3 ? -1 : 1;
      hips[k] = {{-0.3 + 0.3 * (k % 3), 0.25 * side, -0.1}, side * 1.5707963267948966};
    }
    const BoxDesc box = {30.0, {0.5, 1.2, 1.5}};
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_lift(legs, hips, 6, YokeDesc{}, &box, robot));
    built = true;
  }
  return robot;
}
// The box at a pose and velocity, the legs at the planar state p with rowing angles and rates.
void hexapod_state(const SpatialRobot &robot, const PlanarState &p, bool legs_move, const double *box_q,
                   const double *box_v, double *q, double *v) {
  const double *qp[6], *qdp[6];
  static double zero[3 * LEGSIM_MAX_BODIES];
  double psi[6], psid[6];
  for (int k = 0; k < 6; ++k) {
    qp[k] = p.q;
    qdp[k] = legs_move ? p.qd : zero;
    psi[k] = 0.4 * k - 1.0;
    psid[k] = legs_move ? 0.3 * k - 0.8 : 0.0;
  }
  robot_state(robot, box_q, box_v, qp, qdp, psi, psid, q, v);
}
}  // namespace

void test_hexapod_counts_rows_and_motions(void) {
  const SpatialRobot &robot = hexapod();
  TEST_ASSERT_EQUAL_INT(43, robot.nb);
  TEST_ASSERT_EQUAL_INT(234, robot.m);
  const PlanarState p = planar_leg();
  static double q[kBodyConfig * kMaxRobotBodies], v[kBodyDof * kMaxRobotBodies];
  static Row rows[kMaxRobotRows];
  const Quat tilt = quat_exp({0.3, -0.2, 1.1});
  const double box_q[7] = {0.4, -1.2, 0.9, tilt.w, tilt.x, tilt.y, tilt.z};
  const double box_v[6] = {0.5, -0.3, 0.2, 0.7, -1.1, 0.4};
  for (int legs_move = 0; legs_move < 2; ++legs_move) {
    hexapod_state(robot, p, legs_move, box_q, box_v, q, v);
    robot_rows(robot, q, v, rows);
    const MatrixXd J = jacobian(robot, rows);
    VectorXd vv(kBodyDof * robot.nb);
    for (int i = 0; i < kBodyDof * robot.nb; ++i) vv[i] = v[i];
    double phi = 0;
    for (int r = 0; r < robot.m; ++r) phi = std::fmax(phi, std::fabs(rows[r].phi));
    const double jv = (J * vv).cwiseAbs().maxCoeff();
    printf("hexapod, %s: max |Phi| %.2e, max |J v| %.2e\n", legs_move ? "legs moving" : "rigid", phi, jv);
    TEST_ASSERT_TRUE(phi < 1e-12);
    TEST_ASSERT_TRUE(jv < 1e-12);
  }
  const Eigen::JacobiSVD<MatrixXd> svd(jacobian(robot, rows));
  const double smin = svd.singularValues()[robot.m - 1];
  printf("hexapod: smallest singular value of J %.4f\n", smin);
  TEST_ASSERT_TRUE(smin > 0.1);
}

void test_hexapod_falls_freely(void) {
  const SpatialRobot &robot = hexapod();
  PlanarState p = planar_leg();
  const int nv = kBodyDof * robot.nb, m = robot.m;
  static double q[kBodyConfig * kMaxRobotBodies], v[kBodyDof * kMaxRobotBodies];
  static Row rows[kMaxRobotRows];
  const Quat tilt = quat_exp({-0.2, 0.5, 2.0});
  const double box_q[7] = {0.1, 0.2, 0.8, tilt.w, tilt.x, tilt.y, tilt.z}, box_v[6] = {0, 0, 0, 0, 0, 0};
  hexapod_state(robot, p, false, box_q, box_v, q, v);
  robot_rows(robot, q, v, rows);
  VectorXd rhs = VectorXd::Zero(nv + m);
  for (int b = 0; b < robot.nb; ++b) rhs[kBodyDof * b + 2] = robot.mass[b] * robot.gravity.z;
  for (int r = 0; r < m; ++r) rhs[nv + r] = rows[r].gamma;
  const VectorXd x = spatial_kkt::matrix(robot, rows).fullPivLu().solve(rhs);
  double worst = 0;
  for (int b = 0; b < robot.nb; ++b)
    for (int i = 0; i < 6; ++i) worst = std::fmax(worst, std::fabs(x[kBodyDof * b + i] - (i == 2 ? robot.gravity.z : 0.0)));
  const double lam = x.tail(m).cwiseAbs().maxCoeff();
  printf("free fall: accelerations off g by %.2e, largest multiplier %.2e\n", worst, lam);
  TEST_ASSERT_TRUE(worst < 1e-10);
  TEST_ASSERT_TRUE(lam < 1e-9);
}

void test_actuators_push_as_the_planar_leg(void) {
  const SpatialRobot leg = lifted();
  TEST_ASSERT_EQUAL_INT(2, leg.na);
  const PlanarState p = planar_leg(50.0, -30.0);
  static double q[kBodyConfig * kMaxRobotBodies], v[kBodyDof * kMaxRobotBodies];
  const double psi = -1.3;
  leg_state(leg, p.q, p.qd, psi, 0.0, q, v);
  for (int a = 0; a < 2; ++a) TEST_ASSERT_TRUE(std::fabs(robot_actuator_length(leg, a, q) - p.length[a]) < 1e-14);
  const double force[2] = {50.0, -30.0}, rowing[1] = {0.0};
  const VectorXd x = accelerations(leg, q, v, force, rowing);
  double worst, scale;
  lifted_difference(leg, q, p.qdd, psi, x, worst, scale);
  printf("with the actuators at (50, -30) N: spatial - planar accelerations %.2e of %.2e, rowing %.2e\n", worst,
         scale, x[5]);
  TEST_ASSERT_TRUE(worst < 1e-9 * scale);
  TEST_ASSERT_TRUE(std::fabs(x[5]) < 1e-9 * scale);
}

void test_rowing_torque_turns_the_leg_rigidly(void) {
  // the rowing torque turns the yoke and the leg about the hip axis as one body (tau / I_axis,
  // I_axis summed independently from the bodies' poses) when the yoke is not turning yet, and
  // the leg's own accelerations stay the planar ones (the turn's acceleration lies across the
  // leg's plane, its inertia's principal axes keep the two apart)
  const SpatialRobot leg = lifted();
  const PlanarState p = planar_leg();
  const double *qdd = p.qdd;
  static double q[kBodyConfig * kMaxRobotBodies], v[kBodyDof * kMaxRobotBodies];
  const double psi = 0.6, tau = 2.5;
  leg_state(leg, p.q, p.qd, psi, 0.0, q, v);
  double I_axis = 0;
  for (int b = 0; b < leg.nb; ++b) {
    const double *qb = q + kBodyConfig * b;
    const Rot R = rotation({qb[3], qb[4], qb[5], qb[6]});
    const V3 zb = rotate_back(R, V3{0, 0, 1});  // the axis in the body's frame
    I_axis += leg.inertia[b].x * zb.x * zb.x + leg.inertia[b].y * zb.y * zb.y + leg.inertia[b].z * zb.z * zb.z +
              leg.mass[b] * (qb[0] * qb[0] + qb[1] * qb[1]);
  }
  const double force[2] = {0, 0}, rowing[1] = {tau};
  const VectorXd x = accelerations(leg, q, v, force, rowing);
  // the yoke's angular acceleration about z (its frame's z is the axis)
  printf("rowing: psi'' %.12f, tau / I_axis %.12f (I_axis %.6f kg m^2)\n", x[5], tau / I_axis, I_axis);
  TEST_ASSERT_TRUE(std::fabs(x[5] - tau / I_axis) < 1e-12 * std::fabs(tau / I_axis));
  // each body's acceleration: the planar one lifted plus the turn's (psi'' ez x r, and psi''
  // about z in its frame)
  const double c = std::cos(psi), s = std::sin(psi), pdd = x[5];
  double worst = 0;
  for (int b = 1; b < leg.nb; ++b) {
    const double *a = qdd + 3 * (b - 1), *qb = q + kBodyConfig * b;
    const Rot R = rotation({qb[3], qb[4], qb[5], qb[6]});
    const V3 ang = rotate_back(R, V3{a[2] * s, -a[2] * c, pdd});
    const double expect[6] = {c * a[0] - pdd * qb[1], s * a[0] + pdd * qb[0], a[1], ang.x, ang.y, ang.z};
    for (int i = 0; i < 6; ++i) worst = std::fmax(worst, std::fabs(x[kBodyDof * b + i] - expect[i]));
  }
  printf("rowing: the bodies' accelerations off the planar ones plus the turn by %.2e\n", worst);
  TEST_ASSERT_TRUE(worst < 1e-10);
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_rows_and_tree);
  RUN_TEST(test_lifted_state_meets_every_row);
  RUN_TEST(test_jacobian_full_rank_as_the_prototype);
  RUN_TEST(test_dynamics_is_the_planar_leg_lifted);
  RUN_TEST(test_angular_momentum_about_the_hip_axis);
  RUN_TEST(test_joint_order_does_not_matter);
  RUN_TEST(test_refuses_what_it_cannot_lift);
  RUN_TEST(test_actuators_push_as_the_planar_leg);
  RUN_TEST(test_rowing_torque_turns_the_leg_rigidly);
  RUN_TEST(test_hexapod_counts_rows_and_motions);
  RUN_TEST(test_hexapod_falls_freely);
  return UNITY_END();
}
