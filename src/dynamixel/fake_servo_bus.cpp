#include "snake_autonomy/dynamixel/fake_servo_bus.hpp"

#include <algorithm>
#include <cstring>

namespace snake_autonomy::dynamixel {
namespace {
// Deadlines at the moment of sending: every reply is already in the loopback, so a missing one is
// a timeout at once instead of a wait.
BusTiming instant() noexcept {
  BusTiming t;
  t.latency_s = 0.0;
  t.return_delay_s = 0.0;
  t.margin = 0.0;
  return t;
}
}  // namespace

bool LoopbackTransport::write_all(const std::uint8_t* data, std::size_t size) noexcept {
  if (down_) return false;
  // The servos answer what arrives; a reply not read before the next write is discarded by the bus.
  pending_ = servos_.handle(data, size);
  read_ = 0;
  return true;
}

long LoopbackTransport::read_some(std::uint8_t* buffer, std::size_t capacity, SteadyTime /*deadline*/) noexcept {
  if (down_) return -1;
  const std::size_t n = std::min(capacity, pending_ - read_);
  if (n) std::memcpy(buffer, servos_.output() + read_, n);
  read_ += n;
  return static_cast<long>(n);
}

FakeServoBus::FakeServoBus(const ControlTable& table, const std::vector<std::uint8_t>& ids)
    : servos_(table, ids), loopback_(servos_), bus_(loopback_, instant()) {
  servos_.set_follow_goal(true);
}

void FakeServoBus::clear_faults() noexcept {
  servos_.clear_faults();
  loopback_.set_down(false);
}

Status FakeServoBus::ping(std::uint8_t id, std::uint16_t* model_number, std::uint8_t* error) noexcept {
  return bus_.ping(id, model_number, error);
}
Status FakeServoBus::read(std::uint8_t id, std::uint16_t address, std::uint16_t length, std::uint8_t* data,
                          std::uint8_t* error) noexcept {
  return bus_.read(id, address, length, data, error);
}
Status FakeServoBus::write(std::uint8_t id, std::uint16_t address, const std::uint8_t* data, std::uint16_t length,
                           std::uint8_t* error) noexcept {
  return bus_.write(id, address, data, length, error);
}
Status FakeServoBus::reboot(std::uint8_t id, std::uint8_t* error) noexcept { return bus_.reboot(id, error); }
Status FakeServoBus::sync_write(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                                const std::uint8_t* data) noexcept {
  return bus_.sync_write(address, length, ids, n, data);
}
Status FakeServoBus::sync_read(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                               std::uint8_t* data, ServoReply* replies) noexcept {
  return bus_.sync_read(address, length, ids, n, data, replies);
}
Status FakeServoBus::fast_sync_read(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                                    std::uint8_t* data, ServoReply* replies) noexcept {
  return bus_.fast_sync_read(address, length, ids, n, data, replies);
}

}  // namespace snake_autonomy::dynamixel
