// Hexapod scenes of analysis "inverse_gait": reading, checking and running them through
// legsim_hexapod_inverse_dynamics, and their JSON. The keys: scenes/README.md, "The hexapod",
// "Inverse dynamics along the gait". Host only.
#include "scene_hexapod_inverse.hpp"

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <new>
#include <string>

#include <toml++/toml.h>

#include "legsim/hexapod.h"
#include "model_toml.hpp"
#include "scene_hexapod_common.hpp"
#include "scene_read.hpp"
#include "scene_text.hpp"
#include "scene_toml.hpp"
#include "toml_limits.hpp"

namespace legsim_host {
namespace {

using namespace hexapod_scene;
using scene_read::check_keys;
using scene_read::fail;
using scene_read::Node;
using scene_read::real_of;
using scene_read::Table;
using scene_text::name_of;
using scene_text::num;
using scene_text::q;


struct InverseScene {
  std::string path, name, description, model, model_path;
  legsim_hexapod_gait gait{};
  double step_s = 0.01, duration = 0;
  int64_t n = 0;  // samples after t = 0
};

InverseScene parse(const toml::table &doc, const std::string &path) {
  InverseScene s;
  s.path = path;
  Table t = &doc;
  check_keys(t, {"description", "name", "model", "analysis", "gait", "step_s", "duration"}, "");
  const SceneHead head = scene_head(t, path);
  s.model = head.model, s.model_path = head.model_path, s.name = head.name, s.description = head.description;
  Table g = t->get("gait") ? t->get("gait")->as_table() : nullptr;
  const std::string gw = "gait: ";
  if (!g) fail("'gait' must be a table {period_s, duty, step_length_m, step_height_m, turn_rad, box_height_m}");
  check_keys(g, {"period_s", "duty", "step_length_m", "step_height_m", "turn_rad", "box_height_m"}, gw);
  for (const char *k : {"period_s", "duty", "step_length_m", "step_height_m", "box_height_m"})
    if (!g->get(k)) fail(gw + "missing key " + q(k));
  s.gait.period_s = ranged(g->get("period_s"), gw + "'period_s'", 0, 1e3, true);
  s.gait.duty = ranged(g->get("duty"), gw + "'duty'", 0.5, 1, false, true);
  s.gait.step_length_m = ranged(g->get("step_length_m"), gw + "'step_length_m'", 0, LEGSIM_MAX_COORD);
  s.gait.step_height_m = ranged(g->get("step_height_m"), gw + "'step_height_m'", 0, LEGSIM_MAX_COORD);
  s.gait.turn_rad = g->get("turn_rad") ? ranged(g->get("turn_rad"), gw + "'turn_rad'", -kPi / 2, kPi / 2, true, true) : 0;
  s.gait.box_height_m = ranged(g->get("box_height_m"), gw + "'box_height_m'", 0, 10, true);
  if (Node v = t->get("step_s")) s.step_s = ranged(v, "'step_s'", 1e-6, 10);
  s.duration = t->get("duration") ? ranged(t->get("duration"), "'duration'", 0, 1e6, true) : s.gait.period_s;
  s.n = static_cast<int64_t>(std::llround(s.duration / s.step_s));
  if (std::fabs(static_cast<double>(s.n) * s.step_s - s.duration) > kGridTolS || s.n < 1)
    fail("'duration' " + num(s.duration) + " s is not a whole number of samples of " + num(s.step_s) + " s");
  if (s.n + 1 > kMaxSamples) fail("'duration' / 'step_s' asks for more than " + std::to_string(kMaxSamples) + " samples");
  return s;
}

// the header (as the other hexapod scenes', analysis "inverse_gait") and the settings
void write_head(std::ostream &o, const InverseScene &s, const legsim_hexapod_desc &h) {
  const legsim_hexapod_gait &g = s.gait;
  o << "{\"scene\": " << jstr(s.path) << ", \"name\": " << jstr(s.name) << ", \"kind\": \"hexapod\""
    << ", \"description\": " << jstr(s.description) << ", \"demo\": false, \"model\": " << jstr(s.model)
    << ", \"model_path\": " << jstr(s.model_path) << ", \"model_name\": " << jstr(name_of(h.name))
    << ", \"analysis\": \"inverse_gait\",\n  \"legs\": [";
  for (int k = 0; k < L; ++k) o << (k ? ", " : "") << jstr(name_of(h.leg[k].name));
  o << "], \"leg_actuators\": [" << jstr(name_of(h.leg[0].leg.actuator[0].name)) << ", "
    << jstr(name_of(h.leg[0].leg.actuator[1].name)) << "], \"ground\": {\"point\": " << jarr(h.ground_point_m, 3)
    << ", \"normal\": " << jarr(h.ground_normal, 3) << ", \"mu_static\": " << jnum(h.mu_static)
    << ", \"mu_kinetic\": " << jnum(h.mu_kinetic) << "},\n  \"checks\": null, \"step_s\": " << jnum(s.step_s)
    << ", \"duration\": " << jnum(s.duration) << ", \"n_steps\": " << s.n << ", \"record_every\": 1"
    << ", \"lift\": 0,\n  \"gait\": {\"period_s\": " << jnum(g.period_s) << ", \"duty\": " << jnum(g.duty)
    << ", \"step_length_m\": " << jnum(g.step_length_m) << ", \"step_height_m\": " << jnum(g.step_height_m)
    << ", \"turn_rad\": " << jnum(g.turn_rad) << ", \"box_height_m\": " << jnum(g.box_height_m) << "}";
}

void write_sample(std::ostream &o, const legsim_hexapod_inverse &r, const legsim_hexapod_desc &h, bool first) {
  o << (first ? "\n    " : ",\n    ") << "{\"t\": " << jnum(r.t_s) << ", \"box\": " << jarr(r.box_m, 3)
    << ", \"box_quat\": " << jarr(r.box_quat, 4) << ", \"box_velocity\": " << jarr(r.box_velocity_mps, 3)
    << ", \"box_omega\": " << jarr(r.box_omega_radps, 3) << ", \"actuator_forces\": [";
  for (int k = 0; k < L; ++k) o << (k ? ", " : "") << jarr(r.actuator_force_n[k], 2);
  o << "], \"rowing_torques\": " << jarr(r.rowing_torque_nm, L) << ",\n     \"feet\": {";
  for (int k = 0; k < L; ++k)
    o << (k ? ", " : "") << jstr(name_of(h.leg[k].name)) << ": {\"state\": " << (r.stance[k] ? "\"stuck\"" : "\"free\"")
      << ", \"x\": " << jarr(r.foot_m[k], 3) << ", \"velocity\": " << jarr(r.foot_velocity_mps[k], 3)
      << ", \"acceleration\": " << jarr(r.foot_acceleration_mps2[k], 3) << ", \"force\": " << jarr(r.foot_force_n[k], 3)
      << ", \"cone_ratio\": " << jnum(r.cone_ratio[k]) << "}";
  o << "},\n     \"reactions\": {";
  for (int k = 0; k < L; ++k) {
    o << (k ? ", " : "") << jstr(name_of(h.leg[k].name)) << ": [";
    for (int j = 0; j < r.n_joints[k]; ++j)
      o << (j ? ", " : "") << "{\"joint\": " << jstr(j == 0 ? "hip" : name_of(h.leg[k].leg.joint[j - 1].name))
        << ", \"force\": " << jarr(r.joint_force_n[k][j], 3) << ", \"moment\": " << jarr(r.joint_moment_nm[k][j], 3) << "}";
    o << "]";
  }
  o << "}}";
}

}  // namespace

bool scene_is_hexapod_inverse(const std::string &text, const std::string &path) {
  return scene_analysis_is(text, path, "inverse_gait");
}

int run_hexapod_inverse_scene(const std::string &text, const std::string &path, bool check_only, HexapodOutput &out,
                              std::ostream &err) {
  InverseScene s;
  auto h = std::make_unique<legsim_hexapod_desc>();
  try {
    s = parse(scene_document(text, path), path);
  } catch (const scene_read::SceneError &f) {
    err << "legsim_cli: error: " << path << ": " << f.message << "\n";
    return 2;
  }
  if (!load_scene_model(s.model_path, path, *h, err)) return 2;
  Storage st(legsim_hexapod_inverse_storage_size());
  auto r = std::make_unique<legsim_hexapod_inverse>();
  // the gait's start: refused (exit 2) when it asks a leg past its strokes or reach at t = 0
  const legsim_status s0 = legsim_hexapod_inverse_dynamics(h.get(), &s.gait, 0.0, st.p, st.bytes, r.get());
  if (s0 != LEGSIM_OK) {
    err << "legsim_cli: error: " << path << ": gait: its inverse dynamics at t = 0: " << status_text(s0) << "\n";
    return 2;
  }
  std::ostream *o = out.open();
  if (!o) return 2;
  write_head(*o, s, *h);
  if (check_only) {
    *o << "}\n";
    return 0;
  }
  *o << ",\n  \"samples\": [";
  double max_ratio = 0, max_force[2] = {0, 0}, max_torque = 0;
  for (int64_t k = 0; k <= s.n; ++k) {
    const double t = static_cast<double>(k) * s.step_s;
    const legsim_status rs = k ? legsim_hexapod_inverse_dynamics(h.get(), &s.gait, t, st.p, st.bytes, r.get()) : s0;
    if (rs != LEGSIM_OK) {
      const std::string m = "the inverse dynamics at t = " + num(t) + " s: " + status_text(rs);
      *o << "\n  ],\n  \"status\": \"error\", \"status_code\": " << jstr(status_enum_name(rs)) << ", \"error\": " << jstr(m)
         << ", \"failed_at\": " << jnum(t) << "}\n";
      err << "legsim_cli: error: " << s.path << ": " << m << "\n";
      return 1;
    }
    write_sample(*o, *r, *h, k == 0);
    for (int l = 0; l < L; ++l) {
      max_ratio = std::fmax(max_ratio, r->cone_ratio[l]);
      for (int a = 0; a < 2; ++a) max_force[a] = std::fmax(max_force[a], std::fabs(r->actuator_force_n[l][a]));
      max_torque = std::fmax(max_torque, std::fabs(r->rowing_torque_nm[l]));
    }
  }
  *o << "\n  ],\n  \"summary\": {\"max_cone_ratio\": " << jnum(max_ratio)
     << ", \"max_actuator_force\": " << jarr(max_force, 2) << ", \"max_rowing_torque\": " << jnum(max_torque)
     << ", \"friction_enough\": " << (max_ratio <= h->mu_static ? "true" : "false")
     << "},\n  \"status\": \"ok\", \"status_code\": \"LEGSIM_OK\"}\n";
  return 0;
}

}  // namespace legsim_host
