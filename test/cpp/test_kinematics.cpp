#include <gtest/gtest.h>

#include <random>

#include "snake_autonomy/core/kinematics.hpp"
#include "snake_autonomy/core/virtual_chassis.hpp"
#include "test_helpers.hpp"

using namespace snake_autonomy::core;
using snake_autonomy::test::cobra;

namespace {

KinematicState fk(const Kinematics& k, const Eigen::VectorXd& q, const Eigen::Vector3d& p = Eigen::Vector3d::Zero(),
                  const Eigen::Quaterniond& o = Eigen::Quaterniond::Identity()) {
  KinematicState s = k.make_state();
  EXPECT_TRUE(k.compute(p, o, q, s));
  return s;
}

}  // namespace

TEST(Kinematics, StraightBodyLiesAlongMinusX) {
  const RobotModel m = cobra();
  const Kinematics k(m);
  const KinematicState s = fk(k, Eigen::VectorXd::Zero(m.num_joints));
  ASSERT_EQ(s.link_positions.size(), 13u);
  EXPECT_NEAR(s.link_positions[1].x(), -0.1565, 1e-12);
  for (int i = 2; i < 13; ++i) {
    EXPECT_NEAR(s.link_positions[i].x(), -0.1565 - 0.123 * (i - 1), 1e-12) << "frame " << i;
    EXPECT_NEAR(s.link_positions[i].y(), 0.0, 1e-12);
    EXPECT_NEAR(s.link_positions[i].z(), 0.0, 1e-12);
  }
  // Eq. 3.15: masses 0.25, 0.25, 11 x 0.5 -> CoM at (0.25·0 + 0.25·(−H) + 0.5·Σ(−H − kL)) / 6.
  double x = 0.25 * -0.1565;
  for (int kk = 1; kk <= 11; ++kk) x += 0.5 * (-0.1565 - 0.123 * kk);
  EXPECT_NEAR(s.com.x(), x / 6.0, 1e-12);
  // Straight body: chassis aligned with the base, box = length + padding, 0.1 m wide and tall.
  EXPECT_TRUE(s.vc_rotation.isApprox(Eigen::Matrix3d::Identity(), 1e-12));
  EXPECT_NEAR(s.bbox_span.x(), 0.1565 + 11 * 0.123 + 0.1, 1e-12);
  EXPECT_NEAR(s.bbox_span.y(), 0.1, 1e-12);
  EXPECT_NEAR(s.bbox_span.z(), 0.1, 1e-12);
}

TEST(Kinematics, OddJointsPitchEvenJointsYaw) {
  const RobotModel m = cobra();
  const Kinematics k(m);
  for (int j = 0; j < m.num_joints; ++j) {
    Eigen::VectorXd q = Eigen::VectorXd::Zero(m.num_joints);
    q(j) = 0.3;
    const KinematicState s = fk(k, q);
    const Eigen::Vector3d tail = s.link_positions.back();
    if (j % 2 == 0) {  // joint j+1 odd: pitch -> the tail leaves the ground plane, stays at y = 0
      EXPECT_GT(std::abs(tail.z()), 0.01) << "joint " << j + 1;
      EXPECT_NEAR(tail.y(), 0.0, 1e-12) << "joint " << j + 1;
    } else {  // even: yaw -> the tail swings sideways in the ground plane
      EXPECT_GT(std::abs(tail.y()), 0.01) << "joint " << j + 1;
      EXPECT_NEAR(tail.z(), 0.0, 1e-12) << "joint " << j + 1;
    }
  }
}

TEST(Kinematics, JointsRotateByMinusQAsEquation34Says) {
  // link_1 has the base's orientation at q = 0 (Rx(+90°) then Rx(−90°)), so joint 2's Rz(−q)
  // turns the next link by −q about the world vertical.
  const RobotModel m = cobra();
  const Kinematics k(m);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(m.num_joints);
  q(1) = 0.2;
  const KinematicState s = fk(k, q);
  // link_2 = link_1 · Rz(−0.2) · Trans(−L): at (x1 − L cos 0.2, y1 + ..., 0) with link_1 yaw-aligned.
  const Eigen::Vector3d d = s.link_positions[3] - s.link_positions[2];
  const Eigen::Vector3d expected = Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitZ()) * Eigen::Vector3d(-0.123, 0, 0);
  EXPECT_TRUE(d.isApprox(expected, 1e-12)) << d.transpose();
}

TEST(Kinematics, BasePoseMovesTheWholeChainRigidly) {
  const RobotModel m = cobra();
  const Kinematics k(m);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd q(m.num_joints);
  for (int i = 0; i < m.num_joints; ++i) q(i) = u(rng);
  const Eigen::Quaterniond o = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized();
  const Eigen::Vector3d p(1.0, -2.0, 0.5);
  const KinematicState a = fk(k, q), b = fk(k, q, p, o);
  for (int i = 0; i < 13; ++i) {
    EXPECT_TRUE(b.link_positions[i].isApprox(o * a.link_positions[i] + p, 1e-12));
    EXPECT_TRUE(b.link_rotations[i].isApprox(o.toRotationMatrix() * a.link_rotations[i], 1e-12));
    // Parent poses do not depend on the base (except the base's own).
    if (i > 0) {
      EXPECT_TRUE(b.parent_positions[i].isApprox(a.parent_positions[i], 1e-12));
    }
  }
  EXPECT_TRUE(b.com.isApprox(o * a.com + p, 1e-12));
}

TEST(Kinematics, ParentPosesComposeToWorldPoses) {
  const RobotModel m = cobra();
  const Kinematics k(m);
  Eigen::VectorXd q = Eigen::VectorXd::LinSpaced(m.num_joints, -0.8, 0.9);
  const KinematicState s = fk(k, q, Eigen::Vector3d(0.3, 0.2, 0.1));
  for (int i = 1; i < 13; ++i) {
    const Eigen::Vector3d p = s.link_rotations[i - 1] * s.parent_positions[i] + s.link_positions[i - 1];
    EXPECT_TRUE(p.isApprox(s.link_positions[i], 1e-12)) << i;
    EXPECT_TRUE((s.link_rotations[i - 1] * s.parent_rotations[i]).isApprox(s.link_rotations[i], 1e-12)) << i;
  }
}

TEST(Kinematics, RejectsBadInputWithoutTouchingTheState) {
  const RobotModel m = cobra();
  const Kinematics k(m);
  KinematicState s = k.make_state();
  s.com = Eigen::Vector3d(7, 7, 7);
  EXPECT_FALSE(k.compute(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity(), Eigen::VectorXd::Zero(3), s));
  Eigen::VectorXd q = Eigen::VectorXd::Zero(m.num_joints);
  q(2) = std::nan("");
  EXPECT_FALSE(k.compute(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity(), q, s));
  EXPECT_EQ(s.com, Eigen::Vector3d(7, 7, 7));
}

TEST(VirtualChassis, MeanAxisAndSvdAgreeOnAStraightBodyAndFollowTheBaseYaw) {
  RobotModel m = cobra();
  const Eigen::Quaterniond yaw(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()));
  const Eigen::Matrix3d expected = yaw.toRotationMatrix();
  for (ChassisMethod method : {ChassisMethod::kMeanAxis, ChassisMethod::kSvd}) {
    m.chassis = method;
    const Kinematics k(m);
    const KinematicState s = fk(k, Eigen::VectorXd::Zero(m.num_joints), Eigen::Vector3d(1, 2, 0), yaw);
    EXPECT_TRUE(s.vc_rotation.isApprox(expected, 1e-9)) << to_string(method) << "\n" << s.vc_rotation;
  }
}

TEST(VirtualChassis, StaysHorizontalWhenTheBaseRollsAndPitches) {
  const RobotModel m = cobra();
  const Kinematics k(m);
  const Eigen::Quaterniond tilt = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()) *
                                  Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()) *
                                  Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitX());
  const KinematicState s = fk(k, Eigen::VectorXd::Constant(m.num_joints, 0.1), Eigen::Vector3d::Zero(), tilt);
  EXPECT_TRUE(s.vc_rotation.col(2).isApprox(Eigen::Vector3d::UnitZ(), 1e-12));
  EXPECT_NEAR(s.vc_rotation.determinant(), 1.0, 1e-12);
  EXPECT_TRUE((s.vc_rotation.transpose() * s.vc_rotation).isApprox(Eigen::Matrix3d::Identity(), 1e-12));
}

TEST(VirtualChassis, DegenerateVerticalAxisKeepsThePreviousFrame) {
  std::vector<Eigen::Matrix3d> rotations(3, Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix());
  Eigen::Matrix3d R = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Matrix3d before = R;
  EXPECT_FALSE(virtual_chassis_mean_axis(rotations, R));  // every x axis points straight down
  EXPECT_EQ(R, before);
  std::vector<Eigen::Vector3d> column{{0, 0, 0}, {0, 0, 1}, {0, 0, 2}};
  EXPECT_FALSE(virtual_chassis_svd(column, R));
  EXPECT_EQ(R, before);
}

TEST(VirtualChassis, BoundingBoxOfAKnownSet) {
  std::vector<Eigen::Vector3d> pts{{-1, 0, 0}, {1, 0.5, 0}, {0, -0.5, 0.2}};
  const Eigen::Vector3d span = bounding_box_span(pts, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(), 0.1);
  EXPECT_TRUE(span.isApprox(Eigen::Vector3d(2.1, 1.1, 0.3), 1e-12));
  // Rotated by 90° about z: x and y spans swap.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_TRUE(bounding_box_span(pts, Eigen::Vector3d::Zero(), R, 0.1).isApprox(Eigen::Vector3d(1.1, 2.1, 0.3), 1e-12));
}
