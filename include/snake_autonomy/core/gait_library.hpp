// Gait library: named gaits as data (config/gaits.yaml), expanded to per-joint CPG targets for a
// given robot. Degrees and hertz in the file, radians and rad/s inside. Nothing about gaits is
// hard-coded in C++.
//
// A gait gives, for each axis group (pitch joints, yaw joints), a travelling wave:
//   a_i = amplitude,   φ_i = offset + (i − 1) · lag,   b_i = bias,   ω_i = 2π · frequency
// where i is the joint's 1-based index along the body (head to tail), whatever its axis.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "snake_autonomy/core/cpg.hpp"
#include "snake_autonomy/core/robot_model.hpp"

namespace snake_autonomy::core {

struct WaveSpec {
  double amplitude_rad = 0.0;
  double lag_rad = 0.0;     // phase step from one joint index to the next
  double offset_rad = 0.0;  // phase of joint 1 (before the index lag)
  double bias_rad = 0.0;
};

// How a gait may be steered (gaits.yaml `steering:`; the old `steerable: true` reads as
// amplitude_modulation). A command with a steering value the gait does not accept is refused.
enum class SteeringLaw { kNone, kAmplitudeModulation, kCurvature };
const char* to_string(SteeringLaw law) noexcept;  // "none", "amplitude_modulation", "curvature"

struct GaitSpec {
  std::string name;
  std::string description;
  double frequency_hz = 0.0;
  WaveSpec pitch;
  WaveSpec yaw;
  SteeringLaw steering = SteeringLaw::kNone;
  bool steerable = false;  // steering == kAmplitudeModulation (eq. 3.26 applies to this gait)
};

class GaitLibrary {
 public:
  // Parses and validates; throws ConfigError naming the file, gait, key and value of every problem.
  static GaitLibrary from_yaml_file(const std::string& path);
  static GaitLibrary from_yaml_string(const std::string& text, const std::string& source = "<string>");

  std::vector<std::string> names() const;
  bool contains(const std::string& name) const { return gaits_.count(name) != 0; }
  // Throws std::out_of_range naming the gait and the known names.
  const GaitSpec& spec(const std::string& name) const;
  // Per-joint CPG targets of a gait for this robot.
  GaitParameters parameters(const std::string& name, const RobotModel& model) const;

 private:
  std::map<std::string, GaitSpec> gaits_;
};

}  // namespace snake_autonomy::core
