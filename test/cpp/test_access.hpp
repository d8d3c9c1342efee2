// Test hooks (friends of Cpg and GaitSource): the only way to reach a state no input can make
// (a non-finite oscillator phase). Tests only.
#pragma once

#include <cmath>

#include "snake_autonomy/core/cpg.hpp"
#include "snake_autonomy/driver/gait_source.hpp"

namespace snake_autonomy::core {
struct CpgTestAccess {
  static void corrupt_phase(Cpg& cpg, int joint) { cpg.theta_(joint) = std::nan(""); }
};
}  // namespace snake_autonomy::core

namespace snake_autonomy::driver {
struct GaitSourceTestAccess {
  static core::Cpg& cpg(GaitSource& g) { return g.cpg_; }
};
}  // namespace snake_autonomy::driver
