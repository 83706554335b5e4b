// The declared scene sections (scene/src/scalar_keys.hpp): docs/scenes.md's key tables are the
// declarations the parser reads, and every declared key is read, ranged and echoed.
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include <wbm/scene/scene.hpp>

#include "testing.hpp"

namespace {

// The text between "<!-- keys: SECTION -->\n" and "<!-- /keys -->" in docs/scenes.md.
std::string documented_table(const std::string& section) {
  std::ifstream in(WBM_SCENES_DOC);
  std::stringstream text;
  text << in.rdbuf();
  const std::string doc = text.str();
  const std::string open = "<!-- keys: " + section + " -->\n";
  const auto begin = doc.find(open);
  if (begin == std::string::npos) return "(no marker " + open + " in " + WBM_SCENES_DOC + ")";
  const auto end = doc.find("<!-- /keys -->", begin);
  return doc.substr(begin + open.size(), end - begin - open.size());
}

}  // namespace

// A table edited by hand, or a key declared without its row, fails here; the message is the
// table to paste between the markers.
TEST(SceneKeys, DocsTablesAreGeneratedFromTheDeclarations) {
  for (const char* section : {"solver", "timestep", "timestep.rigid"}) {
    const std::string generated = wbm::scene::key_table_markdown(section);
    EXPECT_EQ(documented_table(section), generated) << "docs/scenes.md, [" << section << "]: paste\n" << generated;
  }
  wbm::testing::expect_throw_with<std::invalid_argument>([] { (void)wbm::scene::key_table_markdown("output"); },
                                                         {"section = \"output\"", "\"solver\""});
}

// Every [solver] key read from the file, echoed in to_json, and refused out of range with the
// key, the value and the range.
TEST(SceneKeys, SolverKeysAreReadEchoedAndRanged) {
  const std::string head = R"(
structure = { mass = 1.0, stiffness = 4e4 }
forcing = { amplitude = 5.0, frequency_hz = 20.0 }
basis = { trial = "fourier", dimension = 32 }
)";
  const auto s = wbm::scene::parse_scene(head + R"(
[solver]
tolerance = 1e-9
max_iterations = 7
line_search = false
linear_solver = "sparse-lu"
residual_tolerance = 1e-6
)", "keys.toml");
  EXPECT_EQ(s.solver.newton.tolerance, 1e-9);
  EXPECT_EQ(s.solver.newton.max_iterations, 7);
  EXPECT_FALSE(s.solver.newton.line_search);
  EXPECT_EQ(s.solver.linear_solver, wbm::solvers::LinearSolverPath::SparseLU);
  EXPECT_EQ(s.solver.residual_tolerance, 1e-6);
  const auto echo = wbm::scene::to_json(s)["solver"];
  EXPECT_EQ(echo["tolerance"].get<double>(), 1e-9);
  EXPECT_EQ(echo["max_iterations"].get<int>(), 7);
  EXPECT_FALSE(echo["line_search"].get<bool>());
  EXPECT_EQ(echo["linear_solver"].get<std::string>(), "sparse-lu");
  EXPECT_EQ(echo["residual_tolerance"].get<double>(), 1e-6);
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::scene::parse_scene(head + "[solver]\ntolerance = -1.0\nmax_iterations = 100001\n", "keys.toml"); },
      {"solver.tolerance: value -1 out of range: expected > 0",
       "solver.max_iterations: value 100001 out of range: expected an integer in [0, 100000]"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::scene::parse_scene(head + "[solver]\nlinear_solver = \"dense\"\ntolerence = 1e-9\n", "keys.toml"); },
      {"solver.linear_solver: \"dense\" is not one of \"automatic\", \"sparse-lu\", \"modal\"",
       "solver.tolerence: unknown key; allowed here: tolerance, max_iterations, line_search, linear_solver, "
       "residual_tolerance"});
}
