/* The generated joint-block kernels (firmware_core/src/planar/kernel.hpp) against the general
 * path: the same scenes run twice, once on the kernel and once with it switched off
 * (legsim_kernel_use), must give the same trajectories (q, qd, qdd), multipliers,
 * reactions, actuator and contact forces, events and statuses to round-off, over 1 s,
 * with both integrators, for the leg (free, its slot variant free, resting on a stroke
 * stop: a row after the kernel's block, a saturating servo with a foot load, gravity off)
 * and the robot (feet stuck; on slippery ground, where a foot slides and one lifts off).
 * The general path factors the joint block in the kernel's order, so the two agree bit
 * for bit here, except RK4: its stages and its end solve the kernel's reduced system (on the
 * leg the bodies pinned to the frame on their angles alone; on the robot all its rows; its
 * stages with one foot sliding the stance's with the stuck foot as a pin and the friction as
 * one Sherman-Morrison column) in another copy (FMA), which agrees to round-off (7.3e-12 relative over 1 s on the leg's stop,
 * where the multipliers of a stiff servo amplify it). The tolerances allow for round-off
 * only, and the sliding
 * robot's RK4 run is compared until the paths first take different contact modes after an
 * ambiguous or inconsistent mode choice (a pick that round-off can turn either way). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "legsim/legsim.h"
#include "legsim/models.h"
#include "unity.h"
#if __has_include("legsim/robot_models.h")
#include "legsim/robot_models.h"
#define HAVE_ROBOT 1
#endif

/* firmware_core/src/planar/kernel.hpp: 1 when the sim now uses a kernel, 0 when not */
int legsim_kernel_use(legsim_sim *sim, int on);

#define MAXQ (3 * LEGSIM_MAX_BODIES)
static _Alignas(LEGSIM_STORAGE_ALIGN) unsigned char storage[2][128 * 1024];
static legsim_model_desc slippery; /* outlives the sims */

void setUp(void) {}
void tearDown(void) {}

/* ROBOT_STUCK_QUIET: ROBOT_STUCK with the reactions disabled (generalized-alpha's end then
 * takes the general path's passes on either path: Kernel::end_factored is for reactions on) */
enum scene { LEG_PUSH, LEG_SLOT_PUSH, LEG_ON_STOP, LEG_LOADED, LEG_WEIGHTLESS, ROBOT_STUCK, ROBOT_STUCK_QUIET, ROBOT_SLIDING };

/* Everything a caller can read after a step, as one vector of numbers. */
static int outputs(legsim_sim *sim, double *out) {
  legsim_real v[MAXQ];
  int n = 0;
  const int nq = 3 * legsim_n_bodies(sim);
  legsim_get_q(sim, v);
  for (int k = 0; k < nq; ++k) out[n++] = v[k];
  legsim_get_qd(sim, v);
  for (int k = 0; k < nq; ++k) out[n++] = v[k];
  legsim_get_qdd(sim, v);
  for (int k = 0; k < nq; ++k) out[n++] = v[k];
  legsim_real lambda[LEGSIM_MAX_ROWS];
  legsim_multipliers(sim, lambda);
  for (int i = 0; i < legsim_n_constraints(sim); ++i) out[n++] = lambda[i];
  legsim_reaction r[LEGSIM_MAX_JOINTS];
  const legsim_status rs = legsim_reactions(sim, r);  /* LEGSIM_ERR_DISABLED with them off */
  TEST_ASSERT_TRUE(rs == LEGSIM_OK || rs == LEGSIM_ERR_DISABLED);
  for (int j = 0; rs == LEGSIM_OK && j < legsim_model(sim)->n_joints; ++j) {
    out[n++] = r[j].force_n[0];
    out[n++] = r[j].force_n[1];
    out[n++] = r[j].moment_nm;
  }
  legsim_real f[LEGSIM_MAX_ACTUATORS];
  legsim_actuator_forces(sim, f);
  for (int a = 0; a < legsim_model(sim)->n_actuators; ++a) out[n++] = f[a];
  legsim_contact c[LEGSIM_CONTACT_SLOTS];
  const int nc = legsim_n_contacts(sim);
  if (nc > 0) legsim_contacts(sim, c);
  for (int k = 0; k < nc; ++k) {
    out[n++] = c[k].state;
    out[n++] = c[k].normal_n;
    out[n++] = c[k].tangential_n;
    out[n++] = c[k].impulse_ns[0];
    out[n++] = c[k].impulse_ns[1];
  }
  legsim_report rep;
  legsim_get_report(sim, &rep);
  out[n++] = rep.events;
  out[n++] = rep.iterations;
  out[n++] = rep.condition;
  return n;
}

static legsim_sim *set_up(int slot, enum scene sc, legsim_integrator integ, int kernel) {
  const legsim_model_desc *model = sc == LEG_SLOT_PUSH ? &legsim_model_leg_slot : &legsim_model_leg_revolute;
#ifdef HAVE_ROBOT
  if (sc == ROBOT_STUCK || sc == ROBOT_STUCK_QUIET) model = &legsim_model_robot_revolute;
  if (sc == ROBOT_SLIDING) {
    slippery = legsim_model_robot_revolute;
    slippery.ground.mu_static = slippery.ground.mu_kinetic = 0.1;
    model = &slippery;
  }
#endif
  legsim_options opt = legsim_default_options();
  opt.integrator = integ;
  if (sc == ROBOT_STUCK_QUIET) opt.disable |= LEGSIM_DISABLE_REACTIONS;
  legsim_sim *sim = NULL;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage[slot], sizeof storage[slot], model, &opt, &sim));
  TEST_ASSERT_EQUAL_INT(kernel, legsim_kernel_use(sim, kernel));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  legsim_real len[LEGSIM_MAX_ACTUATORS];
  if (sc == LEG_PUSH || sc == LEG_SLOT_PUSH) {
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_force(sim, 0, 50.0));
  } else if (sc == LEG_ON_STOP) { /* the upper servo holds, the lower pulls into its end */
    legsim_actuator_lengths(sim, len, NULL);
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_length(sim, 0, len[0]));
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_force(sim, 1, -400.0));
  } else if (sc == LEG_LOADED || sc == LEG_WEIGHTLESS) {
    /* the upper servo sent 10 cm away (it saturates: 20 kN/m), a load on the foot (a force element:
     * the reduced solves take Q's base from applied_forces then); weightless: gravity off */
    legsim_actuator_lengths(sim, len, NULL);
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_length(sim, 0, len[0] + 0.1));
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_force(sim, 1, 30.0));
    if (sc == LEG_LOADED) {
      const legsim_real load[2] = {20.0, -150.0};
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_set_force(sim, 0, load));
    } else {
      opt.disable |= LEGSIM_DISABLE_GRAVITY;
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_set_options(sim, &opt));
    }
  } else { /* the robot on the ground, three servos holding, the Fig. 7 Scene A push */
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_on_ground(sim, NULL, 0.0));
    legsim_actuator_lengths(sim, len, NULL);
    for (int a = 1; a < 4; ++a) TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_length(sim, a, len[a]));
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_force(sim, 0, 185.55));
  }
  return sim;
}

/* 1 s at h = 1 ms on both paths, every output compared after every step. */
static void same_scene(enum scene sc, legsim_integrator integ, const char *name) {
  legsim_sim *k = set_up(0, sc, integ, 1), *g = set_up(1, sc, integ, 0);
  static double a[1024], b[1024];
  double worst = 0;
  uint32_t events = 0;
  /* RK4's stages and end in the reduced system (FMA): round-off grows over 1,000 steps,
   * and more through located contact events (their roots found to 1e-7 h) */
  const int rk4 = integ == LEGSIM_INTEGRATOR_RK4;
  /* generalized-alpha: the same arithmetic on both paths, bit for bit */
  const double tol = rk4 ? (sc == ROBOT_SLIDING ? 1e-8 : 1e-10) : 0;
  /* where several contact modes are consistent (CONTACT_AMBIGUOUS) or none is
   * (CONTACT_INCONSISTENT: the fallback rule's) the pick goes by values that round-off can
   * order either way: once either run reported one, the sliding robot's RK4 comparison ends
   * (passing) at the first step where the two runs differ; before, any difference fails */
  const int picks_count = rk4 && sc == ROBOT_SLIDING;
  uint32_t picks = 0;
  int step = 0;
  for (; step < 1000; ++step) {
    const legsim_status sk = legsim_step(k, 1), sg = legsim_step(g, 1);
    legsim_report rk, rg;
    legsim_get_report(k, &rk);
    legsim_get_report(g, &rg);
    picks |= (rk.events | rg.events) & (LEGSIM_EVENT_CONTACT_AMBIGUOUS | LEGSIM_EVENT_CONTACT_INCONSISTENT);
    const int n = outputs(k, a), ng = outputs(g, b);
    double step_worst = 0;
    int at = 0;
    for (int i = 0; i < n && n == ng; ++i) {
      const double d = fabs(a[i] - b[i]) / (1 + fabs(b[i]));
      if (!(d <= step_worst)) step_worst = d, at = i;
    }
    const int differ = sk != sg || n != ng || !(step_worst <= tol);
    if (differ && picks_count && picks) break;
    TEST_ASSERT_EQUAL_INT(sg, sk);
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, sk);
    TEST_ASSERT_EQUAL_INT(n, ng);
    if (!(step_worst <= tol)) {
      printf("%s: step %d, output %d: kernel %.17g, general %.17g\n", name, step, at, a[at], b[at]);
      TEST_FAIL();
    }
    worst = step_worst > worst ? step_worst : worst;
    events |= (uint32_t)a[n - 3];
  }
  printf("%s: %d steps, largest relative difference %.3g, events 0x%x\n", name, step, worst, events);
  if (picks_count)
    TEST_ASSERT_TRUE(step >= 700);
  else
    TEST_ASSERT_EQUAL_INT(1000, step);
  if (sc == LEG_ON_STOP) TEST_ASSERT_TRUE(events & LEGSIM_EVENT_STROKE_MIN);
  if (sc == ROBOT_SLIDING) TEST_ASSERT_TRUE(events & LEGSIM_EVENT_STICK_TO_SLIP);
  if (sc == LEG_LOADED || sc == LEG_WEIGHTLESS) TEST_ASSERT_TRUE(events & LEGSIM_EVENT_FORCE_SATURATED);
}

static void test_leg_push_rk4(void) { same_scene(LEG_PUSH, LEGSIM_INTEGRATOR_RK4, "leg 50 N rk4"); }
static void test_leg_push_galpha(void) {
  same_scene(LEG_PUSH, LEGSIM_INTEGRATOR_GENERALIZED_ALPHA, "leg 50 N generalized-alpha");
}
/* the slot variant: a structure of its own, with its own reduced solves */
static void test_leg_slot_push_rk4(void) { same_scene(LEG_SLOT_PUSH, LEGSIM_INTEGRATOR_RK4, "slot leg 50 N rk4"); }
static void test_leg_slot_push_galpha(void) {
  same_scene(LEG_SLOT_PUSH, LEGSIM_INTEGRATOR_GENERALIZED_ALPHA, "slot leg 50 N generalized-alpha");
}
static void test_leg_on_stop_rk4(void) { same_scene(LEG_ON_STOP, LEGSIM_INTEGRATOR_RK4, "leg on its stop rk4"); }
static void test_leg_on_stop_galpha(void) {
  same_scene(LEG_ON_STOP, LEGSIM_INTEGRATOR_GENERALIZED_ALPHA, "leg on its stop generalized-alpha");
}
/* the reduced solves apply the actuators' forces themselves (Kernel::accelerations): a
 * saturating servo, a force element, gravity off */
static void test_leg_loaded_rk4(void) { same_scene(LEG_LOADED, LEGSIM_INTEGRATOR_RK4, "leg loaded rk4"); }
static void test_leg_weightless_rk4(void) {
  same_scene(LEG_WEIGHTLESS, LEGSIM_INTEGRATOR_RK4, "leg weightless rk4");
}
#ifdef HAVE_ROBOT
static void test_robot_stuck_rk4(void) { same_scene(ROBOT_STUCK, LEGSIM_INTEGRATOR_RK4, "robot stuck rk4"); }
static void test_robot_stuck_galpha(void) {
  same_scene(ROBOT_STUCK, LEGSIM_INTEGRATOR_GENERALIZED_ALPHA, "robot stuck generalized-alpha");
}
static void test_robot_stuck_quiet_galpha(void) {
  same_scene(ROBOT_STUCK_QUIET, LEGSIM_INTEGRATOR_GENERALIZED_ALPHA, "robot stuck, reactions off, generalized-alpha");
}
static void test_robot_sliding_rk4(void) {
  same_scene(ROBOT_SLIDING, LEGSIM_INTEGRATOR_RK4, "robot sliding rk4");
}
static void test_robot_sliding_galpha(void) {
  same_scene(ROBOT_SLIDING, LEGSIM_INTEGRATOR_GENERALIZED_ALPHA, "robot sliding generalized-alpha");
}
#endif

/* Failures: a step far beyond RK4's stability limit under the stiff servo (diverges), the
 * same for generalized-alpha, a dead centre in assembly and a NaN state: the same status
 * at the same step, and the same failure report. */
static void test_same_statuses(void) {
  for (int integ = 0; integ < 2; ++integ) {
    legsim_status st[2];
    int at[2];
    legsim_report rep[2];
    for (int kernel = 0; kernel < 2; ++kernel) {
      legsim_sim *sim = set_up(kernel, LEG_PUSH, (legsim_integrator)integ, kernel);
      legsim_options o = legsim_default_options();
      o.integrator = (legsim_integrator)integ;
      o.step_s = 0.05;
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_set_options(sim, &o));
      legsim_command_length(sim, 0, 0.75);
      legsim_command_force(sim, 1, 1500.0);
      at[kernel] = 0;
      while ((st[kernel] = legsim_step(sim, 1)) == LEGSIM_OK && at[kernel] < 200) ++at[kernel];
      legsim_failure_report(sim, &rep[kernel]);
    }
    printf("integrator %d at h = 50 ms: %s at step %d on both\n", integ, legsim_status_str(st[0]), at[0]);
    TEST_ASSERT_NOT_EQUAL_INT(LEGSIM_OK, st[0]);
    TEST_ASSERT_EQUAL_INT(st[0], st[1]);
    TEST_ASSERT_EQUAL_INT(at[0], at[1]);
    TEST_ASSERT_EQUAL_INT(rep[0].iterations, rep[1].iterations);
  }
  legsim_status dead[2], nan_state[2];
  for (int kernel = 0; kernel < 2; ++kernel) {
    legsim_sim *sim = set_up(kernel, LEG_PUSH, LEGSIM_INTEGRATOR_RK4, kernel);
    const legsim_real lengths[2] = {0.75, 0.6244998}; /* the thigh and the upper actuator in line */
    dead[kernel] = legsim_assemble(sim, lengths);
    legsim_real q[MAXQ], qd[MAXQ];
    legsim_get_q(sim, q);
    legsim_get_qd(sim, qd);
    q[4] = NAN;
    nan_state[kernel] = legsim_set_state(sim, q, qd, 0.0);
  }
  TEST_ASSERT_TRUE(dead[0] == LEGSIM_ERR_SINGULAR || dead[0] == LEGSIM_ERR_NOT_CONVERGED);
  TEST_ASSERT_EQUAL_INT(dead[0], dead[1]);
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, nan_state[0]);
  TEST_ASSERT_EQUAL_INT(nan_state[0], nan_state[1]);
}

/* A model the kernels were not generated for (a structure of its own) stays on the
 * general path; the compiled-in ones have theirs. */
static void test_dispatch_by_structure(void) {
  legsim_options opt = legsim_default_options();
  legsim_sim *sim;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage[0], sizeof storage[0], &legsim_model_leg_revolute, &opt, &sim));
  TEST_ASSERT_EQUAL_INT(1, legsim_kernel_use(sim, 1));
  legsim_model_desc other = legsim_model_leg_revolute;
  other.joint[7].body[0] = 5; /* the last revolute joint's bodies swapped: another structure */
  other.joint[7].body[1] = 4;
  const double p0[2] = {other.joint[7].point[0][0], other.joint[7].point[0][1]};
  other.joint[7].point[0][0] = other.joint[7].point[1][0];
  other.joint[7].point[0][1] = other.joint[7].point[1][1];
  other.joint[7].point[1][0] = p0[0];
  other.joint[7].point[1][1] = p0[1];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage[1], sizeof storage[1], &other, &opt, &sim));
  TEST_ASSERT_EQUAL_INT(0, legsim_kernel_use(sim, 1));
  /* the same joints, the actuators on each other's joints: the reduced solves apply their
   * forces, so a kernel with them is not this model's */
  other = legsim_model_leg_revolute;
  const int32_t j0 = other.actuator[0].joint;
  other.actuator[0].joint = other.actuator[1].joint;
  other.actuator[1].joint = j0;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage[1], sizeof storage[1], &other, &opt, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_KERNELS_REDUCED ? 0 : 1, legsim_kernel_use(sim, 1));
  TEST_ASSERT_EQUAL_INT(-1, legsim_kernel_use(NULL, 1));
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_leg_push_rk4);
  RUN_TEST(test_leg_push_galpha);
  RUN_TEST(test_leg_slot_push_rk4);
  RUN_TEST(test_leg_slot_push_galpha);
  RUN_TEST(test_leg_on_stop_rk4);
  RUN_TEST(test_leg_on_stop_galpha);
  RUN_TEST(test_leg_loaded_rk4);
  RUN_TEST(test_leg_weightless_rk4);
#ifdef HAVE_ROBOT
  RUN_TEST(test_robot_stuck_rk4);
  RUN_TEST(test_robot_stuck_galpha);
  RUN_TEST(test_robot_stuck_quiet_galpha);
  RUN_TEST(test_robot_sliding_rk4);
  RUN_TEST(test_robot_sliding_galpha);
#endif
  RUN_TEST(test_same_statuses);
  RUN_TEST(test_dispatch_by_structure);
  return UNITY_END();
}
