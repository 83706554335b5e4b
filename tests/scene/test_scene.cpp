// Scene files (wbm::scene): the shipped scenes hold Table 1 of [JL14]; resolved JSON round
// trips; every class of bad input is reported with file, line, key and what was expected; the
// analyses a scene runs agree with closed forms.
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

#include "scene.hpp"  // reproduce/common: the shipped scene directory
#include "testing.hpp"

namespace {

using wbm::scene::Scene;
using wbm::testing::expect_throw_with;

// Files of this process's tests, in one folder removed at exit.
struct Scratch {
  std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("wbm_test_scene_" + std::to_string(::getpid()));
  ~Scratch() {
    std::error_code ignored;
    std::filesystem::remove_all(dir, ignored);
  }
};

std::filesystem::path temp(const std::string& name) {
  static const Scratch scratch;
  return scratch.dir / name;
}

std::filesystem::path write(const std::string& name, const std::string& text) {
  const auto path = temp(name);
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path) << text;
  return path;
}

Scene parse(const std::string& text) { return wbm::scene::parse_scene(text, temp("inline.toml")); }

// Linear 1-DOF oscillator m ü + c u̇ + k u = F cos ωt: steady amplitude F / |k − mω² + iωc|.
double oscillator_amplitude(double m, double c, double k, double f, double hz) {
  const double w = 2.0 * std::numbers::pi * hz;
  return f / std::abs(std::complex<double>(k - m * w * w, w * c));
}

const Eigen::VectorXd& column(const wbm::scene::AnalysisResult& r, const std::string& file, size_t c) {
  for (const auto& t : r.tables) {
    if (t.file == file) return t.columns.at(c);
  }
  throw std::out_of_range("no table " + file);
}

}  // namespace

// Table 1 of [JL14]: Case 1 150 Hz, a_c = 1e8 N, α = 50 1/m, β = 1e-4 s, g0 = 1 mm;
// Case 2 1275 Hz, α = 20, β = 5e-6, g0 = 14.5 mm; rod of Sec. 4.
TEST(Scene, ShippedCasesHoldTable1) {
  const Scene s1 = wbm::reproduce::load_scene("jl14_case1");
  const Scene s2 = wbm::reproduce::load_scene("jl14_case2");
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
      wbm::reproduce::load_scene("jl14_case2"),
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
       p + ":17: colour: unknown key; allowed here: title, structure,"});
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
  // Rigid stops in forced responses: not continued, not mixed with penalty laws, no cell average,
  // and Moreau–Jean's keys (not the BDF's) in [timestep].
  const std::string stop = "[contact]\nlaw = \"rigid\"\ngap = 1e-3\n";
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)parse(rod + "[forcing]\namplitude = 1.0\nfrequency_hz = [100.0, 200.0]\n" + stop +
                    "[analysis]\ntype = \"continuation\"\nstability = true\n");
      },
      {"contact.law: \"rigid\" (exact contact) with analysis.stability = true", "set stability = false"});
  EXPECT_FALSE(parse(rod + "[forcing]\namplitude = 1.0\nfrequency_hz = [100.0, 200.0]\n" + stop +
                     "[analysis]\ntype = \"continuation\"\n").analysis.stability);
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)parse(rod + force + "[[contact]]\nlaw = \"rigid\"\ngap = 1e-3\n[[contact]]\nlaw = \"linear\"\n"
                                  "stiffness = 1e9\ngap = 1e-3\nnode = 5\n");
      },
      {"contact[1]: mixes rigid and penalty contacts"});
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

// 1-DOF oscillator (the five-line scene of docs/scenes.md, no contact): the solve equals the
// closed-form amplitude F/|k − mω² + iωc| with c = αm, at one frequency and over a sweep.
TEST(Scene, OscillatorSolveAndSweepMatchClosedForm) {
  const double m = 2.0, k = 8e4, alpha = 3.0, f = 10.0;
  const std::string head = "structure = { mass = 2.0, stiffness = 8e4 }\ndamping = { alpha = 3.0 }\n";
  const auto one = wbm::scene::run_analysis(parse(head + "forcing = { amplitude = 10.0, frequency_hz = 25.0 }\n"));
  ASSERT_TRUE(one.converged);
  // Fourier coefficients {1, cos 2πτ, sin 2πτ, …}: the amplitude is √(a₁² + a₂²).
  const Eigen::VectorXd& a = column(one, "coefficients.csv", 1);
  const double exact = oscillator_amplitude(m, alpha * m, k, f, 25.0);
  EXPECT_NEAR(std::hypot(a(1), a(2)), exact, 1e-12 * exact);
  EXPECT_NEAR(a.cwiseAbs().sum() - std::abs(a(1)) - std::abs(a(2)), 0.0, 1e-12 * exact);  // no other harmonic
  const auto sweep = wbm::scene::run_analysis(
      parse(head + "forcing = { amplitude = 10.0, frequency_hz = [5.0, 55.0], points = 11 }\n"
                   "basis = { dimension = 8 }\noutput = { samples = 4096 }\n"));
  ASSERT_TRUE(sweep.converged);
  const Eigen::VectorXd& hz = column(sweep, "frequency_response.csv", 0);
  const Eigen::VectorXd& max_u = column(sweep, "frequency_response.csv", 1);
  ASSERT_EQ(hz.size(), 11);
  for (Eigen::Index i = 0; i < hz.size(); ++i) {
    // The maximum over 4096 samples of a cosine: within 1 − cos(π/4096) of its amplitude.
    const double a = oscillator_amplitude(m, alpha * m, k, f, hz(i));
    EXPECT_NEAR(max_u(i), a, 1e-6 * a) << hz(i) << " Hz";
  }
}

// [solver] residual_tolerance is the bound the full residual is verified against, echoed in the
// resolved scene and per solve: the oscillator against a stop meets the default 1e-8; a bound
// below what double precision can reach (1e-30) is reported as not converged (never converged
// by hand), with the residual it reached; 0 is refused naming the key.
TEST(Scene, TheResidualToleranceIsAnOptionReportedAsUsed) {
  const std::string head = "structure = { mass = 1.0, stiffness = 4e4 }\ndamping = { alpha = 5.0 }\n"
                           "forcing = { amplitude = 5.0, frequency_hz = 30.0 }\n"
                           "contact = { law = \"linear\", stiffness = 4e5, gap = 2e-3 }\n";
  const auto plain = wbm::scene::run_analysis(parse(head));
  ASSERT_TRUE(plain.converged);
  EXPECT_EQ(plain.diagnostics["solution"]["residual_tolerance"].get<double>(), 1e-8);
  EXPECT_LE(plain.diagnostics["solution"]["relative_residual"].get<double>(), 1e-8);
  const auto loose = parse(head + "solver = { residual_tolerance = 1e-7 }\n");
  EXPECT_EQ(wbm::scene::to_json(loose)["solver"]["residual_tolerance"].get<double>(), 1e-7);
  EXPECT_EQ(wbm::scene::run_analysis(loose).diagnostics["solution"]["residual_tolerance"].get<double>(), 1e-7);
  const auto tight = wbm::scene::run_analysis(parse(head + "solver = { residual_tolerance = 1e-30 }\n"));
  EXPECT_FALSE(tight.converged);
  EXPECT_GT(tight.diagnostics["solution"]["relative_residual"].get<double>(), 1e-30);
  EXPECT_EQ(tight.diagnostics["solution"]["newton"]["status"], "residual-not-verified") << tight.diagnostics.dump();
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(head + "solver = { residual_tolerance = 0.0 }\n"); }, {"solver.residual_tolerance"});
}

// Regression (issue #19): a sweep over the resonance of an oscillator against a stop 100 times
// stiffer than its spring stalls where it continues from the contact branch, restarts from the
// linear response and lands on the no-contact branch. That switch must be reported: a 1 in the
// CSV's restarted_from_linear column, a warning naming the frequency, diagnostics listing it.
// The landed point is the closed-form linear amplitude F/|k − mω² + iωc| (below the gap), while
// the point before it was in contact (above the gap): a genuine branch switch, not a relabel.
TEST(Scene, SweepReportsARestartThatLeavesTheBranch) {
  const double m = 1.0, k = 4e4, alpha = 5.0, f = 5.0, gap = 2e-3;
  const auto r = wbm::scene::run_analysis(parse(
      "structure = { mass = 1.0, stiffness = 4e4 }\ndamping = { alpha = 5.0 }\n"
      "forcing = { amplitude = 5.0, frequency_hz = [15.0, 60.0], points = 91 }\n"
      "contact = { law = \"linear\", stiffness = 4e6, gap = 2e-3 }\noutput = { samples = 4096 }\n"));
  const Eigen::VectorXd& hz = column(r, "frequency_response.csv", 0);
  const Eigen::VectorXd& max_u = column(r, "frequency_response.csv", 1);
  const Eigen::VectorXd& restarted = column(r, "frequency_response.csv", 6);
  ASSERT_EQ(r.tables.front().header.at(6), "restarted_from_linear [-]");
  int switches = 0;
  for (Eigen::Index i = 1; i < hz.size(); ++i) {
    if (restarted(i) != 1.0) continue;
    if (max_u(i - 1) > gap && max_u(i) < gap) {
      ++switches;
      const double linear = oscillator_amplitude(m, alpha * m, k, f, hz(i));
      EXPECT_NEAR(max_u(i), linear, 1e-6 * linear) << hz(i) << " Hz";
    }
  }
  EXPECT_GE(switches, 1);
  ASSERT_EQ(r.warnings.size(), r.diagnostics["restarted_points"].size());
  ASSERT_GE(r.warnings.size(), 1u);
  const double first = r.diagnostics["restarted_points"][0]["frequency_hz"].get<double>();
  EXPECT_NE(r.warnings[0].find("at f = " + std::to_string(static_cast<int>(first))), std::string::npos) << r.warnings[0];
  EXPECT_NE(r.warnings[0].find("continuation"), std::string::npos);
  EXPECT_NE(r.summary.find("restarted from the linear response"), std::string::npos) << r.summary;
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

// A scene without a [basis] table gets harmonic balance with H = 32 (2H + 1 functions, every
// harmonic damped) and the cell-average contact quadrature, as a [basis] without a size does;
// never the M = 2^J basis with its undamped top function (issue #19).
TEST(Scene, NoBasisTableGivesHarmonicBalanceWithDampedHarmonics) {
  const Scene s = parse("structure = { mass = 1.0, stiffness = 4e4 }\ndamping = { alpha = 5.0 }\n"
                        "forcing = { amplitude = 5.0, frequency_hz = 30.0 }\n"
                        "contact = { law = \"linear\", stiffness = 4e6, gap = 2e-3 }\n");
  EXPECT_EQ(s.basis.harmonics, wbm::scene::Basis::kDefaultHarmonics);
  EXPECT_EQ(s.basis.dimension, 2 * wbm::scene::Basis::kDefaultHarmonics + 1);
  EXPECT_EQ(s.basis.contact_quadrature, wbm::solvers::ContactQuadrature::CellAverage);
  const Scene paper = parse("structure = { mass = 1.0, stiffness = 4e4 }\nforcing = { amplitude = 5.0, frequency_hz = 30.0 }\n"
                            "basis = { dimension = 64 }\n");
  EXPECT_EQ(paper.basis.contact_quadrature, wbm::solvers::ContactQuadrature::Midpoint);
  // A law with a corner is averaged over the cells whatever M (issue #35), unless the trial has no
  // slope (Haar) or the scene asks for the paper's rule by name.
  const std::string stop = "structure = { mass = 1.0, stiffness = 4e4 }\nforcing = { amplitude = 5.0, frequency_hz = 30.0 }\n"
                           "contact = { law = \"linear\", stiffness = 4e6, gap = 2e-3 }\n";
  EXPECT_EQ(parse(stop + "basis = { dimension = 64 }\n").basis.contact_quadrature, wbm::solvers::ContactQuadrature::CellAverage);
  EXPECT_EQ(parse(stop + "basis = { trial = \"haar\", weighting = \"fourier\", dimension = 16 }\n").basis.contact_quadrature,
            wbm::solvers::ContactQuadrature::Midpoint);
  EXPECT_EQ(parse(stop + "basis = { dimension = 64, contact_quadrature = \"midpoint\" }\n").basis.contact_quadrature,
            wbm::solvers::ContactQuadrature::Midpoint);
  expect_throw_with<std::invalid_argument>(
      [] {
        (void)parse("structure = { mass = 1.0, stiffness = 4e4 }\nforcing = { amplitude = 5.0, frequency_hz = 30.0 }\n"
                    "basis = { trial = \"haar\", weighting = \"fourier\", dimension = 16, contact_quadrature = \"cell-average\" }\n");
      },
      {"basis.contact_quadrature", "Haar", "\"midpoint\""});
}

// The newcomer's stiff-stop scene (examples/scenes/stiff_stop_continuation.toml, issue #19): a stop
// 100 times stiffer than the spring, continuation with every default. The branch reaches the
// range end with the resonance's two folds only (the midpoint rule stalled at 35.26 Hz on a
// sample crossing the gap), both confirmed by a Floquet multiplier crossing +1, and the folds do
// not move with Q (256 → 1024) nor with H (32 → 64) by more than 0.01 Hz: they are the
// oscillator's, not the discretization's.
TEST(Scene, StiffStopContinuationRunsWithDefaults) {
  const std::string head = "structure = { mass = 1.0, stiffness = 4e4 }\ndamping = { alpha = 5.0 }\n"
                           "forcing = { amplitude = 5.0, frequency_hz = [15.0, 60.0] }\n"
                           "contact = { law = \"linear\", stiffness = 4e6, gap = 2e-3 }\n"
                           "analysis = { type = \"continuation\" }\n";
  auto folds = [](const wbm::scene::AnalysisResult& r) {
    for (const auto& t : r.tables) {
      if (t.file == "folds.csv") return std::pair{t.columns.at(0), t.columns.at(1)};
    }
    return std::pair{Eigen::VectorXd(), Eigen::VectorXd()};
  };
  const auto r = wbm::scene::run_analysis(parse(head));
  ASSERT_TRUE(r.converged) << r.summary;
  const auto [hz, crossing] = folds(r);
  ASSERT_EQ(hz.size(), 2) << r.summary;
  EXPECT_EQ(crossing(0), 1.0);
  EXPECT_EQ(crossing(1), 1.0);
  EXPECT_GT(hz(0), hz(1));  // the upper (jump-down) fold above the lower (jump-up) one
  // The lower (jump-up) fold is the grazing orbit: the linear response of amplitude g,
  // (k − mω²)² + (cω)² = (F/g)², at 32.7251 Hz (the cell-average rule smooths the corner over one
  // cell: within 0.001 Hz of it).
  const double k = 4e4, c = 5.0, force = 5.0, gap = 2e-3, b = 2.0 * k - c * c;
  const double grazing_hz = std::sqrt(0.5 * (b + std::sqrt(b * b - 4.0 * (k * k - std::pow(force / gap, 2))))) / (2.0 * M_PI);
  EXPECT_NEAR(hz(1), grazing_hz, 1e-3);
  // Each fold's state (issue #35): its amplitude lies on the branch at its frequency, on its own
  // sheet: the lower fold's is the gap, the upper fold's above it, and each within 1 % of a
  // branch point less than 0.1 Hz away (the curve there has three sheets, the middle one unstable).
  const wbm::scene::Table* fold_table = nullptr;
  const wbm::scene::Table* branch = nullptr;
  for (const auto& t : r.tables) {
    if (t.file == "folds.csv") fold_table = &t;
    if (t.file == "branch.csv") branch = &t;
  }
  ASSERT_TRUE(fold_table != nullptr && branch != nullptr);
  ASSERT_EQ(fold_table->header.at(4), "amplitude_dof0 [m]");
  ASSERT_EQ(branch->header.at(3), "amplitude_dof0 [m]");
  const Eigen::VectorXd& fold_amplitude = fold_table->columns.at(4);
  EXPECT_NEAR(fold_amplitude(1), gap, 1e-3 * gap);
  EXPECT_GT(fold_amplitude(0), 1.5 * gap);
  for (Eigen::Index k = 0; k < 2; ++k) {
    double nearest = INFINITY;
    for (Eigen::Index i = 0; i < branch->columns[0].size(); ++i) {
      if (std::abs(branch->columns[0](i) - hz(k)) < 0.1) {
        nearest = std::min(nearest, std::abs(branch->columns[3](i) - fold_amplitude(k)));
      }
    }
    EXPECT_LT(nearest, 0.01 * fold_amplitude(k)) << "fold " << k << " at " << hz(k) << " Hz";
  }
  for (const std::string basis : {"basis = { harmonics = 32, time_samples = 1024 }\n", "basis = { harmonics = 64 }\n"}) {
    const auto finer = wbm::scene::run_analysis(parse(head + basis));
    ASSERT_TRUE(finer.converged) << basis << finer.summary;
    const auto [hz2, crossing2] = folds(finer);
    ASSERT_EQ(hz2.size(), 2) << basis;
    EXPECT_NEAR(hz2(0), hz(0), 0.01) << basis;
    EXPECT_NEAR(hz2(1), hz(1), 0.01) << basis;
  }
}

// The stiff stop of issue #35 with the paper's Fourier basis, M = 64, and nothing else: 50 kg on
// 1 MN/m (c = 0.2 √(mk)), a 1e8 N/m stop at 20 µm, 10 N over 60–210 rad/s. Sampled at midpoints it
// stalled at 29.98 Hz (a sample crossing the gap); averaged over the cells it reaches the range
// end with the resonance's two folds, and its lower fold is the grazing orbit, where the linear
// response's amplitude is the gap: (k − mω²)² + (cω)² = (F/g)².
TEST(Scene, StiffStopWithThePapersFourierBasisCompletes) {
  const double m = 50.0, k = 1e6, c = 0.2 * std::sqrt(m * k), force = 10.0, gap = 2e-5;
  const auto r = wbm::scene::run_analysis(parse(
      "structure = { mass = 50.0, stiffness = 1e6 }\ndamping = { alpha = " + std::to_string(c / m) + " }\n"
      "forcing = { amplitude = 10.0, frequency_rad_s = [60.0, 210.0] }\n"
      "contact = { law = \"linear\", stiffness = 1e8, gap = 2e-5 }\n"
      "basis = { trial = \"fourier\", dimension = 64 }\nanalysis = { type = \"continuation\" }\n"));
  ASSERT_TRUE(r.converged) << r.summary;
  const wbm::scene::Table* folds = nullptr;
  for (const auto& t : r.tables) {
    if (t.file == "folds.csv") folds = &t;
  }
  ASSERT_TRUE(folds != nullptr);
  ASSERT_EQ(folds->columns[0].size(), 2);
  const double b = 2.0 * m * k - c * c;
  const double grazing_hz =
      std::sqrt((b + std::sqrt(b * b - 4.0 * m * m * (k * k - std::pow(force / gap, 2)))) / (2.0 * m * m)) / (2.0 * M_PI);
  EXPECT_NEAR(folds->columns[0].minCoeff(), grazing_hz, 1e-3 * grazing_hz);
}

// Units must not matter (issue #19). A peer's nondimensional rod (E = ρ = S = L = 1, 20 elements,
// C = βK with β = 0.04/π, tip force 0.01, linear stop k = 10 at gap 0.1, H = 16, 0.2–0.4 Hz) is
// traced, then the same rod in other units of length, mass and time (factors 2⁻³, 2⁵, 2⁻⁴, so
// every conversion is exact in binary). Continuation scales its state and parameter from the
// problem, so the branch must be the same: the same points, frequencies and amplitudes converted
// back to 1e-10, the same stability flags and folds. Any absolute tolerance, step or bound
// would break this.
TEST(Scene, ContinuationDoesNotDependOnTheUnits) {
  auto scene = [](double sl, double sm, double st) {
    auto num = [](double v) {
      char b[64];
      std::snprintf(b, sizeof b, "%.17g", v);
      return std::string(b);
    };
    const double beta = 0.04 / std::numbers::pi;
    return parse("[structure]\nyoung_modulus = " + num(sm / (sl * st * st)) + "\ndensity = " + num(sm / (sl * sl * sl)) +
                 "\narea = " + num(sl * sl) + "\nlength = " + num(sl) + "\nelements = 20\n[damping]\nbeta = " +
                 num(beta * st) + "\n[forcing]\namplitude = " + num(0.01 * sm * sl / (st * st)) +
                 "\nfrequency_hz = [" + num(0.2 / st) + ", " + num(0.4 / st) + "]\nnode = \"tip\"\n[contact]\n"
                 "law = \"linear\"\nstiffness = " + num(10.0 * sm / (st * st)) + "\ngap = " + num(0.1 * sl) +
                 "\nnode = \"tip\"\n[basis]\nharmonics = 16\n[analysis]\ntype = \"continuation\"\n");
  };
  const double sl = 0.125, sm = 32.0, st = 0.0625;
  const auto a = wbm::scene::run_analysis(scene(1.0, 1.0, 1.0));
  const auto b = wbm::scene::run_analysis(scene(sl, sm, st));
  ASSERT_TRUE(a.converged) << a.summary;
  ASSERT_TRUE(b.converged) << b.summary;
  const auto& fa = column(a, "branch.csv", 0);
  const auto& fb = column(b, "branch.csv", 0);
  ASSERT_EQ(fa.size(), fb.size()) << a.summary << "\n" << b.summary;
  EXPECT_GT(fa.size(), 20);
  const Eigen::VectorXd f_back = fb * st;
  EXPECT_LE((f_back - fa).cwiseAbs().maxCoeff(), 1e-10 * fa.cwiseAbs().maxCoeff());
  const Eigen::VectorXd amp_back = column(b, "branch.csv", 3) / sl;
  const auto& amp = column(a, "branch.csv", 3);
  EXPECT_LE((amp_back - amp).cwiseAbs().maxCoeff(), 1e-10 * amp.cwiseAbs().maxCoeff());
  EXPECT_EQ(column(a, "branch.csv", 5), column(b, "branch.csv", 5));  // stable [-]
  ASSERT_EQ(a.diagnostics["continuation"]["folds"].size(), b.diagnostics["continuation"]["folds"].size());
  for (size_t k = 0; k < a.diagnostics["continuation"]["folds"].size(); ++k) {
    EXPECT_NEAR(b.diagnostics["continuation"]["folds"][k]["frequency_hz"].get<double>() * st,
                a.diagnostics["continuation"]["folds"][k]["frequency_hz"].get<double>(), 1e-10);
  }
}

// Time stepping from a scene: BDF on the same oscillator reaches the closed-form amplitude.
TEST(Scene, TimestepMatchesClosedForm) {
  const auto r = wbm::scene::run_analysis(parse("structure = { mass = 2.0, stiffness = 8e4 }\n"
                                                "damping = { alpha = 30.0 }\n"
                                                "forcing = { amplitude = 10.0, frequency_hz = 25.0 }\n"
                                                "analysis = { type = \"timestep\" }\n"
                                                "output = { samples = 8192 }\n"));
  ASSERT_TRUE(r.converged) << r.diagnostics.dump(2);
  const double a = oscillator_amplitude(2.0, 60.0, 8e4, 10.0, 25.0);
  // Sampled maximum of a cosine on 8192 points: within 1 − cos(π/8192) ≈ 7e-8 of the amplitude.
  EXPECT_NEAR(column(r, "displacement.csv", 2).maxCoeff(), a, 1e-6 * a);
}

// A rigid stop from a scene: the weighted residual solve (Fourier:Fourier, M = 256) and the
// Moreau–Jean time stepping (plastic impacts, e = 0) reach the same periodic tip motion, the
// solve's contact plateau is at the gap, and its force file holds the multipliers at their
// instants; the resolved scene re-runs to the same numbers.
TEST(Scene, RigidStopSolveAgreesWithMoreauJean) {
  const std::string rod = "[structure]\nyoung_modulus = 70e9\ndensity = 2700.0\narea = 25e-4\nlength = 1.0\n"
                          "elements = 25\n[damping]\nbeta = 1e-4\n[forcing]\namplitude = 250e3\nfrequency_hz = 150.0\n"
                          "[contact]\nlaw = \"rigid\"\ngap = 1e-3\n";
  const auto solve = wbm::scene::run_analysis(parse(rod + "[basis]\ntrial = \"fourier\"\ndimension = 256\n"));
  ASSERT_TRUE(solve.converged) << solve.diagnostics.dump(2);
  const auto step = wbm::scene::run_analysis(parse(rod + "[analysis]\ntype = \"timestep\"\n"));
  ASSERT_TRUE(step.converged) << step.diagnostics.dump(2);
  const Eigen::VectorXd& u_solve = column(solve, "displacement.csv", 2);
  const Eigen::VectorXd& u_step = column(step, "displacement.csv", 2);
  EXPECT_LT(wbm::solvers::rms_relative_error(u_solve, u_step), 5e-4);
  EXPECT_LE(solve.diagnostics["solution"]["collocation_penetration_m"].get<double>(), 1e-15);
  const Eigen::VectorXd& tau_k = column(solve, "contact_force.csv", 0);
  ASSERT_EQ(tau_k.size(), 256);
  EXPECT_DOUBLE_EQ(tau_k(0), 0.5 / 256);
  EXPECT_GT(column(solve, "contact_force.csv", 2).maxCoeff(), 0.0);
  for (const std::string& extra : {std::string("[basis]\ntrial = \"fourier\"\ndimension = 256\n"),
                                  std::string("[analysis]\ntype = \"timestep\"\n[timestep]\nsteps_per_period = 4096\n"
                                              "restitution = 0.5\n")}) {
    const Scene s = parse(rod + extra);
    const nlohmann::json j = wbm::scene::to_json(s);
    EXPECT_EQ(wbm::scene::to_json(wbm::scene::scene_from_json(j, temp("back.json"))), j) << j.dump(2);
  }
  EXPECT_EQ(parse(rod + "[analysis]\ntype = \"timestep\"\n[timestep]\nrestitution = 0.5\n").moreau_jean.restitution, 0.5);
}

// Basis plot: Haar φ_{J,k} is 2^{J/2} on [k/M, (k+1)/M) (orthonormal), M there with the paper's
// ∫ = 1 scaling [JL14 Sec. 3.3]; the Fourier q_1 is cos 2πτ.
TEST(Scene, BasisPlotGivesKnownFunctions) {
  const auto haar = wbm::scene::run_analysis(
      parse("[analysis]\ntype = \"basis-plot\"\nfunctions = [1]\nnormalization = \"unit-integral\"\n"
            "[basis]\ntrial = \"haar\"\nlevel = 2\n[output]\nsamples = 16\n"));
  const Eigen::VectorXd& phi = column(haar, "basis_functions.csv", 1);
  for (int p = 0; p < 16; ++p) EXPECT_DOUBLE_EQ(phi(p), (p >= 4 && p < 8) ? 4.0 : 0.0) << p;
  const auto fourier = wbm::scene::run_analysis(
      parse("[analysis]\ntype = \"basis-plot\"\nfunctions = [1]\n[basis]\ntrial = \"fourier\"\ndimension = 8\n"));
  const Eigen::VectorXd& tau = column(fourier, "basis_functions.csv", 0);
  const Eigen::VectorXd& q1 = column(fourier, "basis_functions.csv", 1);
  for (Eigen::Index p = 0; p < tau.size(); ++p) EXPECT_NEAR(q1(p), std::cos(2 * std::numbers::pi * tau(p)), 1e-14);
}

// Result files: NaN never reaches a file, and a staged run leaves nothing until commit().
// One convention for a missing value: an empty cell beside a status column that says why, never
// 0 or −1; inf is never written; a missing value with no status is refused.
TEST(Output, MissingValuesAreEmptyCellsBesideAStatus) {
  const auto dir = temp("missing");
  std::filesystem::create_directories(dir);
  Eigen::VectorXd err(3), m(3);
  err << 1e-3, std::nan(""), 2.5e-5;
  m << 8, 16, 32;
  wbm::scene::write_table(dir / "t.csv", {"t.csv", {"M [-]", "tip_error [-]"}, {m, err}, {"converged", "stagnated", "converged"}});
  std::ifstream in(dir / "t.csv");
  std::string header, row1, row2, row3;
  std::getline(in, header);
  std::getline(in, row1);
  std::getline(in, row2);
  std::getline(in, row3);
  EXPECT_EQ(header, "M [-],tip_error [-],status");
  EXPECT_EQ(row1, "8,0.001,converged");
  EXPECT_EQ(row2, "16,,stagnated");
  EXPECT_EQ(row3, "32,2.5000000000000001e-05,converged");
  Eigen::VectorXd inf = m;
  inf(1) = std::numeric_limits<double>::infinity();
  expect_throw_with<std::invalid_argument>(
      [&] { wbm::scene::write_table(dir / "u.csv", {"u.csv", {"cond [-]"}, {inf}, {"a", "b", "c"}}); },
      {"u.csv: column \"cond [-]\" contains inf; not written"});
  expect_throw_with<std::invalid_argument>(
      [&] { wbm::scene::write_table(dir / "v.csv", {"v.csv", {"x [-]"}, {m}, {"a", "b"}}); },
      {"status column has 2 rows, the first column 3"});
  EXPECT_FALSE(std::filesystem::exists(dir / "u.csv"));
  EXPECT_FALSE(std::filesystem::exists(dir / "v.csv"));
  std::filesystem::remove_all(dir);
}

// A write that fails (a full device) is an error naming the file, not a silently short file.
TEST(Output, AFailedWriteThrows) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full on this system";
  expect_throw_with<std::runtime_error>([] { wbm::scene::write_text("/dev/full", std::string(1 << 16, 'x')); },
                                        {"/dev/full: write failed"});
  expect_throw_with<std::runtime_error>(
      [] { wbm::scene::write_table("/dev/full", {"full.csv", {"x [-]"}, {Eigen::VectorXd::Ones(4096)}}); },
      {"/dev/full: write failed"});
}

TEST(Output, NonFiniteColumnsAndUncommittedRunsWriteNothing) {
  const auto dir = temp("staged");
  std::filesystem::remove_all(dir);
  Eigen::VectorXd bad(2);
  bad << 1.0, std::nan("");
  {
    wbm::scene::StagedOutput out(dir);
    out.table({"good.csv", {"x [-]"}, {Eigen::VectorXd::Ones(2)}});
    expect_throw_with<std::invalid_argument>([&] { out.table({"bad.csv", {"x [-]"}, {bad}}); },
                                             {"bad.csv: column \"x [-]\" has missing values (NaN)",
                                              "no status column"});
  }  // no commit: the staging folder and the folder created for it are gone
  EXPECT_FALSE(std::filesystem::exists(dir));
  {
    wbm::scene::StagedOutput out(dir);
    out.table({"a.csv", {"x [-]"}, {Eigen::VectorXd::Ones(3)}});
    out.text("result.json", "{}\n");
    EXPECT_FALSE(std::filesystem::exists(dir / "a.csv"));
    const auto files = out.commit("result.json");
    ASSERT_EQ(files.size(), 2u);
    EXPECT_EQ(files.back().filename(), "result.json");  // the completion marker goes last
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "a.csv"));
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), {}), 2);  // no staging folder left
  std::filesystem::remove_all(dir);
}

// Continuation from a scene: with the stop out of reach the oscillator is linear, so every
// point's amplitude is F/|k − mω² + iωc| (sampled on 1024 points: within 1 − cos(π/1024)).
TEST(Scene, ContinuationFollowsTheClosedFormAndRoundTrips) {
  const Scene s = parse("structure = { mass = 2.0, stiffness = 8e4 }\ndamping = { alpha = 3.0 }\n"
                        "forcing = { amplitude = 10.0, frequency_hz = [5.0, 55.0] }\n"
                        "contact = { law = \"linear\", stiffness = 1e6, gap = 1.0 }\n"
                        "basis = { dimension = 8 }\n"
                        "analysis = { type = \"continuation\", max_frequency_step_hz = 1.0 }\n");
  EXPECT_EQ(wbm::scene::to_json(wbm::scene::scene_from_json(wbm::scene::to_json(s), temp("c.json"))),
            wbm::scene::to_json(s));
  std::vector<std::pair<double, std::string>> reports;  // progress: one report per accepted point
  const auto r = wbm::scene::run_analysis(s, [&](double f, const std::string& label) { reports.emplace_back(f, label); });
  ASSERT_TRUE(r.converged) << r.diagnostics.dump(2);
  const Eigen::VectorXd& hz = column(r, "branch.csv", 0);
  const Eigen::VectorXd& amplitude = column(r, "branch.csv", 3);
  EXPECT_GE(hz.size(), 50);
  ASSERT_EQ(reports.size(), static_cast<size_t>(hz.size()));
  for (size_t i = 1; i < reports.size(); ++i) EXPECT_GE(reports[i].first, reports[i - 1].first);
  EXPECT_NEAR(reports.back().first, 1.0, 1e-12);  // the range is covered (the fraction is capped at 1)
  char expected[64];
  std::snprintf(expected, sizeof expected, "point 2, f = %.6g Hz, step ", hz(1));
  EXPECT_EQ(reports[1].second.rfind(expected, 0), 0u) << reports[1].second;
  for (Eigen::Index i = 0; i < hz.size(); ++i) {
    if (hz(i) > 55.0) continue;  // the last point may lie one step beyond the range
    const double a = oscillator_amplitude(2.0, 6.0, 8e4, 10.0, hz(i));
    EXPECT_NEAR(amplitude(i), a, 1e-5 * a) << hz(i) << " Hz";
  }
  EXPECT_EQ(column(r, "branch.csv", 5).minCoeff(), 1.0);  // every point stable
}

// A contact between two DOFs (`against`): a mass x1 on a spring and a forced mass x2 that closes
// the gap by moving towards it. With u = T y, T = [[1, 1], [0, 1]], y1 = x1 − x2 and the same
// problem is a contact of y1 against a fixed wall in (TᵀMT, TᵀKT), C = αM in both: the two scenes
// must give x1 = y1 + y2 and x2 = y2. The contact force file is headed by the pair.
TEST(Scene, ContactBetweenTwoDofsEqualsTheTransformedWallContact) {
  const std::string common = "damping = { alpha = 3.0 }\nforcing = { amplitude = 10.0, frequency_hz = 25.0, dof = 1 }\n";
  const Scene between = parse("structure = { mass = [1.0, 2.0], stiffness = [4e4, 1e5], dofs = [\"x1\", \"x2\"] }\n" +
                              common +
                              "contact = { law = \"linear\", stiffness = 4e5, gap = 1e-4, dof = \"x1\", against = \"x2\" }\n");
  const Scene wall = parse("structure = { mass = [[1.0, 1.0], [1.0, 3.0]], stiffness = [[4e4, 4e4], [4e4, 1.4e5]], "
                           "dofs = [\"y1\", \"y2\"] }\n" + common +
                           "contact = { law = \"linear\", stiffness = 4e5, gap = 1e-4, dof = \"y1\" }\n");
  const nlohmann::json j = wbm::scene::to_json(between);
  EXPECT_EQ(j["contact"][0]["against"], "x2");
  EXPECT_EQ(wbm::scene::to_json(wbm::scene::scene_from_json(j, temp("between.json"))), j);
  const auto r = wbm::scene::run_analysis(between);
  const auto w = wbm::scene::run_analysis(wall);
  ASSERT_TRUE(r.converged) << r.diagnostics.dump(2);
  ASSERT_TRUE(w.converged) << w.diagnostics.dump(2);
  const Eigen::VectorXd x1 = column(r, "displacement.csv", 2), x2 = column(r, "displacement.csv", 3);
  const Eigen::VectorXd y1 = column(w, "displacement.csv", 2), y2 = column(w, "displacement.csv", 3);
  EXPECT_LT((x1 - (y1 + y2)).norm(), 1e-8 * x1.norm());
  EXPECT_LT((x2 - y2).norm(), 1e-8 * x2.norm());
  EXPECT_GT((x1 - x2).maxCoeff(), 1e-4);  // the gap does close
  for (const auto& t : r.tables) {
    if (t.file == "contact_force.csv") {
      EXPECT_EQ(t.header.at(2), "f_c_x1-x2 [N]");
    }
  }
  EXPECT_LT((column(r, "contact_force.csv", 2) - column(w, "contact_force.csv", 2)).norm(),
            1e-8 * column(w, "contact_force.csv", 2).norm());
  const std::string two = "structure = { mass = [1.0, 2.0], stiffness = [4e4, 1e5] }\n" + common;
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(two + "contact = { law = \"linear\", stiffness = 4e5, gap = 1e-4, dof = 0, against = 0 }\n"); },
      {"contact.against: is the contact's own DOF dof0", "remove against for a fixed obstacle"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(two + "contact = { law = \"linear\", stiffness = 4e5, gap = 1e-4, dof = 0, against = 7 }\n"); },
      {"contact.against:", "[0, 1]"});
}

// `direction = -1` puts the stop on the −x side: the mirror image (u → −u) of the +x stop under
// the mirrored forcing, for the rigid and the penalty law. A table of DOF weights is a normal
// over several DOFs; both round-trip through JSON, and impossible directions are refused.
TEST(Scene, AStopOnTheNegativeSideMirrorsThePositiveOne) {
  const std::string rod = "[structure]\nyoung_modulus = 70e9\ndensity = 2700.0\narea = 25e-4\nlength = 1.0\n"
                          "elements = 25\n[damping]\nbeta = 1e-4\n[basis]\ntrial = \"bspline\"\ndimension = 64\n";
  for (const std::string law : {"law = \"rigid\"", "law = \"linear\"\nstiffness = 1e9"}) {
    const auto plus = wbm::scene::run_analysis(
        parse(rod + "[forcing]\namplitude = 250e3\nfrequency_hz = 150.0\n[contact]\n" + law + "\ngap = 1e-3\n"));
    const Scene minus_scene = parse(rod + "[forcing]\namplitude = -250e3\nfrequency_hz = 150.0\n[contact]\n" + law +
                                    "\ngap = 1e-3\ndirection = -1\n");
    const auto minus = wbm::scene::run_analysis(minus_scene);
    ASSERT_TRUE(plus.converged && minus.converged) << law;
    const Eigen::VectorXd& up = column(plus, "displacement.csv", 2);
    const Eigen::VectorXd& um = column(minus, "displacement.csv", 2);
    EXPECT_LT((up + um).norm(), 1e-9 * up.norm()) << law;
    EXPECT_LT(um.minCoeff(), -0.99e-3) << law;  // it reaches the stop at −g0
    const nlohmann::json j = wbm::scene::to_json(minus_scene);
    EXPECT_EQ(j["contact"][0]["direction"], -1);
    EXPECT_EQ(wbm::scene::to_json(wbm::scene::scene_from_json(j, temp("minus.json"))), j);
  }
  const std::string plane = "structure = { mass = [1.0, 1.0], stiffness = [4e4, 8e4], dofs = [\"x\", \"y\"] }\n"
                            "forcing = { amplitude = 10.0, frequency_hz = 25.0, dof = \"y\" }\n";
  const Scene normal = parse(plane + "contact = { law = \"rigid\", gap = 1e-4, dof = \"x\", direction = { x = 0.6, y = 0.8 } }\n");
  ASSERT_EQ(normal.contacts.front().along.size(), 2u);
  EXPECT_EQ(normal.contact_points().front().along[1], (std::pair<int, double>{1, 0.8}));
  const nlohmann::json j = wbm::scene::to_json(normal);
  EXPECT_EQ(wbm::scene::to_json(wbm::scene::scene_from_json(j, temp("normal.json"))), j);
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(plane + "contact = { law = \"rigid\", gap = 1e-4, dof = \"x\", direction = 2 }\n"); },
      {"contact.direction: expected +1 or -1"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(plane + "contact = { law = \"rigid\", gap = 1e-4, dof = \"x\", direction = { y = 1.0 } }\n"); },
      {"contact.direction: does not include the contact's DOF x"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(plane + "contact = { law = \"rigid\", gap = 1e-4, dof = \"x\", direction = { x = 1.0, z = 1.0 } }\n"); },
      {"contact.direction.z: is not a DOF name"});
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)parse(plane + "contact = { law = \"rigid\", gap = 1e-4, dof = \"x\", against = \"y\", direction = -1 }\n");
      },
      {"contact.direction: beside against"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(rod + "[forcing]\namplitude = 1.0\nfrequency_hz = 150.0\n[contact]\nlaw = \"rigid\"\ngap = 1e-3\n"
                              "direction = { tip = 1.0 }\n"); },
      {"contact.direction: the rod has one DOF per node: direction is +1 or -1"});
}

// An nnm stop along a direction: `direction = -1` on the 2-DOF chain is the mirror image of the
// +x stop (u → −u), so the backbone (energy, frequency, contact force) is the same, and the
// mode shape at E = 2 is mirrored (u_b reaches −g0 instead of +g0).
TEST(Scene, AnNnmStopOnTheNegativeSideMirrorsThePositiveOne) {
  std::ifstream in(std::filesystem::path(WBM_EXAMPLES) / "two_dof_nnm.toml");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string minus_text = std::regex_replace(text, std::regex("dof = \"b\""), "dof = \"b\"\ndirection = -1");
  ASSERT_NE(minus_text, text);
  const auto plus = wbm::scene::run_analysis(parse(text)), minus = wbm::scene::run_analysis(parse(minus_text));
  ASSERT_TRUE(plus.converged && minus.converged);
  // Columns 8 and 11: first_mode_share and other_share, invariant under the mirror too.
  for (int col : {0, 1, 6, 8, 11}) {
    const Eigen::VectorXd &a = column(plus, "backbone.csv", col), &b = column(minus, "backbone.csv", col);
    ASSERT_EQ(a.size(), b.size());
    EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-9 * a.cwiseAbs().maxCoeff()) << "column " << col;
  }
  EXPECT_GT(column(plus, "backbone.csv", 1).maxCoeff(), 1.05 * column(plus, "backbone.csv", 1).minCoeff());  // contact
  EXPECT_NEAR(column(plus, "backbone.csv", 8)(0), 1.0, 1e-12);  // E = 0.5: the linear first mode holds it all
  EXPECT_LT(column(plus, "backbone.csv", 8).minCoeff(), 1.0 - 1e-3);  // in contact: other components appear
  EXPECT_LE((column(plus, "backbone.csv", 8) + column(plus, "backbone.csv", 11)).maxCoeff(), 1.0 + 1e-12);
  const Eigen::VectorXd &ub_plus = column(plus, "mode_E2.csv", 3), &ub_minus = column(minus, "mode_E2.csv", 3);
  EXPECT_NEAR(ub_plus.maxCoeff(), 1e-3, 1e-9);
  EXPECT_NEAR(ub_minus.minCoeff(), -1e-3, 1e-9);
  EXPECT_NEAR(ub_plus.minCoeff(), -ub_minus.maxCoeff(), 1e-9);
}

// Frequencies in rad/s and an explicit list of frequencies: the 1-DOF oscillator's closed-form
// amplitude F/|k − mω² + iωc| at ω = 2π·25 rad/s given as frequency_rad_s, and a sweep at four
// listed frequencies (in the order given, both units), against the same closed form.
TEST(Scene, FrequenciesInRadPerSecondAndAsAListMatchTheClosedForm) {
  const std::string head = "structure = { mass = 2.0, stiffness = 8e4 }\ndamping = { alpha = 3.0 }\n";
  const double w = 2.0 * std::numbers::pi * 25.0;
  char text[64];
  std::snprintf(text, sizeof text, "%.17g", w);
  const auto one = wbm::scene::run_analysis(parse(head + "forcing = { amplitude = 10.0, frequency_rad_s = " + text + " }\n"));
  ASSERT_TRUE(one.converged);
  const Eigen::VectorXd& a = column(one, "coefficients.csv", 1);
  const double exact = oscillator_amplitude(2.0, 6.0, 8e4, 10.0, 25.0);
  EXPECT_NEAR(std::hypot(a(1), a(2)), exact, 1e-9 * exact);
  const std::vector<double> listed = {40.0, 10.0, 25.0, 31.0};
  for (const std::string& key : {std::string("frequencies_hz = [40.0, 10.0, 25.0, 31.0]"),
                                 std::string("frequencies_rad_s = [") + std::to_string(2 * std::numbers::pi * 40.0) +
                                     ", " + std::to_string(2 * std::numbers::pi * 10.0) + ", " +
                                     std::to_string(2 * std::numbers::pi * 25.0) + ", " +
                                     std::to_string(2 * std::numbers::pi * 31.0) + "]"}) {
    const Scene s = parse(head + "forcing = { amplitude = 10.0, " + key + " }\nbasis = { dimension = 8 }\n"
                          "output = { samples = 4096 }\n");
    const auto sweep = wbm::scene::run_analysis(s);
    ASSERT_TRUE(sweep.converged) << key;
    const Eigen::VectorXd& hz = column(sweep, "frequency_response.csv", 0);
    const Eigen::VectorXd& max_u = column(sweep, "frequency_response.csv", 1);
    ASSERT_EQ(hz.size(), 4);
    for (Eigen::Index i = 0; i < 4; ++i) {
      EXPECT_NEAR(hz(i), listed[static_cast<size_t>(i)], 1e-6) << key;
      const double amp = oscillator_amplitude(2.0, 6.0, 8e4, 10.0, hz(i));
      EXPECT_NEAR(max_u(i), amp, 1e-6 * amp) << key;
    }
    const nlohmann::json j = wbm::scene::to_json(s);
    EXPECT_EQ(j["forcing"]["frequencies_hz"].size(), 4u);
    EXPECT_EQ(wbm::scene::to_json(wbm::scene::scene_from_json(j, temp("list.json"))), j);
  }
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(head + "forcing = { amplitude = 1.0, frequency_hz = 5.0, frequency_rad_s = 30.0 }\n"); },
      {"forcing.frequency_rad_s: given beside forcing.frequency_hz; give the frequencies once"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(head + "forcing = { amplitude = 1.0, frequencies_hz = [5.0] }\n"); },
      {"forcing.frequencies_hz: expected a list of at least two numbers > 0 [Hz]; for one frequency use frequency_hz"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(head + "forcing = { amplitude = 1.0, frequencies_rad_s = [5.0, -1.0] }\n"); },
      {"forcing.frequencies_rad_s[1]", "> 0 [rad/s]"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(head + "forcing = { amplitude = 1.0 }\n"); },
      {"forcing.frequency_hz: missing", "frequency_rad_s", "frequencies_hz"});
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)parse(head + "[[forcing]]\namplitude = 1.0\nfrequency_hz = 5.0\n[[forcing]]\namplitude = 2.0\n"
                           "frequency_hz = 5.0\n");
      },
      {"[[forcing]]: one [forcing] table holds the frequency; several loads go in it as [[forcing.loads]]"});
}

// [output] harmonics = H: amplitudes and phases of u = Σ A_h cos(2πhft + φ_h). Linear oscillator:
// A_1 = F/|k − mω² + iωc|, φ_1 = −arg(k − mω² + iωc), nothing else. With a stop (harmonic
// balance), the harmonics recomputed from the samples equal the solver's Fourier coefficients.
TEST(Scene, HarmonicsOfTheResponseMatchClosedFormAndCoefficients) {
  const std::string head = "structure = { mass = 2.0, stiffness = 8e4 }\ndamping = { alpha = 3.0 }\n"
                           "forcing = { amplitude = 10.0, frequency_hz = 25.0 }\n";
  const auto linear = wbm::scene::run_analysis(parse(head + "output = { harmonics = 5 }\n"));
  ASSERT_TRUE(linear.converged);
  const double w = 2.0 * std::numbers::pi * 25.0;
  const std::complex<double> z(8e4 - 2.0 * w * w, w * 6.0);
  const Eigen::VectorXd& amplitude = column(linear, "harmonics.csv", 2);
  const Eigen::VectorXd& phase = column(linear, "harmonics.csv", 3);
  ASSERT_EQ(amplitude.size(), 6);
  EXPECT_DOUBLE_EQ(column(linear, "harmonics.csv", 1)(3), 75.0);  // frequency of h = 3 [Hz]
  EXPECT_NEAR(amplitude(1), 10.0 / std::abs(z), 1e-12 * amplitude(1));
  EXPECT_NEAR(phase(1), -std::arg(z), 1e-10);
  for (int h : {0, 2, 3, 4, 5}) EXPECT_LT(std::abs(amplitude(h)), 1e-12 * amplitude(1)) << h;

  const auto stop = wbm::scene::run_analysis(
      parse(head + "contact = { law = \"linear\", stiffness = 4e5, gap = 1e-4 }\nbasis = { harmonics = 8 }\n"
                   "output = { harmonics = 8 }\n"));
  ASSERT_TRUE(stop.converged);
  const Eigen::VectorXd& a = column(stop, "coefficients.csv", 1);  // {1, cos 2πτ, sin 2πτ, …}
  const Eigen::VectorXd& amp = column(stop, "harmonics.csv", 2);
  EXPECT_NEAR(amp(0), a(0), 1e-12 * amp(1));
  for (int h = 1; h <= 8; ++h) EXPECT_NEAR(amp(h), std::hypot(a(2 * h - 1), a(2 * h)), 1e-12 * amp(1)) << h;
  EXPECT_GT(amp(2), 1e-3 * amp(1));  // the stop makes harmonics
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)parse("structure = { mass = 2.0, stiffness = 8e4 }\ncontact = { law = \"rigid\", gap = 1e-3 }\n"
                    "analysis = { type = \"nnm\", energy = [0.5, 2.0] }\noutput = { harmonics = 3 }\n");
      },
      {"output.harmonics: written for solves", "not for nnm or basis plots"});
  expect_throw_with<std::invalid_argument>([&] { (void)parse(head + "output = { samples = 16, harmonics = 8 }\n"); },
                                           {"output.harmonics"});
}

// A 1-DOF oscillator whose contact node is massless and held by a spring (issue #18): mass m on a
// ground spring k and a dashpot c, a spring kc to the node x_c, and a linear stop k_s on the −x
// side of x_c at gap g0; forced at ω given in rad/s. The scene condenses x_c statically.
// Closed forms, derived from the two DOFs' equations (node: kc (x_c − x) = k_s (−x_c − g0)₊):
//  - prestressed (g0 < 0, contact closed throughout): x_c = (kc x − k_s g0)/(kc + k_s) and
//      m ẍ + c ẋ + (k + k_e) x = F cos ωt − k_e g0,  k_e = kc k_s/(kc + k_s);
//  - open (gap beyond the motion): x = Re(F e^{iωt}/(k − mω² + iωc)), x_c = x;
//  - with impacts, the same response as a 1-DOF scene with the stop k_e on x (series springs).
TEST(Scene, MasslessContactNodeOnASpringMatchesTheClosedForms) {
  const double m = 1.0, c = 4.0, k = 4000.0, kc = 1e4, ks = 1e4, f0 = 1.0, w = 50.0;
  const double ke = kc * ks / (kc + ks);
  char text[512];
  auto scene = [&](double g0, const std::string& extra) {
    std::snprintf(text, sizeof text,
                  "[structure]\ndofs = [\"x\", \"xc\"]\nmass = [[%.17g, 0.0], [0.0, 0.0]]\n"
                  "stiffness = [[%.17g, %.17g], [%.17g, %.17g]]\ndamping = [[%.17g, 0.0], [0.0, 0.0]]\n"
                  "[forcing]\namplitude = %.17g\ndof = \"x\"\nfrequency_rad_s = %.17g\n"
                  "[contact]\nlaw = \"linear\"\nstiffness = %.17g\ngap = %.17g\ndof = \"xc\"\ndirection = -1\n",
                  m, k + kc, -kc, -kc, kc, c, f0, w, ks, g0);
    return parse(std::string(text) + "[output]\nsamples = 64\ndofs = [\"x\", \"xc\"]\n" + extra);
  };
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(64, 0.0, 63.0 / 64.0);
  for (const std::string basis : {"[basis]\nharmonics = 4\n",
                                  "[basis]\ntrial = \"db6\"\nweighting = \"fourier\"\ndimension = 64\n"}) {
    // Prestressed: g0 = −1 mm; |X| ≈ 1.5e-4 m < −g0 k/(k + k_e) = 4.4e-4 m keeps the contact closed.
    const double g0 = -1e-3;
    const Scene closed_scene = scene(g0, basis);
    ASSERT_TRUE(closed_scene.condensation.has_value());
    EXPECT_EQ(closed_scene.system().dofs(), 1);
    const auto closed = wbm::scene::run_analysis(closed_scene);
    ASSERT_TRUE(closed.converged) << basis << closed.diagnostics.dump();
    const std::complex<double> amplitude = f0 / std::complex<double>(k + ke - m * w * w, c * w);
    const double mean = -ke * g0 / (k + ke);
    const double tolerance = basis.find("db6") != std::string::npos ? 1e-4 : 1e-10;  // DB6: discretization error
    const Eigen::VectorXd& x = column(closed, "displacement.csv", 2);
    const Eigen::VectorXd& xc = column(closed, "displacement.csv", 3);
    const Eigen::VectorXd& fc = column(closed, "contact_force.csv", 2);
    for (Eigen::Index p = 0; p < 64; ++p) {
      const double exact = mean + std::real(amplitude * std::polar(1.0, 2.0 * std::numbers::pi * tau(p)));
      EXPECT_NEAR(x(p), exact, tolerance * std::abs(mean)) << basis << " p = " << p;
      EXPECT_NEAR(xc(p), (kc * exact - ks * g0) / (kc + ks), tolerance * std::abs(mean)) << basis << " p = " << p;
      EXPECT_NEAR(fc(p), ks * (-(kc * exact - ks * g0) / (kc + ks) - g0), tolerance * ks * std::abs(mean)) << p;
    }
    if (basis.find("db6") == std::string::npos) {  // velocity: ẋ_c = kc ẋ/(kc + k_s) while closed
      const Eigen::VectorXd& v = column(closed, "velocity.csv", 2);
      const Eigen::VectorXd& vc = column(closed, "velocity.csv", 3);
      for (Eigen::Index p = 0; p < 64; ++p) {
        const double exact = std::real(std::complex<double>(0.0, w) * amplitude * std::polar(1.0, 2.0 * std::numbers::pi * tau(p)));
        EXPECT_NEAR(v(p), exact, 1e-9 * std::abs(amplitude) * w) << p;
        EXPECT_NEAR(vc(p), kc * exact / (kc + ks), 1e-9 * std::abs(amplitude) * w) << p;
      }
    }
    // Open: the node follows the mass.
    const auto open = wbm::scene::run_analysis(scene(1e-2, basis));
    ASSERT_TRUE(open.converged) << basis;
    const std::complex<double> free = f0 / std::complex<double>(k - m * w * w, c * w);
    const Eigen::VectorXd& xo = column(open, "displacement.csv", 2);
    const Eigen::VectorXd& xco = column(open, "displacement.csv", 3);
    for (Eigen::Index p = 0; p < 64; ++p) {
      const double exact = std::real(free * std::polar(1.0, 2.0 * std::numbers::pi * tau(p)));
      EXPECT_NEAR(xo(p), exact, tolerance * std::abs(free)) << basis << " p = " << p;
      EXPECT_NEAR(xco(p), exact, tolerance * std::abs(free)) << basis << " p = " << p;
    }
  }
  {  // Time stepping (BDF) of the condensed model, prestressed case, from rest to the periodic state.
    const auto bdf = wbm::scene::run_analysis(scene(-1e-3, "[analysis]\ntype = \"timestep\"\n"));
    ASSERT_TRUE(bdf.converged) << bdf.diagnostics.dump();
    const std::complex<double> amplitude = f0 / std::complex<double>(k + ke - m * w * w, c * w);
    const double mean = ke * 1e-3 / (k + ke);
    const Eigen::VectorXd& xc = column(bdf, "displacement.csv", 3);
    for (Eigen::Index p = 0; p < 64; ++p) {
      const double exact = mean + std::real(amplitude * std::polar(1.0, 2.0 * std::numbers::pi * tau(p)));
      EXPECT_NEAR(xc(p), (kc * exact + ks * 1e-3) / (kc + ks), 1e-4 * mean) << p;
    }
  }
  // With impacts (g0 = 0, F = 3 N): the 1-DOF scene with the series stiffness k_e as its stop.
  std::snprintf(text, sizeof text,
                "structure = { mass = %.17g, stiffness = %.17g, damping = %.17g, dofs = [\"x\"] }\n"
                "forcing = { amplitude = 3.0, dof = \"x\", frequency_rad_s = %.17g }\n"
                "contact = { law = \"linear\", stiffness = %.17g, gap = 0.0, dof = \"x\", direction = -1 }\n"
                "basis = { harmonics = 16 }\noutput = { samples = 64 }\n",
                m, k, c, w, ke);
  const auto one = wbm::scene::run_analysis(parse(text));
  Scene two_scene = scene(0.0, "[basis]\nharmonics = 16\n");
  two_scene.forcing->amplitude = 3.0;
  const auto two = wbm::scene::run_analysis(two_scene);
  ASSERT_TRUE(one.converged && two.converged);
  const Eigen::VectorXd& x1 = column(one, "displacement.csv", 2);
  const Eigen::VectorXd& x2 = column(two, "displacement.csv", 2);
  EXPECT_LT((x1 - x2).cwiseAbs().maxCoeff(), 1e-9 * x1.cwiseAbs().maxCoeff());
  // The stop is met: a contact force, and the swing (max − min) well below the free 2|X| = 4.0 mm.
  EXPECT_GT(column(two, "contact_force.csv", 2).maxCoeff(), 1.0);
  EXPECT_LT(x1.maxCoeff() - x1.minCoeff(), 0.6 * 2.0 * 3.0 / std::abs(std::complex<double>(k - m * w * w, c * w)));
  const nlohmann::json j = wbm::scene::to_json(two_scene);
  EXPECT_EQ(wbm::scene::to_json(wbm::scene::scene_from_json(j, temp("massless.json"))), j);

  // Refusals: a rigid stop on a massless node, a force on it, a dashpot on it, nnm.
  const std::string two_dof = "[structure]\ndofs = [\"x\", \"xc\"]\nmass = [[1.0, 0.0], [0.0, 0.0]]\n"
                              "stiffness = [[2.0e4, -1e4], [-1e4, 1e4]]\n";
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(two_dof + "[forcing]\namplitude = 1.0\ndof = \"x\"\nfrequency_hz = 5.0\n"
                                  "[contact]\nlaw = \"rigid\"\ngap = 1e-3\ndof = \"xc\"\n"); },
      {"contact.law: \"rigid\" on the massless DOF xc", "law = \"linear\""});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(two_dof + "[forcing]\namplitude = 1.0\ndof = \"xc\"\nfrequency_hz = 5.0\n"); },
      {"the force acts on the massless DOF xc; force a DOF with mass"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(two_dof + "damping = [[1.0, 0.0], [0.0, 1.0]]\n[forcing]\namplitude = 1.0\ndof = \"x\"\n"
                                  "frequency_hz = 5.0\n"); },
      {"C has an entry at (xc, xc) on a massless DOF"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse("[analysis]\ntype = \"nnm\"\nenergy = [0.5, 2.0]\n" + two_dof +
                        "[contact]\nlaw = \"rigid\"\ngap = 1e-3\ndof = \"x\"\n"); },
      {"structure.mass: has massless DOFs", "nnm"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse("[structure]\ndofs = [\"x\", \"xc\"]\nmass = [[1.0, 0.0], [0.0, 0.0]]\n"
                        "stiffness = [[1e4, 0.0], [0.0, 0.0]]\n[forcing]\namplitude = 1.0\ndof = \"x\"\nfrequency_hz = 5.0\n"); },
      {"is not positive definite: a massless DOF must be held by springs"});
}

// Several loads in one scene: [[forcing.loads]] with phases (degrees or radians) and harmonic
// orders, and a force vector file. Closed forms: the 1-DOF oscillator (m = 2 kg, k = 8e4 N/m,
// c = 6 N·s/m at f = 25 Hz) under 10 N cos ωt + 4 N cos(2ωt + 45°) + 3 N (harmonic 0) is
//   u(t) = Σ Re(F e^{iφ} e^{ihωt} / (k − (hω)² m + i hω c));
// two uncoupled DOFs under the vector (5, −2) N cos ωt respond each as its own oscillator.
TEST(Scene, SeveralLoadsAndAForceVectorMatchTheClosedForms) {
  const std::string head = "structure = { mass = 2.0, stiffness = 8e4 }\ndamping = { alpha = 3.0 }\n"
                           "[forcing]\namplitude = 10.0\nfrequency_hz = 25.0\n"
                           "[[forcing.loads]]\namplitude = 4.0\nphase_deg = 45.0\nharmonic = 2\n"
                           "[[forcing.loads]]\namplitude = 3.0\nharmonic = 0\n";
  const Scene scene = parse(head + "[basis]\nharmonics = 4\n[output]\nsamples = 32\n");
  ASSERT_EQ(scene.forcing->loads.size(), 2u);
  EXPECT_NEAR(scene.forcing->loads[0].phase_rad, std::numbers::pi / 4.0, 1e-15);
  const auto r = wbm::scene::run_analysis(scene);
  ASSERT_TRUE(r.converged);
  const Eigen::VectorXd& tau = column(r, "displacement.csv", 0);
  const Eigen::VectorXd& u = column(r, "displacement.csv", 2);
  const double w = 2.0 * std::numbers::pi * 25.0;
  auto response = [&](double f, double phase, int h, double t) {
    const std::complex<double> z(8e4 - h * h * w * w * 2.0, h * w * 6.0);
    return std::real(f * std::polar(1.0, phase + 2.0 * std::numbers::pi * h * t) / z);
  };
  for (Eigen::Index p = 0; p < tau.size(); ++p) {
    const double exact = response(10.0, 0.0, 1, tau(p)) + response(4.0, std::numbers::pi / 4.0, 2, tau(p)) +
                         response(3.0, 0.0, 0, tau(p));
    EXPECT_NEAR(u(p), exact, 1e-10 * std::abs(response(10.0, 0.0, 1, 0.0))) << p;
  }
  // phase_rad is the same phase; the resolved scene round-trips with its loads.
  const Scene rad = parse("structure = { mass = 2.0, stiffness = 8e4 }\ndamping = { alpha = 3.0 }\n"
                          "[forcing]\namplitude = 10.0\nfrequency_hz = 25.0\n"
                          "[[forcing.loads]]\namplitude = 4.0\nphase_rad = 0.78539816339744828\nharmonic = 2\n"
                          "[[forcing.loads]]\namplitude = 3.0\nharmonic = 0\n[basis]\nharmonics = 4\n[output]\nsamples = 32\n");
  EXPECT_EQ(column(wbm::scene::run_analysis(rad), "displacement.csv", 2), u);
  const nlohmann::json j = wbm::scene::to_json(scene);
  EXPECT_EQ(j["forcing"]["loads"].size(), 2u);
  EXPECT_EQ(wbm::scene::to_json(wbm::scene::scene_from_json(j, temp("loads.json"))), j);

  // A force vector on two uncoupled DOFs; the reported DOF is that of the largest load.
  write("f.mtx", "%%MatrixMarket matrix coordinate real general\n2 1 2\n1 1 5.0\n2 1 -2.0\n");
  const Scene vec = wbm::scene::load_scene(write("vector.toml",
      "structure = { mass = [1.0, 1.0], stiffness = [4e4, 9e4], damping = [2.0, 2.0], dofs = [\"p\", \"q\"] }\n"
      "forcing = { vector = \"f.mtx\", frequency_hz = 20.0 }\nbasis = { harmonics = 2 }\noutput = { samples = 16 }\n"));
  EXPECT_EQ(vec.forcing->dof, 0);
  EXPECT_EQ(vec.forcing->amplitude, 0.0);
  const auto rv = wbm::scene::run_analysis(vec);
  ASSERT_TRUE(rv.converged);
  const double wv = 2.0 * std::numbers::pi * 20.0;
  const Eigen::VectorXd& tv = column(rv, "displacement.csv", 0);
  for (Eigen::Index p = 0; p < tv.size(); ++p) {
    const auto phase = std::polar(1.0, 2.0 * std::numbers::pi * tv(p));
    EXPECT_NEAR(column(rv, "displacement.csv", 2)(p), std::real(5.0 * phase / std::complex<double>(4e4 - wv * wv, 2.0 * wv)), 1e-15);
    EXPECT_NEAR(column(rv, "displacement.csv", 3)(p), std::real(-2.0 * phase / std::complex<double>(9e4 - wv * wv, 2.0 * wv)), 1e-15);
  }

  const std::string one = "structure = { mass = 2.0, stiffness = 8e4 }\n[forcing]\namplitude = 1.0\nfrequency_hz = 5.0\n";
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(one + "[[forcing.loads]]\namplitude = 1.0\nphase_deg = 3.0\nphase_rad = 1.0\n"); },
      {"forcing.loads[0].phase_rad: given beside phase_deg"});
  expect_throw_with<std::invalid_argument>([&] { (void)parse(one + "[[forcing.loads]]\namplitude = 1.0\nharmonic = -1\n"); },
                                           {"forcing.loads[0].harmonic: value -1 out of range", "(0: a constant load"});
  expect_throw_with<std::invalid_argument>([&] { (void)parse(one + "loads = 3\n"); },
                                           {"forcing.loads: expected [[forcing.loads]] tables"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::scene::load_scene(write("bad_vector.toml", "structure = { mass = 2.0, stiffness = 8e4 }\n"
                                                               "forcing = { vector = \"f.mtx\", frequency_hz = 5.0 }\n")); },
      {"forcing.vector", "is 2 x 1; expected 1 x 1 (one amplitude per DOF)"});
}

// Progress of an nnm backbone: one report per accepted point of the energy continuation, the
// fraction of the energy range covered, and a label with the point, its energy and the step.
TEST(Scene, BackboneReportsProgressPerPoint) {
  const Scene s = wbm::scene::load_scene(std::filesystem::path(WBM_EXAMPLES) / "two_dof_nnm.toml");
  std::vector<std::pair<double, std::string>> reports;
  const auto r = wbm::scene::run_analysis(s, [&](double f, const std::string& label) { reports.emplace_back(f, label); });
  ASSERT_TRUE(r.converged);
  ASSERT_GE(reports.size(), 10u);
  EXPECT_EQ(reports.front().second.rfind("point 1, E = 0.5, step ", 0), 0u) << reports.front().second;
  EXPECT_NEAR(reports.front().first, 0.0, 1e-12);
  EXPECT_NEAR(reports.back().first, 1.0, 1e-9);  // E = 3 of [0.5, 3] reached
  // Every backbone level is an accepted point (levels and points are the same list here).
  EXPECT_EQ(reports.size(), static_cast<size_t>(column(r, "backbone.csv", 0).size()));
}

// Per point of a sweep and of a continuation branch: [output] observe and harmonics. Closed
// forms: the 2-DOF chain m = 1 kg, K = [[2k, −k], [−k, k]], C = αM, forced on "a", with a stop
// on "b" too far to be met, responds linearly, U = (K − ω²M + iωC)⁻¹ F e_a: A_1 = |U_j|,
// φ_1 = arg U_j, A_0 = A_2 = 0, and the amplitude columns of the observed DOF "b" are |U_b|.
TEST(Scene, ObservedDofsAndHarmonicsAlongASweepAndABranchMatchTheClosedForm) {
  const std::string head = "structure = { mass = [1.0, 1.0], stiffness = [[2e4, -1e4], [-1e4, 1e4]], dofs = [\"a\", \"b\"] }\n"
                           "damping = { alpha = 2.0 }\ncontact = { law = \"linear\", stiffness = 1e6, gap = 1.0, dof = \"b\" }\n"
                           "basis = { dimension = 8 }\n";
  auto exact = [](double hz) {
    const double w = 2.0 * std::numbers::pi * hz;
    Eigen::Matrix2cd d;
    d << std::complex<double>(2e4 - w * w, 2.0 * w), -1e4, -1e4, std::complex<double>(1e4 - w * w, 2.0 * w);
    return Eigen::Vector2cd(d.inverse() * Eigen::Vector2cd(10.0, 0.0));
  };
  const auto sweep = wbm::scene::run_analysis(parse(
      head + "forcing = { amplitude = 10.0, dof = \"a\", frequencies_hz = [5.0, 12.0, 30.0] }\n"
             "output = { samples = 64, harmonics = 2, observe = [\"b\", \"a\"] }\n"));
  ASSERT_TRUE(sweep.converged);
  // frequency_response.csv follows observe: b first; sweep_harmonics.csv: A0, φ0, A1, φ1, A2, φ2 per DOF.
  const Eigen::VectorXd& hz = column(sweep, "sweep_harmonics.csv", 0);
  ASSERT_EQ(hz.size(), 3);
  for (Eigen::Index i = 0; i < 3; ++i) {
    const Eigen::Vector2cd u = exact(hz(i));
    const double scale = u.cwiseAbs().maxCoeff();
    EXPECT_NEAR(column(sweep, "frequency_response.csv", 1)(i), std::abs(u(1)), 1e-3 * scale);  // max_u_b: sampled max
    EXPECT_NEAR(column(sweep, "sweep_harmonics.csv", 3)(i), std::abs(u(1)), 1e-12 * scale) << hz(i);
    EXPECT_NEAR(column(sweep, "sweep_harmonics.csv", 4)(i), std::arg(u(1)), 1e-9) << hz(i);
    EXPECT_NEAR(column(sweep, "sweep_harmonics.csv", 9)(i), std::abs(u(0)), 1e-12 * scale) << hz(i);
    EXPECT_NEAR(column(sweep, "sweep_harmonics.csv", 10)(i), std::arg(u(0)), 1e-9) << hz(i);
    for (size_t c : {1u, 5u, 7u, 11u}) EXPECT_LT(std::abs(column(sweep, "sweep_harmonics.csv", c)(i)), 1e-12 * scale) << c;
  }
  const auto branch = wbm::scene::run_analysis(parse(
      head + "forcing = { amplitude = 10.0, dof = \"a\", frequency_hz = [5.0, 30.0] }\n"
             "analysis = { type = \"continuation\", stability = false, max_frequency_step_hz = 1.0 }\n"
             "output = { samples = 256, harmonics = 1, observe = [\"a\", \"b\"] }\n"));
  ASSERT_TRUE(branch.converged);
  const Eigen::VectorXd& f = column(branch, "branch.csv", 0);
  const Eigen::VectorXd& amplitude_b = column(branch, "branch.csv", 8);  // after corrector_iterations: b's max, min, amplitude
  const Eigen::VectorXd& a1_b = column(branch, "branch_harmonics.csv", 7);
  ASSERT_GE(f.size(), 25);
  for (Eigen::Index i = 0; i < f.size(); ++i) {
    const Eigen::Vector2cd u = exact(f(i));
    EXPECT_NEAR(amplitude_b(i), std::abs(u(1)), 1e-3 * std::abs(u(1))) << f(i);
    EXPECT_NEAR(a1_b(i), std::abs(u(1)), 1e-9 * std::abs(u(1))) << f(i);
    EXPECT_NEAR(column(branch, "branch_harmonics.csv", 3)(i), std::abs(u(0)), 1e-9 * std::abs(u(0))) << f(i);
  }
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(head + "forcing = { amplitude = 10.0, dof = \"a\", frequency_hz = 5.0 }\noutput = { observe = [\"b\"] }\n"); },
      {"output.observe: the DOFs reported per point of a sweep or a continuation branch", "output.dofs"});
}

// [basis] harmonic_selection = "odd": on a 1-DOF oscillator between two symmetric stops (odd in
// u) the odd-harmonic branch is the full one and drops nothing (half-wave symmetry); with one
// stop the branch says how much it drops where the stop is touched and nothing where it is not.
// The selection is echoed, round-trips through JSON, and what cannot be projected is refused.
TEST(Scene, OddHarmonicSelectionOfASymmetricOscillatorIsTheFullBranch) {
  const std::string oscillator =
      "structure = { mass = [1.0], stiffness = [4e4] }\ndamping = { beta = 2e-4 }\n"
      "forcing = { amplitude = 30.0, frequency_hz = [25.0, 40.0] }\n"
      "analysis = { type = \"continuation\", stability = false }\n";
  const std::string plus = "[[contact]]\nlaw = \"linear\"\nstiffness = 4e5\ngap = 1e-3\ndof = 0\n";
  const std::string minus = plus + "direction = -1\n";
  const std::string odd = "[basis]\nharmonics = 9\nharmonic_selection = \"odd\"\n";
  const std::string all = "[basis]\nharmonics = 9\n";
  const auto full = wbm::scene::run_analysis(parse(oscillator + all + plus + minus));
  const Scene odd_scene = parse(oscillator + odd + plus + minus);
  EXPECT_EQ(odd_scene.basis.selected_harmonics, (std::vector<int>{1, 3, 5, 7, 9}));
  const auto sel = wbm::scene::run_analysis(odd_scene);
  ASSERT_TRUE(full.converged && sel.converged);
  const Eigen::VectorXd& f_full = column(full, "branch.csv", 0);
  const Eigen::VectorXd& f_sel = column(sel, "branch.csv", 0);
  ASSERT_EQ(f_full.size(), f_sel.size());
  EXPECT_LT((f_full - f_sel).cwiseAbs().maxCoeff(), 1e-6);
  const Eigen::VectorXd& a_full = column(full, "branch.csv", 3);
  EXPECT_GT(a_full.maxCoeff(), 1.2e-3);  // both stops (gap 1 mm) are reached
  EXPECT_LT((a_full - column(sel, "branch.csv", 3)).cwiseAbs().maxCoeff(), 1e-8 * a_full.maxCoeff());
  const auto header = [](const wbm::scene::AnalysisResult& r) {
    for (const auto& t : r.tables) {
      if (t.file == "branch.csv") return t.header;
    }
    return std::vector<std::string>{};
  };
  ASSERT_EQ(header(sel).at(5), "dropped_harmonics_residual [-]");
  EXPECT_NE(header(full).at(5), "dropped_harmonics_residual [-]");
  EXPECT_LT(column(sel, "branch.csv", 5).maxCoeff(), 1e-9);
  const nlohmann::json j = wbm::scene::to_json(odd_scene);
  EXPECT_EQ(j["basis"]["harmonic_selection"], "odd");
  EXPECT_EQ(wbm::scene::to_json(wbm::scene::scene_from_json(j, temp("odd.json"))), j);

  const auto one = wbm::scene::run_analysis(parse(oscillator + odd + plus));
  ASSERT_TRUE(one.converged);
  const Eigen::VectorXd& dropped = column(one, "branch.csv", 5);
  const Eigen::VectorXd& force = column(one, "branch.csv", 4);
  for (Eigen::Index i = 0; i < dropped.size(); ++i) {
    if (force(i) == 0.0) {
      EXPECT_EQ(dropped(i), 0.0);
    }
  }
  EXPECT_GT(dropped.maxCoeff(), 1e-2);
  const auto warned = [](const wbm::scene::AnalysisResult& r) {
    return std::any_of(r.warnings.begin(), r.warnings.end(),
                       [](const std::string& w) { return w.find("harmonics outside the selection") != std::string::npos; });
  };
  EXPECT_TRUE(warned(one));
  EXPECT_FALSE(warned(sel));

  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(oscillator + "[basis]\nharmonics = 9\nharmonic_selection = \"even\"\n" + plus); },
      {"basis.harmonic_selection", "\"even\" is not a selection", "\"odd\""});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(oscillator + "[basis]\nharmonics = 9\nharmonic_selection = [1, 10]\n" + plus); },
      {"basis.harmonic_selection", "[0, 9]"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(oscillator + "[basis]\nharmonics = 9\nharmonic_selection = [0, 3]\n" + plus); },
      {"drops harmonic 1, at which a load acts on DOF dof0", "keep harmonic 1"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(oscillator + "[basis]\ntrial = \"db6\"\ndimension = 32\nharmonic_selection = \"odd\"\n" + plus); },
      {"basis.harmonic_selection", "wavelet bases have no harmonics"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse(oscillator + odd + "[[contact]]\nlaw = \"rigid\"\ngap = 1e-3\ndof = 0\n"); },
      {"basis.harmonic_selection", "rigid stops", "law = \"linear\""});
}
