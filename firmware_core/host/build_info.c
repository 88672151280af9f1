/* The build's facts for dynamic bindings (see build_info.h). */
#include "build_info.h"

#include "legsim/hexapod.h"

#define FACT(macro) {#macro, (int64_t)(macro)}
#define SIZE(type) {"sizeof(" #type ")", (int64_t)sizeof(type)}

static const struct {
  const char *name;
  int64_t value;
} facts[] = {
    FACT(LEGSIM_USE_FLOAT),
    FACT(LEGSIM_NAME_LEN),
    FACT(LEGSIM_MAX_BODIES),
    FACT(LEGSIM_MAX_JOINTS),
    FACT(LEGSIM_MAX_ACTUATORS),
    FACT(LEGSIM_MAX_FORCES),
    FACT(LEGSIM_MAX_POSES),
    FACT(LEGSIM_MAX_POSE_DRIVERS),
    FACT(LEGSIM_MAX_CONTACTS),
    FACT(LEGSIM_MAX_ROWS),
    FACT(LEGSIM_FACTOR_ENTRIES),
    FACT(LEGSIM_WITH_RK4),
    FACT(LEGSIM_WITH_GENERALIZED_ALPHA),
    FACT(LEGSIM_WITH_STATICS),
    FACT(LEGSIM_WITH_INVERSE_DYNAMICS),
    FACT(LEGSIM_WITH_FORCE_ELEMENTS),
    FACT(LEGSIM_STORAGE_ALIGN),
    SIZE(legsim_real),
    SIZE(legsim_model_desc),
    SIZE(legsim_options),
    SIZE(legsim_report),
    SIZE(legsim_reaction),
    SIZE(legsim_worst_case),
    SIZE(legsim_contact),
    SIZE(legsim_hexapod_desc),
    SIZE(legsim_hexapod_pose),
    SIZE(legsim_hexapod_standing),
    SIZE(legsim_hexapod_commands),
    SIZE(legsim_hexapod_inverse),
    SIZE(legsim_hexapod_sweep),
    SIZE(legsim_hexapod_sweep_point),
    SIZE(legsim_hexapod_gait),
    SIZE(legsim_hexapod_setpoint),
    SIZE(legsim_hexapod_state),
};

#define N_FACTS ((int32_t)(sizeof facts / sizeof facts[0]))

int32_t legsim_build_info_count(void) { return N_FACTS; }

legsim_status legsim_build_info(int32_t index, const char **name, int64_t *value) {
  if (!name || !value) return LEGSIM_ERR_NULL;
  if (index < 0 || index >= N_FACTS) return LEGSIM_ERR_BAD_INPUT;
  *name = facts[index].name;
  *value = facts[index].value;
  return LEGSIM_OK;
}
