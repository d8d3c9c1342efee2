// snake_autonomy._core: the C++ core for Python (tools, tests, the simulator). One module init; each
// bound area lives in its own src/bindings/expose_<area>.cpp (declared in bindings.hpp).
#include "bindings.hpp"

#include "snake_autonomy/core/robot_model.hpp"

namespace py = pybind11;
namespace sb = snake_autonomy::bindings;

PYBIND11_MODULE(_core, m) {
  m.doc() =
      "snake_autonomy C++ core: robot model, CPG, gaits, steering, kinematics, Dynamixel Protocol 2.0, the driver's "
      "loop";
  py::register_exception<snake_autonomy::core::ConfigError>(m, "ConfigError", PyExc_ValueError);
  sb::expose_robot_model(m);
  sb::expose_cpg(m);
  sb::expose_gaits(m);
  sb::expose_kinematics(m);
  sb::expose_dynamixel(m);
  sb::expose_servo_model(m);     // the one simulated servo chain
  sb::expose_fake_servo_bus(m);
  sb::expose_transmission(m);
  sb::expose_driver(m);
}
