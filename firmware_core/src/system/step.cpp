// The step as named stages (MuJoCo's mj_step reads the same way): the derivative at the
// start, the integrator's step, the stroke stops (impacts, then the derivative anew), the
// contacts' transitions, the stops let go; then time advances. The whole step is one
// all-or-nothing call: a failed stage leaves the state of the last good step.
// Dimension-free: the stages call the integrators and the element module's event handlers.
#include <limits>
#include <new>
#include <type_traits>

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
legsim_status state_refresh(const Model &m, Data &d, bool forcing_only) {
  d.modes_checked = false;  // (a step sets it again at its end)
  // the history is generalized-alpha's alone: RK4 calls leave it (Snapshot), and a change of
  // integrator restarts it (legsim_set_options)
  const bool history = m.opt.integrator == LEGSIM_INTEGRATOR_GENERALIZED_ALPHA;
  VecQ before;
  if (forcing_only && history) before = d.qdd;
  const legsim_status s = dynamics_state_reactions(m, d, d.qdd, forcing_only && d.factor.of_state);
  d.derivative_valid = s == LEGSIM_OK;
  d.history_valid = s == LEGSIM_OK;
  d.forcing_only = false;
  if (!history) return s;
  if (s == LEGSIM_OK) d.acc_aux = d.qdd;
  if (s == LEGSIM_OK && forcing_only) {
    for (int k = 0; k < d.past_steps && k < kPredictorOrder; ++k)
      for (int i = 0; i < m.nq; ++i) d.qdd_past[k][i] += d.qdd[i] - before[i];
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
  d.end_solved = false;
}

namespace {

// A stage's status passes on; LEGSIM_OK lets the next stage run.
// The derivative the integrator starts from: the accelerations at the current state and
// commands (RK4), or generalized-alpha's history. After a change from outside (a state, a
// contact mode or a command set) the contact modes are checked at once, at the step's start
// time: a starting state that cannot hold (stuck feet on a slope steeper than the friction
// allows) is resolved at t, not after the first step.
inline legsim_status stage_start(const Model &m, Data &d, bool rk4) {
  legsim_status r = LEGSIM_OK;
  if (rk4 ? !d.derivative_valid : !d.history_valid) r = state_refresh(m, d, d.forcing_only);
  if (r != LEGSIM_OK || !m.nc || d.modes_checked) return r;
  d.modes_checked = true;
  bool changed = false;
  r = contact_transitions(m, d, changed, d.t);
  return r == LEGSIM_OK && changed ? state_refresh(m, d) : r;
}

inline legsim_status stage_integrate(const Model &m, Data &d, bool rk4, real h) {
  return rk4 ? rk4_step(m, d, h) : generalized_alpha_step(m, d, h, real(m.opt.newton_tol));
}

// An actuator past an end of its stroke is put on its stop `into` s after the step's start
// (an impact that changes q and qd: the derivative and reactions anew); else
// generalized-alpha's reactions at its end (RK4 leaves its end derivative and reactions
// itself). stops = false: the reactions alone (a part step whose stop arrivals are located).
inline legsim_status stage_stroke_stops(const Model &m, Data &d, bool rk4, bool stops, bool &stopped, real into) {
  stopped = false;
  legsim_status r = stops ? stroke_limits_enforce(m, d, stopped, into) : LEGSIM_OK;
  if (r != LEGSIM_OK) return r;
  if (stopped) return state_refresh(m, d);
  return rk4 ? LEGSIM_OK : generalized_alpha_reactions(m, d);
}

// Touchdown, lift-off, stick and slip (contact.cpp) at time `at`, the located ones first; a
// change solves the derivative anew (and restarts generalized-alpha's history). A touchdown
// projects the state onto the feet's rows, which can push an actuator past a stroke end: the
// stops are checked after it as after the integrator's projection.
inline legsim_status stage_contacts(const Model &m, Data &d, bool stops, double at,
                                    const ContactEvents *located = nullptr) {
  if (!m.nc) return LEGSIM_OK;
  bool changed = false;
  legsim_status r = contact_transitions(m, d, changed, at, located);
  if (r == LEGSIM_OK && changed && stops) {
    bool stopped = false;
    r = stroke_limits_enforce(m, d, stopped, real(at - d.t));
    if (r == LEGSIM_OK && stopped) {
      // a stop put on changes the ground forces: the contacts checked once more (a closed
      // foot that would now pull lifts off); the state refreshed again only if one changes
      r = state_refresh(m, d);
      bool again = false;
      if (r == LEGSIM_OK) r = contact_transitions(m, d, again, at);
      if (r != LEGSIM_OK || !again) return r;
    }
  }
  return r == LEGSIM_OK && changed ? state_refresh(m, d) : r;
}

// A stop that would have to pull lets go. The ground forces change with it: the contacts are
// checked again at the step's time plus `done` (a foot that the stop's force held on the
// ground would pull now: it lifts off, rather than slide into the next step with N < 0, its
// friction pushing along the slip, where no event function starts positive to find it).
inline legsim_status stage_stops_release(const Model &m, Data &d, bool stops, real done) {
  if (!stops) return LEGSIM_OK;
  bool released = false;
  legsim_status r = stroke_stops_release(m, d, released);
  if (r != LEGSIM_OK || !released) return r;
  r = state_refresh(m, d);
  return r == LEGSIM_OK ? stage_contacts(m, d, stops, d.t + double(done)) : r;
}

inline void stage_advance(Data &d, bool rk4) {
  if (rk4) d.derivative_valid = true;  // its end derivative is the next step's start
  ++d.steps;
  d.t = d.origin_t + static_cast<double>(d.steps - d.origin_steps) * d.origin_step_s;
  if (d.report.condition > real(LEGSIM_COND_WARN)) raise_event(d, LEGSIM_EVENT_NEAR_SINGULAR);
}

#if LEGSIM_WITH_CONTACT  // a build whose models have no contacts has no events to locate
// ---- contact events and stroke stops located inside the step (docs/design/events.md) ----
// Per contact two event functions of its mode, each > 0 while the mode holds (function
// 2k + j):
// [0] free: the gap n . (p - p0) (touchdown); stuck or sliding: N (lift-off);
// [1] stuck: mu_s N - |T| (stick to slip); sliding: dir v_t (slip to stick); free: none.
// Per actuator off its stops two (function kActBase + 2a + j): [0] L - L_min, [1] L_max - L
// (the stop's arrival); on a stop: none (its release is taken at the (part) step's end).
// A function counts when it is > 0 at the (part) step's start and < 0 at its end.
constexpr real kNoEvent = real(1e30);
constexpr int kActBase = 2 * kMaxContacts;
constexpr int kFunctions = kActBase + 2 * kMaxActuators;
using EventBits = uint64_t;  // bit f: function f
static_assert(kFunctions <= 64, "one bit per event function");
inline bool is_stop(int f) { return f >= kActBase; }
inline int stop_actuator(int f) { return (f - kActBase) / 2; }
constexpr real kThetaTol = real(1e-6);  // the root's tolerance, in parts of the (part) step
constexpr int kLocateIterations = 12;
// The located function at the real part step's end must be 0 to its slope times this part of
// the step; else the bracket shrinks to the part step (past the root) or starts there
// (before it), at most kRefinements times.
constexpr real kRefineTol = real(1e-7);
constexpr int kRefinements = 12;
constexpr int kHalvings = 4;
constexpr int kMaxParts = 2 * LEGSIM_MAX_EVENTS_PER_STEP;  // halved part steps a step takes

struct EventValues {
  real g[kFunctions];
};

// Whether function j of contact k in its current mode needs the ground forces (a solve).
inline bool needs_forces(const ContactData &c, int j) {
  return c.state != LEGSIM_CONTACT_FREE && (j == 0 || c.state == LEGSIM_CONTACT_STUCK);
}

// Function j of contact k (in c's mode) at (q, v) with ground forces N, T (those of its mode).
real event_value(const Model &m, int k, const ContactData &c, int j, const VecQ &q, const VecQ &v, real n_force,
                 real t_force) {
  if (c.state == LEGSIM_CONTACT_FREE && j == 1) return kNoEvent;
  if (needs_forces(c, j)) return j == 0 ? n_force : m.mu_s * n_force - std::abs(t_force);
  Vec2 p, pv;
  contact_point(m, k, q, v, p, pv);
  return j == 0 ? m.ground_n.dot(p - m.ground_point) : real(c.slip_dir) * m.ground_t.dot(pv);
}

// Actuator a's two stop functions at q (m): g[0] = L - L_min, g[1] = L_max - L.
inline void stop_values(const Model &m, int a, const VecQ &q, TrigCache *trig, real *g) {
  const real len = stroke_length(m, a, q, trig);
  g[0] = len - m.act[a].lmin;
  g[1] = m.act[a].lmax - len;
}

// The functions at (q, qd) with the contacts' modes and the forces of their last solve
// (contact) and the stops on (stop_mask): the sim's state, or a step's start kept in its
// snapshot. The contact law PAPER decides stick to slip by its own rule (not one contact at a
// time): not located. stops: the stroke stops are in force (their arrivals located).
void event_values_of(const Model &m, Data &d, bool stops, const VecQ &q, const VecQ &qd, const ContactData *contact,
                     uint32_t stop_mask, EventValues &e) {
  const bool cone = m.opt.contact_law != LEGSIM_CONTACT_PAPER;
  for (real &g : e.g) g = kNoEvent;
  for (int k = 0; k < m.nc; ++k) {
    const ContactData &c = contact[k];
    for (int j = 0; j < 2; ++j)
      e.g[2 * k + j] = (j == 1 && c.state == LEGSIM_CONTACT_STUCK && !cone)
                           ? kNoEvent
                           : event_value(m, k, c, j, q, qd, c.normal, c.tangential);
  }
  if (!stops) return;
  for (int a = 0; a < m.na; ++a)
    if (!((stop_mask >> a) & 1u)) stop_values(m, a, q, &d.trig, &e.g[kActBase + 2 * a]);
}
void event_values(const Model &m, Data &d, bool stops, EventValues &e) {
  event_values_of(m, d, stops, d.q, d.qd, d.contact, d.stop_mask, e);
}
// Whether a function is below zero (a crossing needs one at the (part) step's end).
bool any_below_zero(const EventValues &e) {
  bool below = false;
  for (int f = 0; f < kFunctions; ++f) below = below || e.g[f] < 0;
  return below;
}

// The functions that changed sign over the (part) step (bit f).
EventBits crossings(const EventValues &start, const EventValues &end) {
  EventBits cross = 0;
  for (int f = 0; f < kFunctions; ++f)
    if (start.g[f] > 0 && end.g[f] < 0 && start.g[f] < kNoEvent) cross |= EventBits(1) << f;
  return cross;
}

// The (part) step's end, kept while the state is put back to its start to locate an event.
struct StepEnd {
  VecQ q, v, a;
};

// The step's dense output at theta in [0, 1]: the quintic Hermite interpolant of the start
// (sim's state: q0, v0, a0) and end (q1, v1, a1) over hs seconds (local error O(hs^6) for
// RK4's values, consistent to generalized-alpha's order for its), and its derivative.
void dense_output(const Model &m, const Data &d, const StepEnd &e, real hs, real th, VecQ &q, VecQ &v) {
  const real t2 = th * th, t3 = t2 * th, t4 = t3 * th, t5 = t4 * th;
  const real h0 = 1 - 10 * t3 + 15 * t4 - 6 * t5, h1 = th - 6 * t3 + 8 * t4 - 3 * t5;
  const real h2 = real(0.5) * (t2 - 3 * t3 + 3 * t4 - t5), h3 = 10 * t3 - 15 * t4 + 6 * t5;
  const real h4 = -4 * t3 + 7 * t4 - 3 * t5, h5 = real(0.5) * (t3 - 2 * t4 + t5);
  const real d0 = -30 * t2 + 60 * t3 - 30 * t4, d1 = 1 - 18 * t2 + 32 * t3 - 15 * t4;
  const real d2 = real(0.5) * (2 * th - 9 * t2 + 12 * t3 - 5 * t4), d3 = -d0;
  const real d4 = -12 * t2 + 28 * t3 - 15 * t4, d5 = real(0.5) * (3 * t2 - 8 * t3 + 5 * t4);
  const real hh = hs * hs;
  for (int i = 0; i < m.nq; ++i) {
    q[i] = h0 * d.q[i] + h3 * e.q[i] + hs * (h1 * d.qd[i] + h4 * e.v[i]) + hh * (h2 * d.qdd[i] + h5 * e.a[i]);
    v[i] = (d0 * d.q[i] + d3 * e.q[i]) / hs + d1 * d.qd[i] + d4 * e.v[i] + hs * (d2 * d.qdd[i] + d5 * e.a[i]);
  }
}

// Function f at theta on the dense output; a function of the forces solves the dynamics of
// the current modes there (its multipliers give N and T).
legsim_status event_at(const Model &m, Data &d, const StepEnd &e, real hs, int f, real th, real &g) {
  VecQ q, v, a;
  dense_output(m, d, e, hs, th, q, v);
  if (is_stop(f)) {
    real pair[2];
    stop_values(m, stop_actuator(f), q, nullptr, pair);
    g = pair[f % 2];
    return std::isfinite(g) ? LEGSIM_OK : LEGSIM_ERR_DIVERGED;
  }
  const int k = f / 2, j = f % 2;
  real n_force = 0, t_force = 0;
  if (needs_forces(d.contact[k], j)) {
    const legsim_status r = dynamics_solve(m, d, d.dyn, q, v, a, false, false, nullptr);
    if (r != LEGSIM_OK) return r;
    real normal[kMaxContacts], tangential[kMaxContacts];
    contact_forces_of_layout(m, d.dyn, d.lambda, normal, tangential);
    n_force = normal[k];
    t_force = tangential[k];
  }
  g = event_value(m, k, d.contact[k], j, q, v, n_force, t_force);
  return std::isfinite(g) ? LEGSIM_OK : LEGSIM_ERR_DIVERGED;
}

// The root of function f on [0, 1] (g(0) = g0 > 0 > g(1) = g1) by the Illinois variant of
// regula falsi, to kThetaTol in at most kLocateIterations evaluations. theta: the bracket's
// late end (g <= 0: the event surely happened there); exact = false when the iterations ran
// out (the bracket's late end all the same).
legsim_status event_root(const Model &m, Data &d, const StepEnd &e, real hs, int f, real g0, real g1, real &theta, bool &exact,
                         real &slope) {
  real a = 0, b = 1, ga = g0, gb = g1;
  real fa = g0, fb = g1;  // the values at a and b (Illinois halves ga, gb)
  int side = 0;
  exact = false;
  bool bisect = false;  // the late end's value is not known (its solve failed)
  for (int it = 0; it < kLocateIterations; ++it) {
    real c = bisect ? real(0.5) * (a + b) : (a * gb - b * ga) / (gb - ga);
    if (!(c > a && c < b)) c = real(0.5) * (a + b);
    real gc;
    const legsim_status r = event_at(m, d, e, hs, f, c, gc);
    // a mode whose dynamics cannot be solved there (a sliding foot far past its lift-off:
    // the friction's coupling singular) has surely ended before: the late end, bisected
    bisect = r != LEGSIM_OK;
    if (bisect) {
      b = c;
      side = 0;
      continue;
    }
    if (gc > 0) {
      a = c, ga = fa = gc;
      if (side < 0) gb /= 2;
      side = -1;
    } else {
      b = c, gb = fb = gc;
      if (side > 0) ga /= 2;
      side = 1;
    }
    if (b - a <= kThetaTol || gc == 0) {
      exact = true;
      break;
    }
  }
  theta = b;
  slope = (fb - fa) / (b - a);  // dg / dtheta at the root (< 0)
  return LEGSIM_OK;
}

// The earliest of the crossing functions (with the start in the sim's state, the end in e):
// theta, and the events within kThetaTol of it (simultaneous: a level drop lands both feet
// at once) in ev (contacts) and arriving (bit a: actuator a reaches a stop).
// first: the earliest function (f), slope: its dg / dtheta there.
legsim_status events_locate(const Model &m, Data &d, const StepEnd &e, real hs, const EventValues &g0, const EventValues &g1,
                            EventBits cross, ContactEvents &ev, uint32_t &arriving, real &theta, bool &exact,
                            int &first, real &slope) {
  real at[kFunctions];
  theta = 1;
  exact = true;
  first = -1;
  slope = 0;
  for (int f = 0; f < kFunctions; ++f) {
    at[f] = 2;
    if (!((cross >> f) & 1u)) continue;
    bool ok;
    real dg;
    const legsim_status r = event_root(m, d, e, hs, f, g0.g[f], g1.g[f], at[f], ok, dg);
    if (r != LEGSIM_OK) return r;
    if (at[f] < theta || first < 0) theta = at[f], first = f, slope = dg;
    exact = exact && ok;
  }
  arriving = 0;
  for (int f = kActBase; f < kFunctions; ++f)
    if (at[f] <= theta + kThetaTol) arriving |= 1u << stop_actuator(f);
  ev = ContactEvents{0, 0, 0, 0};
  for (int k = 0; k < m.nc; ++k) {
    const ContactData &c = d.contact[k];
    for (int j = 0; j < 2; ++j) {
      if (!(at[2 * k + j] <= theta + kThetaTol)) continue;
      const uint32_t bit = 1u << k;
      if (c.state == LEGSIM_CONTACT_FREE) ev.touchdown |= bit;
      else if (j == 0) ev.liftoff |= bit;
      else if (c.state == LEGSIM_CONTACT_STUCK) ev.slip |= bit;
      else ev.stick |= bit;
    }
  }
  // a contact that lifts off does not also slip or stick
  ev.slip &= ~ev.liftoff;
  ev.stick &= ~ev.liftoff;
  return LEGSIM_OK;
}

// Whether function f, g0 > 0 at the part step's start, is a force whose bracket [fa, fb]
// has both ends above |g0| once the refinements ran out: a pole, not a root (out of line:
// step_with_events' plain step keeps its cost).
[[gnu::noinline]] bool force_pole(const Data &d, int f, real g0, real fa, real fb) {
  return !is_stop(f) && needs_forces(d.contact[f / 2], f % 2) &&
         std::min(std::abs(fa), std::abs(fb)) > std::abs(g0);
}

// A part step shorter than this is not taken (its change is within the location's tolerance).
inline real tiny_step(real h) { return kThetaTol * h; }

// A part step's start again: the snapshot, the derivative, and generalized-alpha's history
// restarted (h enters it, and a part step's h is its own).
legsim_status part_restart(const Model &m, Data &d, bool rk4, const Snapshot &from) {
  from.restore(m, d);
  const legsim_status r = stage_start(m, d, rk4);
  if (!rk4) {
    d.acc_aux = d.qdd;
    d.past_steps = 0;
  }
  return r;
}

// An RK4 part step inside an event's step, split into equal sub-steps until halving them
// changes the positions by at most kPartTol (m, rad; step doubling): a mode between two
// events of one step can be far faster than the step (a sliding foot whose normal force
// falls to zero within 23 us of its slip onset, the friction's share of its motion growing
// without bound): one RK4 step over it leaves an error that no smaller h removes. split:
// the sub-steps to start from (the last part's), at most kPartMaxSplit; it returns with the
// finer of the last two tries taken. Generalized-alpha takes the part step whole (its
// history restarts at every part step; a split would restart it at each sub-step).
constexpr real kPartTol = real(1e-12);
constexpr int kPartMaxSplit = 16;

legsim_status part_steps(const Model &m, Data &d, real dt, int n) {
  legsim_status r = LEGSIM_OK;
  for (int i = 0; i < n && r == LEGSIM_OK; ++i) r = stage_integrate(m, d, true, dt / real(n));
  return r;
}

legsim_status part_integrate(const Model &m, Data &d, bool rk4, real dt, const Snapshot &from, int &split) {
  if (!rk4) return stage_integrate(m, d, false, dt);
  const int nq = m.nq;
  legsim_status r = part_steps(m, d, dt, split);
  while (r == LEGSIM_OK && split < kPartMaxSplit) {
    const VecQ coarse = d.q;
    r = part_restart(m, d, true, from);
    if (r == LEGSIM_OK) r = part_steps(m, d, dt, 2 * split);
    if (r != LEGSIM_OK) {  // the finer try fails (a mode carried past its domain): the coarse
      r = part_restart(m, d, true, from);
      return r == LEGSIM_OK ? part_steps(m, d, dt, split) : r;
    }
    split *= 2;
    real change = 0;
    for (int i = 0; i < nq; ++i) change = std::max(change, std::abs(d.q[i] - coarse[i]));
    if (!(change > kPartTol)) break;  // a NaN splits no further: the guard refuses it
  }
  return r;
}

// Generalized-alpha's part steps after a located event in the step. A new mode can be far
// faster than the step (a sliding foot whose normal force falls to zero within 23 us of its
// slip onset): one step over it ends past the next event unseen (N growing again, the slip
// reversed). So after an event whose new modes end soon (ga_event_imminent) each part step is
// sized by step doubling: halved until one step and two half steps (the history going on
// between them) agree in the positions and in hs times the velocities to kGaPartTol times
// the Newton tolerance (m, rad; 1e-11 at its default 1e-10), at most kGaPartHalvings times;
// the two half steps are taken, Richardson-extrapolated (positions and velocities: the local
// error of order hs^3 taken off; the difference is far below the positions' scale, so the
// rows hold to its square). The next part starts at most kGaPartGrow times longer; at most
// kGaMaxParts such parts, then the rest is taken whole. Far smaller differences than the
// Newton tolerance are the iterations' noise: halving on them runs the parts down to nothing.
constexpr real kGaPartTol = real(0.1);
constexpr int kGaPartHalvings = 12;
constexpr real kGaPartGrow = 4;
constexpr int kGaMaxParts = 64;
constexpr real kGaMaxRescale = 64;  // the history rescaled to h from a sub-step of >= h / 64

// The part's start again, as the part step first took it (no mode check: stage_start's
// would take the modes' changes at the step's start time), for a step of h_new. Its
// auxiliary acceleration (Arnold & Bruls: acc_aux ~ qdd(t + (am - af) h), so acc_aux - qdd
// ~ (am - af) h qdd'): after an event, qdd + (am - af) h_new jerk (the new modes' jerk); in
// the same modes as the last (sub-)step of h_prev, its acc_aux - qdd rescaled to h_new. A
// plain restart (acc_aux = qdd) leaves an O(h_new^2) error in each part's velocities, which
// the many parts of a fast mode add up.
// The history's acc_aux - qdd (about (am - af) h qdd') carried from a step of h_old to one
// of f h_old.
void ga_history_rescale(const Model &m, Data &d, real f) {
  for (int i = 0; i < m.nq; ++i) d.acc_aux[i] = d.qdd[i] + (d.acc_aux[i] - d.qdd[i]) * f;
}

legsim_status ga_part_restart(const Model &m, Data &d, const Snapshot &from, real h_prev, real h_new, const VecQ *jerk) {
  from.restore(m, d);
  const legsim_status r = d.history_valid ? LEGSIM_OK : state_refresh(m, d);
  if (r == LEGSIM_OK && h_prev > 0) {
    ga_history_rescale(m, d, h_new / h_prev);
  } else if (r == LEGSIM_OK && jerk) {
    const real rho = real(m.opt.rho_inf);
    const real shift = (rho - 1) / (rho + 1) * h_new;  // (am - af) h_new
    for (int i = 0; i < m.nq; ++i) d.acc_aux[i] = d.qdd[i] + shift * (*jerk)[i];
  } else {
    d.acc_aux = d.qdd;
  }
  d.past_steps = 0;
  return r;
}

// A generalized-alpha step of hs < h inside a part: the index-3 form turns the Newton
// iteration's position tolerance into velocities over hs and accelerations over hs^2, so
// the tolerance shrinks by (hs / h)^2 (the errors as at h), down to 64 round-offs. The
// iteration's contraction (h^2 K / M) shrinks alike: about one iteration more.
legsim_status ga_sub_step(const Model &m, Data &d, real hs) {
  const double tol = m.opt.newton_tol;
  const double f = double(hs) / double(m.step_h);
  const double sub_tol = std::min(tol, std::max(tol * f * f, 64.0 * double(std::numeric_limits<real>::epsilon())));
  return generalized_alpha_step(m, d, hs, real(sub_tol));
}

// One adaptive part step from `from` (see above). hs: the part step asked (in), taken (out);
// h_prev, jerk: ga_part_restart's.
legsim_status ga_part_adaptive(const Model &m, Data &d, real &hs, const Snapshot &from, real h_prev, const VecQ *jerk) {
  const int nq = m.nq;
  // the difference asked, and never below what the coordinates' round-off allows (a float
  // build's 1e-7 m would be below a rounding step of a coordinate past 1 m: no try passes)
  real qmax = 0;
  for (int i = 0; i < nq; ++i) qmax = std::max(qmax, std::abs(from.q[i]));
  const real tol = std::max(kGaPartTol * real(m.opt.newton_tol),
                            real(64) * std::numeric_limits<real>::epsilon() * (1 + qmax));
  legsim_status r = ga_part_restart(m, d, from, h_prev, hs, jerk);
  if (r != LEGSIM_OK) return r;
  r = ga_sub_step(m, d, hs);
  bool coarse_ok = r == LEGSIM_OK;
  VecQ coarse = d.q, coarse_v = d.qd;
  for (int halving = 0;; ++halving) {
    r = ga_part_restart(m, d, from, h_prev, real(0.5) * hs, jerk);
    if (r != LEGSIM_OK) return r;
    legsim_status rf = ga_sub_step(m, d, real(0.5) * hs);
    const bool half_ok = rf == LEGSIM_OK;
    const VecQ half = d.q, half_v = d.qd;
    if (half_ok) rf = ga_sub_step(m, d, real(0.5) * hs);
    real change = real(1e30);  // a failed try (a mode past its domain) halves on
    if (coarse_ok && rf == LEGSIM_OK) {
      change = 0;
      for (int i = 0; i < nq; ++i)
        change = std::max(change, std::max(std::abs(d.q[i] - coarse[i]), hs * std::abs(d.qd[i] - coarse_v[i])));
    }
    if (change <= tol) {  // (a NaN does not pass)
      for (int i = 0; i < nq; ++i) {
        d.q[i] += (d.q[i] - coarse[i]) / 3;
        d.qd[i] += (d.qd[i] - coarse_v[i]) / 3;
      }
      d.end_solved = false;  // the last sub-step's end solve is not this state's
      return rf;
    }
    if (halving == kGaPartHalvings) return rf;  // the halvings ran out: the finest try
    hs *= real(0.5);
    coarse = half, coarse_v = half_v;
    coarse_ok = half_ok;
  }
}

// After an event (the sim at the rest's start, in its new modes): whether an event function
// of the new modes is predicted to cross within kGaImminent times the rest (s), by each
// function's rate, from a forward difference over dt_j (one dynamics solve; the functions at
// their boundary, `fresh`, left out): a new mode that ends soon (a foot whose normal force
// falls to zero within 23 us of its slip onset) takes the rest in adaptive part steps; any
// other, one part step, as before. The same solve gives the new modes' jerk (jerk_ok: it
// could be solved; a mode that cannot be solved a moment on is taken adaptively).
constexpr real kGaImminent = 2;

[[gnu::noinline]] bool ga_event_imminent(const Model &m, Data &d, bool stops, EventBits fresh, real rest, VecQ &jerk, bool &jerk_ok) {
  const real dt_j = real(1e-4) * m.step_h;
  EventValues g0;
  event_values(m, d, stops, g0);  // (the forces of the state's own solve)
  VecQ q2, v2, a2;
  for (int i = 0; i < m.nq; ++i) {
    q2[i] = d.q[i] + dt_j * d.qd[i] + real(0.5) * dt_j * dt_j * d.qdd[i];
    v2[i] = d.qd[i] + dt_j * d.qdd[i];
  }
  jerk_ok = dynamics_solve(m, d, d.dyn, q2, v2, a2, false, false, nullptr) == LEGSIM_OK;
  if (!jerk_ok) return true;
  for (int i = 0; i < m.nq; ++i) jerk[i] = (a2[i] - d.qdd[i]) / dt_j;
  real normal[kMaxContacts], tangential[kMaxContacts];
  contact_forces_of_layout(m, d.dyn, d.lambda, normal, tangential);
  EventValues g1;
  for (real &g : g1.g) g = kNoEvent;
  for (int k = 0; k < m.nc; ++k)
    for (int j = 0; j < 2; ++j) g1.g[2 * k + j] = event_value(m, k, d.contact[k], j, q2, v2, normal[k], tangential[k]);
  if (stops)
    for (int a = 0; a < m.na; ++a) stop_values(m, a, q2, nullptr, &g1.g[kActBase + 2 * a]);
  for (int f = 0; f < kFunctions; ++f) {
    if (((fresh >> f) & 1u) || !(g0.g[f] > 0 && g0.g[f] < kNoEvent) || !std::isfinite(g1.g[f])) continue;
    const real fall = g0.g[f] - g1.g[f];  // over dt_j
    if (fall > 0 && g0.g[f] * dt_j < kGaImminent * rest * fall) return true;
  }
  return false;
}

// One step of h = opt.step_s with its events (contacts, stroke stop arrivals) located inside
// it: the step taken whole; when an event function of the current modes changed sign over
// it, the earliest root is located on the step's dense output, the step taken again to the
// event, the event applied there, and the rest of the step taken from it (located again, up
// to LEGSIM_MAX_EVENTS_PER_STEP events; beyond, the rest are taken at the step's end with
// LEGSIM_EVENT_EVENTS_DEFERRED). start: the state the step started from (all_or_nothing's).
// A stop's release (its force would pull) is taken at the end of the (part) step.
[[gnu::noinline]] legsim_status step_with_events(const Model &m, Data &d, bool rk4, bool stops, const Snapshot &start) {
  const real h = m.step_h;
  const bool contacts = m.nc > 0;
  real done = 0;  // the part of the step taken, s
  int located = 0, parts = 0;  // parts: halved part steps (kMaxParts)
  int ga_parts = 0;             // generalized-alpha's adaptive parts (kGaMaxParts), apart
  bool locate = true;  // false once the events are deferred to the step's end
  // the rest's start, after an event: built there, left unbuilt by a step without one (an
  // empty std::optional<Snapshot> is 3 KB of zeros a step)
  union MidStart {
    MidStart() {}
    Snapshot at;
  } mid;
  static_assert(std::is_trivially_destructible_v<Snapshot>, "rebuilt in place without destruction");
  const Snapshot *from = &start;
  // the functions a located event put at their boundary (bit 2k + 1: v_t = 0 after a slip
  // onset, |T| = mu_s N after a slip to stick or a landing; a stop's pair after its arrival,
  // should the stop not hold: a dead centre): not located again in this step (they would be
  // found at once, at round-off), their sign change is taken at its end
  EventBits fresh = 0;
  bool stopped = false;
  // generalized-alpha after a located event whose new modes end soon: its part steps
  // adaptive (ga_part_adaptive); ga is set when adapt is
  bool adapt = false;
  struct {
    real hs_last;  // the last part step taken (an adaptive one grows from it)
    real h_from;   // the history's last sub-step (s) at the part's start; 0 after an event
    real h_sub;    // the last adaptive part's sub-step (s)
    bool jerk_ok;
    VecQ jerk;     // d qdd / dt of the new modes after the event
  } ga;
  // The functions at the step's start are needed only where one is below zero at the (part)
  // step's end. Where stage_start changes nothing (the common step) the start is `start`
  // exactly: they are taken from it then, if at all; else at once, as at a part's start.
  bool g0_from_start = (rk4 ? d.derivative_valid : d.history_valid) && (d.modes_checked || !contacts);
  legsim_status r = stage_start(m, d, rk4);
  for (;;) {
    if (r != LEGSIM_OK) return r;
    EventValues g0;
    bool g0_known = !g0_from_start;
    g0_from_start = false;
    if (g0_known) event_values(m, d, stops, g0);
    real hs = h - done;
    if (adapt && ga_parts >= kGaMaxParts) adapt = false;  // the rest whole (a bounded step)
    if (adapt) {
      hs = std::min(hs, kGaPartGrow * ga.hs_last);
      r = ga_part_adaptive(m, d, hs, *from, ga.h_from, ga.jerk_ok ? &ga.jerk : nullptr);
      ga.hs_last = hs;
      ga.h_sub = real(0.5) * hs;  // the history's (sub-)step, for the next part or step
    } else {
      r = stage_integrate(m, d, rk4, hs);
    }
    // A mode carried far past its event can leave its domain (a sliding foot well past its
    // lift-off: the Newton iteration or the friction's coupling fails): the part step is
    // halved (at most kHalvings times) to find a state before that, from which it goes on.
    for (int halving = 0; r != LEGSIM_OK && contacts && halving < kHalvings && parts < kMaxParts; ++halving) {
      r = part_restart(m, d, rk4, *from);
      if (r != LEGSIM_OK) return r;
      hs /= 2;
      r = stage_integrate(m, d, rk4, hs);
      if (adapt) ga.h_sub = hs;  // (a plain part step: its history's step)
    }
    const bool partial = hs < h - done;  // the part step ends before the step
    if (r == LEGSIM_OK) r = stage_stroke_stops(m, d, rk4, false, stopped, 0);  // (the reactions)
    if (r != LEGSIM_OK) break;
    EventValues g1;
    event_values(m, d, stops, g1);
    if (!g0_known && locate && any_below_zero(g1)) {
      event_values_of(m, d, stops, start.q, start.qd, start.contact, start.stop_mask, g0);
      g0_known = true;
    }
    const EventBits cross = locate && g0_known ? crossings(g0, g1) & ~fresh : 0u;
    if (cross && located == LEGSIM_MAX_EVENTS_PER_STEP) {
      // the rest at the step's end, as without location
      raise_event(d, LEGSIM_EVENT_EVENTS_DEFERRED);
      locate = false;
    }
    if (!cross || !locate) {
      // a stop not located (deferred, or started on its end) is taken at this end; g1 holds
      // the lengths already (an actuator past an end has a negative function)
      bool past = false;
      for (int f = kActBase; f < kFunctions; ++f) past = past || g1.g[f] < 0;
      if (stops && past) r = stroke_limits_enforce(m, d, stopped, done + hs);
      if (r == LEGSIM_OK && stopped) r = state_refresh(m, d);
      if (r != LEGSIM_OK || !partial) break;
      if (adapt)
        ++ga_parts;
      else
        ++parts;
      done += hs;  // the rest of the step from here
      from = new (&mid.at) Snapshot(m, d);
      if (adapt) ga.h_from = ga.h_sub;  // the same modes go on (the history rescaled)
      if (!rk4) {
        d.acc_aux = d.qdd;
        d.past_steps = 0;
      }
      continue;
    }
    // the end kept, the start put back: the event located between them on the dense output,
    // then the part step to it taken; the located function there must be 0 to 1e-4 h (its
    // slope times that): past it, located again over the shorter part step (its dense output
    // is better); before it, that state starts the rest of the step (located again from it)
    StepEnd end;
    end.q = d.q, end.v = d.qd, end.a = d.qdd;
    from->restore(m, d);
    r = stage_start(m, d, rk4);
    if (r != LEGSIM_OK) return r;
    ContactEvents ev;
    uint32_t arriving;
    real theta, slope;
    bool exact;
    int first;
    r = events_locate(m, d, end, hs, g0, g1, cross, ev, arriving, theta, exact, first, slope);
    if (r != LEGSIM_OK) return r;
    if (!exact) raise_event(d, LEGSIM_EVENT_EVENT_INEXACT);
    // The part step to the root found, taken for real: the located function there must be 0
    // to its slope times kRefineTol h; else the root is sought on the real part steps (Illinois
    // on their values, the bracket [0, hs] of the step's own values), at most kRefinements.
    const real tol = std::abs(slope) * kRefineTol * h / hs;
    real ra = 0, rb = hs, fa = g0.g[first], fb = g1.g[first];
    int side = 0;
    real he = theta * hs, g_prev = 0, h_prev = 0;
    int split = 1;  // the part step to the event's sub-steps (part_integrate)
    bool short_of_root = false;
    for (int refine = 0;; ++refine) {
      // the start again (the location's solves and the last part step wrote over it)
      r = adapt ? ga_part_restart(m, d, *from, ga.h_from, he, ga.jerk_ok ? &ga.jerk : nullptr) : part_restart(m, d, rk4, *from);
      if (r != LEGSIM_OK) return r;
      if (!(he > tiny_step(h))) break;
      r = adapt ? ga_sub_step(m, d, he) : part_integrate(m, d, rk4, he, *from, split);
      if (r == LEGSIM_OK) r = stage_stroke_stops(m, d, rk4, false, stopped, 0);  // (the reactions)
      if (r != LEGSIM_OK && refine < kRefinements) {  // past the mode's domain: bisected
        rb = he, side = 1;
        he = real(0.5) * (ra + rb);
        continue;
      }
      if (r != LEGSIM_OK) return r;
      EventValues ge;
      event_values(m, d, stops, ge);
      const real gf = ge.g[first];
      // the distance to the root, by the slope of the interpolant (first) or of the last two
      // part steps' values (after), never steeper than the interpolant's: past its event a
      // mode's values can blow up, and a secant through them would take a point far from
      // the root for one within the tolerance
      const real slope_now = refine == 0 ? slope / hs
                                         : std::min(std::abs((gf - g_prev) / (he - h_prev)), std::abs(slope / hs));
      if (refine == 0 ? std::abs(gf) <= tol : std::abs(gf) <= slope_now * kRefineTol * h) break;
      g_prev = gf, h_prev = he;
      if (refine == kRefinements) {  // the refinements ran out: taken here
        raise_event(d, LEGSIM_EVENT_EVENT_INEXACT);
        // a force whose bracket's ends both exceed its start passes through a pole, not a root
        // (a sliding foot's normal force where the friction's coupling turns singular:
        // Painleve's paradox): its mode has no usable solution there, and the part steps
        // towards it gain energy without bound. Refused; a shorter step meets the mode's end
        // before it (its modes check at a step's end)
        if (force_pole(d, first, g0.g[first], fa, fb)) return LEGSIM_ERR_CONTACT;
        // still short of its root: the step's trial crossed where its part steps do not reach
        // (a motion the step does not resolve); the event is not taken here (a stop or a foot
        // put there would jump), the rest is located again from here
        short_of_root = gf > slope_now * kRefineTol * h;
        break;
      }
      // regula falsi, bisecting when an end is kept twice (a mode far past its event can
      // make the late end's value huge: the mode's motion leaves its domain there)
      const bool again = gf > 0 ? side < 0 : side > 0;
      if (gf > 0) ra = he, fa = gf, side = -1;
      else rb = he, fb = gf, side = 1;
      he = again ? real(0.5) * (ra + rb) : (ra * fb - rb * fa) / (fb - fa);
      if (!(he > ra && he < rb)) he = real(0.5) * (ra + rb);
    }
    done += he;
    ++located;
    if (short_of_root) {  // no event: the rest of the step from here, as after a part step
      if (!(h - done > tiny_step(h))) return stage_contacts(m, d, stops, d.t + double(h));
      from = new (&mid.at) Snapshot(m, d);
      if (adapt) ga.h_from = he;  // (its one sub-step)
      if (!rk4) {
        d.acc_aux = d.qdd;
        d.past_steps = 0;
      }
      continue;
    }
    const double t_event = d.t + double(done);
    // the stops first (the arriving ones, and any other past its end), then the contacts'
    // events and checks with the forces of the state on its stops
    if (stops) {
      r = stroke_limits_enforce(m, d, stopped, done, arriving);
      if (r == LEGSIM_OK && stopped) r = state_refresh(m, d);
    }
    if (r == LEGSIM_OK) r = stage_contacts(m, d, stops, t_event, &ev);
    if (r == LEGSIM_OK) r = stage_stops_release(m, d, stops, done);
    if (r != LEGSIM_OK) return r;
    if (!(h - done > tiny_step(h))) return stage_contacts(m, d, stops, d.t + double(h));  // the event ends the step
    for (int k = 0; k < m.nc; ++k)
      if (((ev.touchdown | ev.slip | ev.stick) >> k) & 1u) fresh |= EventBits(1) << (2 * k + 1);
    for (int a = 0; a < m.na; ++a)
      if ((arriving >> a) & 1u) fresh |= EventBits(3) << (kActBase + 2 * a);
    from = new (&mid.at) Snapshot(m, d);
    if (!rk4) {  // the rest is a part step too
      d.acc_aux = d.qdd;
      d.past_steps = 0;
      adapt = ga_parts < kGaMaxParts && ga_event_imminent(m, d, stops, fresh, h - done, ga.jerk, ga.jerk_ok);
      if (!adapt) {  // the probe's solve wrote over the multipliers: the rest as before
        mid.at.restore(m, d);
        d.acc_aux = d.qdd;
        d.past_steps = 0;
      }
      ga.hs_last = h - done;
      ga.h_from = 0;
      ga.h_sub = 0;
    }
  }
  if (r != LEGSIM_OK) return r;
  if (adapt && ga.h_sub > 0) {
    // the next step's history: the auxiliary acceleration of the last sub-step rescaled to h;
    // from a sub-step far shorter than h (a late event, halvings run out) that difference is
    // mostly the Newton iteration's noise, which the rescale would blow up: a restart instead
    const real f = h / ga.h_sub;
    if (f <= kGaMaxRescale)
      ga_history_rescale(m, d, f);
    else
      d.acc_aux = d.qdd;
    d.past_steps = 0;
  }
  return stage_contacts(m, d, stops, d.t + double(h));
}

#endif

// One whole step of a model without contacts (the leg): none of step_with_events' snapshots
// and dense output on its stack (a Cortex-M4F leg image has 3 KB of stack). Its only events
// are the stops' arrivals: where the event code is built, a step that takes one at its end is
// taken again from its start with the arrival located (the rare step pays; the others pay a
// branch); a build without it (LEGSIM_MAX_CONTACTS = 0: the Cortex-M4F leg image, whose flash
// it does not fit) takes the arrival at the step's end.
legsim_status step_whole(const Model &m, Data &d, bool rk4, bool stops, real h, const Snapshot &start) {
  legsim_status r = stage_start(m, d, rk4);
  if (r == LEGSIM_OK) r = stage_integrate(m, d, rk4, h);
  bool stopped = false;
  if (r == LEGSIM_OK) r = stage_stroke_stops(m, d, rk4, stops, stopped, h);
#if LEGSIM_WITH_CONTACT
  if (r == LEGSIM_OK && stopped) {
    start.restore(m, d);
    r = step_with_events(m, d, rk4, stops, start);
  }
#else
  (void)start;
#endif
  return r;
}

}  // namespace

legsim_status contact_modes_check(const Model &m, Data &d) {
  const bool rk4 = m.opt.integrator == LEGSIM_INTEGRATOR_RK4;
  return all_or_nothing(m, d, [&] { return stage_start(m, d, rk4); });
}

legsim_status steps_run(const Model &m, Data &d, int32_t n_steps) {
  const bool rk4 = m.opt.integrator == LEGSIM_INTEGRATOR_RK4;
  const bool stops = !(m.opt.disable & LEGSIM_DISABLE_STROKE_LIMITS);
  const bool events = m.nc > 0;  // a model with contacts has events to locate
  const real h = m.step_h;  // read once: Data's writes may alias the model's values
  for (int32_t i = 0; i < n_steps; ++i) {
    // a failed step leaves the state of the last good one (all_or_nothing also
    // refuses a step whose state, accelerations, multipliers or report are not finite)
    const legsim_status st = all_or_nothing(m, d, [&](const Snapshot &start) {
#if LEGSIM_WITH_CONTACT
      legsim_status r = events ? step_with_events(m, d, rk4, stops, start) : step_whole(m, d, rk4, stops, h, start);
#else
      (void)events;
      legsim_status r = step_whole(m, d, rk4, stops, h, start);
#endif
      if (r == LEGSIM_OK) r = stage_stops_release(m, d, stops, h);
      if (r != LEGSIM_OK) return r;
      d.modes_checked = true;
      stage_advance(d, rk4);
      return LEGSIM_OK;
    });
    if (st != LEGSIM_OK) return st;
  }
  return LEGSIM_OK;
}

}  // namespace legsim
