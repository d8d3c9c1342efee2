// Fuzzing the Protocol 2.0 parser: a fixed-seed corpus of byte streams (valid packets of every
// instruction, their mutations, garbage), a stream receiver that runs parse_packet exactly as
// Protocol2Bus::receive does (append what a read returned, parse, drop `consumed`), the chunkings
// a serial port may deliver, and the oracle. Shared by test/cpp/test_protocol_fuzz.cpp (bounded,
// in CI), test/cpp/test_dynamixel_resync.cpp and bench/fuzz_protocol.cpp (the long run).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "snake_autonomy/dynamixel/protocol.hpp"

namespace snake_autonomy::dynamixel::fuzz {

using Bytes = std::vector<std::uint8_t>;

// One piece of a stream. `valid`: an intact packet the parser must return, byte for byte.
struct Segment {
  Bytes bytes;
  bool valid = false;
  const char* kind = "";  // "valid", "bit_flip", "truncate", ... (for messages)
};

inline Bytes concat(const std::vector<Segment>& segments) {
  Bytes out;
  for (const auto& s : segments) out.insert(out.end(), s.bytes.begin(), s.bytes.end());
  return out;
}

// ---------------------------------------------------------------------------------------------
// The receive loop of Protocol2Bus without a transport: feed() what one read returned.
class StreamReceiver {
 public:
  struct Counts {
    std::size_t ok = 0, bad_crc = 0, malformed = 0, overflow = 0;
  };
  // Every packet returned kOk: its bytes on the wire (header to CRC).
  std::vector<Bytes> packets;
  Counts counts;

  void feed(const std::uint8_t* data, std::size_t n) {
    while (n > 0) {
      if (size_ == buf_.size()) {  // what Protocol2Bus does with a full buffer
        size_ = 0;
        ++counts.overflow;
      }
      const std::size_t take = std::min(n, buf_.size() - size_);
      std::memcpy(buf_.data() + size_, data, take);
      size_ += take;
      data += take;
      n -= take;
      drain();
    }
  }
  std::size_t pending() const noexcept { return size_; }

 private:
  void drain() {
    for (;;) {
      Packet p;
      const ParseResult r = parse_packet(buf_.data(), size_, scratch_.data(), scratch_.size(), &p);
      if (r.status == ParseStatus::kOk) {
        packets.emplace_back(buf_.begin() + static_cast<long>(r.start), buf_.begin() + static_cast<long>(r.consumed));
        ++counts.ok;
      } else if (r.status == ParseStatus::kBadCrc) {
        ++counts.bad_crc;
      } else if (r.status == ParseStatus::kMalformed) {
        ++counts.malformed;
      }
      if (r.consumed > size_) std::abort();  // parse_packet's contract
      std::memmove(buf_.data(), buf_.data() + r.consumed, size_ - r.consumed);
      size_ -= r.consumed;
      if (r.status == ParseStatus::kIncomplete) return;
    }
  }
  std::array<std::uint8_t, 4 * kMaxPacketBytes> buf_{};
  std::size_t size_ = 0;
  std::array<std::uint8_t, kMaxPacketBytes> scratch_{};
};

// How the bytes arrive: 0 = one read, k > 0 = reads of k bytes, -1 = random sizes 1..24.
inline StreamReceiver receive_chunked(const Bytes& stream, int chunking, std::mt19937_64& rng) {
  StreamReceiver rx;
  std::size_t i = 0;
  while (i < stream.size()) {
    std::size_t k = stream.size() - i;
    if (chunking > 0) k = static_cast<std::size_t>(chunking);
    if (chunking < 0) k = std::uniform_int_distribution<std::size_t>(1, 24)(rng);
    k = std::min(k, stream.size() - i);
    rx.feed(stream.data() + i, k);
    i += k;
  }
  return rx;
}

// The oracle: every valid segment comes out exactly, in order. A valid packet may only go missing
// when the parser accepted another span overlapping it (a mutated packet whose CRC-16 matched by
// chance, 1 in 65536): those are `collisions`, reported, not losses.
struct Verdict {
  std::size_t expected = 0, recovered = 0, lost = 0, collisions = 0, extra = 0;
  std::string first_loss;  // what went missing first (empty when nothing did)
};

inline std::string hex(const Bytes& b, std::size_t max_bytes = 64) {
  std::string out;
  char t[4];
  for (std::size_t i = 0; i < b.size() && i < max_bytes; ++i) {
    std::snprintf(t, sizeof t, "%02X ", b[i]);
    out += t;
  }
  if (b.size() > max_bytes) out += "...";
  return out;
}

inline Verdict judge(const std::vector<Segment>& segments, const StreamReceiver& rx) {
  Verdict v;
  std::size_t j = 0;  // next packet of rx to match
  for (std::size_t i = 0; i < segments.size(); ++i) {
    if (!segments[i].valid) continue;
    ++v.expected;
    const auto it = std::find(rx.packets.begin() + static_cast<long>(j), rx.packets.end(), segments[i].bytes);
    if (it != rx.packets.end()) {
      v.extra += static_cast<std::size_t>(it - (rx.packets.begin() + static_cast<long>(j)));
      j = static_cast<std::size_t>(it - rx.packets.begin()) + 1;
      ++v.recovered;
      continue;
    }
    // Missing: was a foreign span accepted (a CRC collision)? Only a packet not in the valid list
    // can have swallowed it.
    const bool foreign = std::any_of(rx.packets.begin() + static_cast<long>(j), rx.packets.end(), [&](const Bytes& p) {
      return std::none_of(segments.begin(), segments.end(), [&](const Segment& s) { return s.valid && s.bytes == p; });
    });
    if (foreign) {
      ++v.collisions;
    } else {
      ++v.lost;
      if (v.first_loss.empty()) v.first_loss = hex(segments[i].bytes);
    }
  }
  v.extra += rx.packets.size() - std::min(j, rx.packets.size());
  return v;
}

// ---------------------------------------------------------------------------------------------
// The corpus.
class CorpusGenerator {
 public:
  explicit CorpusGenerator(std::uint64_t seed) : rng_(seed) {}
  std::mt19937_64& rng() noexcept { return rng_; }

  std::size_t uniform(std::size_t lo, std::size_t hi) {
    return std::uniform_int_distribution<std::size_t>(lo, hi)(rng_);
  }
  std::uint8_t byte() { return static_cast<std::uint8_t>(uniform(0, 255)); }
  bool chance(double p) { return std::bernoulli_distribution(p)(rng_); }

  // Parameter bytes, biased towards FF and FD so that stuffing happens often.
  Bytes params(std::size_t n) {
    Bytes b(n);
    for (auto& v : b) {
      const std::size_t r = uniform(0, 9);
      v = r < 3 ? 0xFF : r < 5 ? 0xFD : r < 6 ? 0x00 : byte();
    }
    return b;
  }

  // A valid packet of one of the instructions the driver and the servos exchange.
  Bytes valid_packet() {
    static constexpr std::uint8_t kInstructions[] = {
        instruction::kPing,   instruction::kRead,     instruction::kWrite,     instruction::kReboot,
        instruction::kStatus, instruction::kSyncRead, instruction::kSyncWrite, instruction::kFastSyncRead};
    const std::uint8_t inst = kInstructions[uniform(0, sizeof kInstructions - 1)];
    const std::uint8_t id = chance(0.2) ? kBroadcastId : static_cast<std::uint8_t>(uniform(0, kMaxServoId));
    Bytes p;
    switch (inst) {
      case instruction::kPing:
      case instruction::kReboot: break;
      case instruction::kRead: p = params(4); break;
      case instruction::kWrite: p = params(2 + uniform(1, 8)); break;
      case instruction::kStatus: p = params(1 + (chance(0.1) ? uniform(0, 600) : uniform(0, 16))); break;
      case instruction::kSyncRead:
      case instruction::kFastSyncRead: p = params(4 + uniform(1, 11)); break;
      case instruction::kSyncWrite: p = params(4 + uniform(1, 11) * 5); break;
      default: break;
    }
    Bytes out(kMaxPacketBytes);
    out.resize(encode_packet(id, inst, p.data(), p.size(), out.data(), out.size()));
    return out;
  }

  // A damaged copy of a valid packet; `kind` says how.
  Bytes mutate(const Bytes& pkt, const char** kind) {
    Bytes b = pkt;
    switch (uniform(0, 6)) {
      case 0: {  // bit flips
        *kind = "bit_flip";
        const std::size_t flips = uniform(1, 3);
        for (std::size_t i = 0; i < flips; ++i) {
          b[uniform(0, b.size() - 1)] ^= static_cast<std::uint8_t>(1u << uniform(0, 7));
        }
        break;
      }
      case 1:  // a lost byte, or lost bytes, or cut short
        *kind = "truncate";
        if (chance(0.5)) {
          b.erase(b.begin() + static_cast<long>(uniform(0, b.size() - 1)));
        } else {
          b.resize(uniform(1, b.size() - 1));
        }
        break;
      case 2: {  // extra bytes inside the packet (noise on the line)
        *kind = "insert";
        const std::size_t n = uniform(1, 3);
        for (std::size_t i = 0; i < n; ++i) b.insert(b.begin() + static_cast<long>(uniform(1, b.size() - 1)), byte());
        break;
      }
      case 3: {  // LEN lies (CRC recomputed or not)
        *kind = "length_lie";
        const std::size_t len = chance(0.5) ? uniform(0, 0xFFFF) : (b[5] | (b[6] << 8)) + uniform(0, 8) - 4;
        b[5] = static_cast<std::uint8_t>(len & 0xFF);
        b[6] = static_cast<std::uint8_t>((len >> 8) & 0xFF);
        if (chance(0.5)) fix_crc(b);
        break;
      }
      case 4: {  // stuffing broken: FF FF FD not followed by FD, with a valid CRC
        *kind = "stuffing_break";
        Bytes body(b.begin() + 7, b.end() - 2);
        const std::size_t at = uniform(0, body.size());
        const Bytes pattern = {0xFF, 0xFF, 0xFD};
        body.insert(body.begin() + static_cast<long>(at), pattern.begin(), pattern.end());
        // Either the stuffed FD goes missing (the next byte is anything else), or the pattern ends
        // the region.
        if (at + 3 < body.size() && body[at + 3] == 0xFD) body[at + 3] = static_cast<std::uint8_t>(uniform(0, 0xFC));
        Bytes out(b.begin(), b.begin() + 7);
        out.insert(out.end(), body.begin(), body.end());
        out.insert(out.end(), {0, 0});
        const std::size_t len = body.size() + 2;
        out[5] = static_cast<std::uint8_t>(len & 0xFF);
        out[6] = static_cast<std::uint8_t>(len >> 8);
        fix_crc(out);
        b = out;
        break;
      }
      case 5:  // the header damaged
        *kind = "header";
        b[uniform(0, 3)] = byte();
        break;
      default: {  // CRC only
        *kind = "crc";
        b[b.size() - 1 - uniform(0, 1)] ^= static_cast<std::uint8_t>(uniform(1, 255));
        break;
      }
    }
    if (b == pkt) b.back() ^= 0x5A;  // never an intact copy
    return b;
  }

  Bytes garbage() {
    Bytes g = params(uniform(1, 12));
    if (chance(0.3)) g.insert(g.end(), {0xFF, 0xFF, 0xFD});  // a header prefix that goes nowhere
    if (chance(0.1)) g.insert(g.end(), {0xFF, 0xFF, 0xFD, 0xFD});  // stuffed data, never a header
    return g;
  }

  // A stream of 1-5 pieces: valid packets, damaged packets, garbage.
  std::vector<Segment> stream() {
    std::vector<Segment> s;
    const std::size_t n = uniform(1, 5);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t r = uniform(0, 9);
      if (r < 4) {
        s.push_back({valid_packet(), true, "valid"});
      } else if (r < 9) {
        Segment m;
        m.bytes = mutate(valid_packet(), &m.kind);
        s.push_back(m);
      } else {
        s.push_back({garbage(), false, "garbage"});
      }
    }
    if (std::none_of(s.begin(), s.end(), [](const Segment& x) { return x.valid; })) {
      s.push_back({valid_packet(), true, "valid"});  // always something to recover
    }
    return s;
  }

  static void fix_crc(Bytes& b) {
    const std::uint16_t crc = crc16(b.data(), b.size() - 2);
    b[b.size() - 2] = static_cast<std::uint8_t>(crc & 0xFF);
    b[b.size() - 1] = static_cast<std::uint8_t>(crc >> 8);
  }

 private:
  std::mt19937_64 rng_;
};

}  // namespace snake_autonomy::dynamixel::fuzz
