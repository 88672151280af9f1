// One CAN (FD) frame as hil_sim sees it, independent of the socket layer.
#ifndef HIL_SIM_FRAME_H
#define HIL_SIM_FRAME_H

#include <cstdint>

namespace hil {

constexpr int kFdPayload = 64;

struct Frame {
  uint32_t id = 0;        // 11 bits, or 29 with extended
  bool extended = false;
  bool rtr = false;
  bool fd = false;        // CAN FD frame (else classic CAN, len <= 8)
  uint8_t len = 0;        // payload bytes
  uint8_t data[kFdPayload] = {};
};

// Where hil_sim's frames go: the socket, or a test's recorder.
class FrameSink {
 public:
  virtual ~FrameSink() = default;
  virtual bool send(const Frame &frame) = 0;
};

}  // namespace hil

#endif
