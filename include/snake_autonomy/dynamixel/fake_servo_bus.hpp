// FakeServoBus: an in-process ServoBus for unit tests of whatever drives the bus (the driver's loop,
// its fault handling) and for the batch simulator. It is the real protocol engine (Protocol2Bus)
// over a loopback transport into the one simulated servo chain (SimulatedServos): every packet is
// encoded, parsed and answered exactly as on the pty mock; the servo rules and the fault vocabulary
// are SimulatedServos' (see simulated_servos.hpp). Goal positions are reached at once unless
// set_follow_goal(false).
//
// Nothing waits: the replies are in the loopback as soon as the request is written, and a reply that
// does not come (drop_reply, silent) is a timeout at once. No allocation after construction.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "snake_autonomy/dynamixel/control_table.hpp"
#include "snake_autonomy/dynamixel/protocol2_bus.hpp"
#include "snake_autonomy/dynamixel/servo_bus.hpp"
#include "snake_autonomy/dynamixel/simulated_servos.hpp"

namespace snake_autonomy::dynamixel {

// A Transport whose other end is a SimulatedServos: written bytes are handled at once, the replies
// wait to be read. down(true): the port is gone (every write fails: kIoError).
class LoopbackTransport : public Transport {
 public:
  explicit LoopbackTransport(SimulatedServos& servos) noexcept : servos_(servos) {}
  bool is_open() const noexcept override { return true; }
  bool write_all(const std::uint8_t* data, std::size_t size) noexcept override;
  long read_some(std::uint8_t* buffer, std::size_t capacity, SteadyTime deadline) noexcept override;
  void discard_input() noexcept override { pending_ = read_ = 0; }
  int baud_bps() const noexcept override { return 4000000; }
  void set_down(bool down) noexcept { down_ = down; }
  bool down() const noexcept { return down_; }

 private:
  SimulatedServos& servos_;
  std::size_t pending_ = 0, read_ = 0;  // unread replies: servos_.output()[read_, pending_)
  bool down_ = false;
};

class FakeServoBus : public ServoBus {
 public:
  // Throws ConfigError for an invalid table, an ID outside 0..252 or a repeated ID.
  FakeServoBus(const ControlTable& table, const std::vector<std::uint8_t>& ids);

  // ServoBus: Protocol2Bus's.
  Status ping(std::uint8_t id, std::uint16_t* model_number, std::uint8_t* error) noexcept override;
  Status read(std::uint8_t id, std::uint16_t address, std::uint16_t length, std::uint8_t* data,
              std::uint8_t* error) noexcept override;
  Status write(std::uint8_t id, std::uint16_t address, const std::uint8_t* data, std::uint16_t length,
               std::uint8_t* error) noexcept override;
  Status reboot(std::uint8_t id, std::uint8_t* error) noexcept override;
  Status sync_write(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                    const std::uint8_t* data) noexcept override;
  Status sync_read(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                   std::uint8_t* data, ServoReply* replies) noexcept override;
  Status fast_sync_read(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                        std::uint8_t* data, ServoReply* replies) noexcept override;
  const BusCounters& counters() const noexcept override { return bus_.counters(); }
  void reset_counters() noexcept override { bus_.reset_counters(); }
  // Kept for inspection only: the fake answers at once.
  void set_return_delay_s(double seconds) noexcept override { return_delay_s_ = seconds; }
  double return_delay_s() const noexcept override { return return_delay_s_; }

  // The simulated servos: their memory, the fault injection (inject, set_silent,
  // set_hardware_error, clear_faults), their statistics.
  SimulatedServos& servos() noexcept { return servos_; }
  const SimulatedServos& servos() const noexcept { return servos_; }
  // The transport fault: every call returns kIoError (the port is gone).
  void set_bus_down(bool down) noexcept { loopback_.set_down(down); }
  void set_follow_goal(bool follow) noexcept { servos_.set_follow_goal(follow); }
  // clear_faults of the servos, and the bus back up.
  void clear_faults() noexcept;

 private:
  SimulatedServos servos_;
  LoopbackTransport loopback_;
  Protocol2Bus bus_;
  double return_delay_s_ = 0.0;
};

}  // namespace snake_autonomy::dynamixel
