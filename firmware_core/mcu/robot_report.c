/* The robot report (see robot_report.h): platform-independent, C API only. */
#include "robot_report.h"

#include "legsim/legsim.h"
#include "legsim/robot_models.h"
#include "out.h"

#if LEGSIM_USE_FLOAT
#define REAL_NAME "float"
#define REAL_DECIMALS 7
#else
#define REAL_NAME "double"
#define REAL_DECIMALS 12
#endif

/* models/robot.toml: actuator 0 is right.upper (the Fig. 7 push), 1..3 held */
#define PUSH_N 185.55

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

static void print_state(const char *prefix, const legsim_sim *sim) {
  legsim_real q[3 * LEGSIM_MAX_BODIES];
  legsim_contact k[LEGSIM_CONTACT_SLOTS];
  const int32_t nb = legsim_n_bodies(sim), nc = legsim_n_contacts(sim);
  if (legsim_get_q(sim, q) == LEGSIM_OK) {
    for (int32_t b = 0; b < nb; ++b) {
      out_str(prefix);
      out_str(" q ");
      out_int(b);
      for (int i = 0; i < 3; ++i) {
        out_char(' ');
        out_real_n(q[3 * b + i]);
      }
      out_char('\n');
    }
  }
  if (legsim_contacts(sim, k) != LEGSIM_OK) return;
  const legsim_model_desc *m = legsim_model(sim);
  for (int32_t c = 0; c < nc; ++c) {
    out_str(prefix);
    out_str(" contact ");
    out_str(m->contact[c].name);
    out_char(' ');
    out_int(k[c].state);
    out_char(' ');
    out_real_n(k[c].normal_n);
    out_char(' ');
    out_real_n(k[c].tangential_n);
    out_char(' ');
    out_real_n(k[c].position[0]);
    out_char(' ');
    out_real_n(k[c].position[1]);
    out_char('\n');
  }
}

/* the stand on the ground, at rest, t = 0 */
static legsim_status stand(legsim_sim *sim) {
  legsim_real q[3 * LEGSIM_MAX_BODIES];
  legsim_status s = legsim_assemble_pose(sim, 0);
  if (s == LEGSIM_OK) s = legsim_get_q(sim, q);
  if (s == LEGSIM_OK) s = legsim_set_state(sim, q, 0, 0.0);
  if (s == LEGSIM_OK) s = legsim_assemble_on_ground(sim, 0, 0);
  return s;
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
  if (failed("stand", stand(sim))) return 1;
  legsim_real len[4], rate[4];
  if (failed("legsim_actuator_lengths", legsim_actuator_lengths(sim, len, rate))) return 1;
  for (int32_t a = 1; a < 4; ++a)
    if (failed("legsim_command_length", legsim_command_length(sim, a, len[a]))) return 1;
  if (failed("legsim_command_force", legsim_command_force(sim, 0, PUSH_N))) return 1;

  uint64_t sum = 0;
  uint32_t lo = UINT32_MAX, hi = 0;
  int32_t done = 0;
  for (; done < ROBOT_REPORT_STEPS; ++done) {
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
  print_state(prefix, sim);
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

int robot_report_run(void *storage, size_t storage_bytes, const leg_report_platform *pf) {
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
             legsim_init(storage, storage_bytes, &legsim_model_robot_revolute, &opts, &sim))) {
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
  out_str(" contacts ");
  out_int(legsim_n_contacts(sim));
  out_char('\n');

  const uint32_t t0 = ticks();
  const legsim_status s = stand(sim);
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
  if (failed("stand", s)) {
    out_str("done status 1\n");
    return 1;
  }
  print_state("stand", sim);

  int status = 0;
  status |= run_integrator(sim, LEGSIM_INTEGRATOR_RK4, "rk4");
  status |= run_integrator(sim, LEGSIM_INTEGRATOR_GENERALIZED_ALPHA, "generalized_alpha");
  out_str("done status ");
  out_int(status);
  out_char('\n');
  return status;
}
