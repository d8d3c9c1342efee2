// GaitLibrary (config/gaits.yaml) and amplitude-modulation Steering.
#include "bindings.hpp"

#include "snake_autonomy/core/curvature_steering.hpp"
#include "snake_autonomy/core/gait_library.hpp"
#include "snake_autonomy/core/robot_model.hpp"
#include "snake_autonomy/core/steering.hpp"

namespace snake_autonomy::bindings {

using namespace snake_autonomy::core;
namespace dx = snake_autonomy::dynamixel;

void expose_gaits(py::module_& m) {
  py::class_<GaitLibrary>(m, "GaitLibrary", "Named gaits from config/gaits.yaml.")
      .def_static("from_yaml", &GaitLibrary::from_yaml_file, py::arg("path"),
                  "Load and validate; ValueError lists every problem.")
      .def_static("from_yaml_string", &GaitLibrary::from_yaml_string, py::arg("text"), py::arg("source") = "<string>")
      .def_property_readonly("names", &GaitLibrary::names)
      .def("__contains__", &GaitLibrary::contains, py::arg("name"))
      .def(
          "parameters",
          [](const GaitLibrary& lib, const std::string& name, const RobotModel& model) {
            try {
              return lib.parameters(name, model);
            } catch (const std::out_of_range& e) {
              throw py::key_error(e.what());
            }
          },
          py::arg("name"), py::arg("model"), "Per-joint CPG targets of a gait for a robot (KeyError if unknown).")
      .def(
          "frequency_hz", [](const GaitLibrary& lib, const std::string& name) { return lib.spec(name).frequency_hz; },
          py::arg("name"))
      .def(
          "steerable", [](const GaitLibrary& lib, const std::string& name) { return lib.spec(name).steerable; },
          py::arg("name"))
      .def(
          "steering",
          [](const GaitLibrary& lib, const std::string& name) {
            return std::string(to_string(lib.spec(name).steering));
          },
          py::arg("name"), "'amplitude_modulation', 'curvature' or 'none'")
      .def(
          "description", [](const GaitLibrary& lib, const std::string& name) { return lib.spec(name).description; },
          py::arg("name"));

  py::class_<CurvatureSteering>(m, "CurvatureSteering", "Body-curvature steering: yaw-joint bias = kappa x spacing.")
      .def(py::init<const RobotModel&>(), py::arg("model"))
      .def(
          "modify_biases",
          [](const CurvatureSteering& s, py::object nominal, double kappa_per_m) {
            if (!std::isfinite(kappa_per_m))
              throw py::value_error("kappa_per_m: must be finite, got " + std::to_string(kappa_per_m));
            const Eigen::VectorXd b = checked_vector(nominal, s.num_joints(), "nominal");
            Eigen::VectorXd out = b;
            s.modify_biases(b, kappa_per_m, out);
            return out;
          },
          py::arg("nominal"), py::arg("kappa_per_m"), "Yaw-joint biases bent by kappa, clamped to the joint limits.")
      .def_property_readonly("spacing_m", &CurvatureSteering::spacing_m)
      .def_property_readonly("yaw_joints", &CurvatureSteering::yaw_joints);

  py::class_<Steering>(m, "Steering", "Amplitude-modulation steering (eq. 3.26-3.29).")
      .def(py::init<const RobotModel&>(), py::arg("model"))
      .def(
          "modify_amplitudes",
          [](const Steering& s, py::object nominal, double delta_rad) {
            if (!std::isfinite(delta_rad))
              throw py::value_error("delta_rad: must be finite, got " + std::to_string(delta_rad));
            const Eigen::VectorXd a = checked_vector(nominal, s.num_joints(), "nominal");
            Eigen::VectorXd out = a;
            s.modify_amplitudes(a, delta_rad, out);
            return out;
          },
          py::arg("nominal"), py::arg("delta_rad"),
          "Yaw-joint amplitudes modulated by delta (clipped to ±delta_limit), clamped to the amplitude bounds.")
      .def("clip_delta", &Steering::clip_delta, py::arg("delta_rad"), "δ after the ±delta_limit clip.")
      .def_property_readonly("yaw_joints", &Steering::yaw_joints);
}

}  // namespace snake_autonomy::bindings
