// snake_autonomy._core: the C++ core for Python (tools, tests, the simulator).
// One .def per C++ member, the same argument names, a docstring each. Angles in radians.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "snake_autonomy/core/cpg.hpp"
#include "snake_autonomy/core/gait_library.hpp"
#include "snake_autonomy/core/kinematics.hpp"
#include "snake_autonomy/core/robot_model.hpp"
#include "snake_autonomy/core/steering.hpp"
#include "snake_autonomy/core/urdf.hpp"

namespace py = pybind11;
using namespace snake_autonomy::core;

namespace {

Eigen::VectorXd to_vector(const std::vector<double>& v) {
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

void bind_robot_model(py::module_& m) {
  py::class_<RobotModel>(m, "RobotModel", "Robot description loaded from config/robots/<name>.yaml.")
      .def_static("from_yaml", &RobotModel::from_yaml_file, py::arg("path"),
                  "Load and validate a robot description; ValueError lists every problem.")
      .def_static("from_yaml_string", &RobotModel::from_yaml_string, py::arg("text"),
                  py::arg("source") = "<string>", "Same as from_yaml, from YAML text.")
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
      .def_property_readonly("masses_kg", [](const RobotModel& r) { return to_vector(r.masses_kg); },
                             "per frame: base, head, link_1..link_N")
      .def_property_readonly("joint_lower_rad", [](const RobotModel& r) { return to_vector(r.joint_lower_rad); })
      .def_property_readonly("joint_upper_rad", [](const RobotModel& r) { return to_vector(r.joint_upper_rad); })
      .def_property_readonly("servo_model", [](const RobotModel& r) { return r.servos.model; })
      .def_property_readonly("servo_ids", [](const RobotModel& r) { return r.servos.ids; })
      .def_property_readonly("servo_directions", [](const RobotModel& r) { return r.servos.directions; })
      .def_property_readonly("servo_zero_offsets_ticks", [](const RobotModel& r) { return r.servos.zero_offsets_ticks; })
      .def_property_readonly("mu", [](const RobotModel& r) { return r.cpg.mu; })
      .def_property_readonly("gamma", [](const RobotModel& r) { return r.cpg.gamma; })
      .def_property_readonly("amplitude_limit_rad", [](const RobotModel& r) { return r.cpg.amplitude_limit_rad; })
      .def_property_readonly("steering_weights", [](const RobotModel& r) { return to_vector(r.steering.weights); })
      .def_property_readonly("delta_limit_rad", [](const RobotModel& r) { return r.steering.delta_limit_rad; })
      .def_property_readonly("delta_offset_rad", [](const RobotModel& r) { return r.steering.delta_offset_rad; })
      .def_property_readonly("virtual_chassis", [](const RobotModel& r) { return to_string(r.chassis); })
      .def_readonly("bbox_padding_m", &RobotModel::bbox_padding_m);
}

// A 1-D float64 array of length n with only finite values, or ValueError naming the argument.
Eigen::VectorXd checked_vector(const py::handle& obj, Eigen::Index n, const char* name) {
  py::array_t<double, py::array::c_style | py::array::forcecast> arr;
  try {
    arr = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(obj);
  } catch (const py::error_already_set&) {
    arr = py::array_t<double, py::array::c_style | py::array::forcecast>();
  }
  if (!arr) throw py::value_error(std::string(name) + ": expected an array of numbers");
  if (arr.ndim() != 1 || arr.shape(0) != n)
    throw py::value_error(std::string(name) + ": expected shape (" + std::to_string(n) + ",), got " +
                          std::string(py::str(py::tuple(py::cast(std::vector<py::ssize_t>(
                              arr.shape(), arr.shape() + arr.ndim()))))));
  Eigen::VectorXd v = Eigen::Map<const Eigen::VectorXd>(arr.data(), n);
  for (Eigen::Index i = 0; i < n; ++i)
    if (!std::isfinite(v(i)))
      throw py::value_error(std::string(name) + "[" + std::to_string(i) + "]: must be finite, got " +
                            std::to_string(v(i)));
  return v;
}

py::array_t<double> stack_vectors(const std::vector<Eigen::Vector3d>& v) {
  py::array_t<double> out({static_cast<py::ssize_t>(v.size()), py::ssize_t{3}});
  auto m = out.mutable_unchecked<2>();
  for (std::size_t i = 0; i < v.size(); ++i)
    for (int k = 0; k < 3; ++k) m(i, k) = v[i](k);
  return out;
}

py::array_t<double> stack_matrices(const std::vector<Eigen::Matrix3d>& v) {
  py::array_t<double> out({static_cast<py::ssize_t>(v.size()), py::ssize_t{3}, py::ssize_t{3}});
  auto m = out.mutable_unchecked<3>();
  for (std::size_t i = 0; i < v.size(); ++i)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) m(i, r, c) = v[i](r, c);
  return out;
}

void bind_cpg(py::module_& m) {
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
      .def("apply", [](Cpg& cpg, const GaitParameters& p) { cpg.set_parameters(p); }, py::arg("parameters"),
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
      .def_property_readonly("phases", [](const Cpg& c) { return Eigen::VectorXd(c.phases()); }, "θ (rad)")
      .def_property_readonly("amplitudes", [](const Cpg& c) { return Eigen::VectorXd(c.amplitudes()); }, "r (rad)")
      .def_property_readonly("amplitude_rates", [](const Cpg& c) { return Eigen::VectorXd(c.amplitude_rates()); })
      .def_property_readonly("biases", [](const Cpg& c) { return Eigen::VectorXd(c.biases()); })
      .def_property_readonly("output", [](const Cpg& c) { return Eigen::VectorXd(c.output()); },
                             "last joint angles, clamped to the joint limits")
      .def_property_readonly("unclamped_output", [](const Cpg& c) { return Eigen::VectorXd(c.unclamped_output()); });
}

void bind_gaits(py::module_& m) {
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
          "description", [](const GaitLibrary& lib, const std::string& name) { return lib.spec(name).description; },
          py::arg("name"));

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

void bind_kinematics(py::module_& m) {
  py::class_<KinematicState>(m, "KinematicState", "Result of Kinematics.compute (world frame, metres).")
      .def_property_readonly("link_positions", [](const KinematicState& s) { return stack_vectors(s.link_positions); },
                             "(F, 3) frame origins in chain order: base, head, link_1..link_N")
      .def_property_readonly("link_rotations", [](const KinematicState& s) { return stack_matrices(s.link_rotations); },
                             "(F, 3, 3)")
      .def_property_readonly("parent_positions",
                             [](const KinematicState& s) { return stack_vectors(s.parent_positions); },
                             "(F, 3) relative to the previous frame (eq. 3.9)")
      .def_property_readonly("parent_rotations",
                             [](const KinematicState& s) { return stack_matrices(s.parent_rotations); }, "(F, 3, 3)")
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

  m.def("make_urdf", &make_urdf, py::arg("model"), py::arg("effort_nm") = 9.9, py::arg("velocity_rad_s") = 4.8,
        "URDF of the robot description (same frames as Kinematics).");
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "snake_autonomy C++ core: robot model, CPG, gaits, steering, kinematics, Dynamixel Protocol 2.0";
  py::register_exception<ConfigError>(m, "ConfigError", PyExc_ValueError);
  bind_robot_model(m);
  bind_cpg(m);
  bind_gaits(m);
  bind_kinematics(m);
}
