// Small dense linear systems (the system layer's): the Woodbury correction's few columns
// (coupled_solve, dynamics.cpp), the 3D contact problem's generalized Jacobian
// (spatial/friction_cone.cpp), a spatial leg's rows (spatial/dynamics.cpp, in envelope form).
// No Eigen: a header the element modules can take alone; inline, since its callers' sizes are
// small.
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

// A = L L^T for A n x n symmetric positive definite, row-major: L in A's lower triangle (the
// upper part not read, not written). false at a pivot not above floor: A then not positive
// definite to that margin (a singular or dependent set of rows), L part-way.
inline bool dense_cholesky(int n, legsim_real *A, legsim_real floor) {
  for (int j = 0; j < n; ++j) {
    legsim_real d = A[j * n + j];
    for (int k = 0; k < j; ++k) d -= A[j * n + k] * A[j * n + k];
    if (!(d > floor)) return false;
    d = std::sqrt(d);
    A[j * n + j] = d;
    for (int i = j + 1; i < n; ++i) {
      legsim_real s = A[i * n + j];
      for (int k = 0; k < j; ++k) s -= A[i * n + k] * A[j * n + k];
      A[i * n + j] = s / d;
    }
  }
  return true;
}

// dense_cholesky in envelope storage: row i of A holds its columns first[i] .. i at A + off[i]
// (A(i, j) = A[off[i] + j]), L there on return. Row i of L is zero left of first[i] (no fill
// outside the envelope), so the sums skip only zeros: dense_cholesky's result. T: a real, or
// several in the lanes of a vector (each lane the scalar's operations in its order: the spatial
// module's legs two at a time); pivot(d, L_ii) sets L_ii from row i's remaining diagonal d and
// returns false where d is not above its floor.
template <typename T, typename Pivot>
inline bool envelope_cholesky_with(int n, const int *first, const int *off, T *A, Pivot pivot) {
  for (int i = 0; i < n; ++i) {
    T *ri = A + off[i];
    const int fi = first[i];
    // the first column of row i's sum with row j (both envelopes)
    auto from = [&](int j) { return fi > first[j] ? fi : first[j]; };
    T d = ri[i];  // less the squares of the row's entries, as they come
    for (int j = fi; j < i;) {
      const T *r0 = A + off[j];
      const int k0 = from(j);
      // four columns, then two, at a time when their sums start together (then run over
      // [k0, j) together and each over its own tail, each in k's order): each ri[k] loaded
      // once for them all
      if (j + 3 < i && from(j + 1) == k0 && from(j + 2) == k0 && from(j + 3) == k0) {
        const T *r1 = A + off[j + 1], *r2 = A + off[j + 2], *r3 = A + off[j + 3];
        T s0 = ri[j], s1 = ri[j + 1], s2 = ri[j + 2], s3 = ri[j + 3];
        for (int k = k0; k < j; ++k) {
          const T a = ri[k];
          s0 -= a * r0[k], s1 -= a * r1[k], s2 -= a * r2[k], s3 -= a * r3[k];
        }
        const T l0 = ri[j] = s0 / r0[j];
        s1 -= l0 * r1[j], s2 -= l0 * r2[j], s3 -= l0 * r3[j];
        const T l1 = ri[j + 1] = s1 / r1[j + 1];
        s2 -= l1 * r2[j + 1], s3 -= l1 * r3[j + 1];
        const T l2 = ri[j + 2] = s2 / r2[j + 2];
        const T l3 = ri[j + 3] = (s3 - l2 * r3[j + 2]) / r3[j + 3];
        d -= l0 * l0, d -= l1 * l1, d -= l2 * l2, d -= l3 * l3;
        j += 4;
      } else if (j + 1 < i && from(j + 1) == k0) {
        const T *r1 = A + off[j + 1];
        T s0 = ri[j], s1 = ri[j + 1];
        for (int k = k0; k < j; ++k) {
          const T a = ri[k];
          s0 -= a * r0[k], s1 -= a * r1[k];
        }
        const T l0 = ri[j] = s0 / r0[j];
        const T l1 = ri[j + 1] = (s1 - l0 * r1[j]) / r1[j + 1];
        d -= l0 * l0, d -= l1 * l1;
        j += 2;
      } else {
        T s = ri[j];
        for (int k = k0; k < j; ++k) s -= ri[k] * r0[k];
        const T l0 = ri[j] = s / r0[j];
        d -= l0 * l0;
        ++j;
      }
    }
    if (!pivot(d, ri[i])) return false;
  }
  return true;
}

inline bool envelope_cholesky(int n, const int *first, const int *off, legsim_real *A, legsim_real floor) {
  return envelope_cholesky_with(n, first, off, A, [floor](legsim_real d, legsim_real &l) {
    if (!(d > floor)) return false;
    l = std::sqrt(d);
    return true;
  });
}

// L L^T x = b with dense_cholesky's L; b becomes x.
inline void cholesky_solve(int n, const legsim_real *L, legsim_real *b) {
  for (int i = 0; i < n; ++i) {
    legsim_real s = b[i];
    for (int k = 0; k < i; ++k) s -= L[i * n + k] * b[k];
    b[i] = s / L[i * n + i];
  }
  for (int i = n - 1; i >= 0; --i) {
    legsim_real s = b[i];
    for (int k = i + 1; k < n; ++k) s -= L[k * n + i] * b[k];
    b[i] = s / L[i * n + i];
  }
}

}  // namespace legsim
