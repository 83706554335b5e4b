// A Jenkins element with two tangents in a scene (`second_tangent`, issue #36), on the shipped
// examples/scenes/friction_disc.toml. Truths not produced by this code: the closed-form circular
// steady state under the rotating force (the slider on the circle r_s = √(a² − (F_s/k_t)²), the
// energy 2π r_s F_s per cycle, a from the scalar equation of tests/solvers/test_friction_disc.cpp);
// the energy balance over a cycle, work of the loads = viscous + friction dissipation; and the
// explicit time stepping of the same scene, which shares only the law with the weighted residual.
#include <cmath>
#include <complex>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <wbm/contact/jenkins_disc.hpp>
#include <wbm/scene/analysis.hpp>
#include <wbm/scene/scene.hpp>

#include "scene_fixtures.hpp"
#include "testing.hpp"

using wbm::scene::Scene;
using namespace wbm::testing;  // scene_fixtures.hpp, testing.hpp

namespace {

const std::string kDisc = std::string(WBM_EXAMPLES) + "/friction_disc.toml";

// The example with its analysis replaced (one frequency).
std::string disc_at(double hz, const std::string& analysis) {
  std::string text = slurp(kDisc);
  text.replace(text.find("frequency_hz = [5.0, 20.0]"), 26, "frequency_hz = " + std::to_string(hz));
  text = text.substr(0, text.find("[analysis]"));
  return text + "[analysis]\n" + analysis;
}

// The closed-form orbit radius of the scene's isotropic oscillator at hz (bisection on a |D(a)| = F).
double closed_form_radius(const Scene& s, double hz) {
  const auto sys = s.system();
  const double m = sys.mass.coeff(0, 0), k = sys.stiffness.coeff(0, 0), c = sys.damping.coeff(0, 0);
  const double kt = s.contacts[0].tangential_stiffness, fs = s.contacts[0].friction_coefficient * s.contacts[0].normal_load;
  const double w = 2.0 * kPi * hz, force = s.forcing->amplitude;
  const auto residual = [&](double a) {
    const double rs = std::sqrt(a * a - (fs / kt) * (fs / kt)), beta = fs / (kt * rs);
    const std::complex<double> i(0.0, 1.0);
    return a * std::abs(k - m * w * w + i * w * c + kt * i * beta / (1.0 + i * beta)) - force;
  };
  double lo = fs / kt * (1.0 + 1e-12), hi = 1.0;
  for (int it = 0; it < 200; ++it) (residual(0.5 * (lo + hi)) < 0.0 ? lo : hi) = 0.5 * (lo + hi);
  return 0.5 * (lo + hi);
}

}  // namespace

TEST(SceneFrictionDisc, TheKeyMakesTwoContactsThatShareOneDisc) {
  const Scene s = wbm::scene::load_scene(kDisc);
  ASSERT_EQ(s.contacts.size(), 2u);
  EXPECT_EQ(s.contacts[0].second_tangent, 1);
  EXPECT_EQ(s.contacts[1].second_tangent, 0);
  EXPECT_EQ(s.contacts[1].dof, 1);
  const auto points = s.contact_points();
  EXPECT_EQ(points[0].law.get(), points[1].law.get());
  EXPECT_NE(dynamic_cast<const wbm::contact::JenkinsDiscLaw*>(points[0].law.get()), nullptr);
  EXPECT_EQ(points[0].second_tangent, 1);
  EXPECT_EQ(points[1].second_tangent, 0);
  EXPECT_EQ(wbm::scene::to_json(s)["contact"][0]["second_tangent_contact"], 1);

  const auto refused = [](const std::string& text, std::vector<std::string> fragments) {
    expect_throw_with<std::invalid_argument>([&] { (void)parse(text); }, fragments);
  };
  // The example's text with `from` replaced by `to` in its tables (its header comment names the keys too).
  const auto edited = [](const std::string& from, const std::string& to) {
    std::string text = slurp(kDisc);
    const size_t at = text.find(from, text.find("[structure]"));
    text.replace(at, from.size(), to);
    return text;
  };
  refused(edited("stability = false", "stability = true"), {"contact[0].second_tangent", "analysis.stability = false"});
  refused(edited("second_tangent = \"y\"", "second_tangent = \"y\"\nagainst = \"y\""),
          {"contact[0].second_tangent", "beside against"});
  refused(edited("second_tangent = \"y\"", "second_tangent = \"x\""), {"contact[0].second_tangent", "the contact's own DOF"});
  refused(edited("law = \"jenkins\"", "law = \"linear\"\nstiffness = 1.0\ngap = 0.0"), {"contact[0].second_tangent"});
}

// At 9 Hz, where the disc slips at every instant: the slider's path is the closed-form circle and
// its energy 2π r_s F_s per cycle, to first order in 1/Q (Q = 256); the loads' work balances the
// viscous and friction dissipation; the time stepping of the same scene agrees.
TEST(SceneFrictionDisc, ASolveIsTheClosedFormCircleAndTimeSteppingAgrees) {
  const double hz = 9.0;
  const Scene solve = parse(disc_at(hz, "type = \"solve\"\n"));
  const wbm::scene::AnalysisResult r = wbm::scene::run_analysis(solve);
  ASSERT_TRUE(r.converged()) << r.diagnostics.dump();
  const double a = closed_form_radius(solve, hz), kt = solve.contacts[0].tangential_stiffness;
  const double fs = solve.contacts[0].friction_coefficient * solve.contacts[0].normal_load;
  const double rs = std::sqrt(a * a - (fs / kt) * (fs / kt)), energy = 2.0 * kPi * rs * fs;
  const auto& friction = r.diagnostics.at("friction");
  ASSERT_EQ(friction.size(), 1u);  // one entry per element
  const auto& f = friction.at(0);
  EXPECT_EQ(f.at("stick_fraction").get<double>(), 0.0);
  EXPECT_NEAR(f.at("slip_amplitude_m").get<double>(), rs, 5e-3 * rs);
  const double dissipated = f.at("dissipated_energy_per_cycle_J").get<double>();
  EXPECT_NEAR(dissipated, energy, 5e-3 * energy);
  // The loads' work over the cycle from velocity.csv: F cos ωt ẋ + F sin ωt ẏ.
  const Eigen::VectorXd& time = column(r, "velocity.csv", 1);
  const Eigen::VectorXd& vx = column(r, "velocity.csv", 2);
  const Eigen::VectorXd& vy = column(r, "velocity.csv", 3);
  const double c = solve.system().damping.coeff(0, 0), force = solve.forcing->amplitude;
  const auto p = static_cast<double>(time.size());
  double load = 0.0, viscous = 0.0;
  for (Eigen::Index i = 0; i < time.size(); ++i) {
    const double t = 2.0 * kPi * hz * time(i);
    load += force * (std::cos(t) * vx(i) + std::sin(t) * vy(i)) / (hz * p);
    viscous += c * (vx(i) * vx(i) + vy(i) * vy(i)) / (hz * p);
  }
  EXPECT_NEAR(viscous + dissipated, load, 5e-4 * load);

  const Scene stepped = parse(disc_at(hz, "type = \"timestep\"\n[timestep]\nsteps_per_period = 16384\n"));
  const wbm::scene::AnalysisResult b = wbm::scene::run_analysis(stepped);
  ASSERT_TRUE(b.converged()) << b.diagnostics.dump();
  const double stepped_energy = b.diagnostics.at("friction").at(0).at("dissipated_energy_per_cycle_J").get<double>();
  EXPECT_NEAR(stepped_energy, energy, 1e-3 * energy);  // P = 1024 output samples
  const Eigen::VectorXd& xa = column(r, "displacement.csv", 2);
  const Eigen::VectorXd& xb = column(b, "displacement.csv", 2);
  EXPECT_LT((xa - xb).cwiseAbs().maxCoeff(), 5e-3 * a);
  std::printf("slider radius %.6g m against %.6g m; energy %.6g J (solve), %.6g J (timestep) against %.6g J; "
              "balance %.2e; x within %.2e a\n",
              f.at("slip_amplitude_m").get<double>(), rs, dissipated, stepped_energy, energy,
              (viscous + dissipated - load) / load, (xa - xb).cwiseAbs().maxCoeff() / a);
}
