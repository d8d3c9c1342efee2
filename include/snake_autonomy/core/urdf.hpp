// URDF of a robot description, for robot_state_publisher and rviz: the same chain as Kinematics.
//
// URDF rotates a child frame about an axis through its own origin, while eq. 3.4 rotates first and
// translates after: each joint therefore gets a rotor link (link_i_rotor = previous · Rz(−q_i), the
// revolute joint with axis −z) and a fixed joint to link_i (Trans(−L, 0, 0) · Rx(τ_i)). The frames
// base_link, head_link and link_1..link_N coincide with the core's frames for every joint vector.
#pragma once

#include <string>

#include "snake_autonomy/core/robot_model.hpp"

namespace snake_autonomy::core {

// effort_nm and velocity_rad_s go into every joint's <limit> (XH540-W270: 9.9 N·m, about 4.8 rad/s).
std::string make_urdf(const RobotModel& model, double effort_nm = 9.9, double velocity_rad_s = 4.8);

}  // namespace snake_autonomy::core
