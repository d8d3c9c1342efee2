#include <gtest/gtest.h>

#include "snake_autonomy/core/gait_library.hpp"
#include "snake_autonomy/core/steering.hpp"
#include "test_helpers.hpp"

using namespace snake_autonomy::core;
using snake_autonomy::test::cobra;
using snake_autonomy::test::source_path;

namespace {
constexpr double kDeg = M_PI / 180.0;
}

TEST(GaitLibrary, ShippedLibraryHasTheThesisGaits) {
  const GaitLibrary lib = GaitLibrary::from_yaml_file(source_path("config/gaits.yaml"));
  for (const char* name : {"sidewind", "turn_left", "turn_right", "near_turn_left", "near_turn_right", "hold"})
    EXPECT_TRUE(lib.contains(name)) << name;
  const RobotModel m = cobra();
  const GaitParameters sw = lib.parameters("sidewind", m);
  for (int i = 0; i < m.num_joints; ++i) {
    EXPECT_NEAR(sw.amplitude(i), (i % 2 == 0 ? 15.0 : 45.0) * kDeg, 1e-12) << i;  // pitch 15°, yaw 45°
    EXPECT_NEAR(sw.omega(i), sw.omega(0), 0.0);                                       // common frequency
  }
  EXPECT_TRUE(lib.spec("sidewind").steerable);
  EXPECT_FALSE(lib.spec("turn_left").steerable);
  // Turn in place: vertical lag larger than the lateral one (1.67x, tuned on the simulated plant:
  // it turns in place where 1.4x also crawls); left and right differ by the 90° sign.
  const GaitSpec& tl = lib.spec("turn_left");
  const GaitSpec& tr = lib.spec("turn_right");
  EXPECT_NEAR(tl.pitch.lag_rad / tl.yaw.lag_rad, 5.0 / 3.0, 0.01);
  EXPECT_NEAR(tl.pitch.offset_rad - tl.yaw.offset_rad, -(tr.pitch.offset_rad - tr.yaw.offset_rad), 1e-12);
  const GaitParameters hold = lib.parameters("hold", m);
  EXPECT_EQ(hold.amplitude.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(hold.omega.cwiseAbs().maxCoeff(), 0.0);
}

TEST(GaitLibrary, WaveExpansion) {
  const GaitLibrary lib = GaitLibrary::from_yaml_string(R"(
gaits:
  g:
    frequency_hz: 0.5
    pitch: {amplitude_deg: 10, lag_deg: 30, offset_deg: 90, bias_deg: 5}
    yaw: {amplitude_deg: 40, lag_deg: 20}
)");
  const RobotModel m = cobra();
  const GaitParameters p = lib.parameters("g", m);
  EXPECT_NEAR(p.phase(0), 90 * kDeg, 1e-12);           // joint 1 pitch: offset
  EXPECT_NEAR(p.phase(2), (90 + 2 * 30) * kDeg, 1e-12);  // joint 3 pitch: offset + 2 lags
  EXPECT_NEAR(p.phase(1), 20 * kDeg, 1e-12);           // joint 2 yaw: 0 + 1 lag
  EXPECT_NEAR(p.bias(0), 5 * kDeg, 1e-12);
  EXPECT_NEAR(p.bias(1), 0.0, 1e-12);
  EXPECT_NEAR(p.omega(5), M_PI, 1e-12);
  EXPECT_THROW(lib.parameters("nope", m), std::out_of_range);
}

TEST(GaitLibrary, EveryProblemIsListed) {
  try {
    GaitLibrary::from_yaml_string(R"(
gaits:
  a:
    frequency_hz: -1
    pitch: {amplitude_deg: x}
    yaw: {amplitude_deg: 10, lag: 3}
  b:
    pitch: {amplitude_deg: 1}
)",
                                  "test.yaml");
    FAIL() << "accepted a broken library";
  } catch (const ConfigError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("gaits.a.frequency_hz: must be in 0..5 Hz, got -1"), std::string::npos) << w;
    EXPECT_NE(w.find("gaits.a.pitch.amplitude_deg: expected a number, got 'x'"), std::string::npos) << w;
    EXPECT_NE(w.find("gaits.a.yaw.lag: unknown key"), std::string::npos) << w;
    EXPECT_NE(w.find("gaits.b.frequency_hz: missing"), std::string::npos) << w;
    EXPECT_NE(w.find("gaits.b.yaw: missing"), std::string::npos) << w;
  }
}

TEST(Steering, WeightsOnYawJointsOnly) {
  const RobotModel m = cobra();
  const Steering st(m);
  const Eigen::VectorXd nominal = Eigen::VectorXd::Constant(m.num_joints, 30 * kDeg);
  Eigen::VectorXd a(m.num_joints);
  ASSERT_TRUE(st.modify_amplitudes(nominal, 5 * kDeg, a));
  // Yaw joints J2, J4, J6, J8, J10 get 2δ, δ, 0, −δ, −2δ (eq. 3.27, Algorithm 1 lines 50-51).
  const double expected_deg[] = {30, 40, 30, 35, 30, 30, 30, 25, 30, 20, 30};
  for (int i = 0; i < m.num_joints; ++i) EXPECT_NEAR(a(i), expected_deg[i] * kDeg, 1e-12) << "joint " << i + 1;
}

TEST(Steering, ClampsDeltaAndAmplitudes) {
  RobotModel m = cobra();
  m.steering.delta_offset_rad = 1 * kDeg;
  const Steering st(m);
  const Eigen::VectorXd nominal = Eigen::VectorXd::Constant(m.num_joints, 45 * kDeg);
  Eigen::VectorXd a(m.num_joints);
  ASSERT_TRUE(st.modify_amplitudes(nominal, 100 * kDeg, a));  // δ clipped to 25°
  EXPECT_NEAR(a(1), 70 * kDeg, 1e-12);                        // 45 + 50 + 1 -> clamped at 70
  EXPECT_NEAR(a(3), 70 * kDeg, 1e-12);  // 45 + 25 + 1 = 71 -> clamped at 70
  EXPECT_NEAR(a(5), 46 * kDeg, 1e-12);  // centre: only the drift offset
  EXPECT_NEAR(a(9), (45 - 50 + 1) * kDeg, 1e-12);
  EXPECT_NEAR(st.clip_delta(-1.0), -25 * kDeg, 1e-12);
  Eigen::VectorXd untouched = nominal;
  EXPECT_FALSE(st.modify_amplitudes(nominal, std::nan(""), untouched));
  EXPECT_EQ(untouched, nominal);
}
