// SparseLu (newton.hpp): KLU through Eigen's wrapper, with the symbolic analysis kept while the
// sparsity pattern is unchanged.
#include <wbm/solvers/newton.hpp>

#include <algorithm>
#include <limits>
#include <vector>

#include <Eigen/KLUSupport>

namespace wbm::solvers {

struct SparseLu::Impl {
  Eigen::KLU<Eigen::SparseMatrix<double>> lu;
  std::vector<int> outer, inner;  // the analysed pattern
  Eigen::Index rows = 0;
  int analyses = 0;
  bool factorized = false;

  [[nodiscard]] bool same_pattern(const Eigen::SparseMatrix<double>& j) const {
    if (analyses == 0 || j.rows() != rows || j.nonZeros() != static_cast<Eigen::Index>(inner.size())) return false;
    return std::equal(outer.begin(), outer.end(), j.outerIndexPtr()) &&
           std::equal(inner.begin(), inner.end(), j.innerIndexPtr());
  }
};

SparseLu::SparseLu() : impl_(std::make_unique<Impl>()) {}
SparseLu::~SparseLu() = default;
SparseLu::SparseLu(SparseLu&&) noexcept = default;
SparseLu& SparseLu::operator=(SparseLu&&) noexcept = default;

bool SparseLu::factorize(const Eigen::SparseMatrix<double>& jacobian) {
  Impl& p = *impl_;
  p.factorized = false;
  Eigen::SparseMatrix<double> j = jacobian;
  j.makeCompressed();
  if (j.rows() != j.cols() || j.rows() == 0) return false;
  if (!Eigen::Map<const Eigen::VectorXd>(j.valuePtr(), j.nonZeros()).allFinite()) return false;
  if (!p.same_pattern(j)) {
    p.lu.analyzePattern(j);
    if (p.lu.info() != Eigen::Success) return false;
    p.outer.assign(j.outerIndexPtr(), j.outerIndexPtr() + j.outerSize() + 1);
    p.inner.assign(j.innerIndexPtr(), j.innerIndexPtr() + j.nonZeros());
    p.rows = j.rows();
    ++p.analyses;
  }
  p.lu.factorize(j);
  p.factorized = p.lu.info() == Eigen::Success;
  return p.factorized;
}

Eigen::VectorXd SparseLu::solve(const Eigen::VectorXd& rhs) const {
  if (!impl_->factorized) return Eigen::VectorXd::Constant(rhs.size(), std::numeric_limits<double>::quiet_NaN());
  return impl_->lu.solve(rhs);
}

int SparseLu::symbolic_analyses() const { return impl_->analyses; }

}  // namespace wbm::solvers
