// Protocol 2.0 codec: CRC, stuffing both ways, encoding, parsing of every fault, the manual's
// 21 packets (skipped when the shared data directory is absent), byte packing and unit conversions.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "snake_autonomy/dynamixel/conversions.hpp"
#include "snake_autonomy/dynamixel/protocol.hpp"
#include "snake_autonomy/dynamixel/protocol2_bus.hpp"
#include "snake_autonomy/dynamixel/status.hpp"

namespace dx = snake_autonomy::dynamixel;
using Bytes = std::vector<std::uint8_t>;

namespace {

Bytes hex(const std::string& text) {
  Bytes out;
  std::istringstream s(text);
  std::string tok;
  while (s >> tok) out.push_back(static_cast<std::uint8_t>(std::stoul(tok, nullptr, 16)));
  return out;
}

std::string to_hex(const Bytes& b) {
  std::string out;
  char buf[4];
  for (auto v : b) {
    std::snprintf(buf, sizeof buf, "%02X ", v);
    out += buf;
  }
  if (!out.empty()) out.pop_back();
  return out;
}

Bytes encode(std::uint8_t id, std::uint8_t inst, const Bytes& params) {
  Bytes out(dx::kMaxPacketBytes);
  const std::size_t n = dx::encode_packet(id, inst, params.data(), params.size(), out.data(), out.size());
  out.resize(n);
  return out;
}

Bytes status(std::uint8_t id, std::uint8_t error, const Bytes& data) {
  Bytes out(dx::kMaxPacketBytes);
  const std::size_t n = dx::encode_status(id, error, data.data(), data.size(), out.data(), out.size());
  out.resize(n);
  return out;
}

struct Parsed {
  dx::ParseResult r;
  dx::Packet p;       // p.params points into scratch (a vector: moving keeps it valid)
  Bytes params;
  Bytes scratch;
};

Parsed parse(const Bytes& in) {
  Parsed out;
  out.scratch.resize(dx::kMaxPacketBytes);
  out.r = dx::parse_packet(in.data(), in.size(), out.scratch.data(), out.scratch.size(), &out.p);
  if (out.r.status == dx::ParseStatus::kOk) out.params.assign(out.p.params, out.p.params + out.p.n_params);
  return out;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
TEST(Crc16, CheckValueAndKnownPackets) {
  const std::string check = "123456789";
  EXPECT_EQ(dx::crc16(reinterpret_cast<const std::uint8_t*>(check.data()), check.size()), 0xFEE8);
  struct Case {
    const char* packet_without_crc;
    std::uint16_t crc;
  };
  const Case cases[] = {
      {"FF FF FD 00 01 03 00 01", 0x4E19},                    // PING id 1
      {"FF FF FD 00 FE 03 00 01", 0x4231},                    // broadcast PING
      {"FF FF FD 00 01 07 00 02 84 00 04 00", 0x151D},        // READ 132/4
      {"FF FF FD 00 01 04 00 55 00", 0x0CA1},                 // OK status
      {"", 0x0000},
  };
  for (const auto& c : cases) {
    const Bytes b = hex(c.packet_without_crc);
    EXPECT_EQ(dx::crc16(b.data(), b.size()), c.crc) << c.packet_without_crc;
  }
  // Continuing a CRC over a second buffer equals the CRC of the concatenation.
  const Bytes a = hex("FF FF FD 00"), b = hex("01 03 00 01");
  EXPECT_EQ(dx::crc16(b.data(), b.size(), dx::crc16(a.data(), a.size())), 0x4E19);
}

TEST(Stuffing, BothWaysTable) {
  struct Case {
    const char* raw;
    const char* stuffed;
  };
  const Case cases[] = {
      {"", ""},
      {"01 02 03", "01 02 03"},
      {"FF FF FD", "FF FF FD FD"},
      {"FF FF FD FD", "FF FF FD FD FD"},
      {"FF FF FF FD", "FF FF FF FD FD"},
      {"FF FF FD FF FF FD", "FF FF FD FD FF FF FD FD"},
      {"FF FD FF FF FD 00", "FF FD FF FF FD FD 00"},
      {"FD FF FF", "FD FF FF"},
      {"FF FF FC FD", "FF FF FC FD"},
      {"55 00 FF FF FD FF FF FF", "55 00 FF FF FD FD FF FF FF"},  // current -1, velocity -3 ...
  };
  for (const auto& c : cases) {
    const Bytes raw = hex(c.raw), stuffed = hex(c.stuffed);
    Bytes out(64);
    const std::size_t n = dx::stuff(raw.data(), raw.size(), out.data(), out.size());
    ASSERT_NE(n, dx::kNoSpace) << c.raw;
    EXPECT_EQ(to_hex(Bytes(out.begin(), out.begin() + static_cast<long>(n))), to_hex(stuffed)) << "stuff " << c.raw;
    const std::size_t m = dx::unstuff(stuffed.data(), stuffed.size(), out.data(), out.size());
    ASSERT_NE(m, dx::kNoSpace) << c.stuffed;
    EXPECT_EQ(to_hex(Bytes(out.begin(), out.begin() + static_cast<long>(m))), to_hex(raw)) << "unstuff " << c.stuffed;
  }
  std::uint8_t small[3];
  const Bytes raw = hex("FF FF FD");
  EXPECT_EQ(dx::stuff(raw.data(), raw.size(), small, sizeof small), dx::kNoSpace);
}

TEST(Encode, StuffsHeaderPatternInsideParams) {
  // WRITE id 1, address 116 = bytes FF FF FD 00: the FD gets its extra FD, LEN counts it, the CRC
  // covers the stuffed bytes, and FF FF FD 00 never appears after the header.
  const Bytes pkt = encode(1, dx::instruction::kWrite, hex("74 00 FF FF FD 00"));
  EXPECT_EQ(to_hex(Bytes(pkt.begin(), pkt.end() - 2)), "FF FF FD 00 01 0A 00 03 74 00 FF FF FD FD 00");
  const std::uint16_t crc = dx::crc16(pkt.data(), pkt.size() - 2);
  EXPECT_EQ(pkt[pkt.size() - 2], crc & 0xFF);
  EXPECT_EQ(pkt[pkt.size() - 1], crc >> 8);
  for (std::size_t i = 1; i + 4 <= pkt.size(); ++i) {
    EXPECT_FALSE(pkt[i] == 0xFF && pkt[i + 1] == 0xFF && pkt[i + 2] == 0xFD && pkt[i + 3] == 0x00) << i;
  }
  const Parsed p = parse(pkt);
  ASSERT_EQ(p.r.status, dx::ParseStatus::kOk);
  EXPECT_EQ(p.p.instruction, dx::instruction::kWrite);
  EXPECT_EQ(to_hex(p.params), "74 00 FF FF FD 00");
  EXPECT_EQ(p.r.consumed, pkt.size());
}

TEST(Encode, OverflowReturnsZero) {
  std::uint8_t buf[12];
  const Bytes params = hex("01 02 03 04");
  EXPECT_EQ(dx::encode_packet(1, dx::instruction::kWrite, params.data(), params.size(), buf, sizeof buf), 0u);
  EXPECT_EQ(dx::encode_packet(1, dx::instruction::kWrite, params.data(), 2, buf, sizeof buf), 12u);
}

TEST(Encode, SyncWriteMatchesManual) {
  std::uint8_t buf[64];
  dx::PacketEncoder e(buf, sizeof buf);
  e.begin(dx::kBroadcastId, dx::instruction::kSyncWrite);
  e.put16(116);
  e.put16(4);
  e.put(1);
  e.put32(150);
  e.put(2);
  e.put32(170);
  const std::size_t n = e.finish();
  EXPECT_EQ(to_hex(Bytes(buf, buf + n)), "FF FF FD 00 FE 11 00 83 74 00 04 00 01 96 00 00 00 02 AA 00 00 00 82 87");
}

// ---------------------------------------------------------------------------------------------
TEST(Parse, EveryFault) {
  const Bytes ok = hex("FF FF FD 00 01 08 00 55 00 A6 00 00 00 8C C0");  // READ status, 166
  {  // the plain packet
    const Parsed p = parse(ok);
    ASSERT_EQ(p.r.status, dx::ParseStatus::kOk);
    EXPECT_EQ(p.p.id, 1);
    EXPECT_EQ(to_hex(p.params), "00 A6 00 00 00");
  }
  {  // bad CRC: the whole packet is consumed
    Bytes b = ok;
    b[9] ^= 0x01;
    const Parsed p = parse(b);
    EXPECT_EQ(p.r.status, dx::ParseStatus::kBadCrc);
    EXPECT_EQ(p.r.consumed, b.size());
    EXPECT_EQ(p.r.id, 1);
  }
  {  // truncated at the end of input: wait for more, keep the header
    const Bytes b(ok.begin(), ok.end() - 3);
    const Parsed p = parse(b);
    EXPECT_EQ(p.r.status, dx::ParseStatus::kIncomplete);
    EXPECT_EQ(p.r.consumed, 0u);
  }
  {  // truncated, then the next servo's packet: malformed up to the next header, which then parses
    Bytes b(ok.begin(), ok.end() - 4);
    const Bytes next = hex("FF FF FD 00 02 08 00 55 00 1F 08 00 00 BA BE");
    b.insert(b.end(), next.begin(), next.end());
    const Parsed p = parse(b);
    EXPECT_EQ(p.r.status, dx::ParseStatus::kMalformed);
    EXPECT_EQ(p.r.consumed, ok.size() - 4);
    const Parsed q = parse(Bytes(b.begin() + static_cast<long>(p.r.consumed), b.end()));
    ASSERT_EQ(q.r.status, dx::ParseStatus::kOk);
    EXPECT_EQ(q.p.id, 2);
  }
  {  // garbage before the header
    Bytes b = hex("00 13 FF 37 FF FF 42");
    b.insert(b.end(), ok.begin(), ok.end());
    const Parsed p = parse(b);
    ASSERT_EQ(p.r.status, dx::ParseStatus::kOk);
    EXPECT_EQ(p.r.start, 7u);
    EXPECT_EQ(p.r.consumed, b.size());
  }
  {  // FF FF FD FD (stuffed data) is never taken for a header
    Bytes b = hex("FF FF FD FD 01 08 00");
    b.insert(b.end(), ok.begin(), ok.end());
    const Parsed p = parse(b);
    ASSERT_EQ(p.r.status, dx::ParseStatus::kOk);
    EXPECT_EQ(p.r.start, 7u);
  }
  {  // only garbage: all of it can go, except a trailing FF FF FD that may start a header
    const Parsed p = parse(hex("01 02 03 FF FF FD"));
    EXPECT_EQ(p.r.status, dx::ParseStatus::kIncomplete);
    EXPECT_EQ(p.r.consumed, 3u);
    EXPECT_EQ(parse(hex("01 02 03 04")).r.consumed, 4u);
    EXPECT_EQ(parse(hex("01 FF")).r.consumed, 1u);
  }
  {  // impossible lengths
    EXPECT_EQ(parse(hex("FF FF FD 00 01 02 00 55 00")).r.status, dx::ParseStatus::kMalformed);
    EXPECT_EQ(parse(hex("FF FF FD 00 01 FF FF 55 00")).r.status, dx::ParseStatus::kMalformed);
  }
}

TEST(Parse, StuffedStatusRoundTrip) {
  // Current -1 (FF FF), velocity -3 (FD FF FF FF), position 0x000008FD: two FF FF FD patterns.
  const Bytes data = hex("FF FF FD FF FF FF FD 08 00 00");
  const Bytes pkt = status(7, 0, data);
  EXPECT_EQ(pkt.size(), dx::kStatusOverhead + data.size() + 2);  // two stuffed bytes
  const Parsed p = parse(pkt);
  ASSERT_EQ(p.r.status, dx::ParseStatus::kOk);
  std::uint8_t err = 0xEE;
  EXPECT_EQ(dx::check_status_packet(p.p, 7, data.size(), &err), dx::Status::kOk);
  EXPECT_EQ(err, 0);
  EXPECT_EQ(to_hex(Bytes(p.params.begin() + 1, p.params.end())), to_hex(data));
  const dx::ServoFeedback f = dx::decode_feedback(p.params.data() + 1);
  EXPECT_NEAR(f.current_a, -2.69e-3, 1e-12);
  EXPECT_NEAR(f.velocity_rad_s, -3 * 0.229 * 2 * M_PI / 60, 1e-12);
  EXPECT_EQ(f.position_ticks, 0x8FD);
}

TEST(CheckStatus, WrongIdInstructionErrorsAlert) {
  struct Case {
    Bytes packet;
    std::uint8_t expected_id;
    std::size_t data_bytes;
    dx::Status status;
    std::uint8_t error;
  };
  const Case cases[] = {
      {status(1, 0x00, hex("A6 00 00 00")), 1, 4, dx::Status::kOk, 0x00},
      {status(2, 0x00, hex("A6 00 00 00")), 1, 4, dx::Status::kWrongId, 0x00},
      {encode(1, dx::instruction::kRead, hex("84 00 04 00")), 1, 4, dx::Status::kWrongInstruction, 0x00},
      {status(1, 0x80, hex("A6 00 00 00")), 1, 4, dx::Status::kHardwareError, 0x80},
      {status(1, 0x86, {}), 1, 4, dx::Status::kServoError, 0x86},
      {status(1, 0x07, {}), 1, 0, dx::Status::kServoError, 0x07},
      {status(1, 0x00, hex("A6 00")), 1, 4, dx::Status::kMalformed, 0x00},
      {encode(1, dx::instruction::kStatus, {}), 1, 0, dx::Status::kMalformed, 0x00},
  };
  int i = 0;
  for (const auto& c : cases) {
    const Parsed p = parse(c.packet);
    ASSERT_EQ(p.r.status, dx::ParseStatus::kOk) << i;
    std::uint8_t err = 0xEE;
    EXPECT_EQ(dx::check_status_packet(p.p, c.expected_id, c.data_bytes, &err), c.status) << "case " << i;
    EXPECT_EQ(err, c.error) << "case " << i;
    ++i;
  }
  EXPECT_STREQ(dx::servo_error_name(dx::servo_error::kDataLimitError), "data limit error");
}

// ---------------------------------------------------------------------------------------------
TEST(ManualVectors, All21Packets) {
  // The shared data directory: "shared" beside the clone, or beside its parent for a worktree in
  // <clone's parent>/wt/NAME;
  // SNAKE_AUTONOMY_SHARED overrides both (as test/python/conftest.py does).
  const std::filesystem::path root = std::filesystem::canonical(SNAKE_SOURCE_DIR);
  std::vector<std::filesystem::path> candidates = {root.parent_path() / "shared",
                                                   root.parent_path().parent_path() / "shared"};
  if (const char* env = std::getenv("SNAKE_AUTONOMY_SHARED")) candidates.insert(candidates.begin(), env);
  std::filesystem::path shared = candidates[candidates.size() - 2];
  for (const auto& c : candidates) {
    if (std::filesystem::is_directory(c)) {
      shared = c;
      break;
    }
  }
  const std::filesystem::path path = shared / "data/dynamixel/protocol2_emanual_vectors.json";
  if (!std::filesystem::exists(path))
    GTEST_SKIP() << path
                 << " is absent: the manual's vectors live in the shared data directory (SNAKE_AUTONOMY_SHARED)";
  const YAML::Node json = YAML::LoadFile(path.string());  // JSON is YAML
  const YAML::Node vectors = json["vectors"];
  ASSERT_EQ(vectors.size(), 21u);
  for (const auto& v : vectors) {
    const std::string name = v["name"].as<std::string>();
    const Bytes b = hex(v["hex"].as<std::string>());
    const Bytes crc = hex(v["crc_le"].as<std::string>());
    ASSERT_GE(b.size(), dx::kInstructionOverhead) << name;
    EXPECT_EQ(b[b.size() - 2], crc[0]) << name;
    EXPECT_EQ(b[b.size() - 1], crc[1]) << name;
    const std::uint16_t computed = dx::crc16(b.data(), b.size() - 2);
    EXPECT_EQ(computed & 0xFF, crc[0]) << name;
    EXPECT_EQ(computed >> 8, crc[1]) << name;
    const Parsed p = parse(b);
    ASSERT_EQ(p.r.status, dx::ParseStatus::kOk) << name;
    EXPECT_EQ(p.r.consumed, b.size()) << name;
    EXPECT_EQ(static_cast<int>(b[5] | (b[6] << 8)), v["length_field"].as<int>()) << name;
    // Re-encoding what was parsed gives the very same bytes.
    EXPECT_EQ(to_hex(encode(p.p.id, p.p.instruction, p.params)), to_hex(b)) << name;
  }
}

// ---------------------------------------------------------------------------------------------
TEST(Bytes, LittleEndianTable) {
  struct Case {
    const char* bytes;
    std::size_t size;
    bool is_signed;
    std::int32_t value;
  };
  const Case cases[] = {
      {"7F", 1, false, 127},
      {"FF", 1, false, 255},
      {"FF", 1, true, -1},
      {"00 08", 2, false, 2048},
      {"FF FF", 2, true, -1},
      {"FF FF", 2, false, 65535},
      {"00 80", 2, true, -32768},
      {"A6 00 00 00", 4, true, 166},
      {"FF FF FF FF", 4, true, -1},
      {"1F 08 00 00", 4, false, 2079},
      {"00 00 00 80", 4, true, INT32_MIN},
  };
  for (const auto& c : cases) {
    const Bytes b = hex(c.bytes);
    EXPECT_EQ(dx::get_le(b.data(), c.size, c.is_signed), c.value) << c.bytes;
    std::uint8_t out[4] = {0, 0, 0, 0};
    dx::put_le(out, c.size, c.value);
    EXPECT_EQ(to_hex(Bytes(out, out + c.size)), to_hex(b)) << c.bytes;
  }
}

TEST(Conversions, PositionTable) {
  struct Case {
    std::int32_t ticks;
    double rad;
  };
  const Case cases[] = {
      {2048, 0.0},  {3072, M_PI / 2},        {1024, -M_PI / 2},       {0, -M_PI},
      {4096, M_PI}, {2049, 2 * M_PI / 4096}, {2048 + 4096, 2 * M_PI},
  };
  for (const auto& c : cases) {
    EXPECT_NEAR(dx::ticks_to_rad(c.ticks), c.rad, 1e-12) << c.ticks;
    ASSERT_TRUE(dx::rad_to_ticks(c.rad).has_value());
    EXPECT_EQ(*dx::rad_to_ticks(c.rad), c.ticks) << c.rad;
  }
  // 360/4096 degrees per tick; rounding to the nearest tick.
  EXPECT_NEAR(dx::ticks_to_rad(2048 + 1) * 180 / M_PI, 360.0 / 4096, 1e-12);
  EXPECT_EQ(*dx::rad_to_ticks(0.49 * 2 * M_PI / 4096), 2048);
  EXPECT_EQ(*dx::rad_to_ticks(0.51 * 2 * M_PI / 4096), 2049);
  EXPECT_FALSE(dx::rad_to_ticks(std::nan("")).has_value());
  EXPECT_FALSE(dx::rad_to_ticks(INFINITY).has_value());
  EXPECT_FALSE(dx::rad_to_ticks(1e12).has_value());
  EXPECT_EQ(dx::clamp_ticks(5000, 0, 4095), 4095);
  EXPECT_EQ(dx::clamp_ticks(-3, 0, 4095), 0);
  EXPECT_EQ(dx::clamp_ticks(100, 0, 4095), 100);
}

TEST(Conversions, VelocityCurrentVoltageTable) {
  const double rpm = 2 * M_PI / 60;
  struct V {
    std::int32_t units;
    double rad_s;
  };
  for (const V& c : {V{0, 0.0}, V{1, 0.229 * rpm}, V{-1, -0.229 * rpm}, V{100, 22.9 * rpm}, V{-1023, -234.267 * rpm}}) {
    EXPECT_NEAR(dx::velocity_to_rad_s(c.units), c.rad_s, 1e-9) << c.units;
    EXPECT_EQ(dx::rad_s_to_velocity(c.rad_s), c.units) << c.rad_s;
  }
  struct C {
    std::int16_t units;
    double amps;
  };
  for (const C& c : {C{0, 0.0}, C{1, 2.69e-3}, C{-1, -2.69e-3}, C{1000, 2.69}, C{-2047, -5.50643}}) {
    EXPECT_NEAR(dx::current_to_amps(c.units), c.amps, 1e-9) << c.units;
    EXPECT_EQ(dx::amps_to_current(c.amps), c.units) << c.amps;
  }
  EXPECT_EQ(dx::amps_to_current(1e6), 32767);
  EXPECT_NEAR(dx::voltage_to_volts(120), 12.0, 1e-12);
}

TEST(Timing, ReplyTimeoutFromBaudAndLength) {
  dx::BusTiming t;
  t.latency_s = 0.001;
  t.return_delay_s = 0.0;
  t.margin = 1.0;
  EXPECT_NEAR(dx::wire_time_s(100, 1000000), 0.001, 1e-12);
  EXPECT_NEAR(dx::wire_time_s(100, 4000000), 0.00025, 1e-12);
  // 11-servo sync read at 1 Mbaud: 25 bytes out, 11 * 21 back.
  EXPECT_NEAR(dx::reply_timeout_s(25, 231, 11, 1000000, t), 0.001 + 0.00256, 1e-12);
  t.return_delay_s = 0.0005;
  t.margin = 2.0;
  EXPECT_NEAR(dx::reply_timeout_s(25, 231, 11, 1000000, t), 0.001 + 11 * 0.0005 + 0.00512, 1e-12);
}
