#include "snake_autonomy/core/gait_library.hpp"

#include <cmath>
#include <stdexcept>

#include "snake_autonomy/core/config_reader.hpp"

namespace snake_autonomy::core {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

void read_wave(const YAML::Node& gait, const std::string& axis, const std::string& where, WaveSpec* w,
               std::vector<std::string>* errors) {
  ConfigReader r(errors);
  const YAML::Node n = gait[axis];
  if (!n || !n.IsMap()) {
    errors->push_back(where + "." + axis + ": missing (a mapping with amplitude_deg, lag_deg, offset_deg, bias_deg)");
    return;
  }
  const std::string at = where + "." + axis;
  for (auto it = n.begin(); it != n.end(); ++it) {
    const auto key = it->first.as<std::string>();
    if (key != "amplitude_deg" && key != "lag_deg" && key != "offset_deg" && key != "bias_deg")
      errors->push_back(at + "." + key + ": unknown key (expected amplitude_deg, lag_deg, offset_deg, bias_deg)");
  }
  auto angle = [&](const char* key, bool required, double* out_rad) {
    double deg = 0.0;
    if (r.scalar(r.child(n, key, at + "." + key, required), at + "." + key, &deg)) *out_rad = deg * kDegToRad;
  };
  angle("amplitude_deg", true, &w->amplitude_rad);
  angle("lag_deg", false, &w->lag_rad);
  angle("offset_deg", false, &w->offset_rad);
  angle("bias_deg", false, &w->bias_rad);
}

}  // namespace

GaitLibrary GaitLibrary::from_yaml_string(const std::string& text, const std::string& source) {
  const YAML::Node root = load_config_yaml(text, source);
  if (!root["gaits"] || !root["gaits"].IsMap())
    throw ConfigError(source + ": expected a mapping 'gaits:' of gait names to definitions");
  std::vector<std::string> errors;
  GaitLibrary lib;
  for (auto it = root["gaits"].begin(); it != root["gaits"].end(); ++it) {
    GaitSpec g;
    g.name = it->first.as<std::string>();
    const std::string where = "gaits." + g.name;
    const YAML::Node n = it->second;
    if (!n.IsMap()) {
      errors.push_back(where + ": expected a mapping");
      continue;
    }
    if (n["description"]) g.description = n["description"].as<std::string>();
    ConfigReader r(&errors);
    if (r.scalar(r.child(n, "frequency_hz", where + ".frequency_hz"), where + ".frequency_hz", &g.frequency_hz) &&
        g.frequency_hz < 0.0)
      errors.push_back(where + ".frequency_hz: must be >= 0, got " + std::to_string(g.frequency_hz));
    read_wave(n, "pitch", where, &g.pitch, &errors);
    read_wave(n, "yaw", where, &g.yaw, &errors);
    r.scalar(r.child(n, "steerable", where + ".steerable", false), where + ".steerable", &g.steerable);
    lib.gaits_[g.name] = g;
  }
  if (lib.gaits_.empty()) errors.push_back("gaits: no gait defined");
  throw_if_errors(errors, source, "gait library");
  return lib;
}

GaitLibrary GaitLibrary::from_yaml_file(const std::string& path) {
  return from_yaml_string(read_config_file(path, "gait library"), path);
}

std::vector<std::string> GaitLibrary::names() const {
  std::vector<std::string> out;
  for (const auto& kv : gaits_) out.push_back(kv.first);
  return out;
}

const GaitSpec& GaitLibrary::spec(const std::string& name) const {
  const auto it = gaits_.find(name);
  if (it == gaits_.end()) {
    std::string known;
    for (const auto& kv : gaits_) known += (known.empty() ? "" : ", ") + kv.first;
    throw std::out_of_range("unknown gait '" + name + "' (known: " + known + ")");
  }
  return it->second;
}

GaitParameters GaitLibrary::parameters(const std::string& name, const RobotModel& model) const {
  const GaitSpec& g = spec(name);
  GaitParameters p = GaitParameters::zeros(model.num_joints);
  for (int i = 0; i < model.num_joints; ++i) {
    const WaveSpec& w = model.axes[i] == JointAxis::kPitch ? g.pitch : g.yaw;
    p.amplitude(i) = w.amplitude_rad;
    p.phase(i) = w.offset_rad + i * w.lag_rad;
    p.bias(i) = w.bias_rad;
    p.omega(i) = 2.0 * M_PI * g.frequency_hz;
  }
  return p;
}

}  // namespace snake_autonomy::core
