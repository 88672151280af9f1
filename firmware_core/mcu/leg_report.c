/* The leg report (see leg_report.h): platform-independent, C API only. */
#include "leg_report.h"

#include <math.h>

#include "legsim/legsim.h"
#include "legsim/models.h"
#include "out.h"

#if LEGSIM_USE_FLOAT
#define REAL_NAME "float"
#define REAL_DECIMALS 7
#else
#define REAL_NAME "double"
#define REAL_DECIMALS 12
#endif

#define N_STEPS 100

static const leg_report_platform *pf_;

static uint32_t ticks(void) { return pf_->timer_ticks ? pf_->timer_ticks() : 0u; }

static void out_real_n(legsim_real v) { out_real((double)v, REAL_DECIMALS); }

static int failed(const char *what, legsim_status s) {
  if (s == LEGSIM_OK) return 0;
  out_str(what);
  out_str(" failed: ");
  out_str(legsim_status_str(s));
  out_str(" (");
  out_int(s);
  out_str(")\n");
  return 1;
}

/* world position of a body-fixed point (xi, eta): r + xi*u + eta*n, with
 * u = (sin phi, -cos phi), n = (cos phi, sin phi) (models/leg.toml) */
static void body_point(const legsim_real *q, int32_t body, const double *p, double *xy) {
  const double x = (double)q[3 * body], y = (double)q[3 * body + 1];
  /* in the build's precision (no double sin/cos on the M4F just for printing) */
#if LEGSIM_USE_FLOAT
  const double s = (double)sinf(q[3 * body + 2]), c = (double)cosf(q[3 * body + 2]);
#else
  const double s = sin(q[3 * body + 2]), c = cos(q[3 * body + 2]);
#endif
  xy[0] = x + p[0] * s + p[1] * c;
  xy[1] = y - p[0] * c + p[1] * s;
}

static void print_q_foot(const char *prefix, const legsim_sim *sim) {
  legsim_real q[3 * LEGSIM_MAX_BODIES];
  legsim_real foot[2];
  const int32_t nb = legsim_n_bodies(sim);
  if (legsim_get_q(sim, q) != LEGSIM_OK) return;
  for (int32_t b = 0; b < nb; ++b) {
    out_str(prefix);
    out_str(" q ");
    out_int(b);
    for (int k = 0; k < 3; ++k) {
      out_char(' ');
      out_real_n(q[3 * b + k]);
    }
    out_char('\n');
  }
  if (legsim_foot_position(sim, foot) == LEGSIM_OK) {
    out_str(prefix);
    out_str(" foot ");
    out_real_n(foot[0]);
    out_char(' ');
    out_real_n(foot[1]);
    out_char('\n');
  }
}

static void print_joints(const legsim_sim *sim) {
  const legsim_model_desc *m = legsim_model(sim);
  legsim_real q[3 * LEGSIM_MAX_BODIES];
  if (!m || legsim_get_q(sim, q) != LEGSIM_OK) return;
  for (int32_t j = 0; j < m->n_joints; ++j) {
    const legsim_joint_desc *jd = &m->joint[j];
    if (jd->kind == LEGSIM_JOINT_PRISMATIC) continue;
    double xy[2];
    body_point(q, jd->body[0], jd->point[0], xy);
    out_str("stand joint ");
    out_str(jd->name);
    out_char(' ');
    out_real(xy[0], REAL_DECIMALS);
    out_char(' ');
    out_real(xy[1], REAL_DECIMALS);
    out_char('\n');
  }
}

static int run_integrator(legsim_sim *sim, legsim_integrator integrator, const char *name) {
  legsim_options opts = legsim_default_options();
  opts.integrator = integrator;
  legsim_status s = legsim_set_options(sim, &opts);
  if (s == LEGSIM_ERR_DISABLED) {
    out_str("step ");
    out_str(name);
    out_str(" disabled\n");
    return 0;
  }
  if (failed("legsim_set_options", s)) return 1;
  /* from the stand pose, at rest, at t = 0 */
  legsim_real q[3 * LEGSIM_MAX_BODIES];
  if (failed("legsim_assemble_pose", legsim_assemble_pose(sim, 0))) return 1;
  if (failed("legsim_get_q", legsim_get_q(sim, q))) return 1;
  if (failed("legsim_set_state", legsim_set_state(sim, q, 0, 0.0))) return 1;

  uint64_t sum = 0;
  uint32_t lo = UINT32_MAX, hi = 0;
  int32_t done = 0;
  for (; done < N_STEPS; ++done) {
    const uint32_t t0 = ticks();
    s = legsim_step(sim, 1);
    const uint32_t dt = (ticks() - t0) * pf_->insns_per_tick;
    if (s != LEGSIM_OK) break;
    sum += dt;
    if (dt < lo) lo = dt;
    if (dt > hi) hi = dt;
  }
  out_str("step ");
  out_str(name);
  out_str(" status ");
  out_int(s);
  out_str(" steps ");
  out_int(done);
  out_str(" t ");
  out_real(legsim_time(sim), REAL_DECIMALS);
  out_char('\n');
  char prefix[48] = "step ";
  {
    int i = 5;
    for (const char *c = name; *c && i < (int)sizeof prefix - 1; ++c) prefix[i++] = *c;
    prefix[i] = '\0';
  }
  print_q_foot(prefix, sim);
  if (done > 0) {
    out_str(prefix);
    out_str(" insns_per_step mean ");
    out_uint(sum / (uint64_t)done);
    out_str(" min ");
    out_uint(lo);
    out_str(" max ");
    out_uint(hi);
    out_char('\n');
  }
  return failed(name, s);
}

int leg_report_run(void *storage, size_t storage_bytes, const leg_report_platform *pf) {
  pf_ = pf;
  if (pf->timer_start) pf->timer_start();

  out_str("legsim-mcu board ");
  out_str(pf->board);
  out_str(" cpu ");
  out_str(pf->cpu);
  out_str(" real " REAL_NAME "\n");

  const size_t need = legsim_sim_size();
  out_str("sim_size ");
  out_uint(need);
  out_str(" storage ");
  out_uint(storage_bytes);
  out_char('\n');
  if (need > storage_bytes) {
    out_str("storage too small: raise LEGSIM_MCU_STORAGE_BYTES\n");
    out_str("done status 2\n");
    return 2;
  }

  legsim_options opts = legsim_default_options();
  legsim_sim *sim = 0;
  if (failed("legsim_init",
             legsim_init(storage, storage_bytes, &legsim_model_leg_revolute, &opts, &sim))) {
    out_str("done status 1\n");
    return 1;
  }
  out_str("model ");
  out_str(legsim_model(sim)->name);
  out_str(" bodies ");
  out_int(legsim_n_bodies(sim));
  out_str(" coords ");
  out_int(legsim_n_coords(sim));
  out_str(" constraints ");
  out_int(legsim_n_constraints(sim));
  out_str(" actuators ");
  out_int(legsim_n_actuators(sim));
  out_char('\n');

  const uint32_t t0 = ticks();
  const legsim_status s = legsim_assemble_pose(sim, 0);
  const uint32_t insns = (ticks() - t0) * pf->insns_per_tick;
  legsim_report rep = {0, 0, 0, 0};
  legsim_get_report(sim, &rep);
  out_str("stand status ");
  out_int(s);
  out_str(" iterations ");
  out_int(rep.iterations);
  out_str(" residual ");
  out_real((double)rep.residual, 15);
  out_str(" insns ");
  out_uint(insns);
  out_char('\n');
  if (failed("legsim_assemble_pose", s)) {
    out_str("done status 1\n");
    return 1;
  }
  print_q_foot("stand", sim);
  print_joints(sim);

  int status = 0;
  status |= run_integrator(sim, LEGSIM_INTEGRATOR_RK4, "rk4");
  status |= run_integrator(sim, LEGSIM_INTEGRATOR_GENERALIZED_ALPHA, "generalized_alpha");
  out_str("done status ");
  out_int(status);
  out_char('\n');
  return status;
}
