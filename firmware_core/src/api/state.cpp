// The C API, the state and what can be read of it: positions, velocities, accelerations,
// the rows and their Jacobian, actuator lengths and forces, reactions, multipliers, contacts,
// the report and the events; setting a state or a contact's mode from outside.
#include <cmath>

#include "api/internal.hpp"

using namespace legsim;
using namespace legsim::api;

extern "C" {

legsim_status legsim_get_report(const legsim_sim *sim, legsim_report *out) {
  CHECK_SIM(sim);
  if (!out) return LEGSIM_ERR_NULL;
  *out = as_sim(sim)->data.report;
  return LEGSIM_OK;
}

legsim_status legsim_failure_report(const legsim_sim *sim, legsim_report *out) {
  CHECK_SIM(sim);
  if (!out) return LEGSIM_ERR_NULL;
  *out = as_sim(sim)->data.failure;
  return LEGSIM_OK;
}

legsim_status legsim_clear_events(legsim_sim *sim) {
  CHECK_SIM(sim);
  as_sim(sim)->data.report.events = 0;
  as_sim(sim)->data.stroke_mask = 0;
  for (ContactData &c : as_sim(sim)->data.contact) c.events = 0;
  return LEGSIM_OK;
}

uint32_t legsim_stroke_event_mask(const legsim_sim *sim) {
  return sim_ok(sim) ? as_sim(sim)->data.stroke_mask : 0;
}

uint32_t legsim_contact_event_mask(const legsim_sim *sim, int32_t k) {
  if (!sim_ok(sim) || k < 0 || k >= as_sim(sim)->model.nc) return 0;
  return as_sim(sim)->data.contact[k].events;
}

legsim_status legsim_contact_event_time(const legsim_sim *sim, int32_t k, double *t_s) {
  CHECK_SIM(sim);
  if (!t_s) return LEGSIM_ERR_NULL;
  if (k < 0 || k >= as_sim(sim)->model.nc) return LEGSIM_ERR_BAD_INPUT;
  *t_s = as_sim(sim)->data.contact[k].event_time;
  return LEGSIM_OK;
}

legsim_status legsim_stroke_event_time(const legsim_sim *sim, int32_t a, double *t_s) {
  CHECK_SIM(sim);
  if (!t_s) return LEGSIM_ERR_NULL;
  if (a < 0 || a >= as_sim(sim)->model.na) return LEGSIM_ERR_BAD_INPUT;
  *t_s = as_sim(sim)->data.act[a].stop_time;
  return LEGSIM_OK;
}

double legsim_time(const legsim_sim *sim) { return sim_ok(sim) ? as_sim(sim)->data.t : 0.0; }

uint64_t legsim_step_count(const legsim_sim *sim) { return sim_ok(sim) ? as_sim(sim)->data.steps : 0; }

legsim_status legsim_get_q(const legsim_sim *sim, legsim_real *q) {
  CHECK_SIM(sim);
  if (!q) return LEGSIM_ERR_NULL;
  const Sim &s = *as_sim(sim);
  for (int k = 0; k < s.model.nq; ++k) q[k] = s.data.q[k];
  return LEGSIM_OK;
}

legsim_status legsim_get_qd(const legsim_sim *sim, legsim_real *qd) {
  CHECK_SIM(sim);
  if (!qd) return LEGSIM_ERR_NULL;
  const Sim &s = *as_sim(sim);
  for (int k = 0; k < s.model.nq; ++k) qd[k] = s.data.qd[k];
  return LEGSIM_OK;
}

legsim_status legsim_get_qdd(const legsim_sim *sim, legsim_real *qdd) {
  CHECK_SIM(sim);
  if (!qdd) return LEGSIM_ERR_NULL;
  const Sim &s = *as_sim(sim);
  for (int k = 0; k < s.model.nq; ++k) qdd[k] = s.data.qdd[k];
  return LEGSIM_OK;
}

legsim_status legsim_set_state(legsim_sim *sim, const legsim_real *q, const legsim_real *qd,
                               double t_s) {
  CHECK_SIM(sim);
  if (!q) return LEGSIM_ERR_NULL;
  Sim &s = *as_sim(sim);
  const int n = s.model.nq;
  if (!within(t_s, -LEGSIM_MAX_TIME_S, LEGSIM_MAX_TIME_S)) return LEGSIM_ERR_BAD_INPUT;
  Data &d = s.data;
  VecQ qn = VecQ::Zero(), qdn = VecQ::Zero();
  for (int k = 0; k < n; ++k) {
    qn[k] = q[k];
    qdn[k] = qd ? qd[k] : real(0);
  }
  if (!state_sane(qn, qdn, n)) return LEGSIM_ERR_BAD_INPUT;  // NaN too
  return all_or_nothing(s.model, s.data, [&] {
    d.q = qn;
    d.qd = qdn;
    d.t = t_s;
    d.origin_t = t_s;
    d.origin_steps = d.steps;
    d.assembled = true;
    legsim_status c = stops_clear(s.model, s.data);
    if (c == LEGSIM_OK) c = contacts_release(s.model, s.data);
    return c == LEGSIM_OK ? state_refresh(s.model, s.data) : c;
  });
}

legsim_status legsim_constraints(const legsim_sim *sim, legsim_real *phi, legsim_real *max_abs) {
  CHECK_SIM(sim);
  // the workspace is scratch: evaluating into it does not change the state
  Sim &s = *const_cast<Sim *>(as_sim(sim));
  Data &d = s.data;
  rows_eval(s.model, d.joints, d.drivers, d.q, d.qd, d.rows);
  if (phi)
    for (int i = 0; i < s.model.m; ++i) phi[i] = d.rows.phi[i];
  if (max_abs) *max_abs = rows_max_residual(d.joints, d.rows);
  return LEGSIM_OK;
}

legsim_status legsim_jacobian(const legsim_sim *sim, legsim_real *jac) {
  CHECK_SIM(sim);
  if (!jac) return LEGSIM_ERR_NULL;
  Sim &s = *const_cast<Sim *>(as_sim(sim));
  Data &d = s.data;
  const int n = s.model.nq;
  rows_eval(s.model, d.joints, d.drivers, d.q, d.qd, d.rows);
  for (int i = 0; i < s.model.m; ++i) {
    for (int k = 0; k < n; ++k) jac[i * n + k] = 0;
    for (int sl = 0; sl < 2; ++sl) {
      const int b = d.joints.body[i][sl];
      if (b < 0) continue;
      for (int c = 0; c < 3; ++c) jac[i * n + 3 * b + c] += d.rows.coef[i][sl][c];
    }
  }
  return LEGSIM_OK;
}

legsim_status legsim_actuator_lengths(const legsim_sim *sim, legsim_real *length_m, legsim_real *rate_mps) {
  CHECK_SIM(sim);
  if (!length_m && !rate_mps) return LEGSIM_ERR_NULL;
  const Sim &s = *as_sim(sim);
  for (int a = 0; a < s.model.na; ++a) {
    real l, r;
    actuator_length(s.model, a, s.data.q, s.data.qd, l, r);
    if (length_m) length_m[a] = l;
    if (rate_mps) rate_mps[a] = r;
  }
  return LEGSIM_OK;
}

legsim_status legsim_actuator_forces(const legsim_sim *sim, legsim_real *force_n) {
  CHECK_SIM(sim);
  if (!force_n) return LEGSIM_ERR_NULL;
  const Sim &s = *as_sim(sim);
  for (int a = 0; a < s.model.na; ++a) force_n[a] = s.data.act[a].force + s.data.act[a].stop_force;
  return LEGSIM_OK;
}

legsim_status legsim_foot_position(const legsim_sim *sim, legsim_real *xy) {
  CHECK_SIM(sim);
  if (!xy) return LEGSIM_ERR_NULL;
  const Sim &s = *as_sim(sim);
  const int b = s.model.foot_body;
  if (b < 0) return LEGSIM_ERR_BAD_INPUT;
  const real phi = s.data.q[3 * b + 2];
  const Vec2 p = Vec2(s.data.q[3 * b], s.data.q[3 * b + 1]) +
                 s.model.foot_point.x() * axis_u(phi) + s.model.foot_point.y() * normal_n(phi);
  xy[0] = p.x();
  xy[1] = p.y();
  return LEGSIM_OK;
}

legsim_status legsim_reactions(const legsim_sim *sim, legsim_reaction *out) {
  CHECK_SIM(sim);
  if (!out) return LEGSIM_ERR_NULL;
  const Sim &s = *as_sim(sim);
  if (s.model.opt.disable & LEGSIM_DISABLE_REACTIONS) return LEGSIM_ERR_DISABLED;
  for (int j = 0; j < s.model.nj; ++j) out[j] = s.data.reaction[j];
  return LEGSIM_OK;
}

legsim_status legsim_multipliers(const legsim_sim *sim, legsim_real *lambda) {
  CHECK_SIM(sim);
  if (!lambda) return LEGSIM_ERR_NULL;
  const Sim &s = *as_sim(sim);
  for (int i = 0; i < s.model.m; ++i) lambda[i] = s.data.lambda[i];
  return LEGSIM_OK;
}

legsim_status legsim_contacts(const legsim_sim *sim, legsim_contact *out) {
  CHECK_SIM(sim);
  if (!out) return LEGSIM_ERR_NULL;
  if (!LEGSIM_WITH_CONTACT) return LEGSIM_ERR_DISABLED;
  const Sim &s = *as_sim(sim);
  const Model &m = s.model;
  for (int k = 0; k < m.nc; ++k) {
    const ContactData &c = s.data.contact[k];
    Vec2 p, v;
    contact_point(m, k, s.data.q, s.data.qd, p, v);
    legsim_contact &o = out[k];
    o.state = legsim_contact_state(c.state);
    o.normal_n = c.normal;
    o.tangential_n = c.tangential;
    o.friction_use = c.normal > 0 ? std::abs(c.tangential) / c.normal : real(0);
    o.position[0] = p.x();
    o.position[1] = p.y();
    o.slip_mps = v.dot(m.ground_t);
    o.impulse_ns[0] = c.impulse[0];
    o.impulse_ns[1] = c.impulse[1];
    o.holds = c.state != LEGSIM_CONTACT_FREE && c.normal >= 0 &&
              std::abs(c.tangential) <= m.mu_s * c.normal;
  }
  return LEGSIM_OK;
}

legsim_status legsim_set_contact_state(legsim_sim *sim, int32_t k, legsim_contact_state state) {
  CHECK_SIM(sim);
  if (!LEGSIM_WITH_CONTACT) return LEGSIM_ERR_DISABLED;
  Sim &s = *as_sim(sim);
  const Model &m = s.model;
  Data &d = s.data;
  const long long st = raw_enum(state);
  if (k < 0 || k >= m.nc ||
      (st != LEGSIM_CONTACT_FREE && st != LEGSIM_CONTACT_STUCK && st != LEGSIM_CONTACT_SLIDING))
    return LEGSIM_ERR_BAD_INPUT;
  if (!d.assembled) return LEGSIM_ERR_STATE;
  Vec2 p, v;
  contact_point(m, k, d.q, d.qd, p, v);
  const real gap = m.ground_n.dot(p - m.ground_point);
  const real vt = m.ground_t.dot(v);
  if (st != LEGSIM_CONTACT_FREE && !(std::abs(gap) <= real(s.model.opt.newton_tol))) return LEGSIM_ERR_STATE;
  if (st == LEGSIM_CONTACT_SLIDING && !(std::abs(vt) > real(s.model.opt.newton_tol))) return LEGSIM_ERR_STATE;
  const int8_t dir = vt > 0 ? 1 : -1;
  if (d.contact[k].state == st && (st != LEGSIM_CONTACT_SLIDING || d.contact[k].slip_dir == dir))
    return LEGSIM_OK;  // sent again: changes nothing
  return all_or_nothing(s.model, s.data, [&] {
    d.contact[k].state = uint8_t(st);
    d.contact[k].slip_dir = dir;
    d.stop_drivers.stick[k] = m.ground_t.dot(p - m.ground_point);
    legsim_status r = stops_layout(s.model, s.data);
    if (r == LEGSIM_OK && st != LEGSIM_CONTACT_FREE) {
      // the foot stops where it is (stuck) or on the line (sliding): its velocity onto the
      // new rows (an inelastic impact; frictionless: a state set from outside)
      VecQ qd = d.qd;
      r = velocity_solve(s.model, s.data, d.dyn, qd);
      if (r == LEGSIM_OK) d.qd = qd;
    }
    return r == LEGSIM_OK ? state_refresh(s.model, s.data) : r;
  });
}

}  // extern "C"
