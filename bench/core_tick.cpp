// One 100 Hz tick of the core: CPG step + forward kinematics + virtual chassis + CoM + bounding box.
// Prints median, p99 and max over many ticks, for each virtual-chassis construction.
// Usage: bench_core_tick [ROBOT_YAML] [TICKS]   (bench/core_tick runs it beside the numpy version)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "snake_autonomy/core/cpg.hpp"
#include "snake_autonomy/core/gait_library.hpp"
#include "snake_autonomy/core/kinematics.hpp"

using namespace snake_autonomy::core;

int main(int argc, char** argv) {
  const std::string robot = argc > 1 ? argv[1] : std::string(SNAKE_SOURCE_DIR) + "/config/robots/cobra.yaml";
  const int ticks = argc > 2 ? std::stoi(argv[2]) : 200000;
  const GaitLibrary gaits = GaitLibrary::from_yaml_file(std::string(SNAKE_SOURCE_DIR) + "/config/gaits.yaml");
  for (ChassisMethod method : {ChassisMethod::kMeanAxis, ChassisMethod::kSvd}) {
    RobotModel model = RobotModel::from_yaml_file(robot);
    model.chassis = method;
    Cpg cpg(model);
    cpg.set_parameters(gaits.parameters("sidewind", model));
    const Kinematics kin(model);
    KinematicState state = kin.make_state();
    const Eigen::Vector3d base(0.1, 0.2, 0.05);
    const Eigen::Quaterniond orientation(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
    std::vector<double> ns(ticks);
    double checksum = 0.0;
    for (int k = 0; k < ticks; ++k) {
      const auto t0 = std::chrono::steady_clock::now();
      const Eigen::VectorXd& q = cpg.step(0.01);
      kin.compute(base, orientation, q, state);
      const auto t1 = std::chrono::steady_clock::now();
      ns[k] = std::chrono::duration<double, std::nano>(t1 - t0).count();
      checksum += state.com.x();
    }
    std::sort(ns.begin(), ns.end());
    std::printf("cpp %s ticks=%d median_us=%.3f p99_us=%.3f max_us=%.3f checksum=%.6f\n", to_string(method).c_str(),
                ticks, ns[ticks / 2] / 1000.0, ns[static_cast<std::size_t>(ticks * 0.99)] / 1000.0, ns.back() / 1000.0,
                checksum);
  }
  return 0;
}
