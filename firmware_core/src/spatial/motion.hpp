// The legs in space stepped in time (docs/design/spatial.md): the robot's state (q: 7 numbers a
// body, v: 6), its commands held over a step (each linear actuator's axial force, each rowing
// torque), the feet the ground holds; RK4 on the rotation group (Munthe-Kaas: each body's local
// coordinates start at 0 each step, theta' = dexp^-1(theta) omega), then the positions and
// velocities projected onto the rows (M-orthogonal: the least kinetic-energy correction), then
// the accelerations and multipliers at the step's end (the reactions it reports, and the next
// step's first stage).
//
// (model, data): the robot (SpatialRobot, robot.hpp) is the model; RobotData the data. A step is
// all or nothing: data changes only when it returns LEGSIM_OK.
#pragma once

#include "spatial/dynamics.hpp"

namespace legsim::spatial {

struct RobotData {
  real t;  // s
  real q[kBodyConfig * kMaxRobotBodies], v[kMaxRobotDof];
  real a[kMaxRobotDof];     // at (t, q, v)
  real mu[kMaxSystemRows];  // the multipliers at (t, q, v)
  FeetHold hold;
  real actuator_force[kMaxRobotActuators];  // N, each linear actuator's, held over a step
  real rowing_torque[kMaxLegs];             // N m, each yoke's about its hip axis
  int projection_iterations;                // the last step's position projection's Newton iterations
  // work space: the rows at the last evaluation and their factor
  Row rows[kMaxSystemRows];
  RobotFactor factor;
};

// The projection's tolerance: every row's |Phi| (m, or a cosine) at most this.
constexpr real kProjectionTolerance = real(sizeof(real) == sizeof(float) ? 1e-5 : 1e-12);
constexpr int kProjectionMaxIterations = 8;

// q and v moved onto the rows (with hold's feet): q by Newton's iterations of the M-orthogonal
// correction, then v by one. LEGSIM_ERR_NOT_CONVERGED when the rows are not met to
// kProjectionTolerance in kProjectionMaxIterations; LEGSIM_ERR_SINGULAR as robot_kkt.
legsim_status robot_project(const SpatialRobot &robot, const FeetHold &hold, real *q, real *v, int *iterations = nullptr);

// data at (q, v) with the feet of hold stuck and the commands zero: projected, then its
// accelerations and multipliers. LEGSIM_ERR_BAD_INPUT for a stuck leg without a foot or a mask
// naming a leg the robot does not have; else as robot_project.
legsim_status robot_data_init(const SpatialRobot &robot, const real *q, const real *v, const FeetHold &hold,
                              RobotData &data);

// The accelerations and multipliers at data's state under its commands (after a change of
// commands or feet; robot_step keeps them).
legsim_status robot_data_refresh(const SpatialRobot &robot, RobotData &data);

// One RK4 step of h (s, > 0) on the rotation group. Statuses: robot_accelerations' and
// robot_project's, and LEGSIM_ERR_BAD_INPUT for h not positive and finite.
legsim_status robot_step_rk4(const SpatialRobot &robot, RobotData &data, real h);

// The robot's kinetic energy (J) at v, and gravity's potential (J, from z = 0) at q.
real robot_kinetic_energy(const SpatialRobot &robot, const real *v);
real robot_gravity_potential(const SpatialRobot &robot, const real *q);

}  // namespace legsim::spatial
