#include "spatial/motion.hpp"

#include <algorithm>
#include <cmath>

namespace legsim::spatial {

namespace {
constexpr real kNone = real(sizeof(real) == sizeof(float) ? 1e30 : 1e300);  // no event function
inline real norm(const V3 &x) { return std::sqrt(dot(x, x)); }


legsim_status hold_check(const SpatialRobot &robot, const FeetHold &hold) {
  if ((hold.stuck | hold.sliding) >> robot_contacts(robot) || (hold.stuck & hold.sliding)) return LEGSIM_ERR_BAD_INPUT;
  for (int l = 0; l < robot.nlegs; ++l) {
    if (foot_rows(hold, l) && robot.leg[l].foot_body < 0) return LEGSIM_ERR_BAD_INPUT;
    const uint32_t s = leg_stops(hold, l);
    if (((s & 1u) && robot.leg[l].nactuators < 1) || ((s & 2u) && robot.leg[l].nactuators < 2))
      return LEGSIM_ERR_BAD_INPUT;
  }
  if (hold.stops >> (kLegStops * robot.nlegs) || (hold.upper & ~hold.stops)) return LEGSIM_ERR_BAD_INPUT;
  return LEGSIM_OK;
}

// Leg l's stroke k (its actuators' k = 0, 1, its rowing angle's 2) at q: its value and ends.
real stroke_value(const SpatialRobot &robot, int l, int k, const real *q, real &lo, real &hi) {
  if (k == 2) {
    lo = robot.rowing_stroke[0], hi = robot.rowing_stroke[1];
    return robot_rowing_angle(robot, l, q);
  }
  // robot_actuator_length's, without the row's coefficients: (r_rod - r_cyl) . u_cyl + offset
  const RobotActuator &ac = robot.act[robot.leg[l].first_actuator + k];
  lo = ac.stroke[0], hi = ac.stroke[1];
  const real *c = q + kBodyConfig * ac.cyl, *r = q + kBodyConfig * ac.rod;
  const real w = c[3], x = c[4], y = c[5], z = c[6];
  return (r[0] - c[0]) * (1 - 2 * (y * y + z * z)) + (r[1] - c[1]) * 2 * (x * y + w * z) +
         (r[2] - c[2]) * 2 * (x * z - w * y) + ac.offset;
}

// q and v onto the rows: q by simplified Newton iterations of the M-orthogonal correction (the
// factor at the first q), then v by one; on return d.rows and d.factor are those at (q, v).
legsim_status project(const SpatialRobot &robot, RobotData &d, real *q, real *v, int &iterations) {
  static const real zero_v[kMaxRobotDof] = {};
  static const real zero_f[kMaxRobotDof] = {};
  real g[kMaxSystemRows], dx[kMaxRobotDof], mu[kMaxSystemRows];
  int idx[kMaxSystemRows];
  const int n = system_used_rows(robot, d.hold, idx);
  bool factored = false;
  iterations = 0;
  for (;;) {
    system_phi(robot, d.hold, q, g);  // the residual needs the rows' phi alone
    real worst = 0, worst_stop = 0;
    for (int i = 0; i < n; ++i) {
      g[idx[i]] = -g[idx[i]];
      const real e = std::abs(g[idx[i]]);
      if (!(e <= worst)) worst = e;  // a NaN too
      if (idx[i] >= robot.m + 3 * kMaxContacts) worst_stop = std::max(worst_stop, e);
    }
    if (!std::isfinite(worst)) return LEGSIM_ERR_DIVERGED;
    // a stop's gap to round-off (while the others allow): one released with a gap at -tolerance
    // would cross its event's tolerance at once, again and again
    if (worst <= kProjectionTolerance &&
        (worst_stop <= kProjectionTolerance / 100 || (iterations > 0 && iterations == kProjectionMaxIterations)))
      break;
    if (iterations == kProjectionMaxIterations) return LEGSIM_ERR_NOT_CONVERGED;
    if (!factored) {
      system_rows(robot, d.hold, q, zero_v, d.rows);
      const legsim_status s = robot_factor(robot, d.hold, d.rows, d.factor);
      if (s != LEGSIM_OK) return s;
      factored = true;
    }
    robot_solve(robot, d.factor, zero_f, g, dx, mu);
    for (int b = 0; b < robot.nb; ++b) {
      real out[kBodyConfig];
      config_add(q + kBodyConfig * b, dx + kBodyDof * b, out);
      std::copy(out, out + kBodyConfig, q + kBodyConfig * b);
    }
    ++iterations;
  }
  system_rows(robot, d.hold, q, v, d.rows);
  const legsim_status s = robot_factor(robot, d.hold, d.rows, d.factor);
  if (s != LEGSIM_OK) return s;
  for (int i = 0; i < n; ++i) g[idx[i]] = -row_dot(robot, d.rows[idx[i]], idx[i], v);
  robot_solve(robot, d.factor, zero_f, g, dx, mu);
  for (int k = 0; k < kBodyDof * robot.nb; ++k) v[k] += dx[k];
  system_rows(robot, d.hold, q, v, d.rows);  // gamma at the new v; J is the factor's
  return LEGSIM_OK;
}

// The accelerations, multipliers and sliding feet's normal forces at (q, v) under d's commands.
// report: the state is data's own (the forces kept as its report).
// within: (q, v) in the part from d's last state reached (an integrator's stage or iterate, its
// end): refused when the sliding feet's det (I + Lambda) turned sign since (a pole between them).
legsim_status evaluate(const SpatialRobot &robot, RobotData &d, const real *q, const real *v, real *a, real *mu,
                       real *N, bool factored, bool report = false, const V3 *fixed_dir = nullptr,
                       bool within = false) {
  real Q[kMaxRobotDof], F[kMaxRobotActuators], T[kMaxLegs];
  command_forces(robot, d.command, q, v, F, T);
  robot_forces(robot, q, v, F, T, Q);
  if (report) {
    std::copy(F, F + robot.na, d.actuator_force);
    std::copy(T, T + robot.nlegs, d.rowing_torque);
  }
  int sign = 1;
  const legsim_status st = contact_accelerations(robot, d.hold, d.ground.mu_kinetic, fixed_dir ? fixed_dir : d.slip_dir,
                                                 q, v, Q, a, mu, N, d.rows, d.factor, d.contact_work, factored,
                                                 fixed_dir != nullptr, &sign);
  if (st != LEGSIM_OK) {
    // a stage on a pole (the normal forces' system singular): as one past it
    if (within && d.pole_check && st == LEGSIM_ERR_CONTACT && sign == 0) d.pole_crossed = true;
    return st;
  }
  if (within && d.pole_check && d.hold.sliding && d.pole_set == d.hold.sliding && sign != d.pole_sign) {
    d.pole_crossed = true;
    return LEGSIM_ERR_CONTACT;
  }
  if (report) d.pole_sign = sign, d.pole_set = d.hold.sliding;
  return LEGSIM_OK;
}

void save(const SpatialRobot &robot, const RobotData &d, RobotSnapshot &c) {
  c.t = d.t;
  std::copy(d.q, d.q + kBodyConfig * robot.nb, c.q);
  std::copy(d.v, d.v + kBodyDof * robot.nb, c.v);
  std::copy(d.a, d.a + kBodyDof * robot.nb, c.a);
  std::copy(d.acc_aux, d.acc_aux + kBodyDof * robot.nb, c.acc_aux);
  c.acc_aux_h = d.acc_aux_h;
  std::copy(d.mu, d.mu + system_rows_extent(robot), c.mu);
  std::copy(d.normal_force, d.normal_force + kMaxContacts, c.N);
  c.hold = d.hold;
  std::copy(d.slip_dir, d.slip_dir + kMaxContacts, c.slip_dir);
  std::copy(d.slip_ref, d.slip_ref + kMaxContacts, c.slip_ref);
  std::copy(d.slip_stage_min, d.slip_stage_min + kMaxContacts, c.slip_stage_min);
  std::copy(d.actuator_force, d.actuator_force + kMaxRobotActuators, c.actuator_force);
  std::copy(d.rowing_torque, d.rowing_torque + kMaxLegs, c.rowing_torque);
  std::copy(d.impulse, d.impulse + kMaxContacts, c.impulse);
  std::copy(d.stop_impulse, d.stop_impulse + kMaxHeldStops, c.stop_impulse);
  c.impact = d.impact, c.modes = d.modes, c.cone_stats = d.cone_stats;
  c.projection_iterations = d.projection_iterations, c.impacts = d.impacts, c.stop_impacts = d.stop_impacts;
  c.pole_sign = d.pole_sign, c.pole_set = d.pole_set;
}
void load(const SpatialRobot &robot, const RobotSnapshot &c, RobotData &d) {
  d.t = c.t;
  std::copy(c.q, c.q + kBodyConfig * robot.nb, d.q);
  std::copy(c.v, c.v + kBodyDof * robot.nb, d.v);
  std::copy(c.a, c.a + kBodyDof * robot.nb, d.a);
  std::copy(c.acc_aux, c.acc_aux + kBodyDof * robot.nb, d.acc_aux);
  d.acc_aux_h = c.acc_aux_h;
  std::copy(c.mu, c.mu + system_rows_extent(robot), d.mu);
  std::copy(c.N, c.N + kMaxContacts, d.normal_force);
  d.hold = c.hold;
  std::copy(c.slip_dir, c.slip_dir + kMaxContacts, d.slip_dir);
  std::copy(c.slip_ref, c.slip_ref + kMaxContacts, d.slip_ref);
  std::copy(c.slip_stage_min, c.slip_stage_min + kMaxContacts, d.slip_stage_min);
  std::copy(c.actuator_force, c.actuator_force + kMaxRobotActuators, d.actuator_force);
  std::copy(c.rowing_torque, c.rowing_torque + kMaxLegs, d.rowing_torque);
  std::copy(c.impulse, c.impulse + kMaxContacts, d.impulse);
  std::copy(c.stop_impulse, c.stop_impulse + kMaxHeldStops, d.stop_impulse);
  d.impact = c.impact, d.modes = c.modes, d.cone_stats = c.cone_stats;
  d.projection_iterations = c.projection_iterations, d.impacts = c.impacts, d.stop_impacts = c.stop_impacts;
  d.pole_sign = c.pole_sign, d.pole_set = c.pole_set;
}

// One RK4 step of H on d in place (d.a must be the accelerations at d's state); d part-way on
// failure.
legsim_status rk4(const SpatialRobot &robot, RobotData &d, real H) {
  const int nb = robot.nb, nv = kBodyDof * nb;
  real q0[kBodyConfig * kMaxRobotBodies], v0[kMaxRobotDof];
  std::copy(d.q, d.q + kBodyConfig * nb, q0);
  std::copy(d.v, d.v + nv, v0);
  real q[kBodyConfig * kMaxRobotBodies], th[kMaxRobotDof], v[kMaxRobotDof], mu[kMaxSystemRows], N[kMaxContacts];
  real kth[4][kMaxRobotDof], kv[4][kMaxRobotDof];
  auto stage = [&](int s, const real *ths, const real *vs) {
    for (int b = 0; b < nb; ++b) config_add(q0 + kBodyConfig * b, ths + kBodyDof * b, q + kBodyConfig * b);
    for (int b = 0; b < nb; ++b) {
      const real *tb = ths + kBodyDof * b, *vb = vs + kBodyDof * b;
      real *o = kth[s] + kBodyDof * b;
      const V3 w = dexp_inv({tb[3], tb[4], tb[5]}, {vb[3], vb[4], vb[5]});
      o[0] = vb[0], o[1] = vb[1], o[2] = vb[2], o[3] = w.x, o[4] = w.y, o[5] = w.z;
    }
    for (int l = 0; l < robot_contacts(robot); ++l) {
      if (!((d.hold.sliding >> l) & 1u)) continue;
      V3 p, pv;
      foot_motion(robot, l, q, vs, p, pv);
      d.slip_stage_min[l] = std::min(d.slip_stage_min[l], dot(tangential(d.hold, pv), d.slip_ref[l]));
    }
    return evaluate(robot, d, q, vs, kv[s], mu, N, false, false, nullptr, true);
  };
  for (int l = 0; l < robot_contacts(robot); ++l) d.slip_stage_min[l] = kNone;
  for (int k = 0; k < nv; ++k) kth[0][k] = v0[k], kv[0][k] = d.a[k];
  static const real c[3] = {real(0.5), real(0.5), real(1)};
  for (int s = 1; s < 4; ++s) {
    for (int k = 0; k < nv; ++k) th[k] = c[s - 1] * H * kth[s - 1][k], v[k] = v0[k] + c[s - 1] * H * kv[s - 1][k];
    const legsim_status st = stage(s, th, v);
    if (st != LEGSIM_OK) return st;
  }
  for (int k = 0; k < nv; ++k) {
    th[k] = H / 6 * (kth[0][k] + 2 * (kth[1][k] + kth[2][k]) + kth[3][k]);
    d.v[k] = v0[k] + H / 6 * (kv[0][k] + 2 * (kv[1][k] + kv[2][k]) + kv[3][k]);
  }
  for (int b = 0; b < nb; ++b) config_add(q0 + kBodyConfig * b, th + kBodyDof * b, d.q + kBodyConfig * b);
  legsim_status st = project(robot, d, d.q, d.v, d.projection_iterations);
  if (st == LEGSIM_OK) st = evaluate(robot, d, d.q, d.v, d.a, d.mu, d.normal_force, true, true, nullptr, true);
  if (st != LEGSIM_OK) return st;
  for (int k = 0; k < nv; ++k)
    if (!std::isfinite(d.v[k]) || !std::isfinite(d.a[k])) return LEGSIM_ERR_DIVERGED;
  d.t += H;
  return LEGSIM_OK;
}

// One generalized-alpha step of H on d in place (Bruls, Cardona, Arnold 2012 on the group; the
// Chung-Hulbert parameters of kGalphaRhoInf), with the rows explicit: the unknown is the true
// acceleration vd1 at the step's end, found by fixed-point iterations vd1 <- f(q1(vd1), v1(vd1))
// (f: the constrained accelerations, contact_accelerations), then q1 and v1 projected onto the
// rows as RK4's are. d.a must be the accelerations at d's state and d.acc_aux the history;
// d part-way on failure.
legsim_status galpha(const SpatialRobot &robot, RobotData &d, real H) {
  const int nb = robot.nb, nv = kBodyDof * nb;
  const real rho = kGalphaRhoInf;
  const real am = (2 * rho - 1) / (rho + 1), af = rho / (rho + 1);
  const real gam = real(0.5) + af - am, beta = real(0.25) * (gam + real(0.5)) * (gam + real(0.5));
  real q0[kBodyConfig * kMaxRobotBodies], v0[kMaxRobotDof], a0[kMaxRobotDof], x0[kMaxRobotDof];
  std::copy(d.q, d.q + kBodyConfig * nb, q0);
  std::copy(d.v, d.v + nv, v0);
  std::copy(d.a, d.a + nv, a0);
  // the history's lead over the accelerations, (am - af) h vd', to this part's length
  const real scale = d.acc_aux_h > 0 ? H / d.acc_aux_h : real(1);
  for (int k = 0; k < nv; ++k) x0[k] = a0[k] + scale * (d.acc_aux[k] - a0[k]);
  real vd1[kMaxRobotDof], x1[kMaxRobotDof], th[kMaxRobotDof], f[kMaxRobotDof], mu[kMaxSystemRows], N[kMaxContacts];
  // the predictor: the acceleration's rate from the history's lead, x0 - vd0 ~ (am - af) H vd'
  // (0.6 fewer iterations a step than the acceleration held; none at rho_inf = 1, where am = af)
  const real lead = am != af ? 1 / (am - af) : real(0);
  for (int k = 0; k < nv; ++k) vd1[k] = a0[k] + lead * (x0[k] - a0[k]);
  // q1 = q0 (+) H (v0 + H ((1/2 - beta) x0 + beta x1)), v1 = v0 + H ((1 - gamma) x0 + gamma x1),
  // (1 - am) x1 + am x0 = (1 - af) vd1 + af vd0
  auto state = [&](real *q, real *v) {
    for (int k = 0; k < nv; ++k) {
      x1[k] = ((1 - af) * vd1[k] + af * a0[k] - am * x0[k]) / (1 - am);
      th[k] = H * (v0[k] + H * ((real(0.5) - beta) * x0[k] + beta * x1[k]));
      v[k] = v0[k] + H * ((1 - gam) * x0[k] + gam * x1[k]);
    }
    for (int b = 0; b < nb; ++b) config_add(q0 + kBodyConfig * b, th + kBodyDof * b, q + kBodyConfig * b);
  };
  // the iterations with each sliding foot's friction along its slip at the iterate; when they
  // do not contract (a slip turning back within the step: its direction flips between
  // iterates), again from the predictor with the directions at the part's start
  bool converged = false;
  for (int pass = 0; pass < 2 && !converged; ++pass) {
    const V3 *fixed = pass == 1 ? d.slip_ref : nullptr;
    if (pass == 1) {
      if (!d.hold.sliding) break;
      std::copy(a0, a0 + nv, vd1);
    }
    real last = kNone;
    for (int it = 0; it < kGalphaMaxIterations && !converged; ++it) {
      state(d.q, d.v);
      const legsim_status st = evaluate(robot, d, d.q, d.v, f, mu, N, false, false, fixed, true);
      if (st != LEGSIM_OK) return st;
      real change = 0, size = 1;
      for (int k = 0; k < nv; ++k) {
        const real e = std::abs(f[k] - vd1[k]);
        if (!(e <= change)) change = e;  // a NaN too
        size = std::max(size, std::abs(f[k]));
        vd1[k] = f[k];
      }
      if (!std::isfinite(change)) return LEGSIM_ERR_DIVERGED;
      converged = change <= kGalphaTolerance * size;
      if (!converged && it >= 2 && change > real(0.5) * last && d.hold.sliding && pass == 0) break;
      last = change;
    }
  }
  if (!converged) return LEGSIM_ERR_NOT_CONVERGED;
  state(d.q, d.v);
  for (int l = 0; l < robot_contacts(robot); ++l) {
    d.slip_stage_min[l] = kNone;
    if (!((d.hold.sliding >> l) & 1u)) continue;
    V3 p, pv;
    foot_motion(robot, l, d.q, d.v, p, pv);
    d.slip_stage_min[l] = dot(tangential(d.hold, pv), d.slip_ref[l]);
  }
  std::copy(x1, x1 + nv, d.acc_aux);
  d.acc_aux_h = H;
  legsim_status st = project(robot, d, d.q, d.v, d.projection_iterations);
  if (st == LEGSIM_OK) st = evaluate(robot, d, d.q, d.v, d.a, d.mu, d.normal_force, true, true, nullptr, true);
  if (st != LEGSIM_OK) return st;
  for (int k = 0; k < nv; ++k)
    if (!std::isfinite(d.v[k]) || !std::isfinite(d.a[k])) return LEGSIM_ERR_DIVERGED;
  d.t += H;
  return LEGSIM_OK;
}

// One part of H by the integrator.
legsim_status take(const SpatialRobot &robot, RobotData &d, real H, Integrator integrator) {
  return integrator == Integrator::GeneralizedAlpha ? galpha(robot, d, H) : rk4(robot, d, H);
}

// ---- contact and stop events -----------------------------------------------------------------
// Per foot two functions, each >= 0 while its mode holds: a free foot's height above the
// ground (m) and none; a stuck foot's normal force (N) and its cone's margin mu_s N - |F_t|
// (N); a sliding foot's normal force and its slip velocity along its direction at the step's
// start (m/s). Then per stroke (its actuators', its rowing angle's) one: free, its distance to
// the nearer end (m, rad); on a stop, the stop's push -lambda (N, N m).
constexpr int kLegEvents = 2 + kLegStops;
constexpr int kPoleParts = 30;  // halvings of a part whose stages straddle a pole
void event_values(const SpatialRobot &robot, const RobotData &d, const V3 *ref, real (*e)[kLegEvents]) {
  for (int l = 0; l < robot_contacts(robot); ++l) {
    for (int k = 0; k < kLegStops; ++k) {
      real &f = e[l][2 + k];
      f = kNone;
      if (l >= robot.nlegs || (k < 2 && k >= robot.leg[l].nactuators)) continue;
      if ((leg_stops(d.hold, l) >> k) & 1u) {
        f = -d.mu[stop_row(robot, l, k)];
      } else {
        real lo, hi;
        const real x = stroke_value(robot, l, k, d.q, lo, hi);
        f = std::min(x - lo, hi - x);
      }
    }
    e[l][0] = e[l][1] = kNone;
    if (!d.has_ground || contact_body(robot, l) < 0) continue;
    const uint32_t bit = 1u << l;
    const real *m = d.mu + foot_row(robot, l);
    if (d.hold.stuck & bit) {
      e[l][0] = -m[0];
      e[l][1] = d.ground.mu_static * -m[0] - std::hypot(m[1], m[2]);
    } else if (d.hold.sliding & bit) {
      V3 p, pv;
      foot_motion(robot, l, d.q, d.v, p, pv);
      e[l][0] = d.normal_force[l];
      e[l][1] = std::min(dot(tangential(d.hold, pv), ref[l]), d.slip_stage_min[l]);
    } else {
      V3 p, pv;
      foot_motion(robot, l, d.q, d.v, p, pv);
      e[l][0] = dot(p - d.ground.point, d.ground.normal);
    }
  }
}

// Below -tol an event function has crossed (round-off above it is still "at the root"): heights
// and slip velocities to 1e-12 (m, m/s), forces to 1e-10 of the robot's mass in kg (N).
real force_tolerance(const SpatialRobot &robot) {
  real mass = 1;
  for (int b = 0; b < robot.nb; ++b) mass += robot.mass[b];
  return by_precision(1e-10, 1e-4) * mass;
}
real event_tolerance(const SpatialRobot &robot, const RobotData &d, int l, int k) {
  if (k >= 2) return ((leg_stops(d.hold, l) >> (k - 2)) & 1u) ? force_tolerance(robot) : by_precision(1e-12, 1e-5);
  if (!((d.hold.stuck | d.hold.sliding) >> l & 1u) || (k == 1 && ((d.hold.sliding >> l) & 1u)))
    return by_precision(1e-12, 1e-5);
  return force_tolerance(robot);
}

void tally(ConeStats &s, const ConeReport &r) {
  ++s.solved;
  s.by_sweeps += r.method == ConeMethod::Sweeps ? 1 : 0;
  s.max_iterations = std::max(s.max_iterations, r.iterations);
  s.max_residual = std::max(s.max_residual, r.residual);
}

// The modes checked against the cone at d's state (after an event or at the start): when a stuck
// foot pulls or its force leaves its mu_s cone, the stuck feet's modes are decided on their cones
// at once (contact_modes: stick, slip and which way, or leave); a sliding foot pulling is let go;
// projected and evaluated again until none changes.
// decide: the stuck feet's modes decided on their cones in the first round whatever their forces
// (a located stick to slip, its function at its root: slipping, that foot's bit).
legsim_status impact(const SpatialRobot &robot, RobotData &d, uint32_t touching, uint32_t arriving,
                     uint32_t jammed);
legsim_status settle(const SpatialRobot &robot, RobotData &d, bool decide = false, uint32_t slipping = 0) {
  uint32_t let_go = 0, let_go_upper = 0;  // the stops let go here (still at their ends)
  uint32_t dropped = 0;                    // the sliding feet let go here (they pulled)
  uint32_t jam_done = 0;  // those that took an impact without collision here (once: else it is left free)
  // the impact without collision of the feet of jammed (its problem's failure the check's)
  auto jam_impact = [&](uint32_t jammed) {
    const legsim_status s = impact(robot, d, d.hold.stuck | d.hold.sliding | jammed, 0, jammed);
    if (s == LEGSIM_OK) ++d.impacts;
    return s;
  };
  for (int round = 0; round <= 2 * robot_contacts(robot) + kLegStops * robot.nlegs + 1; ++round) {
    legsim_status st = project(robot, d, d.q, d.v, d.projection_iterations);
    if (st == LEGSIM_OK) st = evaluate(robot, d, d.q, d.v, d.a, d.mu, d.normal_force, true, true);
    if (st != LEGSIM_OK) return st;
    for (int k = 0; k < kBodyDof * robot.nb; ++k)
      if (!std::isfinite(d.v[k]) || !std::isfinite(d.a[k])) return LEGSIM_ERR_DIVERGED;
    std::copy(d.a, d.a + kBodyDof * robot.nb, d.acc_aux);  // generalized-alpha's history restarts
    d.acc_aux_h = 0;
    const real tol = force_tolerance(robot);
    bool off_cone = decide && round == 0, changed = false;
    const FeetHold before_round = d.hold;
    uint32_t past_edge = 0;  // stuck feet pressing with their force past the mu_s cone
    // the stop pulling most, let go once the feet's modes hold (a foot's mode changes the stops'
    // multipliers: a stop decided before the feet would be let go and hit again)
    int pull = -1;
    real most = tol;
    for (int s = 0; s < kLegStops * robot.nlegs; ++s) {
      const real m = ((d.hold.stops >> s) & 1u) ? d.mu[stop_row(robot, s / kLegStops, s % kLegStops)] : 0;
      if (m > most) most = m, pull = s;
    }
    if (d.has_ground) {
      for (int l = 0; l < robot_contacts(robot); ++l) {
        const uint32_t bit = 1u << l;
        const real *m = d.mu + foot_row(robot, l);
        if (d.hold.stuck & bit) {
          const real N = -m[0], Ft = std::hypot(m[1], m[2]);
          if (N < -tol || Ft > d.ground.mu_static * N + tol) off_cone = true;
          if (N >= -tol && Ft > d.ground.mu_static * N + tol) past_edge |= bit;
        } else if ((d.hold.sliding & bit) && d.normal_force[l] < -tol) {
          d.hold.sliding &= ~bit, changed = true, dropped |= bit;
        }
      }
    }
    // a stuck foot off its cone or a stop pulling: the stuck feet and the held stops decided in
    // one problem (a stop's push changes the feet's forces and a foot's mode the stops')
    if (off_cone || pull >= 0) {
      const FeetHold before = d.hold;
      real Q[kMaxRobotDof], F[kMaxRobotActuators], T[kMaxLegs];
      command_forces(robot, d.command, d.q, d.v, F, T);
      robot_forces(robot, d.q, d.v, F, T, Q);
      st = contact_modes(robot, d.ground, d.q, d.v, Q, round == 0 ? slipping : 0u, d.hold, d.slip_dir, d.modes,
                         d.rows, d.factor, d.contact_work);
      // with sliding feet the problem may have no solution (their friction coupled in; Painleve's
      // case): the stuck feet decided alone with the stops held, then the stop pulling most let
      // go alone, the sliding feet decided after it (below)
      const bool unsolved = (st == LEGSIM_ERR_CONTACT || st == LEGSIM_ERR_NOT_CONVERGED) && before.sliding;
      if (unsolved) {  // the stuck feet alone, the stops held
        if (st == LEGSIM_ERR_NOT_CONVERGED) tally(d.cone_stats, d.modes);  // (its residual in the statistics)
        d.hold = before;
        st = contact_modes(robot, d.ground, d.q, d.v, Q, round == 0 ? slipping : 0u, d.hold, d.slip_dir, d.modes,
                           d.rows, d.factor, d.contact_work, false);
      }
      if (st != LEGSIM_OK) return st;
      if (before.stuck || before.stops) tally(d.cone_stats, d.modes);  // (none: no problem solved)
      const uint32_t freed = before.stops & ~d.hold.stops;
      let_go |= freed, let_go_upper |= before.upper & freed;
      bool decided = d.hold.stuck != before.stuck || d.hold.sliding != before.sliding || freed;
      // the cone keeps a foot stuck at its edge that the multipliers put past it (the two
      // solves' round-off at the edge): it slips, as a located stick to slip does
      if (!decided && !unsolved && past_edge && !(decide && round == 0)) {
        st = contact_modes(robot, d.ground, d.q, d.v, Q, past_edge, d.hold, d.slip_dir, d.modes, d.rows, d.factor,
                           d.contact_work);
        if (st != LEGSIM_OK) return st;
        tally(d.cone_stats, d.modes);
        const uint32_t freed2 = before.stops & ~d.hold.stops;
        let_go |= freed2, let_go_upper |= before.upper & freed2;
        decided = d.hold.stuck != before.stuck || d.hold.sliding != before.sliding || freed2;
      }
      if (!decided && !changed && !(decide && round == 0) && pull < 0) return LEGSIM_ERR_CONTACT;
      if (decided) {
        changed = true;
      } else if (pull >= 0 && !changed) {
        // the problem keeps a stop its multiplier puts pulling (the two solves' round-off): let go
        const uint32_t bit = 1u << pull;
        let_go |= bit, let_go_upper |= d.hold.upper & bit;
        d.hold.stops &= ~bit, d.hold.upper &= ~bit, changed = true;
      }
    } else if (changed && let_go) {
      // a sliding foot let go after stops were let go for it: with the foot on the ground the
      // stops pulled, with them let go the foot pulls (Painleve's inconsistent case, a stop's
      // push moving it into its stop through the foot's friction): an impact without collision
      // of those feet and stops (still at their ends) in one problem, the feet as if approaching
      // (contact_impact's jammed)
      const uint32_t jammed = before_round.sliding & ~d.hold.sliding & ~d.hold.stuck & ~jam_done;
      if (jammed && d.has_ground) {
        jam_done |= jammed, dropped &= ~jammed;
        if ((st = jam_impact(jammed)) != LEGSIM_OK) return st;
      } else {
        d.hold.stops |= let_go, d.hold.upper |= let_go_upper;
      }
      let_go = let_go_upper = 0;
    }
    if (!changed && dropped && d.has_ground) {
      // a sliding foot let go here (it pulled) that, let go, accelerates into the ground from
      // rest on it: no mode keeps it (Painleve's inconsistent case, with a stop or the others'
      // friction): an impact without collision of it and the feet and strokes at their ends in
      // one problem, it as if approaching (contact_impact's jammed); the slip it cannot keep is
      // stopped by its impulse
      uint32_t jammed = 0;
      for (uint32_t b = dropped & ~jam_done; b; b &= b - 1) {
        const int l = __builtin_ctz(b);
        V3 p, pv;
        foot_motion(robot, l, d.q, d.v, p, pv);
        if (dot(p - d.ground.point, d.ground.normal) <= by_precision(1e-9, 1e-5) &&
            dot(pv, d.ground.normal) <= by_precision(1e-9, 1e-5) &&
            dot(contact_acceleration(robot, l, d.q, d.v, d.a), d.ground.normal) < -by_precision(1e-9, 1e-4))
          jammed |= 1u << l;
      }
      dropped = 0;
      jam_done |= jammed;
      if (jammed) {
        if ((st = jam_impact(jammed)) != LEGSIM_OK) return st;
        changed = true;
      }
    }
    if (!changed) return LEGSIM_OK;
  }
  return LEGSIM_ERR_CONTACT;
}

// The strokes at an end (to 1e-12 m, rad: their events' tolerance) that no stop holds: put on
// hold's stops (at that end) for an impact's problem, which keeps those it pushes; their bits.
// (A wider band would let an impact capture a stroke short of its end, and the projection onto
// its end would then move the others, past theirs.)
uint32_t strokes_at_end(const SpatialRobot &robot, FeetHold &hold, const real *q) {
  uint32_t near = 0;
  for (int l = 0; l < robot.nlegs; ++l)
    for (int k = 0; k < kLegStops; ++k) {
      const uint32_t bit = 1u << (kLegStops * l + k);
      if ((k < 2 && k >= robot.leg[l].nactuators) || (hold.stops & bit)) continue;
      real lo, hi;
      const real x = stroke_value(robot, l, k, q, lo, hi);
      if (!(std::min(x - lo, hi - x) <= by_precision(1e-12, 1e-5))) continue;
      near |= bit, hold.stops |= bit;
      if (hi - x < x - lo) hold.upper |= bit;
    }
  return near;
}

// An impact at d's state: the feet of `touching` on their cones and the strokes of `arriving`
// and those at an end (which count as arrivals when it pushes them) on their stops in one contact
// problem, the held stops holding (contact_impact).
legsim_status impact(const SpatialRobot &robot, RobotData &d, uint32_t touching, uint32_t arriving,
                     uint32_t jammed) {
  const uint32_t near = strokes_at_end(robot, d.hold, d.q);
  for (int j = 0; j < robot_contacts(robot); ++j) d.impulse[j] = {0, 0, 0};
  for (int s = 0; s < kMaxHeldStops; ++s) d.stop_impulse[s] = 0;
  const legsim_status st = contact_impact(robot, d.ground, touching, arriving, near, d.q, d.v, d.hold, d.slip_dir,
                                          d.impulse, d.stop_impulse, d.impact, d.rows, d.factor, d.contact_work,
                                          jammed);
  if (st != LEGSIM_OK) return st;
  tally(d.cone_stats, d.impact);
  for (uint32_t s = d.hold.stops & near; s; s &= s - 1) ++d.stop_impacts;  // arrivals
  return LEGSIM_OK;
}

// A stroke reaching its stop at d's state: an inelastic impact of the stop and the feet on the
// ground (and any foot landing or stroke at its end at that instant) in one contact problem, the
// stop's impulse only pushing; then its row held while it pushes.
legsim_status stop_arrival(const SpatialRobot &robot, RobotData &d, int l, int k) {
  real lo, hi;
  const real x = stroke_value(robot, l, k, d.q, lo, hi);
  const uint32_t bit = 1u << (kLegStops * l + k);
  uint32_t touching = 0;
  if (d.has_ground) {
    touching = d.hold.stuck | d.hold.sliding;
    for (int c = 0; c < robot_contacts(robot); ++c) {
      if (contact_body(robot, c) < 0 || ((touching >> c) & 1u)) continue;
      V3 p, pv;
      foot_motion(robot, c, d.q, d.v, p, pv);
      if (dot(p - d.ground.point, d.ground.normal) <= by_precision(1e-9, 1e-5) && dot(pv, d.ground.normal) < 0)
        touching |= 1u << c;  // landing at this instant
    }
  }
  // the arriving stroke held as a stop from the impact on (unless it leaves it faster than
  // kCapture); a stop pulling at the acceleration level after it is let go by the modes' check
  d.hold.stops |= bit;
  if (hi - x < x - lo) d.hold.upper |= bit;
  const legsim_status st = impact(robot, d, touching, bit, 0);
  if (st != LEGSIM_OK) return st;
  ++d.stop_impacts;
  return settle(robot, d);
}

// Event (l, k) applied at d's state.
legsim_status apply_event(const SpatialRobot &robot, RobotData &d, int l, int k) {
  if (k >= 2) {
    const uint32_t bit = 1u << (kLegStops * l + k - 2);
    if (!(d.hold.stops & bit)) return stop_arrival(robot, d, l, k - 2);
    d.hold.stops &= ~bit, d.hold.upper &= ~bit;  // its push at 0 and falling: released
    return settle(robot, d);
  }
  const uint32_t bit = 1u << l;
  V3 p, pv;
  foot_motion(robot, l, d.q, d.v, p, pv);
  const V3 on_ground = p - dot(p - d.ground.point, d.ground.normal) * d.ground.normal;
  if (d.hold.stuck & bit) {
    if (k == 0) {  // a lift-off: its force at 0 and falling (the acceleration level alone would keep it)
      d.hold.stuck &= ~bit;
      return settle(robot, d);
    }
    return settle(robot, d, true, bit);  // stick to slip: decided on the cones
  } else if (d.hold.sliding & bit) {
    d.hold.sliding &= ~bit;
    if (k == 1) d.hold.stuck |= bit, d.hold.anchor[l] = on_ground;  // slip to stick
    // the box's points stop together when it stops translating: those slipping as this one
    // does stick with it (one at a time, each would be held alone against the others' friction)
    if (k == 1 && l >= robot.nlegs)
      for (int c = robot.nlegs; c < robot_contacts(robot); ++c) {
        if (!((d.hold.sliding >> c) & 1u)) continue;
        V3 pc, vc;
        foot_motion(robot, c, d.q, d.v, pc, vc);
        if (!(norm(tangential(d.hold, vc - pv)) <= by_precision(1e-9, 1e-5))) continue;
        d.hold.sliding &= ~(1u << c), d.hold.stuck |= 1u << c;
        d.hold.anchor[c] = pc - dot(pc - d.ground.point, d.ground.normal) * d.ground.normal;
      }
  } else {  // a touchdown: the impact of every foot in touch
    uint32_t touching = d.hold.stuck | d.hold.sliding | bit;
    // the box's points at the ground with it (a flat face landing: one impact for them all)
    if (l >= robot.nlegs)
      for (int c = robot.nlegs; c < robot_contacts(robot); ++c) {
        V3 pc, vc;
        foot_motion(robot, c, d.q, d.v, pc, vc);
        if (!((touching >> c) & 1u) && dot(pc - d.ground.point, d.ground.normal) <= by_precision(1e-9, 1e-5) &&
            dot(vc, d.ground.normal) < 0)
          touching |= 1u << c;
      }
    const legsim_status st = impact(robot, d, touching, 0, 0);
    if (st != LEGSIM_OK) return st;
    ++d.impacts;
  }
  return settle(robot, d);
}

// The longest part of a step a sliding foot allows: its friction's direction turns at
// |a_t,perp| / |v_t| (a_t,perp its tangential acceleration across its slip): slow slips turn
// fast, faster than RK4 resolves in a step (its error, of low order there, is what the energy
// shows); a part turns them by at most kSlipTurn. Along the slip the friction keeps its
// direction (a slip slowing to a stop is an event). Unlimited (kNone) without sliding feet.
constexpr real kSlipTurn = real(0.05);  // rad per part
real slip_part(const SpatialRobot &robot, const RobotData &d) {
  real rate = 0;
  for (int l = 0; l < robot_contacts(robot); ++l) {
    if (!((d.hold.sliding >> l) & 1u)) continue;
    const int fb = contact_body(robot, l);
    const V3 &pt = contact_point(robot, l);
    const BodyState B = body_state(d.q + kBodyConfig * fb, d.v + kBodyDof * fb);
    const PointJet j = point_jet(B, pt);
    const real *ab = d.a + kBodyDof * fb;
    const V3 pa = V3{ab[0], ab[1], ab[2]} + rotate(B.R, cross({ab[3], ab[4], ab[5]}, pt)) + j.pq;
    const V3 vt = tangential(d.hold, j.pd), at = tangential(d.hold, pa);
    const real speed = norm(vt);
    if (!(speed > kSlipHold)) continue;  // its direction kept: nothing turns
    const V3 s = (1 / speed) * vt;
    rate = std::max(rate, norm(at - dot(at, s) * s) / speed);
    // a box's point: its whole tangential acceleration, along the slip too. Slowing to a stop, a
    // slip's direction is stiff (a turn of it away from the slip's comes back at about
    // |a_t| / |v_t|): unresolved, it turns the box's path away from the fall line (the parts
    // shrink toward the stop, to h / 256 at least, where a slip below kSlipHold keeps its
    // direction)
    rate = std::max(rate, norm(at) / speed);
  }
  return rate > 0 ? kSlipTurn / rate : kNone;
}
}  // namespace

legsim_status robot_data_init(const SpatialRobot &robot, const real *q, const real *v, const FeetHold &hold,
                              const GroundPlane *ground, RobotData &data) {
  legsim_status s = hold_check(robot, hold);
  if (s != LEGSIM_OK) return s;
  RobotData &d = data;
  d.t = 0;
  std::copy(q, q + kBodyConfig * robot.nb, d.q);
  std::copy(v, v + kBodyDof * robot.nb, d.v);
  d.hold = hold;
  d.has_ground = ground != nullptr;
  if (ground) {
    d.ground = *ground;
    ground_frame(*ground, d.hold);
    for (int l = 0; l < robot_contacts(robot); ++l) {
      if (contact_body(robot, l) < 0 || foot_rows(hold, l)) continue;
      const V3 p = robot_contact_position(robot, l, q);
      if (dot(p - ground->point, ground->normal) < -by_precision(1e-9, 1e-5))
        return LEGSIM_ERR_BAD_INPUT;  // a free foot under it
    }
  } else {
    d.ground = {{0, 0, 0}, {0, 0, 1}, 0, 0};
  }
  for (int l = 0; l < kMaxContacts; ++l) {
    d.slip_dir[l] = d.slip_ref[l] = d.hold.t1, d.slip_stage_min[l] = kNone;
    d.normal_force[l] = 0, d.impulse[l] = {0, 0, 0};
  }
  for (int a = 0; a < kMaxRobotActuators; ++a)
    d.command.actuator_mode[a] = CommandMode::Force, d.command.actuator[a] = d.command.actuator_ff[a] = 0;
  for (int l = 0; l < kMaxLegs; ++l)
    d.command.rowing_mode[l] = CommandMode::Force, d.command.rowing[l] = d.command.rowing_ff[l] = 0;
  std::fill(d.actuator_force, d.actuator_force + kMaxRobotActuators, real(0));
  std::fill(d.rowing_torque, d.rowing_torque + kMaxLegs, real(0));
  std::fill(d.mu, d.mu + kMaxSystemRows, real(0));
  std::fill(d.stop_impulse, d.stop_impulse + kMaxHeldStops, real(0));
  d.projection_iterations = d.events = d.impacts = d.stop_impacts = 0;
  d.impact = d.modes = {true, ConeMethod::Newton, 0, 0};
  d.cone_stats = {0, 0, 0, 0};
  d.pole_sign = 1, d.pole_set = 0, d.pole_check = true;
  return settle(robot, d);
}

legsim_status robot_data_refresh(const SpatialRobot &robot, RobotData &data) {
  legsim_status s = hold_check(robot, data.hold);
  if (s != LEGSIM_OK) return s;
  real a[kMaxRobotDof], mu[kMaxSystemRows], N[kMaxContacts];
  std::copy(data.normal_force, data.normal_force + kMaxContacts, N);
  s = evaluate(robot, data, data.q, data.v, a, mu, N, false);
  if (s != LEGSIM_OK) return s;
  command_forces(robot, data.command, data.q, data.v, data.actuator_force, data.rowing_torque);
  // generalized-alpha's history shifted by the jump (its lead over the accelerations kept)
  for (int k = 0; k < kBodyDof * robot.nb; ++k) data.acc_aux[k] += a[k] - data.a[k];
  std::copy(a, a + kBodyDof * robot.nb, data.a);
  std::copy(mu, mu + system_rows_extent(robot), data.mu);
  std::copy(N, N + kMaxContacts, data.normal_force);
  return LEGSIM_OK;
}

legsim_status robot_step(const SpatialRobot &robot, RobotData &d, real h, Integrator integrator) {
  if (!(h > 0) || !std::isfinite(h)) return LEGSIM_ERR_BAD_INPUT;
  RobotSnapshot &start = d.snapshot[0], &s0 = d.snapshot[1];
  save(robot, d, start);
  // new commands (or a new state) may leave a foot pulling or off its cone: its modes first
  if (d.has_ground || d.hold.stops) {
    V3 ref[kMaxContacts] = {};
    real e[kMaxContacts][kLegEvents];
    event_values(robot, d, ref, e);
    bool off = false;
    for (int l = 0; l < robot_contacts(robot); ++l) {
      off = off || ((d.hold.stuck | d.hold.sliding) >> l & 1u && (e[l][0] < -force_tolerance(robot) ||
                                                                  ((d.hold.stuck >> l) & 1u && e[l][1] < -force_tolerance(robot))));
      for (int k = 0; k < kLegStops; ++k)
        off = off || (((leg_stops(d.hold, l) >> k) & 1u) && e[l][2 + k] < -force_tolerance(robot));
    }
    if (off) {
      const legsim_status st = settle(robot, d);
      if (st != LEGSIM_OK) {
        load(robot, start, d);
        return st;
      }
    }
  }
  int events = 0;
  real remaining = h;
  auto fail = [&](legsim_status st) {
    load(robot, start, d);
    return st;
  };
  for (;;) {
    // the part's slip directions (kept below kSlipHold), set before its snapshot: its retakes
    // start from them
    V3 ref[kMaxContacts];
    for (int l = 0; l < robot_contacts(robot); ++l) {
      ref[l] = ((d.hold.sliding >> l) & 1u) ? slip_direction(robot, d.hold, l, d.q, d.v, d.slip_dir[l]) : V3{0, 0, 0};
      if ((d.hold.sliding >> l) & 1u) d.slip_dir[l] = ref[l];
      d.slip_ref[l] = ref[l], d.slip_stage_min[l] = kNone;
    }
    save(robot, d, s0);
    real e0[kMaxContacts][kLegEvents], e1[kMaxContacts][kLegEvents];
    event_values(robot, d, ref, e0);
    // this part: the rest of the step, or what a slow slip allows (at least 1/256 of the step)
    real part = std::min(remaining, std::max(slip_part(robot, d), h / 256));
    // a part whose stages straddle a sliding foot's pole (Painleve's case): shorter, so that the
    // slip stopped before it (the normal force growing toward it) is located as its event
    legsim_status st = LEGSIM_OK;
    d.pole_check = true;
    for (int halving = 0;; ++halving) {
      d.pole_crossed = false;
      st = take(robot, d, part, integrator);
      if (st == LEGSIM_OK || !d.pole_crossed) break;
      load(robot, s0, d);
      // still at the part's start after kPoleParts halvings: not a pole the normal forces grow
      // toward but a jump of the sign there (a slip's direction switching to its kept one at
      // kSlipHold): the part taken, its normal forces' jump an event as any
      if (halving == kPoleParts) d.pole_check = false;
      else part *= real(0.5);
    }
    if (st != LEGSIM_OK) return fail(st);
    event_values(robot, d, ref, e1);
    // the crossings: the earliest by the line through the two ends first
    int el = -1, ek = -1;
    real best = 2;
    for (int l = 0; l < robot_contacts(robot); ++l)
      for (int k = 0; k < kLegEvents; ++k) {
        const real tol = event_tolerance(robot, d, l, k);
        // a crossing; or a function already below at the start still falling (a free foot
        // under the ground, rising from an impact, is left to rise)
        if (!(e1[l][k] < -tol) || !(e0[l][k] >= -tol || e1[l][k] < e0[l][k] - tol)) continue;
        const real a0 = std::max(e0[l][k], real(0));
        const real est = a0 / (a0 - e1[l][k]);
        if (est < best) best = est, el = l, ek = k;
      }
    if (el < 0) {
      remaining -= part;
      if (remaining <= by_precision(1e-14, 1e-6) * h) break;
      continue;
    }
    // locate it: regula falsi (Illinois) on the fraction of the step; then check that no other
    // event crossed before it, else locate that one within the shorter window
    real window = 1;
    for (int guard = 0; guard < kLegEvents * kMaxContacts; ++guard) {
      real lo = 0, hi = window, flo = std::max(e0[el][ek], real(0)), fhi = e1[el][ek];
      if (guard > 0) {  // the new event's value at the window's end
        load(robot, s0, d);
        if ((st = take(robot, d, hi * part, integrator)) != LEGSIM_OK) return fail(st);
        real e[kMaxContacts][kLegEvents];
        event_values(robot, d, ref, e);
        fhi = e[el][ek];
      }
      int side = 0;
      for (int it = 0; it < 60 && (hi - lo) * part > by_precision(1e-13, 1e-6) * (1 + part); ++it) {
        real th = (lo * fhi - hi * flo) / (fhi - flo);
        if (!(th > lo && th < hi)) th = real(0.5) * (lo + hi);
        load(robot, s0, d);
        if ((st = take(robot, d, th * part, integrator)) != LEGSIM_OK) return fail(st);
        real e[kMaxContacts][kLegEvents];
        event_values(robot, d, ref, e);
        const real f = e[el][ek];
        if (f < 0) {
          hi = th, fhi = f;
          if (side == -1) flo *= real(0.5);
          side = -1;
        } else {
          lo = th, flo = f;
          if (side == 1) fhi *= real(0.5);
          side = 1;
        }
        if (f == 0) {
          hi = th;
          break;
        }
      }
      load(robot, s0, d);
      if ((st = take(robot, d, hi * part, integrator)) != LEGSIM_OK) return fail(st);
      real e[kMaxContacts][kLegEvents];
      event_values(robot, d, ref, e);
      int nl = -1, nk = -1;
      for (int l = 0; l < robot_contacts(robot); ++l)
        for (int k = 0; k < kLegEvents; ++k)
          if ((l != el || k != ek) && e[l][k] < -event_tolerance(robot, d, l, k) &&
              (e0[l][k] >= -event_tolerance(robot, d, l, k) || e[l][k] < e0[l][k] - event_tolerance(robot, d, l, k)))
            nl = l, nk = k;
      // located where the last one was (to the search's precision): both cross at one point, a
      // jump of the part's end in its length (a mode's rule switching in a stage): simultaneous,
      // this one applied, the other met at the next part's start
      const bool same = guard > 0 && (window - hi) * part <= by_precision(1e-13, 1e-6) * (1 + part);
      window = hi;
      if (nl < 0 || same) break;
      if (guard == kLegEvents * kMaxContacts - 1) return fail(LEGSIM_ERR_CONTACT);  // still one before it: not located
      el = nl, ek = nk;
    }
    st = apply_event(robot, d, el, ek);
    if (st != LEGSIM_OK) return fail(st);
    remaining -= window * part;
    if (++events > kMaxStepEvents) return fail(LEGSIM_ERR_CONTACT);
    if (remaining <= by_precision(1e-14, 1e-6) * h) break;
  }
  d.t = start.t + h;
  d.events = events;
  return LEGSIM_OK;
}

legsim_status robot_step_rk4(const SpatialRobot &robot, RobotData &d, real h) {
  return robot_step(robot, d, h, Integrator::Rk4);
}
legsim_status robot_step_generalized_alpha(const SpatialRobot &robot, RobotData &d, real h) {
  return robot_step(robot, d, h, Integrator::GeneralizedAlpha);
}

void command_forces(const SpatialRobot &robot, const RobotCommands &c, const real *q, const real *v, real *force_n,
                    real *rowing_nm) {
  for (int a = 0; a < robot.na; ++a) {
    if (c.actuator_mode[a] == CommandMode::Force) {
      force_n[a] = c.actuator[a];
      continue;
    }
    const RobotActuator &ac = robot.act[a];
    const real f = c.actuator_ff[a] + ac.kp * (c.actuator[a] - robot_actuator_length(robot, a, q)) -
                   ac.kd * robot_actuator_rate(robot, a, q, v);
    force_n[a] = std::max(-ac.max_force, std::min(ac.max_force, f));
  }
  for (int l = 0; l < robot.nlegs; ++l) {
    if (c.rowing_mode[l] == CommandMode::Force) {
      rowing_nm[l] = c.rowing[l];
      continue;
    }
    const real t = c.rowing_ff[l] +
                   robot.rowing_kp * std::remainder(c.rowing[l] - robot_rowing_angle(robot, l, q),
                                                    2 * real(3.14159265358979323846)) -
                   robot.rowing_kd * robot_rowing_rate(robot, l, q, v);
    rowing_nm[l] = std::max(-robot.rowing_max_torque, std::min(robot.rowing_max_torque, t));
  }
}

real robot_kinetic_energy(const SpatialRobot &robot, const real *v) {
  real T = 0;
  for (int b = 0; b < robot.nb; ++b) {
    const real *vb = v + kBodyDof * b;
    const V3 &I = robot.inertia[b];
    T += robot.mass[b] * (vb[0] * vb[0] + vb[1] * vb[1] + vb[2] * vb[2]) + I.x * vb[3] * vb[3] + I.y * vb[4] * vb[4] +
         I.z * vb[5] * vb[5];
  }
  return T / 2;
}

real robot_gravity_potential(const SpatialRobot &robot, const real *q) {
  real U = 0;
  for (int b = 0; b < robot.nb; ++b)
    U -= robot.mass[b] * (robot.gravity.x * q[kBodyConfig * b] + robot.gravity.y * q[kBodyConfig * b + 1] +
                          robot.gravity.z * q[kBodyConfig * b + 2]);
  return U;
}

V3 robot_foot_force(const SpatialRobot &robot, const RobotData &d, int l) {
  const uint32_t bit = 1u << l;
  if (d.hold.sliding & bit) {
    const V3 s = slip_direction(robot, d.hold, l, d.q, d.v, d.slip_dir[l]);
    return d.normal_force[l] * d.hold.normal - d.ground.mu_kinetic * d.normal_force[l] * s;
  }
  return foot_force(robot, d.hold, d.mu, l);
}

}  // namespace legsim::spatial
