// GaitSource on its own (no bus): the command handover, stale-pose gating, the command lifetime and
// the CPG-state check, each reported by status (never a throw). The joint state comes from the
// rig's model; the source is driven the way the supervisor drives it.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "driver_rig.hpp"
#include "snake_autonomy/driver/gait_source.hpp"
#include "test_access.hpp"

using snake_autonomy::core::CpgTestAccess;
using snake_autonomy::driver::DriverConfig;
using snake_autonomy::driver::GaitCommandRequest;
using snake_autonomy::driver::GaitSource;
using snake_autonomy::driver::GaitSourceTestAccess;
using snake_autonomy::driver::HoldReason;
using snake_autonomy::driver::JointStateView;
using snake_autonomy::driver::SourceStatus;
using snake_autonomy::test::kDeg;
using snake_autonomy::test::kDt;
using snake_autonomy::test::Rig;

namespace {

// The joint state the supervisor would pass, with a settable pose freshness.
struct State {
  Eigen::VectorXd position, velocity, goal, lower, upper;
  explicit State(const snake_autonomy::core::RobotModel& m)
      : position(Eigen::VectorXd::Zero(m.num_joints)),
        velocity(Eigen::VectorXd::Zero(m.num_joints)),
        goal(Eigen::VectorXd::Zero(m.num_joints)),
        lower(Eigen::VectorXd::Map(m.joint_lower_rad.data(), m.num_joints)),
        upper(Eigen::VectorXd::Map(m.joint_upper_rad.data(), m.num_joints)) {}
  JointStateView view(bool fresh) const { return {position, velocity, goal, lower, upper, fresh}; }
};

struct GaitRig {
  Rig rig;
  GaitSource gait;
  State state;
  Eigen::VectorXd goal;
  double t = 0.0;
  explicit GaitRig(const DriverConfig& cfg = {})
      : rig(cfg), gait(rig.model, rig.gaits, cfg), state(rig.model), goal(Eigen::VectorXd::Zero(rig.model.num_joints)) {
    gait.reset_clock(0.0);
  }
  std::string command(const std::string& name) {
    GaitCommandRequest c;
    c.gait = name;
    return gait.command(c, "");
  }
  SourceStatus run(int cycles, bool fresh) {
    SourceStatus st;
    for (int k = 0; k < cycles; ++k) {
      t += kDt;
      st = gait.update(t, kDt, state.view(fresh), goal);
      if (st.code != SourceStatus::kActive) break;
    }
    return st;
  }
  bool activate(bool fresh) {
    const char* why = "";
    return gait.activate(t, state.view(fresh), state.goal, &why);
  }
};

}  // namespace

TEST(GaitSource, ACommandIsHandedOverOnceAndRefusedWholeWhenBlocked) {
  GaitRig g;
  EXPECT_FALSE(g.gait.take_command(0.0));
  GaitCommandRequest c;
  c.gait = "sidewind";
  EXPECT_EQ(g.gait.command(c, "torque is off: enable it first"), "torque is off: enable it first");
  EXPECT_FALSE(g.gait.take_command(0.0));  // nothing handed over
  EXPECT_EQ(g.gait.commands_refused(), 1u);
  EXPECT_EQ(g.gait.commanded_gait(), "hold");
  c.gait = "no_such_gait";
  EXPECT_NE(g.gait.command(c, ""), "");
  EXPECT_EQ(g.gait.commands_refused(), 2u);
  EXPECT_EQ(g.command("sidewind"), "");
  EXPECT_EQ(g.gait.commanded_gait(), "sidewind");
  EXPECT_TRUE(g.gait.take_command(0.0));
  EXPECT_STREQ(g.gait.gait_name().data(), "sidewind");
  EXPECT_FALSE(g.gait.take_command(0.0));  // once
}

TEST(GaitSource, StalePoseGatesTheAmplitudesAndFreshPosesResumeTheGait) {
  GaitRig g;
  ASSERT_EQ(g.command("sidewind"), "");
  ASSERT_TRUE(g.gait.take_command(0.0));
  ASSERT_TRUE(g.activate(false));  // no fresh pose: gated from the start
  EXPECT_TRUE(g.gait.gated());
  EXPECT_EQ(g.run(200, false).code, SourceStatus::kActive);
  EXPECT_EQ(g.gait.cpg().targets().amplitude.norm(), 0.0);
  EXPECT_LT(g.goal.cwiseAbs().maxCoeff(), 1e-9);  // the posture (zero) is held
  g.gait.reset_clock(g.t);
  EXPECT_EQ(g.run(200, true).code, SourceStatus::kActive);
  EXPECT_FALSE(g.gait.gated());
  EXPECT_NEAR(g.gait.cpg().targets().amplitude[1], 45 * kDeg, 1e-9);
  EXPECT_GT(g.goal.cwiseAbs().maxCoeff(), 10 * kDeg);  // the waves run
  g.gait.reset_clock(g.t);
  EXPECT_EQ(g.run(1, false).code, SourceStatus::kActive);
  EXPECT_TRUE(g.gait.gated());
  EXPECT_EQ(g.gait.cpg().targets().amplitude.norm(), 0.0);
}

TEST(GaitSource, TheCommandLifetimeEndsTheGaitWithTheReason) {
  DriverConfig cfg;
  cfg.command_timeout_s = 1.0;
  GaitRig g(cfg);
  ASSERT_EQ(g.command("sidewind"), "");
  ASSERT_TRUE(g.gait.take_command(0.0));
  ASSERT_TRUE(g.activate(true));
  EXPECT_EQ(g.run(95, true).code, SourceStatus::kActive);
  // A repeated command is a heartbeat.
  ASSERT_EQ(g.command("sidewind"), "");
  ASSERT_TRUE(g.gait.take_command(g.t));
  EXPECT_EQ(g.run(95, true).code, SourceStatus::kActive);
  const SourceStatus st = g.run(10, true);
  EXPECT_EQ(st.code, SourceStatus::kHold);
  EXPECT_EQ(st.hold_reason, HoldReason::kCommandTimeout);
  EXPECT_GT(g.gait.command_age_s(g.t), 1.0);
}

TEST(GaitSource, ANonFiniteCpgStateIsAFaultByStatus) {
  GaitRig g;
  ASSERT_EQ(g.command("sidewind"), "");
  ASSERT_TRUE(g.gait.take_command(0.0));
  ASSERT_TRUE(g.activate(true));
  g.run(10, true);
  CpgTestAccess::corrupt_phase(GaitSourceTestAccess::cpg(g.gait), 2);
  const SourceStatus st = g.run(1, true);
  EXPECT_EQ(st.code, SourceStatus::kFault);
  EXPECT_NE(std::string(st.reason).find("CPG state not finite"), std::string::npos) << st.reason;
  // Restarting from a corrupt phase is refused with the reason instead of throwing.
  const char* why = "";
  EXPECT_FALSE(g.gait.activate(g.t, g.state.view(true), g.state.goal, &why));
  EXPECT_NE(std::string(why).find("cannot restart"), std::string::npos) << why;
}

TEST(GaitSource, ActivationStartsTheWavesFromTheHeldPosture) {
  GaitRig g;
  g.state.goal.setConstant(5 * kDeg);
  ASSERT_EQ(g.command("sidewind"), "");
  ASSERT_TRUE(g.gait.take_command(0.0));
  ASSERT_TRUE(g.activate(true));
  g.run(1, true);
  // One step after the restart the goals are still at the posture (amplitudes start at zero).
  EXPECT_LT((g.goal - g.state.goal).cwiseAbs().maxCoeff(), 1 * kDeg);
}
