// What the C API's files share: the handle check every entry point starts with, the
// argument checks, and the bookkeeping of calls that set a state or build a driven layout.
// The engine below is reached through sim.hpp: the system layer (system/) and the planar
// elements (planar/).
#pragma once

#include <cstring>
#include <type_traits>

#include "sim.hpp"

static_assert(alignof(legsim::Sim) <= LEGSIM_STORAGE_ALIGN, "raise LEGSIM_STORAGE_ALIGN");
static_assert(LEGSIM_MAX_ROWS <= 65535, "row indices are stored in 16 bits (RowIndex)");
static_assert(2 * legsim::kBodyDof * LEGSIM_MAX_ROWS <= 65535, "Pair::ci, cj (coefficient offsets) are 16-bit");
static_assert(LEGSIM_MAX_ACTUATORS <= 31, "actuator sets are 32-bit masks");
static_assert(sizeof(legsim_reaction) == 3 * sizeof(legsim_real), "a reaction is 3 reals, no padding");

namespace legsim::api {

inline Sim *as_sim(legsim_sim *s) { return reinterpret_cast<Sim *>(s); }
inline const Sim *as_sim(const legsim_sim *s) { return reinterpret_cast<const Sim *>(s); }

// One rule for every entry point: a handle is a sim only if legsim_init made it.
inline legsim_status sim_check(const legsim_sim *s) {
  if (!s) return LEGSIM_ERR_NULL;
  if (reinterpret_cast<uintptr_t>(s) % LEGSIM_STORAGE_ALIGN) return LEGSIM_ERR_STORAGE;
  uint32_t magic;
  std::memcpy(&magic, s, sizeof magic);  // Sim::magic is the first member
  return magic == kSimMagic ? LEGSIM_OK : LEGSIM_ERR_STORAGE;
}
inline bool sim_ok(const legsim_sim *s) { return sim_check(s) == LEGSIM_OK; }

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

inline bool within(double x, double lo, double hi) { return x >= lo && x <= hi; }  // false for NaN

// Finite and |x| <= bound (false for NaN).
inline bool bounded_array(const legsim_real *x, int n, double bound) {
  for (int i = 0; i < n; ++i)
    if (!(std::abs(x[i]) <= real(bound))) return false;
  return true;
}

inline uint32_t all_actuators(const Model &m) { return (1u << m.na) - 1; }

legsim_status options_check(const legsim_options *o);
bool same_options(const legsim_options &a, const legsim_options &b);
// Lengths inside every stroke (and finite), else the matching status.
legsim_status lengths_check(const Model &m, const legsim_real *len);
// The driven lengths of an assembly: the given ones, or the actuators' current ones for
// NULL; checked, then held still (rate and acceleration 0) as drivers with no coordinate.
legsim_status drive_to_lengths(legsim_sim *sim, const legsim_real *length_m);
// A state set from outside rests on no stroke stop (the next step finds any).
legsim_status stops_clear(const Model &m, Data &d);
// A state assembled or set from outside rests on no contact (legsim_assemble_on_ground
// and legsim_set_contact_state put feet on the ground).
legsim_status contacts_release(const Model &m, Data &d);
// Data::work for the actuators in act_mask and ncoord coordinate drivers.
legsim_status drivers_layout(const Model &m, Data &d, uint32_t act_mask, int ncoord);
// Assembles d.work from d.q with geometric weights; commits q (qd = 0) on success.
legsim_status assemble_commit(const Model &m, Data &d);

}  // namespace legsim::api
