// Two legs at once: a pair of reals added, multiplied and divided lane by lane (GCC's and
// Clang's vector extension: one SSE2 instruction for two on x86-64). Each lane rounds as the
// scalar operation would, so a pair's results are each leg's own, bit for bit.
#pragma once

#include "spatial/body.hpp"

namespace legsim::spatial {

typedef real Pair2 __attribute__((vector_size(2 * sizeof(real))));

}  // namespace legsim::spatial
