// Friction in the weighted residual (contact::JenkinsLaw through ContactLaw::evaluate_period).
// Truths not produced by this code: Den Hartog's (1931) exact steady state of an undamped 1-DOF
// oscillator with Coulomb friction and a harmonic force, for continuous motion, which the Jenkins
// element tends to as k_t → ∞; central differences of the residual.
#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <wbm/contact/friction.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/time_basis.hpp>
#include <wbm/solvers/weighted_residual.hpp>

#include "testing.hpp"

namespace solvers = wbm::solvers;
namespace contact = wbm::contact;
using solvers::TimeBasis;

namespace {

constexpr double kPi = std::numbers::pi;

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
    const Eigen::MatrixXd j = w.jacobian(a);
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
