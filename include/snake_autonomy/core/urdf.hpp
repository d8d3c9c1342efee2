// URDF of a robot description, for robot_state_publisher and rviz: the same chain as Kinematics.
//
// URDF rotates a child frame about an axis through its own origin, while eq. 3.4 rotates first and
// translates after: each joint therefore gets a rotor link (link_i_rotor = previous · Rz(−q_i), the
// revolute joint with axis −z) and a fixed joint to link_i (Trans(−L, 0, 0) · Rx(τ_i)). The frames
// base_link, head_link and link_1..link_N coincide with the core's frames for every joint vector.
//
// Each body is a capsule of the YAML's link_radius_m: visual cylinder, collision cylinder plus two
// spheres. Segment i (link_i_rotor, from joint i to link_i) carries masses_kg[i+1] (0-based: the
// mass eq. 3.15 lumps at frame link_i) as a solid cylinder at its centroid; the head (base_link to
// head_link) carries masses_kg[0] + masses_kg[1] on head_link (KDL allows no inertia on the root).
// The kinematics keeps eq. 3.15's point masses at the frames; the URDF's inertias are for tools that
// simulate or plan with it. Every revolute joint has a transmission_interface/SimpleTransmission to
// its servo (actuator servo_<id>, mechanical reduction = the YAML's direction, ±1).
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>

#include "snake_autonomy/core/robot_model.hpp"

namespace snake_autonomy::core {

// A camera rigidly mounted on the head (config/camera.yaml, T_head^camera): <name>_link at
// camera_in_head in head_link (x forward, y left, z up, REP 103), and <name>_color_optical_frame
// under it (z forward, x right, y down: rpy −π/2, 0, −π/2), as realsense2_camera names them.
struct CameraMount {
  std::string name = "camera";
  Eigen::Isometry3d camera_in_head = Eigen::Isometry3d::Identity();
};

// effort_nm and velocity_rad_s go into every joint's <limit> (XH540-W270: 9.9 N·m, about 4.8 rad/s).
std::string make_urdf(const RobotModel& model, double effort_nm = 9.9, double velocity_rad_s = 4.8,
                      const std::optional<CameraMount>& camera = std::nullopt);

}  // namespace snake_autonomy::core
