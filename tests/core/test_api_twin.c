/* Seeded random call sequences on twin sims (issue 10): every call of a random
 * sequence goes to sim B first; when B refuses it, A never gets it, and the two
 * must still be equal bit for bit (q, qd, qdd, multipliers, reactions, actuator
 * forces, report, time); when B accepts it, A gets it too and must give the same
 * status and outputs. Between them, B alone gets calls that must be refused
 * whatever the state (NULLs, indices, NaN/Inf, finite-but-absurd values), and
 * after each one the twins are compared again. After every call B's outputs and
 * report are finite. The sequence mixes every entry point: steps (both
 * integrators), commands, loads, options, assemblies, driven analyses, statics,
 * sweeps, states set from outside; half the seeds use the slot leg, whose
 * statics and sweeps fail deep inside the solver.
 *
 *   test_api_twin [seeds [calls]]   (defaults 8 and 1000; built in double and float) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "leg_fixture.h"
#include "unity.h"

static fixture_storage st_a, st_b;
static int g_seeds = 8, g_calls = 1000;

void setUp(void) {}
void tearDown(void) {}

/* ---- a small deterministic generator (xorshift64*) ---- */
typedef struct rng {
  uint64_t s;
} rng;
static uint64_t next_u64(rng *r) {
  r->s ^= r->s >> 12;
  r->s ^= r->s << 25;
  r->s ^= r->s >> 27;
  return r->s * 2685821657736338717ull;
}
static int below(rng *r, int n) { return (int)(next_u64(r) % (uint64_t)n); }
static double uniform(rng *r, double lo, double hi) {
  return lo + (hi - lo) * (double)(next_u64(r) >> 11) * (1.0 / 9007199254740992.0);
}
static double hostile_value(rng *r) {
  static const double v[] = {NAN, INFINITY, -INFINITY, 1e308, -1e308, 1e200, -1e30, 1e30};
  return v[below(r, (int)(sizeof v / sizeof v[0]))];
}

/* ---- one call, drawn once and applied to either sim ---- */
enum kind {
  STEP, COMMAND_FORCE, COMMAND_LENGTH, SET_FORCE, SET_OPTIONS, ASSEMBLE, ASSEMBLE_LENGTHS,
  ASSEMBLE_POSE, VELOCITY, ACCELERATION, INVERSE_DYNAMICS, STATICS, SWEEP, SET_STATE,
  SET_STATE_NULL_QD, CLEAR_EVENTS, READ_ONLY, GET_NULL, N_KINDS
};
static const char *kind_name[N_KINDS] = {
    "step", "command_force", "command_length", "set_force", "set_options", "assemble(NULL)",
    "assemble(lengths)", "assemble_pose", "velocity_analysis", "acceleration_analysis",
    "inverse_dynamics", "statics", "statics_sweep", "set_state", "set_state(qd NULL)",
    "clear_events", "read-only", "get with NULL"};

typedef struct call {
  enum kind kind;
  int32_t i;
  legsim_real a[NQ], b[NQ], c[NA];
  double t;
  legsim_options o;
  int null_arg;
} call;

typedef struct outputs {
  legsim_real force[NA];
  legsim_worst_case wc;
  legsim_real phi[16], jac[16 * NQ], max_abs, foot[2];
} outputs;

static legsim_status run(legsim_sim *s, const call *c, outputs *out) {
  memset(out, 0, sizeof *out);
  switch (c->kind) {
    case STEP: return legsim_step(s, c->i);
    case COMMAND_FORCE: return legsim_command_force(s, c->i, c->a[0]);
    case COMMAND_LENGTH: return legsim_command_length(s, c->i, c->a[0]);
    case SET_FORCE: return legsim_set_force(s, c->i, c->null_arg ? NULL : c->a);
    case SET_OPTIONS: return legsim_set_options(s, c->null_arg ? NULL : &c->o);
    case ASSEMBLE: return legsim_assemble(s, NULL);
    case ASSEMBLE_LENGTHS: return legsim_assemble(s, c->a);
    case ASSEMBLE_POSE: return legsim_assemble_pose(s, c->i);
    case VELOCITY: return legsim_velocity_analysis(s, c->null_arg ? NULL : c->a);
    case ACCELERATION: return legsim_acceleration_analysis(s, c->null_arg ? NULL : c->a);
    case INVERSE_DYNAMICS:
      return legsim_inverse_dynamics(s, c->a, c->null_arg ? NULL : c->b, c->c, out->force);
    case STATICS: return legsim_statics(s, out->force);
    case SWEEP: return legsim_statics_sweep(s, c->i, c->null_arg ? NULL : &out->wc);
    case SET_STATE: return legsim_set_state(s, c->null_arg ? NULL : c->a, c->b, c->t);
    case SET_STATE_NULL_QD: return legsim_set_state(s, c->a, NULL, c->t);
    case CLEAR_EVENTS: return legsim_clear_events(s);
    case READ_ONLY: {
      legsim_status st = legsim_constraints(s, out->phi, &out->max_abs);
      if (st == LEGSIM_OK) st = legsim_jacobian(s, out->jac);
      if (st == LEGSIM_OK) st = legsim_foot_position(s, out->foot);
      return st;
    }
    case GET_NULL:
      switch (c->i) {
        case 0: return legsim_get_q(s, NULL);
        case 1: return legsim_get_qd(s, NULL);
        case 2: return legsim_get_qdd(s, NULL);
        case 3: return legsim_multipliers(s, NULL);
        case 4: return legsim_reactions(s, NULL);
        case 5: return legsim_get_report(s, NULL);
        case 6: return legsim_jacobian(s, NULL);
        default: return legsim_actuator_lengths(s, NULL, NULL);
      }
    case N_KINDS: break;
  }
  return LEGSIM_ERR_BAD_INPUT;
}

/* ---- draws ---- */
static const legsim_model_desc *g_model;

static void random_options(rng *r, legsim_options *o) {
  static const double steps[] = {1e-3, 5e-4, 2e-3, 1e-4};
  *o = legsim_default_options();
  o->integrator = below(r, 2) ? LEGSIM_INTEGRATOR_GENERALIZED_ALPHA : LEGSIM_INTEGRATOR_RK4;
  o->step_s = steps[below(r, 4)];
  o->disable = (uint32_t)below(r, 64) & (uint32_t)below(r, 64); /* mostly few flags */
  o->rho_inf = uniform(r, 0.0, 1.0);
  o->max_newton_iter = 1 + below(r, 30);
}

static void lengths_in_strokes(rng *r, legsim_real *len, double margin) {
  for (int k = 0; k < NA; ++k) {
    const legsim_actuator_desc *ad = &g_model->actuator[k];
    len[k] = (legsim_real)uniform(r, ad->stroke_min_m - margin, ad->stroke_max_m + margin);
  }
}

/* A call of the random sequence: mostly sensible, sometimes not (then B refuses it). */
static void random_call(rng *r, const legsim_sim *b, call *c) {
  memset(c, 0, sizeof *c);
  c->kind = (enum kind)below(r, N_KINDS);
  const int odd = below(r, 12) == 0; /* one in twelve: a bad argument */
  switch (c->kind) {
    case STEP: c->i = odd ? -1 : (below(r, 10) ? 1 + below(r, 20) : 100 + below(r, 200)); break;
    case COMMAND_FORCE:
      c->i = odd ? 2 : below(r, NA);
      c->a[0] = (legsim_real)uniform(r, -1600, 1600);
      break;
    case COMMAND_LENGTH:
      c->i = below(r, NA);
      lengths_in_strokes(r, c->a, odd ? 0.1 : 0.0);
      c->a[0] = c->a[c->i];
      break;
    case SET_FORCE:
      c->i = odd ? 1 : 0;
      c->a[0] = (legsim_real)uniform(r, -300, 300);
      c->a[1] = (legsim_real)(below(r, 20) ? uniform(r, -300, 300) : uniform(r, -1e6, 1e6));
      break;
    case SET_OPTIONS:
      random_options(r, &c->o);
      if (odd) c->o.newton_tol = 1e300;
      break;
    case ASSEMBLE_LENGTHS: lengths_in_strokes(r, c->a, odd ? 0.2 : 0.0); break;
    case ASSEMBLE_POSE: c->i = odd ? 1 : 0; break;
    case VELOCITY:
    case ACCELERATION:
      for (int k = 0; k < NA; ++k) c->a[k] = (legsim_real)uniform(r, -0.5, 0.5);
      if (odd) c->a[0] = (legsim_real)1e30;
      break;
    case INVERSE_DYNAMICS:
      legsim_actuator_lengths(b, c->a, NULL);
      for (int k = 0; k < NA; ++k) {
        c->a[k] += (legsim_real)uniform(r, -0.01, 0.01);
        c->b[k] = (legsim_real)uniform(r, -0.3, 0.3);
        c->c[k] = (legsim_real)uniform(r, -3, 3);
      }
      if (odd) c->c[1] = NAN;
      break;
    case SWEEP: c->i = odd ? 1 : 2 + below(r, 3); break;
    case SET_STATE:
    case SET_STATE_NULL_QD:
      legsim_get_q(b, c->a);
      for (int k = 0; k < NQ; ++k) {
        c->a[k] += (legsim_real)(below(r, 3) ? 0.0 : uniform(r, -1e-3, 1e-3));
        c->b[k] = (legsim_real)uniform(r, -0.5, 0.5);
      }
      c->t = uniform(r, 0, 10);
      if (odd) c->b[below(r, NQ)] = (legsim_real)1e155;
      break;
    case GET_NULL: c->i = below(r, 8); break;
    default: break;
  }
}

/* A call that must be refused whatever the state. */
static void hostile_call(rng *r, call *c) {
  memset(c, 0, sizeof *c);
  const double h = hostile_value(r);
  switch (below(r, 16)) {
    case 0: c->kind = STEP; c->i = -1 - below(r, 1000); break;
    case 1:
      c->kind = COMMAND_FORCE;
      c->i = below(r, 2) ? below(r, NA) : 2 + below(r, 5);
      c->a[0] = (legsim_real)(below(r, 2) ? h : 1.01 * g_model->actuator[0].max_force_n * (below(r, 2) ? 1 : -1));
      break;
    case 2:
      c->kind = COMMAND_LENGTH;
      c->i = below(r, NA);
      c->a[0] = (legsim_real)(below(r, 2) ? h : g_model->actuator[c->i].stroke_max_m + 0.01);
      break;
    case 3:
      c->kind = SET_FORCE;
      c->i = below(r, 3) ? 0 : (below(r, 2) ? -1 : 1 + below(r, 50));
      c->a[below(r, 2)] = (legsim_real)(below(r, 2) ? h : 2 * LEGSIM_MAX_FORCE_N);
      c->null_arg = below(r, 8) == 0;
      break;
    case 4: {
      c->kind = SET_OPTIONS;
      random_options(r, &c->o);
      const int32_t raw = below(r, 2) ? 7 : -1;
      switch (below(r, 8)) {
        case 0: c->o.step_s = below(r, 2) ? 5e-324 : h; break;
        case 1: c->o.step_s = 1.0; break;
        case 2: c->o.newton_tol = below(r, 2) ? 1e300 : 0.0; break;
        case 3: memcpy(&c->o.integrator, &raw, sizeof raw); break;
        case 4: c->o.rho_inf = 1.5; break;
        case 5: c->o.max_newton_iter = below(r, 2) ? 0 : 100000; break;
        case 6: c->o.disable = 1u << (6 + below(r, 26)); break;
        default: c->null_arg = 1; break;
      }
      break;
    }
    case 5:
      c->kind = ASSEMBLE_LENGTHS;
      lengths_in_strokes(r, c->a, 0.0);
      c->a[below(r, NA)] = (legsim_real)(below(r, 2) ? h : 0.01);
      break;
    case 6: c->kind = ASSEMBLE_POSE; c->i = below(r, 2) ? -1 : 1 + below(r, 100); break;
    case 7:
    case 8:
      c->kind = below(r, 2) ? VELOCITY : ACCELERATION;
      c->a[below(r, NA)] = (legsim_real)h;
      c->null_arg = below(r, 6) == 0;
      break;
    case 9:
      c->kind = INVERSE_DYNAMICS;
      lengths_in_strokes(r, c->a, 0.0);
      (below(r, 2) ? c->b : c->c)[below(r, NA)] = (legsim_real)h;
      c->null_arg = below(r, 6) == 0;
      break;
    case 10:
      c->kind = SWEEP;
      c->i = below(r, 2) ? 1 - below(r, 5) : LEGSIM_MAX_GRID + 1 + below(r, 5);
      c->null_arg = below(r, 2) ? 0 : (c->i = 3, 1);
      break;
    case 11:
    case 12:
      c->kind = below(r, 2) ? SET_STATE : SET_STATE_NULL_QD;
      for (int k = 0; k < NQ; ++k) c->a[k] = (legsim_real)uniform(r, -1, 1);
      switch (below(r, 4)) {
        case 0: c->a[below(r, NQ)] = (legsim_real)h; break;
        case 1: c->kind = SET_STATE; c->b[below(r, NQ)] = (legsim_real)(below(r, 2) ? h : 1e155); break;
        case 2: c->t = below(r, 2) ? NAN : 1e300; break;
        default: c->kind = SET_STATE; c->null_arg = 1; break;
      }
      break;
    default: c->kind = GET_NULL; c->i = below(r, 8); break;
  }
}

/* ---- comparisons ---- */
typedef struct observed {
  legsim_real q[NQ], qd[NQ], qdd[NQ], lambda[16], force[NA], len[NA];
  legsim_reaction reaction[NJ];
  int32_t iterations, reactions_status;
  legsim_real residual, condition;
  uint32_t events, stroke_mask;
  double t;
  uint64_t steps;
} observed;

static void observe(const legsim_sim *s, observed *o) {
  memset(o, 0, sizeof *o);
  legsim_report r;
  legsim_get_q(s, o->q);
  legsim_get_qd(s, o->qd);
  legsim_get_qdd(s, o->qdd);
  legsim_multipliers(s, o->lambda);
  legsim_actuator_forces(s, o->force);
  legsim_actuator_lengths(s, o->len, NULL);
  o->reactions_status = legsim_reactions(s, o->reaction);
  legsim_get_report(s, &r);
  o->iterations = r.iterations;
  o->residual = r.residual;
  o->condition = r.condition;
  o->events = r.events;
  o->stroke_mask = legsim_stroke_event_mask(s);
  o->t = legsim_time(s);
  o->steps = legsim_step_count(s);
}

static char g_where[200];

static void assert_twins(const legsim_sim *a, const legsim_sim *b) {
  observed x, y;
  observe(a, &x);
  observe(b, &y);
  if (memcmp(&x, &y, sizeof x) == 0) return;
  char m[400];
  const char *what = memcmp(x.q, y.q, sizeof x.q)              ? "q"
                     : memcmp(x.qd, y.qd, sizeof x.qd)          ? "qd"
                     : memcmp(x.qdd, y.qdd, sizeof x.qdd)       ? "qdd"
                     : memcmp(x.lambda, y.lambda, sizeof x.lambda) ? "multipliers"
                     : memcmp(x.reaction, y.reaction, sizeof x.reaction) ? "reactions"
                     : (x.residual != y.residual || x.condition != y.condition ||
                        x.iterations != y.iterations || x.events != y.events) ? "report"
                                                                              : "forces, time or steps";
  snprintf(m, sizeof m, "%s: the twins differ in %s (max |dq| %g, |dqdd| %g)", g_where, what,
           max_abs_diff(x.q, y.q, NQ), max_abs_diff(x.qdd, y.qdd, NQ));
  TEST_FAIL_MESSAGE(m);
}

static void assert_finite(const legsim_sim *s) {
  observed o;
  observe(s, &o);
  int ok = isfinite(o.residual) && isfinite(o.condition);
  for (int k = 0; k < NQ; ++k) ok = ok && isfinite(o.q[k]) && isfinite(o.qd[k]) && isfinite(o.qdd[k]);
  for (int i = 0; i < 16; ++i) ok = ok && isfinite(o.lambda[i]);
  for (int j = 0; j < NJ; ++j)
    ok = ok && isfinite(o.reaction[j].force_n[0]) && isfinite(o.reaction[j].force_n[1]) &&
         isfinite(o.reaction[j].moment_nm);
  for (int k = 0; k < NA; ++k) ok = ok && isfinite(o.force[k]);
  if (!ok) {
    char m[300];
    snprintf(m, sizeof m, "%s: an output or the report is not finite (residual %g, condition %g)",
             g_where, (double)o.residual, (double)o.condition);
    TEST_FAIL_MESSAGE(m);
  }
}

/* ---- the run ---- */
typedef struct tally {
  long calls, refused, hostile, partial_steps, ok_by_kind[N_KINDS], refused_by_kind[N_KINDS];
} tally;

static void run_seed(uint64_t seed, int n_calls, tally *t) {
  rng r = {seed * 0x9E3779B97F4A7C15ull + 1};
  g_model = (seed % 2) ? &legsim_model_leg_slot : &legsim_model_leg_revolute;
  legsim_options o;
  random_options(&r, &o);
  legsim_sim *a = leg_at_stand(&st_a, g_model, o);
  legsim_sim *b = leg_at_stand(&st_b, g_model, o);
  for (int n = 0; n < n_calls; ++n) {
    call c;
    outputs oa, ob;
    random_call(&r, b, &c);
    const uint64_t steps_before = legsim_step_count(b);
    const legsim_status sb = run(b, &c, &ob);
    snprintf(g_where, sizeof g_where, "seed %llu, call %d: %s -> %s", (unsigned long long)seed, n,
             kind_name[c.kind], legsim_status_str(sb));
    ++t->calls;
    if (sb != LEGSIM_OK && legsim_step_count(b) != steps_before) {
      /* legsim_step(n) keeps the steps made before the one that failed (each step is
       * all or nothing): A makes the same call and must end the same way */
      ++t->partial_steps;
      TEST_ASSERT_EQUAL_INT_MESSAGE(sb, run(a, &c, &oa), g_where);
    } else if (sb != LEGSIM_OK) {
      ++t->refused;
      ++t->refused_by_kind[c.kind];
    } else {
      ++t->ok_by_kind[c.kind];
      const legsim_status sa = run(a, &c, &oa);
      TEST_ASSERT_EQUAL_INT_MESSAGE(LEGSIM_OK, sa, g_where);
      TEST_ASSERT_EQUAL_MEMORY_MESSAGE(&oa, &ob, sizeof oa, g_where);
    }
    assert_twins(a, b);
    assert_finite(b);
    if (below(&r, 3) == 0) {
      hostile_call(&r, &c);
      const legsim_status sh = run(b, &c, &ob);
      snprintf(g_where, sizeof g_where, "seed %llu, after call %d: hostile %s -> %s",
               (unsigned long long)seed, n, kind_name[c.kind], legsim_status_str(sh));
      ++t->hostile;
      TEST_ASSERT_TRUE_MESSAGE(sh != LEGSIM_OK, g_where);
      assert_twins(a, b);
      assert_finite(b);
    }
  }
}

static void test_refused_calls_change_nothing(void) {
  tally t;
  memset(&t, 0, sizeof t);
  for (int s = 0; s < g_seeds; ++s) run_seed((uint64_t)s, g_calls, &t);
  printf("%s: %d seeds: %ld calls (%ld refused by the sim as drawn, %ld multi-step calls stopped "
         "by a failing step) + %ld hostile calls, all refused; twins equal bit for bit after each\n",
         LEGSIM_USE_FLOAT ? "float" : "double", g_seeds, t.calls, t.refused, t.partial_steps, t.hostile);
  for (int k = 0; k < N_KINDS; ++k)
    printf("  %-22s ok %4ld  refused %4ld\n", kind_name[k], t.ok_by_kind[k], t.refused_by_kind[k]);
  /* the sequence does reach the deep refusals, and does real work */
  TEST_ASSERT_GREATER_THAN_INT(0, (int)t.refused_by_kind[SWEEP]);
  TEST_ASSERT_GREATER_THAN_INT(0, (int)t.refused_by_kind[STATICS]);
  TEST_ASSERT_GREATER_THAN_INT(0, (int)t.ok_by_kind[SWEEP]);
  TEST_ASSERT_GREATER_THAN_INT(50, (int)t.ok_by_kind[STEP]);
}

/* A controller's loop: a new length command every step (RK4 restarts from it), and on B
 * alone a refused assembly (both strokes at an end: unreachable) before each step. A
 * refused call puts the state back, not the workspace: the restart must not depend on
 * what the workspace holds (the last step's factor, or not). */
static void test_refused_calls_between_new_commands(void) {
  for (int integ = 0; integ < 2; ++integ) {
    legsim_options o = legsim_default_options();
    o.integrator = integ ? LEGSIM_INTEGRATOR_GENERALIZED_ALPHA : LEGSIM_INTEGRATOR_RK4;
    legsim_sim *a = leg_at_stand(&st_a, &legsim_model_leg_revolute, o);
    legsim_sim *b = leg_at_stand(&st_b, &legsim_model_leg_revolute, o);
    const legsim_model_desc *m = legsim_model(b);
    const legsim_real unreachable[2] = {(legsim_real)m->actuator[0].stroke_min_m,
                                        (legsim_real)m->actuator[1].stroke_max_m};
    legsim_real len[NA];
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_actuator_lengths(a, len, NULL));
    for (int k = 0; k < 200; ++k) {
      snprintf(g_where, sizeof g_where, "%s, step %d", integ ? "generalized-alpha" : "RK4", k);
      TEST_ASSERT_TRUE_MESSAGE(legsim_assemble(b, unreachable) != LEGSIM_OK, g_where);
      const legsim_real l = len[0] + (legsim_real)(0.0005 * sin(0.05 * k));
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_length(a, 0, l));
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_command_length(b, 0, l));
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(a, 1));
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_step(b, 1));
      assert_twins(a, b);
    }
  }
}

int main(int argc, char **argv) {
  if (argc > 1) g_seeds = atoi(argv[1]);
  if (argc > 2) g_calls = atoi(argv[2]);
  UNITY_BEGIN();
  RUN_TEST(test_refused_calls_change_nothing);
  RUN_TEST(test_refused_calls_between_new_commands);
  return UNITY_END();
}
