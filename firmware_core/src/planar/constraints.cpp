// Constraint equations Phi(q) = 0: one small unit per joint kind with its rows,
// Jacobian coefficients and acceleration right-hand side gamma (Phi_q qdd = gamma),
// plus the driver rows (actuator lengths, coordinates) appended after them.
#include "planar/kernel.hpp"

namespace legsim {

void trig_clear(TrigCache &t) {
  for (int b = 0; b < kMaxBodies; ++b) {
    t.phi[b] = t.s[b] = t.c[b] = t.grid_s[b] = t.grid_c[b] = real(NAN);
    t.grid[b] = INT32_MIN;
  }
}

namespace {

struct BodyPose {
  Vec2 r, rd;   // centre and its velocity
  real phi, w;  // angle and angular velocity
  Vec2 u, n;
};

BodyPose pose_of(const VecQ &q, const VecQ &qd, int b, TrigCache *trig) {  // one sin/cos pair per body
  BodyPose p;
  p.r = Vec2(q[3 * b], q[3 * b + 1]);
  p.rd = Vec2(qd[3 * b], qd[3 * b + 1]);
  p.phi = q[3 * b + 2];
  p.w = qd[3 * b + 2];
  real s, c;
  body_trig(trig, b, p.phi, s, c);
  p.u = Vec2(s, -c);  // axis_u
  p.n = Vec2(c, s);   // normal_n
  return p;
}

// Body-fixed (xi, eta) to a world-axes offset from the centre.
Vec2 offset(const BodyPose &p, const Vec2 &xi_eta) { return xi_eta.x() * p.u + xi_eta.y() * p.n; }

void set_coef(real (&c)[3], const Vec2 &g, real gphi) {
  c[0] = g.x();
  c[1] = g.y();
  c[2] = gphi;
}

// Revolute (eqs. (2)-(11)): point on a = point on b (or a frame point).
// Phi = ra + sa - rb - sb; gamma = wa^2 sa - wb^2 sb.
void revolute_rows(const Joint &j, const BodyPose *pose, int row, Rows &out) {
  const BodyPose &a = pose[j.a];
  const Vec2 sa = offset(a, j.pa);
  Vec2 phi = a.r + sa, gamma = a.w * a.w * sa;
  Vec2 sb = Vec2::Zero();
  if (j.b == LEGSIM_FRAME) {
    phi -= j.pb;
  } else {
    const BodyPose &b = pose[j.b];
    sb = offset(b, j.pb);
    phi -= b.r + sb;
    gamma -= b.w * b.w * sb;
    const Vec2 psb = perp(sb);
    set_coef(out.coef[row][1], Vec2(-1, 0), -psb.x());
    set_coef(out.coef[row + 1][1], Vec2(0, -1), -psb.y());
  }
  const Vec2 psa = perp(sa);
  set_coef(out.coef[row][0], Vec2(1, 0), psa.x());
  set_coef(out.coef[row + 1][0], Vec2(0, 1), psa.y());
  out.phi[row] = phi.x();
  out.phi[row + 1] = phi.y();
  out.gamma[row] = gamma.x();
  out.gamma[row + 1] = gamma.y();
  out.nu[row] = out.nu[row + 1] = 0;
}

// Prismatic (eqs. (12)-(16)): phi_b - phi_a = 0 and (rb - ra) . na = 0.
void prismatic_rows(const Joint &j, const BodyPose *pose, int row, Rows &out) {
  const BodyPose &a = pose[j.a], &b = pose[j.b];
  const Vec2 d = b.r - a.r, dd = b.rd - a.rd;
  out.phi[row] = b.phi - a.phi;
  set_coef(out.coef[row][0], Vec2::Zero(), -1);
  set_coef(out.coef[row][1], Vec2::Zero(), 1);
  out.gamma[row] = 0;
  out.phi[row + 1] = d.dot(a.n);
  set_coef(out.coef[row + 1][0], -a.n, -d.dot(a.u));
  set_coef(out.coef[row + 1][1], a.n, 0);
  out.gamma[row + 1] = 2 * a.w * dd.dot(a.u) + a.w * a.w * d.dot(a.n);
  out.nu[row] = out.nu[row + 1] = 0;
}

// Slot (eq. (18)): point on a lies on the axis of b: (ra + sa - rb) . nb = 0.
void slot_rows(const Joint &j, const BodyPose *pose, int row, Rows &out) {
  const BodyPose &a = pose[j.a], &b = pose[j.b];
  const Vec2 sa = offset(a, j.pa);
  const Vec2 d = a.r + sa - b.r;
  const Vec2 dd = a.rd + a.w * perp(sa) - b.rd;
  out.phi[row] = d.dot(b.n);
  set_coef(out.coef[row][0], b.n, perp(sa).dot(b.n));
  set_coef(out.coef[row][1], -b.n, -d.dot(b.u));
  out.gamma[row] = a.w * a.w * sa.dot(b.n) + 2 * b.w * dd.dot(b.u) + b.w * b.w * d.dot(b.n);
  out.nu[row] = 0;
}

// Actuator length driver: (r_rod - r_cyl) . u_cyl + offset - l(t) = 0.
void actuator_row(const Actuator &ac, const DriverValues &dv, int index, const BodyPose *pose,
                  int row, Rows &out) {
  const BodyPose &a = pose[ac.cyl], &b = pose[ac.rod];
  const Vec2 d = b.r - a.r, dd = b.rd - a.rd;
  out.phi[row] = d.dot(a.u) + ac.offset_m - dv.length[index];
  set_coef(out.coef[row][0], -a.u, d.dot(a.n));
  set_coef(out.coef[row][1], a.u, 0);
  out.nu[row] = dv.rate[index];
  out.gamma[row] = dv.accel[index] - 2 * a.w * dd.dot(a.n) + a.w * a.w * d.dot(a.u);
}

// Contact rows: a foot point p = r + s on the ground line through g along t, normal n.
// Normal: n.(p - g) = 0; tangential: t.(p - g) - stick = 0; both with gamma = w^2 e.s.
void contact_row(const Model &m, const Vec2 &e, int k, const BodyPose *pose, real target,
                 int slot, real weight, int row, Rows &out) {
  const Contact &c = m.contact[k];
  const BodyPose &b = pose[c.body];
  const Vec2 sp = offset(b, c.point);
  if (slot == 0) out.phi[row] = out.gamma[row] = 0;
  out.phi[row] += weight * e.dot(b.r + sp - m.ground_point) - (slot == 0 ? target : real(0));
  set_coef(out.coef[row][slot], weight * e, weight * e.dot(perp(sp)));
  out.gamma[row] += weight * b.w * b.w * e.dot(sp);
  out.nu[row] = 0;
}

void coordinate_row(const legsim_coord_driver &c, const VecQ &q, int row, Rows &out) {
  const int k = 3 * c.body + c.coord;
  out.phi[row] = q[k] - real(c.value);
  out.coef[row][0][0] = out.coef[row][0][1] = out.coef[row][0][2] = 0;
  out.coef[row][0][c.coord] = 1;
  out.nu[row] = out.gamma[row] = 0;
}

}  // namespace

legsim_status layout_build(const Model &model, uint32_t actuator_mask, int ncoord, Layout &out,
                           const uint8_t *contacts, bool mid) {
  int m = 0;
  for (int j = 0; j < model.nj; ++j) {
    const Joint &jt = model.joint[j];
    for (int s = 0; s < jt.nrows; ++s, ++m) {
      out.src[m] = {RowKind::Joint, uint8_t(j), uint8_t(s)};
      out.body[m][0] = int8_t(jt.a);
      // a prismatic joint's angle row and every row of a frame joint touch both bodies or one
      out.body[m][1] = int8_t(jt.b == LEGSIM_FRAME ? -1 : jt.b);
    }
  }
  for (int a = 0; a < model.na; ++a) {
    if (!(actuator_mask & (1u << a))) continue;
    if (m >= kMaxRows) return LEGSIM_ERR_CAPACITY;
    out.src[m] = {RowKind::ActuatorLength, uint8_t(a), 0};
    out.body[m][0] = int8_t(model.act[a].cyl);
    out.body[m][1] = int8_t(model.act[a].rod);
    ++m;
  }
  // coordinate drivers: the body is filled in by the caller's driver values
  for (int c = 0; c < ncoord; ++c) {
    if (m >= kMaxRows) return LEGSIM_ERR_CAPACITY;
    out.src[m] = {RowKind::Coordinate, uint8_t(c), 0};
    out.body[m][0] = -1;
    out.body[m][1] = -1;
    ++m;
  }
  // contacts: the normal row, then (stuck) the tangential one
  for (int k = 0; contacts && k < model.nc; ++k)
    for (int r = 0; r < contacts[k]; ++r) {
      if (m >= kMaxRows) return LEGSIM_ERR_CAPACITY;
      out.src[m] = {r == 0 ? RowKind::ContactNormal : RowKind::ContactTangent, uint8_t(k), 0};
      out.body[m][0] = int8_t(model.contact[k].body);
      out.body[m][1] = -1;
      ++m;
    }
  // assembly on the ground: the midpoint of the outer feet (the first and the last) along
  // the line
  if (mid) {
    if (m >= kMaxRows || model.nc < 1) return LEGSIM_ERR_CAPACITY;
    out.src[m] = {RowKind::ContactMid, 0, 0};
    out.body[m][0] = int8_t(model.contact[0].body);
    out.body[m][1] = int8_t(model.nc > 1 ? model.contact[model.nc - 1].body : -1);
    ++m;
  }
  out.m = m;
  out.kernel = model.kernel;
  // every contact stuck and nothing else after the joints: a stance, whose rows the stance
  // kernel serves; its contact rows are ordered with the joint rows (layout_finish) where
  // the build has a stance kernel for the structure, or no kernel at all (not after a joint
  // kernel's block in a build without stance kernels): the general path orders as the
  // kernel it stands in for
  bool stance = LEGSIM_MAX_CONTACTS > 0 && model.nc > 0 && contacts && !mid && ncoord == 0 && actuator_mask == 0;
  for (int k = 0; stance && k < model.nc; ++k) stance = contacts[k] == kContactStuck;
  if (stance && model.stance_kernel) out.kernel = model.stance_kernel;
  out.block = uint8_t(stance && (kernel_find(model, true) || !kernel_find(model)) ? m : 0);
  out.npairs = 0;
  out.stops = false;
  out.nslide = 0;
  layout_path(out);
  return LEGSIM_OK;
}

void rows_eval(const Model &model, const Layout &layout, const DriverValues &dv, const VecQ &q,
               const VecQ &qd, Rows &rows, TrigCache *trig) {
  int i = 0;
  if (layout.kernel) {
    layout.kernel->rows(model, dv, q, qd, rows, trig);
    i = layout.kernel->mj;
    if (i == layout.m) return;
  }
  BodyPose pose[kMaxBodies];
  if (i == 0) {
    for (int b = 0; b < model.nb; ++b) pose[b] = pose_of(q, qd, b, trig);
  } else {  // only the bodies of the rows after the kernel's: one sin/cos pair each
    bool have[kMaxBodies] = {};
    for (int r = i; r < layout.m; ++r)
      for (int sl = 0; sl < 2; ++sl) {
        const int b = layout.body[r][sl];
        if (b >= 0 && !have[b]) {
          pose[b] = pose_of(q, qd, b, trig);
          have[b] = true;
        }
      }
  }
  while (i < layout.m) {
    const RowSource &s = layout.src[i];
    switch (s.kind) {
      case RowKind::Joint: {
        const Joint &j = model.joint[s.index];
        switch (j.kind) {
          case LEGSIM_JOINT_REVOLUTE_TO_FRAME:
          case LEGSIM_JOINT_REVOLUTE: revolute_rows(j, pose, i, rows); break;
          case LEGSIM_JOINT_PRISMATIC: prismatic_rows(j, pose, i, rows); break;
          case LEGSIM_JOINT_SLOT: slot_rows(j, pose, i, rows); break;
        }
        i += j.nrows;
        break;
      }
      case RowKind::ActuatorLength:
        actuator_row(model.act[s.index], dv, s.index, pose, i, rows);
        ++i;
        break;
      case RowKind::Coordinate:
        coordinate_row(dv.coord[s.index], q, i, rows);
        ++i;
        break;
      case RowKind::ContactNormal:
        contact_row(model, model.ground_n, s.index, pose, 0, 0, 1, i, rows);
        ++i;
        break;
      case RowKind::ContactTangent:
        contact_row(model, model.ground_t, s.index, pose, dv.stick[s.index], 0, 1, i, rows);
        ++i;
        break;
      case RowKind::ContactMid: {
        const real w = model.nc > 1 ? real(0.5) : real(1);
        contact_row(model, model.ground_t, 0, pose, dv.feet_mid, 0, w, i, rows);
        if (model.nc > 1) contact_row(model, model.ground_t, model.nc - 1, pose, dv.feet_mid, 1, w, i, rows);
        ++i;
        break;
      }
    }
  }
}

real rows_max_residual(const Layout &layout, const Rows &rows) {
  real r = 0;
  for (int i = 0; i < layout.m; ++i) {
    const real a = std::abs(rows.phi[i]);
    if (!(a <= r)) r = a;  // NaN propagates
  }
  return r;
}

void actuator_length(const Model &model, int a, const VecQ &q, const VecQ &qd, real &length,
                     real &rate, TrigCache *trig) {
  const Actuator &ac = model.act[a];
  const BodyPose c = pose_of(q, qd, ac.cyl, trig), r = pose_of(q, qd, ac.rod, trig);
  const Vec2 d = r.r - c.r, dd = r.rd - c.rd;
  length = d.dot(c.u) + ac.offset_m;
  rate = dd.dot(c.u) + c.w * d.dot(c.n);
}

}  // namespace legsim
