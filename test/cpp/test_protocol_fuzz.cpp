// Fuzz of the Protocol 2.0 parser in bounded time (CI): a fixed-seed corpus of streams made of
// valid packets of every instruction, their mutations (bit flips, truncation, insertion, length
// lies, stuffing breaks, damaged headers and CRCs) and garbage, each delivered in one read, 1-byte,
// 2-byte and random-size reads. No crash; every valid packet comes out exactly, in order; the
// damaged ones are counted (bad CRC or malformed). The long run: bench/fuzz_protocol.cpp.
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "protocol_fuzz_corpus.hpp"

namespace dx = snake_autonomy::dynamixel;
namespace fz = snake_autonomy::dynamixel::fuzz;

namespace {

constexpr int kChunkings[] = {0, 1, 2, -1};

}  // namespace

TEST(ProtocolFuzz, FixedSeedCorpusEveryValidPacketRecoveredInEveryChunking) {
  fz::CorpusGenerator gen(0x5EED2026);
  std::size_t streams = 0, expected = 0, recovered = 0, collisions = 0, refused = 0, damaged = 0;
  for (int i = 0; i < 15000; ++i) {
    const std::vector<fz::Segment> segs = gen.stream();
    const fz::Bytes bytes = fz::concat(segs);
    for (const int chunking : kChunkings) {
      const fz::StreamReceiver rx = fz::receive_chunked(bytes, chunking, gen.rng());
      const fz::Verdict v = fz::judge(segs, rx);
      ++streams;
      expected += v.expected;
      recovered += v.recovered;
      collisions += v.collisions;
      refused += rx.counts.bad_crc + rx.counts.malformed;
      ASSERT_EQ(v.lost, 0u) << "stream " << i << ", chunking " << chunking << ": lost " << v.first_loss
                            << "\nstream: " << fz::hex(bytes, 256);
      EXPECT_EQ(rx.counts.overflow, 0u);
    }
    for (const auto& s : segs) damaged += s.valid ? 0 : 1;
  }
  std::printf(
      "parser fuzz: %zu streams, %zu valid packets, %zu recovered, %zu lost to CRC collisions, "
      "%zu refused (bad CRC or malformed) from %zu damaged pieces\n",
      streams, expected, recovered, collisions, refused, damaged);
  EXPECT_EQ(recovered + collisions, expected);
  EXPECT_LE(collisions, expected / 10000);  // CRC-16 collisions only: about 1 in 65536 damaged packets
  EXPECT_GT(refused, damaged);  // the damage is seen and counted (4 chunkings per stream)
}

// Every mutation kind on its own, followed by a valid packet: refused (never returned as a
// packet) and the valid one recovered.
TEST(ProtocolFuzz, EveryMutationKindIsRefusedAndTheNextPacketKept) {
  fz::CorpusGenerator gen(42);
  std::map<std::string, std::size_t> seen, accepted;
  for (int i = 0; i < 4000; ++i) {
    fz::Segment bad;
    const fz::Bytes original = gen.valid_packet();
    bad.bytes = gen.mutate(original, &bad.kind);
    const std::vector<fz::Segment> segs = {bad, {gen.valid_packet(), true, "valid"}};
    const fz::StreamReceiver rx = fz::receive_chunked(fz::concat(segs), 1, gen.rng());
    const fz::Verdict v = fz::judge(segs, rx);
    ++seen[bad.kind];
    accepted[bad.kind] += v.extra;
    EXPECT_EQ(v.lost, 0u) << bad.kind << ": " << fz::hex(bad.bytes);
  }
  for (const char* kind : {"bit_flip", "truncate", "insert", "length_lie", "stuffing_break", "header", "crc"}) {
    EXPECT_GT(seen[kind], 300u) << kind;
    // A damaged packet accepted as a packet: only a CRC-16 collision can do that (or a length lie
    // shortening a packet onto a span whose CRC matches); never a stuffing break.
    EXPECT_LE(accepted[kind], seen[kind] / 1000) << kind;
  }
  EXPECT_EQ(accepted["stuffing_break"], 0u);
}
