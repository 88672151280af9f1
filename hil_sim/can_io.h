// SocketCAN: one raw AF_CAN socket with CAN FD frames on a named interface.
#ifndef HIL_SIM_CAN_IO_H
#define HIL_SIM_CAN_IO_H

#include <cstdint>
#include <string>

#include "frame.h"

namespace hil {

// What the run loop needs of a CAN socket: a descriptor to poll, frames in and out.
// SocketCan is the real one; the loop's tests use an in-memory one.
class Bus : public FrameSink {
 public:
  // Readable (POLLIN) while frames are pending.
  virtual int fd() const = 0;
  // Reads one frame: 1 read, 0 nothing pending, -1 socket error (errno set).
  virtual int receive(Frame *out) = 0;
  // How long send() may wait for room in a full socket buffer (0: drop at once).
  virtual void set_send_block_ms(int ms) = 0;
  virtual uint32_t tx_errors() const = 0;
};

class SocketCan : public Bus {
 public:
  SocketCan() = default;
  SocketCan(const SocketCan &) = delete;
  SocketCan &operator=(const SocketCan &) = delete;
  ~SocketCan() override;

  // Opens and binds the socket (non-blocking, CAN_RAW_FD_FRAMES). On failure returns false
  // and a one-line reason naming the call and what to do about it.
  bool open(const std::string &channel, std::string *error);
  void close();
  int fd() const override { return fd_; }

  int receive(Frame *out) override;
  // Sends one frame; when the socket buffer is full waits up to block_ms for room
  // (0: drop at once). Counts what it could not send.
  bool send(const Frame &frame) override;
  void set_send_block_ms(int ms) override { send_block_ms_ = ms; }
  uint32_t tx_errors() const override { return tx_errors_; }

 private:
  int fd_ = -1;
  int send_block_ms_ = 20;
  uint32_t tx_errors_ = 0;
};

}  // namespace hil

#endif
