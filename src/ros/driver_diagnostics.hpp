// driver_node's diagnostics of the bus and of each servo (diagnostic_updater tasks, run on the node's
// publisher thread from the loop's latest snapshot), and the small text helpers the node's other tasks use.
#pragma once

#include <diagnostic_msgs/KeyValue.h>
#include <diagnostic_updater/diagnostic_updater.h>

#include <cstddef>
#include <cstdio>
#include <sstream>
#include <string>

#include "snake_autonomy/driver/driver_controller.hpp"
#include "snake_autonomy/dynamixel/control_table.hpp"

namespace snake_autonomy::ros_driver {

inline diagnostic_msgs::KeyValue kv(const std::string& key, const std::string& value) {
  diagnostic_msgs::KeyValue k;
  k.key = key;
  k.value = value;
  return k;
}

template <typename T>
std::string str(T v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

inline std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

// "snake_driver: bus": the bus counters; WARN while cycles fail.
void diagnose_bus(const driver::DriverSnapshot& s, const std::string& port, int baud_bps,
                  diagnostic_updater::DiagnosticStatusWrapper& stat);

// "snake_driver: servo <id> (joint_<j+1>)": ERROR on a hardware error (its bits named by the control table),
// WARN while the servo does not reply.
void diagnose_servo(const driver::DriverSnapshot& s, const dynamixel::ControlTable& table, std::size_t j,
                    diagnostic_updater::DiagnosticStatusWrapper& stat);

}  // namespace snake_autonomy::ros_driver
