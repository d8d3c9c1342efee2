#include "snake_autonomy/dynamixel/protocol.hpp"

#include <array>
#include <cstring>

#include "snake_autonomy/dynamixel/status.hpp"

namespace snake_autonomy::dynamixel {
namespace {

constexpr std::array<std::uint16_t, 256> make_crc_table() {
  std::array<std::uint16_t, 256> table{};
  for (unsigned i = 0; i < 256; ++i) {
    std::uint16_t crc = static_cast<std::uint16_t>(i << 8);
    for (int bit = 0; bit < 8; ++bit) {
      crc = static_cast<std::uint16_t>((crc & 0x8000) ? ((crc << 1) ^ 0x8005) : (crc << 1));
    }
    table[i] = crc;
  }
  return table;
}
constexpr std::array<std::uint16_t, 256> kCrcTable = make_crc_table();

constexpr std::size_t kIdOffset = 4;
constexpr std::size_t kLengthOffset = 5;
constexpr std::size_t kInstructionOffset = 7;

bool is_header(const std::uint8_t* p) noexcept { return p[0] == 0xFF && p[1] == 0xFF && p[2] == 0xFD && p[3] == 0x00; }

}  // namespace

const char* servo_error_name(std::uint8_t error_number) noexcept {
  switch (error_number) {
    case 0: return "no error";
    case servo_error::kResultFail: return "result fail";
    case servo_error::kInstructionError: return "instruction error";
    case servo_error::kCrcError: return "CRC error";
    case servo_error::kDataRangeError: return "data range error";
    case servo_error::kDataLengthError: return "data length error";
    case servo_error::kDataLimitError: return "data limit error";
    case servo_error::kAccessError: return "access error";
    default: return "unknown error number";
  }
}

std::uint16_t crc16(const std::uint8_t* data, std::size_t size, std::uint16_t crc) noexcept {
  for (std::size_t i = 0; i < size; ++i) {
    const unsigned index = ((crc >> 8) ^ data[i]) & 0xFF;
    crc = static_cast<std::uint16_t>((crc << 8) ^ kCrcTable[index]);
  }
  return crc;
}

std::size_t stuff(const std::uint8_t* in, std::size_t size, std::uint8_t* out, std::size_t capacity) noexcept {
  std::size_t n = 0;
  for (std::size_t i = 0; i < size; ++i) {
    if (n >= capacity) return kNoSpace;
    out[n++] = in[i];
    if (in[i] == 0xFD && i >= 2 && in[i - 1] == 0xFF && in[i - 2] == 0xFF) {
      if (n >= capacity) return kNoSpace;
      out[n++] = 0xFD;
    }
  }
  return n;
}

std::size_t unstuff(const std::uint8_t* in, std::size_t size, std::uint8_t* out, std::size_t capacity) noexcept {
  std::size_t n = 0;
  bool just_completed = false;  // the last byte written completed FF FF FD in the output
  for (std::size_t i = 0; i < size; ++i) {
    if (just_completed) {  // the stuffed FD: drop it; anything else means a sender that did not stuff
      if (in[i] != 0xFD) return kBadStuffing;
      just_completed = false;
      continue;
    }
    if (n >= capacity) return kNoSpace;
    out[n++] = in[i];
    // Judged on the un-stuffed output, exactly as the sender judged its input.
    just_completed = in[i] == 0xFD && n >= 3 && out[n - 2] == 0xFF && out[n - 3] == 0xFF;
  }
  return just_completed ? kBadStuffing : n;  // FF FF FD ends the region without its FD
}

std::int32_t get_le(const std::uint8_t* p, std::size_t size, bool is_signed) noexcept {
  switch (size) {
    case 1: return is_signed ? static_cast<std::int8_t>(p[0]) : p[0];
    case 2: {
      const std::uint16_t v = static_cast<std::uint16_t>(p[0] | (p[1] << 8));
      return is_signed ? static_cast<std::int16_t>(v) : v;
    }
    case 4: {
      const std::uint32_t v = static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
                              (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
      return static_cast<std::int32_t>(v);
    }
    default: return 0;
  }
}

void put_le(std::uint8_t* p, std::size_t size, std::int64_t value) noexcept {
  const auto v = static_cast<std::uint64_t>(value);
  for (std::size_t i = 0; i < size && i < 8; ++i) p[i] = static_cast<std::uint8_t>((v >> (8 * i)) & 0xFF);
}

// ---------------------------------------------------------------------------------------------
void PacketEncoder::begin(std::uint8_t id, std::uint8_t instruction) noexcept {
  n_ = 0;
  overflow_ = cap_ < kInstructionOverhead;
  last1_ = last2_ = 0;
  if (overflow_) return;
  buf_[0] = 0xFF;
  buf_[1] = 0xFF;
  buf_[2] = 0xFD;
  buf_[3] = 0x00;
  buf_[kIdOffset] = id;
  n_ = kInstructionOffset;
  put(instruction);
}

void PacketEncoder::put(std::uint8_t byte) noexcept {
  if (overflow_) return;
  // Two bytes stay free for the CRC.
  if (n_ + 1 + 2 > cap_) {
    overflow_ = true;
    return;
  }
  buf_[n_++] = byte;
  if (byte == 0xFD && last1_ == 0xFF && last2_ == 0xFF) {
    if (n_ + 1 + 2 > cap_) {
      overflow_ = true;
      return;
    }
    buf_[n_++] = 0xFD;
  }
  last2_ = last1_;
  last1_ = byte;
}

void PacketEncoder::put(const std::uint8_t* bytes, std::size_t size) noexcept {
  for (std::size_t i = 0; i < size; ++i) put(bytes[i]);
}

void PacketEncoder::put16(std::uint16_t value) noexcept {
  put(static_cast<std::uint8_t>(value & 0xFF));
  put(static_cast<std::uint8_t>(value >> 8));
}

void PacketEncoder::put32(std::uint32_t value) noexcept {
  for (int i = 0; i < 4; ++i) put(static_cast<std::uint8_t>((value >> (8 * i)) & 0xFF));
}

std::size_t PacketEncoder::finish() noexcept {
  if (overflow_ || n_ < kInstructionOffset + 1) return 0;
  const std::size_t length = n_ - kInstructionOffset + 2;
  if (length > 0xFFFF) return 0;
  buf_[kLengthOffset] = static_cast<std::uint8_t>(length & 0xFF);
  buf_[kLengthOffset + 1] = static_cast<std::uint8_t>(length >> 8);
  const std::uint16_t crc = crc16(buf_, n_);
  buf_[n_++] = static_cast<std::uint8_t>(crc & 0xFF);
  buf_[n_++] = static_cast<std::uint8_t>(crc >> 8);
  return n_;
}

std::size_t encode_packet(std::uint8_t id, std::uint8_t instruction, const std::uint8_t* params, std::size_t n_params,
                          std::uint8_t* out, std::size_t capacity) noexcept {
  PacketEncoder e(out, capacity);
  e.begin(id, instruction);
  e.put(params, n_params);
  return e.finish();
}

std::size_t encode_status(std::uint8_t id, std::uint8_t error, const std::uint8_t* data, std::size_t n_data,
                          std::uint8_t* out, std::size_t capacity) noexcept {
  PacketEncoder e(out, capacity);
  e.begin(id, instruction::kStatus);
  e.put(error);
  e.put(data, n_data);
  return e.finish();
}

// ---------------------------------------------------------------------------------------------
const char* to_string(ParseStatus status) noexcept {
  switch (status) {
    case ParseStatus::kOk: return "ok";
    case ParseStatus::kIncomplete: return "incomplete";
    case ParseStatus::kBadCrc: return "bad CRC";
    case ParseStatus::kMalformed: return "malformed";
  }
  return "?";
}

ParseResult parse_packet(const std::uint8_t* in, std::size_t size, std::uint8_t* scratch, std::size_t scratch_capacity,
                         Packet* out, bool input_ended) noexcept {
  ParseResult r;
  // Hunt the header. A trailing FF, FF FF or FF FF FD may be the start of one: keep it.
  std::size_t s = 0;
  while (s + kHeaderBytes <= size && !is_header(in + s)) ++s;
  if (s + kHeaderBytes > size) {
    std::size_t keep = 0;
    for (std::size_t k = 3; k >= 1; --k) {
      if (size < k) continue;
      static constexpr std::uint8_t kPrefix[3] = {0xFF, 0xFF, 0xFD};
      if (std::memcmp(in + size - k, kPrefix, k) == 0) {
        keep = k;
        break;
      }
    }
    r.status = ParseStatus::kIncomplete;
    r.consumed = size - keep;
    return r;
  }
  r.start = s;
  if (s + kInstructionOffset > size) {  // ID and LEN not here yet
    r.status = ParseStatus::kIncomplete;
    r.consumed = s;
    return r;
  }
  r.id = in[s + kIdOffset];
  const std::size_t length = static_cast<std::size_t>(in[s + kLengthOffset] | (in[s + kLengthOffset + 1] << 8));
  const std::size_t total = kInstructionOffset + length;
  if (length < 3 || total > kMaxPacketBytes) {  // INST + CRC at the very least
    r.status = ParseStatus::kMalformed;
    r.consumed = s + kHeaderBytes;
    return r;
  }
  if (s + total > size) {
    // Not all here yet, unless a full header already shows inside the span: cut short.
    for (std::size_t k = s + kHeaderBytes; k + kHeaderBytes <= size; ++k) {
      if (is_header(in + k)) {
        r.status = ParseStatus::kMalformed;
        r.consumed = k;
        return r;
      }
    }
    r.status = ParseStatus::kIncomplete;
    r.consumed = s;
    return r;
  }
  const std::uint8_t* p = in + s;
  const std::uint16_t received = static_cast<std::uint16_t>(p[total - 2] | (p[total - 1] << 8));
  if (crc16(p, total - 2) != received) {
    // A header starting inside the span means this packet was truncated and the next one began
    // early: report it as malformed and keep the next packet (stuffing guarantees FF FF FD 00
    // never occurs inside a packet). A header candidate may run past the span, and past the input:
    // FF, FF FF or FF FF FD at the very end may be the start of the next packet arriving in small
    // reads, so wait for the bytes that decide rather than drop the span and that start with it.
    static constexpr std::uint8_t kHeader[4] = {0xFF, 0xFF, 0xFD, 0x00};
    for (std::size_t k = s + kHeaderBytes; k < s + total; ++k) {
      const std::size_t avail = size - k < kHeaderBytes ? size - k : kHeaderBytes;
      if (std::memcmp(in + k, kHeader, avail) != 0 || (avail < kHeaderBytes && input_ended)) continue;
      if (avail == kHeaderBytes) {
        r.status = ParseStatus::kMalformed;
        r.consumed = k;
      } else {
        r.status = ParseStatus::kIncomplete;
        r.consumed = s;
      }
      return r;
    }
    r.status = ParseStatus::kBadCrc;
    r.consumed = s + total;
    return r;
  }
  const std::size_t n = unstuff(p + kInstructionOffset, length - 2, scratch, scratch_capacity);
  if (n == kBadStuffing) {
    // A valid CRC over a region its sender did not stuff (FF FF FD without its FD): refused. Only
    // the header is dropped, so that a packet starting inside the span is still found.
    r.status = ParseStatus::kMalformed;
    r.consumed = s + kHeaderBytes;
    return r;
  }
  if (n == kNoSpace || n == 0) {
    r.status = ParseStatus::kMalformed;
    r.consumed = s + total;
    return r;
  }
  out->id = p[kIdOffset];
  out->instruction = scratch[0];
  out->params = scratch + 1;
  out->n_params = n - 1;
  r.status = ParseStatus::kOk;
  r.consumed = s + total;
  return r;
}

// ---------------------------------------------------------------------------------------------
const char* to_string(Status status) noexcept {
  switch (status) {
    case Status::kOk: return "ok";
    case Status::kHardwareError: return "hardware error alert";
    case Status::kTimeout: return "timeout";
    case Status::kCrcError: return "CRC error";
    case Status::kMalformed: return "malformed reply";
    case Status::kWrongId: return "reply from the wrong ID";
    case Status::kWrongInstruction: return "not a status packet";
    case Status::kServoError: return "servo refused the instruction";
    case Status::kInvalidArgument: return "invalid argument";
    case Status::kIoError: return "I/O error";
    case Status::kNotOpen: return "port not open";
  }
  return "?";
}

Status check_status_packet(const Packet& packet, std::uint8_t expected_id, std::size_t expected_data_bytes,
                           std::uint8_t* error_byte) noexcept {
  if (error_byte) *error_byte = 0;
  if (packet.id != expected_id) return Status::kWrongId;
  if (packet.instruction != instruction::kStatus) return Status::kWrongInstruction;
  if (packet.n_params < 1) return Status::kMalformed;
  const std::uint8_t error = packet.params[0];
  if (error_byte) *error_byte = error;
  if (error & kErrorNumberMask) return Status::kServoError;
  if (packet.n_params - 1 != expected_data_bytes) return Status::kMalformed;
  if (error & kAlertBit) return Status::kHardwareError;
  return Status::kOk;
}

}  // namespace snake_autonomy::dynamixel
