#include "snake_autonomy/driver/trajectory_source.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace snake_autonomy::driver {

namespace {

// Listed reasons per kind; the rest are counted (a 20000-point trajectory could give 20000 lines).
constexpr int kMaxListedPerKind = 20;

// Velocity of a cubic Hermite segment at its peak (see the header).
double hermite_peak(double p0, double p1, double m0, double m1, double h) noexcept {
  const double d = (p1 - p0) / h;
  const double a = 3.0 * (m0 + m1) - 6.0 * d, b = 6.0 * d - 4.0 * m0 - 2.0 * m1, c = m0;
  double peak = std::max(std::abs(m0), std::abs(m1));
  if (a != 0.0) {
    const double s = -b / (2.0 * a);
    if (s > 0.0 && s < 1.0) peak = std::max(peak, std::abs(c - b * b / (4.0 * a)));
  }
  return peak;
}

double hermite(double p0, double p1, double m0, double m1, double h, double s) noexcept {
  const double s2 = s * s, s3 = s2 * s;
  return (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * h * m0 + (-2 * s3 + 3 * s2) * p1 + (s3 - s2) * h * m1;
}

// Fritsch-Butland (scipy's PCHIP) at a point between secants d0 (over h0, before) and d1 (over h1).
double monotone_slope(double d0, double d1, double h0, double h1) noexcept {
  if (d0 * d1 <= 0.0) return 0.0;
  const double w1 = 2.0 * h1 + h0, w2 = h1 + 2.0 * h0;
  return (w1 + w2) / (w1 / d0 + w2 / d1);
}

bool over(double peak, double limit) noexcept { return peak > limit * (1.0 + 1e-9); }

// Collects reasons per kind, listing the first kMaxListedPerKind of each.
class Reasons {
 public:
  void add(int kind, const std::string& text) {
    if (static_cast<int>(count_.size()) <= kind) count_.resize(kind + 1, 0);
    if (++count_[kind] <= kMaxListedPerKind) lines_.push_back(text);
  }
  std::string str() const {
    std::ostringstream out;
    for (const auto& l : lines_) out << (out.tellp() > 0 ? "\n" : "") << l;
    for (int c : count_) {
      if (c > kMaxListedPerKind) out << "\n(and " << c - kMaxListedPerKind << " more of this kind)";
    }
    return out.str();
  }
  bool empty() const { return lines_.empty(); }

 private:
  std::vector<std::string> lines_;
  std::vector<int> count_;
};

enum Kind { kNames, kSizes, kFinite, kLimits, kTimes, kVelocity, kCount };

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace

const char* to_string(TrajectoryPhase phase) noexcept {
  switch (phase) {
    case TrajectoryPhase::kIdle: return "idle";
    case TrajectoryPhase::kRunning: return "running";
    case TrajectoryPhase::kDone: return "done";
    case TrajectoryPhase::kAborted: return "aborted";
  }
  return "?";
}

const char* to_string(TrajectoryAbort reason) noexcept {
  switch (reason) {
    case TrajectoryAbort::kNone: return "";
    case TrajectoryAbort::kFirstSegmentTooFast: return "first_segment_too_fast";
    case TrajectoryAbort::kNotAllowed: return "not_allowed";
    case TrajectoryAbort::kFault: return "fault";
    case TrajectoryAbort::kTorqueOff: return "torque_off";
    case TrajectoryAbort::kHoldRequest: return "hold_request";
    case TrajectoryAbort::kGaitCommand: return "gait_command";
    case TrajectoryAbort::kSuperseded: return "superseded";
    case TrajectoryAbort::kShutdown: return "shutdown";
  }
  return "?";
}

TrajectorySource::TrajectorySource(int num_joints, const TrajectoryLimits& limits) : n_(num_joints), limits_(limits) {
  if (n_ < 1) throw std::invalid_argument("TrajectorySource: num_joints " + std::to_string(n_) + " < 1");
  if (limits.max_points < 1 || limits.max_points > 1000000)
    throw std::invalid_argument("max_trajectory_points: " + std::to_string(limits.max_points) +
                                " is not in 1 .. 1000000");
  if (!(limits.max_velocity_rad_s > 0.0) || !std::isfinite(limits.max_velocity_rad_s))
    throw std::invalid_argument("max_joint_velocity_rad_s: " + num(limits.max_velocity_rad_s) +
                                " is not a positive number");
  if (!(limits.max_duration_s > 0.0) || !std::isfinite(limits.max_duration_s))
    throw std::invalid_argument("max_trajectory_duration_s: " + num(limits.max_duration_s) +
                                " is not a positive number");
  set_joint_limits(limits.lower_rad, limits.upper_rad);
  const auto points = static_cast<std::size_t>(limits.max_points), values = points * static_cast<std::size_t>(n_);
  for (Buffer* b : {&active_, &pending_}) {
    b->t_s.assign(points, 0.0);
    b->q.assign(values, 0.0);
    b->v.assign(values, 0.0);
    b->v_given.assign(points, 0);
    b->final_rad = Eigen::VectorXd::Zero(n_);
  }
  start_ = Eigen::VectorXd::Zero(n_);
}

void TrajectorySource::set_joint_limits(const Eigen::VectorXd& lower_rad, const Eigen::VectorXd& upper_rad) {
  if (lower_rad.size() != n_ || upper_rad.size() != n_)
    throw std::invalid_argument("TrajectorySource: joint limits for " + std::to_string(lower_rad.size()) + " / " +
                                std::to_string(upper_rad.size()) + " joints, expected " + std::to_string(n_));
  limits_.lower_rad = lower_rad;
  limits_.upper_rad = upper_rad;
}

// ---------------------------------------------------------------------------------------------
// The static part (callers' threads)

std::string TrajectorySource::check(const JointTrajectoryRequest& request) const {
  Reasons why;
  const int count = static_cast<int>(request.points.size());
  if (count == 0) why.add(kSizes, "points: empty (at least one point is needed)");
  if (count > limits_.max_points)
    why.add(kSizes, "points: " + std::to_string(count) + " points, more than max_trajectory_points " +
                        std::to_string(limits_.max_points));
  // Names -> joint indices.
  std::vector<int> joint_of(request.joint_names.size(), -1);
  std::vector<int> column_of(static_cast<std::size_t>(n_), -1);
  for (std::size_t c = 0; c < request.joint_names.size(); ++c) {
    const std::string& name = request.joint_names[c];
    int j = -1;
    if (name.rfind("joint_", 0) == 0 && name.size() > 6 && name.size() < 10 &&
        name.find_first_not_of("0123456789", 6) == std::string::npos && name[6] != '0')
      j = std::stoi(name.substr(6)) - 1;
    if (j < 0 || j >= n_) {
      why.add(kNames, "joint_names[" + std::to_string(c) + "]: '" + name +
                          "' is not a joint of this robot (joint_1 .. joint_" + std::to_string(n_) + ")");
    } else if (column_of[j] >= 0) {
      why.add(kNames, "joint_names[" + std::to_string(c) + "]: '" + name + "' repeats joint_names[" +
                          std::to_string(column_of[j]) + "]");
    } else {
      column_of[j] = static_cast<int>(c);
      joint_of[c] = j;
    }
  }
  for (int j = 0; j < n_; ++j) {
    if (column_of[j] < 0) why.add(kNames, "joint_names: joint_" + std::to_string(j + 1) + " is missing");
  }
  const std::size_t width = request.joint_names.size();
  auto joint_name = [&](std::size_t c) { return c < width ? request.joint_names[c] : "column " + std::to_string(c); };
  double previous_t = 0.0;
  for (int k = 0; k < count; ++k) {
    const JointTrajectoryPoint& p = request.points[k];
    const std::string at = "points[" + std::to_string(k) + "]";
    if (p.positions_rad.size() != width)
      why.add(kSizes, at + ".positions: " + std::to_string(p.positions_rad.size()) + " values for " +
                          std::to_string(width) + " joint names");
    if (!p.velocities_rad_s.empty() && p.velocities_rad_s.size() != width)
      why.add(kSizes, at + ".velocities: " + std::to_string(p.velocities_rad_s.size()) + " values for " +
                          std::to_string(width) + " joint names (give none or one per joint)");
    if (!std::isfinite(p.time_from_start_s)) {
      why.add(kFinite, at + ".time_from_start: " + num(p.time_from_start_s) + " is not finite");
    } else if (k == 0 && !(p.time_from_start_s > 0.0)) {
      why.add(kTimes, at + ".time_from_start: " + num(p.time_from_start_s) +
                          " s, must be > 0 (the driver needs time to reach the first point)");
    } else if (k > 0 && !(p.time_from_start_s > previous_t)) {
      why.add(kTimes, at + ".time_from_start: " + num(p.time_from_start_s) + " s, not after points[" +
                          std::to_string(k - 1) + "] at " + num(previous_t) + " s");
    }
    if (k + 1 == count && std::isfinite(p.time_from_start_s) && p.time_from_start_s > limits_.max_duration_s)
      why.add(kTimes, at + ".time_from_start: " + num(p.time_from_start_s) +
                          " s, the trajectory would last longer than "
                          "max_trajectory_duration_s " +
                          num(limits_.max_duration_s) + " s");
    if (std::isfinite(p.time_from_start_s)) previous_t = p.time_from_start_s;
    for (std::size_t c = 0; c < p.positions_rad.size(); ++c) {
      const double x = p.positions_rad[c];
      if (!std::isfinite(x)) {
        why.add(kFinite,
                at + ".positions[" + std::to_string(c) + "] (" + joint_name(c) + "): " + num(x) + " is not finite");
      } else if (c < width && joint_of[c] >= 0) {
        const int j = joint_of[c];
        const double lo = limits_.lower_rad[j] - limits_.limit_tolerance_rad;
        const double hi = limits_.upper_rad[j] + limits_.limit_tolerance_rad;
        if (x < lo || x > hi)
          why.add(kLimits, at + ".positions[" + std::to_string(c) + "] (" + joint_name(c) + "): " + num(x) +
                               " rad outside the joint limits [" + num(limits_.lower_rad[j]) + ", " +
                               num(limits_.upper_rad[j]) + "] rad");
      }
    }
    for (std::size_t c = 0; c < p.velocities_rad_s.size(); ++c) {
      const double x = p.velocities_rad_s[c];
      if (!std::isfinite(x))
        why.add(kFinite,
                at + ".velocities[" + std::to_string(c) + "] (" + joint_name(c) + "): " + num(x) + " is not finite");
    }
  }
  if (!why.empty()) return why.str();

  // Well formed: the segments between points, with the velocities the loop will use. Segment
  // point 0 -> 1 with an estimated velocity at point 0 depends on the present posture: take() checks it.
  Buffer b;
  b.t_s.resize(count);
  b.q.resize(static_cast<std::size_t>(count) * n_);
  b.v.resize(b.q.size());
  b.v_given.resize(count);
  b.final_rad.resize(n_);
  fill(request, joint_of, b);
  for (int k = 1; k < count; ++k) {
    if (k == 1 && !b.v_given[0]) continue;
    const double h = b.t_s[k] - b.t_s[k - 1];
    for (int j = 0; j < n_; ++j) {
      const std::size_t i0 = static_cast<std::size_t>(k - 1) * n_ + j, i1 = i0 + n_;
      const double peak = hermite_peak(b.q[i0], b.q[i1], b.v[i0], b.v[i1], h);
      if (over(peak, limits_.max_velocity_rad_s))
        why.add(kVelocity, "points[" + std::to_string(k - 1) + "] -> points[" + std::to_string(k) + "] (" +
                               num(b.t_s[k - 1]) + " -> " + num(b.t_s[k]) + " s): joint_" + std::to_string(j + 1) +
                               " needs " + num(peak) + " rad/s, over max_joint_velocity_rad_s " +
                               num(limits_.max_velocity_rad_s));
    }
  }
  return why.str();
}

void TrajectorySource::fill(const JointTrajectoryRequest& request, const std::vector<int>& joint_of,
                            Buffer& out) const {
  const int count = static_cast<int>(request.points.size());
  std::snprintf(out.id.data(), out.id.size(), "%s", request.id.c_str());
  out.count = count;
  for (int k = 0; k < count; ++k) {
    const JointTrajectoryPoint& p = request.points[k];
    out.t_s[k] = p.time_from_start_s;
    out.v_given[k] = p.velocities_rad_s.empty() ? 0 : 1;
    for (std::size_t c = 0; c < joint_of.size(); ++c) {
      const std::size_t i = static_cast<std::size_t>(k) * n_ + joint_of[c];
      out.q[i] = p.positions_rad[c];
      out.v[i] = p.velocities_rad_s.empty() ? 0.0 : p.velocities_rad_s[c];
    }
  }
  // Estimated velocities: inside, the monotone estimate; the last point at rest (v stays 0);
  // point 0's at take() (it needs the present posture).
  for (int k = 1; k + 1 < count; ++k) {
    if (out.v_given[k]) continue;
    const double h0 = out.t_s[k] - out.t_s[k - 1], h1 = out.t_s[k + 1] - out.t_s[k];
    for (int j = 0; j < n_; ++j) {
      const std::size_t i = static_cast<std::size_t>(k) * n_ + j;
      out.v[i] = monotone_slope((out.q[i] - out.q[i - n_]) / h0, (out.q[i + n_] - out.q[i]) / h1, h0, h1);
    }
  }
  for (int j = 0; j < n_; ++j) out.final_rad[j] = out.q[static_cast<std::size_t>(count - 1) * n_ + j];
}

std::string TrajectorySource::submit(const JointTrajectoryRequest& request) {
  std::string why = check(request);
  if (!why.empty()) return why;
  std::vector<int> joint_of(request.joint_names.size());
  for (std::size_t c = 0; c < joint_of.size(); ++c) joint_of[c] = std::stoi(request.joint_names[c].substr(6)) - 1;
  std::lock_guard<std::mutex> lock(mailbox_);
  const std::uint64_t sequence = ++accepted_;
  if (has_pending_) {  // accepted earlier, never taken: it ends here, superseded by this one
    TrajectoryProgress replaced;
    replaced.sequence = pending_.sequence;
    replaced.id = pending_.id;
    replaced.phase = TrajectoryPhase::kAborted;
    replaced.abort = TrajectoryAbort::kSuperseded;
    replaced.num_points = pending_.count;
    replaced.duration_s = pending_.t_s[pending_.count - 1];
    std::snprintf(replaced.superseded_by.data(), replaced.superseded_by.size(), "%s", request.id.c_str());
    replaced.superseded_by_sequence = sequence;
    std::snprintf(replaced.reason.data(), replaced.reason.size(),
                  "superseded by '%s' (sequence %llu) before it started", replaced.superseded_by.data(),
                  static_cast<unsigned long long>(sequence));
    submit_finals_.push(replaced);
  }
  fill(request, joint_of, pending_);  // into the storage reserved at construction: no allocation
  pending_.sequence = sequence;
  has_pending_ = true;
  return "";
}

bool TrajectorySource::pop_final(TrajectoryProgress* out) noexcept {
  return loop_finals_.pop(out) || submit_finals_.pop(out);
}

// ---------------------------------------------------------------------------------------------
// The loop

bool TrajectorySource::take(double t_s, const Eigen::VectorXd& present_rad, bool allowed) noexcept {
  if (!mailbox_.try_lock()) return false;
  if (!has_pending_) {
    mailbox_.unlock();
    return false;
  }
  std::swap(active_.id, pending_.id);
  std::swap(active_.sequence, pending_.sequence);
  std::swap(active_.count, pending_.count);
  active_.t_s.swap(pending_.t_s);
  active_.q.swap(pending_.q);
  active_.v.swap(pending_.v);
  active_.v_given.swap(pending_.v_given);
  active_.final_rad.swap(pending_.final_rad);
  has_pending_ = false;
  mailbox_.unlock();

  if (running()) {
    progress_.superseded_by = active_.id;
    progress_.superseded_by_sequence = active_.sequence;
    std::snprintf(progress_.reason.data(), progress_.reason.size(),
                  "superseded by '%s' (sequence %llu) at %.3f s of %.3f s", active_.id.data(),
                  static_cast<unsigned long long>(active_.sequence), progress_.time_s, progress_.duration_s);
    finish(TrajectoryPhase::kAborted, TrajectoryAbort::kSuperseded);
  }
  progress_.sequence = active_.sequence;
  progress_.id = active_.id;
  progress_.superseded_by[0] = '\0';
  progress_.superseded_by_sequence = 0;
  progress_.phase = TrajectoryPhase::kRunning;
  progress_.abort = TrajectoryAbort::kNone;
  progress_.reason[0] = '\0';
  progress_.point_reached = -1;
  progress_.num_points = active_.count;
  progress_.time_s = 0.0;
  progress_.duration_s = active_.t_s[active_.count - 1];
  start_ = present_rad;
  t0_s_ = t_s;
  segment_ = 0;
  if (!allowed) {
    std::snprintf(progress_.reason.data(), progress_.reason.size(), "taken while torque was off or in a fault");
    finish(TrajectoryPhase::kAborted, TrajectoryAbort::kNotAllowed);
    return true;
  }
  estimate_first_velocity();
  if (!check_first_segments()) finish(TrajectoryPhase::kAborted, TrajectoryAbort::kFirstSegmentTooFast);
  return true;
}

void TrajectorySource::estimate_first_velocity() noexcept {
  if (active_.v_given[0]) return;
  for (int j = 0; j < n_; ++j) {
    double& v0 = active_.v[j];
    v0 = 0.0;  // a single point is the last: at rest
    if (active_.count < 2) continue;
    const double h0 = active_.t_s[0], h1 = active_.t_s[1] - active_.t_s[0];
    v0 = monotone_slope((active_.q[j] - start_[j]) / h0, (active_.q[n_ + j] - active_.q[j]) / h1, h0, h1);
  }
}

bool TrajectorySource::check_first_segments() noexcept {
  const int segments = active_.v_given[0] || active_.count < 2 ? 1 : 2;
  for (int k = 0; k < segments; ++k) {
    const double t_a = k == 0 ? 0.0 : active_.t_s[0], h = active_.t_s[k] - t_a;
    for (int j = 0; j < n_; ++j) {
      const std::size_t i1 = static_cast<std::size_t>(k) * n_ + j;
      const double p0 = k == 0 ? start_[j] : active_.q[i1 - n_], m0 = k == 0 ? 0.0 : active_.v[i1 - n_];
      const double peak = hermite_peak(p0, active_.q[i1], m0, active_.v[i1], h);
      if (!over(peak, limits_.max_velocity_rad_s)) continue;
      std::snprintf(progress_.reason.data(), progress_.reason.size(),
                    "%s (%.6g -> %.6g s): joint_%d needs %.6g rad/s from %.6g rad, over max_joint_velocity_rad_s %.6g",
                    k == 0 ? "present posture -> points[0]" : "points[0] -> points[1]", t_a, active_.t_s[k], j + 1,
                    peak, p0, limits_.max_velocity_rad_s);
      return false;
    }
  }
  return true;
}

bool TrajectorySource::update(double t_s, Eigen::VectorXd& goal_rad) noexcept {
  if (!running()) return false;
  const double tau = std::max(0.0, t_s - t0_s_);
  const int count = active_.count;
  while (segment_ < count && tau >= active_.t_s[segment_]) ++segment_;
  progress_.point_reached = segment_ - 1;
  progress_.time_s = std::min(tau, progress_.duration_s);
  if (segment_ >= count) {
    goal_rad = active_.final_rad;
    finish(TrajectoryPhase::kDone, TrajectoryAbort::kNone);
    return false;
  }
  const int k = segment_;
  const double t_a = k == 0 ? 0.0 : active_.t_s[k - 1], h = active_.t_s[k] - t_a;
  const double s = std::clamp((tau - t_a) / h, 0.0, 1.0);
  for (int j = 0; j < n_; ++j) {
    const std::size_t i1 = static_cast<std::size_t>(k) * n_ + j;
    const double p0 = k == 0 ? start_[j] : active_.q[i1 - n_], m0 = k == 0 ? 0.0 : active_.v[i1 - n_];
    goal_rad[j] = hermite(p0, active_.q[i1], m0, active_.v[i1], h, s);
  }
  return true;
}

void TrajectorySource::abort(TrajectoryAbort reason) noexcept {
  if (!running()) return;
  std::snprintf(progress_.reason.data(), progress_.reason.size(), "ended at %.3f s of %.3f s: %s", progress_.time_s,
                progress_.duration_s, to_string(reason));
  finish(TrajectoryPhase::kAborted, reason);
}

void TrajectorySource::finish(TrajectoryPhase phase, TrajectoryAbort reason) noexcept {
  progress_.phase = phase;
  progress_.abort = reason;
  loop_finals_.push(progress_);  // a full queue counts the loss (finals_dropped)
}

}  // namespace snake_autonomy::driver
