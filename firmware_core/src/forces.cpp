// Generalized applied forces Q: gravity, force elements and actuator forces.
#include "sim.hpp"

namespace legsim {
namespace {

Vec2 body_offset(const VecQ &q, int b, const Vec2 &xi_eta, TrigCache *trig) {
  real s, c;
  body_trig(trig, b, q[3 * b + 2], s, c);                      // the stage's pair (TrigCache)
  return xi_eta.x() * Vec2(s, -c) + xi_eta.y() * Vec2(c, s);  // axis_u, normal_n
}

// A force F (world axes) at offset s from the centre of body b: (F, s x F).
void add_point_force(VecQ &force_q, int b, const Vec2 &s, const Vec2 &f) {
  force_q[3 * b] += f.x();
  force_q[3 * b + 1] += f.y();
  force_q[3 * b + 2] += cross2(s, f);
}

#if LEGSIM_WITH_FORCE_ELEMENTS
// World position and velocity of a point on a body (or fixed on the frame).
void point_state(const VecQ &q, const VecQ &qd, int b, const Vec2 &p, Vec2 &s, Vec2 &pos, Vec2 &vel,
                 TrigCache *trig) {
  if (b == LEGSIM_FRAME) {
    s = Vec2::Zero();
    pos = p;
    vel = Vec2::Zero();
    return;
  }
  s = body_offset(q, b, p, trig);
  pos = Vec2(q[3 * b], q[3 * b + 1]) + s;
  vel = Vec2(qd[3 * b], qd[3 * b + 1]) + qd[3 * b + 2] * perp(s);
}

void add_force_elements(const Model &model, const Data &d, const VecQ &q, const VecQ &qd,
                        VecQ &force_q, TrigCache *trig) {
  for (int i = 0; i < model.nf; ++i) {
    const ForceElement &fe = model.force[i];
    const real *v = d.force_value[i];
    switch (fe.kind) {
      case LEGSIM_FORCE_POINT:
        add_point_force(force_q, fe.a, body_offset(q, fe.a, fe.pa, trig), Vec2(v[0], v[1]));
        break;
      case LEGSIM_FORCE_TORQUE: force_q[3 * fe.a + 2] += v[0]; break;
      case LEGSIM_FORCE_SPRING_DAMPER: {
        Vec2 sa, pa, va, sb, pb, vb;
        point_state(q, qd, fe.a, fe.pa, sa, pa, va, trig);
        point_state(q, qd, fe.b, fe.pb, sb, pb, vb, trig);
        const Vec2 dvec = pb - pa;
        const real len = dvec.norm();
        if (!(len > 0)) break;  // coincident points: no defined direction, no force
        const Vec2 e = dvec / len;
        const real tension = fe.k * (len - fe.l0) + fe.c * e.dot(vb - va);
        if (fe.a != LEGSIM_FRAME) add_point_force(force_q, fe.a, sa, tension * e);
        if (fe.b != LEGSIM_FRAME) add_point_force(force_q, fe.b, sb, -tension * e);
        break;
      }
    }
  }
}
#endif

}  // namespace

void applied_forces(const Model &model, const legsim_options &opt, Data &d, const VecQ &q,
                    const VecQ &qd, VecQ &force_q) {
  for (int k = 0; k < model.nq; ++k) force_q[k] = 0;
  if (!(opt.disable & LEGSIM_DISABLE_GRAVITY))
    for (int b = 0; b < model.nb; ++b) {
      force_q[3 * b] += model.mass[3 * b] * model.gravity.x();
      force_q[3 * b + 1] += model.mass[3 * b] * model.gravity.y();
    }
#if LEGSIM_WITH_FORCE_ELEMENTS
  if (!(opt.disable & LEGSIM_DISABLE_FORCE_ELEMENTS)) add_force_elements(model, d, q, qd, force_q, &d.trig);
#endif
  if (opt.disable & LEGSIM_DISABLE_ACTUATORS) return;
  actuator_forces_update(model, opt, d, q, qd);
  // F along the cylinder axis, by virtual work F dl: Q = F * (d length / d q).
  for (int a = 0; a < model.na; ++a) {
    const Actuator &ac = model.act[a];
    const real f = d.act[a].force;
    real s, c;
    body_trig(&d.trig, ac.cyl, q[3 * ac.cyl + 2], s, c);  // the rows' pair at this q
    const Vec2 u(s, -c), n(c, s);                          // axis_u, normal_n
    const Vec2 dvec(q[3 * ac.rod] - q[3 * ac.cyl], q[3 * ac.rod + 1] - q[3 * ac.cyl + 1]);
    force_q[3 * ac.cyl] -= f * u.x();
    force_q[3 * ac.cyl + 1] -= f * u.y();
    force_q[3 * ac.cyl + 2] += f * dvec.dot(n);
    force_q[3 * ac.rod] += f * u.x();
    force_q[3 * ac.rod + 1] += f * u.y();
  }
}

}  // namespace legsim
