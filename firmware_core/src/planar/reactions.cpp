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
    const int r = jt.row;
    const real *c = rows.coef[r][0];  // the first body's slot: (x, y, phi)
    const real l = lambda[r];
    real g0 = real(0) - c[0] * l, g1 = real(0) - c[1] * l, g2 = real(0) - c[2] * l;
    // a joint's other rows: straight on for the two rows of most joints, a loop otherwise
    if (jt.nrows == 2) {
      const real *c1 = rows.coef[r + 1][0];
      const real l1 = lambda[r + 1];
      g0 -= c1[0] * l1;
      g1 -= c1[1] * l1;
      g2 -= c1[2] * l1;
    } else {
      for (int k = 1; k < jt.nrows; ++k) {
        const real *ck = rows.coef[r + k][0];
        const real lk = lambda[r + k];
        g0 -= ck[0] * lk;
        g1 -= ck[1] * lk;
        g2 -= ck[2] * lk;
      }
    }
    out[j].force_n[0] = g0;
    out[j].force_n[1] = g1;
    out[j].moment_nm = g2;
  }
}

}  // namespace legsim

