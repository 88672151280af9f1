// Generalized applied forces Q: gravity, force elements and actuator forces, with the
// actuators' axial forces from their commands (force, or length through the servo).
#include <cstring>

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
    if (!(d.force_active & (1u << i))) continue;  // none applied (a scene's load left at 0)
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

void actuator_forces_update(const Model &model, const legsim_options &opt, Data &d, const VecQ &q,
                            const VecQ &qd) {
  (void)opt;
  for (int a = 0; a < model.na; ++a) {
    const Actuator &ac = model.act[a];
    ActuatorState &st = d.act[a];
    if (st.mode == LEGSIM_ACTUATOR_FORCE) {
      st.force = st.setpoint;
      continue;
    }
    const int i = 3 * ac.cyl, j = 3 * ac.rod;
    real s, c;
    body_trig(&d.trig, ac.cyl, q[i + 2], s, c);
    const real dx = q[j] - q[i], dy = q[j + 1] - q[i + 1];
    st.force = axial_force(ac, st, d, s, c, dx, dy, qd[j] - qd[i], qd[j + 1] - qd[i + 1], qd[i + 2],
                           dx * c + dy * s);
  }
}

static_assert(kMaxForces <= 32, "Data::force_active has a bit per force element");

void force_active_update(const Model &model, Data &d) {
  d.force_active = 0;
  for (int f = 0; f < model.nf; ++f) {
    const bool spring = model.force[f].kind == LEGSIM_FORCE_SPRING_DAMPER;
    if (spring || d.force_value[f][0] != 0 || d.force_value[f][1] != 0) d.force_active |= 1u << f;
  }
}

void applied_forces(const Model &model, uint32_t disable, Data &d, const VecQ &q, const VecQ &qd,
                    VecQ &force_q) {
  // Gravity, m g at each centre (no moment), written rather than added: it clears Q too.
  // (A whole fixed-size vector: straight-line copies, cheaper on Cortex-M4 than a loop or
  // the library's memcpy of nq values.)
  if (disable & LEGSIM_DISABLE_GRAVITY)
    force_q.setZero();
  else
    force_q = model.gravity_force;
  real *__restrict fq = force_q.data();  // Data's Q: apart from the model, q and qd
#if LEGSIM_WITH_FORCE_ELEMENTS
  if (d.force_active && !(disable & LEGSIM_DISABLE_FORCE_ELEMENTS))
    add_force_elements(model, d, q, qd, force_q, &d.trig);
#endif
  if (disable & LEGSIM_DISABLE_ACTUATORS) return;
  // Each actuator's force from its command (as actuator_forces_update), then F along the
  // cylinder axis by virtual work F dl: Q = F * (d length / d q), one sin/cos pair (the
  // stage's, shared with the rows) for both.
  for (int a = 0; a < model.na; ++a) {
    const Actuator &ac = model.act[a];
    ActuatorState &st = d.act[a];
    const bool commanded_force = st.mode == LEGSIM_ACTUATOR_FORCE;
    real f = st.setpoint;
    if (commanded_force) {
      st.force = f;
      if (f == 0) continue;  // a passive actuator: adds nothing (nor reads the state)
    }
    const int i = 3 * ac.cyl, j = 3 * ac.rod;
    const real dx = q[j] - q[i], dy = q[j + 1] - q[i + 1];
    real s, c;
    body_trig(&d.trig, ac.cyl, q[i + 2], s, c);
    if (!commanded_force) {
      f = axial_force(ac, st, d, s, c, dx, dy, qd[j] - qd[i], qd[j + 1] - qd[i + 1], qd[i + 2],
                      dx * c + dy * s);
      st.force = f;
    }
    const real fs = f * s, fc = f * c;
    fq[i] -= fs;
    fq[i + 1] += fc;  // - F u_y
    fq[i + 2] += f * (dx * c + dy * s);
    fq[j] += fs;
    fq[j + 1] -= fc;
  }
}

}  // namespace legsim
