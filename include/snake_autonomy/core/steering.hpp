// Steering by amplitude modulation (thesis eq. 3.26-3.31, Algorithm 1's MODIFYAMPLITUDES):
//   a_i = clamp(a_i_nominal + α_i · clip(δ, ±δ_limit) + δ_offset, a_min, a_max)   on yaw joints,
// pitch joints unchanged. α (one weight per yaw joint, head to tail), the clamps and δ_offset are
// configuration (the robot YAML's steering section). Real-time safe: no allocation, no throw.
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "snake_autonomy/core/robot_model.hpp"

namespace snake_autonomy::core {

class Steering {
 public:
  explicit Steering(const RobotModel& model);

  // out = modulated copy of nominal (out may alias nominal). Returns false, leaving out untouched,
  // when sizes do not match the robot or delta_rad is not finite.
  bool modify_amplitudes(const Eigen::VectorXd& nominal, double delta_rad, Eigen::VectorXd& out) const noexcept;
  // The δ actually applied after the ±δ_limit clip.
  double clip_delta(double delta_rad) const noexcept;

  int num_joints() const { return n_; }
  const std::vector<int>& yaw_joints() const { return yaw_joints_; }
  const SteeringConfig& config() const { return config_; }

 private:
  int n_;
  std::vector<int> yaw_joints_;
  SteeringConfig config_;
};

}  // namespace snake_autonomy::core
