// Central pattern generator: one Hopf-style oscillator per joint, phases coupled along the chain.
//
// Thesis eq. 3.21-3.25, with A as the negative graph Laplacian of the chain (the printed matrix is
// garbled) and the amplitude dynamics critically damped as the text intends (as printed, eq. 3.23
// has damping ratio 0.5 and overshoots about 16 %):
//   dθ/dt = μ A θ − μ B Δφ + ω          A = −(graph Laplacian of the chain), B[i][i] = 1, B[i+1][i] = −1
//   d²r/dt² = γ² (a_des − r) − 2 γ dr/dt  critically damped: a step in a_des never overshoots
//   q = clamp(r ⊙ sin θ + b, joint limits)
// With Δφ_i = φ_{i+1} − φ_i, θ_{i+1} − θ_i converges to Δφ_i from any initial phases.
// The bias b and the lags Δφ follow their targets through the same critically damped filter as r,
// so no parameter change ever makes q jump: a lag change fed straight into the linear coupling
// would drive the phases at μ·Δlag (about 30 rad/s for a half-turn at μ = 10). A new lag target is
// unwrapped to the nearest equivalent of the current lag (same sin θ, no needless full turns).
// When the oscillators are at rest (r and dr/dt about zero) q does not depend on θ, and the lags
// take their new targets at once.
// A stop (every amplitude target zero) keeps the current lag targets until the oscillators are at
// rest: the wave decays in its own shape, and a gait resumed during the decay starts from its lags
// instead of from nearly equal phases (a rolling gait for sidewinding, see Cpg::apply).
//
// Both linear systems are integrated exactly (eigen-decomposition of the symmetric A, closed-form
// critically damped response), the filtered lags entering the phase step at their mid-step value,
// so a step is stable and accurate at 10 ms, 1 ms or any other dt.
// Storage is sized in the constructor; step() and apply() never allocate and never throw.
#pragma once

#include <Eigen/Dense>
#include <string>

#include "snake_autonomy/core/robot_model.hpp"

namespace snake_autonomy::core {

struct CpgTestAccess;  // tests only (test/cpp): corrupts the state to prove the driver's fault path

// Per-joint gait targets: radians and rad/s, one value per joint.
struct GaitParameters {
  Eigen::VectorXd amplitude;  // a_des
  Eigen::VectorXd omega;      // ω
  Eigen::VectorXd phase;      // φ (absolute); the CPG uses the lags Δφ_i = φ_{i+1} − φ_i
  Eigen::VectorXd bias;       // b

  static GaitParameters zeros(int num_joints);
};

class Cpg {
 public:
  // mu <= 0 or gamma <= 0: taken from the robot model's cpg section.
  explicit Cpg(const RobotModel& model, double mu = 0.0, double gamma = 0.0);

  int num_joints() const { return n_; }
  double mu() const { return mu_; }
  double gamma() const { return gamma_; }

  // Empty when p can be applied; otherwise every problem, naming the field, joint and value
  // (wrong length, NaN or infinite). Amplitudes beyond the limit are not an error: apply() clamps.
  std::string validate(const GaitParameters& p) const;
  // Sets new targets, all at once. Amplitudes are clamped to ±amplitude_limit. Returns false and
  // changes nothing when validate(p) is not empty.
  bool apply(const GaitParameters& p) noexcept;
  // apply() or throw std::invalid_argument with validate()'s message.
  void set_parameters(const GaitParameters& p);
  const GaitParameters& targets() const { return targets_; }

  // Sets the oscillator state directly (tests, restarts). Rates are zeroed. Returns false and
  // changes nothing when a vector has the wrong length or a non-finite value (the loop's path).
  bool restart(const Eigen::VectorXd& phases, const Eigen::VectorXd& amplitudes,
               const Eigen::VectorXd& biases) noexcept;
  // restart() or throw std::invalid_argument naming the problem (callers outside the loop).
  void reset(const Eigen::VectorXd& phases, const Eigen::VectorXd& amplitudes, const Eigen::VectorXd& biases);
  // True when every state variable and the output are finite numbers. Every accepted input keeps
  // them finite; the driver checks this each cycle and faults if it ever fails.
  bool state_finite() const noexcept;

  // Advances by dt_s (> 0) and returns the joint angles, clamped to the joint limits.
  const Eigen::VectorXd& step(double dt_s) noexcept;

  const Eigen::VectorXd& phases() const { return theta_; }
  const Eigen::VectorXd& amplitudes() const { return r_; }
  const Eigen::VectorXd& amplitude_rates() const { return r_dot_; }
  const Eigen::VectorXd& biases() const { return b_; }
  const Eigen::VectorXd& output() const { return q_; }
  // Filtered lags Δφ (n − 1) currently driving the coupling.
  const Eigen::VectorXd& lags() const { return lag_; }
  // Raw r ⊙ sin θ + b before the joint-limit clamp (to see what the limits cut).
  const Eigen::VectorXd& unclamped_output() const { return q_raw_; }

 private:
  friend struct CpgTestAccess;
  void update_drive(const Eigen::VectorXd& lags) noexcept;
  void update_step_factors(double dt_s) noexcept;

  int n_;
  double mu_, gamma_, amplitude_limit_;
  Eigen::VectorXd lower_, upper_;
  Eigen::MatrixXd V_;        // eigenvectors of A (A = V Λ Vᵀ)
  Eigen::VectorXd lambda_;   // eigenvalues of A
  GaitParameters targets_;
  Eigen::VectorXd drive_modal_;  // Vᵀ (−μ B Δφ + ω) for the lags of the current step
  Eigen::VectorXd lag_target_, lag_, lag_dot_, lag_mid_;  // n − 1 each
  double cached_dt_ = -1.0;
  Eigen::VectorXd exp_factor_, int_factor_;  // per mode: e^{μλdt}, (e^{μλdt} − 1)/(μλ)
  Eigen::VectorXd theta_, r_, r_dot_, b_, b_dot_, q_, q_raw_, z_;
};

}  // namespace snake_autonomy::core
