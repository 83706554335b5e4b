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
Eigen::VectorXd sample_times(int q) { return Eigen::VectorXd::LinSpaced(q, 0.0, 1.0 - 1.0 / q); }
}  // namespace

// Slow oracle: the FFT path against the direct O(QM) sum Σ_k A(i,k) q_k(τ_q).
TEST(Aft, ToTimeMatchesDirectSum) {
  for (auto [m, q] : {std::pair{8, 8}, {8, 32}, {64, 256}, {16, 48}}) {
    const Aft aft(m, q);
    const Eigen::MatrixXd a = random_matrix(3, m, 1);
    const Eigen::MatrixXd direct = a * FourierBasis(m).values(sample_times(q)).transpose();
    EXPECT_LT((aft.to_time(a) - direct).cwiseAbs().maxCoeff(), 1e-12) << "M=" << m << " Q=" << q;
  }
}

// Slow oracle: project(S)(i,j) = (1/Q) Σ_q q_j(τ_q) S(i,q).
TEST(Aft, ProjectMatchesDirectSum) {
  for (auto [m, q] : {std::pair{8, 8}, {8, 32}, {64, 256}, {16, 48}}) {
    const Aft aft(m, q);
    const Eigen::MatrixXd s = random_matrix(2, q, 2);
    const Eigen::MatrixXd direct = s * FourierBasis(m).values(sample_times(q)) / q;
    EXPECT_LT((aft.project(s) - direct).cwiseAbs().maxCoeff(), 1e-13) << "M=" << m << " Q=" << q;
  }
}

// Identity: to_frequency is the left inverse of to_time, including Q = M (Nyquist bin).
TEST(Aft, RoundTripRecoversCoefficients) {
  for (auto [m, q] : {std::pair{2, 2}, {8, 8}, {64, 128}, {256, 1024}}) {
    const Aft aft(m, q);
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
                                                         {"M = 6", "power of two"});
}
