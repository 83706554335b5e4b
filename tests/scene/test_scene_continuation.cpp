// Scenes that trace a branch (wbm::scene, type = continuation and nnm): harmonic balance by
// default, the stiff stop, unit independence, closed-form branches, progress and observed DOFs
// along a branch, an odd harmonic selection.
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
  ASSERT_TRUE(r.converged()) << r.summary;
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
  // The changes of stability (bifurcations.csv, issue #39): at a turning point of a branch a real
  // Floquet multiplier passes +1 (the saddle-node theorem), so the branch loses stability at the
  // upper fold and regains it at the lower one, each a "fold" whose crossing lies within four
  // points of the fold (the truncated orbit's crossing may lag it: ResponseCurve::fold_confirmed),
  // here within 0.2 Hz, with |μ| > 1 and arg μ = 0 on the unstable side; result.json lists the same.
  const wbm::scene::Table* crossings = nullptr;
  for (const auto& t : r.tables) {
    if (t.file == "bifurcations.csv") crossings = &t;
  }
  ASSERT_TRUE(crossings != nullptr);
  ASSERT_EQ(crossings->status.size(), 2u);
  ASSERT_EQ(crossings->header.at(0), "frequency [Hz]");
  ASSERT_EQ(crossings->header.at(6), "stability_lost [-]");
  for (Eigen::Index k = 0; k < 2; ++k) {
    EXPECT_EQ(crossings->status[static_cast<size_t>(k)], "fold") << k;
    EXPECT_NEAR(crossings->columns[0](k), hz(k), 0.2) << k;
    EXPECT_GT(crossings->columns[4](k), 1.0) << k;
    EXPECT_LT(std::abs(crossings->columns[5](k)), 1e-6) << k;
    EXPECT_LE(std::min(crossings->columns[1](k), crossings->columns[2](k)), crossings->columns[0](k)) << k;
    EXPECT_GE(std::max(crossings->columns[1](k), crossings->columns[2](k)), crossings->columns[0](k)) << k;
  }
  EXPECT_EQ(crossings->columns[6](0), 1.0);  // lost at the upper fold
  EXPECT_EQ(crossings->columns[6](1), 0.0);  // regained at the lower one
  const auto& listed = r.diagnostics.at("continuation").at("bifurcations");
  ASSERT_EQ(listed.size(), 2u);
  EXPECT_EQ(listed[0].at("kind"), "fold");
  EXPECT_EQ(listed[0].at("stability"), "lost");
  EXPECT_EQ(listed[1].at("stability"), "regained");
  EXPECT_DOUBLE_EQ(listed[1].at("frequency_hz").get<double>(), crossings->columns[0](1));
  for (const std::string basis : {"basis = { harmonics = 32, time_samples = 1024 }\n", "basis = { harmonics = 64 }\n"}) {
    const auto finer = wbm::scene::run_analysis(parse(head + basis));
    ASSERT_TRUE(finer.converged()) << basis << finer.summary;
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
  ASSERT_TRUE(r.converged()) << r.summary;
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
  ASSERT_TRUE(a.converged()) << a.summary;
  ASSERT_TRUE(b.converged()) << b.summary;
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
  ASSERT_TRUE(r.converged()) << r.diagnostics.dump(2);
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

// A stop that is not a computed outcome names the key that gets past it (issue #35, item 4): the
// point limit of a frequency continuation and of a backbone, each with its value now and one to
// try; a complete run adds nothing.
TEST(Scene, AStopThatIsNotAnOutcomeNamesTheKeyToChange) {
  const std::string text = "structure = { mass = 2.0, stiffness = 8e4 }\ndamping = { alpha = 3.0 }\n"
                           "forcing = { amplitude = 10.0, frequency_hz = [5.0, 55.0] }\n"
                           "contact = { law = \"linear\", stiffness = 1e6, gap = 1.0 }\n"
                           "basis = { dimension = 8 }\n";
  const auto cut = wbm::scene::run_analysis(parse(text + "analysis = { type = \"continuation\", max_points = 3 }\n"));
  EXPECT_FALSE(cut.converged());
  // One vocabulary (issue #41): the branch's stop and a status, not a bool, in the result.
  EXPECT_EQ(cut.status, wbm::solvers::SolveStatus::PathEnded);
  ASSERT_TRUE(cut.stop.has_value());
  EXPECT_EQ(*cut.stop, wbm::solvers::StopReason::MaxPoints);
  EXPECT_EQ(cut.diagnostics["status"], "path-ended");
  EXPECT_EQ(cut.diagnostics["stop"], "point limit reached");
  const std::string message = cut.diagnostics["continuation"]["message"].get<std::string>();
  EXPECT_NE(message.find("way out: raise [analysis] max_points (now 3), e.g. to 6"), std::string::npos) << message;
  const auto full = wbm::scene::run_analysis(parse(text + "analysis = { type = \"continuation\" }\n"));
  ASSERT_TRUE(full.converged());
  EXPECT_EQ(full.diagnostics["continuation"]["message"].get<std::string>().find("way out"), std::string::npos);

  Scene nnm = wbm::scene::load_scene(std::filesystem::path(WBM_EXAMPLES) / "two_dof_nnm.toml");
  nnm.analysis.max_points = 4;
  const auto b = wbm::scene::run_analysis(nnm);
  EXPECT_FALSE(b.converged());
  ASSERT_TRUE(b.stop.has_value());
  EXPECT_EQ(*b.stop, wbm::solvers::StopReason::MaxPoints);
  const std::string nnm_message = b.diagnostics["nnm"]["message"].get<std::string>();
  EXPECT_NE(nnm_message.find("way out: raise [analysis] max_points (now 4), e.g. to 8"), std::string::npos) << nnm_message;
}

// A corrector that stalls at its rounding floor is not a singular point: the way out is the
// tolerance, not a shorter step. examples/scenes/rod_continuation.toml with [solver] tolerance =
// 3e-16, below what a double-precision residual of O(1) resolves: the branch starts, then the
// step falls below its minimum with the corrector within 10× of the residual's rounding floor, and
// the message names [solver] tolerance and the residual it met (and no contact-quadrature hint).
TEST(Scene, ACorrectorAtItsRoundingFloorNamesTheTolerance) {
  Scene s = wbm::scene::load_scene(std::filesystem::path(WBM_EXAMPLES) / "rod_continuation.toml");
  s.solver.newton.tolerance = 3e-16;
  const auto r = wbm::scene::run_analysis(s);
  ASSERT_TRUE(r.stop.has_value());
  ASSERT_EQ(*r.stop, wbm::solvers::StopReason::StepBelowMinimum) << r.diagnostics.dump();
  const std::string message = r.diagnostics["continuation"]["message"].get<std::string>();
  EXPECT_NE(message.find("way out: raise [solver] tolerance (now 3e-16) above the corrector's rounding floor"),
            std::string::npos) << message;
  EXPECT_EQ(message.find("max_step"), std::string::npos) << message;
  EXPECT_EQ(message.find("contact_quadrature"), std::string::npos) << message;
}

// Progress of an nnm backbone: one report per accepted point of the energy continuation, the
// fraction of the energy range covered, and a label with the point, its energy and the step.
TEST(Scene, BackboneReportsProgressPerPoint) {
  Scene s = wbm::scene::load_scene(std::filesystem::path(WBM_EXAMPLES) / "two_dof_nnm.toml");
  s.analysis.stability = false;  // the levels' stability reports its own progress after the branch
  std::vector<std::pair<double, std::string>> reports;
  const auto r = wbm::scene::run_analysis(s, [&](double f, const std::string& label) { reports.emplace_back(f, label); });
  ASSERT_TRUE(r.converged());
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
  ASSERT_TRUE(sweep.converged());
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
  ASSERT_TRUE(branch.converged());
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
  ASSERT_TRUE(full.converged() && sel.converged());
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
  ASSERT_TRUE(one.converged());
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

// A rigid stop continued with stability (issue #38): branch.csv gives each point the verdict of
// the exact orbit with plastic impacts near it. The 1-DOF impact oscillator (k g0/F = ½) from 8 to
// 20 Hz: a point whose orbit never reaches the stop has the linear oscillator's |μ| = e^{−ζω_n/f},
// one whose orbit has a contact phase Φ = 0 (the state leaves the stop at the same (g0, 0) every
// period: below 13.5 Hz); a point without a verdict has empty cells, the status "unavailable" and a warning.
TEST(Scene, RigidStopContinuationGivesTheExactOrbitsStability) {
  const double k = std::pow(2.0 * std::numbers::pi * 10.0, 2), c = 2.0 * 0.05 * std::sqrt(k);
  char text[512];
  std::snprintf(text, sizeof text,
                "structure = { mass = 1.0, stiffness = %.17g }\ndamping = { alpha = 0.0, beta = %.17g }\n"
                "forcing = { amplitude = 10.0, frequency_hz = [8.0, 20.0] }\n"
                "contact = { law = \"rigid\", gap = %.17g }\nbasis = { dimension = 64 }\n"
                "analysis = { type = \"continuation\", max_step = 0.05 }\n",
                k, c / k, 5.0 / k);
  const auto r = wbm::scene::run_analysis(parse(text), nullptr);
  ASSERT_TRUE(r.converged()) << r.diagnostics.dump(2);
  const wbm::scene::Table* branch = nullptr;
  for (const auto& t : r.tables) branch = t.file == "branch.csv" ? &t : branch;
  ASSERT_NE(branch, nullptr);
  const auto at = [&](const std::string& name) {
    const auto i = std::find(branch->header.begin(), branch->header.end(), name) - branch->header.begin();
    EXPECT_LT(static_cast<size_t>(i), branch->header.size()) << name;
    return branch->columns.at(static_cast<size_t>(i));
  };
  EXPECT_EQ(std::count(branch->header.begin(), branch->header.end(), "monodromy_steps [-]"), 0);
  const Eigen::VectorXd hz = at("frequency [Hz]"), stable = at("stable [-]"), mu = at("max_floquet_multiplier [-]");
  const Eigen::VectorXd impacts = at("impacts_per_period [-]"), distance = at("shooting_distance [-]");
  const double zeta_wn = c / 2.0;
  int free = 0, phase = 0, none = 0;
  for (Eigen::Index i = 0; i < hz.size(); ++i) {
    if (branch->status[static_cast<size_t>(i)] == "unavailable") {
      ++none;
      EXPECT_TRUE(std::isnan(stable(i)) && std::isnan(mu(i)));
      continue;
    }
    EXPECT_LE(distance(i), 0.1);
    if (impacts(i) == 0.0) {
      ++free;
      EXPECT_NEAR(mu(i), std::exp(-zeta_wn / hz(i)), 1e-9) << hz(i);
    } else if (hz(i) < 13.5) {  // measured: from 14 Hz on the impact no longer closes the stop (0 < |μ| < 1)
      ++phase;
      EXPECT_LT(mu(i), 1e-10) << hz(i);
    }
  }
  EXPECT_GT(free, 5);
  EXPECT_GT(phase, 100);
  EXPECT_GT(none, 0) << "the grazing stretch (14–17.6 Hz) has points without an exact orbit near them";
  EXPECT_EQ(none, r.diagnostics["continuation"]["unavailable_stability_points"].get<int>());
  const bool warned = std::any_of(r.warnings.begin(), r.warnings.end(),
                                  [](const std::string& w) { return w.find("no stability verdict") != std::string::npos; });
  EXPECT_EQ(warned, none > 0);
}
