// Foot contact with the ground line: where a foot is, which rows each contact
// adds to the dynamics (stuck: normal and tangential rows; sliding: the normal row,
// whose multiplier also carries the friction mu_k N against the sliding), the
// ground forces from their multipliers, and the transitions between the modes
// after each step. docs/design/robot-on-ground.md section 2.
#include "sim.hpp"

namespace legsim {

void contact_point(const Model &model, int k, const VecQ &q, const VecQ &qd, Vec2 &pos, Vec2 &vel) {
  const Contact &c = model.contact[k];
  const int b = c.body;
  const real phi = q[3 * b + 2];
  const Vec2 s = c.point.x() * axis_u(phi) + c.point.y() * normal_n(phi);
  pos = Vec2(q[3 * b], q[3 * b + 1]) + s;
  vel = Vec2(qd[3 * b], qd[3 * b + 1]) + qd[3 * b + 2] * perp(s);
}

void contact_rows_of_states(const Model &model, const Data &d, uint8_t *rows) {
  for (int k = 0; k < model.nc; ++k) {
    const uint8_t st = d.contact[k].state;
    rows[k] = st == LEGSIM_CONTACT_STUCK ? kContactStuck
              : st == LEGSIM_CONTACT_SLIDING ? kContactNormal : kContactNone;
  }
}

void contact_slides_mark(const Model &model, const Data &d, Layout &layout) {
  layout.nslide = 0;
  for (int i = model.m; i < layout.m; ++i) {
    const RowSource &r = layout.src[i];
    if (r.kind != RowKind::ContactNormal || d.contact[r.index].state != LEGSIM_CONTACT_SLIDING) continue;
    layout.slide_contact[layout.nslide] = r.index;
    layout.slide_row[layout.nslide] = uint8_t(i);
    ++layout.nslide;
  }
}

// The rows of Data::dyn: joints, stops (one per actuator in stop_mask), contacts.
// The multipliers are the constraint forces with the sign of -J^T lambda: the
// ground force on the foot is -(lambda_n n + lambda_t t); a sliding foot's friction
// is dir mu_k lambda_n t (T = -dir mu_k N).
void contact_forces_update(Sim &sim) {
  const Model &m = sim.model;
  Data &d = sim.data;
  int row = m.m;
  for (int a = 0; a < m.na; ++a) row += (d.stop_mask >> a) & 1u;
  for (int k = 0; k < m.nc; ++k) {
    ContactData &c = d.contact[k];
    if (c.state == LEGSIM_CONTACT_STUCK) {
      c.normal = -d.lambda[row];
      c.tangential = -d.lambda[row + 1];
      row += 2;
    } else if (c.state == LEGSIM_CONTACT_SLIDING) {
      c.normal = -d.lambda[row];
      c.tangential = -real(c.slip_dir) * m.mu_k * c.normal;
      row += 1;
    } else {
      c.normal = c.tangential = 0;
    }
  }
}

void contacts_free(Sim &sim) {
  Data &d = sim.data;
  for (int k = 0; k < kMaxContacts; ++k) d.contact[k] = {uint8_t(LEGSIM_CONTACT_FREE), 0, 0, 0, {0, 0}, 0};
}

void contact_forces_of_layout(const Model &model, const Layout &layout, const VecR &lambda,
                              real *normal, real *tangential) {
  for (int k = 0; k < model.nc; ++k) normal[k] = tangential[k] = 0;
  for (int i = model.m; i < layout.m; ++i) {
    const RowSource &r = layout.src[i];
    if (r.kind == RowKind::ContactNormal) normal[r.index] = -lambda[i];
    if (r.kind == RowKind::ContactTangent) tangential[r.index] = -lambda[i];
  }
}

namespace {

// An inelastic impact onto the rows of Data::dyn (the new modes): the velocity jump
// v+ = v- - M^-1 (J^T mu - F E^T mu) with J v+ = nu, mu from the coupled system, and
// per contact with rows its impulse on the foot (normal, tangential), N s.
legsim_status impact(Sim &sim, const uint32_t hit) {
  const Model &m = sim.model;
  Data &d = sim.data;
  const Layout &lay = d.dyn;
  rows_eval(m, lay, d.stop_drivers, d.q, d.qd, d.rows);
  legsim_status s = factor_build(lay, d.rows, m.minv, d.factor);
  if (s != LEGSIM_OK) return s;
  VecR mu;
  j_times(lay, d.rows, d.qd, mu);
  for (int i = 0; i < lay.m; ++i) mu[i] -= d.rows.nu[i];
  if (lay.nslide) {
    s = coupled_solve(sim, lay, d.q, mu);
    if (s != LEGSIM_OK) return s;
  } else {
    factor_solve(d.factor, mu);
  }
  VecQ g;
  jt_times(m, lay, d.rows, mu, g);
  if (lay.nslide) friction_add(sim, lay, d.q, mu, -1, g);
  for (int k = 0; k < m.nq; ++k) d.qd[k] -= m.minv[k] * g[k];
  real pn[kMaxContacts], pt[kMaxContacts];
  contact_forces_of_layout(m, lay, mu, pn, pt);
  for (int k = 0; k < m.nc; ++k) {
    if (!((hit >> k) & 1u)) continue;
    ContactData &c = d.contact[k];
    if (c.state == LEGSIM_CONTACT_SLIDING) pt[k] = -real(c.slip_dir) * m.mu_k * pn[k];
    c.impulse[0] = pn[k];
    c.impulse[1] = pt[k];
  }
  return all_finite(d.qd, m.nq) ? LEGSIM_OK : LEGSIM_ERR_DIVERGED;
}

real sign_of(real x) { return x > 0 ? real(1) : real(-1); }

// The paper's rule (contact_law PAPER, design section 2) while every contact is closed
// (stuck or sliding) and there are at least two: with all of them stuck, the stuck-stuck
// reactions of the last solve decide; when a foot's |T| exceeds mu_s N, the foot with the
// SMALLEST |T| is released (it slides against its T, with mu_k N); while one slides the
// others stay stuck whatever their T. Returns the contact to release, or -1.
int paper_release(const Model &m, const Data &d) {
  bool over = false;
  for (int k = 0; k < m.nc; ++k) {
    const ContactData &c = d.contact[k];
    if (c.state != LEGSIM_CONTACT_STUCK) return -1;  // one slides already (or is free): no release
    if (std::abs(c.tangential) > m.mu_s * c.normal) over = true;
  }
  if (!over) return -1;
  int pick = 0;
  for (int k = 1; k < m.nc; ++k)
    if (std::abs(d.contact[k].tangential) < std::abs(d.contact[pick].tangential)) pick = k;
  return pick;
}

bool all_closed(const Model &m, const Data &d) {
  if (m.nc < 2) return false;
  for (int k = 0; k < m.nc; ++k)
    if (d.contact[k].state == LEGSIM_CONTACT_FREE) return false;
  return true;
}

}  // namespace

// Checked after every step, each a rule of the design (section 2):
// - touchdown: a free foot below the line is put on it (a projection, as a stroke stop)
//   and its approach removed by an inelastic impulse, stuck if the impulse is inside the
//   static cone (|P_t| <= mu_s P_n), else sliding with mu_k against its tangential velocity;
// - lift-off: a stuck or sliding foot whose normal force would pull (N < 0) is let go;
// - stick to slip: a stuck foot with |T| > mu_s N slides, against T;
// - slip to stick: a sliding foot whose sliding velocity changed sign sticks where it is (its
//   tangential velocity removed by an impulse, reported); the problem at rest then decides.
// Under contact_law PAPER, while every foot is on the ground, stick to slip is the paper's
// rule instead (paper_release): the foot with the smaller |T| is released, the other stays.
// Each pass applies every change at once and solves the dynamics of the new modes; a mode
// that keeps changing (no consistent mode, or several) raises CONTACT_INCONSISTENT and
// keeps the last one.
legsim_status contact_transitions(Sim &sim, bool &changed) {
  changed = false;
  const Model &m = sim.model;
  Data &d = sim.data;
  if (m.nc == 0) return LEGSIM_OK;
  uint32_t slipped = 0, stuck_again = 0;  // each once per check
  uint32_t changing = 0;                  // the contacts the last pass changed
  const real tol = real(sim.opt.newton_tol);
  for (int pass = 0; pass < 3 * kMaxContacts + 2; ++pass) {
    uint32_t touch = 0, to_stick = 0;
    changing = 0;
    bool any = false;
    // contact_law PAPER: while all feet are on the ground the stick-to-slip rule is the
    // paper's (paper_release), lift-off, touchdown and slip to stick are the default's
    const bool paper = sim.opt.contact_law == LEGSIM_CONTACT_PAPER && all_closed(m, d);
    const int release = paper ? paper_release(m, d) : -1;
    for (int k = 0; k < m.nc; ++k) {
      ContactData &c = d.contact[k];
      Vec2 p, v;
      contact_point(m, k, d.q, d.qd, p, v);
      const real vt = m.ground_t.dot(v);
      if (c.state == LEGSIM_CONTACT_FREE) {
        if (!(m.ground_n.dot(p - m.ground_point) < -tol)) continue;
        touch |= 1u << k;
        c.state = LEGSIM_CONTACT_STUCK;  // first as stuck: the impulse decides
        d.stop_drivers.stick[k] = m.ground_t.dot(p - m.ground_point);
        c.slip_dir = int8_t(sign_of(vt));
        c.events |= LEGSIM_EVENT_TOUCHDOWN;
        raise_event(d, LEGSIM_EVENT_TOUCHDOWN);
      } else if (c.normal < 0) {
        c.state = LEGSIM_CONTACT_FREE;
        c.normal = c.tangential = 0;
        c.events |= LEGSIM_EVENT_LIFTOFF;
        raise_event(d, LEGSIM_EVENT_LIFTOFF);
      } else if (c.state == LEGSIM_CONTACT_STUCK) {
        const bool leaves = paper ? k == release : std::abs(c.tangential) > m.mu_s * c.normal;
        if (!leaves || ((slipped >> k) & 1u)) continue;
        c.state = LEGSIM_CONTACT_SLIDING;
        c.slip_dir = int8_t(-sign_of(c.tangential));  // it gives way against the force that held it
        slipped |= 1u << k;
        c.events |= LEGSIM_EVENT_STICK_TO_SLIP;
        raise_event(d, LEGSIM_EVENT_STICK_TO_SLIP);
      } else {  // sliding
        if (!(vt * real(c.slip_dir) < 0) || (((stuck_again | slipped) >> k) & 1u)) continue;
        c.state = LEGSIM_CONTACT_STUCK;
        d.stop_drivers.stick[k] = m.ground_t.dot(p - m.ground_point);
        to_stick |= 1u << k;
        stuck_again |= 1u << k;
        c.events |= LEGSIM_EVENT_SLIP_TO_STICK;
        raise_event(d, LEGSIM_EVENT_SLIP_TO_STICK);
      }
      any = true;
      changing |= 1u << k;
    }
    if (!any) return LEGSIM_OK;
    changed = true;
    legsim_status s = stops_layout(sim);
    if (s != LEGSIM_OK) return s;
    if (touch) {  // onto the line, then the impact
      s = assemble(sim, d.dyn, d.stop_drivers, d.q, m.minv, AssemblyMode::Project);
      const VecQ approach = d.qd;
      if (s == LEGSIM_OK) s = impact(sim, touch);
      if (s != LEGSIM_OK) return s;
      bool slides = false;
      for (int k = 0; k < m.nc; ++k) {
        ContactData &c = d.contact[k];
        if (!((touch >> k) & 1u) || std::abs(c.impulse[1]) <= m.mu_s * c.impulse[0]) continue;
        c.state = LEGSIM_CONTACT_SLIDING;  // outside the cone: a sliding impact with mu_k
        slides = true;
      }
      if (slides) {  // again from the approach velocity, the friction impulse against the slip
        d.qd = approach;
        s = stops_layout(sim);
        if (s == LEGSIM_OK) s = impact(sim, touch);
        if (s != LEGSIM_OK) return s;
      }
    }
    if (to_stick) {
      s = impact(sim, to_stick);  // the tangential velocity removed
      if (s != LEGSIM_OK) return s;
    }
    s = dynamics_state_update(sim);  // forces of the new modes
    if (s != LEGSIM_OK) return s;
  }
  for (int k = 0; k < m.nc; ++k)  // the contacts still changing carry it
    if ((changing >> k) & 1u) d.contact[k].events |= LEGSIM_EVENT_CONTACT_INCONSISTENT;
  raise_event(d, LEGSIM_EVENT_CONTACT_INCONSISTENT);
  return LEGSIM_OK;
}

}  // namespace legsim
