// Writing a scene and its results: the resolved scene (legsim_cli --check) and the run's
// JSON or CSV. Host only.
#include "scene_text.hpp"
#include "scene_toml.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace legsim_host {
namespace {

using scene_text::name_of;
using scene_text::num;

std::string jstr(const std::string &s) {
  std::string o = "\"";
  for (unsigned char c : s) {
    switch (c) {
      case '"': o += "\\\""; break;
      case '\\': o += "\\\\"; break;
      case '\n': o += "\\n"; break;
      case '\r': o += "\\r"; break;
      case '\t': o += "\\t"; break;
      default:
        if (c < 0x20) {
          char b[8];
          std::snprintf(b, sizeof b, "\\u%04x", c);
          o += b;
        } else {
          o += static_cast<char>(c);
        }
    }
  }
  return o + "\"";
}

std::string jnum(double x) { return std::isfinite(x) ? num(x) : "null"; }


// The names of legsim.h's event bits (python/legsim/sim.py EVENTS, the bench's
// legsim_bench.verdict.analyses.EVENT_NAMES say the same), in bit order.
struct EventName {
  uint32_t bit;
  const char *name;
};
const EventName kEventNames[] = {
    {LEGSIM_EVENT_STROKE_MIN, "stroke_min"},
    {LEGSIM_EVENT_STROKE_MAX, "stroke_max"},
    {LEGSIM_EVENT_FORCE_SATURATED, "force_saturated"},
    {LEGSIM_EVENT_NEAR_SINGULAR, "near_singular"},
    {LEGSIM_EVENT_LIFTOFF, "liftoff"},
    {LEGSIM_EVENT_TOUCHDOWN, "touchdown"},
    {LEGSIM_EVENT_STICK_TO_SLIP, "stick_to_slip"},
    {LEGSIM_EVENT_SLIP_TO_STICK, "slip_to_stick"},
    {LEGSIM_EVENT_CONTACT_INCONSISTENT, "contact_inconsistent"},
    {LEGSIM_EVENT_CONTACT_AMBIGUOUS, "contact_ambiguous"},
    {LEGSIM_EVENT_EVENTS_DEFERRED, "events_deferred"},
    {LEGSIM_EVENT_EVENT_INEXACT, "event_inexact"},
};

std::vector<std::string> event_names(uint32_t e) {
  std::vector<std::string> v;
  uint32_t known = 0;
  for (const auto &n : kEventNames) {
    known |= n.bit;
    if (e & n.bit) v.push_back(n.name);
  }
  // a bit this list does not know yet is shown, never dropped
  for (int b = 0; b < 32; ++b)
    if ((e & ~known) & (1u << b)) v.push_back("event_bit_" + std::to_string(b));
  return v;
}

std::string csv_field(const std::string &s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string o = "\"";
  for (char c : s) o += c == '"' ? std::string("\"\"") : std::string(1, c);
  return o + "\"";
}

const char *kXyz[3] = {"x", "y", "phi"};

const char *statics_rule_name(legsim_statics_rule r) {
  return r == LEGSIM_STATICS_MIN_TANGENTIAL ? "min_tangential" : "equal_friction";
}

const char *contact_law_name(legsim_contact_law l) {
  return l == LEGSIM_CONTACT_PAPER ? "paper" : "lcp";
}

const char *contact_state_name(legsim_contact_state st) {
  switch (st) {
    case LEGSIM_CONTACT_FREE: return "free";
    case LEGSIM_CONTACT_STUCK: return "stuck";
    case LEGSIM_CONTACT_SLIDING: return "sliding";
  }
  return "unknown";
}
// Per contact, in this order: state, then the numbers (JSON keys and CSV column suffixes).
const char *kContactNumbers[] = {"normal", "tangential", "friction_use", "x", "y", "slip", "impulse_n",
                                 "impulse_t"};
// The CSV's column names carry their SI units (as the FMU's variables: _m, _rad, _n, _nm).
const char *kContactColumns[] = {"normal_n", "tangential_n", "friction_use", "x_m", "y_m", "slip_m_per_s",
                                 "impulse_n_n_s", "impulse_t_n_s"};
const char *kXyzColumns[3] = {"x_m", "y_m", "phi_rad"};
double contact_number(const legsim_contact &c, int i) {
  const legsim_real v[] = {c.normal_n, c.tangential_n, c.friction_use, c.position[0],
                           c.position[1], c.slip_mps, c.impulse_ns[0], c.impulse_ns[1]};
  return v[i];
}
constexpr int kNContactNumbers = 8;
constexpr int kNContactForces = 3;  // normal, tangential, friction_use: from a solve

}  // namespace

void write_resolved(std::ostream &o, const Scene &sc, const legsim_model_desc &m) {
  o << "{\"scene\": " << jstr(sc.path) << ", \"name\": " << jstr(sc.name)
    << ", \"model\": " << jstr(sc.model) << ", \"model_path\": " << jstr(sc.model_path)
    << ", \"variant\": " << jstr(sc.variant) << ", \"analysis\": " << jstr(analysis_name(sc.analysis))
    << ", \"integrator\": "
    << jstr(sc.options.integrator == LEGSIM_INTEGRATOR_RK4 ? "rk4" : "generalized_alpha")
    << ", \"step_ns\": " << sc.step_ns << ", \"n_steps\": " << sc.n_steps
    << ", \"record_every\": " << sc.record_every << ", \"pose\": "
    << (sc.pose_index >= 0 ? jstr(name_of(m.pose[sc.pose_index].name)) : "null") << ", \"lengths\": ";
  if (sc.has_lengths) {
    o << "[";
    for (size_t i = 0; i < sc.lengths.size(); ++i) o << (i ? ", " : "") << jnum(sc.lengths[i]);
    o << "]";
  } else {
    o << "null";
  }
  o << ", \"grid\": " << sc.grid << ", \"init\": " << jstr(init_name(sc.init))
    << ", \"cmd_timeout_ms\": " << sc.cmd_timeout_ms << ", \"safe_state\": " << jstr(sc.safe_state)
    << ", \"disable\": " << sc.options.disable << ", \"rho_inf\": " << jnum(sc.options.rho_inf)
    << ", \"max_newton_iter\": " << sc.options.max_newton_iter
    << ", \"newton_tol\": " << jnum(sc.options.newton_tol) << ", \"statics_rule\": "
    << jstr(statics_rule_name(sc.options.statics_rule))
    << ", \"contact_law\": " << jstr(contact_law_name(sc.options.contact_law)) << ", \"forces\": {";
  for (size_t i = 0; i < sc.forces.size(); ++i) {
    const ForceValue &f = sc.forces[i];
    o << (i ? ", " : "") << jstr(f.name) << ": [";
    for (int k = 0; k < f.n; ++k) o << (k ? ", " : "") << jnum(f.value[k]);
    o << "]";
  }
  o << "}, \"commands\": {";
  for (size_t i = 0; i < sc.commands.size(); ++i) {
    const Command &c = sc.commands[i];
    const Signal &g = c.signal;
    o << (i ? ", " : "") << jstr(c.actuator) << ": {\"mode\": "
      << jstr(c.mode == LEGSIM_ACTUATOR_FORCE ? "force" : "length") << ", ";
    switch (g.kind) {
      case Signal::kConstant: o << "\"value\": " << jnum(g.value); break;
      case Signal::kInitial: o << "\"value\": \"initial\""; break;
      case Signal::kSinusoid:
        o << "\"sinusoid\": {\"offset\": " << jnum(g.offset) << ", \"amplitude\": " << jnum(g.amplitude)
          << ", \"frequency\": " << jnum(g.frequency_hz) << ", \"phase\": " << jnum(g.phase_rad) << "}";
        break;
      case Signal::kStep:
        o << "\"step\": {\"t0\": " << jnum(g.t0) << ", \"before\": " << jnum(g.before)
          << ", \"after\": " << jnum(g.after) << "}";
        break;
      case Signal::kSwitch:
        o << "\"switch\": {\"event\": " << jstr(g.event) << ", \"contact\": " << jstr(g.contact)
          << ", \"before\": " << jnum(g.before) << ", \"after\": " << jnum(g.after) << "}";
        break;
    }
    o << "}";
  }
  o << "}, \"contacts\": {";
  for (size_t i = 0; i < sc.contacts.size(); ++i)
    o << (i ? ", " : "") << jstr(sc.contacts[i].name) << ": "
      << jstr(sc.contacts[i].state == LEGSIM_CONTACT_FREE    ? "free"
              : sc.contacts[i].state == LEGSIM_CONTACT_SLIDING ? "sliding"
                                                               : "stuck");
  o << "}, \"start\": ";
  if (sc.start.given)
    o << "{\"lift\": " << jnum(sc.start.lift_m) << ", \"tilt\": " << jnum(sc.start.tilt_rad)
      << ", \"velocity\": [" << jnum(sc.start.velocity_mps[0]) << ", " << jnum(sc.start.velocity_mps[1])
      << "], \"spin\": " << jnum(sc.start.spin_radps) << "}";
  else
    o << "null";
  // the ground the scene runs on (its [ground] applied to the model's), or null (no contacts)
  o << ", \"ground_given\": " << (sc.ground.given ? "true" : "false") << ", \"ground\": ";
  if (m.n_contacts > 0)
    o << "{\"point\": [" << jnum(m.ground.point[0]) << ", " << jnum(m.ground.point[1])
      << "], \"slope\": " << jnum(m.ground.slope_rad) << ", \"mu_static\": " << jnum(m.ground.mu_static)
      << ", \"mu_kinetic\": " << jnum(m.ground.mu_kinetic) << "}";
  else
    o << "null";
  o << ", \"box_load\": ";
  if (sc.has_box_load)
    o << "[" << jnum(sc.box_load[0]) << ", " << jnum(sc.box_load[1]) << ", " << jnum(sc.box_load[2]) << "]";
  else
    o << "null";
  o << ", \"checks\": " << sc.checks_json << ", \"inject\": " << sc.inject_json;
  write_resolved_model(o, sc, m);
  o << "}\n";
}

void JsonWriter::begin() {
  o_ << "{\n";
  o_ << "  \"scene\": " << jstr(sc_.path) << ",\n";
  if (!sc_.description.empty()) o_ << "  \"description\": " << jstr(sc_.description) << ",\n";
  o_ << "  \"model\": {\"name\": " << jstr(name_of(m_.name)) << ", \"source\": " << jstr(sc_.model)
     << ", \"variant\": " << jstr(sc_.variant) << "},\n";
  o_ << "  \"analysis\": " << jstr(analysis_name(sc_.analysis)) << ",\n";
  o_ << "  \"integrator\": "
     << jstr(sc_.options.integrator == LEGSIM_INTEGRATOR_RK4 ? "rk4" : "generalized_alpha") << ",\n";
  o_ << "  \"step_s\": " << jnum(sc_.options.step_s) << ",\n";
  o_ << "  \"record_every\": " << sc_.record_every << ",\n";
  auto names = [&](const char *key, int n, auto get) {
    o_ << "  \"" << key << "\": [";
    for (int i = 0; i < n; ++i) o_ << (i ? ", " : "") << jstr(get(i));
    o_ << "],\n";
  };
  names("bodies", m_.n_bodies, [&](int i) { return name_of(m_.body[i].name); });
  names("joints", m_.n_joints, [&](int i) { return name_of(m_.joint[i].name); });
  names("actuators", m_.n_actuators, [&](int i) { return name_of(m_.actuator[i].name); });
  if (m_.n_contacts > 0) {
    // a robot: its feet, the ground line, and the drawn length of each body (plots)
    names("contacts", m_.n_contacts, [&](int i) { return name_of(m_.contact[i].name); });
    const legsim_ground_desc &g = m_.ground;
    o_ << "  \"ground\": {\"point\": [" << jnum(g.point[0]) << ", " << jnum(g.point[1])
       << "], \"slope\": " << jnum(g.slope_rad) << ", \"mu_static\": " << jnum(g.mu_static)
       << ", \"mu_kinetic\": " << jnum(g.mu_kinetic) << "},\n";
    o_ << "  \"body_lengths\": [";
    for (int b = 0; b < m_.n_bodies; ++b) o_ << (b ? ", " : "") << jnum(m_.body[b].length_m);
    o_ << "],\n";
  }
  o_ << "  \"samples\": [";
}

void JsonWriter::sample(const Sample &s) {
  const legsim_model_desc &m = m_;
  o_ << (n_++ ? "," : "") << "\n    {\"t\": " << jnum(s.t) << ",\n     \"q\": {";
  for (int b = 0; b < m.n_bodies; ++b) {
    o_ << (b ? ", " : "") << jstr(name_of(m.body[b].name)) << ": {";
    for (int c = 0; c < 3; ++c) o_ << (c ? ", " : "") << "\"" << kXyz[c] << "\": " << jnum(s.q[3 * b + c]);
    o_ << "}";
  }
  o_ << "},\n     \"actuators\": {";
  for (int a = 0; a < m.n_actuators; ++a)
    o_ << (a ? ", " : "") << jstr(name_of(m.actuator[a].name)) << ": {\"length\": " << jnum(s.length[a])
       << ", \"rate\": " << jnum(s.rate[a]) << ", \"force\": " << jnum(s.force[a]) << "}";
  o_ << "},\n     \"reactions\": ";
  if (s.has_reactions) {
    o_ << "{";
    for (int j = 0; j < m.n_joints; ++j)
      o_ << (j ? ", " : "") << jstr(name_of(m.joint[j].name)) << ": {\"fx\": " << jnum(s.reaction[3 * j])
         << ", \"fy\": " << jnum(s.reaction[3 * j + 1]) << ", \"moment\": " << jnum(s.reaction[3 * j + 2])
         << "}";
    o_ << "}";
  } else {
    o_ << "null";
  }
  o_ << ",\n     \"foot\": ";
  if (s.has_foot)
    o_ << "{\"x\": " << jnum(s.foot[0]) << ", \"y\": " << jnum(s.foot[1]) << "}";
  else
    o_ << "null";
  if (m.n_contacts > 0) {
    o_ << ",\n     \"contacts\": ";
    if (static_cast<int>(s.contacts.size()) == m.n_contacts) {
      o_ << "{";
      for (int k = 0; k < m.n_contacts; ++k) {
        const legsim_contact &c = s.contacts[k];
        o_ << (k ? ", " : "") << jstr(name_of(m.contact[k].name)) << ": {\"state\": "
           << jstr(contact_state_name(c.state));
        for (int i = 0; i < kNContactNumbers; ++i)
          o_ << ", \"" << kContactNumbers[i]
             << "\": " << (i < kNContactForces && !s.contact_forces ? "null" : jnum(contact_number(c, i)));
        // whether the static cone holds the ground force (from a solve, as N and T)
        o_ << ", \"holds\": " << (!s.contact_forces ? "null" : c.holds ? "true" : "false") << "}";
      }
      o_ << "}";
    } else {
      o_ << "null";
    }
  }
  o_ << ", \"residual\": " << jnum(s.residual) << ", \"iterations\": " << s.iterations
     << ", \"condition\": " << jnum(s.condition) << ", \"events\": [";
  const auto ev = event_names(s.events);
  for (size_t k = 0; k < ev.size(); ++k) o_ << (k ? ", " : "") << jstr(ev[k]);
  o_ << "]}";
}

void JsonWriter::end(const Result &r) {
  const legsim_model_desc &m = m_;
  o_ << (n_ ? "\n  ],\n" : "],\n");
  if (r.has_worst_case) {
    const legsim_worst_case &w = r.worst;
    o_ << "  \"worst_case\": {\n    \"grid\": " << sc_.grid << ", \"n_poses\": " << w.n_poses
       << ", \"n_failed\": " << w.n_failed << ",\n    \"reactions\": {";
    for (int j = 0; j < m.n_joints; ++j) {
      o_ << (j ? ", " : "") << "\n      " << jstr(name_of(m.joint[j].name)) << ": {\"max_force\": "
         << jnum(w.max_reaction_n[j]) << ", \"at_lengths\": {";
      for (int a = 0; a < m.n_actuators; ++a)
        o_ << (a ? ", " : "") << jstr(name_of(m.actuator[a].name)) << ": " << jnum(w.at_length_m[j][a]);
      o_ << "}}";
    }
    o_ << "\n    },\n    \"actuators\": {";
    for (int a = 0; a < m.n_actuators; ++a) {
      o_ << (a ? ", " : "") << "\n      " << jstr(name_of(m.actuator[a].name)) << ": {\"max_force\": "
         << jnum(w.max_actuator_force_n[a]) << ", \"at_lengths\": {";
      for (int k = 0; k < m.n_actuators; ++k)
        o_ << (k ? ", " : "") << jstr(name_of(m.actuator[k].name)) << ": "
           << jnum(w.actuator_at_length_m[a][k]);
      o_ << "}}";
    }
    o_ << "\n    }\n  },\n";
  }
  if (r.status != LEGSIM_OK) {
    o_ << "  \"error\": " << jstr(r.error) << ",\n";
    if (r.failed_at_s >= 0) o_ << "  \"failed_at\": " << jnum(r.failed_at_s) << ",\n";
  }
  o_ << "  \"status\": " << jstr(r.status == LEGSIM_OK ? "ok" : "error") << ",\n";
  o_ << "  \"status_code\": " << jstr(status_enum_name(r.status)) << "\n}\n";
  o_.flush();
}

void CsvWriter::begin() {
  const legsim_model_desc &m = m_;
  if (sc_.analysis == Analysis::kStaticsSweep) {
    // One row per joint reaction and per actuator force: the worst case of the sweep.
    o_ << "item,kind,max_force_n";
    for (int a = 0; a < m.n_actuators; ++a) o_ << ",at_" << csv_field(name_of(m.actuator[a].name) + "_m");
    o_ << ",status\n";
    return;
  }
  o_ << "t_s";
  for (int b = 0; b < m.n_bodies; ++b)
    for (int c = 0; c < 3; ++c) o_ << "," << csv_field(name_of(m.body[b].name) + "." + kXyzColumns[c]);
  for (int a = 0; a < m.n_actuators; ++a) {
    const std::string n = name_of(m.actuator[a].name);
    o_ << "," << csv_field(n + ".length_m") << "," << csv_field(n + ".rate_m_per_s") << ","
       << csv_field(n + ".force_n");
  }
  for (int j = 0; j < m.n_joints; ++j) {
    const std::string n = name_of(m.joint[j].name);
    o_ << "," << csv_field(n + ".fx_n") << "," << csv_field(n + ".fy_n") << "," << csv_field(n + ".moment_nm");
  }
  if (m.foot_body >= 0) o_ << ",foot.x_m,foot.y_m";
  for (int k = 0; k < m.n_contacts; ++k) {
    const std::string n = name_of(m.contact[k].name);
    o_ << "," << csv_field(n + ".state");
    for (int i = 0; i < kNContactNumbers; ++i) o_ << "," << csv_field(n + "." + kContactColumns[i]);
    o_ << "," << csv_field(n + ".holds");
  }
  o_ << ",residual,events,status\n";
}

void CsvWriter::sample(const Sample &s) {
  const legsim_model_desc &m = m_;
  o_ << num(s.t);
  for (double x : s.q) o_ << "," << num(x);
  for (int a = 0; a < m.n_actuators; ++a) o_ << "," << num(s.length[a]) << "," << num(s.rate[a]) << "," << num(s.force[a]);
  // Reactions exist after a solve (not at the dynamics' t = 0, nor with reactions disabled):
  // nan then, a number every CSV reader parses.
  for (int j = 0; j < m.n_joints; ++j)
    for (int c = 0; c < 3; ++c) o_ << "," << num(s.has_reactions ? s.reaction[3 * j + c] : NAN);
  if (m.foot_body >= 0) o_ << "," << num(s.has_foot ? s.foot[0] : NAN) << "," << num(s.has_foot ? s.foot[1] : NAN);
  const bool have_contacts = static_cast<int>(s.contacts.size()) == m.n_contacts;
  for (int k = 0; k < m.n_contacts; ++k) {
    o_ << "," << (have_contacts ? contact_state_name(s.contacts[k].state) : "nan");
    for (int i = 0; i < kNContactNumbers; ++i)
      o_ << "," << num(have_contacts && (i >= kNContactForces || s.contact_forces) ? contact_number(s.contacts[k], i) : NAN);
    o_ << "," << (have_contacts && s.contact_forces ? (s.contacts[k].holds ? "1" : "0") : "nan");
  }
  // the sample's events, ';'-separated (no comma: one field), "none" (never an empty field)
  std::string ev;
  for (const auto &n : event_names(s.events)) ev += (ev.empty() ? "" : ";") + n;
  if (ev.empty()) ev = "none";
  o_ << "," << num(s.residual) << "," << ev << ",ok\n";
}

void CsvWriter::end(const Result &r) {
  const legsim_model_desc &m = m_;
  if (r.has_worst_case) {
    const legsim_worst_case &w = r.worst;
    for (int j = 0; j < m.n_joints; ++j) {
      o_ << csv_field(name_of(m.joint[j].name)) << ",reaction," << num(w.max_reaction_n[j]);
      for (int a = 0; a < m.n_actuators; ++a) o_ << "," << num(w.at_length_m[j][a]);
      o_ << ",ok\n";
    }
    for (int a = 0; a < m.n_actuators; ++a) {
      o_ << csv_field(name_of(m.actuator[a].name)) << ",actuator," << num(w.max_actuator_force_n[a]);
      for (int k = 0; k < m.n_actuators; ++k) o_ << "," << num(w.actuator_at_length_m[a][k]);
      o_ << ",ok\n";
    }
  }
  // A failed run: no row for the failure (its time and cause go to stderr and the exit
  // status), so every row holds a complete state.
  o_.flush();
}

}  // namespace legsim_host
