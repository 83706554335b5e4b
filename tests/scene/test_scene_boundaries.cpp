// The edges of the scenes (issue #40): input that used to run and "converge" to a wrong answer
// is refused at parse time (what `wbm check` and `wbm run` read), with the key, the value, the
// allowed range and the way out; what is allowed near the edge still gives the closed form.
#include <cmath>
#include <complex>
#include <filesystem>
#include <numbers>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <unistd.h>

#include <wbm/scene/analysis.hpp>
#include <wbm/scene/resources.hpp>
#include <wbm/scene/scene.hpp>

#include "testing.hpp"

namespace {

using wbm::testing::expect_throw_with;

wbm::scene::Scene parse_boundaries(const std::string& text) {
  return wbm::scene::parse_scene(text, std::filesystem::temp_directory_path() / "wbm_boundaries.toml");
}

// The oscillator: 1 kg on 40 kN/m, α = 5 s⁻¹, a 5 N load at a harmonic h of f = 10 Hz.
std::string oscillator(int harmonic, const std::string& basis) {  // basis: top-level keys and tables
  return "structure = { mass = [1.0], stiffness = [4e4] }\ndamping = { alpha = 5.0 }\n" + basis +
         "[forcing]\nfrequency_hz = 10.0\n[[forcing.loads]]\namplitude = 5.0\ndof = 0\nharmonic = " +
         std::to_string(harmonic) + "\n";
}

double column_rms(const wbm::scene::AnalysisResult& r, const std::string& file, const std::string& header) {
  for (const auto& t : r.tables) {
    if (t.file != file) continue;
    for (size_t c = 0; c < t.header.size(); ++c) {
      if (t.header[c] == header) return std::sqrt(t.columns[c].squaredNorm() / static_cast<double>(t.columns[c].size()));
    }
  }
  ADD_FAILURE() << "no column " << header << " in " << file;
  return 0.0;
}

}  // namespace

// Item 1: harmonic 250 on H = 32 ran, said "converged" and put the response at h = 6. Now the
// highest harmonic the basis resolves (H = 32 of M = 65 functions) gives the closed form
// A = F/|k − Ω² m + iΩc|, Ω = 2π·32·f, and anything above is refused naming the fix.
TEST(SceneBoundaries, ALoadAboveTheBasisHarmonicsIsRefusedWithTheWayOut) {
  const auto top = wbm::scene::run_analysis(parse_boundaries(oscillator(32, "[basis]\nharmonics = 32\n")));
  ASSERT_TRUE(top.converged()) << top.summary;
  const double w = 2.0 * std::numbers::pi * 32 * 10.0;
  const double exact = 5.0 / std::abs(std::complex<double>(4e4 - w * w, 5.0 * w));
  EXPECT_NEAR(std::sqrt(2.0) * column_rms(top, "displacement.csv", "u_dof0 [m]"), exact, 1e-6 * exact);
  for (const int h : {33, 250, 1000}) {
    expect_throw_with<std::invalid_argument>(
        [&] { (void)parse_boundaries(oscillator(h, "[basis]\nharmonics = 32\n")); },
        {"forcing.loads[0].harmonic", std::to_string(h) + " is above the highest harmonic 32",
         "raise [basis] harmonics to at least " + std::to_string(h)});
  }
  expect_throw_with<std::invalid_argument>([&] { (void)parse_boundaries(oscillator(32, "[basis]\ntrial = \"db6\"\nlevel = 6\n")); },
                                           {"highest harmonic 31", "raise [basis] dimension (or level) above 64"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse_boundaries(oscillator(32, "analysis = { type = \"timestep\" }\n[output]\nsamples = 64\n")); },
      {"the 64 output samples per period", "raise [output] samples above 64"});
  // The forcing's own harmonic-1 load on one function (level = 0, M = 1).
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)parse_boundaries("structure = { mass = [1.0], stiffness = [4e4] }\nforcing = { amplitude = 1.0, frequency_hz = 10.0 }\n"
                    "[basis]\ntrial = \"haar\"\nweighting = \"fourier\"\nlevel = 0\n");
      },
      {"basis.dimension", "cannot carry the forcing at harmonic 1"});
}

// Item 5: a negative stiffness "converged"; K = 0 at f = 1e300 said "G singular (forcing at an
// undamped natural frequency?)". K must be positive semidefinite; rigid-body modes need a stop.
TEST(SceneBoundaries, StiffnessMustBeSemidefiniteAndRigidBodyModesNeedAStop) {
  const std::string forcing = "forcing = { amplitude = 1.0, frequency_hz = 10.0, dof = 0 }\n";
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse_boundaries("structure = { mass = [1.0], stiffness = [-4e4] }\n" + forcing); },
      {"structure.stiffness", "K is not positive semidefinite", "1 eigenvalue(s) ω² < 0"});
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)parse_boundaries("structure = { mass = [[1.0, 0.0], [0.0, 1.0]], stiffness = [[1.0, 2.0], [2.0, 1.0]] }\n" + forcing);
      },
      {"K is not positive semidefinite", "1 eigenvalue(s)"});  // eigenvalues 3 and −1
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse_boundaries("structure = { mass = [1.0], stiffness = [0.0] }\nforcing = { amplitude = 1.0, frequency_hz = 1e300 }\n"); },
      {"structure.stiffness", "1 rigid-body mode(s)", "no [[contact]] holds them"});
  // Two masses on one spring: one rigid-body mode, held by a stop: a warning, and the run goes on.
  const auto held = parse_boundaries("structure = { mass = [[1.0, 0.0], [0.0, 2.0]], stiffness = [[1e4, -1e4], [-1e4, 1e4]] }\n" +
                          forcing + "[[contact]]\nlaw = \"linear\"\nstiffness = 1e5\ngap = 0.0\ndof = 0\n");
  ASSERT_EQ(held.warnings.size(), 1U);
  EXPECT_NE(held.warnings[0].find("1 rigid-body mode(s)"), std::string::npos) << held.warnings[0];
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)parse_boundaries("structure = { mass = [[1.0, 0.0], [0.0, 2.0]], stiffness = [[1e4, -1e4], [-1e4, 1e4]] }\n"
                    "analysis = { type = \"nnm\", energy = [0.5, 2.0] }\n[[contact]]\nlaw = \"rigid\"\ngap = 1e-3\ndof = 0\n");
      },
      {"analysis \"nnm\" continues the first mode"});
  // A frequency at which (2π H f)² M overflows is out of range, said so, not "G singular".
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)wbm::scene::run_analysis(
            parse_boundaries("structure = { mass = [1.0], stiffness = [4e4] }\nforcing = { amplitude = 1.0, frequency_hz = 1e300 }\n"));
      },
      {"frequency_hz = 1e+300 Hz", "overflows"});
}

// Item 4: sizes the parser accepted but no machine here can run ended in "std::bad_alloc" after
// `wbm check` said valid. They are refused at parse time with the estimate and the key; a
// max_step below the continuation's minimum step is refused with its range, not an internal
// "PseudoArclengthOptions.steps" message.
TEST(SceneBoundaries, SizesTheMachineCannotServeAreRefusedWithTheEstimate) {
  if (wbm::scene::physical_memory_bytes() > 160e9) GTEST_SKIP() << "a machine with more than 160 GB";
  const std::string rod = "[structure]\nyoung_modulus = 70e9\ndensity = 2700.0\narea = 25e-4\nlength = 1.0\n";
  const std::string forcing = "[forcing]\namplitude = 1.0\nfrequency_hz = 150.0\n";
  expect_throw_with<std::invalid_argument>([&] { (void)parse_boundaries(rod + "elements = 100000\n" + forcing); },
                                           {"structure.elements: the analysis would need about", "GB of memory"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse_boundaries(rod + "elements = 25\n" + forcing + "[basis]\ndimension = 1048576\n"); },
      {"basis.dimension: the analysis would need about", "lower basis.dimension"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse_boundaries(rod + "elements = 25\n" + forcing + "[basis]\nharmonics = 524288\n"); },
      {"basis.harmonics: the analysis would need"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)parse_boundaries(rod + "elements = 25\n" + forcing + "[output]\nsamples = 4194304\n"); },
      {"output.samples: 4194304 samples per period would write about", "lower output.samples"});
  // Near the edge, still accepted: 2000 elements (32 MB for the modal problem), M = 4096.
  EXPECT_NO_THROW((void)parse_boundaries(rod + "elements = 2000\n" + forcing));
  EXPECT_NO_THROW((void)parse_boundaries(rod + "elements = 25\n" + forcing + "[basis]\ndimension = 4096\n"));
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)parse_boundaries("structure = { mass = [1.0], stiffness = [4e4] }\nforcing = { amplitude = 1.0, frequency_hz = [20.0, 40.0] }\n"
                    "analysis = { type = \"continuation\", max_step = 1e-9 }\n"
                    "contact = { law = \"linear\", stiffness = 4e5, gap = 1e-4 }\n");
      },
      {"analysis.max_step", "in [1e-6, 1]"});
}

// Item 4, nnm: 512 harmonics on one DOF was still running after 90 s; N is capped at 256.
TEST(SceneBoundaries, NonlinearModesTakeAtMost256Harmonics) {
  const std::string nnm = "structure = { mass = [1.0], stiffness = [4e4] }\n"
                          "contact = { law = \"rigid\", gap = 1e-3, dof = 0 }\n"
                          "analysis = { type = \"nnm\", energy = [0.5, 2.0], harmonics = ";
  expect_throw_with<std::invalid_argument>([&] { (void)parse_boundaries(nnm + "512 }\n"); },
                                           {"analysis.harmonics", "256", "N = 512 minutes"});
  EXPECT_EQ(parse_boundaries(nnm + "256 }\n").analysis.harmonics, 256);
}
