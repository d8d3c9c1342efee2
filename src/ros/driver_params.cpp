#include "driver_params.hpp"

#include <xmlrpcpp/XmlRpcValue.h>
#include <yaml-cpp/yaml.h>

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

 private:
  bool fetch(const std::string& key, XmlRpc::XmlRpcValue* v) { return nh_.getParam(key, *v); }
  void bad(const std::string& key, XmlRpc::XmlRpcValue& v, const char* what) {
    errors_.push_back("~" + key + ": " + v.toXml() + " " + what);
  }
  const ros::NodeHandle& nh_;
  std::vector<std::string>& errors_;
};

// The rosparams named like DriverConfig's keys, as the YAML mapping the core's loader reads.
YAML::Node controller_params_as_yaml(const ros::NodeHandle& nh) {
  YAML::Node doc(YAML::NodeType::Map);
  for (const auto& key : driver::DriverConfig::keys()) {
    XmlRpc::XmlRpcValue v;
    if (!nh.getParam(key, v)) continue;
    switch (v.getType()) {
      case XmlRpc::XmlRpcValue::TypeBoolean: doc[key] = static_cast<bool>(v); break;
      case XmlRpc::XmlRpcValue::TypeInt: doc[key] = static_cast<int>(v); break;
      case XmlRpc::XmlRpcValue::TypeDouble: doc[key] = static_cast<double>(v); break;
      case XmlRpc::XmlRpcValue::TypeString: doc[key] = static_cast<std::string>(v); break;
      default: doc[key] = v.toXml(); break;  // refused by the loader as the wrong type, value shown
    }
  }
  return doc;
}

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
  // The controller's keys: an optional file (~driver_config_file) read by the core's loader, then
  // every rosparam of DriverConfig::keys() over it through the same loader (apply_yaml).
  std::string controller_file;
  r.get("driver_config_file", &controller_file);
  if (!controller_file.empty()) {
    try {
      c.controller = driver::DriverConfig::from_yaml_file(controller_file);
    } catch (const std::exception& e) {
      errors.push_back(std::string("~driver_config_file: ") + e.what());
    }
  }
  c.controller.apply_yaml(controller_params_as_yaml(pnh), &errors, "~");
  if (c.gaits_file.empty()) c.gaits_file = c.config_dir + "/gaits.yaml";
  for (const auto& e : c.validate()) errors.push_back(e);
  return c;
}

}  // namespace snake_autonomy::ros_driver
