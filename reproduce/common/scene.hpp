#pragma once
/// Rod-with-contact scenes of reproduce/scenes/*.toml (toml++). Units: SI.
/// Keys (all required unless marked):
///   title (string, optional)
///   [structure] young_modulus [Pa] > 0, density [kg/m³] > 0, area [m²] > 0, length [m] > 0,
///               elements (integer ≥ 1)
///   [damping]   beta [s] ≥ 0                        (C = βK)
///   [forcing]   amplitude [N], frequency_hz [Hz] > 0 (F cos 2πft at the free tip)
///   [contact]   (optional table) law = "exponential" (coefficient a_c [N] > 0, exponent α [1/m] > 0,
///               gap g0 [m]) or "linear" (stiffness [N/m] > 0, gap [m]); at the tip.
/// Unknown keys, wrong types and missing keys are errors. Issue #5 generalizes this loader
/// (explicit matrices, [basis], [solver], [analysis]) and moves it behind the `wbm` command.

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <wbm/contact/penalty.hpp>
#include <wbm/fem/rod.hpp>
#include <wbm/solvers/mechanical_system.hpp>

namespace wbm::reproduce {

struct ContactSpec {
  std::string law;          // "exponential" or "linear"
  double coefficient = 0;   // a_c [N] (exponential)
  double exponent = 0;      // α [1/m] (exponential)
  double stiffness = 0;     // k_pen [N/m] (linear)
  double gap = 0;           // g0 [m]
};

struct RodScene {
  std::string name;    // file stem, e.g. "jl14_case1"
  std::string path;    // file it was read from
  std::string title;
  fem::RodParameters rod{};
  double beta = 0;              // [s]
  double force_amplitude = 0;   // F [N]
  double frequency_hz = 0;      // f [Hz]
  std::optional<ContactSpec> contact;

  [[nodiscard]] fem::Rod make_rod() const { return fem::Rod(rod); }
  [[nodiscard]] solvers::MechanicalSystem system() const;
  [[nodiscard]] solvers::HarmonicForcing forcing() const;  // at the tip DOF
  [[nodiscard]] std::vector<solvers::ContactPoint> contacts() const;  // empty without [contact]
  [[nodiscard]] std::shared_ptr<const contact::ContactLaw> contact_law() const;  // null without
};

/// Directory of the scenes shipped with the sources (compile-time WBM_SCENE_DIR).
[[nodiscard]] std::filesystem::path scene_directory();

/// Loads `name` (a stem looked up in scene_directory(), or a path to a .toml file).
/// Throws std::invalid_argument listing every problem, each as "file:line: key: what was
/// expected", or std::runtime_error if the file cannot be read.
[[nodiscard]] RodScene load_scene(const std::string& name);

}  // namespace wbm::reproduce
