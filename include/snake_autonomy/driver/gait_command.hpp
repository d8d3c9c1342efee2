// Gait commands: what a caller asks for (a gait name and/or explicit vectors, steering δ),
// resolved against the gait library and the robot into CPG targets, or refused whole.
//
// Rules (msg/GaitCommand.msg): a named gait replaces the current gait; explicit vectors replace
// the named (or current) gait's; every vector is empty (unchanged) or has one value per joint.
// Refused, with every reason (field, index, joint_N and value) and nothing changed: an unknown gait,
// a vector of the wrong length, a NaN or infinite value, and values outside their physical range:
//   amplitude  |a| > the joint's range (upper − lower); within it, the steering clamp and the CPG's
//              amplitude_limit clamp it (amplitude + |bias| beyond the limits is cut by the goal clamp)
//   omega      |ω| / 2π > max_frequency_hz
//   phase      |φ| > 1000 rad; accepted phases are wrapped to (−π, π] (only differences matter)
//   bias       outside the joint limits [lower, upper]
//   delta      non-finite or |δ| > π (within, Steering clips it to the robot's delta_limit)
//   kappa      non-finite or |kappa| > 100 1/m (within, the biases are clamped to the joint limits)
// and a steering value the gait does not accept (steer on a gait without amplitude_modulation,
// curve on a gait without curvature, both at once). The resolver remembers the nominal (unsteered) parameters of the
// last accepted command: steering applies to one command at a time, it does not accumulate.
//
// Not real-time: resolve() allocates. It runs in the caller's thread (a ROS callback), never in the
// loop; the driver hands the result to the loop without blocking it (DriverController).
#pragma once

#include <string>
#include <vector>

#include "snake_autonomy/core/cpg.hpp"
#include "snake_autonomy/core/curvature_steering.hpp"
#include "snake_autonomy/core/gait_library.hpp"
#include "snake_autonomy/core/robot_model.hpp"
#include "snake_autonomy/core/steering.hpp"

namespace snake_autonomy::driver {

struct GaitCommandRequest {
  std::string gait;                // empty: keep the current gait's parameters
  std::vector<double> amplitude;   // rad, empty or one per joint
  std::vector<double> omega;       // rad/s
  std::vector<double> phase;       // rad, absolute per joint
  std::vector<double> bias;        // rad
  bool steer = false;              // amplitude-modulation steering with delta_rad
  double delta_rad = 0.0;
  bool curve = false;              // curvature steering (gaits with steering: curvature) with kappa_per_m
  double kappa_per_m = 0.0;        // body curvature, 1/m
};

class GaitCommandResolver {
 public:
  // max_frequency_hz: |ω| / 2π above it is refused. The current gait starts as `initial_gait`
  // (which must exist in the library: ConfigError otherwise).
  GaitCommandResolver(const core::RobotModel& model, const core::GaitLibrary& gaits, double max_frequency_hz,
                      const std::string& initial_gait = "hold");

  // Empty when accepted: `out` holds the CPG targets (steering applied) and the resolver the new
  // nominal gait. Otherwise every reason, one per line, and nothing is changed (`out` included).
  std::string resolve(const GaitCommandRequest& command, core::GaitParameters& out);
  // The name of the current gait; explicit vectors on top of a gait are "NAME+custom".
  const std::string& current_gait() const { return name_; }
  const core::GaitParameters& nominal() const { return nominal_; }

 private:
  core::RobotModel model_;
  core::GaitLibrary gaits_;
  core::Steering steering_;
  core::CurvatureSteering curvature_;
  double max_omega_rad_s_;
  std::string name_;
  std::string base_name_;  // the library gait under the custom vectors
  core::GaitParameters nominal_;
};

}  // namespace snake_autonomy::driver
