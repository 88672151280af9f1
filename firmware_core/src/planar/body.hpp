// The planar element module's bodies: a body's coordinates (x, y, phi), the geometry of
// eq. (1) (its axis and normal, body-fixed points), the sin and cos of its angle, and the
// two things the dimension-free system layer asks of a body kind (system/body_dof.hpp...):
// its velocity coordinates per body, its mass matrix and its configuration update.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>

#include "legsim/legsim.h"
#include "planar/kernel_trig.hpp"

namespace legsim {

using real = legsim_real;
using Vec2 = Eigen::Matrix<real, 2, 1>;
using Vec3 = Eigen::Matrix<real, 3, 1>;

constexpr int kMaxBodies = LEGSIM_MAX_BODIES;
// Velocity coordinates per body (x, y, phi): the one number the system layer is
// parameterised by (6 for a spatial body).
constexpr int kBodyDof = 3;

// Unit axis u(phi) = (sin, -cos) and normal n(phi) = (cos, sin) of eq. (1).
// (sincos_any: the library's in double, kernel_trig.hpp's reduction in float)
inline Vec2 axis_u(real phi) {
  real s, c;
  sincos_any(phi, s, c);
  return Vec2(s, -c);
}
inline Vec2 normal_n(real phi) {
  real s, c;
  sincos_any(phi, s, c);
  return Vec2(c, s);
}
// Rotation by +90 degrees: d/dphi of a body-fixed vector s is perp(s).
inline Vec2 perp(const Vec2 &s) { return Vec2(-s.y(), s.x()); }
inline real cross2(const Vec2 &a, const Vec2 &b) { return a.x() * b.y() - a.y() * b.x(); }

// sin and cos of each body's angle where they were last evaluated: a stage evaluates the
// applied forces, the rows and the stroke checks at the same q, so each angle's pair is
// computed once (keyed by the angle's value: a pure function remembered, never stale).
// A new angle phi is reached from the pair at the nearest multiple k / 64 rad (remembered
// too: a body turns through such a cell in many stages) by the angle-sum formulas
// (sincos_grid, kernel_trig.hpp): in double about 30 instructions instead of 70, within
// 2.5 ulp (tests/core/test_body_trig.cpp); in float a fraction of its full reduction, within
// 2 ulp (tests/core/test_trig.cpp); still a pure function of phi.
struct TrigCache {
  real phi[kMaxBodies], s[kMaxBodies], c[kMaxBodies];
  real grid_s[kMaxBodies], grid_c[kMaxBodies];  // sin, cos of grid[b] / 64
  int32_t grid[kMaxBodies];                      // INT32_MIN: none
};
void trig_clear(TrigCache &t);  // nothing remembered (NaN keys)
// Inlined always on x86-64 (flash does not count there): GCC's inliner otherwise leaves some
// of a large generated kernel's calls out of line, and which ones moves with the rest of
// the generated file (the robot's RK4 step took 1,440 instructions more when the leg's
// reduced stage solve was added).
#if defined(__x86_64__) && defined(__GNUC__)
__attribute__((always_inline))
#endif
inline void body_trig(TrigCache *t, int b, real phi, real &s, real &c) {
  if (t && t->phi[b] == phi) {
    s = t->s[b];
    c = t->c[b];
    return;
  }
  if (t && std::abs(phi) < real(kGridMaxAngle)) {
    sincos_grid(phi, t->grid[b], t->grid_s[b], t->grid_c[b], s, c);  // kernel_trig.hpp
  } else {
    sincos_reduced(phi, s, c);
  }
  if (t) {
    t->phi[b] = phi;
    t->s[b] = s;
    t->c[b] = c;
  }
}

// body_trig's pair without its memory of the last angle (the grid's pair still): for RK4's
// reduced solves, whose angles are new at every stage (a memory there is read in vain and
// written for nothing). The same values as body_trig's.
#if defined(__x86_64__) && defined(__GNUC__)
__attribute__((always_inline))
#endif
inline void grid_trig(TrigCache *t, int b, real phi, real &s, real &c) {
  if (std::abs(phi) < real(kGridMaxAngle))
    sincos_grid(phi, t->grid[b], t->grid_s[b], t->grid_c[b], s, c);
  else
    sincos_reduced(phi, s, c);
}

}  // namespace legsim
