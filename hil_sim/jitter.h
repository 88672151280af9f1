// Wake-up lateness of the real-time loop: max, mean and p99 from a fixed histogram
// (1 us bins up to 10 ms, one overflow bin); no allocation per sample.
#ifndef HIL_SIM_JITTER_H
#define HIL_SIM_JITTER_H

#include <cstdint>

namespace hil {

class JitterStats {
 public:
  static constexpr int kBins = 10000;  // 1 us each

  void reset();
  void add(int64_t late_ns);
  void add_overruns(uint32_t n) { overruns_ += n; }

  uint64_t count() const { return count_; }
  uint32_t overruns() const { return overruns_; }
  double max_us() const { return max_ns_ / 1e3; }
  double mean_us() const { return count_ ? static_cast<double>(sum_ns_) / count_ / 1e3 : 0.0; }
  // Upper edge of the bin holding the 99th percentile (max if it lies past 10 ms).
  double p99_us() const;

 private:
  uint32_t bins_[kBins + 1] = {};
  uint64_t count_ = 0;
  uint64_t sum_ns_ = 0;
  int64_t max_ns_ = 0;
  uint32_t overruns_ = 0;
};

}  // namespace hil

#endif
