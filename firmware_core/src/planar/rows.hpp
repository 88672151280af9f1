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

// Inlined always: a large generated kernel calls a unit for every joint, and each call must
// fold into straight-line code on its locals (body_trig, body.hpp, says why the inliner's own
// choice is not enough). The units' arithmetic is on scalars (XY, no Eigen expression): at
// -Os on Cortex-M GCC leaves Eigen's small assignments out of line, and every vector they
// touch (the poses, each joint's rows) then stays on the stack for the whole kernel.
#if defined(__GNUC__)
#define LEGSIM_ROW_UNIT __attribute__((always_inline)) inline
#else
#define LEGSIM_ROW_UNIT inline
#endif

// A planar vector (m, m/s) as two scalars.
struct XY {
  real x, y;
};
LEGSIM_ROW_UNIT real dot(const XY &a, const XY &b) { return a.x * b.x + a.y * b.y; }

// A body's pose (eq. (1)): centre r, angle phi, axis u = (sin, -cos), normal n = (cos, sin),
// and its velocities.
struct BodyPose {
  XY r, rd;     // centre (m) and its velocity (m/s)
  real phi, w;  // angle (rad) and angular velocity (rad/s)
  XY u, n;
};

// The pose of body b at q, with its angle's sin s and cos c given (body_trig's pair).
LEGSIM_ROW_UNIT BodyPose body_pose(const VecQ &q, int b, real s, real c) {
  BodyPose p;
  p.r = {q[kBodyDof * b], q[kBodyDof * b + 1]};
  p.phi = q[kBodyDof * b + 2];
  p.u = {s, -c};
  p.n = {c, s};
  p.rd = {0, 0};
  p.w = 0;
  return p;
}

// Its velocities (vx, vy, w).
LEGSIM_ROW_UNIT void body_velocity(BodyPose &p, real vx, real vy, real w) {
  p.rd = {vx, vy};
  p.w = w;
}

// Body-fixed (xi, eta) to a world-axes offset from the centre: xi u + eta n.
LEGSIM_ROW_UNIT XY offset(const BodyPose &p, const Vec2 &xi_eta) {
  const real xi = xi_eta.x(), eta = xi_eta.y();
  return {xi * p.u.x + eta * p.n.x, xi * p.u.y + eta * p.n.y};
}

// One joint's rows (at most two) and what gamma reuses from the positions' part.
struct JointRows {
  real phi[2], gamma[2];
  real coef[2][2][kBodyDof];  // [row][slot: body a, body b][d/dx, d/dy, d/dphi]
  XY sa, sb;                  // the joint points' offsets from their bodies' centres (m)
  XY d, dd;                   // the separation the rows measure (m) and its rate (m/s)
};

LEGSIM_ROW_UNIT void set_coef(real (&c)[kBodyDof], real gx, real gy, real gphi) {
  c[0] = gx;
  c[1] = gy;
  c[2] = gphi;
}

// Revolute (eqs. (2)-(11)): point on a = point on b (b null: a frame point, pb).
// Phi = ra + sa - rb - sb; d/dphi of a body-fixed offset s is perp(s) = (-s_y, s_x).
LEGSIM_ROW_UNIT void revolute_position(const Joint &j, const BodyPose &a, const BodyPose *b, JointRows &o) {
  o.sa = offset(a, j.pa);
  real phix = a.r.x + o.sa.x, phiy = a.r.y + o.sa.y;
  if (!b) {
    phix -= j.pb.x();
    phiy -= j.pb.y();
  } else {
    o.sb = offset(*b, j.pb);
    phix -= b->r.x + o.sb.x;
    phiy -= b->r.y + o.sb.y;
    set_coef(o.coef[0][1], -1, 0, o.sb.y);
    set_coef(o.coef[1][1], 0, -1, -o.sb.x);
  }
  set_coef(o.coef[0][0], 1, 0, -o.sa.y);
  set_coef(o.coef[1][0], 0, 1, o.sa.x);
  o.phi[0] = phix;
  o.phi[1] = phiy;
}
// gamma = wa^2 sa - wb^2 sb.
LEGSIM_ROW_UNIT void revolute_gamma(const BodyPose &a, const BodyPose *b, JointRows &o) {
  const real wa2 = a.w * a.w;
  real gx = wa2 * o.sa.x, gy = wa2 * o.sa.y;
  if (b) {
    const real wb2 = b->w * b->w;
    gx -= wb2 * o.sb.x;
    gy -= wb2 * o.sb.y;
  }
  o.gamma[0] = gx;
  o.gamma[1] = gy;
}

// Prismatic (eqs. (12)-(16)): phi_b - phi_a = 0 and (rb - ra) . na = 0.
LEGSIM_ROW_UNIT void prismatic_position(const BodyPose &a, const BodyPose &b, JointRows &o) {
  o.d = {b.r.x - a.r.x, b.r.y - a.r.y};
  o.phi[0] = b.phi - a.phi;
  set_coef(o.coef[0][0], 0, 0, -1);
  set_coef(o.coef[0][1], 0, 0, 1);
  o.phi[1] = dot(o.d, a.n);
  set_coef(o.coef[1][0], -a.n.x, -a.n.y, -dot(o.d, a.u));
  set_coef(o.coef[1][1], a.n.x, a.n.y, 0);
}
LEGSIM_ROW_UNIT void prismatic_gamma(const BodyPose &a, const BodyPose &b, JointRows &o) {
  o.dd = {b.rd.x - a.rd.x, b.rd.y - a.rd.y};
  o.gamma[0] = 0;
  o.gamma[1] = 2 * a.w * dot(o.dd, a.u) + a.w * a.w * dot(o.d, a.n);
}

// Slot (eq. (18)): point on a lies on the axis of b: (ra + sa - rb) . nb = 0.
LEGSIM_ROW_UNIT void slot_position(const Joint &j, const BodyPose &a, const BodyPose &b, JointRows &o) {
  o.sa = offset(a, j.pa);
  o.d = {(a.r.x + o.sa.x) - b.r.x, (a.r.y + o.sa.y) - b.r.y};
  o.phi[0] = dot(o.d, b.n);
  set_coef(o.coef[0][0], b.n.x, b.n.y, dot(XY{-o.sa.y, o.sa.x}, b.n));
  set_coef(o.coef[0][1], -b.n.x, -b.n.y, -dot(o.d, b.u));
}
LEGSIM_ROW_UNIT void slot_gamma(const BodyPose &a, const BodyPose &b, JointRows &o) {
  o.dd = {(a.rd.x + a.w * -o.sa.y) - b.rd.x, (a.rd.y + a.w * o.sa.x) - b.rd.y};
  o.gamma[0] = a.w * a.w * dot(o.sa, b.n) + 2 * b.w * dot(o.dd, b.u) + b.w * b.w * dot(o.d, b.n);
}

// Actuator length driver: (r_rod - r_cyl) . u_cyl + offset - l(t) = 0, Phi_q qd = l'(t),
// gamma = l''(t) - 2 w dd . n + w^2 d . u (a: the cylinder, b: the rod; one row).
LEGSIM_ROW_UNIT void actuator_position(const Actuator &ac, real length, const BodyPose &a, const BodyPose &b,
                                       JointRows &o) {
  o.d = {b.r.x - a.r.x, b.r.y - a.r.y};
  o.phi[0] = dot(o.d, a.u) + ac.offset_m - length;
  set_coef(o.coef[0][0], -a.u.x, -a.u.y, dot(o.d, a.n));
  set_coef(o.coef[0][1], a.u.x, a.u.y, 0);
}
LEGSIM_ROW_UNIT void actuator_gamma(real accel, const BodyPose &a, const BodyPose &b, JointRows &o) {
  o.dd = {b.rd.x - a.rd.x, b.rd.y - a.rd.y};
  o.gamma[0] = accel - 2 * a.w * dot(o.dd, a.n) + a.w * a.w * dot(o.d, a.u);
}

// A body pinned to the frame by one revolute joint (RK4's reduced solves, kernel_codegen.py's
// Reduced) moves on its angle alone: qd_b = G u, qdd_b = G udd + g, G = (sa_y, -sa_x, 1)
// (sa: the pin point's offset from the centre, JointRows::sa), g = (g0, g1, 0) (the pin
// rows' gamma): every motion its two rows allow. m: the body's mass matrix (m, m, J).
// 1 / (G^T M_b G): the inverse of its moment of inertia about the pin.
LEGSIM_ROW_UNIT real pin_inverse_inertia(const real *m, const XY &sa) {
  return 1 / ((m[0] * sa.y * sa.y + m[1] * sa.x * sa.x) + m[2]);
}
// G^T (Q_b - M_b g): the force on its angle, from its applied forces (qx, qy, qphi).
LEGSIM_ROW_UNIT real pin_force(const real *m, const XY &sa, real g0, real g1, real qx, real qy, real qphi) {
  return (sa.y * (qx - m[0] * g0) - sa.x * (qy - m[1] * g1)) + qphi;
}
// G udd + g: its centre's acceleration from its angle's udd.
LEGSIM_ROW_UNIT XY pin_acceleration(const XY &sa, real g0, real g1, real udd) {
  return {g0 + sa.y * udd, g1 - sa.x * udd};
}
// wr G^T M_b v (wr = pin_inverse_inertia): the angle's rate whose motion G u is the
// M-nearest to its velocities v = (vx, vy, w).
LEGSIM_ROW_UNIT real pin_rate(const real *m, const XY &sa, real wr, real vx, real vy, real w) {
  return wr * ((m[0] * sa.y * vx - m[1] * sa.x * vy) + m[2] * w);
}
// G u's centre velocity.
LEGSIM_ROW_UNIT XY pin_velocity(const XY &sa, real u) { return {sa.y * u, -sa.x * u}; }

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
  const XY sp = offset(b, point), ew = {e.x(), e.y()};
  o.phi = weight * dot(ew, XY{(b.r.x + sp.x) - ground.x(), (b.r.y + sp.y) - ground.y()}) - target;
  set_coef(o.coef, weight * ew.x, weight * ew.y, weight * dot(ew, XY{-sp.y, sp.x}));
  o.gamma = weight * b.w * b.w * dot(ew, sp);
}

// Coordinate driver: q_k - value = 0 (k: coordinate c of its body).
LEGSIM_ROW_UNIT real coordinate_phi(const legsim_coord_driver &c, const VecQ &q) {
  return q[kBodyDof * c.body + c.coord] - real(c.value);
}

}  // namespace legsim
