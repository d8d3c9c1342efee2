// Result codes of the servo bus (the hot path returns these, it never throws), and the check of a
// status packet against what was asked.
#pragma once

#include <cstddef>
#include <cstdint>

#include "snake_autonomy/dynamixel/protocol.hpp"

namespace snake_autonomy::dynamixel {

enum class Status : std::uint8_t {
  kOk = 0,
  kHardwareError,     // reply valid, data valid, but the alert bit is set: read Hardware Error Status (70)
  kTimeout,           // no (complete) reply before the deadline
  kCrcError,          // a reply arrived with a bad CRC
  kMalformed,         // truncated reply, impossible length, wrong data length
  kWrongId,           // a valid status packet from another servo
  kWrongInstruction,  // a valid packet that is not a status packet
  kServoError,        // the servo refused the instruction (error number 1-7 in the error byte)
  kInvalidArgument,   // bad ID, length, too many servos, packet larger than kMaxPacketBytes
  kIoError,           // the port failed (closed, unplugged): reopen it
  kNotOpen,
};
const char* to_string(Status status) noexcept;

// True when a reply with this status carries usable data (kOk or kHardwareError).
constexpr bool has_data(Status s) noexcept { return s == Status::kOk || s == Status::kHardwareError; }

// Checks a parsed packet as the reply of servo `expected_id` carrying `expected_data_bytes` after
// the error byte. Order: wrong ID, not a status packet, no error byte, error number (the servo
// refused: kServoError), wrong data length, alert bit (kHardwareError), else kOk.
// `error_byte` receives the error byte when there is one (0 otherwise).
Status check_status_packet(const Packet& packet, std::uint8_t expected_id, std::size_t expected_data_bytes,
                           std::uint8_t* error_byte) noexcept;

}  // namespace snake_autonomy::dynamixel
