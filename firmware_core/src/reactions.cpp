// Joint reactions from the multipliers (eq. (20) of the paper): the generalized
// force a joint applies to its first-listed body is -Phi_q^T lambda restricted to
// that body's (x, y, phi) columns: a force in world axes and a moment about the
// body's centre of mass.
#include "sim.hpp"

namespace legsim {

// The joint equations lead every layout, in joint order, so row j of a joint is
// the same in the joints-only, dynamics (stops) and driven layouts.
void reactions_from_multipliers(const Model &model, const Rows &rows, const VecR &lambda,
                                legsim_reaction *out) {
  for (int j = 0; j < model.nj; ++j) {
    const Joint &jt = model.joint[j];
    real g[3] = {0, 0, 0};
    for (int r = jt.row; r < jt.row + jt.nrows; ++r)
      for (int c = 0; c < 3; ++c) g[c] -= rows.coef[r][0][c] * lambda[r];
    out[j].force_n[0] = g[0];
    out[j].force_n[1] = g[1];
    out[j].moment_nm = g[2];
  }
}

}  // namespace legsim

