// The hexapod in space (legsim/hexapod.h, models/hexapod.toml) as the plant on the bus:
// hil_sim --hexapod. Each leg is a node with its own command frame (HEX_CMD_Hj), its own
// state frames (HEX_LEG_Hj, HEX_FOOT_Hj), its own sequence counter and command watchdog; the
// box's frames (HEX_BOX_POSE, HEX_BOX_VEL), CONTROL, ST_STATUS, FAULT and HEARTBEAT are the
// robot's. The only caller of the hexapod's C API in hil_sim. Layout and rules: can/README.md,
// "The hexapod".
//
// Each slot (a leg's upper and lower actuators and its rowing motor) is in its own mode,
// FORCE or SERVO: every slot's at the RESET (Ctrl_ActInit 0 FORCE, 1 SERVO), then each
// HEX_CMD slot not KEEP sets its own, as a leg controller mixes them. A leg's frame holds its
// three slots, and the six legs' slots go to the core together before the next step, once
// per change (legsim_hexapod_command_each with every slot's mode: an all-SERVO robot gets
// Hexapod.walk's command_pose bit for bit).
//
// Every frame is checked in this order: id and format, sequence counter, values (NaN/Inf,
// DBC ranges, the file's limits for each slot's mode); the first failure is one FAULT frame
// and nothing changes. Nothing is allocated after init().
#ifndef HIL_SIM_HEXAPOD_NODE_H
#define HIL_SIM_HEXAPOD_NODE_H

#include <cstdint>
#include <string>

#include "frame.h"
#include "legsim/hexapod.h"
#include "node.h"
#include "protocol.h"

namespace hil {

constexpr int kHexLegs = LEGSIM_HEXAPOD_LEGS;
constexpr int kHexSlots = 3;  // upper, lower, rowing
constexpr int kHexSampleFrames = 2 + 2 * kHexLegs + 1;
extern const uint32_t kHexCmdFrameId[kHexLegs];

enum class HexMode : uint8_t { kKeep = 0, kForce = 1, kServo = 2 };

struct HexConfig {
  uint32_t cmd_timeout_ms = 100;  // 0: none
  uint32_t decimation = 10;       // real time: one sample every N ticks
  bool verbose = false;
};

// One HEX_CMD frame, decoded.
struct HexCommand {
  uint32_t seq = 0;
  HexMode mode[kHexSlots] = {HexMode::kKeep, HexMode::kKeep, HexMode::kKeep};
  double setpoint[kHexSlots] = {0, 0, 0};
  double ff[kHexSlots] = {0, 0, 0};
};

class HexapodNode : public Node {
 public:
  HexapodNode(const legsim_hexapod_desc &desc, FrameSink &sink, const HexConfig &config);
  ~HexapodNode() override;
  HexapodNode(const HexapodNode &) = delete;
  HexapodNode &operator=(const HexapodNode &) = delete;

  // Allocates the sessions' storage and finds each leg's stand lengths (its file's pose 0).
  bool init(std::string *error);

  void on_frame(const Frame &frame, int64_t now_ns) override;
  bool stepping() const override { return step_left_ > 0; }
  uint64_t work(uint64_t max_steps) override;
  void finish_step();
  NodeShutdown shutdown() override;
  void rt_tick(int64_t now_ns) override;
  SimState state() const override { return state_; }
  int64_t rt_period_ns() const override { return rt_period_ns_; }
  uint32_t rt_epoch() const override { return rt_epoch_; }
  void fill_heartbeat(HeartbeatInfo *hb) const override;

  uint32_t rx_frames() const { return rx_frames_; }
  uint32_t rx_rejected() const { return rx_rejected_; }
  uint32_t fault_count() const { return fault_count_; }
  uint64_t step_count() const { return steps_; }
  const legsim_hexapod_sim *sim() const { return sim_; }
  // Each leg's stand lengths (its file's pose 0): a RESET's lengths without a SERVO command.
  double stand_length(int leg, int a) const { return stand_[leg][a]; }

 private:
  struct SeqTrack {
    bool have = false;
    uint32_t last = 0;
  };
  struct Watchdog {
    bool armed = false, safe = false;
    uint64_t steps_since_cmd = 0;
    int64_t last_cmd_ns = 0;
  };
  // A leg's last SERVO slots since the previous RESET: the next RESET's pose (Ctrl_UseLengths)
  struct Held {
    bool have[kHexSlots] = {false, false, false};
    double setpoint[kHexSlots] = {0, 0, 0}, ff[kHexSlots] = {0, 0, 0};
  };

  void raise(const Fault &f);
  void reject(const Fault &f);
  void solver_fault(legsim_status st, uint32_t id, uint32_t seq);
  bool check_command(int leg, const HexCommand &c, uint32_t id, Fault *f) const;
  void handle_command(int leg, const HexCommand &c, int64_t now_ns);
  void handle_control(const Frame &frame, int64_t now_ns);
  legsim_status reset(const struct HexReset &r);
  legsim_status apply_commands();
  bool advance(uint64_t n, bool lockstep_watchdog, uint32_t id, uint32_t seq);
  void trip(int leg, double elapsed_ms);
  void safe_slots(int leg);
  uint32_t status_bits(int leg) const;
  void publish();

  const legsim_hexapod_desc &desc_;
  FrameSink &sink_;
  HexConfig config_;
  double stand_[kHexLegs][2] = {};

  void *storage_[2] = {nullptr, nullptr};
  size_t storage_bytes_ = 0;
  int current_ = 0;
  legsim_hexapod_sim *sim_ = nullptr;
  uint32_t step_ns_ = 1000000;
  int integrator_ = 0;
  uint64_t steps_ = 0;  // since the RESET

  // the commands: every leg's slots, each in its own mode (never KEEP once a session runs)
  HexMode mode_[kHexLegs][kHexSlots] = {};
  double value_[kHexLegs][kHexSlots] = {}, ff_[kHexLegs][kHexSlots] = {};
  bool dirty_ = false;  // changed since they were given to the core
  Held held_[kHexLegs];
  // the rates at the last step's end (legsim_hexapod_state's), published with the sample
  double rate_[kHexLegs][kHexSlots] = {};

  SimState state_ = SimState::kIdle;
  legsim_status legsim_ = LEGSIM_OK;
  FaultCode last_fault_ = FaultCode::kNone;
  bool fault_since_sample_ = false;
  SeqTrack ctrl_seq_, cmd_seq_[kHexLegs];
  uint32_t timeout_ms_ = 0;
  uint64_t timeout_steps_ = 0;
  Watchdog watchdog_[kHexLegs];

  int64_t rt_period_ns_ = 0;
  uint32_t rt_epoch_ = 0, rt_ticks_ = 0, rt_decimation_ = 1, rt_steps_per_tick_ = 1;

  uint64_t step_left_ = 0, step_total_ = 0;
  uint32_t step_seq_ = 0;

  uint32_t rx_frames_ = 0, rx_rejected_ = 0, fault_count_ = 0;
};

}  // namespace hil

#endif
