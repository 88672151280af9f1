// Scene files: parsing (toml++) and checking a scene, and binding it to a model.
// Host only; uses the C API only.
#include "scene_text.hpp"
#include "scene_read.hpp"
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
// [start]: the robot's rigid start motion (docs in scenes/README.md, [start])
constexpr double kMaxLiftM = 10.0;               // m above the stance
constexpr double kMaxTiltRad = LEGSIM_MAX_SLOPE_RAD;  // as the ground's slope
constexpr double kMaxStartSpeedMps = 100.0;      // each component of the box's velocity
constexpr double kMaxStartSpinRadps = 100.0;
constexpr double kMaxSlopeRad = LEGSIM_MAX_SLOPE_RAD;  // legsim_ground_desc's rule

// The contact events a command can switch on (legsim.h's bits).
struct EventName {
  const char *name;
  uint32_t bit;
};
const EventName kSwitchEvents[] = {{"touchdown", LEGSIM_EVENT_TOUCHDOWN},
                                   {"liftoff", LEGSIM_EVENT_LIFTOFF},
                                   {"stick_to_slip", LEGSIM_EVENT_STICK_TO_SLIP},
                                   {"slip_to_stick", LEGSIM_EVENT_SLIP_TO_STICK}};

using scene_read::check_keys;
using scene_read::fail;
using scene_read::is_number;
using scene_read::Node;
using scene_read::real_of;
using scene_read::SceneError;
using scene_read::Table;
using scene_read::to_double;

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
  const bool has_switch = t->get("switch") != nullptr;
  if (int(has_value) + int(has_sin) + int(has_step) + int(has_switch) != 1)
    fail(where + "give exactly one of 'value', 'sinusoid', 'step' or 'switch'");
  Signal s;
  if (has_switch) {
    Table st = t->get("switch")->as_table();
    if (!st) fail(where + "'switch' must be a table {event, contact, before, after}");
    const std::string w = where + "switch: ";
    check_keys(st, {"event", "contact", "before", "after"}, w);
    s.kind = Signal::kSwitch;
    s.event = get_string(st, "event", w, true);
    s.contact = get_string(st, "contact", w, true);
    s.before = get_real(st, "before", w, false, 0);
    s.after = get_real(st, "after", w, true, 0);
    std::string names;
    for (const auto &e : kSwitchEvents) {
      names += (names.empty() ? "" : ", ") + std::string(e.name);
      if (s.event == e.name) s.event_bit = e.bit;
    }
    if (s.event_bit == 0) fail(w + "'event' must be " + names + " (got " + q(s.event) + ")");
  } else if (has_value) {
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
// now: an old file gets a message naming the new key.
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
    // a float stays a float in JSON (1.0, not 1): readers that keep the type see TOML's
    if (std::isfinite(v) && !std::strpbrk(buf, ".e")) o << ".0";
  } else {
    o << toml::json_formatter{n, toml::format_flags::quote_dates_and_times};
  }
}
std::string bench_json(const toml::node &n) {
  std::ostringstream o;
  bench_json_to(o, n);
  return o.str();
}

// ---- the bench's sections: [[inject]] (bad input over CAN) and [checks] (its verdicts) ----

// Fault_Code of can/legsim.dbc (VAL_ ... Fault_Code), by value; tests/bench/test_scene.py
// compares this list with the DBC's.
const char *const kFaultCodes[] = {"NONE",      "UNKNOWN_ID", "BAD_LENGTH",  "NOT_FINITE", "OUT_OF_RANGE",
                                   "STALE_SEQ", "BAD_STATE",  "CMD_TIMEOUT", "SOLVER"};
// The bench -> hil_sim frames of can/legsim.dbc an injection may name (ids as the DBC's BO_).
struct InjectFrame {
  const char *name;
  int id;
};
const InjectFrame kInjectFrames[] = {{"CONTROL", 0x080}, {"ACT_CMD", 0x100}, {"LOAD_CMD", 0x110}};
const int kFdLengths[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64};

std::string upper(std::string v) {
  for (char &c : v) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return v;
}

std::string jstring(const std::string &v) {
  std::ostringstream o;
  o << toml::json_formatter{toml::value<std::string>(v)};
  return o.str();
}

// A time of the run as a step: on the grid and within 0 .. n_steps - 1.
int64_t step_in_run(Node v, const Scene &s, const std::string &w, const char *key) {
  const double t = real_of(v, w + q(key));
  const int64_t k = on_grid(t, s.step_ns, w + q(key) + " =");
  if (k < 0 || k >= s.n_steps)
    fail(w + q(key) + " = " + num(t) + " s is outside the run (0 .. " +
         num(static_cast<double>(s.n_steps) * s.step_ns / 1e9) + " s)");
  return k;
}

struct Injection {
  int64_t step;
  std::string json;
};

// [[inject]] resolved for the bench: the step, the frame's id, the expected Fault_Code name.
std::string parse_injections(const toml::array &a, const Scene &s) {
  std::vector<Injection> out;
  int k = 0;
  for (auto &&e : a) {
    ++k;
    Table x = e.as_table();
    const std::string w = "inject #" + std::to_string(k) + ": ";
    check_keys(x, {"at", "frame", "signals", "seq", "length", "expect", "expect_signal", "silence", "label"}, w);
    if (!x->get("at") || !x->get("expect")) fail(w + "needs 'at' (s) and 'expect' (a Fault_Code name)");
    Injection inj;
    inj.step = step_in_run(x->get("at"), s, w, "at");
    const std::string expect = upper(get_string(x, "expect", w, true));
    bool known = false;
    std::string codes;
    for (const char *c : kFaultCodes) {
      codes += (codes.empty() ? "" : ", ") + std::string(c);
      known = known || expect == c;
    }
    if (!known)
      fail(w + "'expect' = " + q(get_string(x, "expect", w, true)) + " is not a Fault_Code of the DBC (" + codes +
           ")");
    std::string label = get_string(x, "label", w, false);
    const std::string expect_signal = get_string(x, "expect_signal", w, false);
    std::ostringstream o;
    o << "{\"step\": " << inj.step << ", \"expect\": " << jstring(expect);
    if (Node sv = x->get("silence")) {
      if (x->get("frame")) fail(w + "give 'frame' or 'silence', not both");
      for (const char *key : {"signals", "seq", "length", "expect_signal"})
        if (x->get(key)) fail(w + q(key) + " applies to a frame, not to a silence");
      const double d = real_of(sv, w + "'silence'");
      if (!(d > 0)) fail(w + "'silence' must be > 0 (s; got " + num(d) + ")");
      const int64_t n = on_grid(d, s.step_ns, w + "'silence' =");
      if (s.cmd_timeout_ms == 0) fail(w + "a silence needs cmd_timeout_ms > 0");
      if (label.empty()) label = "silence " + num(d) + " s";
      o << ", \"label\": " << jstring(label) << ", \"silence_steps\": " << n << "}";
      out.push_back({inj.step, o.str()});
      continue;
    }
    Node fv = x->get("frame");
    std::string frame, frame_text;
    int64_t id = -1;
    if (fv && fv->is_string()) {
      frame_text = std::string(*fv->value<std::string_view>());
      std::string names;
      for (const auto &f : kInjectFrames) {
        names += (names.empty() ? "" : ", ") + std::string(f.name);
        if (upper(frame_text) == f.name) {
          frame = f.name;
          id = f.id;
        }
      }
      if (id < 0) fail(w + "'frame' must be " + names + " or an 11-bit id (got " + q(frame_text) + ")");
    } else if (fv && fv->is_integer() && *fv->value<int64_t>() >= 0 && *fv->value<int64_t>() < (1 << 11)) {
      id = *fv->value<int64_t>();
      frame_text = std::to_string(id);
    } else {
      fail(w + "'frame' must be a DBC message name (CONTROL, ACT_CMD, LOAD_CMD) or an 11-bit id");
    }
    std::string signals = "{}";
    if (Node gv = x->get("signals")) {
      Table g = gv->as_table();
      if (!g) fail(w + "'signals' must be a table { NAME = value }");
      for (auto &&kv : *g)
        if (!is_number(&kv.second))
          fail(w + "signal " + q(std::string(kv.first.str())) + " must be a number (nan and inf allowed)");
      signals = bench_json(*g);
    }
    std::string seq = "\"next\"";
    if (Node qv = x->get("seq")) {
      if (qv->is_string() && (*qv->value<std::string_view>() == "next" || *qv->value<std::string_view>() == "stale"))
        seq = jstring(std::string(*qv->value<std::string_view>()));
      else if (qv->is_integer() && *qv->value<int64_t>() >= 0 && *qv->value<int64_t>() <= 0xFFFFFFFFll)
        seq = std::to_string(*qv->value<int64_t>());
      else
        fail(w + "'seq' must be \"next\", \"stale\" or a 32-bit integer");
      if (frame.empty() && seq == "\"stale\"") fail(w + "seq = \"stale\" needs a DBC frame (its counter)");
    }
    const int64_t length = get_int(x, "length", w, 64, 0, 64);
    if (std::find(std::begin(kFdLengths), std::end(kFdLengths), length) == std::end(kFdLengths))
      fail(w + "'length' must be a CAN FD payload length (0..8, 12, 16, 20, 24, 32, 48 or 64; got " +
           std::to_string(length) + ")");
    if (label.empty()) label = frame_text + " " + signals;
    o << ", \"label\": " << jstring(label) << ", \"frame\": " << (frame.empty() ? "null" : jstring(frame))
      << ", \"frame_id\": " << id << ", \"signals\": " << signals << ", \"seq\": " << seq
      << ", \"length\": " << length
      << ", \"expect_signal\": " << (expect_signal.empty() ? "null" : jstring(expect_signal)) << "}";
    out.push_back({inj.step, o.str()});
  }
  std::stable_sort(out.begin(), out.end(), [](const Injection &a, const Injection &b) { return a.step < b.step; });
  std::string json = "[";
  for (size_t i = 0; i < out.size(); ++i) json += (i ? ", " : "") + out[i].json;
  return json + "]";
}

// [checks]: tolerances (> 0, in the key's unit) and options of the bench's verdicts.
const char *const kTolerances[] = {"position_m",  "angle_rad",       "reaction_n",         "moment_nm",
                                   "actuator_force_n", "residual",   "balance_n",          "balance_nm",
                                   "stays_put_m", "statics_force_n", "statics_reaction_n", "ground_force_n",
                                   "growth_rel",  "slip_onset_steps", "in_stroke_m"};
bool is_tolerance(const std::string &k) {
  return std::find_if(std::begin(kTolerances), std::end(kTolerances),
                      [&](const char *t) { return k == t; }) != std::end(kTolerances);
}

std::vector<std::string> names_of(Node v, const std::string &w) {
  const toml::array *a = v->as_array();
  if (!a) fail(w + " must be a list of names");
  std::vector<std::string> out;
  for (auto &&e : *a) {
    if (!e.is_string()) fail(w + " must be a list of names");
    out.emplace_back(*e.value<std::string_view>());
  }
  return out;
}

void parse_checks(Table t, CheckSpec &c) {
  c.given = true;
  const std::string w = "[checks] ";
  for (auto &&kv : *t) {
    const std::string key(kv.first.str());
    c.keys.push_back(key);
    if (is_tolerance(key)) {
      const double v = real_of(&kv.second, w + q(key));
      if (!(v > 0)) fail(w + q(key) + " must be > 0 (got " + num(v) + ")");
      ++c.n_tolerances;
    } else if (key == "resolution_ratio") {
      const double v = real_of(&kv.second, w + q(key));
      if (!(v > 0)) fail(w + q(key) + " must be > 0 (got " + num(v) + ")");
    } else if (key == "compare") {
      static const char *const kCompare[] = {"all", "until_stroke"};
      choice(t, "compare", kCompare, 2, "all");
    } else if (key == "stroke") {
      Table st = kv.second.as_table();
      const std::string sw = "[checks.stroke] ";
      if (!st) fail(sw + "must be a table {actuator, end, tolerance_m}");
      check_keys(st, {"actuator", "end", "tolerance_m"}, sw);
      c.stroke_actuator = get_string(st, "actuator", sw, true);
      const std::string end = get_string(st, "end", sw, true);
      if (end != "min" && end != "max") fail(sw + "'end' must be min or max (got " + q(end) + ")");
      const double tol = get_real(st, "tolerance_m", sw, false, 1e-6);
      if (!(tol > 0)) fail(sw + "'tolerance_m' must be > 0 (got " + num(tol) + ")");
    } else if (key == "slips") {
      c.has_slips = true;
      c.slips = names_of(&kv.second, w + "'slips'");
    } else if (key == "lifts") {
      c.has_lifts = true;
      c.lifts = names_of(&kv.second, w + "'lifts'");
    } else if (key == "events") {
      if (!kv.second.is_boolean() || !*kv.second.value<bool>())
        fail(w + "'events' must be true (the reference that locates the contact events; leave it out for none)");
      c.events = true;
    }
    // any other key: refused at bind time, where the keys that apply are known
  }
}

// The [checks] keys that apply to an analysis of a leg or of a robot (a model with contacts).
std::vector<std::string> checks_for(Analysis a, bool robot) {
  switch (a) {
    case Analysis::kDynamics:
      if (robot)
        return {"position_m", "angle_rad", "residual", "actuator_force_n", "reaction_n", "ground_force_n",
                "stays_put_m", "growth_rel", "slips", "lifts", "slip_onset_steps", "events", "in_stroke_m"};
      return {"position_m", "angle_rad", "reaction_n", "moment_nm", "actuator_force_n", "residual", "balance_n",
              "balance_nm", "stays_put_m", "statics_force_n", "statics_reaction_n", "compare", "stroke",
              "resolution_ratio"};
    case Analysis::kStatics:
      if (robot)
        return {"position_m", "angle_rad", "residual", "statics_force_n", "statics_reaction_n", "ground_force_n"};
      return {"position_m", "angle_rad", "residual", "statics_force_n", "statics_reaction_n", "balance_n",
              "balance_nm"};
    case Analysis::kStaticsSweep: return {"statics_force_n", "statics_reaction_n"};
    case Analysis::kInverseDynamics:
      if (robot)
        return {"position_m", "angle_rad", "residual", "actuator_force_n", "reaction_n", "ground_force_n"};
      return {"position_m", "angle_rad", "residual", "actuator_force_n", "reaction_n", "moment_nm"};
    case Analysis::kAssembly: return {"position_m", "angle_rad", "residual"};
  }
  return {};
}

std::string joined(const std::vector<std::string> &v) {
  std::string o;
  for (size_t i = 0; i < v.size(); ++i) o += (i ? ", " : "") + v[i];
  return o;
}

// The keys of [checks] written other than those in keep, sorted.
std::vector<std::string> checks_other_than(const CheckSpec &c, std::initializer_list<const char *> keep) {
  std::vector<std::string> out;
  for (const std::string &k : c.keys)
    if (std::none_of(keep.begin(), keep.end(), [&](const char *x) { return k == x; })) out.push_back(k);
  std::sort(out.begin(), out.end());
  return out;
}

// [checks] against the model: the keys that apply, the actuator and feet named.
void bind_checks(const Scene &s, const legsim_model_desc &m) {
  const CheckSpec &c = s.checks;
  const bool robot = m.n_contacts > 0;
  if (!c.given) return;
  std::vector<std::string> allowed = checks_for(s.analysis, robot);
  std::sort(allowed.begin(), allowed.end());
  const std::string where =
      std::string("[checks] (") + (robot ? "robot " : "") + analysis_name(s.analysis) + "): ";
  for (const std::string &k : c.keys)
    if (std::find(allowed.begin(), allowed.end(), k) == allowed.end())
      fail(where + "unknown key " + q(k) + " (allowed: " + joined(allowed) + ")");
  if (!c.stroke_actuator.empty()) {
    std::vector<std::string> acts;
    for (int32_t a = 0; a < m.n_actuators; ++a) acts.push_back(scene_text::name_of(m.actuator[a].name));
    if (std::find(acts.begin(), acts.end(), c.stroke_actuator) == acts.end())
      fail("[checks.stroke] 'actuator' must be an actuator of the model (" + joined(acts) + "; got " +
           q(c.stroke_actuator) + ")");
  }
  std::vector<std::string> feet;
  for (int32_t k = 0; k < m.n_contacts; ++k) feet.push_back(scene_text::name_of(m.contact[k].name));
  for (const auto *list : {&c.slips, &c.lifts})
    for (const std::string &f : *list)
      if (std::find(feet.begin(), feet.end(), f) == feet.end())
        fail(std::string("[checks] ") + (list == &c.slips ? "'slips'" : "'lifts'") +
             " must be a list of the model's contacts (" + joined(feet) + "; got " + q(f) + ")");
  const bool onset = std::find(c.keys.begin(), c.keys.end(), "slip_onset_steps") != c.keys.end();
  if (c.has_slips) {
    // the feet that must slip: RobotModel's stance on stuck feet is no reference then, except up
    // to the first slip when slip_onset_steps asks for it
    const std::vector<std::string> against =
        onset ? checks_other_than(c, {"slips", "residual", "slip_onset_steps", "position_m", "angle_rad",
                                      "ground_force_n"})
              : checks_other_than(c, {"slips", "residual", "slip_onset_steps"});
    if (!against.empty())
      fail("[checks]: " + joined(against) +
           " compare with RobotModel's stance on stuck feet, which 'slips' leaves: leave them out");
  }
  if (onset && (!c.has_slips || c.slips.empty()))
    fail("[checks]: 'slip_onset_steps' needs 'slips' (the foot that slips first)");
  if (c.has_lifts) {
    // the feet that lift off and touch down: the stance is the reference until the first lift-off
    std::vector<std::string> against = checks_other_than(c, {"lifts", "residual", "position_m", "angle_rad"});
    if (against.empty() && c.has_slips) against = {"slips"};
    if (!against.empty())
      fail("[checks]: " + joined(against) +
           " compare with RobotModel's stance on stuck feet, which 'lifts' leaves: leave them out");
  }
  // a start off the stance (lifted, moving, a foot free or sliding) leaves RobotModel's stuck feet:
  // its reference is the event-locating one (events = true), with constant commands (or a
  // switch, compared until its event)
  bool off_stance = s.start.given;
  for (const ContactInit &ci : s.contacts) off_stance = off_stance || ci.state != LEGSIM_CONTACT_STUCK;
  if (c.events) {
    const std::vector<std::string> against =
        checks_other_than(c, {"events", "position_m", "angle_rad", "residual", "ground_force_n", "in_stroke_m"});
    if (!against.empty())
      fail("[checks]: " + joined(against) + " do not go with 'events' (its reference checks position_m, angle_rad, "
           "ground_force_n; residual and in_stroke_m need none)");
    for (const Command &cmd : s.commands)
      if (cmd.signal.kind == Signal::kSinusoid || cmd.signal.kind == Signal::kStep)
        fail("[checks] 'events': command " + q(cmd.actuator) +
             " changes with time; the event-locating reference takes constant commands (or a 'switch')");
  } else if (off_stance) {
    const std::vector<std::string> against = checks_other_than(c, {"residual", "in_stroke_m"});
    if (!against.empty())
      fail("[checks]: " + joined(against) + " compare with RobotModel's stance on stuck feet, which the start (" +
           (s.start.given ? "[start]" : "a foot not stuck") + ") leaves: add events = true (the reference that "
           "locates the contact events)");
  }
  if (c.n_tolerances == 0 && !c.events && (robot || (s.n_injections == 0 && c.stroke_actuator.empty())))
    fail("[checks] names nothing to check");
}

void parse_scene(Table doc, Scene &s) {
  for (const auto &r : kRenamedKeys)
    if (doc->get(r.old_key)) fail(r.message);
  check_keys(doc, {"description", "name", "demo", "model", "variant", "analysis", "integrator",
                   "step_s", "duration", "record_every", "disable", "rho_inf", "max_newton_iter",
                   "newton_tol", "pose", "lengths", "grid", "init", "cmd_timeout_ms", "safe_state",
                   "box_load",
                   "forces", "command", "contact", "inject", "checks", "statics_rule",
                   "contact_law", "start", "ground"},
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

  only("start", dynamics, "dynamics");
  if (Node sv = doc->get("start")) {
    Table st = sv->as_table();
    if (!st) fail("'start' must be a table ([start] lift, tilt, velocity, spin)");
    const std::string w = "[start] ";
    check_keys(st, {"lift", "tilt", "velocity", "spin"}, w);
    StartState &b = s.start;
    b.given = true;
    b.lift_m = get_real(st, "lift", w, false, 0);
    if (!(b.lift_m >= 0 && b.lift_m <= kMaxLiftM))
      fail(w + "'lift' must be in [0, " + num(kMaxLiftM) + "] m (got " + num(b.lift_m) + ")");
    b.tilt_rad = get_real(st, "tilt", w, false, 0);
    if (!(std::fabs(b.tilt_rad) <= kMaxTiltRad))
      fail(w + "'tilt' must be in [-" + num(kMaxTiltRad) + ", " + num(kMaxTiltRad) + "] rad (got " +
           num(b.tilt_rad) + ")");
    if (Node vv = st->get("velocity")) {
      const toml::array *a = vv->as_array();
      if (!a || a->size() != 2) fail(w + "'velocity' must be [vx, vy] (m/s, world axes)");
      for (int i = 0; i < 2; ++i) {
        b.velocity_mps[i] = real_of(a->get(i), w + "'velocity'");
        if (!(std::fabs(b.velocity_mps[i]) <= kMaxStartSpeedMps))
          fail(w + "'velocity' must be within +-" + num(kMaxStartSpeedMps) + " m/s (got " +
               num(b.velocity_mps[i]) + ")");
      }
    }
    b.spin_radps = get_real(st, "spin", w, false, 0);
    if (!(std::fabs(b.spin_radps) <= kMaxStartSpinRadps))
      fail(w + "'spin' must be within +-" + num(kMaxStartSpinRadps) + " rad/s (got " + num(b.spin_radps) + ")");
  }
  if (Node gv = doc->get("ground")) {
    Table gt = gv->as_table();
    if (!gt) fail("'ground' must be a table ([ground] slope, mu_static, mu_kinetic)");
    const std::string w = "[ground] ";
    check_keys(gt, {"slope", "mu_static", "mu_kinetic"}, w);
    GroundSpec &g = s.ground;
    g.given = true;
    g.has_slope = gt->get("slope") != nullptr;
    g.has_mu_static = gt->get("mu_static") != nullptr;
    g.has_mu_kinetic = gt->get("mu_kinetic") != nullptr;
    g.slope_rad = get_real(gt, "slope", w, false, 0);
    if (!(std::fabs(g.slope_rad) <= kMaxSlopeRad))
      fail(w + "'slope' must be in [-" + num(kMaxSlopeRad) + ", " + num(kMaxSlopeRad) + "] rad (got " +
           num(g.slope_rad) + ")");
    for (const char *key : {"mu_static", "mu_kinetic"}) {
      const double v = get_real(gt, key, w, false, 0);
      if (!(v >= 0 && v <= LEGSIM_MAX_FRICTION))
        fail(w + q(key) + " must be in [0, " + num(LEGSIM_MAX_FRICTION) + "] (got " + num(v) + ")");
      (std::string(key) == "mu_static" ? g.mu_static : g.mu_kinetic) = v;
    }
    if (g.has_mu_static && g.has_mu_kinetic && g.mu_kinetic > g.mu_static)
      fail(w + "'mu_kinetic' " + num(g.mu_kinetic) + " must be at most 'mu_static' " + num(g.mu_static));
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
  if (s.cmd_timeout_ms > 0 && s.record_every * s.step_ns >= s.cmd_timeout_ms * 1000000)
    fail("an exchange every " + num(static_cast<double>(s.record_every * s.step_ns) / 1e6) +
         " ms (record_every x step_s) would let the " + std::to_string(s.cmd_timeout_ms) +
         " ms command timeout trip between ACT_CMDs");
  if (Node iv = doc->get("inject")) {
    const toml::array *a = iv->as_array();
    if (!a || !a->is_array_of_tables()) fail("'inject' must be an array of tables ([[inject]])");
    s.n_injections = static_cast<int>(a->size());
    s.inject_json = parse_injections(*a, s);
  }
  if (Node cv = doc->get("checks")) {
    if (!cv->is_table()) fail("'checks' must be a table ([checks])");
    s.checks_json = bench_json(*cv);
    parse_checks(cv->as_table(), s.checks);
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
      check_keys(ct, {"actuator", "mode", "value", "sinusoid", "step", "switch"}, w0);
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
      if (c.signal.kind == Signal::kSwitch && !dynamics)
        fail(w + "'switch' applies to dynamics only (an event of the run)");
      if (c.signal.kind == Signal::kSwitch && s.record_every != 1)
        fail(w + "'switch' needs record_every = 1 (the switch comes the step after the event; the bench "
                 "sees the events once per sample)");
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
      else if (state == "sliding")
        c.state = LEGSIM_CONTACT_SLIDING;
      else
        fail(w + "'state' must be stuck, free or sliding (got " + q(state) + ")");
      if (c.state == LEGSIM_CONTACT_SLIDING && !(dynamics && doc->get("start")))
        fail(w + "a foot starts sliding only in dynamics with a [start] velocity (a foot at rest cannot slide)");
      s.contacts.push_back(c);
    }
  }
}

}  // namespace

// ---- signals -------------------------------------------------------------------------
double Signal::at(double t) const {
  switch (kind) {
    case kSinusoid: return offset + amplitude * std::sin(kTwoPi * frequency_hz * t + phase_rad);
    case kStep: return t < t0 ? before : after;
    case kSwitch: return before;  // the runner switches to after once the event came
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
    case kStep:
    case kSwitch: return std::min(before, after);
    default: return value;
  }
}
double Signal::max() const {
  switch (kind) {
    case kSinusoid: return frequency_hz > 0 ? offset + std::fabs(amplitude) : at(0);
    case kStep:
    case kSwitch: return std::max(before, after);
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

bool load_scene_text(const std::string &text, const std::string &path, Scene &scene, std::string &err) {
  try {
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

bool load_scene(const std::string &path, Scene &scene, std::string &err) {
  std::string text;
  if (!read_toml_file(path.c_str(), text, err)) return false;  // a regular file only
  return load_scene_text(text, path, scene, err);
}

void write_resolved_model(std::ostream &o, const Scene &sc, const legsim_model_desc &m) {
  using scene_text::name_of;
  auto names = [&](const char *key, int32_t n, auto get) {
    o << ", \"" << key << "\": [";
    for (int32_t i = 0; i < n; ++i) o << (i ? ", " : "") << jstring(get(i));
    o << "]";
  };
  o << ", \"description\": " << jstring(sc.description) << ", \"demo\": " << (sc.demo ? "true" : "false")
    << ", \"model_info\": {\"actuators\": [";
  for (int32_t a = 0; a < m.n_actuators; ++a) {
    const legsim_actuator_desc &ad = m.actuator[a];
    o << (a ? ", " : "") << "{\"name\": " << jstring(name_of(ad.name)) << ", \"stroke\": [" << num(ad.stroke_min_m)
      << ", " << num(ad.stroke_max_m) << "], \"max_force\": " << num(ad.max_force_n) << "}";
  }
  o << "], \"forces\": [";
  for (int32_t f = 0; f < m.n_forces; ++f) {
    const legsim_force_kind k = m.force[f].kind;
    o << (f ? ", " : "") << "{\"name\": " << jstring(name_of(m.force[f].name)) << ", \"kind\": \""
      << (k == LEGSIM_FORCE_POINT ? "point" : k == LEGSIM_FORCE_TORQUE ? "torque" : "spring_damper") << "\"}";
  }
  o << "]";
  names("poses", m.n_poses, [&](int32_t i) { return name_of(m.pose[i].name); });
  names("contacts", m.n_contacts, [&](int32_t i) { return name_of(m.contact[i].name); });
  // a robot's legs: one foot each (its contacts); a leg file is one leg
  o << ", \"legs\": " << std::max<int32_t>(1, m.n_contacts) << "}";
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

bool ground_apply(const Scene &s, legsim_model_desc &d, std::string &why) {
  if (!s.ground.given) return true;
  if (d.n_contacts < 1) {
    why = "the model has no ground (no contacts)";
    return false;
  }
  legsim_ground_desc g = d.ground;
  if (s.ground.has_slope) g.slope_rad = s.ground.slope_rad;
  if (s.ground.has_mu_static) g.mu_static = s.ground.mu_static;
  if (s.ground.has_mu_kinetic) g.mu_kinetic = s.ground.mu_kinetic;
  if (g.mu_kinetic > g.mu_static) {
    why = "mu_kinetic " + num(g.mu_kinetic) + " must be at most mu_static " + num(g.mu_static) +
          " (with the model's own for the key left out)";
    return false;
  }
  d.ground = g;
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
        if (!start_length_in_stroke(m, a, s.lengths[a]))
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
    if (m.n_contacts == 0 && s.start.given)
      fail("[start] applies to a model with contacts only (the robot's box)");
    if (m.n_contacts == 0 && s.ground.given)
      fail("[ground] applies to a model with contacts only (the robot's ground)");
    if (s.ground.given) {
      std::string why;
      const auto probe = std::make_unique<legsim_model_desc>(m);
      if (!ground_apply(s, *probe, why)) fail("[ground]: " + why);
    }
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
    // the bench's sections
    if (m.n_contacts > 0 && s.n_injections > 0)
      fail("[[inject]] is not for a robot scene (the bench's injections are the one leg's frames; "
           "tests/hil/test_robot_can.py sends the robot bad frames)");
    bind_checks(s, m);
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
      if (cmd.signal.kind == Signal::kSwitch) {
        Signal &g = cmd.signal;
        g.contact_index = -1;
        std::string list;
        for (int32_t k = 0; k < m.n_contacts; ++k) {
          list += (k ? ", " : "") + name_of(m.contact[k].name);
          if (name_of(m.contact[k].name) == g.contact) g.contact_index = k;
        }
        if (g.contact_index < 0)
          fail(w + "switch: 'contact' must be a contact of the model (" + (list.empty() ? "none" : list) +
               "; got " + q(g.contact) + ")");
      }
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
