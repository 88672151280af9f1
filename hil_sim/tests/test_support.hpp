// What hil_sim's C++ tests share: the CHECK counters, a FrameSink that keeps frames in
// memory, builders of the CONTROL frames they send, and finders of the frames they get back.
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

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

}  // namespace hil_test
