#include "snake_autonomy/core/gait_library.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "snake_autonomy/core/config_reader.hpp"

namespace snake_autonomy::core {
namespace {

constexpr double kDegToRad = M_PI / 180.0;
// Loader bounds (physical ranges): a gait outside them is refused with its key and value.
constexpr double kMaxFrequencyHz = 5.0;    // far above what the servos follow (the driver limits further)
constexpr double kMaxAngleDeg = 180.0;     // |amplitude_deg|, |bias_deg|
constexpr double kMaxPhaseDeg = 360.0;     // |lag_deg|, |offset_deg|
constexpr std::size_t kMaxGaits = 256;

std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

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
    const auto key = it->first.IsScalar() ? it->first.Scalar() : ConfigReader::dump(it->first);
    if (key != "amplitude_deg" && key != "lag_deg" && key != "offset_deg" && key != "bias_deg")
      errors->push_back(at + "." + key + ": unknown key (expected amplitude_deg, lag_deg, offset_deg, bias_deg)");
  }
  auto angle = [&](const char* key, bool required, double bound_deg, double* out_rad) {
    double deg = 0.0;
    if (!r.scalar(r.child(n, key, at + "." + key, required), at + "." + key, &deg)) return;
    if (std::abs(deg) > bound_deg) {
      errors->push_back(at + "." + key + ": must be within +-" + fmt(bound_deg) + " deg, got " + fmt(deg));
      return;
    }
    *out_rad = deg * kDegToRad;
  };
  angle("amplitude_deg", true, kMaxAngleDeg, &w->amplitude_rad);
  angle("lag_deg", false, kMaxPhaseDeg, &w->lag_rad);
  angle("offset_deg", false, kMaxPhaseDeg, &w->offset_rad);
  angle("bias_deg", false, kMaxAngleDeg, &w->bias_rad);
}

}  // namespace

GaitLibrary GaitLibrary::from_yaml_string(const std::string& text, const std::string& source) {
  const YAML::Node root = load_config_yaml(text, source);
  if (!root["gaits"] || !root["gaits"].IsMap())
    throw ConfigError(source + ": expected a mapping 'gaits:' of gait names to definitions");
  if (root["gaits"].size() > kMaxGaits)
    throw ConfigError(source + ": gaits: at most " + std::to_string(kMaxGaits) + " gaits, got " +
                      std::to_string(root["gaits"].size()));
  std::vector<std::string> errors;
  GaitLibrary lib;
  for (auto it = root["gaits"].begin(); it != root["gaits"].end(); ++it) {
    GaitSpec g;
    if (!it->first.IsScalar()) {
      errors.push_back("gaits: a gait name must be a string, got '" + ConfigReader::dump(it->first) + "'");
      continue;
    }
    g.name = it->first.Scalar();
    const std::string where = "gaits." + g.name;
    const YAML::Node n = it->second;
    if (!n.IsMap()) {
      errors.push_back(where + ": expected a mapping");
      continue;
    }
    ConfigReader(&errors).scalar(n["description"], where + ".description", &g.description);
    ConfigReader r(&errors);
    if (r.scalar(r.child(n, "frequency_hz", where + ".frequency_hz"), where + ".frequency_hz", &g.frequency_hz) &&
        (g.frequency_hz < 0.0 || g.frequency_hz > kMaxFrequencyHz))
      errors.push_back(where + ".frequency_hz: must be in 0.." + fmt(kMaxFrequencyHz) + " Hz, got " +
                       fmt(g.frequency_hz));
    read_wave(n, "pitch", where, &g.pitch, &errors);
    read_wave(n, "yaw", where, &g.yaw, &errors);
    r.scalar(r.child(n, "steerable", where + ".steerable", false), where + ".steerable", &g.steerable);
    if (g.steerable) g.steering = SteeringLaw::kAmplitudeModulation;
    std::string law;
    if (r.scalar(r.child(n, "steering", where + ".steering", false), where + ".steering", &law)) {
      if (law == "amplitude_modulation") {
        g.steering = SteeringLaw::kAmplitudeModulation;
      } else if (law == "curvature" && !g.steerable) {
        g.steering = SteeringLaw::kCurvature;
      } else if (law == "none" && !g.steerable) {
        g.steering = SteeringLaw::kNone;
      } else if (law == "curvature" || law == "none") {
        errors.push_back(where + ".steering: '" + law + "' contradicts steerable: true (amplitude_modulation)");
      } else {
        errors.push_back(where + ".steering: '" + law + "', expected amplitude_modulation, curvature or none");
      }
    }
    g.steerable = g.steering == SteeringLaw::kAmplitudeModulation;
    lib.gaits_[g.name] = g;
  }
  if (lib.gaits_.empty()) errors.push_back("gaits: no gait defined");
  throw_if_errors(errors, source, "gait library");
  return lib;
}

const char* to_string(SteeringLaw law) noexcept {
  switch (law) {
    case SteeringLaw::kNone: return "none";
    case SteeringLaw::kAmplitudeModulation: return "amplitude_modulation";
    case SteeringLaw::kCurvature: return "curvature";
  }
  return "?";
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
