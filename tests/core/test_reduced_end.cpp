// RK4's end of a step in the reduced system (Kernel::end through dynamics_end, kernel.hpp)
// against the general path's sequence at the same state (rk4_step's: project, then
// dynamics_solve), on the revolute and slot legs under a force command, a servo and with
// gravity off, and on the robot on stuck feet (no pinned body: all its rows): velocities off J qd = 0 by a known amount are projected M-weighted in the
// whole system by project (linear_solve.cpp), and the end's own projection, in the reduced
// system where each pinned body keeps its angle alone, must give the same velocities,
// accelerations, multipliers and reactions to round-off. Also what the end leaves alone:
// the velocities unless it solves, and a step whose positions need projecting. And RK4's
// stage on the robot's stuck feet, pinned to the ground by their contact rows (rows_pin),
// and with one foot sliding (the generated one-slide stage, kernel_find_slide).
// Built only where the core has the reduced solves, in double (tests/core/CMakeLists.txt).
#include <cmath>
#include <cstdio>

#include "planar/kernel.hpp"
#include "planar/rows.hpp"
#include "legsim/legsim.h"
#include "legsim/models.h"
#include "unity.h"
#if __has_include("legsim/robot_models.h")
#include "legsim/robot_models.h"
#define HAVE_ROBOT 1
#endif

void setUp(void) {}
void tearDown(void) {}

#if !LEGSIM_KERNELS_REDUCED || LEGSIM_USE_FLOAT
#error "test_reduced_end needs a double core with the reduced solves"
#endif

namespace {
using namespace legsim;

alignas(LEGSIM_STORAGE_ALIGN) unsigned char storage[64 * 1024];
constexpr real kTol = 1e-10;  // the default options' newton_tol
constexpr int NJ = LEGSIM_MAX_JOINTS;

// How a scene drives the leg from its stand pose (RK4).
enum Drive { PUSH_50N, SERVO, PUSH_WEIGHTLESS };

// The leg (model: its revolute or slot variant) at its stand pose, driven for n steps: 50 N
// on the upper actuator; or its servo sent 5 cm out (the actuator's force then depends on
// the velocities); or 50 N with gravity off (no stage plan: each solve takes its base
// forces from reduced_base). A moving state on the reduced system (no stop reached).
Sim &moving_leg(const legsim_model_desc *model = &legsim_model_leg_revolute, Drive drive = PUSH_50N, int n = 200) {
  legsim_options opt = legsim_default_options();
  opt.integrator = LEGSIM_INTEGRATOR_RK4;
  if (drive == PUSH_WEIGHTLESS) opt.disable |= LEGSIM_DISABLE_GRAVITY;
  TEST_ASSERT_EQUAL_DOUBLE(kTol, opt.newton_tol);
  legsim_sim *sim = nullptr;
  TEST_ASSERT_TRUE(legsim_sim_size() <= sizeof storage);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage, sizeof storage, model, &opt, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  if (drive == SERVO) {
    legsim_real len[2];
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_actuator_lengths(sim, len, nullptr));
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_length(sim, 0, len[0] + 0.05));
  } else {
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_force(sim, 0, 50.0));
  }
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, n));
  Sim &s = *reinterpret_cast<Sim *>(sim);
  TEST_ASSERT_TRUE_MESSAGE(reduced_available(s.data.dyn), "the leg's layout has the reduced solves");
  TEST_ASSERT_TRUE((stage_plan(s.model, s.data, s.data.dyn).kernel != nullptr) == (drive != PUSH_WEIGHTLESS));
  return s;
}

#ifdef HAVE_ROBOT
// The robot on stuck feet (its stance: joint and contact rows, no pinned body, all its rows
// in the "reduced" system), three servos holding and the Fig. 7 push, after n steps.
// A stage's positions: q moved half a 1 ms step on at v.
VecQ half_step_on(const VecQ &q0, const VecQ &v, int n) {
  VecQ q = q0;
  for (int k = 0; k < n; ++k) q[k] += real(0.0005) * v[k];
  return q;
}

// The robot of desc on the ground by RK4, three servos holding and the Fig. 7 push on actuator
// 0, after n steps.
Sim &pushed_robot(const legsim_model_desc *desc, int n) {
  legsim_options opt = legsim_default_options();
  opt.integrator = LEGSIM_INTEGRATOR_RK4;
  legsim_sim *sim = nullptr;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage, sizeof storage, desc, &opt, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_on_ground(sim, nullptr, 0.0));
  legsim_real len[LEGSIM_MAX_ACTUATORS];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_actuator_lengths(sim, len, nullptr));
  for (int a = 1; a < 4; ++a) TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_length(sim, a, len[a]));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_force(sim, 0, 185.55));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, n));
  return *reinterpret_cast<Sim *>(sim);
}
Sim &moving_robot(int n = 200) {
  Sim &s = pushed_robot(&legsim_model_robot_revolute, n);
  TEST_ASSERT_TRUE_MESSAGE(reduced_available(s.data.dyn), "the robot's stance layout has the reduced solves");
  TEST_ASSERT_EQUAL_INT(2, s.model.nc);
  return s;
}
#endif

// v + 1e-6 m/s (rad/s) times a fixed pattern: off J v = 0 by about that much
VecQ drifted(const VecQ &v, int n) {
  VecQ out = v;
  for (int k = 0; k < n; ++k) out[k] += real(1e-6) * std::sin(real(1.3) * k + real(0.4));
  return out;
}

real max_abs(const real *a, const real *b, int n) {
  real e = 0;
  for (int k = 0; k < n; ++k) e = std::fmax(e, std::fabs(a[k] - b[k]));
  return e;
}
real max_abs(const real *a, int n) {
  real e = 0;
  for (int k = 0; k < n; ++k) e = std::fmax(e, std::fabs(a[k]));
  return e;
}

void projects_as_the_whole_system(Sim &s, const char *scene) {
  Data &d = s.data;
  const Model &m = s.model;
  const Layout &lay = d.dyn;
  const int n = m.nq, mr = lay.m;
  const VecQ q = d.q, v = drifted(d.qd, n);

  // the general path: rows at (q, v), factor, project, gamma at the projected v, solve
  VecQ v_ref = v, qdd_ref;
  VecR tmp;
  rows_eval(m, lay, d.stop_drivers, q, v_ref, d.rows);
  TEST_ASSERT_TRUE(rows_max_residual(lay, d.rows) <= kTol);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, factor_build(lay, d.rows, m.minv, d.factor));
  const real condition_ref = d.factor.condition;
  j_times(lay, d.rows, v, tmp);
  const real drift_before = max_abs(tmp.data(), mr);
  TEST_ASSERT_TRUE(drift_before > 100 * kTol);
  project(m, lay, d.rows, d.factor, m.minv, d.rows.nu, v_ref, tmp);
  rows_eval(m, lay, d.stop_drivers, q, v_ref, d.rows);
  legsim_reaction reaction_ref[NJ];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, dynamics_solve(s.model, s.data, lay, q, v_ref, qdd_ref, true, true, reaction_ref));
  const VecR lambda_ref = d.lambda;

  // the end's
  VecQ v_end = v, qdd_end;
  legsim_reaction reaction_end[NJ];
  real residual = -1, drift = -1;
  d.lambda.setZero();
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, dynamics_end(s.model, s.data, stage_plan(s.model, s.data, lay), q, v_end, qdd_end, s.data.lambda, reaction_end, kTol, true,
                                                residual, drift));
  TEST_ASSERT_TRUE(residual <= kTol);
  TEST_ASSERT_EQUAL_DOUBLE(0.0, drift);  // projected

  // its velocities meet J v = 0 as well as project's, and are project's to round-off
  rows_eval(m, lay, d.stop_drivers, q, v_end, d.rows);
  j_times(lay, d.rows, v_end, tmp);
  const real drift_after = max_abs(tmp.data(), mr);
  const real dv = max_abs(v_end.data(), v_ref.data(), n), vs = max_abs(v_ref.data(), n);
  const real dqdd = max_abs(qdd_end.data(), qdd_ref.data(), n), qdds = max_abs(qdd_ref.data(), n);
  const real dl = max_abs(d.lambda.data(), lambda_ref.data(), mr), ls = max_abs(lambda_ref.data(), mr);
  const real dr = max_abs(&reaction_end[0].force_n[0], &reaction_ref[0].force_n[0], 3 * m.nj);
  std::printf("%s: drift %.3g -> %.3g; differences from the general path: v %.3g (of %.3g), qdd %.3g (of %.3g), "
              "lambda %.3g (of %.3g), reactions %.3g N, condition %.3g vs %.3g\n",
              scene, drift_before, drift_after, dv, vs, dqdd, qdds, dl, ls, dr, d.report.condition, condition_ref);
  TEST_ASSERT_TRUE(drift_after <= 1e-14 * vs);
  TEST_ASSERT_TRUE(dv <= 1e-14 * vs);
  TEST_ASSERT_TRUE(dqdd <= 1e-12 * qdds);
  TEST_ASSERT_TRUE(dl <= 1e-12 * ls);
  TEST_ASSERT_TRUE(dr <= 1e-12 * ls);
  TEST_ASSERT_TRUE(std::fabs(d.report.condition - condition_ref) <= 1e-12 * condition_ref);
  // and not the drifted velocities: the projection moved them by about the drift
  TEST_ASSERT_TRUE(max_abs(v_end.data(), v.data(), n) > 1e-7);
}

void test_projects_as_the_whole_system(void) { projects_as_the_whole_system(moving_leg(), "leg, 50 N"); }
void test_projects_as_the_whole_system_slot(void) {
  projects_as_the_whole_system(moving_leg(&legsim_model_leg_slot, PUSH_50N, 50), "slot leg, 50 N");
}
void test_projects_as_the_whole_system_servo(void) {
  projects_as_the_whole_system(moving_leg(&legsim_model_leg_revolute, SERVO), "leg, servo");
}
#ifdef HAVE_ROBOT
void test_projects_as_the_whole_system_robot(void) { projects_as_the_whole_system(moving_robot(), "robot, stuck feet"); }
#endif
void test_projects_as_the_whole_system_weightless(void) {
  projects_as_the_whole_system(moving_leg(&legsim_model_leg_revolute, PUSH_WEIGHTLESS), "leg, 50 N, no gravity");
}

// Not asked to project (a restart, or force elements acting): it stops at the test and
// leaves the velocities and the accelerations as they were.
void test_leaves_alone_unless_it_solves(void) {
  Sim &s = moving_leg();
  Data &d = s.data;
  const int n = s.model.nq;
  const VecQ q = d.q, v = drifted(d.qd, n);
  VecQ v_end = v, qdd;
  qdd.setConstant(7);
  real residual, drift;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, dynamics_end(s.model, s.data, stage_plan(s.model, s.data, d.dyn), q, v_end, qdd, d.lambda, nullptr, kTol, false,
                                                residual, drift));
  TEST_ASSERT_TRUE(residual <= kTol);
  TEST_ASSERT_TRUE(drift > 100 * kTol);
  TEST_ASSERT_EQUAL_DOUBLE(0.0, max_abs(v_end.data(), v.data(), n));
  for (int k = 0; k < n; ++k) TEST_ASSERT_EQUAL_DOUBLE(7.0, qdd[k]);

  // positions off Phi = 0 (1e-6 m on the foot's link): rk4_step's sequence, not the end
  VecQ q_off = q;
  q_off[15] += real(1e-6);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, dynamics_end(s.model, s.data, stage_plan(s.model, s.data, d.dyn), q_off, v_end, qdd, d.lambda, nullptr, kTol, true,
                                                residual, drift));
  TEST_ASSERT_TRUE(residual > kTol);
  TEST_ASSERT_EQUAL_DOUBLE(0.0, max_abs(v_end.data(), v.data(), n));
  for (int k = 0; k < n; ++k) TEST_ASSERT_EQUAL_DOUBLE(7.0, qdd[k]);
}

// A load on the foot (a force element: its forces may depend on the velocities): the plan
// leaves the base to each solve, and the end does not project.
void test_no_projection_under_force_elements(void) {
  Sim &s = moving_leg();
  Data &d = s.data;
  const int n = s.model.nq;
  const legsim_real load[2] = {20.0, -150.0};
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_set_force(reinterpret_cast<legsim_sim *>(&s), 0, load));
  const StagePlan plan = stage_plan(s.model, s.data, d.dyn);
  TEST_ASSERT_NULL(plan.kernel);
  const VecQ q = d.q, v = drifted(d.qd, n);
  VecQ v_end = v, qdd;
  real residual, drift;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, dynamics_end(s.model, s.data, plan, q, v_end, qdd, s.data.lambda, nullptr, kTol, true, residual, drift));
  TEST_ASSERT_TRUE(drift > 100 * kTol);
  TEST_ASSERT_EQUAL_DOUBLE(0.0, max_abs(v_end.data(), v.data(), n));
}
// A stuck contact's two rows as a pin (rows_pin, kernel.hpp), on a ground at 0.3 rad: the
// foot point's offset and the pin rows' gamma in the world axes must be those of a revolute
// joint to the frame at that point (revolute_position's offset sa, revolute_gamma's w^2 sa).
void test_contact_rows_as_a_pin(void) {
  const real slope = real(0.3);
  const Vec2 ground(0.1, -0.2), n(-std::sin(slope), std::cos(slope)), t(std::cos(slope), std::sin(slope));
  VecQ q = VecQ::Zero();
  q[0] = real(0.4), q[1] = real(-0.7), q[2] = real(0.9);
  BodyPose p = body_pose(q, 0, std::sin(q[2]), std::cos(q[2]));
  body_velocity(p, real(0.2), real(-0.1), real(1.7));
  Joint pin{};
  pin.kind = LEGSIM_JOINT_REVOLUTE_TO_FRAME;
  pin.pa = Vec2(0.03, -0.25);
  ContactRow cn, ct;
  contact_row(pin.pa, ground, n, real(0), real(1), p, cn);
  contact_row(pin.pa, ground, t, real(0.05), real(1), p, ct);
  real sx, sy, g0, g1;
  rows_pin(cn.coef[0], cn.coef[1], cn.coef[2], ct.coef[0], ct.coef[1], ct.coef[2], cn.gamma, ct.gamma, sx, sy, g0, g1);
  JointRows ref;
  revolute_position(pin, p, nullptr, ref);
  revolute_gamma(p, nullptr, ref);
  TEST_ASSERT_DOUBLE_WITHIN(1e-15, ref.sa.x, sx);
  TEST_ASSERT_DOUBLE_WITHIN(1e-15, ref.sa.y, sy);
  TEST_ASSERT_DOUBLE_WITHIN(1e-14, ref.gamma[0], g0);
  TEST_ASSERT_DOUBLE_WITHIN(1e-14, ref.gamma[1], g1);
  TEST_ASSERT_TRUE(std::fabs(g0) > real(0.05) && std::fabs(g1) > real(0.05));  // not a trivial case
}

#ifdef HAVE_ROBOT
// RK4's stage on the robot's stuck feet (Kernel::accelerations: the feet pinned to the ground,
// 32 rows) against the whole system's solve (dynamics_solve, 36 rows) at a stage's state:
// positions off Phi = 0 (half a step on) and velocities off J v = 0, on a sloped ground.
void test_stage_with_feet_as_pins(void) {
  legsim_model_desc robot = legsim_model_robot_revolute;
  robot.ground.slope_rad = 0.2;
  legsim_options opt = legsim_default_options();
  opt.integrator = LEGSIM_INTEGRATOR_RK4;
  legsim_sim *sim = nullptr;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage, sizeof storage, &robot, &opt, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_on_ground(sim, nullptr, 0.0));
  legsim_real len[LEGSIM_MAX_ACTUATORS];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_actuator_lengths(sim, len, nullptr));
  for (int a = 0; a < 4; ++a) TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_length(sim, a, len[a]));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_force(sim, 0, 185.55));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 100));
  Sim &s = *reinterpret_cast<Sim *>(sim);
  Data &d = s.data;
  const Model &m = s.model;
  const Layout &lay = d.dyn;
  TEST_ASSERT_EQUAL_INT(2, m.nc);
  TEST_ASSERT_TRUE_MESSAGE(reduced_available(lay), "the robot's stance layout has the reduced solves");
  const StagePlan plan = stage_plan(m, d, lay);
  TEST_ASSERT_NOT_NULL(plan.kernel);
  const int n = m.nq;
  const VecQ v = drifted(d.qd, n);
  const VecQ q = half_step_on(d.q, v, n);
  VecQ qdd, qdd_ref;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, dynamics_stage(m, d, plan, q, v, qdd));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, dynamics_solve(m, d, lay, q, v, qdd_ref, false, false));
  const real dqdd = max_abs(qdd.data(), qdd_ref.data(), n), qdds = max_abs(qdd_ref.data(), n);
  std::printf("robot stage, feet as pins, slope 0.2 rad: qdd %.3g (of %.3g) from the whole system's\n", dqdd, qdds);
  TEST_ASSERT_TRUE(qdds > 1);
  TEST_ASSERT_TRUE(dqdd <= 1e-12 * qdds);
}

// The robot on slippery ground (mu 0.1) under the Fig. 7 push (test_kernels.c's sliding
// scene) after n steps: contact 1 slides from step 14, contact 0 too from step 56.
legsim_model_desc slippery;  // outlives the sim
Sim &slippery_robot(int n) {
  slippery = legsim_model_robot_revolute;
  slippery.ground.mu_static = slippery.ground.mu_kinetic = 0.1;
  Sim &s = pushed_robot(&slippery, n);
  TEST_ASSERT_EQUAL_INT(2, s.model.nc);
  return s;
}
void expect_states(Sim &s, legsim_contact_state c0, legsim_contact_state c1) {
  legsim_contact c[2];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_contacts(reinterpret_cast<legsim_sim *>(&s), c));
  TEST_ASSERT_EQUAL_INT(c0, c[0].state);
  TEST_ASSERT_EQUAL_INT(c1, c[1].state);
}

// RK4's stage with one foot sliding and the other stuck: the layout's stage path is the
// generated one-slide kernel (kernel_find_slide), and its qdd at a stage's state (as
// test_stage_with_feet_as_pins) is the general path's (legsim_kernel_use off). The stage
// gives no multipliers (Kernel::accelerations): qdd alone is compared. With both feet stuck
// or both sliding, the stage path is not a one-slide kernel.
void test_stage_with_one_foot_sliding(void) {
  Sim &s = slippery_robot(30);
  expect_states(s, LEGSIM_CONTACT_STUCK, LEGSIM_CONTACT_SLIDING);
  Data &d = s.data;
  const Model &m = s.model;
  TEST_ASSERT_NOT_NULL(m.kernel);
  const Kernel *slide1 = kernel_find_slide(m.kernel, 1);
  TEST_ASSERT_NOT_NULL(slide1);
  TEST_ASSERT_TRUE(slide1 != kernel_find_slide(m.kernel, 0));
  TEST_ASSERT_EQUAL_PTR(slide1, d.dyn.path.stage);
  TEST_ASSERT_NULL(d.dyn.path.reduced);  // not the whole system's: the sliding foot's one row
  const StagePlan plan = stage_plan(m, d, d.dyn);
  TEST_ASSERT_EQUAL_PTR(slide1, plan.kernel);

  const int n = m.nq;
  const VecQ v = drifted(d.qd, n);
  const VecQ q = half_step_on(d.q, v, n);
  VecQ qdd, qdd_ref;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, dynamics_stage(m, d, plan, q, v, qdd));
  TEST_ASSERT_EQUAL_INT(0, legsim_kernel_use(reinterpret_cast<legsim_sim *>(&s), 0));
  TEST_ASSERT_NULL(d.dyn.path.stage);
  const StagePlan general = stage_plan(m, d, d.dyn);
  TEST_ASSERT_NULL(general.kernel);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, dynamics_stage(m, d, general, q, v, qdd_ref));
  const real dqdd = max_abs(qdd.data(), qdd_ref.data(), n), qdds = max_abs(qdd_ref.data(), n);
  std::printf("robot stage, foot 1 sliding, foot 0 stuck: qdd %.3g (of %.3g) from the general path's\n", dqdd, qdds);
  TEST_ASSERT_TRUE(qdds > 1);
  TEST_ASSERT_TRUE(dqdd <= 1e-10 * qdds);

  // both stuck: the reduced system's kernel; both sliding: the general path
  Sim &stuck = moving_robot(30);
  expect_states(stuck, LEGSIM_CONTACT_STUCK, LEGSIM_CONTACT_STUCK);
  TEST_ASSERT_NOT_NULL(stuck.data.dyn.path.stage);
  TEST_ASSERT_EQUAL_PTR(stuck.data.dyn.path.reduced, stuck.data.dyn.path.stage);
  TEST_ASSERT_TRUE(stuck.data.dyn.path.stage != kernel_find_slide(stuck.model.kernel, 0));
  TEST_ASSERT_TRUE(stuck.data.dyn.path.stage != kernel_find_slide(stuck.model.kernel, 1));
  Sim &both = slippery_robot(100);
  expect_states(both, LEGSIM_CONTACT_SLIDING, LEGSIM_CONTACT_SLIDING);
  TEST_ASSERT_NULL(both.data.dyn.path.stage);
  TEST_ASSERT_NULL(stage_plan(both.model, both.data, both.data.dyn).kernel);
}
#endif
}  // namespace

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_projects_as_the_whole_system);
  RUN_TEST(test_projects_as_the_whole_system_slot);
  RUN_TEST(test_projects_as_the_whole_system_servo);
  RUN_TEST(test_projects_as_the_whole_system_weightless);
#ifdef HAVE_ROBOT
  RUN_TEST(test_projects_as_the_whole_system_robot);
#endif
  RUN_TEST(test_leaves_alone_unless_it_solves);
  RUN_TEST(test_no_projection_under_force_elements);
  RUN_TEST(test_contact_rows_as_a_pin);
#ifdef HAVE_ROBOT
  RUN_TEST(test_stage_with_feet_as_pins);
  RUN_TEST(test_stage_with_one_foot_sliding);
#endif
  return UNITY_END();
}
