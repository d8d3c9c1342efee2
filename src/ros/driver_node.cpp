// driver_node: the 100 Hz driver of the snake. Wiring only: parameters, topics, services, TF,
// diagnostics and the loop thread around driver::DriverController (the ROS-free step function).
//
// Threads:
//  - the loop thread: LoopTimer (absolute deadlines on the steady clock, overruns counted) ->
//    controller.update() -> snapshot. It never allocates, never logs and never waits on a lock: it
//    hands the snapshot over with try_lock (a missed handover is simply the next cycle's).
//    Real-time mode (~realtime_priority > 0): before its first cycle the loop thread asks for SCHED_FIFO
//    at that priority and locks the process's memory (driver::enter_realtime); what it got is logged
//    (a warning naming what was refused, e.g. EPERM, and the loop carries on with normal scheduling) and
//    reported in the "loop" diagnostics (realtime, memory_locked).
//  - the publisher thread: takes each new snapshot and publishes joint_states, TF, com_pose,
//    bound_state and, every diagnostics_period_s, /diagnostics (diagnostic_updater tasks: loop,
//    locomotion, bus, one per servo, and the rate and stamps of joint_states and com_pose, the 100 Hz
//    topics, as TopicDiagnostic); it also logs state changes and
//    throttled overrun warnings. Publishing (serialisation, socket writes, their allocations) is kept
//    off the loop thread: realtime_tools is not packaged for Debian, and a roscpp publish() from the
//    loop would put its locks and allocations in the 100 Hz path. Messages are preallocated and
//    reused; the snapshot is copied into storage of the same size (no allocation either).
//  - driver/joint_trajectory and driver/trajectory_status: TrajectoryTopics (trajectory_topics.hpp).
//  - two spinner threads for callbacks and services: they hand data to the controller through its
//    try-lock mailboxes; a service waits (in its own thread) for the loop to run the request.
#include <diagnostic_updater/diagnostic_updater.h>
#include <diagnostic_updater/publisher.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <snake_autonomy/BoundState.h>
#include <snake_autonomy/GaitCommand.h>
#include <snake_autonomy/RebootServo.h>
#include <std_srvs/SetBool.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/transform_broadcaster.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>

#include "driver_diagnostics.hpp"
#include "driver_params.hpp"
#include "snake_autonomy/core/gait_library.hpp"
#include "snake_autonomy/core/robot_model.hpp"
#include "snake_autonomy/driver/driver_controller.hpp"
#include "snake_autonomy/driver/loop_timer.hpp"
#include "snake_autonomy/driver/realtime.hpp"
#include "snake_autonomy/dynamixel/control_table.hpp"
#include "snake_autonomy/dynamixel/serial_bus.hpp"
#include "trajectory_topics.hpp"

namespace core = snake_autonomy::core;
namespace driver = snake_autonomy::driver;
namespace dxl = snake_autonomy::dynamixel;
using snake_autonomy::ros_driver::DriverNodeConfig;
using snake_autonomy::ros_driver::fixed;
using snake_autonomy::ros_driver::kv;
using snake_autonomy::ros_driver::str;
using Clock = std::chrono::steady_clock;

namespace {

// What the loop hands to the publisher each cycle.
struct LoopSnapshot {
  driver::DriverSnapshot driver;
  driver::LoopStats loop;
  Clock::time_point taken{};
  std::uint64_t seq = 0;
};

std::string join(const std::vector<std::string>& lines) {
  std::string out;
  for (const auto& l : lines) out += "\n  " + l;
  return out;
}

class DriverNode {
 public:
  DriverNode(ros::NodeHandle& nh, const DriverNodeConfig& config, const core::RobotModel& model, dxl::SerialBus& bus,
             driver::DriverController& controller)
      : nh_(nh), config_(config), model_(model), bus_(bus), controller_(controller), epoch_(Clock::now()) {
    for (auto* s : {&work_, &shared_, &published_}) s->driver = controller_.make_snapshot();
    joint_states_.name = model_.joint_names();
    const auto n = static_cast<std::size_t>(model_.num_joints);
    joint_states_.position.resize(n);
    joint_states_.velocity.resize(n);
    // JointState.effort in N*m (sensor_msgs, revolute joints): present current x the control table's
    // torque constant (config/dynamixel/<model>.yaml says its source); none without a constant.
    torque_constant_ = controller_.table().torque_constant_nm_per_a;
    joint_states_.effort.resize(torque_constant_ > 0.0 ? n : 0);
    transforms_.resize(2);
    transforms_[0].header.frame_id = transforms_[1].header.frame_id = config_.world_frame;
    transforms_[0].child_frame_id = config_.base_frame;
    transforms_[1].child_frame_id = config_.com_frame;
    com_pose_.header.frame_id = config_.world_frame;
    bound_state_.header.frame_id = config_.world_frame;

    joint_states_pub_ = nh_.advertise<sensor_msgs::JointState>("joint_states", 10);
    com_pose_pub_ = nh_.advertise<geometry_msgs::PoseStamped>("com_pose", 10);
    bound_state_pub_ = nh_.advertise<snake_autonomy::BoundState>("bound_state", 10);
    setup_diagnostics();
    trajectory_topics_ = std::make_unique<snake_autonomy::ros_driver::TrajectoryTopics>(nh_, controller_, *updater_);
    pose_sub_ = nh_.subscribe("base_pose", 10, &DriverNode::on_pose, this, ros::TransportHints().tcpNoDelay());
    gait_sub_ = nh_.subscribe("gait_command", 10, &DriverNode::on_gait_command, this);
    enable_srv_ = nh_.advertiseService("driver/enable_torque", &DriverNode::on_enable_torque, this);
    hold_srv_ = nh_.advertiseService("driver/hold", &DriverNode::on_hold, this);
    reboot_srv_ = nh_.advertiseService("driver/reboot_servo", &DriverNode::on_reboot, this);
  }

  void run_threads() {
    running_ = true;
    loop_thread_ = std::thread(&DriverNode::loop, this);
    publisher_thread_ = std::thread(&DriverNode::publish_loop, this);
  }

  // Stops the loop, then leaves the servos in the configured state.
  void stop() {
    running_ = false;
    if (loop_thread_.joinable()) loop_thread_.join();
    snapshot_cv_.notify_all();
    if (publisher_thread_.joinable()) publisher_thread_.join();
    const bool ok = controller_.shutdown();
    std::fprintf(stderr, "[driver] shutdown: servos left in '%s'%s\n",
                 driver::to_string(config_.controller.shutdown_action), ok ? "" : " (the bus did not take the write)");
  }

 private:
  double now_s() const { return std::chrono::duration<double>(Clock::now() - epoch_).count(); }

  // ---- the loop thread ----
  void loop() {
    realtime_ = driver::enter_realtime(config_.realtime_priority);
    realtime_known_.store(true, std::memory_order_release);
    driver::LoopTimer timer(config_.loop);
    Clock::time_point prev = Clock::now();
    timer.start(prev);
    while (running_.load(std::memory_order_relaxed)) {
      const Clock::time_point wake = timer.wait();
      const double t_s = std::chrono::duration<double>(wake - epoch_).count();
      const double dt_s = std::chrono::duration<double>(wake - prev).count();
      prev = wake;
      controller_.update(t_s, dt_s);
      controller_.fill_snapshot(work_.driver);
      work_.loop = timer.stats();
      work_.taken = wake;
      if (snapshot_mutex_.try_lock()) {
        shared_.driver = work_.driver;
        shared_.loop = work_.loop;
        shared_.taken = work_.taken;
        shared_.seq = ++seq_;
        snapshot_mutex_.unlock();
        snapshot_cv_.notify_one();
      }
      if (reset_window_.exchange(false, std::memory_order_relaxed)) timer.stats().reset_window();
      timer.finish(Clock::now());
    }
  }

  // ---- the publisher thread ----
  void publish_loop() {
    std::uint64_t last_seq = 0;
    ros::WallTime next_diag = ros::WallTime::now();
    bool realtime_logged = false;
    while (running_) {
      if (!realtime_logged && realtime_known_.load(std::memory_order_acquire)) {
        realtime_logged = true;
        if (realtime_.degraded()) {
          ROS_WARN("driver: %s", realtime_.warning().c_str());
        } else {
          ROS_INFO("driver: loop thread real-time mode: %s", realtime_.mode().c_str());
        }
      }
      {
        std::unique_lock<std::mutex> lock(snapshot_mutex_);
        snapshot_cv_.wait_for(lock, std::chrono::milliseconds(20),
                              [&] { return shared_.seq != last_seq || !running_; });
        if (shared_.seq == last_seq) continue;
        published_.driver = shared_.driver;
        published_.loop = shared_.loop;
        published_.taken = shared_.taken;
        published_.seq = last_seq = shared_.seq;
      }
      // The stamp of the cycle: now, minus the time since the loop took the snapshot. With use_sim_time
      // and no /clock yet, now is zero: nothing can be stamped (and zero minus an age would throw).
      const ros::Time now = ros::Time::now();
      if (now.isZero()) continue;
      const double age_s = std::chrono::duration<double>(Clock::now() - published_.taken).count();
      const ros::Time stamp = (age_s > 0.0 && now.toSec() > age_s) ? now - ros::Duration(age_s) : now;
      publish(stamp);
      log_changes();
      if (ros::WallTime::now() >= next_diag) {
        next_diag += ros::WallDuration(config_.diagnostics_period_s);
        if (next_diag < ros::WallTime::now())
          next_diag = ros::WallTime::now() + ros::WallDuration(config_.diagnostics_period_s);
        publish_diagnostics();
        reset_window_ = true;
      }
    }
  }

  void publish(const ros::Time& stamp) {
    const driver::DriverSnapshot& s = published_.driver;
    joint_states_.header.stamp = stamp;
    ++joint_states_.header.seq;
    for (int j = 0; j < model_.num_joints; ++j) {
      joint_states_.position[j] = s.position_rad[j];
      joint_states_.velocity[j] = s.velocity_rad_s[j];
      if (!joint_states_.effort.empty()) joint_states_.effort[j] = torque_constant_ * s.effort_a[j];
    }
    joint_states_pub_.publish(joint_states_);
    joint_states_diag_->tick(stamp);
    trajectory_topics_->publish(s.trajectory, stamp);

    auto set_tf = [&stamp](geometry_msgs::TransformStamped& t, const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
      t.header.stamp = stamp;
      t.transform.translation.x = p.x();
      t.transform.translation.y = p.y();
      t.transform.translation.z = p.z();
      t.transform.rotation.x = q.x();
      t.transform.rotation.y = q.y();
      t.transform.rotation.z = q.z();
      t.transform.rotation.w = q.w();
    };
    // TF unless ~publish_tf is false (identity before the first pose: visualisation only).
    set_tf(transforms_[0], s.base_position, s.base_orientation);
    set_tf(transforms_[1], s.com, s.com_orientation);
    if (config_.publish_tf) tf_.sendTransform(transforms_);

    // The centre of mass feeds the tracker: published only from a fresh base pose.
    if (!s.pose_fresh) return;
    com_pose_.header.stamp = stamp;
    com_pose_.pose.position.x = s.com.x();
    com_pose_.pose.position.y = s.com.y();
    com_pose_.pose.position.z = s.com.z();
    com_pose_.pose.orientation = transforms_[1].transform.rotation;
    com_pose_pub_.publish(com_pose_);
    com_pose_diag_->tick(stamp);
    bound_state_.header.stamp = stamp;
    bound_state_.com_pose = com_pose_.pose;
    bound_state_.span.x = s.bbox_span.x();
    bound_state_.span.y = s.bbox_span.y();
    bound_state_.span.z = s.bbox_span.z();
    bound_state_pub_.publish(bound_state_);
  }

  void log_changes() {
    const driver::DriverSnapshot& s = published_.driver;
    if (s.state != logged_state_ || std::strcmp(s.fault_reason.data(), logged_fault_.c_str()) != 0) {
      if (s.state == driver::DriverState::kFault) {
        // The core's reasons name no ROS interface: the recovery services are named here.
        ROS_ERROR(
            "driver: locomotion stopped (%s): %s [recover: driver/reboot_servo for a hardware error, then "
            "driver/enable_torque]",
            driver::to_string(config_.controller.fault_action), s.fault_reason.data());
      } else if (s.hold_reason == driver::HoldReason::kCommandTimeout) {
        ROS_WARN("driver: %s", command_timeout_text().c_str());
      } else {
        ROS_INFO("driver: %s", driver::to_string(s.state));
      }
      logged_state_ = s.state;
      logged_fault_ = s.fault_reason.data();
    }
    const bool stale = !s.pose_fresh;
    if (stale != logged_stale_) {
      if (stale && config_.controller.require_pose) {
        ROS_WARN("driver: base pose %s: locomotion held until fresh poses return",
                 s.pose_received ? "stale" : "not received yet");
      } else if (!stale) {
        ROS_INFO("driver: base pose fresh");
      }
      logged_stale_ = stale;
    }
    if (published_.loop.overruns > logged_overruns_) {
      ROS_WARN_THROTTLE(5.0, "driver: %lu loop overruns so far (worst cycle %.2f ms of %.2f ms)",
                        static_cast<unsigned long>(published_.loop.overruns), published_.loop.window_work_max_s * 1e3,
                        1e3 / config_.loop.rate_hz);
      logged_overruns_ = published_.loop.overruns;
    }
  }

  std::string command_timeout_text() const {
    return "holding: no gait command for " + fixed(config_.controller.command_timeout_s, 1) +
           " s (command_timeout_s): send one on gait_command to resume";
  }

  // ---- diagnostics (diagnostic_updater; the tasks run in the publisher thread, on published_) ----
  // Names stay "snake_driver: ..." whatever the node is called (tools and tests filter on them).
  void setup_diagnostics() {
    ros::NodeHandle pnh("~");
    updater_ = std::make_unique<diagnostic_updater::Updater>(nh_, pnh, "/snake_driver");
    updater_->setHardwareID("snake driver");
    updater_->add("loop", this, &DriverNode::diagnose_loop);
    updater_->add("locomotion", this, &DriverNode::diagnose_locomotion);
    updater_->add("bus", this, &DriverNode::diagnose_bus);
    for (std::size_t j = 0; j < model_.servos.ids.size(); ++j) {
      updater_->add("servo " + str(model_.servos.ids[j]) + " (joint_" + str(j + 1) + ")",
                    [this, j](diagnostic_updater::DiagnosticStatusWrapper& stat) { diagnose_servo(j, stat); });
    }
    // The 100 Hz topics: rate within 10 % of rate_hz over the last 10 s windows of ticks, stamps no
    // older than 0.1 s. com_pose runs only from a fresh base pose: its rate drops while it is held.
    rate_min_hz_ = rate_max_hz_ = config_.loop.rate_hz;
    const diagnostic_updater::FrequencyStatusParam freq(&rate_min_hz_, &rate_max_hz_, 0.1, 10);
    const diagnostic_updater::TimeStampStatusParam stamps(-0.1, 0.1);
    joint_states_diag_ = std::make_unique<diagnostic_updater::TopicDiagnostic>("joint_states", *updater_, freq, stamps);
    com_pose_diag_ = std::make_unique<diagnostic_updater::TopicDiagnostic>("com_pose", *updater_, freq, stamps);
  }

  void publish_diagnostics() { updater_->force_update(); }

  void diagnose_loop(diagnostic_updater::DiagnosticStatusWrapper& stat) {
    using diagnostic_msgs::DiagnosticStatus;
    const driver::LoopStats& l = published_.loop;
    const double rate = l.window_rate_hz();
    const bool rate_ok = std::abs(rate - config_.loop.rate_hz) <= 0.1 * config_.loop.rate_hz;
    const bool ok = l.window_overruns == 0 && rate_ok;
    const bool rt_known = realtime_known_.load(std::memory_order_acquire);
    const bool rt_refused = rt_known && realtime_.degraded();
    std::string summary =
        ok ? "on time" : (l.window_overruns > 0 ? str(l.window_overruns) + " overruns" : "rate off by more than 10 %");
    if (rt_refused) summary += "; real-time mode refused: " + realtime_.mode();
    stat.summary(ok && !rt_refused ? DiagnosticStatus::OK : DiagnosticStatus::WARN, summary);
    stat.values = {kv("target_rate_hz", fixed(config_.loop.rate_hz, 1)),
                   kv("rate_hz", fixed(rate, 2)),
                   kv("period_mean_ms", fixed(l.window_period_mean_s() * 1e3, 3)),
                   kv("period_std_ms", fixed(l.window_period_std_s() * 1e3, 3)),
                   kv("period_max_ms", fixed(l.window_period_max_s * 1e3, 3)),
                   kv("wake_late_max_ms", fixed(l.window_late_max_s * 1e3, 3)),
                   kv("work_mean_ms", fixed(l.window_cycles ? l.window_work_sum_s / l.window_cycles * 1e3 : 0.0, 3)),
                   kv("work_max_ms", fixed(l.window_work_max_s * 1e3, 3)),
                   kv("overruns", str(l.overruns)),
                   kv("window_overruns", str(l.window_overruns)),
                   kv("skipped_deadlines", str(l.skipped_deadlines)),
                   kv("cycles", str(l.cycles)),
                   kv("realtime", rt_known ? realtime_.mode() : "starting"),
                   kv("realtime_priority", str(config_.realtime_priority)),
                   kv("memory_locked", rt_known && realtime_.memory_locked ? "true" : "false")};
  }

  void diagnose_locomotion(diagnostic_updater::DiagnosticStatusWrapper& stat) {
    using diagnostic_msgs::DiagnosticStatus;
    const driver::DriverSnapshot& s = published_.driver;
    if (s.state == driver::DriverState::kFault) {
      stat.summary(DiagnosticStatus::ERROR, std::string("fault: ") + s.fault_reason.data());
    } else if (s.state == driver::DriverState::kStopped) {
      stat.summary(DiagnosticStatus::WARN, "torque off");
    } else if (s.hold_reason == driver::HoldReason::kCommandTimeout) {
      stat.summary(DiagnosticStatus::WARN, command_timeout_text());
    } else if (s.locomotion_gated) {
      stat.summary(DiagnosticStatus::WARN,
                   s.pose_received ? "base pose stale: locomotion held" : "no base pose yet: locomotion held");
    } else {
      stat.summary(DiagnosticStatus::OK, driver::to_string(s.state));
    }
    stat.values = {kv("state", driver::to_string(s.state)),
                   kv("gait", s.gait.data()),
                   kv("fault", s.fault_reason.data()),
                   kv("last_fault", s.last_fault.data()),
                   kv("pose_received", s.pose_received ? "true" : "false"),
                   kv("pose_fresh", s.pose_fresh ? "true" : "false"),
                   kv("locomotion_held_for_pose", s.locomotion_gated ? "true" : "false"),
                   kv("commands_accepted", str(controller_.commands_accepted())),
                   kv("commands_refused", str(controller_.commands_refused())),
                   kv("commands_applied", str(s.commands_applied)),
                   kv("last_refusal", controller_.last_refusal()),
                   kv("poses_refused", str(s.poses_refused)),
                   kv("last_pose_refusal", s.pose_refusal.data()),
                   kv("hold_reason", driver::to_string(s.hold_reason)),
                   kv("command_age_s", fixed(s.command_age_s, 2)),
                   kv("command_timeout_s", fixed(config_.controller.command_timeout_s, 2)),
                   kv("fault_action", driver::to_string(config_.controller.fault_action)),
                   kv("effort_unit", torque_constant_ > 0.0 ? "N*m (current x " + fixed(torque_constant_, 3) + " N*m/A)"
                                                            : "none (no torque constant in the control table)")};
  }

  void diagnose_bus(diagnostic_updater::DiagnosticStatusWrapper& stat) {
    snake_autonomy::ros_driver::diagnose_bus(published_.driver, config_.serial.device, config_.serial.baud_bps, stat);
  }

  void diagnose_servo(std::size_t j, diagnostic_updater::DiagnosticStatusWrapper& stat) {
    snake_autonomy::ros_driver::diagnose_servo(published_.driver, controller_.table(), j, stat);
  }

  // ---- callbacks (spinner threads) ----
  // base_pose: geometry_msgs/PoseWithCovarianceStamped (motion capture, the pose remapper). The
  // covariance is not used: the safety rules gate on freshness and plausibility, not on uncertainty.
  void on_pose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg) {
    if (!msg->header.frame_id.empty() && msg->header.frame_id != config_.world_frame) {
      ROS_WARN_THROTTLE(5.0, "base_pose in frame '%s' ignored: the driver expects '%s' (~world_frame)",
                        msg->header.frame_id.c_str(), config_.world_frame.c_str());
      return;
    }
    const auto& p = msg->pose.pose.position;
    const auto& q = msg->pose.pose.orientation;
    if (!controller_.set_base_pose(now_s(), Eigen::Vector3d(p.x, p.y, p.z), Eigen::Quaterniond(q.w, q.x, q.y, q.z)))
      ROS_WARN_THROTTLE(5.0, "base_pose ignored: not finite, or a zero quaternion");
  }

  void on_gait_command(const snake_autonomy::GaitCommand::ConstPtr& msg) {
    driver::GaitCommandRequest c;
    c.gait = msg->gait;
    c.amplitude = msg->amplitude;
    c.omega = msg->omega;
    c.phase = msg->phase;
    c.bias = msg->bias;
    c.steer = msg->steer;
    c.delta_rad = msg->delta;
    c.curve = msg->curve;
    c.kappa_per_m = msg->kappa;
    const std::string why = controller_.command_gait(c);
    if (why.empty()) {
      ROS_DEBUG("gait command accepted: %s", controller_.commanded_gait().c_str());
    } else {
      const driver::DriverState state = controller_.state();
      const bool blocked = state == driver::DriverState::kStopped || state == driver::DriverState::kFault;
      ROS_WARN("gait command refused, the running gait is unchanged:\n%s%s", why.c_str(),
               blocked ? " (driver/enable_torque; see /diagnostics)" : "");
    }
  }

  bool on_enable_torque(std_srvs::SetBool::Request& req, std_srvs::SetBool::Response& res) {
    return answer(req.data ? driver::DriverRequest::kEnableTorque : driver::DriverRequest::kDisableTorque, 0, res);
  }
  bool on_hold(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
    return answer(driver::DriverRequest::kHold, 0, res);
  }
  bool on_reboot(snake_autonomy::RebootServo::Request& req, snake_autonomy::RebootServo::Response& res) {
    return answer(driver::DriverRequest::kRebootServo, req.id, res);
  }
  template <typename Response>
  bool answer(driver::DriverRequest request, std::uint8_t id, Response& res) {
    const driver::RequestResult r = controller_.call(request, id, config_.service_timeout_s);
    res.success = r.success;
    res.message = r.message;
    if (r.success) {
      ROS_INFO("driver/%s: %s", driver::to_string(request), r.message.c_str());
    } else {
      ROS_WARN("driver/%s refused: %s", driver::to_string(request), r.message.c_str());
    }
    return true;
  }

  ros::NodeHandle& nh_;
  const DriverNodeConfig& config_;
  const core::RobotModel& model_;
  dxl::SerialBus& bus_;
  driver::DriverController& controller_;
  const Clock::time_point epoch_;

  std::atomic<bool> running_{false};
  std::atomic<bool> reset_window_{false};
  driver::RealtimeReport realtime_;           // written by the loop thread before realtime_known_
  std::atomic<bool> realtime_known_{false};
  std::thread loop_thread_, publisher_thread_;
  LoopSnapshot work_;       // loop thread only
  std::mutex snapshot_mutex_;
  std::condition_variable snapshot_cv_;
  LoopSnapshot shared_;     // under snapshot_mutex_
  std::uint64_t seq_ = 0;   // loop thread only
  LoopSnapshot published_;  // publisher thread only

  // Publisher thread only.
  sensor_msgs::JointState joint_states_;
  std::vector<geometry_msgs::TransformStamped> transforms_;
  geometry_msgs::PoseStamped com_pose_;
  snake_autonomy::BoundState bound_state_;
  tf2_ros::TransformBroadcaster tf_;
  double torque_constant_ = 0.0;  // N*m/A
  driver::DriverState logged_state_ = driver::DriverState::kStopped;
  std::string logged_fault_;
  bool logged_stale_ = false;
  std::uint64_t logged_overruns_ = 0;

  ros::Publisher joint_states_pub_, com_pose_pub_, bound_state_pub_;
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  double rate_min_hz_ = 0.0, rate_max_hz_ = 0.0;  // the topic diagnostics keep pointers to these
  std::unique_ptr<diagnostic_updater::TopicDiagnostic> joint_states_diag_, com_pose_diag_;
  std::unique_ptr<snake_autonomy::ros_driver::TrajectoryTopics> trajectory_topics_;  // driver/joint_trajectory
  ros::Subscriber pose_sub_, gait_sub_;
  ros::ServiceServer enable_srv_, hold_srv_, reboot_srv_;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "driver");
  ros::NodeHandle nh, pnh("~");

  std::vector<std::string> errors;
  const DriverNodeConfig config = snake_autonomy::ros_driver::read_driver_params(pnh, errors);
  if (!errors.empty()) {
    ROS_FATAL("driver: refusing to start, the parameters have problems:%s", join(errors).c_str());
    return 1;
  }
  std::unique_ptr<core::RobotModel> model;
  std::unique_ptr<core::GaitLibrary> gaits;
  std::unique_ptr<dxl::ControlTable> table;
  try {
    model = std::make_unique<core::RobotModel>(core::RobotModel::from_yaml_file(config.robot_file()));
    gaits = std::make_unique<core::GaitLibrary>(core::GaitLibrary::from_yaml_file(config.gaits_file));
    const std::string table_file = config.control_table_file.empty()
                                       ? config.config_dir + "/dynamixel/" + model->servos.model + ".yaml"
                                       : config.control_table_file;
    table = std::make_unique<dxl::ControlTable>(dxl::ControlTable::from_yaml_file(table_file));
  } catch (const std::exception& e) {
    ROS_FATAL("driver: refusing to start: %s", e.what());
    return 1;
  }

  // The port and the servos may take a moment (the mocked bus starting beside us): retry until
  // connect_timeout_s, then give up naming the last problem.
  const auto give_up = Clock::now() + std::chrono::duration<double>(config.connect_timeout_s);
  std::unique_ptr<dxl::SerialBus> bus;
  std::unique_ptr<driver::DriverController> controller;
  std::string last_problem;
  while (ros::ok()) {
    try {
      if (!bus) bus = std::make_unique<dxl::SerialBus>(config.serial);
      if (!controller)
        controller = std::make_unique<driver::DriverController>(*model, *gaits, *table, *bus, config.controller);
      controller->start(0.0);
      break;
    } catch (const dxl::SerialError& e) {
      last_problem = e.what();
    } catch (const core::ConfigError& e) {
      last_problem = e.what();
      if (!bus || !controller) {  // a configuration problem: retrying cannot help
        ROS_FATAL("driver: refusing to start: %s", e.what());
        return 1;
      }
    }
    if (Clock::now() > give_up) {
      ROS_FATAL("driver: no usable servo bus after %.1f s: %s", config.connect_timeout_s, last_problem.c_str());
      return 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  if (!ros::ok()) return 0;
  dxl::SerialBus* bus_ptr = bus.get();
  controller->set_reconnect([bus_ptr](std::string* why) {
    try {
      bus_ptr->reopen();
      return true;
    } catch (const std::exception& e) {
      *why = e.what();
      return false;
    }
  });
  for (const auto& note : controller->start_notes()) ROS_WARN("driver: %s", note.c_str());
  ROS_INFO("driver: %d servos on %s at %d baud, loop %.0f Hz, state %s%s%s", model->num_joints,
           config.serial.device.c_str(), config.serial.baud_bps, config.loop.rate_hz,
           driver::to_string(controller->state()), controller->state() == driver::DriverState::kFault ? ": " : "",
           controller->state() == driver::DriverState::kFault ? controller->fault_reason() : "");

  DriverNode node(nh, config, *model, *bus, *controller);
  ros::AsyncSpinner spinner(2);
  spinner.start();
  node.run_threads();
  ros::waitForShutdown();
  spinner.stop();
  node.stop();
  return 0;
}
