#pragma once
/// The model and run parameters of a reproduction that is not a wbm scene (the LL11 blade: a mesh
/// made by gmsh, a deck assembled by CalculiX, a Craig–Bampton model built in the run), read from
/// reproduce/scenes/<name>.toml beside the scenes, so that every number of a run comes from a file
/// under reproduce/scenes/ (issue #41, item 4). Units are SI unless the key names another.
///
/// File: tables of numbers, integers, booleans and lists of numbers, read by dotted keys ("mesh.size_m").
/// A table [quick] holds the values of --quick (ctest's small run) by the same dotted keys
/// ([quick.mesh] size_m = 0.005); a key it does not hold keeps its full value.
///
/// Errors: load() throws std::runtime_error when the file is missing or is not TOML (naming the
/// path and, for TOML, the line); a getter throws std::invalid_argument naming the file and the key
/// when the key is missing or of another type. Reproduce::Run::execute reports either as the run's
/// failure.

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace wbm::reproduce {

class Parameters {
 public:
  /// reproduce/scenes/<name>.toml (models::scene_path), with its [quick] values if `quick`.
  [[nodiscard]] static Parameters load(const std::string& name, bool quick);

  /// A number (an integer is accepted).
  [[nodiscard]] double number(const std::string& key) const;
  /// A number if the file (or its [quick] table) holds `key`, else `fallback` (a value derived from
  /// others, e.g. the linear peak's energy); the value used is recorded either way.
  [[nodiscard]] double number_or(const std::string& key, double fallback) const;
  /// An integer.
  [[nodiscard]] int integer(const std::string& key) const;
  /// A boolean (true or false; a number is refused).
  [[nodiscard]] bool boolean(const std::string& key) const;
  /// A list of numbers.
  [[nodiscard]] std::vector<double> numbers(const std::string& key) const;
  /// Every value read so far, by dotted key, as used (the [quick] one under --quick): for meta.json.
  [[nodiscard]] const nlohmann::json& used() const { return used_; }
  [[nodiscard]] const std::string& file() const { return file_; }

 private:
  Parameters(std::string file, nlohmann::json values) : file_(std::move(file)), values_(std::move(values)) {}
  [[nodiscard]] const nlohmann::json* find(const std::string& key) const;  // nullptr if absent
  [[nodiscard]] const nlohmann::json& at(const std::string& key, const char* expected) const;
  std::string file_;
  nlohmann::json values_;          // the file's values, [quick] merged in when quick
  mutable nlohmann::json used_ = nlohmann::json::object();
};

}  // namespace wbm::reproduce
