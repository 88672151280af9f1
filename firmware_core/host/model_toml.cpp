// The model file loader: models/leg.toml (or a robot file) -> legsim_model_desc.
//
// The one parser of model files: the run-time API below, and at build time the tool
// legsim_model (firmware_core/tools/legsim_model), which writes what it loads as C
// data, so that a model compiled in and the same model loaded at run time are equal
// bit for bit. Every check and message of the format is here.
//
// toml++ may throw (toml::parse_error); so does this file internally (Fail), which
// keeps each check one line. Everything is caught at the C boundary.
#include "model_toml.hpp"
#include "toml_limits.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <toml++/toml.h>

// The core's semantic checks (legsim_model_check) after the file's own. The build-time
// tool legsim_model compiles this file without them (0): it writes the core's generated
// sources, so it cannot link the core; the core checks a compiled-in model at legsim_init.
#ifndef LEGSIM_MODEL_TOML_CORE_CHECK
#define LEGSIM_MODEL_TOML_CORE_CHECK 1
#endif

namespace {

constexpr int kNameLen = LEGSIM_NAME_LEN;  // NUL included
constexpr const char *kDefaultVariant = LEGSIM_DEFAULT_VARIANT;

struct Fail {
  legsim_status status;
  std::string message;
};

[[noreturn]] void fail(const std::string &label, const std::string &problem,
                       legsim_status status = LEGSIM_ERR_MODEL) {
  throw Fail{status, label + ": " + problem};
}

std::string g(double x) {  // numbers in messages: C's %g
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

// A value refused at a bound: the shortest form that reads back as the same double, so that
// a value just past the bound is not shown as the bound itself.
std::string exact(double x) {
  char buf[64];
  for (int digits : {6, 15, 16, 17}) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, x);
    if (std::strtod(buf, nullptr) == x) break;
  }
  return buf;
}

std::string q(const std::string &s) { return "'" + s + "'"; }

using Node = const toml::node *;
using Table = const toml::table *;

bool is_table(Node v) { return v && v->is_table(); }
bool is_int(Node v) { return v && v->is_integer(); }
bool is_number(Node v) { return v && (v->is_integer() || v->is_floating_point()); }
bool is_string(Node v) { return v && v->is_string(); }

double to_double(Node v) {
  if (v->is_integer()) return static_cast<double>(*v->value<int64_t>());
  return v->as_floating_point()->get();
}

bool has(Table t, const std::string &key) { return t->get(key) != nullptr; }

// Keys in sorted order (bytewise).
std::vector<std::string> sorted_keys(Table t) {
  std::vector<std::string> keys;
  for (auto &&kv : *t) keys.emplace_back(kv.first.str());
  std::sort(keys.begin(), keys.end());
  return keys;
}

// Keys in file order: by where each key first appears.
std::vector<std::string> file_order_keys(Table t) {
  std::vector<std::tuple<uint32_t, uint32_t, std::string>> v;
  for (auto &&kv : *t) {
    const auto &b = kv.first.source().begin;
    v.emplace_back(b.line, b.column, std::string(kv.first.str()));
  }
  std::sort(v.begin(), v.end());
  std::vector<std::string> keys;
  for (auto &e : v) keys.push_back(std::get<2>(e));
  return keys;
}

std::string join(const std::vector<std::string> &v, const char *sep) {
  std::string s;
  for (size_t i = 0; i < v.size(); ++i) {
    if (i) s += sep;
    s += v[i];
  }
  return s;
}

void check_keys(Table t, std::vector<std::string> allowed, const std::string &label) {
  std::sort(allowed.begin(), allowed.end());
  for (const auto &key : sorted_keys(t))
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end())
      fail(label, "unknown key " + q(key) + " (allowed: " + join(allowed, ", ") + ")");
}

Node req(Table t, const std::string &key, const std::string &label) {
  Node v = t->get(key);
  if (!v) fail(label, "missing key " + q(key));
  return v;
}

std::string get_string(Table t, const std::string &key, const std::string &label) {
  Node v = req(t, key, label);
  if (!is_string(v)) fail(label, q(key) + " must be a string");
  return std::string(*v->value<std::string_view>());
}

bool name_char_ok(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' ||
         c == '-' || c == '.';
}

void check_name(const std::string &name, const std::string &label, const std::string &what = "name") {
  const size_t n = name.size();
  if (n < 1 || n > static_cast<size_t>(kNameLen - 1))
    fail(label, what + " must be 1 to " + std::to_string(kNameLen - 1) + " characters (got " +
                    std::to_string(n) + ")");
  for (char c : name)
    if (!name_char_ok(c))
      fail(label, what + " " + q(name) + " may hold only letters, digits, '_', '-' and '.'");
}

// A name not taken by an earlier item of its kind (the message names which one has it);
// name_of reads an item's name.
template <class Items, class NameOf>
void check_unique(const std::string &name, const Items &earlier, NameOf name_of, const char *kind,
                  const std::string &label) {
  for (size_t k = 0; k < earlier.size(); ++k)
    if (name_of(earlier[k]) == name)
      fail(label, "duplicate name " + q(name) + " (" + kind + " #" + std::to_string(k + 1) + " has it too)");
}
void check_unique(const std::string &name, const std::vector<std::string> &earlier, const char *kind,
                  const std::string &label) {
  check_unique(name, earlier, [](const std::string &n) -> const std::string & { return n; }, kind, label);
}

bool is_ident(const std::string &s) {
  if (s.empty()) return false;
  for (size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    const bool alpha = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_';
    const bool digit = c >= '0' && c <= '9';
    if (!(alpha || (i > 0 && digit))) return false;
  }
  return true;
}

double as_real(Node v, const std::string &key, const std::string &label) {
  if (!is_number(v)) fail(label, q(key) + " must be a number");
  const double x = to_double(v);
  if (!std::isfinite(x)) fail(label, q(key) + " is not finite");
  return x;
}

double get_real(Table t, const std::string &key, const std::string &label) {
  return as_real(req(t, key, label), key, label);
}

double get_positive(Table t, const std::string &key, const std::string &label) {
  const double x = get_real(t, key, label);
  if (!(x > 0.0)) fail(label, q(key) + " must be positive (got " + g(x) + ")");
  return x;
}

double get_nonnegative(Table t, const std::string &key, const std::string &label) {
  const double x = get_real(t, key, label);
  if (!(x >= 0.0)) fail(label, q(key) + " must be non-negative (got " + g(x) + ")");
  return x;
}

// The sane ranges of legsim.h (LEGSIM_MAX_* / LEGSIM_MIN_*).
double ranged(double x, double lo, double hi, const std::string &key, const std::string &label) {
  if (!(x >= lo && x <= hi))
    fail(label, q(key) + " must be in [" + g(lo) + ", " + g(hi) + "] (got " + g(x) + ")");
  return x;
}

std::vector<double> ranged_vec(std::vector<double> v, double lo, double hi, const std::string &key,
                               const std::string &label) {
  for (double x : v) ranged(x, lo, hi, key, label);
  return v;
}

std::vector<double> as_vec(Node v, size_t n, const std::string &key, const std::string &label) {
  const toml::array *a = v ? v->as_array() : nullptr;
  bool ok = a && a->size() == n;
  if (ok)
    for (auto &&e : *a) ok = ok && is_number(&e);
  if (!ok) fail(label, q(key) + " must be an array of " + std::to_string(n) + " numbers");
  std::vector<double> out;
  for (auto &&e : *a) out.push_back(to_double(&e));
  for (double x : out)
    if (!std::isfinite(x)) fail(label, q(key) + " is not finite");
  return out;
}

std::vector<double> get_vec(Table t, const std::string &key, size_t n, const std::string &label) {
  return as_vec(req(t, key, label), n, key, label);
}

int64_t get_int(Table t, const std::string &key, const std::string &label) {
  Node v = req(t, key, label);
  if (!is_int(v)) fail(label, q(key) + " must be an integer");
  return *v->value<int64_t>();
}

std::vector<Table> get_table_array(Table t, const std::string &key, const std::string &label) {
  std::vector<Table> out;
  Node v = t->get(key);
  if (!v) return out;
  const toml::array *a = v->as_array();
  bool ok = a != nullptr;
  if (ok)
    for (auto &&e : *a) ok = ok && e.is_table();
  if (!ok) fail(label, q(key) + " must be an array of tables ([[" + key + "]])");
  for (auto &&e : *a) out.push_back(e.as_table());
  return out;
}

void capacity(size_t count, const std::string &what, const std::string &macro, int cap,
              const std::string &label = "model") {
  if (count > static_cast<size_t>(cap))
    fail(label, std::to_string(count) + " " + what + " exceed the capacity " + macro + " = " +
                    std::to_string(cap),
         LEGSIM_ERR_CAPACITY);
}

void copy_name(char (&dst)[LEGSIM_NAME_LEN], const std::string &s) {
  std::memset(dst, 0, sizeof dst);
  std::memcpy(dst, s.data(), std::min(s.size(), sizeof dst - 1));
}

// ---- the model ----------------------------------------------------------------
struct Body {
  int64_t id;
  std::string name;
  double length, mass, inertia;
};

struct Ctx {
  std::vector<std::pair<std::string, std::vector<double>>> frame;
  std::vector<Body> bodies;  // by index (id - 1)

  int body_ref(Node v, const std::string &key, const std::string &label) const {
    if (!is_int(v)) fail(label, q(key) + " must be an integer body id");
    const int64_t id = *v->value<int64_t>();
    const int64_t n = static_cast<int64_t>(bodies.size());
    if (id < 1 || id > n)
      fail(label, "body " + std::to_string(id) + " does not exist (ids are 1.." + std::to_string(n) +
                      ")");
    return static_cast<int>(id - 1);
  }

  std::vector<double> end_point(int body, const std::string &end, Node at_value,
                                const std::string &label) const {
    const double half = bodies[body].length / 2.0;
    if (end == "proximal") return {-half, 0.0};
    if (end == "distal") return {half, 0.0};
    return ranged_vec(as_vec(at_value, 2, "at", label), -LEGSIM_MAX_COORD, LEGSIM_MAX_COORD, "at",
                      label);
  }

  std::vector<double> frame_point(Table t, const std::string &label) const {
    const std::string name = get_string(t, "point", label);
    for (const auto &p : frame)
      if (p.first == name) return p.second;
    fail(label, "frame point " + q(name) + " does not exist");
  }
};

const std::string &check_end(const std::string &end, const std::string &label) {
  if (end != "proximal" && end != "distal" && end != "at")
    fail(label, "bad end " + q(end) + " (expected proximal, distal or at)");
  return end;
}

std::pair<int, std::vector<double>> single_point(const Ctx &ctx, Table t, const std::string &label) {
  const int body = ctx.body_ref(req(t, "body", label), "body", label);
  const std::string end = check_end(get_string(t, "end", label), label);
  if (end == "at") return {body, ctx.end_point(body, end, req(t, "at", label), label)};
  if (has(t, "at")) fail(label, "'at' given but the end is not \"at\"");
  return {body, ctx.end_point(body, end, nullptr, label)};
}

std::vector<int> two_bodies(const Ctx &ctx, Table t, const std::string &label) {
  Node v = req(t, "bodies", label);
  const toml::array *a = v->as_array();
  bool ok = a && a->size() == 2;
  if (ok)
    for (auto &&e : *a) ok = ok && e.is_integer();
  if (!ok) fail(label, "'bodies' must be an array of 2 integer body ids");
  std::vector<int> b = {ctx.body_ref(a->get(0), "bodies", label),
                        ctx.body_ref(a->get(1), "bodies", label)};
  if (b[0] == b[1])
    fail(label, "bodies must differ (got " + std::to_string(*a->get(0)->value<int64_t>()) + " and " +
                    std::to_string(*a->get(1)->value<int64_t>()) + ")");
  return b;
}

std::vector<std::vector<double>> two_ends(const Ctx &ctx, Table t, const std::vector<int> &bodies,
                                          const std::string &label, bool slot) {
  Node v = req(t, "ends", label);
  const toml::array *a = v->as_array();
  bool ok = a && a->size() == 2;
  if (ok)
    for (auto &&e : *a) ok = ok && e.is_string();
  if (!ok) fail(label, "'ends' must be an array of 2 strings");
  const std::string v0(*a->get(0)->value<std::string_view>());
  const std::string v1(*a->get(1)->value<std::string_view>());
  std::vector<std::string> ends;
  ends.push_back(check_end(v0, label));
  if (slot) {
    if (v1 != "axis") fail(label, "bad end " + q(v1) + " for the slot line (expected axis)");
  } else {
    ends.push_back(check_end(v1, label));
  }
  const size_t n_at = static_cast<size_t>(std::count(ends.begin(), ends.end(), "at"));
  std::vector<Node> ats(ends.size(), nullptr);
  if (n_at == 0) {
    if (has(t, "at")) fail(label, "'at' given but no end is \"at\"");
  } else if (n_at == 1) {
    Node at = req(t, "at", label);
    for (size_t i = 0; i < ends.size(); ++i)
      if (ends[i] == "at") ats[i] = at;
  } else {
    Node at = req(t, "at", label);
    const toml::array *aa = at->as_array();
    if (!aa || aa->size() != 2)
      fail(label, "'at' must be an array of 2 [xi, eta] arrays (both ends are \"at\")");
    ats[0] = aa->get(0);
    ats[1] = aa->get(1);
  }
  std::vector<std::vector<double>> pts;
  for (size_t i = 0; i < ends.size(); ++i)
    pts.push_back(ctx.end_point(bodies[i], ends[i], ats[i], label));
  if (slot) pts.push_back({0.0, 0.0});
  return pts;
}

struct Joint {
  std::string name, kind;
  int body[2];
  double point[2][2];
};

void set_point(double (&dst)[2], const std::vector<double> &p) {
  dst[0] = p[0];
  dst[1] = p[1];
}

// override: a [variant.X] table, which names no joint (its key does).
Joint parse_joint(const Ctx &ctx, const std::string &name, Table t, const std::string &label,
                  bool override) {
  static const std::vector<std::string> kinds = {"revolute_to_frame", "revolute", "prismatic", "slot"};
  const std::string kind = get_string(t, "kind", label);
  if (std::find(kinds.begin(), kinds.end(), kind) == kinds.end())
    fail(label, "unknown kind " + q(kind) + " (expected revolute_to_frame, revolute, prismatic or slot)");
  std::vector<std::string> keys;
  if (kind == "revolute_to_frame")
    keys = {"name", "kind", "body", "end", "at", "point"};
  else if (kind == "prismatic")
    keys = {"name", "kind", "bodies"};
  else
    keys = {"name", "kind", "bodies", "ends", "at"};
  if (override) keys.erase(keys.begin());  // "name"
  check_keys(t, keys, label);
  Joint j{name, kind, {0, 0}, {{0.0, 0.0}, {0.0, 0.0}}};
  if (kind == "revolute_to_frame") {
    auto bp = single_point(ctx, t, label);
    j.body[0] = bp.first;
    j.body[1] = LEGSIM_FRAME;
    set_point(j.point[0], bp.second);
    set_point(j.point[1], ctx.frame_point(t, label));
  } else if (kind == "prismatic") {
    auto b = two_bodies(ctx, t, label);
    j.body[0] = b[0];
    j.body[1] = b[1];
  } else {
    auto b = two_bodies(ctx, t, label);
    j.body[0] = b[0];
    j.body[1] = b[1];
    auto pts = two_ends(ctx, t, b, label, kind == "slot");
    set_point(j.point[0], pts[0]);
    set_point(j.point[1], pts[1]);
  }
  return j;
}

legsim_force_desc parse_force(const Ctx &ctx, const std::string &name, Table t) {
  const std::string label = "force " + q(name);
  const std::string kind = get_string(t, "kind", label);
  if (kind != "point" && kind != "torque" && kind != "spring_damper")
    fail(label, "unknown kind " + q(kind) + " (expected point, torque or spring_damper)");
  legsim_force_desc f;
  std::memset(&f, 0, sizeof f);
  copy_name(f.name, name);
  f.body[0] = 0;
  f.body[1] = LEGSIM_FRAME;
  if (kind == "point") {
    f.kind = LEGSIM_FORCE_POINT;
    check_keys(t, {"name", "kind", "body", "end", "at", "value"}, label);
    auto bp = single_point(ctx, t, label);
    f.body[0] = bp.first;
    set_point(f.point[0], bp.second);
    if (has(t, "value"))
      set_point(f.value, ranged_vec(get_vec(t, "value", 2, label), -LEGSIM_MAX_FORCE_N,
                                    LEGSIM_MAX_FORCE_N, "value", label));
  } else if (kind == "torque") {
    f.kind = LEGSIM_FORCE_TORQUE;
    check_keys(t, {"name", "kind", "body", "value"}, label);
    f.body[0] = ctx.body_ref(req(t, "body", label), "body", label);
    if (has(t, "value")) {
      f.value[0] = ranged(get_real(t, "value", label), -LEGSIM_MAX_FORCE_N, LEGSIM_MAX_FORCE_N,
                          "value", label);
      f.value[1] = 0.0;
    }
  } else {
    f.kind = LEGSIM_FORCE_SPRING_DAMPER;
    std::vector<std::string> common = {"name", "kind", "at", "stiffness", "damping", "rest_length"};
    if (has(t, "bodies")) {
      auto keys = common;
      keys.insert(keys.end(), {"bodies", "ends"});
      check_keys(t, keys, label);
      auto b = two_bodies(ctx, t, label);
      f.body[0] = b[0];
      f.body[1] = b[1];
      auto pts = two_ends(ctx, t, b, label, false);
      set_point(f.point[0], pts[0]);
      set_point(f.point[1], pts[1]);
    } else {
      auto keys = common;
      keys.insert(keys.end(), {"body", "end", "point"});
      check_keys(t, keys, label);
      auto bp = single_point(ctx, t, label);
      f.body[0] = bp.first;
      set_point(f.point[0], bp.second);
      f.body[1] = LEGSIM_FRAME;
      set_point(f.point[1], ctx.frame_point(t, label));
    }
    f.stiffness_n_per_m = ranged(get_nonnegative(t, "stiffness", label), 0.0,
                                 LEGSIM_MAX_STIFFNESS_N_PER_M, "stiffness", label);
    f.damping_ns_per_m = ranged(get_nonnegative(t, "damping", label), 0.0,
                                LEGSIM_MAX_DAMPING_NS_PER_M, "damping", label);
    f.rest_length_m = ranged(get_nonnegative(t, "rest_length", label), 0.0, LEGSIM_MAX_COORD,
                             "rest_length", label);
  }
  return f;
}

// [variant.X] tables in file order, checked: X = { JOINT = {...}, ... }.
std::vector<std::pair<std::string, Table>> variant_tables(Table doc,
                                                          const std::vector<std::string> &joint_names) {
  std::vector<std::pair<std::string, Table>> out;
  Node vt = doc->get("variant");
  if (!vt) return out;
  if (!is_table(vt)) fail("model", "'variant' must be a table of [variant.NAME] tables");
  Table vtab = vt->as_table();
  for (const auto &vname : file_order_keys(vtab)) {
    const std::string label = "variant " + q(vname);
    if (!is_ident(vname) || vname.size() > static_cast<size_t>(kNameLen - 1))
      fail(label, "the name must be a C identifier of at most " + std::to_string(kNameLen - 1) +
                      " characters");
    if (vname == kDefaultVariant) fail(label, "the default variant cannot be overridden");
    Node v = vtab->get(vname);
    if (!is_table(v)) fail(label, "must be a table of JOINT = { ... } overrides");
    Table vtb = v->as_table();
    for (const auto &jname : sorted_keys(vtb)) {
      if (std::find(joint_names.begin(), joint_names.end(), jname) == joint_names.end())
        fail(label, "no joint named " + q(jname));
      if (!is_table(vtb->get(jname)))
        fail(label, q(jname) + " must be a table (the joint's keys without its name)");
    }
    out.emplace_back(vname, vtb);
  }
  return out;
}

bool parse_driver_key(const std::string &key, int *coord, int64_t *id) {
  size_t p;
  if (key.compare(0, 3, "phi") == 0) {
    *coord = 2;
    p = 3;
  } else if (!key.empty() && key[0] == 'x') {
    *coord = 0;
    p = 1;
  } else if (!key.empty() && key[0] == 'y') {
    *coord = 1;
    p = 1;
  } else {
    return false;
  }
  const size_t nd = key.size() - p;
  if (nd < 1 || nd > 9 || key[p] < '1' || key[p] > '9') return false;
  int64_t v = 0;
  for (size_t i = p; i < key.size(); ++i) {
    if (key[i] < '0' || key[i] > '9') return false;
    v = v * 10 + (key[i] - '0');
  }
  *id = v;
  return true;
}

void parse_model(Table doc, const std::string &variant, legsim_model_desc &m) {
  static const std::vector<std::string> top_keys = {"name",     "gravity", "frame", "body",
                                                    "joint",    "variant", "actuator", "force",
                                                    "foot",     "pose"};
  check_keys(doc, top_keys, "model");
  const std::string name = get_string(doc, "name", "model");
  check_name(name, "model");
  std::vector<double> gravity =
      has(doc, "gravity") ? get_vec(doc, "gravity", 2, "model") : std::vector<double>{0.0, -9.81};
  ranged_vec(gravity, -LEGSIM_MAX_GRAVITY_MPS2, LEGSIM_MAX_GRAVITY_MPS2, "gravity", "model");

  Ctx ctx;
  if (Node ft = doc->get("frame")) {
    if (!is_table(ft)) fail("model", "'frame' must be a table of NAME = [x, y] points");
    Table ftab = ft->as_table();
    for (const auto &key : sorted_keys(ftab))
      ctx.frame.emplace_back(key, ranged_vec(as_vec(ftab->get(key), 2, key, "frame point " + q(key)),
                                             -LEGSIM_MAX_COORD, LEGSIM_MAX_COORD, key,
                                             "frame point " + q(key)));
  }

  // bodies
  auto body_tables = get_table_array(doc, "body", "model");
  if (body_tables.empty()) fail("model", "no [[body]]");
  const size_t n = body_tables.size();
  capacity(n, "bodies", "LEGSIM_MAX_BODIES", LEGSIM_MAX_BODIES);
  std::vector<Body> parsed;
  for (size_t k = 1; k <= n; ++k) {
    Table tb = body_tables[k - 1];
    std::string label = "body #" + std::to_string(k);
    const std::string bname = get_string(tb, "name", label);
    check_name(bname, label);
    check_unique(bname, parsed, [](const Body &b) -> const std::string & { return b.name; }, "body", label);
    label = "body " + q(bname);
    check_keys(tb, {"id", "name", "length", "mass", "inertia"}, label);
    Body b;
    b.name = bname;
    b.id = get_int(tb, "id", label);
    b.length = ranged(get_positive(tb, "length", label), LEGSIM_MIN_LENGTH_M, LEGSIM_MAX_COORD,
                      "length", label);
    b.mass = ranged(get_positive(tb, "mass", label), LEGSIM_MIN_MASS_KG, LEGSIM_MAX_MASS_KG, "mass",
                    label);
    b.inertia = has(tb, "inertia") ? get_positive(tb, "inertia", label)
                                   : b.mass * b.length * b.length / 12.0;
    ranged(b.inertia, LEGSIM_MIN_INERTIA_KGM2, LEGSIM_MAX_INERTIA_KGM2, "inertia", label);
    parsed.push_back(b);
  }
  std::vector<const Body *> by_id(n + 1, nullptr);
  for (const auto &b : parsed) {
    const std::string label = "body " + q(b.name);
    if (b.id < 1 || b.id > static_cast<int64_t>(n))
      fail(label, "id " + std::to_string(b.id) + " out of range (ids must be 1.." + std::to_string(n) +
                      ")");
    if (by_id[b.id])
      fail(label, "duplicate id " + std::to_string(b.id) + " (body " + q(by_id[b.id]->name) +
                      " has it too)");
    by_id[b.id] = &b;
  }
  for (size_t i = 1; i <= n; ++i) ctx.bodies.push_back(*by_id[i]);

  // joints: names first (variants refer to them)
  auto joint_tables = get_table_array(doc, "joint", "model");
  capacity(joint_tables.size(), "joints", "LEGSIM_MAX_JOINTS", LEGSIM_MAX_JOINTS);
  std::vector<std::string> joint_names;
  for (size_t k = 1; k <= joint_tables.size(); ++k) {
    const std::string label = "joint #" + std::to_string(k);
    const std::string jname = get_string(joint_tables[k - 1], "name", label);
    check_name(jname, label);
    check_unique(jname, joint_names, "joint", label);
    joint_names.push_back(jname);
  }

  auto variants = variant_tables(doc, joint_names);
  std::vector<std::string> names = {kDefaultVariant};
  for (const auto &v : variants) names.push_back(v.first);
  if (std::find(names.begin(), names.end(), variant) == names.end())
    fail("model", "unknown variant " + q(variant) + " (available: " + join(names, ", ") + ")",
         LEGSIM_ERR_BAD_INPUT);
  Table overrides = nullptr;
  for (const auto &v : variants)
    if (v.first == variant) overrides = v.second;

  std::vector<Joint> joints;
  for (size_t k = 0; k < joint_tables.size(); ++k) {
    const std::string &jname = joint_names[k];
    Node ov = overrides ? overrides->get(jname) : nullptr;
    if (ov)
      joints.push_back(parse_joint(ctx, jname, ov->as_table(),
                                   "joint " + q(jname) + " (variant " + q(variant) + ")", true));
    else
      joints.push_back(parse_joint(ctx, jname, joint_tables[k], "joint " + q(jname), false));
  }

  // actuators
  auto act_tables = get_table_array(doc, "actuator", "model");
  capacity(act_tables.size(), "actuators", "LEGSIM_MAX_ACTUATORS", LEGSIM_MAX_ACTUATORS);
  std::vector<legsim_actuator_desc> actuators;
  std::vector<std::string> act_names;
  for (size_t k = 1; k <= act_tables.size(); ++k) {
    Table ta = act_tables[k - 1];
    std::string label = "actuator #" + std::to_string(k);
    const std::string aname = get_string(ta, "name", label);
    check_name(aname, label);
    check_unique(aname, act_names, "actuator", label);
    label = "actuator " + q(aname);
    check_keys(ta, {"name", "joint", "stroke", "max_force", "servo_kp", "servo_kd"}, label);
    const std::string jname = get_string(ta, "joint", label);
    auto it = std::find(joint_names.begin(), joint_names.end(), jname);
    if (it == joint_names.end()) fail(label, "joint " + q(jname) + " does not exist");
    const int ji = static_cast<int>(it - joint_names.begin());
    if (joints[ji].kind != "prismatic")
      fail(label, "joint " + q(jname) + " is " + joints[ji].kind + ", not prismatic");
    for (size_t k2 = 0; k2 < actuators.size(); ++k2)
      if (actuators[k2].joint == ji)
        fail(label, "joint " + q(jname) + " is already driven by actuator " + q(act_names[k2]));
    const auto stroke = get_vec(ta, "stroke", 2, label);
    if (!(stroke[0] > 0.0)) fail(label, "stroke min must be positive (got " + g(stroke[0]) + ")");
    if (stroke[0] >= stroke[1])
      fail(label, "stroke min " + g(stroke[0]) + " >= max " + g(stroke[1]));
    ranged_vec(stroke, LEGSIM_MIN_LENGTH_M, LEGSIM_MAX_COORD, "stroke", label);
    legsim_actuator_desc a;
    std::memset(&a, 0, sizeof a);
    copy_name(a.name, aname);
    a.joint = ji;
    a.stroke_min_m = stroke[0];
    a.stroke_max_m = stroke[1];
    a.max_force_n = ranged(get_positive(ta, "max_force", label), LEGSIM_MIN_FORCE_N,
                           LEGSIM_MAX_FORCE_N, "max_force", label);
    a.servo_kp_n_per_m = ranged(get_nonnegative(ta, "servo_kp", label), 0.0,
                                LEGSIM_MAX_STIFFNESS_N_PER_M, "servo_kp", label);
    a.servo_kd_ns_per_m = ranged(get_nonnegative(ta, "servo_kd", label), 0.0,
                                 LEGSIM_MAX_DAMPING_NS_PER_M, "servo_kd", label);
    actuators.push_back(a);
    act_names.push_back(aname);
  }

  // force elements
  auto force_tables = get_table_array(doc, "force", "model");
  capacity(force_tables.size(), "force elements", "LEGSIM_MAX_FORCES", LEGSIM_MAX_FORCES);
  std::vector<legsim_force_desc> forces;
  std::vector<std::string> force_names;
  for (size_t k = 1; k <= force_tables.size(); ++k) {
    Table tf = force_tables[k - 1];
    const std::string label = "force #" + std::to_string(k);
    const std::string fname = get_string(tf, "name", label);
    check_name(fname, label);
    check_unique(fname, force_names, "force", label);
    forces.push_back(parse_force(ctx, fname, tf));
    force_names.push_back(fname);
  }

  // foot
  int foot_body = LEGSIM_FRAME;
  std::vector<double> foot_point = {0.0, 0.0};
  if (Node tf = doc->get("foot")) {
    if (!is_table(tf)) fail("model", "'foot' must be a table");
    check_keys(tf->as_table(), {"body", "end", "at"}, "foot");
    auto bp = single_point(ctx, tf->as_table(), "foot");
    foot_body = bp.first;
    foot_point = bp.second;
  }

  // poses
  struct Driver {
    int body, coord;
    double value;
  };
  struct Pose {
    std::string name;
    std::vector<Driver> drivers;
    std::vector<std::vector<double>> guess;
  };
  std::vector<Pose> poses;
  if (Node tp = doc->get("pose")) {
    if (!is_table(tp)) fail("model", "'pose' must be a table of [pose.NAME] tables");
    Table ptab = tp->as_table();
    capacity(ptab->size(), "poses", "LEGSIM_MAX_POSES", LEGSIM_MAX_POSES);
    for (const auto &pname : file_order_keys(ptab)) {
      const std::string label = "pose " + q(pname);
      check_name(pname, label);
      Node pn = ptab->get(pname);
      if (!is_table(pn)) fail(label, "must be a table");
      Table pt = pn->as_table();
      Pose pose;
      pose.name = pname;
      for (const auto &key : sorted_keys(pt)) {
        if (key == "guess") continue;
        int coord = 0;
        int64_t bid = 0;
        if (!parse_driver_key(key, &coord, &bid))
          fail(label, "unknown key " + q(key) + " (expected guess, phiN, xN or yN with N a body id)");
        if (bid > static_cast<int64_t>(n))
          fail(label, q(key) + ": body " + std::to_string(bid) + " does not exist (ids are 1.." +
                          std::to_string(n) + ")");
        const double value =
            ranged(as_real(pt->get(key), key, label), -LEGSIM_MAX_COORD, LEGSIM_MAX_COORD, key, label);
        pose.drivers.push_back({static_cast<int>(bid - 1), coord, value});
      }
      capacity(pose.drivers.size(), "drivers", "LEGSIM_MAX_POSE_DRIVERS", LEGSIM_MAX_POSE_DRIVERS,
               label);
      std::stable_sort(pose.drivers.begin(), pose.drivers.end(), [](const Driver &a, const Driver &b) {
        return a.body != b.body ? a.body < b.body : a.coord < b.coord;
      });
      Node gv = req(pt, "guess", label);
      const toml::array *ga = gv->as_array();
      bool ok = ga && ga->size() == n;
      if (ok)
        for (auto &&row : *ga) {
          const toml::array *r = row.as_array();
          ok = ok && r && r->size() == 3;
          if (ok)
            for (auto &&e : *r) ok = ok && is_number(&e);
        }
      if (!ok)
        fail(label, "'guess' must be an array of " + std::to_string(n) +
                        " [x, y, phi] arrays (one per body)");
      for (auto &&row : *ga) {
        std::vector<double> r;
        for (auto &&e : *row.as_array()) r.push_back(to_double(&e));
        pose.guess.push_back(r);
      }
      for (const auto &r : pose.guess)
        for (double x : r)
          if (!std::isfinite(x)) fail(label, "'guess' is not finite");
      for (const auto &r : pose.guess) ranged_vec(r, -LEGSIM_MAX_COORD, LEGSIM_MAX_COORD, "guess", label);
      poses.push_back(pose);
    }
  }

  // ---- fill the description ----
  std::memset(&m, 0, sizeof m);
  copy_name(m.name, name);
  m.gravity_mps2[0] = gravity[0];
  m.gravity_mps2[1] = gravity[1];
  m.n_bodies = static_cast<int32_t>(n);
  m.n_joints = static_cast<int32_t>(joints.size());
  m.n_actuators = static_cast<int32_t>(actuators.size());
  m.n_forces = static_cast<int32_t>(forces.size());
  m.n_poses = static_cast<int32_t>(poses.size());
  for (size_t i = 0; i < n; ++i) {
    copy_name(m.body[i].name, ctx.bodies[i].name);
    m.body[i].length_m = ctx.bodies[i].length;
    m.body[i].mass_kg = ctx.bodies[i].mass;
    m.body[i].inertia_kgm2 = ctx.bodies[i].inertia;
  }
  for (size_t i = 0; i < joints.size(); ++i) {
    const Joint &j = joints[i];
    legsim_joint_desc &d = m.joint[i];
    copy_name(d.name, j.name);
    d.kind = j.kind == "revolute_to_frame" ? LEGSIM_JOINT_REVOLUTE_TO_FRAME
             : j.kind == "revolute"        ? LEGSIM_JOINT_REVOLUTE
             : j.kind == "prismatic"       ? LEGSIM_JOINT_PRISMATIC
                                           : LEGSIM_JOINT_SLOT;
    for (int s = 0; s < 2; ++s) {
      d.body[s] = j.body[s];
      d.point[s][0] = j.point[s][0];
      d.point[s][1] = j.point[s][1];
    }
  }
  for (size_t i = 0; i < actuators.size(); ++i) m.actuator[i] = actuators[i];
  for (size_t i = 0; i < forces.size(); ++i) m.force[i] = forces[i];
  for (size_t i = 0; i < poses.size(); ++i) {
    legsim_pose_desc &p = m.pose[i];
    copy_name(p.name, poses[i].name);
    p.n_drivers = static_cast<int32_t>(poses[i].drivers.size());
    for (size_t d = 0; d < poses[i].drivers.size(); ++d) {
      p.driver[d].body = poses[i].drivers[d].body;
      p.driver[d].coord = poses[i].drivers[d].coord;
      p.driver[d].value = poses[i].drivers[d].value;
    }
    for (size_t b = 0; b < n; ++b)
      for (int c = 0; c < 3; ++c) p.guess[b][c] = poses[i].guess[b][c];
  }
  m.foot_body = foot_body;
  m.foot_point[0] = foot_point[0];
  m.foot_point[1] = foot_point[1];
}

void put_msg(char *msg, size_t msg_len, const std::string &s) {
  if (!msg || msg_len == 0) return;
  const size_t k = std::min(s.size(), msg_len - 1);
  std::memcpy(msg, s.data(), k);
  msg[k] = '\0';
}

// Parses TOML; throws Fail on a syntax error (the library may throw or not), and
// on input outside the limits the parser is known to fail on (toml_limits.hpp).
toml::table parse_toml(const std::string &text, const std::string &source) {
  std::string why;
  if (!toml_input_within_limits(text, why))
    throw Fail{LEGSIM_ERR_MODEL, source + ": TOML input refused: " + why};
#if TOML_EXCEPTIONS
  try {
    return toml::parse(std::string_view(text), std::string_view(source));
  } catch (const toml::parse_error &e) {
    const auto &b = e.source().begin;
    throw Fail{LEGSIM_ERR_MODEL, source + ": TOML syntax error: " + std::string(e.description()) +
                                     " (at line " + std::to_string(b.line) + ", column " +
                                     std::to_string(b.column) + ")"};
  }
#else
  toml::parse_result r = toml::parse(std::string_view(text), std::string_view(source));
  if (!r) {
    const auto &b = r.error().source().begin;
    throw Fail{LEGSIM_ERR_MODEL, source + ": TOML syntax error: " +
                                     std::string(r.error().description()) + " (at line " +
                                     std::to_string(b.line) + ", column " + std::to_string(b.column) +
                                     ")"};
  }
  return std::move(r.table());
#endif
}

// ---- a robot file: a box with leg files placed on it (docs/design/robot-on-ground.md) ----
constexpr double kMaxFriction = LEGSIM_MAX_FRICTION;
constexpr double kMaxSlope = LEGSIM_MAX_SLOPE_RAD;  // rad, legsim.h
constexpr double kCongruentTol = 1e-12;   // m: attach points against the leg's frame

bool is_robot(Table doc) { return has(doc, "box") && has(doc, "leg"); }

// A leg file's path: relative to the robot file's folder unless absolute.
std::string path_join(const std::string &base, const std::string &file) {
  if (base.empty() || (!file.empty() && file[0] == '/')) return file;
  return base.back() == '/' ? base + file : base + "/" + file;
}

std::string dir_name(const std::string &path) {  // the folder part ("" for none)
  const size_t k = path.rfind('/');
  if (k == std::string::npos) return "";
  std::string d = path.substr(0, k + 1);
  while (d.size() > 1 && d.back() == '/') d.pop_back();
  return d;
}

toml::table read_leg_toml(const std::string &path, const std::string &label, const std::string &shown) {
  std::string text, err;
  if (!read_toml_file(path.c_str(), text, err)) {
    const size_t k = err.find(": cannot read: ");
    fail(label, "file " + q(shown) + err.substr(k), LEGSIM_ERR_BAD_INPUT);
  }
  try {
    return parse_toml(text, shown);
  } catch (Fail &f) {
    // parse_toml's message starts with the source name: "SHOWN: TOML ..."
    fail(label, "file " + q(shown) + f.message.substr(shown.size()));
  }
}

struct Leg {
  std::string name, prefix;
  double sign;
  double off[2];
  legsim_model_desc model;
  int body0;
};

void box_xy_to_body(const double xy[2], double (&out)[2]) {
  out[0] = -xy[1];
  out[1] = xy[0];
}

std::vector<std::vector<double>> robot_guess(const std::vector<Leg> &legs, const double gpoint[2],
                                             double slope, const std::string &legs_pose, double mid,
                                             const std::string &label) {
  std::vector<std::vector<double>> rows = {{0.0, 0.0, 0.0}};
  std::vector<std::vector<double>> feet;
  for (const Leg &leg : legs) {
    const legsim_model_desc &lm = leg.model;
    const double sign = leg.sign;
    int pi = -1;
    for (int p = 0; p < lm.n_poses; ++p)
      if (legs_pose == lm.pose[p].name) pi = p;
    if (pi < 0) fail(label, "leg " + q(leg.name) + " has no pose " + q(legs_pose));
    for (int b = 0; b < lm.n_bodies; ++b) {
      const double *r = lm.pose[pi].guess[b];
      rows.push_back({leg.off[0] + sign * r[0], leg.off[1] + r[1], sign * r[2]});
    }
    const std::vector<double> &fb = rows[static_cast<size_t>(leg.body0 + lm.foot_body)];
    const double bx = fb[0], by = fb[1], bphi = fb[2];
    const double xi = lm.foot_point[0], eta = sign * lm.foot_point[1];
    feet.push_back({bx + xi * std::sin(bphi) + eta * std::cos(bphi),
                    by - xi * std::cos(bphi) + eta * std::sin(bphi)});
  }
  // the outer feet (the first and the last leg's) on the line, their midpoint at `mid`, as
  // legsim_assemble_on_ground puts them; the feet between follow where the legs agree
  double theta, m0, m1;
  if (feet.size() > 1) {
    const std::vector<double> &f0 = feet.front(), &f1 = feet.back();
    theta = std::atan2(f0[1] - f1[1], f0[0] - f1[0]);
    m0 = 0.5 * (f0[0] + f1[0]);
    m1 = 0.5 * (f0[1] + f1[1]);
  } else {
    theta = 0.0;
    m0 = feet[0][0];
    m1 = feet[0][1];
  }
  const double psi = slope - theta;
  const double c = std::cos(psi), s = std::sin(psi);
  const double ct = std::cos(slope), st = std::sin(slope);
  const double r0 = gpoint[0] + mid * ct - (c * m0 - s * m1);
  const double r1 = gpoint[1] + mid * st - (s * m0 + c * m1);
  std::vector<std::vector<double>> out;
  for (const auto &row : rows) {
    const double x = row[0], y = row[1], phi = row[2];
    const double v[3] = {r0 + c * x - s * y, r1 + s * x + c * y, phi + psi};
    for (double e : v)
      if (!(std::abs(e) <= LEGSIM_MAX_COORD))
        fail(label, "'guess' must be in [" + g(-LEGSIM_MAX_COORD) + ", " + g(LEGSIM_MAX_COORD) + "]");
    out.push_back({v[0], v[1], v[2]});
  }
  return out;
}

void parse_robot(Table doc, const std::string &base_dir, const std::string &variant,
                 legsim_model_desc &m) {
  check_keys(doc, {"name", "gravity", "box", "leg", "ground", "pose"}, "robot");
  const std::string name = get_string(doc, "name", "robot");
  check_name(name, "robot");
  std::vector<double> gravity =
      has(doc, "gravity") ? get_vec(doc, "gravity", 2, "robot") : std::vector<double>{0.0, -9.81};
  ranged_vec(gravity, -LEGSIM_MAX_GRAVITY_MPS2, LEGSIM_MAX_GRAVITY_MPS2, "gravity", "robot");
  if (variant != kDefaultVariant)
    fail("robot", "unknown variant " + q(variant) + " (available: " + kDefaultVariant + ")",
         LEGSIM_ERR_BAD_INPUT);

  Node bn = doc->get("box");
  if (!is_table(bn)) fail("robot", "'box' must be a table");
  Table bt = bn->as_table();
  check_keys(bt, {"name", "mass", "inertia", "size"}, "box");
  const std::string bname = has(bt, "name") ? get_string(bt, "name", "box") : "box";
  check_name(bname, "box");
  const auto size = ranged_vec(get_vec(bt, "size", 2, "box"), LEGSIM_MIN_LENGTH_M, LEGSIM_MAX_COORD,
                               "size", "box");
  std::vector<legsim_body_desc> bodies(1);
  std::memset(&bodies[0], 0, sizeof bodies[0]);
  copy_name(bodies[0].name, bname);
  bodies[0].length_m = size[0];
  bodies[0].mass_kg =
      ranged(get_positive(bt, "mass", "box"), LEGSIM_MIN_MASS_KG, LEGSIM_MAX_MASS_KG, "mass", "box");
  bodies[0].inertia_kgm2 = ranged(get_positive(bt, "inertia", "box"), LEGSIM_MIN_INERTIA_KGM2,
                                  LEGSIM_MAX_INERTIA_KGM2, "inertia", "box");
  std::vector<legsim_joint_desc> joints;
  std::vector<legsim_actuator_desc> actuators;
  std::vector<legsim_force_desc> forces;
  std::vector<legsim_contact_desc> contacts;
  std::vector<Leg> legs;

  auto leg_tables = get_table_array(doc, "leg", "robot");
  if (leg_tables.empty()) fail("robot", "no [[leg]]");
  for (size_t k = 1; k <= leg_tables.size(); ++k) {
    Table tl = leg_tables[k - 1];
    std::string label = "leg #" + std::to_string(k);
    const std::string lname = get_string(tl, "name", label);
    check_name(lname, label);
    check_unique(lname, legs, [](const auto &l) -> const std::string & { return l.name; }, "leg", label);
    label = "leg " + q(lname);
    check_keys(tl, {"name", "file", "variant", "prefix", "mirror", "attach"}, label);
    const std::string lfile = get_string(tl, "file", label);
    const std::string lvariant = has(tl, "variant") ? get_string(tl, "variant", label) : kDefaultVariant;
    const std::string prefix = has(tl, "prefix") ? get_string(tl, "prefix", label) : lname + ".";
    for (const Leg &other : legs)
      if (other.prefix == prefix) fail(label, "prefix " + q(prefix) + " is taken by leg " + q(other.name));
    bool mirror = false;
    if (Node mv = tl->get("mirror")) {
      if (!mv->is_boolean()) fail(label, "'mirror' must be true or false");
      mirror = *mv->value<bool>();
    }
    Node an = req(tl, "attach", label);
    if (!is_table(an)) fail(label, "'attach' must be a table of POINT = [x, y]");
    Table attach = an->as_table();
    toml::table ldoc = read_leg_toml(path_join(base_dir, lfile), label, lfile);
    if (is_robot(&ldoc)) fail(label, "file " + q(lfile) + " is a robot file, not a leg");
    Leg leg;
    leg.name = lname;
    leg.prefix = prefix;
    try {
      parse_model(&ldoc, lvariant, leg.model);
    } catch (Fail &f) {
      f.message = label + ": " + lfile + ": " + f.message;
      throw;
    }
    const legsim_model_desc &lm = leg.model;
    // one gravity for the whole robot: a leg file that states another is refused, not ignored
    if (lm.gravity_mps2[0] != gravity[0] || lm.gravity_mps2[1] != gravity[1])
      fail(label, "the gravity of " + q(lfile) + ", [" + g(lm.gravity_mps2[0]) + ", " +
                      g(lm.gravity_mps2[1]) + "] m/s^2, differs from the robot's [" + g(gravity[0]) +
                      ", " + g(gravity[1]) + "] m/s^2 (they must be equal)");
    Table frame = ldoc.get("frame") ? ldoc.get("frame")->as_table() : nullptr;
    std::vector<std::string> fnames = frame ? sorted_keys(frame) : std::vector<std::string>{};
    if (fnames.empty()) fail(label, "the leg file has no [frame] points to attach");
    if (sorted_keys(attach) != fnames)
      fail(label, "'attach' must name the leg file's frame points (" + join(fnames, ", ") + ")");
    const double sign = mirror ? -1.0 : 1.0;
    std::vector<std::vector<double>> offs;
    for (const auto &key : fnames) {
      const auto a = ranged_vec(as_vec(attach->get(key), 2, key, label), -LEGSIM_MAX_COORD,
                                LEGSIM_MAX_COORD, key, label);
      const auto fp = as_vec(frame->get(key), 2, key, label);
      offs.push_back({a[0] - sign * fp[0], a[1] - fp[1]});
    }
    for (const auto &o : offs)
      if (std::abs(o[0] - offs[0][0]) > kCongruentTol || std::abs(o[1] - offs[0][1]) > kCongruentTol)
        fail(label, "the box points are not congruent with the leg's frame");
    leg.off[0] = offs[0][0];
    leg.off[1] = offs[0][1];
    if (lm.foot_body == LEGSIM_FRAME) fail(label, "the leg file has no [foot]");
    const int b0 = static_cast<int>(bodies.size()), j0 = static_cast<int>(joints.size());
    leg.body0 = b0;
    leg.sign = sign;
    auto mir = [&](const double p[2], double (&out)[2]) {
      out[0] = p[0];
      out[1] = sign * p[1];
    };
    auto on_box = [&](const double p[2], double (&out)[2]) {
      const double xy[2] = {leg.off[0] + sign * p[0], leg.off[1] + p[1]};
      box_xy_to_body(xy, out);
    };
    auto named = [&](const std::string &what, const char *n, char (&dst)[LEGSIM_NAME_LEN]) {
      const std::string full = prefix + n;
      check_name(full, label, what);
      copy_name(dst, full);
    };
    for (int b = 0; b < lm.n_bodies; ++b) {
      legsim_body_desc bd = lm.body[b];
      named("body name", lm.body[b].name, bd.name);
      bodies.push_back(bd);
    }
    for (int j = 0; j < lm.n_joints; ++j) {
      const legsim_joint_desc &lj = lm.joint[j];
      legsim_joint_desc nj = lj;
      named("joint name", lj.name, nj.name);
      nj.body[0] = lj.body[0] + b0;
      nj.body[1] = lj.body[1] + b0;
      mir(lj.point[0], nj.point[0]);
      mir(lj.point[1], nj.point[1]);
      if (lj.kind == LEGSIM_JOINT_REVOLUTE_TO_FRAME) {
        nj.kind = LEGSIM_JOINT_REVOLUTE;
        nj.body[1] = 0;
        on_box(lj.point[1], nj.point[1]);
      }
      joints.push_back(nj);
    }
    for (int a = 0; a < lm.n_actuators; ++a) {
      legsim_actuator_desc na = lm.actuator[a];
      named("actuator name", lm.actuator[a].name, na.name);
      na.joint = lm.actuator[a].joint + j0;
      actuators.push_back(na);
    }
    for (int fi = 0; fi < lm.n_forces; ++fi) {
      const legsim_force_desc &f = lm.force[fi];
      legsim_force_desc nf = f;
      named("force name", f.name, nf.name);
      mir(f.point[0], nf.point[0]);
      mir(f.point[1], nf.point[1]);
      for (int s = 0; s < 2; ++s) {
        if (f.body[s] == LEGSIM_FRAME) {
          if (f.kind == LEGSIM_FORCE_SPRING_DAMPER) {
            nf.body[s] = 0;
            on_box(f.point[s], nf.point[s]);
          }
        } else {
          nf.body[s] = f.body[s] + b0;
        }
      }
      if (f.kind == LEGSIM_FORCE_POINT) {
        nf.value[0] = sign * f.value[0];
        nf.value[1] = f.value[1];
      } else if (f.kind == LEGSIM_FORCE_TORQUE) {
        nf.value[0] = sign * f.value[0];
        nf.value[1] = 0.0;
      }
      forces.push_back(nf);
    }
    legsim_contact_desc c;
    std::memset(&c, 0, sizeof c);
    named("contact name", "foot", c.name);
    c.body = lm.foot_body + b0;
    mir(lm.foot_point, c.point);
    contacts.push_back(c);
    legs.push_back(leg);
  }

  Node gn = req(doc, "ground", "robot");
  if (!is_table(gn)) fail("robot", "'ground' must be a table");
  Table gt = gn->as_table();
  check_keys(gt, {"point", "slope", "mu_static", "mu_kinetic"}, "ground");
  const std::vector<double> gpoint =
      has(gt, "point") ? ranged_vec(get_vec(gt, "point", 2, "ground"), -LEGSIM_MAX_COORD,
                                    LEGSIM_MAX_COORD, "point", "ground")
                       : std::vector<double>{0.0, 0.0};
  const double slope = has(gt, "slope") ? get_real(gt, "slope", "ground") : 0.0;
  if (!(std::abs(slope) <= kMaxSlope))
    fail("ground", "'slope' must be in [" + g(-kMaxSlope) + ", " + g(kMaxSlope) +
                       "] rad (got " + exact(slope) + ")");
  const double mu_s =
      ranged(get_nonnegative(gt, "mu_static", "ground"), 0.0, kMaxFriction, "mu_static", "ground");
  const double mu_k =
      ranged(get_nonnegative(gt, "mu_kinetic", "ground"), 0.0, kMaxFriction, "mu_kinetic", "ground");
  if (mu_k > mu_s) fail("ground", "mu_kinetic " + g(mu_k) + " > mu_static " + g(mu_s));

  struct Pose {
    std::string name;
    std::vector<std::vector<double>> guess;
  };
  std::vector<Pose> poses;
  if (Node tp = doc->get("pose")) {
    if (!is_table(tp)) fail("robot", "'pose' must be a table of [pose.NAME] tables");
    Table ptab = tp->as_table();
    capacity(ptab->size(), "poses", "LEGSIM_MAX_POSES", LEGSIM_MAX_POSES, "robot");
    for (const auto &pname : file_order_keys(ptab)) {
      const std::string label = "pose " + q(pname);
      check_name(pname, label);
      Node pn = ptab->get(pname);
      if (!is_table(pn)) fail(label, "must be a table");
      Table pt = pn->as_table();
      check_keys(pt, {"legs", "feet_mid", "contact"}, label);
      const std::string legs_pose = has(pt, "legs") ? get_string(pt, "legs", label) : "stand";
      const double mid = has(pt, "feet_mid") ? ranged(get_real(pt, "feet_mid", label), -LEGSIM_MAX_COORD,
                                                      LEGSIM_MAX_COORD, "feet_mid", label)
                                             : 0.0;
      const std::string state = has(pt, "contact") ? get_string(pt, "contact", label) : "stuck";
      if (state != "stuck") fail(label, "'contact' must be \"stuck\" (got " + q(state) + ")");
      const double gp[2] = {gpoint[0], gpoint[1]};
      poses.push_back({pname, robot_guess(legs, gp, slope, legs_pose, mid, label)});
    }
  }

  // the capacities last: every other check of the file comes first, in any build
  capacity(bodies.size(), "bodies", "LEGSIM_MAX_BODIES", LEGSIM_MAX_BODIES, "robot");
  capacity(joints.size(), "joints", "LEGSIM_MAX_JOINTS", LEGSIM_MAX_JOINTS, "robot");
  capacity(actuators.size(), "actuators", "LEGSIM_MAX_ACTUATORS", LEGSIM_MAX_ACTUATORS, "robot");
  capacity(forces.size(), "force elements", "LEGSIM_MAX_FORCES", LEGSIM_MAX_FORCES, "robot");
  capacity(contacts.size(), "contacts", "LEGSIM_MAX_CONTACTS", LEGSIM_MAX_CONTACTS, "robot");
  // ---- fill the description ----
  std::memset(&m, 0, sizeof m);
  copy_name(m.name, name);
  m.gravity_mps2[0] = gravity[0];
  m.gravity_mps2[1] = gravity[1];
  m.n_bodies = static_cast<int32_t>(bodies.size());
  m.n_joints = static_cast<int32_t>(joints.size());
  m.n_actuators = static_cast<int32_t>(actuators.size());
  m.n_forces = static_cast<int32_t>(forces.size());
  m.n_poses = static_cast<int32_t>(poses.size());
  m.n_contacts = static_cast<int32_t>(contacts.size());
  for (size_t i = 0; i < bodies.size(); ++i) m.body[i] = bodies[i];
  for (size_t i = 0; i < joints.size(); ++i) m.joint[i] = joints[i];
  for (size_t i = 0; i < actuators.size(); ++i) m.actuator[i] = actuators[i];
  for (size_t i = 0; i < forces.size(); ++i) m.force[i] = forces[i];
  for (size_t i = 0; i < contacts.size(); ++i) m.contact[i] = contacts[i];
  for (size_t i = 0; i < poses.size(); ++i) {
    copy_name(m.pose[i].name, poses[i].name);
    for (size_t b = 0; b < bodies.size(); ++b)
      for (int c = 0; c < 3; ++c) m.pose[i].guess[b][c] = poses[i].guess[b][c];
  }
  m.foot_body = LEGSIM_FRAME;
  m.ground.point[0] = gpoint[0];
  m.ground.point[1] = gpoint[1];
  m.ground.slope_rad = slope;
  m.ground.mu_static = mu_s;
  m.ground.mu_kinetic = mu_k;
}

// ---- a hexapod file: six leg files on hip yokes on a free box (legsim/hexapod.h) ----
bool is_hexapod(Table doc) { return has(doc, "yoke") || has(doc, "rowing") || has(doc, "box_contact"); }

// A table key of doc, required, as a table.
Table req_table(Table doc, const std::string &key, const std::string &label) {
  Node n = req(doc, key, label);
  if (!is_table(n)) fail(label, q(key) + " must be a table");
  return n->as_table();
}
void copy3(double (&dst)[3], const std::vector<double> &v) {
  for (int i = 0; i < 3; ++i) dst[i] = v[i];
}
std::vector<double> ranged3(Table t, const std::string &key, double lo, double hi, const std::string &label) {
  return ranged_vec(get_vec(t, key, 3, label), lo, hi, key, label);
}

void parse_hexapod(Table doc, const std::string &base_dir, legsim_hexapod_desc &h) {
  const std::string label0 = "hexapod";
  check_keys(doc, {"name", "gravity", "box", "yoke", "rowing", "leg", "ground", "box_contact"}, label0);
  const std::string name = get_string(doc, "name", label0);
  check_name(name, label0);
  const std::vector<double> gravity = ranged_vec(get_vec(doc, "gravity", 3, label0), -LEGSIM_MAX_GRAVITY_MPS2,
                                                 LEGSIM_MAX_GRAVITY_MPS2, "gravity", label0);
  if (gravity[0] != 0 || gravity[1] != 0)
    fail(label0, "'gravity' must be vertical, [0, 0, g_z] (the world's z is up; got [" + g(gravity[0]) + ", " +
                     g(gravity[1]) + ", " + g(gravity[2]) + "])");
  std::memset(&h, 0, sizeof h);
  copy_name(h.name, name);
  copy3(h.gravity_mps2, gravity);

  Table bt = req_table(doc, "box", label0);
  check_keys(bt, {"mass", "size", "inertia"}, "box");
  h.box_mass_kg = ranged(get_positive(bt, "mass", "box"), LEGSIM_MIN_MASS_KG, LEGSIM_MAX_MASS_KG, "mass", "box");
  copy3(h.box_size_m, ranged3(bt, "size", LEGSIM_MIN_LENGTH_M, LEGSIM_MAX_COORD, "box"));
  copy3(h.box_inertia_kgm2, ranged3(bt, "inertia", LEGSIM_MIN_INERTIA_KGM2, LEGSIM_MAX_INERTIA_KGM2, "box"));

  // no [[leg]]: the box alone on its own contact points (a block), without yokes or motors
  const bool block = !has(doc, "leg");
  if (block) {
    for (const char *k : {"yoke", "rowing"})
      if (has(doc, k))
        fail(label0, "[" + std::string(k) + "] needs the [[leg]]s (a file of none is a block on its [[box_contact]]s)");
    if (!has(doc, "box_contact")) fail(label0, "needs 6 [[leg]], or none and a [[box_contact]] (a block)");
  } else {
    Table yt = req_table(doc, "yoke", label0);
    check_keys(yt, {"mass", "com", "inertia", "hip_offset", "bar_radius"}, "yoke");
    h.yoke_mass_kg = ranged(get_positive(yt, "mass", "yoke"), LEGSIM_MIN_MASS_KG, LEGSIM_MAX_MASS_KG, "mass", "yoke");
    copy3(h.yoke_com_m, ranged3(yt, "com", -LEGSIM_MAX_COORD, LEGSIM_MAX_COORD, "yoke"));
    copy3(h.yoke_inertia_kgm2, ranged3(yt, "inertia", LEGSIM_MIN_INERTIA_KGM2, LEGSIM_MAX_INERTIA_KGM2, "yoke"));
    h.hip_offset_m = ranged(get_positive(yt, "hip_offset", "yoke"), LEGSIM_MIN_LENGTH_M, LEGSIM_MAX_COORD,
                            "hip_offset", "yoke");
    h.bar_radius_m = ranged(get_positive(yt, "bar_radius", "yoke"), LEGSIM_MIN_LENGTH_M, LEGSIM_MAX_COORD,
                            "bar_radius", "yoke");

    Table rt = req_table(doc, "rowing", label0);
    check_keys(rt, {"gear_ratio", "max_torque", "stroke", "servo_kp", "servo_kd"}, "rowing");
    h.rowing_gear_ratio = ranged(get_positive(rt, "gear_ratio", "rowing"), 1.0, 1e4, "gear_ratio", "rowing");
    h.rowing_max_torque_nm = ranged(get_positive(rt, "max_torque", "rowing"), LEGSIM_MIN_FORCE_N,
                                    LEGSIM_MAX_FORCE_N, "max_torque", "rowing");
    const std::vector<double> stroke = get_vec(rt, "stroke", 2, "rowing");
    if (!(stroke[0] > -M_PI && stroke[0] < 0 && stroke[1] > 0 && stroke[1] < M_PI))
      fail("rowing", "'stroke' must be [min, max] with -pi < min < 0 < max < pi rad (got [" + exact(stroke[0]) + ", " +
                         exact(stroke[1]) + "])");
    h.rowing_stroke_rad[0] = stroke[0];
    h.rowing_stroke_rad[1] = stroke[1];
    h.rowing_servo_kp_nm_per_rad =
        ranged(get_nonnegative(rt, "servo_kp", "rowing"), 0.0, LEGSIM_MAX_STIFFNESS_N_PER_M, "servo_kp", "rowing");
    h.rowing_servo_kd_nms_per_rad =
        ranged(get_nonnegative(rt, "servo_kd", "rowing"), 0.0, LEGSIM_MAX_DAMPING_NS_PER_M, "servo_kd", "rowing");

    auto leg_tables = get_table_array(doc, "leg", label0);
    if (leg_tables.size() != LEGSIM_HEXAPOD_LEGS)
      fail(label0, "needs " + std::to_string(LEGSIM_HEXAPOD_LEGS) + " [[leg]] (got " +
                       std::to_string(leg_tables.size()) + ")");
    std::vector<std::string> names;
    for (size_t k = 0; k < leg_tables.size(); ++k) {
      Table tl = leg_tables[k];
      std::string label = "leg #" + std::to_string(k + 1);
      const std::string lname = get_string(tl, "name", label);
      check_name(lname, label);
      check_unique(lname, names, "leg", label);
      names.push_back(lname);
      label = "leg " + q(lname);
      check_keys(tl, {"name", "file", "variant", "hip", "heading"}, label);
      const std::string lfile = get_string(tl, "file", label);
      const std::string lvariant = has(tl, "variant") ? get_string(tl, "variant", label) : kDefaultVariant;
      legsim_hexapod_leg_desc &L = h.leg[k];
      copy_name(L.name, lname);
      copy3(L.hip_m, ranged_vec(get_vec(tl, "hip", 3, label), -LEGSIM_MAX_COORD, LEGSIM_MAX_COORD, "hip", label));
      L.heading_rad = ranged(get_real(tl, "heading", label), -M_PI, M_PI, "heading", label);
      toml::table ldoc = read_leg_toml(path_join(base_dir, lfile), label, lfile);
      if (is_robot(&ldoc) || is_hexapod(&ldoc)) fail(label, "file " + q(lfile) + " is not a leg file");
      try {
        parse_model(&ldoc, lvariant, L.leg);
      } catch (Fail &f) {
        f.message = label + ": " + lfile + ": " + f.message;
        throw;
      }
  #if LEGSIM_MODEL_TOML_CORE_CHECK
      char core_msg[256] = {0};
      if (legsim_model_check(&L.leg, core_msg, sizeof core_msg) != LEGSIM_OK)
        fail(label, lfile + ": " + core_msg);
  #endif
      // one gravity: a leg file that states another is refused, not ignored
      if (L.leg.gravity_mps2[0] != 0 || L.leg.gravity_mps2[1] != gravity[2])
        fail(label, "the gravity of " + q(lfile) + ", [" + g(L.leg.gravity_mps2[0]) + ", " +
                        g(L.leg.gravity_mps2[1]) + "], is not the hexapod's [0, " + g(gravity[2]) +
                        "] in its plane");
      if (L.leg.foot_body < 0) fail(label, "file " + q(lfile) + " has no [foot]: a hexapod's feet are its legs'");
      if (L.leg.n_bodies > LEGSIM_HEXAPOD_MAX_LEG_BARS)
        fail(label, "file " + q(lfile) + " has " + std::to_string(L.leg.n_bodies) + " bodies (a hexapod's leg at most " +
                        std::to_string(LEGSIM_HEXAPOD_MAX_LEG_BARS) + ")",
             LEGSIM_ERR_CAPACITY);
      for (int j = 0; j < L.leg.n_joints; ++j)
        if (L.leg.joint[j].kind == LEGSIM_JOINT_SLOT)
          fail(label, "joint " + q(L.leg.joint[j].name) + " of " + q(lfile) + " is a slot (no spatial rows for it)");
    }
    h.n_legs = LEGSIM_HEXAPOD_LEGS;
  }

  Table gt = req_table(doc, "ground", label0);
  check_keys(gt, {"point", "normal", "mu_static", "mu_kinetic"}, "ground");
  copy3(h.ground_point_m, ranged_vec(get_vec(gt, "point", 3, "ground"), -LEGSIM_MAX_COORD, LEGSIM_MAX_COORD,
                                     "point", "ground"));
  const std::vector<double> nrm = get_vec(gt, "normal", 3, "ground");
  const double len = std::sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
  if (!(std::abs(len - 1) <= 1e-9))
    fail("ground", "'normal' must be a unit vector (its length is " + exact(len) + ")");
  if (!(std::acos(std::min(1.0, nrm[2] / len)) <= kMaxSlope))
    fail("ground", "'normal' must be within " + g(kMaxSlope) + " rad of the vertical");
  copy3(h.ground_normal, nrm);
  h.mu_static = ranged(get_nonnegative(gt, "mu_static", "ground"), 0.0, kMaxFriction, "mu_static", "ground");
  h.mu_kinetic = ranged(get_nonnegative(gt, "mu_kinetic", "ground"), 0.0, kMaxFriction, "mu_kinetic", "ground");
  if (h.mu_kinetic > h.mu_static)
    fail("ground", "mu_kinetic " + g(h.mu_kinetic) + " > mu_static " + g(h.mu_static));

  // the box's own contact points: on or inside the box (its skids are on its hull)
  auto contact_tables = get_table_array(doc, "box_contact", label0);
  if (contact_tables.size() > LEGSIM_HEXAPOD_MAX_BOX_CONTACTS)
    fail(label0, std::to_string(contact_tables.size()) + " [[box_contact]] (at most " +
                     std::to_string(LEGSIM_HEXAPOD_MAX_BOX_CONTACTS) + ", LEGSIM_HEXAPOD_MAX_BOX_CONTACTS)",
         LEGSIM_ERR_CAPACITY);
  for (size_t k = 0; k < contact_tables.size(); ++k) {
    Table tc = contact_tables[k];
    const std::string label = "box_contact #" + std::to_string(k + 1);
    check_keys(tc, {"point"}, label);
    const std::vector<double> p = get_vec(tc, "point", 3, label);
    for (int i = 0; i < 3; ++i)
      if (!(std::abs(p[i]) <= 0.5 * h.box_size_m[i]))
        fail(label, "'point' must be on or inside the box, |x_i| <= size_i / 2 (got [" + exact(p[0]) + ", " +
                        exact(p[1]) + ", " + exact(p[2]) + "])");
    copy3(h.box_contact_m[k], p);
  }
  h.n_box_contacts = int32_t(contact_tables.size());
}

legsim_status parse_text(const std::string &text, const std::string &source, const char *variant,
                         legsim_model_desc *out, char *msg, size_t msg_len) {
  const std::string v = (variant && *variant) ? variant : kDefaultVariant;
  try {
    toml::table doc = parse_toml(text, source);
    legsim_model_desc m;
    try {
      if (is_hexapod(&doc))
        fail("file", "a hexapod file: load it with legsim_hexapod_load_toml", LEGSIM_ERR_BAD_INPUT);
      if (is_robot(&doc))
        parse_robot(&doc, dir_name(source), v, m);
      else
        parse_model(&doc, v, m);
    } catch (Fail &f) {
      f.message = source + ": " + f.message;
      throw;
    }
#if LEGSIM_MODEL_TOML_CORE_CHECK
    char core_msg[256] = {0};
    const legsim_status st = legsim_model_check(&m, core_msg, sizeof core_msg);
    if (st != LEGSIM_OK) {
      put_msg(msg, msg_len, source + ": " + core_msg);
      return st;
    }
#endif
    *out = m;
    put_msg(msg, msg_len, "");
    return LEGSIM_OK;
  } catch (const Fail &f) {
    put_msg(msg, msg_len, f.message);
    return f.status;
  } catch (const std::bad_alloc &) {
    put_msg(msg, msg_len, source + ": out of memory");
    return LEGSIM_ERR_MODEL;
  } catch (const std::exception &e) {
    put_msg(msg, msg_len, source + ": " + e.what());
    return LEGSIM_ERR_MODEL;
  } catch (...) {
    put_msg(msg, msg_len, source + ": unexpected error");
    return LEGSIM_ERR_MODEL;
  }
}

}  // namespace

extern "C" legsim_status legsim_model_parse_toml(const char *text, size_t text_len,
                                                 const char *source_name, const char *variant,
                                                 legsim_model_desc *out, char *msg, size_t msg_len) {
  if (!text || !out) {
    put_msg(msg, msg_len, "legsim_model_parse_toml: text or out is NULL");
    return LEGSIM_ERR_NULL;
  }
  try {
    return parse_text(std::string(text, text_len), source_name ? source_name : "<memory>", variant,
                      out, msg, msg_len);
  } catch (...) {
    put_msg(msg, msg_len, "out of memory");
    return LEGSIM_ERR_MODEL;
  }
}

extern "C" legsim_status legsim_model_load_toml(const char *path, const char *variant,
                                                legsim_model_desc *out, char *msg, size_t msg_len) {
  if (!path || !out) {
    put_msg(msg, msg_len, "legsim_model_load_toml: path or out is NULL");
    return LEGSIM_ERR_NULL;
  }
  try {
    std::string text, err;
    if (!read_toml_file(path, text, err)) {
      put_msg(msg, msg_len, err);
      return LEGSIM_ERR_BAD_INPUT;
    }
    return parse_text(text, path, variant, out, msg, msg_len);
  } catch (...) {
    put_msg(msg, msg_len, std::string(path) + ": out of memory");
    return LEGSIM_ERR_MODEL;
  }
}

namespace {
// A file's TOML read and given to use(doc) (which writes the results): the file's refusals,
// Fail's message and status, or any other exception as "unexpected error", into msg.
template <typename Use>
legsim_status with_toml_file(const char *path, char *msg, size_t msg_len, Use &&use) {
  try {
    std::string text, err;
    if (!read_toml_file(path, text, err)) {
      put_msg(msg, msg_len, err);
      return LEGSIM_ERR_BAD_INPUT;
    }
    toml::table doc = parse_toml(text, path);
    use(doc);
    put_msg(msg, msg_len, "");
    return LEGSIM_OK;
  } catch (const Fail &f) {
    put_msg(msg, msg_len, f.message);
    return f.status;
  } catch (...) {
    put_msg(msg, msg_len, std::string(path) + ": unexpected error");
    return LEGSIM_ERR_MODEL;
  }
}
}  // namespace

extern "C" legsim_status legsim_model_toml_variants(const char *path, char (*names)[LEGSIM_NAME_LEN],
                                                    int32_t max_names, int32_t *n_names, char *msg,
                                                    size_t msg_len) {
  if (!path || !n_names || (max_names > 0 && !names)) {
    put_msg(msg, msg_len, "legsim_model_toml_variants: a required pointer is NULL");
    return LEGSIM_ERR_NULL;
  }
  return with_toml_file(path, msg, msg_len, [&](toml::table &doc) {
    std::vector<std::string> list = {kDefaultVariant};
    if (const toml::table *vt = doc["variant"].as_table())
      for (const auto &k : file_order_keys(vt)) list.push_back(k);
    for (int32_t i = 0; i < max_names && i < static_cast<int32_t>(list.size()); ++i) {
      std::memset(names[i], 0, LEGSIM_NAME_LEN);
      std::memcpy(names[i], list[i].data(), std::min(list[i].size(), size_t(LEGSIM_NAME_LEN - 1)));
    }
    *n_names = static_cast<int32_t>(list.size());
  });
}

extern "C" int legsim_toml_is_hexapod_file(const char *path) {
  if (!path) return 0;
  int kind = 0;
  with_toml_file(path, nullptr, 0, [&](toml::table &doc) { kind = !is_hexapod(&doc) ? 0 : has(&doc, "leg") ? 1 : 2; });
  return kind;
}

extern "C" legsim_status legsim_hexapod_load_toml(const char *path, legsim_hexapod_desc *out, char *msg,
                                                  size_t msg_len) {
  if (!path || !out) {
    put_msg(msg, msg_len, "legsim_hexapod_load_toml: path or out is NULL");
    return LEGSIM_ERR_NULL;
  }
  const std::string source = path;
  return with_toml_file(path, msg, msg_len, [&](toml::table &doc) {
    auto h = std::make_unique<legsim_hexapod_desc>();
    try {
      if (!is_hexapod(&doc))
        fail("file", "not a hexapod file (no [yoke], [rowing] or [[box_contact]])", LEGSIM_ERR_BAD_INPUT);
      parse_hexapod(&doc, dir_name(source), *h);
    } catch (Fail &f) {
      f.message = source + ": " + f.message;
      throw;
    }
    *out = *h;
  });
}
