// The spatial row units (docs/design/spatial.md, formulation (a) with the "tree" rows): every
// row is a dot product x . y of two vectors of the bodies (a point r + R s, an axis R c, a
// difference of two points, or a constant), with its Jacobian coefficients on each body's
// (v, omega) and its acceleration right-hand side gamma (Phi_q qdd = gamma with qdd = (v',
// omega')): for a body vector x its velocity x' and the velocity part of its acceleration
// x_q = R (omega x (omega x s)) give gamma = -(x_q . y + 2 x' . y' + x . y_q). A joint kind is a
// few such rows; one implementation of each, as the planar row units (planar/rows.hpp).
//
// The three forms:
//   along:         e . (p_a - p_b), e a constant world direction (a point coincidence's rows);
//   perpendicular: (R_a c_a) . (R_b c_b) (the orientation rows of revolute and prismatic joints);
//   along_axis:    (p_a - p_b) . (R_b c) (a prismatic's rod on its cylinder's axis, a loop-closing
//                  joint's in-plane rows).
// Body b may be the ground (ground_state(): its coefficients are then not used).
//
// Each unit is a template over the body's and the vector's types: BodyState and V3 (body.hpp),
// or their lanes (spatial/robot.cpp: two legs at once, a pair of reals in each number, every
// lane the scalar's operations in its order), found by their own rotate, dot and cross.
#pragma once

#include "spatial/body.hpp"

namespace legsim::spatial {

// The scalar of a vector type (real, or a pair of them in lanes).
template <class Vec>
using ScalarOf = decltype(dot(Vec{}, Vec{}));

// One row: Phi, gamma and the coefficients on the two bodies' velocity coordinates
// (v_x, v_y, v_z, omega_x, omega_y, omega_z; omega in the body's frame).
template <class S>
struct RowOf {
  S phi, gamma;
  S ja[kBodyDof], jb[kBodyDof];
};
using Row = RowOf<real>;

// A point p = r + R s of a body (s body-fixed, m): p, p', and p_q = R (w x (w x s)).
template <class Vec>
struct JetOf {
  Vec p, pd, pq;
};
using PointJet = JetOf<V3>;
template <class Body, class Vec>
inline JetOf<Vec> point_jet(const Body &B, const Vec &s) {
  const Vec ws = cross(B.w, s);
  return {B.r + rotate(B.R, s), B.v + rotate(B.R, ws), rotate(B.R, cross(B.w, ws))};
}
// An axis a = R c of a body (c body-fixed): a, a', a_q.
template <class Body, class Vec>
inline JetOf<Vec> axis_jet(const Body &B, const Vec &c) {
  const Vec wc = cross(B.w, c);
  return {rotate(B.R, c), rotate(B.R, wc), rotate(B.R, cross(B.w, wc))};
}

// The coefficients of y . d(point s of body B) on (v, omega) (sign: +1 or -1): y on v,
// s x (R^T y) on omega (y . R (dtheta x s) = dtheta . (s x R^T y)).
template <class Body, class Vec, class S>
inline void point_coefficients(const Body &B, const Vec &s, const Vec &y, real sign, S *j) {
  const Vec o = cross(s, rotate_back(B.R, y));
  j[0] += sign * y.x, j[1] += sign * y.y, j[2] += sign * y.z;
  j[3] += sign * o.x, j[4] += sign * o.y, j[5] += sign * o.z;
}
// The coefficients of y . d(axis c of body B): c x (R^T y) on omega.
template <class Body, class Vec, class S>
inline void axis_coefficients(const Body &B, const Vec &c, const Vec &y, S *j) {
  const Vec o = cross(c, rotate_back(B.R, y));
  j[3] += o.x, j[4] += o.y, j[5] += o.z;
}
inline Row row_zero() { return Row{}; }

// e . (p_a - p_b): point s_a of body a and s_b of body b along the world direction e (pa, pb
// their jets: a joint's rows on the same two points share them).
inline Row row_along(const BodyState &A, const V3 &sa, const PointJet &pa, const BodyState &B, const V3 &sb,
                     const PointJet &pb, const V3 &e) {
  Row r = row_zero();
  r.phi = dot(e, pa.p - pb.p);
  r.gamma = -dot(e, pa.pq - pb.pq);
  point_coefficients(A, sa, e, 1, r.ja);
  point_coefficients(B, sb, e, -1, r.jb);
  return r;
}
inline Row row_along(const BodyState &A, const V3 &sa, const BodyState &B, const V3 &sb, const V3 &e) {
  return row_along(A, sa, point_jet(A, sa), B, sb, point_jet(B, sb), e);
}

// (R_a c_a) . (R_b c_b): axis c_a of body a and c_b of body b (a, b their jets: a joint's rows
// on the same axis share it).
template <class Body, class Vec>
inline RowOf<ScalarOf<Vec>> row_perpendicular(const Body &A, const Vec &ca, const JetOf<Vec> &a, const Body &B,
                                              const Vec &cb, const JetOf<Vec> &b) {
  RowOf<ScalarOf<Vec>> r{};
  r.phi = dot(a.p, b.p);
  r.gamma = -(dot(a.pq, b.p) + real(2) * dot(a.pd, b.pd) + dot(a.p, b.pq));
  axis_coefficients(A, ca, b.p, r.ja);
  axis_coefficients(B, cb, a.p, r.jb);
  return r;
}
inline Row row_perpendicular(const BodyState &A, const V3 &ca, const BodyState &B, const V3 &cb) {
  return row_perpendicular(A, ca, axis_jet(A, ca), B, cb, axis_jet(B, cb));
}

// (p_a - p_b) . (R_b c): point s_a of body a less point s_b of body b along body b's axis c (pa,
// pb, y their jets, as row_along's).
template <class Body, class Vec>
inline RowOf<ScalarOf<Vec>> row_along_axis(const Body &A, const Vec &sa, const JetOf<Vec> &pa, const Body &B,
                                           const Vec &sb, const JetOf<Vec> &pb, const Vec &c, const JetOf<Vec> &y) {
  const Vec d = pa.p - pb.p, dd = pa.pd - pb.pd, dq = pa.pq - pb.pq;
  RowOf<ScalarOf<Vec>> r{};
  r.phi = dot(d, y.p);
  r.gamma = -(dot(dq, y.p) + real(2) * dot(dd, y.pd) + dot(d, y.pq));
  point_coefficients(A, sa, y.p, 1, r.ja);
  point_coefficients(B, sb, y.p, -1, r.jb);
  axis_coefficients(B, c, d, r.jb);
  return r;
}
template <class Body, class Vec>
inline RowOf<ScalarOf<Vec>> row_along_axis(const Body &A, const Vec &sa, const JetOf<Vec> &pa, const Body &B,
                                           const Vec &sb, const JetOf<Vec> &pb, const Vec &c) {
  return row_along_axis(A, sa, pa, B, sb, pb, c, axis_jet(B, c));
}
inline Row row_along_axis(const BodyState &A, const V3 &sa, const BodyState &B, const V3 &sb, const V3 &c) {
  return row_along_axis(A, sa, point_jet(A, sa), B, sb, point_jet(B, sb), c);
}

// The same row with its two bodies' coefficients exchanged (a unit written with b first).
template <class S>
inline RowOf<S> swapped(const RowOf<S> &r) {
  RowOf<S> o = r;
  for (int i = 0; i < kBodyDof; ++i) o.ja[i] = r.jb[i], o.jb[i] = r.ja[i];
  return o;
}

// ---- joint kinds (the tree set's) ----
constexpr V3 kWorldAxes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

// A spherical joint: point s_a of body a on point s_b of body b (3 rows, world x, y, z): row_along's
// with e a world axis, whose products with e's zeros are left out (R^T e_k is R's row k).
template <class Body, class Vec>
inline void spherical_rows(const Body &A, const Vec &sa, const Body &B, const Vec &sb, RowOf<ScalarOf<Vec>> *out) {
  using S = ScalarOf<Vec>;
  const JetOf<Vec> pa = point_jet(A, sa), pb = point_jet(B, sb);
  const Vec d = pa.p - pb.p, dq = pa.pq - pb.pq;
  const S dk[3] = {d.x, d.y, d.z}, dqk[3] = {dq.x, dq.y, dq.z};
  const Vec ra[3] = {{A.R.c0.x, A.R.c1.x, A.R.c2.x}, {A.R.c0.y, A.R.c1.y, A.R.c2.y}, {A.R.c0.z, A.R.c1.z, A.R.c2.z}};
  const Vec rb[3] = {{B.R.c0.x, B.R.c1.x, B.R.c2.x}, {B.R.c0.y, B.R.c1.y, B.R.c2.y}, {B.R.c0.z, B.R.c1.z, B.R.c2.z}};
  for (int k = 0; k < 3; ++k) {
    RowOf<S> &r = out[k];
    r.phi = dk[k];
    r.gamma = -dqk[k];
    const Vec oa = cross(sa, ra[k]), ob = cross(sb, rb[k]);
    for (int i = 0; i < 3; ++i) r.ja[i] = S{} + (i == k ? real(1) : real(0)), r.jb[i] = S{} + (i == k ? real(-1) : real(0));
    r.ja[3] = oa.x, r.ja[4] = oa.y, r.ja[5] = oa.z;
    r.jb[3] = -ob.x, r.jb[4] = -ob.y, r.jb[5] = -ob.z;
  }
}

// A revolute joint about body a's axis k_a (unit, body-fixed) at point s_a, on body b's point s_b
// whose axes u_b, n_b (unit, perpendicular to each other and to the joint axis in body b's
// frame) stay perpendicular to k_a: 5 rows (the point's 3, then k_a . u_b, k_a . n_b). Its 5
// multipliers are the joint's force (3) and its two moments.
template <class Body, class Vec>
inline void revolute_rows(const Body &A, const Vec &sa, const Vec &ka, const Body &B, const Vec &sb, const Vec &ub,
                          const Vec &nb, RowOf<ScalarOf<Vec>> *out) {
  spherical_rows(A, sa, B, sb, out);
  const JetOf<Vec> k = axis_jet(A, ka);
  out[3] = row_perpendicular(A, ka, k, B, ub, axis_jet(B, ub));
  out[4] = row_perpendicular(A, ka, k, B, nb, axis_jet(B, nb));
}

// A prismatic joint: body b (the rod) slides along body a's (the cylinder's) axis u_a, the two
// frames aligned (body-fixed unit axes (u, n, k) of each, right-handed): 3 orientation rows
// (u_a . n_b, u_a . k_b, n_a . k_b), then the rod's point s_b on the cylinder's axis through
// its point s_a (along n_a and k_a): 5 rows.
template <class Body, class Vec>
inline void prismatic_rows(const Body &A, const Vec &sa, const Vec &ua, const Vec &na, const Vec &ka, const Body &B,
                           const Vec &sb, const Vec &nb, const Vec &kb, RowOf<ScalarOf<Vec>> *out) {
  const JetOf<Vec> ja_u = axis_jet(A, ua), ja_n = axis_jet(A, na), jb_n = axis_jet(B, nb), jb_k = axis_jet(B, kb);
  out[0] = row_perpendicular(A, ua, ja_u, B, nb, jb_n);
  out[1] = row_perpendicular(A, ua, ja_u, B, kb, jb_k);
  out[2] = row_perpendicular(A, na, ja_n, B, kb, jb_k);
  // (p_b - p_a) . (R_a n_a): row_along_axis with the rod first, its coefficients put back in
  // (a, b) order
  const JetOf<Vec> pb = point_jet(B, sb), pa = point_jet(A, sa);
  out[3] = swapped(row_along_axis(B, sb, pb, A, sa, pa, na, ja_n));
  out[4] = swapped(row_along_axis(B, sb, pb, A, sa, pa, ka));
}

// A joint that closes a planar loop: point s_a of body a on point s_b of body b in the plane
// of body b's axes u_b, n_b only (2 rows): out of the plane the loop is already held by the
// tree's joints (a full 3D joint here would add 3 redundant rows).
template <class Body, class Vec>
inline void planar_cut_rows(const Body &A, const Vec &sa, const Body &B, const Vec &sb, const Vec &ub, const Vec &nb,
                            RowOf<ScalarOf<Vec>> *out) {
  const JetOf<Vec> pa = point_jet(A, sa), pb = point_jet(B, sb);
  out[0] = row_along_axis(A, sa, pa, B, sb, pb, ub);
  out[1] = row_along_axis(A, sa, pa, B, sb, pb, nb);
}

}  // namespace legsim::spatial
