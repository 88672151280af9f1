// The step as named stages (MuJoCo's mj_step reads the same way): the derivative at the
// start, the integrator's step, the stroke stops (impacts, then the derivative anew), the
// contacts' transitions, the stops let go; then time advances. The whole step is one
// all-or-nothing call: a failed stage leaves the state of the last good step.
// Dimension-free: the stages call the integrators and the element module's event handlers.
#include "sim.hpp"

namespace legsim {

// After the state changed outside a step: accelerations, multipliers and reactions of the
// free dynamics at the new state, and a fresh start of the generalized-alpha history.
// forcing_only (a changed command or load alone: the state, its rows and the options as
// they were): the same accelerations, from the state's factor when the last step left it
// (Factor::of_state: RK4's whole-system end solve; the same values as a fresh
// factorization; the reduced end keeps none, and its restart is the same solve anyway), and
// generalized-alpha keeps its Newton contraction estimate (the iteration matrix is the
// same) and its predictor's past, shifted by the accelerations' jump (a step change of the
// forcing moves them by about that much on either side of it): a controller that changes
// its setpoint every step costs about one Newton iteration a step, not two.
legsim_status state_refresh(Sim &sim, bool forcing_only) {
  Data &d = sim.data;
  // the history is generalized-alpha's alone: RK4 calls leave it (Snapshot), and a change of
  // integrator restarts it (legsim_set_options)
  const bool history = sim.opt.integrator == LEGSIM_INTEGRATOR_GENERALIZED_ALPHA;
  VecQ before;
  if (forcing_only && history) before = d.qdd;
  const legsim_status s = dynamics_state_reactions(sim, d.qdd, forcing_only && d.factor.of_state);
  d.derivative_valid = s == LEGSIM_OK;
  d.history_valid = s == LEGSIM_OK;
  d.forcing_only = false;
  if (!history) return s;
  if (s == LEGSIM_OK) d.acc_aux = d.qdd;
  if (s == LEGSIM_OK && forcing_only) {
    for (int k = 0; k < d.past_steps && k < kPredictorOrder; ++k)
      for (int i = 0; i < sim.model.nq; ++i) d.qdd_past[k][i] += d.qdd[i] - before[i];
  } else {
    d.past_steps = 0;  // the history starts here
    d.newton_eta = 1;
  }
  return s;
}

// A changed command or load is a discontinuity of the forcing: both integrators
// restart from the accelerations under the new forces (the generalized-alpha
// history would otherwise carry the old ones and drop to first order). The same
// value sent again changes nothing.
void commands_changed(Data &d) {
  d.forcing_only = d.forcing_only || d.derivative_valid || d.history_valid;
  d.derivative_valid = false;
  d.history_valid = false;
}

// The state, its rows or the options changed outside a step: a full restart.
void state_changed(Data &d) {
  d.derivative_valid = false;
  d.history_valid = false;
  d.forcing_only = false;
}

namespace {

// A stage's status passes on; LEGSIM_OK lets the next stage run.
// The derivative the integrator starts from: the accelerations at the current state and
// commands (RK4), or generalized-alpha's history.
inline legsim_status stage_start(Sim &s, bool rk4) {
  Data &d = s.data;
  if (rk4 ? !d.derivative_valid : !d.history_valid) return state_refresh(s, d.forcing_only);
  return LEGSIM_OK;
}

inline legsim_status stage_integrate(Sim &s, bool rk4) { return rk4 ? rk4_step(s) : generalized_alpha_step(s); }

// An actuator past an end of its stroke is put on its stop (an impact that changes q and
// qd: the derivative and reactions anew); else generalized-alpha's reactions at its end
// (RK4 leaves its end derivative and reactions itself).
inline legsim_status stage_stroke_stops(Sim &s, bool rk4, bool stops) {
  bool stopped = false;
  legsim_status r = stops ? stroke_limits_enforce(s, stopped) : LEGSIM_OK;
  if (r != LEGSIM_OK) return r;
  if (stopped) return state_refresh(s);
  return rk4 ? LEGSIM_OK : generalized_alpha_reactions(s);
}

// Touchdown, lift-off, stick and slip (contact.cpp); a change solves the derivative anew.
// A touchdown projects the state onto the feet's rows, which can push an actuator past a
// stroke end: the stops are checked after it as after the integrator's projection.
inline legsim_status stage_contacts(Sim &s, bool stops) {
  if (!s.model.nc) return LEGSIM_OK;
  bool changed = false;
  legsim_status r = contact_transitions(s, changed);
  if (r == LEGSIM_OK && changed && stops) {
    bool stopped = false;
    r = stroke_limits_enforce(s, stopped);
  }
  return r == LEGSIM_OK && changed ? state_refresh(s) : r;
}

// A stop that would have to pull lets go.
inline legsim_status stage_stops_release(Sim &s, bool stops) {
  if (!stops) return LEGSIM_OK;
  bool released = false;
  const legsim_status r = stroke_stops_release(s, released);
  return r == LEGSIM_OK && released ? state_refresh(s) : r;
}

inline void stage_advance(Sim &s, bool rk4) {
  Data &d = s.data;
  if (rk4) d.derivative_valid = true;  // its end derivative is the next step's start
  if (s.opt.step_s != d.origin_step_s) {  // a new step size: the time line starts here
    d.origin_t = d.t;
    d.origin_steps = d.steps;
    d.origin_step_s = s.opt.step_s;
  }
  ++d.steps;
  d.t = d.origin_t + static_cast<double>(d.steps - d.origin_steps) * d.origin_step_s;
  if (d.report.condition > real(LEGSIM_COND_WARN)) raise_event(d, LEGSIM_EVENT_NEAR_SINGULAR);
}

}  // namespace

legsim_status steps_run(Sim &s, int32_t n_steps) {
  const bool rk4 = s.opt.integrator == LEGSIM_INTEGRATOR_RK4;
  const bool stops = !(s.opt.disable & LEGSIM_DISABLE_STROKE_LIMITS);
  for (int32_t i = 0; i < n_steps; ++i) {
    // a failed step leaves the state of the last good one (all_or_nothing also
    // refuses a step whose state, accelerations, multipliers or report are not finite)
    const legsim_status st = all_or_nothing(s, [&] {
      legsim_status r = stage_start(s, rk4);
      if (r == LEGSIM_OK) r = stage_integrate(s, rk4);
      if (r == LEGSIM_OK) r = stage_stroke_stops(s, rk4, stops);
      if (r == LEGSIM_OK) r = stage_contacts(s, stops);
      if (r == LEGSIM_OK) r = stage_stops_release(s, stops);
      if (r != LEGSIM_OK) return r;
      stage_advance(s, rk4);
      return LEGSIM_OK;
    });
    if (st != LEGSIM_OK) return st;
  }
  return LEGSIM_OK;
}

}  // namespace legsim
