#include "spatial/robot.hpp"

#include <algorithm>
#include <cmath>

#include "spatial/dynamics.hpp"
#include "spatial/lanes.hpp"

namespace legsim::spatial {

namespace {
constexpr V3 kX = {1, 0, 0}, kY = {0, 1, 0}, kZ = {0, 0, 1};
// A bar's body axes (u, n, k) in its frame.
constexpr V3 kU = {1, 0, 0}, kN = {0, 1, 0}, kK = {0, 0, 1};

// Union-find over the robot's bodies (a leg's frame joints join its bars to its yoke).
int find(int *parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

Quat z_turn(real angle) { return {std::cos(real(0.5) * angle), 0, 0, std::sin(real(0.5) * angle)}; }
// the yoke's plane: planar (x, y, z) to the yoke's (x, z, -y): +90 degrees about x
const Quat kPlane = {real(0.70710678118654752440), real(0.70710678118654752440), 0, 0};
// a bar's (u, n, k) from the plane's axes at angle 0: u = -y, n = x (-90 degrees about z)
const Quat kBarAxes = {real(0.70710678118654752440), 0, 0, -real(0.70710678118654752440)};

void put(real *q, real *v, const V3 &r, const Quat &p, const V3 &vr, const V3 &w) {
  const real c[kBodyConfig] = {r.x, r.y, r.z, p.w, p.x, p.y, p.z};
  const real s[kBodyDof] = {vr.x, vr.y, vr.z, w.x, w.y, w.z};
  for (int i = 0; i < kBodyConfig; ++i) q[i] = c[i];
  for (int i = 0; i < kBodyDof; ++i) v[i] = s[i];
}
// Leg l's elimination order (RobotLeg::order) over its joints [j0, j1). S_l = J_l M_l^-1 J_l^T
// couples two rows on a common body, and the Cholesky factor of S_l fills only within each
// row's envelope (from its first coupled row on): the joints, and the foot as a block of three
// rows on its bar, are ordered by Cuthill-McKee (next the block coupled to the earliest placed
// one, the fewer rows first) from each block in turn, the smallest factoring cost kept, then
// bettered by moving one block at a time.
void order_leg(SpatialRobot &R, int l, int j0, int j1) {
  RobotLeg &L = R.leg[l];
  const int lo = L.yoke, hi = L.yoke + 1 + L.nbars;
  struct Block {
    int a, b, n, row;  // its bodies in the leg (-1: none), rows, first row (-1: the foot)
  };
  Block blk[kMaxLegJoints + 3];
  int nblk = 0, hip = -1;
  auto in_leg = [&](int b) { return b >= lo && b < hi ? b : -1; };
  for (int j = j0; j < j1; ++j) {
    const LegJoint &J = R.joint[j];
    if (R.free_box && J.b == 0) hip = nblk;
    blk[nblk++] = {in_leg(J.a), in_leg(J.b), J.nrows, J.row};
  }
  if (L.foot_body >= 0) blk[nblk++] = {L.foot_body, -1, 3, -1};
  auto shares = [&](const Block &p, const Block &q) {
    return (p.a >= 0 && (p.a == q.a || p.a == q.b)) || (p.b >= 0 && (p.b == q.a || p.b == q.b));
  };
  // the envelope Cholesky's multiplications for the blocks in order seq
  auto cost = [&](const int *seq) {
    int first[kMaxLegRows], start[kMaxLegJoints + 3], n = 0;
    long c = 0;
    for (int p = 0; p < nblk; ++p) {
      const Block &B = blk[seq[p]];
      int f = n;
      for (int q = 0; q < p; ++q)
        if (shares(B, blk[seq[q]])) f = std::min(f, start[q]);
      start[p] = n;
      for (int k = 0; k < B.n; ++k, ++n) {
        first[n] = f;
        for (int j = f; j <= n; ++j) c += j - std::max(f, first[j]);
      }
    }
    return c;
  };
  int best[kMaxLegJoints + 3], seq[kMaxLegJoints + 3];
  long best_cost = -1;
  if (nblk == 1) best[0] = 0;
  for (int s0 = 0; s0 < nblk && nblk > 1; ++s0) {
    if (s0 == hip) continue;
    bool placed[kMaxLegJoints + 3] = {};
    int np = 0;
    seq[np++] = s0, placed[s0] = true;
    while (np < nblk - (hip >= 0 ? 1 : 0)) {
      int pick = -1, pick_at = 0;
      for (int c = 0; c < nblk; ++c) {
        if (placed[c] || c == hip) continue;
        int at = np;
        for (int q = 0; q < np; ++q)
          if (shares(blk[c], blk[seq[q]])) {
            at = q;
            break;
          }
        if (pick < 0 || at < pick_at || (at == pick_at && blk[c].n < blk[pick].n)) pick = c, pick_at = at;
      }
      seq[np++] = pick, placed[pick] = true;
    }
    if (hip >= 0) seq[np++] = hip;
    const long c = cost(seq);
    if (best_cost < 0 || c < best_cost) {
      best_cost = c;
      std::copy(seq, seq + nblk, best);
    }
  }
  // then one block moved at a time while that lowers the cost (the hip's kept last)
  for (bool better = true; better && nblk > 2;) {
    better = false;
    const int nm = nblk - (hip >= 0 ? 1 : 0);
    for (int i = 0; i < nm; ++i)
      for (int j = 0; j < nm; ++j) {
        if (i == j) continue;
        std::copy(best, best + nblk, seq);
        const int moved = seq[i];
        if (i < j) {
          std::copy(seq + i + 1, seq + j + 1, seq + i);
        } else {
          std::copy_backward(seq + j, seq + i, seq + i + 1);
        }
        seq[j] = moved;
        const long c = cost(seq);
        if (c < best_cost) {
          best_cost = c, better = true;
          std::copy(seq, seq + nblk, best);
        }
      }
  }
  L.norder = 0;
  L.foot_slot = -1;
  for (int p = 0; p < nblk; ++p) {
    const Block &B = blk[best[p]];
    if (best[p] == hip) continue;
    if (B.row < 0) {
      L.foot_slot = L.norder;
      continue;
    }
    for (int k = 0; k < B.n; ++k) L.order[L.norder++] = B.row + k;
  }
  if (L.foot_slot < 0) L.foot_slot = L.norder;
}
}  // namespace

legsim_status robot_lift(const legsim_model_desc *const *legs, const HipDesc *hips, int nlegs, const YokeDesc &yoke,
                         const BoxDesc *box, SpatialRobot &out) {
  if (nlegs < 1 || nlegs > kMaxLegs || !legs || !hips) return LEGSIM_ERR_CAPACITY;
  SpatialRobot &R = out;
  R.free_box = box != nullptr;
  R.nlegs = nlegs;
  R.nbox_contacts = 0;
  R.yoke_com = {real(yoke.com_m[0]), real(yoke.com_m[1]), real(yoke.com_m[2])};
  R.origin_x = real(yoke.hip_offset_m);
  R.rowing_max_torque = real(yoke.rowing_max_torque_nm);
  R.rowing_stroke[0] = real(yoke.rowing_stroke_rad[0]), R.rowing_stroke[1] = real(yoke.rowing_stroke_rad[1]);
  R.rowing_kp = real(yoke.rowing_kp_nm_per_rad), R.rowing_kd = real(yoke.rowing_kd_nms_per_rad);
  R.gravity = {0, 0, real(legs[0]->gravity_mps2[1])};
  int nb = 0, na = 0;
  if (box) {
    R.mass[0] = real(box->mass_kg);
    R.inertia[0] = {real(box->inertia_kgm2[0]), real(box->inertia_kgm2[1]), real(box->inertia_kgm2[2])};
    nb = 1;
  }
  const int box_body = box ? 0 : -1;
  int parent[kMaxRobotBodies];
  int nj = 0, row = 0;
  auto add = [&](const LegJoint &j, int nrows) {
    R.joint[nj] = j;
    R.joint[nj].row = row;
    R.joint[nj].nrows = nrows;
    for (int r = row; r < row + nrows; ++r) R.row_body[r][0] = j.a, R.row_body[r][1] = j.b;
    ++nj;
    row += nrows;
  };
  for (int l = 0; l < nlegs; ++l) {
    const legsim_model_desc &desc = *legs[l];
    const int nbar = desc.n_bodies;
    if (nbar < 1 || nbar > kMaxLegBars || desc.n_joints > kMaxLegJoints) return LEGSIM_ERR_CAPACITY;
    // the leg's plane is vertical, and every leg falls alike
    if (desc.gravity_mps2[0] != 0 || real(desc.gravity_mps2[1]) != R.gravity.z) return LEGSIM_ERR_MODEL;
    const int y = nb;
    RobotLeg &L = R.leg[l];
    L.yoke = y;
    L.nbars = nbar;
    L.hip = {real(hips[l].point_m[0]), real(hips[l].point_m[1]), real(hips[l].point_m[2])};
    L.yaw = real(hips[l].yaw_rad);
    R.mass[y] = real(yoke.mass_kg);
    R.inertia[y] = {real(yoke.inertia_kgm2[0]), real(yoke.inertia_kgm2[1]), real(yoke.inertia_kgm2[2])};
    for (int b = 0; b < nbar; ++b) {
      const legsim_body_desc &bd = desc.body[b];
      R.mass[y + 1 + b] = real(bd.mass_kg);
      // about u a tube's; about n and k the planar inertia (the planar dynamics unchanged)
      R.inertia[y + 1 + b] = {real(0.5 * bd.mass_kg * yoke.bar_radius_m * yoke.bar_radius_m),
                              real(bd.inertia_kgm2), real(bd.inertia_kgm2)};
    }
    L.foot_body = desc.foot_body >= 0 && desc.foot_body < nbar ? y + 1 + desc.foot_body : -1;
    L.foot_point = {real(desc.foot_point[0]), real(desc.foot_point[1]), 0};
    if (desc.n_actuators > LEGSIM_MAX_ACTUATORS) return LEGSIM_ERR_CAPACITY;
    L.first_actuator = na;
    L.nactuators = desc.n_actuators;
    for (int a = 0; a < desc.n_actuators; ++a) {
      const int jn = desc.actuator[a].joint;
      if (jn < 0 || jn >= desc.n_joints || desc.joint[jn].kind != LEGSIM_JOINT_PRISMATIC) return LEGSIM_ERR_MODEL;
      const int cyl = desc.joint[jn].body[0], rod = desc.joint[jn].body[1];
      const legsim_actuator_desc &ad = desc.actuator[a];
      R.act[na++] = {y + 1 + cyl,
                     y + 1 + rod,
                     real(0.5 * (desc.body[cyl].length_m + desc.body[rod].length_m)),
                     {real(ad.stroke_min_m), real(ad.stroke_max_m)},
                     real(ad.max_force_n),
                     real(ad.servo_kp_n_per_m),
                     real(ad.servo_kd_ns_per_m)};
    }
    nb += 1 + nbar;
    for (int i = y; i < nb; ++i) parent[i] = i;
    L.row0 = row;
    // the yoke about the box's z through the hip: its axis point is -com in its frame
    const int j0 = nj;
    add({LegJointKind::Revolute, y, box_body, -1 * R.yoke_com, L.hip, kZ, kX, kY, 0, 0}, 5);
    for (int k = 0; k < desc.n_joints; ++k) {
      const legsim_joint_desc &jd = desc.joint[k];
      const int a = y + 1 + jd.body[0];
      const V3 sa = {real(jd.point[0][0]), real(jd.point[0][1]), 0};
      switch (jd.kind) {
        case LEGSIM_JOINT_REVOLUTE_TO_FRAME: {
          // to the yoke, about the plane's normal; the yoke's in-plane axes x and z across it
          // (or, closing a loop, in their plane only)
          const V3 sb = V3{R.origin_x + real(jd.point[1][0]), 0, real(jd.point[1][1])} - R.yoke_com;
          const int ra = find(parent, a), ry = find(parent, y);
          if (ra == ry) {
            add({LegJointKind::Cut, a, y, sa, sb, kK, kX, kZ, 0, 0}, 2);
          } else {
            parent[ra] = ry;
            add({LegJointKind::Revolute, a, y, sa, sb, kK, kX, kZ, 0, 0}, 5);
          }
          break;
        }
        case LEGSIM_JOINT_REVOLUTE: {
          const int b = y + 1 + jd.body[1];
          const V3 sb = {real(jd.point[1][0]), real(jd.point[1][1]), 0};
          const int ra = find(parent, a), rb = find(parent, b);
          if (ra == rb) {
            add({LegJointKind::Cut, a, b, sa, sb, kK, kU, kN, 0, 0}, 2);
          } else {
            parent[ra] = rb;
            add({LegJointKind::Revolute, a, b, sa, sb, kK, kU, kN, 0, 0}, 5);
          }
          break;
        }
        case LEGSIM_JOINT_PRISMATIC: {
          const int b = y + 1 + jd.body[1];
          const int ra = find(parent, a), rb = find(parent, b);
          if (ra == rb) return LEGSIM_ERR_MODEL;
          parent[ra] = rb;
          add({LegJointKind::Prismatic, a, b, {0, 0, 0}, {0, 0, 0}, kU, kN, kK, 0, 0}, 5);
          break;
        }
        default:
          return LEGSIM_ERR_MODEL;  // a slot: no spatial row unit
      }
    }
    L.nrows = row - L.row0;
    L.joint0 = j0, L.njoints = nj - j0;
    order_leg(R, l, j0, nj);
  }
  // the legs whose joints are of the same kinds in the same order on the same bodies (counted
  // from each leg's yoke; the box, the world), two by two: robot_rows evaluates each such pair in
  // lanes
  for (int l = 0; l < nlegs; ++l) R.leg[l].row_twin = -1;
  for (int l = 0; l < nlegs; ++l) {
    RobotLeg &L = R.leg[l];
    for (int m = l + 1; m < nlegs && L.row_twin < 0; ++m) {
      RobotLeg &M = R.leg[m];
      bool same = M.row_twin < 0 && M.njoints == L.njoints && M.nbars == L.nbars;
      for (int k = 0; k < L.njoints && same; ++k) {
        const LegJoint &a = R.joint[L.joint0 + k], &b = R.joint[M.joint0 + k];
        same = a.kind == b.kind && a.a - L.yoke == b.a - M.yoke &&
               (a.b < L.yoke ? a.b == b.b : b.b >= M.yoke && a.b - L.yoke == b.b - M.yoke);
      }
      if (same) L.row_twin = m, M.row_twin = l;
    }
  }
  R.nb = nb;
  for (int b = 0; b < nb; ++b) {
    const real im[kBodyDof] = {1 / R.mass[b], 1 / R.mass[b], 1 / R.mass[b],
                               1 / R.inertia[b].x, 1 / R.inertia[b].y, 1 / R.inertia[b].z};
    for (int k = 0; k < kBodyDof; ++k) R.inverse_mass[b][k] = im[k];
  }
  R.na = na;
  R.nj = nj;
  R.m = row;
  // the dynamics' elimination, chosen once per hold of each foot (the foot rows' numbers follow m)
  for (int l = 0; l < nlegs; ++l)
    for (int k = 0; k < 3; ++k) leg_layout(R, l, k == 2 ? 3 : k, R.leg[l].layout[k]);
  return LEGSIM_OK;
}

legsim_status robot_lift_hexapod(const legsim_hexapod_desc &h, SpatialRobot &out) {
  if (h.n_legs != LEGSIM_HEXAPOD_LEGS && h.n_legs != 0) return LEGSIM_ERR_MODEL;
  YokeDesc yoke;
  yoke.mass_kg = h.yoke_mass_kg;
  for (int i = 0; i < 3; ++i) yoke.com_m[i] = h.yoke_com_m[i], yoke.inertia_kgm2[i] = h.yoke_inertia_kgm2[i];
  yoke.hip_offset_m = h.hip_offset_m;
  yoke.bar_radius_m = h.bar_radius_m;
  yoke.rowing_max_torque_nm = h.rowing_max_torque_nm;
  yoke.rowing_stroke_rad[0] = h.rowing_stroke_rad[0], yoke.rowing_stroke_rad[1] = h.rowing_stroke_rad[1];
  yoke.rowing_kp_nm_per_rad = h.rowing_servo_kp_nm_per_rad;
  yoke.rowing_kd_nms_per_rad = h.rowing_servo_kd_nms_per_rad;
  const BoxDesc box = {h.box_mass_kg, {h.box_inertia_kgm2[0], h.box_inertia_kgm2[1], h.box_inertia_kgm2[2]}};
  const legsim_model_desc *legs[LEGSIM_HEXAPOD_LEGS];
  HipDesc hips[LEGSIM_HEXAPOD_LEGS];
  for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l) {
    legs[l] = &h.leg[l].leg;
    hips[l] = {{h.leg[l].hip_m[0], h.leg[l].hip_m[1], h.leg[l].hip_m[2]}, h.leg[l].heading_rad};
  }
  legsim_status s = h.n_legs ? robot_lift(legs, hips, LEGSIM_HEXAPOD_LEGS, yoke, &box, out)
                             : robot_lift_block(box, real(h.gravity_mps2[2]), out);
  if (s != LEGSIM_OK || h.n_box_contacts == 0) return s;
  if (h.n_box_contacts < 0 || h.n_box_contacts > kMaxBoxContacts) return LEGSIM_ERR_CAPACITY;
  V3 p[kMaxBoxContacts];
  for (int k = 0; k < h.n_box_contacts; ++k)
    p[k] = {real(h.box_contact_m[k][0]), real(h.box_contact_m[k][1]), real(h.box_contact_m[k][2])};
  return robot_box_contacts(out, p, h.n_box_contacts);
}

legsim_status robot_lift_block(const BoxDesc &box, real gravity_z, SpatialRobot &out) {
  const double m = box.mass_kg, *I = box.inertia_kgm2;
  if (!(m > 0 && I[0] > 0 && I[1] > 0 && I[2] > 0 && std::isfinite(m) && std::isfinite(I[0]) &&
        std::isfinite(I[1]) && std::isfinite(I[2]) && std::isfinite(gravity_z)))
    return LEGSIM_ERR_BAD_INPUT;
  SpatialRobot &R = out;
  R.free_box = true;
  R.nb = 1, R.nj = 0, R.m = 0, R.nlegs = 0, R.na = 0, R.nbox_contacts = 0;
  R.mass[0] = real(m);
  R.inertia[0] = {real(I[0]), real(I[1]), real(I[2])};
  const real im[kBodyDof] = {1 / R.mass[0], 1 / R.mass[0], 1 / R.mass[0],
                             1 / R.inertia[0].x, 1 / R.inertia[0].y, 1 / R.inertia[0].z};
  for (int k = 0; k < kBodyDof; ++k) R.inverse_mass[0][k] = im[k];
  R.gravity = {0, 0, gravity_z};
  R.yoke_com = {0, 0, 0};
  R.origin_x = 0, R.rowing_max_torque = 0, R.rowing_stroke[0] = R.rowing_stroke[1] = 0;
  R.rowing_kp = R.rowing_kd = 0;
  return LEGSIM_OK;
}

legsim_status robot_box_contacts(SpatialRobot &robot, const V3 *points, int n) {
  if (n < 0 || n > kMaxBoxContacts) return LEGSIM_ERR_CAPACITY;
  if (!robot.free_box) return LEGSIM_ERR_MODEL;
  for (int k = 0; k < n; ++k)
    if (!std::isfinite(points[k].x) || !std::isfinite(points[k].y) || !std::isfinite(points[k].z))
      return LEGSIM_ERR_BAD_INPUT;
  for (int k = 0; k < n; ++k) robot.box_contact[k] = points[k];
  robot.nbox_contacts = n;
  return LEGSIM_OK;
}

void leg_plane_target(const SpatialRobot &robot, int l, const V3 &foot_box, real &psi, real *foot_xy) {
  const RobotLeg &L = robot.leg[l];
  const V3 d = foot_box - L.hip;
  real r = std::sqrt(d.x * d.x + d.y * d.y);
  real a = std::atan2(d.y, d.x) - L.yaw;  // the plane's angle from the heading
  a = std::remainder(a, 2 * real(3.14159265358979323846));
  if (std::abs(a) > real(3.14159265358979323846) / 2) {  // the foot behind the axis: the plane turned back
    a -= std::copysign(real(3.14159265358979323846), a);
    r = -r;
  }
  psi = a;
  foot_xy[0] = r - robot.origin_x;
  foot_xy[1] = d.z;
}

V3 robot_foot_position(const SpatialRobot &robot, int l, const real *q) {
  const RobotLeg &L = robot.leg[l];
  if (L.foot_body < 0) return {real(NAN), real(NAN), real(NAN)};  // (documented: none)
  const real *qb = q + kBodyConfig * L.foot_body;
  return V3{qb[0], qb[1], qb[2]} + rotate(rotation({qb[3], qb[4], qb[5], qb[6]}), L.foot_point);
}

V3 robot_contact_position(const SpatialRobot &robot, int c, const real *q) {
  if (c < robot.nlegs) return robot_foot_position(robot, c, q);
  return V3{q[0], q[1], q[2]} + rotate(rotation({q[3], q[4], q[5], q[6]}), robot.box_contact[c - robot.nlegs]);
}

void robot_state(const SpatialRobot &robot, const real *box_q, const real *box_v, const real *const *q_planar,
                 const real *const *qd_planar, const real *psi, const real *psid, real *q, real *v) {
  // the box: its pose, its velocity and its angular velocity in the world
  Quat pb = {1, 0, 0, 0};
  V3 rb = {0, 0, 0}, vb = {0, 0, 0}, wb = {0, 0, 0};
  if (robot.free_box) {
    pb = {box_q[3], box_q[4], box_q[5], box_q[6]};
    rb = {box_q[0], box_q[1], box_q[2]};
    vb = {box_v[0], box_v[1], box_v[2]};
    wb = rotate(rotation(pb), V3{box_v[3], box_v[4], box_v[5]});
    for (int i = 0; i < kBodyConfig; ++i) q[i] = box_q[i];
    for (int i = 0; i < kBodyDof; ++i) v[i] = box_v[i];
  }
  const Rot Rb = rotation(pb);
  for (int l = 0; l < robot.nlegs; ++l) {
    const RobotLeg &L = robot.leg[l];
    // the hip axis point, its velocity; the yoke's rotation and angular velocity (world)
    const V3 ph = rb + rotate(Rb, L.hip), vh = vb + cross(wb, ph - rb);
    const Quat py = quat_mul(pb, z_turn(L.yaw + psi[l]));
    const Rot Ry = rotation(py);
    const V3 wy = wb + psid[l] * Rb.c2;
    const V3 ry = ph + rotate(Ry, robot.yoke_com);
    put(q + kBodyConfig * L.yoke, v + kBodyDof * L.yoke, ry, py, vh + cross(wy, ry - ph), rotate_back(Ry, wy));
    const Quat plane = quat_mul(py, kPlane);
    const V3 k_world = rotate(Ry, V3{0, -1, 0});  // the plane's normal (the planar angle's axis)
    for (int b = 0; b < L.nbars; ++b) {
      const real *qp = q_planar[l] + 3 * b, *vp = qd_planar[l] + 3 * b;
      const V3 r = ph + rotate(Ry, V3{robot.origin_x + qp[0], 0, qp[1]});
      const V3 vr = vh + cross(wy, r - ph) + rotate(Ry, V3{vp[0], 0, vp[1]});
      const Quat p = quat_mul(quat_mul(plane, z_turn(qp[2])), kBarAxes);
      const V3 w = rotate_back(rotation(p), wy + vp[2] * k_world);  // body frame
      const int body = L.yoke + 1 + b;
      put(q + kBodyConfig * body, v + kBodyDof * body, r, p, vr, w);
    }
  }
}

namespace {
// Two legs' bodies at once, one in each lane of a pair of reals (lanes.hpp): the vector
// arithmetic rows.hpp's joint kinds call, each lane doing the scalar's operations in its order
// (the same values as on one leg).
using P2 = Pair2;
struct V2 {
  P2 x, y, z;
};
inline V2 operator+(const V2 &a, const V2 &b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V2 operator-(const V2 &a, const V2 &b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V2 operator*(P2 s, const V2 &a) { return {s * a.x, s * a.y, s * a.z}; }
inline P2 dot(const V2 &a, const V2 &b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V2 cross(const V2 &a, const V2 &b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
struct Rot2 {
  V2 c0, c1, c2;
};
inline V2 rotate(const Rot2 &R, const V2 &s) { return s.x * R.c0 + s.y * R.c1 + s.z * R.c2; }
inline V2 rotate_back(const Rot2 &R, const V2 &y) { return {dot(R.c0, y), dot(R.c1, y), dot(R.c2, y)}; }
struct Body2 {
  V2 r, v;
  Rot2 R;
  V2 w;
};
using Jet2 = JetOf<V2>;
using Row2 = RowOf<P2>;
inline V2 pack(const V3 &a, const V3 &b) { return {P2{a.x, b.x}, P2{a.y, b.y}, P2{a.z, b.z}}; }
inline Body2 pack(const BodyState &a, const BodyState &b) {
  return {pack(a.r, b.r), pack(a.v, b.v), {pack(a.R.c0, b.R.c0), pack(a.R.c1, b.R.c1), pack(a.R.c2, b.R.c2)},
          pack(a.w, b.w)};
}
inline void unpack(const Row2 &r, Row &a, Row &b) {
  a.phi = r.phi[0], b.phi = r.phi[1], a.gamma = r.gamma[0], b.gamma = r.gamma[1];
  for (int i = 0; i < kBodyDof; ++i) a.ja[i] = r.ja[i][0], b.ja[i] = r.ja[i][1];
  for (int i = 0; i < kBodyDof; ++i) a.jb[i] = r.jb[i][0], b.jb[i] = r.jb[i][1];
}

// Joint j of a leg and its twin's (jt) on their bodies A and B packed, in lanes.
void joint_rows2(const LegJoint &j, const LegJoint &jt, const Body2 &A, const Body2 &B, Row *out) {
  const V2 sa = pack(j.sa, jt.sa), sb = pack(j.sb, jt.sb), ka = pack(j.ka, jt.ka), ub = pack(j.ub, jt.ub),
           nb = pack(j.nb, jt.nb);
  Row2 r[5];
  switch (j.kind) {  // robot_rows' calls, on the lanes
    case LegJointKind::Revolute:
      revolute_rows(A, sa, ka, B, sb, ub, nb, r);
      break;
    case LegJointKind::Cut:
      planar_cut_rows(A, sa, B, sb, ub, nb, r);
      break;
    case LegJointKind::Prismatic:
      prismatic_rows(A, sa, ka, ub, nb, B, sb, ub, nb, r);
      break;
  }
  for (int i = 0; i < j.nrows; ++i) unpack(r[i], out[j.row + i], out[jt.row + i]);
}
}  // namespace

void robot_rows(const SpatialRobot &robot, const real *q, const real *v, Row *out) {
  BodyState st[kMaxRobotBodies];
  for (int b = 0; b < robot.nb; ++b) st[b] = body_state(q + kBodyConfig * b, v + kBodyDof * b);
  const BodyState world = ground_state();
  for (int l = 0; l < robot.nlegs; ++l) {
    const RobotLeg &L = robot.leg[l];
    if (L.row_twin >= 0) {
      if (L.row_twin < l) continue;  // done with its twin
      const RobotLeg &T = robot.leg[L.row_twin];
      // the two legs' bodies packed once: each joint's body by its offset from its leg's yoke
      // (the box and the world past them)
      Body2 b2[kMaxLegBodies + 2];
      const int nl = 1 + L.nbars;
      for (int b = 0; b < nl; ++b) b2[b] = pack(st[L.yoke + b], st[T.yoke + b]);
      b2[nl] = pack(world, world);
      if (robot.free_box) b2[nl + 1] = pack(st[0], st[0]);
      auto at = [&](int body, int yoke) { return body < 0 ? nl : body < yoke ? nl + 1 : body - yoke; };
      for (int k = 0; k < L.njoints; ++k) {
        const LegJoint &j = robot.joint[L.joint0 + k];
        joint_rows2(j, robot.joint[T.joint0 + k], b2[at(j.a, L.yoke)], b2[at(j.b, L.yoke)], out);
      }
      continue;
    }
    for (int k = L.joint0; k < L.joint0 + L.njoints; ++k) {
      const LegJoint &j = robot.joint[k];
      const BodyState &A = st[j.a], &B = j.b < 0 ? world : st[j.b];
      Row *r = out + j.row;
      switch (j.kind) {
        case LegJointKind::Revolute:
          revolute_rows(A, j.sa, j.ka, B, j.sb, j.ub, j.nb, r);
          break;
        case LegJointKind::Cut:
          planar_cut_rows(A, j.sa, B, j.sb, j.ub, j.nb, r);
          break;
        case LegJointKind::Prismatic:
          prismatic_rows(A, j.sa, j.ka, j.ub, j.nb, B, j.sb, j.ub, j.nb, r);
          break;
      }
    }
  }
}

void robot_phi(const SpatialRobot &robot, const real *q, real *phi) {
  // robot_rows' phi alone: the same expressions (points r + R s, axes R c, their dot products)
  V3 r[kMaxRobotBodies];
  Rot R[kMaxRobotBodies];
  for (int b = 0; b < robot.nb; ++b) {
    const real *qb = q + kBodyConfig * b;
    r[b] = {qb[0], qb[1], qb[2]}, R[b] = rotation({qb[3], qb[4], qb[5], qb[6]});
  }
  const BodyState world = ground_state();
  for (int k = 0; k < robot.nj; ++k) {
    const LegJoint &j = robot.joint[k];
    const V3 &ra = r[j.a], &rb = j.b < 0 ? world.r : r[j.b];
    const Rot &Ra = R[j.a], &Rb = j.b < 0 ? world.R : R[j.b];
    real *o = phi + j.row;
    switch (j.kind) {
      case LegJointKind::Revolute: {
        const V3 d = (ra + rotate(Ra, j.sa)) - (rb + rotate(Rb, j.sb)), ka = rotate(Ra, j.ka);
        o[0] = d.x, o[1] = d.y, o[2] = d.z;
        o[3] = dot(ka, rotate(Rb, j.ub)), o[4] = dot(ka, rotate(Rb, j.nb));
        break;
      }
      case LegJointKind::Cut: {
        const V3 d = (ra + rotate(Ra, j.sa)) - (rb + rotate(Rb, j.sb));
        o[0] = dot(d, rotate(Rb, j.ub)), o[1] = dot(d, rotate(Rb, j.nb));
        break;
      }
      case LegJointKind::Prismatic: {
        // prismatic_rows': the cylinder a's axes (u, n, k) = (ka, ub, nb), the rod b's (ub, nb)
        const V3 ua = rotate(Ra, j.ka), na = rotate(Ra, j.ub), nb = rotate(Rb, j.ub), kb = rotate(Rb, j.nb);
        const V3 d = (rb + rotate(Rb, j.sb)) - (ra + rotate(Ra, j.sa));
        o[0] = dot(ua, nb), o[1] = dot(ua, kb), o[2] = dot(na, kb);
        o[3] = dot(d, na), o[4] = dot(d, rotate(Ra, j.nb));
        break;
      }
    }
  }
}

real robot_rowing_angle(const SpatialRobot &robot, int l, const real *q) {
  const Rot Rb = robot.free_box ? rotation({q[3], q[4], q[5], q[6]}) : Rot{kX, kY, kZ};
  const real *qy = q + kBodyConfig * robot.leg[l].yoke;
  const V3 x = rotate_back(Rb, rotation({qy[3], qy[4], qy[5], qy[6]}).c0);
  return std::remainder(std::atan2(x.y, x.x) - robot.leg[l].yaw, 2 * real(3.14159265358979323846));
}

real robot_actuator_length(const SpatialRobot &robot, int a, const real *q) {
  const RobotActuator &ac = robot.act[a];
  const real zero[kBodyDof] = {0, 0, 0, 0, 0, 0};
  const BodyState rod = body_state(q + kBodyConfig * ac.rod, zero), cyl = body_state(q + kBodyConfig * ac.cyl, zero);
  return actuator_row(rod, cyl).phi + ac.offset;
}

real robot_actuator_rate(const SpatialRobot &robot, int a, const real *q, const real *v) {
  const RobotActuator &ac = robot.act[a];
  const BodyState rod = body_state(q + kBodyConfig * ac.rod, v + kBodyDof * ac.rod);
  const BodyState cyl = body_state(q + kBodyConfig * ac.cyl, v + kBodyDof * ac.cyl);
  const Row r = actuator_row(rod, cyl);
  real s = 0;
  for (int i = 0; i < kBodyDof; ++i) s += r.ja[i] * v[kBodyDof * ac.rod + i] + r.jb[i] * v[kBodyDof * ac.cyl + i];
  return s;
}

real robot_rowing_rate(const SpatialRobot &robot, int l, const real *q, const real *v) {
  // the yoke's angular velocity less the box's, about the box's z (both in the world)
  const real *qy = q + kBodyConfig * robot.leg[l].yoke, *vy = v + kBodyDof * robot.leg[l].yoke;
  const V3 wy = rotate(rotation({qy[3], qy[4], qy[5], qy[6]}), V3{vy[3], vy[4], vy[5]});
  if (!robot.free_box) return wy.z;
  const Rot Rb = rotation({q[3], q[4], q[5], q[6]});
  const V3 wb = rotate(Rb, V3{v[3], v[4], v[5]});
  return dot(wy - wb, Rb.c2);
}

void robot_forces(const SpatialRobot &robot, const real *q, const real *v, const real *force_n,
                  const real *rowing_nm, real *Q) {
  for (int b = 0; b < robot.nb; ++b) {
    real *f = Q + kBodyDof * b;
    const real *w = v + kBodyDof * b + 3;
    const V3 &I = robot.inertia[b];
    const real m = robot.mass[b];
    const V3 Iw = {I.x * w[0], I.y * w[1], I.z * w[2]};
    const V3 gyro = -1 * cross({w[0], w[1], w[2]}, Iw);
    const real fb[kBodyDof] = {m * robot.gravity.x, m * robot.gravity.y, m * robot.gravity.z, gyro.x, gyro.y, gyro.z};
    for (int i = 0; i < kBodyDof; ++i) f[i] = fb[i];
  }
  // an actuator: F times its length's gradient (actuator_row's coefficients)
  for (int a = 0; a < robot.na; ++a) {
    const RobotActuator &ac = robot.act[a];
    const BodyState rod = body_state(q + kBodyConfig * ac.rod, v + kBodyDof * ac.rod);
    const BodyState cyl = body_state(q + kBodyConfig * ac.cyl, v + kBodyDof * ac.cyl);
    const Row r = actuator_row(rod, cyl);
    for (int i = 0; i < kBodyDof; ++i) {
      Q[kBodyDof * ac.rod + i] += force_n[a] * r.ja[i];
      Q[kBodyDof * ac.cyl + i] += force_n[a] * r.jb[i];
    }
  }
  // a rowing torque about the hip axis: the yoke's z, and the box's z
  for (int l = 0; l < robot.nlegs; ++l) {
    Q[kBodyDof * robot.leg[l].yoke + 5] += rowing_nm[l];
    if (robot.free_box) Q[5] -= rowing_nm[l];
  }
}

}  // namespace legsim::spatial
