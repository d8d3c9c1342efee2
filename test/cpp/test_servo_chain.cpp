// ServoChain on FakeServoBus: start-up checks, the goal clamp (joint limits within the servo's
// limits), the health counters of read(), torque, hardware errors and reboot. The chain runs on the
// rig's bus and model without a DriverController.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "driver_rig.hpp"
#include "snake_autonomy/driver/servo_chain.hpp"

using snake_autonomy::driver::ChainStartReport;
using snake_autonomy::driver::Message;
using snake_autonomy::driver::ServoChain;
using snake_autonomy::test::kDeg;
using snake_autonomy::test::Rig;
namespace dx = snake_autonomy::dynamixel;
namespace core = snake_autonomy::core;
namespace driver = snake_autonomy::driver;

namespace {

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

std::string joined(const std::vector<std::string>& lines) {
  std::string all;
  for (const auto& l : lines) all += l + "\n";
  return all;
}

// Joint limits [-20, 25] deg on every joint; servo 4's own max_position_limit 2100 ticks.
Rig limited_rig() {
  return Rig(
      {},
      [](core::RobotModel& m) {
        for (int j = 0; j < m.num_joints; ++j) {
          m.joint_lower_rad[j] = -20 * kDeg;
          m.joint_upper_rad[j] = 25 * kDeg;
        }
      },
      [](dx::FakeServoBus& b) { b.servos().set(4, "max_position_limit", 2100); });
}

}  // namespace

TEST(ServoChain, GoalClampIsTheJointLimitsWithinTheServoLimits) {
  Rig rig = limited_rig();
  ServoChain chain(rig.model, rig.table, *rig.bus, driver::DriverConfig{});
  const ChainStartReport report = chain.start();
  ASSERT_TRUE(report.problems.empty()) << joined(report.problems);
  // The joint limits in ticks, rounded inwards (-227.6 and +284.4 ticks from the centre).
  const std::int64_t lo = 2048 - static_cast<std::int64_t>(std::floor(20.0 / 360 * 4096));
  const std::int64_t hi = 2048 + static_cast<std::int64_t>(std::floor(25.0 / 360 * 4096));
  Eigen::VectorXd goal = Eigen::VectorXd::Constant(11, 1.0);  // 57 deg: beyond every upper limit
  ASSERT_TRUE(chain.write(goal));
  for (int id = 1; id <= 11; ++id) EXPECT_EQ(rig.goal(id), id == 4 ? 2100 : hi) << id;
  // The caller's vector says what was commanded, in radians, inside the clamp.
  EXPECT_NEAR(goal[0], chain.upper_rad()[0], 1e-12);
  EXPECT_LE(goal[0], 25 * kDeg);
  EXPECT_NEAR(goal[3], (2100 - 2048) * 2 * M_PI / 4096, 1e-12);
  goal.setConstant(-1.0);
  ASSERT_TRUE(chain.write(goal));
  for (int id = 1; id <= 11; ++id) EXPECT_EQ(rig.goal(id), lo) << id;
  // A non-finite goal keeps the joint's previous goal; the others move.
  goal.setZero();
  goal[1] = std::nan("");
  ASSERT_TRUE(chain.write(goal));
  EXPECT_EQ(rig.goal(2), lo);
  EXPECT_EQ(rig.goal(1), 2048);
  EXPECT_EQ(rig.bus->servos().stats().rejected_writes, 0u);
}

TEST(ServoChain, StartNamesEveryServoThatIsNotUsable) {
  Rig rig({}, {}, [](dx::FakeServoBus& b) {
    b.servos().set_silent(5, true);
    b.servos().set(2, "operating_mode", 1);
  });
  ServoChain chain(rig.model, rig.table, *rig.bus, driver::DriverConfig{});
  const std::string problems = joined(chain.start().problems);
  EXPECT_TRUE(contains(problems, "servo 5 (joint_5): no answer to ping")) << problems;
  EXPECT_TRUE(contains(problems, "servo 2 (joint_2): operating_mode 1, the driver needs 3")) << problems;
  EXPECT_FALSE(contains(problems, "servo 3")) << problems;
}

TEST(ServoChain, ADroppedReplyMarksTheServoStaleAndKeepsItsLastGoodState) {
  Rig rig;
  ServoChain chain(rig.model, rig.table, *rig.bus, driver::DriverConfig{});
  ASSERT_TRUE(chain.start().problems.empty());
  rig.bus->set_follow_goal(false);
  rig.bus->servos().set(3, "present_position", 2048 + 200);
  ASSERT_TRUE(chain.read());
  const double before = chain.position_rad()[2];
  EXPECT_NEAR(before, 200 * 2 * M_PI / 4096, 1e-12);
  rig.bus->servos().inject(dx::ReplyFault::kDropReply, {3}, 2);
  rig.bus->servos().set(3, "present_position", 2048 + 500);
  EXPECT_FALSE(chain.read());
  EXPECT_FALSE(chain.read());
  EXPECT_TRUE(chain.servos()[2].stale);
  EXPECT_EQ(chain.servos()[2].consecutive_misses, 2u);
  EXPECT_EQ(chain.servos()[2].timeouts, 2u);
  EXPECT_FALSE(chain.servos()[1].stale);
  EXPECT_EQ(chain.position_rad()[2], before);  // the last good value
  Message m{};
  chain.describe_stale(m);
  EXPECT_TRUE(contains(m.data(), "servo 3 (joint_3) timeout for 2 cycles")) << m.data();
  EXPECT_TRUE(chain.read());
  EXPECT_FALSE(chain.servos()[2].stale);
  EXPECT_EQ(chain.servos()[2].consecutive_misses, 0u);
  EXPECT_NEAR(chain.position_rad()[2], 500 * 2 * M_PI / 4096, 1e-12);
}

TEST(ServoChain, CorruptAndImplausibleRepliesAreCountedAndNeverUsed) {
  Rig rig;
  ServoChain chain(rig.model, rig.table, *rig.bus, driver::DriverConfig{});
  ASSERT_TRUE(chain.start().problems.empty());
  ASSERT_TRUE(chain.read());
  const double before = chain.position_rad()[6];
  rig.bus->servos().inject(dx::ReplyFault::kGarbageData, {7}, 1);  // valid CRC, 0xA5 data
  EXPECT_FALSE(chain.read());
  EXPECT_EQ(chain.servos()[6].implausible, 1u);
  EXPECT_EQ(chain.position_rad()[6], before);
  rig.bus->servos().inject(dx::ReplyFault::kCorruptCrc, {7}, 1);
  EXPECT_FALSE(chain.read());
  EXPECT_EQ(chain.servos()[6].crc_errors, 1u);
  EXPECT_EQ(chain.position_rad()[6], before);
  EXPECT_TRUE(chain.read());
}

TEST(ServoChain, TorqueIsWrittenAndConfirmedServoByServo) {
  Rig rig;
  ServoChain chain(rig.model, rig.table, *rig.bus, driver::DriverConfig{});
  ASSERT_TRUE(chain.start().problems.empty());
  ASSERT_TRUE(chain.write_torque(true));
  for (int id = 1; id <= 11; ++id) EXPECT_EQ(rig.torque(id), 1) << id;
  Message why{};
  EXPECT_TRUE(chain.confirm_torque(true, why)) << why.data();
  rig.bus->servos().set(9, "torque_enable", 0);  // servo 9 dropped its torque by itself
  EXPECT_FALSE(chain.confirm_torque(true, why));
  EXPECT_TRUE(contains(why.data(), "servo 9 (joint_9) did not confirm torque on (torque_enable 0)")) << why.data();
  ASSERT_TRUE(chain.write_torque(false));
  for (int id = 1; id <= 11; ++id) EXPECT_EQ(rig.torque(id), 0) << id;
}

TEST(ServoChain, HardwareErrorBitsAreReadAndRebootClearsThem) {
  Rig rig;
  ServoChain chain(rig.model, rig.table, *rig.bus, driver::DriverConfig{});
  ASSERT_TRUE(chain.start().problems.empty());
  EXPECT_FALSE(chain.read_hardware_errors());
  rig.bus->servos().set_hardware_error(6, (1 << 5) | (1 << 2));  // overload, overheating
  chain.read();  // the alert bit in servo 6's reply
  EXPECT_TRUE(chain.servos()[5].hardware_error);
  EXPECT_TRUE(chain.read_hardware_errors());
  EXPECT_EQ(chain.servos()[5].hardware_error_bits, (1 << 5) | (1 << 2));
  Message m{};
  chain.describe_hardware_errors(m);
  EXPECT_TRUE(contains(m.data(), "servo 6 (joint_6): overheating, overload;")) << m.data();
  EXPECT_EQ(chain.reboot(6), dx::Status::kHardwareError);  // the reply still carries the alert bit
  EXPECT_FALSE(chain.servos()[5].hardware_error);
  EXPECT_EQ(chain.servos()[5].hardware_error_bits, 0);
  chain.read();
  EXPECT_FALSE(chain.read_hardware_errors());
  EXPECT_EQ(chain.joint_of(6), 5);
  EXPECT_EQ(chain.joint_of(42), -1);
}

TEST(ServoChain, StartSetsTheReturnDelayTimeAndReportsIt) {
  driver::DriverConfig cfg;
  cfg.return_delay_time_us = 100;
  Rig rig;
  ServoChain chain(rig.model, rig.table, *rig.bus, cfg);
  const ChainStartReport report = chain.start();
  ASSERT_TRUE(report.problems.empty()) << joined(report.problems);
  EXPECT_EQ(rig.bus->servos().get(1, "return_delay_time"), 50);
  EXPECT_TRUE(contains(joined(report.notes), "servo 1 (joint_1): Return Delay Time")) << joined(report.notes);
  EXPECT_NEAR(rig.bus->return_delay_s(), 100e-6, 1e-12);
}
