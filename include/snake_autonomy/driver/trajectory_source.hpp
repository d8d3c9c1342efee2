// TrajectorySource: a joint trajectory as the driver's goal source, ROS-free.
//
// Units and frames: positions in rad, velocities in rad/s, times in s; joint space only (the
// joints' own angles, as the robot YAML and joint_states define them: no Cartesian frame is
// involved). Joints are named joint_1 .. joint_N (N = the robot's joint count), in any order.
//
// The request (what a trajectory_msgs/JointTrajectory carries): an id, the joint names, and points
// with time_from_start_s (> 0, strictly increasing) and positions (one per name), velocities
// optional per point (none, or one per name).
//
// check() refuses a request WHOLE and lists EVERY reason, each naming the field, the point index,
// the joint and the value: unknown, missing or repeated joint names; a wrong number of positions
// or velocities; NaN or infinite values; a position outside the joint limits (the driver's goal
// clamp, within `limit_tolerance_rad`); a first time <= 0 or a time not after the previous one;
// a segment whose interpolated peak velocity exceeds max_velocity_rad_s; more points than the
// capacity fixed at construction (DriverConfig::max_trajectory_points); a last time_from_start over
// max_duration_s (DriverConfig::max_trajectory_duration_s: a point at 2^31 s is refused, not run).
//
// Execution (loop thread): take() starts the pending trajectory FROM THE PRESENT POSTURE: the goals
// the driver is commanding at that moment (what the servos hold; the measured angles lag them by
// the servos' tracking error, and starting from those would step the command), at rest, at time
// 0. Between knots (the present posture, then every point) the goal is a cubic Hermite: each
// point's velocity is the request's when given; otherwise zero at the last point (the trajectory
// ends at rest) and, inside, the shape-preserving (monotone) estimate of Fritsch and Butland, as
// scipy's PchipInterpolator: zero where the neighbouring secants differ in sign or one is zero,
// else their weighted harmonic mean; so a goal never overshoots two points that it passes between.
// Point 0's estimate depends on the present posture: it, and the segments present -> point 0 and
// point 0 -> point 1, are velocity-checked at take() (refused then, with the reason; the robot is
// left as it was). The goal passes through every point at its time. After the last point the
// source holds it and reports done.
//
// Final statuses (as actionlib's goals): submit() numbers every accepted trajectory (its sequence,
// 1, 2, ...), and each one ends with EXACTLY ONE final status, queued for pop_final():
//   done                      its last point reached (then held);
//   aborted, with the reason  a fault, torque off, a hold request, a gait command, shutdown, or its
//                             take-time check (first segment too fast, torque off or a fault then);
//   aborted, kSuperseded      a newer accepted trajectory replaced it, named in superseded_by (id and
//                             sequence): while it ran (take() of the newer one), or before the loop
//                             took it (submit() of the newer one: point_reached -1, time 0).
// The queue holds kFinalQueue statuses per producer (the loop; submit()); a full queue drops the
// status and counts it (finals_dropped()), never silently. progress() stays the latest trajectory's
// state for whoever samples it (running, point passed), and it may skip states between samples: the
// final statuses never are.
//
// Peak velocity of a Hermite segment: v(s) = a s^2 + b s + c over s in [0, 1], with d = (p1 - p0)/h,
// a = 3 (m0 + m1) - 6 d, b = 6 d - 4 m0 - 2 m1, c = m0: the largest of |m0|, |m1| and |v| at the
// vertex when it lies inside (rest to rest: 1.5 |d|).
//
// Threads and real time: check() and submit() may run on any thread (they allocate: strings);
// pop_final() and finals_dropped() on any ONE consumer thread (lock-free: the loop never waits);
// submit() copies the request into storage reserved at construction under a mutex that the loop
// only try_locks (a missed take is picked up the next cycle). take(), update(), abort() and the
// progress are loop-thread only, noexcept and allocation-free (the handover swaps two buffers).
// set_joint_limits() only before the loop and the callers start.
#pragma once

#include <Eigen/Dense>
#include <array>
#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

namespace snake_autonomy::driver {

struct JointTrajectoryPoint {
  double time_from_start_s = 0.0;
  std::vector<double> positions_rad;     // one per joint name
  std::vector<double> velocities_rad_s;  // empty (estimated) or one per joint name
};

struct JointTrajectoryRequest {
  std::string id;  // the caller's label, echoed in the progress (truncated to 63 characters)
  std::vector<std::string> joint_names;  // joint_1 .. joint_N, any order, each once
  std::vector<JointTrajectoryPoint> points;
};

struct TrajectoryLimits {
  Eigen::VectorXd lower_rad, upper_rad;  // per joint (joint order): the driver's goal clamp
  double limit_tolerance_rad = 0.0;      // positions up to this far outside are accepted (then clamped)
  double max_velocity_rad_s = 0.0;       // the driver's slew limit
  int max_points = 20000;                // capacity, reserved at construction
  double max_duration_s = 600.0;         // the last time_from_start may not exceed this (s)
};

enum class TrajectoryPhase : std::uint8_t { kIdle, kRunning, kDone, kAborted };
const char* to_string(TrajectoryPhase phase) noexcept;

// Why a trajectory ended early (kNone while it runs or when it completed).
enum class TrajectoryAbort : std::uint8_t {
  kNone,
  kFirstSegmentTooFast,  // present posture -> point 0 (or point 0 -> 1) needs more than the limit
  kNotAllowed,           // taken while torque was off or in a fault
  kFault,                // the driver faulted
  kTorqueOff,            // torque disabled
  kHoldRequest,          // a hold request
  kGaitCommand,          // a gait command took over
  kSuperseded,           // a newer trajectory took over (TrajectoryProgress::superseded_by names it)
  kShutdown,             // the driver exits
};
const char* to_string(TrajectoryAbort reason) noexcept;

using TrajectoryText = std::array<char, 256>;
using TrajectoryId = std::array<char, 64>;

struct TrajectoryProgress {
  std::uint64_t sequence = 0;   // the trajectory's number: the accepted ones are numbered 1, 2, ... (0: none yet)
  TrajectoryId id{};
  TrajectoryPhase phase = TrajectoryPhase::kIdle;
  TrajectoryAbort abort = TrajectoryAbort::kNone;
  TrajectoryText reason{};      // why it was aborted, in words ("" otherwise)
  int point_reached = -1;       // index of the last point whose time has passed (-1: none yet)
  int num_points = 0;
  double time_s = 0.0;          // time into the trajectory (s), at most duration_s
  double duration_s = 0.0;      // the last point's time_from_start_s
  // kSuperseded: the trajectory that replaced this one (its id and sequence; "" and 0 otherwise).
  TrajectoryId superseded_by{};
  std::uint64_t superseded_by_sequence = 0;
};

// A fixed-capacity single-producer single-consumer queue of final statuses (no allocation, no lock).
template <std::size_t Capacity>
class FinalStatusQueue {
 public:
  // Producer. False (the status counted in dropped()) when full.
  bool push(const TrajectoryProgress& status) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_.load(std::memory_order_acquire) >= Capacity) {
      dropped_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    slots_[head % Capacity] = status;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }
  // Consumer.
  bool pop(TrajectoryProgress* out) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) return false;
    *out = slots_[tail % Capacity];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }
  std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }

 private:
  std::array<TrajectoryProgress, Capacity> slots_{};
  std::atomic<std::size_t> head_{0}, tail_{0};
  std::atomic<std::uint64_t> dropped_{0};
};

class TrajectorySource {
 public:
  // Reserves storage for limits.max_points points of num_joints joints (twice: pending and active).
  // Throws std::invalid_argument when the sizes disagree or a limit is not usable.
  TrajectorySource(int num_joints, const TrajectoryLimits& limits);

  // Before the loop and any caller start (the driver refines its clamp with the servos' own limits).
  void set_joint_limits(const Eigen::VectorXd& lower_rad, const Eigen::VectorXd& upper_rad);
  const TrajectoryLimits& limits() const noexcept { return limits_; }
  int num_joints() const noexcept { return n_; }

  // --- any thread ---
  // Every reason the request is refused, one per line ("" when acceptable).
  std::string check(const JointTrajectoryRequest& request) const;
  // check(), then hands the request over, numbered (its sequence). "" when accepted. One accepted
  // earlier and not yet taken is replaced: its final status (kSuperseded, naming this one) is queued.
  std::string submit(const JointTrajectoryRequest& request);

  // --- any ONE consumer thread (noexcept, lock-free) ---
  // The next final status (see the file comment); false when none is queued.
  bool pop_final(TrajectoryProgress* out) noexcept;
  // Final statuses lost to a full queue (the consumer fell kFinalQueue statuses behind).
  std::uint64_t finals_dropped() const noexcept { return loop_finals_.dropped() + submit_finals_.dropped(); }
  static constexpr std::size_t kFinalQueue = 64;

  // --- loop thread (noexcept, allocation-free) ---
  // Takes the pending trajectory, if any (false: none, or the mailbox is busy this cycle), and
  // starts it from `present_rad` at t_s. A trajectory still running is aborted (kSuperseded) first.
  // When the first segments are too fast, or !allowed (the driver's state forbids motion), the new
  // one ends at once (kAborted, with the reason) and running() is false: the caller keeps its goals.
  bool take(double t_s, const Eigen::VectorXd& present_rad, bool allowed = true) noexcept;
  // The goals at t_s into `goal_rad` (joint order). Returns true while the trajectory runs; false
  // when idle, aborted or done (on the cycle it completes `goal_rad` holds the last point and
  // phase() turns kDone).
  bool update(double t_s, Eigen::VectorXd& goal_rad) noexcept;
  // Ends a running trajectory (no effect otherwise).
  void abort(TrajectoryAbort reason) noexcept;
  bool running() const noexcept { return progress_.phase == TrajectoryPhase::kRunning; }
  const TrajectoryProgress& progress() const noexcept { return progress_; }
  // The last point of the latest trajectory taken (joint order): what the driver holds when done.
  const Eigen::VectorXd& final_rad() const noexcept { return active_.final_rad; }

 private:
  // One trajectory in joint order: point k's joint j at [k * n + j].
  struct Buffer {
    TrajectoryId id{};
    std::uint64_t sequence = 0;
    int count = 0;
    std::vector<double> t_s, q, v;
    std::vector<std::uint8_t> v_given;  // per point: velocities from the request
    Eigen::VectorXd final_rad;
  };
  void fill(const JointTrajectoryRequest& request, const std::vector<int>& joint_of_column, Buffer& out) const;
  // Velocity of point 0 when estimated, from the present posture: needs start_ and the active buffer.
  void estimate_first_velocity() noexcept;
  bool check_first_segments() noexcept;  // false: progress_ says why
  // Ends the running trajectory: its phase and reason, and its final status queued.
  void finish(TrajectoryPhase phase, TrajectoryAbort reason) noexcept;

  int n_;
  TrajectoryLimits limits_;
  Buffer active_;   // loop thread
  Eigen::VectorXd start_;  // the posture at take()
  double t0_s_ = 0.0;
  int segment_ = 0;  // the segment in use: 0 = present -> point 0, k = point k-1 -> point k
  TrajectoryProgress progress_;

  FinalStatusQueue<kFinalQueue> loop_finals_;  // produced by the loop thread

  std::mutex mailbox_;  // the loop only try_locks it
  Buffer pending_;
  bool has_pending_ = false;
  std::uint64_t accepted_ = 0;                    // under mailbox_: the last sequence given
  FinalStatusQueue<kFinalQueue> submit_finals_;  // produced under mailbox_ (pending ones replaced)
};

}  // namespace snake_autonomy::driver
