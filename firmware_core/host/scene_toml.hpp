// Scene files (scenes/*.toml): what to load, which analysis to run with which inputs,
// and the JSON/CSV writers of the results. Host only; uses the C API only. Parsed and bound
// in scene_parse.cpp, run in scene_run.cpp, written in scene_write.cpp.
//
// The schema (every key, unit, default and range) is documented in scenes/README.md.
// This is the one reader of scene files: the bench reads the resolved scene this reader
// prints (legsim_cli --check, write_resolved). Keys of the bench only ([checks], [[inject]],
// cmd_timeout_ms, safe_state: the CAN link and its verdicts) are checked here as fully as
// the others and otherwise ignored: legsim_cli has no bus.
#ifndef LEGSIM_HOST_SCENE_TOML_HPP
#define LEGSIM_HOST_SCENE_TOML_HPP

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "legsim/legsim.h"

namespace legsim_host {

// A scalar input over time: constant, sinusoid, step, or "initial" (the actuator's
// assembled length at t = 0, known only once the model is assembled).
// kSwitch: `before` until the step after the one in which contact `contact` raised `event`
// (a LEGSIM_EVENT_ contact bit), `after` from then on: its time is the run's, so at() gives
// `before` and the runner switches (scene_run.cpp).
struct Signal {
  enum Kind { kConstant, kSinusoid, kStep, kInitial, kSwitch } kind = kConstant;
  double value = 0;                                            // constant (and initial, once known)
  double offset = 0, amplitude = 0, frequency_hz = 0, phase_rad = 0;  // sinusoid
  double t0 = 0, before = 0, after = 0;                        // step, switch
  std::string event, contact;                                  // switch: names as written
  uint32_t event_bit = 0;                                      // switch: LEGSIM_EVENT_ bit
  int32_t contact_index = -1;                                  // switch: bound against the model
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

// [[contact]]: a contact's state at t = 0 (a robot: its feet start stuck where the stand
// assembly puts them; "free" lifts a foot's rows).
struct ContactInit {
  std::string name;
  int32_t index = -1;  // bound against the model
  legsim_contact_state state = LEGSIM_CONTACT_STUCK;
};

// [start]: a robot's state at t = 0 as a rigid motion of its stance (dynamics): turned by
// tilt about the box's centre, raised by lift along the ground's upward normal, every body
// moving with the box (velocity of the box's centre, spin about it).
struct StartState {
  bool given = false;
  double lift_m = 0, tilt_rad = 0;
  double velocity_mps[2] = {0, 0};
  double spin_radps = 0;
};

// [ground]: the scene's ground instead of the robot file's (any key left out keeps the file's).
struct GroundSpec {
  bool given = false;
  bool has_slope = false, has_mu_static = false, has_mu_kinetic = false;
  double slope_rad = 0, mu_static = 0, mu_kinetic = 0;
};

// [checks]: the bench's verdicts. Values are checked at parse time, the keys that apply
// (which depend on the model: a leg or a robot) and the feet named at bind time.
struct CheckSpec {
  bool given = false;               // [checks] written (else the bench's default tolerances)
  std::vector<std::string> keys;    // the keys written, in file order
  int n_tolerances = 0;             // keys that are tolerances
  std::string stroke_actuator;      // [checks.stroke] actuator ("" without it)
  bool has_slips = false, has_lifts = false;
  bool events = false;              // events = true: the event-locating reference (robot dynamics)
  std::vector<std::string> slips, lifts;  // feet (a robot's contacts)
};

enum class Analysis { kDynamics, kStatics, kStaticsSweep, kInverseDynamics, kAssembly };
const char *analysis_name(Analysis a);

// What the actuators do from t = 0 until (and unless) a command says otherwise.
enum class ActuatorInit { kZeroForce, kHoldLength };
const char *init_name(ActuatorInit i);  // "zero_force" | "hold_length"

struct Scene {
  std::string path;         // the scene file as given
  std::string name;         // 'name', else the file's stem
  std::string description;
  bool demo = false;
  std::string model = "builtin:leg";  // as written in the scene (default: the compiled-in leg)
  std::string model_path;   // resolved against the scene's folder ("" for builtin:)
  std::string builtin;      // "leg" for model = "builtin:leg"
  std::string variant = "revolute";
  Analysis analysis = Analysis::kDynamics;
  legsim_options options{};  // integrator, step_s, disable, solver options
  bool statics_rule_given = false;  // 'statics_rule' written (options.statics_rule holds it)
  bool contact_law_given = false;   // 'contact_law' written (options.contact_law holds it)
  int64_t step_ns = 1000000; // step_s in whole nanoseconds (the bench's and the DBC's unit)
  double duration_s = 0;
  int64_t n_steps = 0;      // duration / step_s, exactly (else the scene is refused)
  int64_t record_every = 1;
  std::string pose;         // "" = the model's first pose, if any
  int32_t pose_index = -1;  // bound
  bool has_lengths = false;
  std::vector<double> lengths;
  int32_t grid = 11;
  ActuatorInit init = ActuatorInit::kZeroForce;
  int64_t cmd_timeout_ms = 0;            // bench only
  std::string safe_state = "zero_force"; // bench only
  std::string checks_json = "null";     // bench only: [checks] as written, JSON (null: none)
  CheckSpec checks;                     // bench only: [checks], checked
  int n_injections = 0;                 // bench only: [[inject]] tables
  std::string inject_json = "[]";       // bench only: [[inject]] resolved (steps, frame ids), JSON
  std::vector<ForceValue> forces;
  std::vector<Command> commands;
  std::vector<ContactInit> contacts;     // [[contact]] (models with contacts only)
  bool has_box_load = false;             // 'box_load' given (models with contacts only)
  double box_load[3] = {0, 0, 0};        // Fx, Fy N at the box's centre, M N m
  StartState start;                      // [start] (dynamics of a model with contacts)
  GroundSpec ground;                     // [ground] (a model with contacts)
};

// [ground]: the scene's ground written into the model's description (before bind_scene and
// legsim_init; legsim_cli does it once the model is loaded). False with why when the model
// has no contacts or the result breaks mu_kinetic <= mu_static. Nothing changes on failure.
bool ground_apply(const Scene &scene, legsim_model_desc &desc, std::string &why);

// box_load: a robot's box (body 0) gets two force elements, kBoxLoadName (a point force at its
// centre, [Fx, Fy]) and kBoxMomentName (a torque, M), appended to the description. False
// with why when the model has no contacts, no room for them, or names them already.
constexpr const char *kBoxLoadName = "box.load";
constexpr const char *kBoxMomentName = "box.moment";
bool box_load_add(legsim_model_desc &desc, const double load[3], std::string &why);

// Reads and checks a scene file (everything that does not need the model).
// On error returns false with "PATH: problem" in err. Never throws.
bool load_scene(const std::string &path, Scene &scene, std::string &err);
// The same for scene text given as if it were the file at path (its name, its folder).
bool load_scene_text(const std::string &text, const std::string &path, Scene &scene, std::string &err);

// Checks the scene against a model (names of actuators, forces, poses; lengths in
// stroke; forces within max_force) and binds the names to indices.
bool bind_scene(Scene &scene, const legsim_model_desc &model, std::string &err);

// The resolved scene as one JSON object (legsim_cli --check): everything the bench reads of
// a scene (bench/legsim_bench/scene.py builds its Scene from it).
void write_resolved(std::ostream &out, const Scene &scene, const legsim_model_desc &model);
// The part of it that says what the bench needs of the model and the scene's own words:
// ", \"description\": ..., \"demo\": ..., \"model_info\": {...}" (write_resolved appends it).
void write_resolved_model(std::ostream &out, const Scene &scene, const legsim_model_desc &model);

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
  std::vector<legsim_contact> contacts;  // n_contacts (a robot's feet)
  bool contact_forces = true;            // false: their forces are not solved yet (null)
};

struct Result {
  legsim_status status = LEGSIM_OK;
  std::string error;                     // what failed, when status != OK
  double failed_at_s = -1;               // time of the failing step (dynamics, inverse dynamics)
  int64_t n_samples = 0;                 // samples written
  bool has_worst_case = false;
  legsim_worst_case worst{};
};

// Receives the results as the run makes them: samples are written out one by one, not
// kept (a long run needs no memory for its history).
class ResultWriter {
 public:
  virtual ~ResultWriter() = default;
  virtual void begin() = 0;
  virtual void sample(const Sample &s) = 0;
  virtual void end(const Result &r) = 0;  // the status, and the sweep's worst case
};

// JSON: the set-up, then "samples" as they come, then the status. CSV: a header, then one
// row per sample (a failed run ends with its last good sample: the failure is in the exit
// status and on stderr, never in a row of empty fields).
class JsonWriter : public ResultWriter {
 public:
  JsonWriter(std::ostream &out, const Scene &scene, const legsim_model_desc &model)
      : o_(out), sc_(scene), m_(model) {}
  void begin() override;
  void sample(const Sample &s) override;
  void end(const Result &r) override;

 private:
  std::ostream &o_;
  const Scene &sc_;
  const legsim_model_desc &m_;
  int64_t n_ = 0;
};

class CsvWriter : public ResultWriter {
 public:
  CsvWriter(std::ostream &out, const Scene &scene, const legsim_model_desc &model)
      : o_(out), sc_(scene), m_(model) {}
  void begin() override;
  void sample(const Sample &s) override;
  void end(const Result &r) override;

 private:
  std::ostream &o_;
  const Scene &sc_;
  const legsim_model_desc &m_;
};

// The rule for a start length (m) of actuator a, a scene's `lengths` and a RESET's
// Ctrl_Length_* alike: finite and inside the stroke [stroke_min_m, stroke_max_m], ends
// included, compared in double with no tolerance and never clamped. legsim_cli's scene check
// and hil_sim's RESET both use it on the same double (CAN carries it as float64), so a start
// one refuses the other refuses, and one both take is the same start. Allocation-free.
bool start_length_in_stroke(const legsim_model_desc &model, int32_t a, double length_m);

// [start] on a robot assembled on the ground (legsim_assemble_on_ground: every contact stuck,
// the stance's contact positions fresh): moves it rigidly as `start` says and sets each
// contact's state: given_state[k] (a legsim_contact_state, or -1: stuck on the ground within
// tol (m), free above it; NULL: none given). Refuses (LEGSIM_ERR_STATE, error says why) a foot
// below the ground, a given state the start cannot honour (stuck or sliding off the ground,
// stuck while moving, sliding off the line) and a foot on the ground, moving, with no state:
// nothing is adjusted. legsim_cli's run and hil_sim's RESET both use it.
legsim_status start_apply(legsim_sim *sim, const legsim_model_desc &model, const StartState &start,
                          const int32_t *given_state, double tol, std::string &error);

// Runs a bound scene on the model (which must outlive the call), handing each sample to
// the writer as it is made. Never throws. Returns the status (also in result.status).
legsim_status run_scene(const Scene &scene, const legsim_model_desc &model, ResultWriter &writer,
                        Result &result);

// "LEGSIM_ERR_DIVERGED" etc.
const char *status_enum_name(legsim_status s);

}  // namespace legsim_host

#endif  // LEGSIM_HOST_SCENE_TOML_HPP
