#include <gtest/gtest.h>

#include <thread>

#include "snake_autonomy/core/robot_model.hpp"
#include "snake_autonomy/driver/loop_timer.hpp"

using namespace snake_autonomy::core;
using namespace snake_autonomy::driver;
using Clock = LoopTimer::Clock;

TEST(LoopTimer, ValidatesTheRate) {
  EXPECT_EQ(LoopConfig{0.5}.validate().size(), 1u);
  EXPECT_NE(LoopConfig{0.5}.validate()[0].find("rate_hz: 0.5"), std::string::npos);
  EXPECT_TRUE(LoopConfig{500.0}.validate().empty());
  EXPECT_THROW(LoopTimer(LoopConfig{-1.0}), ConfigError);
}

TEST(LoopTimer, SleepsToAbsoluteDeadlines) {
  LoopTimer timer(LoopConfig{200.0});
  const auto t0 = Clock::now();
  timer.start(t0);
  Clock::time_point wake;
  for (int k = 0; k < 20; ++k) {
    wake = timer.wait();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));  // work that does not add up
    timer.finish(Clock::now());
  }
  const double elapsed = std::chrono::duration<double>(wake - t0).count();
  EXPECT_GE(elapsed, 20 * 0.005);
  EXPECT_LT(elapsed, 20 * 0.005 + 0.05);  // generous: the machine is shared
  EXPECT_EQ(timer.stats().cycles, 20u);
  EXPECT_NEAR(timer.stats().window_rate_hz(), 200.0, 40.0);
}

TEST(LoopTimer, CountsOverrunsAndSkipsMissedDeadlines) {
  LoopTimer timer(LoopConfig{100.0});
  const auto t0 = Clock::now();
  timer.start(t0);
  timer.wait();
  // The work "ends" 3.5 periods after the first deadline: deadlines 2, 3 and 4 are gone.
  const auto first = t0 + std::chrono::milliseconds(10);
  timer.finish(first + std::chrono::microseconds(35000));
  EXPECT_EQ(timer.stats().overruns, 1u);
  EXPECT_EQ(timer.stats().skipped_deadlines, 3u);
  EXPECT_EQ(timer.deadline(), first + std::chrono::milliseconds(40));
  // A cycle that ends in time is no overrun.
  timer.wait();
  timer.finish(timer.deadline() + std::chrono::milliseconds(2));
  EXPECT_EQ(timer.stats().overruns, 1u);
  EXPECT_EQ(timer.deadline(), first + std::chrono::milliseconds(50));
  timer.stats().reset_window();
  EXPECT_EQ(timer.stats().window_overruns, 0u);
  EXPECT_EQ(timer.stats().overruns, 1u);
}
