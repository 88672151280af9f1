/* The leg report (see leg_report.h): the leg's hooks of the shared report (report.c). */
#include "leg_report.h"

#include <math.h>

#include "legsim/models.h"
#include "out.h"
#if defined(LEGSIM_MCU_BOARD)
#include "mcu_trig.h"
#endif

/* world position of a body-fixed point (xi, eta): r + xi*u + eta*n, with
 * u = (sin phi, -cos phi), n = (cos phi, sin phi) (models/leg.toml) */
static void body_point(const legsim_real *q, int32_t body, const double *p, double *xy) {
  /* in the build's precision (no double arithmetic or sin/cos on the M4F just for
   * printing); an image takes the core's float sin and cos (mcu_trig.h: no libm
   * trigonometry linked) */
#if LEGSIM_USE_FLOAT
  const float x = q[3 * body], y = q[3 * body + 1], px = (float)p[0], py = (float)p[1];
  float s, c;
#if defined(LEGSIM_MCU_BOARD)
  mcu_sincosf(q[3 * body + 2], &s, &c);
#else
  s = sinf(q[3 * body + 2]);
  c = cosf(q[3 * body + 2]);
#endif
  xy[0] = (double)(x + px * s + py * c);
  xy[1] = (double)(y - px * c + py * s);
#else
  const double x = q[3 * body], y = q[3 * body + 1];
  const double s = sin(q[3 * body + 2]), c = cos(q[3 * body + 2]);
  xy[0] = x + p[0] * s + p[1] * c;
  xy[1] = y - p[0] * c + p[1] * s;
#endif
}

static void print_foot(const char *prefix, const legsim_sim *sim) {
  legsim_real foot[2];
  if (legsim_foot_position(sim, foot) != LEGSIM_OK) return;
  out_str(prefix);
  out_str(" foot ");
  report_real((double)foot[0]);
  out_char(' ');
  report_real((double)foot[1]);
  out_char('\n');
}

static void print_joints(const legsim_sim *sim) {
  const legsim_model_desc *m = legsim_model(sim);
  legsim_real q[3 * LEGSIM_MAX_BODIES];
  if (!m || legsim_get_q(sim, q) != LEGSIM_OK) return;
  for (int32_t j = 0; j < m->n_joints; ++j) {
    const legsim_joint_desc *jd = &m->joint[j];
    if (jd->kind == LEGSIM_JOINT_PRISMATIC) continue;
    double xy[2];
    body_point(q, jd->body[0], jd->point[0], xy);
    out_str("stand joint ");
    out_str(jd->name);
    out_char(' ');
    report_real(xy[0]);
    out_char(' ');
    report_real(xy[1]);
    out_char('\n');
  }
}

static legsim_status stand(legsim_sim *sim) { return legsim_assemble_pose(sim, 0); }

/* from the stand pose, at rest, at t = 0 (free fall: no commands) */
static int start(legsim_sim *sim) {
  legsim_real q[3 * LEGSIM_MAX_BODIES];
  if (report_failed("legsim_assemble_pose", legsim_assemble_pose(sim, 0))) return 1;
  if (report_failed("legsim_get_q", legsim_get_q(sim, q))) return 1;
  if (report_failed("legsim_set_state", legsim_set_state(sim, q, 0, 0.0))) return 1;
  return 0;
}

const report_model leg_report = {
    &legsim_model_leg_revolute, LEG_REPORT_STEPS, 0, stand, "legsim_assemble_pose",
    start, print_foot, print_joints};
