// TrajectorySource (ROS-free) and trajectory execution through DriverController on FakeServoBus:
// interpolation through every point, the velocity checks, every refusal reason, the present
// posture as the first knot, the hold at the end, and every way a running trajectory ends.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <string>
#include <thread>
#include <vector>

#include "driver_rig.hpp"
#include "snake_autonomy/driver/trajectory_source.hpp"

using namespace snake_autonomy::driver;
using snake_autonomy::driver::DriverConfig;
using snake_autonomy::driver::DriverRequest;
using snake_autonomy::driver::DriverSnapshot;
using snake_autonomy::driver::DriverState;
using snake_autonomy::driver::HoldReason;
using snake_autonomy::dynamixel::ReplyFault;
using snake_autonomy::test::kDeg;
using snake_autonomy::test::kDt;
using snake_autonomy::test::Rig;

namespace {

constexpr double kVmax = 4.5;

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TrajectoryLimits limits(int n, int max_points = 100) {
  TrajectoryLimits l;
  l.lower_rad = Eigen::VectorXd::Constant(n, -1.5);
  l.upper_rad = Eigen::VectorXd::Constant(n, 1.5);
  l.limit_tolerance_rad = 1e-3;
  l.max_velocity_rad_s = kVmax;
  l.max_points = max_points;
  return l;
}

std::vector<std::string> names(int n) {
  std::vector<std::string> out;
  for (int j = 0; j < n; ++j) out.push_back("joint_" + std::to_string(j + 1));
  return out;
}

// A trajectory of `n` joints: point k at times[k], joint j at positions[k] * (j + 1) / n.
JointTrajectoryRequest ramp(int n, const std::vector<double>& times, const std::vector<double>& positions,
                            const std::string& id = "ramp") {
  JointTrajectoryRequest r;
  r.id = id;
  r.joint_names = names(n);
  for (std::size_t k = 0; k < times.size(); ++k) {
    JointTrajectoryPoint p;
    p.time_from_start_s = times[k];
    for (int j = 0; j < n; ++j) p.positions_rad.push_back(positions[k] * (j + 1) / n);
    r.points.push_back(p);
  }
  return r;
}

}  // namespace

TEST(TrajectorySource, PassesThroughEveryPointAtItsTime) {
  const int n = 3;
  TrajectorySource src(n, limits(n));
  const std::vector<double> times{0.5, 0.75, 1.0, 1.625, 2.0};  // exact in binary: t0 + t - t0 == t
  const std::vector<double> q{0.3, 0.5, 0.4, -0.2, 0.1};
  for (bool with_velocities : {false, true}) {
    JointTrajectoryRequest r = ramp(n, times, q);
    if (with_velocities) {
      for (auto& p : r.points) p.velocities_rad_s.assign(n, 0.1);
    }
    ASSERT_EQ(src.submit(r), "");
    const Eigen::VectorXd present = Eigen::VectorXd::Constant(n, 0.1);
    const double t0 = 10.0;
    ASSERT_TRUE(src.take(t0, present));
    ASSERT_TRUE(src.running());
    Eigen::VectorXd goal = Eigen::VectorXd::Zero(n);
    ASSERT_TRUE(src.update(t0, goal));
    EXPECT_LT((goal - present).norm(), 1e-12) << "the first knot is the present posture";
    for (std::size_t k = 0; k < times.size(); ++k) {
      src.update(t0 + times[k], goal);
      for (int j = 0; j < n; ++j) EXPECT_NEAR(goal[j], q[k] * (j + 1) / n, 1e-12) << "point " << k << " joint " << j;
      EXPECT_EQ(src.progress().point_reached, static_cast<int>(k));
    }
    EXPECT_EQ(src.progress().phase, TrajectoryPhase::kDone);
  }
}

TEST(TrajectorySource, VelocitiesAreTheRequestsOrShapePreservingEstimates) {
  const int n = 1;
  TrajectorySource src(n, limits(n));
  // Given velocities: the slope at a point is the request's.
  JointTrajectoryRequest r = ramp(n, {1.0, 2.0, 3.0}, {0.0, 0.5, 0.5});
  for (auto& p : r.points) p.velocities_rad_s = {0.0};
  r.points[1].velocities_rad_s = {0.7};
  ASSERT_EQ(src.submit(r), "");
  ASSERT_TRUE(src.take(0.0, Eigen::VectorXd::Zero(1)));
  Eigen::VectorXd a(1), b(1);
  src.update(2.0 - 1e-6, a);
  src.update(2.0 + 1e-6, b);
  EXPECT_NEAR((b[0] - a[0]) / 2e-6, 0.7, 1e-4);
  // Estimated: monotone data are never overshot, a local extremum gets slope 0, the end is at rest.
  r = ramp(n, {0.5, 1.0, 1.2, 2.0, 2.5}, {0.2, 0.9, 1.0, 1.0, 0.4});
  ASSERT_EQ(src.submit(r), "");
  ASSERT_TRUE(src.take(0.0, Eigen::VectorXd::Zero(1)));
  const std::vector<double> knots_t{0.0, 0.5, 1.0, 1.2, 2.0, 2.5}, knots_q{0.0, 0.2, 0.9, 1.0, 1.0, 0.4};
  Eigen::VectorXd g(1);
  for (double t = 0.0; t <= 2.5; t += 0.001) {
    src.update(t, g);
    std::size_t k = 1;
    while (k + 1 < knots_t.size() && t > knots_t[k]) ++k;
    const double lo = std::min(knots_q[k - 1], knots_q[k]), hi = std::max(knots_q[k - 1], knots_q[k]);
    ASSERT_GE(g[0], lo - 1e-12) << "t " << t;
    ASSERT_LE(g[0], hi + 1e-12) << "t " << t;
  }
  src.update(2.5 - 1e-6, a);
  EXPECT_NEAR(a[0], 0.4, 1e-5) << "at rest at the end";
}

TEST(TrajectorySource, VelocityCheckCatchesATooFastSegment) {
  const int n = 2;
  TrajectorySource src(n, limits(n));
  // Rest to rest (velocities 0 given) over 0.1 s: the peak is 1.5 |dq| / h: 0.3 rad is exactly 4.5 rad/s.
  auto pair = [&](double dq) {
    JointTrajectoryRequest r = ramp(n, {1.0, 1.1}, {0.0, dq});
    for (auto& p : r.points) p.velocities_rad_s.assign(n, 0.0);
    return r;
  };
  EXPECT_EQ(src.check(pair(0.3)), "");
  const std::string why = src.check(pair(0.31));
  EXPECT_TRUE(contains(why, "points[0] -> points[1]")) << why;
  EXPECT_TRUE(contains(why, "joint_2 needs 4.65 rad/s")) << why;
  EXPECT_FALSE(contains(why, "joint_1")) << "joint_1 moves 0.155 rad: " << why;
  // A given velocity over the limit shows as the segment's peak.
  JointTrajectoryRequest r = pair(0.0);
  r.points[1].velocities_rad_s = {5.0, 0.0};
  EXPECT_TRUE(contains(src.check(r), "joint_1 needs 5 rad/s")) << src.check(r);
}

TEST(TrajectorySource, RefusesWholeWithEveryReason) {
  const int n = 3;
  TrajectorySource src(n, limits(n, 4));
  JointTrajectoryRequest r = ramp(n, {0.0, 1.0, 0.5}, {0.1, 0.2, 0.3});
  r.joint_names = {"joint_2", "joint_9", "joint_2"};
  r.points[0].positions_rad[1] = std::nan("");
  r.points[1].positions_rad[0] = 1.6;
  r.points[1].velocities_rad_s = {0.0, INFINITY, 0.0};
  r.points[2].positions_rad.pop_back();
  r.points[2].velocities_rad_s = {0.0};
  const std::string why = src.check(r);
  for (const char* part :
       {"joint_names[1]: 'joint_9' is not a joint of this robot", "joint_names[2]: 'joint_2' repeats joint_names[0]",
        "joint_names: joint_1 is missing", "joint_names: joint_3 is missing",
        "points[0].positions[1] (joint_9): nan is not finite", "points[1].velocities[1] (joint_9): inf is not finite",
        "points[1].positions[0] (joint_2): 1.6 rad outside the joint limits [-1.5, 1.5]",
        "points[0].time_from_start: 0 s, must be > 0", "points[2].time_from_start: 0.5 s, not after points[1] at 1 s",
        "points[2].positions: 2 values for 3 joint names", "points[2].velocities: 1 values for 3 joint names"})
    EXPECT_TRUE(contains(why, part)) << part << "\nin:\n" << why;
  EXPECT_NE(src.submit(r), "");
  EXPECT_FALSE(src.take(0.0, Eigen::VectorXd::Zero(n))) << "nothing was handed over";
  // Too many points; none at all.
  r = ramp(n, {1, 2, 3, 4, 5}, {0, 0, 0, 0, 0});
  EXPECT_TRUE(contains(src.check(r), "points: 5 points, more than max_trajectory_points 4")) << src.check(r);
  r.points.clear();
  EXPECT_TRUE(contains(src.check(r), "points: empty")) << src.check(r);
  // Within the tolerance of a limit: accepted; names in any order map to their joints.
  r = ramp(n, {1.0}, {0.0});
  r.joint_names = {"joint_3", "joint_1", "joint_2"};
  r.points[0].positions_rad = {1.5005, -0.2, 0.3};
  ASSERT_EQ(src.submit(r), "");
  ASSERT_TRUE(src.take(0.0, Eigen::VectorXd::Zero(n)));
  EXPECT_EQ(src.final_rad(), Eigen::Vector3d(-0.2, 0.3, 1.5005));
}

TEST(TrajectorySource, RefusesATrajectoryLongerThanTheMaximumDuration) {
  // A point at 2^31 s would "run" for 68 years: the duration is bounded (max_duration_s, 600 s by default).
  const int n = 2;
  TrajectorySource src(n, limits(n));
  const JointTrajectoryRequest r = ramp(n, {1.0, 2147483648.0}, {0.1, 0.2});
  const std::string why = src.submit(r);
  EXPECT_TRUE(contains(why,
                       "points[1].time_from_start: 2.14748e+09 s, the trajectory would last longer than "
                       "max_trajectory_duration_s 600 s"))
      << why;
  EXPECT_FALSE(src.take(0.0, Eigen::VectorXd::Zero(n))) << "nothing was handed over";
  // At the bound it is accepted.
  EXPECT_EQ(src.submit(ramp(n, {1.0, 600.0}, {0.1, 0.2})), "");
}

// Every final status queued so far.
std::vector<TrajectoryProgress> finals(TrajectorySource& src) {
  std::vector<TrajectoryProgress> out;
  TrajectoryProgress p;
  while (src.pop_final(&p)) out.push_back(p);
  return out;
}

TEST(TrajectorySource, EveryAcceptedTrajectoryEndsWithExactlyOneFinalStatus) {
  const int n = 2;
  TrajectorySource src(n, limits(n));
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd goal = zero;
  ASSERT_EQ(src.submit(ramp(n, {0.5, 1.0}, {0.1, 0.2}, "a")), "");
  ASSERT_TRUE(src.take(0.0, zero));
  EXPECT_TRUE(finals(src).empty()) << "a runs: no final status yet";
  ASSERT_TRUE(src.update(0.2, goal));
  // b is accepted, then c replaces it before the loop takes it; then c replaces the running a.
  ASSERT_EQ(src.submit(ramp(n, {0.5, 1.0}, {0.1, 0.2}, "b")), "");
  ASSERT_EQ(src.submit(ramp(n, {0.5, 1.0}, {0.1, 0.2}, "c")), "");
  ASSERT_TRUE(src.take(0.3, goal));
  std::vector<TrajectoryProgress> f = finals(src);
  ASSERT_EQ(f.size(), 2u);
  // The loop's first (a), then the one replaced before it started (b).
  EXPECT_STREQ(f[0].id.data(), "a");
  EXPECT_EQ(f[0].sequence, 1u);
  EXPECT_EQ(f[0].phase, TrajectoryPhase::kAborted);
  EXPECT_EQ(f[0].abort, TrajectoryAbort::kSuperseded);
  EXPECT_STREQ(f[0].superseded_by.data(), "c");
  EXPECT_EQ(f[0].superseded_by_sequence, 3u);
  EXPECT_TRUE(contains(f[0].reason.data(), "superseded by 'c' (sequence 3) at 0.200 s of 1.000 s"))
      << f[0].reason.data();
  EXPECT_STREQ(f[1].id.data(), "b");
  EXPECT_EQ(f[1].sequence, 2u);
  EXPECT_EQ(f[1].abort, TrajectoryAbort::kSuperseded);
  EXPECT_STREQ(f[1].superseded_by.data(), "c");
  EXPECT_EQ(f[1].point_reached, -1);
  EXPECT_TRUE(contains(f[1].reason.data(), "before it started")) << f[1].reason.data();
  // c runs to its end: done, once; later cycles and aborts add nothing.
  EXPECT_EQ(src.progress().sequence, 3u);
  EXPECT_TRUE(src.running());
  while (src.update(0.3 + 1.5, goal)) {
  }
  src.abort(TrajectoryAbort::kFault);
  EXPECT_FALSE(src.update(5.0, goal));
  f = finals(src);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_STREQ(f[0].id.data(), "c");
  EXPECT_EQ(f[0].phase, TrajectoryPhase::kDone);
  EXPECT_EQ(f[0].superseded_by[0], '\0');
  // Ended at take (torque off then): its final status says so.
  ASSERT_EQ(src.submit(ramp(n, {0.5, 1.0}, {0.1, 0.2}, "d")), "");
  ASSERT_TRUE(src.take(6.0, goal, false));
  f = finals(src);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].abort, TrajectoryAbort::kNotAllowed);
  EXPECT_EQ(src.finals_dropped(), 0u);
}

// Back to back from another thread, as the driver's callback thread submits while the loop takes and
// updates and the publisher thread pops: whatever the interleaving, every accepted trajectory gets
// exactly one final status and none is dropped. The submitter's pauses make all three ends happen:
// done before the next arrives, superseded while running, superseded before the loop took it (several
// submits between two takes). It keeps at most 32 statuses outstanding (each queue holds kFinalQueue =
// 64), as a publisher thread keeping up would.
TEST(TrajectorySource, BackToBackFromAnotherThreadEachEndExactlyOnce) {
  const int n = 2, total = 1000;
  TrajectorySource src(n, limits(n));
  std::atomic<int> popped{0};
  std::atomic<bool> looping{true}, consuming{true};
  std::vector<int> ends(total + 1, 0);  // per sequence: final statuses seen (consumer thread only)
  int done = 0, superseded_running = 0, superseded_pending = 0;  // consumer thread only
  std::thread loop([&] {
    Eigen::VectorXd goal = Eigen::VectorXd::Zero(n);
    double t_s = 0.0;
    while (looping.load()) {
      t_s += 0.01;  // 50 cycles a trajectory
      src.take(t_s, goal);
      src.update(t_s, goal);
      std::this_thread::sleep_for(std::chrono::microseconds(20));
    }
  });
  std::thread consumer([&] {
    TrajectoryProgress p;
    for (;;) {
      const bool last = !consuming.load();  // read first: set once the loop has stopped
      while (src.pop_final(&p)) {
        if (p.sequence >= 1 && p.sequence <= static_cast<std::uint64_t>(total)) ++ends[p.sequence];
        if (p.phase == TrajectoryPhase::kDone) ++done;
        else if (contains(p.reason.data(), "before it started")) ++superseded_pending;
        else if (p.abort == TrajectoryAbort::kSuperseded) ++superseded_running;
        ++popped;
      }
      if (last) return;
      std::this_thread::sleep_for(std::chrono::microseconds(50));
    }
  });
  // A lost status would stall the waits below: they give up after 30 s and the checks say which.
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  const auto waiting = [&] { return std::chrono::steady_clock::now() < give_up; };
  int accepted = 0;
  for (int k = 0; k < total; ++k) {
    while (k - popped.load() > 32 && waiting()) std::this_thread::yield();
    accepted += src.submit(ramp(n, {0.2, 0.5}, {0.01, 0.02}, "b2b-" + std::to_string(k))).empty();
    if (k % 10 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(10));  // runs to its end
    else if (k % 10 < 5) std::this_thread::sleep_for(std::chrono::milliseconds(1));  // taken, then replaced
  }
  // The last one is taken and runs to its end (done) within 0.5 s of loop time.
  while (popped.load() < total && waiting()) std::this_thread::yield();
  looping = false;
  loop.join();
  consuming = false;
  consumer.join();
  ASSERT_EQ(accepted, total);
  int once = 0;
  for (int s = 1; s <= total; ++s) {
    EXPECT_EQ(ends[s], 1) << "sequence " << s;
    once += ends[s] == 1;
  }
  EXPECT_EQ(once, total);
  EXPECT_EQ(popped.load(), total) << "no final status for a sequence that was never accepted";
  EXPECT_EQ(src.finals_dropped(), 0u);
  EXPECT_EQ(done + superseded_running + superseded_pending, total);
  EXPECT_GT(done, 0);
  EXPECT_GT(superseded_running, 0);
  EXPECT_GT(superseded_pending, 0);
}

TEST(TrajectorySource, AFullFinalStatusQueueCountsWhatItDrops) {
  const int n = 1;
  TrajectorySource src(n, limits(n));
  const int extra = 5;  // replaced before they started: one final status each, none popped
  for (int k = 0; k < static_cast<int>(TrajectorySource::kFinalQueue) + extra + 1; ++k)
    ASSERT_EQ(src.submit(ramp(n, {0.5}, {0.1}, "t" + std::to_string(k))), "");
  EXPECT_EQ(src.finals_dropped(), static_cast<std::uint64_t>(extra));
  EXPECT_EQ(finals(src).size(), TrajectorySource::kFinalQueue);
}

TEST(TrajectorySource, FirstSegmentFromThePresentPostureIsCheckedAtTake) {
  const int n = 2;
  TrajectorySource src(n, limits(n));
  const JointTrajectoryRequest r = ramp(n, {0.2, 0.4}, {0.5, 0.5});  // joint_2: 0.5 rad in 0.2 s
  ASSERT_EQ(src.submit(r), "");
  // From rest at 0.5 rad (joint_2): 0 rad/s needed; from -0.5 rad: 1.5 x 1 / 0.2 = 7.5 rad/s.
  ASSERT_TRUE(src.take(1.0, Eigen::Vector2d(0.25, -0.5)));
  EXPECT_FALSE(src.running());
  EXPECT_EQ(src.progress().phase, TrajectoryPhase::kAborted);
  EXPECT_EQ(src.progress().abort, TrajectoryAbort::kFirstSegmentTooFast);
  EXPECT_TRUE(contains(src.progress().reason.data(), "present posture -> points[0]")) << src.progress().reason.data();
  EXPECT_TRUE(contains(src.progress().reason.data(), "joint_2 needs 7.5 rad/s")) << src.progress().reason.data();
  Eigen::VectorXd goal = Eigen::Vector2d(0.25, -0.5);
  EXPECT_FALSE(src.update(1.1, goal));
  EXPECT_EQ(goal, Eigen::Vector2d(0.25, -0.5)) << "the goals are left as they were";
  // The same request from near its first point runs.
  ASSERT_EQ(src.submit(r), "");
  ASSERT_TRUE(src.take(1.0, Eigen::Vector2d(0.25, 0.4)));
  EXPECT_TRUE(src.running());
  EXPECT_EQ(src.progress().sequence, 2u);
}

TEST(TrajectorySource, HoldsTheLastPointAndReportsDone) {
  const int n = 2;
  TrajectorySource src(n, limits(n));
  ASSERT_EQ(src.submit(ramp(n, {0.5, 1.0}, {0.2, 0.4}, "lift")), "");
  ASSERT_TRUE(src.take(3.0, Eigen::VectorXd::Zero(n)));
  Eigen::VectorXd goal = Eigen::VectorXd::Zero(n);
  EXPECT_TRUE(src.update(3.7, goal));
  EXPECT_EQ(src.progress().point_reached, 0);
  EXPECT_NEAR(src.progress().time_s, 0.7, 1e-12);
  EXPECT_FALSE(src.update(4.2, goal));
  EXPECT_EQ(goal, Eigen::Vector2d(0.2, 0.4));
  const TrajectoryProgress& p = src.progress();
  EXPECT_EQ(p.phase, TrajectoryPhase::kDone);
  EXPECT_EQ(p.abort, TrajectoryAbort::kNone);
  EXPECT_EQ(p.point_reached, 1);
  EXPECT_EQ(p.num_points, 2);
  EXPECT_DOUBLE_EQ(p.time_s, 1.0);
  EXPECT_STREQ(p.id.data(), "lift");
  EXPECT_FALSE(src.update(5.0, goal));
  EXPECT_EQ(src.final_rad(), Eigen::Vector2d(0.2, 0.4));
}

// ---------------------------------------------------------------------------------------------
// Through the controller (COBRA on FakeServoBus; the fake's servos follow their goals)

namespace {

JointTrajectoryRequest cobra_pose(double angle_rad, double duration_s, const std::string& id = "pose") {
  JointTrajectoryRequest r = ramp(11, {duration_s / 2, duration_s}, {angle_rad / 2, angle_rad}, id);
  return r;
}

// Steps until the trajectory is no longer running, at most max_cycles.
void run_out(Rig& rig, int max_cycles) {
  for (int k = 0; k < max_cycles; ++k) {
    rig.step();
    if (rig.ctl->trajectory_progress().phase != TrajectoryPhase::kRunning) return;
  }
}

}  // namespace

TEST(DriverTrajectory, ReachesItsLastPointThenHoldsIt) {
  DriverConfig cfg;
  cfg.command_timeout_s = 0.5;  // shorter than the trajectory: it must not end it
  Rig rig(cfg);
  rig.start();
  ASSERT_EQ(rig.ctl->state(), DriverState::kHolding);
  ASSERT_EQ(rig.ctl->command_trajectory(cobra_pose(40 * kDeg, 2.0, "up")), "");
  rig.step();
  EXPECT_EQ(rig.ctl->state(), DriverState::kRunning);
  EXPECT_EQ(rig.ctl->trajectory_progress().phase, TrajectoryPhase::kRunning);
  run_out(rig, 300);
  const auto& p = rig.ctl->trajectory_progress();
  EXPECT_EQ(p.phase, TrajectoryPhase::kDone);
  EXPECT_EQ(p.point_reached, 1);
  EXPECT_EQ(rig.ctl->state(), DriverState::kHolding);
  EXPECT_EQ(rig.ctl->hold_reason(), HoldReason::kTrajectoryDone);
  rig.step(20);
  for (int j = 0; j < 11; ++j) {
    // One tick (0.088 deg) of rounding between the goal and the servo.
    EXPECT_NEAR(rig.ctl->position_rad()[j], 40 * kDeg * (j + 1) / 11, 0.1 * kDeg) << "joint " << j;
  }
  DriverSnapshot snap = rig.ctl->make_snapshot();
  rig.ctl->fill_snapshot(snap);
  EXPECT_EQ(snap.trajectory.phase, TrajectoryPhase::kDone);
  EXPECT_STREQ(snap.trajectory.id.data(), "up");
  EXPECT_EQ(snap.hold_reason, HoldReason::kTrajectoryDone);
  EXPECT_EQ(rig.ctl->trajectories_accepted(), 1u);
  // A gait command afterwards starts locomotion from the held point.
  ASSERT_EQ(rig.command("sidewind"), "");
  rig.step();
  EXPECT_EQ(rig.ctl->state(), DriverState::kRunning);
}

TEST(DriverTrajectory, RefusedWholeAndTheRobotLeftAsItWas) {
  Rig rig;
  rig.start();
  rig.step(5);
  const Eigen::VectorXd before = rig.ctl->goal_rad();
  JointTrajectoryRequest bad = cobra_pose(100 * kDeg, 2.0);  // joint_11 at 100 deg: beyond 90
  bad.points[1].time_from_start_s = 0.5;                      // before points[0] at 1 s
  const std::string why = rig.ctl->command_trajectory(bad);
  EXPECT_TRUE(contains(why, "points[1].positions[10] (joint_11): 1.74533 rad outside the joint limits")) << why;
  EXPECT_TRUE(contains(why, "points[1].time_from_start: 0.5 s, not after points[0]")) << why;
  EXPECT_EQ(rig.ctl->last_trajectory_refusal(), why);
  EXPECT_EQ(rig.ctl->trajectories_refused(), 1u);
  rig.step(50);
  EXPECT_EQ(rig.ctl->state(), DriverState::kHolding);
  EXPECT_EQ(rig.ctl->goal_rad(), before);
  EXPECT_EQ(rig.ctl->trajectory_progress().phase, TrajectoryPhase::kIdle);
  // Too fast from the present posture: refused when the loop takes it, the posture kept.
  ASSERT_EQ(rig.ctl->command_trajectory(cobra_pose(80 * kDeg, 0.2)), "");
  rig.step(10);
  EXPECT_EQ(rig.ctl->trajectory_progress().abort, TrajectoryAbort::kFirstSegmentTooFast);
  EXPECT_EQ(rig.ctl->state(), DriverState::kHolding);
  EXPECT_EQ(rig.ctl->goal_rad(), before);
  // Torque off: refused with the reason, the static reasons too.
  ASSERT_TRUE(rig.request(DriverRequest::kDisableTorque).success);
  const std::string off = rig.ctl->command_trajectory(bad);
  EXPECT_TRUE(contains(off, "torque is off")) << off;
  EXPECT_TRUE(contains(off, "joint_11")) << off;
}

TEST(DriverTrajectory, EndsOnAHoldRequestAGaitCommandTorqueOffOrAFault) {
  auto running = [](Rig& rig) {
    rig.start();
    EXPECT_EQ(rig.ctl->command_trajectory(cobra_pose(40 * kDeg, 3.0)), "");
    rig.step(50);
    EXPECT_EQ(rig.ctl->trajectory_progress().phase, TrajectoryPhase::kRunning);
  };
  {
    Rig rig;
    running(rig);
    ASSERT_TRUE(rig.request(DriverRequest::kHold).success);
    EXPECT_EQ(rig.ctl->trajectory_progress().abort, TrajectoryAbort::kHoldRequest);
    EXPECT_EQ(rig.ctl->state(), DriverState::kHolding);
    EXPECT_TRUE(contains(rig.ctl->trajectory_progress().reason.data(), "hold_request"));
    const Eigen::VectorXd held = rig.ctl->goal_rad();
    rig.step(100);
    EXPECT_LT((rig.ctl->goal_rad() - held).norm(), 0.01) << "no longer following the trajectory";
  }
  {
    Rig rig;
    running(rig);
    ASSERT_EQ(rig.command("sidewind"), "");
    rig.step(10);
    EXPECT_EQ(rig.ctl->trajectory_progress().abort, TrajectoryAbort::kGaitCommand);
    EXPECT_EQ(rig.ctl->state(), DriverState::kRunning);
    EXPECT_GT(rig.ctl->cpg().amplitudes().maxCoeff(), 0.0) << "the gait drives the joints";
  }
  {
    Rig rig;
    running(rig);
    ASSERT_TRUE(rig.request(DriverRequest::kDisableTorque).success);
    EXPECT_EQ(rig.ctl->trajectory_progress().abort, TrajectoryAbort::kTorqueOff);
  }
  {
    Rig rig;
    running(rig);
    rig.bus->servos().set_silent(4, true);
    rig.step(15);
    EXPECT_EQ(rig.ctl->state(), DriverState::kFault);
    EXPECT_EQ(rig.ctl->trajectory_progress().abort, TrajectoryAbort::kFault);
    const Eigen::VectorXd held = rig.ctl->goal_rad();
    rig.step(50);
    EXPECT_LT((rig.ctl->goal_rad() - held).norm(), 0.01) << "the fault holds: the trajectory no longer moves";
  }
  {
    Rig rig;  // accepted, then torque went off before the loop took it: taken and ended, nothing moves
    rig.start();
    ASSERT_EQ(rig.ctl->command_trajectory(cobra_pose(40 * kDeg, 3.0, "late")), "");
    const auto ticket = rig.ctl->post(DriverRequest::kDisableTorque, 0);
    rig.step();  // the request runs before the trajectory is taken
    snake_autonomy::driver::RequestResult result;
    ASSERT_TRUE(rig.ctl->take_result(ticket, &result));
    EXPECT_EQ(rig.ctl->trajectory_progress().phase, TrajectoryPhase::kAborted);
    EXPECT_EQ(rig.ctl->trajectory_progress().abort, TrajectoryAbort::kNotAllowed);
    EXPECT_EQ(rig.ctl->state(), DriverState::kStopped);
  }
  {
    Rig rig;  // a newer trajectory takes over from the goals commanded now
    running(rig);
    ASSERT_EQ(rig.ctl->command_trajectory(cobra_pose(-20 * kDeg, 3.0, "second")), "");
    rig.step();
    EXPECT_EQ(rig.ctl->trajectory_progress().phase, TrajectoryPhase::kRunning);
    EXPECT_EQ(rig.ctl->trajectory_progress().sequence, 2u);
    EXPECT_STREQ(rig.ctl->trajectory_progress().id.data(), "second");
  }
}

TEST(DriverTrajectory, EachEndIsAFinalStatusOnce) {
  Rig rig;
  rig.start();
  ASSERT_EQ(rig.ctl->command_trajectory(cobra_pose(40 * kDeg, 3.0, "first")), "");
  rig.step(20);
  ASSERT_EQ(rig.ctl->command_trajectory(cobra_pose(-20 * kDeg, 3.0, "second")), "");
  rig.step(20);
  ASSERT_TRUE(rig.request(DriverRequest::kHold).success);
  rig.step(20);
  std::vector<TrajectoryProgress> f;
  TrajectoryProgress p;
  while (rig.ctl->pop_trajectory_final(&p)) f.push_back(p);
  ASSERT_EQ(f.size(), 2u);
  EXPECT_STREQ(f[0].id.data(), "first");
  EXPECT_EQ(f[0].abort, TrajectoryAbort::kSuperseded);
  EXPECT_STREQ(f[0].superseded_by.data(), "second");
  EXPECT_STREQ(f[1].id.data(), "second");
  EXPECT_EQ(f[1].abort, TrajectoryAbort::kHoldRequest);
  EXPECT_EQ(rig.ctl->trajectory_finals_dropped(), 0u);
}

TEST(DriverTrajectory, MaximumDurationIsConfigured) {
  DriverConfig cfg;
  cfg.max_trajectory_duration_s = 2.0;
  Rig rig(cfg);
  rig.start();
  const std::string why = rig.ctl->command_trajectory(cobra_pose(10 * kDeg, 3.0, "long"));
  EXPECT_TRUE(contains(why, "longer than max_trajectory_duration_s 2 s")) << why;
  cfg.max_trajectory_duration_s = 0.0;
  EXPECT_FALSE(cfg.validate().empty());
}

TEST(DriverTrajectory, GoalsPassTheSlewLimitAndTheClamp) {
  DriverConfig cfg;
  cfg.max_joint_velocity_rad_s = 1.0;
  Rig rig(cfg, [](auto& model) { model.joint_upper_rad[0] = 10 * kDeg; });
  rig.start();
  // joint_1's point is within a tick of its (tick-rounded) upper limit: accepted, then clamped.
  JointTrajectoryRequest r = cobra_pose(0.0, 1.0);
  r.points[1].positions_rad[0] = 10 * kDeg;
  r.points[0].positions_rad[0] = 5 * kDeg;
  ASSERT_EQ(rig.ctl->command_trajectory(r), "");
  double prev = rig.ctl->goal_rad()[0], worst = 0.0;
  for (int k = 0; k < 150; ++k) {
    rig.step();
    worst = std::max(worst, std::abs(rig.ctl->goal_rad()[0] - prev) / kDt);
    prev = rig.ctl->goal_rad()[0];
    EXPECT_LE(rig.ctl->goal_rad()[0], 10 * kDeg + 1e-12);
  }
  EXPECT_LE(worst, 1.0 + 1e-9);
  EXPECT_EQ(rig.ctl->trajectory_progress().phase, TrajectoryPhase::kDone);
}
