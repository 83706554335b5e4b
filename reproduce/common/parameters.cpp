// reproduce/scenes/<name>.toml parameter files (parameters.hpp): toml++ into JSON, [quick] merged.
#include "parameters.hpp"

#include <sstream>
#include <stdexcept>

#include <toml++/toml.h>

#include "shipped_scenes.hpp"

namespace wbm::reproduce {
namespace {

nlohmann::json to_json(const toml::node& n) {
  if (const auto* t = n.as_table()) {
    nlohmann::json j = nlohmann::json::object();
    for (const auto& [k, v] : *t) j[std::string(k.str())] = to_json(v);
    return j;
  }
  if (const auto* a = n.as_array()) {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& v : *a) j.push_back(to_json(v));
    return j;
  }
  if (n.is_integer()) return n.value<long long>().value_or(0);
  if (n.is_floating_point()) return n.value<double>().value_or(0.0);
  if (n.is_boolean()) return n.value<bool>().value_or(false);
  return n.value<std::string>().value_or("");
}

// Every leaf of `quick` replaces the same dotted key of `values`.
void merge(nlohmann::json& values, const nlohmann::json& quick) {
  for (const auto& [k, v] : quick.items()) {
    if (v.is_object() && values.contains(k) && values[k].is_object()) {
      merge(values[k], v);
    } else {
      values[k] = v;
    }
  }
}

}  // namespace

Parameters Parameters::load(const std::string& name, bool quick) {
  const std::string file = models::scene_path(name).string();
  toml::table root;
  try {
    root = toml::parse_file(file);
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << file << ":" << e.source().begin.line << ": " << e.description();
    throw std::runtime_error(os.str());
  }
  nlohmann::json values = to_json(root);
  nlohmann::json quick_values = values.contains("quick") ? values["quick"] : nlohmann::json::object();
  values.erase("quick");
  if (quick) merge(values, quick_values);
  return {file, std::move(values)};
}

const nlohmann::json* Parameters::find(const std::string& key) const {
  const nlohmann::json* j = &values_;
  std::istringstream parts(key);
  for (std::string part; std::getline(parts, part, '.');) {
    if (!j->is_object() || !j->contains(part)) return nullptr;
    j = &(*j)[part];
  }
  return j;
}

const nlohmann::json& Parameters::at(const std::string& key, const char* expected) const {
  const nlohmann::json* j = find(key);
  if (j == nullptr) throw std::invalid_argument(file_ + ": " + key + ": missing; expected " + expected);
  return *j;
}

double Parameters::number(const std::string& key) const {
  const nlohmann::json& j = at(key, "a number");
  if (!j.is_number()) throw std::invalid_argument(file_ + ": " + key + ": expected a number, got " + j.dump());
  used_[key] = j;
  return j.get<double>();
}

double Parameters::number_or(const std::string& key, double fallback) const {
  if (find(key) != nullptr) return number(key);
  used_[key] = fallback;
  return fallback;
}

int Parameters::integer(const std::string& key) const {
  const nlohmann::json& j = at(key, "an integer");
  if (!j.is_number_integer()) throw std::invalid_argument(file_ + ": " + key + ": expected an integer, got " + j.dump());
  used_[key] = j;
  return j.get<int>();
}

bool Parameters::boolean(const std::string& key) const {
  const nlohmann::json& j = at(key, "a boolean");
  if (!j.is_boolean()) {
    throw std::invalid_argument(file_ + ": " + key + ": expected true or false, got " + j.dump());
  }
  used_[key] = j;
  return j.get<bool>();
}

std::vector<double> Parameters::numbers(const std::string& key) const {
  const nlohmann::json& j = at(key, "a list of numbers");
  std::vector<double> out;
  if (!j.is_array()) throw std::invalid_argument(file_ + ": " + key + ": expected a list of numbers, got " + j.dump());
  for (const auto& e : j) {
    if (!e.is_number()) throw std::invalid_argument(file_ + ": " + key + ": expected a list of numbers, got " + j.dump());
    out.push_back(e.get<double>());
  }
  used_[key] = j;
  return out;
}

}  // namespace wbm::reproduce
