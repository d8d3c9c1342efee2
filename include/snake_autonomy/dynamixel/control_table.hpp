// A servo model's control table as data: config/dynamixel/<model>.yaml, loaded and validated.
// validate() collects every problem, naming key and value; loading refuses a table with any.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "snake_autonomy/core/robot_model.hpp"  // ConfigError
#include "snake_autonomy/dynamixel/conversions.hpp"

namespace snake_autonomy::dynamixel {

using core::ConfigError;

struct ControlTableEntry {
  std::string name;
  std::uint16_t address = 0;
  std::uint8_t size = 0;       // 1, 2 or 4 bytes
  bool is_signed = false;
  bool writable = false;       // access: rw
  bool eeprom = false;         // written only while torque is off
  std::string unit;            // "" when the raw value has no unit
  double scale = 1.0;          // `unit` per raw unit
  std::int64_t default_value = 0;
  bool has_range = false;      // min/max given
  std::int64_t min = 0, max = 0;
};

struct ControlTable {
  std::string model;
  int model_number = 0;
  std::int32_t position_centre_ticks = 2048;
  // Output torque per ampere of Present Current (N*m/A), for JointState.effort; 0 when the table
  // gives none (the driver then publishes no effort). See torque_nm() for the model and its limits.
  double torque_constant_nm_per_a = 0.0;
  std::vector<std::pair<std::string, int>> hardware_error_bits;  // name, bit (0-7)
  std::vector<ControlTableEntry> entries;                        // in file order

  // nullptr when absent.
  const ControlTableEntry* find(const std::string& name) const noexcept;
  // Throws ConfigError naming the table and the entry when absent.
  const ControlTableEntry& at(const std::string& name) const;

  // Every problem, each naming key and value; empty when usable. Checks sizes, addresses (no two
  // entries overlap), ranges, the entries the driver needs, and that present current, velocity
  // and position are the contiguous 10-byte block at kFeedbackAddress.
  std::vector<std::string> validate() const;
  void validate_or_throw() const;

  // Unit scales derived from the entries' units (deg, rpm, mA, V).
  UnitScales unit_scales() const;
  // "overload, overheating" for the bits of Hardware Error Status; "none" for 0.
  std::string describe_hardware_error(std::uint8_t bits) const;

  static ControlTable from_yaml_file(const std::string& path);
  static ControlTable from_yaml_string(const std::string& text, const std::string& source = "<string>");
};

// The entries the driver relies on; validate() requires each.
extern const char* const kRequiredEntries[];
extern const std::size_t kNumRequiredEntries;

}  // namespace snake_autonomy::dynamixel
