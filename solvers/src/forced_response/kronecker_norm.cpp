// KroneckerFactorization's ‖G‖₁ (kronecker_factorization.hpp), from the Kronecker factors without
// forming G.
#include "kronecker_factorization.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace wbm::solvers::detail {

// From the Kronecker factors t = (f² A_M, f A_C, A_K) and x = (M, C, K), G not formed:
// the column (j, k) of G sums |Σ_s x_s(i, j) t_s(l, k)| over (i, l) = Σ_i ‖v_ij‖ Σ_l |Σ_s u_s t_s(l, k)|
// with v_ij = (M_ij, C_ij, K_ij) = ‖v_ij‖ u. The column sums of |Σ_s u_s T_s| are computed once
// per distinct direction u (to 1e-14), a few for a FE model: O(nnz(T)) each for sparse time
// operators (Fourier:Fourier), O(M²) for dense ones, plus O(nnz(X) · M).
double kronecker_norm1(const std::array<Eigen::SparseMatrix<double>, 3>& t,
                       const std::array<const Eigen::SparseMatrix<double>*, 3>& x) {
  const auto n = x[0]->cols();
  const auto m = t[0].cols();
  // Time operators more than a quarter full (wavelet Galerkin, Petrov–Galerkin): dense sums.
  const bool dense = static_cast<double>(t[0].nonZeros() + t[1].nonZeros() + t[2].nonZeros()) >
                     0.25 * static_cast<double>(m) * static_cast<double>(m);
  std::array<Eigen::MatrixXd, 3> td;
  std::vector<std::pair<Eigen::Vector3d, Eigen::VectorXd>> directions;  // (u, column sums of Σ u_s T_s)
  if (dense) {
    for (int s = 0; s < 3; ++s) td[s] = Eigen::MatrixXd(t[s]);
  }
  double best = 0.0;
  for (Eigen::Index j = 0; j < n; ++j) {
    Eigen::VectorXd colsum = Eigen::VectorXd::Zero(m);  // over k
    // Rows i present in column j of any of M, C, K.
    std::vector<Eigen::Index> rows;
    for (const auto* xs : x) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(*xs, j); it; ++it) rows.push_back(it.row());
    }
    std::sort(rows.begin(), rows.end());
    rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
    for (const Eigen::Index i : rows) {
      const double v0 = x[0]->coeff(i, j), v1 = x[1]->coeff(i, j), v2 = x[2]->coeff(i, j);
      // |s·Σ u_s T_s| = |s| |Σ u_s T_s|: one column sum per direction u = v/‖v‖ (a FE model has
      // a few: the rod's interior diagonal, off-diagonal and end entries), reused to 1e-14.
      const double norm = std::sqrt(v0 * v0 + v1 * v1 + v2 * v2);
      if (norm == 0.0) continue;
      const Eigen::Vector3d u(v0 / norm, v1 / norm, v2 / norm);
      auto it = std::find_if(directions.begin(), directions.end(), [&](const auto& d) {
        return (d.first - u).template lpNorm<Eigen::Infinity>() <= 1e-14;
      });
      if (it == directions.end()) {
        Eigen::VectorXd sums;
        if (dense) {
          sums = (u(0) * td[0] + u(1) * td[1] + u(2) * td[2]).cwiseAbs().colwise().sum().transpose();
        } else {
          const Eigen::SparseMatrix<double> comb = u(0) * t[0] + u(1) * t[1] + u(2) * t[2];
          sums = Eigen::VectorXd::Zero(m);
          for (Eigen::Index k = 0; k < m; ++k) {
            for (Eigen::SparseMatrix<double>::InnerIterator c(comb, k); c; ++c) sums(k) += std::abs(c.value());
          }
        }
        directions.emplace_back(u, std::move(sums));
        it = std::prev(directions.end());
      }
      colsum += norm * it->second;
    }
    best = std::max(best, colsum.maxCoeff());
  }
  return best;
}

}  // namespace wbm::solvers::detail
