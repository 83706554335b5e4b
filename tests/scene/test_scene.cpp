// Scene files (wbm::scene): the shipped scenes hold Table 1 of [JL14]; resolved JSON round
// trips; every class of bad input is reported with file, line, key and what was expected.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <complex>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <regex>
#include <stdexcept>

#include <gtest/gtest.h>
#include <unistd.h>

#include <wbm/scene/analysis.hpp>
#include <wbm/scene/output.hpp>
#include <wbm/scene/scene.hpp>
#include <wbm/solvers/post_processing.hpp>

#include "shipped_scenes.hpp"  // models/: the shipped scene directory
#include "testing.hpp"
#include "scene_fixtures.hpp"

using wbm::scene::Scene;
using namespace wbm::testing;  // scene_fixtures.hpp, testing.hpp

// Table 1 of [JL14]: Case 1 150 Hz, a_c = 1e8 N, α = 50 1/m, β = 1e-4 s, g0 = 1 mm;
// Case 2 1275 Hz, α = 20, β = 5e-6, g0 = 14.5 mm; rod of Sec. 4.
TEST(Scene, ShippedCasesHoldTable1) {
  const Scene s1 = wbm::models::load_scene("jl14_case1");
  const Scene s2 = wbm::models::load_scene("jl14_case2");
  EXPECT_EQ(s1.forcing->frequency_hz, 150.0);
  EXPECT_EQ(s2.forcing->frequency_hz, 1275.0);
  ASSERT_EQ(s1.contacts.size(), 1u);
  ASSERT_EQ(s2.contacts.size(), 1u);
  EXPECT_EQ(s1.contacts[0].exponent, 50.0);
  EXPECT_EQ(s2.contacts[0].exponent, 20.0);
  EXPECT_EQ(s1.contacts[0].coefficient, 1e8);
  EXPECT_EQ(s1.damping.beta, 1e-4);
  EXPECT_EQ(s2.damping.beta, 5e-6);
  EXPECT_EQ(s1.contacts[0].gap, 1e-3);
  EXPECT_EQ(s2.contacts[0].gap, 14.5e-3);
  EXPECT_EQ(s1.structure->rod.young_modulus, 70e9);
  EXPECT_EQ(s1.structure->rod.area, 25e-4);
  EXPECT_EQ(s1.forcing->amplitude, 250e3);
  EXPECT_EQ(s1.forcing->dof, 24);  // the free tip of 25 elements
  EXPECT_EQ(s1.contacts[0].dof, 24);
}

// Scene → resolved JSON → scene is the identity (JSON of the re-read scene equal, and the same
// system matrices), for the rod, inline matrices, a Matrix Market file and a basis plot.
TEST(Scene, ResolvedJsonRoundTrips) {
  const auto market = write("chain.mtx",
                            "%%MatrixMarket matrix coordinate real symmetric\n% 3-DOF spring chain\n3 3 5\n"
                            "1 1 2e4\n2 1 -1e4\n2 2 2e4\n3 2 -1e4\n3 3 1e4\n");
  std::vector<Scene> scenes = {
      wbm::models::load_scene("jl14_case2"),
      parse("structure = { mass = [1.0, 2.0], stiffness = [[3e4, -1e4], [-1e4, 1e4]], dofs = [\"a\", \"b\"] }\n"
            "damping = { alpha = 0.5, beta = 1e-5 }\n"
            "forcing = { amplitude = 2.0, dof = \"b\", frequency_hz = [5.0, 40.0], points = 8 }\n"
            "basis = { trial = \"haar\", weighting = \"B-spline\", level = 5 }\n"
            "solver = { tolerance = 1e-9, max_iterations = 20, linear_solver = \"sparse-lu\" }\n"
            "output = { samples = 64, dofs = \"all\" }\n"
            "[[contact]]\nlaw = \"linear\"\nstiffness = 1e5\ngap = 1e-3\ndof = \"b\"\n"
            "[[contact]]\nlaw = \"exponential\"\ncoefficient = 10.0\nexponent = 100.0\ngap = -1e-3\ndof = 0\n"),
      wbm::scene::load_scene(write("market.toml", "[structure]\nmass = [1.0, 1.0, 1.0]\nstiffness = \"chain.mtx\"\n"
                                                  "[forcing]\namplitude = 1.0\ndof = 2\nfrequency_hz = 3.0\n"
                                                  "[analysis]\ntype = \"timestep\"\n"
                                                  "[timestep]\nrelative_tolerance = 1e-8\n")),
      parse("[analysis]\ntype = \"basis-plot\"\nfunctions = [0, 3]\nnormalization = \"unit-integral\"\n"
            "[basis]\ntrial = \"db6\"\ndimension = 8\n")};
  for (const auto& s : scenes) {
    const nlohmann::json j = wbm::scene::to_json(s);
    const Scene back = wbm::scene::scene_from_json(j, temp("back.json"));
    EXPECT_EQ(wbm::scene::to_json(back), j) << j.dump(2);
    if (s.structure) {
      const auto a = s.system(), b = back.system();
      EXPECT_EQ(Eigen::MatrixXd(a.mass), Eigen::MatrixXd(b.mass));
      EXPECT_EQ(Eigen::MatrixXd(a.damping), Eigen::MatrixXd(b.damping));
      EXPECT_EQ(Eigen::MatrixXd(a.stiffness), Eigen::MatrixXd(b.stiffness));
      EXPECT_EQ(s.output_dofs(), back.output_dofs());
    }
  }
  // A result.json (scene under "scene") is accepted as it is.
  const Scene again = wbm::scene::scene_from_json({{"scene", wbm::scene::to_json(scenes[0])}, {"converged", true}},
                                                  temp("result.json"));
  EXPECT_EQ(again.forcing->frequency_hz, 1275.0);
}

// The Matrix Market reader mirrors a symmetric file's lower triangle: the same K as inline.
TEST(Scene, MatrixMarketSymmetricEqualsInline) {
  write("chain2.mtx", "%%MatrixMarket matrix coordinate real symmetric\n3 3 5\n1 1 2e4\n2 1 -1e4\n2 2 2e4\n"
                      "3 2 -1e4\n3 3 1e4\n");
  const auto file = wbm::scene::load_scene(write("m2.toml", "[structure]\nmass = [1.0, 1.0, 1.0]\n"
                                                           "stiffness = \"chain2.mtx\"\n"
                                                           "[forcing]\namplitude = 1.0\ndof = 2\nfrequency_hz = 3.0\n"));
  const auto inline_ = parse("[structure]\nmass = [1.0, 1.0, 1.0]\nstiffness = [[2e4, -1e4, 0], [-1e4, 2e4, -1e4], "
                             "[0, -1e4, 1e4]]\n[forcing]\namplitude = 1.0\ndof = 2\nfrequency_hz = 3.0\n");
  EXPECT_EQ(Eigen::MatrixXd(file.system().stiffness), Eigen::MatrixXd(inline_.system().stiffness));
}

// One message per problem, each "file:line: key: what", all in one exception.
TEST(Scene, EveryProblemOfAFileIsReportedWithLineAndKey) {
  const auto path = write("bad.toml",
                          "title = 3\n"                                   // 1
                          "[structure]\n"                                 // 2
                          "young_modulus = -70e9\n"                       // 3
                          "density = \"heavy\"\n"                         // 4
                          "area = 25e-4\n"                                // 5
                          "length = 1.0\n"                                // 6
                          "elemnts = 25\n"                                // 7
                          "[forcing]\n"                                   // 8
                          "amplitude = 250e3\n"                           // 9
                          "frequency_hz = 0.0\n"                          // 10
                          "[contact]\nlaw = \"quadratic\"\ngap = 1e-3\n"  // 11-13
                          "[basis]\ntrial = \"morlet\"\ndimension = 48\n"  // 14-16
                          "[colour]\nred = 1\n");                          // 17
  const std::string p = path.string();
  expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::scene::load_scene(path); },
      {p + ":1: title: expected a string, got an integer",
       p + ":3: structure.young_modulus: value -7e+10 out of range: expected > 0 [Pa]",
       p + ":4: structure.density: expected a number > 0 [kg/m^3], got a string",
       p + ":7: structure.elemnts: unknown key; allowed here:",
       "structure.elements: missing; expected an integer in [1, 100000]",
       p + ":10: forcing.frequency_hz: value 0 out of range: expected > 0 [Hz]",
       p + ":12: contact.law: \"quadratic\" is not one of \"exponential\", \"linear\"",
       p + ":16: basis.dimension: M = 48 is not a power of two",
       p + ":17: colour: unknown key; allowed here: title, analysis, structure,"});
}

// Refusals that need the solvers' knowledge: names, admissibility, locations, matrices.
TEST(Scene, RefusesImpossibleChoicesNamingTheWayOut) {
  const std::string rod = "[structure]\nyoung_modulus = 70e9\ndensity = 2700.0\narea = 25e-4\nlength = 1.0\n"
                          "elements = 10\n";
  const std::string force = "[forcing]\namplitude = 1.0\nfrequency_hz = 100.0\n";
  expect_throw_with<std::invalid_argument>([&] { (void)parse(rod + force + "[basis]\ntrial = \"morlet\"\n"); },
                                           {"inline.toml:11: basis.trial: basis 'morlet' is unknown; valid names: "
                                            "fourier, haar, db4"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(rod + force + "[basis]\ntrial = \"haar\"\nweighting = \"fourier\"\nformulation = \"strong\"\n"); },
      {"inline.toml:13: basis: not admissible: Haar:Fourier, strong form: the trial basis Haar has no pointwise "
       "derivative of order 2", "use the distributional form instead"});
  expect_throw_with<std::invalid_argument>([&] { (void)parse(rod + force + "[basis]\ntrial = \"haar\"\n"); },
                                           {"basis: not admissible: Haar:Haar", "no formulation admits this pair"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(rod + "[forcing]\namplitude = 1.0\nfrequency_hz = 100.0\nnode = 11\n"); },
      {"inline.toml:10: forcing.node: expected a rod node, an integer in [1, 10] (node 0 is clamped) or \"tip\""});
  expect_throw_with<std::invalid_argument>([&] { (void)parse(rod + force + "[contact]\nlaw = \"linear\"\nstiffness = "
                                                                           "1e6\ngap = 0.0\ndof = 3\n"); },
                                           {"contact.dof: the rod is located by node"});
  // Continuation traces a nonlinear branch: without contact `check` refuses it (as `run` would).
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)parse(rod + "[forcing]\namplitude = 1.0\nfrequency_hz = [100.0, 200.0]\n[analysis]\ntype = \"continuation\"\n");
      },
      {"[contact]: missing: analysis \"continuation\"", "use type = \"solve\" with frequency_hz = [from, to]"});
  // Fourier:Fourier takes harmonics = H; one of dimension, level and harmonics; not for wavelets.
  expect_throw_with<std::invalid_argument>([&] { (void)parse(rod + force + "[basis]\ntrial = \"db6\"\nharmonics = 8\n"); },
                                           {"basis.harmonics: H harmonics (2H + 1 functions) is the Fourier:Fourier basis"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(rod + force + "[basis]\ntrial = \"fourier\"\nharmonics = 8\ndimension = 16\n"); },
      {"basis: give one of dimension = M, level = J (M = 2^J) or harmonics = H (M = 2H + 1)"});
  EXPECT_EQ(parse(rod + force + "[basis]\ntrial = \"fourier\"\n").basis.dimension, 2 * wbm::scene::Basis::kDefaultHarmonics + 1);
  EXPECT_EQ(parse(rod + force + "[basis]\ntrial = \"fourier\"\nharmonics = 5\n").basis.dimension, 11);
  // nnm: an energy range and a stop are required; the forced-response laws and solvers are not theirs.
  expect_throw_with<std::invalid_argument>([&] { (void)parse(rod + force + "[analysis]\ntype = \"nnm\"\n"); },
                                           {"analysis.energy: missing; give energy = [from, to]",
                                            "[contact]: missing: analysis \"nnm\" needs at least one stop"});
  const std::string nnm = "[analysis]\ntype = \"nnm\"\nenergy = [0.5, 2.0]\n";
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(rod + "[contact]\nlaw = \"exponential\"\ncoefficient = 1.0\nexponent = 1.0\ngap = 1e-3\n" + nnm); },
      {"contact.law: analysis \"nnm\" takes law = \"rigid\" (exact contact) or \"linear\" (penalty spring)"});
  // Rigid stops in forced responses: continued with stability on by default, as penalty laws (from the
  // exact orbit near each point, issue #38), not mixed with penalty laws, no cell average, and
  // Moreau–Jean's keys (not the BDF's) in [timestep].
  const std::string stop = "[contact]\nlaw = \"rigid\"\ngap = 1e-3\n";
  EXPECT_TRUE(parse(rod + "[forcing]\namplitude = 1.0\nfrequency_hz = [100.0, 200.0]\n" + stop +
                    "[analysis]\ntype = \"continuation\"\n").analysis.stability);
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)parse(rod + force + "[[contact]]\nlaw = \"rigid\"\ngap = 1e-3\n[[contact]]\nlaw = \"linear\"\n"
                                  "stiffness = 1e9\ngap = 1e-3\nnode = 5\n");
      },
      {"contact[1]: mixes exact contacts (\"rigid\", \"coulomb\") with penalty"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(rod + force + stop + "[basis]\ntrial = \"fourier\"\nharmonics = 8\ncontact_quadrature = \"cell-average\"\n"); },
      {"basis.contact_quadrature: \"cell-average\" integrates a penalty law", "\"midpoint\""});
  EXPECT_EQ(parse(rod + force + stop + "[basis]\ntrial = \"fourier\"\nharmonics = 8\n").basis.contact_quadrature,
            wbm::solvers::ContactQuadrature::Midpoint);
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(rod + force + stop + "[analysis]\ntype = \"timestep\"\n[timestep]\nrelative_tolerance = 1e-8\n"); },
      {"timestep.relative_tolerance: unknown key", "rigid stops are integrated by Moreau–Jean"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(rod + force + stop + "[analysis]\ntype = \"timestep\"\n[timestep]\nsteps_per_period = 1000\n"); },
      {"timestep.steps_per_period: 1000 is not a multiple of output.samples = 1024"});
  expect_throw_with<std::invalid_argument>([&] { (void)parse(rod + "[contact]\nlaw = \"rigid\"\ngap = 0.0\n" + nnm); },
                                           {"contact.gap: value 0 out of range: expected > 0 [m; nnm normalizes"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(rod + "[contact]\nlaw = \"linear\"\nstiffness = 1e9\ngap = 1e-3\n" + nnm + "algorithm = \"sequential\"\n"); },
      {"analysis.algorithm: \"sequential\" (augmented Lagrangian, LL11 Alg. 1/2) imposes exact contact"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(rod + "[contact]\nlaw = \"rigid\"\ngap = 1e-3\n" + nnm + "harmonics = 16\nsamples = 32\nlevels = [3.0]\n"); },
      {"analysis.samples: m = 32 must exceed 2N = 32", "analysis.levels: energy 3 outside analysis.energy = [0.5, 2]"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(rod + force + "[analysis]\ntype = \"continuation\"\nfunctions = [1]\n"); },
      {"inline.toml:9: forcing.frequency_hz: analysis \"continuation\" follows the branch over a range",
       "analysis.functions: only used by type = \"basis-plot\""});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse("[structure]\nmass = [[1.0, 0.1], [0.0, 1.0]]\nstiffness = [[1.0, 0.0], [0.0, 1.0]]\n" +
                        force); },
      {"inline.toml:2: structure.mass: M is not symmetric (max |M - M^T| = 0.1)"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse("[structure]\nmass = [1.0, 1.0]\nstiffness = [[1.0, 0.0], [0.0, -1.0, 3.0]]\n" + force); },
      {"inline.toml:3: structure.stiffness: row 1 has 3 entries; a square matrix of 2 rows needs 2"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse("[structure]\nmass = [1.0, -1.0]\nstiffness = [1.0, 1.0]\n" + force); },
      {"structure.mass: M is not positive definite"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse("[structure]\nmass = [[1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, -1.0]]\n"
                        "stiffness = [1.0, 1.0, 1.0]\n" + force); },
      {"structure.mass: M is not positive definite on the DOFs with mass"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse("[structure]\nmass = [1.0, 1.0]\nstiffness = [1.0, 1.0]\n" + force); },
      {"inline.toml:4: forcing.dof: missing; which DOF (name or 0-based index)?"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse("[structure]\nmass = [1.0, 1.0]\nstiffness = [1.0, 1.0]\ndofs = [\"a\", \"a\"]\n" + force); },
      {"structure.dofs: \"a\" appears twice"});
  write("bad.mtx", "%%MatrixMarket matrix array real general\n2 2\n1\n0\n0\n1\n");
  expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::scene::load_scene(write("mm.toml", "[structure]\nmass = 1.0\nstiffness = \"bad.mtx\"\n" + force)); },
      {"structure.stiffness:", "is not supported; expected \"%%MatrixMarket matrix coordinate"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::scene::load_scene(write("mm2.toml", "[structure]\nmass = 1.0\nstiffness = \"none.mtx\"\n" + force)); },
      {"structure.stiffness: cannot read Matrix Market file"});
  expect_throw_with<std::invalid_argument>([&] { (void)parse("[structure\nmass = 1.0\n"); },
                                           {"inline.toml:1: TOML syntax:"});
  expect_throw_with<std::invalid_argument>([&] { (void)wbm::scene::load_scene(temp("absent.toml")); },
                                        {"absent.toml: no such file"});
  // JSON input has no lines: "file: key: what".
  expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::scene::scene_from_json(nlohmann::json::parse(R"({"scene": {"forcing": {"amplitude": "x"}}})"),
                                              temp("r.json")); },
      {"r.json: forcing.amplitude: expected a number finite [N], got a string", "r.json: [structure]: missing table"});
}

// A scene models only what it needs: sections an analysis does not use are reported and not
// built (a basis plot builds no structure, even an invalid one).
TEST(Scene, UnusedSectionsAreWarnedAboutAndNotBuilt) {
  const Scene s = parse("[analysis]\ntype = \"basis-plot\"\n[basis]\ntrial = \"haar\"\nlevel = 2\n"
                        "[structure]\nyoung_modulus = -1.0\n");
  EXPECT_FALSE(s.structure.has_value());
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_NE(s.warnings[0].find("inline.toml:6: warning: [structure] is not used by analysis \"basis-plot\""),
            std::string::npos);
}

// Regressions for what fuzz_scene found (issue #19), each now a reported error with file, line
// and key instead of undefined behaviour or an exception outside the contract: (1) an nnm scene
// whose [contact] has no `law` key (the default law is refused) dereferenced the missing node to
// place the message; (2) `level = 71` was reported out of range but still used in 1 << level.
TEST(Scene, FuzzFindingsAreReportedErrors) {
  expect_throw_with<std::invalid_argument>(
      [] {
        (void)parse("[structure]\nyoung_modulus = 7e10\ndensity = 2700.0\narea = 2.5e-3\nlength = 1.0\nelements = 4\n"
                    "[contact]\ngap = 1e-3\nnode = \"tip\"\n[analysis]\ntype = \"nnm\"\nenergy = [0.5, 2.0]\n");
      },
      {"inline.toml:", "contact.law", "\"rigid\""});
  expect_throw_with<std::invalid_argument>(
      [] { (void)parse("[basis]\ntrial = \"db6\"\nlevel = 71\n[analysis]\ntype = \"basis-plot\"\n"); },
      {"inline.toml:3", "basis.level", "value 71 out of range", "[0, 20]"});
  // (3) a Daubechies filter length beyond int made std::stoi throw std::out_of_range.
  expect_throw_with<std::invalid_argument>(
      [] { (void)parse("[basis]\ntrial = \"db13333333333333333333333\"\nlevel = 4\n[analysis]\ntype = \"basis-plot\"\n"); },
      {"inline.toml:2", "basis.trial", "filter length out of range", "4 <= L <= 20"});
}
