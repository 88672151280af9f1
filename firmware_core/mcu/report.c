/* The MCU report (see report.h): platform- and model-independent, C API only. */
#include "report.h"

#include "out.h"

#if LEGSIM_USE_FLOAT
#define REAL_NAME "float"
#define REAL_DECIMALS 7
#else
#define REAL_NAME "double"
#define REAL_DECIMALS 12
#endif

static const report_platform *pf_;

static uint32_t ticks(void) { return pf_->timer_ticks ? pf_->timer_ticks() : 0u; }

void report_real(double v) { out_real(v, REAL_DECIMALS); }

int report_failed(const char *what, legsim_status s) {
  if (s == LEGSIM_OK) return 0;
  out_str(what);
  out_str(" failed: ");
  out_str(legsim_status_str(s));
  out_str(" (");
  out_int(s);
  out_str(")\n");
  return 1;
}

static void print_state(const char *prefix, const legsim_sim *sim, const report_model *m) {
  legsim_real q[3 * LEGSIM_MAX_BODIES];
  const int32_t nb = legsim_n_bodies(sim);
  if (legsim_get_q(sim, q) == LEGSIM_OK) {
    for (int32_t b = 0; b < nb; ++b) {
      out_str(prefix);
      out_str(" q ");
      out_int(b);
      for (int k = 0; k < 3; ++k) {
        out_char(' ');
        report_real((double)q[3 * b + k]);
      }
      out_char('\n');
    }
  }
  m->print_state(prefix, sim);
}

static int run_integrator(legsim_sim *sim, const report_model *m, legsim_integrator integrator,
                          const char *name) {
  legsim_options opts = legsim_default_options();
  opts.integrator = integrator;
  legsim_status s = legsim_set_options(sim, &opts);
  if (s == LEGSIM_ERR_DISABLED) {
    out_str("step ");
    out_str(name);
    out_str(" disabled\n");
    return 0;
  }
  if (report_failed("legsim_set_options", s)) return 1;
  if (m->start(sim)) return 1;

  uint64_t sum = 0;
  uint32_t lo = UINT32_MAX, hi = 0;
  int32_t done = 0;
  for (; done < m->steps; ++done) {
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
  report_real(legsim_time(sim));
  out_char('\n');
  char prefix[48] = "step ";
  {
    int i = 5;
    for (const char *c = name; *c && i < (int)sizeof prefix - 1; ++c) prefix[i++] = *c;
    prefix[i] = '\0';
  }
  print_state(prefix, sim, m);
  if (done > 0) {
    out_str(prefix);
    out_str(" insns_per_step mean ");
    out_uint(out_udiv64(sum, (uint32_t)done, 0));
    out_str(" min ");
    out_uint(lo);
    out_str(" max ");
    out_uint(hi);
    out_char('\n');
  }
  return report_failed(name, s);
}

int report_run(void *storage, size_t storage_bytes, const report_platform *pf,
               const report_model *m) {
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
  if (report_failed("legsim_init", legsim_init(storage, storage_bytes, m->model, &opts, &sim))) {
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
  if (m->model_line_contacts) {
    out_str(" contacts ");
    out_int(legsim_n_contacts(sim));
  }
  out_char('\n');

  const uint32_t t0 = ticks();
  const legsim_status s = m->stand(sim);
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
  if (report_failed(m->stand_name, s)) {
    out_str("done status 1\n");
    return 1;
  }
  print_state("stand", sim, m);
  if (m->print_stand) m->print_stand(sim);

  int status = 0;
  status |= run_integrator(sim, m, LEGSIM_INTEGRATOR_RK4, "rk4");
  status |= run_integrator(sim, m, LEGSIM_INTEGRATOR_GENERALIZED_ALPHA, "generalized_alpha");
  out_str("done status ");
  out_int(status);
  out_char('\n');
  return status;
}
