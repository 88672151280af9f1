// The hexapod's node: frames -> the hexapod's C API -> frames (hexapod_node.h).
#include "hexapod_node.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

extern "C" {
#include "legsim_can.h"
#include "legsim_can_layout.h"
}

namespace hil {

const uint32_t kHexCmdFrameId[kHexLegs] = {LEGSIM_CAN_HEX_CMD_H0_FRAME_ID, LEGSIM_CAN_HEX_CMD_H1_FRAME_ID,
                                           LEGSIM_CAN_HEX_CMD_H2_FRAME_ID, LEGSIM_CAN_HEX_CMD_H3_FRAME_ID,
                                           LEGSIM_CAN_HEX_CMD_H4_FRAME_ID, LEGSIM_CAN_HEX_CMD_H5_FRAME_ID};

struct HexReset {
  uint32_t seq = 0;
  int integrator = 0;
  uint32_t step_ns = 1000000;
  bool servo = false, use_held = false;
  double box_height = 0;
  uint32_t stance = 0;
  uint16_t cmd_timeout_ms = 0;
};

namespace {

// Every leg's frame has leg 0's layout (can/legsim.dbc.in writes it once): one leg's
// generated unpack and pack per type, chosen by the leg.
template <typename Msg>
void command_from(const Msg &m, HexCommand *c) {
  c->seq = m.hc_seq;
  c->mode[0] = static_cast<HexMode>(m.hc_mode_upper);
  c->mode[1] = static_cast<HexMode>(m.hc_mode_lower);
  c->mode[2] = static_cast<HexMode>(m.hc_mode_rowing);
  c->setpoint[0] = m.hc_setpoint_upper;
  c->setpoint[1] = m.hc_setpoint_lower;
  c->setpoint[2] = m.hc_setpoint_rowing;
  c->ff[0] = m.hc_ff_upper;
  c->ff[1] = m.hc_ff_lower;
  c->ff[2] = m.hc_ff_rowing;
}

#define HEX_UNPACK(J)                                          \
  case J: {                                                    \
    legsim_can_hex_cmd_h##J##_t m;                             \
    legsim_can_hex_cmd_h##J##_unpack(&m, data, kFdPayload);    \
    command_from(m, c);                                        \
    break;                                                     \
  }
void unpack_command(int leg, const uint8_t *data, HexCommand *c) {
  switch (leg) {
    HEX_UNPACK(0)
    HEX_UNPACK(1)
    HEX_UNPACK(2)
    HEX_UNPACK(3)
    HEX_UNPACK(4)
    HEX_UNPACK(5)
  }
}
#undef HEX_UNPACK

struct LegOut {
  uint32_t tick, seq;
  uint16_t status;
  uint8_t foot_state, mode[kHexSlots];
  float length[2], rate[2], force[2], rowing, rowing_rate, rowing_torque;
  double foot[3], foot_force[3];
};

template <typename Leg, typename Foot>
void fill_leg(const LegOut &o, Leg *l, Foot *f) {
  l->hl_tick = o.tick;
  l->hl_status = o.status;
  l->hl_foot_state = o.foot_state;
  l->hl_mode_upper = o.mode[0];
  l->hl_mode_lower = o.mode[1];
  l->hl_mode_rowing = o.mode[2];
  l->hl_seq = o.seq;
  l->hl_length_upper = o.length[0];
  l->hl_length_lower = o.length[1];
  l->hl_rate_upper = o.rate[0];
  l->hl_rate_lower = o.rate[1];
  l->hl_force_upper = o.force[0];
  l->hl_force_lower = o.force[1];
  l->hl_rowing = o.rowing;
  l->hl_rowing_rate = o.rowing_rate;
  l->hl_rowing_torque = o.rowing_torque;
  f->hf_tick = o.tick;
  f->hf_x = o.foot[0];
  f->hf_y = o.foot[1];
  f->hf_z = o.foot[2];
  f->hf_fx = o.foot_force[0];
  f->hf_fy = o.foot_force[1];
  f->hf_fz = o.foot_force[2];
}

Frame fd_frame(uint32_t id) {
  Frame fr;
  fr.id = id;
  fr.fd = true;
  fr.len = kFdPayload;
  return fr;
}

#define HEX_PACK(J)                                                                          \
  case J: {                                                                                  \
    legsim_can_hex_leg_h##J##_t l;                                                           \
    legsim_can_hex_foot_h##J##_t f;                                                          \
    fill_leg(o, &l, &f);                                                                     \
    *leg = fd_frame(LEGSIM_CAN_HEX_LEG_H##J##_FRAME_ID);                                     \
    *foot = fd_frame(LEGSIM_CAN_HEX_FOOT_H##J##_FRAME_ID);                                   \
    legsim_can_hex_leg_h##J##_pack(leg->data, &l, kFdPayload);                              \
    legsim_can_hex_foot_h##J##_pack(foot->data, &f, kFdPayload);                             \
    break;                                                                                   \
  }
void pack_leg(int j, const LegOut &o, Frame *leg, Frame *foot) {
  switch (j) {
    HEX_PACK(0)
    HEX_PACK(1)
    HEX_PACK(2)
    HEX_PACK(3)
    HEX_PACK(4)
    HEX_PACK(5)
  }
}
#undef HEX_PACK

// The first failing check of a frame as its fault (Fault_Detail: the signal's start bit).
class Checks {
 public:
  Checks(uint32_t id, uint32_t seq, Fault *f) : id_(id), seq_(seq), f_(f) {}
  bool ok() const { return ok_; }
  void range(bool in_range, unsigned bit, double v) {
    if (ok_ && !in_range) fail(FaultCode::kOutOfRange, bit, v);
  }
  void real(double v, bool in_range, unsigned bit) {
    if (!ok_) return;
    if (!std::isfinite(v))
      fail(FaultCode::kNotFinite, bit, v);
    else if (!in_range)
      fail(FaultCode::kOutOfRange, bit, v);
  }

 private:
  void fail(FaultCode code, unsigned bit, double v) {
    ok_ = false;
    *f_ = Fault{};
    f_->code = code;
    f_->frame_id = id_;
    f_->frame_len = kFdPayload;
    f_->seq = seq_;
    f_->detail = bit;
    f_->value = std::isfinite(v) ? static_cast<float>(std::clamp(v, -double{FLT_MAX}, double{FLT_MAX}))
                                 : static_cast<float>(v);
  }
  uint32_t id_, seq_;
  Fault *f_;
  bool ok_ = true;
};

bool is_own_frame(uint32_t id) {
  if (id >= LEGSIM_CAN_HEX_LEG_H0_FRAME_ID && id <= LEGSIM_CAN_HEX_LEG_H5_FRAME_ID) return true;
  if (id >= LEGSIM_CAN_HEX_FOOT_H0_FRAME_ID && id <= LEGSIM_CAN_HEX_FOOT_H5_FRAME_ID) return true;
  return id == LEGSIM_CAN_HEX_BOX_POSE_FRAME_ID || id == LEGSIM_CAN_HEX_BOX_VEL_FRAME_ID ||
         id == LEGSIM_CAN_ST_STATUS_FRAME_ID || id == LEGSIM_CAN_FAULT_FRAME_ID ||
         id == LEGSIM_CAN_HEARTBEAT_FRAME_ID;
}

}  // namespace

HexapodNode::HexapodNode(const legsim_hexapod_desc &desc, FrameSink &sink, const HexConfig &config)
    : desc_(desc), sink_(sink), config_(config) {
  if (config_.decimation == 0) config_.decimation = 1;
}

HexapodNode::~HexapodNode() {
  std::free(storage_[0]);
  std::free(storage_[1]);
}

bool HexapodNode::init(std::string *error) {
  static_assert(LEGSIM_CAN_HEX_CMD_H5_FRAME_ID == LEGSIM_CAN_HEX_CMD_H0_FRAME_ID + 5, "HEX_CMD ids in a row");
  static_assert(LEGSIM_CAN_HEX_LEG_H5_FRAME_ID == LEGSIM_CAN_HEX_LEG_H0_FRAME_ID + 5, "HEX_LEG ids in a row");
  static_assert(LEGSIM_CAN_HEX_FOOT_H5_FRAME_ID == LEGSIM_CAN_HEX_FOOT_H0_FRAME_ID + 5, "HEX_FOOT ids in a row");
  if (desc_.n_legs != kHexLegs) {
    *error = "the hexapod file has " + std::to_string(desc_.n_legs) + " legs, the DBC 6";
    return false;
  }
  const size_t align = LEGSIM_STORAGE_ALIGN;
  storage_bytes_ = (std::max(legsim_hexapod_sim_size(), legsim_sim_size()) + align - 1) / align * align;
  for (auto &s : storage_) {
    s = std::aligned_alloc(align, storage_bytes_);
    if (s == nullptr) {
      *error = "cannot allocate " + std::to_string(storage_bytes_) + " bytes of sim storage";
      return false;
    }
  }
  // each leg's stand lengths (its file's pose 0), for a RESET at the stand
  for (int j = 0; j < kHexLegs; ++j) {
    const legsim_model_desc &m = desc_.leg[j].leg;
    if (m.n_actuators != 2) {
      *error = std::string("hexapod leg ") + desc_.leg[j].name + ": " + std::to_string(m.n_actuators) +
               " actuators, the DBC 2";
      return false;
    }
    legsim_options opt = legsim_default_options();
    legsim_sim *leg = nullptr;
    legsim_real len[2] = {0, 0};
    legsim_status st = legsim_init(storage_[0], storage_bytes_, &m, &opt, &leg);
    if (st == LEGSIM_OK) st = legsim_assemble_pose(leg, 0);
    if (st == LEGSIM_OK) st = legsim_actuator_lengths(leg, len, nullptr);
    if (st != LEGSIM_OK) {
      *error = std::string("hexapod leg ") + desc_.leg[j].name + ": its stand: " + legsim_status_str(st);
      return false;
    }
    stand_[j][0] = len[0], stand_[j][1] = len[1];
  }
  return true;
}

// ---- faults ---------------------------------------------------------------------------

void HexapodNode::raise(const Fault &f) {
  ++fault_count_;
  last_fault_ = f.code;
  fault_since_sample_ = true;
  Frame frame;
  encode_fault(f, steps_, fault_count_, &frame);
  sink_.send(frame);
  if (config_.verbose)
    std::fprintf(stderr, "hil_sim: FAULT %s (frame 0x%x len %u seq %u detail %u value %g)\n", fault_name(f.code),
                 f.frame_id, f.frame_len, f.seq, f.detail, static_cast<double>(f.value));
}

void HexapodNode::reject(const Fault &f) {
  ++rx_rejected_;
  raise(f);
}

void HexapodNode::solver_fault(legsim_status st, uint32_t id, uint32_t seq) {
  legsim_ = st;
  Fault f;
  f.code = FaultCode::kSolver;
  f.frame_id = id;
  f.frame_len = id != 0 ? kFdPayload : 0;
  f.seq = seq;
  f.detail = static_cast<uint32_t>(st);
  raise(f);
}

// ---- frames ---------------------------------------------------------------------------

void HexapodNode::on_frame(const Frame &frame, int64_t now_ns) {
  finish_step();  // frames act after the STEP before them
  ++rx_frames_;
  Fault f;
  f.frame_id = frame.id;
  f.frame_len = frame.len;
  if (frame.extended || frame.rtr) {
    f.code = FaultCode::kUnknownId;
    f.detail = frame.extended ? 1u : 2u;
    return reject(f);
  }
  const bool cmd = frame.id >= kHexCmdFrameId[0] && frame.id <= kHexCmdFrameId[kHexLegs - 1];
  if (!cmd && frame.id != LEGSIM_CAN_CONTROL_FRAME_ID) {
    if (is_own_frame(frame.id)) return;  // another node's state, never answered
    f.code = FaultCode::kUnknownId;
    return reject(f);
  }
  if (!frame.fd || frame.len != kFdPayload) {
    f.code = FaultCode::kBadLength;
    f.detail = kFdPayload;
    return reject(f);
  }
  if (!cmd) return handle_control(frame, now_ns);
  const int leg = static_cast<int>(frame.id - kHexCmdFrameId[0]);
  HexCommand c;
  unpack_command(leg, frame.data, &c);
  const SeqTrack &t = cmd_seq_[leg];
  if (t.have && c.seq <= t.last) {
    f.code = FaultCode::kStaleSeq;
    f.seq = c.seq;
    f.detail = t.last;
    f.value = static_cast<float>(c.seq);
    return reject(f);
  }
  if (!check_command(leg, c, frame.id, &f)) return reject(f);
  handle_command(leg, c, now_ns);
}

bool HexapodNode::check_command(int leg, const HexCommand &c, uint32_t id, Fault *f) const {
  Checks k(id, c.seq, f);
  const unsigned mode_bit[kHexSlots] = {LEGSIM_CAN_HEX_CMD_H0_HC_MODE_UPPER_START_BIT,
                                        LEGSIM_CAN_HEX_CMD_H0_HC_MODE_LOWER_START_BIT,
                                        LEGSIM_CAN_HEX_CMD_H0_HC_MODE_ROWING_START_BIT};
  const unsigned set_bit[kHexSlots] = {LEGSIM_CAN_HEX_CMD_H0_HC_SETPOINT_UPPER_START_BIT,
                                       LEGSIM_CAN_HEX_CMD_H0_HC_SETPOINT_LOWER_START_BIT,
                                       LEGSIM_CAN_HEX_CMD_H0_HC_SETPOINT_ROWING_START_BIT};
  const unsigned ff_bit[kHexSlots] = {LEGSIM_CAN_HEX_CMD_H0_HC_FF_UPPER_START_BIT,
                                      LEGSIM_CAN_HEX_CMD_H0_HC_FF_LOWER_START_BIT,
                                      LEGSIM_CAN_HEX_CMD_H0_HC_FF_ROWING_START_BIT};
  const bool mode_in[kHexSlots] = {
      legsim_can_hex_cmd_h0_hc_mode_upper_is_in_range(static_cast<uint8_t>(c.mode[0])),
      legsim_can_hex_cmd_h0_hc_mode_lower_is_in_range(static_cast<uint8_t>(c.mode[1])),
      legsim_can_hex_cmd_h0_hc_mode_rowing_is_in_range(static_cast<uint8_t>(c.mode[2]))};
  const bool set_in[kHexSlots] = {legsim_can_hex_cmd_h0_hc_setpoint_upper_is_in_range(c.setpoint[0]),
                                  legsim_can_hex_cmd_h0_hc_setpoint_lower_is_in_range(c.setpoint[1]),
                                  legsim_can_hex_cmd_h0_hc_setpoint_rowing_is_in_range(c.setpoint[2])};
  const bool ff_in[kHexSlots] = {legsim_can_hex_cmd_h0_hc_ff_upper_is_in_range(c.ff[0]),
                                 legsim_can_hex_cmd_h0_hc_ff_lower_is_in_range(c.ff[1]),
                                 legsim_can_hex_cmd_h0_hc_ff_rowing_is_in_range(c.ff[2])};
  // the DBC: every signal, whatever the modes (a NaN anywhere refuses the frame)
  for (int s = 0; s < kHexSlots; ++s) k.range(mode_in[s], mode_bit[s], static_cast<double>(c.mode[s]));
  for (int s = 0; s < kHexSlots; ++s) k.real(c.setpoint[s], set_in[s], set_bit[s]);
  for (int s = 0; s < kHexSlots; ++s) k.real(c.ff[s], ff_in[s], ff_bit[s]);
  if (!k.ok()) return false;
  // the file's limits for each slot's own mode: strokes and saturations, compared in double
  // with no tolerance (legsim_hexapod_command_each's own checks, so that an accepted command
  // is never refused by the core)
  const legsim_model_desc &m = desc_.leg[leg].leg;
  for (int s = 0; s < kHexSlots; ++s) {
    const double max = s < 2 ? m.actuator[s].max_force_n : desc_.rowing_max_torque_nm;
    const double lo = s < 2 ? m.actuator[s].stroke_min_m : desc_.rowing_stroke_rad[0];
    const double hi = s < 2 ? m.actuator[s].stroke_max_m : desc_.rowing_stroke_rad[1];
    if (c.mode[s] == HexMode::kForce) k.range(std::fabs(c.setpoint[s]) <= max, set_bit[s], c.setpoint[s]);
    if (c.mode[s] == HexMode::kServo) {
      k.range(c.setpoint[s] >= lo && c.setpoint[s] <= hi, set_bit[s], c.setpoint[s]);
      k.range(std::fabs(c.ff[s]) <= max, ff_bit[s], c.ff[s]);
    }
  }
  return k.ok();
}

void HexapodNode::handle_command(int leg, const HexCommand &c, int64_t now_ns) {
  for (int s = 0; s < kHexSlots; ++s) {
    if (c.mode[s] == HexMode::kKeep) continue;
    if (c.mode[s] == HexMode::kServo) {
      held_[leg].have[s] = true;
      held_[leg].setpoint[s] = c.setpoint[s];
      held_[leg].ff[s] = c.ff[s];
    }
    if (sim_ == nullptr) continue;
    mode_[leg][s] = c.mode[s];
    value_[leg][s] = c.setpoint[s];
    ff_[leg][s] = c.mode[s] == HexMode::kServo ? c.ff[s] : 0.0;
    dirty_ = true;
  }
  cmd_seq_[leg] = {true, c.seq};
  if (sim_ == nullptr) return;  // kept for the RESET: nothing to time out
  Watchdog &w = watchdog_[leg];
  w.armed = timeout_ms_ > 0;
  w.safe = false;
  w.steps_since_cmd = 0;
  w.last_cmd_ns = now_ns;
}

void HexapodNode::handle_control(const Frame &frame, int64_t now_ns) {
  legsim_can_control_t m;
  legsim_can_control_unpack(&m, frame.data, frame.len);
  const uint32_t id = frame.id;
  Fault f;
  Checks k(id, m.ctrl_seq, &f);
  const Command command = static_cast<Command>(m.ctrl_command);
  // the counter first (a RESET starts it anew), then the values, then the state
  if (command != Command::kReset && ctrl_seq_.have && m.ctrl_seq <= ctrl_seq_.last) {
    f = Fault{};
    f.code = FaultCode::kStaleSeq;
    f.frame_id = id;
    f.frame_len = frame.len;
    f.seq = m.ctrl_seq;
    f.detail = ctrl_seq_.last;
    f.value = static_cast<float>(m.ctrl_seq);
    return reject(f);
  }
  k.range(legsim_can_control_ctrl_command_is_in_range(m.ctrl_command), LEGSIM_CAN_CONTROL_CTRL_COMMAND_START_BIT,
          m.ctrl_command);
  if (!k.ok()) return reject(f);
  HexReset r;
  switch (command) {
    case Command::kReset:
      // the leg's options that the hexapod has not: 0 only
      k.range(m.ctrl_variant == 0, LEGSIM_CAN_CONTROL_CTRL_VARIANT_START_BIT, m.ctrl_variant);
      k.range(legsim_can_control_ctrl_integrator_is_in_range(m.ctrl_integrator),
              LEGSIM_CAN_CONTROL_CTRL_INTEGRATOR_START_BIT, m.ctrl_integrator);
      k.range(m.ctrl_pose == 0, LEGSIM_CAN_CONTROL_CTRL_POSE_START_BIT, m.ctrl_pose);
      k.range(legsim_can_control_ctrl_step_size_is_in_range(m.ctrl_step_size),
              LEGSIM_CAN_CONTROL_CTRL_STEP_SIZE_START_BIT, m.ctrl_step_size);
      k.range(m.ctrl_disable == 0, LEGSIM_CAN_CONTROL_CTRL_DISABLE_START_BIT, m.ctrl_disable);
      k.range(legsim_can_control_ctrl_act_init_is_in_range(m.ctrl_act_init),
              LEGSIM_CAN_CONTROL_CTRL_ACT_INIT_START_BIT, m.ctrl_act_init);
      k.range(legsim_can_control_ctrl_use_lengths_is_in_range(m.ctrl_use_lengths),
              LEGSIM_CAN_CONTROL_CTRL_USE_LENGTHS_START_BIT, m.ctrl_use_lengths);
      k.range(m.ctrl_contact_law == 0, LEGSIM_CAN_CONTROL_CTRL_CONTACT_LAW_START_BIT, m.ctrl_contact_law);
      k.range(m.ctrl_free_contacts == 0, LEGSIM_CAN_CONTROL_CTRL_FREE_CONTACTS_START_BIT, m.ctrl_free_contacts);
      k.range(legsim_can_control_ctrl_hex_stance_is_in_range(m.ctrl_hex_stance),
              LEGSIM_CAN_CONTROL_CTRL_HEX_STANCE_START_BIT, m.ctrl_hex_stance);
      k.real(m.ctrl_hex_box_height,
             legsim_can_control_ctrl_hex_box_height_is_in_range(m.ctrl_hex_box_height) && m.ctrl_hex_box_height > 0,
             LEGSIM_CAN_CONTROL_CTRL_HEX_BOX_HEIGHT_START_BIT);
      r.seq = m.ctrl_seq;
      r.integrator = m.ctrl_integrator;
      r.step_ns = m.ctrl_step_size;
      r.servo = m.ctrl_act_init == 1;
      r.use_held = m.ctrl_use_lengths == 1;
      r.box_height = m.ctrl_hex_box_height;
      r.stance = m.ctrl_hex_stance;
      r.cmd_timeout_ms = m.ctrl_cmd_timeout;
      break;
    case Command::kStep:
      k.range(legsim_can_control_ctrl_n_steps_is_in_range(m.ctrl_n_steps), LEGSIM_CAN_CONTROL_CTRL_N_STEPS_START_BIT,
              m.ctrl_n_steps);
      break;
    case Command::kStartRt:
      k.range(legsim_can_control_ctrl_rt_decimation_is_in_range(m.ctrl_rt_decimation),
              LEGSIM_CAN_CONTROL_CTRL_RT_DECIMATION_START_BIT, m.ctrl_rt_decimation);
      k.range(legsim_can_control_ctrl_rt_steps_per_tick_is_in_range(m.ctrl_rt_steps_per_tick),
              LEGSIM_CAN_CONTROL_CTRL_RT_STEPS_PER_TICK_START_BIT, m.ctrl_rt_steps_per_tick);
      break;
    case Command::kStopRt: break;
  }
  if (!k.ok()) return reject(f);
  const bool allowed = command == Command::kReset ||
                       ((command == Command::kStep || command == Command::kStartRt) && state_ == SimState::kLockstep) ||
                       (command == Command::kStopRt && (state_ == SimState::kLockstep || state_ == SimState::kRealtime));
  if (!allowed) {
    f = Fault{};
    f.code = FaultCode::kBadState;
    f.frame_id = id;
    f.frame_len = frame.len;
    f.seq = m.ctrl_seq;
    f.detail = static_cast<uint32_t>(state_);
    return reject(f);
  }
  switch (command) {
    case Command::kReset: {
      const legsim_status st = reset(r);
      if (st != LEGSIM_OK) {  // the running session (if any) is untouched
        ++rx_rejected_;
        return solver_fault(st, id, m.ctrl_seq);
      }
      ctrl_seq_ = {true, m.ctrl_seq};
      break;
    }
    case Command::kStep:
      ctrl_seq_ = {true, m.ctrl_seq};
      if (m.ctrl_n_steps == 0) {  // no step: the commands given to the core, the state answered
        const legsim_status st = apply_commands();
        if (st != LEGSIM_OK) {
          state_ = SimState::kHalted;
          solver_fault(st, id, m.ctrl_seq);
        }
        break;
      }
      step_seq_ = m.ctrl_seq;
      step_total_ = step_left_ = m.ctrl_n_steps;
      return;
    case Command::kStartRt:
      ctrl_seq_ = {true, m.ctrl_seq};
      rt_steps_per_tick_ = m.ctrl_rt_steps_per_tick;
      rt_period_ns_ = static_cast<int64_t>(m.ctrl_rt_steps_per_tick) * step_ns_;
      rt_decimation_ = m.ctrl_rt_decimation != 0 ? m.ctrl_rt_decimation : config_.decimation;
      rt_ticks_ = 0;
      ++rt_epoch_;
      for (Watchdog &w : watchdog_) w.last_cmd_ns = now_ns;
      state_ = SimState::kRealtime;
      break;
    case Command::kStopRt:
      ctrl_seq_ = {true, m.ctrl_seq};
      for (Watchdog &w : watchdog_) w.steps_since_cmd = 0;
      if (state_ == SimState::kRealtime) state_ = SimState::kLockstep;
      break;
  }
  publish();
}

legsim_status HexapodNode::reset(const HexReset &r) {
  legsim_hexapod_pose pose;
  pose.box_m[0] = 0, pose.box_m[1] = 0, pose.box_m[2] = r.box_height;
  pose.box_quat[0] = 1, pose.box_quat[1] = pose.box_quat[2] = pose.box_quat[3] = 0;
  double ff[kHexLegs][2] = {}, ffm[kHexLegs] = {};
  for (int j = 0; j < kHexLegs; ++j) {
    const Held &h = held_[j];
    for (int a = 0; a < 2; ++a) {
      const bool held = r.use_held && h.have[a];
      pose.length_m[j][a] = held ? h.setpoint[a] : stand_[j][a];
      ff[j][a] = held ? h.ff[a] : 0.0;
    }
    const bool held = r.use_held && h.have[2];
    pose.rowing_rad[j] = held ? h.setpoint[2] : 0.0;
    ffm[j] = held ? h.ff[2] : 0.0;
  }
  const int spare = sim_ == nullptr ? current_ : 1 - current_;
  legsim_hexapod_sim *next = nullptr;
  legsim_status st = legsim_hexapod_sim_init(storage_[spare], storage_bytes_, &desc_, &pose, r.stance, &next);
  if (st == LEGSIM_OK)
    st = legsim_hexapod_set_integrator(next, r.integrator == 1 ? LEGSIM_INTEGRATOR_GENERALIZED_ALPHA
                                                               : LEGSIM_INTEGRATOR_RK4);
  // SERVO: the servos hold the pose, with the held feed-forwards (Hexapod.walk's first command)
  if (st == LEGSIM_OK && r.servo) st = legsim_hexapod_command_pose(next, pose.length_m, pose.rowing_rad, ff, ffm);
  if (st != LEGSIM_OK) return st;
  sim_ = next;
  current_ = spare;
  step_ns_ = r.step_ns;
  integrator_ = r.integrator;
  steps_ = 0;
  for (int j = 0; j < kHexLegs; ++j) {
    for (HexMode &m : mode_[j]) m = r.servo ? HexMode::kServo : HexMode::kForce;
    for (int a = 0; a < 2; ++a) {
      value_[j][a] = r.servo ? pose.length_m[j][a] : 0.0;
      ff_[j][a] = r.servo ? ff[j][a] : 0.0;
    }
    value_[j][2] = r.servo ? pose.rowing_rad[j] : 0.0;
    ff_[j][2] = r.servo ? ffm[j] : 0.0;
    for (double &v : rate_[j]) v = 0;
    held_[j] = Held{};
    cmd_seq_[j] = {};
    watchdog_[j] = Watchdog{};
  }
  dirty_ = false;
  legsim_ = LEGSIM_OK;
  last_fault_ = FaultCode::kNone;
  state_ = SimState::kLockstep;
  timeout_ms_ = r.cmd_timeout_ms == kCmdTimeoutDefault ? config_.cmd_timeout_ms
                : r.cmd_timeout_ms == kCmdTimeoutNone  ? 0
                                                       : r.cmd_timeout_ms;
  timeout_steps_ = (static_cast<uint64_t>(timeout_ms_) * 1000000u + r.step_ns - 1) / r.step_ns;
  if (config_.verbose)
    std::fprintf(stderr, "hil_sim: hexapod RESET box height %g m, stance 0x%02x, %s, h %u ns\n", r.box_height,
                 r.stance, r.servo ? "servo" : "force", r.step_ns);
  return LEGSIM_OK;
}

// ---- stepping -------------------------------------------------------------------------

legsim_status HexapodNode::apply_commands() {
  if (!dirty_) return LEGSIM_OK;
  legsim_hexapod_commands c;
  for (int j = 0; j < kHexLegs; ++j)
    for (int s = 0; s < kHexSlots; ++s) {
      c.mode[j][s] = static_cast<int32_t>(mode_[j][s]);
      c.value[j][s] = value_[j][s];
      c.feedforward[j][s] = ff_[j][s];
    }
  const legsim_status st = legsim_hexapod_command_each(sim_, &c);
  if (st == LEGSIM_OK) dirty_ = false;
  return st;
}

// The safe action of a leg whose commands stopped, slot by slot: a servo holds its set-point
// without feed-forward (SERVO), a force or torque goes to zero (FORCE).
void HexapodNode::safe_slots(int leg) {
  for (int s = 0; s < kHexSlots; ++s) {
    if (mode_[leg][s] == HexMode::kForce) value_[leg][s] = 0;
    ff_[leg][s] = 0;
  }
  dirty_ = true;
}

void HexapodNode::trip(int leg, double elapsed_ms) {
  watchdog_[leg].armed = false;
  watchdog_[leg].safe = true;
  safe_slots(leg);
  Fault f;
  f.code = FaultCode::kCmdTimeout;
  f.frame_id = kHexCmdFrameId[leg];
  f.seq = cmd_seq_[leg].last;
  f.detail = timeout_ms_;
  f.value = static_cast<float>(elapsed_ms);
  raise(f);
}

bool HexapodNode::advance(uint64_t n, bool lockstep_watchdog, uint32_t id, uint32_t seq) {
  const double h = step_ns_ / 1e9;
  for (uint64_t i = 0; i < n; ++i) {
    for (int j = 0; lockstep_watchdog && j < kHexLegs; ++j) {
      const Watchdog &w = watchdog_[j];
      if (w.armed && w.steps_since_cmd >= timeout_steps_)
        trip(j, static_cast<double>(w.steps_since_cmd) * step_ns_ / 1e6);
    }
    legsim_status st = apply_commands();
    if (st == LEGSIM_OK) st = legsim_hexapod_step(sim_, h, 1);
    if (st != LEGSIM_OK) {
      state_ = SimState::kHalted;
      solver_fault(st, id, seq);
      return false;
    }
    ++steps_;
    for (Watchdog &w : watchdog_) ++w.steps_since_cmd;
    if (i + 1 == n) {  // the rates at the step's end (the state's own)
      legsim_hexapod_state after;
      if (legsim_hexapod_get_state(sim_, &after) == LEGSIM_OK)
        for (int j = 0; j < kHexLegs; ++j) {
          rate_[j][0] = after.length_rate_mps[j][0];
          rate_[j][1] = after.length_rate_mps[j][1];
          rate_[j][2] = after.rowing_rate_radps[j];
        }
    }
  }
  legsim_ = LEGSIM_OK;
  return true;
}

uint64_t HexapodNode::work(uint64_t max_steps) {
  if (step_left_ == 0 || max_steps == 0) return 0;
  const uint64_t before = steps_;
  const uint64_t n = std::min(step_left_, max_steps);
  const bool ok = advance(n, true, LEGSIM_CAN_CONTROL_FRAME_ID, step_seq_);
  step_left_ = ok ? step_left_ - n : 0;
  if (step_left_ == 0) {
    step_total_ = 0;
    publish();
  }
  return steps_ - before;
}

void HexapodNode::finish_step() {
  while (step_left_ > 0) work(step_left_);
}

NodeShutdown HexapodNode::shutdown() {
  NodeShutdown out;
  if (step_left_ > 0) {
    out.step_cut = true;
    out.step_total = step_total_;
    out.step_done = step_total_ - step_left_;
    step_left_ = step_total_ = 0;
  }
  if (sim_ != nullptr) {
    for (int j = 0; j < kHexLegs; ++j) safe_slots(j);
    out.safe_status = apply_commands();
    out.safe_applied = out.safe_status == LEGSIM_OK;
    for (Watchdog &w : watchdog_) {
      w.armed = false;
      w.safe = out.safe_applied;
    }
  }
  return out;
}

void HexapodNode::rt_tick(int64_t now_ns) {
  if (state_ != SimState::kRealtime) return;
  for (int j = 0; j < kHexLegs; ++j) {
    const Watchdog &w = watchdog_[j];
    if (w.armed && now_ns - w.last_cmd_ns > static_cast<int64_t>(timeout_ms_) * 1000000)
      trip(j, static_cast<double>(now_ns - w.last_cmd_ns) / 1e6);
  }
  ++rt_ticks_;
  if (!advance(rt_steps_per_tick_, false, 0, 0)) {
    publish();
    return;
  }
  if (rt_ticks_ % rt_decimation_ == 0) publish();
}

// ---- output ---------------------------------------------------------------------------

uint32_t HexapodNode::status_bits(int leg) const {
  uint32_t s = 0;
  if (sim_ != nullptr) s |= kStatusAssembled;
  if (state_ == SimState::kRealtime) s |= kStatusRealtime;
  if (state_ == SimState::kHalted) s |= kStatusHalted;
  for (int j = 0; j < kHexLegs; ++j) {
    if (leg >= 0 && j != leg) continue;
    if (watchdog_[j].safe) s |= kStatusSafeState;
    if (watchdog_[j].armed) s |= kStatusCmdWatchdog;
  }
  if (fault_since_sample_) s |= kStatusFault;
  if (step_left_ > 0) s |= kStatusStepping;
  return s;
}

void HexapodNode::publish() {
  if (sim_ == nullptr) return;
  legsim_hexapod_state x;
  const legsim_status st = legsim_hexapod_get_state(sim_, &x);
  if (st != LEGSIM_OK) {
    legsim_ = st;
    return;
  }
  const uint32_t tick = static_cast<uint32_t>(steps_);
  Frame frames[kHexSampleFrames];
  int n = 0;
  {
    legsim_can_hex_box_pose_t b;
    b.hb_tick = tick;
    b.hb_x = x.box_m[0], b.hb_y = x.box_m[1], b.hb_z = x.box_m[2];
    b.hb_qw = x.box_quat[0], b.hb_qx = x.box_quat[1], b.hb_qy = x.box_quat[2], b.hb_qz = x.box_quat[3];
    frames[n] = fd_frame(LEGSIM_CAN_HEX_BOX_POSE_FRAME_ID);
    legsim_can_hex_box_pose_pack(frames[n++].data, &b, kFdPayload);
    legsim_can_hex_box_vel_t v;
    v.hv_tick = tick;
    v.hv_impacts = static_cast<uint32_t>(x.impacts);
    v.hv_vx = x.box_velocity_mps[0], v.hv_vy = x.box_velocity_mps[1], v.hv_vz = x.box_velocity_mps[2];
    v.hv_wx = x.box_omega_radps[0], v.hv_wy = x.box_omega_radps[1], v.hv_wz = x.box_omega_radps[2];
    v.hv_energy = x.kinetic_energy_j;
    frames[n] = fd_frame(LEGSIM_CAN_HEX_BOX_VEL_FRAME_ID);
    legsim_can_hex_box_vel_pack(frames[n++].data, &v, kFdPayload);
  }
  for (int j = 0; j < kHexLegs; ++j) {
    LegOut o;
    o.tick = tick;
    o.seq = cmd_seq_[j].last;
    o.status = static_cast<uint16_t>(status_bits(j));
    o.foot_state = static_cast<uint8_t>(x.foot_state[j]);
    for (int a = 0; a < kHexSlots; ++a) o.mode[a] = static_cast<uint8_t>(mode_[j][a]);
    for (int a = 0; a < 2; ++a) {
      o.length[a] = static_cast<float>(x.length_m[j][a]);
      o.rate[a] = static_cast<float>(rate_[j][a]);
      o.force[a] = static_cast<float>(x.actuator_force_n[j][a]);
    }
    o.rowing = static_cast<float>(x.rowing_rad[j]);
    o.rowing_rate = static_cast<float>(rate_[j][2]);
    o.rowing_torque = static_cast<float>(x.rowing_torque_nm[j]);
    for (int i = 0; i < 3; ++i) o.foot[i] = x.foot_m[j][i], o.foot_force[i] = x.foot_force_n[j][i];
    pack_leg(j, o, &frames[n], &frames[n + 1]);
    n += 2;
  }
  legsim_can_st_status_t s;
  std::memset(&s, 0, sizeof s);
  s.st_tick = tick;
  s.st_time = x.t_s;
  s.st_step_count = steps_;
  s.st_status = static_cast<uint16_t>(status_bits(-1));
  s.st_state = static_cast<uint8_t>(state_);
  s.st_legsim_status = static_cast<uint8_t>(legsim_);
  s.st_last_fault = static_cast<uint8_t>(last_fault_);
  s.st_integrator = static_cast<uint8_t>(integrator_);
  s.st_act_seq = cmd_seq_[0].last;
  s.st_ctrl_seq = ctrl_seq_.last;
  s.st_step_size = step_ns_;
  frames[n] = fd_frame(LEGSIM_CAN_ST_STATUS_FRAME_ID);
  legsim_can_st_status_pack(frames[n++].data, &s, kFdPayload);
  for (int i = 0; i < n; ++i) sink_.send(frames[i]);
  fault_since_sample_ = false;
}

void HexapodNode::fill_heartbeat(HeartbeatInfo *hb) const {
  hb->state = state_;
  hb->status = status_bits(-1);
  hb->rx_frames = rx_frames_;
  hb->rx_rejected = rx_rejected_;
  hb->fault_count = fault_count_;
  legsim_hexapod_state x;
  hb->sim_time = sim_ != nullptr && legsim_hexapod_get_state(sim_, &x) == LEGSIM_OK ? x.t_s : 0.0;
  hb->rt_ticks = rt_ticks_;
  hb->rt_rate_hz = rt_period_ns_ > 0 ? static_cast<float>(1e9 / rt_period_ns_) : 0.0f;
}

}  // namespace hil
