// Accelerations and multipliers: M qdd + Phi_q^T lambda = Q, Phi_q qdd = gamma,
// by the Schur complement (Phi_q M^-1 Phi_q^T) lambda = Phi_q M^-1 Q - gamma
// (M is diagonal, so this is the whole cost).
#include "sim.hpp"

namespace legsim {

legsim_status dynamics_solve(Sim &sim, const Layout &layout, const VecQ &q, const VecQ &qd, VecQ &qdd,
                             bool rows_ready) {
  const Model &m = sim.model;
  Data &d = sim.data;
  legsim_options opt = sim.opt;
  // Driven analyses: the drivers supply the actuator forces. Stops act besides them.
  if (layout.m > m.m && !layout.stops) opt.disable |= LEGSIM_DISABLE_ACTUATORS;
  applied_forces(m, opt, d, q, qd, d.force_q);
  if (!rows_ready) {
    rows_eval(m, layout, layout.stops ? d.stop_drivers : d.drivers, q, qd, d.rows);
    const legsim_status s = factor_build(layout, d.rows, m.minv, d.factor);
    d.report.condition = d.factor.condition;
    if (s != LEGSIM_OK) return s;
  }
  VecQ tmp;
  for (int k = 0; k < m.nq; ++k) tmp[k] = m.minv[k] * d.force_q[k];
  j_times(layout, d.rows, tmp, d.lambda);
  for (int i = 0; i < layout.m; ++i) d.lambda[i] -= d.rows.gamma[i];
  factor_solve(d.factor, d.lambda);
  jt_times(m, layout, d.rows, d.lambda, tmp);
  for (int k = 0; k < m.nq; ++k) qdd[k] = m.minv[k] * (d.force_q[k] - tmp[k]);
  return all_finite(qdd, m.nq) ? LEGSIM_OK : LEGSIM_ERR_DIVERGED;
}

void stop_forces_update(Sim &sim) {
  const Model &m = sim.model;
  Data &d = sim.data;
  int row = m.m;  // the stop rows follow the joints, in actuator order
  for (int a = 0; a < m.na; ++a)
    d.act[a].stop_force = (d.stop_mask & (1u << a)) ? -d.lambda[row++] : real(0);
  contact_forces_update(sim);  // the contact rows follow the stops
}

legsim_status dynamics_state_update(Sim &sim) { return dynamics_state_reactions(sim, sim.data.qdd); }

legsim_status dynamics_state_reactions(Sim &sim, VecQ &qdd, bool factor_ready) {
  Data &d = sim.data;
  if (factor_ready) rows_eval(sim.model, d.dyn, d.stop_drivers, d.q, d.qd, d.rows);
  const legsim_status s = dynamics_solve(sim, d.dyn, d.q, d.qd, qdd, factor_ready);
  if (s != LEGSIM_OK) return s;
  stop_forces_update(sim);
  if (!(sim.opt.disable & LEGSIM_DISABLE_REACTIONS))
    reactions_from_multipliers(sim.model, d.rows, d.lambda, d.reaction);
  return LEGSIM_OK;
}

}  // namespace legsim
