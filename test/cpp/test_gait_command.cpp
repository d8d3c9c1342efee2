#include <gtest/gtest.h>

#include "snake_autonomy/driver/gait_command.hpp"
#include "test_helpers.hpp"

using namespace snake_autonomy::core;
using namespace snake_autonomy::driver;
using snake_autonomy::test::cobra;
using snake_autonomy::test::source_path;

namespace {
struct Fixture {
  RobotModel model = cobra();
  GaitLibrary gaits = GaitLibrary::from_yaml_file(source_path("config/gaits.yaml"));
  GaitCommandResolver resolver{model, gaits, 2.0};
};
}  // namespace

TEST(GaitCommandResolver, NamedGaitWithExplicitOverrides) {
  Fixture f;
  EXPECT_EQ(f.resolver.current_gait(), "hold");
  GaitCommandRequest c;
  c.gait = "sidewind";
  c.bias.assign(11, 0.1);
  GaitParameters out;
  ASSERT_EQ(f.resolver.resolve(c, out), "");
  const GaitParameters sw = f.gaits.parameters("sidewind", f.model);
  EXPECT_TRUE(out.amplitude.isApprox(sw.amplitude));
  EXPECT_TRUE(out.bias.isApprox(Eigen::VectorXd::Constant(11, 0.1)));
  EXPECT_EQ(f.resolver.current_gait(), "sidewind+custom");
  // No name: the current parameters stay, explicit ones replace them.
  GaitCommandRequest d;
  d.omega.assign(11, 1.0);
  ASSERT_EQ(f.resolver.resolve(d, out), "");
  EXPECT_TRUE(out.bias.isApprox(Eigen::VectorXd::Constant(11, 0.1)));
  EXPECT_TRUE(out.omega.isApprox(Eigen::VectorXd::Constant(11, 1.0)));
  c = GaitCommandRequest{};
  c.gait = "turn_right";
  ASSERT_EQ(f.resolver.resolve(c, out), "");
  EXPECT_EQ(f.resolver.current_gait(), "turn_right");
}

TEST(GaitCommandResolver, RefusesWholeWithEveryReason) {
  Fixture f;
  GaitCommandRequest c;
  c.gait = "sidewind";
  GaitParameters out;
  ASSERT_EQ(f.resolver.resolve(c, out), "");
  const GaitParameters kept = out;
  GaitCommandRequest bad;
  bad.gait = "hold";  // valid name, but the vectors are not
  bad.phase.assign(12, 0.0);
  bad.steer = true;
  bad.delta_rad = NAN;
  const std::string why = f.resolver.resolve(bad, out);
  EXPECT_NE(why.find("phase: 12 values, the robot has 11 joints"), std::string::npos) << why;
  EXPECT_NE(why.find("delta: nan"), std::string::npos) << why;
  EXPECT_NE(why.find("gait 'hold' is not steerable"), std::string::npos) << why;
  EXPECT_TRUE(out.amplitude.isApprox(kept.amplitude));  // untouched
  EXPECT_EQ(f.resolver.current_gait(), "sidewind");
  EXPECT_TRUE(f.resolver.nominal().amplitude.isApprox(kept.amplitude));
}
