// The paper's Section V on the hexapod of models/hexapod.toml: the robot standing on a tripod
// (right front, right rear, left middle), the box level with its centre 1 m above level ground
// (the stand's height), every leg at its stand but the right front ("leg 1"), whose foot is
// moved along its hip's heading on the ground: per foot distance from the hip axis, the ground
// reaction of each stance foot, leg 1's actuator forces and rowing torque (robot_statics), the
// closed form of the tripod's vertical reactions (the centre of mass in the support triangle)
// beside them, and the stability margin: legsim_hexapod_reaction_sweep (legsim/hexapod.h), the
// sweep users call, with the closed form computed here from its centre of mass and feet.
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
#include <vector>

#include "legsim/hexapod.h"
#include "model_toml.hpp"

namespace {
alignas(LEGSIM_STORAGE_ALIGN) unsigned char storage[1 << 20];
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
  if (sizeof storage < legsim_hexapod_storage_size()) return 2;
  const legsim_hexapod_sweep sweep = {0, 1u << 0 | 1u << 2 | 1u << 4, kHeight, {kLo, kHi}, points, {0, 0}, 1};
  const int first = (chunk - 1) * points / chunks, last = chunk * points / chunks;
  std::printf("index,foot_distance_m,status,leg1_fz_n,leg1_fx_n,leg1_fy_n,leg3_fz_n,leg5_fz_n,closed_form_leg1_fz_n,"
              "upper_force_n,lower_force_n,rowing_torque_nm,upper_length_m,lower_length_m,margin_m\n");
  if (last == first) return 0;
  std::vector<legsim_hexapod_sweep_point> out(last - first);
  const legsim_status st =
      legsim_hexapod_reaction_sweep(h.get(), &sweep, first, last - first, storage, sizeof storage, out.data());
  if (st != LEGSIM_OK) {
    std::fprintf(stderr, "legsim_hexapod_reaction_sweep: %s\n", legsim_status_str(st));
    return 2;
  }
  bool agree = true;
  for (const legsim_hexapod_sweep_point &p : out) {
    if (p.status != LEGSIM_OK) {
      std::printf("%d,%.6f,%s,,,,,,,,,,,,\n", p.index, p.distance_m, legsim_status_str(p.status));
      continue;
    }
    // the closed form: the weight shared by the centre of mass's barycentric coordinates in the
    // support triangle (on level ground a tripod's vertical forces need nothing else)
    const legsim_hexapod_standing &s = p.standing;
    const double(*f)[3] = s.foot_m;
    const double cx = s.com_m[0], cy = s.com_m[1];
    const double *a = f[kTripod[0]], *b = f[kTripod[1]], *c = f[kTripod[2]];
    const double det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
    const double wb = ((cx - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (cy - a[1])) / det;
    const double wc = ((b[0] - a[0]) * (cy - a[1]) - (cx - a[0]) * (b[1] - a[1])) / det;
    double M = h->box_mass_kg;
    for (int l = 0; l < LEGSIM_HEXAPOD_LEGS; ++l) {
      M += h->yoke_mass_kg;
      for (int b = 0; b < h->leg[l].leg.n_bodies; ++b) M += h->leg[l].leg.body[b].mass_kg;
    }
    const double W = -M * h->gravity_mps2[2];
    double carried = 0;
    for (int k = 0; k < 3; ++k) carried += s.foot_force_n[kTripod[k]][2];
    agree = agree && std::fabs(carried - W) <= 1e-9 * W;
    const double closed = (1 - wb - wc) * W;
    agree = agree && std::fabs(s.foot_force_n[0][2] - closed) <= 1e-9 * W &&
            std::fabs(s.foot_force_n[2][2] - wb * W) <= 1e-9 * W && std::fabs(s.foot_force_n[4][2] - wc * W) <= 1e-9 * W;
    std::printf("%d,%.6f,OK,%.6f,%.3e,%.3e,%.6f,%.6f,%.6f,%.6f,%.6f,%.9f,%.6f,%.6f,%.6f\n", p.index, p.distance_m,
                s.foot_force_n[0][2], s.foot_force_n[0][0], s.foot_force_n[0][1], s.foot_force_n[2][2],
                s.foot_force_n[4][2], closed, s.actuator_force_n[0][0], s.actuator_force_n[0][1], s.rowing_torque_nm[0],
                p.length_m[0], p.length_m[1], s.margin_m);
  }
  return agree ? 0 : 1;
}
