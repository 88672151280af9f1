/* legsim: fixed-step, allocation-free constraint kinematics and dynamics of a
 * planar multibody leg in absolute coordinates q = (x, y, phi) per body.
 *
 * Plain C API. The solver state lives in storage the caller provides
 * (legsim_sim_size() bytes, aligned to LEGSIM_STORAGE_ALIGN); nothing is
 * allocated, ever. Every function returns a legsim_status; outputs are written
 * only on LEGSIM_OK. SI units throughout (m, kg, s, N, N m, rad).
 *
 * Model (constant data, legsim_model_desc) and simulation (state + workspace,
 * legsim_sim) are separate: every analysis is a function of the sim, which
 * holds its compiled model.
 *
 * Every call is all or nothing: a call that returns an error leaves the sim
 * exactly as it found it (state, what the next step starts from, report). On
 * LEGSIM_OK every output and the report are finite. Inputs are range-checked
 * (the LEGSIM_MAX_* / LEGSIM_MIN_* ranges below), finite-but-absurd values too.
 */
#ifndef LEGSIM_LEGSIM_H
#define LEGSIM_LEGSIM_H

#include <stddef.h>
#include <stdint.h>

#include "legsim/config.h" /* generated: LEGSIM_USE_FLOAT, capacities, feature switches */

#ifdef __cplusplus
extern "C" {
#endif

#if LEGSIM_USE_FLOAT
typedef float legsim_real;
#else
typedef double legsim_real;
#endif

#define LEGSIM_FRAME (-1)        /* body index of the ground (the robot body) */
#define LEGSIM_STORAGE_ALIGN 16  /* required alignment of the sim storage, bytes */

/* ---- ranges ---------------------------------------------------------------
 * Sane magnitudes, inclusive. Outside them a model is refused (legsim_model_check,
 * LEGSIM_ERR_MODEL; the TOML loader and the code generator give the same ranges),
 * an option or call input with LEGSIM_ERR_BAD_INPUT, and a result with
 * LEGSIM_ERR_DIVERGED. They keep every product the solver forms finite in float. */
/* model description */
#define LEGSIM_MAX_COORD 1e3          /* |x|, |y| (m), |phi| (rad): points, guesses, pose drivers */
#define LEGSIM_MAX_GRAVITY_MPS2 1e3   /* |g| per component */
#define LEGSIM_MIN_LENGTH_M 1e-3      /* body lengths and stroke ends: [MIN, MAX_COORD] m */
#define LEGSIM_MIN_MASS_KG 1e-3
#define LEGSIM_MAX_MASS_KG 1e6
#define LEGSIM_MIN_INERTIA_KGM2 1e-12
#define LEGSIM_MAX_INERTIA_KGM2 1e6
#define LEGSIM_MAX_FORCE_N 1e6        /* max_force (and >= LEGSIM_MIN_FORCE_N), loads |F| N and |T| N m */
#define LEGSIM_MIN_FORCE_N 1e-3
#define LEGSIM_MAX_STIFFNESS_N_PER_M 1e9  /* servo kp and spring stiffness, >= 0 */
#define LEGSIM_MAX_DAMPING_NS_PER_M 1e7   /* servo kd and spring damping, >= 0 */
/* (spring rest lengths: [0, LEGSIM_MAX_COORD] m) */
/* options */
#define LEGSIM_MIN_STEP_S 1e-6
#define LEGSIM_MAX_STEP_S 0.1
#define LEGSIM_MIN_NEWTON_TOL 1e-15   /* m, rad */
#define LEGSIM_MAX_NEWTON_TOL 1e-3
#define LEGSIM_MAX_NEWTON_ITER 1000
/* state and call inputs */
#define LEGSIM_MAX_ABS_Q 1e6          /* a state's |x|, |y| (m), |phi| (rad): below */
#define LEGSIM_MAX_ABS_QD 1e9         /* a state's velocities (m/s, rad/s): below */
#define LEGSIM_MAX_TIME_S 1e9         /* |t| given to legsim_set_state */
#define LEGSIM_MAX_RATE_MPS 1e3       /* driven actuator length rates */
#define LEGSIM_MAX_ACCEL_MPS2 1e6     /* driven actuator length accelerations */
#define LEGSIM_MAX_GRID 1000          /* legsim_statics_sweep: n_grid in [2, MAX] */
#define LEGSIM_MAX_FRICTION 10.0      /* ground friction coefficients: 0 <= mu_kinetic <= mu_static <= MAX */
#define LEGSIM_MAX_SLOPE_RAD 1.5      /* ground slope_rad: |slope| <= MAX (about 86 degrees) */

/* ---- status ------------------------------------------------------------ */
typedef enum legsim_status {
  LEGSIM_OK = 0,
  LEGSIM_ERR_NULL = 1,          /* a required pointer is NULL */
  LEGSIM_ERR_STORAGE = 2,       /* storage too small or misaligned, or a sim handle that
                                   legsim_init did not make (every function checks) */
  LEGSIM_ERR_MODEL = 3,         /* model description invalid (legsim_model_check tells why) */
  LEGSIM_ERR_CAPACITY = 4,      /* model exceeds the compile-time capacity */
  LEGSIM_ERR_BAD_INPUT = 5,     /* NaN/Inf, index out of range, or a nonsensical option */
  LEGSIM_ERR_OUT_OF_STROKE = 6, /* a length command or assembly length outside the stroke */
  LEGSIM_ERR_NOT_CONVERGED = 7, /* Newton iteration hit its limit */
  LEGSIM_ERR_SINGULAR = 8,      /* constraint Jacobian (numerically) rank deficient: dead centre */
  LEGSIM_ERR_UNREACHABLE = 9,   /* the lengths cannot be met: Newton diverged or stalled */
  LEGSIM_ERR_NO_EQUILIBRIUM = 10, /* statics: the loads cannot be balanced (a free mechanism) */
  LEGSIM_ERR_DISABLED = 11,     /* stripped at compile time or disabled by the scene options */
  LEGSIM_ERR_STATE = 12,        /* state not finite or no pose assembled yet */
  LEGSIM_ERR_DIVERGED = 13,     /* a step or solve produced a non-finite or absurd result
                                   (beyond LEGSIM_MAX_ABS_Q / LEGSIM_MAX_ABS_QD, or
                                   non-finite accelerations, multipliers or reactions) */
  LEGSIM_ERR_CONTACT = 14       /* the contact problem has no usable solution (redundant or
                                   inconsistent contacts); the state stays the last good one */
} legsim_status;

const char *legsim_status_str(legsim_status s);

/* ---- model description (data; double regardless of the build's real) --- */
typedef enum legsim_joint_kind {
  LEGSIM_JOINT_REVOLUTE_TO_FRAME = 0, /* point on body[0] = frame point (2 eqs) */
  LEGSIM_JOINT_REVOLUTE = 1,          /* point on body[0] = point on body[1] (2 eqs) */
  LEGSIM_JOINT_PRISMATIC = 2,         /* phi1 = phi0, centre of body[1] on the axis of body[0] (2 eqs) */
  LEGSIM_JOINT_SLOT = 3               /* point on body[0] on the axis of body[1] (1 eq) */
} legsim_joint_kind;

typedef enum legsim_force_kind {
  LEGSIM_FORCE_POINT = 0,        /* force value[0..1] (N, world) at point[0] of body[0] */
  LEGSIM_FORCE_TORQUE = 1,       /* torque value[0] (N m) on body[0] */
  LEGSIM_FORCE_SPRING_DAMPER = 2 /* linear spring-damper between point[0] of body[0] and point[1] of body[1] */
} legsim_force_kind;

typedef struct legsim_body_desc {
  char name[LEGSIM_NAME_LEN];
  double length_m;
  double mass_kg;
  double inertia_kgm2; /* about the centre of mass */
} legsim_body_desc;

typedef struct legsim_joint_desc {
  char name[LEGSIM_NAME_LEN];
  legsim_joint_kind kind;
  int32_t body[2];     /* 0-based body indices; body[1] = LEGSIM_FRAME for revolute_to_frame */
  double point[2][2];  /* body-fixed (xi, eta) on each body, or world (x, y) on the frame;
                          prismatic: unused; slot: point[0] only */
} legsim_joint_desc;

typedef struct legsim_actuator_desc {
  char name[LEGSIM_NAME_LEN];
  int32_t joint;        /* a prismatic joint: cylinder body[0], rod body[1] */
  double stroke_min_m;  /* length from the cylinder's proximal end to the rod's distal end */
  double stroke_max_m;
  double max_force_n;
  double servo_kp_n_per_m;
  double servo_kd_ns_per_m;
} legsim_actuator_desc;

typedef struct legsim_force_desc {
  char name[LEGSIM_NAME_LEN];
  legsim_force_kind kind;
  int32_t body[2];       /* body[1] only for spring-dampers (LEGSIM_FRAME allowed) */
  double point[2][2];    /* body-fixed (xi, eta), or world (x, y) on the frame */
  double value[2];       /* point: (Fx, Fy) N; torque: value[0] N m */
  double stiffness_n_per_m;
  double damping_ns_per_m;
  double rest_length_m;
} legsim_force_desc;

typedef struct legsim_coord_driver {
  int32_t body;   /* 0-based */
  int32_t coord;  /* 0: x, 1: y, 2: phi */
  double value;   /* m or rad */
} legsim_coord_driver;

typedef struct legsim_pose_desc {
  char name[LEGSIM_NAME_LEN];
  int32_t n_drivers;
  legsim_coord_driver driver[LEGSIM_MAX_POSE_DRIVERS];
  double guess[LEGSIM_MAX_BODIES][3]; /* starting point of the assembly */
} legsim_pose_desc;

/* A foot point that can touch the ground line (docs/design/robot-on-ground.md). */
typedef struct legsim_contact_desc {
  char name[LEGSIM_NAME_LEN];
  int32_t body;        /* 0-based; each contact on a body of its own */
  double point[2];     /* body-fixed (xi, eta), |.| <= LEGSIM_MAX_COORD */
} legsim_contact_desc;

/* The ground: the line through point at angle slope_rad (counter-clockwise), tangent
 * t = (cos, sin), upward normal n = (-sin, cos); Coulomb friction with
 * 0 <= mu_kinetic <= mu_static <= LEGSIM_MAX_FRICTION. |point| <= LEGSIM_MAX_COORD,
 * |slope_rad| <= LEGSIM_MAX_SLOPE_RAD = 1.5 rad (about 86 degrees; legsim_model_check and
 * the model file loader refuse a steeper one). Unused (all zero) in a model without contacts. */
typedef struct legsim_ground_desc {
  double point[2];
  double slope_rad;
  double mu_static;
  double mu_kinetic;
} legsim_ground_desc;

/* At least one array slot even in a build without contacts (C has no empty arrays). */
#define LEGSIM_CONTACT_SLOTS (LEGSIM_MAX_CONTACTS > 0 ? LEGSIM_MAX_CONTACTS : 1)

typedef struct legsim_model_desc {
  char name[LEGSIM_NAME_LEN];
  double gravity_mps2[2];
  int32_t n_bodies, n_joints, n_actuators, n_forces, n_poses;
  legsim_body_desc body[LEGSIM_MAX_BODIES];
  legsim_joint_desc joint[LEGSIM_MAX_JOINTS];
  legsim_actuator_desc actuator[LEGSIM_MAX_ACTUATORS];
  legsim_force_desc force[LEGSIM_MAX_FORCES];
  legsim_pose_desc pose[LEGSIM_MAX_POSES];
  int32_t foot_body;       /* -1: none (a robot's feet are its contacts) */
  double foot_point[2];    /* (xi, eta) on foot_body */
  int32_t n_contacts;      /* 0 .. LEGSIM_MAX_CONTACTS */
  legsim_contact_desc contact[LEGSIM_CONTACT_SLOTS];
  legsim_ground_desc ground;
} legsim_model_desc;

/* Checks a description. On error writes a one-line reason (e.g. "joint 'D': body 7
 * does not exist") into msg (if not NULL) and returns LEGSIM_ERR_MODEL or
 * LEGSIM_ERR_CAPACITY. */
legsim_status legsim_model_check(const legsim_model_desc *model, char *msg, size_t msg_len);

/* ---- options (per scene) ---------------------------------------------- */
typedef enum legsim_integrator {
  LEGSIM_INTEGRATOR_RK4 = 0,          /* explicit RK4 on the index-1 form + projection of q and qd */
  LEGSIM_INTEGRATOR_GENERALIZED_ALPHA = 1 /* implicit index-3 generalized-alpha (Arnold & Bruls) */
} legsim_integrator;

/* Skip what a scene does not need (as MuJoCo's disable flags). */
enum legsim_disable {
  LEGSIM_DISABLE_GRAVITY = 1u << 0,
  LEGSIM_DISABLE_FORCE_ELEMENTS = 1u << 1, /* point forces, torques, spring-dampers */
  LEGSIM_DISABLE_REACTIONS = 1u << 2,      /* no multipliers at the end of a step */
  LEGSIM_DISABLE_PROJECTION = 1u << 3,     /* RK4: no projection onto Phi = 0, Phi_q qd = 0 */
  LEGSIM_DISABLE_ACTUATORS = 1u << 4,      /* actuators exert no force (passive joints) */
  LEGSIM_DISABLE_STROKE_LIMITS = 1u << 5   /* do not stop actuators at their stroke ends */
};

/* The rule that fixes the statically indeterminate stance on two stuck contacts (its
 * solutions differ by a self-equilibrated pair of tangential ground forces along the
 * line): EQUAL_FRICTION, both feet use the same fraction of their normal force,
 * T_0/N_0 = T_1/N_1 (needs N_0 + N_1 > 0); MIN_TANGENTIAL, T_0^2 + T_1^2 least.
 * docs/design/robot-on-ground.md section 3. */
typedef enum legsim_statics_rule {
  LEGSIM_STATICS_EQUAL_FRICTION = 0,
  LEGSIM_STATICS_MIN_TANGENTIAL = 1
} legsim_statics_rule;

/* The contact law of legsim_step (docs/design/robot-on-ground.md section 2): LCP, the
 * Coulomb transitions of each foot by its own cone (the default); PAPER, the paper's rule
 * while both feet are on the ground: the stuck-stuck reactions decide, and when a foot's
 * |T| exceeds mu_static N the foot with the SMALLER |T| is released to slide
 * (T = mu_kinetic N against its sliding), the other stays stuck. Lift-off and touchdown
 * are the same in both. */
typedef enum legsim_contact_law {
  LEGSIM_CONTACT_LCP = 0,
  LEGSIM_CONTACT_PAPER = 1
} legsim_contact_law;

typedef struct legsim_options {
  legsim_integrator integrator;
  double step_s;            /* fixed step h in [LEGSIM_MIN_STEP_S, LEGSIM_MAX_STEP_S] */
  uint32_t disable;         /* legsim_disable flags */
  double rho_inf;           /* generalized-alpha spectral radius at infinity, in [0, 1] */
  int32_t max_newton_iter;  /* assembly, projection and implicit steps: 1 .. LEGSIM_MAX_NEWTON_ITER */
  double newton_tol;        /* on the constraint residual (m, rad) and on corrections:
                               [LEGSIM_MIN_NEWTON_TOL, LEGSIM_MAX_NEWTON_TOL]; a
                               generalized-alpha step has converged when its last correction,
                               or that correction times the iteration's measured contraction
                               theta / (1 - theta) (its estimated remaining error, Hairer &
                               Wanner), is at most newton_tol */
  legsim_statics_rule statics_rule; /* legsim_statics and legsim_inverse_dynamics on two
                                       stuck contacts; one of the enum, else BAD_INPUT */
  legsim_contact_law contact_law;   /* legsim_step's foot transitions; one of the enum,
                                       else BAD_INPUT */
} legsim_options;

/* h = 1 ms, RK4, nothing disabled, rho_inf = 0.8, 25 iterations, tol 1e-10 (1e-6 float),
 * statics_rule EQUAL_FRICTION, contact_law LCP. */
legsim_options legsim_default_options(void);

/* ---- simulation lifetime ---------------------------------------------- */
typedef struct legsim_sim legsim_sim; /* opaque */

size_t legsim_sim_size(void);

/* Compiles the model into storage and assembles nothing yet (see legsim_assemble_pose).
 * Model and options are checked before the storage is touched; should a later
 * step fail, the storage holds no sim (other functions refuse it). 
 * The description is kept by pointer (its names and poses are read later): it must
 * outlive the sim and not change (the generated models are const data). */
legsim_status legsim_init(void *storage, size_t storage_bytes, const legsim_model_desc *model,
                          const legsim_options *options, legsim_sim **out);
/* The same options sent again change nothing; new ones restart both integrators. */
legsim_status legsim_set_options(legsim_sim *sim, const legsim_options *options);

/* ---- sizes and names --------------------------------------------------- */
int32_t legsim_n_bodies(const legsim_sim *sim);
int32_t legsim_n_coords(const legsim_sim *sim);       /* 3 * bodies */
int32_t legsim_n_constraints(const legsim_sim *sim);  /* joint equations (16 or 15 for the leg) */
int32_t legsim_n_joints(const legsim_sim *sim);
int32_t legsim_n_actuators(const legsim_sim *sim);
int32_t legsim_n_forces(const legsim_sim *sim);
int32_t legsim_n_contacts(const legsim_sim *sim);
const legsim_model_desc *legsim_model(const legsim_sim *sim);

/* ---- state ------------------------------------------------------------- */
/* Never NaN or Inf: a refused call leaves the report as it was. */
typedef struct legsim_report {
  int32_t iterations;         /* Newton iterations of the last solve */
  legsim_real residual;       /* max |Phi| after the last solve (m or rad) */
  legsim_real condition;      /* condition of Phi_q M^-1/2 (or of Phi_q in assembly): after an
                                 assembly its 2-norm condition (power iterations on the factor);
                                 after a step the cheaper pivot-spread estimate of its last solve */
  uint32_t events;            /* legsim_event bits raised since the last legsim_clear_events */
} legsim_report;

enum legsim_event {
  LEGSIM_EVENT_STROKE_MIN = 1u << 0,      /* an actuator reached its shortest length and stopped */
  LEGSIM_EVENT_STROKE_MAX = 1u << 1,      /* an actuator reached its longest length and stopped */
  LEGSIM_EVENT_FORCE_SATURATED = 1u << 2, /* a servo asked for more than max_force */
  LEGSIM_EVENT_NEAR_SINGULAR = 1u << 3,   /* condition estimate above LEGSIM_COND_WARN, or a
                                             stroke end at a dead centre, where no stop can
                                             be projected (the state is left as integrated) */
  /* foot contacts (section 8), checked after every step: */
  LEGSIM_EVENT_LIFTOFF = 1u << 4,         /* a stuck or sliding foot's normal force would pull: FREE */
  LEGSIM_EVENT_TOUCHDOWN = 1u << 5,       /* a free foot reached the line: put on it, inelastic
                                             impulse (legsim_contact.impulse_ns) */
  LEGSIM_EVENT_STICK_TO_SLIP = 1u << 6,   /* a stuck foot's |T| left the static cone: SLIDING */
  LEGSIM_EVENT_SLIP_TO_STICK = 1u << 7,   /* a sliding foot's velocity changed sign: STUCK */
  LEGSIM_EVENT_CONTACT_INCONSISTENT = 1u << 8, /* no consistent contact mode (the enumeration
                                             found none, or the modes still changed after the
                                             passes of one check): decided one by one, or the
                                             last one is kept */
  LEGSIM_EVENT_CONTACT_AMBIGUOUS = 1u << 9, /* several consistent modes: the priority rule picked
                                             one (docs/design/robot-on-ground.md section 8) */
  LEGSIM_EVENT_EVENTS_DEFERRED = 1u << 10,  /* a step had more contact events than
                                             LEGSIM_MAX_EVENTS_PER_STEP: the rest were taken at
                                             its end (docs/design/events.md) */
  LEGSIM_EVENT_EVENT_INEXACT = 1u << 11     /* a contact event's root finding ran out of its
                                             iterations (or a solve inside it failed): taken at
                                             the bracket's late end (or the step's end); one
                                             still short of its root there is not taken (the
                                             step goes on from there) */
};
/* Contact events are located inside the step (on its dense output, to 1e-6 of the step) and
 * taken at their time: a step is cut there and finished from the event. One step locates at
 * most this many; the rest are taken at its end (LEGSIM_EVENT_EVENTS_DEFERRED). Each costs
 * at most 12 dynamics solves and two part steps. */
#define LEGSIM_MAX_EVENTS_PER_STEP 4
/* Condition estimates: above WARN an event is raised; an assembly that lands
 * above SINGULAR is refused as a dead centre (LEGSIM_ERR_SINGULAR). */
#define LEGSIM_COND_WARN 1e3
#define LEGSIM_COND_SINGULAR 1e5

legsim_status legsim_get_report(const legsim_sim *sim, legsim_report *out);
/* The figures where the last failing call stopped inside the solver (its Newton
 * iterations, residual and condition, e.g. a dead centre's; the events it raised):
 * a diagnosis of the failure, kept apart from the sim's report, which a failing
 * call leaves as it was. Unlike that report, these figures may be non-finite (a
 * singular factorization has an infinite condition). All zero until a call fails
 * in the solver (checks at entry leave it too). */
legsim_status legsim_failure_report(const legsim_sim *sim, legsim_report *out);
legsim_status legsim_clear_events(legsim_sim *sim);
/* Which actuators raised a stroke event (bit a = actuator a). */
uint32_t legsim_stroke_event_mask(const legsim_sim *sim);
/* The contact events (LIFTOFF .. CONTACT_AMBIGUOUS bits) contact k raised since the last
 * legsim_clear_events (CONTACT_INCONSISTENT: the contacts whose mode was still changing);
 * 0 for a bad handle or k outside 0 .. n_contacts - 1. */
uint32_t legsim_contact_event_mask(const legsim_sim *sim, int32_t k);
/* The time (s) of contact k's last contact event: located inside its step (to 1e-6 of the
 * step), or the step's end for one taken there (beyond LEGSIM_MAX_EVENTS_PER_STEP, and the
 * modes resolved at the end of a step); the step's start time for a mode resolved before a
 * step (a starting state that cannot hold). 0 before any event. LEGSIM_ERR_BAD_INPUT for k
 * outside 0 .. n_contacts - 1. */
legsim_status legsim_contact_event_time(const legsim_sim *sim, int32_t k, double *t_s);
/* The time (s) actuator a last arrived on a stroke stop: located inside its step (to 1e-6
 * of the step) in a model with contacts, or the end of the (part) step that crossed it (a
 * model without contacts, beyond LEGSIM_MAX_EVENTS_PER_STEP, or a start on its end). 0
 * before any. LEGSIM_ERR_BAD_INPUT for a outside 0 .. n_actuators - 1. */
legsim_status legsim_stroke_event_time(const legsim_sim *sim, int32_t a, double *t_s);

double legsim_time(const legsim_sim *sim);
uint64_t legsim_step_count(const legsim_sim *sim);
/* n_coords values each. */
legsim_status legsim_get_q(const legsim_sim *sim, legsim_real *q);
legsim_status legsim_get_qd(const legsim_sim *sim, legsim_real *qd);
legsim_status legsim_get_qdd(const legsim_sim *sim, legsim_real *qdd);
/* Sets q and qd (qd may be NULL: zero) and time; does not project. |q| < LEGSIM_MAX_ABS_Q,
 * |qd| < LEGSIM_MAX_ABS_QD, |t_s| <= LEGSIM_MAX_TIME_S, else LEGSIM_ERR_BAD_INPUT. */
legsim_status legsim_set_state(legsim_sim *sim, const legsim_real *q, const legsim_real *qd, double t_s);

/* Constraint residual Phi(q) (n_constraints values) and its max-abs norm. */
legsim_status legsim_constraints(const legsim_sim *sim, legsim_real *phi, legsim_real *max_abs);
/* Dense constraint Jacobian, row-major n_constraints x n_coords. */
legsim_status legsim_jacobian(const legsim_sim *sim, legsim_real *jac);

legsim_status legsim_actuator_lengths(const legsim_sim *sim, legsim_real *length_m, legsim_real *rate_mps);
/* Axial force of each actuator in the current state (N, > 0 extends). */
legsim_status legsim_actuator_forces(const legsim_sim *sim, legsim_real *force_n);
/* Foot point position (m, world). */
legsim_status legsim_foot_position(const legsim_sim *sim, legsim_real *xy);

/* ---- 1. assembly -------------------------------------------------------- */
/* Newton-Raphson from the current q onto Phi(q) = 0 with the actuators at the
 * given lengths (NULL: keep the current lengths). qd is set to zero.
 * Reports out-of-stroke lengths, non-convergence, unreachable lengths and
 * singular configurations; on failure q is left unchanged. */
legsim_status legsim_assemble(legsim_sim *sim, const legsim_real *length_m);
/* Assembles a named pose of the model from its guess, driving its coordinates. */
legsim_status legsim_assemble_pose(legsim_sim *sim, int32_t pose);
/* The leg's inverse kinematics: Newton from the current q (the branch near it) onto Phi(q) =
 * 0 with its [foot] point at foot_xy (m, world, |x| <= LEGSIM_MAX_COORD); qd is set to zero,
 * and legsim_actuator_lengths gives the lengths that put it there. A model without a foot or
 * with contacts (a robot) LEGSIM_ERR_BAD_INPUT; a point the leg cannot reach
 * LEGSIM_ERR_UNREACHABLE or LEGSIM_ERR_NOT_CONVERGED, a singular pose LEGSIM_ERR_SINGULAR,
 * one that needs a length outside its stroke LEGSIM_ERR_OUT_OF_STROKE; on failure q is left
 * unchanged. */
legsim_status legsim_assemble_foot(legsim_sim *sim, const legsim_real *foot_xy);

/* ---- 2. velocity and acceleration analysis ------------------------------- */
/* For driven actuator length rates (|rate| <= LEGSIM_MAX_RATE_MPS) and accelerations
 * (|accel| <= LEGSIM_MAX_ACCEL_MPS2), in the current q: solves Phi_q qd = -Phi_t and
 * Phi_q qdd = gamma. Sets qd (and qdd). A resulting qd a state may not hold (near a
 * dead centre) is refused with LEGSIM_ERR_DIVERGED. A contact that is not FREE (feet on the
 * ground) is refused with LEGSIM_ERR_CONTACT: legsim_inverse_dynamics_on_ground drives a stance. */
legsim_status legsim_velocity_analysis(legsim_sim *sim, const legsim_real *rate_mps);
legsim_status legsim_acceleration_analysis(legsim_sim *sim, const legsim_real *accel_mps2);

/* ---- 3. inverse dynamics ------------------------------------------------- */
/* Along a driven motion: assembles the lengths (from the current q), solves
 * velocities and accelerations, then M qdd + Phi_q^T lambda = Q for lambda:
 * actuator forces (driver multipliers) and joint reactions. Any of the output
 * arrays may be NULL. */
legsim_status legsim_inverse_dynamics(legsim_sim *sim, const legsim_real *length_m,
                                      const legsim_real *rate_mps, const legsim_real *accel_mps2,
                                      legsim_real *actuator_force_n);
/* With feet on the ground (docs/design/robot-on-ground.md section 8): contacts that are STUCK
 * hold their feet at their stick points (SLIDING: LEGSIM_ERR_CONTACT). The motion follows
 * from the joints, the driven lengths and the held feet's normal and tangential rows, which
 * must fix it (as many rows as coordinates, else LEGSIM_ERR_BAD_INPUT): on the robot on both
 * feet (3 dof) three lengths drive it and the fourth actuator follows (follow_mask, bit a =
 * actuator a); its length, rate and acceleration are written back into the arrays (those
 * given for a follower are not read; out of stroke: LEGSIM_ERR_OUT_OF_STROKE). The forces of
 * every actuator, the joint reactions and each foot's N and T (legsim_contacts, with holds)
 * come from every driver row and the held feet; on two held feet they are fixed by
 * options.statics_rule as in legsim_statics. legsim_inverse_dynamics on a sim with stuck
 * contacts is this call with follow_mask 0: the lengths must keep both feet where they stick
 * (drift over 1e-7 m or 1e-7 m/s per m/s of rate: LEGSIM_ERR_UNREACHABLE; accelerations that
 * do not: LEGSIM_ERR_NO_EQUILIBRIUM). */
legsim_status legsim_inverse_dynamics_on_ground(legsim_sim *sim, uint32_t follow_mask,
                                                legsim_real *length_m, legsim_real *rate_mps,
                                                legsim_real *accel_mps2, legsim_real *actuator_force_n);

/* ---- 4. statics ------------------------------------------------------------ */
/* Equilibrium actuator forces and joint reactions in the current q (qd = 0)
 * under the active loads (gravity and force elements). Contacts that are not FREE
 * hold their feet (as STUCK) and their ground forces are reported by legsim_contacts,
 * with whether the friction can hold them (legsim_contact.holds). Two such contacts
 * make the stance statically indeterminate: options.statics_rule picks the solution
 * (two square solves, each with one foot's tangential row, combined; with EQUAL_FRICTION
 * and N_0 + N_1 <= 0: LEGSIM_ERR_NO_EQUILIBRIUM). More than two: LEGSIM_ERR_CONTACT. */
legsim_status legsim_statics(legsim_sim *sim, legsim_real *actuator_force_n);

typedef struct legsim_worst_case {
  legsim_real max_reaction_n[LEGSIM_MAX_JOINTS];      /* max |force| over the sweep */
  legsim_real max_actuator_force_n[LEGSIM_MAX_ACTUATORS]; /* max |F| over the sweep */
  legsim_real at_length_m[LEGSIM_MAX_JOINTS][LEGSIM_MAX_ACTUATORS]; /* lengths where each max occurs */
  legsim_real actuator_at_length_m[LEGSIM_MAX_ACTUATORS][LEGSIM_MAX_ACTUATORS];
  int32_t n_poses;     /* poses evaluated */
  int32_t n_failed;    /* grid points that could not be assembled (skipped, counted) */
} legsim_worst_case;

/* Worst-case statics over an n x n grid (n in [2, LEGSIM_MAX_GRID]) of the first two
 * actuators' strokes (the paper's Section V); the leg moves, so every contact is let go
 * (FREE) first. On LEGSIM_OK leaves the sim at the last
 * pose solved; on an error (no grid point solved: LEGSIM_ERR_UNREACHABLE) changes nothing.
 * A grid point that fails changes nothing either (it is counted in n_failed). */
legsim_status legsim_statics_sweep(legsim_sim *sim, int32_t n_grid, legsim_worst_case *out);

/* ---- 5. forward dynamics ------------------------------------------------- */
/* Advances n fixed steps with the selected integrator. Each step is all or nothing:
 * the call stops at the first failing step and returns its status, with the state
 * (and report) of the last good step (legsim_step_count tells how many were made). */
legsim_status legsim_step(legsim_sim *sim, int32_t n_steps);

/* Checks the contact modes at the current state, time and commands now, as the next step
 * would at its start after a change from outside (a state, contact state or command set): a
 * start that cannot hold (feet set stuck on a slope steeper than their friction allows)
 * changes mode here, at the current time, with its event; a state whose modes were already
 * checked is left as it is. All or nothing; LEGSIM_ERR_STATE before an assembly. */
legsim_status legsim_contacts_check(legsim_sim *sim);

/* ---- 6. reactions ---------------------------------------------------------- */
typedef struct legsim_reaction {
  legsim_real force_n[2];  /* force the joint applies to its first-listed body, world axes */
  legsim_real moment_nm;   /* moment it applies about that body's centre of mass */
} legsim_reaction;

/* Reactions of every joint (n_joints entries) from the multipliers of the last
 * dynamics, inverse-dynamics or statics solve (eq. (20) of the paper). */
legsim_status legsim_reactions(const legsim_sim *sim, legsim_reaction *out);
/* Raw multipliers (n_constraints values) of the last solve: after a generalized-alpha
 * step those of its index-3 iteration (the reactions come from an acceleration-level
 * solve at the same state, which is better conditioned; they differ at round-off). */
legsim_status legsim_multipliers(const legsim_sim *sim, legsim_real *lambda);

/* ---- 7. actuators and loads ------------------------------------------------ */
typedef enum legsim_actuator_mode {
  LEGSIM_ACTUATOR_FORCE = 0,  /* apply a commanded axial force */
  LEGSIM_ACTUATOR_LENGTH = 1  /* the servo holds a commanded length */
} legsim_actuator_mode;

/* A changed command or load takes effect at the next step, which restarts both integrators
 * from the accelerations under it (a discontinuity of the forcing); the same value sent
 * again changes nothing. The restart keeps what depends on the state alone, so a controller
 * may send a new command every step: about one Newton iteration a step still.
 * |force| <= max_force and finite, else LEGSIM_ERR_BAD_INPUT (nothing changes). */
legsim_status legsim_command_force(legsim_sim *sim, int32_t actuator, legsim_real force_n);
/* Inside the stroke, else LEGSIM_ERR_OUT_OF_STROKE (nothing changes). */
legsim_status legsim_command_length(legsim_sim *sim, int32_t actuator, legsim_real length_m);
/* Sets a force element's value (point: 2 values N; torque: 1 value N m), each
 * |value| <= LEGSIM_MAX_FORCE_N, else LEGSIM_ERR_BAD_INPUT (nothing changes). */
legsim_status legsim_set_force(legsim_sim *sim, int32_t force, const legsim_real *value);

/* ---- 8. foot contact with the ground ---------------------------------------
 * A model with contacts (n_contacts > 0; a robot file) has per contact a state.
 * STUCK: two rows hold the foot point at its stick point on the ground line
 * (normal and tangential), solved with the joints in both integrators; SLIDING: the
 * normal row, and the kinetic friction T = -mu_kinetic N sign(v_t) at the foot (the
 * non-symmetric coupling solved exactly); FREE: no rows. The ground force on a foot is
 * F = N n + T t (n the line's upward normal, t its tangent). After every step the
 * modes change by the rules of docs/design/robot-on-ground.md section 2, each raised as
 * a legsim_event (LIFTOFF, TOUCHDOWN, STICK_TO_SLIP, SLIP_TO_STICK; located to within
 * the step) with the same all-or-nothing rule as the stroke stops; a contact problem
 * with no usable solution fails the step with LEGSIM_ERR_CONTACT (the last good state
 * kept), as does a foot force that passes through a pole inside the step (a sliding foot
 * whose friction coupling turns singular, Painleve's paradox: a shorter step ends the mode
 * before it). Builds with LEGSIM_MAX_CONTACTS = 0 return LEGSIM_ERR_DISABLED. */
typedef enum legsim_contact_state {
  LEGSIM_CONTACT_FREE = 0,
  LEGSIM_CONTACT_STUCK = 1,
  LEGSIM_CONTACT_SLIDING = 2
} legsim_contact_state;

typedef struct legsim_contact {
  legsim_contact_state state;
  legsim_real normal_n;      /* N: ground force along the upward normal (> 0 pushes up) */
  legsim_real tangential_n;  /* T: along the tangent (cos slope, sin slope) */
  legsim_real friction_use;  /* |T| / N (0 when N <= 0 or free) */
  legsim_real position[2];   /* foot point, world (m) */
  legsim_real slip_mps;      /* foot velocity along the tangent (m/s) */
  legsim_real impulse_ns[2]; /* the last impulse of the ground on the foot (normal, tangential;
                                N s): a touchdown's, or a slip to stick's */
  int32_t holds;             /* 1: the ground force is inside the static cone, N >= 0 and
                                |T| <= mu_static N (a stuck foot the friction can hold); 0 else */
} legsim_contact;

/* n_contacts entries: the state of the last solve (step, statics, assembly). */
legsim_status legsim_contacts(const legsim_sim *sim, legsim_contact *out);
/* Sets contact k (0 .. n_contacts - 1) STUCK at its foot's current point (which must be
 * on the ground line within the Newton tolerance, else LEGSIM_ERR_STATE), SLIDING (on
 * the line, and its velocity along the line |v_t| > newton_tol, whose sign is the
 * sliding direction, else LEGSIM_ERR_STATE) or FREE; other values LEGSIM_ERR_BAD_INPUT.
 * The foot's velocity is put onto its new rows (frictionless). Solves the dynamics at the
 * current state anew (all or nothing: a set that makes the system singular changes
 * nothing). */
legsim_status legsim_set_contact_state(legsim_sim *sim, int32_t k, legsim_contact_state state);
/* The stance: Newton from the current q (e.g. legsim_assemble_pose of a robot's
 * "stand", whose guess has the feet on the ground already) onto the joints, the
 * actuators at length_m (NULL: their current lengths) and the outer contacts (the
 * first and the last) on the ground line, the midpoint of their points at feet_mid_m
 * along the line from its point (|feet_mid_m| <= LEGSIM_MAX_COORD). The box pose
 * follows. qd = 0 and every contact STUCK where it landed; a contact between the outer
 * two must then be on the line (|gap| <= newton_tol, else LEGSIM_ERR_STATE). Needs at
 * least one contact (else LEGSIM_ERR_BAD_INPUT); errors as legsim_assemble, nothing
 * changes on failure. */
legsim_status legsim_assemble_on_ground(legsim_sim *sim, const legsim_real *length_m,
                                        legsim_real feet_mid_m);

#ifdef __cplusplus
}
#endif
#endif /* LEGSIM_LEGSIM_H */
