// sin and cos of a body angle for the per-stage evaluations (body_trig in sim.hpp): in
// double, one reduction and two short polynomials instead of glibc's sincos (about 65
// instead of 130 instructions per pair), within 1.5 ulp of the correctly rounded values
// for |x| < 100 rad (2.4 ulp up to 1e5 rad), so the results agree with the library's to
// round-off. Larger or non-finite angles use std::sin and std::cos. Float builds (the
// Cortex-M4F) have their own reduction and polynomials below, for every angle.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

namespace legsim {

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

// ---- float (the Cortex-M4F build) ---------------------------------------------------------
// The same scheme in float arithmetic, for every angle (no libm trigonometry in a float
// image: newlib's sinf/cosf and their Payne-Hanek tables were 4.2 KB of the M4F's flash).
// Within 0.8 ulp of the exact values (the kernels below: 0.5 ulp of the final
// rounding and up to 0.28 ulp of their own: 0.763 ulp for sin, 0.776 for cos, measured over
// every float in |x| < 4096 against double sin and cos; 0.74 above), tested in
// tests/core/test_trig.cpp. Accuracy near the multiples of pi/2 is what
// matters: a leg standing straight has angles at +-pi/2, where cos is -4.4e-8, and with
// pi/2 in three floats whose products k p_i round, r = x - k pi/2 for the float nearest
// 3 pi/2 comes out 1.3e-7 instead of 1.2e-8; here the products are exact and r is kept as
// a pair rh + rl to about 2^-60 absolute.
namespace trig_detail {

// sin(rh + rl) and cos(rh + rl) for |rh| <= pi/4 (+ a little), |rl| <= ulp(rh): Taylor
// polynomials (their truncation below 0.03 ulp), the first-order terms of rl, and for cos
// the rounding of rh^2 recovered exactly (rh split into two halves of 12 bits, by masking
// so no contraction into fma can spoil the split) and 1 - rh^2/2 rounded once.
inline void sincos_kernel(float rh, float rl, int quadrant, float &s, float &c) {
  const float z = rh * rh;
  unsigned u;
  std::memcpy(&u, &rh, sizeof u);
  u &= 0xfffff000u;
  float hi;
  std::memcpy(&hi, &u, sizeof hi);
  const float lo = rh - hi;
  const float zl = ((hi * hi - z) + 2 * hi * lo) + lo * lo;  // rh^2 = z + zl exactly (to 2^-48)
  const float ps = -1.0f / 6 + z * (1.0f / 120 + z * (-1.0f / 5040 + z * (1.0f / 362880)));
  const float pc = 1.0f / 24 + z * (-1.0f / 720 + z * (1.0f / 40320 + z * (-1.0f / 3628800)));
  const float sr = rh + (rl * (1 - 0.5f * z) + rh * z * ps);  // sin(rh + rl)
  const float hz = 0.5f * z;
  const float w = 1 - hz;  // 1 - hz exactly = w + ((1 - w) - hz) (hz <= 0.31)
  const float cr = w + ((((1 - w) - hz) - 0.5f * zl) + (z * z * pc - rh * rl));  // cos(rh + rl)
  switch (quadrant & 3) {
    case 0: s = sr; c = cr; break;
    case 1: s = cr; c = -sr; break;
    case 2: s = -sr; c = -cr; break;
    default: s = -cr; c = sr; break;
  }
}

// x - k pi/2 as rh + rl for |x| >= 4096 (x finite): Payne-Hanek. |x| = m 2^e with m < 2^24 an
// integer; the bits b_i 2^-i of 2/pi with e - i >= 2 add multiples of 4 to x 2/pi, so 96
// bits from i = e - 1 on give its fraction to 2^-70; the quadrant from its two integer bits.
inline void reduce_large(float x, float &rh, float &rl, int &quadrant) {
  // 2/pi in 32-bit words from bit 1 on, after a zero word (bits i <= 0): from mpmath
  static const std::uint32_t two_over_pi[] = {
      0x00000000u, 0xA2F9836Eu, 0x4E441529u, 0xFC2757D1u, 0xF534DDC0u, 0xDB629599u,
      0x3C439041u, 0xFE5163ABu, 0xDEBBC561u, 0xB7246E3Au, 0x424DD2E0u};
  std::uint32_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  const int e = static_cast<int>((bits >> 23) & 0xffu) - 150;  // 4096 <= |x| -> e >= -11
  const std::uint32_t m = (bits & 0x7fffffu) | 0x800000u;
  const int first = e - 1 + 31;  // bit i = e - 1 (bit i = 1 is the first of word 1)
  const int word = first >> 5, shift = first & 31;
  auto window = [&](int n) {  // 32 bits of the table from bit `shift` of word n on
    const std::uint64_t two = (static_cast<std::uint64_t>(two_over_pi[n]) << 32) | two_over_pi[n + 1];
    return static_cast<std::uint32_t>((two << shift) >> 32);
  };
  // m * (w0 w1 w2) mod 2^96: x 2/pi mod 4 in units of 2^-94
  const std::uint64_t p2 = static_cast<std::uint64_t>(m) * window(word + 2);
  const std::uint64_t p1 = static_cast<std::uint64_t>(m) * window(word + 1) + (p2 >> 32);
  const std::uint32_t top = static_cast<std::uint32_t>(p1 >> 32) + m * window(word);
  // the fraction in [-1/2, 1/2) (units 2^-64) and the nearest quadrant
  const std::int64_t f = static_cast<std::int64_t>(
      ((static_cast<std::uint64_t>(top) << 32) | static_cast<std::uint32_t>(p1)) << 2);
  quadrant = static_cast<int>(top >> 30) + (f < 0 ? 1 : 0);
  std::uint64_t a = f < 0 ? 0 - static_cast<std::uint64_t>(f) : static_cast<std::uint64_t>(f);
  int lz = 0;  // a != 0: no float lies within 2^-64 of a multiple of pi/2 (2^-30 is the closest)
  while (lz < 63 && !(a >> 63)) {
    a <<= 1;
    ++lz;
  }
  // a 2^-(64 + lz) as a pair of floats (the top 24 bits exact, the next 32 rounded)
  const std::uint32_t scale_bits = static_cast<std::uint32_t>(127 - 24 - lz) << 23;
  float scale;  // 2^-(24 + lz)
  std::memcpy(&scale, &scale_bits, sizeof scale);
  const float fh = static_cast<float>(static_cast<std::uint32_t>(a >> 40)) * scale;
  const float fl = static_cast<float>(static_cast<std::uint32_t>(a >> 8)) * 0x1p-32f * scale;
  // times pi/2 = ph + pl, the rounding of fh ph recovered by splitting both into 12-bit halves
  constexpr float ph = 1.57079637050628662109375f, pl = -4.37113900018624283e-8f;
  const float prod = fh * ph;
  std::uint32_t ub;
  std::memcpy(&ub, &fh, sizeof ub);
  ub &= 0xfffff000u;
  float fh1;
  std::memcpy(&fh1, &ub, sizeof fh1);
  const float fh2 = fh - fh1;
  constexpr float ph1 = 1.5703125f, ph2 = ph - 1.5703125f;  // 1.5703125 = 0x1.92p0, 8 bits
  const float err = ((fh1 * ph1 - prod) + (fh1 * ph2 + fh2 * ph1)) + fh2 * ph2;
  const float low = err + (fh * pl + fl * ph);
  rh = prod + low;
  rl = low - (rh - prod);
  if ((f < 0) != ((bits >> 31) != 0)) {  // the fraction's sign, then x's
    rh = -rh;
    rl = -rl;
  }
  if (bits >> 31) quadrant = -quadrant;
}

}  // namespace trig_detail

// Reduction by the nearest multiple k of pi/2 in float: pi/2 = p1 + p2 + p3 + p4 (p1 to p3
// of at most 11 bits, so k p1, k p2, k p3 are exact for |k| < 2^13, and x - k p1 - k p2 is
// exact below 4096), the rest summed with its rounding kept (Fast2Sum, then 2Sum).
inline void sincos_reduced(float x, float &s, float &c) {
  if (!(std::abs(x) < 4096.0f)) {
    if (!(std::abs(x) <= 3.40282347e38f)) {  // NaN or infinite: NaN, as the library's
      s = c = x - x;
      return;
    }
    float rh, rl;
    int quadrant;
    trig_detail::reduce_large(x, rh, rl, quadrant);
    trig_detail::sincos_kernel(rh, rl, quadrant, s, c);
    return;
  }
  if (x == 0) {  // sin(-0) = -0 (the sums below would give +0)
    s = x;
    c = 1;
    return;
  }
  constexpr float shifter = 12582912.0f;  // 1.5 * 2^23: the nearest integer (|x 2/pi| < 2^22)
  const float k = (x * 0.636619772f + shifter) - shifter;
  constexpr float p1 = 1.5703125f, p2 = 4.837512969970703125e-4f, p3 = 7.54953362047672271729e-8f,
                  p4 = 2.56334406825708960e-12f;
  const float t = (x - k * p1) - k * p2;  // exact
  const float q3 = k * p3;                // exact
  const float r3 = t - q3;
  const float e3 = (t - r3) - q3;  // the rounding of r3 (exact: |t| >= |q3| or r3 exact)
  const float tail = e3 - k * p4;
  const float rh = r3 + tail;  // 2Sum: r3 and tail may be of any sizes near k pi/2
  const float bv = rh - r3;
  const float rl = (r3 - (rh - bv)) + (tail - bv);
  trig_detail::sincos_kernel(rh, rl, static_cast<int>(k), s, c);
}

// sin and cos of phi from the pair at the nearest multiple k / 64 rad (grid = k and its
// pair gs, gc: the caller's memory, recomputed here when k changes; a body turns through
// such a cell in many stages) by the angle-sum formulas with d = phi - k / 64 (exact:
// |d| <= 1/128, and k / 64 and phi are multiples of phi's last place) and short Taylor
// polynomials of d (truncation below 2e-19 in double, 3e-16 in float). A pure function of
// phi. For |phi| < kGridMaxAngle only (the shifter's range).
constexpr double kGridMaxAngle = 1e4;
template <typename T>
#if defined(__x86_64__) && defined(__GNUC__)
__attribute__((always_inline))  // as body_trig (sim.hpp), its caller: GCC's inliner otherwise
#endif                          // leaves it out of line in some kernels as the file grows
inline void sincos_grid(T phi, int32_t &grid, T &gs, T &gc, T &s, T &c) {
  constexpr bool single = sizeof(T) == sizeof(float);
  // 1.5 * 2^52 (1.5 * 2^23 in float): adding and subtracting it rounds to the nearest integer
  constexpr T shifter = single ? T(12582912.0f) : T(6755399441055744.0);
  const T k = (phi * 64 + shifter) - shifter;
  const int32_t ki = static_cast<int32_t>(k);
  if (grid != ki) {
    sincos_reduced(k * (T(1) / 64), gs, gc);
    grid = ki;
  }
  const T d = phi - k * (T(1) / 64), z = d * d;
  T sd, cm;  // sin d and cos d - 1: in float two terms each reach its precision
  if constexpr (single) {
    sd = d + d * z * (T(-1) / 6 + z * (T(1) / 120));
    cm = -z * (T(0.5) - z * (T(1) / 24));
  } else {
    sd = d + d * z * (T(-1) / 6 + z * (T(1) / 120 - z * (T(1) / 5040)));
    cm = -z * (T(0.5) - z * (T(1) / 24 - z * (T(1) / 720)));
  }
  const T gsv = gs, gcv = gc;  // once: s and c may alias them for all the compiler knows
  s = gsv + (gsv * cm + gcv * sd);
  c = gcv + (gcv * cm - gsv * sd);
}

// sin and cos of one angle outside the per-stage cache (axis_u and normal_n, the ground's
// slope): the library's in double (the results as before), the reduction above in float.
inline void sincos_any(double x, double &s, double &c) {
  s = std::sin(x);
  c = std::cos(x);
}
inline void sincos_any(float x, float &s, float &c) { sincos_reduced(x, s, c); }

}  // namespace legsim
