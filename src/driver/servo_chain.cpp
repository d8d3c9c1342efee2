#include "snake_autonomy/driver/servo_chain.hpp"

#include <algorithm>
#include <sstream>

#include "snake_autonomy/dynamixel/conversions.hpp"
#include "snake_autonomy/dynamixel/protocol.hpp"

namespace snake_autonomy::driver {

namespace dxl = snake_autonomy::dynamixel;

namespace {

constexpr std::uint8_t kPositionControlMode = 3;

double deg(double rad) { return rad * 180.0 / M_PI; }

}  // namespace

std::vector<std::string> ServoChain::check_table(const dxl::ControlTable& table) {
  std::vector<std::string> errors;
  const auto* voltage = table.find("present_input_voltage");
  const auto* temperature = table.find("present_temperature");
  if (voltage && temperature) {
    const int lo = std::min(voltage->address, temperature->address);
    const int hi = std::max(voltage->address + voltage->size, temperature->address + temperature->size);
    if (hi - lo > 16)
      errors.push_back("control table: present_input_voltage and present_temperature are " + std::to_string(hi - lo) +
                       " bytes apart (at most 16 for one status read)");
  }
  return errors;
}

ServoChain::ServoChain(const core::RobotModel& model, const dxl::ControlTable& table, dxl::ServoBus& bus,
                       const DriverConfig& config)
    : bus_(bus),
      n_(model.num_joints),
      joint_lower_rad_(model.joint_lower_rad),
      joint_upper_rad_(model.joint_upper_rad),
      fast_sync_read_(config.fast_sync_read),
      plausible_margin_ticks_(config.plausible_margin_ticks),
      return_delay_time_us_(config.return_delay_time_us),
      table_(table),
      scales_(table.unit_scales()) {
  const auto* voltage = table.find("present_input_voltage");
  const auto* temperature = table.find("present_temperature");
  if (voltage && temperature) {
    const int lo = std::min(voltage->address, temperature->address);
    const int hi = std::max(voltage->address + voltage->size, temperature->address + temperature->size);
    addr_status_ = static_cast<std::uint16_t>(lo);
    status_bytes_ = static_cast<std::uint16_t>(hi - lo);
    voltage_offset_ = static_cast<std::uint16_t>(voltage->address - lo);
    voltage_bytes_ = voltage->size;
    temperature_offset_ = static_cast<std::uint16_t>(temperature->address - lo);
  }
  addr_torque_ = table.at("torque_enable").address;
  addr_hw_error_ = table.at("hardware_error_status").address;
  addr_mode_ = table.at("operating_mode").address;
  addr_return_delay_ = table.at("return_delay_time").address;
  addr_min_pos_ = table.at("min_position_limit").address;
  addr_max_pos_ = table.at("max_position_limit").address;

  const auto nz = static_cast<std::size_t>(n_);
  for (int id : model.servos.ids) ids_.push_back(static_cast<std::uint8_t>(id));
  tx_ = Transmission::for_robot(model, table);
  feedback_.assign(nz * dxl::kFeedbackBytes, 0);
  status_.assign(nz * std::max<std::uint16_t>(status_bytes_, 1), 0);
  goals_.assign(nz * dxl::kGoalPositionBytes, 0);
  torque_.assign(nz, 0);
  replies_.assign(nz, dxl::ServoReply{});
  status_replies_.assign(nz, dxl::ServoReply{});
  hw_bits_known_.assign(nz, 0);
  position_ = velocity_ = effort_ = lo_rad_ = hi_rad_ = Eigen::VectorXd::Zero(n_);
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
}

void ServoChain::set_limits(int j, std::int32_t servo_min, std::int32_t servo_max) noexcept {
  servo_min_ticks_[j] = servo_min;
  servo_max_ticks_[j] = servo_max;
  // Joint limits in ticks, rounded inwards: the clamp never lets a goal out of the joint's range.
  std::int32_t lo = 0, hi = 0;
  tx_[j].joint_range_to_ticks(joint_lower_rad_[j], joint_upper_rad_[j], &lo, &hi);
  auto& d = diag_[j];
  d.min_ticks = std::max(lo, servo_min);
  d.max_ticks = std::min(hi, servo_max);
  const double a = tx_[j].ticks_to_joint_rad(d.min_ticks), b = tx_[j].ticks_to_joint_rad(d.max_ticks);
  lo_rad_[j] = std::min(a, b);
  hi_rad_[j] = std::max(a, b);
}

std::string ServoChain::servo_name(int j) const {
  return "servo " + std::to_string(ids_[j]) + " (joint_" + std::to_string(j + 1) + ")";
}

int ServoChain::joint_of(std::uint8_t id) const noexcept {
  for (int j = 0; j < n_; ++j) {
    if (ids_[j] == id) return j;
  }
  return -1;
}

// ---------------------------------------------------------------------------------------------
// Start

ChainStartReport ServoChain::start() {
  ChainStartReport report;
  auto& problems = report.problems;
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
    const int delay_us = settle_return_delay(j, servo_name(j), report);
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
        m << servo_name(j) << ": joint limits [" << deg(joint_lower_rad_[j]) << ", " << deg(joint_upper_rad_[j])
          << "] deg do not overlap the servo's position limits [" << mn << ", " << mx << "] ticks";
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
      report.hardware_errors.push_back(j);
    }
  }
  bus_.set_return_delay_s(max_delay_us * 1e-6);
  if (problems.empty() && !read()) {
    for (int j = 0; j < n_; ++j) {
      if (diag_[j].stale)
        problems.push_back(servo_name(j) + ": no feedback (" + dxl::to_string(replies_[j].status) + ")");
    }
  }
  return report;
}

int ServoChain::settle_return_delay(int j, const std::string& name, ChainStartReport& report) {
  const std::uint8_t id = ids_[j];
  std::uint8_t units = 0, error = 0;
  const dxl::Status s = bus_.read(id, addr_return_delay_, 1, &units, &error);
  if (!dxl::has_data(s)) {
    report.problems.push_back(name + ": reading return_delay_time failed (" + dxl::to_string(s) + ")");
    return 0;
  }
  const int want_us = return_delay_time_us_;
  if (want_us < 0 || units * 2 == want_us) return units * 2;
  const std::uint8_t want = static_cast<std::uint8_t>(want_us / 2);
  const dxl::Status w = bus_.write(id, addr_return_delay_, &want, 1, &error);
  std::uint8_t back = units;
  if (w == dxl::Status::kOk && dxl::has_data(bus_.read(id, addr_return_delay_, 1, &back, &error)) && back == want) {
    report.notes.push_back(name + ": Return Delay Time " + std::to_string(units * 2) + " us -> " +
                           std::to_string(want_us) + " us (written to the servo's EEPROM)");
    return want_us;
  }
  // An XH540 refuses EEPROM writes while its torque is on: carry on with the slower replies.
  report.notes.push_back(name + ": Return Delay Time is " + std::to_string(units * 2) + " us, writing " +
                         std::to_string(want_us) + " us failed (" +
                         (w == dxl::Status::kServoError ? std::string("EEPROM locked: torque is on; restart the driver "
                                                                      "with the servo's torque off")
                                                        : std::string(dxl::to_string(w))) +
                         "); reply deadlines allow for " + std::to_string(units * 2) + " us");
  return units * 2;
}

// ---------------------------------------------------------------------------------------------
// Read

bool ServoChain::read() noexcept {
  const dxl::Status status = fast_sync_read_
                                 ? bus_.fast_sync_read(dxl::kFeedbackAddress, dxl::kFeedbackBytes, ids_.data(),
                                                       ids_.size(), feedback_.data(), replies_.data())
                                 : bus_.sync_read(dxl::kFeedbackAddress, dxl::kFeedbackBytes, ids_.data(), ids_.size(),
                                                  feedback_.data(), replies_.data());
  (void)status;  // per-servo replies say everything
  bool all = true;
  for (int j = 0; j < n_; ++j) {
    ServoDiagnostics& d = diag_[j];
    const dxl::ServoReply& r = replies_[j];
    bool usable = dxl::has_data(r.status);
    if (usable) {
      const dxl::ServoFeedback fb = dxl::decode_feedback(&feedback_[j * dxl::kFeedbackBytes], scales_);
      const std::int64_t margin = plausible_margin_ticks_;
      if (fb.position_ticks < servo_min_ticks_[j] - margin || fb.position_ticks > servo_max_ticks_[j] + margin) {
        ++d.implausible;
        usable = false;
      } else {
        d.present_ticks = fb.position_ticks;
        position_[j] = tx_[j].ticks_to_joint_rad(fb.position_ticks);
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

void ServoChain::read_status() noexcept {
  if (status_bytes_ == 0) return;
  bus_.sync_read(addr_status_, status_bytes_, ids_.data(), ids_.size(), status_.data(), status_replies_.data());
  for (int j = 0; j < n_; ++j) {
    const dxl::ServoReply& r = status_replies_[j];
    if (!dxl::has_data(r.status)) continue;
    const std::uint8_t* p = &status_[j * status_bytes_];
    diag_[j].voltage_v = dxl::voltage_to_volts(
        static_cast<std::uint16_t>(dxl::get_le(p + voltage_offset_, voltage_bytes_, false)), scales_);
    diag_[j].temperature_c = p[temperature_offset_];
    if (r.status == dxl::Status::kHardwareError || (r.error & dxl::kAlertBit)) diag_[j].hardware_error = true;
  }
}

bool ServoChain::read_hardware_errors() noexcept {
  bool any = false;
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
    any = true;
  }
  return any;
}

bool ServoChain::io_error() const noexcept {
  for (int j = 0; j < n_; ++j) {
    if (replies_[j].status == dxl::Status::kIoError || replies_[j].status == dxl::Status::kNotOpen) return true;
  }
  return false;
}

bool ServoChain::all_failed_alike(dxl::Status* status) const noexcept {
  for (int j = 0; j < n_; ++j) {
    if (!diag_[j].stale || replies_[j].status != replies_[0].status) return false;
  }
  *status = replies_[0].status;
  return true;
}

// ---------------------------------------------------------------------------------------------
// Write

void ServoChain::clamp(Eigen::Ref<Eigen::VectorXd> rad) const noexcept {
  rad = rad.cwiseMax(lo_rad_).cwiseMin(hi_rad_);
}

bool ServoChain::write(Eigen::Ref<Eigen::VectorXd> goal_rad) noexcept {
  set_goal(goal_rad);
  return bus_.sync_write(dxl::kGoalPositionAddress, dxl::kGoalPositionBytes, ids_.data(), ids_.size(), goals_.data()) ==
         dxl::Status::kOk;
}

void ServoChain::set_goal(Eigen::Ref<Eigen::VectorXd> goal_rad) noexcept {
  for (int j = 0; j < n_; ++j) {
    ServoDiagnostics& d = diag_[j];
    if (std::isfinite(goal_rad[j])) goal_rad[j] = std::clamp(goal_rad[j], lo_rad_[j], hi_rad_[j]);
    std::int32_t ticks = d.goal_ticks;
    if (tx_[j].joint_rad_to_ticks(goal_rad[j], &ticks)) d.goal_ticks = ticks;
    d.goal_ticks = dxl::clamp_ticks(d.goal_ticks, d.min_ticks, d.max_ticks);
    dxl::put_le(&goals_[j * dxl::kGoalPositionBytes], dxl::kGoalPositionBytes, d.goal_ticks);
  }
}

bool ServoChain::write_torque(bool on) noexcept {
  std::fill(torque_.begin(), torque_.end(), on ? 1 : 0);
  return bus_.sync_write(addr_torque_, 1, ids_.data(), ids_.size(), torque_.data()) == dxl::Status::kOk;
}

bool ServoChain::confirm_torque(bool on, Message& why) noexcept {
  bus_.sync_read(addr_torque_, 1, ids_.data(), ids_.size(), status_.data(), status_replies_.data());
  bool all = true;
  for (int j = 0; j < n_; ++j) {
    const bool answered = dxl::has_data(status_replies_[j].status);
    if (answered && status_[j] == (on ? 1 : 0)) continue;
    all = false;
    append(why, "%sservo %d (joint_%d) did not confirm torque %s (%s)", why[0] ? "; " : "", ids_[j], j + 1,
           on ? "on" : "off",
           answered ? (on ? "torque_enable 0" : "torque_enable 1") : dxl::to_string(status_replies_[j].status));
  }
  return all;
}

dxl::Status ServoChain::reboot(std::uint8_t id) noexcept {
  const int j = joint_of(id);
  std::uint8_t error = 0;
  const dxl::Status st = bus_.reboot(id, &error);
  if (j >= 0 && dxl::has_data(st)) {
    diag_[j].hardware_error = false;
    diag_[j].hardware_error_bits = 0;
    hw_bits_known_[j] = 0;
  }
  return st;
}

// ---------------------------------------------------------------------------------------------
// Descriptions (no allocation)

void ServoChain::describe_bits(std::uint8_t bits, char* out, std::size_t size) const noexcept {
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

void ServoChain::describe_hardware_errors(Message& out) const noexcept {
  for (int j = 0; j < n_; ++j) {
    if (!diag_[j].hardware_error) continue;
    char bits[96];
    describe_bits(diag_[j].hardware_error_bits, bits, sizeof bits);
    append(out, " servo %d (joint_%d): %s;", ids_[j], j + 1, bits);
  }
}

void ServoChain::describe_stale(Message& out) const noexcept {
  for (int j = 0; j < n_; ++j) {
    if (diag_[j].stale)
      append(out, " servo %d (joint_%d) %s for %u cycles;", ids_[j], j + 1, dxl::to_string(replies_[j].status),
             diag_[j].consecutive_misses);
  }
}

}  // namespace snake_autonomy::driver
