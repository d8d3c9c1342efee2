// The driver's control loop (DriverController) and its configuration (DriverConfig): the batch
// simulator runs the very same controller as driver_node, on a FakeServoBus.
#include "bindings.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <optional>

#include "snake_autonomy/core/config_reader.hpp"

#include "snake_autonomy/driver/driver_config.hpp"
#include "snake_autonomy/driver/driver_controller.hpp"
#include "snake_autonomy/driver/gait_command.hpp"
#include "snake_autonomy/dynamixel/control_table.hpp"
#include "snake_autonomy/dynamixel/servo_bus.hpp"

namespace snake_autonomy::bindings {

using namespace snake_autonomy::core;
using namespace snake_autonomy::driver;
namespace dx = snake_autonomy::dynamixel;

namespace {

double yaw_of(const Eigen::Matrix3d& r) { return std::atan2(r(1, 0), r(0, 0)); }

// A trajectory's progress or final status as a dict (the fields of driver/trajectory_status).
py::dict progress_dict(const driver::TrajectoryProgress& p) {
  py::dict out;
  out["id"] = std::string(p.id.data());
  out["sequence"] = p.sequence;
  out["phase"] = std::string(driver::to_string(p.phase));
  out["abort"] = std::string(driver::to_string(p.abort));
  out["reason"] = std::string(p.reason.data());
  out["point_reached"] = p.point_reached;
  out["num_points"] = p.num_points;
  out["time_s"] = p.time_s;
  out["duration_s"] = p.duration_s;
  out["superseded_by"] = std::string(p.superseded_by.data());
  out["superseded_by_sequence"] = p.superseded_by_sequence;
  return out;
}

std::string join_keys() {
  std::string out;
  for (const auto& k : DriverConfig::keys()) out += (out.empty() ? "" : ", ") + k;
  return out;
}

}  // namespace

void expose_driver(py::module_& m) {
  py::class_<DriverConfig>(m, "DriverConfig",
                           "Configuration of DriverController (config/driver.yaml documents every key).")
      .def(py::init([](const py::kwargs& kwargs) {
             // The keyword arguments as a YAML mapping, read by the one loader (DriverConfig::apply_yaml).
             YAML::Node doc(YAML::NodeType::Map);
             std::vector<std::string> errors;
             const auto& known = DriverConfig::keys();
             for (const auto& item : kwargs) {
               const std::string key = py::str(item.first);
               const py::handle v = item.second;
               if (std::find(known.begin(), known.end(), key) == known.end())
                 errors.push_back(key + ": unknown key (known: " + join_keys() + ")");
               else if (py::isinstance<py::bool_>(v)) doc[key] = v.cast<bool>();
               else if (py::isinstance<py::int_>(v)) doc[key] = v.cast<long long>();
               else if (py::isinstance<py::float_>(v)) doc[key] = v.cast<double>();
               else doc[key] = std::string(py::str(v));
             }
             DriverConfig c;
             c.apply_yaml(doc, &errors);
             for (const auto& e : c.validate()) errors.push_back(e);
             throw_if_errors(errors, "DriverConfig", "driver configuration");
             return c;
           }),
           "The defaults with keyword overrides (the keys of config/driver.yaml); ConfigError (a ValueError) "
           "lists every problem.")
      .def_static("from_yaml", &DriverConfig::from_yaml_file, py::arg("path"),
                  "The controller's keys of a driver YAML (config/driver.yaml), the node's own ignored; "
                  "ConfigError lists every problem.")
      .def_static("from_yaml_string", &DriverConfig::from_yaml_string, py::arg("text"), py::arg("source") = "<string>",
                  "Same as from_yaml, from YAML text.")
      .def_property_readonly_static(
          "keys", [](const py::object&) { return DriverConfig::keys(); }, "the YAML keys, the field names")
      .def("validate", &DriverConfig::validate, "Every problem, naming key and value (empty when usable).")
      .def_readwrite("fast_sync_read", &DriverConfig::fast_sync_read)
      .def_readwrite("max_failed_cycles", &DriverConfig::max_failed_cycles)
      .def_readwrite("status_every_cycles", &DriverConfig::status_every_cycles)
      .def_readwrite("return_delay_time_us", &DriverConfig::return_delay_time_us)
      .def_property_readonly(
          "fault_action", [](const DriverConfig& c) { return std::string(to_string(c.fault_action)); },
          "'hold' or 'torque_off'")
      .def_property_readonly(
          "shutdown_action", [](const DriverConfig& c) { return std::string(to_string(c.shutdown_action)); },
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
      .def_readwrite("quaternion_norm_tolerance", &DriverConfig::quaternion_norm_tolerance)
      .def_readwrite("max_trajectory_points", &DriverConfig::max_trajectory_points)
      .def_readwrite("max_trajectory_duration_s", &DriverConfig::max_trajectory_duration_s);

  py::class_<DriverController>(
      m, "DriverController",
      "The driver's control loop (src/driver/driver_controller.cpp), the one driver_node runs: gait commands, CPG + "
      "steering, stale-pose gating, slew limit, joint limits, faults, kinematics. Call start(), then update() at "
      "the loop's rate; everything from one thread.")
      .def(py::init<const RobotModel&, const GaitLibrary&, const dx::ControlTable&, dx::ServoBus&,
                    const DriverConfig&>(),
           py::arg("model"), py::arg("gaits"), py::arg("table"), py::arg("bus"), py::arg("config"),
           py::keep_alive<1, 5>(),
           "Checks everything (ConfigError lists every problem); keeps the bus alive as long as the controller.")
      .def("start", &DriverController::start, py::arg("t_s"),
           "Talks to every servo (model, mode, limits, errors, position); torque on and holding "
           "(torque_on_start) or stopped; ConfigError lists every servo that fails.")
      .def("update", &DriverController::update, py::arg("t_s"), py::arg("dt_s"),
           "One cycle: read the servos, gait, CPG, goals, write, kinematics. False when the cycle failed.")
      .def("shutdown", &DriverController::shutdown,
           "Leaves the servos as shutdown_action says; False when the bus failed.")
      .def(
          "command_gait",
          [](DriverController& d, const std::string& gait, const std::vector<double>& amplitude,
             const std::vector<double>& omega, const std::vector<double>& phase, const std::vector<double>& bias,
             bool steer, double delta_rad, bool curve, double kappa_per_m) {
            GaitCommandRequest r;
            r.gait = gait;
            r.amplitude = amplitude;
            r.omega = omega;
            r.phase = phase;
            r.bias = bias;
            r.steer = steer;
            r.delta_rad = delta_rad;
            r.curve = curve;
            r.kappa_per_m = kappa_per_m;
            return d.command_gait(r);
          },
          py::arg("gait") = "", py::arg("amplitude") = std::vector<double>{}, py::arg("omega") = std::vector<double>{},
          py::arg("phase") = std::vector<double>{}, py::arg("bias") = std::vector<double>{}, py::arg("steer") = false,
          py::arg("delta_rad") = 0.0, py::arg("curve") = false, py::arg("kappa_per_m") = 0.0,
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
      .def(
          "command_trajectory",
          [](DriverController& d, const std::vector<std::string>& joint_names, const std::vector<double>& times_s,
             const Eigen::MatrixXd& positions_rad, const std::optional<Eigen::MatrixXd>& velocities_rad_s,
             const std::string& id) {
            if (positions_rad.rows() != static_cast<Eigen::Index>(times_s.size()) ||
                (velocities_rad_s && (velocities_rad_s->rows() != positions_rad.rows() ||
                                      velocities_rad_s->cols() != positions_rad.cols())))
              throw py::value_error(
                  "command_trajectory: positions_rad must be (len(times_s), joints) and "
                  "velocities_rad_s the same shape");
            driver::JointTrajectoryRequest r;
            r.id = id;
            r.joint_names = joint_names;
            r.points.resize(times_s.size());
            for (std::size_t k = 0; k < times_s.size(); ++k) {
              auto& p = r.points[k];
              p.time_from_start_s = times_s[k];
              const auto row = static_cast<Eigen::Index>(k);
              for (Eigen::Index c = 0; c < positions_rad.cols(); ++c) p.positions_rad.push_back(positions_rad(row, c));
              if (velocities_rad_s)
                for (Eigen::Index c = 0; c < velocities_rad_s->cols(); ++c)
                  p.velocities_rad_s.push_back((*velocities_rad_s)(row, c));
            }
            return d.command_trajectory(r);
          },
          py::arg("joint_names"), py::arg("times_s"), py::arg("positions_rad"),
          py::arg("velocities_rad_s") = py::none(), py::arg("id") = "",
          "A joint trajectory (driver/joint_trajectory): names joint_1 .. joint_N in any order, times_s (P,) "
          "time_from_start, positions_rad (P, len(joint_names)), velocities_rad_s the same shape or None "
          "(estimated). Taken at the next update(); '' when accepted, else every reason.")
      .def_property_readonly(
          "trajectory_progress", [](const DriverController& d) { return progress_dict(d.trajectory_progress()); },
          "the latest trajectory (as driver/trajectory_status): id, sequence, phase ('idle', 'running', 'done', "
          "'aborted'), abort, reason, point_reached, num_points, time_s, duration_s, superseded_by, "
          "superseded_by_sequence")
      .def(
          "pop_trajectory_final",
          [](DriverController& d) -> py::object {
            driver::TrajectoryProgress p;
            if (!d.pop_trajectory_final(&p)) return py::none();
            return progress_dict(p);
          },
          "the next final status of an accepted trajectory (a dict as trajectory_progress), None when none is "
          "queued: each accepted trajectory gets exactly one")
      .def_property_readonly("trajectory_finals_dropped", &DriverController::trajectory_finals_dropped,
                             "final statuses lost to a full queue (the consumer fell behind)")
      .def_property_readonly("trajectories_accepted", &DriverController::trajectories_accepted)
      .def_property_readonly("trajectories_refused", &DriverController::trajectories_refused)
      .def_property_readonly("last_trajectory_refusal", &DriverController::last_trajectory_refusal,
                             "why the last refused trajectory was refused")
      .def_property_readonly(
          "state", [](const DriverController& d) { return std::string(to_string(d.state())); },
          "'stopped', 'holding', 'running' or 'fault'")
      .def_property_readonly(
          "fault_reason", [](const DriverController& d) { return std::string(d.fault_reason()); },
          "the active fault ('' when none)")
      .def_property_readonly("commanded_gait", &DriverController::commanded_gait,
                             "the gait of the last accepted command")
      .def_property_readonly(
          "hold_reason",
          [](const DriverController& d) {
            return std::string(d.state() == DriverState::kHolding ? to_string(d.hold_reason()) : "");
          },
          "why the driver holds ('' unless holding), e.g. the command lifetime expired")
      .def_property_readonly("last_refusal", &DriverController::last_refusal,
                             "why the last refused command was refused")
      .def_property_readonly("commands_accepted", &DriverController::commands_accepted)
      .def_property_readonly("commands_refused", &DriverController::commands_refused)
      .def_property_readonly("ids", &DriverController::ids, "servo IDs in joint order")
      .def_property_readonly(
          "position_rad", [](const DriverController& d) { return Eigen::VectorXd(d.position_rad()); },
          "measured joint angles")
      .def_property_readonly(
          "goal_rad", [](const DriverController& d) { return Eigen::VectorXd(d.goal_rad()); },
          "joint goals of the last cycle (before rounding to ticks)")
      .def_property_readonly("pose_fresh", &DriverController::pose_fresh,
                             "the base pose is younger than pose_timeout_s")
      .def_property_readonly("locomotion_gated", &DriverController::locomotion_gated,
                             "running, but held for a stale base pose")
      .def_property_readonly("cpg", &DriverController::cpg, py::return_value_policy::reference_internal,
                             "the loop's CPG (read only)")
      .def_property_readonly("kinematics", &DriverController::kinematics, py::return_value_policy::reference_internal,
                             "KinematicState of the last cycle (base pose of the latest sample, measured joints)")
      .def_property_readonly(
          "com", [](const DriverController& d) { return Eigen::Vector3d(d.kinematics().com); },
          "(3,) centre of mass of the last cycle, world frame")
      .def_property_readonly(
          "vc_rotation", [](const DriverController& d) { return Eigen::Matrix3d(d.kinematics().vc_rotation); },
          "(3, 3) virtual chassis of the last cycle")
      .def_property_readonly(
          "com_yaw", [](const DriverController& d) { return yaw_of(d.kinematics().vc_rotation); },
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

}  // namespace snake_autonomy::bindings
