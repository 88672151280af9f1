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

}  // namespace

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_single_contact_closed_forms);
  RUN_TEST(test_planar_problems_against_enumeration);
  RUN_TEST(test_random_coupled_problems);
  RUN_TEST(test_single_contacts_solved_or_reported);
  RUN_TEST(test_refused_inputs);
  RUN_TEST(test_bounded_on_a_hard_problem);
  return UNITY_END();
}
