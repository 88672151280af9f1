// The hexapod of models/hexapod.toml moving (spatial/dynamics, spatial/motion), checked against
// another solve and against invariants:
// - the leg-by-leg solve with the box's Schur complement gives the dense KKT system's
//   accelerations and multipliers (Eigen's full-pivot LU) with the box turning, the legs rowing
//   and a tripod's feet stuck;
// - standing (robot_statics' actuator forces and rowing torques, on six feet and on a tripod)
//   is rest: no acceleration, the stuck feet's forces the statics', and it stays so over 0.2 s;
// - in flight without gravity, under the actuators' and motors' forces (internal to the robot)
//   the linear and angular momenta stay constant, and the energy (kinetic, less the work the
//   constant forces would do back) at RK4's order;
// - the paper's Fig. 7 on six feet (the stand's statics plus 50 N on the three right legs' upper
//   actuators): the box's path converges at order 4 over h = 8 .. 1 ms, the feet stay where they
//   stand, the energy holds;
// - with generalized-alpha: statics is rest, Fig. 7 at order 2, the drop's invariants;
// - bad input refused, data unchanged.
// Runs from the source tree's root (legsim_add_unity_test's WORKING_DIRECTORY).
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>

#include "hexapod_standing.hpp"
#include "spatial_kkt.hpp"
#include "spatial/motion.hpp"
#include "spatial/statics.hpp"

void setUp(void) {}
void tearDown(void) {}

namespace {
using namespace legsim::spatial;
using Eigen::VectorXd;

constexpr uint32_t kTripod = 0x15;  // legs 0, 2, 4
constexpr uint32_t kSix = 0x3F;

FeetHold hold_at(const SpatialRobot &robot, const double *q, uint32_t stuck) {
  FeetHold h;
  h.stuck = stuck;
  h.sliding = 0;
  for (int l = 0; l < robot.nlegs; ++l) h.anchor[l] = robot_foot_position(robot, l, q);
  return h;
}

// The state of the stand with the box turning and moving and the legs rowing (the legs' own
// planar coordinates at rest).
void moving_state(const Standing &s, double *q, double *v) {
  static double zero[3 * LEGSIM_MAX_BODIES];
  const double *qs[6], *vs[6];
  double psi[6] = {0.3, 0.1, -0.2, 0.0, 0.25, -0.15}, psid[6] = {0.5, -0.4, 0.3, 0.8, -0.6, 0.2};
  for (int l = 0; l < 6; ++l) qs[l] = s.leg_q, vs[l] = zero;
  const Quat tilt = quat_exp({0.1, -0.05, 0.3});
  const double box_q[7] = {0.02, -0.01, 0.03, tilt.w, tilt.x, tilt.y, tilt.z};
  const double box_v[6] = {0.2, -0.1, 0.05, 0.3, -0.2, 0.6};
  robot_state(s.robot, box_q, box_v, qs, vs, psi, psid, q, v);
}

// The rows' number in use and their indices (the joints', then the stuck feet's).
int used(const SpatialRobot &robot, uint32_t stuck, int *idx) {
  int n = 0;
  for (int r = 0; r < robot.m; ++r) idx[n++] = r;
  for (int l = 0; l < robot.nlegs; ++l)
    if ((stuck >> l) & 1u)
      for (int k = 0; k < 3; ++k) idx[n++] = foot_row(robot, l) + k;  // stuck: the normal's, t1's, t2's
  return n;
}

// Linear and angular (about the world's origin) momentum.
void momentum(const SpatialRobot &robot, const double *q, const double *v, V3 &p, V3 &L) {
  p = {0, 0, 0}, L = {0, 0, 0};
  for (int b = 0; b < robot.nb; ++b) {
    const double *qb = q + kBodyConfig * b, *vb = v + kBodyDof * b;
    const V3 mv = robot.mass[b] * V3{vb[0], vb[1], vb[2]};
    const V3 &I = robot.inertia[b];
    const V3 Iw = {I.x * vb[3], I.y * vb[4], I.z * vb[5]};
    p = p + mv;
    L = L + cross({qb[0], qb[1], qb[2]}, mv) + rotate(rotation({qb[3], qb[4], qb[5], qb[6]}), Iw);
  }
}

double norm(const V3 &a) { return std::sqrt(dot(a, a)); }

// The stand's statics on the stance as commands, the stance's feet stuck where they stand.
std::unique_ptr<RobotData> standing_data(const Standing &s, uint32_t stance) {
  static RobotStatics st;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_statics(s.robot, s.q, stance, nullptr, st));
  static double v[kMaxRobotDof];
  auto d = std::make_unique<RobotData>();
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_init(s.robot, s.q, v, hold_at(s.robot, s.q, stance), nullptr, *d));
  for (int a = 0; a < s.robot.na; ++a) d->command.actuator[a] = st.actuator_force[a];
  for (int l = 0; l < s.robot.nlegs; ++l) d->command.rowing[l] = st.rowing_torque[l];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_refresh(s.robot, *d));
  return d;
}
}  // namespace

const char *label(Integrator integrator) { return integrator == Integrator::Rk4 ? "" : "generalized-alpha: "; }

void test_solve_is_the_dense_kkt(void) {
  const Standing &s = standing();
  const SpatialRobot &R = s.robot;
  static double q[kBodyConfig * kMaxRobotBodies], v[kMaxRobotDof], Q[kMaxRobotDof], a[kMaxRobotDof];
  static double mu[kMaxSystemRows];
  static Row rows[kMaxSystemRows];
  moving_state(s, q, v);
  double force[kMaxRobotActuators], tau[kMaxLegs];
  for (int k = 0; k < R.na; ++k) force[k] = 40.0 * std::sin(1.0 + k);
  for (int l = 0; l < R.nlegs; ++l) tau[l] = 3.0 * std::cos(2.0 + l);
  robot_forces(R, q, v, force, tau, Q);
  for (uint32_t stuck : {0u, kTripod}) {
    const FeetHold hold = hold_at(R, q, stuck);
    static RobotFactor F;
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_accelerations(R, hold, q, v, Q, a, mu, rows, F));
    int idx[kMaxSystemRows];
    const int m = used(R, stuck, idx), nv = kBodyDof * R.nb;
    VectorXd rhs(nv + m);
    for (int i = 0; i < nv; ++i) rhs[i] = Q[i];
    for (int i = 0; i < m; ++i) rhs[nv + i] = rows[idx[i]].gamma;
    const VectorXd x = spatial_kkt::matrix(R, rows, idx, m).fullPivLu().solve(rhs);
    double da = 0, sa = 0, dl = 0, sl = 0;
    for (int k = 0; k < nv; ++k) da = std::fmax(da, std::fabs(a[k] - x[k])), sa = std::fmax(sa, std::fabs(x[k]));
    for (int i = 0; i < m; ++i)
      dl = std::fmax(dl, std::fabs(mu[idx[i]] - x[nv + i])), sl = std::fmax(sl, std::fabs(x[nv + i]));
    printf("stuck 0x%02x: %d rows; accelerations off the dense solve by %.2e of %.2e, multipliers %.2e of %.2e\n",
           stuck, m, da, sa, dl, sl);
    TEST_ASSERT_TRUE(sa > 1 && sl > 1);
    TEST_ASSERT_TRUE(da < 1e-11 * sa);
    TEST_ASSERT_TRUE(dl < 1e-11 * sl);
  }
}

void statics_is_rest(Integrator integrator) {
  const Standing &s = standing();
  const SpatialRobot &R = s.robot;
  for (uint32_t stance : {kSix, kTripod}) {
    static RobotStatics st;
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_statics(R, s.q, stance, nullptr, st));
    auto d = standing_data(s, stance);
    double amax = 0, fmax = 0, fdiff = 0;
    for (int k = 0; k < kBodyDof * R.nb; ++k) amax = std::fmax(amax, std::fabs(d->a[k]));
    for (int l = 0; l < R.nlegs; ++l) {
      if (!((stance >> l) & 1u)) continue;
      const V3 f = foot_force(R, d->hold, d->mu, l);
      fdiff = std::fmax(fdiff, norm(f - st.foot_force[l]));
      fmax = std::fmax(fmax, norm(f));
    }
    double drift = 0;
    for (int n = 0; n < 200; ++n) TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step(R, *d, 1e-3, integrator));
    for (int k = 0; k < kBodyConfig * R.nb; ++k) drift = std::fmax(drift, std::fabs(d->q[k] - s.q[k]));
    printf("%sstance 0x%02x: largest acceleration %.2e, feet's forces off the statics by %.2e N of %.1f N; "
           "after 0.2 s moved %.2e\n",
           label(integrator), stance, amax, fdiff, fmax, drift);
    TEST_ASSERT_TRUE(fmax > 50);
    TEST_ASSERT_TRUE(amax < 1e-10);
    TEST_ASSERT_TRUE(fdiff < 1e-10 * fmax);
    TEST_ASSERT_TRUE(drift < 1e-12);
  }
}
void test_statics_is_rest(void) { statics_is_rest(Integrator::Rk4); }
void test_statics_is_rest_galpha(void) { statics_is_rest(Integrator::GeneralizedAlpha); }

// In flight without gravity the actuators' and motors' forces are internal: the linear momentum
// stays (both integrators update velocities linearly in accelerations whose forces sum to zero,
// and the projections' impulses are internal too), the angular momentum and the energy at the
// integrator's order (RK4: the energy's error falls by 2^4 = 16 for a halved step, generalized-
// alpha by 2^2 = 4).
void flight_keeps_momentum_and_energy(Integrator integrator, double angular_tol, double ratio_lo, double ratio_hi) {
  const Standing &s = standing();
  static SpatialRobot R;
  R = s.robot;
  R.gravity = {0, 0, 0};
  static double q[kBodyConfig * kMaxRobotBodies], v[kMaxRobotDof];
  moving_state(s, q, v);
  double dE[2];
  for (int run = 0; run < 2; ++run) {
    const double h = run == 0 ? 2e-3 : 1e-3;
    auto d = std::make_unique<RobotData>();
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_init(R, q, v, hold_at(R, q, 0), nullptr, *d));
    for (int a = 0; a < R.na; ++a) d->command.actuator[a] = 20.0 * std::sin(0.5 + a);
    for (int l = 0; l < R.nlegs; ++l) d->command.rowing[l] = 0.5 * std::cos(1.5 + l);
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_refresh(R, *d));
    V3 p0, L0, p1, L1;
    momentum(R, d->q, d->v, p0, L0);
    const double E0 = robot_energy(R, *d);
    const int n = int(std::lround(0.2 / h));
    for (int k = 0; k < n; ++k) TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step(R, *d, h, integrator));
    momentum(R, d->q, d->v, p1, L1);
    dE[run] = std::fabs(robot_energy(R, *d) - E0);
    printf("%sflight, h = %.0e s: momentum off by %.2e of %.2e kg m/s, angular %.2e of %.2e kg m^2/s; "
           "energy %.3e of kinetic %.3e J\n",
           label(integrator), h, norm(p1 - p0), norm(p0), norm(L1 - L0), norm(L0), dE[run],
           robot_kinetic_energy(R, d->v));
    TEST_ASSERT_TRUE(norm(p1 - p0) < 1e-13 * norm(p0));
    TEST_ASSERT_TRUE(norm(L1 - L0) < angular_tol * norm(L0));
  }
  printf("%sflight energy error ratio over a halved step: %.1f\n", label(integrator), dE[0] / dE[1]);
  TEST_ASSERT_TRUE(dE[0] / dE[1] > ratio_lo && dE[0] / dE[1] < ratio_hi);
}
void test_flight_keeps_momentum_and_energy(void) { flight_keeps_momentum_and_energy(Integrator::Rk4, 1e-9, 12, 20); }
void test_flight_keeps_momentum_and_energy_galpha(void) {
  flight_keeps_momentum_and_energy(Integrator::GeneralizedAlpha, 1e-5, 3, 5);
}

// The orders expected: RK4's 4, generalized-alpha's 2; the energy's drift at h = 2 ms bounded by
// each one's error there.
void fig7_converges(Integrator integrator, double order_lo, double order_hi, double energy_at_2ms) {
  const Standing &s = standing();
  const SpatialRobot &R = s.robot;
  const double hs[4] = {8e-3, 4e-3, 2e-3, 1e-3}, T = 0.4;
  V3 box[4];
  double dE[4];
  for (int run = 0; run < 4; ++run) {
    auto d = standing_data(s, kSix);
    for (int l = 0; l < 3; ++l) d->command.actuator[R.leg[l].first_actuator] += 50;  // the right legs' upper ones
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_refresh(R, *d));
    const double E0 = robot_energy(R, *d);
    const int n = int(std::lround(T / hs[run]));
    double feet = 0;
    for (int k = 0; k < n; ++k) {
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step(R, *d, hs[run], integrator));
      for (int l = 0; l < 6; ++l) feet = std::fmax(feet, norm(robot_foot_position(R, l, d->q) - d->hold.anchor[l]));
    }
    box[run] = {d->q[0], d->q[1], d->q[2]};
    dE[run] = robot_energy(R, *d) - E0;
    printf("%sFig. 7 on six feet, h = %.1e s: box at (%.9f, %.9f, %.9f) m, feet off their places %.1e m, "
           "energy %+.2e J\n",
           label(integrator), hs[run], box[run].x, box[run].y, box[run].z, feet, dE[run]);
    TEST_ASSERT_TRUE(feet < 1e-12);
  }
  TEST_ASSERT_TRUE(norm(box[3] - V3{s.q[0], s.q[1], s.q[2]}) > 0.05);  // the box moves
  for (int k = 0; k < 2; ++k) {
    const double order = std::log2(norm(box[k] - box[k + 1]) / norm(box[k + 1] - box[k + 2]));
    printf("%sorder between h = %.1e and %.1e s: %.2f (differences %.2e, %.2e m)\n", label(integrator), hs[k],
           hs[k + 2], order,
           norm(box[k] - box[k + 1]), norm(box[k + 1] - box[k + 2]));
    TEST_ASSERT_TRUE(order > order_lo && order < order_hi);
  }
  TEST_ASSERT_TRUE(std::fabs(dE[2]) < energy_at_2ms);
}
void test_fig7_on_six_feet_converges_at_order_4(void) { fig7_converges(Integrator::Rk4, 3.5, 4.5, 1e-7); }
void test_fig7_on_six_feet_converges_at_order_2_galpha(void) {
  fig7_converges(Integrator::GeneralizedAlpha, 1.8, 2.3, 5e-5);
}

namespace {
// The fixture's stand moved up so that its feet are `lift` m above the ground of the file (z = 0).
void lifted_stand(const Standing &s, double lift, double *q) {
  std::copy(s.q, s.q + kBodyConfig * s.robot.nb, q);
  const double dz = lift - robot_foot_position(s.robot, 0, s.q).z;
  for (int b = 0; b < s.robot.nb; ++b) q[kBodyConfig * b + 2] += dz;
}
GroundPlane file_ground(const Standing &s) {
  const legsim_hexapod_desc &h = s.desc;
  return {{h.ground_point_m[0], h.ground_point_m[1], h.ground_point_m[2]},
          {h.ground_normal[0], h.ground_normal[1], h.ground_normal[2]}, h.mu_static, h.mu_kinetic};
}
struct Checked {
  double worst_under, energy_rise, worst_cone, worst_pull;
  int events, impacts;
};
// Steps d to T (s) at h, checking at every step: no foot under the ground; the energy (kinetic,
// gravity's, less the commands' work) not rising by more than the integrator's error; every
// stuck foot inside its cone and every foot on the ground pushing.
Checked run_checked(const SpatialRobot &R, RobotData &d, double T, double h, Integrator integrator) {
  Checked c = {0, 0, 0, 0, 0, 0};
  const GroundPlane &g = d.ground;
  double E = robot_energy(R, d);
  for (int n = 0; n < int(std::lround(T / h)); ++n) {
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step(R, d, h, integrator));
    c.events += d.events;
    const double E1 = robot_energy(R, d);
    c.energy_rise = std::fmax(c.energy_rise, E1 - E);
    E = E1;
    for (int l = 0; l < R.nlegs; ++l) {
      const V3 p = robot_foot_position(R, l, d.q);
      c.worst_under = std::fmax(c.worst_under, -dot(p - g.point, g.normal));
      const V3 f = robot_foot_force(R, d, l);
      const double N = dot(f, g.normal), Ft = norm(f - N * g.normal);
      if ((d.hold.stuck | d.hold.sliding) >> l & 1u) c.worst_pull = std::fmax(c.worst_pull, -N);
      if (d.hold.stuck >> l & 1u) c.worst_cone = std::fmax(c.worst_cone, Ft - g.mu_static * N);
    }
  }
  c.impacts = d.impacts;
  return c;
}
}  // namespace

void drop_onto_the_ground(Integrator integrator) {
  // Six feet 2 cm above the ground, the legs held by the stand's statics forces: the robot falls,
  // its feet touch down (impacts on their cones) and it stands.
  const Standing &s = standing();
  const SpatialRobot &R = s.robot;
  static RobotStatics st;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_statics(R, s.q, kSix, nullptr, st));
  static double q[kBodyConfig * kMaxRobotBodies], v[kMaxRobotDof];
  lifted_stand(s, 0.02, q);
  const GroundPlane g = file_ground(s);
  auto d = std::make_unique<RobotData>();
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_init(R, q, v, hold_at(R, q, 0), &g, *d));
  for (int a = 0; a < R.na; ++a) d->command.actuator[a] = st.actuator_force[a];
  for (int l = 0; l < R.nlegs; ++l) d->command.rowing[l] = st.rowing_torque[l];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_refresh(R, *d));
  const Checked c = run_checked(R, *d, 0.3, 1e-3, integrator);
  int on = 0;
  for (int l = 0; l < 6; ++l) on += (d->hold.stuck | d->hold.sliding) >> l & 1u;
  printf("%sdrop from 2 cm: %d events, %d impacts, last impact's contact problem %s in %d iterations (residual "
         "%.1e); feet on the ground at 0.3 s: %d; deepest %.1e m; energy rise at most %.1e J; cone excess %.1e N, "
         "pull %.1e N; kinetic at the end %.2e J\n",
         label(integrator), c.events, c.impacts, d->impact.converged ? "converged" : "NOT converged",
         d->impact.iterations,
         d->impact.residual, on, c.worst_under, c.energy_rise, c.worst_cone, c.worst_pull,
         robot_kinetic_energy(R, d->v));
  TEST_ASSERT_TRUE(c.impacts >= 1 && d->impact.converged);
  TEST_ASSERT_EQUAL_INT(6, on);
  TEST_ASSERT_TRUE(c.worst_under < 1e-9);
  TEST_ASSERT_TRUE(c.energy_rise < 1e-6);
  TEST_ASSERT_TRUE(c.worst_cone < 1e-6 && c.worst_pull < 1e-6);
}
void test_drop_onto_the_ground(void) { drop_onto_the_ground(Integrator::Rk4); }
void test_drop_onto_the_ground_galpha(void) { drop_onto_the_ground(Integrator::GeneralizedAlpha); }

void test_refuses_bad_input(void) {
  const Standing &s = standing();
  const SpatialRobot &R = s.robot;
  auto d = standing_data(s, kSix);
  const RobotData before = *d;
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, robot_step_rk4(R, *d, 0));
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, robot_step_rk4(R, *d, NAN));
  d->hold.stuck = 0x40;  // a seventh leg
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, robot_data_refresh(R, *d));
  d->hold.stuck = before.hold.stuck;
  TEST_ASSERT_EQUAL_INT(0, std::memcmp(&before, d.get(), sizeof before));
  static double v[kMaxRobotDof];
  FeetHold bad = hold_at(R, s.q, 0x80);
  auto e = std::make_unique<RobotData>();
  TEST_ASSERT_EQUAL_INT(LEGSIM_ERR_BAD_INPUT, robot_data_init(R, s.q, v, bad, nullptr, *e));
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_solve_is_the_dense_kkt);
  RUN_TEST(test_statics_is_rest);
  RUN_TEST(test_flight_keeps_momentum_and_energy);
  RUN_TEST(test_fig7_on_six_feet_converges_at_order_4);
  RUN_TEST(test_drop_onto_the_ground);
  RUN_TEST(test_refuses_bad_input);
  RUN_TEST(test_statics_is_rest_galpha);
  RUN_TEST(test_fig7_on_six_feet_converges_at_order_2_galpha);
  RUN_TEST(test_drop_onto_the_ground_galpha);
  RUN_TEST(test_flight_keeps_momentum_and_energy_galpha);
  return UNITY_END();
}
