// The legs in space moving (docs/design/spatial.md): M a + J^T lambda = Q, J a = gamma over the
// joints' rows and each stuck foot's three (its point held at its anchor on the ground), solved
// leg by leg so that the work grows linearly with the legs.
//
// A leg's rows act on its own bodies and, through its hip's revolute, on the box: for a given
// box acceleration a0 a leg's multipliers are lambda_l = lambda0_l + G_l a0 from its own
// S_l = J_l M_l^-1 J_l^T (J_l its rows' coefficients on its bodies). The box then takes
// (M_0 + sum_l B_l^T G_l) a0 = Q_0 - sum_l B_l^T lambda0_l (B_l its rows' coefficients on the
// box: a 6 x 6 Schur complement), and each leg its accelerations a_l = M_l^-1 (Q_l - J_l^T
// lambda_l). The same solve with other right-hand sides projects positions and velocities
// onto the rows (the M-orthogonal corrections).
//
// A multiplier is a row's (rows.hpp): a body's constraint force is -J^T lambda; a stuck foot's
// rows are e_k . (p_foot - anchor), so the ground's force on the foot is -(lambda_x, lambda_y,
// lambda_z).
#pragma once

#include "spatial/robot.hpp"

namespace legsim::spatial {

// The system's rows: the robot's joints' [0, robot.m), then three slots per leg for its foot
// (robot.m + 3 l ..), used when the foot is stuck.
constexpr int kMaxSystemRows = kMaxRobotRows + 3 * kMaxLegs;
constexpr int kMaxRobotDof = kBodyDof * kMaxRobotBodies;

// Which feet the ground holds (bit l: leg l) and where (world, m).
struct FeetHold {
  uint32_t stuck;
  V3 anchor[kMaxLegs];
};
inline int foot_row(const SpatialRobot &robot, int l) { return robot.m + 3 * l; }

// Every row of the system at (q, v): the joints' (robot_rows) and the stuck feet's.
void system_rows(const SpatialRobot &robot, const FeetHold &hold, const real *q, const real *v, Row *rows);

// [M J^T; J 0] [x; mu] = [f; g] with J the coefficients of rows (system_rows'), f one force per
// velocity coordinate (6 per body), g one value per system row (the unused foot slots ignored).
// LEGSIM_ERR_SINGULAR when a leg's rows or the box's complement are dependent (a leg at a dead
// centre, a stuck foot's rows dependent on its leg's); x and mu then unspecified.
legsim_status robot_kkt(const SpatialRobot &robot, uint32_t stuck, const Row *rows, const real *f, const real *g,
                        real *x, real *mu);

// The accelerations a (6 per body: v' world, omega' body frame) and multipliers mu (per system
// row) at (q, v) under the applied forces Q (robot_forces').
legsim_status robot_accelerations(const SpatialRobot &robot, const FeetHold &hold, const real *q, const real *v,
                                  const real *Q, real *a, real *mu);

// The ground's force on stuck foot l (N, world) from the multipliers.
inline V3 foot_force(const SpatialRobot &robot, const real *mu, int l) {
  const real *m = mu + foot_row(robot, l);
  return {-m[0], -m[1], -m[2]};
}

}  // namespace legsim::spatial
