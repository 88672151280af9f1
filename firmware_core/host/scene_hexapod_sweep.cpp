// Hexapod scenes of analysis "reaction_sweep": reading, checking and running them through
// legsim_hexapod_reaction_sweep, and their JSON. The keys: scenes/README.md, "The hexapod",
// "Section V: the reactions over a foot's reach". Host only.
#include "scene_hexapod_sweep.hpp"

#include <cctype>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <toml++/toml.h>

#include "legsim/hexapod.h"
#include "model_toml.hpp"
#include "scene_hexapod_common.hpp"
#include "toml_limits.hpp"

namespace legsim_host {
namespace {

using namespace hexapod_scene;
using scene_read::check_keys;
using scene_read::fail;
using scene_read::Node;
using scene_read::Table;
using scene_text::name_of;
using scene_text::num;
using scene_text::q;

constexpr int64_t kMaxPoints = 1000000;  // legsim_hexapod_reaction_sweep's grid
constexpr int kChunk = 256;              // points asked of the library at a time

// A leg as written: an index 0..5, or a name bound once the file is read.
struct LegRef {
  int index = -1;
  std::string name;
};

struct SweepScene {
  std::string path, name, description, model, model_path;
  LegRef leg = {0, ""};
  std::vector<LegRef> stance = {{0, ""}, {2, ""}, {4, ""}};
  legsim_hexapod_sweep sweep = {0, 0, 1.0, {0.40, 0.62}, 23, {0, 0}, 1};
  int64_t part = 1, parts = 1;                 // this run's part of the grid (1-based)
};

LegRef leg_ref(Node v, const std::string &what) {
  if (v && v->is_integer()) {
    const int64_t k = *v->value<int64_t>();
    if (k < 0 || k >= L) fail(what + " must be a leg's name or an index 0..5 (got " + std::to_string(k) + ")");
    return {static_cast<int>(k), ""};
  }
  if (v && v->is_string()) return {-1, std::string(*v->value<std::string_view>())};
  fail(what + " must be a leg's name or an index 0..5");
}

int bind_leg(const LegRef &leg, const legsim_hexapod_desc &h, const std::string &what) {
  if (leg.index >= 0) return leg.index;
  for (int k = 0; k < L; ++k)
    if (name_of(h.leg[k].name) == leg.name) return k;
  fail(what + ": the file has no leg " + q(leg.name));
}

// [first, last] of a grid's axis
void pair_of(Node v, const std::string &what, double lo, double hi, double out[2]) {
  const toml::array *a = v->as_array();
  if (!a || a->size() != 2) fail(what + " must be [first, last]");
  for (int i = 0; i < 2; ++i) out[i] = ranged(a->get(i), what + "[" + std::to_string(i) + "]", lo, hi);
}

int count_of(Node v, const std::string &what) {
  if (!v->is_integer() || *v->value<int64_t>() < 1 || *v->value<int64_t>() > kMaxPoints)
    fail(what + " must be an integer in 1.." + std::to_string(kMaxPoints));
  return static_cast<int>(*v->value<int64_t>());
}

SweepScene parse(const toml::table &doc, const std::string &path) {
  SweepScene s;
  s.path = path;
  Table t = &doc;
  check_keys(t,
             {"description", "name", "model", "analysis", "leg", "stance", "box_height", "distance", "n_distance",
              "heading", "n_heading", "part"},
             "");
  const SceneHead head = scene_head(t, path);
  s.model = head.model, s.model_path = head.model_path, s.name = head.name, s.description = head.description;
  if (Node v = t->get("leg")) s.leg = leg_ref(v, "'leg'");
  if (Node v = t->get("stance")) {
    const toml::array *a = v->as_array();
    if (!a || a->size() < 3 || a->size() > L) fail("'stance' must list 3 to 6 legs (names or indices 0..5)");
    s.stance.clear();
    for (size_t i = 0; i < a->size(); ++i) s.stance.push_back(leg_ref(a->get(i), "'stance'[" + std::to_string(i) + "]"));
  }
  legsim_hexapod_sweep &w = s.sweep;
  if (Node v = t->get("box_height")) w.box_height_m = ranged(v, "'box_height'", 0, 10, true);
  if (Node v = t->get("distance")) pair_of(v, "'distance'", LEGSIM_MIN_LENGTH_M, 10, w.distance_m);
  if (Node v = t->get("heading")) pair_of(v, "'heading'", -kPi, kPi, w.heading_rad);
  if (Node v = t->get("n_distance")) w.n_distance = count_of(v, "'n_distance'");
  if (Node v = t->get("n_heading")) w.n_heading = count_of(v, "'n_heading'");
  if (int64_t(w.n_distance) * w.n_heading > kMaxPoints)
    fail("'n_distance' x 'n_heading' must be at most " + std::to_string(kMaxPoints) + " points");
  if (Node v = t->get("part")) {
    const toml::array *a = v->as_array();
    if (!a || a->size() != 2 || !a->get(0)->is_integer() || !a->get(1)->is_integer())
      fail("'part' must be [k, n]: the k-th of n parts (1 <= k <= n)");
    s.part = *a->get(0)->value<int64_t>(), s.parts = *a->get(1)->value<int64_t>();
    if (s.parts < 1 || s.parts > int64_t(w.n_distance) * w.n_heading || s.part < 1 || s.part > s.parts)
      fail("'part' must be [k, n] with 1 <= k <= n <= the grid's points (got [" + std::to_string(s.part) + ", " +
           std::to_string(s.parts) + "])");
  }
  return s;
}

void write_head(std::ostream &o, const SweepScene &s, const legsim_hexapod_desc &h, int64_t first, int64_t count) {
  const legsim_hexapod_sweep &w = s.sweep;
  o << "{\"scene\": " << jstr(s.path) << ", \"name\": " << jstr(s.name) << ", \"kind\": \"hexapod\""
    << ", \"description\": " << jstr(s.description) << ", \"demo\": false, \"model\": " << jstr(s.model)
    << ", \"model_path\": " << jstr(s.model_path) << ", \"model_name\": " << jstr(name_of(h.name))
    << ", \"analysis\": \"reaction_sweep\",\n  \"legs\": [";
  for (int k = 0; k < L; ++k) o << (k ? ", " : "") << jstr(name_of(h.leg[k].name));
  o << "], \"leg_actuators\": [" << jstr(name_of(h.leg[0].leg.actuator[0].name)) << ", "
    << jstr(name_of(h.leg[0].leg.actuator[1].name)) << "], \"ground\": {\"point\": " << jarr(h.ground_point_m)
    << ", \"normal\": " << jarr(h.ground_normal) << ", \"mu_static\": " << jnum(h.mu_static)
    << ", \"mu_kinetic\": " << jnum(h.mu_kinetic) << "}, \"gravity\": " << jarr(h.gravity_mps2)
    << ", \"mass\": " << jnum(total_mass(h)) << ", \"checks\": null,\n  \"sweep\": {\"leg\": "
    << jstr(name_of(h.leg[w.leg].name)) << ", \"stance\": [";
  for (int k = 0, n = 0; k < L; ++k)
    if ((w.stance_mask >> k) & 1u) o << (n++ ? ", " : "") << jstr(name_of(h.leg[k].name));
  o << "], \"box_height_m\": " << jnum(w.box_height_m) << ", \"distance_m\": " << jarr(w.distance_m)
    << ", \"n_distance\": " << w.n_distance << ", \"heading_rad\": " << jarr(w.heading_rad)
    << ", \"n_heading\": " << w.n_heading << ", \"part\": [" << s.part << ", " << s.parts << "], \"first\": " << first
    << ", \"count\": " << count << "}";
}

void write_point(std::ostream &o, const legsim_hexapod_sweep_point &p, const legsim_hexapod_desc &h, bool first) {
  o << (first ? "\n    " : ",\n    ") << "{\"index\": " << p.index << ", \"distance\": " << jnum(p.distance_m)
    << ", \"heading\": " << jnum(p.heading_rad) << ", \"status_code\": " << jstr(status_enum_name(p.status));
  if (p.status == LEGSIM_OK) {
    const legsim_hexapod_standing &s = p.standing;
    o << ", \"rowing\": " << jnum(p.rowing_rad) << ", \"lengths\": " << jarr(p.length_m) << ", \"com\": "
      << jarr(s.com_m) << ", \"margin\": " << jnum(s.margin_m) << ",\n     \"actuator_forces\": [";
    for (int k = 0; k < L; ++k) o << (k ? ", " : "") << jarr(s.actuator_force_n[k]);
    o << "], \"rowing_torques\": " << jarr(s.rowing_torque_nm) << ",\n     \"feet\": {";
    for (int k = 0; k < L; ++k)
      o << (k ? ", " : "") << jstr(name_of(h.leg[k].name)) << ": {\"x\": " << jarr(s.foot_m[k])
        << ", \"force\": " << jarr(s.foot_force_n[k]) << "}";
    o << "}";
  }
  o << "}";
}

}  // namespace

bool scene_is_hexapod_sweep(const std::string &text, const std::string &path) {
  return scene_analysis_is(text, path, "reaction_sweep");
}

int run_hexapod_sweep_scene(const std::string &text, const std::string &path, bool check_only, HexapodOutput &out,
                            std::ostream &err) {
  SweepScene s;
  auto h = std::make_unique<legsim_hexapod_desc>();
  try {
    s = parse(scene_document(text, path), path);
    if (!load_scene_model(s.model_path, path, *h, err)) return 2;
    s.sweep.leg = bind_leg(s.leg, *h, "'leg'");
    s.sweep.stance_mask = 0;
    for (size_t i = 0; i < s.stance.size(); ++i) {
      const int k = bind_leg(s.stance[i], *h, "'stance'[" + std::to_string(i) + "]");
      if ((s.sweep.stance_mask >> k) & 1u) fail("'stance' names leg " + q(name_of(h->leg[k].name)) + " twice");
      s.sweep.stance_mask |= 1u << k;
    }
    if (!((s.sweep.stance_mask >> s.sweep.leg) & 1u)) fail("'leg' must be one of the 'stance'");
  } catch (const scene_read::SceneError &f) {
    err << "legsim_cli: error: " << path << ": " << f.message << "\n";
    return 2;
  }
  const int64_t total = int64_t(s.sweep.n_distance) * s.sweep.n_heading;
  const int64_t first = (s.part - 1) * total / s.parts, last = s.part * total / s.parts;
  Storage st(legsim_hexapod_storage_size());
  std::vector<legsim_hexapod_sweep_point> pts(static_cast<size_t>(std::min<int64_t>(kChunk, last - first)));
  // the sweep's values checked by the library on its first point (exit 2, nothing written)
  legsim_status r = legsim_hexapod_reaction_sweep(h.get(), &s.sweep, int32_t(first), 1, st.p, st.bytes, pts.data());
  if (r != LEGSIM_OK) {
    err << "legsim_cli: error: " << path << ": the sweep: " << status_text(r) << "\n";
    return 2;
  }
  std::ostream *o = out.open();
  if (!o) return 2;
  write_head(*o, s, *h, first, last - first);
  if (check_only) {
    *o << "}\n";
    return 0;
  }
  *o << ",\n  \"points\": [";
  int64_t ok = 0;
  double max_force[2] = {0, 0}, max_normal = 0;
  for (int64_t at = first; at < last; at += kChunk) {
    const int32_t n = int32_t(std::min<int64_t>(kChunk, last - at));
    r = legsim_hexapod_reaction_sweep(h.get(), &s.sweep, int32_t(at), n, st.p, st.bytes, pts.data());
    if (r != LEGSIM_OK) {  // the values were good on the first point: not expected
      const std::string m = "the sweep at point " + std::to_string(at) + ": " + status_text(r);
      *o << "\n  ],\n  \"status\": \"error\", \"status_code\": " << jstr(status_enum_name(r)) << ", \"error\": "
         << jstr(m) << "}\n";
      err << "legsim_cli: error: " << s.path << ": " << m << "\n";
      return 1;
    }
    for (int i = 0; i < n; ++i) {
      const legsim_hexapod_sweep_point &p = pts[i];
      write_point(*o, p, *h, at + i == first);
      if (p.status != LEGSIM_OK) continue;
      ++ok;
      for (int l = 0; l < L; ++l) {
        for (int a = 0; a < 2; ++a) max_force[a] = std::fmax(max_force[a], std::fabs(p.standing.actuator_force_n[l][a]));
        max_normal = std::fmax(max_normal, p.standing.foot_force_n[l][2]);
      }
    }
  }
  *o << "\n  ],\n  \"summary\": {\"points\": " << (last - first) << ", \"standing\": " << ok
     << ", \"max_actuator_force\": " << jarr(max_force) << ", \"max_foot_force_z\": " << jnum(max_normal)
     << "},\n  \"status\": \"ok\", \"status_code\": \"LEGSIM_OK\"}\n";
  return 0;
}

}  // namespace legsim_host
