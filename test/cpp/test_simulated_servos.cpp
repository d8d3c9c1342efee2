// SimulatedServos, the one simulated servo chain: every instruction and every fault, fed raw
// Protocol 2.0 packets and checked on the bytes that come back (table-driven).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "snake_autonomy/dynamixel/simulated_servos.hpp"

namespace dx = snake_autonomy::dynamixel;
using Bytes = std::vector<std::uint8_t>;

namespace {

const dx::ControlTable& table() {
  static const dx::ControlTable t =
      dx::ControlTable::from_yaml_file(std::string(SNAKE_SOURCE_DIR) + "/config/dynamixel/xh540_w270.yaml");
  return t;
}

Bytes packet(std::uint8_t id, std::uint8_t inst, const Bytes& params) {
  Bytes out(dx::kMaxPacketBytes);
  out.resize(dx::encode_packet(id, inst, params.data(), params.size(), out.data(), out.size()));
  return out;
}

Bytes le(std::int64_t v, int size) {
  Bytes b(static_cast<std::size_t>(size));
  dx::put_le(b.data(), static_cast<std::size_t>(size), v);
  return b;
}

Bytes cat(std::initializer_list<Bytes> parts) {
  Bytes out;
  for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

struct Reply {
  std::uint8_t id = 0;
  std::uint8_t error = 0;
  Bytes data;
};

// Every status packet in `bytes` (parsed with the project's codec); bad packets counted in *bad.
std::vector<Reply> replies(const Bytes& bytes, int* bad = nullptr) {
  std::vector<Reply> out;
  std::array<std::uint8_t, dx::kMaxPacketBytes> scratch{};
  std::size_t at = 0;
  while (at < bytes.size()) {
    dx::Packet p;
    const auto r = dx::parse_packet(bytes.data() + at, bytes.size() - at, scratch.data(), scratch.size(), &p, true);
    if (r.consumed == 0) break;
    at += r.consumed;
    if (r.status == dx::ParseStatus::kOk && p.instruction == dx::instruction::kStatus && p.n_params >= 1) {
      out.push_back(Reply{p.id, p.params[0], Bytes(p.params + 1, p.params + p.n_params)});
    } else if (r.status != dx::ParseStatus::kIncomplete && bad) {
      ++*bad;
    }
  }
  return out;
}

struct Servos : ::testing::Test {
  dx::SimulatedServos s{table(), {1, 2, 3}};
  Bytes send(const Bytes& p) {
    const std::size_t n = s.handle(p.data(), p.size());
    return Bytes(s.output(), s.output() + n);
  }
  std::vector<Reply> ask(std::uint8_t id, std::uint8_t inst, const Bytes& params) {
    return replies(send(packet(id, inst, params)));
  }
  std::uint8_t write(std::uint8_t id, std::uint16_t address, const Bytes& data) {
    const auto r = ask(id, dx::instruction::kWrite, cat({le(address, 2), data}));
    EXPECT_EQ(r.size(), 1u);
    return r.empty() ? 0xFF : r[0].error;
  }
};

}  // namespace

TEST_F(Servos, EveryInstructionAnswersAsTheServo) {
  struct Case {
    const char* what;
    std::uint8_t id, inst;
    Bytes params;
    std::size_t n_replies;
    std::uint8_t error;   // of every reply
    std::size_t data_bytes;
  };
  const std::vector<Case> cases = {
      {"ping", 2, dx::instruction::kPing, {}, 1, 0, 3},
      {"broadcast ping: every servo", dx::kBroadcastId, dx::instruction::kPing, {}, 3, 0, 3},
      {"ping of an absent ID: silence", 9, dx::instruction::kPing, {}, 0, 0, 0},
      {"read", 1, dx::instruction::kRead, cat({le(132, 2), le(4, 2)}), 1, 0, 4},
      {"read, 3 parameters", 1, dx::instruction::kRead, {132, 0, 4}, 1, dx::servo_error::kDataLengthError, 0},
      {"read past the memory", 1, dx::instruction::kRead, cat({le(1020, 2), le(8, 2)}), 1,
       dx::servo_error::kDataRangeError, 0},
      {"read of 0 bytes", 1, dx::instruction::kRead, cat({le(132, 2), le(0, 2)}), 1, dx::servo_error::kDataLengthError,
       0},
      {"broadcast read: silence", dx::kBroadcastId, dx::instruction::kRead, cat({le(132, 2), le(4, 2)}), 0, 0, 0},
      {"write LED", 3, dx::instruction::kWrite, cat({le(65, 2), le(1, 1)}), 1, 0, 0},
      {"write, 2 parameters", 3, dx::instruction::kWrite, le(65, 2), 1, dx::servo_error::kDataLengthError, 0},
      {"write a read-only entry", 3, dx::instruction::kWrite, cat({le(132, 2), le(5, 4)}), 1,
       dx::servo_error::kAccessError, 0},
      {"write half an entry", 3, dx::instruction::kWrite, cat({le(116, 2), le(5, 2)}), 1,
       dx::servo_error::kDataLengthError, 0},
      {"write outside [min, max]", 3, dx::instruction::kWrite, cat({le(65, 2), le(2, 1)}), 1,
       dx::servo_error::kDataLimitError, 0},
      {"write past the memory", 3, dx::instruction::kWrite, cat({le(1023, 2), le(0, 2)}), 1,
       dx::servo_error::kDataRangeError, 0},
      {"broadcast write: no reply", dx::kBroadcastId, dx::instruction::kWrite, cat({le(65, 2), le(1, 1)}), 0, 0, 0},
      {"reboot", 2, dx::instruction::kReboot, {}, 1, 0, 0},
      {"sync read: one reply each, asked order", dx::kBroadcastId, dx::instruction::kSyncRead,
       cat({le(126, 2), le(10, 2), {3, 1, 9}}), 2, 0, 10},
      {"sync read past the memory", dx::kBroadcastId, dx::instruction::kSyncRead, cat({le(1020, 2), le(10, 2), {1}}), 1,
       dx::servo_error::kDataRangeError, 0},
      {"sync read not broadcast: silence", 1, dx::instruction::kSyncRead, cat({le(126, 2), le(10, 2), {1}}), 0, 0, 0},
      {"sync read, 3 parameters: silence", dx::kBroadcastId, dx::instruction::kSyncRead, {126, 0, 10}, 0, 0, 0},
      {"sync write: no reply", dx::kBroadcastId, dx::instruction::kSyncWrite, cat({le(65, 2), le(1, 2), {1, 1, 2, 1}}),
       0, 0, 0},
      {"fast sync read: one packet", dx::kBroadcastId, dx::instruction::kFastSyncRead,
       cat({le(126, 2), le(10, 2), {1, 2, 3}}), 1, 0, 3 * 14 - 1 - 2},
      {"fast sync read too long for a packet", dx::kBroadcastId, dx::instruction::kFastSyncRead,
       cat({le(0, 2), le(1000, 2), {1, 2, 3}}), 1, dx::servo_error::kDataLengthError, 0},
      {"unknown instruction", 1, 0x04, {}, 1, dx::servo_error::kInstructionError, 0},
      {"a status packet: silence", 1, dx::instruction::kStatus, {0}, 0, 0, 0},
  };
  for (const auto& c : cases) {
    dx::SimulatedServos fresh{table(), {1, 2, 3}};
    const Bytes p = packet(c.id, c.inst, c.params);
    const std::size_t n = fresh.handle(p.data(), p.size());
    const auto r = replies(Bytes(fresh.output(), fresh.output() + n));
    ASSERT_EQ(r.size(), c.n_replies) << c.what;
    for (const auto& x : r) {
      EXPECT_EQ(x.error, c.error) << c.what;
      EXPECT_EQ(x.data.size(), c.data_bytes) << c.what;
    }
  }
}

TEST_F(Servos, MemoryRules) {
  EXPECT_EQ(ask(2, dx::instruction::kPing, {})[0].data, (Bytes{0x4C, 0x04, 46}));  // 1100, firmware 46
  EXPECT_EQ(write(1, 116, le(1000, 4)), 0);
  EXPECT_EQ(s.get(1, "goal_position"), 1000);
  EXPECT_EQ(s.goal_writes(1), 1u);
  EXPECT_EQ(write(1, 11, le(1, 1)), 0);  // EEPROM with torque off
  EXPECT_EQ(write(1, 64, le(1, 1)), 0);
  EXPECT_EQ(write(1, 11, le(3, 1)), dx::servo_error::kAccessError);  // EEPROM with torque on
  EXPECT_EQ(s.get(1, "operating_mode"), 1);                       // refused writes change nothing
  s.set(1, "max_position_limit", 3000);
  EXPECT_EQ(write(1, 116, le(3001, 4)), dx::servo_error::kDataLimitError);
  EXPECT_EQ(s.get(1, "goal_position"), 1000);
  // A sync write: servo 2 accepts, servo 1 refuses (past its limit), servo 9 is not here.
  send(packet(dx::kBroadcastId, dx::instruction::kSyncWrite,
              cat({le(116, 2), le(4, 2), {1}, le(3500, 4), {2}, le(2500, 4), {9}, le(1, 4)})));
  EXPECT_EQ(s.get(1, "goal_position"), 1000);
  EXPECT_EQ(s.get(2, "goal_position"), 2500);
  EXPECT_EQ(s.stats().rejected_writes, 3u);
  EXPECT_EQ(s.stats().sync_write, 1u);
  // Follow goal: present position jumps to an accepted goal while torque is on.
  s.set_follow_goal(true);
  EXPECT_EQ(write(1, 116, le(1234, 4)), 0);
  EXPECT_EQ(s.get(1, "present_position"), 1234);
  EXPECT_EQ(write(2, 116, le(1234, 4)), 0);  // torque off: stays
  EXPECT_EQ(s.get(2, "present_position"), 2048);
  // The present values as hooks write them, saturated.
  s.set_present(3, 100, -5, 70000, 121, 40);
  EXPECT_EQ(s.get(3, "present_current"), 32767);
  const auto r = ask(3, dx::instruction::kRead, cat({le(126, 2), le(10, 2)}));
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(dx::get_le(&r[0].data[6], 4, true), 100);
  EXPECT_EQ(dx::get_le(&r[0].data[2], 4, true), -5);
}

TEST_F(Servos, HardwareErrorAlertsTorqueOffUntilReboot) {
  EXPECT_EQ(write(2, 64, le(1, 1)), 0);
  s.set_hardware_error(2, 0x20);
  EXPECT_EQ(s.get(2, "torque_enable"), 0);
  auto r = ask(2, dx::instruction::kPing, {});
  EXPECT_EQ(r[0].error, dx::kAlertBit);
  EXPECT_EQ(write(2, 64, le(1, 1)), dx::kAlertBit | dx::servo_error::kResultFail);
  r = ask(dx::kBroadcastId, dx::instruction::kFastSyncRead, cat({le(70, 2), le(1, 2), {1, 2}}));
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].error, 0);           // servo 1's block
  EXPECT_EQ(r[0].data[4], dx::kAlertBit);  // servo 2's block: ID 1, data, CRC (2), then ERR
  EXPECT_EQ(ask(2, dx::instruction::kReboot, {})[0].error, dx::kAlertBit);  // answers, then restarts
  EXPECT_EQ(s.get(2, "hardware_error_status"), 0);
  EXPECT_EQ(write(2, 64, le(1, 1)), 0);
}

TEST_F(Servos, EveryReplyFault) {
  const Bytes ping = packet(2, dx::instruction::kPing, {});
  const Bytes clean = send(ping);
  struct Case {
    dx::ReplyFault kind;
    int replies, bad;  // parsed status packets, bad packets
  };
  const std::vector<Case> cases = {
      {dx::ReplyFault::kDropReply, 0, 0},     {dx::ReplyFault::kCorruptCrc, 0, 1},
      {dx::ReplyFault::kTruncateReply, 0, 0}, {dx::ReplyFault::kGarbageBefore, 1, 0},
      {dx::ReplyFault::kGarbageData, 1, 0},
  };
  for (const auto& c : cases) {
    const std::string name = dx::to_string(c.kind);
    dx::ReplyFault back{};
    ASSERT_TRUE(dx::reply_fault_from_string(name, &back)) << name;
    EXPECT_EQ(back, c.kind);
    s.inject(c.kind, {2}, 1);
    int bad = 0;
    const Bytes out = send(ping);
    const auto r = replies(out, &bad);
    EXPECT_EQ(static_cast<int>(r.size()), c.replies) << name;
    EXPECT_EQ(bad, c.bad) << name;
    if (c.kind == dx::ReplyFault::kGarbageData) {
      EXPECT_EQ(r[0].data, (Bytes{0xA5, 0xA5, 0xA5}));
    }
    if (c.kind == dx::ReplyFault::kGarbageBefore) {
      EXPECT_EQ(out.size(), clean.size() + 6);
    }
    if (c.kind == dx::ReplyFault::kTruncateReply) {
      EXPECT_EQ(out.size(), clean.size() / 2);
    }
    EXPECT_EQ(send(ping), clean) << name << ": count 1 is spent";
  }
  EXPECT_FALSE(dx::reply_fault_from_string("timeout", nullptr));
  // Faults aimed at one servo leave the others; count < 0 lasts until cleared.
  s.inject(dx::ReplyFault::kDropReply, {3}, -1);
  for (int k = 0; k < 3; ++k) {
    const auto r = ask(dx::kBroadcastId, dx::instruction::kSyncRead, cat({le(126, 2), le(10, 2), {1, 2, 3}}));
    ASSERT_EQ(r.size(), 2u);
    EXPECT_EQ(r[1].id, 2);
  }
  // A dropped reply still carries out the instruction.
  EXPECT_EQ(ask(3, dx::instruction::kWrite, cat({le(65, 2), le(1, 1)})).size(), 0u);
  EXPECT_EQ(s.get(3, "led"), 1);
  // Silent: answers nothing, obeys writes.
  s.set_silent(1, true);
  EXPECT_TRUE(ask(1, dx::instruction::kWrite, cat({le(65, 2), le(1, 1)})).empty());
  EXPECT_EQ(s.get(1, "led"), 1);
  s.clear_faults();
  EXPECT_EQ(ask(dx::kBroadcastId, dx::instruction::kPing, {}).size(), 3u);
  EXPECT_THROW(s.inject(dx::ReplyFault::kDropReply, {9}, 1), dx::ConfigError);
  EXPECT_THROW(s.inject(dx::ReplyFault::kDropReply, {1}, 0), dx::ConfigError);
  EXPECT_THROW(s.set_silent(9, true), dx::ConfigError);
  EXPECT_THROW(dx::SimulatedServos(table(), {1, 1}), dx::ConfigError);
  EXPECT_THROW(dx::SimulatedServos(table(), {253}), dx::ConfigError);
}

TEST_F(Servos, BadCrcNamingAServoGetsACrcErrorStatus) {
  Bytes p = packet(2, dx::instruction::kPing, {});
  p.back() ^= 0x55;
  const auto r = replies(send(p));
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].error, dx::servo_error::kCrcError);
  Bytes q = packet(9, dx::instruction::kPing, {});
  q.back() ^= 0x55;
  EXPECT_TRUE(send(q).empty());
  EXPECT_EQ(s.stats().bad_packets, 2u);
}

TEST_F(Servos, AnyChunkingGivesTheSameReplies) {
  const Bytes stream =
      cat({packet(1, dx::instruction::kPing, {}),
           {0x00, 0xFF},
           packet(dx::kBroadcastId, dx::instruction::kSyncRead, cat({le(126, 2), le(10, 2), {1, 2, 3}})),
           packet(3, dx::instruction::kRead, cat({le(132, 2), le(4, 2)}))});
  const Bytes whole = send(stream);
  EXPECT_EQ(replies(whole).size(), 5u);
  for (std::size_t chunk : {1u, 2u, 3u, 7u}) {
    Bytes got;
    for (std::size_t at = 0; at < stream.size(); at += chunk) {
      const std::size_t n = std::min(chunk, stream.size() - at);
      const std::size_t m = s.handle(stream.data() + at, n);
      got.insert(got.end(), s.output(), s.output() + m);
    }
    EXPECT_EQ(got, whole) << "chunks of " << chunk;
  }
}
