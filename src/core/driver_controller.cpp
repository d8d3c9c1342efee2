#include "snake_autonomy/core/driver_controller.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <thread>

#include "snake_autonomy/dynamixel/conversions.hpp"
#include "snake_autonomy/dynamixel/protocol.hpp"

namespace snake_autonomy::core {

namespace dxl = snake_autonomy::dynamixel;

namespace {

constexpr std::uint8_t kPositionControlMode = 3;

void copy_message(Message& out, const char* text) noexcept {
  std::snprintf(out.data(), out.size(), "%s", text);
}

// Appends to a Message without allocating.
void append(Message& out, const char* fmt, ...) __attribute__((format(printf, 2, 3)));
void append(Message& out, const char* fmt, ...) {
  const std::size_t used = std::strlen(out.data());
  if (used + 1 >= out.size()) return;
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(out.data() + used, out.size() - used, fmt, args);
  va_end(args);
}

double deg(double rad) { return rad * 180.0 / M_PI; }

// The trajectory source's limits: the joints' (refined to the goal clamp once the servos are known),
// a tolerance of one servo tick (the clamp is the joint limits rounded inwards to whole ticks: a point
// on a joint limit is within a tick of it, and the clamp applies), the slew limit, the capacity.
driver::TrajectoryLimits trajectory_limits(const RobotModel& model, const dxl::ControlTable& table,
                                           const DriverConfig& config) {
  driver::TrajectoryLimits l;
  const auto n = static_cast<std::size_t>(std::max(model.num_joints, 0));
  const bool sized = model.joint_lower_rad.size() == n && model.joint_upper_rad.size() == n;  // else validate() says
  l.lower_rad = l.upper_rad = Eigen::VectorXd::Zero(model.num_joints);
  for (std::size_t j = 0; sized && j < n; ++j) {
    l.lower_rad[j] = model.joint_lower_rad[j];
    l.upper_rad[j] = model.joint_upper_rad[j];
  }
  l.limit_tolerance_rad = table.unit_scales().rad_per_tick;
  // Usable values in place of invalid ones: the constructor's validate() reports those, naming them.
  const double v = config.max_joint_velocity_rad_s;
  l.max_velocity_rad_s = v > 0.0 && std::isfinite(v) ? v : 1.0;
  l.max_points = std::clamp(config.max_trajectory_points, 1, 1000000);
  return l;
}

}  // namespace

const char* to_string(DriverState state) noexcept {
  switch (state) {
    case DriverState::kStopped: return "stopped";
    case DriverState::kHolding: return "holding";
    case DriverState::kRunning: return "running";
    case DriverState::kFault: return "fault";
  }
  return "?";
}

const char* to_string(DriverRequest request) noexcept {
  switch (request) {
    case DriverRequest::kEnableTorque: return "enable torque";
    case DriverRequest::kDisableTorque: return "disable torque";
    case DriverRequest::kHold: return "hold";
    case DriverRequest::kRebootServo: return "reboot servo";
  }
  return "?";
}

// ---------------------------------------------------------------------------------------------
// Configuration

DriverController::DriverController(const RobotModel& model, const GaitLibrary& gaits,
                                   const dxl::ControlTable& table, dxl::ServoBus& bus, const DriverConfig& config)
    : model_(model),
      table_(table),
      scales_(table.unit_scales()),
      bus_(bus),
      config_(config),
      n_(model.num_joints),
      cpg_(model),
      kinematics_(model),
      kin_state_(model.num_frames()),
      resolver_(model, gaits, config.max_frequency_hz > 0.0 ? config.max_frequency_hz : 1.0, "hold"),
      trajectory_(model.num_joints, trajectory_limits(model, table, config)) {
  std::vector<std::string> errors = config.validate();
  for (const auto& e : model.validate()) errors.push_back("robot: " + e);
  for (const auto& e : table.validate()) errors.push_back("control table: " + e);
  if (model.servos.model != table.model)
    errors.push_back("robot servos.model: '" + model.servos.model + "' but the control table is '" + table.model + "'");
  const auto* voltage = table.find("present_input_voltage");
  const auto* temperature = table.find("present_temperature");
  if (voltage && temperature) {
    const int lo = std::min(voltage->address, temperature->address);
    const int hi = std::max(voltage->address + voltage->size, temperature->address + temperature->size);
    if (hi - lo > 16) errors.push_back("control table: present_input_voltage and present_temperature are " +
                                       std::to_string(hi - lo) + " bytes apart (at most 16 for one status read)");
    addr_status_ = static_cast<std::uint16_t>(lo);
    status_bytes_ = static_cast<std::uint16_t>(hi - lo);
    voltage_offset_ = static_cast<std::uint16_t>(voltage->address - lo);
    voltage_bytes_ = voltage->size;
    temperature_offset_ = static_cast<std::uint16_t>(temperature->address - lo);
  }
  if (!errors.empty()) {
    std::string what = "driver configuration:";
    for (const auto& e : errors) what += "\n  " + e;
    throw ConfigError(what);
  }
  addr_torque_ = table.at("torque_enable").address;
  addr_hw_error_ = table.at("hardware_error_status").address;
  addr_mode_ = table.at("operating_mode").address;
  addr_return_delay_ = table.at("return_delay_time").address;
  addr_min_pos_ = table.at("min_position_limit").address;
  addr_max_pos_ = table.at("max_position_limit").address;

  const auto nz = static_cast<std::size_t>(n_);
  for (int id : model.servos.ids) ids_.push_back(static_cast<std::uint8_t>(id));
  tx_ = driver::Transmission::for_robot(model, table);
  feedback_.assign(nz * dxl::kFeedbackBytes, 0);
  status_.assign(nz * std::max<std::uint16_t>(status_bytes_, 1), 0);
  goals_.assign(nz * dxl::kGoalPositionBytes, 0);
  torque_.assign(nz, 0);
  replies_.assign(nz, dxl::ServoReply{});
  status_replies_.assign(nz, dxl::ServoReply{});
  hw_bits_known_.assign(nz, 0);
  position_ = velocity_ = effort_ = goal_rad_ = hold_rad_ = zeros_ = lo_rad_ = hi_rad_ = Eigen::VectorXd::Zero(n_);
  diag_.assign(nz, ServoDiagnostics{});
  servo_min_ticks_.assign(nz, 0);
  servo_max_ticks_.assign(nz, 0);
  const auto& goal_entry = table.at("goal_position");
  for (int j = 0; j < n_; ++j) {
    diag_[j].id = ids_[j];
    const auto lo = goal_entry.has_range ? static_cast<std::int32_t>(goal_entry.min) : 0;
    const auto hi = goal_entry.has_range ? static_cast<std::int32_t>(goal_entry.max) : 4095;
    set_limits(j, lo, hi);
    diag_[j].present_ticks = diag_[j].goal_ticks = tx_[j].centre_ticks() + tx_[j].zero_offset_ticks();
  }
  nominal_ = effective_ = pending_gait_ = resolver_.nominal();
  copy_message(gait_name_, "hold");
  trajectory_.set_joint_limits(lo_rad_, hi_rad_);
  trajectory_goal_ = Eigen::VectorXd::Zero(n_);
}

void DriverController::set_limits(int j, std::int32_t servo_min, std::int32_t servo_max) noexcept {
  servo_min_ticks_[j] = servo_min;
  servo_max_ticks_[j] = servo_max;
  // Joint limits in ticks, rounded inwards: the clamp never lets a goal out of the joint's range.
  std::int32_t lo = 0, hi = 0;
  tx_[j].joint_range_to_ticks(model_.joint_lower_rad[j], model_.joint_upper_rad[j], &lo, &hi);
  auto& d = diag_[j];
  d.min_ticks = std::max(lo, servo_min);
  d.max_ticks = std::min(hi, servo_max);
  const double a = ticks_to_joint_rad(j, d.min_ticks), b = ticks_to_joint_rad(j, d.max_ticks);
  lo_rad_[j] = std::min(a, b);
  hi_rad_[j] = std::max(a, b);
}

double DriverController::ticks_to_joint_rad(int joint, std::int32_t ticks) const noexcept {
  return tx_[joint].ticks_to_joint_rad(ticks);
}

bool DriverController::joint_rad_to_ticks(int joint, double rad, std::int32_t* ticks) const noexcept {
  return tx_[joint].joint_rad_to_ticks(rad, ticks);
}

std::int32_t DriverController::clamp_goal(int joint, std::int32_t ticks) const noexcept {
  return dxl::clamp_ticks(ticks, diag_[joint].min_ticks, diag_[joint].max_ticks);
}

int DriverController::joint_of(std::uint8_t id) const noexcept {
  for (int j = 0; j < n_; ++j) {
    if (ids_[j] == id) return j;
  }
  return -1;
}

void DriverController::describe_bits(std::uint8_t bits, char* out, std::size_t size) const noexcept {
  out[0] = '\0';
  std::size_t used = 0;
  for (int bit = 0; bit < 8 && used + 1 < size; ++bit) {
    if (!(bits & (1u << bit))) continue;
    const char* name = nullptr;
    for (const auto& [n, b] : table_.hardware_error_bits) {
      if (b == bit) name = n.c_str();
    }
    const int w = name ? std::snprintf(out + used, size - used, "%s%s", used ? ", " : "", name)
                       : std::snprintf(out + used, size - used, "%sbit %d", used ? ", " : "", bit);
    if (w < 0) break;
    used = std::min(size - 1, used + static_cast<std::size_t>(w));
  }
  if (used == 0) std::snprintf(out, size, "%s", bits ? "?" : "alert bit set, status not read");
}

// ---------------------------------------------------------------------------------------------
// Start and shutdown

void DriverController::start(double t_s) {
  std::vector<std::string> problems;
  auto servo_name = [this](int j) {
    return "servo " + std::to_string(ids_[j]) + " (joint_" + std::to_string(j + 1) + ")";
  };
  std::vector<int> hw_errors;
  start_notes_.clear();
  int max_delay_us = 0;
  for (int j = 0; j < n_; ++j) {
    const std::uint8_t id = ids_[j];
    std::uint16_t model_number = 0;
    std::uint8_t error = 0;
    dxl::Status s = bus_.ping(id, &model_number, &error);
    if (!dxl::has_data(s)) {
      problems.push_back(servo_name(j) + ": no answer to ping (" + dxl::to_string(s) + ")");
      continue;
    }
    if (model_number != table_.model_number) {
      problems.push_back(servo_name(j) + ": model number " + std::to_string(model_number) + ", expected " +
                         std::to_string(table_.model_number) + " (" + table_.model + ")");
    }
    const int delay_us = settle_return_delay(j, servo_name(j), problems);
    if (delay_us > max_delay_us) max_delay_us = delay_us;
    std::uint8_t mode = 0;
    s = bus_.read(id, addr_mode_, 1, &mode, &error);
    if (!dxl::has_data(s)) {
      problems.push_back(servo_name(j) + ": reading operating_mode failed (" + dxl::to_string(s) + ")");
    } else if (mode != kPositionControlMode) {
      problems.push_back(servo_name(j) + ": operating_mode " + std::to_string(mode) +
                         ", the driver needs 3 (position control)");
    }
    std::uint8_t limits[8] = {};
    const std::uint16_t lo_addr = std::min(addr_min_pos_, addr_max_pos_);
    s = bus_.read(id, lo_addr, 8, limits, &error);
    if (!dxl::has_data(s)) {
      problems.push_back(servo_name(j) + ": reading the position limits failed (" + dxl::to_string(s) + ")");
    } else {
      const std::int32_t mn = dxl::get_le(limits + (addr_min_pos_ - lo_addr), 4, true);
      const std::int32_t mx = dxl::get_le(limits + (addr_max_pos_ - lo_addr), 4, true);
      set_limits(j, mn, mx);
      if (diag_[j].min_ticks > diag_[j].max_ticks) {
        std::ostringstream m;
        m << servo_name(j) << ": joint limits [" << deg(model_.joint_lower_rad[j]) << ", "
          << deg(model_.joint_upper_rad[j]) << "] deg do not overlap the servo's position limits [" << mn << ", "
          << mx << "] ticks";
        problems.push_back(m.str());
      }
    }
    std::uint8_t bits = 0;
    s = bus_.read(id, addr_hw_error_, 1, &bits, &error);
    if (!dxl::has_data(s)) {
      problems.push_back(servo_name(j) + ": reading hardware_error_status failed (" + dxl::to_string(s) + ")");
    } else if (bits != 0 || (error & dxl::kAlertBit)) {
      diag_[j].hardware_error = true;
      diag_[j].hardware_error_bits = bits;
      hw_bits_known_[j] = 1;
      hw_errors.push_back(j);
    }
  }
  bus_.set_return_delay_s(max_delay_us * 1e-6);
  trajectory_.set_joint_limits(lo_rad_, hi_rad_);  // the goal clamp, with the servos' own limits
  if (problems.empty() && !read_feedback()) {
    for (int j = 0; j < n_; ++j) {
      if (diag_[j].stale)
        problems.push_back(servo_name(j) + ": no feedback (" + dxl::to_string(replies_[j].status) + ")");
    }
  }
  if (!problems.empty()) {
    std::string what = "servo bus at start:";
    for (const auto& p : problems) what += "\n  " + p;
    throw ConfigError(what);
  }
  started_ = true;
  t_s_ = last_command_t_s_ = t_s;
  hold_here();
  goals_from_rad();
  if (!hw_errors.empty()) {
    Message m{};
    copy_message(m, "hardware error at start:");
    for (int j : hw_errors) {
      char bits[96];
      describe_bits(diag_[j].hardware_error_bits, bits, sizeof bits);
      append(m, " servo %d (joint_%d): %s;", ids_[j], j + 1, bits);
    }
    append(m, " reboot it (driver/reboot_servo), then enable torque");
    fault_reason_ = last_fault_ = m;
    set_state(DriverState::kFault);
    return;
  }
  if (config_.torque_on_start) {
    Message why{};
    if (!enable_torque(why)) {
      fault_reason_ = last_fault_ = why;
      write_torque(false);
      set_state(DriverState::kFault);
    }
  } else {
    set_state(DriverState::kStopped);
  }
}

int DriverController::settle_return_delay(int j, const std::string& name, std::vector<std::string>& problems) {
  const std::uint8_t id = ids_[j];
  std::uint8_t units = 0, error = 0;
  const dxl::Status s = bus_.read(id, addr_return_delay_, 1, &units, &error);
  if (!dxl::has_data(s)) {
    problems.push_back(name + ": reading return_delay_time failed (" + dxl::to_string(s) + ")");
    return 0;
  }
  const int want_us = config_.return_delay_time_us;
  if (want_us < 0 || units * 2 == want_us) return units * 2;
  const std::uint8_t want = static_cast<std::uint8_t>(want_us / 2);
  const dxl::Status w = bus_.write(id, addr_return_delay_, &want, 1, &error);
  std::uint8_t back = units;
  if (w == dxl::Status::kOk && dxl::has_data(bus_.read(id, addr_return_delay_, 1, &back, &error)) && back == want) {
    start_notes_.push_back(name + ": Return Delay Time " + std::to_string(units * 2) + " us -> " +
                           std::to_string(want_us) + " us (written to the servo's EEPROM)");
    return want_us;
  }
  // An XH540 refuses EEPROM writes while its torque is on: carry on with the slower replies.
  start_notes_.push_back(name + ": Return Delay Time is " + std::to_string(units * 2) + " us, writing " +
                         std::to_string(want_us) + " us failed (" +
                         (w == dxl::Status::kServoError ? std::string("EEPROM locked: torque is on; restart the driver "
                                                                      "with the servo's torque off")
                                                        : std::string(dxl::to_string(w))) +
                         "); reply deadlines allow for " + std::to_string(units * 2) + " us");
  return units * 2;
}

bool DriverController::shutdown() noexcept {
  if (!started_) return true;
  trajectory_.abort(driver::TrajectoryAbort::kShutdown);
  if (config_.shutdown_action == SafeAction::kTorqueOff) {
    const bool ok = write_torque(false);
    set_state(DriverState::kStopped);
    return ok;
  }
  if (state() == DriverState::kStopped) return true;  // torque already off
  read_feedback();
  hold_here();
  goals_from_rad();
  const bool ok = write_goals();
  if (state() != DriverState::kFault) {
    hold_reason_ = HoldReason::kShutdown;
    set_state(DriverState::kHolding);
  }
  return ok;
}

// ---------------------------------------------------------------------------------------------
// The cycle

bool DriverController::update(double t_s, double dt_s) noexcept {
  if (!started_) return false;
  ++cycle_;
  t_s_ = t_s;
  dt_s = std::isfinite(dt_s) ? std::clamp(dt_s, 0.0, config_.max_step_s) : 0.0;

  take_request();
  take_gait();
  take_trajectory(t_s);
  take_pose(t_s);
  if (state() == DriverState::kRunning && !trajectory_.running() &&
      command_expired(t_s, last_command_t_s_, config_.command_timeout_s))
    hold_for(HoldReason::kCommandTimeout);

  const bool read_ok = read_feedback();
  if (config_.status_every_cycles > 0 && cycle_ % static_cast<std::uint64_t>(config_.status_every_cycles) == 0)
    read_status();
  check_hardware_errors();

  // Stale base pose: hold locomotion (amplitudes to zero), resume when fresh poses return.
  const bool gate = config_.require_pose && !pose_fresh_;
  if (state() == DriverState::kRunning && gate != gated_) {
    gated_ = gate;
    apply_gait();
  }

  if (state() == DriverState::kRunning && !trajectory_.running()) step_cpg(dt_s);
  step_trajectory(t_s);
  bool write_ok = true;
  const DriverState s = state();
  if (s == DriverState::kRunning || s == DriverState::kHolding ||
      (s == DriverState::kFault && config_.fault_action == SafeAction::kHold)) {
    compute_goals(dt_s);
    write_ok = write_goals();
  } else if (s == DriverState::kFault) {
    write_ok = write_torque(false);  // repeated: a servo that comes back must not keep torque
  }

  const bool ok = read_ok && write_ok;
  if (ok) {
    consecutive_failed_ = 0;
  } else {
    ++failed_cycles_;
    ++consecutive_failed_;
    const DriverState now = state();
    if (consecutive_failed_ >= static_cast<std::uint32_t>(config_.max_failed_cycles) &&
        (now == DriverState::kRunning || now == DriverState::kHolding)) {
      Message m{};
      bool io = false;
      for (int j = 0; j < n_; ++j)
        io = io || replies_[j].status == dxl::Status::kIoError || replies_[j].status == dxl::Status::kNotOpen;
      if (io || !write_ok) {
        std::snprintf(m.data(), m.size(), "bus failure for %u consecutive cycles: %s%s", consecutive_failed_,
                      io ? "I/O error (port closed or adapter unplugged?)" : "",
                      write_ok ? "" : (io ? "; goal write failed" : "goal write failed"));
      } else {
        std::snprintf(m.data(), m.size(), "%u consecutive cycles with missing replies:", consecutive_failed_);
        for (int j = 0; j < n_; ++j) {
          if (diag_[j].stale)
            append(m, " servo %d (joint_%d) %s for %u cycles;", ids_[j], j + 1, dxl::to_string(replies_[j].status),
                   diag_[j].consecutive_misses);
        }
      }
      enter_fault(m.data());
    }
  }
  run_kinematics();
  return ok;
}

bool DriverController::read_feedback() noexcept {
  const dxl::Status status =
      config_.fast_sync_read
          ? bus_.fast_sync_read(dxl::kFeedbackAddress, dxl::kFeedbackBytes, ids_.data(), ids_.size(), feedback_.data(),
                                replies_.data())
          : bus_.sync_read(dxl::kFeedbackAddress, dxl::kFeedbackBytes, ids_.data(), ids_.size(), feedback_.data(),
                           replies_.data());
  (void)status;  // per-servo replies say everything
  bool all = true;
  for (int j = 0; j < n_; ++j) {
    ServoDiagnostics& d = diag_[j];
    const dxl::ServoReply& r = replies_[j];
    bool usable = dxl::has_data(r.status);
    if (usable) {
      const dxl::ServoFeedback fb = dxl::decode_feedback(&feedback_[j * dxl::kFeedbackBytes], scales_);
      const std::int64_t margin = config_.plausible_margin_ticks;
      if (fb.position_ticks < servo_min_ticks_[j] - margin || fb.position_ticks > servo_max_ticks_[j] + margin) {
        ++d.implausible;
        usable = false;
      } else {
        d.present_ticks = fb.position_ticks;
        position_[j] = ticks_to_joint_rad(j, fb.position_ticks);
        velocity_[j] = tx_[j].shaft_to_joint_sense(fb.velocity_rad_s);
        effort_[j] = tx_[j].shaft_to_joint_sense(fb.current_a);
        d.stale = false;
        d.consecutive_misses = 0;
        if (r.status == dxl::Status::kHardwareError || (r.error & dxl::kAlertBit)) d.hardware_error = true;
      }
    } else if (r.status == dxl::Status::kTimeout) {
      ++d.timeouts;
    } else if (r.status == dxl::Status::kCrcError) {
      ++d.crc_errors;
    } else {
      ++d.other_errors;
    }
    if (!usable) {
      d.stale = true;
      ++d.consecutive_misses;
      all = false;
    }
  }
  return all;
}

void DriverController::read_status() noexcept {
  if (status_bytes_ == 0) return;
  bus_.sync_read(addr_status_, status_bytes_, ids_.data(), ids_.size(), status_.data(), status_replies_.data());
  for (int j = 0; j < n_; ++j) {
    const dxl::ServoReply& r = status_replies_[j];
    if (!dxl::has_data(r.status)) continue;
    const std::uint8_t* p = &status_[j * status_bytes_];
    diag_[j].voltage_v = dxl::voltage_to_volts(static_cast<std::uint16_t>(dxl::get_le(p + voltage_offset_, voltage_bytes_, false)), scales_);
    diag_[j].temperature_c = p[temperature_offset_];
    if (r.status == dxl::Status::kHardwareError || (r.error & dxl::kAlertBit)) diag_[j].hardware_error = true;
  }
}

void DriverController::check_hardware_errors() noexcept {
  int first = -1;
  for (int j = 0; j < n_; ++j) {
    ServoDiagnostics& d = diag_[j];
    if (!d.hardware_error) continue;
    if (!hw_bits_known_[j]) {
      std::uint8_t bits = 0, error = 0;
      if (dxl::has_data(bus_.read(ids_[j], addr_hw_error_, 1, &bits, &error))) {
        d.hardware_error_bits = bits;
        hw_bits_known_[j] = 1;
      }
    }
    if (first < 0) first = j;
  }
  const DriverState s = state();
  if (first < 0 || (s != DriverState::kRunning && s != DriverState::kHolding)) return;
  Message m{};
  copy_message(m, "hardware error:");
  for (int j = 0; j < n_; ++j) {
    if (!diag_[j].hardware_error) continue;
    char bits[96];
    describe_bits(diag_[j].hardware_error_bits, bits, sizeof bits);
    append(m, " servo %d (joint_%d): %s;", ids_[j], j + 1, bits);
  }
  append(m, " reboot it (driver/reboot_servo), then enable torque");
  enter_fault(m.data());
}

void DriverController::step_cpg(double dt_s) noexcept {
  cpg_.step(dt_s);
  if (!cpg_.state_finite())
    enter_fault("CPG state not finite (an oscillator's phase, amplitude or bias is NaN or infinite): locomotion stopped");
}

void DriverController::compute_goals(double dt_s) noexcept {
  const bool running = state() == DriverState::kRunning;
  const Eigen::VectorXd& target = running ? (trajectory_.running() ? trajectory_goal_ : cpg_.output()) : hold_rad_;
  const double max_move = config_.max_joint_velocity_rad_s * dt_s;
  for (int j = 0; j < n_; ++j) {
    const double t = std::isfinite(target[j]) ? target[j] : goal_rad_[j];
    const double move = std::clamp(t - goal_rad_[j], -max_move, max_move);
    goal_rad_[j] = std::clamp(goal_rad_[j] + move, lo_rad_[j], hi_rad_[j]);
  }
  goals_from_rad();
}

void DriverController::goals_from_rad() noexcept {
  for (int j = 0; j < n_; ++j) {
    std::int32_t ticks = diag_[j].goal_ticks;
    if (joint_rad_to_ticks(j, goal_rad_[j], &ticks)) diag_[j].goal_ticks = clamp_goal(j, ticks);
    diag_[j].goal_ticks = clamp_goal(j, diag_[j].goal_ticks);
    dxl::put_le(&goals_[j * dxl::kGoalPositionBytes], dxl::kGoalPositionBytes, diag_[j].goal_ticks);
  }
}

bool DriverController::write_goals() noexcept {
  return bus_.sync_write(dxl::kGoalPositionAddress, dxl::kGoalPositionBytes, ids_.data(), ids_.size(),
                         goals_.data()) == dxl::Status::kOk;
}

bool DriverController::write_torque(bool on) noexcept {
  std::fill(torque_.begin(), torque_.end(), on ? 1 : 0);
  return bus_.sync_write(addr_torque_, 1, ids_.data(), ids_.size(), torque_.data()) == dxl::Status::kOk;
}

void DriverController::run_kinematics() noexcept { kinematics_.compute(base_p_, base_q_, position_, kin_state_); }

void DriverController::hold_here() noexcept {
  hold_rad_ = position_.cwiseMax(lo_rad_).cwiseMin(hi_rad_);
  goal_rad_ = hold_rad_;
}

void DriverController::hold_for(HoldReason reason) noexcept {
  hold_here();
  hold_reason_ = reason;
  set_state(DriverState::kHolding);
}

void DriverController::enter_fault(const char* reason) noexcept {
  if (state() == DriverState::kFault) return;
  copy_message(fault_reason_, reason);
  last_fault_ = fault_reason_;
  if (config_.fault_action == SafeAction::kHold) {
    hold_here();
  } else {
    write_torque(false);
  }
  set_state(DriverState::kFault);
}

// ---------------------------------------------------------------------------------------------
// Gait

void DriverController::apply_gait() noexcept {
  effective_ = nominal_;
  if (gated_) effective_.amplitude.setZero();
  cpg_.apply(effective_);
}

bool DriverController::start_locomotion() noexcept {
  // Restart the oscillators at the held posture (amplitudes zero, biases = posture): the goals
  // continue from where the robot is and move to the gait through the CPG's smooth dynamics.
  if (!cpg_.restart(cpg_.phases(), zeros_, hold_rad_)) {
    enter_fault("CPG state not finite: the oscillators cannot restart from their phases; locomotion stopped");
    return false;
  }
  gated_ = config_.require_pose && !pose_fresh_;
  apply_gait();
  hold_reason_ = HoldReason::kNone;
  set_state(DriverState::kRunning);
  return true;
}

void DriverController::take_gait() noexcept {
  if (!gait_mutex_.try_lock()) return;
  const bool pending = gait_pending_;
  if (pending) {
    nominal_ = pending_gait_;
    gait_name_ = pending_gait_name_;
    gait_pending_ = false;
  }
  gait_mutex_.unlock();
  if (!pending) return;
  last_command_t_s_ = t_s_;  // a repeated command is the caller's heartbeat: it refreshes the lifetime
  trajectory_yields_to_gait();
  const DriverState s = state();
  if (s == DriverState::kHolding) {
    if (!start_locomotion()) return;
  } else if (s == DriverState::kRunning) {
    apply_gait();
  } else {
    return;  // torque off or fault: the command was accepted just before; it is dropped
  }
  ++commands_applied_;
}

std::string DriverController::command_gait(const GaitCommandRequest& command) {
  std::lock_guard<std::mutex> lock(resolver_mutex_);
  std::string why;
  const DriverState s = state();
  if (s == DriverState::kStopped) {
    why = "torque is off: enable it first (driver/enable_torque)";
  } else if (s == DriverState::kFault) {
    why = "locomotion is stopped by a fault (see /diagnostics): recover with driver/enable_torque";
  } else {
    GaitParameters out;
    why = resolver_.resolve(command, out);
    if (why.empty()) {
      std::lock_guard<std::mutex> g(gait_mutex_);
      pending_gait_ = std::move(out);
      copy_message(pending_gait_name_, resolver_.current_gait().c_str());
      gait_pending_ = true;
    }
  }
  if (why.empty()) {
    ++commands_accepted_;
  } else {
    ++commands_refused_;
    last_refusal_ = why;
  }
  return why;
}

std::string DriverController::last_refusal() const {
  std::lock_guard<std::mutex> lock(resolver_mutex_);
  return last_refusal_;
}

std::string DriverController::commanded_gait() const {
  std::lock_guard<std::mutex> lock(resolver_mutex_);
  return resolver_.current_gait();
}

// ---------------------------------------------------------------------------------------------
// Base pose

bool DriverController::set_base_pose(double t_s, const Eigen::Vector3d& position,
                                     const Eigen::Quaterniond& orientation) noexcept {
  Eigen::Quaterniond unit = Eigen::Quaterniond::Identity();
  const PoseRefusal why = check_base_pose(t_s, position, orientation, config_.pose_workspace_m,
                                          config_.quaternion_norm_tolerance, &unit);
  std::lock_guard<std::mutex> lock(pose_mutex_);
  if (why != PoseRefusal::kNone) {
    ++poses_refused_;
    describe_pose_refusal(why, t_s, position, orientation, config_.pose_workspace_m, config_.quaternion_norm_tolerance,
                          pending_pose_refusal_.data(), pending_pose_refusal_.size());
    return false;
  }
  pending_p_ = position;
  pending_q_ = unit;
  pending_pose_t_s_ = t_s;
  ++pose_seq_;
  return true;
}

void DriverController::take_pose(double t_s) noexcept {
  if (pose_mutex_.try_lock()) {
    if (pose_seq_ != pose_seq_seen_) {
      pose_seq_seen_ = pose_seq_;
      base_p_ = pending_p_;
      base_q_ = pending_q_;
      pose_t_s_ = pending_pose_t_s_;
      pose_received_ = true;
    }
    pose_refusal_ = pending_pose_refusal_;
    pose_mutex_.unlock();
  }
  pose_fresh_ = pose_received_ && (t_s - pose_t_s_) <= config_.pose_timeout_s;
}

// ---------------------------------------------------------------------------------------------
// Requests

std::uint64_t DriverController::post(DriverRequest request, std::uint8_t servo_id) {
  std::lock_guard<std::mutex> lock(request_mutex_);
  pending_request_.ticket = next_ticket_++;
  pending_request_.type = request;
  pending_request_.id = servo_id;
  return pending_request_.ticket;
}

bool DriverController::take_result(std::uint64_t ticket, RequestResult* out) {
  if (done_ticket_.load(std::memory_order_acquire) != ticket) return false;
  out->success = done_success_;
  out->message = done_message_.data();
  return true;
}

RequestResult DriverController::call(DriverRequest request, std::uint8_t servo_id, double timeout_s) {
  std::lock_guard<std::mutex> serial(call_mutex_);
  const std::uint64_t ticket = post(request, servo_id);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  RequestResult result;
  while (!take_result(ticket, &result)) {
    if (std::chrono::steady_clock::now() > deadline) {
      std::lock_guard<std::mutex> lock(request_mutex_);
      if (pending_request_.ticket == ticket) {  // not taken: withdraw it
        pending_request_.ticket = 0;
        return {false, "the control loop did not run the request within " + std::to_string(timeout_s) + " s"};
      }
      // Taken: the loop is running it and will finish within its cycle.
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return result;
}

void DriverController::take_request() noexcept {
  if (!request_mutex_.try_lock()) return;
  const PendingRequest r = pending_request_;
  pending_request_.ticket = 0;
  request_mutex_.unlock();
  if (r.ticket != 0) run_request(r);
}

void DriverController::finish_request(std::uint64_t ticket, bool success, const char* fmt, ...) noexcept {
  done_success_ = success;
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(done_message_.data(), done_message_.size(), fmt, args);
  va_end(args);
  done_ticket_.store(ticket, std::memory_order_release);
}

void DriverController::run_request(const PendingRequest& r) noexcept {
  const DriverState s = state();
  switch (r.type) {
    case DriverRequest::kEnableTorque: {
      if (s == DriverState::kHolding || s == DriverState::kRunning) {
        finish_request(r.ticket, true, "torque already on (%s)", to_string(s));
        return;
      }
      Message why{};
      if (enable_torque(why)) {
        finish_request(r.ticket, true, "torque on, holding the posture: send a gait command to move");
      } else {
        finish_request(r.ticket, false, "%s", why.data());
      }
      return;
    }
    case DriverRequest::kDisableTorque: {
      const bool ok = write_torque(false);
      fault_reason_[0] = '\0';
      set_state(DriverState::kStopped);
      if (ok) {
        finish_request(r.ticket, true, "torque off");
      } else {
        finish_request(r.ticket, false, "torque off sent but the bus failed: check the servos");
      }
      return;
    }
    case DriverRequest::kHold: {
      if (s == DriverState::kRunning) {
        hold_for(HoldReason::kHoldRequest);
        finish_request(r.ticket, true, "holding the posture: send a gait command to move");
      } else if (s == DriverState::kHolding) {
        finish_request(r.ticket, true, "already holding");
      } else {
        finish_request(r.ticket, false, "cannot hold: %s",
                       s == DriverState::kStopped ? "torque is off" : "in a fault (see /diagnostics)");
      }
      return;
    }
    case DriverRequest::kRebootServo: {
      const int j = joint_of(r.id);
      if (j < 0) {
        finish_request(r.ticket, false, "no servo with ID %d on this bus", r.id);
        return;
      }
      if (s == DriverState::kRunning || s == DriverState::kHolding) {
        finish_request(r.ticket, false,
                       "refused while torque is on (%s): disable torque first, or reboot after a fault", to_string(s));
        return;
      }
      std::uint8_t error = 0;
      // The status packet goes out before the servo restarts: it still carries the alert bit.
      const dxl::Status st = bus_.reboot(r.id, &error);
      if (!dxl::has_data(st)) {
        finish_request(r.ticket, false, "reboot of servo %d failed: %s", r.id, dxl::to_string(st));
        return;
      }
      diag_[j].hardware_error = false;
      diag_[j].hardware_error_bits = 0;
      hw_bits_known_[j] = 0;
      finish_request(r.ticket, true, "servo %d (joint_%d) rebooted (torque off): enable torque to resume", r.id, j + 1);
      return;
    }
  }
}

bool DriverController::enable_torque(Message& why) noexcept {
  why[0] = '\0';
  bool ok = read_feedback();
  bool io = false;
  for (int j = 0; j < n_; ++j)
    io = io || replies_[j].status == dxl::Status::kIoError || replies_[j].status == dxl::Status::kNotOpen;
  if (!ok && io && reconnect_) {
    std::string reason;
    bool reopened = false;
    try {
      reopened = reconnect_(&reason);
    } catch (const std::exception& e) {
      reason = e.what();
    }
    if (!reopened) {
      std::snprintf(why.data(), why.size(), "cannot enable torque: the bus has an I/O error and reopening failed: %s",
                    reason.c_str());
      return false;
    }
    ok = read_feedback();
  }
  if (!ok) {
    bool all_same = true;
    for (int j = 0; j < n_; ++j) all_same = all_same && diag_[j].stale && replies_[j].status == replies_[0].status;
    if (all_same) {
      std::snprintf(why.data(), why.size(), "cannot enable torque, no feedback from any servo (%s)",
                    dxl::to_string(replies_[0].status));
      return false;
    }
    copy_message(why, "cannot enable torque, no feedback from:");
    for (int j = 0; j < n_; ++j) {
      if (diag_[j].stale) append(why, " servo %d (joint_%d) %s;", ids_[j], j + 1, dxl::to_string(replies_[j].status));
    }
    return false;
  }
  check_hardware_errors();  // reads the bits of any alerting servo (no state change: torque is off)
  for (int j = 0; j < n_; ++j) {
    const ServoDiagnostics& d = diag_[j];
    if (d.hardware_error) {
      char bits[96];
      describe_bits(d.hardware_error_bits, bits, sizeof bits);
      append(why, "%sservo %d (joint_%d) has a hardware error (%s): reboot it first", why[0] ? "; " : "", ids_[j],
             j + 1, bits);
    } else if (d.present_ticks < d.min_ticks || d.present_ticks > d.max_ticks) {
      append(why, "%sservo %d (joint_%d) at %.1f deg is outside its limits [%.1f, %.1f] deg: move it by hand first",
             why[0] ? "; " : "", ids_[j], j + 1, deg(position_[j]), deg(lo_rad_[j]), deg(hi_rad_[j]));
    }
  }
  if (why[0]) return false;
  hold_here();
  goals_from_rad();
  if (!write_goals() || !write_torque(true)) {
    copy_message(why, "cannot enable torque: the bus did not take the writes");
    write_torque(false);
    return false;
  }
  // Sync writes have no reply: read torque_enable back.
  dxl::Status st = bus_.sync_read(addr_torque_, 1, ids_.data(), ids_.size(), status_.data(), status_replies_.data());
  (void)st;
  for (int j = 0; j < n_; ++j) {
    if (!dxl::has_data(status_replies_[j].status) || status_[j] != 1)
      append(why, "%sservo %d (joint_%d) did not confirm torque on (%s)", why[0] ? "; " : "", ids_[j], j + 1,
             dxl::has_data(status_replies_[j].status) ? "torque_enable 0" : dxl::to_string(status_replies_[j].status));
  }
  if (why[0]) {
    write_torque(false);
    return false;
  }
  consecutive_failed_ = 0;
  fault_reason_[0] = '\0';
  hold_reason_ = HoldReason::kTorqueEnabled;
  set_state(DriverState::kHolding);
  return true;
}

// ---------------------------------------------------------------------------------------------
// Snapshot

DriverSnapshot DriverController::make_snapshot() const {
  DriverSnapshot s;
  s.position_rad = s.velocity_rad_s = s.effort_a = s.goal_rad = Eigen::VectorXd::Zero(n_);
  s.servos.assign(static_cast<std::size_t>(n_), ServoDiagnostics{});
  return s;
}

void DriverController::fill_snapshot(DriverSnapshot& out) const noexcept {
  out.t_s = t_s_;
  out.cycle = cycle_;
  out.state = state();
  out.fault_reason = fault_reason_;
  out.last_fault = last_fault_;
  out.gait = gait_name_;
  out.pose_received = pose_received_;
  out.pose_fresh = pose_fresh_;
  out.locomotion_gated = out.state == DriverState::kRunning && gated_ && !trajectory_.running();
  out.hold_reason = out.state == DriverState::kHolding ? hold_reason_ : HoldReason::kNone;
  out.command_age_s = t_s_ - last_command_t_s_;
  out.pose_refusal = pose_refusal_;
  out.position_rad = position_;
  out.velocity_rad_s = velocity_;
  out.effort_a = effort_;
  out.goal_rad = goal_rad_;
  if (out.servos.size() == diag_.size()) std::copy(diag_.begin(), diag_.end(), out.servos.begin());
  out.base_position = base_p_;
  out.base_orientation = base_q_;
  out.com = kin_state_.com;
  out.com_orientation = Eigen::Quaterniond(kin_state_.vc_rotation);
  out.bbox_span = kin_state_.bbox_span;
  out.bus = bus_.counters();
  out.failed_cycles = failed_cycles_;
  out.consecutive_failed_cycles = consecutive_failed_;
  out.commands_applied = commands_applied_;
  out.poses_refused = poses_refused_.load();
  out.trajectory = trajectory_.progress();
}

// ---------------------------------------------------------------------------------------------
// ---- Joint trajectory execution (driver::TrajectorySource as the goal source; issue 11) ----

std::string DriverController::command_trajectory(const driver::JointTrajectoryRequest& request) {
  std::string why;
  const DriverState s = state();
  if (s == DriverState::kStopped || s == DriverState::kFault) {
    why = s == DriverState::kStopped ? "torque is off: enable it first (driver/enable_torque)"
                                     : "in a fault (see /diagnostics): recover with driver/enable_torque";
    const std::string more = trajectory_.check(request);
    if (!more.empty()) why += "\n" + more;
  } else {
    why = trajectory_.submit(request);
  }
  if (why.empty()) {
    ++trajectories_accepted_;
  } else {
    ++trajectories_refused_;
    std::lock_guard<std::mutex> lock(trajectory_refusal_mutex_);
    last_trajectory_refusal_ = why;
  }
  return why;
}

std::string DriverController::last_trajectory_refusal() const {
  std::lock_guard<std::mutex> lock(trajectory_refusal_mutex_);
  return last_trajectory_refusal_;
}

void DriverController::take_trajectory(double t_s) noexcept {
  const DriverState s = state();
  const bool allowed = s == DriverState::kHolding || s == DriverState::kRunning;
  // From the goals commanded now (continuous: no step in the command); refused at take: untouched.
  if (!trajectory_.take(t_s, goal_rad_, allowed) || !trajectory_.running()) return;
  hold_reason_ = HoldReason::kNone;
  set_state(DriverState::kRunning);  // the CPG is not stepped while the trajectory runs
}

void DriverController::step_trajectory(double t_s) noexcept {
  if (!trajectory_.running()) return;
  const DriverState s = state();
  if (s != DriverState::kRunning) {
    trajectory_.abort(s == DriverState::kFault     ? driver::TrajectoryAbort::kFault
                      : s == DriverState::kStopped ? driver::TrajectoryAbort::kTorqueOff
                                                   : driver::TrajectoryAbort::kHoldRequest);
    return;
  }
  if (trajectory_.update(t_s, trajectory_goal_)) return;
  hold_rad_ = trajectory_.final_rad().cwiseMax(lo_rad_).cwiseMin(hi_rad_);  // done: hold the last point
  hold_reason_ = HoldReason::kTrajectoryDone;
  set_state(DriverState::kHolding);
}

void DriverController::trajectory_yields_to_gait() noexcept {
  if (!trajectory_.running()) return;
  trajectory_.abort(driver::TrajectoryAbort::kGaitCommand);
  if (state() == DriverState::kRunning) {
    hold_rad_ = goal_rad_;  // locomotion starts from the goals commanded now
    set_state(DriverState::kHolding);
  }
}
// Hooks elsewhere in this file: the constructor and start() (limits), update() (take_trajectory,
// no command lifetime or CPG step while it runs, step_trajectory), compute_goals() (its goals),
// take_gait() (trajectory_yields_to_gait), shutdown() and fill_snapshot().
// ---- end of joint trajectory execution ----

}  // namespace snake_autonomy::core
