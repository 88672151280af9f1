/* Forward dynamics: energy conservation of a conservative run, agreement of the
 * two integrators, the slot reaction's direction, actuators (servo, saturation,
 * stroke ends), scene options and bad commands. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "leg_fixture.h"
#include "unity.h"

static fixture_storage st, st2;

void setUp(void) {}
void tearDown(void) {}

static legsim_options opts(legsim_integrator integ, double h) {
  legsim_options o = legsim_default_options();
  o.integrator = integ;
  o.step_s = h;
  return o;
}

/* Constant actuator forces, gravity, no damping: T + V - F.l is conserved. The
 * forces hold the leg up so it swings without hitting a stroke end. */
static double energy_drift(legsim_integrator integ, double rho, double h, double t_end) {
  legsim_options o = opts(integ, h);
  o.rho_inf = rho;
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, o);
  const double force[NA] = {-60.0, 10.0};
  for (int a = 0; a < NA; ++a) TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_force(sim, a, force[a]));
  const double e0 = leg_energy(sim, force);
  double worst = 0;
  const int n = (int)(t_end / h + 0.5);
  for (int i = 0; i < n; i += 10) {
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 10));
    worst = fmax(worst, fabs(leg_energy(sim, force) - e0));
  }
  TEST_ASSERT_EQUAL_UINT32(0, legsim_stroke_event_mask(sim));
  return worst / fabs(e0);
}

static void test_energy_is_conserved_with_constant_forces(void) {
  const double rk4 = energy_drift(LEGSIM_INTEGRATOR_RK4, 0.8, 1e-3, 2.0);
  const double ga = energy_drift(LEGSIM_INTEGRATOR_GENERALIZED_ALPHA, 1.0, 1e-3, 2.0);
  printf("relative energy drift over 2 s at h = 1 ms: rk4 %.3g, generalized-alpha (rho 1) %.3g\n", rk4, ga);
  TEST_ASSERT_TRUE(rk4 < 1e-7);
  TEST_ASSERT_TRUE(ga < 1e-4);
  /* rho < 1 damps high frequencies only: still close */
  TEST_ASSERT_TRUE(energy_drift(LEGSIM_INTEGRATOR_GENERALIZED_ALPHA, 0.8, 1e-3, 0.5) < 1e-3);
}

/* Force elements: a spring between the frame and the foot and a constant torque
 * on the thigh, no damping: T + V_gravity + k (L - L0)^2 / 2 - tau phi3 is conserved. */
static legsim_model_desc with_springs;
static void test_spring_and_torque_conserve_energy(void) {
  with_springs = legsim_model_leg_revolute;
  TEST_ASSERT_TRUE(LEGSIM_MAX_FORCES >= 3);
  legsim_force_desc *spring = &with_springs.force[with_springs.n_forces++];
  memset(spring, 0, sizeof *spring);
  strcpy(spring->name, "heel_spring");
  spring->kind = LEGSIM_FORCE_SPRING_DAMPER;
  spring->body[0] = LEGSIM_FRAME;
  spring->point[0][0] = 0.6;
  spring->point[0][1] = -0.9;
  spring->body[1] = 5;
  spring->point[1][0] = 0.30; /* the foot */
  spring->stiffness_n_per_m = 800.0;
  spring->rest_length_m = 0.05;
  legsim_force_desc *torque = &with_springs.force[with_springs.n_forces++];
  memset(torque, 0, sizeof *torque);
  strcpy(torque->name, "hip_torque");
  torque->kind = LEGSIM_FORCE_TORQUE;
  torque->body[0] = 2;
  torque->value[0] = 3.0;
  double drift[2] = {0, 0}, moved = 0;
  legsim_sim *sim = NULL;
  for (int e = 0; e < 2; ++e) { /* h = 1 ms and 0.5 ms: the drift is RK4's, it shrinks ~16x */
    const double h = e ? 5e-4 : 1e-3;
    sim = leg_at_stand(&st, &with_springs, opts(LEGSIM_INTEGRATOR_RK4, h));
    const double none[NA] = {0, 0};
    double e0 = 0;
    legsim_real q0[NQ];
    legsim_get_q(sim, q0);
    for (int i = 0; i <= 40; ++i) {
      if (i) TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, e ? 20 : 10));
      legsim_real q[NQ], foot[2];
      legsim_get_q(sim, q);
      legsim_foot_position(sim, foot);
      const double L = hypot(foot[0] - 0.6, foot[1] + 0.9);
      const double en = leg_energy(sim, none) + 0.5 * 800.0 * (L - 0.05) * (L - 0.05) - 3.0 * q[8];
      if (!i) e0 = en;
      drift[e] = fmax(drift[e], fabs(en - e0));
      moved = fmax(moved, max_abs_diff(q, q0, NQ));
    }
    TEST_ASSERT_EQUAL_UINT32(0, legsim_stroke_event_mask(sim));
  }
  printf("spring and torque: energy drift over 0.4 s %.3g J (h = 1 ms), %.3g J (0.5 ms); motion %.3g\n",
         drift[0], drift[1], moved);
  TEST_ASSERT_TRUE(moved > 0.01);
  TEST_ASSERT_TRUE(drift[0] < 1e-5);
  TEST_ASSERT_TRUE(drift[1] < drift[0] / 8);
  /* a spring-damper's law is model data: no value to set */
  const legsim_real v[2] = {1, 1};
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_set_force(sim, 1, v));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_set_force(sim, 2, v));
}

static void run_free_fall(legsim_sim *sim, double t_end, double h, legsim_real *q) {
  const int n = (int)(t_end / h + 0.5);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, n));
  TEST_ASSERT_DOUBLE_WITHIN(1e-9, t_end, legsim_time(sim));
  legsim_get_q(sim, q);
}

static void test_integrators_agree_at_small_steps(void) {
  legsim_real qa[NQ], qb[NQ], qc[NQ];
  legsim_sim *a = leg_at_stand(&st, &legsim_model_leg_revolute, opts(LEGSIM_INTEGRATOR_RK4, 1e-4));
  run_free_fall(a, 0.1, 1e-4, qa);
  legsim_sim *b = leg_at_stand(&st2, &legsim_model_leg_revolute,
                               opts(LEGSIM_INTEGRATOR_GENERALIZED_ALPHA, 1e-4));
  run_free_fall(b, 0.1, 1e-4, qb);
  const double d_small = max_abs_diff(qa, qb, NQ);
  b = leg_at_stand(&st2, &legsim_model_leg_revolute, opts(LEGSIM_INTEGRATOR_GENERALIZED_ALPHA, 1e-3));
  run_free_fall(b, 0.1, 1e-3, qc);
  const double d_large = max_abs_diff(qa, qc, NQ);
  printf("free fall 0.1 s, max |q_rk4 - q_ga|: h = 1e-4: %.3g, ga at 1e-3: %.3g\n", d_small, d_large);
  TEST_ASSERT_TRUE(d_small < 1e-8);
  /* second order: ten times the step, about a hundred times the difference */
  TEST_ASSERT_TRUE(d_large > 30 * d_small && d_large < 300 * d_small);
  legsim_real res;
  legsim_constraints(b, NULL, &res);
  TEST_ASSERT_TRUE(res < 1e-10); /* index 3: the positions satisfy Phi = 0 */
}

/* Re-sending the same command every step (as a controller does) must not
 * restart the generalized-alpha history: it stays second order. */
static void test_generalized_alpha_order_survives_resent_commands(void) {
  legsim_real ref[NQ], q[NQ];
  legsim_sim *sim = leg_at_stand(&st2, &legsim_model_leg_revolute, opts(LEGSIM_INTEGRATOR_RK4, 1e-4));
  legsim_command_force(sim, 0, 40.0);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 3000));
  legsim_get_q(sim, ref);
  double err[2];
  for (int e = 0; e < 2; ++e) {
    const double h = e ? 1e-3 : 2e-3;
    sim = leg_at_stand(&st, &legsim_model_leg_revolute, opts(LEGSIM_INTEGRATOR_GENERALIZED_ALPHA, h));
    const int n = (int)(0.3 / h + 0.5);
    for (int i = 0; i < n; ++i) {
      legsim_command_force(sim, 0, 40.0);
      legsim_command_force(sim, 1, 0.0);
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 1));
    }
    legsim_get_q(sim, q);
    err[e] = max_abs_diff(q, ref, NQ);
  }
  printf("generalized-alpha with re-sent commands: error %.3g at h = 2 ms, %.3g at 1 ms (ratio %.2f)\n",
         err[0], err[1], err[0] / err[1]);
  TEST_ASSERT_TRUE(err[0] / err[1] > 3.0);
}

/* A controller that changes its force command every step (a setpoint that follows a sine,
 * h = 1 ms): each step restarts from the accelerations under the new command, reusing what
 * depends on the state alone. Against a full restart before every step (legsim_set_state
 * with the same state: a fresh factorization, the generalized-alpha history from scratch):
 * RK4 gives the same trajectory to the last bit, generalized-alpha the same to within its
 * Newton tolerance's effect, in about one Newton iteration a step instead of two. */
static void test_a_command_changed_every_step(void) {
  for (int g = 0; g < 2; ++g) {
    const legsim_integrator integ = g ? LEGSIM_INTEGRATOR_GENERALIZED_ALPHA : LEGSIM_INTEGRATOR_RK4;
    legsim_sim *a = leg_at_stand(&st, &legsim_model_leg_revolute, opts(integ, 1e-3));
    legsim_sim *b = leg_at_stand(&st2, &legsim_model_leg_revolute, opts(integ, 1e-3));
    double worst_q = 0, worst_qd = 0;
    long iterations_a = 0, iterations_b = 0;
    const int n = 500;
    for (int i = 0; i < n; ++i) {
      const double force = 50.0 + 10.0 * sin(4 * 3.14159265358979323846 * i * 1e-3); /* 2 Hz */
      legsim_real q[NQ], qd[NQ], qb[NQ], qdb[NQ];
      legsim_report r;
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_force(a, 0, force));
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(a, 1));
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_get_report(a, &r));
      iterations_a += r.iterations;
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_force(b, 0, force));
      legsim_get_q(b, qb);
      legsim_get_qd(b, qdb);
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_set_state(b, qb, qdb, legsim_time(b)));
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(b, 1));
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_get_report(b, &r));
      iterations_b += r.iterations;
      legsim_get_q(a, q);
      legsim_get_qd(a, qd);
      legsim_get_q(b, qb);
      legsim_get_qd(b, qdb);
      worst_q = fmax(worst_q, max_abs_diff(q, qb, NQ));
      worst_qd = fmax(worst_qd, max_abs_diff(qd, qdb, NQ));
    }
    TEST_ASSERT_EQUAL_UINT32(0, legsim_stroke_event_mask(a)); /* no stop: the two runs alike */
    printf("%s, a new command every step, against a full restart every step: max |dq| %.3g, "
           "max |dqd| %.3g; Newton iterations a step %.3f (full restart %.3f)\n",
           g ? "generalized-alpha" : "RK4", worst_q, worst_qd, (double)iterations_a / n,
           (double)iterations_b / n);
    if (!g) {
      TEST_ASSERT_EQUAL_DOUBLE(0.0, worst_q);
      TEST_ASSERT_EQUAL_DOUBLE(0.0, worst_qd);
    } else {
      TEST_ASSERT_TRUE(worst_q < 1e-7 && worst_qd < 1e-6);
      TEST_ASSERT_TRUE((double)iterations_a / n < 1.4);
      TEST_ASSERT_TRUE((double)iterations_b / n >= 2.0); /* what a fresh start costs */
    }
  }
}

/* Newton-Euler of the shank, which is the second body of both its joints: the
 * reported reactions (on the first bodies) act on it with the opposite sign. */
static void test_reactions_balance_the_shank(void) {
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, opts(LEGSIM_INTEGRATOR_RK4, 1e-3));
  const legsim_model_desc *m = legsim_model(sim);
  legsim_command_force(sim, 0, 70.0);
  legsim_command_force(sim, 1, -20.0);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 150));
  legsim_real q[NQ], qdd[NQ];
  legsim_reaction r[NJ];
  legsim_get_q(sim, q);
  legsim_get_qdd(sim, qdd);
  legsim_reactions(sim, r);
  const int b = 5;                 /* shank */
  const int joints[2] = {5, 7};    /* C_rod_shank (at its proximal end), D (at xi = -0.10) */
  const double xi[2] = {-0.30, -0.10};
  const double mass = m->body[b].mass_kg, inertia = m->body[b].inertia_kgm2;
  double fx = mass * m->gravity_mps2[0], fy = mass * m->gravity_mps2[1], mz = 0;
  for (int k = 0; k < 2; ++k) {
    double p[2];
    body_point(q, b, xi[k], 0, p);
    const double sx = p[0] - q[3 * b], sy = p[1] - q[3 * b + 1];
    const double rx = -r[joints[k]].force_n[0], ry = -r[joints[k]].force_n[1];
    fx += rx;
    fy += ry;
    mz += sx * ry - sy * rx;
  }
  TEST_ASSERT_TRUE(fabs(fx) > 1.0); /* it is loaded and accelerating */
  TEST_ASSERT_DOUBLE_WITHIN(1e-8, mass * qdd[3 * b], fx);
  TEST_ASSERT_DOUBLE_WITHIN(1e-8, mass * qdd[3 * b + 1], fy);
  TEST_ASSERT_DOUBLE_WITHIN(1e-8, inertia * qdd[3 * b + 2], mz);
}

static void test_slot_reaction_is_normal_to_the_shank(void) {
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_slot, opts(LEGSIM_INTEGRATOR_RK4, 1e-3));
  legsim_command_force(sim, 0, -80.0);
  for (int i = 0; i < 5; ++i) {
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 20));
    legsim_real q[NQ];
    legsim_reaction r[NJ];
    legsim_get_q(sim, q);
    legsim_reactions(sim, r);
    const double phi6 = q[17], ux = sin(phi6), uy = -cos(phi6);
    const double along = r[7].force_n[0] * ux + r[7].force_n[1] * uy;
    const double mag = hypot(r[7].force_n[0], r[7].force_n[1]);
    TEST_ASSERT_TRUE(mag > 1e-3); /* it carries load */
    TEST_ASSERT_DOUBLE_WITHIN(1e-9 * mag, 0.0, along);
  }
}

static void test_servo_holds_a_length_and_saturation_is_reported(void) {
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, opts(LEGSIM_INTEGRATOR_RK4, 1e-3));
  legsim_real len[NA], f[NA];
  legsim_actuator_lengths(sim, len, NULL);
  for (int a = 0; a < NA; ++a) TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_length(sim, a, len[a]));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 3000));
  legsim_real now[NA];
  legsim_actuator_lengths(sim, now, NULL);
  legsim_actuator_forces(sim, f);
  /* the servo's steady error carries the static load: F = kp (l_cmd - l) */
  const double kp = legsim_model_leg_revolute.actuator[0].servo_kp_n_per_m;
  TEST_ASSERT_DOUBLE_WITHIN(1e-3, len[0] - now[0], f[0] / kp);
  TEST_ASSERT_TRUE(fabs(now[0] - len[0]) < 0.01);
  legsim_report rep;
  legsim_get_report(sim, &rep);
  TEST_ASSERT_FALSE(rep.events & LEGSIM_EVENT_FORCE_SATURATED);
  /* a far command asks kp * 0.2 m = 4000 N > 1500 N */
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_length(sim, 1, len[1] - 0.2));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 1));
  legsim_get_report(sim, &rep);
  TEST_ASSERT_TRUE(rep.events & LEGSIM_EVENT_FORCE_SATURATED);
  legsim_actuator_forces(sim, f);
  TEST_ASSERT_DOUBLE_WITHIN(1e-9, -1500.0, f[1]);
}

static void test_stroke_end_stops_the_actuator_and_says_so(void) {
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, opts(LEGSIM_INTEGRATOR_RK4, 1e-3));
  legsim_command_force(sim, 1, -400.0); /* retract the lower actuator hard */
  double shortest = 1;
  for (int i = 0; i < 400; ++i) {
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 1));
    legsim_real len[NA];
    legsim_actuator_lengths(sim, len, NULL);
    shortest = fmin(shortest, len[1]);
  }
  legsim_report rep;
  legsim_get_report(sim, &rep);
  TEST_ASSERT_TRUE(rep.events & LEGSIM_EVENT_STROKE_MIN);
  TEST_ASSERT_EQUAL_UINT32(2u, legsim_stroke_event_mask(sim));
  TEST_ASSERT_TRUE(shortest >= 0.35 - 1e-9);
  legsim_real res;
  legsim_constraints(sim, NULL, &res);
  TEST_ASSERT_TRUE(res < 1e-9);
}

/* Resting on a stroke stop: the stop carries load, so the accelerations vanish and
 * the reactions and the actuator's axial force are those of statics at that pose;
 * a force away from the stop lets go of it. */
static void test_resting_on_a_stop_matches_statics_and_releases(void) {
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, opts(LEGSIM_INTEGRATOR_RK4, 1e-3));
  legsim_real len[NA];
  legsim_actuator_lengths(sim, len, NULL);
  legsim_command_length(sim, 0, len[0]);  /* the upper servo holds (and damps) */
  legsim_command_force(sim, 1, -400.0);   /* the lower actuator pulls into its 0.35 m end */
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 4000));
  legsim_real qd[NQ], qdd[NQ], f[NA], f_st[NA], now[NA];
  legsim_reaction r[NJ], r_st[NJ];
  legsim_get_qd(sim, qd);
  legsim_get_qdd(sim, qdd);
  legsim_actuator_lengths(sim, now, NULL);
  legsim_actuator_forces(sim, f);
  legsim_reactions(sim, r);
  double vmax = 0, amax = 0;
  for (int k = 0; k < NQ; ++k) {
    vmax = fmax(vmax, fabs(qd[k]));
    amax = fmax(amax, fabs(qdd[k]));
  }
  printf("on the stop: lower %.9f m, max |qd| %.2e, max |qdd| %.2e, forces %.3f %.3f N\n", now[1], vmax,
         amax, f[0], f[1]);
  TEST_ASSERT_DOUBLE_WITHIN(1e-9, 0.35, now[1]);
  TEST_ASSERT_TRUE(vmax < 1e-3 && amax < 1e-2);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_statics(sim, f_st));
  legsim_reactions(sim, r_st);
  TEST_ASSERT_DOUBLE_WITHIN(0.05, f_st[0], f[0]);
  TEST_ASSERT_DOUBLE_WITHIN(0.05, f_st[1], f[1]);
  TEST_ASSERT_TRUE(f[1] > -400.0 + 1.0); /* the stop takes part of the pull */
  for (int j = 0; j < NJ; ++j) {
    TEST_ASSERT_DOUBLE_WITHIN(0.05, r_st[j].force_n[0], r[j].force_n[0]);
    TEST_ASSERT_DOUBLE_WITHIN(0.05, r_st[j].force_n[1], r[j].force_n[1]);
  }
  /* push away from the stop: it lets go (assembled at the stop's length: the state holds it
   * to round-off, on either side) */
  now[1] = 0.35;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble(sim, now));
  legsim_command_force(sim, 1, 0.0);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 50));
  legsim_command_force(sim, 1, -400.0);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 200));
  legsim_command_force(sim, 1, 300.0);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 100));
  legsim_actuator_lengths(sim, now, NULL);
  TEST_ASSERT_TRUE(now[1] > 0.36);
}

/* The lower stroke ends at 0.70 m, where the knee is straight: a stroke end at a
 * dead centre. Driving into it must not fail the run, nor pass the end. */
static void test_stroke_end_at_the_straight_knee(void) {
  for (int integ = 0; integ < 2; ++integ) {
    legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, opts((legsim_integrator)integ, 1e-3));
    legsim_command_force(sim, 1, 300.0); /* extend the lower actuator: straighten the knee */
    double longest = 0;
    for (int i = 0; i < 1500; ++i) {
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 1));
      legsim_real len[NA];
      legsim_actuator_lengths(sim, len, NULL);
      longest = fmax(longest, len[1]);
    }
    legsim_report rep;
    legsim_get_report(sim, &rep);
    printf("straight knee (%s): longest lower length %.9f, events 0x%x\n",
           integ ? "generalized-alpha" : "rk4", longest, (unsigned)rep.events);
    TEST_ASSERT_TRUE(longest <= 0.70 + 1e-9);
    TEST_ASSERT_TRUE(longest > 0.6999); /* it went all the way to the straight knee */
  }
}

static void test_scene_options_skip_what_is_disabled(void) {
  legsim_options o = opts(LEGSIM_INTEGRATOR_RK4, 1e-3);
  o.disable = LEGSIM_DISABLE_GRAVITY | LEGSIM_DISABLE_REACTIONS;
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, o);
  legsim_real q0[NQ], q1[NQ];
  legsim_get_q(sim, q0);
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 100));
  legsim_get_q(sim, q1);
  TEST_ASSERT_TRUE(max_abs_diff(q0, q1, NQ) < 1e-12); /* no load, no motion */
  legsim_reaction r[NJ];
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_DISABLED, legsim_reactions(sim, r));
  o.disable = 1u << 30;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_set_options(sim, &o));
}

static void test_bad_commands_change_nothing(void) {
  legsim_sim *sim = leg_at_stand(&st, &legsim_model_leg_revolute, opts(LEGSIM_INTEGRATOR_RK4, 1e-3));
  legsim_real f[NA];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_force(sim, 0, 50.0));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_command_force(sim, 0, NAN));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_command_force(sim, 0, INFINITY));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_command_force(sim, 0, 1500.1));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_command_force(sim, 2, 10.0));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_command_length(sim, 0, NAN));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_OUT_OF_STROKE, legsim_command_length(sim, 0, 0.39));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_OUT_OF_STROKE, legsim_command_length(sim, 1, 0.71));
  legsim_actuator_forces(sim, f);
  TEST_ASSERT_EQUAL_DOUBLE(50.0, f[0]);
  const legsim_real nan_load[2] = {NAN, 0};
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_set_force(sim, 0, nan_load));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_step(sim, -1));
  legsim_real q[NQ];
  legsim_get_q(sim, q);
  q[4] = NAN;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_set_state(sim, q, NULL, 0));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(sim, 10));
  legsim_get_q(sim, q);
  for (int k = 0; k < NQ; ++k) TEST_ASSERT_FALSE(isnan(q[k]));
}

static void test_too_large_a_step_fails_with_a_status_never_nan(void) {
  legsim_options o = opts(LEGSIM_INTEGRATOR_RK4, 0.2);
  legsim_sim *sim = NULL;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_init(st.bytes, sizeof st.bytes, &legsim_model_leg_revolute, &o, &sim));
  o = opts(LEGSIM_INTEGRATOR_RK4, LEGSIM_MAX_STEP_S); /* the largest step allowed */
  sim = leg_at_stand(&st, &legsim_model_leg_revolute, o);
  legsim_command_force(sim, 0, 1500.0);
  legsim_status s = LEGSIM_OK;
  for (int i = 0; i < 50 && s == LEGSIM_OK; ++i) s = legsim_step(sim, 1);
  legsim_real q[NQ];
  legsim_get_q(sim, q);
  for (int k = 0; k < NQ; ++k) TEST_ASSERT_TRUE(isfinite(q[k]));
  printf("h = %g s with 1500 N: %s after %llu steps\n", LEGSIM_MAX_STEP_S, legsim_status_str(s),
         (unsigned long long)legsim_step_count(sim));
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_energy_is_conserved_with_constant_forces);
  RUN_TEST(test_integrators_agree_at_small_steps);
  RUN_TEST(test_spring_and_torque_conserve_energy);
  RUN_TEST(test_generalized_alpha_order_survives_resent_commands);
  RUN_TEST(test_a_command_changed_every_step);
  RUN_TEST(test_reactions_balance_the_shank);
  RUN_TEST(test_slot_reaction_is_normal_to_the_shank);
  RUN_TEST(test_servo_holds_a_length_and_saturation_is_reported);
  RUN_TEST(test_stroke_end_stops_the_actuator_and_says_so);
  RUN_TEST(test_resting_on_a_stop_matches_statics_and_releases);
  RUN_TEST(test_stroke_end_at_the_straight_knee);
  RUN_TEST(test_scene_options_skip_what_is_disabled);
  RUN_TEST(test_bad_commands_change_nothing);
  RUN_TEST(test_too_large_a_step_fails_with_a_status_never_nan);
  return UNITY_END();
}
