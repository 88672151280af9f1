#include "spatial/dynamics.hpp"

#include <algorithm>
#include <cmath>

#include "spatial/lanes.hpp"
#include "system/dense_solve.hpp"

namespace legsim::spatial {

// The rows in RobotLeg::order with the foot's in their slot, then the hip's (the rows on the
// box) last, so that S_l^-1 reaches the box through the factor's last rows only.
void leg_layout(const SpatialRobot &robot, int l, int nf, LegLayout &out) {
  static_assert(kMaxLegRows <= 64 && kMaxLegBodies <= 127, "a leg's rows and bodies");
  const RobotLeg &L = robot.leg[l];
  const int f0 = foot_row(robot, l), b_lo = L.yoke, nbl = 1 + L.nbars;
  int *idx = out.row, n = 0;
  for (int i = 0; i < L.foot_slot; ++i) idx[n++] = L.order[i];
  for (int k = 0; k < nf; ++k) idx[n++] = f0 + k;
  for (int i = L.foot_slot; i < L.norder; ++i) idx[n++] = L.order[i];
  out.nh = L.nrows - L.norder;
  for (int k = 0; k < out.nh; ++k) idx[n++] = L.row0 + k;  // the hip's: its joint's, the leg's first
  out.n = n;
  // each row's leg bodies and envelope (from the first row on either body); each body's rows
  int fb[kMaxLegBodies], non[kMaxLegBodies] = {}, size = 0;
  for (int b = 0; b < nbl; ++b) fb[b] = n;
  for (int i = 0; i < n; ++i) {
    int ab[2];
    row_bodies(robot, idx[i], ab[0], ab[1]);
    int f = i;
    for (int s = 0; s < 2; ++s) {
      const int body = ab[s] < 0 ? -1 : ab[s] - b_lo;
      out.body[i][s] = int8_t(body >= 0 && body < nbl ? body : -1);
      if (out.body[i][s] < 0) continue;
      fb[body] = std::min(fb[body], i);
      f = std::min(f, fb[body]);
      ++non[body];
    }
    out.first[i] = f, out.off[i] = size - f;
    size += i - f + 1;
  }
  out.size = size;
  // the orientation rows: a revolute's last two, a prismatic's first three
  bool turn[kMaxRobotRows] = {};
  for (int j = 0; j < robot.nj; ++j) {
    const LegJoint &J = robot.joint[j];
    if (J.kind == LegJointKind::Revolute) turn[J.row + 3] = turn[J.row + 4] = true;
    if (J.kind == LegJointKind::Prismatic) turn[J.row] = turn[J.row + 1] = turn[J.row + 2] = true;
  }
  out.on0[0] = 0;
  for (int b = 0; b < nbl; ++b) out.on0[b + 1] = out.on0[b] + non[b], non[b] = out.on0[b];
  for (int i = 0; i < n; ++i)
    for (int s = 0; s < 2; ++s)
      if (out.body[i][s] >= 0)
        out.on[non[out.body[i][s]]++] = int16_t(4 * i + (idx[i] < robot.m && turn[idx[i]] ? 2 : 0) + s);
  // the first leg before this one laid out the same way for this hold
  const int h = nf == 3 ? 2 : nf;
  out.shape = 3 * l + h;
  for (int m = 0; m < l && out.shape == 3 * l + h; ++m) {
    const LegLayout &o = robot.leg[m].layout[h];
    bool same = robot.leg[m].nbars == L.nbars && o.n == n && o.nh == out.nh && o.size == size &&
                std::equal(o.first, o.first + n, out.first) && std::equal(o.off, o.off + n, out.off) &&
                std::equal(o.on0, o.on0 + nbl + 1, out.on0) && std::equal(o.on, o.on + out.on0[nbl], out.on);
    for (int i = 0; i < n && same; ++i) same = o.body[i][0] == out.body[i][0] && o.body[i][1] == out.body[i][1];
    if (same) out.shape = o.shape;
  }
}

void system_rows(const SpatialRobot &robot, const FeetHold &hold, const real *q, const real *v, Row *rows) {
  robot_rows(robot, q, v, rows);
  const BodyState world = ground_state();
  const V3 axes[3] = {hold.normal, hold.t1, hold.t2};
  const int nc = robot_contacts(robot);
  for (int c = 0; c < nc; ++c) {
    const int n = foot_rows(hold, c);
    if (n == 0) continue;
    const int fb = contact_body(robot, c);
    const BodyState foot = body_state(q + kBodyConfig * fb, v + kBodyDof * fb);
    const PointJet pf = point_jet(foot, contact_point(robot, c)), pw = point_jet(world, hold.anchor[c]);
    for (int k = 0; k < n; ++k)
      rows[foot_row(robot, c) + k] = row_along(foot, contact_point(robot, c), pf, world, hold.anchor[c], pw, axes[k]);
  }
  if (!hold.stops) return;
  for (int l = 0; l < robot.nlegs; ++l)
    for (int k = 0; k < kLegStops; ++k)
      if ((leg_stops(hold, l) >> k) & 1u)
        rows[stop_row(robot, l, k)] = stop_gap_row(robot, l, k, (hold.upper >> (kLegStops * l + k)) & 1u, q, v);
}

void system_phi(const SpatialRobot &robot, const FeetHold &hold, const real *q, real *phi) {
  robot_phi(robot, q, phi);
  const BodyState world = ground_state();
  const V3 axes[3] = {hold.normal, hold.t1, hold.t2};
  for (int c = 0; c < robot_contacts(robot); ++c) {
    const int n = foot_rows(hold, c);
    if (n == 0) continue;
    const real *qf = q + kBodyConfig * contact_body(robot, c);
    const V3 pf = V3{qf[0], qf[1], qf[2]} + rotate(rotation({qf[3], qf[4], qf[5], qf[6]}), contact_point(robot, c));
    const V3 d = pf - (world.r + rotate(world.R, hold.anchor[c]));
    for (int k = 0; k < n; ++k) phi[foot_row(robot, c) + k] = dot(axes[k], d);
  }
  if (!hold.stops) return;
  static const real zero_v[kMaxRobotDof] = {};
  for (int l = 0; l < robot.nlegs; ++l)
    for (int k = 0; k < kLegStops; ++k)
      if ((leg_stops(hold, l) >> k) & 1u)
        phi[stop_row(robot, l, k)] = stop_gap_row(robot, l, k, (hold.upper >> (kLegStops * l + k)) & 1u, q, zero_v).phi;
}

Row stop_gap_row(const SpatialRobot &robot, int l, int k, bool upper, const real *q, const real *v) {
  const RobotLeg &L = robot.leg[l];
  Row r;
  if (k < 2) {
    // the actuator's length row less its end: L - L_min, or L_max - L (all negated)
    const RobotActuator &ac = robot.act[L.first_actuator + k];
    r = actuator_row(body_state(q + kBodyConfig * ac.rod, v + kBodyDof * ac.rod),
                     body_state(q + kBodyConfig * ac.cyl, v + kBodyDof * ac.cyl));
    r.phi += ac.offset - ac.stroke[upper ? 1 : 0];
  } else {
    // the yoke's x against the box's direction at the end, turned by pi / 2: sin(psi - psi_min),
    // or -sin(psi - psi_max)
    const int y = L.yoke;
    const BodyState yoke = body_state(q + kBodyConfig * y, v + kBodyDof * y);
    const BodyState box = robot.free_box ? body_state(q, v) : ground_state();
    const real th = L.yaw + robot.rowing_stroke[upper ? 1 : 0];
    r = row_perpendicular(yoke, {1, 0, 0}, box, {-std::sin(th), std::cos(th), 0});
  }
  if (upper) {
    r.phi = -r.phi, r.gamma = -r.gamma;
    for (int i = 0; i < kBodyDof; ++i) r.ja[i] = -r.ja[i], r.jb[i] = -r.jb[i];
  }
  return r;
}

namespace {
void solve_rows(const SpatialRobot &robot, const RobotFactor &F, const real *f, const real *g, real *x, real *mu);



// The columns (the held stops', the box's contacts') and their Delassus matrix D = -J_s X_s
// (positive semi-definite), factored by Cholesky with a zero pivot's row left out (implied by
// the others).
void factor_stops(const SpatialRobot &robot, const FeetHold &hold, const Row *rows, RobotFactor &F) {
  static const real zero_g[kMaxSystemRows] = {};
  int n = 0;
  for (int s = 0; s < kLegStops * robot.nlegs; ++s)
    if ((hold.stops >> s) & 1u) F.stop[n++] = stop_row(robot, s / kLegStops, s % kLegStops);
  const int n_stops = n;
  for (int c = robot.nlegs; c < robot_contacts(robot); ++c)
    for (int k = 0; k < foot_rows(hold, c); ++k) F.stop[n++] = foot_row(robot, c) + k;
  F.nstops = n;
  F.nnull = 0;
  const int nv = kBodyDof * robot.nb;
  for (int j = 0; j < n; ++j) {
    real f[kMaxRobotDof];
    std::fill(f, f + nv, real(0));
    int a, b;
    const Row &r = rows[F.stop[j]];
    row_bodies(robot, F.stop[j], a, b);
    for (int k = 0; k < kBodyDof; ++k) f[kBodyDof * a + k] = -r.ja[k];
    if (b >= 0)
      for (int k = 0; k < kBodyDof; ++k) f[kBodyDof * b + k] -= r.jb[k];
    // the legs' rows' slots, the unused ones too (robot_solve reads no others)
    std::fill(F.stop_mu[j], F.stop_mu[j] + leg_rows_extent(robot), real(0));
    solve_rows(robot, F, f, zero_g, F.stop_x[j], F.stop_mu[j]);
  }
  real *D = F.D;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) D[n * i + j] = -row_dot(robot, rows[F.stop[i]], F.stop[i], F.stop_x[j]);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < i; ++j) D[n * i + j] = D[n * j + i] = real(0.5) * (D[n * i + j] + D[n * j + i]);
  // in place, lower triangle; a pivot below 1e-10 of its diagonal: that stop dropped
  for (int j = 0; j < n; ++j) {
    const real d0 = D[n * j + j];
    real d = d0;
    for (int k = 0; k < j; ++k)
      if (F.live[k]) d -= D[n * j + k] * D[n * j + k];
    F.live[j] = d > by_precision(1e-10, 1e-5) * d0 && d0 > 0;
    if (!F.live[j]) continue;
    d = std::sqrt(d);
    D[n * j + j] = d;
    for (int i = j + 1; i < n; ++i) {
      real t = D[n * i + j];
      for (int k = 0; k < j; ++k)
        if (F.live[k]) t -= D[n * i + k] * D[n * j + k];
      D[n * i + j] = t / d;
    }
  }
  // a box contact's row left out: the null space of D, z_k = e_k - (D_LL^-1 D_Lk on the live
  // rows), for the least-norm multipliers (the stuck points of a rigid body share its load
  // evenly, not as the factor's order would have it)
  for (int k = n_stops; k < n; ++k) {
    if (F.live[k]) continue;
    real *z = F.null[F.nnull++];
    // -D_Lk = J_L X_k from the columns (D's lower triangle is the factor now)
    for (int i = 0; i < n; ++i)
      z[i] = F.live[i] ? row_dot(robot, rows[F.stop[i]], F.stop[i], F.stop_x[k]) : real(0);
    for (int i = 0; i < n; ++i) {  // L y = -D_Lk
      if (!F.live[i]) continue;
      for (int m = 0; m < i; ++m)
        if (F.live[m]) z[i] -= D[n * i + m] * z[m];
      z[i] /= D[n * i + i];
    }
    for (int i = n - 1; i >= 0; --i) {  // L^T z = y
      if (!F.live[i]) continue;
      for (int m = i + 1; m < n; ++m)
        if (F.live[m]) z[i] -= D[n * m + i] * z[m];
      z[i] /= D[n * i + i];
    }
    z[k] = 1;
  }
  // Z^T Z, factored
  const int nz = F.nnull;
  real *G = F.null_gram;
  for (int a = 0; a < nz; ++a)
    for (int b = 0; b < nz; ++b) {
      real t = 0;
      for (int i = 0; i < n; ++i) t += F.null[a][i] * F.null[b][i];
      G[nz * a + b] = t;
    }
  if (nz) dense_cholesky(nz, G, 0);
}
}  // namespace

namespace {
// a real or a pair of them (lanes.hpp): the lane helpers let one template serve both
constexpr int lanes(real) { return 1; }
constexpr int lanes(Pair2) { return 2; }
inline real lane(real x, int) { return x; }
inline real lane(Pair2 x, int j) { return x[j]; }
inline void set_lane(real &x, int, real v) { x = v; }
inline void set_lane(Pair2 &x, int j, real v) { x[j] = v; }

// envelope_cholesky (system/dense_solve.hpp) in lanes: its operations on each lane, in its order.
template <typename T>
bool envelope_cholesky_lanes(int n, const int *first, const int *off, T *A, const real *floor) {
  if constexpr (lanes(T{}) == 1) {
    return envelope_cholesky(n, first, off, A, floor[0]);
  } else {
    return envelope_cholesky_with(n, first, off, A, [floor](T d, T &l) {
      for (int c = 0; c < lanes(T{}); ++c) {
        if (!(lane(d, c) > floor[c])) return false;
        set_lane(l, c, std::sqrt(lane(d, c)));
      }
      return true;
    });
  }
}

// S = J_l M_l^-1 J_l^T of the legs of one shape (one per lane of T: legs[0 .. lanes)) in their
// envelope at S, and its Cholesky factor; false when a leg's rows are dependent.
template <typename T, bool Pad = false>
bool leg_factor(const SpatialRobot &robot, const Row *rows, const int *legs, const RobotFactor &F, T *S) {
  constexpr int N = lanes(T{});
  const LegLayout &Y = *F.flayout[legs[0]];
  const int nbl = 1 + robot.leg[legs[0]].nbars, n = Y.n;
  const int *first = Y.first, *off = Y.off;
  const int *ix[N];
  int b_lo[N], pad[N];
  for (int c = 0; c < N; ++c)
    ix[c] = F.flayout[legs[c]]->row, b_lo[c] = robot.leg[legs[c]].yoke, pad[c] = F.pad[legs[c]];
  auto padded = [&](int c, int i) { return Pad && pad[c] >= 0 && i >= pad[c] && i < pad[c] + 3; };
  static const real zero[kBodyDof] = {};
  // S in its envelope: the pairs of rows on a common body (its lower triangle; a body's rows in
  // increasing order), the rest zero
  for (int i = 0; i < n; ++i) {
    // row by row: short loops, not one long memset
    T *Si = S + off[i];
    for (int k = first[i]; k <= i; ++k) Si[k] = T{};
  }
  for (int b = 0; b < nbl; ++b) {
    const int p0 = Y.on0[b], np = Y.on0[b + 1] - p0;
    const int16_t *on = Y.on + p0;
    T im[kBodyDof];
    for (int k = 0; k < kBodyDof; ++k) {
      if constexpr (N == 1)
        im[k] = robot.inverse_mass[b_lo[0] + b][k];
      else
        im[k] = T{robot.inverse_mass[b_lo[0] + b][k], robot.inverse_mass[b_lo[1] + b][k]};
    }
    // each row's coefficients on the body (a pair of legs: gathered into lanes)
    const T *coef[2 * kMaxLegRows];
    T gathered[N == 1 ? 1 : 2 * kMaxLegRows][kBodyDof];
    for (int p = 0; p < np; ++p) {
      if constexpr (N == 1) {
        const Row &r = rows[ix[0][on[p] >> 2]];
        coef[p] = on[p] & 1 ? r.jb : r.ja;
      } else {
        const int i = on[p] >> 2;
        const Row &r0 = rows[ix[0][i]], &r1 = rows[ix[1][i]];
        const real *c0 = padded(0, i) ? zero : on[p] & 1 ? r0.jb : r0.ja;
        const real *c1 = padded(1, i) ? zero : on[p] & 1 ? r1.jb : r1.ja;
        for (int k = 0; k < kBodyDof; ++k) gathered[p][k] = T{c0[k], c1[k]};
        coef[p] = gathered[p];
      }
    }
    // with an orientation row the products on v are exact zeros: skipped
    for (int p = 0; p < np; ++p) {
      T sc[kBodyDof];
      for (int k = 0; k < kBodyDof; ++k) sc[k] = coef[p][k] * im[k];
      T *Si = S + off[on[p] >> 2];
      if (on[p] & 2) {
        for (int q = 0; q <= p; ++q) {
          const T *cj = coef[q];
          Si[on[q] >> 2] += sc[3] * cj[3] + sc[4] * cj[4] + sc[5] * cj[5];
        }
        continue;
      }
      for (int q = 0; q <= p; ++q) {
        const T *cj = coef[q];
        const T s_w = sc[3] * cj[3] + sc[4] * cj[4] + sc[5] * cj[5];
        if (on[q] & 2) {
          Si[on[q] >> 2] += s_w;
        } else {
          Si[on[q] >> 2] += sc[0] * cj[0] + sc[1] * cj[1] + sc[2] * cj[2] + s_w;
        }
      }
    }
  }
  real floor[N];
  for (int c = 0; c < N; ++c) {
    real scale = 0;
    for (int i = 0; i < n; ++i)
      if (padded(c, i))
        set_lane(S[off[i] + i], c, 1);
      else
        scale = std::max(scale, lane(S[off[i] + i], c));
    floor[c] = by_precision(1e-12, 1e-6) * scale;
  }
  return envelope_cholesky_lanes(n, first, off, S, floor);
}
}  // namespace

legsim_status robot_factor(const SpatialRobot &robot, const FeetHold &hold, const Row *rows, RobotFactor &F) {
  const bool box = robot.free_box;
  F.stuck = hold.stuck, F.sliding = hold.sliding;
  F.nstops = 0;
  F.rows = rows;
  real *A0 = F.A0;
  for (int i = 0; i < kBodyDof * kBodyDof; ++i) A0[i] = 0;
  if (box)
    for (int i = 0; i < kBodyDof; ++i) A0[7 * i] = 1 / robot.inverse_mass[0][i];
  // the legs two at a time where their shapes agree (each in a lane: the same operations, in
  // the same order, as one alone), the pairs first in L (aligned), then the others alone. A free
  // foot's leg left over pairs with a stuck one's left over when its own stuck layout has that
  // one's shape: its rows in that layout, the foot's three (not held) decoupled with unit pivots;
  // its factor's other entries gain exact zeros only (the same values).
  int unit[kMaxLegs / 2][2], npairs = 0, nsingle = 0, single[kMaxLegs];
  bool taken[kMaxLegs] = {};
  for (int l = 0; l < robot.nlegs; ++l) {
    F.layout[l] = F.flayout[l] = &leg_layout(robot, hold, l);
    F.pad[l] = -1;
  }
  auto stuck_shape = [&](int l) {
    return foot_rows(hold, l) == 0 && robot.leg[l].foot_body >= 0 ? robot.leg[l].layout[2].shape : -1;
  };
  for (int pass = 0; pass < 2; ++pass)
    for (int l = 0; l < robot.nlegs; ++l) {
      if (taken[l]) continue;
      for (int m = l + 1; m < robot.nlegs; ++m) {
        if (taken[m]) continue;
        const int sl = F.layout[l]->shape, sm = F.layout[m]->shape;
        if (pass == 0 ? sl == sm : stuck_shape(l) == sm || stuck_shape(m) == sl) {
          taken[l] = taken[m] = true;
          unit[npairs][0] = l, unit[npairs][1] = m, ++npairs;
          if (pass == 1) {
            const int f = stuck_shape(l) == sm ? l : m;
            F.flayout[f] = &robot.leg[f].layout[2];
            F.pad[f] = robot.leg[f].foot_slot;
          }
          break;
        }
      }
    }
  for (int l = 0; l < robot.nlegs; ++l)
    if (!taken[l]) single[nsingle++] = l;
  F.npairs = npairs;
  int base = 0;
  for (int u = 0; u < npairs; ++u) {
    F.pair[u][0] = unit[u][0], F.pair[u][1] = unit[u][1];
    const int l = unit[u][0], m = unit[u][1];
    F.lbase[l] = base, F.lbase[m] = base + 1, F.lstride[l] = F.lstride[m] = 2;
    Pair2 *S = reinterpret_cast<Pair2 *>(F.L + base);
    if (!(F.pad[l] >= 0 || F.pad[m] >= 0 ? leg_factor<Pair2, true>(robot, rows, unit[u], F, S)
                                         : leg_factor<Pair2>(robot, rows, unit[u], F, S)))
      return LEGSIM_ERR_SINGULAR;
    base += 2 * F.flayout[l]->size;
  }
  for (int u = 0; u < nsingle; ++u) {
    const int l = single[u];
    F.lbase[l] = base, F.lstride[l] = 1;
    if (!leg_factor<real>(robot, rows, single + u, F, F.L + base)) return LEGSIM_ERR_SINGULAR;
    base += F.layout[l]->size;
  }
  for (int l = 0; l < robot.nlegs; ++l) {
    const LegLayout &Y = *F.flayout[l];
    const int n = Y.n, nh = Y.nh;
    const int *ix = Y.row, *off = Y.off;
    const real *S = F.L + F.lbase[l];
    const int st = F.lstride[l];
    if (!box) continue;
    // W = L^-1 B: B is zero above the hip's rows, so W is too; B^T S^-1 B = W^T W
    const int h0 = n - nh;
    real *Wl = F.W[l];
    for (int i = 0; i < nh; ++i) {
      const real *cb = rows[ix[h0 + i]].jb;  // the hip's rows: the box is their second body
      const real *Li = S + st * off[h0 + i];
      for (int k = 0; k < kBodyDof; ++k) {
        real t = cb[k];
        for (int m = 0; m < i; ++m) t -= Li[st * (h0 + m)] * Wl[kBodyDof * m + k];
        Wl[kBodyDof * i + k] = t / Li[st * (h0 + i)];
      }
    }
    for (int i = 0; i < nh; ++i) {
      const real *wi = Wl + kBodyDof * i;
      for (int r = 0; r < kBodyDof; ++r)
        for (int s2 = 0; s2 < kBodyDof; ++s2) A0[kBodyDof * r + s2] += wi[r] * wi[s2];
    }
  }
  if (box) {
    real scale = 0;
    for (int i = 0; i < kBodyDof; ++i) scale = std::max(scale, A0[7 * i]);
    if (!dense_cholesky(kBodyDof, A0, by_precision(1e-12, 1e-6) * scale)) return LEGSIM_ERR_SINGULAR;
  }
  if (hold.stops || box_held(robot, hold)) factor_stops(robot, hold, rows, F);
  return LEGSIM_OK;
}

void robot_solve(const SpatialRobot &robot, const RobotFactor &F, const real *f, const real *g, real *x, real *mu) {
  solve_rows(robot, F, f, g, x, mu);
  const int n = F.nstops;
  if (!n) return;
  // the stops' multipliers: D lambda = -(g_s - J_s x), then x and mu moved by their columns
  real lam[kMaxColumns];
  for (int i = 0; i < n; ++i) lam[i] = row_dot(robot, F.rows[F.stop[i]], F.stop[i], x) - g[F.stop[i]];
  const real *D = F.D;
  for (int i = 0; i < n; ++i) {
    if (!F.live[i]) {
      lam[i] = 0;
      continue;
    }
    for (int k = 0; k < i; ++k)
      if (F.live[k]) lam[i] -= D[n * i + k] * lam[k];
    lam[i] /= D[n * i + i];
  }
  for (int i = n - 1; i >= 0; --i) {
    if (!F.live[i]) continue;
    for (int k = i + 1; k < n; ++k)
      if (F.live[k]) lam[i] -= D[n * k + i] * lam[k];
    lam[i] /= D[n * i + i];
  }
  // least norm: lam - Z (Z^T Z)^-1 Z^T lam
  const int nz = F.nnull;
  if (nz) {
    real c[kMaxColumns];
    for (int a = 0; a < nz; ++a) {
      c[a] = 0;
      for (int i = 0; i < n; ++i) c[a] += F.null[a][i] * lam[i];
    }
    cholesky_solve(nz, F.null_gram, c);
    for (int a = 0; a < nz; ++a)
      for (int i = 0; i < n; ++i) lam[i] -= c[a] * F.null[a][i];
  }
  const int nv = kBodyDof * robot.nb, nr = leg_rows_extent(robot);
  for (int j = 0; j < n; ++j) {
    if (!F.live[j] && !(nz && F.stop[j] < robot.m + 3 * kMaxContacts)) {
      mu[F.stop[j]] = 0;
      continue;
    }
    for (int k = 0; k < nv; ++k) x[k] += lam[j] * F.stop_x[j][k];
    // a column moves the legs' rows' multipliers alone (solve_rows writes no others)
    for (int r = 0; r < nr; ++r) mu[r] += lam[j] * F.stop_mu[j][r];
    mu[F.stop[j]] = lam[j];
  }
}

namespace {
// L y = c (forward) or L^T y = c (backward) in place, L in its envelope: one leg's (T real) or
// two legs' in lanes (T Pair2).
template <typename T>
void envelope_forward(int n, const int *first, const int *off, const T *S, T *c) {
  for (int i = 0; i < n; ++i) {
    const T *Li = S + off[i];
    T ci = c[i];
    for (int k = first[i]; k < i; ++k) ci -= Li[k] * c[k];
    c[i] = ci / Li[i];
  }
}
template <typename T>
void envelope_backward(int n, const int *first, const int *off, const T *S, T *c) {
  // by columns of L's rows: row i's envelope is its column's reach upward
  for (int i = n - 1; i >= 0; --i) {
    const T *Li = S + off[i];
    const T t = c[i] /= Li[i];
    for (int k = first[i]; k < i; ++k) c[k] -= Li[k] * t;
  }
}
// The legs' envelope solves: the pairs' in lanes (their y packed and back), the others' alone.
void legs_envelope(const SpatialRobot &robot, const RobotFactor &F, real (*y)[kMaxLegRows], bool forward) {
  bool paired[kMaxLegs] = {};
  for (int u = 0; u < F.npairs; ++u) {
    const int l = F.pair[u][0], m = F.pair[u][1];
    paired[l] = paired[m] = true;
    const LegLayout &Y = *F.flayout[l];
    Pair2 c[kMaxLegRows];
    // a padded leg's rows: its own before the foot's three, zeros on those, its own after
    const bool pads = F.pad[l] >= 0 || F.pad[m] >= 0;
    const int pl = F.pad[l] >= 0 ? F.pad[l] : Y.n, pm = F.pad[m] >= 0 ? F.pad[m] : Y.n;
    auto at = [](int i, int p) { return i < p ? i : i >= p + 3 ? i - 3 : -1; };
    if (!pads)
      for (int i = 0; i < Y.n; ++i) c[i] = Pair2{y[l][i], y[m][i]};
    else
      for (int i = 0; i < Y.n; ++i) {
        const int il = at(i, pl), im = at(i, pm);
        c[i] = Pair2{il >= 0 ? y[l][il] : real(0), im >= 0 ? y[m][im] : real(0)};
      }
    const Pair2 *S = reinterpret_cast<const Pair2 *>(F.L + F.lbase[l]);
    if (forward)
      envelope_forward(Y.n, Y.first, Y.off, S, c);
    else
      envelope_backward(Y.n, Y.first, Y.off, S, c);
    if (!pads)
      for (int i = 0; i < Y.n; ++i) y[l][i] = c[i][0], y[m][i] = c[i][1];
    else
      for (int i = 0; i < Y.n; ++i) {
        const int il = at(i, pl), im = at(i, pm);
        if (il >= 0) y[l][il] = c[i][0];
        if (im >= 0) y[m][im] = c[i][1];
      }
  }
  for (int l = 0; l < robot.nlegs; ++l) {
    if (paired[l]) continue;
    const LegLayout &Y = *F.layout[l];
    if (forward)
      envelope_forward(Y.n, Y.first, Y.off, F.L + F.lbase[l], y[l]);
    else
      envelope_backward(Y.n, Y.first, Y.off, F.L + F.lbase[l], y[l]);
  }
}

void solve_rows(const SpatialRobot &robot, const RobotFactor &F, const real *f, const real *g, real *x, real *mu) {
  const bool box = robot.free_box;
  const Row *rows = F.rows;
  real y[kMaxLegs][kMaxLegRows], b0[kBodyDof] = {};
  if (box)
    for (int i = 0; i < kBodyDof; ++i) b0[i] = f[i];
  // per leg y = L^-1 c, c = J_l M_l^-1 f_l - g_l; the box's right-hand side f_0 - W^T y
  for (int l = 0; l < robot.nlegs; ++l) {
    const RobotLeg &L = robot.leg[l];
    const LegLayout &Y = *F.layout[l];
    const int b_lo = L.yoke, nbl = 1 + L.nbars, n = Y.n;
    const int *ix = Y.row;
    const int8_t(*rb)[2] = Y.body;
    // M_l^-1 f_l
    real mf[kMaxLegBodies][kBodyDof];
    for (int b = 0; b < nbl; ++b)
      for (int k = 0; k < kBodyDof; ++k) mf[b][k] = robot.inverse_mass[b_lo + b][k] * f[kBodyDof * (b_lo + b) + k];
    real *c = y[l];
    for (int i = 0; i < n; ++i) {
      const Row &ri = rows[ix[i]];
      real ci = -g[ix[i]];
      if (rb[i][0] >= 0)
        for (int k = 0; k < kBodyDof; ++k) ci += ri.ja[k] * mf[rb[i][0]][k];
      if (rb[i][1] >= 0)
        for (int k = 0; k < kBodyDof; ++k) ci += ri.jb[k] * mf[rb[i][1]][k];
      c[i] = ci;
    }
  }
  legs_envelope(robot, F, y, true);
  if (box)
    for (int l = 0; l < robot.nlegs; ++l) {
      const int n = F.layout[l]->n, nh = F.layout[l]->nh;
      for (int i = 0; i < nh; ++i)
        for (int r = 0; r < kBodyDof; ++r) b0[r] -= F.W[l][kBodyDof * i + r] * y[l][n - nh + i];
    }
  real a0[kBodyDof] = {0, 0, 0, 0, 0, 0};
  if (box) {
    cholesky_solve(kBodyDof, F.A0, b0);
    for (int k = 0; k < kBodyDof; ++k) a0[k] = x[k] = b0[k];
    // each leg: lambda = L^-T (y + W a0)
    for (int l = 0; l < robot.nlegs; ++l) {
      const int n = F.layout[l]->n, nh = F.layout[l]->nh;
      for (int i = 0; i < nh; ++i)
        for (int k = 0; k < kBodyDof; ++k) y[l][n - nh + i] += F.W[l][kBodyDof * i + k] * a0[k];
    }
  }
  legs_envelope(robot, F, y, false);
  // then its bodies' a = M^-1 (f - J^T lambda)
  for (int l = 0; l < robot.nlegs; ++l) {
    const RobotLeg &L = robot.leg[l];
    const LegLayout &Y = *F.layout[l];
    const int b_lo = L.yoke, nbl = 1 + L.nbars, n = Y.n;
    const int *ix = Y.row;
    const int8_t(*rb)[2] = Y.body;
    const real *lam = y[l];
    // f - J^T lambda in a local array (no aliasing with the rows: kept in registers)
    real xb[kMaxLegBodies][kBodyDof];
    for (int b = 0; b < nbl; ++b)
      for (int k = 0; k < kBodyDof; ++k) xb[b][k] = f[kBodyDof * (b_lo + b) + k];
    for (int i = 0; i < n; ++i) {
      const Row &ri = rows[ix[i]];
      const real li = lam[i];
      mu[ix[i]] = li;
      if (rb[i][0] >= 0) {
        real *xa = xb[rb[i][0]];
        for (int k = 0; k < kBodyDof; ++k) xa[k] -= ri.ja[k] * li;
      }
      if (rb[i][1] >= 0) {
        real *xa = xb[rb[i][1]];
        for (int k = 0; k < kBodyDof; ++k) xa[k] -= ri.jb[k] * li;
      }
    }
    for (int b = 0; b < nbl; ++b)
      for (int k = 0; k < kBodyDof; ++k) x[kBodyDof * (b_lo + b) + k] = xb[b][k] * robot.inverse_mass[b_lo + b][k];
  }
}
}  // namespace

legsim_status robot_accelerations(const SpatialRobot &robot, const FeetHold &hold, const real *q, const real *v,
                                  const real *Q, real *a, real *mu, Row *rows, RobotFactor &F) {
  system_rows(robot, hold, q, v, rows);
  real g[kMaxSystemRows];
  int idx[kMaxSystemRows];
  const int n = system_used_rows(robot, hold, idx);
  for (int i = 0; i < n; ++i) g[idx[i]] = rows[idx[i]].gamma;
  const legsim_status s = robot_factor(robot, hold, rows, F);
  if (s == LEGSIM_OK) robot_solve(robot, F, Q, g, a, mu);
  return s;
}

}  // namespace legsim::spatial
