#include "snake_autonomy/dynamixel/protocol2_bus.hpp"

#include <algorithm>
#include <cstring>

namespace snake_autonomy::dynamixel {
namespace {

constexpr std::size_t kMaxServos = kMaxServoId + 1;

bool valid_id(std::uint8_t id) noexcept { return id <= kMaxServoId; }

bool valid_ids(const std::uint8_t* ids, std::size_t n) noexcept {
  if (!ids || n == 0 || n > kMaxServos) return false;
  for (std::size_t i = 0; i < n; ++i) {
    if (!valid_id(ids[i])) return false;
  }
  return true;
}

// Index of `id` among the servos still waiting for their reply (status kTimeout), or n.
std::size_t pending_index(const std::uint8_t* ids, std::size_t n, const ServoReply* replies, std::uint8_t id) noexcept {
  for (std::size_t i = 0; i < n; ++i) {
    if (ids[i] == id && replies[i].status == Status::kTimeout) return i;
  }
  return n;
}

// A transaction that ended like this may leave a reply on its way: the bus drains after it.
bool is_line_failure(Status s) noexcept {
  return s == Status::kTimeout || s == Status::kCrcError || s == Status::kMalformed;
}

Status first_failure(const ServoReply* replies, std::size_t n) noexcept {
  for (std::size_t i = 0; i < n; ++i) {
    if (replies[i].status != Status::kOk) return replies[i].status;
  }
  return Status::kOk;
}

}  // namespace

double wire_time_s(std::size_t bytes, int baud_bps) noexcept {
  return baud_bps > 0 ? static_cast<double>(bytes) * 10.0 / baud_bps : 0.0;
}

double reply_timeout_s(std::size_t bytes_out, std::size_t bytes_back, std::size_t n_replies, int baud_bps,
                       const BusTiming& timing) noexcept {
  return timing.latency_s + static_cast<double>(n_replies) * timing.return_delay_s +
         timing.margin * wire_time_s(bytes_out + bytes_back, baud_bps);
}

SteadyTime Protocol2Bus::deadline_for(std::size_t bytes_out, std::size_t bytes_back,
                                      std::size_t n_replies) const noexcept {
  const double s = reply_timeout_s(bytes_out, bytes_back, n_replies, transport_.baud_bps(), timing_);
  return std::chrono::steady_clock::now() +
         std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
}

double Protocol2Bus::single_reply_timeout_s(std::size_t data_bytes) const noexcept {
  return reply_timeout_s(0, kStatusOverhead + data_bytes, 1, transport_.baud_bps(), timing_);
}

Status Protocol2Bus::send(std::size_t size) noexcept {
  if (size == 0) return Status::kInvalidArgument;
  if (!transport_.is_open()) return Status::kNotOpen;
  transport_.discard_input();
  rx_size_ = 0;
  ++counters_.transactions;
  if (!transport_.write_all(tx_.data(), size)) {
    ++counters_.io_errors;
    return Status::kIoError;
  }
  counters_.bytes_sent += size;
  return Status::kOk;
}

Protocol2Bus::Event Protocol2Bus::receive(SteadyTime deadline, Packet* packet, std::uint8_t* id) noexcept {
  for (;;) {
    if (rx_size_ > 0) {
      const ParseResult r = parse_packet(rx_.data(), rx_size_, scratch_.data(), scratch_.size(), packet);
      if (r.consumed > 0) {
        std::memmove(rx_.data(), rx_.data() + r.consumed, rx_size_ - r.consumed);
        rx_size_ -= r.consumed;
      }
      *id = r.id;
      switch (r.status) {
        case ParseStatus::kOk: ++counters_.packets_received; return Event::kPacket;
        case ParseStatus::kBadCrc: ++counters_.crc_errors; return Event::kBadCrc;
        case ParseStatus::kMalformed: ++counters_.malformed; return Event::kMalformed;
        case ParseStatus::kIncomplete: break;
      }
    }
    if (rx_size_ == rx_.size()) {  // a full buffer and still no packet: give up on it
      rx_size_ = 0;
      ++counters_.malformed;
      *id = 0xFF;
      return Event::kMalformed;
    }
    const long got = transport_.read_some(rx_.data() + rx_size_, rx_.size() - rx_size_, deadline);
    if (got < 0) {
      ++counters_.io_errors;
      return Event::kIoError;
    }
    if (got == 0) {
      if (std::chrono::steady_clock::now() < deadline) continue;
      // The deadline: nothing more will come. A damaged packet held back because its last bytes
      // might have begun the next header is judged now (a CRC error, for the servo it names).
      if (rx_size_ > 0) {
        const ParseResult r = parse_packet(rx_.data(), rx_size_, scratch_.data(), scratch_.size(), packet, true);
        if (r.status == ParseStatus::kBadCrc) {
          std::memmove(rx_.data(), rx_.data() + r.consumed, rx_size_ - r.consumed);
          rx_size_ -= r.consumed;
          *id = r.id;
          ++counters_.crc_errors;
          return Event::kBadCrc;
        }
      }
      // A header received without the rest of its packet is a truncated reply.
      const bool partial = rx_size_ >= kHeaderBytes && rx_[0] == 0xFF && rx_[1] == 0xFF && rx_[2] == 0xFD;
      *id = rx_size_ > 4 ? rx_[4] : 0xFF;
      rx_size_ = 0;
      if (partial) {
        ++counters_.malformed;
        return Event::kMalformed;
      }
      return Event::kDeadline;
    }
    counters_.bytes_received += static_cast<std::uint64_t>(got);
    rx_size_ += static_cast<std::size_t>(got);
  }
}

Status Protocol2Bus::record_reply(Status s) noexcept {
  switch (s) {
    case Status::kHardwareError: ++counters_.hardware_error_alerts; break;
    case Status::kServoError: ++counters_.servo_errors; break;
    case Status::kMalformed: ++counters_.malformed; break;
    default: break;
  }
  return s;
}

void Protocol2Bus::drain(double quiet_s) noexcept {
  using Clock = std::chrono::steady_clock;
  ++counters_.drains;
  counters_.late_bytes += rx_size_;  // what the failed transaction left unparsed
  rx_size_ = 0;
  const auto quiet = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(quiet_s));
  const SteadyTime end = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                            std::chrono::duration<double>(quiet_s * kDrainQuietPeriods));
  SteadyTime quiet_until = Clock::now() + quiet;
  for (;;) {
    const SteadyTime until = std::min(quiet_until, end);
    if (Clock::now() >= until) break;
    const long got = transport_.read_some(rx_.data(), rx_.size(), until);
    if (got < 0) break;  // the next transaction meets the I/O error and reports it
    if (got == 0) continue;
    counters_.bytes_received += static_cast<std::uint64_t>(got);
    counters_.late_bytes += static_cast<std::uint64_t>(got);
    quiet_until = Clock::now() + quiet;
  }
  rx_size_ = 0;
}

Status Protocol2Bus::finish(Status s, double timeout_s) noexcept {
  if (s == Status::kTimeout || s == Status::kCrcError || s == Status::kMalformed) {
    drain(timeout_s);
    suspect_ = true;
  }
  return s;
}

Status Protocol2Bus::transact(std::uint8_t id, std::size_t tx_size, std::size_t data_bytes, std::uint8_t* data,
                              std::uint8_t* error) noexcept {
  if (error) *error = 0;
  const Status sent = send(tx_size);
  if (sent != Status::kOk || id == kBroadcastId) return sent;
  const double timeout_s = reply_timeout_s(tx_size, kStatusOverhead + data_bytes, 1, transport_.baud_bps(), timing_);
  const SteadyTime deadline = deadline_for(tx_size, kStatusOverhead + data_bytes, 1);
  for (;;) {
    Packet p;
    std::uint8_t rid = 0;
    switch (receive(deadline, &p, &rid)) {
      case Event::kPacket: {
        std::uint8_t err = 0;
        const Status st = check_status_packet(p, id, data_bytes, &err);
        if (st == Status::kWrongId || st == Status::kWrongInstruction) {
          // Another servo's late reply, or our own instruction echoed by a half-duplex adapter.
          ++counters_.unexpected_packets;
          continue;
        }
        if (error) *error = err;
        if (has_data(st) && data && data_bytes) std::memcpy(data, p.params + 1, data_bytes);
        return finish(record_reply(st), timeout_s);
      }
      case Event::kBadCrc: return finish(Status::kCrcError, timeout_s);
      case Event::kMalformed: return finish(Status::kMalformed, timeout_s);
      case Event::kDeadline: ++counters_.timeouts; return finish(Status::kTimeout, timeout_s);
      case Event::kIoError: return Status::kIoError;
    }
  }
}

Status Protocol2Bus::verified(std::uint8_t id, std::size_t tx_size, std::size_t data_bytes, std::uint8_t* data,
                              std::uint8_t* error) noexcept {
  if (!suspect_) return transact(id, tx_size, data_bytes, data, error);
  // tx_ still holds the request after each transact(): it is sent again as it is.
  Status prev = transact(id, tx_size, data_bytes, verify_.data(), error);
  if (!has_data(prev)) return prev;
  for (int attempt = 1; attempt < kVerifyAttempts; ++attempt) {
    const Status s = transact(id, tx_size, data_bytes, data, error);
    if (!has_data(s)) return s;
    if (s == prev && std::memcmp(verify_.data(), data, data_bytes) == 0) {
      suspect_ = false;
      return s;
    }
    ++counters_.verify_mismatches;
    prev = s;
    std::memcpy(verify_.data(), data, data_bytes);
  }
  suspect_ = true;
  return record_reply(Status::kMalformed);
}

Status Protocol2Bus::ping(std::uint8_t id, std::uint16_t* model_number, std::uint8_t* error) noexcept {
  if (!valid_id(id)) return Status::kInvalidArgument;
  const std::size_t n = encode_packet(id, instruction::kPing, nullptr, 0, tx_.data(), tx_.size());
  std::uint8_t data[3] = {0, 0, 0};
  const Status s = verified(id, n, 3, data, error);
  if (has_data(s) && model_number) *model_number = static_cast<std::uint16_t>(get_le(data, 2, false));
  return s;
}

Status Protocol2Bus::read(std::uint8_t id, std::uint16_t address, std::uint16_t length, std::uint8_t* data,
                          std::uint8_t* error) noexcept {
  if (!valid_id(id) || length == 0 || !data || kStatusOverhead + length > kMaxPacketBytes)
    return Status::kInvalidArgument;
  PacketEncoder e(tx_.data(), tx_.size());
  e.begin(id, instruction::kRead);
  e.put16(address);
  e.put16(length);
  return verified(id, e.finish(), length, data, error);
}

Status Protocol2Bus::write(std::uint8_t id, std::uint16_t address, const std::uint8_t* data, std::uint16_t length,
                           std::uint8_t* error) noexcept {
  if ((!valid_id(id) && id != kBroadcastId) || length == 0 || !data) return Status::kInvalidArgument;
  PacketEncoder e(tx_.data(), tx_.size());
  e.begin(id, instruction::kWrite);
  e.put16(address);
  e.put(data, length);
  const std::size_t n = e.finish();
  if (n == 0) return Status::kInvalidArgument;
  return transact(id, n, 0, nullptr, error);
}

Status Protocol2Bus::reboot(std::uint8_t id, std::uint8_t* error) noexcept {
  if (!valid_id(id)) return Status::kInvalidArgument;
  const std::size_t n = encode_packet(id, instruction::kReboot, nullptr, 0, tx_.data(), tx_.size());
  return transact(id, n, 0, nullptr, error);
}

Status Protocol2Bus::sync_write(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                                const std::uint8_t* data) noexcept {
  if (!valid_ids(ids, n) || length == 0 || !data) return Status::kInvalidArgument;
  PacketEncoder e(tx_.data(), tx_.size());
  e.begin(kBroadcastId, instruction::kSyncWrite);
  e.put16(address);
  e.put16(length);
  for (std::size_t i = 0; i < n; ++i) {
    e.put(ids[i]);
    e.put(data + i * length, length);
  }
  const std::size_t size = e.finish();
  if (size == 0) return Status::kInvalidArgument;
  return send(size);
}

Status Protocol2Bus::send_group_read(std::uint8_t instruction_code, std::uint16_t address, std::uint16_t length,
                                     const std::uint8_t* ids, std::size_t n, ServoReply* replies,
                                     std::size_t* size) noexcept {
  for (std::size_t i = 0; i < n; ++i) replies[i] = ServoReply{};
  PacketEncoder e(tx_.data(), tx_.size());
  e.begin(kBroadcastId, instruction_code);
  e.put16(address);
  e.put16(length);
  e.put(ids, n);
  *size = e.finish();
  if (*size == 0) return Status::kInvalidArgument;
  const Status sent = send(*size);
  if (sent != Status::kOk) {
    for (std::size_t i = 0; i < n; ++i) replies[i].status = sent;
  }
  return sent;
}

Status Protocol2Bus::sync_read(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                               std::uint8_t* data, ServoReply* replies) noexcept {
  if (!valid_ids(ids, n) || length == 0 || !data || !replies || kStatusOverhead + length > kMaxPacketBytes) {
    return Status::kInvalidArgument;
  }
  std::size_t size = 0;
  const Status sent = send_group_read(instruction::kSyncRead, address, length, ids, n, replies, &size);
  if (sent != Status::kOk) return sent;
  const SteadyTime deadline = deadline_for(size, n * (kStatusOverhead + length), n);
  std::size_t pending = n;
  while (pending > 0) {
    Packet p;
    std::uint8_t rid = 0;
    const Event ev = receive(deadline, &p, &rid);
    if (ev == Event::kDeadline) break;
    if (ev == Event::kIoError) {
      for (std::size_t i = 0; i < n; ++i) {
        if (replies[i].status == Status::kTimeout) replies[i].status = Status::kIoError;
      }
      return Status::kIoError;
    }
    const std::size_t i = pending_index(ids, n, replies, ev == Event::kPacket ? p.id : rid);
    if (i == n) {  // no servo waits for this: someone else's packet, or a corrupt ID byte
      if (ev == Event::kPacket) ++counters_.unexpected_packets;
      continue;
    }
    if (ev == Event::kBadCrc || ev == Event::kMalformed) {
      replies[i].status = ev == Event::kBadCrc ? Status::kCrcError : Status::kMalformed;
      --pending;
      continue;
    }
    std::uint8_t err = 0;
    const Status st = check_status_packet(p, ids[i], length, &err);
    if (st == Status::kWrongInstruction) {  // an echo of our instruction
      ++counters_.unexpected_packets;
      continue;
    }
    replies[i].status = record_reply(st);
    replies[i].error = err;
    if (has_data(st)) std::memcpy(data + i * length, p.params + 1, length);
    --pending;
  }
  bool failed = false;
  for (std::size_t i = 0; i < n; ++i) {
    if (replies[i].status == Status::kTimeout) ++counters_.timeouts;
    failed = failed || is_line_failure(replies[i].status);
  }
  if (failed) finish(Status::kTimeout, single_reply_timeout_s(length));
  return first_failure(replies, n);
}

Status Protocol2Bus::fast_sync_read(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                                    std::uint8_t* data, ServoReply* replies) noexcept {
  if (!valid_ids(ids, n) || length == 0 || !data || !replies || kStatusOverhead + n * (length + 4u) > kMaxPacketBytes) {
    return Status::kInvalidArgument;
  }
  std::size_t size = 0;
  const Status sent = send_group_read(instruction::kFastSyncRead, address, length, ids, n, replies, &size);
  if (sent != Status::kOk) return sent;
  // One status packet from ID 0xFE whose parameters are, per servo, ERR ID DATA[length] CRC(2),
  // the last servo's CRC being the packet's own: n * (length + 4) - 2 parameter bytes. The packet
  // CRC covers every block; the intermediate CRCs are not checked.
  const std::size_t block = length + 4u;
  const SteadyTime deadline = deadline_for(size, 8 + n * block, n);
  Status whole = Status::kTimeout;  // what happened to the shared packet
  for (;;) {
    Packet p;
    std::uint8_t rid = 0;
    const Event ev = receive(deadline, &p, &rid);
    if (ev == Event::kDeadline) break;
    if (ev == Event::kIoError) {
      whole = Status::kIoError;
      break;
    }
    if (ev == Event::kBadCrc) {
      whole = Status::kCrcError;
      break;
    }
    if (ev == Event::kMalformed) {
      whole = Status::kMalformed;
      break;
    }
    if (p.id != kBroadcastId || p.instruction != instruction::kStatus) {
      ++counters_.unexpected_packets;
      continue;
    }
    if (p.n_params < block - 2 || (p.n_params + 2) % block != 0) {
      ++counters_.malformed;
      whole = Status::kMalformed;
      break;
    }
    const std::size_t k = (p.n_params + 2) / block;
    for (std::size_t j = 0; j < k; ++j) {
      const std::uint8_t* b = p.params + j * block;
      const std::size_t i = pending_index(ids, n, replies, b[1]);
      if (i == n) {
        ++counters_.unexpected_packets;
        continue;
      }
      const std::uint8_t err = b[0];
      const Status st = (err & kErrorNumberMask) ? Status::kServoError
                        : (err & kAlertBit)      ? Status::kHardwareError
                                                 : Status::kOk;
      replies[i].status = record_reply(st);
      replies[i].error = err;
      if (has_data(st)) std::memcpy(data + i * length, b + 2, length);
    }
    whole = Status::kOk;
    break;
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (replies[i].status != Status::kTimeout) continue;
    if (whole == Status::kOk || whole == Status::kTimeout) {
      ++counters_.timeouts;  // this servo's block never came
    } else {
      replies[i].status = whole;
    }
  }
  bool failed = false;
  for (std::size_t i = 0; i < n; ++i) failed = failed || is_line_failure(replies[i].status);
  if (failed) finish(Status::kTimeout, single_reply_timeout_s(length));
  return first_failure(replies, n);
}

}  // namespace snake_autonomy::dynamixel
