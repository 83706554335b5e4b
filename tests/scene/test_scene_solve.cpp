// Scenes that solve at given frequencies (wbm::scene, type = solve, timestep, basis-plot): the
// analyses agree with closed forms, with Moreau–Jean and with one another (mirrored stops, contacts
// between two DOFs, massless nodes, several loads, frequencies in rad/s).
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

// 1-DOF oscillator (the five-line scene of docs/scenes.md, no contact): the solve equals the
// closed-form amplitude F/|k − mω² + iωc| with c = αm, at one frequency and over a sweep.
TEST(Scene, OscillatorSolveAndSweepMatchClosedForm) {
  const double m = 2.0, k = 8e4, alpha = 3.0, f = 10.0;
  const std::string head = "structure = { mass = 2.0, stiffness = 8e4 }\ndamping = { alpha = 3.0 }\n";
  const auto one = wbm::scene::run_analysis(parse(head + "forcing = { amplitude = 10.0, frequency_hz = 25.0 }\n"));
  ASSERT_TRUE(one.converged());
  // Fourier coefficients {1, cos 2πτ, sin 2πτ, …}: the amplitude is √(a₁² + a₂²).
  const Eigen::VectorXd& a = column(one, "coefficients.csv", 1);
  const double exact = oscillator_amplitude(m, alpha * m, k, f, 25.0);
  EXPECT_NEAR(std::hypot(a(1), a(2)), exact, 1e-12 * exact);
  EXPECT_NEAR(a.cwiseAbs().sum() - std::abs(a(1)) - std::abs(a(2)), 0.0, 1e-12 * exact);  // no other harmonic
  const auto sweep = wbm::scene::run_analysis(
      parse(head + "forcing = { amplitude = 10.0, frequency_hz = [5.0, 55.0], points = 11 }\n"
                   "basis = { dimension = 8 }\noutput = { samples = 4096 }\n"));
  ASSERT_TRUE(sweep.converged());
  const Eigen::VectorXd& hz = column(sweep, "frequency_response.csv", 0);
  const Eigen::VectorXd& max_u = column(sweep, "frequency_response.csv", 1);
  ASSERT_EQ(hz.size(), 11);
  for (Eigen::Index i = 0; i < hz.size(); ++i) {
    // The maximum over 4096 samples of a cosine: within 1 − cos(π/4096) of its amplitude.
    const double a = oscillator_amplitude(m, alpha * m, k, f, hz(i));
    EXPECT_NEAR(max_u(i), a, 1e-6 * a) << hz(i) << " Hz";
  }
}

// [solver] residual_tolerance is the bound the full residual's backward error is verified against
// (never above ‖R‖/‖b‖, both reported), echoed in the
// resolved scene and per solve: the oscillator against a stop meets the default 1e-8; a bound
// below what double precision can reach (1e-30) is reported as not converged (never converged
// by hand), with the residual it reached; 0 is refused naming the key.
TEST(Scene, TheResidualToleranceIsAnOptionReportedAsUsed) {
  const std::string head = "structure = { mass = 1.0, stiffness = 4e4 }\ndamping = { alpha = 5.0 }\n"
                           "forcing = { amplitude = 5.0, frequency_hz = 30.0 }\n"
                           "contact = { law = \"linear\", stiffness = 4e5, gap = 2e-3 }\n";
  const auto plain = wbm::scene::run_analysis(parse(head));
  ASSERT_TRUE(plain.converged());
  EXPECT_EQ(plain.diagnostics["solution"]["residual_tolerance"].get<double>(), 1e-8);
  EXPECT_LE(plain.diagnostics["solution"]["relative_residual"].get<double>(), 1e-8);
  EXPECT_LE(plain.diagnostics["solution"]["backward_error"].get<double>(),
            plain.diagnostics["solution"]["relative_residual"].get<double>());
  const auto loose = parse(head + "solver = { residual_tolerance = 1e-7 }\n");
  EXPECT_EQ(wbm::scene::to_json(loose)["solver"]["residual_tolerance"].get<double>(), 1e-7);
  EXPECT_EQ(wbm::scene::run_analysis(loose).diagnostics["solution"]["residual_tolerance"].get<double>(), 1e-7);
  const auto tight = wbm::scene::run_analysis(parse(head + "solver = { residual_tolerance = 1e-30 }\n"));
  EXPECT_FALSE(tight.converged());
  EXPECT_GT(tight.diagnostics["solution"]["backward_error"].get<double>(), 1e-30);
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

// Time stepping from a scene: BDF on the same oscillator reaches the closed-form amplitude.
TEST(Scene, TimestepMatchesClosedForm) {
  const auto r = wbm::scene::run_analysis(parse("structure = { mass = 2.0, stiffness = 8e4 }\n"
                                                "damping = { alpha = 30.0 }\n"
                                                "forcing = { amplitude = 10.0, frequency_hz = 25.0 }\n"
                                                "analysis = { type = \"timestep\" }\n"
                                                "output = { samples = 8192 }\n"));
  ASSERT_TRUE(r.converged()) << r.diagnostics.dump(2);
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
  ASSERT_TRUE(solve.converged()) << solve.diagnostics.dump(2);
  const auto step = wbm::scene::run_analysis(parse(rod + "[analysis]\ntype = \"timestep\"\n"));
  ASSERT_TRUE(step.converged()) << step.diagnostics.dump(2);
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
  ASSERT_TRUE(r.converged()) << r.diagnostics.dump(2);
  ASSERT_TRUE(w.converged()) << w.diagnostics.dump(2);
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
    ASSERT_TRUE(plus.converged() && minus.converged()) << law;
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
  ASSERT_TRUE(plus.converged() && minus.converged());
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
  ASSERT_TRUE(one.converged());
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
    ASSERT_TRUE(sweep.converged()) << key;
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
  ASSERT_TRUE(linear.converged());
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
  ASSERT_TRUE(stop.converged());
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
    ASSERT_TRUE(closed.converged()) << basis << closed.diagnostics.dump();
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
    ASSERT_TRUE(open.converged()) << basis;
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
    ASSERT_TRUE(bdf.converged()) << bdf.diagnostics.dump();
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
  ASSERT_TRUE(one.converged() && two.converged());
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
  ASSERT_TRUE(r.converged());
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
  ASSERT_TRUE(rv.converged());
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
