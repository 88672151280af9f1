// The I/O and timing loop: lockstep (block on the socket until a frame or a heartbeat is
// due) and real time (clock_nanosleep TIMER_ABSTIME on CLOCK_MONOTONIC, one tick per period,
// frames drained at every tick). Stops on SIGINT/SIGTERM/SIGHUP read from a signalfd.
//
// Liveness, whatever hil_sim is asked to do: the heartbeat goes out on its 100 ms grid and
// a signal is answered within a few milliseconds (at most kStopCheckMs, plus one step
// and one frame's work):
// - a STEP is worked in slices of about kSliceUs of wall time (the steps per slice adapt
//   to the measured step time); between slices the loop sends a due heartbeat and reads
//   the signalfd. Frames are not read during a STEP (they wait in the socket, in order);
// - at most kMaxFramesPerWake frames are handled per wake-up, and reading stops at a due
//   heartbeat and after a frame that starts a STEP;
// - a real-time sleep is cut at a due heartbeat and at least every kStopCheckMs.
// On a signal the STEP in progress is abandoned (unanswered) and the actuators are put in
// the safe state (Node::shutdown).
#ifndef HIL_SIM_RUN_LOOP_H
#define HIL_SIM_RUN_LOOP_H

#include <cstdint>

#include "can_io.h"
#include "node.h"
#include "jitter.h"

namespace hil {

constexpr int kSliceUs = 1000;          // target wall time of one slice of a STEP
constexpr int kMaxFramesPerWake = 64;   // frames handled before the loop looks around
constexpr int kStopCheckMs = 20;        // longest sleep without reading the signalfd

struct LoopConfig {
  uint32_t heartbeat_ms = 100;  // 0: none
  bool verbose = false;
};

struct LoopResult {
  int signal = 0;       // the signal that stopped the loop, 0 if the socket failed
  int socket_errno = 0;
  NodeShutdown shutdown;  // what the exit did (STEP cut short, safe state)
};

LoopResult run_loop(Bus &can, Node &controller, int signal_fd, const LoopConfig &config,
                    JitterStats *stats);

// "real-time run: N ticks at R Hz, O overruns, wake-up lateness max/mean/p99 ..."
void print_rt_stats(const char *what, const JitterStats &stats, double rate_hz);

}  // namespace hil

#endif
