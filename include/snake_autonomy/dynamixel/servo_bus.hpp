// The servo bus: what the driver asks of a chain of Dynamixel servos, behind one interface with
// a serial implementation (SerialBus: termios, the real robot or the mocked bus on a pty) and an
// in-process fake for unit tests (FakeServoBus).
//
// Real-time contract: every method is noexcept, returns a Status, and does not allocate; buffers
// are the caller's (allocated once at configure time) or the bus's own fixed ones. The 100 Hz loop:
//
//   // configure time
//   std::array<uint8_t, 11> ids{1, ..., 11};
//   std::array<uint8_t, 11 * kFeedbackBytes> feedback;  std::array<ServoReply, 11> replies;
//   std::array<uint8_t, 11 * kGoalPositionBytes> goals;
//   // each cycle
//   bus.sync_read(kFeedbackAddress, kFeedbackBytes, ids.data(), 11, feedback.data(), replies.data());
//   for i: if (has_data(replies[i].status)) state[i] = decode_feedback(&feedback[i * kFeedbackBytes]);
//   for i: put_le(&goals[i * 4], 4, clamp_ticks(...));     // never outside the joint limits
//   bus.sync_write(kGoalPositionAddress, kGoalPositionBytes, ids.data(), 11, goals.data());
#pragma once

#include <cstddef>
#include <cstdint>

#include "snake_autonomy/dynamixel/status.hpp"

namespace snake_autonomy::dynamixel {

// Counts since construction or reset_counters(). One transaction = one instruction sent.
struct BusCounters {
  std::uint64_t transactions = 0;
  std::uint64_t bytes_sent = 0;
  std::uint64_t bytes_received = 0;
  std::uint64_t packets_received = 0;       // valid packets (CRC ok)
  std::uint64_t crc_errors = 0;             // packets with a bad CRC
  std::uint64_t timeouts = 0;               // one per expected reply that never came
  std::uint64_t malformed = 0;              // truncated, impossible length, wrong data length
  std::uint64_t hardware_error_alerts = 0;  // replies with the alert bit set
  std::uint64_t servo_errors = 0;           // replies with an error number (instruction refused)
  std::uint64_t unexpected_packets = 0;     // valid packets from another ID or not status packets
  std::uint64_t io_errors = 0;
  std::uint64_t drains = 0;                 // waits for a quiet line after a failed transaction
  std::uint64_t late_bytes = 0;             // bytes discarded by those waits (late or garbled replies)
  std::uint64_t verify_mismatches = 0;      // re-read after a failure disagreed (a late reply was taken)
};

// The outcome for one servo of a (sync) read.
struct ServoReply {
  Status status = Status::kTimeout;
  std::uint8_t error = 0;  // the status packet's error byte (alert bit 7, error number 0-6)
};

class ServoBus {
 public:
  virtual ~ServoBus() = default;

  // PING: the model number (1100 for an XH540-W270).
  virtual Status ping(std::uint8_t id, std::uint16_t* model_number, std::uint8_t* error) noexcept = 0;
  // READ `length` bytes from `address` into data.
  virtual Status read(std::uint8_t id, std::uint16_t address, std::uint16_t length, std::uint8_t* data,
                      std::uint8_t* error) noexcept = 0;
  // WRITE `length` bytes. id == kBroadcastId writes to every servo and waits for no reply.
  virtual Status write(std::uint8_t id, std::uint16_t address, const std::uint8_t* data, std::uint16_t length,
                       std::uint8_t* error) noexcept = 0;
  // REBOOT: clears a hardware error (the servo restarts with torque off).
  virtual Status reboot(std::uint8_t id, std::uint8_t* error) noexcept = 0;

  // SYNC_WRITE the same `length` bytes at `address` of n servos: servo ids[i] gets
  // data[i * length .. (i + 1) * length). Broadcast: there is no reply.
  virtual Status sync_write(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                            const std::uint8_t* data) noexcept = 0;
  // SYNC_READ `length` bytes at `address` of n servos: data[i * length ..] and replies[i] for
  // ids[i]. A servo whose reply carries no data (see has_data) keeps its bytes in `data` untouched,
  // so the caller still holds the last good values. Returns kOk when every servo answered kOk, else
  // the status of the first servo (in `ids` order) that did not.
  virtual Status sync_read(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                           std::uint8_t* data, ServoReply* replies) noexcept = 0;
  // FAST_SYNC_READ (0x8A): the same result, but the servos answer with one shared status packet
  // (fewer bytes on the wire: 4 + length per servo instead of 11 + length).
  virtual Status fast_sync_read(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                                std::uint8_t* data, ServoReply* replies) noexcept = 0;

  virtual const BusCounters& counters() const noexcept = 0;
  virtual void reset_counters() noexcept = 0;

  // The servos' Return Delay Time (the wait before each status packet), which a bus with reply
  // deadlines must allow for: once per reply, so n times in a sync read of n servos.
  virtual void set_return_delay_s(double seconds) noexcept = 0;
  virtual double return_delay_s() const noexcept = 0;
};

}  // namespace snake_autonomy::dynamixel
