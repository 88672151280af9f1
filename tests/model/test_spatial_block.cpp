// A rigid block on three contact points of its own (a robot of no legs: the box's contact points
// on the feet's contact law, spatial/contact and spatial/motion) sliding on an inclined plane,
// against the closed forms of a particle on the plane with Coulomb friction.
//
// The plane at angle alpha, mu_k = k tan(alpha); phi the angle between the velocity and the fall
// line, v the speed. Along and across the velocity:
//   dv/dt = g sin(alpha) (cos(phi) - k),   v dphi/dt = -g sin(alpha) sin(phi),
// so dv/dphi = v (k - cos(phi)) / sin(phi). With u = tan(phi / 2) and a launch across the fall
// line (phi0 = pi / 2, u0 = 1) at v0:
//   k = 1: v (1 + cos(phi)) = v0 (1 + cos(phi0)), i.e. v = v0 (1 + u^2) / 2 -> v0 / 2;
//          t(u) = v0 / (g sin(alpha)) (1/4 - ln(u) / 2 - u^2 / 4),
//          x(u) = v0^2 / (g sin(alpha)) ((1 - u) / 2 + (1 - u^3) / 6)        (across),
//          y(u) = v0^2 / (g sin(alpha)) (-ln(u) / 4 - (1 - u^4) / 16)          (down the fall line);
//   k > 1: v = v0 u^(k-1) (1 + u^2) / 2: it stops (u -> 0, heading down the fall line) at
//          T = v0 k / (g sin(alpha) (k^2 - 1)), x_s = 2 k v0^2 / (g sin(alpha) (4 k^2 - 1)),
//          y_s = v0^2 / (4 g sin(alpha) (k^2 - 1)), and with tan(alpha) < mu_s stays there;
//          before: t(u) = v0 / (2 g sin(alpha)) ((1 - u^(k-1)) / (k-1) + (1 - u^(k+1)) / (k+1)),
//          x(u) = v0^2 / (2 g sin(alpha)) ((1 - u^(2k-1)) / (2k-1) + (1 - u^(2k+1)) / (2k+1)),
//          y(u) = v0^2 / (4 g sin(alpha)) ((1 - u^(2k-2)) / (2k-2) - (1 - u^(2k+2)) / (2k+2)).
// Launched down the fall line: v(t) = v0 + g sin(alpha) (1 - k) t.
// The block: its centre of mass over its contact triangle's centroid. It translates (the friction
// forces are parallel, mu_k N_i against the common slip, and the normal forces' moment balances
// theirs about the centre of mass: no yaw), its normal forces sum to m g cos(alpha), and the
// friction's work is the energy lost.
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "legsim/hexapod.h"
#include "model_toml.hpp"
#include "spatial/motion.hpp"
#include "unity.h"

void setUp(void) {}
void tearDown(void) {}

namespace {
using namespace legsim::spatial;

constexpr double kG = 9.81, kMass = 2.0, kHalfHeight = 0.05, kRadius = 0.15, kV0 = 1.0;
const double kAlpha = 20.0 * 3.14159265358979323846 / 180;

double norm(const V3 &a) { return std::sqrt(dot(a, a)); }

// The plane's normal, its fall line (down) and the horizontal across it.
const V3 kN = {0, std::sin(kAlpha), std::cos(kAlpha)};
const V3 kDown = {0, std::cos(kAlpha), -std::sin(kAlpha)};
const V3 kAcross = {1, 0, 0};

struct Block {
  SpatialRobot R;
  std::unique_ptr<RobotData> d = std::make_unique<RobotData>();
  V3 r0;  // the centre at t = 0
};

// The block on the plane (mu_k = k tan(alpha)), sliding at kV0 along dir.
void make(Block &b, double k, double mu_s, const V3 &dir) {
  const BoxDesc box = {kMass, {kMass / 12 * (0.09 + 0.01), kMass / 12 * (0.09 + 0.01), kMass / 12 * 0.18}};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_lift_block(box, -kG, b.R));
  const double c30 = std::cos(3.14159265358979323846 / 6);
  const V3 pts[3] = {{0, kRadius, -kHalfHeight},
                     {-kRadius * c30, -kRadius / 2, -kHalfHeight},
                     {kRadius * c30, -kRadius / 2, -kHalfHeight}};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_box_contacts(b.R, pts, 3));
  const GroundPlane g = {{0, 0, 0}, kN, mu_s, k * std::tan(kAlpha)};
  // its base on the plane: turned by -alpha about x, its centre kHalfHeight along the normal
  b.r0 = kHalfHeight * kN;
  const double q[kBodyConfig] = {b.r0.x, b.r0.y, b.r0.z, std::cos(kAlpha / 2), -std::sin(kAlpha / 2), 0, 0};
  const double v[kBodyDof] = {kV0 * dir.x, kV0 * dir.y, kV0 * dir.z, 0, 0, 0};
  FeetHold hold;
  hold.stuck = 0, hold.sliding = 7;
  for (int c = 0; c < 3; ++c) hold.anchor[c] = robot_contact_position(b.R, c, q);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_init(b.R, q, v, hold, &g, *b.d));
}

double energy(const Block &b) { return robot_kinetic_energy(b.R, b.d->v) + robot_gravity_potential(b.R, b.d->q); }

// The friction's power (W): each sliding point's ground force on its velocity.
double friction_power(const Block &b) {
  double P = 0;
  for (int c = 0; c < 3; ++c) {
    if (!((b.d->hold.sliding >> c) & 1u)) continue;
    V3 p, pv;
    foot_motion(b.R, c, b.d->q, b.d->v, p, pv);
    P += dot(robot_foot_force(b.R, *b.d, c), pv);
  }
  return P;
}

// The closed form across the fall line at time t (k >= 1): its place (across, down) and speed;
// u from t(u) = t by bisection (t(u) falls with u).
struct Closed {
  double x, y, v;
};
Closed closed_form(double k, double t) {
  const double s = kG * std::sin(kAlpha), T0 = kV0 / s, L0 = kV0 * kV0 / s;
  auto time = [&](double u) {
    if (k == 1) return T0 * (0.25 - 0.5 * std::log(u) - 0.25 * u * u);
    return T0 / 2 * ((1 - std::pow(u, k - 1)) / (k - 1) + (1 - std::pow(u, k + 1)) / (k + 1));
  };
  double lo = 0, hi = 1;  // time(hi) <= t < time(lo)
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (time(mid) > t ? lo : hi) = mid;
  }
  const double u = 0.5 * (lo + hi);
  if (k == 1)
    return {L0 * ((1 - u) / 2 + (1 - u * u * u) / 6), L0 * (-0.25 * std::log(u) - (1 - std::pow(u, 4)) / 16),
            kV0 * (1 + u * u) / 2};
  return {L0 / 2 * ((1 - std::pow(u, 2 * k - 1)) / (2 * k - 1) + (1 - std::pow(u, 2 * k + 1)) / (2 * k + 1)),
          L0 / 4 * ((1 - std::pow(u, 2 * k - 2)) / (2 * k - 2) - (1 - std::pow(u, 2 * k + 2)) / (2 * k + 2)),
          kV0 * std::pow(u, k - 1) * (1 + u * u) / 2};
}

// One run of n steps of h: the largest distance from the closed form's place (m) and speed
// (m/s), the friction's work against the energy lost (J: Simpson's rule on the step ends' power),
// the largest |sum N - m g cos(alpha)| (N), the largest angular speed (rad/s).
struct Run {
  double place, speed, work, normal, spin;
};
Run run_across(double k, double mu_s, double h, int n, Integrator integrator = Integrator::Rk4) {
  Block b;
  make(b, k, mu_s, kAcross);
  const double E0 = energy(b);
  double P[3] = {friction_power(b), 0, 0}, work = 0;
  Run r = {0, 0, 0, 0, 0};
  for (int i = 1; i <= n; ++i) {
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step(b.R, *b.d, h, integrator));
    const RobotData &d = *b.d;
    TEST_ASSERT_EQUAL_UINT32(7, d.hold.sliding);
    const Closed c = closed_form(k, d.t);
    const V3 dr = V3{d.q[0], d.q[1], d.q[2]} - b.r0;
    r.place = std::fmax(r.place, std::hypot(dot(dr, kAcross) - c.x, dot(dr, kDown) - c.y));
    r.place = std::fmax(r.place, std::abs(dot(dr, kN)));
    r.speed = std::fmax(r.speed, std::abs(std::sqrt(d.v[0] * d.v[0] + d.v[1] * d.v[1] + d.v[2] * d.v[2]) - c.v));
    double N = 0;
    for (int c3 = 0; c3 < 3; ++c3) {
      N += d.normal_force[c3];
      // on its kinetic cone, against the slip
      V3 p, pv;
      foot_motion(b.R, c3, d.q, d.v, p, pv);
      const V3 f = robot_foot_force(b.R, d, c3), ft = f - dot(f, kN) * kN, vt = pv - dot(pv, kN) * kN;
      TEST_ASSERT_DOUBLE_WITHIN(1e-12, k * std::tan(kAlpha) * d.normal_force[c3], norm(ft));
      TEST_ASSERT_DOUBLE_WITHIN(1e-9, -1, dot(ft, vt) / (norm(ft) * norm(vt)));
    }
    r.normal = std::fmax(r.normal, std::abs(N - kMass * kG * std::cos(kAlpha)));
    r.spin = std::fmax(r.spin, std::sqrt(d.v[3] * d.v[3] + d.v[4] * d.v[4] + d.v[5] * d.v[5]));
    P[i % 2 ? 1 : 2] = friction_power(b);
    if (i % 2 == 0) {  // Simpson over the last two steps
      work += h / 3 * (P[0] + 4 * P[1] + P[2]);
      P[0] = P[2];
      r.work = std::fmax(r.work, std::abs(E0 + work - energy(b)));
    }
  }
  return r;
}
}  // namespace

// mu_k = tan(alpha): the path curves down the slope, the speed falls to v0 / 2 along the closed
// form, at RK4's order.
void test_block_across_the_fall_line_mu_tan_alpha(void) {
  const double hs[4] = {0.02, 0.01, 0.005, 0.0025};
  Run r[4];
  for (int i = 0; i < 4; ++i) {
    r[i] = run_across(1, 0.6, hs[i], int(std::lround(1.0 / hs[i])));
    printf("mu = tan(alpha), h %.4f s, 1 s: place %.3e m, speed %.3e m/s, |work + dE| %.3e J, |sum N - m g cos| %.3e N,"
           " |omega| %.3e rad/s\n",
           hs[i], r[i].place, r[i].speed, r[i].work, r[i].normal, r[i].spin);
  }
  for (int i = 1; i < 4; ++i)
    printf("  order: place %.2f, speed %.2f, work %.2f\n", std::log2(r[i - 1].place / r[i].place),
           std::log2(r[i - 1].speed / r[i].speed), std::log2(r[i - 1].work / r[i].work));
  TEST_ASSERT_TRUE(r[3].place < 1e-9 && r[3].speed < 1e-9);
  TEST_ASSERT_TRUE(r[3].work < 1e-9);
  for (int i = 2; i < 4; ++i) {
    TEST_ASSERT_TRUE(std::log2(r[i - 1].place / r[i].place) > 3.5);
    TEST_ASSERT_TRUE(std::log2(r[i - 1].speed / r[i].speed) > 3.5);
  }
  for (int i = 0; i < 4; ++i) TEST_ASSERT_TRUE(r[i].normal < 1e-11 && r[i].spin < 1e-12);
}

// The same with generalized-alpha: its order 2.
void test_block_across_the_fall_line_galpha(void) {
  const double hs[3] = {0.01, 0.005, 0.0025};
  Run r[3];
  for (int i = 0; i < 3; ++i) {
    r[i] = run_across(1, 0.6, hs[i], int(std::lround(1.0 / hs[i])), Integrator::GeneralizedAlpha);
    printf("generalized-alpha, h %.4f s, 1 s: place %.3e m, speed %.3e m/s, |sum N - m g cos| %.3e N, |omega| %.3e"
           " rad/s\n",
           hs[i], r[i].place, r[i].speed, r[i].normal, r[i].spin);
  }
  for (int i = 1; i < 3; ++i) {
    const double op = std::log2(r[i - 1].place / r[i].place), ov = std::log2(r[i - 1].speed / r[i].speed);
    printf("  order: place %.2f, speed %.2f\n", op, ov);
    TEST_ASSERT_TRUE(op > 1.8 && op < 2.3 && ov > 1.8 && ov < 2.3);
  }
  for (int i = 0; i < 3; ++i) TEST_ASSERT_TRUE(r[i].normal < 1e-11 && r[i].spin < 1e-12);
}

// mu_k = 1.5 tan(alpha): it stops, at the closed form's time and place, and stays (tan(alpha) <
// mu_s).
void test_block_across_the_fall_line_stops(void) {
  const double k = 1.5, mu_s = 0.6, s = kG * std::sin(kAlpha);
  const double T = kV0 * k / (s * (k * k - 1)), xs = 2 * k * kV0 * kV0 / (s * (4 * k * k - 1)),
               ys = kV0 * kV0 / (4 * s * (k * k - 1));
  const double hs[3] = {0.01, 0.005, 0.0025};
  double et[3], ep[3];
  for (int i = 0; i < 3; ++i) {
    const double h = hs[i];
    Block b;
    make(b, k, mu_s, kAcross);
    auto before = std::make_unique<RobotData>();
    // to the step that ends stuck
    int n = 0;
    for (;; ++n) {
      *before = *b.d;
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step_rk4(b.R, *b.d, h));
      if (b.d->hold.stuck) break;
      TEST_ASSERT_EQUAL_UINT32(7, b.d->hold.sliding);
      TEST_ASSERT_TRUE(b.d->t < 2 * T);
    }
    TEST_ASSERT_EQUAL_UINT32(7, b.d->hold.stuck);  // the three together
    // the stop inside that step: the shortest step from its start that ends stuck
    double lo = 0, hi = h;
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (lo + hi);
      *b.d = *before;
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step_rk4(b.R, *b.d, mid));
      (b.d->hold.stuck ? hi : lo) = mid;
    }
    const double t_stop = before->t + hi;
    *b.d = *before;
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step_rk4(b.R, *b.d, h));
    const V3 dr = V3{b.d->q[0], b.d->q[1], b.d->q[2]} - b.r0;
    et[i] = std::abs(t_stop - T);
    ep[i] = std::hypot(dot(dr, kAcross) - xs, dot(dr, kDown) - ys);
    printf("mu_k = 1.5 tan(alpha), h %.4f s: stop at %.12f s (closed form %.12f s, %.2e s), at (%.9f, %.9f) m"
           " (%.9f, %.9f; %.2e m)\n",
           h, t_stop, T, et[i], dot(dr, kAcross), dot(dr, kDown), xs, ys, ep[i]);
    // then stuck: static friction holds it, its forces inside their static cones, summing to the weight's
    const V3 at_stop = dr;
    for (int j = 0; j < int(0.3 / h); ++j) {
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step_rk4(b.R, *b.d, h));
      TEST_ASSERT_EQUAL_UINT32(7, b.d->hold.stuck);
      V3 F = {0, 0, 0}, ft0;
      for (int c = 0; c < 3; ++c) {
        const V3 f = robot_foot_force(b.R, *b.d, c), ft = f - dot(f, kN) * kN;
        TEST_ASSERT_TRUE(norm(ft) < mu_s * dot(f, kN));
        // the least-norm split of the stuck rows' load: even (the block translates on its centroid)
        if (c == 0) ft0 = ft;
        TEST_ASSERT_TRUE(norm(ft - ft0) < 1e-9);
        F = F + f;
      }
      TEST_ASSERT_DOUBLE_WITHIN(1e-9, 0, norm(F - V3{0, 0, kMass * kG}));
    }
    const V3 dr_end = V3{b.d->q[0], b.d->q[1], b.d->q[2]} - b.r0;
    TEST_ASSERT_TRUE(norm(dr_end - at_stop) < 1e-12);
  }
  for (int i = 1; i < 3; ++i)
    printf("  order: time %.2f, place %.2f\n", std::log2(et[i - 1] / et[i]), std::log2(ep[i - 1] / ep[i]));
  TEST_ASSERT_TRUE(et[2] < 1e-7 && ep[2] < 1e-8);
}

// Launched down the fall line (mu_k = tan(alpha) / 2): v = v0 + g sin(alpha) t / 2, straight.
void test_block_down_the_fall_line(void) {
  const double k = 0.5, h = 0.01, a = kG * std::sin(kAlpha) * (1 - k);
  Block b;
  make(b, k, 0.6, kDown);
  double ev = 0, ex = 0;
  for (int i = 0; i < 100; ++i) {
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step_rk4(b.R, *b.d, h));
    const RobotData &d = *b.d;
    const double t = d.t;
    const V3 dr = V3{d.q[0], d.q[1], d.q[2]} - b.r0, v = {d.v[0], d.v[1], d.v[2]};
    ev = std::fmax(ev, norm(v - (kV0 + a * t) * kDown));
    ex = std::fmax(ex, norm(dr - (kV0 * t + a * t * t / 2) * kDown));
  }
  printf("down the fall line, h %.3f s, 1 s: |v - v(t)| %.2e m/s, |r - r(t)| %.2e m\n", h, ev, ex);
  TEST_ASSERT_TRUE(ev < 1e-12 && ex < 1e-12);
}

// Dropped flat from H onto level ground moving at vx: its three points touch down together (one
// impact on their cones: sliding after it, vx - mu_k g t0 left, t0 = sqrt(2 H / g)), then it
// slides at mu_k g to a stop at t0 + (vx - mu_k g t0) / (mu_k g), and stays.
void test_block_dropped_sliding(void) {
  const double H = 0.01, vx = 1.0, mu = 0.5, h = 0.005;
  const BoxDesc box = {kMass, {kMass / 12 * (0.09 + 0.01), kMass / 12 * (0.09 + 0.01), kMass / 12 * 0.18}};
  SpatialRobot R;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_lift_block(box, -kG, R));
  const double c30 = std::cos(3.14159265358979323846 / 6);
  const V3 pts[3] = {{0, kRadius, -kHalfHeight},
                     {-kRadius * c30, -kRadius / 2, -kHalfHeight},
                     {kRadius * c30, -kRadius / 2, -kHalfHeight}};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_box_contacts(R, pts, 3));
  const GroundPlane g = {{0, 0, 0}, {0, 0, 1}, 0.6, mu};
  const double q[kBodyConfig] = {0, 0, kHalfHeight + H, 1, 0, 0, 0}, v[kBodyDof] = {vx, 0, 0, 0, 0, 0};
  FeetHold hold;
  hold.stuck = hold.sliding = 0;
  auto d = std::make_unique<RobotData>();
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_init(R, q, v, hold, &g, *d));
  const double t0 = std::sqrt(2 * H / kG), v1 = vx - mu * kG * t0, T = t0 + v1 / (mu * kG),
               xs = vx * t0 + v1 * v1 / (2 * mu * kG);
  int impacts = 0;
  double t_touch = -1, x_touch = 0, worst = 0;
  for (int i = 0; i < int(0.4 / h); ++i) {
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step_rk4(R, *d, h));
    if (d->impacts > impacts) {
      impacts = d->impacts;
      TEST_ASSERT_EQUAL_UINT32(7, d->hold.sliding);  // all three, one impact
      t_touch = d->t, x_touch = d->q[0];
    }
    if (d->hold.sliding == 7) {  // sliding: x(t) and v(t) of the slide after the impact
      const double s = d->t - t0;
      worst = std::fmax(worst, std::abs(d->q[0] - (vx * t0 + v1 * s - mu * kG * s * s / 2)));
      worst = std::fmax(worst, std::abs(d->v[0] - (v1 - mu * kG * s)));
    }
  }
  printf("dropped %.3f m at %.1f m/s: %d impact (step ending %.4f s, the touchdown at %.6f s), slide |error| %.2e;"
         " at rest at x %.12f m (closed form %.12f m, stop at %.6f s)\n",
         H, vx, impacts, t_touch, t0, worst, d->q[0], xs, T);
  TEST_ASSERT_EQUAL_INT(1, impacts);
  TEST_ASSERT_EQUAL_UINT32(7, d->hold.stuck);
  TEST_ASSERT_TRUE(worst < 1e-12);
  TEST_ASSERT_DOUBLE_WITHIN(1e-12, xs, d->q[0]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-12, kHalfHeight, d->q[2]);
  (void)x_touch;
}

// The same block as a file of no legs (tests/model/fixtures/good_block_incline.toml) through the C
// API: loaded, started stuck on its three points, launched across the fall line at 1 m/s
// (legsim_hexapod_set_velocity: its points slide), stepped, its state against the closed form.
void test_block_through_the_c_api(void) {
  auto h = std::make_unique<legsim_hexapod_desc>();
  char msg[256] = {0};
  TEST_ASSERT_EQUAL_INT_MESSAGE(LEGSIM_OK,
                                legsim_hexapod_load_toml("tests/model/fixtures/good_block_incline.toml", h.get(), msg,
                                                         sizeof msg),
                                msg);
  TEST_ASSERT_EQUAL_INT(0, h->n_legs);
  TEST_ASSERT_EQUAL_INT(3, h->n_box_contacts);
  std::vector<unsigned char> raw(legsim_hexapod_sim_size() + 64);
  void *store = reinterpret_cast<void *>((reinterpret_cast<uintptr_t>(raw.data()) + 63) / 64 * 64);
  legsim_hexapod_pose pose = {};
  const V3 r0 = kHalfHeight * kN;
  pose.box_m[0] = r0.x, pose.box_m[1] = r0.y, pose.box_m[2] = r0.z;
  pose.box_quat[0] = std::cos(kAlpha / 2), pose.box_quat[1] = -std::sin(kAlpha / 2);
  legsim_hexapod_sim *sim = nullptr;
  // the analyses of legs refuse a block; its points are bits 6 + k, as a hexapod's
  legsim_hexapod_standing sd;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_statics(h.get(), &pose, 0, nullptr, store,
                                                                     legsim_hexapod_sim_size(), &sd));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_sim_init(store, legsim_hexapod_sim_size(), h.get(), &pose,
                                                                      7, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_hexapod_sim_init(store, legsim_hexapod_sim_size(), h.get(), &pose,
                                                           7u << LEGSIM_HEXAPOD_LEGS, &sim));
  legsim_hexapod_state x;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_hexapod_get_state(sim, &x));
  double N = 0;
  for (int k = 0; k < 3; ++k) {
    TEST_ASSERT_EQUAL_INT(LEGSIM_CONTACT_STUCK, x.box_contact_state[k]);
    N += dot({x.box_contact_force_n[k][0], x.box_contact_force_n[k][1], x.box_contact_force_n[k][2]}, kN);
  }
  TEST_ASSERT_DOUBLE_WITHIN(1e-10, kMass * kG * std::cos(kAlpha), N);
  const double v0[3] = {kV0, 0, 0}, w0[3] = {0, 0, 0}, bad[3] = {NAN, 0, 0};
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_set_velocity(sim, bad, w0));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_hexapod_set_velocity(sim, v0, w0));
  const double h_s = 0.0025;
  double worst = 0;
  for (int i = 0; i < 400; ++i) {
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_hexapod_step(sim, h_s, 1));
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_hexapod_get_state(sim, &x));
    const Closed c = closed_form(1, x.t_s);
    const V3 dr = V3{x.box_m[0], x.box_m[1], x.box_m[2]} - r0;
    worst = std::fmax(worst, std::hypot(dot(dr, kAcross) - c.x, dot(dr, kDown) - c.y));
    for (int k = 0; k < 3; ++k) TEST_ASSERT_EQUAL_INT(LEGSIM_CONTACT_SLIDING, x.box_contact_state[k]);
  }
  printf("through the C API, h %.4f s, 1 s: place %.2e m\n", h_s, worst);
  TEST_ASSERT_TRUE(worst < 1e-9);
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_set_velocity(sim, v0, w0));  // after a step
}

// Bad input: past the contact points' capacity, a point not finite.
void test_block_bad_input(void) {
  SpatialRobot R;
  const BoxDesc box = {1, {0.1, 0.1, 0.1}};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_lift_block(box, -kG, R));
  V3 pts[kMaxBoxContacts + 1] = {};
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_CAPACITY, robot_box_contacts(R, pts, kMaxBoxContacts + 1));
  pts[1].y = NAN;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, robot_box_contacts(R, pts, 3));
  const BoxDesc bad = {-1, {0.1, 0.1, 0.1}};
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, robot_lift_block(bad, -kG, R));
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_block_across_the_fall_line_mu_tan_alpha);
  RUN_TEST(test_block_across_the_fall_line_galpha);
  RUN_TEST(test_block_across_the_fall_line_stops);
  RUN_TEST(test_block_down_the_fall_line);
  RUN_TEST(test_block_dropped_sliding);
  RUN_TEST(test_block_through_the_c_api);
  RUN_TEST(test_block_bad_input);
  return UNITY_END();
}
