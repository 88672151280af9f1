// sin and cos of a body angle for the per-stage evaluations (body_trig in sim.hpp): in
// double, one reduction and two short polynomials instead of glibc's sincos (about 65
// instead of 130 instructions per pair), within 1.5 ulp of the correctly rounded values
// for |x| < 100 rad (2.4 ulp up to 1e5 rad), so the results agree with the library's to
// round-off. Larger or non-finite angles, and float builds, use std::sin and std::cos (in
// float the same scheme, 1.5 ulp, moved float statics' round-off past the Python tests'
// tolerance: not worth it there without a closer look).
#pragma once

#include <cmath>

namespace legsim {

inline void sincos_reduced(float x, float &s, float &c) {
  s = std::sin(x);
  c = std::cos(x);
}

// Reduction by the nearest multiple k of pi/2 (pi/2 = p1 + p2 + p3, p1 and p2 of 33 bits,
// so k p1 and k p2 are exact for |k| < 2^20), Taylor polynomials on |r| <= pi/4 (their
// truncation below 1e-19), the quadrant from k mod 4.
inline void sincos_reduced(double x, double &s, double &c) {
  if (!(std::abs(x) < 1e5)) {
    s = std::sin(x);
    c = std::cos(x);
    return;
  }
  // the nearest integer by the double's own rounding (|x 2/pi| < 2^51)
  constexpr double shifter = 6755399441055744.0;  // 1.5 * 2^52
  const double k = (x * 0.636619772367581343075535053490057448 + shifter) - shifter;
  const double r = ((x - k * 1.57079632673412561417e+00) - k * 6.07710050630396597660e-11) -
                   k * 2.02226624879595063154e-21;
  const double z = r * r;
  const double ps =
      -1.0 / 6 + z * (1.0 / 120 + z * (-1.0 / 5040 + z * (1.0 / 362880 + z * (-1.0 / 39916800 +
      z * (1.0 / 6227020800.0 + z * (-1.0 / 1307674368000.0 + z * (1.0 / 355687428096000.0)))))));
  const double pc =
      1.0 / 24 + z * (-1.0 / 720 + z * (1.0 / 40320 + z * (-1.0 / 3628800 + z * (1.0 / 479001600 +
      z * (-1.0 / 87178291200.0 + z * (1.0 / 20922789888000.0 + z * (-1.0 / 6402373705728000.0)))))));
  const double sr = r + r * z * ps;               // sin r
  const double cr = 1 - (0.5 * z - z * z * pc);  // cos r
  switch (static_cast<long>(k) & 3) {
    case 0: s = sr; c = cr; break;
    case 1: s = cr; c = -sr; break;
    case 2: s = -sr; c = -cr; break;
    default: s = -cr; c = sr; break;
  }
}

}  // namespace legsim
