/* The 3D Coulomb cone's contact problem (firmware_core/src/spatial/friction_cone.hpp): the
 * cost of one solve by the number of contacts, over random coupled problems drawn as its test
 * draws them (tests/core/test_friction_cone.cpp: W = G G^T + 0.05 I, G = I + 0.5 x uniform
 * off the diagonal; q in [-3, 3], q_n in [-3, 1]; mu in [0, 1.5]), each from r = 0 (no warm
 * start).
 *
 *   cone_cost N_CONTACTS COUNT
 *
 * prints the iterations and the problems that took the sweeps; instructions a solve come
 * from callgrind on solve() (docs/design/friction-cone.md):
 *   valgrind --tool=callgrind --toggle-collect=solve build/host/firmware_core/benchmarks/cone_cost 6 500
 * then the total over COUNT. */
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "spatial/friction_cone.hpp"

using namespace legsim;
using real = cone_real;

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static real uniform(real a, real b) {  // xorshift64*
  rng_state ^= rng_state >> 12;
  rng_state ^= rng_state << 25;
  rng_state ^= rng_state >> 27;
  const uint64_t x = rng_state * 0x2545F4914F6CDD1Dull;
  return a + (b - a) * real(x >> 11) * real(1.0 / 9007199254740992.0);
}

extern "C" __attribute__((noinline)) legsim_status solve(int n, const real *W, const real *q, const real *mu, real *r,
                                                         real *u, ConeReport *rep) {
  return cone_solve(n, W, q, mu, r, u, *rep);
}

int main(int argc, char **argv) {
  const int n = argc == 3 ? std::atoi(argv[1]) : 0, count = argc == 3 ? std::atoi(argv[2]) : 0;
  if (n < 1 || n > kConeMaxContacts || count < 1) {
    std::fprintf(stderr, "usage: cone_cost N_CONTACTS(1..%d) COUNT\n", kConeMaxContacts);
    return 2;
  }
  const int m = 3 * n;
  static real W[kConeMaxRows * kConeMaxRows], G[kConeMaxRows * kConeMaxRows];
  real q[kConeMaxRows], mu[kConeMaxContacts], r[kConeMaxRows], u[kConeMaxRows];
  long iterations = 0;
  int sweeps = 0, failed = 0, worst = 0;
  for (int t = 0; t < count; ++t) {
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < m; ++j) G[i * m + j] = i == j ? real(1) : real(0.5) * uniform(-1, 1);
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < m; ++j) {
        real s = i == j ? real(0.05) : real(0);
        for (int k = 0; k < m; ++k) s += G[i * m + k] * G[j * m + k];
        W[i * m + j] = s;
      }
    for (int k = 0; k < m; ++k) q[k] = uniform(-3, 3);
    for (int i = 0; i < n; ++i) q[3 * i] = uniform(-3, 1);
    for (int i = 0; i < n; ++i) mu[i] = uniform(0, real(1.5));
    for (int k = 0; k < m; ++k) r[k] = 0;
    ConeReport rep;
    failed += solve(n, W, q, mu, r, u, &rep) != LEGSIM_OK;
    iterations += rep.iterations;
    sweeps += rep.method == ConeMethod::Sweeps;
    worst = rep.iterations > worst ? rep.iterations : worst;
  }
  std::printf("%d contacts, %d problems: %.2f iterations a solve (at most %d), %d by sweeps, %d not converged\n", n,
              count, double(iterations) / count, worst, sweeps, failed);
  return failed ? 1 : 0;
}
