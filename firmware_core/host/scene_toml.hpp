// Host-only scene files for legsim_cli: what to load, which analysis to run, with
// which inputs, and the JSON/CSV writers of the results. Uses the C API only.
//
// A scene (scenes/cli/*.toml):
//
//   description = "free text"                 # optional
//   model = "../../models/leg.toml"           # relative to the scene file;
//                                             # "builtin:leg" = the compiled-in leg
//   variant = "revolute"                      # default "revolute"
//   analysis = "dynamics"                     # dynamics | statics | statics_sweep |
//                                             # inverse_dynamics | assembly
//   integrator = "rk4"                        # rk4 | generalized_alpha (dynamics)
//   step = 0.001                              # s, > 0 (default 0.001)
//   duration = 0.5                            # s (dynamics, inverse_dynamics)
//   output_every = 10                         # steps between samples (default 1)
//   disable = ["reactions", "gravity"]        # gravity, force_elements, reactions,
//                                             # projection, actuators, stroke_limits
//   rho_inf = 0.8                             # optional solver options
//   max_newton_iter = 25
//   newton_tol = 1e-10
//   pose = "stand"                            # pose assembled first (default: the
//                                             # model's first pose, if it has one)
//   lengths = [0.66, 0.62]                    # assembly/statics/dynamics: assemble the
//                                             # actuators at these lengths after the pose
//   grid = 11                                 # statics_sweep: n x n grid (default 11)
//
//   [forces]                                  # force element values
//   foot_load = [0.0, 300.0]                  # point: [Fx, Fy] N; torque: N m
//
//   [[command]]                               # dynamics, inverse_dynamics
//   actuator = "upper"
//   mode = "force"                            # force | length (inverse_dynamics: length)
//   value = 50.0                              # or one of:
//   # sinusoid = { offset = 0.65, amplitude = 0.02, frequency = 1.0, phase = 0.0 }
//   # step = { t0 = 0.1, before = 0.0, after = 50.0 }
#ifndef LEGSIM_HOST_SCENE_TOML_HPP
#define LEGSIM_HOST_SCENE_TOML_HPP

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "legsim/legsim.h"

namespace legsim_host {

// A scalar input over time: constant, sinusoid or step.
struct Signal {
  enum Kind { kConstant, kSinusoid, kStep } kind = kConstant;
  double value = 0;                                            // constant
  double offset = 0, amplitude = 0, frequency_hz = 0, phase_rad = 0;  // sinusoid
  double t0 = 0, before = 0, after = 0;                        // step
  double at(double t) const;
  double rate(double t) const;   // d/dt (0 for constants and steps)
  double accel(double t) const;  // d2/dt2
  double min() const;            // smallest and largest value over all t
  double max() const;
};

struct Command {
  std::string actuator;
  int32_t index = -1;  // bound against the model
  legsim_actuator_mode mode = LEGSIM_ACTUATOR_FORCE;
  Signal signal;
};

struct ForceValue {
  std::string name;
  int32_t index = -1;
  int n = 0;  // values given
  double value[2] = {0, 0};
};

enum class Analysis { kDynamics, kStatics, kStaticsSweep, kInverseDynamics, kAssembly };
const char *analysis_name(Analysis a);

struct Scene {
  std::string path;         // the scene file as given
  std::string description;
  std::string model;        // as written in the scene
  std::string model_path;   // resolved against the scene's folder ("" for builtin:)
  std::string builtin;      // "leg" for model = "builtin:leg"
  std::string variant = "revolute";
  Analysis analysis = Analysis::kDynamics;
  legsim_options options{};
  double duration_s = 0;
  int64_t n_steps = 0;      // duration / step, rounded
  int64_t output_every = 1;
  std::string pose;         // "" = the model's first pose, if any
  int32_t pose_index = -1;  // bound
  bool has_lengths = false;
  std::vector<double> lengths;
  int32_t grid = 11;
  std::vector<ForceValue> forces;
  std::vector<Command> commands;
};

// Reads and checks a scene file (everything that does not need the model).
// On error returns false with "PATH: problem" in err. Never throws.
bool load_scene(const std::string &path, Scene &scene, std::string &err);

// Checks the scene against a model (names of actuators, forces, poses; lengths in
// stroke; forces within max_force) and binds the names to indices.
bool bind_scene(Scene &scene, const legsim_model_desc &model, std::string &err);

// ---- results ----------------------------------------------------------------------
struct Sample {
  double t = 0;
  std::vector<double> q;                 // n_coords
  std::vector<double> length, rate, force;  // per actuator
  bool has_reactions = false;
  std::vector<double> reaction;          // 3 per joint: fx, fy, moment
  bool has_foot = false;
  double foot[2] = {0, 0};
  double residual = 0;                   // max |Phi|
  int32_t iterations = 0;
  double condition = 0;
  uint32_t events = 0;
};

struct Result {
  legsim_status status = LEGSIM_OK;
  std::string error;                     // what failed, when status != OK
  double failed_at_s = -1;               // time of the failing step (dynamics, inverse dynamics)
  std::vector<Sample> samples;
  bool has_worst_case = false;
  legsim_worst_case worst{};
};

// Runs a bound scene on the model (which must outlive the call). Never throws.
// Returns the status (also in result.status); samples up to a failure are kept.
legsim_status run_scene(const Scene &scene, const legsim_model_desc &model, Result &result);

void write_json(std::ostream &out, const Scene &scene, const legsim_model_desc &model,
                const Result &result);
void write_csv(std::ostream &out, const Scene &scene, const legsim_model_desc &model,
               const Result &result);

// "LEGSIM_ERR_DIVERGED" etc.
const char *status_enum_name(legsim_status s);

}  // namespace legsim_host

#endif  // LEGSIM_HOST_SCENE_TOML_HPP
