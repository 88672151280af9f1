// Explicit RK4 on the index-1 form (accelerations from the multiplier solve),
// followed by the projection of positions onto Phi(q) = 0 and of velocities
// onto Phi_q qd = 0, both M-weighted. The derivative at the start of a step is
// the one left by the previous step's end (first same as last), so a step
// costs three stage solves and one end solve.
#include "planar/kernel.hpp"
#include "planar/mass.hpp"

namespace legsim {

#if LEGSIM_WITH_RK4
namespace {
// The stage updates over distinct arrays: __restrict tells the compiler so, and the loops
// vectorize (the same arithmetic per element, so the same values).
#define R_ real *__restrict
LEGSIM_STAGE_TARGETS void stage_first(int n, real h2, const R_ q0, const R_ v0, const R_ a0, R_ qs, R_ vs) {
  for (int k = 0; k < n; ++k) {
    qs[k] = Bodies::config_add(q0[k], h2 * v0[k]);
    vs[k] = v0[k] + h2 * a0[k];
  }
}
// the sums start at the first stage's (v0, a0): the second stage starts them from those
LEGSIM_STAGE_TARGETS void stage_second(int n, real w, real hn, const R_ q0, const R_ v0, const R_ a0, const R_ a,
                                        R_ qs, R_ vs, R_ sum_v, R_ sum_a) {
  for (int k = 0; k < n; ++k) {
    sum_v[k] = v0[k] + w * vs[k];
    sum_a[k] = a0[k] + w * a[k];
    qs[k] = Bodies::config_add(q0[k], hn * vs[k]);
    vs[k] = v0[k] + hn * a[k];
  }
}
LEGSIM_STAGE_TARGETS void stage_next(int n, real w, real hn, const R_ q0, const R_ v0, const R_ a, R_ qs, R_ vs, R_ sum_v,
                R_ sum_a) {
  for (int k = 0; k < n; ++k) {
    sum_v[k] += w * vs[k];
    sum_a[k] += w * a[k];
    qs[k] = Bodies::config_add(q0[k], hn * vs[k]);
    vs[k] = v0[k] + hn * a[k];
  }
}
// The last stage's weight (1) added, and the step's end q1 = q0 + h/6 sum_v, v1 = v0 + h/6
// sum_a written over q0 and v0 (the sim's state: all_or_nothing puts a failed step back);
// false when the end is not a state a sim may hold (state_sane: not finite, or past
// LEGSIM_MAX_ABS_Q or _QD), before the end's solves and projections make another failure of
// it. Every |x| is below its bound when their sum is (NaN fails that too), the usual case.
LEGSIM_STAGE_TARGETS bool stage_last(int n, real h6, R_ q, R_ v, const R_ vs, const R_ a, const R_ sum_v,
                                      const R_ sum_a) {
  real sq = 0, sv = 0;
  for (int k = 0; k < n; ++k) {
    const real q1 = Bodies::config_add(q[k], h6 * (sum_v[k] + vs[k])), v1 = v[k] + h6 * (sum_a[k] + a[k]);
    q[k] = q1;
    v[k] = v1;
    sq += std::abs(q1);
    sv += std::abs(v1);
  }
  return sq < real(LEGSIM_MAX_ABS_Q) && sv < real(LEGSIM_MAX_ABS_QD);
}
#undef R_

}  // namespace

namespace {
// The step's end state (already in d.q, d.qd) committed, with its stop forces (the reactions
// came with its solve); its end solve's factor is the state's unless the positions were
// projected (assemble leaves the rows of its last iterate, not of the projected positions).
legsim_status rk4_finish(const Model &m, Data &d, bool factor_kept = true) {
  d.factor.of_state = factor_kept && !d.end_projected;
  stop_forces_update(m, d);
  return LEGSIM_OK;
}
}  // namespace

legsim_status rk4_step(const Model &m, Data &d, real h) {
  const int n = m.nq;
  const real h2 = h / 2, h6 = h / 6;
  VecQ &qs = d.tq[0], &vs = d.tq[1], &sum_v = d.tq[2], &sum_a = d.tq[3];
  VecQ &a = d.tv[0];
  // stage 1: (v0, a0) at the start
  stage_first(n, h2, d.q.data(), d.qd.data(), d.qdd.data(), qs.data(), vs.data());
  // stages 2 and 3 at the midpoint (weight 2), 4 at the end
  const StagePlan plan = stage_plan(m, d, d.dyn);
  for (int stage = 0; stage < 3; ++stage) {
    const legsim_status s = dynamics_stage(m, d, plan, qs, vs, a);
    if (s != LEGSIM_OK) return s;
    if (stage == 0)
      stage_second(n, 2, h2, d.q.data(), d.qd.data(), d.qdd.data(), a.data(), qs.data(), vs.data(), sum_v.data(),
                   sum_a.data());
    else if (stage == 1)
      stage_next(n, 2, h, d.q.data(), d.qd.data(), a.data(), qs.data(), vs.data(), sum_v.data(), sum_a.data());
  }
  // the step's end (q1, v1), over the state
  VecQ &q1 = d.q, &v1 = d.qd;
  if (!stage_last(n, h6, q1.data(), v1.data(), vs.data(), a.data(), sum_v.data(), sum_a.data()) &&
      !state_sane(q1, v1, n))
    return LEGSIM_ERR_DIVERGED;
  // The end of the step: one evaluation of the rows at (q1, v1) serves the
  // position check, the velocity projection and the end derivative, which is
  // also the next step's first stage.
  const Layout &lay = d.dyn;
  const DriverValues &dv = d.stop_drivers;
  const bool projection = !(m.opt.disable & LEGSIM_DISABLE_PROJECTION);
  const real tol = real(m.opt.newton_tol);
  legsim_reaction *const reaction = m.opt.disable & LEGSIM_DISABLE_REACTIONS ? nullptr : d.reaction;
  d.report.iterations = 0;
  bool factor_ready = false;  // the rows and the factor at q1 kept, the positions on Phi = 0
#if LEGSIM_KERNELS_REDUCED
  if (reduced_available(lay) && !(projection && d.end_projected)) {
    // The joint rows alone, in the reduced system (Kernel::end): the end derivative, the
    // multipliers and the reactions, and the residual and drift that say whether the step
    // needs projecting. The usual step ends here, also one whose velocities alone need
    // projecting (the end projects them, with its factor, unless force elements act). One
    // whose positions need projecting starts over below (no rows or factor kept), as after
    // the fused solve.
    real drift;
    if (dynamics_end(m, d, plan, q1, v1, d.qdd, d.lambda, reaction, projection ? tol : real(INFINITY), projection,
                     d.report.residual, drift) == LEGSIM_OK &&
        (!projection || (d.report.residual <= tol && drift <= tol)))
      return rk4_finish(m, d, false);
  } else
#endif
  if (lay.path.dynamics && !(projection && d.end_projected)) {
    // The joint rows alone: the fused solve at (q1, v1) first, its rows and factor kept.
    // When neither the positions nor the velocities need projecting (the usual step), it
    // is the end derivative; when the velocities alone do, its factor serves their
    // projection; else the sequence below starts over. The same values and statuses
    // either way. Not tried after a step whose positions needed projecting (large steps:
    // every one does).
    if (dynamics_solve(m, d, lay, q1, v1, d.qdd, false, true, reaction) == LEGSIM_OK) {
      d.report.residual = rows_max_residual(lay, d.rows);
      if (!projection) return rk4_finish(m, d);
      if (d.report.residual <= tol) {
        if (velocity_drift(lay, d.rows, v1, d.rhs) <= tol) return rk4_finish(m, d);
        factor_ready = true;
      }
    }
  }
  d.end_projected = false;
  bool gamma_ready = true;  // d.rows' gamma is the one at (q1, v1)
  legsim_status s = LEGSIM_OK;
  if (!factor_ready) {
    rows_eval(m, lay, dv, q1, v1, d.rows, &d.trig);
    d.report.residual = rows_max_residual(lay, d.rows);
    if (projection && d.report.residual > tol) {
      d.end_projected = true;
      // M-weighted Newton, from the rows just evaluated at q1; it leaves the rows at the
      // projected q1 (Phi and the Jacobian serve below, its gamma is at zero velocity)
      s = assemble(m, d, lay, dv, q1, m.minv, AssemblyMode::Project, true);
      if (s != LEGSIM_OK) return s == LEGSIM_ERR_SINGULAR ? s : LEGSIM_ERR_DIVERGED;
#if LEGSIM_KERNELS_REDUCED
      // The rest in the reduced system as a step that needed no position projection (its
      // velocity projection, derivative, multipliers, reactions; the same to round-off): at
      // coarse steps every step gets here. Where it cannot (force elements act on projected
      // velocities), on with the general sequence from the rows at the projected q1.
      if (reduced_available(lay)) {
        real drift;
        if (dynamics_end(m, d, plan, q1, v1, d.qdd, d.lambda, reaction, tol, true, d.report.residual, drift) == LEGSIM_OK &&
            d.report.residual <= tol && drift <= tol)
          return rk4_finish(m, d, false);
      }
#endif
      gamma_ready = false;
    }
    s = factor_build(lay, d.rows, m.minv, d.factor);
    d.report.condition = d.factor.condition;
    if (s != LEGSIM_OK) return s;
  }
  // (factor_ready: the drift was found above the tolerance already)
  if (projection && (factor_ready || velocity_drift(lay, d.rows, v1, d.rhs) > tol)) {
    project(m, lay, d.rows, d.factor, m.minv, d.rows.nu, v1, d.rhs);
    gamma_ready = false;
  }
  if (!gamma_ready) rows_eval(m, lay, dv, q1, v1, d.rows, &d.trig);  // gamma at the final (q1, v1)
  s = dynamics_solve(m, d, lay, q1, v1, d.qdd, true, true, reaction);
  if (s != LEGSIM_OK) return s;
  return rk4_finish(m, d);
}

#else
legsim_status rk4_step(const Model &, Data &, real) { return LEGSIM_ERR_DISABLED; }
#endif

}  // namespace legsim
