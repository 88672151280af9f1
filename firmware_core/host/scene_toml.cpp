// Scene files for legsim_cli: parsing (toml++), binding to a model, running the
// analyses through the C API, and writing JSON or CSV. Host only.
#include "scene_toml.hpp"

#include <algorithm>
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
    s.kind = Signal::kConstant;
    s.value = real_of(t->get("value"), where + "'value'");
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
    if (s.frequency_hz < 0) fail(w + "'frequency' must be >= 0 (Hz)");
  } else {
    Table st = t->get("step")->as_table();
    if (!st) fail(where + "'step' must be a table {t0, before, after}");
    const std::string w = where + "step: ";
    check_keys(st, {"t0", "before", "after"}, w);
    s.kind = Signal::kStep;
    s.t0 = get_real(st, "t0", w, true, 0);
    s.before = get_real(st, "before", w, true, 0);
    s.after = get_real(st, "after", w, true, 0);
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

void parse_scene(Table doc, Scene &s) {
  check_keys(doc, {"description", "model", "variant", "analysis", "integrator", "step", "duration",
                   "output_every", "disable", "rho_inf", "max_newton_iter", "newton_tol", "pose",
                   "lengths", "grid", "forces", "command"},
             "");
  s.description = get_string(doc, "description", "", false);
  s.model = get_string(doc, "model", "", true);
  if (s.model.rfind("builtin:", 0) == 0) {
    s.builtin = s.model.substr(8);
  } else {
    s.model_path = (!s.model.empty() && s.model[0] == '/') ? s.model : dirname_of(s.path) + s.model;
  }
  s.variant = get_string(doc, "variant", "", false, "revolute");

  const std::string an = get_string(doc, "analysis", "", true);
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

  s.options = legsim_default_options();
  const std::string integ = get_string(doc, "integrator", "", false, "rk4");
  if (integ == "rk4")
    s.options.integrator = LEGSIM_INTEGRATOR_RK4;
  else if (integ == "generalized_alpha")
    s.options.integrator = LEGSIM_INTEGRATOR_GENERALIZED_ALPHA;
  else
    fail("'integrator' must be rk4 or generalized_alpha (got " + q(integ) + ")");
  s.options.step_s = get_real(doc, "step", "", false, s.options.step_s);
  if (!(s.options.step_s > 0)) fail("'step' must be > 0 (got " + num(s.options.step_s) + ")");
  s.options.rho_inf = get_real(doc, "rho_inf", "", false, s.options.rho_inf);
  if (!(s.options.rho_inf >= 0 && s.options.rho_inf <= 1))
    fail("'rho_inf' must be in [0, 1] (got " + num(s.options.rho_inf) + ")");
  s.options.max_newton_iter =
      static_cast<int32_t>(get_int(doc, "max_newton_iter", "", s.options.max_newton_iter, 1, 1000));
  s.options.newton_tol = get_real(doc, "newton_tol", "", false, s.options.newton_tol);
  if (!(s.options.newton_tol > 0)) fail("'newton_tol' must be > 0");

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

  if (timed) {
    s.duration_s = get_real(doc, "duration", "", true, 0);
    if (!(s.duration_s > 0)) fail("'duration' must be > 0 (got " + num(s.duration_s) + ")");
    const double n = std::round(s.duration_s / s.options.step_s);
    if (n < 1 || n > 1e9)
      fail("'duration' / 'step' must give 1 to 1e9 steps (got " + num(n) + ")");
    s.n_steps = static_cast<int64_t>(n);
  } else if (doc->get("duration")) {
    fail("'duration' applies to dynamics and inverse_dynamics only");
  }
  s.output_every = get_int(doc, "output_every", "", 1, 1, INT64_C(1000000000));

  s.pose = get_string(doc, "pose", "", false);
  if (Node lv = doc->get("lengths")) {
    if (s.analysis == Analysis::kStaticsSweep) fail("'lengths' does not apply to statics_sweep");
    const toml::array *a = lv->as_array();
    if (!a) fail("'lengths' must be an array of numbers (m), one per actuator");
    for (auto &&e : *a) s.lengths.push_back(real_of(&e, "'lengths'"));
    s.has_lengths = true;
  }
  if (doc->get("grid")) {
    if (s.analysis != Analysis::kStaticsSweep) fail("'grid' applies to statics_sweep only");
  }
  s.grid = static_cast<int32_t>(get_int(doc, "grid", "", 11, 2, 1000));

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
      s.commands.push_back(c);
    }
  }
}

bool read_text(const std::string &path, std::string &text, std::string &err) {
  std::ifstream f(path, std::ios::binary);
  if (!f) {
    err = path + ": cannot read: " + std::strerror(errno);
    return false;
  }
  std::ostringstream ss;
  ss << f.rdbuf();
  text = ss.str();
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
  }
  return "LEGSIM_ERR_UNKNOWN";
}

bool load_scene(const std::string &path, Scene &scene, std::string &err) {
  try {
    std::string text;
    if (!read_text(path, text, err)) return false;
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
      if (cmd.mode == LEGSIM_ACTUATOR_LENGTH) {
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
Sample record(legsim_sim *sim, const legsim_model_desc &m, double t, const legsim_real *forces) {
  Sample s;
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
  legsim_real max_abs = 0;
  if (legsim_constraints(sim, buf.data(), &max_abs) == LEGSIM_OK) s.residual = max_abs;
  legsim_report rep;
  if (legsim_get_report(sim, &rep) == LEGSIM_OK) {
    s.iterations = rep.iterations;
    s.condition = rep.condition;
    s.events = rep.events;
  }
  legsim_clear_events(sim);
  return s;
}

legsim_status run(const Scene &sc, const legsim_model_desc &m, Result &res) {
  Storage storage(legsim_sim_size());
  if (!storage.p) {
    res.error = "out of memory";
    return LEGSIM_ERR_STORAGE;
  }
  legsim_sim *sim = nullptr;
  legsim_status st = legsim_init(storage.p, legsim_sim_size(), &m, &sc.options, &sim);
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
  if (sc.has_lengths) {
    std::vector<legsim_real> len(sc.lengths.begin(), sc.lengths.end());
    st = legsim_assemble(sim, len.data());
    if (st != LEGSIM_OK) {
      std::string l;
      for (size_t i = 0; i < sc.lengths.size(); ++i) l += (i ? ", " : "") + num(sc.lengths[i]);
      res.error = call_failed("assembling the lengths [" + l + "]", st);
      return st;
    }
  }
  std::vector<legsim_real> forces(std::max(na, 1));

  switch (sc.analysis) {
    case Analysis::kAssembly:
      res.samples.push_back(record(sim, m, legsim_time(sim), nullptr));
      return LEGSIM_OK;

    case Analysis::kStatics:
      st = legsim_statics(sim, forces.data());
      if (st != LEGSIM_OK) {
        res.error = call_failed("statics", st);
        return st;
      }
      res.samples.push_back(record(sim, m, legsim_time(sim), forces.data()));
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
      // Uncommanded actuators hold their assembled length.
      std::vector<legsim_real> hold(std::max(na, 1)), len(std::max(na, 1)), rate(std::max(na, 1)),
          acc(std::max(na, 1));
      if (na > 0) legsim_actuator_lengths(sim, hold.data(), nullptr);
      const double h = sc.options.step_s;
      for (int64_t k = 0; k <= sc.n_steps; ++k) {
        const double t = static_cast<double>(k) * h;
        for (int32_t a = 0; a < na; ++a) {
          len[a] = hold[a];
          rate[a] = acc[a] = 0;
        }
        for (const auto &c : sc.commands) {
          len[c.index] = static_cast<legsim_real>(c.signal.at(t));
          rate[c.index] = static_cast<legsim_real>(c.signal.rate(t));
          acc[c.index] = static_cast<legsim_real>(c.signal.accel(t));
        }
        st = legsim_inverse_dynamics(sim, len.data(), rate.data(), acc.data(), forces.data());
        if (st != LEGSIM_OK) {
          res.failed_at_s = t;
          res.error = call_failed("inverse dynamics at t = " + num(t) + " s", st);
          return st;
        }
        if (k % sc.output_every == 0) res.samples.push_back(record(sim, m, t, forces.data()));
      }
      return LEGSIM_OK;
    }

    case Analysis::kDynamics: {
      auto apply = [&](double t) -> legsim_status {
        for (const auto &c : sc.commands) {
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
      res.samples.push_back(record(sim, m, legsim_time(sim), nullptr));
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
        if (k % sc.output_every == 0 || k == sc.n_steps)
          res.samples.push_back(record(sim, m, legsim_time(sim), nullptr));
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

std::vector<std::string> event_names(uint32_t e) {
  std::vector<std::string> v;
  if (e & LEGSIM_EVENT_STROKE_MIN) v.push_back("stroke_min");
  if (e & LEGSIM_EVENT_STROKE_MAX) v.push_back("stroke_max");
  if (e & LEGSIM_EVENT_FORCE_SATURATED) v.push_back("force_saturated");
  if (e & LEGSIM_EVENT_NEAR_SINGULAR) v.push_back("near_singular");
  return v;
}

std::string csv_field(const std::string &s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string o = "\"";
  for (char c : s) o += c == '"' ? std::string("\"\"") : std::string(1, c);
  return o + "\"";
}

}  // namespace

legsim_status run_scene(const Scene &scene, const legsim_model_desc &model, Result &result) {
  result = Result{};
  try {
    result.status = run(scene, model, result);
  } catch (const std::exception &e) {
    result.status = LEGSIM_ERR_STORAGE;
    result.error = e.what();
  } catch (...) {
    result.status = LEGSIM_ERR_STORAGE;
    result.error = "unexpected error";
  }
  return result.status;
}

void write_json(std::ostream &o, const Scene &sc, const legsim_model_desc &m, const Result &r) {
  const char *xyz[3] = {"x", "y", "phi"};
  o << "{\n";
  o << "  \"scene\": " << jstr(sc.path) << ",\n";
  if (!sc.description.empty()) o << "  \"description\": " << jstr(sc.description) << ",\n";
  o << "  \"model\": {\"name\": " << jstr(name_of(m.name)) << ", \"source\": " << jstr(sc.model)
    << ", \"variant\": " << jstr(sc.variant) << "},\n";
  o << "  \"analysis\": " << jstr(analysis_name(sc.analysis)) << ",\n";
  o << "  \"integrator\": "
    << jstr(sc.options.integrator == LEGSIM_INTEGRATOR_RK4 ? "rk4" : "generalized_alpha") << ",\n";
  o << "  \"step\": " << jnum(sc.options.step_s) << ",\n";
  o << "  \"output_every\": " << sc.output_every << ",\n";
  o << "  \"status\": " << jstr(r.status == LEGSIM_OK ? "ok" : "error") << ",\n";
  o << "  \"status_code\": " << jstr(status_enum_name(r.status)) << ",\n";
  if (r.status != LEGSIM_OK) {
    o << "  \"error\": " << jstr(r.error) << ",\n";
    if (r.failed_at_s >= 0) o << "  \"failed_at\": " << jnum(r.failed_at_s) << ",\n";
  }
  auto names = [&](const char *key, int n, auto get) {
    o << "  \"" << key << "\": [";
    for (int i = 0; i < n; ++i) o << (i ? ", " : "") << jstr(get(i));
    o << "],\n";
  };
  names("bodies", m.n_bodies, [&](int i) { return name_of(m.body[i].name); });
  names("joints", m.n_joints, [&](int i) { return name_of(m.joint[i].name); });
  names("actuators", m.n_actuators, [&](int i) { return name_of(m.actuator[i].name); });
  if (r.has_worst_case) {
    const legsim_worst_case &w = r.worst;
    o << "  \"worst_case\": {\n    \"grid\": " << sc.grid << ", \"n_poses\": " << w.n_poses
      << ", \"n_failed\": " << w.n_failed << ",\n    \"reactions\": {";
    for (int j = 0; j < m.n_joints; ++j) {
      o << (j ? ", " : "") << "\n      " << jstr(name_of(m.joint[j].name)) << ": {\"max_force\": "
        << jnum(w.max_reaction_n[j]) << ", \"at_lengths\": {";
      for (int a = 0; a < m.n_actuators; ++a)
        o << (a ? ", " : "") << jstr(name_of(m.actuator[a].name)) << ": " << jnum(w.at_length_m[j][a]);
      o << "}}";
    }
    o << "\n    },\n    \"actuators\": {";
    for (int a = 0; a < m.n_actuators; ++a) {
      o << (a ? ", " : "") << "\n      " << jstr(name_of(m.actuator[a].name)) << ": {\"max_force\": "
        << jnum(w.max_actuator_force_n[a]) << ", \"at_lengths\": {";
      for (int k = 0; k < m.n_actuators; ++k)
        o << (k ? ", " : "") << jstr(name_of(m.actuator[k].name)) << ": "
          << jnum(w.actuator_at_length_m[a][k]);
      o << "}}";
    }
    o << "\n    }\n  },\n";
  }
  o << "  \"samples\": [";
  for (size_t i = 0; i < r.samples.size(); ++i) {
    const Sample &s = r.samples[i];
    o << (i ? "," : "") << "\n    {\"t\": " << jnum(s.t) << ",\n     \"q\": {";
    for (int b = 0; b < m.n_bodies; ++b) {
      o << (b ? ", " : "") << jstr(name_of(m.body[b].name)) << ": {";
      for (int c = 0; c < 3; ++c) o << (c ? ", " : "") << "\"" << xyz[c] << "\": " << jnum(s.q[3 * b + c]);
      o << "}";
    }
    o << "},\n     \"actuators\": {";
    for (int a = 0; a < m.n_actuators; ++a)
      o << (a ? ", " : "") << jstr(name_of(m.actuator[a].name)) << ": {\"length\": " << jnum(s.length[a])
        << ", \"rate\": " << jnum(s.rate[a]) << ", \"force\": " << jnum(s.force[a]) << "}";
    o << "},\n     \"reactions\": ";
    if (s.has_reactions) {
      o << "{";
      for (int j = 0; j < m.n_joints; ++j)
        o << (j ? ", " : "") << jstr(name_of(m.joint[j].name)) << ": {\"fx\": " << jnum(s.reaction[3 * j])
          << ", \"fy\": " << jnum(s.reaction[3 * j + 1]) << ", \"moment\": " << jnum(s.reaction[3 * j + 2])
          << "}";
      o << "}";
    } else {
      o << "null";
    }
    o << ",\n     \"foot\": ";
    if (s.has_foot)
      o << "{\"x\": " << jnum(s.foot[0]) << ", \"y\": " << jnum(s.foot[1]) << "}";
    else
      o << "null";
    o << ", \"residual\": " << jnum(s.residual) << ", \"iterations\": " << s.iterations
      << ", \"condition\": " << jnum(s.condition) << ", \"events\": [";
    const auto ev = event_names(s.events);
    for (size_t k = 0; k < ev.size(); ++k) o << (k ? ", " : "") << jstr(ev[k]);
    o << "]}";
  }
  o << (r.samples.empty() ? "]\n" : "\n  ]\n") << "}\n";
}

void write_csv(std::ostream &o, const Scene &sc, const legsim_model_desc &m, const Result &r) {
  if (r.has_worst_case) {
    // One row per joint reaction and per actuator force: the worst case of the sweep.
    o << "item,kind,max_force";
    for (int a = 0; a < m.n_actuators; ++a) o << ",at_" << csv_field(name_of(m.actuator[a].name));
    o << ",status\n";
    const legsim_worst_case &w = r.worst;
    for (int j = 0; j < m.n_joints; ++j) {
      o << csv_field(name_of(m.joint[j].name)) << ",reaction," << num(w.max_reaction_n[j]);
      for (int a = 0; a < m.n_actuators; ++a) o << "," << num(w.at_length_m[j][a]);
      o << ",ok\n";
    }
    for (int a = 0; a < m.n_actuators; ++a) {
      o << csv_field(name_of(m.actuator[a].name)) << ",actuator," << num(w.max_actuator_force_n[a]);
      for (int k = 0; k < m.n_actuators; ++k) o << "," << num(w.actuator_at_length_m[a][k]);
      o << ",ok\n";
    }
    (void)sc;
    return;
  }
  const char *xyz[3] = {"x", "y", "phi"};
  o << "t";
  for (int b = 0; b < m.n_bodies; ++b)
    for (int c = 0; c < 3; ++c) o << "," << csv_field(name_of(m.body[b].name) + "." + xyz[c]);
  for (int a = 0; a < m.n_actuators; ++a) {
    const std::string n = name_of(m.actuator[a].name);
    o << "," << csv_field(n + ".length") << "," << csv_field(n + ".rate") << "," << csv_field(n + ".force");
  }
  for (int j = 0; j < m.n_joints; ++j) {
    const std::string n = name_of(m.joint[j].name);
    o << "," << csv_field(n + ".fx") << "," << csv_field(n + ".fy") << "," << csv_field(n + ".moment");
  }
  if (m.foot_body >= 0) o << ",foot.x,foot.y";
  o << ",residual,status\n";
  const int ncols = 1 + 3 * m.n_bodies + 3 * m.n_actuators + 3 * m.n_joints + (m.foot_body >= 0 ? 2 : 0) + 1;
  for (const Sample &s : r.samples) {
    o << num(s.t);
    for (double x : s.q) o << "," << num(x);
    for (int a = 0; a < m.n_actuators; ++a) o << "," << num(s.length[a]) << "," << num(s.rate[a]) << "," << num(s.force[a]);
    for (int j = 0; j < m.n_joints; ++j)
      for (int c = 0; c < 3; ++c) o << "," << (s.has_reactions ? num(s.reaction[3 * j + c]) : std::string());
    if (m.foot_body >= 0) o << "," << (s.has_foot ? num(s.foot[0]) : "") << "," << (s.has_foot ? num(s.foot[1]) : "");
    o << "," << num(s.residual) << ",ok\n";
  }
  if (r.status != LEGSIM_OK) {
    // A last row: when and how the run failed (the other columns empty).
    o << (r.failed_at_s >= 0 ? num(r.failed_at_s) : std::string());
    for (int i = 1; i < ncols; ++i) o << ",";
    o << "," << status_enum_name(r.status) << "\n";
  }
}

}  // namespace legsim_host
