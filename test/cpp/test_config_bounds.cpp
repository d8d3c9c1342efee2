// Loader bounds: sizes refused before anything is allocated, physical ranges,
// files that are not configuration text, and error messages that stay short whatever the node.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <regex>
#include <string>

#include "snake_autonomy/core/config_reader.hpp"
#include "snake_autonomy/core/gait_library.hpp"
#include "snake_autonomy/core/robot_model.hpp"
#include "snake_autonomy/core/urdf.hpp"
#include "test_helpers.hpp"

using namespace snake_autonomy::core;
using snake_autonomy::test::source_path;

namespace {

std::string cobra_text() {
  std::ifstream in(source_path("config/robots/cobra.yaml"));
  return std::string(std::istreambuf_iterator<char>(in), {});
}

std::string error_of(const std::string& text) {
  try {
    RobotModel::from_yaml_string(text, "robot.yaml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

std::string temp_file(const std::string& name, const std::string& data) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path, std::ios::binary) << data;
  return path;
}

}  // namespace

TEST(ConfigBounds, AHugeJointCountIsRefusedBeforeAllocating) {
  // before: 6 GB and 13 s of axis_pattern expansion, then bad_alloc
  const auto text = std::regex_replace(cobra_text(), std::regex("num_joints: 11"), "num_joints: 1000000000");
  const auto w = error_of(text);
  EXPECT_NE(w.find("robot.yaml"), std::string::npos) << w;
  EXPECT_NE(w.find("num_joints: must be an integer in 2..64, got 1000000000"), std::string::npos) << w;
  EXPECT_NE(error_of(std::regex_replace(cobra_text(), std::regex("num_joints: 11"), "num_joints: 65"))
                .find("num_joints: must be an integer in 2..64, got 65"),
            std::string::npos);
}

TEST(ConfigBounds, MassesAndLengthsHavePhysicalRanges) {
  auto text = std::regex_replace(cobra_text(), std::regex("masses_kg: \\[0.25"), "masses_kg: [1e308");
  text = std::regex_replace(text, std::regex("link_length_m: 0.1230"), "link_length_m: 1e300");
  text = std::regex_replace(text, std::regex("mu: 10.0"), "mu: 1e9");
  text = std::regex_replace(text, std::regex("weights: \\[2.0"), "weights: [1e200");
  const auto w = error_of(text);
  EXPECT_NE(w.find("masses_kg[0]: must be at most 100 kg, got 1e+308"), std::string::npos) << w;
  EXPECT_NE(w.find("link_length_m: must be at most 10 m, got 1e+300"), std::string::npos) << w;
  EXPECT_NE(w.find("cpg.mu: must be at most 1000 1/s, got 1e+09"), std::string::npos) << w;
  EXPECT_NE(w.find("steering.weights[0]: must be within +-100 , got 1e+200"), std::string::npos) << w;
}

TEST(ConfigBounds, NoInfiniteMassReachesTheUrdf) {
  RobotModel m = snake_autonomy::test::cobra();
  m.masses_kg[0] = m.masses_kg[1] = 1e308;  // their sum (head_link's inertial) would be inf
  EXPECT_THROW(make_urdf(m), ConfigError);
  m = snake_autonomy::test::cobra();
  EXPECT_EQ(make_urdf(m).find("inf"), std::string::npos);
}

TEST(ConfigBounds, LongListsAreRefusedUnread) {
  std::string ids = "[";
  for (int i = 0; i < 2000; ++i) ids += (i ? ", " : "") + std::to_string(i);
  ids += "]";
  const auto text = std::regex_replace(cobra_text(), std::regex("ids: \\[[^\\]]*\\]"), "ids: " + ids);
  const auto w = error_of(text);
  EXPECT_NE(w.find("servos.ids: at most 1024 values, got 2000"), std::string::npos) << w;
}

namespace {

// Nested aliases: the last key (the names' last letter) expands to 9^names.size() leaves.
std::string laughs(const std::string& names) {
  std::string text = "a: &a [x, x, x, x, x, x, x, x, x]\n";
  for (std::size_t i = 1; i < names.size(); ++i) {
    const char p = names[i - 1], c = names[i];
    text += std::string(1, c) + ": &" + c + " [";
    for (int k = 0; k < 9; ++k) text += std::string(k ? ", " : "") + "*" + p;
    text += "]\n";
  }
  return text;
}

}  // namespace

TEST(ConfigBounds, ABillionLaughsIsRefusedUnwalked) {
  const auto w = error_of(laughs("abcdefghi") + "num_joints: *i\n");  // 9^9 leaves
  EXPECT_NE(w.find("robot.yaml: more than 65536 values (aliases expanding?)"), std::string::npos) << w;
}

TEST(ConfigBounds, DuplicateKeysAndDeepNestingAreRefused) {
  auto w = error_of(cobra_text() + "num_joints: 12\n");
  EXPECT_NE(w.find("robot.yaml: line "), std::string::npos) << w;
  EXPECT_NE(w.find(": duplicate key 'num_joints' (first given on line 5)"), std::string::npos) << w;
  w = error_of("name: x\nnum_joints: " + std::string(100, '[') + std::string(100, ']') + "\n");
  EXPECT_NE(w.find("robot.yaml: line 2: nested deeper than 32 levels"), std::string::npos) << w;
}

TEST(ConfigBounds, AliasedNodesInErrorsAreCutShort) {
  // an aliased value (9^4 leaves, under the node budget): its error message stays one short line
  const auto w = error_of(laughs("abcd") + "num_joints: *d\n");
  EXPECT_NE(w.find("num_joints: expected an integer, got '[[[[x, x, x"), std::string::npos) << w;
  EXPECT_LT(w.size(), 2000u) << w;
}

TEST(ConfigBounds, FilesThatAreNotConfigurationTextAreRefused) {
  const auto binary = temp_file("binary.yaml", std::string("name: x\0\x01\x02", 10));
  try {
    RobotModel::from_yaml_file(binary);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(binary + ": not a text file (NUL byte at offset 7)"), std::string::npos)
        << e.what();
  }
  const auto big = temp_file("big.yaml", "# " + std::string(kMaxConfigBytes, 'x') + "\n");
  try {
    GaitLibrary::from_yaml_file(big);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(big + ": larger than 1048576 bytes"), std::string::npos) << e.what();
  }
  std::remove(binary.c_str());
  std::remove(big.c_str());
}

TEST(ConfigBounds, GaitValuesHavePhysicalRanges) {
  const std::string text =
      "gaits:\n"
      "  g:\n"
      "    frequency_hz: 1.0e+308\n"
      "    pitch: {amplitude_deg: 1e300, lag_deg: 30, offset_deg: 9000, bias_deg: 0}\n"
      "    yaw: {amplitude_deg: 45, lag_deg: 30, offset_deg: 0, bias_deg: -200}\n";
  try {
    GaitLibrary::from_yaml_string(text, "gaits.yaml");
    FAIL();
  } catch (const ConfigError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("gaits.g.frequency_hz: must be in 0..5 Hz, got 1e+308"), std::string::npos) << w;
    EXPECT_NE(w.find("gaits.g.pitch.amplitude_deg: must be within +-180 deg, got 1e+300"), std::string::npos) << w;
    EXPECT_NE(w.find("gaits.g.pitch.offset_deg: must be within +-360 deg, got 9000"), std::string::npos) << w;
    EXPECT_NE(w.find("gaits.g.yaw.bias_deg: must be within +-180 deg, got -200"), std::string::npos) << w;
  }
  // a non-scalar gait name is an error with its value, not a YAML exception
  EXPECT_THROW(GaitLibrary::from_yaml_string("gaits:\n  [a, b]: {frequency_hz: 1}\n", "gaits.yaml"), ConfigError);
}
