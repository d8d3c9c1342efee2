// DriverSupervisor on a ServoChain on FakeServoBus, with a scripted JointCommandSource (any source
// plugs in): the fault rules, the request mailbox, which source is active, and the one slew limit
// and clamp applied after whichever source is active.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "driver_rig.hpp"
#include "snake_autonomy/driver/servo_chain.hpp"
#include "snake_autonomy/driver/supervisor.hpp"

using snake_autonomy::driver::DriverConfig;
using snake_autonomy::driver::DriverRequest;
using snake_autonomy::driver::DriverState;
using snake_autonomy::driver::DriverSupervisor;
using snake_autonomy::driver::HoldReason;
using snake_autonomy::driver::JointCommandSource;
using snake_autonomy::driver::JointStateView;
using snake_autonomy::driver::RequestResult;
using snake_autonomy::driver::SafeAction;
using snake_autonomy::driver::ServoChain;
using snake_autonomy::driver::SourceStatus;
using snake_autonomy::driver::StopCause;
using snake_autonomy::test::kDt;
using snake_autonomy::test::Rig;

namespace {

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// Proposes `target` every cycle and returns `next` (then keeps returning it).
struct ScriptedSource : JointCommandSource {
  Eigen::VectorXd target;
  SourceStatus next;
  Eigen::VectorXd activated_at;
  std::string deactivated;  // to_string(StopCause) of the last deactivate()
  int updates = 0;
  bool activate(double, const JointStateView&, const Eigen::VectorXd& posture, const char**) noexcept override {
    activated_at = posture;
    return true;
  }
  SourceStatus update(double, double, const JointStateView&, Eigen::Ref<Eigen::VectorXd> goal) noexcept override {
    ++updates;
    goal = target;
    return next;
  }
  void deactivate(StopCause cause) noexcept override { deactivated = to_string(cause); }
};

// A chain + supervisor on the rig's bus (the rig's own controller is not started).
struct Stack {
  Rig rig;
  ServoChain chain;
  DriverSupervisor sup;
  double t = 0.0;
  explicit Stack(const DriverConfig& cfg = {}) : rig(cfg), chain(rig.model, rig.table, *rig.bus, cfg), sup(chain, cfg) {
    const auto report = chain.start();
    EXPECT_TRUE(report.problems.empty());
    sup.begin(report);
  }
  // One loop cycle as DriverController runs it; returns the cycle's success.
  bool cycle() {
    t += kDt;
    sup.take_request();
    const bool read_ok = chain.read();
    sup.check_hardware_errors();
    const bool write_ok = sup.drive(t, kDt, true);
    return sup.count_cycle(read_ok, write_ok);
  }
  RequestResult request(DriverRequest r, std::uint8_t id = 0) {
    const auto ticket = sup.post(r, id);
    cycle();
    RequestResult out;
    EXPECT_TRUE(sup.take_result(ticket, &out));
    return out;
  }
  bool command(JointCommandSource& s) {
    bool was_active = false;
    return sup.command(s, t, true, &was_active);
  }
};

ScriptedSource source_towards(double rad) {
  ScriptedSource s;
  s.target = Eigen::VectorXd::Constant(11, rad);
  return s;
}

}  // namespace

TEST(DriverSupervisor, StartHoldsThenASourceRunsThroughOneSlewLimitAndTheClamp) {
  DriverConfig cfg;
  cfg.max_joint_velocity_rad_s = 2.0;
  Stack s(cfg);
  ASSERT_EQ(s.sup.state(), DriverState::kHolding);
  EXPECT_EQ(s.sup.hold_reason(), HoldReason::kTorqueEnabled);
  ScriptedSource src = source_towards(10.0);  // far beyond the joint limits
  ASSERT_TRUE(s.command(src));
  EXPECT_EQ(s.sup.state(), DriverState::kRunning);
  EXPECT_EQ(s.sup.active(), &src);
  EXPECT_TRUE(src.activated_at.isApprox(s.chain.position_rad(), 1e-12));
  const double before = s.sup.goal_rad()[0];
  ASSERT_TRUE(s.cycle());
  EXPECT_NEAR(s.sup.goal_rad()[0] - before, 2.0 * kDt, 1e-12);  // the slew limit
  for (int k = 0; k < 200; ++k) s.cycle();
  for (int j = 0; j < 11; ++j) EXPECT_DOUBLE_EQ(s.sup.goal_rad()[j], s.chain.upper_rad()[j]) << j;  // the clamp
  // A non-finite goal from the source never becomes a command.
  src.target[4] = std::nan("");
  s.cycle();
  EXPECT_DOUBLE_EQ(s.sup.goal_rad()[4], s.chain.upper_rad()[4]);
}

TEST(DriverSupervisor, FaultAfterMaxFailedCyclesNamesTheServoAndHolds) {
  DriverConfig cfg;
  cfg.max_failed_cycles = 4;
  Stack s(cfg);
  ScriptedSource src = source_towards(0.1);
  ASSERT_TRUE(s.command(src));
  s.rig.bus->servos().set_silent(7, true);
  for (int k = 0; k < 3; ++k) EXPECT_FALSE(s.cycle());
  EXPECT_EQ(s.sup.state(), DriverState::kRunning);
  EXPECT_EQ(s.sup.consecutive_failed_cycles(), 3u);
  EXPECT_FALSE(s.cycle());
  ASSERT_EQ(s.sup.state(), DriverState::kFault);
  const std::string why = s.sup.fault_reason().data();
  EXPECT_TRUE(contains(why, "4 consecutive cycles with missing replies: servo 7 (joint_7) timeout for 4 cycles"))
      << why;
  EXPECT_EQ(src.deactivated, "fault");  // the source was taken off
  EXPECT_EQ(s.sup.active(), nullptr);
  // fault action hold: the others keep torque and their goals stay put.
  const auto goal = s.rig.goal(2);
  s.cycle();
  EXPECT_EQ(s.rig.goal(2), goal);
  EXPECT_EQ(s.rig.torque(2), 1);
  // Commands are refused with the reason while in the fault.
  EXPECT_STRNE(s.sup.command_refusal(), "");
  EXPECT_FALSE(s.command(src));
}

TEST(DriverSupervisor, FaultActionTorqueOffRepeatsTorqueOff) {
  DriverConfig cfg;
  cfg.fault_action = SafeAction::kTorqueOff;
  Stack s(cfg);
  s.rig.bus->servos().set_hardware_error(3, 1 << 2);
  s.cycle();
  ASSERT_EQ(s.sup.state(), DriverState::kFault);
  EXPECT_TRUE(contains(s.sup.fault_reason().data(), "servo 3 (joint_3): overheating")) << s.sup.fault_reason().data();
  s.rig.bus->servos().set(5, "torque_enable", 1);  // a servo that comes back must not keep torque
  s.cycle();
  EXPECT_EQ(s.rig.torque(5), 0);
}

TEST(DriverSupervisor, MailboxCarriesTheResultOfAReboot) {
  Stack s;
  s.rig.bus->servos().set_hardware_error(6, 1 << 5);
  s.cycle();
  ASSERT_EQ(s.sup.state(), DriverState::kFault);
  RequestResult r = s.request(DriverRequest::kRebootServo, 99);
  EXPECT_FALSE(r.success);
  EXPECT_EQ(r.message, "no servo with ID 99 on this bus");
  r = s.request(DriverRequest::kEnableTorque);
  EXPECT_FALSE(r.success);
  EXPECT_TRUE(contains(r.message, "servo 6 (joint_6) has a hardware error (overload): reboot it first")) << r.message;
  r = s.request(DriverRequest::kRebootServo, 6);
  EXPECT_TRUE(r.success) << r.message;
  EXPECT_EQ(r.message, "servo 6 (joint_6) rebooted (torque off): enable torque to resume");
  EXPECT_EQ(s.rig.bus->servos().stats().reboot, 1u);
  r = s.request(DriverRequest::kEnableTorque);
  EXPECT_TRUE(r.success) << r.message;
  EXPECT_EQ(s.sup.state(), DriverState::kHolding);
  EXPECT_EQ(s.sup.fault_reason()[0], '\0');
  EXPECT_TRUE(contains(s.sup.last_fault().data(), "overload"));
  // A result is taken once per ticket: an old ticket does not match the latest result.
  RequestResult old;
  EXPECT_FALSE(s.sup.take_result(1, &old));
}

TEST(DriverSupervisor, HoldRequestAndAnotherSourceTakeTheActiveSourceOff) {
  Stack s;
  ScriptedSource a = source_towards(0.2), b = source_towards(-0.2);
  ASSERT_TRUE(s.command(a));
  s.cycle();
  // Another source's command: a is taken off, b starts from where the goals are.
  const Eigen::VectorXd goals = s.sup.goal_rad();
  ASSERT_TRUE(s.command(b));
  EXPECT_EQ(s.sup.active(), &b);
  EXPECT_EQ(a.deactivated, "another command source took over");
  EXPECT_TRUE(b.activated_at.isApprox(goals, 1e-12));
  // A repeated command for the active source keeps it (the caller applies it).
  bool was_active = false;
  EXPECT_TRUE(s.sup.command(b, s.t, true, &was_active));
  EXPECT_TRUE(was_active);
  // A hold request ends it.
  const RequestResult r = s.request(DriverRequest::kHold);
  EXPECT_TRUE(r.success) << r.message;
  EXPECT_EQ(s.sup.state(), DriverState::kHolding);
  EXPECT_EQ(s.sup.hold_reason(), HoldReason::kHoldRequest);
  EXPECT_EQ(s.sup.active(), nullptr);
  EXPECT_EQ(b.deactivated, "hold request");
  const int updates = b.updates;
  s.cycle();
  EXPECT_EQ(b.updates, updates);  // a source taken off is never updated
}

TEST(DriverSupervisor, ASourceThatFinishesHoldsAndOneThatFaultsFaults) {
  Stack s;
  ScriptedSource done = source_towards(0.0);
  done.next.code = SourceStatus::kHold;
  done.next.hold_reason = HoldReason::kCommandTimeout;
  ASSERT_TRUE(s.command(done));
  s.cycle();
  EXPECT_EQ(s.sup.state(), DriverState::kHolding);
  EXPECT_EQ(s.sup.hold_reason(), HoldReason::kCommandTimeout);
  EXPECT_TRUE(done.deactivated.empty());  // it finished by itself
  ScriptedSource broken = source_towards(0.0);
  broken.next.code = SourceStatus::kFault;
  broken.next.reason = "the source's state is not finite";
  ASSERT_TRUE(s.command(broken));
  s.cycle();
  EXPECT_EQ(s.sup.state(), DriverState::kFault);
  EXPECT_STREQ(s.sup.fault_reason().data(), "the source's state is not finite");
}

TEST(DriverSupervisor, ASourceEndingAtItsLastGoalIsHeldThereNotWhereTheRobotIs) {
  DriverConfig cfg;
  cfg.max_joint_velocity_rad_s = 1.0;
  Stack s(cfg);
  s.rig.bus->set_follow_goal(false);  // the shafts stay at the centre: measured posture zero
  ScriptedSource last = source_towards(0.3);
  last.next.code = SourceStatus::kHold;
  last.next.hold_reason = HoldReason::kNone;
  last.next.hold_at_goal = true;
  ASSERT_TRUE(s.command(last));
  s.cycle();
  EXPECT_EQ(s.sup.state(), DriverState::kHolding);
  for (int k = 0; k < 100; ++k) s.cycle();  // 1 s at 1 rad/s: the goals reach the last point
  for (int j = 0; j < 11; ++j) EXPECT_NEAR(s.sup.goal_rad()[j], 0.3, 1e-12) << j;
  EXPECT_LT(s.chain.position_rad().cwiseAbs().maxCoeff(), 1e-9);
}

TEST(DriverSupervisor, DisableTorqueStopsAndRefusesCommands) {
  Stack s;
  ScriptedSource src = source_towards(0.1);
  ASSERT_TRUE(s.command(src));
  const RequestResult r = s.request(DriverRequest::kDisableTorque);
  EXPECT_TRUE(r.success) << r.message;
  EXPECT_EQ(s.sup.state(), DriverState::kStopped);
  for (int id = 1; id <= 11; ++id) EXPECT_EQ(s.rig.torque(id), 0) << id;
  EXPECT_TRUE(contains(s.sup.command_refusal(), "torque is off"));
  EXPECT_FALSE(s.command(src));
}
