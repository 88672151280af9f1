// legsim_cli: runs a scene file (scenes/*.toml, schema in scenes/README.md) and writes
// its results as JSON or CSV, sample by sample as the run makes them.
//
//   legsim_cli SCENE.toml [--out FILE.json|FILE.csv] [--format json|csv]
//   legsim_cli SCENE.toml --check
//   legsim_cli - --as PATH --check      (the scene's text on stdin, read as the file PATH)
//
// The scene names the model file (loaded at run time, host/model_toml.cpp) or
// "builtin:leg" (the default: the leg compiled in from models/leg.toml; "builtin:robot"
// the two-leg robot of models/robot.toml when the build holds it), the analysis
// and its inputs; a hexapod file (models/hexapod.toml) has its own keys and JSON
// (host/scene_hexapod.hpp). Exit status: 0 ok, 1 the run failed (the output holds the samples up
// to the failure; JSON also the status), 2 bad usage or a bad scene or model (nothing
// is written).
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>

#include "legsim/legsim.h"
#include "legsim/models.h"
#if __has_include("legsim/robot_models.h")
#include "legsim/robot_models.h"  // models/robot.toml, compiled in when the capacities hold it
#define LEGSIM_CLI_HAS_ROBOT 1
#else
#define LEGSIM_CLI_HAS_ROBOT 0
#endif
#include "model_toml.hpp"
#include "toml_limits.hpp"
#include "scene_toml.hpp"
#include "scene_hexapod.hpp"

namespace {

const char *kUsage =
    "usage: legsim_cli SCENE.toml [--out FILE.json|FILE.csv] [--format json|csv]\n"
    "       legsim_cli SCENE.toml --check\n"
    "       legsim_cli - --as PATH [--check]\n"
    "  Runs the scene (model, analysis, inputs; scenes/README.md) and writes time, body\n"
    "  coordinates, actuator lengths and forces, joint reactions, constraint residual and\n"
    "  status, sample by sample. Without --out the output goes to stdout; the format\n"
    "  follows --format, else the extension of --out, else JSON.\n"
    "  --check: read the scene and its model, print the resolved scene as JSON, run nothing.\n"
    "  -: read the scene's text from stdin, as if it were the file --as PATH (its name, and\n"
    "  its folder for a relative model path; default \"stdin\").\n"
    "  A hexapod scene (its model a hexapod file, scenes/README.md \"The hexapod\") writes\n"
    "  JSON only: the statics on its stance, or per sample the box, legs, feet and contacts.\n";

int usage_error(const std::string &msg) {
  std::cerr << "legsim_cli: " << msg << "\n" << kUsage;
  return 2;
}

bool ends_with(const std::string &s, const char *suffix) {
  const size_t n = std::strlen(suffix);
  return s.size() >= n && s.compare(s.size() - n, n, suffix) == 0;
}

}  // namespace

int main(int argc, char **argv) {
  std::string scene_path, out_path, format, as_path;
  bool check_only = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help") {
      std::cout << kUsage;
      return 0;
    } else if (a == "--check") {
      check_only = true;
    } else if (a == "--as") {
      if (++i >= argc) return usage_error("--as needs a file name");
      as_path = argv[i];
    } else if (a == "--out" || a == "-o") {
      if (++i >= argc) return usage_error("--out needs a file name");
      out_path = argv[i];
    } else if (a.rfind("--out=", 0) == 0) {
      out_path = a.substr(6);
    } else if (a == "--format") {
      if (++i >= argc) return usage_error("--format needs json or csv");
      format = argv[i];
    } else if (a.rfind("--format=", 0) == 0) {
      format = a.substr(9);
    } else if (a.size() > 1 && a[0] == '-') {
      return usage_error("unknown option " + a);
    } else if (scene_path.empty()) {
      scene_path = a;
    } else {
      return usage_error("one scene at a time (got " + scene_path + " and " + a + ")");
    }
  }
  if (scene_path.empty()) return usage_error("no scene file given");
  if (format.empty()) format = ends_with(out_path, ".csv") ? "csv" : "json";
  if (format != "json" && format != "csv") return usage_error("--format must be json or csv");

  if (!as_path.empty() && scene_path != "-") return usage_error("--as names a scene read from stdin (-)");
  legsim_host::Scene scene;
  std::string err, text;
  if (scene_path == "-") {
    // read at most one byte past the TOML limit: a larger text is refused without being held
    std::istreambuf_iterator<char> it(std::cin), end;
    for (; it != end && text.size() <= kTomlMaxBytes; ++it) text.push_back(*it);
    scene_path = as_path.empty() ? "stdin" : as_path;
  } else if (!read_toml_file(scene_path.c_str(), text, err)) {
    std::cerr << "legsim_cli: error: " << err << "\n";
    return 2;
  }
  // A hexapod's scene (its model a hexapod file) has keys of its own: its reader and runner.
  if (legsim_host::scene_is_hexapod(text, scene_path)) {
    if (format != "json") return usage_error("a hexapod scene writes JSON only (--format csv)");
    struct Out : legsim_host::HexapodOutput {
      std::string path;
      std::ofstream file;
      std::ostream *open() override {
        if (path.empty() || path == "-") return &std::cout;
        file.open(path, std::ios::binary);
        if (!file) {
          std::cerr << "legsim_cli: error: cannot write " << path << "\n";
          return nullptr;
        }
        return &file;
      }
    } hex_out;
    hex_out.path = check_only ? "" : out_path;
    const int rc = legsim_host::run_hexapod_scene(text, scene_path, check_only, hex_out, std::cerr);
    std::ostream &o = hex_out.file.is_open() ? static_cast<std::ostream &>(hex_out.file) : std::cout;
    o.flush();
    if (rc != 2 && !o) {
      std::cerr << "legsim_cli: error: cannot write " << (hex_out.file.is_open() ? out_path : "stdout") << "\n";
      return 2;
    }
    return rc;
  }
  if (!legsim_host::load_scene_text(text, scene_path, scene, err)) {
    std::cerr << "legsim_cli: error: " << err << "\n";
    return 2;
  }

  // The model: compiled in, or loaded (and checked) at run time. It must outlive the sim.
  legsim_model_desc model;
  if (!scene.builtin.empty()) {
    // The compiled-in models: the leg (models/leg.toml) and, when this build's capacities
    // hold it, the robot (models/robot.toml).
    const legsim_model_variant *variants = legsim_model_leg_variants;
    int32_t n_variants = legsim_model_leg_variant_count;
    const char *builtins = LEGSIM_CLI_HAS_ROBOT ? "leg, robot" : "leg";
#if LEGSIM_CLI_HAS_ROBOT
    if (scene.builtin == "robot") {
      variants = legsim_model_robot_variants;
      n_variants = legsim_model_robot_variant_count;
    } else
#endif
    if (scene.builtin != "leg") {
      std::cerr << "legsim_cli: error: " << scene_path << ": unknown builtin model '" << scene.builtin
                << "' (this build has: " << builtins << ")\n";
      return 2;
    }
    const legsim_model_desc *found = nullptr;
    std::string have;
    for (int32_t v = 0; v < n_variants; ++v) {
      have += std::string(v ? ", " : "") + variants[v].name;
      if (scene.variant == variants[v].name) found = variants[v].model;
    }
    if (!found) {
      std::cerr << "legsim_cli: error: " << scene_path << ": the builtin " << scene.builtin
                << " has no variant '" << scene.variant << "' (available: " << have << ")\n";
      return 2;
    }
    model = *found;
  } else {
    char msg[512];
    const legsim_status st =
        legsim_model_load_toml(scene.model_path.c_str(), scene.variant.c_str(), &model, msg, sizeof msg);
    if (st != LEGSIM_OK) {
      std::cerr << "legsim_cli: error: " << msg << " (model of " << scene_path << ")\n";
      return 2;
    }
  }
  if (!legsim_host::bind_scene(scene, model, err)) {
    std::cerr << "legsim_cli: error: " << err << "\n";
    return 2;
  }
  // [ground]: the scene's ground in the model it runs (bind_scene checked that it applies)
  if (!legsim_host::ground_apply(scene, model, err)) {
    std::cerr << "legsim_cli: error: " << scene_path << ": [ground]: " << err << "\n";
    return 2;
  }

  if (check_only) {
    legsim_host::write_resolved(std::cout, scene, model);
    return 0;
  }

  // The output is opened only now (a bad scene or model writes nothing) and written as
  // the run goes: a long run keeps no history in memory.
  std::ofstream file;
  const bool to_stdout = out_path.empty() || out_path == "-";
  if (!to_stdout) {
    file.open(out_path, std::ios::binary);
    if (!file) {
      std::cerr << "legsim_cli: error: cannot write " << out_path << "\n";
      return 2;
    }
  }
  std::ostream &out = to_stdout ? std::cout : file;
  legsim_host::JsonWriter json(out, scene, model);
  legsim_host::CsvWriter csv(out, scene, model);
  legsim_host::ResultWriter &writer = format == "csv" ? static_cast<legsim_host::ResultWriter &>(csv)
                                                      : static_cast<legsim_host::ResultWriter &>(json);
  legsim_host::Result result;
  legsim_host::run_scene(scene, model, writer, result);
  out.flush();
  if (!out) {
    std::cerr << "legsim_cli: error: cannot write " << (to_stdout ? "stdout" : out_path) << "\n";
    return 2;
  }
  if (result.status != LEGSIM_OK) {
    std::cerr << "legsim_cli: error: " << scene_path << ": " << result.error << "\n";
    return 1;
  }
  return 0;
}
