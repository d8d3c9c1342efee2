// DriverController: the driver's control loop, ROS-free: the composition of its layers
// (include/snake_autonomy/driver/), shaped as ros_control shapes drivers: read -> update -> write.
//
//   ServoChain         hardware: start-up checks, sync read into joint space (Transmissions),
//                      per-servo health, THE goal clamp (joint limits within the servo limits), write
//   GaitSource         a JointCommandSource: gait commands, CPG, steering law, stale-pose gating,
//                      command lifetime, CPG-state check
//   TrajectorySource   joint trajectories (command_trajectory), a JointCommandSource through
//                      TrajectoryCommand: checks, cubic interpolation from the present goals, progress
//   DriverSupervisor   Stopped / Holding / Running / Fault, the fault rules, the request mailbox,
//                      the active source; the one slew limit after whichever source is active
//   Kinematics         centre of mass, virtual chassis, bounding box, for whoever publishes
//
//   update(t_s, dt_s):  requests -> gait command -> trajectory -> base pose -> ServoChain::read (+ the slow status
//                       read) -> hardware errors -> active source -> slew limit -> clamp -> write
//                       -> fault rule on failed cycles -> forward kinematics
//
// States and rules: supervisor.hpp (states, faults, requests), gait_source.hpp (gait, gating,
// lifetime), servo_chain.hpp (clamp, health). Whatever a source says, a goal is never outside the
// joint's limits nor the servo's own position limits, never moves faster than
// max_joint_velocity_rad_s, and a non-finite value never becomes a command. Inputs are range-checked
// before they reach the loop: gait commands by GaitCommandResolver, base poses by check_base_pose.
//
// Joint trajectories: taken while Holding or Running, a trajectory becomes the active source (state
// kRunning; the CPG is not stepped: waves off; no command lifetime and no pose gate: it ends by
// itself), its goals through the same slew limit and clamp as the gait's. A fault, torque off, a
// hold request, a gait command or a newer trajectory ends it (progress: aborted, with the reason);
// at its end the driver holds the last point (kHolding, HoldReason::kTrajectoryDone). Each accepted
// trajectory ends with exactly one final status (pop_trajectory_final).
//
// Threads: start(), update() and shutdown() run on one thread (the loop). command_gait(),
// set_base_pose() and call() may be called from any other thread: they hand their data over through
// mutexes the loop only try_locks (never waits on), so no caller can block the loop; a handover
// missed by a failed try_lock is picked up the next cycle. update() never allocates and never throws.
#pragma once

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

#include "snake_autonomy/core/cpg.hpp"
#include "snake_autonomy/core/gait_library.hpp"
#include "snake_autonomy/core/kinematics.hpp"
#include "snake_autonomy/core/robot_model.hpp"
#include "snake_autonomy/driver/driver_config.hpp"
#include "snake_autonomy/driver/gait_command.hpp"
#include "snake_autonomy/driver/gait_source.hpp"
#include "snake_autonomy/driver/message.hpp"
#include "snake_autonomy/driver/safety_rules.hpp"
#include "snake_autonomy/driver/servo_chain.hpp"
#include "snake_autonomy/driver/supervisor.hpp"
#include "snake_autonomy/driver/trajectory_command.hpp"
#include "snake_autonomy/driver/trajectory_source.hpp"
#include "snake_autonomy/driver/transmission.hpp"
#include "snake_autonomy/dynamixel/control_table.hpp"
#include "snake_autonomy/dynamixel/servo_bus.hpp"

namespace snake_autonomy::driver {

// What the loop publishes: a copy made by fill_snapshot() into storage sized by make_snapshot().
struct DriverSnapshot {
  double t_s = 0.0;
  std::uint64_t cycle = 0;
  DriverState state = DriverState::kStopped;
  Message fault_reason{};       // the active fault ("" when none)
  Message last_fault{};         // the latest fault, kept after recovery
  Message gait{};               // the gait the loop runs (or would resume)
  bool pose_received = false;   // a base pose arrived at least once
  bool pose_fresh = false;      // the latest pose is younger than pose_timeout_s
  bool locomotion_gated = false;  // running, but held for the stale pose
  HoldReason hold_reason = HoldReason::kNone;  // why the driver holds (kNone unless kHolding)
  double command_age_s = 0.0;   // since the last gait command reached the loop (repeats included)
  Message pose_refusal{};       // why the latest refused base pose was refused ("" when none yet)
  Eigen::VectorXd position_rad, velocity_rad_s, effort_a, goal_rad;  // joint space
  std::vector<ServoDiagnostics> servos;
  // Kinematics from the latest base pose (identity before the first: for visualisation only).
  Eigen::Vector3d base_position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond base_orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  Eigen::Quaterniond com_orientation = Eigen::Quaterniond::Identity();  // virtual chassis
  Eigen::Vector3d bbox_span = Eigen::Vector3d::Zero();
  dynamixel::BusCounters bus;
  std::uint64_t failed_cycles = 0;
  std::uint32_t consecutive_failed_cycles = 0;
  std::uint64_t commands_applied = 0;
  std::uint64_t poses_refused = 0;
  driver::TrajectoryProgress trajectory;  // the latest joint trajectory (phase kIdle: none yet)
};

class DriverController {
 public:
  // Checks the configuration, the robot model and the servo mapping against the control table;
  // throws ConfigError listing every problem. The bus must outlive the controller.
  DriverController(const core::RobotModel& model, const core::GaitLibrary& gaits, const dynamixel::ControlTable& table,
                   dynamixel::ServoBus& bus, const DriverConfig& config);

  // --- loop thread (or before the loop starts / after it stopped) ---
  // ServoChain::start() (model number, operating mode, position limits, Return Delay Time, hardware
  // error status, present position): throws ConfigError listing every servo that fails; start_notes()
  // says what was changed or could not be. Then: torque on and kHolding (torque_on_start), or
  // kStopped; kFault when a servo reports a hardware error.
  void start(double t_s);
  const std::vector<std::string>& start_notes() const noexcept { return start_notes_; }
  // One cycle (see the file comment). Returns false when the cycle failed (a missing reply or a
  // failed write). dt_s is clamped to [0, max_step_s].
  bool update(double t_s, double dt_s) noexcept;
  // Leaves the servos as config.shutdown_action says (hold: goals = present positions; torque_off).
  // Returns false when the bus did not take the write.
  bool shutdown() noexcept;
  // Called by a kEnableTorque request when the bus reports an I/O error (the port went away: an
  // unplugged adapter, the mock restarted): reopen the port, return false with a reason if it cannot.
  // Runs on the loop thread, only then (a recovery path: it may allocate and take milliseconds).
  void set_reconnect(std::function<bool(std::string* why)> reconnect) {
    supervisor_.set_reconnect(std::move(reconnect));
  }
  // Copies the loop's outputs; `out` must come from make_snapshot() (no allocation then).
  void fill_snapshot(DriverSnapshot& out) const noexcept;
  DriverSnapshot make_snapshot() const;

  // --- any thread ---
  // Resolves and hands over a gait command. Returns "" when accepted, else every reason (the
  // running gait is untouched). Refused as well while torque is off or in a fault.
  std::string command_gait(const GaitCommandRequest& command);
  // A base pose received at t_s (the loop's clock). False (ignored, counted, the reason kept for the
  // snapshot) when check_base_pose refuses it: not finite, outside pose_workspace_m, or a quaternion
  // whose norm is not 1 within quaternion_norm_tolerance; accepted quaternions are normalised.
  bool set_base_pose(double t_s, const Eigen::Vector3d& position, const Eigen::Quaterniond& orientation) noexcept;
  // Posts a request that the loop runs at its next update(), and waits for its result up to
  // timeout_s (the loop must be running in another thread). `servo_id` is for kRebootServo.
  RequestResult call(DriverRequest request, std::uint8_t servo_id, double timeout_s) {
    return supervisor_.call(request, servo_id, timeout_s);
  }
  // Non-blocking halves of call() (tests drive the loop themselves): post, update(), take.
  std::uint64_t post(DriverRequest request, std::uint8_t servo_id) { return supervisor_.post(request, servo_id); }
  bool take_result(std::uint64_t ticket, RequestResult* out) { return supervisor_.take_result(ticket, out); }

  // Joint trajectories (driver::TrajectorySource; any thread). Checks the request's static part and
  // hands it over; the loop takes it at its next update(). "" when accepted, else every reason (the
  // robot is untouched). Refused while torque is off or in a fault. The first segment (present
  // posture -> point 0) is checked when the loop takes it: the progress says if it was refused then.
  std::string command_trajectory(const driver::JointTrajectoryRequest& request);
  std::uint64_t trajectories_accepted() const noexcept { return trajectories_accepted_.load(); }
  std::uint64_t trajectories_refused() const noexcept { return trajectories_refused_.load(); }
  std::string last_trajectory_refusal() const;
  const driver::TrajectoryProgress& trajectory_progress() const noexcept { return trajectory_.progress(); }  // loop
  // Every accepted trajectory's final status, exactly once (done; aborted with the reason; superseded,
  // naming the trajectory that replaced it): driver::TrajectorySource::pop_final. Any ONE consumer
  // thread (the node's publisher thread), lock-free. finals_dropped: lost to a full queue (counted).
  bool pop_trajectory_final(driver::TrajectoryProgress* out) noexcept { return trajectory_.pop_final(out); }
  std::uint64_t trajectory_finals_dropped() const noexcept { return trajectory_.finals_dropped(); }

  DriverState state() const noexcept { return supervisor_.state(); }
  std::uint64_t commands_accepted() const noexcept { return gait_.commands_accepted(); }
  std::uint64_t commands_refused() const noexcept { return gait_.commands_refused(); }
  std::string last_refusal() const { return gait_.last_refusal(); }
  std::string commanded_gait() const { return gait_.commanded_gait(); }

  const core::RobotModel& model() const noexcept { return model_; }
  const DriverConfig& config() const noexcept { return config_; }
  const dynamixel::ControlTable& table() const noexcept { return table_; }
  const std::vector<std::uint8_t>& ids() const noexcept { return chain_.ids(); }
  // Loop-thread views (tests).
  const Eigen::VectorXd& position_rad() const noexcept { return chain_.position_rad(); }
  const Eigen::VectorXd& goal_rad() const noexcept { return supervisor_.goal_rad(); }
  const std::vector<ServoDiagnostics>& servos() const noexcept { return chain_.servos(); }
  const core::KinematicState& kinematics() const noexcept { return kin_state_; }
  const core::Cpg& cpg() const noexcept { return gait_.cpg(); }
  bool pose_fresh() const noexcept { return pose_fresh_; }
  bool locomotion_gated() const noexcept { return gait_.gated(); }
  const char* fault_reason() const noexcept { return supervisor_.fault_reason().data(); }
  HoldReason hold_reason() const noexcept { return supervisor_.hold_reason(); }
  // The layers (tests, tools).
  const driver::ServoChain& chain() const noexcept { return chain_; }
  const driver::DriverSupervisor& supervisor() const noexcept { return supervisor_; }
  const driver::GaitSource& gait_source() const noexcept { return gait_; }

  // Joint angle <-> servo ticks with the servo's direction and zero offset (no clamping).
  double ticks_to_joint_rad(int joint, std::int32_t ticks) const noexcept {
    return chain_.transmission(joint).ticks_to_joint_rad(ticks);
  }
  bool joint_rad_to_ticks(int joint, double rad, std::int32_t* ticks) const noexcept {
    return chain_.transmission(joint).joint_rad_to_ticks(rad, ticks);
  }

 private:
  friend struct DriverControllerTestAccess;  // tests only (test/cpp): reaches the gait source's CPG

  void take_pose(double t_s) noexcept;
  void take_trajectory(double t_s) noexcept;  // a pending trajectory becomes the active source

  core::RobotModel model_;
  dynamixel::ControlTable table_;
  DriverConfig config_;
  driver::ServoChain chain_;
  driver::DriverSupervisor supervisor_;
  driver::GaitSource gait_;
  driver::TrajectorySource trajectory_;
  driver::TrajectoryCommand trajectory_command_;
  mutable std::mutex trajectory_refusal_mutex_;
  std::string last_trajectory_refusal_;
  std::atomic<std::uint64_t> trajectories_accepted_{0}, trajectories_refused_{0};
  std::vector<std::string> start_notes_;
  std::uint64_t cycle_ = 0, commands_applied_ = 0;
  bool started_ = false;
  double t_s_ = 0.0;

  // Base pose and kinematics.
  core::Kinematics kinematics_;
  core::KinematicState kin_state_;
  Eigen::Vector3d base_p_ = Eigen::Vector3d::Zero();
  Eigen::Quaterniond base_q_ = Eigen::Quaterniond::Identity();
  double pose_t_s_ = 0.0;
  std::uint64_t pose_seq_seen_ = 0;
  bool pose_received_ = false, pose_fresh_ = false;

  // The base pose handover (the loop only try_locks it).
  std::mutex pose_mutex_;
  Eigen::Vector3d pending_p_ = Eigen::Vector3d::Zero();
  Eigen::Quaterniond pending_q_ = Eigen::Quaterniond::Identity();
  double pending_pose_t_s_ = 0.0;
  std::uint64_t pose_seq_ = 0;
  std::atomic<std::uint64_t> poses_refused_{0};
  Message pending_pose_refusal_{}, pose_refusal_{};  // under pose_mutex_ / the loop's copy
};

}  // namespace snake_autonomy::driver
