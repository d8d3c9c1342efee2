#include <gtest/gtest.h>

#include "snake_autonomy/core/robot_model.hpp"

using snake_autonomy::core::RobotModel;

TEST(RobotModel, LoadsCobra) {
  const auto m = RobotModel::from_yaml_file(std::string(SNAKE_SOURCE_DIR) + "/config/robots/cobra.yaml");
  EXPECT_EQ(m.num_joints, 11);
}
