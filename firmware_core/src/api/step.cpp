// The C API, stepping and commands: legsim_step (the step's stages: system/step.cpp) and the
// actuator commands and loads that force the next steps.
#include <cmath>

#include "api/internal.hpp"

using namespace legsim;
using namespace legsim::api;

extern "C" {

legsim_status legsim_step(legsim_sim *sim, int32_t n_steps) {
  CHECK_SIM(sim);
  if (n_steps < 0) return LEGSIM_ERR_BAD_INPUT;
  Sim &s = *as_sim(sim);
  if (!s.data.assembled || !state_finite(s.data.q, s.data.qd, s.model.nq)) return LEGSIM_ERR_STATE;
  return steps_run(s.model, s.data, n_steps);  // system/step.cpp: the step's stages
}

legsim_status legsim_contacts_check(legsim_sim *sim) {
  CHECK_SIM(sim);
  Sim &s = *as_sim(sim);
  if (!s.data.assembled || !state_finite(s.data.q, s.data.qd, s.model.nq)) return LEGSIM_ERR_STATE;
  return contact_modes_check(s.model, s.data);  // system/step.cpp: the step's first stage
}

legsim_status legsim_command_force(legsim_sim *sim, int32_t actuator, legsim_real force_n) {
  CHECK_SIM(sim);
  Sim &s = *as_sim(sim);
  if (actuator < 0 || actuator >= s.model.na) return LEGSIM_ERR_BAD_INPUT;
  if (!(std::abs(force_n) <= s.model.act[actuator].fmax)) return LEGSIM_ERR_BAD_INPUT;  // NaN too
  ActuatorState &a = s.data.act[actuator];
  if (a.mode != LEGSIM_ACTUATOR_FORCE || a.setpoint != force_n) commands_changed(s.data);
  a.mode = LEGSIM_ACTUATOR_FORCE;
  a.setpoint = force_n;
  a.force = force_n;
  return LEGSIM_OK;
}

legsim_status legsim_command_length(legsim_sim *sim, int32_t actuator, legsim_real length_m) {
  CHECK_SIM(sim);
  Sim &s = *as_sim(sim);
  if (actuator < 0 || actuator >= s.model.na || !std::isfinite(length_m)) return LEGSIM_ERR_BAD_INPUT;
  const Actuator &ac = s.model.act[actuator];
  if (length_m < ac.lmin || length_m > ac.lmax) return LEGSIM_ERR_OUT_OF_STROKE;
  ActuatorState &a = s.data.act[actuator];
  if (a.mode != LEGSIM_ACTUATOR_LENGTH || a.setpoint != length_m) commands_changed(s.data);
  a.mode = LEGSIM_ACTUATOR_LENGTH;
  a.setpoint = length_m;
  return LEGSIM_OK;
}

legsim_status legsim_set_force(legsim_sim *sim, int32_t force, const legsim_real *value) {
  CHECK_SIM(sim);
  if (!value) return LEGSIM_ERR_NULL;
  Sim &s = *as_sim(sim);
  if (force < 0 || force >= s.model.nf) return LEGSIM_ERR_BAD_INPUT;
  if (!LEGSIM_WITH_FORCE_ELEMENTS) return LEGSIM_ERR_DISABLED;
  // a spring-damper's law is model data; point forces and torques take values
  if (s.model.force[force].kind == LEGSIM_FORCE_SPRING_DAMPER) return LEGSIM_ERR_BAD_INPUT;
  const int nv = s.model.force[force].kind == LEGSIM_FORCE_POINT ? 2 : 1;
  if (!bounded_array(value, nv, LEGSIM_MAX_FORCE_N)) return LEGSIM_ERR_BAD_INPUT;
  for (int i = 0; i < nv; ++i) {
    if (s.data.force_value[force][i] != value[i]) commands_changed(s.data);
    s.data.force_value[force][i] = value[i];
  }
  force_active_update(s.model, s.data);
  return LEGSIM_OK;
}

}  // extern "C"
