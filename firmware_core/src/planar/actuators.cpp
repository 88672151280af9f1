// Actuators: the hard stops at the stroke ends and the layouts with length rows. Their
// forces (commands, the length servo) are applied forces: forces.cpp.
#include "sim.hpp"

namespace legsim {

legsim_status work_layout(const Model &m, Data &d, uint32_t mask) {
  if (d.work_mask == int32_t(mask)) return LEGSIM_OK;
  d.work_mask = -1;
  legsim_status s = layout_build(m, mask, 0, d.work);
  if (s == LEGSIM_OK) s = layout_finish(d.work, d.drivers);
  if (s == LEGSIM_OK) d.work_mask = int32_t(mask);
  return s;
}

legsim_status stops_layout(const Model &m, Data &d) {
  uint8_t contacts[kMaxContacts];
  contact_rows_of_states(m, d, contacts);
  legsim_status s = layout_build(m, d.stop_mask, 0, d.dyn, contacts);
  if (s == LEGSIM_OK) s = layout_finish(d.dyn, d.stop_drivers);
  d.dyn.stops = true;
  // more rows than coordinates: the surplus are dependent (factor_build drops them)
  d.dyn.surplus = RowIndex(d.dyn.m > m.nq ? d.dyn.m - m.nq : 0);
  contact_slides_mark(m, d, d.dyn);
  return s;
}

// An actuator's length at q, (r_rod - r_cyl) . u_cyl + offset: actuator_length's without
// the rate, from the cylinder's sin/cos alone (the stroke checks need no more).
real stroke_length(const Model &m, int a, const VecQ &q, TrigCache *trig) {
  const Actuator &ac = m.act[a];
  const int i = 3 * ac.cyl, j = 3 * ac.rod;
  real s, c;
  body_trig(trig, ac.cyl, q[i + 2], s, c);
  return ((q[j] - q[i]) * s + (q[j + 1] - q[i + 1]) * -c) + ac.offset_m;
}

// The stop law (one implementation, whether the arrival was located inside the step or is
// taken at a (part) step's end): an actuator past its stroke, or one in `arriving` (located
// on its end: the nearer end), is put back on its end (a projection onto Phi = 0 with that
// length held) and its velocity along the stroke removed: an inelastic impact, the velocity
// projected M-orthogonally onto the rows held (joints, closed feet, stops), so every held
// row takes its share of the impulse. From then on a length row holds it in the dynamics,
// and its multiplier is the stop's force. Raised as an event, never silent. Putting one
// actuator on its stop can push another past its end, so the check repeats.
legsim_status stroke_limits_enforce(const Model &m, Data &d, bool &changed, real into, uint32_t arriving) {
  changed = false;
  DriverValues &dv = d.stop_drivers;
  for (int pass = 0; pass <= m.na; ++pass) {
    uint32_t added = 0;
    for (int a = 0; a < m.na; ++a) {
      if (d.stop_mask & (1u << a)) continue;
      const real len = stroke_length(m, a, d.q, &d.trig);
      const Actuator &ac = m.act[a];
      const bool arrived = (arriving >> a) & 1u;
      if (!arrived && len >= ac.lmin && len <= ac.lmax) continue;
      const bool low = arrived ? len - ac.lmin < ac.lmax - len : len < ac.lmin;
      added |= 1u << a;
      d.act[a].stop_time = d.t + double(into);  // (the step starts at d.t)
      raise_event(d, low ? LEGSIM_EVENT_STROKE_MIN : LEGSIM_EVENT_STROKE_MAX);
      dv.length[a] = low ? ac.lmin : ac.lmax;
      dv.rate[a] = dv.accel[a] = 0;
    }
    if (!added) break;
    d.stroke_mask |= added;
    const uint32_t before = d.stop_mask;
    const VecQ q0 = d.q, qd0 = d.qd;
    const legsim_report report0 = d.report;
    d.stop_mask |= added;
    auto project_onto_stops = [&]() {
      legsim_status r = stops_layout(m, d);
      if (r == LEGSIM_OK) r = assemble(m, d, d.dyn, dv, d.q, m.minv, AssemblyMode::Project);
      if (r == LEGSIM_OK) r = velocity_solve(m, d, d.dyn, d.qd);
      return r;
    };
    legsim_status s = project_onto_stops();
    const uint32_t all = before | added;
    if (s == LEGSIM_ERR_NOT_CONVERGED && (all & (all - 1))) {
      // The stops over-determine the mechanism and do not agree: both feet stuck and all four
      // actuators crossing their minima in one step is 40 rows on 39 coordinates, the four
      // lengths tied by one relation, so the fourth follows from the other three and lies a
      // round-off past its end. One stop lets go, the first whose actuator then stays within
      // its stroke (to the assembly's tolerance), as if it had been reached last.
      const real tol = real(m.opt.newton_tol);
      for (int b = 0; b < m.na && s != LEGSIM_OK; ++b) {
        if (!(all & (1u << b))) continue;
        d.q = q0;
        d.qd = qd0;
        d.stop_mask = all & ~(1u << b);
        s = project_onto_stops();
        if (s != LEGSIM_OK) continue;
        const real len = stroke_length(m, b, d.q, &d.trig);
        if (len < m.act[b].lmin - tol || len > m.act[b].lmax + tol) s = LEGSIM_ERR_NOT_CONVERGED;
        else d.act[b].stop_force = 0;
      }
      if (s != LEGSIM_OK) {  // no such choice: the stops together, and their failure
        d.q = q0;
        d.qd = qd0;
        d.stop_mask = all;
        s = project_onto_stops();
      }
    }
    // velocity_solve left the factor of the system with the stop: a stop that
    // nearly locks a dead centre would make every later solve ill-conditioned
    if (s == LEGSIM_OK && factor_condition(d.factor) > real(LEGSIM_COND_SINGULAR)) s = LEGSIM_ERR_SINGULAR;
    if (s == LEGSIM_ERR_SINGULAR) {
      // A stroke end that is also a dead centre (the leg's lower stroke ends
      // where the knee is straight, as far as the geometry reaches): no stop can
      // be held there, and none is needed. Keep the integrated state, say so.
      // The report stays that of the step (the failed factorization's infinite
      // condition is not the state's).
      d.q = q0;
      d.qd = qd0;
      d.stop_mask = before;
      d.report.iterations = report0.iterations;
      d.report.residual = report0.residual;
      d.report.condition = report0.condition;
      raise_event(d, LEGSIM_EVENT_NEAR_SINGULAR);
      return stops_layout(m, d);
    }
    if (s != LEGSIM_OK) return s;
    changed = true;
  }
  return LEGSIM_OK;
}

// A stop only pushes: the shortest-length stop pushes the rod out (force > 0),
// the longest-length one pushes it in (force < 0). A stop asked to pull lets go.
legsim_status stroke_stops_release(const Model &m, Data &d, bool &changed) {
  changed = false;
  for (int a = 0; a < m.na; ++a) {
    if (!(d.stop_mask & (1u << a))) continue;
    const bool at_min = d.stop_drivers.length[a] <= m.act[a].lmin;
    const real f = d.act[a].stop_force;
    if (at_min ? f >= 0 : f <= 0) continue;
    d.stop_mask &= ~(1u << a);
    d.act[a].stop_force = 0;
    changed = true;
  }
  return changed ? stops_layout(m, d) : LEGSIM_OK;
}

}  // namespace legsim
