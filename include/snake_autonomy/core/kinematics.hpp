// Forward kinematics of the whole chain with Orocos KDL (thesis eq. 3.2-3.20).
//
// The chain is built from the robot description exactly as eq. 3.3-3.4:
//   head_link = base · Trans(−H, 0, 0) · Rx(+90°)           (when joint 1 pitches; Rx(0) if it yaws)
//   link_i    = link_{i−1} · Rz(−q_i) · Trans(−L, 0, 0) · Rx(τ_i)
// with τ_i = −90° from a pitch joint to a yaw joint, +90° from yaw to pitch, 0° between joints of the
// same axis; after the last joint the alternation continues. For COBRA: τ = −90°, +90°, −90°, ...
// so joint 1 pitches and joint 2 yaws. Frames in chain order: base_link, head_link, link_1..link_N.
//
// compute() fills a KinematicState sized at construction: world and parent poses of every frame,
// the centre of mass (eq. 3.15), the virtual chassis (eq. 3.11-3.14 or SVD, by configuration) and
// the bounding box (eq. 3.17-3.20). It never allocates and never throws.
#pragma once

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <kdl/chain.hpp>
#include <vector>

#include "snake_autonomy/core/robot_model.hpp"

namespace snake_autonomy::core {

struct KinematicState {
  std::vector<Eigen::Vector3d> link_positions;    // world, per frame
  std::vector<Eigen::Matrix3d> link_rotations;    // world, per frame
  std::vector<Eigen::Vector3d> parent_positions;  // relative to the previous frame (base: world)
  std::vector<Eigen::Matrix3d> parent_rotations;
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  Eigen::Matrix3d vc_rotation = Eigen::Matrix3d::Identity();  // kept from the last good value when degenerate
  Eigen::Vector3d bbox_span = Eigen::Vector3d::Zero();        // padding included
  bool vc_degenerate = false;                                 // the construction had no horizontal axis

  explicit KinematicState(int num_frames = 0);
};

class Kinematics {
 public:
  explicit Kinematics(const RobotModel& model);

  const RobotModel& model() const { return model_; }
  const KDL::Chain& chain() const { return chain_; }
  int num_frames() const { return model_.num_frames(); }

  // The twist angle τ after joint i (0-based), and the head's, as described above.
  static double head_twist_rad(const RobotModel& model);
  static double link_twist_rad(const RobotModel& model, int joint_index);

  // Returns false (state untouched) when q has the wrong size or a non-finite value, or the base
  // pose is not finite. The quaternion is normalised.
  bool compute(const Eigen::Vector3d& base_position, const Eigen::Quaterniond& base_orientation,
               const Eigen::VectorXd& q, KinematicState& out) const noexcept;

  KinematicState make_state() const { return KinematicState(num_frames()); }

 private:
  RobotModel model_;
  KDL::Chain chain_;  // one segment for the head, then one per joint (Rz(−q) then the fixed tip)
  double inverse_total_mass_ = 0.0;
};

}  // namespace snake_autonomy::core
