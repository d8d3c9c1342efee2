#include "driver_diagnostics.hpp"

#include <cmath>

namespace snake_autonomy::ros_driver {

void diagnose_bus(const driver::DriverSnapshot& s, const std::string& port, int baud_bps,
                  diagnostic_updater::DiagnosticStatusWrapper& stat) {
  using diagnostic_msgs::DiagnosticStatus;
  stat.hardware_id = port;
  stat.summary(
      s.consecutive_failed_cycles > 0 ? DiagnosticStatus::WARN : DiagnosticStatus::OK,
      s.consecutive_failed_cycles > 0 ? str(s.consecutive_failed_cycles) + " consecutive failed cycles" : "ok");
  const auto& c = s.bus;
  stat.values = {kv("port", port),
                 kv("baud", str(baud_bps)),
                 kv("transactions", str(c.transactions)),
                 kv("bytes_sent", str(c.bytes_sent)),
                 kv("bytes_received", str(c.bytes_received)),
                 kv("packets_received", str(c.packets_received)),
                 kv("crc_errors", str(c.crc_errors)),
                 kv("timeouts", str(c.timeouts)),
                 kv("malformed", str(c.malformed)),
                 kv("hardware_error_alerts", str(c.hardware_error_alerts)),
                 kv("servo_errors", str(c.servo_errors)),
                 kv("unexpected_packets", str(c.unexpected_packets)),
                 kv("io_errors", str(c.io_errors)),
                 kv("drains", str(c.drains)),
                 kv("late_bytes", str(c.late_bytes)),
                 kv("verify_mismatches", str(c.verify_mismatches)),
                 kv("failed_cycles", str(s.failed_cycles)),
                 kv("consecutive_failed_cycles", str(s.consecutive_failed_cycles))};
}

void diagnose_servo(const driver::DriverSnapshot& s, const dynamixel::ControlTable& table, std::size_t j,
                    diagnostic_updater::DiagnosticStatusWrapper& stat) {
  using diagnostic_msgs::DiagnosticStatus;
  if (j >= s.servos.size()) return;
  const driver::ServoDiagnostics& d = s.servos[j];
  stat.hardware_id = "dynamixel " + str(int(d.id));
  const std::string bits = table.describe_hardware_error(d.hardware_error_bits);
  if (d.hardware_error) {
    stat.summary(DiagnosticStatus::ERROR, "hardware error: " + bits);
  } else if (d.stale) {
    stat.summary(DiagnosticStatus::WARN, "no reply for " + str(d.consecutive_misses) + " cycles");
  } else {
    stat.summary(DiagnosticStatus::OK, "ok");
  }
  stat.values = {kv("id", str(int(d.id))),
                 kv("temperature_c", std::isnan(d.temperature_c) ? "unknown" : fixed(d.temperature_c, 0)),
                 kv("voltage_v", std::isnan(d.voltage_v) ? "unknown" : fixed(d.voltage_v, 1)),
                 kv("hardware_error", d.hardware_error ? "true" : "false"),
                 kv("hardware_error_bits", str(int(d.hardware_error_bits))),
                 kv("hardware_error_names", bits),
                 kv("stale", d.stale ? "true" : "false"),
                 kv("consecutive_misses", str(d.consecutive_misses)),
                 kv("timeouts", str(d.timeouts)),
                 kv("crc_errors", str(d.crc_errors)),
                 kv("implausible", str(d.implausible)),
                 kv("other_errors", str(d.other_errors)),
                 kv("present_ticks", str(d.present_ticks)),
                 kv("goal_ticks", str(d.goal_ticks)),
                 kv("goal_min_ticks", str(d.min_ticks)),
                 kv("goal_max_ticks", str(d.max_ticks))};
}

}  // namespace snake_autonomy::ros_driver
