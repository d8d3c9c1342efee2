// Transmission (snake_autonomy/driver/transmission.hpp): the one servo <-> joint conversion, for the
// simulator's servo backend and the tools.
#include "bindings.hpp"

#include "snake_autonomy/core/robot_model.hpp"
#include "snake_autonomy/driver/transmission.hpp"
#include "snake_autonomy/dynamixel/control_table.hpp"

namespace snake_autonomy::bindings {

void expose_transmission(py::module_& m) {
  using driver::Transmission;
  py::class_<Transmission>(m, "Transmission",
                           "One joint's servo <-> joint mapping: the control table's resolution and centre, the robot "
                           "YAML's direction and zero offset. The only place that converts ticks and radians.")
      .def_static("for_robot", &Transmission::for_robot, py::arg("model"), py::arg("table"),
                  "One per joint, in joint order.")
      .def("ticks_to_joint_rad", &Transmission::ticks_to_joint_rad, py::arg("ticks"))
      .def(
          "joint_rad_to_ticks",
          [](const Transmission& t, double joint_rad) -> py::object {
            std::int32_t ticks = 0;
            return t.joint_rad_to_ticks(joint_rad, &ticks) ? py::object(py::int_(ticks)) : py::object(py::none());
          },
          py::arg("joint_rad"), "Nearest tick (no clamping); None when not representable.")
      .def("shaft_rad_to_joint_rad", &Transmission::shaft_rad_to_joint_rad, py::arg("shaft_rad"),
           "shaft angle from the servo's centre -> joint angle")
      .def("joint_rad_to_shaft_rad", &Transmission::joint_rad_to_shaft_rad, py::arg("joint_rad"))
      .def("ticks_to_shaft_rad", &Transmission::ticks_to_shaft_rad, py::arg("ticks"))
      .def("velocity_to_joint_rad_s", &Transmission::velocity_to_joint_rad_s, py::arg("units"))
      .def("current_to_joint_amps", &Transmission::current_to_joint_amps, py::arg("units"))
      .def("shaft_to_joint_sense", &Transmission::shaft_to_joint_sense, py::arg("value"))
      .def_property_readonly("direction", &Transmission::direction)
      .def_property_readonly("zero_offset_ticks", &Transmission::zero_offset_ticks)
      .def_property_readonly("centre_ticks", &Transmission::centre_ticks)
      .def_property_readonly("rad_per_tick", &Transmission::rad_per_tick);
}

}  // namespace snake_autonomy::bindings
