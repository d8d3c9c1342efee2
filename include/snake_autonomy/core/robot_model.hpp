// Robot description: geometry, masses, joint limits, servo mapping, CPG and steering settings.
// Loaded from config/robots/<name>.yaml; validate() collects every problem at once, naming the key
// and the value, and loading refuses a description with any problem. ROS-free.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace snake_autonomy::core {

enum class JointAxis { kPitch, kYaw };

enum class ChassisMethod { kMeanAxis, kSvd };

struct SteeringConfig {
  std::vector<double> weights;      // one per yaw joint, head to tail (eq. 3.27)
  double delta_limit_rad = 0.0;     // |delta| clip (eq. 3.30)
  double delta_offset_rad = 0.0;    // drift compensation (eq. 3.31)
  double amplitude_min_rad = 0.0;   // clamp of corrected amplitudes (eq. 3.29)
  double amplitude_max_rad = 0.0;
};

struct CpgConfig {
  double mu = 10.0;                  // 1/s, phase coupling strength (eq. 3.21)
  double gamma = 2.0;                // rad/s, amplitude dynamics (eq. 3.23 as critically damped)
  double amplitude_limit_rad = 0.0;  // |a_des| clamp
};

struct ServoConfig {
  std::string model;                    // control table name, e.g. "xh540_w270"
  std::vector<int> ids;                 // Dynamixel IDs in joint order
  std::vector<int> directions;          // +1 or -1
  std::vector<int> zero_offsets_ticks;  // ticks added to the centre (2048) at q = 0
};

// Thrown by RobotModel::from_yaml / validate(): what() lists every problem, one per line.
class ConfigError : public std::runtime_error {
 public:
  explicit ConfigError(const std::string& what) : std::runtime_error(what) {}
};

// Physical ranges of a robot description (validate() refuses anything outside, naming key and value).
inline constexpr int kMaxJoints = 64;               // num_joints in 2..64 (checked before any allocation)
inline constexpr double kMaxMassKg = 100.0;         // per frame, (0, 100] kg
inline constexpr double kMaxLengthM = 10.0;         // lengths, radius and bounding-box padding, (0, 10] m
inline constexpr double kMaxCpgRate = 1000.0;       // cpg.mu (1/s) and cpg.gamma (rad/s), (0, 1000]
inline constexpr double kMaxSteeringWeight = 100.0;  // |steering.weights[i]|

struct RobotModel {
  std::string name;
  int num_joints = 0;
  std::vector<JointAxis> axes;        // per joint
  double head_length_m = 0.0;         // H of eq. 3.3
  double link_length_m = 0.0;         // L of eq. 3.4
  double link_radius_m = 0.0;         // capsule radius for URDF / MuJoCo
  std::vector<double> masses_kg;      // per frame: base, head, link_1..link_N (N + 2 values)
  std::vector<double> joint_lower_rad;
  std::vector<double> joint_upper_rad;
  ServoConfig servos;
  CpgConfig cpg;
  SteeringConfig steering;
  ChassisMethod chassis = ChassisMethod::kMeanAxis;
  double bbox_padding_m = 0.1;        // eq. 3.20

  int num_frames() const { return num_joints + 2; }
  // Frame names in chain order (URDF links, TF frames): base_link, head_link, link_1..link_N.
  std::vector<std::string> frame_names() const;
  // Joint names in order: joint_1..joint_N.
  std::vector<std::string> joint_names() const;
  // Indices (0-based joint numbers) of the yaw / pitch joints, head to tail.
  std::vector<int> yaw_joints() const;
  std::vector<int> pitch_joints() const;

  // Every problem found, each naming key and value; empty when the model is usable.
  std::vector<std::string> validate() const;
  // Throws ConfigError listing every problem of validate().
  void validate_or_throw() const;

  // Parses and validates. Throws ConfigError naming the file, each key and each bad value.
  static RobotModel from_yaml_file(const std::string& path);
  static RobotModel from_yaml_string(const std::string& text, const std::string& source = "<string>");
};

std::string to_string(JointAxis axis);
std::string to_string(ChassisMethod method);

}  // namespace snake_autonomy::core
