// FakeServoBus (submodule dynamixel): the in-process bus of the tests and the batch simulator.
#include "bindings.hpp"

#include "snake_autonomy/dynamixel/fake_servo_bus.hpp"

namespace snake_autonomy::bindings {

using namespace snake_autonomy::core;
namespace dx = snake_autonomy::dynamixel;

void expose_fake_servo_bus(py::module_& m) {
  py::module_ dm = m.attr("dynamixel").cast<py::module_>();
  using Fake = dx::FakeServoBus;
  py::class_<Fake, dx::ServoBus>(dm, "FakeServoBus",
                                 "In-process ServoBus: control-table memory per servo, faults on command (tests, "
                                 "the batch simulator).")
      .def(py::init<const dx::ControlTable&, const std::vector<std::uint8_t>&>(), py::arg("table"), py::arg("ids"),
           "Memory from the table's defaults; ConfigError for an ID outside 0..252 or a repeated one.")
      .def("get", &Fake::get, py::arg("id"), py::arg("entry"),
           "Value of a control-table entry (e.g. 'goal_position'); ConfigError for an unknown ID or entry.")
      .def("set", &Fake::set, py::arg("id"), py::arg("entry"), py::arg("value"),
           "Writes an entry's memory, no checks (e.g. 'present_position' ticks from a plant).")
      .def("set_follow_goal", &Fake::set_follow_goal, py::arg("follow"),
           "True (default): a goal position becomes the present position at once; False: present values are the caller's.")
      .def("set_dead", &Fake::set_dead, py::arg("id"), py::arg("dead"), "The servo never answers (TIMEOUT).")
      .def("inject_timeouts", &Fake::inject_timeouts, py::arg("id"), py::arg("count"),
           "The next `count` replies of the servo time out.")
      .def("inject_crc_errors", &Fake::inject_crc_errors, py::arg("id"), py::arg("count"),
           "The next `count` replies of the servo have a bad CRC.")
      .def("set_garbage", &Fake::set_garbage, py::arg("id"), py::arg("garbage"),
           "Replies carry garbage bytes with a valid CRC.")
      .def("set_hardware_error", &Fake::set_hardware_error, py::arg("id"), py::arg("bits"),
           "Hardware Error Status bits: alert bit in every reply, torque off (REBOOT clears it).")
      .def("set_bus_down", &Fake::set_bus_down, py::arg("down"), "Every call returns IO_ERROR (the port is gone).")
      .def("clear_faults", &Fake::clear_faults, "Removes every injected fault.")
      .def("counters", [](const Fake& b) { return counters_dict(b.counters()); }, "Error and traffic counters (dict).")
      .def("reset_counters", &Fake::reset_counters, "Zero the counters.")
      .def_property_readonly("sync_writes", &Fake::sync_writes, "SYNC_WRITEs received")
      .def_property_readonly("sync_reads", &Fake::sync_reads, "SYNC_READs received")
      .def("goal_writes", &Fake::goal_writes, py::arg("id"), "Goal positions the servo accepted.")
      .def_property_readonly("refused_writes", &Fake::refused_writes, "writes refused (range, limits, EEPROM)");
}

}  // namespace snake_autonomy::bindings
