// LoopTimer: the timing of a fixed-rate loop thread. ROS-free, no allocation after construction.
//
// The loop sleeps until absolute deadlines on the steady clock (clock_nanosleep, CLOCK_MONOTONIC,
// TIMER_ABSTIME), so the rate does not drift with the work done in a cycle. A cycle whose work
// ends after the next deadline is an overrun: it is counted, and the deadlines that passed
// meanwhile are skipped (the next deadline is the first one of the grid after the work ended), so a
// stall is never followed by a burst of catch-up cycles.
//
//   LoopTimer timer(LoopConfig{100.0});
//   timer.start(LoopTimer::Clock::now());
//   while (running) {
//     const auto wake = timer.wait();          // sleeps until the deadline
//     controller.update(t_s(wake), dt_s);      // the work
//     timer.finish(LoopTimer::Clock::now());   // counts overruns, schedules the next deadline
//   }
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

namespace snake_autonomy::driver {

struct LoopConfig {
  double rate_hz = 100.0;  // cycles per second, 1 .. 10000
  // Every problem, naming key and value; empty when usable.
  std::vector<std::string> validate() const;
};

// Figures of the loop. Totals since start(); the window figures since the last reset_window()
// (the diagnostics publisher resets them once per report).
struct LoopStats {
  std::uint64_t cycles = 0;
  std::uint64_t overruns = 0;         // cycles whose work ended after the next deadline
  std::uint64_t skipped_deadlines = 0;  // deadlines dropped after overruns
  // Window:
  std::uint64_t window_cycles = 0;
  std::uint64_t window_overruns = 0;
  double window_period_sum_s = 0.0;     // wake-to-wake periods
  double window_period_sq_sum_s2 = 0.0;
  double window_period_max_s = 0.0;
  double window_period_min_s = 0.0;
  double window_work_sum_s = 0.0;       // wake to finish
  double window_work_max_s = 0.0;
  double window_late_max_s = 0.0;       // wake-up time minus deadline

  double window_period_mean_s() const noexcept;
  double window_period_std_s() const noexcept;
  double window_rate_hz() const noexcept;  // 1 / mean period, 0 without data
  void reset_window() noexcept;
};

class LoopTimer {
 public:
  using Clock = std::chrono::steady_clock;

  // Throws core::ConfigError listing config.validate()'s problems.
  explicit LoopTimer(const LoopConfig& config);

  double period_s() const noexcept { return period_s_; }
  // The first deadline is now + one period.
  void start(Clock::time_point now) noexcept;
  // Sleeps until the current deadline (returns at once when it has passed) and returns the
  // wake-up time. Records the wake-to-wake period and the wake-up lateness.
  Clock::time_point wait() noexcept;
  // The cycle's work is done at `now`: counts an overrun when now is past the next deadline and
  // schedules the next deadline.
  void finish(Clock::time_point now) noexcept;
  Clock::time_point deadline() const noexcept { return deadline_; }

  const LoopStats& stats() const noexcept { return stats_; }
  LoopStats& stats() noexcept { return stats_; }

 private:
  Clock::duration period_;
  double period_s_;
  Clock::time_point deadline_{};
  Clock::time_point wake_{};
  Clock::time_point last_wake_{};
  bool have_wake_ = false;
  LoopStats stats_;
};

}  // namespace snake_autonomy::driver
