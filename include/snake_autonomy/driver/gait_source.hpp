// GaitSource: the gait as a JointCommandSource (the CPG of eq. 3.5-3.9 driven by gait commands).
//
//   command()   any thread: resolves a GaitCommandRequest (gait library, steering law of the gait,
//               range checks: GaitCommandResolver) and hands the CPG targets to the loop through a
//               mutex the loop only try_locks. Refused whole with every reason (nothing changes).
//   take_command(t_s)   loop: picks up the handed-over command; a command (a repeat included) is the
//               caller's heartbeat: it refreshes the command lifetime.
//   activate()  loop: the oscillators restart at the held posture (amplitudes zero, biases = posture)
//               and move to the gait through the CPG's smooth dynamics.
//   update()    loop, while active:
//               - command lifetime: the last command older than command_timeout_s -> kHold
//                 (HoldReason::kCommandTimeout) until the next command;
//               - stale-pose gating: with require_pose and no fresh base pose the CPG
//                 amplitudes go to zero (the waves decay, critically damped; posture held) and the
//                 commanded gait resumes with fresh poses;
//               - one CPG step; the CPG state is checked: not finite -> kFault with the reason
//                 (never a throw); the goals are the CPG's output.
// Units: radians, rad/s, seconds (loop clock). Real-time safety: take_command(), activate(),
// update() and the loop-side accessors are noexcept and allocation-free; command() allocates (it
// runs in the caller's thread, never in the loop).
#pragma once

#include <Eigen/Dense>
#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>

#include "snake_autonomy/core/cpg.hpp"
#include "snake_autonomy/core/gait_library.hpp"
#include "snake_autonomy/core/robot_model.hpp"
#include "snake_autonomy/driver/driver_config.hpp"
#include "snake_autonomy/driver/gait_command.hpp"
#include "snake_autonomy/driver/joint_command_source.hpp"
#include "snake_autonomy/driver/message.hpp"

namespace snake_autonomy::driver {

class GaitSource : public JointCommandSource {
 public:
  GaitSource(const core::RobotModel& model, const core::GaitLibrary& gaits, const DriverConfig& config);

  // --- any thread ---
  // "" when accepted, else every reason. `blocked`: when not empty, the command is refused with it
  // (the supervisor's reason: torque off, a fault) and not resolved.
  std::string command(const GaitCommandRequest& command, const char* blocked);
  std::uint64_t commands_accepted() const noexcept { return accepted_.load(); }
  std::uint64_t commands_refused() const noexcept { return refused_.load(); }
  std::string last_refusal() const;
  std::string commanded_gait() const;

  // --- loop thread ---
  // True when a command was handed over since the last call (its lifetime starts at t_s).
  bool take_command(double t_s) noexcept;
  // Applies the latest command to the running CPG (the source is active).
  void apply() noexcept;
  // Restarts the command lifetime (driver start).
  void reset_clock(double t_s) noexcept { last_command_t_s_ = t_s; }
  bool activate(double t_s, const JointStateView& state, const Eigen::VectorXd& posture_rad,
                const char** why) noexcept override;
  SourceStatus update(double t_s, double dt_s, const JointStateView& state,
                      Eigen::Ref<Eigen::VectorXd> goal_rad) noexcept override;

  const core::Cpg& cpg() const noexcept { return cpg_; }
  bool gated() const noexcept { return gated_; }
  const Message& gait_name() const noexcept { return gait_name_; }  // the gait the loop runs
  double command_age_s(double t_s) const noexcept { return t_s - last_command_t_s_; }

 private:
  friend struct GaitSourceTestAccess;  // tests only (test/cpp): reaches the CPG to corrupt it

  core::Cpg cpg_;
  core::GaitParameters nominal_, effective_;
  Eigen::VectorXd zeros_;
  bool require_pose_;
  double command_timeout_s_;
  bool gated_ = false;
  double last_command_t_s_ = 0.0;
  Message gait_name_{};

  std::mutex handover_mutex_;  // the loop only try_locks it
  core::GaitParameters pending_;
  Message pending_name_{};
  bool pending_set_ = false;

  mutable std::mutex resolver_mutex_;  // callers' threads only
  GaitCommandResolver resolver_;
  std::string last_refusal_;
  std::atomic<std::uint64_t> accepted_{0}, refused_{0};
};

}  // namespace snake_autonomy::driver
