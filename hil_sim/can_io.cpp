// SocketCAN raw socket with CAN FD frames.
#include "can_io.h"

#include <cerrno>
#include <cstring>

#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#ifndef CANFD_FDF
#define CANFD_FDF 0x04
#endif

namespace hil {

namespace {

std::string errno_text(int err) { return std::strerror(err); }

}  // namespace

SocketCan::~SocketCan() { close(); }

void SocketCan::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

bool SocketCan::open(const std::string &channel, std::string *error) {
  close();
  if (channel.empty() || channel.size() >= IFNAMSIZ) {
    *error = "bad CAN interface name '" + channel + "'";
    return false;
  }
  int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    int err = errno;
    *error = "socket(AF_CAN) failed: " + errno_text(err);
    if (err == EAFNOSUPPORT || err == EPROTONOSUPPORT)
      *error += " - no SocketCAN in this kernel; use tools/with-vcan";
    return false;
  }
  fd_ = fd;

  // the interface: exists, is CAN FD capable (MTU 72)
  struct ifreq ifr;
  std::memset(&ifr, 0, sizeof ifr);
  std::strncpy(ifr.ifr_name, channel.c_str(), IFNAMSIZ - 1);
  if (::ioctl(fd, SIOCGIFINDEX, &ifr) < 0) {
    int err = errno;
    *error = "no CAN interface '" + channel + "' (" + errno_text(err) +
             "); create it: ip link add dev " + channel + " type vcan && ip link set " + channel +
             " mtu 72 up (or run under tools/with-vcan)";
    close();
    return false;
  }
  int ifindex = ifr.ifr_ifindex;
  if (::ioctl(fd, SIOCGIFMTU, &ifr) == 0 && ifr.ifr_mtu != static_cast<int>(CANFD_MTU)) {
    *error = "CAN interface '" + channel + "' has MTU " + std::to_string(ifr.ifr_mtu) +
             ", not CAN FD (72): ip link set " + channel + " mtu 72";
    close();
    return false;
  }

  int on = 1;
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) < 0) {
    *error = "setsockopt(CAN_RAW_FD_FRAMES) failed: " + errno_text(errno) +
             " (kernel without CAN FD support)";
    close();
    return false;
  }
  // a generous receive buffer: a burst of commands must not be dropped while stepping
  int rcvbuf = 1 << 20;
  ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);

  struct sockaddr_can addr;
  std::memset(&addr, 0, sizeof addr);
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifindex;
  if (::bind(fd, reinterpret_cast<struct sockaddr *>(&addr), sizeof addr) < 0) {
    *error = "bind(" + channel + ") failed: " + errno_text(errno);
    close();
    return false;
  }
  return true;
}

int SocketCan::receive(Frame *out) {
  struct canfd_frame raw;
  ssize_t n = ::read(fd_, &raw, sizeof raw);
  if (n < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return 0;
    return -1;
  }
  if (n != static_cast<ssize_t>(CANFD_MTU) && n != static_cast<ssize_t>(CAN_MTU)) return 0;
  out->fd = n == static_cast<ssize_t>(CANFD_MTU);
  out->extended = (raw.can_id & CAN_EFF_FLAG) != 0;
  out->rtr = (raw.can_id & CAN_RTR_FLAG) != 0;
  out->id = raw.can_id & (out->extended ? CAN_EFF_MASK : CAN_SFF_MASK);
  out->len = raw.len > kFdPayload ? kFdPayload : raw.len;
  std::memset(out->data, 0, sizeof out->data);
  std::memcpy(out->data, raw.data, out->len);
  return 1;
}

bool SocketCan::send(const Frame &frame) {
  struct canfd_frame raw;
  std::memset(&raw, 0, sizeof raw);
  raw.can_id = frame.id | (frame.extended ? CAN_EFF_FLAG : 0u);
  raw.len = frame.len;
  raw.flags = frame.fd ? CANFD_FDF : 0;
  std::memcpy(raw.data, frame.data, frame.len);
  size_t size = frame.fd ? CANFD_MTU : CAN_MTU;
  for (int attempt = 0; attempt < 2; ++attempt) {
    if (::write(fd_, &raw, size) == static_cast<ssize_t>(size)) return true;
    if ((errno != ENOBUFS && errno != EAGAIN) || send_block_ms_ <= 0) break;
    struct pollfd p = {fd_, POLLOUT, 0};
    ::poll(&p, 1, send_block_ms_);
  }
  ++tx_errors_;
  return false;
}

}  // namespace hil
