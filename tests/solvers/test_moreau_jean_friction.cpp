// Moreau–Jean time stepping with exact Coulomb friction, its one-step frictional contact problem
// solved by Siconos Numerics (fc2d, Lemke). Truths not produced by this code: Den Hartog's (1931)
// steady state of a 1-DOF oscillator with Coulomb and viscous damping in continuous motion,
// computed here from its four turning-point conditions; the physics of a normal DOF held on a
// rigid plane by a static load, whose reaction is that load; the explicit central differences
// with a Jenkins element on a penalty normal law (integrate_central_difference_to_periodic, no
// Siconos), which tend to Coulomb–Signorini as both stiffnesses grow; and the projected
// Gauss–Seidel path of frictionless stops, exact for one stop.
#include <cmath>
#include <complex>
#include <memory>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <wbm/contact/friction.hpp>
#include <wbm/contact/penalty.hpp>
#include <wbm/contact/signorini.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/post_processing.hpp>
#include <wbm/solvers/time_integration.hpp>

#include "testing.hpp"

namespace solvers = wbm::solvers;
namespace contact = wbm::contact;

namespace {

using wbm::testing::kPi;

// n point masses m = 1 kg on springs k = (2π 10 Hz)² m with damping ratio ζ, uncoupled.
solvers::MechanicalSystem point_masses(int n, double zeta) {
  const double m = 1.0, k = std::pow(2.0 * kPi * 10.0, 2);
  solvers::MechanicalSystem s;
  s.mass.resize(n, n);
  s.stiffness.resize(n, n);
  s.damping.resize(n, n);
  for (int i = 0; i < n; ++i) {
    s.mass.insert(i, i) = m;
    s.stiffness.insert(i, i) = k;
    if (zeta > 0.0) s.damping.insert(i, i) = 2.0 * zeta * std::sqrt(k * m);
  }
  return s;
}

std::shared_ptr<const contact::CoulombFriction> coulomb_law(double mu, double normal_load) {
  return std::make_shared<contact::CoulombFriction>(contact::CoulombParameters{mu, normal_load});
}

// Den Hartog's continuous motion of m ẍ + c ẋ + k x + F0 sign ẋ = P cos(ωt + φ) [Den Hartog,
// Trans. ASME 53 (1931) APM-53-9, 107–115], derived here: over the half period from the turning
// point x(0) = x0 (ẋ < 0, friction +F0) to x(T/2) = −x0, with σ = ζω_n, ω_d = ω_n √(1 − ζ²),
//   x(t) = F0/k + e^{−σt} (A cos ω_d t + B sin ω_d t) + Re(Z e^{i(ωt + φ)}),  Z = P/(k − mω² + icω).
// ẋ(0) = 0, x(T/2) = −x0 and ẋ(T/2) = 0 with x(0) = x0 are linear in (A, B, cos φ, sin φ) for a
// given x0; cos²φ + sin²φ = 1 is then a quadratic in x0, whose larger root is the amplitude.
double den_hartog_damped_amplitude(double m, double c, double k, double p, double f0, double omega) {
  using C = std::complex<double>;
  const double sigma = c / (2.0 * m), wd = std::sqrt(k / m - sigma * sigma), half = kPi / omega;
  const C z = p / C(k - m * omega * omega, c * omega);
  const auto x_p = [&](double t) { return z * std::exp(C(0.0, omega * t)); };              // Re(x_p e^{iφ})
  const auto v_p = [&](double t) { return C(0.0, omega) * z * std::exp(C(0.0, omega * t)); };
  const double e = std::exp(-sigma * half), co = std::cos(wd * half), si = std::sin(wd * half);
  // Re(w (cos φ + i sin φ)) = Re(w) cos φ − Im(w) sin φ.
  Eigen::Matrix4d a;
  a << 1.0, 0.0, x_p(0).real(), -x_p(0).imag(),  //
      -sigma, wd, v_p(0).real(), -v_p(0).imag(),  //
      e * co, e * si, x_p(half).real(), -x_p(half).imag(),  //
      e * (-sigma * co - wd * si), e * (-sigma * si + wd * co), v_p(half).real(), -v_p(half).imag();
  const Eigen::Vector4d constant(-f0 / k, 0.0, -f0 / k, 0.0), per_x0(1.0, 0.0, -1.0, 0.0);
  const Eigen::PartialPivLU<Eigen::Matrix4d> lu(a);
  const Eigen::Vector4d y0 = lu.solve(constant), y1 = lu.solve(per_x0);
  const double qa = y1.tail<2>().squaredNorm(), qb = 2.0 * y0.tail<2>().dot(y1.tail<2>()),
               qc = y0.tail<2>().squaredNorm() - 1.0;
  return (-qb + std::sqrt(qb * qb - 4.0 * qa * qc)) / (2.0 * qa);
}

solvers::MoreauJeanOptions mj_options(int steps) {
  solvers::MoreauJeanOptions o;
  o.steps_per_period = steps;
  o.samples_per_period = 1024;
  o.periodicity_tolerance = 1e-9;
  return o;
}

}  // namespace

// Den Hartog's damped steady state (ζ = 5 %, F0/P = 0.2, below and above resonance, continuous
// motion: no sample has ẋ = 0 over a span): the Moreau–Jean amplitude with the Coulomb contact
// solved by Siconos tends to his, within 1e-4 at T/16384 and 5e-6 at T/65536.
TEST(MoreauJeanFriction, TendsToDenHartogsDampedSteadyState) {
  const double zeta = 0.05, p = 1.0, f0 = 0.2, k = std::pow(2.0 * kPi * 10.0, 2);
  const solvers::MechanicalSystem system = point_masses(1, zeta);
  const std::vector<solvers::ContactPoint> contacts{{0, coulomb_law(f0, 1.0)}};  // μ N = F0
  for (const auto& [r, steps, tolerance] : {std::tuple{0.75, 16384, 1e-4}, std::tuple{1.5, 16384, 1e-4},
                                            std::tuple{0.75, 65536, 5e-6}}) {
    const double f = 10.0 * r;
    const auto response = solvers::integrate_moreau_jean_to_periodic(system, {0, p, f}, contacts, mj_options(steps));
    ASSERT_TRUE(response.report.converged()) << response.report.message;
    EXPECT_EQ(response.report.unsettled_lcp_steps, 0) << response.report.message;
    const double exact = den_hartog_damped_amplitude(1.0, 2.0 * zeta * std::sqrt(k), k, p, f0, 2.0 * kPi * f);
    const double amplitude = response.displacement.row(0).cwiseAbs().maxCoeff();
    EXPECT_LT(std::abs(amplitude / exact - 1.0), tolerance) << "r = " << r << ", N = " << steps;
    EXPECT_GT(response.velocity.row(0).cwiseAbs().minCoeff(), 0.0) << "the motion must not stick, r = " << r;
    // The friction force is ±F0 in slip: its mean over each output interval lies in [−F0, F0].
    EXPECT_LE(response.contact_force.row(0).cwiseAbs().maxCoeff(), f0 * (1.0 + 1e-12));
  }
}

// A normal DOF held on a rigid plane by a static load N is a constant normal load N: the 2D
// contact (a rigid stop on y, exact Coulomb on x with `normal` naming it) gives the tangential
// response of a Coulomb contact under N. They differ only by the normal DOF's drift into the
// plane (velocity-level Signorini), about h v at the first impact.
TEST(MoreauJeanFriction, RigidNormalUnderAStaticLoadActsAsAConstantNormalLoad) {
  const double mu = 0.3, n0 = 1.0;
  const solvers::MechanicalSystem system = point_masses(2, 0.02);
  solvers::ContactPoint friction{0, coulomb_law(mu, 0.0)};
  friction.normal = 0;
  const std::vector<solvers::ContactPoint> paired{{1, std::make_shared<contact::RigidStop>(0.0)}, friction};
  const solvers::HarmonicForcing pressed{0, 1.0, 12.0, {{1, n0, 0.0, 0}}};  // x: 1 N at 12 Hz; y: N0 static
  const auto a = solvers::integrate_moreau_jean_to_periodic(system, pressed, paired, mj_options(8192));
  const auto b = solvers::integrate_moreau_jean_to_periodic(system, {0, 1.0, 12.0}, {{0, coulomb_law(mu, n0)}},
                                                            mj_options(8192));
  ASSERT_TRUE(a.report.converged()) << a.report.message;
  ASSERT_TRUE(b.report.converged()) << b.report.message;
  EXPECT_EQ(a.report.unsettled_lcp_steps + b.report.unsettled_lcp_steps, 0);
  EXPECT_LT(solvers::rms_relative_error(a.displacement.row(0).transpose(), b.displacement.row(0).transpose()), 1e-6);
  // The stop's mean reaction is N0; y stays on the plane (drift below 1e-9 m).
  EXPECT_NEAR(a.contact_force.row(0).mean(), n0, 1e-6 * n0);
  EXPECT_LT(a.displacement.row(1).cwiseAbs().maxCoeff(), 1e-9);
}

// A normal load that varies: y is pressed on the plane by N0 + P_y cos ωt (0.2 … 1.8 N), x rubs
// with μ = 0.3. The explicit central differences with a Jenkins element (k_t = s k) whose slip
// force follows a linear penalty normal law (k_n = s k) — no Siconos, no impulses — tend to this
// Coulomb–Signorini reference as s grows, at order s^(−1/2) (the Jenkins element's, see
// test_friction), well above the reference's own error against 2N steps (1.5e-4). Measured:
// 7.5e-2, 1.3e-2, 4.3e-3 at s = 50, 500, 5000 (order 0.62).
TEST(MoreauJeanFriction, JenkinsOnAPenaltyNormalTendsToCoulombSignoriniUnderAVaryingLoad) {
  const double mu = 0.3, k = std::pow(2.0 * kPi * 10.0, 2);
  const solvers::MechanicalSystem system = point_masses(2, 0.02);
  const solvers::HarmonicForcing load{0, 1.0, 12.0, {{1, 0.8}, {1, 1.0, 0.0, 0}}};
  solvers::ContactPoint friction{0, coulomb_law(mu, 0.0)};
  friction.normal = 0;
  const auto reference = solvers::integrate_moreau_jean_to_periodic(
      system, load, {{1, std::make_shared<contact::RigidStop>(0.0)}, friction}, mj_options(8192));
  ASSERT_TRUE(reference.report.converged()) << reference.report.message;
  EXPECT_NEAR(reference.contact_force.row(0).minCoeff(), 0.2, 1e-3);  // N0 − P_y
  EXPECT_NEAR(reference.contact_force.row(0).maxCoeff(), 1.8, 1e-3);  // N0 + P_y
  std::vector<double> errors;
  for (const double s : {50.0, 500.0, 5000.0}) {
    solvers::ContactPoint jenkins{0, std::make_shared<contact::JenkinsLaw>(contact::JenkinsParameters{s * k, mu, 0.0})};
    jenkins.normal = 0;
    const std::vector<solvers::ContactPoint> penalty{
        {1, std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{s * k, 0.0})}, jenkins};
    solvers::CentralDifferenceOptions o;
    o.steps_per_period = 18432;  // h ω_max < 2 at s = 5000 with a margin
    o.samples_per_period = 1024;
    o.periodicity_tolerance = 1e-9;
    const auto cd = solvers::integrate_central_difference_to_periodic(system, load, penalty, o);
    ASSERT_TRUE(cd.report.converged()) << cd.report.message;
    errors.push_back(solvers::rms_relative_error(cd.displacement.row(0).transpose(),
                                                 reference.displacement.row(0).transpose()));
  }
  const double order = std::log10(errors.front() / errors.back()) / 2.0;
  EXPECT_GT(order, 0.4) << errors[0] << " " << errors[1] << " " << errors[2];
  EXPECT_LT(errors[1], errors[0]);
  EXPECT_LT(errors.back(), 1e-2);
}

// A frictionless stop goes through fc2d (μ = 0, a decoupled tangent row) once any contact has
// friction: with a second mass carrying a Coulomb contact without load, the stop's response is
// the projected Gauss–Seidel one (exact for one stop) to rounding.
TEST(MoreauJeanFriction, AFrictionlessStopThroughSiconosEqualsTheProjectedGaussSeidelPath) {
  const solvers::MechanicalSystem system = point_masses(2, 0.02);
  const auto stop = std::make_shared<contact::RigidStop>(4e-4);  // the free amplitude at 7 Hz is 5e-4 m
  const solvers::HarmonicForcing load{0, 1.0, 7.0, {{1, 0.5}}};
  const auto pgs = solvers::integrate_moreau_jean_to_periodic(system, load, {{0, stop}}, mj_options(4096));
  const auto fc2d =
      solvers::integrate_moreau_jean_to_periodic(system, load, {{0, stop}, {1, coulomb_law(0.3, 0.0)}}, mj_options(4096));
  ASSERT_TRUE(pgs.report.converged()) << pgs.report.message;
  ASSERT_TRUE(fc2d.report.converged()) << fc2d.report.message;
  ASSERT_GT(pgs.contact_force.row(0).maxCoeff(), 0.0);  // the stop is hit
  EXPECT_LT((pgs.displacement - fc2d.displacement).cwiseAbs().maxCoeff(), 1e-12 * pgs.displacement.cwiseAbs().maxCoeff());
  EXPECT_EQ(pgs.report.periods, fc2d.report.periods);
}

TEST(MoreauJeanFriction, PairingsItCannotSolveAreRefusedByName) {
  const solvers::MechanicalSystem system = point_masses(2, 0.02);
  const solvers::HarmonicForcing load{0, 1.0, 12.0};
  const auto stop = std::make_shared<contact::RigidStop>(0.0);
  const auto expect_refusal = [&](const std::vector<solvers::ContactPoint>& contacts, const std::string& part) {
    try {
      (void)solvers::integrate_moreau_jean_to_periodic(system, load, contacts, mj_options(1024));
      ADD_FAILURE() << "accepted; expected a message with \"" << part << "\"";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  solvers::ContactPoint friction{0, coulomb_law(0.3, 0.0)};
  friction.normal = 0;
  // The normal law must be a rigid stop.
  expect_refusal({{1, std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{1e6, 0.0})}, friction},
                 "takes its normal load from a rigid stop");
  // A preload beside a rigid normal is refused: the stop's reaction is the load.
  solvers::ContactPoint preloaded{0, coulomb_law(0.3, 0.5)};
  preloaded.normal = 0;
  expect_refusal({{1, stop}, preloaded}, "normal_load = 0.5");
  // One tangent per stop.
  solvers::ContactPoint second{1, coulomb_law(0.3, 0.0), -1, {{0, 1.0}, {1, 1.0}}};
  second.normal = 0;
  solvers::ContactPoint first{0, coulomb_law(0.3, 0.0)};
  first.normal = 0;
  expect_refusal({{1, stop}, first, second}, "already takes its normal load");
  // A Jenkins element has its own reference.
  expect_refusal({{0, std::make_shared<contact::JenkinsLaw>(contact::JenkinsParameters{1e6, 0.3, 1.0})}},
                 "integrate_central_difference_to_periodic");
}
