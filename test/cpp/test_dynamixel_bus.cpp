// Protocol2Bus over a scripted transport (an in-test servo emulator that can corrupt, drop and
// truncate replies), and FakeServoBus with its injected faults.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <functional>
#include <map>
#include <set>
#include <thread>
#include <vector>

#include "snake_autonomy/dynamixel/conversions.hpp"
#include "snake_autonomy/dynamixel/fake_servo_bus.hpp"
#include "snake_autonomy/dynamixel/protocol2_bus.hpp"

namespace dx = snake_autonomy::dynamixel;
using Bytes = std::vector<std::uint8_t>;

namespace {

Bytes status_packet(std::uint8_t id, std::uint8_t error, const std::uint8_t* data, std::size_t n) {
  Bytes out(dx::kMaxPacketBytes);
  out.resize(dx::encode_status(id, error, data, n, out.data(), out.size()));
  return out;
}

// Servos emulated at the byte level, with hooks to damage their replies.
struct Emulator {
  std::map<std::uint8_t, std::array<std::uint8_t, 256>> memory;
  std::set<std::uint8_t> silent;
  std::map<std::uint8_t, std::uint8_t> error_byte;
  std::function<void(std::uint8_t id, Bytes& reply)> damage = [](std::uint8_t, Bytes&) {};
  Bytes before_replies;  // garbage sent ahead of the first reply

  Bytes respond(const Bytes& pkt) {
    Bytes scratch(dx::kMaxPacketBytes);
    dx::Packet p;
    const auto r = dx::parse_packet(pkt.data(), pkt.size(), scratch.data(), scratch.size(), &p);
    if (r.status != dx::ParseStatus::kOk) return {};
    Bytes out = before_replies;
    const auto u16 = [&](std::size_t i) { return static_cast<std::uint16_t>(p.params[i] | (p.params[i + 1] << 8)); };
    const auto reply = [&](std::uint8_t id, const std::uint8_t* data, std::size_t n) {
      if (silent.count(id) || !memory.count(id)) return;
      Bytes b = status_packet(id, error_byte[id], data, n);
      damage(id, b);
      out.insert(out.end(), b.begin(), b.end());
    };
    switch (p.instruction) {
      case dx::instruction::kPing: {
        const std::uint8_t d[3] = {0x4C, 0x04, 46};
        reply(p.id, d, 3);
        break;
      }
      case dx::instruction::kRead:
        if (memory.count(p.id)) reply(p.id, &memory[p.id][u16(0)], u16(2));
        break;
      case dx::instruction::kWrite:
        if (memory.count(p.id)) {
          std::copy(p.params + 2, p.params + p.n_params, &memory[p.id][u16(0)]);
          reply(p.id, nullptr, 0);
        }
        break;
      case dx::instruction::kSyncWrite: {
        const std::uint16_t addr = u16(0), len = u16(2);
        for (std::size_t i = 4; i + 1 + len <= p.n_params; i += 1 + len) {
          if (memory.count(p.params[i]))
            std::copy(p.params + i + 1, p.params + i + 1 + len, &memory[p.params[i]][addr]);
        }
        break;
      }
      case dx::instruction::kSyncRead:
        for (std::size_t i = 4; i < p.n_params; ++i) reply(p.params[i], &memory[p.params[i]][u16(0)], u16(2));
        break;
      case dx::instruction::kFastSyncRead: {
        Bytes params;
        for (std::size_t i = 4; i < p.n_params; ++i) {
          const std::uint8_t id = p.params[i];
          if (silent.count(id) || !memory.count(id)) continue;
          if (!params.empty()) params.insert(params.end(), {0x00, 0x00});  // the previous block's CRC
          params.push_back(error_byte[id]);
          params.push_back(id);
          params.insert(params.end(), &memory[id][u16(0)], &memory[id][u16(0)] + u16(2));
        }
        Bytes b(dx::kMaxPacketBytes);
        b.resize(dx::encode_packet(dx::kBroadcastId, dx::instruction::kStatus, params.data(), params.size(), b.data(),
                                   b.size()));
        damage(dx::kBroadcastId, b);
        out.insert(out.end(), b.begin(), b.end());
        break;
      }
      default: break;
    }
    return out;
  }
};

class ScriptedTransport : public dx::Transport {
 public:
  explicit ScriptedTransport(Emulator* emu) : emu_(emu) {}
  bool is_open() const noexcept override { return open; }
  bool write_all(const std::uint8_t* data, std::size_t size) noexcept override {
    const Bytes pkt(data, data + size);
    written.insert(written.end(), pkt.begin(), pkt.end());
    const Bytes r = emu_->respond(pkt);
    pending.insert(pending.end(), r.begin(), r.end());
    return true;
  }
  long read_some(std::uint8_t* buffer, std::size_t capacity, dx::SteadyTime deadline) noexcept override {
    if (fail_reads) return -1;
    if (pending.empty()) {  // nothing more will come: wait for the deadline, as a port would
      std::this_thread::sleep_until(deadline);
      return 0;
    }
    const std::size_t n = std::min({capacity, pending.size(), chunk});
    std::copy(pending.begin(), pending.begin() + static_cast<long>(n), buffer);
    pending.erase(pending.begin(), pending.begin() + static_cast<long>(n));
    return static_cast<long>(n);
  }
  void discard_input() noexcept override {}
  int baud_bps() const noexcept override { return 1000000; }

  bool open = true;
  bool fail_reads = false;
  std::size_t chunk = 7;  // bytes per read: replies arrive in pieces, as from a USB adapter
  Bytes written, pending;

 private:
  Emulator* emu_;
};

constexpr std::size_t kN = 11;

struct BusFixture : ::testing::Test {
  Emulator emu;
  ScriptedTransport transport{&emu};
  dx::BusTiming timing{0.005, 0.0, 1.5};
  dx::Protocol2Bus bus{transport, timing};
  std::array<std::uint8_t, kN> ids{};
  std::array<std::uint8_t, kN * dx::kFeedbackBytes> feedback{};
  std::array<dx::ServoReply, kN> replies{};

  void SetUp() override {
    for (std::size_t i = 0; i < kN; ++i) {
      ids[i] = static_cast<std::uint8_t>(i + 1);
      auto& m = emu.memory[ids[i]];
      m.fill(0);
      // current -1, velocity -3, position 2048 + 100 i: the FF FF FD pattern in every reply
      dx::put_le(&m[126], 2, -1);
      dx::put_le(&m[128], 4, -3);
      dx::put_le(&m[132], 4, 2048 + 100 * static_cast<int>(i));
    }
    feedback.fill(0xEE);
  }
  std::int32_t position_of(std::size_t i) const {
    return dx::decode_feedback(&feedback[i * dx::kFeedbackBytes]).position_ticks;
  }
};

}  // namespace

TEST_F(BusFixture, SyncReadFeedbackOfElevenServosWithStuffing) {
  EXPECT_EQ(bus.sync_read(dx::kFeedbackAddress, dx::kFeedbackBytes, ids.data(), kN, feedback.data(), replies.data()),
            dx::Status::kOk);
  for (std::size_t i = 0; i < kN; ++i) {
    EXPECT_EQ(replies[i].status, dx::Status::kOk) << i;
    const auto f = dx::decode_feedback(&feedback[i * dx::kFeedbackBytes]);
    EXPECT_EQ(f.position_ticks, 2048 + 100 * static_cast<int>(i));
    EXPECT_NEAR(f.current_a, -2.69e-3, 1e-12);
    EXPECT_NEAR(f.velocity_rad_s, -3 * 0.229 * 2 * M_PI / 60, 1e-12);
  }
  EXPECT_EQ(bus.counters().bytes_sent, 25u);                       // 14 + 11 IDs
  EXPECT_EQ(bus.counters().bytes_received, kN * (11 + 10 + 1));    // one stuffed byte each
  EXPECT_EQ(bus.counters().packets_received, kN);
}

TEST_F(BusFixture, SyncReadFaultsAreAttributedToTheirServo) {
  emu.before_replies = {0x00, 0xFF, 0x13, 0xFF, 0xFF, 0xFD, 0xFD};  // garbage, stuffed pattern included
  emu.silent.insert(3);
  emu.error_byte[9] = dx::kAlertBit;
  emu.damage = [](std::uint8_t id, Bytes& b) {
    if (id == 5) b[10] ^= 0x40;                 // bad CRC
    if (id == 7) b.resize(b.size() - 3);        // truncated
  };
  const auto t0 = std::chrono::steady_clock::now();
  const dx::Status s =
      bus.sync_read(dx::kFeedbackAddress, dx::kFeedbackBytes, ids.data(), kN, feedback.data(), replies.data());
  const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(s, dx::Status::kTimeout);  // the first servo (in ID order) that failed: 3
  for (std::size_t i = 0; i < kN; ++i) {
    const int id = static_cast<int>(i + 1);
    const dx::Status want = id == 3   ? dx::Status::kTimeout
                            : id == 5 ? dx::Status::kCrcError
                            : id == 7 ? dx::Status::kMalformed
                            : id == 9 ? dx::Status::kHardwareError
                                      : dx::Status::kOk;
    EXPECT_EQ(replies[i].status, want) << "id " << id << ": " << dx::to_string(replies[i].status);
    if (dx::has_data(want)) {
      EXPECT_EQ(position_of(i), 2048 + 100 * static_cast<int>(i)) << id;
    } else {
      EXPECT_EQ(feedback[i * dx::kFeedbackBytes], 0xEE) << "id " << id << ": data must stay untouched";
    }
  }
  EXPECT_EQ(replies[8].error, dx::kAlertBit);
  const auto& c = bus.counters();
  EXPECT_EQ(c.timeouts, 1u);
  EXPECT_EQ(c.crc_errors, 1u);
  EXPECT_EQ(c.malformed, 1u);
  EXPECT_EQ(c.hardware_error_alerts, 1u);
  EXPECT_LT(dt, 0.2);  // bounded by the computed deadline (~9 ms), not hung
}

TEST_F(BusFixture, FastSyncReadSameDataFewerBytes) {
  EXPECT_EQ(
      bus.fast_sync_read(dx::kFeedbackAddress, dx::kFeedbackBytes, ids.data(), kN, feedback.data(), replies.data()),
      dx::Status::kOk);
  for (std::size_t i = 0; i < kN; ++i) {
    EXPECT_EQ(replies[i].status, dx::Status::kOk) << i;
    EXPECT_EQ(position_of(i), 2048 + 100 * static_cast<int>(i));
  }
  EXPECT_EQ(bus.counters().bytes_sent, 25u);
  // 8 (header, ID, LEN, INST) + 11 blocks of ERR ID DATA CRC, plus the stuffed bytes.
  EXPECT_GE(bus.counters().bytes_received, 8u + kN * 14);
  EXPECT_LE(bus.counters().bytes_received, 8u + kN * 14 + 2 * kN);
}

TEST_F(BusFixture, FastSyncReadMissingServoAndBadCrc) {
  emu.silent.insert(4);
  EXPECT_EQ(
      bus.fast_sync_read(dx::kFeedbackAddress, dx::kFeedbackBytes, ids.data(), kN, feedback.data(), replies.data()),
      dx::Status::kTimeout);
  for (std::size_t i = 0; i < kN; ++i)
    EXPECT_EQ(replies[i].status, i == 3 ? dx::Status::kTimeout : dx::Status::kOk) << i;
  EXPECT_EQ(bus.counters().timeouts, 1u);

  emu.silent.clear();
  emu.damage = [](std::uint8_t, Bytes& b) { b[b.size() - 1] ^= 0xFF; };
  EXPECT_EQ(
      bus.fast_sync_read(dx::kFeedbackAddress, dx::kFeedbackBytes, ids.data(), kN, feedback.data(), replies.data()),
      dx::Status::kCrcError);
  for (const auto& r : replies) EXPECT_EQ(r.status, dx::Status::kCrcError);
  EXPECT_EQ(bus.counters().crc_errors, 1u);
}

TEST_F(BusFixture, SyncWriteGoalsAndBytesPerCycle) {
  std::array<std::uint8_t, kN * 4> goals{};
  for (std::size_t i = 0; i < kN; ++i) dx::put_le(&goals[i * 4], 4, 1000 + static_cast<int>(i));
  EXPECT_EQ(bus.sync_write(dx::kGoalPositionAddress, dx::kGoalPositionBytes, ids.data(), kN, goals.data()),
            dx::Status::kOk);
  EXPECT_EQ(transport.written.size(), 69u);  // 12 + 11 * (1 + 4) + 2
  for (std::size_t i = 0; i < kN; ++i)
    EXPECT_EQ(dx::get_le(&emu.memory[ids[i]][116], 4, true), 1000 + static_cast<int>(i));
  bus.reset_counters();
  // One cycle, feedback sync read + goal sync write: the ~325-byte minimum of the issue (plus stuffing).
  for (auto& [id, m] : emu.memory) dx::put_le(&m[126], 2, 5);  // no FF FF FD: the plain minimum
  bus.sync_read(dx::kFeedbackAddress, dx::kFeedbackBytes, ids.data(), kN, feedback.data(), replies.data());
  bus.sync_write(dx::kGoalPositionAddress, dx::kGoalPositionBytes, ids.data(), kN, goals.data());
  EXPECT_EQ(bus.counters().bytes_sent + bus.counters().bytes_received, 325u);
  bus.reset_counters();
  bus.fast_sync_read(dx::kFeedbackAddress, dx::kFeedbackBytes, ids.data(), kN, feedback.data(), replies.data());
  bus.sync_write(dx::kGoalPositionAddress, dx::kGoalPositionBytes, ids.data(), kN, goals.data());
  EXPECT_EQ(bus.counters().bytes_sent + bus.counters().bytes_received, 25u + 162u + 69u);
}

TEST_F(BusFixture, PingReadWriteReboot) {
  std::uint16_t model = 0;
  std::uint8_t err = 0xEE;
  EXPECT_EQ(bus.ping(1, &model, &err), dx::Status::kOk);
  EXPECT_EQ(model, 1100);
  EXPECT_EQ(err, 0);
  // A reply from another servo first (late, or an echo) is skipped and counted.
  emu.before_replies = status_packet(9, 0, nullptr, 0);
  EXPECT_EQ(bus.ping(2, &model, &err), dx::Status::kOk);
  EXPECT_EQ(bus.counters().unexpected_packets, 1u);
  emu.before_replies.clear();
  std::uint8_t pos[4];
  EXPECT_EQ(bus.read(3, 132, 4, pos, &err), dx::Status::kOk);
  EXPECT_EQ(dx::get_le(pos, 4, true), 2248);
  const std::uint8_t on = 1;
  EXPECT_EQ(bus.write(3, 64, &on, 1, &err), dx::Status::kOk);
  EXPECT_EQ(emu.memory[3][64], 1);
  EXPECT_EQ(bus.read(42, 132, 4, pos, &err), dx::Status::kTimeout);  // nobody has ID 42
  EXPECT_EQ(bus.counters().timeouts, 1u);
  emu.error_byte[3] = dx::kAlertBit | dx::servo_error::kDataLimitError;
  EXPECT_EQ(bus.write(3, 116, pos, 4, &err), dx::Status::kServoError);
  EXPECT_EQ(err, 0x86);
  EXPECT_EQ(bus.counters().servo_errors, 1u);
}

TEST_F(BusFixture, IoErrorsAndInvalidArguments) {
  std::uint8_t data[4];
  EXPECT_EQ(bus.read(253, 132, 4, data, nullptr), dx::Status::kInvalidArgument);
  EXPECT_EQ(bus.read(1, 132, 0, data, nullptr), dx::Status::kInvalidArgument);
  EXPECT_EQ(bus.sync_read(126, 10, ids.data(), 0, feedback.data(), replies.data()), dx::Status::kInvalidArgument);
  const std::uint8_t bad_ids[2] = {1, 254};
  EXPECT_EQ(bus.sync_write(116, 4, bad_ids, 2, data), dx::Status::kInvalidArgument);
  std::vector<std::uint8_t> big(3000);
  EXPECT_EQ(bus.write(1, 0, big.data(), static_cast<std::uint16_t>(big.size()), nullptr), dx::Status::kInvalidArgument);
  transport.fail_reads = true;
  EXPECT_EQ(bus.sync_read(126, 10, ids.data(), kN, feedback.data(), replies.data()), dx::Status::kIoError);
  EXPECT_EQ(replies[0].status, dx::Status::kIoError);
  transport.open = false;
  EXPECT_EQ(bus.ping(1, nullptr, nullptr), dx::Status::kNotOpen);
}

// ---------------------------------------------------------------------------------------------
namespace {
struct FakeFixture : ::testing::Test {
  dx::ControlTable table =
      dx::ControlTable::from_yaml_file(std::string(SNAKE_SOURCE_DIR) + "/config/dynamixel/xh540_w270.yaml");
  std::vector<std::uint8_t> id_list{1, 2, 3};
  dx::FakeServoBus bus{table, id_list};
  std::array<std::uint8_t, 3 * 10> data{};
  std::array<dx::ServoReply, 3> replies{};

  void torque_on() {
    const std::uint8_t on[3] = {1, 1, 1};
    ASSERT_EQ(bus.sync_write(64, 1, id_list.data(), 3, on), dx::Status::kOk);
  }
  dx::Status goals(std::int32_t a, std::int32_t b, std::int32_t c) {
    std::uint8_t g[12];
    dx::put_le(g, 4, a);
    dx::put_le(g + 4, 4, b);
    dx::put_le(g + 8, 4, c);
    return bus.sync_write(116, 4, id_list.data(), 3, g);
  }
};
}  // namespace

TEST_F(FakeFixture, PingSyncWriteThenSyncReadRoundTrip) {
  std::uint16_t model = 0;
  EXPECT_EQ(bus.ping(2, &model, nullptr), dx::Status::kOk);
  EXPECT_EQ(model, 1100);
  torque_on();
  EXPECT_EQ(goals(1000, 2048, 3000), dx::Status::kOk);
  EXPECT_EQ(bus.sync_read(126, 10, id_list.data(), 3, data.data(), replies.data()), dx::Status::kOk);
  EXPECT_EQ(dx::decode_feedback(&data[0]).position_ticks, 1000);
  EXPECT_EQ(dx::decode_feedback(&data[20]).position_ticks, 3000);
  EXPECT_EQ(bus.servos().goal_writes(1), 1u);
  EXPECT_EQ(bus.servos().stats().sync_write, 2u);
  EXPECT_EQ(bus.servos().stats().sync_read, 1u);
}

TEST_F(FakeFixture, RefusesOutOfLimitGoalsAndEepromWithTorqueOn) {
  torque_on();
  bus.servos().set(2, "max_position_limit", 3000);  // a test's word: no checks
  EXPECT_EQ(goals(1000, 3001, 1000), dx::Status::kOk);  // sync write has no reply
  EXPECT_EQ(bus.servos().stats().rejected_writes, 1u);
  EXPECT_EQ(bus.servos().get(2, "goal_position"), 2048);  // unchanged
  EXPECT_EQ(bus.servos().get(1, "goal_position"), 1000);
  std::uint8_t err = 0;
  std::uint8_t v[4];
  dx::put_le(v, 4, -5);
  EXPECT_EQ(bus.write(1, 116, v, 4, &err), dx::Status::kServoError);
  EXPECT_EQ(err, dx::servo_error::kDataLimitError);
  const std::uint8_t mode = 1;
  EXPECT_EQ(bus.write(1, 11, &mode, 1, &err), dx::Status::kServoError);
  EXPECT_EQ(err, dx::servo_error::kAccessError);
  EXPECT_EQ(bus.write(1, 132, v, 4, &err), dx::Status::kServoError);  // present position is read-only
  EXPECT_EQ(err, dx::servo_error::kAccessError);
}

TEST_F(FakeFixture, InjectedFaults) {
  torque_on();
  bus.servos().set_silent(2, true);
  bus.servos().inject(dx::ReplyFault::kCorruptCrc, {3}, 1);
  EXPECT_EQ(bus.sync_read(126, 10, id_list.data(), 3, data.data(), replies.data()), dx::Status::kTimeout);
  EXPECT_EQ(replies[0].status, dx::Status::kOk);
  EXPECT_EQ(replies[1].status, dx::Status::kTimeout);
  EXPECT_EQ(replies[2].status, dx::Status::kCrcError);
  EXPECT_EQ(bus.counters().timeouts, 1u);
  EXPECT_EQ(bus.counters().crc_errors, 1u);
  bus.servos().set_silent(2, false);
  bus.servos().inject(dx::ReplyFault::kDropReply, {1}, 2);
  EXPECT_EQ(bus.sync_read(126, 10, id_list.data(), 3, data.data(), replies.data()), dx::Status::kTimeout);
  EXPECT_EQ(bus.sync_read(126, 10, id_list.data(), 3, data.data(), replies.data()), dx::Status::kTimeout);
  EXPECT_EQ(bus.sync_read(126, 10, id_list.data(), 3, data.data(), replies.data()), dx::Status::kOk);
  bus.servos().inject(dx::ReplyFault::kGarbageData, {1}, -1);
  EXPECT_EQ(bus.sync_read(126, 10, id_list.data(), 3, data.data(), replies.data()), dx::Status::kOk);
  EXPECT_EQ(dx::decode_feedback(&data[0]).position_ticks, static_cast<std::int32_t>(0xA5A5A5A5));
  bus.set_bus_down(true);
  EXPECT_EQ(bus.sync_read(126, 10, id_list.data(), 3, data.data(), replies.data()), dx::Status::kIoError);
  bus.clear_faults();
  EXPECT_EQ(bus.sync_read(126, 10, id_list.data(), 3, data.data(), replies.data()), dx::Status::kOk);
}

TEST_F(FakeFixture, HardwareErrorAlertTorqueOffUntilReboot) {
  torque_on();
  bus.servos().set_hardware_error(2, 0x20);  // overload
  EXPECT_EQ(bus.sync_read(126, 10, id_list.data(), 3, data.data(), replies.data()), dx::Status::kHardwareError);
  EXPECT_EQ(replies[1].status, dx::Status::kHardwareError);
  EXPECT_EQ(replies[1].error, dx::kAlertBit);
  EXPECT_EQ(bus.servos().get(2, "torque_enable"), 0);
  std::uint8_t hw = 0, err = 0;
  EXPECT_EQ(bus.read(2, 70, 1, &hw, &err), dx::Status::kHardwareError);
  EXPECT_EQ(table.describe_hardware_error(hw), "overload");
  const std::uint8_t on = 1;
  EXPECT_EQ(bus.write(2, 64, &on, 1, &err), dx::Status::kServoError);  // no torque with a hardware error
  // The status packet goes out before the servo restarts: it still carries the alert bit.
  EXPECT_EQ(bus.reboot(2, &err), dx::Status::kHardwareError);
  EXPECT_EQ(bus.read(2, 70, 1, &hw, &err), dx::Status::kOk);
  EXPECT_EQ(hw, 0);
  EXPECT_EQ(bus.counters().hardware_error_alerts, 3u);
  EXPECT_THROW(bus.servos().set_silent(99, true), dx::ConfigError);
  EXPECT_THROW(dx::FakeServoBus(table, {1, 1}), dx::ConfigError);
}
