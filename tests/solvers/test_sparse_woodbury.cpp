// The sparse form of the identity-plus-low-rank Jacobian (LowRankJacobian, newton.hpp; issue #39,
// item 1): J = (I + U L⁻¹ V′)/s solved through the sparse capacitance K = L + V′ U. Its solves
// and its bordered form against dense LUs of the matrices formed entry by entry (at a fold too,
// where J is singular and the bordered matrix is not), and the condensed contact Jacobian of a
// chain with a contact on every mass, which takes the form, against the dense Jacobian
// contact_jacobian(x) and against the verified full residual of the solve it gives.
#include <wbm/solvers/newton.hpp>

#include <cmath>
#include <memory>
#include <vector>

#include <Eigen/LU>
#include <gtest/gtest.h>

#include <wbm/contact/penalty.hpp>
#include <wbm/solvers/harmonic_balance.hpp>
#include <wbm/solvers/weighted_residual.hpp>
#include <wbm/spectral/layout.hpp>

#include "spring_chain.hpp"
#include "testing.hpp"

using namespace wbm;
using solvers::LowRankJacobian;
using solvers::TimeBasis;

namespace {

// A random sparse matrix with about `fill` of its entries, plus `diagonal` on the diagonal.
Eigen::SparseMatrix<double> random_sparse(Eigen::Index rows, Eigen::Index cols, double fill, double diagonal,
                                          unsigned seed) {
  std::srand(seed);
  const Eigen::MatrixXd pick = Eigen::MatrixXd::Random(rows, cols), value = Eigen::MatrixXd::Random(rows, cols);
  Eigen::MatrixXd m = (pick.array().abs() < fill).select(value, 0.0);
  for (Eigen::Index i = 0; i < std::min(rows, cols); ++i) m(i, i) += diagonal;
  return m.sparseView();
}

// J = (I + U L⁻¹ V′)/s in the sparse form, its update by a dense LU of L (the slow path).
LowRankJacobian sparse_form(const Eigen::SparseMatrix<double>& l, const Eigen::SparseMatrix<double>& u,
                            const Eigen::SparseMatrix<double>& v, double s) {
  LowRankJacobian j;
  j.scale = s;
  j.rows = u.rows();
  j.sparse_u = u;
  j.sparse_v = v;
  j.sparse_capacitance = l + Eigen::SparseMatrix<double>(v * u);
  const auto update = std::make_shared<const Eigen::MatrixXd>(Eigen::MatrixXd(u) *
                                                              Eigen::MatrixXd(l).lu().solve(Eigen::MatrixXd(v)));
  j.times_update = [update](const Eigen::MatrixXd& y) { return Eigen::MatrixXd(*update * y); };
  return j;
}

// [[α J, b], [cᵀ, d]] entry by entry, J given dense.
Eigen::MatrixXd bordered_matrix(const Eigen::MatrixXd& j, double alpha, const Eigen::VectorXd& b,
                                const Eigen::VectorXd& c, double d) {
  const Eigen::Index n = j.rows();
  Eigen::MatrixXd m(n + 1, n + 1);
  m.topLeftCorner(n, n) = alpha * j;
  m.topRightCorner(n, 1) = b;
  m.bottomLeftCorner(1, n) = c.transpose();
  m(n, n) = d;
  return m;
}

// The chain of `masses` forced at its free end at 0.8 f₁ (1 N), with linear penalty stops
// (1e3 N/m) on its last `contacts` masses at 0.95 of their linear amplitude: every contact is
// in contact over part of the period.
solvers::WeightedResidual chain_problem(int masses, int contacts, int m) {
  const double k = 1e4;
  const auto system = models::spring_chain(masses, k, 1e-4);
  const double f1 = std::sqrt(k) * std::sin(wbm::testing::kPi / (2.0 * (2 * masses + 1))) / wbm::testing::kPi;
  const solvers::HarmonicForcing forcing{masses - 1, 1.0, 0.8 * f1};
  const Eigen::VectorXcd lin = solvers::frequency_response(system, forcing);
  std::vector<solvers::ContactPoint> points;
  for (int c = masses - contacts; c < masses; ++c) {
    const contact::LinearPenaltyParameters stop{1e3, 0.95 * std::abs(lin(c))};
    points.push_back({c, std::make_shared<contact::LinearPenalty>(stop)});
  }
  return {system, forcing, points, TimeBasis::from_name("fourier", m), TimeBasis::from_name("fourier", m)};
}

}  // namespace

// J's solve and the bordered matrix's, against dense LUs of the matrices formed entry by entry.
TEST(SparseWoodbury, SolvesAsDenseLusOfTheMatricesItRepresents) {
  const Eigen::Index n = 7, q = 11;
  const auto l = random_sparse(q, q, 0.3, 4.0, 3);
  const auto u = random_sparse(n, q, 0.3, 0.0, 5);
  const auto v = random_sparse(q, n, 0.3, 0.0, 9);
  const double s = 0.41;
  const LowRankJacobian j = sparse_form(l, u, v, s);
  const Eigen::MatrixXd dense = (Eigen::MatrixXd::Identity(n, n) +
                                 Eigen::MatrixXd(u) * Eigen::MatrixXd(l).inverse() * Eigen::MatrixXd(v)) / s;
  EXPECT_TRUE(j.sparse_form());
  EXPECT_FALSE(j.dense_form());
  EXPECT_EQ(j.rank(), q);
  EXPECT_LE((j.dense() - dense).norm(), 1e-13 * dense.norm());
  const Eigen::VectorXd y = Eigen::VectorXd::Random(n);
  solvers::WoodburyLu w;
  ASSERT_TRUE(w.factorize(j));
  EXPECT_FALSE(w.rcond().has_value());
  const Eigen::VectorXd expected = dense.lu().solve(y);
  EXPECT_LE((w.solve(y) - expected).norm(), 1e-13 * expected.norm());

  const Eigen::VectorXd b = Eigen::VectorXd::Random(n), c = Eigen::VectorXd::Random(n);
  const Eigen::VectorXd rhs = Eigen::VectorXd::Random(n + 1);
  const double alpha = 1.7, d = -0.3;
  const LowRankJacobian bj = solvers::bordered_low_rank(j, alpha, b, c, d);
  const Eigen::MatrixXd reference = bordered_matrix(dense, alpha, b, c, d);
  EXPECT_TRUE(bj.sparse_form());
  EXPECT_EQ(bj.rank(), q + 2);
  EXPECT_EQ(bj.size(), n + 1);
  EXPECT_LE((bj.dense() - reference).norm(), 1e-13 * reference.norm());
  EXPECT_LE((bj.apply(rhs) - reference * rhs).norm(), 1e-13 * (reference * rhs).norm());
  solvers::WoodburyLu wb;
  ASSERT_TRUE(wb.factorize(bj));
  const Eigen::VectorXd bordered_expected = reference.lu().solve(rhs);
  EXPECT_LE((wb.solve(rhs) - bordered_expected).norm(), 1e-12 * bordered_expected.norm());
}

// J = I − e₁e₁ᵀ (singular) through U = [I 0], V′ = L [−e₁e₁ᵀ; 0]: K = L (I − E₁₁) has a zero
// column, so J's factorization fails, while the bordered matrix with b₁, c₁ ≠ 0 (a fold's) is
// regular and solved as a dense LU solves it.
TEST(SparseWoodbury, FailsOnASingularJacobianAndSolvesItsBorderedMatrix) {
  const Eigen::Index n = 5, q = 8;
  const auto l = random_sparse(q, q, 0.4, 3.0, 11);
  Eigen::SparseMatrix<double> u(n, q);
  for (Eigen::Index i = 0; i < n; ++i) u.insert(i, i) = 1.0;
  Eigen::MatrixXd e11 = Eigen::MatrixXd::Zero(q, n);
  e11(0, 0) = -1.0;
  const Eigen::SparseMatrix<double> v = (Eigen::MatrixXd(l) * e11).sparseView();
  const LowRankJacobian j = sparse_form(l, u, v, 1.0);
  Eigen::MatrixXd singular = Eigen::MatrixXd::Identity(n, n);
  singular(0, 0) = 0.0;
  EXPECT_LE((j.dense() - singular).norm(), 1e-14);
  solvers::WoodburyLu w;
  EXPECT_FALSE(w.factorize(j));
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(n), c = Eigen::VectorXd::Ones(n);
  const Eigen::VectorXd rhs = Eigen::VectorXd::Random(n + 1);
  const Eigen::MatrixXd reference = bordered_matrix(singular, 1.0, b, c, 0.0);
  ASSERT_GT(std::abs(reference.determinant()), 1e-3);
  solvers::WoodburyLu wb;
  ASSERT_TRUE(wb.factorize(solvers::bordered_low_rank(j, 1.0, b, c, 0.0)));
  const Eigen::VectorXd expected = reference.lu().solve(rhs);
  EXPECT_LE((wb.solve(rhs) - expected).norm(), 1e-12 * expected.norm());
}

// A chain with a stop on each of its 16 masses, Fourier:Fourier M = 16 (Q = 256 samples per
// contact, most of them in contact: r > ¾ n_c·M): the condensed Jacobian takes the sparse form,
// represents contact_jacobian(x) (H N by the compliance) and solves with it; on 2 contacts the
// dense form stays (K would hold 2 194 entries or fewer, more than the dense 32²).
TEST(SparseWoodbury, ChainContactJacobianIsTheDenseOneAndSolvesWithIt) {
  const auto wr = chain_problem(16, 16, 16);
  const Eigen::VectorXd x = wr.contact_unknowns(wr.linear_response()) * 1.05;
  const LowRankJacobian j = wr.contact_jacobian_low_rank(x);
  ASSERT_TRUE(j.sparse_form());
  const Eigen::MatrixXd dense = wr.contact_jacobian(x);
  EXPECT_LE((j.dense() - dense).norm(), 1e-12 * dense.norm());
  const Eigen::VectorXd y = Eigen::VectorXd::Random(x.size());
  solvers::WoodburyLu w;
  ASSERT_TRUE(w.factorize(j));
  const Eigen::VectorXd d = w.solve(y);
  EXPECT_LE((dense * d - y).norm(), 1e-12 * y.norm());
  const auto few = chain_problem(16, 2, 16);
  EXPECT_FALSE(few.contact_jacobian_low_rank(few.contact_unknowns(few.linear_response()) * 1.05).sparse_form());
}

// The contact homotopy's linearization in that form against central differences, and the solve
// of the 16-contact chain verified on the full residual R(a) = G a + Pᵀ n(P a) − b (not the
// condensed one the sparse form solves).
TEST(SparseWoodbury, ChainHomotopyLinearizationAndSolveAreVerified) {
  const auto wr = chain_problem(16, 16, 16);
  const auto homotopy = wr.contact_homotopy();
  const Eigen::VectorXd x = wr.contact_unknowns(wr.linear_response()) * 1.05;
  struct AtLambda {
    solvers::WeightedResidual::ContactHomotopy h;
    double lambda;
    Eigen::VectorXd residual(const Eigen::VectorXd& y) const { return h.residual(y, lambda); }
    Eigen::MatrixXd jacobian(const Eigen::VectorXd& y) const { return h.linearize(y, lambda).jacobian.dense(); }
  };
  ASSERT_TRUE(homotopy.linearize(x, -0.7).jacobian.sparse_form());
  wbm::testing::expect_jacobian_matches_fd(AtLambda{homotopy, -0.7}, x, 1e-5, 1e-7, 1e-6);
  const auto sol = wr.solve();
  ASSERT_TRUE(sol.converged()) << sol.report.message;
  const Eigen::VectorXd a = spectral::stacked(sol.coefficients);
  EXPECT_LE(wr.backward_error(a, wr.residual(a)), 1e-12);
  EXPECT_LE(sol.relative_residual, 1e-8);
}
