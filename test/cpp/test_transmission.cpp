// Transmission: the one servo <-> joint conversion (table resolution and centre, direction, zero offset).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "snake_autonomy/driver/transmission.hpp"
#include "snake_autonomy/dynamixel/control_table.hpp"
#include "test_helpers.hpp"

using snake_autonomy::driver::Transmission;
namespace dx = snake_autonomy::dynamixel;

namespace {
constexpr double kPi = 3.14159265358979323846;
}

TEST(Transmission, PositionBothWaysWithDirectionAndZeroOffset) {
  const Transmission t(dx::kXh540Scales, -1, 100);
  std::int32_t ticks = 0;
  ASSERT_TRUE(t.joint_rad_to_ticks(kPi / 2, &ticks));
  EXPECT_EQ(ticks, 2048 + 100 - 1024);
  EXPECT_NEAR(t.ticks_to_joint_rad(2048 + 100 - 1024), kPi / 2, 1e-12);
  EXPECT_NEAR(t.ticks_to_joint_rad(2048 + 100), 0.0, 1e-12);
  EXPECT_NEAR(t.joint_rad_to_shaft_rad(0.3), 100 * 2 * kPi / 4096 - 0.3, 1e-12);
  EXPECT_NEAR(t.shaft_rad_to_joint_rad(t.joint_rad_to_shaft_rad(0.3)), 0.3, 1e-12);
  EXPECT_FALSE(t.joint_rad_to_ticks(std::nan(""), &ticks));
  EXPECT_FALSE(t.joint_rad_to_ticks(1e12, &ticks));
}

TEST(Transmission, AnotherResolutionConvertsCorrectly) {
  dx::UnitScales s;                 // a 1024-tick servo centred on 512
  s.rad_per_tick = 2 * kPi / 1024;
  s.centre_ticks = 512;
  const Transmission t(s, 1, 0);
  std::int32_t ticks = 0;
  ASSERT_TRUE(t.joint_rad_to_ticks(kPi / 2, &ticks));
  EXPECT_EQ(ticks, 512 + 256);
  EXPECT_NEAR(t.ticks_to_joint_rad(512 - 256), -kPi / 2, 1e-12);
}

TEST(Transmission, JointRangeIsRoundedInwardsWhateverTheDirection) {
  for (int d : {1, -1}) {
    const Transmission t(dx::kXh540Scales, d, 37);
    std::int32_t lo = 0, hi = 0;
    t.joint_range_to_ticks(-1.0, 0.5, &lo, &hi);
    ASSERT_LT(lo, hi);
    const double a = t.ticks_to_joint_rad(lo), b = t.ticks_to_joint_rad(hi);
    EXPECT_GE(std::min(a, b), -1.0);
    EXPECT_LE(std::max(a, b), 0.5);
    EXPECT_LT(std::min(a, b), -1.0 + 2 * kPi / 4096);  // and no more than one tick inside
    EXPECT_GT(std::max(a, b), 0.5 - 2 * kPi / 4096);
  }
}

TEST(Transmission, VelocityAndCurrentInJointSense) {
  const Transmission t(dx::kXh540Scales, -1, 0);
  EXPECT_NEAR(t.velocity_to_joint_rad_s(100), -100 * 0.229 * 2 * kPi / 60, 1e-12);
  EXPECT_NEAR(t.current_to_joint_amps(-200), 200 * 2.69e-3, 1e-12);
  EXPECT_DOUBLE_EQ(t.shaft_to_joint_sense(1.5), -1.5);
}

TEST(Transmission, ForRobotTakesTheTableAndTheRobotYaml) {
  const auto model = snake_autonomy::test::cobra();
  const auto table = dx::ControlTable::from_yaml_file(
      snake_autonomy::test::source_path("config/dynamixel/" + model.servos.model + ".yaml"));
  const auto tx = Transmission::for_robot(model, table);
  ASSERT_EQ(static_cast<int>(tx.size()), model.num_joints);
  for (int j = 0; j < model.num_joints; ++j) {
    EXPECT_EQ(tx[j].direction(), model.servos.directions[j]);
    EXPECT_EQ(tx[j].zero_offset_ticks(), model.servos.zero_offsets_ticks[j]);
    EXPECT_EQ(tx[j].centre_ticks(), table.position_centre_ticks);
  }
}
