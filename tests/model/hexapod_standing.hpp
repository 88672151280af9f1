// A test fixture: the hexapod of models/hexapod.toml at its legs' stand, the box level at the
// origin, the legs turned by unequal rowing angles (the centre of mass off the middle, no two
// support triangles alike). Runs from the source tree's root.
#pragma once

#include "legsim/legsim.h"
#include "model_toml.hpp"
#include "spatial/motion.hpp"
#include "spatial/robot.hpp"
#include "unity.h"

struct Standing {
  legsim::spatial::SpatialRobot robot;
  double q[legsim::spatial::kBodyConfig * legsim::spatial::kMaxRobotBodies];
  double M;
  legsim::spatial::V3 com;
  legsim_hexapod_desc desc;
  double leg_q[3 * LEGSIM_MAX_BODIES];  // the leg's stand (planar)
};

inline Standing &standing() {
  using namespace legsim::spatial;
  static Standing s;
  static bool built = false;
  if (built) return s;
  alignas(16) static unsigned char storage[1 << 20];
  char msg[256];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_hexapod_load_toml("models/hexapod.toml", &s.desc, msg, sizeof msg));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, robot_lift_hexapod(s.desc, s.robot));
  legsim_options opt = legsim_default_options();
  legsim_sim *sim = nullptr;
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_init(storage, sizeof storage, &s.desc.leg[0].leg, &opt, &sim));
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_assemble_pose(sim, 0));
  static double zero[3 * LEGSIM_MAX_BODIES];
  TEST_ASSERT_EQUAL_INT(LEGSIM_OK, legsim_get_q(sim, s.leg_q));
  const double *qs[6], *vs[6];
  double psi[6] = {0.3, 0.1, -0.2, 0.0, 0.25, -0.15}, psid[6] = {0};
  for (int l = 0; l < 6; ++l) qs[l] = s.leg_q, vs[l] = zero;
  const double box_q[7] = {0, 0, 0, 1, 0, 0, 0}, box_v[6] = {0, 0, 0, 0, 0, 0};
  static double v[kBodyDof * kMaxRobotBodies];
  robot_state(s.robot, box_q, box_v, qs, vs, psi, psid, s.q, v);
  s.M = 0;
  double c[3] = {0, 0, 0};
  for (int b = 0; b < s.robot.nb; ++b) {
    s.M += s.robot.mass[b];
    for (int i = 0; i < 3; ++i) c[i] += s.robot.mass[b] * s.q[kBodyConfig * b + i];
  }
  s.com = {c[0] / s.M, c[1] / s.M, c[2] / s.M};
  built = true;
  return s;
}

// The robot's energy under constant commands: kinetic, gravity's, less the work the actuators and
// the motors would do back (-F l, -tau psi): what no OK step may raise beyond its error.
inline double robot_energy(const legsim::spatial::SpatialRobot &robot, const legsim::spatial::RobotData &d) {
  using namespace legsim::spatial;
  double E = robot_kinetic_energy(robot, d.v) + robot_gravity_potential(robot, d.q);
  for (int a = 0; a < robot.na; ++a) E -= d.actuator_force[a] * robot_actuator_length(robot, a, d.q);
  for (int l = 0; l < robot.nlegs; ++l) E -= d.rowing_torque[l] * robot_rowing_angle(robot, l, d.q);
  return E;
}
