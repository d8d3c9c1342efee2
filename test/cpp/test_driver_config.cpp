// DriverConfig::from_yaml: the one loader of the driver's configuration (node, batch simulator, Python).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "snake_autonomy/core/robot_model.hpp"
#include "snake_autonomy/driver/driver_config.hpp"

using snake_autonomy::core::ConfigError;
using snake_autonomy::driver::DriverConfig;
using snake_autonomy::driver::SafeAction;

TEST(DriverConfigYaml, ReadsTheControllersKeysAndIgnoresTheNodesOwn) {
  const DriverConfig c = DriverConfig::from_yaml_string(
      "rate_hz: 250.0\nbase_frame: b\nreturn_delay_time_us: -1\nmax_failed_cycles: 4\n"
      "fault_action: torque_off\nrequire_pose: false\nmax_joint_velocity_rad_s: 3\n");
  EXPECT_EQ(c.return_delay_time_us, -1);
  EXPECT_EQ(c.max_failed_cycles, 4);
  EXPECT_EQ(c.fault_action, SafeAction::kTorqueOff);
  EXPECT_FALSE(c.require_pose);
  EXPECT_DOUBLE_EQ(c.max_joint_velocity_rad_s, 3.0);
  EXPECT_DOUBLE_EQ(c.pose_timeout_s, DriverConfig{}.pose_timeout_s);  // absent: the default
}

TEST(DriverConfigYaml, EmptyTextGivesTheDefaults) {
  const DriverConfig c = DriverConfig::from_yaml_string("");
  EXPECT_EQ(c.max_failed_cycles, DriverConfig{}.max_failed_cycles);
}

TEST(DriverConfigYaml, EveryProblemNamesKeyAndValue) {
  try {
    DriverConfig::from_yaml_string(
        "max_failed_cycles: 2.5\nfault_action: explode\nreturn_delay_time_us: 3\n"
        "require_pose: maybe\npose_timeout_s: .nan\n",
        "drv.yaml");
    FAIL() << "accepted";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("drv.yaml: invalid driver configuration"), std::string::npos) << what;
    EXPECT_NE(what.find("max_failed_cycles: expected an integer, got '2.5'"), std::string::npos) << what;
    EXPECT_NE(what.find("fault_action: 'explode'"), std::string::npos) << what;
    EXPECT_NE(what.find("return_delay_time_us: 3"), std::string::npos) << what;
    EXPECT_NE(what.find("require_pose: expected true or false, got 'maybe'"), std::string::npos) << what;
    EXPECT_NE(what.find("pose_timeout_s: must be finite"), std::string::npos) << what;
  }
}

TEST(DriverConfigYaml, ApplyOverridesWithAPrefixAndKeysListEveryField) {
  DriverConfig c = DriverConfig::from_yaml_string("max_failed_cycles: 4\n");
  std::vector<std::string> errors;
  YAML::Node over(YAML::NodeType::Map);
  over["max_failed_cycles"] = 7;
  over["shutdown_action"] = "sideways";
  c.apply_yaml(over, &errors, "~");
  EXPECT_EQ(c.max_failed_cycles, 7);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0].rfind("~shutdown_action: 'sideways'", 0), 0u) << errors[0];
  EXPECT_EQ(DriverConfig::keys().size(), 18u);
  EXPECT_EQ(DriverConfig::keys().front(), "fast_sync_read");
}

TEST(DriverConfigYaml, TheShippedDriverYamlLoads) {
  const DriverConfig c = DriverConfig::from_yaml_file(std::string(SNAKE_SOURCE_DIR) + "/config/driver.yaml");
  EXPECT_DOUBLE_EQ(c.command_timeout_s, 3.0);
  EXPECT_EQ(c.return_delay_time_us, 0);
}
