/* Host proof of no allocation: malloc, calloc, realloc and free are
 * interposed and counted around init, assembly, every analysis and many steps
 * of each integrator. */
#define _GNU_SOURCE
#include <stddef.h>
#include <stdio.h>

#include "leg_fixture.h"
#include "unity.h"

extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void __libc_free(void *);

static volatile long allocations;
static volatile int counting;

void *malloc(size_t n) {
  if (counting) ++allocations;
  return __libc_malloc(n);
}
void *calloc(size_t n, size_t s) {
  if (counting) ++allocations;
  return __libc_calloc(n, s);
}
void *realloc(void *p, size_t n) {
  if (counting) ++allocations;
  return __libc_realloc(p, n);
}
void free(void *p) {
  if (counting && p) ++allocations;
  __libc_free(p);
}

static fixture_storage st;

void setUp(void) {}
void tearDown(void) {}

static void test_the_hook_counts(void) {
  allocations = 0;
  counting = 1;
  void *p = malloc(16);
  free(p);
  counting = 0;
  TEST_ASSERT_EQUAL_INT(2, allocations); /* the hook is live: this test can fail */
}

static void test_no_allocation_in_any_analysis_or_step(void) {
  allocations = 0;
  counting = 1;
  for (int integ = 0; integ < 2; ++integ) {
    legsim_options o = legsim_default_options();
    o.integrator = (legsim_integrator)integ;
    legsim_sim *sim = NULL;
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(st.bytes, sizeof st.bytes, &legsim_model_leg_revolute, &o, &sim));
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
    legsim_command_force(sim, 0, 30.0);
    legsim_command_length(sim, 1, 0.6);
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 5000));
    legsim_real f[NA];
    legsim_reaction r[NJ];
    legsim_reactions(sim, r);
    legsim_assemble_pose(sim, 0);
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_statics(sim, f));
    const legsim_real len[NA] = {0.62, 0.6}, rate[NA] = {0.1, 0.1}, acc[NA] = {0, 0};
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_inverse_dynamics(sim, len, rate, acc, f));
    legsim_worst_case wc;
    legsim_statics_sweep(sim, 5, &wc);
  }
  counting = 0;
  TEST_ASSERT_EQUAL_INT(0, allocations);
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_the_hook_counts);
  RUN_TEST(test_no_allocation_in_any_analysis_or_step);
  return UNITY_END();
}
