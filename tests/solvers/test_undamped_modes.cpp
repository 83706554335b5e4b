// Undamped modes of a tridiagonal pencil by Sturm bisection and inverse iteration
// (undamped_modes.hpp). Truths from outside the code under test:
//  - the closed-form eigenvalues of the fixed-free chain of unit masses and unit springs,
//    λ_k = 4 sin²((2k − 1)π / (2(2n + 1))) [Gantmacher & Krein 2002, Oscillation Matrices and
//    Kernels, Ch. III; the discrete string];
//  - Eigen's dense generalized eigensolver on the FE rod (consistent mass), eigenvalues to
//    1e-12 of the largest, and the identities Φᵀ M Φ = I and K Φ = M Φ Λ to rounding;
//  - refusals: a pentadiagonal K, and an M that is not positive definite.
#include <gtest/gtest.h>

#include <cmath>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include <wbm/fem/rod.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/undamped_modes.hpp>

#include "spring_chain.hpp"
#include "testing.hpp"

namespace wbm::solvers {
namespace {

using wbm::testing::kPi;

void expect_identities(const Eigen::SparseMatrix<double>& k, const Eigen::SparseMatrix<double>& m,
                       const UndampedModes& modes) {
  const Eigen::Index n = k.rows();
  const Eigen::MatrixXd mphi = m * modes.phi;
  EXPECT_LE((modes.phi.transpose() * mphi - Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff(), 1e-12);
  const double kmax = modes.lambda.cwiseAbs().maxCoeff();
  EXPECT_LE((k * modes.phi - mphi * modes.lambda.asDiagonal()).colwise().norm().maxCoeff(), 1e-12 * kmax);
  for (Eigen::Index i = 1; i < n; ++i) EXPECT_LE(modes.lambda(i - 1), modes.lambda(i));
}

TEST(UndampedModes, ChainMatchesTheClosedForm) {
  const int n = 600;
  const MechanicalSystem chain = models::spring_chain(n, 1.0, 0.0);  // unit masses and springs, fixed-free
  const Eigen::SparseMatrix<double>& k = chain.stiffness;
  const Eigen::SparseMatrix<double>& m = chain.mass;
  const auto modes = tridiagonal_undamped_modes(k, m);
  ASSERT_TRUE(modes.has_value());
  EXPECT_EQ(modes->method, "tridiagonal");
  for (int j = 1; j <= n; ++j) {
    const double s = std::sin((2.0 * j - 1.0) * kPi / (2.0 * (2.0 * n + 1.0)));
    EXPECT_NEAR(modes->lambda(j - 1), 4.0 * s * s, 1e-14 * 4.0) << "mode " << j;
  }
  expect_identities(k, m, *modes);
}

TEST(UndampedModes, RodMatchesTheDenseSolver) {
  for (const int elements : {40, 450}) {
    SCOPED_TRACE(elements);
    const fem::Rod rod({70e9, 2700.0, 25e-4, 1.0, elements});
    const MechanicalSystem s = beta_damped(rod, 0.0);
    const auto modes = tridiagonal_undamped_modes(s.stiffness, s.mass);
    ASSERT_TRUE(modes.has_value());
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> dense{Eigen::MatrixXd(s.stiffness),
                                                                          Eigen::MatrixXd(s.mass)};
    const double top = dense.eigenvalues().cwiseAbs().maxCoeff();
    EXPECT_LE((modes->lambda - dense.eigenvalues()).cwiseAbs().maxCoeff(), 1e-12 * top);
    expect_identities(s.stiffness, s.mass, *modes);
    EXPECT_EQ(undamped_modes(s.stiffness, s.mass).method, elements >= 400 ? "tridiagonal" : "dense");
  }
}

TEST(UndampedModes, RefusesWhatIsNotATridiagonalDefinitePencil) {
  const int n = 6;
  Eigen::SparseMatrix<double> k(n, n), m(n, n);
  for (int i = 0; i < n; ++i) {
    k.insert(i, i) = 2.0;
    m.insert(i, i) = 1.0;
  }
  k.insert(0, 2) = k.insert(2, 0) = -0.5;  // pentadiagonal
  EXPECT_FALSE(tridiagonal_undamped_modes(k, m).has_value());
  k.coeffRef(0, 2) = k.coeffRef(2, 0) = 0.0;
  m.coeffRef(3, 3) = -1.0;  // indefinite
  EXPECT_FALSE(tridiagonal_undamped_modes(k, m).has_value());
  m.coeffRef(3, 3) = 1.0;
  EXPECT_TRUE(tridiagonal_undamped_modes(k, m).has_value());
}

}  // namespace
}  // namespace wbm::solvers
