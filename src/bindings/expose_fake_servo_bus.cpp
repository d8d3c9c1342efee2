// FakeServoBus (submodule dynamixel): the in-process bus of the tests and the batch simulator,
// Protocol2Bus over a loopback into SimulatedServos (its servos: expose_servo_model.cpp).
#include "bindings.hpp"

#include "snake_autonomy/dynamixel/fake_servo_bus.hpp"

namespace snake_autonomy::bindings {

namespace dx = snake_autonomy::dynamixel;

void expose_fake_servo_bus(py::module_& top) {
  py::module_ m = top.attr("dynamixel").cast<py::module_>();
  using Fake = dx::FakeServoBus;
  py::class_<Fake, dx::ServoBus>(m, "FakeServoBus",
                                 "In-process ServoBus: Protocol2Bus over a loopback into SimulatedServos (tests, the "
                                 "batch simulator).")
      .def(py::init<const dx::ControlTable&, const std::vector<std::uint8_t>&>(), py::arg("table"), py::arg("ids"),
           "Memory from the table's defaults; ConfigError for an ID outside 0..252 or a repeated one.")
      .def_property_readonly("servos", py::overload_cast<>(&Fake::servos), py::return_value_policy::reference_internal,
                             "The simulated servos: memory, faults, stats.")
      .def("set_follow_goal", &Fake::set_follow_goal, py::arg("follow"),
           "True (default): a goal position becomes the present position at once; False: present values are the "
           "caller's.")
      .def("set_bus_down", &Fake::set_bus_down, py::arg("down"), "Every call returns IO_ERROR (the port is gone).")
      .def("clear_faults", &Fake::clear_faults, "Removes every fault of the servos; the bus back up.")
      .def("reset_counters", &Fake::reset_counters, "Zero the counters.")
      .def("counters", [](const Fake& b) { return counters_dict(b.counters()); }, "Error and traffic counters (dict).");
}

}  // namespace snake_autonomy::bindings
