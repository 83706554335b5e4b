// Helpers shared by the scene tests (test_scene*.cpp, test_output.cpp): a scratch folder of this
// process removed at exit, scenes given inline, the 1-DOF oscillator's closed form, a column of a
// result table.
#pragma once

#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>

#include "scratch.hpp"

#include <Eigen/Core>

#include <wbm/scene/analysis.hpp>
#include <wbm/scene/scene.hpp>

namespace wbm::testing {

// Files of this process's tests, in one folder removed at exit.
inline std::filesystem::path temp(const std::string& name) {
  static const ScratchDir scratch("scene");
  return scratch.path() / name;
}

inline std::filesystem::path write(const std::string& name, const std::string& text) {
  const auto path = temp(name);
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path) << text;
  return path;
}

inline wbm::scene::Scene parse(const std::string& text) { return wbm::scene::parse_scene(text, temp("inline.toml")); }

// The text of a file (an example scene to edit before parsing).
inline std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Linear 1-DOF oscillator m ü + c u̇ + k u = F cos ωt: steady amplitude F / |k − mω² + iωc|.
inline double oscillator_amplitude(double m, double c, double k, double f, double hz) {
  const double w = 2.0 * std::numbers::pi * hz;
  return f / std::abs(std::complex<double>(k - m * w * w, w * c));
}

inline const Eigen::VectorXd& column(const wbm::scene::AnalysisResult& r, const std::string& file, size_t c) {
  for (const auto& t : r.tables) {
    if (t.file == file) return t.columns.at(c);
  }
  throw std::out_of_range("no table " + file);
}

}  // namespace wbm::testing
