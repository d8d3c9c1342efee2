// snake_autonomy._core: the C++ core for Python (tools, tests, the simulator).
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "snake_autonomy/core/robot_model.hpp"

namespace py = pybind11;
using namespace snake_autonomy::core;

PYBIND11_MODULE(_core, m) {
  m.doc() = "snake_autonomy C++ core";
  py::register_exception<ConfigError>(m, "ConfigError", PyExc_ValueError);
  py::class_<RobotModel>(m, "RobotModel")
      .def_static("from_yaml", &RobotModel::from_yaml_file, py::arg("path"),
                  "Load and validate a robot description; ValueError lists every problem.")
      .def_readonly("name", &RobotModel::name)
      .def_readonly("num_joints", &RobotModel::num_joints);
}
