// Dynamixel Protocol 2.0 (submodule snake_autonomy._core.dynamixel): the codec the mocked bus
// uses, the control table, conversions, and SerialBus (the GIL is released while it waits).
#include "bindings.hpp"

#include "snake_autonomy/dynamixel/control_table.hpp"
#include "snake_autonomy/dynamixel/conversions.hpp"
#include "snake_autonomy/dynamixel/protocol.hpp"
#include "snake_autonomy/dynamixel/serial_bus.hpp"

namespace snake_autonomy::bindings {

using namespace snake_autonomy::core;
namespace dx = snake_autonomy::dynamixel;

namespace {

// sync_read / fast_sync_read for Python: (status, data, [(status, error) per servo]).
template <typename Fn>
py::tuple group_read(dx::SerialBus& bus, std::uint16_t address, std::uint16_t length,
                     const std::vector<std::uint8_t>& ids, Fn fn) {
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

}  // namespace

void expose_dynamixel(py::module_& parent) {
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

  m.def(
      "crc16",
      [](const py::bytes& data, std::uint16_t crc) {
        const std::string s = from_bytes(data);
        return dx::crc16(reinterpret_cast<const std::uint8_t*>(s.data()), s.size(), crc);
      },
      py::arg("data"), py::arg("crc") = 0, "CRC-16 of Protocol 2.0 (0x8005, init 0); pass crc to continue.");
  m.def(
      "stuff",
      [](const py::bytes& data) {
        const std::string s = from_bytes(data);
        std::vector<std::uint8_t> out(s.size() * 2 + 1);
        const std::size_t n =
            dx::stuff(reinterpret_cast<const std::uint8_t*>(s.data()), s.size(), out.data(), out.size());
        return to_bytes(out.data(), n);
      },
      py::arg("data"), "Byte stuffing of an INST+PARAM region: FF FF FD gets an extra FD.");
  m.def(
      "unstuff",
      [](const py::bytes& data) {
        const std::string s = from_bytes(data);
        std::vector<std::uint8_t> out(s.size() + 1);
        const std::size_t n =
            dx::unstuff(reinterpret_cast<const std::uint8_t*>(s.data()), s.size(), out.data(), out.size());
        if (n == dx::kBadStuffing) throw py::value_error("data: FF FF FD not followed by its stuffed FD");
        return to_bytes(out.data(), n);
      },
      py::arg("data"), "Removes the FD that follows FF FF FD; ValueError when one is missing.");
  m.def(
      "encode_packet",
      [](std::uint8_t id, std::uint8_t instruction, const py::bytes& params) {
        const std::string s = from_bytes(params);
        std::vector<std::uint8_t> out(dx::kMaxPacketBytes);
        const std::size_t n = dx::encode_packet(id, instruction, reinterpret_cast<const std::uint8_t*>(s.data()),
                                                s.size(), out.data(), out.size());
        if (n == 0) throw py::value_error("params: " + std::to_string(s.size()) + " bytes do not fit one packet");
        return to_bytes(out.data(), n);
      },
      py::arg("id"), py::arg("instruction"), py::arg("params") = py::bytes(), "A whole packet, stuffed, with its CRC.");
  m.def(
      "encode_status",
      [](std::uint8_t id, std::uint8_t error, const py::bytes& data) {
        const std::string s = from_bytes(data);
        std::vector<std::uint8_t> out(dx::kMaxPacketBytes);
        const std::size_t n = dx::encode_status(id, error, reinterpret_cast<const std::uint8_t*>(s.data()), s.size(),
                                                out.data(), out.size());
        if (n == 0) throw py::value_error("data: " + std::to_string(s.size()) + " bytes do not fit one packet");
        return to_bytes(out.data(), n);
      },
      py::arg("id"), py::arg("error"), py::arg("data") = py::bytes(), "A status packet (instruction 0x55).");
  m.def(
      "parse_packet",
      [](const py::bytes& buffer) {
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
      },
      py::arg("buffer"),
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
      .def(
          "find",
          [](const dx::ControlTable& t, const std::string& name) -> py::object {
            const auto* e = t.find(name);
            return e ? py::cast(*e) : py::none();
          },
          py::arg("name"), "The entry called name, or None.")
      .def("at", &dx::ControlTable::at, py::arg("name"), "The entry called name; ConfigError when absent.")
      .def("describe_hardware_error", &dx::ControlTable::describe_hardware_error, py::arg("bits"),
           "'overload, overheating' for Hardware Error Status bits; 'none' for 0.");

  m.def(
      "ticks_to_rad", [](std::int32_t ticks) { return dx::ticks_to_rad(ticks); }, py::arg("ticks"),
      "XH540: radians from the centre (2048), 360/4096 degrees per tick.");
  m.def(
      "rad_to_ticks", [](double rad) { return dx::rad_to_ticks(rad); }, py::arg("rad"),
      "Nearest tick, None for NaN/inf/out of int32.");
  m.def(
      "velocity_to_rad_s", [](std::int32_t units) { return dx::velocity_to_rad_s(units); }, py::arg("units"),
      "0.229 rpm per unit.");
  m.def("rad_s_to_velocity", [](double rad_s) { return dx::rad_s_to_velocity(rad_s); }, py::arg("rad_s"));
  m.def(
      "current_to_amps", [](std::int16_t units) { return dx::current_to_amps(units); }, py::arg("units"),
      "2.69 mA per unit, signed.");
  m.def("amps_to_current", [](double amps) { return dx::amps_to_current(amps); }, py::arg("amps"));

  py::class_<dx::ServoBus>(m, "ServoBus", "A Dynamixel bus the driver talks to (SerialBus, FakeServoBus); abstract.");

  using Bus = dx::SerialBus;
  py::class_<Bus, dx::ServoBus>(m, "SerialBus",
                                "ServoBus on a serial port (termios2); every call returns a Status, never raises.")
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
      .def(
          "ping",
          [](Bus& b, std::uint8_t id) {
            std::uint16_t model = 0;
            std::uint8_t err = 0;
            dx::Status s;
            {
              py::gil_scoped_release release;
              s = b.ping(id, &model, &err);
            }
            return py::make_tuple(s, model, err);
          },
          py::arg("id"), "(Status, model_number, error byte)")
      .def(
          "read",
          [](Bus& b, std::uint8_t id, std::uint16_t address, std::uint16_t length) {
            std::vector<std::uint8_t> data(length);
            std::uint8_t err = 0;
            dx::Status s;
            {
              py::gil_scoped_release release;
              s = b.read(id, address, length, data.data(), &err);
            }
            return py::make_tuple(s, to_bytes(data.data(), data.size()), err);
          },
          py::arg("id"), py::arg("address"), py::arg("length"), "(Status, data, error byte)")
      .def(
          "write",
          [](Bus& b, std::uint8_t id, std::uint16_t address, const py::bytes& data) {
            const std::string d = from_bytes(data);
            std::uint8_t err = 0;
            dx::Status s;
            {
              py::gil_scoped_release release;
              s = b.write(id, address, reinterpret_cast<const std::uint8_t*>(d.data()),
                          static_cast<std::uint16_t>(d.size()), &err);
            }
            return py::make_tuple(s, err);
          },
          py::arg("id"), py::arg("address"), py::arg("data"), "(Status, error byte)")
      .def(
          "reboot",
          [](Bus& b, std::uint8_t id) {
            std::uint8_t err = 0;
            dx::Status s;
            {
              py::gil_scoped_release release;
              s = b.reboot(id, &err);
            }
            return py::make_tuple(s, err);
          },
          py::arg("id"), "(Status, error byte)")
      .def(
          "sync_write",
          [](Bus& b, std::uint16_t address, std::uint16_t length, const std::vector<std::uint8_t>& ids,
             const py::bytes& data) {
            const std::string d = from_bytes(data);
            if (d.size() != ids.size() * length) {
              throw py::value_error("data: " + std::to_string(d.size()) +
                                    " bytes, expected len(ids) * length = " + std::to_string(ids.size() * length));
            }
            py::gil_scoped_release release;
            return b.sync_write(address, length, ids.data(), ids.size(),
                                reinterpret_cast<const std::uint8_t*>(d.data()));
          },
          py::arg("address"), py::arg("length"), py::arg("ids"), py::arg("data"),
          "Status; data holds length bytes per servo, in ids order.")
      .def(
          "sync_read",
          [](Bus& b, std::uint16_t address, std::uint16_t length, const std::vector<std::uint8_t>& ids) {
            return group_read(b, address, length, ids, &Bus::sync_read);
          },
          py::arg("address"), py::arg("length"), py::arg("ids"),
          "(Status, data, [(Status, error byte) per servo]); data of a servo without reply is zeros.")
      .def(
          "fast_sync_read",
          [](Bus& b, std::uint16_t address, std::uint16_t length, const std::vector<std::uint8_t>& ids) {
            return group_read(b, address, length, ids, &Bus::fast_sync_read);
          },
          py::arg("address"), py::arg("length"), py::arg("ids"), "Same as sync_read with FAST_SYNC_READ (0x8A).")
      .def(
          "counters", [](const Bus& b) { return counters_dict(b.counters()); }, "Error and traffic counters (dict).")
      .def("reset_counters", &Bus::reset_counters, "Zero the counters.")
      .def("reopen", &Bus::reopen, "Reopen the port after an I/O error; SerialError on failure.")
      .def_property_readonly(
          "low_latency_applied", [](Bus& b) { return b.port().low_latency_applied(); },
          "False when the driver refused ASYNC_LOW_LATENCY (always on a pty).");
}

}  // namespace snake_autonomy::bindings
