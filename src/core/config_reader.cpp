#include "snake_autonomy/core/config_reader.hpp"

#include <fstream>
#include <sstream>

#include "snake_autonomy/core/robot_model.hpp"

namespace snake_autonomy::core {

std::string read_config_file(const std::string& path, const std::string& what) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open " + what);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

YAML::Node load_config_yaml(const std::string& text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& ex) {
    throw ConfigError(source + ": not valid YAML: " + ex.what());
  }
  if (!root.IsMap()) throw ConfigError(source + ": expected a mapping at the top level");
  return root;
}

YAML::Node ConfigReader::child(const YAML::Node& parent, const std::string& key, const std::string& path,
                               bool required) {
  if (!parent || !parent.IsMap()) return YAML::Node();
  YAML::Node n = parent[key];
  if (!n && required) errors_->push_back(path + ": missing");
  return n;
}

std::string ConfigReader::dump(const YAML::Node& n) {
  YAML::Emitter e;
  e << YAML::Flow << n;
  return e.c_str();
}

void throw_if_errors(const std::vector<std::string>& errors, const std::string& source, const std::string& what) {
  if (errors.empty()) return;
  std::string msg = source + ": invalid " + what + " (" + std::to_string(errors.size()) + " problems):";
  for (const auto& e : errors) msg += "\n  " + e;
  throw ConfigError(msg);
}

}  // namespace snake_autonomy::core
