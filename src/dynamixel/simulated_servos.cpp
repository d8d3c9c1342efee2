#include "snake_autonomy/dynamixel/simulated_servos.hpp"

#include <algorithm>
#include <cstring>

namespace snake_autonomy::dynamixel {
namespace {

constexpr const char* kFaultNames[kNumReplyFaults] = {"drop_reply", "corrupt_crc", "truncate_reply", "garbage_before",
                                                      "garbage_data"};
constexpr std::uint8_t kGarbage[] = {0x00, 0x13, 0xFF, 0xFF, 0xFD, 0xFD};
constexpr std::size_t kRxBytes = 4 * kMaxPacketBytes;

std::uint16_t u16(const std::uint8_t* p) noexcept { return static_cast<std::uint16_t>(p[0] | (p[1] << 8)); }

// The servo error number of a read of `length` bytes at `address` (0: a legal read).
std::uint8_t read_error(std::uint16_t address, std::uint16_t length) noexcept {
  if (length == 0) return servo_error::kDataLengthError;
  return address + length > SimulatedServos::kMemoryBytes ? servo_error::kDataRangeError : 0;
}

}  // namespace

const char* to_string(ReplyFault kind) noexcept {
  const auto i = static_cast<std::size_t>(kind);
  return i < kNumReplyFaults ? kFaultNames[i] : "unknown";
}

bool reply_fault_from_string(const std::string& name, ReplyFault* kind) noexcept {
  for (std::size_t i = 0; i < kNumReplyFaults; ++i) {
    if (name == kFaultNames[i]) {
      if (kind) *kind = static_cast<ReplyFault>(i);
      return true;
    }
  }
  return false;
}

SimulatedServos::SimulatedServos(const ControlTable& table, const std::vector<std::uint8_t>& ids)
    : table_(table), ids_(ids) {
  table_.validate_or_throw();
  index_.fill(-1);
  const auto place = [this](const char* name) {
    const auto& e = table_.at(name);
    if (e.address + e.size > kMemoryBytes) throw ConfigError(std::string(name) + ": address past the memory");
    return Entry{e.address, e.size, e.is_signed};
  };
  torque_ = place("torque_enable");
  hw_error_ = place("hardware_error_status");
  goal_ = place("goal_position");
  min_pos_ = place("min_position_limit");
  max_pos_ = place("max_position_limit");
  firmware_ = place("firmware_version");
  present_pos_ = place("present_position");
  present_vel_ = place("present_velocity");
  present_cur_ = place("present_current");
  present_volt_ = place("present_input_voltage");
  present_temp_ = place("present_temperature");
  servos_.reserve(ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (ids[i] > kMaxServoId) {
      throw ConfigError("ids[" + std::to_string(i) + "]: " + std::to_string(ids[i]) + " is not in 0..252");
    }
    if (index_[ids[i]] >= 0) {
      throw ConfigError("ids[" + std::to_string(i) + "]: " + std::to_string(ids[i]) + " is repeated");
    }
    Servo s;
    s.id = ids[i];
    for (const auto& e : table_.entries) {
      if (e.address + e.size <= kMemoryBytes) put_le(&s.memory[e.address], e.size, e.default_value);
    }
    if (const auto* e = table_.find("id")) put_le(&s.memory[e->address], e->size, ids[i]);
    index_[ids[i]] = static_cast<int>(servos_.size());
    servos_.push_back(s);
  }
  rx_.assign(kRxBytes, 0);
  // Worst case of one handle(): a full receive buffer of 10-byte packets, each answered by every
  // servo with a packet of at most kMaxPacketBytes is far beyond need; bound it by what one packet
  // can ask (every servo answers once) times the packets that fit in the buffer, capped.
  out_.assign((servos_.size() + 1) * (kMaxPacketBytes + sizeof kGarbage) * 4, 0);
}

const SimulatedServos::Servo& SimulatedServos::servo_or_throw(std::uint8_t id) const {
  if (index_[id] < 0) throw ConfigError("id: " + std::to_string(id) + " is not on this bus");
  return servos_[static_cast<std::size_t>(index_[id])];
}

// ------------------------------------------------------------------------------------------------
// bytes in, bytes out

std::size_t SimulatedServos::handle(const std::uint8_t* in, std::size_t size, bool latest_only) noexcept {
  out_size_ = 0;
  stats_.bytes_received += size;
  std::size_t used = 0;
  for (;;) {
    const std::size_t take = std::min(size - used, kRxBytes - rx_size_);
    if (take) std::memcpy(&rx_[rx_size_], in + used, take);
    rx_size_ += take;
    used += take;
    while (rx_size_ > 0) {
      Packet p;
      const ParseResult r = parse_packet(rx_.data(), rx_size_, scratch_.data(), scratch_.size(), &p);
      std::size_t consumed = std::min(r.consumed, rx_size_);
      if (r.status == ParseStatus::kIncomplete && consumed == 0 && rx_size_ == kRxBytes) consumed = 1;  // never fits
      if (r.status != ParseStatus::kIncomplete) {
        refreshed_ = false;
        if (latest_only && out_size_ > 0) {  // a later packet followed: the master gave up on that answer
          ++stats_.superseded;
          out_size_ = 0;
        }
        if (r.status == ParseStatus::kOk) {
          ++stats_.packets;
          dispatch(p);  // p.params points into scratch_, not rx_: safe to shift rx_ after
        } else {
          ++stats_.bad_packets;
          if (r.status == ParseStatus::kBadCrc) on_bad_crc(r.id);
        }
      }
      if (consumed) {
        std::memmove(rx_.data(), rx_.data() + consumed, rx_size_ - consumed);
        rx_size_ -= consumed;
      }
      if (r.status == ParseStatus::kIncomplete) break;
    }
    if (used >= size) break;
  }
  stats_.bytes_sent += out_size_;
  return out_size_;
}

void SimulatedServos::on_bad_crc(std::uint8_t id) noexcept {
  if (has(id)) reply(servo(id), servo_error::kCrcError, nullptr, 0);  // the servo it names says so
}

void SimulatedServos::dispatch(const Packet& p) noexcept {
  const std::uint8_t* prm = p.params;
  const std::size_t n = p.n_params;
  const bool broadcast = p.id == kBroadcastId;
  switch (p.instruction) {
    case instruction::kPing: ++stats_.ping; break;
    case instruction::kRead: ++stats_.read; break;
    case instruction::kWrite: ++stats_.write; break;
    case instruction::kReboot: ++stats_.reboot; break;
    case instruction::kSyncRead: ++stats_.sync_read; break;
    case instruction::kSyncWrite: ++stats_.sync_write; break;
    case instruction::kFastSyncRead: ++stats_.fast_sync_read; break;
    default: break;
  }
  if (p.instruction == instruction::kStatus) return;  // another device's status (or an echo)
  if (!broadcast && !has(p.id)) return;
  if (p.instruction == instruction::kPing) {
    for (auto& s : servos_) {
      if (!broadcast && s.id != p.id) continue;
      std::uint8_t d[3] = {s.memory[0], s.memory[1], s.memory[firmware_.address]};
      reply(s, 0, d, 3);
    }
    return;
  }
  if (p.instruction == instruction::kSyncRead || p.instruction == instruction::kFastSyncRead ||
      p.instruction == instruction::kSyncWrite) {
    if (!broadcast || n < 4) return;
    const std::uint16_t address = u16(prm), length = u16(prm + 2);
    if (p.instruction == instruction::kSyncWrite) {
      const std::uint8_t* body = prm + 4;
      const std::size_t nb = n - 4;
      for (std::size_t k = 0; k + 1 + length <= nb; k += 1u + length) {
        if (!has(body[k])) continue;
        if (apply_write(servo(body[k]), address, body + k + 1, length)) ++stats_.rejected_writes;
      }
      return;
    }
    refresh();
    std::size_t m = 0;
    for (std::size_t k = 4; k < n && m < group_.size(); ++k) {
      if (has(prm[k])) group_[m++] = prm[k];
    }
    if (p.instruction == instruction::kSyncRead) {
      const std::uint8_t err = read_error(address, length);
      for (std::size_t k = 0; k < m; ++k) {
        const Servo& s = servo(group_[k]);
        reply(s, err, err ? nullptr : &s.memory[address], err ? 0 : length);
      }
      return;
    }
    fast_reply(group_.data(), m, address, length);
    return;
  }
  if (p.instruction == instruction::kWrite) {
    if (n < 3) {
      if (!broadcast) reply(servo(p.id), servo_error::kDataLengthError, nullptr, 0);
      return;
    }
    if (broadcast) {
      for (auto& s : servos_) {
        if (apply_write(s, u16(prm), prm + 2, n - 2)) ++stats_.rejected_writes;
      }
      return;
    }
    Servo& s = servo(p.id);
    const std::uint8_t err = apply_write(s, u16(prm), prm + 2, n - 2);
    if (err) ++stats_.rejected_writes;
    reply(s, err, nullptr, 0);
    return;
  }
  if (broadcast) return;
  Servo& s = servo(p.id);
  if (p.instruction == instruction::kRead) {
    if (n != 4) return reply(s, servo_error::kDataLengthError, nullptr, 0);
    const std::uint16_t address = u16(prm), length = u16(prm + 2);
    if (const std::uint8_t err = read_error(address, length)) return reply(s, err, nullptr, 0);
    refresh();
    return reply(s, 0, &s.memory[address], length);
  }
  if (p.instruction == instruction::kReboot) {
    reply(s, 0, nullptr, 0);  // the servo answers, then restarts
    s.memory[hw_error_.address] = 0;
    set_torque(s, false);
    return;
  }
  reply(s, servo_error::kInstructionError, nullptr, 0);
}

// ------------------------------------------------------------------------------------------------
// the servo's memory rules

std::uint8_t SimulatedServos::alert(const Servo& s) const noexcept {
  return s.memory[hw_error_.address] ? kAlertBit : 0;
}

void SimulatedServos::set_torque(Servo& s, bool on) noexcept {
  s.memory[torque_.address] = on ? 1 : 0;
  if (hooks_) hooks_->on_torque(s.id, on);
}

std::uint8_t SimulatedServos::apply_write(Servo& s, std::uint16_t address, const std::uint8_t* data,
                                          std::size_t length) noexcept {
  const std::size_t end = address + length;
  if (end > kMemoryBytes || length == 0) return servo_error::kDataRangeError;
  const bool torque_on = s.memory[torque_.address] != 0;
  bool writes_goal = false, writes_torque = false;
  std::int64_t goal = 0, torque = 0;
  // Check everything first: a refused write changes nothing.
  for (const auto& e : table_.entries) {
    if (e.address + e.size <= address || e.address >= end) continue;
    if (!e.writable || (e.eeprom && torque_on)) return servo_error::kAccessError;
    if (e.address < address || e.address + e.size > end) return servo_error::kDataLengthError;
    const std::int64_t v = get_le(data + (e.address - address), e.size, e.is_signed);
    if (e.has_range && (v < e.min || v > e.max)) return servo_error::kDataLimitError;
    if (e.address == goal_.address) writes_goal = true, goal = v;
    if (e.address == torque_.address) writes_torque = true, torque = v;
  }
  if (writes_goal) {
    const std::int64_t lo = get_le(&s.memory[min_pos_.address], min_pos_.size, min_pos_.is_signed);
    const std::int64_t hi = get_le(&s.memory[max_pos_.address], max_pos_.size, max_pos_.is_signed);
    if (goal < lo || goal > hi) return servo_error::kDataLimitError;
  }
  if (writes_torque && torque != 0 && s.memory[hw_error_.address] != 0) return servo_error::kResultFail;
  if (hooks_) hooks_->before_write(*this);
  std::memcpy(&s.memory[address], data, length);
  if (writes_torque) set_torque(s, torque != 0);
  if (writes_goal) {
    ++s.goal_writes;
    if (hooks_) hooks_->on_goal(s.id, static_cast<std::int32_t>(goal));
    if (follow_goal_ && s.memory[torque_.address]) {
      put_le(&s.memory[present_pos_.address], present_pos_.size, goal);
    }
  }
  return 0;
}

void SimulatedServos::refresh() noexcept {
  if (refreshed_ || !hooks_) return;
  refreshed_ = true;
  hooks_->before_read(*this);
}

void SimulatedServos::set_present(std::uint8_t id, std::int64_t position, std::int64_t velocity, std::int64_t current,
                                  std::int64_t input_voltage, std::int64_t temperature) noexcept {
  if (!has(id)) return;
  Servo& s = servo(id);
  const auto put = [&s](const Entry& e, std::int64_t v) {
    const int bits = 8 * e.size;
    const std::int64_t lo = e.is_signed ? -(std::int64_t{1} << (bits - 1)) : 0;
    const std::int64_t hi = e.is_signed ? (std::int64_t{1} << (bits - 1)) - 1 : (std::int64_t{1} << bits) - 1;
    put_le(&s.memory[e.address], e.size, std::clamp(v, lo, hi));
  };
  put(present_pos_, position);
  put(present_vel_, velocity);
  put(present_cur_, current);
  put(present_volt_, input_voltage);
  put(present_temp_, temperature);
}

// ------------------------------------------------------------------------------------------------
// faults and replies

void SimulatedServos::inject(ReplyFault kind, const std::vector<std::uint8_t>& ids, int count) {
  if (static_cast<std::size_t>(kind) >= kNumReplyFaults) throw ConfigError("kind: not a reply fault");
  if (count == 0) throw ConfigError("count: 0 is not a positive count (or negative: until cleared)");
  if (n_faults_ >= kMaxFaults)
    throw ConfigError("inject: more than " + std::to_string(kMaxFaults) + " faults standing");
  Fault f;
  f.kind = kind;
  f.remaining = count < 0 ? -1 : count;
  for (std::uint8_t id : ids) {
    servo_or_throw(id);
    f.ids.set(id);
  }
  faults_[n_faults_++] = f;
}

void SimulatedServos::set_silent(std::uint8_t id, bool silent) {
  servo_or_throw(id);
  servo(id).silent = silent;
}

bool SimulatedServos::silent(std::uint8_t id) const { return servo_or_throw(id).silent; }

void SimulatedServos::set_hardware_error(std::uint8_t id, std::uint8_t bits) {
  servo_or_throw(id);
  Servo& s = servo(id);
  s.memory[hw_error_.address] = bits;
  if (bits) set_torque(s, false);  // the servo's shutdown
}

void SimulatedServos::clear_faults() noexcept {
  n_faults_ = 0;
  for (auto& s : servos_) {
    s.silent = false;
    s.memory[hw_error_.address] = 0;
  }
}

std::int64_t SimulatedServos::get(std::uint8_t id, const std::string& entry) const {
  const Servo& s = servo_or_throw(id);
  const auto& e = table_.at(entry);
  return get_le(&s.memory[e.address], e.size, e.is_signed);
}

void SimulatedServos::set(std::uint8_t id, const std::string& entry, std::int64_t value) {
  servo_or_throw(id);
  const auto& e = table_.at(entry);
  put_le(&servo(id).memory[e.address], e.size, value);
}

std::uint64_t SimulatedServos::goal_writes(std::uint8_t id) const { return servo_or_throw(id).goal_writes; }

void SimulatedServos::reset_stats() noexcept {
  stats_ = SimulatedServoStats{};
  for (auto& s : servos_) s.goal_writes = 0;
}

SimulatedServos::Damage SimulatedServos::take_faults(const std::uint8_t* ids, std::size_t n) noexcept {
  Damage d;
  std::size_t kept = 0;
  for (std::size_t i = 0; i < n_faults_; ++i) {
    Fault& f = faults_[i];
    bool hit = f.ids.none();
    for (std::size_t k = 0; k < n && !hit; ++k) hit = f.ids.test(ids[k]);
    if (hit) {
      d.any = true;
      d.kinds[static_cast<std::size_t>(f.kind)] = true;
      if (f.remaining > 0) --f.remaining;
    }
    if (f.remaining != 0) faults_[kept++] = f;
  }
  n_faults_ = kept;
  return d;
}

void SimulatedServos::append(const std::uint8_t* packet, std::size_t size, const Damage& d) noexcept {
  const auto has = [&d](ReplyFault k) { return d.kinds[static_cast<std::size_t>(k)]; };
  if (d.any) ++stats_.replies_damaged;
  if (size == 0 || has(ReplyFault::kDropReply)) return;
  if (has(ReplyFault::kCorruptCrc)) packet_[size - 1] ^= 0xFF;  // packet is packet_ here
  if (has(ReplyFault::kTruncateReply)) size = std::max<std::size_t>(5, size / 2);
  const std::size_t extra = has(ReplyFault::kGarbageBefore) ? sizeof kGarbage : 0;
  if (out_size_ + extra + size > out_.size()) {
    ++stats_.dropped;
    return;
  }
  if (extra) std::memcpy(&out_[out_size_], kGarbage, extra);
  std::memcpy(&out_[out_size_ + extra], packet, size);
  out_size_ += extra + size;
}

void SimulatedServos::reply(const Servo& s, std::uint8_t error, const std::uint8_t* data, std::size_t n) noexcept {
  if (s.silent) return;
  ++stats_.replies;
  const Damage d = take_faults(&s.id, 1);
  if (d.kinds[static_cast<std::size_t>(ReplyFault::kGarbageData)] && n) {
    std::memset(data_.data(), 0xA5, n);
    data = data_.data();
  }
  std::size_t size =
      encode_status(s.id, static_cast<std::uint8_t>(error | alert(s)), data, n, packet_.data(), packet_.size());
  if (size == 0) {  // cannot happen for reads within the memory; refuse rather than send nothing
    size = encode_status(s.id, static_cast<std::uint8_t>(servo_error::kDataLengthError | alert(s)), nullptr, 0,
                         packet_.data(), packet_.size());
  }
  append(packet_.data(), size, d);
}

void SimulatedServos::fast_reply(const std::uint8_t* ids, std::size_t n, std::uint16_t address,
                                 std::uint16_t length) noexcept {
  std::size_t m = 0;  // the servos that answer, in place
  for (std::size_t k = 0; k < n; ++k) {
    if (!servo(ids[k]).silent) group_[m++] = ids[k];
  }
  if (m == 0) return;
  ++stats_.replies;
  const Damage d = take_faults(group_.data(), m);
  std::size_t size = 0;
  if (kStatusOverhead + m * (length + 4u) <= kMaxPacketBytes) {
    const std::uint8_t err = read_error(address, length);
    const bool garbage = d.kinds[static_cast<std::size_t>(ReplyFault::kGarbageData)];
    // The un-stuffed packet: header, ID, LEN, INST, then ERR ID DATA CRC per servo (the intermediate
    // CRCs over the un-stuffed packet so far; the last one is the packet's own).
    const std::size_t n_params = m * (length + 4u) - 2;
    std::size_t b = 0;
    const std::uint8_t head[] = {0xFF,
                                 0xFF,
                                 0xFD,
                                 0x00,
                                 kBroadcastId,
                                 static_cast<std::uint8_t>((n_params + 3) & 0xFF),
                                 static_cast<std::uint8_t>((n_params + 3) >> 8),
                                 instruction::kStatus};
    std::memcpy(body_.data(), head, sizeof head);
    b = sizeof head;
    for (std::size_t k = 0; k < m; ++k) {
      const Servo& s = servo(group_[k]);
      if (k) {
        const std::uint16_t crc = crc16(body_.data(), b);
        body_[b++] = static_cast<std::uint8_t>(crc & 0xFF);
        body_[b++] = static_cast<std::uint8_t>(crc >> 8);
      }
      body_[b++] = static_cast<std::uint8_t>(err | alert(s));
      body_[b++] = s.id;
      if (err || garbage) {
        std::memset(&body_[b], err ? 0 : 0xA5, length);
      } else {
        std::memcpy(&body_[b], &s.memory[address], length);
      }
      b += length;
    }
    size = encode_status(kBroadcastId, body_[8], &body_[9], b - 9, packet_.data(), packet_.size());
  }
  if (size == 0) {  // more than one packet can carry (before or after stuffing): the servos refuse it
    size = encode_status(kBroadcastId, servo_error::kDataLengthError, nullptr, 0, packet_.data(), packet_.size());
  }
  append(packet_.data(), size, d);
}

}  // namespace snake_autonomy::dynamixel
