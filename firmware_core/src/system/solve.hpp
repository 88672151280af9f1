// The multipliers' solve and the constraint forces as the integrators see them: whatever
// the element module couples into the solve (sliding contacts' friction, which makes the
// system non-symmetric) stays behind these two, so an integrator knows no contact law.
#pragma once

#include "sim.hpp"

namespace legsim {

// y = J^T x minus the sliding contacts' friction of the multipliers x: the generalized
// forces -(J^T - F E^T) x enters the equations of motion with (rows: sim.data.rows at q).
inline void constraint_forces(const Sim &sim, const Layout &layout, const VecQ &q, const VecR &x, VecQ &y) {
  jt_times(sim.model, layout, sim.data.rows, x, y);
  if (layout.nslide) friction_add(sim, layout, q, x, -1, y);
}

// (J M^-1 J^T - J M^-1 F E^T) x = rhs in place, with the factor of J M^-1 J^T in
// sim.data.factor: the factor's solve, or with sliding contacts their coupling's
// (coupled_solve: LEGSIM_ERR_CONTACT when the coupled matrix is singular).
inline legsim_status multiplier_solve(Sim &sim, const Layout &layout, const VecQ &q, VecR &x) {
  if (layout.nslide) return coupled_solve(sim, layout, q, x);
  factor_solve(sim.data.factor, x);
  return LEGSIM_OK;
}

}  // namespace legsim
