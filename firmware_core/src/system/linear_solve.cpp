// The one linear-algebra kernel of the core: J W J^T with W diagonal (M^-1 or
// the identity), assembled from the sparse rows, factored in place as L D L^T (L unit
// lower triangular) in its envelope, packed row after row (Factor). Hand-written so that no
// Eigen path can fall back to the heap.
// The factor's diagonal holds 1 / D_i: no square roots, and the only divisions are the m
// reciprocals (a division's or a square root's latency is 4-10 multiplies', and the
// factorization and its solves are chains of them).
#include <cstring>

#include "planar/kernel.hpp"
#include "planar/mass.hpp"

namespace legsim {

void factor_order(const Layout &layout, Factor &f) {
  f.of_state = false;  // about to be written
  f.nredundant = 0;
  f.m = layout.m;
  f.kernel = layout.kernel;
  f.separator = -1;  // factor_build sets it once B is factored
  std::memcpy(f.perm, layout.perm, sizeof f.perm);
  std::memcpy(f.first, layout.first, sizeof f.first);
  std::memcpy(f.row, layout.row, sizeof f.row);
}

namespace {
// Position i's row of the packed storage, indexed by column: row_of(f, i)[j] is entry (i, j).
inline real *row_of(Factor &f, int i) { return f.a.data() + f.row[i]; }
inline const real *row_of(const Factor &f, int i) { return f.a.data() + f.row[i]; }

// L D L^T of the assembled envelope of f.a in place, positions mk .. m-1 (those before:
// the kernel's block, already factored), its pivots' range into pmin, pmax; false at a
// pivot at or below the floor.
bool eliminate(Factor &f, int mk, int surplus, real max_diag, real &pmin, real &pmax) {
  const int m = f.m;
  // 1 / D by position, side by side (Factor::dinv): the block's, then each pivot as found
  real *dinv = f.dinv;
  if (m > mk)
    for (int k = 0; k < mk; ++k) dinv[k] = f.a[f.row[k] + k];
  real *row[kMaxRows];  // the rows eliminated here (the inner loop reads one per entry)
  for (int i = mk; i < m; ++i) row[i] = row_of(f, i);
  for (int i = mk; i < m; ++i) {
    const int fi = f.first[i];
    real *ai = row[i];
    int j0 = fi;
    if (fi < mk) {
      // its columns in the kernel's block: L11 t = a by the kernel's sparse forward solve
      // (the same products in the same order as the loop below, less the zero ones; the
      // row keeps columns from 0, Layout::row)
      for (int j = 0; j < fi; ++j) ai[j] = 0;
      f.kernel->forward(f.a.data(), ai, fi);
      j0 = mk;
    }
    // row i as t_ij = L_ij D_j first (each from the ones before it), then L_ij = t_ij / D_j
    for (int j = j0; j < i; ++j) {
      const real *aj = row[j];
      const int k0 = fi > f.first[j] ? fi : f.first[j];
      real s = ai[j];
      for (int k = k0; k < j; ++k) s -= ai[k] * aj[k];
      ai[j] = s;
    }
    real d = ai[i];
    const real *dk = dinv + fi;
    for (real *ak = ai + fi, *end = ai + i; ak < end; ++ak, ++dk) {  // k = fi .. i-1
      const real t = *ak;
      *ak = t * *dk;
      d -= t * *ak;
    }
    if (!(d > kPivotFloor * max_diag)) {
      if (f.nredundant < surplus && d == d) {
        // a row that depends on the ones before it: dropped (1 / D = 0 zeroes its
        // column of L in the rows after it and its multiplier in every solve)
        for (int r = 0; r < m; ++r)
          if (f.perm[r] == i) f.redundant[f.nredundant++] = RowIndex(r);
        ai[i] = dinv[i] = 0;
        continue;
      }
      return false;
    }
    pmin = d < pmin ? d : pmin;
    pmax = d > pmax ? d : pmax;
    ai[i] = dinv[i] = 1 / d;
  }
  return true;
}

// The envelope's solve: L D L^T y = y in the factor's own (permuted) order, without the
// separator's correction.
void solve_envelope(const Factor &f, real *y);

// Layout::separator's part of a factor: u (the rows' coefficients on the body, by
// position) and wb, read before B is factored.
void separator_coefficients(const Layout &layout, const Rows &rows, const real *w, Factor &f) {
  const int b = layout.separator;
  for (int e = 0; e < kBodyDof; ++e) f.wb[e] = Bodies::mass_inverse_times(w, kBodyDof * b + e, real(1));
  for (int i = 0; i < layout.m; ++i) {
    real *u = f.u[layout.perm[i]];
    for (int e = 0; e < kBodyDof; ++e) u[e] = 0;
    for (int s = 0; s < 2; ++s)
      if (layout.body[i][s] == b)
        for (int e = 0; e < kBodyDof; ++e) u[e] = rows.coef[i][s][e];
  }
}

// With B factored: z = B^-1 u and the factor of S = W_b^-1 + u^T z; false when S has a
// pivot at or below the floor (relative to its largest diagonal).
bool separator_complement(Factor &f) {
  const int m = f.m;
  real y[kMaxRows];
  for (int c = 0; c < kBodyDof; ++c) {
    for (int p = 0; p < m; ++p) y[p] = f.u[p][c];
    solve_envelope(f, y);
    for (int p = 0; p < m; ++p) f.z[p][c] = y[p];
  }
  real smax = 0;
  for (int r = 0; r < kBodyDof; ++r)
    for (int c = 0; c <= r; ++c) {
      real v = r == c ? 1 / f.wb[r] : real(0);
      for (int p = 0; p < m; ++p) v += f.u[p][r] * f.z[p][c];
      f.s[r][c] = v;
      if (r == c) smax = v > smax ? v : smax;
    }
  for (int r = 0; r < kBodyDof; ++r) {  // L D L^T of the 3 x 3, as eliminate's loop
    for (int c = 0; c < r; ++c) {
      real t = f.s[r][c];
      for (int k = 0; k < c; ++k) t -= f.s[r][k] * f.s[c][k];
      f.s[r][c] = t;
    }
    real d = f.s[r][r];
    for (int k = 0; k < r; ++k) {
      const real t = f.s[r][k];
      f.s[r][k] = t * f.s[k][k];
      d -= t * f.s[r][k];
    }
    if (!(d > kPivotFloor * smax) || !std::isfinite(d)) return false;
    f.s[r][r] = 1 / d;
  }
  return true;
}
}  // namespace

namespace {
// J W J^T's entries that can be non-zero (Layout::pair), added into the factor's storage
// from the rows' coefficients weighted (wflat) and not (cflat).
// A pair's entry of J W J^T: the weighted row's coefficients on its body dotted with the other's.
inline real pair_dot(const Pair &p, const real *wflat, const real *cflat) {
  const real *ci = wflat + p.ci, *cj = cflat + p.cj;
  real dot = ci[0] * cj[0];
  for (int e = 1; e < kBodyDof; ++e) dot += ci[e] * cj[e];
  return dot;
}

void pairs_add(const Layout &layout, const real *wflat, const real *cflat, real *aflat) {
  for (int k = 0; k < layout.npairs; ++k) aflat[layout.pair[k].aij] += pair_dot(layout.pair[k], wflat, cflat);
}
}  // namespace

legsim_status factor_build(const Layout &layout, const Rows &rows, const real *w, Factor &f) {
  const int m = layout.m;
  const Kernel *kern = layout.kernel;
  const int mk = kern ? kern->mj : 0;  // positions 0 .. mk-1: the kernel's block
  // dependent rows that may be dropped: only the dynamics' layout with more rows than
  // coordinates has them, and only that many (Layout::surplus)
  const int surplus = layout.stops ? layout.surplus : 0;
  factor_order(layout, f);
  for (int i = mk; i < m; ++i) {
    real *ai = row_of(f, i);
    for (int j = f.first[i]; j <= i; ++j) ai[j] = 0;
  }
  // weight each row's coefficients once, then every non-zero entry is one dot product
  real wc[kMaxRows][2][kBodyDof];
  for (int i = mk; i < m; ++i)
    for (int sl = 0; sl < 2; ++sl) {
      const int b = layout.body[i][sl];
      if (b < 0) continue;
      const real *c = rows.coef[i][sl];
      for (int e = 0; e < kBodyDof; ++e) wc[i][sl][e] = Bodies::mass_inverse_times(w, kBodyDof * b + e, c[e]);
    }
  const real *wflat = &wc[0][0][0], *cflat = &rows.coef[0][0][0];
  real *aflat = f.a.data();
  pairs_add(layout, wflat, cflat, aflat);
  real max_diag = 0;
  for (int i = mk; i < m; ++i) {
    const real aii = f.a[f.row[i] + i];
    max_diag = aii > max_diag ? aii : max_diag;
  }
  if (layout.separator >= 0) {
    // the pivot floor is relative to J W J^T's diagonal, B's plus the separator's share
    separator_coefficients(layout, rows, w, f);
    for (int i = 0; i < m; ++i) {
      real d = f.a[f.row[i] + i];
      for (int e = 0; e < kBodyDof; ++e) d += f.u[i][e] * f.wb[e] * f.u[i][e];
      max_diag = d > max_diag ? d : max_diag;
    }
  }
  real pmin, pmax;
  if (kern) {
    // the block assembled and factored by the kernel, the largest diagonal of all found
    if (!kern->factor(rows, w, f.a.data(), max_diag, pmin, pmax)) {
      f.condition = real(INFINITY);
      return LEGSIM_ERR_SINGULAR;
    }
  } else {
    if (!(max_diag > 0) || !std::isfinite(max_diag)) {
      // no rows (a free body, e.g. a block off the ground): nothing to factor, well conditioned
      f.condition = m == 0 ? real(1) : real(INFINITY);
      return m == 0 ? LEGSIM_OK : LEGSIM_ERR_SINGULAR;
    }
    pmin = max_diag;
    pmax = 0;
  }
  bool ok = eliminate(f, mk, surplus, max_diag, pmin, pmax);
  if (!ok && layout.separator >= 0) {
    // B singular (a group whose rows fix its bodies with the separator held, e.g. a leg
    // stretched straight) says nothing of J W J^T: factor the whole of it, dense (the
    // layout keeps room for the whole lower triangle, Layout::entries)
    for (int i = 0; i < m; ++i) {
      f.first[i] = 0;
      f.row[i] = uint16_t(i * (i + 1) / 2);
      for (int j = 0; j <= i; ++j) f.a[f.row[i] + j] = 0;
    }
    constexpr int kRowCoef = 2 * kBodyDof;  // Pair::ci, cj: kBodyDof * (2 * row + slot)
    for (int k = 0; k < layout.npairs; ++k) {  // pairs_add at the triangle's offsets
      const Pair &p = layout.pair[k];
      const int pi = f.perm[p.ci / kRowCoef], pj = f.perm[p.cj / kRowCoef];
      aflat[f.row[pi] + pj] += pair_dot(p, wflat, cflat);
    }
    for (int i = 0; i < m; ++i)
      for (int j = 0; j <= i; ++j)
        for (int e = 0; e < kBodyDof; ++e) f.a[f.row[i] + j] += f.u[i][e] * f.wb[e] * f.u[j][e];
    pmin = max_diag;
    pmax = 0;
    f.nredundant = 0;
    ok = eliminate(f, mk, surplus, max_diag, pmin, pmax);
  } else if (ok && layout.separator >= 0) {
    f.separator = layout.separator;
    ok = separator_complement(f);
    if (!ok) f.separator = -1;
  }
  if (!ok) {
    f.condition = real(INFINITY);
    return LEGSIM_ERR_SINGULAR;
  }
  // cond(J W^1/2) ~ sqrt of the pivot spread of J W J^T: an estimate, cheap and monotone.
  f.condition = std::sqrt(pmax / pmin);
  return LEGSIM_OK;
}

namespace {
void solve_envelope(const Factor &f, real *y) {
  const int m = f.m, mk = f.kernel ? f.kernel->mj : 0;
  if (mk) f.kernel->forward(f.a.data(), y, 0);
  for (int i = mk; i < m; ++i) {
    const real *ai = row_of(f, i);
    real s = y[i];
    for (int k = f.first[i]; k < i; ++k) s -= ai[k] * y[k];
    y[i] = s;
  }
  if (m > mk) {
    for (int i = 0; i < m; ++i) y[i] *= f.dinv[i];
  } else {
    for (int i = 0; i < m; ++i) y[i] *= f.a[f.row[i] + i];
  }
  for (int i = m - 1; i >= mk; --i) {
    const real *ai = row_of(f, i);
    const real yi = y[i];
    for (int k = f.first[i]; k < i; ++k) y[k] -= ai[k] * yi;
  }
  if (mk) f.kernel->backward(f.a.data(), y);
}

// (J W J^T)^-1 y in place in the factor's own (permuted) order: the envelope's solve, with a
// separator B^-1 y less z S^-1 u^T B^-1 y.
void solve_in_place(const Factor &f, real *y) {
  solve_envelope(f, y);
  if (f.separator < 0) return;
  real t[kBodyDof];
  for (int c = 0; c < kBodyDof; ++c) {
    real v = 0;
    for (int p = 0; p < f.m; ++p) v += f.u[p][c] * y[p];
    t[c] = v;
  }
  for (int r = 0; r < kBodyDof; ++r)
    for (int c = 0; c < r; ++c) t[r] -= f.s[r][c] * t[c];
  for (int r = 0; r < kBodyDof; ++r) t[r] *= f.s[r][r];
  for (int r = kBodyDof - 1; r >= 0; --r)
    for (int c = r + 1; c < kBodyDof; ++c) t[r] -= f.s[c][r] * t[c];
  for (int p = 0; p < f.m; ++p)
    for (int c = 0; c < kBodyDof; ++c) y[p] -= f.z[p][c] * t[c];
}

// y = L D L^T x in the factor's order.
void multiply(const Factor &f, const real *x, real *y) {
  const int m = f.m;
  real t[kMaxRows];
  for (int k = 0; k < m; ++k) t[k] = 0;
  for (int i = 0; i < m; ++i) {  // t = L^T x
    const real *ai = row_of(f, i);
    for (int k = f.first[i]; k < i; ++k) t[k] += ai[k] * x[i];
    t[i] += x[i];
  }
  for (int k = 0; k < m; ++k) {  // t = D t (0: dropped)
    const real akk = f.a[f.row[k] + k];
    t[k] = akk != 0 ? t[k] / akk : real(0);
  }
  for (int i = 0; i < m; ++i) {  // y = L t
    const real *ai = row_of(f, i);
    real s = t[i];
    for (int k = f.first[i]; k < i; ++k) s += ai[k] * t[k];
    y[i] = s;
  }
  if (f.separator < 0) return;
  for (int c = 0; c < kBodyDof; ++c) {  // y += u W_b u^T x
    real v = 0;
    for (int p = 0; p < m; ++p) v += f.u[p][c] * x[p];
    v *= f.wb[c];
    for (int p = 0; p < m; ++p) y[p] += f.u[p][c] * v;
  }
}

real normalize(real *x, int m) {
  real n = 0;
  for (int i = 0; i < m; ++i) n += x[i] * x[i];
  n = std::sqrt(n);
  for (int i = 0; i < m; ++i) x[i] /= n;
  return n;
}
}  // namespace

void factor_solve(const Factor &f, VecR &x) {
  const int m = f.m;
  if (f.kernel && m == f.kernel->mj) {  // the block alone: the kernel's own solve
    f.kernel->solve(f.a.data(), x.data());
    return;
  }
  real y[kMaxRows];
  for (int i = 0; i < m; ++i) y[f.perm[i]] = x[i];
  solve_in_place(f, y);
  for (int i = 0; i < m; ++i) x[i] = y[f.perm[i]];
}

real factor_condition(const Factor &f) {
  // sqrt(lambda_max / lambda_min) of J W J^T by a few power and inverse-power
  // iterations on the factor: the 2-norm condition of J W^1/2, to a few digits.
  const int m = f.m;
  if (m == 0) return 1;
  real x[kMaxRows], y[kMaxRows];
  for (int i = 0; i < m; ++i) x[i] = real(1) + real(i % 3) * real(0.25);
  normalize(x, m);
  real lmax = 0, lmin_inv = 0;
  for (int it = 0; it < 12; ++it) {
    multiply(f, x, y);
    lmax = normalize(y, m);
    for (int i = 0; i < m; ++i) x[i] = y[i];
  }
  for (int i = 0; i < m; ++i) x[i] = real(1) - real(i % 2) * real(0.5);
  normalize(x, m);
  for (int it = 0; it < 12; ++it) {
    solve_in_place(f, x);
    lmin_inv = normalize(x, m);
  }
  return std::sqrt(lmax * lmin_inv);
}

void jt_times(const Model &model, const Layout &layout, const Rows &rows, const VecR &x, VecQ &y) {
  int i0 = 0;
  if (layout.kernel) {
    layout.kernel->jt_times(rows, x.data(), y.data());
    i0 = layout.kernel->mj;
  } else {
    for (int k = 0; k < model.nq; ++k) y[k] = 0;
  }
  for (int i = i0; i < layout.m; ++i)
    for (int s = 0; s < 2; ++s) {
      const int b = layout.body[i][s];
      if (b < 0) continue;
      const real *c = rows.coef[i][s];
      for (int e = 0; e < kBodyDof; ++e) y[kBodyDof * b + e] += c[e] * x[i];
    }
}

void j_times(const Layout &layout, const Rows &rows, const VecQ &x, VecR &y) {
  int i0 = 0;
  if (layout.kernel) {
    layout.kernel->j_times(rows, x.data(), y.data());
    i0 = layout.kernel->mj;
  }
  for (int i = i0; i < layout.m; ++i) {
    real s = 0;
    for (int k = 0; k < 2; ++k) {
      const int b = layout.body[i][k];
      if (b < 0) continue;
      const real *c = rows.coef[i][k];
      const real *xb = x.data() + kBodyDof * b;
      real t = c[0] * xb[0];
      for (int e = 1; e < kBodyDof; ++e) t += c[e] * xb[e];
      s += t;
    }
    y[i] = s;
  }
}

void project(const Model &model, const Layout &layout, const Rows &rows, const Factor &f,
             const real *w, const VecR &target, VecQ &x, VecR &tmp) {
  j_times(layout, rows, x, tmp);
  for (int i = 0; i < layout.m; ++i) tmp[i] -= target[i];
  factor_solve(f, tmp);
  VecQ corr;
  jt_times(model, layout, rows, tmp, corr);
  for (int k = 0; k < model.nq; ++k) x[k] -= Bodies::mass_inverse_times(w, k, corr[k]);
}

bool all_finite(const VecQ &v, int n) {
  // x * 0 is 0 for every finite x and NaN for an infinite or NaN one: one sum tells, with
  // no branch per value. Four partial sums (the order cannot change whether the sum is NaN)
  // let the compiler use vector registers.
  real z0 = 0, z1 = 0, z2 = 0, z3 = 0;
  int k = 0;
  for (; k + 4 <= n; k += 4) {
    z0 += v[k] * real(0);
    z1 += v[k + 1] * real(0);
    z2 += v[k + 2] * real(0);
    z3 += v[k + 3] * real(0);
  }
  for (; k < n; ++k) z0 += v[k] * real(0);
  const real z = (z0 + z1) + (z2 + z3);
  return z == z;
}

void raise_event(Data &d, uint32_t ev) { d.report.events |= ev; }

}  // namespace legsim
