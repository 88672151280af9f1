// The I/O and timing loop: lockstep (block on the socket until a frame or a heartbeat is
// due) and real time (clock_nanosleep TIMER_ABSTIME on CLOCK_MONOTONIC, one tick per period,
// frames drained at every tick). Stops on SIGINT/SIGTERM/SIGHUP read from a signalfd.
#ifndef HIL_SIM_RUN_LOOP_H
#define HIL_SIM_RUN_LOOP_H

#include <cstdint>

#include "can_io.h"
#include "controller.h"
#include "jitter.h"

namespace hil {

struct LoopConfig {
  uint32_t heartbeat_ms = 100;  // 0: none
  bool verbose = false;
};

struct LoopResult {
  int signal = 0;       // the signal that stopped the loop, 0 if the socket failed
  int socket_errno = 0;
};

LoopResult run_loop(SocketCan &can, Controller &controller, int signal_fd,
                    const LoopConfig &config, JitterStats *stats);

// "real-time run: N ticks at R Hz, O overruns, wake-up lateness max/mean/p99 ..."
void print_rt_stats(const char *what, const JitterStats &stats, double rate_hz);

}  // namespace hil

#endif
