// Lockstep / real-time state machine of hil_sim.
#include "controller.h"

#include <algorithm>
#include <cstdio>

namespace hil {

Controller::Controller(Session &session, FrameSink &sink, const ControllerConfig &config)
    : session_(session), sink_(sink), config_(config) {
  if (config_.decimation == 0) config_.decimation = 1;
}

// ---- faults ---------------------------------------------------------------------------

void Controller::raise(const Fault &f) {
  ++fault_count_;
  last_fault_ = f.code;
  fault_since_sample_ = true;
  Frame frame;
  encode_fault(f, session_.active() ? session_.step_count() : 0, fault_count_, &frame);
  sink_.send(frame);
  if (config_.verbose)
    std::fprintf(stderr, "hil_sim: FAULT %s (frame 0x%x len %u seq %u detail %u value %g)\n",
                 fault_name(f.code), f.frame_id, f.frame_len, f.seq, f.detail,
                 static_cast<double>(f.value));
}

void Controller::reject(const Fault &f) {
  ++rx_rejected_;
  raise(f);
}

void Controller::solver_fault(legsim_status st, const Request *req) {
  legsim_ = st;
  Fault f;
  f.code = FaultCode::kSolver;
  if (req != nullptr) {
    f.frame_id = req->id;
    f.frame_len = kFdPayload;
    f.seq = req->seq;
  }
  f.detail = static_cast<uint32_t>(st);
  raise(f);
}

// ---- frames ---------------------------------------------------------------------------

bool Controller::state_allows(const Request &req) const {
  if (req.kind == Request::Kind::kStart) return true;  // for the next RESET, in any state
  if (req.kind != Request::Kind::kControl)
    return state_ == SimState::kLockstep || state_ == SimState::kRealtime;
  switch (req.control.command) {
    case Command::kReset: return true;
    case Command::kStep:
    case Command::kStartRt: return state_ == SimState::kLockstep;
    case Command::kStopRt: return state_ == SimState::kLockstep || state_ == SimState::kRealtime;
  }
  return false;
}

void Controller::on_frame(const Frame &frame, int64_t now_ns) {
  finish_step();  // frames act after the STEP before them, however it was worked
  ++rx_frames_;
  Request req;
  Fault f;
  if (!decode_frame(frame, &req, &f, Session::legs())) return reject(f);
  if (req.kind == Request::Kind::kForeign) return;

  // sequence counter: greater than the last accepted of its id (a RESET starts anew)
  const bool is_reset =
      req.kind == Request::Kind::kControl && req.control.command == Command::kReset;
  SeqTrack *track = req.kind == Request::Kind::kControl ? &ctrl_seq_
                    : req.kind == Request::Kind::kAct   ? &act_seq_[req.leg]
                    : req.kind == Request::Kind::kStart ? &start_seq_
                                                        : &load_seq_[req.leg];
  if (!is_reset && track->have && req.seq <= track->last) {
    f = Fault{};
    f.code = FaultCode::kStaleSeq;
    f.frame_id = req.id;
    f.frame_len = frame.len;
    f.seq = req.seq;
    f.detail = track->last;
    f.value = static_cast<float>(req.seq);
    return reject(f);
  }
  if (!validate_request(req, session_.active() ? session_.model() : nullptr, &f))
    return reject(f);
  if (!state_allows(req)) {
    f = Fault{};
    f.code = FaultCode::kBadState;
    f.frame_id = req.id;
    f.frame_len = frame.len;
    f.seq = req.seq;
    f.detail = static_cast<uint32_t>(state_);
    return reject(f);
  }

  switch (req.kind) {
    case Request::Kind::kControl: handle_control(req, now_ns); break;
    case Request::Kind::kAct: handle_act(req, now_ns); break;
    case Request::Kind::kLoad: handle_load(req); break;
    case Request::Kind::kStart: handle_start(req); break;
    case Request::Kind::kForeign: break;
  }
}

void Controller::handle_start(const Request &req) {
  pending_start_ = req.start;
  start_seq_ = {true, req.seq};
}

void Controller::handle_control(const Request &req, int64_t now_ns) {
  const ControlRequest &r = req.control;
  switch (r.command) {
    case Command::kReset: {
      ResetParams p = r.reset;
      p.hold_length = r.act_init == 1;
      p.use_lengths = r.use_lengths == 1;
      // a RESET uses up the START_CMD since the previous one (none: the stance at rest)
      const StartRequest start = pending_start_;
      pending_start_ = StartRequest{};
      start_seq_ = {};
      p.use_start = start.use == 1;
      p.start_lift = start.lift;
      p.start_tilt = start.tilt;
      p.start_velocity[0] = start.velocity[0];
      p.start_velocity[1] = start.velocity[1];
      p.start_spin = start.spin;
      p.stuck_contacts = start.stuck_contacts;
      p.sliding_contacts = start.sliding_contacts;
      legsim_status st = session_.reset(p);
      if (st != LEGSIM_OK) {  // the running session (if any) is untouched
        ++rx_rejected_;
        return solver_fault(st, &req);
      }
      legsim_ = LEGSIM_OK;
      last_fault_ = FaultCode::kNone;
      state_ = SimState::kLockstep;
      ctrl_seq_ = {true, req.seq};
      for (int k = 0; k < kMaxLegs; ++k) act_seq_[k] = load_seq_[k] = {};
      timeout_ms_ = r.cmd_timeout_ms == kCmdTimeoutDefault ? config_.cmd_timeout_ms
                    : r.cmd_timeout_ms == kCmdTimeoutNone  ? 0
                                                           : r.cmd_timeout_ms;
      timeout_steps_ = (static_cast<uint64_t>(timeout_ms_) * 1000000u + p.step_ns - 1) / p.step_ns;
      for (Watchdog &w : watchdog_) w = Watchdog{};
      if (config_.verbose)
        std::fprintf(stderr, "hil_sim: RESET variant %d integrator %d pose %d h %u ns\n",
                     p.variant, p.integrator, p.pose, p.step_ns);
      break;
    }
    case Command::kStep:  // worked by work(), answered when done
      ctrl_seq_ = {true, req.seq};
      if (r.n_steps == 0) {
        // no step: the contact modes checked at the current state and commands (as a step's
        // start would), answered with the state there (a scene's t = 0 after its commands)
        const legsim_status st = session_.contacts_check();
        if (st != LEGSIM_OK) {
          state_ = SimState::kHalted;
          solver_fault(st, &req);
        }
        break;
      }
      step_req_ = req;
      step_total_ = step_left_ = r.n_steps;  // validated: <= 1e7
      return;
    case Command::kStartRt:
      ctrl_seq_ = {true, req.seq};
      rt_steps_per_tick_ = r.steps_per_tick;
      rt_period_ns_ = static_cast<int64_t>(r.steps_per_tick) * session_.params().step_ns;
      rt_decimation_ = r.decimation != 0 ? r.decimation : config_.decimation;
      rt_ticks_ = 0;
      ++rt_epoch_;
      for (Watchdog &w : watchdog_) w.last_cmd_ns = now_ns;  // the windows restart
      state_ = SimState::kRealtime;
      break;
    case Command::kStopRt:
      ctrl_seq_ = {true, req.seq};
      for (Watchdog &w : watchdog_) w.steps_since_cmd = 0;  // the windows restart
      if (state_ == SimState::kRealtime) state_ = SimState::kLockstep;
      break;
  }
  publish();
}

void Controller::handle_act(const Request &req, int64_t now_ns) {
  for (int a = 0; a < kActuators; ++a) {
    legsim_status st =
        session_.command(req.leg * kActuators + a, req.act.mode[a], req.act.setpoint[a]);
    if (st != LEGSIM_OK) return solver_fault(st, &req);
  }
  act_seq_[req.leg] = {true, req.seq};
  Watchdog &w = watchdog_[req.leg];  // this leg's only: the other leg's runs on
  w.armed = timeout_ms_ > 0;
  w.safe = false;
  w.steps_since_cmd = 0;
  w.last_cmd_ns = now_ns;
}

void Controller::handle_load(const Request &req) {
  const double v[2] = {req.load.value[0], req.load.value[1]};
  const legsim_model_desc *m = session_.model();
  const int box = Session::box_force(m);
  const int force = req.leg == 0 && box >= 0 && req.load.index >= kBoxLoadIndex
                        ? box + (req.load.index - kBoxLoadIndex)  // box.load, box.moment
                        : req.leg * Session::forces_per_leg(m) + req.load.index;
  legsim_status st = session_.set_load(force, v);
  if (st != LEGSIM_OK) return solver_fault(st, &req);
  load_seq_[req.leg] = {true, req.seq};
}

// ---- stepping -------------------------------------------------------------------------

void Controller::trip(int leg, double elapsed_ms) {
  watchdog_[leg].armed = false;
  watchdog_[leg].safe = true;
  legsim_status st = session_.apply_safe_state(config_.safe_mode, leg);
  Fault f;
  f.code = FaultCode::kCmdTimeout;
  f.frame_id = kActCmdFrameId[leg];
  f.seq = act_seq_[leg].last;
  f.detail = timeout_ms_;
  f.value = static_cast<float>(elapsed_ms);
  raise(f);
  if (st != LEGSIM_OK) solver_fault(st, nullptr);
}

bool Controller::advance(uint32_t n, bool lockstep_watchdog, const Request *req) {
  uint64_t remaining = n;
  while (remaining > 0) {
    uint64_t chunk = remaining;
    for (int k = 0; lockstep_watchdog && k < Session::legs(); ++k) {
      Watchdog &w = watchdog_[k];
      if (w.armed && w.steps_since_cmd >= timeout_steps_)
        trip(k, static_cast<double>(w.steps_since_cmd) * session_.params().step_ns / 1e6);
      if (w.armed) chunk = std::min(chunk, timeout_steps_ - w.steps_since_cmd);
    }
    const uint64_t before = session_.step_count();
    legsim_status st = session_.step(static_cast<int32_t>(chunk));
    const uint64_t done = session_.step_count() - before;
    for (Watchdog &w : watchdog_) w.steps_since_cmd += done;
    remaining -= std::min(done, remaining);
    if (st != LEGSIM_OK) {
      state_ = SimState::kHalted;
      solver_fault(st, req);
      return false;
    }
    if (done == 0) break;  // defensive: a core that reports OK without stepping
  }
  legsim_ = LEGSIM_OK;
  return true;
}

uint64_t Controller::work(uint64_t max_steps) {
  if (step_left_ == 0 || max_steps == 0) return 0;
  const uint64_t before = session_.step_count();
  const uint64_t n = std::min(step_left_, max_steps);
  const bool ok = advance(static_cast<uint32_t>(n), true, &step_req_);
  const uint64_t done = session_.step_count() - before;
  step_left_ -= std::min(step_left_, n);
  if (!ok || done < n) step_left_ = 0;  // failed (HALTED): the last good state is the answer
  if (step_left_ == 0) end_step();
  return done;
}

void Controller::finish_step() {
  while (step_left_ > 0) work(step_left_);
}

void Controller::end_step() {
  step_left_ = step_total_ = 0;
  publish();
}

Controller::Shutdown Controller::shutdown() {
  Shutdown out;
  if (step_left_ > 0) {
    out.step_cut = true;
    out.step_total = step_total_;
    out.step_done = step_total_ - step_left_;
    step_left_ = step_total_ = 0;  // not answered: the bench sees the heartbeat stop
  }
  if (session_.active()) {
    out.safe_status = session_.apply_safe_state(config_.safe_mode);
    out.safe_applied = out.safe_status == LEGSIM_OK;
    if (out.safe_applied) {
      for (Watchdog &w : watchdog_) {
        w.safe = true;
        w.armed = false;
      }
    }
  }
  return out;
}

void Controller::rt_tick(int64_t now_ns) {
  if (state_ != SimState::kRealtime) return;
  for (int k = 0; k < Session::legs(); ++k) {
    const Watchdog &w = watchdog_[k];
    if (w.armed && now_ns - w.last_cmd_ns > static_cast<int64_t>(timeout_ms_) * 1000000)
      trip(k, static_cast<double>(now_ns - w.last_cmd_ns) / 1e6);
  }
  ++rt_ticks_;
  if (!advance(rt_steps_per_tick_, false, nullptr)) {
    publish();  // the last good state, HALTED
    return;
  }
  if (rt_ticks_ % rt_decimation_ == 0) publish();
}

// ---- output ---------------------------------------------------------------------------

uint32_t Controller::status_bits(uint32_t events, int leg) const {
  uint32_t s = status_from_events(events);
  if (session_.active()) s |= kStatusAssembled;
  if (state_ == SimState::kRealtime) s |= kStatusRealtime;
  if (state_ == SimState::kHalted) s |= kStatusHalted;
  for (int k = 0; k < kMaxLegs; ++k) {
    if (leg >= 0 && k != leg) continue;
    if (watchdog_[k].safe) s |= kStatusSafeState;
    if (watchdog_[k].armed) s |= kStatusCmdWatchdog;
  }
  if (fault_since_sample_) s |= kStatusFault;
  if (step_left_ > 0) s |= kStatusStepping;
  return s;
}

void Controller::publish() {
  if (!session_.active()) return;
  Sample s;
  legsim_status st = session_.sample(&s);
  if (st != LEGSIM_OK) legsim_ = st;
  StatusInfo info;
  for (int k = 0; k < kMaxLegs; ++k) info.status[k] = status_bits(s.report.events, k);
  info.state = state_;
  info.legsim = legsim_;
  info.last_fault = last_fault_;
  info.variant = session_.params().variant;
  info.integrator = session_.params().integrator;
  for (int k = 0; k < kMaxLegs; ++k) info.act_seq[k] = act_seq_[k].last;
  info.ctrl_seq = ctrl_seq_.last;
  info.step_ns = session_.params().step_ns;
  // the feet's events (Ct_Events) are the core's since the last clear, below: none is lost
  Frame frames[kMaxSampleFrames];
  const int n = encode_sample(s, info, frames);
  for (int i = 0; i < n; ++i) sink_.send(frames[i]);
  session_.clear_events();
  fault_since_sample_ = false;
}

void Controller::fill_heartbeat(HeartbeatInfo *hb) const {
  hb->state = state_;
  hb->status = status_bits(session_.active() ? session_.events() : 0, -1);
  hb->rx_frames = rx_frames_;
  hb->rx_rejected = rx_rejected_;
  hb->fault_count = fault_count_;
  hb->sim_time = session_.active() ? session_.time() : 0.0;
  hb->rt_ticks = rt_ticks_;
  hb->rt_rate_hz = rt_period_ns_ > 0 ? static_cast<float>(1e9 / rt_period_ns_) : 0.0f;
}

}  // namespace hil
