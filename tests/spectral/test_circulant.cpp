#include <wbm/spectral/circulant.hpp>

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
