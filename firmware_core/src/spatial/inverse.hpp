// The legs in space along a planned motion (docs/design/spatial.md, "Inverse dynamics along the
// gait"): the robot's velocities and accelerations from the box's motion and each foot's, then
// the actuator forces, rowing torques, stance feet's ground forces and every joint's reaction
// that make that motion: M a + J^T lambda = Q + B u.
//
// The stance feet stuck on the ground leave the problem redundant (a tripod's feet: 9 force
// components against 6 equations of the whole robot); it is resolved by statics' rule
// (robot_statics_applied): the inertial forces -M a join the applied forces, the stance feet take
// the resultant with the least sum of squares of their forces, and each leg then its own square
// equilibrium.
#pragma once

#include "spatial/statics.hpp"

namespace legsim::spatial {

// The robot's velocities v and accelerations a (6 per body: v world, omega body frame, and their
// rates) at q for the box's (box_v, box_a: the same layout) and each foot's (world, m/s and m/s^2:
// foot_v[l], foot_a[l] for every leg). Each leg is a square system: its joints' rows (its hip's
// coefficients on the box moved to the right-hand side) and its foot's three along the world's
// axes, J_l v_l = -B_l v_0 + foot_v, J_l a_l = gamma_l - B_l a_0 + foot_a (gamma from (q, v)).
// LEGSIM_ERR_SINGULAR at a leg's dead centre; LEGSIM_ERR_MODEL for a leg without a foot or with
// other freedoms than its foot's three; LEGSIM_ERR_BAD_INPUT for a fixed box.
legsim_status robot_prescribed_motion(const SpatialRobot &robot, const real *q, const real *box_v, const real *box_a,
                                      const V3 *foot_v, const V3 *foot_a, real *v, real *a);

// The forces that make (q, v, a) with the feet of stance_mask on the ground: robot_statics_applied
// with Q = gravity, the gyroscopic moments, less M a. Its statuses.
legsim_status robot_inverse_dynamics(const SpatialRobot &robot, const real *q, const real *v, const real *a,
                                     uint32_t stance_mask, RobotStatics &out);

// Each joint's reaction on its first body (joint[j].a) from the multipliers mu (robot.m): its
// force (N, world) and its moment about the joint's point on that body (N m, world); its second
// body takes the opposite at the same point. force, moment: robot.nj each.
void robot_joint_reactions(const SpatialRobot &robot, const real *q, const real *mu, V3 *force, V3 *moment);

// The box moving at a constant twist in its own frame: forward (x) at speed (m/s) and turning
// about its z at rate (rad/s), level at height z, at the world's origin heading along x at
// t = 0 (the tripod gait's plan). Its q (7), v and a (6 each, robot coordinates) at t_s.
void twist_motion(real height, real speed, real rate, double t_s, real *box_q, real *box_v, real *box_a);

// The first and second derivatives at 0 of a function sampled at the offsets k h, k = k0 .. k0 + 4
// (f[0 .. 4]), by the five-point stencil's weights (central for k0 = -2, else one-sided).
void stencil_derivatives(int k0, real h, const real *f, real &d1, real &d2);

}  // namespace legsim::spatial
