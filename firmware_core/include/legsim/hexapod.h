/* The hexapod's description (docs/design/spatial.md): six legs, each the leg's own planar file
 * on a hip yoke that a rowing actuator turns about the box's vertical axis, on a box that moves
 * with six degrees of freedom, over a ground plane. A hexapod file (models/hexapod.toml) is read
 * by the one model file parser (firmware_core/host/model_toml.hpp: legsim_hexapod_load_toml);
 * the spatial module lifts it (firmware_core/src/spatial/robot.hpp). SI units, the world z up.
 *
 * Ranges (the loader refuses anything outside them):
 *   gravity: (0, 0, g_z), |g_z| <= LEGSIM_MAX_GRAVITY_MPS2, and each leg file's (0, g_z);
 *   masses [LEGSIM_MIN_MASS_KG, LEGSIM_MAX_MASS_KG]; principal inertias
 *   [LEGSIM_MIN_INERTIA_KGM2, LEGSIM_MAX_INERTIA_KGM2]; sizes, the hip offset and the bar radius
 *   [LEGSIM_MIN_LENGTH_M, LEGSIM_MAX_COORD]; points |x| <= LEGSIM_MAX_COORD; headings |h| <= pi;
 *   the rowing stroke -pi < min < 0 < max < pi rad; gear ratio [1, 1e4]; max torque
 *   [LEGSIM_MIN_FORCE_N, LEGSIM_MAX_FORCE_N] N m; servo kp [0, LEGSIM_MAX_STIFFNESS_N_PER_M] N m/rad,
 *   kd [0, LEGSIM_MAX_DAMPING_NS_PER_M] N m s/rad; each leg file at most
 *   LEGSIM_HEXAPOD_MAX_LEG_BARS bodies and no slot joint (the spatial rows have none), its force
 *   elements not lifted (the hexapod's loads are its own); the ground's normal a unit vector within 1e-9 whose angle from z
 *   is at most LEGSIM_MAX_SLOPE_RAD; 0 <= mu_kinetic <= mu_static <= LEGSIM_MAX_FRICTION; at most
 *   LEGSIM_HEXAPOD_MAX_BOX_CONTACTS box contact points ([[box_contact]] point = [x, y, z]), each on
 *   or inside the box, |x_i| <= box_size_m[i] / 2. A file of no [[leg]] (n_legs 0), [yoke] or
 *   [rowing] and at least one [[box_contact]] is a block: the box alone on its points
 *   (legsim_hexapod_sim_init and what follows it take it; the analyses of legs refuse it). */
#ifndef LEGSIM_HEXAPOD_H
#define LEGSIM_HEXAPOD_H

#include "legsim/legsim.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LEGSIM_HEXAPOD_LEGS 6
#define LEGSIM_HEXAPOD_MAX_LEG_BARS 8
#define LEGSIM_HEXAPOD_MAX_BOX_CONTACTS 4

typedef struct legsim_hexapod_leg_desc {
  char name[LEGSIM_NAME_LEN];
  legsim_model_desc leg;  /* its file (the variant named), as the planar model reads it */
  double hip_m[3];        /* the hip axis point on the box: box frame, from its centre */
  double heading_rad;     /* the yoke's x (the leg's plane, out from the hip) at rowing angle 0,
                             about the box's z from its x */
} legsim_hexapod_leg_desc;

typedef struct legsim_hexapod_desc {
  char name[LEGSIM_NAME_LEN];
  double gravity_mps2[3];
  /* the box: a uniform block's size (drawing and clearance), its mass and principal inertia
   * (box frame: x forward, y left, z up) */
  double box_mass_kg, box_size_m[3], box_inertia_kgm2[3];
  /* every hip's yoke: mass, centre of mass (yoke frame from the hip axis point: x out along
   * the leg's plane, z up), principal inertia, the leg's planar origin out along x from the
   * axis, and the bars' radius (their inertia about their own axis: m r^2 / 2) */
  double yoke_mass_kg, yoke_com_m[3], yoke_inertia_kgm2[3], hip_offset_m, bar_radius_m;
  /* the rowing actuator, a DC gear motor at each hip: torque at the yoke saturates at
   * max_torque; its angle's stroke about the heading; its angle servo's gains (the torque
   * kp (angle_cmd - angle) - kd rate, saturated) */
  double rowing_gear_ratio, rowing_max_torque_nm, rowing_stroke_rad[2];
  double rowing_servo_kp_nm_per_rad, rowing_servo_kd_nms_per_rad;
  int32_t n_legs; /* LEGSIM_HEXAPOD_LEGS; 0: a block (its box on its box contact points) */
  legsim_hexapod_leg_desc leg[LEGSIM_HEXAPOD_LEGS];
  /* the ground plane: a point, its upward unit normal, Coulomb friction */
  double ground_point_m[3], ground_normal[3], mu_static, mu_kinetic;
  /* the box's own contact points (box frame, from its centre; 0 .. LEGSIM_HEXAPOD_MAX_BOX_CONTACTS):
   * where it touches the ground when the legs give way, on the feet's contact law (three hold
   * it with independent normal rows; a fourth makes them redundant) */
  int32_t n_box_contacts;
  double box_contact_m[LEGSIM_HEXAPOD_MAX_BOX_CONTACTS][3];
} legsim_hexapod_desc;

/* ---- standing (statics) ------------------------------------------------ */
/* A pose of the hexapod: the box's centre (m, world) and its unit quaternion (w, x, y, z: box to
 * world, normalized by the call when within 1e-6 of unit length), each leg's rowing angle (rad,
 * within its stroke) and its two actuators' lengths (m, within their strokes: each leg is
 * assembled at them from its file's stand, the branch nearest it). */
typedef struct legsim_hexapod_pose {
  double box_m[3];
  double box_quat[4];
  double rowing_rad[LEGSIM_HEXAPOD_LEGS];
  double length_m[LEGSIM_HEXAPOD_LEGS][2];
} legsim_hexapod_pose;

/* The hexapod standing at a pose. */
typedef struct legsim_hexapod_standing {
  double com_m[3];                                  /* the centre of mass (world) */
  double foot_m[LEGSIM_HEXAPOD_LEGS][3];            /* each foot (world) */
  double foot_force_n[LEGSIM_HEXAPOD_LEGS][3];      /* the ground's force on it (world; 0 off the stance) */
  double actuator_force_n[LEGSIM_HEXAPOD_LEGS][2];  /* each leg's two actuators' axial forces */
  double rowing_torque_nm[LEGSIM_HEXAPOD_LEGS];     /* each yoke's, about its hip axis */
  double margin_m;                                  /* the stance's static stability margin */
} legsim_hexapod_standing;

/* Bytes of storage legsim_hexapod_statics needs (aligned to LEGSIM_STORAGE_ALIGN). */
size_t legsim_hexapod_storage_size(void);

/* The hexapod of h standing at pose on the feet of stance_mask (bit l: leg l), a force
 * box_force_n (N, world; NULL: none) at the box's centre: the stance feet take the loads with the
 * least sum of squares of their forces among those that balance them (on level ground a tripod's
 * vertical forces are the closed form of the centre of mass in its triangle, its horizontal ones
 * zero), then each leg its own (docs/design/spatial.md). Statuses: LEGSIM_ERR_NULL,
 * LEGSIM_ERR_STORAGE (storage too small or misaligned), LEGSIM_ERR_BAD_INPUT (a pose value out of
 * range or not finite, a quaternion not of unit length, a mask of other legs),
 * LEGSIM_ERR_OUT_OF_STROKE, LEGSIM_ERR_UNREACHABLE / _NOT_CONVERGED / _SINGULAR (a leg's
 * assembly), LEGSIM_ERR_NO_EQUILIBRIUM (fewer than three feet, on one line, or a foot that would
 * pull). *out is written only on LEGSIM_OK. The feet need not be on the ground plane (the
 * caller's pose says where they are). */
legsim_status legsim_hexapod_statics(const legsim_hexapod_desc *h, const legsim_hexapod_pose *pose,
                                     uint32_t stance_mask, const double *box_force_n, void *storage,
                                     size_t storage_bytes, legsim_hexapod_standing *out);

/* ---- the tripod gait ------------------------------------------------------- */
/* Two tripods (legs 0, 2, 4 and 1, 3, 5) take turns: each foot stands for the fraction duty
 * (in [0.5, 1)) of period_s (> 0) while the box moves forward by step_length_m (>= 0) and turns by
 * turn_rad (|turn| < pi / 2) about its z, then swings, rising by step_height_m (>= 0). Each
 * foot's neutral point (its place at the middle of its stance) is the stand's foot (x, y in the
 * box's frame), on the ground. The ground is the description's plane: on a slope the box stays
 * level, its path seen from above the level ground's, its centre box_height_m (> 0) over the
 * ground directly below it; the standing feet are on the plane and a swinging foot rises by
 * step_height_m over the ground directly below it (docs/design/spatial.md, "The gait on a
 * slope"; lengths <= LEGSIM_MAX_COORD). */
typedef struct legsim_hexapod_gait {
  double period_s, duty, step_length_m, step_height_m, turn_rad, box_height_m;
} legsim_hexapod_gait;

/* The set-points of the gait at a time: each foot's target (box frame, m), whether it stands,
 * the rowing angle (rad) and actuator lengths (m) that put it there, and the box's planned pose
 * (world: its centre, m, and unit quaternion w, x, y, z; at t = 0 level over the world's origin,
 * heading along x, box_height_m over the ground). */
typedef struct legsim_hexapod_setpoint {
  double foot_box_m[LEGSIM_HEXAPOD_LEGS][3];
  int32_t stance[LEGSIM_HEXAPOD_LEGS];
  double rowing_rad[LEGSIM_HEXAPOD_LEGS];
  double length_m[LEGSIM_HEXAPOD_LEGS][2];
  double box_m[3], box_quat[4];
} legsim_hexapod_setpoint;

/* The set-points at t_s (s; the gait repeats, in the box's frame, on level ground and walking
 * straight on a slope). LEGSIM_ERR_BAD_INPUT for a gait out of range; LEGSIM_ERR_OUT_OF_STROKE
 * for a target past a rowing or linear stroke, LEGSIM_ERR_UNREACHABLE / _NOT_CONVERGED /
 * _SINGULAR for one the leg cannot reach (each leg's inverse kinematics from its file's stand);
 * storage as legsim_hexapod_statics'. *out is written only on LEGSIM_OK. */
legsim_status legsim_hexapod_gait_setpoints(const legsim_hexapod_desc *h, const legsim_hexapod_gait *gait, double t_s,
                                            void *storage, size_t storage_bytes, legsim_hexapod_setpoint *out);

/* The static stability margin (m) of the n feet at foot_m (world) about the centre of mass com_m
 * (world): both projected along gravity (the world's z) onto a level plane, the least distance from
 * the centre of mass to the edges of the feet's convex hull, positive inside, negative outside;
 * -INFINITY for fewer than three feet or feet on one line. LEGSIM_ERR_NULL, LEGSIM_ERR_BAD_INPUT
 * (n outside 0..LEGSIM_HEXAPOD_LEGS, a value not finite or beyond LEGSIM_MAX_COORD). */
legsim_status legsim_hexapod_support_margin(const double foot_m[][3], int32_t n, const double com_m[3],
                                            double *margin_m);

/* ---- one leg's reach, and the Section V sweep ------------------------------- */
/* Leg leg's (0 .. 5) rowing angle (rad) and its two actuators' lengths (m) that put its foot at
 * foot_box_m (m, in the box's frame, |x| <= LEGSIM_MAX_COORD), from its file's stand (the branch
 * nearest it): the inverse kinematics a leg controller needs. LEGSIM_ERR_BAD_INPUT for another
 * leg or a point not finite or out of range; LEGSIM_ERR_OUT_OF_STROKE past the rowing or a linear
 * stroke; LEGSIM_ERR_UNREACHABLE / _NOT_CONVERGED / _SINGULAR for a point the leg cannot reach;
 * storage as legsim_hexapod_statics'. The outputs are written only on LEGSIM_OK. */
legsim_status legsim_hexapod_leg_reach(const legsim_hexapod_desc *h, int32_t leg, const double foot_box_m[3],
                                       void *storage, size_t storage_bytes, double *rowing_rad, double length_m[2]);

/* The paper's Section V on the hexapod: the robot standing on stance_mask (at least three feet)
 * with its box level, its centre box_height_m above the stance feet's plane; every leg at its
 * file's stand (rowing 0) but the stance ones, whose feet stand on that plane under their stand's
 * places, and leg `leg` (one of the stance), whose foot moves about its hip axis over a grid: its
 * horizontal distance from the axis (distance_m[0] .. [1], n_distance points) by its direction
 * from the leg's heading (heading_rad[0] .. [1], n_heading points; one point: the first value).
 * Point i (0 <= i < n_distance n_heading) is distance i / n_heading, direction i % n_heading.
 * Ranges: box_height_m (0, LEGSIM_MAX_COORD]; distances [LEGSIM_MIN_LENGTH_M, LEGSIM_MAX_COORD];
 * |heading| <= pi; 1 <= n_distance, n_heading and their product <= 1,000,000. */
typedef struct legsim_hexapod_sweep {
  int32_t leg;
  uint32_t stance_mask;
  double box_height_m;
  double distance_m[2];
  int32_t n_distance;
  double heading_rad[2];
  int32_t n_heading;
} legsim_hexapod_sweep;

/* One point of the sweep: its place, its status (LEGSIM_OK, or why it has no statics: out of a
 * stroke, unreachable, no equilibrium (a foot that would pull, the centre of mass out of the
 * stance)), and on LEGSIM_OK its pose's rowing angle and lengths of the moving leg and the
 * standing robot (every stance foot's ground force, every actuator's force and rowing torque,
 * the stability margin). */
typedef struct legsim_hexapod_sweep_point {
  int32_t index;
  legsim_status status;
  double distance_m, heading_rad;
  double rowing_rad, length_m[2];
  legsim_hexapod_standing standing;
} legsim_hexapod_sweep_point;

/* Points first .. first + count - 1 of the sweep into out[0 .. count - 1]: a part of the whole, so
 * that parts computed anywhere concatenate into it. LEGSIM_ERR_NULL, LEGSIM_ERR_BAD_INPUT (a
 * sweep value out of range, a part outside the grid, count < 1), storage as
 * legsim_hexapod_statics'; each point's own failure is its status. out is written only on
 * LEGSIM_OK. */
legsim_status legsim_hexapod_reaction_sweep(const legsim_hexapod_desc *h, const legsim_hexapod_sweep *sweep,
                                            int32_t first, int32_t count, void *storage, size_t storage_bytes,
                                            legsim_hexapod_sweep_point *out);

/* ---- the hexapod moving --------------------------------------------------- */
/* Forward dynamics (docs/design/spatial.md): the whole robot in absolute spatial coordinates on
 * the file's ground plane, each foot free, stuck (three rows hold it: its ground force is their
 * multipliers) or sliding (its normal row; friction mu_kinetic N against its slip), changing at
 * events located inside the step: a touchdown (an impact on the feet's circular cones), a lift-off
 * (N reaches 0), stick to slip (|F_t| reaches mu_static N), slip to stick. Each linear actuator's
 * length and each rowing angle stays within its stroke: its arrival at an end is an event too (an
 * inelastic impact on the stop), the stop then holds it while it pushes and lets go when it would
 * pull. Each linear actuator's
 * axial force and each rowing torque held over a step as commanded; RK4 (or generalized-alpha) on the rotation group,
 * the positions and velocities projected onto the rows at each step's end. A step is all or
 * nothing. */
typedef struct legsim_hexapod_sim legsim_hexapod_sim;

/* Bytes of storage legsim_hexapod_sim_init needs (aligned to LEGSIM_STORAGE_ALIGN). */
size_t legsim_hexapod_sim_size(void);

/* The hexapod of h at pose (of a file of no legs, a block: the box's place alone), at rest, the feet of stuck_mask (bit l: leg l; bit 6 + k: the box's
 * contact point k) stuck where the pose puts them (on the ground or not: the caller's pose says),
 * the others free, the commands zero.
 * Statuses as legsim_hexapod_statics' (its pose checks, a leg's assembly; LEGSIM_ERR_BAD_INPUT
 * also for a free foot more than 1e-9 m (float: 1e-5 m) under the ground), LEGSIM_ERR_SINGULAR /
 * _NOT_CONVERGED (the rows with the stuck feet cannot be met or solved). *out is written only on
 * LEGSIM_OK. The commands zero, the stuck feet's modes are checked at the first command. */
legsim_status legsim_hexapod_sim_init(void *storage, size_t storage_bytes, const legsim_hexapod_desc *h,
                                      const legsim_hexapod_pose *pose, uint32_t stuck_mask,
                                      legsim_hexapod_sim **out);

/* The commands from the next step on: each leg's two actuators' axial forces (N, |F| <= its
 * max_force) and rowing torques (N m, |tau| <= the file's rowing max_torque). LEGSIM_ERR_BAD_INPUT
 * for a value out of range or not finite (nothing changed). */
legsim_status legsim_hexapod_command(legsim_hexapod_sim *sim, const double actuator_force_n[LEGSIM_HEXAPOD_LEGS][2],
                                     const double rowing_torque_nm[LEGSIM_HEXAPOD_LEGS]);

/* The servos' set-points from the next step on: each leg's two actuator lengths (m, within their
 * strokes) and rowing angles (rad, within the rowing stroke): each actuator's force
 * F_ff + kp (l_cmd - l) - kd l' (its file's gains) and each rowing torque
 * tau_ff + kp (a_cmd - a) - kd a' (the file's [rowing] gains), saturated at max_force and
 * max_torque; the feed-forwards (N, |F_ff| <= max_force; N m, |tau_ff| <= max_torque; NULL: 0),
 * e.g. legsim_hexapod_statics' at the set-points, carry the load the gains would otherwise sag
 * under. LEGSIM_ERR_OUT_OF_STROKE for a set-point past its stroke, LEGSIM_ERR_BAD_INPUT for a
 * value not finite or a feed-forward out of range (nothing changed). */
legsim_status legsim_hexapod_command_pose(legsim_hexapod_sim *sim, const double length_m[LEGSIM_HEXAPOD_LEGS][2],
                                          const double rowing_rad[LEGSIM_HEXAPOD_LEGS],
                                          const double feedforward_n[LEGSIM_HEXAPOD_LEGS][2],
                                          const double feedforward_nm[LEGSIM_HEXAPOD_LEGS]);

/* Each command slot on its own (a leg controller's mix: some legs by force, others by servo):
 * per leg its upper and lower actuators and its rowing motor (slots 0, 1, 2), each
 * LEGSIM_HEXAPOD_KEEP (its command unchanged), _FORCE (value: N, |F| <= its max_force; N m,
 * |tau| <= max_torque) or _SERVO (value: the set-point, m or rad, within its stroke; feedforward
 * N or N m within the same bounds as a force), as legsim_hexapod_command and _command_pose. The
 * statuses as theirs, and LEGSIM_ERR_BAD_INPUT for another mode; all or nothing. */
typedef enum legsim_hexapod_mode {
  LEGSIM_HEXAPOD_KEEP = 0,
  LEGSIM_HEXAPOD_FORCE = 1,
  LEGSIM_HEXAPOD_SERVO = 2
} legsim_hexapod_mode;

typedef struct legsim_hexapod_commands {
  int32_t mode[LEGSIM_HEXAPOD_LEGS][3];
  double value[LEGSIM_HEXAPOD_LEGS][3];
  double feedforward[LEGSIM_HEXAPOD_LEGS][3];
} legsim_hexapod_commands;

legsim_status legsim_hexapod_command_each(legsim_hexapod_sim *sim, const legsim_hexapod_commands *commands);

/* n_steps (>= 1) steps of h_s (s, in (0, 0.1]). Stops at the first step that fails, the state
 * that of the last step taken: LEGSIM_ERR_SINGULAR (a leg at a dead centre), _NOT_CONVERGED (the
 * projection, an impact's contact problem, generalized-alpha's iterations), _DIVERGED (a
 * non-finite result), _CONTACT (friction making a normal force arbitrary, modes that do not
 * settle, more than 64 events in a step). */
legsim_status legsim_hexapod_step(legsim_hexapod_sim *sim, double h_s, int32_t n_steps);

/* The integrator of the steps from the next on: LEGSIM_INTEGRATOR_RK4 (legsim_hexapod_sim_init's)
 * or LEGSIM_INTEGRATOR_GENERALIZED_ALPHA (second order, rho_inf 0.8, its iterations explicit in
 * the rows: docs/design/spatial.md; a step may also fail with _NOT_CONVERGED when they do not
 * converge). LEGSIM_ERR_BAD_INPUT for another value (nothing changed). */
legsim_status legsim_hexapod_set_integrator(legsim_hexapod_sim *sim, legsim_integrator integrator);

/* A launch, before the first step: the box's velocity (m/s, world) and angular velocity (rad/s,
 * its frame), every body carried with it rigidly; a contact point stuck at the start that this
 * moves along the ground slides; the modes checked again as at legsim_hexapod_sim_init, the
 * commands kept. LEGSIM_ERR_BAD_INPUT for a value not finite or past LEGSIM_MAX_RATE_MPS, or
 * after a step; else as legsim_hexapod_sim_init's (the start then left as it was). */
legsim_status legsim_hexapod_set_velocity(legsim_hexapod_sim *sim, const double velocity_mps[3],
                                          const double omega_radps[3]);

typedef struct legsim_hexapod_state {
  double t_s;
  double box_m[3], box_quat[4];                  /* the box's centre (world) and rotation */
  double box_velocity_mps[3], box_omega_radps[3]; /* world; its angular velocity in its frame */
  double rowing_rad[LEGSIM_HEXAPOD_LEGS];        /* each yoke's angle from its heading */
  double length_m[LEGSIM_HEXAPOD_LEGS][2];       /* each leg's actuators */
  double foot_m[LEGSIM_HEXAPOD_LEGS][3];         /* each foot (world) */
  double foot_force_n[LEGSIM_HEXAPOD_LEGS][3];   /* the ground's force on each foot (world; 0 when free) */
  double actuator_force_n[LEGSIM_HEXAPOD_LEGS][2]; /* each actuator's axial force (its command's) */
  double rowing_torque_nm[LEGSIM_HEXAPOD_LEGS];   /* each rowing motor's torque at its yoke */
  int32_t foot_state[LEGSIM_HEXAPOD_LEGS];       /* legsim_contact_state */
  double kinetic_energy_j;
  int32_t events;                                /* contact events located in the last step */
  int32_t impacts;                               /* touchdowns since the start */
  /* the contact problems on the cones since the start (each impact's, each decision of the stuck
   * feet's modes): how many, how many the projected Gauss-Seidel fallback finished, the most
   * iterations and the largest residual (the natural map's, / (1 + |q|)); every one converged
   * (one that does not fails its step with LEGSIM_ERR_NOT_CONVERGED) */
  int32_t cone_solved, cone_by_sweeps, cone_max_iterations;
  double cone_max_residual;
  /* which strokes sit on a stop: -1 at its min, 1 at its max, 0 inside; arrivals on a stop (each
   * an inelastic impact) since the start */
  int32_t actuator_stop[LEGSIM_HEXAPOD_LEGS][2];
  int32_t rowing_stop[LEGSIM_HEXAPOD_LEGS];
  int32_t stop_impacts;
  double length_rate_mps[LEGSIM_HEXAPOD_LEGS][2]; /* each actuator's rate (the servos' l') */
  double rowing_rate_radps[LEGSIM_HEXAPOD_LEGS];   /* each yoke's angle's rate */
  /* the box's own contact points (legsim_hexapod_desc's box_contact_m, n_box_contacts of them;
   * the rest 0), as the feet: each point (world), the ground's force on it (world; 0 when free),
   * its legsim_contact_state */
  int32_t n_box_contacts;
  double box_contact_m[LEGSIM_HEXAPOD_MAX_BOX_CONTACTS][3];
  double box_contact_force_n[LEGSIM_HEXAPOD_MAX_BOX_CONTACTS][3];
  int32_t box_contact_state[LEGSIM_HEXAPOD_MAX_BOX_CONTACTS];
} legsim_hexapod_state;

legsim_status legsim_hexapod_get_state(const legsim_hexapod_sim *sim, legsim_hexapod_state *out);

/* Every body's pose (world): its centre (m) and unit quaternion (w, x, y, z), 7 numbers each, in
 * the order the box, then per leg its yoke and its bars in its file's order (a bar's axis, from
 * its proximal to its distal end, is its frame's x). *n: the bodies' number; capacity: pose's
 * room in bodies (LEGSIM_ERR_CAPACITY, nothing written, when short). */
legsim_status legsim_hexapod_body_poses(const legsim_hexapod_sim *sim, double *pose, int32_t capacity, int32_t *n);

/* ---- inverse dynamics along the gait ------------------------------------------ */
/* The forces that make the hexapod follow the tripod gait exactly (docs/design/spatial.md,
 * "Inverse dynamics along the gait"): at a time, the robot where the gait's set-points put it
 * (legsim_hexapod_gait_setpoints, each leg assembled at its lengths from its file's stand), the box
 * on its plan (level at box_height_m, over the world's origin heading along x at t = 0, moving at
 * the gait's constant twist: forward at step_length / (duty period), turning at turn / (duty
 * period)), the standing feet stuck where they are, the swinging feet on their curves; its
 * velocities and accelerations from the rows (the box's and the standing feet's motion exact, a
 * swinging foot's rates in the box's frame by five-point differences of its curve over 3e-4
 * periods: 3e-8 m/s^2 from the exact curve); then M a + J^T lambda = Q + B u solved by statics'
 * rule with the inertial forces -M a as loads: the stance feet take the resultant with the least
 * sum of squares of their forces, each leg then its own equilibrium. */
#define LEGSIM_HEXAPOD_MAX_LEG_JOINTS 11 /* the hip's, then the leg file's (at most 10) */

typedef struct legsim_hexapod_inverse {
  double t_s;
  double box_m[3], box_quat[4];                   /* the plan's box (world; w, x, y, z) */
  double box_velocity_mps[3], box_omega_radps[3];  /* world; box frame */
  int32_t stance[LEGSIM_HEXAPOD_LEGS];            /* the gait's: 1 standing (stuck), 0 swinging */
  double foot_m[LEGSIM_HEXAPOD_LEGS][3];          /* each foot (world) */
  double foot_velocity_mps[LEGSIM_HEXAPOD_LEGS][3];     /* world: 0 standing */
  double foot_acceleration_mps2[LEGSIM_HEXAPOD_LEGS][3]; /* world: 0 standing */
  double actuator_force_n[LEGSIM_HEXAPOD_LEGS][2];  /* each leg's two actuators' axial forces */
  double rowing_torque_nm[LEGSIM_HEXAPOD_LEGS];     /* each yoke's, about its hip axis */
  double foot_force_n[LEGSIM_HEXAPOD_LEGS][3];      /* the ground's force on each foot (world; 0 swinging) */
  /* |F_t| / N on the file's ground plane (its normal): above the ground's mu_static the gait needs
   * more friction than the ground has; 0 swinging */
  double cone_ratio[LEGSIM_HEXAPOD_LEGS];
  /* every joint's reaction on its first body: per leg the hip (on its yoke; the box takes the
   * opposite), then its file's joints in order (on the joint's first body); the force (world) and
   * the moment about the joint's point (world) */
  int32_t n_joints[LEGSIM_HEXAPOD_LEGS];
  double joint_force_n[LEGSIM_HEXAPOD_LEGS][LEGSIM_HEXAPOD_MAX_LEG_JOINTS][3];
  double joint_moment_nm[LEGSIM_HEXAPOD_LEGS][LEGSIM_HEXAPOD_MAX_LEG_JOINTS][3];
} legsim_hexapod_inverse;

/* Bytes of storage legsim_hexapod_inverse_dynamics needs (aligned to LEGSIM_STORAGE_ALIGN). */
size_t legsim_hexapod_inverse_storage_size(void);

/* The inverse dynamics at t_s (s; the gait repeats, the box's plan does not). Statuses as
 * legsim_hexapod_gait_setpoints' (the gait, its targets, a leg's assembly; LEGSIM_ERR_BAD_INPUT
 * also for a swing shorter than the stencil: a duty within 1.2e-3 of 1), LEGSIM_ERR_SINGULAR (a
 * leg at a dead centre), LEGSIM_ERR_NO_EQUILIBRIUM (a stance foot that would have to pull: its
 * force not against gravity, or not along the ground's normal). *out is written only on
 * LEGSIM_OK. */
legsim_status legsim_hexapod_inverse_dynamics(const legsim_hexapod_desc *h, const legsim_hexapod_gait *gait,
                                              double t_s, void *storage, size_t storage_bytes,
                                              legsim_hexapod_inverse *out);

/* The plan's state at t_s that legsim_hexapod_inverse_dynamics solves at: every body's pose (7
 * numbers: centre, unit quaternion), velocity and acceleration (6 each: world, then angular in the
 * body's frame), bodies as legsim_hexapod_body_poses'. *n: their number; capacity: room in bodies
 * (LEGSIM_ERR_CAPACITY when short). Statuses otherwise as legsim_hexapod_inverse_dynamics'. */
legsim_status legsim_hexapod_gait_state(const legsim_hexapod_desc *h, const legsim_hexapod_gait *gait, double t_s,
                                        void *storage, size_t storage_bytes, double *q, double *v, double *a,
                                        int32_t capacity, int32_t *n);

#ifdef __cplusplus
}
#endif

#endif
