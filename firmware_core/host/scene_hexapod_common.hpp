// What the hexapod's scene readers and writers share (scene_hexapod.cpp, scene_hexapod_inverse.cpp,
// scene_hexapod_sweep.cpp): the strings' and numbers' JSON, the TOML values' checks, the C API's
// aligned storage and a status's text. Host only; internal to them.
#ifndef LEGSIM_HOST_SCENE_HEXAPOD_COMMON_HPP
#define LEGSIM_HOST_SCENE_HEXAPOD_COMMON_HPP

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <new>
#include <ostream>
#include <string>
#include <vector>

#include "legsim/hexapod.h"
#include "model_toml.hpp"
#include "scene_read.hpp"
#include "scene_text.hpp"
#include "scene_toml.hpp"
#include "toml_limits.hpp"

namespace legsim_host {
namespace hexapod_scene {

constexpr int L = LEGSIM_HEXAPOD_LEGS;
constexpr double kPi = 3.14159265358979323846;
constexpr double kGridTolS = 1e-9;        // a duration is a whole number of steps within 1 ns
constexpr int64_t kMaxSamples = 1000000;  // as the planar scenes (scene_parse.cpp)

inline std::string jstr(const std::string &s) {
  std::string o = "\"";
  for (unsigned char c : s) {
    if (c == '"' || c == '\\') {
      o += '\\';
      o += static_cast<char>(c);
    } else if (c < 0x20) {
      char b[8];
      std::snprintf(b, sizeof b, "\\u%04x", c);
      o += b;
    } else {
      o += static_cast<char>(c);
    }
  }
  return o + "\"";
}

// a number as JSON: non-finite ones as strings ("nan", "inf", "-inf")
inline std::string jnum(double x) {
  return std::isfinite(x) ? scene_text::num(x) : "\"" + scene_text::num(x) + "\"";
}

inline std::string jarr(const double *v, int n) {
  std::string o = "[";
  for (int i = 0; i < n; ++i) o += (i ? ", " : "") + jnum(v[i]);
  return o + "]";
}
template <size_t N>
std::string jarr(const double (&v)[N]) {
  return jarr(v, int(N));
}

inline std::string string_of(scene_read::Node v, const std::string &what) {
  if (!v || !v->is_string()) scene_read::fail(what + " must be a string");
  return std::string(*v->value<std::string_view>());
}

// a real in [lo, hi] (open ends where the flags say)
inline double ranged(scene_read::Node v, const std::string &what, double lo, double hi, bool lo_open = false,
                     bool hi_open = false) {
  using scene_text::num;
  const double x = scene_read::real_of(v, what);
  if ((lo_open ? x <= lo : x < lo) || (hi_open ? x >= hi : x > hi))
    scene_read::fail(what + " must be in " + (lo_open ? "(" : "[") + num(lo) + ", " + num(hi) + (hi_open ? ")" : "]") +
                     " (got " + num(x) + ")");
  return x;
}

// The C API's storage, aligned as it asks.
struct Storage {
  explicit Storage(size_t n)
      : bytes(n), p(static_cast<unsigned char *>(::operator new(n, std::align_val_t(LEGSIM_STORAGE_ALIGN)))) {}
  ~Storage() { ::operator delete(p, std::align_val_t(LEGSIM_STORAGE_ALIGN)); }
  Storage(const Storage &) = delete;
  Storage &operator=(const Storage &) = delete;
  size_t bytes;
  unsigned char *p;
};

// every body's mass in legsim_hexapod_body_poses' order: the box, then per leg its yoke and bars
inline int body_masses(const legsim_hexapod_desc &h, double *m) {
  int n = 0;
  m[n++] = h.box_mass_kg;
  for (int k = 0; k < L; ++k) {
    m[n++] = h.yoke_mass_kg;
    for (int b = 0; b < h.leg[k].leg.n_bodies; ++b) m[n++] = h.leg[k].leg.body[b].mass_kg;
  }
  return n;
}
constexpr int kMaxBodies = 1 + L * (1 + LEGSIM_HEXAPOD_MAX_LEG_BARS);

inline double total_mass(const legsim_hexapod_desc &h) {
  double m[kMaxBodies], M = 0;
  const int n = body_masses(h, m);
  for (int b = 0; b < n; ++b) M += m[b];
  return M;
}

// True when the scene text parses and says analysis = `analysis` (false otherwise: the hexapod
// reader then says what is wrong).
inline bool scene_analysis_is(const std::string &text, const std::string &path, std::string_view analysis) {
  try {
    std::string why;
    if (!toml_input_within_limits(text, why)) return false;
    const toml::table doc = toml::parse(text, path);
    scene_read::Node a = doc.get("analysis");
    return a && a->is_string() && *a->value<std::string_view>() == analysis;
  } catch (...) {
    return false;
  }
}

// The scene's TOML document; a parse error refused as the scene's (scene_read::SceneError).
inline toml::table scene_document(const std::string &text, const std::string &path) {
  try {
    return toml::parse(text, path);
  } catch (const toml::parse_error &e) {
    scene_read::fail(std::string(e.description()));
  }
}

// The folder of a path, with its '/' ("" for none).
inline std::string dirname_of(const std::string &path) {
  const size_t p = path.find_last_of('/');
  return p == std::string::npos ? "" : path.substr(0, p + 1);
}

// The keys every scene of a hexapod file has: `model` (and its path, relative to the scene's
// folder), `name` (the file's stem by default; letters, digits, '_', '-' and '.'), `description`.
struct SceneHead {
  std::string model, model_path, name, description;
};

inline SceneHead scene_head(scene_read::Table t, const std::string &path) {
  SceneHead h;
  h.model = string_of(t->get("model"), "'model'");
  h.model_path = h.model[0] == '/' ? h.model : dirname_of(path) + h.model;
  const size_t slash = path.find_last_of('/');  // npos + 1 == 0: no folder
  h.name = path.substr(slash + 1);
  h.name = h.name.substr(0, h.name.find_last_of('.'));
  if (t->get("name")) h.name = string_of(t->get("name"), "'name'");
  for (char c : h.name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.'))
      scene_read::fail("'name' may hold letters, digits, '_', '-' and '.' only (got " + scene_text::q(h.name) + ")");
  if (t->get("description")) h.description = string_of(t->get("description"), "'description'");
  return h;
}

// [checks] as JSON: targets `{ value, tolerance > 0 }`, bounds (numbers > 0), `impacts_min` (an
// integer, when listed in `others`) and the other keys of `others` by other(key, value).
template <class Other>
std::string checks_json(scene_read::Node v, const std::vector<std::string> &targets,
                        const std::vector<std::string> &bounds, const std::vector<std::string> &others,
                        Other &&other);

// [checks]' target `{ value, tolerance > 0 }` (the result within tolerance of value), as JSON.
inline std::string target_json(scene_read::Node v, const std::string &what) {
  scene_read::Table t = v ? v->as_table() : nullptr;
  if (!t) scene_read::fail(what + " must be { value, tolerance }");
  scene_read::check_keys(t, {"value", "tolerance"}, what + ": ");
  if (!t->get("value") || !t->get("tolerance")) scene_read::fail(what + " must be { value, tolerance }");
  const double x = scene_read::real_of(t->get("value"), what + ": 'value'");
  const double tol = scene_read::real_of(t->get("tolerance"), what + ": 'tolerance'");
  if (!(tol > 0)) scene_read::fail(what + ": 'tolerance' must be > 0 (got " + scene_text::num(tol) + ")");
  return "{\"value\": " + jnum(x) + ", \"tolerance\": " + jnum(tol) + "}";
}

template <class Other>
std::string checks_json(scene_read::Node v, const std::vector<std::string> &targets,
                        const std::vector<std::string> &bounds, const std::vector<std::string> &others,
                        Other &&other) {
  using scene_read::fail;
  scene_read::Table t = v->as_table();
  if (!t) fail("'checks' must be a table");
  std::vector<std::string> allowed = targets;
  allowed.insert(allowed.end(), bounds.begin(), bounds.end());
  allowed.insert(allowed.end(), others.begin(), others.end());
  scene_read::check_keys(t, allowed, "checks: ");
  if (t->empty()) fail("checks: name something to check");
  std::string o = "{";
  for (auto &&kv : *t) {
    const std::string key(kv.first.str());
    const std::string what = "checks: " + scene_text::q(key);
    o += (o.size() > 1 ? ", " : "") + jstr(key) + ": ";
    if (std::find(targets.begin(), targets.end(), key) != targets.end()) {
      o += target_json(&kv.second, what);
    } else if (std::find(bounds.begin(), bounds.end(), key) != bounds.end()) {
      const double x = scene_read::real_of(&kv.second, what);
      if (!(x > 0)) fail(what + " must be > 0 (got " + scene_text::num(x) + ")");
      o += jnum(x);
    } else if (key == "impacts_min") {
      if (!kv.second.is_integer() || *kv.second.value<int64_t>() < 0 || *kv.second.value<int64_t>() > 1000000000)
        fail(what + " must be an integer in 0..1000000000");
      o += std::to_string(*kv.second.value<int64_t>());
    } else {
      o += other(key, &kv.second);
    }
  }
  return o + "}";
}

// A run's failure: its status and message.
struct RunFail {
  legsim_status status;
  std::string message;
};

// The samples' list closed and the run's end written: "ok" (exit status 0), or the failure f at
// t_fail (exit status 1: the JSON's status, code, error and failed_at; the message on err).
inline int run_end(std::ostream &o, std::ostream &err, const std::string &path, const RunFail *f, double t_fail) {
  if (!f) {
    o << "\n  ],\n  \"status\": \"ok\", \"status_code\": \"LEGSIM_OK\"}\n";
    return 0;
  }
  o << "\n  ],\n  \"status\": \"error\", \"status_code\": " << jstr(status_enum_name(f->status))
    << ", \"error\": " << jstr(f->message) << ", \"failed_at\": " << jnum(t_fail) << "}\n";
  err << "legsim_cli: error: " << path << ": " << f->message << "\n";
  return 1;
}

// The keys of a run in time (the hexapod's dynamics and the block's): step_s, integrator,
// duration, record_every; units and ranges in scenes/README.md.
struct RunKeys {
  double step_s = 0.001, duration = 0;
  legsim_integrator integrator = LEGSIM_INTEGRATOR_RK4;
  int64_t step_ns = 1000000, n_steps = 0, record_every = 1;
};
constexpr int64_t kMaxSteps = 100000000;  // 1e8 steps
constexpr int64_t kMaxRecordEvery = 10000000;

inline RunKeys run_keys(scene_read::Table t) {
  using scene_read::fail;
  using scene_text::num;
  RunKeys s;
  if (scene_read::Node v = t->get("step_s")) {
    s.step_s = ranged(v, "'step_s'", 1e-6, 0.1);
    const double ns = s.step_s * 1e9;
    if (std::fabs(ns - std::round(ns)) > 1e-6) fail("'step_s' must be a whole number of nanoseconds (got " + num(s.step_s) + ")");
    s.step_ns = static_cast<int64_t>(std::llround(ns));
  }
  if (scene_read::Node v = t->get("integrator")) {
    const std::string in = string_of(v, "'integrator'");
    if (in == "rk4") {
      s.integrator = LEGSIM_INTEGRATOR_RK4;
    } else if (in == "generalized_alpha") {
      s.integrator = LEGSIM_INTEGRATOR_GENERALIZED_ALPHA;
    } else {
      fail("'integrator' of a hexapod must be rk4 or generalized_alpha (got " + scene_text::q(in) + ")");
    }
  }
  scene_read::Node dv = t->get("duration");
  if (!dv) fail("missing key 'duration'");
  s.duration = ranged(dv, "'duration'", 0, 1e6, true);
  const double steps = s.duration * 1e9 / static_cast<double>(s.step_ns);
  s.n_steps = static_cast<int64_t>(std::llround(steps));
  if (std::fabs(static_cast<double>(s.n_steps) * s.step_s - s.duration) > kGridTolS || s.n_steps < 1)
    fail("'duration' " + num(s.duration) + " s is not a whole number of steps of " + num(s.step_s) + " s");
  if (s.n_steps > kMaxSteps) fail("'duration' asks for more than " + std::to_string(kMaxSteps) + " steps");
  if (scene_read::Node v = t->get("record_every")) {
    if (!v->is_integer()) fail("'record_every' must be an integer");
    s.record_every = *v->value<int64_t>();
    if (s.record_every < 1 || s.record_every > kMaxRecordEvery)
      fail("'record_every' must be in 1.." + std::to_string(kMaxRecordEvery) + " (got " +
           std::to_string(s.record_every) + ")");
  }
  if (s.n_steps / s.record_every + 1 > kMaxSamples)
    fail("'duration' / ('step_s' x 'record_every') asks for more than " + std::to_string(kMaxSamples) + " samples");
  return s;
}

// [ground]: the file's plane turned to slope (rad) rising toward uphill (rad about z from x),
// its friction replaced; each key left out keeps the file's.
struct GroundKeys {
  bool has_slope = false, has_mu_static = false, has_mu_kinetic = false;
  double slope = 0, uphill = 0, mu_static = 0, mu_kinetic = 0;
};

inline GroundKeys ground_keys(scene_read::Node v) {
  using scene_read::fail;
  GroundKeys s;
  if (!v) return s;
  scene_read::Table g = v->as_table();
  const std::string gw = "ground: ";
  if (!g) fail("'ground' must be a table {slope, uphill, mu_static, mu_kinetic}");
  scene_read::check_keys(g, {"slope", "uphill", "mu_static", "mu_kinetic"}, gw);
  if (scene_read::Node x = g->get("slope")) s.has_slope = true, s.slope = ranged(x, gw + "'slope'", 0, LEGSIM_MAX_SLOPE_RAD);
  if (scene_read::Node x = g->get("uphill")) {
    if (!s.has_slope) fail(gw + "'uphill' needs 'slope'");
    s.uphill = ranged(x, gw + "'uphill'", -kPi, kPi);
  }
  if (scene_read::Node x = g->get("mu_static"))
    s.has_mu_static = true, s.mu_static = ranged(x, gw + "'mu_static'", 0, LEGSIM_MAX_FRICTION);
  if (scene_read::Node x = g->get("mu_kinetic"))
    s.has_mu_kinetic = true, s.mu_kinetic = ranged(x, gw + "'mu_kinetic'", 0, LEGSIM_MAX_FRICTION);
  return s;
}

// The scene's ground over the file's (h's); refused when mu_kinetic > mu_static.
inline void ground_apply(const GroundKeys &s, legsim_hexapod_desc &h) {
  if (s.has_slope) {
    h.ground_normal[0] = -std::sin(s.slope) * std::cos(s.uphill);
    h.ground_normal[1] = -std::sin(s.slope) * std::sin(s.uphill);
    h.ground_normal[2] = std::cos(s.slope);
  }
  if (s.has_mu_static) h.mu_static = s.mu_static;
  if (s.has_mu_kinetic) h.mu_kinetic = s.mu_kinetic;
  if (!(h.mu_kinetic <= h.mu_static))
    scene_read::fail("ground: mu_kinetic " + scene_text::num(h.mu_kinetic) + " must be at most mu_static " +
                     scene_text::num(h.mu_static));
}

// The scene's hexapod file into h; false, the loader's message on err, when it is refused.
inline bool load_scene_model(const std::string &model_path, const std::string &scene_path, legsim_hexapod_desc &h,
                             std::ostream &err) {
  char msg[512];
  if (legsim_hexapod_load_toml(model_path.c_str(), &h, msg, sizeof msg) == LEGSIM_OK) return true;
  err << "legsim_cli: error: " << msg << " (model of " << scene_path << ")\n";
  return false;
}

inline std::string status_text(legsim_status st) {
  return std::string(status_enum_name(st)) + " (" + legsim_status_str(st) + ")";
}

}  // namespace hexapod_scene
}  // namespace legsim_host

#endif  // LEGSIM_HOST_SCENE_HEXAPOD_COMMON_HPP
