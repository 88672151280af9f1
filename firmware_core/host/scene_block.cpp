// Block scenes: parsing, placing and running a block (a hexapod file of no legs) and its JSON.
// The keys, units, defaults and ranges: scenes/README.md, "A block". Host only; the hexapod's C
// API only (legsim/hexapod.h).
#include "scene_block.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>

#include <toml++/toml.h>

#include "legsim/hexapod.h"
#include "legsim/legsim.h"
#include "scene_hexapod_common.hpp"

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
using Fail = scene_read::SceneError;

constexpr double kMaxLiftM = 1.0;
constexpr int C = LEGSIM_HEXAPOD_MAX_BOX_CONTACTS;
constexpr const char *kPointState[3] = {"free", "stuck", "sliding"};  // legsim_contact_state
// A contact point this close to the lowest one (along the ground's normal) starts on the ground.
constexpr double kOnGroundM = 1e-12;

struct BlockScene : RunKeys, GroundKeys {
  std::string path, name, description, model, model_path;
  double lift = 0, velocity[3] = {0, 0, 0}, omega[3] = {0, 0, 0};
  std::string checks_json = "null";
};

// [x, y, z], each within +-bound
void vec3(Node v, const std::string &what, double bound, double (&out)[3]) {
  const toml::array *a = v ? v->as_array() : nullptr;
  if (!a || a->size() != 3) fail(what + " must be [x, y, z]");
  for (int i = 0; i < 3; ++i) out[i] = ranged(a->get(i), what + "[" + std::to_string(i) + "]", -bound, bound);
}

std::string checks_of(Node v) {
  return checks_json(v, {"box_x_m", "box_y_m", "box_z_m", "rest_s"}, {"slip_mu_off", "friction_work_off"},
                     {"impacts_min"}, [](const std::string &, Node) { return std::string(); });
}

BlockScene parse(const toml::table &doc, const std::string &path) {
  BlockScene s;
  s.path = path;
  Table t = &doc;
  check_keys(t,
             {"description", "name", "model", "analysis", "step_s", "integrator", "duration", "record_every", "lift",
              "velocity", "omega", "ground", "checks"},
             "a block's scene: ");
  const SceneHead head = scene_head(t, path);
  s.model = head.model, s.model_path = head.model_path, s.name = head.name, s.description = head.description;
  if (t->get("analysis") && string_of(t->get("analysis"), "'analysis'") != "dynamics")
    fail("'analysis' of a block must be dynamics (a block has no legs to stand on)");
  static_cast<GroundKeys &>(s) = ground_keys(t->get("ground"));
  if (Node v = t->get("checks")) s.checks_json = checks_of(v);
  static_cast<RunKeys &>(s) = run_keys(t);
  if (Node v = t->get("lift")) s.lift = ranged(v, "'lift'", 0, kMaxLiftM);
  // the C API's launch's range (legsim_hexapod_set_velocity)
  if (Node v = t->get("velocity")) vec3(v, "'velocity'", LEGSIM_MAX_RATE_MPS, s.velocity);
  if (Node v = t->get("omega")) vec3(v, "'omega'", LEGSIM_MAX_RATE_MPS, s.omega);
  return s;
}

// The block set on the ground: turned so that its frame's z is the ground's normal (the least
// rotation from the world's z), its lowest contact points on the plane below the origin, then
// lifted along the normal. Its points on the plane (lift 0) start stuck: bit n_legs + k.
legsim_hexapod_pose place(const BlockScene &s, const legsim_hexapod_desc &h, uint32_t &stuck) {
  const double *n = h.ground_normal, *g = h.ground_point_m;
  double qw = 1 + n[2], qx = -n[1], qy = n[0];
  const double r = std::sqrt(qw * qw + qx * qx + qy * qy);
  legsim_hexapod_pose p{};
  p.box_quat[0] = qw / r, p.box_quat[1] = qx / r, p.box_quat[2] = qy / r;
  // the rotation maps the frame's z onto n: a point's height over the plane is its frame z plus
  // the centre's
  double low = h.box_contact_m[0][2];
  for (int k = 1; k < h.n_box_contacts; ++k) low = std::min(low, h.box_contact_m[k][2]);
  stuck = 0;
  if (s.lift == 0)
    for (int k = 0; k < h.n_box_contacts; ++k)
      if (h.box_contact_m[k][2] - low <= kOnGroundM) stuck |= 1u << (LEGSIM_HEXAPOD_LEGS + k);
  const double z0 = g[2] - (n[0] * (0 - g[0]) + n[1] * (0 - g[1])) / n[2];
  const double up = s.lift - low;
  p.box_m[0] = up * n[0], p.box_m[1] = up * n[1], p.box_m[2] = z0 + up * n[2];
  return p;
}

void write_head(std::ostream &o, const BlockScene &s, const legsim_hexapod_desc &h, const legsim_hexapod_pose &p) {
  o << "{\"scene\": " << jstr(s.path) << ", \"name\": " << jstr(s.name) << ", \"kind\": \"block\""
    << ", \"description\": " << jstr(s.description) << ", \"demo\": false, \"model\": " << jstr(s.model)
    << ", \"model_path\": " << jstr(s.model_path) << ", \"model_name\": " << jstr(name_of(h.name))
    << ", \"analysis\": \"dynamics\",\n  \"ground\": {\"point\": " << jarr(h.ground_point_m)
    << ", \"normal\": " << jarr(h.ground_normal) << ", \"mu_static\": " << jnum(h.mu_static)
    << ", \"mu_kinetic\": " << jnum(h.mu_kinetic) << "}, \"gravity\": " << jarr(h.gravity_mps2)
    << ", \"mass\": " << jnum(h.box_mass_kg) << ", \"box_contacts\": [";
  for (int k = 0; k < h.n_box_contacts; ++k) o << (k ? ", " : "") << jarr(h.box_contact_m[k]);
  o << "],\n  \"checks\": " << s.checks_json << ",\n  \"pose\": {\"box\": " << jarr(p.box_m)
    << ", \"box_quat\": " << jarr(p.box_quat) << "}, \"integrator\": \""
    << (s.integrator == LEGSIM_INTEGRATOR_GENERALIZED_ALPHA ? "generalized_alpha" : "rk4") << "\", \"step_s\": "
    << jnum(s.step_s) << ", \"step_ns\": " << s.step_ns << ", \"duration\": " << jnum(s.duration)
    << ", \"n_steps\": " << s.n_steps << ", \"record_every\": " << s.record_every << ", \"lift\": " << jnum(s.lift)
    << ", \"velocity\": " << jarr(s.velocity) << ", \"omega\": " << jarr(s.omega);
}

void write_sample(std::ostream &o, const legsim_hexapod_state &x, int64_t events, bool first) {
  o << (first ? "\n    " : ",\n    ") << "{\"t\": " << jnum(x.t_s) << ", \"box\": " << jarr(x.box_m)
    << ", \"box_quat\": " << jarr(x.box_quat) << ", \"box_velocity\": " << jarr(x.box_velocity_mps)
    << ", \"box_omega\": " << jarr(x.box_omega_radps) << ", \"contacts\": [";
  for (int k = 0; k < x.n_box_contacts && k < C; ++k) {
    const int st = x.box_contact_state[k];
    o << (k ? ", " : "") << "{\"state\": " << jstr(st >= 0 && st < 3 ? kPointState[st] : "unknown")
      << ", \"x\": " << jarr(x.box_contact_m[k]) << ", \"force\": " << jarr(x.box_contact_force_n[k]) << "}";
  }
  o << "], \"kinetic_energy\": " << jnum(x.kinetic_energy_j) << ", \"events\": " << events
    << ", \"impacts\": " << x.impacts << "}";
}

int run(const BlockScene &s, const legsim_hexapod_desc &h, const legsim_hexapod_pose &p, uint32_t stuck,
        std::ostream &o, std::ostream &err) {
  Storage sim_st(legsim_hexapod_sim_size());
  legsim_hexapod_sim *sim = nullptr;
  write_head(o, s, h, p);
  o << ",\n  \"samples\": [";
  double t_fail = 0;
  try {
    legsim_status r = legsim_hexapod_sim_init(sim_st.p, sim_st.bytes, &h, &p, stuck, &sim);
    if (r != LEGSIM_OK) throw RunFail{r, "the start (legsim_hexapod_sim_init): " + status_text(r)};
    r = legsim_hexapod_set_integrator(sim, s.integrator);
    if (r != LEGSIM_OK) throw RunFail{r, "the integrator (legsim_hexapod_set_integrator): " + status_text(r)};
    r = legsim_hexapod_set_velocity(sim, s.velocity, s.omega);
    if (r != LEGSIM_OK) throw RunFail{r, "the launch (legsim_hexapod_set_velocity): " + status_text(r)};
    legsim_hexapod_state x{};
    legsim_hexapod_get_state(sim, &x);
    write_sample(o, x, 0, true);
    int64_t events = 0;
    for (int64_t i = 1; i <= s.n_steps; ++i) {
      t_fail = static_cast<double>(i - 1) * s.step_s;
      r = legsim_hexapod_step(sim, s.step_s, 1);
      if (r != LEGSIM_OK) throw RunFail{r, "step from t = " + num(t_fail) + " s: " + status_text(r)};
      legsim_hexapod_get_state(sim, &x);
      events += x.events;
      if (i % s.record_every == 0 || i == s.n_steps) {
        write_sample(o, x, events, false);
        events = 0;
      }
    }
  } catch (const RunFail &e) {
    return run_end(o, err, s.path, &e, t_fail);
  }
  return run_end(o, err, s.path, nullptr, 0);
}

}  // namespace

int run_block_scene(const std::string &text, const std::string &path, bool check_only, HexapodOutput &out,
                    std::ostream &err) {
  BlockScene s;
  auto h = std::make_unique<legsim_hexapod_desc>();
  legsim_hexapod_pose pose{};
  uint32_t stuck = 0;
  try {
    s = parse(scene_document(text, path), path);
    if (!load_scene_model(s.model_path, path, *h, err)) return 2;
    if (h->n_legs != 0) fail("the model " + q(s.model) + " has legs: a hexapod's scene (scenes/README.md)");
    ground_apply(s, *h);
    pose = place(s, *h, stuck);
  } catch (const Fail &f) {
    err << "legsim_cli: error: " << path << ": " << f.message << "\n";
    return 2;
  }
  std::ostream *o = out.open();
  if (!o) return 2;
  if (check_only) {
    write_head(*o, s, *h, pose);
    *o << "}\n";
    return 0;
  }
  return run(s, *h, pose, stuck, *o, err);
}

}  // namespace legsim_host
