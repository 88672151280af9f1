// Statics (the paper's Section V): with the actuators locked at their current
// lengths and qd = 0, the driven system's multipliers balance the loads:
// Phi_q^T lambda = Q. The same Schur-complement solve as the dynamics gives
// lambda and a residual acceleration that must vanish; when it does not, the
// locked leg is still a mechanism and no equilibrium exists.
#include "sim.hpp"

namespace legsim {

#if LEGSIM_WITH_STATICS
namespace {
#if LEGSIM_USE_FLOAT
constexpr real kBalanceTol = real(1e-3);
#else
constexpr real kBalanceTol = real(1e-8);
#endif

void lock_all_actuators(Sim &sim) {
  const Model &m = sim.model;
  Data &d = sim.data;
  const VecQ zero = VecQ::Zero();
  for (int a = 0; a < m.na; ++a) {
    real rate;
    actuator_length(m, a, d.q, zero, d.drivers.length[a], rate);
    d.drivers.rate[a] = d.drivers.accel[a] = 0;
  }
  d.drivers.ncoord = 0;
}
}  // namespace

legsim_status statics_solve(Sim &sim, real *actuator_force) {
  const Model &m = sim.model;
  Data &d = sim.data;
  lock_all_actuators(sim);
  legsim_status s = work_layout(sim, (1u << m.na) - 1);
  if (s != LEGSIM_OK) return s;
  d.qd.setZero();
  s = dynamics_solve(sim, d.work, d.q, d.qd, d.qdd);
  if (s != LEGSIM_OK) return s;
  // scale: the acceleration the loads alone would cause
  real scale = 1, worst = 0;
  for (int k = 0; k < m.nq; ++k) {
    const real free_acc = std::abs(m.minv[k] * d.force_q[k]);
    scale = free_acc > scale ? free_acc : scale;
    worst = std::abs(d.qdd[k]) > worst ? std::abs(d.qdd[k]) : worst;
  }
  if (!(worst <= kBalanceTol * scale)) return LEGSIM_ERR_NO_EQUILIBRIUM;
  d.qdd.setZero();
  reactions_from_multipliers(m, d.rows, d.lambda, d.reaction);
  bool finite_result = true;
  for (int j = 0; j < m.nj; ++j)
    finite_result = finite_result && finite(d.reaction[j].force_n[0]) &&
                    finite(d.reaction[j].force_n[1]) && finite(d.reaction[j].moment_nm);
  for (int a = 0; a < m.na; ++a) {
    d.act[a].force = -d.lambda[m.m + a];  // F = -lambda_driver: the driver pulls back on the rod
    finite_result = finite_result && finite(d.act[a].force);
    if (actuator_force) actuator_force[a] = d.act[a].force;
  }
  // loads a float cannot balance: refused, not reported as infinite reactions
  return finite_result ? LEGSIM_OK : LEGSIM_ERR_DIVERGED;
}

legsim_status statics_sweep(Sim &sim, int n_grid, legsim_worst_case *out) {
  const Model &m = sim.model;
  Data &d = sim.data;
  if (m.na < 2 || n_grid < 2) return LEGSIM_ERR_BAD_INPUT;
  *out = legsim_worst_case{};
  // serpentine order so that each pose starts from its neighbour
  for (int i = 0; i < n_grid; ++i) {
    for (int jj = 0; jj < n_grid; ++jj) {
      const int j = (i % 2 == 0) ? jj : n_grid - 1 - jj;
      real len[kMaxActuators];
      for (int a = 0; a < m.na; ++a) {
        real rate;
        actuator_length(m, a, d.q, d.qd, len[a], rate);
      }
      const Actuator &a0 = m.act[0], &a1 = m.act[1];
      len[0] = a0.lmin + (a0.lmax - a0.lmin) * real(i) / real(n_grid - 1);
      len[1] = a1.lmin + (a1.lmax - a1.lmin) * real(j) / real(n_grid - 1);
      for (int a = 0; a < m.na; ++a) {
        d.drivers.length[a] = len[a];
        d.drivers.rate[a] = d.drivers.accel[a] = 0;
      }
      d.drivers.ncoord = 0;
      // a grid point that fails leaves nothing behind (state, report)
      const Snapshot before(d);
      legsim_status s = work_layout(sim, (1u << m.na) - 1);
      VecQ q = d.q;
      if (s == LEGSIM_OK) s = assemble(sim, d.work, d.drivers, q, m.minv, AssemblyMode::Assemble);
      if (s == LEGSIM_OK) {
        d.q = q;
        s = statics_solve(sim, nullptr);
      }
      if (s != LEGSIM_OK) {
        before.restore(sim);
        ++out->n_failed;
        continue;
      }
      ++out->n_poses;
      for (int k = 0; k < m.nj; ++k) {
        const real f = std::hypot(d.reaction[k].force_n[0], d.reaction[k].force_n[1]);
        if (f > out->max_reaction_n[k]) {
          out->max_reaction_n[k] = f;
          for (int a = 0; a < m.na; ++a) out->at_length_m[k][a] = len[a];
        }
      }
      for (int b = 0; b < m.na; ++b) {
        const real f = std::abs(d.act[b].force);
        if (f > out->max_actuator_force_n[b]) {
          out->max_actuator_force_n[b] = f;
          for (int a = 0; a < m.na; ++a) out->actuator_at_length_m[b][a] = len[a];
        }
      }
    }
  }
  if (out->n_poses == 0) return LEGSIM_ERR_UNREACHABLE;
  for (int k = 0; k < m.nj; ++k)
    if (!finite(out->max_reaction_n[k])) return LEGSIM_ERR_DIVERGED;
  return LEGSIM_OK;
}
#else
legsim_status statics_solve(Sim &, real *) { return LEGSIM_ERR_DISABLED; }
legsim_status statics_sweep(Sim &, int, legsim_worst_case *) { return LEGSIM_ERR_DISABLED; }
#endif

}  // namespace legsim
