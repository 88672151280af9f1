// hil_sim's protocol and controller against the real core, with frames in memory (no CAN):
// validation faults, "a bad frame changes nothing", the command timeout, determinism,
// solver failures, a STEP worked in slices (same frames whatever the slicing, cut short by a
// shutdown at a whole step), and a fuzz run that must not crash.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "controller.h"
#include "protocol.h"
#include "session.h"
#include "test_support.hpp"

extern "C" {
#include "legsim_can.h"
#include "legsim_can_layout.h"
}

namespace {

using namespace hil_test;

hil::Frame reset(uint32_t seq, int variant = 0, uint8_t act_init = 0) {
  legsim_can_control_t m = control(seq, LEGSIM_CAN_CONTROL_CTRL_COMMAND_RESET_CHOICE);
  m.ctrl_variant = static_cast<uint8_t>(variant);
  m.ctrl_act_init = act_init;
  return pack(m);
}
hil::Frame act(uint32_t seq, uint8_t mode_u, float sp_u, uint8_t mode_l = 0, float sp_l = 0) {
  legsim_can_act_cmd_t m;
  legsim_can_act_cmd_init(&m);
  m.act_seq = seq;
  m.act_mode_upper = mode_u;
  m.act_setpoint_upper = sp_u;
  m.act_mode_lower = mode_l;
  m.act_setpoint_lower = sp_l;
  hil::Frame f = fd_frame(LEGSIM_CAN_ACT_CMD_FRAME_ID);
  legsim_can_act_cmd_pack(f.data, &m, 64);
  return f;
}

int count(const std::vector<hil::Frame> &v, uint32_t id) {
  int n = 0;
  for (const auto &f : v) n += f.id == id;
  return n;
}
legsim_can_st_status_t status_of(const std::vector<hil::Frame> &v) {
  legsim_can_st_status_t m;
  legsim_can_st_status_init(&m);
  if (const hil::Frame *f = find(v, LEGSIM_CAN_ST_STATUS_FRAME_ID))
    legsim_can_st_status_unpack(&m, f->data, f->len);
  return m;
}
// The five state frames but ST_STATUS: the physics, byte for byte.
std::vector<uint8_t> physics(const std::vector<hil::Frame> &v) {
  std::vector<uint8_t> out;
  for (const auto &f : v)
    if (f.id >= LEGSIM_CAN_ST_POS_FRAME_ID && f.id < LEGSIM_CAN_ST_STATUS_FRAME_ID)
      out.insert(out.end(), f.data, f.data + f.len);
  return out;
}

struct Rig {
  hil::Session session;
  Recorder rec;
  hil::Controller ctl;
  explicit Rig(hil::ControllerConfig cfg = {}) : ctl(session, rec, cfg) {
    init_or_exit(session);
  }
  // The frame, and the STEP it starts worked to its end in one go.
  std::vector<hil::Frame> feed(const hil::Frame &f, int64_t now_ns = 0) {
    ctl.on_frame(f, now_ns);
    ctl.finish_step();
    return rec.take();
  }
};

void test_reset_and_step() {
  Rig r;
  auto out = r.feed(reset(7));
  CHECK(out.size() == 6);
  CHECK(out.back().id == LEGSIM_CAN_ST_STATUS_FRAME_ID);
  auto st = status_of(out);
  CHECK(st.st_state == LEGSIM_CAN_ST_STATUS_ST_STATE_LOCKSTEP_CHOICE);
  CHECK(st.st_step_count == 0);
  CHECK(st.st_ctrl_seq == 7);
  CHECK(st.st_status & hil::kStatusAssembled);
  CHECK(st.st_residual < 1e-6f);
  out = r.feed(step(8, 25));
  st = status_of(out);
  CHECK(out.size() == 6);
  CHECK(st.st_step_count == 25);
  CHECK(st.st_tick == 25);
  CHECK(std::fabs(st.st_time - 0.025) < 1e-12);
  CHECK(st.st_ctrl_seq == 8);
  CHECK(st.st_step_size == 1000000);
}

void test_bad_frames_fault_and_change_nothing() {
  Rig good, bad;
  good.feed(reset(1));
  bad.feed(reset(1));
  good.feed(act(1, 2, 0.60f));
  bad.feed(act(1, 2, 0.60f));

  struct Case {
    const char *what;
    hil::Frame frame;
    uint8_t code;
    uint32_t detail;
  };
  hil::Frame unknown = fd_frame(0x123);
  hil::Frame classic = act(2, 1, 10.0f);
  classic.fd = false;
  classic.len = 8;
  hil::Frame short_fd = act(2, 1, 10.0f);
  short_fd.len = 48;
  hil::Frame ext = act(2, 1, 10.0f);
  ext.extended = true;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  legsim_can_control_t bad_cmd = control(2, 9);
  Case cases[] = {
      {"unknown id", unknown, 1, 0},
      {"classic frame", classic, 2, 64},
      {"48-byte FD frame", short_fd, 2, 64},
      {"extended id", ext, 1, 1},
      {"NaN setpoint", act(2, 1, nan), 3, LEGSIM_CAN_ACT_CMD_ACT_SETPOINT_UPPER_START_BIT},
      {"Inf setpoint", act(2, 0, 0, 1, inf), 3, LEGSIM_CAN_ACT_CMD_ACT_SETPOINT_LOWER_START_BIT},
      {"length above stroke", act(2, 2, 0.95f), 4, LEGSIM_CAN_ACT_CMD_ACT_SETPOINT_UPPER_START_BIT},
      {"length below stroke", act(2, 0, 0, 2, 0.20f), 4,
       LEGSIM_CAN_ACT_CMD_ACT_SETPOINT_LOWER_START_BIT},
      {"force above max", act(2, 1, 1600.0f), 4, LEGSIM_CAN_ACT_CMD_ACT_SETPOINT_UPPER_START_BIT},
      {"mode 3", act(2, 3, 0.0f), 4, LEGSIM_CAN_ACT_CMD_ACT_MODE_UPPER_START_BIT},
      {"stale ACT_CMD counter", act(1, 2, 0.70f), 5, 1},
      {"stale CONTROL counter", step(1, 5), 5, 1},
      {"command 9", pack(bad_cmd), 4, LEGSIM_CAN_CONTROL_CTRL_COMMAND_START_BIT},
  };
  for (const Case &c : cases) {
    auto out = bad.feed(c.frame);
    auto f = fault_of(out);
    bool ok = out.size() == 1 && f.fault_code == c.code && f.fault_detail == c.detail;
    if (!ok)
      std::fprintf(stderr, "  case '%s': %zu frames, code %u detail %u\n", c.what, out.size(),
                   f.fault_code, f.fault_detail);
    CHECK(ok);
  }
  auto fo = fault_of(bad.feed(act(1, 2, 0.70f)));
  CHECK(fo.fault_seq == 1 && fo.fault_frame_id == LEGSIM_CAN_ACT_CMD_FRAME_ID);
  fo = fault_of(bad.feed(act(2, 2, 0.95f)));
  CHECK(std::fabs(fo.fault_value - 0.95f) < 1e-6f && fo.fault_frame_len == 64);

  // the physics after the bad frames is that of the run without them, byte for byte
  auto g = good.feed(step(2, 40));
  auto b = bad.feed(step(2, 40));
  CHECK(physics(g) == physics(b));
  CHECK(!physics(g).empty());
  auto sb = status_of(b);
  CHECK(sb.st_act_seq == 1);
  CHECK(sb.st_step_count == 40);
  CHECK(sb.st_last_fault != 0);
  CHECK(sb.st_status & hil::kStatusFault);
  CHECK(status_of(bad.feed(step(3, 1))).st_status == status_of(good.feed(step(3, 1))).st_status);
  // STEP 0: no step; the state answered as it is (the leg has no contact modes to check)
  auto z = good.feed(step(4, 0));
  CHECK(fault_of(z).fault_code == 0 && !physics(z).empty());
  CHECK(status_of(z).st_step_count == 41);
  CHECK(physics(z) == physics(good.feed(step(5, 0))));
}

void test_state_rules() {
  Rig r;
  auto f = fault_of(r.feed(act(1, 1, 0.0f)));
  CHECK(f.fault_code == 6 && f.fault_detail == 0);  // BAD_STATE, IDLE
  f = fault_of(r.feed(step(1, 1)));
  CHECK(f.fault_code == 6);
  r.feed(reset(5));
  // STEP in real time is refused; STOP_RT answers with a sample
  auto out = r.feed(pack(control(6, LEGSIM_CAN_CONTROL_CTRL_COMMAND_START_RT_CHOICE)), 1000);
  CHECK(out.size() == 6);
  CHECK(r.ctl.state() == hil::SimState::kRealtime);
  CHECK(r.ctl.rt_period_ns() == 1000000);
  f = fault_of(r.feed(step(7, 1)));
  CHECK(f.fault_code == 6 && f.fault_detail == 2);
  r.ctl.rt_tick(2000000);
  r.ctl.rt_tick(3000000);
  out = r.feed(pack(control(8, LEGSIM_CAN_CONTROL_CTRL_COMMAND_STOP_RT_CHOICE)));
  CHECK(status_of(out).st_step_count == 2);
  CHECK(r.ctl.state() == hil::SimState::kLockstep);
  // a RESET with any counter starts the count anew
  out = r.feed(reset(1));
  CHECK(out.size() == 6 && status_of(out).st_ctrl_seq == 1);
  CHECK(r.feed(act(0, 1, 5.0f)).empty());
}

void test_timeout_lockstep() {
  Rig r;  // default: 100 ms, zero force
  r.feed(reset(1, 0, 1));
  CHECK(r.feed(act(1, 2, 0.62f)).empty());
  auto out = r.feed(step(2, 100));  // exactly the timeout: not yet
  CHECK(count(out, LEGSIM_CAN_FAULT_FRAME_ID) == 0);
  CHECK(status_of(out).st_status & hil::kStatusCmdWatchdog);
  out = r.feed(step(3, 50));
  CHECK(count(out, LEGSIM_CAN_FAULT_FRAME_ID) == 1);
  auto f = fault_of(out);
  CHECK(f.fault_code == 7 && f.fault_detail == 100 && f.fault_step_count == 100);
  CHECK(f.fault_seq == 1);
  auto st = status_of(out);
  CHECK(st.st_status & hil::kStatusSafeState);
  CHECK(!(st.st_status & hil::kStatusCmdWatchdog));
  CHECK(st.st_step_count == 150);
  // safe state: zero force on both actuators
  legsim_can_st_act_t a;
  legsim_can_st_act_unpack(&a, find(out, LEGSIM_CAN_ST_ACT_FRAME_ID)->data, 64);
  CHECK(a.act_upper_force == 0.0f && a.act_lower_force == 0.0f);
  // a new command leaves the safe state
  r.feed(act(2, 2, 0.62f));
  st = status_of(r.feed(step(4, 1)));
  CHECK(!(st.st_status & hil::kStatusSafeState));

  // hold length: the actuators hold where they are
  hil::ControllerConfig cfg;
  cfg.safe_mode = hil::SafeMode::kHoldLength;
  cfg.cmd_timeout_ms = 20;
  Rig h(cfg);
  h.feed(reset(1));
  h.feed(act(1, 1, 50.0f, 1, -50.0f));
  out = h.feed(step(2, 30));
  f = fault_of(out);
  CHECK(f.fault_code == 7 && f.fault_step_count == 20);
  // a RESET with Ctrl_CmdTimeout = 65535 has none
  legsim_can_control_t m = control(3, LEGSIM_CAN_CONTROL_CTRL_COMMAND_RESET_CHOICE);
  m.ctrl_cmd_timeout = 65535;
  h.feed(pack(m));
  h.feed(act(1, 1, 0.0f));
  CHECK(count(h.feed(step(4, 500)), LEGSIM_CAN_FAULT_FRAME_ID) == 0);
}

void test_timeout_realtime() {
  Rig r;
  r.feed(reset(1));
  r.feed(act(1, 1, 0.0f), 0);
  legsim_can_control_t m = control(2, LEGSIM_CAN_CONTROL_CTRL_COMMAND_START_RT_CHOICE);
  m.ctrl_rt_decimation = 1;
  r.feed(pack(m), 0);
  int64_t t = 0;
  int faults = 0;
  for (int i = 0; i < 150; ++i) {
    t += 1000000;
    r.ctl.rt_tick(t);
    auto out = r.rec.take();
    CHECK(count(out, LEGSIM_CAN_ST_STATUS_FRAME_ID) == 1);
    faults += count(out, LEGSIM_CAN_FAULT_FRAME_ID);
    if (i == 99) CHECK(faults == 0);
  }
  CHECK(faults == 1);
}

void test_determinism() {
  std::vector<uint8_t> runs[2];
  for (auto &run : runs) {
    Rig r;
    r.feed(reset(1));
    r.feed(act(1, 2, 0.70f, 2, 0.50f));
    for (uint32_t k = 0; k < 5; ++k) {
      for (const auto &f : r.feed(step(2 + k, 20))) run.insert(run.end(), f.data, f.data + 64);
      r.feed(act(2 + k, 1, 100.0f * k, 0, 0));
    }
  }
  CHECK(!runs[0].empty() && runs[0] == runs[1]);
}

void test_reset_failure_keeps_session() {
  Rig r;
  r.feed(reset(1));
  r.feed(step(2, 10));
  // lengths inside each stroke but an unreachable combination is the core's call; a length
  // outside the stroke is refused before the core sees it
  legsim_can_control_t m = control(3, LEGSIM_CAN_CONTROL_CTRL_COMMAND_RESET_CHOICE);
  m.ctrl_use_lengths = 1;
  m.ctrl_length_upper = 0.81f;
  m.ctrl_length_lower = 0.5f;
  auto f = fault_of(r.feed(pack(m)));
  CHECK(f.fault_code == 4 && f.fault_detail == LEGSIM_CAN_CONTROL_CTRL_LENGTH_UPPER_START_BIT);
  m.ctrl_pose = 1;  // the leg has one pose
  m.ctrl_use_lengths = 0;
  f = fault_of(r.feed(pack(m)));
  CHECK(f.fault_code == 4 && f.fault_detail == LEGSIM_CAN_CONTROL_CTRL_POSE_START_BIT);
  auto st = status_of(r.feed(step(4, 1)));
  CHECK(st.st_step_count == 11);
}

void test_solver_failures() {
  Rig r;
  r.feed(reset(1));
  r.feed(step(2, 10));
  // lengths inside both strokes that the leg cannot take at once: the core refuses the
  // assembly, the running session goes on untouched
  legsim_can_control_t m = control(3, LEGSIM_CAN_CONTROL_CTRL_COMMAND_RESET_CHOICE);
  m.ctrl_use_lengths = 1;
  m.ctrl_length_upper = 0.80;  // float64 on the bus (0.80f would be 1.2e-8 m past the stroke)
  m.ctrl_length_lower = 0.35;
  auto out = r.feed(pack(m));
  auto f = fault_of(out);
  CHECK(out.size() == 1 && f.fault_code == 8 && f.fault_detail == LEGSIM_ERR_UNREACHABLE);
  CHECK(f.fault_frame_id == LEGSIM_CAN_CONTROL_FRAME_ID && f.fault_seq == 3);
  CHECK(status_of(r.feed(step(4, 1))).st_step_count == 11);

  // generalized-alpha at h = 100 ms: Newton gives up at the second step -> HALTED
  m = control(5, LEGSIM_CAN_CONTROL_CTRL_COMMAND_RESET_CHOICE);
  m.ctrl_integrator = LEGSIM_CAN_CONTROL_CTRL_INTEGRATOR_GENERALIZED_ALPHA_CHOICE;
  m.ctrl_step_size = 100000000;
  r.feed(pack(m));
  out = r.feed(step(6, 10));
  f = fault_of(out);
  auto st = status_of(out);
  CHECK(f.fault_code == 8 && f.fault_detail == LEGSIM_ERR_NOT_CONVERGED && f.fault_seq == 6);
  CHECK(out.size() == 7 && out.back().id == LEGSIM_CAN_ST_STATUS_FRAME_ID);
  CHECK(st.st_state == LEGSIM_CAN_ST_STATUS_ST_STATE_HALTED_CHOICE);
  CHECK(st.st_status & hil::kStatusHalted);
  CHECK(st.st_legsim_status == LEGSIM_ERR_NOT_CONVERGED);
  CHECK(st.st_step_count == f.fault_step_count && st.st_step_count < 10);
  f = fault_of(r.feed(step(7, 1)));
  CHECK(f.fault_code == 6 && f.fault_detail == 3);  // BAD_STATE: HALTED
  f = fault_of(r.feed(act(1, 1, 0.0f)));
  CHECK(f.fault_code == 6);
  out = r.feed(reset(8));
  CHECK(status_of(out).st_state == LEGSIM_CAN_ST_STATUS_ST_STATE_LOCKSTEP_CHOICE);
  CHECK(status_of(out).st_legsim_status == 0 && status_of(out).st_last_fault == 0);

  // the same in real time: the tick publishes the last good state, HALTED
  r.feed(pack(m));
  r.feed(pack(control(9, LEGSIM_CAN_CONTROL_CTRL_COMMAND_START_RT_CHOICE)));
  CHECK(r.ctl.rt_period_ns() == 100000000);
  int faults = 0;
  for (int i = 0; i < 5; ++i) {
    r.ctl.rt_tick(i * 100000000LL);
    faults += count(r.rec.take(), LEGSIM_CAN_FAULT_FRAME_ID);
  }
  CHECK(faults == 1 && r.ctl.state() == hil::SimState::kHalted);
}

void test_events_in_status() {
  Rig r;
  legsim_can_control_t m = control(1, LEGSIM_CAN_CONTROL_CTRL_COMMAND_RESET_CHOICE);
  m.ctrl_cmd_timeout = 65535;  // no timeout: the commands hold for the whole run
  r.feed(pack(m));
  // a length far from the current one saturates the upper servo; full force retracts the
  // lower actuator to its shortest length
  r.feed(act(1, 2, 0.80f, 1, -1500.0f));
  auto st = status_of(r.feed(step(2, 20)));
  CHECK(st.st_status & hil::kStatusForceSaturated);
  uint16_t seen = 0;
  uint8_t mask = 0;
  for (uint32_t k = 0; k < 50; ++k) {
    st = status_of(r.feed(step(3 + k, 20)));
    seen |= st.st_status;
    mask |= st.st_stroke_mask;
  }
  CHECK(seen & hil::kStatusStrokeMin);
  CHECK(mask & 2u);  // the lower actuator
  // events are cleared after each sample: a quiet step reports none
  r.feed(act(2, 1, 0.0f, 1, 0.0f));
  r.feed(reset(60));
  st = status_of(r.feed(step(61, 1)));
  CHECK(!(st.st_status & (hil::kStatusStrokeMax | hil::kStatusStrokeMin | hil::kStatusForceSaturated)));
}

// A scene with a command timeout that trips in the middle of a STEP, a load, a STEP
// ending exactly at the timeout, and a STEP on which Newton gives up (HALTED). slice = 0:
// every STEP in one go; else slice steps per work() call. Every frame sent, in order.
std::vector<hil::Frame> sliced_scene(uint64_t slice) {
  Rig r;
  std::vector<hil::Frame> all;
  auto run = [&](const hil::Frame &f) {
    r.ctl.on_frame(f, 0);
    if (slice == 0) {
      r.ctl.finish_step();
    } else {
      while (r.ctl.stepping()) {
        const uint64_t left = r.ctl.step_left();
        const uint64_t done = r.ctl.work(slice);
        // a sample goes out only with the STEP's last step
        CHECK(done <= slice && (r.ctl.stepping() == (count(r.rec.frames, LEGSIM_CAN_ST_STATUS_FRAME_ID) == 0)));
        if (r.ctl.stepping()) CHECK(r.ctl.step_left() == left - done);
        hil::HeartbeatInfo hb;
        r.ctl.fill_heartbeat(&hb);
        CHECK(((hb.status & hil::kStatusStepping) != 0) == r.ctl.stepping());
      }
    }
    auto out = r.rec.take();
    all.insert(all.end(), out.begin(), out.end());
  };
  run(reset(1, 0, 1));
  run(act(1, 2, 0.62f, 1, 40.0f));
  run(step(2, 250));  // the 100 ms timeout trips after step 100
  run(act(2, 1, -30.0f));
  legsim_can_load_cmd_t l;
  legsim_can_load_cmd_init(&l);
  l.load_seq = 1;
  l.load_value1 = 20.0f;
  l.load_value2 = -80.0f;
  hil::Frame lf = fd_frame(LEGSIM_CAN_LOAD_CMD_FRAME_ID);
  legsim_can_load_cmd_pack(lf.data, &l, 64);
  run(lf);
  run(step(3, 100));  // ends exactly at the timeout: trips at the next STEP's first step
  run(step(4, 37));
  legsim_can_control_t m = control(5, LEGSIM_CAN_CONTROL_CTRL_COMMAND_RESET_CHOICE);
  m.ctrl_integrator = LEGSIM_CAN_CONTROL_CTRL_INTEGRATOR_GENERALIZED_ALPHA_CHOICE;
  m.ctrl_step_size = 100000000;
  run(pack(m));
  run(step(6, 10));  // Newton gives up at the second step: FAULT, then the HALTED sample
  return all;
}

void test_slicing_changes_nothing() {
  const auto whole = sliced_scene(0);
  CHECK(count(whole, LEGSIM_CAN_FAULT_FRAME_ID) == 3);  // two timeouts, one solver failure
  CHECK(count(whole, LEGSIM_CAN_ST_STATUS_FRAME_ID) == 6);
  for (uint64_t slice : {1u, 7u, 64u, 1000u}) {
    const auto cut = sliced_scene(slice);
    bool same = cut.size() == whole.size();
    for (size_t i = 0; same && i < whole.size(); ++i)
      same = cut[i].id == whole[i].id && std::memcmp(cut[i].data, whole[i].data, 64) == 0;
    CHECK(same);
    if (!same) std::fprintf(stderr, "  slices of %llu steps differ\n", static_cast<unsigned long long>(slice));
  }
}

// A shutdown in the middle of a STEP: the steps done stay done (the state is that of a
// whole number of steps, bit for bit), the STEP is not answered, the actuators are safe.
void test_shutdown_mid_step() {
  Rig r;
  r.feed(reset(1, 0, 1));
  r.feed(act(1, 1, 300.0f, 1, -200.0f));
  r.ctl.on_frame(step(2, 90), 0);
  CHECK(r.ctl.work(33) == 33 && r.ctl.stepping());
  auto sd = r.ctl.shutdown();
  CHECK(sd.step_cut && sd.step_done == 33 && sd.step_total == 90);
  CHECK(sd.safe_applied && sd.safe_status == LEGSIM_OK);
  CHECK(!r.ctl.stepping() && r.rec.take().empty());  // unanswered
  CHECK(r.session.step_count() == 33);
  hil::Sample cut, ref;
  CHECK(r.session.sample(&cut) == LEGSIM_OK);
  Rig q;  // the same 33 steps in one STEP
  q.feed(reset(1, 0, 1));
  q.feed(act(1, 1, 300.0f, 1, -200.0f));
  q.feed(step(2, 33));
  CHECK(q.session.sample(&ref) == LEGSIM_OK);
  CHECK(std::memcmp(cut.q, ref.q, sizeof cut.q) == 0 && std::memcmp(cut.qd, ref.qd, sizeof cut.qd) == 0);
  CHECK(cut.t == ref.t);
  CHECK(cut.force[0] == 0 && cut.force[1] == 0);  // zero-force safe state
  hil::HeartbeatInfo hb;
  r.ctl.fill_heartbeat(&hb);
  CHECK((hb.status & hil::kStatusSafeState) && !(hb.status & hil::kStatusStepping));
  // without a STEP in progress nothing is cut
  Rig idle;
  sd = idle.ctl.shutdown();
  CHECK(!sd.step_cut && !sd.safe_applied);
}

void test_fuzz() {
  Rig r;
  r.feed(reset(1));
  std::mt19937 rng(12345);
  const uint32_t ids[] = {LEGSIM_CAN_CONTROL_FRAME_ID, LEGSIM_CAN_ACT_CMD_FRAME_ID,
                          LEGSIM_CAN_LOAD_CMD_FRAME_ID, LEGSIM_CAN_ST_POS_FRAME_ID, 0x7ff, 0x0};
  size_t frames_out = 0;
  for (int i = 0; i < 20000; ++i) {
    hil::Frame f;
    f.id = ids[rng() % 6];
    f.fd = rng() % 8 != 0;
    f.len = f.fd ? (rng() % 8 ? 64 : 32) : 8;
    f.extended = rng() % 50 == 0;
    for (auto &b : f.data) b = static_cast<uint8_t>(rng());
    // keep steps small so the fuzz stays fast
    if (f.id == LEGSIM_CAN_CONTROL_FRAME_ID && f.data[4] == 2) f.data[14] = f.data[15] = f.data[13] = 0;
    r.ctl.on_frame(f, i * 1000000LL);
    r.ctl.finish_step();
    frames_out += r.rec.take().size();
  }
  CHECK(frames_out > 0);
  CHECK(r.ctl.rx_frames() == 20000 + 1);
  auto out = r.feed(reset(1));
  CHECK(out.size() == 6 && status_of(out).st_state == 1);
}

}  // namespace

int main() {
  test_reset_and_step();
  test_bad_frames_fault_and_change_nothing();
  test_state_rules();
  test_timeout_lockstep();
  test_timeout_realtime();
  test_determinism();
  test_reset_failure_keeps_session();
  test_solver_failures();
  test_events_in_status();
  test_slicing_changes_nothing();
  test_shutdown_mid_step();
  test_fuzz();
  return report();
}
