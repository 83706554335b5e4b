#include <wbm/spectral/fourier_basis.hpp>

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <gtest/gtest.h>

#include "testing.hpp"

using wbm::spectral::FourierBasis;

// Ordering of [JL14 Sec. 3.1] as fixed in fourier_basis.hpp: 1, cos 2πτ, sin 2πτ, ..., cos πMτ.
TEST(FourierBasis, FunctionsFollowTheDocumentedOrdering) {
  const FourierBasis basis(8);
  const double tau = 0.1234;
  const double pi = std::numbers::pi;
  EXPECT_DOUBLE_EQ(basis.value(0, tau), 1.0);
  EXPECT_NEAR(basis.value(1, tau), std::cos(2 * pi * tau), 1e-15);
  EXPECT_NEAR(basis.value(2, tau), std::sin(2 * pi * tau), 1e-15);
  EXPECT_NEAR(basis.value(5, tau), std::cos(6 * pi * tau), 1e-15);
  EXPECT_NEAR(basis.value(6, tau), std::sin(6 * pi * tau), 1e-15);
  EXPECT_NEAR(basis.value(7, tau), std::cos(8 * pi * tau), 1e-15);
  EXPECT_EQ(basis.harmonic(7), 4);
}

// M = 2H + 1: harmonics 0 … H, each cosine with its sine, no top function.
TEST(FourierBasis, HarmonicFormHasEveryHarmonicWithItsPair) {
  const FourierBasis basis = FourierBasis::with_harmonics(3);
  const double tau = 0.4321;
  const double pi = std::numbers::pi;
  ASSERT_EQ(basis.dimension(), 7);
  EXPECT_FALSE(basis.has_top_function());
  EXPECT_EQ(basis.highest_harmonic(), 3);
  EXPECT_NEAR(basis.value(5, tau), std::cos(6 * pi * tau), 1e-15);
  EXPECT_NEAR(basis.value(6, tau), std::sin(6 * pi * tau), 1e-15);
  EXPECT_TRUE(basis.is_sine(6));
  EXPECT_FALSE(FourierBasis(8).is_sine(7));  // the top function of M = 2^J is a cosine
}

// values() (one phase per harmonic for its cosine and sine) against the closed forms
// (2πh)^d cos(2πhτ + dπ/2) and (2πh)^d sin(2πhτ + dπ/2) written here, and entry for entry the
// same bits as value(): the rigid stops' collocation matrices moved to values() must not move
// any result (both M forms, derivatives 0 to 2).
TEST(FourierBasis, ValuesMatchTheClosedFormsAndValueBitForBit) {
  const double pi = std::numbers::pi;
  for (const int dim : {2, 16, 17}) {
    const FourierBasis basis(dim);
    const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(37, -0.31, 1.73);
    for (int d = 0; d <= 2; ++d) {
      const Eigen::MatrixXd v = basis.values(tau, d);
      ASSERT_EQ(v.rows(), tau.size());
      ASSERT_EQ(v.cols(), dim);
      for (Eigen::Index p = 0; p < tau.size(); ++p) {
        EXPECT_EQ(v(p, 0), d == 0 ? 1.0 : 0.0);
        for (int k = 1; k < dim; ++k) {
          const int h = (dim % 2 == 0 && k == dim - 1) ? dim / 2 : (k + 1) / 2;
          const bool sine = k % 2 == 0 && !(dim % 2 == 0 && k == dim - 1);
          const double phase = 2 * pi * h * tau(p) + d * pi / 2;
          const double closed = std::pow(2 * pi * h, d) * (sine ? std::sin(phase) : std::cos(phase));
          EXPECT_NEAR(v(p, k), closed, 1e-13 * std::pow(2 * pi * h, d)) << "M=" << dim << " k=" << k << " d=" << d;
          EXPECT_EQ(v(p, k), basis.value(k, tau(p), d)) << "M=" << dim << " k=" << k << " d=" << d;
        }
      }
    }
  }
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [] { (void)FourierBasis(8).values(Eigen::VectorXd::Zero(2), -1); }, {"derivative order -1"});
}

// grid_values against values() at the same τ_p = (p + s/2)/P (agreement to the rounding of
// values()' own argument, 4·eps·2πh), both grids and both M forms, with P ≠ M as well; the top
// function vanishes exactly at the midpoints of P = M, and cos 2πhτ at τ = 1/4 (h = 1, P = 4)
// is exactly 0 (a multiple of π/2 read exactly).
TEST(FourierBasis, GridValuesMatchValuesOnTheSameGrid) {
  for (const int dim : {8, 9, 256}) {
    const FourierBasis basis(dim);
    for (const int points : {dim, 3, 64}) {
      for (const bool midpoints : {false, true}) {
        Eigen::VectorXd tau(points);
        for (int p = 0; p < points; ++p) tau(p) = (p + (midpoints ? 0.5 : 0.0)) / points;
        const Eigen::MatrixXd grid = basis.grid_values(points, midpoints);
        const Eigen::MatrixXd direct = basis.values(tau, 0);
        for (int k = 0; k < dim; ++k) {
          const double bound = 4 * 2.2e-16 * 2 * std::numbers::pi * (basis.harmonic(k) + 1);
          EXPECT_LE((grid.col(k) - direct.col(k)).lpNorm<Eigen::Infinity>(), bound)
              << "M=" << dim << " P=" << points << " midpoints=" << midpoints << " k=" << k;
        }
      }
    }
  }
  EXPECT_EQ(FourierBasis(8).grid_values(8, true).col(7).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(FourierBasis(8).grid_values(4, false)(1, 1), 0.0);
  wbm::testing::expect_throw_with<std::invalid_argument>([] { (void)FourierBasis(8).grid_values(0, false); },
                                                         {"points = 0", "[1, 2^28]"});
}

// The top function's damping row is zero for M = 2^J (its derivative leaves the span), while
// every harmonic of M = 2H + 1 has A₁ = ±πm on its (cos, sin) pair.
TEST(FourierBasis, OnlyTheTopFunctionEscapesTheFirstDerivativeOperator) {
  const Eigen::MatrixXd top(FourierBasis(8).galerkin_operator(1));
  EXPECT_EQ(top.row(7).cwiseAbs().sum(), 0.0);
  const Eigen::MatrixXd paired(FourierBasis::with_harmonics(4).galerkin_operator(1));
  for (int k = 1; k < 9; ++k) EXPECT_GT(paired.row(k).cwiseAbs().sum(), 1.0) << "row " << k;
}

// Derivatives against central differences of the values (step 1e-5, error O(h²·w³) ≈ 1e-6).
TEST(FourierBasis, DerivativesMatchCentralDifferences) {
  for (const int dim : {16, 17}) {
    const FourierBasis basis(dim);
    const double h = 1e-5;
    for (int k = 0; k < dim; ++k) {
      for (double tau : {0.0, 0.3, 0.77}) {
        for (int d = 1; d <= 2; ++d) {
          const double fd = (basis.value(k, tau + h, d - 1) - basis.value(k, tau - h, d - 1)) / (2 * h);
          const double scale = std::pow(2 * std::numbers::pi * basis.harmonic(k), d) + 1.0;
          EXPECT_NEAR(basis.value(k, tau, d), fd, 1e-6 * scale) << "M=" << dim << " k=" << k << " d=" << d;
        }
      }
    }
  }
}

// Slow oracle: A_d(j,k) = ∫ q_j q_k^{(d)} by a 4M-point rectangle rule, exact for these
// trigonometric polynomials (degree ≤ M < 4M).
TEST(FourierBasis, GalerkinOperatorsMatchQuadrature) {
  for (const int m : {16, 15}) {
    const int q = 4 * m;
    const FourierBasis basis(m);
    const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(q, 0.0, 1.0 - 1.0 / q);
    const Eigen::MatrixXd v0 = basis.values(tau, 0);
    for (int d = 0; d <= 2; ++d) {
      const Eigen::MatrixXd quad = v0.transpose() * basis.values(tau, d) / q;
      const Eigen::MatrixXd exact(basis.galerkin_operator(d));
      const double scale = std::pow(std::numbers::pi * m, d);
      EXPECT_LT((quad - exact).cwiseAbs().maxCoeff(), 1e-12 * scale) << "M = " << m << " d = " << d;
    }
  }
}

// Integration by parts on the circle: ∫ q_j q_k' = −∫ q_j' q_k (A₁ antisymmetric) and
// ∫ q_j q_k'' = ∫ q_j'' q_k (A₂ symmetric).
TEST(FourierBasis, DerivativeOperatorsHaveIntegrationByPartsSymmetry) {
  const FourierBasis basis(32);
  const Eigen::MatrixXd a1(basis.galerkin_operator(1));
  const Eigen::MatrixXd a2(basis.galerkin_operator(2));
  EXPECT_LT((a1 + a1.transpose()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((a2 - a2.transpose()).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_GT(a1.cwiseAbs().maxCoeff(), 1.0);  // not trivially zero
}

// The coefficient-space derivative against the analytic derivatives of the functions:
// V₁ = V₀ Dᵀ column by column, except the top function of M = 2^J, whose row of D is zero.
TEST(FourierBasis, DerivativeMatrixMapsEveryFunctionButTheTopOne) {
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(37, 0.01, 0.97);
  for (int m : {8, 9, 16}) {
    const wbm::spectral::FourierBasis basis(m);
    const Eigen::MatrixXd d(basis.derivative_matrix());
    const Eigen::MatrixXd predicted = basis.values(tau, 0) * d.transpose();
    const Eigen::MatrixXd exact = basis.values(tau, 1);
    const int checked = basis.has_top_function() ? m - 1 : m;
    EXPECT_LT((predicted.leftCols(checked) - exact.leftCols(checked)).cwiseAbs().maxCoeff(), 1e-12 * exact.cwiseAbs().maxCoeff()) << m;
    if (basis.has_top_function()) {
      EXPECT_EQ(d.row(m - 1).norm(), 0.0);
      EXPECT_GT(exact.col(m - 1).cwiseAbs().maxCoeff(), 1.0);  // −πM sin πMτ: outside the span
    }
  }
}

TEST(FourierBasis, RejectsDimensionsThatAreNeitherPowersOfTwoNorOdd) {
  for (int m : {0, 1, 6, 12, -4}) {
    wbm::testing::expect_throw_with<std::invalid_argument>([m] { FourierBasis b(m); },
                                                           {"M = " + std::to_string(m), "power of two", "odd >= 3"});
  }
  wbm::testing::expect_throw_with<std::invalid_argument>([] { (void)FourierBasis::with_harmonics(0); },
                                                         {"H = 0", "[1, 2^28]"});
}
