#include <gtest/gtest.h>

#include <string>

#include "snake_autonomy/dynamixel/control_table.hpp"

namespace dx = snake_autonomy::dynamixel;

namespace {
const std::string kXh540 = std::string(SNAKE_SOURCE_DIR) + "/config/dynamixel/xh540_w270.yaml";

std::string load_error(const std::string& yaml) {
  try {
    dx::ControlTable::from_yaml_string(yaml, "test.yaml");
  } catch (const dx::ConfigError& e) {
    return e.what();
  }
  return "";
}

// A minimal valid table with one line replaced.
std::string table_with(const std::string& replace_key, const std::string& line) {
  std::string base =
      "model: t\nmodel_number: 1100\nentries:\n"
      "  model_number: {address: 0, size: 2, access: r}\n"
      "  return_delay_time: {address: 9, size: 1, access: rw, eeprom: true}\n"
      "  operating_mode: {address: 11, size: 1, access: rw, eeprom: true}\n"
      "  min_position_limit: {address: 52, size: 4, access: rw, eeprom: true, min: 0, max: 4095}\n"
      "  max_position_limit: {address: 48, size: 4, access: rw, eeprom: true, min: 0, max: 4095}\n"
      "  torque_enable: {address: 64, size: 1, access: rw, min: 0, max: 1}\n"
      "  hardware_error_status: {address: 70, size: 1, access: r}\n"
      "  goal_position: {address: 116, size: 4, access: rw, signed: true, min: 0, max: 4095}\n"
      "  present_current: {address: 126, size: 2, access: r, signed: true, unit: mA, scale: 2.69}\n"
      "  present_velocity: {address: 128, size: 4, access: r, signed: true, unit: rpm, scale: 0.229}\n"
      "  present_position: {address: 132, size: 4, access: r, signed: true, unit: deg, scale: 0.087890625}\n"
      "  present_input_voltage: {address: 144, size: 2, access: r, unit: V, scale: 0.1}\n"
      "  present_temperature: {address: 146, size: 1, access: r, unit: degC}\n";
  if (replace_key.empty()) return base;
  const auto start = base.find("  " + replace_key + ":");
  const auto end = base.find('\n', start);
  return base.replace(start, end - start, line);
}
}  // namespace

TEST(ControlTable, LoadsXh540WithTheIssueAddresses) {
  const auto t = dx::ControlTable::from_yaml_file(kXh540);
  EXPECT_EQ(t.model, "xh540_w270");
  EXPECT_EQ(t.model_number, 1100);
  struct Want {
    const char* name;
    int address, size;
    bool is_signed;
  };
  for (const Want& w : {Want{"return_delay_time", 9, 1, false}, Want{"operating_mode", 11, 1, false},
                        Want{"torque_enable", 64, 1, false}, Want{"hardware_error_status", 70, 1, false},
                        Want{"goal_position", 116, 4, true}, Want{"present_current", 126, 2, true},
                        Want{"present_velocity", 128, 4, true}, Want{"present_position", 132, 4, true},
                        Want{"present_input_voltage", 144, 2, false}, Want{"present_temperature", 146, 1, false}}) {
    const auto& e = t.at(w.name);
    EXPECT_EQ(e.address, w.address) << w.name;
    EXPECT_EQ(e.size, w.size) << w.name;
    EXPECT_EQ(e.is_signed, w.is_signed) << w.name;
  }
  const dx::UnitScales s = t.unit_scales();
  EXPECT_NEAR(s.rad_per_tick, dx::kXh540Scales.rad_per_tick, 1e-15);
  EXPECT_NEAR(s.rad_s_per_velocity_unit, dx::kXh540Scales.rad_s_per_velocity_unit, 1e-15);
  EXPECT_NEAR(s.amps_per_current_unit, dx::kXh540Scales.amps_per_current_unit, 1e-15);
  EXPECT_EQ(s.centre_ticks, 2048);
  EXPECT_EQ(t.describe_hardware_error(0), "none");
  EXPECT_EQ(t.describe_hardware_error(0x24), "overheating, overload");
  EXPECT_EQ(t.describe_hardware_error(0x42), "bit 1, bit 6");
  EXPECT_THROW(t.at("no_such_entry"), dx::ConfigError);
}

TEST(ControlTable, MinimalTableIsValid) { EXPECT_EQ(load_error(table_with("", "")), ""); }

// JointState.effort = current x torque constant: the XH540-W270's 12 V stall point, 10.6 N*m at 4.4 A.
TEST(ControlTable, TorqueConstantOfTheXh540IsTheStallRatioAndOptional) {
  const auto t = dx::ControlTable::from_yaml_file(kXh540);
  EXPECT_NEAR(t.torque_constant_nm_per_a, 10.6 / 4.4, 1e-3);
  EXPECT_EQ(dx::ControlTable::from_yaml_string(table_with("", ""), "t.yaml").torque_constant_nm_per_a, 0.0);
  const std::string error = load_error("torque_constant_nm_per_a: -2.4\n" + table_with("", ""));
  EXPECT_NE(error.find("torque_constant_nm_per_a: -2.4 is not a finite number >= 0"), std::string::npos) << error;
}

TEST(ControlTable, ErrorsNameKeyAndValue) {
  struct Case {
    std::string key, line, expected;
  };
  const Case cases[] = {
      {"torque_enable", "  torque_enable: {address: 64, size: 3, access: rw}",
       "entries.torque_enable.size: 3 is not 1, 2 or 4"},
      {"torque_enable", "  torque_enable: {address: 65, size: 1, access: rx}",
       "entries.torque_enable.access: 'rx' is not r or rw"},
      {"torque_enable", "  torque_enable: {address: 64, size: 1, acess: rw}",
       "entries.torque_enable.acess: unknown key"},
      {"torque_enable", "  torque_enable: {address: 10, size: 2, access: rw}",
       "entries.operating_mode.address: 11 overlaps entries.torque_enable (10, 2 bytes)"},
      {"torque_enable", "  torque_enable: {address: 64, size: 1, access: rw, min: 2, max: 1}", "min 2 > max 1"},
      {"torque_enable", "  torque_enable: {address: x, size: 1, access: rw}",
       "entries.torque_enable.address: expected an integer, got 'x'"},
      {"torque_enable", "  led: {address: 65, size: 1, access: rw}", "entries.torque_enable: missing"},
      {"present_velocity",
       "  present_velocity: {address: 136, size: 4, access: r, signed: true, unit: rpm, scale: 0.229}",
       "not the contiguous 10-byte block"},
      {"present_current", "  present_current: {address: 126, size: 2, access: r, signed: true, unit: A, scale: 2.69}",
       "entries.present_current.unit: 'A' is not mA"},
      {"hardware_error_status", "  hardware_error_status: {address: 70, size: 1, access: r, default: 300}",
       "entries.hardware_error_status.default: 300 does not fit 1 unsigned byte(s)"},
  };
  for (const auto& c : cases) {
    const std::string err = load_error(table_with(c.key, c.line));
    EXPECT_NE(err.find(c.expected), std::string::npos) << "expected '" << c.expected << "' in:\n" << err;
    EXPECT_NE(err.find("test.yaml"), std::string::npos) << err;
  }
  EXPECT_NE(load_error("model: t\nmodel_number: 0\nentries: {}\n").find("model_number: 0 is not in 1..65535"),
            std::string::npos);
  EXPECT_NE(load_error("[1, 2]").find("expected a mapping"), std::string::npos);
  EXPECT_THROW(dx::ControlTable::from_yaml_file("/nonexistent.yaml"), dx::ConfigError);
}
