// CTest hil_sim_hexapod: the hexapod's node (hil_sim --hexapod) in memory against its C API:
// the tripod walk's set-points with the statics' feed-forward sent as frames step by step give
// the C API's own run of the same commands bit for bit (box and feet in float64, the legs'
// float32 values its float32 rounding), and so do slots of mixed modes against
// legsim_hexapod_command_each; bad frames (a mode past SERVO among them) are refused with one
// FAULT naming the signal and change nothing; each leg's command watchdog trips alone, its
// safe action the C API's command with that leg's feed-forward zero (and, a FORCE slot, its
// force zero); in the real run loop (an in-memory bus) a long STEP keeps the heartbeat and
// gives the same answer as in one go.
#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstring>
#include <vector>

#include <sys/signalfd.h>
#include <time.h>
#include <unistd.h>

#include "can_io.h"
#include "hexapod_node.h"
#include "run_loop.h"
#include "model_toml.hpp"
#include "test_support.hpp"

extern "C" {
#include "legsim_can.h"
#include "legsim_can_layout.h"
}

using hil::Frame;
using hil_test::Recorder;

namespace {

constexpr int L = LEGSIM_HEXAPOD_LEGS;
const legsim_hexapod_gait kGait = {1.2, 0.6, 0.12, 0.05, 0.0, 1.0};  // tests/python/test_hexapod.py's

legsim_hexapod_desc g_desc;
std::vector<unsigned char> g_work;  // gait and statics storage
void *work() {
  const size_t a = LEGSIM_STORAGE_ALIGN;
  if (g_work.empty()) g_work.resize(legsim_hexapod_storage_size() + a);
  uintptr_t p = reinterpret_cast<uintptr_t>(g_work.data());
  return reinterpret_cast<void *>((p + a - 1) / a * a);
}

// The walk's command at t: the gait's set-points, the statics of the planned pose on its
// planned stance as feed-forward (Hexapod.walk's command()).
struct WalkCmd {
  legsim_hexapod_setpoint sp;
  double ff[L][2], fm[L];
  uint32_t stance;
};
WalkCmd walk_command(double t) {
  WalkCmd c;
  CHECK(legsim_hexapod_gait_setpoints(&g_desc, &kGait, t, work(), legsim_hexapod_storage_size(), &c.sp) ==
        LEGSIM_OK);
  legsim_hexapod_pose at = {};
  at.box_m[2] = kGait.box_height_m;
  at.box_quat[0] = 1;
  c.stance = 0;
  for (int l = 0; l < L; ++l) {
    at.rowing_rad[l] = c.sp.rowing_rad[l];
    at.length_m[l][0] = c.sp.length_m[l][0], at.length_m[l][1] = c.sp.length_m[l][1];
    if (c.sp.stance[l]) c.stance |= 1u << l;
  }
  legsim_hexapod_standing s;
  CHECK(legsim_hexapod_statics(&g_desc, &at, c.stance, nullptr, work(), legsim_hexapod_storage_size(), &s) ==
        LEGSIM_OK);
  for (int l = 0; l < L; ++l) c.ff[l][0] = s.actuator_force_n[l][0], c.ff[l][1] = s.actuator_force_n[l][1];
  for (int l = 0; l < L; ++l) c.fm[l] = s.rowing_torque_nm[l];
  return c;
}

Frame hex_cmd(int leg, uint32_t seq, const uint8_t mode[3], const double set[3], const double ff[3]) {
  legsim_can_hex_cmd_h0_t m;
  legsim_can_hex_cmd_h0_init(&m);
  m.hc_seq = seq;
  m.hc_mode_upper = mode[0], m.hc_mode_lower = mode[1], m.hc_mode_rowing = mode[2];
  m.hc_setpoint_upper = set[0], m.hc_setpoint_lower = set[1], m.hc_setpoint_rowing = set[2];
  m.hc_ff_upper = ff[0], m.hc_ff_lower = ff[1], m.hc_ff_rowing = ff[2];
  // every leg's frame has leg 0's layout (the DBC's template): leg 0's pack at leg j's id
  Frame f = hil_test::fd_frame(hil::kHexCmdFrameId[leg]);
  legsim_can_hex_cmd_h0_pack(f.data, &m, 64);
  return f;
}
std::vector<Frame> servo_frames(const WalkCmd &c, uint32_t seq) {
  std::vector<Frame> out;
  const uint8_t servo[3] = {2, 2, 2};
  for (int l = 0; l < L; ++l) {
    const double set[3] = {c.sp.length_m[l][0], c.sp.length_m[l][1], c.sp.rowing_rad[l]};
    const double ff[3] = {c.ff[l][0], c.ff[l][1], c.fm[l]};
    out.push_back(hex_cmd(l, seq, servo, set, ff));
  }
  return out;
}

Frame reset(uint32_t seq, bool servo, bool use_held, uint32_t stance, float height, uint16_t timeout = 65535) {
  legsim_can_control_t m = hil_test::control(seq, LEGSIM_CAN_CONTROL_CTRL_COMMAND_RESET_CHOICE);
  m.ctrl_act_init = servo ? 1 : 0;
  m.ctrl_use_lengths = use_held ? 1 : 0;
  m.ctrl_hex_stance = static_cast<uint8_t>(stance);
  m.ctrl_hex_box_height = height;
  m.ctrl_cmd_timeout = timeout;
  return hil_test::pack(m);
}

// The C API's run: its own storage, stepped as the walk steps it.
struct Reference {
  std::vector<unsigned char> buf;
  legsim_hexapod_sim *sim = nullptr;
  legsim_status init(const WalkCmd &c, float height) {
    const size_t a = LEGSIM_STORAGE_ALIGN;
    buf.assign(legsim_hexapod_sim_size() + a, 0);
    uintptr_t p = reinterpret_cast<uintptr_t>(buf.data());
    legsim_hexapod_pose pose = {};
    pose.box_m[2] = height;
    pose.box_quat[0] = 1;
    for (int l = 0; l < L; ++l) {
      pose.rowing_rad[l] = c.sp.rowing_rad[l];
      pose.length_m[l][0] = c.sp.length_m[l][0], pose.length_m[l][1] = c.sp.length_m[l][1];
    }
    legsim_status st = legsim_hexapod_sim_init(reinterpret_cast<void *>((p + a - 1) / a * a),
                                               legsim_hexapod_sim_size(), &g_desc, &pose, c.stance, &sim);
    return st == LEGSIM_OK ? command(c) : st;
  }
  legsim_status command(const WalkCmd &c) {
    double len[L][2], row[L];
    for (int l = 0; l < L; ++l)
      len[l][0] = c.sp.length_m[l][0], len[l][1] = c.sp.length_m[l][1], row[l] = c.sp.rowing_rad[l];
    return legsim_hexapod_command_pose(sim, len, row, c.ff, c.fm);
  }
  legsim_hexapod_state state() const {
    legsim_hexapod_state s;
    legsim_hexapod_get_state(sim, &s);
    return s;
  }
};


// A sample's frames decoded, and compared with the C API's state.
struct Decoded {
  int frames = 0;
  legsim_can_hex_box_pose_t box;
  legsim_can_hex_box_vel_t vel;
  legsim_can_hex_leg_h0_t leg[L];
  legsim_can_hex_foot_h0_t foot[L];
  legsim_can_st_status_t status;
};
Decoded decode(const std::vector<Frame> &v) {
  Decoded d;
  std::memset(&d, 0, sizeof d);
  for (const Frame &f : v) {
    ++d.frames;
    if (f.id == LEGSIM_CAN_HEX_BOX_POSE_FRAME_ID) legsim_can_hex_box_pose_unpack(&d.box, f.data, 64);
    if (f.id == LEGSIM_CAN_HEX_BOX_VEL_FRAME_ID) legsim_can_hex_box_vel_unpack(&d.vel, f.data, 64);
    if (f.id == LEGSIM_CAN_ST_STATUS_FRAME_ID) legsim_can_st_status_unpack(&d.status, f.data, 64);
    for (int l = 0; l < L; ++l) {
      if (f.id == LEGSIM_CAN_HEX_LEG_H0_FRAME_ID + static_cast<uint32_t>(l))
        legsim_can_hex_leg_h0_unpack(&d.leg[l], f.data, 64);
      if (f.id == LEGSIM_CAN_HEX_FOOT_H0_FRAME_ID + static_cast<uint32_t>(l))
        legsim_can_hex_foot_h0_unpack(&d.foot[l], f.data, 64);
    }
  }
  return d;
}
bool same(const Decoded &d, const legsim_hexapod_state &s) {
  bool ok = d.box.hb_x == s.box_m[0] && d.box.hb_y == s.box_m[1] && d.box.hb_z == s.box_m[2] &&
            d.box.hb_qw == s.box_quat[0] && d.box.hb_qx == s.box_quat[1] && d.box.hb_qy == s.box_quat[2] &&
            d.box.hb_qz == s.box_quat[3] && d.vel.hv_vx == s.box_velocity_mps[0] &&
            d.vel.hv_vy == s.box_velocity_mps[1] && d.vel.hv_vz == s.box_velocity_mps[2] &&
            d.vel.hv_wx == s.box_omega_radps[0] && d.vel.hv_wy == s.box_omega_radps[1] &&
            d.vel.hv_wz == s.box_omega_radps[2] && d.vel.hv_energy == s.kinetic_energy_j &&
            d.status.st_time == s.t_s;
  for (int l = 0; l < L; ++l) {
    ok = ok && d.foot[l].hf_x == s.foot_m[l][0] && d.foot[l].hf_y == s.foot_m[l][1] &&
         d.foot[l].hf_z == s.foot_m[l][2] && d.foot[l].hf_fx == s.foot_force_n[l][0] &&
         d.foot[l].hf_fy == s.foot_force_n[l][1] && d.foot[l].hf_fz == s.foot_force_n[l][2];
    ok = ok && d.leg[l].hl_length_upper == static_cast<float>(s.length_m[l][0]) &&
         d.leg[l].hl_length_lower == static_cast<float>(s.length_m[l][1]) &&
         d.leg[l].hl_force_upper == static_cast<float>(s.actuator_force_n[l][0]) &&
         d.leg[l].hl_force_lower == static_cast<float>(s.actuator_force_n[l][1]) &&
         d.leg[l].hl_rowing == static_cast<float>(s.rowing_rad[l]) &&
         d.leg[l].hl_rowing_torque == static_cast<float>(s.rowing_torque_nm[l]) &&
         d.leg[l].hl_foot_state == s.foot_state[l];
  }
  return ok;
}

void send(hil::HexapodNode &node, const std::vector<Frame> &v) {
  for (const Frame &f : v) node.on_frame(f, 0);
}

// A servoed walk's start: its pose at t = 0 held for a RESET whose watchdogs time out after
// timeout_ms, the reference sim at the same start, the RESET's frames taken.
void start_walk(hil::HexapodNode &node, Recorder &rec, const WalkCmd &c, float height, uint16_t timeout_ms,
                Reference &ref) {
  send(node, servo_frames(c, 1));
  node.on_frame(reset(1, true, true, c.stance, height, timeout_ms), 0);
  CHECK(ref.init(c, height) == LEGSIM_OK);
  rec.take();
}

// A STEP worked to its end, as the run loop does in slices.
void step(hil::HexapodNode &node, uint32_t seq, uint32_t n) {
  node.on_frame(hil_test::step(seq, n), 0);
  node.finish_step();
}

// The walk over the bus equals the C API's walk; bad frames change nothing.
void test_walk() {
  Recorder rec;
  hil::HexConfig cfg;
  hil::HexapodNode node(g_desc, rec, cfg);
  std::string err;
  CHECK(node.init(&err));
  const float height = static_cast<float>(kGait.box_height_m);
  WalkCmd c = walk_command(0.0);
  send(node, servo_frames(c, 1));  // held for the RESET: the walk's pose at t = 0
  CHECK(rec.take().empty());
  node.on_frame(reset(1, true, true, c.stance, height), 0);
  Reference ref;
  CHECK(ref.init(c, height) == LEGSIM_OK);
  std::vector<Frame> out = rec.take();
  CHECK(static_cast<int>(out.size()) == hil::kHexSampleFrames);
  CHECK(!out.empty() && out.back().id == LEGSIM_CAN_ST_STATUS_FRAME_ID);
  CHECK(same(decode(out), ref.state()));
  const int n = 300;  // a quarter period: the first tripod swings, its feet leave the ground
  int equal = 0, free_feet = 0;
  uint32_t ctrl = 2;
  for (int i = 0; i < n; ++i) {
    c = walk_command((i + 1) * 1e-3);
    send(node, servo_frames(c, static_cast<uint32_t>(i + 2)));
    step(node, ctrl++, 1);
    CHECK(ref.command(c) == LEGSIM_OK);
    CHECK(legsim_hexapod_step(ref.sim, 1e-3, 1) == LEGSIM_OK);
    const Decoded d = decode(rec.take());
    if (d.frames == hil::kHexSampleFrames && same(d, ref.state())) ++equal;
    for (int l = 0; l < L; ++l) free_feet += d.leg[l].hl_foot_state == LEGSIM_CONTACT_FREE;
    if (i == 100) {
      // bad frames: one FAULT each naming the signal, no sample, nothing applied
      uint8_t servo[3] = {2, 2, 2};
      double set[3] = {c.sp.length_m[0][0], c.sp.length_m[0][1], c.sp.rowing_rad[0]};
      double ff[3] = {0, 0, 0};
      const uint32_t seq = 10000;
      struct Bad {
        Frame f;
        uint8_t code;
        uint32_t detail;
      };
      std::vector<Bad> bad;
      double nan_set[3] = {set[0], NAN, set[2]};
      bad.push_back({hex_cmd(0, seq, servo, nan_set, ff), 3, LEGSIM_CAN_HEX_CMD_H0_HC_SETPOINT_LOWER_START_BIT});
      double nan_ff[3] = {0, 0, NAN};
      bad.push_back({hex_cmd(1, seq, servo, set, nan_ff), 3, LEGSIM_CAN_HEX_CMD_H0_HC_FF_ROWING_START_BIT});
      double past[3] = {g_desc.leg[2].leg.actuator[0].stroke_max_m + 1e-9, set[1], set[2]};
      bad.push_back({hex_cmd(2, seq, servo, past, ff), 4, LEGSIM_CAN_HEX_CMD_H0_HC_SETPOINT_UPPER_START_BIT});
      double row_past[3] = {set[0], set[1], g_desc.rowing_stroke_rad[1] + 1e-9};
      bad.push_back({hex_cmd(3, seq, servo, row_past, ff), 4, LEGSIM_CAN_HEX_CMD_H0_HC_SETPOINT_ROWING_START_BIT});
      // modes past SERVO (the DBC's [0|2]), whatever the other slots
      uint8_t wrong[3] = {3, 2, 2};
      bad.push_back({hex_cmd(5, seq, wrong, set, ff), 4, LEGSIM_CAN_HEX_CMD_H0_HC_MODE_UPPER_START_BIT});
      uint8_t wrong_lower[3] = {1, 255, 0};
      const double push[3] = {10, 0, 0};
      bad.push_back({hex_cmd(4, seq, wrong_lower, push, ff), 4, LEGSIM_CAN_HEX_CMD_H0_HC_MODE_LOWER_START_BIT});
      uint8_t wrong_rowing[3] = {0, 0, 4};
      bad.push_back({hex_cmd(3, seq, wrong_rowing, set, ff), 4, LEGSIM_CAN_HEX_CMD_H0_HC_MODE_ROWING_START_BIT});
      // a FORCE slot past its actuator's max_force in a leg of mixed slots
      uint8_t mixed[3] = {2, 1, 2};
      double too_much[3] = {set[0], -1.0001 * g_desc.leg[4].leg.actuator[1].max_force_n, set[2]};
      bad.push_back({hex_cmd(4, seq, mixed, too_much, ff), 4, LEGSIM_CAN_HEX_CMD_H0_HC_SETPOINT_LOWER_START_BIT});
      double big_ff[3] = {g_desc.leg[0].leg.actuator[0].max_force_n * 1.01, 0, 0};
      bad.push_back({hex_cmd(0, seq, servo, set, big_ff), 4, LEGSIM_CAN_HEX_CMD_H0_HC_FF_UPPER_START_BIT});
      Frame short_frame = hex_cmd(1, seq, servo, set, ff);
      short_frame.len = 48;
      bad.push_back({short_frame, 2, 64});
      bad.push_back({hex_cmd(2, 5, servo, set, ff), 5, static_cast<uint32_t>(i + 2)});  // stale counter
      bad.push_back({hil_test::step(1, 1), 5, static_cast<uint32_t>(i + 2)});  // a stale STEP
      Frame act = hil_test::fd_frame(LEGSIM_CAN_ACT_CMD_FRAME_ID);  // the one leg's: not the hexapod's
      bad.push_back({act, 1, 0});
      legsim_can_control_t r = hil_test::control(1, LEGSIM_CAN_CONTROL_CTRL_COMMAND_RESET_CHOICE);
      r.ctrl_hex_box_height = NAN;
      bad.push_back({hil_test::pack(r), 3, LEGSIM_CAN_CONTROL_CTRL_HEX_BOX_HEIGHT_START_BIT});
      for (const Bad &b : bad) {
        node.on_frame(b.f, 0);
        const std::vector<Frame> got = rec.take();
        const legsim_can_fault_t f = hil_test::fault_of(got);
        CHECK(got.size() == 1 && f.fault_code == b.code && f.fault_detail == b.detail &&
              f.fault_frame_id == b.f.id);
        if (!(f.fault_code == b.code && f.fault_detail == b.detail))
          std::fprintf(stderr, "  bad frame 0x%x: fault %u detail %u, expected %u %u\n", b.f.id, f.fault_code,
                       f.fault_detail, b.code, b.detail);
      }
    }
  }
  std::printf("walk over frames: %d of %d samples equal to the C API's, %d free-foot samples\n", equal, n,
              free_feet);
  CHECK(equal == n);
  CHECK(free_feet > 0);  // the swing legs' feet left the ground
}

// Each leg's watchdog: leg 2 silent trips alone (its feed-forward zero, set-points held), the
// others fed on; a FORCE robot's safe action is zero force.
void test_watchdog() {
  Recorder rec;
  hil::HexConfig cfg;
  hil::HexapodNode node(g_desc, rec, cfg);
  std::string err;
  CHECK(node.init(&err));
  const float height = 1.0f;
  WalkCmd c = walk_command(0.0);
  Reference ref;
  start_walk(node, rec, c, height, 10, ref);  // 10 ms: 10 steps
  uint32_t ctrl = 2;
  int faults = 0;
  for (int i = 0; i < 30; ++i) {
    std::vector<Frame> f = servo_frames(c, static_cast<uint32_t>(i + 2));
    if (i > 0) f.erase(f.begin() + 2);  // leg 2 stops after the first
    send(node, f);
    step(node, ctrl++, 1);
    WalkCmd given = c;  // leg 2's 10 steps are up before step 10: its feed-forward zero
    if (i >= 10) given.ff[2][0] = given.ff[2][1] = given.fm[2] = 0;
    CHECK(ref.command(given) == LEGSIM_OK);
    CHECK(legsim_hexapod_step(ref.sim, 1e-3, 1) == LEGSIM_OK);
    const std::vector<Frame> got = rec.take();
    const legsim_can_fault_t fault = hil_test::fault_of(got);
    if (fault.fault_code == 7) {
      ++faults;
      CHECK(i == 10 && fault.fault_frame_id == hil::kHexCmdFrameId[2] && fault.fault_detail == 10 &&
            fault.fault_seq == 2);
    }
    const Decoded d = decode(got);
    CHECK(same(d, ref.state()));
    if (i >= 10) {
      CHECK((d.leg[2].hl_status & hil::kStatusSafeState) != 0);
      CHECK((d.leg[1].hl_status & hil::kStatusSafeState) == 0 && (d.leg[1].hl_status & hil::kStatusCmdWatchdog));
      CHECK((d.status.st_status & hil::kStatusSafeState) != 0);
    }
  }
  CHECK(faults == 1);
  // a FORCE robot at the stand: the silent legs' forces go to zero
  const uint8_t force[3] = {1, 1, 1};
  node.on_frame(reset(1, false, false, 0x3F, 1.0f, 5), 0);
  Decoded d = decode(rec.take());
  for (int l = 0; l < L; ++l) {
    CHECK(d.leg[l].hl_mode_upper == 1 && d.leg[l].hl_mode_lower == 1 && d.leg[l].hl_mode_rowing == 1);
    CHECK(d.leg[l].hl_length_upper == static_cast<float>(node.stand_length(l, 0)));
  }
  const double push[3] = {100, -50, 2};
  const double zero[3] = {0, 0, 0};
  node.on_frame(hex_cmd(0, 1, force, push, zero), 0);
  step(node, 2, 4);
  d = decode(rec.take());
  CHECK(d.leg[0].hl_force_upper == 100.0f && d.leg[0].hl_force_lower == -50.0f && d.leg[0].hl_rowing_torque == 2.0f);
  step(node, 3, 2);  // 5 ms after the command: tripped before the 6th step
  const std::vector<Frame> got = rec.take();
  CHECK(hil_test::fault_of(got).fault_code == 7 && hil_test::fault_of(got).fault_frame_id == hil::kHexCmdFrameId[0]);
  d = decode(got);
  CHECK(d.leg[0].hl_force_upper == 0.0f && d.leg[0].hl_rowing_torque == 0.0f);
}


// A frame per leg from the C API's per-slot command (its KEEP slots KEEP on the bus too).
std::vector<Frame> each_frames(const legsim_hexapod_commands &cmd, uint32_t seq, int skip_leg = -1) {
  std::vector<Frame> out;
  for (int l = 0; l < L; ++l) {
    if (l == skip_leg) continue;
    const uint8_t mode[3] = {static_cast<uint8_t>(cmd.mode[l][0]), static_cast<uint8_t>(cmd.mode[l][1]),
                             static_cast<uint8_t>(cmd.mode[l][2])};
    out.push_back(hex_cmd(l, seq, mode, cmd.value[l], cmd.feedforward[l]));
  }
  return out;
}

// A leg controller's mix on the walk: some slots pushed by the force (or torque) the statics
// give them, the others servoed, a slot switched from servo to force and one back, a slot
// KEEP; the frames give the C API's legsim_hexapod_command_each of the same slots bit for bit,
// each slot's mode in its HEX_LEG_Hj. A mode past SERVO is refused and changes nothing. Then a
// mixed leg falls silent: slot by slot its forces go to zero and its servos hold their
// set-points without feed-forward (the C API's command_each of that leg alone).
void test_mixed() {
  Recorder rec;
  hil::HexapodNode node(g_desc, rec, hil::HexConfig{});
  std::string err;
  CHECK(node.init(&err));
  const float height = static_cast<float>(kGait.box_height_m);
  WalkCmd c = walk_command(0.0);
  Reference ref;
  start_walk(node, rec, c, height, 20, ref);  // 20 ms: 20 steps
  constexpr int32_t K = LEGSIM_HEXAPOD_KEEP, F = LEGSIM_HEXAPOD_FORCE, S = LEGSIM_HEXAPOD_SERVO;
  const int n = 140, silent_leg = 3, silent_from = 100, timeout_steps = 20;
  int equal = 0, modes_seen = 0, trips = 0, trip_step = -1, forced_equal = 0;
  legsim_hexapod_commands last3 = {};  // leg 3's last command, for its safe action
  uint32_t ctrl = 2;
  for (int i = 0; i < n; ++i) {
    c = walk_command((i + 1) * 1e-3);
    const int32_t modes[L][3] = {{S, F, S},
                                 {S, S, i < 60 ? F : S},
                                 {S, S, S},
                                 {F, F, S},
                                 {i < 30 ? S : F, S, S},
                                 {S, S, i == 0 ? S : K}};
    legsim_hexapod_commands cmd = {};
    for (int l = 0; l < L; ++l)
      for (int k = 0; k < 3; ++k) {
        const double set = k < 2 ? c.sp.length_m[l][k] : c.sp.rowing_rad[l];
        const double load = k < 2 ? c.ff[l][k] : c.fm[l];
        cmd.mode[l][k] = modes[l][k];
        cmd.value[l][k] = modes[l][k] == F ? load : modes[l][k] == S ? set : 0.0;
        cmd.feedforward[l][k] = modes[l][k] == S ? load : 0.0;
      }
    const bool silent = i >= silent_from;
    send(node, each_frames(cmd, static_cast<uint32_t>(i + 2), silent ? silent_leg : -1));
    if (i == 50) {  // a mode past SERVO among good slots: refused, nothing applied
      const uint8_t bad[3] = {1, 3, 2};
      const double set[3] = {c.ff[0][0], c.sp.length_m[0][1], c.sp.rowing_rad[0]};
      const double ff[3] = {0, 0, 0};
      node.on_frame(hex_cmd(0, 100000, bad, set, ff), 0);
      const legsim_can_fault_t f = hil_test::fault_of(rec.take());
      CHECK(f.fault_code == 4 && f.fault_detail == LEGSIM_CAN_HEX_CMD_H0_HC_MODE_LOWER_START_BIT &&
            f.fault_frame_id == hil::kHexCmdFrameId[0] && f.fault_value == 3.0f);
    }
    if (silent)
      for (int k = 0; k < 3; ++k) cmd.mode[silent_leg][k] = K;
    else
      last3 = cmd;
    if (i == silent_from - 1 + timeout_steps)  // the silent leg's safe action, with this step's commands
      for (int k = 0; k < 3; ++k) {
        cmd.mode[silent_leg][k] = last3.mode[silent_leg][k];
        cmd.value[silent_leg][k] = last3.mode[silent_leg][k] == F ? 0.0 : last3.value[silent_leg][k];
        cmd.feedforward[silent_leg][k] = 0.0;
      }
    CHECK(legsim_hexapod_command_each(ref.sim, &cmd) == LEGSIM_OK);
    step(node, ctrl++, 1);
    CHECK(legsim_hexapod_step(ref.sim, 1e-3, 1) == LEGSIM_OK);
    const std::vector<Frame> got = rec.take();
    const legsim_can_fault_t fault = hil_test::fault_of(got);
    if (fault.fault_code == 7) {
      ++trips;
      trip_step = i;
      CHECK(fault.fault_frame_id == hil::kHexCmdFrameId[silent_leg]);
    }
    const Decoded d = decode(got);
    const legsim_hexapod_state x = ref.state();
    if (d.frames == hil::kHexSampleFrames + (fault.fault_code != 0) && same(d, x))
      ++equal;
    else
      std::fprintf(stderr, "  mixed: sample after step %d differs from command_each's\n", i);
    // each slot's mode as last given (leg 5's KEEP rowing still SERVO)
    bool modes_ok = true;
    for (int l = 0; l < L; ++l) {
      const uint8_t m[3] = {d.leg[l].hl_mode_upper, d.leg[l].hl_mode_lower, d.leg[l].hl_mode_rowing};
      for (int k = 0; k < 3; ++k) modes_ok = modes_ok && m[k] == (modes[l][k] == K ? S : modes[l][k]);
    }
    modes_seen += modes_ok;
    // a FORCE slot's force is its command's: the statics' load, float32 (zero once tripped)
    const double want = i >= silent_from - 1 + timeout_steps ? 0.0 : last3.value[silent_leg][1];
    forced_equal += d.leg[silent_leg].hl_force_lower == static_cast<float>(want) &&
                    x.actuator_force_n[silent_leg][1] == want;
  }
  std::printf("mixed slots over frames: %d of %d samples equal to command_each's, modes in %d, leg %d's forced "
              "lower actuator as commanded in %d; leg %d tripped at step %d\n",
              equal, n, modes_seen, silent_leg, forced_equal, silent_leg, trip_step);
  CHECK(equal == n && modes_seen == n && forced_equal == n);
  CHECK(trips == 1 && trip_step == silent_from - 1 + timeout_steps);
}

// Real time: a leg silent for more than the timeout of wall time trips alone, at the first tick
// past it; a sample every decimation ticks; STOP_RT answers with one and goes back to lockstep.
void test_realtime_watchdog() {
  Recorder rec;
  hil::HexConfig cfg;  // decimation 10
  hil::HexapodNode node(g_desc, rec, cfg);
  std::string err;
  CHECK(node.init(&err));
  const WalkCmd c = walk_command(0.0);
  send(node, servo_frames(c, 1));
  node.on_frame(reset(1, true, true, c.stance, 1.0f, 10), 0);
  send(node, servo_frames(c, 2));  // at 0 ms: every leg's watchdog armed (the RESET's held ones are not)
  legsim_can_control_t go = hil_test::control(2, LEGSIM_CAN_CONTROL_CTRL_COMMAND_START_RT_CHOICE);
  node.on_frame(hil_test::pack(go), 0);
  CHECK(node.state() == hil::SimState::kRealtime && node.rt_period_ns() == 1000000);
  rec.take();
  const int64_t ms = 1000000;
  int trip_tick = -1, samples = 0;
  for (int k = 1; k <= 30; ++k) {
    const int64_t now = k * ms;
    for (int l = 0; l < L; ++l)
      if (l != 5) node.on_frame(servo_frames(c, static_cast<uint32_t>(k + 2))[l], now);  // leg 5 silent
    node.rt_tick(now);
    const std::vector<Frame> got = rec.take();
    const legsim_can_fault_t f = hil_test::fault_of(got);
    if (f.fault_code == 7) {
      CHECK(trip_tick < 0 && f.fault_frame_id == hil::kHexCmdFrameId[5]);
      trip_tick = k;
    }
    if (hil_test::find(got, LEGSIM_CAN_ST_STATUS_FRAME_ID)) ++samples;
  }
  std::printf("real time: leg 5 tripped at tick %d (timeout 10 ms, its command at 0 ms), %d samples in 30 ticks\n",
              trip_tick, samples);
  CHECK(trip_tick == 11);  // 11 ms > 10 ms since its command
  CHECK(samples == 3);
  legsim_can_control_t stop = hil_test::control(3, LEGSIM_CAN_CONTROL_CTRL_COMMAND_STOP_RT_CHOICE);
  node.on_frame(hil_test::pack(stop), 31 * ms);
  const Decoded d = decode(rec.take());
  CHECK(d.frames == hil::kHexSampleFrames && d.status.st_state == 1 && node.step_count() == 30);
  CHECK((d.leg[5].hl_status & hil::kStatusSafeState) && !(d.leg[4].hl_status & hil::kStatusSafeState));
}

// A STEP of about 0.5 s of CPU in the real loop: heartbeats all along (state LOCKSTEP, bit
// STEPPING, the simulated time moving on), gaps within the period plus the leg's liveness
// slack (200 ms, less the time spent waiting for a CPU), and the answer bit-identical to the
// same STEP worked in one go; SIGTERM after it puts every leg in its safe action.
void test_liveness() {
  const float height = 1.0f;
  const WalkCmd c = walk_command(0.0);
  std::vector<Frame> in = servo_frames(c, 1);
  in.push_back(reset(1, true, true, c.stance, height));
  // the step's cost here, to size the STEP in CPU time
  Recorder rec;
  hil::HexapodNode ref(g_desc, rec, hil::HexConfig{});
  std::string err;
  CHECK(ref.init(&err));
  send(ref, in);
  struct timespec a, b;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &a);
  step(ref, 2, 50);
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &b);
  const double per_step = ((b.tv_sec - a.tv_sec) + (b.tv_nsec - a.tv_nsec) / 1e9) / 50;
  const uint32_t n = static_cast<uint32_t>(std::clamp(0.5 / per_step, 200.0, 100000.0));
  rec.take();
  step(ref, 3, n);
  const std::vector<Frame> expected = rec.take();

  hil_test::MemoryBus bus;
  hil::HexapodNode node(g_desc, bus, hil::HexConfig{});
  CHECK(node.init(&err));
  for (const Frame &f : in) bus.push(f);
  bus.push(hil_test::step(2, 50));
  bus.push(hil_test::step(3, n));
  int samples = 0;  // the RESET's, the STEP 50's, the long STEP's: then SIGTERM
  bus.on_send = [&samples](const hil_test::Sent &s) {
    if (s.frame.id == LEGSIM_CAN_ST_STATUS_FRAME_ID && ++samples == 3) ::kill(::getpid(), SIGTERM);
  };
  sigset_t mask;
  sigemptyset(&mask);
  sigaddset(&mask, SIGTERM);
  sigprocmask(SIG_BLOCK, &mask, nullptr);
  const int sfd = signalfd(-1, &mask, SFD_NONBLOCK | SFD_CLOEXEC);
  hil::LoopConfig cfg;
  cfg.heartbeat_ms = 100;
  hil::JitterStats stats;
  const int64_t t0 = hil_test::mono_ns();
  const hil::LoopResult res = hil::run_loop(bus, node, sfd, cfg, &stats);
  const double secs = (hil_test::mono_ns() - t0) / 1e9;
  ::close(sfd);
  CHECK(res.signal == SIGTERM && res.shutdown.safe_applied && !res.shutdown.step_cut);
  // the long STEP's window: from the STEP 50's answer to the long STEP's
  std::vector<hil_test::Sent> w;
  std::vector<Frame> answer;
  int statuses = 0, stepping = 0;
  for (const auto &s : bus.sent) {
    if (s.frame.id == LEGSIM_CAN_ST_STATUS_FRAME_ID) ++statuses;
    if (statuses == 2 && s.frame.id == LEGSIM_CAN_ST_STATUS_FRAME_ID) w.push_back(s);
    if (statuses == 2 && s.frame.id == LEGSIM_CAN_HEARTBEAT_FRAME_ID) {
      w.push_back(s);
      legsim_can_heartbeat_t h;
      legsim_can_heartbeat_unpack(&h, s.frame.data, 64);
      stepping += h.hb_state == 1 && (h.hb_status & hil::kStatusStepping) && h.hb_sim_time > 0.05;
    }
    // the long STEP's answer: what hil_sim sent after the STEP 50's, heartbeats aside
    if (statuses == 2 && s.frame.id != LEGSIM_CAN_HEARTBEAT_FRAME_ID && s.frame.id != LEGSIM_CAN_ST_STATUS_FRAME_ID)
      answer.push_back(s.frame);
    if (statuses == 3 && s.frame.id == LEGSIM_CAN_ST_STATUS_FRAME_ID) answer.push_back(s.frame);
    if (statuses == 3 && s.frame.id == LEGSIM_CAN_ST_STATUS_FRAME_ID) w.push_back(s);
  }
  const hil_test::Gaps g = hil_test::gaps(w);
  const double step_s = (w.size() >= 2 ? (w.back().t_ns - w.front().t_ns) / 1e9 : 0);
  char what[96];
  std::snprintf(what, sizeof what, "hexapod STEP %u (%.1f us a step) in the loop", n, per_step * 1e6);
  hil_test::print_gaps(what, g, step_s);
  std::printf("  %d heartbeats STEPPING; loop %.2f s\n", stepping, secs);
  CHECK(stepping >= 3);
  CHECK(g.own_ms <= 100 + 200);
  bool same_answer = answer.size() == expected.size();
  for (size_t i = 0; same_answer && i < answer.size(); ++i)
    same_answer = answer[i].id == expected[i].id && std::memcmp(answer[i].data, expected[i].data, 64) == 0;
  CHECK(same_answer);
}
}  // namespace

int main() {
  char msg[512] = "";
  if (legsim_hexapod_load_toml(HIL_SIM_HEXAPOD_FILE, &g_desc, msg, sizeof msg) != LEGSIM_OK) {
    std::fprintf(stderr, "%s: %s\n", HIL_SIM_HEXAPOD_FILE, msg);
    return 1;
  }
  test_walk();
  test_mixed();
  test_watchdog();
  test_realtime_watchdog();
  test_liveness();
  return hil_test::report();
}
