// Velocity and acceleration analysis: Phi_q qd = nu and Phi_q qdd = gamma,
// solved as the M-weighted projection of the current value (the unique answer
// when the drivers fix every degree of freedom; the least-kinetic-energy one otherwise).
#include "sim.hpp"

namespace legsim {

legsim_status velocity_solve(const Model &m, Data &d, const Layout &layout, VecQ &qd) {
  rows_eval(m, layout, layout.stops ? d.stop_drivers : d.drivers, d.q, qd, d.rows);
  const legsim_status s = factor_build(layout, d.rows, m.minv, d.factor);
  d.report.condition = d.factor.condition;
  if (s != LEGSIM_OK) return s;
  project(m, layout, d.rows, d.factor, m.minv, d.rows.nu, qd, d.rhs);
  return all_finite(qd, m.nq) ? LEGSIM_OK : LEGSIM_ERR_DIVERGED;
}

real velocity_drift(const Layout &lay, const Rows &rows, const VecQ &v, VecR &jv) {
  j_times(lay, rows, v, jv);
  real drift = 0;
  for (int i = 0; i < lay.m; ++i) drift = std::abs(jv[i]) > drift ? std::abs(jv[i]) : drift;
  return drift;
}

legsim_status acceleration_solve(const Model &m, Data &d, const Layout &layout, VecQ &qdd) {
  rows_eval(m, layout, d.drivers, d.q, d.qd, d.rows);
  const legsim_status s = factor_build(layout, d.rows, m.minv, d.factor);
  d.report.condition = d.factor.condition;
  if (s != LEGSIM_OK) return s;
  qdd.setZero();
  project(m, layout, d.rows, d.factor, m.minv, d.rows.gamma, qdd, d.rhs);
  return all_finite(qdd, m.nq) ? LEGSIM_OK : LEGSIM_ERR_DIVERGED;
}

}  // namespace legsim
