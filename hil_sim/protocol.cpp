// Frames <-> requests, samples, faults and heartbeats through the generated pack/unpack code.
#include "protocol.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>

#include "scene_toml.hpp"  // legsim_host::start_length_in_stroke: legsim_cli's rule for a start length

extern "C" {
#include "legsim_can.h"
#include "legsim_can_layout.h"
}

namespace hil {

const uint32_t kActCmdFrameId[kMaxLegs] = {LEGSIM_CAN_ACT_CMD_FRAME_ID, LEGSIM_CAN_ACT_CMD_L1_FRAME_ID};

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

uint8_t contact_event_bits(uint32_t legsim_events) {
  constexpr uint32_t kContactEvents = LEGSIM_EVENT_LIFTOFF | LEGSIM_EVENT_TOUCHDOWN |
                                      LEGSIM_EVENT_STICK_TO_SLIP | LEGSIM_EVENT_SLIP_TO_STICK |
                                      LEGSIM_EVENT_CONTACT_INCONSISTENT |
                                      LEGSIM_EVENT_CONTACT_AMBIGUOUS;
  static_assert(kContactEvents == 0x3Fu << 4, "the contact events are legsim_event bits 4-9");
  return static_cast<uint8_t>((legsim_events & kContactEvents) >> 4);
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
  // a float signal (float32, float64): finite, then its DBC range
  void real(double value, bool in_range, unsigned start_bit) {
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
    // Fault_Value is float32: a finite float64 beyond it (a CONTROL length of 1e300) is
    // reported as +-FLT_MAX, the DBC's range; NaN/Inf stay as they are (NOT_FINITE).
    fault_->value = std::isfinite(value) ? static_cast<float>(std::clamp(value, -double{FLT_MAX}, double{FLT_MAX}))
                                         : static_cast<float>(value);
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

// An ACT_CMD servo set-point (float32) is inside the stroke when it is inside the stroke's
// ends rounded to float32 (0.8f is 0.800000012): the session then clamps it onto the exact
// stroke. (A RESET's start lengths travel as float64 and follow legsim_cli's rule instead.)
bool stroke_ok(const legsim_model_desc *m, int a, float l) {
  return l >= static_cast<float>(m->actuator[a].stroke_min_m) &&
         l <= static_cast<float>(m->actuator[a].stroke_max_m);
}

// START_CMD: DBC ranges, finite values, and feet the model has (the robot's: variant 0)
void validate_start(const Request &req, Checker &c) {
  const StartRequest &r = req.start;
  c.range(legsim_can_start_cmd_start_use_is_in_range(r.use), LEGSIM_CAN_START_CMD_START_USE_START_BIT, r.use);
  c.range(legsim_can_start_cmd_start_stuck_contacts_is_in_range(r.stuck_contacts),
          LEGSIM_CAN_START_CMD_START_STUCK_CONTACTS_START_BIT, r.stuck_contacts);
  c.range(legsim_can_start_cmd_start_sliding_contacts_is_in_range(r.sliding_contacts),
          LEGSIM_CAN_START_CMD_START_SLIDING_CONTACTS_START_BIT, r.sliding_contacts);
  c.real(r.lift, legsim_can_start_cmd_start_lift_is_in_range(r.lift), LEGSIM_CAN_START_CMD_START_LIFT_START_BIT);
  c.real(r.tilt, legsim_can_start_cmd_start_tilt_is_in_range(r.tilt), LEGSIM_CAN_START_CMD_START_TILT_START_BIT);
  c.real(r.velocity[0], legsim_can_start_cmd_start_vx_is_in_range(r.velocity[0]),
         LEGSIM_CAN_START_CMD_START_VX_START_BIT);
  c.real(r.velocity[1], legsim_can_start_cmd_start_vy_is_in_range(r.velocity[1]),
         LEGSIM_CAN_START_CMD_START_VY_START_BIT);
  c.real(r.spin, legsim_can_start_cmd_start_spin_is_in_range(r.spin), LEGSIM_CAN_START_CMD_START_SPIN_START_BIT);
  if (!c.ok() || !r.use) return;
  const legsim_model_desc *m = Session::variant_model(0);
  const int nk = m ? m->n_contacts : 0;
  c.model(nk > 0, LEGSIM_CAN_START_CMD_START_USE_START_BIT, r.use);
  c.model((r.stuck_contacts >> nk) == 0, LEGSIM_CAN_START_CMD_START_STUCK_CONTACTS_START_BIT, r.stuck_contacts);
  c.model((r.sliding_contacts >> nk) == 0, LEGSIM_CAN_START_CMD_START_SLIDING_CONTACTS_START_BIT,
          r.sliding_contacts);
  c.model((r.stuck_contacts & r.sliding_contacts) == 0, LEGSIM_CAN_START_CMD_START_SLIDING_CONTACTS_START_BIT,
          r.sliding_contacts);
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
      c.range(legsim_can_control_ctrl_contact_law_is_in_range(r.contact_law),
              LEGSIM_CAN_CONTROL_CTRL_CONTACT_LAW_START_BIT, r.contact_law);
      c.range(legsim_can_control_ctrl_free_contacts_is_in_range(r.free_contacts),
              LEGSIM_CAN_CONTROL_CTRL_FREE_CONTACTS_START_BIT, r.free_contacts);
      if (!c.ok()) return;
      const legsim_model_desc *m = Session::variant_model(p.variant);  // the robot has one
      c.model(m != nullptr, LEGSIM_CAN_CONTROL_CTRL_VARIANT_START_BIT, p.variant);
      if (!c.ok()) return;
      c.model(p.pose < m->n_poses, LEGSIM_CAN_CONTROL_CTRL_POSE_START_BIT, p.pose);
      // the feet's options need feet: a contact law, and only the model's contacts freed
      c.model(r.contact_law == 0 || m->n_contacts > 0, LEGSIM_CAN_CONTROL_CTRL_CONTACT_LAW_START_BIT,
              r.contact_law);
      c.model((r.free_contacts >> m->n_contacts) == 0, LEGSIM_CAN_CONTROL_CTRL_FREE_CONTACTS_START_BIT,
              r.free_contacts);
      if (p.use_lengths) {
        // leg 0's lengths, then (robot) leg 1's: float64 on the bus, the bench's double as
        // sent; finite, the DBC's range, then legsim_cli's rule
        const double *l = p.lengths;
        const unsigned bit[kMaxActuators] = {LEGSIM_CAN_CONTROL_CTRL_LENGTH_UPPER_START_BIT,
                                             LEGSIM_CAN_CONTROL_CTRL_LENGTH_LOWER_START_BIT,
                                             LEGSIM_CAN_CONTROL_CTRL_LENGTH_UPPER_L1_START_BIT,
                                             LEGSIM_CAN_CONTROL_CTRL_LENGTH_LOWER_L1_START_BIT};
        const bool in_range[kMaxActuators] = {
            legsim_can_control_ctrl_length_upper_is_in_range(l[0]),
            legsim_can_control_ctrl_length_lower_is_in_range(l[1]),
            legsim_can_control_ctrl_length_upper_l1_is_in_range(l[2]),
            legsim_can_control_ctrl_length_lower_l1_is_in_range(l[3])};
        const int na = m->n_actuators;
        for (int a = 0; a < na; ++a) c.real(l[a], in_range[a], bit[a]);
        for (int a = 0; a < na; ++a)
          c.model(legsim_host::start_length_in_stroke(*m, a, l[a]), bit[a], l[a]);
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

// The DBC's checks of one leg's ACT_CMD (leg 1: ACT_CMD_L1, the same layout).
struct ActChecks {
  bool (*mode_in_range[kActuators])(uint8_t);
  bool (*setpoint_in_range[kActuators])(float);
  unsigned mode_bit[kActuators], setpoint_bit[kActuators];
};
const ActChecks kActChecks[kMaxLegs] = {
    {{legsim_can_act_cmd_act_mode_upper_is_in_range, legsim_can_act_cmd_act_mode_lower_is_in_range},
     {legsim_can_act_cmd_act_setpoint_upper_is_in_range,
      legsim_can_act_cmd_act_setpoint_lower_is_in_range},
     {LEGSIM_CAN_ACT_CMD_ACT_MODE_UPPER_START_BIT, LEGSIM_CAN_ACT_CMD_ACT_MODE_LOWER_START_BIT},
     {LEGSIM_CAN_ACT_CMD_ACT_SETPOINT_UPPER_START_BIT,
      LEGSIM_CAN_ACT_CMD_ACT_SETPOINT_LOWER_START_BIT}},
    {{legsim_can_act_cmd_l1_act_mode_upper_is_in_range,
      legsim_can_act_cmd_l1_act_mode_lower_is_in_range},
     {legsim_can_act_cmd_l1_act_setpoint_upper_is_in_range,
      legsim_can_act_cmd_l1_act_setpoint_lower_is_in_range},
     {LEGSIM_CAN_ACT_CMD_L1_ACT_MODE_UPPER_START_BIT, LEGSIM_CAN_ACT_CMD_L1_ACT_MODE_LOWER_START_BIT},
     {LEGSIM_CAN_ACT_CMD_L1_ACT_SETPOINT_UPPER_START_BIT,
      LEGSIM_CAN_ACT_CMD_L1_ACT_SETPOINT_LOWER_START_BIT}}};

void validate_act(const Request &req, const legsim_model_desc *m, Checker &c) {
  const ActRequest &r = req.act;
  const ActChecks &k = kActChecks[req.leg];
  for (int a = 0; a < kActuators; ++a)
    c.range(k.mode_in_range[a](static_cast<uint8_t>(r.mode[a])), k.mode_bit[a],
            static_cast<double>(r.mode[a]));
  for (int a = 0; a < kActuators; ++a) {
    if (r.mode[a] == ActMode::kKeep) continue;  // setpoint ignored
    c.real(r.setpoint[a], k.setpoint_in_range[a](r.setpoint[a]), k.setpoint_bit[a]);
    if (m == nullptr || !c.ok()) continue;
    const float v = r.setpoint[a];
    const int ma = req.leg * kActuators + a;  // the model's actuator
    if (r.mode[a] == ActMode::kForce)
      c.model(std::fabs(v) <= static_cast<float>(m->actuator[ma].max_force_n), k.setpoint_bit[a], v);
    else
      c.model(stroke_ok(m, ma, v), k.setpoint_bit[a], v);
  }
}

struct LoadChecks {
  bool (*index_in_range)(uint8_t);
  bool (*value1_in_range)(float);
  bool (*value2_in_range)(float);
  unsigned index_bit, value1_bit, value2_bit;
};
const LoadChecks kLoadChecks[kMaxLegs] = {
    {legsim_can_load_cmd_load_index_is_in_range, legsim_can_load_cmd_load_value1_is_in_range,
     legsim_can_load_cmd_load_value2_is_in_range, LEGSIM_CAN_LOAD_CMD_LOAD_INDEX_START_BIT,
     LEGSIM_CAN_LOAD_CMD_LOAD_VALUE1_START_BIT, LEGSIM_CAN_LOAD_CMD_LOAD_VALUE2_START_BIT},
    {legsim_can_load_cmd_l1_load_index_is_in_range, legsim_can_load_cmd_l1_load_value1_is_in_range,
     legsim_can_load_cmd_l1_load_value2_is_in_range, LEGSIM_CAN_LOAD_CMD_L1_LOAD_INDEX_START_BIT,
     LEGSIM_CAN_LOAD_CMD_L1_LOAD_VALUE1_START_BIT, LEGSIM_CAN_LOAD_CMD_L1_LOAD_VALUE2_START_BIT}};

void validate_load(const Request &req, const legsim_model_desc *m, Checker &c) {
  const LoadRequest &r = req.load;
  const LoadChecks &k = kLoadChecks[req.leg];
  c.range(k.index_in_range(static_cast<uint8_t>(r.index)), k.index_bit, r.index);
  // the leg's own force elements (the robot: per leg), or leg 0's box load (index 2, 3)
  const bool box = m != nullptr && req.leg == 0 && Session::box_force(m) >= 0 &&
                   (r.index == kBoxLoadIndex || r.index == kBoxLoadIndex + 1);
  if (m != nullptr) c.model(box || r.index < Session::forces_per_leg(m), k.index_bit, r.index);
  c.real(r.value[0], k.value1_in_range(r.value[0]), k.value1_bit);
  c.real(r.value[1], k.value2_in_range(r.value[1]), k.value2_bit);
}

float f32(double v) { return static_cast<float>(v); }

}  // namespace

namespace {

template <typename Msg>
void act_from(const Msg &m, Request *out) {
  out->seq = m.act_seq;
  out->act.mode[0] = static_cast<ActMode>(m.act_mode_upper);
  out->act.mode[1] = static_cast<ActMode>(m.act_mode_lower);
  out->act.setpoint[0] = m.act_setpoint_upper;
  out->act.setpoint[1] = m.act_setpoint_lower;
}

template <typename Msg>
void load_from(const Msg &m, Request *out) {
  out->seq = m.load_seq;
  out->load.index = m.load_index;
  out->load.value[0] = m.load_value1;
  out->load.value[1] = m.load_value2;
}

}  // namespace

bool decode_frame(const Frame &frame, Request *out, Fault *fault, int legs) {
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
    case LEGSIM_CAN_START_CMD_FRAME_ID: out->kind = Request::Kind::kStart; break;
    case LEGSIM_CAN_ACT_CMD_L1_FRAME_ID:
    case LEGSIM_CAN_LOAD_CMD_L1_FRAME_ID:
      if (legs < 2) {  // leg 1's commands exist only on the robot's bus
        reject_frame(frame, FaultCode::kUnknownId, 0, fault);
        return false;
      }
      out->kind = frame.id == LEGSIM_CAN_ACT_CMD_L1_FRAME_ID ? Request::Kind::kAct
                                                             : Request::Kind::kLoad;
      out->leg = 1;
      break;
    case LEGSIM_CAN_ST_POS_L1_FRAME_ID:
    case LEGSIM_CAN_ST_VEL_L1_FRAME_ID:
    case LEGSIM_CAN_ST_ACT_L1_FRAME_ID:
    case LEGSIM_CAN_ST_REACT_A_L1_FRAME_ID:
    case LEGSIM_CAN_ST_REACT_B_L1_FRAME_ID:
    case LEGSIM_CAN_ST_STATUS_L1_FRAME_ID:
    case LEGSIM_CAN_ST_CONTACT_FRAME_ID:
    case LEGSIM_CAN_ST_CONTACT_L1_FRAME_ID:
    case LEGSIM_CAN_ST_BOX_FRAME_ID:
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
      r.reset.lengths[2] = m.ctrl_length_upper_l1;
      r.reset.lengths[3] = m.ctrl_length_lower_l1;
      r.cmd_timeout_ms = m.ctrl_cmd_timeout;
      r.n_steps = m.ctrl_n_steps;
      r.decimation = m.ctrl_rt_decimation;
      r.steps_per_tick = m.ctrl_rt_steps_per_tick;
      r.act_init = m.ctrl_act_init;
      r.use_lengths = m.ctrl_use_lengths;
      r.contact_law = m.ctrl_contact_law;
      r.free_contacts = m.ctrl_free_contacts;
      r.reset.contact_law = m.ctrl_contact_law;
      r.reset.free_contacts = m.ctrl_free_contacts;
      break;
    }
    case Request::Kind::kAct:
      if (out->leg == 0) {
        legsim_can_act_cmd_t m;
        legsim_can_act_cmd_unpack(&m, frame.data, frame.len);
        act_from(m, out);
      } else {
        legsim_can_act_cmd_l1_t m;
        legsim_can_act_cmd_l1_unpack(&m, frame.data, frame.len);
        act_from(m, out);
      }
      break;
    case Request::Kind::kLoad:
      if (out->leg == 0) {
        legsim_can_load_cmd_t m;
        legsim_can_load_cmd_unpack(&m, frame.data, frame.len);
        load_from(m, out);
      } else {
        legsim_can_load_cmd_l1_t m;
        legsim_can_load_cmd_l1_unpack(&m, frame.data, frame.len);
        load_from(m, out);
      }
      break;
    case Request::Kind::kStart: {
      legsim_can_start_cmd_t m;
      legsim_can_start_cmd_unpack(&m, frame.data, frame.len);
      StartRequest &r = out->start;
      out->seq = m.start_seq;
      r.use = m.start_use;
      r.stuck_contacts = m.start_stuck_contacts;
      r.sliding_contacts = m.start_sliding_contacts;
      r.lift = m.start_lift;
      r.tilt = m.start_tilt;
      r.velocity[0] = m.start_vx;
      r.velocity[1] = m.start_vy;
      r.spin = m.start_spin;
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
    case Request::Kind::kStart: validate_start(req, c); break;
    case Request::Kind::kForeign: break;
  }
  return c.ok();
}

namespace {

// One leg's frames, for leg 0's and leg 1's generated structs alike (the same signal names).
// b: the leg's body 1..6; o: 3 x the robot index of the leg's body 1 (0 for the one leg).
#define HIL_POS(msg, pre, b)                      \
  msg.pre##_b##b##_x = f32(s.q[o + 3 * (b - 1)]);     \
  msg.pre##_b##b##_y = f32(s.q[o + 3 * (b - 1) + 1]); \
  msg.pre##_b##b##_phi = f32(s.q[o + 3 * (b - 1) + 2])
#define HIL_VEL(msg, pre, b)                        \
  msg.pre##_b##b##_vx = f32(s.qd[o + 3 * (b - 1)]);     \
  msg.pre##_b##b##_vy = f32(s.qd[o + 3 * (b - 1) + 1]); \
  msg.pre##_b##b##_omega = f32(s.qd[o + 3 * (b - 1) + 2])
#define HIL_REACT(msg, pre, name, j)                       \
  msg.pre##_##name##_fx = f32(s.reaction[jo + j].force_n[0]); \
  msg.pre##_##name##_fy = f32(s.reaction[jo + j].force_n[1]); \
  msg.pre##_##name##_m = f32(s.reaction[jo + j].moment_nm)

template <typename Pos, typename Vel, typename Act, typename ReactA, typename ReactB>
struct LegFrames {
  Pos pos;
  Vel vel;
  Act act;
  ReactA ra;
  ReactB rb;

  void fill(const Sample &s, int leg, uint32_t tick) {
    const int o = s.legs > 1 ? 3 * (1 + leg * kBodies) : 0;  // the robot's box is body 0
    const int jo = leg * kJoints, ao = leg * kActuators;
    std::memset(this, 0, sizeof *this);
    pos.pos_tick = tick;
    HIL_POS(pos, pos, 1);
    HIL_POS(pos, pos, 2);
    HIL_POS(pos, pos, 3);
    HIL_POS(pos, pos, 4);
    HIL_POS(pos, pos, 5);
    vel.vel_tick = tick;
    HIL_VEL(vel, vel, 1);
    HIL_VEL(vel, vel, 2);
    HIL_VEL(vel, vel, 3);
    HIL_VEL(vel, vel, 4);
    HIL_VEL(vel, vel, 5);
    act.act_tick = tick;
    HIL_POS(act, act, 6);
    HIL_VEL(act, act, 6);
    act.act_upper_length = f32(s.length[ao]);
    act.act_upper_rate = f32(s.rate[ao]);
    act.act_upper_force = f32(s.force[ao]);
    act.act_lower_length = f32(s.length[ao + 1]);
    act.act_lower_rate = f32(s.rate[ao + 1]);
    act.act_lower_force = f32(s.force[ao + 1]);
    ra.ra_tick = tick;
    HIL_REACT(ra, ra, a, 0);
    HIL_REACT(ra, ra, upper_actuator, 1);
    HIL_REACT(ra, ra, b_thigh, 2);
    HIL_REACT(ra, ra, b_lower, 3);
    HIL_REACT(ra, ra, c_rod_thigh, 4);
    rb.rb_tick = tick;
    HIL_REACT(rb, rb, c_rod_shank, 5);
    HIL_REACT(rb, rb, lower_actuator, 6);
    HIL_REACT(rb, rb, d, 7);
  }
};

#undef HIL_POS
#undef HIL_VEL
#undef HIL_REACT

template <typename Status>
void fill_status(const Sample &s, const StatusInfo &info, int leg, Status *st) {
  std::memset(st, 0, sizeof *st);
  st->st_tick = static_cast<uint32_t>(s.steps);
  st->st_time = s.t;
  st->st_step_count = s.steps;
  st->st_residual = f32(s.residual);
  st->st_condition = f32(s.report.condition);
  st->st_status = static_cast<uint16_t>(info.status[leg]);
  st->st_stroke_mask = static_cast<uint8_t>((s.stroke_mask >> (leg * kActuators)) & 0x3u);
  st->st_state = static_cast<uint8_t>(info.state);
  st->st_legsim_status = static_cast<uint8_t>(info.legsim);
  st->st_last_fault = static_cast<uint8_t>(info.last_fault);
  st->st_iterations = static_cast<uint8_t>(s.report.iterations < 0     ? 0
                                           : s.report.iterations > 255 ? 255
                                                                       : s.report.iterations);
  st->st_variant = static_cast<uint8_t>(info.variant);
  st->st_integrator = static_cast<uint8_t>(info.integrator);
  st->st_act_seq = info.act_seq[leg];
  st->st_ctrl_seq = info.ctrl_seq;
  st->st_step_size = info.step_ns;
}

template <typename Contact>
void fill_contact(const Sample &s, int k, Contact *m) {
  const ContactSample &c = s.contact[k];
  std::memset(m, 0, sizeof *m);
  m->ct_tick = static_cast<uint32_t>(s.steps);
  m->ct_state = static_cast<uint8_t>(c.state);
  m->ct_events = contact_event_bits(c.events);
  m->ct_normal = f32(c.normal);
  m->ct_tangential = f32(c.tangential);
  m->ct_friction_use = f32(c.friction_use);
  m->ct_x = f32(c.position[0]);
  m->ct_y = f32(c.position[1]);
  m->ct_slip = f32(c.slip);
  m->ct_impulse_n = f32(c.impulse[0]);
  m->ct_impulse_t = f32(c.impulse[1]);
}

Frame *next_frame(Frame *out, int *n, uint32_t id) {
  Frame *f = &out[(*n)++];
  *f = Frame{};
  f->id = id;
  f->fd = true;
  f->len = kFdPayload;
  return f;
}

}  // namespace

int encode_sample(const Sample &s, const StatusInfo &info, Frame out[kMaxSampleFrames]) {
  const uint32_t tick = static_cast<uint32_t>(s.steps);
  int n = 0;
  if (s.legs > 1) {  // the robot: the box first
    legsim_can_st_box_t box;
    std::memset(&box, 0, sizeof box);
    box.box_tick = tick;
    box.box_x = f32(s.q[0]);
    box.box_y = f32(s.q[1]);
    box.box_phi = f32(s.q[2]);
    box.box_vx = f32(s.qd[0]);
    box.box_vy = f32(s.qd[1]);
    box.box_omega = f32(s.qd[2]);
    legsim_can_st_box_pack(next_frame(out, &n, LEGSIM_CAN_ST_BOX_FRAME_ID)->data, &box, kFdPayload);
  }

  LegFrames<legsim_can_st_pos_t, legsim_can_st_vel_t, legsim_can_st_act_t, legsim_can_st_react_a_t,
            legsim_can_st_react_b_t>
      leg0;
  leg0.fill(s, 0, tick);
  legsim_can_st_pos_pack(next_frame(out, &n, LEGSIM_CAN_ST_POS_FRAME_ID)->data, &leg0.pos, kFdPayload);
  legsim_can_st_vel_pack(next_frame(out, &n, LEGSIM_CAN_ST_VEL_FRAME_ID)->data, &leg0.vel, kFdPayload);
  legsim_can_st_act_pack(next_frame(out, &n, LEGSIM_CAN_ST_ACT_FRAME_ID)->data, &leg0.act, kFdPayload);
  legsim_can_st_react_a_pack(next_frame(out, &n, LEGSIM_CAN_ST_REACT_A_FRAME_ID)->data, &leg0.ra,
                             kFdPayload);
  legsim_can_st_react_b_pack(next_frame(out, &n, LEGSIM_CAN_ST_REACT_B_FRAME_ID)->data, &leg0.rb,
                             kFdPayload);
  if (s.legs > 1) {
    legsim_can_st_contact_t c0;
    fill_contact(s, 0, &c0);
    legsim_can_st_contact_pack(next_frame(out, &n, LEGSIM_CAN_ST_CONTACT_FRAME_ID)->data, &c0,
                               kFdPayload);
    LegFrames<legsim_can_st_pos_l1_t, legsim_can_st_vel_l1_t, legsim_can_st_act_l1_t,
              legsim_can_st_react_a_l1_t, legsim_can_st_react_b_l1_t>
        leg1;
    leg1.fill(s, 1, tick);
    legsim_can_st_pos_l1_pack(next_frame(out, &n, LEGSIM_CAN_ST_POS_L1_FRAME_ID)->data, &leg1.pos,
                              kFdPayload);
    legsim_can_st_vel_l1_pack(next_frame(out, &n, LEGSIM_CAN_ST_VEL_L1_FRAME_ID)->data, &leg1.vel,
                              kFdPayload);
    legsim_can_st_act_l1_pack(next_frame(out, &n, LEGSIM_CAN_ST_ACT_L1_FRAME_ID)->data, &leg1.act,
                              kFdPayload);
    legsim_can_st_react_a_l1_pack(next_frame(out, &n, LEGSIM_CAN_ST_REACT_A_L1_FRAME_ID)->data,
                                  &leg1.ra, kFdPayload);
    legsim_can_st_react_b_l1_pack(next_frame(out, &n, LEGSIM_CAN_ST_REACT_B_L1_FRAME_ID)->data,
                                  &leg1.rb, kFdPayload);
    legsim_can_st_contact_l1_t c1;
    fill_contact(s, 1, &c1);
    legsim_can_st_contact_l1_pack(next_frame(out, &n, LEGSIM_CAN_ST_CONTACT_L1_FRAME_ID)->data, &c1,
                                  kFdPayload);
  }
  // every leg's ST_STATUS last: the sample is complete when the last one is sent
  legsim_can_st_status_t st0;
  fill_status(s, info, 0, &st0);
  legsim_can_st_status_pack(next_frame(out, &n, LEGSIM_CAN_ST_STATUS_FRAME_ID)->data, &st0,
                            kFdPayload);
  if (s.legs > 1) {
    legsim_can_st_status_l1_t st1;
    fill_status(s, info, 1, &st1);
    legsim_can_st_status_l1_pack(next_frame(out, &n, LEGSIM_CAN_ST_STATUS_L1_FRAME_ID)->data, &st1,
                                 kFdPayload);
  }
  return n;
}

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
