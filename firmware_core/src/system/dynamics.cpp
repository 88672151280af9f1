// Accelerations and multipliers: M qdd + Phi_q^T lambda = Q, Phi_q qdd = gamma,
// by the Schur complement (Phi_q M^-1 Phi_q^T) lambda = Phi_q M^-1 Q - gamma
// (M is diagonal, so this is the whole cost).
#include <utility>

#include "planar/kernel.hpp"
#include "planar/mass.hpp"
#include "system/dense_solve.hpp"
#include "system/solve.hpp"

namespace legsim {

namespace {
// Q at (q, qd) for a solve on layout.
void layout_forces(const Model &m, Data &d, const Layout &layout, const VecQ &q, const VecQ &qd) {
  applied_forces(m, layout_disable(m, layout), d, q, qd, d.force_q);
}

#if LEGSIM_KERNELS_REDUCED
// The reduced solves' base forces (Kernel::accelerations): gravity alone, the model's own,
// unless it is disabled or force elements act (then applied_forces' without the actuators,
// which the solves apply). actuators: whether they act.
// elements: whether force elements act (their forces may depend on the velocities).
const VecQ &reduced_base(const Model &m, Data &d, const Layout &layout, const VecQ &q, const VecQ &qd, bool &actuators,
                         bool &elements) {
  const uint32_t disable = layout_disable(m, layout);
  actuators = !(disable & LEGSIM_DISABLE_ACTUATORS);
  elements = force_elements_act(d, disable);
  if (!(disable & LEGSIM_DISABLE_GRAVITY) && !elements) return m.gravity_force;
  applied_forces(m, disable | LEGSIM_DISABLE_ACTUATORS, d, q, qd, d.force_q);
  return d.force_q;
}
#endif
}  // namespace

legsim_status dynamics_solve(const Model &m, Data &d, const Layout &layout, const VecQ &q, const VecQ &qd, VecQ &qdd,
                             bool rows_ready, bool keep, legsim_reaction *reaction) {
  const Kernel *kern = layout.path.dynamics;
  layout_forces(m, d, layout, q, qd);
  if (kern && !rows_ready) {
    // the joint rows alone: the generated solve, fused (the same values as below)
    Factor &f = d.factor;
    // without keep, no condition estimate either (the factor is not kept, the step reports
    // its end's): the report says infinite for a singular matrix still, and a stage whose
    // accelerations are not finite leaves the last estimate there
    const legsim_status s = kern->dynamics(m, layout.stops ? d.stop_drivers : d.drivers, q, qd, d.force_q, &d.trig, keep ? &d.rows : nullptr,
                                           keep ? f.a.data() : nullptr, keep ? &f.condition : nullptr, d.lambda, qdd, reaction);
    if (keep) {
      factor_order(layout, f);
      d.report.condition = f.condition;
    } else if (s == LEGSIM_ERR_SINGULAR) {
      d.report.condition = real(INFINITY);
    }
    return s;
  }
  if (!rows_ready) {
    rows_eval(m, layout, layout.stops ? d.stop_drivers : d.drivers, q, qd, d.rows, &d.trig);
    const legsim_status s = factor_build(layout, d.rows, m.minv, d.factor);
    d.report.condition = d.factor.condition;
    if (s != LEGSIM_OK) return s;
  }
  VecQ tmp;
  for (int k = 0; k < m.nq; ++k) tmp[k] = Bodies::mass_inverse_times(m.minv, k, d.force_q[k]);
  j_times(layout, d.rows, tmp, d.lambda);
  for (int i = 0; i < layout.m; ++i) d.lambda[i] -= d.rows.gamma[i];
  if (const legsim_status s = multiplier_solve(m, d, layout, q, d.lambda); s != LEGSIM_OK) return s;
  constraint_forces(m, d, layout, q, d.lambda, tmp);
  for (int k = 0; k < m.nq; ++k) qdd[k] = Bodies::mass_inverse_times(m.minv, k, d.force_q[k] - tmp[k]);
  if (!all_finite(qdd, m.nq)) return LEGSIM_ERR_DIVERGED;
  if (reaction) reactions_from_multipliers(m, d.rows, d.lambda, reaction);
  return LEGSIM_OK;
}

legsim_status dynamics_stage_solve(const Model &m, Data &d, const Layout &layout, const VecQ &q, const VecQ &qd, VecQ &qdd) {
#if LEGSIM_KERNELS_REDUCED
  if (stage_available(m, layout)) {
    bool actuators, elements;
    const VecQ &base = reduced_base(m, d, layout, q, qd, actuators, elements);
    return reduced_stage(m, d, *stage_kernel(layout), layout.stops ? d.stop_drivers : d.drivers, base, actuators,
                         q, qd, qdd);
  }
#endif
  return dynamics_solve(m, d, layout, q, qd, qdd, false, false);
}

#if LEGSIM_KERNELS_REDUCED
legsim_status dynamics_end(const Model &m, Data &d, const StagePlan &plan, const VecQ &q, VecQ &qd, VecQ &qdd, VecR &lambda,
                           legsim_reaction *reaction, real tol, bool project, real &residual, real &drift) {
  const Layout &layout = *plan.layout;
  bool actuators = plan.actuators, elements = false;
  const VecQ &base = plan.kernel ? *plan.base : reduced_base(m, d, layout, q, qd, actuators, elements);
  d.factor.of_state = false;  // it keeps no factor: whatever d.factor holds is not this state's
  // the stages' sin/cos cache: on x86-64 this runs in their copy with FMA (stage_trig)
  return layout.path.reduced->end(m, layout.stops ? d.stop_drivers : d.drivers, q, qd, base, d, actuators,
                            stage_trig(d), tol, project && !elements, residual, drift, d.report.condition,
                            lambda, qdd, reaction);
}
#endif

#if LEGSIM_WITH_CONTACT
// M qdd = Q - J^T lambda + F E^T lambda, J qdd = gamma: (A - J M^-1 F E^T) lambda = rhs with
// A = J M^-1 J^T. With U = -J M^-1 F: lambda = x - Z (I + E^T Z)^-1 E^T x, x = A^-1 rhs,
// Z = A^-1 U (Woodbury, the columns in d.slide_z). At most kMaxContacts columns: a small
// dense elimination.
namespace {
inline legsim_status woodbury(Data &d, const Layout &layout, VecR &x) {
  const int ns = layout.nslide;
  const VecR *z = d.slide_z;
  factor_solve(d.factor, x);
  // C y = E^T x, C = I + E^T Z; a vanishing pivot: friction that cancels the normal
  // stiffness (Painleve). Zeroed first: GCC cannot tell that only the first ns rows and
  // columns are read (an LTO link's -Wmaybe-uninitialized).
  real c[kMaxContacts * kMaxContacts] = {}, y[kMaxContacts] = {};
  for (int i = 0; i < ns; ++i) {
    for (int j = 0; j < ns; ++j) c[i * ns + j] = (i == j ? real(1) : real(0)) + z[j][layout.slide_row[i]];
    y[i] = x[layout.slide_row[i]];
  }
  if (!dense_solve(ns, c, y, real(1e-9))) return LEGSIM_ERR_CONTACT;
  for (int j = 0; j < ns; ++j)
    for (int i = 0; i < layout.m; ++i) x[i] -= z[j][i] * y[j];
  return LEGSIM_OK;
}
}  // namespace

legsim_status coupled_solve(const Model &m, Data &d, const Layout &layout, const VecQ &q, VecR &x) {
  for (int j = 0; j < layout.nslide; ++j) {
    const int k = layout.slide_contact[j], b = m.contact[k].body;
    real f[kBodyDof];
    friction_column(m, d, k, q, f);
    VecQ mf = VecQ::Zero();
    for (int c = 0; c < kBodyDof; ++c) mf[kBodyDof * b + c] = -Bodies::mass_inverse_times(m.minv, kBodyDof * b + c, f[c]);
    j_times(layout, d.rows, mf, d.slide_z[j]);
    factor_solve(d.factor, d.slide_z[j]);
  }
  return woodbury(d, layout, x);
}

legsim_status coupled_resolve(Data &d, const Layout &layout, VecR &x) { return woodbury(d, layout, x); }
#else  // nothing slides without contacts (no layout has a sliding row)
legsim_status coupled_solve(const Model &, Data &, const Layout &, const VecQ &, VecR &) { return LEGSIM_ERR_DISABLED; }
legsim_status coupled_resolve(Data &, const Layout &, VecR &) { return LEGSIM_ERR_DISABLED; }
#endif

void stop_forces_update(const Model &m, Data &d) {
  int row = m.m;  // the stop rows follow the joints, in actuator order
  for (int a = 0; a < m.na; ++a)
    d.act[a].stop_force = (d.stop_mask & (1u << a)) ? -d.lambda[row++] : real(0);
  if (m.nc > 0) contact_forces_update(m, d);  // the contact rows follow the stops
}

legsim_status dynamics_state_update(const Model &m, Data &d) { return dynamics_state_reactions(m, d, d.qdd); }

legsim_status dynamics_state_factored(const Model &m, Data &d) {
  return dynamics_state_reactions(m, d, d.qdd, false, true);
}

legsim_status dynamics_state_reactions(const Model &m, Data &d, VecQ &qdd, bool factor_ready, bool keep_factor) {
  (void)keep_factor;  // (a build without the reduced solves always keeps them)
  const Layout &lay = d.dyn;
  const Kernel *kern = lay.path.factored;
#if LEGSIM_KERNELS_REDUCED
  if (m.opt.integrator == LEGSIM_INTEGRATOR_RK4 && reduced_available(lay) && !keep_factor) {
    // RK4's restart as its step's end, in the reduced system: the same solve whatever came
    // before (a changed command alone or not), so a refused call changes no later result
    const bool reactions = !(m.opt.disable & LEGSIM_DISABLE_REACTIONS);
    real residual, drift;  // (no projection test here: the report's residual stays the step's)
    const legsim_status s = dynamics_end(m, d, stage_plan(m, d, lay), d.q, d.qd, qdd, d.lambda, reactions ? d.reaction : nullptr,
                                         real(INFINITY), false, residual, drift);
    if (s != LEGSIM_OK) return s;
    stop_forces_update(m, d);
    return LEGSIM_OK;
  }
#endif
  if (factor_ready && kern) {
    // the joint rows alone, their factor given: the generated solve, fused, with the
    // reactions (the same values as below)
    layout_forces(m, d, lay, d.q, d.qd);
    const bool reactions = !(m.opt.disable & LEGSIM_DISABLE_REACTIONS);
    const legsim_status s = kern->factored(m, lay.stops ? d.stop_drivers : d.drivers, d.q, d.qd, d.force_q,
                                           &d.trig, d.factor.a.data(), d.lambda, qdd, reactions ? d.reaction : nullptr);
    if (s != LEGSIM_OK) return s;
    stop_forces_update(m, d);
    return LEGSIM_OK;
  }
  if (factor_ready) rows_eval(m, d.dyn, d.stop_drivers, d.q, d.qd, d.rows, &d.trig);
  const bool reactions = !(m.opt.disable & LEGSIM_DISABLE_REACTIONS);
  const legsim_status s = dynamics_solve(m, d, d.dyn, d.q, d.qd, qdd, factor_ready, true, reactions ? d.reaction : nullptr);
  if (s != LEGSIM_OK) return s;
  stop_forces_update(m, d);
  return LEGSIM_OK;
}

}  // namespace legsim
