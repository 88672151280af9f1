// Constraint equations Phi(q) = 0 of a layout: its rows (the joints', then the drivers'
// and the contacts') from the row units (rows.hpp), which the generated kernels call too.
#include "planar/kernel.hpp"
#include "planar/rows.hpp"

namespace legsim {

void trig_clear(TrigCache &t) {
  for (int b = 0; b < kMaxBodies; ++b) {
    t.phi[b] = t.s[b] = t.c[b] = t.grid_s[b] = t.grid_c[b] = real(NAN);
    t.grid[b] = INT32_MIN;
  }
}

namespace {

BodyPose pose_of(const VecQ &q, const VecQ &qd, int b, TrigCache *trig) {  // one sin/cos pair per body
  real s, c;
  body_trig(trig, b, q[kBodyDof * b + 2], s, c);
  BodyPose p = body_pose(q, b, s, c);
  body_velocity(p, qd[kBodyDof * b], qd[kBodyDof * b + 1], qd[kBodyDof * b + 2]);
  return p;
}

// A unit's rows into Rows from row `row` on (slot 1 only where the rows have a second body).
void store(const JointRows &j, int nrows, bool two, int row, Rows &out) {
  for (int k = 0; k < nrows; ++k) {
    for (int x = 0; x < kBodyDof; ++x) out.coef[row + k][0][x] = j.coef[k][0][x];
    if (two)
      for (int x = 0; x < kBodyDof; ++x) out.coef[row + k][1][x] = j.coef[k][1][x];
    out.phi[row + k] = j.phi[k];
    out.gamma[row + k] = j.gamma[k];
    out.nu[row + k] = 0;
  }
}

void joint_rows(const Joint &j, const BodyPose *pose, int row, Rows &out) {
  JointRows r;
  const BodyPose &a = pose[j.a];
  switch (j.kind) {
    case LEGSIM_JOINT_REVOLUTE_TO_FRAME:
    case LEGSIM_JOINT_REVOLUTE: {
      const BodyPose *b = j.b == LEGSIM_FRAME ? nullptr : &pose[j.b];
      revolute_position(j, a, b, r);
      revolute_gamma(a, b, r);
      store(r, 2, b, row, out);
      break;
    }
    case LEGSIM_JOINT_PRISMATIC:
      prismatic_position(a, pose[j.b], r);
      prismatic_gamma(a, pose[j.b], r);
      store(r, 2, true, row, out);
      break;
    case LEGSIM_JOINT_SLOT:
      slot_position(j, a, pose[j.b], r);
      slot_gamma(a, pose[j.b], r);
      store(r, 1, true, row, out);
      break;
  }
}

void actuator_rows(const Actuator &ac, const DriverValues &dv, int index, const BodyPose *pose, int row,
                   Rows &out) {
  JointRows r;
  actuator_position(ac, dv.length[index], pose[ac.cyl], pose[ac.rod], r);
  actuator_gamma(dv.accel[index], pose[ac.cyl], pose[ac.rod], r);
  store(r, 1, true, row, out);
  out.nu[row] = dv.rate[index];
}

// Contact k's row along e into slot `slot` of row `row`, summed onto the slots before it.
void contact_rows(const Model &m, const Vec2 &e, int k, const BodyPose *pose, real target, int slot,
                  real weight, int row, Rows &out) {
  const Contact &c = m.contact[k];
  ContactRow r;
  contact_row(c.point, m.ground_point, e, slot == 0 ? target : real(0), weight, pose[c.body], r);
  if (slot == 0) out.phi[row] = out.gamma[row] = 0;
  out.phi[row] += r.phi;
  for (int x = 0; x < kBodyDof; ++x) out.coef[row][slot][x] = r.coef[x];
  out.gamma[row] += r.gamma;
  out.nu[row] = 0;
}

// The foot's point along world x (sub 0) or y (1) at its target: contact_row's unit (a body
// point along a direction) from the origin.
void foot_rows(const Model &m, const DriverValues &dv, int sub, const BodyPose *pose, int row, Rows &out) {
  ContactRow r;
  contact_row(m.foot_point, Vec2(0, 0), sub == 0 ? Vec2(1, 0) : Vec2(0, 1), dv.foot[sub], 1, pose[m.foot_body], r);
  out.phi[row] = r.phi;
  for (int x = 0; x < kBodyDof; ++x) out.coef[row][0][x] = r.coef[x];
  out.gamma[row] = r.gamma;
  out.nu[row] = 0;
}

void coordinate_rows(const legsim_coord_driver &c, const VecQ &q, int row, Rows &out) {
  out.phi[row] = coordinate_phi(c, q);
  out.coef[row][0][0] = out.coef[row][0][1] = out.coef[row][0][2] = 0;
  out.coef[row][0][c.coord] = 1;
  out.nu[row] = out.gamma[row] = 0;
}

}  // namespace

legsim_status layout_build(const Model &model, uint32_t actuator_mask, int ncoord, Layout &out,
                           const uint8_t *contacts, bool mid, bool foot) {
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
  // the foot at a point: its x and y rows
  for (int r = 0; foot && r < 2; ++r) {
    if (m >= kMaxRows || model.foot_body < 0) return LEGSIM_ERR_CAPACITY;
    out.src[m] = {RowKind::FootPoint, 0, uint8_t(r)};
    out.body[m][0] = int8_t(model.foot_body);
    out.body[m][1] = -1;
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
  out.block = RowIndex(stance && (kernel_find(model, true) || !kernel_find(model)) ? m : 0);
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
        joint_rows(j, pose, i, rows);
        i += j.nrows;
        break;
      }
      case RowKind::ActuatorLength:
        actuator_rows(model.act[s.index], dv, s.index, pose, i, rows);
        ++i;
        break;
      case RowKind::Coordinate:
        coordinate_rows(dv.coord[s.index], q, i, rows);
        ++i;
        break;
      case RowKind::ContactNormal:
        contact_rows(model, model.ground_n, s.index, pose, 0, 0, 1, i, rows);
        ++i;
        break;
      case RowKind::ContactTangent:
        contact_rows(model, model.ground_t, s.index, pose, dv.stick[s.index], 0, 1, i, rows);
        ++i;
        break;
      case RowKind::FootPoint:
        foot_rows(model, dv, s.sub, pose, i, rows);
        ++i;
        break;
      case RowKind::ContactMid: {
        const real w = model.nc > 1 ? real(0.5) : real(1);
        contact_rows(model, model.ground_t, 0, pose, dv.feet_mid, 0, w, i, rows);
        if (model.nc > 1) contact_rows(model, model.ground_t, model.nc - 1, pose, dv.feet_mid, 1, w, i, rows);
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
  const XY d = {r.r.x - c.r.x, r.r.y - c.r.y}, dd = {r.rd.x - c.rd.x, r.rd.y - c.rd.y};
  length = dot(d, c.u) + ac.offset_m;
  rate = dot(dd, c.u) + c.w * dot(d, c.n);
}

}  // namespace legsim
