// Unit conversions of the servo's raw control-table values: small pure functions, table-tested.
// The scales come from the control table YAML (ControlTable::unit_scales()); kXh540Scales holds
// the XH540-W270's values for tests and tools: 360/4096 deg per tick with 2048 the centre,
// 0.229 rpm per velocity unit, 2.69 mA per current unit (signed), 0.1 V per voltage unit.
#pragma once

#include <cmath>
#include <cstdint>
#include <optional>

namespace snake_autonomy::dynamixel {

struct UnitScales {
  double rad_per_tick = 2.0 * M_PI / 4096.0;
  std::int32_t centre_ticks = 2048;
  double rad_s_per_velocity_unit = 0.229 * 2.0 * M_PI / 60.0;
  double amps_per_current_unit = 2.69e-3;
  double volts_per_voltage_unit = 0.1;
};
inline constexpr UnitScales kXh540Scales{};

// One sync read of this block returns current (2 bytes), velocity (4) and position (4).
constexpr std::uint16_t kFeedbackAddress = 126;
constexpr std::uint16_t kFeedbackBytes = 10;
constexpr std::uint16_t kGoalPositionAddress = 116;
constexpr std::uint16_t kGoalPositionBytes = 4;

inline double ticks_to_rad(std::int32_t ticks, const UnitScales& s = kXh540Scales) noexcept {
  return static_cast<double>(ticks - s.centre_ticks) * s.rad_per_tick;
}

// Nearest tick; std::nullopt for NaN, infinities and angles beyond the int32 range, so that a
// non-number can never become a command. Limits are the caller's job (see clamp_ticks).
inline std::optional<std::int32_t> rad_to_ticks(double rad, const UnitScales& s = kXh540Scales) noexcept {
  if (!std::isfinite(rad)) return std::nullopt;
  const double ticks = std::round(rad / s.rad_per_tick) + s.centre_ticks;
  if (ticks < -2147483648.0 || ticks > 2147483647.0) return std::nullopt;
  return static_cast<std::int32_t>(ticks);
}

inline std::int32_t clamp_ticks(std::int32_t ticks, std::int32_t min_ticks, std::int32_t max_ticks) noexcept {
  return ticks < min_ticks ? min_ticks : (ticks > max_ticks ? max_ticks : ticks);
}

inline double velocity_to_rad_s(std::int32_t units, const UnitScales& s = kXh540Scales) noexcept {
  return units * s.rad_s_per_velocity_unit;
}
inline std::int32_t rad_s_to_velocity(double rad_s, const UnitScales& s = kXh540Scales) noexcept {
  return static_cast<std::int32_t>(std::lround(rad_s / s.rad_s_per_velocity_unit));
}

inline double current_to_amps(std::int16_t units, const UnitScales& s = kXh540Scales) noexcept {
  return units * s.amps_per_current_unit;
}
inline std::int16_t amps_to_current(double amps, const UnitScales& s = kXh540Scales) noexcept {
  const long v = std::lround(amps / s.amps_per_current_unit);
  return static_cast<std::int16_t>(v < -32768 ? -32768 : (v > 32767 ? 32767 : v));
}

inline double voltage_to_volts(std::uint16_t units, const UnitScales& s = kXh540Scales) noexcept {
  return units * s.volts_per_voltage_unit;
}

// The 10 bytes read from kFeedbackAddress, decoded.
struct ServoFeedback {
  std::int32_t position_ticks = 0;
  double position_rad = 0.0;
  double velocity_rad_s = 0.0;
  double current_a = 0.0;
};
ServoFeedback decode_feedback(const std::uint8_t* block, const UnitScales& s = kXh540Scales) noexcept;

}  // namespace snake_autonomy::dynamixel
