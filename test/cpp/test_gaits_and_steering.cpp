#include <gtest/gtest.h>

#include <cmath>

#include "snake_autonomy/core/curvature_steering.hpp"
#include "snake_autonomy/core/gait_library.hpp"
#include "snake_autonomy/core/steering.hpp"
#include "snake_autonomy/driver/gait_command.hpp"
#include "test_helpers.hpp"

using namespace snake_autonomy::core;
using namespace snake_autonomy::driver;
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

// --- steering laws per gait (config/gaits.yaml `steering:`) ---------------------------------------

TEST(SteeringLaw, GaitsNameTheirLawAndSteerableReadsAsAmplitudeModulation) {
  const auto lib = snake_autonomy::core::GaitLibrary::from_yaml_string(
      "gaits:\n"
      "  old: {frequency_hz: 0.3, steerable: true, pitch: {amplitude_deg: 0}, yaw: {amplitude_deg: 0}}\n"
      "  am: {frequency_hz: 0.3, steering: amplitude_modulation, pitch: {amplitude_deg: 0}, yaw: {amplitude_deg: 0}}\n"
      "  rect: {frequency_hz: 0.3, steering: curvature, pitch: {amplitude_deg: 0}, yaw: {amplitude_deg: 0}}\n"
      "  plain: {frequency_hz: 0.3, pitch: {amplitude_deg: 0}, yaw: {amplitude_deg: 0}}\n");
  using snake_autonomy::core::SteeringLaw;
  EXPECT_EQ(lib.spec("old").steering, SteeringLaw::kAmplitudeModulation);
  EXPECT_EQ(lib.spec("am").steering, SteeringLaw::kAmplitudeModulation);
  EXPECT_TRUE(lib.spec("am").steerable);
  EXPECT_EQ(lib.spec("rect").steering, SteeringLaw::kCurvature);
  EXPECT_FALSE(lib.spec("rect").steerable);
  EXPECT_EQ(lib.spec("plain").steering, SteeringLaw::kNone);
  try {
    snake_autonomy::core::GaitLibrary::from_yaml_string(
        "gaits:\n  g: {frequency_hz: 0.3, steering: wiggle, pitch: {amplitude_deg: 0}, yaw: {amplitude_deg: 0}}\n",
        "g.yaml");
    FAIL() << "accepted";
  } catch (const snake_autonomy::core::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("gaits.g.steering: 'wiggle'"), std::string::npos) << e.what();
  }
}

TEST(SteeringLaw, CurvatureBiasesTheLateralJointsByKappaTimesSpacingWithinTheLimits) {
  const auto model = snake_autonomy::test::cobra();
  const snake_autonomy::core::CurvatureSteering c(model);
  const auto yaw = model.yaw_joints();
  ASSERT_FALSE(yaw.empty());
  const Eigen::VectorXd nominal = Eigen::VectorXd::Zero(model.num_joints);
  Eigen::VectorXd out = nominal;
  ASSERT_TRUE(c.modify_biases(nominal, 0.5, out));
  for (std::size_t k = 0; k < yaw.size(); ++k) {
    EXPECT_NEAR(out(yaw[k]), 0.5 * c.spacing_m()[k], 1e-12);
    EXPECT_GT(c.spacing_m()[k], 0.0);
  }
  for (int p : model.pitch_joints()) EXPECT_EQ(out(p), 0.0);
  ASSERT_TRUE(c.modify_biases(nominal, 100.0, out));  // huge curvature: clamped to the upper limits
  for (int j : yaw) EXPECT_DOUBLE_EQ(out(j), model.joint_upper_rad[j]);
  EXPECT_FALSE(c.modify_biases(nominal, std::nan(""), out));
}

TEST(SteeringLaw, ASteeringValueTheGaitDoesNotAcceptIsRefusedWithTheReason) {
  const auto model = snake_autonomy::test::cobra();
  const auto lib = snake_autonomy::core::GaitLibrary::from_yaml_string(
      "gaits:\n"
      "  hold: {frequency_hz: 0, pitch: {amplitude_deg: 0}, yaw: {amplitude_deg: 0}}\n"
      "  am: {frequency_hz: 0.3, steering: amplitude_modulation, pitch: {amplitude_deg: 0}, yaw: {amplitude_deg: 30, "
      "lag_deg: 30}}\n"
      "  rect: {frequency_hz: 0.3, steering: curvature, pitch: {amplitude_deg: 0}, yaw: {amplitude_deg: 10, lag_deg: "
      "30}}\n");
  snake_autonomy::driver::GaitCommandResolver r(model, lib, 2.0);
  snake_autonomy::core::GaitParameters out = snake_autonomy::core::GaitParameters::zeros(model.num_joints);
  snake_autonomy::driver::GaitCommandRequest c;
  c.gait = "am";
  c.curve = true;
  c.kappa_per_m = 1.0;
  EXPECT_NE(r.resolve(c, out).find("kappa: gait 'am' does not steer by curvature (steering: amplitude_modulation)"),
            std::string::npos);
  c.gait = "rect";
  c.curve = false;
  c.steer = true;
  EXPECT_NE(r.resolve(c, out).find("steer: gait 'rect' is not steerable (steering: curvature"), std::string::npos);
  c.steer = false;
  c.curve = true;
  c.kappa_per_m = std::nan("");
  EXPECT_NE(r.resolve(c, out).find("kappa: nan is not a finite number"), std::string::npos);
  c.kappa_per_m = 0.5;
  ASSERT_EQ(r.resolve(c, out), "");
  const snake_autonomy::core::CurvatureSteering law(model);
  const auto yaw = model.yaw_joints();
  for (std::size_t k = 0; k < yaw.size(); ++k) EXPECT_NEAR(out.bias(yaw[k]), 0.5 * law.spacing_m()[k], 1e-12);
}
