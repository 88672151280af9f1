// Hexapod scenes: parsing, checking and running a scene whose model is a hexapod file, and its
// JSON. The keys, units, defaults and ranges: scenes/README.md, "The hexapod". Host only; the
// hexapod's C API only (legsim/hexapod.h), the walk driven as legsim.Hexapod.walk drives it.
#include "scene_hexapod.hpp"
#include "scene_block.hpp"
#include "scene_hexapod_common.hpp"
#include "scene_hexapod_inverse.hpp"
#include "scene_hexapod_sweep.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <new>
#include <sstream>
#include <string>
#include <vector>

#include <toml++/toml.h>

#include "legsim/hexapod.h"
#include "legsim/legsim.h"
#include "model_toml.hpp"
#include "scene_text.hpp"
#include "scene_read.hpp"
#include "scene_toml.hpp"
#include "toml_limits.hpp"

namespace legsim_host {
namespace {

using namespace hexapod_scene;
using scene_text::name_of;
using scene_text::num;
using scene_text::q;

constexpr double kMaxBoxHeightM = 10.0;
constexpr double kMaxLiftM = 1.0;
constexpr double kMaxBoxLoadN = 1e6;
constexpr const char *kWhich[3] = {"upper", "lower", "rowing"};
constexpr const char *kFootState[3] = {"free", "stuck", "sliding"};  // legsim_contact_state

using scene_read::check_keys;
using scene_read::fail;
using scene_read::is_number;
using scene_read::Node;
using scene_read::real_of;
using scene_read::Table;
using Fail = scene_read::SceneError;

// A leg as written: a name of the file's [[leg]]s or an index 0..5 (bound once the file is read).
struct LegRef {
  std::string name;
  int64_t index = -1;
  std::string text() const { return index >= 0 ? std::to_string(index) : q(name); }
};

LegRef leg_ref(Node v, const std::string &what) {
  LegRef r;
  if (v && v->is_integer()) {
    r.index = *v->value<int64_t>();
  } else if (v && v->is_string()) {
    r.name = std::string(*v->value<std::string_view>());
  } else {
    fail(what + " must be a leg's name or its index 0..5");
  }
  return r;
}

std::vector<LegRef> leg_list(Node v, const std::string &what) {
  const toml::array *a = v ? v->as_array() : nullptr;
  if (!a) fail(what + " must be a list of legs (names or indices 0..5)");
  std::vector<LegRef> out;
  for (size_t i = 0; i < a->size(); ++i) out.push_back(leg_ref(a->get(i), what + "[" + std::to_string(i) + "]"));
  return out;
}

struct Offset {
  LegRef leg;
  int which = 0;  // 0 upper, 1 lower (N), 2 rowing (N m)
  double value = 0;
};

enum class HexAnalysis { kStatics, kDynamics };

struct HexScene : RunKeys, GroundKeys {
  std::string path, name, description, model, model_path;
  HexAnalysis analysis = HexAnalysis::kDynamics;
  bool has_box_height = false, has_rowing = false, has_lengths = false;
  double box_height = 0, rowing[L] = {}, lengths[L][2] = {};
  bool has_stance = false;
  std::vector<LegRef> stance;
  bool has_box_load = false;
  double box_load[3] = {0, 0, 0};
  // dynamics (RunKeys: step_s, integrator, duration, record_every)
  double lift = 0;
  bool has_stuck = false;
  std::vector<LegRef> stuck;
  bool force_control = false;  // control = "force" (else "servo")
  std::vector<Offset> offsets;
  bool has_gait = false;
  legsim_hexapod_gait gait{};
  std::string checks_json = "null";  // [checks] resolved (tests/model/check_cli_output.py runs them)
  std::vector<LegRef> stuck_at_end;   // [checks] stuck_at_end, as written
  // bound against the file
  uint32_t stance_mask = 0x3f, stuck_mask = 0;
};

const std::vector<std::string> kCommonKeys = {"description", "name", "model", "analysis", "box_height", "rowing",
                                              "lengths", "ground", "checks"};

std::string checks_of(Node v, bool statics, std::vector<LegRef> &stuck_at_end) {
  const std::vector<std::string> targets =
      statics ? std::vector<std::string>{"margin_m"}
              : std::vector<std::string>{"box_x_m", "box_y_m", "box_z_m", "yaw_rad", "roll_rad", "touchdown_s"};
  const std::vector<std::string> bounds =
      statics ? std::vector<std::string>{}
              : std::vector<std::string>{"height_off_m", "tilt_max_rad", "settle_m", "margin_min_m", "friction_use_max",
                                         "slip_mu_off", "slip_angle_max_rad", "friction_work_off"};
  const std::vector<std::string> others =
      statics ? std::vector<std::string>{} : std::vector<std::string>{"impacts_min", "stuck_at_end"};
  return checks_json(v, targets, bounds, others, [&](const std::string &key, Node x) {
    stuck_at_end = leg_list(x, "checks: " + q(key));
    return std::string("@STUCK_AT_END@");  // the names, once bound against the file
  });
}
const std::vector<std::string> kStaticsKeys = {"stance", "box_load"};
const std::vector<std::string> kDynamicsKeys = {"step_s",  "duration", "record_every", "stuck", "lift",
                                                "control", "offset",   "gait",         "integrator"};

HexScene parse(const toml::table &doc, const std::string &path) {
  HexScene s;
  s.path = path;
  Table t = &doc;
  const SceneHead head = scene_head(t, path);
  s.model = head.model, s.model_path = head.model_path, s.name = head.name, s.description = head.description;
  const std::string an = t->get("analysis") ? string_of(t->get("analysis"), "'analysis'") : "dynamics";
  if (an == "statics") {
    s.analysis = HexAnalysis::kStatics;
  } else if (an == "dynamics") {
    s.analysis = HexAnalysis::kDynamics;
  } else {
    fail("'analysis' of a hexapod must be statics or dynamics (got " + q(an) + ")");
  }
  // the keys of the other analysis are refused by name, the unknown ones with the list
  std::vector<std::string> allowed = kCommonKeys;
  const auto &own = s.analysis == HexAnalysis::kStatics ? kStaticsKeys : kDynamicsKeys;
  const auto &other = s.analysis == HexAnalysis::kStatics ? kDynamicsKeys : kStaticsKeys;
  for (const auto &k : other)
    if (t->get(k)) fail(q(k) + " applies to a hexapod's " + (s.analysis == HexAnalysis::kStatics ? "dynamics" : "statics") +
                        " only");
  allowed.insert(allowed.end(), own.begin(), own.end());
  check_keys(t, allowed, "");

  if (Node v = t->get("box_height")) {
    s.has_box_height = true;
    s.box_height = ranged(v, "'box_height'", 0, kMaxBoxHeightM, true);
  }
  if (Node v = t->get("rowing")) {
    const toml::array *a = v->as_array();
    if (!a || a->size() != L) fail("'rowing' must be six angles (rad), one per leg in the file's order");
    s.has_rowing = true;
    for (int k = 0; k < L; ++k) s.rowing[k] = real_of(a->get(k), "'rowing'[" + std::to_string(k) + "]");
  }
  if (Node v = t->get("lengths")) {
    const toml::array *a = v->as_array();
    if (!a || a->size() != L) fail("'lengths' must be six pairs [upper, lower] (m), one per leg in the file's order");
    s.has_lengths = true;
    for (int k = 0; k < L; ++k) {
      const toml::array *p = a->get(k)->as_array();
      if (!p || p->size() != 2) fail("'lengths'[" + std::to_string(k) + "] must be [upper, lower] (m)");
      for (int j = 0; j < 2; ++j)
        s.lengths[k][j] = real_of(p->get(j), "'lengths'[" + std::to_string(k) + "][" + std::to_string(j) + "]");
    }
  }
  if (Node v = t->get("stance")) {
    s.has_stance = true;
    s.stance = leg_list(v, "'stance'");
  }
  if (Node v = t->get("box_load")) {
    const toml::array *a = v->as_array();
    if (!a || a->size() != 3) fail("'box_load' must be [Fx, Fy, Fz] (N, world, at the box's centre)");
    s.has_box_load = true;
    for (int i = 0; i < 3; ++i)
      s.box_load[i] = ranged(a->get(i), "'box_load'[" + std::to_string(i) + "]", -kMaxBoxLoadN, kMaxBoxLoadN);
  }
  static_cast<GroundKeys &>(s) = ground_keys(t->get("ground"));
  if (Node v = t->get("checks")) s.checks_json = checks_of(v, s.analysis == HexAnalysis::kStatics, s.stuck_at_end);
  if (s.analysis == HexAnalysis::kStatics) return s;

  static_cast<RunKeys &>(s) = run_keys(t);
  if (Node v = t->get("lift")) s.lift = ranged(v, "'lift'", 0, kMaxLiftM);
  if (Node v = t->get("stuck")) {
    s.has_stuck = true;
    s.stuck = leg_list(v, "'stuck'");
  }
  if (Node v = t->get("control")) {
    const std::string c = string_of(v, "'control'");
    if (c != "servo" && c != "force") fail("'control' must be servo or force (got " + q(c) + ")");
    s.force_control = c == "force";
  }
  if (Node v = t->get("offset")) {
    const toml::array *a = v->as_array();
    if (!a) fail("'offset' must be [[offset]] tables {leg, actuator, value}");
    for (size_t i = 0; i < a->size(); ++i) {
      Table o = a->get(i)->as_table();
      const std::string ow = "offset[" + std::to_string(i) + "]: ";
      if (!o) fail(ow + "must be a table {leg, actuator, value}");
      check_keys(o, {"leg", "actuator", "value"}, ow);
      Offset off;
      if (!o->get("leg")) fail(ow + "missing key 'leg'");
      off.leg = leg_ref(o->get("leg"), ow + "'leg'");
      const std::string act = string_of(o->get("actuator"), ow + "'actuator'");
      off.which = -1;
      for (int j = 0; j < 3; ++j)
        if (act == kWhich[j]) off.which = j;
      if (off.which < 0) fail(ow + "'actuator' must be upper, lower or rowing (got " + q(act) + ")");
      if (!o->get("value")) fail(ow + "missing key 'value'");
      off.value = real_of(o->get("value"), ow + "'value'");
      s.offsets.push_back(off);
    }
  }
  if (Node v = t->get("gait")) {
    Table g = v->as_table();
    const std::string gw = "gait: ";
    if (!g) fail("'gait' must be a table {period_s, duty, step_length_m, step_height_m, turn_rad, box_height_m}");
    check_keys(g, {"period_s", "duty", "step_length_m", "step_height_m", "turn_rad", "box_height_m"}, gw);
    for (const char *k : {"period_s", "duty", "step_length_m", "step_height_m", "box_height_m"})
      if (!g->get(k)) fail(gw + "missing key " + q(k));
    s.has_gait = true;
    s.gait.period_s = ranged(g->get("period_s"), gw + "'period_s'", 0, 1e3, true);
    s.gait.duty = ranged(g->get("duty"), gw + "'duty'", 0.5, 1, false, true);
    s.gait.step_length_m = ranged(g->get("step_length_m"), gw + "'step_length_m'", 0, LEGSIM_MAX_COORD);
    s.gait.step_height_m = ranged(g->get("step_height_m"), gw + "'step_height_m'", 0, LEGSIM_MAX_COORD);
    s.gait.turn_rad = g->get("turn_rad") ? ranged(g->get("turn_rad"), gw + "'turn_rad'", -kPi / 2, kPi / 2, true, true) : 0;
    s.gait.box_height_m = ranged(g->get("box_height_m"), gw + "'box_height_m'", 0, kMaxBoxHeightM, true);
    // the gait sets the pose, the stance and the commands: what would set them again is refused
    for (const char *k : {"box_height", "rowing", "lengths", "stuck", "lift", "control", "offset"})
      if (t->get(k)) fail(q(k) + " does not go with 'gait' (the gait sets the pose, the stuck feet and the servos)");
  }
  if (s.lift > 0 && s.has_stuck && !s.stuck.empty()) fail("'stuck' feet with 'lift' > 0: a foot in the air cannot be stuck");
  return s;
}

uint32_t bind_legs(const std::vector<LegRef> &legs, const legsim_hexapod_desc &h, const std::string &what) {
  uint32_t mask = 0;
  for (const auto &r : legs) {
    int k = -1;
    if (r.index >= 0 || r.name.empty()) {
      if (r.index < 0 || r.index >= L) fail(what + ": leg " + r.text() + " does not exist (indices 0..5)");
      k = static_cast<int>(r.index);
    } else {
      std::string have;
      for (int j = 0; j < L; ++j) {
        have += (j ? ", " : "") + name_of(h.leg[j].name);
        if (r.name == name_of(h.leg[j].name)) k = j;
      }
      if (k < 0) fail(what + ": the hexapod has no leg " + q(r.name) + " (its legs: " + have + ")");
    }
    if (mask >> k & 1u) fail(what + ": leg " + r.text() + " given twice");
    mask |= 1u << k;
  }
  return mask;
}


// legsim_hexapod_statics' storage, aligned as the API asks
bool sloped(const legsim_hexapod_desc &h) { return h.ground_normal[0] != 0 || h.ground_normal[1] != 0; }

// The scene's pose (statics, and dynamics without a gait): the stand's lengths, the box level
// over the origin with the stand's lowest foot at the ground point's height unless box_height
// says otherwise. On a sloped ground, without lengths and rowing: the box level box_height (else
// the stand's height) over the ground below the origin, each foot where the stand puts it seen
// from above, on the plane (the gait's set-points standing still).
legsim_hexapod_pose scene_pose(const HexScene &s, const legsim_hexapod_desc &h, Storage &st) {
  legsim_hexapod_pose p{};
  p.box_quat[0] = 1;
  for (int k = 0; k < L; ++k) {
    p.rowing_rad[k] = s.has_rowing ? s.rowing[k] : 0;
    const legsim_model_desc &leg = h.leg[k].leg;
    if (s.has_lengths) {
      for (int j = 0; j < 2; ++j) {
        const legsim_actuator_desc &a = leg.actuator[j];
        const double x = s.lengths[k][j];
        if (x < a.stroke_min_m || x > a.stroke_max_m)
          fail("'lengths'[" + std::to_string(k) + "][" + std::to_string(j) + "] = " + num(x) + " m is outside the stroke of " +
               name_of(h.leg[k].name) + "'s " + name_of(a.name) + " [" + num(a.stroke_min_m) + ", " +
               num(a.stroke_max_m) + "]");
        p.length_m[k][j] = x;
      }
    } else {
      // the leg file's stand: its first pose assembled, as Hexapod.stand_pose takes it
      std::vector<unsigned char> buf(legsim_sim_size() + LEGSIM_STORAGE_ALIGN);
      void *base = buf.data();
      size_t room = buf.size();
      void *aligned = std::align(LEGSIM_STORAGE_ALIGN, legsim_sim_size(), base, room);
      legsim_options o = legsim_default_options();
      legsim_sim *sim = nullptr;
      legsim_status r = legsim_init(aligned, legsim_sim_size(), &leg, &o, &sim);
      if (r == LEGSIM_OK) r = legsim_assemble_pose(sim, 0);
      legsim_real len[LEGSIM_MAX_ACTUATORS], rate[LEGSIM_MAX_ACTUATORS];
      if (r == LEGSIM_OK) r = legsim_actuator_lengths(sim, len, rate);
      if (r != LEGSIM_OK) fail("leg " + q(name_of(h.leg[k].name)) + ": its file's stand: " + status_text(r));
      for (int j = 0; j < 2; ++j) p.length_m[k][j] = static_cast<double>(len[j]);
    }
  }
  if (s.has_rowing)
    for (int k = 0; k < L; ++k)
      if (s.rowing[k] < h.rowing_stroke_rad[0] || s.rowing[k] > h.rowing_stroke_rad[1])
        fail("'rowing'[" + std::to_string(k) + "] = " + num(s.rowing[k]) + " rad is outside the rowing stroke [" +
             num(h.rowing_stroke_rad[0]) + ", " + num(h.rowing_stroke_rad[1]) + "]");
  // where the feet hang below the box's centre: statics on six feet at a trial height gives them
  p.box_m[2] = 1.0;
  legsim_hexapod_standing sd{};
  const legsim_status r = legsim_hexapod_statics(&h, &p, 0x3f, nullptr, st.p, st.bytes, &sd);
  if (r != LEGSIM_OK) fail("the pose: " + status_text(r));
  double drop = 0;
  for (int k = 0; k < L; ++k) drop = std::max(drop, 1.0 - sd.foot_m[k][2]);
  if (sloped(h) && !s.has_lengths && !s.has_rowing) {
    const legsim_hexapod_gait still = {1.0, 0.75, 0, 0, 0, s.has_box_height ? s.box_height : drop};
    legsim_hexapod_setpoint sp{};
    const legsim_status g = legsim_hexapod_gait_setpoints(&h, &still, 0.0, st.p, st.bytes, &sp);
    if (g != LEGSIM_OK) fail("the stand on the sloped ground: " + status_text(g));
    for (int k = 0; k < L; ++k) {
      p.rowing_rad[k] = sp.rowing_rad[k];
      p.length_m[k][0] = sp.length_m[k][0];
      p.length_m[k][1] = sp.length_m[k][1];
    }
    for (int i = 0; i < 3; ++i) p.box_m[i] = sp.box_m[i];
    return p;
  }
  // on the file's ground (a plane through ground_point; the box level over the origin)
  const double ground_z = h.ground_point_m[2];
  p.box_m[2] = s.has_box_height ? s.box_height : ground_z + drop;
  return p;
}

void write_pose(std::ostream &o, const legsim_hexapod_pose &p) {
  o << "{\"box\": " << jarr(p.box_m) << ", \"box_quat\": " << jarr(p.box_quat) << ", \"rowing\": " << jarr(p.rowing_rad)
    << ", \"lengths\": [";
  for (int k = 0; k < L; ++k) o << (k ? ", " : "") << jarr(p.length_m[k]);
  o << "]}";
}

std::string legs_json(uint32_t mask, const legsim_hexapod_desc &h) {
  std::string o = "[";
  bool first = true;
  for (int k = 0; k < L; ++k)
    if (mask >> k & 1u) {
      o += (first ? "" : ", ") + jstr(name_of(h.leg[k].name));
      first = false;
    }
  return o + "]";
}


// the header both the resolved scene and the results begin with
void write_head(std::ostream &o, const HexScene &s, const legsim_hexapod_desc &h) {
  o << "{\"scene\": " << jstr(s.path) << ", \"name\": " << jstr(s.name) << ", \"kind\": \"hexapod\""
    << ", \"description\": " << jstr(s.description) << ", \"demo\": false, \"model\": " << jstr(s.model)
    << ", \"model_path\": " << jstr(s.model_path) << ", \"model_name\": " << jstr(name_of(h.name))
    << ", \"analysis\": " << jstr(s.analysis == HexAnalysis::kStatics ? "statics" : "dynamics") << ",\n  \"legs\": [";
  for (int k = 0; k < L; ++k) o << (k ? ", " : "") << jstr(name_of(h.leg[k].name));
  o << "], \"leg_actuators\": [" << jstr(name_of(h.leg[0].leg.actuator[0].name)) << ", "
    << jstr(name_of(h.leg[0].leg.actuator[1].name)) << "], \"ground\": {\"point\": " << jarr(h.ground_point_m)
    << ", \"normal\": " << jarr(h.ground_normal) << ", \"mu_static\": " << jnum(h.mu_static)
    << ", \"mu_kinetic\": " << jnum(h.mu_kinetic) << "}, \"gravity\": " << jarr(h.gravity_mps2)
    << ", \"mass\": " << jnum(total_mass(h));
}

void write_settings(std::ostream &o, const HexScene &s, const legsim_hexapod_desc &h, const legsim_hexapod_pose &p) {
  o << ",\n  \"checks\": " << s.checks_json << ",\n  \"pose\": ";
  write_pose(o, p);
  if (s.analysis == HexAnalysis::kStatics) {
    o << ",\n  \"stance\": " << legs_json(s.stance_mask, h) << ", \"box_load\": " << jarr(s.box_load);
    return;
  }
  o << ",\n  \"integrator\": \"" << (s.integrator == LEGSIM_INTEGRATOR_GENERALIZED_ALPHA ? "generalized_alpha" : "rk4") << "\"";
  o << ",\n  \"step_s\": " << jnum(s.step_s) << ", \"step_ns\": " << s.step_ns << ", \"duration\": " << jnum(s.duration)
    << ", \"n_steps\": " << s.n_steps << ", \"record_every\": " << s.record_every << ", \"lift\": " << jnum(s.lift)
    << ", \"stuck\": " << legs_json(s.stuck_mask, h) << ", \"control\": "
    << jstr(s.has_gait ? "gait" : s.force_control ? "force" : "servo") << ",\n  \"offsets\": [";
  for (size_t i = 0; i < s.offsets.size(); ++i) {
    const Offset &f = s.offsets[i];
    o << (i ? ", " : "") << "{\"leg\": " << jstr(name_of(h.leg[f.leg.index].name)) << ", \"actuator\": " << jstr(kWhich[f.which])
      << ", \"value\": " << jnum(f.value) << "}";
  }
  o << "], \"gait\": ";
  if (s.has_gait) {
    const legsim_hexapod_gait &g = s.gait;
    o << "{\"period_s\": " << jnum(g.period_s) << ", \"duty\": " << jnum(g.duty) << ", \"step_length_m\": "
      << jnum(g.step_length_m) << ", \"step_height_m\": " << jnum(g.step_height_m) << ", \"turn_rad\": "
      << jnum(g.turn_rad) << ", \"box_height_m\": " << jnum(g.box_height_m) << "}";
  } else {
    o << "null";
  }
}

// The centre of mass (world) of the sim's bodies and the static stability margin about it of the
// feet of support (bit l: leg l) where they are.
void com_margin(const legsim_hexapod_sim *sim, const legsim_hexapod_desc &h, const legsim_hexapod_state &x,
                uint32_t support, double com[3], double &margin) {
  double m[kMaxBodies], pose[7 * kMaxBodies], M = 0;
  const int nm = body_masses(h, m);
  int32_t nb = 0;
  com[0] = com[1] = com[2] = 0;
  if (legsim_hexapod_body_poses(sim, pose, kMaxBodies, &nb) != LEGSIM_OK || nb != nm) {
    com[0] = com[1] = com[2] = margin = NAN;
    return;
  }
  for (int b = 0; b < nb; ++b) {
    M += m[b];
    for (int i = 0; i < 3; ++i) com[i] += m[b] * pose[7 * b + i];
  }
  for (int i = 0; i < 3; ++i) com[i] /= M;
  double feet[L][3];
  int n = 0;
  for (int k = 0; k < L; ++k)
    if (support >> k & 1u) {
      for (int i = 0; i < 3; ++i) feet[n][i] = x.foot_m[k][i];
      ++n;
    }
  if (legsim_hexapod_support_margin(feet, n, com, &margin) != LEGSIM_OK) margin = NAN;
}

void write_state_sample(std::ostream &o, const legsim_hexapod_state &x, const legsim_hexapod_desc &h, int64_t events,
                        bool first, const double com[3], double margin) {
  o << (first ? "\n    " : ",\n    ") << "{\"t\": " << jnum(x.t_s) << ", \"box\": " << jarr(x.box_m)
    << ", \"box_quat\": " << jarr(x.box_quat) << ", \"box_velocity\": " << jarr(x.box_velocity_mps)
    << ", \"box_omega\": " << jarr(x.box_omega_radps) << ", \"rowing\": " << jarr(x.rowing_rad) << ", \"lengths\": [";
  for (int k = 0; k < L; ++k) o << (k ? ", " : "") << jarr(x.length_m[k]);
  o << "], \"actuator_forces\": [";
  for (int k = 0; k < L; ++k) o << (k ? ", " : "") << jarr(x.actuator_force_n[k]);
  o << "], \"rowing_torques\": " << jarr(x.rowing_torque_nm) << ",\n     \"feet\": {";
  for (int k = 0; k < L; ++k) {
    const int fs = x.foot_state[k];
    o << (k ? ", " : "") << jstr(name_of(h.leg[k].name)) << ": {\"state\": "
      << jstr(fs >= 0 && fs < 3 ? kFootState[fs] : "unknown") << ", \"x\": " << jarr(x.foot_m[k])
      << ", \"force\": " << jarr(x.foot_force_n[k]) << "}";
  }
  o << "}, \"com\": [" << jnum(com[0]) << ", " << jnum(com[1]) << ", " << jnum(com[2]) << "], \"margin\": "
    << jnum(margin) << ", \"kinetic_energy\": " << jnum(x.kinetic_energy_j) << ", \"events\": " << events
    << ", \"impacts\": " << x.impacts << "}";
}

int run_statics(const HexScene &s, const legsim_hexapod_desc &h, const legsim_hexapod_pose &p, Storage &st,
                std::ostream &o, std::ostream &err) {
  legsim_hexapod_standing sd{};
  const legsim_status r =
      legsim_hexapod_statics(&h, &p, s.stance_mask, s.has_box_load ? s.box_load : nullptr, st.p, st.bytes, &sd);
  write_head(o, s, h);
  write_settings(o, s, h, p);
  if (r == LEGSIM_OK) {
    o << ",\n  \"statics\": {\"com\": " << jarr(sd.com_m) << ", \"margin\": " << jnum(sd.margin_m) << ", \"feet\": {";
    for (int k = 0; k < L; ++k)
      o << (k ? ", " : "") << "\n    " << jstr(name_of(h.leg[k].name)) << ": {\"stance\": "
        << ((s.stance_mask >> k & 1u) ? "true" : "false") << ", \"x\": " << jarr(sd.foot_m[k])
        << ", \"force\": " << jarr(sd.foot_force_n[k]) << "}";
    o << "},\n    \"actuator_forces\": [";
    for (int k = 0; k < L; ++k) o << (k ? ", " : "") << jarr(sd.actuator_force_n[k]);
    o << "], \"rowing_torques\": " << jarr(sd.rowing_torque_nm) << "},\n  \"status\": \"ok\", \"status_code\": \"LEGSIM_OK\"}\n";
    return 0;
  }
  const std::string why = "statics on " + legs_json(s.stance_mask, h) + ": " + status_text(r);
  o << ",\n  \"statics\": null, \"status\": \"error\", \"status_code\": " << jstr(status_enum_name(r))
    << ", \"error\": " << jstr(why) << "}\n";
  err << "legsim_cli: error: " << s.path << ": " << why << "\n";
  return 1;
}

// the statics of a planned pose on a stance: the servos' feed-forward (as Hexapod.walk's)
void feedforward(const legsim_hexapod_desc &h, const legsim_hexapod_pose &p, uint32_t stance, Storage &st,
                 double f[L][2], double tau[L], const std::string &what) {
  legsim_hexapod_standing sd{};
  const legsim_status r = legsim_hexapod_statics(&h, &p, stance, nullptr, st.p, st.bytes, &sd);
  if (r != LEGSIM_OK) throw RunFail{r, what + ": the statics (feed-forward): " + status_text(r)};
  for (int k = 0; k < L; ++k) {
    f[k][0] = sd.actuator_force_n[k][0];
    f[k][1] = sd.actuator_force_n[k][1];
    tau[k] = sd.rowing_torque_nm[k];
  }
}

int run_dynamics(const HexScene &s, const legsim_hexapod_desc &h, const legsim_hexapod_pose &p, Storage &st,
                 std::ostream &o, std::ostream &err) {
  Storage sim_st(legsim_hexapod_sim_size());
  legsim_hexapod_sim *sim = nullptr;
  write_head(o, s, h);
  write_settings(o, s, h, p);
  o << ",\n  \"samples\": [";
  double t_fail = 0;
  try {
    legsim_status r = legsim_hexapod_sim_init(sim_st.p, sim_st.bytes, &h, &p, s.stuck_mask, &sim);
    if (r != LEGSIM_OK) throw RunFail{r, "the start (legsim_hexapod_sim_init): " + status_text(r)};
    r = legsim_hexapod_set_integrator(sim, s.integrator);
    if (r != LEGSIM_OK) throw RunFail{r, "the integrator (legsim_hexapod_set_integrator): " + status_text(r)};
    double f[L][2], tau[L];
    uint32_t plan_stance = s.stuck_mask;  // the gait's stance at the last set-points
    // what a step commands: the gait's set-points at its end with their statics, or the fixed
    // commands of the start pose
    auto command_gait = [&](double t) {
      legsim_hexapod_setpoint sp{};
      legsim_status g = legsim_hexapod_gait_setpoints(&h, &s.gait, t, st.p, st.bytes, &sp);
      if (g != LEGSIM_OK) throw RunFail{g, "the gait's set-points at t = " + num(t) + " s: " + status_text(g)};
      legsim_hexapod_pose at = p;
      uint32_t stance = 0;
      for (int k = 0; k < L; ++k) {
        at.rowing_rad[k] = sp.rowing_rad[k];
        at.length_m[k][0] = sp.length_m[k][0];
        at.length_m[k][1] = sp.length_m[k][1];
        if (sp.stance[k]) stance |= 1u << k;
      }
      feedforward(h, at, stance, st, f, tau, "t = " + num(t) + " s");
      plan_stance = stance;
      g = legsim_hexapod_command_pose(sim, sp.length_m, sp.rowing_rad, f, tau);
      if (g != LEGSIM_OK) throw RunFail{g, "the gait's commands at t = " + num(t) + " s: " + status_text(g)};
    };
    if (s.has_gait) {
      command_gait(s.step_s);
    } else {
      // the statics of the start on its stuck feet (on all six when fewer than three stick)
      const uint32_t stance = __builtin_popcount(s.stuck_mask) >= 3 ? s.stuck_mask : 0x3fu;
      feedforward(h, p, stance, st, f, tau, "the start");
      for (const Offset &off : s.offsets) {
        if (off.which < 2) f[off.leg.index][off.which] += off.value;
        else tau[off.leg.index] += off.value;
      }
      for (int k = 0; k < L; ++k) {
        const std::string leg = name_of(h.leg[k].name);
        for (int j = 0; j < 2; ++j) {
          const double mf = h.leg[k].leg.actuator[j].max_force_n;
          if (std::fabs(f[k][j]) > mf)
            throw RunFail{LEGSIM_ERR_BAD_INPUT, leg + "'s " + kWhich[j] + ": the statics' force with its offset, " +
                                                    num(f[k][j]) + " N, exceeds max_force " + num(mf) + " N"};
        }
        if (std::fabs(tau[k]) > h.rowing_max_torque_nm)
          throw RunFail{LEGSIM_ERR_BAD_INPUT, leg + "'s rowing: the statics' torque with its offset, " + num(tau[k]) +
                                                  " N m, exceeds max_torque " + num(h.rowing_max_torque_nm) + " N m"};
      }
      r = s.force_control ? legsim_hexapod_command(sim, f, tau)
                          : legsim_hexapod_command_pose(sim, p.length_m, p.rowing_rad, f, tau);
      if (r != LEGSIM_OK)
        throw RunFail{r, std::string("the commands (the statics' ") + (s.force_control ? "forces" : "feed-forward") +
                             " with the offsets; each within max_force / max_torque): " + status_text(r)};
    }
    legsim_hexapod_state x{};
    legsim_hexapod_get_state(sim, &x);
    // the margin's feet: the gait's stance (a foot bouncing inside a step is no less the
    // stance's), else the feet on the ground
    auto support = [&]() {
      if (s.has_gait) return plan_stance;
      uint32_t m = 0;
      for (int k = 0; k < L; ++k)
        if (x.foot_state[k] != LEGSIM_CONTACT_FREE) m |= 1u << k;
      return m;
    };
    double com[3], margin;
    com_margin(sim, h, x, s.has_gait ? s.stuck_mask : support(), com, margin);
    write_state_sample(o, x, h, 0, true, com, margin);
    int64_t events = 0;
    for (int64_t i = 1; i <= s.n_steps; ++i) {
      if (s.has_gait && i > 1) command_gait(static_cast<double>(i) * s.step_s);
      t_fail = static_cast<double>(i - 1) * s.step_s;
      r = legsim_hexapod_step(sim, s.step_s, 1);
      if (r != LEGSIM_OK) throw RunFail{r, "step from t = " + num(t_fail) + " s: " + status_text(r)};
      legsim_hexapod_get_state(sim, &x);
      events += x.events;
      if (i % s.record_every == 0 || i == s.n_steps) {
        com_margin(sim, h, x, support(), com, margin);
        write_state_sample(o, x, h, events, false, com, margin);
        events = 0;
      }
    }
  } catch (const RunFail &e) {
    return run_end(o, err, s.path, &e, t_fail);
  }
  return run_end(o, err, s.path, nullptr, 0);
}

}  // namespace

namespace {
// legsim_toml_is_hexapod_file of the scene's model: 1 a hexapod, 2 a block, 0 neither (or a
// scene that does not parse).
int scene_model_kind(const std::string &text, const std::string &path) {
  try {
    std::string why;
    if (!toml_input_within_limits(text, why)) return 0;
    toml::table doc = toml::parse(text, path);
    Node m = doc.get("model");
    if (!m || !m->is_string()) return 0;
    const std::string model(*m->value<std::string_view>());
    if (model.empty() || model.rfind("builtin:", 0) == 0) return 0;
    const std::string mp = model[0] == '/' ? model : dirname_of(path) + model;
    return legsim_toml_is_hexapod_file(mp.c_str());
  } catch (...) {
    return 0;
  }
}
}  // namespace

bool scene_is_hexapod(const std::string &text, const std::string &path) { return scene_model_kind(text, path) != 0; }

int run_hexapod_scene(const std::string &text, const std::string &path, bool check_only, HexapodOutput &out,
                      std::ostream &err) {
  if (scene_is_hexapod_inverse(text, path)) return run_hexapod_inverse_scene(text, path, check_only, out, err);
  if (scene_is_hexapod_sweep(text, path)) return run_hexapod_sweep_scene(text, path, check_only, out, err);
  if (scene_model_kind(text, path) == 2) return run_block_scene(text, path, check_only, out, err);
  HexScene s;
  auto h = std::make_unique<legsim_hexapod_desc>();
  legsim_hexapod_pose pose{};
  Storage st(legsim_hexapod_storage_size());
  try {
    s = parse(scene_document(text, path), path);
    if (!load_scene_model(s.model_path, path, *h, err)) return 2;
    ground_apply(s, *h);
    if (s.has_stance) s.stance_mask = bind_legs(s.stance, *h, "'stance'");
    if (s.has_stuck) s.stuck_mask = bind_legs(s.stuck, *h, "'stuck'");
    const size_t at = s.checks_json.find("@STUCK_AT_END@");
    if (at != std::string::npos)
      s.checks_json.replace(at, 14, legs_json(bind_legs(s.stuck_at_end, *h, "checks: 'stuck_at_end'"), *h));
    for (size_t i = 0; i < s.offsets.size(); ++i) {
      Offset &off = s.offsets[i];
      const uint32_t m = bind_legs({off.leg}, *h, "offset[" + std::to_string(i) + "]: 'leg'");
      off.leg.index = __builtin_ctz(m);
      for (size_t j = 0; j < i; ++j)
        if (s.offsets[j].leg.index == off.leg.index && s.offsets[j].which == off.which)
          fail("offset[" + std::to_string(i) + "]: " + name_of(h->leg[off.leg.index].name) + "'s " + kWhich[off.which] +
               " has an offset already");
    }
    if (s.has_gait) {
      // the gait's pose at t = 0: its set-points, the box level at its height over the ground
      // below the origin
      legsim_hexapod_setpoint sp{};
      const legsim_status g = legsim_hexapod_gait_setpoints(h.get(), &s.gait, 0.0, st.p, st.bytes, &sp);
      if (g != LEGSIM_OK) fail("gait: its set-points at t = 0: " + status_text(g));
      for (int i = 0; i < 3; ++i) pose.box_m[i] = sp.box_m[i];
      pose.box_quat[0] = 1;
      s.stuck_mask = 0;
      for (int k = 0; k < L; ++k) {
        pose.rowing_rad[k] = sp.rowing_rad[k];
        pose.length_m[k][0] = sp.length_m[k][0];
        pose.length_m[k][1] = sp.length_m[k][1];
        if (sp.stance[k]) s.stuck_mask |= 1u << k;
      }
    } else {
      pose = scene_pose(s, *h, st);
      if (s.analysis == HexAnalysis::kDynamics) {
        if (!s.has_stuck) s.stuck_mask = s.lift > 0 ? 0u : 0x3fu;
        pose.box_m[2] += s.lift;
      }
    }
  } catch (const Fail &f) {
    err << "legsim_cli: error: " << path << ": " << f.message << "\n";
    return 2;
  }
  std::ostream *o = out.open();
  if (!o) return 2;
  if (check_only) {
    write_head(*o, s, *h);
    write_settings(*o, s, *h, pose);
    *o << "}\n";
    return 0;
  }
  return s.analysis == HexAnalysis::kStatics ? run_statics(s, *h, pose, st, *o, err)
                                          : run_dynamics(s, *h, pose, st, *o, err);
}

}  // namespace legsim_host
