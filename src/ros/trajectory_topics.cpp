#include "trajectory_topics.hpp"

#include <cstdio>

namespace snake_autonomy::ros_driver {

namespace {

diagnostic_msgs::KeyValue kv(const std::string& key, const std::string& value) {
  diagnostic_msgs::KeyValue k;
  k.key = key;
  k.value = value;
  return k;
}

std::string fixed(double v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.3f", v);
  return buf;
}

}  // namespace

driver::JointTrajectoryRequest to_request(const trajectory_msgs::JointTrajectory& msg, const std::string& id) {
  driver::JointTrajectoryRequest r;
  r.id = id;
  r.joint_names = msg.joint_names;
  r.points.resize(msg.points.size());
  for (std::size_t k = 0; k < msg.points.size(); ++k) {
    r.points[k].time_from_start_s = msg.points[k].time_from_start.toSec();
    r.points[k].positions_rad = msg.points[k].positions;
    r.points[k].velocities_rad_s = msg.points[k].velocities;
  }
  return r;
}

TrajectoryTopics::TrajectoryTopics(ros::NodeHandle& nh, driver::DriverController& controller,
                                   diagnostic_updater::Updater& updater)
    : controller_(controller) {
  // The status queue holds a burst of final statuses (kQueueSize trajectories superseded at once).
  status_pub_ = nh.advertise<snake_autonomy::TrajectoryStatus>("driver/trajectory_status", 2 * kQueueSize, true);
  sub_ = nh.subscribe("driver/joint_trajectory", kQueueSize, &TrajectoryTopics::on_trajectory, this);
  updater.add("trajectory", this, &TrajectoryTopics::diagnose);
  status_.phase = "idle";
  status_.point_reached = -1;
  status_pub_.publish(status_);
}

void TrajectoryTopics::count_lost(const std::string& publisher, std::uint32_t seq) {
  if (seq == 0) return;  // not numbered by its sender: not tracked
  std::uint32_t gap = 0;
  {
    std::lock_guard<std::mutex> lock(seq_mutex_);
    auto it = last_seq_.find(publisher);
    if (it != last_seq_.end() && seq > it->second + 1) gap = seq - it->second - 1;
    last_seq_[publisher] = seq;  // a lower seq: the publisher restarted
  }
  if (gap == 0) return;
  lost_ += gap;
  ROS_WARN(
      "driver/joint_trajectory: %u message(s) from %s never reached the driver (header.seq jumped to %u): "
      "lost in a queue (driver's: %u messages), they get no status",
      gap, publisher.c_str(), seq, kQueueSize);
}

void TrajectoryTopics::on_trajectory(const ros::MessageEvent<const trajectory_msgs::JointTrajectory>& event) {
  const trajectory_msgs::JointTrajectory::ConstPtr& msg = event.getConstMessage();
  count_lost(event.getPublisherName(), msg->header.seq);
  const std::uint64_t n = ++received_;
  const std::string id = msg->header.frame_id.empty() ? "trajectory " + std::to_string(n) : msg->header.frame_id;
  const std::string why = controller_.command_trajectory(to_request(*msg, id));
  if (why.empty()) {
    ROS_INFO("driver/joint_trajectory '%s' accepted: %zu points over %.3f s", id.c_str(), msg->points.size(),
             msg->points.empty() ? 0.0 : msg->points.back().time_from_start.toSec());
    return;
  }
  ROS_WARN("driver/joint_trajectory '%s' refused, the robot is left as it was:\n%s", id.c_str(), why.c_str());
  snake_autonomy::TrajectoryStatus s;
  s.header.stamp = ros::Time::now();
  s.id = id;
  s.phase = "refused";
  s.reason = why;
  s.point_reached = -1;
  status_pub_.publish(s);
}

void TrajectoryTopics::fill(const driver::TrajectoryProgress& p, const ros::Time& stamp) {
  status_.header.stamp = stamp;
  status_.id = p.id.data();
  status_.sequence = p.sequence;
  status_.phase = driver::to_string(p.phase);
  status_.abort = driver::to_string(p.abort);
  status_.reason = p.reason.data();
  status_.point_reached = p.point_reached;
  status_.num_points = p.num_points;
  status_.time_s = p.time_s;
  status_.duration_s = p.duration_s;
  status_.superseded_by = p.superseded_by.data();
  status_.superseded_by_sequence = p.superseded_by_sequence;
}

void TrajectoryTopics::publish(const driver::TrajectoryProgress& p, const ros::Time& stamp) {
  // Running (sampled): only for a trajectory whose final status has not been published yet.
  const bool changed = p.sequence != last_.sequence || p.phase != last_.phase || p.point_reached != last_.point_reached;
  last_ = p;
  if (changed && p.phase == driver::TrajectoryPhase::kRunning && finished_.count(p.sequence) == 0) {
    fill(p, stamp);
    status_pub_.publish(status_);
  }
  // The loop runs trajectories in sequence order: the older ones can no longer show up running.
  finished_.erase(finished_.begin(), finished_.lower_bound(p.sequence));
  // Final statuses: each accepted trajectory's, exactly once, in the order the driver ended them.
  driver::TrajectoryProgress f;
  while (controller_.pop_trajectory_final(&f)) {
    fill(f, stamp);
    status_pub_.publish(status_);
    ++finals_published_;
    last_final_ = f;
    finished_.insert(f.sequence);
    if (f.abort == driver::TrajectoryAbort::kSuperseded)
      ROS_INFO("driver/joint_trajectory '%s' (sequence %llu) superseded: %s", f.id.data(),
               static_cast<unsigned long long>(f.sequence), f.reason.data());
    else if (f.phase == driver::TrajectoryPhase::kAborted)
      ROS_WARN("driver/joint_trajectory '%s' aborted (%s): %s", f.id.data(), driver::to_string(f.abort),
               f.reason.data());
    else ROS_INFO("driver/joint_trajectory '%s' done: holding its last point", f.id.data());
  }
}

void TrajectoryTopics::diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  using diagnostic_msgs::DiagnosticStatus;
  const driver::TrajectoryProgress& p = last_;
  const std::string id = p.id.data(), refusal = controller_.last_trajectory_refusal();
  switch (p.phase) {
    case driver::TrajectoryPhase::kIdle: stat.summary(DiagnosticStatus::OK, "no trajectory yet"); break;
    case driver::TrajectoryPhase::kRunning:
      stat.summary(DiagnosticStatus::OK, "running '" + id + "': point " + std::to_string(p.point_reached + 1) + " of " +
                                             std::to_string(p.num_points));
      break;
    case driver::TrajectoryPhase::kDone:
      stat.summary(DiagnosticStatus::OK, "'" + id + "' done: last point held");
      break;
    case driver::TrajectoryPhase::kAborted:
      stat.summary(DiagnosticStatus::WARN,
                   "'" + id + "' aborted (" + driver::to_string(p.abort) + "): " + p.reason.data());
      break;
  }
  stat.values = {kv("id", id),
                 kv("sequence", std::to_string(p.sequence)),
                 kv("phase", driver::to_string(p.phase)),
                 kv("abort", driver::to_string(p.abort)),
                 kv("reason", p.reason.data()),
                 kv("point_reached", std::to_string(p.point_reached)),
                 kv("num_points", std::to_string(p.num_points)),
                 kv("time_s", fixed(p.time_s)),
                 kv("duration_s", fixed(p.duration_s)),
                 kv("trajectories_accepted", std::to_string(controller_.trajectories_accepted())),
                 kv("trajectories_refused", std::to_string(controller_.trajectories_refused())),
                 kv("last_refusal", refusal),
                 kv("final_statuses", std::to_string(finals_published_)),
                 kv("last_final", last_final_.sequence == 0 ? ""
                                                            : std::string(last_final_.id.data()) + " " +
                                                                  driver::to_string(last_final_.phase) + " " +
                                                                  driver::to_string(last_final_.abort)),
                 kv("final_statuses_dropped", std::to_string(controller_.trajectory_finals_dropped())),
                 kv("lost_before_driver", std::to_string(lost_.load())),
                 kv("queue_size", std::to_string(kQueueSize))};
  if (lost_.load() > 0 || controller_.trajectory_finals_dropped() > 0)
    stat.mergeSummary(DiagnosticStatus::WARN, std::to_string(lost_.load()) + " trajectories lost before the driver, " +
                                                  std::to_string(controller_.trajectory_finals_dropped()) +
                                                  " final statuses dropped");
}

}  // namespace snake_autonomy::ros_driver
