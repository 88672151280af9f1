// Names of the status codes, for logs and error messages.
#include "legsim/legsim.h"

extern "C" const char *legsim_status_str(legsim_status s) {
  switch (s) {
    case LEGSIM_OK: return "ok";
    case LEGSIM_ERR_NULL: return "null pointer argument";
    case LEGSIM_ERR_STORAGE: return "storage too small or misaligned, or not a sim made by legsim_init";
    case LEGSIM_ERR_MODEL: return "invalid model description";
    case LEGSIM_ERR_CAPACITY: return "model exceeds the compile-time capacity";
    case LEGSIM_ERR_BAD_INPUT: return "bad input (NaN/Inf, index or option out of range)";
    case LEGSIM_ERR_OUT_OF_STROKE: return "length outside the actuator stroke";
    case LEGSIM_ERR_NOT_CONVERGED: return "Newton iteration did not converge";
    case LEGSIM_ERR_SINGULAR: return "singular constraint Jacobian (dead centre)";
    case LEGSIM_ERR_UNREACHABLE: return "lengths cannot be reached";
    case LEGSIM_ERR_NO_EQUILIBRIUM: return "no static equilibrium (the locked leg is a mechanism)";
    case LEGSIM_ERR_DISABLED: return "disabled by the scene options or stripped from this build";
    case LEGSIM_ERR_STATE: return "state not valid (not assembled or not finite)";
    case LEGSIM_ERR_DIVERGED: return "diverged: a non-finite or absurd result";
    case LEGSIM_ERR_CONTACT: return "the contact problem has no usable solution";
  }
  return "unknown status";
}
