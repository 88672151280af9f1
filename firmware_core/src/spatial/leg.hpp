// One leg in space (docs/design/spatial.md, formulation (a), the tree rows): the planar leg's
// own description (legsim_model_desc, the leg file as the planar model reads it) lifted onto a
// hip yoke that the rowing actuator turns about the box's vertical axis. Bodies: 0 the yoke,
// 1 .. n the leg's bars in its file's order; the box is fixed here (the origin, z up: the hip
// axis). The leg moves in the yoke's plane: planar x along the yoke's x (out from the axis),
// planar y along z (up), the planar angle's positive sense about -y_yoke; a bar's body frame is
// (u, n, k): its axis u and normal n of eq. (1) and the plane's normal k = u x n.
//
// Rows (non-redundant: the tree set): the yoke's revolute to the box (5); the joints of a
// spanning tree of the leg, taken in the file's order, as 3D joints (a revolute 5, a
// prismatic 5); a revolute that closes a loop by its 2 in-plane rows only. A prismatic joint
// that would close a loop is refused. The leg of models/leg.toml: 39 rows on 42 velocity
// coordinates, 3 degrees of freedom (the rowing angle and the leg's two).
#pragma once

#include "legsim/legsim.h"
#include "spatial/rows.hpp"

namespace legsim::spatial {

constexpr int kMaxLegBodies = 1 + LEGSIM_MAX_BODIES;  // the yoke and the bars
constexpr int kMaxLegJoints = 1 + LEGSIM_MAX_JOINTS;
constexpr int kMaxLegRows = 5 * kMaxLegJoints;

// The hip yoke. The paper gives no yoke or hip numbers: these defaults are ASSUMPTIONS (the
// spatial prototype's, firmware_core/tools/prototypes/spatial_leg.py).
struct YokeDesc {
  double mass_kg = 1.0;
  double com_m[3] = {0.03, 0.0, 0.0};  // from the hip axis point, yoke frame (x out, z up)
  double inertia_kgm2[3] = {0.004, 0.006, 0.005};  // principal, about the centre of mass
  double hip_offset_m = 0.08;  // the leg's planar origin, out along x from the axis
  double bar_radius_m = 0.025;  // a bar's inertia about its own axis: a tube's m r^2 / 2
};

enum class LegJointKind : uint8_t { Revolute, Cut, Prismatic };

// A joint's rows (rows.hpp): Revolute: a's axis ka at its point sa, on b's point sb, b's axes
// ub, nb across it; Cut: a's point sa on b's sb in the plane of ub, nb; Prismatic: b (the rod)
// along a's (the cylinder's) axis ka = u, the frames aligned (ub = n, nb = k of both). Body -1:
// the box.
struct LegJoint {
  LegJointKind kind;
  int a, b;
  V3 sa, sb, ka, ub, nb;
  int row, nrows;
};

struct SpatialLeg {
  int nb, nj, m;  // bodies, joints, rows
  real mass[kMaxLegBodies];
  V3 inertia[kMaxLegBodies];  // principal, body frame (kg m^2)
  LegJoint joint[kMaxLegJoints];
  V3 gravity;            // world (m/s^2): the leg file's (0, g_y), along z
  V3 origin;             // the leg's planar origin in the yoke's plane, yoke frame from the axis
  V3 yoke_com;           // yoke frame, from the axis point
};

// The leg of desc on yoke: LEGSIM_ERR_MODEL for a slot joint, a prismatic joint closing a
// loop, or a gravity with a horizontal part; LEGSIM_ERR_CAPACITY past the capacities above.
legsim_status leg_lift(const legsim_model_desc &desc, const YokeDesc &yoke, SpatialLeg &out);

// The spatial state (q: 7 per body, v: 6 per body) of the planar leg's (q_planar: x, y, phi per
// bar; qd_planar their rates) on the yoke at angle psi (rad) turning at psid (rad/s).
void leg_state(const SpatialLeg &leg, const real *q_planar, const real *qd_planar, real psi, real psid, real *q,
               real *v);

// Every row at (q, v): out[0 .. leg.m - 1]; row r of joint j acts on bodies joint[j].a, .b
// (ja, jb).
void leg_rows(const SpatialLeg &leg, const real *q, const real *v, Row *out);

}  // namespace legsim::spatial
