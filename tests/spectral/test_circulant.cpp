#include <wbm/spectral/circulant.hpp>

#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Core>
#include <gtest/gtest.h>

using namespace wbm;

// spectral::Circulant against its dense matrix: products, transposed products and the inverse.
TEST(Circulant, ProductsAndInverseMatchTheDenseMatrix) {
  for (int m : {1, 2, 7, 16, 33}) {
    Eigen::VectorXd c = Eigen::VectorXd::LinSpaced(m, 1.0, 2.0).array().sin();
    c(0) += 3.0;  // diagonally dominant: invertible
    const spectral::Circulant circ(c);
    const Eigen::MatrixXd dense = circ.dense();
    EXPECT_DOUBLE_EQ(dense(0, 0), c(0));
    if (m > 1) {
      EXPECT_DOUBLE_EQ(dense(1, 0), c(1));
      EXPECT_DOUBLE_EQ(dense(0, 1), c(m - 1));  // C(i, k) = c((i − k) mod M)
    }
    EXPECT_TRUE(spectral::Circulant::is_circulant(dense));
    const Eigen::MatrixXd v = Eigen::MatrixXd::Random(m, 3);
    EXPECT_LT((circ.apply(v) - dense * v).norm(), 1e-13 * (dense * v).norm()) << m;
    EXPECT_LT((circ.apply(v, true) - dense.transpose() * v).norm(), 1e-13 * (dense * v).norm()) << m;
    EXPECT_LT((circ.inverse().dense() * dense - Eigen::MatrixXd::Identity(m, m)).norm(), 1e-13) << m;
  }
  Eigen::MatrixXd not_circulant = spectral::Circulant(Eigen::VectorXd::LinSpaced(4, 1.0, 4.0)).dense();
  not_circulant(1, 2) += 1e-6;
  EXPECT_FALSE(spectral::Circulant::is_circulant(not_circulant));
  EXPECT_THROW((void)spectral::Circulant(Eigen::VectorXd::Ones(4)).inverse(), std::domain_error);  // eigenvalues 4, 0, 0
  EXPECT_THROW(spectral::Circulant{Eigen::VectorXd()}, std::invalid_argument);
}

// Circulant::from_eigenvalues against a closed form: the second-difference circulant (first column
// 2, −1, 0, …, 0, −1) has eigenvalues 2 − 2 cos(2πm/M). Built from them it gives back that column
// and that matrix's products; lengths other than ⌊M/2⌋ + 1 and non-finite eigenvalues are refused.
TEST(Circulant, FromEigenvaluesGivesTheCirculantOfThoseEigenvalues) {
  constexpr double kPi = 3.14159265358979323846;
  for (int m : {1, 2, 7, 16, 256}) {
    SCOPED_TRACE(m);
    Eigen::VectorXd column = Eigen::VectorXd::Zero(m);
    column(0) += 2.0;
    column((m - 1) % m) -= 1.0;
    column(1 % m) -= 1.0;
    Eigen::VectorXcd bins(m / 2 + 1);
    for (int k = 0; k <= m / 2; ++k) bins(k) = 2.0 - 2.0 * std::cos(2.0 * kPi * k / m);
    const spectral::Circulant c = spectral::Circulant::from_eigenvalues(bins, m);
    EXPECT_LT((c.first_column() - column).norm(), 1e-14);
    const Eigen::MatrixXd v = Eigen::MatrixXd::Random(m, 2);
    Eigen::MatrixXd dense = 2.0 * Eigen::MatrixXd::Identity(m, m);
    for (int i = 0; i < m; ++i) {
      dense(i, (i + 1) % m) -= 1.0;
      dense(i, (i + m - 1) % m) -= 1.0;
    }
    EXPECT_LT((c.apply(v) - dense * v).norm(), 1e-13 * (1.0 + (dense * v).norm()));
  }
  EXPECT_THROW((void)spectral::Circulant::from_eigenvalues(Eigen::VectorXcd::Ones(3), 8), std::invalid_argument);
  Eigen::VectorXcd bad = Eigen::VectorXcd::Ones(5);
  bad(2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW((void)spectral::Circulant::from_eigenvalues(bad, 8), std::invalid_argument);
}
