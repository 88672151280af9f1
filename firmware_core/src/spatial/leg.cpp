#include "spatial/leg.hpp"

namespace legsim::spatial {

namespace {
constexpr V3 kX = {1, 0, 0}, kY = {0, 1, 0}, kZ = {0, 0, 1};
// A bar's body axes (u, n, k) in its frame.
constexpr V3 kU = {1, 0, 0}, kN = {0, 1, 0}, kK = {0, 0, 1};

// A planar point (x, y) of the leg's frame in the yoke's frame, from the yoke's centre of mass.
V3 plane_point(const SpatialLeg &leg, const double *xy) {
  return V3{leg.origin.x + real(xy[0]), 0, leg.origin.z + real(xy[1])} - leg.yoke_com;
}

// Union-find over the leg's bodies (0: the yoke, which the frame joints reach).
int find(int *parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

Quat z_turn(real psi) { return {std::cos(real(0.5) * psi), 0, 0, std::sin(real(0.5) * psi)}; }
// the yoke's plane: planar (x, y, z) to the yoke's (x, z, -y): +90 degrees about x
const Quat kPlane = {real(0.70710678118654752440), real(0.70710678118654752440), 0, 0};
// a bar's (u, n, k) from the plane's axes at angle 0: u = -y, n = x (-90 degrees about z)
const Quat kBarAxes = {real(0.70710678118654752440), 0, 0, -real(0.70710678118654752440)};
}  // namespace

legsim_status leg_lift(const legsim_model_desc &desc, const YokeDesc &yoke, SpatialLeg &out) {
  const int nbar = desc.n_bodies;
  if (nbar < 1 || nbar + 1 > kMaxLegBodies || desc.n_joints + 1 > kMaxLegJoints) return LEGSIM_ERR_CAPACITY;
  if (desc.gravity_mps2[0] != 0) return LEGSIM_ERR_MODEL;  // the leg's plane is vertical
  SpatialLeg &L = out;
  L.nb = nbar + 1;
  L.gravity = {0, 0, real(desc.gravity_mps2[1])};
  L.yoke_com = {real(yoke.com_m[0]), real(yoke.com_m[1]), real(yoke.com_m[2])};
  L.origin = {real(yoke.hip_offset_m), 0, 0};
  L.mass[0] = real(yoke.mass_kg);
  L.inertia[0] = {real(yoke.inertia_kgm2[0]), real(yoke.inertia_kgm2[1]), real(yoke.inertia_kgm2[2])};
  for (int b = 0; b < nbar; ++b) {
    const legsim_body_desc &bd = desc.body[b];
    L.mass[b + 1] = real(bd.mass_kg);
    // about u a tube's; about n and k the planar inertia (the planar dynamics unchanged)
    L.inertia[b + 1] = {real(0.5 * bd.mass_kg * yoke.bar_radius_m * yoke.bar_radius_m), real(bd.inertia_kgm2),
                        real(bd.inertia_kgm2)};
  }
  int parent[kMaxLegBodies];
  for (int i = 0; i < L.nb; ++i) parent[i] = i;
  int nj = 0, row = 0;
  auto add = [&](const LegJoint &j, int nrows) {
    L.joint[nj] = j;
    L.joint[nj].row = row;
    L.joint[nj].nrows = nrows;
    ++nj;
    row += nrows;
  };
  // the yoke about the box's vertical through the origin: its axis point (the origin) is -com
  add({LegJointKind::Revolute, 0, -1, -1 * L.yoke_com, {0, 0, 0}, kZ, kX, kY, 0, 0}, 5);
  for (int k = 0; k < desc.n_joints; ++k) {
    const legsim_joint_desc &jd = desc.joint[k];
    const int a = jd.body[0] + 1;
    const V3 sa = {real(jd.point[0][0]), real(jd.point[0][1]), 0};
    switch (jd.kind) {
      case LEGSIM_JOINT_REVOLUTE_TO_FRAME: {
        // to the yoke, about the plane's normal; the yoke's in-plane axes x and z across it
        parent[find(parent, a)] = find(parent, 0);
        add({LegJointKind::Revolute, a, 0, sa, plane_point(L, jd.point[1]), kK, kX, kZ, 0, 0}, 5);
        break;
      }
      case LEGSIM_JOINT_REVOLUTE: {
        const int b = jd.body[1] + 1;
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
        const int b = jd.body[1] + 1;
        const int ra = find(parent, a), rb = find(parent, b);
        if (ra == rb) return LEGSIM_ERR_MODEL;
        parent[ra] = rb;
        add({LegJointKind::Prismatic, a, b, {0, 0, 0}, {0, 0, 0}, kU, kN, kK, 0, 0}, 5);
        break;
      }
      default:
        return LEGSIM_ERR_MODEL;  // a slot has no spatial row unit yet
    }
  }
  if (row > kMaxLegRows) return LEGSIM_ERR_CAPACITY;
  L.nj = nj;
  L.m = row;
  return LEGSIM_OK;
}

void leg_state(const SpatialLeg &leg, const real *q_planar, const real *qd_planar, real psi, real psid, real *q,
               real *v) {
  const Quat yaw = z_turn(psi);
  const Rot Ryaw = rotation(yaw);
  const V3 wz = {0, 0, psid};
  // the yoke: its centre of mass turned about the axis
  const V3 r0 = rotate(Ryaw, leg.yoke_com), v0 = cross(wz, r0);
  const real y0[kBodyConfig] = {r0.x, r0.y, r0.z, yaw.w, yaw.x, yaw.y, yaw.z};
  const real w0[kBodyDof] = {v0.x, v0.y, v0.z, 0, 0, psid};
  for (int i = 0; i < kBodyConfig; ++i) q[i] = y0[i];
  for (int i = 0; i < kBodyDof; ++i) v[i] = w0[i];
  const Quat plane = quat_mul(yaw, kPlane);
  const V3 k_world = rotate(Ryaw, V3{0, -1, 0});  // the plane's normal (the planar angle's axis)
  for (int b = 1; b < leg.nb; ++b) {
    const real *qp = q_planar + 3 * (b - 1), *vp = qd_planar + 3 * (b - 1);
    const V3 r = rotate(Ryaw, V3{leg.origin.x + qp[0], 0, leg.origin.z + qp[1]});
    const V3 vr = rotate(Ryaw, V3{vp[0], 0, vp[1]}) + cross(wz, r);
    const Quat p = quat_mul(quat_mul(plane, z_turn(qp[2])), kBarAxes);
    const V3 w = rotate_back(rotation(p), wz + vp[2] * k_world);  // body frame
    real *qb = q + kBodyConfig * b, *vb = v + kBodyDof * b;
    const real c[kBodyConfig] = {r.x, r.y, r.z, p.w, p.x, p.y, p.z};
    const real s[kBodyDof] = {vr.x, vr.y, vr.z, w.x, w.y, w.z};
    for (int i = 0; i < kBodyConfig; ++i) qb[i] = c[i];
    for (int i = 0; i < kBodyDof; ++i) vb[i] = s[i];
  }
}

void leg_rows(const SpatialLeg &leg, const real *q, const real *v, Row *out) {
  BodyState st[kMaxLegBodies];
  for (int b = 0; b < leg.nb; ++b) st[b] = body_state(q + kBodyConfig * b, v + kBodyDof * b);
  const BodyState box = ground_state();
  for (int k = 0; k < leg.nj; ++k) {
    const LegJoint &j = leg.joint[k];
    const BodyState &A = st[j.a], &B = j.b < 0 ? box : st[j.b];
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

}  // namespace legsim::spatial
