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
// A multiplier is a row's (rows.hpp): a body's constraint force is -J^T lambda. A foot on the
// ground has its rows along the ground's frame (normal, t1, t2): e_k . (p_foot - anchor), three
// when stuck, the normal's alone when sliding; the ground's force on it is -(lambda_n n +
// lambda_1 t1 + lambda_2 t2), its normal force N = -lambda_n.
//
// A stroke's stop (a linear actuator's length or a rowing angle at its end) held is one more
// row, its gap: L - L_min, L_max - L, sin(psi - psi_min) or sin(psi_max - psi) (>= 0 inside the
// stroke); it pushes while its multiplier is <= 0 (the force -lambda along the gap's gradient).
// The held stops are not in the legs' factors (a leg with its foot stuck has no freedom of its own
// left for one: its stop holds the box through the foot): the solve takes each as a column, its
// response to a unit multiplier, and their multipliers from a small system (the stops' Delassus
// matrix): the rows' solve with the stops' rows met.
#pragma once

#include "spatial/robot.hpp"

namespace legsim::spatial {

// The system's rows: the robot's joints' [0, robot.m), then three slots per contact point for
// its hold (robot.m + 3 c ..: the normal's, t1's, t2's; the feet, then the box's points), used as
// its mode says, then three per leg for its stops (robot.m + 3 kMaxContacts + 3 l + k: its
// actuators' k = 0, 1, its rowing angle's k = 2).
constexpr int kMaxSystemRows = kMaxRobotRows + 3 * kMaxContacts + 3 * kMaxLegs;
constexpr int kMaxRobotDof = kBodyDof * kMaxRobotBodies;

// Which contact points the ground holds (bit c: contact c, robot_contacts'; the feet first, bit l
// leg l's) and how: stuck (held at anchor[l], world, m) or
// sliding (held on the plane through anchor[l]); the ground's frame (world: unit normal, up, and
// two unit tangents, right-handed). Which strokes sit on a stop (bit 3 l + k: leg l's actuator k
// = 0, 1 or its rowing angle k = 2) and at which end (upper's bit: the max).
struct FeetHold {
  uint32_t stuck, sliding;
  V3 anchor[kMaxContacts];
  V3 normal = {0, 0, 1}, t1 = {1, 0, 0}, t2 = {0, 1, 0};
  uint32_t stops = 0, upper = 0;
};
// The number of rows contact c has in hold.
inline int foot_rows(const FeetHold &hold, int c) {
  return ((hold.stuck >> c) & 1u) ? 3 : ((hold.sliding >> c) & 1u) ? 1 : 0;
}
inline int foot_row(const SpatialRobot &robot, int c) { return robot.m + 3 * c; }
// The box's contact points held (their bits: those past the legs').
inline uint32_t box_held(const SpatialRobot &robot, const FeetHold &hold) {
  return (hold.stuck | hold.sliding) >> robot.nlegs;
}
constexpr int kLegStops = 3;
constexpr int kMaxHeldStops = kLegStops * kMaxLegs;
// The rows the factor takes as columns (dynamics.cpp): the held stops', the box's contacts'.
constexpr int kMaxColumns = kMaxHeldStops + 3 * kMaxBoxContacts;
inline int stop_row(const SpatialRobot &robot, int l, int k) { return robot.m + 3 * kMaxContacts + kLegStops * l + k; }
// The rows' extent for this robot: past its legs' stops no row is ever used (loops and copies of
// multipliers stop there, not at kMaxSystemRows).
inline int system_rows_extent(const SpatialRobot &robot) { return stop_row(robot, robot.nlegs, 0); }
// The legs' factors' rows (the joints', the feet's slots): the only multipliers solve_rows writes.
inline int leg_rows_extent(const SpatialRobot &robot) { return foot_row(robot, robot.nlegs); }
// Leg l's held stops (bit k).
inline uint32_t leg_stops(const FeetHold &hold, int l) { return (hold.stops >> (kLegStops * l)) & 7u; }

// System row r's two bodies (-1: the world): a joint's, a contact's (a foot's bar, the box), a
// stop's (an actuator's rod and cylinder; a rowing angle's yoke and box).
inline void row_bodies(const SpatialRobot &robot, int r, int &a, int &b) {
  if (r < robot.m) {
    a = robot.row_body[r][0], b = robot.row_body[r][1];
  } else if (r < robot.m + 3 * kMaxContacts) {
    a = contact_body(robot, (r - robot.m) / 3), b = -1;
  } else {
    const int s = r - robot.m - 3 * kMaxContacts, l = s / kLegStops, k = s % kLegStops;
    const RobotLeg &L = robot.leg[l];
    if (k < 2) {
      a = robot.act[L.first_actuator + k].rod, b = robot.act[L.first_actuator + k].cyl;
    } else {
      a = L.yoke, b = robot.free_box ? 0 : -1;
    }
  }
}

// System row r's rate at x (its coefficients on its two bodies' velocity coordinates): J_r x.
inline real row_dot(const SpatialRobot &robot, const Row &row, int r, const real *x) {
  int a, b;
  row_bodies(robot, r, a, b);
  real s = 0;
  for (int k = 0; k < kBodyDof; ++k) s += row.ja[k] * x[kBodyDof * a + k];
  if (b >= 0)
    for (int k = 0; k < kBodyDof; ++k) s += row.jb[k] * x[kBodyDof * b + k];
  return s;
}

// Leg l's LegLayout with nf rows of its foot held (robot_lift's, once per count).
void leg_layout(const SpatialRobot &robot, int l, int nf, LegLayout &out);
inline const LegLayout &leg_layout(const SpatialRobot &robot, const FeetHold &hold, int l) {
  const int nf = foot_rows(hold, l);
  return robot.leg[l].layout[nf == 3 ? 2 : nf];
}

// The indices of the rows in use with hold's feet (the joints', each foot's on the ground, each
// stop's held):
// their number; a sum over them reads no unused foot slot.
inline int system_used_rows(const SpatialRobot &robot, const FeetHold &hold, int *idx) {
  int n = 0;
  for (int r = 0; r < robot.m; ++r) idx[n++] = r;
  const int nc = robot_contacts(robot);
  for (int c = 0; c < nc; ++c)
    for (int k = 0; k < foot_rows(hold, c); ++k) idx[n++] = foot_row(robot, c) + k;
  if (hold.stops)
    for (int l = 0; l < robot.nlegs; ++l)
      for (int k = 0; k < kLegStops; ++k)
        if ((leg_stops(hold, l) >> k) & 1u) idx[n++] = stop_row(robot, l, k);
  return n;
}

// Every row of the system at (q, v): the joints' (robot_rows), the feet's on the ground, the
// stops' held.
void system_rows(const SpatialRobot &robot, const FeetHold &hold, const real *q, const real *v, Row *rows);
// Their phi alone at q (system_rows' phi, the same values; the unused slots not written): what
// a projection's residual needs, for a fifth of the rows' work.
void system_phi(const SpatialRobot &robot, const FeetHold &hold, const real *q, real *phi);
// Leg l's stop k's row at its lower or upper end (its gap, >= 0 inside the stroke).
Row stop_gap_row(const SpatialRobot &robot, int l, int k, bool upper, const real *q, const real *v);

// The factor of [M J^T; J 0] for the rows of system_rows at one q with the feet of `stuck`: per
// leg its rows in elimination order (RobotLeg::layout for its foot's hold), the Cholesky
// factor L_l of S_l = J_l M_l^-1 J_l^T, W_l = L_l^-1 B_l on its hip rows; the box's
// complement's factor. Built once, solved for several right-hand sides (the stages'
// accelerations, the projections, a sliding foot's friction columns).
struct RobotFactor {
  uint32_t stuck, sliding;
  const Row *rows;  // the rows it was built from (system_rows'), read by the solves
  const LegLayout *layout[kMaxLegs];  // each leg's rows and L_l's envelope (its foot's hold's)
  // L_l in its envelope: entry k of leg l at L[lbase[l] + lstride[l] k]; two legs of one shape
  // interleaved (stride 2, their pairs first and aligned), another alone (stride 1)
  alignas(2 * sizeof(real)) real L[kMaxLegs * kMaxLegRows * (kMaxLegRows + 1) / 2];
  int lbase[kMaxLegs], lstride[kMaxLegs];
  int npairs, pair[kMaxLegs / 2][2];  // the legs factored two at a time (stride 2: lanes 0, 1)
  // the layout L_l is stored in: its own, or for a free foot paired with a stuck one its stuck
  // layout with the foot's three rows (from pad[l], else -1) decoupled, unit pivots
  const LegLayout *flayout[kMaxLegs];
  int pad[kMaxLegs];
  real W[kMaxLegs][5 * kBodyDof];
  real A0[kBodyDof * kBodyDof];  // the box's complement M_0 + sum_l W_l^T W_l, factored
  // the rows taken as columns (the held stops', the box's contacts' held): their rows, their
  // responses to a unit multiplier (accelerations and the other rows' multipliers), their
  // Delassus matrix -J_s x_s factored (a row the others already imply, a zero pivot, is left
  // out of the factor: live 0). With rows left out the multipliers are the least-norm ones
  // (a rigid body's stuck points share the load: null, the null space's basis, nnull of them)
  int nstops;
  int stop[kMaxColumns];
  real stop_x[kMaxColumns][kMaxRobotDof], stop_mu[kMaxColumns][kMaxSystemRows];
  real D[kMaxColumns * kMaxColumns];
  bool live[kMaxColumns];
  int nnull;
  real null[kMaxColumns][kMaxColumns], null_gram[kMaxColumns * kMaxColumns];
};

// Factor the system for rows (kept by pointer: they must outlive the solves). LEGSIM_ERR_SINGULAR
// when a leg's rows or the box's complement are dependent (a leg at a dead centre, a stuck
// foot's rows dependent on its leg's); the factor is then unusable.
legsim_status robot_factor(const SpatialRobot &robot, const FeetHold &hold, const Row *rows, RobotFactor &F);

// [M J^T; J 0] [x; mu] = [f; g] with F's factor: f one force per velocity coordinate (6 per
// body), g one value per system row (the unused foot and stop slots ignored); x, mu out.
void robot_solve(const SpatialRobot &robot, const RobotFactor &F, const real *f, const real *g, real *x, real *mu);

// The accelerations a (6 per body: v' world, omega' body frame) and multipliers mu (per system
// row) at (q, v) under the applied forces Q (robot_forces'), the feet's rows held as hold says
// (a sliding foot's friction is not here: it is a force, spatial/contact's); rows and F: work
// space (the rows at (q, v) and their factor on return).
legsim_status robot_accelerations(const SpatialRobot &robot, const FeetHold &hold, const real *q, const real *v,
                                  const real *Q, real *a, real *mu, Row *rows, RobotFactor &F);

// The ground's force on contact c (N, world) from the multipliers: 0 for a free one, the normal
// force alone for a sliding one (its friction is an applied force).
inline V3 foot_force(const SpatialRobot &robot, const FeetHold &hold, const real *mu, int c) {
  const real *m = mu + foot_row(robot, c);
  const int n = foot_rows(hold, c);
  const V3 f = n == 0 ? V3{0, 0, 0} : -m[0] * hold.normal;
  return n == 3 ? f - m[1] * hold.t1 - m[2] * hold.t2 : f;
}

}  // namespace legsim::spatial
