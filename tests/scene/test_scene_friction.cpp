// Friction scenes (law = "jenkins" and "coulomb", issue #36). Truths not produced by this code: the first-
// harmonic energy balance at resonance, where the slipping slider's fundamental 4μN/π opposes the
// velocity and the viscous force c ω X takes the rest of the load, X = (P − 4μN/π)/(c ω); the
// energy balance over a cycle, work of the load = viscous dissipation + friction dissipation
// (Parseval on the samples); the slip force as the largest friction force.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>
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

const std::string kDamper = std::string(WBM_EXAMPLES) + "/friction_damper.toml";
const std::string kCoulombDamper = std::string(WBM_EXAMPLES) + "/friction_damper_coulomb.toml";

// The result table written as `file`, or nullptr.
const wbm::scene::Table* find_table(const wbm::scene::AnalysisResult& r, const std::string& file) {
  const auto t = std::find_if(r.tables.begin(), r.tables.end(), [&](const auto& x) { return x.file == file; });
  return t == r.tables.end() ? nullptr : &*t;
}

// Over one cycle of a 1-DOF solve, from velocity.csv: the load's work ∮ P cos ωt u̇ dt and the
// viscous dissipation ∮ c u̇² dt [J] (rectangle rule on the uniform output samples).
std::pair<double, double> cycle_work(const Scene& s, const wbm::scene::AnalysisResult& r) {
  const Eigen::VectorXd& time = column(r, "velocity.csv", 1);
  const Eigen::VectorXd& v = column(r, "velocity.csv", 2);
  const double hz = s.forcing->frequency_hz, period = 1.0 / hz, c = s.system().damping.coeff(0, 0),
               amplitude = s.forcing->amplitude;
  const auto samples = static_cast<double>(time.size());
  double load = 0.0, viscous = 0.0;
  for (Eigen::Index i = 0; i < time.size(); ++i) {
    load += amplitude * std::cos(2.0 * kPi * hz * time(i)) * v(i) * period / samples;
    viscous += c * v(i) * v(i) * period / samples;
  }
  return {load, viscous};
}

}  // namespace

// The shipped friction damper (examples/scenes/friction_damper.toml): m = 1 kg, f_n = 10 Hz,
// ζ = 0.5 %, P = 1 N, μN = 0.2 N, k_t = 1000 k. Its resonance peak is the closed form
// (P − 4μN/π)/(c ω_n) = 74.5 static deflections to 1e-3 (Coulomb friction alone cannot bound it:
// 4μN/π < P), and the largest friction force along the branch is μN.
TEST(SceneFriction, TheDamperPeakIsTheFirstHarmonicEnergyBalance) {
  const Scene s = wbm::scene::load_scene(kDamper);
  ASSERT_EQ(s.contacts.size(), 1u);
  EXPECT_EQ(s.basis.contact_quadrature, wbm::solvers::ContactQuadrature::Midpoint);  // automatic, for friction
  const wbm::scene::AnalysisResult r = wbm::scene::run_analysis(s);
  ASSERT_TRUE(r.converged()) << r.diagnostics.dump();
  const Eigen::VectorXd& amplitude = column(r, "branch.csv", 3);
  const Eigen::VectorXd& force = column(r, "branch.csv", 4);
  // The parameters as the scene gives them (M, C, K of 1 DOF; the load; μN).
  const wbm::solvers::MechanicalSystem sys = s.system();
  const double m = sys.mass.coeff(0, 0), k = sys.stiffness.coeff(0, 0), c = sys.damping.coeff(0, 0);
  const double p = s.forcing->amplitude, slip = s.contacts[0].friction_coefficient * s.contacts[0].normal_load;
  const double omega = std::sqrt(k / m);
  EXPECT_NEAR(amplitude.maxCoeff() / ((p - 4.0 * slip / kPi) / (c * omega)), 1.0, 1e-3);
  EXPECT_NEAR(force.maxCoeff(), slip, 1e-12);
  // Every point stable, as incremental passivity requires of a damped structure with Jenkins
  // elements under constant normal loads (tests/solvers/test_floquet_jenkins.cpp); at 5 Hz, where
  // the slider slips over nearly the whole cycle (its stick phases at the reversals are short:
  // k_t = 1000 k), the multipliers are nearly those of the free oscillator, |μ| = e^{−cT/2}
  // (measured 1.5e-4 below it).
  const Eigen::VectorXd& stable = column(r, "branch.csv", 5);
  const Eigen::VectorXd& multiplier = column(r, "branch.csv", 6);
  EXPECT_EQ(stable.minCoeff(), 1.0);
  EXPECT_LT(multiplier.maxCoeff(), 1.0);
  EXPECT_NEAR(multiplier(0), std::exp(-0.5 * c / (m * 5.0)), 1e-3);
}

// One solve at 8 Hz: over a cycle the load's work equals the viscous dissipation plus the
// friction element's (diagnostics.friction), from the written samples; the slider slips over
// most of the cycle and its dissipation is 4 μN × (its slip amplitude), as for any Jenkins loop
// with two reversals a cycle; the friction force stays within ±μN.
TEST(SceneFriction, ASolveBalancesTheEnergyOfLoadViscosityAndFriction) {
  std::string text = slurp(kDamper);
  text.replace(text.find("frequency_hz = [5.0, 20.0]"), 26, "frequency_hz = 8.0");
  const std::string continuation = "type = \"continuation\", stability = true";
  text.replace(text.find(continuation), continuation.size(), "type = \"solve\"");
  const Scene s = parse(text);
  const wbm::scene::AnalysisResult r = wbm::scene::run_analysis(s);
  ASSERT_TRUE(r.converged()) << r.diagnostics.dump();
  const Eigen::VectorXd& f = column(r, "contact_force.csv", 2);
  const double slip = s.contacts[0].friction_coefficient * s.contacts[0].normal_load;
  const auto [load, viscous] = cycle_work(s, r);
  const auto& friction = r.diagnostics.at("friction").at(0);
  const double dissipated = friction.at("dissipated_energy_per_cycle_J").get<double>();
  EXPECT_NEAR(viscous + dissipated, load, 1e-3 * load);
  EXPECT_NEAR(dissipated, 4.0 * slip * friction.at("slip_amplitude_m").get<double>(), 1e-9 * dissipated);
  EXPECT_LT(friction.at("stick_fraction").get<double>(), 0.05);
  EXPECT_LE(f.cwiseAbs().maxCoeff(), slip * (1.0 + 1e-15));
  EXPECT_EQ(r.diagnostics.at("energy").get<std::string>().rfind("not written", 0), 0u);
  // The hysteresis loop beside the force: w_c is the contact DOF's displacement (the only DOF),
  // and the loop's area ∮ f dw (closed trapezoids) is the energy the element dissipates, which the
  // loop computes instead from the slider's increments, Σ f Δs.
  const auto* table = find_table(r, "contact_force.csv");
  ASSERT_NE(table, nullptr);
  ASSERT_EQ(table->header.size(), 4u);
  const std::string& force_name = table->header[2];  // "f_c_<label> [N]"
  EXPECT_EQ(table->header[3], "w_c_" + force_name.substr(4, force_name.size() - 8) + " [m]");
  const Eigen::VectorXd& w = table->columns[3];
  EXPECT_LT((w - column(r, "displacement.csv", 2)).cwiseAbs().maxCoeff(), 1e-15 * w.cwiseAbs().maxCoeff());
  double area = 0.0;
  for (Eigen::Index i = 0; i < w.size(); ++i) {
    const Eigen::Index j = (i + 1) % w.size();
    area += 0.5 * (f(i) + f(j)) * (w(j) - w(i));
  }
  EXPECT_NEAR(area, dissipated, 1e-3 * dissipated);
}

// The keys of a friction contact, their echo and round trip, and what friction is refused for.
TEST(SceneFriction, KeysAreReadEchoedAndRefusedWhereFrictionIsNotComputed) {
  const std::string base = "structure = { mass = 1.0, stiffness = 4e4 }\nforcing = { amplitude = 1.0, frequency_hz = 8.0 }\n";
  const std::string law = "contact = { law = \"jenkins\", tangential_stiffness = 4e7, friction_coefficient = 0.3, "
                          "normal_load = 2.0";
  const Scene s = parse(base + law + " }\n");
  ASSERT_EQ(s.contacts.size(), 1u);
  EXPECT_EQ(s.contacts[0].law, wbm::scene::ContactLawKind::Jenkins);
  EXPECT_EQ(s.contacts[0].tangential_stiffness, 4e7);
  EXPECT_EQ(s.contacts[0].friction_coefficient, 0.3);
  EXPECT_EQ(s.contacts[0].normal_load, 2.0);
  EXPECT_TRUE(s.friction());
  const nlohmann::json echo = wbm::scene::to_json(s)["contact"][0];
  EXPECT_EQ(echo["law"], "jenkins");
  EXPECT_FALSE(echo.contains("gap"));
  EXPECT_EQ(echo["normal_load"], 2.0);
  const Scene again = wbm::scene::scene_from_json(wbm::scene::to_json(s), temp("again.json"));
  EXPECT_EQ(wbm::scene::to_json(again), wbm::scene::to_json(s));
  const auto law_ptr = s.contact_points().at(0).law;
  EXPECT_TRUE(law_ptr->hysteretic());
  EXPECT_EQ(law_ptr->describe(), "Jenkins element k_t = 4e+07 N/m, mu = 0.3, N = 2 N");
  // Its loop saturates at μN = 0.6 N (not μ, not N): a sinusoid far past the slip threshold.
  const Eigen::VectorXd w = 1e-6 * Eigen::VectorXd::LinSpaced(64, 0.0, 2.0 * kPi * 63.0 / 64.0).array().cos();
  Eigen::VectorXd f(64), kq(64);
  Eigen::VectorXi anchor(64);
  law_ptr->evaluate_period(w, f, kq, anchor);
  EXPECT_DOUBLE_EQ(f.maxCoeff(), 0.6);
  EXPECT_DOUBLE_EQ(f.minCoeff(), -0.6);

  const auto refused = [](const std::string& text, std::vector<std::string> fragments) {
    expect_throw_with<std::invalid_argument>([&] { (void)parse(text); }, fragments);
  };
  refused(base + law + ", gap = 1e-3 }\n", {"contact.gap: unknown key"});
  refused(base + "contact = { law = \"jenkins\", tangential_stiffness = 4e7, normal_load = 2.0 }\n",
          {"contact.friction_coefficient"});
  refused(base + "contact = { law = \"jenkins\", tangential_stiffness = 4e7, friction_coefficient = 0.3, "
                 "normal_load = -1.0 }\n",
          {"contact.normal_load", ">= 0 [N]"});
  // A continuation computes its points' stability by default (floquet.hpp, "Jenkins elements").
  EXPECT_TRUE(parse("structure = { mass = 1.0, stiffness = 4e4 }\nforcing = { amplitude = 1.0, frequency_hz = "
                    "[5.0, 20.0] }\n" + law + " }\nanalysis = { type = \"continuation\" }\n")
                  .analysis.stability);
  // timestep takes a Jenkins element by central differences: their keys, not the BDF's.
  const Scene stepped = parse(base + law + " }\nanalysis = { type = \"timestep\" }\n[timestep]\n"
                                           "steps_per_period = 32768\nmax_periods = 900\n");
  EXPECT_EQ(stepped.central_difference.steps_per_period, 32768);
  EXPECT_EQ(stepped.central_difference.max_periods, 900);
  EXPECT_EQ(stepped.central_difference.samples_per_period, stepped.output.samples);
  EXPECT_EQ(wbm::scene::to_json(stepped)["timestep"]["steps_per_period"], 32768);
  EXPECT_FALSE(wbm::scene::to_json(stepped)["timestep"].contains("relative_tolerance"));
  refused(base + law + " }\nanalysis = { type = \"timestep\" }\n[timestep]\nrelative_tolerance = 1e-8\n",
          {"timestep.relative_tolerance", "central differences"});
  refused(base + law + " }\nanalysis = { type = \"timestep\" }\n[timestep]\nsteps_per_period = 1000\n",
          {"timestep.steps_per_period", "not a multiple of output.samples = 1024"});
  refused(base + law + " }\nbasis = { harmonics = 8, contact_quadrature = \"cell-average\" }\n",
          {"basis.contact_quadrature", "\"jenkins\"", "\"midpoint\""});
}

// The shipped damper at 8 Hz by `timestep` (explicit central differences, the Jenkins element's
// slider state carried from step to step) against the weighted residual's solve of the same scene
// (Fourier:Fourier, H = 32, the element's periodic loop): two discretizations, one in time and
// one in the frequency domain, that share only the contact law. The steady state agrees to
// 1e-3 of its amplitude (measured 3.3e-4), the dissipated energy per cycle likewise (3.1e-4) and
// the stick fraction to 1e-2 (0.0059 against 0.0039), and over the stepped cycle the load's work
// equals the viscous dissipation plus the element's to 1e-4 (4.5e-6): periodic after 78 periods.
TEST(SceneFriction, TimeSteppingAJenkinsDamperMatchesItsWeightedResidualSolve) {
  std::string text = slurp(kDamper);
  const auto analysis = text.find("analysis = ");
  ASSERT_NE(analysis, std::string::npos);
  text = text.substr(0, analysis);
  const auto at = text.find("frequency_hz = [5.0, 20.0]");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, std::string("frequency_hz = [5.0, 20.0]").size(), "frequency_hz = 8.0");
  const Scene solve = parse(text + "analysis = { type = \"solve\" }\n");
  // 8192 steps per period: 66 times the explicit limit of the stiff element (k_t = 1000 k).
  const Scene stepped = parse(text + "analysis = { type = \"timestep\" }\n[timestep]\nsteps_per_period = 8192\n");
  const wbm::scene::AnalysisResult a = wbm::scene::run_analysis(solve);
  const wbm::scene::AnalysisResult b = wbm::scene::run_analysis(stepped);
  ASSERT_TRUE(a.converged()) << a.diagnostics.dump();
  ASSERT_TRUE(b.converged()) << b.diagnostics.dump();
  EXPECT_NE(b.diagnostics.at("timestep").at("method").get<std::string>().find("central differences"),
            std::string::npos);
  // Both write displacement.csv on the same P = 1024 output samples τ_p = p/P.
  const Eigen::VectorXd& xa = column(a, "displacement.csv", 2);
  const Eigen::VectorXd& xb = column(b, "displacement.csv", 2);
  ASSERT_EQ(xa.size(), xb.size());
  const double amplitude = 0.5 * (xa.maxCoeff() - xa.minCoeff());
  EXPECT_LE((xa - xb).cwiseAbs().maxCoeff(), 1e-3 * amplitude);
  const auto& fa = a.diagnostics.at("friction").at(0);
  const auto& fb = b.diagnostics.at("friction").at(0);
  const double dissipated = fa.at("dissipated_energy_per_cycle_J").get<double>();
  EXPECT_NEAR(fb.at("dissipated_energy_per_cycle_J").get<double>(), dissipated, 1e-3 * dissipated);
  EXPECT_NEAR(fb.at("stick_fraction").get<double>(), fa.at("stick_fraction").get<double>(), 1e-2);
  const auto [load, viscous] = cycle_work(stepped, b);
  EXPECT_NEAR(load, viscous + fb.at("dissipated_energy_per_cycle_J").get<double>(), 1e-4 * load);
}

// The damper with exact Coulomb friction (examples/scenes/friction_damper_coulomb.toml, M = 129,
// steps of 0.002 Hz):
// its peak is the first-harmonic balance (P − 4μN/π)/(c ω_n) to 1e-3 (measured 2.1e-4; first order
// in 1/M), every friction impulse is within ±μN, and the impulses are the branch's unknowns.
TEST(SceneFriction, TheExactCoulombDamperPeakIsTheFirstHarmonicEnergyBalance) {
  const Scene s = wbm::scene::load_scene(kCoulombDamper);
  ASSERT_TRUE(s.rigid());
  ASSERT_TRUE(s.friction());
  const wbm::scene::AnalysisResult r = wbm::scene::run_analysis(s);
  ASSERT_TRUE(r.converged()) << r.diagnostics.dump();
  const wbm::solvers::MechanicalSystem sys = s.system();
  const double m = sys.mass.coeff(0, 0), k = sys.stiffness.coeff(0, 0), c = sys.damping.coeff(0, 0);
  const double p = s.forcing->amplitude, slip = s.contacts[0].friction_coefficient * s.contacts[0].normal_load;
  EXPECT_NEAR(column(r, "branch.csv", 3).maxCoeff() / ((p - 4.0 * slip / kPi) / (c * std::sqrt(k / m))), 1.0, 1e-3);
  EXPECT_LE(column(r, "branch.csv", 4).maxCoeff(), slip * (1.0 + 1e-12));
}

// One solve at 8 Hz with exact Coulomb friction: the load's work over a cycle equals the viscous
// dissipation plus the friction's, Σ λ_k (w_{k+1} − w_k) from the impulses and the written w
// (1e-2: the impulses' M-point rule against the load's P-point one); with two reversals a cycle
// and every instant slipping or still, that is 4 μN × the slip amplitude; w_c is the contact
// DOF's displacement at the instants, beside the impulses in contact_force.csv.
TEST(SceneFriction, AnExactCoulombSolveBalancesTheEnergyOfLoadViscosityAndFriction) {
  std::string text = slurp(kCoulombDamper);
  const auto replace = [&text](const std::string& from, const std::string& to) {
    ASSERT_NE(text.find(from), std::string::npos) << from;
    text.replace(text.find(from), from.size(), to);
  };
  replace("frequency_hz = [9.5, 10.5]", "frequency_hz = 8.0");
  replace("type = \"continuation\", stability = false, max_frequency_step_hz = 0.002", "type = \"solve\"");
  const Scene s = parse(text);
  const wbm::scene::AnalysisResult r = wbm::scene::run_analysis(s);
  ASSERT_TRUE(r.converged()) << r.diagnostics.dump();
  const double slip = s.contacts[0].friction_coefficient * s.contacts[0].normal_load;
  const auto [load, viscous] = cycle_work(s, r);
  const auto& friction = r.diagnostics.at("friction").at(0);
  const double dissipated = friction.at("dissipated_energy_per_cycle_J").get<double>();
  EXPECT_NEAR(viscous + dissipated, load, 1e-2 * load);
  EXPECT_NEAR(dissipated, 4.0 * slip * friction.at("slip_amplitude_m").get<double>(), 1e-9 * dissipated);
  EXPECT_LT(friction.at("stick_fraction").get<double>(), 0.05);
  const auto* table = find_table(r, "contact_force.csv");
  ASSERT_NE(table, nullptr);
  ASSERT_EQ(table->header.size(), 4u);
  EXPECT_EQ(table->header[3].rfind("w_c_", 0), 0u);
  const Eigen::VectorXd& tk = table->columns[0];
  const Eigen::VectorXd& f = table->columns[2];
  const Eigen::VectorXd& w = table->columns[3];
  EXPECT_EQ(tk.size(), s.trial().dimension());
  EXPECT_LE(f.cwiseAbs().maxCoeff(), slip * (1.0 + 1e-12));
  // w at the instants from the written coefficients: u(τ) = Σ_k a_k q_k(τ).
  const Eigen::VectorXd& a = column(r, "coefficients.csv", 1);
  const Eigen::VectorXd at_instants = s.trial().values(tk, 0) * a;
  EXPECT_LT((w - at_instants).cwiseAbs().maxCoeff(), 1e-12 * w.cwiseAbs().maxCoeff());
}

// law = "coulomb": its keys, echo and round trip; mixing it with a penalty or Jenkins contact and
// stability are refused by name; time stepping takes it, with normal_contact on a rigid contact.
TEST(SceneFriction, CoulombKeysAreReadEchoedAndRefusedWhereNotComputed) {
  const std::string base = "structure = { mass = [[1.0, 0.0], [0.0, 1.0]], stiffness = [[4e4, -1e4], [-1e4, 4e4]] }\n"
                           "forcing = { amplitude = 1.0, frequency_hz = 8.0, dof = 0 }\n";
  const std::string law = "[[contact]]\nlaw = \"coulomb\"\ndof = 0\nfriction_coefficient = 0.3\nnormal_load = 2.0\n";
  const Scene s = parse(base + law);
  ASSERT_EQ(s.contacts.size(), 1u);
  EXPECT_EQ(s.contacts[0].law, wbm::scene::ContactLawKind::Coulomb);
  EXPECT_TRUE(s.friction());
  EXPECT_TRUE(s.rigid());
  const nlohmann::json echo = wbm::scene::to_json(s)["contact"][0];
  EXPECT_EQ(echo["law"], "coulomb");
  EXPECT_FALSE(echo.contains("gap"));
  EXPECT_FALSE(echo.contains("tangential_stiffness"));
  EXPECT_EQ(echo["friction_coefficient"], 0.3);
  const Scene again = wbm::scene::scene_from_json(wbm::scene::to_json(s), temp("again_coulomb.json"));
  EXPECT_EQ(wbm::scene::to_json(again), wbm::scene::to_json(s));
  EXPECT_EQ(s.contact_points().at(0).law->describe(), "Coulomb friction (exact) mu = 0.3, N = 2 N");
  // With a rigid stop on the other DOF (both exact) it is accepted.
  (void)parse(base + law + "[[contact]]\nlaw = \"rigid\"\ndof = 1\ngap = 1e-4\n");
  const auto refused = [](const std::string& text, std::vector<std::string> fragments) {
    expect_throw_with<std::invalid_argument>([&] { (void)parse(text); }, fragments);
  };
  refused(base + law + "tangential_stiffness = 1e6\n", {"contact[0].tangential_stiffness: unknown key"});
  refused(base + law + "[[contact]]\nlaw = \"jenkins\"\ndof = 1\ntangential_stiffness = 4e7\nfriction_coefficient = 0.3\n"
                       "normal_load = 2.0\n",
          {"mixes exact contacts", "\"coulomb\" ones a stiff \"jenkins\" law"});
  // Time stepping (Moreau–Jean with Siconos) and the weighted residual take it, with a constant
  // load or a rigid normal contact's reaction (normal_contact).
  (void)parse(base + "analysis = { type = \"timestep\" }\n" + law);
  const std::string two_d = "[[contact]]\nlaw = \"rigid\"\ndof = 1\ngap = 0.0\n[[contact]]\nlaw = \"coulomb\"\ndof = 0\n"
                            "friction_coefficient = 0.3\nnormal_contact = 0\n";
  const Scene pressed = parse(base + "analysis = { type = \"timestep\" }\n" + two_d);
  ASSERT_EQ(pressed.contact_points().size(), 2u);
  EXPECT_EQ(pressed.contact_points()[1].normal, 0);
  EXPECT_EQ(wbm::scene::to_json(pressed)["contact"][1]["normal_contact"], 0);
  EXPECT_EQ(parse(base + two_d).contact_points()[1].normal, 0);
  refused(base + "analysis = { type = \"timestep\" }\n" + two_d + "normal_load = 0.5\n",
          {"contact[1].normal_load", "= 0.5 beside normal_contact", "harmonic = 0"});
  refused(base + "analysis = { type = \"timestep\" }\n" + two_d +
              "[[contact]]\nlaw = \"coulomb\"\ndof = 1\ndirection = { dof0 = 1.0, dof1 = 1.0 }\nfriction_coefficient = 0.3\n"
              "normal_contact = 0\n",
          {"contact[2].normal_contact", "already takes its normal load"});
  std::string on_penalty = two_d;
  const std::string rigid_law = "law = \"rigid\"";
  on_penalty.replace(on_penalty.find(rigid_law), rigid_law.size(), "law = \"linear\"\nstiffness = 1e6");
  refused(base + "analysis = { type = \"timestep\" }\n" + on_penalty,
          {"contact[1].normal_contact", "from a \"rigid\" contact"});
  refused("structure = { mass = 1.0, stiffness = 4e4 }\nforcing = { amplitude = 1.0, frequency_hz = [5.0, 20.0] }\n"
          "analysis = { type = \"continuation\" }\n" + law,
          {"contact[0].law", "stability = true", "use law = \"jenkins\""});
}

// examples/scenes/friction_timestep_normal_load.toml: the scheme's energy account over the last
// period closes (input = damping + contacts, the identity of θ = ½ once periodic), and the
// friction's dissipated power summed over the output samples, Σ f_p Δw_p (diagnostics.friction),
// is the contacts' power summed over the steps to within the output sampling (the normal stop
// does no work: y rests on the plane). The slip force follows the stop: |f_t| ≤ μ f_n in every
// output interval.
TEST(SceneFriction, TimeSteppingWithARigidNormalContactBalancesItsEnergy) {
  const Scene s = parse(slurp(std::string(WBM_EXAMPLES) + "/friction_timestep_normal_load.toml"));
  const wbm::scene::AnalysisResult r = wbm::scene::run_analysis(s);
  ASSERT_TRUE(r.converged()) << r.diagnostics.dump();
  const auto& powers = r.diagnostics.at("timestep").at("powers_W");
  const double input = powers.at("input").get<double>(), damping = powers.at("damping").get<double>(),
               contacts = powers.at("contacts").get<double>();
  EXPECT_NEAR(input, damping + contacts, 1e-6 * input);  // measured 8.7e-8
  const double friction = r.diagnostics.at("friction").at(0).at("dissipated_power_W").get<double>();
  EXPECT_GT(friction, 0.3 * input);  // friction takes a good share: the test is not vacuous
  EXPECT_NEAR(friction, contacts, 1e-4 * contacts);  // measured 4.1e-6
  const auto* table = find_table(r, "contact_force.csv");
  ASSERT_NE(table, nullptr);
  ASSERT_EQ(table->header.size(), 5u);  // tau, time, f_c of y, f_c of x, w_c of x
  const Eigen::VectorXd& normal = table->columns[2];
  const Eigen::VectorXd& tangent = table->columns[3];
  EXPECT_GT(normal.minCoeff(), 0.0);
  EXPECT_LE((tangent.cwiseAbs() - 0.3 * normal).maxCoeff(), 1e-9);
}

// examples/scenes/friction_rigid_normal.toml: the point of the time-stepping example solved by the
// weighted residual, the plane's multipliers as the friction's normal load. x balances its energy:
// the load's work is the viscous and the friction dissipation (1e-2: the impulses' M-point rule
// against the samples' P-point one, as for the constant load above); the friction force stays
// within μ λ_n at every instant. The same scene in time stepping (Moreau–Jean with Siconos'
// fc2d, T/16384) gives the same x motion to 2e-2 rms at M = 129 (measured 3e-3;
// tests/solvers/test_friction_rigid_normal.cpp).
TEST(SceneFriction, ASolveOfA2DContactBalancesItsEnergyAndMatchesTimeStepping) {
  const std::string text = slurp(std::string(WBM_EXAMPLES) + "/friction_rigid_normal.toml");
  const Scene s = parse(text);
  const wbm::scene::AnalysisResult r = wbm::scene::run_analysis(s);
  ASSERT_TRUE(r.converged()) << r.diagnostics.dump();
  const auto [load, viscous] = cycle_work(s, r);
  const auto& friction = r.diagnostics.at("friction").at(0);
  const double dissipated = friction.at("dissipated_energy_per_cycle_J").get<double>();
  EXPECT_GT(dissipated, 0.2 * load);  // friction takes a good share: the test is not vacuous
  EXPECT_NEAR(viscous + dissipated, load, 1e-2 * load);
  const auto* table = find_table(r, "contact_force.csv");
  ASSERT_NE(table, nullptr);
  ASSERT_EQ(table->header.size(), 5u);  // tau, time, f_c of y, f_c of x, w_c of x
  const Eigen::VectorXd& normal = table->columns[2];
  const Eigen::VectorXd& tangent = table->columns[3];
  EXPECT_NEAR(normal.minCoeff(), 0.2, 1e-2);  // 1 N − 0.8 N: the slip force swings with it
  EXPECT_LE((tangent.cwiseAbs() - 0.3 * normal.cwiseMax(0.0)).maxCoeff(), 1e-9);
  // The same point by time stepping.
  std::string stepped = text;
  const std::string from =
      "[basis]\nharmonics = 64                 # M = 129 impulses per contact\n\n[analysis]\ntype = \"solve\"";
  ASSERT_NE(stepped.find(from), std::string::npos);
  stepped.replace(stepped.find(from), from.size(),
                  "[analysis]\ntype = \"timestep\"\n[timestep]\nsteps_per_period = 16384");
  const wbm::scene::AnalysisResult t = wbm::scene::run_analysis(parse(stepped));
  ASSERT_TRUE(t.converged()) << t.diagnostics.dump();
  const Eigen::VectorXd& x_wr = column(r, "displacement.csv", 2);
  const Eigen::VectorXd& x_ts = column(t, "displacement.csv", 2);
  ASSERT_EQ(x_wr.size(), x_ts.size());
  EXPECT_LT((x_wr - x_ts).norm() / x_ts.norm(), 2e-2);
}
