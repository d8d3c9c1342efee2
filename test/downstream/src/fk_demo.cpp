// fk_demo ROBOT_YAML: loads a robot description with snake_autonomy's core, runs forward kinematics
// with every joint at zero and checks the straight chain's geometry. Prints
//   frames=N tail_x=X com_x=C
// and exits 0 when the tail sits at -(head_length + N_joints * link_length) on x and the centre of
// mass lies between head and tail; 1 otherwise, 2 on a usage or configuration error.
#include <snake_autonomy/core/kinematics.hpp>
#include <snake_autonomy/core/robot_model.hpp>

#include <cmath>
#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fk_demo ROBOT_YAML\n");
    return 2;
  }
  using namespace snake_autonomy::core;
  try {
    const RobotModel model = RobotModel::from_yaml_file(argv[1]);
    const Kinematics kinematics(model);
    KinematicState state = kinematics.make_state();
    const Eigen::VectorXd q = Eigen::VectorXd::Zero(model.num_joints);
    if (!kinematics.compute(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity(), q, state)) {
      std::fprintf(stderr, "fk_demo: forward kinematics refused the zero posture\n");
      return 1;
    }
    const double tail_x = state.link_positions.back().x();
    const double expected_x = -(model.head_length_m + model.num_joints * model.link_length_m);
    std::printf("frames=%d tail_x=%.9f com_x=%.9f\n", kinematics.num_frames(), tail_x, state.com.x());
    const bool ok = std::abs(tail_x - expected_x) < 1e-9 && state.com.x() < 0.0 && state.com.x() > tail_x;
    return ok ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fk_demo: %s\n", e.what());
    return 2;
  }
}
