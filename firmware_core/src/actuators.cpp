// Actuators: force commands, the length servo (PD, saturated at max_force, and
// saying so), and the hard stops at the stroke ends.
#include "sim.hpp"

namespace legsim {

void actuator_forces_update(const Model &model, const legsim_options &opt, Data &d, const VecQ &q,
                            const VecQ &qd) {
  (void)opt;
  for (int a = 0; a < model.na; ++a) {
    ActuatorState &st = d.act[a];
    if (st.mode == LEGSIM_ACTUATOR_FORCE) {
      st.force = st.setpoint;
      continue;
    }
    const Actuator &ac = model.act[a];
    real len, rate;
    actuator_length(model, a, q, qd, len, rate);
    real f = ac.kp * (st.setpoint - len) - ac.kd * rate;
    // A real cylinder cannot push harder: saturate, and report it.
    if (f > ac.fmax || f < -ac.fmax) {
      f = f > 0 ? ac.fmax : -ac.fmax;
      raise_event(d, LEGSIM_EVENT_FORCE_SATURATED);
    }
    st.force = f;
  }
}

// After a step: an actuator beyond its stroke is put back on its end (a
// projection onto Phi = 0 with that length driven) and its outward velocity is
// removed: an inelastic hard stop. Raised as an event, never silent. Stopping
// one actuator can push another past its end, so the check repeats with the
// stopped ones held until no actuator is out.
legsim_status stroke_limits_enforce(Sim &sim, bool &stopped) {
  stopped = false;
  const Model &m = sim.model;
  Data &d = sim.data;
  DriverValues &dv = d.drivers;
  dv.ncoord = 0;
  uint32_t mask = 0;
  for (int pass = 0; pass <= m.na; ++pass) {
    uint32_t added = 0;
    for (int a = 0; a < m.na; ++a) {
      if (mask & (1u << a)) continue;
      real len, rate;
      actuator_length(m, a, d.q, d.qd, len, rate);
      const Actuator &ac = m.act[a];
      if (len >= ac.lmin && len <= ac.lmax) continue;
      const bool low = len < ac.lmin;
      added |= 1u << a;
      raise_event(d, low ? LEGSIM_EVENT_STROKE_MIN : LEGSIM_EVENT_STROKE_MAX);
      dv.length[a] = low ? ac.lmin : ac.lmax;
      const bool outward = low ? rate < 0 : rate > 0;
      dv.rate[a] = outward ? real(0) : rate;
      dv.accel[a] = 0;
    }
    if (!added) break;
    mask |= added;
    stopped = true;
    d.stroke_mask |= added;
    legsim_status s = layout_build(m, mask, 0, d.work);
    if (s != LEGSIM_OK) return s;
    s = layout_finish(d.work, dv);
    if (s != LEGSIM_OK) return s;
    const VecQ q0 = d.q, qd0 = d.qd;
    s = assemble(sim, d.work, dv, d.q, m.minv, AssemblyMode::Project);
    if (s == LEGSIM_OK) s = velocity_solve(sim, d.work, d.qd);
    if (s == LEGSIM_ERR_SINGULAR) {
      // A stroke end that is also a dead centre (the leg's lower stroke ends
      // where the knee is straight, as far as the geometry reaches): no stop can
      // be projected there, and none is needed. Keep the integrated state, say so.
      d.q = q0;
      d.qd = qd0;
      raise_event(d, LEGSIM_EVENT_NEAR_SINGULAR);
      return LEGSIM_OK;
    }
    if (s != LEGSIM_OK) return s;
  }
  return LEGSIM_OK;
}

}  // namespace legsim
