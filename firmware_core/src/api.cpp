// The plain C API: argument checks, state bookkeeping, and dispatch to the
// analyses. Bad input is refused with a status before anything changes; a call
// that fails half-way puts everything back (all_or_nothing), and a result that
// is not finite is refused rather than passed on (outputs_check).
#include <cstring>
#include <new>
#include <type_traits>

#include "sim.hpp"

using namespace legsim;

static_assert(alignof(Sim) <= LEGSIM_STORAGE_ALIGN, "raise LEGSIM_STORAGE_ALIGN");
static_assert(LEGSIM_MAX_ROWS <= 255, "row indices are stored in 8 bits");
static_assert(LEGSIM_MAX_ACTUATORS <= 31, "actuator sets are 32-bit masks");
static_assert(sizeof(legsim_reaction) == 3 * sizeof(legsim_real), "a reaction is 3 reals, no padding");

namespace legsim {

namespace {
// The first n values of a fixed-size vector (the rest is never read): a snapshot copies what
// the model uses, not the capacity. A build sized to its model (a firmware image) copies the
// whole vector: straight-line code, cheaper than the library's memcpy on a Cortex-M4.
template <typename V>
void copy_head(V &dst, const V &src, int n) {
  if (n == V::SizeAtCompileTime)
    dst = src;
  else
    std::memcpy(dst.data(), src.data(), sizeof(real) * size_t(n));
}
}  // namespace

Snapshot::Snapshot(const Sim &sim)
    : history(sim.opt.integrator == LEGSIM_INTEGRATOR_GENERALIZED_ALPHA), past_steps(sim.data.past_steps), newton_eta(sim.data.newton_eta), report(sim.data.report),
      t(sim.data.t), steps(sim.data.steps), stroke_mask(sim.data.stroke_mask), stop_mask(sim.data.stop_mask),
      assembled(sim.data.assembled), derivative_valid(sim.data.derivative_valid),
      history_valid(sim.data.history_valid), forcing_only(sim.data.forcing_only),
      end_projected(sim.data.end_projected) {
  const Data &d = sim.data;
  const Model &m = sim.model;
  copy_head(q, d.q, m.nq);
  copy_head(qd, d.qd, m.nq);
  copy_head(qdd, d.qdd, m.nq);
  if (history) {
    copy_head(acc_aux, d.acc_aux, m.nq);
    for (int k = 0; k < kPredictorOrder; ++k) copy_head(qdd_past[k], d.qdd_past[k], m.nq);
  }
  lambda = d.lambda;  // whole: the solves of every layout write it
  std::memcpy(reaction, d.reaction, sizeof(legsim_reaction) * size_t(m.nj));
  for (int a = 0; a < m.na; ++a) {
    act_force[a] = d.act[a].force;
    stop_force[a] = d.act[a].stop_force;
    stop_length[a] = d.stop_drivers.length[a];
  }
  for (int k = 0; k < kMaxContacts; ++k) {
    contact[k] = d.contact[k];
    stick[k] = d.stop_drivers.stick[k];
  }
}

void Snapshot::restore(Sim &sim) const {
  Data &d = sim.data;
  const Model &m = sim.model;
  copy_head(d.q, q, m.nq);
  copy_head(d.qd, qd, m.nq);
  copy_head(d.qdd, qdd, m.nq);
  if (history) {
    copy_head(d.acc_aux, acc_aux, m.nq);
    for (int k = 0; k < kPredictorOrder; ++k) copy_head(d.qdd_past[k], qdd_past[k], m.nq);
  }
  d.past_steps = past_steps;
  d.newton_eta = newton_eta;
  d.lambda = lambda;
  d.report = report;
  std::memcpy(d.reaction, reaction, sizeof(legsim_reaction) * size_t(m.nj));
  for (int a = 0; a < m.na; ++a) {
    d.act[a].force = act_force[a];
    d.act[a].stop_force = stop_force[a];
    d.stop_drivers.length[a] = stop_length[a];
    d.stop_drivers.rate[a] = d.stop_drivers.accel[a] = 0;
  }
  bool rows_changed = d.stop_mask != stop_mask;
  for (int k = 0; k < kMaxContacts; ++k) {
    rows_changed = rows_changed || d.contact[k].state != contact[k].state;
    d.contact[k] = contact[k];
    d.stop_drivers.stick[k] = stick[k];
  }
  if (rows_changed) {
    d.stop_mask = stop_mask;
    stops_layout(sim);  // the same rows as before: cannot fail
  }
  d.t = t;
  d.steps = steps;
  d.stroke_mask = stroke_mask;
  d.assembled = assembled;
  d.derivative_valid = derivative_valid;
  d.history_valid = history_valid;
  d.forcing_only = forcing_only;
  d.end_projected = end_projected;
  // The workspace is not put back: a refused step may have run to its end, its factor that
  // of a state now undone (the output check refuses after the solves).
  d.factor.of_state = false;
}

namespace {
// Fixed-size blocks of four: Eigen keeps them in vector registers (unaligned loads).
using Block4 = Eigen::Array<real, 4, 1>;
using ConstBlock4 = Eigen::Map<const Block4>;

// The sum of n values, in blocks of eight (the tests below do not depend on the order).
real block_sum(const real *x, int n) {
  Block4 z0 = Block4::Zero(), z1 = Block4::Zero();
  int k = 0;
  for (; k + 8 <= n; k += 8) {
    z0 += ConstBlock4(x + k);
    z1 += ConstBlock4(x + k + 4);
  }
  real z = (z0 + z1).sum();
  for (; k < n; ++k) z += x[k];
  return z;
}

// 0 for finite values, NaN if any is not (x * 0 is NaN for an infinity or a NaN).
real nan_unless_finite(const real *x, int n) {
  real z = 0;
  for (int k = 0; k < n; ++k) z += x[k] * real(0);
  return z;
}

// The values a call's caller can read besides the state and qdd, summed: finite only if
// each is (an infinity or a NaN anywhere makes it not). Exact: times 0, so that the rare
// finite values whose sum overflows are told apart from a non-finite one.
template <bool Exact>
real outputs_sum(const Sim &sim) {
  const Model &m = sim.model;
  const Data &d = sim.data;
  const auto sum = [](const real *x, int n) { return Exact ? nan_unless_finite(x, n) : block_sum(x, n); };
  const real o = Exact ? real(0) : real(1);
  real z = sum(d.lambda.data(), kMaxRows) + sum(&d.reaction[0].force_n[0], 3 * m.nj);  // 3 reals each
  z += d.report.residual * o + d.report.condition * o;
  for (int a = 0; a < m.na; ++a) z += d.act[a].force * o + d.act[a].stop_force * o;
  for (int c = 0; c < m.nc; ++c) z += d.contact[c].normal * o + d.contact[c].tangential * o;
  return z;
}
// q and qd finite: their sum is unless one is not (or the rare finite values overflow it,
// told apart by nan_unless_finite). Every call leaves the state sane (outputs_check), so
// this is the cheap common case: one pass in blocks.
bool state_finite(const VecQ &q, const VecQ &qd, int n) {
  Block4 z = Block4::Zero();
  int k = 0;
  for (; k + 4 <= n; k += 4) z += ConstBlock4(q.data() + k) + ConstBlock4(qd.data() + k);
  real sum = z.sum();
  for (; k < n; ++k) sum += q[k] + qd[k];
  if (sum - sum == 0) return true;
  const real exact = nan_unless_finite(q.data(), n) + nan_unless_finite(qd.data(), n);
  return exact == exact;
}
}  // namespace

bool state_sane(const VecQ &q, const VecQ &qd, int n) {
  for (int k = 0; k < n; ++k)
    if (!(std::abs(q[k]) < real(LEGSIM_MAX_ABS_Q)) || !(std::abs(qd[k]) < real(LEGSIM_MAX_ABS_QD)))
      return false;
  return true;
}

// Once per call (per step): everything a caller can read is finite, the state sane.
legsim_status outputs_check(const Sim &sim) {
  const Data &d = sim.data;
  const int n = sim.model.nq;
  // One pass over the coordinates, four at a time (partial sums in vector registers): |q|
  // and |qd| summed, and qdd. Every |x| is below its bound when their sum is (a NaN fails
  // that test too): the common case; past it, state_sane looks at each value.
  const real *q = d.q.data(), *qd = d.qd.data(), *qdd = d.qdd.data();
  Block4 aq = Block4::Zero(), av = Block4::Zero(), za = Block4::Zero();
  int k = 0;
  for (; k + 4 <= n; k += 4) {
    aq += ConstBlock4(q + k).abs();
    av += ConstBlock4(qd + k).abs();
    za += ConstBlock4(qdd + k);
  }
  real sq = aq.sum(), sv = av.sum(), sa = za.sum();
  for (; k < n; ++k) {
    sq += std::abs(q[k]);
    sv += std::abs(qd[k]);
    sa += qdd[k];
  }
  if (!(sq < real(LEGSIM_MAX_ABS_Q) && sv < real(LEGSIM_MAX_ABS_QD)) && !state_sane(d.q, d.qd, n))
    return LEGSIM_ERR_DIVERGED;
  const real z = sa + outputs_sum<false>(sim);
  if (z - z == 0) return LEGSIM_OK;  // finite
  const real exact = nan_unless_finite(qdd, n) + outputs_sum<true>(sim);
  return exact == exact ? LEGSIM_OK : LEGSIM_ERR_DIVERGED;
}

}  // namespace legsim

namespace {

Sim *as_sim(legsim_sim *s) { return reinterpret_cast<Sim *>(s); }
const Sim *as_sim(const legsim_sim *s) { return reinterpret_cast<const Sim *>(s); }

// One rule for every entry point: a handle is a sim only if legsim_init made it.
legsim_status sim_check(const legsim_sim *s) {
  if (!s) return LEGSIM_ERR_NULL;
  if (reinterpret_cast<uintptr_t>(s) % LEGSIM_STORAGE_ALIGN) return LEGSIM_ERR_STORAGE;
  uint32_t magic;
  std::memcpy(&magic, s, sizeof magic);  // Sim::magic is the first member
  return magic == kSimMagic ? LEGSIM_OK : LEGSIM_ERR_STORAGE;
}
bool sim_ok(const legsim_sim *s) { return sim_check(s) == LEGSIM_OK; }

#define CHECK_SIM(h)                                 \
  do {                                               \
    const legsim_status check_ = sim_check(h);       \
    if (check_ != LEGSIM_OK) return check_;          \
  } while (0)

// The integer a C caller stored in an enum field, read as such: a value outside
// the enum must be checked before it is ever held in the C++ enum type.
template <typename E>
long long raw_enum(const E &field) {
  std::underlying_type_t<E> v;
  std::memcpy(&v, &field, sizeof v);
  return static_cast<long long>(v);
}

constexpr uint32_t kAllDisableFlags =
    LEGSIM_DISABLE_GRAVITY | LEGSIM_DISABLE_FORCE_ELEMENTS | LEGSIM_DISABLE_REACTIONS |
    LEGSIM_DISABLE_PROJECTION | LEGSIM_DISABLE_ACTUATORS | LEGSIM_DISABLE_STROKE_LIMITS;

bool within(double x, double lo, double hi) { return x >= lo && x <= hi; }  // false for NaN

legsim_status options_check(const legsim_options *o) {
  if (!o) return LEGSIM_ERR_NULL;
  const long long integ = raw_enum(o->integrator);
  if (integ != LEGSIM_INTEGRATOR_RK4 && integ != LEGSIM_INTEGRATOR_GENERALIZED_ALPHA)
    return LEGSIM_ERR_BAD_INPUT;
  if (!within(o->step_s, LEGSIM_MIN_STEP_S, LEGSIM_MAX_STEP_S)) return LEGSIM_ERR_BAD_INPUT;
  if (!within(o->rho_inf, 0, 1)) return LEGSIM_ERR_BAD_INPUT;
  if (o->max_newton_iter < 1 || o->max_newton_iter > LEGSIM_MAX_NEWTON_ITER) return LEGSIM_ERR_BAD_INPUT;
  if (!within(o->newton_tol, LEGSIM_MIN_NEWTON_TOL, LEGSIM_MAX_NEWTON_TOL)) return LEGSIM_ERR_BAD_INPUT;
  if (o->disable & ~kAllDisableFlags) return LEGSIM_ERR_BAD_INPUT;
  const long long rule = raw_enum(o->statics_rule);
  if (rule != LEGSIM_STATICS_EQUAL_FRICTION && rule != LEGSIM_STATICS_MIN_TANGENTIAL)
    return LEGSIM_ERR_BAD_INPUT;
  const long long law = raw_enum(o->contact_law);
  if (law != LEGSIM_CONTACT_LCP && law != LEGSIM_CONTACT_PAPER) return LEGSIM_ERR_BAD_INPUT;
  const bool compiled = integ == LEGSIM_INTEGRATOR_RK4 ? LEGSIM_WITH_RK4 : LEGSIM_WITH_GENERALIZED_ALPHA;
  return compiled ? LEGSIM_OK : LEGSIM_ERR_DISABLED;
}

bool same_options(const legsim_options &a, const legsim_options &b) {
  return a.integrator == b.integrator && a.step_s == b.step_s && a.disable == b.disable &&
         a.rho_inf == b.rho_inf && a.max_newton_iter == b.max_newton_iter &&
         a.newton_tol == b.newton_tol && a.statics_rule == b.statics_rule &&
         a.contact_law == b.contact_law;
}

// Finite and |x| <= bound (false for NaN).
bool bounded_array(const legsim_real *x, int n, double bound) {
  for (int i = 0; i < n; ++i)
    if (!(std::abs(x[i]) <= real(bound))) return false;
  return true;
}

// Lengths inside every stroke (and finite), else the matching status.
legsim_status lengths_check(const Model &m, const legsim_real *len) {
  if (!bounded_array(len, m.na, LEGSIM_MAX_COORD)) return LEGSIM_ERR_BAD_INPUT;
  for (int a = 0; a < m.na; ++a)
    if (len[a] < m.act[a].lmin || len[a] > m.act[a].lmax) return LEGSIM_ERR_OUT_OF_STROKE;
  return LEGSIM_OK;
}

// The driven lengths of an assembly: the given ones, or the actuators' current ones for
// NULL; checked, then held still (rate and acceleration 0) as drivers with no coordinate.
legsim_status drive_to_lengths(legsim_sim *sim, Sim &s, const legsim_real *length_m) {
  const Model &m = s.model;
  Data &d = s.data;
  real len[kMaxActuators];
  if (length_m) {
    for (int a = 0; a < m.na; ++a) len[a] = length_m[a];
  } else {
    legsim_actuator_lengths(sim, len, nullptr);
  }
  const legsim_status st = lengths_check(m, len);
  if (st != LEGSIM_OK) return st;
  for (int a = 0; a < m.na; ++a) {
    d.drivers.length[a] = len[a];
    d.drivers.rate[a] = d.drivers.accel[a] = 0;
  }
  d.drivers.ncoord = 0;
  return LEGSIM_OK;
}

// After the state changed outside a step: accelerations, multipliers and reactions of the
// free dynamics at the new state, and a fresh start of the generalized-alpha history.
// forcing_only (a changed command or load alone: the state, its rows and the options as
// they were): the same accelerations, from the state's factor when the last step left it
// (Factor::of_state: RK4's whole-system end solve; the same values as a fresh
// factorization; the reduced end keeps none, and its restart is the same solve anyway), and
// generalized-alpha keeps its Newton contraction estimate (the iteration matrix is the
// same) and its predictor's past, shifted by the accelerations' jump (a step change of the
// forcing moves them by about that much on either side of it): a controller that changes
// its setpoint every step costs about one Newton iteration a step, not two.
legsim_status state_refresh(Sim &sim, bool forcing_only = false) {
  Data &d = sim.data;
  // the history is generalized-alpha's alone: RK4 calls leave it (Snapshot), and a change of
  // integrator restarts it (legsim_set_options)
  const bool history = sim.opt.integrator == LEGSIM_INTEGRATOR_GENERALIZED_ALPHA;
  VecQ before;
  if (forcing_only && history) before = d.qdd;
  const legsim_status s = dynamics_state_reactions(sim, d.qdd, forcing_only && d.factor.of_state);
  d.derivative_valid = s == LEGSIM_OK;
  d.history_valid = s == LEGSIM_OK;
  d.forcing_only = false;
  if (!history) return s;
  if (s == LEGSIM_OK) d.acc_aux = d.qdd;
  if (s == LEGSIM_OK && forcing_only) {
    for (int k = 0; k < d.past_steps && k < kPredictorOrder; ++k)
      for (int i = 0; i < sim.model.nq; ++i) d.qdd_past[k][i] += d.qdd[i] - before[i];
  } else {
    d.past_steps = 0;  // the history starts here
    d.newton_eta = 1;
  }
  return s;
}

// A changed command or load is a discontinuity of the forcing: both integrators
// restart from the accelerations under the new forces (the generalized-alpha
// history would otherwise carry the old ones and drop to first order). The same
// value sent again changes nothing.
void commands_changed(Data &d) {
  d.forcing_only = d.forcing_only || d.derivative_valid || d.history_valid;
  d.derivative_valid = false;
  d.history_valid = false;
}

// The state, its rows or the options changed outside a step: a full restart.
void state_changed(Data &d) {
  d.derivative_valid = false;
  d.history_valid = false;
  d.forcing_only = false;
}

// A state set from outside rests on no stroke stop (the next step finds any).
legsim_status stops_clear(Sim &sim) {
  Data &d = sim.data;
  for (int a = 0; a < sim.model.na; ++a) d.act[a].stop_force = 0;
  if (!d.stop_mask) return LEGSIM_OK;
  d.stop_mask = 0;
  return stops_layout(sim);
}

// A state assembled or set from outside rests on no contact (legsim_assemble_on_ground
// and legsim_set_contact_state put feet on the ground).
legsim_status contacts_release(Sim &sim) {
  bool any = false;
  for (int k = 0; k < sim.model.nc; ++k) any = any || sim.data.contact[k].state != LEGSIM_CONTACT_FREE;
  contacts_free(sim);
  return any ? stops_layout(sim) : LEGSIM_OK;
}

legsim_status drivers_layout(Sim &sim, uint32_t act_mask, int ncoord) {
  if (ncoord == 0) return work_layout(sim, act_mask);
  sim.data.work_mask = -1;  // coordinate rows: built for this call only
  legsim_status s = layout_build(sim.model, act_mask, ncoord, sim.data.work);
  return s == LEGSIM_OK ? layout_finish(sim.data.work, sim.data.drivers) : s;
}

uint32_t all_actuators(const Model &m) { return (1u << m.na) - 1; }

// Assembles d.work from d.q with geometric weights; commits q (qd = 0) on success.
legsim_status assemble_commit(Sim &sim) {
  Data &d = sim.data;
  if (const legsim_status st = stops_clear(sim); st != LEGSIM_OK) return st;
  if (const legsim_status st = contacts_release(sim); st != LEGSIM_OK) return st;
  VecQ q = d.q;
  const legsim_status s = assemble(sim, d.work, d.drivers, q, sim.model.unit_weight, AssemblyMode::Assemble);
  if (s != LEGSIM_OK) return s;
  d.q = q;
  d.qd.setZero();
  d.assembled = true;
  const legsim_report assembly = d.report;
  const legsim_status st = state_refresh(sim);
  // report the assembly's figures, not those of the free dynamics solved after it
  d.report.iterations = assembly.iterations;
  d.report.residual = assembly.residual;
  d.report.condition = assembly.condition;
  return st;
}

}  // namespace

extern "C" {

legsim_status legsim_model_check(const legsim_model_desc *model, char *msg, size_t msg_len) {
  return model_check(model, msg, msg_len);
}

legsim_options legsim_default_options(void) {
  legsim_options o;
  o.integrator = LEGSIM_INTEGRATOR_RK4;
  o.step_s = 1e-3;
  o.disable = 0;
  o.rho_inf = 0.8;
  o.max_newton_iter = 25;
  o.newton_tol = LEGSIM_USE_FLOAT ? 1e-6 : 1e-10;
  o.statics_rule = LEGSIM_STATICS_EQUAL_FRICTION;
  o.contact_law = LEGSIM_CONTACT_LCP;
  return o;
}

size_t legsim_sim_size(void) { return sizeof(Sim); }

legsim_status legsim_init(void *storage, size_t storage_bytes, const legsim_model_desc *model,
                          const legsim_options *options, legsim_sim **out) {
  if (!storage || !model || !options || !out) return LEGSIM_ERR_NULL;
  if (storage_bytes < sizeof(Sim) || reinterpret_cast<uintptr_t>(storage) % LEGSIM_STORAGE_ALIGN)
    return LEGSIM_ERR_STORAGE;
  legsim_status s = options_check(options);
  if (s == LEGSIM_OK) s = model_check(model, nullptr, 0);
  if (s != LEGSIM_OK) return s;  // the storage (and any sim in it) untouched
  Sim *sim = new (storage) Sim;  // placement: the caller's storage, no heap
  sim->magic = 0;                // not a sim until complete
  s = model_compile(model, sim->model);
  if (s != LEGSIM_OK) return s;
  sim->opt = *options;
  Data &d = sim->data;
  const Model &m = sim->model;
  d.t = 0;
  d.steps = 0;
  d.assembled = false;
  state_changed(d);
  d.end_projected = false;
  d.factor.of_state = false;
  d.q.setZero();
  d.qd.setZero();
  d.qdd.setZero();
  d.acc_aux.setZero();
  for (VecQ &past : d.qdd_past) past.setZero();
  d.past_steps = 0;
  d.newton_eta = 1;
  d.lambda.setZero();
  std::memset(d.reaction, 0, sizeof d.reaction);
  std::memset(&d.report, 0, sizeof d.report);
  std::memset(&d.failure, 0, sizeof d.failure);
  std::memset(&d.drivers, 0, sizeof d.drivers);
  d.stroke_mask = 0;
  for (int a = 0; a < kMaxActuators; ++a) d.act[a] = {LEGSIM_ACTUATOR_FORCE, 0, 0, 0};
  std::memset(&d.stop_drivers, 0, sizeof d.stop_drivers);
  d.stop_mask = 0;
  d.work_mask = -1;
  trig_clear(d.trig);
  trig_clear(*stage_trig(d));
  contacts_free(*sim);
  for (int f = 0; f < m.nf; ++f) {
    d.force_value[f][0] = real(model->force[f].value[0]);
    d.force_value[f][1] = real(model->force[f].value[1]);
  }
  force_active_update(m, d);
  s = layout_build(m, 0, 0, d.joints);
  if (s == LEGSIM_OK) s = layout_finish(d.joints, d.drivers);
  if (s == LEGSIM_OK) s = stops_layout(*sim);
  if (s != LEGSIM_OK) return s;
  sim->magic = kSimMagic;
  *out = reinterpret_cast<legsim_sim *>(sim);
  return LEGSIM_OK;
}

legsim_status legsim_set_options(legsim_sim *sim, const legsim_options *options) {
  CHECK_SIM(sim);
  const legsim_status s = options_check(options);
  if (s != LEGSIM_OK) return s;
  Sim &sm = *as_sim(sim);
  if (same_options(sm.opt, *options)) return LEGSIM_OK;  // sent again: changes nothing
  sm.opt = *options;
  state_changed(sm.data);  // the step, the integrator, what is enabled: a full restart
  return LEGSIM_OK;
}

int32_t legsim_n_bodies(const legsim_sim *sim) { return sim_ok(sim) ? as_sim(sim)->model.nb : 0; }
int32_t legsim_n_coords(const legsim_sim *sim) { return sim_ok(sim) ? as_sim(sim)->model.nq : 0; }
int32_t legsim_n_constraints(const legsim_sim *sim) { return sim_ok(sim) ? as_sim(sim)->model.m : 0; }
int32_t legsim_n_joints(const legsim_sim *sim) { return sim_ok(sim) ? as_sim(sim)->model.nj : 0; }
int32_t legsim_n_actuators(const legsim_sim *sim) { return sim_ok(sim) ? as_sim(sim)->model.na : 0; }
int32_t legsim_n_forces(const legsim_sim *sim) { return sim_ok(sim) ? as_sim(sim)->model.nf : 0; }
int32_t legsim_n_contacts(const legsim_sim *sim) { return sim_ok(sim) ? as_sim(sim)->model.nc : 0; }
const legsim_model_desc *legsim_model(const legsim_sim *sim) {
  return sim_ok(sim) ? as_sim(sim)->model.desc : nullptr;
}

legsim_status legsim_get_report(const legsim_sim *sim, legsim_report *out) {
  CHECK_SIM(sim);
  if (!out) return LEGSIM_ERR_NULL;
  *out = as_sim(sim)->data.report;
  return LEGSIM_OK;
}

legsim_status legsim_failure_report(const legsim_sim *sim, legsim_report *out) {
  CHECK_SIM(sim);
  if (!out) return LEGSIM_ERR_NULL;
  *out = as_sim(sim)->data.failure;
  return LEGSIM_OK;
}

legsim_status legsim_clear_events(legsim_sim *sim) {
  CHECK_SIM(sim);
  as_sim(sim)->data.report.events = 0;
  as_sim(sim)->data.stroke_mask = 0;
  for (ContactData &c : as_sim(sim)->data.contact) c.events = 0;
  return LEGSIM_OK;
}

uint32_t legsim_stroke_event_mask(const legsim_sim *sim) {
  return sim_ok(sim) ? as_sim(sim)->data.stroke_mask : 0;
}

uint32_t legsim_contact_event_mask(const legsim_sim *sim, int32_t k) {
  if (!sim_ok(sim) || k < 0 || k >= as_sim(sim)->model.nc) return 0;
  return as_sim(sim)->data.contact[k].events;
}

double legsim_time(const legsim_sim *sim) { return sim_ok(sim) ? as_sim(sim)->data.t : 0.0; }
uint64_t legsim_step_count(const legsim_sim *sim) { return sim_ok(sim) ? as_sim(sim)->data.steps : 0; }

legsim_status legsim_get_q(const legsim_sim *sim, legsim_real *q) {
  CHECK_SIM(sim);
  if (!q) return LEGSIM_ERR_NULL;
  const Sim &s = *as_sim(sim);
  for (int k = 0; k < s.model.nq; ++k) q[k] = s.data.q[k];
  return LEGSIM_OK;
}

legsim_status legsim_get_qd(const legsim_sim *sim, legsim_real *qd) {
  CHECK_SIM(sim);
  if (!qd) return LEGSIM_ERR_NULL;
  const Sim &s = *as_sim(sim);
  for (int k = 0; k < s.model.nq; ++k) qd[k] = s.data.qd[k];
  return LEGSIM_OK;
}

legsim_status legsim_get_qdd(const legsim_sim *sim, legsim_real *qdd) {
  CHECK_SIM(sim);
  if (!qdd) return LEGSIM_ERR_NULL;
  const Sim &s = *as_sim(sim);
  for (int k = 0; k < s.model.nq; ++k) qdd[k] = s.data.qdd[k];
  return LEGSIM_OK;
}

legsim_status legsim_set_state(legsim_sim *sim, const legsim_real *q, const legsim_real *qd,
                               double t_s) {
  CHECK_SIM(sim);
  if (!q) return LEGSIM_ERR_NULL;
  Sim &s = *as_sim(sim);
  const int n = s.model.nq;
  if (!within(t_s, -LEGSIM_MAX_TIME_S, LEGSIM_MAX_TIME_S)) return LEGSIM_ERR_BAD_INPUT;
  Data &d = s.data;
  VecQ qn = VecQ::Zero(), qdn = VecQ::Zero();
  for (int k = 0; k < n; ++k) {
    qn[k] = q[k];
    qdn[k] = qd ? qd[k] : real(0);
  }
  if (!state_sane(qn, qdn, n)) return LEGSIM_ERR_BAD_INPUT;  // NaN too
  return all_or_nothing(s, [&] {
    d.q = qn;
    d.qd = qdn;
    d.t = t_s;
    d.assembled = true;
    legsim_status c = stops_clear(s);
    if (c == LEGSIM_OK) c = contacts_release(s);
    return c == LEGSIM_OK ? state_refresh(s) : c;
  });
}

legsim_status legsim_constraints(const legsim_sim *sim, legsim_real *phi, legsim_real *max_abs) {
  CHECK_SIM(sim);
  // the workspace is scratch: evaluating into it does not change the state
  Sim &s = *const_cast<Sim *>(as_sim(sim));
  Data &d = s.data;
  rows_eval(s.model, d.joints, d.drivers, d.q, d.qd, d.rows);
  if (phi)
    for (int i = 0; i < s.model.m; ++i) phi[i] = d.rows.phi[i];
  if (max_abs) *max_abs = rows_max_residual(d.joints, d.rows);
  return LEGSIM_OK;
}

legsim_status legsim_jacobian(const legsim_sim *sim, legsim_real *jac) {
  CHECK_SIM(sim);
  if (!jac) return LEGSIM_ERR_NULL;
  Sim &s = *const_cast<Sim *>(as_sim(sim));
  Data &d = s.data;
  const int n = s.model.nq;
  rows_eval(s.model, d.joints, d.drivers, d.q, d.qd, d.rows);
  for (int i = 0; i < s.model.m; ++i) {
    for (int k = 0; k < n; ++k) jac[i * n + k] = 0;
    for (int sl = 0; sl < 2; ++sl) {
      const int b = d.joints.body[i][sl];
      if (b < 0) continue;
      for (int c = 0; c < 3; ++c) jac[i * n + 3 * b + c] += d.rows.coef[i][sl][c];
    }
  }
  return LEGSIM_OK;
}

legsim_status legsim_actuator_lengths(const legsim_sim *sim, legsim_real *length_m, legsim_real *rate_mps) {
  CHECK_SIM(sim);
  if (!length_m && !rate_mps) return LEGSIM_ERR_NULL;
  const Sim &s = *as_sim(sim);
  for (int a = 0; a < s.model.na; ++a) {
    real l, r;
    actuator_length(s.model, a, s.data.q, s.data.qd, l, r);
    if (length_m) length_m[a] = l;
    if (rate_mps) rate_mps[a] = r;
  }
  return LEGSIM_OK;
}

legsim_status legsim_actuator_forces(const legsim_sim *sim, legsim_real *force_n) {
  CHECK_SIM(sim);
  if (!force_n) return LEGSIM_ERR_NULL;
  const Sim &s = *as_sim(sim);
  for (int a = 0; a < s.model.na; ++a) force_n[a] = s.data.act[a].force + s.data.act[a].stop_force;
  return LEGSIM_OK;
}

legsim_status legsim_foot_position(const legsim_sim *sim, legsim_real *xy) {
  CHECK_SIM(sim);
  if (!xy) return LEGSIM_ERR_NULL;
  const Sim &s = *as_sim(sim);
  const int b = s.model.foot_body;
  if (b < 0) return LEGSIM_ERR_BAD_INPUT;
  const real phi = s.data.q[3 * b + 2];
  const Vec2 p = Vec2(s.data.q[3 * b], s.data.q[3 * b + 1]) +
                 s.model.foot_point.x() * axis_u(phi) + s.model.foot_point.y() * normal_n(phi);
  xy[0] = p.x();
  xy[1] = p.y();
  return LEGSIM_OK;
}

legsim_status legsim_assemble(legsim_sim *sim, const legsim_real *length_m) {
  CHECK_SIM(sim);
  Sim &s = *as_sim(sim);
  const Model &m = s.model;
  Data &d = s.data;
  if (!all_finite(d.q, m.nq)) return LEGSIM_ERR_STATE;
  legsim_status st = drive_to_lengths(sim, s, length_m);
  if (st != LEGSIM_OK) return st;
  st = drivers_layout(s, all_actuators(m), 0);
  return st == LEGSIM_OK ? all_or_nothing(s, [&] { return assemble_commit(s); }) : st;
}

legsim_status legsim_assemble_pose(legsim_sim *sim, int32_t pose) {
  CHECK_SIM(sim);
  Sim &s = *as_sim(sim);
  const legsim_model_desc *desc = s.model.desc;
  if (pose < 0 || pose >= desc->n_poses) return LEGSIM_ERR_BAD_INPUT;
  const legsim_pose_desc &p = desc->pose[pose];
  Data &d = s.data;
  d.drivers.ncoord = p.n_drivers;
  for (int k = 0; k < p.n_drivers; ++k) d.drivers.coord[k] = p.driver[k];
  legsim_status st = drivers_layout(s, 0, p.n_drivers);
  if (st != LEGSIM_OK) return st;
  return all_or_nothing(s, [&] {
    for (int b = 0; b < s.model.nb; ++b)
      for (int c = 0; c < 3; ++c) d.q[3 * b + c] = real(p.guess[b][c]);
    return assemble_commit(s);
  });
}

legsim_status legsim_velocity_analysis(legsim_sim *sim, const legsim_real *rate_mps) {
  CHECK_SIM(sim);
  if (!rate_mps) return LEGSIM_ERR_NULL;
  Sim &s = *as_sim(sim);
  const Model &m = s.model;
  Data &d = s.data;
  if (!d.assembled) return LEGSIM_ERR_STATE;
  // feet on the ground: their rows and the lengths over-determine the motion; the driven
  // motion with stuck feet is legsim_inverse_dynamics_on_ground's (it sets q, qd and qdd)
  for (int k = 0; k < m.nc; ++k)
    if (d.contact[k].state != LEGSIM_CONTACT_FREE) return LEGSIM_ERR_CONTACT;
  if (!bounded_array(rate_mps, m.na, LEGSIM_MAX_RATE_MPS)) return LEGSIM_ERR_BAD_INPUT;
  legsim_actuator_lengths(sim, d.drivers.length, nullptr);
  for (int a = 0; a < m.na; ++a) {
    d.drivers.rate[a] = rate_mps[a];
    d.drivers.accel[a] = 0;
  }
  d.drivers.ncoord = 0;
  legsim_status st = drivers_layout(s, all_actuators(m), 0);
  if (st != LEGSIM_OK) return st;
  return all_or_nothing(s, [&] {
    VecQ qd = VecQ::Zero();
    legsim_status v = stops_clear(s);
    if (v == LEGSIM_OK) v = velocity_solve(s, d.work, qd);
    if (v != LEGSIM_OK) return v;
    // a velocity a state may not hold is refused here, not at the next step
    if (!state_sane(d.q, qd, m.nq)) return LEGSIM_ERR_DIVERGED;
    d.qd = qd;
    return state_refresh(s);
  });
}

legsim_status legsim_acceleration_analysis(legsim_sim *sim, const legsim_real *accel_mps2) {
  CHECK_SIM(sim);
  if (!accel_mps2) return LEGSIM_ERR_NULL;
  Sim &s = *as_sim(sim);
  const Model &m = s.model;
  Data &d = s.data;
  if (!d.assembled) return LEGSIM_ERR_STATE;
  // feet on the ground: their rows and the lengths over-determine the motion; the driven
  // motion with stuck feet is legsim_inverse_dynamics_on_ground's (it sets q, qd and qdd)
  for (int k = 0; k < m.nc; ++k)
    if (d.contact[k].state != LEGSIM_CONTACT_FREE) return LEGSIM_ERR_CONTACT;
  if (!bounded_array(accel_mps2, m.na, LEGSIM_MAX_ACCEL_MPS2)) return LEGSIM_ERR_BAD_INPUT;
  legsim_actuator_lengths(sim, d.drivers.length, d.drivers.rate);
  for (int a = 0; a < m.na; ++a) d.drivers.accel[a] = accel_mps2[a];
  d.drivers.ncoord = 0;
  legsim_status st = drivers_layout(s, all_actuators(m), 0);
  if (st != LEGSIM_OK) return st;
  return all_or_nothing(s, [&] {
    VecQ qdd;
    const legsim_status r = acceleration_solve(s, d.work, qdd);
    if (r != LEGSIM_OK) return r;
    d.qdd = qdd;
    state_changed(d);  // qdd is kinematic, not the dynamics'
    return LEGSIM_OK;
  });
}

legsim_status legsim_inverse_dynamics(legsim_sim *sim, const legsim_real *length_m,
                                      const legsim_real *rate_mps, const legsim_real *accel_mps2,
                                      legsim_real *actuator_force_n) {
  CHECK_SIM(sim);
  if (!length_m || !rate_mps || !accel_mps2) return LEGSIM_ERR_NULL;
  Sim &s = *as_sim(sim);
  if (!s.data.assembled) return LEGSIM_ERR_STATE;
  legsim_status st = lengths_check(s.model, length_m);
  if (st != LEGSIM_OK) return st;
  if (!bounded_array(rate_mps, s.model.na, LEGSIM_MAX_RATE_MPS) ||
      !bounded_array(accel_mps2, s.model.na, LEGSIM_MAX_ACCEL_MPS2))
    return LEGSIM_ERR_BAD_INPUT;
  real force[kMaxActuators];
  bool held = false;  // feet on the ground: their rows too (section 8)
  for (int k = 0; k < s.model.nc; ++k) held = held || s.data.contact[k].state != LEGSIM_CONTACT_FREE;
  real len[kMaxActuators], rate[kMaxActuators], acc[kMaxActuators];
  for (int a = 0; a < s.model.na; ++a) {
    len[a] = length_m[a];
    rate[a] = rate_mps[a];
    acc[a] = accel_mps2[a];
  }
  st = all_or_nothing(s, [&] {
    legsim_status r = stops_clear(s);
    if (r == LEGSIM_OK)
      r = held ? inverse_dynamics_ground_solve(s, 0, len, rate, acc, force)
               : inverse_dynamics_solve(s, length_m, rate_mps, accel_mps2, force);
    state_changed(s.data);  // qdd is the driven motion's
    return r;
  });
  if (st == LEGSIM_OK && actuator_force_n)
    for (int a = 0; a < s.model.na; ++a) actuator_force_n[a] = force[a];
  return st;
}

legsim_status legsim_inverse_dynamics_on_ground(legsim_sim *sim, uint32_t follow_mask, legsim_real *length_m,
                                                legsim_real *rate_mps, legsim_real *accel_mps2,
                                                legsim_real *actuator_force_n) {
  CHECK_SIM(sim);
  if (!length_m || !rate_mps || !accel_mps2) return LEGSIM_ERR_NULL;
  Sim &s = *as_sim(sim);
  const Model &m = s.model;
  if (!s.data.assembled) return LEGSIM_ERR_STATE;
  if (follow_mask & ~all_actuators(m)) return LEGSIM_ERR_BAD_INPUT;
  real len[kMaxActuators], rate[kMaxActuators], acc[kMaxActuators];
  for (int a = 0; a < m.na; ++a) {
    const bool driven = !(follow_mask & (1u << a));
    len[a] = driven ? length_m[a] : (m.act[a].lmin + m.act[a].lmax) / 2;  // followers: not read
    rate[a] = driven ? rate_mps[a] : 0;
    acc[a] = driven ? accel_mps2[a] : 0;
  }
  legsim_status st = lengths_check(m, len);
  if (st != LEGSIM_OK) return st;
  if (!bounded_array(rate, m.na, LEGSIM_MAX_RATE_MPS) || !bounded_array(acc, m.na, LEGSIM_MAX_ACCEL_MPS2))
    return LEGSIM_ERR_BAD_INPUT;
  real force[kMaxActuators];
  st = all_or_nothing(s, [&] {
    legsim_status r = stops_clear(s);
    if (r == LEGSIM_OK) r = inverse_dynamics_ground_solve(s, follow_mask, len, rate, acc, force);
    state_changed(s.data);  // qdd is the driven motion's
    return r;
  });
  if (st != LEGSIM_OK) return st;
  for (int a = 0; a < m.na; ++a) {
    length_m[a] = len[a];
    rate_mps[a] = rate[a];
    accel_mps2[a] = acc[a];
    if (actuator_force_n) actuator_force_n[a] = force[a];
  }
  return LEGSIM_OK;
}

legsim_status legsim_statics(legsim_sim *sim, legsim_real *actuator_force_n) {
  CHECK_SIM(sim);
  Sim &s = *as_sim(sim);
  if (!s.data.assembled) return LEGSIM_ERR_STATE;
  real force[kMaxActuators];
  const legsim_status st = all_or_nothing(s, [&] {
    legsim_status r = stops_clear(s);
    if (r == LEGSIM_OK) r = statics_solve(s, force);
    state_changed(s.data);
    return r;
  });
  if (st == LEGSIM_OK && actuator_force_n)
    for (int a = 0; a < s.model.na; ++a) actuator_force_n[a] = force[a];
  return st;
}

legsim_status legsim_statics_sweep(legsim_sim *sim, int32_t n_grid, legsim_worst_case *out) {
  CHECK_SIM(sim);
  if (!out) return LEGSIM_ERR_NULL;
  Sim &s = *as_sim(sim);
  if (!s.data.assembled) return LEGSIM_ERR_STATE;
  if (n_grid < 2 || n_grid > LEGSIM_MAX_GRID) return LEGSIM_ERR_BAD_INPUT;
  legsim_worst_case wc;
  const legsim_status st = all_or_nothing(s, [&] {
    legsim_status r = stops_clear(s);
    if (r == LEGSIM_OK) r = contacts_release(s);
    if (r == LEGSIM_OK) r = statics_sweep(s, n_grid, &wc);  // leaves the last pose solved
    state_changed(s.data);
    return r;
  });
  if (st == LEGSIM_OK) *out = wc;
  return st;
}

legsim_status legsim_step(legsim_sim *sim, int32_t n_steps) {
  CHECK_SIM(sim);
  if (n_steps < 0) return LEGSIM_ERR_BAD_INPUT;
  Sim &s = *as_sim(sim);
  Data &d = s.data;
  if (!d.assembled || !state_finite(d.q, d.qd, s.model.nq)) return LEGSIM_ERR_STATE;
  const bool rk4 = s.opt.integrator == LEGSIM_INTEGRATOR_RK4;
  for (int32_t i = 0; i < n_steps; ++i) {
    // a failed step leaves the state of the last good one (all_or_nothing also
    // refuses a step whose state, accelerations, multipliers or report are not finite)
    const legsim_status st = all_or_nothing(s, [&] {
      legsim_status r = LEGSIM_OK;
      // both start from the accelerations at the current state and commands
      if (rk4 ? !d.derivative_valid : !d.history_valid) r = state_refresh(s, d.forcing_only);
      if (r == LEGSIM_OK) r = rk4 ? rk4_step(s) : generalized_alpha_step(s);
      bool stopped = false, released = false;
      const bool stops = !(s.opt.disable & LEGSIM_DISABLE_STROKE_LIMITS);
      if (r == LEGSIM_OK && stops) r = stroke_limits_enforce(s, stopped);
      if (r == LEGSIM_OK) {
        if (stopped)
          r = state_refresh(s);  // the impact changed q and qd: derivative and reactions anew
        else if (!rk4)           // RK4 leaves its end derivative and reactions itself
          r = generalized_alpha_reactions(s);
      }
      bool contacts_changed = false;
      if (r == LEGSIM_OK && s.model.nc) r = contact_transitions(s, contacts_changed);
      if (r == LEGSIM_OK && contacts_changed) r = state_refresh(s);
      if (r == LEGSIM_OK && stops) r = stroke_stops_release(s, released);
      if (r == LEGSIM_OK && released) r = state_refresh(s);
      if (r != LEGSIM_OK) return r;
      if (rk4) d.derivative_valid = true;  // its end derivative is the next step's start
      d.t += s.opt.step_s;
      ++d.steps;
      if (d.report.condition > real(LEGSIM_COND_WARN)) raise_event(d, LEGSIM_EVENT_NEAR_SINGULAR);
      return LEGSIM_OK;
    });
    if (st != LEGSIM_OK) return st;
  }
  return LEGSIM_OK;
}

legsim_status legsim_reactions(const legsim_sim *sim, legsim_reaction *out) {
  CHECK_SIM(sim);
  if (!out) return LEGSIM_ERR_NULL;
  const Sim &s = *as_sim(sim);
  if (s.opt.disable & LEGSIM_DISABLE_REACTIONS) return LEGSIM_ERR_DISABLED;
  for (int j = 0; j < s.model.nj; ++j) out[j] = s.data.reaction[j];
  return LEGSIM_OK;
}

legsim_status legsim_multipliers(const legsim_sim *sim, legsim_real *lambda) {
  CHECK_SIM(sim);
  if (!lambda) return LEGSIM_ERR_NULL;
  const Sim &s = *as_sim(sim);
  for (int i = 0; i < s.model.m; ++i) lambda[i] = s.data.lambda[i];
  return LEGSIM_OK;
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

legsim_status legsim_contacts(const legsim_sim *sim, legsim_contact *out) {
  CHECK_SIM(sim);
  if (!out) return LEGSIM_ERR_NULL;
  if (!LEGSIM_WITH_CONTACT) return LEGSIM_ERR_DISABLED;
  const Sim &s = *as_sim(sim);
  const Model &m = s.model;
  for (int k = 0; k < m.nc; ++k) {
    const ContactData &c = s.data.contact[k];
    Vec2 p, v;
    contact_point(m, k, s.data.q, s.data.qd, p, v);
    legsim_contact &o = out[k];
    o.state = legsim_contact_state(c.state);
    o.normal_n = c.normal;
    o.tangential_n = c.tangential;
    o.friction_use = c.normal > 0 ? std::abs(c.tangential) / c.normal : real(0);
    o.position[0] = p.x();
    o.position[1] = p.y();
    o.slip_mps = v.dot(m.ground_t);
    o.impulse_ns[0] = c.impulse[0];
    o.impulse_ns[1] = c.impulse[1];
    o.holds = c.state != LEGSIM_CONTACT_FREE && c.normal >= 0 &&
              std::abs(c.tangential) <= m.mu_s * c.normal;
  }
  return LEGSIM_OK;
}

legsim_status legsim_set_contact_state(legsim_sim *sim, int32_t k, legsim_contact_state state) {
  CHECK_SIM(sim);
  if (!LEGSIM_WITH_CONTACT) return LEGSIM_ERR_DISABLED;
  Sim &s = *as_sim(sim);
  const Model &m = s.model;
  Data &d = s.data;
  const long long st = raw_enum(state);
  if (k < 0 || k >= m.nc ||
      (st != LEGSIM_CONTACT_FREE && st != LEGSIM_CONTACT_STUCK && st != LEGSIM_CONTACT_SLIDING))
    return LEGSIM_ERR_BAD_INPUT;
  if (!d.assembled) return LEGSIM_ERR_STATE;
  Vec2 p, v;
  contact_point(m, k, d.q, d.qd, p, v);
  const real gap = m.ground_n.dot(p - m.ground_point);
  const real vt = m.ground_t.dot(v);
  if (st != LEGSIM_CONTACT_FREE && !(std::abs(gap) <= real(s.opt.newton_tol))) return LEGSIM_ERR_STATE;
  if (st == LEGSIM_CONTACT_SLIDING && !(std::abs(vt) > real(s.opt.newton_tol))) return LEGSIM_ERR_STATE;
  const int8_t dir = vt > 0 ? 1 : -1;
  if (d.contact[k].state == st && (st != LEGSIM_CONTACT_SLIDING || d.contact[k].slip_dir == dir))
    return LEGSIM_OK;  // sent again: changes nothing
  return all_or_nothing(s, [&] {
    d.contact[k].state = uint8_t(st);
    d.contact[k].slip_dir = dir;
    d.stop_drivers.stick[k] = m.ground_t.dot(p - m.ground_point);
    legsim_status r = stops_layout(s);
    if (r == LEGSIM_OK && st != LEGSIM_CONTACT_FREE) {
      // the foot stops where it is (stuck) or on the line (sliding): its velocity onto the
      // new rows (an inelastic impact; frictionless: a state set from outside)
      VecQ qd = d.qd;
      r = velocity_solve(s, d.dyn, qd);
      if (r == LEGSIM_OK) d.qd = qd;
    }
    return r == LEGSIM_OK ? state_refresh(s) : r;
  });
}

legsim_status legsim_assemble_on_ground(legsim_sim *sim, const legsim_real *length_m,
                                        legsim_real feet_mid_m) {
  CHECK_SIM(sim);
  if (!LEGSIM_WITH_CONTACT) return LEGSIM_ERR_DISABLED;
  Sim &s = *as_sim(sim);
  const Model &m = s.model;
  Data &d = s.data;
  if (m.nc < 1 || !(std::abs(feet_mid_m) <= real(LEGSIM_MAX_COORD))) return LEGSIM_ERR_BAD_INPUT;
  if (!all_finite(d.q, m.nq)) return LEGSIM_ERR_STATE;
  const legsim_status lc = drive_to_lengths(sim, s, length_m);
  if (lc != LEGSIM_OK) return lc;
  d.drivers.feet_mid = feet_mid_m;
  // joints, lengths, the outer feet's normal gaps and their midpoint along the line: with
  // the box's three coordinates that is all the stance fixes; a foot between the outer two
  // must then lie on the line already (legs of one shape at one height), checked below
  uint8_t normal_only[kMaxContacts];
  for (int k = 0; k < m.nc; ++k) normal_only[k] = k == 0 || k == m.nc - 1 ? kContactNormal : kContactNone;
  d.work_mask = -1;  // built for this call only
  legsim_status st = layout_build(m, all_actuators(m), 0, d.work, normal_only, true);
  if (st == LEGSIM_OK) st = layout_finish(d.work, d.drivers);
  if (st != LEGSIM_OK) return st;
  return all_or_nothing(s, [&] {
    legsim_status r = stops_clear(s);
    if (r != LEGSIM_OK) return r;
    VecQ q = d.q;
    r = assemble(s, d.work, d.drivers, q, m.unit_weight, AssemblyMode::Assemble);
    if (r != LEGSIM_OK) return r;
    d.q = q;
    d.qd.setZero();
    d.assembled = true;
    const VecQ zero = VecQ::Zero();
    for (int k = 0; k < m.nc; ++k) {
      Vec2 p, v;
      contact_point(m, k, d.q, zero, p, v);
      if (k > 0 && k < m.nc - 1 && !(std::abs(m.ground_n.dot(p - m.ground_point)) <= real(s.opt.newton_tol)))
        return LEGSIM_ERR_STATE;  // a middle foot off the line
      d.contact[k].state = uint8_t(LEGSIM_CONTACT_STUCK);
      d.stop_drivers.stick[k] = m.ground_t.dot(p - m.ground_point);
    }
    r = stops_layout(s);
    if (r != LEGSIM_OK) return r;
    const legsim_report assembly = d.report;
    r = state_refresh(s);
    d.report.iterations = assembly.iterations;
    d.report.residual = assembly.residual;
    d.report.condition = assembly.condition;
    return r;
  });
}

}  // extern "C"
