// Lockstep and real-time loops over the CAN socket.
#include "run_loop.h"

#include <cerrno>
#include <cstdio>
#include <ctime>

#include <poll.h>
#include <sys/signalfd.h>
#include <unistd.h>

namespace hil {

namespace {

int64_t mono_ns() {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

void sleep_until(int64_t t_ns) {
  struct timespec ts;
  ts.tv_sec = t_ns / 1000000000;
  ts.tv_nsec = t_ns % 1000000000;
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

class Loop {
 public:
  Loop(Bus &can, Node &ctl, int signal_fd, const LoopConfig &cfg, JitterStats *stats)
      : can_(can), ctl_(ctl), signal_fd_(signal_fd), cfg_(cfg), stats_(*stats) {}

  LoopResult run() {
    start_ns_ = mono_ns();
    next_hb_ns_ = start_ns_;  // first heartbeat at once: tells the bench hil_sim is up
    bool in_rt = false;
    uint32_t epoch = ctl_.rt_epoch();
    int64_t next = 0, period = 0;
    for (;;) {
      if (ctl_.state() == SimState::kRealtime) {
        if (!in_rt || epoch != ctl_.rt_epoch()) {  // a new real-time run
          in_rt = true;
          epoch = ctl_.rt_epoch();
          period = ctl_.rt_period_ns();
          stats_.reset();
          can_.set_send_block_ms(0);  // never block a tick on a full socket
          next = mono_ns() + period;
        }
        const int64_t wake = rt_wake(next);
        sleep_until(wake);
        int64_t now = mono_ns();
        if (wake < next && now < next) {  // a long period: heartbeat and signals only
          heartbeat_if_due(now);
          if (signal_pending()) break;
          continue;
        }
        stats_.add(now - next);
        if (!service(0)) break;
        ctl_.rt_tick(now);
        heartbeat_if_due(mono_ns());
        next += period;
        int64_t late = mono_ns() - next;
        if (late > 0) {  // the tick ended after the next deadline: skip the missed ticks
          int64_t missed = late / period + 1;
          stats_.add_overruns(static_cast<uint32_t>(missed));
          next += missed * period;
        }
      } else {
        if (in_rt) {
          in_rt = false;
          can_.set_send_block_ms(20);
          print_rt_stats("real-time run", stats_, period > 0 ? 1e9 / period : 0.0);
        }
        if (ctl_.stepping()) {  // a slice of the STEP, then heartbeat and signals
          step_slice();
          heartbeat_if_due(mono_ns());
          if (signal_pending()) break;
          continue;
        }
        int timeout_ms = -1;
        if (cfg_.heartbeat_ms > 0) {
          int64_t wait = next_hb_ns_ - mono_ns();
          timeout_ms = wait <= 0 ? 0 : static_cast<int>((wait + 999999) / 1000000);
        }
        if (!service(timeout_ms)) break;
        heartbeat_if_due(mono_ns());
      }
    }
    if (in_rt) print_rt_stats("real-time run (stopped by exit)", stats_, period > 0 ? 1e9 / period : 0.0);
    result_.shutdown = ctl_.shutdown();
    const NodeShutdown &sd = result_.shutdown;
    if (sd.step_cut)
      std::fprintf(stderr, "hil_sim: STEP of %llu steps cut short after %llu (not answered)\n",
                   static_cast<unsigned long long>(sd.step_total),
                   static_cast<unsigned long long>(sd.step_done));
    if (cfg_.verbose && sd.safe_applied)
      std::fprintf(stderr, "hil_sim: actuators in the safe state\n");
    return result_;
  }

 private:
  // When a real-time sleep ends: the tick, or earlier for a heartbeat due well before it
  // (more than 2 ms: at 1 kHz the heartbeat goes out after a tick, as it always did) and to
  // read the signalfd at least every kStopCheckMs.
  int64_t rt_wake(int64_t next) const {
    int64_t wake = next;
    if (cfg_.heartbeat_ms > 0 && next - next_hb_ns_ > 2000000) wake = next_hb_ns_;
    const int64_t check = mono_ns() + static_cast<int64_t>(kStopCheckMs) * 1000000;
    return wake < check ? wake : check;
  }

  // One slice of the STEP in progress: about kSliceUs of steps. The steps per slice double
  // while a slice takes under half the target and halve while it takes over twice the
  // target, so the clock is read every few steps whatever a step costs (about 5 us on a
  // desktop CPU, about 1 ms under emulation).
  void step_slice() {
    const int64_t t0 = mono_ns();
    ctl_.work(steps_per_slice_);
    const int64_t dt = mono_ns() - t0;
    const int64_t target = static_cast<int64_t>(kSliceUs) * 1000;
    if (dt < target / 2 && steps_per_slice_ < (1u << 16))
      steps_per_slice_ *= 2;
    else if (dt > 2 * target && steps_per_slice_ > 1)
      steps_per_slice_ /= 2;
  }

  // A pending signal, read without waiting; recorded in result_.
  bool signal_pending() {
    struct signalfd_siginfo si;
    if (::read(signal_fd_, &si, sizeof si) == static_cast<ssize_t>(sizeof si)) {
      result_.signal = static_cast<int>(si.ssi_signo);
      return true;
    }
    return false;
  }

  // Waits up to timeout_ms for frames or a signal; handles at most kMaxFramesPerWake
  // frames, and none after a heartbeat falls due or a frame starts a STEP (the loop then
  // works the STEP in slices). False when the loop must stop.
  bool service(int timeout_ms) {
    struct pollfd fds[2] = {{can_.fd(), POLLIN, 0}, {signal_fd_, POLLIN, 0}};
    int n = ::poll(fds, 2, timeout_ms);
    if (n < 0) return errno == EINTR;
    if ((fds[1].revents & POLLIN) && signal_pending()) return false;
    if (fds[0].revents & (POLLERR | POLLHUP | POLLNVAL)) {
      result_.socket_errno = EIO;
      return false;
    }
    if (fds[0].revents & POLLIN) {
      Frame frame;
      for (int i = 0; i < kMaxFramesPerWake; ++i) {
        int r = can_.receive(&frame);
        if (r == 0) break;
        if (r < 0) {
          result_.socket_errno = errno;
          return false;
        }
        ctl_.on_frame(frame, mono_ns());
        if (ctl_.stepping() || (cfg_.heartbeat_ms > 0 && mono_ns() >= next_hb_ns_)) break;
      }
    }
    return true;
  }

  void heartbeat_if_due(int64_t now) {
    if (cfg_.heartbeat_ms == 0 || now < next_hb_ns_) return;
    HeartbeatInfo hb;
    ctl_.fill_heartbeat(&hb);
    hb.counter = hb_counter_++;
    hb.uptime_ms = static_cast<uint32_t>((now - start_ns_) / 1000000);
    hb.rt_overruns = stats_.overruns();
    hb.jitter_max_us = static_cast<float>(stats_.max_us());
    hb.jitter_mean_us = static_cast<float>(stats_.mean_us());
    hb.jitter_p99_us = static_cast<float>(stats_.p99_us());
    hb.tx_errors = can_.tx_errors();
    Frame frame;
    encode_heartbeat(hb, &frame);
    can_.send(frame);
    const int64_t period = static_cast<int64_t>(cfg_.heartbeat_ms) * 1000000;
    next_hb_ns_ += period;
    if (next_hb_ns_ <= now) next_hb_ns_ = now + period;
  }

  Bus &can_;
  Node &ctl_;
  int signal_fd_;
  LoopConfig cfg_;
  JitterStats &stats_;
  LoopResult result_;
  int64_t start_ns_ = 0;
  int64_t next_hb_ns_ = 0;
  uint32_t hb_counter_ = 0;
  uint64_t steps_per_slice_ = 1;
};

}  // namespace

LoopResult run_loop(Bus &can, Node &controller, int signal_fd, const LoopConfig &config,
                    JitterStats *stats) {
  return Loop(can, controller, signal_fd, config, stats).run();
}

void print_rt_stats(const char *what, const JitterStats &stats, double rate_hz) {
  std::fprintf(stderr,
               "hil_sim: %s: %llu ticks at %.1f Hz, %u overruns, wake-up lateness max %.1f us, "
               "mean %.1f us, p99 %.0f us\n",
               what, static_cast<unsigned long long>(stats.count()), rate_hz, stats.overruns(),
               stats.max_us(), stats.mean_us(), stats.p99_us());
}

}  // namespace hil
