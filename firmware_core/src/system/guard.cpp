// The all-or-nothing guard: what a call that fails half-way puts back (Snapshot), and the
// one check of everything a caller can read once a call succeeds (outputs_check).
// Dimension-free: it copies the coordinates, multipliers and per-element results as arrays.
#include <cstring>

#include "planar/kernel.hpp"  // LEGSIM_KERNEL_TARGETS
#include "sim.hpp"

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

// The most rows any layout of the model has (joints, a driver per actuator, the pose
// drivers, two per contact): what the solves may write in lambda.
int rows_bound(const Model &m) {
  const int n = m.m + m.na + LEGSIM_MAX_POSE_DRIVERS + 2 * m.nc;
  return n < kMaxRows ? n : kMaxRows;
}
}  // namespace

Snapshot::Snapshot(const Model &m, const Data &d)
    : history(m.opt.integrator == LEGSIM_INTEGRATOR_GENERALIZED_ALPHA), past_steps(d.past_steps), newton_eta(d.newton_eta), report(d.report),
      t(d.t), origin_t(d.origin_t), origin_step_s(d.origin_step_s),
      steps(d.steps), origin_steps(d.origin_steps), stroke_mask(d.stroke_mask), stop_mask(d.stop_mask),
      assembled(d.assembled), derivative_valid(d.derivative_valid),
      history_valid(d.history_valid), forcing_only(d.forcing_only),
      end_projected(d.end_projected) {
  copy_head(q, d.q, m.nq);
  copy_head(qd, d.qd, m.nq);
  copy_head(qdd, d.qdd, m.nq);
  if (history) {
    copy_head(acc_aux, d.acc_aux, m.nq);
    for (int k = 0; k < kPredictorOrder; ++k) copy_head(qdd_past[k], d.qdd_past[k], m.nq);
  }
  copy_head(lambda, d.lambda, rows_bound(m));  // the solves of every layout write it
  std::memcpy(reaction, d.reaction, sizeof(legsim_reaction) * size_t(m.nj));
  for (int a = 0; a < m.na; ++a) {
    act_force[a] = d.act[a].force;
    stop_force[a] = d.act[a].stop_force;
    stop_time[a] = d.act[a].stop_time;
    stop_length[a] = d.stop_drivers.length[a];
  }
  for (int k = 0; k < m.nc; ++k) {
    contact[k] = d.contact[k];
    stick[k] = d.stop_drivers.stick[k];
  }
}

void Snapshot::restore(const Model &m, Data &d) const {
  copy_head(d.q, q, m.nq);
  copy_head(d.qd, qd, m.nq);
  copy_head(d.qdd, qdd, m.nq);
  if (history) {
    copy_head(d.acc_aux, acc_aux, m.nq);
    for (int k = 0; k < kPredictorOrder; ++k) copy_head(d.qdd_past[k], qdd_past[k], m.nq);
  }
  d.past_steps = past_steps;
  d.newton_eta = newton_eta;
  copy_head(d.lambda, lambda, rows_bound(m));
  d.report = report;
  std::memcpy(d.reaction, reaction, sizeof(legsim_reaction) * size_t(m.nj));
  for (int a = 0; a < m.na; ++a) {
    d.act[a].force = act_force[a];
    d.act[a].stop_force = stop_force[a];
    d.act[a].stop_time = stop_time[a];
    d.stop_drivers.length[a] = stop_length[a];
    d.stop_drivers.rate[a] = d.stop_drivers.accel[a] = 0;
  }
  bool rows_changed = d.stop_mask != stop_mask;
  for (int k = 0; k < m.nc; ++k) {
    rows_changed = rows_changed || d.contact[k].state != contact[k].state;
    d.contact[k] = contact[k];
    d.stop_drivers.stick[k] = stick[k];
  }
  if (rows_changed) {
    d.stop_mask = stop_mask;
    stops_layout(m, d);  // the same rows as before: cannot fail
  }
  d.t = t;
  d.origin_t = origin_t;
  d.origin_step_s = origin_step_s;
  d.steps = steps;
  d.origin_steps = origin_steps;
  d.stroke_mask = stroke_mask;
  d.assembled = assembled;
  d.derivative_valid = derivative_valid;
  d.history_valid = history_valid;
  d.forcing_only = forcing_only;
  d.end_projected = end_projected;
  d.end_solved = false;  // (of a step now undone)
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
real outputs_sum(const Model &m, const Data &d) {
  const auto sum = [](const real *x, int n) { return Exact ? nan_unless_finite(x, n) : block_sum(x, n); };
  const real o = Exact ? real(0) : real(1);
  // the multipliers a caller can read (legsim_multipliers: the joints' rows)
  real z = sum(d.lambda.data(), m.m) + sum(&d.reaction[0].force_n[0], 3 * m.nj);  // 3 reals each
  z += d.report.residual * o + d.report.condition * o;
  for (int a = 0; a < m.na; ++a) z += d.act[a].force * o + d.act[a].stop_force * o;
  for (int c = 0; c < m.nc; ++c) z += d.contact[c].normal * o + d.contact[c].tangential * o;
  return z;
}
}  // namespace

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

bool state_sane(const VecQ &q, const VecQ &qd, int n) {
  for (int k = 0; k < n; ++k)
    if (!(std::abs(q[k]) < real(LEGSIM_MAX_ABS_Q)) || !(std::abs(qd[k]) < real(LEGSIM_MAX_ABS_QD)))
      return false;
  return true;
}

// Once per call (per step): everything a caller can read is finite, the state sane. In
// AVX's wider blocks where the CPU has them (the same tests: a sum's order does not matter).
LEGSIM_KERNEL_TARGETS legsim_status outputs_check(const Model &m, const Data &d) {
  const int n = m.nq;
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
  const real z = sa + outputs_sum<false>(m, d);
  if (z - z == 0) return LEGSIM_OK;  // finite
  const real exact = nan_unless_finite(qdd, n) + outputs_sum<true>(m, d);
  return exact == exact ? LEGSIM_OK : LEGSIM_ERR_DIVERGED;
}

}  // namespace legsim
