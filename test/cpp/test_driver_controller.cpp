// DriverController on FakeServoBus: the loop's contract (start-up, limits, gait commands, stale pose,
// the bus's packets) and that update() never allocates. Faults, requests and shutdown:
// test_driver_faults.cpp.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <functional>
#include <memory>
#include <new>
#include <thread>

#include "driver_rig.hpp"
#include "snake_autonomy/driver/driver_controller.hpp"

using namespace snake_autonomy::core;
using namespace snake_autonomy::driver;
using snake_autonomy::dynamixel::FakeServoBus;
namespace dx = snake_autonomy::dynamixel;
using snake_autonomy::test::kDeg;
using snake_autonomy::test::kDt;
using snake_autonomy::test::Rig;

// ---- allocation counter: counts operator new calls while g_count_allocations is set ----
namespace {
std::atomic<bool> g_count_allocations{false};
std::atomic<long> g_allocations{0};
}  // namespace
// GCC cannot tell that these free() calls pair with the malloc() in operator new below.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t size) {
  if (g_count_allocations.load(std::memory_order_relaxed)) {
    g_allocations.fetch_add(1, std::memory_order_relaxed);
    if (std::getenv("SNAKE_ABORT_ON_ALLOCATION")) std::abort();  // run under gdb to see where
  }
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

TEST(DriverConfig, ValidateCollectsEveryProblem) {
  DriverConfig c;
  c.max_failed_cycles = 0;
  c.pose_timeout_s = -1.0;
  c.max_step_s = 0.0;
  c.max_joint_velocity_rad_s = std::nan("");
  const auto errors = c.validate();
  ASSERT_EQ(errors.size(), 4u);
  EXPECT_NE(errors[0].find("max_failed_cycles: 0"), std::string::npos) << errors[0];
  std::string all;
  for (const auto& e : errors) all += e + "\n";
  for (const char* key : {"pose_timeout_s: -1", "max_step_s: 0", "max_joint_velocity_rad_s: nan"})
    EXPECT_NE(all.find(key), std::string::npos) << all;
  EXPECT_TRUE(DriverConfig{}.validate().empty());
  try {
    Rig rig(c);
    FAIL() << "an invalid configuration was accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("pose_timeout_s"), std::string::npos) << e.what();
  }
  SafeAction a;
  EXPECT_TRUE(parse_safe_action("torque_off", &a));
  EXPECT_EQ(a, SafeAction::kTorqueOff);
  EXPECT_FALSE(parse_safe_action("limp", &a));
}

TEST(DriverController, StartEnablesTorqueAndHoldsThePresentPosture) {
  Rig rig({}, {}, [](FakeServoBus& b) { b.servos().set(3, "present_position", 2048 + 300); });
  rig.start();
  EXPECT_EQ(rig.ctl->state(), DriverState::kHolding);
  for (int id = 1; id <= 11; ++id) EXPECT_EQ(rig.torque(id), 1) << id;
  EXPECT_EQ(rig.goal(3), 2048 + 300);  // no jump at torque-on
  rig.step(20);
  EXPECT_EQ(rig.goal(3), 2048 + 300);
  EXPECT_NEAR(rig.ctl->position_rad()[2], 300 * 2 * M_PI / 4096, 1e-12);
  EXPECT_EQ(rig.bus->servos().stats().rejected_writes, 0u);
}

TEST(DriverController, StartNamesEveryServoThatIsNotUsable) {
  Rig rig({}, {}, [](FakeServoBus& b) {
    b.servos().set_silent(5, true);
    b.servos().set(3, "operating_mode", 1);
  });
  try {
    rig.start();
    FAIL() << "started with a dead servo";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("servo 5 (joint_5): no answer"), std::string::npos) << what;
    EXPECT_NE(what.find("servo 3 (joint_3): operating_mode 1"), std::string::npos) << what;
  }
  EXPECT_FALSE(rig.ctl->update(0.01, 0.01));  // not started: nothing happens
}

TEST(DriverController, StartWritesTheReturnDelayTimeAndTheBusAllowsForTheSlowestServo) {
  // Factory servos answer after 500 us (250 units): the driver writes 0 while torque is off.
  Rig rig;
  ASSERT_EQ(rig.bus->servos().get(4, "return_delay_time"), 250);
  rig.start();
  for (int id = 1; id <= 11; ++id)
    EXPECT_EQ(rig.bus->servos().get(static_cast<std::uint8_t>(id), "return_delay_time"), 0) << id;
  EXPECT_EQ(rig.bus->return_delay_s(), 0.0);
  ASSERT_EQ(rig.ctl->start_notes().size(), 11u);
  EXPECT_NE(rig.ctl->start_notes()[0].find("servo 1 (joint_1): Return Delay Time 500 us -> 0 us"), std::string::npos)
      << rig.ctl->start_notes()[0];
  EXPECT_EQ(rig.ctl->state(), DriverState::kHolding);

  // A servo whose torque is already on keeps its EEPROM locked: the driver carries on, says so,
  // and the reply deadlines allow for its 500 us.
  Rig locked({}, {}, [](FakeServoBus& b) {
    for (int id = 1; id <= 11; ++id) b.servos().set(static_cast<std::uint8_t>(id), "return_delay_time", 0);
    b.servos().set(7, "return_delay_time", 250);
    b.servos().set(7, "torque_enable", 1);
  });
  locked.start();
  EXPECT_EQ(locked.bus->servos().get(7, "return_delay_time"), 250);
  EXPECT_DOUBLE_EQ(locked.bus->return_delay_s(), 500e-6);
  ASSERT_EQ(locked.ctl->start_notes().size(), 1u);
  EXPECT_NE(locked.ctl->start_notes()[0].find("servo 7 (joint_7): Return Delay Time is 500 us"), std::string::npos)
      << locked.ctl->start_notes()[0];
  EXPECT_NE(locked.ctl->start_notes()[0].find("torque is on"), std::string::npos) << locked.ctl->start_notes()[0];
  EXPECT_EQ(locked.ctl->state(), DriverState::kHolding);

  // -1 leaves the servos as found.
  DriverConfig leave;
  leave.return_delay_time_us = -1;
  Rig as_found(leave);
  as_found.start();
  EXPECT_EQ(as_found.bus->servos().get(2, "return_delay_time"), 250);
  EXPECT_DOUBLE_EQ(as_found.bus->return_delay_s(), 500e-6);
  EXPECT_TRUE(as_found.ctl->start_notes().empty());

  DriverConfig odd;
  odd.return_delay_time_us = 7;
  const auto errors = odd.validate();
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("return_delay_time_us: 7"), std::string::npos) << errors[0];
}

TEST(DriverController, DirectionAndZeroOffsetMapJointsToTicks) {
  Rig rig({}, [](RobotModel& m) {
    m.servos.directions[0] = -1;
    m.servos.zero_offsets_ticks[0] = 100;
  });
  std::int32_t ticks = 0;
  ASSERT_TRUE(rig.ctl->joint_rad_to_ticks(0, 90 * kDeg, &ticks));
  EXPECT_EQ(ticks, 2048 + 100 - 1024);
  EXPECT_NEAR(rig.ctl->ticks_to_joint_rad(0, 2048 + 100 - 1024), 90 * kDeg, 1e-12);
  EXPECT_NEAR(rig.ctl->ticks_to_joint_rad(0, 2048 + 100), 0.0, 1e-12);
  EXPECT_FALSE(rig.ctl->joint_rad_to_ticks(0, std::nan(""), &ticks));
  // Limits are mirrored: joint [-90, 90] deg = ticks [2148 - 1024, 2148 + 1024].
  EXPECT_EQ(rig.ctl->servos()[0].min_ticks, 2148 - 1024);
  EXPECT_EQ(rig.ctl->servos()[0].max_ticks, 2148 + 1024);
}

TEST(DriverController, GaitCommandDrivesTheGoalsThroughTheCpg) {
  Rig rig;
  rig.start();
  EXPECT_EQ(rig.command("sidewind"), "");
  rig.heartbeat = Rig::named("sidewind");
  rig.step(300);
  EXPECT_EQ(rig.ctl->state(), DriverState::kRunning);
  EXPECT_FALSE(rig.ctl->locomotion_gated());
  // The CPG output reaches the bus: goals follow the CPG within the slew limit, and they move.
  std::int64_t lo = 1 << 30, hi = -(1 << 30);
  for (int k = 0; k < 150; ++k) {
    rig.step();
    const auto& q = rig.ctl->cpg().output();
    for (int j = 0; j < 11; ++j) EXPECT_NEAR(rig.ctl->goal_rad()[j], q[j], 1e-9) << j;
    lo = std::min(lo, rig.goal(2));
    hi = std::max(hi, rig.goal(2));
  }
  EXPECT_GT(hi - lo, 600);  // yaw joint 2 swings about ±45 deg (±512 ticks)
  EXPECT_EQ(rig.bus->servos().goal_writes(2),
            rig.bus->servos().stats().sync_write - 1);  // every cycle wrote (all but the torque-on write)
  DriverSnapshot snap = rig.ctl->make_snapshot();
  rig.ctl->fill_snapshot(snap);
  EXPECT_STREQ(snap.gait.data(), "sidewind");
  EXPECT_EQ(snap.commands_applied, 5u);  // the command and 4 heartbeats
  EXPECT_TRUE(snap.pose_fresh);
  // Kinematics ran from the base pose.
  EXPECT_NEAR(rig.ctl->kinematics().link_positions[0].x(), 1.0, 1e-12);
  EXPECT_GT(snap.bbox_span.norm(), 0.1);
}

TEST(DriverController, GoalsNeverLeaveTheJointOrServoLimits) {
  Rig rig(
      {},
      [](RobotModel& m) {
        for (int j = 0; j < m.num_joints; ++j) {
          m.joint_lower_rad[j] = -20 * kDeg;
          m.joint_upper_rad[j] = 25 * kDeg;
        }
      },
      [](FakeServoBus& b) { b.servos().set(4, "max_position_limit", 2100); });
  rig.start();
  GaitCommandRequest c;
  c.gait = "sidewind";
  c.amplitude.assign(11, 0.3);  // amplitude + bias beyond the upper limit (25 deg) half of the time
  c.bias.assign(11, 0.43);
  ASSERT_EQ(rig.ctl->command_gait(c), "");
  rig.heartbeat = c;
  const std::int64_t lo = 2048 - std::lround(20.0 / 360 * 4096), hi = 2048 + std::lround(25.0 / 360 * 4096);
  for (int k = 0; k < 600; ++k) {
    rig.step();
    for (int id = 1; id <= 11; ++id) {
      ASSERT_GE(rig.goal(id), lo) << id;
      ASSERT_LE(rig.goal(id), id == 4 ? 2100 : hi) << id;
    }
  }
  EXPECT_EQ(rig.goal(4), 2100);  // pushed against the servo's own limit
  EXPECT_EQ(rig.bus->servos().stats().rejected_writes, 0u);
}

TEST(DriverController, GoalsAreSlewLimited) {
  DriverConfig cfg;
  cfg.max_joint_velocity_rad_s = 1.0;
  Rig rig(cfg);
  rig.start();
  GaitCommandRequest c;
  c.gait = "hold";
  c.bias.assign(11, 0.0);
  c.bias[0] = 60 * kDeg;
  ASSERT_EQ(rig.ctl->command_gait(c), "");
  double prev = 0.0;
  for (int k = 0; k < 200; ++k) {
    rig.step();
    const double g = rig.ctl->goal_rad()[0];
    ASSERT_LE(std::abs(g - prev), 1.0 * kDt + 1e-12);
    prev = g;
  }
  EXPECT_GT(prev, 30 * kDeg);
}

TEST(DriverController, RefusedCommandLeavesTheRunningGaitUntouched) {
  Rig rig;
  rig.start();
  ASSERT_EQ(rig.command("sidewind"), "");
  rig.step(50);
  const GaitParameters before = rig.ctl->cpg().targets();
  GaitCommandRequest c;
  c.gait = "moonwalk";
  c.amplitude.assign(5, 0.1);
  c.omega.assign(11, 1.0);
  c.omega[3] = std::nan("");
  c.bias.assign(11, 0.0);
  c.bias[7] = INFINITY;
  const std::string why = rig.ctl->command_gait(c);
  for (const char* part :
       {"unknown gait 'moonwalk'", "amplitude: 5 values", "omega[3] (joint_4): nan", "bias[7] (joint_8): inf"})
    EXPECT_NE(why.find(part), std::string::npos) << part << " in:\n" << why;
  GaitCommandRequest fast;
  fast.omega.assign(11, 2 * M_PI * 5.0);
  EXPECT_NE(rig.ctl->command_gait(fast).find("(max_frequency_hz 2)"), std::string::npos);
  GaitCommandRequest steer_turn;
  steer_turn.gait = "turn_left";
  steer_turn.steer = true;
  steer_turn.delta_rad = 0.1;
  EXPECT_NE(rig.ctl->command_gait(steer_turn).find("not steerable"), std::string::npos);
  rig.step(10);
  const GaitParameters& after = rig.ctl->cpg().targets();
  EXPECT_TRUE(after.amplitude.isApprox(before.amplitude));
  EXPECT_TRUE(after.omega.isApprox(before.omega));
  EXPECT_TRUE(after.bias.isApprox(before.bias));
  EXPECT_EQ(rig.ctl->commanded_gait(), "sidewind");
  EXPECT_EQ(rig.ctl->commands_refused(), 3u);
  EXPECT_EQ(rig.ctl->state(), DriverState::kRunning);
}

TEST(DriverController, SteeringModulatesTheYawAmplitudesOfOneCommand) {
  Rig rig;
  rig.start();
  GaitCommandRequest c;
  c.gait = "sidewind";
  c.steer = true;
  c.delta_rad = 5 * kDeg;
  ASSERT_EQ(rig.ctl->command_gait(c), "");
  rig.step();
  const auto& a = rig.ctl->cpg().targets().amplitude;
  EXPECT_NEAR(a[1], (45 + 2 * 5) * kDeg, 1e-9);  // first yaw joint, weight 2
  EXPECT_NEAR(a[9], (45 - 2 * 5) * kDeg, 1e-9);  // last yaw joint, weight -2
  EXPECT_NEAR(a[0], 15 * kDeg, 1e-9);            // pitch untouched
  GaitCommandRequest plain;  // no gait name, no steer: the nominal sidewind again
  ASSERT_EQ(rig.ctl->command_gait(plain), "");
  rig.step();
  EXPECT_NEAR(rig.ctl->cpg().targets().amplitude[1], 45 * kDeg, 1e-9);
}

TEST(DriverController, StalePoseHoldsLocomotionAndFreshPosesResumeIt) {
  Rig rig;
  rig.feed_pose = false;
  rig.start();
  ASSERT_EQ(rig.command("sidewind"), "");
  rig.heartbeat = Rig::named("sidewind");  // the mission keeps commanding while the pose is stale
  rig.step(5);
  // No pose yet: identity for the kinematics, locomotion held.
  EXPECT_TRUE(rig.ctl->locomotion_gated());
  EXPECT_EQ(rig.ctl->cpg().targets().amplitude.norm(), 0.0);
  EXPECT_NEAR(rig.ctl->kinematics().link_positions[0].norm(), 0.0, 1e-12);
  rig.feed_pose = true;
  rig.step(200);
  EXPECT_FALSE(rig.ctl->locomotion_gated());
  EXPECT_NEAR(rig.ctl->cpg().targets().amplitude[1], 45 * kDeg, 1e-9);
  EXPECT_GT(rig.ctl->cpg().amplitudes()[1], 20 * kDeg);
  // Poses stop: after pose_timeout_s (0.5 s) the waves decay and stay down.
  rig.feed_pose = false;
  rig.step(45);
  EXPECT_FALSE(rig.ctl->locomotion_gated());
  rig.step(10);
  EXPECT_TRUE(rig.ctl->locomotion_gated());
  EXPECT_FALSE(rig.ctl->pose_fresh());
  rig.step(400);
  EXPECT_LT(rig.ctl->cpg().amplitudes().cwiseAbs().maxCoeff(), 0.5 * kDeg);
  EXPECT_EQ(rig.ctl->state(), DriverState::kRunning);
  // Fresh poses: the commanded gait comes back.
  rig.feed_pose = true;
  rig.step(100);
  EXPECT_FALSE(rig.ctl->locomotion_gated());
  EXPECT_GT(rig.ctl->cpg().amplitudes()[1], 10 * kDeg);
  // A non-finite pose is refused and does not count as fresh.
  EXPECT_FALSE(rig.ctl->set_base_pose(rig.t, Eigen::Vector3d(NAN, 0, 0), Eigen::Quaterniond::Identity()));
  EXPECT_FALSE(rig.ctl->set_base_pose(rig.t, Eigen::Vector3d::Zero(), Eigen::Quaterniond(0, 0, 0, 0)));
}

TEST(DriverController, PoseNotRequiredRunsWithoutOne) {
  DriverConfig cfg;
  cfg.require_pose = false;
  Rig rig(cfg);
  rig.feed_pose = false;
  rig.start();
  ASSERT_EQ(rig.command("sidewind"), "");
  rig.step(100);
  EXPECT_FALSE(rig.ctl->locomotion_gated());
  EXPECT_GT(rig.ctl->cpg().amplitudes()[1], 20 * kDeg);
}

TEST(DriverController, FastSyncReadWorksAndLosesTheCycleOnACorruptSharedPacket) {
  DriverConfig cfg;
  cfg.fast_sync_read = true;
  Rig rig(cfg);
  rig.start();
  ASSERT_EQ(rig.command("sidewind"), "");
  EXPECT_TRUE(rig.step(50));
  rig.bus->servos().inject(dx::ReplyFault::kCorruptCrc, {7}, 1);
  EXPECT_FALSE(rig.step());
  for (const auto& d : rig.ctl->servos()) EXPECT_TRUE(d.stale);
  EXPECT_TRUE(rig.step());
}

TEST(DriverController, StatusReadFillsVoltageAndTemperature) {
  DriverConfig cfg;
  cfg.status_every_cycles = 5;
  Rig rig(cfg);
  rig.start();
  EXPECT_TRUE(std::isnan(rig.ctl->servos()[0].temperature_c));
  rig.bus->servos().set(9, "present_temperature", 61);
  rig.step(5);
  EXPECT_DOUBLE_EQ(rig.ctl->servos()[8].temperature_c, 61.0);
  EXPECT_NEAR(rig.ctl->servos()[8].voltage_v, 12.0, 1e-9);
}

TEST(DriverController, UpdateNeverAllocates) {
  Rig rig;
  rig.start();
  ASSERT_EQ(rig.command("sidewind"), "");
  rig.step(2);
  DriverSnapshot snap = rig.ctl->make_snapshot();
  const std::vector<std::uint8_t> servo_3{3};  // the test's own allocation, before counting
  g_allocations = 0;
  g_count_allocations = true;
  rig.step(100);                   // running, poses fed
  rig.bus->servos().inject(dx::ReplyFault::kCorruptCrc, servo_3, 2);  // failed cycles
  rig.feed_pose = false;
  rig.step(100);                   // the pose goes stale: gating
  rig.bus->servos().set_silent(4, true);
  rig.step(15);                    // fault: message formatting, hold
  rig.ctl->fill_snapshot(snap);
  g_count_allocations = false;
  EXPECT_EQ(rig.ctl->state(), DriverState::kFault);
  EXPECT_EQ(g_allocations.load(), 0);
  // The command lifetime expiring, and refused base poses (their reason formatted).
  DriverConfig cfg;
  cfg.command_timeout_s = 0.5;
  Rig timed(cfg);
  timed.start();
  ASSERT_EQ(timed.command("sidewind"), "");
  timed.step(2);
  g_count_allocations = true;
  timed.step(60);
  timed.ctl->set_base_pose(timed.t, Eigen::Vector3d(1e300, 0, 0), Eigen::Quaterniond::Identity());
  timed.ctl->set_base_pose(timed.t, Eigen::Vector3d::Zero(), Eigen::Quaterniond(1e200, 0, 0, 1e200));
  timed.step(2);
  timed.ctl->fill_snapshot(snap);
  g_count_allocations = false;
  EXPECT_EQ(timed.ctl->state(), DriverState::kHolding);
  EXPECT_EQ(g_allocations.load(), 0);
}

TEST(DriverController, UpdateNeverAllocatesWhileATrajectoryRuns) {
  // Handover (swap of the reserved buffers), the take-time check, interpolation, the end, aborts.
  Rig rig;
  rig.start();
  namespace drv = snake_autonomy::driver;
  auto request = [](double angle_rad, double t_s) {
    drv::JointTrajectoryRequest r;
    r.id = "alloc";
    for (int j = 0; j < 11; ++j) r.joint_names.push_back("joint_" + std::to_string(j + 1));
    for (int k = 1; k <= 50; ++k) {
      drv::JointTrajectoryPoint p;
      p.time_from_start_s = t_s * k / 50;
      p.positions_rad.assign(11, angle_rad * k / 50);
      r.points.push_back(p);
    }
    return r;
  };
  const auto slow = request(30 * kDeg, 1.0);
  auto other = request(-10 * kDeg, 2.0);  // from where slow ends: 30 deg down to 20 deg
  for (auto& p : other.points) p.positions_rad.assign(11, 30 * kDeg + p.positions_rad[0]);
  auto fast = request(-80 * kDeg, 0.1);  // one point 0.1 s away: too fast from the present posture
  fast.points.erase(fast.points.begin(), fast.points.end() - 1);
  ASSERT_EQ(rig.ctl->command_trajectory(slow), "");
  DriverSnapshot snap = rig.ctl->make_snapshot();
  g_allocations = 0;
  g_count_allocations = true;
  rig.step(150);  // taken, run through, done: holding the last point
  rig.ctl->fill_snapshot(snap);
  g_count_allocations = false;
  EXPECT_EQ(snap.trajectory.phase, snake_autonomy::driver::TrajectoryPhase::kDone);
  EXPECT_EQ(g_allocations.load(), 0);
  ASSERT_EQ(rig.ctl->command_trajectory(fast), "");  // refused at take: the reason is formatted
  g_count_allocations = true;
  rig.step(2);
  g_count_allocations = false;
  EXPECT_EQ(rig.ctl->trajectory_progress().abort, snake_autonomy::driver::TrajectoryAbort::kFirstSegmentTooFast);
  ASSERT_EQ(rig.ctl->command_trajectory(other), "");
  g_count_allocations = true;
  rig.step(20);  // taken, running
  const auto ticket = rig.ctl->post(DriverRequest::kHold, 0);
  rig.step(5);   // ended by the hold request
  g_count_allocations = false;
  RequestResult result;
  EXPECT_TRUE(rig.ctl->take_result(ticket, &result));
  EXPECT_EQ(rig.ctl->trajectory_progress().abort, snake_autonomy::driver::TrajectoryAbort::kHoldRequest);
  EXPECT_EQ(g_allocations.load(), 0);
}

TEST(DriverController, OtherThreadsNeverBlockTheLoop) {
  Rig rig;
  rig.start();
  std::atomic<bool> run{true};
  std::atomic<long> cycles{0};
  std::thread loop([&] {
    double t = 0.0;
    while (run) {
      t += 0.001;
      rig.ctl->set_base_pose(t, Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity());
      rig.ctl->update(t, 0.001);
      ++cycles;
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  });
  for (int k = 0; k < 20; ++k) {
    EXPECT_EQ(rig.command(k % 2 ? "sidewind" : "turn_left"), "");
    const RequestResult r = rig.ctl->call(k % 2 ? DriverRequest::kHold : DriverRequest::kEnableTorque, 0, 2.0);
    EXPECT_TRUE(r.success) << r.message;
  }
  run = false;
  loop.join();
  EXPECT_GT(cycles.load(), 20);
}
