// DriverSupervisor: the driver's state machine, fault rules and request mailbox, over a ServoChain.
//
// States (DriverState):
//   kStopped  torque off (at start when torque_on_start is false, or by request). No goals are written.
//   kHolding  torque on, goals frozen at the posture the robot had when it stopped; hold_reason() says
//             why (start/recovery, hold request, command lifetime, shutdown, a source that finished).
//   kRunning  the active JointCommandSource drives the goals.
//   kFault    latched after max_failed_cycles consecutive failed cycles (a missing, corrupt or
//             implausible reply, or a failed write), any hardware error, or a source that reports a
//             fault: the fault action is applied (hold: goals frozen at the present positions;
//             torque_off: torque off, repeated every cycle) and the reason kept. Left with a
//             kEnableTorque request (which checks every servo first) after rebooting a servo that
//             reported a hardware error (kRebootServo).
// Whatever the source says, the goals pass ONE slew limit (max_joint_velocity_rad_s) and then the
// ServoChain's goal clamp, for every source and for the hold posture alike.
//
// Reason codes and texts name values and servos, never ROS topics or services (the node adds those).
//
// Threads: everything runs on the loop thread except post(), take_result() and call(), which may be
// called from any thread: post() hands the request over under a mutex the loop only try_locks
// (a missed handover is picked up the next cycle); the result comes back through an atomic ticket.
// Real-time safety: the loop-thread functions are noexcept and allocation-free, except the recovery
// path of kEnableTorque after an I/O error (set_reconnect: reopening a port may allocate).
#pragma once

#include <Eigen/Dense>
#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>

#include "snake_autonomy/driver/driver_config.hpp"
#include "snake_autonomy/driver/joint_command_source.hpp"
#include "snake_autonomy/driver/message.hpp"
#include "snake_autonomy/driver/safety_rules.hpp"
#include "snake_autonomy/driver/servo_chain.hpp"

namespace snake_autonomy::driver {

enum class DriverState : std::uint8_t { kStopped, kHolding, kRunning, kFault };
const char* to_string(DriverState state) noexcept;

enum class DriverRequest : std::uint8_t { kEnableTorque, kDisableTorque, kHold, kRebootServo };
const char* to_string(DriverRequest request) noexcept;

struct RequestResult {
  bool success = false;
  std::string message;
};

class DriverSupervisor {
 public:
  // The chain must outlive the supervisor.
  DriverSupervisor(ServoChain& chain, const DriverConfig& config);

  // After ServoChain::start() found no problem: holds the measured posture, then kFault when a
  // servo reports a hardware error, else torque on and kHolding (torque_on_start) or kStopped.
  void begin(const ChainStartReport& report) noexcept;
  // Runs the request posted since the last cycle, if any.
  void take_request() noexcept;
  // A new command for `source` reached the loop: Holding -> the source becomes active (started at
  // the held posture); Running -> it becomes (or stays) the active one. Returns false when the
  // command is dropped (torque off, a fault, or the source could not start: fault entered).
  // When true and the source was already active, the caller applies the new command to it.
  bool command(JointCommandSource& source, double t_s, bool pose_fresh, bool* was_active) noexcept;
  // Why commands are refused now ("" when they are not): torque off or a fault.
  const char* command_refusal() const noexcept;
  // Faults (Running or Holding) when a servo reports a hardware error; reads the error bits first.
  void check_hardware_errors() noexcept;
  // The goal step: the active source (Running) or the hold posture -> slew limit -> goal clamp ->
  // write; in a fault with fault action torque_off, torque off again. False when the bus failed.
  bool drive(double t_s, double dt_s, bool pose_fresh) noexcept;
  // The fault rule on failed cycles. Returns read_ok && write_ok.
  bool count_cycle(bool read_ok, bool write_ok) noexcept;
  // Leaves the servos as config.shutdown_action says. False when the bus did not take the write.
  bool shutdown() noexcept;
  // Called by kEnableTorque when the bus reports an I/O error: reopen the port (may allocate).
  void set_reconnect(std::function<bool(std::string* why)> reconnect) { reconnect_ = std::move(reconnect); }

  // --- any thread ---
  std::uint64_t post(DriverRequest request, std::uint8_t servo_id);
  bool take_result(std::uint64_t ticket, RequestResult* out);
  // post(), then waits up to timeout_s for the loop (running in another thread) to run it.
  RequestResult call(DriverRequest request, std::uint8_t servo_id, double timeout_s);

  DriverState state() const noexcept { return state_.load(std::memory_order_acquire); }
  HoldReason hold_reason() const noexcept { return hold_reason_; }
  const Message& fault_reason() const noexcept { return fault_reason_; }
  const Message& last_fault() const noexcept { return last_fault_; }
  const JointCommandSource* active() const noexcept { return active_; }
  const Eigen::VectorXd& goal_rad() const noexcept { return goal_; }
  std::uint64_t failed_cycles() const noexcept { return failed_cycles_; }
  std::uint32_t consecutive_failed_cycles() const noexcept { return consecutive_failed_; }

  // Loop thread: hold the measured posture (kHolding, with the reason); fault with the reason.
  void hold(HoldReason reason) noexcept;
  void enter_fault(const char* reason) noexcept;

 private:
  struct PendingRequest {
    std::uint64_t ticket = 0;  // 0: none
    DriverRequest type = DriverRequest::kHold;
    std::uint8_t id = 0;
  };
  JointStateView view(bool pose_fresh) const noexcept {
    return {chain_.position_rad(), chain_.velocity_rad_s(), goal_, chain_.lower_rad(), chain_.upper_rad(), pose_fresh};
  }
  void hold_here() noexcept;  // hold posture = measured positions clamped to the limits; goals = it
  void take_off(StopCause cause) noexcept;  // the active source is taken off (deactivate)
  void set_state(DriverState s) noexcept { state_.store(s, std::memory_order_release); }
  void run_request(const PendingRequest& request) noexcept;
  bool enable_torque(Message& why) noexcept;
  void finish_request(std::uint64_t ticket, bool success, const char* fmt, ...) noexcept
      __attribute__((format(printf, 4, 5)));

  ServoChain& chain_;
  int max_failed_cycles_;
  SafeAction fault_action_, shutdown_action_;
  bool torque_on_start_;
  double max_joint_velocity_rad_s_;
  std::atomic<DriverState> state_{DriverState::kStopped};
  HoldReason hold_reason_ = HoldReason::kNone;
  Message fault_reason_{}, last_fault_{};
  JointCommandSource* active_ = nullptr;
  Eigen::VectorXd hold_, goal_, target_;
  std::uint64_t failed_cycles_ = 0;
  std::uint32_t consecutive_failed_ = 0;
  bool started_ = false;
  std::function<bool(std::string*)> reconnect_;

  std::mutex request_mutex_;
  PendingRequest pending_request_;
  std::uint64_t next_ticket_ = 1;
  // Written by the loop only, published by done_ticket_ (release); read after an acquire load.
  std::atomic<std::uint64_t> done_ticket_{0};
  bool done_success_ = false;
  Message done_message_{};
  std::mutex call_mutex_;  // one call() at a time
};

}  // namespace snake_autonomy::driver
