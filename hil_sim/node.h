// What the run loop (run_loop.cpp) drives: a node's state machine over frames, STEP slices and
// real-time ticks. The leg and the two-leg robot (controller.h) and the hexapod
// (hexapod_node.h) are nodes; the loop keeps their heartbeat and signals the same way.
#ifndef HIL_SIM_NODE_H
#define HIL_SIM_NODE_H

#include <cstdint>

#include "frame.h"
#include "protocol.h"

namespace hil {

// What an exit did (signal or socket failure): a STEP cut short, the safe state applied.
struct NodeShutdown {
  bool step_cut = false;
  uint64_t step_done = 0, step_total = 0;
  bool safe_applied = false;
  legsim_status safe_status = LEGSIM_OK;
};

class Node {
 public:
  virtual ~Node() = default;
  virtual void on_frame(const Frame &frame, int64_t now_ns) = 0;
  // A STEP is accepted and not finished yet.
  virtual bool stepping() const = 0;
  // Advances the STEP in progress by at most max_steps steps; answers it when done.
  virtual uint64_t work(uint64_t max_steps) = 0;
  // On exit: a STEP in progress abandoned unanswered, the actuators put in the safe state.
  virtual NodeShutdown shutdown() = 0;
  // One real-time tick; no-op outside REALTIME.
  virtual void rt_tick(int64_t now_ns) = 0;
  virtual SimState state() const = 0;
  virtual int64_t rt_period_ns() const = 0;
  virtual uint32_t rt_epoch() const = 0;  // +1 at every START_RT
  virtual void fill_heartbeat(HeartbeatInfo *hb) const = 0;
};

}  // namespace hil

#endif
