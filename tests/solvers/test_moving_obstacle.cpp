// Moving counter-surfaces (ContactPoint::obstacle): a law sees u_c − s_c(τ). Truths not produced by
// this code: the closed-form steady state of a 1-DOF oscillator on a linear spring whose far end
// moves (a base excitation through the spring), and its Floquet multipliers e^{λT}; the change of
// coordinates z = u − s, under which a moving obstacle is a fixed one plus the load
// −(m s̈ + c ṡ + k s) (a different path through the solver: forcing instead of obstacle); the
// closed-form force of a mass pressed on a stop that moves; a counter-surface sliding by so fast
// that friction slips one way at every instant (a constant force μN, closed form); and the
// central-difference time stepping of the same problem with an exponential stop.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <memory>
#include <string>
#include <vector>
#include <wbm/contact/friction.hpp>
#include <wbm/contact/penalty.hpp>
#include <wbm/contact/signorini.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/post_processing.hpp>
#include <wbm/solvers/response_curve.hpp>
#include <wbm/solvers/time_basis.hpp>
#include <wbm/solvers/time_integration.hpp>
#include <wbm/solvers/weighted_residual.hpp>

#include "impact_oscillators.hpp"
#include "testing.hpp"

namespace solvers = wbm::solvers;
namespace contact = wbm::contact;
using solvers::TimeBasis;

namespace {

using wbm::testing::kPi;

// m ü + c u̇ + k u = F cos ωt − f_c, m = 1 kg, f_n = 10 Hz, ζ = 2 %.
struct ObstacleOscillator {
  double m = 1.0, k = std::pow(2.0 * kPi * 10.0, 2), c = 2.0 * 0.02 * std::sqrt(std::pow(2.0 * kPi * 10.0, 2));
  double force = 1.0;

  [[nodiscard]] solvers::MechanicalSystem system() const { return wbm::testing::one_dof_system(m, c, k); }
  // The dynamic stiffness at harmonic h of f, with an extra spring k_extra [N/m].
  [[nodiscard]] std::complex<double> dynamic_stiffness(double f, int h, double k_extra = 0.0) const {
    const double w = 2.0 * kPi * f * h;
    return {k + k_extra - w * w * m, w * c};
  }
};

// u(τ) on a grid of the period from trial coefficients (row 0).
Eigen::VectorXd on_obstacle_grid(const TimeBasis& basis, const Eigen::MatrixXd& coefficients,
                                 const Eigen::VectorXd& tau) {
  return basis.values(tau, 0) * coefficients.row(0).transpose();
}

Eigen::VectorXd period_grid(int p) { return Eigen::VectorXd::LinSpaced(p, 0.0, (p - 1.0) / p); }

// s(τ) = Re(S_h e^{2πihτ}) for S_h = a_h − i b_h: the complex amplitude of harmonic h.
std::complex<double> obstacle_harmonic(const solvers::ObstacleMotion& o, int h) {
  const double a = h - 1 < static_cast<int>(o.cosine.size()) ? o.cosine[static_cast<size_t>(h - 1)] : 0.0;
  const double b = h - 1 < static_cast<int>(o.sine.size()) ? o.sine[static_cast<size_t>(h - 1)] : 0.0;
  return {a, -b};
}

// The change of coordinates z = u − s of a 1-DOF oscillator: the load −(m s̈ + c ṡ + k s) on the
// fixed-obstacle problem, one HarmonicLoad per harmonic of s.
solvers::HarmonicForcing obstacle_shifted_forcing(const ObstacleOscillator& o, double f,
                                                  const solvers::ObstacleMotion& s) {
  solvers::HarmonicForcing forcing{0, o.force, f};
  for (int h = 1; h <= s.highest_harmonic(); ++h) {
    const std::complex<double> load = -o.dynamic_stiffness(f, h) * obstacle_harmonic(s, h);
    forcing.more.push_back({0, std::abs(load), std::arg(load), h});
  }
  return forcing;
}

}  // namespace

// ObstacleMotion's own closed forms: s(τ), ds/dτ against a central difference, the drift, the
// highest harmonic, and the bound Σ |S_h|.
TEST(MovingObstacle, TheMotionIsItsFourierSeries) {
  const solvers::ObstacleMotion s{.cosine = {1e-3, 0.0, 2e-4}, .sine = {5e-4}, .drift = -0.3};
  EXPECT_TRUE(s.moving());
  EXPECT_FALSE(solvers::ObstacleMotion{}.moving());
  EXPECT_FALSE((solvers::ObstacleMotion{.cosine = {0.0}, .sine = {0.0, 0.0}}).moving());
  EXPECT_EQ(s.highest_harmonic(), 3);
  for (double tau : {0.0, 0.13, 0.5, 0.97, 1.4}) {
    const double expected =
        -0.3 * tau + 1e-3 * std::cos(2 * kPi * tau) + 2e-4 * std::cos(6 * kPi * tau) + 5e-4 * std::sin(2 * kPi * tau);
    EXPECT_NEAR(s.at(tau), expected, 1e-16);
    const double h = 1e-6;
    EXPECT_NEAR(s.rate(tau), (s.at(tau + h) - s.at(tau - h)) / (2 * h), 1e-8);
  }
  EXPECT_NEAR(s.at(1.25) - s.at(0.25), -0.3, 1e-15);  // one period: the drift
  EXPECT_DOUBLE_EQ(s.amplitude_bound(), std::hypot(1e-3, 5e-4) + 2e-4);
}

// A linear spring k_p between the mass and a counter-surface that moves by s(τ), always in
// contact (g0 = −0.1 m: a preload far beyond the motion): m ü + c u̇ + (k + k_p) u = F cos ωt +
// k_p (s + g0), whose steady state is, harmonic by harmonic, U_h = (F δ_h1 + k_p S_h)/(k + k_p −
// (hω)² m + i hω c), plus the static k_p g0/(k + k_p). Fourier:Fourier carries it exactly (to
// rounding); the Galerkin B-spline pair at M = 64 to its truncation (measured 2.1e-7 of the peak),
// and DB6:Fourier (distributional) likewise; the cell-average quadrature equals the midpoint rule
// on a linear law.
TEST(MovingObstacle, ALinearSpringOnAMovingObstacleIsTheClosedFormResponse) {
  const ObstacleOscillator o;
  const double kp = 3.0 * o.k, g0 = -0.1, f = 8.0;
  const solvers::ObstacleMotion s{.cosine = {1e-3}, .sine = {0.0, 5e-4}};
  const solvers::ContactPoint stop{
      .dof = 0,
      .law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{kp, g0}),
      .obstacle = s};
  const Eigen::VectorXd tau = period_grid(256);
  Eigen::VectorXd exact = Eigen::VectorXd::Constant(tau.size(), kp * g0 / (o.k + kp));
  for (int h = 1; h <= 2; ++h) {
    const std::complex<double> u =
        ((h == 1 ? o.force : 0.0) + kp * obstacle_harmonic(s, h)) / o.dynamic_stiffness(f, h, kp);
    for (Eigen::Index p = 0; p < tau.size(); ++p) exact(p) += std::real(u * std::polar(1.0, 2 * kPi * h * tau(p)));
  }
  const double peak = (exact.array() - exact.mean()).abs().maxCoeff();
  struct Case {
    std::string trial, weighting;
    solvers::ContactQuadrature quadrature;
    double tolerance;  // relative to the peak of the oscillating part
  };
  for (const Case& cs : {Case{"fourier", "fourier", solvers::ContactQuadrature::Midpoint, 1e-10},
                         Case{"fourier", "fourier", solvers::ContactQuadrature::CellAverage, 1e-10},
                         Case{"bspline", "bspline", solvers::ContactQuadrature::Midpoint, 1e-5},
                         Case{"db6", "fourier", solvers::ContactQuadrature::Midpoint, 1e-3}}) {
    const TimeBasis trial =
        cs.trial == "fourier" ? TimeBasis::fourier_harmonics(8) : TimeBasis::from_name(cs.trial, 64);
    const TimeBasis weighting = cs.weighting == "fourier" ? (cs.trial == "fourier" ? trial : TimeBasis::fourier(64))
                                                          : TimeBasis::from_name(cs.weighting, 64);
    const solvers::WeightedResidual w(o.system(), {0, o.force, f}, {stop}, trial, weighting,
                                      {.contact_quadrature = cs.quadrature});
    const auto sol = w.solve();
    ASSERT_TRUE(sol.converged()) << cs.trial << ":" << cs.weighting << " " << sol.brief();
    const Eigen::VectorXd u = on_obstacle_grid(trial, sol.coefficients, tau);
    EXPECT_LT((u - exact).cwiseAbs().maxCoeff(), cs.tolerance * peak) << cs.trial << ":" << cs.weighting;
    // The spring's force k_p (u − s − g0) ≥ 0 and its largest value (relative displacement).
    double largest = 0.0;
    for (Eigen::Index p = 0; p < tau.size(); ++p) largest = std::max(largest, kp * (exact(p) - s.at(tau(p)) - g0));
    EXPECT_NEAR(sol.max_contact_force, largest, 1e-3 * largest) << cs.trial << ":" << cs.weighting;
  }
}

// The change of coordinates z = u − s: an exponential stop that opens and closes against an
// obstacle moving at harmonic 1 gives u = z + s, z the response with the obstacle fixed under the
// extra load −(m s̈ + c ṡ + k s). For Fourier:Fourier both are the same discrete equations (s lies
// in the trial space, the contact samples are the same numbers), to rounding, with the midpoint
// and the cell-average quadratures (the latter's slope ż = u̇ − ṡ); for the B-spline pair s is
// not in the trial space, and the two differ by the truncation (bound 1e-3 of the peak).
TEST(MovingObstacle, AMovingObstacleIsAChangeOfCoordinates) {
  ObstacleOscillator o;
  o.force = 2.0;
  const double f = 9.0, g0 = 5e-4;
  const auto law = std::make_shared<contact::ExponentialPenalty>(contact::ExponentialPenaltyParameters{50.0, 2e3, g0});
  const solvers::ObstacleMotion s{.cosine = {1.5e-3}, .sine = {-1e-3}};
  const Eigen::VectorXd tau = period_grid(512);
  Eigen::VectorXd s_tau(tau.size());
  for (Eigen::Index p = 0; p < tau.size(); ++p) s_tau(p) = s.at(tau(p));
  struct Case {
    std::string pair;
    solvers::ContactQuadrature quadrature;
    double tolerance;
  };
  for (const Case& cs : {Case{"fourier", solvers::ContactQuadrature::Midpoint, 1e-9},
                         Case{"fourier", solvers::ContactQuadrature::CellAverage, 1e-9},
                         Case{"bspline", solvers::ContactQuadrature::Midpoint, 1e-3}}) {
    const TimeBasis basis =
        cs.pair == "fourier" ? TimeBasis::fourier_harmonics(32) : TimeBasis::from_name(cs.pair, 128);
    const solvers::WeightedResidualOptions options{.contact_quadrature = cs.quadrature};
    const solvers::WeightedResidual moving(o.system(), {0, o.force, f}, {{.dof = 0, .law = law, .obstacle = s}}, basis,
                                           basis, options);
    const solvers::WeightedResidual fixed(o.system(), obstacle_shifted_forcing(o, f, s), {{0, law}}, basis, basis,
                                          options);
    const auto a = moving.solve(), b = fixed.solve();
    ASSERT_TRUE(a.converged()) << cs.pair << ": " << a.brief();
    ASSERT_TRUE(b.converged()) << cs.pair << ": " << b.brief();
    const Eigen::VectorXd u = on_obstacle_grid(basis, a.coefficients, tau),
                          z = on_obstacle_grid(basis, b.coefficients, tau);
    ASSERT_GT(b.max_contact_force, 1e-3) << "the stop must close";
    ASSERT_LT(z.minCoeff(), g0) << "and open";
    const double peak = u.cwiseAbs().maxCoeff();
    EXPECT_LT((u - z - s_tau).cwiseAbs().maxCoeff(), cs.tolerance * peak) << cs.pair;
    EXPECT_NEAR(a.max_contact_force, b.max_contact_force, cs.tolerance * 1e2 * b.max_contact_force) << cs.pair;
    EXPECT_NEAR(a.max_penetration, b.max_penetration, cs.tolerance * peak) << cs.pair;
  }
}

// The same change of coordinates with exact contact, Fourier of odd M (every function seen at
// the instants): a rigid stop whose obstacle moves, and exact Coulomb friction whose
// counter-surface oscillates along the tangent (its slips and the full-stick pin relative). The
// impulses are the same numbers to rounding.
TEST(MovingObstacle, ExactContactAgainstAMovingObstacleIsAChangeOfCoordinates) {
  ObstacleOscillator o;
  o.force = 2.0;
  const double f = 9.0;
  const solvers::ObstacleMotion s{.cosine = {1.5e-3}, .sine = {-1e-3}};
  const TimeBasis basis = TimeBasis::fourier_harmonics(24);
  const Eigen::VectorXd tau = period_grid(256);
  const std::vector<std::shared_ptr<const contact::ContactLaw>> laws = {
      std::make_shared<contact::RigidStop>(5e-4),
      std::make_shared<contact::CoulombFriction>(contact::CoulombParameters{0.3, 1.0})};
  for (const auto& law : laws) {
    const solvers::WeightedResidual moving(o.system(), {0, o.force, f}, {{.dof = 0, .law = law, .obstacle = s}}, basis,
                                           basis);
    const solvers::WeightedResidual fixed(o.system(), obstacle_shifted_forcing(o, f, s), {{0, law}}, basis, basis);
    const auto a = moving.solve(), b = fixed.solve();
    ASSERT_TRUE(a.converged()) << law->describe() << ": " << a.brief();
    ASSERT_TRUE(b.converged()) << law->describe() << ": " << b.brief();
    const double lambda_max = b.contact_force_samples.cwiseAbs().maxCoeff();
    ASSERT_GT(lambda_max, 0.05) << law->describe() << ": the contact must carry load";
    EXPECT_LT((a.contact_force_samples - b.contact_force_samples).cwiseAbs().maxCoeff(), 1e-8 * lambda_max)
        << law->describe();
    Eigen::VectorXd s_tau(tau.size());
    for (Eigen::Index p = 0; p < tau.size(); ++p) s_tau(p) = s.at(tau(p));
    const Eigen::VectorXd u = on_obstacle_grid(basis, a.coefficients, tau),
                          z = on_obstacle_grid(basis, b.coefficients, tau);
    EXPECT_LT((u - z - s_tau).cwiseAbs().maxCoeff(), 1e-9 * u.cwiseAbs().maxCoeff()) << law->describe();
    EXPECT_LT(a.complementarity, 1e-9 * moving.residual_scale()) << law->describe();
  }
}

// A mass pressed on a rigid stop by a static load P0 = 500 N while the stop moves by s(τ) =
// a cos 2πτ stays on it: u = g0 + s exactly at the M instants (Fourier of odd M interpolates
// them), and the stop's force is λ(τ) = P0 − k g0 − Re((k − ω²m + iωc) a e^{iωt}) ≥ 0, which the
// impulses λ_k sample at the instants (the M-point sums of harmonic 1 are exact).
TEST(MovingObstacle, AMassPressedOnAMovingStopFollowsIt) {
  const ObstacleOscillator o;
  const double f = 12.0, g0 = 1e-3, p0 = 500.0, a = 2e-3;
  const solvers::ObstacleMotion s{.cosine = {a}};
  const TimeBasis basis = TimeBasis::fourier_harmonics(8);
  solvers::HarmonicForcing forcing{0, 0.0, f, {{0, p0, 0.0, 0}}};
  const solvers::WeightedResidual w(
      o.system(), forcing, {{.dof = 0, .law = std::make_shared<contact::RigidStop>(g0), .obstacle = s}}, basis, basis);
  const auto sol = w.solve();
  ASSERT_TRUE(sol.converged()) << sol.brief();
  const Eigen::VectorXd tk = w.collocation_times();
  const Eigen::VectorXd u = on_obstacle_grid(basis, sol.coefficients, tk);
  const std::complex<double> z = o.dynamic_stiffness(f, 1) * a;
  for (Eigen::Index k = 0; k < tk.size(); ++k) {
    EXPECT_NEAR(u(k), g0 + s.at(tk(k)), 1e-12) << "instant " << k;
    const double lambda = p0 - o.k * g0 - std::real(z * std::polar(1.0, 2 * kPi * tk(k)));
    ASSERT_GT(lambda, 0.0);
    EXPECT_NEAR(sol.contact_force_samples(0, k), lambda, 1e-9 * p0) << "instant " << k;
  }
}

// A counter-surface sliding by d = ∓0.5 m per period, far more than the vibration's 2e-3 m:
// the relative slip has the sign of −d at every instant, so exact Coulomb friction is the constant
// ±μN, and u is the linear response shifted by ∓μN/k (closed form). A Jenkins element (k_t = 100 k)
// carries its slider across the periods (ContactLaw::evaluate_period's shift) and slips at every
// sample too: the same constant force, the same closed form.
TEST(MovingObstacle, ASlidingCounterSurfaceMakesFrictionAConstantForce) {
  const ObstacleOscillator o;
  const double f = 8.0, mu = 0.3, normal = 2.0;
  const auto law = std::make_shared<contact::CoulombFriction>(contact::CoulombParameters{mu, normal});
  const Eigen::VectorXd tau = period_grid(256);
  const std::complex<double> u1 = o.force / o.dynamic_stiffness(f, 1);
  const auto jenkins = std::make_shared<contact::JenkinsLaw>(contact::JenkinsParameters{100.0 * o.k, mu, normal});
  for (const std::string pair : {"fourier", "bspline", "jenkins"}) {
    const bool exact = pair != "jenkins";
    const TimeBasis basis = pair == "bspline" ? TimeBasis::from_name(pair, 64) : TimeBasis::fourier_harmonics(16);
    for (double drift : {-0.5, 0.5}) {
      const solvers::WeightedResidual w(o.system(), {0, o.force, f},
                                        {{.dof = 0,
                                          .law = exact ? std::shared_ptr<const contact::ContactLaw>(law) : jenkins,
                                          .obstacle = {.drift = drift}}},
                                        basis, basis);
      const auto sol = w.solve();
      ASSERT_TRUE(sol.converged()) << pair << " d = " << drift << ": " << sol.brief();
      const double sign = drift < 0.0 ? 1.0 : -1.0;  // the slip u − s grows when the surface recedes
      if (exact) {
        EXPECT_LT((sol.contact_force_samples.array() - sign * mu * normal).abs().maxCoeff(), 1e-12 * mu * normal)
            << pair;
      } else {
        EXPECT_NEAR(sol.max_contact_force, mu * normal, 1e-12 * mu * normal);
      }
      const Eigen::VectorXd u = on_obstacle_grid(basis, sol.coefficients, tau);
      Eigen::VectorXd exact(tau.size());
      for (Eigen::Index p = 0; p < tau.size(); ++p) {
        exact(p) = std::real(u1 * std::polar(1.0, 2 * kPi * tau(p))) - sign * mu * normal / o.k;
      }
      const double tolerance = pair == "fourier" ? 1e-10 : 1e-4;
      EXPECT_LT((u - exact).cwiseAbs().maxCoeff(), tolerance * exact.cwiseAbs().maxCoeff()) << pair << " d = " << drift;
    }
  }
}

// The branch of the spring on a moving obstacle from 7 to 9 Hz, with stability: every point is the
// closed form at its frequency (the obstacle moves in τ, with the period), and the monodromy
// matrix is that of the linear system of stiffness k + k_p, μ = e^{(−ζ'ω' ± iω'_d)T} (its modulus
// e^{−cT/2m} for any stiffness, its argument ω'_d T that of k + k_p alone). Here the
// mass's own displacement crosses g0 (so a monodromy taken on it instead of u − s would open the
// spring for part of each period), while u − s never does.
TEST(MovingObstacle, TheBranchAndItsFloquetMultipliersAreTheClosedForm) {
  const ObstacleOscillator o;
  const double kp = 3.0 * o.k, g0 = -0.1;  // u − s − g0 ≥ 0.018 m at every instant and frequency
  const solvers::ObstacleMotion s{.cosine = {5e-2}};
  const TimeBasis basis = TimeBasis::fourier_harmonics(8);
  const solvers::WeightedResidual w(
      o.system(), {0, o.force, 7.0},
      {{.dof = 0,
        .law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{kp, g0}),
        .obstacle = s}},
      basis, basis);
  const solvers::ResponseCurve curve =
      solvers::trace_response(w, {.parameter_min = 7.0, .parameter_max = 9.0, .max_step = 0.05});
  ASSERT_GT(curve.points.size(), 5U) << curve.message;
  EXPECT_NEAR(curve.points.back().frequency_hz, 9.0, 1e-9) << curve.message;
  const double wn = std::sqrt((o.k + kp) / o.m), zeta = o.c / (2.0 * std::sqrt((o.k + kp) * o.m));
  bool crosses = false;
  for (const auto& p : curve.points) {
    const std::complex<double> u = (o.force + kp * s.cosine[0]) / o.dynamic_stiffness(p.frequency_hz, 1, kp);
    const double mean = kp * g0 / (o.k + kp);
    // The largest of P = 512 samples: within 1 − cos(π/P) = 1.9e-5 of the peak.
    EXPECT_NEAR(p.max_displacement, mean + std::abs(u), 2e-5 * std::abs(u)) << p.frequency_hz;
    crosses = crosses || p.min_displacement < g0;
    ASSERT_TRUE(p.stability_available);
    const double t = 1.0 / p.frequency_hz;
    const std::complex<double> exact = std::exp(std::complex<double>(-zeta * wn, wn * std::sqrt(1 - zeta * zeta)) * t);
    const std::complex<double> mu = p.leading_multiplier;
    EXPECT_NEAR(std::abs(mu), std::abs(exact), 1e-6) << p.frequency_hz;
    // The stepping's phase error, second order: (hω')²/12 per step, 9e-4 rad over P = 512 steps.
    EXPECT_NEAR(std::abs(std::arg(mu)), std::abs(std::arg(exact)), 2e-3) << p.frequency_hz;
  }
  EXPECT_TRUE(crosses) << "the mass itself must pass g0 for this test to tell u from u − s";
}

// Central differences in time (a different method: no basis, physical time; at 8192 steps per
// period its difference from 4096 and 16384 steps is below 1e-6 here) of an exponential stop against an obstacle moving
// at harmonics 1 and 2, below resonance (6 Hz, ζ = 5 %, a stable orbit that the time stepping settles on). The harmonic
// balance with the cell-average quadrature (its slope relative to the surface, u̇ − ṡ) converges to it at second order
// in H: measured rms 1.0e-4, 4.4e-5, 1.1e-5 at H = 48, 96, 192, as with the obstacle fixed (2.1e-4, 9.1e-5, 2.3e-5
// under a larger load).
TEST(MovingObstacle, HarmonicBalanceConvergesToCentralDifferences) {
  ObstacleOscillator o;
  o.c = 2.0 * 0.05 * std::sqrt(o.k * o.m);  // ζ = 5 %
  const double f = 6.0, g0 = 5e-4;
  const auto law = std::make_shared<contact::ExponentialPenalty>(contact::ExponentialPenaltyParameters{50.0, 2e3, g0});
  const std::vector<solvers::ContactPoint> contacts = {
      {.dof = 0, .law = law, .obstacle = {.cosine = {1.5e-3, 4e-4}, .sine = {-1e-3}}}};
  const auto ref = solvers::integrate_central_difference_to_periodic(
      o.system(), {0, o.force, f}, contacts, {.steps_per_period = 8192, .samples_per_period = 256});
  ASSERT_EQ(ref.report.status, solvers::SolveStatus::Converged) << ref.report.message;
  ASSERT_GT(ref.contact_force.maxCoeff(), 1.0) << "the stop must close";
  ASSERT_EQ(ref.contact_force.minCoeff(), 0.0) << "and open";
  std::vector<double> sizes, errors;
  for (int h : {48, 96, 192}) {
    const TimeBasis basis = TimeBasis::fourier_harmonics(h);
    const solvers::WeightedResidual w(o.system(), {0, o.force, f}, contacts, basis, basis,
                                      {.contact_quadrature = solvers::ContactQuadrature::CellAverage});
    const auto sol = w.solve();
    ASSERT_TRUE(sol.converged()) << "H = " << h << ": " << sol.brief();
    const Eigen::VectorXd u = on_obstacle_grid(basis, sol.coefficients, ref.tau);
    sizes.push_back(h);
    errors.push_back(solvers::rms_relative_error(u, ref.displacement.row(0).transpose()));
  }
  EXPECT_GT(-wbm::testing::observed_order(sizes, errors), 1.5);
  EXPECT_LT(errors.back(), 3e-5);
}

// The full residual's Jacobian against central differences, with moving counter-surfaces on both
// contacts of a 2D Jenkins contact: a linear normal spring whose obstacle oscillates (it opens and
// closes) and a Jenkins element under its varying normal load, its counter-surface sliding by
// 0.05 m per period (the slider carried across the period) and oscillating along the tangent.
TEST(MovingObstacle, JacobianWithMovingCounterSurfacesMatchesCentralDifferences) {
  const ObstacleOscillator o;
  solvers::MechanicalSystem two;
  two.mass = (o.m * Eigen::MatrixXd::Identity(2, 2)).sparseView();
  two.stiffness = (o.k * Eigen::MatrixXd::Identity(2, 2)).sparseView();
  two.damping = (o.c * Eigen::MatrixXd::Identity(2, 2)).sparseView();
  const auto normal = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{1e5, 0.0});
  const auto jenkins = std::make_shared<contact::JenkinsLaw>(contact::JenkinsParameters{1e5, 0.15, 0.0});
  const std::vector<solvers::ContactPoint> contacts = {
      {.dof = 0, .law = normal, .obstacle = {.cosine = {1e-3}}},
      {.dof = 1, .law = jenkins, .normal = 0, .obstacle = {.cosine = {0.0, 2e-4}, .drift = -0.05}}};
  const int harmonics = 8;
  const TimeBasis basis = TimeBasis::fourier_harmonics(harmonics);
  const solvers::WeightedResidual w(two, {0, 0.0, 20.0, {{0, 2.0, 0.0, 0}}}, contacts, basis, basis,
                                    {.time_samples = 256});
  // A state where the normal spring opens over part of the period: u_x = 5e-4 + 1.2e-3 cos 2πτ,
  // u_y = 3e-4 sin 2πτ (coefficients of the stacked layout: DOF-major within each function).
  const int m = basis.dimension();
  Eigen::VectorXd a = Eigen::VectorXd::Zero(2 * m);
  const Eigen::VectorXd tau = period_grid(m);
  const Eigen::VectorXd ux = (5e-4 + 1.2e-3 * (2.0 * kPi * tau.array()).cos()).matrix();
  const Eigen::VectorXd uy = (3e-4 * (2.0 * kPi * tau.array()).sin()).matrix();
  const Eigen::MatrixXd fit =
      basis.values(tau, 0).colPivHouseholderQr().solve((Eigen::MatrixXd(m, 2) << ux, uy).finished());
  for (int k = 0; k < m; ++k) {
    a(2 * k) = fit(k, 0);
    a(2 * k + 1) = fit(k, 1);
  }
  const Eigen::MatrixXd j = w.jacobian(a);
  const double h = 1e-9;
  for (int col = 0; col < 2 * m; ++col) {
    Eigen::VectorXd ap = a, am = a;
    ap(col) += h;
    am(col) -= h;
    const Eigen::VectorXd fd = (w.residual(ap) - w.residual(am)) / (2.0 * h);
    EXPECT_LT((fd - j.col(col)).cwiseAbs().maxCoeff(), 1e-6 * j.cwiseAbs().maxCoeff()) << "column " << col;
  }
}

// What is not modelled is refused by name, with the way out.
TEST(MovingObstacle, WhatIsNotModelledIsRefused) {
  const ObstacleOscillator o;
  const TimeBasis basis = TimeBasis::fourier_harmonics(8);
  const auto stop = std::make_shared<contact::RigidStop>(1e-3);
  const auto spring = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{o.k, 1e-3});
  using wbm::testing::expect_throw_with;
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)solvers::WeightedResidual(o.system(), {0, 1.0, 8.0},
                                        {{.dof = 0, .law = spring, .obstacle = {.drift = 1e-3}}}, basis, basis);
      },
      {"obstacle", "drift", "no periodic response", "drift = 0"});
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)solvers::WeightedResidual(o.system(), {0, 1.0, 8.0},
                                        {{.dof = 0, .law = spring, .obstacle = {.sine = {0.0, NAN}}}}, basis, basis);
      },
      {"sine[1]", "harmonic 2", "finite"});
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)solvers::WeightedResidual(
            o.system(), {0, 1.0, 8.0},
            {{.dof = 0, .law = spring, .obstacle = {.cosine = std::vector<double>(9, 1e-4)}}}, basis, basis);
      },
      {"harmonic 9", "M = 17", "raise the basis dimension"});
  const std::vector<solvers::ContactPoint> moving_stop = {{.dof = 0, .law = stop, .obstacle = {.cosine = {1e-4}}}};
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)solvers::integrate_moreau_jean_to_periodic(o.system(), {0, 1.0, 8.0}, moving_stop);
      },
      {"integrate_moreau_jean_to_periodic", "moving counter-surface", "weighted residual"});
  expect_throw_with<std::invalid_argument>(
      [&] {
        const solvers::WeightedResidual w(o.system(), {0, 1.0, 8.0}, moving_stop, basis, basis);
        (void)solvers::trace_response(w, {.parameter_min = 7.0, .parameter_max = 9.0});
      },
      {"stability = true", "moving counter-surface", "stability = false"});
  const std::vector<solvers::ContactPoint> moving_spring = {{.dof = 0, .law = spring, .obstacle = {.cosine = {1e-4}}}};
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)solvers::integrate_to_periodic(o.system(), {0, 1.0, 8.0}, moving_spring);
      },
      {"BDF", "integrate_central_difference_to_periodic"});
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)solvers::system_energy(o.system(), moving_spring, Eigen::MatrixXd::Zero(1, 4),
                                     Eigen::MatrixXd::Zero(1, 4));
      },
      {"system_energy", "works on the structure"});
}
