// Friction in the weighted residual: the Jenkins element (contact::JenkinsLaw through
// ContactLaw::evaluate_period) and exact Coulomb friction (contact::CoulombFriction, multipliers at
// the collocation instants). Truths not produced by this code: Den Hartog's (1931) exact steady
// state of an undamped 1-DOF oscillator with Coulomb friction and a harmonic force, for
// continuous motion, which the Jenkins element tends to as k_t → ∞ and exact Coulomb friction as
// M grows; full stick, where friction carries the whole load P cos ωt and the mass stays put;
// central differences of the residuals in the unknowns, the frequency and the load.
#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <wbm/contact/friction.hpp>
#include <wbm/contact/signorini.hpp>
#include <wbm/solvers/floquet.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/response_curve.hpp>
#include <wbm/solvers/time_integration.hpp>
#include <wbm/spectral/layout.hpp>
#include <wbm/solvers/time_basis.hpp>
#include <wbm/solvers/weighted_residual.hpp>

#include "testing.hpp"

namespace solvers = wbm::solvers;
namespace contact = wbm::contact;
using solvers::TimeBasis;

namespace {

using wbm::testing::kPi;

// m ẍ + k x + F0 sign(ẋ) = P0 cos ωt: m = 1 kg, f_n = 10 Hz, P0 = 1 N, F0 = 0.2 N.
struct DenHartog {
  double m = 1.0, k = std::pow(2.0 * kPi * 10.0, 2), p0 = 1.0, f0 = 0.2;

  [[nodiscard]] solvers::MechanicalSystem system() const {
    solvers::MechanicalSystem s;
    s.mass.resize(1, 1);
    s.mass.insert(0, 0) = m;
    s.stiffness.resize(1, 1);
    s.stiffness.insert(0, 0) = k;
    s.damping.resize(1, 1);  // undamped: Coulomb friction only
    return s;
  }
  [[nodiscard]] std::shared_ptr<const contact::JenkinsLaw> jenkins(double kt) const {
    return std::make_shared<contact::JenkinsLaw>(contact::JenkinsParameters{kt, f0, 1.0});  // μ N = F0
  }
  [[nodiscard]] std::shared_ptr<const contact::CoulombFriction> coulomb() const {
    return std::make_shared<contact::CoulombFriction>(contact::CoulombParameters{f0, 1.0});  // μ N = F0
  }
  // The amplitude x0 of the continuous motion at r = ω/ω_n. Over the half period from x0 down to
  // −x0 (friction +F0), x = F0/k + A cos(τ/r) + B sin(τ/r) + D cos(τ + φ), D = (P0/k)/(1 − r²);
  // the four conditions x(0) = x0, ẋ(0) = 0, x(π) = −x0, ẋ(π) = 0 give D sin φ = −(F0/k) U with
  // U = tan(π/(2r))/r, and x0 = D cos φ, so x0 = (P0/k) √((1/(1 − r²))² − (F0 U/P0)²) [Den Hartog,
  // Phil. Mag. (7) 9 (1930) 801–817, Sec. II, derived here as above].
  [[nodiscard]] double amplitude(double r) const {
    const double u = std::tan(kPi / (2.0 * r)) / r;
    return p0 / k * std::sqrt(std::pow(1.0 / (1.0 - r * r), 2) - std::pow(f0 * u / p0, 2));
  }
};

// max |u(τ)| of the solution on a fine grid.
double peak(const TimeBasis& basis, const Eigen::MatrixXd& coefficients) {
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(4096, 0.0, 4095.0 / 4096.0);
  return (basis.values(tau, 0) * coefficients.row(0).transpose()).cwiseAbs().maxCoeff();
}

}  // namespace

// The residual's Jacobian with a Jenkins element (stick samples hanging on their last slip)
// equals central differences of the residual, for Fourier:Fourier and for wavelet pairs.
TEST(Friction, JacobianOfTheWeightedResidualMatchesCentralDifferences) {
  const DenHartog d;
  for (const std::string pair : {"fourier", "db6", "bspline"}) {
    const int dimension = 32;
    const TimeBasis basis = TimeBasis::from_name(pair, dimension);
    const solvers::WeightedResidual w(d.system(), {0, d.p0, 15.0}, {{0, d.jenkins(50.0 * d.k)}}, basis, basis,
                                      {.time_samples = 512});
    Eigen::VectorXd a = Eigen::VectorXd::Zero(dimension);
    Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(dimension, 0.0, (dimension - 1.0) / dimension);
    // Coefficients of u(τ) ≈ 2e-4 cos 2πτ + 5e-5 sin 6πτ: a least-squares fit at the grid.
    const Eigen::VectorXd target =
        2e-4 * (2.0 * kPi * tau.array()).cos() + 5e-5 * (6.0 * kPi * tau.array()).sin();
    a = basis.values(tau, 0).colPivHouseholderQr().solve(target);
    // The stick samples' term takes the basis at the samples (SampledBasis::rows_at): a Fourier
    // basis is evaluated at them until the rows asked for add up to Q, then read from its table
    // of all Q samples. Both give the same entries, and the central differences check the latter.
    const Eigen::MatrixXd first = w.jacobian(a);
    Eigen::MatrixXd j = first;
    for (int call = 0; call < 48; ++call) j = w.jacobian(a);  // 12 stick rows a call here, Q = 512
    EXPECT_EQ((j - first).cwiseAbs().maxCoeff(), 0.0) << pair;
    const double h = 1e-7 * a.cwiseAbs().maxCoeff();
    for (int col = 0; col < dimension; ++col) {
      Eigen::VectorXd ap = a, am = a;
      ap(col) += h;
      am(col) -= h;
      const Eigen::VectorXd fd = (w.residual(ap) - w.residual(am)) / (2.0 * h);
      EXPECT_LT((fd - j.col(col)).cwiseAbs().maxCoeff(), 1e-6 * j.cwiseAbs().maxCoeff()) << pair << " column " << col;
    }
  }
}

// Den Hartog's continuous motion below and above resonance (r = 0.75, 1.5), by Fourier:Fourier
// (H = 128) and the Galerkin DB6 and B-spline pairs (M = 256), Q = 4096 samples: the Jenkins
// element tends to his Coulomb amplitude as k_t grows, with an error ∝ k_t^(−1/2). Near a
// reversal x ≈ x0 − ½|ẍ| t², and the element sticks until x has moved by 2F0/k_t, a time
// ∝ (F0/k_t)^(1/2) per half period: each decade of k_t divides the error by about √10 = 3.16
// (measured 2.6 … 3.2), and at k_t = 1e4 k it is below 3.5e-3 (measured 1.0e-3 … 2.5e-3). The
// largest friction force is μN itself: the element slips.
TEST(Friction, JenkinsTendsToDenHartogsCoulombSteadyStateAsTheTangentialStiffnessGrows) {
  const DenHartog d;
  for (const std::string pair : {"fourier", "db6", "bspline"}) {
    const TimeBasis basis = pair == "fourier" ? TimeBasis::fourier_harmonics(128) : TimeBasis::from_name(pair, 256);
    for (double r : {0.75, 1.5}) {
      const double exact = d.amplitude(r);
      std::vector<double> errors;
      for (double ratio : {1e2, 1e3, 1e4}) {  // k_t / k
        const solvers::WeightedResidual w(d.system(), {0, d.p0, 10.0 * r}, {{0, d.jenkins(ratio * d.k)}}, basis, basis,
                                          {.time_samples = 4096});
        const auto s = w.solve();
        ASSERT_TRUE(s.converged()) << pair << " r = " << r << ": " << s.brief();
        EXPECT_NEAR(s.max_contact_force, d.f0, 1e-12 * d.f0) << pair << " r = " << r;
        errors.push_back(std::abs(peak(basis, s.coefficients) / exact - 1.0));
      }
      for (size_t i = 1; i < errors.size(); ++i) {
        const double rate = errors[i - 1] / errors[i];
        EXPECT_GT(rate, 2.4) << pair << " r = " << r << " decade " << i;
        EXPECT_LT(rate, 4.0) << pair << " r = " << r << " decade " << i;
      }
      EXPECT_LT(errors.back(), 3.5e-3) << pair << " r = " << r;
    }
  }
}

// What friction does not have yet is refused by name: the cell-average quadrature (a law f(u)).
TEST(Friction, RefusesTheCellAverageQuadrature) {
  const DenHartog d;
  const TimeBasis fourier = TimeBasis::fourier_harmonics(8);
  const solvers::WeightedResidual w(d.system(), {0, d.p0, 15.0}, {{0, d.jenkins(1e3 * d.k)}}, fourier, fourier,
                                    {.contact_quadrature = solvers::ContactQuadrature::CellAverage});
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)w.solve(); },
                                                         {"contact_quadrature = CellAverage", "Jenkins element",
                                                          "use contact_quadrature = Midpoint"});
}

// Exact Coulomb friction tends to Den Hartog's steady state at first order in 1/M: the friction
// force switches at a collocation instant, within one cell of the reversal. Largest error over six
// frequency ratios of continuous motion, Fourier with M = 2H + 1 (measured 2.5e-2, 1.0e-2, 7.3e-3,
// 3.9e-3 for M = 33 … 257: a fitted order of 0.9); the friction force is ±μN at every instant.
TEST(Friction, ExactCoulombTendsToDenHartogAtFirstOrder) {
  const DenHartog d;
  std::vector<double> sizes, worst;
  for (int h : {16, 32, 64, 128}) {
    const TimeBasis basis = TimeBasis::fourier_harmonics(h);
    double largest = 0.0;
    for (double r : {0.6, 0.75, 0.9, 1.25, 1.5, 2.0}) {
      const solvers::WeightedResidual w(d.system(), {0, d.p0, 10.0 * r}, {{0, d.coulomb()}}, basis, basis);
      ASSERT_TRUE(w.rigid());
      const auto s = w.solve();
      ASSERT_TRUE(s.converged()) << "H = " << h << " r = " << r << ": " << s.brief();
      // Continuous motion: at most one instant per reversal can hold (a reversal between τ_k and
      // τ_{k+1} may leave Δ_k = 0); the others slip at exactly μN.
      int stuck = 0;
      for (double f : s.contact_force_samples.row(0)) stuck += std::abs(f) < d.f0 * (1.0 - 1e-12) ? 1 : 0;
      EXPECT_LE(stuck, 2) << "H = " << h << " r = " << r;
      EXPECT_NEAR(s.max_contact_force, d.f0, 1e-12 * d.f0);
      EXPECT_LT(s.complementarity, 1e-9 * w.residual_scale());
      largest = std::max(largest, std::abs(peak(basis, s.coefficients) / d.amplitude(r) - 1.0));
    }
    sizes.push_back(basis.dimension());
    worst.push_back(largest);
  }
  const double order = -std::log(worst.back() / worst.front()) / std::log(sizes.back() / sizes.front());
  EXPECT_GT(order, 0.7);
  EXPECT_LT(order, 1.4);
  EXPECT_LT(worst.back(), 5e-3);
}

// Full stick: with a load below the slip force, friction carries the whole load and the mass
// stays put: u = 0 and λ_k = P cos 2πτ_k at the instants (the pinned position u(τ_1) = 0 is the
// Jenkins convention's k_t → ∞ limit). For Fourier the instants' quadrature is exact (with even
// M the instants are k/M: the top function vanishes at the midpoints, and so does the B-splines'
// sum against (−1)^k). Wavelet pairs project the load with the Q-point rule, the impulses with
// the M-point one: λ agrees to 1e-3 P there.
TEST(Friction, ExactCoulombInFullStickCarriesTheWholeLoad) {
  DenHartog d;
  d.p0 = 0.1;  // < F0 = 0.2 N
  for (const std::string pair : {"fourier-odd", "fourier", "db6", "bspline"}) {
    const TimeBasis basis = pair == "fourier-odd" ? TimeBasis::fourier_harmonics(16) : TimeBasis::from_name(pair, 32);
    const solvers::WeightedResidual w(d.system(), {0, d.p0, 6.0}, {{0, d.coulomb()}}, basis, basis);
    const auto s = w.solve();
    ASSERT_TRUE(s.converged()) << pair << ": " << s.brief();
    EXPECT_LT(s.coefficients.cwiseAbs().maxCoeff(), 1e-12 * d.p0 / d.k) << pair;
    const Eigen::VectorXd tau = w.collocation_times();
    const double tolerance = pair.starts_with("fourier") ? 1e-12 : 1e-3;
    for (Eigen::Index k = 0; k < tau.size(); ++k) {
      EXPECT_NEAR(s.contact_force_samples(0, k), d.p0 * std::cos(2.0 * kPi * tau(k)), tolerance * d.p0) << pair << " k = " << k;
    }
    EXPECT_LT(s.max_contact_force, d.f0) << pair << ": every instant sticks";
  }
}

// The friction rows' generalized Jacobian (at load 1 and 0.5), frequency and load derivatives
// equal central differences away from a switch, in stick–slip (ζ = 2 %, μN/P = 0.5, r = 0.4: the Den Hartog
// oscillator stops at its reversals), for Fourier and DB6.
TEST(Friction, ExactCoulombDerivativesMatchCentralDifferences) {
  DenHartog d;
  d.f0 = 0.5;
  solvers::MechanicalSystem sys = d.system();
  sys.damping.insert(0, 0) = 2.0 * 0.02 * std::sqrt(d.k * d.m);
  for (const std::string pair : {"fourier", "db6"}) {
    const TimeBasis basis = TimeBasis::from_name(pair, 64);
    const solvers::WeightedResidual w(sys, {0, d.p0, 4.0}, {{0, d.coulomb()}}, basis, basis);
    const auto s = w.solve();
    ASSERT_TRUE(s.converged()) << pair << ": " << s.brief();
    const Eigen::VectorXd lambda = wbm::spectral::stacked(s.contact_force_samples);
    int stuck = 0;
    for (Eigen::Index k = 0; k < lambda.size(); ++k) stuck += std::abs(lambda(k)) < d.f0 * (1.0 - 1e-9) ? 1 : 0;
    ASSERT_GT(stuck, 0) << pair;
    ASSERT_LT(stuck, lambda.size()) << pair;
    // A point near the solution, with every row strictly on its branch: the slips off their bound.
    Eigen::VectorXd x = lambda;
    for (Eigen::Index k = 0; k < x.size(); ++k) x(k) *= std::abs(x(k)) < d.f0 * (1.0 - 1e-9) ? 1.0 : 1.001;
    const Eigen::MatrixXd j = w.signorini_jacobian(x).dense();
    const double h = 1e-7 * d.f0;
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      Eigen::VectorXd xp = x, xm = x;
      xp(i) += h;
      xm(i) -= h;
      const Eigen::VectorXd fd = (w.signorini_residual(xp) - w.signorini_residual(xm)) / (2.0 * h);
      EXPECT_LT((fd - j.col(i)).cwiseAbs().maxCoeff(), 1e-6 * j.cwiseAbs().maxCoeff()) << pair << " column " << i;
    }
    // At another load s the branches are those at s (the load stepping of exact friction uses it).
    const Eigen::MatrixXd j_half = w.signorini_jacobian(x, 0.5).dense();
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      Eigen::VectorXd xp = x, xm = x;
      xp(i) += h;
      xm(i) -= h;
      const Eigen::VectorXd fd = (w.signorini_residual(xp, 0.5) - w.signorini_residual(xm, 0.5)) / (2.0 * h);
      EXPECT_LT((fd - j_half.col(i)).cwiseAbs().maxCoeff(), 1e-6 * j_half.cwiseAbs().maxCoeff()) << pair << " s = 0.5, column " << i;
    }
    const double df = 1e-6 * w.frequency_hz();
    const Eigen::VectorXd by_f = (w.at_frequency(w.frequency_hz() + df).signorini_residual(x) -
                                  w.at_frequency(w.frequency_hz() - df).signorini_residual(x)) / (2.0 * df);
    const Eigen::VectorXd exact_f = w.signorini_frequency_derivative(x);
    EXPECT_LT((by_f - exact_f).cwiseAbs().maxCoeff(), 1e-5 * exact_f.cwiseAbs().maxCoeff()) << pair;
    const Eigen::VectorXd by_load = (w.signorini_residual(x, 1.0 + 1e-6) - w.signorini_residual(x, 1.0 - 1e-6)) / 2e-6;
    const Eigen::VectorXd exact_load = w.signorini_load_derivative(x);
    EXPECT_LT((by_load - exact_load).cwiseAbs().maxCoeff(), 1e-6 * exact_load.cwiseAbs().maxCoeff()) << pair;
  }
}

// Exact contacts are not mixed with penalty or Jenkins laws in one problem, and the integrators
// that need f(u) refuse Coulomb friction by name, pointing to Moreau–Jean (which takes it:
// test_moreau_jean_friction.cpp).
TEST(Friction, ExactCoulombIsRefusedWhereItIsNotComputed) {
  const DenHartog d;
  const TimeBasis fourier = TimeBasis::fourier_harmonics(8);
  solvers::MechanicalSystem two;
  two.mass = Eigen::MatrixXd::Identity(2, 2).sparseView();
  two.stiffness = (d.k * Eigen::MatrixXd::Identity(2, 2)).sparseView();
  two.damping.resize(2, 2);
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] {
        (void)solvers::WeightedResidual(two, {0, d.p0, 15.0}, {{0, d.coulomb()}, {1, d.jenkins(1e3 * d.k)}}, fourier, fourier);
      },
      {"1 of the 2 contacts are exact", "Coulomb ones a stiff JenkinsLaw"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::integrate_to_periodic(d.system(), {0, d.p0, 15.0}, {{0, d.coulomb()}}); },
      {"Coulomb friction (exact)", "integrate_moreau_jean_to_periodic for exact Coulomb friction"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::floquet_multipliers(d.system(), {{0, d.coulomb()}}, Eigen::MatrixXd::Zero(1, 64), 15.0); },
      {"Coulomb friction (exact)", "stability is not computed for exact friction", "stiff Jenkins element"});
  solvers::ResponseCurveOptions o;
  o.parameter_min = 5.0;
  o.parameter_max = 20.0;
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] {
        (void)solvers::trace_response(solvers::WeightedResidual(d.system(), {0, d.p0, 5.0}, {{0, d.coulomb()}}, fourier,
                                                                fourier),
                                      o);
      },
      {"stability = true with exact Coulomb friction", "stiff Jenkins element"});
}

// Exact friction and rigid stops in one problem: on a 2-DOF chain with a rigid stop on DOF 0
// (1 mm) and a Coulomb contact on DOF 1, loaded at 8 Hz, a stop that is never reached leaves the
// friction solution unchanged, and friction of zero slip force leaves the stop solution
// unchanged (each against the problem without the other contact, to 1e-9 of the response); with
// a stop that is reached, both multipliers are active in one solve.
TEST(Friction, ExactCoulombAndRigidStopsMixInOneProblem) {
  const double k = std::pow(2.0 * kPi * 10.0, 2);
  solvers::MechanicalSystem s;
  s.mass = Eigen::MatrixXd::Identity(2, 2).sparseView();
  s.stiffness = (Eigen::MatrixXd(2, 2) << 2.0 * k, -k, -k, k).finished().sparseView();
  s.damping = (2.0 * 0.02 * std::sqrt(k) * Eigen::MatrixXd::Identity(2, 2)).sparseView();
  const TimeBasis basis = TimeBasis::fourier_harmonics(32);
  const solvers::HarmonicForcing load{1, 1.0, 8.0};
  const auto friction = std::make_shared<contact::CoulombFriction>(contact::CoulombParameters{0.3, 1.0});
  const auto none = std::make_shared<contact::CoulombFriction>(contact::CoulombParameters{0.0, 1.0});
  const auto far = std::make_shared<contact::RigidStop>(1.0), near = std::make_shared<contact::RigidStop>(1e-3);
  const auto compare = [&](const std::vector<solvers::ContactPoint>& both, const std::vector<solvers::ContactPoint>& one) {
    const auto a = solvers::WeightedResidual(s, load, both, basis, basis).solve();
    const auto b = solvers::WeightedResidual(s, load, one, basis, basis).solve();
    ASSERT_TRUE(a.converged()) << a.brief();
    ASSERT_TRUE(b.converged()) << b.brief();
    EXPECT_LT((a.coefficients - b.coefficients).cwiseAbs().maxCoeff(), 1e-9 * b.coefficients.cwiseAbs().maxCoeff());
  };
  compare({{0, far}, {1, friction}}, {{1, friction}});
  compare({{0, near}, {1, none}}, {{0, near}});
  // Both active: the stop pushes and the friction slips at μN. The active-set Newton from zero
  // impulses cycles here (measured); load stepping reaches the solution.
  const auto touching = std::make_shared<contact::RigidStop>(2e-4);
  const auto mixed = solvers::WeightedResidual(s, load, {{0, touching}, {1, friction}}, basis, basis).solve();
  ASSERT_TRUE(mixed.converged()) << mixed.brief();
  EXPECT_EQ(mixed.path, solvers::SolutionPath::LoadStepping);
  EXPECT_GT(mixed.contact_force_samples.row(0).maxCoeff(), 0.0) << "the stop is reached";
  EXPECT_NEAR(mixed.contact_force_samples.row(1).cwiseAbs().maxCoeff(), 0.3, 1e-12) << "friction slips at mu N";
  EXPECT_LT(mixed.complementarity, 1e-9 * 2e-4);
}
