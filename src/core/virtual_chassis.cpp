#include "snake_autonomy/core/virtual_chassis.hpp"

#include <Eigen/Eigenvalues>
#include <limits>

namespace snake_autonomy::core {
namespace {

constexpr double kDegenerate = 1e-9;

// R = [x̂ ẑ×x̂ ẑ] from a direction; false when it has no horizontal part.
bool horizontal_frame(const Eigen::Vector3d& direction, Eigen::Matrix3d& R) noexcept {
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d h = direction - direction.dot(z) * z;
  const double norm = h.norm();
  if (!(norm > kDegenerate)) return false;
  const Eigen::Vector3d x = h / norm;
  R.col(0) = x;
  R.col(1) = z.cross(x);
  R.col(2) = z;
  return true;
}

}  // namespace

bool virtual_chassis_mean_axis(const std::vector<Eigen::Matrix3d>& rotations, Eigen::Matrix3d& R) noexcept {
  if (rotations.empty()) return false;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& Ri : rotations) mean += Ri.col(0);
  mean /= static_cast<double>(rotations.size());
  return horizontal_frame(mean, R);
}

bool virtual_chassis_svd(const std::vector<Eigen::Vector3d>& positions, Eigen::Matrix3d& R) noexcept {
  if (positions.size() < 2) return false;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : positions) centroid += p;
  centroid /= static_cast<double>(positions.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& p : positions) scatter.noalias() += (p - centroid) * (p - centroid).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);  // fixed size: no allocation
  if (eig.info() != Eigen::Success) return false;
  Eigen::Vector3d axis = eig.eigenvectors().col(2);  // largest eigenvalue last
  // Sign: from the tail towards the head (positions are in chain order, head first).
  if (axis.dot(positions.front() - positions.back()) < 0.0) axis = -axis;
  return horizontal_frame(axis, R);
}

Eigen::Vector3d centre_of_mass(const std::vector<Eigen::Vector3d>& positions, const std::vector<double>& masses_kg,
                               double inverse_total_mass) noexcept {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  const std::size_t n = std::min(positions.size(), masses_kg.size());
  for (std::size_t i = 0; i < n; ++i) sum += masses_kg[i] * positions[i];
  return sum * inverse_total_mass;
}

Eigen::Vector3d bounding_box_span(const std::vector<Eigen::Vector3d>& positions, const Eigen::Vector3d& com,
                                  const Eigen::Matrix3d& R, double padding_m) noexcept {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const auto& p : positions) {
    const Eigen::Vector3d local = R.transpose() * (p - com);
    lo = lo.cwiseMin(local);
    hi = hi.cwiseMax(local);
  }
  if (positions.empty()) return Eigen::Vector3d::Constant(padding_m);
  return (hi - lo) + Eigen::Vector3d::Constant(padding_m);
}

}  // namespace snake_autonomy::core
