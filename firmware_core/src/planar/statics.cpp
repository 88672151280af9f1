// Statics (the paper's Section V): with the actuators locked at their current
// lengths and qd = 0, the driven system's multipliers balance the loads:
// Phi_q^T lambda = Q. The same Schur-complement solve as the dynamics gives
// lambda and a residual acceleration that must vanish; when it does not, the
// locked leg is still a mechanism and no equilibrium exists.
#include "sim.hpp"

namespace legsim {

#if LEGSIM_WITH_STATICS || LEGSIM_WITH_INVERSE_DYNAMICS
namespace {
#if LEGSIM_USE_FLOAT
constexpr real kBalanceTol = real(1e-3);
#else
constexpr real kBalanceTol = real(1e-8);
#endif

// One solve of the driven system (every actuator driven at d.drivers) with the given
// contact rows at (d.q, d.qd): the multipliers in d.lambda, the rows in d.rows. Its
// accelerations must be target (statics: zero; inverse dynamics: the driven motion's),
// else the system is still a mechanism there, or the motion is not the one these rows allow.
legsim_status driven_solve(const Model &m, Data &d, const uint8_t *contacts, const VecQ &target) {
  const uint32_t all = (1u << m.na) - 1;
  legsim_status s;
  if (m.nc > 0) {  // with contact rows: built for this call only
    d.work_mask = -1;
    for (int k = 0; k < m.nc; ++k) d.drivers.stick[k] = d.stop_drivers.stick[k];
    s = layout_build(m, all, 0, d.work, contacts);
    if (s == LEGSIM_OK) s = layout_finish(d.work, d.drivers);
  } else {
    s = work_layout(m, d, all);
  }
  VecQ qdd;
  if (s == LEGSIM_OK) s = dynamics_solve(m, d, d.work, d.q, d.qd, qdd);
  if (s != LEGSIM_OK) return s;
  // scale: the acceleration the loads alone would cause, or the motion's
  real scale = 1, worst = 0;
  for (int k = 0; k < m.nq; ++k) {
    const real free_acc = std::abs(m.minv[k] * d.force_q[k]);
    scale = free_acc > scale ? free_acc : scale;
    scale = std::abs(target[k]) > scale ? std::abs(target[k]) : scale;
    const real e = std::abs(qdd[k] - target[k]);
    worst = e > worst ? e : worst;
  }
  return worst <= kBalanceTol * scale ? LEGSIM_OK : LEGSIM_ERR_NO_EQUILIBRIUM;
}
}  // namespace

// A contact that is not free holds its foot. Two held feet make the stance statically
// indeterminate by one self-stress (a tangential pair along the line): solve A with
// the tangential row of the first only, B with that of the second only; every
// solution is (1 - s) A + s B, and statics_rule picks s (design section 3).
legsim_status held_contacts_solve(const Model &m, Data &d, const VecQ &target, real *normal, real *tangential) {
  uint8_t rows[kMaxContacts];
  int held[2] = {0, 0}, nheld = 0;
  for (int k = 0; k < m.nc; ++k) {
    const bool on = d.contact[k].state != LEGSIM_CONTACT_FREE;
    rows[k] = on ? kContactStuck : kContactNone;
    if (!on) continue;
    if (nheld == 2) return LEGSIM_ERR_CONTACT;
    held[nheld++] = k;
  }
  legsim_status s;
  if (nheld < 2) {
    s = driven_solve(m, d, rows, target);
    if (s != LEGSIM_OK) return s;
    contact_forces_of_layout(m, d.work, d.lambda, normal, tangential);
    return LEGSIM_OK;
  }
  const int k0 = held[0], k1 = held[1];
  rows[k1] = kContactNormal;
  s = driven_solve(m, d, rows, target);
  if (s != LEGSIM_OK) return s;
  const VecR lambda_a = d.lambda;
  real na[kMaxContacts], ta[kMaxContacts];
  contact_forces_of_layout(m, d.work, d.lambda, na, ta);
  rows[k1] = kContactStuck;
  rows[k0] = kContactNormal;
  s = driven_solve(m, d, rows, target);
  if (s != LEGSIM_OK) return s;
  real nb[kMaxContacts], tb[kMaxContacts];
  contact_forces_of_layout(m, d.work, d.lambda, nb, tb);
  real frac = real(0.5);  // MIN_TANGENTIAL: T_0 = (1 - s) T, T_1 = s T least at s = 1/2
  if (m.opt.statics_rule == LEGSIM_STATICS_EQUAL_FRICTION) {
    const real sum = na[k0] + na[k1];  // the normal forces do not depend on s
    if (!(sum > 0)) return LEGSIM_ERR_NO_EQUILIBRIUM;
    frac = na[k1] / sum;  // (1 - s) T / N_0 = s T / N_1
  }
  // the joint and driver rows lead both layouts in the same order
  for (int i = 0; i < m.m + m.na; ++i) d.lambda[i] = (1 - frac) * lambda_a[i] + frac * d.lambda[i];
  for (int k = 0; k < m.nc; ++k) {
    normal[k] = (1 - frac) * na[k] + frac * nb[k];
    tangential[k] = (1 - frac) * ta[k] + frac * tb[k];
  }
  for (int i = m.m + m.na; i < d.work.m; ++i) {  // B's contact rows, as the combination
    const RowSource &r = d.work.src[i];
    d.lambda[i] = r.kind == RowKind::ContactNormal ? -normal[r.index] : -tangential[r.index];
  }
  return LEGSIM_OK;
}

// The results of a driven solve: joint reactions, actuator forces F = -lambda_driver (the
// driver pulls back on the rod) and the contacts' N and T. A float that cannot balance the
// loads is refused, not reported as infinite reactions.
legsim_status driven_outputs(const Model &m, Data &d, const real *normal, const real *tangential, real *actuator_force) {
  reactions_from_multipliers(m, d.rows, d.lambda, d.reaction);
  bool finite_result = true;
  for (int j = 0; j < m.nj; ++j)
    finite_result = finite_result && finite(d.reaction[j].force_n[0]) &&
                    finite(d.reaction[j].force_n[1]) && finite(d.reaction[j].moment_nm);
  for (int a = 0; a < m.na; ++a) {
    d.act[a].force = -d.lambda[m.m + a];
    finite_result = finite_result && finite(d.act[a].force);
    if (actuator_force) actuator_force[a] = d.act[a].force;
  }
  for (int k = 0; k < m.nc; ++k) {
    d.contact[k].normal = normal[k];
    d.contact[k].tangential = tangential[k];
    finite_result = finite_result && finite(normal[k]) && finite(tangential[k]);
  }
  return finite_result ? LEGSIM_OK : LEGSIM_ERR_DIVERGED;
}
#endif

#if LEGSIM_WITH_STATICS
namespace {
void lock_all_actuators(const Model &m, Data &d) {
  const VecQ zero = VecQ::Zero();
  for (int a = 0; a < m.na; ++a) {
    real rate;
    actuator_length(m, a, d.q, zero, d.drivers.length[a], rate);
    d.drivers.rate[a] = d.drivers.accel[a] = 0;
  }
  d.drivers.ncoord = 0;
}
}  // namespace

legsim_status statics_solve(const Model &m, Data &d, real *actuator_force) {
  lock_all_actuators(m, d);
  d.qd.setZero();
  real normal[kMaxContacts], tangential[kMaxContacts];
  const legsim_status s = held_contacts_solve(m, d, VecQ::Zero(), normal, tangential);
  if (s != LEGSIM_OK) return s;
  d.qdd.setZero();
  return driven_outputs(m, d, normal, tangential, actuator_force);
}

legsim_status statics_sweep(const Model &m, Data &d, int n_grid, legsim_worst_case *out) {
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
      const Snapshot before(m, d);
      legsim_status s = work_layout(m, d, (1u << m.na) - 1);
      VecQ q = d.q;
      if (s == LEGSIM_OK) s = assemble(m, d, d.work, d.drivers, q, m.minv, AssemblyMode::Assemble);
      if (s == LEGSIM_OK) {
        d.q = q;
        s = statics_solve(m, d, nullptr);
      }
      if (s != LEGSIM_OK) {
        before.restore(m, d);
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
legsim_status statics_solve(const Model &, Data &, real *) { return LEGSIM_ERR_DISABLED; }
legsim_status statics_sweep(const Model &, Data &, int, legsim_worst_case *) { return LEGSIM_ERR_DISABLED; }
#endif

}  // namespace legsim
