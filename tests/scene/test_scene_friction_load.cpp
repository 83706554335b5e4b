// A continuation in the friction coefficient from a scene (analysis.parameter =
// "friction_coefficient"): the friction damper's design curve, amplitude against μN at resonance.
// Truths not produced by this code: the linear resonance P/(c ω_n) at μ = 0; the first-harmonic
// energy balance while the slider slips, X = (P − 4μN/π)/(c ω_n) (the slider's fundamental
// opposes the velocity); full stick, where the mass rides on k + k_t, X = P/(k + k_t − m ω²);
// and, with C = α M, multipliers of modulus e^{−αT/2} whatever the stiffness once it sticks.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <wbm/scene/analysis.hpp>
#include <wbm/scene/scene.hpp>

#include "scene_fixtures.hpp"
#include "testing.hpp"

using wbm::scene::Scene;
using namespace wbm::testing;  // scene_fixtures.hpp, testing.hpp

namespace {

const std::string kDamperLoad = std::string(WBM_EXAMPLES) + "/friction_damper_load.toml";

// The column named `name` of branch.csv.
const Eigen::VectorXd& branch_column(const wbm::scene::AnalysisResult& r, const std::string& name) {
  const auto t = std::find_if(r.tables.begin(), r.tables.end(), [](const auto& x) { return x.file == "branch.csv"; });
  EXPECT_NE(t, r.tables.end());
  const auto c = std::find(t->header.begin(), t->header.end(), name);
  EXPECT_NE(c, t->header.end()) << name;
  return t->columns.at(static_cast<size_t>(c - t->header.begin()));
}

}  // namespace

// The shipped examples/scenes/friction_damper_load.toml: 1 kg at f_n = 10 Hz, C = α M (ζ = 0.5 %),
// P = 1 N at 10 Hz, N = 1 N, k_t = 1000 k, μ from 0 to 1.2. Measured: the first harmonic balance
// within 7.3e-6 up to μ = 0.6 (the higher harmonics of the slider's force move the peak a little),
// the μ = 0 and stuck ends to rounding.
TEST(SceneFrictionLoad, TheDampersDesignCurveMeetsItsClosedFormsAtBothEndsAndWhileItSlips) {
  const Scene s = wbm::scene::load_scene(kDamperLoad);
  const wbm::scene::AnalysisResult r = wbm::scene::run_analysis(s);
  ASSERT_TRUE(r.converged()) << r.diagnostics.dump();
  EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();  // the file's μ is the range's start
  const Eigen::VectorXd& mu = branch_column(r, "friction_coefficient [-]");
  const Eigen::VectorXd& hz = branch_column(r, "frequency [Hz]");
  const Eigen::VectorXd& amplitude = branch_column(r, "amplitude_dof0 [m]");
  const Eigen::VectorXd& stable = branch_column(r, "stable [-]");
  const Eigen::VectorXd& multiplier = branch_column(r, "max_floquet_multiplier [-]");
  const wbm::solvers::MechanicalSystem sys = s.system();
  const double m = sys.mass.coeff(0, 0), k = sys.stiffness.coeff(0, 0), c = sys.damping.coeff(0, 0);
  const double p = s.forcing->amplitude, normal = s.contacts[0].normal_load, kt = s.contacts[0].tangential_stiffness;
  const double omega = 2.0 * kPi * s.forcing->frequency_hz;
  ASSERT_EQ(mu(0), 0.0);
  EXPECT_EQ(mu(mu.size() - 1), 1.2);
  EXPECT_EQ(hz.minCoeff(), 10.0);
  EXPECT_EQ(hz.maxCoeff(), 10.0);
  EXPECT_NEAR(amplitude(0) / (p / (c * omega)), 1.0, 1e-9);
  double worst = 0.0;
  int slipping = 0;
  for (Eigen::Index i = 0; i < mu.size(); ++i) {
    if (mu(i) > 0.6) continue;
    worst = std::max(worst, std::abs(amplitude(i) / ((p - 4.0 * mu(i) * normal / kPi) / (c * omega)) - 1.0));
    ++slipping;
  }
  EXPECT_GT(slipping, 20);
  EXPECT_LT(worst, 1e-4);
  EXPECT_NEAR(amplitude(amplitude.size() - 1) / (p / (k + kt - m * omega * omega)), 1.0, 1e-9);
  EXPECT_EQ(stable.minCoeff(), 1.0);
  EXPECT_NEAR(multiplier(multiplier.size() - 1), std::exp(-0.5 * c / m / s.forcing->frequency_hz), 1e-9);
  // Between, the slider's stick phases damp the orbit far more than the viscous part alone.
  EXPECT_LT(multiplier.minCoeff(), 0.1);
  const nlohmann::json echo = wbm::scene::to_json(s)["analysis"];
  EXPECT_EQ(echo["parameter"], "friction_coefficient");
  EXPECT_EQ(echo["friction_coefficient"], nlohmann::json({0.0, 1.2}));
  EXPECT_NE(r.summary.find("continuation in mu 0 → 1.2 at 10 Hz"), std::string::npos) << r.summary;
}

// What a branch in μ needs, refused by name with the way out; a contact μ other than the range's
// start is replaced with a warning; the frequency parameter takes no μ range.
TEST(SceneFrictionLoad, KeysAreReadAndRefusedWithTheWayOut) {
  const std::string structure = "structure = { mass = 1.0, stiffness = 4e4 }\n";
  const std::string one = "forcing = { amplitude = 1.0, frequency_hz = 8.0 }\n";
  const std::string jenkins = "[[contact]]\nlaw = \"jenkins\"\ntangential_stiffness = 4e7\nfriction_coefficient = 0.3\n"
                              "normal_load = 1.0\n";
  const std::string in_mu = "[analysis]\ntype = \"continuation\"\nparameter = \"friction_coefficient\"\n";
  const auto refused = [](const std::string& text, std::vector<std::string> fragments) {
    expect_throw_with<std::invalid_argument>([&] { (void)parse(text); }, fragments);
  };
  const Scene s = parse(structure + one + jenkins + in_mu + "friction_coefficient = [0.1, 0.9]\n");
  EXPECT_EQ(s.analysis.parameter, wbm::scene::BranchParameter::FrictionCoefficient);
  EXPECT_EQ(s.analysis.friction_from, 0.1);
  EXPECT_EQ(s.analysis.friction_to, 0.9);
  refused(structure + one + jenkins + in_mu, {"analysis.friction_coefficient: missing", "[from, to]"});
  refused(structure + one + jenkins + in_mu + "friction_coefficient = [0.1, 0.9]\nstick_slip_events = \"sometimes\"\n",
          {"analysis.stick_slip_events", "\"sometimes\" is not one of \"on-stall\", \"always\", \"never\""});
  const Scene always =
      parse(structure + one + jenkins + in_mu + "friction_coefficient = [0.1, 0.9]\nstick_slip_events = \"always\"\n");
  EXPECT_EQ(always.analysis.stick_slip_events, wbm::scene::StickSlipEvents::Always);
  refused(structure + one + jenkins + in_mu + "friction_coefficient = [0.2, 0.2]\n", {"from = to"});
  refused(structure + one + jenkins + in_mu + "friction_coefficient = [-0.1, 0.5]\n",
          {"analysis.friction_coefficient[0]", ">= 0"});
  refused(structure + "forcing = { amplitude = 1.0, frequency_hz = [5.0, 20.0] }\n" + jenkins + in_mu +
              "friction_coefficient = [0.1, 0.9]\n",
          {"forcing.frequency_hz", "at one forcing frequency", "parameter = \"frequency\""});
  refused(structure + one + jenkins + in_mu + "friction_coefficient = [0.1, 0.9]\nmax_frequency_step_hz = 0.1\n",
          {"analysis.max_frequency_step_hz", "remove it"});
  refused(structure + "forcing = { amplitude = 1.0, frequency_hz = [5.0, 20.0] }\n" + jenkins +
              "[analysis]\ntype = \"continuation\"\nfriction_coefficient = [0.1, 0.9]\n",
          {"analysis.friction_coefficient", "only used with parameter = \"friction_coefficient\""});
  refused(structure + one + "[[contact]]\nlaw = \"coulomb\"\nfriction_coefficient = 0.3\nnormal_load = 1.0\n" + in_mu +
              "friction_coefficient = [0.1, 0.9]\nstability = false\n",
          {"contact[0].law", "\"coulomb\"", "law = \"jenkins\""});
  refused(structure + one + "[[contact]]\nlaw = \"linear\"\nstiffness = 4e5\ngap = 1e-4\n" + in_mu +
              "friction_coefficient = [0.1, 0.9]\n",
          {"[contact]", "there is none", "parameter = \"frequency\""});
  const std::string two = "structure = { dofs = [\"x\", \"y\"], mass = [1.0, 1.0], stiffness = [4e4, 4e4] }\n"
                          "forcing = { amplitude = 1.0, dof = \"x\", frequency_hz = 8.0 }\n";
  const std::string other = "[[contact]]\nlaw = \"jenkins\"\ntangential_stiffness = 4e7\nfriction_coefficient = 0.4\n"
                            "normal_load = 1.0\ndof = \"y\"\n";
  refused(two + jenkins + "dof = \"x\"\n" + other + in_mu +
              "friction_coefficient = [0.1, 0.9]\n",
          {"contact[1].friction_coefficient: = 0.4", "the same value"});
  // The contact's μ (0.3) is replaced by the range's start (0.1), and the result says so.
  const wbm::scene::AnalysisResult r =
      wbm::scene::run_analysis(parse(structure + one + "damping = { alpha = 1.0 }\n" + jenkins + in_mu +
                                     "friction_coefficient = [0.1, 0.2]\nstability = false\n"));
  ASSERT_TRUE(r.converged()) << r.diagnostics.dump();
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("friction_coefficient = 0.3 is replaced by the branch's mu"), std::string::npos)
      << r.warnings[0];
  EXPECT_EQ(branch_column(r, "friction_coefficient [-]")(0), 0.1);
}


// The same scene at Q = 256 samples: with stick_slip_events = "never" the nonsmooth corrector
// stalls at the onset of full stick (near μ = 0.998) and the run says so; by default the branch
// goes on there on stick/slip events and lands on μ = 1.2 in full stick, X = P/|k + k_t − mω² +
// icω| (the linear oscillator; measured 5e-11, the peak read at the output samples).
TEST(SceneFrictionLoad, AtFewSamplesTheBranchCrossesTheOnsetOfFullStickOnEvents) {
  Scene s = wbm::scene::load_scene(kDamperLoad);
  s.basis.time_samples = 256;
  s.analysis.stability = false;
  s.analysis.stick_slip_events = wbm::scene::StickSlipEvents::Never;
  const wbm::scene::AnalysisResult stalled = wbm::scene::run_analysis(s);
  EXPECT_FALSE(stalled.converged());
  EXPECT_EQ(stalled.diagnostics["continuation"]["events"], 0);
  s.analysis.stick_slip_events = wbm::scene::StickSlipEvents::OnStall;
  const wbm::scene::AnalysisResult r = wbm::scene::run_analysis(s);
  ASSERT_TRUE(r.converged()) << r.diagnostics.dump();
  EXPECT_GT(r.diagnostics["continuation"]["events"].get<int>(), 0);
  const Eigen::VectorXd& mu = branch_column(r, "friction_coefficient [-]");
  const Eigen::VectorXd& amplitude = branch_column(r, "amplitude_dof0 [m]");
  EXPECT_EQ(mu(mu.size() - 1), 1.2);
  const wbm::solvers::MechanicalSystem sys = s.system();
  const double m = sys.mass.coeff(0, 0), k = sys.stiffness.coeff(0, 0), c = sys.damping.coeff(0, 0);
  const double kt = s.contacts[0].tangential_stiffness, omega = 2.0 * kPi * s.forcing->frequency_hz;
  const double exact = s.forcing->amplitude / std::hypot(k + kt - m * omega * omega, c * omega);
  EXPECT_NEAR(amplitude(amplitude.size() - 1) / exact, 1.0, 1e-9);
  EXPECT_EQ(wbm::scene::to_json(s)["analysis"]["stick_slip_events"], "on-stall");
}
