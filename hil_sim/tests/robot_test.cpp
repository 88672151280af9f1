// hil_sim running the two-leg robot (models/robot.toml, compiled in), frames in memory (no
// CAN): every leg's frames at its ids, in order, with ST_CONTACT per leg and ST_BOX; a
// lockstep STEP gives the state of the C API driven directly, bit for bit (every signal is
// float32 of the solver's double, the time its double); leg 1's commands reach the robot's
// actuators 2-3 and force element 1; bad leg-1 frames get a FAULT and change nothing; a
// leg-1 command to the one-leg hil_sim is an UNKNOWN_ID.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "controller.h"
#include "protocol.h"
#include "session.h"
#include "test_support.hpp"
#include "legsim/models.h"
#include "legsim/robot_models.h"
#include "scene_toml.hpp"  // legsim_host::start_apply: what a START_CMD makes the RESET do


extern "C" {
#include "legsim_can.h"
#include "legsim_can_layout.h"
}

namespace {

using namespace hil_test;

// No command timeout: the runs below are longer than 100 ms (read at RESET only).
legsim_can_control_t untimed(legsim_can_control_t m) {
  m.ctrl_cmd_timeout = 65535;
  return m;
}
hil::Frame reset(uint32_t seq, uint8_t act_init = 1, int variant = 0) {
  legsim_can_control_t m = untimed(control(seq, LEGSIM_CAN_CONTROL_CTRL_COMMAND_RESET_CHOICE));
  m.ctrl_act_init = act_init;
  m.ctrl_variant = static_cast<uint8_t>(variant);
  return pack(m);
}
template <typename Msg>
void fill_act(Msg *m, uint32_t seq, uint8_t mode_u, float sp_u, uint8_t mode_l, float sp_l) {
  std::memset(m, 0, sizeof *m);
  m->act_seq = seq;
  m->act_mode_upper = mode_u;
  m->act_setpoint_upper = sp_u;
  m->act_mode_lower = mode_l;
  m->act_setpoint_lower = sp_l;
}
// ACT_CMD of leg 0 or leg 1 (ACT_CMD_L1)
hil::Frame act(int leg, uint32_t seq, uint8_t mode_u, float sp_u, uint8_t mode_l = 0,
               float sp_l = 0) {
  if (leg == 0) {
    legsim_can_act_cmd_t m;
    fill_act(&m, seq, mode_u, sp_u, mode_l, sp_l);
    hil::Frame f = fd_frame(LEGSIM_CAN_ACT_CMD_FRAME_ID);
    legsim_can_act_cmd_pack(f.data, &m, 64);
    return f;
  }
  legsim_can_act_cmd_l1_t m;
  fill_act(&m, seq, mode_u, sp_u, mode_l, sp_l);
  hil::Frame f = fd_frame(LEGSIM_CAN_ACT_CMD_L1_FRAME_ID);
  legsim_can_act_cmd_l1_pack(f.data, &m, 64);
  return f;
}
hil::Frame load_l1(uint32_t seq, uint8_t index, float fx, float fy) {
  legsim_can_load_cmd_l1_t m;
  std::memset(&m, 0, sizeof m);
  m.load_seq = seq;
  m.load_index = index;
  m.load_value1 = fx;
  m.load_value2 = fy;
  hil::Frame f = fd_frame(LEGSIM_CAN_LOAD_CMD_L1_FRAME_ID);
  legsim_can_load_cmd_l1_pack(f.data, &m, 64);
  return f;
}


struct Rig {
  hil::Session session;
  Recorder rec;
  hil::Controller ctl;
  explicit Rig(const hil::ControllerConfig &cfg = hil::ControllerConfig{})
      : ctl(session, rec, cfg) {
    init_or_exit(session);
  }
  std::vector<hil::Frame> feed(const hil::Frame &f, uint64_t slice = 0) {
    ctl.on_frame(f, 0);
    if (slice > 0)
      while (ctl.stepping()) ctl.work(slice);
    ctl.finish_step();
    return rec.take();
  }
};

bool same_bits(float a, double b) {
  const float fb = static_cast<float>(b);
  return std::memcmp(&a, &fb, sizeof a) == 0;
}

// The robot driven straight through the C API, as hil_sim's RESET builds it: stand pose,
// onto the ground with the feet's midpoint where the pose put them (then the feet in
// free_mask lifted), servos holding.
struct Direct {
  std::vector<unsigned char> storage;
  legsim_sim *sim = nullptr;
  explicit Direct(legsim_contact_law law = LEGSIM_CONTACT_LCP, uint32_t free_mask = 0,
                  const legsim_host::StartState *start = nullptr)
      : storage(legsim_sim_size() + LEGSIM_STORAGE_ALIGN) {
    void *p = storage.data();
    size_t space = storage.size();
    void *aligned = std::align(LEGSIM_STORAGE_ALIGN, legsim_sim_size(), p, space);
    legsim_options opt = legsim_default_options();
    opt.step_s = 0.001;
    opt.contact_law = law;
    CHECK(legsim_init(aligned, space, &legsim_model_robot_revolute, &opt, &sim) == LEGSIM_OK);
    CHECK(legsim_assemble_pose(sim, 0) == LEGSIM_OK);
    legsim_contact c[2];
    CHECK(legsim_contacts(sim, c) == LEGSIM_OK);
    // the robot file's ground is level through the origin: the midpoint is x
    const legsim_real mid = (c[0].position[0] + c[1].position[0]) / 2;
    CHECK(std::fabs(mid) < 1e-9);
    CHECK(legsim_assemble_on_ground(sim, nullptr, mid) == LEGSIM_OK);
    for (int k = 0; k < 2; ++k)
      if ((free_mask >> k) & 1u) CHECK(legsim_set_contact_state(sim, k, LEGSIM_CONTACT_FREE) == LEGSIM_OK);
    std::string why;
    if (start) CHECK(legsim_host::start_apply(sim, legsim_model_robot_revolute, *start, nullptr, 1e-10, why) == LEGSIM_OK);
    legsim_real len[4], rate[4];
    CHECK(legsim_actuator_lengths(sim, len, rate) == LEGSIM_OK);
    for (int a = 0; a < 4; ++a) CHECK(legsim_command_length(sim, a, len[a]) == LEGSIM_OK);
    CHECK(legsim_contacts_check(sim) == LEGSIM_OK);  // as hil_sim's RESET ends
  }
};

// Every signal of a robot sample against the C API's state, bit for bit.
template <typename Pos, typename Vel, typename Act, typename RA, typename RB>
void check_leg(const std::vector<hil::Frame> &out, int leg, const legsim_real *q,
               const legsim_real *qd, const legsim_real *len, const legsim_real *rate,
               const legsim_real *force, const legsim_reaction *r, uint32_t id0,
               int (*upos)(Pos *, const uint8_t *, size_t),
               int (*uvel)(Vel *, const uint8_t *, size_t),
               int (*uact)(Act *, const uint8_t *, size_t), int (*ura)(RA *, const uint8_t *, size_t),
               int (*urb)(RB *, const uint8_t *, size_t)) {
  const hil::Frame *fp = find(out, id0), *fv = find(out, id0 + 1), *fa = find(out, id0 + 2),
                   *fra = find(out, id0 + 3), *frb = find(out, id0 + 4);
  CHECK(fp && fv && fa && fra && frb);
  if (!(fp && fv && fa && fra && frb)) return;
  Pos p;
  Vel v;
  Act a;
  RA ra;
  RB rb;
  upos(&p, fp->data, 64);
  uvel(&v, fv->data, 64);
  uact(&a, fa->data, 64);
  ura(&ra, fra->data, 64);
  urb(&rb, frb->data, 64);
  const int o = 3 * (1 + 6 * leg);
  const float got_q[18] = {p.pos_b1_x, p.pos_b1_y, p.pos_b1_phi, p.pos_b2_x, p.pos_b2_y, p.pos_b2_phi,
                           p.pos_b3_x, p.pos_b3_y, p.pos_b3_phi, p.pos_b4_x, p.pos_b4_y, p.pos_b4_phi,
                           p.pos_b5_x, p.pos_b5_y, p.pos_b5_phi, a.act_b6_x, a.act_b6_y, a.act_b6_phi};
  const float got_qd[18] = {v.vel_b1_vx, v.vel_b1_vy, v.vel_b1_omega, v.vel_b2_vx, v.vel_b2_vy,
                            v.vel_b2_omega, v.vel_b3_vx, v.vel_b3_vy, v.vel_b3_omega, v.vel_b4_vx,
                            v.vel_b4_vy, v.vel_b4_omega, v.vel_b5_vx, v.vel_b5_vy, v.vel_b5_omega,
                            a.act_b6_vx, a.act_b6_vy, a.act_b6_omega};
  bool q_ok = true, qd_ok = true;
  for (int i = 0; i < 18; ++i) {
    q_ok = q_ok && same_bits(got_q[i], q[o + i]);
    qd_ok = qd_ok && same_bits(got_qd[i], qd[o + i]);
  }
  CHECK(q_ok);
  CHECK(qd_ok);
  const int ao = 2 * leg;
  CHECK(same_bits(a.act_upper_length, len[ao]) && same_bits(a.act_lower_length, len[ao + 1]));
  CHECK(same_bits(a.act_upper_rate, rate[ao]) && same_bits(a.act_lower_rate, rate[ao + 1]));
  CHECK(same_bits(a.act_upper_force, force[ao]) && same_bits(a.act_lower_force, force[ao + 1]));
  const legsim_reaction *j = r + 8 * leg;
  const float got_r[24] = {ra.ra_a_fx, ra.ra_a_fy, ra.ra_a_m,
                           ra.ra_upper_actuator_fx, ra.ra_upper_actuator_fy, ra.ra_upper_actuator_m,
                           ra.ra_b_thigh_fx, ra.ra_b_thigh_fy, ra.ra_b_thigh_m,
                           ra.ra_b_lower_fx, ra.ra_b_lower_fy, ra.ra_b_lower_m,
                           ra.ra_c_rod_thigh_fx, ra.ra_c_rod_thigh_fy, ra.ra_c_rod_thigh_m,
                           rb.rb_c_rod_shank_fx, rb.rb_c_rod_shank_fy, rb.rb_c_rod_shank_m,
                           rb.rb_lower_actuator_fx, rb.rb_lower_actuator_fy, rb.rb_lower_actuator_m,
                           rb.rb_d_fx, rb.rb_d_fy, rb.rb_d_m};
  bool r_ok = true;
  for (int k = 0; k < 8; ++k) {
    r_ok = r_ok && same_bits(got_r[3 * k], j[k].force_n[0]) &&
           same_bits(got_r[3 * k + 1], j[k].force_n[1]) && same_bits(got_r[3 * k + 2], j[k].moment_nm);
  }
  CHECK(r_ok);
}

// Ct_Events of a sample's ST_CONTACT (leg 0 or leg 1).
uint8_t ct_events(const std::vector<hil::Frame> &out, int leg) {
  const hil::Frame *f = find(out, leg == 0 ? LEGSIM_CAN_ST_CONTACT_FRAME_ID : LEGSIM_CAN_ST_CONTACT_L1_FRAME_ID);
  if (f == nullptr) return 0xFF;
  legsim_can_st_contact_t m;  // both legs' frames have the same layout
  legsim_can_st_contact_unpack(&m, f->data, 64);
  return m.ct_events;
}

template <typename Ct>
void check_contact(const hil::Frame *f, int (*unpack)(Ct *, const uint8_t *, size_t),
                   const legsim_contact &c, uint32_t tick) {
  CHECK(f != nullptr);
  if (f == nullptr) return;
  Ct m;
  unpack(&m, f->data, 64);
  CHECK(m.ct_tick == tick);
  CHECK(m.ct_state == static_cast<uint8_t>(c.state));
  CHECK(same_bits(m.ct_normal, c.normal_n) && same_bits(m.ct_tangential, c.tangential_n));
  CHECK(same_bits(m.ct_friction_use, c.friction_use));
  CHECK(same_bits(m.ct_x, c.position[0]) && same_bits(m.ct_y, c.position[1]));
  CHECK(same_bits(m.ct_slip, c.slip_mps));
  CHECK(same_bits(m.ct_impulse_n, c.impulse_ns[0]) && same_bits(m.ct_impulse_t, c.impulse_ns[1]));
}

void check_sample(const std::vector<hil::Frame> &out, const legsim_sim *sim) {
  legsim_real q[39], qd[39], len[4], rate[4], force[4];
  legsim_reaction r[16];
  legsim_contact c[2];
  CHECK(legsim_get_q(sim, q) == LEGSIM_OK && legsim_get_qd(sim, qd) == LEGSIM_OK);
  CHECK(legsim_actuator_lengths(sim, len, rate) == LEGSIM_OK);
  CHECK(legsim_actuator_forces(sim, force) == LEGSIM_OK);
  if (legsim_reactions(sim, r) != LEGSIM_OK) std::memset(r, 0, sizeof r);
  CHECK(legsim_contacts(sim, c) == LEGSIM_OK);
  const uint32_t tick = static_cast<uint32_t>(legsim_step_count(sim));

  const hil::Frame *fb = find(out, LEGSIM_CAN_ST_BOX_FRAME_ID);
  CHECK(fb != nullptr);
  if (fb != nullptr) {
    legsim_can_st_box_t b;
    legsim_can_st_box_unpack(&b, fb->data, 64);
    CHECK(b.box_tick == tick);
    CHECK(same_bits(b.box_x, q[0]) && same_bits(b.box_y, q[1]) && same_bits(b.box_phi, q[2]));
    CHECK(same_bits(b.box_vx, qd[0]) && same_bits(b.box_vy, qd[1]) && same_bits(b.box_omega, qd[2]));
  }
  check_leg(out, 0, q, qd, len, rate, force, r, LEGSIM_CAN_ST_POS_FRAME_ID, legsim_can_st_pos_unpack,
            legsim_can_st_vel_unpack, legsim_can_st_act_unpack, legsim_can_st_react_a_unpack,
            legsim_can_st_react_b_unpack);
  check_leg(out, 1, q, qd, len, rate, force, r, LEGSIM_CAN_ST_POS_L1_FRAME_ID,
            legsim_can_st_pos_l1_unpack, legsim_can_st_vel_l1_unpack, legsim_can_st_act_l1_unpack,
            legsim_can_st_react_a_l1_unpack, legsim_can_st_react_b_l1_unpack);
  check_contact(find(out, LEGSIM_CAN_ST_CONTACT_FRAME_ID), legsim_can_st_contact_unpack, c[0], tick);
  check_contact(find(out, LEGSIM_CAN_ST_CONTACT_L1_FRAME_ID), legsim_can_st_contact_l1_unpack, c[1],
                tick);
  // both statuses: the same time (float64, exact) and step count
  const hil::Frame *s0 = find(out, LEGSIM_CAN_ST_STATUS_FRAME_ID);
  const hil::Frame *s1 = find(out, LEGSIM_CAN_ST_STATUS_L1_FRAME_ID);
  CHECK(s0 && s1);
  if (s0 && s1) {
    legsim_can_st_status_t a;
    legsim_can_st_status_l1_t b;
    legsim_can_st_status_unpack(&a, s0->data, 64);
    legsim_can_st_status_l1_unpack(&b, s1->data, 64);
    CHECK(a.st_time == legsim_time(sim) && b.st_time == legsim_time(sim));
    CHECK(a.st_step_count == legsim_step_count(sim) && b.st_step_count == a.st_step_count);
    CHECK(a.st_tick == tick && b.st_tick == tick);
  }
}

// The frames of one robot sample, in the order of protocol.h.
const uint32_t kOrder[] = {
    LEGSIM_CAN_ST_BOX_FRAME_ID,        LEGSIM_CAN_ST_POS_FRAME_ID,
    LEGSIM_CAN_ST_VEL_FRAME_ID,        LEGSIM_CAN_ST_ACT_FRAME_ID,
    LEGSIM_CAN_ST_REACT_A_FRAME_ID,    LEGSIM_CAN_ST_REACT_B_FRAME_ID,
    LEGSIM_CAN_ST_CONTACT_FRAME_ID,    LEGSIM_CAN_ST_POS_L1_FRAME_ID,
    LEGSIM_CAN_ST_VEL_L1_FRAME_ID,     LEGSIM_CAN_ST_ACT_L1_FRAME_ID,
    LEGSIM_CAN_ST_REACT_A_L1_FRAME_ID, LEGSIM_CAN_ST_REACT_B_L1_FRAME_ID,
    LEGSIM_CAN_ST_CONTACT_L1_FRAME_ID, LEGSIM_CAN_ST_STATUS_FRAME_ID,
    LEGSIM_CAN_ST_STATUS_L1_FRAME_ID};

void test_frames_and_ids() {
  CHECK(sizeof kOrder / sizeof kOrder[0] == hil::kMaxSampleFrames);
  CHECK(LEGSIM_CAN_ST_POS_L1_FRAME_ID == LEGSIM_CAN_ST_POS_FRAME_ID + 0x20);
  CHECK(LEGSIM_CAN_ST_STATUS_L1_FRAME_ID == LEGSIM_CAN_ST_STATUS_FRAME_ID + 0x20);
  CHECK(LEGSIM_CAN_ST_CONTACT_L1_FRAME_ID == LEGSIM_CAN_ST_CONTACT_FRAME_ID + 0x20);
  CHECK(LEGSIM_CAN_ACT_CMD_L1_FRAME_ID == LEGSIM_CAN_ACT_CMD_FRAME_ID + 0x20);
  CHECK(LEGSIM_CAN_LOAD_CMD_L1_FRAME_ID == LEGSIM_CAN_LOAD_CMD_FRAME_ID + 0x20);
  Rig r;
  auto out = r.feed(reset(3));
  CHECK(out.size() == hil::kMaxSampleFrames);
  bool order = out.size() == hil::kMaxSampleFrames;
  for (size_t i = 0; order && i < out.size(); ++i)
    order = out[i].id == kOrder[i] && out[i].fd && out[i].len == 64;
  CHECK(order);
  Direct d;
  check_sample(out, d.sim);
  legsim_contact c[2];
  CHECK(legsim_contacts(d.sim, c) == LEGSIM_OK);
  CHECK(c[0].state == LEGSIM_CONTACT_STUCK && c[1].state == LEGSIM_CONTACT_STUCK);
}

// The Fig. 7 push (design section 7, Scene A's commands) with leg 1's commands and load in
// its own frames: the same state as the C API given the same calls, bit for bit, however
// the STEP is sliced.
void test_lockstep_matches_the_c_api() {
  Direct d;
  legsim_real force[4];
  CHECK(legsim_step(d.sim, 1) == LEGSIM_OK);  // the servos' hold forces, after one solve
  CHECK(legsim_actuator_forces(d.sim, force) == LEGSIM_OK);
  const float push = static_cast<float>(force[0] + 50.0);
  const float left_upper = 0.70f;  // leg 1 upper servo moves (inside 0.4 .. 0.8 m)
  const float load[2] = {3.0f, -20.0f};

  for (uint64_t slice : {uint64_t{0}, uint64_t{7}, uint64_t{64}}) {
    Rig r;
    r.feed(reset(1));
    auto out = r.feed(step(2, 1), slice);
    check_sample(out, d.sim);  // after one step, as the direct sim
    r.feed(act(0, 1, LEGSIM_CAN_ACT_CMD_ACT_MODE_UPPER_FORCE_CHOICE, push));
    r.feed(act(1, 1, LEGSIM_CAN_ACT_CMD_L1_ACT_MODE_UPPER_LENGTH_CHOICE, left_upper));
    r.feed(load_l1(1, 0, load[0], load[1]));
    out = r.feed(step(3, 99), slice);
    Direct e;  // the same calls, straight
    CHECK(legsim_step(e.sim, 1) == LEGSIM_OK);
    CHECK(legsim_command_force(e.sim, 0, push) == LEGSIM_OK);
    CHECK(legsim_command_length(e.sim, 2, left_upper) == LEGSIM_OK);
    const legsim_real lv[2] = {load[0], load[1]};
    CHECK(legsim_set_force(e.sim, 1, lv) == LEGSIM_OK);
    CHECK(legsim_step(e.sim, 99) == LEGSIM_OK);
    check_sample(out, e.sim);
    CHECK(out.size() == hil::kMaxSampleFrames);
    // leg 1's status carries its own ACT_CMD counter, leg 0's its own
    legsim_can_st_status_t s0;
    legsim_can_st_status_l1_t s1;
    legsim_can_st_status_unpack(&s0, find(out, LEGSIM_CAN_ST_STATUS_FRAME_ID)->data, 64);
    legsim_can_st_status_l1_unpack(&s1, find(out, LEGSIM_CAN_ST_STATUS_L1_FRAME_ID)->data, 64);
    CHECK(s0.st_act_seq == 1 && s1.st_act_seq == 1 && s0.st_ctrl_seq == 3);
    // the commands moved the box (this is no run at rest)
    legsim_real q[39], q0[39];
    CHECK(legsim_get_q(e.sim, q) == LEGSIM_OK && legsim_get_q(d.sim, q0) == LEGSIM_OK);
    CHECK(std::fabs(q[0] - q0[0]) + std::fabs(q[1] - q0[1]) > 1e-3);
  }
}

// Bad leg-1 frames: a FAULT naming the frame (and the signal), and nothing changes.
void test_bad_leg1_frames() {
  Rig good, bad;
  good.feed(reset(1));
  bad.feed(reset(1));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  hil::Frame classic = act(1, 1, 1, 10.0f);
  classic.fd = false;
  classic.len = 8;
  struct Case {
    const char *what;
    hil::Frame frame;
    uint8_t code;
    uint32_t detail;
  };
  const Case cases[] = {
      {"classic ACT_CMD_L1", classic, 2, 64},
      {"NaN setpoint", act(1, 1, 1, nan), 3, LEGSIM_CAN_ACT_CMD_L1_ACT_SETPOINT_UPPER_START_BIT},
      {"force above max_force", act(1, 1, 0, 0, 1, 2000.0f), 4,
       LEGSIM_CAN_ACT_CMD_L1_ACT_SETPOINT_LOWER_START_BIT},
      {"length out of stroke", act(1, 1, 2, 0.95f), 4,
       LEGSIM_CAN_ACT_CMD_L1_ACT_SETPOINT_UPPER_START_BIT},
      {"mode out of range", act(1, 1, 3, 0.6f), 4, LEGSIM_CAN_ACT_CMD_L1_ACT_MODE_UPPER_START_BIT},
      {"load index beyond the leg's", load_l1(1, 1, 1.0f, 1.0f), 4,
       LEGSIM_CAN_LOAD_CMD_L1_LOAD_INDEX_START_BIT},
      {"NaN load", load_l1(1, 0, nan, 1.0f), 3, LEGSIM_CAN_LOAD_CMD_L1_LOAD_VALUE1_START_BIT},
  };
  for (const Case &c : cases) {
    auto out = bad.feed(c.frame);
    legsim_can_fault_t f = fault_of(out);
    const bool ok = out.size() == 1 && f.fault_code == c.code && f.fault_frame_id == c.frame.id &&
                    f.fault_detail == c.detail;
    if (!ok)
      std::fprintf(stderr, "%s: %zu frames, code %u id 0x%x detail %u\n", c.what, out.size(),
                   f.fault_code, f.fault_frame_id, f.fault_detail);
    CHECK(ok);
  }
  // a stale counter: accept seq 5 on leg 1, then 5 again is refused (leg 0's count apart)
  bad.feed(act(1, 5, 0, 0));
  good.feed(act(1, 5, 0, 0));
  auto out = bad.feed(act(1, 5, 1, 10.0f));
  CHECK(fault_of(out).fault_code == 5 && fault_of(out).fault_frame_id == LEGSIM_CAN_ACT_CMD_L1_FRAME_ID);
  CHECK(bad.feed(act(0, 1, 0, 0)).empty() && good.feed(act(0, 1, 0, 0)).empty());
  // nothing changed: the same STEP gives the same physics (the statuses differ in FAULT bits)
  auto a = good.feed(step(2, 20));
  auto b = bad.feed(step(2, 20));
  CHECK(a.size() == b.size());
  bool same = a.size() == b.size();
  for (size_t i = 0; same && i < a.size(); ++i) {
    if (a[i].id == LEGSIM_CAN_ST_STATUS_FRAME_ID || a[i].id == LEGSIM_CAN_ST_STATUS_L1_FRAME_ID)
      continue;
    same = a[i].id == b[i].id && std::memcmp(a[i].data, b[i].data, 64) == 0;
  }
  CHECK(same);
  // the robot has one variant: the slot variant is out of range
  out = bad.feed(reset(9, 1, 1));
  CHECK(fault_of(out).fault_code == 4 &&
        fault_of(out).fault_detail == LEGSIM_CAN_CONTROL_CTRL_VARIANT_START_BIT);
}

// RESET with the four lengths: the robot assembled on the ground at them.
void test_reset_with_lengths() {
  Rig r;
  legsim_can_control_t m = untimed(control(1, LEGSIM_CAN_CONTROL_CTRL_COMMAND_RESET_CHOICE));
  m.ctrl_use_lengths = 1;
  m.ctrl_length_upper = 0.62f;
  m.ctrl_length_lower = 0.52f;
  m.ctrl_length_upper_l1 = 0.63f;
  m.ctrl_length_lower_l1 = 0.53f;
  auto out = r.feed(pack(m));
  CHECK(out.size() == hil::kMaxSampleFrames);
  legsim_can_st_act_t a0;
  legsim_can_st_act_l1_t a1;
  legsim_can_st_act_unpack(&a0, find(out, LEGSIM_CAN_ST_ACT_FRAME_ID)->data, 64);
  legsim_can_st_act_l1_unpack(&a1, find(out, LEGSIM_CAN_ST_ACT_L1_FRAME_ID)->data, 64);
  CHECK(std::fabs(a0.act_upper_length - 0.62f) < 1e-6f && std::fabs(a0.act_lower_length - 0.52f) < 1e-6f);
  CHECK(std::fabs(a1.act_upper_length - 0.63f) < 1e-6f && std::fabs(a1.act_lower_length - 0.53f) < 1e-6f);
  legsim_can_st_contact_t c0;
  legsim_can_st_contact_l1_t c1;
  legsim_can_st_contact_unpack(&c0, find(out, LEGSIM_CAN_ST_CONTACT_FRAME_ID)->data, 64);
  legsim_can_st_contact_l1_unpack(&c1, find(out, LEGSIM_CAN_ST_CONTACT_L1_FRAME_ID)->data, 64);
  CHECK(c0.ct_state == 1 && c1.ct_state == 1);                  // stuck
  CHECK(std::fabs(c0.ct_y) < 1e-6f && std::fabs(c1.ct_y) < 1e-6f);  // on the ground line
  CHECK(std::fabs(c0.ct_x + c1.ct_x) < 1e-6f);                     // midpoint kept at 0
  // a leg-1 length out of its stroke is refused, naming it
  m.ctrl_seq = 2;
  m.ctrl_length_lower_l1 = 0.2f;
  out = r.feed(pack(m));
  CHECK(out.size() == 1 && fault_of(out).fault_code == 4 &&
        fault_of(out).fault_detail == LEGSIM_CAN_CONTROL_CTRL_LENGTH_LOWER_L1_START_BIT);
}

// RESET with Ctrl_ContactLaw and Ctrl_FreeContacts (the left foot free at t = 0): the same sim
// as the C API given options.contact_law and legsim_set_contact_state FREE. Ct_Events are the
// core's events of that foot over every step since the previous sample
// (legsim_contact_event_mask): one STEP of n steps carries the union of the per-step events
// of n STEPs of one, each on its own foot.
legsim_can_control_t reset_feet(uint32_t seq, uint8_t law, uint8_t free_mask) {
  legsim_can_control_t m = untimed(control(seq, LEGSIM_CAN_CONTROL_CTRL_COMMAND_RESET_CHOICE));
  m.ctrl_act_init = 1;
  m.ctrl_contact_law = law;
  m.ctrl_free_contacts = free_mask;
  return m;
}

void test_contact_events_and_reset_options() {
  constexpr int kSteps = 60;
  Direct d(LEGSIM_CONTACT_PAPER, 2u);
  Rig one, each;
  auto out = one.feed(pack(reset_feet(1, 1, 2)));
  check_sample(out, d.sim);
  CHECK(ct_events(out, 0) == 0 && ct_events(out, 1) == 0);  // a RESET's sample: none
  legsim_contact c[2];
  CHECK(legsim_contacts(d.sim, c) == LEGSIM_OK);
  CHECK(c[0].state == LEGSIM_CONTACT_STUCK && c[1].state == LEGSIM_CONTACT_FREE);
  each.feed(pack(reset_feet(1, 1, 2)));
  // the C API step by step: each foot's events, per step and over the run
  uint32_t direct[2] = {0, 0};
  uint8_t sampled[2] = {0, 0};
  bool per_step_same = true;
  for (int i = 0; i < kSteps; ++i) {
    CHECK(legsim_clear_events(d.sim) == LEGSIM_OK);
    CHECK(legsim_step(d.sim, 1) == LEGSIM_OK);
    auto o = each.feed(step(2 + i, 1));
    for (int k = 0; k < 2; ++k) {
      const uint32_t ev = legsim_contact_event_mask(d.sim, k);
      direct[k] |= ev;
      sampled[k] |= ct_events(o, k);
      per_step_same = per_step_same && ct_events(o, k) == ((ev >> 4) & 0x3Fu);
    }
  }
  CHECK(per_step_same);
  out = one.feed(step(2, kSteps), 7);
  check_sample(out, d.sim);
  CHECK(ct_events(out, 0) == ((direct[0] >> 4) & 0x3Fu) && ct_events(out, 1) == ((direct[1] >> 4) & 0x3Fu));
  CHECK(ct_events(out, 0) == sampled[0] && ct_events(out, 1) == sampled[1]);
  // the free left foot came down on the ground (TOUCHDOWN, bit 1); the right one had none
  CHECK((ct_events(out, 1) & 0x2u) != 0 && ct_events(out, 0) == 0);
  std::fprintf(stderr, "contact events over %d steps: right 0x%x, left 0x%x\n", kSteps, ct_events(out, 0),
               ct_events(out, 1));
  // out of range: a third contact law, a foot the robot does not have
  legsim_can_control_t m = reset_feet(9, 2, 0);
  out = one.feed(pack(m));
  CHECK(out.size() == 1 && fault_of(out).fault_code == 4 &&
        fault_of(out).fault_detail == LEGSIM_CAN_CONTROL_CTRL_CONTACT_LAW_START_BIT);
  m = reset_feet(10, 0, 4);
  out = one.feed(pack(m));
  CHECK(out.size() == 1 && fault_of(out).fault_code == 4 &&
        fault_of(out).fault_detail == LEGSIM_CAN_CONTROL_CTRL_FREE_CONTACTS_START_BIT);
}

// START_CMD then RESET (a scene's [start]): the same sim as the C API given
// legsim_host::start_apply with the float32 values sent, the feet in the state the masks give
// (stuck on the ground, free above it otherwise); bit for bit at the RESET and after 50 steps
// through the touchdown. A bad START_CMD is refused on arrival and the RESET then starts at rest.
hil::Frame start_cmd(uint32_t seq, float lift, float vx, float vy, uint8_t stuck = 0, uint8_t sliding = 0) {
  legsim_can_start_cmd_t m;
  std::memset(&m, 0, sizeof m);
  m.start_seq = seq;
  m.start_use = 1;
  m.start_lift = lift;
  m.start_vx = vx;
  m.start_vy = vy;
  m.start_stuck_contacts = stuck;
  m.start_sliding_contacts = sliding;
  hil::Frame f = fd_frame(LEGSIM_CAN_START_CMD_FRAME_ID);
  legsim_can_start_cmd_pack(f.data, &m, 64);
  return f;
}

void test_start_off_the_stance() {
  legsim_host::StartState start;
  start.given = true;
  start.lift_m = static_cast<double>(0.01f);
  start.velocity_mps[0] = static_cast<double>(0.3f);
  start.velocity_mps[1] = static_cast<double>(-0.1f);
  Direct d(LEGSIM_CONTACT_LCP, 0, &start);
  CHECK(legsim_clear_events(d.sim) == LEGSIM_OK);
  Rig r;
  CHECK(r.feed(start_cmd(1, 0.01f, 0.3f, -0.1f)).empty());   // accepted, not answered
  auto out = r.feed(pack(reset_feet(1, 0, 0)));
  check_sample(out, d.sim);
  legsim_contact c[2];
  CHECK(legsim_contacts(d.sim, c) == LEGSIM_OK);
  CHECK(c[0].state == LEGSIM_CONTACT_FREE && c[1].state == LEGSIM_CONTACT_FREE);
  CHECK(legsim_step(d.sim, 50) == LEGSIM_OK);
  out = r.feed(step(2, 50), 7);
  check_sample(out, d.sim);
  CHECK((ct_events(out, 0) & 0x2u) != 0 && (ct_events(out, 1) & 0x2u) != 0);   // both touched down
  // the next RESET has no START_CMD: the stance at rest, both feet stuck
  out = r.feed(pack(reset_feet(3, 0, 0)));
  Direct rest;
  check_sample(out, rest.sim);
  // refused on arrival, naming the signal: not finite, out of range, a foot in both masks,
  // a foot the robot does not have; a start the robot cannot take fails the RESET (SOLVER)
  out = r.feed(start_cmd(5, std::nanf(""), 0, 0));
  CHECK(out.size() == 1 && fault_of(out).fault_code == 3 &&
        fault_of(out).fault_detail == LEGSIM_CAN_START_CMD_START_LIFT_START_BIT);
  out = r.feed(start_cmd(6, 0.01f, 101.0f, 0));
  CHECK(out.size() == 1 && fault_of(out).fault_code == 4 &&
        fault_of(out).fault_detail == LEGSIM_CAN_START_CMD_START_VX_START_BIT);
  out = r.feed(start_cmd(7, 0.0f, 0, 0, 1, 1));
  CHECK(out.size() == 1 && fault_of(out).fault_code == 4 &&
        fault_of(out).fault_detail == LEGSIM_CAN_START_CMD_START_SLIDING_CONTACTS_START_BIT);
  out = r.feed(start_cmd(8, 0.0f, 0, 0, 4, 0));
  CHECK(out.size() == 1 && fault_of(out).fault_code == 4);
  CHECK(r.feed(start_cmd(9, 0.1f, 0, 0, 1, 0)).empty());   // right foot stuck, 0.1 m up: cannot
  out = r.feed(pack(reset_feet(4, 0, 0)));
  CHECK(out.size() == 1 && fault_of(out).fault_code == 8);
}

// The one-leg hil_sim: leg-1 commands are unknown ids; leg-1 state frames (another sim's)
// are ignored; the one leg's sample stays six frames.
void test_one_leg_refuses_leg1_frames() {
  hil::Session::use_models(&legsim_model_leg_revolute, &legsim_model_leg_slot);
  CHECK(hil::Session::legs() == 1);
  Rig r;
  auto out = r.feed(reset(1, 0));
  CHECK(out.size() == hil::kSampleFrames);
  out = r.feed(act(1, 1, 1, 10.0f));
  CHECK(out.size() == 1 && fault_of(out).fault_code == 1 &&
        fault_of(out).fault_frame_id == LEGSIM_CAN_ACT_CMD_L1_FRAME_ID);
  out = r.feed(load_l1(1, 0, 1.0f, 1.0f));
  CHECK(out.size() == 1 && fault_of(out).fault_code == 1);
  CHECK(r.feed(fd_frame(LEGSIM_CAN_ST_BOX_FRAME_ID)).empty());
  CHECK(r.feed(fd_frame(LEGSIM_CAN_ST_STATUS_L1_FRAME_ID)).empty());
  CHECK(r.feed(fd_frame(LEGSIM_CAN_ST_CONTACT_FRAME_ID)).empty());
  CHECK(r.feed(act(0, 1, 1, 10.0f)).empty());  // leg 0's still works
  // the feet's RESET options need feet: refused by the model, naming the signal
  out = r.feed(pack(reset_feet(2, 1, 0)));
  CHECK(out.size() == 1 && fault_of(out).fault_code == 4 &&
        fault_of(out).fault_detail == LEGSIM_CAN_CONTROL_CTRL_CONTACT_LAW_START_BIT);
  out = r.feed(pack(reset_feet(3, 0, 1)));
  CHECK(out.size() == 1 && fault_of(out).fault_code == 4 &&
        fault_of(out).fault_detail == LEGSIM_CAN_CONTROL_CTRL_FREE_CONTACTS_START_BIT);
}

// Each leg node has its own command watchdog: a leg silent past the timeout trips alone
// (FAULT CMD_TIMEOUT naming its ACT_CMD id and counter, SAFE_STATE in its own ST_STATUS, its
// actuators at zero force) while the other leg, still commanded, keeps its command and its
// armed watchdog; in lockstep at the same step as the one leg (ceil(timeout / h) steps after
// its last command) and in real time at the first tick past the timeout.
legsim_can_st_status_t status0(const std::vector<hil::Frame> &v) {
  legsim_can_st_status_t m;
  legsim_can_st_status_init(&m);
  if (const hil::Frame *f = find(v, LEGSIM_CAN_ST_STATUS_FRAME_ID)) legsim_can_st_status_unpack(&m, f->data, 64);
  return m;
}
legsim_can_st_status_l1_t status1(const std::vector<hil::Frame> &v) {
  legsim_can_st_status_l1_t m;
  legsim_can_st_status_l1_init(&m);
  if (const hil::Frame *f = find(v, LEGSIM_CAN_ST_STATUS_L1_FRAME_ID)) legsim_can_st_status_l1_unpack(&m, f->data, 64);
  return m;
}
// The actuator forces of leg 0 (upper, lower) then leg 1, from a sample.
void forces_of(const std::vector<hil::Frame> &v, float out[4]) {
  legsim_can_st_act_t a0;
  legsim_can_st_act_l1_t a1;
  legsim_can_st_act_unpack(&a0, find(v, LEGSIM_CAN_ST_ACT_FRAME_ID)->data, 64);
  legsim_can_st_act_l1_unpack(&a1, find(v, LEGSIM_CAN_ST_ACT_L1_FRAME_ID)->data, 64);
  out[0] = a0.act_upper_force;
  out[1] = a0.act_lower_force;
  out[2] = a1.act_upper_force;
  out[3] = a1.act_lower_force;
}
int faults_in(const std::vector<hil::Frame> &v) {
  int n = 0;
  for (const auto &f : v) n += f.id == LEGSIM_CAN_FAULT_FRAME_ID;
  return n;
}

void test_watchdog_per_leg() {
  constexpr uint8_t kLength = LEGSIM_CAN_ACT_CMD_ACT_MODE_UPPER_LENGTH_CHOICE;
  hil::ControllerConfig cfg;  // 100 ms, zero force
  Rig r(cfg);
  legsim_can_control_t m = control(1, LEGSIM_CAN_CONTROL_CTRL_COMMAND_RESET_CHOICE);
  m.ctrl_act_init = 1;  // the default timeout (100 ms = 100 steps of 1 ms)
  auto out = r.feed(pack(m));
  legsim_can_st_act_t a0;
  legsim_can_st_act_l1_t a1;
  legsim_can_st_act_unpack(&a0, find(out, LEGSIM_CAN_ST_ACT_FRAME_ID)->data, 64);
  legsim_can_st_act_l1_unpack(&a1, find(out, LEGSIM_CAN_ST_ACT_L1_FRAME_ID)->data, 64);
  // both legs' servos hold their RESET lengths, commanded at step 0
  const float len[4] = {a0.act_upper_length, a0.act_lower_length, a1.act_upper_length,
                        a1.act_lower_length};
  uint32_t seq0 = 1, seq1 = 1, ctrl = 2;
  CHECK(r.feed(act(0, seq0++, kLength, len[0], kLength, len[1])).empty());
  CHECK(r.feed(act(1, seq1++, kLength, len[2], kLength, len[3])).empty());
  out = r.feed(step(ctrl++, 1));
  CHECK((status0(out).st_status & hil::kStatusCmdWatchdog) && (status1(out).st_status & hil::kStatusCmdWatchdog));

  // leg 0 commands every 40 steps, leg 1 is silent: leg 1 trips at step 100, alone
  int faults = 0;
  legsim_can_fault_t fault;
  legsim_can_fault_init(&fault);
  for (int i = 0; i < 5; ++i) {  // steps 1 .. 200
    CHECK(r.feed(act(0, seq0++, kLength, len[0], kLength, len[1])).empty());
    out = r.feed(step(ctrl++, 40), 7);
    faults += faults_in(out);
    if (faults_in(out) > 0) fault = fault_of(out);
  }
  CHECK(faults == 1);
  CHECK(fault.fault_code == 7 && fault.fault_frame_id == LEGSIM_CAN_ACT_CMD_L1_FRAME_ID);
  CHECK(fault.fault_seq == 1 && fault.fault_detail == 100 && fault.fault_step_count == 100);
  const uint32_t s0 = status0(out).st_status, s1 = status1(out).st_status;
  CHECK(!(s0 & hil::kStatusSafeState) && (s0 & hil::kStatusCmdWatchdog));
  CHECK((s1 & hil::kStatusSafeState) && !(s1 & hil::kStatusCmdWatchdog));
  float f[4];
  forces_of(out, f);
  CHECK(f[2] == 0.0f && f[3] == 0.0f);  // leg 1 in the safe state (zero force)
  CHECK(f[0] != 0.0f && f[1] != 0.0f);  // leg 0's servos still hold
  // the heartbeat says that a node is in its safe state and that one is armed
  hil::HeartbeatInfo hb;
  r.ctl.fill_heartbeat(&hb);
  CHECK((hb.status & hil::kStatusSafeState) && (hb.status & hil::kStatusCmdWatchdog));

  // leg 1 commanded again leaves its safe state; now leg 0 falls silent and trips alone,
  // 100 steps after its last command (step 161), while leg 1 keeps its servo command
  CHECK(r.feed(act(1, seq1++, kLength, len[2], kLength, len[3])).empty());
  faults = 0;
  for (int i = 0; i < 3; ++i) {  // steps 201 .. 320
    CHECK(r.feed(act(1, seq1++, kLength, len[2], kLength, len[3])).empty());
    out = r.feed(step(ctrl++, 40));
    faults += faults_in(out);
    if (faults_in(out) > 0) fault = fault_of(out);
  }
  CHECK(faults == 1);
  CHECK(fault.fault_code == 7 && fault.fault_frame_id == LEGSIM_CAN_ACT_CMD_FRAME_ID);
  CHECK(fault.fault_seq == seq0 - 1 && fault.fault_step_count == 261);
  CHECK((status0(out).st_status & hil::kStatusSafeState) && !(status1(out).st_status & hil::kStatusSafeState));
  forces_of(out, f);
  CHECK(f[0] == 0.0f && f[1] == 0.0f && f[2] != 0.0f && f[3] != 0.0f);
  // a RESET disarms both and leaves both safe states
  m.ctrl_seq = ctrl++;
  out = r.feed(pack(m));
  CHECK(!((status0(out).st_status | status1(out).st_status) &
          (hil::kStatusSafeState | hil::kStatusCmdWatchdog)));

  // real time: leg 0 commands every 40 ticks, leg 1 silent since tick 0: leg 1 trips at the
  // first tick more than 100 ms after its command, once
  CHECK(r.feed(act(0, 1, kLength, len[0], kLength, len[1])).empty());
  CHECK(r.feed(act(1, 1, kLength, len[2], kLength, len[3])).empty());
  legsim_can_control_t rt = control(ctrl++, LEGSIM_CAN_CONTROL_CTRL_COMMAND_START_RT_CHOICE);
  rt.ctrl_rt_decimation = 1;
  r.ctl.on_frame(pack(rt), 0);
  r.rec.take();
  faults = 0;
  int64_t t = 0;
  uint32_t s = 2;
  for (int i = 1; i <= 160; ++i) {
    t += 1000000;
    if (i % 40 == 0) r.ctl.on_frame(act(0, s++, kLength, len[0], kLength, len[1]), t);
    r.ctl.rt_tick(t);
    out = r.rec.take();
    if (faults_in(out) > 0) {
      fault = fault_of(out);
      CHECK(i == 101);
    }
    faults += faults_in(out);
  }
  CHECK(faults == 1 && fault.fault_frame_id == LEGSIM_CAN_ACT_CMD_L1_FRAME_ID);
  CHECK(!(status0(out).st_status & hil::kStatusSafeState) && (status1(out).st_status & hil::kStatusSafeState));
}

// A RESET at start lengths (Ctrl_Length_*, float64 on the bus) follows legsim_cli's rule for
// a scene's `lengths` (legsim_host::start_length_in_stroke): a length at a stroke end is that
// end, bit for bit, and runs as the C API given the scene's doubles
// (scenes/robot_stops_stuck: both feet stuck, the four lengths at their minima 0.40, 0.35 m,
// zero force, RK4 at 1 ms, 0.3 s); one double below a minimum, 1 mm out of a stroke or NaN
// is refused where the CLI refuses it, with a FAULT naming the signal, and the running
// session steps on (never HALTED for bad input).
legsim_can_control_t reset_at(uint32_t seq, const double len[4]) {
  legsim_can_control_t m = untimed(control(seq, LEGSIM_CAN_CONTROL_CTRL_COMMAND_RESET_CHOICE));
  m.ctrl_act_init = 0;  // zero force (a scene's init = "zero_force")
  m.ctrl_use_lengths = 1;
  m.ctrl_length_upper = len[0];
  m.ctrl_length_lower = len[1];
  m.ctrl_length_upper_l1 = len[2];
  m.ctrl_length_lower_l1 = len[3];
  return m;
}

void test_start_lengths_at_the_stroke_ends() {
  using legsim_host::start_length_in_stroke;
  const legsim_model_desc &rm = legsim_model_robot_revolute;
  const double minima[4] = {rm.actuator[0].stroke_min_m, rm.actuator[1].stroke_min_m,
                            rm.actuator[2].stroke_min_m, rm.actuator[3].stroke_min_m};
  // the scene's values are the model's minima (models/robot.toml); float32 cannot hold them:
  // 0.35f is below the stroke, 0.40f 6e-9 m inside it (the core's step 0 failed from there)
  CHECK(minima[0] == 0.40 && minima[1] == 0.35 && minima[2] == 0.40 && minima[3] == 0.35);
  CHECK(static_cast<double>(0.35f) < 0.35 && static_cast<double>(0.40f) > 0.40);
  CHECK(!start_length_in_stroke(rm, 1, static_cast<double>(0.35f)));
  CHECK(start_length_in_stroke(rm, 1, 0.35) && start_length_in_stroke(rm, 0, 0.40));
  // the C API given the scene's doubles, as legsim_cli runs it
  std::vector<unsigned char> storage(legsim_sim_size() + LEGSIM_STORAGE_ALIGN);
  void *p = storage.data();
  size_t space = storage.size();
  void *aligned = std::align(LEGSIM_STORAGE_ALIGN, legsim_sim_size(), p, space);
  legsim_options opt = legsim_default_options();
  opt.step_s = 0.001;
  legsim_sim *sim = nullptr;
  CHECK(legsim_init(aligned, space, &rm, &opt, &sim) == LEGSIM_OK);
  CHECK(legsim_assemble_pose(sim, 0) == LEGSIM_OK);
  legsim_contact c[2];
  CHECK(legsim_contacts(sim, c) == LEGSIM_OK);
  legsim_real given[4] = {minima[0], minima[1], minima[2], minima[3]};
  CHECK(legsim_assemble_on_ground(sim, given, (c[0].position[0] + c[1].position[0]) / 2) == LEGSIM_OK);
  for (int a = 0; a < 4; ++a) CHECK(legsim_command_force(sim, a, 0) == LEGSIM_OK);
  CHECK(legsim_clear_events(sim) == LEGSIM_OK);
  CHECK(legsim_contacts_check(sim) == LEGSIM_OK);  // as hil_sim's RESET ends

  Rig r;
  auto out = r.feed(pack(reset_at(1, minima)));
  // the frame carries the scene's doubles bit for bit
  legsim_can_control_t sent;
  legsim_can_control_unpack(&sent, pack(reset_at(1, minima)).data, 64);
  CHECK(sent.ctrl_length_upper == 0.40 && sent.ctrl_length_lower == 0.35 &&
        sent.ctrl_length_upper_l1 == 0.40 && sent.ctrl_length_lower_l1 == 0.35);
  CHECK(out.size() == hil::kMaxSampleFrames && fault_of(out).fault_code == 0);
  check_sample(out, sim);
  CHECK(status0(out).st_state == LEGSIM_CAN_ST_STATUS_ST_STATE_LOCKSTEP_CHOICE);
  CHECK(legsim_step(sim, 300) == LEGSIM_OK);
  out = r.feed(step(2, 300), 64);
  CHECK(fault_of(out).fault_code == 0);
  CHECK(status0(out).st_state == LEGSIM_CAN_ST_STATUS_ST_STATE_LOCKSTEP_CHOICE);
  CHECK(status0(out).st_step_count == 300);
  check_sample(out, sim);

  // refused where legsim_cli refuses: the same rule on the same double
  struct Bad {
    int actuator;
    double length;
    unsigned code, bit;
  };
  const Bad bad[] = {
      {1, std::nextafter(0.35, 0.0), 4, LEGSIM_CAN_CONTROL_CTRL_LENGTH_LOWER_START_BIT},  // 1 ulp short
      {1, 0.35 - 1e-3, 4, LEGSIM_CAN_CONTROL_CTRL_LENGTH_LOWER_START_BIT},                // 1 mm short
      {2, rm.actuator[2].stroke_max_m + 1e-3, 4, LEGSIM_CAN_CONTROL_CTRL_LENGTH_UPPER_L1_START_BIT},
      {3, std::nan(""), 3, LEGSIM_CAN_CONTROL_CTRL_LENGTH_LOWER_L1_START_BIT},            // NOT_FINITE
  };
  uint32_t seq = 3;
  for (const Bad &b : bad) {
    CHECK(!start_length_in_stroke(rm, b.actuator, b.length));  // legsim_cli refuses it too
    double len[4] = {minima[0], minima[1], minima[2], minima[3]};
    len[b.actuator] = b.length;
    out = r.feed(pack(reset_at(seq++, len)));
    const legsim_can_fault_t f = fault_of(out);
    CHECK(out.size() == 1 && f.fault_code == b.code && f.fault_detail == b.bit);
    CHECK(f.fault_frame_id == LEGSIM_CAN_CONTROL_FRAME_ID);
    CHECK(std::isnan(b.length) ? std::isnan(f.fault_value) : f.fault_value == static_cast<float>(b.length));
    // the running session is untouched and steps on
    CHECK(legsim_step(sim, 1) == LEGSIM_OK);
    out = r.feed(step(seq++, 1));
    CHECK(fault_of(out).fault_code == 0);
    CHECK(status0(out).st_state == LEGSIM_CAN_ST_STATUS_ST_STATE_LOCKSTEP_CHOICE);
    check_sample(out, sim);
  }
  // the stroke's other ends are in too (ends included): at most the core's call, never OUT_OF_RANGE
  const double ends[4] = {rm.actuator[0].stroke_max_m, minima[1], minima[2], rm.actuator[3].stroke_max_m};
  for (int a = 0; a < 4; ++a) CHECK(start_length_in_stroke(rm, a, ends[a]));
  out = r.feed(pack(reset_at(seq++, ends)));
  CHECK(fault_of(out).fault_code != 4);
}

}  // namespace

int main() {
  hil::Session::use_robot(&legsim_model_robot_revolute);
  test_start_lengths_at_the_stroke_ends();
  test_frames_and_ids();
  test_lockstep_matches_the_c_api();
  test_bad_leg1_frames();
  test_reset_with_lengths();
  test_contact_events_and_reset_options();
  test_watchdog_per_leg();
  test_start_off_the_stance();
  test_one_leg_refuses_leg1_frames();  // last: it switches to the one leg
  return report();
}
