#include "snake_autonomy/core/driver_config.hpp"

#include <cmath>
#include <sstream>

namespace snake_autonomy::core {

const char* to_string(SafeAction action) noexcept {
  switch (action) {
    case SafeAction::kHold: return "hold";
    case SafeAction::kTorqueOff: return "torque_off";
  }
  return "?";
}

bool parse_safe_action(const std::string& text, SafeAction* out) noexcept {
  if (text == "hold") {
    *out = SafeAction::kHold;
  } else if (text == "torque_off") {
    *out = SafeAction::kTorqueOff;
  } else {
    return false;
  }
  return true;
}

std::vector<std::string> DriverConfig::validate() const {
  std::vector<std::string> errors;
  auto bad = [&errors](const char* key, double value, const char* need) {
    std::ostringstream s;
    s << key << ": " << value << " " << need;
    errors.push_back(s.str());
  };
  if (max_failed_cycles < 1 || max_failed_cycles > 1000) bad("max_failed_cycles", max_failed_cycles, "is not in 1 .. 1000");
  if (return_delay_time_us != -1 &&
      (return_delay_time_us < 0 || return_delay_time_us > 508 || return_delay_time_us % 2 != 0))
    bad("return_delay_time_us", return_delay_time_us, "is not an even number in 0 .. 508 (or -1: leave as found)");
  if (status_every_cycles < 0) bad("status_every_cycles", status_every_cycles, "is negative (0 disables)");
  if (!(max_joint_velocity_rad_s > 0.0) || !std::isfinite(max_joint_velocity_rad_s))
    bad("max_joint_velocity_rad_s", max_joint_velocity_rad_s, "is not a positive number");
  if (!(max_frequency_hz > 0.0) || !std::isfinite(max_frequency_hz))
    bad("max_frequency_hz", max_frequency_hz, "is not a positive number");
  if (!(max_step_s > 0.0) || !std::isfinite(max_step_s) || max_step_s > 1.0)
    bad("max_step_s", max_step_s, "is not in (0, 1] s");
  if (plausible_margin_ticks < 0) bad("plausible_margin_ticks", plausible_margin_ticks, "is negative");
  if (!(pose_timeout_s > 0.0) || !std::isfinite(pose_timeout_s)) bad("pose_timeout_s", pose_timeout_s, "is not a positive number");
  if (!(command_timeout_s >= 0.0) || !std::isfinite(command_timeout_s) || command_timeout_s > 3600.0)
    bad("command_timeout_s", command_timeout_s, "is not in [0, 3600] s (0: no command lifetime)");
  if (!(pose_workspace_m > 0.0) || !std::isfinite(pose_workspace_m) || pose_workspace_m > 1e6)
    bad("pose_workspace_m", pose_workspace_m, "is not in (0, 1e6] m");
  if (!(quaternion_norm_tolerance > 0.0) || !(quaternion_norm_tolerance < 0.5))
    bad("quaternion_norm_tolerance", quaternion_norm_tolerance, "is not in (0, 0.5)");
  return errors;
}

}  // namespace snake_autonomy::core
