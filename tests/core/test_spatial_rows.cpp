// The spatial module's bodies and row units (firmware_core/src/spatial/body.hpp, rows.hpp)
// against references that do not use their formulas:
// - quat_exp's rotation against Rodrigues' formula in long double; config_add keeps a
//   quaternion unit over 100,000 updates without normalizing, and undoes itself;
// - dexp_inv: exp(theta + e theta') against exp(theta) exp(e omega), by central differences
//   (both of its branches);
// - every row form's Jacobian against central differences of Phi along q (+) e xi, and its
//   gamma against a fourth-order second difference of Phi along the constant-velocity path
//   q (+) t xi (whose accelerations are zero, so Phi'' = -gamma);
// - the joint kinds: assembled, their rows vanish; the motion each joint allows (a revolute's
//   turn about its axis, a prismatic's slide, a rigid motion of both bodies) is in the
//   Jacobian's null space, and a motion it forbids is not; a loop-closing joint's rows ignore
//   an offset out of its plane.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "spatial/rows.hpp"
#include "unity.h"

void setUp(void) {}
void tearDown(void) {}

namespace {
using namespace legsim::spatial;

uint64_t rng_state = 0x243F6A8885A308D3ull;
real uniform(real a, real b) {  // xorshift64*
  rng_state ^= rng_state >> 12;
  rng_state ^= rng_state << 25;
  rng_state ^= rng_state >> 27;
  const uint64_t x = rng_state * 0x2545F4914F6CDD1Dull;
  return a + (b - a) * real(x >> 11) * real(1.0 / 9007199254740992.0);
}
V3 random_v3(real s) { return {uniform(-s, s), uniform(-s, s), uniform(-s, s)}; }
V3 unit(const V3 &a) { return (1 / std::sqrt(dot(a, a))) * a; }

// A body's configuration (7) and velocity (6).
struct Body {
  real q[kBodyConfig], v[kBodyDof];
};
Body random_body() {
  Body b;
  const V3 r = random_v3(1);
  const Quat p = quat_exp(random_v3(3));
  const real q[kBodyConfig] = {r.x, r.y, r.z, p.w, p.x, p.y, p.z};
  for (int i = 0; i < kBodyConfig; ++i) b.q[i] = q[i];
  for (int i = 0; i < kBodyDof; ++i) b.v[i] = uniform(-2, 2);
  return b;
}
// q (+) t xi of a body (xi: its velocity coordinates)
Body moved(const Body &b, real t) {
  Body o = b;
  real dq[kBodyDof];
  for (int i = 0; i < kBodyDof; ++i) dq[i] = t * b.v[i];
  config_add(b.q, dq, o.q);
  return o;
}
BodyState state(const Body &b) { return body_state(b.q, b.v); }

// A row form on two bodies.
using Form = Row (*)(const Body &a, const Body &b, const V3 *u);
Row form_along(const Body &a, const Body &b, const V3 *u) { return row_along(state(a), u[0], state(b), u[1], u[2]); }
Row form_perpendicular(const Body &a, const Body &b, const V3 *u) {
  return row_perpendicular(state(a), u[0], state(b), u[1]);
}
Row form_along_axis(const Body &a, const Body &b, const V3 *u) {
  return row_along_axis(state(a), u[0], state(b), u[1], u[2]);
}

void check_form(Form f, const char *name) {
  for (int trial = 0; trial < 200; ++trial) {
    const Body a = random_body(), b = random_body();
    const V3 u[3] = {random_v3(0.5), random_v3(0.5), unit(random_v3(1))};
    const Row r = f(a, b, u);
    // the Jacobian along (v_a, v_b): Phi's rate on q (+) t xi
    real jv = 0;
    for (int i = 0; i < kBodyDof; ++i) jv += r.ja[i] * a.v[i] + r.jb[i] * b.v[i];
    const real e = 1e-6;
    const real d1 = (f(moved(a, e), moved(b, e), u).phi - f(moved(a, -e), moved(b, -e), u).phi) / (2 * e);
    TEST_ASSERT_TRUE_MESSAGE(std::abs(jv - d1) <= 1e-8 * (1 + std::abs(jv)), name);
    // gamma: Phi'' = -gamma along the constant-velocity path (fourth-order difference)
    const real h = 1e-3;
    real p[5];
    for (int k = -2; k <= 2; ++k) p[k + 2] = f(moved(a, k * h), moved(b, k * h), u).phi;
    const real d2 = (-p[0] + 16 * p[1] - 30 * p[2] + 16 * p[3] - p[4]) / (12 * h * h);
    TEST_ASSERT_TRUE_MESSAGE(std::abs(-r.gamma - d2) <= 1e-8 * (1 + std::abs(r.gamma)), name);
  }
}

// J v over a joint's rows (n of them) for bodies a, b.
real rows_rate(const Row *r, int n, const Body &a, const Body &b) {
  real worst = 0;
  for (int k = 0; k < n; ++k) {
    real s = 0;
    for (int i = 0; i < kBodyDof; ++i) s += r[k].ja[i] * a.v[i] + r[k].jb[i] * b.v[i];
    worst = std::max(worst, std::abs(s));
  }
  return worst;
}
real rows_phi(const Row *r, int n) {
  real worst = 0;
  for (int k = 0; k < n; ++k) worst = std::max(worst, std::abs(r[k].phi));
  return worst;
}
// Body b's configuration: its rotation p and its centre r.
void set_pose(Body &b, const Quat &p, const V3 &r) {
  const real q[kBodyConfig] = {r.x, r.y, r.z, p.w, p.x, p.y, p.z};
  for (int i = 0; i < kBodyConfig; ++i) b.q[i] = q[i];
}
void set_velocity(Body &b, const V3 &v, const V3 &w) {
  const real x[kBodyDof] = {v.x, v.y, v.z, w.x, w.y, w.z};
  for (int i = 0; i < kBodyDof; ++i) b.v[i] = x[i];
}
// Two unit vectors completing k to a right-handed frame (u, n, k).
void frame_of(const V3 &k, V3 &u, V3 &n) {
  const V3 t = std::abs(k.x) < real(0.9) ? V3{1, 0, 0} : V3{0, 1, 0};
  u = unit(cross(t, k));
  n = cross(k, u);
}
}  // namespace

void test_quat_exp_against_rodrigues(void) {
  for (int trial = 0; trial < 2000; ++trial) {
    const real scale = trial % 4 == 0 ? real(1e-4) : trial % 4 == 1 ? real(2e-3) : real(3);
    const V3 th = random_v3(scale), x = random_v3(1);
    const Rot R = rotation(quat_exp(th));
    const V3 y = rotate(R, x);
    // Rodrigues: x cos t + (k x x) sin t + k (k . x)(1 - cos t), in long double
    const long double t = std::sqrt((long double)th.x * th.x + (long double)th.y * th.y + (long double)th.z * th.z);
    const long double kx = th.x / t, ky = th.y / t, kz = th.z / t, c = std::cos(t), s = std::sin(t);
    const long double kdx = kx * x.x + ky * x.y + kz * x.z;
    const long double ry[3] = {x.x * c + (ky * x.z - kz * x.y) * s + kx * kdx * (1 - c),
                               x.y * c + (kz * x.x - kx * x.z) * s + ky * kdx * (1 - c),
                               x.z * c + (kx * x.y - ky * x.x) * s + kz * kdx * (1 - c)};
    TEST_ASSERT_TRUE(std::abs((long double)y.x - ry[0]) < 2e-15L);
    TEST_ASSERT_TRUE(std::abs((long double)y.y - ry[1]) < 2e-15L);
    TEST_ASSERT_TRUE(std::abs((long double)y.z - ry[2]) < 2e-15L);
  }
}

void test_config_add_stays_unit_and_undoes(void) {
  Body b = random_body();
  const Body start = b;
  real worst = 0;
  for (int step = 0; step < 100000; ++step) {
    real dq[kBodyDof];
    for (int i = 0; i < kBodyDof; ++i) dq[i] = uniform(real(-0.1), real(0.1));
    real out[kBodyConfig];
    config_add(b.q, dq, out);
    // and back: dq then -dq returns to the start (the inverse of exp(dtheta) is exp(-dtheta))
    real neg[kBodyDof], back[kBodyConfig];
    for (int i = 0; i < kBodyDof; ++i) neg[i] = -dq[i];
    config_add(out, neg, back);
    for (int i = 0; i < kBodyConfig; ++i) TEST_ASSERT_TRUE(std::abs(back[i] - b.q[i]) < 1e-14);
    for (int i = 0; i < kBodyConfig; ++i) b.q[i] = out[i];
    const real norm = std::sqrt(b.q[3] * b.q[3] + b.q[4] * b.q[4] + b.q[5] * b.q[5] + b.q[6] * b.q[6]);
    worst = std::max(worst, std::abs(norm - 1));
  }
  TEST_ASSERT_TRUE(worst < 1e-12);
  TEST_ASSERT_TRUE(std::abs(b.q[0] - start.q[0]) > 0);  // it moved
}

void test_dexp_inv_by_differences(void) {
  for (int trial = 0; trial < 1000; ++trial) {
    // both branches (below and above t = 0.01) and up to 3 rad
    const real scale = trial % 3 == 0 ? real(4e-3) : trial % 3 == 1 ? real(0.02) : real(1.7);
    const V3 th = random_v3(scale), w = random_v3(2);
    const V3 thd = dexp_inv(th, w);
    const real e = 1e-5;
    const Quat p = quat_exp(th);
    const Quat a = quat_exp(th + e * thd), b = quat_exp(th - e * thd);
    const Quat c = quat_mul(p, quat_exp(e * w)), d = quat_mul(p, quat_exp(-e * w));
    const real lhs[4] = {a.w - b.w, a.x - b.x, a.y - b.y, a.z - b.z};
    const real rhs[4] = {c.w - d.w, c.x - d.x, c.y - d.y, c.z - d.z};
    for (int i = 0; i < 4; ++i) TEST_ASSERT_TRUE(std::abs(lhs[i] - rhs[i]) / (2 * e) < 1e-9);
  }
}

void test_row_forms_jacobian_and_gamma(void) {
  check_form(form_along, "along");
  check_form(form_perpendicular, "perpendicular");
  check_form(form_along_axis, "along_axis");
}

void test_revolute_holds_and_turns_freely(void) {
  for (int trial = 0; trial < 200; ++trial) {
    Body a = random_body(), b = random_body();
    const V3 sa = random_v3(0.3), sb = random_v3(0.3), ka = unit(random_v3(1));
    V3 ub, nb;
    frame_of(ka, ub, nb);
    // b: a's frame turned by alpha about k_a, its point s_b on a's point s_a
    const Quat pa = {a.q[3], a.q[4], a.q[5], a.q[6]};
    const Quat pb = quat_mul(pa, quat_exp(uniform(-3, 3) * ka));
    const BodyState A = state(a);
    const V3 p = A.r + rotate(A.R, sa);
    set_pose(b, pb, p - rotate(rotation(pb), sb));
    // a at rest, b turning about the joint's axis through the joint's point
    const real rate = uniform(-5, 5);
    const V3 axis = rotate(rotation(pb), ka);
    set_velocity(a, {0, 0, 0}, {0, 0, 0});
    set_velocity(b, rate * cross(axis, state(b).r - p), rate * ka);
    Row r[5];
    revolute_rows(state(a), sa, ka, state(b), sb, ub, nb, r);
    TEST_ASSERT_TRUE(rows_phi(r, 5) < 1e-14);
    TEST_ASSERT_TRUE(rows_rate(r, 5, a, b) < 1e-13);
    // a rigid motion of both: allowed too
    const V3 wb = random_v3(2), va = random_v3(1);
    set_velocity(a, va, wb);
    const V3 ww = rotate(A.R, wb);  // world
    set_velocity(b, va + cross(ww, state(b).r - A.r), rotate_back(rotation(pb), ww));
    revolute_rows(state(a), sa, ka, state(b), sb, ub, nb, r);
    TEST_ASSERT_TRUE(rows_rate(r, 5, a, b) < 1e-13);
    // b turning about an axis across the joint's: forbidden
    set_velocity(a, {0, 0, 0}, {0, 0, 0});
    set_velocity(b, {0, 0, 0}, ub);
    revolute_rows(state(a), sa, ka, state(b), sb, ub, nb, r);
    TEST_ASSERT_TRUE(rows_rate(r, 5, a, b) > 0.1);
  }
}

void test_prismatic_holds_and_slides(void) {
  for (int trial = 0; trial < 200; ++trial) {
    Body a = random_body(), b = random_body();
    const V3 sa = random_v3(0.3), sb = random_v3(0.3), ua = unit(random_v3(1));
    V3 na, ka;
    frame_of(ua, na, ka);  // (na, ka, ua) right-handed: the frame (ua, na, ka) is too
    const Quat pa = {a.q[3], a.q[4], a.q[5], a.q[6]};
    const BodyState A = state(a);
    const real sigma = uniform(-0.5, 0.5);
    set_pose(b, pa, A.r + rotate(A.R, sa + sigma * ua - sb));
    set_velocity(a, {0, 0, 0}, {0, 0, 0});
    set_velocity(b, uniform(-2, 2) * rotate(A.R, ua), {0, 0, 0});
    Row r[5];
    prismatic_rows(state(a), sa, ua, na, ka, state(b), sb, na, ka, r);
    TEST_ASSERT_TRUE(rows_phi(r, 5) < 1e-14);
    TEST_ASSERT_TRUE(rows_rate(r, 5, a, b) < 1e-13);
    // rigid motion of both
    const V3 w = random_v3(2), va = random_v3(1), ww = rotate(A.R, w);
    set_velocity(a, va, w);
    set_velocity(b, va + cross(ww, state(b).r - A.r), w);
    prismatic_rows(state(a), sa, ua, na, ka, state(b), sb, na, ka, r);
    TEST_ASSERT_TRUE(rows_rate(r, 5, a, b) < 1e-13);
    // the rod moving across the axis, or turning about it: forbidden
    set_velocity(a, {0, 0, 0}, {0, 0, 0});
    set_velocity(b, rotate(A.R, na), {0, 0, 0});
    prismatic_rows(state(a), sa, ua, na, ka, state(b), sb, na, ka, r);
    TEST_ASSERT_TRUE(rows_rate(r, 5, a, b) > 0.5);
    set_velocity(b, {0, 0, 0}, ua);
    prismatic_rows(state(a), sa, ua, na, ka, state(b), sb, na, ka, r);
    TEST_ASSERT_TRUE(rows_rate(r, 5, a, b) > 0.5);
  }
}

void test_planar_cut_ignores_the_normal(void) {
  for (int trial = 0; trial < 200; ++trial) {
    Body a = random_body(), b = random_body();
    const V3 sa = random_v3(0.3), sb = random_v3(0.3), kb = unit(random_v3(1));
    V3 ub, nb;
    frame_of(kb, ub, nb);
    const BodyState B = state(b);
    // a's point on b's, but for an offset along b's plane normal
    const real off = uniform(-0.2, 0.2);
    const Quat pa = {a.q[3], a.q[4], a.q[5], a.q[6]};
    set_pose(a, pa, B.r + rotate(B.R, sb + off * kb) - rotate(rotation(pa), sa));
    Row r[2];
    planar_cut_rows(state(a), sa, state(b), sb, ub, nb, r);
    TEST_ASSERT_TRUE(rows_phi(r, 2) < 1e-14);
    // an in-plane offset is seen: Phi = its components along u_b and n_b
    const real du = uniform(-0.2, 0.2), dn = uniform(-0.2, 0.2);
    set_pose(a, pa, B.r + rotate(B.R, sb + off * kb + du * ub + dn * nb) - rotate(rotation(pa), sa));
    planar_cut_rows(state(a), sa, state(b), sb, ub, nb, r);
    TEST_ASSERT_TRUE(std::abs(r[0].phi - du) < 1e-14 && std::abs(r[1].phi - dn) < 1e-14);
  }
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_quat_exp_against_rodrigues);
  RUN_TEST(test_config_add_stays_unit_and_undoes);
  RUN_TEST(test_dexp_inv_by_differences);
  RUN_TEST(test_row_forms_jacobian_and_gamma);
  RUN_TEST(test_revolute_holds_and_turns_freely);
  RUN_TEST(test_prismatic_holds_and_slides);
  RUN_TEST(test_planar_cut_ignores_the_normal);
  return UNITY_END();
}
