// Implicit generalized-alpha on the index-3 form (Arnold & Bruls 2007):
//   q1 = q0 + h v0 + h^2 (1/2 - beta) a0 + h^2 beta a1
//   v1 = v0 + h (1 - gamma) a0 + h gamma a1
//   (1 - am) a1 + am a0 = (1 - af) qdd1 + af qdd0
//   M qdd1 + Phi_q^T lambda = Q(q1, v1),  Phi(q1) = 0
// solved by Newton with the iteration matrix [beta' M, Phi_q^T; Phi_q, 0]
// (beta' = (1 - am) / (h^2 beta (1 - af))): M is diagonal, so each iteration
// is one factorization of Phi_q M^-1 Phi_q^T, the kernel of every other solve.
//
// The iteration matrix leaves out the derivatives of Phi_q^T lambda and Q by q and qd, so
// the iteration converges linearly, with a contraction theta = |dq_k| / |dq_k-1| of order
// h^2 K / M (about 1e-5 for the leg at h = 1 ms). Two things keep it to about one
// iteration a step:
// - the predictor: qdd1 extrapolated from the last steps' accelerations (quadratic when
//   two are known), which makes the first correction small. In float the accelerations of
//   the index-3 form carry the positions' round-off divided by h^2 (several m/s^2 from step
//   to step at h = 1 ms), which an extrapolation amplifies (3x linear, 7x quadratic): there
//   the last step's accelerations are the better guess (kPredictorOrder, sim.hpp);
// - the convergence test of Hairer & Wanner (Solving ODEs II, IV.8, as RADAU5): after a
//   correction dq the iterate's error is about eta |dq|, eta = theta / (1 - theta). The
//   step is converged when |dq| <= tol, or when eta |dq| <= tol with eta measured in this
//   step or, at its first iteration, the last step's raised to 3/4 (a stale estimate
//   grows toward 1 step by step, so a second iteration measures it again before it can
//   mislead). eta is kept at least kEtaMin: a first correction is accepted only up to
//   tol / kEtaMin, where the terms of second order in dq are still far below tol.
#include "planar/kernel.hpp"
#include "planar/mass.hpp"
#include "system/solve.hpp"

namespace legsim {

#if LEGSIM_WITH_GENERALIZED_ALPHA
namespace {
// The per-coordinate updates over distinct arrays: __restrict tells the compiler so, and
// the loops vectorize (the same arithmetic per element, so the same values).
#define R_ real *__restrict
// r = M qdd + r - Q (r holds J^T lambda); t = M^-1 r
LEGSIM_KERNEL_TARGETS void residual(int n, const R_ mass, const R_ minv, const R_ qdd1, const R_ force, R_ res, R_ tmp) {
  for (int k = 0; k < n; ++k) {
    res[k] += Bodies::mass_times(mass, k, qdd1[k]) - force[k];
    tmp[k] = Bodies::mass_inverse_times(minv, k, res[k]);
  }
}
// the Newton correction dq = -(M^-1 / beta') (r + J^T dlambda) applied to q1, v1, qdd1
LEGSIM_KERNEL_TARGETS void correct(int n, real bprime, real gprime, const R_ minv, const R_ res, const R_ tmp, R_ q1, R_ v1,
             R_ qdd1, R_ dq) {
  for (int k = 0; k < n; ++k) {
    dq[k] = -Bodies::mass_inverse_times(minv, k, res[k] + tmp[k]) / bprime;
    q1[k] = Bodies::config_add(q1[k], dq[k]);
    v1[k] += gprime * dq[k];
    qdd1[k] += bprime * dq[k];
  }
}
// q1 and v1 of the step from qdd1 given (a1: the auxiliary acceleration it gives)
[[gnu::always_inline]] inline void start_at(int k, real h, real af, real am, real beta, real gam, const R_ q,
                                            const R_ qd, const R_ qdd, const R_ acc_aux, real qdd1, R_ q1, R_ v1) {
  const real a1 = (af * qdd[k] + (1 - af) * qdd1 - am * acc_aux[k]) / (1 - am);
  // q (+) h qd (+) h^2 (...): two increments, in the order of q + h qd + h^2 (...)
  q1[k] = Bodies::config_add(Bodies::config_add(q[k], h * qd[k]), h * h * ((real(0.5) - beta) * acc_aux[k] + beta * a1));
  v1[k] = qd[k] + h * ((1 - gam) * acc_aux[k] + gam * a1);
}
// qdd1's prediction from qdd (this state's) and the past steps' (past of them used): the
// polynomial through them, one step on; and q1, v1 from it in the same pass. A loop per
// past, so that an unknown past is never read.
LEGSIM_KERNEL_TARGETS void start(int n, int past, real h, real af, real am, real beta, real gam, const R_ q,
                                 const R_ qd, const R_ qdd, const R_ acc_aux, const R_ qdd_p1, const R_ qdd_p2,
                                 R_ qdd1, R_ q1, R_ v1) {
  if (past >= 2) {
    for (int k = 0; k < n; ++k) {
      qdd1[k] = 3 * (qdd[k] - qdd_p1[k]) + qdd_p2[k];
      start_at(k, h, af, am, beta, gam, q, qd, qdd, acc_aux, qdd1[k], q1, v1);
    }
  } else if (past == 1) {
    for (int k = 0; k < n; ++k) {
      qdd1[k] = 2 * qdd[k] - qdd_p1[k];
      start_at(k, h, af, am, beta, gam, q, qd, qdd, acc_aux, qdd1[k], q1, v1);
    }
  } else {
    for (int k = 0; k < n; ++k) {
      qdd1[k] = qdd[k];
      start_at(k, h, af, am, beta, gam, q, qd, qdd, acc_aux, qdd1[k], q1, v1);
    }
  }
}
// the auxiliary acceleration's update at the end of the step
LEGSIM_KERNEL_TARGETS void acc_aux_update(int n, real af, real am, const R_ qdd, const R_ qdd1, R_ acc_aux) {
  for (int k = 0; k < n; ++k) acc_aux[k] = (af * qdd[k] + (1 - af) * qdd1[k] - am * acc_aux[k]) / (1 - am);
}
// x += y
LEGSIM_KERNEL_TARGETS void add_to(int n, R_ x, const R_ y) {
  for (int k = 0; k < n; ++k) x[k] += y[k];
}
#undef R_

// The end's velocity drift J v1 - nu taken off at the rows of q1 (at most two passes), on the
// general path. Where a contact slides its normal impulse brings its friction, as in a
// sliding impact: v1 moves along M^-1 (J^T - F E^T), the direction the step's own constraint
// forces act in. The M-orthogonal projection (a normal impulse alone) leaves an O(h^2) error
// in the slip's velocities at every step: first order over a slide. Not inlined: the step's
// own code, where the kernel's end or no contact takes it, stays as it was.
[[gnu::noinline]] legsim_status end_drift_off(const Model &m, Data &d, const Layout &lay, const VecQ &q1, real tol,
                                              VecQ &v1) {
  rows_eval(m, lay, d.stop_drivers, q1, v1, d.rows, &d.trig);
  for (int pass = 0; pass < 2 && velocity_drift(lay, d.rows, v1, d.rhs) > tol; ++pass) {
    if (!lay.nslide) {
      project(m, lay, d.rows, d.factor, m.minv, d.rows.nu, v1, d.rhs);
      continue;
    }
    for (int i = 0; i < lay.m; ++i) d.rhs[i] -= d.rows.nu[i];  // (d.rhs: J v1)
    // the Newton iteration's last coupled solve left its columns, on this factor: the rows
    // they were built from are within the tolerance of q1's, which the second pass takes off
    const legsim_status s = coupled_resolve(d, lay, d.rhs);
    if (s != LEGSIM_OK) return s;
    VecQ corr;
    constraint_forces(m, d, lay, q1, d.rhs, corr);
    for (int k = 0; k < m.nq; ++k) v1[k] -= Bodies::mass_inverse_times(m.minv, k, corr[k]);
  }
  return LEGSIM_OK;
}

// The smallest contraction estimate trusted (see the top of this file).
constexpr real kEtaMin = real(0.01);
}  // namespace

legsim_status generalized_alpha_step(const Model &m, Data &d, real h, real tol) {
  const int n = m.nq;
  const real rho = real(m.opt.rho_inf);
  const real am = (2 * rho - 1) / (rho + 1), af = rho / (rho + 1);
  const real gam = real(0.5) + af - am;
  const real beta = real(0.25) * (gam + real(0.5)) * (gam + real(0.5));
  const real bprime = (1 - am) / (h * h * beta * (1 - af));
  const real gprime = gam / (h * beta);  // dv1 / dq1

  // predictor: qdd1 extrapolated, lambda1 = lambda0 (the first iteration corrects it
  // exactly: it enters linearly)
  VecQ &q1 = d.tq[0], &v1 = d.tq[1], &qdd1 = d.tq[2], &res = d.tq[3];
  VecR lambda = d.lambda;
  const int past = d.past_steps < kPredictorOrder ? d.past_steps : kPredictorOrder;
  start(n, past, h, af, am, beta, gam, d.q.data(), d.qd.data(), d.qdd.data(), d.acc_aux.data(), d.qdd_past[0].data(),
        d.qdd_past[kPastSlots - 1].data(), qdd1.data(), q1.data(), v1.data());
  const Layout &lay = d.dyn;
  bool converged = false;
  // the last step's contraction estimate, raised to 3/4 (1 stays 1: none)
  real eta = d.newton_eta;
  eta = std::sqrt(eta) * std::sqrt(std::sqrt(eta));
  real dq_before = 0;  // the last iteration's |dq|
  // the joint rows alone: each iteration's solve generated and fused (the same values)
  const Kernel *kern = lay.path.newton;
  if (kern) factor_order(lay, d.factor);  // the iterations write its entries
  // the kernel's applied forces where it has them (Kernel::newton_fused): gravity and the
  // actuators' from its own sin/cos, unless force elements act or gravity is off
  // (applied_forces then, the kernel adding nothing); and its residual
#if LEGSIM_KERNELS_NEWTON_FUSED
  const bool kern_fused = kern && kern->newton_fused;
#else
  const bool kern_fused = false;  // (a cross build's kernels have none: its code left out)
#endif
  const bool kern_forces = kern_fused && !force_elements_act(d, m.opt.disable) &&
                           !(m.opt.disable & LEGSIM_DISABLE_GRAVITY);
  real kern_residual = 0;  // the kernel's largest |Phi|
  for (int it = 0; it < m.opt.max_newton_iter; ++it) {
    if (!kern_forces) applied_forces(m, m.opt.disable, d, q1, v1, d.force_q);
    VecQ tmp;
    if (kern) {
      const legsim_status s =
          kern_fused ? kern->newton_fused(m, d.stop_drivers, q1, v1, kern_forces ? m.gravity_force : d.force_q, d,
                                          kern_forces && !(m.opt.disable & LEGSIM_DISABLE_ACTUATORS), &d.trig, qdd1.data(),
                                          lambda, bprime, d.rows, d.factor.a.data(), d.factor.condition,
                                          kern_residual, res.data(), d.rhs, tmp.data())
                     : kern->newton(m, d.stop_drivers, q1, v1, d.force_q, &d.trig, qdd1.data(), lambda, bprime, d.rows,
                                    d.factor.a.data(), d.factor.condition, res.data(), d.rhs, tmp.data());
      d.report.condition = d.factor.condition;
      if (s != LEGSIM_OK) return s;
    } else {
      rows_eval(m, lay, d.stop_drivers, q1, v1, d.rows, &d.trig);
      legsim_status s = factor_build(lay, d.rows, m.minv, d.factor);
      d.report.condition = d.factor.condition;
      if (s != LEGSIM_OK) return s;
      // r = M qdd + J^T lambda - Q
      constraint_forces(m, d, lay, q1, lambda, res);
      // (J M^-1 J^T) dlambda = beta' Phi - J M^-1 r ;  dq = -(M^-1 / beta') (r + J^T dlambda)
      residual(n, m.mass, m.minv, qdd1.data(), d.force_q.data(), res.data(), tmp.data());
      j_times(lay, d.rows, tmp, d.rhs);
      for (int i = 0; i < lay.m; ++i) d.rhs[i] = bprime * d.rows.phi[i] - d.rhs[i];
      s = multiplier_solve(m, d, lay, q1, d.rhs);
      if (s != LEGSIM_OK) return s;
      constraint_forces(m, d, lay, q1, d.rhs, tmp);
    }
    VecQ dq;
    correct(n, bprime, gprime, m.minv, res.data(), tmp.data(), q1.data(), v1.data(), qdd1.data(),
            dq.data());
    real dq_max = 0;
    for (int k = 0; k < n; ++k) {
      const real a = std::abs(dq[k]);
      dq_max = a > dq_max ? a : dq_max;
    }
    add_to(lay.m, lambda.data(), d.rhs.data());
    d.report.iterations = it + 1;
    d.report.residual = kern_fused ? kern_residual : rows_max_residual(lay, d.rows);  // before this iteration's correction
    if (!std::isfinite(dq_max)) return LEGSIM_ERR_DIVERGED;
    if (it > 0) {  // this step's contraction (eta >= 1 once theta >= 1/2: none trusted)
      const real theta = dq_max / dq_before;
      eta = theta < real(0.5) ? theta / (1 - theta) : real(1);
      eta = eta > kEtaMin ? eta : kEtaMin;
    }
    dq_before = dq_max;
    if (dq_max <= tol || eta * dq_max <= tol) {
      converged = true;
      break;
    }
  }
  if (!converged) return LEGSIM_ERR_NOT_CONVERGED;
  // The index-3 form holds the positions on Phi = 0 but leaves the velocities off the rows by
  // O(h^2) (J v1 != nu). Projected M-weighted onto J v1 = nu, as RK4's end is, which only
  // takes kinetic energy out (with a sliding contact, along its friction too: end_drift_off;
  // that correction does the friction's work over the drift, either way, of order h^2 a step).
  // Without it a step restarted from such a velocity (after a
  // contact event, at a part step) turns the drift into a velocity jump that does not shrink
  // with the part step, and an event located on its rows acts on a foot moving off them.
  // (Projected only there, the drift grows along a run: 0.56 m/s in a throw at 27 m/s.) The
  // factor is the Newton iteration's last, J M^-1 J^T at an iterate within the tolerance of
  // q1: a second pass takes off what that difference leaves, cheaper than a new factor.
  // A model without contacts has no such restart: it keeps its cost (the Cortex-M4F leg).
  // Where the generated kernel has the end on that factor (Kernel::end_factored: the robot's),
  // the passes and the end state's solve, reactions and forces are one call, and
  // generalized_alpha_reactions has nothing left to do; not where force elements act (their
  // forces may depend on the projected velocities), nor with the reactions disabled (the
  // contacts' and stops' forces are then the iteration's, as on the general path).
  if (LEGSIM_WITH_CONTACT && m.nc > 0) d.end_solved = false;  // (never set without contacts)
  if (LEGSIM_WITH_CONTACT && m.nc > 0 && !(m.opt.disable & LEGSIM_DISABLE_PROJECTION)) {
#if LEGSIM_KERNELS_REDUCED
    const StagePlan plan = stage_plan(m, d, lay);
    if (kern && plan.kernel && plan.kernel->end_factored && !(m.opt.disable & LEGSIM_DISABLE_REACTIONS)) {
      // its multipliers (acceleration level) into d.lambda, for the forces below; the
      // iteration's are put back after
      real drift;
      d.end_solved = plan.kernel->end_factored(m, d.stop_drivers, q1, v1, *plan.base, d, plan.actuators, &d.trig,
                                               d.factor.a.data(), tol, drift, d.lambda, d.reaction) == LEGSIM_OK;
    }
#endif
    if (!d.end_solved) {
      const legsim_status s = end_drift_off(m, d, lay, q1, tol, v1);
      if (s != LEGSIM_OK) return s;
    }
  }
  acc_aux_update(n, af, am, d.qdd.data(), qdd1.data(), d.acc_aux.data());
  // the history for the next step's predictor (its order's steps: whole fixed-size vectors,
  // cheaper to copy than a run-time count of values) and test
  for (int k = kPredictorOrder - 1; k > 0; --k) d.qdd_past[k] = d.qdd_past[k - 1];
  if (kPredictorOrder > 0) d.qdd_past[0] = d.qdd;
  d.past_steps = d.past_steps < kPredictorOrder ? d.past_steps + 1 : kPredictorOrder;
  d.newton_eta = eta;
  d.q = q1;
  d.qd = v1;
  d.qdd = qdd1;
  // the ground's and the stops' forces: the end solve's where it ran (d.lambda holds its
  // multipliers), else the iteration's (generalized_alpha_reactions replaces them); the next
  // step starts from the iteration's multipliers either way
  if (LEGSIM_WITH_CONTACT && d.end_solved) stop_forces_update(m, d);
  d.lambda = lambda;
  if (!(LEGSIM_WITH_CONTACT && d.end_solved)) stop_forces_update(m, d);
  return LEGSIM_OK;
}

// The index-3 multipliers carry the position-level round-off amplified by
// beta' ~ 1/h^2 (about 1 N at h = 1 ms in float). The reactions reported are
// those of the acceleration-level solve at the step's (q, qd): well conditioned,
// the exact reactions of that state. Skipped when reactions are disabled.
legsim_status generalized_alpha_reactions(const Model &m, Data &d) {
  if (LEGSIM_WITH_CONTACT && d.end_solved) {  // the step's end solve left them (and the actuators' forces)
    d.end_solved = false;
    return LEGSIM_OK;
  }
  if (m.opt.disable & LEGSIM_DISABLE_REACTIONS) {
    actuator_forces_update(m, m.opt, d, d.q, d.qd);
    return LEGSIM_OK;
  }
  // the step's own multipliers seed the next step: keep them, so that
  // reporting reactions never changes the trajectory
  const VecR lambda = d.lambda;
  VecQ qdd;
  // the last Newton iteration's factorization (at q within newton_tol) serves
  const legsim_status s = dynamics_state_reactions(m, d, qdd, true);  // and the stops' forces
  d.lambda = lambda;
  return s;
}
#else
legsim_status generalized_alpha_step(const Model &, Data &, real, real) { return LEGSIM_ERR_DISABLED; }
legsim_status generalized_alpha_reactions(const Model &, Data &) { return LEGSIM_ERR_DISABLED; }
#endif

}  // namespace legsim
