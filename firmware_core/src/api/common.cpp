// The C API's shared checks and bookkeeping (api/internal.hpp).
#include "api/internal.hpp"

namespace legsim::api {

namespace {
constexpr uint32_t kAllDisableFlags =
    LEGSIM_DISABLE_GRAVITY | LEGSIM_DISABLE_FORCE_ELEMENTS | LEGSIM_DISABLE_REACTIONS |
    LEGSIM_DISABLE_PROJECTION | LEGSIM_DISABLE_ACTUATORS | LEGSIM_DISABLE_STROKE_LIMITS;

}  // namespace

legsim_status options_check(const legsim_options *o) {
  if (!o) return LEGSIM_ERR_NULL;
  const long long integ = raw_enum(o->integrator);
  if (integ != LEGSIM_INTEGRATOR_RK4 && integ != LEGSIM_INTEGRATOR_GENERALIZED_ALPHA)
    return LEGSIM_ERR_BAD_INPUT;
  if (!within(o->step_s, LEGSIM_MIN_STEP_S, LEGSIM_MAX_STEP_S)) return LEGSIM_ERR_BAD_INPUT;
  if (!within(o->rho_inf, 0, 1)) return LEGSIM_ERR_BAD_INPUT;
  if (o->max_newton_iter < 1 || o->max_newton_iter > LEGSIM_MAX_NEWTON_ITER) return LEGSIM_ERR_BAD_INPUT;
  if (!within(o->newton_tol, LEGSIM_MIN_NEWTON_TOL, LEGSIM_MAX_NEWTON_TOL)) return LEGSIM_ERR_BAD_INPUT;
  if (o->disable & ~kAllDisableFlags) return LEGSIM_ERR_BAD_INPUT;
  const long long rule = raw_enum(o->statics_rule);
  if (rule != LEGSIM_STATICS_EQUAL_FRICTION && rule != LEGSIM_STATICS_MIN_TANGENTIAL)
    return LEGSIM_ERR_BAD_INPUT;
  const long long law = raw_enum(o->contact_law);
  if (law != LEGSIM_CONTACT_LCP && law != LEGSIM_CONTACT_PAPER) return LEGSIM_ERR_BAD_INPUT;
  const bool compiled = integ == LEGSIM_INTEGRATOR_RK4 ? LEGSIM_WITH_RK4 : LEGSIM_WITH_GENERALIZED_ALPHA;
  return compiled ? LEGSIM_OK : LEGSIM_ERR_DISABLED;
}

bool same_options(const legsim_options &a, const legsim_options &b) {
  return a.integrator == b.integrator && a.step_s == b.step_s && a.disable == b.disable &&
         a.rho_inf == b.rho_inf && a.max_newton_iter == b.max_newton_iter &&
         a.newton_tol == b.newton_tol && a.statics_rule == b.statics_rule &&
         a.contact_law == b.contact_law;
}

// Lengths inside every stroke (and finite), else the matching status.
legsim_status lengths_check(const Model &m, const legsim_real *len) {
  if (!bounded_array(len, m.na, LEGSIM_MAX_COORD)) return LEGSIM_ERR_BAD_INPUT;
  for (int a = 0; a < m.na; ++a)
    if (len[a] < m.act[a].lmin || len[a] > m.act[a].lmax) return LEGSIM_ERR_OUT_OF_STROKE;
  return LEGSIM_OK;
}

// The driven lengths of an assembly: the given ones, or the actuators' current ones for
// NULL; checked, then held still (rate and acceleration 0) as drivers with no coordinate.
legsim_status drive_to_lengths(legsim_sim *sim, const legsim_real *length_m) {
  const Model &m = as_sim(sim)->model;
  Data &d = as_sim(sim)->data;
  real len[kMaxActuators];
  if (length_m) {
    for (int a = 0; a < m.na; ++a) len[a] = length_m[a];
  } else {
    legsim_actuator_lengths(sim, len, nullptr);
  }
  const legsim_status st = lengths_check(m, len);
  if (st != LEGSIM_OK) return st;
  for (int a = 0; a < m.na; ++a) {
    d.drivers.length[a] = len[a];
    d.drivers.rate[a] = d.drivers.accel[a] = 0;
  }
  d.drivers.ncoord = 0;
  return LEGSIM_OK;
}

// A state set from outside rests on no stroke stop (the next step finds any).
legsim_status stops_clear(const Model &m, Data &d) {
  for (int a = 0; a < m.na; ++a) d.act[a].stop_force = 0;
  if (!d.stop_mask) return LEGSIM_OK;
  d.stop_mask = 0;
  return stops_layout(m, d);
}

// A state assembled or set from outside rests on no contact (legsim_assemble_on_ground
// and legsim_set_contact_state put feet on the ground).
legsim_status contacts_release(const Model &m, Data &d) {
  bool any = false;
  for (int k = 0; k < m.nc; ++k) any = any || d.contact[k].state != LEGSIM_CONTACT_FREE;
  contacts_free(d);
  return any ? stops_layout(m, d) : LEGSIM_OK;
}

legsim_status drivers_layout(const Model &m, Data &d, uint32_t act_mask, int ncoord) {
  if (ncoord == 0) return work_layout(m, d, act_mask);
  d.work_mask = -1;  // coordinate rows: built for this call only
  legsim_status s = layout_build(m, act_mask, ncoord, d.work);
  return s == LEGSIM_OK ? layout_finish(d.work, d.drivers) : s;
}

// Assembles d.work from d.q with geometric weights; commits q (qd = 0) on success.
legsim_status assemble_commit(const Model &m, Data &d) {
  if (const legsim_status st = stops_clear(m, d); st != LEGSIM_OK) return st;
  if (const legsim_status st = contacts_release(m, d); st != LEGSIM_OK) return st;
  VecQ q = d.q;
  const legsim_status s = assemble(m, d, d.work, d.drivers, q, m.unit_weight, AssemblyMode::Assemble);
  if (s != LEGSIM_OK) return s;
  d.q = q;
  d.qd.setZero();
  d.assembled = true;
  const legsim_report assembly = d.report;
  const legsim_status st = state_refresh(m, d);
  // report the assembly's figures, not those of the free dynamics solved after it
  d.report.iterations = assembly.iterations;
  d.report.residual = assembly.residual;
  d.report.condition = assembly.condition;
  return st;
}

}  // namespace legsim::api
