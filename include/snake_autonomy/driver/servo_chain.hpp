// ServoChain: the driver's hardware layer (ros_control's RobotHW for a chain of Dynamixel servos on
// one ServoBus). It owns the bus reference, the Transmissions (the only tick <-> radian conversion)
// and the goal clamp; it knows nothing of gaits, states or faults.
//
//   start()          start-up checks and setup: model number, operating mode (position control),
//                    position limits (the servo's own, read here), Return Delay Time (written where it
//                    differs from the configuration; the bus's reply deadlines allow for the slowest
//                    servo), hardware error status, a first feedback read. Allocates; problems are
//                    returned, not thrown (the caller decides).
//   read()           one sync read of position/velocity/current of every servo into joint space
//                    (radians, rad/s, amperes in joint sense) with the per-servo health counters: a
//                    servo without a usable reply (missing, corrupt, implausible) keeps its last good
//                    values and is flagged stale.
//   read_status()    the slow read: input voltage and temperature.
//   write(goal_rad)  THE goal clamp: each goal is clamped into the joint's limits (robot YAML)
//                    intersected with the servo's position limits (read at start), in radians (the
//                    caller's vector is updated: it sees what was commanded) and again in ticks; a
//                    non-finite goal keeps the previous goal. Then one sync write of Goal Position.
//   write_torque(), confirm_torque(), reboot(), read_hardware_errors(): torque on/off, reboot, the
//                    Hardware Error Status bits of alerting servos.
//
// Units: joint radians (eq. 3.4: direction and zero offset applied by the Transmission), rad/s,
// amperes; ticks only inside. Joint j is servo ids()[j].
// Real-time safety: everything but the constructor and start() is noexcept and allocation-free
// (buffers sized in the constructor). One thread (the loop) uses a ServoChain; the bus must outlive it.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "snake_autonomy/core/robot_model.hpp"
#include "snake_autonomy/driver/driver_config.hpp"
#include "snake_autonomy/driver/message.hpp"
#include "snake_autonomy/driver/transmission.hpp"
#include "snake_autonomy/dynamixel/control_table.hpp"
#include "snake_autonomy/dynamixel/servo_bus.hpp"

namespace snake_autonomy::driver {

// Per servo, for diagnostics.
struct ServoDiagnostics {
  std::uint8_t id = 0;
  bool stale = true;                      // the last cycle had no usable reply: values are the last good ones
  std::uint32_t consecutive_misses = 0;
  std::uint64_t timeouts = 0;             // missed replies
  std::uint64_t crc_errors = 0;
  std::uint64_t implausible = 0;          // valid CRC, impossible values (garbage)
  std::uint64_t other_errors = 0;         // malformed, wrong ID, servo error, I/O error
  bool hardware_error = false;            // the alert bit was seen since the last enable/reboot
  std::uint8_t hardware_error_bits = 0;   // Hardware Error Status (address 70) as last read
  double temperature_c = std::nan("");    // NaN until read
  double voltage_v = std::nan("");
  std::int32_t present_ticks = 0;
  std::int32_t goal_ticks = 0;
  std::int32_t min_ticks = 0, max_ticks = 0;  // the goal clamp: joint limits within the servo's limits
};

// What start() found.
struct ChainStartReport {
  std::vector<std::string> problems;   // each names the servo (ID and joint): the chain is not usable
  std::vector<std::string> notes;      // what was changed or could not be (Return Delay Time)
  std::vector<int> hardware_errors;    // joints whose servo reports a hardware error
};

class ServoChain {
 public:
  // Problems of the table layout for this chain (the status read must span <= 16 bytes), each a line.
  static std::vector<std::string> check_table(const dynamixel::ControlTable& table);
  // The model, table and config must have been validated (DriverController does). Keeps a reference
  // to the bus.
  ServoChain(const core::RobotModel& model, const dynamixel::ControlTable& table, dynamixel::ServoBus& bus,
             const DriverConfig& config);

  ChainStartReport start();

  // Returns false when a servo had no usable reply (or the bus failed).
  bool read() noexcept;
  void read_status() noexcept;
  // Reads the Hardware Error Status of every servo that raised the alert bit and whose bits are not
  // known yet; returns true when any servo has a hardware error.
  bool read_hardware_errors() noexcept;
  // Clamps goal_rad in place into [lower_rad, upper_rad], converts, clamps the ticks, writes.
  // Returns false when the bus did not take the write.
  bool write(Eigen::Ref<Eigen::VectorXd> goal_rad) noexcept;
  // The clamp and conversion of write() without sending (what the next write sends; the snapshot's
  // goal ticks).
  void set_goal(Eigen::Ref<Eigen::VectorXd> goal_rad) noexcept;
  bool write_torque(bool on) noexcept;
  // Reads torque_enable back (sync writes have no reply); appends every servo that did not confirm
  // `on` to `why`. True when all confirmed.
  bool confirm_torque(bool on, Message& why) noexcept;
  // Reboots servo `id` and clears its hardware error flags (the status packet goes out before the
  // servo restarts: it still carries the alert bit).
  dynamixel::Status reboot(std::uint8_t id) noexcept;

  // The posture clamped into the goal limits (the hold posture).
  void clamp(Eigen::Ref<Eigen::VectorXd> rad) const noexcept;
  // True when a reply of the last read was an I/O error or the port was not open.
  bool io_error() const noexcept;
  // True when every servo of the last read failed with the same status (that status in *status).
  bool all_failed_alike(dynamixel::Status* status) const noexcept;
  dynamixel::Status reply_status(int joint) const noexcept { return replies_[joint].status; }
  bool outside_limits(int joint) const noexcept {
    return diag_[joint].present_ticks < diag_[joint].min_ticks || diag_[joint].present_ticks > diag_[joint].max_ticks;
  }
  // " servo 3 (joint_3): overheating;" for every servo with a hardware error.
  void describe_hardware_errors(Message& out) const noexcept;
  // One servo's hardware error bits in words, into out (size bytes).
  void describe_bits(std::uint8_t bits, char* out, std::size_t size) const noexcept;
  // " servo 3 (joint_3) timeout for 4 cycles;" for every stale servo.
  void describe_stale(Message& out) const noexcept;
  int joint_of(std::uint8_t id) const noexcept;

  int size() const noexcept { return n_; }
  const std::vector<std::uint8_t>& ids() const noexcept { return ids_; }
  const Eigen::VectorXd& position_rad() const noexcept { return position_; }
  const Eigen::VectorXd& velocity_rad_s() const noexcept { return velocity_; }
  const Eigen::VectorXd& effort_a() const noexcept { return effort_; }
  const Eigen::VectorXd& lower_rad() const noexcept { return lo_rad_; }  // the goal clamp in joint space
  const Eigen::VectorXd& upper_rad() const noexcept { return hi_rad_; }
  const std::vector<ServoDiagnostics>& servos() const noexcept { return diag_; }
  const Transmission& transmission(int joint) const noexcept { return tx_[joint]; }
  dynamixel::BusCounters bus_counters() const noexcept { return bus_.counters(); }

 private:
  void set_limits(int joint, std::int32_t servo_min_ticks, std::int32_t servo_max_ticks) noexcept;
  // Reads servo j's Return Delay Time, writes the configured one where it differs; returns the
  // servo's delay in microseconds afterwards.
  int settle_return_delay(int j, const std::string& name, ChainStartReport& report);
  std::string servo_name(int j) const;

  dynamixel::ServoBus& bus_;
  int n_;
  std::vector<double> joint_lower_rad_, joint_upper_rad_;  // robot YAML
  bool fast_sync_read_;
  std::int64_t plausible_margin_ticks_;
  int return_delay_time_us_;
  std::vector<std::uint8_t> ids_;
  std::vector<Transmission> tx_;
  dynamixel::ControlTable table_;
  dynamixel::UnitScales scales_;
  std::uint16_t addr_torque_ = 0, addr_hw_error_ = 0, addr_mode_ = 0, addr_min_pos_ = 0, addr_max_pos_ = 0;
  std::uint16_t addr_return_delay_ = 0;
  std::uint16_t addr_status_ = 0, status_bytes_ = 0, voltage_offset_ = 0, voltage_bytes_ = 2, temperature_offset_ = 0;

  std::vector<std::uint8_t> feedback_, status_, goals_, torque_;
  std::vector<dynamixel::ServoReply> replies_, status_replies_;
  Eigen::VectorXd position_, velocity_, effort_, lo_rad_, hi_rad_;
  std::vector<std::int32_t> servo_min_ticks_, servo_max_ticks_;
  std::vector<std::uint8_t> hw_bits_known_;
  std::vector<ServoDiagnostics> diag_;
};

}  // namespace snake_autonomy::driver
