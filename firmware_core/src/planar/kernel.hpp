// Generated fixed-sparsity kernels for the joint block of a model's constraint system.
//
// Every layout starts with the joint equations (rows 0 .. mj-1), and their sparsity is
// fixed by the model's structure (which joint kind joins which bodies). For the models
// compiled in (models/*.toml), firmware_core/tools/kernel_codegen.py generates at build
// time straight-line code for that block: the rows (one sin/cos per body), J W J^T and its
// L D L^T factor in an elimination order and fill fixed at generation time, the
// triangular solves, J x and J^T x, and for a model's main system the whole dynamics solve
// and a generalized-alpha Newton iteration fused. Rows that change at run time (stroke
// stops, drivers, contacts) follow the joint block in the factor's order; the general
// envelope code factors and solves them against the generated block (block elimination:
// their rows of L are the Schur complement's), so one kernel serves every row set. A model
// with contacts also has a stance kernel: its joint rows and both rows of every stuck
// contact, used when that is the whole system. The factor keeps the general storage
// (Factor::a by position), so every other use of it (condition estimate, projections) is
// unchanged.
//
// A kernel is chosen by structure (kernel_find): bodies, joint kinds and the bodies each
// joint joins. The geometry (joint points) is read from the Model at run time, so a model
// of the same structure, compiled in or loaded, gets the same kernel, and its results
// agree with the general path's to round-off (tests/core/test_kernels.c).
#pragma once

#include "sim.hpp"

// The generated kernels and the integrators' per-coordinate loops are compiled twice on
// x86-64 with GCC and glibc (LEGSIM_KERNEL_AVX, CMake's option of that name): for the
// baseline ISA and for AVX, the copy picked at load time by the CPU (an ifunc). AVX's
// three-operand instructions drop most of the register copies that straight-line code
// needs in two-operand SSE2, and its loops take four doubles at a time; neither copy has
// FMA, so both give the same values bit for bit (tests/core/test_kernels.c checks the
// copy in use against the general path).
// RK4's stages (LEGSIM_STAGE_TARGETS: the reduced solve and the stage loops), which agree
// with the general path to round-off only anyway, also come in an x86-64-v3 copy (AVX2
// and FMA, any x86-64 CPU since about 2015; LEGSIM_KERNEL_FMA) that fuses a * b + c where
// it can (-ffp-contract=fast on these files; only that copy has FMA instructions): one
// rounding fewer per fused pair, 5 % fewer instructions per RK4 step of the leg. Not the
// rest: generalized-alpha's Newton iteration stops at its tolerance, and one rounding more
// or less anywhere moves its results by that tolerance (2e-7 relative over 1 s), not by
// round-off.
#if LEGSIM_KERNEL_AVX && defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__GLIBC__)
#define LEGSIM_KERNEL_TARGETS __attribute__((target_clones("avx", "default")))
#if LEGSIM_KERNEL_FMA
#define LEGSIM_STAGE_TARGETS __attribute__((target_clones("arch=x86-64-v3", "avx", "default")))
#else
#define LEGSIM_STAGE_TARGETS LEGSIM_KERNEL_TARGETS
#endif
#else
#define LEGSIM_KERNEL_TARGETS
#define LEGSIM_STAGE_TARGETS
#endif

namespace legsim {

struct Kernel {
  const char *name;  // the model and variant it was generated from
  // the structure it serves
  int nb, nj;
  const int8_t (*joint)[3];  // per joint: kind, body a, body b (LEGSIM_FRAME: -1)
  // A stance kernel (nc > 0) serves the joint rows and both rows of every contact, all
  // stuck (normal, tangential), in the general layout's order: the robot standing.
  int nc;
  const int8_t *contact_body;  // per contact: its body
  // per actuator: its prismatic joint, cylinder and rod (the reduced solves apply their
  // forces: a model whose actuators differ has no kernel with them)
  int na;
  const int8_t (*actuator)[3];
  int mj;                    // joint rows
  const uint8_t *perm;       // joint row -> position in the factor
  const uint8_t *first;      // by position: first column of L's envelope (fill included)
  // Rows 0 .. mj-1 of Phi, the Jacobian, nu and gamma at (q, qd), from the row units
  // (rows.hpp) as the general path calls them (the same values to the last bit);
  // sin/cos through trig.
  void (*rows)(const Model &model, const DriverValues &dv, const VecQ &q, const VecQ &qd, Rows &rows,
               TrigCache *trig);
  // J W J^T's block (positions 0 .. mj-1 of its lower envelope, zeros included) assembled
  // and factored in place (L D L^T, linear_solve.cpp's storage). max_diag comes in as the largest diagonal entry of the rows
  // after the block (0: none) and leaves as the largest of all; pmin, pmax: the pivots'
  // range. false: a diagonal that is not positive and finite, or a pivot <= kPivotFloor
  // times max_diag.
  bool (*factor)(const Rows &rows, const real *w, real *a, real &max_diag, real &pmin, real &pmax);
  // L y = y (from position `from` on, y zero before it) and L^T y = y on positions 0 .. mj-1
  // (L unit lower triangular: D is the caller's).
  void (*forward)(const real *a, real *y, int from);
  void (*backward)(const real *a, real *y);
  // L D L^T x = x in row order, for a system of the block alone (factor_solve's permutation
  // folded in).
  void (*solve)(const real *a, real *x);
  // y[i] = (J x)_i for the joint rows; y = J_joint^T x (all nq values written).
  void (*j_times)(const Rows &rows, const real *x, real *y);
  void (*jt_times)(const Rows &rows, const real *x, real *y);
  // The fused solves below are generated for a model's main system only (nullptr else:
  // the pieces above serve; kernel_codegen.py --fused-max-rows).
  // The whole forward-dynamics solve of a system of the joint rows alone (dynamics_solve:
  // M qdd + J^T lambda = force, J qdd = gamma) fused, its values in locals: lambda and qdd;
  // the factor's condition estimate, the rows and the factor (by position) only where asked
  // (condition, keep_rows, keep_a not null: RK4's stages need none of them, and the pivots'
  // range is a third of a Cortex-M4's factorization), and the joints' reactions where
  // reaction is not null (reactions_from_multipliers). LEGSIM_ERR_SINGULAR (condition
  // infinite) or LEGSIM_ERR_DIVERGED (qdd not finite) as the general path.
  legsim_status (*dynamics)(const Model &model, const DriverValues &dv, const VecQ &q, const VecQ &qd, const VecQ &force,
                            TrigCache *trig, Rows *keep_rows, real *keep_a, real *condition, VecR &lambda,
                            VecQ &qdd, legsim_reaction *reaction);
  // One Newton iteration of generalized-alpha on a system of the joint rows alone
  // (integrator_generalized_alpha.cpp), fused: at (q, qd) with the applied forces force,
  // the iterate's accelerations qdd1 and multipliers lambda, res = J^T lambda + M qdd1 -
  // force, dlambda from (J M^-1 J^T) dlambda = beta' Phi - J M^-1 res, jt_dlambda = J^T
  // dlambda; rows.phi and the factor (a, by position) kept. LEGSIM_ERR_SINGULAR (condition
  // infinite) as factor_build. Cross builds' (flash); host builds have newton_fused instead.
  legsim_status (*newton)(const Model &model, const DriverValues &dv, const VecQ &q, const VecQ &qd, const VecQ &force,
                          TrigCache *trig, const real *qdd1, const VecR &lambda, real bprime, Rows &rows,
                          real *a, real &condition, real *res, VecR &dlambda, real *jt_dlambda);
  // The forward-dynamics solve of a system of the joint rows alone with its factor given
  // (a, by position: generalized-alpha's last iteration's), fused: dynamics_solve's
  // rows_ready path at (q, qd), lambda and qdd, and with reaction not null the joints'
  // reactions (reactions_from_multipliers). LEGSIM_ERR_DIVERGED (qdd not finite) as the
  // general path.
  legsim_status (*factored)(const Model &model, const DriverValues &dv, const VecQ &q, const VecQ &qd,
                            const VecQ &force, TrigCache *trig, const real *a, VecR &lambda, VecQ &qdd,
                            legsim_reaction *reaction);
  // RK4's stage solve: the accelerations qdd alone of a system of the joint rows alone (a
  // stance kernel's: and its stuck contacts' rows), in fewer rows where a body is pinned to
  // the frame by one revolute joint: it keeps its angle alone (its pin's rows and
  // multipliers drop out; kernel_codegen.py's Reduced says how), and on a stance each stuck
  // foot likewise, pinned to the ground by its two contact rows (rows_pin: the robot's 36
  // rows become 32). The same accelerations as dynamics' to round-off, not bit for bit; no
  // multipliers, rows, factor or condition estimate. LEGSIM_ERR_SINGULAR on a pivot <=
  // kPivotFloor times the whole J M^-1 J^T's largest diagonal entry (dynamics' floor: both
  // paths order a joint's pin rows so that the reduced pivots are the whole factor's later
  // ones; a stance's stages factor in an order of their own, whose pivots are another
  // elimination's of the same matrix), LEGSIM_ERR_DIVERGED (qdd not finite). nullptr where
  // not generated (dynamics serves).
  // The applied forces: base (gravity and the force elements, applied_forces' without the
  // actuators) and, with actuators, each actuator's axial force from its command
  // (actuator_force: its force and events into data) from the solve's own sin/cos (grid_trig,
  // sim.hpp). The same for end, which writes the sum into data.force_q too, as
  // applied_forces would leave it (a stage's is read by no one).
  legsim_status (*accelerations)(const Model &model, const DriverValues &dv, const VecQ &q, const VecQ &qd,
                                 const VecQ &base, Data &data, bool actuators, TrigCache *trig, VecQ &qdd);
  // RK4's end of a step (and its restart at a state) in the joints' reduced system (a stance's
  // with its contact rows: the condition estimate is the whole factor's): the largest
  // |Phi| (residual, as rows_max_residual) and |J qd| (drift, as velocity_drift) for its
  // projection test. Where the residual is past tol, or the drift is and not project: no
  // more, LEGSIM_OK (the step starts over). Where the drift is past tol and project: qd
  // projected onto J qd = 0 (M-weighted, as project; drift then 0), written only when the
  // whole call succeeds; base must not depend on qd then. Then besides qdd the condition
  // estimate from the pivots (the reduced system's and the pins' own, the whole factor's to
  // round-off), every row's multiplier (a pin's from its body's x and y equations) and,
  // reaction not null, the joints' reactions. No rows or factor kept. Statuses as
  // accelerations'. nullptr with it.
  legsim_status (*end)(const Model &model, const DriverValues &dv, const VecQ &q, VecQ &qd,
                       const VecQ &base, Data &data, bool actuators, TrigCache *trig, real tol,
                       bool project, real &residual, real &drift, real &condition, VecR &lambda,
                       VecQ &qdd, legsim_reaction *reaction);
  // Generalized-alpha's end of a step: end's work on the factor given (a, by position: the
  // last Newton iteration's, at an iterate within tol of q) instead of its own, for a
  // structure whose reduced system is the whole one (no pinned body: the robot's). |J qd|
  // past tol: qd projected (M-weighted, onto J qd = 0), a second time where the first pass
  // leaves it past tol (the factor is not q's own); drift: |J qd| after. Then every row's
  // multiplier and, reaction not null, the joints' reactions (not qdd: the step keeps the
  // iteration's); no condition estimate; qd written only when the whole call succeeds (the
  // multipliers, reactions, data.force_q and the actuators' forces may be written before a
  // failure: the caller's fallback writes them again). LEGSIM_ERR_DIVERGED (Q or a
  // multiplier not finite: the end's qdd would not be). nullptr elsewhere (and in a build
  // without generalized-alpha).
  legsim_status (*end_factored)(const Model &model, const DriverValues &dv, const VecQ &q, VecQ &qd,
                                const VecQ &base, Data &data, bool actuators, TrigCache *trig, const real *a,
                                real tol, real &drift, VecR &lambda, legsim_reaction *reaction);
  // newton's iteration with the applied forces Q = base and, with actuators, the
  // actuators' forces from the rows' own sin/cos (as accelerations'; written into
  // data.force_q as applied_forces leaves it), which also gives the residual, the largest
  // |Phi| (rows_max_residual's): applied_forces' and rows_max_residual's work (a tenth of
  // the leg's step) in the iteration's own locals. Host builds' (a Cortex-M4F pays flash
  // and instructions for it); nullptr with newton.
  legsim_status (*newton_fused)(const Model &model, const DriverValues &dv, const VecQ &q, const VecQ &qd,
                                const VecQ &base, Data &data, bool actuators, TrigCache *trig, const real *qdd1,
                                const VecR &lambda, real bprime, Rows &rows, real *a, real &condition,
                                real &residual, real *res, VecR &dlambda, real *jt_dlambda);
};

// Whether RK4's solves on layout take the reduced system (dynamics_stage, dynamics_end: the
// joint rows alone, a kernel with Kernel::accelerations and Kernel::end, which come
// together): never in a build without them (LEGSIM_KERNELS_REDUCED 0: their callers are
// left out too).
inline bool reduced_available(const Layout &layout) {
#if LEGSIM_KERNELS_REDUCED
  return layout.path.reduced != nullptr;  // chosen when the layout was built (layout_path)
#else
  (void)layout;
  return false;
#endif
}

// RK4's solves of one step on a layout (dynamics_stage, dynamics_end): what stays the same
// from solve to solve, decided once (stage_plan): where the reduced system serves and its
// base forces are gravity alone (no force element acts), its kernel, driver values, base
// and whether the actuators act; else kernel null (each solve decides: dynamics_stage_solve,
// sim.hpp, and reduced_base).
struct StagePlan {
  const Layout *layout;
  const Kernel *kernel;
  const DriverValues *dv;
  const VecQ *base;
  bool actuators;
};
// Whether RK4's stages on layout take a generated solve (Kernel::accelerations: the reduced
// system's, or a stance's with one foot sliding): layout.path.stage, chosen when it was built
// by the joints' structure; a sliding stance's also needs the model's stance kernel (its
// actuators' joints checked: the stages apply their forces).
inline bool stage_available(const Model &m, const Layout &layout) {
#if LEGSIM_KERNELS_REDUCED && LEGSIM_MAX_CONTACTS >= 2
  return layout.path.stage && (layout.path.stage == layout.path.reduced || m.stance_kernel);
#else
  (void)m;
  return reduced_available(layout);
#endif
}
// Its kernel where stage_available.
inline const Kernel *stage_kernel(const Layout &layout) {
#if LEGSIM_MAX_CONTACTS >= 2
  return layout.path.stage;
#else
  return layout.path.reduced;
#endif
}
inline StagePlan stage_plan(const Model &m, Data &d, const Layout &layout) {
  StagePlan p{&layout, nullptr, nullptr, nullptr, false};
  if (!stage_available(m, layout)) return p;
  const uint32_t disable = layout_disable(m, layout);
  if (force_elements_act(d, disable) || (disable & LEGSIM_DISABLE_GRAVITY)) return p;
  p.kernel = stage_kernel(layout);
  p.dv = layout.stops ? &d.stop_drivers : &d.drivers;
  p.base = &m.gravity_force;
  p.actuators = !(disable & LEGSIM_DISABLE_ACTUATORS);
  return p;
}
// RK4's end of a step and its restart in the reduced system (Kernel::end), on the plan's
// layout where reduced_available: residual and drift, the largest |Phi| and |J qd|; where
// the drift is past tol, project and no force element acts (their forces may depend on qd),
// qd projected onto J qd = 0 and drift 0; unless the residual or the drift is past tol then
// (no more) qdd, the multipliers (into lambda), the condition estimate into the report and
// reaction where not null. No rows or factor kept.
legsim_status dynamics_end(const Model &m, Data &d, const StagePlan &plan, const VecQ &q, VecQ &qd, VecQ &qdd, VecR &lambda,
                           legsim_reaction *reaction, real tol, bool project, real &residual, real &drift);
// A stage's solve in the reduced system (Kernel::accelerations): neither multipliers nor a
// factor (the step's end has its own); a singular matrix reports an infinite condition, as
// dynamics_solve.
inline legsim_status reduced_stage(const Model &m, Data &d, const Kernel &kern, const DriverValues &dv, const VecQ &base,
                                   bool actuators, const VecQ &q, const VecQ &qd, VecQ &qdd) {
  const legsim_status s = kern.accelerations(m, dv, q, qd, base, d, actuators, stage_trig(d), qdd);
  if (s == LEGSIM_ERR_SINGULAR) d.report.condition = real(INFINITY);
  return s;
}
// RK4's stage solve at (q, qd): dynamics_stage_solve's, with the plan's decisions.
inline legsim_status dynamics_stage(const Model &m, Data &d, const StagePlan &plan, const VecQ &q, const VecQ &qd, VecQ &qdd) {
  if (!plan.kernel) return dynamics_stage_solve(m, d, *plan.layout, q, qd, qdd);
  return reduced_stage(m, d, *plan.kernel, *plan.dv, *plan.base, plan.actuators, q, qd, qdd);
}

// Two rows on one body whose coefficients there are E (1, 0, -s_y; 0, 1, s_x) with E an
// invertible 2 x 2 matrix (a stuck contact's normal and tangential rows: E's rows are the
// ground's normal and tangent) hold its point s still as a pin to the frame does: the pin
// units of rows.hpp serve it with s (sx, sy) and the pin rows' gamma E^-1 (ga, gb) (g0, g1),
// here from the rows' own coefficients (a: the first row's x, y, phi; b: the second's) and
// gammas. RK4's reduced stages on a stance (kernel_codegen.py's Reduced).
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline void rows_pin(real a0, real a1, real a2, real b0, real b1, real b2, real ga, real gb, real &sx, real &sy,
                     real &g0, real &g1) {
  const real id = 1 / (a0 * b1 - a1 * b0);
  // E^-1 (a2, b2) = (-s_y, s_x)
  sx = (a0 * b2 - b0 * a2) * id;
  sy = -(b1 * a2 - a1 * b2) * id;
  g0 = (b1 * ga - a1 * gb) * id;
  g1 = (a0 * gb - b0 * ga) * id;
}

// The generated kernel for this model's structure (stance: its stance kernel), or nullptr
// (the general path).
const Kernel *kernel_find(const Model &model, bool stance = false);
// The stages (Kernel::accelerations alone) of the stance of joint kernel joints' structure
// with contact slide sliding (its normal row alone, mu_k N along the ground on its
// multiplier: one Sherman-Morrison column, the general path's woodbury) and the others
// stuck, or nullptr.
const Kernel *kernel_find_slide(const Kernel *joints, int slide);

}  // namespace legsim

// For tests and benchmarks (not in legsim.h): on = 0 puts a sim on the general path,
// on = 1 back on its model's kernel (if it has one). Returns 1 when the sim now uses a
// kernel, 0 when not, -1 for a null or uninitialized sim.
extern "C" int legsim_kernel_use(legsim_sim *sim, int on);
