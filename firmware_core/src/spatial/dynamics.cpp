#include "spatial/dynamics.hpp"

#include <algorithm>

#include "system/dense_solve.hpp"

namespace legsim::spatial {

namespace {
constexpr int kMaxLegBodies = 1 + kMaxLegBars;

// The rows of leg l in its elimination order: RobotLeg::order (its joints' but the hip's on a
// free box) with its held foot's in their slot, then its hip's (the rows on the box) last, so
// that S_l^-1 reaches the box through the factor's last rows only. Returns their number; nh: the
// hip's.
int leg_rows(const SpatialRobot &robot, const FeetHold &hold, int l, int *idx, int &nh) {
  const RobotLeg &L = robot.leg[l];
  const int nf = foot_rows(hold, l), f0 = foot_row(robot, l);
  int n = 0;
  for (int i = 0; i < L.foot_slot; ++i) idx[n++] = L.order[i];
  for (int k = 0; k < nf; ++k) idx[n++] = f0 + k;
  for (int i = L.foot_slot; i < L.norder; ++i) idx[n++] = L.order[i];
  nh = L.nrows - L.norder;
  for (int k = 0; k < nh; ++k) idx[n++] = L.row0 + k;  // the hip's: its joint's, the leg's first
  return n;
}

// Row r's two bodies (a foot row: the foot's bar and the world).
inline void bodies_of(const SpatialRobot &robot, int r, int &a, int &b) {
  if (r < robot.m) {
    a = robot.row_body[r][0], b = robot.row_body[r][1];
  } else {
    a = robot.leg[(r - robot.m) / 3].foot_body, b = -1;
  }
}
}  // namespace

void system_rows(const SpatialRobot &robot, const FeetHold &hold, const real *q, const real *v, Row *rows) {
  robot_rows(robot, q, v, rows);
  const BodyState world = ground_state();
  const V3 axes[3] = {hold.normal, hold.t1, hold.t2};
  for (int l = 0; l < robot.nlegs; ++l) {
    const int n = foot_rows(hold, l);
    if (n == 0) continue;
    const int fb = robot.leg[l].foot_body;
    const BodyState foot = body_state(q + kBodyConfig * fb, v + kBodyDof * fb);
    for (int k = 0; k < n; ++k)
      rows[foot_row(robot, l) + k] = row_along(foot, robot.leg[l].foot_point, world, hold.anchor[l], axes[k]);
  }
}

legsim_status robot_factor(const SpatialRobot &robot, const FeetHold &hold, const Row *rows, RobotFactor &F) {
  const bool box = robot.free_box;
  F.stuck = hold.stuck, F.sliding = hold.sliding;
  F.rows = rows;
  real *A0 = F.A0;
  for (int i = 0; i < kBodyDof * kBodyDof; ++i) A0[i] = 0;
  if (box)
    for (int i = 0; i < kBodyDof; ++i) A0[7 * i] = 1 / robot.inverse_mass[0][i];
  static_assert(kMaxLegRows <= 64 && kMaxLegBodies <= 127, "a leg's rows and bodies");
  for (int l = 0; l < robot.nlegs; ++l) {
    const RobotLeg &L = robot.leg[l];
    const int b_lo = L.yoke, nbl = 1 + L.nbars;
    int *ix = F.idx[l], *first = F.first[l], *off = F.off[l];
    int8_t(*rb)[2] = F.body[l];
    int nh;
    const int n = F.nrow[l] = leg_rows(robot, hold, l, ix, nh);
    F.nhip[l] = nh;
    real *S = F.L[l];
    // each row's leg bodies and its envelope (from the first row on either body); each body's
    // rows (local index, and the row's coefficients on it scaled by M^-1)
    int on[kMaxLegBodies][kMaxLegRows], non[kMaxLegBodies], fb[kMaxLegBodies];
    for (int b = 0; b < nbl; ++b) non[b] = 0, fb[b] = n;
    real scaled[kMaxLegRows][2][kBodyDof];
    const real *coef[kMaxLegBodies][kMaxLegRows], *scl[kMaxLegBodies][kMaxLegRows];
    int size = 0;
    for (int i = 0; i < n; ++i) {
      int ab[2];
      bodies_of(robot, ix[i], ab[0], ab[1]);
      const Row &ri = rows[ix[i]];
      int f = i;
      for (int s = 0; s < 2; ++s) {
        const int body = ab[s] - b_lo;
        if (ab[s] < 0 || body < 0 || body >= nbl) {
          rb[i][s] = -1;
          continue;
        }
        rb[i][s] = int8_t(body);
        fb[body] = std::min(fb[body], i);
        f = std::min(f, fb[body]);
        const real *cf = s == 0 ? ri.ja : ri.jb, *im = robot.inverse_mass[ab[s]];
        real *sc = scaled[i][s];
        for (int k = 0; k < kBodyDof; ++k) sc[k] = cf[k] * im[k];
        coef[body][non[body]] = cf, scl[body][non[body]] = sc;
        on[body][non[body]++] = i;
      }
      first[i] = f, off[i] = size - f;
      // zeroed row by row: a short loop, not one long memset
      for (int k = size; k <= size + i - f; ++k) S[k] = 0;
      size += i - f + 1;
    }
    // S = J_l M_l^-1 J_l^T: the pairs of rows on a common body (its lower triangle)
    for (int b = 0; b < nbl; ++b)
      for (int p = 0; p < non[b]; ++p) {
        const real *sc = scl[b][p];
        real *Si = S + off[on[b][p]];
        for (int q = 0; q <= p; ++q) {
          // a body's rows in increasing order: j <= i
          const real *cj = coef[b][q];
          real s_ij = 0;
          for (int k = 0; k < kBodyDof; ++k) s_ij += sc[k] * cj[k];
          Si[on[b][q]] += s_ij;
        }
      }
    real scale = 0;
    for (int i = 0; i < n; ++i) scale = std::max(scale, S[off[i] + i]);
    if (!envelope_cholesky(n, first, off, S, real(1e-12) * scale)) return LEGSIM_ERR_SINGULAR;
    if (!box) continue;
    // W = L^-1 B: B is zero above the hip's rows, so W is too; B^T S^-1 B = W^T W
    const int h0 = n - nh;
    real *Wl = F.W[l];
    for (int i = 0; i < nh; ++i) {
      const real *cb = rows[ix[h0 + i]].jb;  // the hip's rows: the box is their second body
      const real *Li = S + off[h0 + i];
      for (int k = 0; k < kBodyDof; ++k) {
        real t = cb[k];
        for (int m = 0; m < i; ++m) t -= Li[h0 + m] * Wl[kBodyDof * m + k];
        Wl[kBodyDof * i + k] = t / Li[h0 + i];
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
    if (!dense_cholesky(kBodyDof, A0, real(1e-12) * scale)) return LEGSIM_ERR_SINGULAR;
  }
  return LEGSIM_OK;
}

void robot_solve(const SpatialRobot &robot, const RobotFactor &F, const real *f, const real *g, real *x, real *mu) {
  const bool box = robot.free_box;
  const Row *rows = F.rows;
  real y[kMaxLegs][kMaxLegRows], b0[kBodyDof] = {};
  if (box)
    for (int i = 0; i < kBodyDof; ++i) b0[i] = f[i];
  // per leg y = L^-1 c, c = J_l M_l^-1 f_l - g_l; the box's right-hand side f_0 - W^T y
  for (int l = 0; l < robot.nlegs; ++l) {
    const RobotLeg &L = robot.leg[l];
    const int b_lo = L.yoke, nbl = 1 + L.nbars, n = F.nrow[l], nh = F.nhip[l];
    const int *ix = F.idx[l], *first = F.first[l], *off = F.off[l];
    const int8_t(*rb)[2] = F.body[l];
    const real *S = F.L[l];
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
      const real *Li = S + off[i];
      for (int k = first[i]; k < i; ++k) ci -= Li[k] * c[k];
      c[i] = ci / Li[i];
    }
    if (!box) continue;
    for (int i = 0; i < nh; ++i)
      for (int r = 0; r < kBodyDof; ++r) b0[r] -= F.W[l][kBodyDof * i + r] * c[n - nh + i];
  }
  real a0[kBodyDof] = {0, 0, 0, 0, 0, 0};
  if (box) {
    cholesky_solve(kBodyDof, F.A0, b0);
    for (int k = 0; k < kBodyDof; ++k) a0[k] = x[k] = b0[k];
  }
  // each leg: lambda = L^-T (y + W a0), then its bodies' a = M^-1 (f - J^T lambda)
  for (int l = 0; l < robot.nlegs; ++l) {
    const RobotLeg &L = robot.leg[l];
    const int b_lo = L.yoke, nbl = 1 + L.nbars, n = F.nrow[l], nh = F.nhip[l];
    const int *ix = F.idx[l], *first = F.first[l], *off = F.off[l];
    const int8_t(*rb)[2] = F.body[l];
    const real *S = F.L[l];
    real *lam = y[l];
    if (box)
      for (int i = 0; i < nh; ++i)
        for (int k = 0; k < kBodyDof; ++k) lam[n - nh + i] += F.W[l][kBodyDof * i + k] * a0[k];
    // L^T by columns of L's rows: row i's envelope is its column's reach upward
    for (int i = n - 1; i >= 0; --i) {
      const real *Li = S + off[i];
      const real t = lam[i] /= Li[i];
      for (int k = first[i]; k < i; ++k) lam[k] -= Li[k] * t;
    }
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

legsim_status robot_accelerations(const SpatialRobot &robot, const FeetHold &hold, const real *q, const real *v,
                                  const real *Q, real *a, real *mu, Row *rows, RobotFactor &F) {
  system_rows(robot, hold, q, v, rows);
  real g[kMaxSystemRows];
  for (int r = 0; r < robot.m; ++r) g[r] = rows[r].gamma;
  for (int l = 0; l < robot.nlegs; ++l)
    for (int k = 0; k < foot_rows(hold, l); ++k) g[foot_row(robot, l) + k] = rows[foot_row(robot, l) + k].gamma;
  const legsim_status s = robot_factor(robot, hold, rows, F);
  if (s == LEGSIM_OK) robot_solve(robot, F, Q, g, a, mu);
  return s;
}

}  // namespace legsim::spatial
