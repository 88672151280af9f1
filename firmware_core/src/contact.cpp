// Foot contact with the ground line: where a foot is, which rows each contact
// adds to the dynamics (a stuck foot: its normal and tangential rows), and the
// ground forces from their multipliers. docs/design/robot-on-ground.md.
#include "sim.hpp"

namespace legsim {

void contact_point(const Model &model, int k, const VecQ &q, const VecQ &qd, Vec2 &pos, Vec2 &vel) {
  const Contact &c = model.contact[k];
  const int b = c.body;
  const real phi = q[3 * b + 2];
  const Vec2 s = c.point.x() * axis_u(phi) + c.point.y() * normal_n(phi);
  pos = Vec2(q[3 * b], q[3 * b + 1]) + s;
  vel = Vec2(qd[3 * b], qd[3 * b + 1]) + qd[3 * b + 2] * perp(s);
}

void contact_rows_of_states(const Model &model, const Data &d, uint8_t *rows) {
  for (int k = 0; k < model.nc; ++k)
    rows[k] = d.contact[k].state == LEGSIM_CONTACT_STUCK ? kContactStuck : kContactNone;
}

// The rows of Data::dyn: joints, stops (one per actuator in stop_mask), contacts.
// The multipliers are the constraint forces with the sign of -J^T lambda: the
// ground force on the foot is -(lambda_n n + lambda_t t).
void contact_forces_update(Sim &sim) {
  const Model &m = sim.model;
  Data &d = sim.data;
  int row = m.m;
  for (int a = 0; a < m.na; ++a) row += (d.stop_mask >> a) & 1u;
  for (int k = 0; k < m.nc; ++k) {
    ContactData &c = d.contact[k];
    if (c.state == LEGSIM_CONTACT_STUCK) {
      c.normal = -d.lambda[row];
      c.tangential = -d.lambda[row + 1];
      row += 2;
    } else {
      c.normal = c.tangential = 0;
    }
  }
}

void contacts_free(Sim &sim) {
  Data &d = sim.data;
  for (int k = 0; k < kMaxContacts; ++k) d.contact[k] = {uint8_t(LEGSIM_CONTACT_FREE), 0, 0, 0, {0, 0}};
}

void contact_forces_of_layout(const Model &model, const Layout &layout, const VecR &lambda,
                              real *normal, real *tangential) {
  for (int k = 0; k < model.nc; ++k) normal[k] = tangential[k] = 0;
  for (int i = model.m; i < layout.m; ++i) {
    const RowSource &r = layout.src[i];
    if (r.kind == RowKind::ContactNormal) normal[r.index] = -lambda[i];
    if (r.kind == RowKind::ContactTangent) tangential[r.index] = -lambda[i];
  }
}

}  // namespace legsim
