// driver_node's joint trajectory wiring (ROS side only): subscribes driver/joint_trajectory
// (trajectory_msgs/JointTrajectory), hands each message to DriverController::command_trajectory,
// logs a refusal with every reason (ROS_WARN) and publishes it; publishes the progress on
// driver/trajectory_status (snake_autonomy/TrajectoryStatus, latched: on a refusal, a take, each point
// passed, the end or an abort) and adds the "trajectory" task to the node's /diagnostics.
// The rules (checks, interpolation, ends) live in driver::TrajectorySource and the controller.
//
// Threads: the callback runs on the node's spinner threads (command_trajectory never blocks the
// loop); publish() and the diagnostics task on the node's publisher thread.
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>
#include <snake_autonomy/TrajectoryStatus.h>
#include <trajectory_msgs/JointTrajectory.h>

#include <atomic>
#include <cstdint>
#include <string>

#include "snake_autonomy/core/driver_controller.hpp"
#include "snake_autonomy/driver/trajectory_source.hpp"

namespace snake_autonomy::ros_driver {

// The message as a request (header.stamp is not used: the loop starts it when it takes it).
driver::JointTrajectoryRequest to_request(const trajectory_msgs::JointTrajectory& msg, const std::string& id);

class TrajectoryTopics {
 public:
  TrajectoryTopics(ros::NodeHandle& nh, core::DriverController& controller, diagnostic_updater::Updater& updater);
  // Publisher thread: the loop's latest progress; publishes the status when it changed.
  void publish(const driver::TrajectoryProgress& progress, const ros::Time& stamp);

 private:
  void on_trajectory(const trajectory_msgs::JointTrajectory::ConstPtr& msg);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat);

  core::DriverController& controller_;
  ros::Subscriber sub_;
  ros::Publisher status_pub_;
  std::atomic<std::uint64_t> received_{0};
  driver::TrajectoryProgress last_{};  // publisher thread
  snake_autonomy::TrajectoryStatus status_;
};

}  // namespace snake_autonomy::ros_driver
