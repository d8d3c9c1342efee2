// driver_node's joint trajectory wiring (ROS side only): subscribes driver/joint_trajectory
// (trajectory_msgs/JointTrajectory), hands each message to DriverController::command_trajectory,
// logs a refusal with every reason (ROS_WARN) and publishes it; publishes the progress on
// driver/trajectory_status (snake_autonomy/TrajectoryStatus, latched) and adds the "trajectory" task
// to the node's /diagnostics. The rules (checks, interpolation, ends) live in driver::TrajectorySource
// and the controller.
//
// Statuses, as actionlib's: every message gets exactly one final status. A refused one: "refused"
// (from the callback). An accepted one (numbered: `sequence`): "running" when the loop takes it and
// as it passes points (sampled from the loop's snapshots: a point may be skipped), then exactly one of
// "done", "aborted" (abort + reason) or "aborted"/"superseded" naming the trajectory that replaced it
// (superseded_by, superseded_by_sequence), from DriverController::pop_trajectory_final: never lost
// between samples, never a "running" after it.
// Nothing is dropped silently: the subscriber queue holds kQueueSize messages; beyond that roscpp
// discards the oldest, which the driver counts from gaps in each publisher's header.seq (rospy numbers
// its messages; a sender that leaves header.seq at 0 is not tracked) and reports in the
// diagnostics (lost_before_driver) with a warning; final statuses lost to a full queue are counted
// too (final_statuses_dropped).
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
#include <map>
#include <mutex>
#include <set>
#include <string>

#include "snake_autonomy/driver/driver_controller.hpp"
#include "snake_autonomy/driver/trajectory_source.hpp"

namespace snake_autonomy::ros_driver {

// The message as a request (header.stamp is not used: the loop starts it when it takes it).
driver::JointTrajectoryRequest to_request(const trajectory_msgs::JointTrajectory& msg, const std::string& id);

class TrajectoryTopics {
 public:
  static constexpr std::uint32_t kQueueSize = 100;  // driver/joint_trajectory's subscriber queue

  TrajectoryTopics(ros::NodeHandle& nh, driver::DriverController& controller, diagnostic_updater::Updater& updater);
  // Publisher thread: the loop's latest progress (a "running" status when it changed), then every
  // final status the loop queued.
  void publish(const driver::TrajectoryProgress& progress, const ros::Time& stamp);

 private:
  void on_trajectory(const ros::MessageEvent<const trajectory_msgs::JointTrajectory>& event);
  // Counts the messages a publisher numbered but the driver never received (header.seq gaps).
  void count_lost(const std::string& publisher, std::uint32_t seq);
  void fill(const driver::TrajectoryProgress& p, const ros::Time& stamp);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat);

  driver::DriverController& controller_;
  ros::Subscriber sub_;
  ros::Publisher status_pub_;
  std::atomic<std::uint64_t> received_{0};
  std::mutex seq_mutex_;
  std::map<std::string, std::uint32_t> last_seq_;  // per publisher (caller id), under seq_mutex_
  std::atomic<std::uint64_t> lost_{0};            // messages numbered by a publisher and never received
  // Publisher thread:
  driver::TrajectoryProgress last_{};        // the latest progress sampled
  driver::TrajectoryProgress last_final_{};  // the latest final status published
  std::set<std::uint64_t> finished_;         // sequences with a final status published (pruned)
  std::uint64_t finals_published_ = 0;
  snake_autonomy::TrajectoryStatus status_;
};

}  // namespace snake_autonomy::ros_driver
