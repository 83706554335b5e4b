#pragma once
// A certified lower bound of a matrix's reciprocal condition number from its LU factors, cheap
// enough to skip a condition estimate wherever it proves the matrix far from singular.

#include <algorithm>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/LU>

namespace wbm::solvers::detail {

/// A lower bound of rcond₁(A) = 1 / (‖A‖₁ ‖A⁻¹‖₁) from the partial-pivoting LU P A = L U.
/// For a triangular T, |T⁻¹| ≤ M(T)⁻¹ entry by entry, M(T) the comparison matrix (|t_ii| on the
/// diagonal, −|t_ij| off it) [Higham 2002, Accuracy and Stability of Numerical Algorithms, 2nd
/// ed., Thm. 8.12]; so |A⁻¹| = |U⁻¹ L⁻¹ P| ≤ M(U)⁻¹ M(L)⁻¹ P (P a permutation) and
/// ‖A⁻¹‖₁ = ‖ |A⁻¹|ᵀ e ‖∞ ≤ ‖ M(L)⁻ᵀ M(U)⁻ᵀ e ‖∞, e the vector of ones. Two triangular solves
/// on |U| and |L|, O(n²), without allocating beyond one vector of n.
///
/// a_one_norm = ‖A‖₁ (max column sum of |A|). The bound is of the factors' product L U, as any
/// estimate from the factors is (Eigen's PartialPivLU::rcond() too, which estimates ‖A⁻¹‖₁ from
/// below by Hager–Higham and so rcond₁ from above): bound ≤ rcond₁(P⁻¹LU) ≤ rcond(), to rounding
/// in the two solves (relative O(n ε) on the bound). The comparison matrix can make the bound
/// pessimistic, by up to 2ⁿ⁻¹ in the worst case; it is used only to skip the estimate where it
/// already proves rcond large enough. Returns 0 for an empty or singular U (a zero pivot) or
/// on overflow, never NaN for finite factors.
[[nodiscard]] inline double rcond_lower_bound(const Eigen::PartialPivLU<Eigen::MatrixXd>& lu, double a_one_norm) {
  const Eigen::MatrixXd& f = lu.matrixLU();  // L (unit, strictly below the diagonal) and U, packed
  const Eigen::Index n = f.rows();
  if (n == 0 || !(a_one_norm > 0.0) || !std::isfinite(a_one_norm)) return 0.0;
  Eigen::VectorXd w(n);
  // y = M(U)⁻ᵀ e: y_j = (1 + Σ_{i<j} |u_ij| y_i) / |u_jj|, forward, column j of U.
  for (Eigen::Index j = 0; j < n; ++j) {
    const double pivot = std::abs(f(j, j));
    if (!(pivot > 0.0)) return 0.0;
    const double sum = j > 0 ? f.col(j).head(j).cwiseAbs().dot(w.head(j)) : 0.0;
    w(j) = (1.0 + sum) / pivot;
  }
  // z = M(L)⁻ᵀ y: z_j = y_j + Σ_{i>j} |l_ij| z_i, backward, column j of L (unit diagonal).
  double inverse_norm = 0.0;
  for (Eigen::Index j = n - 1; j >= 0; --j) {
    const Eigen::Index below = n - 1 - j;
    if (below > 0) w(j) += f.col(j).tail(below).cwiseAbs().dot(w.tail(below));
    inverse_norm = std::max(inverse_norm, w(j));
  }
  if (!std::isfinite(inverse_norm)) return 0.0;
  const double bound = 1.0 / (a_one_norm * inverse_norm);
  return std::isfinite(bound) ? bound : 0.0;
}

}  // namespace wbm::solvers::detail
