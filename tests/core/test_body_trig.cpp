// body_trig (sim.hpp), the sin and cos of every body angle in the per-stage evaluations: in
// double it turns the pair at the nearest multiple of 1/64 rad by the angle-sum formulas.
// Checked against long double sinl/cosl: within 2.5 ulp where |value| >= 1/16, within 2^-55
// absolute below (near the zeros: the rows use these values as lengths' factors, so the
// absolute error is what matters), the same values whatever the cache has seen (a pure
// function of the angle), and the library's path for huge or non-finite angles.
#include <cmath>
#include <cstdio>
#include <random>

#include "sim.hpp"
#include "unity.h"

void setUp(void) {}
void tearDown(void) {}

namespace {
using legsim::TrigCache;

#if !LEGSIM_USE_FLOAT
struct Worst {
  double ulps = 0, abs_small = 0;
  void check(double x, double got, long double exact) {
    const double err = std::fabs(static_cast<double>(static_cast<long double>(got) - exact));
    if (std::fabs(static_cast<double>(exact)) >= 0.0625) {
      int e;
      std::frexp(static_cast<double>(exact), &e);
      const double u = err / std::ldexp(1.0, e - 53);
      if (u > ulps) ulps = u;
    } else if (err > abs_small) {
      abs_small = err;
    }
    (void)x;
  }
};

// random angles, angles near the multiples of pi/2 and near the cells' edges (k + 1/2) / 64
void test_accuracy(void) {
  TrigCache t;
  legsim::trig_clear(t);
  std::mt19937_64 gen(7);
  std::uniform_real_distribution<double> u(-20, 20);
  Worst w;
  for (int i = 0; i < 300000; ++i) {
    double x = u(gen);
    if (i % 3 == 1) x = std::nearbyint(x / M_PI_2) * M_PI_2 + u(gen) * 1e-9;
    if (i % 3 == 2) x = (std::nearbyint(x * 64) + 0.5) / 64 + u(gen) * 1e-12;
    double s, c;
    legsim::body_trig(&t, i % legsim::kMaxBodies, x, s, c);
    w.check(x, s, sinl(static_cast<long double>(x)));
    w.check(x, c, cosl(static_cast<long double>(x)));
  }
  std::printf("body_trig: %.3f ulp at most where |value| >= 1/16, %.3g absolute below\n", w.ulps, w.abs_small);
  TEST_ASSERT_TRUE(w.ulps <= 2.5);
  TEST_ASSERT_TRUE(w.abs_small <= std::ldexp(1.0, -55));
}

// the value of an angle does not depend on what the cache saw before (nor on the body)
void test_pure_function_of_the_angle(void) {
  std::mt19937_64 gen(11);
  std::uniform_real_distribution<double> u(-7, 7);
  for (int i = 0; i < 1000; ++i) {
    const double x = u(gen), before = u(gen);
    TrigCache fresh, seen;
    legsim::trig_clear(fresh);
    legsim::trig_clear(seen);
    double s0, c0, s1, c1, sx, cx;
    legsim::body_trig(&seen, 1, before, sx, cx);      // another cell first
    legsim::body_trig(&seen, 1, x + 1e-3, sx, cx);    // a neighbour in (maybe) the same cell
    legsim::body_trig(&fresh, 0, x, s0, c0);
    legsim::body_trig(&seen, 1, x, s1, c1);
    TEST_ASSERT_TRUE(s0 == s1 && c0 == c1);
    double s2, c2;
    legsim::body_trig(nullptr, 0, x, s2, c2);  // no cache: the reduction itself, within 2.5 ulp too
    TEST_ASSERT_TRUE(std::fabs(s2 - s0) <= 4 * std::ldexp(1.0, -53) && std::fabs(c2 - c0) <= 4 * std::ldexp(1.0, -53));
  }
}

void test_huge_and_non_finite_angles(void) {
  TrigCache t;
  legsim::trig_clear(t);
  double s, c, rs, rc;
  legsim::body_trig(&t, 0, 3.0e6, s, c);
  legsim::sincos_reduced(3.0e6, rs, rc);
  TEST_ASSERT_TRUE(s == rs && c == rc);
  legsim::body_trig(&t, 0, NAN, s, c);
  TEST_ASSERT_TRUE(std::isnan(s) && std::isnan(c));
  legsim::body_trig(&t, 0, INFINITY, s, c);
  TEST_ASSERT_TRUE(std::isnan(s) && std::isnan(c));
  legsim::body_trig(&t, 0, 0.0, s, c);
  TEST_ASSERT_TRUE(s == 0 && c == 1);
}
#endif
}  // namespace

int main(void) {
  UNITY_BEGIN();
#if !LEGSIM_USE_FLOAT
  RUN_TEST(test_accuracy);
  RUN_TEST(test_pure_function_of_the_angle);
  RUN_TEST(test_huge_and_non_finite_angles);
#endif
  return UNITY_END();
}
