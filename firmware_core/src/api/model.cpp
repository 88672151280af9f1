// The C API, the model and the sim: checking a model, the options, legsim_init (the
// compiled model and a fresh data in the caller's storage), the model's sizes.
#include <cstring>
#include <new>

#include "api/internal.hpp"

using namespace legsim;
using namespace legsim::api;

extern "C" {

legsim_status legsim_model_check(const legsim_model_desc *model, char *msg, size_t msg_len) {
  return model_check(model, msg, msg_len);
}

legsim_options legsim_default_options(void) {
  legsim_options o;
  o.integrator = LEGSIM_INTEGRATOR_RK4;
  o.step_s = 1e-3;
  o.disable = 0;
  o.rho_inf = 0.8;
  o.max_newton_iter = 25;
  o.newton_tol = LEGSIM_USE_FLOAT ? 1e-6 : 1e-10;
  o.statics_rule = LEGSIM_STATICS_EQUAL_FRICTION;
  o.contact_law = LEGSIM_CONTACT_LCP;
  return o;
}

size_t legsim_sim_size(void) { return sizeof(Sim); }

legsim_status legsim_init(void *storage, size_t storage_bytes, const legsim_model_desc *model,
                          const legsim_options *options, legsim_sim **out) {
  if (!storage || !model || !options || !out) return LEGSIM_ERR_NULL;
  if (storage_bytes < sizeof(Sim) || reinterpret_cast<uintptr_t>(storage) % LEGSIM_STORAGE_ALIGN)
    return LEGSIM_ERR_STORAGE;
  legsim_status s = options_check(options);
  if (s == LEGSIM_OK) s = model_check(model, nullptr, 0);
  if (s != LEGSIM_OK) return s;  // the storage (and any sim in it) untouched
  Sim *sim = new (storage) Sim;  // placement: the caller's storage, no heap
  sim->magic = 0;                // not a sim until complete
  s = model_compile(model, sim->model);
  if (s != LEGSIM_OK) return s;
  sim->model.opt = *options;
  sim->model.step_h = real(options->step_s);
  Data &d = sim->data;
  const Model &m = sim->model;
  d.t = 0;
  d.steps = 0;
  d.origin_t = 0;
  d.origin_steps = 0;
  d.origin_step_s = options->step_s;
  d.assembled = false;
  state_changed(d);
  d.end_projected = false;
  d.end_solved = false;
  d.factor.of_state = false;
  d.q.setZero();
  d.qd.setZero();
  d.qdd.setZero();
  d.acc_aux.setZero();
  for (VecQ &past : d.qdd_past) past.setZero();
  d.past_steps = 0;
  d.newton_eta = 1;
  d.lambda.setZero();
  std::memset(d.reaction, 0, sizeof d.reaction);
  std::memset(&d.report, 0, sizeof d.report);
  std::memset(&d.failure, 0, sizeof d.failure);
  std::memset(&d.drivers, 0, sizeof d.drivers);
  d.stroke_mask = 0;
  for (int a = 0; a < kMaxActuators; ++a) d.act[a] = {LEGSIM_ACTUATOR_FORCE, 0, 0, 0, 0.0};
  std::memset(&d.stop_drivers, 0, sizeof d.stop_drivers);
  d.stop_mask = 0;
  d.work_mask = -1;
  trig_clear(d.trig);
  trig_clear(*stage_trig(d));
  contacts_free(d);
  for (int f = 0; f < m.nf; ++f) {
    d.force_value[f][0] = real(model->force[f].value[0]);
    d.force_value[f][1] = real(model->force[f].value[1]);
  }
  force_active_update(m, d);
  s = layout_build(m, 0, 0, d.joints);
  if (s == LEGSIM_OK) s = layout_finish(d.joints, d.drivers);
  if (s == LEGSIM_OK) s = stops_layout(m, d);
  if (s != LEGSIM_OK) return s;
  sim->magic = kSimMagic;
  *out = reinterpret_cast<legsim_sim *>(sim);
  return LEGSIM_OK;
}

legsim_status legsim_set_options(legsim_sim *sim, const legsim_options *options) {
  CHECK_SIM(sim);
  const legsim_status s = options_check(options);
  if (s != LEGSIM_OK) return s;
  Sim &sm = *as_sim(sim);
  if (same_options(sm.model.opt, *options)) return LEGSIM_OK;  // sent again: changes nothing
  sm.model.opt = *options;
  sm.model.step_h = real(options->step_s);
  Data &d = sm.data;
  if (options->step_s != d.origin_step_s) {  // a new step size: the time line starts here
    d.origin_t = d.t;
    d.origin_steps = d.steps;
    d.origin_step_s = options->step_s;
  }
  state_changed(d);  // the step, the integrator, what is enabled: a full restart
  return LEGSIM_OK;
}

int32_t legsim_n_bodies(const legsim_sim *sim) { return sim_ok(sim) ? as_sim(sim)->model.nb : 0; }

int32_t legsim_n_coords(const legsim_sim *sim) { return sim_ok(sim) ? as_sim(sim)->model.nq : 0; }

int32_t legsim_n_constraints(const legsim_sim *sim) { return sim_ok(sim) ? as_sim(sim)->model.m : 0; }

int32_t legsim_n_joints(const legsim_sim *sim) { return sim_ok(sim) ? as_sim(sim)->model.nj : 0; }

int32_t legsim_n_actuators(const legsim_sim *sim) { return sim_ok(sim) ? as_sim(sim)->model.na : 0; }

int32_t legsim_n_forces(const legsim_sim *sim) { return sim_ok(sim) ? as_sim(sim)->model.nf : 0; }

int32_t legsim_n_contacts(const legsim_sim *sim) { return sim_ok(sim) ? as_sim(sim)->model.nc : 0; }

const legsim_model_desc *legsim_model(const legsim_sim *sim) {
  return sim_ok(sim) ? as_sim(sim)->model.desc : nullptr;
}

}  // extern "C"
