// Foot contact with the ground line: where a foot is, which rows each contact
// adds to the dynamics (stuck: normal and tangential rows; sliding: the normal row,
// whose multiplier also carries the friction mu_k N against the sliding), the
// ground forces from their multipliers, and the transitions between the modes
// after each step. docs/design/robot-on-ground.md section 2.
#include <limits>

#include "sim.hpp"
#include "system/solve.hpp"

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
    layout.slide_row[layout.nslide] = RowIndex(i);
    ++layout.nslide;
  }
}

// The rows of Data::dyn: joints, stops (one per actuator in stop_mask), contacts.
// The multipliers are the constraint forces with the sign of -J^T lambda: the
// ground force on the foot is -(lambda_n n + lambda_t t); a sliding foot's friction
// is dir mu_k lambda_n t (T = -dir mu_k N).
void contact_forces_update(const Model &m, Data &d) {
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

void contacts_free(Data &d) {
  for (int k = 0; k < kMaxContacts; ++k) d.contact[k] = {uint8_t(LEGSIM_CONTACT_FREE), 0, 0, 0, {0, 0}, 0, 0};
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
legsim_status impact(const Model &m, Data &d, const uint32_t hit) {
  const Layout &lay = d.dyn;
  rows_eval(m, lay, d.stop_drivers, d.q, d.qd, d.rows);
  legsim_status s = factor_build(lay, d.rows, m.minv, d.factor);
  if (s != LEGSIM_OK) return s;
  VecR mu;
  j_times(lay, d.rows, d.qd, mu);
  for (int i = 0; i < lay.m; ++i) mu[i] -= d.rows.nu[i];
  s = multiplier_solve(m, d, lay, d.q, mu);
  if (s != LEGSIM_OK) return s;
  VecQ g;
  constraint_forces(m, d, lay, d.q, mu, g);
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

// One candidate of the impact problem: the contacts in `leave` free, the others of `hit`
// closed in the modes they came with (a landing foot first stuck), the impact from the
// approach velocity; a landing foot whose impulse falls outside the static cone
// (|P_t| > mu_s P_n) slides with mu_k against its approach's tangential velocity, and the
// impact is taken again from the approach. Leaves d.qd, the modes and the impulses of it.
legsim_status impact_candidate(const Model &m, Data &d, uint32_t hit, uint32_t touch, uint32_t leave, const VecQ &approach,
                               const ContactData *start) {
  for (int k = 0; k < m.nc; ++k) {
    if (!((hit >> k) & 1u)) continue;
    d.contact[k] = start[k];
    if ((leave >> k) & 1u) d.contact[k].state = LEGSIM_CONTACT_FREE;
    d.contact[k].impulse[0] = d.contact[k].impulse[1] = 0;
  }
  d.qd = approach;
  legsim_status s = stops_layout(m, d);
  if (s != LEGSIM_OK || !(hit & ~leave)) return s;  // nothing closed: no impulse
  s = impact(m, d, hit & ~leave);
  if (s != LEGSIM_OK) return s;
  bool slides = false;
  for (int k = 0; k < m.nc; ++k) {
    ContactData &c = d.contact[k];
    if (!(((touch & ~leave) >> k) & 1u) || std::abs(c.impulse[1]) <= m.mu_s * c.impulse[0]) continue;
    c.state = LEGSIM_CONTACT_SLIDING;  // outside the cone: a sliding impact with mu_k
    slides = true;
  }
  if (!slides) return LEGSIM_OK;
  d.qd = approach;
  s = stops_layout(m, d);
  return s == LEGSIM_OK ? impact(m, d, hit & ~leave) : s;
}

// The inelastic impact of the closed contacts `hit` (the landing ones `touch` among them,
// already on the line) as the linear complementarity problem of its normal impulses:
// P_n >= 0, the post-impact normal velocity v_n >= 0, P_n v_n = 0 per contact. Solved
// exactly by enumerating its active sets (which contacts leave: 2^n candidates, n <= the
// contact slots): a candidate holds when every closed contact's P_n >= 0 and every leaving
// one separates (v_n >= 0), to round-off. A contact that leaves goes free with no impulse
// (LEGSIM_EVENT_LIFTOFF). The tangential impulse keeps its rule (impact_candidate). With
// stuck feet the problem's matrix is positive definite and one candidate holds; a sliding
// impact's non-symmetric coupling (large mu_k) can make several hold: then the one closest
// to the approach wins (the candidates in the order of how many contacts differ from
// "the contacts separating before the impact leave, the others stay"), with
// CONTACT_AMBIGUOUS. None holds: CONTACT_INCONSISTENT, and the first candidate in that
// order whose impulses do not pull (all leaving always qualifies). So an impulse never
// pulls, and the solve is bounded: 2^n candidates, at most two impact solves each, and
// one more for the chosen one.
legsim_status impact_lcp(const Model &m, Data &d, uint32_t hit, uint32_t touch) {
  const VecQ approach = d.qd;
  ContactData start[kMaxContacts];
  real vmax = 0, vn[kMaxContacts];
  for (int k = 0; k < m.nc; ++k) {
    start[k] = d.contact[k];
    Vec2 p, v;
    contact_point(m, k, d.q, approach, p, v);
    vn[k] = m.ground_n.dot(v);
    if ((hit >> k) & 1u) vmax = std::max(vmax, std::abs(vn[k]));
  }
  const real eps = real(1e4) * std::numeric_limits<real>::epsilon();
  const real tol_v = eps * (1 + vmax);
  uint32_t guess = 0;  // the contacts separating before the impact
  for (int k = 0; k < m.nc; ++k)
    if (((hit >> k) & 1u) && vn[k] > tol_v) guess |= 1u << k;
  int found = 0;
  uint32_t chosen = hit, fallback = hit;
  bool have_fallback = false;
  for (int ndiff = 0; ndiff <= m.nc; ++ndiff) {
    for (uint32_t leave = 0; leave < (1u << m.nc); ++leave) {
      if ((leave & ~hit) || __builtin_popcount(leave ^ guess) != ndiff) continue;
      legsim_status s = impact_candidate(m, d, hit, touch, leave, approach, start);
      if (s != LEGSIM_OK) continue;  // a singular candidate is no solution
      real pmax = 0;
      for (int k = 0; k < m.nc; ++k)
        if ((hit >> k) & 1u) pmax = std::max(pmax, std::abs(d.contact[k].impulse[0]));
      const real tol_p = eps * (1 + pmax);
      bool pulls = false, sinks = false;
      for (int k = 0; k < m.nc; ++k) {
        if (!((hit >> k) & 1u)) continue;
        if ((leave >> k) & 1u) {
          Vec2 p, v;
          contact_point(m, k, d.q, d.qd, p, v);
          if (m.ground_n.dot(v) < -tol_v) sinks = true;
        } else if (!(d.contact[k].impulse[0] >= -tol_p)) {
          pulls = true;
        }
      }
      if (!pulls && !have_fallback) fallback = leave, have_fallback = true;
      if (pulls || sinks) continue;
      if (found++ == 0) chosen = leave;
    }
  }
  if (found > 1) raise_event(d, LEGSIM_EVENT_CONTACT_AMBIGUOUS);
  if (!found) {
    raise_event(d, LEGSIM_EVENT_CONTACT_INCONSISTENT);
    chosen = fallback;
  }
  legsim_status s = impact_candidate(m, d, hit, touch, chosen, approach, start);
  if (s != LEGSIM_OK) return s;
  for (int k = 0; k < m.nc; ++k) {
    if (!((hit >> k) & 1u)) continue;
    ContactData &c = d.contact[k];
    if (found > 1) c.events |= LEGSIM_EVENT_CONTACT_AMBIGUOUS;
    if (!found) c.events |= LEGSIM_EVENT_CONTACT_INCONSISTENT;
    if (!((chosen >> k) & 1u)) continue;
    c.normal = c.tangential = 0;
    c.events |= LEGSIM_EVENT_LIFTOFF;
    raise_event(d, LEGSIM_EVENT_LIFTOFF);
  }
  return LEGSIM_OK;
}

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

// The modes of one closed contact in the enumeration (design section 2, step 5).
enum Mode : uint8_t { kStick, kSlipPlus, kSlipMinus, kSlide, kFree };

// Solves the small contact problem a = W f + b of the closed contacts (n <= kMaxContacts,
// per contact (normal, tangential), f = (N, T)) in the given modes, as
// legsim_bench.reference.contact_analytic.contact_modes does, and says whether the solution
// keeps every inequality of its modes: a free contact does not sink (a_n >= 0), a closed one
// does not pull (N >= 0), a stuck one holds (|T| <= mu_s N, a_t = 0), one starting to slip
// does so on the static cone (T = -s mu_s N) in its direction (s a_t > 0), a sliding one
// keeps T = -dir mu_k N. tol_f, tol_a: round-off allowances (N, m/s^2).
bool mode_consistent(const Model &m, int n, const real (&W)[2 * kMaxContacts][2 * kMaxContacts],
                     const real *b, const uint8_t *mode, const int8_t *dir, real tol_f, real tol_a) {
  const int nr = 2 * n;
  real A[2 * kMaxContacts][2 * kMaxContacts + 1] = {};
  for (int i = 0; i < n; ++i) {
    const int rn = 2 * i, rt = 2 * i + 1;
    if (mode[i] == kFree) {
      A[rn][rn] = A[rt][rt] = 1;
      continue;
    }
    for (int j = 0; j < nr; ++j) A[rn][j] = W[rn][j];  // a_n = 0
    A[rn][nr] = -b[rn];
    if (mode[i] == kStick) {
      for (int j = 0; j < nr; ++j) A[rt][j] = W[rt][j];  // a_t = 0
      A[rt][nr] = -b[rt];
    } else {
      const real sgn = mode[i] == kSlipPlus ? real(1) : mode[i] == kSlipMinus ? real(-1) : real(dir[i]);
      A[rt][rt] = 1;
      A[rt][rn] = sgn * (mode[i] == kSlide ? m.mu_k : m.mu_s);  // T + s mu N = 0
    }
  }
  for (int col = 0; col < nr; ++col) {  // Gaussian elimination, partial pivoting
    int piv = col;
    for (int i = col + 1; i < nr; ++i)
      if (std::abs(A[i][col]) > std::abs(A[piv][col])) piv = i;
    if (!(std::abs(A[piv][col]) > real(1e-12))) return false;  // a singular mode: not a solution
    for (int j = 0; j <= nr; ++j) std::swap(A[col][j], A[piv][j]);
    for (int i = col + 1; i < nr; ++i) {
      const real r = A[i][col] / A[col][col];
      for (int j = col; j <= nr; ++j) A[i][j] -= r * A[col][j];
    }
  }
  real f[2 * kMaxContacts];
  for (int i = nr - 1; i >= 0; --i) {
    real acc = A[i][nr];
    for (int j = i + 1; j < nr; ++j) acc -= A[i][j] * f[j];
    f[i] = acc / A[i][i];
  }
  for (int i = 0; i < n; ++i) {
    const int rn = 2 * i, rt = 2 * i + 1;
    real an = b[rn], at = b[rt];
    for (int j = 0; j < nr; ++j) {
      an += W[rn][j] * f[j];
      at += W[rt][j] * f[j];
    }
    if (!std::isfinite(f[rn]) || !std::isfinite(f[rt])) return false;
    if (mode[i] == kFree) {
      if (an < -tol_a) return false;
      continue;
    }
    if (f[rn] < -tol_f) return false;
    if (mode[i] == kStick && std::abs(f[rt]) > m.mu_s * f[rn] + tol_f) return false;
    if (mode[i] == kSlipPlus && !(at > tol_a)) return false;
    if (mode[i] == kSlipMinus && !(at < -tol_a)) return false;
  }
  return true;
}

// Section 2, step 5: the current modes of the closed contacts failed their inequalities.
// Every closed contact is held stuck where it is for one solve (a stuck one keeps its stick
// point); its Delassus matrix W comes from the factor of that solve, W^-1 = (S^-1)_cc with
// S = J M^-1 J^T (one solve per contact row), and b = W lambda_c (a = W f + b, f = -lambda:
// the accelerations of the gap and of the tangential offset). Then each combination of modes
// (at tangential rest: stick, slip+, slip-, free; sliding: slide, free; at most 4^2 = 16) is
// one small dense solve, and the first consistent combination in the priority order wins:
// the current mode first, then stick before slip, then contact before lift-off (the least sum
// of the ranks current 0, stick 1, slip 2, free 3; ties by enumeration order). Several
// consistent: CONTACT_AMBIGUOUS. The chosen modes are set (events raised, d.contact[k].events
// too), d.dyn rebuilt and solved. found = false (none consistent, or a singular W): the modes
// and the solve are put back as they were, for the caller's fallback.
legsim_status contact_modes_choose(const Model &m, Data &d, bool &found, uint32_t &changes, uint32_t &slipped) {
  found = false;
  changes = 0;
  int idx[kMaxContacts], n = 0;
  ContactData saved[kMaxContacts];
  real saved_stick[kMaxContacts];
  for (int k = 0; k < m.nc; ++k) {
    saved[k] = d.contact[k];
    saved_stick[k] = d.stop_drivers.stick[k];
    if (d.contact[k].state != LEGSIM_CONTACT_FREE) idx[n++] = k;
  }
  if (n == 0) return LEGSIM_OK;
  auto restore = [&]() -> legsim_status {
    for (int k = 0; k < m.nc; ++k) {
      d.contact[k] = saved[k];
      d.stop_drivers.stick[k] = saved_stick[k];
    }
    legsim_status s = stops_layout(m, d);
    return s == LEGSIM_OK ? dynamics_state_update(m, d) : s;  // (its factor is read by no one)
  };
  for (int i = 0; i < n; ++i) {  // every closed contact stuck where it is, for W and b
    ContactData &c = d.contact[idx[i]];
    if (c.state == LEGSIM_CONTACT_STUCK) continue;
    Vec2 p, v;
    contact_point(m, idx[i], d.q, d.qd, p, v);
    c.state = LEGSIM_CONTACT_STUCK;
    d.stop_drivers.stick[idx[i]] = m.ground_t.dot(p - m.ground_point);
  }
  legsim_status s = stops_layout(m, d);
  if (s == LEGSIM_OK) s = dynamics_state_factored(m, d);
  if (s != LEGSIM_OK) return s;
  const Layout &lay = d.dyn;
  int row[2 * kMaxContacts];  // the rows of d.dyn of contact i: normal 2i, tangential 2i+1
  for (int i = 0; i < 2 * n; ++i) row[i] = -1;
  for (int r = m.m; r < lay.m; ++r) {
    const RowSource &src = lay.src[r];
    for (int i = 0; i < n; ++i)
      if (src.index == idx[i]) {
        if (src.kind == RowKind::ContactNormal) row[2 * i] = r;
        if (src.kind == RowKind::ContactTangent) row[2 * i + 1] = r;
      }
  }
  const int nr = 2 * n;
  for (int i = 0; i < nr; ++i)
    if (row[i] < 0) return restore();
  // W^-1 = (S^-1)_cc, then W by Gauss-Jordan
  real G[2 * kMaxContacts][4 * kMaxContacts] = {};
  for (int j = 0; j < nr; ++j) {
    VecR e = VecR::Zero();
    e[row[j]] = 1;
    factor_solve(d.factor, e);
    for (int i = 0; i < nr; ++i) G[i][j] = e[row[i]];
    G[j][nr + j] = 1;
  }
  for (int col = 0; col < nr; ++col) {
    int piv = col;
    for (int i = col + 1; i < nr; ++i)
      if (std::abs(G[i][col]) > std::abs(G[piv][col])) piv = i;
    if (!(std::abs(G[piv][col]) > real(0))) return restore();
    for (int j = 0; j < 2 * nr; ++j) std::swap(G[col][j], G[piv][j]);
    const real dv = G[col][col];
    for (int j = 0; j < 2 * nr; ++j) G[col][j] /= dv;
    for (int i = 0; i < nr; ++i) {
      if (i == col) continue;
      const real r = G[i][col];
      for (int j = 0; j < 2 * nr; ++j) G[i][j] -= r * G[col][j];
    }
  }
  real W[2 * kMaxContacts][2 * kMaxContacts], b[2 * kMaxContacts];
  real fmax = 0, bmax = 0;
  for (int i = 0; i < nr; ++i) {
    b[i] = 0;
    for (int j = 0; j < nr; ++j) {
      W[i][j] = G[i][nr + j];
      b[i] += W[i][j] * d.lambda[row[j]];
    }
    fmax = std::max(fmax, std::abs(d.lambda[row[i]]));
  }
  for (int i = 0; i < nr; ++i) bmax = std::max(bmax, std::abs(b[i]));
  for (int i = 0; i < nr; ++i)
    if (!std::isfinite(b[i])) return restore();
  // round-off allowances: 2.2e-12 relative in double (the slope tests put mu_s 1e-9 from
  // tan(slope)), 1.2e-3 in float
  const real eps = real(1e4) * std::numeric_limits<real>::epsilon();
  const real tol_f = eps * (1 + fmax), tol_a = eps * (1 + bmax);

  uint8_t choice[kMaxContacts][4], nch[kMaxContacts], cur[kMaxContacts];
  int8_t dir[kMaxContacts];
  int total = 1;
  for (int i = 0; i < n; ++i) {
    const ContactData &c0 = saved[idx[i]];
    dir[i] = c0.slip_dir;
    if (c0.state == LEGSIM_CONTACT_SLIDING) {
      choice[i][0] = kSlide, choice[i][1] = kFree, nch[i] = 2, cur[i] = kSlide;
    } else {
      choice[i][0] = kStick, choice[i][1] = kSlipPlus, choice[i][2] = kSlipMinus, choice[i][3] = kFree;
      nch[i] = 4, cur[i] = kStick;
    }
    total *= nch[i];
  }
  auto rank = [](uint8_t md, uint8_t current) {
    return md == current ? 0 : md == kStick ? 1 : md == kFree ? 3 : 2;
  };
  int consistent = 0, best_score = 1 << 30;
  uint8_t best[kMaxContacts] = {};
  for (int code = 0; code < total; ++code) {
    uint8_t mode[kMaxContacts];
    int rest = code, score = 0;
    for (int i = 0; i < n; ++i) {
      mode[i] = choice[i][rest % nch[i]];
      rest /= nch[i];
      score += rank(mode[i], cur[i]);
    }
    if (!mode_consistent(m, n, W, b, mode, dir, tol_f, tol_a)) continue;
    ++consistent;
    if (score < best_score) {
      best_score = score;
      for (int i = 0; i < n; ++i) best[i] = mode[i];
    }
  }
  s = restore();  // the modes as they were, then the chosen ones
  if (s != LEGSIM_OK || consistent == 0) return s;
  found = true;
  if (consistent > 1) raise_event(d, LEGSIM_EVENT_CONTACT_AMBIGUOUS);
  for (int i = 0; i < n; ++i) {
    if (best[i] == cur[i]) continue;
    ContactData &c = d.contact[idx[i]];
    changes |= 1u << idx[i];
    if (consistent > 1) c.events |= LEGSIM_EVENT_CONTACT_AMBIGUOUS;
    if (best[i] == kFree) {
      c.state = LEGSIM_CONTACT_FREE;
      c.normal = c.tangential = 0;
      c.events |= LEGSIM_EVENT_LIFTOFF;
      raise_event(d, LEGSIM_EVENT_LIFTOFF);
    } else {  // slip+ or slip- from tangential rest: it slides that way (with mu_k)
      c.state = LEGSIM_CONTACT_SLIDING;
      c.slip_dir = int8_t(best[i] == kSlipPlus ? 1 : -1);
      slipped |= 1u << idx[i];
      c.events |= LEGSIM_EVENT_STICK_TO_SLIP;
      raise_event(d, LEGSIM_EVENT_STICK_TO_SLIP);
    }
  }
  if (!changes) return LEGSIM_OK;
  s = stops_layout(m, d);
  return s == LEGSIM_OK ? dynamics_state_update(m, d) : s;
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
//   On frictionless ground (mu_s = 0) it slides on, the other way, with no impulse.
// Under contact_law PAPER, while every foot is on the ground, stick to slip is the paper's
// rule instead (paper_release): the foot with the smaller |T| is released, the other stays.
// Under the default law, lift-off and stick to slip are not decided one contact at a time:
// once the impulses of a pass are done, a closed contact whose mode fails its inequalities
// sends every closed contact through the enumeration of section 2, step 5
// (contact_modes_choose: the exact planar contact problem, CONTACT_AMBIGUOUS when several
// modes are consistent); when none is, CONTACT_INCONSISTENT is raised and the one-by-one
// rules above decide.
// Each pass applies every change at once and solves the dynamics of the new modes; a mode
// that keeps changing raises CONTACT_INCONSISTENT and keeps the last one.
legsim_status contact_transitions(const Model &m, Data &d, bool &changed, double at, const ContactEvents *located) {
  changed = false;
  // (LEGSIM_WITH_CONTACT 0: no model has contacts; the code below is not compiled in)
  if (!LEGSIM_WITH_CONTACT || m.nc == 0) return LEGSIM_OK;
  uint32_t slipped = 0, stuck_again = 0;  // each once per check
  uint32_t changing = 0;                  // the contacts the last pass changed
  const real tol = real(m.opt.newton_tol);
  // mu_s = 0 (so mu_k = 0): a closed foot only slides (sticking needs T = 0 exactly); its
  // slip's direction, which no force depends on, turns with its velocity
  const bool frictionless = !(m.mu_s > 0);
  bool enumerated = false;  // the modes enumerated once per check; after that, one by one
  // The located events switch their contacts in the first pass; a contact switched so sits
  // on its new mode's boundary (N = 0, |T| = mu_s N, v_t = 0 to round-off), where the rules
  // below would switch it back: the rest of this check leaves it (the step locates its next
  // event like any other).
  ContactEvents ev = located ? *located : ContactEvents{0, 0, 0, 0};
  const uint32_t settled = ev.liftoff | ev.slip | ev.stick;
  ContactData before[kMaxContacts];
  for (int k = 0; k < m.nc; ++k) before[k] = d.contact[k];
  const uint32_t applied = ev.touchdown | settled;
  uint32_t turned = 0;  // frictionless slips turned (no event: their event time stays)
  const auto stamp = [&]() {  // the time of each contact's events of this check
    for (int k = 0; k < m.nc; ++k) {
      const ContactData &c = d.contact[k], &b = before[k];
      if (((turned >> k) & 1u) && c.events == b.events && c.state == b.state) continue;
      if (c.events != b.events || c.state != b.state || c.slip_dir != b.slip_dir || ((applied >> k) & 1u))
        d.contact[k].event_time = at;
    }
  };
  for (int pass = 0; pass < 3 * kMaxContacts + 2; ++pass) {
    uint32_t touch = 0, to_stick = 0, fails = 0;
    changing = 0;
    bool any = false;
    // contact_law PAPER: while all feet are on the ground the stick-to-slip rule is the
    // paper's (paper_release), lift-off, touchdown and slip to stick are the default's
    const bool paper = m.opt.contact_law == LEGSIM_CONTACT_PAPER && all_closed(m, d);
    const int release = paper ? paper_release(m, d) : -1;
    // the default law: a closed contact whose mode fails (lift-off, stick to slip) is decided
    // with the others by the enumeration (contact_modes_choose) once the impulses are done
    const bool enumerate = !paper && !enumerated;
    for (int k = 0; k < m.nc; ++k) {
      ContactData &c = d.contact[k];
      const uint32_t bit = 1u << k;
      if ((settled & bit) && pass > 0) continue;
      // the foot's point and velocity: no branch of a stuck contact reads them
      Vec2 p = Vec2::Zero(), v = Vec2::Zero();
      if (c.state != LEGSIM_CONTACT_STUCK) contact_point(m, k, d.q, d.qd, p, v);
      const real vt = m.ground_t.dot(v);
      if (c.state != LEGSIM_CONTACT_FREE && (ev.liftoff & bit)) {  // located: N reached 0
        c.state = LEGSIM_CONTACT_FREE;
        c.normal = c.tangential = 0;
        c.events |= LEGSIM_EVENT_LIFTOFF;
        raise_event(d, LEGSIM_EVENT_LIFTOFF);
      } else if (c.state == LEGSIM_CONTACT_STUCK && (ev.slip & bit)) {  // located: |T| reached mu_s N
        c.state = LEGSIM_CONTACT_SLIDING;
        c.slip_dir = int8_t(-sign_of(c.tangential));
        slipped |= bit;
        c.events |= LEGSIM_EVENT_STICK_TO_SLIP;
        raise_event(d, LEGSIM_EVENT_STICK_TO_SLIP);
      } else if (c.state == LEGSIM_CONTACT_SLIDING && (ev.stick & bit)) {  // located: v_t reached 0
        if (frictionless) {  // no friction to stop it: it slides on the other way
          c.slip_dir = int8_t(-c.slip_dir);
          turned |= bit;
          continue;
        }
        c.state = LEGSIM_CONTACT_STUCK;
        d.stop_drivers.stick[k] = m.ground_t.dot(p - m.ground_point);
        to_stick |= bit;
        stuck_again |= bit;
        c.events |= LEGSIM_EVENT_SLIP_TO_STICK;
        raise_event(d, LEGSIM_EVENT_SLIP_TO_STICK);
      } else if (c.state == LEGSIM_CONTACT_FREE) {
        if (!(m.ground_n.dot(p - m.ground_point) < -tol) && !(ev.touchdown & bit)) continue;
        touch |= 1u << k;
        c.state = LEGSIM_CONTACT_STUCK;  // first as stuck: the impulse decides
        d.stop_drivers.stick[k] = m.ground_t.dot(p - m.ground_point);
        c.slip_dir = int8_t(sign_of(vt));
        c.events |= LEGSIM_EVENT_TOUCHDOWN;
        raise_event(d, LEGSIM_EVENT_TOUCHDOWN);
      } else if (c.normal < 0) {
        if (enumerate) {
          fails |= 1u << k;
          continue;
        }
        c.state = LEGSIM_CONTACT_FREE;
        c.normal = c.tangential = 0;
        c.events |= LEGSIM_EVENT_LIFTOFF;
        raise_event(d, LEGSIM_EVENT_LIFTOFF);
      } else if (c.state == LEGSIM_CONTACT_STUCK) {
        const bool leaves = paper ? k == release : std::abs(c.tangential) > m.mu_s * c.normal;
        if (!leaves || ((slipped >> k) & 1u)) continue;
        if (enumerate) {
          fails |= 1u << k;
          continue;
        }
        c.state = LEGSIM_CONTACT_SLIDING;
        c.slip_dir = int8_t(-sign_of(c.tangential));  // it gives way against the force that held it
        slipped |= 1u << k;
        c.events |= LEGSIM_EVENT_STICK_TO_SLIP;
        raise_event(d, LEGSIM_EVENT_STICK_TO_SLIP);
      } else {  // sliding
        if (!(vt * real(c.slip_dir) < 0) || (((stuck_again | slipped) >> k) & 1u)) continue;
        if (frictionless) {
          c.slip_dir = int8_t(sign_of(vt));
          turned |= bit;
          continue;
        }
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
    ev = ContactEvents{0, 0, 0, 0};  // the located events are applied
    if (!any && fails) {  // no impulse this pass: the enumeration decides the closed contacts
      enumerated = true;
      bool found = false;
      uint32_t chosen = 0;
      legsim_status s = contact_modes_choose(m, d, found, chosen, slipped);
      if (s != LEGSIM_OK) return s;
      if (found && !chosen) {  // the current modes hold after all (round-off)
        stamp();
        return LEGSIM_OK;
      }
      if (!found) {  // no consistent mode: reported, then the one-by-one rules of this pass
        for (int k = 0; k < m.nc; ++k)
          if ((fails >> k) & 1u) d.contact[k].events |= LEGSIM_EVENT_CONTACT_INCONSISTENT;
        raise_event(d, LEGSIM_EVENT_CONTACT_INCONSISTENT);
      }
      changed = changed || found;
      changing = chosen;
      continue;
    }
    if (!any) {
      stamp();
      return LEGSIM_OK;
    }
    changed = true;
    legsim_status s = stops_layout(m, d);
    if (s != LEGSIM_OK) return s;
    // every closed contact takes a share of an impact and reports it (a foot stuck before
    // it reports its own, not its old touchdown's)
    uint32_t closed = 0;
    for (int k = 0; k < m.nc; ++k)
      if (d.contact[k].state != LEGSIM_CONTACT_FREE) closed |= 1u << k;
    if (touch) {  // onto the line, then the impact (its LCP: a foot that would pull leaves)
      s = assemble(m, d, d.dyn, d.stop_drivers, d.q, m.minv, AssemblyMode::Project);
      if (s == LEGSIM_OK) s = impact_lcp(m, d, touch | closed, touch);
      if (s != LEGSIM_OK) return s;
    }
    if (to_stick) {  // the tangential velocity removed, by the same LCP
      uint32_t still = 0;
      for (int k = 0; k < m.nc; ++k)
        if (d.contact[k].state != LEGSIM_CONTACT_FREE) still |= 1u << k;
      if (to_stick & still) s = impact_lcp(m, d, still, 0);
      if (s != LEGSIM_OK) return s;
    }
    s = dynamics_state_update(m, d);  // forces of the new modes
    if (s != LEGSIM_OK) return s;
  }
  for (int k = 0; k < m.nc; ++k)  // the contacts still changing carry it
    if ((changing >> k) & 1u) d.contact[k].events |= LEGSIM_EVENT_CONTACT_INCONSISTENT;
  raise_event(d, LEGSIM_EVENT_CONTACT_INCONSISTENT);
  stamp();
  return LEGSIM_OK;
}

// ---- the sliding contacts' friction (Coulomb, mu_k): its columns in the equations of motion ----
// f_i: the generalized force of the friction dir mu_k t at sliding contact i's foot, per
// unit normal multiplier (the force on the foot is mu_k dir lambda_n t = -dir mu_k N t).
void friction_column(const Model &m, const Data &d, int k, const VecQ &q, real (&f)[kBodyDof]) {
  real s, c;
  sincos_any(q[3 * m.contact[k].body + 2], s, c);  // axis_u's and normal_n's pair
  friction_column_at(m, d, k, s, c, f);
}

void friction_add(const Model &m, const Data &d, const Layout &layout, const VecQ &q, const VecR &lambda,
                  real sign, VecQ &y) {
  for (int i = 0; i < layout.nslide; ++i) {
    const int k = layout.slide_contact[i], b = m.contact[k].body;
    real f[kBodyDof];
    friction_column(m, d, k, q, f);
    const real l = sign * lambda[layout.slide_row[i]];
    for (int c = 0; c < kBodyDof; ++c) y[kBodyDof * b + c] += f[c] * l;
  }
}

}  // namespace legsim
