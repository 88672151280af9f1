// Lateness histogram of the real-time loop.
#include "jitter.h"

#include <cstring>

namespace hil {

void JitterStats::reset() {
  std::memset(bins_, 0, sizeof bins_);
  count_ = 0;
  sum_ns_ = 0;
  max_ns_ = 0;
  overruns_ = 0;
}

void JitterStats::add(int64_t late_ns) {
  if (late_ns < 0) late_ns = 0;
  int64_t bin = late_ns / 1000;
  ++bins_[bin < kBins ? bin : kBins];
  ++count_;
  sum_ns_ += static_cast<uint64_t>(late_ns);
  if (late_ns > max_ns_) max_ns_ = late_ns;
}

double JitterStats::p99_us() const {
  if (count_ == 0) return 0.0;
  const uint64_t rank = (count_ * 99 + 99) / 100;  // ceil(0.99 count)
  uint64_t seen = 0;
  for (int b = 0; b < kBins; ++b) {
    seen += bins_[b];
    if (seen >= rank) return b + 1.0;
  }
  return max_us();
}

}  // namespace hil
