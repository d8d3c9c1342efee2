// Reading YAML configuration while collecting every problem (key and value) instead of stopping
// at the first: the robot description and the gait library both load through this.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <string>
#include <type_traits>
#include <vector>

namespace snake_autonomy::core {

// Configuration files are small: larger ones are refused before they are read.
inline constexpr std::size_t kMaxConfigBytes = std::size_t{1} << 20;
// Longest list a configuration may hold (joints, ids, masses, ...): longer ones are refused unread.
inline constexpr std::size_t kMaxConfigListLength = 1024;
// Longest rendering of a value inside an error message (a huge or aliased node is cut short).
inline constexpr std::size_t kMaxDumpChars = 120;
// Most values (keys, scalars, lists, mappings; aliases counted each time they are used) and deepest
// nesting of a configuration document: a "billion laughs" file is refused, not walked.
inline constexpr std::size_t kMaxConfigNodes = 65536;
inline constexpr int kMaxConfigDepth = 32;

// The whole text of a configuration file; throws ConfigError "<path>: cannot open <what>",
// "<path>: larger than 1048576 bytes" or "<path>: not a text file (NUL byte at offset N)".
std::string read_config_file(const std::string& path, const std::string& what);

// The YAML document of a configuration text; throws ConfigError "<source>: not valid YAML: ...",
// "<source>: expected a mapping at the top level", "<source>: line N: duplicate key 'k' (first given
// on line M)", or when the document has more than kMaxConfigNodes values or kMaxConfigDepth levels.
YAML::Node load_config_yaml(const std::string& text, const std::string& source);

class ConfigReader {
 public:
  explicit ConfigReader(std::vector<std::string>* errors) : errors_(errors) {}

  // parent[key]; records "<path>: missing" when required and absent.
  YAML::Node child(const YAML::Node& parent, const std::string& key, const std::string& path, bool required = true);

  // Converts n (if present) into out; records "<path>: expected <a type>, got '<value>'" on failure
  // and "<path>: must be finite, got <value>" for a non-finite number.
  template <typename T>
  bool scalar(const YAML::Node& n, const std::string& path, T* out) {
    if (!n) return false;
    try {
      *out = n.as<T>();
    } catch (const YAML::Exception&) {
      errors_->push_back(path + ": expected " + type_name<T>() + ", got '" + dump(n) + "'");
      return false;
    }
    if constexpr (std::is_floating_point_v<T>) {
      if (!std::isfinite(*out)) {
        errors_->push_back(path + ": must be finite, got " + dump(n));
        return false;
      }
    }
    return true;
  }

  template <typename T>
  bool list(const YAML::Node& n, const std::string& path, std::vector<T>* out) {
    if (!n) return false;
    if (!n.IsSequence()) {
      errors_->push_back(path + ": expected a list, got '" + dump(n) + "'");
      return false;
    }
    if (n.size() > kMaxConfigListLength) {
      errors_->push_back(path + ": at most " + std::to_string(kMaxConfigListLength) + " values, got " +
                         std::to_string(n.size()));
      return false;
    }
    out->clear();
    bool ok = true;
    for (std::size_t i = 0; i < n.size(); ++i) {
      T v{};
      if (scalar(n[i], path + "[" + std::to_string(i) + "]", &v)) {
        out->push_back(v);
      } else {
        ok = false;
      }
    }
    return ok;
  }

  void error(const std::string& message) { errors_->push_back(message); }

  // The value in flow style, at most kMaxDumpChars characters (then "...").
  static std::string dump(const YAML::Node& n);

 private:
  template <typename T>
  static const char* type_name() {
    if constexpr (std::is_same_v<T, bool>) return "true or false";
    if constexpr (std::is_integral_v<T>) return "an integer";
    if constexpr (std::is_floating_point_v<T>) return "a number";
    return "a string";
  }
  std::vector<std::string>* errors_;
};

// Throws ConfigError "<source>: invalid <what> (N problems):" and one line per problem, if any.
void throw_if_errors(const std::vector<std::string>& errors, const std::string& source, const std::string& what);

}  // namespace snake_autonomy::core
