// Protocol 2.0 parser: broken byte stuffing is refused even under a valid CRC, and
// resynchronisation after a damaged packet never loses the next valid one, however the bytes are
// chunked by the reads (one read, 1-byte, 2-byte, 3-byte and random reads), through parse_packet
// and through Protocol2Bus on a transport that hands out a few bytes per read.
#include <gtest/gtest.h>

#include <deque>
#include <random>

#include "protocol_fuzz_corpus.hpp"
#include "snake_autonomy/dynamixel/protocol2_bus.hpp"

namespace dx = snake_autonomy::dynamixel;
namespace fz = snake_autonomy::dynamixel::fuzz;
using Bytes = fz::Bytes;

namespace {

Bytes status(std::uint8_t id, std::uint8_t error, const Bytes& data) {
  Bytes out(dx::kMaxPacketBytes);
  out.resize(dx::encode_status(id, error, data.data(), data.size(), out.data(), out.size()));
  return out;
}

// A raw packet around an already-stuffed INST+PARAM region, LEN and CRC filled in (valid CRC).
Bytes raw_packet(std::uint8_t id, const Bytes& region) {
  Bytes b(7 + region.size() + 2, 0);  // (built by index: GCC 12 -O2 warns wrongly on vector::insert here)
  const std::uint8_t head[7] = {0xFF, 0xFF, 0xFD, 0x00, id, 0, 0};
  std::copy(head, head + 7, b.begin());
  std::copy(region.begin(), region.end(), b.begin() + 7);
  const std::size_t len = region.size() + 2;
  b[5] = static_cast<std::uint8_t>(len & 0xFF);
  b[6] = static_cast<std::uint8_t>(len >> 8);
  fz::CorpusGenerator::fix_crc(b);
  return b;
}

dx::ParseStatus parse_status(const Bytes& b) {
  std::uint8_t scratch[dx::kMaxPacketBytes];
  dx::Packet p;
  return dx::parse_packet(b.data(), b.size(), scratch, sizeof scratch, &p).status;
}

const int kChunkings[] = {0, 1, 2, 3, -1, -1, -1, -1};

}  // namespace

// ---------------------------------------------------------------------------------------------
TEST(Stuffing, UnstuffRefusesAMissingStuffedByte) {
  struct Case {
    Bytes stuffed;
    const char* why;
  };
  const Case cases[] = {
      {{0x55, 0xFF, 0xFF, 0xFD, 0x01}, "FF FF FD followed by 01"},
      {{0x55, 0xFF, 0xFF, 0xFD, 0x00, 0x01}, "a header inside the region"},
      {{0x55, 0x00, 0xFF, 0xFF, 0xFD}, "FF FF FD ends the region"},
      {{0x55, 0xFF, 0xFF, 0xFD, 0xFD, 0xFF, 0xFF, 0xFD, 0xFF}, "the second pattern lacks its FD"},
  };
  std::uint8_t out[32];
  for (const auto& c : cases) {
    EXPECT_EQ(dx::unstuff(c.stuffed.data(), c.stuffed.size(), out, sizeof out), dx::kBadStuffing) << c.why;
  }
  const Bytes good = {0x55, 0xFF, 0xFF, 0xFD, 0xFD, 0xFD, 0xFF, 0xFF, 0xFD, 0xFD};  // FF FF FD FD, FF FF FD
  EXPECT_EQ(dx::unstuff(good.data(), good.size(), out, sizeof out), good.size() - 2);
}

TEST(Parse, ValidCrcButBrokenStuffingIsMalformed) {
  const Bytes bad[] = {
      raw_packet(1, {0x55, 0x00, 0xFF, 0xFF, 0xFD, 0x01, 0x02}),
      raw_packet(1, {0x55, 0x00, 0x12, 0xFF, 0xFF, 0xFD}),  // the pattern ends the region
      raw_packet(7, {0x03, 0x74, 0x00, 0xFF, 0xFF, 0xFD, 0xFD, 0xFF, 0xFF, 0xFD, 0x08}),
  };
  for (const auto& b : bad) {
    EXPECT_EQ(parse_status(b), dx::ParseStatus::kMalformed) << fz::hex(b);
    // Followed by a valid packet, in every chunking: one malformed, the valid one recovered.
    const std::vector<fz::Segment> segs = {{b, false, "stuffing_break"},
                                           {status(2, 0, {0xA6, 0, 0, 0}), true, "valid"}};
    std::mt19937_64 rng(1);
    for (const int chunking : kChunkings) {
      const fz::StreamReceiver rx = fz::receive_chunked(fz::concat(segs), chunking, rng);
      EXPECT_EQ(rx.counts.malformed, 1u) << fz::hex(b) << " chunking " << chunking;
      EXPECT_EQ(rx.counts.ok, 1u) << fz::hex(b) << " chunking " << chunking;
      EXPECT_EQ(fz::judge(segs, rx).lost, 0u) << fz::hex(b) << " chunking " << chunking;
    }
  }
  // The same region correctly stuffed is fine.
  EXPECT_EQ(parse_status(raw_packet(1, {0x55, 0x00, 0xFF, 0xFF, 0xFD, 0xFD, 0x01, 0x02})), dx::ParseStatus::kOk);
}

// A reply that lost one byte (every position), then a valid reply, delivered in every chunking.
TEST(Resync, LostByteThenValidReplyInEveryChunking) {
  const Bytes first = status(1, 0, {0x00, 0x00, 0xFF, 0xFF, 0xFD, 0xFF, 0xFF, 0xFF, 0x1F, 0x08, 0x00, 0x00});
  const Bytes second = status(2, 0, {0x01, 0x00, 0x00, 0x00, 0x03, 0x00, 0x00, 0x00, 0xFD, 0x07, 0x00, 0x00});
  std::mt19937_64 rng(7);
  std::size_t streams = 0;
  for (std::size_t lost = 0; lost < first.size(); ++lost) {
    Bytes damaged = first;
    damaged.erase(damaged.begin() + static_cast<long>(lost));
    const std::vector<fz::Segment> segs = {{damaged, false, "truncate"}, {second, true, "valid"}};
    for (const int chunking : kChunkings) {
      const fz::StreamReceiver rx = fz::receive_chunked(fz::concat(segs), chunking, rng);
      const fz::Verdict v = fz::judge(segs, rx);
      EXPECT_EQ(v.lost + v.collisions, 0u) << "byte " << lost << " lost, chunking " << chunking;
      // Refused once; a lost header byte leaves no header to refuse: skipped as garbage.
      EXPECT_EQ(rx.counts.bad_crc + rx.counts.malformed, lost < dx::kHeaderBytes ? 0u : 1u)
          << "byte " << lost << " lost, chunking " << chunking;
      ++streams;
    }
  }
  EXPECT_EQ(streams, first.size() * std::size(kChunkings));
}

// ---------------------------------------------------------------------------------------------
namespace {

// Hands the scripted reply out `chunk` bytes per read_some.
class ChunkedTransport : public dx::Transport {
 public:
  Bytes reply;
  std::size_t chunk = 1;
  bool is_open() const noexcept override { return true; }
  bool write_all(const std::uint8_t*, std::size_t) noexcept override {
    pending_.assign(reply.begin(), reply.end());
    return true;
  }
  long read_some(std::uint8_t* buffer, std::size_t capacity, dx::SteadyTime) noexcept override {
    std::size_t n = std::min({chunk, capacity, pending_.size()});
    for (std::size_t i = 0; i < n; ++i) {
      buffer[i] = pending_.front();
      pending_.pop_front();
    }
    return static_cast<long>(n);
  }
  void discard_input() noexcept override { pending_.clear(); }
  int baud_bps() const noexcept override { return 1000000; }

 private:
  std::deque<std::uint8_t> pending_;
};

}  // namespace

TEST(Resync, SyncReadKeepsTheNextServoAfterALostByteInSmallReads) {
  const Bytes data1 = {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F, 0x08, 0x00, 0x00};
  const Bytes data2 = {0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xA6, 0x00, 0x00, 0x00};
  const Bytes first = status(1, 0, data1), second = status(2, 0, data2);
  const std::uint8_t ids[2] = {1, 2};
  std::size_t runs = 0;
  for (std::size_t chunk : {1u, 2u, 3u, 64u}) {
    for (std::size_t lost = 0; lost < first.size(); ++lost) {
      ChunkedTransport t;
      t.chunk = chunk;
      t.reply = first;
      t.reply.erase(t.reply.begin() + static_cast<long>(lost));
      t.reply.insert(t.reply.end(), second.begin(), second.end());
      dx::BusTiming timing;
      timing.latency_s = 0.0;  // the transport never blocks: the deadline is reached only when it runs dry
      dx::Protocol2Bus bus(t, timing);
      std::uint8_t data[24] = {};
      dx::ServoReply replies[2];
      bus.sync_read(126, 12, ids, 2, data, replies);
      EXPECT_NE(replies[0].status, dx::Status::kOk) << "chunk " << chunk << ", byte " << lost << " lost";
      ASSERT_EQ(replies[1].status, dx::Status::kOk) << "chunk " << chunk << ", byte " << lost << " lost";
      EXPECT_EQ(Bytes(data + 12, data + 24), data2);
      ++runs;
    }
  }
  EXPECT_EQ(runs, 4 * first.size());
}

// A damaged reply whose last byte is FF may be followed by the next header: the parser waits for
// the next bytes; when none come (the reply deadline), it is judged a CRC error of its servo.
TEST(Resync, BadCrcEndingInFfIsACrcErrorAtTheDeadline) {
  Bytes bad = status(3, 0, {0xA6, 0x00, 0x00, 0x00});
  bad.back() = 0xFF;  // a CRC high byte of FF that does not match
  ASSERT_NE(dx::crc16(bad.data(), bad.size() - 2) >> 8, 0xFF);
  std::uint8_t scratch[dx::kMaxPacketBytes];
  dx::Packet p;
  EXPECT_EQ(dx::parse_packet(bad.data(), bad.size(), scratch, sizeof scratch, &p).status, dx::ParseStatus::kIncomplete);
  const dx::ParseResult r = dx::parse_packet(bad.data(), bad.size(), scratch, sizeof scratch, &p, true);
  EXPECT_EQ(r.status, dx::ParseStatus::kBadCrc);
  EXPECT_EQ(r.consumed, bad.size());
  EXPECT_EQ(r.id, 3);
  for (std::size_t chunk : {1u, 64u}) {
    ChunkedTransport t;
    t.chunk = chunk;
    t.reply = bad;
    dx::BusTiming timing;
    timing.latency_s = 0.0;
    dx::Protocol2Bus bus(t, timing);
    std::uint8_t data[4] = {};
    std::uint8_t error = 0;
    EXPECT_EQ(bus.read(3, 132, 4, data, &error), dx::Status::kCrcError) << "chunk " << chunk;
    EXPECT_EQ(bus.counters().crc_errors, 1u);
    EXPECT_EQ(bus.counters().malformed, 0u);
  }
}
