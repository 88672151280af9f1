// The leg's controller as a state machine over frames: IDLE -> (RESET) -> LOCKSTEP <->
// REALTIME, HALTED after a solver failure until the next RESET. Mode-independent: the run
// loop (run_loop.cpp) feeds it frames and real-time ticks with the time they happened.
//
// A STEP is worked in slices: on_frame() accepts it and work() advances it, a bounded
// number of steps per call, so the run loop keeps its heartbeat and reads signals while a
// long STEP runs. The slicing never changes a result: legsim_step(n) is n single steps,
// and the command timeout splits a STEP at the same steps whatever the slices (the sample
// of STEP n is bit-identical however it was sliced). The answer (one state sample) goes
// out when the last step is done. A frame given to on_frame() during a STEP first finishes
// the STEP (the run loop does not read frames during a STEP: they wait in the socket, in
// order, which keeps the lockstep exchange deterministic).
//
// Every frame is checked in this order: id and format (64-byte CAN FD), sequence counter,
// values (NaN/Inf, DBC ranges, model limits), state. The first failure is answered with
// one FAULT frame and nothing else changes. Every accepted CONTROL frame is answered with
// one state sample; accepted ACT_CMD and LOAD_CMD frames are not answered.
//
// The robot (Session::legs() == 2): each leg has its own ACT_CMD and LOAD_CMD ids with their
// own sequence counters; a sample is every leg's frames (protocol.h). Each leg is a node with
// its own command timeout, fed only by its own ACT_CMD: a silent leg trips alone, whatever the
// other leg is sent, and its safe state is on its own actuators.
//
// Command timeout (per leg): armed by an accepted ACT_CMD of that leg when a timeout is set;
// it trips when no further ACT_CMD of that leg is accepted within the timeout, measured in
// simulated time in lockstep (before the first step that would pass the timeout: ceil(timeout
// / h) steps after the command) and in wall-clock time in real time (checked at every tick).
// A mode change (START_RT, STOP_RT) restarts every leg's window, a RESET disarms them.
// Tripping puts that leg's actuators in the safe state, sends FAULT CMD_TIMEOUT once (its
// ACT_CMD id and counter) and sets SAFE_STATE in that leg's ST_STATUS; the leg's next accepted
// ACT_CMD leaves the safe state. The heartbeat is one frame for the whole hil_sim (the DBC has
// one HEARTBEAT): its SAFE_STATE and CMD_WATCHDOG bits are set when any leg's are.
#ifndef HIL_SIM_CONTROLLER_H
#define HIL_SIM_CONTROLLER_H

#include <cstdint>

#include "frame.h"
#include "node.h"
#include "protocol.h"
#include "session.h"

namespace hil {

struct ControllerConfig {
  uint32_t cmd_timeout_ms = 100;  // 0: none
  SafeMode safe_mode = SafeMode::kZeroForce;
  uint32_t decimation = 10;       // real time: one sample every N ticks
  bool verbose = false;           // log faults and mode changes on stderr
};

class Controller : public Node {
 public:
  Controller(Session &session, FrameSink &sink, const ControllerConfig &config);

  void on_frame(const Frame &frame, int64_t now_ns) override;
  // A STEP is accepted and not finished yet.
  bool stepping() const override { return step_left_ > 0; }
  uint64_t step_left() const { return step_left_; }
  // Advances the STEP in progress by at most max_steps steps (> 0); when its last step is
  // done (or a step fails) the STEP is answered. Returns the steps done; 0 when idle.
  uint64_t work(uint64_t max_steps) override;
  // Works the STEP in progress to its end (tests, and on_frame during a STEP).
  void finish_step();
  // On exit (signal or socket failure): a STEP in progress is abandoned, unanswered, after
  // the steps already done (the session is at a whole step, as after any STEP); the
  // actuators of an active session are put in the safe state (config safe_mode).
  using Shutdown = NodeShutdown;
  Shutdown shutdown() override;
  // One real-time tick (steps_per_tick steps); no-op outside REALTIME.
  void rt_tick(int64_t now_ns) override;

  SimState state() const override { return state_; }
  int64_t rt_period_ns() const override { return rt_period_ns_; }
  uint32_t rt_epoch() const override { return rt_epoch_; }  // +1 at every START_RT
  uint32_t rt_ticks() const { return rt_ticks_; }
  void fill_heartbeat(HeartbeatInfo *hb) const override;

  uint32_t rx_frames() const { return rx_frames_; }
  uint32_t rx_rejected() const { return rx_rejected_; }
  uint32_t fault_count() const { return fault_count_; }

 private:
  struct SeqTrack {
    bool have = false;
    uint32_t last = 0;
  };

  void reject(const Fault &f);
  void raise(const Fault &f);
  void solver_fault(legsim_status st, const Request *req);
  bool state_allows(const Request &req) const;
  void handle_control(const Request &req, int64_t now_ns);
  void handle_act(const Request &req, int64_t now_ns);
  void handle_load(const Request &req);
  void end_step();
  // Steps n with the lockstep watchdogs (or none in real time); false after a failure.
  bool advance(uint32_t n, bool lockstep_watchdog, const Request *req);
  void trip(int leg, double elapsed_ms);
  // The status bits of leg's node; leg = -1: the heartbeat's (any leg's watchdog bits).
  uint32_t status_bits(uint32_t events, int leg) const;
  void publish();
  void handle_start(const Request &req);

  Session &session_;
  FrameSink &sink_;
  ControllerConfig config_;

  SimState state_ = SimState::kIdle;
  legsim_status legsim_ = LEGSIM_OK;
  FaultCode last_fault_ = FaultCode::kNone;
  bool fault_since_sample_ = false;
  SeqTrack ctrl_seq_, act_seq_[kMaxLegs], load_seq_[kMaxLegs];  // per leg: its own frame ids
  SeqTrack start_seq_;
  StartRequest pending_start_;  // START_CMD accepted since the last RESET (use = 0: none)

  // command timeout: the same limit for every leg, a watchdog per leg
  struct Watchdog {
    bool armed = false;
    bool safe = false;
    uint64_t steps_since_cmd = 0;  // lockstep
    int64_t last_cmd_ns = 0;       // real time
  };
  uint32_t timeout_ms_ = 0;
  uint64_t timeout_steps_ = 0;
  Watchdog watchdog_[kMaxLegs];

  // real time
  int64_t rt_period_ns_ = 0;
  uint32_t rt_epoch_ = 0;
  uint32_t rt_ticks_ = 0;
  uint32_t rt_decimation_ = 1;
  uint32_t rt_steps_per_tick_ = 1;

  // the STEP in progress
  uint64_t step_left_ = 0, step_total_ = 0;
  Request step_req_;

  uint32_t rx_frames_ = 0, rx_rejected_ = 0, fault_count_ = 0;
};

}  // namespace hil

#endif
