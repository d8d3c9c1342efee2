#include <gtest/gtest.h>

#include "snake_autonomy/core/robot_model.hpp"
#include "test_helpers.hpp"

using namespace snake_autonomy::core;
using snake_autonomy::test::cobra;
using snake_autonomy::test::source_path;

TEST(RobotModel, LoadsCobraAsTheThesisDescribesIt) {
  const RobotModel m = cobra();
  EXPECT_EQ(m.num_joints, 11);
  EXPECT_EQ(m.num_frames(), 13);
  EXPECT_DOUBLE_EQ(m.head_length_m, 0.1565);
  EXPECT_DOUBLE_EQ(m.link_length_m, 0.1230);
  double total = 0;
  for (double mass : m.masses_kg) total += mass;
  EXPECT_NEAR(total, 6.0, 1e-12);  // eq. 3.16's masses, not the 7 kg of section 3.1
  EXPECT_EQ(m.yaw_joints(), (std::vector<int>{1, 3, 5, 7, 9}));
  EXPECT_EQ(m.pitch_joints(), (std::vector<int>{0, 2, 4, 6, 8, 10}));
  EXPECT_EQ(m.frame_names().front(), "base_link");
  EXPECT_EQ(m.frame_names().back(), "link_11");
}

TEST(RobotModel, LoadsTheUnifiedSnake) {
  const RobotModel m = RobotModel::from_yaml_file(source_path("config/robots/unified_snake.yaml"));
  EXPECT_EQ(m.num_joints, 16);
  EXPECT_EQ(m.num_frames(), 18);
  EXPECT_EQ(m.yaw_joints().size(), 8u);
}

TEST(RobotModel, AnyJointCountFromTwoWorks) {
  RobotModel m = cobra();
  m.num_joints = 2;
  m.axes.resize(2);
  m.masses_kg.resize(4);
  m.joint_lower_rad.resize(2);
  m.joint_upper_rad.resize(2);
  m.servos.ids.resize(2);
  m.servos.directions.resize(2);
  m.servos.zero_offsets_ticks.resize(2);
  m.steering.weights = {1.0};
  EXPECT_TRUE(m.validate().empty()) << m.validate().front();
  m.num_joints = 1;
  ASSERT_FALSE(m.validate().empty());
  EXPECT_EQ(m.validate().front(), "num_joints: must be an integer in 2..64, got 1");
}

TEST(RobotModel, ReportsEveryProblemNamingKeyAndValue) {
  RobotModel m = cobra();
  m.link_length_m = 0.0;
  m.masses_kg[4] = -1.0;
  m.joint_lower_rad[2] = m.joint_upper_rad[2];
  m.servos.ids[3] = m.servos.ids[0];
  m.servos.directions[5] = 2;
  m.steering.weights.pop_back();
  const auto errors = m.validate();
  auto has = [&](const std::string& text) {
    for (const auto& e : errors)
      if (e.find(text) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(has("link_length_m: must be a positive number, got 0"));
  EXPECT_TRUE(has("masses_kg[4]: must be a positive number, got -1"));
  EXPECT_TRUE(has("joint_limits_deg[2]: lower must be < upper"));
  EXPECT_TRUE(has("servos.ids[3]: duplicate id 1"));
  EXPECT_TRUE(has("servos.directions[5]: must be 1 or -1, got 2"));
  EXPECT_TRUE(has("steering.weights: expected 5 values, got 4"));
  EXPECT_EQ(errors.size(), 6u);
  EXPECT_THROW(m.validate_or_throw(), ConfigError);
}

TEST(RobotModel, YamlErrorsNameTheFile) {
  try {
    RobotModel::from_yaml_string("name: x\nnum_joints: seven\n", "robots/x.yaml");
    FAIL();
  } catch (const ConfigError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("robots/x.yaml"), std::string::npos) << w;
    EXPECT_NE(w.find("num_joints: expected an integer, got 'seven'"), std::string::npos) << w;
    EXPECT_NE(w.find("head_length_m: missing"), std::string::npos) << w;
  }
  EXPECT_THROW(RobotModel::from_yaml_file("/nonexistent.yaml"), ConfigError);
}
