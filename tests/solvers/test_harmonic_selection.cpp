// Harmonic selection (WeightedResidualOptions::harmonics): the Galerkin projection of harmonic
// balance on a subset of harmonics, checked against truths the selection code does not produce:
// the half-wave symmetry of a symmetric system, the full-basis residual evaluated by the path
// without a selection, and central finite differences.
#include <wbm/solvers/weighted_residual.hpp>

#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <wbm/contact/penalty.hpp>
#include <wbm/contact/signorini.hpp>
#include <wbm/spectral/fourier_basis.hpp>
#include <wbm/spectral/layout.hpp>

#include "testing.hpp"

using namespace wbm;
using solvers::ContactPoint;
using solvers::TimeBasis;
using solvers::WeightedResidual;
using solvers::WeightedResidualOptions;

namespace {

constexpr int kHarmonics = 15;  // M = 31
constexpr double kGap = 1e-3;   // m

// Two unit masses in a chain (ground –k– m0 –k– m1), k = 4e4 N/m, C = 2e-4 K (first mode
// 19.7 Hz, ζ₁ ≈ 1.2 %), forced on m0 at 20 Hz with 50 N: the linear motion of m1 is several gaps.
solvers::MechanicalSystem two_mass_chain() {
  const double k = 4e4;
  Eigen::MatrixXd kk(2, 2), mm = Eigen::MatrixXd::Identity(2, 2);
  kk << 2 * k, -k, -k, k;
  return {mm.sparseView(), (2e-4 * kk).sparseView(), kk.sparseView()};
}

solvers::HarmonicForcing forcing() { return {0, 50.0, 20.0}; }

std::shared_ptr<const contact::ContactLaw> penalty() {
  return std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{4e5, kGap});
}

// Stops at +g0 and (symmetric = true) at −g0 on m1: the system is odd in u.
std::vector<ContactPoint> stops(bool symmetric) {
  std::vector<ContactPoint> c = {{1, penalty()}};
  if (symmetric) c.push_back({1, penalty(), -1, {{1, -1.0}}});
  return c;
}

std::vector<int> odd() {
  std::vector<int> h;
  for (int i = 1; i <= kHarmonics; i += 2) h.push_back(i);
  return h;
}

WeightedResidual problem(bool symmetric, const std::vector<int>& harmonics,
                         solvers::ContactQuadrature rule = solvers::ContactQuadrature::Midpoint, int samples = 256) {
  const TimeBasis b = TimeBasis::fourier_harmonics(kHarmonics);
  return {two_mass_chain(), forcing(), stops(symmetric), b, b,
          WeightedResidualOptions{.time_samples = samples, .contact_quadrature = rule, .harmonics = harmonics}};
}

// ‖coefficients of harmonics with (h odd) == odd_part‖_F over every DOF.
double harmonic_part(const Eigen::MatrixXd& a, bool odd_part) {
  const spectral::FourierBasis basis(static_cast<int>(a.cols()));
  double s = 0.0;
  for (int k = 0; k < a.cols(); ++k) {
    if ((basis.harmonic(k) % 2 == 1) == odd_part) s += a.col(k).squaredNorm();
  }
  return std::sqrt(s);
}

}  // namespace

// A system odd in u (two stops at ±g0, forcing in harmonic 1) has the half-wave symmetry
// u(τ + ½) = −u(τ) (with Q even, the samples map onto each other): the full harmonic balance's
// solution has no even harmonic, so the odd-harmonic Galerkin projection is the same solution and
// drops nothing.
TEST(HarmonicSelection, OddHarmonicsOfASymmetricSystemAreTheFullSolution) {
  const auto full = problem(true, {}).solve();
  const auto sel = problem(true, odd()).solve();
  ASSERT_TRUE(full.converged()) << full.report.message;
  ASSERT_TRUE(sel.converged()) << sel.report.message;
  EXPECT_GT(full.max_contact_force, 100.0);  // well into both stops
  const double size = full.coefficients.norm();
  EXPECT_LE(harmonic_part(full.coefficients, false), 1e-9 * size);
  EXPECT_GT(harmonic_part(full.coefficients, true), 0.999 * size);
  EXPECT_EQ(harmonic_part(sel.coefficients, false), 0.0);  // dropped unknowns are zero exactly
  EXPECT_LE((sel.coefficients - full.coefficients).norm(), 1e-8 * size);
  EXPECT_LE(sel.dropped_harmonics_residual, 1e-9);
  EXPECT_TRUE(std::isnan(full.dropped_harmonics_residual));
  EXPECT_NE(problem(true, odd()).describe().find("harmonics 1, 3, 5"), std::string::npos);
}

// A single stop breaks the symmetry: the contact force has a mean and even harmonics. The odd
// projection is then a different, wrong answer; what it leaves out is exactly the full-basis
// residual (evaluated by the path without a selection) on the dropped harmonics, while on the
// kept ones the full residual vanishes (Galerkin).
TEST(HarmonicSelection, DroppedResidualIsTheFullResidualOnTheDroppedHarmonics) {
  const auto full_problem = problem(false, {});
  const auto full = full_problem.solve();
  const auto sel = problem(false, odd()).solve();
  ASSERT_TRUE(full.converged()) << full.report.message;
  ASSERT_TRUE(sel.converged()) << sel.report.message;
  const double size = full.coefficients.norm();
  EXPECT_GT(harmonic_part(full.coefficients, false), 1e-2 * size);  // the one-sided stop makes a mean
  EXPECT_EQ(harmonic_part(sel.coefficients, false), 0.0);
  EXPECT_GT((sel.coefficients - full.coefficients).norm(), 1e-2 * size);

  const Eigen::VectorXd r = full_problem.residual(spectral::stacked(sel.coefficients));
  const Eigen::MatrixXd rm = spectral::as_coefficients(r, 2);
  const double bnorm = full_problem.residual(Eigen::VectorXd::Zero(r.size())).norm();  // ‖b‖ (no contact at 0)
  EXPECT_LE(harmonic_part(rm, true), 1e-7 * bnorm);
  EXPECT_NEAR(sel.dropped_harmonics_residual, harmonic_part(rm, false) / bnorm, 1e-9 * sel.dropped_harmonics_residual);
  EXPECT_GT(sel.dropped_harmonics_residual, 1e-2);
}

// Jacobians of the condensed residual with a selection: the dense form, the low-rank form (the
// shift-kernel path of Fourier:Fourier for the midpoint rule) against central differences, with
// one stop and with the symmetric pair (the kernel's cross terms between contacts).
TEST(HarmonicSelection, CondensedJacobiansMatchFiniteDifferences) {
  struct Case {
    bool symmetric;
    std::vector<int> harmonics;
    solvers::ContactQuadrature rule;
  };
  for (const auto& [symmetric, harmonics, rule] :
       {Case{false, {0, 1, 3}, solvers::ContactQuadrature::Midpoint}, Case{false, {0, 1, 3}, solvers::ContactQuadrature::CellAverage},
        Case{true, odd(), solvers::ContactQuadrature::Midpoint}}) {
    SCOPED_TRACE(std::string(solvers::to_string(rule)) + (symmetric ? ", two stops" : ", one stop"));
    // Q = 1.5 M samples, and the linear motion scaled down until few samples are in contact
    // (the low-rank form needs rank <= 3/4 of the contact unknowns).
    const auto wr = problem(symmetric, harmonics, rule, 46);
    const Eigen::VectorXd x_lin = wr.contact_unknowns(wr.linear_response());
    Eigen::VectorXd x;
    double factor = 1.0;
    do {
      factor *= 0.9;
      ASSERT_GT(factor, 1e-3);
      x = x_lin * factor;
    } while (wr.contact_jacobian_low_rank(x).dense_form());
    const auto low = wr.contact_jacobian_low_rank(x);
    ASSERT_GT(low.rank(), 0);
    // The capacitance Newton's Woodbury solve uses (gathered from the shift kernel for the
    // midpoint rule) is I_r + V U with the products that dense() uses.
    const Eigen::MatrixXd eye = Eigen::MatrixXd::Identity(low.rank(), low.rank());
    EXPECT_LE((low.capacitance - eye - low.times_v(low.u_times(eye))).norm(), 1e-10 * low.capacitance.norm());
    EXPECT_EQ(static_cast<bool>(low.times_u), rule == solvers::ContactQuadrature::Midpoint);
    struct Dense {
      const WeightedResidual* wr;
      Eigen::VectorXd residual(const Eigen::VectorXd& y) const { return wr->contact_residual(y); }
      Eigen::MatrixXd jacobian(const Eigen::VectorXd& y) const { return wr->contact_jacobian(y); }
    };
    struct LowRank : Dense {
      Eigen::MatrixXd jacobian(const Eigen::VectorXd& y) const { return wr->contact_jacobian_low_rank(y).dense(); }
    };
    const double tol = rule == solvers::ContactQuadrature::CellAverage ? 1e-4 : 1e-7;
    wbm::testing::expect_jacobian_matches_fd(Dense{&wr}, x, tol, 1e-6, 1e-3);
    wbm::testing::expect_jacobian_matches_fd(LowRank{{&wr}}, x, tol, 1e-6, 1e-3);
  }
}

TEST(HarmonicSelection, RefusesWhatItCannotProject) {
  using wbm::testing::expect_throw_with;
  const TimeBasis f = TimeBasis::fourier_harmonics(kHarmonics);
  auto build = [&](const std::vector<int>& h, TimeBasis trial, TimeBasis weighting, solvers::HarmonicForcing fo,
                   std::vector<ContactPoint> c) {
    return WeightedResidual(two_mass_chain(), fo, std::move(c), std::move(trial), std::move(weighting),
                            WeightedResidualOptions{.harmonics = h});
  };
  expect_throw_with<std::invalid_argument>(
      [&] { (void)build({1}, TimeBasis::from_name("db6", 32), TimeBasis::from_name("db6", 32), forcing(), stops(false)); },
      {"harmonics", "DB6:DB6", "Fourier"});
  expect_throw_with<std::invalid_argument>([&] { (void)build({1, 16}, f, f, forcing(), stops(false)); },
                                           {"harmonic 16", "[0, 15]"});
  expect_throw_with<std::invalid_argument>([&] { (void)build({3, 1, 3}, f, f, forcing(), stops(false)); },
                                           {"harmonic 3", "twice"});
  solvers::HarmonicForcing two = forcing();
  two.more.push_back({1, 5.0, 0.0, 2});
  expect_throw_with<std::invalid_argument>([&] { (void)build(odd(), f, f, two, stops(false)); },
                                           {"DOF 1", "harmonic 2", "not kept"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)build(odd(), f, f, forcing(), {{1, std::make_shared<contact::RigidStop>(kGap)}}); },
      {"rigid stops", "penalty"});
}
