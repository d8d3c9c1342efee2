// RobotModel: the robot description (config/robots/<name>.yaml).
#include "bindings.hpp"

#include "snake_autonomy/core/robot_model.hpp"

namespace snake_autonomy::bindings {

using namespace snake_autonomy::core;
namespace dx = snake_autonomy::dynamixel;

void expose_robot_model(py::module_& m) {
  py::class_<RobotModel>(m, "RobotModel", "Robot description loaded from config/robots/<name>.yaml.")
      .def_static("from_yaml", &RobotModel::from_yaml_file, py::arg("path"),
                  "Load and validate a robot description; ValueError lists every problem.")
      .def_static("from_yaml_string", &RobotModel::from_yaml_string, py::arg("text"), py::arg("source") = "<string>",
                  "Same as from_yaml, from YAML text.")
      .def("validate", &RobotModel::validate, "Every problem of the description (empty when valid).")
      .def_readonly("name", &RobotModel::name)
      .def_readonly("num_joints", &RobotModel::num_joints)
      .def_property_readonly("num_frames", &RobotModel::num_frames, "base + head + one per joint")
      .def_property_readonly("frame_names", &RobotModel::frame_names, "base_link, head_link, link_1..link_N")
      .def_property_readonly("joint_names", &RobotModel::joint_names, "joint_1..joint_N")
      .def_property_readonly(
          "axes",
          [](const RobotModel& r) {
            std::vector<std::string> out;
            for (auto a : r.axes) out.push_back(to_string(a));
            return out;
          },
          "'pitch' or 'yaw' per joint")
      .def_property_readonly("yaw_joints", &RobotModel::yaw_joints, "0-based indices of the yaw joints")
      .def_property_readonly("pitch_joints", &RobotModel::pitch_joints, "0-based indices of the pitch joints")
      .def_readonly("head_length_m", &RobotModel::head_length_m)
      .def_readonly("link_length_m", &RobotModel::link_length_m)
      .def_readonly("link_radius_m", &RobotModel::link_radius_m)
      .def_property_readonly(
          "masses_kg", [](const RobotModel& r) { return to_vector(r.masses_kg); },
          "per frame: base, head, link_1..link_N")
      .def_property_readonly("joint_lower_rad", [](const RobotModel& r) { return to_vector(r.joint_lower_rad); })
      .def_property_readonly("joint_upper_rad", [](const RobotModel& r) { return to_vector(r.joint_upper_rad); })
      .def_property_readonly("servo_model", [](const RobotModel& r) { return r.servos.model; })
      .def_property_readonly("servo_ids", [](const RobotModel& r) { return r.servos.ids; })
      .def_property_readonly("servo_directions", [](const RobotModel& r) { return r.servos.directions; })
      .def_property_readonly("servo_zero_offsets_ticks",
                             [](const RobotModel& r) { return r.servos.zero_offsets_ticks; })
      .def_property_readonly("mu", [](const RobotModel& r) { return r.cpg.mu; })
      .def_property_readonly("gamma", [](const RobotModel& r) { return r.cpg.gamma; })
      .def_property_readonly("amplitude_limit_rad", [](const RobotModel& r) { return r.cpg.amplitude_limit_rad; })
      .def_property_readonly("steering_weights", [](const RobotModel& r) { return to_vector(r.steering.weights); })
      .def_property_readonly("delta_limit_rad", [](const RobotModel& r) { return r.steering.delta_limit_rad; })
      .def_property_readonly("delta_offset_rad", [](const RobotModel& r) { return r.steering.delta_offset_rad; })
      .def_property_readonly("virtual_chassis", [](const RobotModel& r) { return to_string(r.chassis); })
      .def_readonly("bbox_padding_m", &RobotModel::bbox_padding_m);
}

}  // namespace snake_autonomy::bindings
