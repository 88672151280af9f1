// What hil_sim's C++ tests share: the CHECK counters, a FrameSink that keeps frames in
// memory, builders of the CONTROL frames they send, finders of the frames they get back, and
// the run loop's socket in memory with the gaps between the frames it sent (the liveness
// checks of the leg and the hexapod).
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <functional>
#include <string>
#include <vector>

#include <sys/eventfd.h>
#include <time.h>
#include <unistd.h>

#include "can_io.h"
#include "frame.h"
#include "session.h"

extern "C" {
#include "legsim_can.h"
}

namespace hil_test {

// A failed CHECK says where and goes on; report() gives the counts and the exit code.
inline int g_failed = 0, g_passed = 0;
#define CHECK(cond)                                                                  \
  do {                                                                               \
    if (cond) {                                                                      \
      ++hil_test::g_passed;                                                          \
    } else {                                                                         \
      ++hil_test::g_failed;                                                          \
      std::fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
    }                                                                                \
  } while (0)

inline int report() {
  std::printf("%d passed, %d failed\n", g_passed, g_failed);
  return g_failed == 0 ? 0 : 1;
}

// A session the tests cannot go on without: exit with the reason if it does not start.
inline void init_or_exit(hil::Session &session) {
  std::string err;
  if (!session.init(&err)) {
    std::fprintf(stderr, "session init: %s\n", err.c_str());
    std::exit(1);
  }
}

// The controller's output, kept until the test takes it.
class Recorder : public hil::FrameSink {
 public:
  bool send(const hil::Frame &f) override {
    frames.push_back(f);
    return true;
  }
  std::vector<hil::Frame> frames;
  std::vector<hil::Frame> take() {
    std::vector<hil::Frame> out;
    out.swap(frames);
    return out;
  }
};

inline hil::Frame fd_frame(uint32_t id) {
  hil::Frame f;
  f.id = id;
  f.fd = true;
  f.len = 64;
  return f;
}

// A CONTROL message with 1 ms steps, one step per STEP and per real-time tick.
inline legsim_can_control_t control(uint32_t seq, uint8_t command) {
  legsim_can_control_t m;
  legsim_can_control_init(&m);
  m.ctrl_seq = seq;
  m.ctrl_command = command;
  m.ctrl_step_size = 1000000;
  m.ctrl_n_steps = 1;
  m.ctrl_rt_steps_per_tick = 1;
  return m;
}
inline hil::Frame pack(const legsim_can_control_t &m) {
  hil::Frame f = fd_frame(LEGSIM_CAN_CONTROL_FRAME_ID);
  legsim_can_control_pack(f.data, &m, 64);
  return f;
}
inline hil::Frame step(uint32_t seq, uint32_t n) {
  legsim_can_control_t m = control(seq, LEGSIM_CAN_CONTROL_CTRL_COMMAND_STEP_CHOICE);
  m.ctrl_n_steps = n;
  return pack(m);
}

inline const hil::Frame *find(const std::vector<hil::Frame> &v, uint32_t id) {
  for (const auto &f : v)
    if (f.id == id) return &f;
  return nullptr;
}
// The FAULT among v, or an initialised (all-zero) message if there is none.
inline legsim_can_fault_t fault_of(const std::vector<hil::Frame> &v) {
  legsim_can_fault_t m;
  legsim_can_fault_init(&m);
  if (const hil::Frame *f = find(v, LEGSIM_CAN_FAULT_FRAME_ID))
    legsim_can_fault_unpack(&m, f->data, f->len);
  return m;
}

// ---- the run loop on an in-memory socket --------------------------------------------------

inline int64_t mono_ns() {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

// Nanoseconds this thread has spent runnable but waiting for a CPU (the machine's time, not
// the loop's); 0 if not available.
inline int64_t run_delay_ns() {
  long long on_cpu = 0, waited = 0;
  FILE *f = std::fopen("/proc/thread-self/schedstat", "r");
  if (f == nullptr) return 0;
  if (std::fscanf(f, "%lld %lld", &on_cpu, &waited) != 2) waited = 0;
  std::fclose(f);
  return waited;
}

struct Sent {
  int64_t t_ns;
  hil::Frame frame;
  int64_t waited_ns = run_delay_ns();
};

// The socket in memory: frames queued by the test (an eventfd says when some are pending),
// frames sent with the time they left; on_send sees each as it goes.
class MemoryBus : public hil::Bus {
 public:
  MemoryBus() : efd_(eventfd(0, EFD_SEMAPHORE | EFD_NONBLOCK | EFD_CLOEXEC)) {}
  ~MemoryBus() override { ::close(efd_); }
  MemoryBus(const MemoryBus &) = delete;
  MemoryBus &operator=(const MemoryBus &) = delete;
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

// Gaps between consecutive frames of a window (its ends and the heartbeats between): the
// largest as seen on the clock, and the largest less the time spent waiting for a CPU.
struct Gaps {
  double wall_ms = 0, own_ms = 0, waited_ms = 0;  // waited: in the gap with the largest wall
  size_t heartbeats = 0;
};
inline Gaps gaps(const std::vector<Sent> &w) {
  Gaps g;
  g.heartbeats = w.size() >= 2 ? w.size() - 2 : 0;
  for (size_t i = 1; i < w.size(); ++i) {
    const double wall = (w[i].t_ns - w[i - 1].t_ns) / 1e6;
    const double waited = (w[i].waited_ns - w[i - 1].waited_ns) / 1e6;
    if (wall > g.wall_ms) {
      g.wall_ms = wall;
      g.waited_ms = waited;
    }
    g.own_ms = std::max(g.own_ms, wall - waited);
  }
  return g;
}
inline void print_gaps(const char *what, const Gaps &g, double secs) {
  std::printf("%s (%.2f s): %zu heartbeats, max gap %.1f ms (%.1f ms of it waiting for a CPU), "
              "max gap less CPU waits %.1f ms\n",
              what, secs, g.heartbeats, g.wall_ms, g.waited_ms, g.own_ms);
}

}  // namespace hil_test
