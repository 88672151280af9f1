// The frictional contact problem on the circular cone (friction_cone.hpp): Alart-Curnier's
// semismooth Newton over all contacts, projected Gauss-Seidel as its fallback.
#include "spatial/friction_cone.hpp"

#include <cmath>

#include "system/dense_solve.hpp"

namespace legsim {
namespace {

using real = cone_real;

inline real hypot2(real a, real b) { return std::sqrt(a * a + b * b); }

// The Alart-Curnier function of contact i and its generalized Jacobian by r (rows 3i .. 3i+2
// of the 3n x 3n matrix, leading dimension ld; jac may be null), with u = W r + q and the
// contact's scaling rho (Jean-Moreau's variant: the disk's radius mu P+(r_n - rho u_n), so
// that a contact apart has no tangential force whatever r_n was):
//   phi_n = r_n - P+(r_n - rho u_n),  phi_t = r_t - P_D(mu P+(r_n - rho u_n))(r_t - rho u_t).
void alart_curnier(int n, int i, const real *W, const real *r, const real *u, real mu, real rho, real *phi,
                   real *jac) {
  const int m = 3 * n, a = 3 * i;
  const real xn = r[a] - rho * u[a];
  const real xt[2] = {r[a + 1] - rho * u[a + 1], r[a + 2] - rho * u[a + 2]};
  const bool pressed = xn > 0;
  const real radius = pressed ? mu * xn : real(0);
  const real norm = hypot2(xt[0], xt[1]);
  // apart: the disk is a point, P_D = 0 whatever x_t (and so is its derivative)
  const bool inside = pressed && norm <= radius;
  phi[0] = r[a] - (pressed ? xn : real(0));
  const real s = !pressed ? real(0) : inside ? real(1) : radius / norm;  // P_D(x_t) = s x_t
  phi[1] = r[a + 1] - s * xt[0];
  phi[2] = r[a + 2] - s * xt[1];
  if (!jac) return;
  // dx/dr = E - rho W (E: the contact's rows of the identity); rows of jac: d phi / dr
  for (int c = 0; c < m; ++c) {
    const real e0 = c == a ? real(1) : real(0), e1 = c == a + 1 ? real(1) : real(0), e2 = c == a + 2 ? real(1) : real(0);
    const real dxn = e0 - rho * W[a * m + c];
    const real dxt0 = e1 - rho * W[(a + 1) * m + c], dxt1 = e2 - rho * W[(a + 2) * m + c];
    jac[0 * m + c] = e0 - (pressed ? dxn : real(0));
    real dp0, dp1;
    if (!pressed) {
      dp0 = dp1 = 0;
    } else if (inside) {
      dp0 = dxt0;
      dp1 = dxt1;
    } else {
      // P = radius x_t / |x_t|: d P = t d radius + radius / |x_t| (I - t t^T) d x_t
      const real t0 = xt[0] / norm, t1 = xt[1] / norm;
      const real drad = pressed ? mu * dxn : real(0);
      const real proj = t0 * dxt0 + t1 * dxt1;
      dp0 = t0 * drad + s * (dxt0 - t0 * proj);
      dp1 = t1 * drad + s * (dxt1 - t1 * proj);
    }
    jac[1 * m + c] = e1 - dp0;
    jac[2 * m + c] = e2 - dp1;
  }
}

void velocities(int m, const real *W, const real *q, const real *r, real *u) {
  for (int i = 0; i < m; ++i) {
    real s = q[i];
    for (int j = 0; j < m; ++j) s += W[i * m + j] * r[j];
    u[i] = s;
  }
}

real merit(int n, const real *W, const real *r, const real *u, const real *mu, const real *rho, real *phi) {
  real f = 0;
  for (int i = 0; i < n; ++i) {
    alart_curnier(n, i, W, r, u, mu[i], rho[i], phi + 3 * i, nullptr);
    for (int k = 0; k < 3; ++k) f += phi[3 * i + k] * phi[3 * i + k];
  }
  return real(0.5) * f;
}

// One contact exactly, the others' reactions fixed: the 3 x 3 problem on w r + b (w: W's
// diagonal block, symmetric positive definite; b: q_i plus the others' share) by its cases,
// in the order apart, stuck, sliding. Sliding along e = (cos t, sin t): r = r_n (1, -mu e),
// u_n = 0 gives r_n, and the slip u_t must lie along +e: the roots of e x u_t(t) (scaled, see
// below) bracketed on a grid of kSlipGrid angles, each refined by bisection; of several
// valid ones, the one the natural map likes best. false: no case holds (r untouched).
constexpr int kSlipGrid = 64;
bool local_exact(const real *w, const real *b, real mu, real *r) {
  if (b[0] >= 0) {  // apart
    r[0] = r[1] = r[2] = 0;
    return true;
  }
  {  // stuck: w r = -b
    real A[9], x[3] = {-b[0], -b[1], -b[2]};
    for (int k = 0; k < 9; ++k) A[k] = w[k];
    if (dense_solve(3, A, x, real(0)) && x[0] >= 0 && hypot2(x[1], x[2]) <= mu * x[0]) {
      r[0] = x[0], r[1] = x[1], r[2] = x[2];
      return true;
    }
  }
  // sliding along e(t): with wn = (w d)_n, d = (1, -mu e), r_n = -b_n / wn and the slip
  // u_t = b_t + r_n (w d)_t; g(t) = wn (e x u_t), a trigonometric polynomial of degree 2 (at
  // most four roots, continuous where wn changes sign), is 0 where the slip lies along +-e
  auto g = [&](real t) {
    const real c = std::cos(t), s = std::sin(t);
    const real wn = w[0] - mu * (w[1] * c + w[2] * s);
    const real u1 = wn * b[1] - b[0] * (w[3] - mu * (w[4] * c + w[5] * s));
    const real u2 = wn * b[2] - b[0] * (w[6] - mu * (w[7] * c + w[8] * s));
    return c * u2 - s * u1;
  };
  real best_err = real(INFINITY);
  auto consider = [&](real t) {
    const real c = std::cos(t), s = std::sin(t);
    const real d[3] = {1, -mu * c, -mu * s};
    const real wn = w[0] * d[0] + w[1] * d[1] + w[2] * d[2];
    if (!(wn > 0)) return;
    const real rn = -b[0] / wn;
    const real cand[3] = {rn, rn * d[1], rn * d[2]};
    real u[3];
    for (int e = 0; e < 3; ++e) u[e] = b[e] + w[3 * e] * cand[0] + w[3 * e + 1] * cand[1] + w[3 * e + 2] * cand[2];
    if (!(c * u[1] + s * u[2] >= 0)) return;  // slipping along +e, against the force
    const real mu1[1] = {mu};
    const real err = cone_error(1, cand, u, mu1);
    if (err < best_err) best_err = err, r[0] = cand[0], r[1] = cand[1], r[2] = cand[2];
  };
  // the grid starts off the axes, where the slip of a problem symmetric about them lies
  // (a root on a grid point would be seen by neither interval)
  const real two_pi = real(6.283185307179586), phase = real(0.0123456789);
  real g0 = g(phase);
  for (int k = 1; k <= kSlipGrid; ++k) {
    real lo = phase + two_pi * real(k - 1) / kSlipGrid, hi = phase + two_pi * real(k) / kSlipGrid;
    const real g1 = g(hi);
    if ((g0 < 0 && g1 > 0) || (g0 > 0 && g1 < 0)) {
      real glo = g0;
      for (int it = 0; it < 60; ++it) {
        const real mid = real(0.5) * (lo + hi);
        const real gm = g(mid);
        if (gm == 0) {
          lo = hi = mid;
          break;
        }
        if ((gm < 0) == (glo < 0)) lo = mid, glo = gm;
        else hi = mid;
      }
      consider(real(0.5) * (lo + hi));
    } else if (g1 == 0) {
      consider(hi);
    }
    g0 = g1;
  }
  return best_err < real(INFINITY);
}

}  // namespace

void cone_project(real mu, const real *x, real *p) {
  const real tn = hypot2(x[1], x[2]);
  if (mu * tn <= -x[0]) {  // in the polar cone (first: with mu = 0 and x_t = 0 both tests pass)
    p[0] = p[1] = p[2] = 0;
  } else if (tn <= mu * x[0]) {  // inside
    p[0] = x[0], p[1] = x[1], p[2] = x[2];
  } else {  // onto the surface
    const real a = (x[0] + mu * tn) / (1 + mu * mu);
    p[0] = a;
    p[1] = mu * a * x[1] / tn;
    p[2] = mu * a * x[2] / tn;
  }
}

real cone_error(int n, const real *r, const real *u, const real *mu) {
  real e = 0;
  for (int i = 0; i < n; ++i) {
    const real *ri = r + 3 * i, *ui = u + 3 * i;
    const real uhat[3] = {ui[0] + mu[i] * hypot2(ui[1], ui[2]), ui[1], ui[2]};
    const real x[3] = {ri[0] - uhat[0], ri[1] - uhat[1], ri[2] - uhat[2]};
    real p[3];
    cone_project(mu[i], x, p);
    for (int k = 0; k < 3; ++k) e += (ri[k] - p[k]) * (ri[k] - p[k]);
  }
  return std::sqrt(e);
}

namespace {
// The problem and the best iterate so far (the one a bounded solve returns).
struct Search {
  int n, m;
  const real *W, *q, *mu;
  real rho[kConeMaxContacts];
  real tol;
  real best[kConeMaxRows], best_error;
  int iterations;
  void keep(const real *r, const real *u) {
    const real e = cone_error(n, r, u, mu);
    if (e < best_error) {
      best_error = e;
      for (int k = 0; k < m; ++k) best[k] = r[k];
    }
  }
};

// At most `iterations` Newton steps on the Alart-Curnier function from r (u = W r + q), each
// with a backtracking line search on its merit; stops converged, at a singular generalized
// Jacobian or where no step descends.
void newton(Search &p, real *r, real *u, int iterations) {
  const int n = p.n, m = p.m;
  real phi[kConeMaxRows], jac[kConeMaxRows * kConeMaxRows], dr[kConeMaxRows], trial[kConeMaxRows],
      ut[kConeMaxRows];
  real f = merit(n, p.W, r, u, p.mu, p.rho, phi);
  for (int it = 0; it < iterations && !(p.best_error <= p.tol); ++it) {
    for (int i = 0; i < n; ++i) alart_curnier(n, i, p.W, r, u, p.mu[i], p.rho[i], phi + 3 * i, jac + 3 * i * m);
    for (int k = 0; k < m; ++k) dr[k] = -phi[k];
    if (!dense_solve(m, jac, dr, real(1e-13))) return;  // a singular generalized Jacobian
    real step = 1, ft = f;
    bool descent = false;
    for (int ls = 0; ls < 30; ++ls, step *= real(0.5)) {
      for (int k = 0; k < m; ++k) trial[k] = r[k] + step * dr[k];
      velocities(m, p.W, p.q, trial, ut);
      ft = merit(n, p.W, trial, ut, p.mu, p.rho, phi);
      if (ft <= (1 - real(1e-4) * step) * f) {  // Armijo on 0.5 |phi|^2 (its slope is -2 f)
        descent = true;
        break;
      }
    }
    ++p.iterations;
    if (!descent) return;
    for (int k = 0; k < m; ++k) r[k] = trial[k], u[k] = ut[k];
    f = ft;
    p.keep(r, u);
  }
}

// One projected Gauss-Seidel sweep: each contact solved exactly (local_exact) with the
// others' reactions as they stand.
void sweep(Search &p, real *r, real *u) {
  const int m = p.m;
  for (int i = 0; i < p.n; ++i) {
    const int a = 3 * i;
    real w[9], b[3];
    for (int k = 0; k < 3; ++k) {
      b[k] = u[a + k];
      for (int l = 0; l < 3; ++l) {
        w[3 * k + l] = p.W[(a + k) * m + a + l];
        b[k] -= w[3 * k + l] * r[a + l];  // q_i and the others' share alone
      }
    }
    local_exact(w, b, p.mu[i], r + a);
    velocities(m, p.W, p.q, r, u);
  }
  ++p.iterations;
  p.keep(r, u);
}

// Newton's polish from a sweep's iterate, every kPolishEvery sweeps (few iterations: it
// converges fast near the solution, where sweeps crawl).
constexpr int kPolishEvery = 8;
constexpr int kPolishIterations = 6;
}  // namespace

legsim_status cone_solve(int n, const real *W, const real *q, const real *mu, real *r, real *u, ConeReport &report,
                         const ConeOptions &opt) {
  if (n < 1 || n > kConeMaxContacts || !W || !q || !mu || !r || !u) return LEGSIM_ERR_BAD_INPUT;
  const int m = 3 * n;
  real qnorm = 0;
  for (int i = 0; i < m; ++i) {
    if (!std::isfinite(q[i]) || !std::isfinite(r[i])) return LEGSIM_ERR_BAD_INPUT;
    for (int j = 0; j < m; ++j)
      if (!std::isfinite(W[i * m + j])) return LEGSIM_ERR_BAD_INPUT;
    if (!(W[i * m + i] > 0)) return LEGSIM_ERR_BAD_INPUT;
    qnorm += q[i] * q[i];
  }
  for (int i = 0; i < n; ++i)
    if (!(mu[i] >= 0) || !std::isfinite(mu[i])) return LEGSIM_ERR_BAD_INPUT;
  const real scale = 1 + std::sqrt(qnorm);
  Search p{n, m, W, q, mu, {}, opt.tol * scale, {}, real(INFINITY), 0};
  // each contact's scaling: 1 / (its block's largest diagonal entry), so that r and rho u are
  // alike in size
  for (int i = 0; i < n; ++i) {
    real d = W[3 * i * m + 3 * i];
    for (int k = 1; k < 3; ++k) d = W[(3 * i + k) * m + 3 * i + k] > d ? W[(3 * i + k) * m + 3 * i + k] : d;
    p.rho[i] = 1 / d;
  }
  velocities(m, W, q, r, u);
  p.keep(r, u);
  report.method = ConeMethod::Newton;
  newton(p, r, u, opt.max_newton);
  if (!(p.best_error <= p.tol)) {
    // sweeps from the best iterate, Newton's polish now and then from where they are
    report.method = ConeMethod::Sweeps;
    for (int k = 0; k < m; ++k) r[k] = p.best[k];
    velocities(m, W, q, r, u);
    real rs[kConeMaxRows], us[kConeMaxRows];
    for (int s = 0; s < opt.max_sweeps && !(p.best_error <= p.tol); ++s) {
      sweep(p, r, u);
      if ((s + 1) % kPolishEvery == 0 && !(p.best_error <= p.tol)) {
        for (int k = 0; k < m; ++k) rs[k] = r[k], us[k] = u[k];
        newton(p, rs, us, kPolishIterations);
      }
    }
  }
  for (int k = 0; k < m; ++k) r[k] = p.best[k];
  velocities(m, W, q, r, u);
  report.iterations = p.iterations;
  report.residual = p.best_error / scale;
  report.converged = p.best_error <= p.tol;
  return report.converged ? LEGSIM_OK : LEGSIM_ERR_NOT_CONVERGED;
}

}  // namespace legsim
