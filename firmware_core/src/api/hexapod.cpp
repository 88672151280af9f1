// The C API, the hexapod (legsim/hexapod.h): standing at a pose, on the spatial module
// (spatial/robot, spatial/statics) with each leg assembled by the planar core; the tripod gait's
// set-points on the description's ground (spatial/gait).
#include <cmath>
#include <new>

#include "api/internal.hpp"
#include "legsim/hexapod.h"
#include "spatial/gait.hpp"
#include "spatial/motion.hpp"
#include "spatial/statics.hpp"

using namespace legsim;

namespace {
using spatial::kBodyConfig;
using spatial::kBodyDof;
using spatial::kMaxRobotBodies;

// The storage's parts, each aligned: the planar leg's sim, then the spatial robot's.
struct HexapodWork {
  spatial::SpatialRobot robot;
  spatial::RobotStatics statics;
  real q[kBodyConfig * kMaxRobotBodies], v[kBodyDof * kMaxRobotBodies];
  real leg_q[LEGSIM_HEXAPOD_LEGS][3 * LEGSIM_MAX_BODIES];
};
constexpr size_t round_up(size_t n) { return (n + LEGSIM_STORAGE_ALIGN - 1) / LEGSIM_STORAGE_ALIGN * LEGSIM_STORAGE_ALIGN; }
size_t sim_bytes() { return round_up(legsim_sim_size()); }

bool finite_within(const double *x, int n, double bound) {
  for (int i = 0; i < n; ++i)
    if (!(std::abs(x[i]) <= bound)) return false;
  return true;
}

bool within(double x, double lo, double hi) { return x >= lo && x <= hi; }  // false for NaN
constexpr double pi = 3.14159265358979323846;

// The description's numbers in the ranges legsim/hexapod.h states (the loader's, checked again
// here: a caller may build or change a description), each leg by legsim_model_check.
legsim_status desc_check(const legsim_hexapod_desc &h) {
  if (h.n_legs != LEGSIM_HEXAPOD_LEGS && h.n_legs != 0) return LEGSIM_ERR_BAD_INPUT;
  const bool legs = h.n_legs != 0;
  if (h.gravity_mps2[0] != 0 || h.gravity_mps2[1] != 0 ||
      !within(h.gravity_mps2[2], -LEGSIM_MAX_GRAVITY_MPS2, LEGSIM_MAX_GRAVITY_MPS2))
    return LEGSIM_ERR_BAD_INPUT;
  if (!within(h.box_mass_kg, LEGSIM_MIN_MASS_KG, LEGSIM_MAX_MASS_KG)) return LEGSIM_ERR_BAD_INPUT;
  for (int i = 0; i < 3; ++i) {
    if (!within(h.box_inertia_kgm2[i], LEGSIM_MIN_INERTIA_KGM2, LEGSIM_MAX_INERTIA_KGM2) ||
        !within(h.box_size_m[i], LEGSIM_MIN_LENGTH_M, LEGSIM_MAX_COORD) ||
        !within(h.ground_point_m[i], -LEGSIM_MAX_COORD, LEGSIM_MAX_COORD))
      return LEGSIM_ERR_BAD_INPUT;
    if (legs && (!within(h.yoke_inertia_kgm2[i], LEGSIM_MIN_INERTIA_KGM2, LEGSIM_MAX_INERTIA_KGM2) ||
                 !within(h.yoke_com_m[i], -LEGSIM_MAX_COORD, LEGSIM_MAX_COORD)))
      return LEGSIM_ERR_BAD_INPUT;
  }
  if (legs && (!within(h.yoke_mass_kg, LEGSIM_MIN_MASS_KG, LEGSIM_MAX_MASS_KG) ||
               !within(h.hip_offset_m, LEGSIM_MIN_LENGTH_M, LEGSIM_MAX_COORD) ||
      !within(h.bar_radius_m, LEGSIM_MIN_LENGTH_M, LEGSIM_MAX_COORD) || !within(h.rowing_gear_ratio, 1, 1e4) ||
      !within(h.rowing_max_torque_nm, LEGSIM_MIN_FORCE_N, LEGSIM_MAX_FORCE_N) ||
      !(h.rowing_stroke_rad[0] > -pi && h.rowing_stroke_rad[0] < 0 && h.rowing_stroke_rad[1] > 0 &&
        h.rowing_stroke_rad[1] < pi) ||
      !within(h.rowing_servo_kp_nm_per_rad, 0, LEGSIM_MAX_STIFFNESS_N_PER_M) ||
      !within(h.rowing_servo_kd_nms_per_rad, 0, LEGSIM_MAX_DAMPING_NS_PER_M)))
    return LEGSIM_ERR_BAD_INPUT;
  const double *n = h.ground_normal;
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (!(std::abs(len - 1) <= 1e-9) || !(n[2] >= std::cos(LEGSIM_MAX_SLOPE_RAD))) return LEGSIM_ERR_BAD_INPUT;
  if (!within(h.mu_kinetic, 0, LEGSIM_MAX_FRICTION) || !within(h.mu_static, h.mu_kinetic, LEGSIM_MAX_FRICTION))
    return LEGSIM_ERR_BAD_INPUT;
  if (h.n_box_contacts < 0 || h.n_box_contacts > LEGSIM_HEXAPOD_MAX_BOX_CONTACTS) return LEGSIM_ERR_CAPACITY;
  for (int k = 0; k < h.n_box_contacts; ++k)
    for (int i = 0; i < 3; ++i)
      if (!(std::abs(h.box_contact_m[k][i]) <= 0.5 * h.box_size_m[i])) return LEGSIM_ERR_BAD_INPUT;
  for (int l = 0; l < h.n_legs; ++l) {
    const legsim_hexapod_leg_desc &L = h.leg[l];
    for (int i = 0; i < 3; ++i)
      if (!within(L.hip_m[i], -LEGSIM_MAX_COORD, LEGSIM_MAX_COORD)) return LEGSIM_ERR_BAD_INPUT;
    if (!within(L.heading_rad, -pi, pi)) return LEGSIM_ERR_BAD_INPUT;
    if (legsim_model_check(&L.leg, nullptr, 0) != LEGSIM_OK) return LEGSIM_ERR_BAD_INPUT;
    if (L.leg.gravity_mps2[0] != 0 || L.leg.gravity_mps2[1] != h.gravity_mps2[2]) return LEGSIM_ERR_BAD_INPUT;
  }
  return LEGSIM_OK;
}

// The storage checked and its work part built, the robot lifted from h (a file of no legs, a
// block, only where block_ok: the analyses of legs refuse it).
legsim_status work_begin(const legsim_hexapod_desc &h, void *storage, size_t bytes, HexapodWork *&w,
                         bool block_ok = false) {
  if (bytes < legsim_hexapod_storage_size() || reinterpret_cast<uintptr_t>(storage) % LEGSIM_STORAGE_ALIGN)
    return LEGSIM_ERR_STORAGE;
  const legsim_status st = desc_check(h);
  if (st != LEGSIM_OK) return st;
  if (h.n_legs == 0 && !block_ok) return LEGSIM_ERR_BAD_INPUT;
  w = new (static_cast<unsigned char *>(storage) + sim_bytes()) HexapodWork;
  return spatial::robot_lift_hexapod(h, w->robot);
}

// Leg l's planar sim at its file's stand, in the storage's first part.
legsim_status leg_at_stand(const legsim_hexapod_desc &h, int l, void *storage, legsim_sim *&sim) {
  const legsim_options opt = legsim_default_options();
  legsim_status st = legsim_init(storage, sim_bytes(), &h.leg[l].leg, &opt, &sim);
  return st == LEGSIM_OK ? legsim_assemble_pose(sim, 0) : st;
}

// The robot's state at rest: the box at box_q, each leg at w.leg_q turned by psi.
void place_at_rest(HexapodWork &w, const real *box_q, const real *psi) {
  static const real rest[3 * LEGSIM_MAX_BODIES] = {};
  const real box_v[6] = {0, 0, 0, 0, 0, 0};
  const real *qs[LEGSIM_HEXAPOD_LEGS], *vs[LEGSIM_HEXAPOD_LEGS];
  const real psid[LEGSIM_HEXAPOD_LEGS] = {};
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l) qs[l] = w.leg_q[l], vs[l] = rest;
  spatial::robot_state(w.robot, box_q, box_v, qs, vs, psi, psid, w.q, w.v);
}

// The robot at pose, at rest (the pose's ranges checked, each leg assembled at its lengths from
// its file's stand), in w.q, w.v.
legsim_status place_pose(const legsim_hexapod_desc &h, const legsim_hexapod_pose &pose, void *storage, size_t bytes,
                         HexapodWork *&wp, bool block_ok = false) {
  const double qn = std::sqrt(pose.box_quat[0] * pose.box_quat[0] + pose.box_quat[1] * pose.box_quat[1] +
                              pose.box_quat[2] * pose.box_quat[2] + pose.box_quat[3] * pose.box_quat[3]);
  if (!finite_within(pose.box_m, 3, LEGSIM_MAX_COORD) || !(std::abs(qn - 1) <= 1e-6)) return LEGSIM_ERR_BAD_INPUT;
  for (int l = 0; l < h.n_legs; ++l) {
    const double psi = pose.rowing_rad[l];
    if (!(psi >= h.rowing_stroke_rad[0] && psi <= h.rowing_stroke_rad[1])) return LEGSIM_ERR_BAD_INPUT;
    if (!finite_within(pose.length_m[l], 2, LEGSIM_MAX_COORD)) return LEGSIM_ERR_BAD_INPUT;
  }
  legsim_status st = work_begin(h, storage, bytes, wp, block_ok);
  if (st != LEGSIM_OK) return st;
  HexapodWork &w = *wp;
  for (int l = 0; l < h.n_legs; ++l) {
    legsim_sim *sim = nullptr;
    st = leg_at_stand(h, l, storage, sim);
    legsim_real len[2] = {legsim_real(pose.length_m[l][0]), legsim_real(pose.length_m[l][1])};
    if (st == LEGSIM_OK) st = legsim_assemble(sim, len);
    if (st == LEGSIM_OK) st = legsim_get_q(sim, w.leg_q[l]);
    if (st != LEGSIM_OK) return st;
  }
  const real box_q[7] = {real(pose.box_m[0]), real(pose.box_m[1]), real(pose.box_m[2]), real(pose.box_quat[0] / qn),
                         real(pose.box_quat[1] / qn), real(pose.box_quat[2] / qn), real(pose.box_quat[3] / qn)};
  real psi[LEGSIM_HEXAPOD_LEGS];
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l) psi[l] = real(pose.rowing_rad[l]);
  place_at_rest(w, box_q, psi);
  return LEGSIM_OK;
}
}  // namespace

// A hexapod in motion: the model (the lifted robot) and its data.
struct legsim_hexapod_sim {
  uint32_t magic;
  spatial::SpatialRobot robot;
  spatial::RobotData data;
  spatial::Integrator integrator;
};

namespace {
constexpr uint32_t kHexapodMagic = 0x48455841u;  // "HEXA"

// New commands from the next step on: the accelerations under them now (all or nothing).
legsim_status command_apply(legsim_hexapod_sim &sim, const spatial::RobotCommands &c) {
  spatial::RobotData &d = sim.data;
  const spatial::RobotCommands before = d.command;
  d.command = c;
  const legsim_status st = spatial::robot_data_refresh(sim.robot, d);
  if (st != LEGSIM_OK) d.command = before;  // refresh writes nothing unless it succeeds
  return st;
}
size_t hexapod_sim_offset() { return sim_bytes() + round_up(sizeof(HexapodWork)); }

// Leg l's rowing angle and lengths that put its foot at foot (box frame): its planar sim (the
// storage's first part) assembled there from its file's stand.
legsim_status reach(const legsim_hexapod_desc &h, const spatial::SpatialRobot &robot, int l, const spatial::V3 &foot,
                    void *storage, real &psi, legsim_real len[2]) {
  real xy[2];
  spatial::leg_plane_target(robot, l, foot, psi, xy);
  if (!(psi >= h.rowing_stroke_rad[0] && psi <= h.rowing_stroke_rad[1])) return LEGSIM_ERR_OUT_OF_STROKE;
  legsim_sim *sim = nullptr;
  legsim_status st = leg_at_stand(h, l, storage, sim);
  if (st == LEGSIM_OK) st = legsim_assemble_foot(sim, xy);
  if (st == LEGSIM_OK) st = legsim_actuator_lengths(sim, len, nullptr);
  return st;
}

legsim_status sweep_check(const legsim_hexapod_sweep &s) {
  int stance = 0;
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l) stance += (s.stance_mask >> l) & 1u;
  const bool ok = s.leg >= 0 && s.leg < LEGSIM_HEXAPOD_LEGS && !(s.stance_mask >> LEGSIM_HEXAPOD_LEGS) &&
                  ((s.stance_mask >> s.leg) & 1u) && stance >= 3 && within(s.box_height_m, 0, LEGSIM_MAX_COORD) &&
                  s.box_height_m > 0 && within(s.distance_m[0], LEGSIM_MIN_LENGTH_M, LEGSIM_MAX_COORD) &&
                  within(s.distance_m[1], LEGSIM_MIN_LENGTH_M, LEGSIM_MAX_COORD) &&
                  within(s.heading_rad[0], -pi, pi) && within(s.heading_rad[1], -pi, pi) &&
                  s.n_distance >= 1 && s.n_heading >= 1 && int64_t(s.n_distance) * s.n_heading <= 1000000;
  return ok ? LEGSIM_OK : LEGSIM_ERR_BAD_INPUT;
}

// The grid's value k of n from v[0] to v[1] (one point: v[0]).
double grid_at(const double v[2], int k, int n) { return n == 1 ? v[0] : v[0] + (v[1] - v[0]) * k / (n - 1); }
}  // namespace

extern "C" {

size_t legsim_hexapod_storage_size(void) { return sim_bytes() + round_up(sizeof(HexapodWork)); }

legsim_status legsim_hexapod_statics(const legsim_hexapod_desc *h, const legsim_hexapod_pose *pose,
                                     uint32_t stance_mask, const double *box_force_n, void *storage,
                                     size_t storage_bytes, legsim_hexapod_standing *out) {
  if (!h || !pose || !storage || !out) return LEGSIM_ERR_NULL;
  if (stance_mask >> LEGSIM_HEXAPOD_LEGS) return LEGSIM_ERR_BAD_INPUT;
  if (box_force_n && !finite_within(box_force_n, 3, LEGSIM_MAX_FORCE_N)) return LEGSIM_ERR_BAD_INPUT;
  HexapodWork *wp = nullptr;
  legsim_status st = place_pose(*h, *pose, storage, storage_bytes, wp);
  if (st != LEGSIM_OK) return st;
  HexapodWork &w = *wp;
  real load[3] = {0, 0, 0};
  if (box_force_n) load[0] = real(box_force_n[0]), load[1] = real(box_force_n[1]), load[2] = real(box_force_n[2]);
  st = spatial::robot_statics(w.robot, w.q, stance_mask, load, w.statics);
  if (st != LEGSIM_OK) return st;
  // the results (the centre of mass, the feet and the margin of the stance about it)
  legsim_hexapod_standing r;
  double M = 0, c[3] = {0, 0, 0};
  for (int b = 0; b < w.robot.nb; ++b) {
    M += w.robot.mass[b];
    for (int i = 0; i < 3; ++i) c[i] += w.robot.mass[b] * w.q[kBodyConfig * b + i];
  }
  for (int i = 0; i < 3; ++i) r.com_m[i] = c[i] / M;
  spatial::V3 stance_feet[LEGSIM_HEXAPOD_LEGS];
  int n = 0;
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l) {
    const spatial::V3 f = spatial::robot_foot_position(w.robot, l, w.q);
    const spatial::V3 &F = w.statics.foot_force[l];
    r.foot_m[l][0] = f.x, r.foot_m[l][1] = f.y, r.foot_m[l][2] = f.z;
    r.foot_force_n[l][0] = F.x, r.foot_force_n[l][1] = F.y, r.foot_force_n[l][2] = F.z;
    for (int a = 0; a < 2; ++a) r.actuator_force_n[l][a] = w.statics.actuator_force[w.robot.leg[l].first_actuator + a];
    r.rowing_torque_nm[l] = w.statics.rowing_torque[l];
    if ((stance_mask >> l) & 1u) stance_feet[n++] = f;
  }
  r.margin_m = spatial::support_margin(stance_feet, n, real(r.com_m[0]), real(r.com_m[1]));
  *out = r;
  return LEGSIM_OK;
}

legsim_status legsim_hexapod_gait_setpoints(const legsim_hexapod_desc *h, const legsim_hexapod_gait *gait, double t_s,
                                            void *storage, size_t storage_bytes, legsim_hexapod_setpoint *out) {
  if (!h || !gait || !storage || !out) return LEGSIM_ERR_NULL;
  if (!std::isfinite(t_s) || !(std::abs(t_s) <= LEGSIM_MAX_TIME_S) ||
      !(gait->box_height_m > 0 && gait->box_height_m <= LEGSIM_MAX_COORD))
    return LEGSIM_ERR_BAD_INPUT;
  HexapodWork *wp = nullptr;
  legsim_status st = work_begin(*h, storage, storage_bytes, wp);
  if (st != LEGSIM_OK) return st;
  HexapodWork &w = *wp;
  // the neutral points: the stand's feet (rowing 0, the box level at the origin), on the ground
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l) {
    legsim_sim *sim = nullptr;
    st = leg_at_stand(*h, l, storage, sim);
    if (st == LEGSIM_OK) st = legsim_get_q(sim, w.leg_q[l]);
    if (st != LEGSIM_OK) return st;
  }
  const real box_q[7] = {0, 0, 0, 1, 0, 0, 0}, psi[LEGSIM_HEXAPOD_LEGS] = {};
  place_at_rest(w, box_q, psi);
  spatial::TripodGait g;
  g.period_s = real(gait->period_s), g.duty = real(gait->duty), g.step_length_m = real(gait->step_length_m);
  g.step_height_m = real(gait->step_height_m), g.turn_rad = real(gait->turn_rad);
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l) {
    const spatial::V3 f = spatial::robot_foot_position(w.robot, l, w.q);
    g.neutral[l] = {f.x, f.y, -real(gait->box_height_m)};
  }
  // the ground's grade along the world's x and y: the box's frame at t = 0
  const double *n = h->ground_normal, *p0 = h->ground_point_m;
  g.grade[0] = real(-n[0] / n[2]), g.grade[1] = real(-n[1] / n[2]);
  if (spatial::gait_check(g) != LEGSIM_OK) return LEGSIM_ERR_BAD_INPUT;
  spatial::V3 feet[LEGSIM_HEXAPOD_LEGS];
  bool stance[LEGSIM_HEXAPOD_LEGS];
  spatial::gait_feet(g, t_s, feet, stance);
  legsim_hexapod_setpoint r;
  // the box's planned pose: from over the world's origin, box_height_m above the ground there
  spatial::V3 d;
  real yaw;
  spatial::gait_box(g, t_s, d, yaw);
  const double z0 = p0[2] + (n[0] * p0[0] + n[1] * p0[1]) / n[2];
  r.box_m[0] = d.x, r.box_m[1] = d.y, r.box_m[2] = z0 + gait->box_height_m + d.z;
  r.box_quat[0] = std::cos(yaw / 2), r.box_quat[1] = 0, r.box_quat[2] = 0, r.box_quat[3] = std::sin(yaw / 2);
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l) {
    real angle;
    legsim_real len[2] = {0, 0};
    st = reach(*h, w.robot, l, feet[l], storage, angle, len);
    if (st != LEGSIM_OK) return st;
    r.foot_box_m[l][0] = feet[l].x, r.foot_box_m[l][1] = feet[l].y, r.foot_box_m[l][2] = feet[l].z;
    r.stance[l] = stance[l] ? 1 : 0;
    r.rowing_rad[l] = angle;
    r.length_m[l][0] = len[0], r.length_m[l][1] = len[1];
  }
  *out = r;
  return LEGSIM_OK;
}

legsim_status legsim_hexapod_leg_reach(const legsim_hexapod_desc *h, int32_t leg, const double foot_box_m[3],
                                       void *storage, size_t storage_bytes, double *rowing_rad, double length_m[2]) {
  if (!h || !foot_box_m || !storage || !rowing_rad || !length_m) return LEGSIM_ERR_NULL;
  if (leg < 0 || leg >= LEGSIM_HEXAPOD_LEGS || !finite_within(foot_box_m, 3, LEGSIM_MAX_COORD))
    return LEGSIM_ERR_BAD_INPUT;
  HexapodWork *wp = nullptr;
  legsim_status st = work_begin(*h, storage, storage_bytes, wp);
  if (st != LEGSIM_OK) return st;
  real psi;
  legsim_real len[2];
  st = reach(*h, wp->robot, leg, {real(foot_box_m[0]), real(foot_box_m[1]), real(foot_box_m[2])}, storage, psi, len);
  if (st != LEGSIM_OK) return st;
  *rowing_rad = psi, length_m[0] = len[0], length_m[1] = len[1];
  return LEGSIM_OK;
}

legsim_status legsim_hexapod_reaction_sweep(const legsim_hexapod_desc *h, const legsim_hexapod_sweep *sweep,
                                            int32_t first, int32_t count, void *storage, size_t storage_bytes,
                                            legsim_hexapod_sweep_point *out) {
  if (!h || !sweep || !storage || !out) return LEGSIM_ERR_NULL;
  const legsim_hexapod_sweep &s = *sweep;
  if (sweep_check(s) != LEGSIM_OK || first < 0 || count < 1 ||
      int64_t(first) + count > int64_t(s.n_distance) * s.n_heading)
    return LEGSIM_ERR_BAD_INPUT;
  HexapodWork *wp = nullptr;
  legsim_status st = work_begin(*h, storage, storage_bytes, wp);
  if (st != LEGSIM_OK) return st;
  // the stand (rowing 0, the box level at the origin): the free legs' lengths, the stance feet's places
  legsim_hexapod_pose stand;
  spatial::V3 stand_foot[LEGSIM_HEXAPOD_LEGS], hip[LEGSIM_HEXAPOD_LEGS];
  real yaw[LEGSIM_HEXAPOD_LEGS];
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l) {
    legsim_sim *sim = nullptr;
    legsim_real len[2] = {0, 0};
    st = leg_at_stand(*h, l, storage, sim);
    if (st == LEGSIM_OK) st = legsim_get_q(sim, wp->leg_q[l]);
    if (st == LEGSIM_OK) st = legsim_actuator_lengths(sim, len, nullptr);
    if (st != LEGSIM_OK) return st;
    stand.length_m[l][0] = len[0], stand.length_m[l][1] = len[1], stand.rowing_rad[l] = 0;
  }
  const real origin[7] = {0, 0, 0, 1, 0, 0, 0}, zero[LEGSIM_HEXAPOD_LEGS] = {};
  place_at_rest(*wp, origin, zero);
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l)
    stand_foot[l] = spatial::robot_foot_position(wp->robot, l, wp->q), hip[l] = wp->robot.leg[l].hip,
    yaw[l] = wp->robot.leg[l].yaw;
  const real H = real(s.box_height_m);
  for (int k = 0; k < count; ++k) {
    legsim_hexapod_sweep_point &p = out[k];
    const int i = first + k, id = i / s.n_heading, ia = i % s.n_heading;
    p = legsim_hexapod_sweep_point{};
    p.index = i;
    p.distance_m = grid_at(s.distance_m, id, s.n_distance), p.heading_rad = grid_at(s.heading_rad, ia, s.n_heading);
    legsim_hexapod_pose pose = stand;
    pose.box_m[0] = 0, pose.box_m[1] = 0, pose.box_m[2] = H;
    pose.box_quat[0] = 1, pose.box_quat[1] = 0, pose.box_quat[2] = 0, pose.box_quat[3] = 0;
    legsim_status ps = LEGSIM_OK;
    for (int l = 0; l < LEGSIM_HEXAPOD_LEGS && ps == LEGSIM_OK; ++l) {
      if (!((s.stance_mask >> l) & 1u)) continue;
      const real d = real(p.distance_m), a = yaw[l] + real(p.heading_rad);
      const spatial::V3 foot = l == s.leg ? spatial::V3{hip[l].x + d * std::cos(a), hip[l].y + d * std::sin(a), -H}
                                          : spatial::V3{stand_foot[l].x, stand_foot[l].y, -H};
      real psi = 0;
      legsim_real len[2] = {0, 0};
      ps = reach(*h, wp->robot, l, foot, storage, psi, len);
      pose.rowing_rad[l] = psi, pose.length_m[l][0] = len[0], pose.length_m[l][1] = len[1];
    }
    if (ps == LEGSIM_OK)
      ps = legsim_hexapod_statics(h, &pose, s.stance_mask, nullptr, storage, storage_bytes, &p.standing);
    p.status = ps;
    if (ps == LEGSIM_OK) {
      p.rowing_rad = pose.rowing_rad[s.leg];
      p.length_m[0] = pose.length_m[s.leg][0], p.length_m[1] = pose.length_m[s.leg][1];
    }
    // statics rebuilt the work part in place: the same robot lifted from the same h
  }
  return LEGSIM_OK;
}

legsim_status legsim_hexapod_support_margin(const double foot_m[][3], int32_t n, const double com_m[3],
                                            double *margin_m) {
  if (!foot_m || !com_m || !margin_m) return LEGSIM_ERR_NULL;
  if (n < 0 || n > LEGSIM_HEXAPOD_LEGS || !finite_within(com_m, 3, LEGSIM_MAX_COORD)) return LEGSIM_ERR_BAD_INPUT;
  spatial::V3 feet[LEGSIM_HEXAPOD_LEGS];
  for (int k = 0; k < n; ++k) {
    if (!finite_within(foot_m[k], 3, LEGSIM_MAX_COORD)) return LEGSIM_ERR_BAD_INPUT;
    feet[k] = {real(foot_m[k][0]), real(foot_m[k][1]), real(foot_m[k][2])};
  }
  *margin_m = spatial::support_margin(feet, n, real(com_m[0]), real(com_m[1]));
  return LEGSIM_OK;
}

size_t legsim_hexapod_sim_size(void) { return hexapod_sim_offset() + round_up(sizeof(legsim_hexapod_sim)); }

legsim_status legsim_hexapod_sim_init(void *storage, size_t storage_bytes, const legsim_hexapod_desc *h,
                                      const legsim_hexapod_pose *pose, uint32_t stuck_mask,
                                      legsim_hexapod_sim **out) {
  if (!h || !pose || !storage || !out) return LEGSIM_ERR_NULL;
  if (storage_bytes < legsim_hexapod_sim_size()) return LEGSIM_ERR_STORAGE;
  if (h->n_box_contacts < 0 || h->n_box_contacts > LEGSIM_HEXAPOD_MAX_BOX_CONTACTS) return LEGSIM_ERR_CAPACITY;
  if (stuck_mask >> (LEGSIM_HEXAPOD_LEGS + h->n_box_contacts)) return LEGSIM_ERR_BAD_INPUT;
  HexapodWork *wp = nullptr;
  legsim_status st = place_pose(*h, *pose, storage, storage_bytes, wp, true);
  if (st != LEGSIM_OK) return st;
  HexapodWork &w = *wp;
  auto *sim = new (static_cast<unsigned char *>(storage) + hexapod_sim_offset()) legsim_hexapod_sim;
  sim->magic = 0;
  sim->robot = w.robot;
  sim->integrator = spatial::Integrator::Rk4;
  // the mask's feet (bits 0 .. 5) and box points (bit 6 + k) as the robot's contact points (a
  // block's first are its box's)
  const uint32_t feet = stuck_mask & ((1u << LEGSIM_HEXAPOD_LEGS) - 1), box = stuck_mask >> LEGSIM_HEXAPOD_LEGS;
  if (w.robot.nlegs == 0 && feet) return LEGSIM_ERR_BAD_INPUT;
  spatial::FeetHold hold;
  hold.stuck = feet | box << w.robot.nlegs;
  hold.sliding = 0;
  for (int c = 0; c < spatial::robot_contacts(w.robot); ++c) hold.anchor[c] = spatial::robot_contact_position(w.robot, c, w.q);
  const spatial::GroundPlane ground = {
      {real(h->ground_point_m[0]), real(h->ground_point_m[1]), real(h->ground_point_m[2])},
      {real(h->ground_normal[0]), real(h->ground_normal[1]), real(h->ground_normal[2])},
      real(h->mu_static),
      real(h->mu_kinetic)};
  st = spatial::robot_data_init(sim->robot, w.q, w.v, hold, &ground, sim->data);
  if (st != LEGSIM_OK) return st;
  sim->magic = kHexapodMagic;
  *out = sim;
  return LEGSIM_OK;
}

legsim_status legsim_hexapod_command_each(legsim_hexapod_sim *sim, const legsim_hexapod_commands *commands) {
  if (!sim || !commands) return LEGSIM_ERR_NULL;
  if (sim->magic != kHexapodMagic) return LEGSIM_ERR_STORAGE;
  const spatial::SpatialRobot &R = sim->robot;
  const legsim_hexapod_commands &in = *commands;
  // every slot checked before any is taken
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l)
    for (int k = 0; k < 3; ++k) {
      const int32_t mode = in.mode[l][k];
      if (mode == LEGSIM_HEXAPOD_KEEP || l >= R.nlegs || (k < 2 && k >= R.leg[l].nactuators)) continue;
      if (mode != LEGSIM_HEXAPOD_FORCE && mode != LEGSIM_HEXAPOD_SERVO) return LEGSIM_ERR_BAD_INPUT;
      const double bound = k < 2 ? double(R.act[R.leg[l].first_actuator + k].max_force) : double(R.rowing_max_torque);
      const double x = in.value[l][k];
      if (mode == LEGSIM_HEXAPOD_FORCE) {
        if (!finite_within(&x, 1, bound)) return LEGSIM_ERR_BAD_INPUT;
        continue;
      }
      if (!std::isfinite(x) || !finite_within(&in.feedforward[l][k], 1, bound)) return LEGSIM_ERR_BAD_INPUT;
      const real *stroke = k < 2 ? R.act[R.leg[l].first_actuator + k].stroke : R.rowing_stroke;
      if (!(x >= stroke[0] && x <= stroke[1])) return LEGSIM_ERR_OUT_OF_STROKE;
    }
  spatial::RobotCommands c = sim->data.command;
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l)
    for (int k = 0; k < 3; ++k) {
      const int32_t mode = in.mode[l][k];
      if (mode == LEGSIM_HEXAPOD_KEEP || l >= R.nlegs || (k < 2 && k >= R.leg[l].nactuators)) continue;
      const spatial::CommandMode m = mode == LEGSIM_HEXAPOD_FORCE ? spatial::CommandMode::Force : spatial::CommandMode::Servo;
      const real ff = mode == LEGSIM_HEXAPOD_SERVO ? real(in.feedforward[l][k]) : real(0);
      if (k < 2) {
        const int a = R.leg[l].first_actuator + k;
        c.actuator_mode[a] = m, c.actuator[a] = real(in.value[l][k]), c.actuator_ff[a] = ff;
      } else {
        c.rowing_mode[l] = m, c.rowing[l] = real(in.value[l][k]), c.rowing_ff[l] = ff;
      }
    }
  return command_apply(*sim, c);
}

legsim_status legsim_hexapod_command(legsim_hexapod_sim *sim, const double actuator_force_n[LEGSIM_HEXAPOD_LEGS][2],
                                     const double rowing_torque_nm[LEGSIM_HEXAPOD_LEGS]) {
  if (!sim || !actuator_force_n || !rowing_torque_nm) return LEGSIM_ERR_NULL;
  legsim_hexapod_commands c = {};
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l)
    for (int k = 0; k < 3; ++k)
      c.mode[l][k] = LEGSIM_HEXAPOD_FORCE, c.value[l][k] = k < 2 ? actuator_force_n[l][k] : rowing_torque_nm[l];
  return legsim_hexapod_command_each(sim, &c);
}

legsim_status legsim_hexapod_command_pose(legsim_hexapod_sim *sim, const double length_m[LEGSIM_HEXAPOD_LEGS][2],
                                          const double rowing_rad[LEGSIM_HEXAPOD_LEGS],
                                          const double feedforward_n[LEGSIM_HEXAPOD_LEGS][2],
                                          const double feedforward_nm[LEGSIM_HEXAPOD_LEGS]) {
  if (!sim || !length_m || !rowing_rad) return LEGSIM_ERR_NULL;
  legsim_hexapod_commands c = {};
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l)
    for (int k = 0; k < 3; ++k) {
      c.mode[l][k] = LEGSIM_HEXAPOD_SERVO;
      c.value[l][k] = k < 2 ? length_m[l][k] : rowing_rad[l];
      c.feedforward[l][k] = k < 2 ? (feedforward_n ? feedforward_n[l][k] : 0.0) : (feedforward_nm ? feedforward_nm[l] : 0.0);
    }
  return legsim_hexapod_command_each(sim, &c);
}

legsim_status legsim_hexapod_step(legsim_hexapod_sim *sim, double h_s, int32_t n_steps) {
  if (!sim) return LEGSIM_ERR_NULL;
  if (sim->magic != kHexapodMagic) return LEGSIM_ERR_STORAGE;
  if (!(h_s > 0 && h_s <= 0.1) || n_steps < 1) return LEGSIM_ERR_BAD_INPUT;
  for (int32_t k = 0; k < n_steps; ++k) {
    const legsim_status st = spatial::robot_step(sim->robot, sim->data, real(h_s), sim->integrator);
    if (st != LEGSIM_OK) return st;
  }
  return LEGSIM_OK;
}

legsim_status legsim_hexapod_set_integrator(legsim_hexapod_sim *sim, legsim_integrator integrator) {
  if (!sim) return LEGSIM_ERR_NULL;
  if (sim->magic != kHexapodMagic) return LEGSIM_ERR_STORAGE;
  if (integrator != LEGSIM_INTEGRATOR_RK4 && integrator != LEGSIM_INTEGRATOR_GENERALIZED_ALPHA)
    return LEGSIM_ERR_BAD_INPUT;
  const spatial::Integrator next =
      integrator == LEGSIM_INTEGRATOR_RK4 ? spatial::Integrator::Rk4 : spatial::Integrator::GeneralizedAlpha;
  // generalized-alpha's history starts at the accelerations when it takes over
  if (next != sim->integrator) {
    std::copy(sim->data.a, sim->data.a + spatial::kBodyDof * sim->robot.nb, sim->data.acc_aux);
    sim->data.acc_aux_h = 0;
  }
  sim->integrator = next;
  return LEGSIM_OK;
}

legsim_status legsim_hexapod_set_velocity(legsim_hexapod_sim *sim, const double velocity_mps[3],
                                         const double omega_radps[3]) {
  if (!sim || !velocity_mps || !omega_radps) return LEGSIM_ERR_NULL;
  if (sim->magic != kHexapodMagic) return LEGSIM_ERR_STORAGE;
  if (!finite_within(velocity_mps, 3, LEGSIM_MAX_RATE_MPS) || !finite_within(omega_radps, 3, LEGSIM_MAX_RATE_MPS))
    return LEGSIM_ERR_BAD_INPUT;
  const spatial::SpatialRobot &R = sim->robot;
  spatial::RobotData &d = sim->data;
  if (d.t != 0 || d.impacts || d.stop_impacts) return LEGSIM_ERR_BAD_INPUT;  // a launch: before the first step
  // every body on the box's rigid motion: v_b = v + w x (r_b - r_0), its omega in its own frame
  const spatial::Rot Rb = spatial::rotation({d.q[3], d.q[4], d.q[5], d.q[6]});
  const spatial::V3 v0 = {real(velocity_mps[0]), real(velocity_mps[1]), real(velocity_mps[2])};
  const spatial::V3 w = spatial::rotate(Rb, spatial::V3{real(omega_radps[0]), real(omega_radps[1]), real(omega_radps[2])});
  real v[spatial::kMaxRobotDof], v_before[spatial::kMaxRobotDof];
  std::copy(d.v, d.v + spatial::kBodyDof * R.nb, v_before);
  for (int b = 0; b < R.nb; ++b) {
    const real *qb = d.q + spatial::kBodyConfig * b;
    const spatial::V3 vb = v0 + spatial::cross(w, spatial::V3{qb[0] - d.q[0], qb[1] - d.q[1], qb[2] - d.q[2]});
    const spatial::V3 wb = spatial::rotate_back(spatial::rotation({qb[3], qb[4], qb[5], qb[6]}), w);
    const real vv[spatial::kBodyDof] = {vb.x, vb.y, vb.z, wb.x, wb.y, wb.z};
    std::copy(vv, vv + spatial::kBodyDof, v + spatial::kBodyDof * b);
  }
  // a point held on the ground and moving along it slides
  const spatial::FeetHold before = d.hold;
  spatial::FeetHold hold = before;
  for (int c = 0; c < spatial::robot_contacts(R); ++c) {
    if (!((hold.stuck >> c) & 1u)) continue;
    spatial::V3 p, pv;
    spatial::foot_motion(R, c, d.q, v, p, pv);
    const spatial::V3 vt = spatial::tangential(hold, pv);
    if (spatial::dot(vt, vt) > 0) hold.stuck &= ~(1u << c), hold.sliding |= 1u << c;
  }
  const spatial::RobotCommands commands = d.command;
  const spatial::GroundPlane ground = d.ground;
  const bool has_ground = d.has_ground;
  legsim_status st = spatial::robot_data_init(R, d.q, v, hold, has_ground ? &ground : nullptr, d);
  if (st == LEGSIM_OK) {
    d.command = commands;
    st = spatial::robot_data_refresh(R, d);
  }
  if (st != LEGSIM_OK) {  // back to the start as it was (its init succeeded there)
    spatial::robot_data_init(R, d.q, v_before, before, has_ground ? &ground : nullptr, d);
    d.command = commands;
    spatial::robot_data_refresh(R, d);
  }
  return st;
}

legsim_status legsim_hexapod_get_state(const legsim_hexapod_sim *sim, legsim_hexapod_state *out) {
  if (!sim || !out) return LEGSIM_ERR_NULL;
  if (sim->magic != kHexapodMagic) return LEGSIM_ERR_STORAGE;
  const spatial::SpatialRobot &R = sim->robot;
  const spatial::RobotData &d = sim->data;
  legsim_hexapod_state r = {};  // a block's legs' zeros
  r.t_s = d.t;
  for (int i = 0; i < 3; ++i) r.box_m[i] = d.q[i], r.box_velocity_mps[i] = d.v[i], r.box_omega_radps[i] = d.v[3 + i];
  for (int i = 0; i < 4; ++i) r.box_quat[i] = d.q[3 + i];
  for (int l = 0; l < R.nlegs; ++l) {
    const spatial::RobotLeg &L = R.leg[l];
    r.rowing_rad[l] = spatial::robot_rowing_angle(R, l, d.q);
    r.rowing_rate_radps[l] = spatial::robot_rowing_rate(R, l, d.q, d.v);
    for (int a = 0; a < 2; ++a) {
      r.length_m[l][a] = a < L.nactuators ? spatial::robot_actuator_length(R, L.first_actuator + a, d.q) : 0.0;
      r.length_rate_mps[l][a] = a < L.nactuators ? spatial::robot_actuator_rate(R, L.first_actuator + a, d.q, d.v) : 0.0;
    }
    const spatial::V3 f = spatial::robot_foot_position(R, l, d.q);
    r.foot_m[l][0] = f.x, r.foot_m[l][1] = f.y, r.foot_m[l][2] = f.z;
    const spatial::V3 F = spatial::robot_foot_force(R, d, l);
    r.foot_force_n[l][0] = F.x, r.foot_force_n[l][1] = F.y, r.foot_force_n[l][2] = F.z;
    r.foot_state[l] = ((d.hold.stuck >> l) & 1u)     ? LEGSIM_CONTACT_STUCK
                      : ((d.hold.sliding >> l) & 1u) ? LEGSIM_CONTACT_SLIDING
                                                     : LEGSIM_CONTACT_FREE;
  }
  for (int l = 0; l < R.nlegs; ++l) {
    const spatial::RobotLeg &L = R.leg[l];
    for (int a = 0; a < 2; ++a) r.actuator_force_n[l][a] = a < L.nactuators ? d.actuator_force[L.first_actuator + a] : 0.0;
    r.rowing_torque_nm[l] = d.rowing_torque[l];
  }
  r.kinetic_energy_j = spatial::robot_kinetic_energy(R, d.v);
  r.events = d.events;
  r.impacts = d.impacts;
  r.cone_solved = d.cone_stats.solved, r.cone_by_sweeps = d.cone_stats.by_sweeps;
  r.cone_max_iterations = d.cone_stats.max_iterations, r.cone_max_residual = d.cone_stats.max_residual;
  for (int l = 0; l < R.nlegs; ++l)
    for (int k = 0; k < spatial::kLegStops; ++k) {
      const uint32_t bit = 1u << (spatial::kLegStops * l + k);
      const int32_t at = (d.hold.stops & bit) ? ((d.hold.upper & bit) ? 1 : -1) : 0;
      if (k < 2) r.actuator_stop[l][k] = at;
      else r.rowing_stop[l] = at;
    }
  r.stop_impacts = d.stop_impacts;
  r.n_box_contacts = R.nbox_contacts;
  for (int k = 0; k < LEGSIM_HEXAPOD_MAX_BOX_CONTACTS; ++k) {
    const int c = R.nlegs + k;
    const bool has = k < R.nbox_contacts;
    const spatial::V3 p = has ? spatial::robot_contact_position(R, c, d.q) : spatial::V3{0, 0, 0};
    const spatial::V3 F = has ? spatial::robot_foot_force(R, d, c) : spatial::V3{0, 0, 0};
    r.box_contact_m[k][0] = p.x, r.box_contact_m[k][1] = p.y, r.box_contact_m[k][2] = p.z;
    r.box_contact_force_n[k][0] = F.x, r.box_contact_force_n[k][1] = F.y, r.box_contact_force_n[k][2] = F.z;
    r.box_contact_state[k] = !has                           ? LEGSIM_CONTACT_FREE
                             : ((d.hold.stuck >> c) & 1u)   ? LEGSIM_CONTACT_STUCK
                             : ((d.hold.sliding >> c) & 1u) ? LEGSIM_CONTACT_SLIDING
                                                            : LEGSIM_CONTACT_FREE;
  }
  *out = r;
  return LEGSIM_OK;
}

legsim_status legsim_hexapod_body_poses(const legsim_hexapod_sim *sim, double *pose, int32_t capacity, int32_t *n) {
  if (!sim || !pose || !n) return LEGSIM_ERR_NULL;
  if (sim->magic != kHexapodMagic) return LEGSIM_ERR_STORAGE;
  const int nb = sim->robot.nb;
  if (capacity < nb) return LEGSIM_ERR_CAPACITY;
  for (int k = 0; k < kBodyConfig * nb; ++k) pose[k] = sim->data.q[k];
  *n = nb;
  return LEGSIM_OK;
}

}  // extern "C"
