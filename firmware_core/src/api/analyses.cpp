// The C API, the analyses: assembly (by lengths, a stored pose, on the ground), velocity and
// acceleration analysis, inverse dynamics, statics and its sweep.
#include <cmath>

#include "api/internal.hpp"

using namespace legsim;
using namespace legsim::api;

namespace {
// The velocity and acceleration analyses drive every actuator of a free mechanism: feet on the
// ground would over-determine the motion (the driven motion with stuck feet is
// legsim_inverse_dynamics_on_ground's, which sets q, qd and qdd). Then the input's range.
legsim_status free_motion_check(const Model &m, const Data &d, const legsim_real *values, double bound) {
  if (!d.assembled) return LEGSIM_ERR_STATE;
  for (int k = 0; k < m.nc; ++k)
    if (d.contact[k].state != LEGSIM_CONTACT_FREE) return LEGSIM_ERR_CONTACT;
  return bounded_array(values, m.na, bound) ? LEGSIM_OK : LEGSIM_ERR_BAD_INPUT;
}
}  // namespace

extern "C" {

legsim_status legsim_assemble(legsim_sim *sim, const legsim_real *length_m) {
  CHECK_SIM(sim);
  Sim &s = *as_sim(sim);
  const Model &m = s.model;
  Data &d = s.data;
  if (!all_finite(d.q, m.nq)) return LEGSIM_ERR_STATE;
  legsim_status st = drive_to_lengths(sim, length_m);
  if (st != LEGSIM_OK) return st;
  st = drivers_layout(s.model, s.data, all_actuators(m), 0);
  return st == LEGSIM_OK ? all_or_nothing(s.model, s.data, [&] { return assemble_commit(s.model, s.data); }) : st;
}

legsim_status legsim_assemble_pose(legsim_sim *sim, int32_t pose) {
  CHECK_SIM(sim);
  Sim &s = *as_sim(sim);
  const legsim_model_desc *desc = s.model.desc;
  if (pose < 0 || pose >= desc->n_poses) return LEGSIM_ERR_BAD_INPUT;
  const legsim_pose_desc &p = desc->pose[pose];
  Data &d = s.data;
  d.drivers.ncoord = p.n_drivers;
  for (int k = 0; k < p.n_drivers; ++k) d.drivers.coord[k] = p.driver[k];
  legsim_status st = drivers_layout(s.model, s.data, 0, p.n_drivers);
  if (st != LEGSIM_OK) return st;
  return all_or_nothing(s.model, s.data, [&] {
    for (int b = 0; b < s.model.nb; ++b)
      for (int c = 0; c < 3; ++c) d.q[3 * b + c] = real(p.guess[b][c]);
    return assemble_commit(s.model, s.data);
  });
}

legsim_status legsim_assemble_foot(legsim_sim *sim, const legsim_real *foot_xy) {
  CHECK_SIM(sim);
  if (!foot_xy) return LEGSIM_ERR_NULL;
  Sim &s = *as_sim(sim);
  const Model &m = s.model;
  Data &d = s.data;
  if (m.foot_body < 0 || m.nc > 0) return LEGSIM_ERR_BAD_INPUT;  // a leg's foot; a robot's feet are contacts
  if (!bounded_array(foot_xy, 2, LEGSIM_MAX_COORD)) return LEGSIM_ERR_BAD_INPUT;
  if (!all_finite(d.q, m.nq)) return LEGSIM_ERR_STATE;
  d.drivers.foot[0] = foot_xy[0];
  d.drivers.foot[1] = foot_xy[1];
  d.drivers.ncoord = 0;
  d.work_mask = -1;  // foot rows: built for this call only
  legsim_status st = layout_build(m, 0, 0, d.work, nullptr, false, true);
  if (st == LEGSIM_OK) st = layout_finish(d.work, d.drivers);
  if (st != LEGSIM_OK) return st;
  return all_or_nothing(s.model, s.data, [&] {
    legsim_status r = assemble_commit(s.model, s.data);
    if (r != LEGSIM_OK) return r;
    real len[kMaxActuators];
    legsim_actuator_lengths(sim, len, nullptr);
    return lengths_check(m, len);  // a foot the strokes do not reach: refused
  });
}

legsim_status legsim_velocity_analysis(legsim_sim *sim, const legsim_real *rate_mps) {
  CHECK_SIM(sim);
  if (!rate_mps) return LEGSIM_ERR_NULL;
  Sim &s = *as_sim(sim);
  const Model &m = s.model;
  Data &d = s.data;
  const legsim_status c = free_motion_check(s.model, s.data, rate_mps, LEGSIM_MAX_RATE_MPS);
  if (c != LEGSIM_OK) return c;
  legsim_actuator_lengths(sim, d.drivers.length, nullptr);
  for (int a = 0; a < m.na; ++a) {
    d.drivers.rate[a] = rate_mps[a];
    d.drivers.accel[a] = 0;
  }
  d.drivers.ncoord = 0;
  legsim_status st = drivers_layout(s.model, s.data, all_actuators(m), 0);
  if (st != LEGSIM_OK) return st;
  return all_or_nothing(s.model, s.data, [&] {
    VecQ qd = VecQ::Zero();
    legsim_status v = stops_clear(s.model, s.data);
    if (v == LEGSIM_OK) v = velocity_solve(s.model, s.data, d.work, qd);
    if (v != LEGSIM_OK) return v;
    // a velocity a state may not hold is refused here, not at the next step
    if (!state_sane(d.q, qd, m.nq)) return LEGSIM_ERR_DIVERGED;
    d.qd = qd;
    return state_refresh(s.model, s.data);
  });
}

legsim_status legsim_acceleration_analysis(legsim_sim *sim, const legsim_real *accel_mps2) {
  CHECK_SIM(sim);
  if (!accel_mps2) return LEGSIM_ERR_NULL;
  Sim &s = *as_sim(sim);
  const Model &m = s.model;
  Data &d = s.data;
  const legsim_status c = free_motion_check(s.model, s.data, accel_mps2, LEGSIM_MAX_ACCEL_MPS2);
  if (c != LEGSIM_OK) return c;
  legsim_actuator_lengths(sim, d.drivers.length, d.drivers.rate);
  for (int a = 0; a < m.na; ++a) d.drivers.accel[a] = accel_mps2[a];
  d.drivers.ncoord = 0;
  legsim_status st = drivers_layout(s.model, s.data, all_actuators(m), 0);
  if (st != LEGSIM_OK) return st;
  return all_or_nothing(s.model, s.data, [&] {
    VecQ qdd;
    const legsim_status r = acceleration_solve(s.model, s.data, d.work, qdd);
    if (r != LEGSIM_OK) return r;
    d.qdd = qdd;
    state_changed(d);  // qdd is kinematic, not the dynamics'
    return LEGSIM_OK;
  });
}

legsim_status legsim_inverse_dynamics(legsim_sim *sim, const legsim_real *length_m,
                                      const legsim_real *rate_mps, const legsim_real *accel_mps2,
                                      legsim_real *actuator_force_n) {
  CHECK_SIM(sim);
  if (!length_m || !rate_mps || !accel_mps2) return LEGSIM_ERR_NULL;
  Sim &s = *as_sim(sim);
  if (!s.data.assembled) return LEGSIM_ERR_STATE;
  legsim_status st = lengths_check(s.model, length_m);
  if (st != LEGSIM_OK) return st;
  if (!bounded_array(rate_mps, s.model.na, LEGSIM_MAX_RATE_MPS) ||
      !bounded_array(accel_mps2, s.model.na, LEGSIM_MAX_ACCEL_MPS2))
    return LEGSIM_ERR_BAD_INPUT;
  real force[kMaxActuators];
  bool held = false;  // feet on the ground: their rows too (section 8)
  for (int k = 0; k < s.model.nc; ++k) held = held || s.data.contact[k].state != LEGSIM_CONTACT_FREE;
  real len[kMaxActuators], rate[kMaxActuators], acc[kMaxActuators];
  for (int a = 0; a < s.model.na; ++a) {
    len[a] = length_m[a];
    rate[a] = rate_mps[a];
    acc[a] = accel_mps2[a];
  }
  st = all_or_nothing(s.model, s.data, [&] {
    legsim_status r = stops_clear(s.model, s.data);
    if (r == LEGSIM_OK)
      r = held ? inverse_dynamics_ground_solve(s.model, s.data, 0, len, rate, acc, force)
               : inverse_dynamics_solve(s.model, s.data, length_m, rate_mps, accel_mps2, force);
    state_changed(s.data);  // qdd is the driven motion's
    return r;
  });
  if (st == LEGSIM_OK && actuator_force_n)
    for (int a = 0; a < s.model.na; ++a) actuator_force_n[a] = force[a];
  return st;
}

legsim_status legsim_inverse_dynamics_on_ground(legsim_sim *sim, uint32_t follow_mask, legsim_real *length_m,
                                                legsim_real *rate_mps, legsim_real *accel_mps2,
                                                legsim_real *actuator_force_n) {
  CHECK_SIM(sim);
  if (!length_m || !rate_mps || !accel_mps2) return LEGSIM_ERR_NULL;
  Sim &s = *as_sim(sim);
  const Model &m = s.model;
  if (!s.data.assembled) return LEGSIM_ERR_STATE;
  if (follow_mask & ~all_actuators(m)) return LEGSIM_ERR_BAD_INPUT;
  real len[kMaxActuators], rate[kMaxActuators], acc[kMaxActuators];
  for (int a = 0; a < m.na; ++a) {
    const bool driven = !(follow_mask & (1u << a));
    len[a] = driven ? length_m[a] : (m.act[a].lmin + m.act[a].lmax) / 2;  // followers: not read
    rate[a] = driven ? rate_mps[a] : 0;
    acc[a] = driven ? accel_mps2[a] : 0;
  }
  legsim_status st = lengths_check(m, len);
  if (st != LEGSIM_OK) return st;
  if (!bounded_array(rate, m.na, LEGSIM_MAX_RATE_MPS) || !bounded_array(acc, m.na, LEGSIM_MAX_ACCEL_MPS2))
    return LEGSIM_ERR_BAD_INPUT;
  real force[kMaxActuators];
  st = all_or_nothing(s.model, s.data, [&] {
    legsim_status r = stops_clear(s.model, s.data);
    if (r == LEGSIM_OK) r = inverse_dynamics_ground_solve(s.model, s.data, follow_mask, len, rate, acc, force);
    state_changed(s.data);  // qdd is the driven motion's
    return r;
  });
  if (st != LEGSIM_OK) return st;
  for (int a = 0; a < m.na; ++a) {
    length_m[a] = len[a];
    rate_mps[a] = rate[a];
    accel_mps2[a] = acc[a];
    if (actuator_force_n) actuator_force_n[a] = force[a];
  }
  return LEGSIM_OK;
}

legsim_status legsim_statics(legsim_sim *sim, legsim_real *actuator_force_n) {
  CHECK_SIM(sim);
  Sim &s = *as_sim(sim);
  if (!s.data.assembled) return LEGSIM_ERR_STATE;
  real force[kMaxActuators];
  const legsim_status st = all_or_nothing(s.model, s.data, [&] {
    legsim_status r = stops_clear(s.model, s.data);
    if (r == LEGSIM_OK) r = statics_solve(s.model, s.data, force);
    state_changed(s.data);
    return r;
  });
  if (st == LEGSIM_OK && actuator_force_n)
    for (int a = 0; a < s.model.na; ++a) actuator_force_n[a] = force[a];
  return st;
}

legsim_status legsim_statics_sweep(legsim_sim *sim, int32_t n_grid, legsim_worst_case *out) {
  CHECK_SIM(sim);
  if (!out) return LEGSIM_ERR_NULL;
  Sim &s = *as_sim(sim);
  if (!s.data.assembled) return LEGSIM_ERR_STATE;
  if (n_grid < 2 || n_grid > LEGSIM_MAX_GRID) return LEGSIM_ERR_BAD_INPUT;
  legsim_worst_case wc;
  const legsim_status st = all_or_nothing(s.model, s.data, [&] {
    legsim_status r = stops_clear(s.model, s.data);
    if (r == LEGSIM_OK) r = contacts_release(s.model, s.data);
    if (r == LEGSIM_OK) r = statics_sweep(s.model, s.data, n_grid, &wc);  // leaves the last pose solved
    state_changed(s.data);
    return r;
  });
  if (st == LEGSIM_OK) *out = wc;
  return st;
}

legsim_status legsim_assemble_on_ground(legsim_sim *sim, const legsim_real *length_m,
                                        legsim_real feet_mid_m) {
  CHECK_SIM(sim);
  if (!LEGSIM_WITH_CONTACT) return LEGSIM_ERR_DISABLED;
  Sim &s = *as_sim(sim);
  const Model &m = s.model;
  Data &d = s.data;
  if (m.nc < 1 || !(std::abs(feet_mid_m) <= real(LEGSIM_MAX_COORD))) return LEGSIM_ERR_BAD_INPUT;
  if (!all_finite(d.q, m.nq)) return LEGSIM_ERR_STATE;
  const legsim_status lc = drive_to_lengths(sim, length_m);
  if (lc != LEGSIM_OK) return lc;
  d.drivers.feet_mid = feet_mid_m;
  // joints, lengths, the outer feet's normal gaps and their midpoint along the line: with
  // the box's three coordinates that is all the stance fixes; a foot between the outer two
  // must then lie on the line already (legs of one shape at one height), checked below
  uint8_t normal_only[kMaxContacts];
  for (int k = 0; k < m.nc; ++k) normal_only[k] = k == 0 || k == m.nc - 1 ? kContactNormal : kContactNone;
  d.work_mask = -1;  // built for this call only
  legsim_status st = layout_build(m, all_actuators(m), 0, d.work, normal_only, true);
  if (st == LEGSIM_OK) st = layout_finish(d.work, d.drivers);
  if (st != LEGSIM_OK) return st;
  return all_or_nothing(s.model, s.data, [&] {
    legsim_status r = stops_clear(s.model, s.data);
    if (r != LEGSIM_OK) return r;
    VecQ q = d.q;
    r = assemble(s.model, s.data, d.work, d.drivers, q, m.unit_weight, AssemblyMode::Assemble);
    if (r != LEGSIM_OK) return r;
    d.q = q;
    d.qd.setZero();
    d.assembled = true;
    const VecQ zero = VecQ::Zero();
    for (int k = 0; k < m.nc; ++k) {
      Vec2 p, v;
      contact_point(m, k, d.q, zero, p, v);
      if (k > 0 && k < m.nc - 1 && !(std::abs(m.ground_n.dot(p - m.ground_point)) <= real(s.model.opt.newton_tol)))
        return LEGSIM_ERR_STATE;  // a middle foot off the line
      d.contact[k].state = uint8_t(LEGSIM_CONTACT_STUCK);
      d.stop_drivers.stick[k] = m.ground_t.dot(p - m.ground_point);
    }
    r = stops_layout(s.model, s.data);
    if (r != LEGSIM_OK) return r;
    const legsim_report assembly = d.report;
    r = state_refresh(s.model, s.data);
    d.report.iterations = assembly.iterations;
    d.report.residual = assembly.residual;
    d.report.condition = assembly.condition;
    return r;
  });
}

}  // extern "C"
