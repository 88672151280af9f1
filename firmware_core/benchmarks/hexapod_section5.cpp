// The paper's Section V on the hexapod of models/hexapod.toml: the robot standing on a tripod
// (right front, right rear, left middle), the box level with its centre 1 m above level ground
// (the stand's height), every leg at its stand but the right front ("leg 1"), whose foot is
// moved along its hip's heading on the ground: per foot distance from the hip axis, the ground
// reaction of each stance foot, leg 1's actuator forces and rowing torque (robot_statics), the
// closed form of the tripod's vertical reactions (the centre of mass in the support triangle)
// beside them, and the stability margin. The other two stance feet stay where the stand puts
// them; leg 1's lengths come from its inverse kinematics (legsim_assemble_foot).
//
//   build/host/firmware_core/benchmarks/hexapod_section5 [POINTS] [CHUNK/CHUNKS] > part.csv
//
// run from the repository's root. The sweep's POINTS (default 23) distances from 0.40 to 0.62 m
// are cut in CHUNKS parts (default 1/1): each run writes the rows of its part (with their index),
// so that parts run anywhere concatenate into the whole (`sort -n`). A point the leg cannot reach
// or hold (out of stroke, no equilibrium) writes its status instead of numbers. Exit 0 when every
// point's vertical reactions agree with the closed form to 1e-9 of the weight.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "legsim/legsim.h"
#include "model_toml.hpp"
#include "spatial/gait.hpp"
#include "spatial/robot.hpp"
#include "spatial/statics.hpp"

using namespace legsim::spatial;

namespace {
alignas(16) unsigned char storage[1 << 20];
constexpr int kTripod[3] = {0, 2, 4};
constexpr double kLo = 0.40, kHi = 0.62, kHeight = 1.0;  // m
}  // namespace

int main(int argc, char **argv) {
  const int points = argc > 1 ? std::atoi(argv[1]) : 23;
  int chunk = 1, chunks = 1;
  if (argc > 2 && std::sscanf(argv[2], "%d/%d", &chunk, &chunks) != 2) chunks = 0;
  if (points < 2 || points > 100000 || chunks < 1 || chunk < 1 || chunk > chunks) {
    std::fprintf(stderr, "usage: hexapod_section5 [POINTS 2..100000] [CHUNK/CHUNKS]\n");
    return 2;
  }
  auto h = std::make_unique<legsim_hexapod_desc>();
  char msg[512];
  if (legsim_hexapod_load_toml("models/hexapod.toml", h.get(), msg, sizeof msg) != LEGSIM_OK) {
    std::fprintf(stderr, "%s\n", msg);
    return 2;
  }
  static SpatialRobot robot;
  if (robot_lift_hexapod(*h, robot) != LEGSIM_OK) return 2;
  // the planar leg: its stand, and a sim for leg 1's inverse kinematics
  legsim_options opt = legsim_default_options();
  legsim_sim *sim = nullptr;
  if (legsim_init(storage, sizeof storage, &h->leg[0].leg, &opt, &sim) != LEGSIM_OK ||
      legsim_assemble_pose(sim, 0) != LEGSIM_OK)
    return 2;
  static double q_stand[3 * LEGSIM_MAX_BODIES], q_leg1[3 * LEGSIM_MAX_BODIES], zero[3 * LEGSIM_MAX_BODIES];
  legsim_get_q(sim, q_stand);
  const double box_q[7] = {0, 0, kHeight, 1, 0, 0, 0}, box_v[6] = {0, 0, 0, 0, 0, 0};
  std::printf("index,foot_distance_m,status,leg1_fz_n,leg1_fx_n,leg1_fy_n,leg3_fz_n,leg5_fz_n,closed_form_leg1_fz_n,"
              "upper_force_n,lower_force_n,rowing_torque_nm,upper_length_m,lower_length_m,margin_m\n");
  bool agree = true;
  const int first = (chunk - 1) * points / chunks, last = chunk * points / chunks;
  for (int i = first; i < last; ++i) {
    const double rho = kLo + (kHi - kLo) * i / (points - 1);
    const RobotLeg &L = robot.leg[0];
    const V3 foot = {L.hip.x + rho * std::cos(L.yaw), L.hip.y + rho * std::sin(L.yaw), -kHeight};
    double psi0, xy[2];
    leg_plane_target(robot, 0, foot, psi0, xy);
    legsim_assemble_pose(sim, 0);  // from the stand's branch
    legsim_status st = legsim_assemble_foot(sim, xy);
    double len[2] = {NAN, NAN};
    if (st == LEGSIM_OK) {
      legsim_get_q(sim, q_leg1);
      legsim_actuator_lengths(sim, len, nullptr);
    }
    static double q[kBodyConfig * kMaxRobotBodies], v[kBodyDof * kMaxRobotBodies];
    static RobotStatics s;
    if (st == LEGSIM_OK) {
      const double *qs[6], *vs[6];
      double psi[6] = {psi0, 0, 0, 0, 0, 0}, psid[6] = {0};
      for (int l = 0; l < 6; ++l) qs[l] = l == 0 ? q_leg1 : q_stand, vs[l] = zero;
      robot_state(robot, box_q, box_v, qs, vs, psi, psid, q, v);
      st = robot_statics(robot, q, 1u << 0 | 1u << 2 | 1u << 4, nullptr, s);
    }
    if (st != LEGSIM_OK) {
      std::printf("%d,%.6f,%s,,,,,,,,,,,,\n", i, rho, legsim_status_str(st));
      continue;
    }
    // the closed form: the weight shared by the centre of mass's barycentric coordinates
    double M = 0, cx = 0, cy = 0;
    for (int b = 0; b < robot.nb; ++b) {
      M += robot.mass[b];
      cx += robot.mass[b] * q[kBodyConfig * b];
      cy += robot.mass[b] * q[kBodyConfig * b + 1];
    }
    cx /= M, cy /= M;
    V3 f[3];
    for (int k = 0; k < 3; ++k) f[k] = robot_foot_position(robot, kTripod[k], q);
    const double det = (f[1].x - f[0].x) * (f[2].y - f[0].y) - (f[2].x - f[0].x) * (f[1].y - f[0].y);
    const double wb = ((cx - f[0].x) * (f[2].y - f[0].y) - (f[2].x - f[0].x) * (cy - f[0].y)) / det;
    const double wc = ((f[1].x - f[0].x) * (cy - f[0].y) - (cx - f[0].x) * (f[1].y - f[0].y)) / det;
    const double W = -M * robot.gravity.z, closed = (1 - wb - wc) * W;
    agree = agree && std::fabs(s.foot_force[0].z - closed) <= 1e-9 * W &&
            std::fabs(s.foot_force[2].z - wb * W) <= 1e-9 * W && std::fabs(s.foot_force[4].z - wc * W) <= 1e-9 * W;
    std::printf("%d,%.6f,OK,%.6f,%.3e,%.3e,%.6f,%.6f,%.6f,%.6f,%.6f,%.9f,%.6f,%.6f,%.6f\n", i, rho, s.foot_force[0].z,
                s.foot_force[0].x, s.foot_force[0].y, s.foot_force[2].z, s.foot_force[4].z, closed, s.actuator_force[0],
                s.actuator_force[1], s.rowing_torque[0], len[0], len[1], support_margin(f, 3, cx, cy));
  }
  return agree ? 0 : 1;
}
