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
// - the stuck feet and the held stops decided in one acceleration-level problem (contact_modes):
//   at the modes it returns every stuck foot in its cone, no foot pulling or accelerating into the
//   ground, every stop kept pushing and every stop let go opening.
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

void test_stops_and_feet_in_one_impact(void) {
  // The stand with its six feet on the ground (free), the robot moving down (0.3 m/s), sideways
  // (0 .. 0.25 m/s) and at random (each body's velocity +-0.2, projected onto the joints' rows:
  // every leg's strokes moving), and five strokes on a stop at the end their rate approaches (the
  // impact problem reads the rows' coefficients, not the gaps): one contact problem of the feet's
  // cones and the stops, 24 such. Checked against what holds whatever solved it: the joints' rows
  // still met, no foot approaching the ground and no stroke its stop (the strokes' rates from
  // robot_*_rate, not the impact's rows), every foot's impulse in its cone (mu_k) and opposite its
  // slip, every stop's impulse pushing (>= 0), complementarity for both, the kinetic energy not
  // raised, and the ground's impulses alone changing the robot's momentum and its angular momentum
  // (a stop's impulse is internal).
  const Standing &s = standing();
  const SpatialRobot &R = s.robot;
  const legsim_hexapod_desc &h = s.desc;
  const V3 n = {h.ground_normal[0], h.ground_normal[1], h.ground_normal[2]};
  static double q[kBodyConfig * kMaxRobotBodies], v[kMaxRobotDof], v0[kMaxRobotDof];
  std::memcpy(q, s.q, sizeof q);
  double zmin = 1e9;
  for (int l = 0; l < 6; ++l) zmin = std::fmin(zmin, dot(robot_foot_position(R, l, q), n));
  const V3 gp = {0, 0, zmin};  // (n: the file's level ground)
  const GroundPlane g = {gp, n, h.mu_static, h.mu_kinetic};
  // leg 0's two actuators, leg 2's upper, legs 1 and 4's rowing angles
  const int stop_leg[5] = {0, 0, 2, 1, 4}, stop_k[5] = {0, 1, 0, 2, 2};
  auto d = std::make_unique<RobotData>();
  auto rate = [&](int l, int k, const double *x) {
    return k == 2 ? robot_rowing_rate(R, l, d->q, x) : robot_actuator_rate(R, R.leg[l].first_actuator + k, d->q, x);
  };
  auto momentum = [&](const double *x, V3 &P, V3 &L) {  // and about the origin
    P = L = {0, 0, 0};
    for (int b = 0; b < R.nb; ++b) {
      const double *qb = d->q + kBodyConfig * b, *xb = x + kBodyDof * b;
      const V3 p = R.mass[b] * V3{xb[0], xb[1], xb[2]};
      const V3 &I = R.inertia[b];
      P = P + p;
      L = L + cross({qb[0], qb[1], qb[2]}, p) + rotate(body_state(qb, xb).R, {I.x * xb[3], I.y * xb[4], I.z * xb[5]});
    }
  };
  double worst_T = -1, approach = 0, cone = 0, against = 0, comp = 0, neg = 0, into = 0, scomp = 0, jv = 0, eP = 0,
         eL = 0, residual = 0;
  int mixed = 0, pushing_stops = 0, most_iterations = 0, by_sweeps = 0;
  srand(7);
  for (int trial = 0; trial < 24; ++trial) {
    for (int k = 0; k < kBodyDof * R.nb; ++k) v[k] = 0.4 * (double(rand()) / RAND_MAX - 0.5);
    for (int b = 0; b < R.nb; ++b) v[kBodyDof * b] += 0.05 * (trial % 6), v[kBodyDof * b + 2] -= 0.3;
    FeetHold hold;
    hold.stuck = hold.sliding = 0;
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_init(R, q, v, hold, &g, *d));  // v onto the joints' rows
    uint32_t touching = 0;
    for (int l = 0; l < 6; ++l)
      touching |= std::fabs(dot(robot_foot_position(R, l, d->q) - gp, n)) < 1e-9 ? 1u << l : 0u;
    TEST_ASSERT_EQUAL_HEX32(0x3F, touching);
    FeetHold &H = d->hold;
    uint32_t arriving = 0;
    double sign[5];  // the gap's rate per the stroke's: -1 at the max end
    for (int i = 0; i < 5; ++i) {
      const uint32_t bit = 1u << (kLegStops * stop_leg[i] + stop_k[i]);
      H.stops |= bit, arriving |= bit;
      sign[i] = rate(stop_leg[i], stop_k[i], d->v) > 0 ? -1 : 1;
      if (sign[i] < 0) H.upper |= bit;
    }
    std::memcpy(v0, d->v, sizeof v0);
    V3 P0, L0, P1, L1;
    momentum(v0, P0, L0);
    V3 imp[kMaxContacts];
    double simp[kMaxHeldStops] = {};
    legsim::ConeReport rep;
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, contact_impact(R, g, touching, arriving, 0, d->q, d->v, H, d->slip_dir, imp, simp, rep,
                                                    d->rows, d->factor, d->contact_work));
    TEST_ASSERT_TRUE(rep.converged);
    residual = std::fmax(residual, rep.residual);
    most_iterations = std::max(most_iterations, rep.iterations);
    by_sweeps += rep.method == legsim::ConeMethod::Sweeps;
    const double T0 = robot_kinetic_energy(R, v0), T1 = robot_kinetic_energy(R, d->v);
    worst_T = std::fmax(worst_T, T1 / T0);
    momentum(d->v, P1, L1);
    FeetHold none;
    none.stuck = none.sliding = 0;
    system_rows(R, none, d->q, d->v, d->rows);
    for (int r = 0; r < R.m; ++r) jv = std::fmax(jv, std::fabs(row_dot(R, d->rows[r], r, d->v)));
    V3 dP = {0, 0, 0}, dL = {0, 0, 0};
    int sliding = 0, stuck = 0;
    for (int l = 0; l < 6; ++l) {
      V3 p, pv;
      foot_motion(R, l, d->q, d->v, p, pv);
      const double rn = dot(imp[l], n), un = dot(pv, n);
      const V3 rt = imp[l] - rn * n, ut = pv - un * n;
      const double art = std::sqrt(dot(rt, rt)), aut = std::sqrt(dot(ut, ut));
      dP = dP + imp[l];
      dL = dL + cross(p, imp[l]);
      approach = std::fmax(approach, -un);
      cone = std::fmax(cone, art - g.mu_kinetic * rn);
      comp = std::fmax(comp, std::fabs(rn * un));
      if (aut > 1e-9 && rn > 1e-12) {  // on the cone's edge, against the slip
        ++sliding;
        against = std::fmax(against, std::fabs(dot(rt, ut) / aut + g.mu_kinetic * rn));
      } else if (rn > 1e-12) {
        ++stuck;
      }
    }
    for (int i = 0; i < 5; ++i) {
      const int b = kLegStops * stop_leg[i] + stop_k[i];
      const double gap_rate = sign[i] * rate(stop_leg[i], stop_k[i], d->v);
      neg = std::fmin(neg, simp[b]);
      into = std::fmax(into, -gap_rate);
      scomp = std::fmax(scomp, std::fabs(simp[b] * gap_rate));
      pushing_stops += simp[b] > 1e-9;
    }
    mixed += stuck > 0 && sliding > 0;
    const V3 e1 = P1 - P0 - dP, e2 = L1 - L0 - dL;
    eP = std::fmax(eP, std::sqrt(dot(e1, e1)));
    eL = std::fmax(eL, std::sqrt(dot(e2, e2)));
  }
  printf("24 impacts of 6 feet and 5 stops: %d by sweeps, at most %d iterations, residual %.1e; kinetic energy "
         "after / before at most %.4f; feet stuck and sliding in one impact %d times; feet approaching at most %.1e "
         "m/s, off the cone %.1e N s, off the slip's opposite %.1e, r_n u_n %.1e; stops pushing %d of 120, least "
         "impulse %.1e, into a stop %.1e, p u %.1e; J v %.1e; momentum less the ground's impulses %.1e N s, "
         "%.1e N m s\n",
         by_sweeps, most_iterations, residual, worst_T, mixed, approach, cone, against, comp, pushing_stops, neg, into,
         scomp, jv, eP, eL);
  TEST_ASSERT_TRUE(worst_T < 1);
  TEST_ASSERT_TRUE(mixed >= 1 && pushing_stops >= 24);
  TEST_ASSERT_TRUE(approach < 1e-9 && cone < 1e-9 && against < 1e-9 && comp < 1e-9);
  TEST_ASSERT_TRUE(neg >= 0 && into < 1e-9 && scomp < 1e-9);
  TEST_ASSERT_TRUE(jv < 1e-12);
  TEST_ASSERT_TRUE(eP < 1e-10 && eL < 1e-10);
}

void test_stops_and_feet_decided_in_one_problem(void) {
  // The stand at rest with its six feet stuck on the ground and the five strokes of
  // test_stops_and_feet_in_one_impact held on a stop (the acceleration-level problem reads the
  // stops' rows, not their gaps), under random actuator forces (+-400 N) and rowing torques
  // (+-20 N m): contact_modes decides the feet and the stops in one problem, 40 such. Checked with
  // the modes it returns, by the robot's solve at them (not the problem's own numbers): every
  // stuck foot's force in its mu_s cone, every sliding foot's normal force >= 0, every free foot's
  // point not accelerating into the ground; every stop it keeps pushing (its multiplier <= 0:
  // the stop's sign), every stop it lets go opening (its gap's acceleration >= 0).
  const Standing &s = standing();
  const SpatialRobot &R = s.robot;
  const legsim_hexapod_desc &h = s.desc;
  const V3 n = {h.ground_normal[0], h.ground_normal[1], h.ground_normal[2]};
  double zmin = 1e9;
  for (int l = 0; l < 6; ++l) zmin = std::fmin(zmin, dot(robot_foot_position(R, l, s.q), n));
  const GroundPlane g = {{0, 0, zmin}, n, h.mu_static, h.mu_kinetic};
  const int stop_leg[5] = {0, 0, 2, 1, 4}, stop_k[5] = {0, 1, 0, 2, 2};
  auto d = std::make_unique<RobotData>();
  static double v[kMaxRobotDof] = {};
  double cone = 0, pull = 0, into = 0, stop_pull = 0, closing = 0;
  int kept = 0, freed = 0, changed_feet = 0, trials_mixed = 0, modes[3] = {};  // stuck, sliding, free
  srand(11);
  for (int trial = 0; trial < 40; ++trial) {
    FeetHold hold;
    hold.stuck = 0x3F, hold.sliding = 0;
    for (int l = 0; l < 6; ++l) hold.anchor[l] = robot_foot_position(R, l, s.q);
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_init(R, s.q, v, hold, &g, *d));
    FeetHold &H = d->hold;
    H.stuck = 0x3F, H.sliding = 0;
    for (int l = 0; l < 6; ++l) H.anchor[l] = robot_foot_position(R, l, d->q);
    for (int i = 0; i < 5; ++i) {
      const uint32_t bit = 1u << (kLegStops * stop_leg[i] + stop_k[i]);
      H.stops |= bit;
      if (trial % 2) H.upper |= bit;
    }
    double F[kMaxRobotActuators], T[kMaxLegs], Q[kMaxRobotDof];
    for (int a = 0; a < R.na; ++a) F[a] = 800.0 * (double(rand()) / RAND_MAX - 0.5);
    for (int l = 0; l < R.nlegs; ++l) T[l] = 40.0 * (double(rand()) / RAND_MAX - 0.5);
    robot_forces(R, d->q, d->v, F, T, Q);
    const FeetHold before = H;
    legsim::ConeReport rep;
    const legsim_status st = contact_modes(R, g, d->q, d->v, Q, 0, H, d->slip_dir, rep, d->rows, d->factor,
                                           d->contact_work);
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, st);
    TEST_ASSERT_TRUE(rep.converged);
    changed_feet += H.stuck != before.stuck;
    // the robot's solve at the modes it returned
    double a[kMaxRobotDof], mu[kMaxSystemRows], N[kMaxContacts] = {};
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, contact_accelerations(R, H, g.mu_kinetic, d->slip_dir, d->q, d->v, Q, a, mu, N,
                                                           d->rows, d->factor, d->contact_work));
    for (int l = 0; l < 6; ++l) {
      const double *m = mu + foot_row(R, l);
      ++modes[(H.stuck >> l) & 1u ? 0 : (H.sliding >> l) & 1u ? 1 : 2];
      if ((H.stuck >> l) & 1u) {
        cone = std::fmax(cone, std::hypot(m[1], m[2]) - g.mu_static * -m[0]);
        pull = std::fmax(pull, m[0]);
      } else if ((H.sliding >> l) & 1u) {
        pull = std::fmax(pull, -N[l]);
      } else {
        const int fb = contact_body(R, l);
        const BodyState B = body_state(d->q + kBodyConfig * fb, d->v + kBodyDof * fb);
        const double *ab = a + kBodyDof * fb;
        const V3 &pt = contact_point(R, l);
        const V3 pa = V3{ab[0], ab[1], ab[2]} + rotate(B.R, cross({ab[3], ab[4], ab[5]}, pt)) + point_jet(B, pt).pq;
        into = std::fmax(into, -dot(pa, n));
      }
    }
    bool some_kept = false, some_freed = false;
    for (int i = 0; i < 5; ++i) {
      const int l = stop_leg[i], k = stop_k[i], b = kLegStops * l + k;
      if ((H.stops >> b) & 1u) {
        ++kept, some_kept = true;
        stop_pull = std::fmax(stop_pull, mu[stop_row(R, l, k)]);
      } else {
        ++freed, some_freed = true;
        const Row r = stop_gap_row(R, l, k, (before.upper >> b) & 1u, d->q, d->v);
        closing = std::fmax(closing, -(row_dot(R, r, stop_row(R, l, k), a) - r.gamma));
      }
    }
    trials_mixed += some_kept && some_freed;
  }
  printf("40 decisions of 6 stuck feet and 5 stops: feet's modes changed in %d (then %d stuck, %d sliding, %d "
         "free); stops kept %d, let go %d (both in %d); at the modes returned: stuck feet off the cone %.1e N, pulling %.1e N, free feet into the ground "
         "%.1e m/s^2; kept stops pulling %.1e, let-go stops closing %.1e\n",
         changed_feet, modes[0], modes[1], modes[2], kept, freed, trials_mixed, cone, pull, into, stop_pull, closing);
  TEST_ASSERT_TRUE(kept >= 20 && freed >= 20 && trials_mixed >= 10);
  TEST_ASSERT_TRUE(modes[0] >= 20 && modes[1] >= 20 && modes[2] >= 20);
  TEST_ASSERT_TRUE(cone < 1e-6 && pull < 1e-6 && into < 1e-8);
  TEST_ASSERT_TRUE(stop_pull < 1e-6 && closing < 1e-8);
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_upper_actuator_into_its_min_stroke);
  RUN_TEST(test_rowing_motor_into_its_stroke_end);
  RUN_TEST(test_touchdown_and_stop_in_one_step);
  RUN_TEST(test_stops_and_feet_in_one_impact);
  RUN_TEST(test_stops_and_feet_decided_in_one_problem);
  return UNITY_END();
}
