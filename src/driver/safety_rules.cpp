#include "snake_autonomy/driver/safety_rules.hpp"

#include <cmath>
#include <cstdio>

namespace snake_autonomy::driver {

const char* to_string(HoldReason reason) noexcept {
  switch (reason) {
    case HoldReason::kNone: return "";
    case HoldReason::kTorqueEnabled: return "torque enabled: posture held until a gait command";
    case HoldReason::kHoldRequest: return "hold requested";
    case HoldReason::kCommandTimeout: return "no gait command within command_timeout_s: holding until the next";
    case HoldReason::kShutdown: return "driver shut down";
    case HoldReason::kTrajectoryDone: return "joint trajectory done: its last point held until the next command";
  }
  return "?";
}

const char* to_string(PoseRefusal refusal) noexcept {
  switch (refusal) {
    case PoseRefusal::kNone: return "";
    case PoseRefusal::kNotFinite: return "not a finite number";
    case PoseRefusal::kOutsideWorkspace: return "position outside the workspace (pose_workspace_m)";
    case PoseRefusal::kQuaternionNotUnit: return "quaternion norm not 1 within quaternion_norm_tolerance";
  }
  return "?";
}

bool command_expired(double now_s, double last_command_s, double timeout_s) noexcept {
  return timeout_s > 0.0 && now_s - last_command_s > timeout_s;
}

PoseRefusal check_base_pose(double t_s, const Eigen::Vector3d& position, const Eigen::Quaterniond& orientation,
                            double workspace_m, double quaternion_norm_tolerance, Eigen::Quaterniond* unit) noexcept {
  if (!std::isfinite(t_s) || !position.allFinite() || !orientation.coeffs().allFinite()) return PoseRefusal::kNotFinite;
  if (position.cwiseAbs().maxCoeff() > workspace_m) return PoseRefusal::kOutsideWorkspace;
  // A component beyond 2 cannot belong to a unit quaternion within any sane tolerance, and its
  // square may overflow (1e200² = inf): refused before the norm is computed.
  if (orientation.coeffs().cwiseAbs().maxCoeff() > 2.0) return PoseRefusal::kQuaternionNotUnit;
  const double norm = orientation.norm();
  if (!(std::abs(norm - 1.0) <= quaternion_norm_tolerance)) return PoseRefusal::kQuaternionNotUnit;
  *unit = Eigen::Quaterniond(orientation.coeffs() / norm);
  return PoseRefusal::kNone;
}

void describe_pose_refusal(PoseRefusal refusal, double t_s, const Eigen::Vector3d& p, const Eigen::Quaterniond& q,
                           double workspace_m, double quaternion_norm_tolerance, char* out, std::size_t size) noexcept {
  switch (refusal) {
    case PoseRefusal::kNone: std::snprintf(out, size, "%s", ""); return;
    case PoseRefusal::kOutsideWorkspace:
      std::snprintf(out, size, "%s %g m: position (%g, %g, %g)", to_string(refusal), workspace_m, p.x(), p.y(), p.z());
      return;
    case PoseRefusal::kQuaternionNotUnit:
      std::snprintf(out, size, "%s %g: (x, y, z, w) (%g, %g, %g, %g)", to_string(refusal), quaternion_norm_tolerance,
                    q.x(), q.y(), q.z(), q.w());
      return;
    case PoseRefusal::kNotFinite:
      std::snprintf(out, size, "%s: t %g s, position (%g, %g, %g), (x, y, z, w) (%g, %g, %g, %g)", to_string(refusal),
                    t_s, p.x(), p.y(), p.z(), q.x(), q.y(), q.z(), q.w());
      return;
  }
}

}  // namespace snake_autonomy::driver
