#include "snake_autonomy/dynamixel/control_table.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "snake_autonomy/core/config_reader.hpp"
#include "snake_autonomy/dynamixel/protocol.hpp"

namespace snake_autonomy::dynamixel {

const char* const kRequiredEntries[] = {
    "model_number",        "return_delay_time",  "operating_mode",     "torque_enable",    "hardware_error_status",
    "goal_position",       "present_current",    "present_velocity",   "present_position", "present_input_voltage",
    "present_temperature", "min_position_limit", "max_position_limit",
};
const std::size_t kNumRequiredEntries = sizeof(kRequiredEntries) / sizeof(kRequiredEntries[0]);

namespace {

const char* const kEntryKeys[] = {"address", "size",  "access",  "signed", "eeprom",
                                  "unit",    "scale", "default", "min",    "max"};

}  // namespace

const ControlTableEntry* ControlTable::find(const std::string& name) const noexcept {
  for (const auto& e : entries) {
    if (e.name == name) return &e;
  }
  return nullptr;
}

const ControlTableEntry& ControlTable::at(const std::string& name) const {
  const ControlTableEntry* e = find(name);
  if (!e) throw ConfigError("control table '" + model + "': no entry '" + name + "'");
  return *e;
}

std::vector<std::string> ControlTable::validate() const {
  std::vector<std::string> errors;
  if (model.empty()) errors.push_back("model: missing or empty");
  if (model_number <= 0 || model_number > 0xFFFF) {
    errors.push_back("model_number: " + std::to_string(model_number) + " is not in 1..65535");
  }
  if (!(torque_constant_nm_per_a >= 0.0) || !std::isfinite(torque_constant_nm_per_a)) {
    std::ostringstream s;
    s << "torque_constant_nm_per_a: " << torque_constant_nm_per_a << " is not a finite number >= 0";
    errors.push_back(s.str());
  }
  for (const auto& [name, bit] : hardware_error_bits) {
    if (bit < 0 || bit > 7)
      errors.push_back("hardware_error_bits." + name + ": bit " + std::to_string(bit) + " is not in 0..7");
  }
  for (const auto& e : entries) {
    const std::string key = "entries." + e.name;
    if (e.size != 1 && e.size != 2 && e.size != 4) {
      errors.push_back(key + ".size: " + std::to_string(e.size) + " is not 1, 2 or 4");
      continue;
    }
    if (e.address + e.size > 1024)
      errors.push_back(key + ".address: " + std::to_string(e.address) + " is beyond the table (1024 bytes)");
    if (!(e.scale > 0.0) || !std::isfinite(e.scale)) {
      std::ostringstream s;
      s << e.scale;
      errors.push_back(key + ".scale: " + s.str() + " is not a positive number");
    }
    const std::int64_t lo = e.is_signed ? -(std::int64_t{1} << (8 * e.size - 1)) : 0;
    const std::int64_t hi =
        e.is_signed ? (std::int64_t{1} << (8 * e.size - 1)) - 1 : (std::int64_t{1} << (8 * e.size)) - 1;
    if (e.default_value < lo || e.default_value > hi) {
      errors.push_back(key + ".default: " + std::to_string(e.default_value) + " does not fit " +
                       std::to_string(e.size) + (e.is_signed ? " signed" : " unsigned") + " byte(s)");
    }
    if (e.has_range) {
      if (!e.writable) errors.push_back(key + ": min/max given for a read-only entry");
      if (e.min > e.max) errors.push_back(key + ": min " + std::to_string(e.min) + " > max " + std::to_string(e.max));
      if (e.min < lo || e.max > hi)
        errors.push_back(key + ": range " + std::to_string(e.min) + ".." + std::to_string(e.max) +
                         " does not fit its size");
    }
  }
  // No two entries may overlap.
  std::vector<const ControlTableEntry*> sorted;
  for (const auto& e : entries) sorted.push_back(&e);
  std::sort(sorted.begin(), sorted.end(), [](auto* a, auto* b) { return a->address < b->address; });
  for (std::size_t i = 1; i < sorted.size(); ++i) {
    if (sorted[i - 1]->address + sorted[i - 1]->size > sorted[i]->address) {
      errors.push_back("entries." + sorted[i]->name + ".address: " + std::to_string(sorted[i]->address) +
                       " overlaps entries." + sorted[i - 1]->name + " (" + std::to_string(sorted[i - 1]->address) +
                       ", " + std::to_string(sorted[i - 1]->size) + " bytes)");
    }
  }
  for (std::size_t i = 0; i < kNumRequiredEntries; ++i) {
    if (!find(kRequiredEntries[i]))
      errors.push_back(std::string("entries.") + kRequiredEntries[i] + ": missing (the driver needs it)");
  }
  // The 100 Hz loop reads current, velocity and position in one 10-byte block.
  const auto* cur = find("present_current");
  const auto* vel = find("present_velocity");
  const auto* pos = find("present_position");
  if (cur && vel && pos) {
    if (cur->address != kFeedbackAddress || cur->size != 2 || vel->address != kFeedbackAddress + 2 || vel->size != 4 ||
        pos->address != kFeedbackAddress + 6 || pos->size != 4) {
      errors.push_back("entries.present_current/velocity/position: at " + std::to_string(cur->address) + "/" +
                       std::to_string(vel->address) + "/" + std::to_string(pos->address) +
                       ", not the contiguous 10-byte block 126/128/132 (2+4+4 bytes) the driver reads");
    }
    if (cur->unit != "mA") errors.push_back("entries.present_current.unit: '" + cur->unit + "' is not mA");
    if (vel->unit != "rpm") errors.push_back("entries.present_velocity.unit: '" + vel->unit + "' is not rpm");
    if (pos->unit != "deg") errors.push_back("entries.present_position.unit: '" + pos->unit + "' is not deg");
  }
  const auto* goal = find("goal_position");
  if (goal && (goal->address != kGoalPositionAddress || goal->size != kGoalPositionBytes)) {
    errors.push_back("entries.goal_position: at " + std::to_string(goal->address) + " with " +
                     std::to_string(goal->size) + " bytes, not 116 with 4 bytes");
  }
  return errors;
}

void ControlTable::validate_or_throw() const {
  const auto errors = validate();
  if (errors.empty()) return;
  std::string what = "control table '" + model + "' is invalid:";
  for (const auto& e : errors) what += "\n  " + e;
  throw ConfigError(what);
}

UnitScales ControlTable::unit_scales() const {
  UnitScales s;
  s.centre_ticks = position_centre_ticks;
  if (const auto* e = find("present_position")) s.rad_per_tick = e->scale * M_PI / 180.0;
  if (const auto* e = find("present_velocity")) s.rad_s_per_velocity_unit = e->scale * 2.0 * M_PI / 60.0;
  if (const auto* e = find("present_current")) s.amps_per_current_unit = e->scale * 1e-3;
  if (const auto* e = find("present_input_voltage")) s.volts_per_voltage_unit = e->scale;
  return s;
}

std::string ControlTable::describe_hardware_error(std::uint8_t bits) const {
  if (bits == 0) return "none";
  std::string out;
  for (int bit = 0; bit < 8; ++bit) {
    if (!(bits & (1u << bit))) continue;
    std::string name = "bit " + std::to_string(bit);
    for (const auto& [n, b] : hardware_error_bits) {
      if (b == bit) name = n;
    }
    out += (out.empty() ? "" : ", ") + name;
  }
  return out;
}

ControlTable ControlTable::from_yaml_file(const std::string& path) {
  return from_yaml_string(core::read_config_file(path, "control table"), path);
}

ControlTable ControlTable::from_yaml_string(const std::string& text, const std::string& source) {
  const YAML::Node root = core::load_config_yaml(text, source);
  std::vector<std::string> errors;
  core::ConfigReader r(&errors);
  ControlTable t;
  r.scalar(r.child(root, "model", "model"), "model", &t.model);
  r.scalar(r.child(root, "model_number", "model_number"), "model_number", &t.model_number);
  if (root["position_centre_ticks"])
    r.scalar(root["position_centre_ticks"], "position_centre_ticks", &t.position_centre_ticks);
  if (root["torque_constant_nm_per_a"]) {
    r.scalar(root["torque_constant_nm_per_a"], "torque_constant_nm_per_a", &t.torque_constant_nm_per_a);
  }
  if (const auto bits = root["hardware_error_bits"]) {
    if (!bits.IsMap()) {
      errors.push_back("hardware_error_bits: expected a mapping name: bit, got '" + core::ConfigReader::dump(bits) +
                       "'");
    } else {
      for (const auto& kv : bits) {
        const std::string name = kv.first.as<std::string>();
        int bit = 0;
        if (r.scalar(kv.second, "hardware_error_bits." + name, &bit)) t.hardware_error_bits.emplace_back(name, bit);
      }
    }
  }
  const auto entries = root["entries"];
  if (!entries || !entries.IsMap()) {
    errors.push_back("entries: missing or not a mapping");
  } else {
    for (const auto& kv : entries) {
      ControlTableEntry e;
      e.name = kv.first.as<std::string>();
      const std::string key = "entries." + e.name;
      const YAML::Node n = kv.second;
      if (!n.IsMap()) {
        errors.push_back(key + ": expected a mapping, got '" + core::ConfigReader::dump(n) + "'");
        continue;
      }
      for (const auto& field : n) {
        const std::string f = field.first.as<std::string>();
        if (std::find_if(std::begin(kEntryKeys), std::end(kEntryKeys), [&](const char* k) { return f == k; }) ==
            std::end(kEntryKeys)) {
          errors.push_back(key + "." + f + ": unknown key");
        }
      }
      int address = -1, size = 0;
      r.scalar(r.child(n, "address", key + ".address"), key + ".address", &address);
      r.scalar(r.child(n, "size", key + ".size"), key + ".size", &size);
      if (address < 0 || address > 0xFFFF) {
        if (n["address"])
          errors.push_back(key + ".address: " + core::ConfigReader::dump(n["address"]) + " is not in 0..65535");
      } else {
        e.address = static_cast<std::uint16_t>(address);
      }
      e.size = static_cast<std::uint8_t>(size < 0 || size > 255 ? 0 : size);
      std::string access = "r";
      if (n["access"]) r.scalar(n["access"], key + ".access", &access);
      if (access == "rw") e.writable = true;
      else if (access != "r") errors.push_back(key + ".access: '" + access + "' is not r or rw");
      if (n["signed"]) r.scalar(n["signed"], key + ".signed", &e.is_signed);
      if (n["eeprom"]) r.scalar(n["eeprom"], key + ".eeprom", &e.eeprom);
      if (n["unit"]) r.scalar(n["unit"], key + ".unit", &e.unit);
      if (n["scale"]) r.scalar(n["scale"], key + ".scale", &e.scale);
      if (n["default"]) r.scalar(n["default"], key + ".default", &e.default_value);
      if (n["min"] || n["max"]) {
        if (!n["min"] || !n["max"]) errors.push_back(key + ": min and max go together");
        else e.has_range = r.scalar(n["min"], key + ".min", &e.min) & r.scalar(n["max"], key + ".max", &e.max);
      }
      t.entries.push_back(std::move(e));
    }
  }
  for (const auto& e : t.validate()) {
    if (std::find(errors.begin(), errors.end(), e) == errors.end()) errors.push_back(e);
  }
  core::throw_if_errors(errors, source, "control table");
  return t;
}

}  // namespace snake_autonomy::dynamixel
