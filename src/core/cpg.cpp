#include "snake_autonomy/core/cpg.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace snake_autonomy::core {
namespace {

// Amplitude (rad) and amplitude rate (rad/s) below which the oscillators count as at rest.
constexpr double kRestAmplitude = 1e-3;

// Exact step of x'' = γ² (target − x) − 2γ x' over dt (critically damped, no overshoot).
inline void critically_damped_step(double target, double gamma, double decay, double dt, double& x,
                                   double& x_dot) noexcept {
  const double e = x - target;
  const double c = x_dot + gamma * e;
  x = target + (e + c * dt) * decay;
  x_dot = (x_dot - gamma * c * dt) * decay;
}

}  // namespace

GaitParameters GaitParameters::zeros(int num_joints) {
  GaitParameters p;
  p.amplitude = Eigen::VectorXd::Zero(num_joints);
  p.omega = Eigen::VectorXd::Zero(num_joints);
  p.phase = Eigen::VectorXd::Zero(num_joints);
  p.bias = Eigen::VectorXd::Zero(num_joints);
  return p;
}

Cpg::Cpg(const RobotModel& model, double mu, double gamma)
    : n_(model.num_joints),
      mu_(mu > 0.0 ? mu : model.cpg.mu),
      gamma_(gamma > 0.0 ? gamma : model.cpg.gamma),
      amplitude_limit_(model.cpg.amplitude_limit_rad) {
  model.validate_or_throw();
  if (!std::isfinite(mu_) || !std::isfinite(gamma_))
    throw std::invalid_argument("Cpg: mu and gamma must be finite, got " + std::to_string(mu_) + " and " +
                                std::to_string(gamma_));
  lower_ = Eigen::Map<const Eigen::VectorXd>(model.joint_lower_rad.data(), n_);
  upper_ = Eigen::Map<const Eigen::VectorXd>(model.joint_upper_rad.data(), n_);

  // A: negative graph Laplacian of the joint chain.
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n_, n_);
  for (int i = 0; i + 1 < n_; ++i) {
    A(i, i) -= 1.0;
    A(i + 1, i + 1) -= 1.0;
    A(i, i + 1) += 1.0;
    A(i + 1, i) += 1.0;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(A);
  V_ = eig.eigenvectors();
  lambda_ = eig.eigenvalues();
  // The zero eigenvalue (uniform phase shift) must be exactly zero for the integrator's branch.
  for (int k = 0; k < n_; ++k)
    if (std::abs(lambda_(k)) < 1e-12) lambda_(k) = 0.0;

  targets_ = GaitParameters::zeros(n_);
  drive_modal_ = Eigen::VectorXd::Zero(n_);
  lag_target_ = lag_ = lag_dot_ = lag_mid_ = Eigen::VectorXd::Zero(n_ - 1);
  exp_factor_ = Eigen::VectorXd::Zero(n_);
  int_factor_ = Eigen::VectorXd::Zero(n_);
  theta_ = r_ = r_dot_ = b_ = b_dot_ = q_ = q_raw_ = z_ = Eigen::VectorXd::Zero(n_);
  update_drive(lag_);
}

std::string Cpg::validate(const GaitParameters& p) const {
  std::ostringstream err;
  auto check = [&](const char* field, const Eigen::VectorXd& v) {
    if (v.size() != n_) {
      err << field << ": expected " << n_ << " values, got " << v.size() << "\n";
      return;
    }
    for (int i = 0; i < n_; ++i)
      if (!std::isfinite(v(i))) err << field << "[" << i << "]: must be finite, got " << v(i) << "\n";
  };
  check("amplitude", p.amplitude);
  check("omega", p.omega);
  check("phase", p.phase);
  check("bias", p.bias);
  std::string s = err.str();
  if (!s.empty()) s.pop_back();
  return s;
}

bool Cpg::apply(const GaitParameters& p) noexcept {
  // validate() builds a string: only on the failure path does it matter, and sizes are checked
  // first without allocating.
  if (p.amplitude.size() != n_ || p.omega.size() != n_ || p.phase.size() != n_ || p.bias.size() != n_) return false;
  if (!p.amplitude.allFinite() || !p.omega.allFinite() || !p.phase.allFinite() || !p.bias.allFinite()) return false;
  targets_.amplitude = p.amplitude.cwiseMax(-amplitude_limit_).cwiseMin(amplitude_limit_);
  targets_.omega = p.omega;
  targets_.phase = p.phase;
  targets_.bias = p.bias;
  const bool at_rest = r_.cwiseAbs().maxCoeff() < kRestAmplitude && r_dot_.cwiseAbs().maxCoeff() < kRestAmplitude;
  // A stop (every amplitude target zero) while the waves still move keeps the lags: the wave decays
  // in its own shape. The lags only shape the body where there is amplitude, and gliding them
  // towards the stop's (the hold gait's 0) while the amplitudes decay passes through the rolling
  // gait described below; a gait resumed before the body is at rest then starts from those lags.
  // On the simulated COBRA, tracking lost 1 s in every 2.5 s (the mission's hold, then its gait)
  // rolled the robot over in seeds 0-4 of the star mission with the lags gliding, in none without.
  const bool stopping = targets_.amplitude.cwiseAbs().maxCoeff() < kRestAmplitude;
  if (!stopping || at_rest) {
    for (int i = 0; i + 1 < n_; ++i) {
      const double wanted = p.phase(i + 1) - p.phase(i);
      const double d = wanted - lag_(i);
      lag_target_(i) = lag_(i) + std::atan2(std::sin(d), std::cos(d));
    }
  }
  // At rest (no amplitude, none building up) q does not depend on θ: the lags may jump, and so may
  // the phases (θ_{i+1} = θ_i + lag_i), so a gait starts with its travelling wave instead of gliding
  // in. Only jumping the lags is not enough: the phase coupling takes seconds to spread phases that
  // start equal (slowest mode 1 / (μ λ_min), about 1.2 s for 11 joints and μ = 10), and meanwhile the
  // joints swing nearly in phase with pitch and yaw 90° apart, which is a rolling gait: started that
  // way from a straight body, sidewinding rolled the simulated COBRA onto its back in every seed.
  if (at_rest) {
    lag_ = lag_target_;
    lag_dot_.setZero();
    for (int i = 0; i + 1 < n_; ++i) theta_(i + 1) = theta_(i) + lag_(i);
  }
  return true;
}

void Cpg::set_parameters(const GaitParameters& p) {
  const std::string err = validate(p);
  if (!err.empty()) throw std::invalid_argument(err);
  apply(p);
}

bool Cpg::restart(const Eigen::VectorXd& phases, const Eigen::VectorXd& amplitudes,
                  const Eigen::VectorXd& biases) noexcept {
  if (phases.size() != n_ || amplitudes.size() != n_ || biases.size() != n_) return false;
  if (!phases.allFinite() || !amplitudes.allFinite() || !biases.allFinite()) return false;
  theta_ = phases;
  r_ = amplitudes;
  b_ = biases;
  r_dot_.setZero();
  b_dot_.setZero();
  // The lags jump to their targets: a reset is a restart, not a transition.
  lag_ = lag_target_;
  lag_dot_.setZero();
  q_raw_ = r_.cwiseProduct(theta_.array().sin().matrix()) + b_;
  q_ = q_raw_.cwiseMax(lower_).cwiseMin(upper_);
  return true;
}

void Cpg::reset(const Eigen::VectorXd& phases, const Eigen::VectorXd& amplitudes, const Eigen::VectorXd& biases) {
  if (phases.size() != n_ || amplitudes.size() != n_ || biases.size() != n_)
    throw std::invalid_argument("Cpg::reset: phases, amplitudes and biases need " + std::to_string(n_) +
                                " values each, got " + std::to_string(phases.size()) + ", " +
                                std::to_string(amplitudes.size()) + ", " + std::to_string(biases.size()));
  if (!restart(phases, amplitudes, biases)) throw std::invalid_argument("Cpg::reset: values must be finite");
}

bool Cpg::state_finite() const noexcept {
  return theta_.allFinite() && r_.allFinite() && r_dot_.allFinite() && b_.allFinite() && b_dot_.allFinite() &&
         lag_.allFinite() && lag_dot_.allFinite() && q_.allFinite();
}

void Cpg::update_drive(const Eigen::VectorXd& lags) noexcept {
  // c = −μ B Δφ + ω, with (B Δφ)_i = Δφ_i − Δφ_{i−1} (Δφ_{−1} = Δφ_{n−1} = 0).
  for (int i = 0; i < n_; ++i) {
    const double lag_out = (i + 1 < n_) ? lags(i) : 0.0;
    const double lag_in = (i > 0) ? lags(i - 1) : 0.0;
    z_(i) = -mu_ * (lag_out - lag_in) + targets_.omega(i);
  }
  drive_modal_.noalias() = V_.transpose() * z_;
}

void Cpg::update_step_factors(double dt_s) noexcept {
  cached_dt_ = dt_s;
  for (int k = 0; k < n_; ++k) {
    const double rate = mu_ * lambda_(k);
    if (rate == 0.0) {
      exp_factor_(k) = 1.0;
      int_factor_(k) = dt_s;
    } else {
      exp_factor_(k) = std::exp(rate * dt_s);
      int_factor_(k) = std::expm1(rate * dt_s) / rate;
    }
  }
}

const Eigen::VectorXd& Cpg::step(double dt_s) noexcept {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) return q_;
  if (dt_s != cached_dt_) update_step_factors(dt_s);
  const double decay = std::exp(-gamma_ * dt_s);

  // Lags: critically damped towards their targets; the phase step uses their mid-step value.
  lag_mid_ = lag_;
  for (int i = 0; i + 1 < n_; ++i) critically_damped_step(lag_target_(i), gamma_, decay, dt_s, lag_(i), lag_dot_(i));
  lag_mid_ = 0.5 * (lag_mid_ + lag_);
  update_drive(lag_mid_);

  // Phases: exact solution of the linear system in the eigenbasis of A.
  z_.noalias() = V_.transpose() * theta_;
  z_ = exp_factor_.cwiseProduct(z_) + int_factor_.cwiseProduct(drive_modal_);
  theta_.noalias() = V_ * z_;
  // Keep phases bounded: a common shift by whole turns changes neither sin θ nor the lags.
  const double turns = std::floor(theta_(0) / (2.0 * M_PI));
  if (turns != 0.0) theta_.array() -= turns * 2.0 * M_PI;

  // Amplitudes and biases: exact critically damped response.
  for (int i = 0; i < n_; ++i) {
    critically_damped_step(targets_.amplitude(i), gamma_, decay, dt_s, r_(i), r_dot_(i));
    critically_damped_step(targets_.bias(i), gamma_, decay, dt_s, b_(i), b_dot_(i));
    q_raw_(i) = r_(i) * std::sin(theta_(i)) + b_(i);
    q_(i) = std::min(std::max(q_raw_(i), lower_(i)), upper_(i));
  }
  return q_;
}

}  // namespace snake_autonomy::core
