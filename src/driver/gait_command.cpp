#include "snake_autonomy/driver/gait_command.hpp"

#include <cmath>
#include <sstream>

namespace snake_autonomy::driver {
namespace {

// Bound of |phase| in a command (rad): accepted phases are wrapped to (−π, π]; beyond this a value
// is not a phase anyone meant (and its difference to a neighbour may overflow).
constexpr double kMaxPhaseRad = 1000.0;
// Bound of |δ| (rad): beyond a half turn a steering value means nothing; within it the steering
// clips δ to the robot's delta_limit.
constexpr double kMaxDeltaRad = M_PI;
constexpr double kMaxKappaPerM = 100.0;

// Checks one explicit vector: empty or n finite values within [lower_i, upper_i] (`what` names the
// range in the message).
void check_vector(const char* field, const std::vector<double>& v, int n, const std::vector<double>& lower,
                  const std::vector<double>& upper, const std::string& what, std::vector<std::string>& errors) {
  if (v.empty()) return;
  if (static_cast<int>(v.size()) != n) {
    std::ostringstream s;
    s << field << ": " << v.size() << " values, the robot has " << n << " joints (give " << n << " or none)";
    errors.push_back(s.str());
    return;
  }
  for (int i = 0; i < n; ++i) {
    std::ostringstream s;
    if (!std::isfinite(v[i])) {
      s << field << "[" << i << "] (joint_" << i + 1 << "): " << v[i] << " is not a finite number";
    } else if (v[i] < lower[i] || v[i] > upper[i]) {
      s << field << "[" << i << "] (joint_" << i + 1 << "): " << v[i] << " is outside [" << lower[i] << ", " << upper[i]
        << "] " << what;
    } else {
      continue;
    }
    errors.push_back(s.str());
  }
}

// (−π, π]
double wrap_pi(double a) {
  const double w = std::remainder(a, 2.0 * M_PI);
  return w <= -M_PI ? w + 2.0 * M_PI : w;
}

void assign(const std::vector<double>& v, Eigen::VectorXd& out) {
  if (!v.empty()) out = Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

}  // namespace

GaitCommandResolver::GaitCommandResolver(const core::RobotModel& model, const core::GaitLibrary& gaits,
                                         double max_frequency_hz, const std::string& initial_gait)
    : model_(model),
      gaits_(gaits),
      steering_(model),
      curvature_(model),
      max_omega_rad_s_(2.0 * M_PI * max_frequency_hz) {
  if (!gaits_.contains(initial_gait))
    throw core::ConfigError("initial gait '" + initial_gait + "' is not in the gait library");
  name_ = base_name_ = initial_gait;
  nominal_ = gaits_.parameters(initial_gait, model_);
}

std::string GaitCommandResolver::resolve(const GaitCommandRequest& command, core::GaitParameters& out) {
  const int n = model_.num_joints;
  std::vector<std::string> errors;
  const bool named = !command.gait.empty();
  if (named && !gaits_.contains(command.gait)) {
    std::string known;
    for (const auto& g : gaits_.names()) known += (known.empty() ? "" : ", ") + g;
    errors.push_back("gait: unknown gait '" + command.gait + "' (known: " + known + ")");
  }
  const std::vector<double> lo_phase(n, -kMaxPhaseRad), hi_phase(n, kMaxPhaseRad);
  const std::vector<double> lo_omega(n, -max_omega_rad_s_), hi_omega(n, max_omega_rad_s_);
  std::vector<double> lo_amp(n), hi_amp(n);
  for (int i = 0; i < n; ++i) {
    hi_amp[i] = model_.joint_upper_rad[i] - model_.joint_lower_rad[i];
    lo_amp[i] = -hi_amp[i];
  }
  std::ostringstream omega_limit;
  omega_limit << "rad/s (max_frequency_hz " << max_omega_rad_s_ / (2.0 * M_PI) << ")";
  check_vector("amplitude", command.amplitude, n, lo_amp, hi_amp, "rad (|amplitude| at most the joint's range)",
               errors);
  check_vector("omega", command.omega, n, lo_omega, hi_omega, omega_limit.str(), errors);
  check_vector("phase", command.phase, n, lo_phase, hi_phase, "rad (phases are wrapped to (-pi, pi])", errors);
  check_vector("bias", command.bias, n, model_.joint_lower_rad, model_.joint_upper_rad, "rad (the joint limits)",
               errors);
  if (command.steer) {
    if (!std::isfinite(command.delta_rad) || std::abs(command.delta_rad) > kMaxDeltaRad) {
      std::ostringstream s;
      s << "delta: " << command.delta_rad
        << (std::isfinite(command.delta_rad) ? " is outside [-pi, pi] rad" : " is not a finite number");
      errors.push_back(s.str());
    }
    const std::string& base = named ? command.gait : base_name_;
    if (gaits_.contains(base) && !gaits_.spec(base).steerable)
      errors.push_back("steer: gait '" + base + "' is not steerable (steering: " +
                       to_string(gaits_.spec(base).steering) + "; steer needs amplitude_modulation)");
  }
  if (command.curve) {
    if (!std::isfinite(command.kappa_per_m) || std::abs(command.kappa_per_m) > kMaxKappaPerM) {
      std::ostringstream s;
      s << "kappa: " << command.kappa_per_m
        << (std::isfinite(command.kappa_per_m) ? " is outside [-100, 100] 1/m" : " is not a finite number");
      errors.push_back(s.str());
    }
    const std::string& base = named ? command.gait : base_name_;
    if (gaits_.contains(base) && gaits_.spec(base).steering != core::SteeringLaw::kCurvature)
      errors.push_back("kappa: gait '" + base +
                       "' does not steer by curvature (steering: " + to_string(gaits_.spec(base).steering) + ")");
  }
  if (!errors.empty()) {
    std::string what;
    for (const auto& e : errors) what += (what.empty() ? "" : "\n") + e;
    return what;
  }

  core::GaitParameters nominal = named ? gaits_.parameters(command.gait, model_) : nominal_;
  assign(command.amplitude, nominal.amplitude);
  assign(command.omega, nominal.omega);
  assign(command.phase, nominal.phase);
  if (!command.phase.empty()) nominal.phase = nominal.phase.unaryExpr([](double a) { return wrap_pi(a); });
  assign(command.bias, nominal.bias);
  core::GaitParameters result = nominal;
  if (command.steer && !steering_.modify_amplitudes(nominal.amplitude, command.delta_rad, result.amplitude))
    return "steer: steering refused the amplitudes";  // unreachable after the checks above
  if (command.curve && !curvature_.modify_biases(nominal.bias, command.kappa_per_m, result.bias))
    return "kappa: curvature steering refused the biases";  // unreachable after the checks above

  const std::string base = named ? command.gait : base_name_;
  const bool custom = !command.amplitude.empty() || !command.omega.empty() || !command.phase.empty() ||
                      !command.bias.empty() || (!named && name_ != base_name_);
  base_name_ = base;
  name_ = custom ? base + "+custom" : base;
  nominal_ = std::move(nominal);
  out = std::move(result);
  return {};
}

}  // namespace snake_autonomy::driver
