#include "spatial/motion.hpp"

#include <algorithm>
#include <cmath>

namespace legsim::spatial {

namespace {
// J v on the used rows: the joints' and the stuck feet's (a row's rate from its coefficients).
int used_rows(const SpatialRobot &robot, const FeetHold &hold, int *idx) {
  int n = 0;
  for (int r = 0; r < robot.m; ++r) idx[n++] = r;
  for (int l = 0; l < robot.nlegs; ++l)
    for (int k = 0; k < foot_rows(hold, l); ++k) idx[n++] = foot_row(robot, l) + k;
  return n;
}

void body_pair(const SpatialRobot &robot, int r, int &a, int &b) {
  if (r < robot.m) {
    a = robot.row_body[r][0], b = robot.row_body[r][1];
  } else {
    a = robot.leg[(r - robot.m) / 3].foot_body, b = -1;
  }
}

real row_rate(const SpatialRobot &robot, const Row &row, int r, const real *v) {
  int a, b;
  body_pair(robot, r, a, b);
  real s = 0;
  for (int k = 0; k < kBodyDof; ++k) s += row.ja[k] * v[kBodyDof * a + k];
  if (b >= 0)
    for (int k = 0; k < kBodyDof; ++k) s += row.jb[k] * v[kBodyDof * b + k];
  return s;
}

legsim_status hold_check(const SpatialRobot &robot, const FeetHold &hold) {
  if ((hold.stuck | hold.sliding) >> robot.nlegs || (hold.stuck & hold.sliding)) return LEGSIM_ERR_BAD_INPUT;
  for (int l = 0; l < robot.nlegs; ++l)
    if (foot_rows(hold, l) && robot.leg[l].foot_body < 0) return LEGSIM_ERR_BAD_INPUT;
  return LEGSIM_OK;
}

legsim_status accelerations(const SpatialRobot &robot, RobotData &d, const real *q, const real *v, real *a,
                            real *mu) {
  real Q[kMaxRobotDof];
  robot_forces(robot, q, v, d.actuator_force, d.rowing_torque, Q);
  return robot_accelerations(robot, d.hold, q, v, Q, a, mu, d.rows, d.factor);
}
}  // namespace

legsim_status robot_project(const SpatialRobot &robot, const FeetHold &hold, real *q, real *v, int *iterations) {
  const int nv = kBodyDof * robot.nb;
  static const real zero_v[kMaxRobotDof] = {};
  real f[kMaxRobotDof] = {}, g[kMaxSystemRows], dx[kMaxRobotDof], mu[kMaxSystemRows];
  int idx[kMaxSystemRows];
  const int n = used_rows(robot, hold, idx);
  Row rows[kMaxSystemRows];
  int it = 0;
  for (;; ++it) {
    system_rows(robot, hold, q, zero_v, rows);
    real worst = 0;
    for (int i = 0; i < n; ++i) {
      g[idx[i]] = -rows[idx[i]].phi;
      worst = std::max(worst, std::abs(rows[idx[i]].phi));
    }
    if (!(worst == worst)) return LEGSIM_ERR_NOT_CONVERGED;  // NaN
    if (worst <= kProjectionTolerance) break;
    if (it == kProjectionMaxIterations) return LEGSIM_ERR_NOT_CONVERGED;
    static thread_local RobotFactor F;
    const legsim_status s = robot_factor(robot, hold, rows, F);
    if (s != LEGSIM_OK) return s;
    robot_solve(robot, F, f, g, dx, mu);
    for (int b = 0; b < robot.nb; ++b) {
      real out[kBodyConfig];
      config_add(q + kBodyConfig * b, dx + kBodyDof * b, out);
      std::copy(out, out + kBodyConfig, q + kBodyConfig * b);
    }
  }
  if (iterations) *iterations = it;
  system_rows(robot, hold, q, v, rows);
  for (int i = 0; i < n; ++i) g[idx[i]] = -row_rate(robot, rows[idx[i]], idx[i], v);
  static thread_local RobotFactor F;
  const legsim_status s = robot_factor(robot, hold, rows, F);
  if (s != LEGSIM_OK) return s;
  robot_solve(robot, F, f, g, dx, mu);
  for (int k = 0; k < nv; ++k) v[k] += dx[k];
  return LEGSIM_OK;
}

legsim_status robot_data_init(const SpatialRobot &robot, const real *q, const real *v, const FeetHold &hold,
                              RobotData &data) {
  legsim_status s = hold_check(robot, hold);
  if (s != LEGSIM_OK) return s;
  RobotData d;
  d.t = 0;
  std::copy(q, q + kBodyConfig * robot.nb, d.q);
  std::copy(v, v + kBodyDof * robot.nb, d.v);
  d.hold = hold;
  std::fill(d.actuator_force, d.actuator_force + kMaxRobotActuators, real(0));
  std::fill(d.rowing_torque, d.rowing_torque + kMaxLegs, real(0));
  d.projection_iterations = 0;
  s = robot_project(robot, d.hold, d.q, d.v, &d.projection_iterations);
  if (s == LEGSIM_OK) s = accelerations(robot, d, d.q, d.v, d.a, d.mu);
  if (s == LEGSIM_OK) data = d;
  return s;
}

legsim_status robot_data_refresh(const SpatialRobot &robot, RobotData &data) {
  legsim_status s = hold_check(robot, data.hold);
  if (s != LEGSIM_OK) return s;
  real a[kMaxRobotDof], mu[kMaxSystemRows];
  s = accelerations(robot, data, data.q, data.v, a, mu);
  if (s != LEGSIM_OK) return s;
  std::copy(a, a + kBodyDof * robot.nb, data.a);
  std::copy(mu, mu + kMaxSystemRows, data.mu);
  return LEGSIM_OK;
}

legsim_status robot_step_rk4(const SpatialRobot &robot, RobotData &data, real h) {
  if (!(h > 0) || !std::isfinite(h)) return LEGSIM_ERR_BAD_INPUT;
  const int nb = robot.nb, nv = kBodyDof * nb;
  const real *q0 = data.q, *v0 = data.v;
  real q[kBodyConfig * kMaxRobotBodies], th[kMaxRobotDof], v[kMaxRobotDof], mu[kMaxSystemRows];
  real kth[4][kMaxRobotDof], kv[4][kMaxRobotDof];
  // stage s at theta = th, velocity v: theta' and v'
  auto stage = [&](int s, const real *ths, const real *vs) {
    for (int b = 0; b < nb; ++b) config_add(q0 + kBodyConfig * b, ths + kBodyDof * b, q + kBodyConfig * b);
    for (int b = 0; b < nb; ++b) {
      const real *tb = ths + kBodyDof * b, *vb = vs + kBodyDof * b;
      real *o = kth[s] + kBodyDof * b;
      const V3 w = dexp_inv({tb[3], tb[4], tb[5]}, {vb[3], vb[4], vb[5]});
      o[0] = vb[0], o[1] = vb[1], o[2] = vb[2], o[3] = w.x, o[4] = w.y, o[5] = w.z;
    }
    return accelerations(robot, data, q, vs, kv[s], mu);
  };
  // the first stage is the last step's end (robot_data_init / _refresh keep it current)
  for (int k = 0; k < nv; ++k) kth[0][k] = v0[k], kv[0][k] = data.a[k];
  static const real c[3] = {real(0.5), real(0.5), real(1)};
  for (int s = 1; s < 4; ++s) {
    for (int k = 0; k < nv; ++k) th[k] = c[s - 1] * h * kth[s - 1][k], v[k] = v0[k] + c[s - 1] * h * kv[s - 1][k];
    const legsim_status st = stage(s, th, v);
    if (st != LEGSIM_OK) return st;
  }
  for (int k = 0; k < nv; ++k) {
    th[k] = h / 6 * (kth[0][k] + 2 * (kth[1][k] + kth[2][k]) + kth[3][k]);
    v[k] = v0[k] + h / 6 * (kv[0][k] + 2 * (kv[1][k] + kv[2][k]) + kv[3][k]);
  }
  for (int b = 0; b < nb; ++b) config_add(q0 + kBodyConfig * b, th + kBodyDof * b, q + kBodyConfig * b);
  int iterations = 0;
  legsim_status st = robot_project(robot, data.hold, q, v, &iterations);
  real a[kMaxRobotDof];
  if (st == LEGSIM_OK) st = accelerations(robot, data, q, v, a, mu);
  if (st != LEGSIM_OK) return st;
  for (int k = 0; k < nv; ++k) {
    if (!std::isfinite(v[k]) || !std::isfinite(a[k])) return LEGSIM_ERR_NOT_CONVERGED;
  }
  std::copy(q, q + kBodyConfig * nb, data.q);
  std::copy(v, v + nv, data.v);
  std::copy(a, a + nv, data.a);
  std::copy(mu, mu + kMaxSystemRows, data.mu);
  data.projection_iterations = iterations;
  data.t += h;
  return LEGSIM_OK;
}

real robot_kinetic_energy(const SpatialRobot &robot, const real *v) {
  real T = 0;
  for (int b = 0; b < robot.nb; ++b) {
    const real *vb = v + kBodyDof * b;
    const V3 &I = robot.inertia[b];
    T += robot.mass[b] * (vb[0] * vb[0] + vb[1] * vb[1] + vb[2] * vb[2]) + I.x * vb[3] * vb[3] + I.y * vb[4] * vb[4] +
         I.z * vb[5] * vb[5];
  }
  return T / 2;
}

real robot_gravity_potential(const SpatialRobot &robot, const real *q) {
  real U = 0;
  for (int b = 0; b < robot.nb; ++b)
    U -= robot.mass[b] * (robot.gravity.x * q[kBodyConfig * b] + robot.gravity.y * q[kBodyConfig * b + 1] +
                          robot.gravity.z * q[kBodyConfig * b + 2]);
  return U;
}

}  // namespace legsim::spatial
