// The hexapod's feet on the ground's circular cone (spatial/contact, spatial/motion), against
// Coulomb's law and the energy:
// - a foot slipping: the stand on six feet on a slippery ground (mu 0.1 and 0.08), under the
//   stand's statics forces but 80 N less on every lower actuator (the knees give, the feet push
//   out): the feet start to slip (stick to slip, decided on the cones), and every sliding foot's ground force is on its kinetic cone,
//   |F_t| = mu_k N, against its slip velocity (exactly, above 0.1 mm/s), while every stuck one
//   is inside its static cone;
// - the friction's work is the energy lost: the robot's energy (kinetic, gravity's, less the
//   commands' work) falls by the integral of the sliding feet's friction power, to the
//   quadrature's error;
// - on frictionless ground (mu 0) the feet slide without loss: with no impact the energy holds at
//   the integrator's order (RK4 4, generalized-alpha 2), and the horizontal momentum, which no
//   force changes there, stays to round-off.
// Runs from the source tree's root (legsim_add_unity_test's WORKING_DIRECTORY).
#include <cmath>
#include <cstdio>
#include <memory>

#include "hexapod_standing.hpp"
#include "spatial/motion.hpp"
#include "spatial/statics.hpp"

void setUp(void) {}
void tearDown(void) {}

namespace {
using namespace legsim::spatial;

double norm(const V3 &a) { return std::sqrt(dot(a, a)); }

// The sliding feet's friction power (W) at d's state: the tangential ground force on the slip.
double friction_power(const SpatialRobot &R, const RobotData &d) {
  double P = 0;
  for (int l = 0; l < R.nlegs; ++l) {
    if (!((d.hold.sliding >> l) & 1u)) continue;
    V3 p, pv;
    foot_motion(R, l, d.q, d.v, p, pv);
    P += dot(robot_foot_force(R, d, l), pv);
  }
  return P;
}
}  // namespace

void test_feet_slip_on_a_slippery_ground(void) {
  const Standing &s = standing();
  const SpatialRobot &R = s.robot;
  static RobotStatics st;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_statics(R, s.q, 0x3F, nullptr, st));
  // the ground through the stand's feet, slippery
  const V3 foot0 = robot_foot_position(R, 0, s.q);
  const GroundPlane g = {{0, 0, foot0.z}, {0, 0, 1}, 0.1, 0.08};
  static double v[kMaxRobotDof];
  FeetHold hold;
  hold.stuck = 0x3F, hold.sliding = 0;
  for (int l = 0; l < 6; ++l) hold.anchor[l] = robot_foot_position(R, l, s.q);
  auto d = std::make_unique<RobotData>();
  // at zero commands the stand would fall: its statics' forces from the start
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_init(R, s.q, v, hold, &g, *d));
  // and 80 N less on every lower actuator: the knees give, the feet push out
  for (int a = 0; a < R.na; ++a) d->command.actuator[a] = st.actuator_force[a] - (a % 2 ? 80.0 : 0.0);
  for (int l = 0; l < R.nlegs; ++l) d->command.rowing[l] = st.rowing_torque[l];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_refresh(R, *d));
  const double h = 1e-4;
  double E0 = 0, work = 0, P0 = 0, worst_cone = 0, worst_dir = 0, worst_stuck = 0;
  int slid = 0, sliding_samples = 0;
  for (int n = 0; n < 2000; ++n) {  // 0.2 s
    if (n == 0) {
      // the first step settles the modes the slippery cones refuse
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step_rk4(R, *d, h));
      E0 = robot_energy(R, *d), P0 = friction_power(R, *d);
      continue;
    }
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step_rk4(R, *d, h));
    const double P1 = friction_power(R, *d);
    work += 0.5 * h * (P0 + P1);
    P0 = P1;
    slid |= int(d->hold.sliding);
    for (int l = 0; l < 6; ++l) {
      const V3 f = robot_foot_force(R, *d, l);
      const double N = f.z, Ft = std::hypot(f.x, f.y);
      if ((d->hold.sliding >> l) & 1u) {
        ++sliding_samples;
        worst_cone = std::fmax(worst_cone, std::fabs(Ft - g.mu_kinetic * N) / N);
        V3 p, pv;
        foot_motion(R, l, d->q, d->v, p, pv);
        const V3 vt = {pv.x, pv.y, 0};
        if (norm(vt) > 1e-4) worst_dir = std::fmax(worst_dir, norm((1 / Ft) * V3{f.x, f.y, 0} + (1 / norm(vt)) * vt));
      } else if ((d->hold.stuck >> l) & 1u) {
        worst_stuck = std::fmax(worst_stuck, Ft - g.mu_static * N);
      }
    }
  }
  const double lost = E0 - robot_energy(R, *d);
  printf("slippery ground: feet that slid 0x%02x, %d sliding samples; |F_t| off mu_k N by %.1e of N, its "
         "direction off -v_t by %.1e; a stuck foot past its cone by %.1e N; energy lost %.6e J, friction's "
         "work %.6e J (off by %.1e)\n",
         slid, sliding_samples, worst_cone, worst_dir, worst_stuck, lost, -work, std::fabs(lost + work));
  TEST_ASSERT_TRUE(slid != 0 && sliding_samples > 100);
  TEST_ASSERT_TRUE(worst_cone < 1e-9);
  TEST_ASSERT_TRUE(worst_dir < 1e-9);
  TEST_ASSERT_TRUE(worst_stuck < 1e-6);
  TEST_ASSERT_TRUE(lost > 1e-3);
  TEST_ASSERT_TRUE(std::fabs(lost + work) < 1e-6 * lost);  // the trapezoid rule's error
}

void frictionless_ground_keeps_energy(Integrator integrator, double ratio_lo, double ratio_hi, double at_1ms) {
  // The stand on six feet on ice, sliding forward and turning as one body, under the stand's
  // statics forces less 20 N on every lower actuator: the knees give, the feet slide out.
  const Standing &s = standing();
  const SpatialRobot &R = s.robot;
  static RobotStatics st;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_statics(R, s.q, 0x3F, nullptr, st));
  const V3 foot0 = robot_foot_position(R, 0, s.q);
  const GroundPlane g = {{0, 0, foot0.z}, {0, 0, 1}, 0.0, 0.0};
  double dE[2], dp[2];
  int impacts = 0;
  for (int run = 0; run < 2; ++run) {
    const double h = run == 0 ? 2e-3 : 1e-3;
    static double q[kBodyConfig * kMaxRobotBodies], v[kMaxRobotDof];
    static const double zero[3 * LEGSIM_MAX_BODIES] = {};
    const double *qs[6], *vs[6];
    double psi[6], psid[6] = {0};
    for (int l = 0; l < 6; ++l) qs[l] = s.leg_q, vs[l] = zero, psi[l] = robot_rowing_angle(R, l, s.q);
    const double box_q[7] = {0, 0, 0, 1, 0, 0, 0}, box_v[6] = {0.3, 0.1, 0, 0, 0, 0.5};
    robot_state(R, box_q, box_v, qs, vs, psi, psid, q, v);
    FeetHold hold;
    hold.stuck = 0, hold.sliding = 0x3F;
    for (int l = 0; l < 6; ++l) hold.anchor[l] = robot_foot_position(R, l, q);
    auto d = std::make_unique<RobotData>();
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_init(R, q, v, hold, &g, *d));
    for (int a = 0; a < R.na; ++a) d->command.actuator[a] = st.actuator_force[a] - (a % 2 ? 20.0 : 0.0);
    for (int l = 0; l < R.nlegs; ++l) d->command.rowing[l] = st.rowing_torque[l];
    TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_data_refresh(R, *d));
    TEST_ASSERT_EQUAL_INT(0x3F, int(d->hold.sliding));  // no foot sticks on ice
    const double E0 = robot_energy(R, *d);
    V3 p0 = {0, 0, 0};
    for (int b = 0; b < R.nb; ++b) p0 = p0 + R.mass[b] * V3{d->v[kBodyDof * b], d->v[kBodyDof * b + 1], 0};
    double E_worst = 0, p_worst = 0;
    for (int n = 0; n < int(std::lround(0.2 / h)); ++n) {
      TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_step(R, *d, h, integrator));
      E_worst = std::fmax(E_worst, std::fabs(robot_energy(R, *d) - E0));
      V3 p = {0, 0, 0};
      for (int b = 0; b < R.nb; ++b) p = p + R.mass[b] * V3{d->v[kBodyDof * b], d->v[kBodyDof * b + 1], 0};
      p_worst = std::fmax(p_worst, norm(p - p0));
    }
    impacts += d->impacts;
    TEST_ASSERT_EQUAL_INT(0x3F, int(d->hold.sliding));  // on the ice throughout
    dE[run] = E_worst, dp[run] = p_worst;
    V3 p, pv;
    foot_motion(R, 0, d->q, d->v, p, pv);
    printf("%sice, h = %.0e s: %d impacts, energy off by at most %.2e J, horizontal momentum %.1e kg m/s, feet "
           "sliding 0x%02x, foot 0 at %.2f m/s, box down %.4f m\n",
           integrator == Integrator::Rk4 ? "" : "generalized-alpha: ", h, d->impacts, E_worst, p_worst,
           int(d->hold.sliding), norm(pv), s.q[2] - d->q[2]);
  }
  printf("ice: energy error ratio over a halved step %.1f\n", dE[0] / dE[1]);
  TEST_ASSERT_EQUAL_INT(0, impacts);
  TEST_ASSERT_TRUE(dp[0] < 1e-12 * 50 && dp[1] < 1e-12 * 50);  // of about 50 kg m/s
  TEST_ASSERT_TRUE(dE[1] < at_1ms);
  TEST_ASSERT_TRUE(dE[0] / dE[1] > ratio_lo && dE[0] / dE[1] < ratio_hi);
}
void test_frictionless_ground_keeps_energy(void) { frictionless_ground_keeps_energy(Integrator::Rk4, 12, 20, 1e-6); }
void test_frictionless_ground_keeps_energy_galpha(void) {
  frictionless_ground_keeps_energy(Integrator::GeneralizedAlpha, 3, 5, 1e-2);
}

int main(void) {
  UNITY_BEGIN();
  RUN_TEST(test_feet_slip_on_a_slippery_ground);
  RUN_TEST(test_frictionless_ground_keeps_energy);
  RUN_TEST(test_frictionless_ground_keeps_energy_galpha);
  return UNITY_END();
}
