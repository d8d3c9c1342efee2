// bench_fuzz_protocol: the long fuzz of the Protocol 2.0 parser (the CI test is
// test/cpp/test_protocol_fuzz.cpp). Generates N streams of valid packets of every instruction,
// their mutations and garbage (test/cpp/protocol_fuzz_corpus.hpp), delivers each in one read,
// 1-byte, 2-byte and random-size reads, and checks that every valid packet comes out exactly.
// Prints inputs tried, crashes, packets recovered and lost, and the time; exits 1 on a loss.
//
//   bench_fuzz_protocol [--streams 200000] [--seed 1]
//
// bench/fuzz_protocol runs it; `bench/fuzz_protocol --sanitize` builds the parser and this file
// with AddressSanitizer and UndefinedBehaviorSanitizer first (an out-of-bounds read then aborts).
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "../test/cpp/protocol_fuzz_corpus.hpp"

namespace fz = snake_autonomy::dynamixel::fuzz;

int main(int argc, char** argv) {
  long streams = 200000;
  unsigned long long seed = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--streams" && i + 1 < argc) {
      streams = std::atol(argv[++i]);
    } else if (a == "--seed" && i + 1 < argc) {
      seed = std::strtoull(argv[++i], nullptr, 10);
    } else {
      std::fprintf(stderr, "usage: bench_fuzz_protocol [--streams N] [--seed S]\n");
      return 2;
    }
  }
  if (streams <= 0) {
    std::fprintf(stderr, "bench_fuzz_protocol: --streams: %ld is not a positive number\n", streams);
    return 2;
  }
  constexpr int kChunkings[] = {0, 1, 2, -1};
  fz::CorpusGenerator gen(seed);
  std::size_t inputs = 0, bytes = 0, expected = 0, recovered = 0, lost = 0, collisions = 0, refused = 0, damaged = 0;
  std::string first_loss;
  const auto t0 = std::chrono::steady_clock::now();
  for (long i = 0; i < streams; ++i) {
    const std::vector<fz::Segment> segs = gen.stream();
    const fz::Bytes stream = fz::concat(segs);
    for (const auto& s : segs) damaged += s.valid ? 0 : 1;
    for (const int chunking : kChunkings) {
      const fz::StreamReceiver rx = fz::receive_chunked(stream, chunking, gen.rng());
      const fz::Verdict v = fz::judge(segs, rx);
      ++inputs;
      bytes += stream.size();
      expected += v.expected;
      recovered += v.recovered;
      lost += v.lost;
      collisions += v.collisions;
      refused += rx.counts.bad_crc + rx.counts.malformed;
      if (v.lost && first_loss.empty()) {
        first_loss =
            "stream " + std::to_string(i) + " chunking " + std::to_string(chunking) + ": " + fz::hex(stream, 200);
      }
    }
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("protocol parser fuzz, seed %llu\n", seed);
  std::printf("  inputs tried      %zu (%ld streams x 4 chunkings: one read, 1-byte, 2-byte, random reads), %.1f MB\n",
              inputs, streams, static_cast<double>(bytes) / 1e6);
  std::printf("  crashes           0 (every input ran to the end)\n");
  std::printf("  valid packets     %zu embedded, %zu recovered exactly, %zu lost, %zu lost to CRC-16 collisions\n",
              expected, recovered, lost, collisions);
  std::printf("  damaged pieces    %zu, refused as bad CRC or malformed %zu times over the 4 chunkings\n", damaged,
              refused);
  std::printf("  time              %.2f s (%.0f inputs/s)\n", s, static_cast<double>(inputs) / s);
  if (lost) {
    std::printf("  first loss        %s\n", first_loss.c_str());
    return 1;
  }
  return 0;
}
