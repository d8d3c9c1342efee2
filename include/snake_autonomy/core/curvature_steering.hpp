// Steering by body curvature (the `curvature` steering law of config/gaits.yaml; rectilinear gait,
// Chang et al.): a curvature command kappa (1/m, positive bends the body towards positive lateral
// joint angles) becomes a bias on the lateral (yaw) joints,
//   b_i = clamp(b_i_nominal + kappa * s_i, lower_i, upper_i)    on yaw joints, pitch joints unchanged,
// where s_i is the body length between yaw joint i and the previous yaw joint (the next one for the
// first): (index difference) x link_length_m, so the bent body approximates an arc of radius 1/kappa.
// Real-time safe: no allocation, no throw.
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "snake_autonomy/core/robot_model.hpp"

namespace snake_autonomy::core {

class CurvatureSteering {
 public:
  explicit CurvatureSteering(const RobotModel& model);

  // out = copy of nominal with the yaw-joint biases bent by kappa (out may alias nominal). False,
  // leaving out untouched, when the sizes do not match the robot or kappa is not finite.
  bool modify_biases(const Eigen::VectorXd& nominal, double kappa_per_m, Eigen::VectorXd& out) const noexcept;
  // s_i in metres, one per yaw joint (yaw_joints() order).
  const std::vector<double>& spacing_m() const { return spacing_m_; }
  const std::vector<int>& yaw_joints() const { return yaw_joints_; }
  int num_joints() const { return n_; }

 private:
  int n_;
  std::vector<int> yaw_joints_;
  std::vector<double> spacing_m_, lower_rad_, upper_rad_;
};

}  // namespace snake_autonomy::core
