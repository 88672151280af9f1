#include "spatial/statics.hpp"

#include <algorithm>

#include "system/dense_solve.hpp"

namespace legsim::spatial {

namespace {
constexpr int kLegBodiesMax = 1 + kMaxLegBars;
constexpr int kLegUnknownsMax = kBodyDof * kLegBodiesMax;  // a leg's equations, as many unknowns

// The whole robot's stance forces: the least-norm f with A f = b, A (6 x 3n) the equilibrium of
// the forces f_k at the feet p_k about the centre of mass c, b = -(the loads' resultant and
// their moment about c). f = A^T y, (A A^T) y = b.
legsim_status stance_forces(int n, const V3 *p, const V3 &c, const V3 &load, const V3 &load_moment, V3 *f) {
  real AAt[36] = {}, y[6] = {-load.x, -load.y, -load.z, -load_moment.x, -load_moment.y, -load_moment.z};
  real scale = 0;
  // A's columns for foot k: [I; (p_k - c)^] (the moment (p - c) x f)
  auto column = [&](int k, int axis, real *a) {
    const V3 e = axis == 0 ? V3{1, 0, 0} : axis == 1 ? V3{0, 1, 0} : V3{0, 0, 1};
    const V3 m = cross(p[k] - c, e);
    a[0] = e.x, a[1] = e.y, a[2] = e.z, a[3] = m.x, a[4] = m.y, a[5] = m.z;
  };
  for (int k = 0; k < n; ++k)
    for (int axis = 0; axis < 3; ++axis) {
      real a[6];
      column(k, axis, a);
      for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 6; ++j) AAt[6 * i + j] += a[i] * a[j];
    }
  for (int i = 0; i < 6; ++i) scale = std::max(scale, std::abs(AAt[7 * i]));
  // collinear feet leave the moment about their line unbalanced: A A^T singular
  if (!dense_solve(6, AAt, y, real(1e-9) * scale)) return LEGSIM_ERR_NO_EQUILIBRIUM;
  for (int k = 0; k < n; ++k) {
    real fk[3];
    for (int axis = 0; axis < 3; ++axis) {
      real a[6];
      column(k, axis, a);
      fk[axis] = 0;
      for (int i = 0; i < 6; ++i) fk[axis] += a[i] * y[i];
    }
    f[k] = {fk[0], fk[1], fk[2]};
  }
  return LEGSIM_OK;
}
}  // namespace

legsim_status robot_statics(const SpatialRobot &robot, const real *q, uint32_t stance_mask, const real *box_force_n,
                            RobotStatics &out) {
  if (!robot.free_box || (stance_mask >> robot.nlegs) != 0) return LEGSIM_ERR_BAD_INPUT;
  // the weights, and the load on the box's centre
  real Q[kBodyDof * kMaxRobotBodies];
  for (int b = 0; b < robot.nb; ++b) {
    const real m = robot.mass[b];
    const real f[kBodyDof] = {m * robot.gravity.x, m * robot.gravity.y, m * robot.gravity.z, 0, 0, 0};
    for (int i = 0; i < kBodyDof; ++i) Q[kBodyDof * b + i] = f[i];
  }
  if (box_force_n)
    for (int i = 0; i < 3; ++i) Q[i] += box_force_n[i];
  return robot_statics_applied(robot, q, stance_mask, Q, out);
}

legsim_status robot_statics_applied(const SpatialRobot &robot, const real *q, uint32_t stance_mask, const real *Q,
                                    RobotStatics &out) {
  if (!robot.free_box || (stance_mask >> robot.nlegs) != 0) return LEGSIM_ERR_BAD_INPUT;
  // the centre of mass, and the loads' resultant and moment about it (a body's moment is in its
  // frame)
  real M = 0;
  V3 c = {0, 0, 0};
  for (int b = 0; b < robot.nb; ++b) {
    M += robot.mass[b];
    c = c + robot.mass[b] * V3{q[kBodyConfig * b], q[kBodyConfig * b + 1], q[kBodyConfig * b + 2]};
  }
  c = (1 / M) * c;
  V3 load = {0, 0, 0}, load_moment = {0, 0, 0};
  for (int b = 0; b < robot.nb; ++b) {
    const real *qb = q + kBodyConfig * b, *Qb = Q + kBodyDof * b;
    const V3 f = {Qb[0], Qb[1], Qb[2]};
    load = load + f;
    load_moment = load_moment + cross(V3{qb[0], qb[1], qb[2]} - c, f) +
                  rotate(rotation({qb[3], qb[4], qb[5], qb[6]}), V3{Qb[3], Qb[4], Qb[5]});
  }
  V3 p[kMaxLegs], f[kMaxLegs];
  int leg_of[kMaxLegs], n = 0;
  for (int l = 0; l < robot.nlegs; ++l) {
    out.foot_force[l] = {0, 0, 0};
    if (!((stance_mask >> l) & 1u)) continue;
    if (robot.leg[l].foot_body < 0) return LEGSIM_ERR_BAD_INPUT;
    p[n] = robot_foot_position(robot, l, q);
    leg_of[n++] = l;
  }
  if (n < 3) return LEGSIM_ERR_NO_EQUILIBRIUM;
  legsim_status s = stance_forces(n, p, c, load, load_moment, f);
  if (s != LEGSIM_OK) return s;
  // a foot that would have to pull (its force not up, against gravity) cannot stand there: the
  // loads' line of action outside the support polygon, or a stance that needs the ground to hold
  const V3 up = -1 * robot.gravity;
  for (int k = 0; k < n; ++k)
    if (!(dot(f[k], up) > 0)) return LEGSIM_ERR_NO_EQUILIBRIUM;
  for (int k = 0; k < n; ++k) out.foot_force[leg_of[k]] = f[k];

  // each leg on its own: K x = Q, x = (its multipliers, its actuators' forces, its rowing torque)
  const real zero_v[kBodyDof] = {0, 0, 0, 0, 0, 0};
  BodyState st[kMaxRobotBodies];
  for (int b = 0; b < robot.nb; ++b) st[b] = body_state(q + kBodyConfig * b, zero_v);
  Row rows[kMaxRobotRows];
  real rest[kBodyDof * kMaxRobotBodies] = {};  // statics: at rest
  robot_rows(robot, q, rest, rows);
  for (int l = 0; l < robot.nlegs; ++l) {
    const RobotLeg &L = robot.leg[l];
    const int nbl = 1 + L.nbars, neq = kBodyDof * nbl, b0 = L.yoke;
    // its rows: the joints whose first body is one of its bodies (the hip's too)
    int r0 = -1, r1 = -1;
    for (int k = 0; k < robot.nj; ++k) {
      const LegJoint &j = robot.joint[k];
      if (j.a < b0 || j.a >= b0 + nbl) continue;
      if (r0 < 0) r0 = j.row;
      r1 = j.row + j.nrows;
    }
    const int nrows = r1 - r0;
    if (nrows + L.nactuators + 1 != neq) return LEGSIM_ERR_MODEL;  // not as many freedoms as actuators
    static_assert(kLegUnknownsMax <= 64, "a leg's dense system on the stack");
    real K[kLegUnknownsMax * kLegUnknownsMax] = {}, x[kLegUnknownsMax] = {};
    auto put = [&](int body, int col, const real *coef, real sign) {
      if (body < b0 || body >= b0 + nbl) return;  // the box: held
      for (int i = 0; i < kBodyDof; ++i) K[(kBodyDof * (body - b0) + i) * neq + col] += sign * coef[i];
    };
    for (int k = 0; k < robot.nj; ++k) {
      const LegJoint &j = robot.joint[k];
      if (j.row < r0 || j.row >= r1) continue;
      for (int r = j.row; r < j.row + j.nrows; ++r) {
        put(j.a, r - r0, rows[r].ja, 1);
        if (j.b >= 0) put(j.b, r - r0, rows[r].jb, 1);
      }
    }
    for (int a = 0; a < L.nactuators; ++a) {
      const RobotActuator &ac = robot.act[L.first_actuator + a];
      const Row g = actuator_row(st[ac.rod], st[ac.cyl]);
      put(ac.rod, nrows + a, g.ja, -1);
      put(ac.cyl, nrows + a, g.jb, -1);
    }
    const real tau_col[kBodyDof] = {0, 0, 0, 0, 0, 1};  // about the yoke's z: the hip axis
    put(b0, neq - 1, tau_col, -1);
    // Q, and the foot's force at its point
    for (int i = 0; i < neq; ++i) x[i] = Q[kBodyDof * b0 + i];
    if (L.foot_body >= 0) {
      const V3 &ff = out.foot_force[l];
      real fq[kBodyDof] = {};
      point_coefficients(st[L.foot_body], L.foot_point, ff, 1, fq);
      for (int i = 0; i < kBodyDof; ++i) x[kBodyDof * (L.foot_body - b0) + i] += fq[i];
    }
    real scale = 0;
    for (int i = 0; i < neq * neq; ++i) scale = std::max(scale, std::abs(K[i]));
    if (!dense_solve(neq, K, x, real(1e-10) * scale)) return LEGSIM_ERR_SINGULAR;
    for (int r = 0; r < nrows; ++r) out.multiplier[r0 + r] = x[r];
    for (int a = 0; a < L.nactuators; ++a) out.actuator_force[L.first_actuator + a] = x[nrows + a];
    out.rowing_torque[l] = x[neq - 1];
  }
  return LEGSIM_OK;
}

}  // namespace legsim::spatial
