// SparseLu (newton.hpp): KLU through Eigen's wrapper, with the symbolic analysis kept while the
// sparsity pattern is unchanged; solves with J and Jᵀ (klu_solve, klu_tsolve) on its factors.
// SupernodalLu: Eigen's SparseLU (COLAMD), for matrices whose factors fill in densely.
#include <wbm/solvers/newton.hpp>

#include <algorithm>
#include <limits>
#include <optional>
#include <vector>

#include <Eigen/KLUSupport>
#include <Eigen/SparseLU>

namespace wbm::solvers {

namespace detail {

// Eigen's KLU wrapper solves with J only; its KLU objects are protected members, which klu_tsolve
// needs for Jᵀ. B is overwritten by the solution, column by column (KLU's own convention). In a
// named namespace, not an anonymous one: it is a member of SparseLu::Impl, and in a unity build
// (CMakeLists.txt) g++ would warn that Impl's field has a type of internal linkage.
class KluWithTranspose : public Eigen::KLU<Eigen::SparseMatrix<double>> {
 public:
  [[nodiscard]] bool solve_in_place(Eigen::MatrixXd& b, bool transposed) const {
    auto* common = const_cast<klu_common*>(&m_common);  // KLU's API is not const-correct
    const int n = static_cast<int>(b.rows()), columns = static_cast<int>(b.cols());
    const int ok = transposed ? klu_tsolve(m_symbolic, m_numeric, n, columns, b.data(), common)
                              : klu_solve(m_symbolic, m_numeric, n, columns, b.data(), common);
    return ok != 0;
  }
};

// The sparsity pattern of the last symbolic analysis (ordering, blocks, elimination tree: they
// depend on the pattern only), so that a matrix with the same stored pattern, explicit zeros
// included, is factorized on it again: every Newton iteration of an unchanged active set, every
// step of a continuation that passes the same object.
struct AnalysedPattern {
  std::vector<int> outer, inner;
  Eigen::Index rows = 0;
  int analyses = 0;
  [[nodiscard]] bool same(const Eigen::SparseMatrix<double>& j) const {
    if (analyses == 0 || j.rows() != rows || j.nonZeros() != static_cast<Eigen::Index>(inner.size())) return false;
    return std::equal(outer.begin(), outer.end(), j.outerIndexPtr()) &&
           std::equal(inner.begin(), inner.end(), j.innerIndexPtr());
  }
  void record(const Eigen::SparseMatrix<double>& j) {
    outer.assign(j.outerIndexPtr(), j.outerIndexPtr() + j.outerSize() + 1);
    inner.assign(j.innerIndexPtr(), j.innerIndexPtr() + j.nonZeros());
    rows = j.rows();
    ++analyses;
  }
};

}  // namespace detail

namespace {

// A compressed copy of m if it is square, not empty and finite (what both policies factorize);
// nullopt otherwise, which factorize() reports as false.
std::optional<Eigen::SparseMatrix<double>> factorizable(const Eigen::SparseMatrix<double>& m) {
  Eigen::SparseMatrix<double> a = m;
  a.makeCompressed();
  if (a.rows() != a.cols() || a.rows() == 0) return std::nullopt;
  if (!Eigen::Map<const Eigen::VectorXd>(a.valuePtr(), a.nonZeros()).allFinite()) return std::nullopt;
  return a;
}

}  // namespace

struct SparseLu::Impl {
  detail::KluWithTranspose lu;
  detail::AnalysedPattern pattern;
  bool factorized = false;
};

SparseLu::SparseLu() : impl_(std::make_unique<Impl>()) {}
SparseLu::~SparseLu() = default;
SparseLu::SparseLu(SparseLu&&) noexcept = default;
SparseLu& SparseLu::operator=(SparseLu&&) noexcept = default;

bool SparseLu::factorize(const Eigen::SparseMatrix<double>& jacobian) {
  Impl& p = *impl_;
  p.factorized = false;
  const auto prepared = factorizable(jacobian);
  if (!prepared) return false;
  const Eigen::SparseMatrix<double>& j = *prepared;
  if (!p.pattern.same(j)) {
    p.lu.analyzePattern(j);
    if (p.lu.info() != Eigen::Success) return false;
    p.pattern.record(j);
  }
  p.lu.factorize(j);
  p.factorized = p.lu.info() == Eigen::Success;
  return p.factorized;
}

Eigen::MatrixXd SparseLu::solve_columns(const Eigen::MatrixXd& rhs, bool transposed) const {
  Eigen::MatrixXd x = rhs;
  if (!impl_->factorized || rhs.rows() != impl_->pattern.rows || rhs.cols() == 0 ||
      !impl_->lu.solve_in_place(x, transposed)) {
    x.setConstant(std::numeric_limits<double>::quiet_NaN());
  }
  return x;
}

Eigen::VectorXd SparseLu::solve(const Eigen::VectorXd& rhs) const { return solve_columns(rhs, false); }

Eigen::VectorXd SparseLu::solve_transposed(const Eigen::VectorXd& rhs) const { return solve_columns(rhs, true); }

int SparseLu::symbolic_analyses() const { return impl_->pattern.analyses; }

struct SupernodalLu::Impl {
  // SparseLU::transpose() is not const in Eigen 3.4 (it only stores a pointer to the factors).
  mutable Eigen::SparseLU<Eigen::SparseMatrix<double>, Eigen::COLAMDOrdering<int>> lu;
  detail::AnalysedPattern pattern;  // COLAMD's column ordering and the elimination tree
  bool factorized = false;
};

SupernodalLu::SupernodalLu() : impl_(std::make_unique<Impl>()) {}
SupernodalLu::~SupernodalLu() = default;
SupernodalLu::SupernodalLu(SupernodalLu&&) noexcept = default;
SupernodalLu& SupernodalLu::operator=(SupernodalLu&&) noexcept = default;

bool SupernodalLu::factorize(const Eigen::SparseMatrix<double>& matrix) {
  Impl& p = *impl_;
  p.factorized = false;
  const auto prepared = factorizable(matrix);
  if (!prepared) return false;
  const Eigen::SparseMatrix<double>& a = *prepared;
  if (!p.pattern.same(a)) {
    p.lu.analyzePattern(a);
    p.pattern.record(a);
  }
  p.lu.factorize(a);
  p.factorized = p.lu.info() == Eigen::Success;
  return p.factorized;
}

Eigen::MatrixXd SupernodalLu::solve_columns(const Eigen::MatrixXd& rhs, bool transposed) const {
  const Impl& p = *impl_;
  if (!p.factorized || rhs.rows() != p.pattern.rows) {
    return Eigen::MatrixXd::Constant(rhs.rows(), rhs.cols(), std::numeric_limits<double>::quiet_NaN());
  }
  return transposed ? Eigen::MatrixXd(p.lu.transpose().solve(rhs)) : Eigen::MatrixXd(p.lu.solve(rhs));
}

Eigen::VectorXd SupernodalLu::solve(const Eigen::VectorXd& rhs) const { return solve_columns(rhs, false); }

Eigen::VectorXd SupernodalLu::solve_transposed(const Eigen::VectorXd& rhs) const { return solve_columns(rhs, true); }

int SupernodalLu::symbolic_analyses() const { return impl_->pattern.analyses; }

}  // namespace wbm::solvers
