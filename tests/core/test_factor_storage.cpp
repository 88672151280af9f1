// The factor's packed storage (sim.hpp: Layout::row, Factor): on the leg's and the robot's
// layouts (joint rows; the dynamics' after steps, with a generated kernel's block and the
// general path alike) each position's columns tile the storage without gap or overlap, every
// pair of J W J^T lands on its own entry, L D L^T read back from the packed factor is
// J W J^T assembled densely in long double, and layout_storage refuses a capacity one entry
// short with LEGSIM_ERR_CAPACITY, leaving the layout untouched (C++: the core's internals).
#include <cmath>
#include <cstring>

#include "api/internal.hpp"
#include "planar/kernel.hpp"
#include "legsim/legsim.h"
#include "legsim/models.h"
#include "unity.h"
#if __has_include("legsim/robot_models.h")
#include "legsim/robot_models.h"
#define HAVE_ROBOT 1
#endif

extern "C" int legsim_kernel_use(legsim_sim *sim, int on);  // kernel.cpp: the tests' switch

void setUp(void) {}
void tearDown(void) {}

namespace {
using namespace legsim;

alignas(LEGSIM_STORAGE_ALIGN) unsigned char storage[64 * 1024];

// Positions before the generated kernel's block end (0: none).
int block_end(const Layout &lay) { return lay.kernel ? lay.kernel->mj : 0; }

// The first column row p keeps: its envelope's, or 0 for a row after the kernel's block
// that reaches into it.
int stored_from(const Layout &lay, int p) {
  const int p0 = block_end(lay);
  return p >= p0 && lay.first[p] < p0 ? 0 : lay.first[p];
}

// Rows after a kernel's block that keep columns before their envelope (stored_from).
int widened;

void storage_tiles(const Layout &lay) {
  int next = 0;
  for (int p = 0; p < lay.m; ++p) {
    TEST_ASSERT_TRUE(lay.first[p] <= p);
    widened += stored_from(lay, p) < lay.first[p];
    TEST_ASSERT_EQUAL_INT(next, lay.row[p] + stored_from(lay, p));  // right after the row before
    next = lay.row[p] + p + 1;
  }
  if (lay.separator < 0) TEST_ASSERT_EQUAL_INT(next, lay.entries);
  else TEST_ASSERT_EQUAL_INT(lay.m * (lay.m + 1) / 2, lay.entries);  // the dense fallback's room
  TEST_ASSERT_TRUE(lay.entries <= kFactorEntries);
  for (int k = 0; k < lay.npairs; ++k) {
    const Pair &pr = lay.pair[k];
    const int pi = lay.perm[pr.ci / (2 * kBodyDof)], pj = lay.perm[pr.cj / (2 * kBodyDof)];
    TEST_ASSERT_TRUE(pj <= pi && pj >= lay.first[pi]);
    TEST_ASSERT_EQUAL_INT(lay.row[pi] + pj, pr.aij);
  }
}

// L D L^T from the packed factor against J M^-1 J^T by rows, densely in long double.
void factor_reproduces_the_system(const Sim &s, const Layout &lay) {
  const Model &m = s.model;
  static Rows rows;
  static Factor f;
  rows_eval(m, lay, s.data.drivers, s.data.q, s.data.qd, rows);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, factor_build(lay, rows, m.minv, f));
  TEST_ASSERT_EQUAL_INT(0, f.nredundant);
  const int n = lay.m;
  static long double l[kMaxRows][kMaxRows];
  long double dinv[kMaxRows];
  for (int p = 0; p < n; ++p) {
    for (int q = 0; q < n; ++q) l[p][q] = q == p ? 1 : 0;
    for (int q = f.first[p]; q < p; ++q) l[p][q] = f.a[f.row[p] + q];
    dinv[p] = f.a[f.row[p] + p];
  }
  long double worst = 0, scale = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      long double a = 0;  // (J M^-1 J^T)_ij
      for (int si = 0; si < 2; ++si)
        for (int sj = 0; sj < 2; ++sj) {
          const int b = lay.body[i][si];
          if (b < 0 || b != lay.body[j][sj]) continue;
          for (int e = 0; e < kBodyDof; ++e)
            a += (long double)rows.coef[i][si][e] * m.minv[kBodyDof * b + e] * rows.coef[j][sj][e];
        }
      const int pi = lay.perm[i], pj = lay.perm[j];
      long double ldl = 0;
      for (int k = 0; k < n; ++k) ldl += l[pi][k] * l[pj][k] / dinv[k];
      worst = std::fmax(worst, std::fabs(ldl - a));
      scale = std::fmax(scale, std::fabs(a));
    }
  TEST_ASSERT_TRUE(scale > 0);
  TEST_ASSERT_TRUE_MESSAGE(worst <= 1e-12L * scale, "L D L^T from the packed storage is J M^-1 J^T");
}

void refused_when_short(const Layout &lay) {
  static Layout copy;
  std::memcpy(&copy, &lay, sizeof copy);
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_CAPACITY, layout_storage(copy, block_end(lay), lay.entries - 1));
  TEST_ASSERT_EQUAL_MEMORY(&lay, &copy, sizeof copy);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, layout_storage(copy, block_end(lay), lay.entries));
  TEST_ASSERT_EQUAL_MEMORY(&lay, &copy, sizeof copy);  // the same storage again
}

Sim &moving(const legsim_model_desc *model, bool on_ground, bool kernel) {
  legsim_options opt = legsim_default_options();
  opt.integrator = LEGSIM_INTEGRATOR_RK4;
  legsim_sim *sim = nullptr;
  TEST_ASSERT_TRUE(legsim_sim_size() <= sizeof storage);
  std::memset(storage, 0, sizeof storage);  // padding too: the layouts are compared bytewise
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage, sizeof storage, model, &opt, &sim));
  if (!kernel) TEST_ASSERT_EQUAL_INT(0, legsim_kernel_use(sim, 0));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  if (on_ground) TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_on_ground(sim, nullptr, 0.0));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_force(sim, 0, 50.0));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 20));
  return *reinterpret_cast<Sim *>(sim);
}

// The joint rows, the dynamics' and the pose assembly's (its coordinate drivers after the
// joint rows).
void check(const Sim &s) {
  for (const Layout *lay : {&s.data.joints, &s.data.dyn, &s.data.work}) {
    storage_tiles(*lay);
    factor_reproduces_the_system(s, *lay);
    refused_when_short(*lay);
  }
}
}  // namespace

void test_leg(void) {
  widened = 0;
  check(moving(&legsim_model_leg_revolute, false, true));
  TEST_ASSERT_TRUE_MESSAGE(widened > 0, "a row after the kernel's block reaches into it");
  check(moving(&legsim_model_leg_revolute, false, false));
}

void test_robot(void) {
#ifdef HAVE_ROBOT
  const Sim &s = moving(&legsim_model_robot_revolute, true, true);
  TEST_ASSERT_TRUE(s.data.dyn.m > s.data.joints.m);  // the stance's contact rows too
  check(s);
  check(moving(&legsim_model_robot_revolute, true, false));
#else
  TEST_IGNORE_MESSAGE("no robot in this build");
#endif
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_leg);
  RUN_TEST(test_robot);
  return UNITY_END();
}
