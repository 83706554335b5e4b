// Moving counter-surfaces in scenes ([[counter_surface]], a contact's counter_surface; issue #36,
// item 3), on the shipped example examples/scenes/oval_casing_rub.toml. Truths not produced by
// this code: a tip pressed on an oval casing follows it, x = δ cos 2πτ, with the reaction
// λ = P0 − Re((k − ω²m + iωc) δ e^{iωt}); a casing that slides by one lobe per period keeps the
// friction force at μλ against the rotation, so y = −μ P0/k + μ δ cos 2πτ (the linear response to
// −μλ, closed form); a spring on a moving obstacle has the closed-form amplitude of a base
// excitation.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>
#include <wbm/scene/analysis.hpp>
#include <wbm/scene/scene.hpp>

#include "scene_fixtures.hpp"
#include "testing.hpp"

using wbm::scene::Scene;
using namespace wbm::testing;  // scene_fixtures.hpp, testing.hpp

namespace {

using wbm::testing::kPi;
const std::string kOvalCasing = std::string(WBM_EXAMPLES) + "/oval_casing_rub.toml";

// The column of `file` headed `header`.
const Eigen::VectorXd& column_named(const wbm::scene::AnalysisResult& r, const std::string& file,
                                    const std::string& header) {
  for (const auto& t : r.tables) {
    if (t.file != file) continue;
    for (size_t i = 0; i < t.header.size(); ++i) {
      if (t.header[i] == header) return t.columns.at(i);
    }
  }
  throw std::out_of_range("no column \"" + header + "\" in " + file);
}

// The example as one solve at `hz`.
Scene oval_casing_at(double hz) {
  std::string text = slurp(kOvalCasing);
  const std::string sweep = "frequency_hz = [4.0, 30.0]\npoints = 27";
  text.replace(text.find(sweep), sweep.size(), "frequency_hz = " + std::to_string(hz));
  return parse(text);
}

}  // namespace

// At 20 Hz (above the tip's 10 Hz resonance, Ω = 62.8 rad/s): the closed forms above at every
// instant and output sample, every instant slipping, and the dissipated power the sliding's
// μ P0 (2πR/n) f plus the work of the tip's own slip, which is second order in δ here (bound 1 %).
TEST(SceneCounterSurface, ATipOnAnOvalCasingFollowsItAndSlipsAtEveryInstant) {
  const Scene s = oval_casing_at(20.0);
  ASSERT_EQ(s.counter_surfaces.size(), 1u);
  EXPECT_EQ(s.contacts.at(0).counter_surface, 0);
  const auto points = s.contact_points();
  EXPECT_DOUBLE_EQ(points.at(0).obstacle.cosine.at(0), 1e-3);
  EXPECT_DOUBLE_EQ(points.at(1).obstacle.drift, -2.0 * kPi * 0.25 / 2.0);
  const wbm::scene::AnalysisResult r = wbm::scene::run_analysis(s);
  ASSERT_TRUE(r.converged()) << r.summary;
  const double m = 1.0, k = std::pow(2.0 * kPi * 10.0, 2), c = 2.5132741228718345, p0 = 50.0, delta = 1e-3, mu = 0.15;
  const double w = 2.0 * kPi * 20.0;
  const std::complex<double> z(k - w * w * m, w * c);
  const Eigen::VectorXd& tk = column_named(r, "contact_force.csv", "tau [-]");
  const Eigen::VectorXd& normal = column_named(r, "contact_force.csv", "f_c_x [N]");
  const Eigen::VectorXd& tangential = column_named(r, "contact_force.csv", "f_c_y [N]");
  for (Eigen::Index i = 0; i < tk.size(); ++i) {
    const double lambda = p0 - std::real(z * delta * std::polar(1.0, 2.0 * kPi * tk(i)));
    EXPECT_NEAR(normal(i), lambda, 1e-9 * p0) << "instant " << i;
    EXPECT_NEAR(tangential(i), mu * normal(i), 1e-12 * p0) << "instant " << i;
  }
  const Eigen::VectorXd& tau = column_named(r, "displacement.csv", "tau [-]");
  const Eigen::VectorXd& x = column_named(r, "displacement.csv", "u_x [m]");
  const Eigen::VectorXd& y = column_named(r, "displacement.csv", "u_y [m]");
  for (Eigen::Index i = 0; i < tau.size(); ++i) {
    const double cosine = std::cos(2.0 * kPi * tau(i));
    EXPECT_NEAR(x(i), delta * cosine, 1e-9 * delta) << "sample " << i;
    EXPECT_NEAR(y(i), -mu * p0 / k + mu * delta * cosine, 1e-9 * delta) << "sample " << i;
  }
  const auto& friction = r.diagnostics.at("friction").at(0);
  EXPECT_EQ(friction.at("stick_fraction").get<double>(), 0.0);
  const double sliding = mu * p0 * (2.0 * kPi * 0.25 / 2.0) * 20.0;
  EXPECT_NEAR(friction.at("dissipated_power_W").get<double>(), sliding, 1e-2 * sliding);
}

// The example's sweep over 4 … 30 Hz converges at every point.
TEST(SceneCounterSurface, TheOvalCasingSweepConverges) {
  const wbm::scene::AnalysisResult r = wbm::scene::run_analysis(parse(slurp(kOvalCasing)));
  ASSERT_TRUE(r.converged()) << r.summary;
  EXPECT_EQ(r.diagnostics.at("failed_points").get<int>(), 0);
  EXPECT_EQ(r.diagnostics.at("converged_points").get<int>(), 27);
}

// A "fourier" counter-surface under a linear spring in a continuation with stability: every point
// is the base excitation's closed form u = (F + k_p a) / (k + k_p − ω² m + iωc) about k_p g0/(k + k_p),
// and every point is stable (a linear system); the scene is echoed and read back unchanged.
TEST(SceneCounterSurface, AFourierCounterSurfaceUnderASpringIsTheClosedForm) {
  const std::string text = R"(
structure = { mass = 1.0, stiffness = 3947.8417604357433 }
damping = { alpha = 2.5132741228718345 }
forcing = { amplitude = 1.0, frequency_hz = [7.0, 9.0] }
basis = { harmonics = 8 }
analysis = { type = "continuation", max_step = 0.05 }
[[counter_surface]]
name = "shaker"
cosine = [5e-2]
[[contact]]
law = "linear"
stiffness = 11843.52528130723
gap = -0.1
counter_surface = "shaker"
)";
  const Scene s = parse(text);
  const Scene again = wbm::scene::scene_from_json(wbm::scene::to_json(s), temp("again.json"));
  EXPECT_EQ(wbm::scene::to_json(again), wbm::scene::to_json(s));
  EXPECT_EQ(wbm::scene::to_json(s)["counter_surface"][0]["cosine"][0], 5e-2);
  EXPECT_EQ(wbm::scene::to_json(s)["contact"][0]["counter_surface"], "shaker");
  const wbm::scene::AnalysisResult r = wbm::scene::run_analysis(s);
  ASSERT_TRUE(r.converged()) << r.summary;
  const double m = 1.0, k = 3947.8417604357433, c = 2.5132741228718345, kp = 3.0 * k, g0 = -0.1, a = 5e-2;
  const Eigen::VectorXd& f = column_named(r, "branch.csv", "frequency [Hz]");
  const Eigen::VectorXd& umax = column_named(r, "branch.csv", "u_max_dof0 [m]");
  const Eigen::VectorXd& stable = column_named(r, "branch.csv", "stable [-]");
  ASSERT_GT(f.size(), 5);
  for (Eigen::Index i = 0; i < f.size(); ++i) {
    const double w = 2.0 * kPi * f(i);
    const double amplitude = std::abs((1.0 + kp * a) / std::complex<double>(k + kp - w * w * m, w * c));
    // The largest of the output samples: within 1 − cos(π/P) of the peak (P = 1024 by default).
    EXPECT_NEAR(umax(i), kp * g0 / (k + kp) + amplitude, 1e-5 * amplitude) << f(i) << " Hz";
    EXPECT_EQ(stable(i), 1.0) << f(i) << " Hz";
  }
}

// Bad input is refused with the key, the value and the way out; nothing runs.
TEST(SceneCounterSurface, BadCounterSurfacesAreRefusedByName) {
  const std::string head =
      "structure = { dofs = [\"x\", \"y\"], mass = [1.0, 1.0], stiffness = [4e4, 4e4] }\n"
      "forcing = { amplitude = 1.0, dof = \"x\", frequency_hz = 8.0 }\n"
      "basis = { harmonics = 8 }\n";
  const std::string fourier = "[[counter_surface]]\nname = \"s\"\ncosine = [1e-3]\n";
  const std::string sliding = "[[counter_surface]]\nname = \"s\"\ndrift = -0.5\n";
  const std::string oval =
      "[[counter_surface]]\nname = \"s\"\ntype = \"oval_casing\"\novalization = 1e-3\nradius = 0.2\n";
  const std::string linear = "[[contact]]\nlaw = \"linear\"\ndof = \"x\"\nstiffness = 1e5\ngap = 1e-3\n";
  const std::string jenkins =
      "[[contact]]\nlaw = \"jenkins\"\ndof = \"y\"\ntangential_stiffness = 1e5\n"
      "friction_coefficient = 0.3\nnormal_load = 1.0\n";
  std::string range = head;
  range.replace(range.find("frequency_hz = 8.0"), 18, "frequency_hz = [7.0, 9.0]");
  const auto refused = [](const std::string& text, std::vector<std::string> fragments) {
    expect_throw_with<std::invalid_argument>([&] { (void)parse(text); }, fragments);
  };
  EXPECT_NO_THROW((void)parse(head + fourier + linear + "counter_surface = \"s\"\n"));
  EXPECT_NO_THROW((void)parse(head + oval + linear + "counter_surface = \"s\"\n"));
  {  // the lobe's phase: s = δ cos(2πτ + 90°) = −δ sin 2πτ on the normal contact; echoed as given
    const Scene phased = parse(head + oval + "phase_deg = 90.0\n" + linear + "counter_surface = \"s\"\n");
    const auto motion = phased.contact_points().at(0).obstacle;
    EXPECT_NEAR(motion.cosine.at(0), 0.0, 1e-18);
    EXPECT_DOUBLE_EQ(motion.sine.at(0), -1e-3);
    EXPECT_EQ(wbm::scene::to_json(phased)["counter_surface"][0]["phase_deg"], 90.0);
  }
  refused(head + fourier + linear + "counter_surface = \"t\"\n", {"contact[0].counter_surface", "\"t\"", "\"s\""});
  refused(head + linear + "counter_surface = \"t\"\n", {"contact[0].counter_surface", "there is none"});
  refused(head + sliding + linear + "counter_surface = \"s\"\n",
          {"contact[0].counter_surface", "drift", "grow every period"});
  EXPECT_NO_THROW((void)parse(head + oval + jenkins + "counter_surface = \"s\"\n"));  // its slider slides along
  refused(head + fourier + fourier + linear, {"counter_surface[1].name", "twice"});
  refused(head + "[[counter_surface]]\nname = \"s\"\ncosine = [1e-3, 0, 0, 0, 0, 0, 0, 0, 0, 2e-4]\n" + linear +
              "counter_surface = \"s\"\n",
          {"counter_surface", "harmonic 10", "raise [basis] harmonics to at least 10"});
  refused(head + "[[counter_surface]]\nname = \"s\"\ntype = \"oval_casing\"\novalization = 1e-3\n" + linear,
          {"counter_surface[0].radius", "missing"});
  refused(head + fourier + "drift = 1e-3\n" + "ovalization = 1.0\n" + linear, {"counter_surface[0]", "ovalization"});
  refused(head + "analysis = { type = \"timestep\" }\n" + fourier + linear + "counter_surface = \"s\"\n",
          {"contact[0].counter_surface", "timestep", "fixed obstacles"});
  refused(range + "analysis = { type = \"continuation\" }\n" + fourier +
              "[[contact]]\nlaw = \"rigid\"\ndof = \"x\"\ngap = 1e-3\ncounter_surface = \"s\"\n",
          {"contact[0].counter_surface", "analysis.stability = false"});
  EXPECT_NO_THROW((void)parse(range + "analysis = { type = \"continuation\", stability = false }\n" + fourier +
                              "[[contact]]\nlaw = \"rigid\"\ndof = \"x\"\ngap = 1e-3\ncounter_surface = \"s\"\n"));
}
