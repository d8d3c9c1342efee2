// The driver's loop on a real serial port (normally the mocked bus's pty): DriverController +
// SerialBus + LoopTimer, exactly what driver_node's loop thread runs, without ROS. Sidewinding, no
// base pose required. Prints the sustained rate, overruns, period jitter, wall time and CPU time
// per cycle (the loop thread's CLOCK_THREAD_CPUTIME_ID) and bytes on the wire per cycle.
// Usage: bench_driver_loop PORT [RATE_HZ=500] [SECONDS=5] [fast]   (bench/driver_loop starts the mock)
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "snake_autonomy/driver/driver_controller.hpp"
#include "snake_autonomy/driver/loop_timer.hpp"
#include "snake_autonomy/dynamixel/serial_bus.hpp"

using namespace snake_autonomy;
using Clock = std::chrono::steady_clock;

namespace {
double thread_cpu_s() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + ts.tv_nsec * 1e-9;
}
double pct(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[std::min(v.size() - 1, static_cast<std::size_t>(p * v.size()))];
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s PORT [RATE_HZ] [SECONDS] [fast]\n", argv[0]);
    return 2;
  }
  const std::string port = argv[1];
  const double rate_hz = argc > 2 ? std::stod(argv[2]) : 500.0;
  const double seconds = argc > 3 ? std::stod(argv[3]) : 5.0;
  const bool fast = argc > 4 && std::string(argv[4]) == "fast";
  const std::string dir = SNAKE_SOURCE_DIR;
  const auto model = core::RobotModel::from_yaml_file(dir + "/config/robots/cobra.yaml");
  const auto gaits = core::GaitLibrary::from_yaml_file(dir + "/config/gaits.yaml");
  const auto table = dynamixel::ControlTable::from_yaml_file(dir + "/config/dynamixel/xh540_w270.yaml");
  dynamixel::SerialConfig sc;
  sc.device = port;
  sc.timing.latency_s = 0.002;  // a pty has no USB latency; the Python mock answers in about 1 ms
  dynamixel::SerialBus bus(sc);
  driver::DriverConfig cfg;
  cfg.require_pose = false;
  cfg.command_timeout_s = 0.0;  // one command for the whole run: no command lifetime
  cfg.fast_sync_read = fast;
  cfg.status_every_cycles = static_cast<int>(rate_hz);  // voltage/temperature once a second, as on the robot
  driver::DriverController ctl(model, gaits, table, bus, cfg);
  ctl.start(0.0);
  driver::GaitCommandRequest cmd;
  cmd.gait = "sidewind";
  if (!ctl.command_gait(cmd).empty()) return 1;

  driver::LoopTimer timer(driver::LoopConfig{rate_hz});
  const auto n = static_cast<std::size_t>(rate_hz * seconds);
  std::vector<double> work_ms, cpu_us, period_ms;
  work_ms.reserve(n);
  cpu_us.reserve(n);
  period_ms.reserve(n);
  const auto epoch = Clock::now();
  timer.start(epoch);
  Clock::time_point prev = epoch;
  bus.reset_counters();
  std::uint64_t failed = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const auto wake = timer.wait();
    const double c0 = thread_cpu_s();
    if (!ctl.update(std::chrono::duration<double>(wake - epoch).count(),
                    std::chrono::duration<double>(wake - prev).count()))
      ++failed;
    const double c1 = thread_cpu_s();
    const auto end = Clock::now();
    timer.finish(end);
    if (k > 0) period_ms.push_back(std::chrono::duration<double, std::milli>(wake - prev).count());
    prev = wake;
    work_ms.push_back(std::chrono::duration<double, std::milli>(end - wake).count());
    cpu_us.push_back((c1 - c0) * 1e6);
  }
  const double elapsed = std::chrono::duration<double>(prev - epoch).count();
  const auto& st = timer.stats();
  const auto& c = bus.counters();
  double mean_p = 0, sq = 0;
  for (double p : period_ms) mean_p += p;
  mean_p /= period_ms.size();
  for (double p : period_ms) sq += (p - mean_p) * (p - mean_p);
  std::printf(
      "driver_loop port=%s target_hz=%.0f %s cycles=%zu rate_hz=%.1f overruns=%lu skipped=%lu failed_cycles=%lu "
      "state=%s\n",
      port.c_str(), rate_hz, fast ? "fast_sync_read" : "sync_read", n, (n - 1) / elapsed,
      static_cast<unsigned long>(st.overruns), static_cast<unsigned long>(st.skipped_deadlines),
      static_cast<unsigned long>(failed), driver::to_string(ctl.state()));
  std::printf("  period_ms mean=%.3f std=%.3f p99=%.3f max=%.3f\n", mean_p, std::sqrt(sq / period_ms.size()),
              pct(period_ms, 0.99), pct(period_ms, 1.0));
  std::printf("  wall_per_cycle_ms median=%.3f p99=%.3f max=%.3f (bus round trips to the Python mock included)\n",
              pct(work_ms, 0.5), pct(work_ms, 0.99), pct(work_ms, 1.0));
  std::printf("  cpu_per_cycle_us median=%.1f p99=%.1f max=%.1f (loop thread CPU time: codec, CPG, FK, syscalls)\n",
              pct(cpu_us, 0.5), pct(cpu_us, 0.99), pct(cpu_us, 1.0));
  std::printf("  bytes_per_cycle sent=%.1f received=%.1f crc_errors=%lu timeouts=%lu\n",
              static_cast<double>(c.bytes_sent) / n, static_cast<double>(c.bytes_received) / n,
              static_cast<unsigned long>(c.crc_errors), static_cast<unsigned long>(c.timeouts));
  ctl.shutdown();
  return 0;
}
