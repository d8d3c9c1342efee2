// Dynamixel Protocol 2.0 packets: CRC-16, byte stuffing, encoding and parsing. ROS-free, no
// allocation: every function writes into a buffer the caller owns, and nothing here throws.
//
// Why our own codec: ROBOTIS's C++ SDK is not packaged for Debian 12 (our platform), and its Python
// SDK (PyPI dynamixel-sdk 4.1.0) mishandles byte stuffing: its transmit path builds the stuffed
// packet and then discards it, and its receive-side un-stuffing can drop a byte. Stuffing matters
// on our bus: a sync read from address 126 returns current, velocity and position back to back,
// and a current of -1 (FF FF) followed by a velocity of -3 (FD ...) is exactly the FF FF FD pattern.
//
// Packet layout (ROBOTIS e-manual, Protocol 2.0):
//   FF FF FD 00 | ID | LEN_L LEN_H | INST | PARAM... | CRC_L CRC_H
// LEN counts INST + PARAMs + CRC *after* stuffing. The CRC covers every byte from the header to the
// last parameter, after stuffing. A status packet is INST 0x55 whose first parameter is the error
// byte (bit 7: hardware alert; bits 0-6: error number 1-7 of the instruction just processed).
#pragma once

#include <cstddef>
#include <cstdint>

namespace snake_autonomy::dynamixel {

namespace instruction {
constexpr std::uint8_t kPing = 0x01;
constexpr std::uint8_t kRead = 0x02;
constexpr std::uint8_t kWrite = 0x03;
constexpr std::uint8_t kReboot = 0x08;
constexpr std::uint8_t kStatus = 0x55;
constexpr std::uint8_t kSyncRead = 0x82;
constexpr std::uint8_t kSyncWrite = 0x83;
constexpr std::uint8_t kFastSyncRead = 0x8A;
}  // namespace instruction

constexpr std::uint8_t kBroadcastId = 0xFE;
constexpr std::uint8_t kMaxServoId = 252;
constexpr std::size_t kHeaderBytes = 4;          // FF FF FD 00
constexpr std::size_t kInstructionOverhead = 10;  // header, ID, LEN (2), INST, CRC (2)
constexpr std::size_t kStatusOverhead = 11;       // the same plus the error byte
// Largest packet we build or accept, stuffing included. Bounds every fixed buffer of a bus.
constexpr std::size_t kMaxPacketBytes = 2048;

// The error byte of a status packet.
constexpr std::uint8_t kAlertBit = 0x80;          // a hardware error is present (read address 70)
constexpr std::uint8_t kErrorNumberMask = 0x7F;
namespace servo_error {
constexpr std::uint8_t kResultFail = 1;
constexpr std::uint8_t kInstructionError = 2;
constexpr std::uint8_t kCrcError = 3;
constexpr std::uint8_t kDataRangeError = 4;
constexpr std::uint8_t kDataLengthError = 5;
constexpr std::uint8_t kDataLimitError = 6;
constexpr std::uint8_t kAccessError = 7;
}  // namespace servo_error
// "data limit error", "unknown error 9", ... (static strings).
const char* servo_error_name(std::uint8_t error_number) noexcept;

// CRC-16 of Protocol 2.0: polynomial 0x8005, initial value 0, not reflected, no final xor.
// Pass a previous result as `crc` to continue over a second buffer. crc16("123456789") == 0xFEE8.
std::uint16_t crc16(const std::uint8_t* data, std::size_t size, std::uint16_t crc = 0) noexcept;

// Byte stuffing of the INST + PARAM region: every FF FF FD gets an extra FD after it.
// Returns the number of bytes written, or kNoSpace when `capacity` is too small.
constexpr std::size_t kNoSpace = static_cast<std::size_t>(-1);
std::size_t stuff(const std::uint8_t* in, std::size_t size, std::uint8_t* out, std::size_t capacity) noexcept;
// The inverse: drops the FD that follows FF FF FD. Same return convention, plus kBadStuffing when
// an FF FF FD is not followed by its stuffed FD (the sender always adds one, even at the end of
// the region). `out` may equal `in`.
constexpr std::size_t kBadStuffing = static_cast<std::size_t>(-2);
std::size_t unstuff(const std::uint8_t* in, std::size_t size, std::uint8_t* out, std::size_t capacity) noexcept;

// Little-endian helpers (Dynamixel sends low byte first). Sizes 1, 2 or 4; `is_signed`
// sign-extends 1- and 2-byte values.
std::int32_t get_le(const std::uint8_t* p, std::size_t size, bool is_signed) noexcept;
void put_le(std::uint8_t* p, std::size_t size, std::int64_t value) noexcept;

// Builds one packet in a caller-owned buffer, stuffing as it goes, with no temporary buffer:
//   PacketEncoder e(buf, sizeof buf);
//   e.begin(kBroadcastId, instruction::kSyncWrite); e.put16(116); e.put16(4); ...;
//   std::size_t n = e.finish();   // 0 when the packet did not fit
class PacketEncoder {
 public:
  PacketEncoder(std::uint8_t* buffer, std::size_t capacity) noexcept : buf_(buffer), cap_(capacity) {}
  void begin(std::uint8_t id, std::uint8_t instruction) noexcept;
  void put(std::uint8_t byte) noexcept;
  void put(const std::uint8_t* bytes, std::size_t size) noexcept;
  void put16(std::uint16_t value) noexcept;
  void put32(std::uint32_t value) noexcept;
  // Fills LEN and the CRC. Returns the packet size in bytes, or 0 if the buffer overflowed.
  std::size_t finish() noexcept;

 private:
  std::uint8_t* buf_;
  std::size_t cap_;
  std::size_t n_ = 0;
  std::uint8_t last1_ = 0, last2_ = 0;  // the two previous unstuffed bytes of the region
  bool overflow_ = false;
};

// Whole packets in one call (tests, the mock bus). Return the size, 0 if it did not fit.
std::size_t encode_packet(std::uint8_t id, std::uint8_t instruction, const std::uint8_t* params, std::size_t n_params,
                          std::uint8_t* out, std::size_t capacity) noexcept;
std::size_t encode_status(std::uint8_t id, std::uint8_t error, const std::uint8_t* data, std::size_t n_data,
                          std::uint8_t* out, std::size_t capacity) noexcept;

// A parsed packet. `params` points into the caller's scratch buffer and is un-stuffed; for a
// status packet params[0] is the error byte.
struct Packet {
  std::uint8_t id = 0;
  std::uint8_t instruction = 0;
  const std::uint8_t* params = nullptr;
  std::size_t n_params = 0;
};

enum class ParseStatus : std::uint8_t {
  kOk,          // a packet with a valid CRC; drop `consumed` bytes
  kIncomplete,  // no complete packet yet; bytes before `consumed` are garbage and can be dropped
  kBadCrc,      // a whole packet whose CRC does not match; drop `consumed` bytes (the packet)
  kMalformed,   // a header with an impossible length, cut short by the next header (truncated), or
                // a valid CRC over a region that breaks byte stuffing (FF FF FD not followed by FD)
};
const char* to_string(ParseStatus status) noexcept;

struct ParseResult {
  ParseStatus status = ParseStatus::kIncomplete;
  std::size_t consumed = 0;  // bytes the caller removes from the front of its input
  std::size_t start = 0;     // offset of the header of the packet reported (kOk/kBadCrc/kMalformed)
  std::uint8_t id = 0;       // ID byte of that header (as received, maybe corrupt)
};

// Finds the first packet in `in`: skips garbage before the header (FF FF FD FD, the stuffed
// pattern, is never taken for a header), checks LEN, the CRC, and un-stuffs INST + PARAMs into
// `scratch` (needs LEN - 2 bytes). Stuffing guarantees FF FF FD 00 never occurs inside a packet,
// so a header inside the span LEN announces (seen before the span is complete, or when its CRC
// fails) means the first packet was truncated: kMalformed, consumed up to the next header. When the
// CRC fails and the input ends on what may be the start of such a header, kIncomplete: the bytes
// that decide have not arrived. So however the reads chunk the bytes, a packet following a damaged
// one is never dropped with it. A valid CRC over broken stuffing is kMalformed (header consumed).
// `input_ended`: no more bytes will come (a reply deadline passed): nothing is held back for them.
ParseResult parse_packet(const std::uint8_t* in, std::size_t size, std::uint8_t* scratch, std::size_t scratch_capacity,
                         Packet* out, bool input_ended = false) noexcept;

}  // namespace snake_autonomy::dynamixel
