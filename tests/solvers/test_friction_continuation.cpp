// Continuation in the friction coefficient μ (ContinuationParameter::FrictionCoefficient): every
// Jenkins element's μ is the parameter, G is kept, ∂r/∂μ is analytic. Truths not produced by this
// code:
//  - Den Hartog's (1931) closed-form steady state of an undamped oscillator with Coulomb
//    friction F0 = μN and a harmonic force, continuous motion, which a stiff Jenkins element
//    approaches (test_friction measures the rate in k_t); every point of the branch in μ against
//    the closed form at its own μ;
//  - central differences of the residual in μ between problems built from scratch at μ ± δ (the
//    slow path, without set_friction_coefficient), under a constant and a varying normal load;
//  - full stick: once μN exceeds the largest elastic force the element is a spring k_t, and the
//    Floquet multipliers are e^{λT} of the linear oscillator with k + k_t.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include <wbm/contact/friction.hpp>
#include <wbm/contact/penalty.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/response_curve.hpp>
#include <wbm/solvers/time_basis.hpp>
#include <wbm/solvers/weighted_residual.hpp>
#include <wbm/spectral/layout.hpp>

#include "impact_oscillators.hpp"
#include "testing.hpp"

namespace wbm::solvers {
namespace {

using wbm::testing::kPi;
const double kMuOscillatorStiffness = std::pow(2.0 * kPi * 10.0, 2);  // 1 kg at f_n = 10 Hz

std::shared_ptr<const contact::JenkinsLaw> element(double kt, double mu, double normal_load) {
  return std::make_shared<contact::JenkinsLaw>(contact::JenkinsParameters{kt, mu, normal_load});
}

// Den Hartog's amplitude x0 of the continuous motion of m ẍ + k x + F0 sign(ẋ) = P0 cos ωt at
// r = ω/ω_n (m = 1 kg, P0 = 1 N): x0 = (P0/k) √((1/(1 − r²))² − (F0 U/P0)²), U = tan(π/(2r))/r
// (the derivation is in test_friction.cpp, Den Hartog, Phil. Mag. (7) 9 (1930) 801–817).
double den_hartog_amplitude(double r, double f0) {
  const double k = kMuOscillatorStiffness, u = std::tan(kPi / (2.0 * r)) / r;
  return 1.0 / k * std::sqrt(std::pow(1.0 / (1.0 - r * r), 2) - std::pow(f0 * u, 2));
}

// Every point of the branch in μ from 0.05 to 0.3 at r = 0.75 (N = 1 N, so F0 = μ) against Den
// Hartog's amplitude at its own μ. k_t = 1e4 k, Fourier H = 128, Q = 4096: the Jenkins element's
// own distance from Coulomb is 1e-3 … 2.5e-3 at F0 = 0.2 (test_friction); measured here 1.2e-4 at
// μ = 0.05 up to 2.0e-3 at 0.3 (44 points). The slip force μN is reached at every point: the
// element slips there.
TEST(FrictionContinuation, EveryPointOfTheBranchInMuIsDenHartogsSteadyStateAtItsMu) {
  const double k = kMuOscillatorStiffness, r = 0.75;
  const MechanicalSystem s = wbm::testing::one_dof_system(1.0, 0.0, k);
  const TimeBasis basis = TimeBasis::fourier_harmonics(128);
  const WeightedResidual base(s, {0, 1.0, 10.0 * r}, {{0, element(1e4 * k, 0.05, 1.0)}}, basis, basis,
                              {.time_samples = 4096});
  ResponseCurveOptions o;
  o.parameter = ContinuationParameter::FrictionCoefficient;
  o.parameter_min = 0.05;
  o.parameter_max = 0.3;
  o.samples = 4096;
  o.stability = false;  // undamped: the multipliers sit on the unit circle
  const ResponseCurve curve = trace_response(base, o);
  ASSERT_TRUE(curve.converged()) << curve.brief() << ": " << curve.message;
  ASSERT_GE(curve.points.size(), 5U);
  EXPECT_DOUBLE_EQ(curve.points.back().parameter, 0.3);
  double worst = 0.0;
  for (const ResponsePoint& p : curve.points) {
    EXPECT_DOUBLE_EQ(p.frequency_hz, 10.0 * r);
    const double exact = den_hartog_amplitude(r, p.parameter);
    worst = std::max(worst, std::abs(p.amplitude / exact - 1.0));
    EXPECT_NEAR(p.max_contact_force, p.parameter, 1e-12) << "mu = " << p.parameter;
  }
  EXPECT_LT(worst, 4e-3);
  // Friction lowers the amplitude at every step, as Den Hartog's x0 falls with F0.
  for (size_t i = 1; i < curve.points.size(); ++i) {
    EXPECT_LT(curve.points[i].amplitude, curve.points[i - 1].amplitude) << "mu = " << curve.points[i].parameter;
  }
}

// A 2-DOF contact: DOF 0 normal, pressed by a preloaded penalty (its force varies with u_0), DOF 1
// tangential with a Jenkins element whose slip force is μ (N + n(u_0)); both DOFs driven at 8 Hz
// so that the element sticks and slips within the period.
struct Pressed {
  double k0 = std::pow(2.0 * kPi * 10.0, 2), k1 = std::pow(2.0 * kPi * 12.0, 2), c = 1.0;
  [[nodiscard]] MechanicalSystem system() const {
    MechanicalSystem s;
    s.mass = Eigen::MatrixXd::Identity(2, 2).sparseView();
    s.stiffness = (Eigen::MatrixXd(2, 2) << k0, 100.0, 100.0, k1).finished().sparseView();
    s.damping = (c * Eigen::MatrixXd::Identity(2, 2)).sparseView();
    return s;
  }
  [[nodiscard]] std::vector<ContactPoint> contacts(double mu, bool varying) const {
    ContactPoint normal{0, std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{2e4, -2e-4})};
    ContactPoint tangent{1, element(5e4, mu, varying ? 0.5 : 2.0)};
    if (varying) tangent.normal = 0;
    return {normal, tangent};
  }
  [[nodiscard]] WeightedResidual problem(double mu, bool varying, const TimeBasis& basis) const {
    HarmonicForcing forcing{1, 3.0, 8.0};
    forcing.more.push_back({0, 2.0, 0.7});
    return {system(), forcing, contacts(mu, varying), basis, basis, {.time_samples = 1024}};
  }
};

// ∂r/∂μ (analytic, on the problem whose μ was set in place) against central differences of
// problems built from scratch at μ ± δ, at a solved stick–slip state, for Fourier and DB6, with a
// constant and a varying normal load (measured 5e-11 … 1.4e-10 of max |∂r/∂μ|); and the residual
// of the set problem equals the fresh one's (bit for bit, measured). At μ = 0 every sample slips
// and ∂r/∂μ is the one-sided limit: a forward difference. r is linear in μ while every sample
// slips, so the difference has no truncation error and its rounding is about ε‖r‖/h: the step is
// 1e-6, where every sample still slips (measured 1.3e-10 … 1.3e-9 of max |∂r/∂μ|; with 1e-9 the
// rounding alone was 1.1e-7 to 1.1e-6, depending on the order of the compliance products' sums).
TEST(FrictionContinuation, TheDerivativeInMuMatchesDifferencesOfProblemsBuiltAtEachMu) {
  const Pressed d;
  for (const bool varying : {false, true}) {
    for (const std::string name : {"fourier", "db6"}) {
      const TimeBasis basis = name == "fourier" ? TimeBasis::fourier_harmonics(16) : TimeBasis::from_name(name, 32);
      const double mu = 1.2;
      const auto solved = d.problem(mu, varying, basis).solve();
      ASSERT_TRUE(solved.converged()) << name << ": " << solved.brief();
      // The state sticks and slips: both kinds of samples are in the loop at x (measured: stuck at
      // 13 … 41 % of the samples).
      const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(1024, 0.5 / 1024, 1.0 - 0.5 / 1024);
      const Eigen::MatrixXd u = basis.values(tau, 0) * solved.coefficients.transpose();  // Q × 2
      Eigen::VectorXd normal(u.rows()), normal_stiffness(u.rows());
      const std::vector<ContactPoint> contacts = d.contacts(mu, varying);  // owns the laws read below
      contacts[0].law->evaluate(u.col(0), normal, normal_stiffness);
      if (!varying) normal.setZero();
      const auto* law = dynamic_cast<const contact::JenkinsLaw*>(contacts[1].law.get());
      ASSERT_NE(law, nullptr);
      const int slipping = law->loop(u.col(1), normal).slipping_samples;
      EXPECT_GT(slipping, 100) << name;
      EXPECT_LT(slipping, 924) << name;
      WeightedResidual set = d.problem(0.1, varying, basis);
      set.set_friction_coefficient(mu);
      const Eigen::VectorXd x = set.contact_unknowns(spectral::stacked(solved.coefficients));
      const Eigen::VectorXd fresh = d.problem(mu, varying, basis).contact_residual(x);
      EXPECT_LT((set.contact_residual(x) - fresh).cwiseAbs().maxCoeff(), 1e-12 * x.cwiseAbs().maxCoeff() /
                                                                            set.residual_scale())
          << name;
      const Eigen::VectorXd analytic = set.contact_residual_friction_derivative(x);
      ASSERT_GT(analytic.cwiseAbs().maxCoeff(), 0.0);
      const double delta = 1e-6;
      const Eigen::VectorXd central = (d.problem(mu + delta, varying, basis).contact_residual(x) -
                                       d.problem(mu - delta, varying, basis).contact_residual(x)) /
                                      (2.0 * delta);
      EXPECT_LT((analytic - central).cwiseAbs().maxCoeff(), 1e-8 * analytic.cwiseAbs().maxCoeff())
          << name << (varying ? ", varying load" : ", constant load");
      set.set_friction_coefficient(0.0);
      const Eigen::VectorXd at_zero = set.contact_residual_friction_derivative(x);
      const double h = 1e-6;
      const Eigen::VectorXd forward =
          (d.problem(h, varying, basis).contact_residual(x) - d.problem(0.0, varying, basis).contact_residual(x)) / h;
      EXPECT_LT((at_zero - forward).cwiseAbs().maxCoeff(), 1e-8 * at_zero.cwiseAbs().maxCoeff())
          << name << " at mu = 0" << (varying ? ", varying load" : ", constant load");
    }
  }
}

// A damped oscillator (ζ = 2 %, k_t = 2k, 1 N at 12 Hz, N = 1 N) continued from μ = 0.05, where
// the element slips over most of the cycle, to μ = 2, above the largest elastic force k_t |X|
// (about 1.3 N): full stick, whose multipliers are e^{λT} of the oscillator with k + k_t. Each
// point's stability takes its own μ; with the start's, the last point would slip. Every point is
// stable (incremental passivity under a constant normal load). Measured at P = 2048: |μ| equal to
// 8 digits, arg 3.3e-6 off (the second-order stepping), 55 points.
TEST(FrictionContinuation, StabilityAlongTheBranchInMuReachesTheFullStickClosedForm) {
  const double k = kMuOscillatorStiffness, kt = 2.0 * k, c = 2.0 * 0.02 * std::sqrt(k), f = 12.0;
  const MechanicalSystem s = wbm::testing::one_dof_system(1.0, c, k);
  const TimeBasis basis = TimeBasis::fourier_harmonics(32);
  const WeightedResidual base(s, {0, 1.0, f}, {{0, element(kt, 0.05, 1.0)}}, basis, basis, {.time_samples = 1024});
  ResponseCurveOptions o;
  o.parameter = ContinuationParameter::FrictionCoefficient;
  o.parameter_min = 0.05;
  o.parameter_max = 2.0;
  o.samples = 2048;
  o.stability = true;
  const ResponseCurve curve = trace_response(base, o);
  ASSERT_TRUE(curve.converged()) << curve.brief() << ": " << curve.message;
  for (const ResponsePoint& p : curve.points) EXPECT_TRUE(p.stable) << "mu = " << p.parameter;
  // The characteristic roots of s² + c s + (k + k_t) = 0, and e^{λT}.
  const std::complex<double> lambda =
      0.5 * (-c + std::sqrt(std::complex<double>(c * c - 4.0 * (k + kt), 0.0)));
  const std::complex<double> exact = std::exp(lambda / f);
  const ResponsePoint& last = curve.points.back();
  EXPECT_LT(last.max_contact_force, 2.0);  // below μN = 2 N: full stick
  EXPECT_NEAR(std::abs(last.leading_multiplier), std::abs(exact), 1e-5);
  EXPECT_NEAR(std::abs(std::arg(last.leading_multiplier)), std::abs(std::arg(exact)), 1e-5);
  // The start slips: its multipliers are not those of the stuck oscillator.
  EXPECT_GT(std::abs(std::abs(curve.points.front().leading_multiplier) - std::abs(exact)), 1e-3);
  // On two threads each point's own analysis at its μ runs beside the continuation
  // (point_stability.hpp); on one, after it: the same multipliers to the bit.
  o.threads = 1;
  const ResponseCurve serial = trace_response(base, o);
  o.threads = 2;
  const ResponseCurve beside = trace_response(base, o);
  ASSERT_EQ(serial.points.size(), beside.points.size());
  EXPECT_EQ(serial.stability_points_beside, 0);
  EXPECT_GT(beside.stability_points_beside, static_cast<int>(beside.points.size()) / 2);  // most beside it
  for (size_t i = 0; i < serial.points.size(); ++i) {
    EXPECT_EQ(serial.points[i].leading_multiplier, beside.points[i].leading_multiplier) << i;
    EXPECT_EQ(serial.points[i].max_multiplier_error, beside.points[i].max_multiplier_error) << i;
  }
}

// What the parameter cannot vary is refused by name, with the way out.
TEST(FrictionContinuation, RefusesWhatItCannotVary) {
  const double k = kMuOscillatorStiffness;
  const MechanicalSystem s = wbm::testing::one_dof_system(1.0, 1.0, k);
  const TimeBasis basis = TimeBasis::fourier_harmonics(8);
  ResponseCurveOptions o;
  o.parameter = ContinuationParameter::FrictionCoefficient;
  o.parameter_min = 0.0;
  o.parameter_max = 1.0;
  o.stability = false;
  MechanicalSystem two;
  two.mass = Eigen::MatrixXd::Identity(2, 2).sparseView();
  two.stiffness = (k * Eigen::MatrixXd::Identity(2, 2)).sparseView();
  two.damping = Eigen::MatrixXd::Identity(2, 2).sparseView();
  const WeightedResidual unequal(two, {0, 1.0, 8.0}, {{0, element(1e5, 0.1, 1.0)}, {1, element(1e5, 0.2, 1.0)}},
                                 basis, basis);
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)trace_response(unequal, o); },
                                                         {"contacts 0 and 1", "mu = 0.1 and 0.2", "start's mu"});
  const WeightedResidual penalty(s, {0, 1.0, 8.0},
                                 {{0, std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{1e5, 1e-4})}},
                                 basis, basis);
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)trace_response(penalty, o); },
                                                         {"no contact is a Jenkins element"});
  const WeightedResidual coulomb(
      s, {0, 1.0, 8.0}, {{0, std::make_shared<contact::CoulombFriction>(contact::CoulombParameters{0.1, 1.0})}}, basis,
      basis);
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)trace_response(coulomb, o); },
                                                         {"exact Coulomb friction", "law \"jenkins\""});
  const WeightedResidual jenkins(s, {0, 1.0, 8.0}, {{0, element(1e5, 0.1, 1.0)}}, basis, basis);
  o.parameter_min = -0.1;
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)trace_response(jenkins, o); },
                                                         {"parameter_min = -0.1", "must be >= 0"});
  WeightedResidual set(s, {0, 1.0, 8.0}, {{0, element(1e5, 0.1, 1.0)}}, basis, basis);
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { set.set_friction_coefficient(-1.0); },
                                                         {"mu = -1", "finite and >= 0"});
}

}  // namespace
}  // namespace wbm::solvers
