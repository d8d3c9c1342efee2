#include "snake_autonomy/core/gait_command.hpp"

#include <cmath>
#include <sstream>

namespace snake_autonomy::core {
namespace {

// Checks one explicit vector: empty or n finite values; `limit` > 0 also bounds |value|.
void check_vector(const char* field, const std::vector<double>& v, int n, double limit, const char* limit_what,
                  std::vector<std::string>& errors) {
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
    } else if (limit > 0.0 && std::abs(v[i]) > limit) {
      s << field << "[" << i << "] (joint_" << i + 1 << "): " << v[i] << " exceeds " << limit_what;
    } else {
      continue;
    }
    errors.push_back(s.str());
  }
}

void assign(const std::vector<double>& v, Eigen::VectorXd& out) {
  if (!v.empty()) out = Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

}  // namespace

GaitCommandResolver::GaitCommandResolver(const RobotModel& model, const GaitLibrary& gaits, double max_frequency_hz,
                                         const std::string& initial_gait)
    : model_(model), gaits_(gaits), steering_(model), max_omega_rad_s_(2.0 * M_PI * max_frequency_hz) {
  if (!gaits_.contains(initial_gait)) throw ConfigError("initial gait '" + initial_gait + "' is not in the gait library");
  name_ = base_name_ = initial_gait;
  nominal_ = gaits_.parameters(initial_gait, model_);
}

std::string GaitCommandResolver::resolve(const GaitCommandRequest& command, GaitParameters& out) {
  const int n = model_.num_joints;
  std::vector<std::string> errors;
  const bool named = !command.gait.empty();
  if (named && !gaits_.contains(command.gait)) {
    std::string known;
    for (const auto& g : gaits_.names()) known += (known.empty() ? "" : ", ") + g;
    errors.push_back("gait: unknown gait '" + command.gait + "' (known: " + known + ")");
  }
  check_vector("amplitude", command.amplitude, n, 0.0, "", errors);
  std::ostringstream omega_limit;
  omega_limit << max_omega_rad_s_ << " rad/s (max_frequency_hz " << max_omega_rad_s_ / (2.0 * M_PI) << ")";
  check_vector("omega", command.omega, n, max_omega_rad_s_, omega_limit.str().c_str(), errors);
  check_vector("phase", command.phase, n, 0.0, "", errors);
  check_vector("bias", command.bias, n, 0.0, "", errors);
  if (command.steer) {
    if (!std::isfinite(command.delta_rad)) {
      std::ostringstream s;
      s << "delta: " << command.delta_rad << " is not a finite number";
      errors.push_back(s.str());
    }
    const std::string& base = named ? command.gait : base_name_;
    if (gaits_.contains(base) && !gaits_.spec(base).steerable)
      errors.push_back("steer: gait '" + base + "' is not steerable (only gaits marked steerable in gaits.yaml are)");
  }
  if (!errors.empty()) {
    std::string what;
    for (const auto& e : errors) what += (what.empty() ? "" : "\n") + e;
    return what;
  }

  GaitParameters nominal = named ? gaits_.parameters(command.gait, model_) : nominal_;
  assign(command.amplitude, nominal.amplitude);
  assign(command.omega, nominal.omega);
  assign(command.phase, nominal.phase);
  assign(command.bias, nominal.bias);
  GaitParameters result = nominal;
  if (command.steer && !steering_.modify_amplitudes(nominal.amplitude, command.delta_rad, result.amplitude))
    return "steer: steering refused the amplitudes";  // unreachable after the checks above

  const std::string base = named ? command.gait : base_name_;
  const bool custom = !command.amplitude.empty() || !command.omega.empty() || !command.phase.empty() ||
                      !command.bias.empty() || (!named && name_ != base_name_);
  base_name_ = base;
  name_ = custom ? base + "+custom" : base;
  nominal_ = std::move(nominal);
  out = std::move(result);
  return {};
}

}  // namespace snake_autonomy::core
