// Shared by the src/bindings/expose_*.cpp files of snake_autonomy._core (one file per bound area,
// Pinocchio style). module.cpp calls every expose_* declared here, in this order: add a file and one
// line there. Conventions: one .def per C++ member under its C++ name, the same argument names, a
// docstring each; angles in radians; configuration errors are ConfigError (a ValueError).
#pragma once

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "snake_autonomy/dynamixel/servo_bus.hpp"

namespace snake_autonomy::bindings {

namespace py = pybind11;

// The areas, each in src/bindings/expose_<area>.cpp.
void expose_robot_model(py::module_& m);
void expose_cpg(py::module_& m);
void expose_gaits(py::module_& m);
void expose_kinematics(py::module_& m);
void expose_dynamixel(py::module_& m);        // creates the submodule `dynamixel`
void expose_servo_model(py::module_& m);      // SimulatedServos into `dynamixel`; after expose_dynamixel
void expose_fake_servo_bus(py::module_& m);   // into `dynamixel`; after expose_servo_model
void expose_transmission(py::module_& m);     // after expose_robot_model and expose_dynamixel
void expose_driver(py::module_& m);           // after expose_fake_servo_bus

// Helpers shared by several areas (helpers.cpp).
Eigen::VectorXd to_vector(const std::vector<double>& v);
// A 1-D float64 array of length n with only finite values, or ValueError naming the argument.
Eigen::VectorXd checked_vector(const py::handle& obj, Eigen::Index n, const char* name);
py::array_t<double> stack_vectors(const std::vector<Eigen::Vector3d>& v);
py::array_t<double> stack_matrices(const std::vector<Eigen::Matrix3d>& v);
py::bytes to_bytes(const std::uint8_t* p, std::size_t n);
std::string from_bytes(const py::bytes& b);
py::dict counters_dict(const dynamixel::BusCounters& c);

}  // namespace snake_autonomy::bindings
