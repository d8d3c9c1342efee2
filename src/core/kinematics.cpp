#include "snake_autonomy/core/kinematics.hpp"

#include <kdl/frames.hpp>
#include <kdl/joint.hpp>
#include <kdl/segment.hpp>
#include <numeric>

#include "snake_autonomy/core/virtual_chassis.hpp"

namespace snake_autonomy::core {
namespace {

inline void to_eigen(const KDL::Frame& f, Eigen::Vector3d& p, Eigen::Matrix3d& R) noexcept {
  p << f.p.x(), f.p.y(), f.p.z();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R(r, c) = f.M(r, c);
}

}  // namespace

KinematicState::KinematicState(int num_frames)
    : link_positions(num_frames, Eigen::Vector3d::Zero()),
      link_rotations(num_frames, Eigen::Matrix3d::Identity()),
      parent_positions(num_frames, Eigen::Vector3d::Zero()),
      parent_rotations(num_frames, Eigen::Matrix3d::Identity()) {}

double Kinematics::head_twist_rad(const RobotModel& model) {
  return model.axes.front() == JointAxis::kPitch ? M_PI / 2.0 : 0.0;
}

double Kinematics::link_twist_rad(const RobotModel& model, int i) {
  const JointAxis here = model.axes[i];
  JointAxis next;
  if (i + 1 < model.num_joints) {
    next = model.axes[i + 1];
  } else {
    next = here == JointAxis::kPitch ? JointAxis::kYaw : JointAxis::kPitch;  // the alternation continues
  }
  if (here == next) return 0.0;
  return here == JointAxis::kPitch ? -M_PI / 2.0 : M_PI / 2.0;
}

Kinematics::Kinematics(const RobotModel& model) : model_(model) {
  model_.validate_or_throw();
  const std::vector<std::string> names = model_.frame_names();
  // Base -> head: fixed.
  chain_.addSegment(KDL::Segment(
      names[1], KDL::Joint("head_fixed", KDL::Joint::None),
      KDL::Frame(KDL::Rotation::RotX(head_twist_rad(model_)), KDL::Vector(-model_.head_length_m, 0.0, 0.0))));
  // Joint i: Rz(−q_i) (a RotZ joint with scale −1), then Trans(−L, 0, 0) · Rx(τ_i).
  for (int i = 0; i < model_.num_joints; ++i) {
    chain_.addSegment(KDL::Segment(
        names[i + 2], KDL::Joint(model_.joint_names()[i], KDL::Joint::RotZ, -1.0),
        KDL::Frame(KDL::Rotation::RotX(link_twist_rad(model_, i)), KDL::Vector(-model_.link_length_m, 0.0, 0.0))));
  }
  // Note: KDL::Frame(R, p) is the transform x -> R x + p; Trans(−L)·Rx(τ) is exactly that.
  inverse_total_mass_ = 1.0 / std::accumulate(model_.masses_kg.begin(), model_.masses_kg.end(), 0.0);
}

bool Kinematics::compute(const Eigen::Vector3d& base_position, const Eigen::Quaterniond& base_orientation,
                         const Eigen::VectorXd& q, KinematicState& out) const noexcept {
  const int frames = num_frames();
  if (q.size() != model_.num_joints || !q.allFinite() || !base_position.allFinite() ||
      !base_orientation.coeffs().allFinite() || base_orientation.norm() < 1e-9 ||
      static_cast<int>(out.link_positions.size()) != frames || static_cast<int>(out.link_rotations.size()) != frames ||
      static_cast<int>(out.parent_positions.size()) != frames ||
      static_cast<int>(out.parent_rotations.size()) != frames)
    return false;

  const Eigen::Quaterniond qb = base_orientation.normalized();
  const Eigen::Matrix3d Rb = qb.toRotationMatrix();
  KDL::Frame world(
      KDL::Rotation(Rb(0, 0), Rb(0, 1), Rb(0, 2), Rb(1, 0), Rb(1, 1), Rb(1, 2), Rb(2, 0), Rb(2, 1), Rb(2, 2)),
      KDL::Vector(base_position.x(), base_position.y(), base_position.z()));
  to_eigen(world, out.link_positions[0], out.link_rotations[0]);
  out.parent_positions[0] = out.link_positions[0];
  out.parent_rotations[0] = out.link_rotations[0];
  // KDL's recursive FK, one pass: each segment's pose relative to its parent, accumulated.
  unsigned int joint = 0;
  for (unsigned int s = 0; s < chain_.getNrOfSegments(); ++s) {
    const KDL::Segment& seg = chain_.getSegment(s);
    const double qj = seg.getJoint().getType() == KDL::Joint::None ? 0.0 : q(joint++);
    const KDL::Frame rel = seg.pose(qj);
    world = world * rel;
    to_eigen(rel, out.parent_positions[s + 1], out.parent_rotations[s + 1]);
    to_eigen(world, out.link_positions[s + 1], out.link_rotations[s + 1]);
  }

  out.com = centre_of_mass(out.link_positions, model_.masses_kg, inverse_total_mass_);
  const bool ok = model_.chassis == ChassisMethod::kMeanAxis
                      ? virtual_chassis_mean_axis(out.link_rotations, out.vc_rotation)
                      : virtual_chassis_svd(out.link_positions, out.vc_rotation);
  out.vc_degenerate = !ok;
  out.bbox_span = bounding_box_span(out.link_positions, out.com, out.vc_rotation, model_.bbox_padding_m);
  return true;
}

}  // namespace snake_autonomy::core
