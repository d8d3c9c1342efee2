// The DriverController test rig: the COBRA model, the gait library and the XH540 table on a
// FakeServoBus; step() advances the loop by kDt, feeding a base pose each cycle (feed_pose).
#pragma once

#include <gtest/gtest.h>

#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "snake_autonomy/driver/driver_controller.hpp"
#include "snake_autonomy/dynamixel/fake_servo_bus.hpp"
#include "test_helpers.hpp"

namespace snake_autonomy::test {

using core::GaitLibrary;
using core::RobotModel;
using driver::DriverConfig;
using driver::DriverController;
using driver::DriverRequest;
using driver::GaitCommandRequest;
using driver::RequestResult;
using dynamixel::ControlTable;
using dynamixel::FakeServoBus;

constexpr double kDt = 0.01;
constexpr double kDeg = M_PI / 180.0;

struct Rig {
  RobotModel model;
  GaitLibrary gaits;
  ControlTable table;
  std::unique_ptr<FakeServoBus> bus;
  std::unique_ptr<DriverController> ctl;
  double t = 0.0;
  bool feed_pose = true;
  // Re-sent every 100 cycles (1 s) when set, as the mission node re-sends its command (the driver's
  // command_timeout_s); commanding allocates, so tests counting allocations leave it unset.
  std::optional<GaitCommandRequest> heartbeat;

  explicit Rig(DriverConfig config = DriverConfig{}, const std::function<void(RobotModel&)>& edit = {},
               const std::function<void(FakeServoBus&)>& before_start = {})
      : model(cobra()),
        gaits(GaitLibrary::from_yaml_file(source_path("config/gaits.yaml"))),
        table(ControlTable::from_yaml_file(source_path("config/dynamixel/xh540_w270.yaml"))) {
    if (edit) edit(model);
    std::vector<std::uint8_t> ids;
    for (int id : model.servos.ids) ids.push_back(static_cast<std::uint8_t>(id));
    bus = std::make_unique<FakeServoBus>(table, ids);
    if (before_start) before_start(*bus);
    ctl = std::make_unique<DriverController>(model, gaits, table, *bus, config);
  }
  void start() { ctl->start(t); }
  bool step(int cycles = 1) {
    bool ok = true;
    for (int k = 0; k < cycles; ++k) {
      t += kDt;
      if (feed_pose) ctl->set_base_pose(t, Eigen::Vector3d(1.0, 2.0, 0.0), Eigen::Quaterniond::Identity());
      if (heartbeat && ++cycles_since_beat_ >= 100) {
        cycles_since_beat_ = 0;
        EXPECT_EQ(ctl->command_gait(*heartbeat), "");
      }
      ok = ctl->update(t, kDt) && ok;
    }
    return ok;
  }
  RequestResult request(DriverRequest r, std::uint8_t id = 0) {
    const auto ticket = ctl->post(r, id);
    step();
    RequestResult out;
    EXPECT_TRUE(ctl->take_result(ticket, &out));
    return out;
  }
  static GaitCommandRequest named(const std::string& gait) {
    GaitCommandRequest c;
    c.gait = gait;
    return c;
  }
  std::string command(const std::string& gait) {
    GaitCommandRequest c;
    c.gait = gait;
    return ctl->command_gait(c);
  }
  std::int64_t goal(int id) const { return bus->servos().get(static_cast<std::uint8_t>(id), "goal_position"); }
  std::int64_t torque(int id) const { return bus->servos().get(static_cast<std::uint8_t>(id), "torque_enable"); }

 private:
  int cycles_since_beat_ = 0;
};

}  // namespace snake_autonomy::test
