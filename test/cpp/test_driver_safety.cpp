// The driver's safety rules on FakeServoBus: absurd but finite inputs are refused before
// they reach the loop, nothing in the loop throws, a non-finite CPG state faults with a reason, a
// running gait without commands stops and holds, base poses are range-checked.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "driver_rig.hpp"
#include "snake_autonomy/driver/safety_rules.hpp"
#include "test_access.hpp"

namespace snake_autonomy::driver {
// Test hook (friend of DriverController): reaches the gait source's CPG (test_access.hpp).
struct DriverControllerTestAccess {
  static core::Cpg& cpg(DriverController& d) { return GaitSourceTestAccess::cpg(d.gait_); }
};
}  // namespace snake_autonomy::driver

using namespace snake_autonomy::core;
using namespace snake_autonomy::driver;
using snake_autonomy::test::kDeg;
using snake_autonomy::test::Rig;

namespace {

GaitCommandRequest absurd_phases() {
  GaitCommandRequest c;
  c.gait = "sidewind";
  for (int i = 0; i < 11; ++i) c.phase.push_back(i % 2 ? -1e308 : 1e308);
  return c;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// Max - min of servo `id`'s goal ticks over `cycles` cycles.
std::int64_t goal_span(Rig& rig, int id, int cycles) {
  std::int64_t lo = rig.goal(id), hi = lo;
  for (int k = 0; k < cycles; ++k) {
    rig.step();
    lo = std::min(lo, rig.goal(id));
    hi = std::max(hi, rig.goal(id));
  }
  return hi - lo;
}

}  // namespace

// Phases of ±1e308 were accepted and made the oscillators NaN while the driver
// said "running"; then a hold and a new command aborted the driver (Cpg::reset threw in noexcept).
TEST(DriverSafety, AbsurdPhasesAreRefusedAndTheCpgStaysFinite) {
  Rig rig;
  rig.start();
  ASSERT_EQ(rig.command("sidewind"), "");
  rig.step(100);
  const std::string why = rig.ctl->command_gait(absurd_phases());
  EXPECT_TRUE(contains(why, "phase[0] (joint_1): 1e+308 is outside [-1000, 1000]")) << why;
  EXPECT_TRUE(contains(why, "phase[1] (joint_2): -1e+308")) << why;
  rig.step(100);
  EXPECT_TRUE(rig.ctl->cpg().state_finite());
  EXPECT_EQ(rig.ctl->state(), DriverState::kRunning);
  EXPECT_GT(goal_span(rig, 2, 300), 300);  // still sidewinding
  // The recovery that used to abort: hold, then a command.
  EXPECT_TRUE(rig.request(DriverRequest::kHold).success);
  ASSERT_EQ(rig.command("sidewind"), "");
  rig.step(5);
  EXPECT_EQ(rig.ctl->state(), DriverState::kRunning);
  EXPECT_TRUE(rig.ctl->cpg().state_finite());
}

TEST(DriverSafety, EveryAbsurdValueIsRefusedNamingFieldJointAndValue) {
  Rig rig;
  rig.start();
  GaitCommandRequest c;
  c.gait = "sidewind";
  c.amplitude.assign(11, 0.5);
  c.amplitude[4] = 1e308;
  c.bias.assign(11, 0.0);
  c.bias[6] = 1e308;
  c.bias[7] = -2.0;  // beyond -90 deg
  c.steer = true;
  c.delta_rad = 1e300;
  const std::string why = rig.ctl->command_gait(c);
  for (const char* part : {"amplitude[4] (joint_5): 1e+308 is outside", "bias[6] (joint_7): 1e+308 is outside",
                           "bias[7] (joint_8): -2 is outside [-1.5708, 1.5708] rad (the joint limits)",
                           "delta: 1e+300 is outside [-pi, pi]"})
    EXPECT_TRUE(contains(why, part)) << part << " in:\n" << why;
  EXPECT_EQ(rig.ctl->commands_refused(), 1u);
  // Within range: accepted (an amplitude beyond the CPG's 70 deg limit is clamped, not refused).
  c.amplitude[4] = 2.0;
  c.bias[6] = 0.2;
  c.bias[7] = -0.2;
  c.delta_rad = 0.3;
  EXPECT_EQ(rig.ctl->command_gait(c), "");
}

TEST(DriverSafety, AcceptedPhasesAreWrappedAndKeepTheirDifferences) {
  Rig rig;
  rig.start();
  GaitCommandRequest c;
  c.gait = "sidewind";
  for (int i = 0; i < 11; ++i) c.phase.push_back(900.0 + 1.3 * i);
  ASSERT_EQ(rig.ctl->command_gait(c), "");
  rig.step(300);
  const Eigen::VectorXd& lags = rig.ctl->cpg().lags();
  for (int i = 0; i < 10; ++i) EXPECT_NEAR(std::remainder(lags(i) - 1.3, 2 * M_PI), 0.0, 1e-6) << i;
  EXPECT_TRUE(rig.ctl->cpg().state_finite());
}

// Point 2: if the CPG state ever becomes non-finite the supervisor faults with a reason and applies
// the fault action (a corrupted state, injected through the test hook: no input can make one).
TEST(DriverSafety, CorruptedCpgStateFaultsWithAReasonAndAppliesTheFaultAction) {
  for (SafeAction action : {SafeAction::kHold, SafeAction::kTorqueOff}) {
    DriverConfig cfg;
    cfg.fault_action = action;
    Rig rig(cfg);
    rig.start();
    ASSERT_EQ(rig.command("sidewind"), "");
    rig.step(100);
    CpgTestAccess::corrupt_phase(DriverControllerTestAccess::cpg(*rig.ctl), 3);
    rig.step();
    EXPECT_EQ(rig.ctl->state(), DriverState::kFault);
    EXPECT_TRUE(contains(rig.ctl->fault_reason(), "CPG state not finite")) << rig.ctl->fault_reason();
    if (action == SafeAction::kHold) {
      EXPECT_EQ(goal_span(rig, 2, 50), 0);
      EXPECT_EQ(rig.torque(2), 1);
    } else {
      for (int id = 1; id <= 11; ++id) EXPECT_EQ(rig.torque(id), 0) << id;
    }
    EXPECT_TRUE(contains(rig.command("sidewind"), "fault"));  // refused until recovered
  }
}

// Point 2: the restart at a command from Holding (Cpg::reset threw inside noexcept) faults instead.
TEST(DriverSafety, CorruptedCpgAtRestartFaultsInsteadOfAborting) {
  Rig rig;
  rig.start();
  CpgTestAccess::corrupt_phase(DriverControllerTestAccess::cpg(*rig.ctl), 0);
  ASSERT_EQ(rig.command("sidewind"), "");
  rig.step();
  EXPECT_EQ(rig.ctl->state(), DriverState::kFault);
  EXPECT_TRUE(contains(rig.ctl->fault_reason(), "CPG state not finite")) << rig.ctl->fault_reason();
  EXPECT_EQ(goal_span(rig, 2, 20), 0);
  Cpg cpg(rig.model);
  const Eigen::VectorXd z = Eigen::VectorXd::Zero(11);
  Eigen::VectorXd bad = z;
  bad(2) = INFINITY;
  EXPECT_FALSE(cpg.restart(bad, z, z));
  EXPECT_FALSE(cpg.restart(Eigen::VectorXd::Zero(3), z, z));
  EXPECT_THROW(cpg.reset(bad, z, z), std::invalid_argument);
  EXPECT_TRUE(cpg.restart(z, z, z));
}

// Point 3 (driver part): the command lifetime. A repeat of the same command is a heartbeat: it
// keeps the gait running and does not perturb the CPG; without one the gait stops and holds, with
// the reason; the next command resumes.
TEST(DriverSafety, CommandLifetimeHoldsWithTheReasonAndTheNextCommandResumes) {
  DriverConfig cfg;
  cfg.command_timeout_s = 1.5;
  Rig beat(cfg);
  DriverConfig untimed;
  untimed.command_timeout_s = 0.0;
  Rig reference(untimed);
  for (Rig* r : {&beat, &reference}) {
    r->start();
    ASSERT_EQ(r->command("sidewind"), "");
  }
  for (int k = 0; k < 400; ++k) {  // 4 s, a heartbeat every 0.5 s
    if (k % 50 == 49) {
      ASSERT_EQ(beat.command("sidewind"), "");
    }
    beat.step();
    reference.step();
  }
  EXPECT_EQ(beat.ctl->state(), DriverState::kRunning);
  EXPECT_TRUE(beat.ctl->cpg().output().isApprox(reference.ctl->cpg().output(), 1e-12));
  EXPECT_TRUE(beat.ctl->cpg().phases().isApprox(reference.ctl->cpg().phases(), 1e-12));
  // No more commands: Running until command_timeout_s has passed, then Holding.
  beat.step(145);
  EXPECT_EQ(beat.ctl->state(), DriverState::kRunning);
  beat.step(10);
  EXPECT_EQ(beat.ctl->state(), DriverState::kHolding);
  EXPECT_EQ(beat.ctl->hold_reason(), HoldReason::kCommandTimeout);
  DriverSnapshot snap = beat.ctl->make_snapshot();
  beat.ctl->fill_snapshot(snap);
  EXPECT_EQ(snap.hold_reason, HoldReason::kCommandTimeout);
  EXPECT_GT(snap.command_age_s, 1.5);
  EXPECT_TRUE(contains(to_string(snap.hold_reason), "command_timeout_s"));
  EXPECT_EQ(goal_span(beat, 2, 100), 0);  // the posture is held
  // The untimed reference keeps running.
  reference.step(200);
  EXPECT_EQ(reference.ctl->state(), DriverState::kRunning);
  // The next command (the same one) resumes.
  ASSERT_EQ(beat.command("sidewind"), "");
  beat.heartbeat = Rig::named("sidewind");
  beat.step();
  EXPECT_EQ(beat.ctl->state(), DriverState::kRunning);
  EXPECT_EQ(beat.ctl->hold_reason(), HoldReason::kNone);
  EXPECT_GT(goal_span(beat, 2, 300), 300);
  EXPECT_EQ(beat.ctl->state(), DriverState::kRunning);
}

TEST(DriverSafety, CommandExpiryRule) {
  EXPECT_FALSE(command_expired(10.0, 8.0, 3.0));
  EXPECT_TRUE(command_expired(11.5, 8.0, 3.0));
  EXPECT_FALSE(command_expired(1e9, 0.0, 0.0));  // 0: no lifetime
}

// Point 5 (driver part): base poses within the workspace and unit quaternions within tolerance.
TEST(DriverSafety, AbsurdBasePosesAreRefusedWithTheReasonAndNeverReachTheKinematics) {
  Rig rig;
  rig.start();
  rig.step(5);
  const double t = rig.t;
  EXPECT_FALSE(rig.ctl->set_base_pose(t, Eigen::Vector3d(1.7e308, 0, 0), Eigen::Quaterniond::Identity()));
  rig.feed_pose = false;
  rig.step();
  EXPECT_TRUE(rig.ctl->kinematics().com.allFinite());
  EXPECT_LT(rig.ctl->kinematics().com.norm(), 10.0);
  DriverSnapshot snap = rig.ctl->make_snapshot();
  rig.ctl->fill_snapshot(snap);
  EXPECT_TRUE(contains(snap.pose_refusal.data(), "outside the workspace (pose_workspace_m) 1000 m"))
      << snap.pose_refusal.data();
  // (x, y, z, w) = (0, 0, 1e200, 1e200): its norm overflows; normalising gave a zero rotation.
  EXPECT_FALSE(rig.ctl->set_base_pose(t, Eigen::Vector3d(1, 2, 0), Eigen::Quaterniond(1e200, 0, 0, 1e200)));
  EXPECT_FALSE(rig.ctl->set_base_pose(t, Eigen::Vector3d(1, 2, 0), Eigen::Quaterniond(1.05, 0, 0, 0)));
  EXPECT_FALSE(rig.ctl->set_base_pose(t, Eigen::Vector3d(1, 2, 0), Eigen::Quaterniond(0, 0, 0, 0)));
  EXPECT_FALSE(rig.ctl->set_base_pose(t, Eigen::Vector3d(NAN, 2, 0), Eigen::Quaterniond::Identity()));
  rig.step();
  rig.ctl->fill_snapshot(snap);
  EXPECT_EQ(snap.poses_refused, 5u);
  EXPECT_TRUE(contains(snap.pose_refusal.data(), "not a finite number")) << snap.pose_refusal.data();
  // Within tolerance: accepted and normalised (a 90 deg yaw, norm 1.005).
  const double h = std::sqrt(0.5) * 1.005;
  EXPECT_TRUE(rig.ctl->set_base_pose(rig.t, Eigen::Vector3d(999, -999, 0.1), Eigen::Quaterniond(h, 0, 0, h)));
  rig.step();
  rig.ctl->fill_snapshot(snap);
  EXPECT_NEAR(snap.base_orientation.norm(), 1.0, 1e-12);
  EXPECT_NEAR(snap.base_orientation.z(), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(snap.base_position.x(), 999.0, 1e-12);
  EXPECT_TRUE(rig.ctl->kinematics().com.allFinite());
}

TEST(DriverSafety, QuaternionCheckNeverOverflows) {
  Eigen::Quaterniond unit;
  const Eigen::Vector3d p(1, 2, 3);
  EXPECT_EQ(check_base_pose(0, p, Eigen::Quaterniond(1e200, 1e200, 0, 0), 1000, 0.01, &unit),
            PoseRefusal::kQuaternionNotUnit);
  EXPECT_EQ(check_base_pose(0, p, Eigen::Quaterniond(1e-200, 0, 0, 0), 1000, 0.01, &unit),
            PoseRefusal::kQuaternionNotUnit);
  EXPECT_EQ(check_base_pose(INFINITY, p, Eigen::Quaterniond::Identity(), 1000, 0.01, &unit), PoseRefusal::kNotFinite);
  EXPECT_EQ(check_base_pose(0, Eigen::Vector3d(0, 0, -1000.5), Eigen::Quaterniond::Identity(), 1000, 0.01, &unit),
            PoseRefusal::kOutsideWorkspace);
  EXPECT_EQ(check_base_pose(0, p, Eigen::Quaterniond(0.999, 0, 0, 0), 1000, 0.01, &unit), PoseRefusal::kNone);
  EXPECT_DOUBLE_EQ(unit.w(), 1.0);
}

TEST(DriverSafety, ConfigurationOfTheRulesIsValidated) {
  DriverConfig c;
  c.command_timeout_s = -1.0;
  c.pose_workspace_m = 0.0;
  c.quaternion_norm_tolerance = NAN;
  std::string all;
  for (const auto& e : c.validate()) all += e + "\n";
  for (const char* key : {"command_timeout_s: -1", "pose_workspace_m: 0", "quaternion_norm_tolerance: nan"})
    EXPECT_TRUE(contains(all, key)) << all;
  c = DriverConfig{};
  c.command_timeout_s = 0.0;  // off: allowed
  EXPECT_TRUE(c.validate().empty());
}
