// The leg (or the two-leg robot) on the solver: the only file that calls the legsim C API.
//
// A session is one RESET: a compiled model (revolute or slot D variant of the leg, or the
// robot of models/robot.toml: a box and two legs, each leg laid out on the bus as the
// one leg is), its options and state. RESET builds the new session in spare storage and swaps only on success, so a
// failed RESET leaves the running session as it was. Storage is allocated once at start.
#ifndef HIL_SIM_SESSION_H
#define HIL_SIM_SESSION_H

#include <cstdint>
#include <string>

#include "legsim/legsim.h"

namespace hil {

// The leg as can/legsim.dbc lays it out (one leg's frames).
constexpr int kBodies = 6;
constexpr int kCoords = 3 * kBodies;
constexpr int kJoints = 8;
constexpr int kActuators = 2;
// The robot: body 0 the box, then leg k's bodies 1 + 6k .. 6 + 6k, joints 8k .., actuators
// 2k .., its force elements n_forces / 2 each, contact k its foot (docs/design/robot-on-ground.md).
constexpr int kMaxLegs = 2;
constexpr int kMaxBodies = 1 + kMaxLegs * kBodies;
constexpr int kMaxCoords = 3 * kMaxBodies;
constexpr int kMaxJoints = kMaxLegs * kJoints;
constexpr int kMaxActuators = kMaxLegs * kActuators;
constexpr int kMaxContacts = kMaxLegs;
constexpr int kBoxLoadIndex = 2;  // leg 0's LOAD_CMD: 2 box.load (Fx, Fy), 3 box.moment (M)

enum class SafeMode { kZeroForce, kHoldLength };
enum class ActMode : uint8_t { kKeep = 0, kForce = 1, kLength = 2 };

struct ResetParams {
  int variant = 0;      // 0 revolute, 1 slot
  int integrator = 0;   // legsim_integrator
  int pose = 0;
  uint32_t step_ns = 1000000;
  uint32_t disable = 0;
  bool hold_length = false;  // else zero force
  bool use_lengths = false;
  double lengths[kMaxActuators] = {0, 0, 0, 0};  // leg 0 upper, lower, then leg 1's
  int contact_law = 0;        // legsim_contact_law (the robot's feet)
  uint32_t free_contacts = 0; // bit k: contact k FREE after the assembly on the ground
  // START_CMD (a scene's [start]): the stance moved rigidly after the assembly on the ground,
  // each foot's state given by the bit masks (free: free_contacts) or by where it is
  bool use_start = false;
  float start_lift = 0, start_tilt = 0, start_velocity[2] = {0, 0}, start_spin = 0;
  uint32_t stuck_contacts = 0, sliding_contacts = 0;
};

struct ContactSample {  // legsim_contact, as sent (plain data: Session::sample zeroes it)
  int state;              // legsim_contact_state
  legsim_real normal, tangential, friction_use, position[2], slip, impulse[2];
  uint32_t events;        // legsim_contact_event_mask: its contact events since the last clear
};

struct Sample {
  int legs;          // 1: the leg (no box, no contacts); 2: the robot
  legsim_real q[kMaxCoords];
  legsim_real qd[kMaxCoords];
  legsim_real length[kMaxActuators], rate[kMaxActuators], force[kMaxActuators];
  legsim_reaction reaction[kMaxJoints];
  ContactSample contact[kMaxContacts];
  double t;
  uint64_t steps;
  legsim_real residual;
  legsim_report report;
  uint32_t stroke_mask;
};

class Session {
 public:
  Session() = default;
  Session(const Session &) = delete;
  Session &operator=(const Session &) = delete;
  ~Session();

  // Allocates storage and checks that both compiled-in variants match the DBC's leg (or,
  // after use_robot(), that the robot is a box and two such legs with a contact each).
  bool init(std::string *error);

  // The model of a variant (0 revolute, 1 slot); nullptr if out of range. The compiled-in
  // leg, unless use_models() gave others (hil_sim --model FILE).
  static const legsim_model_desc *variant_model(int variant);
  // Before init(): the models RESET builds from; they must outlive every session.
  static void use_models(const legsim_model_desc *revolute, const legsim_model_desc *slot);
  // Before init(): run the two-leg robot (its one variant, Ctrl_Variant 0) instead.
  static void use_robot(const legsim_model_desc *robot);
  // Legs on the bus: 1 (the leg), 2 (the robot).
  static int legs();
  // The robot's box load: the model's force elements box.load (a point force) and
  // box.moment (a torque), the last two, set by leg 0's LOAD_CMD index kBoxLoadIndex and
  // kBoxLoadIndex + 1; -1 when the model has none.
  static int box_force(const legsim_model_desc *m);
  // Force elements per leg (LOAD_CMD of leg k, index i -> force k * per_leg + i).
  static int forces_per_leg(const legsim_model_desc *m) {
    return (m->n_forces - (box_force(m) >= 0 ? 2 : 0)) / legs();
  }

  legsim_status reset(const ResetParams &params);
  bool active() const { return sim_ != nullptr; }
  const legsim_model_desc *model() const { return legsim_model(sim_); }
  const ResetParams &params() const { return params_; }

  legsim_status step(int32_t n);
  // The contact modes checked now (legsim_contacts_check): a model without contacts has none.
  legsim_status contacts_check();
  // Mode kKeep is a no-op. Values were checked against the model by the protocol.
  legsim_status command(int actuator, ActMode mode, double value);
  legsim_status set_load(int force, const double value[2]);  // the model's force index
  // The safe state on leg's actuators (leg k: actuators 2k, 2k + 1), or on every actuator
  // with leg = -1.
  legsim_status apply_safe_state(SafeMode mode, int leg = -1);

  legsim_status sample(Sample *out) const;
  legsim_status clear_events();
  double time() const { return legsim_time(sim_); }
  uint64_t step_count() const { return legsim_step_count(sim_); }
  // Events raised since the last clear (without clearing).
  uint32_t events() const;

 private:
  legsim_status build(void *storage, const ResetParams &params, legsim_sim **out);

  void *storage_[2] = {nullptr, nullptr};
  size_t storage_bytes_ = 0;
  int current_ = 0;  // storage_[current_] holds sim_
  legsim_sim *sim_ = nullptr;
  ResetParams params_;
};

}  // namespace hil

#endif
