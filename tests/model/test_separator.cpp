// The factor of J W J^T with a separator body (Layout::separator: the box of a robot on three
// or more legs, factored as a Schur complement on B = J W J^T less the box's share) against
// a dense reference: J W J^T formed entry by entry from the rows' coefficients (no pairs, no
// envelope, no order) and solved by Gaussian elimination with partial pivoting in long
// double. Also: which layouts get a separator (the box of 4 and 6 legs, none for 2, whose
// order its generated stance kernel shares), the dense fallback when B is singular but J W J^T
// is not, and the power-iteration condition (factor_condition) against the eigenvalues.
// The six-leg capacities (legsim_host_legs6), run from the source tree's root.
#include <cmath>
#include <cstring>

#include "legsim/legsim.h"
#include "model_toml.hpp"
#include "sim.hpp"
#include "unity.h"

// the general path instead of a generated kernel (planar/kernel.hpp)
extern "C" int legsim_kernel_use(legsim_sim *sim, int on);

void setUp(void) {}
void tearDown(void) {}

namespace {
using namespace legsim;

alignas(LEGSIM_STORAGE_ALIGN) unsigned char storage[1024 * 1024];
legsim_model_desc model;  // outlives the sim

// The robot file standing on every foot, servos at their stand lengths, after 20 steps
// (generalized-alpha): a state off the assembly's exact one.
Sim &standing(const char *path) {
  char msg[256] = "";
  TEST_ASSERT_EQUAL_INT_MESSAGE(LEGSIM_OK, legsim_model_load_toml(path, NULL, &model, msg, sizeof msg), msg);
  legsim_options opt = legsim_default_options();
  opt.integrator = LEGSIM_INTEGRATOR_GENERALIZED_ALPHA;
  legsim_sim *sim = nullptr;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage, sizeof storage, &model, &opt, &sim));
  TEST_ASSERT_TRUE(legsim_kernel_use(sim, 0) >= 0);  // the general path
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_on_ground(sim, NULL, 0.0));
  legsim_real len[LEGSIM_MAX_ACTUATORS], rate[LEGSIM_MAX_ACTUATORS];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_actuator_lengths(sim, len, rate));
  for (int a = 0; a < model.n_actuators; ++a) TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_length(sim, a, len[a]));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 20));
  return *reinterpret_cast<Sim *>(sim);
}

int box_index() {
  for (int b = 0; b < model.n_bodies; ++b)
    if (!std::strcmp(model.body[b].name, "box")) return b;
  TEST_FAIL_MESSAGE("no body named box");
  return -1;
}

// A = J W J^T by rows (not positions), dense, long double.
void dense_system(const Layout &lay, const Rows &rows, const real *w, long double (*a)[kMaxRows]) {
  for (int i = 0; i < lay.m; ++i)
    for (int j = 0; j < lay.m; ++j) {
      long double v = 0;
      for (int si = 0; si < 2; ++si)
        for (int sj = 0; sj < 2; ++sj) {
          const int b = lay.body[i][si];
          if (b < 0 || b != lay.body[j][sj]) continue;
          for (int e = 0; e < kBodyDof; ++e)
            v += (long double)rows.coef[i][si][e] * w[kBodyDof * b + e] * rows.coef[j][sj][e];
        }
      a[i][j] = v;
    }
}

// x = A^-1 r by Gaussian elimination with partial pivoting.
void dense_solve(long double (*a)[kMaxRows], int m, const long double *r, long double *x) {
  static long double t[kMaxRows][kMaxRows + 1];
  for (int i = 0; i < m; ++i) {
    for (int j = 0; j < m; ++j) t[i][j] = a[i][j];
    t[i][m] = r[i];
  }
  for (int c = 0; c < m; ++c) {
    int p = c;
    for (int i = c + 1; i < m; ++i)
      if (fabsl(t[i][c]) > fabsl(t[p][c])) p = i;
    for (int j = 0; j <= m; ++j) {
      const long double s = t[c][j];
      t[c][j] = t[p][j], t[p][j] = s;
    }
    for (int i = c + 1; i < m; ++i) {
      const long double f = t[i][c] / t[c][c];
      for (int j = c; j <= m; ++j) t[i][j] -= f * t[c][j];
    }
  }
  for (int i = m - 1; i >= 0; --i) {
    long double s = t[i][m];
    for (int j = i + 1; j < m; ++j) s -= t[i][j] * x[j];
    x[i] = s / t[i][i];
  }
}

// The factor's solve of J W J^T x = r against the dense one, r a fixed pseudo-random vector:
// relative error in the max norm.
real solve_error(const Layout &lay, const Rows &rows, const real *w, const Factor &f) {
  static long double a[kMaxRows][kMaxRows];
  dense_system(lay, rows, w, a);
  long double r[kMaxRows], ref[kMaxRows];
  VecR x;
  for (int i = 0; i < lay.m; ++i) r[i] = std::sin(1.0 + 0.7 * i), x[i] = real(r[i]);
  dense_solve(a, lay.m, r, ref);
  factor_solve(f, x);
  long double err = 0, big = 0;
  for (int i = 0; i < lay.m; ++i) {
    err = fmaxl(err, fabsl(x[i] - ref[i]));
    big = fmaxl(big, fabsl(ref[i]));
  }
  return real(err / big);
}

Factor factor;  // large: not on the stack
Rows rows;

void check_separated(const char *path, int legs) {
  Sim &s = standing(path);
  Data &d = s.data;
  const Layout &lay = d.dyn;
  TEST_ASSERT_NULL(lay.kernel);
  TEST_ASSERT_EQUAL_INT(box_index(), lay.separator);
  TEST_ASSERT_TRUE(lay.m > 12 * legs);  // the stance: joints and every foot's rows
  rows_eval(s.model, lay, d.stop_drivers, d.q, d.qd, rows);
  // M^-1 (dynamics) and the identity (assembly's weight)
  real ones[kMaxCoords];
  for (real &v : ones) v = 1;
  const real *weights[] = {s.model.minv, ones};
  for (const real *w : weights) {
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, factor_build(lay, rows, w, factor));
    TEST_ASSERT_EQUAL_INT(box_index(), factor.separator);
    TEST_ASSERT_TRUE(std::isfinite(factor.condition) && factor.condition >= 1);
    TEST_ASSERT_TRUE(solve_error(lay, rows, w, factor) < 1e-11);
  }
}

}  // namespace

void test_two_legs_have_no_separator(void) {
  Sim &s = standing("models/robot.toml");
  TEST_ASSERT_EQUAL_INT(-1, s.data.dyn.separator);
  TEST_ASSERT_EQUAL_INT(-1, s.data.joints.separator);
}

// The leg: its upper rod splits its rows into three groups too, but only six rows act on it
// (a clique cheaper than the Schur complement): no separator, on the general path either.
void test_leg_has_no_separator(void) {
  char msg[256] = "";
  TEST_ASSERT_EQUAL_INT_MESSAGE(LEGSIM_OK, legsim_model_load_toml("models/leg.toml", NULL, &model, msg, sizeof msg), msg);
  legsim_sim *sim = nullptr;
  legsim_options opt = legsim_default_options();
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage, sizeof storage, &model, &opt, &sim));
  TEST_ASSERT_TRUE(legsim_kernel_use(sim, 0) >= 0);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 5));
  Sim &s = *reinterpret_cast<Sim *>(sim);
  TEST_ASSERT_NULL(s.data.dyn.kernel);
  TEST_ASSERT_EQUAL_INT(16, s.data.dyn.m);
  TEST_ASSERT_EQUAL_INT(-1, s.data.dyn.separator);
  TEST_ASSERT_EQUAL_INT(-1, s.data.joints.separator);
}

void test_four_legs_solve_as_dense(void) { check_separated("models/robot4.toml", 4); }
void test_six_legs_solve_as_dense(void) { check_separated("models/robot6.toml", 6); }

// A row of one leg that touches the box loses its coefficients on the leg's body: that row of
// B is zero (B singular) while J W J^T keeps it through the box. The factor must fall back to
// the whole system and still solve it.
void test_singular_b_falls_back(void) {
  Sim &s = standing("models/robot6.toml");
  Data &d = s.data;
  const Layout &lay = d.dyn;
  rows_eval(s.model, lay, d.stop_drivers, d.q, d.qd, rows);
  int row = -1;
  for (int i = 0; i < lay.m && row < 0; ++i)
    for (int k = 0; k < 2; ++k)
      if (lay.body[i][k] == lay.separator && lay.body[i][1 - k] >= 0) {
        row = i;
        for (int e = 0; e < kBodyDof; ++e) rows.coef[i][1 - k][e] = 0;
        break;
      }
  TEST_ASSERT_TRUE(row >= 0);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, factor_build(lay, rows, s.model.minv, factor));
  TEST_ASSERT_EQUAL_INT(-1, factor.separator);  // the dense fallback
  TEST_ASSERT_TRUE(solve_error(lay, rows, s.model.minv, factor) < 1e-9);
}

// factor_condition (power iterations on the factor, which with a separator multiply and solve
// through the Schur complement) against sqrt(lambda_max / lambda_min) of the dense system.
void test_condition_with_separator(void) {
  Sim &s = standing("models/robot6.toml");
  Data &d = s.data;
  const Layout &lay = d.dyn;
  rows_eval(s.model, lay, d.stop_drivers, d.q, d.qd, rows);
  real ones[kMaxCoords];
  for (real &v : ones) v = 1;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, factor_build(lay, rows, ones, factor));
  TEST_ASSERT_EQUAL_INT(lay.separator, factor.separator);
  // lambda_max by power iteration and lambda_min by inverse iteration on the dense system,
  // run to convergence
  static long double a[kMaxRows][kMaxRows];
  dense_system(lay, rows, ones, a);
  const int m = lay.m;
  long double x[kMaxRows], y[kMaxRows], lmax = 0, lmin_inv = 0;
  for (int i = 0; i < m; ++i) x[i] = 1 + 0.1L * (i % 7);
  for (int it = 0; it < 3000; ++it) {
    long double n = 0;
    for (int i = 0; i < m; ++i) {
      y[i] = 0;
      for (int j = 0; j < m; ++j) y[i] += a[i][j] * x[j];
      n += y[i] * y[i];
    }
    lmax = sqrtl(n);
    for (int i = 0; i < m; ++i) x[i] = y[i] / lmax;
  }
  for (int i = 0; i < m; ++i) x[i] = 1 - 0.1L * (i % 5);
  for (int it = 0; it < 300; ++it) {
    dense_solve(a, m, x, y);
    long double n = 0;
    for (int i = 0; i < m; ++i) n += y[i] * y[i];
    lmin_inv = sqrtl(n);
    for (int i = 0; i < m; ++i) x[i] = y[i] / lmin_inv;
  }
  const double exact = double(sqrtl(lmax * lmin_inv));
  const double estimate = double(factor_condition(factor));
  TEST_ASSERT_TRUE(exact > 1);
  TEST_ASSERT_DOUBLE_WITHIN(0.05 * exact, exact, estimate);  // 12 iterations each: a few digits
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_two_legs_have_no_separator);
  RUN_TEST(test_leg_has_no_separator);
  RUN_TEST(test_four_legs_solve_as_dense);
  RUN_TEST(test_six_legs_solve_as_dense);
  RUN_TEST(test_singular_b_falls_back);
  RUN_TEST(test_condition_with_separator);
  return UNITY_END();
}
