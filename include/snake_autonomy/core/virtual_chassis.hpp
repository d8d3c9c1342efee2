// Reduced-order description of the whole body from its frames (thesis 3.4.2-3.4.3):
// virtual chassis orientation, centre of mass, bounding box. Pure functions on fixed-size Eigen
// types: no allocation, no throw.
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "snake_autonomy/core/robot_model.hpp"

namespace snake_autonomy::core {

// Mean-axis construction (eq. 3.11-3.14): mean of the frames' x axes, projected on the horizontal
// plane; z is the world vertical. Returns false (R untouched) when the mean axis is vertical.
bool virtual_chassis_mean_axis(const std::vector<Eigen::Matrix3d>& rotations, Eigen::Matrix3d& R) noexcept;

// SVD construction (Rollinson & Choset's virtual chassis; the thesis's "SVD-based" option): principal axis of the frame
// positions about their centroid (eigenvector of the largest eigenvalue of their scatter matrix,
// i.e. the first left singular vector of the centred positions), projected on the horizontal plane
// and signed to point from the tail towards the head. Returns false (R untouched) when degenerate.
bool virtual_chassis_svd(const std::vector<Eigen::Vector3d>& positions, Eigen::Matrix3d& R) noexcept;

// Centre of mass (eq. 3.15): mass-weighted mean of the frame positions.
Eigen::Vector3d centre_of_mass(const std::vector<Eigen::Vector3d>& positions, const std::vector<double>& masses_kg,
                               double inverse_total_mass) noexcept;

// Bounding box spans in the chassis frame (eq. 3.17-3.20): 2Δ_k + padding per axis.
Eigen::Vector3d bounding_box_span(const std::vector<Eigen::Vector3d>& positions, const Eigen::Vector3d& com,
                                  const Eigen::Matrix3d& R, double padding_m) noexcept;

}  // namespace snake_autonomy::core
