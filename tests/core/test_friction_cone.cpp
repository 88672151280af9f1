// The frictional contact problem on the circular cone (firmware_core/src/spatial/
// friction_cone.hpp) against references that do not use its method:
// - single contacts with closed-form answers (apart, stuck, sliding on a diagonal W);
// - problems whose second tangent direction is decoupled and unloaded, so that each contact's
//   reaction stays in the plane of its normal and first tangent: there Coulomb's law is
//   piecewise linear, and every combination of modes (apart, stuck, sliding either way) is
//   solved as a linear system and kept when it is consistent (the planar robot's
//   enumeration, here written out again): the solver must find that solution;
// - random coupled problems of 1 to 6 contacts: Coulomb's law checked condition by condition
//   (in the cone, not pulling, no slip where inside the cone, sliding opposite the force on
//   its surface, complementarity), beside the natural map's error;
// - inputs it must refuse, and a problem without the iterations to solve it: a finite
//   result, reported.
#include <cmath>
#include <cstdint>
#include <cstdio>

#include "spatial/friction_cone.hpp"
#include "unity.h"

void setUp(void) {}
void tearDown(void) {}

namespace {
using namespace legsim;
using real = cone_real;
constexpr int M = kConeMaxRows;

uint64_t rng_state = 0x9E3779B97F4A7C15ull;
real uniform(real a, real b) {  // xorshift64*
  rng_state ^= rng_state >> 12;
  rng_state ^= rng_state << 25;
  rng_state ^= rng_state >> 27;
  const uint64_t x = rng_state * 0x2545F4914F6CDD1Dull;
  return a + (b - a) * real(x >> 11) * real(1.0 / 9007199254740992.0);
}

// Coulomb's law at every contact, condition by condition, to tol (scaled by the problem).
void check_coulomb(int n, const real *r, const real *u, const real *mu, real tol) {
  for (int i = 0; i < n; ++i) {
    const real *ri = r + 3 * i, *ui = u + 3 * i;
    const real rt = std::hypot(ri[1], ri[2]), ut = std::hypot(ui[1], ui[2]);
    TEST_ASSERT_TRUE(ri[0] >= -tol);                 // never pulls
    TEST_ASSERT_TRUE(rt <= mu[i] * ri[0] + tol);     // in the cone
    TEST_ASSERT_TRUE(ui[0] >= -tol);                 // never sinks
    TEST_ASSERT_TRUE(std::abs(ri[0] * ui[0]) <= tol * (1 + std::abs(ri[0]) + std::abs(ui[0])));
    if (ut > 10 * tol) {  // sliding: on the surface, opposite the slip
      TEST_ASSERT_TRUE(std::abs(rt - mu[i] * ri[0]) <= 10 * tol * (1 + ri[0]));
      if (rt > 10 * tol) {
        const real cosine = (ri[1] * ui[1] + ri[2] * ui[2]) / (rt * ut);
        TEST_ASSERT_TRUE(cosine <= -1 + 1e-6);
      }
    }
  }
}

void solve_and_check(int n, const real *W, const real *q, const real *mu, real *r, real *u, ConeReport &rep) {
  for (int k = 0; k < 3 * n; ++k) r[k] = 0;
  const legsim_status s = cone_solve(n, W, q, mu, r, u, rep);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, s);
  TEST_ASSERT_TRUE(rep.converged);
  real qn = 0;
  for (int k = 0; k < 3 * n; ++k) qn += q[k] * q[k];
  const real scale = 1 + std::sqrt(qn);
  TEST_ASSERT_TRUE(cone_error(n, r, u, mu) <= 1e-10 * scale);
  check_coulomb(n, r, u, mu, 1e-8 * scale);
}

void test_single_contact_closed_forms(void) {
  real r[3], u[3];
  ConeReport rep;
  const real W[9] = {2, 0, 0, 0, 1, 0, 0, 0, 4};
  const real mu[1] = {real(0.5)};
  // stuck: r = -W^-1 q = (0.5, -0.1, 0.025), |r_t| = 0.103 < 0.25
  const real q_stuck[3] = {-1, real(0.1), real(-0.1)};
  solve_and_check(1, W, q_stuck, mu, r, u, rep);
  TEST_ASSERT_DOUBLE_WITHIN(1e-12, 0.5, r[0]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-12, -0.1, r[1]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-12, 0.025, r[2]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-12, 0, u[1]);
  // apart: q_n > 0, r = 0
  const real q_apart[3] = {real(0.3), 5, -2};
  solve_and_check(1, W, q_apart, mu, r, u, rep);
  for (int k = 0; k < 3; ++k) TEST_ASSERT_DOUBLE_WITHIN(1e-12, 0, r[k]);
  // sliding on W = diag(2, 1, 1): r_n = 0.5, the slip along q_t's direction (the diagonal
  // tangent block keeps it there), r_t = -mu r_n q_t / |q_t|, u_t = q_t (1 - mu r_n / |q_t|)
  const real Wi[9] = {2, 0, 0, 0, 1, 0, 0, 0, 1};
  const real q_slide[3] = {-1, 3, 4};  // |q_t| = 5
  solve_and_check(1, Wi, q_slide, mu, r, u, rep);
  TEST_ASSERT_DOUBLE_WITHIN(1e-12, 0.5, r[0]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-12, -0.25 * 3 / 5, r[1]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-12, -0.25 * 4 / 5, r[2]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-12, 3 * (1 - 0.25 / 5), u[1]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-12, 4 * (1 - 0.25 / 5), u[2]);
  // frictionless: the tangential force 0 whatever the slip; apart without a slip at once
  const real mu0[1] = {0};
  const real q_leave[3] = {1, 0, 0};
  solve_and_check(1, Wi, q_leave, mu0, r, u, rep);
  for (int k = 0; k < 3; ++k) TEST_ASSERT_EQUAL_DOUBLE(0, r[k]);
  TEST_ASSERT_EQUAL_INT(0, rep.iterations);
  solve_and_check(1, Wi, q_slide, mu0, r, u, rep);
  TEST_ASSERT_DOUBLE_WITHIN(1e-12, 0.5, r[0]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-12, 0, r[1]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-12, 0, r[2]);
}

// The planar reference: unknowns per contact (r_n, r_t) with u = A r + b on the 2n in-plane
// rows; modes 0 apart (r = 0, u_n >= 0), 1 stuck (u = 0, |r_t| <= mu r_n), 2 sliding +
// (u_n = 0, r_t = -mu r_n, u_t >= 0), 3 sliding - (u_n = 0, r_t = mu r_n, u_t <= 0). Each
// combination is a linear system; the first consistent one is returned.
bool planar_reference(int n, const real *A, const real *b, const real *mu, real *r) {
  const int m = 2 * n;
  int combos = 1;
  for (int i = 0; i < n; ++i) combos *= 4;
  for (int c = 0; c < combos; ++c) {
    int mode[kConeMaxContacts];
    for (int i = 0, x = c; i < n; ++i, x /= 4) mode[i] = x % 4;
    // rows: for each contact two equations in r (2n unknowns)
    real K[M * M], y[M];
    for (int i = 0; i < n; ++i) {
      for (int e = 0; e < 2; ++e) {
        const int row = 2 * i + e;
        for (int j = 0; j < m; ++j) K[row * m + j] = 0;
        y[row] = 0;
        if (mode[i] == 0) {  // r_n = 0, r_t = 0
          K[row * m + row] = 1;
        } else if (mode[i] == 1) {  // u = 0
          for (int j = 0; j < m; ++j) K[row * m + j] = A[row * m + j];
          y[row] = -b[row];
        } else if (e == 0) {  // u_n = 0
          for (int j = 0; j < m; ++j) K[row * m + j] = A[row * m + j];
          y[row] = -b[row];
        } else {  // r_t = -+ mu r_n
          K[row * m + row] = 1;
          K[row * m + row - 1] = mode[i] == 2 ? mu[i] : -mu[i];
        }
      }
    }
    // Gaussian elimination with partial pivoting
    bool ok = true;
    for (int col = 0; col < m && ok; ++col) {
      int p = col;
      for (int i = col + 1; i < m; ++i)
        if (std::abs(K[i * m + col]) > std::abs(K[p * m + col])) p = i;
      if (std::abs(K[p * m + col]) < 1e-12) {
        ok = false;
        break;
      }
      for (int j = 0; j < m; ++j) {
        const real t = K[col * m + j];
        K[col * m + j] = K[p * m + j];
        K[p * m + j] = t;
      }
      const real t = y[col];
      y[col] = y[p];
      y[p] = t;
      for (int i = col + 1; i < m; ++i) {
        const real f = K[i * m + col] / K[col * m + col];
        for (int j = col; j < m; ++j) K[i * m + j] -= f * K[col * m + j];
        y[i] -= f * y[col];
      }
    }
    if (!ok) continue;
    for (int i = m - 1; i >= 0; --i) {
      real s = y[i];
      for (int j = i + 1; j < m; ++j) s -= K[i * m + j] * y[j];
      y[i] = s / K[i * m + i];
    }
    bool consistent = true;
    for (int i = 0; i < n && consistent; ++i) {
      real u[2];
      for (int e = 0; e < 2; ++e) {
        u[e] = b[2 * i + e];
        for (int j = 0; j < m; ++j) u[e] += A[(2 * i + e) * m + j] * y[j];
      }
      const real rn = y[2 * i], rt = y[2 * i + 1], eps = 1e-10;
      if (mode[i] == 0) consistent = u[0] >= -eps;
      if (mode[i] == 1) consistent = rn >= -eps && std::abs(rt) <= mu[i] * rn + eps;
      if (mode[i] == 2) consistent = rn >= -eps && u[1] >= -eps;
      if (mode[i] == 3) consistent = rn >= -eps && u[1] <= eps;
    }
    if (!consistent) continue;
    for (int k = 0; k < m; ++k) r[k] = y[k];
    return true;
  }
  return false;
}

// W = G G^T + d I (symmetric positive definite), row-major 3n x 3n.
void random_delassus(int n, real *W, real coupling) {
  const int m = 3 * n;
  real G[M * M];
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) G[i * m + j] = (i == j ? real(1) : coupling * uniform(-1, 1));
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      real s = i == j ? real(0.05) : real(0);
      for (int k = 0; k < m; ++k) s += G[i * m + k] * G[j * m + k];
      W[i * m + j] = s;
    }
}

void test_planar_problems_against_enumeration(void) {
  int checked = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const int n = 1 + trial % 3;
    const int m = 3 * n;
    real W[M * M], q[M], mu[kConeMaxContacts], r[M], u[M];
    random_delassus(n, W, real(0.6));
    // decouple each contact's second tangent (row and column 3i + 2) and leave it unloaded
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < m; ++j)
        if (j != 3 * i + 2) W[(3 * i + 2) * m + j] = W[j * m + 3 * i + 2] = 0;
    for (int k = 0; k < m; ++k) q[k] = k % 3 == 2 ? real(0) : uniform(-2, 2);
    for (int i = 0; i < n; ++i) q[3 * i] = uniform(-2, real(0.5));  // mostly pressed
    for (int i = 0; i < n; ++i) mu[i] = uniform(0, real(1.5));
    ConeReport rep;
    solve_and_check(n, W, q, mu, r, u, rep);
    real A[M * M], b[M], ref[M];
    for (int i = 0; i < n; ++i)
      for (int e = 0; e < 2; ++e) {
        b[2 * i + e] = q[3 * i + e];
        for (int j = 0; j < n; ++j)
          for (int f = 0; f < 2; ++f) A[(2 * i + e) * (2 * n) + 2 * j + f] = W[(3 * i + e) * m + 3 * j + f];
      }
    if (!planar_reference(n, A, b, mu, ref)) continue;  // (none consistent: not a reference)
    ++checked;
    for (int i = 0; i < n; ++i) {
      TEST_ASSERT_DOUBLE_WITHIN(1e-8 * (1 + std::abs(ref[2 * i])), ref[2 * i], r[3 * i]);
      TEST_ASSERT_DOUBLE_WITHIN(1e-8 * (1 + std::abs(ref[2 * i])), ref[2 * i + 1], r[3 * i + 1]);
      TEST_ASSERT_DOUBLE_WITHIN(1e-10, 0, r[3 * i + 2]);
    }
  }
  printf("planar problems against the enumeration: %d of 300\n", checked);
  TEST_ASSERT_TRUE(checked >= 250);
}

void test_random_coupled_problems(void) {
  int sweeps = 0, iterations = 0, worst = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const int n = 1 + trial % kConeMaxContacts;
    const int m = 3 * n;
    real W[M * M], q[M], mu[kConeMaxContacts], r[M], u[M];
    random_delassus(n, W, real(0.5));
    for (int k = 0; k < m; ++k) q[k] = uniform(-3, 3);
    for (int i = 0; i < n; ++i) q[3 * i] = uniform(-3, 1);
    for (int i = 0; i < n; ++i) mu[i] = uniform(0, real(1.5));
    ConeReport rep;
    solve_and_check(n, W, q, mu, r, u, rep);
    sweeps += rep.method == ConeMethod::Sweeps;
    iterations += rep.iterations;
    worst = rep.iterations > worst ? rep.iterations : worst;
  }
  printf("2000 coupled problems of 1..6 contacts: %.2f iterations on average, at most %d; %d by sweeps\n",
         iterations / 2000.0, worst, sweeps);
}

// Whether one contact's problem (w r + b) has a solution, by a scan that is not the
// solver's: apart, stuck, or sliding along e(t) for t on a fine grid, a sign change of
// e x u_t with the slip along +e and r_n > 0 next to it.
bool single_contact_solvable(const real *w, const real *b, real mu) {
  if (b[0] >= 0) return true;
  const real det = w[0] * (w[4] * w[8] - w[5] * w[7]) - w[1] * (w[3] * w[8] - w[5] * w[6]) +
                   w[2] * (w[3] * w[7] - w[4] * w[6]);
  // stuck: Cramer's rule
  real x[3];
  for (int c = 0; c < 3; ++c) {
    real a[9];
    for (int k = 0; k < 9; ++k) a[k] = k % 3 == c ? -b[k / 3] : w[k];
    x[c] = (a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) +
            a[2] * (a[3] * a[7] - a[4] * a[6])) / det;
  }
  if (x[0] >= 0 && std::hypot(x[1], x[2]) <= mu * x[0]) return true;
  const int grid = 100000;
  real g_prev = 0;
  bool have = false;
  for (int k = 0; k <= grid; ++k) {
    const real t = 6.283185307179586 * k / grid, c = std::cos(t), s = std::sin(t);
    const real d[3] = {1, -mu * c, -mu * s};
    const real wn = w[0] * d[0] + w[1] * d[1] + w[2] * d[2];
    if (!(wn > 0)) {
      have = false;
      continue;
    }
    const real rn = -b[0] / wn;
    const real u1 = b[1] + rn * (w[3] * d[0] + w[4] * d[1] + w[5] * d[2]);
    const real u2 = b[2] + rn * (w[6] * d[0] + w[7] * d[1] + w[8] * d[2]);
    const real g = c * u2 - s * u1;
    if (have && (g <= 0) != (g_prev <= 0) && c * u1 + s * u2 >= 0) return true;
    g_prev = g;
    have = true;
  }
  return false;
}

// One contact, strong coupling, friction up to 10 (where Coulomb's problem need not have a
// solution: existence is known for small friction): a result Coulomb's law holds for, or a
// report of none that the scan confirms.
void test_single_contacts_solved_or_reported(void) {
  int unsolvable = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    real W[9], q[3], mu[1], r[3] = {0, 0, 0}, u[3];
    random_delassus(1, W, real(0.8));
    for (int k = 0; k < 3; ++k) q[k] = uniform(-3, 3);
    mu[0] = uniform(0, real(10));
    ConeReport rep;
    const legsim_status s = cone_solve(1, W, q, mu, r, u, rep);
    for (int k = 0; k < 3; ++k) TEST_ASSERT_TRUE(std::isfinite(r[k]) && std::isfinite(u[k]));
    if (s == LEGSIM_OK) {
      check_coulomb(1, r, u, mu, 1e-8 * (1 + std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2])));
    } else {
      TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_NOT_CONVERGED, s);
      TEST_ASSERT_FALSE(rep.converged);
      TEST_ASSERT_FALSE(single_contact_solvable(W, q, mu[0]));
      ++unsolvable;
    }
  }
  printf("3000 single contacts, friction up to 10: %d without a solution, reported\n", unsolvable);
}

void test_refused_inputs(void) {
  real W[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, q[3] = {-1, 0, 0}, mu[1] = {real(0.5)}, r[3] = {7, 8, 9}, u[3];
  ConeReport rep;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, cone_solve(0, W, q, mu, r, u, rep));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, cone_solve(kConeMaxContacts + 1, W, q, mu, r, u, rep));
  q[1] = NAN;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, cone_solve(1, W, q, mu, r, u, rep));
  q[1] = 0;
  mu[0] = -1;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, cone_solve(1, W, q, mu, r, u, rep));
  mu[0] = real(0.5);
  W[4] = 0;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, cone_solve(1, W, q, mu, r, u, rep));
  TEST_ASSERT_EQUAL_DOUBLE(7, r[0]);  // untouched
}

// Two contacts whose W is all but singular (rank one plus 1e-12, the second tangents apart):
// solved, Coulomb's law holding; and the same problem without the iterations to solve it: a
// finite result (the start), reported as not converged with its residual.
void test_bounded_on_a_hard_problem(void) {
  real W[36], q[6] = {-1, 2, 0, -1, -2, 0}, mu[2] = {real(8), real(8)}, r[6] = {0}, u[6];
  const real g[6] = {1, 1, 0, 1, -1, 0};
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) W[i * 6 + j] = g[i] * g[j] + (i == j ? real(1e-12) : real(0));
  for (int i = 0; i < 6; ++i) W[i * 6 + i] += i % 3 == 2 ? real(1) : real(0);
  ConeReport rep;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, cone_solve(2, W, q, mu, r, u, rep));
  check_coulomb(2, r, u, mu, 1e-8 * 4);
  ConeOptions none;
  none.max_newton = 0;
  none.max_sweeps = 0;
  for (int k = 0; k < 6; ++k) r[k] = 0;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_NOT_CONVERGED, cone_solve(2, W, q, mu, r, u, rep, none));
  TEST_ASSERT_FALSE(rep.converged);
  TEST_ASSERT_EQUAL_INT(0, rep.iterations);
  for (int k = 0; k < 6; ++k) TEST_ASSERT_EQUAL_DOUBLE(0, r[k]);
  for (int k = 0; k < 6; ++k) TEST_ASSERT_EQUAL_DOUBLE(q[k], u[k]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-12, cone_error(2, r, u, mu) / (1 + std::sqrt(10.0)), rep.residual);
  TEST_ASSERT_TRUE(rep.residual > none.tol);
}

// The last contact problem of the walk across 15 degrees with the box at 0.9 m before its step
// from 1.809 s failed (scenes/hexapod_slope_across.toml at box_height_m = 0.9; captured at
// t = 1.809313568 s): the right middle foot touching down (approaching at 1.2 mm/s) with the
// right front and rear stuck and the left middle and rear sliding at 0.7 mm/s; the
// impact's Delassus matrix (15 x 15, positive definite: eigenvalues 0.165 .. 1.73) and
// velocities before it, mu_kinetic 0.5, exactly as the walk gave them (hex). A solvable problem
// (W positive definite), solved: the step failed elsewhere (docs/design/spatial.md, "The
// contact problems at a failure").
const double kWalkImpactW[225] = {
    0x1.554f4ed3ad339p-2, -0x1.9409487cadd2cp-6, -0x1.d54cdca216fa6p-2, 0x1.4a8e4fd8930e4p-7,
    0x1.5c6d17b635ed6p-8, -0x1.7b70a11af63c4p-9, -0x1.b51cedcc587fep-10, 0x1.e1096d169a7c2p-8,
    -0x1.90af6af0298cdp-12, 0x1.a573318d24a0bp-10, 0x1.dd840b37639e4p-7, -0x1.ae0cf74ff0721p-9,
    0x1.2d6f2eef716e4p-11, 0x1.0db06d7fa576ep-6, 0x1.b68e81f67042cp-9, -0x1.9409487cadd2cp-6,
    0x1.af79a79ce8848p-2, 0x1.781697ae5108cp-4, 0x1.64eb2ae6e06e4p-12, 0x1.c9ac4e2fea7dap-6,
    0x1.84debef943a76p-9, -0x1.095c4d05eb6cfp-8, 0x1.ebd09ed1dd3f2p-6, 0x1.bf043d4d7fd46p-9,
    -0x1.0db6614141144p-14, 0x1.d4142ca3990bap-6, 0x1.892803ed5df3dp-9, 0x1.ea5dc36b4f168p-8,
    0x1.d9bf806501127p-6, -0x1.5a69fee3d6c3p-9, -0x1.d54cdca216fa6p-2, 0x1.781697ae5108cp-4,
    0x1.910d5b0eed665p+0, -0x1.b8b9290227e34p-9, -0x1.dadd703c3afd3p-8, 0x1.4488fc68f80f8p-10,
    0x1.adf0314a9ae27p-15, -0x1.1518197f4d3f7p-7, 0x1.379c76f472de8p-11, 0x1.fdcc304d3ea84p-12,
    -0x1.30c927cc885f6p-7, -0x1.936fdf96dd64ep-10, -0x1.64688b0e16a83p-10, -0x1.6379ea3e0a8efp-7,
    -0x1.21f954b68492ep-10, 0x1.4a8e4fd8930e4p-7, 0x1.64eb2ae6e06e4p-12, -0x1.b8b9290227e34p-9,
    0x1.4bfc003491e24p-2, 0x1.8c41dca366671p-5, -0x1.d661968416dd2p-2, 0x1.738326bd15937p-7,
    0x1.88fa3c8419ec3p-13, -0x1.31f3652ac1c6fp-8, 0x1.b7a51b5a9e8e6p-10, -0x1.759661a9853fp-10,
    -0x1.17298f06a008p-8, 0x1.c39b29a3f34dap-10, -0x1.405887e91e1d1p-12, -0x1.2d71f76d69237p-8,
    0x1.5c6d17b635ed6p-8, 0x1.c9ac4e2fea7dap-6, -0x1.dadd703c3afd3p-8, 0x1.8c41dca366671p-5,
    0x1.bb98b1f5b6e72p-2, -0x1.1399027f3940cp-3, -0x1.3d26f16f575e2p-8, 0x1.ed9cfaacca1cp-6,
    0x1.064baade3445cp-8, -0x1.bac6f4d92e582p-11, 0x1.e68f6707bdcfap-6, 0x1.27edc576e1f64p-10,
    0x1.c07cedfc0f606p-8, 0x1.d0eec5d66645ep-6, -0x1.2bbb1fdf22516p-8, -0x1.7b70a11af63c4p-9,
    0x1.84debef943a76p-9, 0x1.4488fc68f80f8p-10, -0x1.d661968416dd2p-2, -0x1.1399027f3940cp-3,
    0x1.8d19d011d114ep+0, -0x1.f6007f655bc27p-9, 0x1.a4633282b08eep-9, 0x1.67fa3849ecdebp-9,
    0x1.285d31a05474ep-12, 0x1.0424986e413ep-8, -0x1.219f610893c1ap-11, 0x1.2468b20b0eb5ap-10,
    0x1.3c04e3f61b622p-9, -0x1.164d13a232e72p-10, -0x1.b51cedcc587fep-10, -0x1.095c4d05eb6cfp-8,
    0x1.adf0314a9ae27p-15, 0x1.738326bd15937p-7, -0x1.3d26f16f575e2p-8, -0x1.f6007f655bc27p-9,
    0x1.4cba95a9021edp-2, -0x1.198489e459562p-5, -0x1.b29cff058437cp-2, 0x1.b8fa5f84a00c1p-10,
    -0x1.8dbb568cd771cp-7, -0x1.4574ddad546d4p-8, 0x1.b787bf6540de6p-9, -0x1.87d01bbb6193p-7,
    -0x1.74814adfac19cp-7, 0x1.e1096d169a7c2p-8, 0x1.ebd09ed1dd3f2p-6, -0x1.1518197f4d3f7p-7,
    0x1.88fa3c8419ec3p-13, 0x1.ed9cfaacca1cp-6, 0x1.a4633282b08eep-9, -0x1.198489e459562p-5,
    0x1.a8d7e1b08eff4p-2, 0x1.b3c30a78e2538p-4, -0x1.0b6c166815286p-13, 0x1.027b3b8492a6ep-5,
    0x1.bcd91ca2186c4p-9, 0x1.09327aa4b1b87p-7, 0x1.05fd8b8db3a3cp-5, -0x1.4b9a8f6dce802p-9,
    -0x1.90af6af0298cdp-12, 0x1.bf043d4d7fd46p-9, 0x1.379c76f472de8p-11, -0x1.31f3652ac1c6fp-8,
    0x1.064baade3445cp-8, 0x1.67fa3849ecdebp-9, -0x1.b29cff058437cp-2, 0x1.b3c30a78e2538p-4,
    0x1.92b2c471b455p+0, 0x1.4ce09ab4921c4p-13, 0x1.b774c4cfb25d7p-8, 0x1.9ed5730503ap-15,
    0x1.6693d9babb324p-11, 0x1.5ebc3f87366a8p-8, 0x1.0a747aee9eadp-10, 0x1.a573318d24a0bp-10,
    -0x1.0db6614141144p-14, 0x1.fdcc304d3ea84p-12, 0x1.b7a51b5a9e8e6p-10, -0x1.bac6f4d92e582p-11,
    0x1.285d31a05474ep-12, 0x1.b8fa5f84a00c1p-10, -0x1.0b6c166815286p-13, 0x1.4ce09ab4921c4p-13,
    0x1.d5c0cf5423c4dp-2, 0x1.c4c3dc09f448ap-6, -0x1.8a37865bcb5cp-2, 0x1.d391705905ecbp-10,
    -0x1.9ab985cf3bd4dp-13, -0x1.691aacae3f73ep-11, 0x1.dd840b37639e4p-7, 0x1.d4142ca3990bap-6,
    -0x1.30c927cc885f6p-7, -0x1.759661a9853fp-10, 0x1.e68f6707bdcfap-6, 0x1.0424986e413ep-8,
    -0x1.8dbb568cd771cp-7, 0x1.027b3b8492a6ep-5, 0x1.b774c4cfb25d7p-8, 0x1.c4c3dc09f448ap-6,
    0x1.3ae97fbadf447p-2, -0x1.58917511f595bp-4, 0x1.9611f97d439dp-8, 0x1.28d34f1048534p-5,
    -0x1.e6ba1e3af318ep-12, -0x1.ae0cf74ff0721p-9, 0x1.892803ed5df3dp-9, -0x1.936fdf96dd64ep-10,
    -0x1.17298f06a008p-8, 0x1.27edc576e1f64p-10, -0x1.219f610893c1ap-11, -0x1.4574ddad546d4p-8,
    0x1.bcd91ca2186c4p-9, 0x1.9ed5730503ap-15, -0x1.8a37865bcb5cp-2, -0x1.58917511f595bp-4,
    0x1.752b7bdd11b78p+0, -0x1.0d14a63ab8554p-13, 0x1.8362a31589574p-8, 0x1.38e4ccb1d8b11p-7,
    0x1.2d6f2eef716e4p-11, 0x1.ea5dc36b4f168p-8, -0x1.64688b0e16a83p-10, 0x1.c39b29a3f34dap-10,
    0x1.c07cedfc0f606p-8, 0x1.2468b20b0eb5ap-10, 0x1.b787bf6540de6p-9, 0x1.09327aa4b1b87p-7,
    0x1.6693d9babb324p-11, 0x1.d391705905ecbp-10, 0x1.9611f97d439dp-8, -0x1.0d14a63ab8554p-13,
    0x1.dbf142200dd2ep-2, -0x1.88f5470c88082p-5, -0x1.9005117ae8388p-2, 0x1.0db06d7fa576ep-6,
    0x1.d9bf806501127p-6, -0x1.6379ea3e0a8efp-7, -0x1.405887e91e1d1p-12, 0x1.d0eec5d66645ep-6,
    0x1.3c04e3f61b622p-9, -0x1.87d01bbb6193p-7, 0x1.05fd8b8db3a3cp-5, 0x1.5ebc3f87366a8p-8,
    -0x1.9ab985cf3bd4dp-13, 0x1.28d34f1048534p-5, 0x1.8362a31589574p-8, -0x1.88f5470c88082p-5,
    0x1.46f868609ad66p-2, 0x1.483ad330bab4dp-3, 0x1.b68e81f67042cp-9, -0x1.5a69fee3d6c3p-9,
    -0x1.21f954b68492ep-10, -0x1.2d71f76d69237p-8, -0x1.2bbb1fdf22516p-8, -0x1.164d13a232e72p-10,
    -0x1.74814adfac19cp-7, -0x1.4b9a8f6dce802p-9, 0x1.0a747aee9eadp-10, -0x1.691aacae3f73ep-11,
    -0x1.e6ba1e3af318ep-12, 0x1.38e4ccb1d8b11p-7, -0x1.9005117ae8388p-2, 0x1.483ad330bab4dp-3,
    0x1.7203ea0e41d32p+0};
const double kWalkImpactQ[15] = {
    -0x1.1ac8cdf81ad96p-60, 0x1p-57, 0x1.ff1e52361ef7ep-58, -0x1.43673f26c9957p-10,
    0x1.95147808cfbp-11, -0x1.e51551e8d8d66p-13, 0x1.72ea5f5768f5p-62, 0x1.a79394c9e8a0ap-118,
    0x1.8d8bca25c89d8p-64, 0x1.e8p-61, 0x1.08640e3bfd2p-11, -0x1.d8acad5c869afp-12, 0x1.4p-61,
    0x1.2ac7e5ae63fp-11, -0x1.c110419c15175p-12};

void test_walk_touchdown_impact(void) {
  real W[225], q[15], r[15], u[15];
  const real mu[5] = {real(0.5), real(0.5), real(0.5), real(0.5), real(0.5)};
  for (int k = 0; k < 225; ++k) W[k] = real(kWalkImpactW[k]);
  for (int k = 0; k < 15; ++k) q[k] = real(kWalkImpactQ[k]);
  ConeReport rep;
  solve_and_check(5, W, q, mu, r, u, rep);
  TEST_ASSERT_TRUE(rep.iterations <= 10);
  // against the mode's closed form: the touching foot (contact 1) stuck, r_1 = -W_11^-1 q_1
  // (Cramer's rule), inside its cone; the others without an impulse, leaving at
  // q_i + W_i1 r_1 (u_n > 0: slower than 0.1 mm/s, so the walk keeps them on the ground)
  const real *w = W;
  auto at = [&](int i, int j) { return w[15 * (3 + i) + 3 + j]; };
  const real det = at(0, 0) * (at(1, 1) * at(2, 2) - at(1, 2) * at(2, 1)) -
                   at(0, 1) * (at(1, 0) * at(2, 2) - at(1, 2) * at(2, 0)) +
                   at(0, 2) * (at(1, 0) * at(2, 1) - at(1, 1) * at(2, 0));
  real r1[3];
  for (int c = 0; c < 3; ++c) {
    real m[3][3];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m[i][j] = j == c ? -q[3 + i] : at(i, j);
    r1[c] = (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
             m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])) / det;
  }
  TEST_ASSERT_TRUE(std::hypot(r1[1], r1[2]) < real(0.5) * r1[0]);
  for (int k = 0; k < 3; ++k) TEST_ASSERT_DOUBLE_WITHIN(1e-12, r1[k], r[3 + k]);
  for (int i = 0; i < 5; ++i) {
    if (i == 1) continue;
    for (int k = 0; k < 3; ++k) {
      TEST_ASSERT_EQUAL_DOUBLE(0, r[3 * i + k]);
      const real ui = q[3 * i + k] + W[15 * (3 * i + k) + 3] * r1[0] + W[15 * (3 * i + k) + 4] * r1[1] +
                      W[15 * (3 * i + k) + 5] * r1[2];
      TEST_ASSERT_DOUBLE_WITHIN(1e-15, ui, u[3 * i + k]);
    }
    TEST_ASSERT_TRUE(u[3 * i] > 0 && u[3 * i] < real(1e-4));
  }
  printf("the walk's impact: %d iterations, residual %.1e; slips after it (m/s):", rep.iterations, double(rep.residual));
  for (int i = 0; i < 5; ++i) printf(" %.2e", double(std::hypot(u[3 * i + 1], u[3 * i + 2])));
  printf("\n");
}

}  // namespace

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_single_contact_closed_forms);
  RUN_TEST(test_planar_problems_against_enumeration);
  RUN_TEST(test_random_coupled_problems);
  RUN_TEST(test_single_contacts_solved_or_reported);
  RUN_TEST(test_refused_inputs);
  RUN_TEST(test_bounded_on_a_hard_problem);
  RUN_TEST(test_walk_touchdown_impact);
  return UNITY_END();
}
