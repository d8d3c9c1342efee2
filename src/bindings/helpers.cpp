// Conversions shared by the expose_*.cpp files.
#include "bindings.hpp"

#include "snake_autonomy/dynamixel/servo_bus.hpp"

namespace snake_autonomy::bindings {

namespace dx = snake_autonomy::dynamixel;

Eigen::VectorXd to_vector(const std::vector<double>& v) {
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

Eigen::VectorXd checked_vector(const py::handle& obj, Eigen::Index n, const char* name) {
  py::array_t<double, py::array::c_style | py::array::forcecast> arr;
  try {
    arr = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(obj);
  } catch (const py::error_already_set&) {
    arr = py::array_t<double, py::array::c_style | py::array::forcecast>();
  }
  if (!arr) throw py::value_error(std::string(name) + ": expected an array of numbers");
  if (arr.ndim() != 1 || arr.shape(0) != n)
    throw py::value_error(
        std::string(name) + ": expected shape (" + std::to_string(n) + ",), got " +
        std::string(py::str(py::tuple(py::cast(std::vector<py::ssize_t>(arr.shape(), arr.shape() + arr.ndim()))))));
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
  d["drains"] = c.drains;
  d["late_bytes"] = c.late_bytes;
  d["verify_mismatches"] = c.verify_mismatches;
  return d;
}

}  // namespace snake_autonomy::bindings
