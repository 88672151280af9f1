// A small dense linear system (the system layer's one): the Woodbury correction's few
// columns (coupled_solve, dynamics.cpp) and the 3D contact problem's generalized Jacobian
// (spatial/friction_cone.cpp). No Eigen: a header the element modules can take alone;
// inline, since its callers' sizes are small.
#pragma once

#include <cmath>
#include <utility>

#include "legsim/legsim.h"

namespace legsim {

// A x = b, A n x n row-major (destroyed), b becomes x, by Gaussian elimination with partial
// pivoting. false at a pivot whose magnitude is not above floor (A and b then part-way).
inline bool dense_solve(int n, legsim_real *A, legsim_real *b, legsim_real floor) {
  for (int c = 0; c < n; ++c) {
    int p = c;
    for (int i = c + 1; i < n; ++i)
      if (std::abs(A[i * n + c]) > std::abs(A[p * n + c])) p = i;
    if (!(std::abs(A[p * n + c]) > floor)) return false;
    if (p != c) {
      for (int j = 0; j < n; ++j) std::swap(A[c * n + j], A[p * n + j]);
      std::swap(b[c], b[p]);
    }
    for (int i = c + 1; i < n; ++i) {
      const legsim_real f = A[i * n + c] / A[c * n + c];
      for (int j = c; j < n; ++j) A[i * n + j] -= f * A[c * n + j];
      b[i] -= f * b[c];
    }
  }
  for (int i = n - 1; i >= 0; --i) {
    legsim_real s = b[i];
    for (int j = i + 1; j < n; ++j) s -= A[i * n + j] * b[j];
    b[i] = s / A[i * n + i];
  }
  return true;
}

}  // namespace legsim
