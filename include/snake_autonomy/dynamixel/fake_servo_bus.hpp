// FakeServoBus: an in-process ServoBus for unit tests of whatever drives the bus (the driver's
// loop, its fault handling). Each servo has its control-table memory initialised from the YAML
// defaults and behaves like the real one where tests care: writes outside [min, max] or past
// the position limits are refused (data limit error), EEPROM entries are refused while torque is on
// (access error), a hardware error sets the alert bit in every reply and turns torque off, REBOOT
// clears it. Goal positions are reached at once unless set_follow_goal(false).
//
// Faults are injected by the test and take effect on the next transactions; nothing waits: a
// "timeout" returns kTimeout immediately. No allocation after construction.
#pragma once

#include <cstdint>
#include <vector>

#include "snake_autonomy/dynamixel/control_table.hpp"
#include "snake_autonomy/dynamixel/servo_bus.hpp"

namespace snake_autonomy::dynamixel {

class FakeServoBus : public ServoBus {
 public:
  // Throws ConfigError for an ID outside 0..252 or a repeated ID.
  FakeServoBus(const ControlTable& table, const std::vector<std::uint8_t>& ids);

  // ServoBus
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
  const BusCounters& counters() const noexcept override { return counters_; }
  void reset_counters() noexcept override { counters_ = BusCounters{}; }
  // Kept for inspection only: the fake answers at once.
  void set_return_delay_s(double seconds) noexcept override { return_delay_s_ = seconds; }
  double return_delay_s() const noexcept override { return return_delay_s_; }

  // --- fault injection ---
  void set_dead(std::uint8_t id, bool dead);                 // never answers (kTimeout)
  void inject_timeouts(std::uint8_t id, int count);          // the next `count` replies of id time out
  void inject_crc_errors(std::uint8_t id, int count);        // the next `count` replies of id: kCrcError
  void set_garbage(std::uint8_t id, bool garbage);           // replies carry garbage bytes (0xA5..., valid CRC)
  void set_hardware_error(std::uint8_t id, std::uint8_t bits);  // Hardware Error Status bits, alert bit, torque off
  void set_bus_down(bool down);                              // every call returns kIoError (port gone)
  void set_follow_goal(bool follow) noexcept { follow_goal_ = follow; }
  void clear_faults();

  // --- inspection and setting of the servos' memory ---
  std::int64_t get(std::uint8_t id, const std::string& entry) const;        // throws for unknown id/entry
  void set(std::uint8_t id, const std::string& entry, std::int64_t value);  // no checks: the test's word
  std::uint64_t sync_writes() const noexcept { return sync_writes_; }
  std::uint64_t sync_reads() const noexcept { return sync_reads_; }
  std::uint64_t goal_writes(std::uint8_t id) const;                           // accepted goal positions
  std::uint64_t refused_writes() const noexcept { return refused_writes_; }

 private:
  double return_delay_s_ = 0.0;
  struct Servo {
    std::uint8_t id = 0;
    std::vector<std::uint8_t> memory;  // 1024 bytes, sized at construction
    bool dead = false;
    bool garbage = false;
    int timeouts = 0;
    int crc_errors = 0;
    std::uint64_t goal_writes = 0;
  };
  Servo* find(std::uint8_t id) noexcept;
  const Servo& servo_or_throw(std::uint8_t id) const;
  Servo& servo_or_throw(std::uint8_t id);
  // The reply of one servo: kTimeout / kCrcError when a fault says so, else the error byte.
  Status reply_fault(Servo& s) noexcept;
  std::uint8_t alert(const Servo& s) const noexcept;
  // Applies a write; returns the error number (0 when accepted).
  std::uint8_t apply_write(Servo& s, std::uint16_t address, const std::uint8_t* data, std::uint16_t length) noexcept;
  void fill_read(const Servo& s, std::uint16_t address, std::uint16_t length, std::uint8_t* out) const noexcept;
  Status group_read(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                    std::uint8_t* data, ServoReply* replies) noexcept;

  ControlTable table_;
  std::vector<Servo> servos_;
  BusCounters counters_;
  bool follow_goal_ = true;
  bool bus_down_ = false;
  std::uint64_t sync_writes_ = 0, sync_reads_ = 0, refused_writes_ = 0;
  std::uint16_t addr_torque_ = 0, addr_hw_error_ = 0, addr_goal_ = 0, addr_present_ = 0;
  std::uint16_t addr_min_pos_ = 0, addr_max_pos_ = 0;
};

}  // namespace snake_autonomy::dynamixel
