#include "snake_autonomy/dynamixel/fake_servo_bus.hpp"

#include <algorithm>
#include <cstring>

#include "snake_autonomy/dynamixel/protocol.hpp"

namespace snake_autonomy::dynamixel {
namespace {
constexpr std::size_t kMemoryBytes = 1024;
}

FakeServoBus::FakeServoBus(const ControlTable& table, const std::vector<std::uint8_t>& ids) : table_(table) {
  table_.validate_or_throw();
  addr_torque_ = table_.at("torque_enable").address;
  addr_hw_error_ = table_.at("hardware_error_status").address;
  addr_goal_ = table_.at("goal_position").address;
  addr_present_ = table_.at("present_position").address;
  addr_min_pos_ = table_.at("min_position_limit").address;
  addr_max_pos_ = table_.at("max_position_limit").address;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (ids[i] > kMaxServoId) throw ConfigError("ids[" + std::to_string(i) + "]: " + std::to_string(ids[i]) + " is not in 0..252");
    for (std::size_t j = 0; j < i; ++j) {
      if (ids[j] == ids[i]) throw ConfigError("ids[" + std::to_string(i) + "]: " + std::to_string(ids[i]) + " repeats ids[" + std::to_string(j) + "]");
    }
    Servo s;
    s.id = ids[i];
    s.memory.assign(kMemoryBytes, 0);
    for (const auto& e : table_.entries) put_le(&s.memory[e.address], e.size, e.default_value);
    if (const auto* e = table_.find("id")) put_le(&s.memory[e->address], e->size, ids[i]);
    servos_.push_back(std::move(s));
  }
}

FakeServoBus::Servo* FakeServoBus::find(std::uint8_t id) noexcept {
  for (auto& s : servos_) {
    if (s.id == id) return &s;
  }
  return nullptr;
}

const FakeServoBus::Servo& FakeServoBus::servo_or_throw(std::uint8_t id) const {
  for (const auto& s : servos_) {
    if (s.id == id) return s;
  }
  throw ConfigError("FakeServoBus: no servo with ID " + std::to_string(id));
}

FakeServoBus::Servo& FakeServoBus::servo_or_throw(std::uint8_t id) {
  Servo* s = find(id);
  if (!s) throw ConfigError("FakeServoBus: no servo with ID " + std::to_string(id));
  return *s;
}

std::uint8_t FakeServoBus::alert(const Servo& s) const noexcept { return s.memory[addr_hw_error_] ? kAlertBit : 0; }

Status FakeServoBus::reply_fault(Servo& s) noexcept {
  if (s.dead) return Status::kTimeout;
  if (s.timeouts > 0) {
    --s.timeouts;
    return Status::kTimeout;
  }
  if (s.crc_errors > 0) {
    --s.crc_errors;
    return Status::kCrcError;
  }
  return Status::kOk;
}

std::uint8_t FakeServoBus::apply_write(Servo& s, std::uint16_t address, const std::uint8_t* data,
                                       std::uint16_t length) noexcept {
  if (address + length > kMemoryBytes) return servo_error::kDataRangeError;
  const bool torque_on = s.memory[addr_torque_] != 0;
  // Check everything first: a refused write changes nothing.
  for (const auto& e : table_.entries) {
    if (e.address + e.size <= address || e.address >= address + length) continue;
    if (!e.writable) return servo_error::kAccessError;
    if (e.eeprom && torque_on) return servo_error::kAccessError;
    if (e.address < address || e.address + e.size > address + length) return servo_error::kDataLengthError;
    const std::int64_t v = get_le(data + (e.address - address), e.size, e.is_signed);
    if (e.has_range && (v < e.min || v > e.max)) return servo_error::kDataLimitError;
    if (e.address == addr_goal_) {
      const std::int64_t lo = get_le(&s.memory[addr_min_pos_], 4, true);
      const std::int64_t hi = get_le(&s.memory[addr_max_pos_], 4, true);
      if (v < lo || v > hi) return servo_error::kDataLimitError;
    }
    if (e.address == addr_torque_ && v != 0 && s.memory[addr_hw_error_] != 0) return servo_error::kResultFail;
  }
  std::memcpy(&s.memory[address], data, length);
  if (address <= addr_goal_ && addr_goal_ + 4 <= address + length) {
    ++s.goal_writes;
    if (follow_goal_ && s.memory[addr_torque_]) std::memcpy(&s.memory[addr_present_], &s.memory[addr_goal_], 4);
  }
  return 0;
}

void FakeServoBus::fill_read(const Servo& s, std::uint16_t address, std::uint16_t length,
                             std::uint8_t* out) const noexcept {
  if (s.garbage) {
    std::memset(out, 0xA5, length);
  } else {
    std::memcpy(out, &s.memory[address], length);
  }
}

Status FakeServoBus::ping(std::uint8_t id, std::uint16_t* model_number, std::uint8_t* error) noexcept {
  if (error) *error = 0;
  ++counters_.transactions;
  if (bus_down_) return ++counters_.io_errors, Status::kIoError;
  Servo* s = find(id);
  const Status f = s ? reply_fault(*s) : Status::kTimeout;
  if (f == Status::kTimeout) return ++counters_.timeouts, f;
  if (f == Status::kCrcError) return ++counters_.crc_errors, f;
  if (model_number) *model_number = static_cast<std::uint16_t>(get_le(&s->memory[0], 2, false));
  if (error) *error = alert(*s);
  if (alert(*s)) return ++counters_.hardware_error_alerts, Status::kHardwareError;
  return Status::kOk;
}

Status FakeServoBus::read(std::uint8_t id, std::uint16_t address, std::uint16_t length, std::uint8_t* data,
                          std::uint8_t* error) noexcept {
  if (error) *error = 0;
  if (!data || length == 0 || id > kMaxServoId) return Status::kInvalidArgument;
  ++counters_.transactions;
  if (bus_down_) return ++counters_.io_errors, Status::kIoError;
  Servo* s = find(id);
  const Status f = s ? reply_fault(*s) : Status::kTimeout;
  if (f == Status::kTimeout) return ++counters_.timeouts, f;
  if (f == Status::kCrcError) return ++counters_.crc_errors, f;
  if (address + length > kMemoryBytes) {
    if (error) *error = static_cast<std::uint8_t>(servo_error::kDataRangeError | alert(*s));
    return ++counters_.servo_errors, Status::kServoError;
  }
  fill_read(*s, address, length, data);
  if (error) *error = alert(*s);
  if (alert(*s)) return ++counters_.hardware_error_alerts, Status::kHardwareError;
  return Status::kOk;
}

Status FakeServoBus::write(std::uint8_t id, std::uint16_t address, const std::uint8_t* data, std::uint16_t length,
                           std::uint8_t* error) noexcept {
  if (error) *error = 0;
  if (!data || length == 0 || (id > kMaxServoId && id != kBroadcastId)) return Status::kInvalidArgument;
  ++counters_.transactions;
  if (bus_down_) return ++counters_.io_errors, Status::kIoError;
  if (id == kBroadcastId) {
    for (auto& s : servos_) {
      if (!s.dead && apply_write(s, address, data, length) != 0) ++refused_writes_;
    }
    return Status::kOk;
  }
  Servo* s = find(id);
  const Status f = s ? reply_fault(*s) : Status::kTimeout;
  if (f == Status::kTimeout) return ++counters_.timeouts, f;
  const std::uint8_t err = apply_write(*s, address, data, length);  // the servo got it even if its reply is lost
  if (err) ++refused_writes_;
  if (f == Status::kCrcError) return ++counters_.crc_errors, f;
  if (error) *error = static_cast<std::uint8_t>(err | alert(*s));
  if (err) return ++counters_.servo_errors, Status::kServoError;
  if (alert(*s)) return ++counters_.hardware_error_alerts, Status::kHardwareError;
  return Status::kOk;
}

Status FakeServoBus::reboot(std::uint8_t id, std::uint8_t* error) noexcept {
  if (error) *error = 0;
  ++counters_.transactions;
  if (bus_down_) return ++counters_.io_errors, Status::kIoError;
  Servo* s = find(id);
  const Status f = s ? reply_fault(*s) : Status::kTimeout;
  if (f == Status::kTimeout) return ++counters_.timeouts, f;
  s->memory[addr_hw_error_] = 0;
  s->memory[addr_torque_] = 0;
  if (f == Status::kCrcError) return ++counters_.crc_errors, f;
  return Status::kOk;
}

Status FakeServoBus::sync_write(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                                const std::uint8_t* data) noexcept {
  if (!ids || !data || n == 0 || length == 0) return Status::kInvalidArgument;
  ++counters_.transactions;
  if (bus_down_) return ++counters_.io_errors, Status::kIoError;
  ++sync_writes_;
  for (std::size_t i = 0; i < n; ++i) {
    Servo* s = find(ids[i]);
    if (!s || s->dead) continue;
    if (apply_write(*s, address, data + i * length, length) != 0) ++refused_writes_;
  }
  return Status::kOk;
}

Status FakeServoBus::group_read(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                                std::uint8_t* data, ServoReply* replies) noexcept {
  if (!ids || !data || !replies || n == 0 || length == 0 || address + length > kMemoryBytes) return Status::kInvalidArgument;
  ++counters_.transactions;
  ++sync_reads_;
  Status first = Status::kOk;
  for (std::size_t i = 0; i < n; ++i) {
    ServoReply& r = replies[i];
    r = ServoReply{};
    Servo* s = bus_down_ ? nullptr : find(ids[i]);
    if (bus_down_) {
      r.status = Status::kIoError;
    } else if (!s) {
      r.status = Status::kTimeout;
    } else {
      r.status = reply_fault(*s);
    }
    if (r.status == Status::kTimeout) ++counters_.timeouts;
    if (r.status == Status::kCrcError) ++counters_.crc_errors;
    if (r.status == Status::kIoError) ++counters_.io_errors;
    if (r.status == Status::kOk) {
      fill_read(*s, address, length, data + i * length);
      r.error = alert(*s);
      if (r.error) {
        r.status = Status::kHardwareError;
        ++counters_.hardware_error_alerts;
      }
    }
    if (first == Status::kOk && r.status != Status::kOk) first = r.status;
  }
  return first;
}

Status FakeServoBus::sync_read(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                               std::uint8_t* data, ServoReply* replies) noexcept {
  return group_read(address, length, ids, n, data, replies);
}

Status FakeServoBus::fast_sync_read(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids,
                                    std::size_t n, std::uint8_t* data, ServoReply* replies) noexcept {
  // One shared status packet: a CRC error in it loses every servo's data.
  const Status s = group_read(address, length, ids, n, data, replies);
  bool crc = false;
  for (std::size_t i = 0; i < n && replies; ++i) crc = crc || replies[i].status == Status::kCrcError;
  if (!crc) return s;
  for (std::size_t i = 0; i < n; ++i) replies[i] = ServoReply{Status::kCrcError, 0};
  return Status::kCrcError;
}

void FakeServoBus::set_dead(std::uint8_t id, bool dead) { servo_or_throw(id).dead = dead; }
void FakeServoBus::inject_timeouts(std::uint8_t id, int count) { servo_or_throw(id).timeouts = count; }
void FakeServoBus::inject_crc_errors(std::uint8_t id, int count) { servo_or_throw(id).crc_errors = count; }
void FakeServoBus::set_garbage(std::uint8_t id, bool garbage) { servo_or_throw(id).garbage = garbage; }
void FakeServoBus::set_bus_down(bool down) { bus_down_ = down; }

void FakeServoBus::set_hardware_error(std::uint8_t id, std::uint8_t bits) {
  Servo& s = servo_or_throw(id);
  s.memory[addr_hw_error_] = bits;
  if (bits) s.memory[addr_torque_] = 0;  // the servo's shutdown: torque off
}

void FakeServoBus::clear_faults() {
  bus_down_ = false;
  for (auto& s : servos_) {
    s.dead = s.garbage = false;
    s.timeouts = s.crc_errors = 0;
    s.memory[addr_hw_error_] = 0;
  }
}

std::int64_t FakeServoBus::get(std::uint8_t id, const std::string& entry) const {
  const Servo& s = servo_or_throw(id);
  const auto& e = table_.at(entry);
  return get_le(&s.memory[e.address], e.size, e.is_signed);
}

void FakeServoBus::set(std::uint8_t id, const std::string& entry, std::int64_t value) {
  Servo& s = servo_or_throw(id);
  const auto& e = table_.at(entry);
  put_le(&s.memory[e.address], e.size, value);
}

std::uint64_t FakeServoBus::goal_writes(std::uint8_t id) const { return servo_or_throw(id).goal_writes; }

}  // namespace snake_autonomy::dynamixel
