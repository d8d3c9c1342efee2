#include "snake_autonomy/core/curvature_steering.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace snake_autonomy::core {

CurvatureSteering::CurvatureSteering(const RobotModel& model) : n_(model.num_joints), yaw_joints_(model.yaw_joints()) {
  const std::size_t m = yaw_joints_.size();
  for (std::size_t k = 0; k < m; ++k) {
    int gap = 1;
    if (k > 0) gap = yaw_joints_[k] - yaw_joints_[k - 1];
    else if (m > 1) gap = yaw_joints_[1] - yaw_joints_[0];
    spacing_m_.push_back(std::abs(gap) * model.link_length_m);
    lower_rad_.push_back(model.joint_lower_rad[static_cast<std::size_t>(yaw_joints_[k])]);
    upper_rad_.push_back(model.joint_upper_rad[static_cast<std::size_t>(yaw_joints_[k])]);
  }
}

bool CurvatureSteering::modify_biases(const Eigen::VectorXd& nominal, double kappa_per_m,
                                      Eigen::VectorXd& out) const noexcept {
  if (nominal.size() != n_ || out.size() != n_ || !std::isfinite(kappa_per_m)) return false;
  if (&out != &nominal) out = nominal;
  for (std::size_t k = 0; k < yaw_joints_.size(); ++k) {
    const int j = yaw_joints_[k];
    out(j) = std::clamp(nominal(j) + kappa_per_m * spacing_m_[k], lower_rad_[k], upper_rad_[k]);
  }
  return true;
}

}  // namespace snake_autonomy::core
