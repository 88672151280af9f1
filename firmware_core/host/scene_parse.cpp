// Scene files: parsing (toml++) and checking a scene, and binding it to a model.
// Host only; uses the C API only.
#include "scene_text.hpp"
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

using scene_text::num;
using scene_text::q;

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

// The bench's sections as JSON for --check. JSON has no nan or inf: a non-finite number (a
// bad input an injection sends on purpose) is the string "nan", "inf" or "-inf".
void bench_json_to(std::ostream &o, const toml::node &n) {
  if (const toml::table *t = n.as_table()) {
    o << "{";
    bool first = true;
    for (auto &&kv : *t) {
      o << (first ? "" : ", ") << toml::json_formatter{toml::value<std::string>(std::string(kv.first.str()))}
        << ": ";
      bench_json_to(o, kv.second);
      first = false;
    }
    o << "}";
  } else if (const toml::array *a = n.as_array()) {
    o << "[";
    for (size_t i = 0; i < a->size(); ++i) {
      o << (i ? ", " : "");
      bench_json_to(o, *a->get(i));
    }
    o << "]";
  } else if (n.is_floating_point()) {
    const double v = n.as_floating_point()->get();
    char buf[40];
    if (std::isnan(v)) std::snprintf(buf, sizeof buf, "\"nan\"");
    else if (std::isinf(v)) std::snprintf(buf, sizeof buf, v > 0 ? "\"inf\"" : "\"-inf\"");
    else std::snprintf(buf, sizeof buf, "%.17g", v);
    o << buf;
  } else {
    o << toml::json_formatter{n, toml::format_flags::quote_dates_and_times};
  }
}
std::string bench_json(const toml::node &n) {
  std::ostringstream o;
  bench_json_to(o, n);
  return o.str();
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
    s.inject_json = bench_json(*iv);
  }
  if (Node cv = doc->get("checks")) {
    if (!cv->is_table()) fail("'checks' must be a table ([checks])");
    s.checks_json = bench_json(*cv);
  }

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

}  // namespace legsim_host
