// GaitParameters and the CPG (eq. 3.21-3.25).
#include "bindings.hpp"

#include "snake_autonomy/core/cpg.hpp"
#include "snake_autonomy/core/robot_model.hpp"

namespace snake_autonomy::bindings {

using namespace snake_autonomy::core;
namespace dx = snake_autonomy::dynamixel;

void expose_cpg(py::module_& m) {
  py::class_<GaitParameters>(m, "GaitParameters", "Per-joint CPG targets (rad, rad/s).")
      .def(py::init([](int num_joints) { return GaitParameters::zeros(num_joints); }), py::arg("num_joints"))
      .def_readwrite("amplitude", &GaitParameters::amplitude)
      .def_readwrite("omega", &GaitParameters::omega)
      .def_readwrite("phase", &GaitParameters::phase)
      .def_readwrite("bias", &GaitParameters::bias)
      .def("__repr__", [](const GaitParameters& p) {
        return "<GaitParameters of " + std::to_string(p.amplitude.size()) + " joints>";
      });

  py::class_<Cpg>(m, "CPG", "Coupled phase oscillators with critically damped amplitudes (eq. 3.21-3.25).")
      .def(py::init([](const RobotModel& model, double mu, double gamma) { return Cpg(model, mu, gamma); }),
           py::arg("model"), py::kw_only(), py::arg("mu") = 0.0, py::arg("gamma") = 0.0,
           "mu, gamma <= 0 take the robot description's values.")
      .def_property_readonly("num_joints", &Cpg::num_joints)
      .def_property_readonly("mu", &Cpg::mu)
      .def_property_readonly("gamma", &Cpg::gamma)
      .def(
          "set_parameters",
          [](Cpg& cpg, py::object amplitude, py::object omega, py::object phase, py::object bias) {
            GaitParameters p = cpg.targets();
            const Eigen::Index n = cpg.num_joints();
            if (!amplitude.is_none()) p.amplitude = checked_vector(amplitude, n, "amplitude");
            if (!omega.is_none()) p.omega = checked_vector(omega, n, "omega");
            if (!phase.is_none()) p.phase = checked_vector(phase, n, "phase");
            if (!bias.is_none()) p.bias = checked_vector(bias, n, "bias");
            cpg.set_parameters(p);
          },
          py::kw_only(), py::arg("amplitude") = py::none(), py::arg("omega") = py::none(),
          py::arg("phase") = py::none(), py::arg("bias") = py::none(),
          "New targets (radians, rad/s, one value per joint); omitted ones are kept. All or nothing: "
          "ValueError on a wrong length or a non-finite value, and nothing changes.")
      .def(
          "apply", [](Cpg& cpg, const GaitParameters& p) { cpg.set_parameters(p); }, py::arg("parameters"),
          "Sets all targets from a GaitParameters (ValueError, and nothing changes, when invalid).")
      .def_property_readonly("targets", &Cpg::targets)
      .def(
          "reset",
          [](Cpg& cpg, py::object phases, py::object amplitudes, py::object biases) {
            const Eigen::Index n = cpg.num_joints();
            cpg.reset(checked_vector(phases, n, "phases"),
                      amplitudes.is_none() ? Eigen::VectorXd::Zero(n) : checked_vector(amplitudes, n, "amplitudes"),
                      biases.is_none() ? Eigen::VectorXd::Zero(n) : checked_vector(biases, n, "biases"));
          },
          py::arg("phases"), py::arg("amplitudes") = py::none(), py::arg("biases") = py::none(),
          "Sets the oscillator state (rates zeroed).")
      .def(
          "step",
          [](Cpg& cpg, double dt_s) {
            if (!(dt_s > 0.0) || !std::isfinite(dt_s))
              throw py::value_error("dt_s: must be a positive finite number, got " + std::to_string(dt_s));
            return Eigen::VectorXd(cpg.step(dt_s));
          },
          py::arg("dt_s"), "Advances the oscillators by dt_s seconds; returns the joint angles (rad).")
      .def_property_readonly(
          "phases", [](const Cpg& c) { return Eigen::VectorXd(c.phases()); }, "θ (rad)")
      .def_property_readonly(
          "amplitudes", [](const Cpg& c) { return Eigen::VectorXd(c.amplitudes()); }, "r (rad)")
      .def_property_readonly("amplitude_rates", [](const Cpg& c) { return Eigen::VectorXd(c.amplitude_rates()); })
      .def_property_readonly("biases", [](const Cpg& c) { return Eigen::VectorXd(c.biases()); })
      .def_property_readonly(
          "output", [](const Cpg& c) { return Eigen::VectorXd(c.output()); },
          "last joint angles, clamped to the joint limits")
      .def_property_readonly("unclamped_output", [](const Cpg& c) { return Eigen::VectorXd(c.unclamped_output()); });
}

}  // namespace snake_autonomy::bindings
