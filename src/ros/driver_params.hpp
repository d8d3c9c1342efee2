// The driver node's configuration: a plain struct read from rosparam (config/driver.yaml documents
// every key). The controller's keys go through the core's loader (DriverConfig::apply_yaml): an
// optional ~driver_config_file, then the rosparams over it. read_driver_params() collects every problem (wrong type,
// bad value), naming the key and the value, so that the node refuses to start with the complete list.
#pragma once

#include <ros/node_handle.h>

#include <string>
#include <vector>

#include "snake_autonomy/driver/driver_config.hpp"
#include "snake_autonomy/driver/loop_timer.hpp"
#include "snake_autonomy/dynamixel/serial_bus.hpp"

namespace snake_autonomy::ros_driver {

struct DriverNodeConfig {
  std::string config_dir;           // the package's config/ (robots/, gaits.yaml, dynamixel/)
  std::string robot = "cobra";      // a name under config/robots/ or a YAML path
  std::string gaits_file;           // default: config_dir/gaits.yaml
  std::string control_table_file;   // default: config_dir/dynamixel/<servos.model>.yaml
  dynamixel::SerialConfig serial;   // port, baud, low_latency, bus timing
  driver::LoopConfig loop;            // rate_hz
  driver::DriverConfig controller;
  int realtime_priority = 0;        // SCHED_FIFO priority of the loop thread (1-99), 0: normal scheduling
  std::string world_frame = "odom";
  std::string base_frame = "base_link";
  std::string com_frame = "com";
  bool publish_tf = true;           // world_frame -> base_frame and -> com_frame on /tf; false when a
                                    // localisation node owns that transform (REP 105)
  double diagnostics_period_s = 1.0;
  double connect_timeout_s = 10.0;  // wait this long for the port and the servos at start
  double service_timeout_s = 2.0;   // a service waits this long for the loop to run its request

  std::string robot_file() const;
  std::vector<std::string> validate() const;
};

// Reads ~params over the defaults; appends every problem to `errors`.
DriverNodeConfig read_driver_params(const ros::NodeHandle& pnh, std::vector<std::string>& errors);

}  // namespace snake_autonomy::ros_driver
