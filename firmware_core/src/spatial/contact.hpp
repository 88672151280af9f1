// The feet on the ground in space (docs/design/spatial.md, "Contact"): a plane with Coulomb's
// circular cone. The box's own contact points (robot.hpp) are on the same law: a "foot" below
// is any contact point c (robot_contacts: the feet, then the box's). A foot is free, stuck (three rows hold it at its anchor) or sliding (the
// normal's row keeps it on the plane; friction mu_k N opposite its slip velocity, whose
// direction may turn, is an applied force that depends on the normal force N). Its modes change
// at events located inside the step (spatial/motion): a touchdown (an impact: the feet in touch
// take impulses on their cones, cone_solve, friction_cone.hpp), a lift-off (N reaches 0), stick
// to slip (the tangential force reaches mu_s N), slip to stick (the slip velocity reaches 0).
#pragma once

#include "spatial/dynamics.hpp"
#include "spatial/friction_cone.hpp"

namespace legsim::spatial {

// every contact point of a robot can touch at once (the feet and the box's points)
static_assert(kMaxContacts <= kConeMaxContacts, "one contact problem must hold every contact point");

// The contact solves' columns, too large for a stack (about 80 KB in double): kept in the data.
struct ContactWork {
  real x[kMaxContacts][kMaxRobotDof], m[kMaxContacts][kMaxSystemRows];  // a sliding point's friction's response
  real X[kConeMaxRows][kMaxRobotDof];  // an impact's velocity change per unit impulse
};

// The ground: a point on it and its upward unit normal (world, m), friction coefficients.
struct GroundPlane {
  V3 point, normal;
  real mu_static, mu_kinetic;
};

// The ground's frame for the feet's rows: its normal and two unit tangents (right-handed).
void ground_frame(const GroundPlane &g, FeetHold &hold);

// Contact c's point and its velocity (world) at (q, v).
void foot_motion(const SpatialRobot &robot, int l, const real *q, const real *v, V3 &p, V3 &pv);

// Contact c's point's acceleration (world) from the bodies' accelerations a at (q, v).
V3 contact_acceleration(const SpatialRobot &robot, int l, const real *q, const real *v, const real *a);

// The tangential part of a world vector in hold's frame.
inline V3 tangential(const FeetHold &hold, const V3 &x) { return x - dot(x, hold.normal) * hold.normal; }

// A slip slower than this (m/s) keeps the direction it had (its last above it, or the one its
// slip started with: contact_modes'): near a standstill a slip's direction turns faster than any
// step resolves (it is singular at 0). Friction along a kept direction s does work -mu_k N s . v_t,
// never positive while the slip goes along s; its turning back is the slip-to-stick event.
constexpr real kSlipHold = real(1e-4);

// The accelerations and multipliers at (q, v) under Q with the feet of hold, each sliding foot's
// friction -mu_k N s coupled in (s its slip velocity's direction, or slip_dir[l] below
// kSlipHold): the solve for Q, one more per sliding foot for its friction per newton of N,
// and a small system for the N's (their friction moves their own multipliers). normal_force[l]:
// each sliding foot's N. factored: rows and F are already those at (q, v) (the projections'),
// else they are built here. LEGSIM_ERR_CONTACT when that system is singular (Painleve: friction
// can make the normal force arbitrary); else as robot_factor. fixed_dir: slip_dir[l] is the
// direction whatever the slip (an implicit step's iterations, where a slip turning back within
// the step would flip it between iterates: that reversal is an event of its own). pole_sign: the
// sign of det (I + Lambda) (+1 without sliding feet): where it turns between two states of one
// part, the N's went through a pole between them (Painleve's case, passed unseen by the stages).
legsim_status contact_accelerations(const SpatialRobot &robot, const FeetHold &hold, real mu_kinetic,
                                    const V3 *slip_dir, const real *q, const real *v, const real *Q, real *a, real *mu,
                                    real *normal_force, Row *rows, RobotFactor &F, ContactWork &w, bool factored = false,
                                    bool fixed_dir = false, int *pole_sign = nullptr);

// Sliding foot l's friction direction at (q, v) (unit, tangential): its slip velocity's, or
// fallback's below kSlipHold.
V3 slip_direction(const SpatialRobot &robot, const FeetHold &hold, int l, const real *q, const real *v,
                  const V3 &fallback);

// An impact at (q, v) (a touchdown, a stroke's arrival on its stop): one contact problem of the
// feet of `touching` (bit l: impulses on their cones, mu_kinetic) and the strokes of `arriving`
// and `near` (bit 3 l + k, on hold.stops at the end hold.upper says: an impulse along the stop's
// gap that only pushes, a cone of mu = 0), the joints' rows and the other held stops' holding (as
// bilateral rows); solved by cone_solve (its bounded iterations and report). v becomes the
// velocity after it (no foot approaching the ground, no stroke of the problem its stop, the
// kinetic energy not above before). On return `hold` gives each touching foot's mode after it:
// stuck where it stopped, sliding along its slip (slip_dir), free when it leaves faster than 1e-4
// m/s (slower it stays: the projection takes its normal velocity off); a stroke of `arriving`
// held unless it leaves its stop faster than 1e-4 m/s (rad/s), one of `near` (at its end, not
// held before) when its impulse pushes, or when it approached and leaves slower than that; impulse[l] the ground's on foot l (N s, world),
// stop_impulse[3 l + k] each problem stroke's (N s, N m s; >= 0). LEGSIM_ERR_NOT_CONVERGED with
// cone_solve's best iterate refused; LEGSIM_ERR_SINGULAR as robot_factor; LEGSIM_ERR_CAPACITY
// for more feet and strokes than one contact problem holds (kConeMaxContacts).
legsim_status contact_impact(const SpatialRobot &robot, const GroundPlane &ground, uint32_t touching,
                             uint32_t arriving, uint32_t near, const real *q, real *v, FeetHold &hold, V3 *slip_dir,
                             V3 *impulse, real *stop_impulse, ConeReport &report, Row *rows, RobotFactor &F,
                             ContactWork &w, uint32_t jammed = 0);

// The normal rate (m/s) an impact takes for a foot of `jammed` (contact_impact): a sliding foot
// that no mode of the acceleration level keeps on the ground or lets go (Painleve's inconsistent
// case with a stop) meets it as if approaching this slowly, so that the problem's solution, if
// the slip cannot go on, is the impulse that stops it (an impact without collision).
constexpr real kJamRate = real(1e-7);

// The modes of the stuck feet decided on their cones at (q, v) under Q: the acceleration-level
// contact problem of those feet (u = W r + q: r their ground forces, u their points'
// accelerations; W and q from the robot's solve with them released, the sliding feet's friction
// coupled in), by cone_solve: first on mu_static (which stick), then with mu_kinetic on those that
// slip (which way: slip_dir, their acceleration's tangential direction). The feet of `slipping`
// (their force at the mu_static cone's edge and leaving it: a located stick to slip) are on
// mu_kinetic from the start: the acceleration level alone would keep them at the edge (and one
// still at the edge, mu_kinetic = mu_static, slips against its force). A foot whose force
// vanishes and whose point accelerates off the ground is let go. LEGSIM_ERR_NOT_CONVERGED with
// the contact problem unsolved, LEGSIM_ERR_CONTACT when the modes and the coefficients do not
// agree within a pass a foot; LEGSIM_ERR_CAPACITY for more stuck points than kConeMaxContacts;
// else as contact_accelerations.
legsim_status contact_modes(const SpatialRobot &robot, const GroundPlane &ground, const real *q, const real *v,
                            const real *Q, uint32_t slipping, FeetHold &hold, V3 *slip_dir, ConeReport &report,
                            Row *rows, RobotFactor &F, ContactWork &w, bool with_stops = true);

}  // namespace legsim::spatial
