// The run loop keeps its promises whatever it is asked to do: a HEARTBEAT every 100 ms of
// wall time and an exit within one heartbeat period of SIGTERM, during a long STEP, a
// queue of 100 STEP frames, and a real-time run with a 1 s tick. The real loop
// (run_loop.cpp) and the real core run in real time; only the socket is an in-memory bus
// (an eventfd says when frames are pending), and SIGTERM is a real signal read through a
// signalfd, sent by a POSIX timer at a chosen moment (whatever the loop is doing then) or
// by the bus when the test's last answer goes out.
//
// Tolerance: a heartbeat gap may exceed the 100 ms period by kSlackMs = 50 ms. The loop
// itself adds at most one slice (~1 ms) and one frame's work; the rest is the scheduler of
// a shared machine (2 cores, several builds and tests at once), which can keep a runnable
// process off the CPU for tens of ms. The figures printed are the measured ones.
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <deque>
#include <functional>
#include <string>
#include <vector>

#include <sys/eventfd.h>
#include <sys/signalfd.h>
#include <time.h>
#include <unistd.h>

#include "can_io.h"
#include "controller.h"
#include "protocol.h"
#include "run_loop.h"
#include "session.h"

extern "C" {
#include "legsim_can.h"
}

namespace {

int g_failed = 0, g_passed = 0;
#define CHECK(cond)                                                                  \
  do {                                                                               \
    if (cond) {                                                                      \
      ++g_passed;                                                                    \
    } else {                                                                         \
      ++g_failed;                                                                    \
      std::fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
    }                                                                                \
  } while (0)

constexpr int64_t kPeriodMs = 100;  // hil_sim's default heartbeat
constexpr int64_t kSlackMs = 50;    // see the top of the file

int64_t mono_ns() {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

struct Sent {
  int64_t t_ns;
  hil::Frame frame;
};

// The socket in memory: frames queued by the test, frames sent with the time they left.
class MemoryBus : public hil::Bus {
 public:
  MemoryBus() : efd_(eventfd(0, EFD_SEMAPHORE | EFD_NONBLOCK | EFD_CLOEXEC)) {}
  ~MemoryBus() override { ::close(efd_); }
  void push(const hil::Frame &f) {
    in_.push_back(f);
    uint64_t one = 1;
    if (::write(efd_, &one, sizeof one) != sizeof one) std::perror("eventfd write");
  }
  int fd() const override { return efd_; }
  int receive(hil::Frame *out) override {
    uint64_t v;
    if (in_.empty() || ::read(efd_, &v, sizeof v) != sizeof v) return 0;
    *out = in_.front();
    in_.pop_front();
    return 1;
  }
  bool send(const hil::Frame &f) override {
    sent.push_back({mono_ns(), f});
    if (on_send) on_send(sent.back());
    return true;
  }
  void set_send_block_ms(int) override {}
  uint32_t tx_errors() const override { return 0; }

  std::vector<Sent> sent;
  std::function<void(const Sent &)> on_send;

 private:
  int efd_;
  std::deque<hil::Frame> in_;
};

// ---- frames --------------------------------------------------------------------------

hil::Frame control_frame(const legsim_can_control_t &m) {
  hil::Frame f;
  f.id = LEGSIM_CAN_CONTROL_FRAME_ID;
  f.fd = true;
  f.len = 64;
  legsim_can_control_pack(f.data, &m, 64);
  return f;
}
legsim_can_control_t control(uint32_t seq, uint8_t command) {
  legsim_can_control_t m;
  legsim_can_control_init(&m);
  m.ctrl_seq = seq;
  m.ctrl_command = command;
  m.ctrl_step_size = 1000000;
  m.ctrl_n_steps = 1;
  m.ctrl_rt_steps_per_tick = 1;
  return m;
}
// RESET with zero force and no command timeout: the leg falls freely.
hil::Frame reset(uint32_t seq) {
  legsim_can_control_t m = control(seq, LEGSIM_CAN_CONTROL_CTRL_COMMAND_RESET_CHOICE);
  m.ctrl_cmd_timeout = 65535;
  return control_frame(m);
}
hil::Frame step(uint32_t seq, uint32_t n) {
  legsim_can_control_t m = control(seq, LEGSIM_CAN_CONTROL_CTRL_COMMAND_STEP_CHOICE);
  m.ctrl_n_steps = n;
  return control_frame(m);
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

class Recorder : public hil::FrameSink {
 public:
  bool send(const hil::Frame &f) override {
    frames.push_back(f);
    return true;
  }
  std::vector<hil::Frame> frames;
};

// The controller alone, every STEP in one go: the reference for the loop's answers.
struct Reference {
  hil::Session session;
  Recorder rec;
  hil::Controller ctl{session, rec, hil::ControllerConfig{}};
  Reference() {
    std::string err;
    if (!session.init(&err)) {
      std::fprintf(stderr, "session init: %s\n", err.c_str());
      std::exit(1);
    }
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
    std::string err;
    if (!session.init(&err)) {
      std::fprintf(stderr, "session init: %s\n", err.c_str());
      std::exit(1);
    }
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
  // Heartbeat times (ns) in [from, to].
  std::vector<int64_t> heartbeats(int64_t from, int64_t to) const {
    std::vector<int64_t> t;
    for (const auto &s : bus.sent)
      if (s.frame.id == LEGSIM_CAN_HEARTBEAT_FRAME_ID && s.t_ns >= from && s.t_ns <= to)
        t.push_back(s.t_ns);
    return t;
  }
};

// Largest gap (ms) between heartbeats, counting the window's ends.
double max_gap_ms(const std::vector<int64_t> &t, int64_t from, int64_t to) {
  int64_t prev = from, worst = 0;
  for (int64_t x : t) {
    worst = std::max(worst, x - prev);
    prev = x;
  }
  worst = std::max(worst, to - prev);
  return worst / 1e6;
}

// Seconds per step of the free-falling leg (RK4, h = 1 ms) on this machine now.
double seconds_per_step() {
  Reference r;
  r.feed(reset(1));
  const int64_t t0 = mono_ns();
  r.feed(step(2, 20000));
  return (mono_ns() - t0) / 1e9 / 20000;
}

void block_sigterm() {
  sigset_t mask;
  sigemptyset(&mask);
  sigaddset(&mask, SIGTERM);
  sigprocmask(SIG_BLOCK, &mask, nullptr);
}

// ---- tests ---------------------------------------------------------------------------

// One STEP of about 1.5 s: heartbeats all along, saying STEPPING with the simulated time
// moving on; the answer is bit-identical to the same STEP worked in one go.
void test_long_step(double s_per_step) {
  const uint32_t n = static_cast<uint32_t>(std::clamp(1.5 / s_per_step, 20000.0, 1e7));
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
  const auto hb = rig.heartbeats(step_begin, step_end);
  const double gap = max_gap_ms(hb, step_begin, step_end);
  const double secs = (step_end - step_begin) / 1e9;
  std::printf("STEP %u (%.2f s): %zu heartbeats, max gap %.1f ms (period %lld ms)\n", n, secs,
              hb.size(), gap, static_cast<long long>(kPeriodMs));
  CHECK(gap <= kPeriodMs + kSlackMs);
  CHECK(hb.size() >= static_cast<size_t>(secs * 1000 / kPeriodMs) - 1);
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
  CHECK(stepping >= static_cast<int>(hb.size()) - 1 && stepping > 0);
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

// RESET and 100 STEP frames queued at once, each STEP about 15 ms: heartbeats all along,
// every STEP answered in order, the last answer bit-identical to the reference's.
void test_step_queue(double s_per_step) {
  const uint32_t m = static_cast<uint32_t>(std::clamp(0.015 / s_per_step, 30.0, 1e6));
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
  const auto hb = rig.heartbeats(t0, end);
  const double gap = max_gap_ms(hb, t0, end);
  std::printf("queue of %u STEP %u frames (%.2f s): %zu heartbeats, max gap %.1f ms\n", kFrames, m,
              (end - t0) / 1e9, hb.size(), gap);
  CHECK(gap <= kPeriodMs + kSlackMs);
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
  int busy = 0;
  for (const auto &s : rig.bus.sent)
    busy += s.frame.id == LEGSIM_CAN_HEARTBEAT_FRAME_ID && s.t_ns > step_begin &&
            (heartbeat_of(s.frame).hb_status & hil::kStatusStepping);
  CHECK(busy >= 2);  // the STEP's heartbeats before the signal
  const double exit_ms = (mono_ns() - rig.kill_ns) / 1e6;
  const auto &sd = res.shutdown;
  std::printf("SIGTERM during STEP %u: loop ended %.2f ms after the signal, after %llu steps\n", n,
              exit_ms, static_cast<unsigned long long>(sd.step_done));
  CHECK(rig.kill_ns > 0 && res.signal == SIGTERM);
  CHECK(exit_ms <= kPeriodMs);
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
  rig.bus.push(control_frame(m));
  m = control(2, LEGSIM_CAN_CONTROL_CTRL_COMMAND_START_RT_CHOICE);
  m.ctrl_rt_steps_per_tick = 100;  // one tick per second
  m.ctrl_rt_decimation = 1;
  rig.bus.push(control_frame(m));
  int64_t rt_begin = 0;
  rig.bus.on_send = [&](const Sent &s) {
    if (is_status(s.frame, 2) && rt_begin == 0) {
      rt_begin = s.t_ns;
      rig.terminate_at(rt_begin + 2550000000LL);
    }
  };
  hil::LoopResult res = rig.run();
  const int64_t end = mono_ns();
  const double exit_ms = (end - rig.kill_ns) / 1e6;
  const auto hb = rig.heartbeats(rt_begin, rig.kill_ns);
  const double gap = max_gap_ms(hb, rt_begin, rig.kill_ns);
  int ticks = 0;
  for (const auto &f : rig.frames()) ticks += is_status(f, 2);
  std::printf("real time, 1 s ticks: %d samples, %zu heartbeats in %.2f s, max gap %.1f ms; "
              "exit %.2f ms after SIGTERM\n",
              ticks, hb.size(), (rig.kill_ns - rt_begin) / 1e9, gap, exit_ms);
  CHECK(res.signal == SIGTERM && rig.ctl.state() == hil::SimState::kRealtime);
  CHECK(ticks >= 3);  // START_RT's sample and the ticks at 1 s and 2 s
  CHECK(gap <= kPeriodMs + kSlackMs);
  CHECK(exit_ms <= kPeriodMs);
}

}  // namespace

int main() {
  block_sigterm();  // SIGTERM arrives through the loop's signalfd, as in hil_sim
  const double sps = seconds_per_step();
  std::printf("%.2f us per step here\n", sps * 1e6);
  test_long_step(sps);
  test_step_queue(sps);
  test_sigterm_mid_step();
  test_realtime_long_tick();
  std::printf("%d passed, %d failed\n", g_passed, g_failed);
  return g_failed == 0 ? 0 : 1;
}
