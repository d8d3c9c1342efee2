// Kinematics (KDL) and its KinematicState; make_urdf.
#include "bindings.hpp"

#include "snake_autonomy/core/kinematics.hpp"
#include "snake_autonomy/core/robot_model.hpp"
#include "snake_autonomy/core/urdf.hpp"

namespace snake_autonomy::bindings {

using namespace snake_autonomy::core;
namespace dx = snake_autonomy::dynamixel;

void expose_kinematics(py::module_& m) {
  py::class_<KinematicState>(m, "KinematicState", "Result of Kinematics.compute (world frame, metres).")
      .def_property_readonly(
          "link_positions", [](const KinematicState& s) { return stack_vectors(s.link_positions); },
          "(F, 3) frame origins in chain order: base, head, link_1..link_N")
      .def_property_readonly(
          "link_rotations", [](const KinematicState& s) { return stack_matrices(s.link_rotations); }, "(F, 3, 3)")
      .def_property_readonly(
          "parent_positions", [](const KinematicState& s) { return stack_vectors(s.parent_positions); },
          "(F, 3) relative to the previous frame (eq. 3.9)")
      .def_property_readonly(
          "parent_rotations", [](const KinematicState& s) { return stack_matrices(s.parent_rotations); }, "(F, 3, 3)")
      .def_readonly("com", &KinematicState::com, "(3,) centre of mass, eq. 3.15")
      .def_readonly("vc_rotation", &KinematicState::vc_rotation, "(3, 3) virtual chassis, eq. 3.14 or SVD")
      .def_readonly("bbox_span", &KinematicState::bbox_span, "(3,) bounding box spans, padding included, eq. 3.20")
      .def_readonly("vc_degenerate", &KinematicState::vc_degenerate);

  py::class_<Kinematics>(m, "Kinematics", "Forward kinematics of the whole chain (KDL), eq. 3.2-3.20.")
      .def(py::init<const RobotModel&>(), py::arg("model"))
      .def_property_readonly("num_frames", &Kinematics::num_frames)
      .def(
          "compute",
          [](const Kinematics& k, py::object base_position, py::object base_quaternion_xyzw, py::object q) {
            const Eigen::Vector3d p = checked_vector(base_position, 3, "base_position");
            const Eigen::VectorXd qx = checked_vector(base_quaternion_xyzw, 4, "base_quaternion_xyzw");
            if (qx.norm() < 1e-9) throw py::value_error("base_quaternion_xyzw: must not be zero");
            const Eigen::VectorXd joints = checked_vector(q, k.model().num_joints, "q");
            KinematicState s = k.make_state();
            k.compute(p, Eigen::Quaterniond(qx(3), qx(0), qx(1), qx(2)), joints, s);
            return s;
          },
          py::arg("base_position"), py::arg("base_quaternion_xyzw"), py::arg("q"),
          "Poses of every frame, centre of mass, virtual chassis and bounding box; q in radians.");

  m.def(
      "make_urdf",
      [](const RobotModel& model, double effort_nm, double velocity_rad_s, const py::object& camera_in_head,
         const std::string& camera_name) {
        std::optional<CameraMount> camera;
        if (!camera_in_head.is_none()) {
          const auto t = camera_in_head.cast<Eigen::Matrix4d>();
          camera = CameraMount{camera_name, Eigen::Isometry3d(t)};
        }
        return make_urdf(model, effort_nm, velocity_rad_s, camera);
      },
      py::arg("model"), py::arg("effort_nm") = 9.9, py::arg("velocity_rad_s") = 4.8,
      py::arg("camera_in_head") = py::none(), py::arg("camera_name") = "camera",
      "URDF of the robot description (same frames as Kinematics); camera_in_head (4x4, T_head^camera) "
      "adds <camera_name>_link and <camera_name>_color_optical_frame on head_link.");
}

}  // namespace snake_autonomy::bindings
