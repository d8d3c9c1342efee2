// The URDF generated from the robot YAML, parsed by kdl_parser (the library robot_state_publisher
// uses), gives the same frame poses as the core's own KDL chain for random joint vectors.
#include <gtest/gtest.h>

#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/tree.hpp>
#include <kdl_parser/kdl_parser.hpp>
#include <map>
#include <random>

#include "snake_autonomy/core/kinematics.hpp"
#include "snake_autonomy/core/urdf.hpp"

using namespace snake_autonomy::core;

namespace {

void check_robot(const std::string& yaml) {
  const RobotModel model = RobotModel::from_yaml_file(std::string(SNAKE_SOURCE_DIR) + "/" + yaml);
  const Kinematics kin(model);
  KDL::Tree tree;
  ASSERT_TRUE(kdl_parser::treeFromString(make_urdf(model), tree));
  const auto frames = model.frame_names();
  KDL::Chain chain;
  ASSERT_TRUE(tree.getChain(frames.front(), frames.back(), chain));
  ASSERT_EQ(chain.getNrOfJoints(), static_cast<unsigned>(model.num_joints));
  // Segment index of each named frame in the parsed chain.
  std::map<std::string, int> index;
  for (unsigned s = 0; s < chain.getNrOfSegments(); ++s) index[chain.getSegment(s).getName()] = static_cast<int>(s);

  KDL::ChainFkSolverPos_recursive solver(chain);
  std::mt19937 rng(42);
  KinematicState state = kin.make_state();
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::VectorXd q(model.num_joints);
    KDL::JntArray jq(model.num_joints);
    for (int i = 0; i < model.num_joints; ++i) {
      std::uniform_real_distribution<double> u(model.joint_lower_rad[i], model.joint_upper_rad[i]);
      q(i) = jq(i) = u(rng);
    }
    ASSERT_TRUE(kin.compute(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity(), q, state));
    for (std::size_t f = 1; f < frames.size(); ++f) {
      ASSERT_TRUE(index.count(frames[f])) << frames[f] << " missing from the URDF chain";
      KDL::Frame pose;
      ASSERT_GE(solver.JntToCart(jq, pose, index[frames[f]] + 1), 0);
      for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(pose.p(k), state.link_positions[f](k), 1e-9) << yaml << " " << frames[f];
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(pose.M(k, c), state.link_rotations[f](k, c), 1e-9) << frames[f];
      }
    }
  }
}

}  // namespace

TEST(Urdf, KdlParserChainMatchesTheCoreForCobra) { check_robot("config/robots/cobra.yaml"); }

TEST(Urdf, KdlParserChainMatchesTheCoreForTheUnifiedSnake) { check_robot("config/robots/unified_snake.yaml"); }

TEST(Urdf, JointLimitsComeFromTheYaml) {
  const RobotModel model = RobotModel::from_yaml_file(std::string(SNAKE_SOURCE_DIR) + "/config/robots/cobra.yaml");
  const std::string urdf = make_urdf(model);
  EXPECT_NE(urdf.find("<joint name=\"joint_11\" type=\"revolute\">"), std::string::npos);
  EXPECT_NE(urdf.find("lower=\"-1.5707963267948966\""), std::string::npos);
}

// camera_link sits at T_head^camera on head_link, and the optical frame looks along camera_link's x
// (its z axis) with x to the camera's right (−y) and y down (−z), as REP 103 asks.
TEST(Urdf, CameraFramesParsedByKdlMatchTheCalibration) {
  const RobotModel model = RobotModel::from_yaml_file(std::string(SNAKE_SOURCE_DIR) + "/config/robots/cobra.yaml");
  CameraMount camera;
  camera.camera_in_head = Eigen::Translation3d(0.03, -0.01, 0.02) * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()) *
                          Eigen::AngleAxisd(-1.2, Eigen::Vector3d::UnitY()) *
                          Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ());
  KDL::Tree tree;
  ASSERT_TRUE(kdl_parser::treeFromString(make_urdf(model, 9.9, 4.8, camera), tree));
  KDL::Chain chain;
  ASSERT_TRUE(tree.getChain("head_link", "camera_color_optical_frame", chain));
  ASSERT_EQ(chain.getNrOfJoints(), 0u);
  KDL::ChainFkSolverPos_recursive solver(chain);
  KDL::Frame link_pose, optical_pose;
  const KDL::JntArray none(0);
  ASSERT_GE(solver.JntToCart(none, link_pose, 1), 0);
  ASSERT_GE(solver.JntToCart(none, optical_pose, 2), 0);
  const Eigen::Matrix3d r = camera.camera_in_head.rotation();
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(link_pose.p(k), camera.camera_in_head.translation()(k), 1e-12);
    EXPECT_NEAR(optical_pose.p(k), camera.camera_in_head.translation()(k), 1e-12);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(link_pose.M(k, c), r(k, c), 1e-12);
    EXPECT_NEAR(optical_pose.M(k, 2), r(k, 0), 1e-12);   // optical z = camera x (forward)
    EXPECT_NEAR(optical_pose.M(k, 0), -r(k, 1), 1e-12);  // optical x = camera −y (right)
    EXPECT_NEAR(optical_pose.M(k, 1), -r(k, 2), 1e-12);  // optical y = camera −z (down)
  }
}
