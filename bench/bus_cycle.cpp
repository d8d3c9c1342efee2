// bench_bus_cycle: one driver cycle on a real port (the mocked bus's pty, or the robot):
// a sync read of the 10-byte feedback block (current, velocity, position) of every servo and a
// sync write of their goal positions; then the same with fast sync read. Prints bytes on the wire
// per cycle against the minimum, and CPU and wall time per cycle of this process.
//
//   bench_bus_cycle --port /tmp/snake_bus [--ids 11] [--cycles 2000] [--baud 1000000]
//
// bench/bus_cycle starts the mock, runs this, runs ROBOTIS's Python SDK on the same mock, and
// compares. Leaves torque on at the goals it wrote (the mock does not care; on a robot, mind it).
#include <time.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "snake_autonomy/dynamixel/conversions.hpp"
#include "snake_autonomy/dynamixel/serial_bus.hpp"

namespace dx = snake_autonomy::dynamixel;

namespace {

double cpu_s() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + ts.tv_nsec * 1e-9;
}

double wall_s() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

struct Result {
  double cpu_ms = 0, wall_ms = 0, bytes = 0;
  int failed_cycles = 0;
};

constexpr std::size_t kMaxServos = 32;

}  // namespace

int main(int argc, char** argv) {
  std::string port;
  int n_ids = 11, cycles = 2000, baud = 1000000;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i];
    if (k == "--port") port = argv[i + 1];
    else if (k == "--ids") n_ids = std::atoi(argv[i + 1]);
    else if (k == "--cycles") cycles = std::atoi(argv[i + 1]);
    else if (k == "--baud") baud = std::atoi(argv[i + 1]);
    else {
      std::fprintf(stderr, "unknown option %s\n", k.c_str());
      return 2;
    }
  }
  if (port.empty() || n_ids < 1 || n_ids > static_cast<int>(kMaxServos) || cycles < 1) {
    std::fprintf(stderr, "usage: bench_bus_cycle --port PATH [--ids 1..%zu] [--cycles N] [--baud B]\n", kMaxServos);
    return 2;
  }
  dx::SerialConfig config;
  config.device = port;
  config.baud_bps = baud;
  config.timing.latency_s = 0.05;  // generous: a Python mock on a loaded machine
  dx::SerialBus bus(config);
  const std::size_t n = static_cast<std::size_t>(n_ids);

  // Configure-time buffers: nothing below allocates.
  std::array<std::uint8_t, kMaxServos> ids{};
  std::array<std::uint8_t, kMaxServos * dx::kFeedbackBytes> feedback{};
  std::array<dx::ServoReply, kMaxServos> replies{};
  std::array<std::uint8_t, kMaxServos * dx::kGoalPositionBytes> goals{};
  std::array<std::uint8_t, kMaxServos> ones{};
  for (std::size_t i = 0; i < n; ++i) {
    ids[i] = static_cast<std::uint8_t>(i + 1);
    ones[i] = 1;
    dx::put_le(&goals[i * 4], 4, 2048 + 20 * static_cast<int>(i));
  }
  if (bus.sync_write(64, 1, ids.data(), n, ones.data()) != dx::Status::kOk) {
    std::fprintf(stderr, "torque enable failed\n");
    return 1;
  }

  const auto run = [&](bool fast) {
    Result r;
    for (int w = 0; w < 20; ++w) {  // warm-up
      bus.sync_read(dx::kFeedbackAddress, dx::kFeedbackBytes, ids.data(), n, feedback.data(), replies.data());
    }
    bus.reset_counters();
    const double c0 = cpu_s(), w0 = wall_s();
    for (int c = 0; c < cycles; ++c) {
      const dx::Status s = fast ? bus.fast_sync_read(dx::kFeedbackAddress, dx::kFeedbackBytes, ids.data(), n,
                                                     feedback.data(), replies.data())
                                : bus.sync_read(dx::kFeedbackAddress, dx::kFeedbackBytes, ids.data(), n,
                                                feedback.data(), replies.data());
      if (s != dx::Status::kOk) ++r.failed_cycles;
      double sum_rad = 0;  // what a loop does with the feedback
      for (std::size_t i = 0; i < n; ++i)
        sum_rad += dx::decode_feedback(&feedback[i * dx::kFeedbackBytes]).position_rad;
      if (!std::isfinite(sum_rad)) ++r.failed_cycles;
      bus.sync_write(dx::kGoalPositionAddress, dx::kGoalPositionBytes, ids.data(), n, goals.data());
    }
    r.cpu_ms = (cpu_s() - c0) * 1e3 / cycles;
    r.wall_ms = (wall_s() - w0) * 1e3 / cycles;
    const auto& k = bus.counters();
    r.bytes = static_cast<double>(k.bytes_sent + k.bytes_received) / cycles;
    return r;
  };

  // The minimum on the wire (no stuffing): sync read = 14 + n out, n * (11 + 10) back;
  // fast sync read = 14 + n out, 8 + n * (4 + 10) back; sync write = 14 + n * (1 + 4).
  const double write_min = 14.0 + n * 5.0;
  const double sync_min = 14.0 + n + n * 21.0 + write_min;
  const double fast_min = 14.0 + n + 8.0 + n * 14.0 + write_min;
  const Result sync = run(false);
  const Result fast = run(true);
  std::printf("servos=%zu cycles=%d baud=%d port=%s\n", n, cycles, baud, port.c_str());
  std::printf(
      "cpp sync_read+sync_write:      bytes/cycle %.1f (minimum %.0f), cpu %.4f ms/cycle, wall %.3f ms/cycle, "
      "failed cycles %d\n",
      sync.bytes, sync_min, sync.cpu_ms, sync.wall_ms, sync.failed_cycles);
  std::printf(
      "cpp fast_sync_read+sync_write: bytes/cycle %.1f (minimum %.0f), cpu %.4f ms/cycle, wall %.3f ms/cycle, "
      "failed cycles %d\n",
      fast.bytes, fast_min, fast.cpu_ms, fast.wall_ms, fast.failed_cycles);
  std::printf("wire time at %d baud: sync %.3f ms, fast %.3f ms per cycle\n", baud,
              dx::wire_time_s(static_cast<std::size_t>(sync_min), baud) * 1e3,
              dx::wire_time_s(static_cast<std::size_t>(fast_min), baud) * 1e3);
  return sync.failed_cycles + fast.failed_cycles > 0 ? 1 : 0;
}
