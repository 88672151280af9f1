// What the system layer asks of the planar bodies beyond their count of velocity coordinates
// (kBodyDof, planar/body.hpp): the mass matrix and the configuration update. The system
// layer (projection, assembly, the dynamics solve, both integrators) reaches M and q (+) dq
// only through these, so it assumes neither a diagonal M nor an additive angle; a spatial
// module implements the same names on its 6 x 6 blocks and its rotations
// (docs/design/layers.md).
//
// The plane: M is diagonal, (m, m, J) per body, kept per coordinate (Model::mass, its
// inverse Model::minv: the factor's weight W = M^-1); the configuration is (x, y, phi), whose
// update is additive. Each function is inline and per coordinate, so the integrators'
// per-coordinate loops keep their shape (and their vector code): the same arithmetic, the
// same values, as the products they replace. (A spatial instance acts on a body's block:
// its loops run over bodies.)
#pragma once

#include "planar/body.hpp"

namespace legsim {

struct PlanarBodies {
  static constexpr int kDof = kBodyDof;
  // (M x)_k, coordinate k of M x (x_k the value of coordinate k), M given by Model::mass.
  static inline real mass_times(const real *mass, int k, real x) { return mass[k] * x; }
  // (W x)_k, W = M^-1 given by Model::minv, or any weight of that form (assembly's W = I).
  static inline real mass_inverse_times(const real *minv, int k, real x) { return minv[k] * x; }
  // q (+) dq, coordinate k: the configuration moved by a velocity-space increment dq (h v,
  // a correction). Additive in the plane; on the rotation group in space.
  static inline real config_add(real q, real dq) { return q + dq; }
};

// The element module this build's system layer is instantiated with.
using Bodies = PlanarBodies;

}  // namespace legsim
