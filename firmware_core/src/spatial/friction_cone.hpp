// The three-dimensional frictional contact problem on Coulomb's circular cone (the hexapod's
// feet: docs/design/friction-cone.md). Given the Delassus matrix W of n point contacts
// (3n x 3n, symmetric positive semi-definite: J M^-1 J^T on the contacts' normal and two
// tangent directions) and the free velocity q, find the reactions (or impulses) r with
// u = W r + q such that at every contact i, in its frame (normal first):
//   r_i in K_i = {r : |r_t| <= mu_i r_n}, u^_i = u_i + (mu_i |u_t,i|, 0, 0) in K_i*, r_i . u^_i = 0
// (De Saxce's bipotential form of Coulomb's law: apart (r = 0, u_n >= 0), stuck (u = 0, r
// inside the cone) or sliding (u_n = 0, r on the cone's surface opposite the slip)). The cone
// is round: no pyramid, no regularization.
//
// Solved by a semismooth Newton method on the Alart-Curnier function over all contacts at
// once, with a backtracking line search on its merit; where that fails (a singular
// generalized Jacobian, a direction that does not descend, the iterations spent), by
// projected Gauss-Seidel sweeps (one contact at a time, each exactly by its own Newton
// iteration). Bounded: at most max_newton iterations and max_sweeps sweeps. The result is
// always finite; the report says whether it converged, how, and to what residual (the
// natural map's error, independent of the Alart-Curnier function the iterations use).
#pragma once

#include "legsim/legsim.h"

namespace legsim {

using cone_real = legsim_real;

// The most contacts one problem holds (the hexapod's six feet and its box's four points,
// LEGSIM_HEXAPOD_MAX_BOX_CONTACTS: a robot whose legs give way lands on its belly with its feet
// down; an impact's strokes on their stops, spatial/contact: six feet and ten stops): the
// solver's workspace is fixed at this size, on the stack (about 24 KB in double).
constexpr int kConeMaxContacts = 16;
constexpr int kConeMaxRows = 3 * kConeMaxContacts;

struct ConeOptions {
  // the natural map's error / (1 + |q|) that counts as converged: 1e-10 in double, 1e-5 in
  // float (64 of its round-offs)
  cone_real tol = cone_real(sizeof(cone_real) == sizeof(float) ? 1e-5 : 1e-10);
  int max_newton = 30;
  int max_sweeps = 200;
};

// How the problem was solved.
enum class ConeMethod { Newton, Sweeps };

struct ConeReport {
  bool converged;
  ConeMethod method;  // the last one that ran
  int iterations;     // Newton iterations plus sweeps
  cone_real residual; // the natural map's error of the result, / (1 + |q|)
};

// n contacts (1 .. kConeMaxContacts); W: 3n x 3n, row-major with leading dimension 3n; q: 3n;
// mu: n friction coefficients (>= 0). r: in, a start (warm start from the last modes; zeros
// are fine); out, the reactions. u: out, W r + q. LEGSIM_OK when converged;
// LEGSIM_ERR_NOT_CONVERGED with the best iterate found (finite) otherwise;
// LEGSIM_ERR_BAD_INPUT for n out of range, a non-finite or negative input, or a diagonal
// entry of W that is not positive (r and u untouched then).
legsim_status cone_solve(int n, const cone_real *W, const cone_real *q, const cone_real *mu, cone_real *r,
                         cone_real *u, ConeReport &report, const ConeOptions &options = ConeOptions());

// The natural map's error at (r, u): |r - P_K(r - u^)| over all contacts (De Saxce's u^),
// the measure of a solution that does not depend on how it was found.
cone_real cone_error(int n, const cone_real *r, const cone_real *u, const cone_real *mu);

// The projection of (x_n, x_t1, x_t2) onto the cone |x_t| <= mu x_n.
void cone_project(cone_real mu, const cone_real *x, cone_real *p);

}  // namespace legsim
