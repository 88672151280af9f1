/* legsim as an FMI 3.0 co-simulation FMU: one compiled-in model (the leg, or the two-leg
 * robot: LEGSIM_FMU_ROBOT), stepped through the public C API (legsim/legsim.h) at its own
 * fixed step inside each communication step.
 *
 * Variables (value references; the model's own names, e.g. "upper.length_m"):
 *   0                time (s)
 *   1, 2             parameters step_s (s), integrator (0 RK4, 1 generalized-alpha)
 *   100 + 10 a + i   actuator a: mode (parameter, 0 force, 1 length), length0_m (parameter:
 *                    the lengths the model is assembled at), force_n and length_m (inputs:
 *                    the command of its mode), length_out_m and force_out_n (outputs)
 *   200 + 10 f + i   load f (a point force: value_x_n, value_y_n; a torque: value_nm): inputs
 *   1000 + 10 b + i  body b: x_m, y_m, phi_rad (outputs)
 *   2000 + 10 j + i  joint j's reaction: fx_n, fy_n, moment_nm (outputs; of the last step)
 *   3000 + 10 k + i  foot contact k: normal_n, tangential_n, x_m, y_m (outputs)
 * legsim_fmu_describe (describe.c) writes modelDescription.xml from the same table, so the
 * two cannot disagree.
 *
 * The start (fmi3ExitInitializationMode) is the scene runner's (firmware_core/host,
 * legsim_cli): the model's first pose assembled, then, when any length0_m was set, the
 * actuators at length0_m (else the pose's own lengths, which length0_m's start values are);
 * a robot: both feet on the ground, their midpoint where the pose puts it, both stuck. fmi3DoStep
 * applies the commands and makes round(step / step_s) fixed steps (a communication step
 * must be a whole number of them); each command is re-applied before every step, as the CLI
 * does. A failing legsim call ends the step with fmi3Error and its status in the log. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "legsim/legsim.h"
#include "legsim_fmu.h"

#if LEGSIM_FMU_ROBOT
#include "legsim/robot_models.h"
#define FMU_MODEL legsim_model_robot_revolute
#else
#include "legsim/models.h"
#define FMU_MODEL legsim_model_leg_revolute
#endif

enum { VR_TIME = 0, VR_STEP = 1, VR_INTEGRATOR = 2, VR_ACT = 100, VR_LOAD = 200, VR_BODY = 1000,
       VR_JOINT = 2000, VR_CONTACT = 3000 };

typedef struct fmu {
  fmi3String name;
  fmi3InstanceEnvironment env;
  fmi3LogMessageCallback log;
  int initialized;
  int lengths_set; /* a length0_m was set: assemble at length0_m, else the pose's own lengths */
  double step_s;
  int32_t integrator;
  int32_t mode[LEGSIM_MAX_ACTUATORS];
  double length0[LEGSIM_MAX_ACTUATORS], force_cmd[LEGSIM_MAX_ACTUATORS],
      length_cmd[LEGSIM_MAX_ACTUATORS];
  double load[LEGSIM_MAX_FORCES][2];
  double time;
  legsim_sim *sim;
  void *storage;
} fmu;

const legsim_model_desc *legsim_fmu_model(void) { return &FMU_MODEL; }

/* ---- the variable table --------------------------------------------------------------- */
static int is_load(const legsim_model_desc *m, int f) {
  return m->force[f].kind == LEGSIM_FORCE_POINT || m->force[f].kind == LEGSIM_FORCE_TORQUE;
}

int legsim_fmu_variable(int index, legsim_fmu_var *v) {
  const legsim_model_desc *m = legsim_fmu_model();
  static const char *act[] = {"mode", "length0_m", "force_n", "length_m", "length_out_m",
                              "force_out_n"};
  static const char *body[] = {"x_m", "y_m", "phi_rad"};
  static const char *joint[] = {"fx_n", "fy_n", "moment_nm"};
  static const char *contact[] = {"normal_n", "tangential_n", "x_m", "y_m"};
  memset(v, 0, sizeof *v);
  if (index == 0) { v->vr = VR_TIME; v->kind = LEGSIM_FMU_TIME; snprintf(v->name, sizeof v->name, "time"); return 1; }
  if (index == 1) { v->vr = VR_STEP; v->kind = LEGSIM_FMU_PARAMETER; snprintf(v->name, sizeof v->name, "step_s"); return 1; }
  if (index == 2) { v->vr = VR_INTEGRATOR; v->kind = LEGSIM_FMU_PARAMETER; v->is_int = 1; snprintf(v->name, sizeof v->name, "integrator"); return 1; }
  index -= 3;
  if (index < 6 * m->n_actuators) {
    int a = index / 6, i = index % 6;
    v->vr = VR_ACT + 10 * a + i;
    v->kind = i < 2 ? LEGSIM_FMU_PARAMETER : i < 4 ? LEGSIM_FMU_INPUT : LEGSIM_FMU_OUTPUT;
    v->is_int = i == 0;
    snprintf(v->name, sizeof v->name, "%s.%s", m->actuator[a].name, act[i]);
    return 1;
  }
  index -= 6 * m->n_actuators;
  for (int f = 0; f < m->n_forces; ++f) {
    if (!is_load(m, f)) continue;
    int n = m->force[f].kind == LEGSIM_FORCE_POINT ? 2 : 1;
    if (index < n) {
      v->vr = VR_LOAD + 10 * f + index;
      v->kind = LEGSIM_FMU_INPUT;
      snprintf(v->name, sizeof v->name, "%s.%s", m->force[f].name,
               n == 1 ? "value_nm" : index == 0 ? "value_x_n" : "value_y_n");
      return 1;
    }
    index -= n;
  }
  if (index < 3 * m->n_bodies) {
    v->vr = VR_BODY + 10 * (index / 3) + index % 3;
    v->kind = LEGSIM_FMU_OUTPUT;
    snprintf(v->name, sizeof v->name, "%s.%s", m->body[index / 3].name, body[index % 3]);
    return 1;
  }
  index -= 3 * m->n_bodies;
  if (index < 3 * m->n_joints) {
    v->vr = VR_JOINT + 10 * (index / 3) + index % 3;
    v->kind = LEGSIM_FMU_OUTPUT;
    snprintf(v->name, sizeof v->name, "joint_%s.%s", m->joint[index / 3].name, joint[index % 3]);
    return 1;
  }
  index -= 3 * m->n_joints;
  if (index < 4 * m->n_contacts) {
    v->vr = VR_CONTACT + 10 * (index / 4) + index % 4;
    v->kind = LEGSIM_FMU_OUTPUT;
    snprintf(v->name, sizeof v->name, "%s.%s", m->contact[index / 4].name, contact[index % 4]);
    return 1;
  }
  return 0;
}

/* ---- logging ---------------------------------------------------------------------------- */
static void logf_(fmu *c, fmi3Status st, const char *fmt, ...) {
  char msg[512];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  if (c && c->log) c->log(c->env, st, st == fmi3OK ? "info" : "error", msg);
}

static fmi3Status fail(fmu *c, const char *what, legsim_status st) {
  logf_(c, fmi3Error, "%s: %s", what, legsim_status_str(st));
  return fmi3Error;
}

/* ---- life cycle ---------------------------------------------------------------------------- */
static void defaults(fmu *c) {
  const legsim_model_desc *m = legsim_fmu_model();
  legsim_options o = legsim_default_options();
  c->step_s = o.step_s;
  c->integrator = (int32_t)o.integrator;
  c->time = 0;
  c->initialized = 0;
  c->lengths_set = 0;
  double len[LEGSIM_MAX_ACTUATORS];
  legsim_fmu_stand_lengths(len);
  for (int a = 0; a < m->n_actuators; ++a) {
    c->mode[a] = LEGSIM_ACTUATOR_FORCE;
    c->length0[a] = c->length_cmd[a] = len[a];
    c->force_cmd[a] = 0;
  }
  for (int f = 0; f < m->n_forces; ++f) {
    c->load[f][0] = m->force[f].value[0];
    c->load[f][1] = m->force[f].value[1];
  }
}

/* The lengths of the model's first pose (a robot's: standing on the ground). Uses a
 * temporary sim; NaN when the pose does not assemble. */
int legsim_fmu_stand_lengths(double *len) {
  const legsim_model_desc *m = legsim_fmu_model();
  void *mem = aligned_alloc(LEGSIM_STORAGE_ALIGN, (legsim_sim_size() + LEGSIM_STORAGE_ALIGN - 1) /
                                                      LEGSIM_STORAGE_ALIGN * LEGSIM_STORAGE_ALIGN);
  legsim_sim *sim = NULL;
  legsim_options o = legsim_default_options();
  legsim_real l[LEGSIM_MAX_ACTUATORS];
  legsim_status st = mem ? legsim_init(mem, legsim_sim_size(), m, &o, &sim) : LEGSIM_ERR_STORAGE;
  if (st == LEGSIM_OK) st = legsim_assemble_pose(sim, 0);
  if (st == LEGSIM_OK && m->n_contacts > 0) st = legsim_assemble_on_ground(sim, NULL, 0);
  if (st == LEGSIM_OK) st = legsim_actuator_lengths(sim, l, NULL);
  for (int a = 0; a < m->n_actuators; ++a) len[a] = st == LEGSIM_OK ? (double)l[a] : NAN;
  free(mem);
  return st == LEGSIM_OK;
}

static fmi3Status start(fmu *c) {
  const legsim_model_desc *m = legsim_fmu_model();
  legsim_options o = legsim_default_options();
  o.step_s = c->step_s;
  o.integrator = (legsim_integrator)c->integrator;
  legsim_status st = legsim_init(c->storage, legsim_sim_size(), m, &o, &c->sim);
  if (st != LEGSIM_OK) return fail(c, "legsim_init (step_s, integrator)", st);
  for (int f = 0; f < m->n_forces; ++f) {
    if (!is_load(m, f)) continue;
    legsim_real v[2] = {(legsim_real)c->load[f][0], (legsim_real)c->load[f][1]};
    if ((st = legsim_set_force(c->sim, f, v)) != LEGSIM_OK) return fail(c, "legsim_set_force", st);
  }
  if ((st = legsim_assemble_pose(c->sim, 0)) != LEGSIM_OK) return fail(c, "legsim_assemble_pose", st);
  legsim_real len[LEGSIM_MAX_ACTUATORS];
  for (int a = 0; a < m->n_actuators; ++a) len[a] = (legsim_real)c->length0[a];
  if (m->n_contacts > 0) {
    /* the feet's midpoint along the ground line, where the pose put them (as legsim_cli) */
    legsim_contact k[LEGSIM_CONTACT_SLOTS];
    if ((st = legsim_contacts(c->sim, k)) != LEGSIM_OK) return fail(c, "legsim_contacts", st);
    const legsim_ground_desc *g = &m->ground;
    double mid = 0;
    for (int i = 0; i < m->n_contacts; ++i)
      mid += ((k[i].position[0] - g->point[0]) * cos(g->slope_rad) +
              (k[i].position[1] - g->point[1]) * sin(g->slope_rad)) / m->n_contacts;
    st = legsim_assemble_on_ground(c->sim, c->lengths_set ? len : NULL, (legsim_real)mid);
    if (st != LEGSIM_OK) return fail(c, "legsim_assemble_on_ground (length0_m)", st);
  } else if (c->lengths_set && (st = legsim_assemble(c->sim, len)) != LEGSIM_OK) {
    return fail(c, "legsim_assemble (length0_m)", st);
  }
  c->time = legsim_time(c->sim);
  return fmi3OK;
}

static legsim_status apply_commands(fmu *c) {
  const legsim_model_desc *m = legsim_fmu_model();
  legsim_status st = LEGSIM_OK;
  for (int a = 0; a < m->n_actuators && st == LEGSIM_OK; ++a)
    st = c->mode[a] == LEGSIM_ACTUATOR_LENGTH
             ? legsim_command_length(c->sim, a, (legsim_real)c->length_cmd[a])
             : legsim_command_force(c->sim, a, (legsim_real)c->force_cmd[a]);
  for (int f = 0; f < m->n_forces && st == LEGSIM_OK; ++f) {
    if (!is_load(m, f)) continue;
    legsim_real v[2] = {(legsim_real)c->load[f][0], (legsim_real)c->load[f][1]};
    st = legsim_set_force(c->sim, f, v);
  }
  return st;
}

/* ---- values ------------------------------------------------------------------------------ */
static int get_real(fmu *c, fmi3ValueReference ref, double *out) {
  const int vr = ref > 100000u ? -1 : (int)ref;
  const legsim_model_desc *m = legsim_fmu_model();
  if (vr == VR_TIME) { *out = c->time; return 1; }
  if (vr == VR_STEP) { *out = c->step_s; return 1; }
  if (vr >= VR_ACT && vr < VR_ACT + 10 * m->n_actuators) {
    int a = (vr - VR_ACT) / 10, i = (vr - VR_ACT) % 10;
    if (i == 1) { *out = c->length0[a]; return 1; }
    if (i == 2) { *out = c->force_cmd[a]; return 1; }
    if (i == 3) { *out = c->length_cmd[a]; return 1; }
    if ((i == 4 || i == 5) && c->sim) {
      legsim_real l[LEGSIM_MAX_ACTUATORS], f[LEGSIM_MAX_ACTUATORS];
      if (i == 4 && legsim_actuator_lengths(c->sim, l, NULL) == LEGSIM_OK) { *out = l[a]; return 1; }
      if (i == 5 && legsim_actuator_forces(c->sim, f) == LEGSIM_OK) { *out = f[a]; return 1; }
    }
    return 0;
  }
  if (vr >= VR_LOAD && vr < VR_LOAD + 10 * m->n_forces) {
    int f = (vr - VR_LOAD) / 10, i = (vr - VR_LOAD) % 10;
    if (!is_load(m, f) || i > 1) return 0;
    *out = c->load[f][i];
    return 1;
  }
  if (!c->sim) return 0;
  if (vr >= VR_BODY && vr < VR_BODY + 10 * m->n_bodies) {
    legsim_real q[3 * LEGSIM_MAX_BODIES];
    int b = (vr - VR_BODY) / 10, i = (vr - VR_BODY) % 10;
    if (i > 2 || legsim_get_q(c->sim, q) != LEGSIM_OK) return 0;
    *out = q[3 * b + i];
    return 1;
  }
  if (vr >= VR_JOINT && vr < VR_JOINT + 10 * m->n_joints) {
    legsim_reaction r[LEGSIM_MAX_JOINTS];
    int j = (vr - VR_JOINT) / 10, i = (vr - VR_JOINT) % 10;
    if (i > 2) return 0;
    if (legsim_reactions(c->sim, r) != LEGSIM_OK) { *out = NAN; return 1; } /* none solved yet */
    *out = i < 2 ? r[j].force_n[i] : r[j].moment_nm;
    return 1;
  }
  if (vr >= VR_CONTACT && vr < VR_CONTACT + 10 * m->n_contacts) {
    legsim_contact k[LEGSIM_CONTACT_SLOTS];
    int n = (vr - VR_CONTACT) / 10, i = (vr - VR_CONTACT) % 10;
    if (i > 3 || legsim_contacts(c->sim, k) != LEGSIM_OK) return 0;
    *out = i == 0 ? k[n].normal_n : i == 1 ? k[n].tangential_n : k[n].position[i - 2];
    return 1;
  }
  return 0;
}

static int set_real(fmu *c, fmi3ValueReference ref, double v) {
  const int vr = ref > 100000u ? -1 : (int)ref;
  const legsim_model_desc *m = legsim_fmu_model();
  if (!isfinite(v)) return 0;
  if (vr == VR_STEP && !c->initialized) { c->step_s = v; return 1; }
  if (vr >= VR_ACT && vr < VR_ACT + 10 * m->n_actuators) {
    int a = (vr - VR_ACT) / 10, i = (vr - VR_ACT) % 10;
    if (i == 1 && !c->initialized) {
      c->length0[a] = v;
      c->lengths_set = 1;
      return 1;
    }
    if (i == 2) { c->force_cmd[a] = v; return 1; }
    if (i == 3) { c->length_cmd[a] = v; return 1; }
    return 0;
  }
  if (vr >= VR_LOAD && vr < VR_LOAD + 10 * m->n_forces) {
    int f = (vr - VR_LOAD) / 10, i = (vr - VR_LOAD) % 10;
    if (!is_load(m, f) || i > (m->force[f].kind == LEGSIM_FORCE_POINT ? 1 : 0)) return 0;
    c->load[f][i] = v;
    return 1;
  }
  return 0;
}

static int get_int(fmu *c, fmi3ValueReference ref, int32_t *out) {
  const int vr = ref > 100000u ? -1 : (int)ref;
  const legsim_model_desc *m = legsim_fmu_model();
  if (vr == VR_INTEGRATOR) { *out = c->integrator; return 1; }
  if (vr >= VR_ACT && vr < VR_ACT + 10 * m->n_actuators && (vr - VR_ACT) % 10 == 0) {
    *out = c->mode[(vr - VR_ACT) / 10];
    return 1;
  }
  return 0;
}

static int set_int(fmu *c, fmi3ValueReference ref, int32_t v) {
  const int vr = ref > 100000u ? -1 : (int)ref;
  const legsim_model_desc *m = legsim_fmu_model();
  if (c->initialized) return 0;
  if (vr == VR_INTEGRATOR && (v == 0 || v == 1)) { c->integrator = v; return 1; }
  if (vr >= VR_ACT && vr < VR_ACT + 10 * m->n_actuators && (vr - VR_ACT) % 10 == 0 &&
      (v == LEGSIM_ACTUATOR_FORCE || v == LEGSIM_ACTUATOR_LENGTH)) {
    c->mode[(vr - VR_ACT) / 10] = v;
    return 1;
  }
  return 0;
}

/* ---- the FMI 3.0 functions --------------------------------------------------------------- */
const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance i, fmi3Boolean on, size_t n, const fmi3String c[]) {
  (void)i; (void)on; (void)n; (void)c;
  return fmi3OK;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String name, fmi3String token, fmi3String resources,
                                         fmi3Boolean visible, fmi3Boolean logging,
                                         fmi3Boolean event_mode, fmi3Boolean early_return,
                                         const fmi3ValueReference req[], size_t n_req,
                                         fmi3InstanceEnvironment env, fmi3LogMessageCallback log,
                                         fmi3IntermediateUpdateCallback update) {
  (void)resources; (void)visible; (void)logging; (void)early_return; (void)req; (void)n_req;
  (void)update;
  if (!token || strcmp(token, LEGSIM_FMU_TOKEN) != 0) {
    if (log) log(env, fmi3Error, "error", "instantiationToken does not match this FMU's");
    return NULL;
  }
  if (event_mode) {
    if (log) log(env, fmi3Error, "error", "event mode is not supported");
    return NULL;
  }
  fmu *c = calloc(1, sizeof *c);
  if (!c) return NULL;
  size_t size = (legsim_sim_size() + LEGSIM_STORAGE_ALIGN - 1) / LEGSIM_STORAGE_ALIGN *
                LEGSIM_STORAGE_ALIGN;
  c->storage = aligned_alloc(LEGSIM_STORAGE_ALIGN, size);
  if (!c->storage) { free(c); return NULL; }
  c->name = name;
  c->env = env;
  c->log = log;
  defaults(c);
  return c;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String a, fmi3String b, fmi3String c, fmi3Boolean d,
                                          fmi3Boolean e, fmi3InstanceEnvironment f,
                                          fmi3LogMessageCallback g) {
  (void)a; (void)b; (void)c; (void)d; (void)e; (void)f; (void)g;
  return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String a, fmi3String b, fmi3String c,
                                               fmi3Boolean d, fmi3Boolean e,
                                               fmi3InstanceEnvironment f, fmi3LogMessageCallback g,
                                               fmi3ClockUpdateCallback h,
                                               fmi3LockPreemptionCallback k,
                                               fmi3UnlockPreemptionCallback l) {
  (void)a; (void)b; (void)c; (void)d; (void)e; (void)f; (void)g; (void)h; (void)k; (void)l;
  return NULL;
}

void fmi3FreeInstance(fmi3Instance i) {
  fmu *c = i;
  if (!c) return;
  free(c->storage);
  free(c);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance i, fmi3Boolean tol_defined, fmi3Float64 tol,
                                       fmi3Float64 start_time, fmi3Boolean stop_defined,
                                       fmi3Float64 stop_time) {
  (void)tol_defined; (void)tol; (void)stop_defined; (void)stop_time;
  fmu *c = i;
  if (start_time != 0) {
    logf_(c, fmi3Error, "startTime must be 0 (got %g)", start_time);
    return fmi3Error;
  }
  return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance i) {
  fmu *c = i;
  fmi3Status st = start(c);
  if (st == fmi3OK) c->initialized = 1;
  return st;
}

fmi3Status fmi3EnterEventMode(fmi3Instance i) { (void)i; return fmi3Error; }
fmi3Status fmi3Terminate(fmi3Instance i) { (void)i; return fmi3OK; }

fmi3Status fmi3Reset(fmi3Instance i) {
  fmu *c = i;
  c->sim = NULL;
  defaults(c);
  return fmi3OK;
}

fmi3Status fmi3DoStep(fmi3Instance i, fmi3Float64 t, fmi3Float64 h, fmi3Boolean no_prior,
                      fmi3Boolean *event_needed, fmi3Boolean *terminate, fmi3Boolean *early,
                      fmi3Float64 *last_t) {
  (void)no_prior;
  fmu *c = i;
  *event_needed = fmi3False;
  *terminate = fmi3False;
  *early = fmi3False;
  *last_t = c->time;
  if (!c->sim) return fmi3Error;
  double n_real = h / c->step_s;
  long n = lround(n_real);
  if (n < 1 || fabs(n_real - (double)n) > 1e-9 * (double)n) {
    logf_(c, fmi3Error, "communication step %g s is not a whole number of steps of %g s", h,
          c->step_s);
    return fmi3Error;
  }
  if (fabs(t - c->time) > 1e-9 * c->step_s) {
    logf_(c, fmi3Error, "currentCommunicationPoint %.17g s is not the FMU's time %.17g s", t,
          c->time);
    return fmi3Error;
  }
  for (long k = 0; k < n; ++k) {
    legsim_status st = apply_commands(c);
    if (st != LEGSIM_OK) return fail(c, "a command (force_n, length_m or a load)", st);
    if ((st = legsim_step(c->sim, 1)) != LEGSIM_OK) {
      c->time = legsim_time(c->sim);
      *last_t = c->time;
      return fail(c, "legsim_step", st);
    }
  }
  c->time = legsim_time(c->sim);
  *last_t = c->time;
  return fmi3OK;
}

#define GETSET_REAL(T, NAME, SETNAME)                                                             \
  fmi3Status NAME(fmi3Instance i, const fmi3ValueReference vr[], size_t n, T v[], size_t nv) {   \
    if (nv != n) return fmi3Error;                                                                \
    for (size_t k = 0; k < n; ++k) {                                                              \
      double x;                                                                                   \
      if (!get_real(i, vr[k], &x)) return fmi3Error;                                              \
      v[k] = (T)x;                                                                                \
    }                                                                                             \
    return fmi3OK;                                                                                \
  }
GETSET_REAL(fmi3Float64, fmi3GetFloat64, _)

fmi3Status fmi3SetFloat64(fmi3Instance i, const fmi3ValueReference vr[], size_t n,
                          const fmi3Float64 v[], size_t nv) {
  if (nv != n) return fmi3Error;
  for (size_t k = 0; k < n; ++k)
    if (!set_real(i, vr[k], v[k])) {
      logf_(i, fmi3Error, "value reference %u: cannot be set to %g now", vr[k], v[k]);
      return fmi3Error;
    }
  return fmi3OK;
}

fmi3Status fmi3GetInt32(fmi3Instance i, const fmi3ValueReference vr[], size_t n, fmi3Int32 v[],
                        size_t nv) {
  if (nv != n) return fmi3Error;
  for (size_t k = 0; k < n; ++k)
    if (!get_int(i, vr[k], &v[k])) return fmi3Error;
  return fmi3OK;
}

fmi3Status fmi3SetInt32(fmi3Instance i, const fmi3ValueReference vr[], size_t n,
                        const fmi3Int32 v[], size_t nv) {
  if (nv != n) return fmi3Error;
  for (size_t k = 0; k < n; ++k)
    if (!set_int(i, vr[k], v[k])) {
      logf_(i, fmi3Error, "value reference %u: cannot be set to %d now", vr[k], (int)v[k]);
      return fmi3Error;
    }
  return fmi3OK;
}

/* The types and services this FMU has no variable or capability for. */
#define UNSUPPORTED_GET(T, NAME)                                                                \
  fmi3Status NAME(fmi3Instance i, const fmi3ValueReference vr[], size_t n, T v[], size_t nv) { \
    (void)i; (void)vr; (void)v; (void)nv;                                                      \
    return n == 0 ? fmi3OK : fmi3Error;                                                        \
  }
#define UNSUPPORTED_SET(T, NAME)                                                         \
  fmi3Status NAME(fmi3Instance i, const fmi3ValueReference vr[], size_t n, const T v[], \
                  size_t nv) {                                                          \
    (void)i; (void)vr; (void)v; (void)nv;                                               \
    return n == 0 ? fmi3OK : fmi3Error;                                                 \
  }
UNSUPPORTED_GET(fmi3Float32, fmi3GetFloat32)
UNSUPPORTED_GET(fmi3Int8, fmi3GetInt8)
UNSUPPORTED_GET(fmi3UInt8, fmi3GetUInt8)
UNSUPPORTED_GET(fmi3Int16, fmi3GetInt16)
UNSUPPORTED_GET(fmi3UInt16, fmi3GetUInt16)
UNSUPPORTED_GET(fmi3UInt32, fmi3GetUInt32)
UNSUPPORTED_GET(fmi3Int64, fmi3GetInt64)
UNSUPPORTED_GET(fmi3UInt64, fmi3GetUInt64)
UNSUPPORTED_GET(fmi3Boolean, fmi3GetBoolean)
UNSUPPORTED_GET(fmi3String, fmi3GetString)
UNSUPPORTED_SET(fmi3Float32, fmi3SetFloat32)
UNSUPPORTED_SET(fmi3Int8, fmi3SetInt8)
UNSUPPORTED_SET(fmi3UInt8, fmi3SetUInt8)
UNSUPPORTED_SET(fmi3Int16, fmi3SetInt16)
UNSUPPORTED_SET(fmi3UInt16, fmi3SetUInt16)
UNSUPPORTED_SET(fmi3UInt32, fmi3SetUInt32)
UNSUPPORTED_SET(fmi3Int64, fmi3SetInt64)
UNSUPPORTED_SET(fmi3UInt64, fmi3SetUInt64)
UNSUPPORTED_SET(fmi3Boolean, fmi3SetBoolean)
UNSUPPORTED_SET(fmi3String, fmi3SetString)

fmi3Status fmi3GetBinary(fmi3Instance i, const fmi3ValueReference vr[], size_t n, size_t sizes[],
                         fmi3Binary v[], size_t nv) {
  (void)i; (void)vr; (void)sizes; (void)v; (void)nv;
  return n == 0 ? fmi3OK : fmi3Error;
}
fmi3Status fmi3SetBinary(fmi3Instance i, const fmi3ValueReference vr[], size_t n,
                         const size_t sizes[], const fmi3Binary v[], size_t nv) {
  (void)i; (void)vr; (void)sizes; (void)v; (void)nv;
  return n == 0 ? fmi3OK : fmi3Error;
}
fmi3Status fmi3GetClock(fmi3Instance i, const fmi3ValueReference vr[], size_t n, fmi3Clock v[]) {
  (void)i; (void)vr; (void)v;
  return n == 0 ? fmi3OK : fmi3Error;
}
fmi3Status fmi3SetClock(fmi3Instance i, const fmi3ValueReference vr[], size_t n,
                        const fmi3Clock v[]) {
  (void)i; (void)vr; (void)v;
  return n == 0 ? fmi3OK : fmi3Error;
}
fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance i, fmi3ValueReference vr, size_t *n) {
  (void)i; (void)vr; (void)n;
  return fmi3Error;
}
fmi3Status fmi3GetVariableDependencies(fmi3Instance i, fmi3ValueReference d, size_t e[],
                                       fmi3ValueReference f[], size_t g[],
                                       fmi3DependencyKind h[], size_t n) {
  (void)i; (void)d; (void)e; (void)f; (void)g; (void)h; (void)n;
  return fmi3Error;
}
fmi3Status fmi3GetFMUState(fmi3Instance i, fmi3FMUState *s) { (void)i; (void)s; return fmi3Error; }
fmi3Status fmi3SetFMUState(fmi3Instance i, fmi3FMUState s) { (void)i; (void)s; return fmi3Error; }
fmi3Status fmi3FreeFMUState(fmi3Instance i, fmi3FMUState *s) { (void)i; (void)s; return fmi3Error; }
fmi3Status fmi3SerializedFMUStateSize(fmi3Instance i, fmi3FMUState s, size_t *n) {
  (void)i; (void)s; (void)n;
  return fmi3Error;
}
fmi3Status fmi3SerializeFMUState(fmi3Instance i, fmi3FMUState s, fmi3Byte b[], size_t n) {
  (void)i; (void)s; (void)b; (void)n;
  return fmi3Error;
}
fmi3Status fmi3DeserializeFMUState(fmi3Instance i, const fmi3Byte b[], size_t n, fmi3FMUState *s) {
  (void)i; (void)b; (void)n; (void)s;
  return fmi3Error;
}
fmi3Status fmi3GetDirectionalDerivative(fmi3Instance i, const fmi3ValueReference a[], size_t b,
                                        const fmi3ValueReference c[], size_t d,
                                        const fmi3Float64 e[], size_t f, fmi3Float64 g[],
                                        size_t h) {
  (void)i; (void)a; (void)b; (void)c; (void)d; (void)e; (void)f; (void)g; (void)h;
  return fmi3Error;
}
fmi3Status fmi3GetAdjointDerivative(fmi3Instance i, const fmi3ValueReference a[], size_t b,
                                    const fmi3ValueReference c[], size_t d, const fmi3Float64 e[],
                                    size_t f, fmi3Float64 g[], size_t h) {
  (void)i; (void)a; (void)b; (void)c; (void)d; (void)e; (void)f; (void)g; (void)h;
  return fmi3Error;
}
fmi3Status fmi3EnterConfigurationMode(fmi3Instance i) { (void)i; return fmi3Error; }
fmi3Status fmi3ExitConfigurationMode(fmi3Instance i) { (void)i; return fmi3Error; }
fmi3Status fmi3GetIntervalDecimal(fmi3Instance i, const fmi3ValueReference a[], size_t b,
                                  fmi3Float64 c[], fmi3IntervalQualifier d[]) {
  (void)i; (void)a; (void)b; (void)c; (void)d;
  return fmi3Error;
}
fmi3Status fmi3GetIntervalFraction(fmi3Instance i, const fmi3ValueReference a[], size_t b,
                                   fmi3UInt64 c[], fmi3UInt64 d[], fmi3IntervalQualifier e[]) {
  (void)i; (void)a; (void)b; (void)c; (void)d; (void)e;
  return fmi3Error;
}
fmi3Status fmi3GetShiftDecimal(fmi3Instance i, const fmi3ValueReference a[], size_t b,
                               fmi3Float64 c[]) {
  (void)i; (void)a; (void)b; (void)c;
  return fmi3Error;
}
fmi3Status fmi3GetShiftFraction(fmi3Instance i, const fmi3ValueReference a[], size_t b,
                                fmi3UInt64 c[], fmi3UInt64 d[]) {
  (void)i; (void)a; (void)b; (void)c; (void)d;
  return fmi3Error;
}
fmi3Status fmi3SetIntervalDecimal(fmi3Instance i, const fmi3ValueReference a[], size_t b,
                                  const fmi3Float64 c[]) {
  (void)i; (void)a; (void)b; (void)c;
  return fmi3Error;
}
fmi3Status fmi3SetIntervalFraction(fmi3Instance i, const fmi3ValueReference a[], size_t b,
                                   const fmi3UInt64 c[], const fmi3UInt64 d[]) {
  (void)i; (void)a; (void)b; (void)c; (void)d;
  return fmi3Error;
}
fmi3Status fmi3SetShiftDecimal(fmi3Instance i, const fmi3ValueReference a[], size_t b,
                               const fmi3Float64 c[]) {
  (void)i; (void)a; (void)b; (void)c;
  return fmi3Error;
}
fmi3Status fmi3SetShiftFraction(fmi3Instance i, const fmi3ValueReference a[], size_t b,
                                const fmi3UInt64 c[], const fmi3UInt64 d[]) {
  (void)i; (void)a; (void)b; (void)c; (void)d;
  return fmi3Error;
}
fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance i) { (void)i; return fmi3Error; }
fmi3Status fmi3UpdateDiscreteStates(fmi3Instance i, fmi3Boolean *a, fmi3Boolean *b, fmi3Boolean *c,
                                    fmi3Boolean *d, fmi3Boolean *e, fmi3Float64 *f) {
  (void)i; (void)a; (void)b; (void)c; (void)d; (void)e; (void)f;
  return fmi3Error;
}
fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance i) { (void)i; return fmi3Error; }
fmi3Status fmi3CompletedIntegratorStep(fmi3Instance i, fmi3Boolean a, fmi3Boolean *b,
                                       fmi3Boolean *c) {
  (void)i; (void)a; (void)b; (void)c;
  return fmi3Error;
}
fmi3Status fmi3SetTime(fmi3Instance i, fmi3Float64 t) { (void)i; (void)t; return fmi3Error; }
fmi3Status fmi3SetContinuousStates(fmi3Instance i, const fmi3Float64 x[], size_t n) {
  (void)i; (void)x; (void)n;
  return fmi3Error;
}
fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance i, fmi3Float64 x[], size_t n) {
  (void)i; (void)x; (void)n;
  return fmi3Error;
}
fmi3Status fmi3GetEventIndicators(fmi3Instance i, fmi3Float64 x[], size_t n) {
  (void)i; (void)x; (void)n;
  return fmi3Error;
}
fmi3Status fmi3GetContinuousStates(fmi3Instance i, fmi3Float64 x[], size_t n) {
  (void)i; (void)x; (void)n;
  return fmi3Error;
}
fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance i, fmi3Float64 x[], size_t n) {
  (void)i; (void)x; (void)n;
  return fmi3Error;
}
fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance i, size_t *n) { (void)i; (void)n; return fmi3Error; }
fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance i, size_t *n) { (void)i; (void)n; return fmi3Error; }
fmi3Status fmi3EnterStepMode(fmi3Instance i) { (void)i; return fmi3Error; }
fmi3Status fmi3GetOutputDerivatives(fmi3Instance i, const fmi3ValueReference a[], size_t b,
                                    const fmi3Int32 c[], fmi3Float64 d[], size_t e) {
  (void)i; (void)a; (void)b; (void)c; (void)d; (void)e;
  return fmi3Error;
}
fmi3Status fmi3ActivateModelPartition(fmi3Instance i, fmi3ValueReference a, fmi3Float64 b) {
  (void)i; (void)a; (void)b;
  return fmi3Error;
}
