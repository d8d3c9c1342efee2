#include "snake_autonomy/driver/gait_source.hpp"

#include "snake_autonomy/driver/safety_rules.hpp"

namespace snake_autonomy::driver {

GaitSource::GaitSource(const core::RobotModel& model, const core::GaitLibrary& gaits, const DriverConfig& config)
    : cpg_(model),
      zeros_(Eigen::VectorXd::Zero(model.num_joints)),
      require_pose_(config.require_pose),
      command_timeout_s_(config.command_timeout_s),
      resolver_(model, gaits, config.max_frequency_hz > 0.0 ? config.max_frequency_hz : 1.0, "hold") {
  nominal_ = effective_ = pending_ = resolver_.nominal();
  copy_message(gait_name_, "hold");
}

// ---------------------------------------------------------------------------------------------
// Callers' threads

std::string GaitSource::command(const GaitCommandRequest& command, const char* blocked) {
  std::lock_guard<std::mutex> lock(resolver_mutex_);
  std::string why;
  if (blocked && blocked[0]) {
    why = blocked;
  } else {
    core::GaitParameters out;
    why = resolver_.resolve(command, out);
    if (why.empty()) {
      std::lock_guard<std::mutex> g(handover_mutex_);
      pending_ = std::move(out);
      copy_message(pending_name_, resolver_.current_gait().c_str());
      pending_set_ = true;
    }
  }
  if (why.empty()) {
    ++accepted_;
  } else {
    ++refused_;
    last_refusal_ = why;
  }
  return why;
}

std::string GaitSource::last_refusal() const {
  std::lock_guard<std::mutex> lock(resolver_mutex_);
  return last_refusal_;
}

std::string GaitSource::commanded_gait() const {
  std::lock_guard<std::mutex> lock(resolver_mutex_);
  return resolver_.current_gait();
}

// ---------------------------------------------------------------------------------------------
// Loop thread

bool GaitSource::take_command(double t_s) noexcept {
  if (!handover_mutex_.try_lock()) return false;  // picked up next cycle
  const bool taken = pending_set_;
  if (taken) {
    nominal_ = pending_;  // same sizes: no allocation
    gait_name_ = pending_name_;
    pending_set_ = false;
  }
  handover_mutex_.unlock();
  if (taken) last_command_t_s_ = t_s;  // a repeated command is the caller's heartbeat
  return taken;
}

void GaitSource::apply() noexcept {
  effective_ = nominal_;
  if (gated_) effective_.amplitude.setZero();
  cpg_.apply(effective_);
}

bool GaitSource::activate(double /*t_s*/, const JointStateView& state, const Eigen::VectorXd& posture_rad,
                          const char** why) noexcept {
  // Restart the oscillators at the held posture (amplitudes zero, biases = posture): the goals
  // continue from where the robot is and move to the gait through the CPG's smooth dynamics.
  if (!cpg_.restart(cpg_.phases(), zeros_, posture_rad)) {
    *why = "CPG state not finite: the oscillators cannot restart from their phases; locomotion stopped";
    return false;
  }
  gated_ = require_pose_ && !state.pose_fresh;
  apply();
  return true;
}

SourceStatus GaitSource::update(double t_s, double dt_s, const JointStateView& state,
                                Eigen::Ref<Eigen::VectorXd> goal_rad) noexcept {
  SourceStatus status;
  if (command_expired(t_s, last_command_t_s_, command_timeout_s_)) {
    status.code = SourceStatus::kHold;
    status.hold_reason = HoldReason::kCommandTimeout;
    return status;
  }
  // Stale base pose: hold locomotion (amplitudes to zero), resume when fresh poses return.
  const bool gate = require_pose_ && !state.pose_fresh;
  if (gate != gated_) {
    gated_ = gate;
    apply();
  }
  cpg_.step(dt_s);
  if (!cpg_.state_finite()) {
    status.code = SourceStatus::kFault;
    status.reason =
        "CPG state not finite (an oscillator's phase, amplitude or bias is NaN or infinite): locomotion stopped";
    return status;
  }
  goal_rad = cpg_.output();
  return status;
}

}  // namespace snake_autonomy::driver
