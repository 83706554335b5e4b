#include <wbm/spectral/aft.hpp>

#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include <wbm/spectral/fourier_basis.hpp>

#include "testing.hpp"

using wbm::spectral::Aft;
using wbm::spectral::FourierBasis;

namespace {
Eigen::MatrixXd random_matrix(int rows, int cols, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd a(rows, cols);
  for (int j = 0; j < cols; ++j)
    for (int i = 0; i < rows; ++i) a(i, j) = u(gen);
  return a;
}
Eigen::VectorXd sample_times(int q, double offset = 0.0) {
  return (Eigen::VectorXd::LinSpaced(q, 0.0, q - 1.0).array() + offset) / q;
}
struct Grid {
  int m, q;
  double offset;
};
// Q = M (Nyquist bin), Q < 2M (aliased products), Q not a power of two, and three offsets.
// M = 2H + 1 with Q = M and Q even.
const Grid kGrids[] = {{8, 8, 0.0},    {8, 32, 0.0},  {64, 256, 0.0}, {16, 48, 0.0}, {8, 8, 0.5},
                       {8, 32, 0.5},   {64, 256, 0.5}, {16, 48, 0.5}, {16, 24, 0.3}, {2, 2, 0.25},
                       {7, 7, 0.0},    {7, 7, 0.5},    {9, 32, 0.5},  {25, 64, 0.0}};
}  // namespace

// Slow oracle: the FFT path against the direct O(QM) sum Σ_k A(i,k) q_k(τ_q).
TEST(Aft, ToTimeMatchesDirectSum) {
  for (const auto& [m, q, offset] : kGrids) {
    const Aft aft(m, q, offset);
    const Eigen::MatrixXd a = random_matrix(3, m, 1);
    const Eigen::MatrixXd direct = a * FourierBasis(m).values(sample_times(q, offset)).transpose();
    EXPECT_LT((aft.to_time(a) - direct).cwiseAbs().maxCoeff(), 1e-12) << "M=" << m << " Q=" << q << " d=" << offset;
  }
}

// Slow oracle: project(S)(i,j) = (1/Q) Σ_q q_j(τ_q) S(i,q).
TEST(Aft, ProjectMatchesDirectSum) {
  for (const auto& [m, q, offset] : kGrids) {
    const Aft aft(m, q, offset);
    const Eigen::MatrixXd s = random_matrix(2, q, 2);
    const Eigen::MatrixXd direct = s * FourierBasis(m).values(sample_times(q, offset)) / q;
    EXPECT_LT((aft.project(s) - direct).cwiseAbs().maxCoeff(), 1e-13) << "M=" << m << " Q=" << q << " d=" << offset;
  }
}

// Slow oracle: jacobian(κ)(j,k) = (1/Q) Σ_q q_j(τ_q) κ_q q_k(τ_q), including harmonics
// m_j + m_k ≥ Q/2 that alias (Q < 2M) and the Q = M Nyquist bin.
TEST(Aft, JacobianMatchesDirectSum) {
  for (const auto& [m, q, offset] : kGrids) {
    const Aft aft(m, q, offset);
    const Eigen::VectorXd kappa = random_matrix(q, 1, 5).col(0).array() + 1.0;
    const Eigen::MatrixXd v = FourierBasis(m).values(sample_times(q, offset));
    const Eigen::MatrixXd direct = v.transpose() * kappa.asDiagonal() * v / q;
    EXPECT_LT((aft.jacobian(kappa) - direct).cwiseAbs().maxCoeff(), 1e-13) << "M=" << m << " Q=" << q << " d=" << offset;
  }
}

// Finite differences: the Jacobian of a ↦ project(f(to_time(a))) for f(u) = u³ is
// jacobian(3u²) at the same grid.
TEST(Aft, JacobianIsTheDerivativeOfTheSampledForce) {
  const Aft aft(16, 40, 0.5);
  const Eigen::MatrixXd a = random_matrix(1, 16, 6);
  const auto force = [&](const Eigen::MatrixXd& x) { return aft.project(aft.to_time(x).array().cube().matrix()); };
  const Eigen::VectorXd u = aft.to_time(a).row(0).transpose();
  const Eigen::MatrixXd jac = aft.jacobian(3.0 * u.array().square().matrix());
  const double h = 1e-6;
  for (int k = 0; k < 16; ++k) {
    Eigen::MatrixXd ap = a, am = a;
    ap(0, k) += h;
    am(0, k) -= h;
    const Eigen::VectorXd fd = ((force(ap) - force(am)) / (2 * h)).row(0).transpose();
    EXPECT_LT((fd - jac.col(k)).cwiseAbs().maxCoeff(), 1e-8) << "column " << k;
  }
}

// Identity: to_frequency is the left inverse of to_time, including Q = M (Nyquist bin).
TEST(Aft, RoundTripRecoversCoefficients) {
  for (const auto& [m, q, offset] : {Grid{2, 2, 0.0}, {8, 8, 0.0}, {64, 128, 0.0}, {256, 1024, 0.0}, {64, 128, 0.5},
                                     {8, 8, 0.3}, {7, 7, 0.5}, {9, 20, 0.0}}) {
    const Aft aft(m, q, offset);
    const Eigen::MatrixXd a = random_matrix(5, m, 3);
    EXPECT_LT((aft.to_frequency(aft.to_time(a)) - a).cwiseAbs().maxCoeff(), 1e-13) << "M=" << m;
  }
}

// Parseval for the unnormalized real basis: ∫ u² = a₀² + ½ Σ (a_m² + b_m²) + ½ a_{M/2}²,
// and the Q-point mean of u² is exact for Q > M.
TEST(Aft, ParsevalHolds) {
  const int m = 32, q = 128;
  const Aft aft(m, q);
  const Eigen::MatrixXd a = random_matrix(1, m, 4);
  const double mean_square = aft.to_time(a).squaredNorm() / q;
  const double parseval = a(0, 0) * a(0, 0) + 0.5 * a.rightCols(m - 1).squaredNorm();
  EXPECT_NEAR(mean_square, parseval, 1e-13 * parseval);
}

TEST(Aft, RejectsTooFewSamples) {
  wbm::testing::expect_throw_with<std::invalid_argument>([] { Aft aft(64, 32); },
                                                         {"Q = 32", "Q must be >= M"});
  wbm::testing::expect_throw_with<std::invalid_argument>([] { Aft aft(6, 32); },
                                                         {"M = 6", "power of two", "odd >= 3"});
  wbm::testing::expect_throw_with<std::invalid_argument>([] { Aft aft(8, 16, 1.0); },
                                                         {"offset", "[0, 1)"});
}

// With Q = M midpoint samples, cos πMτ is zero at every sample: no left inverse.
TEST(Aft, ToFrequencyRefusesAnUndeterminedLastFunction) {
  const Aft aft(8, 8, 0.5);
  wbm::testing::expect_throw_with<std::domain_error>(
      [&] { (void)aft.to_frequency(Eigen::MatrixXd::Ones(1, 8)); }, {"Q = M = 8", "use Q > M"});
}
