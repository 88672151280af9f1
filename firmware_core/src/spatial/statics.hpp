// The legs in space standing (docs/design/spatial.md): the ground forces of the stance feet from
// the whole robot's equilibrium, then each leg's actuator forces, rowing torque and joint
// multipliers from its own equilibrium (its weight, its foot's force; the box holding its hip).
//
// The stance's feet take the weight (and a load on the box) with the least sum of squares of
// their forces among the forces that balance it: the rule for what statics leaves free. On level
// ground the horizontal equations (x, y and the moment about z) and the vertical ones (z and the
// moments about horizontal axes through a ground point) part: a tripod's vertical forces are
// those the centre of mass's place in its support triangle gives and its horizontal forces are
// zero; on six feet the vertical forces are the nearest to equal that balance the weight.
//
// A leg's equilibrium is square: its 7 bodies' 42 equations J_l^T lambda - sum F_a grad l_a -
// tau e = Q (gravity and its foot's force) for its 39 multipliers, 2 actuator forces and rowing
// torque; its hip rows' multipliers are the hip's reaction. A multiplier is a row's (rows.hpp):
// a body's constraint force is -J^T lambda.
#pragma once

#include "spatial/robot.hpp"

namespace legsim::spatial {

struct RobotStatics {
  V3 foot_force[kMaxLegs];                // N, world: the ground's force on each foot (0 off the stance)
  real actuator_force[kMaxRobotActuators];  // N: each linear actuator's axial force
  real rowing_torque[kMaxLegs];           // N m: each yoke's, about its hip axis
  real multiplier[kMaxRobotRows];         // each row's, in the robot's row order
};

// At q (the velocities zero), the feet in stance_mask (bit l: leg l) on the ground, a force
// box_force_n (N, world; nullptr: none) at the box's centre. LEGSIM_ERR_NO_EQUILIBRIUM when the
// stance cannot balance the loads (fewer than three feet, all on one line, or a foot that would
// have to pull: its force not against gravity), LEGSIM_ERR_SINGULAR
// when a leg is at a dead centre, LEGSIM_ERR_MODEL for a leg with other freedoms than its
// actuators and its rowing, LEGSIM_ERR_BAD_INPUT for a fixed box, a mask naming a leg
// the robot does not have or a leg without a foot.
legsim_status robot_statics(const SpatialRobot &robot, const real *q, uint32_t stance_mask, const real *box_force_n,
                            RobotStatics &out);

// The same under any applied forces Q (6 per body, robot_forces' convention: a force in the world
// on v, a moment in the body's frame on omega): the weights and the box's load above are one
// such Q; with -M a added (d'Alembert's inertial forces) it is inverse dynamics
// (spatial/inverse.hpp). A foot "pulls" when its force is not against gravity.
legsim_status robot_statics_applied(const SpatialRobot &robot, const real *q, uint32_t stance_mask, const real *Q,
                                    RobotStatics &out);

}  // namespace legsim::spatial
