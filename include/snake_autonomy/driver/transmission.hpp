// Transmission: one joint's servo <-> joint mapping (ros_control's SimpleTransmission, for a
// Dynamixel). The ONLY place that converts servo units into joint units and back: the driver's
// control loop, the MuJoCo servo backend of the simulator (through the bindings) and the tools all
// call it, so a servo model with another resolution converts correctly everywhere.
//
// Units and frames:
//   ticks        the servo's Present/Goal Position register; the centre (control table
//                `position_centre_ticks`, 2048 on the XH540) is the shaft's zero.
//   shaft rad    the servo shaft's angle from the centre, positive in the servo's own sense:
//                shaft_rad = (ticks - centre) * rad_per_tick            (rad_per_tick from the table)
//   joint rad    the joint angle q of the robot description (eq. 3.4), direction d = +-1 and zero
//                offset z (ticks at q = 0, counted from the centre) from the robot YAML:
//                ticks = centre + z + d * q / rad_per_tick  <=>  shaft_rad = z * rad_per_tick + d * q
//   velocity     the table's velocity unit (0.229 rpm on the XH540) -> joint rad/s (sign d)
//   current      the table's current unit (2.69 mA on the XH540), signed -> joint-sense amperes
// Real-time safety: every member function is noexcept, allocation-free and constant-time; the
// constructor and for_robot() allocate and run at configuration only.
#pragma once

#include <cstdint>
#include <vector>

#include "snake_autonomy/dynamixel/conversions.hpp"

namespace snake_autonomy::dynamixel {
struct ControlTable;
}
namespace snake_autonomy::core {
struct RobotModel;
}

namespace snake_autonomy::driver {

class Transmission {
 public:
  Transmission() = default;
  Transmission(const dynamixel::UnitScales& scales, int direction, std::int32_t zero_offset_ticks) noexcept
      : scales_(scales), direction_(direction < 0 ? -1 : 1), zero_offset_ticks_(zero_offset_ticks) {}
  // One per joint, in joint order: the table's scales, the robot YAML's directions and zero offsets.
  static std::vector<Transmission> for_robot(const core::RobotModel& model, const dynamixel::ControlTable& table);

  // Position.
  double ticks_to_joint_rad(std::int32_t ticks) const noexcept {
    return direction_ * static_cast<double>(ticks - scales_.centre_ticks - zero_offset_ticks_) * scales_.rad_per_tick;
  }
  // Nearest tick, no clamping; false for NaN/inf and angles beyond the int32 range (a non-number
  // never becomes a command).
  bool joint_rad_to_ticks(double joint_rad, std::int32_t* ticks) const noexcept;
  double shaft_rad_to_joint_rad(double shaft_rad) const noexcept {
    return direction_ * (shaft_rad - zero_offset_ticks_ * scales_.rad_per_tick);
  }
  double joint_rad_to_shaft_rad(double joint_rad) const noexcept {
    return zero_offset_ticks_ * scales_.rad_per_tick + direction_ * joint_rad;
  }
  double ticks_to_shaft_rad(std::int32_t ticks) const noexcept { return dynamixel::ticks_to_rad(ticks, scales_); }
  // The joint range [lower_rad, upper_rad] in ticks, rounded inwards (a goal inside the tick range is
  // inside the joint range), lo <= hi whatever the direction.
  void joint_range_to_ticks(double lower_rad, double upper_rad, std::int32_t* lo, std::int32_t* hi) const noexcept;

  // Velocity and current (effort) in joint sense.
  double velocity_to_joint_rad_s(std::int32_t units) const noexcept {
    return direction_ * dynamixel::velocity_to_rad_s(units, scales_);
  }
  double current_to_joint_amps(std::int32_t units) const noexcept {
    return direction_ * units * scales_.amps_per_current_unit;
  }
  // A shaft-sense rate or effort already in SI units (decode_feedback) in joint sense.
  double shaft_to_joint_sense(double value) const noexcept { return direction_ * value; }

  int direction() const noexcept { return direction_; }
  std::int32_t zero_offset_ticks() const noexcept { return zero_offset_ticks_; }
  std::int32_t centre_ticks() const noexcept { return scales_.centre_ticks; }
  double rad_per_tick() const noexcept { return scales_.rad_per_tick; }
  const dynamixel::UnitScales& scales() const noexcept { return scales_; }

 private:
  dynamixel::UnitScales scales_{};
  int direction_ = 1;
  std::int32_t zero_offset_ticks_ = 0;
};

}  // namespace snake_autonomy::driver
