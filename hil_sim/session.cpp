// The legsim C API calls behind the protocol.
#include "session.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "legsim/models.h"
#include "scene_toml.hpp"  // legsim_host::start_apply: a scene's [start], as legsim_cli

namespace hil {

namespace {

// ACT_CMD set-points arrive as float32 and were checked against the stroke rounded to
// float32; the core gets them on the exact stroke (a move of at most one float32 ulp).
legsim_real on_stroke(const legsim_model_desc *m, int a, double l) {
  return static_cast<legsim_real>(
      std::clamp(l, m->actuator[a].stroke_min_m, m->actuator[a].stroke_max_m));
}

// Where the contacts' midpoint lies along the ground line, from the line's point (m).
legsim_status feet_mid(const legsim_sim *sim, const legsim_model_desc *m, legsim_real *out) {
  legsim_contact c[kMaxContacts];
  legsim_status st = legsim_contacts(sim, c);
  if (st != LEGSIM_OK) return st;
  double mx = 0, my = 0;
  for (int k = 0; k < m->n_contacts; ++k) {
    mx += c[k].position[0] / m->n_contacts;
    my += c[k].position[1] / m->n_contacts;
  }
  const double s = m->ground.slope_rad;
  *out = static_cast<legsim_real>((mx - m->ground.point[0]) * std::cos(s) +
                                  (my - m->ground.point[1]) * std::sin(s));
  return LEGSIM_OK;
}

}  // namespace

Session::~Session() {
  std::free(storage_[0]);
  std::free(storage_[1]);
}

namespace {
const legsim_model_desc *g_variant_models[2] = {&legsim_model_leg_revolute, &legsim_model_leg_slot};
const legsim_model_desc *g_robot = nullptr;  // set: the robot runs, as variant 0 only
}  // namespace

const legsim_model_desc *Session::variant_model(int variant) {
  if (g_robot != nullptr) return variant == 0 ? g_robot : nullptr;
  return variant == 0 || variant == 1 ? g_variant_models[variant] : nullptr;
}

void Session::use_models(const legsim_model_desc *revolute, const legsim_model_desc *slot) {
  g_variant_models[0] = revolute;
  g_variant_models[1] = slot;
  g_robot = nullptr;
}

namespace {
// The robot must be laid out as the DBC's legs: the box, then per leg its 6 bodies, 8
// joints, 2 actuators, and a contact each (design: robot-on-ground.md, section 1).
bool check_robot(std::string *error) {
  const legsim_model_desc *m = g_robot;
  char msg[160] = "";
  legsim_status st = legsim_model_check(m, msg, sizeof msg);
  if (st != LEGSIM_OK) {
    *error = std::string("robot model '") + m->name + "' rejected: " + legsim_status_str(st) +
             (msg[0] ? std::string(": ") + msg : std::string());
    return false;
  }
  if (m->n_bodies != kMaxBodies || m->n_joints != kMaxJoints || m->n_actuators != kMaxActuators ||
      m->n_contacts != kMaxContacts ||
      (m->n_forces - (Session::box_force(m) >= 0 ? 2 : 0)) % kMaxLegs != 0 ||
      Session::forces_per_leg(m) > 2) {
    *error = std::string("robot model '") + m->name + "' has " + std::to_string(m->n_bodies) +
             " bodies, " + std::to_string(m->n_joints) + " joints, " +
             std::to_string(m->n_actuators) + " actuators, " + std::to_string(m->n_contacts) +
             " contacts, " + std::to_string(m->n_forces) +
             " force elements; can/legsim.dbc carries a box and two legs: 13, 16, 4, 2 and up "
             "to 2 per leg (LOAD_CMD index 0-1; 2-3 of leg 0 are the box load)";
    return false;
  }
  for (int k = 0; k < kMaxLegs; ++k) {
    if (m->contact[k].body != kBodies * (k + 1)) {
      *error = std::string("robot model '") + m->name + "': contact " + std::to_string(k) +
               " is not on leg " + std::to_string(k) + "'s last body";
      return false;
    }
  }
  return true;
}

}  // namespace

void Session::use_robot(const legsim_model_desc *robot) { g_robot = robot; }

int Session::box_force(const legsim_model_desc *m) {
  const int b = m->n_forces - 2;
  if (m->n_contacts == 0 || b < 0) return -1;
  return std::strncmp(m->force[b].name, "box.load", LEGSIM_NAME_LEN) == 0 &&
                 std::strncmp(m->force[b + 1].name, "box.moment", LEGSIM_NAME_LEN) == 0
             ? b
             : -1;
}

int Session::legs() { return g_robot != nullptr ? 2 : 1; }

bool Session::init(std::string *error) {
  size_t align = LEGSIM_STORAGE_ALIGN;
  storage_bytes_ = (legsim_sim_size() + align - 1) / align * align;
  for (auto &s : storage_) {
    s = std::aligned_alloc(align, storage_bytes_);
    if (s == nullptr) {
      *error = "cannot allocate " + std::to_string(storage_bytes_) + " bytes of sim storage";
      return false;
    }
  }
  if (g_robot != nullptr) return check_robot(error);
  // both variants must be the leg of can/legsim.dbc
  for (int v = 0; v < 2; ++v) {
    const legsim_model_desc *m = variant_model(v);
    char msg[160] = "";
    legsim_status st = legsim_model_check(m, msg, sizeof msg);
    if (st != LEGSIM_OK) {
      *error = std::string("compiled-in model '") + m->name + "' rejected: " +
               legsim_status_str(st) + (msg[0] ? std::string(": ") + msg : std::string());
      return false;
    }
    if (m->n_bodies != kBodies || m->n_joints != kJoints || m->n_actuators != kActuators) {
      *error = std::string("compiled-in model '") + m->name + "' has " +
               std::to_string(m->n_bodies) + " bodies, " + std::to_string(m->n_joints) +
               " joints, " + std::to_string(m->n_actuators) +
               " actuators; can/legsim.dbc carries 6, 8 and 2";
      return false;
    }
  }
  return true;
}

legsim_status Session::build(void *storage, const ResetParams &p, legsim_sim **out) {
  legsim_options opt = legsim_default_options();
  opt.integrator = static_cast<legsim_integrator>(p.integrator);
  opt.step_s = static_cast<double>(p.step_ns) / 1e9;  // correctly rounded: 1000000 -> 0.001
  opt.disable = p.disable;
  opt.contact_law = static_cast<legsim_contact_law>(p.contact_law);
  legsim_sim *sim = nullptr;
  legsim_status st = legsim_init(storage, storage_bytes_, variant_model(p.variant), &opt, &sim);
  if (st != LEGSIM_OK) return st;
  st = legsim_assemble_pose(sim, p.pose);
  if (st != LEGSIM_OK) return st;
  const legsim_model_desc *m = variant_model(p.variant);
  const int na = m->n_actuators;
  legsim_real given[kMaxActuators];
  // the RESET's lengths: float64 as sent, inside the stroke by legsim_cli's rule (protocol)
  for (int a = 0; a < na && p.use_lengths; ++a) given[a] = static_cast<legsim_real>(p.lengths[a]);
  if (m->n_contacts > 0) {
    // the robot: onto the ground, both feet stuck, their midpoint where the pose put it
    // (the pose's guess has the feet on the line already); the box pose follows
    legsim_real mid = 0;
    st = feet_mid(sim, m, &mid);
    if (st == LEGSIM_OK) st = legsim_assemble_on_ground(sim, p.use_lengths ? given : nullptr, mid);
    if (st == LEGSIM_OK && p.use_start) {
      // START_CMD: the scene's [start], as legsim_cli runs it (legsim_host::start_apply)
      int32_t state[kMaxContacts];
      for (int k = 0; k < m->n_contacts; ++k) {
        const uint32_t bits = ((p.free_contacts >> k) & 1u) + ((p.stuck_contacts >> k) & 1u) +
                              ((p.sliding_contacts >> k) & 1u);
        if (bits > 1) return LEGSIM_ERR_BAD_INPUT;  // two states for one foot
        state[k] = ((p.free_contacts >> k) & 1u)    ? LEGSIM_CONTACT_FREE
                   : ((p.stuck_contacts >> k) & 1u) ? LEGSIM_CONTACT_STUCK
                   : ((p.sliding_contacts >> k) & 1u) ? LEGSIM_CONTACT_SLIDING
                                                      : -1;
      }
      legsim_host::StartState start;
      start.given = true;
      start.lift_m = p.start_lift;
      start.tilt_rad = p.start_tilt;
      start.velocity_mps[0] = p.start_velocity[0];
      start.velocity_mps[1] = p.start_velocity[1];
      start.spin_radps = p.start_spin;
      std::string why;
      st = legsim_host::start_apply(sim, *m, start, state, opt.newton_tol, why);
      if (st != LEGSIM_OK) std::fprintf(stderr, "hil_sim: RESET: %s\n", why.c_str());
    } else {
      // the scene's [[contact]] state = free: that foot's rows lifted at t = 0 (as legsim_cli)
      for (int k = 0; k < m->n_contacts && st == LEGSIM_OK; ++k)
        if ((p.free_contacts >> k) & 1u) st = legsim_set_contact_state(sim, k, LEGSIM_CONTACT_FREE);
    }
    if (st != LEGSIM_OK) return st;
  } else if (p.use_lengths) {
    st = legsim_assemble(sim, given);
    if (st != LEGSIM_OK) return st;
  }
  legsim_real len[kMaxActuators], rate[kMaxActuators];
  if (p.hold_length) {
    st = legsim_actuator_lengths(sim, len, rate);
    if (st != LEGSIM_OK) return st;
  }
  for (int a = 0; a < na && st == LEGSIM_OK; ++a)
    st = p.hold_length ? legsim_command_length(sim, a, len[a])
                       : legsim_command_force(sim, a, 0);
  if (st != LEGSIM_OK) return st;
  st = legsim_clear_events(sim);
  // the contact modes at t = 0, as legsim_cli checks them before its first sample: a start
  // that cannot hold changes mode here, its event in the first state frames
  if (st == LEGSIM_OK && m->n_contacts > 0) st = legsim_contacts_check(sim);
  if (st != LEGSIM_OK) return st;
  *out = sim;
  return LEGSIM_OK;
}

legsim_status Session::reset(const ResetParams &params) {
  if (variant_model(params.variant) == nullptr) return LEGSIM_ERR_BAD_INPUT;
  // build into the spare storage: a failure leaves the running session untouched
  int spare = sim_ == nullptr ? current_ : 1 - current_;
  legsim_sim *sim = nullptr;
  legsim_status st = build(storage_[spare], params, &sim);
  if (st != LEGSIM_OK) return st;
  sim_ = sim;
  current_ = spare;
  params_ = params;
  return LEGSIM_OK;
}

legsim_status Session::step(int32_t n) { return legsim_step(sim_, n); }

legsim_status Session::contacts_check() {
  return model()->n_contacts > 0 ? legsim_contacts_check(sim_) : LEGSIM_OK;
}

legsim_status Session::command(int actuator, ActMode mode, double value) {
  switch (mode) {
    case ActMode::kForce:
      return legsim_command_force(sim_, actuator, static_cast<legsim_real>(value));
    case ActMode::kLength:
      return legsim_command_length(sim_, actuator, on_stroke(model(), actuator, value));
    case ActMode::kKeep:
      break;
  }
  return LEGSIM_OK;
}

legsim_status Session::set_load(int force, const double value[2]) {
  legsim_real v[2] = {static_cast<legsim_real>(value[0]), static_cast<legsim_real>(value[1])};
  return legsim_set_force(sim_, force, v);
}

legsim_status Session::apply_safe_state(SafeMode mode, int leg) {
  legsim_real len[kMaxActuators], rate[kMaxActuators];
  legsim_status st = LEGSIM_OK;
  if (mode == SafeMode::kHoldLength) st = legsim_actuator_lengths(sim_, len, rate);
  const legsim_model_desc *m = model();
  const int first = leg < 0 ? 0 : leg * kActuators;
  const int end = leg < 0 ? m->n_actuators : std::min(m->n_actuators, first + kActuators);
  for (int a = first; a < end && st == LEGSIM_OK; ++a) {
    if (mode == SafeMode::kZeroForce) {
      st = legsim_command_force(sim_, a, 0);
    } else {
      st = legsim_command_length(sim_, a, on_stroke(m, a, len[a]));  // hold where it is
    }
  }
  return st;
}

legsim_status Session::sample(Sample *out) const {
  std::memset(out, 0, sizeof *out);
  legsim_status st = legsim_get_q(sim_, out->q);
  if (st == LEGSIM_OK) st = legsim_get_qd(sim_, out->qd);
  if (st == LEGSIM_OK) st = legsim_actuator_lengths(sim_, out->length, out->rate);
  if (st == LEGSIM_OK) st = legsim_actuator_forces(sim_, out->force);
  if (st == LEGSIM_OK) {
    legsim_real phi[LEGSIM_MAX_ROWS];
    st = legsim_constraints(sim_, phi, &out->residual);
  }
  if (st == LEGSIM_OK) st = legsim_get_report(sim_, &out->report);
  // reactions exist only after a dynamics solve (and not with DISABLE_REACTIONS): else zero
  if (legsim_reactions(sim_, out->reaction) != LEGSIM_OK)
    std::memset(out->reaction, 0, sizeof out->reaction);
  const legsim_model_desc *m = model();
  out->legs = m->n_contacts > 0 ? kMaxLegs : 1;
  if (st == LEGSIM_OK && m->n_contacts > 0) {
    legsim_contact c[kMaxContacts];
    st = legsim_contacts(sim_, c);
    for (int k = 0; k < m->n_contacts && st == LEGSIM_OK; ++k) {
      ContactSample &o = out->contact[k];
      o.state = static_cast<int>(c[k].state);
      o.normal = c[k].normal_n;
      o.tangential = c[k].tangential_n;
      o.friction_use = c[k].friction_use;
      o.position[0] = c[k].position[0];
      o.position[1] = c[k].position[1];
      o.slip = c[k].slip_mps;
      o.impulse[0] = c[k].impulse_ns[0];
      o.impulse[1] = c[k].impulse_ns[1];
      o.events = legsim_contact_event_mask(sim_, k);  // since the last sample's clear
    }
  }
  out->t = legsim_time(sim_);
  out->steps = legsim_step_count(sim_);
  out->stroke_mask = legsim_stroke_event_mask(sim_);
  return st;
}

legsim_status Session::clear_events() { return legsim_clear_events(sim_); }

uint32_t Session::events() const {
  legsim_report r;
  return legsim_get_report(sim_, &r) == LEGSIM_OK ? r.events : 0u;
}

}  // namespace hil
