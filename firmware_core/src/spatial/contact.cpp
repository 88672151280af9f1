#include "spatial/contact.hpp"

#include <algorithm>
#include <cmath>

#include "system/dense_solve.hpp"

namespace legsim::spatial {

namespace {

constexpr real kCapture = real(1e-4);    // m/s: a foot leaving an impact slower stays on the ground

inline real norm(const V3 &x) { return std::sqrt(dot(x, x)); }

// The generalized force of a force f (world) at contact l's point: 6 per body, zero but its body's.
void foot_force_column(const SpatialRobot &robot, int l, const real *q, const V3 &f, real *col) {
  const int nv = kBodyDof * robot.nb, fb = contact_body(robot, l);
  std::fill(col, col + nv, real(0));
  static const real zero_v[kBodyDof] = {0, 0, 0, 0, 0, 0};
  point_coefficients(body_state(q + kBodyConfig * fb, zero_v), contact_point(robot, l), f, 1,
                     col + kBodyDof * fb);
}

// The sign of det A (n x n row-major, kept), by elimination with partial pivoting on a copy.
int determinant_sign(int n, const real *A) {
  real B[kMaxContacts * kMaxContacts];
  std::copy(A, A + n * n, B);
  int sign = 1;
  for (int c = 0; c < n; ++c) {
    int p = c;
    for (int i = c + 1; i < n; ++i)
      if (std::abs(B[i * n + c]) > std::abs(B[p * n + c])) p = i;
    if (B[p * n + c] == 0) return 0;
    if (p != c) {
      for (int j = 0; j < n; ++j) std::swap(B[c * n + j], B[p * n + j]);
      sign = -sign;
    }
    if (B[c * n + c] < 0) sign = -sign;
    for (int i = c + 1; i < n; ++i) {
      const real f = B[i * n + c] / B[c * n + c];
      for (int j = c; j < n; ++j) B[i * n + j] -= f * B[c * n + j];
    }
  }
  return sign;
}

}  // namespace

void ground_frame(const GroundPlane &g, FeetHold &hold) {
  const V3 n = g.normal;
  const V3 e = std::abs(n.x) < real(0.9) ? V3{1, 0, 0} : V3{0, 1, 0};
  V3 t1 = e - dot(e, n) * n;
  t1 = (1 / norm(t1)) * t1;
  hold.normal = n, hold.t1 = t1, hold.t2 = cross(n, t1);
}

void foot_motion(const SpatialRobot &robot, int l, const real *q, const real *v, V3 &p, V3 &pv) {
  const int fb = contact_body(robot, l);
  const PointJet j = point_jet(body_state(q + kBodyConfig * fb, v + kBodyDof * fb), contact_point(robot, l));
  p = j.p, pv = j.pd;
}

V3 slip_direction(const SpatialRobot &robot, const FeetHold &hold, int l, const real *q, const real *v,
                  const V3 &fallback) {
  V3 p, pv;
  foot_motion(robot, l, q, v, p, pv);
  const V3 vt = tangential(hold, pv);
  const real s = norm(vt);
  return s > kSlipHold ? (1 / s) * vt : fallback;
}

legsim_status contact_accelerations(const SpatialRobot &robot, const FeetHold &hold, real mu_kinetic,
                                    const V3 *slip_dir, const real *q, const real *v, const real *Q, real *a, real *mu,
                                    real *normal_force, Row *rows, RobotFactor &F, ContactWork &w, bool factored,
                                    bool fixed_dir, int *pole_sign) {
  if (pole_sign) *pole_sign = 1;
  if (!factored) {
    system_rows(robot, hold, q, v, rows);
    const legsim_status st = robot_factor(robot, hold, rows, F);
    if (st != LEGSIM_OK) return st;
  }
  int idx[kMaxSystemRows];
  const int n = system_used_rows(robot, hold, idx);
  real g[kMaxSystemRows];
  for (int i = 0; i < n; ++i) g[idx[i]] = rows[idx[i]].gamma;
  robot_solve(robot, F, Q, g, a, mu);
  if (!hold.sliding) return LEGSIM_OK;
  // each sliding foot's friction per newton of its normal force, and what it does
  const int nv = kBodyDof * robot.nb;
  int feet[kMaxContacts], s = 0;
  for (int l = 0; l < robot_contacts(robot); ++l)
    if ((hold.sliding >> l) & 1u) feet[s++] = l;
  real(&x)[kMaxContacts][kMaxRobotDof] = w.x;
  real(&m)[kMaxContacts][kMaxSystemRows] = w.m;
  real col[kMaxRobotDof];
  static const real zero_g[kMaxSystemRows] = {};
  for (int j = 0; j < s; ++j) {
    const V3 dir = fixed_dir ? slip_dir[feet[j]] : slip_direction(robot, hold, feet[j], q, v, slip_dir[feet[j]]);
    foot_force_column(robot, feet[j], q, -mu_kinetic * dir, col);
    robot_solve(robot, F, col, zero_g, x[j], m[j]);
  }
  // N_k = -lambda_n,k of the whole: (I + Lambda) N = -lambda0_n, Lambda_kj = lambda_n,k of column j
  real A[kMaxContacts * kMaxContacts], N[kMaxContacts], scale = 1;
  for (int k = 0; k < s; ++k) {
    const int r = foot_row(robot, feet[k]);
    N[k] = -mu[r];
    for (int j = 0; j < s; ++j) {
      A[s * k + j] = (k == j ? 1 : 0) + m[j][r];
      scale = std::max(scale, std::abs(A[s * k + j]));
    }
  }
  if (pole_sign) *pole_sign = determinant_sign(s, A);
  if (!dense_solve(s, A, N, by_precision(1e-9, 1e-5) * scale)) {
    if (pole_sign) *pole_sign = 0;  // on the pole
    return LEGSIM_ERR_CONTACT;
  }
  for (int j = 0; j < s; ++j) {
    for (int k = 0; k < nv; ++k) a[k] += N[j] * x[j][k];
    for (int i = 0; i < n; ++i) mu[idx[i]] += N[j] * m[j][idx[i]];
    normal_force[feet[j]] = N[j];
  }
  return LEGSIM_OK;
}

V3 contact_acceleration(const SpatialRobot &robot, int l, const real *q, const real *v, const real *a) {
  const int fb = contact_body(robot, l);
  const V3 &pt = contact_point(robot, l);
  const BodyState B = body_state(q + kBodyConfig * fb, v + kBodyDof * fb);
  const real *ab = a + kBodyDof * fb;
  return V3{ab[0], ab[1], ab[2]} + rotate(B.R, cross({ab[3], ab[4], ab[5]}, pt)) + point_jet(B, pt).pq;
}

legsim_status contact_modes(const SpatialRobot &robot, const GroundPlane &ground, const real *q, const real *v,
                            const real *Q, uint32_t slipping, FeetHold &hold, V3 *slip_dir, ConeReport &report,
                            Row *rows, RobotFactor &F, ContactWork &w, bool with_stops) {
  // the problem's contacts: the stuck feet (their cones), then the held stops (a cone of mu = 0:
  // the push alone, >= 0; two decoupled placeholder rows, as contact_impact's)
  int feet[kMaxContacts], stops[kMaxHeldStops], nf = 0, ns = 0;
  for (int l = 0; l < robot_contacts(robot); ++l)
    if ((hold.stuck >> l) & 1u) feet[nf++] = l;
  for (int s = 0; s < kLegStops * robot.nlegs && with_stops; ++s)
    if ((hold.stops >> s) & 1u) stops[ns++] = s;
  const int n = nf + ns;
  if (n == 0) return LEGSIM_OK;
  if (n > kConeMaxContacts) return LEGSIM_ERR_CAPACITY;
  FeetHold released = hold;
  released.stuck = 0;
  if (with_stops) released.stops = released.upper = 0;
  system_rows(robot, released, q, v, rows);
  legsim_status st = robot_factor(robot, released, rows, F);
  if (st != LEGSIM_OK) return st;
  const V3 axes[3] = {hold.normal, hold.t1, hold.t2};
  const int nv = kBodyDof * robot.nb, nr = 3 * n;
  // each stop's gap row (its coefficients on its two bodies, its gamma: gap'' = J a - gamma)
  Row gap[kMaxHeldStops];
  int ga[kMaxHeldStops], gb[kMaxHeldStops];
  for (int i = 0; i < ns; ++i) {
    const int s = stops[i], l = s / kLegStops, k = s % kLegStops;
    gap[i] = stop_gap_row(robot, l, k, (hold.upper >> s) & 1u, q, v);
    row_bodies(robot, stop_row(robot, l, k), ga[i], gb[i]);
  }
  real a[kMaxRobotDof], mu[kMaxSystemRows], N[kMaxContacts], Qc[kMaxRobotDof], col[kMaxRobotDof];
  // the problem's rates at accelerations a: the feet's points' along the ground's axes, the
  // stops' gaps' (their placeholders 0)
  auto rates = [&](const real *acc, real *out) {
    for (int i = 0; i < nf; ++i) {
      const V3 pa = contact_acceleration(robot, feet[i], q, v, acc);
      for (int k = 0; k < 3; ++k) out[3 * i + k] = dot(axes[k], pa);
    }
    for (int i = 0; i < ns; ++i) {
      real x = -gap[i].gamma;
      for (int k = 0; k < kBodyDof; ++k) x += gap[i].ja[k] * acc[kBodyDof * ga[i] + k];
      if (gb[i] >= 0)
        for (int k = 0; k < kBodyDof; ++k) x += gap[i].jb[k] * acc[kBodyDof * gb[i] + k];
      out[3 * (nf + i)] = x, out[3 * (nf + i) + 1] = out[3 * (nf + i) + 2] = 0;
    }
  };
  // q: the rates released; W: their change per unit force (a foot's along each axis, a stop's
  // push along its gap's gradient; the solve is affine in the applied forces: the differences
  // are exact)
  real W[kConeMaxRows * kConeMaxRows] = {}, q0[kConeMaxRows], r[kConeMaxRows] = {}, u[kConeMaxRows], rc[kConeMaxRows];
  st = contact_accelerations(robot, released, ground.mu_kinetic, slip_dir, q, v, Q, a, mu, N, rows, F, w, true);
  if (st != LEGSIM_OK) return st;
  rates(a, q0);
  for (int j = 0; j < n; ++j)
    for (int m = 0; m < (j < nf ? 3 : 1); ++m) {
      if (j < nf) {
        foot_force_column(robot, feet[j], q, axes[m], col);
      } else {
        const int i = j - nf;
        std::fill(col, col + nv, real(0));
        for (int k = 0; k < kBodyDof; ++k) col[kBodyDof * ga[i] + k] = gap[i].ja[k];
        if (gb[i] >= 0)
          for (int k = 0; k < kBodyDof; ++k) col[kBodyDof * gb[i] + k] += gap[i].jb[k];
      }
      for (int k = 0; k < nv; ++k) Qc[k] = Q[k] + col[k];
      st = contact_accelerations(robot, released, ground.mu_kinetic, slip_dir, q, v, Qc, a, mu, N, rows, F, w, true);
      if (st != LEGSIM_OK) return st;
      rates(a, rc);
      for (int c = 0; c < nr; ++c) W[nr * c + 3 * j + m] = rc[c] - q0[c];
    }
  // a stop's placeholders: its push's scale on the diagonal (the solver's scaling per contact)
  for (int j = nf; j < n; ++j) W[nr * (3 * j + 1) + 3 * j + 1] = W[nr * (3 * j + 2) + 3 * j + 2] = W[nr * 3 * j + 3 * j];
  if (!hold.sliding)  // symmetric but for round-off (the solver's contract); sliding feet make it not
    for (int i = 0; i < nr; ++i)
      for (int j = 0; j < i; ++j) W[nr * i + j] = W[nr * j + i] = real(0.5) * (W[nr * i + j] + W[nr * j + i]);
  // a contact whose own force moves it into the ground or its stop (the sliding feet's friction
  // coupled in: Painleve's case): no solution of the problem need exist
  for (int c = 0; c < nr; ++c)
    if (!(W[nr * c + c] > 0)) return LEGSIM_ERR_CONTACT;
  real mus[kConeMaxContacts], scale = 0;
  for (int i = 0; i < n; ++i)
    mus[i] = i >= nf ? real(0) : ((slipping >> feet[i]) & 1u) ? ground.mu_kinetic : ground.mu_static;
  for (int c = 0; c < nr; ++c) scale = std::max(scale, std::abs(q0[c]));
  const real tol = by_precision(1e-9, 1e-4) * (1 + scale);
  // which stick (on mu_static), then the others' slip on mu_kinetic: until the coefficients
  // are those the solution's modes ask (a foot changes once at most: nf + 1 passes)
  bool settled = false;
  for (int pass = 0; pass <= nf && !settled; ++pass) {
    st = cone_solve(n, W, q0, mus, r, u, report);
    if (st != LEGSIM_OK) return st;
    bool changed = false;
    for (int i = 0; i < nf; ++i) {
      const bool slips = std::hypot(u[3 * i + 1], u[3 * i + 2]) > tol && !(u[3 * i] > tol);
      const real want = slips || ((slipping >> feet[i]) & 1u) ? ground.mu_kinetic : ground.mu_static;
      if (want != mus[i]) mus[i] = want, changed = true;
    }
    settled = !changed;
  }
  if (!settled) return LEGSIM_ERR_CONTACT;
  for (int i = 0; i < nf; ++i) {
    const int l = feet[i];
    const uint32_t bit = 1u << l;
    const V3 ut = u[3 * i + 1] * axes[1] + u[3 * i + 2] * axes[2];
    const V3 rt = r[3 * i + 1] * axes[1] + r[3 * i + 2] * axes[2];
    if (u[3 * i] > tol) {
      hold.stuck &= ~bit;  // its force gone, its point leaving the ground
    } else if (norm(ut) > tol) {
      hold.stuck &= ~bit, hold.sliding |= bit;
      slip_dir[l] = (1 / norm(ut)) * ut;
    } else if (((slipping >> l) & 1u) && norm(rt) > 0) {
      // at its cone's edge and leaving it (a located stick to slip), held on mu_kinetic = mu_static
      // at the edge: it slips, against the ground's force
      hold.stuck &= ~bit, hold.sliding |= bit;
      slip_dir[l] = (-1 / norm(rt)) * rt;
    }
  }
  // a stop whose push vanishes and whose gap opens is let go
  for (int i = 0; i < ns; ++i)
    if (u[3 * (nf + i)] > tol) hold.stops &= ~(1u << stops[i]), hold.upper &= ~(1u << stops[i]);
  return LEGSIM_OK;
}

legsim_status contact_impact(const SpatialRobot &robot, const GroundPlane &ground, uint32_t touching,
                             uint32_t arriving, uint32_t near, const real *q, real *v, FeetHold &hold, V3 *slip_dir,
                             V3 *impulse, real *stop_impulse, ConeReport &report, Row *rows, RobotFactor &F,
                             ContactWork &w, uint32_t jammed) {
  // the problem's contacts released: the joints' rows and the other held stops in the factor
  const uint32_t problem = arriving | near;
  FeetHold none = hold;
  none.stuck = none.sliding = 0, none.stops = hold.stops & ~problem, none.upper = hold.upper & ~problem;
  system_rows(robot, none, q, v, rows);
  legsim_status st = robot_factor(robot, none, rows, F);
  if (st != LEGSIM_OK) return st;
  const int nv = kBodyDof * robot.nb;
  // the problem's contacts: the feet (their cones, mu_k), then the stops (a cone of mu = 0: the
  // normal's impulse alone, >= 0; its two tangential rows are decoupled placeholders)
  int feet[kMaxContacts], stops[kMaxHeldStops], n = 0, ns = 0;
  for (int l = 0; l < robot_contacts(robot); ++l)
    if ((touching >> l) & 1u) feet[n++] = l;
  for (int s = 0; s < kLegStops * robot.nlegs; ++s)
    if ((problem >> s) & 1u) stops[ns++] = s;
  const int nf = n;
  n += ns;
  if (n == 0) return LEGSIM_OK;
  if (n > kConeMaxContacts) return LEGSIM_ERR_CAPACITY;
  const V3 axes[3] = {hold.normal, hold.t1, hold.t2};
  // each row of the problem: its coefficients on its bodies (a foot's: one; a stop's: two), the
  // velocity change per unit impulse along it (X), its rate before (u0)
  struct ImpactRow {
    int a, b;  // bodies (-1: none)
    real ja[kBodyDof], jb[kBodyDof];
  };
  ImpactRow prow[kConeMaxRows];
  real(&X)[kConeMaxRows][kMaxRobotDof] = w.X;
  real mu_tmp[kMaxSystemRows], col[kMaxRobotDof];
  static const real zero_g[kMaxSystemRows] = {};
  static const real zero_v[kBodyDof] = {0, 0, 0, 0, 0, 0};
  real W[kConeMaxRows * kConeMaxRows], u0[kConeMaxRows], r[kConeMaxRows] = {}, u[kConeMaxRows], mus[kConeMaxContacts];
  const int nr = 3 * n;
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      ImpactRow &p = prow[3 * i + k];
      p.a = p.b = -1;
      std::fill(p.ja, p.ja + kBodyDof, real(0));
      std::fill(p.jb, p.jb + kBodyDof, real(0));
      if (i < nf) {
        p.a = contact_body(robot, feet[i]);
        point_coefficients(body_state(q + kBodyConfig * p.a, zero_v), contact_point(robot, feet[i]), axes[k], 1, p.ja);
      } else if (k == 0) {
        const int s = stops[i - nf], l = s / kLegStops, ks = s % kLegStops;
        const Row g = stop_gap_row(robot, l, ks, (hold.upper >> s) & 1u, q, v);
        row_bodies(robot, stop_row(robot, l, ks), p.a, p.b);
        std::copy(g.ja, g.ja + kBodyDof, p.ja);
        std::copy(g.jb, g.jb + kBodyDof, p.jb);
      }
    }
  auto rate = [&](const ImpactRow &p, const real *x) {
    real s = 0;
    if (p.a >= 0)
      for (int k = 0; k < kBodyDof; ++k) s += p.ja[k] * x[kBodyDof * p.a + k];
    if (p.b >= 0)
      for (int k = 0; k < kBodyDof; ++k) s += p.jb[k] * x[kBodyDof * p.b + k];
    return s;
  };
  for (int c = 0; c < nr; ++c) {
    const ImpactRow &p = prow[c];
    std::fill(col, col + nv, real(0));
    if (p.a >= 0) std::copy(p.ja, p.ja + kBodyDof, col + kBodyDof * p.a);
    if (p.b >= 0)
      for (int k = 0; k < kBodyDof; ++k) col[kBodyDof * p.b + k] += p.jb[k];
    if (p.a >= 0) {
      robot_solve(robot, F, col, zero_g, X[c], mu_tmp);
    } else {
      std::fill(X[c], X[c] + nv, real(0));
    }
    u0[c] = rate(p, v);
    if (c % 3 == 0 && c / 3 < nf && ((jammed >> feet[c / 3]) & 1u)) u0[c] = std::min(u0[c], -kJamRate);
  }
  for (int i = 0; i < n; ++i) mus[i] = i < nf ? ground.mu_kinetic : real(0);
  for (int a = 0; a < nr; ++a)
    for (int c = 0; c < nr; ++c) W[nr * a + c] = rate(prow[a], X[c]);
  // symmetric to round-off: make it so (the solver's contract)
  for (int i = 0; i < nr; ++i)
    for (int j = 0; j < i; ++j) W[nr * i + j] = W[nr * j + i] = real(0.5) * (W[nr * i + j] + W[nr * j + i]);
  // a stop's placeholders: its normal's scale on the diagonal (the solver's scaling per contact)
  for (int i = nf; i < n; ++i) W[nr * (3 * i + 1) + 3 * i + 1] = W[nr * (3 * i + 2) + 3 * i + 2] = W[nr * 3 * i + 3 * i];
  st = cone_solve(n, W, u0, mus, r, u, report);
  if (st != LEGSIM_OK) return st;
  for (int c = 0; c < nr; ++c)
    for (int k = 0; k < nv; ++k) v[k] += r[c] * X[c][k];
  real scale_u = 0;
  for (int c = 0; c < nr; ++c) scale_u = std::max(scale_u, std::abs(u0[c]));
  const real tol_u = by_precision(1e-8, 1e-4) * (1 + scale_u);
  for (int i = 0; i < nf; ++i) {
    const int l = feet[i];
    const uint32_t bit = 1u << l;
    impulse[l] = r[3 * i] * axes[0] + r[3 * i + 1] * axes[1] + r[3 * i + 2] * axes[2];
    V3 p, pv;
    foot_motion(robot, l, q, v, p, pv);
    hold.anchor[l] = p - dot(p - ground.point, hold.normal) * hold.normal;
    const V3 ut = u[3 * i + 1] * axes[1] + u[3 * i + 2] * axes[2];
    hold.stuck &= ~bit, hold.sliding &= ~bit;
    // leaves the ground (its impulse zero by the cone's law): free; slower than kCapture it would
    // be back within microseconds (a cascade of ever smaller impacts): it stays, its normal
    // velocity taken off by the projection (kinetic energy removed, never added), and the
    // modes' check lets it go if it pulls
    if (u[3 * i] > std::max(tol_u, kCapture)) continue;
    if (norm(ut) <= tol_u) {
      hold.stuck |= bit;
    } else {
      hold.sliding |= bit;
      slip_dir[l] = (1 / norm(ut)) * ut;
    }
  }
  // a stop: held while it pushes or leaves slower than kCapture (the modes' check lets it go if it
  // pulls); one of `near` (at its end, not held before) when it pushes, or approached and leaves
  // slower than kCapture (a grazing arrival: no impulse, the acceleration level decides)
  for (int i = nf; i < n; ++i) {
    const int s = stops[i - nf];
    const uint32_t bit = 1u << s;
    stop_impulse[s] = r[3 * i];
    const bool leaves = u[3 * i] > std::max(tol_u, kCapture);
    const bool held = (near >> s) & 1u ? r[3 * i] > 0 || (u0[3 * i] < 0 && !leaves) : !leaves;
    if (!held) hold.stops &= ~bit, hold.upper &= ~bit;
  }
  return LEGSIM_OK;
}

}  // namespace legsim::spatial
