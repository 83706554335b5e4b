#include <wbm/solvers/newton.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <Eigen/SparseCore>

#include <gtest/gtest.h>

#include "testing.hpp"

using namespace wbm::solvers;

namespace {
// x³ − 8 = 0 component-wise: root 2, quadratic convergence from x0 = 3.
struct Cubic {
  Eigen::VectorXd residual(const Eigen::VectorXd& x) const { return x.array().cube() - 8.0; }
  Eigen::MatrixXd jacobian(const Eigen::VectorXd& x) const {
    return (3.0 * x.array().square()).matrix().asDiagonal();
  }
};
// arctan(x) = 0: undamped Newton diverges from |x0| > 1.39; the line search must rescue it.
struct Arctan {
  Eigen::VectorXd residual(const Eigen::VectorXd& x) const { return x.array().atan(); }
  Eigen::MatrixXd jacobian(const Eigen::VectorXd& x) const {
    return (1.0 / (1.0 + x.array().square())).matrix().asDiagonal();
  }
};
// x² + 1 = 0 has no real root: Newton cannot converge.
struct NoRoot {
  Eigen::VectorXd residual(const Eigen::VectorXd& x) const { return x.array().square() + 1.0; }
  Eigen::MatrixXd jacobian(const Eigen::VectorXd& x) const { return (2.0 * x).asDiagonal(); }
};
struct Nan {
  Eigen::VectorXd residual(const Eigen::VectorXd& x) const {
    return Eigen::VectorXd::Constant(x.size(), std::numeric_limits<double>::quiet_NaN());
  }
  Eigen::MatrixXd jacobian(const Eigen::VectorXd& x) const { return Eigen::MatrixXd::Identity(x.size(), x.size()); }
};
}  // namespace

// Quadratic convergence: e_{k+1} ≈ e_k² f''/(2f') = e_k²/2 at the root 2 of x³ − 8.
TEST(Newton, ConvergesQuadraticallyOnASmoothRoot) {
  const auto r = newton(Cubic{}, Eigen::VectorXd::Constant(2, 3.0), {.tolerance = 1e-13});
  ASSERT_TRUE(r.report.converged()) << r.report.message;
  EXPECT_NEAR(r.x(0), 2.0, 1e-14);
  const auto& n = r.report.residual_norms;
  ASSERT_GE(n.size(), 4u);
  EXPECT_LT(n[n.size() - 2], 1e-3 * n[n.size() - 3]);  // super-linear near the root
}

// Invalid options are refused before the first residual, naming the field, its value and the
// range (issue #41): a tolerance <= 0 used to be accepted and could never be met.
TEST(Newton, RefusesInvalidOptionsNamingTheField) {
  const Eigen::VectorXd x0 = Eigen::VectorXd::Constant(2, 3.0);
  using wbm::testing::expect_throw_with;
  expect_throw_with<std::invalid_argument>([&] { (void)newton(Cubic{}, x0, {.tolerance = 0.0}); },
                                           {"NewtonOptions.tolerance = 0", "must be > 0"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)newton(Cubic{}, x0, {.tolerance = std::numeric_limits<double>::quiet_NaN()}); },
      {"NewtonOptions.tolerance", "finite"});
  expect_throw_with<std::invalid_argument>([&] { (void)newton(Cubic{}, x0, {.max_iterations = -1}); },
                                           {"NewtonOptions.max_iterations = -1", ">= 0"});
  expect_throw_with<std::invalid_argument>([&] { (void)newton(Cubic{}, x0, {.max_backtracks = -2}); },
                                           {"NewtonOptions.max_backtracks = -2"});
  expect_throw_with<std::invalid_argument>([&] { (void)newton(Cubic{}, x0, {.min_rcond = 1.0}); },
                                           {"NewtonOptions.min_rcond = 1", "[0, 1)"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)newton(Cubic{}, x0, {.levenberg_marquardt = true, .max_lm_trials = 0}); },
      {"NewtonOptions.max_lm_trials = 0", "levenberg_marquardt = false"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)newton(Cubic{}, x0, {.stop_on_cycle = true, .cycle_tolerance = -1e-3}); },
      {"NewtonOptions.cycle_tolerance"});
  // The boundary values are accepted: no iteration at all, and a bound that is met.
  EXPECT_EQ(newton(Cubic{}, x0, {.max_iterations = 0}).report.iterations, 0);
  EXPECT_TRUE(newton(Cubic{}, x0, {.tolerance = 1e-300, .min_rcond = 0.0}).x.isApprox(Eigen::VectorXd::Constant(2, 2.0)));
}

TEST(Newton, LineSearchGlobalizesArctan) {
  const auto damped = newton(Arctan{}, Eigen::VectorXd::Constant(1, 10.0));
  ASSERT_TRUE(damped.report.converged()) << damped.report.message;
  EXPECT_NEAR(damped.x(0), 0.0, 1e-10);
  const auto plain = newton(Arctan{}, Eigen::VectorXd::Constant(1, 10.0), {.max_iterations = 10, .line_search = false});
  EXPECT_FALSE(plain.report.converged());
}

TEST(Newton, ReportsFailureWithoutThrowing) {
  const auto r = newton(NoRoot{}, Eigen::VectorXd::Constant(1, 0.5), {.max_iterations = 20});
  EXPECT_FALSE(r.report.converged());
  EXPECT_NE(r.report.message.find("last ||R||"), std::string::npos);
  const auto bad = newton(Nan{}, Eigen::VectorXd::Zero(3));
  EXPECT_EQ(bad.report.status, SolveStatus::NonFinite);
}

namespace {
// x³ − 8 = 0 with a sparse (diagonal) Jacobian: the pattern never changes.
struct SparseCubic {
  Eigen::VectorXd residual(const Eigen::VectorXd& x) const { return x.array().cube() - 8.0; }
  Eigen::SparseMatrix<double> jacobian(const Eigen::VectorXd& x) const {
    Eigen::SparseMatrix<double> j(x.size(), x.size());
    for (Eigen::Index i = 0; i < x.size(); ++i) j.insert(i, i) = 3.0 * x(i) * x(i);
    return j;
  }
};
// Semismooth: min(x₀, x₁) = 0, x₀ − x₁ − 2 = 0, unique root (2, 0). From (−1, 1) the min picks
// x₀, after one step (0, −2) it picks x₁: the Jacobian's pattern changes on the way.
struct Switching {
  Eigen::VectorXd residual(const Eigen::VectorXd& x) const {
    return Eigen::Vector2d(std::min(x(0), x(1)), x(0) - x(1) - 2.0);
  }
  Eigen::SparseMatrix<double> jacobian(const Eigen::VectorXd& x) const {
    Eigen::SparseMatrix<double> j(2, 2);
    j.insert(0, x(0) <= x(1) ? 0 : 1) = 1.0;  // the min picks x₀ or x₁
    j.insert(1, 0) = 1.0;
    j.insert(1, 1) = -1.0;
    return j;
  }
};
}  // namespace

// The sparse policies (KLU, and Eigen's SparseLU) reach the same root, 2, and analyse the
// (constant) pattern once for the whole solve, and once for a second solve with the same object.
template <class Policy>
void expect_analysis_kept_while_the_pattern_holds(const char* name) {
  Policy solver;
  const auto r = newton(SparseCubic{}, Eigen::VectorXd::Constant(5, 3.0), {.tolerance = 1e-13}, solver);
  ASSERT_TRUE(r.report.converged()) << name << ": " << r.report.message;
  EXPECT_LT((r.x.array() - 2.0).abs().maxCoeff(), 1e-14) << name;
  EXPECT_GE(r.report.iterations, 4) << name;
  EXPECT_EQ(solver.symbolic_analyses(), 1) << name;
  EXPECT_FALSE(r.report.jacobian_rcond.has_value()) << name;  // sparse LU estimates no condition number
  const auto again = newton(SparseCubic{}, Eigen::VectorXd::Constant(5, 5.0), {.tolerance = 1e-13}, solver);
  ASSERT_TRUE(again.report.converged()) << name;
  EXPECT_EQ(solver.symbolic_analyses(), 1) << name;
}

TEST(Newton, SparseLuKeepsItsSymbolicAnalysisWhileThePatternHolds) {
  expect_analysis_kept_while_the_pattern_holds<SparseLu>("SparseLu (KLU)");
  expect_analysis_kept_while_the_pattern_holds<wbm::solvers::SupernodalLu>("SupernodalLu");
}

// A semismooth Newton whose active set changes: the pattern changes, a new analysis is made,
// and the root (2, 0) is found in two steps.
template <class Policy>
void expect_reanalysis_when_the_pattern_changes(const char* name) {
  Policy solver;
  const auto r = newton(Switching{}, Eigen::Vector2d(-1.0, 1.0), {.line_search = false}, solver);
  ASSERT_TRUE(r.report.converged()) << name << ": " << r.report.message;
  EXPECT_EQ(r.report.iterations, 2) << name;
  EXPECT_NEAR(r.x(0), 2.0, 1e-12) << name;
  EXPECT_NEAR(r.x(1), 0.0, 1e-12) << name;
  EXPECT_EQ(solver.symbolic_analyses(), 2) << name;
}

TEST(Newton, SparseLuReanalysesWhenThePatternChanges) {
  expect_reanalysis_when_the_pattern_changes<SparseLu>("SparseLu (KLU)");
  expect_reanalysis_when_the_pattern_changes<wbm::solvers::SupernodalLu>("SupernodalLu");
}

// The kept analysis depends on the pattern only: a reused SupernodalLu solves a second matrix of
// the same pattern (other values, pivots in other rows) to the same bits as a fresh one, and
// after a change of pattern as a dense LU does.
TEST(Newton, SupernodalLuReusedAnalysisGivesTheFreshFactorsBits) {
  const int n = 60;
  auto matrix = [n](unsigned seed, int band) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<double> value(-0.5, 0.5);
    std::vector<Eigen::Triplet<double>> t;
    for (int i = 0; i < n; ++i) {
      for (int j = std::max(0, i - band); j < std::min(n, i + band + 1); ++j) {
        t.emplace_back(i, j, value(random));
      }
      t.emplace_back(i, (7 * i + 3) % n, 1.0);  // off the band: fill-in that the ordering must handle
    }
    Eigen::SparseMatrix<double> a(n, n);
    a.setFromTriplets(t.begin(), t.end());
    a.makeCompressed();
    return a;
  };
  const Eigen::SparseMatrix<double> a = matrix(1, 2), b = matrix(2, 2), c = matrix(3, 4);
  ASSERT_TRUE(a.nonZeros() == b.nonZeros());
  const Eigen::VectorXd rhs = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0);
  wbm::solvers::SupernodalLu reused, fresh;
  ASSERT_TRUE(reused.factorize(a));
  ASSERT_TRUE(reused.factorize(b));
  ASSERT_TRUE(fresh.factorize(b));
  EXPECT_EQ(reused.symbolic_analyses(), 1);
  const Eigen::VectorXd x = reused.solve(rhs);
  EXPECT_EQ(x, fresh.solve(rhs));
  EXPECT_EQ(reused.solve_transposed(rhs), fresh.solve_transposed(rhs));
  EXPECT_LT((Eigen::MatrixXd(b) * x - rhs).norm(), 1e-12 * rhs.norm());
  ASSERT_TRUE(reused.factorize(c));
  EXPECT_EQ(reused.symbolic_analyses(), 2);
  const Eigen::VectorXd xc = Eigen::MatrixXd(c).partialPivLu().solve(rhs);
  EXPECT_LT((reused.solve(rhs) - xc).norm(), 1e-12 * xc.norm());
}

// The sparse policy (KLU) refuses a singular Jacobian: SparseCubic at x = (2, 0, 2) has a zero
// row (3·0² = 0), and Newton reports SingularJacobian instead of a step. A 3 × 3 system with a
// known solution checks the solve itself: A = [[4, 1, 0], [1, 3, 1], [0, 1, 2]], A (1, 2, 3) =
// (6, 10, 8).
// DenseLu refuses factors that are not finite (it returned true whatever J held, issue #41) and
// solves a known system; an exactly singular J has finite factors (newton() tells it by rcond or
// by its non-finite step).
TEST(Newton, DenseLuRefusesANonFiniteJacobianAndSolvesAKnownSystem) {
  DenseLu lu;
  Eigen::MatrixXd j(2, 2);
  j << 4.0, 1.0, 2.0, 3.0;
  ASSERT_TRUE(lu.factorize(j));
  EXPECT_TRUE(lu.solve(Eigen::Vector2d(6.0, 8.0)).isApprox(Eigen::Vector2d(1.0, 2.0), 1e-14));
  j(1, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(lu.factorize(j));
  j(1, 0) = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(lu.factorize(j));
  Eigen::MatrixXd singular(2, 2);
  singular << 1.0, 2.0, 2.0, 4.0;
  EXPECT_TRUE(lu.factorize(singular));
}

TEST(Newton, SparseLuRefusesASingularJacobianAndSolvesAKnownSystem) {
  SparseLu solver;
  EXPECT_FALSE(solver.factorize(SparseCubic{}.jacobian(Eigen::Vector3d(2.0, 0.0, 2.0))));
  const auto r = newton(SparseCubic{}, Eigen::Vector3d(2.0, 0.0, 2.0), {}, solver);
  EXPECT_EQ(r.report.status, SolveStatus::SingularJacobian) << r.report.message;
  Eigen::SparseMatrix<double> a(3, 3);
  const double entries[3][3] = {{4, 1, 0}, {1, 3, 1}, {0, 1, 2}};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (entries[i][j] != 0.0) a.insert(i, j) = entries[i][j];
    }
  }
  ASSERT_TRUE(solver.factorize(a));
  EXPECT_LT((solver.solve(Eigen::Vector3d(6.0, 10.0, 8.0)) - Eigen::Vector3d(1.0, 2.0, 3.0)).norm(), 1e-14);
  Eigen::SparseMatrix<double> infinite = a;
  infinite.coeffRef(1, 1) = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(solver.factorize(infinite));
}

namespace {
// A nonsymmetric sparse test matrix: tridiagonal 4 on the diagonal, 1 above, −2 below, plus a
// corner entry; diagonally dominant, so nonsingular.
Eigen::SparseMatrix<double> nonsymmetric(int n) {
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, 4.0 + 0.1 * i);
    if (i + 1 < n) t.emplace_back(i, i + 1, 1.0);
    if (i > 0) t.emplace_back(i, i - 1, -2.0);
  }
  t.emplace_back(0, n - 1, 0.5);
  Eigen::SparseMatrix<double> a(n, n);
  a.setFromTriplets(t.begin(), t.end());
  return a;
}

// Both sparse policies against a dense LU of the same matrix: A⁻¹ b, A⁻ᵀ b and several columns
// at once, to rounding; a singular (zero column) or non-finite matrix is refused, and a solve
// after a refused factorization is NaN, never stale.
template <class Policy>
void expect_sparse_policy_solves(const char* name) {
  const Eigen::SparseMatrix<double> a = nonsymmetric(12);
  const Eigen::MatrixXd dense(a);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(12, -1.0, 2.0);
  Eigen::MatrixXd columns(12, 3);
  columns << b, b.reverse(), Eigen::VectorXd::Ones(12);
  Policy p;
  ASSERT_TRUE(p.factorize(a)) << name;
  const Eigen::PartialPivLU<Eigen::MatrixXd> reference(dense);
  EXPECT_LT((p.solve(b) - reference.solve(b)).norm(), 1e-14 * reference.solve(b).norm()) << name;
  const Eigen::VectorXd xt = dense.transpose().partialPivLu().solve(b);
  EXPECT_LT((p.solve_transposed(b) - xt).norm(), 1e-14 * xt.norm()) << name;
  EXPECT_LT((dense.transpose() * p.solve_transposed(b) - b).norm(), 1e-14 * b.norm()) << name;
  const Eigen::MatrixXd xc = p.solve_columns(columns, false), xct = p.solve_columns(columns, true);
  EXPECT_LT((dense * xc - columns).norm(), 1e-14 * columns.norm()) << name;
  EXPECT_LT((dense.transpose() * xct - columns).norm(), 1e-14 * columns.norm()) << name;
  Eigen::SparseMatrix<double> singular = a;
  for (Eigen::SparseMatrix<double>::InnerIterator it(singular, 4); it; ++it) it.valueRef() = 0.0;
  EXPECT_FALSE(p.factorize(singular)) << name;
  EXPECT_TRUE(p.solve(b).array().isNaN().all()) << name;
  Eigen::SparseMatrix<double> infinite = a;
  infinite.coeffRef(2, 2) = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(p.factorize(infinite)) << name;
}
}  // namespace

TEST(Newton, SparsePoliciesSolveWithTheMatrixAndItsTransposeAsADenseLu) {
  expect_sparse_policy_solves<SparseLu>("SparseLu (KLU)");
  expect_sparse_policy_solves<wbm::solvers::SupernodalLu>("SupernodalLu");
}

// From x₀ = 10 the full Newton step on arctan overshoots to −138 and, with no backtracking
// allowed, the line search fails: plain Newton stagnates, the Levenberg–Marquardt fallback
// (damped steps) reaches the root 0.
TEST(Newton, LevenbergMarquardtRescuesAStalledLineSearch) {
  const auto plain = newton(Arctan{}, Eigen::VectorXd::Constant(1, 10.0), {.max_backtracks = 0});
  EXPECT_EQ(plain.report.status, SolveStatus::Stagnated);
  const auto lm = newton(Arctan{}, Eigen::VectorXd::Constant(1, 10.0),
                         {.max_backtracks = 0, .levenberg_marquardt = true, .max_lm_trials = 40});
  ASSERT_TRUE(lm.report.converged()) << lm.report.message;
  EXPECT_NEAR(lm.x(0), 0.0, 1e-10);
  EXPECT_GT(lm.report.levenberg_marquardt_steps, 0);
}

// The fallback is taken only where the Newton step fails. On arctan the full Newton step
// decreases |x| exactly when |x| < 1.3917 (the root of 2x = (1 + x²) arctan x), and near the root
// it is x ↦ x − (1 + x²) arctan x = −(2/3) x³ + O(x⁵): cubic. From x₀ = 10 the iterates 10 and
// about 2 (‖R‖ = 1.47, 1.11) lie outside that basin, so exactly two damped steps are needed; after
// them every step must be Newton's, ‖R‖ₖ₊₁ ≤ ‖R‖ₖ³ (arctan x ≈ x). Damped steps kept to the end
// converge only linearly once μ stops shrinking: 9.8e-7 → 2.6e-12, not below 1e-18.
TEST(Newton, LevenbergMarquardtFallbackHandsBackToNewtonSteps) {
  const auto lm = newton(Arctan{}, Eigen::VectorXd::Constant(1, 10.0),
                         {.max_backtracks = 0, .levenberg_marquardt = true, .max_lm_trials = 40});
  ASSERT_TRUE(lm.report.converged()) << lm.report.message;
  const std::vector<double>& r = lm.report.residual_norms;
  const double basin = std::atan(1.3917);
  const auto outside = std::count_if(r.begin(), r.end(), [&](double v) { return v > basin; });
  EXPECT_EQ(lm.report.levenberg_marquardt_steps, outside);
  int newton_pairs = 0;
  for (size_t k = 0; k + 1 < r.size(); ++k) {
    if (r[k] >= basin) continue;
    EXPECT_LE(r[k + 1], r[k] * r[k] * r[k]) << "step " << k << ": " << r[k] << " -> " << r[k + 1];
    ++newton_pairs;
  }
  EXPECT_GE(newton_pairs, 3);
}

namespace {
// x³ − 2x + 2 = 0: from x0 = 0 Newton's iterates cycle exactly, 0 → 1 → 0 → … (the classic
// example of a Newton cycle; its one real root, −1.7693, is never reached), ‖R‖ = 2, 1, 2, 1, …
struct CyclingCubic {
  Eigen::VectorXd residual(const Eigen::VectorXd& x) const { return x.array().cube() - 2.0 * x.array() + 2.0; }
  Eigen::MatrixXd jacobian(const Eigen::VectorXd& x) const {
    return (3.0 * x.array().square() - 2.0).matrix().asDiagonal();
  }
};
// |x| + 1 = 0 has no root, and its semismooth Newton alternates between the two pieces:
// 1 → −1 → 1 (a continuation corrector whose hyperplane misses the branch beyond a corner).
struct Vee {
  Eigen::VectorXd residual(const Eigen::VectorXd& x) const { return x.array().abs() + 1.0; }
  Eigen::MatrixXd jacobian(const Eigen::VectorXd& x) const { return x.array().sign().matrix().asDiagonal(); }
};
}  // namespace

// stop_on_cycle ends a cycling Newton (smooth or semismooth) as Stagnated after 3 iterations,
// when the norms have repeated twice with period 2, instead of running to max_iterations; it
// does not stop a converging solve, even one whose active set changes (Switching).
TEST(Newton, StopOnCycleEndsACyclingNewtonAndNotAConvergingOne) {
  const NewtonOptions plain{.max_iterations = 30, .line_search = false};
  NewtonOptions cycle = plain;
  cycle.stop_on_cycle = true;
  const auto endless = newton(CyclingCubic{}, Eigen::VectorXd::Zero(1), plain);
  EXPECT_EQ(endless.report.status, SolveStatus::MaxIterations);
  EXPECT_EQ(endless.report.iterations, 30);
  EXPECT_NEAR(endless.x(0), 0.0, 1e-12);  // 30 iterations: back at 0
  const auto stopped = newton(CyclingCubic{}, Eigen::VectorXd::Zero(1), cycle);
  EXPECT_EQ(stopped.report.status, SolveStatus::Stagnated);
  EXPECT_EQ(stopped.report.iterations, 3);
  EXPECT_NE(stopped.report.message.find("period 2"), std::string::npos) << stopped.report.message;
  const std::vector<double> expected = {2.0, 1.0, 2.0, 1.0};
  ASSERT_EQ(stopped.report.residual_norms.size(), expected.size());
  for (size_t k = 0; k < expected.size(); ++k) EXPECT_NEAR(stopped.report.residual_norms[k], expected[k], 1e-12);
  const auto vee = newton(Vee{}, Eigen::VectorXd::Constant(1, 1.0), cycle);
  EXPECT_EQ(vee.report.status, SolveStatus::Stagnated);
  EXPECT_EQ(vee.report.iterations, 3);
  // Converging solves are not stopped: the same root as without the check.
  const auto cubic = newton(Cubic{}, Eigen::VectorXd::Constant(2, 3.0), cycle);
  ASSERT_TRUE(cubic.report.converged()) << cubic.report.message;
  EXPECT_NEAR(cubic.x(0), 2.0, 1e-10);
  const auto switching = newton(Switching{}, Eigen::Vector2d(-1.0, 1.0), cycle);
  ASSERT_TRUE(switching.report.converged()) << switching.report.message;
  EXPECT_NEAR(switching.x(0), 2.0, 1e-12);
  EXPECT_NEAR(switching.x(1), 0.0, 1e-12);
}

// The convergence test uses the norm asked for: for R = x³ − 8 on two components from (3, 2.5),
// ‖R‖∞ ≤ tol is reported, and the tolerance used is in the report.
TEST(Newton, MaxNormConvergenceTestAndTheToleranceUsedAreReported) {
  const auto r = newton(Cubic{}, Eigen::Vector2d(3.0, 2.5), {.tolerance = 1e-9, .norm = ResidualNorm::Max});
  ASSERT_TRUE(r.report.converged());
  EXPECT_EQ(r.report.tolerance, 1e-9);
  EXPECT_LE(Cubic{}.residual(r.x).lpNorm<Eigen::Infinity>(), 1e-9);
  EXPECT_DOUBLE_EQ(r.report.residual_norms.back(), Cubic{}.residual(r.x).lpNorm<Eigen::Infinity>());
  EXPECT_NE(r.report.brief().find("converged in"), std::string::npos);
}

// Messages print small numbers in scientific notation (a step h = 3e-8 used to print as
// "0.000000").
TEST(Newton, MessagesPrintSmallNumbersInScientificNotation) {
  EXPECT_EQ(format_number(3.2e-11), "3.2e-11");
  EXPECT_EQ(format_number(1297.52), "1298");
  EXPECT_EQ(format_number(0.0125), "0.0125");
  const auto r = newton(NoRoot{}, Eigen::VectorXd::Constant(1, 0.5), {.tolerance = 1e-12, .max_iterations = 3});
  EXPECT_NE(r.report.message.find("tolerance 1e-12"), std::string::npos) << r.report.message;
  EXPECT_EQ(r.report.message.find("0.000000"), std::string::npos) << r.report.message;
}

namespace {
// J = (I + U V)/s with random U (n × r), V (r × n), V applied as a dense product.
LowRankJacobian random_low_rank(Eigen::Index n, Eigen::Index r, double u_size, double scale, unsigned seed) {
  std::srand(seed);
  LowRankJacobian j;
  j.scale = scale;
  j.rows = n;
  j.u = u_size * Eigen::MatrixXd::Random(n, r);
  const Eigen::MatrixXd v = Eigen::MatrixXd::Random(r, n);
  j.times_v = [v](const Eigen::MatrixXd& y) { return Eigen::MatrixXd(v * y); };
  j.capacitance = v * j.u;
  j.capacitance.diagonal().array() += 1.0;
  return j;
}
}  // namespace

// Sherman–Morrison–Woodbury against a dense LU of (I + U V)/s formed here: rank 7 of 40, a
// stiff update (‖U V‖ ~ 1e8, the penalty limit: J's solution is found by cancellation in
// y − U C⁻¹ V y) whose backward error the refinement step brings to rounding, rank 0 (J = I/s)
// and the dense form (C = s J).
TEST(Newton, WoodburyLuSolvesIdentityPlusLowRank) {
  const Eigen::Index n = 40;
  const Eigen::VectorXd y = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0);
  for (const double u_size : {1.0, 1e8}) {
    const LowRankJacobian j = random_low_rank(n, 7, u_size, 0.25, 3);
    Eigen::MatrixXd dense = j.u * j.times_v(Eigen::MatrixXd::Identity(n, n));
    dense.diagonal().array() += 1.0;
    dense /= j.scale;
    EXPECT_LT((j.dense() - dense).norm(), 1e-15 * dense.norm());
    WoodburyLu solver;
    ASSERT_TRUE(solver.factorize(j));
    const Eigen::VectorXd d = solver.solve(y);
    const Eigen::VectorXd reference = dense.partialPivLu().solve(y);
    const double backward = (dense * d - y).norm() / (dense.norm() * d.norm());
    EXPECT_LT(backward, 1e-15) << "|U| ~ " << u_size;
    // Forward error: both solutions are within ε κ(J) of the exact one.
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(dense);
    const double kappa = svd.singularValues()(0) / svd.singularValues()(n - 1);
    EXPECT_LT((d - reference).norm(), 10.0 * std::numeric_limits<double>::epsilon() * kappa * reference.norm())
        << "|U| ~ " << u_size << ", kappa " << kappa;
    EXPECT_GT(*solver.rcond(), 0.0);
  }
  LowRankJacobian none;
  none.scale = 0.5;
  none.rows = n;
  none.u.resize(n, 0);
  none.capacitance.resize(0, 0);
  none.times_v = [](const Eigen::MatrixXd& x) { return Eigen::MatrixXd(0, x.cols()); };
  WoodburyLu solver;
  ASSERT_TRUE(solver.factorize(none));
  EXPECT_LT((solver.solve(y) - 0.5 * y).norm(), 1e-16);
  EXPECT_EQ(*solver.rcond(), 1.0);
  LowRankJacobian dense_form;
  dense_form.scale = 2.0;
  dense_form.capacitance = Eigen::MatrixXd::Identity(n, n) + Eigen::MatrixXd::Random(n, n);
  ASSERT_TRUE(solver.factorize(dense_form));
  EXPECT_LT((dense_form.capacitance / 2.0 * solver.solve(y) - y).norm(), 1e-13 * y.norm());
  LowRankJacobian broken = random_low_rank(n, 3, 1.0, 1.0, 5);
  broken.u(0, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(solver.factorize(broken));
}

namespace {
// R(x) = x + U V (x³) − y: the Jacobian (I + U V diag(3x²)) is identity plus rank r, as in the
// condensed contact problem (x the contact unknowns, V the samples, U the compliance).
struct LowRankCubic {
  Eigen::MatrixXd u, v;
  Eigen::VectorXd y;
  Eigen::VectorXd residual(const Eigen::VectorXd& x) const { return x + u * (v * x.array().cube().matrix()) - y; }
  LowRankJacobian jacobian(const Eigen::VectorXd& x) const {
    LowRankJacobian j;
    j.rows = u.rows();
    j.u = u;
    const Eigen::MatrixXd vd = v * (3.0 * x.array().square()).matrix().asDiagonal();
    j.times_v = [vd](const Eigen::MatrixXd& z) { return Eigen::MatrixXd(vd * z); };
    j.capacitance = vd * u;
    j.capacitance.diagonal().array() += 1.0;
    return j;
  }
};
}  // namespace

// newton() picks WoodburyLu for a LowRankJacobian and converges quadratically to the root that
// the same Newton with the dense Jacobian (DenseLu) finds.
TEST(Newton, WoodburyLuIsTheDefaultForLowRankJacobians) {
  static_assert(std::is_same_v<DefaultLinearSolver<LowRankCubic>, WoodburyLu>);
  std::srand(11);
  const LowRankCubic system{0.1 * Eigen::MatrixXd::Random(30, 4).cwiseAbs(), Eigen::MatrixXd::Random(4, 30).cwiseAbs(),
                            Eigen::VectorXd::LinSpaced(30, 0.5, 1.5)};
  struct Dense {
    const LowRankCubic* s;
    Eigen::VectorXd residual(const Eigen::VectorXd& x) const { return s->residual(x); }
    Eigen::MatrixXd jacobian(const Eigen::VectorXd& x) const { return s->jacobian(x).dense(); }
  };
  const auto low = newton(system, Eigen::VectorXd::Zero(30), {.tolerance = 1e-13});
  const auto dense = newton(Dense{&system}, Eigen::VectorXd::Zero(30), {.tolerance = 1e-13});
  ASSERT_TRUE(low.report.converged()) << low.report.message;
  ASSERT_TRUE(dense.report.converged()) << dense.report.message;
  EXPECT_LT(system.residual(low.x).norm(), 1e-13);
  EXPECT_LT((low.x - dense.x).norm(), 1e-12 * dense.x.norm());
  EXPECT_EQ(low.report.iterations, dense.report.iterations);
}

// The Levenberg–Marquardt step against its closed form by the SVD J = U Σ Vᵀ:
//   d = −Σᵢ σᵢ / (σᵢ² + μ²) (uᵢᵀ r) vᵢ.
// With σ = (1, 1e-4, 1e-7) and μ = 1e-9 the normal equations (JᵀJ + μ²I) d = −Jᵀr have condition
// number 1e14: solved by LDLᵀ (the previous code) the step is 1.9e-4 off, relative (measured);
// the QR of [J; μI] (condition 1e7) is 6e-11 off.
TEST(Newton, LevenbergMarquardtStepMatchesItsSvdClosedFormOnAnIllConditionedJacobian) {
  const Eigen::Matrix3d u = (Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()) *
                             Eigen::AngleAxisd(1.1, Eigen::Vector3d::UnitZ())).toRotationMatrix();
  const Eigen::Matrix3d v = Eigen::AngleAxisd(-0.4, Eigen::Vector3d(3, -1, 2).normalized()).toRotationMatrix();
  const Eigen::Vector3d sigma(1.0, 1e-4, 1e-7);
  const Eigen::MatrixXd j = u * sigma.asDiagonal() * v.transpose();
  const Eigen::Vector3d r(0.3, -1.2, 0.8);
  const double mu = 1e-9;
  Eigen::Vector3d expected = Eigen::Vector3d::Zero();
  for (int i = 0; i < 3; ++i) {
    expected -= sigma(i) / (sigma(i) * sigma(i) + mu * mu) * u.col(i).dot(r) * v.col(i);
  }
  const Eigen::VectorXd d = detail::levenberg_marquardt_step(j, r, mu);
  EXPECT_LT((d - expected).norm(), 1e-6 * expected.norm()) << d.transpose() << " vs " << expected.transpose();
  // μ → large: the step tends to gradient descent, −Jᵀr / μ².
  const double big = 1e6;
  const Eigen::VectorXd steepest = detail::levenberg_marquardt_step(j, r, big);
  EXPECT_LT((steepest + j.transpose() * r / (big * big)).norm(), 1e-10 * (j.transpose() * r).norm() / (big * big));
}
