#include "spatial/inverse.hpp"

#include <algorithm>

#include "spatial/gait.hpp"
#include "system/dense_solve.hpp"

namespace legsim::spatial {

namespace {
constexpr int kLegUnknownsMax = kBodyDof * (1 + kMaxLegBars);

// Leg l's rows [r0, r1): the joints whose first body is one of its bodies (its hip's too).
void leg_rows(const SpatialRobot &robot, int l, int &r0, int &r1) {
  const int b0 = robot.leg[l].yoke, nbl = 1 + robot.leg[l].nbars;
  r0 = r1 = -1;
  for (int k = 0; k < robot.nj; ++k) {
    const LegJoint &j = robot.joint[k];
    if (j.a < b0 || j.a >= b0 + nbl) continue;
    if (r0 < 0) r0 = j.row;
    r1 = j.row + j.nrows;
  }
}

// Leg l's square system at q with rows (robot_rows' at q and some v) and its foot's: K (neq x neq,
// its joints' rows then the foot's three), and the right-hand side's part from the rows (rhs:
// their gamma (with_gamma) less their coefficients on the box times box_x, the foot's row gamma
// plus foot_x).
void leg_system(const SpatialRobot &robot, int l, const BodyState *st, const Row *rows, int r0, int r1,
                const real *box_x, const V3 &foot_x, bool with_gamma, real *K, real *rhs) {
  const RobotLeg &L = robot.leg[l];
  const int nbl = 1 + L.nbars, neq = kBodyDof * nbl, b0 = L.yoke, nrows = r1 - r0;
  std::fill(K, K + neq * neq, real(0));
  auto put = [&](int row, int body, const real *coef) {
    if (body == 0 && robot.free_box) {
      for (int i = 0; i < kBodyDof; ++i) rhs[row] -= coef[i] * box_x[i];
      return;
    }
    if (body < b0 || body >= b0 + nbl) return;  // the world
    for (int i = 0; i < kBodyDof; ++i) K[row * neq + kBodyDof * (body - b0) + i] += coef[i];
  };
  for (int r = r0; r < r1; ++r) {
    rhs[r - r0] = with_gamma ? rows[r].gamma : real(0);
    put(r - r0, robot.row_body[r][0], rows[r].ja);
    put(r - r0, robot.row_body[r][1], rows[r].jb);
  }
  const BodyState world = ground_state();
  const real fx[3] = {foot_x.x, foot_x.y, foot_x.z};
  for (int k = 0; k < 3; ++k) {
    const Row f = row_along(st[L.foot_body], L.foot_point, world, {0, 0, 0}, kWorldAxes[k]);
    rhs[nrows + k] = (with_gamma ? f.gamma : real(0)) + fx[k];
    put(nrows + k, L.foot_body, f.ja);
  }
}

bool solve(int n, real *K, real *x) {
  real scale = 0;
  for (int i = 0; i < n * n; ++i) scale = std::max(scale, std::abs(K[i]));
  return dense_solve(n, K, x, real(1e-10) * scale);
}
}  // namespace

legsim_status robot_prescribed_motion(const SpatialRobot &robot, const real *q, const real *box_v, const real *box_a,
                                      const V3 *foot_v, const V3 *foot_a, real *v, real *a) {
  if (!robot.free_box) return LEGSIM_ERR_BAD_INPUT;
  static_assert(kLegUnknownsMax <= 64, "a leg's dense system on the stack");
  real K[kLegUnknownsMax * kLegUnknownsMax], x[kLegUnknownsMax];
  BodyState st[kMaxRobotBodies];
  Row rows[kMaxRobotRows];
  for (int i = 0; i < kBodyDof; ++i) v[i] = box_v[i], a[i] = box_a[i];
  // the velocities: the rows' coefficients (at any v) and no gamma
  const real zero[kBodyDof * kMaxRobotBodies] = {};
  for (int b = 0; b < robot.nb; ++b) st[b] = body_state(q + kBodyConfig * b, zero);
  robot_rows(robot, q, zero, rows);
  for (int l = 0; l < robot.nlegs; ++l) {
    const RobotLeg &L = robot.leg[l];
    int r0, r1;
    leg_rows(robot, l, r0, r1);
    const int neq = kBodyDof * (1 + L.nbars);
    if (L.foot_body < 0 || r1 - r0 + 3 != neq) return LEGSIM_ERR_MODEL;
    leg_system(robot, l, st, rows, r0, r1, box_v, foot_v[l], false, K, x);
    if (!solve(neq, K, x)) return LEGSIM_ERR_SINGULAR;
    std::copy(x, x + neq, v + kBodyDof * L.yoke);
  }
  // the accelerations: gamma at (q, v)
  for (int b = 0; b < robot.nb; ++b) st[b] = body_state(q + kBodyConfig * b, v + kBodyDof * b);
  robot_rows(robot, q, v, rows);
  for (int l = 0; l < robot.nlegs; ++l) {
    const RobotLeg &L = robot.leg[l];
    int r0, r1;
    leg_rows(robot, l, r0, r1);
    const int neq = kBodyDof * (1 + L.nbars);
    leg_system(robot, l, st, rows, r0, r1, box_a, foot_a[l], true, K, x);
    if (!solve(neq, K, x)) return LEGSIM_ERR_SINGULAR;
    std::copy(x, x + neq, a + kBodyDof * L.yoke);
  }
  return LEGSIM_OK;
}

legsim_status robot_inverse_dynamics(const SpatialRobot &robot, const real *q, const real *v, const real *a,
                                     uint32_t stance_mask, RobotStatics &out) {
  real Q[kBodyDof * kMaxRobotBodies];
  const real no_force[kMaxRobotActuators] = {}, no_torque[kMaxLegs] = {};
  robot_forces(robot, q, v, no_force, no_torque, Q);
  // d'Alembert: the inertial forces -M a are applied forces of the equilibrium
  for (int b = 0; b < robot.nb; ++b) {
    const real m[kBodyDof] = {robot.mass[b],      robot.mass[b],      robot.mass[b],
                              robot.inertia[b].x, robot.inertia[b].y, robot.inertia[b].z};
    for (int i = 0; i < kBodyDof; ++i) Q[kBodyDof * b + i] -= m[i] * a[kBodyDof * b + i];
  }
  return robot_statics_applied(robot, q, stance_mask, Q, out);
}

void robot_joint_reactions(const SpatialRobot &robot, const real *q, const real *mu, V3 *force, V3 *moment) {
  const real zero[kBodyDof * kMaxRobotBodies] = {};
  Row rows[kMaxRobotRows];
  robot_rows(robot, q, zero, rows);
  for (int j = 0; j < robot.nj; ++j) {
    const LegJoint &J = robot.joint[j];
    // a body's constraint force is -J^T lambda: its force (world), its moment about its centre
    // (its frame)
    real g[kBodyDof] = {};
    for (int r = J.row; r < J.row + J.nrows; ++r)
      for (int i = 0; i < kBodyDof; ++i) g[i] -= rows[r].ja[i] * mu[r];
    const BodyState A = body_state(q + kBodyConfig * J.a, zero);
    force[j] = {g[0], g[1], g[2]};
    moment[j] = rotate(A.R, V3{g[3], g[4], g[5]}) - cross(rotate(A.R, J.sa), force[j]);
  }
}

void twist_motion(real height, real speed, real rate, double t_s, real *box_q, real *box_v, real *box_a) {
  const real th = real(double(rate) * t_s), c = std::cos(th), s = std::sin(th);
  real x, y;  // the gait's own plan (spatial/gait)
  twist_displacement(speed, rate, real(t_s), x, y);
  const real q[7] = {x, y, height, std::cos(th / 2), 0, 0, std::sin(th / 2)};
  const real v[6] = {speed * c, speed * s, 0, 0, 0, rate};
  const real a[6] = {-speed * rate * s, speed * rate * c, 0, 0, 0, 0};
  std::copy(q, q + 7, box_q);
  std::copy(v, v + 6, box_v);
  std::copy(a, a + 6, box_a);
}

void stencil_derivatives(int k0, real h, const real *f, real &d1, real &d2) {
  // the weights w of derivative d: sum_i w_i x_i^m = m! [m == d], m = 0 .. 4, x_i = k0 + i
  real w[2][5];
  for (int d = 1; d <= 2; ++d) {
    real V[25];
    for (int m = 0; m < 5; ++m)
      for (int i = 0; i < 5; ++i) V[5 * m + i] = std::pow(real(k0 + i), real(m));
    for (int m = 0; m < 5; ++m) w[d - 1][m] = m == d ? real(d == 2 ? 2 : 1) : real(0);
    dense_solve(5, V, w[d - 1], 0);  // distinct nodes: never singular
  }
  d1 = d2 = 0;
  for (int i = 0; i < 5; ++i) d1 += w[0][i] * f[i], d2 += w[1][i] * f[i];
  d1 /= h, d2 /= h * h;
}

}  // namespace legsim::spatial
