// The driver's input and lifetime rules as small pure functions with reason codes (ROS-free).
//
// Each rule answers one question for the loop (DriverController) and returns a code; the text of
// a code says what happened in words a user acts on, without topic or service names (the ROS node
// adds those). Every function here is noexcept and allocation-free: the loop and the callers'
// threads (set_base_pose) use them.
//
//   command lifetime  a Running gait whose last command is older than command_timeout_s stops and
//                     holds its posture (HoldReason::kCommandTimeout) until the next command.
//   base pose         finite; |x|, |y|, |z| <= pose_workspace_m (m); a quaternion whose norm is 1
//                     within quaternion_norm_tolerance, normalised (PoseRefusal says why not).
//   CPG state         every state variable finite, else the supervisor faults ("CPG state not finite").
// The gait command's ranges are checked where commands are resolved (gait_command.hpp).
#pragma once

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>

namespace snake_autonomy::driver {

// Why the driver is Holding (kNone while it is not).
enum class HoldReason : std::uint8_t {
  kNone,
  kTorqueEnabled,   // start or recovery: torque on, posture held until a gait command
  kHoldRequest,     // a hold request
  kCommandTimeout,  // the running gait's last command is older than command_timeout_s
  kShutdown,        // the driver exits (shutdown_action hold)
  kTrajectoryDone,  // a joint trajectory reached its last point: held there until the next command
};
const char* to_string(HoldReason reason) noexcept;

// Why a base pose was refused (kNone: accepted).
enum class PoseRefusal : std::uint8_t {
  kNone,
  kNotFinite,           // NaN or infinite time, position or quaternion component
  kOutsideWorkspace,    // |x|, |y| or |z| beyond pose_workspace_m
  kQuaternionNotUnit,   // |norm - 1| beyond quaternion_norm_tolerance (zero and overflowing ones too)
};
const char* to_string(PoseRefusal refusal) noexcept;

// True when the command given at last_command_s has expired at now_s; timeout_s <= 0: never.
bool command_expired(double now_s, double last_command_s, double timeout_s) noexcept;

// Checks a base pose; on kNone `unit` holds the normalised orientation.
PoseRefusal check_base_pose(double t_s, const Eigen::Vector3d& position, const Eigen::Quaterniond& orientation,
                            double workspace_m, double quaternion_norm_tolerance, Eigen::Quaterniond* unit) noexcept;

// The refusal in words with the values that caused it (into out, at most size bytes; no allocation).
void describe_pose_refusal(PoseRefusal refusal, double t_s, const Eigen::Vector3d& position,
                           const Eigen::Quaterniond& orientation, double workspace_m, double quaternion_norm_tolerance,
                           char* out, std::size_t size) noexcept;

}  // namespace snake_autonomy::driver
