#include "spatial/dynamics.hpp"

#include <algorithm>

#include "system/dense_solve.hpp"

namespace legsim::spatial {

namespace {
constexpr int kMaxLegRows = 5 * (1 + kMaxLegJoints) + 3;

// M^-1 of body b on its 6 velocity coordinates.
inline void inverse_mass(const SpatialRobot &robot, int b, real *out) {
  const real im = 1 / robot.mass[b];
  out[0] = out[1] = out[2] = im;
  out[3] = 1 / robot.inertia[b].x, out[4] = 1 / robot.inertia[b].y, out[5] = 1 / robot.inertia[b].z;
}

// A row's coefficients on body b (nullptr when it does not act on b).
inline const real *coefficients(const Row &row, int a, int b_row, int body) {
  return body == a ? row.ja : body == b_row ? row.jb : nullptr;
}

// The rows of leg l: its joints', then its foot's when stuck.
int leg_rows(const SpatialRobot &robot, uint32_t stuck, int l, int *idx) {
  const RobotLeg &L = robot.leg[l];
  int n = 0;
  for (int r = L.row0; r < L.row0 + L.nrows; ++r) idx[n++] = r;
  if ((stuck >> l) & 1u)
    for (int k = 0; k < 3; ++k) idx[n++] = foot_row(robot, l) + k;
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
  for (int l = 0; l < robot.nlegs; ++l) {
    if (!((hold.stuck >> l) & 1u)) continue;
    const int fb = robot.leg[l].foot_body;
    const BodyState foot = body_state(q + kBodyConfig * fb, v + kBodyDof * fb);
    spherical_rows(foot, robot.leg[l].foot_point, world, hold.anchor[l], rows + foot_row(robot, l));
  }
}

legsim_status robot_kkt(const SpatialRobot &robot, uint32_t stuck, const Row *rows, const real *f, const real *g,
                        real *x, real *mu) {
  const bool box = robot.free_box;
  real A0[36] = {}, b0[6] = {};
  if (box) {
    real im[kBodyDof];
    inverse_mass(robot, 0, im);
    for (int i = 0; i < kBodyDof; ++i) A0[7 * i] = 1 / im[i], b0[i] = f[i];
  }
  // each leg's lambda0 (in mu) and G (6 columns) for the box's solve and the legs' back-substitution
  static_assert(kMaxLegRows <= 64, "a leg's rows on the stack");
  real G[kMaxLegs][kMaxLegRows * kBodyDof];
  int idx[kMaxLegs][kMaxLegRows], nrow[kMaxLegs];
  for (int l = 0; l < robot.nlegs; ++l) {
    const RobotLeg &L = robot.leg[l];
    const int b_lo = L.yoke, b_hi = L.yoke + 1 + L.nbars;
    int *ix = idx[l];
    const int n = nrow[l] = leg_rows(robot, stuck, l, ix);
    real S[kMaxLegRows * kMaxLegRows], c[kMaxLegRows];
    real *Gl = G[l];  // row-major n x 6: B_l, then S_l^-1 B_l
    real scale = 0;
    for (int i = 0; i < n; ++i) {
      int ai, bi;
      bodies_of(robot, ix[i], ai, bi);
      const Row &ri = rows[ix[i]];
      // (J M^-1 f)_i - g_i on the leg's bodies; B_l's row on the box
      real ci = -g[ix[i]];
      for (int s = 0; s < 2; ++s) {
        const int body = s == 0 ? ai : bi;
        if (body < b_lo || body >= b_hi) continue;
        const real *cf = s == 0 ? ri.ja : ri.jb;
        real im[kBodyDof];
        inverse_mass(robot, body, im);
        for (int k = 0; k < kBodyDof; ++k) ci += cf[k] * im[k] * f[kBodyDof * body + k];
      }
      c[i] = ci;
      const real *cb = box ? coefficients(ri, ai, bi, 0) : nullptr;
      for (int k = 0; k < kBodyDof; ++k) Gl[kBodyDof * i + k] = cb ? cb[k] : 0;
      for (int j = 0; j <= i; ++j) {
        int aj, bj;
        bodies_of(robot, ix[j], aj, bj);
        const Row &rj = rows[ix[j]];
        real s_ij = 0;
        for (int s = 0; s < 2; ++s) {
          const int body = s == 0 ? ai : bi;
          if (body < b_lo || body >= b_hi) continue;
          const real *cj = coefficients(rj, aj, bj, body);
          if (!cj) continue;
          const real *cf = s == 0 ? ri.ja : ri.jb;
          real im[kBodyDof];
          inverse_mass(robot, body, im);
          for (int k = 0; k < kBodyDof; ++k) s_ij += cf[k] * im[k] * cj[k];
        }
        S[n * i + j] = s_ij;
      }
      scale = std::max(scale, S[n * i + i]);
    }
    if (!dense_cholesky(n, S, real(1e-12) * scale)) return LEGSIM_ERR_SINGULAR;
    cholesky_solve(n, S, c);
    for (int i = 0; i < n; ++i) mu[ix[i]] = c[i];
    if (!box) continue;
    real col[kMaxLegRows], B[kMaxLegRows * kBodyDof];
    std::copy(Gl, Gl + n * kBodyDof, B);
    for (int k = 0; k < kBodyDof; ++k) {
      for (int i = 0; i < n; ++i) col[i] = B[kBodyDof * i + k];
      cholesky_solve(n, S, col);
      for (int i = 0; i < n; ++i) Gl[kBodyDof * i + k] = col[i];
    }
    // the box's complement: M_0 + B^T G, and its right-hand side f_0 - B^T lambda0
    for (int i = 0; i < n; ++i) {
      const real *bi = B + kBodyDof * i, *gi = Gl + kBodyDof * i;
      for (int r = 0; r < kBodyDof; ++r) {
        if (bi[r] == 0) continue;
        for (int s = 0; s < kBodyDof; ++s) A0[kBodyDof * r + s] += bi[r] * gi[s];
        b0[r] -= bi[r] * c[i];
      }
    }
  }
  real a0[kBodyDof] = {0, 0, 0, 0, 0, 0};
  if (box) {
    real scale = 0;
    for (int i = 0; i < kBodyDof; ++i) scale = std::max(scale, A0[7 * i]);
    if (!dense_cholesky(kBodyDof, A0, real(1e-12) * scale)) return LEGSIM_ERR_SINGULAR;
    cholesky_solve(kBodyDof, A0, b0);
    for (int k = 0; k < kBodyDof; ++k) a0[k] = x[k] = b0[k];
  }
  // each leg: lambda = lambda0 + G a0, then its bodies' a = M^-1 (f - J^T lambda)
  for (int l = 0; l < robot.nlegs; ++l) {
    const RobotLeg &L = robot.leg[l];
    const int b_lo = L.yoke, b_hi = L.yoke + 1 + L.nbars;
    for (int b = b_lo; b < b_hi; ++b)
      for (int k = 0; k < kBodyDof; ++k) x[kBodyDof * b + k] = f[kBodyDof * b + k];
    for (int i = 0; i < nrow[l]; ++i) {
      const int r = idx[l][i];
      real lam = mu[r];
      if (box)
        for (int k = 0; k < kBodyDof; ++k) lam += G[l][kBodyDof * i + k] * a0[k];
      mu[r] = lam;
      int a, b;
      bodies_of(robot, r, a, b);
      for (int s = 0; s < 2; ++s) {
        const int body = s == 0 ? a : b;
        if (body < b_lo || body >= b_hi) continue;
        const real *cf = s == 0 ? rows[r].ja : rows[r].jb;
        for (int k = 0; k < kBodyDof; ++k) x[kBodyDof * body + k] -= cf[k] * lam;
      }
    }
    for (int b = b_lo; b < b_hi; ++b) {
      real im[kBodyDof];
      inverse_mass(robot, b, im);
      for (int k = 0; k < kBodyDof; ++k) x[kBodyDof * b + k] *= im[k];
    }
  }
  return LEGSIM_OK;
}

legsim_status robot_accelerations(const SpatialRobot &robot, const FeetHold &hold, const real *q, const real *v,
                                  const real *Q, real *a, real *mu) {
  Row rows[kMaxSystemRows];
  system_rows(robot, hold, q, v, rows);
  real g[kMaxSystemRows];
  for (int r = 0; r < robot.m; ++r) g[r] = rows[r].gamma;
  for (int l = 0; l < robot.nlegs; ++l)
    if ((hold.stuck >> l) & 1u)
      for (int k = 0; k < 3; ++k) g[foot_row(robot, l) + k] = rows[foot_row(robot, l) + k].gamma;
  return robot_kkt(robot, hold.stuck, rows, Q, g, a, mu);
}

}  // namespace legsim::spatial
