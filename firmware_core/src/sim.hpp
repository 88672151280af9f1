// Internal types of the core: the compiled model (constant), the per-sim data
// (state and preallocated workspace), and the functions over them. Everything
// is fixed-size; the capacities come from legsim/config.h.
#pragma once

#include <array>
#include <type_traits>

#include <Eigen/Core>
#include <cstdint>

#include "legsim/legsim.h"
#include "planar/body.hpp"

namespace legsim {

constexpr int kMaxCoords = kBodyDof * kMaxBodies;
constexpr int kMaxJoints = LEGSIM_MAX_JOINTS;
constexpr int kMaxActuators = LEGSIM_MAX_ACTUATORS;
constexpr int kMaxForces = LEGSIM_MAX_FORCES;
constexpr int kMaxRows = LEGSIM_MAX_ROWS;
constexpr int kMaxContacts = LEGSIM_CONTACT_SLOTS;  // >= 1 slot; the model's count may be 0
// Entries of J W J^T that can be non-zero: a row touches at most two bodies,
// and a body appears in a handful of rows, so this is far below kMaxRows^2. A
// robot's box is in every hip row (12 of them for two legs): 286 pairs for the
// two-leg robot with all four stops, against 6 * 43 = 258 the one-leg rule gives. With
// more legs (one foot contact each) the box's 6 hip rows a leg pair with one another:
// (6 L)^2 / 2 more, 648 for six legs (1,290 pairs in all for models/robot6.toml).
constexpr int kMaxPairs = (LEGSIM_MAX_CONTACTS > 0 ? 8 : 6) * kMaxRows +
                          (LEGSIM_MAX_CONTACTS > 2 ? 18 * LEGSIM_MAX_CONTACTS * LEGSIM_MAX_CONTACTS : 0);

// A build for three or more contacts (legs) can factor J W J^T with a body that all the
// legs share, the box, as a Schur complement (Layout::separator); its rows' coefficients on
// that body are kept with the factor. A smaller build keeps one slot.
constexpr int kSeparatorRows = LEGSIM_MAX_CONTACTS >= 3 ? kMaxRows : 1;

// A row's index or position.
using RowIndex = uint16_t;
// Entries of the factor's packed storage (Factor::a): L's envelope, row after row, of the
// largest layout the build must hold (LEGSIM_FACTOR_ENTRIES; 0: the full lower triangle of
// kMaxRows rows, which every layout fits). layout_finish refuses a layout that needs more
// (LEGSIM_ERR_CAPACITY).
constexpr int kFactorEntries =
    LEGSIM_FACTOR_ENTRIES > 0 ? LEGSIM_FACTOR_ENTRIES : kMaxRows * (kMaxRows + 1) / 2;
static_assert(kFactorEntries <= 65535, "factor offsets (Layout::row, Pair::aij) are 16-bit");

using VecQ = Eigen::Matrix<real, kMaxCoords, 1>;
using VecR = Eigen::Matrix<real, kMaxRows, 1>;

struct Kernel;  // generated joint-block kernels (kernel.hpp)

// ---- compiled model (constant after legsim_init) ----
struct Joint {
  legsim_joint_kind kind;
  int a, b;        // body indices; b = LEGSIM_FRAME for revolute_to_frame
  Vec2 pa, pb;     // body-fixed (xi, eta), or world point when on the frame
  int row, nrows;  // first row and count in the joint block of the Jacobian
};

struct Actuator {
  int joint, cyl, rod;
  real offset_m;  // (L_cyl + L_rod) / 2: length = (r_rod - r_cyl) . u_cyl + offset
  real lmin, lmax, fmax, kp, kd;
};

struct ForceElement {
  legsim_force_kind kind;
  int a, b;
  Vec2 pa, pb;
  real k, c, l0;
};

// A foot point that can touch the ground line.
struct Contact {
  int body;
  Vec2 point;  // body-fixed (xi, eta)
};

// The compiled model and its options (as MuJoCo's mjModel holds mjOption): functions over a
// sim take (const Model &, Data &); legsim_set_options is the one call that writes opt.
struct Model {
  const legsim_model_desc *desc;
  legsim_options opt;
  real step_h;  // opt.step_s as real, set with opt: no conversion in every step (soft-float on a Cortex-M4F)
  int nb, nq, nj, na, nf, nc;
  int m;  // joint equations
  real mass[kMaxCoords];  // diagonal of M: (m, m, J) per body
  real minv[kMaxCoords];
  real length[kMaxBodies];
  Vec2 gravity;
  VecQ gravity_force;  // m g per coordinate (N; 0 for the angles and past nq): Q's first term
  Joint joint[kMaxJoints];
  Actuator act[kMaxActuators];
  ForceElement force[kMaxForces];
  int foot_body;
  Vec2 foot_point;
  real unit_weight[kMaxCoords];  // W = I for geometric (assembly) corrections
  Contact contact[kMaxContacts];
  Vec2 ground_point, ground_t, ground_n;  // the line, its tangent and upward normal
  real mu_s, mu_k;
  const Kernel *kernel;  // the generated kernel of this structure, or nullptr (kernel_find)
  const Kernel *stance_kernel;  // its stance kernel: the joints and every contact stuck (or nullptr)
};

// ---- rows of the constraint system: joint equations plus drivers ----
// Contact rows: the foot's normal gap, its tangential offset from the stick point,
// and (assembly on the ground) the midpoint of two feet along the line.
// FootPoint: the leg's foot at a point (legsim_assemble_foot; sub 0: x, 1: y).
enum class RowKind : uint8_t { Joint, ActuatorLength, Coordinate, ContactNormal, ContactTangent, ContactMid, FootPoint };

// Which rows a contact contributes to a layout.
enum ContactRows : uint8_t { kContactNone = 0, kContactNormal = 1, kContactStuck = 2 };

struct RowSource {
  RowKind kind;
  uint8_t index;  // joint, actuator or coordinate index
  uint8_t sub;    // equation within the joint
};

// (J W J^T)(i, j) gets coef[i][si] . w . coef[j][sj]; the offsets into the
// flattened coefficient and matrix arrays are worked out once, at layout time.
struct Pair {
  uint16_t ci, cj;  // (kBodyDof * (2 * row + slot)) of each side
  uint16_t aij;     // entry (i, j) of the factor's storage (by position): Layout::row[i] + j
};

// Which equations make up the system and which entries of J W J^T can be
// non-zero: constant for a scene, built once, not per step.
struct Layout {
  int m;
  RowSource src[kMaxRows];
  int8_t body[kMaxRows][2];  // -1: no body in this slot
  int npairs;
  Pair pair[kMaxPairs];
  // J W J^T is factored in an elimination order of its rows (row i sits at position
  // perm[i]; layout_finish: reverse Cuthill-McKee or minimum degree, whichever leaves the
  // factor fewer entries), which keeps the work small.
  RowIndex perm[kMaxRows];
  RowIndex first[kMaxRows];  // by position: the first non-zero column, the envelope
  // The factor's packed storage (Factor::a) by position: entry (i, j) at row[i] + j, row i
  // holding columns first[i] .. i; a row after a generated kernel's block that reaches into it holds columns
  // 0 .. i (eliminate's forward solve through the block writes them all). entries: the
  // storage it needs (with a separator, at least the full lower triangle of factor_build's
  // dense fallback), at most kFactorEntries.
  uint16_t row[kMaxRows];
  int entries;
  // A body (the box of a robot on three or more legs) whose removal splits the rows into
  // groups that share no other body, or -1. With one, the pairs and the envelope are the
  // ones of B = J W J^T less the body's share U W_b U^T (U: each row's coefficients on it),
  // block diagonal by group, each group's rows together; the solves add the body back as a
  // Schur complement (linear_solve.cpp), so the work grows linearly with the groups.
  int8_t separator;
  // The rows ordered together (layout_finish): a stance's joint and contact rows (all
  // stuck, nothing else), or 0: the joint rows alone, the other rows after them.
  RowIndex block;
  // Its actuator rows are stroke stops (Data::stop_drivers; the actuators still
  // push) rather than drivers that replace the actuators (Data::drivers).
  bool stops;
  // Sliding contacts (Data::dyn only): their normal row also carries the friction
  // force mu_k lambda_n along the tangent, which makes the system non-symmetric.
  uint8_t nslide;
  uint8_t slide_contact[kMaxContacts];
  RowIndex slide_row[kMaxContacts];
  // Rows beyond the coordinates (Data::dyn only: max(0, m - nq), stops_layout): that many
  // rows must depend on the others (e.g. both feet stuck with all four stops: 40 rows on 39
  // coordinates, the self-stress of the stance), and factor_build drops that many dependent
  // rows (the basic solution: their multipliers 0); one more vanishing pivot is singular.
  RowIndex surplus;
  const Kernel *kernel;  // the model's kernel serves rows 0 .. kernel->mj-1 (nullptr: none)
  // The path of each solve on this layout, chosen once when it is built (layout_path): the
  // kernel whose generated solve serves the whole system (its block is all the rows: the
  // joint rows alone, or a stance), or nullptr: the general path (with the kernel's block
  // where it has one). The solvers call through it and never ask again.
  struct Path {
    const Kernel *dynamics;  // Kernel::dynamics, the forward-dynamics solve
    const Kernel *newton;    // Kernel::newton, generalized-alpha's Newton iteration
    const Kernel *factored;  // Kernel::factored, the solve with a given factor
    const Kernel *reduced;   // Kernel::accelerations and Kernel::end, RK4 in the reduced system
#if LEGSIM_MAX_CONTACTS >= 2
    // Kernel::accelerations, RK4's stages: reduced's, or with one contact sliding and the
    // others stuck after the joint rows, that stance's (kernel_find_slide)
    const Kernel *stage;
#endif
  } path;
};

// Values of the rows at one (q, qd): sparse Jacobian, residual, right-hand sides.
struct Rows {
  real coef[kMaxRows][2][kBodyDof];  // d(row)/d(x, y, phi) of each slot's body
  VecR phi;                   // Phi(q)
  VecR nu;                    // Phi_q qd = nu (driver rates)
  VecR gamma;                 // Phi_q qdd = gamma
};

struct DriverValues {
  real length[kMaxActuators], rate[kMaxActuators], accel[kMaxActuators];
  legsim_coord_driver coord[LEGSIM_MAX_POSE_DRIVERS];
  int ncoord;
  real stick[kMaxContacts];  // a stuck contact's stick point: its coordinate along the line (m)
  real feet_mid;             // ContactMid target (m along the line)
  real foot[2];              // FootPoint targets (m, world)
};

// Relative pivot of J W J^T below which J is taken as rank deficient.
#if LEGSIM_USE_FLOAT
constexpr real kPivotFloor = real(1e-6);
#else
constexpr real kPivotFloor = real(1e-13);
#endif

// L D L^T factor of J W J^T (L below the diagonal in place, 1 / D on it) with its condition
// estimate, packed: entry (i, j) (by position) at a[row[i] + j], j in first[i] .. i.
struct Factor {
  std::array<real, kFactorEntries> a;
  int m;
  RowIndex perm[kMaxRows];   // row -> position, as in the layout
  RowIndex first[kMaxRows];  // the envelope (fill-in stays inside it)
  uint16_t row[kMaxRows];    // each position's offset into a, as in the layout
  // 1 / D by position side by side, as a's diagonal (which is a gather): factor_build's
  // (eliminate), for a system with rows after the kernel's block or without a kernel (m >
  // the block's rows); a kernel's system alone (its fused solves write a only) has none.
  real dinv[kMaxRows];
  real condition;
  // The rows the factorization dropped as dependent on the rows before them in its order
  // (at most Layout::surplus of them, by row index): 1 / D is 0 there, so a solve gives
  // them a zero multiplier and satisfies their equations through the others'.
  int nredundant;
  RowIndex redundant[kMaxRows];
  const Kernel *kernel;  // positions 0 .. kernel->mj-1 are the kernel's block (nullptr: none)
  // Layout::separator's body, or -1; with one, a holds the factor of B and, by position, u
  // the rows' coefficients on the body, z = B^-1 u, wb its weights and s the factor of
  // S = W_b^-1 + u^T z (L D L^T, 1 / D on the diagonal): (B + u W_b u^T)^-1 = B^-1 - z S^-1 z^T.
  int separator;
  real u[kSeparatorRows][kBodyDof], z[kSeparatorRows][kBodyDof];
  real wb[kBodyDof], s[kBodyDof][kBodyDof];
  // This is the sim's state's factor exactly, as a fresh factorization would give it (RK4's
  // whole-system end solve left it, the positions not projected after; its reduced end,
  // Kernel::end, keeps none), and untouched since: factor_order
  // and factor_build, which every write of a factor goes through, clear it, and so does a
  // refused call (Snapshot::restore: all-or-nothing restores the state, not the workspace).
  // A restart after a changed command solves with it (state_refresh): the same values
  // either way, so a refused call changes no later result.
  bool of_state;
};

struct ActuatorState {
  legsim_actuator_mode mode;
  real setpoint;    // N or m
  real force;       // axial force it applies in the current state, N
  real stop_force;  // axial force of the stroke stop it rests on (0 when free), N
  double stop_time; // s: when it last arrived on a stroke stop (located inside the step, or
                    // the (part) step's end for one taken there); 0 before any
};

struct ContactData {
  uint8_t state;     // legsim_contact_state
  int8_t slip_dir;   // SLIDING: the sign of the sliding velocity along the tangent (+1, -1)
  real normal, tangential;  // N, T of the last solve (0 when free)
  real impulse[2];   // the last impact's (normal, tangential) impulse on the foot, N s
  uint32_t events;   // the contact legsim_event bits this contact raised since legsim_clear_events
  double event_time; // s: the time of its last contact event (located inside the step, or the
                     // step's end for one taken there); 0 before any
};

// Contact events a step located inside itself (bit k: contact k), applied at their time by
// contact_transitions: touchdown (a free foot), lift-off (a closed one), stick to slip (a
// stuck one, against its T), slip to stick (a sliding one).
struct ContactEvents {
  uint32_t touchdown, liftoff, slip, stick;
};

// Generalized-alpha's predictor: the polynomial order of its extrapolation of the
// accelerations, the past steps it keeps (integrator_generalized_alpha.cpp: none in float,
// whose accelerations' round-off an extrapolation amplifies). An array has at least one slot.
constexpr int kPredictorOrder = LEGSIM_USE_FLOAT ? 0 : 2;
constexpr int kPastSlots = kPredictorOrder > 0 ? kPredictorOrder : 1;

struct Data {
  double t;
  uint64_t steps;
  // t is origin_t + (steps - origin_steps) * origin_step_s, not a running sum of h (whose
  // round-off grows with the steps): the origin moves when the time is set or h changes.
  double origin_t, origin_step_s;
  uint64_t origin_steps;
  bool assembled;
  bool derivative_valid;  // qdd and lambda belong to the current state and commands (RK4's start)
  bool history_valid;     // qdd and acc_aux are the generalized-alpha history of this state
  // Since qdd was last valid, only the forcing changed (commands, loads: commands_changed),
  // not the state, the rows or the options: the restart keeps what depends on the state alone.
  bool forcing_only;
  // The contact modes were checked at the current state (a step's end): false after a change
  // from outside (state_refresh), so the next step checks them at its start first.
  bool modes_checked;
  VecQ q, qd, qdd;
  VecQ acc_aux;  // generalized-alpha auxiliary acceleration
  // Generalized-alpha's predictor and convergence test: the accelerations of the steps
  // before this state's (qdd_past[0] the last), past_steps of them (0 .. kPredictorOrder)
  // since the history started, and the Newton contraction's estimate newton_eta =
  // theta / (1 - theta) in [kEtaMin, 1] (1: none).
  VecQ qdd_past[kPastSlots];
  int past_steps;
  real newton_eta;
  VecR lambda;   // multipliers of the last dynamics/statics solve
  legsim_reaction reaction[kMaxJoints];
  ActuatorState act[kMaxActuators];
  real force_value[kMaxForces][2];
  uint32_t force_active;  // bit f: force element f may apply a force (a spring, or a load not 0)
  legsim_report report;
  legsim_report failure;  // the figures of the last call that failed (legsim_failure_report)
  uint32_t stroke_mask;

  // workspace
  Layout joints;  // the joint equations only
  Layout dyn;     // the forward-dynamics system: the joints plus the stops in use
  uint32_t stop_mask;         // actuators resting on a stroke stop (the active set)
  DriverValues stop_drivers;  // their stop lengths (rate and acceleration 0), the stick points
  ContactData contact[kMaxContacts];
  Layout work;    // joints plus drivers, for assembly and driven analyses
  int32_t work_mask;  // the actuator set Layout work was built for; -1: none or with coordinates
  Rows rows;
  TrigCache trig;
#if defined(__x86_64__)
  // RK4's reduced stage solves' own: on x86-64 their copy that fuses multiply-adds
  // (kernel.hpp, LEGSIM_STAGE_TARGETS) computes sin/cos with other roundings, and a cache's
  // values must not depend on which code filled it (stage_trig below)
  TrigCache stage_trig_cache;
#endif
  Factor factor;
  bool end_projected;  // RK4: the last step's end needed projecting (its next end takes the general sequence)
  // generalized-alpha: its last step ended in the generated end solve (Kernel::end_factored),
  // which left the end state's reactions and forces: generalized_alpha_reactions, right
  // after it, takes them. Whatever changes q or qd in between clears it.
  bool end_solved;
  DriverValues drivers;
  VecQ force_q;  // generalized applied forces Q
  VecQ tq[4], tv[3];
  VecR rhs;
#if LEGSIM_WITH_CONTACT
  // coupled_solve's Woodbury columns A^-1 U (one per sliding contact) of its last call, with
  // d.factor and the rows it had: another solve on them pays no column again (coupled_resolve)
  VecR slide_z[kMaxContacts];
#endif
};

// The TrigCache of RK4's reduced stage solves (Kernel::accelerations).
inline TrigCache *stage_trig(Data &d) {
#if defined(__x86_64__)
  return &d.stage_trig_cache;
#else
  return &d.trig;
#endif
}

// legsim_init writes kSimMagic last, when the sim is complete; every entry point
// checks it, so storage that never went through legsim_init is refused alike.
constexpr uint32_t kSimMagic = 0x4C454753u;  // "LEGS"

struct Sim {
  uint32_t magic;
  Model model;
  Data data;
};

// Everything a failed call must leave as it found it (the state, what the next
// step starts from, and the report): calls that can fail half-way work on the
// live state and put this back.
struct Snapshot {
  // generalized-alpha's history (acc_aux, qdd_past) too: only under it (RK4 calls never
  // write it, state_refresh)
  bool history;
  VecQ q, qd, qdd, acc_aux, qdd_past[kPastSlots];
  int past_steps;
  real newton_eta;
  VecR lambda;
  legsim_reaction reaction[kMaxJoints];
  real act_force[kMaxActuators], stop_force[kMaxActuators], stop_length[kMaxActuators];
  double stop_time[kMaxActuators];
  ContactData contact[kMaxContacts];
  real stick[kMaxContacts];
  legsim_report report;
  double t, origin_t, origin_step_s;
  uint64_t steps, origin_steps;
  uint32_t stroke_mask, stop_mask;
  bool assembled, derivative_valid, history_valid, forcing_only;
  bool end_projected;  // which way RK4's next end goes: its values differ to round-off

  explicit Snapshot(const Model &m, const Data &d);  // the model's coordinates, joints and actuators
  void restore(const Model &m, Data &d) const;
};

// Runs a call on the live state; on failure, the state is put back as it was.
// On success the outputs are checked once: a non-finite or absurd result is
// refused (LEGSIM_ERR_DIVERGED) rather than passed on.
legsim_status outputs_check(const Model &m, const Data &d);
template <typename F>
legsim_status all_or_nothing(const Model &m, Data &d, F &&call) {
  const Snapshot before(m, d);
  legsim_status s;
  if constexpr (std::is_invocable_v<F, const Snapshot &>)
    s = call(before);  // a call that goes back to its start part-way (a step cut at an event)
  else
    s = call();
  if (s == LEGSIM_OK) s = outputs_check(m, d);
  if (s != LEGSIM_OK) {
    d.failure = d.report;  // where the solver stopped, kept apart
    before.restore(m, d);
  }
  return s;
}

// Positions and velocities a sim may hold: finite and within LEGSIM_MAX_ABS_Q/QD.
bool state_sane(const VecQ &q, const VecQ &qd, int n);
// q and qd finite (the cheap test a step starts with).
bool state_finite(const VecQ &q, const VecQ &qd, int n);

// ---- system/step.cpp: the step's stages ----
// n_steps steps, each all-or-nothing; the sim is assembled, its state finite.
legsim_status steps_run(const Model &m, Data &d, int32_t n_steps);
// The step's first stage alone, all or nothing: the contact modes checked at the current state.
legsim_status contact_modes_check(const Model &m, Data &d);
// After the state changed outside a step: accelerations, multipliers and reactions at the
// new state, and a fresh start of generalized-alpha's history. forcing_only: only a command
// or a load changed (the state, its rows and the options as they were).
legsim_status state_refresh(const Model &m, Data &d, bool forcing_only = false);
// A changed command or load: both integrators restart from the accelerations under the new
// forces (the same value sent again changes nothing).
void commands_changed(Data &d);
// The state, its rows or the options changed outside a step: a full restart.
void state_changed(Data &d);

// ---- model.cpp ----
legsim_status model_check(const legsim_model_desc *desc, char *msg, size_t len);
legsim_status model_compile(const legsim_model_desc *desc, Model &model);

// ---- constraints.cpp ----
// Builds a layout of the joint equations followed by driver rows for the
// actuators in actuator_mask and for ncoord coordinate drivers.
// contacts (NULL: none): per contact its ContactRows; mid: one ContactMid row (assembly);
// foot: the two FootPoint rows (legsim_assemble_foot).
legsim_status layout_build(const Model &model, uint32_t actuator_mask, int ncoord, Layout &out,
                           const uint8_t *contacts = nullptr, bool mid = false, bool foot = false);
// The layout's solve path (Layout::path) from its kernel and rows (layout_build's last step).
void layout_path(Layout &out);
// Completes a layout once the coordinate drivers are known: lists the non-zeros of J W J^T.
legsim_status layout_finish(Layout &out, const DriverValues &drivers);
// layout_finish's last step, with its order and envelope: the factor's storage by position
// (Layout::row, entries; positions before p0 are a generated kernel's block) and each pair's
// offset into it, or LEGSIM_ERR_CAPACITY with out untouched where it needs more than
// capacity entries.
legsim_status layout_storage(Layout &out, int p0, int capacity);
// Evaluates Phi, the Jacobian and the velocity/acceleration right-hand sides.
// trig (optional): the sim's TrigCache.
void rows_eval(const Model &model, const Layout &layout, const DriverValues &drivers, const VecQ &q,
               const VecQ &qd, Rows &rows, TrigCache *trig = nullptr);
real rows_max_residual(const Layout &layout, const Rows &rows);
void actuator_length(const Model &model, int a, const VecQ &q, const VecQ &qd, real &length,
                     real &rate, TrigCache *trig = nullptr);

// ---- linear_solve.cpp ----
// Factors J W J^T (W diagonal, n values). LEGSIM_ERR_SINGULAR on a vanishing pivot.
legsim_status factor_build(const Layout &layout, const Rows &rows, const real *w, Factor &f);
void factor_order(const Layout &layout, Factor &f);  // f's size, order and kernel from layout
void factor_solve(const Factor &f, VecR &x);  // in place
// cond(J W^1/2) by power iterations on the factor: for reports that decide (assembly);
// Factor::condition is the cheap pivot-spread estimate of every factorization.
real factor_condition(const Factor &f);
// y = J^T x (n values), J x (m values)
void jt_times(const Model &model, const Layout &layout, const Rows &rows, const VecR &x, VecQ &y);
void j_times(const Layout &layout, const Rows &rows, const VecQ &x, VecR &y);
// x <- x - W J^T (J W J^T)^-1 (J x - target): the W-weighted projection onto J x = target.
void project(const Model &model, const Layout &layout, const Rows &rows, const Factor &f,
             const real *w, const VecR &target, VecQ &x, VecR &tmp);

// ---- forces.cpp ----
// Q: gravity, force elements, actuator forces (by the current commands), per options.
// Data::force_active from the model's force elements and their values (after a change).
void force_active_update(const Model &model, Data &d);
void applied_forces(const Model &model, uint32_t disable, Data &d, const VecQ &q,
                    const VecQ &qd, VecQ &force_q);

// The axial force of an actuator from its command at the cylinder's axis u = (s, -c) and
// normal n = (c, s): d = r_rod - r_cyl, dd its rate, w the cylinder's angular velocity;
// arm = d . n, the length's derivative by the cylinder's angle. A force command is the
// force; a length command goes through the servo (PD on length and rate, saturated at
// max_force: a real cylinder cannot push harder, and the event says so). The arithmetic
// is actuator_length's (constraints.cpp), term for term.
void raise_event(Data &d, uint32_t ev);  // status.cpp
inline real axial_force(const Actuator &ac, const ActuatorState &st, Data &d, real s, real c, real dx,
                        real dy, real dvx, real dvy, real w, real arm) {
  if (st.mode == LEGSIM_ACTUATOR_FORCE) return st.setpoint;
  const real len = (dx * s + dy * -c) + ac.offset_m;
  const real rate = (dvx * s + dvy * -c) + w * arm;
  real f = ac.kp * (st.setpoint - len) - ac.kd * rate;
  if (f > ac.fmax || f < -ac.fmax) {
    f = f > 0 ? ac.fmax : -ac.fmax;
    raise_event(d, LEGSIM_EVENT_FORCE_SATURATED);
  }
  return f;
}
// The same, kept as the actuator's force (applied_forces' per actuator; the generated
// reduced solves call it, kernel_codegen.py).
inline real actuator_force(const Actuator &ac, ActuatorState &st, Data &d, real s, real c, real dx, real dy,
                           real dvx, real dvy, real w) {
  st.force = axial_force(ac, st, d, s, c, dx, dy, dvx, dvy, w, dx * c + dy * s);
  return st.force;
}

// ---- forces.cpp (with applied_forces, which shares its servo law) ----
// Axial force of each actuator from its command (servo law for length mode).
void actuator_forces_update(const Model &model, const legsim_options &opt, Data &d, const VecQ &q,
                            const VecQ &qd);
// ---- actuators.cpp ----
// Stroke stops: an actuator past an end (or in `arriving`: located on it, to the location's
// tolerance) is put on it `into` s after the step's start d.t (inelastic impact) and held there by a length row
// in the dynamics; one whose stop would have to pull is let go. changed: the active set
// changed (derivative anew).
legsim_status stroke_limits_enforce(const Model &m, Data &d, bool &changed, real into, uint32_t arriving = 0);
legsim_status stroke_stops_release(const Model &m, Data &d, bool &changed);
// Data::work for the joints plus length drivers of the actuators in mask (built
// once per set: analyses called along a motion do not rebuild it).
legsim_status work_layout(const Model &m, Data &d, uint32_t mask);
// Actuator a's length at q (m), for the stroke checks and their event functions.
real stroke_length(const Model &m, int a, const VecQ &q, TrigCache *trig);
// Rebuilds Data::dyn for Data::stop_mask and the contacts' states.
legsim_status stops_layout(const Model &m, Data &d);

// ---- contact.cpp ----
// World position and velocity of contact k's foot point.
void contact_point(const Model &model, int k, const VecQ &q, const VecQ &qd, Vec2 &pos, Vec2 &vel);
// The rows of each contact in the dynamics (stuck: 2, free: 0), for layout_build.
void contact_rows_of_states(const Model &model, const Data &d, uint8_t *rows);
// Lists the sliding contacts' normal rows in layout (Layout::nslide).
void contact_slides_mark(const Model &model, const Data &d, Layout &layout);
// N and T of the stuck contacts from the multipliers of Data::dyn (rows after the stops).
void contact_forces_update(const Model &m, Data &d);
// After a step: touchdown, lift-off, stick to slip, slip to stick (docs/design/robot-on-ground.md
// section 2), each raised as an event; changed: the contact modes or the state changed.
// located: the events found inside the step, applied first whatever the tolerances say;
// at: the time the transitions take place (s), kept as each changed contact's event_time.
legsim_status contact_transitions(const Model &m, Data &d, bool &changed, double at, const ContactEvents *located = nullptr);
// Every contact free (a state set or assembled from outside).
void contacts_free(Data &d);
// N and T of each contact with rows in layout, from the multipliers lambda (0 for the others).
void contact_forces_of_layout(const Model &model, const Layout &layout, const VecR &lambda,
                              real *normal, real *tangential);

// ---- dynamics.cpp ----
// qdd and lambda from M qdd + J^T lambda = Q, J qdd = gamma, for layout rows.
// rows_ready: d.rows and d.factor already hold this (q, qd) on this layout. keep = false:
// the caller needs only qdd and lambda, so d.rows and d.factor need not be written (a
// layout of the joint rows alone with a generated kernel skips them).
// reaction not null: the joints' reactions too (reactions_from_multipliers; the fused solve
// computes them from its locals), for the caller's all-or-nothing to put back on failure.
legsim_status dynamics_solve(const Model &m, Data &d, const Layout &layout, const VecQ &q, const VecQ &qd, VecQ &qdd,
                             bool rows_ready = false, bool keep = true, legsim_reaction *reaction = nullptr);
// The options' disabled forces for a solve on layout. Driven analyses: the drivers supply the
// actuator forces. Stops act besides them.
inline uint32_t layout_disable(const Model &m, const Layout &layout) {
  uint32_t disable = m.opt.disable;
  if (layout.m > m.m && !layout.stops) disable |= LEGSIM_DISABLE_ACTUATORS;
  return disable;
}
// Whether force elements act in a solve with these disabled forces (their forces may depend
// on the velocities).
inline bool force_elements_act(const Data &d, uint32_t disable) {
  return LEGSIM_WITH_FORCE_ELEMENTS && d.force_active && !(disable & LEGSIM_DISABLE_FORCE_ELEMENTS);
}
// RK4's stage solve, qdd alone at (q, qd) on layout: in the reduced system where the
// layout's kernel has it (reduced_available, kernel.hpp; Kernel::accelerations: the same qdd
// as dynamics_solve's to round-off, and as it the actuators' forces and events; no
// multipliers or factor), else dynamics_solve without keep.
// The stages of a step call it through dynamics_stage (kernel.hpp), with what they share
// decided once.
legsim_status dynamics_stage_solve(const Model &m, Data &d, const Layout &layout, const VecQ &q, const VecQ &qd, VecQ &qdd);
legsim_status dynamics_state_update(const Model &m, Data &d);  // qdd, lambda, reactions at the current state
// The same, with d.rows and d.factor (J M^-1 J^T) those of the state, for a caller that reads
// the factor (the contacts' Delassus matrix): the solve that keeps them, never RK4's reduced end.
legsim_status dynamics_state_factored(const Model &m, Data &d);
// The friction of the sliding contacts of layout (contact.cpp): y += sign * sum_i f_i
// lambda[row_i], f_i the generalized friction force per unit normal multiplier (dir mu_k
// G_t^T, at q); friction_column: f_i of contact k, its body's kBodyDof entries.
void friction_add(const Model &m, const Data &d, const Layout &layout, const VecQ &q, const VecR &lambda,
                  real sign, VecQ &y);
void friction_column(const Model &m, const Data &d, int k, const VecQ &q, real (&f)[kBodyDof]);
// friction_column from its body's sin s and cos c (a generated stage passes its own pair):
// mu_k dir (t, t . perp(p_x u + p_y n)), u = (s, -c), n = (c, s).
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline void friction_column_at(const Model &m, const Data &d, int k, real s, real c, real (&f)[kBodyDof]) {
  const Vec2 &p = m.contact[k].point;
  const real spx = p.x() * s + p.y() * c, spy = p.x() * -c + p.y() * s;
  const real g = real(d.contact[k].slip_dir) * m.mu_k;
  f[0] = g * m.ground_t.x();
  f[1] = g * m.ground_t.y();
  f[2] = g * (m.ground_t.x() * -spy + m.ground_t.y() * spx);
}
// Solves (J M^-1 J^T - J M^-1 F E^T) x = rhs in place with the factor of J M^-1 J^T (F: the
// sliding contacts' friction columns, E: their normal rows) by the Woodbury identity: one
// extra solve per sliding contact. LEGSIM_ERR_CONTACT when the coupled matrix is singular.
legsim_status coupled_solve(const Model &m, Data &d, const Layout &layout, const VecQ &q, VecR &x);
// The same system again, on the columns and factor of coupled_solve's last call (Data::slide_z).
legsim_status coupled_resolve(Data &d, const Layout &layout, VecR &x);
void stop_forces_update(const Model &m, Data &d);  // the stops' forces from the multipliers of Data::dyn
// lambda and reactions at the current state; the accelerations go to qdd
// factor_ready: Data::factor already holds J M^-1 J^T of Data::dyn at (or, within
// the Newton tolerance, near) the current q; only the rows are evaluated anew.
// keep_factor: Data::rows and Data::factor left those of the state (not RK4's reduced end,
// which keeps neither: dynamics_state_factored).
legsim_status dynamics_state_reactions(const Model &m, Data &d, VecQ &qdd, bool factor_ready = false, bool keep_factor = false);

// ---- assembly.cpp ----
// Project: the per-step projection (stroke stops too): cheap, no polishing, no
// condition estimate. Assemble: the analyses' assembly: at least one Newton
// iteration, the 2-norm condition where it lands, dead centres refused.
// rows_ready: data.rows already holds the layout's rows at q (at any velocities: Phi and
// the Jacobian do not depend on them), so the first iteration does not evaluate them.
enum class AssemblyMode { Project, Assemble };
legsim_status assemble(const Model &m, Data &d, const Layout &layout, const DriverValues &drivers, VecQ &q,
                       const real *w, AssemblyMode mode, bool rows_ready = false);

// ---- kinematics.cpp ----
legsim_status velocity_solve(const Model &m, Data &d, const Layout &layout, VecQ &qd);
// The largest |J v| of the rows, J v in jv: the velocities' distance from J v = nu for the rows
// of forward dynamics, whose rates nu are 0 (joints, stops, closed contacts).
real velocity_drift(const Layout &layout, const Rows &rows, const VecQ &v, VecR &jv);
legsim_status acceleration_solve(const Model &m, Data &d, const Layout &layout, VecQ &qdd);

// ---- reactions.cpp ----
void reactions_from_multipliers(const Model &model, const Rows &rows, const VecR &lambda,
                                legsim_reaction *out);

// ---- integrators ----
// One step of h seconds (the options' step_s, or a part of it: a step cut at an event).
legsim_status rk4_step(const Model &m, Data &d, real h);
// tol: the Newton iteration's (the options' newton_tol; a part step's own, step.cpp)
legsim_status generalized_alpha_step(const Model &m, Data &d, real h, real tol);
legsim_status generalized_alpha_reactions(const Model &m, Data &d);

// ---- statics.cpp / inverse_dynamics.cpp ----
legsim_status statics_solve(const Model &m, Data &d, real *actuator_force);
legsim_status statics_sweep(const Model &m, Data &d, int n_grid, legsim_worst_case *out);
legsim_status inverse_dynamics_solve(const Model &m, Data &d, const real *length, const real *rate,
                                     const real *accel, real *actuator_force);
// With feet on the ground (held contacts) or followers: the actuators in follow are not
// driven, their length, rate and acceleration follow and are written back (section 8).
legsim_status inverse_dynamics_ground_solve(const Model &m, Data &d, uint32_t follow, real *length, real *rate,
                                            real *accel, real *actuator_force);
// Every actuator driven at d.drivers, the contacts that are not free held (two: combined by
// options.statics_rule), at (d.q, d.qd) whose accelerations must be target: d.lambda, d.rows,
// each contact's N and T (statics.cpp, shared with the inverse dynamics).
legsim_status held_contacts_solve(const Model &m, Data &d, const VecQ &target, real *normal, real *tangential);
// Reactions, actuator forces (F = -lambda_driver) and contact forces from that solve.
legsim_status driven_outputs(const Model &m, Data &d, const real *normal, const real *tangential, real *actuator_force);

// ---- helpers ----
inline bool finite(real x) { return std::isfinite(x); }
bool all_finite(const VecQ &v, int n);
void raise_event(Data &d, uint32_t ev);

}  // namespace legsim
