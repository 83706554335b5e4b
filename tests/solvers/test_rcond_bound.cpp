// detail::rcond_lower_bound (solvers/detail/rcond_bound.hpp), the certified lower bound of
// rcond₁ that lets the LL11 KKT solver skip the condition estimate of its harmonic blocks.
// Truths from outside the code under test: rcond₁ = 1 / (‖A‖₁ ‖A⁻¹‖₁) with A⁻¹ from Eigen's
// full-pivoting LU; Eigen's PartialPivLU::rcond() (Hager–Higham), which estimates ‖A⁻¹‖₁ from
// below and so can only lie above the bound; a singular matrix.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include <wbm/fem/rod.hpp>
#include <wbm/solvers/detail/rcond_bound.hpp>

namespace wbm::solvers {
namespace {

double one_norm(const Eigen::MatrixXd& a) { return a.cwiseAbs().colwise().sum().maxCoeff(); }

double exact_rcond(const Eigen::MatrixXd& a) { return 1.0 / (one_norm(a) * one_norm(a.fullPivLu().inverse())); }

// The bound never exceeds rcond₁ nor the estimate, to the accuracy of the computed inverse
// (relative 100 n ε / rcond₁, plus 1e-8); `tight` is how far below rcond₁ it may lie.
void expect_bound(const Eigen::MatrixXd& a, double tight, const char* what) {
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(a);
  const double bound = detail::rcond_lower_bound(lu, one_norm(a));
  const double exact = exact_rcond(a);
  const double slack = 1.0 + 1e-8 + 100.0 * static_cast<double>(a.rows()) * std::numeric_limits<double>::epsilon() / exact;
  EXPECT_GT(bound, 0.0) << what;
  EXPECT_LE(bound, exact * slack) << what << ": bound " << bound << ", rcond " << exact;
  EXPECT_LE(bound, lu.rcond() * slack) << what;
  EXPECT_GE(bound, exact / tight) << what << ": bound " << bound << ", rcond " << exact;
}

TEST(RcondLowerBound, BoundsTheConditionOfTheRodsHarmonicBlocksFromBelow) {
  // The LL11 rod's blocks K − (kω)² M (20 elements, consistent mass), k = 0 … 32 at ω near its
  // first natural frequency: indefinite once kω passes it. The comparison matrices make the
  // bound pessimistic, by 1 to 8e4 on these (rcond₁ 7e-7 … 5e-2; the largest factors where
  // K − (kω)² M is most indefinite): still above the 1e-10 at which the solver skips the estimate.
  const fem::Rod rod({2.1e11, 7800.0, 9e-4, 1.0, 20});
  const Eigen::MatrixXd k = Eigen::MatrixXd(rod.stiffness()), m = Eigen::MatrixXd(rod.mass());
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> modes(k, m);
  const double omega = 1.0003 * std::sqrt(modes.eigenvalues()(0));
  for (int h = 0; h <= 32; ++h) {
    const Eigen::MatrixXd a = k - (h * omega) * (h * omega) * m;
    expect_bound(a, 1e6, "rod block");
    EXPECT_GE(detail::rcond_lower_bound(Eigen::PartialPivLU<Eigen::MatrixXd>(a), one_norm(a)), 1e-10) << h;
  }
  // At 1 + 1e-9 times the first eigenvalue: rcond₁ about 1e-12, and still bounded from below.
  const Eigen::MatrixXd near = k - (1.0 + 1e-9) * modes.eigenvalues()(0) * m;
  expect_bound(near, 1e6, "near resonance");
  EXPECT_LT(exact_rcond(near), 1e-11);
}

TEST(RcondLowerBound, IsBelowTheConditionOfRandomAndIllConditionedMatrices) {
  std::srand(7);
  for (int n : {1, 2, 5, 30}) {
    const Eigen::MatrixXd a = Eigen::MatrixXd::Random(n, n) + n * Eigen::MatrixXd::Identity(n, n);
    expect_bound(a, 1e3, "diagonally dominant");
  }
  // The Hilbert matrix of order 8: rcond₁ ≈ 3e-11; the bound may be far below, never above.
  Eigen::MatrixXd hilbert(8, 8);
  for (int i = 0; i < 8; ++i) {
    for (int j = 0; j < 8; ++j) hilbert(i, j) = 1.0 / (i + j + 1);
  }
  expect_bound(hilbert, 1e12, "Hilbert");
  EXPECT_LT(detail::rcond_lower_bound(Eigen::PartialPivLU<Eigen::MatrixXd>(hilbert), one_norm(hilbert)), 1e-10);
}

TEST(RcondLowerBound, IsZeroForASingularOrEmptyMatrix) {
  Eigen::MatrixXd singular(3, 3);
  singular << 1, 2, 3, 2, 4, 6, 1, 0, 1;  // row 2 = 2 × row 1
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(singular);
  EXPECT_EQ(detail::rcond_lower_bound(lu, one_norm(singular)), 0.0);
  EXPECT_EQ(detail::rcond_lower_bound(Eigen::PartialPivLU<Eigen::MatrixXd>(Eigen::MatrixXd(0, 0)), 0.0), 0.0);
}

}  // namespace
}  // namespace wbm::solvers
