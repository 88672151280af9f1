// The C API, the hexapod's inverse dynamics along the tripod gait (legsim/hexapod.h): the plan's
// state from the gait's set-points and the box's twist (spatial/inverse: the rows' velocities and
// accelerations), then statics' rule with the inertial forces as loads.
#include <cmath>
#include <new>

#include "legsim/hexapod.h"
#include "spatial/inverse.hpp"

using namespace legsim;

namespace {
using spatial::kBodyConfig;
using spatial::kBodyDof;
using spatial::kMaxRobotBodies;
using spatial::V3;
using spatial::real;

static_assert(LEGSIM_HEXAPOD_MAX_LEG_JOINTS == 1 + spatial::kMaxLegJoints, "a leg's joints: its hip's and its file's");

// The storage after legsim_hexapod_gait_setpoints' part (whose first bytes also hold the planar
// leg each assembly takes).
struct InverseWork {
  spatial::SpatialRobot robot;
  spatial::RobotStatics statics;
  real q[kBodyConfig * kMaxRobotBodies], v[kBodyDof * kMaxRobotBodies], a[kBodyDof * kMaxRobotBodies];
  real leg_q[LEGSIM_HEXAPOD_LEGS][3 * LEGSIM_MAX_BODIES];
  legsim_hexapod_setpoint sp, near[9];  // the set-points at t and at t + k h, k = -4 .. 4
  bool have[9];
  V3 foot_v[LEGSIM_HEXAPOD_LEGS], foot_a[LEGSIM_HEXAPOD_LEGS];
  uint32_t stance;
};
constexpr size_t round_up(size_t n) { return (n + LEGSIM_STORAGE_ALIGN - 1) / LEGSIM_STORAGE_ALIGN * LEGSIM_STORAGE_ALIGN; }
size_t head_bytes() { return round_up(legsim_hexapod_storage_size()); }

// A swinging foot's rates in the box's frame: its curve (the set-points' targets) sampled over a
// five-point stencil of step h that lies within its swing (central when it can), as close to t as
// the swing allows.
legsim_status swing_rates(const legsim_hexapod_desc &h, const legsim_hexapod_gait &g, double t, double step,
                          void *storage, InverseWork &w, int l, V3 &d1, V3 &d2) {
  static const int starts[5] = {-2, -1, -3, 0, -4};
  for (int k0 : starts) {
    bool swinging = true;
    for (int k = k0; k < k0 + 5 && swinging; ++k) {
      if (!w.have[k + 4]) {
        const legsim_status st =
            legsim_hexapod_gait_setpoints(&h, &g, t + k * step, storage, legsim_hexapod_storage_size(), &w.near[k + 4]);
        if (st != LEGSIM_OK) return st;
        w.have[k + 4] = true;
      }
      swinging = !w.near[k + 4].stance[l];
    }
    if (!swinging) continue;
    real d[2][3];
    for (int i = 0; i < 3; ++i) {
      real f[5];
      for (int k = 0; k < 5; ++k) f[k] = real(w.near[k0 + k + 4].foot_box_m[l][i]);
      spatial::stencil_derivatives(k0, real(step), f, d[0][i], d[1][i]);
    }
    d1 = {d[0][0], d[0][1], d[0][2]}, d2 = {d[1][0], d[1][1], d[1][2]};
    return LEGSIM_OK;
  }
  return LEGSIM_ERR_BAD_INPUT;  // a swing shorter than the stencil (a duty within 1.2e-3 of 1)
}

// The plan at t: the robot's q, v, a, the stance and each foot's rates (world) in w.
legsim_status plan(const legsim_hexapod_desc &h, const legsim_hexapod_gait &g, double t, void *storage,
                   size_t bytes, InverseWork *&wp) {
  if (bytes < legsim_hexapod_inverse_storage_size() || reinterpret_cast<uintptr_t>(storage) % LEGSIM_STORAGE_ALIGN)
    return LEGSIM_ERR_STORAGE;
  wp = new (static_cast<unsigned char *>(storage) + head_bytes()) InverseWork;
  InverseWork &w = *wp;
  // the set-points (the description, the gait and t checked there)
  legsim_status st = legsim_hexapod_gait_setpoints(&h, &g, t, storage, legsim_hexapod_storage_size(), &w.sp);
  if (st != LEGSIM_OK) return st;
  st = spatial::robot_lift_hexapod(h, w.robot);
  if (st != LEGSIM_OK) return st;
  // each leg at its set-point's lengths, from its file's stand
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l) {
    const legsim_options opt = legsim_default_options();
    legsim_sim *sim = nullptr;
    st = legsim_init(storage, legsim_sim_size(), &h.leg[l].leg, &opt, &sim);
    if (st == LEGSIM_OK) st = legsim_assemble_pose(sim, 0);
    legsim_real len[2] = {legsim_real(w.sp.length_m[l][0]), legsim_real(w.sp.length_m[l][1])};
    if (st == LEGSIM_OK) st = legsim_assemble(sim, len);
    if (st == LEGSIM_OK) st = legsim_get_q(sim, w.leg_q[l]);
    if (st != LEGSIM_OK) return st;
  }
  // the box on its twist
  const real Ts = real(g.duty * g.period_s);
  real box_q[7], box_v[6], box_a[6];
  spatial::twist_motion(real(g.box_height_m), real(g.step_length_m) / Ts, real(g.turn_rad) / Ts, t, box_q, box_v,
                        box_a);
  // on a sloped ground the box keeps its height over the ground below it (the gait's plan): its z
  // the set-point's, its vertical rates the ground's grade along its horizontal ones
  const real grade_x = real(-h.ground_normal[0] / h.ground_normal[2]);
  const real grade_y = real(-h.ground_normal[1] / h.ground_normal[2]);
  box_q[2] = real(w.sp.box_m[2]);
  box_v[2] = grade_x * box_v[0] + grade_y * box_v[1];
  box_a[2] = grade_x * box_a[0] + grade_y * box_a[1];
  static const real rest[3 * LEGSIM_MAX_BODIES] = {};
  const real *qs[LEGSIM_HEXAPOD_LEGS], *vs[LEGSIM_HEXAPOD_LEGS];
  real psi[LEGSIM_HEXAPOD_LEGS];
  const real psid[LEGSIM_HEXAPOD_LEGS] = {}, box_rest[6] = {};
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l) qs[l] = w.leg_q[l], vs[l] = rest, psi[l] = real(w.sp.rowing_rad[l]);
  spatial::robot_state(w.robot, box_q, box_rest, qs, vs, psi, psid, w.q, w.v);
  // the feet: a standing one held; a swinging one's curve in the box's frame carried by the box
  // (omega' = 0): p = r + R s, p' = v + w x R s + R s', p'' = a + w x (w x R s) + 2 w x R s' + R s''
  const spatial::Rot R = spatial::rotation({box_q[3], box_q[4], box_q[5], box_q[6]});
  const V3 vb = {box_v[0], box_v[1], box_v[2]}, ab = {box_a[0], box_a[1], box_a[2]};
  const V3 wb = spatial::rotate(R, V3{box_v[3], box_v[4], box_v[5]});
  const double step = double(spatial::by_precision(3e-4, 1e-2)) * g.period_s;
  for (int k = 0; k < 9; ++k) w.have[k] = false;
  w.stance = 0;
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l) {
    w.foot_v[l] = w.foot_a[l] = {0, 0, 0};
    if (w.sp.stance[l]) {
      w.stance |= 1u << l;
      continue;
    }
    V3 d1, d2;
    st = swing_rates(h, g, t, step, storage, w, l, d1, d2);
    if (st != LEGSIM_OK) return st;
    const V3 s = spatial::rotate(R, V3{real(w.sp.foot_box_m[l][0]), real(w.sp.foot_box_m[l][1]),
                                       real(w.sp.foot_box_m[l][2])});
    const V3 s1 = spatial::rotate(R, d1), s2 = spatial::rotate(R, d2);
    w.foot_v[l] = vb + spatial::cross(wb, s) + s1;
    w.foot_a[l] = ab + spatial::cross(wb, spatial::cross(wb, s)) + 2 * spatial::cross(wb, s1) + s2;
  }
  return spatial::robot_prescribed_motion(w.robot, w.q, box_v, box_a, w.foot_v, w.foot_a, w.v, w.a);
}
}  // namespace

extern "C" {

size_t legsim_hexapod_inverse_storage_size(void) { return head_bytes() + round_up(sizeof(InverseWork)); }

legsim_status legsim_hexapod_inverse_dynamics(const legsim_hexapod_desc *h, const legsim_hexapod_gait *gait,
                                              double t_s, void *storage, size_t storage_bytes,
                                              legsim_hexapod_inverse *out) {
  if (!h || !gait || !storage || !out) return LEGSIM_ERR_NULL;
  InverseWork *wp = nullptr;
  legsim_status st = plan(*h, *gait, t_s, storage, storage_bytes, wp);
  if (st != LEGSIM_OK) return st;
  InverseWork &w = *wp;
  const spatial::SpatialRobot &R = w.robot;
  st = spatial::robot_inverse_dynamics(R, w.q, w.v, w.a, w.stance, w.statics);
  if (st != LEGSIM_OK) return st;
  V3 force[spatial::kMaxRobotJoints], moment[spatial::kMaxRobotJoints];
  spatial::robot_joint_reactions(R, w.q, w.statics.multiplier, force, moment);
  legsim_hexapod_inverse r = {};
  r.t_s = t_s;
  for (int i = 0; i < 3; ++i) r.box_m[i] = w.q[i], r.box_velocity_mps[i] = w.v[i], r.box_omega_radps[i] = w.v[3 + i];
  for (int i = 0; i < 4; ++i) r.box_quat[i] = w.q[3 + i];
  const V3 n = {real(h->ground_normal[0]), real(h->ground_normal[1]), real(h->ground_normal[2])};
  // statics' rule keeps each stance force up against gravity; on a sloped ground a foot must also
  // push along the ground's normal, or the plan needs the ground to hold it (all or nothing)
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l)
    if (((w.stance >> l) & 1u) && !(spatial::dot(w.statics.foot_force[l], n) > 0)) return LEGSIM_ERR_NO_EQUILIBRIUM;
  int j = 0;
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l) {
    const spatial::RobotLeg &L = R.leg[l];
    r.stance[l] = (w.stance >> l) & 1u;
    const V3 p = spatial::robot_foot_position(R, l, w.q), F = w.statics.foot_force[l];
    const double pf[3][3] = {{p.x, p.y, p.z}, {w.foot_v[l].x, w.foot_v[l].y, w.foot_v[l].z},
                             {w.foot_a[l].x, w.foot_a[l].y, w.foot_a[l].z}};
    for (int i = 0; i < 3; ++i) {
      r.foot_m[l][i] = pf[0][i], r.foot_velocity_mps[l][i] = pf[1][i], r.foot_acceleration_mps2[l][i] = pf[2][i];
    }
    r.foot_force_n[l][0] = F.x, r.foot_force_n[l][1] = F.y, r.foot_force_n[l][2] = F.z;
    if (r.stance[l]) {
      const real N = spatial::dot(F, n);
      const V3 Ft = F - N * n;
      r.cone_ratio[l] = std::sqrt(double(spatial::dot(Ft, Ft))) / double(N);
    }
    for (int a = 0; a < L.nactuators && a < 2; ++a) r.actuator_force_n[l][a] = w.statics.actuator_force[L.first_actuator + a];
    r.rowing_torque_nm[l] = w.statics.rowing_torque[l];
    // the leg's joints: contiguous from its hip's (robot_lift's order)
    r.n_joints[l] = 0;
    for (; j < R.nj && (R.joint[j].a >= L.yoke && R.joint[j].a <= L.yoke + L.nbars); ++j) {
      const int k = r.n_joints[l]++;
      const double fm[2][3] = {{force[j].x, force[j].y, force[j].z}, {moment[j].x, moment[j].y, moment[j].z}};
      for (int i = 0; i < 3; ++i) r.joint_force_n[l][k][i] = fm[0][i], r.joint_moment_nm[l][k][i] = fm[1][i];
    }
  }
  *out = r;
  return LEGSIM_OK;
}

legsim_status legsim_hexapod_gait_state(const legsim_hexapod_desc *h, const legsim_hexapod_gait *gait, double t_s,
                                        void *storage, size_t storage_bytes, double *q, double *v, double *a,
                                        int32_t capacity, int32_t *n) {
  if (!h || !gait || !storage || !q || !v || !a || !n) return LEGSIM_ERR_NULL;
  InverseWork *wp = nullptr;
  const legsim_status st = plan(*h, *gait, t_s, storage, storage_bytes, wp);
  if (st != LEGSIM_OK) return st;
  const int nb = wp->robot.nb;
  if (capacity < nb) return LEGSIM_ERR_CAPACITY;
  for (int k = 0; k < kBodyConfig * nb; ++k) q[k] = wp->q[k];
  for (int k = 0; k < kBodyDof * nb; ++k) v[k] = wp->v[k], a[k] = wp->a[k];
  *n = nb;
  return LEGSIM_OK;
}

}  // extern "C"
