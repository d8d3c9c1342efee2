#include "snake_autonomy/driver/supervisor.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include "snake_autonomy/dynamixel/protocol.hpp"

namespace snake_autonomy::driver {

namespace dxl = snake_autonomy::dynamixel;

namespace {
double deg(double rad) { return rad * 180.0 / M_PI; }
}  // namespace

const char* to_string(DriverState state) noexcept {
  switch (state) {
    case DriverState::kStopped: return "stopped";
    case DriverState::kHolding: return "holding";
    case DriverState::kRunning: return "running";
    case DriverState::kFault: return "fault";
  }
  return "?";
}

const char* to_string(DriverRequest request) noexcept {
  switch (request) {
    case DriverRequest::kEnableTorque: return "enable torque";
    case DriverRequest::kDisableTorque: return "disable torque";
    case DriverRequest::kHold: return "hold";
    case DriverRequest::kRebootServo: return "reboot servo";
  }
  return "?";
}

DriverSupervisor::DriverSupervisor(ServoChain& chain, const DriverConfig& config)
    : chain_(chain),
      max_failed_cycles_(config.max_failed_cycles),
      fault_action_(config.fault_action),
      shutdown_action_(config.shutdown_action),
      torque_on_start_(config.torque_on_start),
      max_joint_velocity_rad_s_(config.max_joint_velocity_rad_s),
      hold_(Eigen::VectorXd::Zero(chain.size())),
      goal_(Eigen::VectorXd::Zero(chain.size())),
      target_(Eigen::VectorXd::Zero(chain.size())) {}

// ---------------------------------------------------------------------------------------------
// States

void DriverSupervisor::begin(const ChainStartReport& report) noexcept {
  started_ = true;
  hold_here();
  chain_.set_goal(goal_);  // the posture, not sent: nothing is written before torque on
  if (!report.hardware_errors.empty()) {
    Message m{};
    copy_message(m, "hardware error at start:");
    chain_.describe_hardware_errors(m);
    append(m, " reboot it, then enable torque");
    fault_reason_ = last_fault_ = m;
    set_state(DriverState::kFault);
    return;
  }
  if (torque_on_start_) {
    Message why{};
    if (!enable_torque(why)) {
      fault_reason_ = last_fault_ = why;
      chain_.write_torque(false);
      set_state(DriverState::kFault);
    }
  } else {
    set_state(DriverState::kStopped);
  }
}

void DriverSupervisor::hold_here() noexcept {
  hold_ = chain_.position_rad();
  chain_.clamp(hold_);
  goal_ = hold_;
}

const char* to_string(StopCause cause) noexcept {
  switch (cause) {
    case StopCause::kFault: return "fault";
    case StopCause::kTorqueOff: return "torque off";
    case StopCause::kHoldRequest: return "hold request";
    case StopCause::kOtherSource: return "another command source took over";
    case StopCause::kShutdown: return "shutdown";
  }
  return "?";
}

void DriverSupervisor::take_off(StopCause cause) noexcept {
  if (active_) active_->deactivate(cause);
  active_ = nullptr;
}

void DriverSupervisor::hold(HoldReason reason) noexcept {
  take_off(reason == HoldReason::kShutdown ? StopCause::kShutdown : StopCause::kHoldRequest);
  hold_here();
  hold_reason_ = reason;
  set_state(DriverState::kHolding);
}

void DriverSupervisor::enter_fault(const char* reason) noexcept {
  if (state() == DriverState::kFault) return;
  take_off(StopCause::kFault);
  copy_message(fault_reason_, reason);
  last_fault_ = fault_reason_;
  if (fault_action_ == SafeAction::kHold) {
    hold_here();
  } else {
    chain_.write_torque(false);
  }
  set_state(DriverState::kFault);
}

const char* DriverSupervisor::command_refusal() const noexcept {
  switch (state()) {
    case DriverState::kStopped: return "torque is off: enable it first";
    case DriverState::kFault: return "locomotion is stopped by a fault: recover by enabling torque";
    default: return "";
  }
}

bool DriverSupervisor::command(JointCommandSource& source, double t_s, bool pose_fresh, bool* was_active) noexcept {
  *was_active = false;
  const DriverState s = state();
  if (s == DriverState::kRunning && active_ == &source) {
    *was_active = true;
    return true;
  }
  if (s != DriverState::kHolding && s != DriverState::kRunning) return false;  // accepted just before: dropped
  // Another source running: it ends, and the new one starts from the goals where they are.
  if (s == DriverState::kRunning) {
    take_off(StopCause::kOtherSource);
    hold_ = goal_;
  }
  const char* why = "";
  if (!source.activate(t_s, view(pose_fresh), hold_, &why)) {
    enter_fault(why);
    return false;
  }
  active_ = &source;
  hold_reason_ = HoldReason::kNone;
  set_state(DriverState::kRunning);
  return true;
}

void DriverSupervisor::check_hardware_errors() noexcept {
  if (!chain_.read_hardware_errors()) return;
  const DriverState s = state();
  if (s != DriverState::kRunning && s != DriverState::kHolding) return;
  Message m{};
  copy_message(m, "hardware error:");
  chain_.describe_hardware_errors(m);
  append(m, " reboot it, then enable torque");
  enter_fault(m.data());
}

// ---------------------------------------------------------------------------------------------
// The goal step

bool DriverSupervisor::drive(double t_s, double dt_s, bool pose_fresh) noexcept {
  if (state() == DriverState::kRunning && active_) {
    const SourceStatus st = active_->update(t_s, dt_s, view(pose_fresh), target_);
    if (st.code == SourceStatus::kHold) {
      active_ = nullptr;  // finished by itself: nothing to tell it
      if (st.hold_at_goal) {  // at the source's last goal (clamped); the goals continue from where they are
        for (int j = 0; j < hold_.size(); ++j) hold_[j] = std::isfinite(target_[j]) ? target_[j] : goal_[j];
        chain_.clamp(hold_);
        hold_reason_ = st.hold_reason;
        set_state(DriverState::kHolding);
      } else {
        hold(st.hold_reason);
      }
    } else if (st.code == SourceStatus::kFault) {
      enter_fault(st.reason);
    }
  }
  const DriverState s = state();
  if (s == DriverState::kRunning || s == DriverState::kHolding ||
      (s == DriverState::kFault && fault_action_ == SafeAction::kHold)) {
    const Eigen::VectorXd& target = s == DriverState::kRunning ? target_ : hold_;
    // The one slew limit, for every source and the hold posture; then the one clamp (ServoChain).
    const double max_move = max_joint_velocity_rad_s_ * dt_s;
    for (int j = 0; j < goal_.size(); ++j) {
      const double t = std::isfinite(target[j]) ? target[j] : goal_[j];
      goal_[j] += std::clamp(t - goal_[j], -max_move, max_move);
    }
    return chain_.write(goal_);
  }
  if (s == DriverState::kFault)
    return chain_.write_torque(false);  // repeated: a servo that comes back must not keep torque
  return true;
}

bool DriverSupervisor::count_cycle(bool read_ok, bool write_ok) noexcept {
  const bool ok = read_ok && write_ok;
  if (ok) {
    consecutive_failed_ = 0;
    return true;
  }
  ++failed_cycles_;
  ++consecutive_failed_;
  const DriverState now = state();
  if (consecutive_failed_ < static_cast<std::uint32_t>(max_failed_cycles_) ||
      (now != DriverState::kRunning && now != DriverState::kHolding))
    return false;
  Message m{};
  const bool io = chain_.io_error();
  if (io || !write_ok) {
    std::snprintf(m.data(), m.size(), "bus failure for %u consecutive cycles: %s%s", consecutive_failed_,
                  io ? "I/O error (port closed or adapter unplugged?)" : "",
                  write_ok ? "" : (io ? "; goal write failed" : "goal write failed"));
  } else {
    std::snprintf(m.data(), m.size(), "%u consecutive cycles with missing replies:", consecutive_failed_);
    chain_.describe_stale(m);
  }
  enter_fault(m.data());
  return false;
}

bool DriverSupervisor::shutdown() noexcept {
  if (!started_) return true;
  if (shutdown_action_ == SafeAction::kTorqueOff) {
    take_off(StopCause::kShutdown);
    const bool ok = chain_.write_torque(false);
    set_state(DriverState::kStopped);
    return ok;
  }
  if (state() == DriverState::kStopped) return true;  // torque already off
  chain_.read();  // the posture where the robot is now
  if (state() != DriverState::kFault) {
    hold(HoldReason::kShutdown);
  } else {
    hold_here();
  }
  return chain_.write(goal_);
}

// ---------------------------------------------------------------------------------------------
// Requests

std::uint64_t DriverSupervisor::post(DriverRequest request, std::uint8_t servo_id) {
  std::lock_guard<std::mutex> lock(request_mutex_);
  pending_request_.ticket = next_ticket_++;
  pending_request_.type = request;
  pending_request_.id = servo_id;
  return pending_request_.ticket;
}

bool DriverSupervisor::take_result(std::uint64_t ticket, RequestResult* out) {
  if (done_ticket_.load(std::memory_order_acquire) != ticket) return false;
  out->success = done_success_;
  out->message = done_message_.data();
  return true;
}

RequestResult DriverSupervisor::call(DriverRequest request, std::uint8_t servo_id, double timeout_s) {
  std::lock_guard<std::mutex> serial(call_mutex_);
  const std::uint64_t ticket = post(request, servo_id);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  RequestResult result;
  while (!take_result(ticket, &result)) {
    if (std::chrono::steady_clock::now() > deadline) {
      std::lock_guard<std::mutex> lock(request_mutex_);
      if (pending_request_.ticket == ticket) {  // not taken: withdraw it
        pending_request_.ticket = 0;
        return {false, "the control loop did not run the request within " + std::to_string(timeout_s) + " s"};
      }
      // Taken: the loop is running it and will finish within its cycle.
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return result;
}

void DriverSupervisor::take_request() noexcept {
  if (!request_mutex_.try_lock()) return;
  const PendingRequest r = pending_request_;
  pending_request_.ticket = 0;
  request_mutex_.unlock();
  if (r.ticket != 0) run_request(r);
}

void DriverSupervisor::finish_request(std::uint64_t ticket, bool success, const char* fmt, ...) noexcept {
  done_success_ = success;
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(done_message_.data(), done_message_.size(), fmt, args);
  va_end(args);
  done_ticket_.store(ticket, std::memory_order_release);
}

void DriverSupervisor::run_request(const PendingRequest& r) noexcept {
  const DriverState s = state();
  switch (r.type) {
    case DriverRequest::kEnableTorque: {
      if (s == DriverState::kHolding || s == DriverState::kRunning) {
        finish_request(r.ticket, true, "torque already on (%s)", to_string(s));
        return;
      }
      Message why{};
      if (enable_torque(why)) {
        finish_request(r.ticket, true, "torque on, holding the posture: send a gait command to move");
      } else {
        finish_request(r.ticket, false, "%s", why.data());
      }
      return;
    }
    case DriverRequest::kDisableTorque: {
      take_off(StopCause::kTorqueOff);
      const bool ok = chain_.write_torque(false);
      fault_reason_[0] = '\0';
      set_state(DriverState::kStopped);
      if (ok) {
        finish_request(r.ticket, true, "torque off");
      } else {
        finish_request(r.ticket, false, "torque off sent but the bus failed: check the servos");
      }
      return;
    }
    case DriverRequest::kHold: {
      if (s == DriverState::kRunning) {
        hold(HoldReason::kHoldRequest);
        finish_request(r.ticket, true, "holding the posture: send a gait command to move");
      } else if (s == DriverState::kHolding) {
        finish_request(r.ticket, true, "already holding");
      } else {
        finish_request(r.ticket, false, "cannot hold: %s",
                       s == DriverState::kStopped ? "torque is off" : "in a fault (see the fault reason)");
      }
      return;
    }
    case DriverRequest::kRebootServo: {
      const int j = chain_.joint_of(r.id);
      if (j < 0) {
        finish_request(r.ticket, false, "no servo with ID %d on this bus", r.id);
        return;
      }
      if (s == DriverState::kRunning || s == DriverState::kHolding) {
        finish_request(r.ticket, false,
                       "refused while torque is on (%s): disable torque first, or reboot after a fault", to_string(s));
        return;
      }
      const dxl::Status st = chain_.reboot(r.id);
      if (!dxl::has_data(st)) {
        finish_request(r.ticket, false, "reboot of servo %d failed: %s", r.id, dxl::to_string(st));
        return;
      }
      finish_request(r.ticket, true, "servo %d (joint_%d) rebooted (torque off): enable torque to resume", r.id, j + 1);
      return;
    }
  }
}

bool DriverSupervisor::enable_torque(Message& why) noexcept {
  why[0] = '\0';
  bool ok = chain_.read();
  if (!ok && chain_.io_error() && reconnect_) {
    std::string reason;
    bool reopened = false;
    try {
      reopened = reconnect_(&reason);
    } catch (const std::exception& e) {
      reason = e.what();
    }
    if (!reopened) {
      std::snprintf(why.data(), why.size(), "cannot enable torque: the bus has an I/O error and reopening failed: %s",
                    reason.c_str());
      return false;
    }
    ok = chain_.read();
  }
  if (!ok) {
    dxl::Status status = dxl::Status::kOk;
    if (chain_.all_failed_alike(&status)) {
      std::snprintf(why.data(), why.size(), "cannot enable torque, no feedback from any servo (%s)",
                    dxl::to_string(status));
      return false;
    }
    copy_message(why, "cannot enable torque, no feedback from:");
    for (int j = 0; j < chain_.size(); ++j) {
      if (chain_.servos()[j].stale)
        append(why, " servo %d (joint_%d) %s;", chain_.ids()[j], j + 1, dxl::to_string(chain_.reply_status(j)));
    }
    return false;
  }
  chain_.read_hardware_errors();  // the bits of any alerting servo (no state change: torque is off)
  for (int j = 0; j < chain_.size(); ++j) {
    const ServoDiagnostics& d = chain_.servos()[j];
    if (d.hardware_error) {
      char bits[96];
      chain_.describe_bits(d.hardware_error_bits, bits, sizeof bits);
      append(why, "%sservo %d (joint_%d) has a hardware error (%s): reboot it first", why[0] ? "; " : "", d.id, j + 1,
             bits);
    } else if (chain_.outside_limits(j)) {
      append(why, "%sservo %d (joint_%d) at %.1f deg is outside its limits [%.1f, %.1f] deg: move it by hand first",
             why[0] ? "; " : "", d.id, j + 1, deg(chain_.position_rad()[j]), deg(chain_.lower_rad()[j]),
             deg(chain_.upper_rad()[j]));
    }
  }
  if (why[0]) return false;
  hold_here();
  if (!chain_.write(goal_) || !chain_.write_torque(true)) {
    copy_message(why, "cannot enable torque: the bus did not take the writes");
    chain_.write_torque(false);
    return false;
  }
  if (!chain_.confirm_torque(true, why)) {
    chain_.write_torque(false);
    return false;
  }
  consecutive_failed_ = 0;
  fault_reason_[0] = '\0';
  hold_reason_ = HoldReason::kTorqueEnabled;
  set_state(DriverState::kHolding);
  return true;
}

}  // namespace snake_autonomy::driver
