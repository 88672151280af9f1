// What the hexapod's scene readers and writers share (scene_hexapod.cpp, scene_hexapod_inverse.cpp,
// scene_hexapod_sweep.cpp): the strings' and numbers' JSON, the TOML values' checks, the C API's
// aligned storage and a status's text. Host only; internal to them.
#ifndef LEGSIM_HOST_SCENE_HEXAPOD_COMMON_HPP
#define LEGSIM_HOST_SCENE_HEXAPOD_COMMON_HPP

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <new>
#include <ostream>
#include <string>

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
