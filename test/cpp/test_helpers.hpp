// Shared helpers of the C++ unit tests.
#pragma once

#include <string>

#include "snake_autonomy/core/robot_model.hpp"

namespace snake_autonomy::test {

inline std::string source_path(const std::string& relative) { return std::string(SNAKE_SOURCE_DIR) + "/" + relative; }

inline core::RobotModel cobra() { return core::RobotModel::from_yaml_file(source_path("config/robots/cobra.yaml")); }

}  // namespace snake_autonomy::test
