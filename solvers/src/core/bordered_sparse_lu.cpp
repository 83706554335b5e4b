// BorderedSparseLu (newton.hpp): a symmetric sparse-plus-low-rank Jacobian H = S + U C Uᵀ solved
// through the bordered sparse system whose Schur complement is H, verified on H's residual, with
// a dense LU as the fallback; and its Levenberg–Marquardt step through the shifted system
// H − iμI in real form.
#include <wbm/solvers/newton.hpp>

#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/LU>

#include "core/one_norm_estimate.hpp"

namespace wbm::solvers {

Eigen::VectorXd SparseLowRankHessian::apply(const Eigen::VectorXd& y) const {
  Eigen::VectorXd out = sparse * y;
  if (u.cols() > 0) out.noalias() += u * (core * (u.transpose() * y));
  return out;
}

Eigen::MatrixXd SparseLowRankHessian::dense() const {
  Eigen::MatrixXd out(sparse);
  if (u.cols() > 0) out.noalias() += u * core * u.transpose();
  return out;
}

namespace {

constexpr double kMaxBackwardError = 1e-11;  // normwise, of a refined solve before the dense fallback

bool well_formed(const SparseLowRankHessian& h) {
  const Eigen::Index n = h.sparse.rows(), p = h.core.rows();
  return h.sparse.cols() == n && h.core.cols() == p && h.u.rows() == (p > 0 ? n : h.u.rows()) && h.u.cols() == p;
}

bool all_finite(const SparseLowRankHessian& h) {
  for (Eigen::Index j = 0; j < h.sparse.outerSize(); ++j) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(h.sparse, j); it; ++it) {
      if (!std::isfinite(it.value())) return false;
    }
  }
  return h.u.allFinite() && h.core.allFinite();
}

// ‖H‖∞ = ‖H‖₁ (H symmetric) without forming H: column i is S(:, i) + U (C U(i, :)ᵀ). O(n² p).
double infinity_norm(const SparseLowRankHessian& h) {
  const Eigen::Index n = h.sparse.rows();
  const Eigen::MatrixXd uc = h.u.cols() > 0 ? Eigen::MatrixXd(h.u * h.core) : Eigen::MatrixXd::Zero(n, 0);
  Eigen::VectorXd column(n);
  double norm = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (uc.cols() > 0) {
      column.noalias() = h.u * uc.row(i).transpose();
    } else {
      column.setZero();
    }
    for (Eigen::SparseMatrix<double>::InnerIterator it(h.sparse, i); it; ++it) column(it.row()) += it.value();
    norm = std::max(norm, column.lpNorm<1>());
  }
  return norm;
}

// The border of H's bordered system: its columns U C D and rows D⁻¹ Uᵀ, D = diag(‖U(:, q)‖∞)
// (rows of unit size beside the −I block; a zero column keeps d = 1).
void border(const SparseLowRankHessian& h, Eigen::MatrixXd& columns, Eigen::MatrixXd& rows) {
  const Eigen::Index p = h.core.rows();
  Eigen::VectorXd d(p);
  for (Eigen::Index q = 0; q < p; ++q) {
    const double uq = h.u.col(q).lpNorm<Eigen::Infinity>();
    d(q) = uq > 0.0 ? uq : 1.0;
  }
  columns = h.u * h.core * d.asDiagonal();
  rows = d.cwiseInverse().asDiagonal() * h.u.transpose();
}

// copies = 1: [[S, U C D], [D⁻¹ Uᵀ, −I]] (z = D⁻¹ Uᵀ x, so that S x + U C D z = H x).
// copies = 2, the real form of H − iμI:
// [[S, μI, U C D, 0], [−μI, S, 0, U C D], [D⁻¹ Uᵀ, 0, −I, 0], [0, D⁻¹ Uᵀ, 0, −I]].
// Unknowns: the copies' n first, then their p border unknowns.
Eigen::SparseMatrix<double> bordered(const SparseLowRankHessian& h, const Eigen::MatrixXd& columns,
                                     const Eigen::MatrixXd& rows, int copies, double mu) {
  const Eigen::Index n = h.sparse.rows(), p = columns.cols(), size = copies * (n + p);
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<size_t>(copies) * static_cast<size_t>(h.sparse.nonZeros() + 2 * n * p + p + n));
  for (int c = 0; c < copies; ++c) {
    const Eigen::Index x0 = c * n, z0 = copies * n + c * p;
    for (Eigen::Index j = 0; j < h.sparse.outerSize(); ++j) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(h.sparse, j); it; ++it) {
        t.emplace_back(x0 + it.row(), x0 + it.col(), it.value());
      }
    }
    for (Eigen::Index q = 0; q < p; ++q) {
      for (Eigen::Index i = 0; i < n; ++i) {  // explicit zeros kept: the pattern, and KLU's analysis, stay
        t.emplace_back(x0 + i, z0 + q, columns(i, q));
        t.emplace_back(z0 + q, x0 + i, rows(q, i));
      }
      t.emplace_back(z0 + q, z0 + q, -1.0);
    }
  }
  if (copies == 2) {
    for (Eigen::Index i = 0; i < n; ++i) {
      t.emplace_back(i, n + i, mu);
      t.emplace_back(n + i, i, -mu);
    }
  }
  Eigen::SparseMatrix<double> b(size, size);
  b.setFromTriplets(t.begin(), t.end());
  return b;
}

}  // namespace

struct BorderedSparseLu::Impl {
  SparseLowRankHessian h;
  Eigen::MatrixXd columns, rows;  // the border
  SparseLu lu, shifted;
  bool ok = false;
  double norm_inf = 0.0;
  mutable std::optional<Eigen::PartialPivLU<Eigen::MatrixXd>> dense;  // the fallback, formed on first need
  mutable std::optional<double> rcond;
  mutable int fallbacks = 0;

  [[nodiscard]] Eigen::VectorXd bordered_solve(const Eigen::VectorXd& b) const {
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(h.size() + columns.cols());
    rhs.head(h.size()) = b;
    return lu.solve(rhs).head(h.size());
  }
};

BorderedSparseLu::BorderedSparseLu() : impl_(std::make_unique<Impl>()) {}
BorderedSparseLu::~BorderedSparseLu() = default;
BorderedSparseLu::BorderedSparseLu(BorderedSparseLu&&) noexcept = default;
BorderedSparseLu& BorderedSparseLu::operator=(BorderedSparseLu&&) noexcept = default;

bool BorderedSparseLu::factorize(const SparseLowRankHessian& hessian) {
  Impl& m = *impl_;
  m.ok = false;
  m.dense.reset();
  m.rcond.reset();
  if (!well_formed(hessian) || !all_finite(hessian)) return false;
  m.h = hessian;
  m.h.sparse.makeCompressed();
  border(m.h, m.columns, m.rows);
  m.norm_inf = infinity_norm(m.h);
  m.ok = m.lu.factorize(bordered(m.h, m.columns, m.rows, 1, 0.0));
  return m.ok;
}

Eigen::VectorXd BorderedSparseLu::solve(const Eigen::VectorXd& rhs) const {
  const Impl& m = *impl_;
  if (!m.ok || rhs.size() != m.h.size()) {
    return Eigen::VectorXd::Constant(rhs.size(), std::numeric_limits<double>::quiet_NaN());
  }
  Eigen::VectorXd x = m.bordered_solve(rhs);
  x += m.bordered_solve(rhs - m.h.apply(x));  // one step of iterative refinement
  const double scale = m.norm_inf * x.lpNorm<Eigen::Infinity>() + rhs.lpNorm<Eigen::Infinity>();
  const double error = (rhs - m.h.apply(x)).lpNorm<Eigen::Infinity>();
  if (x.allFinite() && error <= kMaxBackwardError * scale) return x;
  if (!m.dense) m.dense.emplace(m.h.dense());
  ++m.fallbacks;
  return m.dense->solve(rhs);
}

std::optional<double> BorderedSparseLu::rcond() const {
  const Impl& m = *impl_;
  if (!m.ok) return 0.0;
  if (!m.rcond) {
    const double inverse = detail::inverse_one_norm_estimate(
        m.h.size(), [&](const Eigen::VectorXd& v, bool) { return solve(v); });  // H symmetric: H⁻ᵀ = H⁻¹
    m.rcond = inverse > 0.0 && m.norm_inf > 0.0 ? 1.0 / (m.norm_inf * inverse) : 0.0;
  }
  return m.rcond;
}

double BorderedSparseLu::jacobian_infinity_norm(const SparseLowRankHessian& hessian) const {
  return well_formed(hessian) ? infinity_norm(hessian) : std::numeric_limits<double>::quiet_NaN();
}

Eigen::VectorXd BorderedSparseLu::levenberg_marquardt_step(const SparseLowRankHessian& hessian,
                                                           const Eigen::VectorXd& r, double mu) {
  const Eigen::Index n = hessian.size();
  Eigen::VectorXd nan = Eigen::VectorXd::Constant(n, std::numeric_limits<double>::quiet_NaN());
  if (!(mu > 0.0) || r.size() != n || !well_formed(hessian)) return nan;
  Eigen::MatrixXd columns, rows;
  border(hessian, columns, rows);
  Impl& m = *impl_;
  if (!m.shifted.factorize(bordered(hessian, columns, rows, 2, mu))) return nan;
  const Eigen::Index p = columns.cols();
  // (H − iμI)(x + iy) = r: H x + μ y = r, H y − μ x = 0; then d = −x.
  auto solve2 = [&](const Eigen::VectorXd& e1, const Eigen::VectorXd& e2) {
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(2 * (n + p));
    rhs.head(n) = e1;
    rhs.segment(n, n) = e2;
    return Eigen::VectorXd(m.shifted.solve(rhs).head(2 * n));
  };
  Eigen::VectorXd xy = solve2(r, Eigen::VectorXd::Zero(n));
  const Eigen::VectorXd hx = hessian.apply(xy.head(n)), hy = hessian.apply(xy.tail(n));
  xy += solve2(r - hx - mu * xy.tail(n), mu * xy.head(n) - hy);  // one step of iterative refinement
  return -xy.head(n);
}

int BorderedSparseLu::fallback_solves() const { return impl_->fallbacks; }

}  // namespace wbm::solvers
