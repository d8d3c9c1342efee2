#include "snake_autonomy/driver/driver_config.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <sstream>
#include <type_traits>

#include "snake_autonomy/core/config_reader.hpp"

namespace snake_autonomy::driver {

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
  if (max_failed_cycles < 1 || max_failed_cycles > 1000)
    bad("max_failed_cycles", max_failed_cycles, "is not in 1 .. 1000");
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
  if (!(pose_timeout_s > 0.0) || !std::isfinite(pose_timeout_s))
    bad("pose_timeout_s", pose_timeout_s, "is not a positive number");
  if (!(command_timeout_s >= 0.0) || !std::isfinite(command_timeout_s) || command_timeout_s > 3600.0)
    bad("command_timeout_s", command_timeout_s, "is not in [0, 3600] s (0: no command lifetime)");
  if (!(pose_workspace_m > 0.0) || !std::isfinite(pose_workspace_m) || pose_workspace_m > 1e6)
    bad("pose_workspace_m", pose_workspace_m, "is not in (0, 1e6] m");
  if (!(quaternion_norm_tolerance > 0.0) || !(quaternion_norm_tolerance < 0.5))
    bad("quaternion_norm_tolerance", quaternion_norm_tolerance, "is not in (0, 0.5)");
  if (max_trajectory_points < 1 || max_trajectory_points > 1000000)
    bad("max_trajectory_points", max_trajectory_points, "is not in 1 .. 1000000");
  if (!(max_trajectory_duration_s > 0.0) || !(max_trajectory_duration_s <= 86400.0))
    bad("max_trajectory_duration_s", max_trajectory_duration_s, "is not in (0, 86400] s");
  return errors;
}

namespace {

// Every field once: its key and where it lives. Adding a field = one line here.
template <typename Visit>
void for_each_field(DriverConfig& c, Visit&& visit) {
  visit("fast_sync_read", c.fast_sync_read);
  visit("max_failed_cycles", c.max_failed_cycles);
  visit("status_every_cycles", c.status_every_cycles);
  visit("return_delay_time_us", c.return_delay_time_us);
  visit("fault_action", c.fault_action);
  visit("shutdown_action", c.shutdown_action);
  visit("torque_on_start", c.torque_on_start);
  visit("max_joint_velocity_rad_s", c.max_joint_velocity_rad_s);
  visit("max_frequency_hz", c.max_frequency_hz);
  visit("max_step_s", c.max_step_s);
  visit("command_timeout_s", c.command_timeout_s);
  visit("plausible_margin_ticks", c.plausible_margin_ticks);
  visit("pose_timeout_s", c.pose_timeout_s);
  visit("require_pose", c.require_pose);
  visit("pose_workspace_m", c.pose_workspace_m);
  visit("quaternion_norm_tolerance", c.quaternion_norm_tolerance);
  visit("max_trajectory_points", c.max_trajectory_points);
  visit("max_trajectory_duration_s", c.max_trajectory_duration_s);
}

}  // namespace

const std::vector<std::string>& DriverConfig::keys() {
  static const std::vector<std::string> k = [] {
    std::vector<std::string> out;
    DriverConfig c;
    for_each_field(c, [&out](const char* key, auto&) { out.emplace_back(key); });
    return out;
  }();
  return k;
}

void DriverConfig::apply_yaml(const YAML::Node& doc, std::vector<std::string>* errors, const std::string& prefix) {
  core::ConfigReader r(errors);
  if (!doc.IsMap()) {
    if (doc && !doc.IsNull())
      r.error(prefix + ": expected a mapping of driver keys, got '" + core::ConfigReader::dump(doc) + "'");
    return;
  }
  for_each_field(*this, [&](const char* key, auto& field) {
    const YAML::Node n = doc[key];
    if (!n) return;
    using T = std::decay_t<decltype(field)>;
    const std::string path = prefix + key;
    if constexpr (std::is_same_v<T, SafeAction>) {
      std::string text;
      if (r.scalar(n, path, &text) && !parse_safe_action(text, &field))
        r.error(path + ": '" + text + "', expected 'hold' or 'torque_off'");
    } else {
      r.scalar(n, path, &field);
    }
  });
}

DriverConfig DriverConfig::from_yaml_string(const std::string& text, const std::string& source) {
  DriverConfig c;
  std::vector<std::string> errors;
  const YAML::Node doc =
      text.find_first_not_of(" \t\r\n") == std::string::npos ? YAML::Node() : core::load_config_yaml(text, source);
  c.apply_yaml(doc, &errors);
  for (const auto& e : c.validate()) errors.push_back(e);
  core::throw_if_errors(errors, source, "driver configuration");
  return c;
}

DriverConfig DriverConfig::from_yaml_file(const std::string& path) {
  return from_yaml_string(core::read_config_file(path, "driver configuration"), path);
}

}  // namespace snake_autonomy::driver
