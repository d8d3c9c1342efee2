// DriverController::update() alone: the driver's cycle (layers: supervisor, servo chain, gait
// source, slew limit, clamp, kinematics) on the in-process FakeServoBus, without a serial port or
// the Python mock, so the figure is the controller's own cost (protocol encode/decode included).
//   scripts/with-env bench/driver_update [CYCLES=20000]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "snake_autonomy/driver/driver_controller.hpp"
#include "snake_autonomy/dynamixel/fake_servo_bus.hpp"

using namespace snake_autonomy;

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::max(100, std::atoi(argv[1])) : 20000;
  const std::string dir = SNAKE_SOURCE_DIR;
  const auto model = core::RobotModel::from_yaml_file(dir + "/config/robots/cobra.yaml");
  const auto gaits = core::GaitLibrary::from_yaml_file(dir + "/config/gaits.yaml");
  const auto table = dynamixel::ControlTable::from_yaml_file(dir + "/config/dynamixel/xh540_w270.yaml");
  std::vector<std::uint8_t> ids;
  for (int id : model.servos.ids) ids.push_back(static_cast<std::uint8_t>(id));
  dynamixel::FakeServoBus bus(table, ids);
  driver::DriverConfig cfg;
  cfg.require_pose = false;
  cfg.command_timeout_s = 0.0;     // one command for the whole run
  cfg.status_every_cycles = 100;   // voltage/temperature once a second at 100 Hz
  driver::DriverController ctl(model, gaits, table, bus, cfg);
  ctl.start(0.0);
  driver::GaitCommandRequest cmd;
  cmd.gait = "sidewind";
  if (!ctl.command_gait(cmd).empty()) return 1;
  double t = 0.0;
  for (int k = 0; k < 500; ++k) ctl.update(t += 0.01, 0.01);  // warm up, the gait running
  std::vector<double> us(static_cast<std::size_t>(n));
  for (auto& u : us) {
    const auto a = std::chrono::steady_clock::now();
    ctl.update(t += 0.01, 0.01);
    u = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - a).count();
  }
  std::sort(us.begin(), us.end());
  std::printf("driver_update cycles=%d median_us=%.2f p10_us=%.2f p99_us=%.2f max_us=%.2f state=%s\n", n,
              us[us.size() / 2], us[us.size() / 10], us[us.size() * 99 / 100], us.back(),
              driver::to_string(ctl.state()));
  return ctl.state() == driver::DriverState::kRunning ? 0 : 1;
}
