// driver::TrajectorySource costs: check() and submit() on the caller's thread for a trajectory of the
// full capacity (max_trajectory_points, 16 joints: the unified snake), take() and update() on the
// loop (median, p99, max per call). Prints figures; asserts nothing.
// Usage: bench_trajectory_source [POINTS=20000] [JOINTS=16]   (bench/trajectory_source runs it)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "snake_autonomy/driver/trajectory_source.hpp"

using namespace snake_autonomy::driver;
using Clock = std::chrono::steady_clock;

namespace {
double us_since(Clock::time_point t0) { return std::chrono::duration<double, std::micro>(Clock::now() - t0).count(); }
}  // namespace

int main(int argc, char** argv) {
  const int points = argc > 1 ? std::stoi(argv[1]) : 20000;
  const int n = argc > 2 ? std::stoi(argv[2]) : 16;
  TrajectoryLimits limits;
  limits.lower_rad = Eigen::VectorXd::Constant(n, -1.5);
  limits.upper_rad = Eigen::VectorXd::Constant(n, 1.5);
  limits.max_velocity_rad_s = 4.5;
  limits.max_points = points;
  auto t0 = Clock::now();
  TrajectorySource src(n, limits);
  const double construct_us = us_since(t0);
  JointTrajectoryRequest r;
  r.id = "bench";
  for (int j = 0; j < n; ++j) r.joint_names.push_back("joint_" + std::to_string(j + 1));
  const double period_s = 0.05;
  for (int k = 0; k < points; ++k) {
    JointTrajectoryPoint p;
    p.time_from_start_s = 1.0 + k * period_s;
    for (int j = 0; j < n; ++j) p.positions_rad.push_back(0.5 * std::sin(0.01 * k + j));
    r.points.push_back(std::move(p));
  }
  t0 = Clock::now();
  const std::string why = src.check(r);
  const double check_us = us_since(t0);
  t0 = Clock::now();
  const std::string why2 = src.submit(r);
  const double submit_us = us_since(t0);
  if (!why.empty() || !why2.empty()) {
    std::fprintf(stderr, "refused:\n%s\n", why.c_str());
    return 1;
  }
  t0 = Clock::now();
  src.take(0.0, Eigen::VectorXd::Zero(n));
  const double take_us = us_since(t0);
  Eigen::VectorXd goal = Eigen::VectorXd::Zero(n);
  std::vector<double> ns;
  const double duration = 1.0 + (points - 1) * period_s;
  ns.reserve(static_cast<std::size_t>(duration / 0.01) + 2);
  double checksum = 0.0;
  for (double t = 0.0; src.running(); t += 0.01) {
    const auto a = Clock::now();
    src.update(t, goal);
    ns.push_back(std::chrono::duration<double, std::nano>(Clock::now() - a).count());
    checksum += goal[0];
  }
  std::sort(ns.begin(), ns.end());
  std::printf(
      "trajectory_source points=%d joints=%d storage_mb=%.1f construct_ms=%.2f check_ms=%.2f submit_ms=%.2f "
      "take_us=%.2f\n",
      points, n, 2.0 * points * (2.0 * n + 1) * 8 / 1e6, construct_us / 1e3, check_us / 1e3, submit_us / 1e3, take_us);
  std::printf("  update (100 Hz over %.0f s) calls=%zu median_us=%.3f p99_us=%.3f max_us=%.3f checksum=%.6f\n",
              duration, ns.size(), ns[ns.size() / 2] / 1e3, ns[static_cast<std::size_t>(ns.size() * 0.99)] / 1e3,
              ns.back() / 1e3, checksum);
  return 0;
}
