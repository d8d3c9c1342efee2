// JointCommandSource: what drives the joint goals while the driver runs (ros_control's controller).
// The driver's supervisor makes one source active at a time (GaitSource: the CPG; a trajectory
// source: interpolated points) and applies the slew limit and THE goal clamp once, after whichever
// source is active: a source proposes goals, it never writes the servos.
//
// Units: radians, rad/s, seconds (t_s on the loop's clock, dt_s the step already clamped to
// [0, max_step_s]). Joint order: joint_1 ... joint_N.
// Real-time safety: activate() and update() run on the loop thread, noexcept and allocation-free.
// Handovers from other threads (new commands) are the source's own business (try_lock mailboxes).
#pragma once

#include <Eigen/Dense>
#include <cstdint>

#include "snake_autonomy/driver/safety_rules.hpp"

namespace snake_autonomy::driver {

// The joint state a source sees (read-only views, valid during the call).
struct JointStateView {
  const Eigen::VectorXd& position_rad;    // measured (a stale servo: its last good value)
  const Eigen::VectorXd& velocity_rad_s;  // measured
  const Eigen::VectorXd& goal_rad;        // the goal written last cycle (after slew limit and clamp)
  const Eigen::VectorXd& lower_rad;       // the goal clamp (joint limits within the servos' limits)
  const Eigen::VectorXd& upper_rad;
  bool pose_fresh;                        // a base pose younger than pose_timeout_s is known
};

// What update() says about the source.
struct SourceStatus {
  enum Code : std::uint8_t {
    kActive,  // goal_rad holds this cycle's goals
    kHold,    // the source has finished (hold_reason says why): the supervisor holds the posture
    kFault,   // the source cannot go on (reason, a static text): the supervisor faults
  };
  Code code = kActive;
  HoldReason hold_reason = HoldReason::kNone;
  // kHold: hold at this cycle's goal_rad (a trajectory's last point) instead of the measured posture.
  bool hold_at_goal = false;
  const char* reason = "";
};

// Why the supervisor took an active source off before it finished.
enum class StopCause : std::uint8_t {
  kFault,        // the driver faulted (the fault reason says why)
  kTorqueOff,    // a disable-torque request
  kHoldRequest,  // a hold request
  kOtherSource,  // a command for another source took over
  kShutdown,     // the driver exits
};
const char* to_string(StopCause cause) noexcept;

class JointCommandSource {
 public:
  virtual ~JointCommandSource() = default;
  // The supervisor makes this source active with the robot at `posture_rad` (the held goals):
  // the source starts from there. False (reason in *why, a static text) when it cannot start.
  virtual bool activate(double t_s, const JointStateView& state, const Eigen::VectorXd& posture_rad,
                        const char** why) noexcept = 0;
  // One cycle while active: this cycle's desired goals into goal_rad (size N, radians; a non-finite
  // value keeps the joint's previous goal).
  virtual SourceStatus update(double t_s, double dt_s, const JointStateView& state,
                              Eigen::Ref<Eigen::VectorXd> goal_rad) noexcept = 0;
  // The supervisor took this source off before it finished; it must not resume by itself.
  virtual void deactivate(StopCause cause) noexcept { (void)cause; }
};

}  // namespace snake_autonomy::driver
