// The declared scene sections (scene/src/declared_keys.hpp): docs/scenes.md's key tables are the
// declarations the parser reads, and every declared key is read, ranged and echoed.
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

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
// table to paste between the markers. Every section of the scene is declared.
TEST(SceneKeys, DocsTablesAreGeneratedFromTheDeclarations) {
  for (const std::string& section : wbm::scene::declared_sections()) {
    const std::string generated = wbm::scene::key_table_markdown(section);
    EXPECT_EQ(documented_table(section), generated) << "docs/scenes.md, [" << section << "]: paste\n" << generated;
  }
  wbm::testing::expect_throw_with<std::invalid_argument>([] { (void)wbm::scene::key_table_markdown("outputs"); },
                                                         {"section = \"outputs\"", "\"solver\"", "\"forcing.loads\""});
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

namespace {

constexpr const char* kRod =
    "[structure]\nyoung_modulus = 70e9\ndensity = 2700.0\narea = 25e-4\nlength = 1.0\nelements = 4\n";

void expect_refused(const std::string& text, const std::vector<std::string>& fragments) {
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)wbm::scene::parse_scene(text, "keys.toml"); },
                                                         fragments);
}

}  // namespace

// A section's known keys depend on its variant (issue #41, item 3): the contact law, the structure
// kind, the analysis type. Each error lists what that variant reads, as docs/scenes.md says, and
// nothing of another variant.
TEST(SceneKeys, EachVariantReadsItsOwnKeys) {
  const std::string forcing = "[forcing]\namplitude = 1.0\nfrequency_hz = 100.0\n";
  expect_refused(
      std::string(kRod) + forcing + "[contact]\nlaw = \"linear\"\ngap = 1e-3\nstiffness = 1e6\ncoefficient = 1.0\n",
      {"contact.coefficient: unknown key; allowed here: law, gap, stiffness, counter_surface, node, dof, nodes, "
       "against, direction"});
  expect_refused(std::string(kRod) + forcing + "[contact]\nlaw = \"rigid\"\ngap = 1e-3\nstiffness = 1e6\n",
                 {"contact.stiffness: unknown key; allowed here: law, gap, counter_surface, node, dof, nodes, against, "
                  "direction"});
  expect_refused(std::string(kRod) + "type = \"rod\"\nmass = 1.0\n" + forcing,
                 {"structure.mass: unknown key; allowed here: type, young_modulus, density, area, length, elements"});
  expect_refused(std::string(kRod) + forcing + "[analysis]\ntype = \"solve\"\nmax_points = 10\nlevels = [1.0]\n",
                 {"analysis.max_points: only used by type = \"continuation\" or \"nnm\"; remove it",
                  "analysis.levels: only used by type = \"nnm\"; remove it"});
}

// The newly declared sections read, range and echo through their declarations: [damping],
// [structure] (rod), [[forcing.loads]], [[contact]] by law, [basis], [output], [analysis] with
// the nnm default of max_step (0.05) that is not Analysis{}'s (0.02).
TEST(SceneKeys, DeclaredSectionsAreReadRangedAndEchoed) {
  const std::string base = std::string(kRod) +
                           "[forcing]\namplitude = 1.0\nfrequency_hz = 100.0\n"
                           "[[forcing.loads]]\namplitude = 2.0\nnode = 2\nphase_deg = 90.0\nharmonic = 3\n"
                           "[damping]\nalpha = 0.5\nbeta = 1e-6\n"
                           "[contact]\nlaw = \"exponential\"\ngap = 1e-3\ncoefficient = 2.0\nexponent = 3e3\n"
                           "[basis]\ntrial = \"fourier\"\nharmonics = 8\nformulation = \"weak\"\ntime_samples = 64\n"
                           "operators = \"discrete\"\n"
                           "[output]\nsamples = 64\nharmonics = 4\n";
  const auto s = wbm::scene::parse_scene(base, "keys.toml");
  EXPECT_EQ(s.structure->rod.elements, 4);
  EXPECT_EQ(s.damping.alpha, 0.5);
  EXPECT_EQ(s.damping.beta, 1e-6);
  ASSERT_EQ(s.forcing->loads.size(), 1u);
  EXPECT_EQ(s.forcing->loads[0].amplitude, 2.0);
  EXPECT_EQ(s.forcing->loads[0].harmonic, 3);
  EXPECT_NEAR(s.forcing->loads[0].phase_rad, std::acos(0.0), 1e-15);
  EXPECT_EQ(s.contacts.front().coefficient, 2.0);
  EXPECT_EQ(s.contacts.front().exponent, 3e3);
  EXPECT_EQ(s.basis.formulation, wbm::solvers::Formulation::Weak);
  EXPECT_EQ(s.basis.time_samples, 64);
  EXPECT_EQ(s.basis.operators, wbm::solvers::OperatorRule::Discrete);
  EXPECT_EQ(s.output.samples, 64);
  const auto j = wbm::scene::to_json(s);
  EXPECT_EQ(j["damping"]["alpha"].get<double>(), 0.5);
  EXPECT_EQ(j["structure"]["type"].get<std::string>(), "rod");
  EXPECT_EQ(j["structure"]["elements"].get<int>(), 4);
  EXPECT_EQ(j["output"]["harmonics"].get<int>(), 4);
  EXPECT_EQ(j["output"]["samples"].get<int>(), 64);
  EXPECT_EQ(j["analysis"]["type"].get<std::string>(), "solve");
  EXPECT_FALSE(j["analysis"].contains("max_step"));
  // Read back from its echo, the scene is the same.
  const auto again = wbm::scene::scene_from_json(j, "keys.json");
  EXPECT_EQ(wbm::scene::to_json(again), j);
  const std::string bad = std::string(kRod) +
                          "[forcing]\namplitude = 1.0\nfrequency_hz = 100.0\n"
                          "[[forcing.loads]]\namplitude = 2.0\nharmonic = 1001\n"
                          "[damping]\nalpha = -1.0\n"
                          "[contact]\nlaw = \"linear\"\ngap = 1e-3\nstiffness = 0.0\n";
  expect_refused(bad, {"damping.alpha: value -1 out of range: expected >= 0 [1/s]",
                       "forcing.loads[0].harmonic: value 1001 out of range: expected an integer in [0, 1000] (0: a "
                       "constant load",
                       "contact.stiffness: value 0 out of range: expected > 0 [N/m]"});
  expect_refused(std::string(kRod).replace(std::string(kRod).find("elements = 4"), 12, "elements = 0") +
                     "[forcing]\namplitude = 1.0\nfrequency_hz = 100.0\n",
                 {"structure.elements: value 0 out of range: expected an integer in [1, 100000]"});
  const std::string nnm = std::string(kRod) + "[contact]\nlaw = \"rigid\"\ngap = 1e-3\n"
                          "[analysis]\ntype = \"nnm\"\nenergy = [0.5, 2.0]\n";
  EXPECT_EQ(wbm::scene::parse_scene(nnm, "keys.toml").analysis.max_step, 0.05);
  EXPECT_EQ(wbm::scene::to_json(wbm::scene::parse_scene(nnm, "keys.toml"))["analysis"]["max_step"].get<double>(), 0.05);
}
