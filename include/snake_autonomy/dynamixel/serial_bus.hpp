// SerialBus: the ServoBus on a serial port (U2D2 / FTDI adapter, or the mocked bus's pty).
// SerialPort is the termios transport: raw 8N1, any baud rate through termios2/BOTHER (1 to
// 4.5 Mbaud), and the ASYNC_LOW_LATENCY hint for FTDI adapters where the driver supports it (a
// pty rejects that ioctl: tolerated, see low_latency_applied()).
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "snake_autonomy/dynamixel/protocol2_bus.hpp"

namespace snake_autonomy::dynamixel {

// Opening or configuring the port failed; what() names the device, the setting and errno's text.
class SerialError : public std::runtime_error {
 public:
  explicit SerialError(const std::string& what) : std::runtime_error(what) {}
};

struct SerialConfig {
  std::string device;           // e.g. /dev/ttyUSB0 or the mock's symlink
  int baud_bps = 1000000;       // 9600 .. 4500000
  bool low_latency = true;      // ask the driver for ASYNC_LOW_LATENCY (FTDI: 1 ms instead of 16 ms)
  BusTiming timing;
  // Problems naming key and value (empty when valid).
  std::vector<std::string> validate() const;
};

class SerialPort : public Transport {
 public:
  SerialPort() = default;
  ~SerialPort() override { close(); }
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  // Opens and configures the device. Throws SerialError (device, setting, reason).
  void open(const std::string& device, int baud_bps, bool low_latency);
  void close() noexcept;
  // False when the driver refused ASYNC_LOW_LATENCY (always on a pty).
  bool low_latency_applied() const noexcept { return low_latency_applied_; }
  const std::string& device() const noexcept { return device_; }

  bool is_open() const noexcept override { return fd_ >= 0; }
  bool write_all(const std::uint8_t* data, std::size_t size) noexcept override;
  long read_some(std::uint8_t* buffer, std::size_t capacity, SteadyTime deadline) noexcept override;
  void discard_input() noexcept override;
  int baud_bps() const noexcept override { return baud_bps_; }

 private:
  int fd_ = -1;
  int baud_bps_ = 0;
  bool low_latency_applied_ = false;
  std::string device_;
};

class SerialBus : public ServoBus {
 public:
  // Validates the configuration (ConfigError naming key and value) and opens the port (SerialError).
  explicit SerialBus(const SerialConfig& config);

  Status ping(std::uint8_t id, std::uint16_t* model_number, std::uint8_t* error) noexcept override {
    return bus_.ping(id, model_number, error);
  }
  Status read(std::uint8_t id, std::uint16_t address, std::uint16_t length, std::uint8_t* data,
              std::uint8_t* error) noexcept override {
    return bus_.read(id, address, length, data, error);
  }
  Status write(std::uint8_t id, std::uint16_t address, const std::uint8_t* data, std::uint16_t length,
               std::uint8_t* error) noexcept override {
    return bus_.write(id, address, data, length, error);
  }
  Status reboot(std::uint8_t id, std::uint8_t* error) noexcept override { return bus_.reboot(id, error); }
  Status sync_write(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                    const std::uint8_t* data) noexcept override {
    return bus_.sync_write(address, length, ids, n, data);
  }
  Status sync_read(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                   std::uint8_t* data, ServoReply* replies) noexcept override {
    return bus_.sync_read(address, length, ids, n, data, replies);
  }
  Status fast_sync_read(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                        std::uint8_t* data, ServoReply* replies) noexcept override {
    return bus_.fast_sync_read(address, length, ids, n, data, replies);
  }
  const BusCounters& counters() const noexcept override { return bus_.counters(); }
  void reset_counters() noexcept override { bus_.reset_counters(); }
  void set_return_delay_s(double seconds) noexcept override { bus_.set_return_delay_s(seconds); }
  double return_delay_s() const noexcept override { return bus_.return_delay_s(); }

  const SerialConfig& config() const noexcept { return config_; }
  SerialPort& port() noexcept { return port_; }
  // Reopens the port after an I/O error (unplugged adapter, the mock restarted). Throws SerialError.
  void reopen();

 private:
  SerialConfig config_;
  SerialPort port_;
  Protocol2Bus bus_;
};

}  // namespace snake_autonomy::dynamixel
