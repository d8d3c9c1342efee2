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
