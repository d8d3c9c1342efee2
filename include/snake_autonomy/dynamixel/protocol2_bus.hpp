// Protocol2Bus: the ServoBus protocol engine over any byte transport (a serial port, or a scripted
// transport in unit tests). Fixed buffers sized by kMaxPacketBytes; no allocation after construction.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>

#include "snake_autonomy/dynamixel/protocol.hpp"
#include "snake_autonomy/dynamixel/servo_bus.hpp"

namespace snake_autonomy::dynamixel {

using SteadyTime = std::chrono::steady_clock::time_point;

// The byte pipe under a bus. Implementations: SerialPort (termios), test doubles.
class Transport {
 public:
  virtual ~Transport() = default;
  virtual bool is_open() const noexcept = 0;
  // Writes every byte; false on an I/O error.
  virtual bool write_all(const std::uint8_t* data, std::size_t size) noexcept = 0;
  // Waits until at least one byte is available or `deadline` passes, then reads what is there (up
  // to `capacity`). Returns the number of bytes read (0 at the deadline), or -1 on an I/O error.
  virtual long read_some(std::uint8_t* buffer, std::size_t capacity, SteadyTime deadline) noexcept = 0;
  // Drops whatever was received and not read yet (late replies of an earlier transaction).
  virtual void discard_input() noexcept = 0;
  virtual int baud_bps() const noexcept = 0;
};

// How long to wait for replies. The deadline of a transaction is
//   latency_s + n_replies * return_delay_s + margin * (bytes out + bytes back) * 10 / baud
// (10 bits per byte on the wire: start, 8 data, stop).
struct BusTiming {
  double latency_s = 0.003;       // USB-serial latency (FTDI low latency: 1 ms) and OS scheduling
  double return_delay_s = 0.0;    // the servos' Return Delay Time (address 9, 2 us per unit); set it to 0
  double margin = 1.5;            // factor on the wire time (stuffing, inter-byte gaps)
};
// After a transaction that failed (timeout, CRC error, truncated or garbled reply) the bus drains:
// it reads and discards until the line has been quiet for the failed transaction's own reply
// deadline, for at most kDrainQuietPeriods of them in total (a babbling line cannot stall it).
// Status packets carry nothing that ties them to their request (ID, error, params only): a reply
// arriving after its deadline would otherwise be taken as the answer to the next request.
constexpr double kDrainQuietPeriods = 4.0;
// Seconds to move `bytes` bytes at `baud_bps` (10 bits per byte).
double wire_time_s(std::size_t bytes, int baud_bps) noexcept;
// The deadline above, in seconds.
double reply_timeout_s(std::size_t bytes_out, std::size_t bytes_back, std::size_t n_replies, int baud_bps,
                       const BusTiming& timing) noexcept;

class Protocol2Bus : public ServoBus {
 public:
  // `transport` must outlive the bus.
  explicit Protocol2Bus(Transport& transport, const BusTiming& timing = BusTiming{}) noexcept
      : transport_(transport), timing_(timing) {}

  Status ping(std::uint8_t id, std::uint16_t* model_number, std::uint8_t* error) noexcept override;
  // After a failed transaction (the bus is suspect: a late reply may still be on its way, later
  // than the drain waited) a read is verified: repeated until two consecutive replies agree (at
  // most kVerifyAttempts reads, else kMalformed), so a late reply to an earlier request carrying
  // another register's value is refused, counted in verify_mismatches. PING is verified the same way.
  Status read(std::uint8_t id, std::uint16_t address, std::uint16_t length, std::uint8_t* data,
              std::uint8_t* error) noexcept override;
  static constexpr int kVerifyAttempts = 4;
  bool suspect() const noexcept { return suspect_; }
  Status write(std::uint8_t id, std::uint16_t address, const std::uint8_t* data, std::uint16_t length,
               std::uint8_t* error) noexcept override;
  Status reboot(std::uint8_t id, std::uint8_t* error) noexcept override;
  Status sync_write(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                    const std::uint8_t* data) noexcept override;
  Status sync_read(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                   std::uint8_t* data, ServoReply* replies) noexcept override;
  Status fast_sync_read(std::uint16_t address, std::uint16_t length, const std::uint8_t* ids, std::size_t n,
                        std::uint8_t* data, ServoReply* replies) noexcept override;

  const BusCounters& counters() const noexcept override { return counters_; }
  void reset_counters() noexcept override { counters_ = BusCounters{}; }
  void set_return_delay_s(double seconds) noexcept override { timing_.return_delay_s = seconds; }
  double return_delay_s() const noexcept override { return timing_.return_delay_s; }

  const BusTiming& timing() const noexcept { return timing_; }
  void set_timing(const BusTiming& timing) noexcept { timing_ = timing; }

 private:
  // What receive() found.
  enum class Event : std::uint8_t { kPacket, kBadCrc, kMalformed, kDeadline, kIoError };
  Status send(std::size_t size) noexcept;
  // Sends a (FAST_)SYNC_READ request for n servos and resets their replies; on a send failure every
  // reply gets that status. *size receives the request's size on the wire.
  Status send_group_read(std::uint8_t instruction_code, std::uint16_t address, std::uint16_t length,
                         const std::uint8_t* ids, std::size_t n, ServoReply* replies, std::size_t* size) noexcept;
  Event receive(SteadyTime deadline, Packet* packet, std::uint8_t* id) noexcept;
  Status transact(std::uint8_t id, std::size_t tx_size, std::size_t data_bytes, std::uint8_t* data,
                  std::uint8_t* error) noexcept;
  // transact() of the request in tx_, verified when the bus is suspect (see read()).
  Status verified(std::uint8_t id, std::size_t tx_size, std::size_t data_bytes, std::uint8_t* data,
                  std::uint8_t* error) noexcept;
  SteadyTime deadline_for(std::size_t bytes_out, std::size_t bytes_back, std::size_t n_replies) const noexcept;
  Status record_reply(Status s) noexcept;
  // Reads and discards until the line is quiet for `quiet_s` (bounded, see kDrainQuietPeriods).
  void drain(double quiet_s) noexcept;
  // The quiet time of a drain after a group read: one servo's reply deadline (not the whole
  // group's), so a dead servo costs the 100 Hz loop little more than its timeout.
  double single_reply_timeout_s(std::size_t data_bytes) const noexcept;
  // Ends a single-servo transaction: a failure drains and marks the bus suspect (see read()).
  Status finish(Status s, double timeout_s) noexcept;

  Transport& transport_;
  BusTiming timing_;
  BusCounters counters_;
  std::array<std::uint8_t, kMaxPacketBytes> tx_{};
  std::array<std::uint8_t, 4 * kMaxPacketBytes> rx_{};  // received, not yet parsed
  std::size_t rx_size_ = 0;
  std::array<std::uint8_t, kMaxPacketBytes> scratch_{};  // un-stuffed parameters of one packet
  // Set by a failed transaction, cleared by a verified read that agreed.
  bool suspect_ = false;
  std::array<std::uint8_t, kMaxPacketBytes> verify_{};  // the previous read of a verified read
};

}  // namespace snake_autonomy::dynamixel
