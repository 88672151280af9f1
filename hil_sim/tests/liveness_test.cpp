// The run loop keeps its promises whatever it is asked to do: a HEARTBEAT every 100 ms of
// wall time and an exit within one heartbeat period of SIGTERM, during a long STEP, a
// queue of 100 STEP frames, and a real-time run with a 1 s tick. The real loop
// (run_loop.cpp) and the real core run in real time; only the socket is an in-memory bus
// (an eventfd says when frames are pending), and SIGTERM is a real signal read through a
// signalfd, sent by a POSIX timer at a chosen moment (whatever the loop is doing then) or
// by the bus when the test's last answer goes out.
//
// Tolerance: a heartbeat gap may exceed the 100 ms period by kSlackMs = 200 ms, not counting
// the time the loop's thread spent runnable but waiting for a CPU (its run_delay in
// /proc/thread-self/schedstat): that time is the machine's, not the loop's. On a shared
// machine (2 cores, several builds and tests at once, CPU pressure ~90 %) a runnable
// process waited up to 123 ms in one gap (wall 155 ms). The loop itself adds at most one
// slice (~1 ms) and one frame's work. The work asked for is sized in CPU time (0.6 s for
// the long STEP, 100 x 6 ms for the queue), so a loop that kept silent during it would show
// a gap of at least 600 ms (resp. ~6 ms per frame times the frames per wake-up) of its own
// time however loaded the machine is, and a queue worked without heartbeats would show
// 64 frames x 6 ms = 384 ms: both stay beyond period + slack (300 ms), while the slack
// absorbs what the run_delay accounting misses on a loaded machine (a 155 ms wall gap was
// seen once with 50 ms of slack). The figures printed give both.
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include <sys/signalfd.h>
#include <time.h>
#include <unistd.h>

#include "can_io.h"
#include "controller.h"
#include "protocol.h"
#include "run_loop.h"
#include "session.h"
#include "test_support.hpp"

extern "C" {
#include "legsim_can.h"
}

namespace {

using namespace hil_test;

constexpr int64_t kPeriodMs = 100;  // hil_sim's default heartbeat
constexpr int64_t kSlackMs = 200;   // see the top of the file

// ---- frames --------------------------------------------------------------------------

// RESET with zero force and no command timeout: the leg falls freely.
hil::Frame reset(uint32_t seq) {
  legsim_can_control_t m = control(seq, LEGSIM_CAN_CONTROL_CTRL_COMMAND_RESET_CHOICE);
  m.ctrl_cmd_timeout = 65535;
  return pack(m);
}

bool is_status(const hil::Frame &f, uint32_t ctrl_seq) {
  if (f.id != LEGSIM_CAN_ST_STATUS_FRAME_ID) return false;
  legsim_can_st_status_t s;
  legsim_can_st_status_unpack(&s, f.data, f.len);
  return s.st_ctrl_seq == ctrl_seq;
}
legsim_can_heartbeat_t heartbeat_of(const hil::Frame &f) {
  legsim_can_heartbeat_t h;
  legsim_can_heartbeat_unpack(&h, f.data, f.len);
  return h;
}

// The sample frames answering CONTROL counter ctrl_seq (the six frames up to its ST_STATUS).
std::vector<hil::Frame> sample_of(const std::vector<hil::Frame> &frames, uint32_t ctrl_seq) {
  for (size_t i = 0; i < frames.size(); ++i)
    if (is_status(frames[i], ctrl_seq) && i + 1 >= hil::kSampleFrames)
      return std::vector<hil::Frame>(frames.begin() + (i + 1 - hil::kSampleFrames),
                                     frames.begin() + i + 1);
  return {};
}
bool same_frames(const std::vector<hil::Frame> &a, const std::vector<hil::Frame> &b) {
  if (a.size() != b.size() || a.empty()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (a[i].id != b[i].id || std::memcmp(a[i].data, b[i].data, 64) != 0) return false;
  return true;
}

// ---- rigs ----------------------------------------------------------------------------

// The controller alone, every STEP in one go: the reference for the loop's answers.
struct Reference {
  hil::Session session;
  Recorder rec;
  hil::Controller ctl{session, rec, hil::ControllerConfig{}};
  Reference() {
    init_or_exit(session);
  }
  void feed(const hil::Frame &f) {
    ctl.on_frame(f, 0);
    ctl.finish_step();
  }
};

// The loop on a memory bus, with the signalfd the real hil_sim uses.
struct LoopRig {
  hil::Session session;
  MemoryBus bus;
  hil::Controller ctl{session, bus, hil::ControllerConfig{}};
  hil::JitterStats stats;
  int sfd = -1;
  int64_t kill_ns = 0;
  LoopRig() {
    init_or_exit(session);
    sigset_t mask;
    sigemptyset(&mask);
    sigaddset(&mask, SIGTERM);
    sfd = signalfd(-1, &mask, SFD_NONBLOCK | SFD_CLOEXEC);
  }
  ~LoopRig() {
    if (timer_armed) timer_delete(timer);
    ::close(sfd);
  }
  void terminate() {  // SIGTERM to this process now, as `kill` would send it
    if (kill_ns == 0) {
      kill_ns = mono_ns();
      ::kill(::getpid(), SIGTERM);
    }
  }
  // SIGTERM at t_ns (CLOCK_MONOTONIC), from a timer: it lands wherever the loop then is.
  void terminate_at(int64_t t_ns) {
    if (timer_armed) return;
    struct sigevent sev;
    std::memset(&sev, 0, sizeof sev);
    sev.sigev_notify = SIGEV_SIGNAL;
    sev.sigev_signo = SIGTERM;
    if (timer_create(CLOCK_MONOTONIC, &sev, &timer) != 0) {
      std::perror("timer_create");
      std::exit(1);
    }
    timer_armed = true;
    struct itimerspec its;
    std::memset(&its, 0, sizeof its);
    its.it_value.tv_sec = t_ns / 1000000000;
    its.it_value.tv_nsec = t_ns % 1000000000;
    timer_settime(timer, TIMER_ABSTIME, &its, nullptr);
    kill_ns = t_ns;
  }
  timer_t timer{};
  bool timer_armed = false;
  // Time spent waiting for a CPU since the last frame sent before the signal (an upper
  // bound of the waits since the signal).
  double waited_since_kill_ms() const {
    int64_t at = 0;
    for (const auto &s : bus.sent)
      if (s.t_ns <= kill_ns) at = s.waited_ns;
    return (run_delay_ns() - at) / 1e6;
  }
  hil::LoopResult run() {
    hil::LoopConfig cfg;
    cfg.heartbeat_ms = kPeriodMs;
    return hil::run_loop(bus, ctl, sfd, cfg, &stats);
  }
  std::vector<hil::Frame> frames() const {
    std::vector<hil::Frame> out;
    for (const auto &s : bus.sent) out.push_back(s.frame);
    return out;
  }
  // The frames sent from the first matching `first` to the first matching `last` after
  // it, both included, keeping only those two and the heartbeats between.
  std::vector<Sent> window(const std::function<bool(const Sent &)> &first,
                           const std::function<bool(const Sent &)> &last) const {
    std::vector<Sent> out;
    for (const auto &s : bus.sent) {
      if (out.empty()) {
        if (first(s)) out.push_back(s);
      } else if (last(s)) {
        out.push_back(s);
        return out;
      } else if (s.frame.id == LEGSIM_CAN_HEARTBEAT_FRAME_ID) {
        out.push_back(s);
      }
    }
    out.clear();
    return out;
  }
};

int64_t process_cpu_ns() {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

// CPU seconds per step of the free-falling leg (RK4, h = 1 ms) on this machine.
double seconds_per_step() {
  Reference r;
  r.feed(reset(1));
  const int64_t t0 = process_cpu_ns();
  r.feed(step(2, 20000));
  return (process_cpu_ns() - t0) / 1e9 / 20000;
}

void block_sigterm() {
  sigset_t mask;
  sigemptyset(&mask);
  sigaddset(&mask, SIGTERM);
  sigprocmask(SIG_BLOCK, &mask, nullptr);
}

// ---- tests ---------------------------------------------------------------------------

// One STEP of 0.6 s of CPU work: heartbeats all along, saying STEPPING with the simulated
// time moving on; the answer is bit-identical to the same STEP worked in one go.
void test_long_step(double s_per_step) {
  const uint32_t n = static_cast<uint32_t>(std::clamp(0.6 / s_per_step, 20000.0, 1e7));
  LoopRig rig;
  rig.bus.push(reset(1));
  rig.bus.push(step(2, n));
  int64_t step_end = 0;
  rig.bus.on_send = [&](const Sent &s) {
    if (is_status(s.frame, 2)) {
      step_end = s.t_ns;
      rig.terminate();
    }
  };
  const int64_t t0 = mono_ns();
  hil::LoopResult res = rig.run();
  CHECK(res.signal == SIGTERM && !res.shutdown.step_cut);

  // the STEP began when the RESET's sample went out
  int64_t step_begin = 0;
  for (const auto &s : rig.bus.sent)
    if (is_status(s.frame, 1)) step_begin = s.t_ns;
  CHECK(step_begin > t0 && step_end > step_begin);
  const Gaps g = gaps(rig.window([](const Sent &s) { return is_status(s.frame, 1); },
                                 [](const Sent &s) { return is_status(s.frame, 2); }));
  const double secs = (step_end - step_begin) / 1e9;
  char what[64];
  std::snprintf(what, sizeof what, "STEP %u", n);
  print_gaps(what, g, secs);
  CHECK(g.heartbeats >= 5 && g.own_ms <= kPeriodMs + kSlackMs);
  // during the STEP: LOCKSTEP and STEPPING, the simulated time going forward
  double last_t = -1;
  int stepping = 0;
  for (const auto &s : rig.bus.sent) {
    if (s.frame.id != LEGSIM_CAN_HEARTBEAT_FRAME_ID || s.t_ns <= step_begin || s.t_ns >= step_end)
      continue;
    auto h = heartbeat_of(s.frame);
    CHECK(h.hb_state == LEGSIM_CAN_HEARTBEAT_HB_STATE_LOCKSTEP_CHOICE);
    if (h.hb_status & hil::kStatusStepping) ++stepping;
    CHECK(h.hb_sim_time > last_t && h.hb_sim_time < n * 1e-3);
    last_t = h.hb_sim_time;
  }
  CHECK(stepping >= static_cast<int>(g.heartbeats) - 1 && stepping > 0);
  // after it: no STEPPING bit in the sample
  legsim_can_st_status_t st;
  auto got = sample_of(rig.frames(), 2);
  CHECK(!got.empty());
  if (!got.empty()) {
    legsim_can_st_status_unpack(&st, got.back().data, 64);
    CHECK(st.st_step_count == n && !(st.st_status & hil::kStatusStepping));
  }
  Reference ref;
  ref.feed(reset(1));
  ref.feed(step(2, n));
  CHECK(same_frames(got, sample_of(ref.rec.frames, 2)));
}

// RESET and 100 STEP frames queued at once, each STEP 6 ms of CPU work: heartbeats all
// along, every STEP answered in order, the last answer bit-identical to the reference's.
void test_step_queue(double s_per_step) {
  const uint32_t m = static_cast<uint32_t>(std::clamp(0.006 / s_per_step, 30.0, 1e6));
  constexpr uint32_t kFrames = 100;
  LoopRig rig;
  Reference ref;
  rig.bus.push(reset(1));
  ref.feed(reset(1));
  for (uint32_t k = 0; k < kFrames; ++k) {
    rig.bus.push(step(2 + k, m));
    ref.feed(step(2 + k, m));
  }
  const uint32_t last = 1 + kFrames;
  int64_t end = 0;
  rig.bus.on_send = [&](const Sent &s) {
    if (is_status(s.frame, last)) {
      end = s.t_ns;
      rig.terminate();
    }
  };
  const int64_t t0 = mono_ns();
  hil::LoopResult res = rig.run();
  CHECK(res.signal == SIGTERM && end > t0);
  const Gaps g = gaps(rig.window([](const Sent &s) { return s.frame.id == LEGSIM_CAN_HEARTBEAT_FRAME_ID; },
                                 [&](const Sent &s) { return is_status(s.frame, last); }));
  char what[64];
  std::snprintf(what, sizeof what, "queue of %u STEP %u frames", kFrames, m);
  print_gaps(what, g, (end - t0) / 1e9);
  CHECK(g.heartbeats > 0 && g.own_ms <= kPeriodMs + kSlackMs);
  // every STEP answered, in order, after exactly its steps
  uint32_t next = 1;
  bool in_order = true;
  for (const auto &f : rig.frames()) {
    if (f.id != LEGSIM_CAN_ST_STATUS_FRAME_ID) continue;
    legsim_can_st_status_t st;
    legsim_can_st_status_unpack(&st, f.data, 64);
    in_order = in_order && st.st_ctrl_seq == next && st.st_step_count == uint64_t(next - 1) * m;
    ++next;
  }
  CHECK(in_order && next == last + 1);
  CHECK(same_frames(sample_of(rig.frames(), last), sample_of(ref.rec.frames, last)));
}

// SIGTERM 350 ms into the longest STEP the DBC allows: the loop ends within one heartbeat
// period, the STEP unanswered, the session at a whole step (bit-identical to a STEP of
// that many steps) with the actuators in the safe state (zero force).
void test_sigterm_mid_step() {
  constexpr uint32_t n = 10000000;
  LoopRig rig;
  rig.bus.push(reset(1));
  rig.bus.push(step(2, n));
  int64_t step_begin = 0;
  rig.bus.on_send = [&](const Sent &s) {
    if (is_status(s.frame, 1)) {
      step_begin = s.t_ns;
      rig.terminate_at(s.t_ns + 350000000);
    }
  };
  hil::LoopResult res = rig.run();
  const double exit_ms = (mono_ns() - rig.kill_ns) / 1e6;
  const double own_ms = exit_ms - rig.waited_since_kill_ms();
  int busy = 0;
  for (const auto &s : rig.bus.sent)
    busy += s.frame.id == LEGSIM_CAN_HEARTBEAT_FRAME_ID && s.t_ns > step_begin &&
            (heartbeat_of(s.frame).hb_status & hil::kStatusStepping);
  CHECK(busy >= 2);  // the STEP's heartbeats before the signal
  const auto &sd = res.shutdown;
  std::printf("SIGTERM during STEP %u: loop ended %.2f ms after the signal, after %llu steps\n",
              n, exit_ms, static_cast<unsigned long long>(sd.step_done));
  CHECK(rig.kill_ns > 0 && res.signal == SIGTERM);
  CHECK(exit_ms <= kPeriodMs || own_ms <= kPeriodMs);
  CHECK(sd.step_cut && sd.step_total == n && sd.step_done > 0 && sd.step_done < n);
  CHECK(sd.safe_applied && sd.safe_status == LEGSIM_OK);
  CHECK(rig.session.step_count() == sd.step_done);
  CHECK(sample_of(rig.frames(), 2).empty());  // not answered
  hil::Sample cut, want;
  CHECK(rig.session.sample(&cut) == LEGSIM_OK);
  CHECK(cut.force[0] == 0 && cut.force[1] == 0);
  Reference ref;
  ref.feed(reset(1));
  ref.feed(step(2, static_cast<uint32_t>(sd.step_done)));
  CHECK(ref.session.sample(&want) == LEGSIM_OK);
  CHECK(std::memcmp(cut.q, want.q, sizeof cut.q) == 0 && std::memcmp(cut.qd, want.qd, sizeof cut.qd) == 0);
  CHECK(cut.t == want.t);
}

// Real time with a 1 s tick (100 steps of 10 ms per tick): the sleep between ticks is cut
// for the heartbeat and for signals; SIGTERM 2.55 s in lands in the middle of a sleep.
void test_realtime_long_tick() {
  LoopRig rig;
  legsim_can_control_t m = control(1, LEGSIM_CAN_CONTROL_CTRL_COMMAND_RESET_CHOICE);
  m.ctrl_cmd_timeout = 65535;
  m.ctrl_step_size = 10000000;  // 10 ms
  m.ctrl_disable = 3;           // no gravity, no force elements: the leg rests
  rig.bus.push(pack(m));
  m = control(2, LEGSIM_CAN_CONTROL_CTRL_COMMAND_START_RT_CHOICE);
  m.ctrl_rt_steps_per_tick = 100;  // one tick per second
  m.ctrl_rt_decimation = 1;
  rig.bus.push(pack(m));
  int64_t rt_begin = 0;
  rig.bus.on_send = [&](const Sent &s) {
    if (is_status(s.frame, 2) && rt_begin == 0) {
      rt_begin = s.t_ns;
      rig.terminate_at(rt_begin + 2550000000LL);
    }
  };
  hil::LoopResult res = rig.run();
  const double exit_ms = (mono_ns() - rig.kill_ns) / 1e6;
  const double own_ms = exit_ms - rig.waited_since_kill_ms();
  // from START_RT's sample to the last heartbeat before the signal
  int64_t last_hb = 0;
  for (const auto &s : rig.bus.sent)
    if (s.frame.id == LEGSIM_CAN_HEARTBEAT_FRAME_ID && s.t_ns < rig.kill_ns) last_hb = s.t_ns;
  const Gaps g = gaps(rig.window([](const Sent &s) { return is_status(s.frame, 2); },
                                 [&](const Sent &s) { return s.t_ns == last_hb; }));
  int ticks = 0;
  for (const auto &f : rig.frames()) ticks += is_status(f, 2);
  print_gaps("real time, 1 s ticks", g, (last_hb - rt_begin) / 1e9);
  std::printf("  %d samples; loop ended %.2f ms after SIGTERM\n", ticks, exit_ms);
  CHECK(res.signal == SIGTERM && rig.ctl.state() == hil::SimState::kRealtime);
  CHECK(ticks >= 3);  // START_RT's sample and the ticks at 1 s and 2 s
  CHECK(g.heartbeats >= 20 && g.own_ms <= kPeriodMs + kSlackMs);
  CHECK(exit_ms <= kPeriodMs || own_ms <= kPeriodMs);
}

}  // namespace

int main() {
  block_sigterm();  // SIGTERM arrives through the loop's signalfd, as in hil_sim
  const double sps = seconds_per_step();
  std::printf("%.2f us of CPU per step here\n", sps * 1e6);
  test_long_step(sps);
  test_step_queue(sps);
  test_sigterm_mid_step();
  test_realtime_long_tick();
  return report();
}
