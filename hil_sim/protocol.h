// can/legsim.dbc on the hil_sim side: validates and decodes the bench's frames into
// requests, encodes samples, faults and heartbeats. Bits are packed only by the code
// cantools generates from the DBC at build time (legsim_can.c); nothing here packs bits.
#ifndef HIL_SIM_PROTOCOL_H
#define HIL_SIM_PROTOCOL_H

#include <cstdint>

#include "frame.h"
#include "session.h"

namespace hil {

constexpr int kProtocolVersion = 1;
extern const uint32_t kActCmdFrameId[kMaxLegs];  // ACT_CMD of leg 0, ACT_CMD_L1, from the DBC

enum class FaultCode : uint8_t {
  kNone = 0,
  kUnknownId = 1,
  kBadLength = 2,
  kNotFinite = 3,
  kOutOfRange = 4,
  kStaleSeq = 5,
  kBadState = 6,
  kCmdTimeout = 7,
  kSolver = 8,
};
const char *fault_name(FaultCode code);

struct Fault {
  FaultCode code = FaultCode::kNone;
  uint32_t frame_id = 0;
  uint8_t frame_len = 0;
  uint32_t seq = 0;
  uint32_t detail = 0;
  float value = 0;
};

enum class Command : uint8_t { kReset = 1, kStep = 2, kStartRt = 3, kStopRt = 4 };
enum class SimState : uint8_t { kIdle = 0, kLockstep = 1, kRealtime = 2, kHalted = 3 };

// St_Status / Hb_Status bits.
enum StatusBit : uint32_t {
  kStatusAssembled = 1u << 0,
  kStatusRealtime = 1u << 1,
  kStatusSafeState = 1u << 2,
  kStatusStrokeMin = 1u << 3,
  kStatusStrokeMax = 1u << 4,
  kStatusForceSaturated = 1u << 5,
  kStatusNearSingular = 1u << 6,
  kStatusHalted = 1u << 7,
  kStatusFault = 1u << 8,
  kStatusCmdWatchdog = 1u << 9,
  kStatusStepping = 1u << 10,  // heartbeats only: a STEP is being worked (never in a sample)
};
// legsim_report events -> status bits
uint32_t status_from_events(uint32_t events);

struct ControlRequest {
  Command command = Command::kReset;
  ResetParams reset;
  uint8_t act_init = 0, use_lengths = 0;  // raw Ctrl_ActInit, Ctrl_UseLengths (range-checked)
  uint8_t contact_law = 0, free_contacts = 0;  // raw Ctrl_ContactLaw, Ctrl_FreeContacts
  uint16_t cmd_timeout_ms = 0;  // 0 default, 65535 none
  uint32_t n_steps = 0;
  uint16_t decimation = 0;      // 0 default
  uint8_t steps_per_tick = 1;
};
struct ActRequest {
  ActMode mode[kActuators] = {ActMode::kKeep, ActMode::kKeep};
  float setpoint[kActuators] = {0, 0};
};
struct StartRequest {  // START_CMD: a robot's start off the stance for the next RESET
  uint8_t use = 0, stuck_contacts = 0, sliding_contacts = 0;
  float lift = 0, tilt = 0, velocity[2] = {0, 0}, spin = 0;
};
struct LoadRequest {
  int index = 0;
  float value[2] = {0, 0};
};

struct Request {
  enum class Kind { kControl, kAct, kLoad, kStart, kForeign } kind = Kind::kForeign;
  uint32_t id = 0;
  int leg = 0;  // ACT_CMD / LOAD_CMD: the leg whose frame it is (0, or 1 for the _L1 ids)
  uint32_t seq = 0;
  ControlRequest control;
  ActRequest act;
  LoadRequest load;
  StartRequest start;
};

constexpr uint16_t kCmdTimeoutDefault = 0;
constexpr uint16_t kCmdTimeoutNone = 65535;

// Stage 1, the frame: id, format and length, then unpacks. kForeign: one of hil_sim's own
// ids sent by another node; ignored, never answered (two sims on a bus must not
// answer each other's faults). False with *fault set when the frame is rejected. legs: the
// legs on the bus (Session::legs()); a leg-1 command to a one-leg hil_sim is UNKNOWN_ID.
bool decode_frame(const Frame &frame, Request *out, Fault *fault, int legs = 1);

// Stage 2, the values: NaN/Inf, DBC ranges of the signals the request uses, then the
// model's limits (pose, stroke, max_force, force element). model = the running session's
// (nullptr before the first RESET; ACT/LOAD are then refused by state, not here).
bool validate_request(const Request &req, const legsim_model_desc *model, Fault *fault);

struct StatusInfo {
  uint32_t status[kMaxLegs] = {0, 0};  // per leg: its node's St_Status bits
  SimState state = SimState::kIdle;
  legsim_status legsim = LEGSIM_OK;
  FaultCode last_fault = FaultCode::kNone;
  int variant = 0, integrator = 0;
  uint32_t act_seq[kMaxLegs] = {0, 0};  // per leg: its last accepted ACT_CMD counter
  uint32_t ctrl_seq = 0, step_ns = 0;
};

// Ct_Events: a foot's contact events (legsim_contact_event_mask, LIFTOFF .. CONTACT_AMBIGUOUS,
// legsim_event bits 4-9) as the DBC's bits 0-5.
uint8_t contact_event_bits(uint32_t legsim_events);

// One leg: ST_POS, ST_VEL, ST_ACT, ST_REACT_A, ST_REACT_B, ST_STATUS (6 frames). The robot:
// ST_BOX, then per leg its ST_POS .. ST_REACT_B and ST_CONTACT, then every leg's ST_STATUS
// (leg 0 first): 1 + 2 x 6 + 2 = 15 frames, the sample complete when the last ST_STATUS is.
constexpr int kSampleFrames = 6;
constexpr int kMaxSampleFrames = 1 + kMaxLegs * (kSampleFrames + 1);
// Returns the number of frames written to out.
int encode_sample(const Sample &s, const StatusInfo &info, Frame out[kMaxSampleFrames]);

void encode_fault(const Fault &f, uint64_t step_count, uint32_t fault_count, Frame *out);

struct HeartbeatInfo {
  uint32_t counter = 0;
  SimState state = SimState::kIdle;
  uint32_t status = 0;
  uint32_t uptime_ms = 0;
  uint32_t rt_ticks = 0, rt_overruns = 0;
  float jitter_max_us = 0, jitter_mean_us = 0, jitter_p99_us = 0, rt_rate_hz = 0;
  uint32_t rx_frames = 0, rx_rejected = 0, fault_count = 0, tx_errors = 0;
  double sim_time = 0;
};
void encode_heartbeat(const HeartbeatInfo &h, Frame *out);

}  // namespace hil

#endif
