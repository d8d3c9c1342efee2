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
// ---------------------------------------------------------------------------------------------
// Dynamixel Protocol 2.0 (submodule snake_autonomy._core.dynamixel): the codec the mocked bus
// uses, the control table, conversions, and SerialBus (the GIL is released while it waits).
}  // namespace

#include "snake_autonomy/core/driver_config.hpp"
#include "snake_autonomy/core/driver_controller.hpp"
#include "snake_autonomy/core/gait_command.hpp"
#include "snake_autonomy/dynamixel/control_table.hpp"
#include "snake_autonomy/dynamixel/conversions.hpp"
#include "snake_autonomy/dynamixel/protocol.hpp"
#include "snake_autonomy/dynamixel/serial_bus.hpp"

namespace {

namespace dx = snake_autonomy::dynamixel;

py::bytes to_bytes(const std::uint8_t* p, std::size_t n) { return py::bytes(reinterpret_cast<const char*>(p), n); }

std::string from_bytes(const py::bytes& b) { return std::string(b); }

py::dict counters_dict(const dx::BusCounters& c) {
  py::dict d;
  d["transactions"] = c.transactions;
  d["bytes_sent"] = c.bytes_sent;
  d["bytes_received"] = c.bytes_received;
  d["packets_received"] = c.packets_received;
  d["crc_errors"] = c.crc_errors;
  d["timeouts"] = c.timeouts;
  d["malformed"] = c.malformed;
  d["hardware_error_alerts"] = c.hardware_error_alerts;
  d["servo_errors"] = c.servo_errors;
  d["unexpected_packets"] = c.unexpected_packets;
  d["io_errors"] = c.io_errors;
  return d;
}

// sync_read / fast_sync_read for Python: (status, data, [(status, error) per servo]).
template <typename Fn>
py::tuple group_read(dx::SerialBus& bus, std::uint16_t address, std::uint16_t length, const std::vector<std::uint8_t>& ids,
                     Fn fn) {
  std::vector<std::uint8_t> data(ids.size() * length, 0);
  std::vector<dx::ServoReply> replies(ids.size());
  dx::Status s;
  {
    py::gil_scoped_release release;
    s = (bus.*fn)(address, length, ids.data(), ids.size(), data.data(), replies.data());
  }
  py::list per_servo;
  for (const auto& r : replies) per_servo.append(py::make_tuple(r.status, r.error));
  return py::make_tuple(s, to_bytes(data.data(), data.size()), per_servo);
}

void bind_dynamixel(py::module_& parent) {
  py::module_ m = parent.def_submodule("dynamixel", "Dynamixel Protocol 2.0: packets, control table, serial bus");
  py::register_exception<dx::SerialError>(m, "SerialError", PyExc_OSError);

  m.attr("BROADCAST_ID") = dx::kBroadcastId;
  m.attr("ALERT_BIT") = dx::kAlertBit;
  m.attr("MAX_PACKET_BYTES") = dx::kMaxPacketBytes;
  m.attr("STATUS_OVERHEAD") = dx::kStatusOverhead;
  m.attr("FEEDBACK_ADDRESS") = dx::kFeedbackAddress;
  m.attr("FEEDBACK_BYTES") = dx::kFeedbackBytes;
  py::module_ inst = m.def_submodule("instruction", "Instruction codes");
  inst.attr("PING") = dx::instruction::kPing;
  inst.attr("READ") = dx::instruction::kRead;
  inst.attr("WRITE") = dx::instruction::kWrite;
  inst.attr("REBOOT") = dx::instruction::kReboot;
  inst.attr("STATUS") = dx::instruction::kStatus;
  inst.attr("SYNC_READ") = dx::instruction::kSyncRead;
  inst.attr("SYNC_WRITE") = dx::instruction::kSyncWrite;
  inst.attr("FAST_SYNC_READ") = dx::instruction::kFastSyncRead;

  py::enum_<dx::ParseStatus>(m, "ParseStatus")
      .value("OK", dx::ParseStatus::kOk)
      .value("INCOMPLETE", dx::ParseStatus::kIncomplete)
      .value("BAD_CRC", dx::ParseStatus::kBadCrc)
      .value("MALFORMED", dx::ParseStatus::kMalformed);
  py::enum_<dx::Status>(m, "Status")
      .value("OK", dx::Status::kOk)
      .value("HARDWARE_ERROR", dx::Status::kHardwareError)
      .value("TIMEOUT", dx::Status::kTimeout)
      .value("CRC_ERROR", dx::Status::kCrcError)
      .value("MALFORMED", dx::Status::kMalformed)
      .value("WRONG_ID", dx::Status::kWrongId)
      .value("WRONG_INSTRUCTION", dx::Status::kWrongInstruction)
      .value("SERVO_ERROR", dx::Status::kServoError)
      .value("INVALID_ARGUMENT", dx::Status::kInvalidArgument)
      .value("IO_ERROR", dx::Status::kIoError)
      .value("NOT_OPEN", dx::Status::kNotOpen);

  m.def("crc16", [](const py::bytes& data, std::uint16_t crc) {
        const std::string s = from_bytes(data);
        return dx::crc16(reinterpret_cast<const std::uint8_t*>(s.data()), s.size(), crc);
      }, py::arg("data"), py::arg("crc") = 0, "CRC-16 of Protocol 2.0 (0x8005, init 0); pass crc to continue.");
  m.def("stuff", [](const py::bytes& data) {
        const std::string s = from_bytes(data);
        std::vector<std::uint8_t> out(s.size() * 2 + 1);
        const std::size_t n = dx::stuff(reinterpret_cast<const std::uint8_t*>(s.data()), s.size(), out.data(), out.size());
        return to_bytes(out.data(), n);
      }, py::arg("data"), "Byte stuffing of an INST+PARAM region: FF FF FD gets an extra FD.");
  m.def("unstuff", [](const py::bytes& data) {
        const std::string s = from_bytes(data);
        std::vector<std::uint8_t> out(s.size() + 1);
        const std::size_t n = dx::unstuff(reinterpret_cast<const std::uint8_t*>(s.data()), s.size(), out.data(), out.size());
        if (n == dx::kBadStuffing) throw py::value_error("data: FF FF FD not followed by its stuffed FD");
        return to_bytes(out.data(), n);
      }, py::arg("data"), "Removes the FD that follows FF FF FD; ValueError when one is missing.");
  m.def("encode_packet", [](std::uint8_t id, std::uint8_t instruction, const py::bytes& params) {
        const std::string s = from_bytes(params);
        std::vector<std::uint8_t> out(dx::kMaxPacketBytes);
        const std::size_t n = dx::encode_packet(id, instruction, reinterpret_cast<const std::uint8_t*>(s.data()), s.size(),
                                                out.data(), out.size());
        if (n == 0) throw py::value_error("params: " + std::to_string(s.size()) + " bytes do not fit one packet");
        return to_bytes(out.data(), n);
      }, py::arg("id"), py::arg("instruction"), py::arg("params") = py::bytes(), "A whole packet, stuffed, with its CRC.");
  m.def("encode_status", [](std::uint8_t id, std::uint8_t error, const py::bytes& data) {
        const std::string s = from_bytes(data);
        std::vector<std::uint8_t> out(dx::kMaxPacketBytes);
        const std::size_t n = dx::encode_status(id, error, reinterpret_cast<const std::uint8_t*>(s.data()), s.size(),
                                                out.data(), out.size());
        if (n == 0) throw py::value_error("data: " + std::to_string(s.size()) + " bytes do not fit one packet");
        return to_bytes(out.data(), n);
      }, py::arg("id"), py::arg("error"), py::arg("data") = py::bytes(), "A status packet (instruction 0x55).");
  m.def("parse_packet", [](const py::bytes& buffer) {
        const std::string s = from_bytes(buffer);
        std::vector<std::uint8_t> scratch(dx::kMaxPacketBytes);
        dx::Packet p;
        const dx::ParseResult r = dx::parse_packet(reinterpret_cast<const std::uint8_t*>(s.data()), s.size(),
                                                   scratch.data(), scratch.size(), &p);
        py::object instruction = py::none(), params = py::none();
        if (r.status == dx::ParseStatus::kOk) {
          instruction = py::int_(p.instruction);
          params = to_bytes(p.params, p.n_params);
        }
        return py::make_tuple(r.status, r.consumed, r.start, r.id, instruction, params);
      }, py::arg("buffer"),
      "First packet in buffer: (ParseStatus, consumed, start, id, instruction, params); instruction and params "
      "are None unless OK. Drop `consumed` bytes from the front of the buffer.");

  py::class_<dx::ControlTableEntry>(m, "ControlTableEntry", "One entry of a control table.")
      .def_readonly("name", &dx::ControlTableEntry::name)
      .def_readonly("address", &dx::ControlTableEntry::address)
      .def_readonly("size", &dx::ControlTableEntry::size)
      .def_readonly("is_signed", &dx::ControlTableEntry::is_signed)
      .def_readonly("writable", &dx::ControlTableEntry::writable)
      .def_readonly("eeprom", &dx::ControlTableEntry::eeprom)
      .def_readonly("unit", &dx::ControlTableEntry::unit)
      .def_readonly("scale", &dx::ControlTableEntry::scale)
      .def_readonly("default", &dx::ControlTableEntry::default_value)
      .def_readonly("has_range", &dx::ControlTableEntry::has_range)
      .def_readonly("min", &dx::ControlTableEntry::min)
      .def_readonly("max", &dx::ControlTableEntry::max);
  py::class_<dx::ControlTable>(m, "ControlTable", "A servo model's control table, from config/dynamixel/<model>.yaml.")
      .def_static("from_yaml", &dx::ControlTable::from_yaml_file, py::arg("path"),
                  "Load and validate; ConfigError (a ValueError) lists every problem.")
      .def_static("from_yaml_string", &dx::ControlTable::from_yaml_string, py::arg("text"),
                  py::arg("source") = "<string>", "Same as from_yaml, from YAML text.")
      .def_readonly("model", &dx::ControlTable::model)
      .def_readonly("model_number", &dx::ControlTable::model_number)
      .def_readonly("position_centre_ticks", &dx::ControlTable::position_centre_ticks)
      .def_readonly("entries", &dx::ControlTable::entries)
      .def_readonly("hardware_error_bits", &dx::ControlTable::hardware_error_bits)
      .def("find", [](const dx::ControlTable& t, const std::string& name) -> py::object {
             const auto* e = t.find(name);
             return e ? py::cast(*e) : py::none();
           }, py::arg("name"), "The entry called name, or None.")
      .def("at", &dx::ControlTable::at, py::arg("name"), "The entry called name; ConfigError when absent.")
      .def("describe_hardware_error", &dx::ControlTable::describe_hardware_error, py::arg("bits"),
           "'overload, overheating' for Hardware Error Status bits; 'none' for 0.");

  m.def("ticks_to_rad", [](std::int32_t ticks) { return dx::ticks_to_rad(ticks); }, py::arg("ticks"),
        "XH540: radians from the centre (2048), 360/4096 degrees per tick.");
  m.def("rad_to_ticks", [](double rad) { return dx::rad_to_ticks(rad); }, py::arg("rad"),
        "Nearest tick, None for NaN/inf/out of int32.");
  m.def("velocity_to_rad_s", [](std::int32_t units) { return dx::velocity_to_rad_s(units); }, py::arg("units"),
        "0.229 rpm per unit.");
  m.def("rad_s_to_velocity", [](double rad_s) { return dx::rad_s_to_velocity(rad_s); }, py::arg("rad_s"));
  m.def("current_to_amps", [](std::int16_t units) { return dx::current_to_amps(units); }, py::arg("units"),
        "2.69 mA per unit, signed.");
  m.def("amps_to_current", [](double amps) { return dx::amps_to_current(amps); }, py::arg("amps"));

  py::class_<dx::ServoBus>(m, "ServoBus", "A Dynamixel bus the driver talks to (SerialBus, FakeServoBus); abstract.");

  using Bus = dx::SerialBus;
  py::class_<Bus, dx::ServoBus>(m, "SerialBus", "ServoBus on a serial port (termios2); every call returns a Status, never raises.")
      .def(py::init([](const std::string& device, int baud_bps, bool low_latency, double latency_s,
                       double return_delay_s, double margin) {
             dx::SerialConfig c;
             c.device = device;
             c.baud_bps = baud_bps;
             c.low_latency = low_latency;
             c.timing.latency_s = latency_s;
             c.timing.return_delay_s = return_delay_s;
             c.timing.margin = margin;
             return std::make_unique<Bus>(c);
           }),
           py::arg("device"), py::arg("baud_bps") = 1000000, py::arg("low_latency") = true,
           py::arg("latency_s") = dx::BusTiming{}.latency_s, py::arg("return_delay_s") = 0.0,
           py::arg("margin") = dx::BusTiming{}.margin,
           "Opens the port; ConfigError for a bad setting, SerialError when the port cannot be opened.")
      .def("ping", [](Bus& b, std::uint8_t id) {
             std::uint16_t model = 0;
             std::uint8_t err = 0;
             dx::Status s;
             {
               py::gil_scoped_release release;
               s = b.ping(id, &model, &err);
             }
             return py::make_tuple(s, model, err);
           }, py::arg("id"), "(Status, model_number, error byte)")
      .def("read", [](Bus& b, std::uint8_t id, std::uint16_t address, std::uint16_t length) {
             std::vector<std::uint8_t> data(length);
             std::uint8_t err = 0;
             dx::Status s;
             {
               py::gil_scoped_release release;
               s = b.read(id, address, length, data.data(), &err);
             }
             return py::make_tuple(s, to_bytes(data.data(), data.size()), err);
           }, py::arg("id"), py::arg("address"), py::arg("length"), "(Status, data, error byte)")
      .def("write", [](Bus& b, std::uint8_t id, std::uint16_t address, const py::bytes& data) {
             const std::string d = from_bytes(data);
             std::uint8_t err = 0;
             dx::Status s;
             {
               py::gil_scoped_release release;
               s = b.write(id, address, reinterpret_cast<const std::uint8_t*>(d.data()),
                           static_cast<std::uint16_t>(d.size()), &err);
             }
             return py::make_tuple(s, err);
           }, py::arg("id"), py::arg("address"), py::arg("data"), "(Status, error byte)")
      .def("reboot", [](Bus& b, std::uint8_t id) {
             std::uint8_t err = 0;
             dx::Status s;
             {
               py::gil_scoped_release release;
               s = b.reboot(id, &err);
             }
             return py::make_tuple(s, err);
           }, py::arg("id"), "(Status, error byte)")
      .def("sync_write", [](Bus& b, std::uint16_t address, std::uint16_t length, const std::vector<std::uint8_t>& ids,
                            const py::bytes& data) {
             const std::string d = from_bytes(data);
             if (d.size() != ids.size() * length) {
               throw py::value_error("data: " + std::to_string(d.size()) + " bytes, expected len(ids) * length = " +
                                     std::to_string(ids.size() * length));
             }
             py::gil_scoped_release release;
             return b.sync_write(address, length, ids.data(), ids.size(), reinterpret_cast<const std::uint8_t*>(d.data()));
           }, py::arg("address"), py::arg("length"), py::arg("ids"), py::arg("data"),
           "Status; data holds length bytes per servo, in ids order.")
      .def("sync_read", [](Bus& b, std::uint16_t address, std::uint16_t length, const std::vector<std::uint8_t>& ids) {
             return group_read(b, address, length, ids, &Bus::sync_read);
           }, py::arg("address"), py::arg("length"), py::arg("ids"),
           "(Status, data, [(Status, error byte) per servo]); data of a servo without reply is zeros.")
      .def("fast_sync_read", [](Bus& b, std::uint16_t address, std::uint16_t length, const std::vector<std::uint8_t>& ids) {
             return group_read(b, address, length, ids, &Bus::fast_sync_read);
           }, py::arg("address"), py::arg("length"), py::arg("ids"), "Same as sync_read with FAST_SYNC_READ (0x8A).")
      .def("counters", [](const Bus& b) { return counters_dict(b.counters()); }, "Error and traffic counters (dict).")
      .def("reset_counters", &Bus::reset_counters, "Zero the counters.")
      .def("reopen", &Bus::reopen, "Reopen the port after an I/O error; SerialError on failure.")
      .def_property_readonly("low_latency_applied", [](Bus& b) { return b.port().low_latency_applied(); },
                             "False when the driver refused ASYNC_LOW_LATENCY (always on a pty).");
}

// ---------------------------------------------------------------------------------------------
// The driver's control loop (DriverController) and the in-process bus it can run on
// (FakeServoBus, submodule dynamixel): the batch simulator runs the very same controller as
// driver_node, the plant's servo states written into the fake bus and its goals read back.

double yaw_of(const Eigen::Matrix3d& r) { return std::atan2(r(1, 0), r(0, 0)); }

void bind_driver(py::module_& m) {
  py::class_<DriverConfig>(m, "DriverConfig", "Configuration of DriverController (config/driver.yaml documents every key).")
      .def(py::init([](bool fast_sync_read, int max_failed_cycles, int status_every_cycles, int return_delay_time_us,
                       const std::string& fault_action, const std::string& shutdown_action, bool torque_on_start,
                       double max_joint_velocity_rad_s, double max_frequency_hz, double max_step_s,
                       int plausible_margin_ticks, double pose_timeout_s, bool require_pose, double command_timeout_s,
                       double pose_workspace_m, double quaternion_norm_tolerance) {
             DriverConfig c;
             std::vector<std::string> errors;
             if (!parse_safe_action(fault_action, &c.fault_action))
               errors.push_back("fault_action: '" + fault_action + "', expected 'hold' or 'torque_off'");
             if (!parse_safe_action(shutdown_action, &c.shutdown_action))
               errors.push_back("shutdown_action: '" + shutdown_action + "', expected 'hold' or 'torque_off'");
             c.fast_sync_read = fast_sync_read;
             c.max_failed_cycles = max_failed_cycles;
             c.status_every_cycles = status_every_cycles;
             c.return_delay_time_us = return_delay_time_us;
             c.torque_on_start = torque_on_start;
             c.max_joint_velocity_rad_s = max_joint_velocity_rad_s;
             c.max_frequency_hz = max_frequency_hz;
             c.max_step_s = max_step_s;
             c.plausible_margin_ticks = plausible_margin_ticks;
             c.pose_timeout_s = pose_timeout_s;
             c.require_pose = require_pose;
             c.command_timeout_s = command_timeout_s;
             c.pose_workspace_m = pose_workspace_m;
             c.quaternion_norm_tolerance = quaternion_norm_tolerance;
             for (const auto& e : c.validate()) errors.push_back(e);
             if (!errors.empty()) {
               std::string what = "driver configuration:";
               for (const auto& e : errors) what += "\n  " + e;
               throw py::value_error(what);
             }
             return c;
           }),
           py::kw_only(), py::arg("fast_sync_read") = DriverConfig{}.fast_sync_read,
           py::arg("max_failed_cycles") = DriverConfig{}.max_failed_cycles,
           py::arg("status_every_cycles") = DriverConfig{}.status_every_cycles,
           py::arg("return_delay_time_us") = DriverConfig{}.return_delay_time_us,
           py::arg("fault_action") = std::string(to_string(DriverConfig{}.fault_action)),
           py::arg("shutdown_action") = std::string(to_string(DriverConfig{}.shutdown_action)),
           py::arg("torque_on_start") = DriverConfig{}.torque_on_start,
           py::arg("max_joint_velocity_rad_s") = DriverConfig{}.max_joint_velocity_rad_s,
           py::arg("max_frequency_hz") = DriverConfig{}.max_frequency_hz,
           py::arg("max_step_s") = DriverConfig{}.max_step_s,
           py::arg("plausible_margin_ticks") = DriverConfig{}.plausible_margin_ticks,
           py::arg("pose_timeout_s") = DriverConfig{}.pose_timeout_s, py::arg("require_pose") = DriverConfig{}.require_pose,
           py::arg("command_timeout_s") = DriverConfig{}.command_timeout_s,
           py::arg("pose_workspace_m") = DriverConfig{}.pose_workspace_m,
           py::arg("quaternion_norm_tolerance") = DriverConfig{}.quaternion_norm_tolerance,
           "The defaults with keyword overrides; ValueError lists every problem (DriverConfig::validate).")
      .def("validate", &DriverConfig::validate, "Every problem, naming key and value (empty when usable).")
      .def_readwrite("fast_sync_read", &DriverConfig::fast_sync_read)
      .def_readwrite("max_failed_cycles", &DriverConfig::max_failed_cycles)
      .def_readwrite("status_every_cycles", &DriverConfig::status_every_cycles)
      .def_readwrite("return_delay_time_us", &DriverConfig::return_delay_time_us)
      .def_property_readonly("fault_action", [](const DriverConfig& c) { return std::string(to_string(c.fault_action)); },
                             "'hold' or 'torque_off'")
      .def_property_readonly("shutdown_action",
                             [](const DriverConfig& c) { return std::string(to_string(c.shutdown_action)); },
                             "'hold' or 'torque_off'")
      .def_readwrite("torque_on_start", &DriverConfig::torque_on_start)
      .def_readwrite("max_joint_velocity_rad_s", &DriverConfig::max_joint_velocity_rad_s)
      .def_readwrite("max_frequency_hz", &DriverConfig::max_frequency_hz)
      .def_readwrite("max_step_s", &DriverConfig::max_step_s)
      .def_readwrite("plausible_margin_ticks", &DriverConfig::plausible_margin_ticks)
      .def_readwrite("pose_timeout_s", &DriverConfig::pose_timeout_s)
      .def_readwrite("require_pose", &DriverConfig::require_pose)
      .def_readwrite("command_timeout_s", &DriverConfig::command_timeout_s)
      .def_readwrite("pose_workspace_m", &DriverConfig::pose_workspace_m)
      .def_readwrite("quaternion_norm_tolerance", &DriverConfig::quaternion_norm_tolerance);

  py::class_<DriverController>(
      m, "DriverController",
      "The driver's control loop (src/core/driver_controller.cpp), the one driver_node runs: gait commands, CPG + "
      "steering, stale-pose gating, slew limit, joint limits, faults, kinematics. Call start(), then update() at "
      "the loop's rate; everything from one thread.")
      .def(py::init<const RobotModel&, const GaitLibrary&, const dx::ControlTable&, dx::ServoBus&, const DriverConfig&>(),
           py::arg("model"), py::arg("gaits"), py::arg("table"), py::arg("bus"), py::arg("config"),
           py::keep_alive<1, 5>(),
           "Checks everything (ConfigError lists every problem); keeps the bus alive as long as the controller.")
      .def("start", &DriverController::start, py::arg("t_s"),
           "Talks to every servo (model, mode, limits, errors, position); torque on and holding "
           "(torque_on_start) or stopped; ConfigError lists every servo that fails.")
      .def("update", &DriverController::update, py::arg("t_s"), py::arg("dt_s"),
           "One cycle: read the servos, gait, CPG, goals, write, kinematics. False when the cycle failed.")
      .def("shutdown", &DriverController::shutdown, "Leaves the servos as shutdown_action says; False when the bus failed.")
      .def(
          "command_gait",
          [](DriverController& d, const std::string& gait, const std::vector<double>& amplitude,
             const std::vector<double>& omega, const std::vector<double>& phase, const std::vector<double>& bias,
             bool steer, double delta_rad) {
            GaitCommandRequest r;
            r.gait = gait;
            r.amplitude = amplitude;
            r.omega = omega;
            r.phase = phase;
            r.bias = bias;
            r.steer = steer;
            r.delta_rad = delta_rad;
            return d.command_gait(r);
          },
          py::arg("gait") = "", py::arg("amplitude") = std::vector<double>{}, py::arg("omega") = std::vector<double>{},
          py::arg("phase") = std::vector<double>{}, py::arg("bias") = std::vector<double>{}, py::arg("steer") = false,
          py::arg("delta_rad") = 0.0,
          "A gait command (msg/GaitCommand.msg), taken at the next update(). '' when accepted, else every reason.")
      .def(
          "set_base_pose",
          [](DriverController& d, double t_s, const Eigen::Vector3d& position, const Eigen::Vector4d& orientation) {
            return d.set_base_pose(t_s, position,
                                   Eigen::Quaterniond(orientation(3), orientation(0), orientation(1), orientation(2)));
          },
          py::arg("t_s"), py::arg("position"), py::arg("orientation"),
          "base_link pose at t_s (the loop's clock), orientation as (x, y, z, w). False (ignored, counted) when not "
          "finite, outside pose_workspace_m or not a unit quaternion within quaternion_norm_tolerance.")
      .def_property_readonly("state", [](const DriverController& d) { return std::string(to_string(d.state())); },
                             "'stopped', 'holding', 'running' or 'fault'")
      .def_property_readonly("fault_reason", [](const DriverController& d) { return std::string(d.fault_reason()); },
                             "the active fault ('' when none)")
      .def_property_readonly("commanded_gait", &DriverController::commanded_gait, "the gait of the last accepted command")
      .def_property_readonly("hold_reason",
                             [](const DriverController& d) {
                               return std::string(d.state() == DriverState::kHolding ? to_string(d.hold_reason()) : "");
                             },
                             "why the driver holds ('' unless holding), e.g. the command lifetime expired")
      .def_property_readonly("last_refusal", &DriverController::last_refusal, "why the last refused command was refused")
      .def_property_readonly("commands_accepted", &DriverController::commands_accepted)
      .def_property_readonly("commands_refused", &DriverController::commands_refused)
      .def_property_readonly("ids", &DriverController::ids, "servo IDs in joint order")
      .def_property_readonly("position_rad", [](const DriverController& d) { return Eigen::VectorXd(d.position_rad()); },
                             "measured joint angles")
      .def_property_readonly("goal_rad", [](const DriverController& d) { return Eigen::VectorXd(d.goal_rad()); },
                             "joint goals of the last cycle (before rounding to ticks)")
      .def_property_readonly("pose_fresh", &DriverController::pose_fresh, "the base pose is younger than pose_timeout_s")
      .def_property_readonly("locomotion_gated", &DriverController::locomotion_gated,
                             "running, but held for a stale base pose")
      .def_property_readonly("cpg", &DriverController::cpg, py::return_value_policy::reference_internal,
                             "the loop's CPG (read only)")
      .def_property_readonly("kinematics", &DriverController::kinematics, py::return_value_policy::reference_internal,
                             "KinematicState of the last cycle (base pose of the latest sample, measured joints)")
      .def_property_readonly("com", [](const DriverController& d) { return Eigen::Vector3d(d.kinematics().com); },
                             "(3,) centre of mass of the last cycle, world frame")
      .def_property_readonly("vc_rotation",
                             [](const DriverController& d) { return Eigen::Matrix3d(d.kinematics().vc_rotation); },
                             "(3, 3) virtual chassis of the last cycle")
      .def_property_readonly("com_yaw", [](const DriverController& d) { return yaw_of(d.kinematics().vc_rotation); },
                             "yaw of the virtual chassis (rad), as com_pose carries it")
      .def("ticks_to_joint_rad", &DriverController::ticks_to_joint_rad, py::arg("joint"), py::arg("ticks"),
           "Servo ticks -> joint angle (direction, zero offset).")
      .def(
          "joint_rad_to_ticks",
          [](const DriverController& d, int joint, double rad) -> py::object {
            std::int32_t t = 0;
            return d.joint_rad_to_ticks(joint, rad, &t) ? py::object(py::int_(t)) : py::object(py::none());
          },
          py::arg("joint"), py::arg("rad"), "Joint angle -> servo ticks (no clamping); None when not representable.");
}

}  // namespace

void expose_servo_model(py::module_& m);

PYBIND11_MODULE(_core, m) {
  m.doc() = "snake_autonomy C++ core: robot model, CPG, gaits, steering, kinematics, Dynamixel Protocol 2.0, the driver's loop";
  py::register_exception<ConfigError>(m, "ConfigError", PyExc_ValueError);
  bind_robot_model(m);
  bind_cpg(m);
  bind_gaits(m);
  bind_kinematics(m);
  bind_dynamixel(m);
  expose_servo_model(m);  // src/bindings/expose_servo_model.cpp
  bind_driver(m);
}
