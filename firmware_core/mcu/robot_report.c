/* The robot report (see robot_report.h): the robot's hooks of the shared report (report.c). */
#include "robot_report.h"

#include "legsim/robot_models.h"
#include "out.h"

/* models/robot.toml: actuator 0 is right.upper (the Fig. 7 push), 1..3 held */
#define PUSH_N 185.55

static void print_contacts(const char *prefix, const legsim_sim *sim) {
  legsim_contact k[LEGSIM_CONTACT_SLOTS];
  const int32_t nc = legsim_n_contacts(sim);
  if (legsim_contacts(sim, k) != LEGSIM_OK) return;
  const legsim_model_desc *m = legsim_model(sim);
  for (int32_t c = 0; c < nc; ++c) {
    out_str(prefix);
    out_str(" contact ");
    out_str(m->contact[c].name);
    out_char(' ');
    out_int(k[c].state);
    out_char(' ');
    report_real((double)k[c].normal_n);
    out_char(' ');
    report_real((double)k[c].tangential_n);
    out_char(' ');
    report_real((double)k[c].position[0]);
    out_char(' ');
    report_real((double)k[c].position[1]);
    out_char('\n');
  }
}

/* the stand on the ground, at rest, t = 0 */
static legsim_status stand(legsim_sim *sim) {
  legsim_real q[3 * LEGSIM_MAX_BODIES];
  legsim_status s = legsim_assemble_pose(sim, 0);
  if (s == LEGSIM_OK) s = legsim_get_q(sim, q);
  if (s == LEGSIM_OK) s = legsim_set_state(sim, q, 0, 0.0);
  if (s == LEGSIM_OK) s = legsim_assemble_on_ground(sim, 0, 0);
  return s;
}

/* the stand, then the Fig. 7 Scene A commands */
static int start(legsim_sim *sim) {
  if (report_failed("stand", stand(sim))) return 1;
  legsim_real len[4], rate[4];
  if (report_failed("legsim_actuator_lengths", legsim_actuator_lengths(sim, len, rate))) return 1;
  for (int32_t a = 1; a < 4; ++a)
    if (report_failed("legsim_command_length", legsim_command_length(sim, a, len[a]))) return 1;
  if (report_failed("legsim_command_force", legsim_command_force(sim, 0, PUSH_N))) return 1;
  return 0;
}

const report_model robot_report = {
    &legsim_model_robot_revolute, ROBOT_REPORT_STEPS, 1, stand, "stand",
    start, print_contacts, 0};
