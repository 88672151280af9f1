// Scene files for legsim_cli: parsing (toml++), binding to a model, running the
// analyses through the C API, and writing JSON or CSV. Host only.
#include "scene_toml.hpp"
#include "toml_limits.hpp"

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

#include <toml++/toml.h>

namespace legsim_host {
namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;
constexpr double kGridTolS = 1e-9;               // a time is on the step grid within 1 ns
constexpr int64_t kMaxRecordEvery = 10000000;    // the DBC's largest STEP (Ctrl_NSteps)
// Output is streamed, but a run still may not ask for more rows than a file can sensibly
// hold (about 1 GB of CSV): n_steps / record_every + 1 <= kMaxSamples.
constexpr int64_t kMaxSamples = 1000000;
constexpr double kMaxFrequencyHz = 1e3;          // command sinusoids

struct SceneError {
  std::string message;
};

[[noreturn]] void fail(const std::string &problem) { throw SceneError{problem}; }

std::string q(const std::string &s) { return "'" + s + "'"; }

std::string num(double x) {  // shortest round-trip form
  if (!std::isfinite(x)) return std::isnan(x) ? "nan" : (x > 0 ? "inf" : "-inf");
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}

using Node = const toml::node *;
using Table = const toml::table *;

bool is_number(Node v) { return v && (v->is_integer() || v->is_floating_point()); }
double to_double(Node v) {
  if (v->is_integer()) return static_cast<double>(*v->value<int64_t>());
  return v->as_floating_point()->get();
}

void check_keys(Table t, const std::vector<std::string> &allowed, const std::string &where) {
  for (auto &&kv : *t) {
    const std::string key(kv.first.str());
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
      std::vector<std::string> sorted = allowed;
      std::sort(sorted.begin(), sorted.end());
      std::string list;
      for (size_t i = 0; i < sorted.size(); ++i) list += (i ? ", " : "") + sorted[i];
      fail(where + "unknown key " + q(key) + " (allowed: " + list + ")");
    }
  }
}

double real_of(Node v, const std::string &what) {
  if (!is_number(v)) fail(what + " must be a number");
  const double x = to_double(v);
  if (!std::isfinite(x)) fail(what + " is not finite");
  return x;
}

double get_real(Table t, const std::string &key, const std::string &where, bool required,
                double dflt) {
  Node v = t->get(key);
  if (!v) {
    if (required) fail(where + "missing key " + q(key));
    return dflt;
  }
  return real_of(v, where + q(key));
}

std::string get_string(Table t, const std::string &key, const std::string &where, bool required,
                       const std::string &dflt = "") {
  Node v = t->get(key);
  if (!v) {
    if (required) fail(where + "missing key " + q(key));
    return dflt;
  }
  if (!v->is_string()) fail(where + q(key) + " must be a string");
  return std::string(*v->value<std::string_view>());
}

int64_t get_int(Table t, const std::string &key, const std::string &where, int64_t dflt, int64_t lo,
                int64_t hi) {
  Node v = t->get(key);
  if (!v) return dflt;
  if (!v->is_integer()) fail(where + q(key) + " must be an integer");
  const int64_t x = *v->value<int64_t>();
  if (x < lo || x > hi)
    fail(where + q(key) + " must be in " + std::to_string(lo) + ".." + std::to_string(hi) + " (got " +
         std::to_string(x) + ")");
  return x;
}

Signal parse_signal(Table t, const std::string &where) {
  const bool has_value = t->get("value") != nullptr;
  const bool has_sin = t->get("sinusoid") != nullptr;
  const bool has_step = t->get("step") != nullptr;
  if (int(has_value) + int(has_sin) + int(has_step) != 1)
    fail(where + "give exactly one of 'value', 'sinusoid' or 'step'");
  Signal s;
  if (has_value) {
    Node v = t->get("value");
    if (v->is_string() && *v->value<std::string_view>() == "initial") {
      s.kind = Signal::kInitial;  // the assembled length, filled in at run time
    } else {
      s.kind = Signal::kConstant;
      s.value = real_of(v, where + "'value' (a number, or \"initial\")");
    }
  } else if (has_sin) {
    Table st = t->get("sinusoid")->as_table();
    if (!st) fail(where + "'sinusoid' must be a table {offset, amplitude, frequency, phase}");
    const std::string w = where + "sinusoid: ";
    check_keys(st, {"offset", "amplitude", "frequency", "phase"}, w);
    s.kind = Signal::kSinusoid;
    s.offset = get_real(st, "offset", w, true, 0);
    s.amplitude = get_real(st, "amplitude", w, true, 0);
    s.frequency_hz = get_real(st, "frequency", w, true, 0);
    s.phase_rad = get_real(st, "phase", w, false, 0);
    if (!(s.frequency_hz > 0)) fail(w + "'frequency' must be > 0 (Hz; a constant is 'value')");
    if (s.frequency_hz > kMaxFrequencyHz)
      fail(w + "'frequency' must be at most " + num(kMaxFrequencyHz) + " Hz (got " + num(s.frequency_hz) + ")");
    if (std::fabs(s.phase_rad) > LEGSIM_MAX_COORD)
      fail(w + "'phase' must be in [-" + num(LEGSIM_MAX_COORD) + ", " + num(LEGSIM_MAX_COORD) + "] rad (got " +
           num(s.phase_rad) + ")");
  } else {
    Table st = t->get("step")->as_table();
    if (!st) fail(where + "'step' must be a table {t0, before, after}");
    const std::string w = where + "step: ";
    check_keys(st, {"t0", "before", "after"}, w);
    s.kind = Signal::kStep;
    s.t0 = get_real(st, "t0", w, true, 0);
    s.before = get_real(st, "before", w, false, 0);
    s.after = get_real(st, "after", w, true, 0);
    if (!(s.t0 >= 0 && s.t0 <= LEGSIM_MAX_TIME_S))
      fail(w + "'t0' must be in [0, " + num(LEGSIM_MAX_TIME_S) + "] s (got " + num(s.t0) + ")");
  }
  return s;
}

struct DisableFlag {
  const char *name;
  uint32_t flag;
};
const DisableFlag kDisable[] = {
    {"gravity", LEGSIM_DISABLE_GRAVITY},
    {"force_elements", LEGSIM_DISABLE_FORCE_ELEMENTS},
    {"reactions", LEGSIM_DISABLE_REACTIONS},
    {"projection", LEGSIM_DISABLE_PROJECTION},
    {"actuators", LEGSIM_DISABLE_ACTUATORS},
    {"stroke_limits", LEGSIM_DISABLE_STROKE_LIMITS},
};

std::string dirname_of(const std::string &path) {
  const size_t p = path.find_last_of('/');
  if (p == std::string::npos) return "";
  return path.substr(0, p + 1);
}

// Keys and values of the two former schemas (scenes/cli and bench/scenes) and what they are
// now: an old file gets a message naming the new key (the bench says the same words).
struct Renamed {
  const char *old_key;
  const char *message;
};
const Renamed kRenamedKeys[] = {
    {"output_every", "'output_every' is now 'record_every' (steps between recorded samples)"},
    {"decimation", "'decimation' is now 'record_every' (steps between recorded samples)"},
    {"step",
     "'step' is now 'step_s' (the step size, s); 'step = { t0, before, after }' is a step "
     "signal in a [[command]]"},
    {"foot_load", "'foot_load' is now a force element value: [forces] foot_load = [Fx, Fy] (N)"},
};
struct RenamedValue {
  const char *old_value, *new_value;
};
const RenamedValue kRenamedValues[] = {
    {"force_zero", "zero_force"}, {"zero-force", "zero_force"}, {"hold-length", "hold_length"}};

std::string choice(Table t, const char *key, const char *const *options, size_t n,
                   const std::string &dflt) {
  const std::string v = get_string(t, key, "", false, dflt);
  for (size_t i = 0; i < n; ++i)
    if (v == options[i]) return v;
  for (const auto &r : kRenamedValues)
    if (v == r.old_value)
      fail(std::string(key) + " = \"" + v + "\" is now " + key + " = \"" + r.new_value + "\"");
  std::string list;
  for (size_t i = 0; i < n; ++i) list += (i ? (i + 1 == n ? " or " : ", ") : "") + std::string(options[i]);
  fail(q(key) + " must be " + list + " (got " + q(v) + ")");
}

// A time on the step grid: t = k h exactly (within 1 ns), as the bench requires.
int64_t on_grid(double t, int64_t step_ns, const std::string &what) {
  const double k = std::round(t * 1e9 / static_cast<double>(step_ns));
  if (std::fabs(k * static_cast<double>(step_ns) / 1e9 - t) > kGridTolS)
    fail(what + " " + num(t) + " s is not on the step grid (h = " + num(step_ns / 1e9) + " s)");
  return static_cast<int64_t>(k);
}

std::string stem_of(const std::string &path) {
  const size_t p = path.find_last_of('/');
  std::string base = p == std::string::npos ? path : path.substr(p + 1);
  const size_t dot = base.rfind('.');
  return dot == std::string::npos || dot == 0 ? base : base.substr(0, dot);
}

bool is_name(const std::string &s) {
  if (s.empty()) return false;
  for (unsigned char c : s)
    if (!(std::isalnum(c) || c == '_' || c == '-' || c == '.')) return false;
  return true;
}

void parse_scene(Table doc, Scene &s) {
  for (const auto &r : kRenamedKeys)
    if (doc->get(r.old_key)) fail(r.message);
  check_keys(doc, {"description", "name", "demo", "model", "variant", "analysis", "integrator",
                   "step_s", "duration", "record_every", "disable", "rho_inf", "max_newton_iter",
                   "newton_tol", "pose", "lengths", "grid", "init", "cmd_timeout_ms", "safe_state",
                   "box_load",
                   "forces", "command", "contact", "inject", "checks", "statics_rule",
                   "contact_law"},
             "");
  s.description = get_string(doc, "description", "", false);
  s.name = get_string(doc, "name", "", false, stem_of(s.path));
  if (!is_name(s.name)) fail("'name' must be letters, digits, '_', '-', '.' (got " + q(s.name) + ")");
  if (Node dv = doc->get("demo")) {
    if (!dv->is_boolean()) fail("'demo' must be true or false");
    s.demo = *dv->value<bool>();
  }
  s.model = get_string(doc, "model", "", false, "builtin:leg");
  if (s.model.rfind("builtin:", 0) == 0) {
    s.builtin = s.model.substr(8);
  } else {
    if (s.model.empty()) fail("'model' must name a model file (or \"builtin:leg\")");
    s.model_path = s.model[0] == '/' ? s.model : dirname_of(s.path) + s.model;
  }
  s.variant = get_string(doc, "variant", "", false, "revolute");

  const std::string an = get_string(doc, "analysis", "", false, "dynamics");
  const struct {
    const char *name;
    Analysis a;
  } analyses[] = {{"dynamics", Analysis::kDynamics},
                  {"statics", Analysis::kStatics},
                  {"statics_sweep", Analysis::kStaticsSweep},
                  {"inverse_dynamics", Analysis::kInverseDynamics},
                  {"assembly", Analysis::kAssembly}};
  bool found = false;
  for (const auto &e : analyses)
    if (an == e.name) {
      s.analysis = e.a;
      found = true;
    }
  if (!found)
    fail("'analysis' must be dynamics, statics, statics_sweep, inverse_dynamics or assembly (got " +
         q(an) + ")");
  const bool timed = s.analysis == Analysis::kDynamics || s.analysis == Analysis::kInverseDynamics;
  const bool dynamics = s.analysis == Analysis::kDynamics;
  auto only = [&](const char *key, bool applies, const char *which) {
    if (doc->get(key) && !applies) fail(q(key) + " applies to " + which + " only");
  };

  s.options = legsim_default_options();
  static const char *const kIntegrators[] = {"rk4", "generalized_alpha"};
  s.options.integrator = choice(doc, "integrator", kIntegrators, 2, "rk4") == "rk4"
                             ? LEGSIM_INTEGRATOR_RK4
                             : LEGSIM_INTEGRATOR_GENERALIZED_ALPHA;
  // The step size in whole nanoseconds, 1 us .. 100 ms: what the DBC's RESET carries.
  const double h = get_real(doc, "step_s", "", false, 0.001);
  const double h_ns = std::round(h * 1e9);
  if (!(h > 0) || std::fabs(h_ns / 1e9 - h) > 1e-15 || h_ns < 1000 || h_ns > 1e8)
    fail("'step_s' must be a whole number of ns in 1 us .. 100 ms (got " + num(h) + ")");
  s.step_ns = static_cast<int64_t>(h_ns);
  s.options.step_s = h;
  s.options.rho_inf = get_real(doc, "rho_inf", "", false, s.options.rho_inf);
  if (!(s.options.rho_inf >= 0 && s.options.rho_inf <= 1))
    fail("'rho_inf' must be in [0, 1] (got " + num(s.options.rho_inf) + ")");
  s.options.max_newton_iter =
      static_cast<int32_t>(get_int(doc, "max_newton_iter", "", s.options.max_newton_iter, 1, 1000));
  s.options.newton_tol = get_real(doc, "newton_tol", "", false, s.options.newton_tol);
  if (!(s.options.newton_tol >= LEGSIM_MIN_NEWTON_TOL && s.options.newton_tol <= LEGSIM_MAX_NEWTON_TOL))
    fail("'newton_tol' must be in [" + num(LEGSIM_MIN_NEWTON_TOL) + ", " + num(LEGSIM_MAX_NEWTON_TOL) +
         "] (m, rad; got " + num(s.options.newton_tol) + ")");

  if (Node dv = doc->get("disable")) {
    const toml::array *a = dv->as_array();
    if (!a) fail("'disable' must be an array of names");
    for (auto &&e : *a) {
      if (!e.is_string()) fail("'disable' must be an array of names");
      const std::string name(*e.value<std::string_view>());
      bool ok = false;
      for (const auto &f : kDisable)
        if (name == f.name) {
          s.options.disable |= f.flag;
          ok = true;
        }
      if (!ok)
        fail("'disable': unknown " + q(name) +
             " (expected gravity, force_elements, reactions, projection, actuators or stroke_limits)");
    }
  }

  only("duration", timed, "dynamics and inverse_dynamics");
  only("record_every", timed, "dynamics and inverse_dynamics");
  if (timed) {
    s.duration_s = get_real(doc, "duration", "", true, 0);
    if (!(s.duration_s > 0)) fail("'duration' must be > 0 (got " + num(s.duration_s) + ")");
    // A whole number of steps, or refused: a run never ends at a time other than the one asked.
    const double n = std::floor(s.duration_s * 1e9 / h_ns + 0.5);
    if (std::fabs(n * h_ns / 1e9 - s.duration_s) > kGridTolS) {
      const double lo = std::floor(s.duration_s * 1e9 / h_ns);
      fail("'duration' " + num(s.duration_s) + " s is not a whole number of steps of " + num(h) + " s (" +
           num(lo * h_ns / 1e9) + " or " + num((lo + 1) * h_ns / 1e9) + " s would be)");
    }
    if (n < 1 || n > 1e9) fail("'duration' / 'step_s' must give 1 to 1e9 steps (got " + num(n) + ")");
    s.n_steps = static_cast<int64_t>(n);
    s.record_every = get_int(doc, "record_every", "", 1, 1, kMaxRecordEvery);
    if (s.n_steps / s.record_every + 1 > kMaxSamples)
      fail("'duration' / ('step_s' x 'record_every') asks for " + std::to_string(s.n_steps / s.record_every + 1) +
           " samples, more than " + std::to_string(kMaxSamples) + ": raise 'record_every'");
  }

  if (Node pv = doc->get("pose")) {
    if (!pv->is_string()) fail("'pose' must be the name of a pose of the model (e.g. pose = \"stand\")");
    s.pose = std::string(*pv->value<std::string_view>());
  }
  if (Node lv = doc->get("lengths")) {
    if (s.analysis == Analysis::kStaticsSweep) fail("'lengths' does not apply to statics_sweep");
    const toml::array *a = lv->as_array();
    if (!a) fail("'lengths' must be an array of numbers (m), one per actuator");
    for (auto &&e : *a) s.lengths.push_back(real_of(&e, "'lengths'"));
    s.has_lengths = true;
  }
  only("grid", s.analysis == Analysis::kStaticsSweep, "statics_sweep");
  // The rule that fixes a two-foot stance's statics (a model with contacts: bind_scene).
  only("statics_rule", s.analysis == Analysis::kStatics || s.analysis == Analysis::kInverseDynamics,
       "statics and inverse_dynamics");
  s.statics_rule_given = doc->get("statics_rule") != nullptr;
  static const char *const kRules[] = {"equal_friction", "min_tangential"};
  s.options.statics_rule = choice(doc, "statics_rule", kRules, 2, "equal_friction") == "equal_friction"
                               ? LEGSIM_STATICS_EQUAL_FRICTION
                               : LEGSIM_STATICS_MIN_TANGENTIAL;
  s.grid = static_cast<int32_t>(get_int(doc, "grid", "", 11, 2, 1000));
  // The feet's transitions in a step (a model with contacts: bind_scene).
  only("contact_law", dynamics, "dynamics");
  s.contact_law_given = doc->get("contact_law") != nullptr;
  static const char *const kLaws[] = {"lcp", "paper"};
  s.options.contact_law =
      choice(doc, "contact_law", kLaws, 2, "lcp") == "lcp" ? LEGSIM_CONTACT_LCP : LEGSIM_CONTACT_PAPER;

  // A load on a robot's box (a model with contacts: bind_scene): [Fx, Fy] N at its centre and
  // M N m, two force elements added to the model (box_load_add).
  only("box_load", dynamics || s.analysis == Analysis::kStatics || s.analysis == Analysis::kInverseDynamics,
       "statics, dynamics and inverse_dynamics");
  if (Node bv = doc->get("box_load")) {
    const toml::array *a = bv->as_array();
    if (!a || a->size() != 3) fail("'box_load' must be [Fx, Fy, M] (N, N, N m: a load on the box)");
    for (int i = 0; i < 3; ++i) {
      s.box_load[i] = real_of(a->get(i), "'box_load'");
      if (std::fabs(s.box_load[i]) > LEGSIM_MAX_FORCE_N)
        fail("'box_load' must be within +-" + num(LEGSIM_MAX_FORCE_N) + " (N, N, N m)");
    }
    s.has_box_load = true;
  }

  only("init", dynamics, "dynamics");
  static const char *const kInits[] = {"zero_force", "hold_length"};
  s.init = choice(doc, "init", kInits, 2, "zero_force") == "zero_force" ? ActuatorInit::kZeroForce
                                                                          : ActuatorInit::kHoldLength;
  // The bench's keys: the command watchdog of the CAN link, bad frames, the checks.
  only("cmd_timeout_ms", dynamics, "dynamics (over CAN)");
  only("safe_state", dynamics, "dynamics (over CAN)");
  only("inject", dynamics, "dynamics (over CAN)");
  s.cmd_timeout_ms = get_int(doc, "cmd_timeout_ms", "", 0, 0, 65534);
  s.safe_state = choice(doc, "safe_state", kInits, 2, "zero_force");
  if (Node iv = doc->get("inject")) {
    const toml::array *a = iv->as_array();
    if (!a || !a->is_array_of_tables()) fail("'inject' must be an array of tables ([[inject]])");
  }
  if (Node cv = doc->get("checks"))
    if (!cv->is_table()) fail("'checks' must be a table ([checks])");

  if (Node fv = doc->get("forces")) {
    Table ft = fv->as_table();
    if (!ft) fail("'forces' must be a table: NAME = [Fx, Fy] or NAME = torque");
    for (auto &&kv : *ft) {
      ForceValue f;
      f.name = std::string(kv.first.str());
      const std::string w = "forces." + f.name;
      if (is_number(&kv.second)) {
        f.n = 1;
        f.value[0] = real_of(&kv.second, w);
      } else if (const toml::array *a = kv.second.as_array()) {
        if (a->size() < 1 || a->size() > 2) fail(w + " must be a number or an array of 1 or 2 numbers");
        f.n = static_cast<int>(a->size());
        for (int i = 0; i < f.n; ++i) f.value[i] = real_of(a->get(i), w);
      } else {
        fail(w + " must be a number or an array of 1 or 2 numbers");
      }
      for (int i = 0; i < f.n; ++i)
        if (std::fabs(f.value[i]) > LEGSIM_MAX_FORCE_N)
          fail(w + " must be within +-" + num(LEGSIM_MAX_FORCE_N) + " (N or N m; got " + num(f.value[i]) + ")");
      s.forces.push_back(f);
    }
  }

  if (Node cv = doc->get("command")) {
    if (!timed) fail("[[command]] applies to dynamics and inverse_dynamics only");
    const toml::array *a = cv->as_array();
    if (!a) fail("'command' must be an array of tables ([[command]])");
    int k = 0;
    for (auto &&e : *a) {
      ++k;
      Table ct = e.as_table();
      if (!ct) fail("'command' must be an array of tables ([[command]])");
      const std::string w0 = "command #" + std::to_string(k) + ": ";
      check_keys(ct, {"actuator", "mode", "value", "sinusoid", "step"}, w0);
      Command c;
      c.actuator = get_string(ct, "actuator", w0, true);
      const std::string w = "command " + q(c.actuator) + ": ";
      for (const Command &o : s.commands)
        if (o.actuator == c.actuator) fail(w + "a second command for the same actuator");
      const std::string mode = get_string(ct, "mode", w, true);
      if (mode == "force")
        c.mode = LEGSIM_ACTUATOR_FORCE;
      else if (mode == "length")
        c.mode = LEGSIM_ACTUATOR_LENGTH;
      else
        fail(w + "'mode' must be force or length (got " + q(mode) + ")");
      if (s.analysis == Analysis::kInverseDynamics && c.mode != LEGSIM_ACTUATOR_LENGTH)
        fail(w + "inverse_dynamics prescribes lengths: use mode = \"length\"");
      c.signal = parse_signal(ct, w);
      if (c.signal.kind == Signal::kInitial && c.mode != LEGSIM_ACTUATOR_LENGTH)
        fail(w + "value = \"initial\" is for mode = \"length\" (hold the assembled length)");
      if (c.signal.kind == Signal::kStep) on_grid(c.signal.t0, s.step_ns, w + "step t0 =");
      s.commands.push_back(c);
    }
  }

  if (Node cv = doc->get("contact")) {
    if (!dynamics && s.analysis != Analysis::kAssembly)
      fail("[[contact]] applies to dynamics and assembly only");
    const toml::array *a = cv->as_array();
    if (!a || !a->is_array_of_tables()) fail("'contact' must be an array of tables ([[contact]])");
    int k = 0;
    for (auto &&e : *a) {
      ++k;
      Table ct = e.as_table();
      const std::string w0 = "contact #" + std::to_string(k) + ": ";
      check_keys(ct, {"name", "state"}, w0);
      ContactInit c;
      c.name = get_string(ct, "name", w0, true);
      const std::string w = "contact " + q(c.name) + ": ";
      for (const ContactInit &o : s.contacts)
        if (o.name == c.name) fail(w + "a second [[contact]] for the same contact");
      const std::string state = get_string(ct, "state", w, true);
      if (state == "stuck")
        c.state = LEGSIM_CONTACT_STUCK;
      else if (state == "free")
        c.state = LEGSIM_CONTACT_FREE;
      else
        fail(w + "'state' must be stuck or free (got " + q(state) + ")");
      s.contacts.push_back(c);
    }
  }
}

bool read_text(const std::string &path, std::string &text, std::string &err) {
  std::ifstream f(path, std::ios::binary);
  if (!f) {
    err = path + ": cannot read: " + std::strerror(errno);
    return false;
  }
  // Read at most one byte past the limit: a larger file is refused without being held.
  text.resize(kTomlMaxBytes + 1);
  f.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<size_t>(f.gcount()));
  if (f.bad()) {
    err = path + ": cannot read: " + std::strerror(errno);
    return false;
  }
  return true;
}

}  // namespace

// ---- signals -------------------------------------------------------------------------
double Signal::at(double t) const {
  switch (kind) {
    case kSinusoid: return offset + amplitude * std::sin(kTwoPi * frequency_hz * t + phase_rad);
    case kStep: return t < t0 ? before : after;
    default: return value;
  }
}
double Signal::rate(double t) const {
  if (kind != kSinusoid) return 0;
  const double w = kTwoPi * frequency_hz;
  return amplitude * w * std::cos(w * t + phase_rad);
}
double Signal::accel(double t) const {
  if (kind != kSinusoid) return 0;
  const double w = kTwoPi * frequency_hz;
  return -amplitude * w * w * std::sin(w * t + phase_rad);
}
double Signal::min() const {
  switch (kind) {
    case kSinusoid: return frequency_hz > 0 ? offset - std::fabs(amplitude) : at(0);
    case kStep: return std::min(before, after);
    default: return value;
  }
}
double Signal::max() const {
  switch (kind) {
    case kSinusoid: return frequency_hz > 0 ? offset + std::fabs(amplitude) : at(0);
    case kStep: return std::max(before, after);
    default: return value;
  }
}

const char *init_name(ActuatorInit i) {
  return i == ActuatorInit::kZeroForce ? "zero_force" : "hold_length";
}

const char *analysis_name(Analysis a) {
  switch (a) {
    case Analysis::kDynamics: return "dynamics";
    case Analysis::kStatics: return "statics";
    case Analysis::kStaticsSweep: return "statics_sweep";
    case Analysis::kInverseDynamics: return "inverse_dynamics";
    case Analysis::kAssembly: return "assembly";
  }
  return "?";
}

const char *status_enum_name(legsim_status s) {
  switch (s) {
    case LEGSIM_OK: return "LEGSIM_OK";
    case LEGSIM_ERR_NULL: return "LEGSIM_ERR_NULL";
    case LEGSIM_ERR_STORAGE: return "LEGSIM_ERR_STORAGE";
    case LEGSIM_ERR_MODEL: return "LEGSIM_ERR_MODEL";
    case LEGSIM_ERR_CAPACITY: return "LEGSIM_ERR_CAPACITY";
    case LEGSIM_ERR_BAD_INPUT: return "LEGSIM_ERR_BAD_INPUT";
    case LEGSIM_ERR_OUT_OF_STROKE: return "LEGSIM_ERR_OUT_OF_STROKE";
    case LEGSIM_ERR_NOT_CONVERGED: return "LEGSIM_ERR_NOT_CONVERGED";
    case LEGSIM_ERR_SINGULAR: return "LEGSIM_ERR_SINGULAR";
    case LEGSIM_ERR_UNREACHABLE: return "LEGSIM_ERR_UNREACHABLE";
    case LEGSIM_ERR_NO_EQUILIBRIUM: return "LEGSIM_ERR_NO_EQUILIBRIUM";
    case LEGSIM_ERR_DISABLED: return "LEGSIM_ERR_DISABLED";
    case LEGSIM_ERR_STATE: return "LEGSIM_ERR_STATE";
    case LEGSIM_ERR_DIVERGED: return "LEGSIM_ERR_DIVERGED";
    case LEGSIM_ERR_CONTACT: return "LEGSIM_ERR_CONTACT";
  }
  return "LEGSIM_ERR_UNKNOWN";
}

bool load_scene(const std::string &path, Scene &scene, std::string &err) {
  try {
    std::string text;
    if (!read_text(path, text, err)) return false;
    std::string why;
    if (!toml_input_within_limits(text, why)) {
      err = path + ": TOML input refused: " + why;
      return false;
    }
    Scene s;
    s.path = path;
#if TOML_EXCEPTIONS
    toml::table doc;
    try {
      doc = toml::parse(std::string_view(text), std::string_view(path));
    } catch (const toml::parse_error &e) {
      err = path + ": TOML syntax error: " + std::string(e.description()) + " (at line " +
            std::to_string(e.source().begin.line) + ", column " +
            std::to_string(e.source().begin.column) + ")";
      return false;
    }
#else
    toml::parse_result r = toml::parse(std::string_view(text), std::string_view(path));
    if (!r) {
      err = path + ": TOML syntax error: " + std::string(r.error().description());
      return false;
    }
    toml::table doc = std::move(r.table());
#endif
    parse_scene(&doc, s);
    scene = std::move(s);
    return true;
  } catch (const SceneError &e) {
    err = path + ": " + e.message;
  } catch (const std::exception &e) {
    err = path + ": " + e.what();
  } catch (...) {
    err = path + ": unexpected error";
  }
  return false;
}

bool box_load_add(legsim_model_desc &d, const double load[3], std::string &why) {
  if (d.n_contacts < 1) {
    why = "the model has no box (no contacts)";
    return false;
  }
  if (d.n_forces + 2 > LEGSIM_MAX_FORCES) {
    why = "needs 2 force elements beyond the model's " + std::to_string(d.n_forces) + " (this build holds " +
          std::to_string(LEGSIM_MAX_FORCES) + ")";
    return false;
  }
  for (int32_t i = 0; i < d.n_forces; ++i)
    for (const char *n : {kBoxLoadName, kBoxMomentName})
      if (strncmp(d.force[i].name, n, LEGSIM_NAME_LEN) == 0) {
        why = std::string("the model has a force element named ") + q(n) + " already";
        return false;
      }
  for (int k = 0; k < 2; ++k) {
    legsim_force_desc &f = d.force[d.n_forces + k];
    f = legsim_force_desc{};
    std::snprintf(f.name, LEGSIM_NAME_LEN, "%s", k == 0 ? kBoxLoadName : kBoxMomentName);
    f.kind = k == 0 ? LEGSIM_FORCE_POINT : LEGSIM_FORCE_TORQUE;
    f.body[0] = 0;  // the box is body 0 of a robot file
    f.body[1] = LEGSIM_FRAME;
    f.value[0] = k == 0 ? load[0] : load[2];
    f.value[1] = k == 0 ? load[1] : 0;
  }
  d.n_forces += 2;
  return true;
}

bool bind_scene(Scene &s, const legsim_model_desc &m, std::string &err) {
  try {
    auto name_of = [](const char (&n)[LEGSIM_NAME_LEN]) { return std::string(n, strnlen(n, LEGSIM_NAME_LEN)); };
    // pose
    s.pose_index = -1;
    if (!s.pose.empty()) {
      for (int32_t p = 0; p < m.n_poses; ++p)
        if (name_of(m.pose[p].name) == s.pose) s.pose_index = p;
      if (s.pose_index < 0) {
        std::string list;
        for (int32_t p = 0; p < m.n_poses; ++p) list += (p ? ", " : "") + name_of(m.pose[p].name);
        fail("pose " + q(s.pose) + " is not in the model (poses: " + (list.empty() ? "none" : list) + ")");
      }
    } else if (m.n_poses > 0) {
      s.pose_index = 0;
    }
    if (s.pose_index < 0 && !s.has_lengths && s.analysis != Analysis::kStaticsSweep)
      fail("the model has no pose to assemble: give 'lengths'");
    if (s.pose_index < 0 && s.analysis == Analysis::kStaticsSweep)
      fail("statics_sweep starts from a pose, and the model has none");
    // lengths
    if (s.has_lengths) {
      if (static_cast<int32_t>(s.lengths.size()) != m.n_actuators)
        fail("'lengths' must hold " + std::to_string(m.n_actuators) + " values, one per actuator (got " +
             std::to_string(s.lengths.size()) + ")");
      for (int32_t a = 0; a < m.n_actuators; ++a) {
        const auto &ad = m.actuator[a];
        if (s.lengths[a] < ad.stroke_min_m || s.lengths[a] > ad.stroke_max_m)
          fail("lengths[" + std::to_string(a) + "] = " + num(s.lengths[a]) +
               " m is outside the stroke of actuator " + q(name_of(ad.name)) + " [" +
               num(ad.stroke_min_m) + ", " + num(ad.stroke_max_m) + "]");
      }
    }
    if (s.analysis == Analysis::kStaticsSweep && m.n_actuators < 2)
      fail("statics_sweep needs two actuators (the model has " + std::to_string(m.n_actuators) + ")");
    // force values
    for (auto &f : s.forces) {
      f.index = -1;
      for (int32_t i = 0; i < m.n_forces; ++i)
        if (name_of(m.force[i].name) == f.name) f.index = i;
      if (f.index < 0) fail("forces." + f.name + ": the model has no force element " + q(f.name));
      const legsim_force_kind k = m.force[f.index].kind;
      if (k == LEGSIM_FORCE_SPRING_DAMPER)
        fail("forces." + f.name + ": a spring_damper has no value to set");
      if (k == LEGSIM_FORCE_POINT && f.n != 2)
        fail("forces." + f.name + ": a point force takes [Fx, Fy] (N)");
      if (k == LEGSIM_FORCE_TORQUE && f.n != 1)
        fail("forces." + f.name + ": a torque takes one value (N m)");
    }
    // contacts: a robot's feet (stuck or free in assembly and dynamics; stuck in statics and
    // inverse dynamics)
    if (m.n_contacts > 0 && s.analysis == Analysis::kStaticsSweep)
      fail("statics_sweep of a model with contacts is not in this core yet (the legs move, the feet "
           "cannot stay on the ground): run dynamics, statics, inverse_dynamics or assembly");
    if (s.has_box_load) {
      if (m.n_contacts == 0) fail("'box_load' applies to a model with contacts only (the robot's box)");
      std::string why;
      const auto probe = std::make_unique<legsim_model_desc>(m);
      if (!box_load_add(*probe, s.box_load, why)) fail("'box_load': " + why);
    }
    if (m.n_contacts == 0 && s.statics_rule_given)
      fail("'statics_rule' applies to a model with contacts only (a stance on two feet)");
    if (m.n_contacts == 0 && s.contact_law_given)
      fail("'contact_law' applies to a model with contacts only (a robot's feet)");
    for (size_t c = 0; c < s.contacts.size(); ++c) {
      ContactInit &ci = s.contacts[c];
      ci.index = -1;
      std::string list;
      for (int32_t k = 0; k < m.n_contacts; ++k) {
        list += (k ? ", " : "") + name_of(m.contact[k].name);
        if (name_of(m.contact[k].name) == ci.name) ci.index = k;
      }
      if (ci.index < 0)
        fail("contact " + q(ci.name) + ": the model has no contact " + q(ci.name) + " (contacts: " +
             (list.empty() ? "none" : list) + ")");
    }
    // commands
    for (size_t c = 0; c < s.commands.size(); ++c) {
      Command &cmd = s.commands[c];
      cmd.index = -1;
      for (int32_t a = 0; a < m.n_actuators; ++a)
        if (name_of(m.actuator[a].name) == cmd.actuator) cmd.index = a;
      const std::string w = "command " + q(cmd.actuator) + ": ";
      if (cmd.index < 0) fail(w + "the model has no actuator " + q(cmd.actuator));
      for (size_t o = 0; o < c; ++o)
        if (s.commands[o].index == cmd.index) fail(w + "the actuator is commanded twice");
      const auto &ad = m.actuator[cmd.index];
      if (cmd.signal.kind == Signal::kInitial) {
        // the assembled length: in the stroke by construction
      } else if (cmd.mode == LEGSIM_ACTUATOR_LENGTH) {
        if (cmd.signal.min() < ad.stroke_min_m || cmd.signal.max() > ad.stroke_max_m)
          fail(w + "lengths " + num(cmd.signal.min()) + ".." + num(cmd.signal.max()) +
               " m leave the stroke [" + num(ad.stroke_min_m) + ", " + num(ad.stroke_max_m) + "]");
      } else if (std::max(std::fabs(cmd.signal.min()), std::fabs(cmd.signal.max())) > ad.max_force_n) {
        fail(w + "forces up to " + num(std::max(std::fabs(cmd.signal.min()), std::fabs(cmd.signal.max()))) +
             " N exceed max_force " + num(ad.max_force_n) + " N");
      }
    }
    return true;
  } catch (const SceneError &e) {
    err = s.path + ": " + e.message;
  } catch (const std::exception &e) {
    err = s.path + ": " + e.what();
  }
  return false;
}

// ---- running ---------------------------------------------------------------------------
namespace {

struct Storage {
  void *p = nullptr;
  explicit Storage(size_t n) {
    const size_t a = LEGSIM_STORAGE_ALIGN;
    p = std::aligned_alloc(a, (n + a - 1) / a * a);
  }
  ~Storage() { std::free(p); }
  Storage(const Storage &) = delete;
  Storage &operator=(const Storage &) = delete;
};

std::string call_failed(const std::string &what, legsim_status st) {
  return what + ": " + status_enum_name(st) + " (" + legsim_status_str(st) + ")";
}

// Reads the sim's state into a sample; forces: from the analysis (or NULL: the sim's).
void record(legsim_sim *sim, const legsim_model_desc &m, double t, const legsim_real *forces,
            Sample &s) {
  s = Sample{};
  s.t = t;
  const int32_t nq = legsim_n_coords(sim), na = legsim_n_actuators(sim), nj = legsim_n_joints(sim),
                nc = legsim_n_constraints(sim);
  std::vector<legsim_real> buf(std::max({nq, na, 3 * nj, nc, 1}));
  legsim_get_q(sim, buf.data());
  s.q.assign(buf.begin(), buf.begin() + nq);
  if (na > 0) {
    std::vector<legsim_real> len(na), rate(na), f(na);
    legsim_actuator_lengths(sim, len.data(), rate.data());
    if (forces)
      std::copy(forces, forces + na, f.begin());
    else
      legsim_actuator_forces(sim, f.data());
    s.length.assign(len.begin(), len.end());
    s.rate.assign(rate.begin(), rate.end());
    s.force.assign(f.begin(), f.end());
  }
  std::vector<legsim_reaction> r(std::max(nj, 1));
  if (nj > 0 && legsim_reactions(sim, r.data()) == LEGSIM_OK) {
    s.has_reactions = true;
    for (int32_t j = 0; j < nj; ++j) {
      s.reaction.push_back(r[j].force_n[0]);
      s.reaction.push_back(r[j].force_n[1]);
      s.reaction.push_back(r[j].moment_nm);
    }
  }
  if (m.foot_body >= 0) {
    legsim_real xy[2];
    if (legsim_foot_position(sim, xy) == LEGSIM_OK) {
      s.has_foot = true;
      s.foot[0] = xy[0];
      s.foot[1] = xy[1];
    }
  }
  if (const int32_t nk = legsim_n_contacts(sim); nk > 0) {
    s.contacts.resize(nk);
    if (legsim_contacts(sim, s.contacts.data()) != LEGSIM_OK) s.contacts.clear();
  }
  legsim_real max_abs = 0;
  if (legsim_constraints(sim, buf.data(), &max_abs) == LEGSIM_OK) s.residual = max_abs;
  legsim_report rep;
  if (legsim_get_report(sim, &rep) == LEGSIM_OK) {
    s.iterations = rep.iterations;
    s.condition = rep.condition;
    s.events = rep.events;
  }
  legsim_clear_events(sim);
}

legsim_status run(const Scene &sc, const legsim_model_desc &m, ResultWriter &out, Result &res) {
  Storage storage(legsim_sim_size());
  if (!storage.p) {
    res.error = "out of memory";
    return LEGSIM_ERR_STORAGE;
  }
  legsim_sim *sim = nullptr;
  // box_load: the description with the box's two force elements (it must outlive the sim)
  std::unique_ptr<legsim_model_desc> loaded;
  if (sc.has_box_load) {
    loaded.reset(new legsim_model_desc(m));
    std::string why;
    if (!box_load_add(*loaded, sc.box_load, why)) {
      res.error = "box_load: " + why;
      return LEGSIM_ERR_CAPACITY;
    }
  }
  legsim_status st =
      legsim_init(storage.p, legsim_sim_size(), loaded ? loaded.get() : &m, &sc.options, &sim);
  if (st != LEGSIM_OK) {
    res.error = call_failed("legsim_init", st);
    return st;
  }
  for (const auto &f : sc.forces) {
    legsim_real v[2] = {static_cast<legsim_real>(f.value[0]), static_cast<legsim_real>(f.value[1])};
    st = legsim_set_force(sim, f.index, v);
    if (st != LEGSIM_OK) {
      res.error = call_failed("setting force " + q(f.name), st);
      return st;
    }
  }
  if (sc.pose_index >= 0) {
    st = legsim_assemble_pose(sim, sc.pose_index);
    if (st != LEGSIM_OK) {
      res.error = call_failed("assembling pose " + q(m.pose[sc.pose_index].name), st);
      return st;
    }
  }
  const int32_t na = legsim_n_actuators(sim);
  const int32_t nk = legsim_n_contacts(sim);
  if (nk > 0) {
    // A robot stands on the ground: the feet on the line, their midpoint where the pose put
    // it (its guess has them there), the box pose following; every contact stuck.
    std::vector<legsim_contact> c(nk);
    st = legsim_contacts(sim, c.data());
    double mid = 0;
    const legsim_ground_desc &g = m.ground;
    for (const auto &k : c)
      mid += ((k.position[0] - g.point[0]) * std::cos(g.slope_rad) +
              (k.position[1] - g.point[1]) * std::sin(g.slope_rad)) / nk;
    std::vector<legsim_real> len(sc.lengths.begin(), sc.lengths.end());
    if (st == LEGSIM_OK)
      st = legsim_assemble_on_ground(sim, sc.has_lengths ? len.data() : nullptr, static_cast<legsim_real>(mid));
    if (st != LEGSIM_OK) {
      std::string l;
      for (size_t i = 0; i < sc.lengths.size(); ++i) l += (i ? ", " : "") + num(sc.lengths[i]);
      res.error = call_failed(sc.has_lengths ? "assembling on the ground at the lengths [" + l + "]"
                                             : std::string("assembling on the ground"), st);
      return st;
    }
    for (const auto &ci : sc.contacts) {
      st = legsim_set_contact_state(sim, ci.index, ci.state);
      if (st != LEGSIM_OK) {
        res.error = call_failed("setting contact " + q(ci.name) + " " +
                                    (ci.state == LEGSIM_CONTACT_FREE ? "free" : "stuck"), st);
        return st;
      }
    }
  } else if (sc.has_lengths) {
    std::vector<legsim_real> len(sc.lengths.begin(), sc.lengths.end());
    st = legsim_assemble(sim, len.data());
    if (st != LEGSIM_OK) {
      std::string l;
      for (size_t i = 0; i < sc.lengths.size(); ++i) l += (i ? ", " : "") + num(sc.lengths[i]);
      res.error = call_failed("assembling the lengths [" + l + "]", st);
      return st;
    }
  }
  std::vector<legsim_real> forces(std::max(na, 1)), assembled(std::max(na, 1));
  if (na > 0) legsim_actuator_lengths(sim, assembled.data(), nullptr);
  // value = "initial": the length each actuator was assembled at
  std::vector<Command> commands = sc.commands;
  for (Command &c : commands)
    if (c.signal.kind == Signal::kInitial) c.signal.value = assembled[c.index];
  Sample sample;
  auto emit = [&](double t, const legsim_real *f) {
    record(sim, m, t, f, sample);
    out.sample(sample);
    ++res.n_samples;
  };

  switch (sc.analysis) {
    case Analysis::kAssembly:
      emit(legsim_time(sim), nullptr);
      return LEGSIM_OK;

    case Analysis::kStatics:
      st = legsim_statics(sim, forces.data());
      if (st != LEGSIM_OK) {
        res.error = call_failed("statics", st);
        return st;
      }
      emit(legsim_time(sim), forces.data());
      return LEGSIM_OK;

    case Analysis::kStaticsSweep:
      st = legsim_statics_sweep(sim, sc.grid, &res.worst);
      if (st != LEGSIM_OK) {
        res.error = call_failed("statics sweep", st);
        return st;
      }
      res.has_worst_case = true;
      return LEGSIM_OK;

    case Analysis::kInverseDynamics: {
      // Uncommanded actuators hold their assembled length; a robot's (feet stuck) follow: their
      // motion comes from the commanded lengths and the feet (legsim_inverse_dynamics_on_ground).
      uint32_t follow = 0;
      if (nk > 0) {
        follow = (1u << na) - 1;
        for (const auto &c : commands) follow &= ~(1u << c.index);
      }
      std::vector<legsim_real> len(std::max(na, 1)), rate(std::max(na, 1)), acc(std::max(na, 1));
      for (int64_t k = 0; k <= sc.n_steps; ++k) {
        const double t = static_cast<double>(k * sc.step_ns) / 1e9;
        for (int32_t a = 0; a < na; ++a) {
          len[a] = assembled[a];
          rate[a] = acc[a] = 0;
        }
        for (const auto &c : commands) {
          len[c.index] = static_cast<legsim_real>(c.signal.at(t));
          rate[c.index] = static_cast<legsim_real>(c.signal.rate(t));
          acc[c.index] = static_cast<legsim_real>(c.signal.accel(t));
        }
        st = nk > 0 ? legsim_inverse_dynamics_on_ground(sim, follow, len.data(), rate.data(), acc.data(),
                                                        forces.data())
                    : legsim_inverse_dynamics(sim, len.data(), rate.data(), acc.data(), forces.data());
        if (st != LEGSIM_OK) {
          res.failed_at_s = t;
          res.error = call_failed("inverse dynamics at t = " + num(t) + " s", st);
          return st;
        }
        if (k % sc.record_every == 0 || k == sc.n_steps) emit(t, forces.data());
      }
      return LEGSIM_OK;
    }

    case Analysis::kDynamics: {
      // init: what every actuator does until a command says otherwise
      for (int32_t a = 0; a < na; ++a) {
        st = sc.init == ActuatorInit::kHoldLength ? legsim_command_length(sim, a, assembled[a])
                                                   : legsim_command_force(sim, a, 0);
        if (st != LEGSIM_OK) {
          res.error = call_failed(std::string("init = ") + init_name(sc.init), st);
          return st;
        }
      }
      auto apply = [&](double t) -> legsim_status {
        for (const auto &c : commands) {
          const legsim_real v = static_cast<legsim_real>(c.signal.at(t));
          const legsim_status s2 = c.mode == LEGSIM_ACTUATOR_FORCE ? legsim_command_force(sim, c.index, v)
                                                                  : legsim_command_length(sim, c.index, v);
          if (s2 != LEGSIM_OK) {
            res.failed_at_s = t;
            res.error = call_failed("command " + q(c.actuator) + " at t = " + num(t) + " s", s2);
            return s2;
          }
        }
        return LEGSIM_OK;
      };
      st = apply(0.0);
      if (st != LEGSIM_OK) return st;
      // A robot's first sample: the assembly's multipliers are not the dynamics' forces
      // (the first step solves those), so its reactions and ground forces are null, as the
      // leg's reactions are.
      record(sim, m, legsim_time(sim), nullptr, sample);
      if (legsim_n_contacts(sim) > 0) {
        sample.has_reactions = false;
        sample.contact_forces = false;
      }
      out.sample(sample);
      ++res.n_samples;
      for (int64_t k = 1; k <= sc.n_steps; ++k) {
        const double t = legsim_time(sim);
        st = apply(t);
        if (st != LEGSIM_OK) return st;
        st = legsim_step(sim, 1);
        if (st != LEGSIM_OK) {
          res.failed_at_s = t;
          res.error = call_failed("step from t = " + num(t) + " s", st);
          return st;
        }
        if (k % sc.record_every == 0 || k == sc.n_steps) emit(legsim_time(sim), nullptr);
      }
      return LEGSIM_OK;
    }
  }
  return LEGSIM_OK;
}

// ---- writing ---------------------------------------------------------------------------
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

std::string name_of(const char (&n)[LEGSIM_NAME_LEN]) { return std::string(n, strnlen(n, LEGSIM_NAME_LEN)); }

// The names of legsim.h's event bits (python/legsim/sim.py EVENTS, the bench's
// legsim_bench.analyses.EVENT_NAMES say the same), in bit order.
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
double contact_number(const legsim_contact &c, int i) {
  const legsim_real v[] = {c.normal_n, c.tangential_n, c.friction_use, c.position[0],
                           c.position[1], c.slip_mps, c.impulse_ns[0], c.impulse_ns[1]};
  return v[i];
}
constexpr int kNContactNumbers = 8;
constexpr int kNContactForces = 3;  // normal, tangential, friction_use: from a solve

}  // namespace

legsim_status run_scene(const Scene &scene, const legsim_model_desc &model, ResultWriter &writer,
                        Result &result) {
  result = Result{};
  try {
    writer.begin();
    result.status = run(scene, model, writer, result);
  } catch (const std::exception &e) {
    result.status = LEGSIM_ERR_STORAGE;
    result.error = e.what();
  } catch (...) {
    result.status = LEGSIM_ERR_STORAGE;
    result.error = "unexpected error";
  }
  try {
    writer.end(result);
  } catch (...) {
    // the stream's own state tells the caller (a failed write)
  }
  return result.status;
}

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
    }
    o << "}";
  }
  o << "}, \"contacts\": {";
  for (size_t i = 0; i < sc.contacts.size(); ++i)
    o << (i ? ", " : "") << jstr(sc.contacts[i].name) << ": "
      << jstr(sc.contacts[i].state == LEGSIM_CONTACT_FREE ? "free" : "stuck");
  o << "}, \"box_load\": ";
  if (sc.has_box_load)
    o << "[" << jnum(sc.box_load[0]) << ", " << jnum(sc.box_load[1]) << ", " << jnum(sc.box_load[2]) << "]";
  else
    o << "null";
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
    o_ << "item,kind,max_force";
    for (int a = 0; a < m.n_actuators; ++a) o_ << ",at_" << csv_field(name_of(m.actuator[a].name));
    o_ << ",status\n";
    return;
  }
  o_ << "t";
  for (int b = 0; b < m.n_bodies; ++b)
    for (int c = 0; c < 3; ++c) o_ << "," << csv_field(name_of(m.body[b].name) + "." + kXyz[c]);
  for (int a = 0; a < m.n_actuators; ++a) {
    const std::string n = name_of(m.actuator[a].name);
    o_ << "," << csv_field(n + ".length") << "," << csv_field(n + ".rate") << "," << csv_field(n + ".force");
  }
  for (int j = 0; j < m.n_joints; ++j) {
    const std::string n = name_of(m.joint[j].name);
    o_ << "," << csv_field(n + ".fx") << "," << csv_field(n + ".fy") << "," << csv_field(n + ".moment");
  }
  if (m.foot_body >= 0) o_ << ",foot.x,foot.y";
  for (int k = 0; k < m.n_contacts; ++k) {
    const std::string n = name_of(m.contact[k].name);
    o_ << "," << csv_field(n + ".state");
    for (int i = 0; i < kNContactNumbers; ++i) o_ << "," << csv_field(n + "." + kContactNumbers[i]);
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
