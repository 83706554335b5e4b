// The symmetric sparse-plus-low-rank Jacobian H = S + U C Uᵀ (SparseLowRankHessian, newton.hpp)
// and its policy BorderedSparseLu, against dense LUs, inverses and QRs of H formed entry by
// entry: solves where S alone is singular (a harmonic block at resonance, the linear mode of
// LL11 Alg. 1), the reciprocal condition estimate against the exact one, a singular H reported
// singular, and the Levenberg–Marquardt step against the QR of [H; μI] and the SVD closed form.
#include <wbm/solvers/newton.hpp>

#include <cmath>
#include <limits>
#include <type_traits>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <gtest/gtest.h>

using namespace wbm;
using solvers::BorderedSparseLu;
using solvers::SparseLowRankHessian;

namespace {

// S: n/b symmetric tridiagonal blocks of size b (a harmonic balance's K − ν²ω²M per harmonic),
// the block `singular_block` shifted so that it has an exact zero eigenvalue; U (n × 2) dense;
// C = [[c_e, −a], [−a, 0]], the Rayleigh quotient's and the normalization's (LL11 Eq. (18)).
SparseLowRankHessian example(Eigen::Index n, Eigen::Index b, int singular_block, unsigned seed) {
  std::srand(seed);
  std::vector<Eigen::Triplet<double>> t;
  for (Eigen::Index k = 0; k * b < n; ++k) {
    Eigen::MatrixXd block = Eigen::MatrixXd::Zero(b, b);
    for (Eigen::Index i = 0; i < b; ++i) {
      block(i, i) = 2.0 + 0.5 * k;
      if (i + 1 < b) block(i, i + 1) = block(i + 1, i) = -1.0 + 0.1 * Eigen::VectorXd::Random(1)(0);
    }
    if (k == singular_block) {
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(block);
      block -= eig.eigenvalues()(0) * Eigen::MatrixXd::Identity(b, b);
    }
    for (Eigen::Index i = 0; i < b; ++i) {
      for (Eigen::Index j = 0; j < b; ++j) {
        if (block(i, j) != 0.0) t.emplace_back(k * b + i, k * b + j, block(i, j));
      }
    }
  }
  SparseLowRankHessian h;
  h.sparse.resize(n, n);
  h.sparse.setFromTriplets(t.begin(), t.end());
  h.u = Eigen::MatrixXd::Random(n, 2);
  h.u.col(0) *= 1e-3;
  h.u.col(1) *= 1e4;
  h.core.resize(2, 2);
  h.core << 4e6, -1.5e-8, -1.5e-8, 0.0;  // c_e ≫ a as in LL11 Alg. 1 (C⁻¹ would hold 1e22)
  return h;
}

double backward_error(const Eigen::MatrixXd& h, const Eigen::VectorXd& x, const Eigen::VectorXd& b) {
  return (b - h * x).lpNorm<Eigen::Infinity>() /
         (h.cwiseAbs().rowwise().sum().maxCoeff() * x.lpNorm<Eigen::Infinity>() + b.lpNorm<Eigen::Infinity>());
}

}  // namespace

TEST(BorderedSparseLu, IsNewtonsDefaultForTheStructuredHessian) {
  struct System {
    [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x) const { return x; }
    [[nodiscard]] SparseLowRankHessian jacobian(const Eigen::VectorXd&) const { return {}; }
  };
  static_assert(std::is_same_v<solvers::DefaultLinearSolver<System>, BorderedSparseLu>);
  static_assert(solvers::LevenbergMarquardtPolicy<BorderedSparseLu, SparseLowRankHessian>);
  static_assert(!solvers::LevenbergMarquardtPolicy<solvers::DenseLu, Eigen::MatrixXd>);
}

TEST(BorderedSparseLu, SolvesLikeADenseLuWhereSAloneIsSingular) {
  for (int singular : {-1, 1}) {
    const SparseLowRankHessian h = example(60, 12, singular, 3);
    const Eigen::MatrixXd dense = Eigen::MatrixXd(h.sparse) + h.u * h.core * h.u.transpose();
    ASSERT_LT((h.dense() - dense).cwiseAbs().maxCoeff(), 1e-15 * dense.cwiseAbs().maxCoeff());
    const Eigen::VectorXd y = Eigen::VectorXd::LinSpaced(60, -1.0, 2.0);
    EXPECT_LT((h.apply(y) - dense * y).lpNorm<Eigen::Infinity>(), 1e-14 * (dense * y).lpNorm<Eigen::Infinity>());
    if (singular >= 0) {  // S singular (its block's smallest eigenvalue removed), H regular
      const Eigen::VectorXd ls =
          Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Eigen::MatrixXd(h.sparse)).eigenvalues();
      const Eigen::VectorXd lh = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(dense).eigenvalues();
      EXPECT_LT(ls.cwiseAbs().minCoeff(), 1e-14 * ls.cwiseAbs().maxCoeff());
      ASSERT_GT(lh.cwiseAbs().minCoeff(), 1e-9 * lh.cwiseAbs().maxCoeff());
    }
    BorderedSparseLu lu;
    ASSERT_TRUE(lu.factorize(h));
    for (unsigned seed : {1u, 2u}) {
      std::srand(seed);
      const Eigen::VectorXd b = Eigen::VectorXd::Random(60);
      const Eigen::VectorXd x = lu.solve(b), expected = dense.partialPivLu().solve(b);
      EXPECT_LT(backward_error(dense, x, b), 1e-15) << "S singular: " << (singular >= 0);
      EXPECT_LT((x - expected).norm(), 1e-9 * expected.norm()) << "S singular: " << (singular >= 0);
    }
    EXPECT_EQ(lu.fallback_solves(), 0);
    EXPECT_NEAR(lu.jacobian_infinity_norm(h), dense.cwiseAbs().rowwise().sum().maxCoeff(),
                1e-14 * dense.cwiseAbs().rowwise().sum().maxCoeff());
    // rcond: Hager–Higham's estimate is a lower bound of ‖H⁻¹‖₁, so rcond is at least the exact one.
    const double exact =
        1.0 / (dense.cwiseAbs().colwise().sum().maxCoeff() * dense.inverse().cwiseAbs().colwise().sum().maxCoeff());
    ASSERT_TRUE(lu.rcond().has_value());
    EXPECT_GE(*lu.rcond(), exact * (1.0 - 1e-9));
    EXPECT_LE(*lu.rcond(), 10.0 * exact);
  }
}

TEST(BorderedSparseLu, ASingularHessianIsReportedSingular) {
  // S = diag(1, 2, …), U = e₀, C = [−1]: H = diag(0, 2, …).
  SparseLowRankHessian h;
  h.sparse.resize(8, 8);
  for (int i = 0; i < 8; ++i) h.sparse.insert(i, i) = i + 1.0;
  h.u = Eigen::MatrixXd::Zero(8, 1);
  h.u(0, 0) = 1.0;
  h.core = Eigen::MatrixXd::Constant(1, 1, -1.0);
  BorderedSparseLu lu;
  const bool factorized = lu.factorize(h);
  EXPECT_TRUE(!factorized || *lu.rcond() < 1e-14) << "rcond " << *lu.rcond();
  // Ill-formed or non-finite input is refused, never solved.
  SparseLowRankHessian bad = h;
  bad.u = Eigen::MatrixXd::Zero(7, 1);
  EXPECT_FALSE(lu.factorize(bad));
  EXPECT_FALSE(lu.solve(Eigen::VectorXd::Ones(8)).allFinite());
  bad = h;
  bad.core(0, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(lu.factorize(bad));
  bad = h;
  bad.core(0, 0) = 0.0;  // C singular, H = S regular: solved all the same
  ASSERT_TRUE(lu.factorize(bad));
  EXPECT_LT((lu.solve(Eigen::VectorXd::Ones(8)) - Eigen::VectorXd::LinSpaced(8, 1.0, 8.0).cwiseInverse()).norm(),
            1e-15);
}

// The step d = argmin ‖H d + r‖² + μ²‖d‖² by the shifted system against the dense QR of [H; μI]
// (detail::levenberg_marquardt_step) and the eigen-decomposition closed form
// d = −Σᵢ λᵢ / (λᵢ² + μ²) (vᵢᵀ r) vᵢ, on a regular H and on a singular one (where the fallback is
// taken), from μ = 1e-6 ‖H‖∞ (newton()'s start) to μ far above ‖H‖. The step's own condition:
// an eigenvalue perturbed by ε‖H‖ moves it by up to ε (‖H‖/μ)² relative, the tolerance used.
TEST(BorderedSparseLu, LevenbergMarquardtStepMatchesTheQrOfTheStackedSystem) {
  for (int singular : {-1, 2}) {
    SparseLowRankHessian h = example(48, 8, 2, 5);
    if (singular >= 0) {  // make H itself singular: remove its smallest eigenvalue through S
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(h.dense());
      Eigen::Index i = 0;
      eig.eigenvalues().cwiseAbs().minCoeff(&i);
      const Eigen::VectorXd v = eig.eigenvectors().col(i);
      Eigen::MatrixXd s = Eigen::MatrixXd(h.sparse) - eig.eigenvalues()(i) * v * v.transpose();
      h.sparse = s.sparseView();
    }
    const Eigen::MatrixXd dense = h.dense();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(dense);
    std::srand(7);
    const Eigen::VectorXd r = Eigen::VectorXd::Random(48);
    BorderedSparseLu lu;
    const double norm = lu.jacobian_infinity_norm(h);
    for (double mu : {1e-6 * norm, 1e-2 * norm, norm, 1e3 * norm}) {
      const Eigen::VectorXd d = lu.levenberg_marquardt_step(h, r, mu);
      const Eigen::VectorXd qr = solvers::detail::levenberg_marquardt_step(dense, r, mu);
      Eigen::VectorXd closed = Eigen::VectorXd::Zero(48);
      for (Eigen::Index i = 0; i < 48; ++i) {
        const double l = eig.eigenvalues()(i);
        closed -= l / (l * l + mu * mu) * eig.eigenvectors().col(i).dot(r) * eig.eigenvectors().col(i);
      }
      const double tolerance = 1e-10 + 1e-15 * (norm / mu) * (norm / mu);
      EXPECT_LT((d - closed).norm(), tolerance * closed.norm()) << "μ = " << mu << ", H singular: " << (singular >= 0);
      EXPECT_LT((d - qr).norm(), tolerance * qr.norm()) << "μ = " << mu;
    }
    EXPECT_FALSE(lu.levenberg_marquardt_step(h, r, 0.0).allFinite());  // μ must be > 0
  }
}
