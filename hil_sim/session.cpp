// The legsim C API calls behind the protocol.
#include "session.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>

#include "legsim/models.h"

namespace hil {

namespace {

// Lengths arrive as float32 and were checked against the stroke rounded to float32; the
// core gets them on the exact stroke (a move of at most one float32 ulp).
legsim_real on_stroke(const legsim_model_desc *m, int a, double l) {
  return static_cast<legsim_real>(
      std::clamp(l, m->actuator[a].stroke_min_m, m->actuator[a].stroke_max_m));
}

}  // namespace

Session::~Session() {
  std::free(storage_[0]);
  std::free(storage_[1]);
}

namespace {
const legsim_model_desc *g_variant_models[2] = {&legsim_model_leg_revolute, &legsim_model_leg_slot};
}  // namespace

const legsim_model_desc *Session::variant_model(int variant) {
  return variant == 0 || variant == 1 ? g_variant_models[variant] : nullptr;
}

void Session::use_models(const legsim_model_desc *revolute, const legsim_model_desc *slot) {
  g_variant_models[0] = revolute;
  g_variant_models[1] = slot;
}

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
  legsim_sim *sim = nullptr;
  legsim_status st = legsim_init(storage, storage_bytes_, variant_model(p.variant), &opt, &sim);
  if (st != LEGSIM_OK) return st;
  st = legsim_assemble_pose(sim, p.pose);
  if (st != LEGSIM_OK) return st;
  if (p.use_lengths) {
    legsim_real len[kActuators];
    for (int a = 0; a < kActuators; ++a) len[a] = on_stroke(variant_model(p.variant), a, p.lengths[a]);
    st = legsim_assemble(sim, len);
    if (st != LEGSIM_OK) return st;
  }
  legsim_real len[kActuators], rate[kActuators];
  if (p.hold_length) {
    st = legsim_actuator_lengths(sim, len, rate);
    if (st != LEGSIM_OK) return st;
  }
  for (int a = 0; a < kActuators && st == LEGSIM_OK; ++a)
    st = p.hold_length ? legsim_command_length(sim, a, len[a])
                       : legsim_command_force(sim, a, 0);
  if (st != LEGSIM_OK) return st;
  st = legsim_clear_events(sim);
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

legsim_status Session::apply_safe_state(SafeMode mode) {
  legsim_real len[kActuators], rate[kActuators];
  legsim_status st = LEGSIM_OK;
  if (mode == SafeMode::kHoldLength) st = legsim_actuator_lengths(sim_, len, rate);
  const legsim_model_desc *m = model();
  for (int a = 0; a < kActuators && st == LEGSIM_OK; ++a) {
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
