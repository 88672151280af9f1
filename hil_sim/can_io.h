// SocketCAN: one raw AF_CAN socket with CAN FD frames on a named interface.
#ifndef HIL_SIM_CAN_IO_H
#define HIL_SIM_CAN_IO_H

#include <cstdint>
#include <string>

#include "frame.h"

namespace hil {

class SocketCan : public FrameSink {
 public:
  SocketCan() = default;
  SocketCan(const SocketCan &) = delete;
  SocketCan &operator=(const SocketCan &) = delete;
  ~SocketCan() override;

  // Opens and binds the socket (non-blocking, CAN_RAW_FD_FRAMES). On failure returns false
  // and a one-line reason naming the call and what to do about it.
  bool open(const std::string &channel, std::string *error);
  void close();
  int fd() const { return fd_; }

  // Reads one frame: 1 read, 0 nothing pending, -1 socket error (errno set).
  int receive(Frame *out);
  // Sends one frame; when the socket buffer is full waits up to block_ms for room
  // (0: drop at once). Counts what it could not send.
  bool send(const Frame &frame) override;
  void set_send_block_ms(int ms) { send_block_ms_ = ms; }
  uint32_t tx_errors() const { return tx_errors_; }

 private:
  int fd_ = -1;
  int send_block_ms_ = 20;
  uint32_t tx_errors_ = 0;
};

}  // namespace hil

#endif
