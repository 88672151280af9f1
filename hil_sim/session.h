// The leg on the solver: the only file that calls the legsim C API.
//
// A session is one RESET: a compiled model (revolute or slot D variant), its options and
// state. RESET builds the new session in spare storage and swaps only on success, so a
// failed RESET leaves the running session as it was. Storage is allocated once at start.
#ifndef HIL_SIM_SESSION_H
#define HIL_SIM_SESSION_H

#include <cstdint>
#include <string>

#include "legsim/legsim.h"

namespace hil {

// The leg as can/legsim.dbc lays it out.
constexpr int kBodies = 6;
constexpr int kCoords = 3 * kBodies;
constexpr int kJoints = 8;
constexpr int kActuators = 2;

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
  double lengths[kActuators] = {0, 0};
};

struct Sample {
  legsim_real q[kCoords];
  legsim_real qd[kCoords];
  legsim_real length[kActuators], rate[kActuators], force[kActuators];
  legsim_reaction reaction[kJoints];
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

  // Allocates storage and checks that both compiled-in variants match the DBC's leg.
  bool init(std::string *error);

  // The model of a variant (0 revolute, 1 slot); nullptr if out of range. The compiled-in
  // leg, unless use_models() gave others (hil_sim --model FILE).
  static const legsim_model_desc *variant_model(int variant);
  // Before init(): the models RESET builds from; they must outlive every session.
  static void use_models(const legsim_model_desc *revolute, const legsim_model_desc *slot);

  legsim_status reset(const ResetParams &params);
  bool active() const { return sim_ != nullptr; }
  const legsim_model_desc *model() const { return legsim_model(sim_); }
  const ResetParams &params() const { return params_; }

  legsim_status step(int32_t n);
  // Mode kKeep is a no-op. Values were checked against the model by the protocol.
  legsim_status command(int actuator, ActMode mode, double value);
  legsim_status set_load(int force, const double value[2]);
  legsim_status apply_safe_state(SafeMode mode);

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
