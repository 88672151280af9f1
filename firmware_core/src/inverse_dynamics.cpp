// Inverse dynamics along a driven motion: assemble the lengths, solve the
// velocities and accelerations for the driven rates, then the multipliers of the
// driven system: the driver multipliers are the actuator forces (F = -lambda)
// and the joint multipliers the reactions.
#include "sim.hpp"

namespace legsim {

#if LEGSIM_WITH_INVERSE_DYNAMICS
legsim_status inverse_dynamics_solve(Sim &sim, const real *length, const real *rate,
                                     const real *accel, real *actuator_force) {
  const Model &m = sim.model;
  Data &d = sim.data;
  for (int a = 0; a < m.na; ++a) {
    d.drivers.length[a] = length[a];
    d.drivers.rate[a] = rate[a];
    d.drivers.accel[a] = accel[a];
  }
  d.drivers.ncoord = 0;
  legsim_status s = work_layout(sim, (1u << m.na) - 1);
  VecQ q = d.q;
  if (s == LEGSIM_OK) s = assemble(sim, d.work, d.drivers, q, m.minv, AssemblyMode::Assemble);
  if (s != LEGSIM_OK) return s;
  d.q = q;
  s = velocity_solve(sim, d.work, d.qd);
  if (s == LEGSIM_OK) s = dynamics_solve(sim, d.work, d.q, d.qd, d.qdd);
  if (s != LEGSIM_OK) return s;
  reactions_from_multipliers(m, d.rows, d.lambda, d.reaction);
  for (int a = 0; a < m.na; ++a) {
    d.act[a].force = -d.lambda[m.m + a];
    if (actuator_force) actuator_force[a] = d.act[a].force;
  }
  return LEGSIM_OK;
}
#else
legsim_status inverse_dynamics_solve(Sim &, const real *, const real *, const real *, real *) {
  return LEGSIM_ERR_DISABLED;
}
#endif

}  // namespace legsim
