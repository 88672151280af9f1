// The leg in space (firmware_core/src/spatial/leg.hpp): models/leg.toml (the compiled-in
// description) lifted onto its hip yoke, against the planar core (another formulation: planar
// absolute coordinates and its own row units) and the spatial prototype
// (firmware_core/tools/prototypes/spatial_leg.py, docs/design/spatial.md):
// - 39 rows on 42 velocity coordinates; the two loop-closing joints by their in-plane rows;
// - the planar core's stand pose and a planar velocity, lifted at any rowing angle and rate:
//   every row vanishes, J v = 0;
// - J has full row rank, its smallest singular value at the stand 0.254 (the prototype's);
// - the spatial equations of motion (M a + J^T lambda = Q, J a = gamma, gravity alone, the
//   yoke free) give the planar core's accelerations lifted, and no rowing acceleration (the
//   leg's forces lie in a plane through the hip axis).
#include <Eigen/Dense>
#include <cmath>
#include <cstdio>

#include "legsim/legsim.h"
#include "legsim/models.h"
#include "spatial/leg.hpp"
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
};

// The planar core's leg at its stand pose moving at actuator rates (0.1, -0.2) m/s under
// gravity and zero actuator forces, one RK4 step of 1 ms on: q, qd and the derivative at them.
PlanarState planar_leg() {
  legsim_options opt = legsim_default_options();
  opt.integrator = LEGSIM_INTEGRATOR_RK4;
  legsim_sim *sim = nullptr;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage, sizeof storage, &legsim_model_leg_revolute, &opt, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  const legsim_real rates[2] = {0.1, -0.2};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_velocity_analysis(sim, rates));
  for (int a = 0; a < 2; ++a) TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_force(sim, a, 0.0));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 1));
  PlanarState p;
  p.nq = 3 * legsim_model_leg_revolute.n_bodies;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_get_q(sim, p.q));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_get_qd(sim, p.qd));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_get_qdd(sim, p.qdd));
  return p;
}

SpatialLeg lifted() {
  SpatialLeg leg;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, leg_lift(legsim_model_leg_revolute, YokeDesc{}, leg));
  return leg;
}

// J (m x 6 nb) from the rows.
MatrixXd jacobian(const SpatialLeg &leg, const Row *rows) {
  MatrixXd J = MatrixXd::Zero(leg.m, kBodyDof * leg.nb);
  for (int k = 0; k < leg.nj; ++k) {
    const LegJoint &j = leg.joint[k];
    for (int r = j.row; r < j.row + j.nrows; ++r)
      for (int i = 0; i < kBodyDof; ++i) {
        J(r, kBodyDof * j.a + i) += rows[r].ja[i];
        if (j.b >= 0) J(r, kBodyDof * j.b + i) += rows[r].jb[i];
      }
  }
  return J;
}
}  // namespace

void test_rows_and_tree(void) {
  const SpatialLeg leg = lifted();
  TEST_ASSERT_EQUAL_INT(7, leg.nb);
  TEST_ASSERT_EQUAL_INT(39, leg.m);
  // the yoke's hip, then leg.toml's joints: C_rod_thigh (5th) and D (8th) close the loops
  int cuts = 0;
  for (int k = 0; k < leg.nj; ++k) cuts += leg.joint[k].kind == LegJointKind::Cut;
  TEST_ASSERT_EQUAL_INT(2, cuts);
  TEST_ASSERT_TRUE(leg.joint[5].kind == LegJointKind::Cut && leg.joint[8].kind == LegJointKind::Cut);
}

void test_lifted_state_meets_every_row(void) {
  const SpatialLeg leg = lifted();
  const PlanarState p = planar_leg();
  legsim_real q[kBodyConfig * kMaxLegBodies], v[kBodyDof * kMaxLegBodies];
  Row rows[kMaxLegRows];
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
  const SpatialLeg leg = lifted();
  legsim_options opt = legsim_default_options();
  legsim_sim *sim = nullptr;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage, sizeof storage, &legsim_model_leg_revolute, &opt, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  double qp[3 * LEGSIM_MAX_BODIES], zero[3 * LEGSIM_MAX_BODIES] = {0};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_get_q(sim, qp));
  legsim_real q[kBodyConfig * kMaxLegBodies], v[kBodyDof * kMaxLegBodies];
  Row rows[kMaxLegRows];
  leg_state(leg, qp, zero, 0.0, 0.0, q, v);
  leg_rows(leg, q, v, rows);
  const Eigen::JacobiSVD<MatrixXd> svd(jacobian(leg, rows));
  const double smin = svd.singularValues()[leg.m - 1];
  printf("the stand pose: smallest singular value of J %.4f\n", smin);
  TEST_ASSERT_TRUE(std::fabs(smin - 0.254) < 5e-4);
}

void test_dynamics_is_the_planar_leg_lifted(void) {
  const SpatialLeg leg = lifted();
  const PlanarState p = planar_leg();
  const int nv = kBodyDof * leg.nb, m = leg.m;
  legsim_real q[kBodyConfig * kMaxLegBodies], v[kBodyDof * kMaxLegBodies];
  Row rows[kMaxLegRows];
  const double psi = 0.9;
  leg_state(leg, p.q, p.qd, psi, 0.0, q, v);
  leg_rows(leg, q, v, rows);
  // [M J^T; J 0] [a; lambda] = [Q; gamma]: Q the weights and the gyroscopic forces
  MatrixXd K = MatrixXd::Zero(nv + m, nv + m);
  VectorXd rhs = VectorXd::Zero(nv + m);
  const MatrixXd J = jacobian(leg, rows);
  for (int b = 0; b < leg.nb; ++b) {
    const double I[3] = {leg.inertia[b].x, leg.inertia[b].y, leg.inertia[b].z};
    const double *w = v + kBodyDof * b + 3;
    for (int i = 0; i < 3; ++i) K(kBodyDof * b + i, kBodyDof * b + i) = leg.mass[b];
    for (int i = 0; i < 3; ++i) K(kBodyDof * b + 3 + i, kBodyDof * b + 3 + i) = I[i];
    rhs[kBodyDof * b + 2] = leg.mass[b] * leg.gravity.z;
    // -omega x (I omega)
    const double Iw[3] = {I[0] * w[0], I[1] * w[1], I[2] * w[2]};
    rhs[kBodyDof * b + 3] = -(w[1] * Iw[2] - w[2] * Iw[1]);
    rhs[kBodyDof * b + 4] = -(w[2] * Iw[0] - w[0] * Iw[2]);
    rhs[kBodyDof * b + 5] = -(w[0] * Iw[1] - w[1] * Iw[0]);
  }
  K.topRightCorner(nv, m) = J.transpose();
  K.bottomLeftCorner(m, nv) = J;
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

void test_refuses_what_it_cannot_lift(void) {
  SpatialLeg leg;
  legsim_model_desc d = legsim_model_leg_revolute;
  d.gravity_mps2[0] = 1.0;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_MODEL, leg_lift(d, YokeDesc{}, leg));
  d = legsim_model_leg_revolute;
  d.joint[0].kind = LEGSIM_JOINT_SLOT;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_MODEL, leg_lift(d, YokeDesc{}, leg));
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_rows_and_tree);
  RUN_TEST(test_lifted_state_meets_every_row);
  RUN_TEST(test_jacobian_full_rank_as_the_prototype);
  RUN_TEST(test_dynamics_is_the_planar_leg_lifted);
  RUN_TEST(test_refuses_what_it_cannot_lift);
  return UNITY_END();
}
