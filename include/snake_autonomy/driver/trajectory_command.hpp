// TrajectoryCommand: a TrajectorySource as the driver's JointCommandSource (the plug between the
// trajectory's own API and the supervisor). The loop takes a pending trajectory with
// TrajectorySource::take() (from the goals commanded now; its take-time check may end it at once,
// the robot left as it was); when it runs, the supervisor makes this source active. Then:
//   update()      the interpolated goals (radians); at the end: kHold, HoldReason::kTrajectoryDone,
//                 held at the last point (hold_at_goal), not where the robot happens to be
//   deactivate()  the supervisor's stop cause becomes the trajectory's abort reason (a fault, torque
//                 off, a hold request, a gait command, shutdown), reported in its progress
// No command lifetime and no pose gate: a trajectory ends by itself.
// Real-time safety: noexcept, allocation-free (the goal buffer is sized at construction).
#pragma once

#include <Eigen/Dense>

#include "snake_autonomy/driver/joint_command_source.hpp"
#include "snake_autonomy/driver/trajectory_source.hpp"

namespace snake_autonomy::driver {

class TrajectoryCommand : public JointCommandSource {
 public:
  explicit TrajectoryCommand(TrajectorySource& trajectory)
      : trajectory_(trajectory), goal_(Eigen::VectorXd::Zero(trajectory.num_joints())) {}

  bool activate(double /*t_s*/, const JointStateView& /*state*/, const Eigen::VectorXd& /*posture_rad*/,
                const char** why) noexcept override {
    *why = "the trajectory is not running";  // take() started it (or ended it at once)
    return trajectory_.running();
  }

  SourceStatus update(double t_s, double /*dt_s*/, const JointStateView& /*state*/,
                      Eigen::Ref<Eigen::VectorXd> goal_rad) noexcept override {
    const bool running = trajectory_.update(t_s, goal_);
    goal_rad = goal_;
    SourceStatus status;
    if (running) return status;
    status.code = SourceStatus::kHold;
    status.hold_reason = HoldReason::kTrajectoryDone;
    status.hold_at_goal = trajectory_.progress().phase == TrajectoryPhase::kDone;  // goal_ = the last point
    return status;
  }

  void deactivate(StopCause cause) noexcept override {
    switch (cause) {
      case StopCause::kFault: trajectory_.abort(TrajectoryAbort::kFault); return;
      case StopCause::kTorqueOff: trajectory_.abort(TrajectoryAbort::kTorqueOff); return;
      case StopCause::kHoldRequest: trajectory_.abort(TrajectoryAbort::kHoldRequest); return;
      case StopCause::kOtherSource: trajectory_.abort(TrajectoryAbort::kGaitCommand); return;
      case StopCause::kShutdown: trajectory_.abort(TrajectoryAbort::kShutdown); return;
    }
  }

 private:
  TrajectorySource& trajectory_;
  Eigen::VectorXd goal_;
};

}  // namespace snake_autonomy::driver
