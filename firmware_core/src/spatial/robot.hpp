// Legs in space on a box (docs/design/spatial.md, formulation (a), the tree rows): each leg is
// its own planar description (legsim_model_desc, the leg file as the planar model reads it)
// lifted onto a hip yoke that its rowing actuator turns about the box's vertical axis at the
// leg's hip. The box is a free body (body 0: the hexapod) or the fixed world (one leg on a test
// stand). Bodies: [the box,] then per leg its yoke and its bars in the leg file's order. The
// world: z up.
//
// A leg moves in its yoke's plane: planar x along the yoke's x (out from the hip axis), planar y
// along z (up), the planar angle's positive sense about -y_yoke; a bar's body frame is (u, n,
// k): its axis u and normal n of eq. (1) and the plane's normal k = u x n. A leg on the left of
// the box is the same leg with its hip turned by pi (a planar mechanism turned about an axis in
// its plane is its mirror image): no mirrored file.
//
// Rows (non-redundant: the tree set): per leg its yoke's revolute to the box (5), the joints of
// a spanning tree of the leg, taken in the file's order, as 3D joints (a revolute 5, a
// prismatic 5), a revolute that closes a loop by its 2 in-plane rows only (a prismatic joint
// that would close one is refused). The leg of models/leg.toml: 39 rows on 42 velocity
// coordinates; six of them on a free box: 234 rows on 258.
#pragma once

#include "legsim/hexapod.h"
#include "legsim/legsim.h"
#include "spatial/rows.hpp"

namespace legsim::spatial {

constexpr int kMaxLegs = 6;
constexpr int kMaxLegBars = LEGSIM_HEXAPOD_MAX_LEG_BARS;
constexpr int kMaxRobotBodies = 1 + kMaxLegs * (1 + kMaxLegBars);
constexpr int kMaxLegJoints = 10;
constexpr int kMaxRobotJoints = kMaxLegs * (1 + kMaxLegJoints);
constexpr int kMaxRobotRows = 5 * kMaxRobotJoints;
constexpr int kMaxRobotActuators = kMaxLegs * LEGSIM_MAX_ACTUATORS;
// The box's own contact points (where it touches the ground when the legs give way: the belly's
// skids; a block's feet), on the feet's contact law. Three on a rigid body hold it with
// independent normal rows; a fourth would make them redundant.
constexpr int kMaxBoxContacts = LEGSIM_HEXAPOD_MAX_BOX_CONTACTS;
// The contact points: the legs' feet (contact l: leg l), then the box's (contact nlegs + k).
constexpr int kMaxContacts = kMaxLegs + kMaxBoxContacts;

// The hip yoke. The paper gives no yoke or hip numbers: these defaults are ASSUMPTIONS (the
// spatial prototype's, firmware_core/tools/prototypes/spatial_leg.py).
struct YokeDesc {
  double mass_kg = 1.0;
  double com_m[3] = {0.03, 0.0, 0.0};  // from the hip axis point, yoke frame (x out, z up)
  double inertia_kgm2[3] = {0.004, 0.006, 0.005};  // principal, about the centre of mass
  double hip_offset_m = 0.08;  // the leg's planar origin, out along x from the axis
  double bar_radius_m = 0.025;  // a bar's inertia about its own axis: a tube's m r^2 / 2
  // the rowing motor: its torque at the yoke saturates; its angle's stroke; its angle servo
  double rowing_max_torque_nm = 30.0, rowing_stroke_rad[2] = {-0.6, 0.6};
  double rowing_kp_nm_per_rad = 2000.0, rowing_kd_nms_per_rad = 40.0;
};

// The box (body 0 when free): mass and principal inertia (box frame, about its centre).
struct BoxDesc {
  double mass_kg;
  double inertia_kgm2[3];
};

// A leg's place: its hip axis point on the box (box frame, from its centre; the world's origin
// for a fixed box) and its yoke's heading at rowing angle 0 (rad about the box's z).
struct HipDesc {
  double point_m[3];
  double yaw_rad;
};

enum class LegJointKind : uint8_t { Revolute, Cut, Prismatic };

// A joint's rows (rows.hpp): Revolute: a's axis ka at its point sa, on b's point sb, b's axes
// ub, nb across it; Cut: a's point sa on b's sb in the plane of ub, nb; Prismatic: b (the rod)
// along a's (the cylinder's) axis ka = u, the frames aligned (ub = n, nb = k of both). Body -1:
// the fixed world.
struct LegJoint {
  LegJointKind kind;
  int a, b;
  V3 sa, sb, ka, ub, nb;
  int row, nrows;
};

// A leg's rows: its joints' and its foot's three.
constexpr int kMaxLegRows = 5 * (1 + kMaxLegJoints) + 3;
constexpr int kMaxLegBodies = 1 + kMaxLegBars;

// A leg's rows as the constrained dynamics eliminates them (spatial/dynamics.cpp), for one count
// of its foot's held rows: its joints' but the hip's on a free box in RobotLeg::order, its
// foot's in their slot, its hip's last; the envelope of S_l's Cholesky factor (row i holds
// columns first[i] .. i, L(i, j) at off[i] + j; size in all); each leg body's rows (CSR:
// on[on0[b] ..], in increasing order: a row's local index times 4, plus 2 for an orientation
// row (its coefficients on v zero, rows.hpp's perpendicular), plus which of its two bodies).
// shape: 3 l + h of the first leg l (robot_lift's order) whose layout for this hold h (its index
// in RobotLeg::layout) is the same as this one but for the rows' numbers (its own leg's when
// none before is): legs of one shape are factored two at a time, one in each lane of a pair of
// reals.
struct LegLayout {
  int n, nh, size, shape;
  int row[kMaxLegRows];  // the system's row numbers
  int first[kMaxLegRows], off[kMaxLegRows];
  int8_t body[kMaxLegRows][2];  // a row's two bodies from the leg's yoke (-1: off the leg)
  int on0[kMaxLegBodies + 1];
  int16_t on[2 * kMaxLegRows];
};

struct RobotLeg {
  int yoke, nbars;  // the yoke's body; its bars follow it
  int first_actuator, nactuators;  // its linear actuators in SpatialRobot::act
  int row0, nrows;  // its joints' rows (its hip's first): contiguous in the robot's row order
  int joint0, njoints;  // its joints in SpatialRobot::joint (its hip's first)
  int row_twin;     // the leg whose rows robot_rows evaluates with its own, in lanes (-1: none)
  int foot_body;    // its foot's bar (a body of the robot), or -1: the leg file has no [foot]
  V3 foot_point;    // on it, body frame
  V3 hip;           // the hip axis point (box frame, from its centre; world if the box is fixed)
  real yaw;         // rad
  // The order its rows are eliminated in (spatial/dynamics.cpp), chosen at lift: its joints'
  // rows but the hip's on a free box (those go last), the foot's held rows before
  // order[foot_slot] (after the last when foot_slot == norder).
  int order[5 * (1 + kMaxLegJoints)];
  int norder, foot_slot;
  LegLayout layout[3];  // by its foot's held rows: none, the normal's (sliding), three (stuck)
};

// A linear actuator: its length (m) is (r_rod - r_cyl) . u_cyl + offset, the planar model's,
// and its axial force F acts by virtual work F dl (the planar model's applied force).
struct RobotActuator {
  int cyl, rod;
  real offset;  // (L_cyl + L_rod) / 2
  real stroke[2], max_force, kp, kd;  // m, N, N/m, N s/m: its file's; the servo's F = kp (l* - l) - kd l'
};
// Its length less the offset as a row (rows.hpp's along_axis form): its gradient is the row's
// coefficients (ja on the rod, jb on the cylinder).
inline Row actuator_row(const BodyState &rod, const BodyState &cyl) {
  return row_along_axis(rod, {0, 0, 0}, cyl, {0, 0, 0}, {1, 0, 0});
}

struct SpatialRobot {
  bool free_box;     // body 0 is the box (else the box is the fixed world)
  int nb, nj, m, nlegs, na;  // bodies, joints, rows, legs, linear actuators
  real mass[kMaxRobotBodies];
  V3 inertia[kMaxRobotBodies];  // principal, body frame (kg m^2)
  real inverse_mass[kMaxRobotBodies][kBodyDof];  // M^-1's diagonal on (v, omega)
  LegJoint joint[kMaxRobotJoints];
  int row_body[kMaxRobotRows][2];  // each row's two bodies (-1: the world), from its joint
  RobotLeg leg[kMaxLegs];
  RobotActuator act[kMaxRobotActuators];
  V3 gravity;    // world (m/s^2): the leg files' (0, g_y), along z
  V3 yoke_com;   // yoke frame, from the hip axis point
  real origin_x; // the leg's planar origin, yoke frame: out along x from the hip axis
  real rowing_max_torque, rowing_stroke[2], rowing_kp, rowing_kd;  // N m, rad, N m/rad, N m s/rad
  int nbox_contacts;
  V3 box_contact[kMaxBoxContacts];  // box frame, from its centre (m)
};

// The contact points: the feet, then the box's.
inline int robot_contacts(const SpatialRobot &robot) { return robot.nlegs + robot.nbox_contacts; }
// Contact c's body (-1: a leg without a foot) and its point on it (body frame, m).
inline int contact_body(const SpatialRobot &robot, int c) { return c < robot.nlegs ? robot.leg[c].foot_body : 0; }
inline const V3 &contact_point(const SpatialRobot &robot, int c) {
  return c < robot.nlegs ? robot.leg[c].foot_point : robot.box_contact[c - robot.nlegs];
}

// nlegs legs (legs[k] placed at hips[k]) on the box (nullptr: fixed). LEGSIM_ERR_MODEL for a
// slot joint, a prismatic joint closing a loop, or a gravity with a horizontal part or that
// differs between the legs; LEGSIM_ERR_CAPACITY past the capacities above.
legsim_status robot_lift(const legsim_model_desc *const *legs, const HipDesc *hips, int nlegs, const YokeDesc &yoke,
                         const BoxDesc *box, SpatialRobot &out);

// A robot of no legs: the free box alone (a block), falling at gravity_z (m/s^2, along z).
// LEGSIM_ERR_BAD_INPUT for a mass or inertia not positive and finite, a gravity not finite.
legsim_status robot_lift_block(const BoxDesc &box, real gravity_z, SpatialRobot &out);

// The box's contact points (box frame, from its centre, m): n of them, replacing any before.
// LEGSIM_ERR_CAPACITY for n past kMaxBoxContacts (or negative), LEGSIM_ERR_BAD_INPUT for a
// point not finite, LEGSIM_ERR_MODEL on a fixed box (the world's points touch nothing).
legsim_status robot_box_contacts(SpatialRobot &robot, const V3 *points, int n);

// The hexapod of its file (legsim/hexapod.h): its six legs, their hips and yokes, its box, its
// box's contact points; a file of no legs: the box alone (robot_lift_block) on its points.
legsim_status robot_lift_hexapod(const legsim_hexapod_desc &hexapod, SpatialRobot &out);

// Where leg l must be for its foot at foot_box (box frame, m; the world for a fixed box): its
// rowing angle psi (rad, within pi / 2 of its heading: the leg's plane through the hip axis and
// the foot, the foot on the yoke's x side when it can be) and the point its planar leg must put
// its [foot] at (m, in its file's frame: legsim_assemble_foot gives the lengths). The foot's
// place on its bar (its planar point) is where the lift put it: the planar leg's own.
void leg_plane_target(const SpatialRobot &robot, int l, const V3 &foot_box, real &psi, real *foot_xy);

// Leg l's foot point (world, m) at q; NaN for a leg without a foot. Contact c's point.
V3 robot_foot_position(const SpatialRobot &robot, int l, const real *q);
V3 robot_contact_position(const SpatialRobot &robot, int c, const real *q);

// The spatial state (q: 7 per body, v: 6 per body) of: the box at box_q (r, quaternion) moving
// at box_v (v world, omega box frame), ignored for a fixed box; per leg k its planar state
// (q_planar[k]: x, y, phi per bar; qd_planar[k] their rates) on its yoke at rowing angle psi[k]
// (rad) turning at psid[k] (rad/s).
void robot_state(const SpatialRobot &robot, const real *box_q, const real *box_v, const real *const *q_planar,
                 const real *const *qd_planar, const real *psi, const real *psid, real *q, real *v);

// Every row at (q, v): out[0 .. robot.m - 1]; row r of joint j acts on bodies joint[j].a, .b
// (its ja, jb).
void robot_rows(const SpatialRobot &robot, const real *q, const real *v, Row *out);

// Every row's phi at q (robot_rows' phi alone, the same values): phi[0 .. robot.m - 1].
void robot_phi(const SpatialRobot &robot, const real *q, real *phi);

// Leg l's rowing angle (rad, in [-pi, pi]) at q: its yoke's x in the box's frame, from its heading.
real robot_rowing_angle(const SpatialRobot &robot, int l, const real *q);

// Linear actuator a's length (m) at q.
real robot_actuator_length(const SpatialRobot &robot, int a, const real *q);
// Its rate (m/s) and leg l's rowing rate (rad/s) at (q, v).
real robot_actuator_rate(const SpatialRobot &robot, int a, const real *q, const real *v);
real robot_rowing_rate(const SpatialRobot &robot, int l, const real *q, const real *v);

// The applied forces Q (6 per body: force on v in the world, moment on omega in the body's
// frame) at (q, v): gravity, the gyroscopic moments -omega x (J omega), each linear actuator's
// axial force force_n[a] (N), and each leg's rowing torque rowing_nm[l] (N m, on its yoke about
// the hip axis, and its reaction on the box).
void robot_forces(const SpatialRobot &robot, const real *q, const real *v, const real *force_n,
                  const real *rowing_nm, real *Q);

}  // namespace legsim::spatial
