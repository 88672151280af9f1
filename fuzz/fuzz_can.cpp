// Fuzz target: hil_sim's CAN frame handling (protocol + controller + session on the real
// core, or the hexapod's node on its C API), frames in memory, no socket.
//
// The input is a bus byte, then a sequence of operations (fuzz/README.md, "The CAN input
// format"):
//   bus byte: bit 1 set: hil_sim --hexapod (the hexapod in space, models/hexapod.toml: the
//             box's and six legs' frames); else bit 0 set: hil_sim --robot (the two-leg robot,
//             models/robot.toml: the box and both legs' frames); else the one leg (hil_sim)
//   op byte: bits 0-1 what, bits 2-7 milliseconds the clock advances first
//     0 frame:     id selector, flags, len, then len payload bytes (zeros past the end)
//                  selector < 0xF0: one of the bus's ids (kIds, kRobotIds, kHexIds); else a
//                  raw id in the next 4 bytes (LE)
//                  flags: bit 0 extended id, bit 1 RTR, bit 2 classic CAN (else FD)
//     1 work:      one byte n: Node::work(n + 1) (a slice of a STEP in progress)
//     2 rt tick:   Node::rt_tick(now)
//     3 heartbeat: fill_heartbeat + encode_heartbeat
// A STEP's Ctrl_NSteps inside the DBC's range is reduced to 1..max_steps (64, the hexapod
// 16), a START_RT's Ctrl_RtStepsPerTick so to 1..4 on the hexapod (the values are still
// valid; out-of-range values are left for the validation to refuse), and at most max_ticks
// real-time ticks (256, the hexapod 32) run per input. The hexapod's step costs 20 to 60 of the
// leg's (180 us on a servoed stand, 510 us with actuators pushing against stuck feet), and 50
// to 140 times that in the fuzz build (9 to 70 ms): its STEPs and ticks also share a budget of
// 32 steps per input (a STEP past it is a STEP 0, a tick past it is not run), so that an input
// stays within a few seconds of libFuzzer's 20 s timeout on a loaded machine.
//
// Invariants (a violation aborts, which libFuzzer records as a crash):
// - every frame hil_sim sends is one of its DBC messages, 11-bit id, CAN FD, 64 bytes, and
//   every signal is inside its DBC range (finite), except where the DBC says otherwise
//   (Fault_Value of a NOT_FINITE fault is the offending NaN/Inf);
// - samples go out whole and in order: ST_POS, ST_VEL, ST_ACT, ST_REACT_A, ST_REACT_B,
//   ST_STATUS; the robot's ST_BOX, then per leg its ST_POS .. ST_REACT_B and ST_CONTACT, then
//   ST_STATUS and ST_STATUS_L1 (hil_sim/protocol.h); the hexapod's HEX_BOX_POSE, HEX_BOX_VEL,
//   per leg HEX_LEG_Hj and HEX_FOOT_Hj, then ST_STATUS (hil_sim/hexapod_node.h);
// - a rejected frame is answered with exactly one FAULT and changes nothing: a twin node
//   that never sees the rejected frames sends the same samples (bit for bit, but for the
//   fault bit and last-fault code of ST_STATUS, and the fault bit of each HEX_LEG_Hj) and
//   the same solver and timeout faults.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "controller.h"
#include "hexapod_node.h"
#include "legsim/hexapod.h"
#include "legsim/models.h"
#include "model_toml.hpp"
#include "protocol.h"
#include "reach.h"
#include "session.h"
#ifndef HIL_SIM_HAS_ROBOT
#define HIL_SIM_HAS_ROBOT 0  // hil_sim_lib defines it when the robot is compiled in
#endif
#if HIL_SIM_HAS_ROBOT
#include "legsim/robot_models.h"
#endif

extern "C" {
#include "can_tx_checks.h"
#include "legsim_can.h"
#include "legsim_can_layout.h"
}

FUZZ_REACH_DEFINE

namespace {

const uint32_t kIds[] = {
    LEGSIM_CAN_CONTROL_FRAME_ID,  LEGSIM_CAN_ACT_CMD_FRAME_ID,   LEGSIM_CAN_LOAD_CMD_FRAME_ID,
    LEGSIM_CAN_CONTROL_FRAME_ID,  LEGSIM_CAN_ACT_CMD_FRAME_ID,   LEGSIM_CAN_LOAD_CMD_FRAME_ID,
    LEGSIM_CAN_FAULT_FRAME_ID,    LEGSIM_CAN_ST_POS_FRAME_ID,    LEGSIM_CAN_ST_STATUS_FRAME_ID,
    LEGSIM_CAN_HEARTBEAT_FRAME_ID, 0x000u,                       0x7ffu,
    0x123u};
constexpr size_t kNIds = sizeof kIds / sizeof kIds[0];
// The robot's bus: the same ids, then leg 1's commands (twice as often) and the robot's
// own state frames (sent by another node: ignored).
const uint32_t kRobotIds[] = {
    LEGSIM_CAN_CONTROL_FRAME_ID,  LEGSIM_CAN_ACT_CMD_FRAME_ID,   LEGSIM_CAN_LOAD_CMD_FRAME_ID,
    LEGSIM_CAN_CONTROL_FRAME_ID,  LEGSIM_CAN_ACT_CMD_FRAME_ID,   LEGSIM_CAN_LOAD_CMD_FRAME_ID,
    LEGSIM_CAN_FAULT_FRAME_ID,    LEGSIM_CAN_ST_POS_FRAME_ID,    LEGSIM_CAN_ST_STATUS_FRAME_ID,
    LEGSIM_CAN_HEARTBEAT_FRAME_ID, 0x000u,                       0x7ffu,
    0x123u,
    LEGSIM_CAN_ACT_CMD_L1_FRAME_ID, LEGSIM_CAN_LOAD_CMD_L1_FRAME_ID,
    LEGSIM_CAN_ACT_CMD_L1_FRAME_ID, LEGSIM_CAN_LOAD_CMD_L1_FRAME_ID,
    LEGSIM_CAN_ST_BOX_FRAME_ID,   LEGSIM_CAN_ST_CONTACT_L1_FRAME_ID, LEGSIM_CAN_ST_STATUS_L1_FRAME_ID};
constexpr size_t kNRobotIds = sizeof kRobotIds / sizeof kRobotIds[0];

// The hexapod's bus: CONTROL, every leg's HEX_CMD (twice as often), the leg's and the robot's
// commands (not the hexapod's: UNKNOWN_ID), its own frames (sent by another node: ignored),
// and foreign ids.
const uint32_t kHexIds[] = {
    LEGSIM_CAN_CONTROL_FRAME_ID,     LEGSIM_CAN_CONTROL_FRAME_ID,     LEGSIM_CAN_HEX_CMD_H0_FRAME_ID,
    LEGSIM_CAN_HEX_CMD_H1_FRAME_ID,  LEGSIM_CAN_HEX_CMD_H2_FRAME_ID,  LEGSIM_CAN_HEX_CMD_H3_FRAME_ID,
    LEGSIM_CAN_HEX_CMD_H4_FRAME_ID,  LEGSIM_CAN_HEX_CMD_H5_FRAME_ID,  LEGSIM_CAN_HEX_CMD_H0_FRAME_ID,
    LEGSIM_CAN_HEX_CMD_H1_FRAME_ID,  LEGSIM_CAN_HEX_CMD_H2_FRAME_ID,  LEGSIM_CAN_HEX_CMD_H3_FRAME_ID,
    LEGSIM_CAN_HEX_CMD_H4_FRAME_ID,  LEGSIM_CAN_HEX_CMD_H5_FRAME_ID,  LEGSIM_CAN_ACT_CMD_FRAME_ID,
    LEGSIM_CAN_LOAD_CMD_FRAME_ID,    LEGSIM_CAN_START_CMD_FRAME_ID,   LEGSIM_CAN_FAULT_FRAME_ID,
    LEGSIM_CAN_ST_STATUS_FRAME_ID,   LEGSIM_CAN_HEARTBEAT_FRAME_ID,   LEGSIM_CAN_HEX_BOX_POSE_FRAME_ID,
    LEGSIM_CAN_HEX_BOX_VEL_FRAME_ID, LEGSIM_CAN_HEX_LEG_H2_FRAME_ID,  LEGSIM_CAN_HEX_FOOT_H5_FRAME_ID,
    0x000u,                          0x7ffu,                          0x123u};
constexpr size_t kNHexIds = sizeof kHexIds / sizeof kHexIds[0];

// A sample's frames in the order they go out (hil_sim/protocol.h).
const uint32_t kLegSample[] = {LEGSIM_CAN_ST_POS_FRAME_ID,     LEGSIM_CAN_ST_VEL_FRAME_ID,
                               LEGSIM_CAN_ST_ACT_FRAME_ID,     LEGSIM_CAN_ST_REACT_A_FRAME_ID,
                               LEGSIM_CAN_ST_REACT_B_FRAME_ID, LEGSIM_CAN_ST_STATUS_FRAME_ID};
const uint32_t kRobotSample[] = {
    LEGSIM_CAN_ST_BOX_FRAME_ID,        LEGSIM_CAN_ST_POS_FRAME_ID,
    LEGSIM_CAN_ST_VEL_FRAME_ID,        LEGSIM_CAN_ST_ACT_FRAME_ID,
    LEGSIM_CAN_ST_REACT_A_FRAME_ID,    LEGSIM_CAN_ST_REACT_B_FRAME_ID,
    LEGSIM_CAN_ST_CONTACT_FRAME_ID,    LEGSIM_CAN_ST_POS_L1_FRAME_ID,
    LEGSIM_CAN_ST_VEL_L1_FRAME_ID,     LEGSIM_CAN_ST_ACT_L1_FRAME_ID,
    LEGSIM_CAN_ST_REACT_A_L1_FRAME_ID, LEGSIM_CAN_ST_REACT_B_L1_FRAME_ID,
    LEGSIM_CAN_ST_CONTACT_L1_FRAME_ID, LEGSIM_CAN_ST_STATUS_FRAME_ID,
    LEGSIM_CAN_ST_STATUS_L1_FRAME_ID};

const uint32_t kHexSample[] = {
    LEGSIM_CAN_HEX_BOX_POSE_FRAME_ID, LEGSIM_CAN_HEX_BOX_VEL_FRAME_ID,
    LEGSIM_CAN_HEX_LEG_H0_FRAME_ID,   LEGSIM_CAN_HEX_FOOT_H0_FRAME_ID,
    LEGSIM_CAN_HEX_LEG_H1_FRAME_ID,   LEGSIM_CAN_HEX_FOOT_H1_FRAME_ID,
    LEGSIM_CAN_HEX_LEG_H2_FRAME_ID,   LEGSIM_CAN_HEX_FOOT_H2_FRAME_ID,
    LEGSIM_CAN_HEX_LEG_H3_FRAME_ID,   LEGSIM_CAN_HEX_FOOT_H3_FRAME_ID,
    LEGSIM_CAN_HEX_LEG_H4_FRAME_ID,   LEGSIM_CAN_HEX_FOOT_H4_FRAME_ID,
    LEGSIM_CAN_HEX_LEG_H5_FRAME_ID,   LEGSIM_CAN_HEX_FOOT_H5_FRAME_ID,
    LEGSIM_CAN_ST_STATUS_FRAME_ID};
static_assert(std::size(kHexSample) == hil::kHexSampleFrames, "the hexapod's sample");

enum class Kind { kLeg, kRobot, kHexapod };

// The bus of an input: its ids, its sample and how much work an input may ask of it.
struct Bus {
  Kind kind;
  const uint32_t *ids;
  size_t n_ids;
  const uint32_t *sample;
  int n_sample;
  uint32_t max_steps;           // per STEP frame
  uint32_t max_steps_per_tick;  // a START_RT's (0: the DBC's)
  int max_ticks;                // per input
  uint32_t max_input_steps;     // STEPs' and ticks' steps per input (0: no budget)
  int sample_index(uint32_t id) const {
    for (int i = 0; i < n_sample; ++i)
      if (sample[i] == id) return i;
    return -1;
  }
};
const Bus kLegBus{Kind::kLeg, kIds, kNIds, kLegSample, static_cast<int>(std::size(kLegSample)), 64, 0, 256, 0};
const Bus kRobotBus{Kind::kRobot, kRobotIds, kNRobotIds, kRobotSample, static_cast<int>(std::size(kRobotSample)),
                    64, 0, 256, 0};
const Bus kHexBus{Kind::kHexapod, kHexIds, kNHexIds, kHexSample, static_cast<int>(std::size(kHexSample)),
                  16, 4, 32, 32};

[[noreturn]] void violated(const char *what, const std::string &detail) {
  std::fprintf(stderr, "fuzz_can: invariant violated: %s: %s\n", what, detail.c_str());
  std::abort();
}

class Recorder : public hil::FrameSink {
 public:
  bool send(const hil::Frame &f) override {
    frames.push_back(f);
    return true;
  }
  std::vector<hil::Frame> take() {
    std::vector<hil::Frame> out;
    out.swap(frames);
    return out;
  }
  std::vector<hil::Frame> frames;
};

// The hexapod file hil_sim --hexapod runs (this source tree's), read once.
const legsim_hexapod_desc &hexapod_desc() {
  static legsim_hexapod_desc desc;
  static bool loaded = false;
  if (!loaded) {
    char msg[512] = "";
    if (legsim_hexapod_load_toml(LEGSIM_FUZZ_SOURCE_DIR "/models/hexapod.toml", &desc, msg, sizeof msg) != LEGSIM_OK)
      violated("hexapod file", msg);
    loaded = true;
  }
  return desc;
}

// One node of the input's bus: the leg's or the robot's controller, or the hexapod's node.
struct Rig {
  Recorder rec;
  hil::Session session;
  std::unique_ptr<hil::Controller> ctl;
  std::unique_ptr<hil::HexapodNode> hex;
  hil::Node *node = nullptr;
  explicit Rig(Kind kind) {
    std::string err;
    if (kind == Kind::kHexapod) {
      hex = std::make_unique<hil::HexapodNode>(hexapod_desc(), rec, hil::HexConfig{});
      if (!hex->init(&err)) violated("hexapod node init", err);
      node = hex.get();
    } else {
      if (!session.init(&err)) violated("session init", err);
      ctl = std::make_unique<hil::Controller>(session, rec, hil::ControllerConfig{});
      node = ctl.get();
    }
  }
  void finish_step() {
    if (hex) hex->finish_step();
    else ctl->finish_step();
  }
};

std::string hex_id(uint32_t id) {
  char b[16];
  std::snprintf(b, sizeof b, "0x%x", id);
  return b;
}

// A frame sent by hil_sim, against the DBC.
void check_tx_frame(const hil::Frame &f) {
  if (f.extended || f.rtr || !f.fd || f.len != hil::kFdPayload)
    violated("sent frame format", hex_id(f.id) + " len " + std::to_string(f.len));
  can_tx_signal sig[32];
  const int n = can_tx_check(f.id, f.data, f.len, sig, 32);
  if (n < 0) violated("sent frame", hex_id(f.id) + " is not a frame hil_sim sends (or does not unpack)");
  if (n > 32) violated("sent frame", "more signals than the check holds");
  const bool not_finite_fault = f.id == LEGSIM_CAN_FAULT_FRAME_ID &&
                                sig[0].value == static_cast<double>(hil::FaultCode::kNotFinite);
  for (int i = 0; i < n; ++i) {
    if (sig[i].in_range) continue;
    if (not_finite_fault && std::strcmp(sig[i].name, "Fault_Value") == 0 && !std::isfinite(sig[i].value))
      continue;  // the DBC: "may be NaN/Inf for NOT_FINITE"
    char v[64];
    std::snprintf(v, sizeof v, "%.17g", sig[i].value);
    violated("sent signal outside its DBC range", std::string(sig[i].name) + " = " + v);
  }
}

// Checks a stream of sent frames (format, ranges, whole samples) and returns what the
// twin comparison looks at: samples with the fault bookkeeping masked, and the faults that
// are not rejections (solver, command timeout) without their counter.
std::vector<std::vector<uint8_t>> checked(const Bus &bus, const std::vector<hil::Frame> &frames,
                                          int *sample_pos) {
  std::vector<std::vector<uint8_t>> out;
  for (const hil::Frame &f : frames) {
    check_tx_frame(f);
    const int in_sample = bus.sample_index(f.id);
    if (in_sample >= 0) {
      if (in_sample != *sample_pos)
        violated("sample frames out of order", hex_id(f.id) + " at position " + std::to_string(*sample_pos));
      *sample_pos = (*sample_pos + 1) % bus.n_sample;
    } else if (*sample_pos != 0) {
      violated("sample interrupted", hex_id(f.id) + " inside a sample");
    }
    std::vector<uint8_t> key(f.data, f.data + f.len);
    key.insert(key.begin(), {static_cast<uint8_t>(f.id >> 8), static_cast<uint8_t>(f.id)});
    if (f.id == LEGSIM_CAN_ST_STATUS_FRAME_ID) {
      legsim_can_st_status_t m;
      legsim_can_st_status_unpack(&m, f.data, f.len);
      m.st_status &= static_cast<uint16_t>(~hil::kStatusFault);
      m.st_last_fault = 0;
      legsim_can_st_status_pack(key.data() + 2, &m, f.len);
    } else if (f.id == LEGSIM_CAN_ST_STATUS_L1_FRAME_ID) {
      legsim_can_st_status_l1_t m;
      legsim_can_st_status_l1_unpack(&m, f.data, f.len);
      m.st_status &= static_cast<uint16_t>(~hil::kStatusFault);
      m.st_last_fault = 0;
      legsim_can_st_status_l1_pack(key.data() + 2, &m, f.len);
    } else if (f.id >= LEGSIM_CAN_HEX_LEG_H0_FRAME_ID && f.id <= LEGSIM_CAN_HEX_LEG_H5_FRAME_ID) {
      legsim_can_hex_leg_h0_t m;  // every leg's frame has leg 0's layout
      legsim_can_hex_leg_h0_unpack(&m, f.data, f.len);
      m.hl_status &= static_cast<uint16_t>(~hil::kStatusFault);
      legsim_can_hex_leg_h0_pack(key.data() + 2, &m, f.len);
    } else if (f.id == LEGSIM_CAN_FAULT_FRAME_ID) {
      legsim_can_fault_t m;
      legsim_can_fault_unpack(&m, f.data, f.len);
      m.fault_count = 0;
      legsim_can_fault_pack(key.data() + 2, &m, f.len);
    }
    out.push_back(key);
  }
  return out;
}

bool is_rejection(const std::vector<hil::Frame> &frames) {
  if (frames.size() != 1 || frames[0].id != LEGSIM_CAN_FAULT_FRAME_ID) return false;
  const uint8_t code = frames[0].data[0];  // Fault_Code: bits 0..7
  return code >= static_cast<uint8_t>(hil::FaultCode::kUnknownId) &&
         code <= static_cast<uint8_t>(hil::FaultCode::kBadState);
}

class Reader {
 public:
  Reader(const uint8_t *d, size_t n) : d_(d), n_(n) {}
  bool more() const { return i_ < n_; }
  uint8_t byte() { return i_ < n_ ? d_[i_++] : 0; }
  // n bytes into out, zeros past the end of the input (as n calls of byte())
  void bytes(uint8_t *out, size_t n) {
    const size_t k = n < n_ - i_ ? n : n_ - i_;
    if (k) std::memcpy(out, d_ + i_, k);
    std::memset(out + k, 0, n - k);
    i_ += k;
  }

 private:
  const uint8_t *d_;
  size_t n_, i_ = 0;
};

// budget: the steps the input may still ask for (bus.max_input_steps), spent by STEP frames.
hil::Frame read_frame(Reader &r, const Bus &bus, uint32_t *budget) {
  hil::Frame f;
  const uint8_t sel = r.byte();
  if (sel < 0xF0) {
    f.id = bus.ids[sel % bus.n_ids];
  } else {
    uint32_t id = 0;
    for (int k = 0; k < 4; ++k) id |= static_cast<uint32_t>(r.byte()) << (8 * k);
    f.id = id;
  }
  const uint8_t flags = r.byte();
  f.extended = flags & 1;
  f.rtr = flags & 2;
  f.fd = !(flags & 4);
  f.id &= f.extended ? 0x1fffffffu : 0x7ffu;  // what SocketCAN can deliver
  f.len = static_cast<uint8_t>(r.byte() % (hil::kFdPayload + 1));
  r.bytes(f.data, f.len);
  // A STEP (a START_RT on the hexapod) within the DBC's range stays valid but short.
  const bool control = f.id == LEGSIM_CAN_CONTROL_FRAME_ID && !f.extended && f.fd && f.len == hil::kFdPayload;
  const uint8_t command = f.data[LEGSIM_CAN_CONTROL_CTRL_COMMAND_START_BIT / 8];
  if (control && command == LEGSIM_CAN_CONTROL_CTRL_COMMAND_STEP_CHOICE) {
    uint8_t *p = f.data + LEGSIM_CAN_CONTROL_CTRL_N_STEPS_START_BIT / 8;
    uint32_t n = static_cast<uint32_t>(p[0]) | static_cast<uint32_t>(p[1]) << 8 |
                 static_cast<uint32_t>(p[2]) << 16 | static_cast<uint32_t>(p[3]) << 24;
    if (legsim_can_control_ctrl_n_steps_is_in_range(n)) {
      if (n > bus.max_steps) n = 1 + (n - 1) % bus.max_steps;
      if (bus.max_input_steps > 0) {
        n = n < *budget ? n : *budget;
        *budget -= n;
      }
      for (int k = 0; k < 4; ++k) p[k] = static_cast<uint8_t>(n >> (8 * k));
    }
  }
  static_assert(LEGSIM_CAN_CONTROL_CTRL_RT_STEPS_PER_TICK_START_BIT % 8 == 0, "one byte");
  if (control && command == LEGSIM_CAN_CONTROL_CTRL_COMMAND_START_RT_CHOICE && bus.max_steps_per_tick > 0) {
    uint8_t &n = f.data[LEGSIM_CAN_CONTROL_CTRL_RT_STEPS_PER_TICK_START_BIT / 8];
    if (legsim_can_control_ctrl_rt_steps_per_tick_is_in_range(n) && n > bus.max_steps_per_tick)
      n = static_cast<uint8_t>(1 + (n - 1) % bus.max_steps_per_tick);
  }
  return f;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  fuzz_reach::input("fuzz_can");
  Reader r(data, size);
  const uint8_t bus_byte = r.byte();
  const Bus &bus = (bus_byte & 2)                        ? kHexBus
                   : (bus_byte & 1) && HIL_SIM_HAS_ROBOT ? kRobotBus
                                                         : kLegBus;
#if HIL_SIM_HAS_ROBOT
  if (bus.kind == Kind::kRobot) hil::Session::use_robot(&legsim_model_robot_revolute);  // hil_sim --robot
  else
#endif
    hil::Session::use_models(&legsim_model_leg_revolute, &legsim_model_leg_slot);
  Rig a(bus.kind), b(bus.kind);  // a gets every frame; b never sees the frames a rejects
  int pos_a = 0, pos_b = 0;
  std::vector<std::vector<uint8_t>> seen_a, seen_b;
  auto collect = [&bus](Rig &rig, int *pos, std::vector<std::vector<uint8_t>> &seen) {
    for (auto &k : checked(bus, rig.rec.take(), pos)) seen.push_back(std::move(k));
  };
  int64_t now_ns = 0;
  int ticks = 0;
  uint32_t hb_counter = 0;
  uint32_t budget = bus.max_input_steps;
  while (r.more()) {
    const uint8_t op = r.byte();
    now_ns += static_cast<int64_t>(op >> 2) * 1000000;
    switch (op & 3) {
      case 0: {
        const hil::Frame f = read_frame(r, bus, &budget);
        // The STEP before the frame is finished first (on_frame does so too): the frame's
        // own answer is then all that a.rec holds.
        a.finish_step();
        b.finish_step();
        collect(a, &pos_a, seen_a);
        collect(b, &pos_b, seen_b);
        a.node->on_frame(f, now_ns);
        std::vector<hil::Frame> reply = a.rec.take();
        const bool rejected = is_rejection(reply);
        for (const hil::Frame &g : reply) {
          if (g.id == LEGSIM_CAN_FAULT_FRAME_ID && reply.size() != 1)
            violated("a FAULT with other frames", "for frame " + hex_id(f.id));
        }
        for (auto &k : checked(bus, reply, &pos_a))
          if (!rejected) seen_a.push_back(std::move(k));
        // the robot reached: one of leg 1's commands accepted by hil_sim --robot
        if (bus.kind == Kind::kRobot && !rejected && !f.extended &&
            (f.id == LEGSIM_CAN_ACT_CMD_L1_FRAME_ID || f.id == LEGSIM_CAN_LOAD_CMD_L1_FRAME_ID))
          fuzz_reach::robot();
        // the hexapod reached: a leg's command accepted by a running hil_sim --hexapod
        if (bus.kind == Kind::kHexapod && !rejected && !f.extended && a.hex->sim() != nullptr &&
            f.id >= LEGSIM_CAN_HEX_CMD_H0_FRAME_ID && f.id <= LEGSIM_CAN_HEX_CMD_H5_FRAME_ID)
          fuzz_reach::hexapod();
        if (!rejected) b.node->on_frame(f, now_ns);
        collect(b, &pos_b, seen_b);
        break;
      }
      case 1: {
        const uint64_t n = static_cast<uint64_t>(r.byte()) + 1;
        a.node->work(n);
        b.node->work(n);
        break;
      }
      case 2:
        if (++ticks > bus.max_ticks) break;
        if (bus.max_input_steps > 0) {  // a tick's steps, at most max_steps_per_tick
          if (budget < bus.max_steps_per_tick) break;
          budget -= bus.max_steps_per_tick;
        }
        a.node->rt_tick(now_ns);
        b.node->rt_tick(now_ns);
        break;
      case 3: {
        hil::HeartbeatInfo hb;
        hb.counter = hb_counter++;
        a.node->fill_heartbeat(&hb);
        hil::Frame f;
        hil::encode_heartbeat(hb, &f);
        check_tx_frame(f);
        break;
      }
    }
    collect(a, &pos_a, seen_a);
    collect(b, &pos_b, seen_b);
  }
  a.finish_step();
  b.finish_step();
  collect(a, &pos_a, seen_a);
  collect(b, &pos_b, seen_b);
  if (pos_a != 0) violated("sample cut short", "the input's last sample is incomplete");
  if (seen_a != seen_b) {
    size_t i = 0;
    while (i < seen_a.size() && i < seen_b.size() && seen_a[i] == seen_b[i]) ++i;
    violated("a rejected frame changed something",
             "sent frame " + std::to_string(i) + " differs from the twin's (" +
                 std::to_string(seen_a.size()) + " vs " + std::to_string(seen_b.size()) + " frames)");
  }
  // Shutdown: the safe state, and whatever it sends, is valid too.
  a.node->shutdown();
  collect(a, &pos_a, seen_a);
  return 0;
}
