// The row units: each joint kind's, a driver's and a contact's constraint rows, Phi(q) = 0,
// with their Jacobian coefficients and the acceleration right-hand side gamma
// (Phi_q qdd = gamma), as inline functions over the bodies' poses. One implementation of
// each equation: the general path (rows_eval, constraints.cpp) and the generated kernels
// (kernel_codegen.py, which calls them with fixed joint and body indices) both use these,
// so both compute the same numbers with the same operations.
//
// A joint's unit comes in two parts, the positions' (Phi, the Jacobian) and the
// velocities' (gamma), so that a caller can test and factor before it has velocities; the
// second reuses the first's offsets, kept in JointRows.
#pragma once

#include "sim.hpp"

namespace legsim {

// Inlined always on x86-64 (flash does not count there): a large generated kernel calls a
// unit for every joint, and each call must fold into straight-line code on its locals
// (body_trig, body.hpp, says why the inliner's own choice is not enough).
#if defined(__x86_64__) && defined(__GNUC__)
#define LEGSIM_ROW_UNIT __attribute__((always_inline)) inline
#else
#define LEGSIM_ROW_UNIT inline
#endif

// A body's pose (eq. (1)): centre r, angle phi, axis u = (sin, -cos), normal n = (cos, sin),
// and its velocities.
struct BodyPose {
  Vec2 r, rd;   // centre (m) and its velocity (m/s)
  real phi, w;  // angle (rad) and angular velocity (rad/s)
  Vec2 u, n;
};

// The pose of body b at q, with its angle's sin s and cos c given (body_trig's pair).
LEGSIM_ROW_UNIT BodyPose body_pose(const VecQ &q, int b, real s, real c) {
  BodyPose p;
  p.r = Vec2(q[kBodyDof * b], q[kBodyDof * b + 1]);
  p.phi = q[kBodyDof * b + 2];
  p.u = Vec2(s, -c);
  p.n = Vec2(c, s);
  p.rd = Vec2::Zero();
  p.w = 0;
  return p;
}

// Its velocities (vx, vy, w).
LEGSIM_ROW_UNIT void body_velocity(BodyPose &p, real vx, real vy, real w) {
  p.rd = Vec2(vx, vy);
  p.w = w;
}

// Body-fixed (xi, eta) to a world-axes offset from the centre: xi u + eta n.
LEGSIM_ROW_UNIT Vec2 offset(const BodyPose &p, const Vec2 &xi_eta) { return xi_eta.x() * p.u + xi_eta.y() * p.n; }

// One joint's rows (at most two) and what gamma reuses from the positions' part.
struct JointRows {
  real phi[2], gamma[2];
  real coef[2][2][kBodyDof];  // [row][slot: body a, body b][d/dx, d/dy, d/dphi]
  Vec2 sa, sb;                // the joint points' offsets from their bodies' centres (m)
  Vec2 d, dd;                 // the separation the rows measure (m) and its rate (m/s)
};

LEGSIM_ROW_UNIT void set_coef(real (&c)[kBodyDof], const Vec2 &g, real gphi) {
  c[0] = g.x();
  c[1] = g.y();
  c[2] = gphi;
}

// Revolute (eqs. (2)-(11)): point on a = point on b (b null: a frame point, pb).
// Phi = ra + sa - rb - sb.
LEGSIM_ROW_UNIT void revolute_position(const Joint &j, const BodyPose &a, const BodyPose *b, JointRows &o) {
  o.sa = offset(a, j.pa);
  Vec2 phi = a.r + o.sa;
  if (!b) {
    phi -= j.pb;
  } else {
    o.sb = offset(*b, j.pb);
    phi -= b->r + o.sb;
    const Vec2 psb = perp(o.sb);
    set_coef(o.coef[0][1], Vec2(-1, 0), -psb.x());
    set_coef(o.coef[1][1], Vec2(0, -1), -psb.y());
  }
  const Vec2 psa = perp(o.sa);
  set_coef(o.coef[0][0], Vec2(1, 0), psa.x());
  set_coef(o.coef[1][0], Vec2(0, 1), psa.y());
  o.phi[0] = phi.x();
  o.phi[1] = phi.y();
}
// gamma = wa^2 sa - wb^2 sb.
LEGSIM_ROW_UNIT void revolute_gamma(const BodyPose &a, const BodyPose *b, JointRows &o) {
  Vec2 gamma = a.w * a.w * o.sa;
  if (b) gamma -= b->w * b->w * o.sb;
  o.gamma[0] = gamma.x();
  o.gamma[1] = gamma.y();
}

// Prismatic (eqs. (12)-(16)): phi_b - phi_a = 0 and (rb - ra) . na = 0.
LEGSIM_ROW_UNIT void prismatic_position(const BodyPose &a, const BodyPose &b, JointRows &o) {
  o.d = b.r - a.r;
  o.phi[0] = b.phi - a.phi;
  set_coef(o.coef[0][0], Vec2::Zero(), -1);
  set_coef(o.coef[0][1], Vec2::Zero(), 1);
  o.phi[1] = o.d.dot(a.n);
  set_coef(o.coef[1][0], -a.n, -o.d.dot(a.u));
  set_coef(o.coef[1][1], a.n, 0);
}
LEGSIM_ROW_UNIT void prismatic_gamma(const BodyPose &a, const BodyPose &b, JointRows &o) {
  o.dd = b.rd - a.rd;
  o.gamma[0] = 0;
  o.gamma[1] = 2 * a.w * o.dd.dot(a.u) + a.w * a.w * o.d.dot(a.n);
}

// Slot (eq. (18)): point on a lies on the axis of b: (ra + sa - rb) . nb = 0.
LEGSIM_ROW_UNIT void slot_position(const Joint &j, const BodyPose &a, const BodyPose &b, JointRows &o) {
  o.sa = offset(a, j.pa);
  o.d = a.r + o.sa - b.r;
  o.phi[0] = o.d.dot(b.n);
  set_coef(o.coef[0][0], b.n, perp(o.sa).dot(b.n));
  set_coef(o.coef[0][1], -b.n, -o.d.dot(b.u));
}
LEGSIM_ROW_UNIT void slot_gamma(const BodyPose &a, const BodyPose &b, JointRows &o) {
  o.dd = a.rd + a.w * perp(o.sa) - b.rd;
  o.gamma[0] = a.w * a.w * o.sa.dot(b.n) + 2 * b.w * o.dd.dot(b.u) + b.w * b.w * o.d.dot(b.n);
}

// Actuator length driver: (r_rod - r_cyl) . u_cyl + offset - l(t) = 0, Phi_q qd = l'(t),
// gamma = l''(t) - 2 w dd . n + w^2 d . u (a: the cylinder, b: the rod; one row).
LEGSIM_ROW_UNIT void actuator_position(const Actuator &ac, real length, const BodyPose &a, const BodyPose &b,
                                       JointRows &o) {
  o.d = b.r - a.r;
  o.phi[0] = o.d.dot(a.u) + ac.offset_m - length;
  set_coef(o.coef[0][0], -a.u, o.d.dot(a.n));
  set_coef(o.coef[0][1], a.u, 0);
}
LEGSIM_ROW_UNIT void actuator_gamma(real accel, const BodyPose &a, const BodyPose &b, JointRows &o) {
  o.dd = b.rd - a.rd;
  o.gamma[0] = accel - 2 * a.w * o.dd.dot(a.n) + a.w * a.w * o.d.dot(a.u);
}

// A body pinned to the frame by one revolute joint (RK4's reduced solves, kernel_codegen.py's
// Reduced) moves on its angle alone: qd_b = G u, qdd_b = G udd + g, G = (sa_y, -sa_x, 1)
// (sa: the pin point's offset from the centre), g = (gamma_0, gamma_1, 0) (the pin rows'
// gamma): every motion its two rows allow. m: the body's mass matrix (m, m, J).
// 1 / (G^T M_b G): the inverse of its moment of inertia about the pin.
LEGSIM_ROW_UNIT real pin_inverse_inertia(const real *m, const JointRows &pin) {
  return 1 / ((m[0] * pin.sa.y() * pin.sa.y() + m[1] * pin.sa.x() * pin.sa.x()) + m[2]);
}
// G^T (Q_b - M_b g): the force on its angle, from its applied forces (qx, qy, qphi).
LEGSIM_ROW_UNIT real pin_force(const real *m, const JointRows &pin, real qx, real qy, real qphi) {
  return (pin.sa.y() * (qx - m[0] * pin.gamma[0]) - pin.sa.x() * (qy - m[1] * pin.gamma[1])) + qphi;
}
// G udd + g: its centre's acceleration from its angle's udd.
LEGSIM_ROW_UNIT Vec2 pin_acceleration(const JointRows &pin, real udd) {
  return Vec2(pin.gamma[0] + pin.sa.y() * udd, pin.gamma[1] - pin.sa.x() * udd);
}
// wr G^T M_b v (wr = pin_inverse_inertia): the angle's rate whose motion G u is the
// M-nearest to its velocities v = (vx, vy, w).
LEGSIM_ROW_UNIT real pin_rate(const real *m, const JointRows &pin, real wr, real vx, real vy, real w) {
  return wr * ((m[0] * pin.sa.y() * vx - m[1] * pin.sa.x() * vy) + m[2] * w);
}
// G u's centre velocity.
LEGSIM_ROW_UNIT Vec2 pin_velocity(const JointRows &pin, real u) { return Vec2(pin.sa.y() * u, -pin.sa.x() * u); }

// A contact row: a foot point p = r + s on the ground line through g, along the direction
// e (the line's normal: the gap n.(p - g) = 0; its tangent: t.(p - g) - stick = 0, target
// the stick point), times weight (the feet's midpoint row sums two feet's halves);
// gamma = w^2 e.s.
struct ContactRow {
  real phi, gamma;
  real coef[kBodyDof];
};
LEGSIM_ROW_UNIT void contact_row(const Vec2 &point, const Vec2 &ground, const Vec2 &e, real target, real weight,
                                 const BodyPose &b, ContactRow &o) {
  const Vec2 sp = offset(b, point);
  o.phi = weight * e.dot(b.r + sp - ground) - target;
  set_coef(o.coef, weight * e, weight * e.dot(perp(sp)));
  o.gamma = weight * b.w * b.w * e.dot(sp);
}

// Coordinate driver: q_k - value = 0 (k: coordinate c of its body).
LEGSIM_ROW_UNIT real coordinate_phi(const legsim_coord_driver &c, const VecQ &q) {
  return q[kBodyDof * c.body + c.coord] - real(c.value);
}

}  // namespace legsim
