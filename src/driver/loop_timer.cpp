#include "snake_autonomy/driver/loop_timer.hpp"

#include <time.h>

#include <cerrno>
#include <cmath>
#include <sstream>

#include "snake_autonomy/core/robot_model.hpp"  // core::ConfigError

namespace snake_autonomy::driver {

std::vector<std::string> LoopConfig::validate() const {
  std::vector<std::string> errors;
  if (!std::isfinite(rate_hz) || rate_hz < 1.0 || rate_hz > 10000.0) {
    std::ostringstream s;
    s << "rate_hz: " << rate_hz << " is not in 1 .. 10000";
    errors.push_back(s.str());
  }
  return errors;
}

double LoopStats::window_period_mean_s() const noexcept {
  // The first window cycle has no period when the loop just started: periods = cycles - 1 at most.
  return window_cycles > 1 ? window_period_sum_s / static_cast<double>(window_cycles - 1) : 0.0;
}

double LoopStats::window_period_std_s() const noexcept {
  if (window_cycles < 3) return 0.0;
  const double n = static_cast<double>(window_cycles - 1);
  const double mean = window_period_sum_s / n;
  const double var = window_period_sq_sum_s2 / n - mean * mean;
  return var > 0.0 ? std::sqrt(var) : 0.0;
}

double LoopStats::window_rate_hz() const noexcept {
  const double mean = window_period_mean_s();
  return mean > 0.0 ? 1.0 / mean : 0.0;
}

void LoopStats::reset_window() noexcept {
  // Keep one cycle so that the next period (from the last wake-up) counts in the new window.
  window_cycles = window_cycles > 0 ? 1 : 0;
  window_overruns = 0;
  window_period_sum_s = window_period_sq_sum_s2 = window_period_max_s = window_period_min_s = 0.0;
  window_work_sum_s = window_work_max_s = window_late_max_s = 0.0;
}

LoopTimer::LoopTimer(const LoopConfig& config) {
  const auto errors = config.validate();
  if (!errors.empty()) {
    std::string what = "loop configuration:";
    for (const auto& e : errors) what += "\n  " + e;
    throw core::ConfigError(what);
  }
  period_s_ = 1.0 / config.rate_hz;
  period_ = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(period_s_));
}

void LoopTimer::start(Clock::time_point now) noexcept {
  deadline_ = now + period_;
  have_wake_ = false;
  stats_ = LoopStats{};
}

LoopTimer::Clock::time_point LoopTimer::wait() noexcept {
  // steady_clock is CLOCK_MONOTONIC on Linux (libstdc++): sleep to the absolute deadline.
  const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(deadline_.time_since_epoch()).count();
  timespec ts;
  ts.tv_sec = static_cast<time_t>(ns / 1000000000LL);
  ts.tv_nsec = static_cast<long>(ns % 1000000000LL);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
  wake_ = Clock::now();
  const double late = std::chrono::duration<double>(wake_ - deadline_).count();
  ++stats_.cycles;
  ++stats_.window_cycles;
  if (late > stats_.window_late_max_s) stats_.window_late_max_s = late;
  if (have_wake_) {
    const double period = std::chrono::duration<double>(wake_ - last_wake_).count();
    stats_.window_period_sum_s += period;
    stats_.window_period_sq_sum_s2 += period * period;
    if (period > stats_.window_period_max_s) stats_.window_period_max_s = period;
    if (stats_.window_period_min_s == 0.0 || period < stats_.window_period_min_s) stats_.window_period_min_s = period;
  }
  last_wake_ = wake_;
  have_wake_ = true;
  return wake_;
}

void LoopTimer::finish(Clock::time_point now) noexcept {
  const double work = std::chrono::duration<double>(now - wake_).count();
  stats_.window_work_sum_s += work;
  if (work > stats_.window_work_max_s) stats_.window_work_max_s = work;
  Clock::time_point next = deadline_ + period_;
  if (now > next) {
    ++stats_.overruns;
    ++stats_.window_overruns;
    // First deadline of the grid strictly after `now`.
    const auto behind = (now - next) / period_ + 1;
    stats_.skipped_deadlines += static_cast<std::uint64_t>(behind);
    next += behind * period_;
  }
  deadline_ = next;
}

}  // namespace snake_autonomy::driver
