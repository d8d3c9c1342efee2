#include "driver_params.hpp"

#include <xmlrpcpp/XmlRpcValue.h>

#include <cmath>
#include <sstream>

namespace snake_autonomy::ros_driver {
namespace {

class ParamReader {
 public:
  ParamReader(const ros::NodeHandle& nh, std::vector<std::string>& errors) : nh_(nh), errors_(errors) {}

  void get(const std::string& key, std::string* out) {
    XmlRpc::XmlRpcValue v;
    if (!fetch(key, &v)) return;
    if (v.getType() == XmlRpc::XmlRpcValue::TypeString) {
      *out = static_cast<std::string>(v);
    } else {
      bad(key, v, "is not a string");
    }
  }
  void get(const std::string& key, int* out) {
    XmlRpc::XmlRpcValue v;
    if (!fetch(key, &v)) return;
    if (v.getType() == XmlRpc::XmlRpcValue::TypeInt) {
      *out = static_cast<int>(v);
    } else {
      bad(key, v, "is not an integer");
    }
  }
  void get(const std::string& key, double* out) {
    XmlRpc::XmlRpcValue v;
    if (!fetch(key, &v)) return;
    if (v.getType() == XmlRpc::XmlRpcValue::TypeDouble) {
      *out = static_cast<double>(v);
    } else if (v.getType() == XmlRpc::XmlRpcValue::TypeInt) {
      *out = static_cast<int>(v);
    } else {
      bad(key, v, "is not a number");
    }
  }
  void get(const std::string& key, bool* out) {
    XmlRpc::XmlRpcValue v;
    if (!fetch(key, &v)) return;
    if (v.getType() == XmlRpc::XmlRpcValue::TypeBoolean) {
      *out = static_cast<bool>(v);
    } else {
      bad(key, v, "is not true or false");
    }
  }
  void get(const std::string& key, core::SafeAction* out) {
    std::string text = core::to_string(*out);
    get(key, &text);
    if (!core::parse_safe_action(text, out)) errors_.push_back("~" + key + ": '" + text + "' is not hold or torque_off");
  }

 private:
  bool fetch(const std::string& key, XmlRpc::XmlRpcValue* v) { return nh_.getParam(key, *v); }
  void bad(const std::string& key, XmlRpc::XmlRpcValue& v, const char* what) {
    errors_.push_back("~" + key + ": " + v.toXml() + " " + what);
  }
  const ros::NodeHandle& nh_;
  std::vector<std::string>& errors_;
};

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

std::string DriverNodeConfig::robot_file() const {
  if (ends_with(robot, ".yaml") || robot.find('/') != std::string::npos) return robot;
  return config_dir + "/robots/" + robot + ".yaml";
}

std::vector<std::string> DriverNodeConfig::validate() const {
  std::vector<std::string> errors;
  for (const auto& e : serial.validate()) errors.push_back("~" + e);
  for (const auto& e : loop.validate()) errors.push_back("~" + e);
  for (const auto& e : controller.validate()) errors.push_back("~" + e);
  auto bad = [&errors](const std::string& key, double value, const char* need) {
    std::ostringstream s;
    s << "~" << key << ": " << value << " " << need;
    errors.push_back(s.str());
  };
  if (config_dir.empty()) errors.push_back("~config_dir: missing (the launch file sets $(find snake_autonomy)/config)");
  if (robot.empty()) errors.push_back("~robot: empty");
  if (realtime_priority < 0 || realtime_priority > 99) bad("realtime_priority", realtime_priority, "is not in 0 .. 99");
  for (const auto* f : {&world_frame, &base_frame, &com_frame}) {
    if (f->empty()) errors.push_back("~world_frame/base_frame/com_frame: a frame name is empty");
  }
  if (!(diagnostics_period_s >= 0.1) || !std::isfinite(diagnostics_period_s))
    bad("diagnostics_period_s", diagnostics_period_s, "is not a number >= 0.1");
  if (!(connect_timeout_s >= 0.0) || !std::isfinite(connect_timeout_s))
    bad("connect_timeout_s", connect_timeout_s, "is not a number >= 0");
  if (!(service_timeout_s > 0.0) || !std::isfinite(service_timeout_s))
    bad("service_timeout_s", service_timeout_s, "is not a positive number");
  return errors;
}

DriverNodeConfig read_driver_params(const ros::NodeHandle& pnh, std::vector<std::string>& errors) {
  DriverNodeConfig c;
  ParamReader r(pnh, errors);
  r.get("config_dir", &c.config_dir);
  r.get("robot", &c.robot);
  r.get("gaits_file", &c.gaits_file);
  r.get("control_table_file", &c.control_table_file);
  r.get("port", &c.serial.device);
  r.get("baud", &c.serial.baud_bps);
  r.get("low_latency", &c.serial.low_latency);
  r.get("bus_latency_s", &c.serial.timing.latency_s);
  r.get("bus_timeout_margin", &c.serial.timing.margin);
  r.get("rate_hz", &c.loop.rate_hz);
  r.get("realtime_priority", &c.realtime_priority);
  r.get("world_frame", &c.world_frame);
  r.get("base_frame", &c.base_frame);
  r.get("com_frame", &c.com_frame);
  r.get("publish_tf", &c.publish_tf);
  r.get("diagnostics_period_s", &c.diagnostics_period_s);
  r.get("connect_timeout_s", &c.connect_timeout_s);
  r.get("service_timeout_s", &c.service_timeout_s);
  auto& k = c.controller;
  r.get("fast_sync_read", &k.fast_sync_read);
  r.get("max_failed_cycles", &k.max_failed_cycles);
  r.get("status_every_cycles", &k.status_every_cycles);
  r.get("return_delay_time_us", &k.return_delay_time_us);
  r.get("fault_action", &k.fault_action);
  r.get("shutdown_action", &k.shutdown_action);
  r.get("torque_on_start", &k.torque_on_start);
  r.get("max_joint_velocity_rad_s", &k.max_joint_velocity_rad_s);
  r.get("max_frequency_hz", &k.max_frequency_hz);
  r.get("max_step_s", &k.max_step_s);
  r.get("plausible_margin_ticks", &k.plausible_margin_ticks);
  r.get("pose_timeout_s", &k.pose_timeout_s);
  r.get("require_pose", &k.require_pose);
  r.get("command_timeout_s", &k.command_timeout_s);
  r.get("pose_workspace_m", &k.pose_workspace_m);
  r.get("quaternion_norm_tolerance", &k.quaternion_norm_tolerance);
  if (c.gaits_file.empty()) c.gaits_file = c.config_dir + "/gaits.yaml";
  for (const auto& e : c.validate()) errors.push_back(e);
  return c;
}

}  // namespace snake_autonomy::ros_driver
