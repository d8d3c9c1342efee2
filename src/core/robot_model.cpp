#include "snake_autonomy/core/robot_model.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "snake_autonomy/core/config_reader.hpp"

namespace snake_autonomy::core {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

std::string to_string(JointAxis axis) { return axis == JointAxis::kPitch ? "pitch" : "yaw"; }

std::string to_string(ChassisMethod method) { return method == ChassisMethod::kMeanAxis ? "mean_axis" : "svd"; }

std::vector<std::string> RobotModel::frame_names() const {
  std::vector<std::string> out{"base_link", "head_link"};
  for (int i = 1; i <= num_joints; ++i) out.push_back("link_" + std::to_string(i));
  return out;
}

std::vector<std::string> RobotModel::joint_names() const {
  std::vector<std::string> out;
  for (int i = 1; i <= num_joints; ++i) out.push_back("joint_" + std::to_string(i));
  return out;
}

std::vector<int> RobotModel::yaw_joints() const {
  std::vector<int> out;
  for (int i = 0; i < static_cast<int>(axes.size()); ++i)
    if (axes[i] == JointAxis::kYaw) out.push_back(i);
  return out;
}

std::vector<int> RobotModel::pitch_joints() const {
  std::vector<int> out;
  for (int i = 0; i < static_cast<int>(axes.size()); ++i)
    if (axes[i] == JointAxis::kPitch) out.push_back(i);
  return out;
}

std::vector<std::string> RobotModel::validate() const {
  std::vector<std::string> e;
  // a physical range (lo, hi]: positive and at most hi (e.g. no mass of 1e308 kg)
  auto positive_upto = [&](const std::string& key, double v, double hi, const char* unit) {
    if (!(v > 0.0) || !std::isfinite(v)) e.push_back(key + ": must be a positive number, got " + fmt(v));
    else if (v > hi) e.push_back(key + ": must be at most " + fmt(hi) + " " + unit + ", got " + fmt(v));
  };
  auto within = [&](const std::string& key, double v, double bound, const char* unit) {
    if (!std::isfinite(v) || std::abs(v) > bound)
      e.push_back(key + ": must be within +-" + fmt(bound) + " " + unit + ", got " + fmt(v));
  };
  auto length = [&](const std::string& key, std::size_t got, std::size_t want) {
    if (got != want) e.push_back(key + ": expected " + std::to_string(want) + " values, got " + std::to_string(got));
    return got == want;
  };
  if (num_joints < 2 || num_joints > kMaxJoints) {
    e.push_back("num_joints: must be an integer in 2.." + std::to_string(kMaxJoints) + ", got " +
                std::to_string(num_joints));
    return e;  // every other length check depends on it
  }
  const auto n = static_cast<std::size_t>(num_joints);
  length("axis_pattern", axes.size(), n);
  positive_upto("head_length_m", head_length_m, kMaxLengthM, "m");
  positive_upto("link_length_m", link_length_m, kMaxLengthM, "m");
  positive_upto("link_radius_m", link_radius_m, kMaxLengthM, "m");
  if (length("masses_kg", masses_kg.size(), n + 2))
    for (std::size_t i = 0; i < masses_kg.size(); ++i)
      positive_upto("masses_kg[" + std::to_string(i) + "]", masses_kg[i], kMaxMassKg, "kg");
  const bool lower_ok = length("joint_limits_deg.lower", joint_lower_rad.size(), n);
  const bool upper_ok = length("joint_limits_deg.upper", joint_upper_rad.size(), n);
  if (lower_ok && upper_ok) {
    for (std::size_t i = 0; i < n; ++i) {
      const double lo = joint_lower_rad[i], hi = joint_upper_rad[i];
      if (!std::isfinite(lo) || !std::isfinite(hi) || lo >= hi)
        e.push_back("joint_limits_deg[" + std::to_string(i) + "]: lower must be < upper, got lower " +
                    fmt(lo / kDegToRad) + ", upper " + fmt(hi / kDegToRad));
      else if (lo < -M_PI - 1e-12 || hi > M_PI + 1e-12)
        e.push_back("joint_limits_deg[" + std::to_string(i) + "]: must be within +-180, got lower " +
                    fmt(lo / kDegToRad) + ", upper " + fmt(hi / kDegToRad));
    }
  }
  if (servos.model.empty()) e.push_back("servos.model: missing");
  if (length("servos.ids", servos.ids.size(), n)) {
    for (std::size_t i = 0; i < n; ++i) {
      if (servos.ids[i] < 0 || servos.ids[i] > 252)
        e.push_back("servos.ids[" + std::to_string(i) + "]: must be 0-252, got " + std::to_string(servos.ids[i]));
      for (std::size_t j = 0; j < i; ++j)
        if (servos.ids[j] == servos.ids[i])
          e.push_back("servos.ids[" + std::to_string(i) + "]: duplicate id " + std::to_string(servos.ids[i]));
    }
  }
  if (length("servos.directions", servos.directions.size(), n))
    for (std::size_t i = 0; i < n; ++i)
      if (servos.directions[i] != 1 && servos.directions[i] != -1)
        e.push_back("servos.directions[" + std::to_string(i) + "]: must be 1 or -1, got " +
                    std::to_string(servos.directions[i]));
  if (length("servos.zero_offsets_ticks", servos.zero_offsets_ticks.size(), n))
    for (std::size_t i = 0; i < n; ++i)
      if (std::abs(servos.zero_offsets_ticks[i]) > 2048)
        e.push_back("servos.zero_offsets_ticks[" + std::to_string(i) + "]: must be within +-2048, got " +
                    std::to_string(servos.zero_offsets_ticks[i]));
  positive_upto("cpg.mu", cpg.mu, kMaxCpgRate, "1/s");
  positive_upto("cpg.gamma", cpg.gamma, kMaxCpgRate, "rad/s");
  positive_upto("cpg.amplitude_limit_deg", cpg.amplitude_limit_rad / kDegToRad, 180.0, "deg");
  const std::size_t n_yaw = yaw_joints().size();
  if (axes.size() == n) length("steering.weights", steering.weights.size(), n_yaw);
  for (std::size_t i = 0; i < steering.weights.size(); ++i)
    within("steering.weights[" + std::to_string(i) + "]", steering.weights[i], kMaxSteeringWeight, "");
  positive_upto("steering.delta_limit_deg", steering.delta_limit_rad / kDegToRad, 90.0, "deg");
  within("steering.delta_offset_deg", steering.delta_offset_rad / kDegToRad, 90.0, "deg");
  within("steering.amplitude_min_deg", steering.amplitude_min_rad / kDegToRad, 180.0, "deg");
  within("steering.amplitude_max_deg", steering.amplitude_max_rad / kDegToRad, 180.0, "deg");
  if (!(steering.amplitude_min_rad < steering.amplitude_max_rad))
    e.push_back("steering.amplitude_min_deg: must be < amplitude_max_deg, got " +
                fmt(steering.amplitude_min_rad / kDegToRad) + " and " + fmt(steering.amplitude_max_rad / kDegToRad));
  if (!(bbox_padding_m >= 0.0) || !std::isfinite(bbox_padding_m))
    e.push_back("bounding_box_padding_m: must be >= 0, got " + fmt(bbox_padding_m));
  else if (bbox_padding_m > kMaxLengthM)
    e.push_back("bounding_box_padding_m: must be at most " + fmt(kMaxLengthM) + " m, got " + fmt(bbox_padding_m));
  return e;
}

void RobotModel::validate_or_throw() const {
  const auto errors = validate();
  if (errors.empty()) return;
  std::string msg = "robot '" + name + "' is invalid (" + std::to_string(errors.size()) + " problems):";
  for (const auto& err : errors) msg += "\n  " + err;
  throw ConfigError(msg);
}

RobotModel RobotModel::from_yaml_string(const std::string& text, const std::string& source) {
  const YAML::Node root = load_config_yaml(text, source);

  std::vector<std::string> errors;
  ConfigReader r(&errors);
  RobotModel m;
  r.scalar(r.child(root, "name", "name"), "name", &m.name);
  r.scalar(r.child(root, "num_joints", "num_joints"), "num_joints", &m.num_joints);
  const bool joints_ok = m.num_joints >= 2 && m.num_joints <= kMaxJoints;  // before anything is sized by it

  std::vector<std::string> pattern;
  if (r.list(r.child(root, "axis_pattern", "axis_pattern"), "axis_pattern", &pattern)) {
    std::vector<JointAxis> cycle;
    for (std::size_t i = 0; i < pattern.size(); ++i) {
      if (pattern[i] == "pitch") {
        cycle.push_back(JointAxis::kPitch);
      } else if (pattern[i] == "yaw") {
        cycle.push_back(JointAxis::kYaw);
      } else {
        errors.push_back("axis_pattern[" + std::to_string(i) + "]: unknown axis '" + pattern[i] +
                         "' (expected pitch or yaw)");
      }
    }
    if (cycle.size() == pattern.size() && !cycle.empty() && joints_ok) {
      if (cycle.size() > static_cast<std::size_t>(m.num_joints)) {
        errors.push_back("axis_pattern: " + std::to_string(cycle.size()) + " entries for " +
                         std::to_string(m.num_joints) + " joints");
      } else {
        for (int i = 0; i < m.num_joints; ++i) m.axes.push_back(cycle[i % cycle.size()]);
      }
    }
  }
  r.scalar(r.child(root, "head_length_m", "head_length_m"), "head_length_m", &m.head_length_m);
  r.scalar(r.child(root, "link_length_m", "link_length_m"), "link_length_m", &m.link_length_m);
  m.link_radius_m = 0.04;
  r.scalar(r.child(root, "link_radius_m", "link_radius_m", false), "link_radius_m", &m.link_radius_m);
  r.list(r.child(root, "masses_kg", "masses_kg"), "masses_kg", &m.masses_kg);

  YAML::Node limits = r.child(root, "joint_limits_deg", "joint_limits_deg");
  std::vector<double> lo, hi;
  r.list(r.child(limits, "lower", "joint_limits_deg.lower"), "joint_limits_deg.lower", &lo);
  r.list(r.child(limits, "upper", "joint_limits_deg.upper"), "joint_limits_deg.upper", &hi);
  for (double v : lo) m.joint_lower_rad.push_back(v * kDegToRad);
  for (double v : hi) m.joint_upper_rad.push_back(v * kDegToRad);

  YAML::Node servos = r.child(root, "servos", "servos");
  r.scalar(r.child(servos, "model", "servos.model"), "servos.model", &m.servos.model);
  r.list(r.child(servos, "ids", "servos.ids"), "servos.ids", &m.servos.ids);
  r.list(r.child(servos, "directions", "servos.directions"), "servos.directions", &m.servos.directions);
  r.list(r.child(servos, "zero_offsets_ticks", "servos.zero_offsets_ticks"), "servos.zero_offsets_ticks",
         &m.servos.zero_offsets_ticks);

  YAML::Node cpg = r.child(root, "cpg", "cpg");
  r.scalar(r.child(cpg, "mu", "cpg.mu"), "cpg.mu", &m.cpg.mu);
  r.scalar(r.child(cpg, "gamma", "cpg.gamma"), "cpg.gamma", &m.cpg.gamma);
  double amp_limit_deg = 0.0;
  r.scalar(r.child(cpg, "amplitude_limit_deg", "cpg.amplitude_limit_deg"), "cpg.amplitude_limit_deg", &amp_limit_deg);
  m.cpg.amplitude_limit_rad = amp_limit_deg * kDegToRad;

  YAML::Node steer = r.child(root, "steering", "steering");
  r.list(r.child(steer, "weights", "steering.weights"), "steering.weights", &m.steering.weights);
  double deg = 0.0;
  if (r.scalar(r.child(steer, "delta_limit_deg", "steering.delta_limit_deg"), "steering.delta_limit_deg", &deg))
    m.steering.delta_limit_rad = deg * kDegToRad;
  deg = 0.0;
  if (r.scalar(r.child(steer, "delta_offset_deg", "steering.delta_offset_deg", false), "steering.delta_offset_deg",
               &deg))
    m.steering.delta_offset_rad = deg * kDegToRad;
  if (r.scalar(r.child(steer, "amplitude_min_deg", "steering.amplitude_min_deg"), "steering.amplitude_min_deg", &deg))
    m.steering.amplitude_min_rad = deg * kDegToRad;
  if (r.scalar(r.child(steer, "amplitude_max_deg", "steering.amplitude_max_deg"), "steering.amplitude_max_deg", &deg))
    m.steering.amplitude_max_rad = deg * kDegToRad;

  std::string chassis = "mean_axis";
  r.scalar(r.child(root, "virtual_chassis", "virtual_chassis", false), "virtual_chassis", &chassis);
  if (chassis == "mean_axis") {
    m.chassis = ChassisMethod::kMeanAxis;
  } else if (chassis == "svd") {
    m.chassis = ChassisMethod::kSvd;
  } else {
    errors.push_back("virtual_chassis: unknown construction '" + chassis + "' (expected mean_axis or svd)");
  }
  r.scalar(r.child(root, "bounding_box_padding_m", "bounding_box_padding_m", false), "bounding_box_padding_m",
           &m.bbox_padding_m);

  // Semantic checks only where parsing succeeded enough to make them meaningful.
  if (m.num_joints >= 2 || errors.empty())
    for (auto& e : m.validate())
      if (std::find(errors.begin(), errors.end(), e) == errors.end()) errors.push_back(e);
  throw_if_errors(errors, source, "robot description");
  return m;
}

RobotModel RobotModel::from_yaml_file(const std::string& path) {
  return from_yaml_string(read_config_file(path, "robot description"), path);
}

}  // namespace snake_autonomy::core
