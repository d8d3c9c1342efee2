#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "snake_autonomy/core/cpg.hpp"
#include "snake_autonomy/core/gait_library.hpp"
#include "test_helpers.hpp"

using namespace snake_autonomy::core;
using snake_autonomy::test::cobra;
using snake_autonomy::test::source_path;

namespace {

double wrap(double a) { return std::atan2(std::sin(a), std::cos(a)); }

GaitParameters random_parameters(std::mt19937& rng, int n, double amp_max = 1.2) {
  std::uniform_real_distribution<double> amp(-amp_max, amp_max), w(0.0, 6.0), ph(-M_PI, M_PI), b(-0.3, 0.3);
  GaitParameters p = GaitParameters::zeros(n);
  const double omega = w(rng);  // common frequency, as the gaits use
  for (int i = 0; i < n; ++i) {
    p.amplitude(i) = amp(rng);
    p.omega(i) = omega;
    p.phase(i) = ph(rng);
    p.bias(i) = b(rng);
  }
  return p;
}

}  // namespace

TEST(Cpg, LagsConvergeToCommandedFromRandomPhases) {
  const RobotModel model = cobra();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ph(-10.0, 10.0);
  for (int trial = 0; trial < 20; ++trial) {
    Cpg cpg(model);
    const GaitParameters p = random_parameters(rng, model.num_joints);
    cpg.set_parameters(p);
    Eigen::VectorXd theta0(model.num_joints);
    for (int i = 0; i < model.num_joints; ++i) theta0(i) = ph(rng);
    cpg.reset(theta0, Eigen::VectorXd::Zero(model.num_joints), Eigen::VectorXd::Zero(model.num_joints));
    for (int k = 0; k < 2000; ++k) cpg.step(0.01);  // 20 s; slowest mode τ = 1/(μ·0.081) ≈ 1.2 s
    for (int i = 0; i + 1 < model.num_joints; ++i) {
      const double lag = cpg.phases()(i + 1) - cpg.phases()(i);
      EXPECT_NEAR(wrap(lag - (p.phase(i + 1) - p.phase(i))), 0.0, 1e-6) << "trial " << trial << " joint " << i;
    }
  }
}

TEST(Cpg, CommonFrequencyAdvancesEveryPhase) {
  const RobotModel model = cobra();
  Cpg cpg(model);
  GaitParameters p = GaitParameters::zeros(model.num_joints);
  p.omega.setConstant(2.0);
  cpg.set_parameters(p);
  const Eigen::VectorXd before = cpg.phases();
  for (int k = 0; k < 100; ++k) cpg.step(0.01);
  // 1 s at 2 rad/s: every phase advanced by 2 rad (modulo whole turns).
  for (int i = 0; i < model.num_joints; ++i) EXPECT_NEAR(wrap(cpg.phases()(i) - before(i) - 2.0), 0.0, 1e-9);
}

TEST(Cpg, AmplitudeStepNeverOvershoots) {
  const RobotModel model = cobra();
  for (double target : {0.2, 0.7, 1.2, -0.5}) {
    Cpg cpg(model);
    GaitParameters p = GaitParameters::zeros(model.num_joints);
    p.amplitude.setConstant(target);
    cpg.set_parameters(p);
    double previous = 0.0;
    for (int k = 0; k < 1500; ++k) {
      cpg.step(0.01);
      const double r = cpg.amplitudes()(0);
      // Monotonic approach from 0 to the target, never beyond it (eq. 3.23 as printed overshoots ~16 %).
      EXPECT_LE(std::abs(r), std::abs(target) + 1e-12) << "step " << k;
      EXPECT_GE(std::abs(r), std::abs(previous) - 1e-12) << "step " << k;
      previous = r;
    }
    EXPECT_NEAR(previous, target, 1e-6);
  }
}

TEST(Cpg, AmplitudeDynamicsAreCriticallyDamped) {
  // Critically damped closed form: r(t) = a (1 − (1 + γt) e^{−γt}) from rest.
  const RobotModel model = cobra();
  Cpg cpg(model);
  GaitParameters p = GaitParameters::zeros(model.num_joints);
  p.amplitude.setConstant(0.5);
  cpg.set_parameters(p);
  const double g = cpg.gamma();
  for (int k = 1; k <= 300; ++k) {
    cpg.step(0.01);
    const double t = 0.01 * k;
    EXPECT_NEAR(cpg.amplitudes()(3), 0.5 * (1.0 - (1.0 + g * t) * std::exp(-g * t)), 1e-12);
  }
}

TEST(Cpg, OneMillisecondAndTenMillisecondStepsAgree) {
  const RobotModel model = cobra();
  std::mt19937 rng(3);
  for (int trial = 0; trial < 10; ++trial) {
    const GaitParameters p = random_parameters(rng, model.num_joints);
    Cpg coarse(model), fine(model);
    coarse.set_parameters(p);
    fine.set_parameters(p);
    double worst_transient = 0.0;
    for (int k = 0; k < 3000; ++k) {  // 30 s
      coarse.step(0.01);
      for (int j = 0; j < 10; ++j) fine.step(0.001);
      worst_transient = std::max(worst_transient, (coarse.output() - fine.output()).cwiseAbs().maxCoeff());
    }
    // While the lags move, they enter the phase step at their mid-step value: second order in dt.
    EXPECT_LT(worst_transient, 1e-3);
    // Once they settle, the exact integration leaves no step-size dependence at all.
    EXPECT_LT((coarse.output() - fine.output()).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT((coarse.amplitudes() - fine.amplitudes()).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(Cpg, StableWithLargeStepsAndStrongCoupling) {
  const RobotModel model = cobra();
  Cpg cpg(model, /*mu=*/500.0, /*gamma=*/50.0);  // explicit Euler at 10 ms would diverge (μ·4·dt = 20)
  std::mt19937 rng(11);
  cpg.set_parameters(random_parameters(rng, model.num_joints));
  for (int k = 0; k < 1000; ++k) {
    cpg.step(0.01);
    ASSERT_TRUE(cpg.phases().allFinite());
    ASSERT_LT(cpg.amplitudes().cwiseAbs().maxCoeff(), model.cpg.amplitude_limit_rad + 1e-9);
  }
}

TEST(Cpg, ParameterChangesNeverMakeTheOutputJump) {
  const RobotModel model = cobra();
  Cpg cpg(model);
  std::mt19937 rng(5);
  const double dt = 0.01;
  double worst = 0.0;
  for (int k = 0; k < 6000; ++k) {
    if (k % 50 == 0) cpg.set_parameters(random_parameters(rng, model.num_joints));  // every 0.5 s
    const Eigen::VectorXd before = cpg.output();
    cpg.step(dt);
    worst = std::max(worst, (cpg.output() - before).cwiseAbs().maxCoeff());
  }
  // The fastest smooth motion possible: |r| ω + |dr/dt| + |db/dt| with |r| <= 70°, ω <= 6 rad/s.
  // A jump of a bias (0.6 rad) or of an amplitude would far exceed 0.1 rad in one 10 ms step.
  EXPECT_LT(worst, 0.1);
}

TEST(Cpg, OutputStaysInsideJointLimitsWhateverIsCommanded) {
  const RobotModel model = cobra();
  Cpg cpg(model);
  std::mt19937 rng(9);
  bool clamped = false;
  for (int k = 0; k < 5000; ++k) {
    if (k % 100 == 0) {
      GaitParameters p = random_parameters(rng, model.num_joints, 10.0);  // far beyond any limit
      p.bias *= 20.0;
      cpg.set_parameters(p);
    }
    const Eigen::VectorXd& q = cpg.step(0.01);
    for (int i = 0; i < model.num_joints; ++i) {
      ASSERT_GE(q(i), model.joint_lower_rad[i]);
      ASSERT_LE(q(i), model.joint_upper_rad[i]);
    }
    clamped = clamped || (cpg.unclamped_output() - q).cwiseAbs().maxCoeff() > 0.0;
  }
  EXPECT_TRUE(clamped) << "the commands never reached the limits: the test proves nothing";
  EXPECT_LE(cpg.targets().amplitude.cwiseAbs().maxCoeff(), model.cpg.amplitude_limit_rad);
}

TEST(Cpg, InvalidParametersAreRefusedWhole) {
  const RobotModel model = cobra();
  Cpg cpg(model);
  GaitParameters good = GaitParameters::zeros(model.num_joints);
  good.amplitude.setConstant(0.3);
  cpg.set_parameters(good);
  GaitParameters bad = good;
  bad.amplitude.setConstant(0.9);
  bad.omega(4) = std::nan("");
  bad.phase.resize(3);
  const std::string err = cpg.validate(bad);
  EXPECT_NE(err.find("omega[4]: must be finite"), std::string::npos) << err;
  EXPECT_NE(err.find("phase: expected 11 values, got 3"), std::string::npos) << err;
  EXPECT_FALSE(cpg.apply(bad));
  EXPECT_THROW(cpg.set_parameters(bad), std::invalid_argument);
  EXPECT_DOUBLE_EQ(cpg.targets().amplitude(0), 0.3);  // nothing of the bad command applied
}

TEST(Cpg, SidewindingGaitHasNinetyDegreesBetweenWaves) {
  const RobotModel model = cobra();
  const GaitLibrary lib = GaitLibrary::from_yaml_file(source_path("config/gaits.yaml"));
  const GaitParameters p = lib.parameters("sidewind", model);
  Cpg cpg(model);
  cpg.set_parameters(p);
  for (int k = 0; k < 3000; ++k) cpg.step(0.01);
  // Pitch joint 1 and yaw joint 2: lag = (yaw offset + lag) − pitch offset, as the file says.
  const double lag12 = cpg.phases()(1) - cpg.phases()(0);
  EXPECT_NEAR(wrap(lag12 - (p.phase(1) - p.phase(0))), 0.0, 1e-6);
  EXPECT_NEAR(cpg.amplitudes()(0), 15.0 * M_PI / 180.0, 1e-6);
  EXPECT_NEAR(cpg.amplitudes()(1), 45.0 * M_PI / 180.0, 1e-6);
}

TEST(Cpg, PhasesStartOnTheTravellingWaveFromRest) {
  // From rest the phases take the gait's pattern at once: the first cycle is already the travelling
  // wave (equal phases with pitch and yaw 90 deg apart would be a rolling gait).
  const RobotModel model = cobra();
  Cpg cpg(model);
  GaitParameters p = GaitParameters::zeros(model.num_joints);
  p.amplitude.setConstant(0.5);
  p.omega.setConstant(2.0 * M_PI * 0.7);
  p.phase = Eigen::VectorXd::LinSpaced(model.num_joints, 0.0, 3.0);  // lags 0.3
  cpg.set_parameters(p);
  for (int i = 0; i + 1 < model.num_joints; ++i)
    EXPECT_NEAR(cpg.phases()(i + 1) - cpg.phases()(i), 0.3, 1e-12) << "joint " << i;
  cpg.step(0.01);
  for (int i = 0; i + 1 < model.num_joints; ++i)
    EXPECT_NEAR(wrap(cpg.phases()(i + 1) - cpg.phases()(i) - 0.3), 0.0, 1e-9) << "joint " << i;
}

TEST(Cpg, LagsGlideWhileMovingAndJumpAtRest) {
  const RobotModel model = cobra();
  Cpg cpg(model);
  GaitParameters p = GaitParameters::zeros(model.num_joints);
  p.amplitude.setConstant(0.5);
  p.phase = Eigen::VectorXd::LinSpaced(model.num_joints, 0.0, 2.0);  // lags 0.2
  cpg.set_parameters(p);  // from rest: lags at their targets at once
  EXPECT_NEAR(cpg.lags()(3), 0.2, 1e-12);
  for (int k = 0; k < 500; ++k) cpg.step(0.01);
  p.phase = Eigen::VectorXd::LinSpaced(model.num_joints, 0.0, -2.0);  // lags −0.2 while oscillating
  cpg.set_parameters(p);
  cpg.step(0.01);
  EXPECT_GT(cpg.lags()(3), 0.19);  // still near the old lag: gliding, not jumping
  for (int k = 0; k < 1000; ++k) cpg.step(0.01);
  EXPECT_NEAR(cpg.lags()(3), -0.2, 1e-6);
}

TEST(Cpg, StopKeepsTheLagsWhileTheWaveDecaysAndAGaitResumesFromThem) {
  // Tracking lost for 1 s while sidewinding: the mission sends `hold` (amplitudes, frequency and
  // lags 0), then sidewinding again. The lags must stay the sidewinding ones throughout: gliding to
  // 0 while the waves are still large, and resumed from there, swings the joints nearly in phase
  // with pitch and yaw 90 deg apart, which rolled the simulated COBRA over.
  const RobotModel model = cobra();
  const GaitLibrary lib = GaitLibrary::from_yaml_file(source_path("config/gaits.yaml"));
  const GaitParameters sidewind = lib.parameters("sidewind", model);
  const GaitParameters hold = lib.parameters("hold", model);
  Cpg cpg(model);
  cpg.set_parameters(sidewind);
  for (int k = 0; k < 1000; ++k) cpg.step(0.01);
  const Eigen::VectorXd moving_lags = cpg.lags();
  cpg.set_parameters(hold);
  double worst_lag_change = 0.0;
  for (int k = 0; k < 100; ++k) {
    cpg.step(0.01);
    worst_lag_change = std::max(worst_lag_change, (cpg.lags() - moving_lags).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst_lag_change, 1e-9);
  EXPECT_GT(cpg.amplitudes()(1), 0.1) << "still moving after 1 s: the stop is a decay, not a jump";
  EXPECT_LT(cpg.amplitudes()(1), 0.5 * 45.0 * M_PI / 180.0);
  cpg.set_parameters(sidewind);
  for (int k = 0; k < 300; ++k) {
    cpg.step(0.01);
    worst_lag_change = std::max(worst_lag_change, (cpg.lags() - moving_lags).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst_lag_change, 1e-9);
}

TEST(Cpg, StopTakesItsLagsOnceAtRest) {
  const RobotModel model = cobra();
  const GaitLibrary lib = GaitLibrary::from_yaml_file(source_path("config/gaits.yaml"));
  Cpg cpg(model);
  cpg.set_parameters(lib.parameters("sidewind", model));
  for (int k = 0; k < 500; ++k) cpg.step(0.01);
  const GaitParameters hold = lib.parameters("hold", model);
  cpg.set_parameters(hold);
  for (int k = 0; k < 1500; ++k) cpg.step(0.01);  // 15 s: the waves have decayed
  cpg.set_parameters(hold);                        // the mission repeats its command every tick
  EXPECT_NEAR(cpg.lags().cwiseAbs().maxCoeff(), 0.0, 1e-12);
}
