// Periodized bases: wrapping, normalization, operators and their convergence.
#include <cmath>
#include <numbers>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <wbm/wavelets/periodized_basis.hpp>

#include "testing.hpp"

namespace ww = wbm::wavelets;

// Σ_ℓ φ(τ − ℓ) = 1 (partition of unity), so at J = 0 every family periodizes to the constant 1
// [JL14 Sec. 3.2.1], also where the support (DB6: 5 periods) is longer than the period.
TEST(PeriodizedBasis, LevelZeroIsTheConstantOne) {
  for (const auto& family : {ww::Family::haar(), ww::Family::daubechies(6), ww::Family::daubechies(20),
                             ww::Family::orthogonal_cubic_bspline()}) {
    const ww::PeriodizedBasis basis(family, 0);
    for (double tau : {0.0, 0.125, 0.3, 0.71, 0.999}) EXPECT_NEAR(basis.value(0, tau), 1.0, 1e-12) << family.name();
  }
}

// The paper's scaling ∫₀¹ φ_{J,k} = 1 [JL14 Sec. 3.3] against the orthonormal one: the rectangle
// rule on the dyadic grid integrates a periodized Haar function exactly and the others to the
// quadrature error; and the orthonormal functions have unit L² norm by discrete inner products.
TEST(PeriodizedBasis, UnitIntegralAndOrthonormalScalings) {
  for (const auto& family : {ww::Family::haar(), ww::Family::daubechies(6), ww::Family::orthogonal_cubic_bspline()}) {
    for (int level : {0, 1, 3, 5}) {
      const ww::PeriodizedBasis unit(family, level, {.normalization = ww::Normalization::UnitIntegral});
      const Eigen::MatrixXd v = unit.sampled(4096);
      for (int k = 0; k < unit.dimension(); ++k) EXPECT_NEAR(v.col(k).mean(), 1.0, 1e-12) << family.name() << " J = " << level;
      const ww::PeriodizedBasis ortho(family, level);
      const Eigen::MatrixXd d = ortho.discrete_inner_products(0, 0, 4096);
      // Rectangle rule, Q = 4096: exact for Haar; B-spline products have jumps in the third
      // derivative at the knots k/M, so Euler–Maclaurin leaves O((M/Q)^4); DB6 is Hölder 1.09.
      const double ratio = static_cast<double>(ortho.dimension()) / 4096.0;
      const double tol = family.kind == ww::FamilyKind::Daubechies ? 1e-4 : 10.0 * std::pow(ratio, 4) + 1e-12;
      EXPECT_LE((d - Eigen::MatrixXd::Identity(d.rows(), d.cols())).cwiseAbs().maxCoeff(), tol)
          << family.name() << " J = " << level;
    }
  }
}

// Orthonormality at the extremes J = 0 … 14 and L up to 20: the wrapped Gram matrix of the
// connection coefficients is the identity (each wrap sums Γ^{0,0}[k + ℓM] over ℓ, so at J = 0
// it needs Σ_k Γ^{0,0}[k] = 1 and at large J the plain δ_k), and the level-J partition of unity
// Σ_k φ_{J,k}(τ) = 2^{J/2} holds pointwise.
TEST(PeriodizedBasis, OrthonormalFromLevelZeroToFourteen) {
  for (const auto& family : {ww::Family::haar(), ww::Family::daubechies(6), ww::Family::daubechies(20),
                             ww::Family::orthogonal_cubic_bspline()}) {
    for (int level : {0, 1, 2, 3, 6, 10, 14}) {
      const ww::PeriodizedBasis basis(family, level);
      const Eigen::SparseMatrix<double> g = basis.connection_matrix(0, 0);
      Eigen::SparseMatrix<double> id(g.rows(), g.cols());
      id.setIdentity();
      const double tol = family.kind == ww::FamilyKind::OrthogonalCubicBSpline ? 1e-12 : 1e-13;
      Eigen::SparseMatrix<double> diff = g - id;  // sparse: M = 16384 at J = 14
      diff.makeCompressed();
      EXPECT_LE(diff.coeffs().cwiseAbs().maxCoeff(), tol) << family.name() << " J = " << level;
      if (level >= 10) {
        for (double tau : {0.1, 0.5}) {
          double s = 0.0;
          for (int k = 0; k < basis.dimension(); ++k) s += basis.value(k, tau);
          EXPECT_NEAR(s, std::sqrt(double(basis.dimension())), 1e-9 * std::sqrt(double(basis.dimension())));
        }
      }
    }
  }
}

// Second-derivative Galerkin operator on the projection of sin 2πτ. By shift covariance
// (φ_{J,k}(τ) = φ_{J,0}(τ − k/M)) the projection's coefficients are a_k = A sin(2π(k + c)/M),
// an eigenvector of the symmetric circulant C = connection_matrix(0, 2) with eigenvalue
//   λ = M² Σ_k Γ^{0,2}[k] cos(2πk/M) = −(2π)² + O(M^{−(2N−2)}),
// since Σ_k k^m Γ^{0,2}[k] = 2δ_{m2} for m ≤ 2N − 1 (expand cos to order 2N). So
// ‖C a + (2π)² a‖ / ‖(2π)² a‖ = O(M^{−(2N−2)}): order 4 for DB6, 6 for DB8 and the B-spline.
TEST(PeriodizedBasis, SecondDerivativeOperatorConvergesAtOrderTwoNMinusTwo) {
  const double w2 = 4.0 * std::numbers::pi * std::numbers::pi;
  for (const auto& [family, order] : std::vector<std::pair<ww::Family, double>>{
           {ww::Family::daubechies(6), 4.0}, {ww::Family::daubechies(8), 6.0}, {ww::Family::orthogonal_cubic_bspline(), 6.0}}) {
    std::vector<double> h, err;
    for (int level = 3; level <= 6; ++level) {
      const ww::PeriodizedBasis basis(family, level);
      const int m = basis.dimension();
      Eigen::VectorXd a(m);
      for (int k = 0; k < m; ++k) a(k) = std::sin(2.0 * std::numbers::pi * (k + 0.37) / m);
      const Eigen::VectorXd r = basis.galerkin_operator(2) * a + w2 * a;
      h.push_back(1.0 / m);
      err.push_back(r.norm() / (w2 * a.norm()));
    }
    EXPECT_NEAR(wbm::testing::observed_order(h, err), order, 0.15) << family.name();
  }
}

// The paper's 256-point discrete inner products approach the exact connection-coefficient
// operators as Q grows (slow reference path); for the B-spline (C², piecewise cubic, periodic)
// the rectangle rule is already accurate at Q = 256.
TEST(PeriodizedBasis, DiscreteInnerProductsConvergeToConnectionMatrices) {
  const ww::PeriodizedBasis db6(ww::Family::daubechies(6), 3, {.grid_level = 14});
  const Eigen::MatrixXd exact = Eigen::MatrixXd(db6.connection_matrix(0, 1));
  double previous = 1e300;
  for (int q : {256, 1024, 4096, 16384}) {
    const double e = (db6.discrete_inner_products(0, 1, q) - exact).cwiseAbs().maxCoeff();
    EXPECT_LT(e, previous) << "Q = " << q;
    previous = e;
  }
  EXPECT_LT(previous, 1e-2);
  // B-spline: φ'' has kinks at the knots, so the rule converges at least at second order.
  const ww::PeriodizedBasis spline(ww::Family::orthogonal_cubic_bspline(), 4);
  for (const auto& [d1, d2] : std::vector<std::pair<int, int>>{{0, 0}, {0, 1}, {1, 1}, {0, 2}}) {
    const Eigen::MatrixXd c = Eigen::MatrixXd(spline.connection_matrix(d1, d2));
    const double scale = c.cwiseAbs().maxCoeff();
    const double coarse = (spline.discrete_inner_products(d1, d2, 512) - c).cwiseAbs().maxCoeff();
    const double fine = (spline.discrete_inner_products(d1, d2, 2048) - c).cwiseAbs().maxCoeff();
    EXPECT_TRUE(fine <= coarse / 10.0 || fine < 1e-12 * scale) << d1 << "," << d2 << ": " << coarse << " -> " << fine;
    EXPECT_LE(fine, 1e-4 * scale) << d1 << "," << d2;
  }
}

// The tabulation by support (values) against the direct periodization sum (value), one function
// and one time at a time — including non-dyadic τ, negative τ and levels where the support wraps.
TEST(PeriodizedBasis, TabulatedValuesMatchTheDirectPeriodizationSum) {
  Eigen::VectorXd tau(6);  // not a copy of .finished(): g++ -O1 (the tests' level) warns of it in Eigen's copy
  tau << 0.0, 0.1, 0.3125, 0.77, 0.999, -0.4;
  for (const auto& family : {ww::Family::haar(), ww::Family::daubechies(6), ww::Family::orthogonal_cubic_bspline()}) {
    for (int level : {0, 1, 2, 5}) {
      const ww::PeriodizedBasis basis(family, level, {.normalization = ww::Normalization::UnitIntegral});
      for (int d = 0; d <= basis.max_derivative(); ++d) {
        const Eigen::MatrixXd v = basis.values(tau, d);
        for (Eigen::Index p = 0; p < tau.size(); ++p) {
          for (int k = 0; k < basis.dimension(); ++k) {
            const double direct = basis.value(k, tau(p), d);
            EXPECT_NEAR(v(p, k), direct, 1e-12 * (1.0 + std::abs(direct))) << family.name() << " J = " << level;
          }
        }
      }
    }
  }
}

// The sparse sample matrix keeps only the functions whose support covers each sample: at most
// ⌊support length⌋ + 1 per row, so Q × M values cost O(Q · support) (issue #17); the rows keep
// the partition of unity.
TEST(PeriodizedBasis, SparseValuesStoreOnlyTheSupport) {
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(512, 0.0005, 0.9995);
  for (const auto& family : {ww::Family::haar(), ww::Family::daubechies(6), ww::Family::orthogonal_cubic_bspline()}) {
    const ww::PeriodizedBasis basis(family, 8);
    const auto& phi = basis.scaling_function();
    const auto width = static_cast<Eigen::Index>(std::floor(phi.support_end() - phi.support_begin())) + 1;
    const auto sv = basis.sparse_values(tau, 0);
    for (Eigen::Index p = 0; p < tau.size(); ++p) {
      const Eigen::Index nonzeros = sv.outerIndexPtr()[p + 1] - sv.outerIndexPtr()[p];
      EXPECT_LE(nonzeros, width) << family.name() << " sample " << p;
      EXPECT_GE(nonzeros, 1) << family.name() << " sample " << p;
    }
    // Partition of unity, Σ_j φ(x − j) = 1: every row of the orthonormal basis sums to 2^{J/2}.
    const Eigen::VectorXd row_sums = sv * Eigen::VectorXd::Ones(basis.dimension());
    EXPECT_LT((row_sums.array() - 16.0).abs().maxCoeff(), 1e-8 * 16.0) << family.name();
  }
}

TEST(PeriodizedBasis, RefusesBadLevelsAndMissingDerivatives) {
  wbm::testing::expect_throw_with<std::invalid_argument>([] { (void)ww::PeriodizedBasis(ww::Family::haar(), -1); },
                                                         {"level J = -1", "[0, 20]"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [] { (void)ww::PeriodizedBasis(ww::Family::haar(), 5, {.grid_level = 3}); },
      {"PeriodizedBasisOptions.grid_level = 3", "[J, J + 20] = [5, 25]"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [] { (void)ww::PeriodizedBasis(ww::Family::haar(), 2, {.grid_level = 23}); }, {"grid_level = 23", "[2, 22]"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [] { (void)ww::PeriodizedBasis(ww::Family::haar(), 2, {.grid_level = -2}); }, {"grid_level = -2", "must be -1"});
  EXPECT_EQ(ww::PeriodizedBasisOptions{}.grid_level_at(3), 12);   // the default: max(J, 12)
  EXPECT_EQ(ww::PeriodizedBasisOptions{}.grid_level_at(14), 14);
  const ww::PeriodizedBasis haar(ww::Family::haar(), 3);
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)haar.sampled(256, 1); }, {"Haar", "order 1"});
  EXPECT_THROW((void)haar.value(8, 0.1), std::out_of_range);
}
