// Fuzz target: the scene loaders (firmware_core/host/scene_parse.cpp, scene_toml.hpp; a hexapod's or
// a block's: scene_hexapod*.cpp, scene_block.cpp), TOML text in.
//
// The text is written to a scratch file (load_scene reads a path), read and checked,
// bound against its model, written out resolved, and run on a short horizon (at most
// kMaxSteps steps, a statics grid of at most kMaxGrid). The model, as legsim_cli finds it:
// a model file the scene names (relative, as written) is read as if the scene were a file
// of a seed folder (kSeedFolders, absolute: whatever the working directory): scenes/ (the
// shipped robot scenes' "../models/robot.toml", "models/robot_slope_stand.toml"), then
// tests/model/fixtures/scenes/ ("../../../../models/robot.toml"); a file that loads is
// used (a robot's leg files with it, on its own ground), one that fails to load is
// refused as the CLI refuses it. A model = "builtin:robot", or a file that none of the
// folders has, binds to a compiled-in model: the two-leg robot (models/robot.toml) when the
// name says robot, else the leg; the scene's variant if the model has it, else its first.
// - every input gives true or false with a message, never a crash or undefined behaviour;
// - a scene that loads is accepted within the documented ranges (step counts, record
//   interval): the run is streamed sample by sample (the 1e9-step regression);
// - every sample of a run is finite (the C API's "never NaN on OK").
// A scene whose model is a hexapod file (legsim_cli's scene_is_hexapod, the scene read as a file of
// the first seed folder) goes to legsim_cli's hexapod reader instead: resolved (--check) and, when
// it is a statics or asks for at most kMaxHexapodSteps steps, run; its exit status 0 (the JSON
// ends "ok"), 1 (a failed run: "error", with a message) or 2 (refused, with a message, nothing
// written).
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>

#include "legsim/legsim.h"
#include "legsim/models.h"
#include "model_toml.hpp"
#if __has_include("legsim/robot_models.h")
#include "legsim/robot_models.h"  // compiled in when the build's capacities hold the robot
#define FUZZ_SCENE_HAS_ROBOT 1
#else
#define FUZZ_SCENE_HAS_ROBOT 0
#endif
#include "reach.h"
#include "scene_hexapod.hpp"
#include "scene_toml.hpp"

FUZZ_REACH_DEFINE

namespace {

constexpr int64_t kMaxSteps = 100;
constexpr int32_t kMaxGrid = 4;
constexpr int64_t kMaxHexapodSteps = 20;

[[noreturn]] void violated(const std::string &what) {
  std::fprintf(stderr, "fuzz_scene: invariant violated: %s\n", what.c_str());
  std::abort();
}

// A scratch file of this process (libFuzzer's -jobs/-fork run several processes), removed
// at exit. Kept in static char arrays: they outlive the exit handlers.
char g_scratch_dir[4096], g_scratch_file[4200];

void remove_scratch() {
  std::remove(g_scratch_file);
  rmdir(g_scratch_dir);
}

const char *scratch_path() {
  if (g_scratch_file[0] == '\0') {
    const char *tmp = std::getenv("TMPDIR");
    std::snprintf(g_scratch_dir, sizeof g_scratch_dir, "%s/legsim_fuzz_scene.XXXXXX",
                  tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(g_scratch_dir)) violated("cannot make a scratch directory");
    std::snprintf(g_scratch_file, sizeof g_scratch_file, "%s/scene.toml", g_scratch_dir);
    std::atexit(remove_scratch);
  }
  return g_scratch_file;
}

void finite(double x, const std::string &what) {
  if (!std::isfinite(x)) violated("sample " + what + " = " + std::to_string(x));
}
void finite(const std::vector<double> &v, const std::string &what) {
  for (size_t i = 0; i < v.size(); ++i) finite(v[i], what + "[" + std::to_string(i) + "]");
}

// The CLI's two writers, and the checks, on every sample.
class CheckingWriter : public legsim_host::ResultWriter {
 public:
  CheckingWriter(const legsim_host::Scene &s, const legsim_model_desc &m)
      : json_(out_, s, m), csv_(out_, s, m) {}
  void begin() override {
    json_.begin();
    csv_.begin();
  }
  void sample(const legsim_host::Sample &s) override {
    ++n_;
    finite(s.t, "t");
    finite(s.q, "q");
    finite(s.length, "length");
    finite(s.rate, "rate");
    finite(s.force, "force");
    finite(s.reaction, "reaction");
    finite(s.foot[0], "foot x");
    finite(s.foot[1], "foot y");
    finite(s.residual, "residual");
    finite(s.condition, "condition");
    json_.sample(s);
    csv_.sample(s);
    out_.str("");  // streamed: nothing is kept
  }
  void end(const legsim_host::Result &r) override {
    if (r.status == LEGSIM_OK && !r.error.empty()) violated("OK with an error message: " + r.error);
    if (r.status != LEGSIM_OK && r.error.empty()) violated("a failed run without a message");
    if (r.n_samples != n_) violated("n_samples differs from the samples written");
    json_.end(r);
    csv_.end(r);
  }

 private:
  std::ostringstream out_;
  legsim_host::JsonWriter json_;
  legsim_host::CsvWriter csv_;
  int64_t n_ = 0;
};

// "FOLDER/" of the seed folders a scene's model file is looked up from.
const char *const kSeedFolders[] = {LEGSIM_FUZZ_SOURCE_DIR "/scenes/",
                                    LEGSIM_FUZZ_SOURCE_DIR "/tests/model/fixtures/scenes/"};

// The model file a scene names, loaded from the first seed folder that has it: 1 loaded,
// 0 refused by the loader (the CLI's exit 2), -1 in no folder (or absolute, or builtin).
int load_model_file(const legsim_host::Scene &scene, legsim_model_desc *out) {
  if (!scene.builtin.empty() || scene.model.empty() || scene.model[0] == '/') return -1;
  for (const char *folder : kSeedFolders) {
    const std::string path = std::string(folder) + scene.model;
    char msg[512];
    std::memset(msg, 'x', sizeof msg);  // a message must end inside msg
    msg[0] = '\0';
    const legsim_status st = legsim_model_load_toml(path.c_str(), scene.variant.c_str(), out, msg, sizeof msg);
    if (std::memchr(msg, '\0', sizeof msg) == nullptr) violated("loader message not terminated");
    if (st == LEGSIM_OK) return 1;
    if (msg[0] == '\0') violated("the model loader refused without a message");
    // the file itself unreadable (a leg file of a robot that is: refused, as by the CLI)
    if (!(st == LEGSIM_ERR_BAD_INPUT && std::strncmp(msg, path.c_str(), path.size()) == 0 &&
          std::strncmp(msg + path.size(), ": cannot read: ", 15) == 0))
      return 0;
  }
  return -1;
}

// The compiled-in model a scene stands for (the header says which).
const legsim_model_desc *model_of(const legsim_host::Scene &scene, bool *robot) {
  const legsim_model_variant *variants = legsim_model_leg_variants;
  int32_t n = legsim_model_leg_variant_count;
  *robot = false;
#if FUZZ_SCENE_HAS_ROBOT
  const std::string file = scene.model.substr(scene.model.find_last_of('/') + 1);
  if (scene.builtin == "robot" || (scene.builtin.empty() && file.find("robot") != std::string::npos)) {
    variants = legsim_model_robot_variants;
    n = legsim_model_robot_variant_count;
    *robot = true;
  }
#endif
  for (int32_t v = 0; v < n; ++v)
    if (scene.variant == variants[v].name) return variants[v].model;
  return variants[0].model;
}

struct StringOutput : legsim_host::HexapodOutput {
  std::ostringstream s;
  bool opened = false;
  std::ostream *open() override {
    opened = true;
    return &s;
  }
};

// legsim_cli's hexapod reader on the text (read as the file at path): its exit status, with the
// invariants above checked.
int hexapod_scene(const std::string &text, const std::string &path, bool check_only, std::string &json) {
  StringOutput out;
  std::ostringstream err;
  const int rc = legsim_host::run_hexapod_scene(text, path, check_only, out, err);
  json = out.s.str();
  const std::string e = err.str();
  if (rc == 2) {
    if (e.rfind("legsim_cli: error: ", 0) != 0) violated("a hexapod scene refused without a message: " + e);
    return rc;
  }
  if (rc != 0 && rc != 1) violated("hexapod scene exit status " + std::to_string(rc));
  if (!out.opened) violated("a hexapod scene accepted without output");
  const bool ok = json.find("\"status\": \"ok\"") != std::string::npos;
  if (!check_only && (rc == 0) != ok) violated("hexapod scene exit " + std::to_string(rc) + " with its JSON's status");
  if (rc == 1 && e.rfind("legsim_cli: error: ", 0) != 0) violated("a failed hexapod run without a message");
  if (rc == 0 && !e.empty()) violated("a hexapod scene accepted with a message: " + e);
  return rc;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  fuzz_reach::input("fuzz_scene");
  const std::string path = scratch_path();
  FILE *f = std::fopen(path.c_str(), "wb");
  if (!f) violated("cannot write the scratch file " + path);
  if (size > 0 && std::fwrite(data, 1, size, f) != size) violated("short write to " + path);
  std::fclose(f);

  const std::string text(reinterpret_cast<const char *>(data), size);
  const std::string as_seed = std::string(kSeedFolders[0]) + "fuzz_input.toml";  // never read
  if (legsim_host::scene_is_hexapod(text, as_seed)) {
    std::string json;
    if (hexapod_scene(text, as_seed, true, json) != 0) return 0;
    fuzz_reach::hexapod();  // accepted by the hexapod's (or the block's) reader
    // run the statics and, by the resolved header's step count, the short runs
    const size_t at = json.find("\"n_steps\": ");
    if (json.find("\"analysis\": \"statics\"") != std::string::npos ||
        (at != std::string::npos && std::strtoll(json.c_str() + at + 11, nullptr, 10) <= kMaxHexapodSteps))
      hexapod_scene(text, as_seed, false, json);
    return 0;
  }

  legsim_host::Scene scene;
  std::string err;
  if (!legsim_host::load_scene(path, scene, err)) {
    if (err.empty()) violated("load_scene refused without a message");
    return 0;
  }
  if (!err.empty()) violated("load_scene accepted with a message: " + err);
  // The documented ranges (scenes/README.md): 1 .. 1e9 steps, record_every 1 .. 1e7.
  if (scene.n_steps < 0 || scene.n_steps > 1000000000) violated("n_steps out of range");
  if (scene.record_every < 1 || scene.record_every > 10000000) violated("record_every out of range");

  bool robot = false;
  static legsim_model_desc loaded;  // the sim reads it by pointer while the run lasts
  const legsim_model_desc *model = nullptr;
  switch (load_model_file(scene, &loaded)) {
    case 1:
      model = &loaded;
      robot = loaded.n_contacts > 0;
      break;
    case 0: return 0;  // refused with a message, as legsim_cli refuses it
    default: model = model_of(scene, &robot);
  }
  if (!legsim_host::bind_scene(scene, *model, err)) {
    if (err.empty()) violated("bind_scene refused without a message");
    return 0;
  }
  if (robot) fuzz_reach::robot();  // a robot scene bound: its run is the robot's
  std::ostringstream resolved;
  legsim_host::write_resolved(resolved, scene, *model);

  // A short horizon: the loader's job is checked above; the run shows it streams.
  if (scene.n_steps > kMaxSteps) scene.n_steps = kMaxSteps;
  if (scene.grid > kMaxGrid) scene.grid = kMaxGrid;
  CheckingWriter writer(scene, *model);
  legsim_host::Result result;
  const legsim_status st = legsim_host::run_scene(scene, *model, writer, result);
  if (st != result.status) violated("run_scene's status differs from result.status");
  if (result.has_worst_case) {
    for (int32_t j = 0; j < model->n_joints; ++j) {
      finite(result.worst.max_reaction_n[j], "worst-case reaction");
    }
    for (int32_t a = 0; a < model->n_actuators; ++a)
      finite(result.worst.max_actuator_force_n[a], "worst-case actuator force");
  }
  return 0;
}
