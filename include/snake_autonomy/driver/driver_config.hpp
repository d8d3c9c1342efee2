// Configuration of the driver's control loop (DriverController): a plain struct, validate()
// collects every problem naming key and value. Read once, here, from YAML (config/driver.yaml
// documents every key): driver_node (rosparam overrides go through apply_yaml too), the batch
// simulator and Python (DriverConfig.from_yaml, DriverConfig(**keys)) all use from_yaml / apply_yaml.
#pragma once

#include <string>
#include <vector>

namespace YAML {
class Node;
}

namespace snake_autonomy::driver {

// What the servos are left doing when locomotion stops for a fault, or when the driver exits.
enum class SafeAction {
  kHold,       // torque stays on, goals frozen at the present positions
  kTorqueOff,  // torque off: the robot goes limp
};
const char* to_string(SafeAction action) noexcept;
// "hold" or "torque_off"; false for anything else.
bool parse_safe_action(const std::string& text, SafeAction* out) noexcept;

struct DriverConfig {
  // Bus
  bool fast_sync_read = false;        // FAST_SYNC_READ (0x8A) instead of SYNC_READ for the feedback
  int max_failed_cycles = 10;         // consecutive cycles with a missing reply (or a failed write) before
                                      // locomotion stops; 1 .. 1000
  int status_every_cycles = 50;       // read voltage and temperature every this many cycles (0: never)
  // The servos' Return Delay Time (EEPROM address 9, 2 us units), written at start where it differs
  // (possible only while torque is off) and used for the reply deadlines. The factory value, 500 us,
  // costs 11 x 0.5 = 5.5 ms per sync read of COBRA's chain: half the 100 Hz cycle. -1: leave as found.
  int return_delay_time_us = 0;
  // Safety
  SafeAction fault_action = SafeAction::kHold;     // after N failed cycles or a hardware error
  SafeAction shutdown_action = SafeAction::kHold;  // when the driver exits
  bool torque_on_start = true;        // enable torque at start (posture held until a gait command)
  double max_joint_velocity_rad_s = 4.5;  // goal slew limit per joint (XH540-W270: 4.8 rad/s no load)
  double max_frequency_hz = 2.0;      // gait commands with |ω| / 2π above it are refused
  double max_step_s = 0.05;           // longer steps (after a stall) are integrated as this long
  // Command lifetime: a running gait whose last command (a repeat counts: callers re-send theirs as
  // a heartbeat) is older than this stops and holds the posture until the next command. Above the
  // mission's 1 s control period with room for two lost commands; 0: no lifetime (bench use).
  double command_timeout_s = 3.0;
  // Position readings further than this outside the servo's position limits are implausible
  // (garbage with a valid CRC): treated as a missed reply.
  int plausible_margin_ticks = 1024;
  // Base pose: driving on a made-up pose is unsafe, so a stale or lost pose holds the posture
  double pose_timeout_s = 0.5;        // no pose for this long: stale, locomotion held until fresh poses return
  bool require_pose = true;           // false: gaits run without a base pose (robot on a stand, bench)
  double pose_workspace_m = 1000.0;   // base poses with |x|, |y| or |z| beyond this are refused
  double quaternion_norm_tolerance = 0.01;  // |norm - 1| beyond this is refused; within, normalised
  // Joint trajectories (driver/joint_trajectory): the most points one may carry; storage for twice
  // this many points is reserved at construction (2 x points x joints x 16 bytes: 7 MB for COBRA).
  int max_trajectory_points = 20000;
  // The longest a trajectory may last (its last time_from_start, s); longer ones are refused whole.
  double max_trajectory_duration_s = 600.0;

  // Every problem, naming key and value; empty when usable.
  std::vector<std::string> validate() const;

  // The YAML keys, which are the field names above.
  static const std::vector<std::string>& keys();
  // Reads every key of keys() present in the mapping `doc` over the present values; other keys are
  // ignored (driver.yaml also holds the node's own: port, rate_hz, frames). Appends a problem per
  // wrong type or unknown fault/shutdown action, the key written as `prefix` + key ("~" for rosparam).
  // Does not validate().
  void apply_yaml(const YAML::Node& doc, std::vector<std::string>* errors, const std::string& prefix = "");
  // The defaults with the keys of a YAML text / file over them, validated: throws ConfigError
  // "<source>: invalid driver configuration (N problems):" naming every key and value.
  static DriverConfig from_yaml_string(const std::string& text, const std::string& source = "<string>");
  static DriverConfig from_yaml_file(const std::string& path);
};

}  // namespace snake_autonomy::driver
