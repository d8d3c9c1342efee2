#include "snake_autonomy/core/steering.hpp"

#include <algorithm>
#include <cmath>

namespace snake_autonomy::core {

Steering::Steering(const RobotModel& model)
    : n_(model.num_joints), yaw_joints_(model.yaw_joints()), config_(model.steering) {
  model.validate_or_throw();
}

double Steering::clip_delta(double delta_rad) const noexcept {
  return std::clamp(delta_rad, -config_.delta_limit_rad, config_.delta_limit_rad);
}

bool Steering::modify_amplitudes(const Eigen::VectorXd& nominal, double delta_rad,
                                 Eigen::VectorXd& out) const noexcept {
  if (nominal.size() != n_ || out.size() != n_ || !std::isfinite(delta_rad) || !nominal.allFinite()) return false;
  if (&out != &nominal) out = nominal;
  const double delta = clip_delta(delta_rad);
  for (std::size_t k = 0; k < yaw_joints_.size(); ++k) {
    const int j = yaw_joints_[k];
    out(j) = std::clamp(nominal(j) + config_.weights[k] * delta + config_.delta_offset_rad, config_.amplitude_min_rad,
                        config_.amplitude_max_rad);
  }
  return true;
}

}  // namespace snake_autonomy::core
