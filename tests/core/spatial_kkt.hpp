// The spatial tests' independent check: the dense KKT matrix [M J^T; J 0] of a spatial robot
// built from its rows with Eigen (the solves under test never form it), for a full-pivot LU.
#pragma once

#include <Eigen/Dense>

#include "spatial/dynamics.hpp"

namespace spatial_kkt {
using legsim::spatial::kBodyDof;
using legsim::spatial::Row;
using legsim::spatial::SpatialRobot;

// The rows of the system the test uses, by index into rows: the joints' (below robot.m) and the
// feet's (foot_row(robot, l) + k, acting on leg l's foot body alone).
inline Eigen::MatrixXd matrix(const SpatialRobot &robot, const Row *rows, const int *idx, int m) {
  const int nv = kBodyDof * robot.nb;
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(nv + m, nv + m);
  for (int b = 0; b < robot.nb; ++b) {
    const double I[3] = {robot.inertia[b].x, robot.inertia[b].y, robot.inertia[b].z};
    for (int i = 0; i < 3; ++i) K(kBodyDof * b + i, kBodyDof * b + i) = robot.mass[b];
    for (int i = 0; i < 3; ++i) K(kBodyDof * b + 3 + i, kBodyDof * b + 3 + i) = I[i];
  }
  for (int i = 0; i < m; ++i) {
    const int r = idx[i];
    const int ba = r < robot.m ? robot.row_body[r][0] : robot.leg[(r - robot.m) / 3].foot_body;
    const int bb = r < robot.m ? robot.row_body[r][1] : -1;
    for (int k = 0; k < kBodyDof; ++k) {
      if (ba >= 0) K(nv + i, kBodyDof * ba + k) += rows[r].ja[k];
      if (bb >= 0) K(nv + i, kBodyDof * bb + k) += rows[r].jb[k];
    }
  }
  K.topRightCorner(nv, m) = K.bottomLeftCorner(m, nv).transpose();
  return K;
}

// The joints' rows alone (0 .. robot.m).
inline Eigen::MatrixXd matrix(const SpatialRobot &robot, const Row *rows) {
  int idx[legsim::spatial::kMaxSystemRows];
  for (int r = 0; r < robot.m; ++r) idx[r] = r;
  return matrix(robot, rows, idx, robot.m);
}

// J (the joints' rows x 6 nb): the matrix's lower left block.
inline Eigen::MatrixXd jacobian(const SpatialRobot &robot, const Row *rows) {
  return matrix(robot, rows).bottomLeftCorner(robot.m, kBodyDof * robot.nb);
}

}  // namespace spatial_kkt
