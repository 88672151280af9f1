// The hexapod's inverse dynamics along the tripod gait (spatial/inverse, legsim_hexapod_inverse_dynamics),
// checked against statics, Newton-Euler and the forward dynamics:
// - at rest (v = a = 0) it is robot_statics, on a tripod and on six feet, to round-off;
// - along the gait: the box's Newton-Euler equations from the reported hip reactions and rowing
//   torques and its planned acceleration; the whole robot's momentum law with the centre of
//   mass's acceleration from second differences of the plan's assembled positions (independent
//   of the rows' accelerations): the ground forces' sum is M (a_com - g);
// - the rows hold along the plan: J v = 0 and J a = gamma with the stance feet stuck;
// - the forward dynamics' accelerations and ground forces at the plan's state under the computed
//   forces are the plan's and the computed ones;
// - a closed form: the tripod's box accelerating straight up from rest, the ground forces' sum
//   M (a_com - g), a_com = a_z d(com)/dz from assemblies with the box raised;
// - the computed forces fed to the forward dynamics (RK4 from the plan's state, the stance feet
//   stuck) follow the plan: through robot_step_rk4 the commands are held over a step (at its
//   middle), so the error falls as h^2 (the held commands' midpoint rule; RK4's own error is h^4,
//   below it); with the commands at RK4's stages (RK4 on the group written here, on the core's
//   forward solve) it falls as h^4.
// Runs from the source tree's root (legsim_add_unity_test's WORKING_DIRECTORY).
#include <cmath>
#include <algorithm>
#include <cstdio>
#include <vector>

#include "hexapod_standing.hpp"
#include "spatial/inverse.hpp"
#include "spatial/motion.hpp"

void setUp(void) {}
void tearDown(void) {}

namespace {
using namespace legsim::spatial;

constexpr uint32_t kTripod = 0x15;  // legs 0, 2, 4
constexpr uint32_t kSix = 0x3F;

// The gait of the tests: scenes/hexapod_walk.toml's, turning by 0.1 rad a stance (six feet stand over
// [0, 0.12) and [0.6, 0.72) s, a tripod alone between).
legsim_hexapod_gait walk_gait() { return {1.2, 0.6, 0.12, 0.05, 0.1, 1.0}; }

std::vector<unsigned char> &storage() {
  static std::vector<unsigned char> s(legsim_hexapod_inverse_storage_size() + 64);
  return s;
}
void *aligned() {
  auto p = reinterpret_cast<uintptr_t>(storage().data());
  return reinterpret_cast<void *>((p + 63) / 64 * 64);
}

struct Plan {
  double q[kBodyConfig * kMaxRobotBodies], v[kBodyDof * kMaxRobotBodies], a[kBodyDof * kMaxRobotBodies];
  int nb;
};
Plan plan_at(const legsim_hexapod_desc &h, const legsim_hexapod_gait &g, double t) {
  Plan p;
  int32_t n = 0;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_hexapod_gait_state(&h, &g, t, aligned(), legsim_hexapod_inverse_storage_size(),
                                                             p.q, p.v, p.a, kMaxRobotBodies, &n));
  p.nb = n;
  return p;
}
legsim_hexapod_inverse inverse_at(const legsim_hexapod_desc &h, const legsim_hexapod_gait &g, double t) {
  legsim_hexapod_inverse r;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_hexapod_inverse_dynamics(&h, &g, t, aligned(),
                                                                   legsim_hexapod_inverse_storage_size(), &r));
  return r;
}
V3 v3(const double *x) { return {x[0], x[1], x[2]}; }
double norm(const V3 &x) { return std::sqrt(dot(x, x)); }

void test_rest_is_statics(void) {
  const Standing &s = standing();
  const double zero[kBodyDof * kMaxRobotBodies] = {};
  for (uint32_t mask : {kTripod, kSix}) {
    RobotStatics st, id;
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_statics(s.robot, s.q, mask, nullptr, st));
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_inverse_dynamics(s.robot, s.q, zero, zero, mask, id));
    double df = 0, da = 0, dm = 0, fmax = 0, mmax = 0;
    for (int l = 0; l < 6; ++l) {
      df = std::fmax(df, norm(id.foot_force[l] - st.foot_force[l]));
      fmax = std::fmax(fmax, norm(st.foot_force[l]));
      da = std::fmax(da, std::fabs(id.rowing_torque[l] - st.rowing_torque[l]));
    }
    for (int a = 0; a < s.robot.na; ++a) da = std::fmax(da, std::fabs(id.actuator_force[a] - st.actuator_force[a]));
    for (int r = 0; r < s.robot.m; ++r) {
      dm = std::fmax(dm, std::fabs(id.multiplier[r] - st.multiplier[r]));
      mmax = std::fmax(mmax, std::fabs(st.multiplier[r]));
    }
    std::printf("rest (mask %#x): feet %.1e of %.0f N, actuators and torques %.1e, multipliers %.1e of %.0f\n", mask,
                df, fmax, da, dm, mmax);
    TEST_ASSERT_TRUE(df < 1e-11 * fmax);
    TEST_ASSERT_TRUE(da < 1e-11 * fmax);
    TEST_ASSERT_TRUE(dm < 1e-11 * mmax);
  }
}

// The box's Newton-Euler from the hips (each hip's reaction on its yoke, opposite on the box, at
// the hip's point) and the rowing torques' reactions; the whole robot's momentum law with the
// centre of mass's acceleration from second differences of the plan's positions.
void test_newton_euler_along_the_gait(void) {
  const Standing &s = standing();
  const SpatialRobot &R = s.robot;
  const legsim_hexapod_gait g = walk_gait();
  double worst_force = 0, worst_moment = 0, worst_com = 0, worst_sum = 0, a_com = 0, weight = s.M * 9.81;
  for (double t : {0.0, 0.05, 0.12, 0.25, 0.49, 0.6, 0.65, 0.77, 1.19}) {
    const legsim_hexapod_inverse r = inverse_at(s.desc, g, t);
    const Plan p = plan_at(s.desc, g, t);
    // the box
    const BodyState box = body_state(p.q, p.v);
    V3 F = R.mass[0] * R.gravity, Mw = {0, 0, 0};
    for (int l = 0; l < 6; ++l) {
      const RobotLeg &L = R.leg[l];
      const BodyState y = body_state(p.q + kBodyConfig * L.yoke, p.v + kBodyDof * L.yoke);
      // the hip's joint: the one on the yoke, at its point sa
      int j = 0;
      while (R.joint[j].a != L.yoke) ++j;
      const V3 ph = y.r + rotate(y.R, R.joint[j].sa);
      const V3 f = -1 * v3(r.joint_force_n[l][0]), m = -1 * v3(r.joint_moment_nm[l][0]);
      F = F + f;
      Mw = Mw + m + cross(ph - box.r, f) - r.rowing_torque_nm[l] * box.R.c2;
    }
    const V3 I = R.inertia[0], w = box.w, al = {p.a[3], p.a[4], p.a[5]};
    const V3 Iw = {I.x * w.x, I.y * w.y, I.z * w.z}, Ial = {I.x * al.x, I.y * al.y, I.z * al.z};
    const V3 lhs_m = rotate(box.R, Ial + cross(w, Iw)), lhs_f = R.mass[0] * V3{p.a[0], p.a[1], p.a[2]};
    worst_force = std::fmax(worst_force, norm(lhs_f - F));
    worst_moment = std::fmax(worst_moment, norm(lhs_m - Mw));
    // the whole robot: sum of the ground forces = M (a_com - g), a_com by second differences
    // (away from a lift-off or a touchdown, where a swinging foot's acceleration jumps)
    if (t == 0.0 || t == 0.12 || t == 0.6) continue;
    const double d = 1e-3;
    V3 com[3];
    for (int k = 0; k < 3; ++k) {
      const Plan pk = plan_at(s.desc, g, t + (k - 1) * d);
      com[k] = {0, 0, 0};
      for (int b = 0; b < pk.nb; ++b) com[k] = com[k] + R.mass[b] * v3(pk.q + kBodyConfig * b);
      com[k] = (1 / s.M) * com[k];
    }
    const V3 a_fd = (1 / (d * d)) * (com[2] - 2 * com[1] + com[0]);
    V3 a_rows = {0, 0, 0}, feet = {0, 0, 0};
    for (int b = 0; b < p.nb; ++b) a_rows = a_rows + (R.mass[b] / s.M) * v3(p.a + kBodyDof * b);
    for (int l = 0; l < 6; ++l) feet = feet + v3(r.foot_force_n[l]);
    a_com = std::fmax(a_com, norm(a_rows));
    worst_com = std::fmax(worst_com, norm(a_fd - a_rows));
    worst_sum = std::fmax(worst_sum, norm(feet - s.M * (a_fd - R.gravity)));
  }
  std::printf("the box's Newton-Euler: force %.1e N, moment %.1e N m; a_com (up to %.3f m/s^2) from the rows "
              "against second differences %.1e m/s^2; the ground forces' sum against M (a_com - g) %.1e N (weight "
              "%.0f N)\n",
              worst_force, worst_moment, a_com, worst_com, worst_sum, weight);
  TEST_ASSERT_TRUE(worst_force < 1e-9 * weight);
  TEST_ASSERT_TRUE(worst_moment < 1e-9 * weight);
  TEST_ASSERT_TRUE(worst_com < 5e-5);  // second differences: d^2 a''''/12, and the assembly's error / d^2
  TEST_ASSERT_TRUE(worst_sum < 1e-5 * weight);
}

// The rows at the plan's state: every joint's and each stance foot's held (J v = 0, J a = gamma).
void test_rows_hold_along_the_plan(void) {
  const Standing &s = standing();
  const SpatialRobot &R = s.robot;
  const legsim_hexapod_gait g = walk_gait();
  double phi = 0, vel = 0, acc = 0;
  for (double t : {0.07, 0.3, 0.55, 0.91}) {
    const Plan p = plan_at(s.desc, g, t);
    static Row rows[kMaxRobotRows];
    robot_rows(R, p.q, p.v, rows);
    for (int r = 0; r < R.m; ++r) {
      double jv = 0, ja = 0;
      for (int k = 0; k < 2; ++k) {
        const int b = R.row_body[r][k];
        if (b < 0) continue;
        const double *c = k == 0 ? rows[r].ja : rows[r].jb;
        for (int i = 0; i < kBodyDof; ++i) jv += c[i] * p.v[kBodyDof * b + i], ja += c[i] * p.a[kBodyDof * b + i];
      }
      phi = std::fmax(phi, std::fabs(rows[r].phi));
      vel = std::fmax(vel, std::fabs(jv));
      acc = std::fmax(acc, std::fabs(ja - rows[r].gamma));
    }
    // the stance feet at rest in the world, with no acceleration
    const legsim_hexapod_inverse inv = inverse_at(s.desc, g, t);
    for (int l = 0; l < 6; ++l) {
      if (!inv.stance[l]) continue;
      const RobotLeg &L = R.leg[l];
      const BodyState f = body_state(p.q + kBodyConfig * L.foot_body, p.v + kBodyDof * L.foot_body);
      const PointJet j = point_jet(f, L.foot_point);
      const V3 al = {p.a[kBodyDof * L.foot_body + 3], p.a[kBodyDof * L.foot_body + 4], p.a[kBodyDof * L.foot_body + 5]};
      const V3 pa = v3(p.a + kBodyDof * L.foot_body) + rotate(f.R, cross(al, L.foot_point)) + j.pq;
      vel = std::fmax(vel, norm(j.pd));
      acc = std::fmax(acc, norm(pa));
    }
  }
  std::printf("along the plan: |Phi| %.1e, |J v| %.1e, |J a - gamma| %.1e\n", phi, vel, acc);
  TEST_ASSERT_TRUE(phi < 1e-9);
  TEST_ASSERT_TRUE(vel < 1e-11);
  TEST_ASSERT_TRUE(acc < 1e-10);
}

// The forward dynamics from the plan's state, the stance feet stuck (no ground: no events), each
// step's commands the inverse dynamics' at its middle: the box's and the feet's distance from the
// plan after 0.2 s of a stance.
double tracking_error(const Standing &s, const legsim_hexapod_gait &g, double t0, double T, double h) {
  const SpatialRobot &R = s.robot;
  const Plan p0 = plan_at(s.desc, g, t0);
  const legsim_hexapod_inverse i0 = inverse_at(s.desc, g, t0);
  FeetHold hold;
  hold.stuck = 0, hold.sliding = 0;
  for (int l = 0; l < 6; ++l) {
    if (i0.stance[l]) hold.stuck |= 1u << l;
    hold.anchor[l] = robot_foot_position(R, l, p0.q);
  }
  static RobotData d;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_init(R, p0.q, p0.v, hold, nullptr, d));
  const int n = int(std::lround(T / h));
  for (int k = 0; k < n; ++k) {
    const legsim_hexapod_inverse u = inverse_at(s.desc, g, t0 + (k + 0.5) * h);
    for (int l = 0; l < 6; ++l) {
      for (int a = 0; a < 2; ++a) {
        d.command.actuator_mode[R.leg[l].first_actuator + a] = CommandMode::Force;
        d.command.actuator[R.leg[l].first_actuator + a] = u.actuator_force_n[l][a];
      }
      d.command.rowing_mode[l] = CommandMode::Force;
      d.command.rowing[l] = u.rowing_torque_nm[l];
    }
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_refresh(R, d));
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step_rk4(R, d, h));
  }
  const Plan p1 = plan_at(s.desc, g, t0 + n * h);
  double e = norm(v3(d.q) - v3(p1.q));
  for (int l = 0; l < 6; ++l) e = std::fmax(e, norm(robot_foot_position(R, l, d.q) - robot_foot_position(R, l, p1.q)));
  return e;
}

// The same with the commands at RK4's stages: classical RK4 on the group written here (the
// tableau on (dr, theta, v, omega), theta' = dexp^-1(theta) omega, as spatial/motion.cpp's; no
// projection) on the core's forward solve (robot_accelerations) with the inverse dynamics' forces
// at each stage's time. The plan is then followed at RK4's order.
double stage_commands_error(const Standing &s, const legsim_hexapod_gait &g, double t0, double T, double h) {
  const SpatialRobot &R = s.robot;
  const int nb = R.nb, nv = kBodyDof * nb;
  const Plan p0 = plan_at(s.desc, g, t0);
  const legsim_hexapod_inverse i0 = inverse_at(s.desc, g, t0);
  FeetHold hold;
  hold.stuck = 0, hold.sliding = 0;
  for (int l = 0; l < 6; ++l) {
    if (i0.stance[l]) hold.stuck |= 1u << l;
    hold.anchor[l] = robot_foot_position(R, l, p0.q);
  }
  static double q[kBodyConfig * kMaxRobotBodies], v[kMaxRobotDof], qs[kBodyConfig * kMaxRobotBodies],
      vs[kMaxRobotDof], d[kMaxRobotDof], kq[4][kMaxRobotDof], kv[4][kMaxRobotDof], Q[kMaxRobotDof], mu[kMaxSystemRows];
  static Row rows[kMaxSystemRows];
  static RobotFactor F;
  std::copy(p0.q, p0.q + kBodyConfig * nb, q);
  std::copy(p0.v, p0.v + nv, v);
  const int n = int(std::lround(T / h));
  const double c[4] = {0, 0.5, 0.5, 1}, w[4] = {1, 2, 2, 1};
  for (int k = 0; k < n; ++k) {
    const double t = t0 + k * h;
    std::fill(d, d + nv, 0.0);
    for (int st = 0; st < 4; ++st) {
      // the stage's state: q (+) c h k_{st-1} on the group, v + c h kv_{st-1}
      for (int i = 0; i < nv; ++i) d[i] = st ? c[st] * h * kq[st - 1][i] : 0, vs[i] = v[i] + (st ? c[st] * h * kv[st - 1][i] : 0);
      for (int b = 0; b < nb; ++b) config_add(q + kBodyConfig * b, d + kBodyDof * b, qs + kBodyConfig * b);
      const legsim_hexapod_inverse u = inverse_at(s.desc, g, t + c[st] * h);
      double force[kMaxRobotActuators] = {}, torque[kMaxLegs] = {};
      for (int l = 0; l < 6; ++l) {
        for (int a = 0; a < 2; ++a) force[R.leg[l].first_actuator + a] = u.actuator_force_n[l][a];
        torque[l] = u.rowing_torque_nm[l];
      }
      robot_forces(R, qs, vs, force, torque, Q);
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_accelerations(R, hold, qs, vs, Q, kv[st], mu, rows, F));
      for (int b = 0; b < nb; ++b) {
        const double *db = d + kBodyDof * b, *vb = vs + kBodyDof * b;
        const V3 th = dexp_inv({db[3], db[4], db[5]}, {vb[3], vb[4], vb[5]});
        const double r[kBodyDof] = {vb[0], vb[1], vb[2], th.x, th.y, th.z};
        for (int i = 0; i < kBodyDof; ++i) kq[st][kBodyDof * b + i] = r[i];
      }
    }
    for (int i = 0; i < nv; ++i) {
      double sq = 0, sv = 0;
      for (int st = 0; st < 4; ++st) sq += w[st] * kq[st][i], sv += w[st] * kv[st][i];
      d[i] = h / 6 * sq, v[i] += h / 6 * sv;
    }
    for (int b = 0; b < nb; ++b) {
      double qb[kBodyConfig];
      config_add(q + kBodyConfig * b, d + kBodyDof * b, qb);
      std::copy(qb, qb + kBodyConfig, q + kBodyConfig * b);
    }
  }
  const Plan p1 = plan_at(s.desc, g, t0 + n * h);
  double e = norm(v3(q) - v3(p1.q));
  for (int l = 0; l < 6; ++l) e = std::fmax(e, norm(robot_foot_position(R, l, q) - robot_foot_position(R, l, p1.q)));
  return e;
}

// The error over 0.2 s of a stance from t = 0.15 s at each of hs, printed; the observed orders
// between neighbours in (lo, hi) and the finest error below `finest`.
void check_orders(const char *what, double (*error)(const Standing &, const legsim_hexapod_gait &, double, double, double),
                  const double (&hs)[4], double lo, double hi, double finest) {
  const Standing &s = standing();
  const legsim_hexapod_gait g = walk_gait();
  double e[4];
  for (int k = 0; k < 4; ++k) {
    e[k] = error(s, g, 0.15, 0.2, hs[k]);
    std::printf("%s, 0.2 s of a stance, h = %g ms: %.3e m\n", what, hs[k] * 1e3, e[k]);
  }
  for (int k = 1; k < 4; ++k) {
    const double order = std::log2(e[k - 1] / e[k]);
    std::printf("  order %.2f\n", order);
    TEST_ASSERT_TRUE(order > lo && order < hi);
  }
  TEST_ASSERT_TRUE(e[3] < finest);
}

void test_stage_commands_follow_the_plan_at_order_4(void) {
  check_orders("commands at RK4's stages", stage_commands_error, {40e-3, 20e-3, 10e-3, 5e-3}, 3.7, 4.6, 2e-9);
}

void test_forward_dynamics_follows_the_plan(void) {
  check_orders("tracking with the commands held over each step", tracking_error, {8e-3, 4e-3, 2e-3, 1e-3}, 1.8, 2.3,
               1e-5);
}

// The forward dynamics' accelerations at the plan's state under the computed forces (the stance
// feet stuck) are the plan's, and its stance feet's forces the computed ones: with the actuators
// and motors given, the forward problem has one solution.
void test_forward_accelerations_are_the_plan(void) {
  const Standing &s = standing();
  const SpatialRobot &R = s.robot;
  const legsim_hexapod_gait g = walk_gait();
  double da = 0, amax = 0, df = 0, fmax = 0;
  for (double t : {0.05, 0.3, 0.62, 0.9}) {
    const Plan p = plan_at(s.desc, g, t);
    const legsim_hexapod_inverse u = inverse_at(s.desc, g, t);
    FeetHold hold;
    hold.stuck = 0, hold.sliding = 0;
    for (int l = 0; l < 6; ++l) {
      if (u.stance[l]) hold.stuck |= 1u << l;
      hold.anchor[l] = robot_foot_position(R, l, p.q);
    }
    double force[kMaxRobotActuators] = {}, torque[kMaxLegs] = {};
    for (int l = 0; l < 6; ++l) {
      for (int a = 0; a < 2; ++a) force[R.leg[l].first_actuator + a] = u.actuator_force_n[l][a];
      torque[l] = u.rowing_torque_nm[l];
    }
    static double Q[kMaxRobotDof], a[kMaxRobotDof], mu[kMaxSystemRows];
    static Row rows[kMaxSystemRows];
    static RobotFactor F;
    robot_forces(R, p.q, p.v, force, torque, Q);
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_accelerations(R, hold, p.q, p.v, Q, a, mu, rows, F));
    for (int i = 0; i < kBodyDof * p.nb; ++i) da = std::fmax(da, std::fabs(a[i] - p.a[i])), amax = std::fmax(amax, std::fabs(p.a[i]));
    for (int l = 0; l < 6; ++l) {
      df = std::fmax(df, norm(foot_force(R, hold, mu, l) - v3(u.foot_force_n[l])));
      fmax = std::fmax(fmax, norm(v3(u.foot_force_n[l])));
    }
  }
  std::printf("forward dynamics at the plan under the computed forces: accelerations %.1e of %.1f, feet's forces %.1e "
              "of %.0f N\n", da, amax, df, fmax);
  TEST_ASSERT_TRUE(da < 1e-9 * amax);
  TEST_ASSERT_TRUE(df < 1e-9 * fmax);
}

// The closed form of the centre of mass: the box of the standing tripod accelerating straight up
// from rest, the feet stuck. The centre of mass then accelerates at a_z d(com)/dz (its velocity
// zero), d(com)/dz by central differences of the robot assembled with the box raised (each leg
// by its planar inverse kinematics to its foot, as the gait's set-points), and the ground's
// vertical forces sum to M (g + a_com,z), the horizontal ones to M a_com,xy.
void test_tripod_box_accelerating_up(void) {
  const Standing &s = standing();
  const SpatialRobot &R = s.robot;
  alignas(16) static unsigned char leg_storage[1 << 16];
  auto assemble_raised = [&](double dz, double *q) {
    const double *qs[6], *vs[6];
    static double leg_q[6][3 * LEGSIM_MAX_BODIES], zero[3 * LEGSIM_MAX_BODIES];
    double psi[6], psid[6] = {}, v[kBodyDof * kMaxRobotBodies];
    for (int l = 0; l < 6; ++l) {
      const V3 foot = robot_foot_position(R, l, s.q) - V3{0, 0, dz};  // held in the world: the box rose by dz
      double xy[2];
      leg_plane_target(R, l, foot, psi[l], xy);
      legsim_options opt = legsim_default_options();
      legsim_sim *sim = nullptr;
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(leg_storage, sizeof leg_storage, &s.desc.leg[l].leg, &opt, &sim));
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_foot(sim, xy));
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_get_q(sim, leg_q[l]));
      qs[l] = leg_q[l], vs[l] = zero;
    }
    const double box_q[7] = {0, 0, dz, 1, 0, 0, 0}, box_v[6] = {};
    robot_state(R, box_q, box_v, qs, vs, psi, psid, q, v);
  };
  auto com = [&](const double *q) {
    V3 c = {0, 0, 0};
    for (int b = 0; b < R.nb; ++b) c = c + R.mass[b] * v3(q + kBodyConfig * b);
    return (1 / s.M) * c;
  };
  static double q0[kBodyConfig * kMaxRobotBodies], qp[kBodyConfig * kMaxRobotBodies],
      qm[kBodyConfig * kMaxRobotBodies];
  const double d = 1e-4;
  assemble_raised(0, q0);
  assemble_raised(d, qp);
  assemble_raised(-d, qm);
  const V3 dcom = (1 / (2 * d)) * (com(qp) - com(qm));
  for (double az : {0.0, 2.0, -3.0}) {
    static double v[kMaxRobotDof], a[kMaxRobotDof];
    const double box_v[6] = {}, box_a[6] = {0, 0, az, 0, 0, 0};
    V3 feet_v[6] = {}, feet_a[6] = {};
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_prescribed_motion(R, q0, box_v, box_a, feet_v, feet_a, v, a));
    RobotStatics out;
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_inverse_dynamics(R, q0, v, a, kTripod, out));
    V3 sum = {0, 0, 0};
    for (int l = 0; l < 6; ++l) sum = sum + out.foot_force[l];
    const V3 closed = s.M * (az * dcom - R.gravity);
    std::printf("tripod, box at %+.1f m/s^2 up: sum of the ground forces (%.6f, %.6f, %.6f) N, closed form (%.6f, "
                "%.6f, %.6f) N (%.1e N apart); d(com)/dz = (%.4f, %.4f, %.4f)\n",
                az, sum.x, sum.y, sum.z, closed.x, closed.y, closed.z, norm(sum - closed), dcom.x, dcom.y, dcom.z);
    TEST_ASSERT_TRUE(norm(sum - closed) < 1e-6 * s.M * 9.81);
  }
}

void test_bad_input(void) {
  const Standing &s = standing();
  legsim_hexapod_gait g = walk_gait();
  legsim_hexapod_inverse r;
  const size_t n = legsim_hexapod_inverse_storage_size();
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_NULL, legsim_hexapod_inverse_dynamics(nullptr, &g, 0, aligned(), n, &r));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_STORAGE, legsim_hexapod_inverse_dynamics(&s.desc, &g, 0, aligned(), n - 1, &r));
  g.duty = 1.2;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_inverse_dynamics(&s.desc, &g, 0, aligned(), n, &r));
  g = walk_gait();
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, legsim_hexapod_inverse_dynamics(&s.desc, &g, NAN, aligned(), n, &r));
}
}  // namespace

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_rest_is_statics);
  RUN_TEST(test_newton_euler_along_the_gait);
  RUN_TEST(test_rows_hold_along_the_plan);
  RUN_TEST(test_forward_accelerations_are_the_plan);
  RUN_TEST(test_tripod_box_accelerating_up);
  RUN_TEST(test_forward_dynamics_follows_the_plan);
  RUN_TEST(test_stage_commands_follow_the_plan_at_order_4);
  RUN_TEST(test_bad_input);
  return UNITY_END();
}
