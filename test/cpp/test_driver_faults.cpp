// DriverController on FakeServoBus when things go wrong: CRC errors, a dead servo, a hardware error, the bus
// down or replying garbage stop locomotion by the configured fault action; hold, torque and reboot requests;
// the state left at shutdown.
#include <gtest/gtest.h>

#include "driver_rig.hpp"
#include "snake_autonomy/driver/driver_controller.hpp"

using namespace snake_autonomy::core;
using namespace snake_autonomy::driver;
using snake_autonomy::dynamixel::FakeServoBus;
namespace dx = snake_autonomy::dynamixel;
using snake_autonomy::test::kDeg;
using snake_autonomy::test::kDt;
using snake_autonomy::test::Rig;

TEST(DriverController, CrcErrorsAreCountedAndTheLastGoodStateKept) {
  Rig rig;
  rig.start();
  rig.bus->set_follow_goal(false);
  rig.bus->servos().set(4, "present_position", 2048 + 100);
  rig.step();
  EXPECT_NEAR(rig.ctl->position_rad()[3], 100 * 2 * M_PI / 4096, 1e-12);
  rig.bus->servos().inject(dx::ReplyFault::kCorruptCrc, {4}, 3);
  rig.bus->servos().set(4, "present_position", 2048 + 400);
  EXPECT_FALSE(rig.step());
  EXPECT_TRUE(rig.ctl->servos()[3].stale);
  EXPECT_NEAR(rig.ctl->position_rad()[3], 100 * 2 * M_PI / 4096, 1e-12);  // last good value
  rig.step(2);
  EXPECT_TRUE(rig.step());
  EXPECT_FALSE(rig.ctl->servos()[3].stale);
  EXPECT_NEAR(rig.ctl->position_rad()[3], 400 * 2 * M_PI / 4096, 1e-12);
  EXPECT_EQ(rig.ctl->servos()[3].crc_errors, 3u);
  EXPECT_EQ(rig.ctl->state(), DriverState::kHolding);  // 3 < max_failed_cycles
  DriverSnapshot snap = rig.ctl->make_snapshot();
  rig.ctl->fill_snapshot(snap);
  EXPECT_EQ(snap.bus.crc_errors, 3u);
  EXPECT_EQ(snap.failed_cycles, 3u);
}

TEST(DriverController, DeadServoStopsLocomotionAfterNFailedCyclesAndHolds) {
  DriverConfig cfg;
  cfg.max_failed_cycles = 5;
  Rig rig(cfg);
  rig.start();
  ASSERT_EQ(rig.command("sidewind"), "");
  rig.step(200);
  rig.bus->servos().set_silent(5, true);
  rig.step(4);
  EXPECT_EQ(rig.ctl->state(), DriverState::kRunning);
  rig.step();
  ASSERT_EQ(rig.ctl->state(), DriverState::kFault);
  const std::string why = rig.ctl->fault_reason();
  EXPECT_NE(why.find("servo 5 (joint_5) timeout for 5 cycles"), std::string::npos) << why;
  // Hold: the goals stop at the position measured when the fault came; torque stays on.
  const std::int32_t measured = rig.ctl->servos()[2].present_ticks;
  rig.step();
  const std::int64_t g3 = rig.goal(3);
  EXPECT_EQ(g3, measured);
  rig.step(50);
  EXPECT_EQ(rig.goal(3), g3);
  EXPECT_EQ(rig.torque(3), 1);
  EXPECT_NE(rig.command("sidewind"), "");  // refused in a fault
  // Recovery: the servo answers again, enable torque checks everything and holds.
  rig.bus->servos().set_silent(5, false);
  const RequestResult r = rig.request(DriverRequest::kEnableTorque);
  EXPECT_TRUE(r.success) << r.message;
  EXPECT_EQ(rig.ctl->state(), DriverState::kHolding);
  EXPECT_EQ(rig.command("sidewind"), "");
  rig.step(20);
  EXPECT_EQ(rig.ctl->state(), DriverState::kRunning);
  EXPECT_EQ(rig.bus->servos().stats().rejected_writes, 0u);
}

TEST(DriverController, FaultActionTorqueOff) {
  DriverConfig cfg;
  cfg.max_failed_cycles = 3;
  cfg.fault_action = SafeAction::kTorqueOff;
  Rig rig(cfg);
  rig.start();
  ASSERT_EQ(rig.command("sidewind"), "");
  rig.step(50);
  rig.bus->servos().set_silent(2, true);
  rig.step(3);
  ASSERT_EQ(rig.ctl->state(), DriverState::kFault);
  for (int id = 1; id <= 11; ++id) {
    if (id != 2) {
      EXPECT_EQ(rig.torque(id), 0) << id;
    }
  }
}

TEST(DriverController, HardwareErrorStopsAtOnceAndRebootRecovers) {
  Rig rig;
  rig.start();
  ASSERT_EQ(rig.command("sidewind"), "");
  rig.step(100);
  rig.bus->servos().set_hardware_error(6, 1 << 5);  // overload
  rig.step();
  ASSERT_EQ(rig.ctl->state(), DriverState::kFault);
  const std::string why = rig.ctl->fault_reason();
  EXPECT_NE(why.find("servo 6 (joint_6): overload"), std::string::npos) << why;
  EXPECT_EQ(rig.ctl->servos()[5].hardware_error_bits, 1 << 5);
  EXPECT_EQ(rig.torque(7), 1);  // the others hold
  // Enabling torque is refused while the error is there; reboot is refused for an unknown ID.
  RequestResult r = rig.request(DriverRequest::kEnableTorque);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.message.find("servo 6 (joint_6) has a hardware error (overload): reboot it first"), std::string::npos)
      << r.message;
  r = rig.request(DriverRequest::kRebootServo, 42);
  EXPECT_FALSE(r.success);
  r = rig.request(DriverRequest::kRebootServo, 6);
  EXPECT_TRUE(r.success) << r.message;
  r = rig.request(DriverRequest::kEnableTorque);
  EXPECT_TRUE(r.success) << r.message;
  EXPECT_EQ(rig.ctl->state(), DriverState::kHolding);
  for (int id = 1; id <= 11; ++id) EXPECT_EQ(rig.torque(id), 1) << id;
  DriverSnapshot snap = rig.ctl->make_snapshot();
  rig.ctl->fill_snapshot(snap);
  EXPECT_EQ(snap.fault_reason[0], '\0');
  EXPECT_NE(std::string(snap.last_fault.data()).find("overload"), std::string::npos);
}

TEST(DriverController, BusDownAndGarbageRepliesStopLocomotion) {
  DriverConfig cfg;
  cfg.max_failed_cycles = 4;
  {
    Rig rig(cfg);
    rig.start();
    rig.bus->set_bus_down(true);
    rig.step(4);
    ASSERT_EQ(rig.ctl->state(), DriverState::kFault);
    EXPECT_NE(std::string(rig.ctl->fault_reason()).find("I/O error"), std::string::npos) << rig.ctl->fault_reason();
    // Recovery reopens the port through the hook.
    RequestResult r = rig.request(DriverRequest::kEnableTorque);
    EXPECT_FALSE(r.success);
    EXPECT_NE(r.message.find("I/O error"), std::string::npos) << r.message;
    int reopened = 0;
    rig.ctl->set_reconnect([&](std::string*) {
      ++reopened;
      rig.bus->set_bus_down(false);
      return true;
    });
    r = rig.request(DriverRequest::kEnableTorque);
    EXPECT_TRUE(r.success) << r.message;
    EXPECT_EQ(reopened, 1);
  }
  {
    Rig rig(cfg);
    rig.start();
    rig.bus->servos().inject(dx::ReplyFault::kGarbageData, {3}, -1);
    rig.step(4);
    ASSERT_EQ(rig.ctl->state(), DriverState::kFault);
    EXPECT_EQ(rig.ctl->servos()[2].implausible, 4u);
    EXPECT_NE(std::string(rig.ctl->fault_reason()).find("servo 3 (joint_3)"), std::string::npos);
  }
}

TEST(DriverController, HoldDisableEnableRequests) {
  Rig rig;
  rig.start();
  ASSERT_EQ(rig.command("sidewind"), "");
  rig.step(150);
  RequestResult r = rig.request(DriverRequest::kHold);
  EXPECT_TRUE(r.success) << r.message;
  EXPECT_EQ(rig.ctl->state(), DriverState::kHolding);
  const std::int64_t g = rig.goal(2);
  rig.step(30);
  EXPECT_EQ(rig.goal(2), g);
  r = rig.request(DriverRequest::kRebootServo, 2);
  EXPECT_FALSE(r.success);  // torque on
  r = rig.request(DriverRequest::kDisableTorque);
  EXPECT_TRUE(r.success);
  EXPECT_EQ(rig.ctl->state(), DriverState::kStopped);
  for (int id = 1; id <= 11; ++id) EXPECT_EQ(rig.torque(id), 0) << id;
  EXPECT_NE(rig.command("sidewind").find("torque is off"), std::string::npos);
  r = rig.request(DriverRequest::kHold);
  EXPECT_FALSE(r.success);
  // Someone bends joint 2 past its limit while limp: enabling torque is refused.
  rig.bus->servos().set(2, "present_position", 2048 + 1100);
  r = rig.request(DriverRequest::kEnableTorque);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.message.find("servo 2 (joint_2) at 96.7 deg is outside its limits"), std::string::npos) << r.message;
  rig.bus->servos().set(2, "present_position", 2048 + 1000);
  r = rig.request(DriverRequest::kEnableTorque);
  EXPECT_TRUE(r.success) << r.message;
  EXPECT_EQ(rig.goal(2), 2048 + 1000);
}

TEST(DriverController, ShutdownLeavesTheConfiguredState) {
  for (SafeAction action : {SafeAction::kHold, SafeAction::kTorqueOff}) {
    DriverConfig cfg;
    cfg.shutdown_action = action;
    Rig rig(cfg);
    rig.start();
    ASSERT_EQ(rig.command("sidewind"), "");
    rig.step(120);
    rig.bus->set_follow_goal(false);
    rig.bus->servos().set(1, "present_position", 2100);
    EXPECT_TRUE(rig.ctl->shutdown());
    if (action == SafeAction::kHold) {
      EXPECT_EQ(rig.torque(1), 1);
      EXPECT_EQ(rig.goal(1), 2100);  // frozen at the present position
    } else {
      for (int id = 1; id <= 11; ++id) EXPECT_EQ(rig.torque(id), 0) << id;
    }
  }
}
