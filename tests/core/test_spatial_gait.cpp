// The tripod gait and the stability margin (firmware_core/src/spatial/gait.hpp) against
// invariants and closed forms:
// - a standing foot holds its place in the world while the box moves at the gait's twist (the
//   box's pose integrated in closed form), straight and turning, to 1e-12 m;
// - a foot's place is continuous at its lift-off and touchdown, and so is its world velocity
//   (zero there: it leaves and lands at rest in the world), by differences; it rises by the step
//   height at the swing's middle;
// - with duty >= 0.5 at least three feet stand at every time, and the two tripods alternate;
// - the margin of an equilateral support triangle about its centre is its inradius, of a point
//   outside minus its distance to the nearest edge; the hexagon of six feet; fewer than three
//   feet or feet on one line give -inf;
// - on a slope (the ground's grade), the box level: a standing foot holds its place in the world
//   in 3D and lies on the plane (1e-12 m), a swinging one rises by the step height over the
//   ground directly below it; the box's planned motion (gait_box) is the closed form's, its rise
//   the grade's along it;
// - gaits outside their ranges are refused.
#include <cmath>
#include <cstdio>
#include <initializer_list>

#include "spatial/gait.hpp"
#include "unity.h"

void setUp(void) {}
void tearDown(void) {}

namespace {
using namespace legsim::spatial;

TripodGait gait(real turn) {
  TripodGait g;
  g.period_s = 1.2;
  g.duty = 0.6;
  g.step_length_m = 0.12;
  g.step_height_m = 0.05;
  g.turn_rad = turn;
  const real x[3] = {0.35, 0.0, -0.35};
  for (int l = 0; l < 6; ++l) g.neutral[l] = {x[l % 3], l < 3 ? real(-0.76) : real(0.76), real(-1.0)};
  return g;
}

// The box's pose at time t (the gait's constant twist from the box at rest at the origin,
// yaw 0, at t = 0): position (x, y) and yaw.
void box_pose(const TripodGait &g, double t, double &x, double &y, double &yaw) {
  const double Ts = g.duty * g.period_s, v = g.step_length_m / Ts, w = g.turn_rad / Ts;
  yaw = w * t;
  if (std::fabs(w) < 1e-15) {
    x = v * t, y = 0;
  } else {
    x = v / w * std::sin(yaw), y = v / w * (1 - std::cos(yaw));
  }
}
void world(const TripodGait &g, double t, const V3 &p, double &X, double &Y) {
  double x, y, yaw;
  box_pose(g, t, x, y, yaw);
  X = x + std::cos(yaw) * p.x - std::sin(yaw) * p.y;
  Y = y + std::sin(yaw) * p.x + std::cos(yaw) * p.y;
}
}  // namespace

void test_standing_feet_hold_and_swings_join(void) {
  for (const real turn : {real(0.0), real(0.3), real(-0.5)}) {
    const TripodGait g = gait(turn);
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, gait_check(g));
    const double dt = 1e-4, T = g.period_s;
    double held[6][2];
    bool was[6] = {false, false, false, false, false, false};
    double worst_hold = 0, worst_jump = 0, worst_land = 0, peak = 0;
    V3 prev[6];
    for (int k = 0; k <= 30000; ++k) {  // 2.5 periods
      const double t = k * dt;
      V3 f[6];
      bool st[6];
      gait_feet(g, t, f, st);
      int standing = 0;
      for (int l = 0; l < 6; ++l) {
        standing += st[l];
        double X, Y;
        world(g, t, f[l], X, Y);
        if (st[l] && was[l]) worst_hold = std::fmax(worst_hold, std::hypot(X - held[l][0], Y - held[l][1]));
        if (st[l] && !was[l]) held[l][0] = X, held[l][1] = Y;
        if (k > 0) {  // the place changes by O(dt) only, across the phase changes too
          worst_jump = std::fmax(worst_jump, std::hypot(std::hypot(f[l].x - prev[l].x, f[l].y - prev[l].y),
                                                         f[l].z - prev[l].z));
          if (st[l] != was[l]) {  // its world velocity at the change: zero
            double X0, Y0;
            world(g, t - dt, prev[l], X0, Y0);
            worst_land = std::fmax(worst_land, std::hypot(X - X0, Y - Y0) / dt);
          }
        }
        if (!st[l]) peak = std::fmax(peak, f[l].z - g.neutral[l].z);
        was[l] = st[l];
        prev[l] = f[l];
      }
      TEST_ASSERT_TRUE(standing >= 3);
      // the tripods alternate: A (0, 2, 4) stand together, B (1, 3, 5) together
      TEST_ASSERT_TRUE(st[0] == st[2] && st[2] == st[4] && st[1] == st[3] && st[3] == st[5]);
      (void)T;
    }
    printf("turn %+.1f: standing feet held to %.2e m; step between samples %.2e m; world speed at a "
           "change %.2e m/s; swing peak %.6f m\n",
           turn, worst_hold, worst_jump, worst_land, peak);
    TEST_ASSERT_TRUE(worst_hold < 1e-12);
    TEST_ASSERT_TRUE(worst_jump < 1e-3);   // 1e-4 s at below 10 m/s
    TEST_ASSERT_TRUE(worst_land < 1e-2);   // O(dt) of a smooth zero
    TEST_ASSERT_TRUE(std::fabs(peak - g.step_height_m) < 1e-6);
  }
}

void test_gait_on_a_slope(void) {
  for (const real turn : {real(0.0), real(0.3)}) {
    TripodGait g = gait(turn);
    g.grade[0] = 0.2, g.grade[1] = -0.15;  // the plane z = 0.2 X - 0.15 Y, the box 1 m over it at t = 0
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, gait_check(g));
    double held[6][3], worst_hold = 0, worst_plane = 0, worst_box = 0, peak = 0;
    bool was[6] = {false, false, false, false, false, false};
    for (int k = 0; k <= 3000; ++k) {  // 2.5 periods
      const double t = k * 1e-3;
      V3 f[6], d;
      bool st[6];
      real yaw;
      gait_feet(g, t, f, st);
      gait_box(g, t, d, yaw);
      double bx, by, byaw;
      box_pose(g, t, bx, by, byaw);
      const double bz = 1.0 + 0.2 * bx - 0.15 * by;  // level, 1 m over the ground below it
      worst_box = std::fmax(worst_box, std::fabs(d.x - bx) + std::fabs(d.y - by) + std::fabs(1.0 + d.z - bz) +
                                           std::fabs(yaw - byaw));
      for (int l = 0; l < 6; ++l) {
        double X, Y;
        world(g, t, f[l], X, Y);
        const double Z = bz + f[l].z, ground = 0.2 * X - 0.15 * Y;
        if (st[l]) {
          worst_plane = std::fmax(worst_plane, std::fabs(Z - ground));
          if (was[l]) worst_hold = std::fmax(worst_hold, std::fabs(X - held[l][0]) + std::fabs(Y - held[l][1]) +
                                                            std::fabs(Z - held[l][2]));
          else held[l][0] = X, held[l][1] = Y, held[l][2] = Z;
        } else {
          TEST_ASSERT_TRUE(Z - ground > -1e-12 && Z - ground < g.step_height_m + 1e-12);
          peak = std::fmax(peak, Z - ground);
        }
        was[l] = st[l];
      }
    }
    printf("slope (grade 0.2, -0.15), turn %+.1f: standing feet on the plane to %.1e m, held to %.1e m; "
           "the box's motion off the closed form %.1e; swing peak %.6f m\n",
           turn, worst_plane, worst_hold, worst_box, peak);
    TEST_ASSERT_TRUE(worst_plane < 1e-12 && worst_hold < 1e-12 && worst_box < 1e-12);
    TEST_ASSERT_TRUE(std::fabs(peak - g.step_height_m) < 1e-6);
  }
}

void test_support_margin(void) {
  // an equilateral triangle of side a about the origin: the inradius a / (2 sqrt 3)
  const double a = 0.9, R = a / std::sqrt(3.0);
  V3 tri[3];
  for (int k = 0; k < 3; ++k) {
    const double th = 2 * 3.14159265358979323846 * k / 3 + 0.4;
    tri[k] = {R * std::cos(th), R * std::sin(th), -1};
  }
  TEST_ASSERT_TRUE(std::fabs(support_margin(tri, 3, 0, 0) - a / (2 * std::sqrt(3.0))) < 1e-14);
  // a point beyond an edge's middle by d: -d
  const V3 m = {(tri[0].x + tri[1].x) / 2, (tri[0].y + tri[1].y) / 2, 0};
  const double ex = m.x / std::hypot(m.x, m.y), ey = m.y / std::hypot(m.x, m.y), d = 0.05;
  TEST_ASSERT_TRUE(std::fabs(support_margin(tri, 3, m.x + d * ex, m.y + d * ey) + d) < 1e-14);
  // six feet in a regular hexagon of circumradius r: the apothem r cos(30 deg) (any order)
  const double r = 0.8;
  V3 hex[6];
  const int order[6] = {3, 0, 5, 1, 4, 2};
  for (int k = 0; k < 6; ++k) {
    const double th = 3.14159265358979323846 / 3 * order[k];
    hex[k] = {r * std::cos(th), r * std::sin(th), 0};
  }
  TEST_ASSERT_TRUE(std::fabs(support_margin(hex, 6, 0, 0) - r * std::cos(3.14159265358979323846 / 6)) < 1e-14);
  const V3 line[3] = {{0, 0, 0}, {1, 1, 0}, {2, 2, 0}};
  TEST_ASSERT_TRUE(std::isinf(support_margin(line, 3, 0.5, 0.2)) && support_margin(line, 3, 0.5, 0.2) < 0);
  TEST_ASSERT_TRUE(std::isinf(support_margin(tri, 2, 0, 0)));
  // the gait's tripod about the box's centre at mid-stance: positive
  const TripodGait g = gait(0);
  V3 f[6], s3[3];
  bool st[6];
  gait_feet(g, 0.25 * g.period_s, f, st);
  int n = 0;
  for (int l = 0; l < 6; ++l)
    if (st[l]) s3[n++] = f[l];
  TEST_ASSERT_EQUAL_INT(3, n);
  printf("the gait's tripod at a quarter period: margin %.4f m\n", support_margin(s3, 3, 0, 0));
  TEST_ASSERT_TRUE(support_margin(s3, 3, 0, 0) > 0.1);
}

void test_gait_ranges(void) {
  TripodGait g = gait(0);
  g.duty = 0.4;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, gait_check(g));
  g = gait(0);
  g.period_s = 0;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, gait_check(g));
  g = gait(0);
  g.turn_rad = 2;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, gait_check(g));
  g = gait(0);
  g.step_height_m = NAN;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, gait_check(g));
  g = gait(0);
  g.grade[0] = 20;  // steeper than LEGSIM_MAX_SLOPE_RAD
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, gait_check(g));
  g.grade[0] = NAN;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, gait_check(g));
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_standing_feet_hold_and_swings_join);
  RUN_TEST(test_gait_on_a_slope);
  RUN_TEST(test_support_margin);
  RUN_TEST(test_gait_ranges);
  return UNITY_END();
}
