// Assembly: Newton-Raphson onto Phi(q) = 0 (joint equations plus drivers), with
// the W-weighted minimum-norm correction dq = -W J^T (J W J^T)^-1 Phi, which is
// Newton's step when the system is square and the nearest solution when it is not.
#include "planar/mass.hpp"
#include "sim.hpp"

namespace legsim {

legsim_status assemble(const Model &m, Data &d, const Layout &layout, const DriverValues &dv, VecQ &q_io,
                       const real *w, AssemblyMode mode, bool rows_ready) {
  const bool full = mode == AssemblyMode::Assemble;
  const real tol = real(m.opt.newton_tol);
  VecQ q = q_io;
  const VecQ zero = VecQ::Zero();
  real first = -1;
  d.report.iterations = 0;
  for (int it = 0;; ++it) {
    if (it > 0 || !rows_ready) rows_eval(m, layout, dv, q, zero, d.rows);
    const real r = rows_max_residual(layout, d.rows);
    d.report.residual = r;
    if (!std::isfinite(r)) return LEGSIM_ERR_UNREACHABLE;
    if (first < 0) first = r;
    if (r <= tol && (it > 0 || !full)) break;
    // Growth far past the start means Newton left the basin: the lengths are not reachable.
    if (r > real(1e3) * (first + 1)) return LEGSIM_ERR_UNREACHABLE;
    if (it >= m.opt.max_newton_iter)
      // Close but not there: slow convergence (near a dead centre); far: no solution.
      return r < real(1e-4) ? LEGSIM_ERR_NOT_CONVERGED : LEGSIM_ERR_UNREACHABLE;
    const legsim_status s = factor_build(layout, d.rows, w, d.factor);
    d.report.condition = d.factor.condition;
    if (s != LEGSIM_OK) return s;
    d.report.iterations = it + 1;
    d.rhs = d.rows.phi;
    factor_solve(d.factor, d.rhs);
    VecQ corr;
    jt_times(m, layout, d.rows, d.rhs, corr);
    for (int k = 0; k < m.nq; ++k) q[k] = Bodies::config_add(q[k], -Bodies::mass_inverse_times(w, k, corr[k]));
  }
  // the condition where it landed: a converged dead centre is still a dead centre
  if (full) {
    const legsim_status s = factor_build(layout, d.rows, w, d.factor);
    if (s != LEGSIM_OK) return s;
    d.report.condition = factor_condition(d.factor);
    if (d.report.condition > real(LEGSIM_COND_WARN)) raise_event(d, LEGSIM_EVENT_NEAR_SINGULAR);
    if (d.report.condition > real(LEGSIM_COND_SINGULAR)) return LEGSIM_ERR_SINGULAR;
  }
  q_io = q;
  return LEGSIM_OK;
}

}  // namespace legsim
