// nnm scenes with analysis.stability (issue #38, item 4): the columns of backbone.csv, the default,
// and the refusal for penalty stops. The verdicts themselves are tested against the exact flow in
// tests/solvers/test_impact_modes.cpp.
#include <cmath>
#include <filesystem>
#include <numbers>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include <wbm/scene/analysis.hpp>
#include <wbm/scene/scene.hpp>

#include "scene_fixtures.hpp"
#include "testing.hpp"

namespace {

const wbm::scene::Table& table_named(const wbm::scene::AnalysisResult& r, const std::string& file) {
  for (const auto& t : r.tables) {
    if (t.file == file) return t;
  }
  throw std::out_of_range("no table " + file);
}

const Eigen::VectorXd& column_named(const wbm::scene::Table& t, const std::string& name) {
  for (size_t i = 0; i < t.header.size(); ++i) {
    if (t.header[i] == name) return t.columns[i];
  }
  throw std::out_of_range("no column " + name + " in " + t.file);
}

const std::string kChain = R"(
[structure]
dofs = ["a", "b"]
mass = [1.0, 1.0]
stiffness = [[2000.0, -1000.0], [-1000.0, 1000.0]]
[contact]
law = "rigid"
gap = 1e-3
dof = "b"
[analysis]
type = "nnm"
energy = [0.5, 1.5]
harmonics = 8
samples = 64
)";

}  // namespace

// examples/scenes/two_dof_nnm.toml asks for the levels' stability. Below contact onset every level
// is the linear first mode, an exact orbit without impacts: stable, its exact frequency the linear
// one in closed form, √((3 − √5)/2 · k/m)/2π for the chain wall–k–a–k–b, and at zero distance.
// Every level has a status; a level without a verdict has empty cells.
TEST(SceneNnmStability, BackboneCsvCarriesEachLevelsVerdict) {
  const auto s = wbm::scene::load_scene(std::filesystem::path(WBM_EXAMPLES) / "two_dof_nnm.toml");
  ASSERT_TRUE(s.analysis.stability);
  const auto r = wbm::scene::run_analysis(s);
  ASSERT_TRUE(r.converged());
  const auto& t = table_named(r, "backbone.csv");
  const Eigen::VectorXd& energy = column_named(t, "energy [-]");
  const Eigen::VectorXd& stable = column_named(t, "stable [-]");
  const Eigen::VectorXd& mu = column_named(t, "max_multiplier [-]");
  const Eigen::VectorXd& exact = column_named(t, "exact_frequency [Hz]");
  const Eigen::VectorXd& impacts = column_named(t, "impacts [-]");
  ASSERT_EQ(t.status.size(), static_cast<size_t>(energy.size()));
  const double linear = std::sqrt((3.0 - std::sqrt(5.0)) / 2.0 * 1000.0) / (2.0 * std::numbers::pi);
  int below = 0, verdicts = 0;
  for (Eigen::Index i = 0; i < energy.size(); ++i) {
    const std::string& status = t.status[static_cast<size_t>(i)];
    if (std::isnan(stable(i))) {
      EXPECT_EQ(status.rfind("no verdict: ", 0), 0U) << status;
      EXPECT_TRUE(std::isnan(mu(i)));
      continue;
    }
    ++verdicts;
    EXPECT_EQ(status, stable(i) == 1.0 ? "stable" : "unstable");
    if (energy(i) < 0.99 && impacts(i) == 0.0) {
      ++below;
      EXPECT_EQ(stable(i), 1.0) << energy(i);
      EXPECT_NEAR(mu(i), 1.0, 1e-8) << energy(i);
      EXPECT_NEAR(exact(i), linear, 1e-9 * linear) << energy(i);
    }
  }
  EXPECT_GT(below, 5);
  const auto& d = r.diagnostics["nnm_stability"];
  EXPECT_EQ(d["stable"].get<int>() + d["unstable"].get<int>(), verdicts);
  EXPECT_EQ(d["stable"].get<int>() + d["unstable"].get<int>() + d["no_verdict"].get<int>(), energy.size());
}

// Off by default for nnm (a shooting per level), and refused for penalty stops with the key, the
// law and a way out.
TEST(SceneNnmStability, DefaultOffAndRefusedForPenaltyStops) {
  const auto plain = wbm::scene::parse_scene(kChain, "chain.toml");
  EXPECT_FALSE(plain.analysis.stability);
  const auto r = wbm::scene::run_analysis(plain);
  const auto& t = table_named(r, "backbone.csv");
  for (const auto& h : t.header) EXPECT_NE(h, "stable [-]");
  EXPECT_TRUE(t.status.empty());
  std::string penalty = kChain + "stability = true\n";
  penalty.replace(penalty.find("law = \"rigid\""), 13, "law = \"linear\"\nstiffness = 1e6");
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::scene::parse_scene(penalty, "chain.toml"); },
      {"contact.law", "\"linear\" with analysis.stability = true", "law = \"rigid\""});
}
