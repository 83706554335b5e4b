// Friction under a varying normal load in scenes (normal_contact, issue #36), on the shipped
// example examples/scenes/friction_normal_load.toml. Truths not produced by this code: the energy
// balance over a cycle, work of the loads = viscous dissipation + friction dissipation (the
// normal penalty spring is conservative, ∮ n dy = 0), from the written samples; Coulomb's bound
// |f_t| ≤ μ n at every written sample, with f_t = 0 where the normal contact is open.
#include <cmath>
#include <numbers>
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

using wbm::testing::kPi;
const std::string kExample = std::string(WBM_EXAMPLES) + "/friction_normal_load.toml";

// The example at one frequency (a solve).
Scene example_at(double hz) {
  std::string text = slurp(kExample);
  text.replace(text.find("frequency_hz = [5.0, 25.0]"), 26, "frequency_hz = " + std::to_string(hz));
  text.replace(text.find("type = \"continuation\""), 21, "type = \"solve\"");
  text.replace(text.find("stability = false"), 17, "");
  return parse(text);
}

}  // namespace

// At 12 Hz (the normal contact opens over part of the cycle): the loads' work equals the viscous
// dissipation of both DOFs plus the element's own dissipation (diagnostics.friction, Σ f̄ Δs of
// its loop on the 1024 output samples; friction takes 45 % of the input) to 1e-4 (measured 2.5e-5;
// 2.8e-4 on 256 samples: second order, as the mean slip force along a slip makes it), and every
// written friction force lies within ±μ n(τ), zero where n = 0.
TEST(SceneFrictionNormalLoad, ASolveBalancesEnergyAndKeepsCoulombsBound) {
  const Scene s = example_at(12.0);
  ASSERT_EQ(s.contacts.size(), 2u);
  EXPECT_EQ(s.contacts[1].normal_contact, 0);
  EXPECT_EQ(s.contact_points().at(1).normal, 0);
  const wbm::scene::AnalysisResult r = wbm::scene::run_analysis(s);
  ASSERT_TRUE(r.converged()) << r.diagnostics.dump();
  const Eigen::VectorXd& time = column(r, "velocity.csv", 1);
  const Eigen::VectorXd& vx = column(r, "velocity.csv", 2);
  const Eigen::VectorXd& vy = column(r, "velocity.csv", 3);
  const auto sys = s.system();
  const double hz = 12.0, period = 1.0 / hz, samples = static_cast<double>(time.size());
  const double px = s.forcing->amplitude, py = s.forcing->loads.at(0).amplitude;
  double load = 0.0, viscous = 0.0;
  for (Eigen::Index i = 0; i < time.size(); ++i) {
    const double c = std::cos(2.0 * kPi * hz * time(i));
    load += c * (px * vx(i) + py * vy(i)) * period / samples;
    viscous += (sys.damping.coeff(0, 0) * vx(i) * vx(i) + sys.damping.coeff(1, 1) * vy(i) * vy(i)) * period / samples;
  }
  const auto& friction = r.diagnostics.at("friction").at(0);
  const double dissipated = friction.at("dissipated_energy_per_cycle_J").get<double>();
  EXPECT_GT(dissipated, 0.3 * load);
  EXPECT_NEAR(viscous + dissipated, load, 1e-4 * load);
  // contact_force.csv: tau, time, f_c of the normal contact, f_c and w_c of the friction contact.
  const Eigen::VectorXd& n = column(r, "contact_force.csv", 2);
  const Eigen::VectorXd& f = column(r, "contact_force.csv", 3);
  const double mu = s.contacts[1].friction_coefficient;
  EXPECT_EQ(n.minCoeff(), 0.0);  // the contact opens
  for (Eigen::Index i = 0; i < n.size(); ++i) {
    EXPECT_LE(std::abs(f(i)), mu * n(i) * (1.0 + 1e-12)) << "sample " << i;
  }
}

// normal_contact is read, echoed and round-tripped; a bad one is refused by name: itself, out of
// range, a friction contact as the normal one, on a law that takes no varying load; without it,
// normal_load stays required.
TEST(SceneFrictionNormalLoad, KeysAreReadEchoedAndRefused) {
  const Scene s = parse(slurp(kExample));
  const nlohmann::json echo = wbm::scene::to_json(s)["contact"][1];
  EXPECT_EQ(echo["normal_contact"], 0);
  EXPECT_EQ(echo["normal_load"], 0.0);
  const Scene again = wbm::scene::scene_from_json(wbm::scene::to_json(s), temp("again.json"));
  EXPECT_EQ(wbm::scene::to_json(again), wbm::scene::to_json(s));
  EXPECT_EQ(again.contact_points().at(1).normal, 0);

  const std::string base = "structure = { dofs = [\"x\", \"y\"], mass = [1.0, 1.0], stiffness = [4e4, 4e4] }\n"
                           "forcing = { amplitude = 1.0, dof = \"x\", frequency_hz = 8.0 }\n"
                           "[[contact]]\nlaw = \"linear\"\ndof = \"y\"\nstiffness = 1e5\ngap = -1e-5\n";
  const std::string jenkins = "[[contact]]\nlaw = \"jenkins\"\ndof = \"x\"\ntangential_stiffness = 1e5\n"
                              "friction_coefficient = 0.3\n";
  EXPECT_NO_THROW((void)parse(base + jenkins + "normal_contact = 0\n"));
  const auto refused = [](const std::string& text, std::vector<std::string> fragments) {
    expect_throw_with<std::invalid_argument>([&] { (void)parse(text); }, fragments);
  };
  refused(base + jenkins + "normal_contact = 1\n", {"contact[1].normal_contact", "this contact itself"});
  refused(base + jenkins + "normal_contact = 2\n", {"contact[1].normal_contact", "out of range"});
  refused(base + jenkins + "normal_contact = 0\n" + jenkins.substr(0, jenkins.find("dof")) +
              "dof = \"y\"\ntangential_stiffness = 1e5\nfriction_coefficient = 0.3\nnormal_contact = 1\n",
          {"contact[2].normal_contact", "of law \"jenkins\"", "\"linear\" or \"exponential\""});
  refused(base + jenkins, {"contact[1].normal_load", "missing"});
  refused(base + "[[contact]]\nlaw = \"coulomb\"\ndof = \"x\"\nfriction_coefficient = 0.3\nnormal_contact = 0\n",
          {"contact[1].normal_contact", "of law \"linear\"", "from a \"rigid\" contact"});
}
