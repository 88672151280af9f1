// legsim_model: what the build needs from a model file, read by the one loader
// (host/model_toml.cpp).
//
//   legsim_model MODEL.toml --check
//   legsim_model MODEL.toml --emit-c --symbol leg --out-c legsim_models.c --out-h legsim/models.h
//   legsim_model MODEL.toml --emit-structure [--out leg.json]
//
// --emit-c writes, for the default variant "revolute" and every [variant.X] of the file,
// `const legsim_model_desc legsim_model_<symbol>_<variant>`, the table
// `legsim_model_<symbol>_variants[]` and its count. Every number is written as the
// shortest decimal that reads back as the same double, so a model compiled in equals
// the same file loaded at run time bit for bit. The build's capacities are checked by
// the generated source itself (#if / #error against legsim/config.h).
//
// --emit-structure writes JSON of the variants' structure, which the kernel generator
// (tools/kernel_codegen.py) reads:
//   {"file": "leg.toml", "variants": [{"name": "revolute", "model": {
//      "bodies": [{"name": ...}], "joints": [{"name", "kind", "body": [a, b]}],
//      "actuators": [{"name", "joint"}], "contacts": [{"name", "body"}]}}, ...]}
// with 0-based indices, -1 for the frame and kinds "revolute_to_frame", "revolute",
// "prismatic" or "slot".
//
// An invalid model: exit status 1 and "legsim_model: error: FILE: ITEM: PROBLEM" on stderr.
#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "legsim/legsim.h"
#include "model_toml.hpp"

namespace {

const char *kProgram = "legsim_model";

struct Variant {
  std::string name;
  legsim_model_desc model;
};

// ---- numbers and strings as C (and JSON) text --------------------------------------
// The shortest digits that round-trip (std::to_chars), laid out as Python's repr() lays
// out a float: positional for exponents -4 <= e < 16 (with ".0" on integers), else
// d.ddde+XX. C reads either back as the same double.
std::string real(double x) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::scientific);
  std::string sci(buf, r.ptr);  // [-]d[.ddd]e(+|-)XX
  std::string sign;
  if (sci[0] == '-') {
    sign = "-";
    sci.erase(0, 1);
  }
  const size_t e = sci.find('e');
  const int exp10 = std::stoi(sci.substr(e + 1));
  std::string digits = sci.substr(0, e);
  if (digits.size() > 1) digits.erase(1, 1);  // the point
  const int n = static_cast<int>(digits.size());
  const int point = exp10 + 1;  // digits before the decimal point
  if (point > -4 && point <= 16) {
    if (point <= 0) return sign + "0." + std::string(static_cast<size_t>(-point), '0') + digits;
    if (point < n) return sign + digits.substr(0, point) + "." + digits.substr(point);
    return sign + digits + std::string(static_cast<size_t>(point - n), '0') + ".0";
  }
  std::string mant = digits.substr(0, 1);
  if (n > 1) mant += "." + digits.substr(1);
  char ex[16];
  std::snprintf(ex, sizeof ex, "e%c%02d", exp10 < 0 ? '-' : '+', exp10 < 0 ? -exp10 : exp10);
  return sign + mant + ex;
}

std::string vec(const double *v, int n) {
  std::string s = "{";
  for (int i = 0; i < n; ++i) s += (i ? ", " : "") + real(v[i]);
  return s + "}";
}

// Names hold only [A-Za-z0-9_.-] (the loader's rule); escaped anyway.
std::string str(const char *s) {
  std::string out = "\"";
  for (const char *p = s; *p; ++p) {
    if (*p == '\\' || *p == '"') out += '\\';
    out += *p;
  }
  return out + "\"";
}

const char *joint_enum(legsim_joint_kind k) {
  switch (k) {
    case LEGSIM_JOINT_REVOLUTE_TO_FRAME: return "LEGSIM_JOINT_REVOLUTE_TO_FRAME";
    case LEGSIM_JOINT_REVOLUTE: return "LEGSIM_JOINT_REVOLUTE";
    case LEGSIM_JOINT_PRISMATIC: return "LEGSIM_JOINT_PRISMATIC";
    default: return "LEGSIM_JOINT_SLOT";
  }
}

const char *joint_kind_name(legsim_joint_kind k) {
  switch (k) {
    case LEGSIM_JOINT_REVOLUTE_TO_FRAME: return "revolute_to_frame";
    case LEGSIM_JOINT_REVOLUTE: return "revolute";
    case LEGSIM_JOINT_PRISMATIC: return "prismatic";
    default: return "slot";
  }
}

const char *force_enum(legsim_force_kind k) {
  switch (k) {
    case LEGSIM_FORCE_POINT: return "LEGSIM_FORCE_POINT";
    case LEGSIM_FORCE_TORQUE: return "LEGSIM_FORCE_TORQUE";
    default: return "LEGSIM_FORCE_SPRING_DAMPER";
  }
}

std::string base_name(const std::string &path) {
  const size_t k = path.rfind('/');
  return k == std::string::npos ? path : path.substr(k + 1);
}

std::string upper(std::string s) {
  for (char &c : s)
    if (c >= 'a' && c <= 'z') c = static_cast<char>(c - 'a' + 'A');
  return s;
}

bool is_ident(const std::string &s) {
  if (s.empty()) return false;
  for (size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    const bool alpha = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_';
    if (!(alpha || (i > 0 && c >= '0' && c <= '9'))) return false;
  }
  return true;
}

// ---- the C data --------------------------------------------------------------------
std::string c_model(const legsim_model_desc &m, const std::string &cname, const std::string &src,
                    const std::string &variant) {
  std::string o;
  auto line = [&o](const std::string &s) { o += s + "\n"; };
  line("/* " + src + ", variant \"" + variant + "\" */");
  line("const legsim_model_desc " + cname + " = {");
  line("  " + str(m.name) + ",");
  line("  " + vec(m.gravity_mps2, 2) + ",");
  line("  " + std::to_string(m.n_bodies) + ", " + std::to_string(m.n_joints) + ", " +
       std::to_string(m.n_actuators) + ", " + std::to_string(m.n_forces) + ", " +
       std::to_string(m.n_poses) + ", /* bodies, joints, actuators, forces, poses */");
  line("  { /* body: name, length, mass, inertia */");
  for (int i = 0; i < m.n_bodies; ++i) {
    const legsim_body_desc &b = m.body[i];
    line("    {" + str(b.name) + ", " + real(b.length_m) + ", " + real(b.mass_kg) + ", " +
         real(b.inertia_kgm2) + "},");
  }
  line("  },");
  line("  { /* joint: name, kind, body[2], point[2][2] */");
  for (int i = 0; i < m.n_joints; ++i) {
    const legsim_joint_desc &j = m.joint[i];
    line("    {" + str(j.name) + ", " + joint_enum(j.kind) + ", {" + std::to_string(j.body[0]) + ", " +
         std::to_string(j.body[1]) + "}, {" + vec(j.point[0], 2) + ", " + vec(j.point[1], 2) + "}},");
  }
  if (m.n_joints == 0) line("    {\"\", LEGSIM_JOINT_REVOLUTE_TO_FRAME, {0, 0}, {{0.0, 0.0}, {0.0, 0.0}}},");
  line("  },");
  line("  { /* actuator: name, joint, stroke min, max, max force, servo kp, kd */");
  for (int i = 0; i < m.n_actuators; ++i) {
    const legsim_actuator_desc &a = m.actuator[i];
    line("    {" + str(a.name) + ", " + std::to_string(a.joint) + ", " + real(a.stroke_min_m) + ", " +
         real(a.stroke_max_m) + ", " + real(a.max_force_n) + ", " + real(a.servo_kp_n_per_m) + ", " +
         real(a.servo_kd_ns_per_m) + "},");
  }
  if (m.n_actuators == 0) line("    {\"\", 0, 0.0, 0.0, 0.0, 0.0, 0.0},");
  line("  },");
  line("  { /* force: name, kind, body[2], point[2][2], value[2], stiffness, damping, rest length */");
  for (int i = 0; i < m.n_forces; ++i) {
    const legsim_force_desc &f = m.force[i];
    line("    {" + str(f.name) + ", " + force_enum(f.kind) + ", {" + std::to_string(f.body[0]) + ", " +
         std::to_string(f.body[1]) + "}, {" + vec(f.point[0], 2) + ", " + vec(f.point[1], 2) + "}, " +
         vec(f.value, 2) + ", " + real(f.stiffness_n_per_m) + ", " + real(f.damping_ns_per_m) + ", " +
         real(f.rest_length_m) + "},");
  }
  if (m.n_forces == 0)
    line("    {\"\", LEGSIM_FORCE_POINT, {0, 0}, {{0.0, 0.0}, {0.0, 0.0}}, {0.0, 0.0}, 0.0, 0.0, 0.0},");
  line("  },");
  line("  { /* pose: name, n_drivers, driver[] {body, coord, value}, guess[][3] */");
  for (int i = 0; i < m.n_poses; ++i) {
    const legsim_pose_desc &p = m.pose[i];
    std::string drv;
    for (int d = 0; d < p.n_drivers; ++d)
      drv += (d ? ", {" : "{") + std::to_string(p.driver[d].body) + ", " +
             std::to_string(p.driver[d].coord) + ", " + real(p.driver[d].value) + "}";
    if (p.n_drivers == 0) drv = "{0, 0, 0.0}";
    std::string gs;
    for (int b = 0; b < m.n_bodies; ++b) gs += (b ? ", " : "") + vec(p.guess[b], 3);
    line("    {" + str(p.name) + ", " + std::to_string(p.n_drivers) + ", {" + drv + "},");
    line("     {" + gs + "}},");
  }
  if (m.n_poses == 0) line("    {\"\", 0, {{0, 0, 0.0}}, {{0.0, 0.0, 0.0}}},");
  line("  },");
  line("  " + std::to_string(m.foot_body) + ", " + vec(m.foot_point, 2) + ", /* foot body, point */");
  line("  " + std::to_string(m.n_contacts) + ", /* contacts */");
  line("  { /* contact: name, body, point */");
  for (int i = 0; i < m.n_contacts; ++i) {
    const legsim_contact_desc &c = m.contact[i];
    line("    {" + str(c.name) + ", " + std::to_string(c.body) + ", " + vec(c.point, 2) + "},");
  }
  if (m.n_contacts == 0) line("    {\"\", 0, {0.0, 0.0}},");
  line("  },");
  const legsim_ground_desc &gr = m.ground;
  line("  {" + vec(gr.point, 2) + ", " + real(gr.slope_rad) + ", " + real(gr.mu_static) + ", " +
       real(gr.mu_kinetic) + "} /* ground: point, slope, mu static, kinetic */");
  line("};");
  return o;
}

// #if / #error for each capacity the variants need (the build's legsim/config.h).
std::string capacity_checks(const std::vector<Variant> &vs, const std::string &symbol,
                            const std::string &src) {
  int need[7] = {0, 0, 0, 0, 0, 0, 0};
  size_t longest = 0;
  auto name = [&longest](const char *s) { longest = std::max(longest, std::strlen(s)); };
  for (const Variant &v : vs) {
    const legsim_model_desc &m = v.model;
    const int counts[6] = {m.n_bodies, m.n_joints, m.n_actuators, m.n_forces, m.n_poses, m.n_contacts};
    for (int k = 0; k < 6; ++k) need[k] = std::max(need[k], counts[k]);
    for (int p = 0; p < m.n_poses; ++p) need[6] = std::max(need[6], static_cast<int>(m.pose[p].n_drivers));
    name(m.name);
    for (int i = 0; i < m.n_bodies; ++i) name(m.body[i].name);
    for (int i = 0; i < m.n_joints; ++i) name(m.joint[i].name);
    for (int i = 0; i < m.n_actuators; ++i) name(m.actuator[i].name);
    for (int i = 0; i < m.n_forces; ++i) name(m.force[i].name);
    for (int i = 0; i < m.n_poses; ++i) name(m.pose[i].name);
    for (int i = 0; i < m.n_contacts; ++i) name(m.contact[i].name);
  }
  static const char *const macro[7] = {"LEGSIM_MAX_BODIES",   "LEGSIM_MAX_JOINTS", "LEGSIM_MAX_ACTUATORS",
                                       "LEGSIM_MAX_FORCES",   "LEGSIM_MAX_POSES",  "LEGSIM_MAX_CONTACTS",
                                       "LEGSIM_MAX_POSE_DRIVERS"};
  static const char *const what[7] = {"bodies", "joints",   "actuators",   "force elements",
                                      "poses",  "contacts", "pose drivers"};
  const std::string who = "legsim model '" + symbol + "' (" + base_name(src) + ")";
  std::string o;
  for (int k = 0; k < 7; ++k) {
    const std::string c = std::to_string(need[k]);
    o += std::string("#if !defined(") + macro[k] + ") || " + macro[k] + " < " + c + "\n";
    o += "#error \"" + who + " needs " + macro[k] + " >= " + c + " (" + what[k] +
         "): raise it (the build's capacity, legsim/config.h)\"\n#endif\n";
  }
  const std::string len = std::to_string(longest + 1);
  o += "#if !defined(LEGSIM_NAME_LEN) || LEGSIM_NAME_LEN < " + len + "\n";
  o += "#error \"" + who + " has names of " + std::to_string(longest) +
       " characters: LEGSIM_NAME_LEN must be at least " + len + "\"\n#endif\n";
  return o;
}

std::pair<std::string, std::string> emit_c(const std::vector<Variant> &vs, const std::string &src,
                                           const std::string &symbol, const std::string &include_as) {
  const std::string up = upper(symbol), guard = "LEGSIM_MODELS_" + up + "_H";
  const std::string count = std::to_string(vs.size());
  const std::string banner = "/* Generated by legsim_model (firmware_core/tools/legsim_model) from " +
                             base_name(src) + ". Do not edit. */\n";
  std::string h = banner + "#ifndef " + guard + "\n#define " + guard + "\n\n#include \"legsim/legsim.h\"\n\n" +
                  "#ifdef __cplusplus\nextern \"C\" {\n#endif\n\n" +
                  "#ifndef LEGSIM_MODEL_VARIANT_DEFINED\n#define LEGSIM_MODEL_VARIANT_DEFINED\n" +
                  "/* A compiled-in model variant. */\ntypedef struct legsim_model_variant {\n" +
                  "  const char *name;\n  const legsim_model_desc *model;\n} legsim_model_variant;\n#endif\n\n";
  for (const Variant &v : vs) h += "extern const legsim_model_desc legsim_model_" + symbol + "_" + v.name + ";\n";
  h += "\n#define LEGSIM_MODEL_" + up + "_VARIANT_COUNT " + count + "\n";
  h += "/* \"" + vs[0].name + "\" (the default) first, then the file's [variant.X] in order. */\n";
  h += "extern const legsim_model_variant legsim_model_" + symbol + "_variants[" + count + "];\n";
  h += "extern const int32_t legsim_model_" + symbol + "_variant_count;\n\n";
  h += "#ifdef __cplusplus\n}\n#endif\n#endif /* " + guard + " */\n";

  std::string c = banner + "#include \"" + include_as + "\"\n\n" + capacity_checks(vs, symbol, src) + "\n";
  for (const Variant &v : vs)
    c += c_model(v.model, "legsim_model_" + symbol + "_" + v.name, base_name(src), v.name) + "\n";
  c += "const legsim_model_variant legsim_model_" + symbol + "_variants[" + count + "] = {\n";
  for (const Variant &v : vs) c += "  {" + str(v.name.c_str()) + ", &legsim_model_" + symbol + "_" + v.name + "},\n";
  c += "};\nconst int32_t legsim_model_" + symbol + "_variant_count = " + count + ";\n";
  return {c, h};
}

// ---- the structure as JSON ---------------------------------------------------------
std::string emit_structure(const std::vector<Variant> &vs, const std::string &src) {
  std::string o = "{\"file\": " + str(base_name(src).c_str()) + ", \"variants\": [";
  for (size_t k = 0; k < vs.size(); ++k) {
    const legsim_model_desc &m = vs[k].model;
    o += std::string(k ? ",\n  " : "\n  ") + "{\"name\": " + str(vs[k].name.c_str()) + ", \"model\": {";
    o += "\"bodies\": [";
    for (int i = 0; i < m.n_bodies; ++i) o += std::string(i ? ", " : "") + "{\"name\": " + str(m.body[i].name) + "}";
    o += "], \"joints\": [";
    for (int i = 0; i < m.n_joints; ++i)
      o += std::string(i ? ", " : "") + "{\"name\": " + str(m.joint[i].name) + ", \"kind\": \"" +
           joint_kind_name(m.joint[i].kind) + "\", \"body\": [" + std::to_string(m.joint[i].body[0]) + ", " +
           std::to_string(m.joint[i].body[1]) + "]}";
    o += "], \"actuators\": [";
    for (int i = 0; i < m.n_actuators; ++i)
      o += std::string(i ? ", " : "") + "{\"name\": " + str(m.actuator[i].name) +
           ", \"joint\": " + std::to_string(m.actuator[i].joint) + "}";
    o += "], \"contacts\": [";
    for (int i = 0; i < m.n_contacts; ++i)
      o += std::string(i ? ", " : "") + "{\"name\": " + str(m.contact[i].name) +
           ", \"body\": " + std::to_string(m.contact[i].body) + "}";
    o += "]}}";
  }
  return o + "\n]}\n";
}

// ---- loading and writing -----------------------------------------------------------
bool load_all(const std::string &path, std::vector<Variant> &out) {
  char msg[512] = {0};
  char names[16][LEGSIM_NAME_LEN];
  int32_t n = 0;
  legsim_status st = legsim_model_toml_variants(path.c_str(), names, 16, &n, msg, sizeof msg);
  if (st == LEGSIM_OK && n > 16) {
    std::snprintf(msg, sizeof msg, "%s: %d variants, at most 16", path.c_str(), static_cast<int>(n));
    st = LEGSIM_ERR_CAPACITY;
  }
  // the default variant first: it validates the base model and the [variant] tables
  for (int32_t v = 0; st == LEGSIM_OK && v < n; ++v) {
    Variant var;
    var.name = names[v];
    st = legsim_model_load_toml(path.c_str(), names[v], &var.model, msg, sizeof msg);
    if (st == LEGSIM_OK) out.push_back(var);
  }
  if (st != LEGSIM_OK) {
    std::fprintf(stderr, "%s: error: %s\n", kProgram, msg);
    return false;
  }
  return true;
}

// Written whole (a temporary file renamed), its folder made if missing.
bool write_file(const std::string &path, const std::string &text) {
  std::error_code ec;
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  if (!dir.empty()) std::filesystem::create_directories(dir, ec);
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    f << text;
    if (!f.good()) {
      std::fprintf(stderr, "%s: error: cannot write %s\n", kProgram, tmp.c_str());
      return false;
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::fprintf(stderr, "%s: error: cannot write %s: %s\n", kProgram, path.c_str(), std::strerror(errno));
    return false;
  }
  return true;
}

int usage(const char *why) {
  std::fprintf(stderr,
               "%s: %s\nusage: %s MODEL.toml --check\n"
               "       %s MODEL.toml --emit-c --symbol NAME --out-c FILE.c --out-h DIR/legsim/NAME.h "
               "[--include-as legsim/NAME.h]\n"
               "       %s MODEL.toml --emit-structure [--out FILE.json]\n",
               kProgram, why, kProgram, kProgram, kProgram);
  return 2;
}

}  // namespace

int main(int argc, char **argv) {
  std::string model, symbol, out_c, out_h, out, include_as;
  bool check = false, emit_c_ = false, emit_structure_ = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](std::string &dst) {
      if (i + 1 >= argc) return false;
      dst = argv[++i];
      return true;
    };
    if (a == "--check") check = true;
    else if (a == "--emit-c") emit_c_ = true;
    else if (a == "--emit-structure") emit_structure_ = true;
    else if (a == "--symbol" || a == "--out-c" || a == "--out-h" || a == "--out" || a == "--include-as") {
      std::string &dst = a == "--symbol" ? symbol : a == "--out-c" ? out_c : a == "--out-h" ? out_h
                         : a == "--out" ? out : include_as;
      if (!value(dst)) return usage((a + " needs a value").c_str());
    } else if (!a.empty() && a[0] == '-') {
      return usage(("unknown option " + a).c_str());
    } else if (model.empty()) {
      model = a;
    } else {
      return usage("more than one model file");
    }
  }
  if (model.empty()) return usage("no model file");
  if (check + emit_c_ + emit_structure_ != 1) return usage("give one of --check, --emit-c, --emit-structure");
  if (emit_c_) {
    if (!is_ident(symbol)) return usage(("--symbol '" + symbol + "' is not a C identifier").c_str());
    if (out_c.empty() || out_h.empty()) return usage("--emit-c needs --out-c and --out-h");
  }

  std::vector<Variant> variants;
  if (!load_all(model, variants)) return 1;
  if (check) {
    std::string names;
    for (const Variant &v : variants) names += (names.empty() ? "" : ", ") + v.name;
    std::printf("%s: OK (%s)\n", model.c_str(), names.c_str());
    return 0;
  }
  if (emit_structure_) {
    const std::string text = emit_structure(variants, model);
    if (out.empty()) return std::fputs(text.c_str(), stdout) < 0 ? 1 : 0;
    return write_file(out, text) ? 0 : 1;
  }
  if (include_as.empty()) {  // legsim/<name> when the header sits in a legsim/ folder
    const std::string base = base_name(out_h);
    const std::string dir = out_h.size() > base.size() ? out_h.substr(0, out_h.size() - base.size() - 1) : "";
    include_as = base_name(dir) == "legsim" ? "legsim/" + base : base;
  }
  const auto text = emit_c(variants, model, symbol, include_as);
  return write_file(out_h, text.second) && write_file(out_c, text.first) ? 0 : 1;
}
