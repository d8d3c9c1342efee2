// DriverController: the driver's control loop, ROS-free. One step function, called by the loop
// thread at a fixed rate:
//
//   update(t_s, dt_s):  requests (torque, hold, reboot) -> gait command -> base pose
//                       -> one sync read of current/velocity/position of every servo -> joint state
//                       -> fault checks -> CPG step -> goal ticks clamped to the limits -> one sync write
//                       -> forward kinematics (centre of mass, virtual chassis, bounding box)
//
// States (DriverState):
//   kStopped  torque off (at start when torque_on_start is false, or by request). No goals are written.
//   kHolding  torque on, goals frozen at the posture the robot had when it stopped. The state after
//             start, after recovery, after a hold request and when the running gait's last command
//             is older than command_timeout_s (hold_reason() says which); a gait command (a repeat
//             of the last one included) starts locomotion.
//   kRunning  the CPG drives the goals. With a stale base pose (no pose for pose_timeout_s, or none
//             yet; ERRATA #7) the CPG amplitudes go to zero (the waves decay, critically damped:
//             locomotion stops, posture held) and the commanded gait resumes with fresh poses.
//   kFault    latched after max_failed_cycles consecutive failed cycles (a missing, corrupt or
//             implausible reply, or a failed write) or any hardware error: the fault action is applied
//             (hold: goals frozen at the present positions; torque_off) and the reason kept. Leave it
//             with request kEnableTorque (which checks every servo first) after rebooting a servo
//             that reported a hardware error (kRebootServo). The CPG's state is checked every cycle:
//             if it is ever not finite the supervisor faults ("CPG state not finite").
// A failed cycle keeps the last good state of the servos that did not answer (flagged stale).
//
// Whatever the CPG or a command says, a goal is never outside the joint's limits (robot YAML) nor
// the servo's own position limits (read at start), never moves faster than max_joint_velocity_rad_s,
// and a non-finite value never becomes a command. Inputs are range-checked before they reach the
// loop: gait commands by GaitCommandResolver, base poses by check_base_pose (safety_rules.hpp).
//
// Joint trajectories (command_trajectory, driver::TrajectorySource): taken while Holding or Running,
// a trajectory becomes the goal source (state kRunning, the CPG no longer stepped: waves off; no
// command lifetime and no pose gate: it ends by itself), its goals through the same slew limit and
// clamp as the gait's. A fault, torque off, a hold request, a gait command or a newer trajectory
// ends it (progress: aborted, with the reason); at its end the driver holds the last point
// (kHolding, HoldReason::kTrajectoryDone).
//
// Threads: start(), update() and shutdown() run on one thread (the loop). command_gait(),
// set_base_pose() and call() may be called from any other thread: they hand their data over through
// mutexes the loop only try_locks (never waits on), so no caller can block the loop; a handover
// missed by a failed try_lock is picked up the next cycle. update() never allocates and never throws.
#pragma once

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

#include "snake_autonomy/core/cpg.hpp"
#include "snake_autonomy/core/driver_config.hpp"
#include "snake_autonomy/core/gait_command.hpp"
#include "snake_autonomy/core/gait_library.hpp"
#include "snake_autonomy/core/kinematics.hpp"
#include "snake_autonomy/core/robot_model.hpp"
#include "snake_autonomy/core/safety_rules.hpp"
#include "snake_autonomy/driver/trajectory_source.hpp"
#include "snake_autonomy/driver/transmission.hpp"
#include "snake_autonomy/dynamixel/control_table.hpp"
#include "snake_autonomy/dynamixel/servo_bus.hpp"

namespace snake_autonomy::core {

enum class DriverState : std::uint8_t { kStopped, kHolding, kRunning, kFault };
const char* to_string(DriverState state) noexcept;

// A fixed-size text (no allocation when copied or written in the loop).
using Message = std::array<char, 256>;

enum class DriverRequest : std::uint8_t { kEnableTorque, kDisableTorque, kHold, kRebootServo };
const char* to_string(DriverRequest request) noexcept;

struct RequestResult {
  bool success = false;
  std::string message;
};

// Per servo, for diagnostics.
struct ServoDiagnostics {
  std::uint8_t id = 0;
  bool stale = true;                      // the last cycle had no usable reply: values are the last good ones
  std::uint32_t consecutive_misses = 0;
  std::uint64_t timeouts = 0;             // missed replies
  std::uint64_t crc_errors = 0;
  std::uint64_t implausible = 0;          // valid CRC, impossible values (garbage)
  std::uint64_t other_errors = 0;         // malformed, wrong ID, servo error, I/O error
  bool hardware_error = false;            // the alert bit was seen since the last enable/reboot
  std::uint8_t hardware_error_bits = 0;   // Hardware Error Status (address 70) as last read
  double temperature_c = std::nan("");    // NaN until read
  double voltage_v = std::nan("");
  std::int32_t present_ticks = 0;
  std::int32_t goal_ticks = 0;
  std::int32_t min_ticks = 0, max_ticks = 0;  // the goal clamp: joint limits within the servo's limits
};

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
  DriverController(const RobotModel& model, const GaitLibrary& gaits, const dynamixel::ControlTable& table,
                   dynamixel::ServoBus& bus, const DriverConfig& config);

  // --- loop thread (or before the loop starts / after it stopped) ---
  // Talks to every servo: model number, operating mode (position control), position limits,
  // hardware error status, present position. Throws ConfigError listing every servo that fails.
  // Then: torque on and kHolding (torque_on_start), or kStopped; kFault when a servo reports a
  // hardware error.
  // Before that, each servo's Return Delay Time is set to config.return_delay_time_us where it differs
  // (EEPROM: only while the servo's torque is off) and the bus's reply deadlines allow for the
  // slowest servo; start_notes() says what was changed or could not be.
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
  void set_reconnect(std::function<bool(std::string* why)> reconnect) { reconnect_ = std::move(reconnect); }
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
  RequestResult call(DriverRequest request, std::uint8_t servo_id, double timeout_s);
  // Non-blocking halves of call() (tests drive the loop themselves): post, update(), take.
  std::uint64_t post(DriverRequest request, std::uint8_t servo_id);
  bool take_result(std::uint64_t ticket, RequestResult* out);

  // ---- Joint trajectory execution (driver::TrajectorySource; any thread) ----
  // Checks the request's static part and hands it over; the loop takes it at its next update().
  // "" when accepted, else every reason (the robot is untouched). Refused while torque is off or in
  // a fault. The first segment (present posture -> point 0) is checked when the loop takes it:
  // fill_snapshot()'s trajectory progress says if it was refused then.
  std::string command_trajectory(const driver::JointTrajectoryRequest& request);
  std::uint64_t trajectories_accepted() const noexcept { return trajectories_accepted_.load(); }
  std::uint64_t trajectories_refused() const noexcept { return trajectories_refused_.load(); }
  std::string last_trajectory_refusal() const;
  const driver::TrajectoryProgress& trajectory_progress() const noexcept { return trajectory_.progress(); }  // loop
  // ---- end of joint trajectory execution ----

  DriverState state() const noexcept { return state_.load(std::memory_order_acquire); }
  std::uint64_t commands_accepted() const noexcept { return commands_accepted_.load(); }
  std::uint64_t commands_refused() const noexcept { return commands_refused_.load(); }
  std::string last_refusal() const;
  std::string commanded_gait() const;

  const RobotModel& model() const noexcept { return model_; }
  const DriverConfig& config() const noexcept { return config_; }
  const dynamixel::ControlTable& table() const noexcept { return table_; }
  const std::vector<std::uint8_t>& ids() const noexcept { return ids_; }
  // Loop-thread views (tests).
  const Eigen::VectorXd& position_rad() const noexcept { return position_; }
  const Eigen::VectorXd& goal_rad() const noexcept { return goal_rad_; }
  const std::vector<ServoDiagnostics>& servos() const noexcept { return diag_; }
  const KinematicState& kinematics() const noexcept { return kin_state_; }
  const Cpg& cpg() const noexcept { return cpg_; }
  bool pose_fresh() const noexcept { return pose_fresh_; }
  bool locomotion_gated() const noexcept { return gated_; }
  const char* fault_reason() const noexcept { return fault_reason_.data(); }
  HoldReason hold_reason() const noexcept { return hold_reason_; }

  // Joint angle <-> servo ticks with the servo's direction and zero offset (no clamping): tx_[joint].
  double ticks_to_joint_rad(int joint, std::int32_t ticks) const noexcept;
  bool joint_rad_to_ticks(int joint, double rad, std::int32_t* ticks) const noexcept;

 private:
  friend struct DriverControllerTestAccess;  // tests only (test/cpp): reaches the CPG to corrupt it

  struct PendingRequest {
    std::uint64_t ticket = 0;  // 0: none
    DriverRequest type = DriverRequest::kHold;
    std::uint8_t id = 0;
  };

  // The steps of update().
  void take_request() noexcept;
  void take_gait() noexcept;
  void take_pose(double t_s) noexcept;
  bool read_feedback() noexcept;  // false: a servo had no usable reply or the bus failed
  void read_status() noexcept;
  void check_hardware_errors() noexcept;
  void step_cpg(double dt_s) noexcept;  // faults when the CPG state is not finite
  void compute_goals(double dt_s) noexcept;
  bool write_goals() noexcept;
  bool write_torque(bool on) noexcept;
  void run_kinematics() noexcept;
  void take_trajectory(double t_s) noexcept;  // a pending trajectory becomes the goal source
  void step_trajectory(double t_s) noexcept;  // its goals; ends it when the state no longer allows it
  void trajectory_yields_to_gait() noexcept;  // a gait command ends a running trajectory

  void enter_fault(const char* reason) noexcept;
  void hold_here() noexcept;  // hold posture = measured positions clamped to the limits
  void hold_for(HoldReason reason) noexcept;  // hold_here() and kHolding, with the reason
  bool start_locomotion() noexcept;  // false: the CPG could not restart (fault entered)
  void apply_gait() noexcept;  // nominal or gated targets into the CPG
  void finish_request(std::uint64_t ticket, bool success, const char* fmt, ...) noexcept
      __attribute__((format(printf, 4, 5)));
  void run_request(const PendingRequest& request) noexcept;
  bool enable_torque(Message& why) noexcept;
  void set_state(DriverState s) noexcept { state_.store(s, std::memory_order_release); }
  int joint_of(std::uint8_t id) const noexcept;
  void describe_bits(std::uint8_t bits, char* out, std::size_t size) const noexcept;
  std::int32_t clamp_goal(int joint, std::int32_t ticks) const noexcept;
  void set_limits(int joint, std::int32_t servo_min_ticks, std::int32_t servo_max_ticks) noexcept;
  // Reads servo j's Return Delay Time, writes the configured one where it differs; returns the
  // servo's delay in microseconds afterwards (problems: a failed read).
  int settle_return_delay(int j, const std::string& name, std::vector<std::string>& problems);
  void goals_from_rad() noexcept;  // goal_rad_ -> clamped goal ticks -> the write buffer

  RobotModel model_;
  dynamixel::ControlTable table_;
  dynamixel::UnitScales scales_;
  dynamixel::ServoBus& bus_;
  DriverConfig config_;
  int n_;
  std::vector<std::uint8_t> ids_;
  std::vector<driver::Transmission> tx_;  // one per joint: the only tick <-> radian conversion
  std::uint16_t addr_torque_ = 0, addr_hw_error_ = 0, addr_mode_ = 0, addr_min_pos_ = 0, addr_max_pos_ = 0;
  std::uint16_t addr_return_delay_ = 0;
  std::vector<std::string> start_notes_;
  std::uint16_t addr_status_ = 0, status_bytes_ = 0, voltage_offset_ = 0, voltage_bytes_ = 2, temperature_offset_ = 0;

  // Bus buffers, sized in the constructor.
  std::vector<std::uint8_t> feedback_, status_, goals_, torque_;
  std::vector<dynamixel::ServoReply> replies_, status_replies_;

  // Joint state and goals.
  Eigen::VectorXd position_, velocity_, effort_, goal_rad_, hold_rad_, zeros_;
  Eigen::VectorXd lo_rad_, hi_rad_;  // the goal clamp in joint space
  std::vector<std::int32_t> servo_min_ticks_, servo_max_ticks_;  // the servos' own position limits
  std::vector<std::uint8_t> hw_bits_known_;  // Hardware Error Status read since the alert
  std::vector<ServoDiagnostics> diag_;
  std::atomic<DriverState> state_{DriverState::kStopped};
  Message fault_reason_{}, last_fault_{}, gait_name_{};
  std::uint64_t cycle_ = 0, failed_cycles_ = 0, commands_applied_ = 0;
  std::uint32_t consecutive_failed_ = 0;
  bool started_ = false;
  std::function<bool(std::string*)> reconnect_;
  double t_s_ = 0.0;

  // Gait.
  Cpg cpg_;
  GaitParameters nominal_, effective_;
  bool gated_ = false;
  HoldReason hold_reason_ = HoldReason::kNone;
  double last_command_t_s_ = 0.0;  // loop clock

  // Base pose and kinematics.
  Kinematics kinematics_;
  KinematicState kin_state_;
  Eigen::Vector3d base_p_ = Eigen::Vector3d::Zero();
  Eigen::Quaterniond base_q_ = Eigen::Quaterniond::Identity();
  double pose_t_s_ = 0.0;
  std::uint64_t pose_seq_seen_ = 0;
  bool pose_received_ = false, pose_fresh_ = false;

  // Handovers from other threads (the loop only try_locks these).
  std::mutex gait_mutex_;
  GaitParameters pending_gait_;
  Message pending_gait_name_{};
  bool gait_pending_ = false;

  std::mutex pose_mutex_;
  Eigen::Vector3d pending_p_ = Eigen::Vector3d::Zero();
  Eigen::Quaterniond pending_q_ = Eigen::Quaterniond::Identity();
  double pending_pose_t_s_ = 0.0;
  std::uint64_t pose_seq_ = 0;
  std::atomic<std::uint64_t> poses_refused_{0};
  Message pending_pose_refusal_{}, pose_refusal_{};  // under pose_mutex_ / the loop's copy

  std::mutex request_mutex_;
  PendingRequest pending_request_;
  std::uint64_t next_ticket_ = 1;
  // Written by the loop only, published by done_ticket_ (release); read after an acquire load.
  std::atomic<std::uint64_t> done_ticket_{0};
  bool done_success_ = false;
  Message done_message_{};
  std::mutex call_mutex_;  // one call() at a time

  // Command resolution (callers' threads only).
  mutable std::mutex resolver_mutex_;
  GaitCommandResolver resolver_;
  std::string last_refusal_;
  std::atomic<std::uint64_t> commands_accepted_{0}, commands_refused_{0};

  // Joint trajectory execution: the source owns its mailbox (the loop only try_locks it).
  driver::TrajectorySource trajectory_;
  Eigen::VectorXd trajectory_goal_;
  mutable std::mutex trajectory_refusal_mutex_;
  std::string last_trajectory_refusal_;
  std::atomic<std::uint64_t> trajectories_accepted_{0}, trajectories_refused_{0};
};

}  // namespace snake_autonomy::core
