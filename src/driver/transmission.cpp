#include "snake_autonomy/driver/transmission.hpp"

#include <cmath>

#include "snake_autonomy/core/robot_model.hpp"
#include "snake_autonomy/dynamixel/control_table.hpp"

namespace snake_autonomy::driver {

std::vector<Transmission> Transmission::for_robot(const core::RobotModel& model, const dynamixel::ControlTable& table) {
  const dynamixel::UnitScales scales = table.unit_scales();
  std::vector<Transmission> out;
  out.reserve(static_cast<std::size_t>(model.num_joints));
  for (int j = 0; j < model.num_joints; ++j) {
    const auto i = static_cast<std::size_t>(j);
    const int d = i < model.servos.directions.size() ? model.servos.directions[i] : 1;
    const int z = i < model.servos.zero_offsets_ticks.size() ? model.servos.zero_offsets_ticks[i] : 0;
    out.emplace_back(scales, d, z);
  }
  return out;
}

bool Transmission::joint_rad_to_ticks(double joint_rad, std::int32_t* ticks) const noexcept {
  const auto t = dynamixel::rad_to_ticks(direction_ * joint_rad, scales_);
  if (!t) return false;
  const std::int64_t v = static_cast<std::int64_t>(*t) + zero_offset_ticks_;
  if (v < INT32_MIN || v > INT32_MAX) return false;
  *ticks = static_cast<std::int32_t>(v);
  return true;
}

void Transmission::joint_range_to_ticks(double lower_rad, double upper_rad, std::int32_t* lo,
                                        std::int32_t* hi) const noexcept {
  const double rpt = scales_.rad_per_tick;
  const double c = static_cast<double>(scales_.centre_ticks) + zero_offset_ticks_;
  double a, b;
  if (direction_ > 0) {
    a = c + std::ceil(lower_rad / rpt - 1e-9);
    b = c + std::floor(upper_rad / rpt + 1e-9);
  } else {
    a = c + std::ceil(-upper_rad / rpt - 1e-9);
    b = c + std::floor(-lower_rad / rpt + 1e-9);
  }
  auto to_i32 = [](double v) {
    return static_cast<std::int32_t>(v < INT32_MIN ? INT32_MIN : (v > INT32_MAX ? INT32_MAX : v));
  };
  *lo = to_i32(a);
  *hi = to_i32(b);
}

}  // namespace snake_autonomy::driver
