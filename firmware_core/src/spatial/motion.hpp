// The legs in space stepped in time (docs/design/spatial.md): the robot's state (q: 7 numbers a
// body, v: 6), its commands held over a step (each linear actuator's axial force, each rowing
// torque), its feet's modes on the ground (spatial/contact). A step is RK4 on the rotation
// group (Munthe-Kaas: each body's local coordinates start at 0, theta' = dexp^-1(theta) omega),
// then the positions and velocities projected onto the rows (M-orthogonal: the least
// kinetic-energy correction), then the accelerations and multipliers at its end (the reactions
// it reports, and the next step's first stage). Or generalized-alpha on the group (Bruls,
// Cardona, Arnold 2012: q1 = q0 (+) h dq, the Chung-Hulbert parameters of rho_inf), explicit in
// the rows: its unknown is the constrained acceleration at the step's end (contact_accelerations,
// the index-1 form), found by fixed-point iterations, then the same projections. Second order,
// with numerical damping of what the step does not resolve (rho_inf); no Jacobian of the
// contact problem needed, so the contact modes and their events are RK4's. Its history (the
// auxiliary acceleration) is RobotData's, restarted at the accelerations whenever the modes are
// settled (an event, an impact); for a part of another length its lead over the accelerations
// ((alpha_m - alpha_f) h a') is scaled to it. A contact event inside the step (a touchdown, a
// lift-off, stick to slip, slip to stick) is located by retaking the step from its start to a
// fraction of it (regula falsi with the Illinois rule on the event's function), applied there,
// and the rest of the step taken after it. So is a stroke's arrival at its stop (a linear
// actuator's length or a rowing angle at its end: an inelastic impact, then the stop's row held,
// FeetHold::stops) and a stop's release (its push falling to 0: decided at the acceleration level
// as a stuck foot's lift-off).
//
// (model, data): the robot (SpatialRobot, robot.hpp) is the model; RobotData the data. A step is
// all or nothing: data changes only when it returns LEGSIM_OK.
#pragma once

#include "spatial/contact.hpp"

namespace legsim::spatial {

// What each actuator is told, held over a step: a force (N; a rowing torque, N m) or a servo's
// set-point (a length, m; a rowing angle, rad) that the servo holds by its PD law plus a
// feed-forward force (N; N m), saturated at the actuator's largest force (robot.hpp:
// RobotActuator, SpatialRobot's rowing numbers).
enum class CommandMode : uint8_t { Force, Servo };
struct RobotCommands {
  CommandMode actuator_mode[kMaxRobotActuators];
  real actuator[kMaxRobotActuators], actuator_ff[kMaxRobotActuators];
  CommandMode rowing_mode[kMaxLegs];
  real rowing[kMaxLegs], rowing_ff[kMaxLegs];
};

// The contact problems solved since data_init (each impact's, each decision of the stuck feet's
// modes): how many, how many the projected Gauss-Seidel fallback finished, the most iterations
// (Newton's plus sweeps) and the largest residual (friction_cone.hpp's natural map).
struct ConeStats {
  int solved, by_sweeps, max_iterations;
  real max_residual;
};

// What a step starts from and returns to when it fails (and a located event's retakes from the
// start of their part).
struct RobotSnapshot {
  real t;
  real q[kBodyConfig * kMaxRobotBodies], v[kMaxRobotDof], a[kMaxRobotDof], mu[kMaxSystemRows];
  real acc_aux[kMaxRobotDof], acc_aux_h;
  real N[kMaxContacts];
  FeetHold hold;
  V3 slip_dir[kMaxContacts], slip_ref[kMaxContacts];
  real slip_stage_min[kMaxContacts];
  // the report a failed step must leave as it was
  real actuator_force[kMaxRobotActuators], rowing_torque[kMaxLegs];
  V3 impulse[kMaxContacts];
  real stop_impulse[kMaxHeldStops];
  ConeReport impact, modes;
  ConeStats cone_stats;
  int projection_iterations, impacts, stop_impacts;
  int pole_sign;
  uint32_t pole_set;
};

struct RobotData {
  real t;  // s
  real q[kBodyConfig * kMaxRobotBodies], v[kMaxRobotDof];
  real a[kMaxRobotDof];       // at (t, q, v)
  real acc_aux[kMaxRobotDof];  // generalized-alpha's auxiliary acceleration (its history)
  real acc_aux_h;              // s: the part it was taken over (0: none, acc_aux = a)
  real mu[kMaxSystemRows];    // the multipliers at (t, q, v)
  real normal_force[kMaxContacts];  // N: each sliding foot's at (t, q, v)
  FeetHold hold;              // the feet's modes (and the ground's frame)
  V3 slip_dir[kMaxContacts];      // a sliding foot's friction direction while its slip is below kSlipHold
  // a sliding foot's slip direction at the (part) step's start, and its slip velocity's least
  // component along it over the last RK4 step's stages (a reversal the end can miss)
  V3 slip_ref[kMaxContacts];
  real slip_stage_min[kMaxContacts];
  bool has_ground;            // else the feet pass through (no contact events)
  GroundPlane ground;
  RobotCommands command;
  real actuator_force[kMaxRobotActuators];  // N, each linear actuator's at (t, q, v)
  real rowing_torque[kMaxLegs];             // N m, each yoke's about its hip axis at (t, q, v)
  // the last step's report
  int projection_iterations;  // its last position projection's Newton iterations
  int events;                 // contact events located in it
  int impacts;                // touchdowns since data_init
  int stop_impacts;           // arrivals on a stroke's stop since data_init
  // the sign of the sliding feet's det (I + Lambda) at the last state a part reached, and those
  // feet (contact_accelerations): a part whose stages find it turned passed a pole (refused)
  int pole_sign;
  uint32_t pole_set;
  bool pole_crossed;          // the last refusal was that turn
  bool pole_check;            // the turn refused (robot_step's parts)
  ConeReport impact;          // the last impact's contact problem
  ConeReport modes;           // the last decision of the stuck feet's modes (contact_modes)
  ConeStats cone_stats;       // every contact problem's since data_init
  V3 impulse[kMaxContacts];       // N s, world: the ground's on each foot at the last impact
  real stop_impulse[kMaxHeldStops];  // N s, N m s (>= 0): each stop's (bit 3 l + k) at the last impact
  // work space: the rows at the last evaluation and their factor, the contact solves' columns,
  // the step's snapshots (not on the stack: about 110 KB together in double)
  Row rows[kMaxSystemRows];
  RobotFactor factor;
  ContactWork contact_work;
  RobotSnapshot snapshot[2];
};

// The projection's tolerance: every row's |Phi| (m, or a cosine) at most this.
constexpr real kProjectionTolerance = by_precision(1e-12, 1e-5);
constexpr int kProjectionMaxIterations = 8;
// The most events located in one step: more is a Zeno cascade or modes that do not settle.
constexpr int kMaxStepEvents = 64;
// Generalized-alpha: the spectral radius at infinity (legsim_options.rho_inf's default); its
// fixed-point iterations stop when the acceleration changes by at most this relative to the
// largest (at least 1 m/s^2, rad/s^2), else LEGSIM_ERR_NOT_CONVERGED after kGalphaMaxIterations.
constexpr real kGalphaRhoInf = real(0.8);
constexpr real kGalphaTolerance = by_precision(1e-8, 1e-4);
constexpr int kGalphaMaxIterations = 40;

enum class Integrator : uint8_t { Rk4, GeneralizedAlpha };

// data at (q, v) with the feet of hold (stuck and sliding; free feet may not be below the
// ground), the ground (nullptr: none) and zero forces commanded: projected, its modes checked against
// the cone (a stuck foot pulling or past mu_s N is let go), its accelerations and multipliers.
// LEGSIM_ERR_BAD_INPUT for a foot mode on a leg without a foot or the robot does not have, a
// foot both stuck and sliding, a free foot more than 1e-9 m (float: 1e-5 m) under the ground; LEGSIM_ERR_CONTACT when no modes hold; else as robot_step_rk4.
legsim_status robot_data_init(const SpatialRobot &robot, const real *q, const real *v, const FeetHold &hold,
                              const GroundPlane *ground, RobotData &data);

// The accelerations and multipliers at data's state under its commands (after a change of
// commands; robot_step keeps them).

// Each actuator's force and rowing torque at (q, v) by the commands (a servo's saturated).
void command_forces(const SpatialRobot &robot, const RobotCommands &c, const real *q, const real *v, real *force_n,
                    real *rowing_nm);
legsim_status robot_data_refresh(const SpatialRobot &robot, RobotData &data);

// One step of h (s, > 0): RK4 (or generalized-alpha) on the group with the contact events inside it located. Statuses:
// LEGSIM_ERR_BAD_INPUT for h not positive and finite; LEGSIM_ERR_SINGULAR (a leg at a dead
// centre); LEGSIM_ERR_NOT_CONVERGED (the projection, an impact's contact problem);
// LEGSIM_ERR_CONTACT (friction making a normal force arbitrary, modes that do not settle, more
// than kMaxStepEvents events); LEGSIM_ERR_DIVERGED (a non-finite result).
// LEGSIM_ERR_NOT_CONVERGED also for generalized-alpha's iterations.
legsim_status robot_step(const SpatialRobot &robot, RobotData &data, real h, Integrator integrator);
legsim_status robot_step_rk4(const SpatialRobot &robot, RobotData &data, real h);
legsim_status robot_step_generalized_alpha(const SpatialRobot &robot, RobotData &data, real h);

// The robot's kinetic energy (J) at v, and gravity's potential (J, from z = 0) at q.
real robot_kinetic_energy(const SpatialRobot &robot, const real *v);
real robot_gravity_potential(const SpatialRobot &robot, const real *q);

// The ground's force on foot l at data's state (N, world): a stuck foot's from its rows, a
// sliding foot's normal force and its friction, 0 for a free foot.
V3 robot_foot_force(const SpatialRobot &robot, const RobotData &data, int l);

}  // namespace legsim::spatial
