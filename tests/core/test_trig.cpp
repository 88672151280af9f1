// The float sin and cos of kernel_trig.hpp (every angle of a float build, the Cortex-M4F's)
// against double sin and cos of the same float (glibc's, to well under a float ulp), in ulps
// of the exact value: the full reduction and the per-stage grid path (sincos_grid, which
// body_trig uses below kGridMaxAngle); and sincos_any in double is the library's, bit for bit.
#include <cfloat>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <cstdio>

#include "planar/kernel_trig.hpp"
#include "unity.h"

void setUp(void) {}
void tearDown(void) {}

namespace {

// |got - exact| in units of the last place of exact (as a float; subnormals' fixed ulp)
double ulps(float got, double exact) {
  int e;
  std::frexp(exact, &e);  // |exact| = m 2^e, m in [0.5, 1)
  const double ulp = std::fabs(exact) < FLT_MIN ? std::ldexp(1.0, -149) : std::ldexp(1.0, e - 24);
  return std::fabs(static_cast<double>(got) - exact) / ulp;
}

float float_of_bits(std::uint32_t u) {
  float x;
  std::memcpy(&x, &u, sizeof x);
  return x;
}

struct Worst {
  double sin_ulps = 0, cos_ulps = 0;
  long checked = 0;
  void check(float x) {
    float s, c;
    legsim::sincos_reduced(x, s, c);
    const double es = std::sin(static_cast<double>(x)), ec = std::cos(static_cast<double>(x));
    sin_ulps = std::fmax(sin_ulps, ulps(s, es));
    cos_ulps = std::fmax(cos_ulps, ulps(c, ec));
    ++checked;
  }
};

// The bound the header states (0.763 and 0.776 ulp measured over every float below 4096)
constexpr double kBound = 0.8;

}  // namespace

// every 61st float of |x| < 4096 (the Cody-Waite path), both signs
static void test_float_sincos_within_bound_below_4096(void) {
  Worst w;
  const std::uint32_t end = 0x45800000u;  // 4096.0f
  for (std::uint32_t u = 0; u < end; u += 61) {
    w.check(float_of_bits(u));
    w.check(-float_of_bits(u));
  }
  TEST_ASSERT_TRUE(w.checked > 30000000);
  TEST_ASSERT_TRUE(w.sin_ulps < kBound);
  TEST_ASSERT_TRUE(w.cos_ulps < kBound);
}

// every float within 1000 ulps of each multiple of pi/2 up to 4096, where r = x - k pi/2
// cancels (cos(pi/2) and sin(pi) of the nearest floats are -4.4e-8 and -8.7e-8)
static void test_float_sincos_near_multiples_of_half_pi(void) {
  Worst w;
  for (int k = 1; k * 1.5707963267948966 < 4096; ++k) {
    const float x = static_cast<float>(k * 1.5707963267948966);
    std::uint32_t u;
    std::memcpy(&u, &x, sizeof u);
    for (std::uint32_t v = u - 1000; v <= u + 1000; ++v) {
      w.check(float_of_bits(v));
      w.check(-float_of_bits(v));
    }
  }
  TEST_ASSERT_TRUE(w.sin_ulps < kBound);
  TEST_ASSERT_TRUE(w.cos_ulps < kBound);
  // the stand's straight angles: cos(pi/2) is the float's distance to pi/2
  float s, c;
  legsim::sincos_reduced(static_cast<float>(M_PI_2), s, c);
  TEST_ASSERT_EQUAL_FLOAT(1.0f, s);
  TEST_ASSERT_TRUE(std::fabs(c - std::cos(static_cast<double>(static_cast<float>(M_PI_2)))) < 1e-14);
}

// |x| >= 4096 (the Payne-Hanek path) up to the largest float
static void test_float_sincos_large_arguments(void) {
  Worst w;
  for (std::uint32_t u = 0x45800000u; u < 0x7f800000u; u += 997) {
    w.check(float_of_bits(u));
    w.check(-float_of_bits(u));
  }
  w.check(FLT_MAX);
  w.check(4096.0f);
  TEST_ASSERT_TRUE(w.checked > 1900000);
  TEST_ASSERT_TRUE(w.sin_ulps < kBound);
  TEST_ASSERT_TRUE(w.cos_ulps < kBound);
}

static void test_float_sincos_zero_and_non_finite(void) {
  float s, c;
  legsim::sincos_reduced(-0.0f, s, c);
  TEST_ASSERT_TRUE(s == 0.0f && std::signbit(s));
  TEST_ASSERT_EQUAL_FLOAT(1.0f, c);
  const float bad[] = {NAN, INFINITY, -INFINITY};
  for (float x : bad) {
    legsim::sincos_reduced(x, s, c);
    TEST_ASSERT_TRUE(std::isnan(s) && std::isnan(c));
  }
}

// sincos_grid in float: within 2 ulp where |value| >= 1/16 and 2^-25 absolute below (near
// the zeros, where the rows use these values as lengths' factors), over random angles,
// angles near the cells' edges (k + 1/2) / 64 and near multiples of pi/2, up to
// kGridMaxAngle; the same values whatever the grid remembered (a pure function of phi).
static void test_float_sincos_grid(void) {
  std::uint64_t state = 7;
  const auto uniform = [&state](double lo, double hi) {  // a small LCG: no <random> in Unity tests
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return lo + (hi - lo) * static_cast<double>(state >> 11) * 0x1.0p-53;
  };
  double worst_ulps = 0, worst_abs = 0;
  int32_t grid = INT32_MIN, grid2 = INT32_MIN;
  float gs = 0, gc = 0, gs2 = 0, gc2 = 0;
  for (int i = 0; i < 3000000; ++i) {
    const double range = i % 10 == 0 ? legsim::kGridMaxAngle : 20.0;
    double xd = uniform(-range, range);
    if (i % 3 == 1) xd = std::nearbyint(xd / M_PI_2) * M_PI_2 + uniform(-1e-5, 1e-5);
    if (i % 3 == 2) xd = (std::nearbyint(xd * 64) + 0.5) / 64 + uniform(-1e-6, 1e-6);
    const float x = static_cast<float>(xd);
    if (!(std::fabs(x) < static_cast<float>(legsim::kGridMaxAngle))) continue;
    float s, c;
    legsim::sincos_grid(x, grid, gs, gc, s, c);
    const double ex[2] = {std::sin(static_cast<double>(x)), std::cos(static_cast<double>(x))};
    const float got[2] = {s, c};
    for (int j = 0; j < 2; ++j) {
      if (std::fabs(ex[j]) >= 0.0625)
        worst_ulps = std::fmax(worst_ulps, ulps(got[j], ex[j]));
      else
        worst_abs = std::fmax(worst_abs, std::fabs(static_cast<double>(got[j]) - ex[j]));
    }
    if (i % 7 == 0) {  // from a grid that remembered another cell: the same values
      float s2, c2;
      grid2 = INT32_MIN;
      legsim::sincos_grid(x, grid2, gs2, gc2, s2, c2);
      TEST_ASSERT_TRUE(s2 == s && c2 == c);
    }
  }
  std::printf("sincos_grid (float): %.3f ulp at most where |value| >= 1/16, %.3g absolute below\n", worst_ulps,
              worst_abs);
  TEST_ASSERT_TRUE(worst_ulps <= 2.0);
  TEST_ASSERT_TRUE(worst_abs <= std::ldexp(1.0, -25));
}

// sincos_any (axis_u, normal_n, the ground's slope) in double: std::sin and std::cos
static void test_double_sincos_any_is_the_library(void) {
  const double xs[] = {0.0, 0.3, -1.2, 1.5707963267948966, 3.0, 100.5, 1e6, -7e22};
  for (double x : xs) {
    double s, c;
    legsim::sincos_any(x, s, c);
    TEST_ASSERT_TRUE(s == std::sin(x) && c == std::cos(x));
  }
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_float_sincos_within_bound_below_4096);
  RUN_TEST(test_float_sincos_near_multiples_of_half_pi);
  RUN_TEST(test_float_sincos_large_arguments);
  RUN_TEST(test_float_sincos_zero_and_non_finite);
  RUN_TEST(test_float_sincos_grid);
  RUN_TEST(test_double_sincos_any_is_the_library);
  return UNITY_END();
}
