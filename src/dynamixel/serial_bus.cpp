// The termios side. termios2 (for BOTHER, any baud rate) comes from <asm/termbits.h>, which
// clashes with glibc's <termios.h>: this file uses the kernel's structures only.
#include "snake_autonomy/dynamixel/serial_bus.hpp"

#include <asm/termbits.h>
#include <fcntl.h>
#include <linux/serial.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <vector>

#include "snake_autonomy/core/robot_model.hpp"  // ConfigError

namespace snake_autonomy::dynamixel {
namespace {

constexpr int kMinBaud = 9600;
constexpr int kMaxBaud = 4500000;

std::string errno_text(int err) { return std::string(std::strerror(err)) + " (errno " + std::to_string(err) + ")"; }

}  // namespace

std::vector<std::string> SerialConfig::validate() const {
  std::vector<std::string> errors;
  if (device.empty()) errors.push_back("device: empty");
  if (baud_bps < kMinBaud || baud_bps > kMaxBaud) {
    errors.push_back("baud_bps: " + std::to_string(baud_bps) + " is not in " + std::to_string(kMinBaud) + ".." +
                     std::to_string(kMaxBaud));
  }
  if (!(timing.latency_s >= 0.0 && timing.latency_s <= 1.0)) {
    errors.push_back("timing.latency_s: " + std::to_string(timing.latency_s) + " is not in 0..1 s");
  }
  if (!(timing.return_delay_s >= 0.0 && timing.return_delay_s <= 0.001)) {
    errors.push_back("timing.return_delay_s: " + std::to_string(timing.return_delay_s) + " is not in 0..0.001 s");
  }
  if (!(timing.margin >= 1.0 && timing.margin <= 10.0)) {
    errors.push_back("timing.margin: " + std::to_string(timing.margin) + " is not in 1..10");
  }
  return errors;
}

void SerialPort::open(const std::string& device, int baud_bps, bool low_latency) {
  close();
  if (baud_bps < kMinBaud || baud_bps > kMaxBaud) {
    throw SerialError(device + ": baud rate " + std::to_string(baud_bps) + " is not in " + std::to_string(kMinBaud) +
                      ".." + std::to_string(kMaxBaud));
  }
  const int fd = ::open(device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw SerialError(device + ": cannot open: " + errno_text(errno));
  struct termios2 tio;
  if (ioctl(fd, TCGETS2, &tio) != 0) {
    const int err = errno;
    ::close(fd);
    throw SerialError(device + ": not a serial port (TCGETS2): " + errno_text(err));
  }
  // Raw 8N1, no flow control, no echo, no translation; reads return at once (VMIN = VTIME = 0).
  tio.c_iflag &=
      ~static_cast<tcflag_t>(IGNBRK | BRKINT | PARMRK | ISTRIP | INLCR | IGNCR | ICRNL | IXON | IXOFF | IXANY);
  tio.c_oflag &= ~static_cast<tcflag_t>(OPOST);
  tio.c_lflag &= ~static_cast<tcflag_t>(ECHO | ECHONL | ICANON | ISIG | IEXTEN);
  tio.c_cflag &= ~static_cast<tcflag_t>(CSIZE | PARENB | CSTOPB | CRTSCTS | CBAUD | (CBAUD << IBSHIFT));
  tio.c_cflag |= CS8 | CLOCAL | CREAD | BOTHER | (BOTHER << IBSHIFT);
  tio.c_ispeed = static_cast<speed_t>(baud_bps);
  tio.c_ospeed = static_cast<speed_t>(baud_bps);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  if (ioctl(fd, TCSETS2, &tio) != 0) {
    const int err = errno;
    ::close(fd);
    throw SerialError(device + ": cannot set baud rate " + std::to_string(baud_bps) +
                      " (TCSETS2/BOTHER): " + errno_text(err));
  }
  low_latency_applied_ = false;
  if (low_latency) {
    // FTDI adapters buffer received bytes for up to 16 ms unless asked for low latency. A pty (the
    // mocked bus) and some drivers do not know this ioctl: that is not an error.
    struct serial_struct ss;
    if (ioctl(fd, TIOCGSERIAL, &ss) == 0) {
      ss.flags |= ASYNC_LOW_LATENCY;
      low_latency_applied_ = ioctl(fd, TIOCSSERIAL, &ss) == 0;
    }
  }
  ioctl(fd, TCFLSH, TCIOFLUSH);
  fd_ = fd;
  baud_bps_ = baud_bps;
  device_ = device;
}

void SerialPort::close() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

bool SerialPort::write_all(const std::uint8_t* data, std::size_t size) noexcept {
  if (fd_ < 0) return false;
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(fd_, data + done, size - done);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno == EAGAIN) {
      pollfd p{fd_, POLLOUT, 0};
      if (::poll(&p, 1, 100) <= 0 || (p.revents & (POLLERR | POLLHUP | POLLNVAL))) return false;
      continue;
    }
    return false;
  }
  return true;
}

long SerialPort::read_some(std::uint8_t* buffer, std::size_t capacity, SteadyTime deadline) noexcept {
  if (fd_ < 0) return -1;
  for (;;) {
    const ssize_t n = ::read(fd_, buffer, capacity);
    if (n > 0) return static_cast<long>(n);
    if (n < 0 && errno != EAGAIN && errno != EINTR) return -1;  // EIO: the pty's other side closed
    const auto left = deadline - std::chrono::steady_clock::now();
    if (left <= SteadyTime::duration::zero()) return 0;
    const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(left).count();
    timespec ts{static_cast<time_t>(ns / 1000000000), static_cast<long>(ns % 1000000000)};
    pollfd p{fd_, POLLIN, 0};
    const int r = ::ppoll(&p, 1, &ts, nullptr);
    if (r < 0 && errno != EINTR) return -1;
    if (r > 0 && (p.revents & (POLLERR | POLLNVAL))) return -1;
    if (r > 0 && (p.revents & POLLHUP) && !(p.revents & POLLIN)) return -1;
  }
}

void SerialPort::discard_input() noexcept {
  if (fd_ >= 0) ioctl(fd_, TCFLSH, TCIFLUSH);
}

// ---------------------------------------------------------------------------------------------
namespace {
const SerialConfig& validated(const SerialConfig& c) {
  const auto errors = c.validate();
  if (!errors.empty()) {
    std::string what = "serial bus configuration is invalid:";
    for (const auto& e : errors) what += "\n  " + e;
    throw core::ConfigError(what);
  }
  return c;
}
}  // namespace

SerialBus::SerialBus(const SerialConfig& config) : config_(validated(config)), bus_(port_, config.timing) {
  port_.open(config_.device, config_.baud_bps, config_.low_latency);
}

void SerialBus::reopen() { port_.open(config_.device, config_.baud_bps, config_.low_latency); }

}  // namespace snake_autonomy::dynamixel
