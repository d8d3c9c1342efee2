#include "snake_autonomy/driver/driver_controller.hpp"

#include <algorithm>
#include <cmath>

namespace snake_autonomy::driver {

namespace {

// Every problem of the configuration, the robot model and the control table, or the config itself.
const DriverConfig& checked(const core::RobotModel& model, const dynamixel::ControlTable& table,
                            const DriverConfig& config) {
  std::vector<std::string> errors = config.validate();
  for (const auto& e : model.validate()) errors.push_back("robot: " + e);
  for (const auto& e : table.validate()) errors.push_back("control table: " + e);
  if (model.servos.model != table.model)
    errors.push_back("robot servos.model: '" + model.servos.model + "' but the control table is '" + table.model + "'");
  for (const auto& e : driver::ServoChain::check_table(table)) errors.push_back(e);
  if (!errors.empty()) {
    std::string what = "driver configuration:";
    for (const auto& e : errors) what += "\n  " + e;
    throw core::ConfigError(what);
  }
  return config;
}

// The trajectory source's limits: the joints' (refined to the goal clamp once the servos are known),
// a tolerance of one servo tick (the clamp is the joint limits rounded inwards to whole ticks: a point
// on a joint limit is within a tick of it, and the clamp applies), the slew limit, the capacity.
driver::TrajectoryLimits trajectory_limits(const core::RobotModel& model, const dynamixel::ControlTable& table,
                                           const DriverConfig& config) {
  driver::TrajectoryLimits l;
  l.lower_rad = Eigen::VectorXd::Map(model.joint_lower_rad.data(), model.num_joints);
  l.upper_rad = Eigen::VectorXd::Map(model.joint_upper_rad.data(), model.num_joints);
  l.limit_tolerance_rad = table.unit_scales().rad_per_tick;
  l.max_velocity_rad_s = config.max_joint_velocity_rad_s;
  l.max_points = config.max_trajectory_points;
  l.max_duration_s = config.max_trajectory_duration_s;
  return l;
}

}  // namespace

DriverController::DriverController(const core::RobotModel& model, const core::GaitLibrary& gaits,
                                   const dynamixel::ControlTable& table, dynamixel::ServoBus& bus,
                                   const DriverConfig& config)
    : model_(model),
      table_(table),
      config_(checked(model, table, config)),
      chain_(model_, table_, bus, config_),
      supervisor_(chain_, config_),
      gait_(model_, gaits, config_),
      trajectory_(model_.num_joints, trajectory_limits(model_, table_, config_)),
      trajectory_command_(trajectory_),
      kinematics_(model_),
      kin_state_(model_.num_frames()) {
  trajectory_.set_joint_limits(chain_.lower_rad(), chain_.upper_rad());
}

void DriverController::start(double t_s) {
  driver::ChainStartReport report = chain_.start();
  if (!report.problems.empty()) {
    std::string what = "servo bus at start:";
    for (const auto& p : report.problems) what += "\n  " + p;
    throw core::ConfigError(what);
  }
  start_notes_ = std::move(report.notes);
  trajectory_.set_joint_limits(chain_.lower_rad(), chain_.upper_rad());  // with the servos' own limits
  started_ = true;
  t_s_ = t_s;
  gait_.reset_clock(t_s);
  supervisor_.begin(report);
}

bool DriverController::shutdown() noexcept { return !started_ || supervisor_.shutdown(); }

// ---------------------------------------------------------------------------------------------
// The cycle: read -> update -> write

bool DriverController::update(double t_s, double dt_s) noexcept {
  if (!started_) return false;
  ++cycle_;
  t_s_ = t_s;
  dt_s = std::isfinite(dt_s) ? std::clamp(dt_s, 0.0, config_.max_step_s) : 0.0;

  supervisor_.take_request();
  if (gait_.take_command(t_s)) {
    bool was_active = false;
    if (supervisor_.command(gait_, t_s, pose_fresh_, &was_active)) {
      if (was_active) gait_.apply();
      ++commands_applied_;
    }
  }
  take_trajectory(t_s);
  take_pose(t_s);

  const bool read_ok = chain_.read();
  if (config_.status_every_cycles > 0 && cycle_ % static_cast<std::uint64_t>(config_.status_every_cycles) == 0)
    chain_.read_status();
  supervisor_.check_hardware_errors();

  const bool write_ok = supervisor_.drive(t_s, dt_s, pose_fresh_);
  const bool ok = supervisor_.count_cycle(read_ok, write_ok);
  kinematics_.compute(base_p_, base_q_, chain_.position_rad(), kin_state_);
  return ok;
}

// ---------------------------------------------------------------------------------------------
// Commands and base pose (callers' threads)

std::string DriverController::command_gait(const GaitCommandRequest& command) {
  return gait_.command(command, supervisor_.command_refusal());
}

bool DriverController::set_base_pose(double t_s, const Eigen::Vector3d& position,
                                     const Eigen::Quaterniond& orientation) noexcept {
  Eigen::Quaterniond unit = Eigen::Quaterniond::Identity();
  const PoseRefusal why =
      check_base_pose(t_s, position, orientation, config_.pose_workspace_m, config_.quaternion_norm_tolerance, &unit);
  std::lock_guard<std::mutex> lock(pose_mutex_);
  if (why != PoseRefusal::kNone) {
    ++poses_refused_;
    describe_pose_refusal(why, t_s, position, orientation, config_.pose_workspace_m, config_.quaternion_norm_tolerance,
                          pending_pose_refusal_.data(), pending_pose_refusal_.size());
    return false;
  }
  pending_p_ = position;
  pending_q_ = unit;
  pending_pose_t_s_ = t_s;
  ++pose_seq_;
  return true;
}

void DriverController::take_pose(double t_s) noexcept {
  if (pose_mutex_.try_lock()) {
    if (pose_seq_ != pose_seq_seen_) {
      pose_seq_seen_ = pose_seq_;
      base_p_ = pending_p_;
      base_q_ = pending_q_;
      pose_t_s_ = pending_pose_t_s_;
      pose_received_ = true;
    }
    pose_refusal_ = pending_pose_refusal_;
    pose_mutex_.unlock();
  }
  pose_fresh_ = pose_received_ && (t_s - pose_t_s_) <= config_.pose_timeout_s;
}

// ---------------------------------------------------------------------------------------------
// Snapshot

DriverSnapshot DriverController::make_snapshot() const {
  DriverSnapshot s;
  const int n = model_.num_joints;
  s.position_rad = s.velocity_rad_s = s.effort_a = s.goal_rad = Eigen::VectorXd::Zero(n);
  s.servos.assign(static_cast<std::size_t>(n), ServoDiagnostics{});
  return s;
}

void DriverController::fill_snapshot(DriverSnapshot& out) const noexcept {
  out.t_s = t_s_;
  out.cycle = cycle_;
  out.state = state();
  out.fault_reason = supervisor_.fault_reason();
  out.last_fault = supervisor_.last_fault();
  out.gait = gait_.gait_name();
  out.pose_received = pose_received_;
  out.pose_fresh = pose_fresh_;
  out.locomotion_gated = out.state == DriverState::kRunning && supervisor_.active() == &gait_ && gait_.gated();
  out.hold_reason = out.state == DriverState::kHolding ? supervisor_.hold_reason() : HoldReason::kNone;
  out.command_age_s = gait_.command_age_s(t_s_);
  out.pose_refusal = pose_refusal_;
  out.position_rad = chain_.position_rad();
  out.velocity_rad_s = chain_.velocity_rad_s();
  out.effort_a = chain_.effort_a();
  out.goal_rad = supervisor_.goal_rad();
  const auto& servos = chain_.servos();
  if (out.servos.size() == servos.size()) std::copy(servos.begin(), servos.end(), out.servos.begin());
  out.base_position = base_p_;
  out.base_orientation = base_q_;
  out.com = kin_state_.com;
  out.com_orientation = Eigen::Quaterniond(kin_state_.vc_rotation);
  out.bbox_span = kin_state_.bbox_span;
  out.bus = chain_.bus_counters();
  out.failed_cycles = supervisor_.failed_cycles();
  out.consecutive_failed_cycles = supervisor_.consecutive_failed_cycles();
  out.commands_applied = commands_applied_;
  out.poses_refused = poses_refused_.load();
  out.trajectory = trajectory_.progress();
}

// ---------------------------------------------------------------------------------------------
// Joint trajectories

std::string DriverController::command_trajectory(const driver::JointTrajectoryRequest& request) {
  std::string why = supervisor_.command_refusal();
  if (!why.empty()) {
    const std::string more = trajectory_.check(request);
    if (!more.empty()) why += "\n" + more;
  } else {
    why = trajectory_.submit(request);
  }
  if (why.empty()) {
    ++trajectories_accepted_;
  } else {
    ++trajectories_refused_;
    std::lock_guard<std::mutex> lock(trajectory_refusal_mutex_);
    last_trajectory_refusal_ = why;
  }
  return why;
}

std::string DriverController::last_trajectory_refusal() const {
  std::lock_guard<std::mutex> lock(trajectory_refusal_mutex_);
  return last_trajectory_refusal_;
}

void DriverController::take_trajectory(double t_s) noexcept {
  const DriverState s = state();
  const bool allowed = s == DriverState::kHolding || s == DriverState::kRunning;
  // From the goals commanded now (no step in the command); refused at take: the robot as it was.
  if (!trajectory_.take(t_s, supervisor_.goal_rad(), allowed) || !trajectory_.running()) return;
  bool was_active = false;  // a newer trajectory replaces the running one inside the source
  supervisor_.command(trajectory_command_, t_s, pose_fresh_, &was_active);
}

}  // namespace snake_autonomy::driver
