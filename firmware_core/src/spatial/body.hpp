// The spatial element module's bodies (docs/design/spatial.md, formulation (a), absolute
// spatial coordinates): a body's configuration is its centre of mass r (m, world) and a unit
// quaternion (its rotation R, body to world): 7 numbers; its velocity is v (m/s, world) and
// omega (rad/s, body frame): 6, the velocity coordinates per body the system layer counts.
// Its mass matrix is constant and diagonal on its principal axes (m, m, m, J1, J2, J3); the
// gyroscopic term -omega x J omega is a force.
//
// The configuration update q (+) dq (config_add) is r + dr and q exp(dtheta) (dtheta the
// body-frame rotation vector): on the rotation group, so a step moves a quaternion by products
// with unit quaternions only (no normalization, no singular parameterization). RK4 on the group
// (Munthe-Kaas) takes each body's local coordinates theta from 0 at the step's start, with
// theta' = dexp^-1(theta) omega (dexp_inv).
//
// Plain scalar structs, as the planar row units' XY (rows.hpp says why: no Eigen expression
// left out of line on a Cortex-M).
#pragma once

#include <cmath>

#include "legsim/legsim.h"

namespace legsim::spatial {

using real = legsim_real;

// A tolerance in double, and its float build's (the round-off of float is 1e-7 where double's
// is 2e-16: a tolerance tied to round-off is looser there).
constexpr real by_precision(double in_double, double in_float) {
  return real(sizeof(real) == sizeof(float) ? in_float : in_double);
}

constexpr int kBodyDof = 6;     // velocity coordinates per body: v (3), omega (3)
constexpr int kBodyConfig = 7;  // configuration numbers per body: r (3), quaternion (w, x, y, z)

struct V3 {
  real x, y, z;
};
inline V3 operator+(const V3 &a, const V3 &b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(const V3 &a, const V3 &b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator-(const V3 &a) { return {-a.x, -a.y, -a.z}; }
inline V3 operator*(real s, const V3 &a) { return {s * a.x, s * a.y, s * a.z}; }
inline real dot(const V3 &a, const V3 &b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 cross(const V3 &a, const V3 &b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

struct Quat {
  real w, x, y, z;
};
// a b: the rotation b, then a (body-frame increments multiply on the right)
inline Quat quat_mul(const Quat &a, const Quat &b) {
  return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
          a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}

// The unit quaternion of the rotation by |theta| (rad) about theta's direction:
// (cos(t/2), sin(t/2) theta / t), by its series below t = 1e-3 rad (the division's
// cancellation; the series' first term left out is below 1e-19).
inline Quat quat_exp(const V3 &theta) {
  const real t2 = dot(theta, theta);
  real c, s;  // cos(t/2), sin(t/2) / t
  if (t2 < real(1e-6)) {
    c = 1 - t2 * (real(1) / 8) + t2 * t2 * (real(1) / 384);
    s = real(0.5) - t2 * (real(1) / 48) + t2 * t2 * (real(1) / 3840);
  } else {
    const real t = std::sqrt(t2);
    c = std::cos(real(0.5) * t);
    s = std::sin(real(0.5) * t) / t;
  }
  return {c, s * theta.x, s * theta.y, s * theta.z};
}

// A rotation matrix by its columns: the body's axes in world coordinates.
struct Rot {
  V3 c0, c1, c2;
};
// R of a unit quaternion.
inline Rot rotation(const Quat &q) {
  const real w = q.w, x = q.x, y = q.y, z = q.z;
  return {{1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)},
          {2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)},
          {2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)}};
}
inline V3 rotate(const Rot &R, const V3 &s) { return s.x * R.c0 + s.y * R.c1 + s.z * R.c2; }        // R s
inline V3 rotate_back(const Rot &R, const V3 &y) { return {dot(R.c0, y), dot(R.c1, y), dot(R.c2, y)}; }  // R^T y

// q (+) dq for one body: q = (r, quaternion), dq = (dr world, dtheta body frame).
inline void config_add(const real *q, const real *dq, real *out) {
  out[0] = q[0] + dq[0];
  out[1] = q[1] + dq[1];
  out[2] = q[2] + dq[2];
  const Quat p = quat_mul({q[3], q[4], q[5], q[6]}, quat_exp({dq[3], dq[4], dq[5]}));
  out[3] = p.w, out[4] = p.x, out[5] = p.y, out[6] = p.z;
}

// theta' of R = R0 exp(theta) turning at omega (body frame): the inverse of the right
// Jacobian of exp, theta' = omega + theta x omega / 2 + c theta x (theta x omega) with
// c = 1/t^2 - (1 + cos t) / (2 t sin t), by its series below t = 0.01 rad (the first term left
// out is below 1e-18). Singular at t = 2 pi: RK4 on the group starts theta at 0 each step.
inline V3 dexp_inv(const V3 &theta, const V3 &omega) {
  const real t2 = dot(theta, theta);
  real c;
  if (t2 < real(1e-4)) {
    c = real(1) / 12 + t2 * (real(1) / 720) + t2 * t2 * (real(1) / 30240);
  } else {
    const real t = std::sqrt(t2);
    c = 1 / t2 - (1 + std::cos(t)) / (2 * t * std::sin(t));
  }
  const V3 tw = cross(theta, omega);
  return omega + real(0.5) * tw + c * cross(theta, tw);
}

// A body's state as the row units read it: centre r, rotation R, velocity v (world) and
// omega (body frame). The ground: R = I, at rest.
struct BodyState {
  V3 r, v;
  Rot R;
  V3 w;
};
inline BodyState body_state(const real *q, const real *v) {
  return {{q[0], q[1], q[2]}, {v[0], v[1], v[2]}, rotation({q[3], q[4], q[5], q[6]}), {v[3], v[4], v[5]}};
}
inline BodyState ground_state() { return {{0, 0, 0}, {0, 0, 0}, {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {0, 0, 0}}; }

}  // namespace legsim::spatial
