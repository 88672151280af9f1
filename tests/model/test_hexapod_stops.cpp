// The hexapod's stroke stops (spatial/motion: a linear actuator's length or a rowing angle
// reaching its stroke's end is an event located inside the step, an inelastic impact on the stop,
// then the stop's row held while it pushes), against the step size's convergence and the energy:
// - a leg of the hexapod on a fixed stand (no gravity), its upper actuator driven by a constant
//   force into its min stroke (its max, 0.80 m, is past the leg's reach, |AB| + |BC| = 0.75 m):
//   the arrival's time converges over h = 4, 2, 1 ms to the time at h = 0.25 ms (RK4: order 4);
//   no length or angle past its stroke after any step (1e-12); the energy (kinetic, gravity's,
//   less the commands' work) falls at the arrival's step by the inelastic impact's loss computed
//   on its own (1/2 the stop row's approach rate squared over J M^-1 J^T) and holds while the
//   stop holds; the force reversed, the stop lets go and the length leaves it;
// - the hexapod in the air, leg 0's rowing motor driven by a torque into its stroke's max (the
//   stop's row on the free box): the same, and the torque reversed takes it to its min stop;
// - both with generalized-alpha too (the same invariants);
// - a touchdown and a stop arrival in one step: both located, no foot under the ground, no length
//   or angle past its stroke, no energy gained.
// Runs from the source tree's root (legsim_add_unity_test's WORKING_DIRECTORY).
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <stdlib.h>
#include <unistd.h>

#include "hexapod_standing.hpp"
#include "legsim/hexapod.h"
#include "spatial/motion.hpp"
#include "spatial/statics.hpp"

void setUp(void) {}
void tearDown(void) {}

namespace {
using namespace legsim::spatial;

double norm(const V3 &a) { return std::sqrt(dot(a, a)); }

// How far the furthest length or angle is past its stroke (m or rad; negative: all inside).
double worst_past(const SpatialRobot &R, const double *q) {
  double w = -1;
  for (int a = 0; a < R.na; ++a) {
    const double L = robot_actuator_length(R, a, q);
    w = std::fmax(w, std::fmax(R.act[a].stroke[0] - L, L - R.act[a].stroke[1]));
  }
  for (int l = 0; l < R.nlegs; ++l) {
    const double p = robot_rowing_angle(R, l, q);
    w = std::fmax(w, std::fmax(R.rowing_stroke[0] - p, p - R.rowing_stroke[1]));
  }
  return w;
}

// Leg 0's stroke k (0: its upper actuator, 2: its rowing angle) at q.
double stroke_of(const SpatialRobot &R, int k, const double *q) {
  return k == 2 ? robot_rowing_angle(R, 0, q) : robot_actuator_length(R, R.leg[0].first_actuator + k, q);
}
double stroke_rate(const SpatialRobot &R, int k, const double *q, const double *v) {
  return k == 2 ? robot_rowing_rate(R, 0, q, v) : robot_actuator_rate(R, R.leg[0].first_actuator + k, q, v);
}
double stroke_max(const SpatialRobot &R, int k) {
  return k == 2 ? R.rowing_stroke[1] : R.act[R.leg[0].first_actuator + k].stroke[1];
}
double stroke_min(const SpatialRobot &R, int k) {
  return k == 2 ? R.rowing_stroke[0] : R.act[R.leg[0].first_actuator + k].stroke[0];
}
uint32_t stop_bit(int k) { return 1u << k; }  // leg 0's

// A robot at rest in the air: the hexapod on its free box, or one of its legs on a fixed stand
// (its hip axis the world's z at the origin), its legs at their stand, every rowing angle 0.
struct Scene {
  SpatialRobot R;
  double q[kBodyConfig * kMaxRobotBodies], v[kMaxRobotDof];
};
const Scene &scene(bool stand) {
  static Scene sc[2];
  static bool built[2] = {false, false};
  Scene &o = sc[stand];
  if (built[stand]) return o;
  const Standing &s = standing();
  if (stand) {
    const legsim_hexapod_desc &h = s.desc;
    YokeDesc yoke;
    yoke.mass_kg = h.yoke_mass_kg;
    for (int i = 0; i < 3; ++i) yoke.com_m[i] = h.yoke_com_m[i], yoke.inertia_kgm2[i] = h.yoke_inertia_kgm2[i];
    yoke.hip_offset_m = h.hip_offset_m, yoke.bar_radius_m = h.bar_radius_m;
    yoke.rowing_max_torque_nm = h.rowing_max_torque_nm;
    yoke.rowing_stroke_rad[0] = h.rowing_stroke_rad[0], yoke.rowing_stroke_rad[1] = h.rowing_stroke_rad[1];
    const legsim_model_desc *legs[1] = {&h.leg[0].leg};
    const HipDesc hip = {{0, 0, 0}, 0};
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_lift(legs, &hip, 1, yoke, nullptr, o.R));
    o.R.gravity = {0, 0, 0};  // the leg moved by its actuator alone
  } else {
    o.R = s.robot;
  }
  static double zero[3 * LEGSIM_MAX_BODIES];
  const double *qs[6], *vs[6];
  const double psi[6] = {0, 0, 0, 0, 0, 0};
  for (int l = 0; l < 6; ++l) qs[l] = s.leg_q, vs[l] = zero;
  const double box_q[7] = {0, 0, 0, 1, 0, 0, 0}, box_v[6] = {0, 0, 0, 0, 0, 0};
  robot_state(o.R, box_q, box_v, qs, vs, psi, psi, o.q, o.v);
  built[stand] = true;
  return o;
}

// The scene in the air (no ground), leg 0's stroke k driven by `push` (N or N m), its other
// actuator by `other` (N), the other commands zero.
std::unique_ptr<RobotData> driven(const Scene &sc, int k, double push, double other) {
  const SpatialRobot &R = sc.R;
  FeetHold hold;
  hold.stuck = hold.sliding = 0;
  auto d = std::make_unique<RobotData>();
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_init(R, sc.q, sc.v, hold, nullptr, *d));
  if (k == 2) {
    d->command.rowing[0] = push;
  } else {
    d->command.actuator[sc.R.leg[0].first_actuator + k] = push;
    // the other actuator a constant force too (the energy's commands' work), keeping it off its stops
    d->command.actuator[sc.R.leg[0].first_actuator + 1 - k] = other;
  }
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_refresh(sc.R, *d));
  return d;
}

// The time of the first arrival on a stop at step h: the step it falls in, then the part of that
// step (from the same start) that first takes it, by bisection.
double first_arrival(const Scene &sc, int k, double push, double other, double h, Integrator integrator) {
  auto d = driven(sc, k, push, other);
  auto c = std::make_unique<RobotData>();
  for (int n = 0; n < int(2.0 / h) && d->stop_impacts == 0; ++n) {
    *c = *d;
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step(sc.R, *d, h, integrator));
  }
  TEST_ASSERT_TRUE(d->stop_impacts > 0);
  if (d->hold.stops != stop_bit(k))
    printf("  first on a stop at t = %.4f s: stops 0x%x upper 0x%x, leg 0's strokes %.6f %.6f %.6f\n", d->t,
           d->hold.stops, d->hold.upper, stroke_of(sc.R, 0, d->q), stroke_of(sc.R, 1, d->q), stroke_of(sc.R, 2, d->q));
  TEST_ASSERT_TRUE_MESSAGE(d->hold.stops == stop_bit(k), "the first stop reached is the driven one");
  double lo = 0, hi = h;
  auto e = std::make_unique<RobotData>();
  for (int it = 0; it < 60 && hi - lo > 1e-15; ++it) {
    const double mid = 0.5 * (lo + hi);
    *e = *c;
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step(sc.R, *e, mid, integrator));
    (e->stop_impacts > 0 ? hi : lo) = mid;
  }
  return c->t + hi;
}

// The inelastic impact's loss on the stop row alone (no other row held but the joints'): 1/2
// rate^2 / (J M^-1 J^T), J M^-1 J^T from the factor (the projection's response to a unit rate).
double impact_loss(const SpatialRobot &R, const RobotData &d, int k, bool upper) {
  static Row rows[kMaxSystemRows];
  static RobotFactor F;
  static double f[kMaxRobotDof], g[kMaxSystemRows], x[kMaxRobotDof], mu[kMaxSystemRows];
  FeetHold h = d.hold;
  h.stops = stop_bit(k), h.upper = upper ? stop_bit(k) : 0;
  system_rows(R, h, d.q, d.v, rows);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_factor(R, h, rows, F));
  // [M J^T; J 0] [x; mu] = [0; g] with g = 1 on the stop's row: mu = -(J M^-1 J^T)^-1 there
  const int r = stop_row(R, 0, k);
  g[r] = 1;
  robot_solve(R, F, f, g, x, mu);
  g[r] = 0;
  const double rate = (upper ? -1 : 1) * stroke_rate(R, k, d.q, d.v);
  return 0.5 * rate * rate * -mu[r];
}

struct Run {
  double arrival_drop, expected_drop, held_drift, worst_past;
  int arrivals;
  bool released, reached_other;
};

// Leg 0's stroke k driven by push into its stop (its max for push > 0, else its min) at h; held for
// 0.1 s; push reversed: released, then driven into its other end's stop (other_end; else 0.2 s
// on). Checked at every step: nothing past its stroke; the energy.
Run drive_hold_release(const Scene &sc, int k, double push, double other, double h, Integrator integrator,
                       bool other_end) {
  const SpatialRobot &R = sc.R;
  auto d = driven(sc, k, push, other);
  auto c = std::make_unique<RobotData>();
  Run r = {0, 0, 0, -1, 0, false, false};
  double E = robot_energy(R, *d), E_held = 0, t_held = -1;
  bool reversed = false;
  int n = 0;
  for (; n < 4000 && !(r.released && !other_end && d->t > t_held + 0.3); ++n) {
    *c = *d;
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step(R, *d, h, integrator));
    r.worst_past = std::fmax(r.worst_past, worst_past(R, d->q));
    const double E1 = robot_energy(R, *d);
    if (d->stop_impacts > r.arrivals) {
      r.arrivals = d->stop_impacts;
      if (r.arrivals == 1) {
        TEST_ASSERT_TRUE(d->hold.stops == stop_bit(k) && d->hold.upper == (push > 0 ? stop_bit(k) : 0u));
        // the loss the impact must take: at the arrival, from the step's start retaken to it
        auto e = std::make_unique<RobotData>(*c);
        double lo = 0, hi = h;
        for (int it = 0; it < 60 && hi - lo > 1e-15; ++it) {
          const double mid = 0.5 * (lo + hi);
          *e = *c;
          TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step(R, *e, mid, integrator));
          (e->stop_impacts > 0 ? hi : lo) = mid;
        }
        *e = *c;
        TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step(R, *e, lo, integrator));
        r.expected_drop = impact_loss(R, *e, k, push > 0);
        r.arrival_drop = E - E1;
        E_held = E1, t_held = d->t;
      }
    }
    if (t_held >= 0 && !reversed && r.arrivals == 1) r.held_drift = std::fmax(r.held_drift, std::fabs(E1 - E_held));
    E = E1;
    if (t_held >= 0 && d->t > t_held + 0.1 - 1e-12 && !reversed) {
      reversed = true;
      // reversed: the stop would pull, so it lets go at the next step's start
      if (k == 2) d->command.rowing[0] = -push;
      else d->command.actuator[R.leg[0].first_actuator + k] = -push;
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_refresh(R, *d));
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step(R, *d, h, integrator));
      r.worst_past = std::fmax(r.worst_past, worst_past(R, d->q));
      r.released = !(d->hold.stops & stop_bit(k)) && (push > 0 ? stroke_rate(R, k, d->q, d->v) < 0 &&
                                                                     stroke_of(R, k, d->q) < stroke_max(R, k)
                                                                 : stroke_rate(R, k, d->q, d->v) > 0 &&
                                                                     stroke_of(R, k, d->q) > stroke_min(R, k));
      E = robot_energy(R, *d);
    }
    if (r.released && (d->hold.stops & stop_bit(k))) {
      const bool at_max = d->hold.upper & stop_bit(k);
      r.reached_other = push > 0 ? !at_max && std::fabs(stroke_of(R, k, d->q) - stroke_min(R, k)) < 1e-12
                               : at_max && std::fabs(stroke_of(R, k, d->q) - stroke_max(R, k)) < 1e-12;
      break;
    }
  }
  return r;
}

// (other_end: the push reversed takes it to its stroke's other end; else it only leaves the stop)
void stop_scene(bool stand, int k, double push, double other, bool other_end, const char *what) {
  const Scene &sc = scene(stand);
  const SpatialRobot &R = sc.R;
  printf("%s: from %.6f toward its %s %.3f\n", what, stroke_of(R, k, sc.q), push > 0 ? "max" : "min",
         push > 0 ? stroke_max(R, k) : stroke_min(R, k));
  // the arrival's time against the step
  const double hs[4] = {4e-3, 2e-3, 1e-3, 2.5e-4};
  double t[4];
  for (int i = 0; i < 4; ++i) t[i] = first_arrival(sc, k, push, other, hs[i], Integrator::Rk4);
  for (int i = 0; i < 3; ++i)
    printf("  arrival at h = %.1e s: t = %.12f s, off h = 0.25 ms's by %.2e s\n", hs[i], t[i], t[i] - t[3]);
  printf("  h = 0.25 ms: t = %.12f s\n", t[3]);
  TEST_ASSERT_TRUE(std::fabs(t[2] - t[3]) < 1e-9);
  TEST_ASSERT_TRUE(std::fabs(t[0] - t[3]) < 1e-6);
  // fourth order: halving h divides the error by about 16 (until round-off)
  TEST_ASSERT_TRUE(std::fabs(t[0] - t[3]) > 8 * std::fabs(t[1] - t[3]) || std::fabs(t[1] - t[3]) < 1e-12);
  for (int g = 0; g < 2; ++g) {
    const Integrator in = g == 0 ? Integrator::Rk4 : Integrator::GeneralizedAlpha;
    const Run r = drive_hold_release(sc, k, push, other, 1e-3, in, other_end);
    printf("  %s, h = 1 ms: energy lost at the arrival %.6e J (the impact's own loss %.6e J), drift while "
           "held %.1e J; furthest past a stroke %.1e; released %s, at its other end's stop %s\n",
           g == 0 ? "RK4" : "generalized-alpha", r.arrival_drop, r.expected_drop, r.held_drift, r.worst_past,
           r.released ? "yes" : "no", r.reached_other ? "yes" : "no");
    TEST_ASSERT_TRUE(r.worst_past <= 1e-12);
    TEST_ASSERT_TRUE(r.expected_drop > 0);
    // the step's energy change is the impact's loss and the integrator's error over the step
    TEST_ASSERT_TRUE(std::fabs(r.arrival_drop - r.expected_drop) < (g == 0 ? 1e-6 : 1e-3) * (1 + r.expected_drop));
    TEST_ASSERT_TRUE(r.held_drift < (g == 0 ? 1e-7 : 1e-4));
    TEST_ASSERT_TRUE(r.released && (r.reached_other || !other_end));
  }
}
}  // namespace

void test_upper_actuator_into_its_min_stroke(void) {
  // (its max, 0.80 m, is past the leg's reach: |AC| <= |AB| + |BC| = 0.25 + 0.50 m)
  stop_scene(true, 0, -200.0, 0.0, false, "a leg on a fixed stand, its upper actuator at -200 N");
}
void test_rowing_motor_into_its_stroke_end(void) {
  stop_scene(false, 2, 2.0, 0.0, true, "the hexapod in the air, leg 0's rowing motor at 2 N m");
}

void test_touchdown_and_stop_in_one_step(void) {
  // The stand 0.5 mm above the ground of the file, held by its statics' forces, leg 1 turning
  // at 0.5 rad/s 0.002 rad from its rowing stroke's max: the stop at about 4 ms, the touchdown at
  // about 10 ms, both in the first step of 20 ms; then 0.2 s at 1 ms.
  const Standing &s = standing();
  const SpatialRobot &R = s.robot;
  static double q[kBodyConfig * kMaxRobotBodies], v[kMaxRobotDof];
  static double zero[3 * LEGSIM_MAX_BODIES];
  const double *qs[6], *vs[6];
  double psi[6] = {0.3, R.rowing_stroke[1] - 0.002, -0.2, 0.0, 0.25, -0.15}, psid[6] = {0, 0.5, 0, 0, 0, 0};
  for (int l = 0; l < 6; ++l) qs[l] = s.leg_q, vs[l] = zero;
  const double box_q[7] = {0, 0, 0, 1, 0, 0, 0}, box_v[6] = {0, 0, 0, 0, 0, 0};
  robot_state(R, box_q, box_v, qs, vs, psi, psid, q, v);
  const double dz = 0.0005 - robot_foot_position(R, 0, q).z;
  for (int b = 0; b < R.nb; ++b) q[kBodyConfig * b + 2] += dz;
  static RobotStatics st;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_statics(R, q, 0x3F, nullptr, st));
  const legsim_hexapod_desc &h = s.desc;
  const GroundPlane g = {{h.ground_point_m[0], h.ground_point_m[1], h.ground_point_m[2]},
                         {h.ground_normal[0], h.ground_normal[1], h.ground_normal[2]}, h.mu_static, h.mu_kinetic};
  FeetHold hold;
  hold.stuck = hold.sliding = 0;
  auto d = std::make_unique<RobotData>();
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_init(R, q, v, hold, &g, *d));
  for (int a = 0; a < R.na; ++a) d->command.actuator[a] = st.actuator_force[a];
  for (int l = 0; l < R.nlegs; ++l) d->command.rowing[l] = st.rowing_torque[l];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_refresh(R, *d));
  double E = robot_energy(R, *d);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step_rk4(R, *d, 0.02));
  const int events = d->events, impacts = d->impacts, stops = d->stop_impacts;
  double rise = robot_energy(R, *d) - E, under = 0, past = worst_past(R, d->q);
  E = robot_energy(R, *d);
  for (int n = 0; n < 200; ++n) {
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step_rk4(R, *d, 1e-3));
    const double E1 = robot_energy(R, *d);
    rise = std::fmax(rise, E1 - E);
    E = E1;
    past = std::fmax(past, worst_past(R, d->q));
    for (int l = 0; l < 6; ++l) under = std::fmax(under, -dot(robot_foot_position(R, l, d->q) - g.point, g.normal));
  }
  int on = 0;
  for (int l = 0; l < 6; ++l) on += (d->hold.stuck | d->hold.sliding) >> l & 1u;
  printf("touchdown and stop in one 20 ms step: %d events (%d impacts, %d stop arrivals); then 0.2 s: feet on "
         "the ground %d, deepest %.1e m, furthest past a stroke %.1e, energy rise at most %.1e J; leg 1's "
         "rowing stop %s\n",
         events, impacts, stops, on, under, past, rise, (d->hold.stops >> 5) & 1u ? "held" : "free");
  TEST_ASSERT_TRUE(impacts >= 1 && stops >= 1 && events >= 2);
  TEST_ASSERT_TRUE(under < 1e-9 && past <= 1e-12 && rise < 1e-6);
  TEST_ASSERT_EQUAL_INT(6, on);
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_upper_actuator_into_its_min_stroke);
  RUN_TEST(test_rowing_motor_into_its_stroke_end);
  RUN_TEST(test_touchdown_and_stop_in_one_step);
  return UNITY_END();
}
