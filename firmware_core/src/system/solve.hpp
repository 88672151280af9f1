// The multipliers' solve and the constraint forces as the integrators see them: whatever
// the element module couples into the solve (sliding contacts' friction, which makes the
// system non-symmetric) stays behind these two, so an integrator knows no contact law.
#pragma once

#include "sim.hpp"

namespace legsim {

// y = J^T x minus the sliding contacts' friction of the multipliers x: the generalized
// forces -(J^T - F E^T) x enters the equations of motion with (rows: d.rows at q).
inline void constraint_forces(const Model &m, const Data &d, const Layout &layout, const VecQ &q, const VecR &x,
                              VecQ &y) {
  jt_times(m, layout, d.rows, x, y);
  if (layout.nslide) friction_add(m, d, layout, q, x, -1, y);
}

// (J M^-1 J^T - J M^-1 F E^T) x = rhs in place, with the factor of J M^-1 J^T in
// d.factor: the factor's solve, or with sliding contacts their coupling's
// (coupled_solve: LEGSIM_ERR_CONTACT when the coupled matrix is singular).
inline legsim_status multiplier_solve(const Model &m, Data &d, const Layout &layout, const VecQ &q, VecR &x) {
  if (layout.nslide) return coupled_solve(m, d, layout, q, x);
  factor_solve(d.factor, x);
  return LEGSIM_OK;
}

}  // namespace legsim
