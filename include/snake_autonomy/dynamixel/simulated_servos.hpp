// SimulatedServos: the one simulated Dynamixel chain. N servos, each with its control-table memory
// (defaults from config/dynamixel/<model>.yaml), answering raw Protocol 2.0 packets as the real ones
// do where the driver cares. Both simulated buses are this class: FakeServoBus (in-process, gtests and
// the batch simulator) runs Protocol2Bus over a loopback into it; the pty mock (Python,
// snake_autonomy.sim.mock_servo_bus) forwards the bytes it reads from the pty to it.
//
// Rules (one list, tested in test_simulated_servos.cpp):
//   PING (unicast or broadcast: every servo, ID order): model number + firmware version.
//   READ: 4 parameters else data length error; past the 1024-byte memory: data range error.
//   WRITE (unicast, or broadcast without reply): all or nothing. Fewer than 3 parameters: data length
//     error; past the memory: data range error; a read-only entry, or an EEPROM entry while torque is
//     on: access error; an entry cut by the write's bounds: data length error; outside [min, max] of
//     the YAML or a goal outside the servo's position limits: data limit error; torque on while a
//     hardware error stands: result fail.
//   REBOOT: the servo answers, then clears its hardware error, torque off.
//   SYNC_WRITE / SYNC_READ / FAST_SYNC_READ: broadcast only, >= 4 parameters (else silence); a read
//     past the memory is answered with data range errors; a FAST_SYNC_READ reply larger than one
//     packet is refused with one data length error status from ID 0xFE.
//   Other instructions: instruction error. Status packets, other IDs: silence. A bad CRC naming one
//     of our servos: a CRC error status from it; a malformed packet: silence.
//   A hardware error (set_hardware_error) sets the alert bit in every reply and turns torque off.
//
// Fault vocabulary (the same names in C++, Python, the control socket and the docs):
//   reply faults, by inject(kind, ids, count): drop_reply | corrupt_crc | truncate_reply |
//     garbage_before | garbage_data; per servo: silent (answers nothing, still obeys what it hears),
//     hardware_error (bits); per transport: bus_down (FakeServoBus) / close_pty (the pty mock).
//
// What moves the shafts is not here: a ShaftHooks implementation refreshes the present values before
// a read and hears goal and torque changes (the first-order model or MuJoCo in Python); without hooks,
// set_follow_goal(true) makes Present Position jump to each accepted goal (FakeServoBus).
//
// Real time: handle() and the memory accessors are noexcept and allocate nothing (buffers are sized at
// construction); configuration (constructor, inject with an unknown ID, get/set by name) throws
// ConfigError naming the value.
#pragma once

#include <array>
#include <bitset>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "snake_autonomy/dynamixel/control_table.hpp"
#include "snake_autonomy/dynamixel/protocol.hpp"

namespace snake_autonomy::dynamixel {

// How the next replies are damaged (see the vocabulary above).
enum class ReplyFault : std::uint8_t {
  kDropReply,      // no reply (the instruction is still carried out)
  kCorruptCrc,     // the last CRC byte flipped
  kTruncateReply,  // only the first half of the packet (at least 5 bytes)
  kGarbageBefore,  // 00 13 FF FF FD FD sent before the packet
  kGarbageData,    // every data byte 0xA5, valid CRC
};
constexpr std::size_t kNumReplyFaults = 5;
const char* to_string(ReplyFault kind) noexcept;
// false when `name` is none of the names above.
bool reply_fault_from_string(const std::string& name, ReplyFault* kind) noexcept;

// Counts since construction or reset_stats().
struct SimulatedServoStats {
  std::uint64_t packets = 0;          // valid packets received
  std::uint64_t bad_packets = 0;      // bad CRC or malformed
  std::uint64_t dropped = 0;          // replies that did not fit the output buffer (0 expected)
  std::uint64_t bytes_received = 0;
  std::uint64_t bytes_sent = 0;
  std::uint64_t replies = 0;          // status packets built (before damage)
  std::uint64_t replies_damaged = 0;
  std::uint64_t rejected_writes = 0;  // writes a servo refused (error status or silently, broadcast)
  std::uint64_t superseded = 0;       // answers not sent because a later packet came in the same read
  std::uint64_t ping = 0, read = 0, write = 0, reboot = 0, sync_read = 0, sync_write = 0, fast_sync_read = 0;
};

class SimulatedServos;

// What moves the shafts (called from handle(), on the caller's thread).
class ShaftHooks {
 public:
  virtual ~ShaftHooks() = default;
  // Before a write is applied (bring the physics up to now).
  virtual void before_write(SimulatedServos& servos) noexcept = 0;
  // Before a read is answered: write the present values with SimulatedServos::set_present.
  virtual void before_read(SimulatedServos& servos) noexcept = 0;
  virtual void on_goal(std::uint8_t id, std::int32_t goal_ticks) noexcept = 0;
  virtual void on_torque(std::uint8_t id, bool enabled) noexcept = 0;
};

class SimulatedServos {
 public:
  static constexpr std::size_t kMemoryBytes = 1024;
  static constexpr std::size_t kMaxFaults = 32;

  // Throws ConfigError for an invalid table, an ID outside 0..252 or a repeated ID.
  SimulatedServos(const ControlTable& table, const std::vector<std::uint8_t>& ids);

  // Feeds received bytes (any chunking: partial packets wait for the rest); the servos' replies are
  // in output()/output_size() until the next call. noexcept, no allocation. latest_only (the pty
  // mock): when several packets came in one read, the master sent the later ones after giving up on
  // the earlier ones, so only the replies to the last packet are sent (a real servo's late answer
  // would have collided with them); the earlier ones still act (writes are applied), counted as
  // superseded.
  std::size_t handle(const std::uint8_t* in, std::size_t size, bool latest_only = false) noexcept;
  const std::uint8_t* output() const noexcept { return out_.data(); }
  std::size_t output_size() const noexcept { return out_size_; }
  void clear_input() noexcept { rx_size_ = 0; }
  // The received bytes not decided yet (a packet still arriving).
  const std::uint8_t* input() const noexcept { return rx_.data(); }
  std::size_t input_size() const noexcept { return rx_size_; }

  // --- faults ---
  // Damages the next `count` replies (count < 0: until cleared) of the servos `ids` (empty: every
  // servo). Throws ConfigError for an ID not on the bus, a count of 0 or more than kMaxFaults faults.
  void inject(ReplyFault kind, const std::vector<std::uint8_t>& ids, int count);
  void set_silent(std::uint8_t id, bool silent);
  bool silent(std::uint8_t id) const;
  // Hardware Error Status bits; non-zero also turns torque off (the servo's shutdown).
  void set_hardware_error(std::uint8_t id, std::uint8_t bits);
  // Removes every injected fault, silence and hardware error.
  void clear_faults() noexcept;
  void set_follow_goal(bool follow) noexcept { follow_goal_ = follow; }
  // Not owned; nullptr: none. Must outlive this object or be reset.
  void set_hooks(ShaftHooks* hooks) noexcept { hooks_ = hooks; }

  // --- memory ---
  const ControlTable& table() const noexcept { return table_; }
  const std::vector<std::uint8_t>& ids() const noexcept { return ids_; }
  bool has(std::uint8_t id) const noexcept { return index_[id] >= 0; }
  std::int64_t get(std::uint8_t id, const std::string& entry) const;        // throws for unknown id/entry
  void set(std::uint8_t id, const std::string& entry, std::int64_t value);  // no checks: the caller's word
  // The present values (raw units of the table), as a ShaftHooks::before_read writes them; values
  // outside an entry's integer range are saturated. Unknown id: ignored.
  void set_present(std::uint8_t id, std::int64_t position, std::int64_t velocity, std::int64_t current,
                   std::int64_t input_voltage, std::int64_t temperature) noexcept;
  std::uint64_t goal_writes(std::uint8_t id) const;
  const SimulatedServoStats& stats() const noexcept { return stats_; }
  void reset_stats() noexcept;

 private:
  struct Servo {
    std::uint8_t id = 0;
    std::array<std::uint8_t, kMemoryBytes> memory{};
    bool silent = false;
    std::uint64_t goal_writes = 0;
  };
  struct Fault {
    ReplyFault kind = ReplyFault::kDropReply;
    std::bitset<256> ids;  // none set: every servo
    int remaining = -1;
  };
  struct Damage {
    bool any = false;
    std::array<bool, kNumReplyFaults> kinds{};
  };
  struct Entry {  // an entry's place, resolved at construction
    std::uint16_t address = 0;
    std::uint8_t size = 0;
    bool is_signed = false;
  };

  Servo& servo(std::uint8_t id) noexcept { return servos_[static_cast<std::size_t>(index_[id])]; }
  const Servo& servo_or_throw(std::uint8_t id) const;
  void dispatch(const Packet& p) noexcept;
  void on_bad_crc(std::uint8_t id) noexcept;
  std::uint8_t apply_write(Servo& s, std::uint16_t address, const std::uint8_t* data, std::size_t length) noexcept;
  void set_torque(Servo& s, bool on) noexcept;
  std::uint8_t alert(const Servo& s) const noexcept;
  Damage take_faults(const std::uint8_t* ids, std::size_t n) noexcept;
  // Encodes one status packet of servo s and appends it, damaged as the faults say.
  void reply(const Servo& s, std::uint8_t error, const std::uint8_t* data, std::size_t n) noexcept;
  void fast_reply(const std::uint8_t* ids, std::size_t n, std::uint16_t address, std::uint16_t length) noexcept;
  void append(const std::uint8_t* packet, std::size_t size, const Damage& d) noexcept;
  void refresh() noexcept;

  ControlTable table_;
  std::vector<std::uint8_t> ids_;
  std::vector<Servo> servos_;
  std::array<int, 256> index_{};
  std::array<Fault, kMaxFaults> faults_{};
  std::size_t n_faults_ = 0;
  ShaftHooks* hooks_ = nullptr;
  bool follow_goal_ = false;
  bool refreshed_ = false;  // present values refreshed for the packet being answered
  SimulatedServoStats stats_;
  Entry torque_, hw_error_, goal_, min_pos_, max_pos_, firmware_;
  Entry present_pos_, present_vel_, present_cur_, present_volt_, present_temp_;
  std::vector<std::uint8_t> rx_;      // received, not yet parsed
  std::size_t rx_size_ = 0;
  std::vector<std::uint8_t> out_;     // replies of the last handle()
  std::size_t out_size_ = 0;
  std::array<std::uint8_t, kMaxPacketBytes> scratch_{};  // un-stuffed parameters
  std::array<std::uint8_t, kMaxPacketBytes> packet_{};   // one reply being built
  std::array<std::uint8_t, kMaxPacketBytes> body_{};     // a fast sync read's un-stuffed body
  std::array<std::uint8_t, kMaxPacketBytes> data_{};     // data of one reply
  std::array<std::uint8_t, 256> group_{};                // servo IDs of a group read
};

}  // namespace snake_autonomy::dynamixel
