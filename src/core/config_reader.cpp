#include "snake_autonomy/core/config_reader.hpp"

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <system_error>

#include "snake_autonomy/core/robot_model.hpp"

namespace snake_autonomy::core {

namespace {

// Flow-style rendering that stops after `budget` characters (never walks a huge node whole).
void dump_bounded(const YAML::Node& n, std::string* out, std::size_t budget, int depth) {
  if (out->size() >= budget) return;
  if (depth > 8) {
    *out += "...";
    return;
  }
  switch (n.Type()) {
    case YAML::NodeType::Scalar: *out += n.Scalar().substr(0, budget - out->size()); return;
    case YAML::NodeType::Sequence: {
      *out += "[";
      bool first = true;
      for (const auto& item : n) {
        if (out->size() >= budget) return;
        if (!first) *out += ", ";
        first = false;
        dump_bounded(item, out, budget, depth + 1);
      }
      *out += "]";
      return;
    }
    case YAML::NodeType::Map: {
      *out += "{";
      bool first = true;
      for (const auto& kv : n) {
        if (out->size() >= budget) return;
        if (!first) *out += ", ";
        first = false;
        dump_bounded(kv.first, out, budget, depth + 1);
        *out += ": ";
        dump_bounded(kv.second, out, budget, depth + 1);
      }
      *out += "}";
      return;
    }
    case YAML::NodeType::Null: *out += "~"; return;
    case YAML::NodeType::Undefined: return;
  }
}

std::string line_of(const YAML::Node& n) { return "line " + std::to_string(n.Mark().line + 1); }

// Duplicate keys, size and depth of a parsed document (yaml-cpp keeps either of two equal keys
// silently, and shares aliased nodes: counting visits bounds what the loaders will walk).
void check_tree(const YAML::Node& n, const std::string& source, int depth, std::size_t* visits) {
  if (++*visits > kMaxConfigNodes)
    throw ConfigError(source + ": more than " + std::to_string(kMaxConfigNodes) +
                      " values (aliases expanding?): not a configuration file");
  if (depth > kMaxConfigDepth)
    throw ConfigError(source + ": " + line_of(n) + ": nested deeper than " + std::to_string(kMaxConfigDepth) +
                      " levels");
  if (n.IsSequence()) {
    for (const auto& item : n) check_tree(item, source, depth + 1, visits);
  } else if (n.IsMap()) {
    std::map<std::string, int> first_line;
    for (const auto& kv : n) {
      check_tree(kv.first, source, depth + 1, visits);
      if (kv.first.IsScalar()) {
        const auto [it, inserted] = first_line.emplace(kv.first.Scalar(), kv.first.Mark().line + 1);
        if (!inserted)
          throw ConfigError(source + ": " + line_of(kv.first) + ": duplicate key '" + kv.first.Scalar() +
                            "' (first given on line " + std::to_string(it->second) + ")");
      }
      check_tree(kv.second, source, depth + 1, visits);
    }
  }
}

}  // namespace

std::string read_config_file(const std::string& path, const std::string& what) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) throw ConfigError(path + ": cannot open " + what + " (" + ec.message() + ")");
  if (size > kMaxConfigBytes)
    throw ConfigError(path + ": larger than " + std::to_string(kMaxConfigBytes) + " bytes (" + std::to_string(size) +
                      "): not a " + what);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path + ": cannot open " + what);
  std::string text(static_cast<std::size_t>(size), '\0');
  in.read(text.data(), static_cast<std::streamsize>(size));
  text.resize(static_cast<std::size_t>(in.gcount()));
  const auto nul = text.find('\0');
  if (nul != std::string::npos)
    throw ConfigError(path + ": not a text file (NUL byte at offset " + std::to_string(nul) + "): not a " + what);
  return text;
}

YAML::Node load_config_yaml(const std::string& text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& ex) {
    throw ConfigError(source + ": not valid YAML: " + ex.what());
  }
  if (!root.IsMap()) throw ConfigError(source + ": expected a mapping at the top level");
  std::size_t visits = 0;
  check_tree(root, source, 0, &visits);
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
  std::string out;
  dump_bounded(n, &out, kMaxDumpChars, 0);
  if (out.size() >= kMaxDumpChars) {
    out.resize(kMaxDumpChars);
    out += "...";
  }
  return out;
}

void throw_if_errors(const std::vector<std::string>& errors, const std::string& source, const std::string& what) {
  if (errors.empty()) return;
  std::string msg = source + ": invalid " + what + " (" + std::to_string(errors.size()) + " problems):";
  for (const auto& e : errors) msg += "\n  " + e;
  throw ConfigError(msg);
}

}  // namespace snake_autonomy::core
