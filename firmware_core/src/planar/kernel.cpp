// The switch between a sim's generated kernel and the general path (kernel.hpp), for
// the tests that compare the two and for benchmarks. kernel_find itself is generated
// with the kernels (tools/kernel_codegen.py).
#include <cstring>

#include "planar/kernel.hpp"

extern "C" int legsim_kernel_use(legsim_sim *sim, int on) {
  using namespace legsim;
  if (!sim) return -1;
  uint32_t magic;
  std::memcpy(&magic, sim, sizeof magic);  // Sim::magic is the first member
  if (magic != kSimMagic) return -1;
  Sim &s = *reinterpret_cast<Sim *>(sim);
  Data &d = s.data;
  s.model.kernel = on ? kernel_find(s.model) : nullptr;
  s.model.stance_kernel = on ? kernel_find(s.model, true) : nullptr;
  // the layouts carry the factor's order: build them anew for the path chosen (the same
  // rows as before, so this cannot fail where it did not)
  layout_build(s.model, 0, 0, d.joints);
  layout_finish(d.joints, d.drivers);
  stops_layout(s.model, s.data);
  d.work_mask = -1;
  d.factor.of_state = false;  // in the other path's order
  return s.model.kernel ? 1 : 0;
}
