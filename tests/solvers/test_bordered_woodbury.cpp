// The bordered Woodbury of the continuation corrector (bordered_low_rank, newton.hpp; issue #39):
// the bordered matrix it represents against the matrix formed entry by entry, its solves against
// a dense LU of that matrix (at a fold too, where J is singular and the bordered matrix is not),
// and forced-response branches through it against the same branches through dense linearizations
// (the path every branch took before). The sparse bordered matrix, written in compressed form,
// against the dense one and against setFromTriplets.
#include <wbm/solvers/newton.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <vector>

#include <Eigen/LU>
#include <gtest/gtest.h>

#include <wbm/contact/penalty.hpp>
#include <wbm/contact/signorini.hpp>
#include <wbm/solvers/detail/continuation_corrector.hpp>
#include <wbm/solvers/response_curve.hpp>
#include <wbm/spectral/layout.hpp>

#include "shipped_scenes.hpp"
#include "testing.hpp"

using namespace wbm;
using solvers::ActiveSet;
using solvers::LowRankJacobian;
using solvers::TimeBasis;

namespace {

// J = (I + U V)/s with V given by its product, n = 9, r = 3; U as a matrix or (with_product) by
// its product only.
LowRankJacobian random_low_rank(bool with_product, unsigned seed) {
  std::srand(seed);
  const Eigen::Index n = 9, r = 3;
  LowRankJacobian j;
  j.scale = 0.37;
  j.rows = n;
  const Eigen::MatrixXd u = Eigen::MatrixXd::Random(n, r);
  const auto v = std::make_shared<const Eigen::MatrixXd>(Eigen::MatrixXd::Random(r, n));
  j.times_v = [v](const Eigen::MatrixXd& y) { return Eigen::MatrixXd(*v * y); };
  if (with_product) {
    j.times_u = [u](const Eigen::MatrixXd& z) { return Eigen::MatrixXd(u * z); };
  } else {
    j.u = u;
  }
  j.capacitance = Eigen::MatrixXd::Identity(r, r) + *v * u;
  return j;
}

// [[α J, b], [cᵀ, d]] entry by entry.
Eigen::MatrixXd formed(const LowRankJacobian& j, double alpha, const Eigen::VectorXd& b, const Eigen::VectorXd& c,
                       double d) {
  const Eigen::Index n = j.size();
  Eigen::MatrixXd m(n + 1, n + 1);
  m.topLeftCorner(n, n) = alpha * j.dense();
  m.topRightCorner(n, 1) = b;
  m.bottomLeftCorner(1, n) = c.transpose();
  m(n, n) = d;
  return m;
}

// A family through dense linearizations: the path of every branch before the bordered Woodbury.
template <class F>
struct Dense {
  const F* f;
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double p) const { return f->residual(x, p); }
  [[nodiscard]] solvers::Linearization linearize(const Eigen::VectorXd& x, double p) const {
    const auto l = f->linearize(x, p);
    return {l.residual, l.jacobian.dense(), l.parameter_derivative};
  }
};
struct DensePieces : Dense<solvers::SignoriniResponseFamily> {
  using Dense::linearize;
  using Dense::residual;
  [[nodiscard]] ActiveSet active_set(const Eigen::VectorXd& x, double p) const { return f->active_set(x, p); }
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double p, const ActiveSet& a) const {
    return f->residual(x, p, a);
  }
  [[nodiscard]] solvers::Linearization linearize(const Eigen::VectorXd& x, double p, const ActiveSet& a) const {
    const auto l = f->linearize(x, p, a);
    return {l.residual, l.jacobian.dense(), l.parameter_derivative};
  }
  [[nodiscard]] Eigen::VectorXd events(const Eigen::VectorXd& x, double p, const ActiveSet& a) const {
    return f->events(x, p, a);
  }
};

// The largest difference of two branches' points once their point counts agree (infinite
// otherwise): of the parameter relative to it, and of the state relative to the largest state
// along the branch (where the stop is left the impulses fall to zero).
double branch_difference(const solvers::Branch& a, const solvers::Branch& b) {
  if (a.points.size() != b.points.size()) return INFINITY;
  double scale = 0.0;
  for (const auto& q : b.points) scale = std::max(scale, q.x.norm());
  double worst = 0.0;
  for (size_t i = 0; i < a.points.size(); ++i) {
    const auto& p = a.points[i];
    const auto& q = b.points[i];
    worst = std::max(worst, std::abs(p.parameter - q.parameter) / std::abs(q.parameter));
    worst = std::max(worst, (p.x - q.x).norm() / scale);
  }
  return worst;
}

}  // namespace

// The represented matrix is the bordered matrix, with U as a matrix or as a product only, and in
// the dense form; WoodburyLu solves it as a dense LU does.
TEST(BorderedWoodbury, RepresentsTheBorderedMatrixAndSolvesItAsADenseLu) {
  for (bool with_product : {false, true}) {
    const LowRankJacobian j = random_low_rank(with_product, 7);
    const Eigen::VectorXd b = Eigen::VectorXd::Random(9), c = Eigen::VectorXd::Random(9), rhs = Eigen::VectorXd::Random(10);
    const double alpha = 2.5, d = -0.8;
    const LowRankJacobian bj = solvers::bordered_low_rank(j, alpha, b, c, d);
    const Eigen::MatrixXd reference = formed(j, alpha, b, c, d);
    EXPECT_EQ(bj.rank(), j.rank() + 2);
    EXPECT_LE((bj.dense() - reference).norm(), 1e-13 * reference.norm());
    solvers::WoodburyLu woodbury;
    ASSERT_TRUE(woodbury.factorize(bj));
    const Eigen::VectorXd x = woodbury.solve(rhs), expected = reference.partialPivLu().solve(rhs);
    EXPECT_LE((x - expected).norm(), 1e-12 * expected.norm()) << with_product;
  }
  // Dense form: the same matrix, formed as the dense corrector forms it.
  LowRankJacobian dense;
  dense.scale = 0.37;
  dense.capacitance = Eigen::MatrixXd::Random(5, 5) + 3.0 * Eigen::MatrixXd::Identity(5, 5);
  const Eigen::VectorXd b = Eigen::VectorXd::Random(5), c = Eigen::VectorXd::Random(5);
  const LowRankJacobian bd = solvers::bordered_low_rank(dense, 1.7, b, c, 0.3);
  ASSERT_TRUE(bd.dense_form());
  EXPECT_EQ(bd.dense(), formed(dense, 1.7, b, c, 0.3));
}

// At a fold J is singular and the bordered matrix is not: J = I − w wᵀ (w a unit vector, the
// null direction), bordered by a column outside J's range and the null direction as its row. The
// capacitance is regular there (det B = aⁿ⁺¹ det(I + V̂ Û)), and the solve matches a dense LU.
TEST(BorderedWoodbury, SolvesAtAFoldWhereTheJacobianIsSingular) {
  const Eigen::Index n = 12;
  const Eigen::VectorXd w = Eigen::VectorXd::LinSpaced(n, 1.0, 2.0).normalized();
  LowRankJacobian j;
  j.rows = n;
  j.u = -w;
  j.times_v = [w](const Eigen::MatrixXd& y) { return Eigen::MatrixXd(w.transpose() * y); };
  j.capacitance = Eigen::MatrixXd::Constant(1, 1, 1.0 - w.squaredNorm());  // 0: J singular
  const Eigen::VectorXd b = w, c = w, rhs = Eigen::VectorXd::LinSpaced(n + 1, -1.0, 1.0);
  const LowRankJacobian bj = solvers::bordered_low_rank(j, 1.0, b, c, 0.0);
  const Eigen::MatrixXd reference = formed(j, 1.0, b, c, 0.0);
  ASSERT_GT(std::abs(reference.determinant()), 0.5);
  solvers::WoodburyLu woodbury;
  ASSERT_TRUE(woodbury.factorize(bj));
  EXPECT_GT(*woodbury.rcond(), 1e-3);
  const Eigen::VectorXd expected = reference.partialPivLu().solve(rhs);
  EXPECT_LE((woodbury.solve(rhs) - expected).norm(), 1e-13 * expected.norm());
}

TEST(BorderedWoodbury, RefusesABadFactorOrBorder) {
  const LowRankJacobian j = random_low_rank(false, 3);
  const Eigen::VectorXd b = Eigen::VectorXd::Zero(9), short_c = Eigen::VectorXd::Zero(8);
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)solvers::bordered_low_rank(j, 0.0, b, b, 1.0); },
                                                         {"alpha = 0", "> 0"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::bordered_low_rank(j, 1.0, b, short_c, 1.0); }, {"8 columns", "size 9"});
}

// A forced-response branch through the bordered Woodbury is the branch of the dense path: Case 2
// of [JL14 Table 1] (clamped rod, 1000–1700 Hz over its first resonance) with a linear penalty
// stop (the samples in contact carry the rank) and with a rigid stop (continued piece by piece),
// Fourier:Fourier and B-spline:B-spline at M = 32: the same points, and the low-rank form used at
// some of them. Points agree to rounding on a smooth piece; a switching point is located to the
// event tolerance (a quarter of the corrector's, on the scaled event function), so both paths
// place it within that and not closer (measured: 2e-10 in f and 3e-8 in the state, relative).
TEST(BorderedWoodbury, ForcedResponseBranchesEqualTheDensePath) {
  const scene::Scene scene = models::load_scene("jl14_case2");
  const auto system = scene.system();
  auto forcing = scene.harmonic_forcing();
  forcing.frequency_hz = 1000.0;
  const int tip = scene.contact_points().front().dof;
  const double gap = scene.contact_points().front().law->gap();
  const std::vector<solvers::ContactPoint> penalty{
      {tip, std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{1e8, gap})}};
  const std::vector<solvers::ContactPoint> rigid{{tip, std::make_shared<contact::RigidStop>(gap)}};
  solvers::PseudoArclengthOptions o;
  o.parameter_min = 1000.0;
  o.parameter_max = 1700.0;
  o.parameter_scale = 1000.0;
  o.max_parameter_step = 10.0;
  o.max_points = 2000;
  for (const char* name : {"fourier", "bspline"}) {
    for (bool is_rigid : {false, true}) {
      const solvers::WeightedResidual base(system, forcing, is_rigid ? rigid : penalty, TimeBasis::from_name(name, 32),
                                           TimeBasis::from_name(name, 32));
      const auto start = base.solve();
      ASSERT_TRUE(start.converged()) << name;
      const solvers::ForcedResponseFamily family(base, solvers::ContinuationParameter::Frequency);
      o.state_scale = is_rigid ? base.residual_scale() / base.force_compliance() : base.residual_scale();
      solvers::Branch low_rank, dense;
      if (is_rigid) {
        const solvers::SignoriniResponseFamily pieces(family);
        const Eigen::VectorXd x0 = spectral::stacked(start.contact_force_samples);
        low_rank = solvers::pseudo_arclength(pieces, x0, 1000.0, o);
        dense = solvers::pseudo_arclength(DensePieces{{&pieces}}, x0, 1000.0, o);
      } else {
        const Eigen::VectorXd x0 = base.contact_unknowns(spectral::stacked(start.coefficients));
        low_rank = solvers::pseudo_arclength(family, x0, 1000.0, o);
        dense = solvers::pseudo_arclength(Dense<solvers::ForcedResponseFamily>{&family}, x0, 1000.0, o);
      }
      const std::string what = std::string(name) + (is_rigid ? ", rigid" : ", penalty");
      ASSERT_EQ(dense.stop, solvers::StopReason::RangeReached) << what << ": " << dense.message;
      ASSERT_EQ(low_rank.stop, solvers::StopReason::RangeReached) << what << ": " << low_rank.message;
      EXPECT_EQ(low_rank.folds.size(), dense.folds.size()) << what;
      EXPECT_EQ(low_rank.events, dense.events) << what;
      EXPECT_LE(branch_difference(low_rank, dense), 1e-7) << what;
      int low_rank_points = 0;
      for (const auto& p : low_rank.points) low_rank_points += family.linearize(p.x, p.parameter).jacobian.dense_form() ? 0 : 1;
      EXPECT_GT(low_rank_points, 0) << what;
    }
  }
}

// The sparse bordered matrix [[J xs, ∂R/∂λ ls]; [t_xᵀ/n, t_λ]] of the continuation corrector,
// written column by column (continuation_corrector.hpp): entry for entry the dense bordered
// matrix of the same J, and equal, pattern included, to setFromTriplets of J's entries and the
// border's. J has an empty column and an explicit zero (kept: the pattern must not depend on
// values, for the reuse of the symbolic analysis).
TEST(BorderedSparse, EqualsTheDenseBorderedMatrixAndSetFromTriplets) {
  const int n = 6;
  std::vector<Eigen::Triplet<double>> entries{{0, 0, 2.0}, {3, 0, -1.5}, {5, 0, 0.25}, {1, 1, 4.0}, {2, 1, 0.0},
                                              {4, 3, 1.0}, {0, 3, 3.0},  {5, 4, -2.0}, {2, 5, 7.0}, {5, 5, 1.0}};
  solvers::SparseLinearization sl;
  sl.jacobian.resize(n, n);
  sl.jacobian.setFromTriplets(entries.begin(), entries.end());  // column 2 empty
  sl.residual = Eigen::VectorXd::Zero(n);
  sl.parameter_derivative = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0);
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(n + 1, 0.3, -0.9);
  const double xs = 1.7, ls = 0.45;
  const Eigen::SparseMatrix<double> b = solvers::detail::bordered(sl, t, xs, ls);

  solvers::Linearization dl;
  dl.jacobian = Eigen::MatrixXd(sl.jacobian);
  dl.residual = sl.residual;
  dl.parameter_derivative = sl.parameter_derivative;
  EXPECT_EQ(Eigen::MatrixXd(b), solvers::detail::bordered(dl, t, xs, ls));

  std::vector<Eigen::Triplet<double>> all;
  for (const auto& e : entries) all.emplace_back(e.row(), e.col(), e.value() * xs);
  for (int i = 0; i < n; ++i) {
    all.emplace_back(i, n, sl.parameter_derivative(i) * ls);
    all.emplace_back(n, i, t(i) / n);
  }
  all.emplace_back(n, n, t(n));
  Eigen::SparseMatrix<double> reference(n + 1, n + 1);
  reference.setFromTriplets(all.begin(), all.end());
  ASSERT_TRUE(b.isCompressed());
  ASSERT_EQ(b.nonZeros(), reference.nonZeros());
  for (int c = 0; c <= n + 1; ++c) EXPECT_EQ(b.outerIndexPtr()[c], reference.outerIndexPtr()[c]) << "column " << c;
  for (Eigen::Index k = 0; k < b.nonZeros(); ++k) {
    EXPECT_EQ(b.innerIndexPtr()[k], reference.innerIndexPtr()[k]) << "entry " << k;
    EXPECT_EQ(b.valuePtr()[k], reference.valuePtr()[k]) << "entry " << k;
  }
}
