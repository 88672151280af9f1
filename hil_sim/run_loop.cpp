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
  Loop(SocketCan &can, Controller &ctl, int signal_fd, const LoopConfig &cfg, JitterStats *stats)
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
        sleep_until(next);
        int64_t now = mono_ns();
        stats_.add(now - next);
        if (!service(0, 64)) break;
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
        int timeout_ms = -1;
        if (cfg_.heartbeat_ms > 0) {
          int64_t wait = next_hb_ns_ - mono_ns();
          timeout_ms = wait <= 0 ? 0 : static_cast<int>((wait + 999999) / 1000000);
        }
        if (!service(timeout_ms, 1024)) break;
        heartbeat_if_due(mono_ns());
      }
    }
    if (in_rt) print_rt_stats("real-time run (stopped by exit)", stats_, period > 0 ? 1e9 / period : 0.0);
    return result_;
  }

 private:
  // Waits up to timeout_ms for frames or a signal; handles up to max_frames frames.
  // False when the loop must stop.
  bool service(int timeout_ms, int max_frames) {
    struct pollfd fds[2] = {{can_.fd(), POLLIN, 0}, {signal_fd_, POLLIN, 0}};
    int n = ::poll(fds, 2, timeout_ms);
    if (n < 0) return errno == EINTR;
    if (fds[1].revents & POLLIN) {
      struct signalfd_siginfo si;
      if (::read(signal_fd_, &si, sizeof si) == static_cast<ssize_t>(sizeof si)) {
        result_.signal = static_cast<int>(si.ssi_signo);
        return false;
      }
    }
    if (fds[0].revents & (POLLERR | POLLHUP | POLLNVAL)) {
      result_.socket_errno = EIO;
      return false;
    }
    if (fds[0].revents & POLLIN) {
      Frame frame;
      for (int i = 0; i < max_frames; ++i) {
        int r = can_.receive(&frame);
        if (r == 0) break;
        if (r < 0) {
          result_.socket_errno = errno;
          return false;
        }
        ctl_.on_frame(frame, mono_ns());
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

  SocketCan &can_;
  Controller &ctl_;
  int signal_fd_;
  LoopConfig cfg_;
  JitterStats &stats_;
  LoopResult result_;
  int64_t start_ns_ = 0;
  int64_t next_hb_ns_ = 0;
  uint32_t hb_counter_ = 0;
};

}  // namespace

LoopResult run_loop(SocketCan &can, Controller &controller, int signal_fd,
                    const LoopConfig &config, JitterStats *stats) {
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
