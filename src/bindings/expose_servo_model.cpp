// Python bindings of the one simulated servo chain (snake_autonomy._core.dynamixel):
// SimulatedServos (the servo memory and rules, fed raw Protocol 2.0 bytes by the pty mock) and
// FakeServoBus (the in-process bus over it). Names as in C++; fault kinds by their vocabulary names.
#include "bindings.hpp"

#include <memory>
#include <string>
#include <vector>

#include "snake_autonomy/dynamixel/simulated_servos.hpp"

namespace snake_autonomy::bindings {

namespace dx = snake_autonomy::dynamixel;

namespace {

// ShaftHooks implemented by a Python object with before_write(), before_read(),
// on_goal(id, ticks), on_torque(id, enabled). An exception in one of them costs that call, never the
// packet loop: it is counted and kept (errors(), last_error()) for the Python side to report.
class PyShaftHooks : public dx::ShaftHooks {
 public:
  explicit PyShaftHooks(py::object target)
      : target_(std::move(target)),
        before_write_(target_.attr("before_write")),
        before_read_(target_.attr("before_read")),
        on_goal_(target_.attr("on_goal")),
        on_torque_(target_.attr("on_torque")) {}
  void before_write(dx::SimulatedServos&) noexcept override {
    call("before_write", [&] { before_write_(); });
  }
  void before_read(dx::SimulatedServos&) noexcept override {
    call("before_read", [&] { before_read_(); });
  }
  void on_goal(std::uint8_t id, std::int32_t ticks) noexcept override {
    call("on_goal", [&] { on_goal_(id, ticks); });
  }
  void on_torque(std::uint8_t id, bool on) noexcept override {
    call("on_torque", [&] { on_torque_(id, on); });
  }
  std::uint64_t errors() const noexcept { return errors_; }
  const std::string& last_error() const noexcept { return last_error_; }

 private:
  template <typename F>
  void call(const char* hook, F&& f) noexcept {
    try {
      f();
    } catch (py::error_already_set& e) {
      ++errors_;
      last_error_ = std::string(hook) + ": " + e.what();
    } catch (std::exception& e) {
      ++errors_;
      last_error_ = std::string(hook) + ": " + e.what();
    } catch (...) {
      ++errors_;
      last_error_ = std::string(hook) + ": unknown exception";
    }
  }
  py::object target_, before_write_, before_read_, on_goal_, on_torque_;
  std::uint64_t errors_ = 0;
  std::string last_error_;
};

// SimulatedServos as Python holds it: the model plus the Python hooks it may call.
struct PySimulatedServos {
  PySimulatedServos(const dx::ControlTable& table, const std::vector<std::uint8_t>& ids) : model(table, ids) {}
  dx::SimulatedServos model;
  std::unique_ptr<PyShaftHooks> hooks;
};

dx::ReplyFault fault_kind(const std::string& kind) {
  dx::ReplyFault k{};
  if (!dx::reply_fault_from_string(kind, &k)) {
    std::string names;
    for (std::size_t i = 0; i < dx::kNumReplyFaults; ++i) {
      names += std::string(i ? ", " : "") + dx::to_string(static_cast<dx::ReplyFault>(i));
    }
    throw py::value_error("kind: '" + kind + "' is not one of " + names);
  }
  return k;
}

py::dict stats_dict(const dx::SimulatedServos& s) {
  const auto& t = s.stats();
  py::dict d, inst;
  d["packets"] = t.packets;
  d["bad_packets"] = t.bad_packets;
  d["dropped"] = t.dropped;
  d["bytes_received"] = t.bytes_received;
  d["bytes_sent"] = t.bytes_sent;
  d["replies"] = t.replies;
  d["replies_damaged"] = t.replies_damaged;
  d["rejected_writes"] = t.rejected_writes;
  d["superseded"] = t.superseded;
  inst["PING"] = t.ping;
  inst["READ"] = t.read;
  inst["WRITE"] = t.write;
  inst["REBOOT"] = t.reboot;
  inst["SYNC_READ"] = t.sync_read;
  inst["SYNC_WRITE"] = t.sync_write;
  inst["FAST_SYNC_READ"] = t.fast_sync_read;
  d["instructions"] = inst;
  return d;
}

}  // namespace

void expose_servo_model(py::module_& top) {
  py::module_ m = top.attr("dynamixel").cast<py::module_>();
  py::tuple kinds(dx::kNumReplyFaults);
  for (std::size_t i = 0; i < dx::kNumReplyFaults; ++i) kinds[i] = dx::to_string(static_cast<dx::ReplyFault>(i));
  m.attr("REPLY_FAULTS") = kinds;
  py::module_ err = m.def_submodule("servo_error", "Error numbers of a status packet (bits 0-6 of the error byte)");
  err.attr("RESULT_FAIL") = dx::servo_error::kResultFail;
  err.attr("INSTRUCTION_ERROR") = dx::servo_error::kInstructionError;
  err.attr("CRC_ERROR") = dx::servo_error::kCrcError;
  err.attr("DATA_RANGE_ERROR") = dx::servo_error::kDataRangeError;
  err.attr("DATA_LENGTH_ERROR") = dx::servo_error::kDataLengthError;
  err.attr("DATA_LIMIT_ERROR") = dx::servo_error::kDataLimitError;
  err.attr("ACCESS_ERROR") = dx::servo_error::kAccessError;

  using S = PySimulatedServos;
  py::class_<S>(m, "SimulatedServos",
                "The one simulated servo chain: control-table memory per servo, the servos' rules, reply faults; "
                "fed raw Protocol 2.0 bytes (include/snake_autonomy/dynamixel/simulated_servos.hpp).")
      .def(py::init<const dx::ControlTable&, const std::vector<std::uint8_t>&>(), py::arg("table"), py::arg("ids"),
           "Memory from the table's defaults; ConfigError for an ID outside 0..252 or a repeated one.")
      .def(
          "handle",
          [](S& s, const py::bytes& data, bool latest_only) {
            const std::string_view v(data);
            const std::size_t n =
                s.model.handle(reinterpret_cast<const std::uint8_t*>(v.data()), v.size(), latest_only);
            return py::bytes(reinterpret_cast<const char*>(s.model.output()), n);
          },
          py::arg("data"), py::arg("latest_only") = false,
          "Feeds received bytes (any chunking); returns the bytes the servos send back. latest_only: only the "
          "last packet of this read is answered (the earlier ones act and count as superseded).")
      .def(
          "clear_input", [](S& s) { s.model.clear_input(); }, "Forgets a partly received packet.")
      .def(
          "pending_input",
          [](const S& s) { return py::bytes(reinterpret_cast<const char*>(s.model.input()), s.model.input_size()); },
          "The received bytes not decided yet (a packet still arriving).")
      .def(
          "inject",
          [](S& s, const std::string& kind, py::object ids, py::object count) {
            std::vector<std::uint8_t> list;
            if (!ids.is_none()) {
              for (auto h : ids) {
                const int id = h.cast<int>();
                if (id < 0 || id > 252 || !s.model.has(static_cast<std::uint8_t>(id))) {
                  throw py::value_error("ids: " + std::to_string(id) + " is not on this bus");
                }
                list.push_back(static_cast<std::uint8_t>(id));
              }
            }
            int c = -1;
            if (!count.is_none()) {
              if (!py::isinstance<py::int_>(count) || py::isinstance<py::bool_>(count) || count.cast<long long>() < 1 ||
                  count.cast<long long>() > 1000000000) {
                throw py::value_error("count: " + std::string(py::str(py::repr(count))) +
                                      " is not a positive integer or None");
              }
              c = count.cast<int>();
            }
            s.model.inject(fault_kind(kind), list, c);
          },
          py::arg("kind"), py::arg("ids") = py::none(), py::arg("count") = py::none(),
          "Damages the next `count` replies (None: until cleared) of `ids` (None: every servo); kind is one of "
          "REPLY_FAULTS.")
      .def(
          "set_silent", [](S& s, std::uint8_t id, bool silent) { s.model.set_silent(id, silent); }, py::arg("id"),
          py::arg("silent") = true, "The servo answers nothing (it still obeys what it hears).")
      .def(
          "silent", [](const S& s, std::uint8_t id) { return s.model.silent(id); }, py::arg("id"))
      .def(
          "set_hardware_error", [](S& s, std::uint8_t id, std::uint8_t bits) { s.model.set_hardware_error(id, bits); },
          py::arg("id"), py::arg("bits"), "Hardware Error Status bits: alert bit in every reply, torque off.")
      .def(
          "clear_faults", [](S& s) { s.model.clear_faults(); }, "Removes every fault, silence and hardware error.")
      .def(
          "set_follow_goal", [](S& s, bool f) { s.model.set_follow_goal(f); }, py::arg("follow"),
          "True: an accepted goal becomes the present position at once (no hooks needed).")
      .def(
          "set_hooks",
          [](S& s, py::object target) {
            if (target.is_none()) {
              s.model.set_hooks(nullptr);
              s.hooks.reset();
              return;
            }
            auto h = std::make_unique<PyShaftHooks>(target);
            s.model.set_hooks(h.get());
            s.hooks = std::move(h);
          },
          py::arg("hooks"),
          "An object with before_write(), before_read(), on_goal(id, ticks), on_torque(id, enabled): what "
          "moves the shafts; None removes it.")
      .def_property_readonly(
          "hook_errors", [](const S& s) { return s.hooks ? s.hooks->errors() : 0; },
          "Exceptions raised by the hooks (each cost that call only).")
      .def_property_readonly("last_hook_error", [](const S& s) { return s.hooks ? s.hooks->last_error() : ""; })
      .def_property_readonly("ids", [](const S& s) { return s.model.ids(); })
      .def(
          "has", [](const S& s, std::uint8_t id) { return s.model.has(id); }, py::arg("id"))
      .def(
          "get", [](const S& s, std::uint8_t id, const std::string& e) { return s.model.get(id, e); }, py::arg("id"),
          py::arg("entry"), "Value of a control-table entry; ConfigError for an unknown ID or entry.")
      .def(
          "set", [](S& s, std::uint8_t id, const std::string& e, std::int64_t v) { s.model.set(id, e, v); },
          py::arg("id"), py::arg("entry"), py::arg("value"), "Writes an entry's memory, no checks.")
      .def(
          "set_present",
          [](S& s, std::uint8_t id, std::int64_t pos, std::int64_t vel, std::int64_t cur, std::int64_t volt,
             std::int64_t temp) { s.model.set_present(id, pos, vel, cur, volt, temp); },
          py::arg("id"), py::arg("position"), py::arg("velocity"), py::arg("current"), py::arg("input_voltage"),
          py::arg("temperature"), "Present values in raw table units (saturated to each entry's range).")
      .def(
          "goal_writes", [](const S& s, std::uint8_t id) { return s.model.goal_writes(id); }, py::arg("id"),
          "Goal positions the servo accepted.")
      .def(
          "stats", [](const S& s) { return stats_dict(s.model); }, "Counts of what the servos received and sent.")
      .def("reset_stats", [](S& s) { s.model.reset_stats(); }, "Zero the counts and goal writes.");

  py::class_<dx::SimulatedServos>(m, "SimulatedServosView",
                                  "The servos of a FakeServoBus (memory, faults, stats); owned by the bus.")
      .def(
          "inject",
          [](dx::SimulatedServos& s, const std::string& kind, const std::vector<std::uint8_t>& ids, int count) {
            s.inject(fault_kind(kind), ids, count);
          },
          py::arg("kind"), py::arg("ids") = std::vector<std::uint8_t>{}, py::arg("count") = -1,
          "As SimulatedServos.inject; count < 0: until cleared.")
      .def("set_silent", &dx::SimulatedServos::set_silent, py::arg("id"), py::arg("silent") = true)
      .def("set_hardware_error", &dx::SimulatedServos::set_hardware_error, py::arg("id"), py::arg("bits"))
      .def("clear_faults", &dx::SimulatedServos::clear_faults)
      .def("get", &dx::SimulatedServos::get, py::arg("id"), py::arg("entry"))
      .def("set", &dx::SimulatedServos::set, py::arg("id"), py::arg("entry"), py::arg("value"))
      .def("set_present", &dx::SimulatedServos::set_present, py::arg("id"), py::arg("position"), py::arg("velocity"),
           py::arg("current"), py::arg("input_voltage"), py::arg("temperature"))
      .def("goal_writes", &dx::SimulatedServos::goal_writes, py::arg("id"))
      .def("stats", [](const dx::SimulatedServos& s) { return stats_dict(s); })
      .def("reset_stats", &dx::SimulatedServos::reset_stats);
}

}  // namespace snake_autonomy::bindings
