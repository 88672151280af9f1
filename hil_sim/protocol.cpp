// Frames <-> requests, samples, faults and heartbeats through the generated pack/unpack code.
#include "protocol.h"

#include <cmath>
#include <cstring>

extern "C" {
#include "legsim_can.h"
#include "legsim_can_layout.h"
}

namespace hil {

const uint32_t kActCmdFrameId = LEGSIM_CAN_ACT_CMD_FRAME_ID;

const char *fault_name(FaultCode code) {
  switch (code) {
    case FaultCode::kNone: return "NONE";
    case FaultCode::kUnknownId: return "UNKNOWN_ID";
    case FaultCode::kBadLength: return "BAD_LENGTH";
    case FaultCode::kNotFinite: return "NOT_FINITE";
    case FaultCode::kOutOfRange: return "OUT_OF_RANGE";
    case FaultCode::kStaleSeq: return "STALE_SEQ";
    case FaultCode::kBadState: return "BAD_STATE";
    case FaultCode::kCmdTimeout: return "CMD_TIMEOUT";
    case FaultCode::kSolver: return "SOLVER";
  }
  return "?";
}

uint32_t status_from_events(uint32_t events) {
  uint32_t s = 0;
  if (events & LEGSIM_EVENT_STROKE_MIN) s |= kStatusStrokeMin;
  if (events & LEGSIM_EVENT_STROKE_MAX) s |= kStatusStrokeMax;
  if (events & LEGSIM_EVENT_FORCE_SATURATED) s |= kStatusForceSaturated;
  if (events & LEGSIM_EVENT_NEAR_SINGULAR) s |= kStatusNearSingular;
  return s;
}

namespace {

// Collects the first problem of a request as a fault.
class Checker {
 public:
  Checker(const Request &req, Fault *fault) : req_(req), fault_(fault) {}
  bool ok() const { return ok_; }

  // an integer signal against its DBC range
  void range(bool in_range, unsigned start_bit, double value) {
    if (ok_ && !in_range) fail(FaultCode::kOutOfRange, start_bit, value);
  }
  // a float signal: finite, then its DBC range
  void real(float value, bool in_range, unsigned start_bit) {
    if (!ok_) return;
    if (!std::isfinite(value))
      fail(FaultCode::kNotFinite, start_bit, value);
    else if (!in_range)
      fail(FaultCode::kOutOfRange, start_bit, value);
  }
  // a limit of the model (stroke, max_force, pose, force element)
  void model(bool ok, unsigned start_bit, double value) {
    if (ok_ && !ok) fail(FaultCode::kOutOfRange, start_bit, value);
  }

 private:
  void fail(FaultCode code, unsigned start_bit, double value) {
    ok_ = false;
    fault_->code = code;
    fault_->frame_id = req_.id;
    fault_->frame_len = kFdPayload;
    fault_->seq = req_.seq;
    fault_->detail = start_bit;
    fault_->value = static_cast<float>(value);
  }
  const Request &req_;
  Fault *fault_;
  bool ok_ = true;
};

void reject_frame(const Frame &frame, FaultCode code, uint32_t detail, Fault *fault) {
  *fault = Fault{};
  fault->code = code;
  fault->frame_id = frame.id;
  fault->frame_len = frame.len;
  fault->detail = detail;
}

// A float32 length is inside the stroke when it is inside the stroke's ends rounded to
// float32 (0.8f is 0.800000012): the session then clamps it onto the exact stroke.
bool stroke_ok(const legsim_model_desc *m, int a, float l) {
  return l >= static_cast<float>(m->actuator[a].stroke_min_m) &&
         l <= static_cast<float>(m->actuator[a].stroke_max_m);
}

void validate_control(const Request &req, Checker &c) {
  const ControlRequest &r = req.control;
  c.range(legsim_can_control_ctrl_command_is_in_range(static_cast<uint8_t>(r.command)),
          LEGSIM_CAN_CONTROL_CTRL_COMMAND_START_BIT, static_cast<double>(r.command));
  if (!c.ok()) return;
  switch (r.command) {
    case Command::kReset: {
      const ResetParams &p = r.reset;
      c.range(legsim_can_control_ctrl_variant_is_in_range(static_cast<uint8_t>(p.variant)),
              LEGSIM_CAN_CONTROL_CTRL_VARIANT_START_BIT, p.variant);
      c.range(legsim_can_control_ctrl_integrator_is_in_range(static_cast<uint8_t>(p.integrator)),
              LEGSIM_CAN_CONTROL_CTRL_INTEGRATOR_START_BIT, p.integrator);
      c.range(legsim_can_control_ctrl_pose_is_in_range(static_cast<uint8_t>(p.pose)),
              LEGSIM_CAN_CONTROL_CTRL_POSE_START_BIT, p.pose);
      c.range(legsim_can_control_ctrl_step_size_is_in_range(p.step_ns),
              LEGSIM_CAN_CONTROL_CTRL_STEP_SIZE_START_BIT, p.step_ns);
      c.range(legsim_can_control_ctrl_disable_is_in_range(static_cast<uint8_t>(p.disable)),
              LEGSIM_CAN_CONTROL_CTRL_DISABLE_START_BIT, p.disable);
      c.range(legsim_can_control_ctrl_act_init_is_in_range(r.act_init),
              LEGSIM_CAN_CONTROL_CTRL_ACT_INIT_START_BIT, r.act_init);
      c.range(legsim_can_control_ctrl_use_lengths_is_in_range(r.use_lengths),
              LEGSIM_CAN_CONTROL_CTRL_USE_LENGTHS_START_BIT, r.use_lengths);
      if (!c.ok()) return;
      const legsim_model_desc *m = Session::variant_model(p.variant);
      c.model(p.pose < m->n_poses, LEGSIM_CAN_CONTROL_CTRL_POSE_START_BIT, p.pose);
      if (p.use_lengths) {
        const float l[kActuators] = {static_cast<float>(p.lengths[0]),
                                     static_cast<float>(p.lengths[1])};
        const unsigned bit[kActuators] = {LEGSIM_CAN_CONTROL_CTRL_LENGTH_UPPER_START_BIT,
                                          LEGSIM_CAN_CONTROL_CTRL_LENGTH_LOWER_START_BIT};
        c.real(l[0], legsim_can_control_ctrl_length_upper_is_in_range(l[0]), bit[0]);
        c.real(l[1], legsim_can_control_ctrl_length_lower_is_in_range(l[1]), bit[1]);
        for (int a = 0; a < kActuators; ++a) c.model(stroke_ok(m, a, l[a]), bit[a], l[a]);
      }
      break;
    }
    case Command::kStep:
      c.range(legsim_can_control_ctrl_n_steps_is_in_range(r.n_steps),
              LEGSIM_CAN_CONTROL_CTRL_N_STEPS_START_BIT, r.n_steps);
      break;
    case Command::kStartRt:
      c.range(legsim_can_control_ctrl_rt_decimation_is_in_range(r.decimation),
              LEGSIM_CAN_CONTROL_CTRL_RT_DECIMATION_START_BIT, r.decimation);
      c.range(legsim_can_control_ctrl_rt_steps_per_tick_is_in_range(r.steps_per_tick),
              LEGSIM_CAN_CONTROL_CTRL_RT_STEPS_PER_TICK_START_BIT, r.steps_per_tick);
      break;
    case Command::kStopRt:
      break;
  }
}

void validate_act(const Request &req, const legsim_model_desc *m, Checker &c) {
  const ActRequest &r = req.act;
  const unsigned mode_bit[kActuators] = {LEGSIM_CAN_ACT_CMD_ACT_MODE_UPPER_START_BIT,
                                         LEGSIM_CAN_ACT_CMD_ACT_MODE_LOWER_START_BIT};
  const unsigned sp_bit[kActuators] = {LEGSIM_CAN_ACT_CMD_ACT_SETPOINT_UPPER_START_BIT,
                                       LEGSIM_CAN_ACT_CMD_ACT_SETPOINT_LOWER_START_BIT};
  const bool mode_in_range[kActuators] = {
      legsim_can_act_cmd_act_mode_upper_is_in_range(static_cast<uint8_t>(r.mode[0])),
      legsim_can_act_cmd_act_mode_lower_is_in_range(static_cast<uint8_t>(r.mode[1]))};
  const bool sp_in_range[kActuators] = {
      legsim_can_act_cmd_act_setpoint_upper_is_in_range(r.setpoint[0]),
      legsim_can_act_cmd_act_setpoint_lower_is_in_range(r.setpoint[1])};
  for (int a = 0; a < kActuators; ++a)
    c.range(mode_in_range[a], mode_bit[a], static_cast<double>(r.mode[a]));
  for (int a = 0; a < kActuators; ++a) {
    if (r.mode[a] == ActMode::kKeep) continue;  // setpoint ignored
    c.real(r.setpoint[a], sp_in_range[a], sp_bit[a]);
    if (m == nullptr || !c.ok()) continue;
    const float v = r.setpoint[a];
    if (r.mode[a] == ActMode::kForce)
      c.model(std::fabs(v) <= static_cast<float>(m->actuator[a].max_force_n), sp_bit[a], v);
    else
      c.model(stroke_ok(m, a, v), sp_bit[a], v);
  }
}

void validate_load(const Request &req, const legsim_model_desc *m, Checker &c) {
  const LoadRequest &r = req.load;
  c.range(legsim_can_load_cmd_load_index_is_in_range(static_cast<uint8_t>(r.index)),
          LEGSIM_CAN_LOAD_CMD_LOAD_INDEX_START_BIT, r.index);
  if (m != nullptr)
    c.model(r.index < m->n_forces, LEGSIM_CAN_LOAD_CMD_LOAD_INDEX_START_BIT, r.index);
  c.real(r.value[0], legsim_can_load_cmd_load_value1_is_in_range(r.value[0]),
         LEGSIM_CAN_LOAD_CMD_LOAD_VALUE1_START_BIT);
  c.real(r.value[1], legsim_can_load_cmd_load_value2_is_in_range(r.value[1]),
         LEGSIM_CAN_LOAD_CMD_LOAD_VALUE2_START_BIT);
}

float f32(double v) { return static_cast<float>(v); }

}  // namespace

bool decode_frame(const Frame &frame, Request *out, Fault *fault) {
  *out = Request{};
  out->id = frame.id;
  if (frame.extended || frame.rtr) {
    reject_frame(frame, FaultCode::kUnknownId, frame.extended ? 1u : 2u, fault);
    return false;
  }
  switch (frame.id) {
    case LEGSIM_CAN_CONTROL_FRAME_ID: out->kind = Request::Kind::kControl; break;
    case LEGSIM_CAN_ACT_CMD_FRAME_ID: out->kind = Request::Kind::kAct; break;
    case LEGSIM_CAN_LOAD_CMD_FRAME_ID: out->kind = Request::Kind::kLoad; break;
    case LEGSIM_CAN_FAULT_FRAME_ID:
    case LEGSIM_CAN_ST_POS_FRAME_ID:
    case LEGSIM_CAN_ST_VEL_FRAME_ID:
    case LEGSIM_CAN_ST_ACT_FRAME_ID:
    case LEGSIM_CAN_ST_REACT_A_FRAME_ID:
    case LEGSIM_CAN_ST_REACT_B_FRAME_ID:
    case LEGSIM_CAN_ST_STATUS_FRAME_ID:
    case LEGSIM_CAN_HEARTBEAT_FRAME_ID:
      out->kind = Request::Kind::kForeign;
      return true;
    default:
      reject_frame(frame, FaultCode::kUnknownId, 0, fault);
      return false;
  }
  // every bench frame is a 64-byte CAN FD frame
  if (!frame.fd || frame.len != kFdPayload) {
    reject_frame(frame, FaultCode::kBadLength, kFdPayload, fault);
    return false;
  }
  switch (out->kind) {
    case Request::Kind::kControl: {
      legsim_can_control_t m;
      legsim_can_control_unpack(&m, frame.data, frame.len);
      ControlRequest &r = out->control;
      out->seq = m.ctrl_seq;
      r.command = static_cast<Command>(m.ctrl_command);
      r.reset.variant = m.ctrl_variant;
      r.reset.integrator = m.ctrl_integrator;
      r.reset.pose = m.ctrl_pose;
      r.reset.step_ns = m.ctrl_step_size;
      r.reset.disable = m.ctrl_disable;
      r.reset.hold_length = m.ctrl_act_init != 0;
      r.reset.use_lengths = m.ctrl_use_lengths != 0;
      r.reset.lengths[0] = m.ctrl_length_upper;
      r.reset.lengths[1] = m.ctrl_length_lower;
      r.cmd_timeout_ms = m.ctrl_cmd_timeout;
      r.n_steps = m.ctrl_n_steps;
      r.decimation = m.ctrl_rt_decimation;
      r.steps_per_tick = m.ctrl_rt_steps_per_tick;
      r.act_init = m.ctrl_act_init;
      r.use_lengths = m.ctrl_use_lengths;
      break;
    }
    case Request::Kind::kAct: {
      legsim_can_act_cmd_t m;
      legsim_can_act_cmd_unpack(&m, frame.data, frame.len);
      out->seq = m.act_seq;
      out->act.mode[0] = static_cast<ActMode>(m.act_mode_upper);
      out->act.mode[1] = static_cast<ActMode>(m.act_mode_lower);
      out->act.setpoint[0] = m.act_setpoint_upper;
      out->act.setpoint[1] = m.act_setpoint_lower;
      break;
    }
    case Request::Kind::kLoad: {
      legsim_can_load_cmd_t m;
      legsim_can_load_cmd_unpack(&m, frame.data, frame.len);
      out->seq = m.load_seq;
      out->load.index = m.load_index;
      out->load.value[0] = m.load_value1;
      out->load.value[1] = m.load_value2;
      break;
    }
    case Request::Kind::kForeign:
      break;
  }
  return true;
}

bool validate_request(const Request &req, const legsim_model_desc *model, Fault *fault) {
  Checker c(req, fault);
  switch (req.kind) {
    case Request::Kind::kControl: validate_control(req, c); break;
    case Request::Kind::kAct: validate_act(req, model, c); break;
    case Request::Kind::kLoad: validate_load(req, model, c); break;
    case Request::Kind::kForeign: break;
  }
  return c.ok();
}

#define HIL_POS(msg, pre, b, q)      \
  msg.pre##_b##b##_x = f32(q[3 * (b - 1)]); \
  msg.pre##_b##b##_y = f32(q[3 * (b - 1) + 1]); \
  msg.pre##_b##b##_phi = f32(q[3 * (b - 1) + 2])
#define HIL_VEL(msg, pre, b, qd)      \
  msg.pre##_b##b##_vx = f32(qd[3 * (b - 1)]); \
  msg.pre##_b##b##_vy = f32(qd[3 * (b - 1) + 1]); \
  msg.pre##_b##b##_omega = f32(qd[3 * (b - 1) + 2])
#define HIL_REACT(msg, pre, name, j)             \
  msg.pre##_##name##_fx = f32(s.reaction[j].force_n[0]); \
  msg.pre##_##name##_fy = f32(s.reaction[j].force_n[1]); \
  msg.pre##_##name##_m = f32(s.reaction[j].moment_nm)

void encode_sample(const Sample &s, const StatusInfo &info, Frame out[kSampleFrames]) {
  const uint32_t tick = static_cast<uint32_t>(s.steps);
  for (int i = 0; i < kSampleFrames; ++i) {
    out[i] = Frame{};
    out[i].fd = true;
    out[i].len = kFdPayload;
  }

  legsim_can_st_pos_t pos;
  legsim_can_st_pos_init(&pos);
  pos.pos_tick = tick;
  HIL_POS(pos, pos, 1, s.q);
  HIL_POS(pos, pos, 2, s.q);
  HIL_POS(pos, pos, 3, s.q);
  HIL_POS(pos, pos, 4, s.q);
  HIL_POS(pos, pos, 5, s.q);
  out[0].id = LEGSIM_CAN_ST_POS_FRAME_ID;
  legsim_can_st_pos_pack(out[0].data, &pos, kFdPayload);

  legsim_can_st_vel_t vel;
  legsim_can_st_vel_init(&vel);
  vel.vel_tick = tick;
  HIL_VEL(vel, vel, 1, s.qd);
  HIL_VEL(vel, vel, 2, s.qd);
  HIL_VEL(vel, vel, 3, s.qd);
  HIL_VEL(vel, vel, 4, s.qd);
  HIL_VEL(vel, vel, 5, s.qd);
  out[1].id = LEGSIM_CAN_ST_VEL_FRAME_ID;
  legsim_can_st_vel_pack(out[1].data, &vel, kFdPayload);

  legsim_can_st_act_t act;
  legsim_can_st_act_init(&act);
  act.act_tick = tick;
  HIL_POS(act, act, 6, s.q);
  HIL_VEL(act, act, 6, s.qd);
  act.act_upper_length = f32(s.length[0]);
  act.act_upper_rate = f32(s.rate[0]);
  act.act_upper_force = f32(s.force[0]);
  act.act_lower_length = f32(s.length[1]);
  act.act_lower_rate = f32(s.rate[1]);
  act.act_lower_force = f32(s.force[1]);
  out[2].id = LEGSIM_CAN_ST_ACT_FRAME_ID;
  legsim_can_st_act_pack(out[2].data, &act, kFdPayload);

  legsim_can_st_react_a_t ra;
  legsim_can_st_react_a_init(&ra);
  ra.ra_tick = tick;
  HIL_REACT(ra, ra, a, 0);
  HIL_REACT(ra, ra, upper_actuator, 1);
  HIL_REACT(ra, ra, b_thigh, 2);
  HIL_REACT(ra, ra, b_lower, 3);
  HIL_REACT(ra, ra, c_rod_thigh, 4);
  out[3].id = LEGSIM_CAN_ST_REACT_A_FRAME_ID;
  legsim_can_st_react_a_pack(out[3].data, &ra, kFdPayload);

  legsim_can_st_react_b_t rb;
  legsim_can_st_react_b_init(&rb);
  rb.rb_tick = tick;
  HIL_REACT(rb, rb, c_rod_shank, 5);
  HIL_REACT(rb, rb, lower_actuator, 6);
  HIL_REACT(rb, rb, d, 7);
  out[4].id = LEGSIM_CAN_ST_REACT_B_FRAME_ID;
  legsim_can_st_react_b_pack(out[4].data, &rb, kFdPayload);

  legsim_can_st_status_t st;
  legsim_can_st_status_init(&st);
  st.st_tick = tick;
  st.st_time = s.t;
  st.st_step_count = s.steps;
  st.st_residual = f32(s.residual);
  st.st_condition = f32(s.report.condition);
  st.st_status = static_cast<uint16_t>(info.status);
  st.st_stroke_mask = static_cast<uint8_t>(s.stroke_mask & 0x3u);
  st.st_state = static_cast<uint8_t>(info.state);
  st.st_legsim_status = static_cast<uint8_t>(info.legsim);
  st.st_last_fault = static_cast<uint8_t>(info.last_fault);
  st.st_iterations = static_cast<uint8_t>(s.report.iterations < 0     ? 0
                                          : s.report.iterations > 255 ? 255
                                                                      : s.report.iterations);
  st.st_variant = static_cast<uint8_t>(info.variant);
  st.st_integrator = static_cast<uint8_t>(info.integrator);
  st.st_act_seq = info.act_seq;
  st.st_ctrl_seq = info.ctrl_seq;
  st.st_step_size = info.step_ns;
  out[5].id = LEGSIM_CAN_ST_STATUS_FRAME_ID;
  legsim_can_st_status_pack(out[5].data, &st, kFdPayload);
}

#undef HIL_POS
#undef HIL_VEL
#undef HIL_REACT

void encode_fault(const Fault &f, uint64_t step_count, uint32_t fault_count, Frame *out) {
  *out = Frame{};
  out->id = LEGSIM_CAN_FAULT_FRAME_ID;
  out->fd = true;
  out->len = kFdPayload;
  legsim_can_fault_t m;
  legsim_can_fault_init(&m);
  m.fault_code = static_cast<uint8_t>(f.code);
  m.fault_frame_id = f.frame_id;
  m.fault_frame_len = f.frame_len;
  m.fault_seq = f.seq;
  m.fault_detail = f.detail;
  m.fault_value = f.value;
  m.fault_step_count = step_count;
  m.fault_count = fault_count;
  legsim_can_fault_pack(out->data, &m, kFdPayload);
}

void encode_heartbeat(const HeartbeatInfo &h, Frame *out) {
  *out = Frame{};
  out->id = LEGSIM_CAN_HEARTBEAT_FRAME_ID;
  out->fd = true;
  out->len = kFdPayload;
  legsim_can_heartbeat_t m;
  legsim_can_heartbeat_init(&m);
  m.hb_counter = h.counter;
  m.hb_state = static_cast<uint8_t>(h.state);
  m.hb_status = static_cast<uint16_t>(h.status);
  m.hb_protocol_version = kProtocolVersion;
  m.hb_uptime_ms = h.uptime_ms;
  m.hb_rt_ticks = h.rt_ticks;
  m.hb_rt_overruns = h.rt_overruns;
  m.hb_jitter_max = h.jitter_max_us;
  m.hb_jitter_mean = h.jitter_mean_us;
  m.hb_jitter_p99 = h.jitter_p99_us;
  m.hb_rt_rate = h.rt_rate_hz;
  m.hb_rx_frames = h.rx_frames;
  m.hb_rx_rejected = h.rx_rejected;
  m.hb_fault_count = h.fault_count;
  m.hb_tx_errors = h.tx_errors;
  m.hb_sim_time = h.sim_time;
  legsim_can_heartbeat_pack(out->data, &m, kFdPayload);
}

}  // namespace hil
