// Inverse dynamics along a driven motion: assemble the lengths, solve the
// velocities and accelerations for the driven rates, then the multipliers of the
// driven system: the driver multipliers are the actuator forces (F = -lambda)
// and the joint multipliers the reactions.
#include "sim.hpp"

namespace legsim {

#if LEGSIM_WITH_INVERSE_DYNAMICS
legsim_status inverse_dynamics_solve(const Model &m, Data &d, const real *length, const real *rate,
                                     const real *accel, real *actuator_force) {
  for (int a = 0; a < m.na; ++a) {
    d.drivers.length[a] = length[a];
    d.drivers.rate[a] = rate[a];
    d.drivers.accel[a] = accel[a];
  }
  d.drivers.ncoord = 0;
  legsim_status s = work_layout(m, d, (1u << m.na) - 1);
  VecQ q = d.q;
  if (s == LEGSIM_OK) s = assemble(m, d, d.work, d.drivers, q, m.minv, AssemblyMode::Assemble);
  if (s != LEGSIM_OK) return s;
  d.q = q;
  s = velocity_solve(m, d, d.work, d.qd);
  if (s == LEGSIM_OK) s = dynamics_solve(m, d, d.work, d.q, d.qd, d.qdd);
  if (s != LEGSIM_OK) return s;
  reactions_from_multipliers(m, d.rows, d.lambda, d.reaction);
  for (int a = 0; a < m.na; ++a) {
    d.act[a].force = -d.lambda[m.m + a];
    if (actuator_force) actuator_force[a] = d.act[a].force;
  }
  return LEGSIM_OK;
}

namespace {
#if LEGSIM_USE_FLOAT
constexpr real kDriftTol = real(1e-3);
#else
constexpr real kDriftTol = real(1e-7);
#endif

// The second derivative of each actuator's length at (q, qd, qdd): l_dd = J_a qdd - gamma_a
// with the driver's own acceleration 0 in gamma_a (its velocity-product term alone).
void length_accelerations(const Model &m, Data &d, const VecQ &qdd, real *accel) {
  for (int a = 0; a < m.na; ++a) d.drivers.accel[a] = 0;
  d.work_mask = -1;  // built for this call only
  layout_build(m, (1u << m.na) - 1, 0, d.work);
  rows_eval(m, d.work, d.drivers, d.q, d.qd, d.rows);
  VecR jq;
  j_times(d.work, d.rows, qdd, jq);
  for (int a = 0; a < m.na; ++a) accel[a] = jq[m.m + a] - d.rows.gamma[m.m + a];
}
}  // namespace

// The feet on the ground (docs/design/robot-on-ground.md section 8): the motion from the
// joints, the driven lengths and each held foot's normal and tangential rows, which must fix
// it (as many rows as coordinates); the forces from every actuator's driver row and the held
// feet, two held feet combined by options.statics_rule as in the statics.
legsim_status inverse_dynamics_ground_solve(const Model &m, Data &d, uint32_t follow, real *length, real *rate,
                                            real *accel, real *actuator_force) {
  const uint32_t all = (1u << m.na) - 1, driven = all & ~follow;
  uint8_t kin[kMaxContacts];
  int held[2] = {0, 0}, nheld = 0;
  for (int k = 0; k < m.nc; ++k) {
    const uint8_t st = d.contact[k].state;
    if (st == LEGSIM_CONTACT_SLIDING) return LEGSIM_ERR_CONTACT;  // stuck or free only
    kin[k] = st == LEGSIM_CONTACT_STUCK ? kContactStuck : kContactNone;
    if (st != LEGSIM_CONTACT_STUCK) continue;
    if (nheld == 2) return LEGSIM_ERR_CONTACT;
    held[nheld++] = k;
  }
  // every length driven on two held feet: one tangential row too many (the lengths fix the
  // feet's spacing); the second foot's is left out of the motion and checked after it
  const bool check_second = follow == 0 && nheld == 2;
  if (check_second) kin[held[1]] = kContactNormal;
  for (int a = 0; a < m.na; ++a) {
    if (!(driven & (1u << a))) continue;
    d.drivers.length[a] = length[a];
    d.drivers.rate[a] = rate[a];
    d.drivers.accel[a] = accel[a];
  }
  d.drivers.ncoord = 0;
  for (int k = 0; k < m.nc; ++k) d.drivers.stick[k] = d.stop_drivers.stick[k];
  d.work_mask = -1;  // built for this call only
  legsim_status s = layout_build(m, driven, 0, d.work, kin);
  if (s == LEGSIM_OK) s = layout_finish(d.work, d.drivers);
  if (s != LEGSIM_OK) return s;
  if (d.work.m != m.nq) return LEGSIM_ERR_BAD_INPUT;  // the driven lengths must fix the motion
  VecQ q = d.q;
  s = assemble(m, d, d.work, d.drivers, q, m.minv, AssemblyMode::Assemble);
  if (s != LEGSIM_OK) return s;
  d.q = q;
  s = velocity_solve(m, d, d.work, d.qd);
  if (s == LEGSIM_OK) s = acceleration_solve(m, d, d.work, d.qdd);
  if (s != LEGSIM_OK) return s;
  if (check_second) {  // the lengths must keep the second foot where it sticks
    Vec2 p, v;
    contact_point(m, held[1], d.q, d.qd, p, v);
    const real drift = m.ground_t.dot(p - m.ground_point) - d.stop_drivers.stick[held[1]];
    real vscale = 1;
    for (int a = 0; a < m.na; ++a) vscale = std::abs(rate[a]) > vscale ? std::abs(rate[a]) : vscale;
    if (!(std::abs(drift) <= kDriftTol) || !(std::abs(m.ground_t.dot(v)) <= kDriftTol * vscale))
      return LEGSIM_ERR_UNREACHABLE;
  }
  // the followers' motion, then every actuator driven along it
  real lacc[kMaxActuators];
  const VecQ qdd = d.qdd;
  length_accelerations(m, d, qdd, lacc);
  for (int a = 0; a < m.na; ++a) {
    if (driven & (1u << a)) {
      d.drivers.accel[a] = accel[a];
      continue;
    }
    actuator_length(m, a, d.q, d.qd, length[a], rate[a]);
    accel[a] = lacc[a];
    if (length[a] < m.act[a].lmin || length[a] > m.act[a].lmax) return LEGSIM_ERR_OUT_OF_STROKE;
    d.drivers.length[a] = length[a];
    d.drivers.rate[a] = rate[a];
    d.drivers.accel[a] = accel[a];
  }
  // the forces (the accelerations the driven rows give must be the motion's: else the
  // lengths' accelerations do not keep the feet stuck, LEGSIM_ERR_NO_EQUILIBRIUM)
  real normal[kMaxContacts], tangential[kMaxContacts];
  s = held_contacts_solve(m, d, qdd, normal, tangential);
  if (s != LEGSIM_OK) return s;
  d.qdd = qdd;
  return driven_outputs(m, d, normal, tangential, actuator_force);
}
#else
legsim_status inverse_dynamics_solve(const Model &, Data &, const real *, const real *, const real *, real *) {
  return LEGSIM_ERR_DISABLED;
}
legsim_status inverse_dynamics_ground_solve(const Model &, Data &, uint32_t, real *, real *, real *, real *) {
  return LEGSIM_ERR_DISABLED;
}
#endif

}  // namespace legsim
